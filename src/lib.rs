//! # scanline3d
//!
//! An allocation-free, fixed-point scanline 3D renderer with a span z-buffer, for
//! microcontroller displays.
//!
//! Triangle meshes (borrowed from flash) are transformed, clipped and projected in fixed point,
//! bucketed by their first row, and walked row by row with exact edge stepping. Visibility is
//! resolved with one row of depth (the span z-buffer), and every finished row goes to a
//! [`RowSink`](sink::RowSink): an embedded-graphics `DrawTarget`, a frame buffer or a closure
//! that feeds a panel, with no frame buffer needed.
//!
//! ```
//! use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
//! use fixed::types::I16F16;
//! use scanline3d::scene::{Camera, Instance, Light, Mesh, MeshColors, Scene, Transform};
//! use scanline3d::sink::FnSink;
//! use scanline3d::{Flat, RenderOptions, Workspace};
//!
//! let c = |v: f32| I16F16::from_num(v);
//! let vertices = [[c(-1.0), c(-1.0), c(0.0)], [c(1.0), c(-1.0), c(0.0)], [c(0.0), c(1.0), c(0.0)]];
//! let triangles = [[0, 1, 2]];
//! let mesh = Mesh::new(&vertices, &triangles, MeshColors::Uniform(Rgb888::new(255, 128, 0)), None)?;
//! let instances = [Instance { mesh: &mesh, transform: Transform::rotation_y(0.3) }];
//! let scene = Scene {
//!     instances: &instances,
//!     camera: Camera::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?.perspective(60.0, 0.1, 50.0)?,
//!     light: Light::new([0.3, 0.5, 1.0], 0.2, 0.8)?,
//! };
//!
//! // 64×48 pixels, room for 16 triangles, 8 active per row: under 2 KiB of RAM.
//! let mut ws: Workspace<Rgb565, Flat, 64, 48, 16, 8> = Workspace::new(Rgb565::new(0, 0, 0));
//! let mut lit = 0;
//! let mut panel = FnSink(|row: scanline3d::sink::Row<'_, Rgb565>| -> Result<(), ()> {
//!     lit += row.pixels.iter().filter(|p| **p != Rgb565::new(0, 0, 0)).count();
//!     Ok(()) // here a driver would send the row over SPI
//! });
//! let stats = ws.render(&scene, &RenderOptions::default(), &mut panel).unwrap();
//! assert_eq!(stats.rows, 48);
//! assert_eq!(stats.pixels_written as usize, lit);
//! # Ok::<(), scanline3d::scene::SceneError>(())
//! ```
//!
//! ## Pipeline (one module per stage)
//!
//! [`scene`] → [`vertex`] (transform, lighting) → [`clip`] → [`project`] → [`raster`] (setup,
//! edge walk) → [`render`] (buckets, active list, span z-buffer) with [`shading`] → [`sink`].
//!
//! ## Rules
//!
//! Pixel centres at `(c + ½, r + ½)`, top-left fill rule, exact edge walking: see [`raster`].
//! Every fixed-point format is named in its type and each stage documents its bit budget.
//! Nothing on the render path allocates, panics or uses `unsafe`.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod clip;
pub mod demo;
pub mod math;
pub mod project;
pub mod raster;
pub mod render;
pub mod scene;
pub mod shading;
pub mod sink;
pub mod vertex;

pub use project::Depth;
pub use render::{FrameStats, RenderError, RenderOptions, Workspace};
pub use shading::{Flat, Gouraud, Shading};
