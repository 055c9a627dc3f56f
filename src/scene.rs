//! Scene description: meshes that borrow static slices (so they can live in flash), model
//! transforms, the camera and the light. Everything is validated when it is constructed, so the
//! render path never meets an index out of range or a NaN.
//!
//! Conventions (fixed, see DESIGN.md): the world is right-handed and the camera looks down −z;
//! [`Camera::look_at`] and [`View::perspective`] mean what `gluLookAt` and `gluPerspective` mean,
//! with `aspect = width / height` of the render target. Front faces wind counter-clockwise as
//! seen by the camera (the OpenGL default).

use crate::math::{Libm, MathBackend};
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;

/// A model-space coordinate: I16F16, range ±32768 with a resolution of 2^-16.
pub type Coord = I16F16;

/// A model-space point or direction.
pub type Vertex = [Coord; 3];

/// Largest |coordinate| a mesh vertex may have: 2^12 = 4096 model units.
///
/// Keeps `|matrix entry| * |coordinate|` sums far from the I16F16 eye-space limit (see
/// `crate::vertex` for the full bit budget).
pub const MAX_MODEL_COORD: i32 = 1 << 12;

/// Largest number of triangles in one frame, all instances together: 65,535.
///
/// The row walkers keep each bucketed triangle's id in 16 bits and thread their row buckets
/// through 16-bit links that end at `u16::MAX`; with at most 65,535 triangles every id and every
/// link index is in `0..=65534`, so neither is ever truncated nor taken for the end of a list.
/// The same bound applies to one mesh ([`Mesh::new`], [`SceneError::MeshTooLarge`]), to a
/// workspace's `TRIS` and to the `PIECES` of [`NewellWorkspace`](crate::resolve::NewellWorkspace)
/// and [`WarnockWorkspace`](crate::resolve::WarnockWorkspace) (checked when the workspace is
/// built). A scene over it is rejected by [`Scene::new`] ([`SceneError::TooManyTriangles`]) and,
/// as `Scene`'s fields are public, again by every render before any row is sent
/// ([`RenderError::TooManyTriangles`](crate::RenderError::TooManyTriangles)).
pub const MAX_SCENE_TRIANGLES: usize = u16::MAX as usize;

/// Largest |eye-space coordinate| the camera's near and far planes may use: 2^14 units.
pub const MAX_EYE_DISTANCE: f32 = 16384.0;

/// Smallest near-plane distance: 2^-8 eye units (so `near` keeps 8 significant bits in I16F16).
pub const MIN_NEAR: f32 = 1.0 / 256.0;

/// Largest far/near ratio: 2^20. At the far plane 1/w then still has 10 significant bits in the
/// I2F30 depth format (see [`crate::depth::Depth`]).
pub const MAX_FAR_NEAR_RATIO: f32 = 1048576.0;

