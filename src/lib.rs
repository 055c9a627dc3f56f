//! # scanline3d
//!
//! An allocation-free, fixed-point scanline 3D renderer with a span z-buffer, for
//! microcontroller displays.
//!
//! Triangle meshes (borrowed from flash) are transformed, clipped and projected in fixed point,
//! bucketed by their first row, and walked row by row with exact edge stepping. Visibility is
//! resolved with one row of depth (the span z-buffer), and every finished row goes to a
//! [`RowSink`](sink::RowSink): an embedded-graphics `DrawTarget`, a frame buffer or a closure
//! that feeds a panel, with no frame buffer needed. The other classic hidden-surface methods
//! (band and full-frame z-buffer, span sorting, depth sort, Newell–Newell–Sancha, BSP order,
//! Warnock) run on the same pipeline: see [`resolve`].
//!
//! A user names every precision choice once (a [`Config`]: [`Settings`] with a
//! [`preset`], or a type of their own), all memory once (a [`Storage`], whose
//! `const fn new` lets it live in a `static`), and renders with `render(&scene, &mut sink)`:
//!
//! ```
//! use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
//! use fixed::types::I16F16;
//! use scanline3d::scene::{Instance, Light, Mesh, MeshColors, Scene, Transform};
//! use scanline3d::sink::{FnSink, Row};
//! use scanline3d::{preset, Config, Flat, Settings, Storage};
//!
//! type Cfg = Settings<Rgb565, Flat, preset::Balanced>;
//!
//! let c = |v: f32| I16F16::from_num(v);
//! let vertices = [[c(-1.0), c(-1.0), c(0.0)], [c(1.0), c(-1.0), c(0.0)], [c(0.0), c(1.0), c(0.0)]];
//! let triangles = [[0, 1, 2]];
//! let mesh = Mesh::new(&vertices, &triangles, MeshColors::Uniform(Rgb888::new(255, 128, 0)), None)?;
//! let instances = [Instance { mesh: &mesh, transform: Transform::rotation_y(0.3) }];
//! let camera = Cfg::camera([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0], 60.0, 0.1, 50.0)?;
//! let scene = Scene::new(&instances, camera, Light::new([0.3, 0.5, 1.0], 0.2, 0.8)?)?;
//!
//! // 64×48 pixels, room for 16 triangles, 8 active per row: under 2 KiB of RAM.
//! let mut renderer: Storage<Cfg, 64, 48, 16, 8> = Storage::new(Rgb565::new(0, 0, 0));
//! let mut lit = 0;
//! let mut panel = FnSink(|row: Row<'_, Rgb565>| -> Result<(), ()> {
//!     lit += row.pixels.iter().filter(|p| **p != Rgb565::new(0, 0, 0)).count();
//!     Ok(()) // here a driver would send the row over SPI
//! });
//! let stats = renderer.render(&scene, &mut panel).unwrap();
//! assert_eq!(stats.rows, 48);
//! assert_eq!(stats.pixels_written as usize, lit);
//! # Ok::<(), scanline3d::scene::SceneError>(())
//! ```
//!
//! ## From an OBJ file to firmware
//!
//! `sim analyze model.obj` (in this repository's `sim/`) measures what the model needs over a
//! set of views: sub-pixel bits for an accuracy goal, capacities, whether clipping or culling
//! can change the image. `sim export model.obj --out scene.rs` writes it as `static` I16F16
//! data with `VIEWS`, `PROJECTION`, `LIGHT` and a `SceneStorage<C>` sized for those views;
//! include it with `mod scene;` and build each frame as `Scene::new(&[Instance { mesh:
//! &scene::MESH, .. }], C::camera(eye, target, up, fovy, near, far)?, light)`. The
//! repository's `docs/export.md` walks through it.
//!
//! ## Pipeline (one module per stage)
//!
//! [`scene`] → `vertex` (transform, lighting) → [`clip`] → `project` → `raster` (setup,
//! edge walk) → `render` (buckets, active list) → [`workspace`] (the span z-buffer in a
//! [`depth`] format) or a [`resolve`] method, with [`shading`] → [`sink`]. [`options`] and
//! [`stats`] are what a frame takes and reports; [`config`], [`method`] and [`renderer`] put
//! them behind one call. An optional [`cache`] keeps each vertex's transform and projection
//! for the frame, trading RAM for set-up time. [`patch`] feeds the same pipeline with
//! Bezier patches from flash, tessellated row by row as the rows reach them.
//!
//! ## Rules
//!
//! Pixel centres at `(c + ½, r + ½)`, top-left fill rule, exact edge walking: see `raster`.
//! Every fixed-point format is named in its type and each stage documents its bit budget.
//! Nothing on the render path allocates, panics or uses `unsafe`: `examples/panic_never.rs`
//! links only if no panic is reachable from it.
//!
//! ## Operating envelope
//!
//! Input outside these limits is rejected with a specific error where it enters (mesh and camera
//! construction, or the frame's transform set-up), never clamped silently:
//!
//! | limit | value | reason (bit budget) |
//! |---|---|---|
//! | model coordinates | ±[`MAX_MODEL_COORD`](scene::MAX_MODEL_COORD) = 4096 | I16F16 products stay far below the eye-space limit (`vertex`) |
//! | eye coordinates | ±2^14, checked per instance and frame | I16F16 with 2× headroom for clip interpolation (`vertex`) |
//! | target size | 1 to [`MAX_SCREEN`](project::MAX_SCREEN) = 2048 per side | with the guard band, sub-pixel coordinates stay below 2^22 (`project`, `raster`) |
//! | sub-pixel bits | 0 to 8 | same |
//! | near plane | ≥ [`MIN_NEAR`](scene::MIN_NEAR) = 1/256 | `near` keeps 8 significant bits in I16F16 |
//! | far plane | ≤ [`MAX_EYE_DISTANCE`](scene::MAX_EYE_DISTANCE) = 16384 | eye-space envelope |
//! | far/near | ≤ [`MAX_FAR_NEAR_RATIO`](scene::MAX_FAR_NEAR_RATIO) = 2^20 | `q = near/w` keeps ≥ 2^10 steps of I2F30 at the far plane: relative depth resolution 2^-30 · far/near ≤ 2^-10 there |
//! | instances | `INSTANCES` of the [`Workspace`], default [`MAX_INSTANCES`](options::MAX_INSTANCES) = 8 | per-frame set-up on the stack, about 120 B each |
//! | triangles per frame | [`MAX_SCENE_TRIANGLES`](scene::MAX_SCENE_TRIANGLES) = 65535 over all instances, checked by [`Scene::new`](scene::Scene::new) and per frame; `TRIS` (and `PIECES`) ≤ 65535 | 16-bit triangle ids and bucket links, `u16::MAX` ends a list |
//!
//! Any triangle size works: triangles far larger than the screen are clipped to a guard band of
//! 8 half-screens; triangles smaller than a pixel cover exactly the centres they contain (often
//! none). Exactly coplanar overlapping surfaces resolve deterministically: the triangle that
//! becomes active first (earlier first row, then lower id) keeps the pixel. Each limit has a test
//! at the limit and just past it (`tests/suite/envelope.rs`).
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;
#[cfg(test)]
mod test_rng;

