//! A traced scene in fixed point: materials, lights, background and ambient, borrowing its
//! objects, materials and lights from slices (so all of it can be `static` data in flash), and
//! the camera that makes primary rays.

use crate::trace::bvh::{Bvh, BvhError, BvhNode};
use crate::trace::grid::{Grid, GridError, GridShape};
use crate::trace::shape::Object;
use crate::trace::vector::{Vec3, MAX_COORD};
use fixed::types::{I16F16, I8F24};

/// Why a scene, material, light or camera was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceSceneError {
    /// A colour channel or the ambient level is outside [0, 1].
    BadColour,
    /// A material coefficient (KA, KD, KR, KT) is outside [0, [`MAX_COEFFICIENT`]].
    BadCoefficient,
    /// An index of refraction is outside [1, [`MAX_IOR`]].
    BadIor,
    /// A light's intensity is outside [0, [`MAX_COEFFICIENT`]], its position outside the
    /// envelope or its direction zero.
    BadLight,
    /// More than [`MAX_LIGHTS`] lights.
    TooManyLights,
    /// More objects than ids (`u32::MAX − 1`).
    TooManyObjects,
    /// An object names a material index the scene does not have.
    UnknownMaterial,
    /// A checker names a material the scene lacks, or its cell size is not a power of two
    /// between 2^-8 and 2^8 world units.
    BadChecker,
    /// A checker texture is on an object other than a plane or a polygon.
    CheckerOnShape,
    /// Camera: eye outside the envelope, eye = target, up parallel to the view direction,
    /// field of view outside (0°, 160°], near ≤ 0, far ≤ near, far beyond the envelope, or a
    /// size of zero or above [`MAX_TRACE_SIZE`].
    BadCamera,
}

impl core::fmt::Display for TraceSceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            TraceSceneError::BadColour => "a colour channel or the ambient level is outside [0, 1]",
            TraceSceneError::BadCoefficient => "a material coefficient is outside [0, 8]",
            TraceSceneError::BadIor => "an index of refraction is outside [1, 4]",
            TraceSceneError::BadLight => "a light has a bad intensity, position or direction",
            TraceSceneError::TooManyLights => "more than 8 lights",
            TraceSceneError::TooManyObjects => "too many objects",
            TraceSceneError::UnknownMaterial => "an object names a material the scene lacks",
            TraceSceneError::BadChecker => {
                "a checker names a missing material or its size is not a power of two in [2^-8, 2^8]"
            }
            TraceSceneError::CheckerOnShape => "a checker texture is only for planes and polygons",
            TraceSceneError::BadCamera => "the camera is outside the tracer's envelope",
        })
    }
}

impl core::error::Error for TraceSceneError {}

/// The largest material coefficient or light intensity: 8.
pub const MAX_COEFFICIENT: I16F16 = I16F16::from_bits(8 << 16);
/// The largest index of refraction: 4 (diamond is 2.42).
pub const MAX_IOR: I16F16 = I16F16::from_bits(4 << 16);
/// The most lights a scene may have: one bit each in a shadow mask byte.
pub const MAX_LIGHTS: usize = 8;
/// The largest traced image side, in pixels.
pub const MAX_TRACE_SIZE: u16 = 2048;

/// A linear RGB colour, each channel an [`I16F16`] (1.0 = full).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Colour(pub [I16F16; 3]);

impl Colour {
    /// Black.
    pub const BLACK: Colour = Colour([I16F16::ZERO; 3]);

    /// A colour with every channel in [0, 1].
    pub fn new(rgb: [I16F16; 3]) -> Result<Colour, TraceSceneError> {
        if rgb.iter().all(|c| *c >= I16F16::ZERO && *c <= I16F16::ONE) {
            Ok(Colour(rgb))
        } else {
            Err(TraceSceneError::BadColour)
        }
    }
}