/// Why a scene part was rejected. Every variant names what was wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// Triangle `triangle` refers to vertex `index`, but the mesh has only `vertex_count`.
    IndexOutOfRange {
        /// Triangle number within its mesh.
        triangle: usize,
        /// The offending vertex index.
        index: u16,
        /// Number of vertices in the mesh.
        vertex_count: usize,
    },
    /// Vertex `vertex` has a coordinate beyond ±[`MAX_MODEL_COORD`].
    VertexOutOfEnvelope {
        /// Vertex number.
        vertex: usize,
    },
    /// Per-face colours: one per triangle needed; per-vertex colours or normals: one per vertex.
    CountMismatch {
        /// Which array is the wrong length.
        what: &'static str,
        /// Length required.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A mesh has more than 65,535 triangles ([`MAX_SCENE_TRIANGLES`]) or vertices: more than
    /// 16-bit indices allow.
    MeshTooLarge,
    /// The scene's instances hold `triangles` triangles together, more than
    /// [`MAX_SCENE_TRIANGLES`] (65,535).
    TooManyTriangles {
        /// Triangles over all instances.
        triangles: usize,
    },
    /// A floating-point input was NaN or infinite.
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// The camera's eye and target coincide.
    EyeEqualsTarget,
    /// The up vector is zero or parallel to the viewing direction.
    DegenerateUp,
    /// Field of view outside (0°, 180°).
    FieldOfView,
    /// Near/far planes invalid: need `MIN_NEAR <= near < far <= MAX_EYE_DISTANCE` and
    /// `far / near <= MAX_FAR_NEAR_RATIO`.
    DepthRange,
    /// The light direction is zero, or ambient/diffuse outside [0, 1].
    Light,
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::IndexOutOfRange { triangle, index, vertex_count } => write!(
                f,
                "triangle {triangle} uses vertex index {index}, but the mesh has {vertex_count} vertices"
            ),
            Self::VertexOutOfEnvelope { vertex } => write!(
                f,
                "vertex {vertex} is outside the model envelope of +-{MAX_MODEL_COORD} units"
            ),
            Self::CountMismatch { what, expected, found } => {
                write!(f, "{what}: expected {expected} entries, found {found}")
            }
            Self::MeshTooLarge => write!(f, "mesh exceeds 65535 vertices or triangles"),
            Self::TooManyTriangles { triangles } => write!(
                f,
                "the scene has {triangles} triangles, more than the limit of {MAX_SCENE_TRIANGLES} per frame"
            ),
            Self::NonFinite { what } => write!(f, "{what} is not a finite number"),
            Self::EyeEqualsTarget => write!(f, "camera eye and target are the same point"),
            Self::DegenerateUp => {
                write!(f, "camera up vector is zero or parallel to the view direction")
            }
            Self::FieldOfView => write!(f, "field of view must be in (0, 180) degrees"),
            Self::DepthRange => write!(
                f,
                "need {MIN_NEAR} <= near < far <= {MAX_EYE_DISTANCE} and far/near <= {MAX_FAR_NEAR_RATIO}"
            ),
            Self::Light => write!(
                f,
                "light direction must be non-zero and ambient, diffuse within [0, 1]"
            ),
        }
    }
}

impl core::error::Error for SceneError {}

/// Where a mesh's base colours come from.
#[derive(Clone, Copy, Debug)]
pub enum MeshColors<'a> {
    /// One colour for the whole mesh.
    Uniform(Rgb888),
    /// One colour per triangle.
    PerFace(&'a [Rgb888]),
    /// One colour per vertex (flat shading uses each triangle's first vertex).
    PerVertex(&'a [Rgb888]),
}

/// A triangle mesh borrowing its data, typically `static` arrays in flash.
///
/// Vertices are I16F16 model coordinates within ±[`MAX_MODEL_COORD`]; triangles index them and
/// wind counter-clockwise when seen from the front. Optional per-vertex normals (any length,
/// they are normalised) are used by Gouraud shading.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb888;
/// use fixed::types::I16F16;
/// use scanline3d::scene::{Mesh, MeshColors};
///
/// const ONE: I16F16 = I16F16::ONE;
/// const Z: I16F16 = I16F16::ZERO;
/// static VERTS: [[I16F16; 3]; 3] = [[Z, Z, Z], [ONE, Z, Z], [Z, ONE, Z]];
/// static TRIS: [[u16; 3]; 1] = [[0, 1, 2]];
/// let mesh = Mesh::new(&VERTS, &TRIS, MeshColors::Uniform(Rgb888::new(200, 80, 40)), None)?;
/// assert_eq!(mesh.triangles().len(), 1);
///
/// static BAD: [[u16; 3]; 1] = [[0, 1, 7]];
/// assert!(Mesh::new(&VERTS, &BAD, MeshColors::Uniform(Rgb888::new(0, 0, 0)), None).is_err());
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Mesh<'a> {
    vertices: &'a [Vertex],
    triangles: &'a [[u16; 3]],
    colors: MeshColors<'a>,
    normals: Option<&'a [Vertex]>,
    max_abs: i32,
}