pub mod arithmetic;
pub mod cache;
pub mod clip;
pub mod config;
pub mod depth;
pub mod math;
pub mod metaball;
pub mod method;
pub mod options;
pub mod patch;
pub mod preset;
// A pipeline stage: public only with the feature `internals` (measurement firmware, tests).
#[cfg(feature = "internals")]
pub mod project;
#[cfg(not(feature = "internals"))]
mod project;
// A pipeline stage: public only with the feature `internals` (measurement firmware, tests).
#[cfg(feature = "internals")]
pub mod raster;
#[cfg(not(feature = "internals"))]
mod raster;
// A pipeline stage: public only with the feature `internals` (measurement firmware, tests).
#[cfg(feature = "internals")]
pub mod render;
#[cfg(not(feature = "internals"))]
mod render;
pub mod renderer;
pub mod resolve;
pub mod scene;
pub mod shading;
pub mod sink;
pub mod stats;
pub mod trace;
// A pipeline stage: public only with the feature `internals` (measurement firmware, tests).
#[cfg(feature = "internals")]
pub mod vertex;
#[cfg(not(feature = "internals"))]
mod vertex;
pub mod workspace;

pub use config::{Config, Settings};

// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub use depth::Depth;
pub use options::RenderOptions;
pub use renderer::{Renderer, Storage, View};
pub use shading::{Flat, Gouraud, Shading, Unlit};
pub use stats::{FrameStats, RenderError};
pub use workspace::Workspace;