/// A surface's material: `KA·C·ambient + Σ KD·(N·L)·C·I` locally, plus KR of the reflected
/// and KT of the refracted ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Material {
    /// Surface colour C.
    pub colour: Colour,
    /// Ambient coefficient KA, in [0, [`MAX_COEFFICIENT`]].
    pub ka: I16F16,
    /// Diffuse coefficient KD, in [0, [`MAX_COEFFICIENT`]].
    pub kd: I16F16,
    /// Reflection coefficient KR, in [0, [`MAX_COEFFICIENT`]].
    pub kr: I16F16,
    /// Transmission coefficient KT, in [0, [`MAX_COEFFICIENT`]].
    pub kt: I16F16,
    /// Index of refraction (inside the object; outside is air, 1.0), in [1, [`MAX_IOR`]].
    pub ior: I16F16,
}

impl Material {
    /// A material, or an error for a coefficient outside [0, [`MAX_COEFFICIENT`]] or an IOR
    /// outside [1, [`MAX_IOR`]].
    pub fn new(
        colour: Colour,
        [ka, kd, kr, kt]: [I16F16; 4],
        ior: I16F16,
    ) -> Result<Material, TraceSceneError> {
        let material = Material {
            colour,
            ka,
            kd,
            kr,
            kt,
            ior,
        };
        material.check()?;
        Ok(material)
    }

    /// Whether the material keeps the limits its fields document.
    fn check(&self) -> Result<(), TraceSceneError> {
        Colour::new(self.colour.0)?;
        if [self.ka, self.kd, self.kr, self.kt]
            .iter()
            .any(|k| *k < I16F16::ZERO || *k > MAX_COEFFICIENT)
        {
            return Err(TraceSceneError::BadCoefficient);
        }
        if self.ior < I16F16::ONE || self.ior > MAX_IOR {
            return Err(TraceSceneError::BadIor);
        }
        Ok(())
    }
}

/// A checker texture over a plane or polygon: at a hit point, drop the coordinate of the
/// normal's largest axis ([`Shape::texture_axis`](crate::trace::shape::Shape::texture_axis));
/// the cell of the other two, `(u, v)` in increasing axis order, is
/// `(floor(u / size), floor(v / size))`, and the surface there is material `a` when the cell's
/// indices sum to an even number, `b` otherwise (every coefficient from that material).
///
/// The size is a power of two, so a cell index is an arithmetic shift of the raw I16F16
/// coordinate (a floor, negative coordinates included): no division, no rounding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Checker {
    /// Material of the even cells (an index into [`Scene::materials`]).
    pub a: u16,
    /// Material of the odd cells.
    pub b: u16,
    /// The cell size as a shift of raw I16F16 bits: size = 2^(shift − 16) world units, shift
    /// in [`CHECKER_SHIFTS`] (2^-8 to 2^8 units).
    pub shift: u8,
}

/// The shifts a [`Checker`] may have: cells of 2^-8 to 2^8 world units.
pub const CHECKER_SHIFTS: core::ops::RangeInclusive<u8> = 8..=24;

impl Checker {
    /// A checker of materials `a` (even cells) and `b` with cells of 2^`log2_size` world units,
    /// or an error for a size outside 2^-8..2^8 (the materials are checked by [`Scene::textured`]).
    pub fn new(a: u16, b: u16, log2_size: i8) -> Result<Checker, TraceSceneError> {
        let shift = u8::try_from(i16::from(log2_size) + 16)
            .ok()
            .filter(|s| CHECKER_SHIFTS.contains(s))
            .ok_or(TraceSceneError::BadChecker)?;
        Ok(Checker { a, b, shift })
    }

    /// The material index at `point`, projected along `axis` (the dropped one).
    #[inline]
    pub fn cell_material(&self, point: Vec3, axis: u8) -> u16 {
        let [x, y, z] = point.bits();
        let (u, v) = match axis {
            0 => (y, z),
            1 => (x, z),
            _ => (x, y),
        };
        // An arithmetic shift is the floor of the division, for negative coordinates too.
        let shift = u32::from(self.shift);
        let parity = (u.wrapping_shr(shift) ^ v.wrapping_shr(shift)) & 1;
        if parity == 0 {
            self.a
        } else {
            self.b
        }
    }
}

/// Where a light is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// A point light at this position (no distance falloff).
    Point(Vec3),
    /// A light at infinity; the unit vector points from surfaces towards it.
    Directional(Vec3),
}

/// A light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Light {
    /// Position or direction.
    pub kind: LightKind,
    /// Intensity I, in [0, [`MAX_COEFFICIENT`]].
    pub intensity: I16F16,
}