impl<'a> Mesh<'a> {
    /// Validates and wraps mesh data. `const`, so a firmware mesh is checked at compile time:
    /// `const MESH: Mesh = match Mesh::new(..) { Ok(m) => m, Err(_) => panic!() };`
    pub const fn new(
        vertices: &'a [Vertex],
        triangles: &'a [[u16; 3]],
        colors: MeshColors<'a>,
        normals: Option<&'a [Vertex]>,
    ) -> Result<Self, SceneError> {
        if vertices.len() > u16::MAX as usize || triangles.len() > MAX_SCENE_TRIANGLES {
            return Err(SceneError::MeshTooLarge);
        }
        let mut max_abs = 0i32;
        let mut v = 0;
        while v < vertices.len() {
            let mut k = 0;
            while k < 3 {
                let bits = vertices[v][k].to_bits();
                // Compare in bits: MAX_MODEL_COORD in I16F16 is MAX_MODEL_COORD << 16.
                if bits > (MAX_MODEL_COORD << 16) || bits < -(MAX_MODEL_COORD << 16) {
                    return Err(SceneError::VertexOutOfEnvelope { vertex: v });
                }
                let a = if bits < 0 { -bits } else { bits };
                if a > max_abs {
                    max_abs = a;
                }
                k += 1;
            }
            v += 1;
        }
        let mut t = 0;
        while t < triangles.len() {
            let mut k = 0;
            while k < 3 {
                let index = triangles[t][k];
                if index as usize >= vertices.len() {
                    return Err(SceneError::IndexOutOfRange {
                        triangle: t,
                        index,
                        vertex_count: vertices.len(),
                    });
                }
                k += 1;
            }
            t += 1;
        }
        match colors {
            MeshColors::Uniform(_) => {}
            MeshColors::PerFace(c) => {
                if c.len() != triangles.len() {
                    return Err(SceneError::CountMismatch {
                        what: "per-face colours",
                        expected: triangles.len(),
                        found: c.len(),
                    });
                }
            }
            MeshColors::PerVertex(c) => {
                if c.len() != vertices.len() {
                    return Err(SceneError::CountMismatch {
                        what: "per-vertex colours",
                        expected: vertices.len(),
                        found: c.len(),
                    });
                }
            }
        }
        if let Some(n) = normals {
            if n.len() != vertices.len() {
                return Err(SceneError::CountMismatch {
                    what: "normals",
                    expected: vertices.len(),
                    found: n.len(),
                });
            }
        }
        Ok(Mesh {
            vertices,
            triangles,
            colors,
            normals,
            max_abs,
        })
    }

    /// The vertices.
    pub const fn vertices(&self) -> &'a [Vertex] {
        self.vertices
    }
    /// The triangles (vertex index triples).
    pub const fn triangles(&self) -> &'a [[u16; 3]] {
        self.triangles
    }
    /// The colour source.
    pub const fn colors(&self) -> MeshColors<'a> {
        self.colors
    }
    /// Per-vertex normals, if given.
    pub const fn normals(&self) -> Option<&'a [Vertex]> {
        self.normals
    }
    /// Largest |coordinate| of any vertex, in I16F16 bits.
    pub(crate) const fn max_abs_bits(&self) -> i32 {
        self.max_abs
    }
}

