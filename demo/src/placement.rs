//! Where the demo's meshes stand and where its light comes from: shared by the crate and its
//! build script, which lights the baked colour tables (`*_BAKED`) with exactly these values.

use scanline3d::scene::Transform;

/// The demo light's parameters: towards the light, ambient, diffuse.
pub const LIGHT: ([f32; 3], f32, f32) = ([-0.45, 0.8, 0.55], 0.25, 0.75);

/// The icosphere's model transform.
pub fn sphere_transform() -> Transform {
    Transform::IDENTITY
}

/// The cube's model transform: scaled, turned and placed beside the sphere.
pub fn cube_transform() -> Transform {
    Transform::translation([1.35, -0.55, 1.15])
        .then_after(&Transform::rotation_y(0.6))
        .then_after(&Transform::scale([0.45; 3]))
}

/// The ground's model transform.
pub fn ground_transform() -> Transform {
    Transform::translation([0.0, -1.0, 0.0])
}