impl Light {
    /// A point light at `position`.
    pub fn point(position: Vec3, intensity: I16F16) -> Result<Light, TraceSceneError> {
        Light::with(LightKind::Point(position), intensity)
    }

    /// A directional light; `towards` (any length) points from surfaces to the light.
    pub fn directional(towards: Vec3, intensity: I16F16) -> Result<Light, TraceSceneError> {
        if !towards.in_envelope() {
            return Err(TraceSceneError::BadLight);
        }
        let unit = towards.normalized().ok_or(TraceSceneError::BadLight)?;
        Light::with(LightKind::Directional(unit), intensity)
    }

    fn with(kind: LightKind, intensity: I16F16) -> Result<Light, TraceSceneError> {
        let light = Light { kind, intensity };
        light.check()?;
        Ok(light)
    }

    /// Whether the light keeps its limits: the intensity in [0, [`MAX_COEFFICIENT`]], a point
    /// light's position in the envelope, a directional light's components in [−1, 1].
    fn check(&self) -> Result<(), TraceSceneError> {
        let place = match self.kind {
            LightKind::Point(p) => p.in_envelope(),
            LightKind::Directional(d) => d.bits().iter().all(|c| c.unsigned_abs() <= 1 << 16),
        };
        if place && self.intensity >= I16F16::ZERO && self.intensity <= MAX_COEFFICIENT {
            Ok(())
        } else {
            Err(TraceSceneError::BadLight)
        }
    }
}

/// A traced scene: objects (ids are their indices), materials, lights, background colour and
/// ambient level, all borrowed. Made by [`Scene::new`] or [`Scene::textured`], which check the
/// limits its parts document; a field replaced afterwards must keep them too (outside them
/// colours are unspecified, though the tracer never panics).
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    /// Primitives; an object's id is its index.
    pub objects: &'a [Object<'a>],
    /// Materials, indexed by [`Object::material`].
    pub materials: &'a [Material],
    /// Checker textures: an [`Object::material`] of `materials.len() + k` names checker k.
    pub checkers: &'a [Checker],
    /// Lights; light k is bit k of a shadow mask.
    pub lights: &'a [Light],
    /// Colour of rays that hit nothing.
    pub background: Colour,
    /// Ambient level, in [0, 1].
    pub ambient: I16F16,
    /// A bounding-volume hierarchy over the objects ([`Scene::with_bvh`]); without one every
    /// ray tests every object.
    pub bvh: Option<Bvh<'a>>,
    /// A uniform grid over the objects ([`Scene::with_grid`]); used instead of the hierarchy
    /// when both are given.
    pub grid: Option<Grid<'a>>,
}

