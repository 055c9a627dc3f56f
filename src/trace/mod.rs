//! Ray tracing in fixed point: the lecture's fourth hidden-surface method, a Whitted tracer with
//! shadows, reflection and refraction, row by row into the same [`RowSink`](crate::sink::RowSink)s
//! as the rasterizers, with no frame buffer and no depth memory.
//!
//! [`vector`] (I16F16 vectors, integer square root) → [`shape`] (primitives, validated) →
//! [`intersect`] (ray–primitive tests) → [`bvh`] (bounding volumes, built into caller buffers
//! or exported as `static` data) → [`scene`] (materials, checker textures, lights, camera) →
//! [`row_shadow`] (hybrid mode's per-row shadow candidates) → [`tracer`] (the ray tree on an
//! explicit stack, shading, rows, the shadow cache) → [`hybrid`] (primary visibility from the
//! objects' screen bounds instead of a walk per pixel, the row's shadow candidates).
//!
//! ## Envelope and bit budget
//!
//! | quantity | format | limit | why |
//! |---|---|---|---|
//! | coordinates, radii, `t` | [`I16F16`](fixed::types::I16F16) | ±[`MAX_COORD`](vector::MAX_COORD) = 4096 | dot products of differences (< 3·2^26) fit [`I32F32`](fixed::types::I32F32) |
//! | directions, normals | I16F16, unit length ± 2^-15 | — | normalised with a 32-bit integer square root |
//! | colours, coefficients | I16F16 | [0, 1] colours, [0, 8] coefficients | products stay below 2^6 |
//! | camera steps | [`I8F24`](fixed::types::I8F24) | half-width of the view ≤ 16 at distance 1 | 2048 steps accumulate below 2^-13 |
//! | image | — | 1 to 2048 pixels per side | — |
//! | lights | — | ≤ 8 | one bit each in the shadow mask |
//! | ray length through a hierarchy | — | below 2^10 world units | the box test's rounding (t · 2^-16) stays inside the boxes' padding [`bvh::PAD`] |
//!
//! RAM per frame: one row of pixels (the caller's slice) plus the ray stack (`STACK` × 36 bytes)
//! on the call stack; the scene is borrowed and may live in flash.
//!
//! ```
//! use embedded_graphics::pixelcolor::Rgb565;
//! use fixed::types::I16F16;
//! use scanline3d::sink::HashSink;
//! use scanline3d::trace::{Colour, Light, Material, Object, Scene, Shape, Sphere, TraceCamera, TraceOptions, Tracer, Vec3};
//!
//! let f = I16F16::from_num;
//! let p = |x: f64, y: f64, z: f64| Vec3 { x: f(x), y: f(y), z: f(z) };
//! let red = Material::new(Colour::new([f(1.0), f(0.2), f(0.2)])?, [f(0.1), f(0.9), f(0.0), f(0.0)], f(1.0))?;
//! let objects = [Object { shape: Shape::Sphere(Sphere::new(p(0.0, 0.0, 0.0), f(1.0))?), material: 0 }];
//! let lights = [Light::point(p(5.0, 5.0, 5.0), f(1.0))?];
//! let materials = [red];
//! let scene = Scene::new(&objects, &materials, &lights, Colour::BLACK, f(0.2))?;
//! let camera = TraceCamera::new([0.0, 0.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0], 60.0, 0.1, 100.0, 32, 24)?;
//! let mut row = [Rgb565::new(0, 0, 0); 32];
//! let mut sink = HashSink::new();
//! let stats = Tracer::<5>::new(&scene, &camera, TraceOptions::default()).render(&mut row, &mut sink).unwrap();
//! assert_eq!((stats.rows, stats.primary_rays, stats.dropped_rays), (24, 32 * 24, 0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod bvh;
pub mod grid;
pub mod hybrid;
pub mod intersect;
pub mod row_shadow;
pub mod scene;
pub mod shape;
pub mod tracer;
pub mod vector;

pub use hybrid::ScreenBound;
pub use intersect::Ray;
pub use row_shadow::ShadowCandidate;
pub use scene::{Checker, Colour, Light, LightKind, Material, Scene, TraceCamera, TraceSceneError};
pub use shape::{Object, Plane, Polygon, Shape, ShapeError, Sphere, Triangle};
pub use tracer::{PixelTrace, ShadowCache, TraceError, TraceOptions, TraceStats, Tracer};
pub use vector::Vec3;
