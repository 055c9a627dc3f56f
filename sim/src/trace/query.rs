//! A ray query over the scene's objects: nearest hit or any hit, with counters of the tests it
//! makes. The acceleration structures ([`super::bvh`], [`super::grid`]) feed it object ids; it
//! runs the exact intersection test and keeps the best hit.
//!
//! Ties: the nearest `t` wins and equal `t` goes to the smaller id, so every structure that
//! offers the hit object returns the same hit as brute force.

use super::intersect::intersect;
use super::scene::TracedScene;
use super::vector::{Ray, Span, V3};

/// The nearest surface a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Object id (index in [`TracedScene::objects`]).
    pub id: usize,
    /// Ray parameter.
    pub t: f64,
    /// Outward unit normal of the surface there.
    pub normal: V3,
}

/// How much work queries did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Exact ray–object intersection tests.
    pub object_tests: u64,
    /// Ray–box tests (bounding-volume nodes and the grid's outer box).
    pub box_tests: u64,
    /// Grid cells visited by the 3D-DDA.
    pub cells: u64,
}

impl Counters {
    /// Adds `o` to these counters.
    pub fn add(&mut self, o: &Counters) {
        self.object_tests += o.object_tests;
        self.box_tests += o.box_tests;
        self.cells += o.cells;
    }
}

/// One query in progress.
pub struct Query<'a> {
    scene: &'a TracedScene,
    /// The ray.
    pub ray: Ray,
    /// What is still acceptable: shrinks to the best hit so far.
    pub span: Span,
    /// The best hit so far.
    pub best: Option<Hit>,
    /// Stop at the first hit (shadow rays).
    any: bool,
    /// Work done.
    pub counters: Counters,
    /// Objects already tested, when a structure may offer one object more than once (empty:
    /// no mailbox).
    mailbox: Vec<bool>,
}

impl<'a> Query<'a> {
    /// A query for the nearest hit (`any` false) or for any hit.
    pub fn new(scene: &'a TracedScene, ray: Ray, span: Span, any: bool) -> Self {
        Query {
            scene,
            ray,
            span,
            best: None,
            any,
            counters: Counters::default(),
            mailbox: Vec::new(),
        }
    }

    /// Tests each of `objects` at most once from now on (the grid lists an object in every
    /// cell it overlaps).
    pub fn use_mailbox(&mut self, objects: usize) {
        if self.mailbox.len() != objects {
            self.mailbox = vec![false; objects];
        }
    }

    /// Whether the query needs no more tests.
    pub fn done(&self) -> bool {
        self.any && self.best.is_some()
    }

    /// Runs the exact test against object `id`.
    pub fn test(&mut self, id: usize) {
        let Some(object) = self.scene.objects.get(id) else {
            return;
        };
        if let Some(seen) = self.mailbox.get_mut(id) {
            if std::mem::replace(seen, true) {
                return;
            }
        }
        self.counters.object_tests += 1;
        let Some(h) = intersect(&object.shape, &self.ray, self.span) else {
            return;
        };
        let better = match self.best {
            None => true,
            Some(b) => h.t < b.t || (h.t == b.t && id < b.id),
        };
        if better {
            self.best = Some(Hit {
                id,
                t: h.t,
                normal: h.normal,
            });
            // Keep equal parameters acceptable so the smaller id can still win a tie.
            self.span.max = next_up(h.t);
        }
    }
}

/// The next float above `t` (for a finite `t`).
fn next_up(t: f64) -> f64 {
    if t == 0.0 {
        f64::from_bits(1)
    } else if t > 0.0 {
        f64::from_bits(t.to_bits() + 1)
    } else {
        f64::from_bits(t.to_bits() - 1)
    }
}