impl<'a> Scene<'a> {
    /// The scene with a uniform grid over its objects, as
    /// [`grid::build`](crate::trace::grid::build) made it, checked by [`Grid::new`].
    pub fn with_grid(
        self,
        shape: GridShape,
        starts: &'a [u32],
        items: &'a [u32],
        unbounded: &'a [u32],
    ) -> Result<Scene<'a>, GridError> {
        Ok(Scene {
            grid: Some(Grid::new(
                shape,
                starts,
                items,
                unbounded,
                self.objects.len(),
            )?),
            ..self
        })
    }

    /// The scene with a bounding-volume hierarchy over its objects, as
    /// [`bvh::build`](crate::trace::bvh::build) made it (nodes, items and how many items are in
    /// the tree), checked against the objects by [`Bvh::new`].
    pub fn with_bvh(
        self,
        nodes: &'a [BvhNode],
        items: &'a [u32],
        bounded: usize,
    ) -> Result<Scene<'a>, BvhError> {
        Ok(Scene {
            bvh: Some(Bvh::new(nodes, items, bounded, self.objects)?),
            ..self
        })
    }

    /// A scene, or an error for an unknown material index, more than [`MAX_LIGHTS`] lights,
    /// an ambient level or background channel outside [0, 1], or a material or light outside
    /// the limits its fields document.
    pub fn new(
        objects: &'a [Object<'a>],
        materials: &'a [Material],
        lights: &'a [Light],
        background: Colour,
        ambient: I16F16,
    ) -> Result<Scene<'a>, TraceSceneError> {
        Scene::textured(objects, materials, &[], lights, background, ambient)
    }

    /// A scene whose objects may name checker textures ([`Object::material`] from
    /// `materials.len()` on), or an error as [`Scene::new`], for a checker naming a missing
    /// material, or for a checker on an object other than a plane or polygon.
    pub fn textured(
        objects: &'a [Object<'a>],
        materials: &'a [Material],
        checkers: &'a [Checker],
        lights: &'a [Light],
        background: Colour,
        ambient: I16F16,
    ) -> Result<Scene<'a>, TraceSceneError> {
        if lights.len() > MAX_LIGHTS {
            return Err(TraceSceneError::TooManyLights);
        }
        if objects.len() >= u32::MAX as usize {
            return Err(TraceSceneError::TooManyObjects);
        }
        if materials.len() + checkers.len() > usize::from(u16::MAX) {
            return Err(TraceSceneError::UnknownMaterial);
        }
        let known = |m: u16| usize::from(m) < materials.len();
        if checkers
            .iter()
            .any(|c| !known(c.a) || !known(c.b) || !CHECKER_SHIFTS.contains(&c.shift))
        {
            return Err(TraceSceneError::BadChecker);
        }
        for o in objects {
            match usize::from(o.material).checked_sub(materials.len()) {
                None => {}
                Some(k) if k >= checkers.len() => return Err(TraceSceneError::UnknownMaterial),
                Some(_) if o.shape.texture_axis().is_none() => {
                    return Err(TraceSceneError::CheckerOnShape)
                }
                Some(_) => {}
            }
        }
        if ambient < I16F16::ZERO || ambient > I16F16::ONE {
            return Err(TraceSceneError::BadColour);
        }
        // Checked again here, for materials and lights made field by field: the tracer's
        // products rely on these limits.
        Colour::new(background.0)?;
        materials.iter().try_for_each(Material::check)?;
        lights.iter().try_for_each(Light::check)?;
        Ok(Scene {
            objects,
            materials,
            checkers,
            lights,
            background,
            ambient,
            bvh: None,
            grid: None,
        })
    }
}

impl Scene<'_> {
    /// The index in [`Scene::materials`] of the material of `object` at `point` on its
    /// surface: its own, or its checker's cell's.
    #[inline]
    pub fn material_index_at(&self, object: &Object<'_>, point: Vec3) -> Option<u16> {
        let index = usize::from(object.material);
        if index < self.materials.len() {
            return Some(object.material);
        }
        let checker = self
            .checkers
            .get(index.checked_sub(self.materials.len())?)?;
        Some(checker.cell_material(point, object.shape.texture_axis()?))
    }

    /// The material of `object` at `point` on its surface: its own, or its checker's cell's.
    #[inline]
    pub fn material_at(&self, object: &Object<'_>, point: Vec3) -> Option<&Material> {
        self.materials
            .get(usize::from(self.material_index_at(object, point)?))
    }
}

/// The camera of a traced frame: `look_at` + `perspective` as in the rasterizers (DESIGN.md),
/// pixel centres at `(c + ½, r + ½)`.
///
/// The direction through pixel (c, r) is `corner + c·right + r·down`, accumulated in [`I8F24`]
/// (24 fraction bits, so 2048 steps add at most 2^-13 of error before the sum is rounded to
/// I16F16 and normalised); its component along the view direction is exactly 1, so a primary
/// ray's eye depth is its `t` along that direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceCamera {
    /// Eye position.
    pub eye: Vec3,
    /// Direction through the centre of pixel (0, 0).
    pub corner: [I8F24; 3],
    /// Step from one column to the next.
    pub right: [I8F24; 3],
    /// Step from one row to the next (downwards).
    pub down: [I8F24; 3],
    /// Near distance along the view direction (primary rays see eye depths in [near, far)).
    pub near: I16F16,
    /// Far distance along the view direction.
    pub far: I16F16,
    /// Image width in pixels.
    pub width: u16,
    /// Image height in pixels.
    pub height: u16,
}