/// An affine transform `p' = M p + t` stored as a 3×4 row-major `f32` matrix.
///
/// Composition happens once per frame in `f32`; vertices are transformed in fixed point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rows of `[M | t]`.
    pub m: [[f32; 4]; 3],
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform {
        m: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
    };

    /// Translation by `t`.
    pub const fn translation(t: [f32; 3]) -> Self {
        Transform {
            m: [
                [1.0, 0.0, 0.0, t[0]],
                [0.0, 1.0, 0.0, t[1]],
                [0.0, 0.0, 1.0, t[2]],
            ],
        }
    }

    /// Scaling by `s` along each axis.
    pub const fn scale(s: [f32; 3]) -> Self {
        Transform {
            m: [
                [s[0], 0.0, 0.0, 0.0],
                [0.0, s[1], 0.0, 0.0],
                [0.0, 0.0, s[2], 0.0],
            ],
        }
    }

    /// Rotation by `angle` radians about the x axis (right-handed), with [`Libm`].
    pub fn rotation_x(angle: f32) -> Self {
        Self::rotation_x_with::<Libm>(angle)
    }
    /// Rotation by `angle` radians about the y axis (right-handed), with [`Libm`].
    pub fn rotation_y(angle: f32) -> Self {
        Self::rotation_y_with::<Libm>(angle)
    }
    /// Rotation by `angle` radians about the z axis (right-handed), with [`Libm`].
    pub fn rotation_z(angle: f32) -> Self {
        Self::rotation_z_with::<Libm>(angle)
    }
    /// [`Transform::rotation_x`] with a chosen math backend.
    pub fn rotation_x_with<M: MathBackend>(angle: f32) -> Self {
        let (s, c) = (M::sin(angle), M::cos(angle));
        Transform {
            m: [[1.0, 0.0, 0.0, 0.0], [0.0, c, -s, 0.0], [0.0, s, c, 0.0]],
        }
    }
    /// [`Transform::rotation_y`] with a chosen math backend.
    pub fn rotation_y_with<M: MathBackend>(angle: f32) -> Self {
        let (s, c) = (M::sin(angle), M::cos(angle));
        Transform {
            m: [[c, 0.0, s, 0.0], [0.0, 1.0, 0.0, 0.0], [-s, 0.0, c, 0.0]],
        }
    }
    /// [`Transform::rotation_z`] with a chosen math backend.
    pub fn rotation_z_with<M: MathBackend>(angle: f32) -> Self {
        let (s, c) = (M::sin(angle), M::cos(angle));
        Transform {
            m: [[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
        }
    }

    /// `self ∘ inner`: applies `inner` first, then `self`.
    pub fn then_after(&self, inner: &Transform) -> Transform {
        // Row by row and column by column without indexing (no bounds checks to survive
        // `opt-level = "z"`): m[r][c] = Σ_k a[r][k]·b[k][c], plus a[r][3] in the last column.
        let [b0, b1, b2] = &inner.m;
        let m = self.m.map(|[a0, a1, a2, a3]| {
            let mut row = [0.0f32; 4];
            for (((out, x), y), z) in row.iter_mut().zip(b0).zip(b1).zip(b2) {
                *out = a0 * x + a1 * y + a2 * z;
            }
            if let Some(last) = row.last_mut() {
                *last += a3;
            }
            row
        });
        Transform { m }
    }

    /// The nearest rigid transform (rotation + the same translation), by Gram–Schmidt on the
    /// linear part's rows, with [`Libm`].
    ///
    /// Animation that accumulates small rotations frame after frame (`r = step.then_after(&r)`)
    /// drifts: every product adds rounding, and an approximate backend adds more, so after
    /// thousands of frames the mesh grows or shears. Re-orthonormalising each frame keeps it rigid.
    ///
    /// ```
    /// use scanline3d::scene::Transform;
    /// let skewed = Transform { m: [[1.1, 0.2, 0.0, 5.0], [0.0, 0.9, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]] };
    /// let r = skewed.orthonormalized();
    /// let p = r.apply([1.0, 0.0, 0.0]);
    /// assert!(((p[0] - 5.0).powi(2) + p[1] * p[1] + p[2] * p[2] - 1.0).abs() < 1e-6);
    /// ```
    pub fn orthonormalized(&self) -> Transform {
        self.orthonormalized_with::<Libm>()
    }

    /// [`Transform::orthonormalized`] with a chosen math backend.
    pub fn orthonormalized_with<M: MathBackend>(&self) -> Transform {
        let row = |r: usize| [self.m[r][0], self.m[r][1], self.m[r][2]];
        let x = normalize::<M>(row(0)).unwrap_or([1.0, 0.0, 0.0]);
        let y0 = row(1);
        let d = dot(x, y0);
        let y = normalize::<M>([y0[0] - d * x[0], y0[1] - d * x[1], y0[2] - d * x[2]])
            .unwrap_or([0.0, 1.0, 0.0]);
        let z = cross(x, y);
        let t = [self.m[0][3], self.m[1][3], self.m[2][3]];
        Transform {
            m: [
                [x[0], x[1], x[2], t[0]],
                [y[0], y[1], y[2], t[1]],
                [z[0], z[1], z[2], t[2]],
            ],
        }
    }

    /// Applies the transform to a point.
    pub fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let m = &self.m;
        [0, 1, 2].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
    }

    pub(crate) fn is_finite(&self) -> bool {
        self.m.iter().flatten().all(|v| v.is_finite())
    }
}

