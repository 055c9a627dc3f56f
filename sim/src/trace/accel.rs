//! The scene's acceleration structure, chosen per render: none (brute force), a bounding-volume
//! hierarchy, a uniform grid, or both (a grid whose cells hold a hierarchy). Every choice gives
//! the same hits (see [`super::query`] on ties); they differ in the tests they need.
//!
//! Unbounded objects (planes) are outside every structure and tested on every ray.

use super::bvh::Bvh;
use super::grid::Grid;
use super::intersect::bounds;
use super::query::{Counters, Hit, Query};
use super::scene::TracedScene;
use super::vector::{Ray, Span};

/// Which acceleration a tracer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// Test every object (the lecture's baseline).
    None,
    /// Bounding volumes: a hierarchy of boxes over the objects.
    Bvh,
    /// Space subdivision: a uniform grid walked with 3D-DDA.
    Grid,
    /// Both: a grid whose cells hold a hierarchy over their objects.
    Both,
}

impl Structure {
    /// Every choice, brute force first.
    pub const ALL: [Structure; 4] = [
        Structure::None,
        Structure::Bvh,
        Structure::Grid,
        Structure::Both,
    ];

    /// Lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            Structure::None => "none",
            Structure::Bvh => "bvh",
            Structure::Grid => "grid",
            Structure::Both => "both",
        }
    }
}

#[derive(Clone, Debug)]
enum Index {
    None,
    Bvh(Bvh),
    Grid(Grid),
}

/// A built acceleration structure over one scene.
#[derive(Clone, Debug)]
pub struct Accel<'a> {
    scene: &'a TracedScene,
    structure: Structure,
    unbounded: Vec<usize>,
    index: Index,
}

impl<'a> Accel<'a> {
    /// Builds `structure` over `scene`.
    pub fn build(scene: &'a TracedScene, structure: Structure) -> Self {
        let mut unbounded = Vec::new();
        let mut items = Vec::new();
        for (id, o) in scene.objects.iter().enumerate() {
            match bounds(&o.shape) {
                Some(b) => items.push((id, b)),
                None => unbounded.push(id),
            }
        }
        let n = scene.objects.len();
        let index = match structure {
            Structure::None => {
                // Brute force tests everything in id order.
                unbounded = (0..n).collect();
                Index::None
            }
            Structure::Bvh => Index::Bvh(Bvh::build(&items)),
            Structure::Grid => Index::Grid(Grid::build(&items, n, false)),
            Structure::Both => Index::Grid(Grid::build(&items, n, true)),
        };
        Accel {
            scene,
            structure,
            unbounded,
            index,
        }
    }

    /// The structure this is.
    pub fn structure(&self) -> Structure {
        self.structure
    }

    /// The scene it indexes.
    pub fn scene(&self) -> &'a TracedScene {
        self.scene
    }

    /// Grid cells per axis, if this has a grid.
    pub fn grid_dims(&self) -> Option<[usize; 3]> {
        match &self.index {
            Index::Grid(g) => Some(g.dims()),
            _ => None,
        }
    }

    fn run(&self, ray: Ray, span: Span, any: bool, counters: &mut Counters) -> Option<Hit> {
        let mut q = Query::new(self.scene, ray, span, any);
        for &id in &self.unbounded {
            if q.done() {
                break;
            }
            q.test(id);
        }
        if !q.done() {
            match &self.index {
                Index::None => {}
                Index::Bvh(b) => b.walk(&mut q),
                Index::Grid(g) => g.walk(&mut q),
            }
        }
        counters.add(&q.counters);
        q.best
    }

    /// The nearest hit in `span`.
    pub fn nearest(&self, ray: Ray, span: Span, counters: &mut Counters) -> Option<Hit> {
        self.run(ray, span, false, counters)
    }

    /// Whether anything is hit in `span` (a shadow ray).
    pub fn blocked(&self, ray: Ray, span: Span, counters: &mut Counters) -> bool {
        self.run(ray, span, true, counters).is_some()
    }
}