impl TraceCamera {
    /// A camera at `eye` looking at `target`, `fovy_degrees` vertical field of view, aspect
    /// `width / height`, primary rays limited to eye depths in `[near, far)`. The basis is
    /// computed in f64 once; everything per pixel is integer.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
        fovy_degrees: f64,
        near: f64,
        far: f64,
        width: u16,
        height: u16,
    ) -> Result<TraceCamera, TraceSceneError> {
        let bad = TraceSceneError::BadCamera;
        let limit = MAX_COORD.to_num::<f64>();
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        if !finite(&eye) || !finite(&target) || !finite(&up) || !finite(&[fovy_degrees, near, far])
        {
            return Err(bad);
        }
        if eye.iter().any(|c| c.abs() > limit)
            || !(fovy_degrees > 0.0 && fovy_degrees <= 160.0)
            || !(near > 0.0 && far > near && far <= limit)
            || near < 1.0 / 256.0
            || width == 0
            || height == 0
            || width > MAX_TRACE_SIZE
            || height > MAX_TRACE_SIZE
        {
            return Err(bad);
        }
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let unit = |a: [f64; 3]| {
            let l = libm::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            if l > 1e-9 {
                Ok(a.map(|c| c / l))
            } else {
                Err(bad)
            }
        };
        let forward = unit(sub(target, eye))?;
        let right = unit(cross(forward, up))?;
        let true_up = cross(right, forward);
        // Half-heights of the image plane at distance 1.
        let half_h = libm::tan(fovy_degrees.to_radians() / 2.0);
        let half_w = half_h * f64::from(width) / f64::from(height);
        let (sx, sy) = (
            2.0 * half_w / f64::from(width),
            2.0 * half_h / f64::from(height),
        );
        let corner: [f64; 3] = core::array::from_fn(|i| {
            forward[i] + right[i] * (-half_w + sx / 2.0) + true_up[i] * (half_h - sy / 2.0)
        });
        let fix = |v: [f64; 3]| -> Result<[I8F24; 3], TraceSceneError> {
            let mut out = [I8F24::ZERO; 3];
            for (o, c) in out.iter_mut().zip(v) {
                // Keep |corner + W·right + H·down| below 2^6 per component.
                if c.abs() >= 16.0 {
                    return Err(bad);
                }
                *o = I8F24::checked_from_num(c).ok_or(bad)?;
            }
            Ok(out)
        };
        let fix1 = |v: f64| I16F16::checked_from_num(v).ok_or(bad);
        let eye = Vec3 {
            x: fix1(eye[0])?,
            y: fix1(eye[1])?,
            z: fix1(eye[2])?,
        };
        if half_w > 16.0 {
            return Err(bad);
        }
        Ok(TraceCamera {
            eye,
            corner: fix(corner)?,
            right: fix(right.map(|c| c * sx))?,
            down: fix(true_up.map(|c| -c * sy))?,
            near: fix1(near)?,
            far: fix1(far)?,
            width,
            height,
        })
    }

    /// The camera in `f32` for the hybrid mode's per-frame and per-row estimates: the
    /// directions through pixel (0, 0), one column right and one row down, and the eye.
    pub(crate) fn float_basis(&self) -> [[f32; 3]; 4] {
        let f = |v: [I8F24; 3]| v.map(|c| c.to_num::<f32>());
        let eye = self.eye.bits().map(|c| c as f32 / 65536.0);
        [f(self.corner), f(self.right), f(self.down), eye]
    }

    /// The classic scene's view (`sim/scenes/classic.scene`, its corpus camera "front") at
    /// `width × height`, for tests.
    #[cfg(test)]
    pub(crate) fn classic(width: u16, height: u16) -> TraceCamera {
        let view = ([0.0, 3.0, 7.0], [0.0, 0.8, 0.0], [0.0, 1.0, 0.0]);
        TraceCamera::new(view.0, view.1, view.2, 50.0, 0.1, 100.0, width, height)
            .expect("the classic view is valid")
    }

    /// The direction through the centre of pixel (`column`, `row`), not normalised: its
    /// component along the view direction is 1. Raw I16F16 bits.
    #[inline]
    pub fn pixel_direction(&self, column: u16, row: u16) -> Vec3 {
        let (c, r) = (i32::from(column), i32::from(row));
        // |corner| < 16 and |c·right|, |r·down| < 2·half-width ≤ 32: the sum stays below 2^7.
        let axis = |i: usize| {
            let pick = |v: &[I8F24; 3]| v.get(i).map_or(0, |x| x.to_bits());
            let sum = pick(&self.corner)
                .wrapping_add(pick(&self.right).wrapping_mul(c))
                .wrapping_add(pick(&self.down).wrapping_mul(r));
            // 24 → 16 fraction bits, rounded to nearest.
            (sum + (1 << 7)) >> 8
        };
        Vec3::from_bits(axis(0), axis(1), axis(2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::shape::{Plane, Polygon, Shape, Sphere};

    fn p(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3 {
            x: I16F16::from_num(x),
            y: I16F16::from_num(y),
            z: I16F16::from_num(z),
        }
    }

    #[test]
    fn checker_cells_are_floors_of_the_projected_coordinates() {
        let unit = Checker::new(0, 1, 0).unwrap();
        // Floor y = 0 (axis 1 dropped): u = x, v = z; (-4, -4) is even, its neighbours odd.
        assert_eq!(unit.cell_material(p(-3.5, 0.0, -3.5), 1), 0);
        assert_eq!(unit.cell_material(p(-2.5, 0.0, -3.5), 1), 1);
        assert_eq!(unit.cell_material(p(-3.5, 0.0, -2.5), 1), 1);
        // Boundaries belong to the cell above: x = 0 is cell 0, x = −2^-16 cell −1.
        assert_eq!(unit.cell_material(p(0.0, 0.0, 0.5), 1), 0);
        assert_eq!(
            unit.cell_material(Vec3::from_bits(-1, 0, 1 << 15), 1),
            1,
            "just below 0 is cell -1"
        );
        // The dropped axis does not matter; the other two do.
        assert_eq!(unit.cell_material(p(7.3, 0.5, 0.5), 0), 0);
        assert_eq!(unit.cell_material(p(7.3, 1.5, 0.5), 0), 1);
        assert_eq!(unit.cell_material(p(0.5, 1.5, 9.0), 2), 1);
        // Cells of 2 and of 1/4 units.
        let big = Checker::new(0, 1, 1).unwrap();
        assert_eq!(big.cell_material(p(1.9, 0.0, -0.1), 1), 1);
        assert_eq!(big.cell_material(p(2.1, 0.0, -0.1), 1), 0);
        let small = Checker::new(0, 1, -2).unwrap();
        assert_eq!(small.cell_material(p(0.3, 0.0, 0.1), 1), 1);
        assert_eq!(Checker::new(0, 1, 9), Err(TraceSceneError::BadChecker));
        assert_eq!(Checker::new(0, 1, -9), Err(TraceSceneError::BadChecker));
    }

    #[test]
    fn textured_scenes_are_checked() {
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let m = Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap();
        let materials = [
            m,
            Material {
                kr: I16F16::ZERO,
                ..m
            },
        ];
        let checkers = [Checker::new(0, 1, 0).unwrap()];
        let square = [
            p(0.0, 0.0, 0.0),
            p(0.0, 0.0, 2.0),
            p(2.0, 0.0, 2.0),
            p(2.0, 0.0, 0.0),
        ];
        let floor = Object {
            shape: Shape::Polygon(Polygon::new(&square).unwrap()),
            material: 2,
        };
        let plane = Object {
            shape: Shape::Plane(Plane::new(p(0.0, 1.0, 0.0), I16F16::ZERO).unwrap()),
            material: 2,
        };
        let ball = Object {
            shape: Shape::Sphere(Sphere::new(p(0.0, 1.0, 0.0), I16F16::ONE).unwrap()),
            material: 2,
        };
        let scene = |objects: &[Object<'_>], checkers: &[Checker]| {
            Scene::textured(
                objects,
                &materials,
                checkers,
                &[],
                Colour::BLACK,
                I16F16::ZERO,
            )
            .map(|_| ())
        };
        assert_eq!(scene(&[floor, plane], &checkers), Ok(()));
        assert_eq!(
            scene(&[floor, ball], &checkers),
            Err(TraceSceneError::CheckerOnShape)
        );
        assert_eq!(scene(&[floor], &[]), Err(TraceSceneError::UnknownMaterial));
        let missing = [Checker {
            b: 2,
            ..checkers[0]
        }];
        assert_eq!(scene(&[floor], &missing), Err(TraceSceneError::BadChecker));
        let objects = [floor];
        let textured = Scene::textured(
            &objects,
            &materials,
            &checkers,
            &[],
            Colour::BLACK,
            I16F16::ZERO,
        )
        .unwrap();
        assert_eq!(
            textured.material_at(&floor, p(0.5, 0.0, 0.5)),
            Some(&materials[0])
        );
        assert_eq!(
            textured.material_at(&floor, p(1.5, 0.0, 0.5)),
            Some(&materials[1])
        );
    }

    #[test]
    fn parts_made_field_by_field_are_checked_by_the_scene() {
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let m = Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap();
        let light = Light::point(p(0.0, 4.0, 0.0), I16F16::ONE).unwrap();
        let scene = |materials: &[Material], lights: &[Light], background: Colour| {
            Scene::new(&[], materials, lights, background, I16F16::ZERO).map(|_| ())
        };
        assert_eq!(scene(&[m], &[light], Colour::BLACK), Ok(()));
        let over = MAX_COEFFICIENT + I16F16::DELTA;
        let bad_materials = [
            (Material { kd: over, ..m }, TraceSceneError::BadCoefficient),
            (
                Material {
                    kr: -I16F16::DELTA,
                    ..m
                },
                TraceSceneError::BadCoefficient,
            ),
            (
                Material {
                    ior: MAX_IOR + I16F16::DELTA,
                    ..m
                },
                TraceSceneError::BadIor,
            ),
            (
                Material {
                    colour: Colour([I16F16::from_num(1.5); 3]),
                    ..m
                },
                TraceSceneError::BadColour,
            ),
        ];
        for (bad, error) in bad_materials {
            assert_eq!(scene(&[m, bad], &[light], Colour::BLACK), Err(error));
        }
        let bad_lights = [
            Light {
                intensity: over,
                ..light
            },
            Light {
                kind: LightKind::Point(p(5000.0, 0.0, 0.0)),
                ..light
            },
            Light {
                kind: LightKind::Directional(p(0.0, 2.0, 0.0)),
                ..light
            },
        ];
        for bad in bad_lights {
            assert_eq!(
                scene(&[m], &[light, bad], Colour::BLACK),
                Err(TraceSceneError::BadLight)
            );
        }
        let bright = Colour([I16F16::from_num(2); 3]);
        assert_eq!(
            scene(&[m], &[light], bright),
            Err(TraceSceneError::BadColour)
        );
    }

    #[test]
    fn camera_centre_ray_points_at_the_target() {
        let cam = TraceCamera::new(
            [0.0, 0.0, 5.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            60.0,
            0.1,
            100.0,
            4,
            4,
        )
        .unwrap();
        // Pixels (1, 1) and (2, 2) straddle the centre symmetrically.
        let a = cam.pixel_direction(1, 1).bits();
        let b = cam.pixel_direction(2, 2).bits();
        assert_eq!(a[2], -65536);
        assert!((a[0] + b[0]).abs() <= 1 && (a[1] + b[1]).abs() <= 1);
        assert!(
            a[0] < 0 && a[1] > 0,
            "row 0 is at the top, column 0 at the left"
        );
    }

    #[test]
    fn bad_cameras_are_rejected() {
        let ok = |eye, fov, near, far, w| {
            TraceCamera::new(eye, [0.0; 3], [0.0, 1.0, 0.0], fov, near, far, w, 4).is_ok()
        };
        assert!(ok([0.0, 0.0, 5.0], 60.0, 0.1, 100.0, 4));
        assert!(!ok([0.0, 0.0, 0.0], 60.0, 0.1, 100.0, 4));
        assert!(!ok([0.0, 0.0, 5.0], 0.0, 0.1, 100.0, 4));
        assert!(!ok([0.0, 0.0, 5.0], 60.0, 1.0, 0.5, 4));
        assert!(!ok([0.0, 0.0, 5.0], 60.0, 0.1, 100.0, 0));
        assert!(!ok([0.0, 0.0, 5.0], f64::NAN, 0.1, 100.0, 4));
        assert!(TraceCamera::new(
            [0.0, 5.0, 0.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            60.0,
            0.1,
            9.0,
            4,
            4
        )
        .is_err());
    }
}