fn finite3(v: [f32; 3], what: &'static str) -> Result<[f32; 3], SceneError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(v)
    } else {
        Err(SceneError::NonFinite { what })
    }
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize<M: MathBackend>(v: [f32; 3]) -> Option<[f32; 3]> {
    let len = M::sqrt(dot(v, v));
    if len.is_nan() || len <= 0.0 || len.is_infinite() {
        return None;
    }
    Some([v[0] / len, v[1] / len, v[2] / len])
}

/// The camera's position and orientation, as built by [`Camera::look_at`]. Add a projection with
/// [`View::perspective`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// World → eye transform.
    pub world_to_eye: Transform,
    /// Eye position in world space.
    pub eye: [f32; 3],
}

impl View {
    /// Adds a `gluPerspective` projection: vertical field of view `fovy_degrees` in (0, 180),
    /// clip planes at eye distances `near` and `far`. Uses [`Libm`] for the tangent.
    pub fn perspective(self, fovy_degrees: f32, near: f32, far: f32) -> Result<Camera, SceneError> {
        self.perspective_with::<Libm>(fovy_degrees, near, far)
    }

    /// [`View::perspective`] with a chosen math backend.
    pub fn perspective_with<M: MathBackend>(
        self,
        fovy_degrees: f32,
        near: f32,
        far: f32,
    ) -> Result<Camera, SceneError> {
        for (v, what) in [
            (fovy_degrees, "field of view"),
            (near, "near"),
            (far, "far"),
        ] {
            if !v.is_finite() {
                return Err(SceneError::NonFinite { what });
            }
        }
        if !(fovy_degrees > 0.0 && fovy_degrees < 180.0) {
            return Err(SceneError::FieldOfView);
        }
        if !(near >= MIN_NEAR && near < far && far <= MAX_EYE_DISTANCE)
            || far / near > MAX_FAR_NEAR_RATIO
        {
            return Err(SceneError::DepthRange);
        }
        let half = fovy_degrees * (core::f32::consts::PI / 360.0);
        let tan_half = M::tan(half);
        if tan_half.is_nan() || tan_half <= 0.0 || tan_half.is_infinite() {
            return Err(SceneError::FieldOfView);
        }
        Ok(Camera {
            view: self,
            focal: 1.0 / tan_half,
            near,
            far,
        })
    }
}

/// A perspective camera: where it is, where it looks and how it projects.
///
/// ```
/// use scanline3d::scene::Camera;
/// let camera = Camera::look_at([-3.0, 2.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0])?
///     .perspective(60.0, 0.1, 100.0)?;
/// assert!((camera.focal() - 1.732).abs() < 1e-3); // 1 / tan(30°)
/// assert!(Camera::look_at([1.0; 3], [1.0; 3], [0.0, 1.0, 0.0]).is_err());
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    view: View,
    focal: f32,
    near: f32,
    far: f32,
}

impl Camera {
    /// A view from `eye` towards `target` with `up` roughly upwards (`gluLookAt`), using [`Libm`].
    // `look_at` is the established name; it builds the View half of a camera.
    #[allow(clippy::new_ret_no_self)]
    pub fn look_at(eye: [f32; 3], target: [f32; 3], up: [f32; 3]) -> Result<View, SceneError> {
        Self::look_at_with::<Libm>(eye, target, up)
    }

    /// `gluLookAt` · `gluPerspective` in one call, computed with math backend `M`.
    pub fn look_at_perspective_with<M: MathBackend>(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fovy_degrees: f32,
        near: f32,
        far: f32,
    ) -> Result<Camera, SceneError> {
        Camera::look_at_with::<M>(eye, target, up)?.perspective_with::<M>(fovy_degrees, near, far)
    }

    /// [`Camera::look_at`] with a chosen math backend.
    pub fn look_at_with<M: MathBackend>(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
    ) -> Result<View, SceneError> {
        let eye = finite3(eye, "camera eye")?;
        let target = finite3(target, "camera target")?;
        let up = finite3(up, "camera up")?;
        let forward = normalize::<M>(sub(target, eye)).ok_or(SceneError::EyeEqualsTarget)?;
        let side = cross(forward, up);
        // Reject an up vector within ~0.06° of the view direction: the basis would be noise.
        let up_len = M::sqrt(dot(up, up));
        let side_len = M::sqrt(dot(side, side));
        if side_len.is_nan() || side_len <= 1e-3 * up_len {
            return Err(SceneError::DegenerateUp);
        }
        let side = normalize::<M>(side).ok_or(SceneError::DegenerateUp)?;
        let true_up = cross(side, forward);
        let back = [-forward[0], -forward[1], -forward[2]];
        let row = |a: [f32; 3]| [a[0], a[1], a[2], -dot(a, eye)];
        Ok(View {
            world_to_eye: Transform {
                m: [row(side), row(true_up), row(back)],
            },
            eye,
        })
    }

    /// `1 / tan(fovy / 2)`.
    pub fn focal(&self) -> f32 {
        self.focal
    }
    /// Near-plane eye distance.
    pub fn near(&self) -> f32 {
        self.near
    }

    /// Eye distance (along the view axis) of a stored depth `q`, or `None` for background
    /// (`q <= 0`). Depth is `q = near / w` with `near` rounded to I16F16, as the renderer uses
    /// it, so this inverts it exactly up to the format's resolution.
    ///
    /// ```
    /// use scanline3d::{scene::Camera, Depth};
    /// let cam = Camera::look_at([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0])?.perspective(60.0, 0.5, 50.0)?;
    /// assert_eq!(cam.eye_distance(Depth::from_num(0.25)), Some(2.0));
    /// assert_eq!(cam.eye_distance(Depth::ZERO), None);
    /// # Ok::<(), scanline3d::scene::SceneError>(())
    /// ```
    pub fn eye_distance(&self, q: crate::depth::Depth) -> Option<f32> {
        let near = I16F16::checked_from_num(self.near)?.to_num::<f64>();
        let q = q.to_num::<f64>();
        (q > 0.0).then(|| (near / q) as f32)
    }
    /// Far-plane eye distance.
    pub fn far(&self) -> f32 {
        self.far
    }
    /// The view (position and orientation).
    pub fn view(&self) -> &View {
        &self.view
    }
}

/// A directional light plus ambient term: a surface with unit normal `n` receives
/// `ambient + diffuse * max(0, n · direction)`, clamped to 1, times its base colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    direction: [f32; 3],
    ambient: f32,
    diffuse: f32,
}

impl Light {
    /// `towards_light` points from the surface to the light (any non-zero length);
    /// `ambient` and `diffuse` within [0, 1].
    pub fn new(towards_light: [f32; 3], ambient: f32, diffuse: f32) -> Result<Self, SceneError> {
        let d = finite3(towards_light, "light direction")?;
        if !ambient.is_finite() || !diffuse.is_finite() {
            return Err(SceneError::NonFinite {
                what: "light intensity",
            });
        }
        if !(0.0..=1.0).contains(&ambient) || !(0.0..=1.0).contains(&diffuse) {
            return Err(SceneError::Light);
        }
        let direction = normalize::<Libm>(d).ok_or(SceneError::Light)?;
        Ok(Light {
            direction,
            ambient,
            diffuse,
        })
    }
    /// Unit vector towards the light.
    pub fn direction(&self) -> [f32; 3] {
        self.direction
    }
    /// Ambient intensity.
    pub fn ambient(&self) -> f32 {
        self.ambient
    }
    /// Diffuse intensity.
    pub fn diffuse(&self) -> f32 {
        self.diffuse
    }
}

/// A mesh placed in the world.
#[derive(Clone, Copy, Debug)]
pub struct Instance<'a> {
    /// The mesh.
    pub mesh: &'a Mesh<'a>,
    /// Model → world transform.
    pub transform: Transform,
}

/// What to render: mesh instances, a camera and a light. Triangle ids number the instances'
/// triangles consecutively, in instance order.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    /// The instances, drawn with consecutive triangle ids.
    pub instances: &'a [Instance<'a>],
    /// The camera.
    pub camera: Camera,
    /// The light.
    pub light: Light,
}

impl<'a> Scene<'a> {
    /// A scene of `instances` seen by `camera` under `light`, rejected if the instances hold
    /// more than [`MAX_SCENE_TRIANGLES`] triangles together. `const`, like [`Mesh::new`].
    ///
    /// (The fields are public, so a scene can also be built as a struct literal; the render
    /// checks the same limit then, see [`RenderError::TooManyTriangles`].)
    ///
    /// [`RenderError::TooManyTriangles`]: crate::RenderError::TooManyTriangles
    ///
    /// ```
    /// use embedded_graphics::pixelcolor::Rgb888;
    /// use fixed::types::I16F16;
    /// use scanline3d::scene::*;
    ///
    /// const Z: I16F16 = I16F16::ZERO;
    /// static VERTS: [Vertex; 3] = [[Z, Z, Z], [I16F16::ONE, Z, Z], [Z, I16F16::ONE, Z]];
    /// static TRIS: [[u16; 3]; 1] = [[0, 1, 2]];
    /// let mesh = Mesh::new(&VERTS, &TRIS, MeshColors::Uniform(Rgb888::new(9, 9, 9)), None)?;
    /// let instances = [Instance { mesh: &mesh, transform: Transform::IDENTITY }; 2];
    /// let camera = Camera::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?.perspective(60.0, 0.5, 10.0)?;
    /// let scene = Scene::new(&instances, camera, Light::new([0.0, 0.0, 1.0], 0.2, 0.8)?)?;
    /// assert_eq!(scene.triangle_count(), 2);
    /// # Ok::<(), scanline3d::scene::SceneError>(())
    /// ```
    pub const fn new(
        instances: &'a [Instance<'a>],
        camera: Camera,
        light: Light,
    ) -> Result<Self, SceneError> {
        let scene = Scene {
            instances,
            camera,
            light,
        };
        let triangles = scene.triangle_count();
        if triangles > MAX_SCENE_TRIANGLES {
            return Err(SceneError::TooManyTriangles { triangles });
        }
        Ok(scene)
    }

    /// Total number of triangles over all instances (saturating at `usize::MAX`).
    pub const fn triangle_count(&self) -> usize {
        let (mut total, mut rest) = (0usize, self.instances);
        while let [instance, tail @ ..] = rest {
            total = total.saturating_add(instance.mesh.triangles().len());
            rest = tail;
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_maps_eye_to_origin_and_target_to_minus_z() {
        let v = Camera::look_at([3.0, 2.0, 1.0], [0.0, 2.0, 1.0], [0.0, 1.0, 0.0]).unwrap();
        let e = v.world_to_eye.apply([3.0, 2.0, 1.0]);
        assert!(e.iter().all(|c| c.abs() < 1e-6));
        let t = v.world_to_eye.apply([0.0, 2.0, 1.0]);
        assert!((t[2] + 3.0).abs() < 1e-6 && t[0].abs() < 1e-6 && t[1].abs() < 1e-6);
        // Up stays up.
        let u = v.world_to_eye.apply([3.0, 3.0, 1.0]);
        assert!((u[1] - 1.0).abs() < 1e-6);
    }

    #[test]
    fn degenerate_cameras_are_rejected() {
        let up = [0.0, 1.0, 0.0];
        assert_eq!(
            Camera::look_at([0.0; 3], [0.0; 3], up),
            Err(SceneError::EyeEqualsTarget)
        );
        assert_eq!(
            Camera::look_at([0.0; 3], [0.0, 5.0, 0.0], up),
            Err(SceneError::DegenerateUp)
        );
        assert_eq!(
            Camera::look_at([0.0; 3], [0.0, 0.0, -1.0], [0.0; 3]),
            Err(SceneError::DegenerateUp)
        );
        assert_eq!(
            Camera::look_at([f32::NAN, 0.0, 0.0], [0.0, 0.0, -1.0], up),
            Err(SceneError::NonFinite { what: "camera eye" })
        );
        let v = Camera::look_at([0.0; 3], [0.0, 0.0, -1.0], up).unwrap();
        assert_eq!(v.perspective(0.0, 0.1, 10.0), Err(SceneError::FieldOfView));
        assert_eq!(
            v.perspective(180.0, 0.1, 10.0),
            Err(SceneError::FieldOfView)
        );
        assert_eq!(v.perspective(60.0, 0.0, 10.0), Err(SceneError::DepthRange));
        assert_eq!(v.perspective(60.0, 1.0, 1.0), Err(SceneError::DepthRange));
        assert_eq!(
            v.perspective(60.0, 0.01, 16000.0),
            Err(SceneError::DepthRange)
        );
        assert!(v.perspective(60.0, 0.1, 100.0).is_ok());
    }

    #[test]
    fn mesh_validation_names_the_problem() {
        let z = Coord::ZERO;
        let verts = [[z, z, z], [Coord::ONE, z, z], [z, Coord::ONE, z]];
        let far = [[z, z, z], [Coord::from_num(5000), z, z], [z, Coord::ONE, z]];
        let c = MeshColors::Uniform(Rgb888::new(1, 2, 3));
        assert!(Mesh::new(&verts, &[[0, 1, 2]], c, None).is_ok());
        assert_eq!(
            Mesh::new(&verts, &[[0, 1, 3]], c, None).unwrap_err(),
            SceneError::IndexOutOfRange {
                triangle: 0,
                index: 3,
                vertex_count: 3
            }
        );
        assert_eq!(
            Mesh::new(&far, &[[0, 1, 2]], c, None).unwrap_err(),
            SceneError::VertexOutOfEnvelope { vertex: 1 }
        );
        let faces = [Rgb888::new(0, 0, 0); 2];
        assert!(matches!(
            Mesh::new(&verts, &[[0, 1, 2]], MeshColors::PerFace(&faces), None),
            Err(SceneError::CountMismatch {
                expected: 1,
                found: 2,
                ..
            })
        ));
        assert!(matches!(
            Mesh::new(&verts, &[[0, 1, 2]], c, Some(&verts[..2])),
            Err(SceneError::CountMismatch {
                what: "normals",
                ..
            })
        ));
    }

    #[test]
    fn light_is_validated_and_normalised() {
        let l = Light::new([0.0, 3.0, 4.0], 0.2, 0.8).unwrap();
        assert!((l.direction()[1] - 0.6).abs() < 1e-6);
        assert_eq!(Light::new([0.0; 3], 0.2, 0.8), Err(SceneError::Light));
        assert_eq!(
            Light::new([0.0, 1.0, 0.0], 1.5, 0.8),
            Err(SceneError::Light)
        );
    }

    #[test]
    fn transforms_compose_right_to_left() {
        let t = Transform::translation([1.0, 0.0, 0.0]).then_after(&Transform::scale([2.0; 3]));
        assert_eq!(t.apply([1.0, 1.0, 1.0]), [3.0, 2.0, 2.0]);
        let r = Transform::rotation_y(core::f32::consts::FRAC_PI_2);
        let p = r.apply([1.0, 0.0, 0.0]);
        assert!((p[2] + 1.0).abs() < 1e-6);
    }
}
