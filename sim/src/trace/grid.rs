//! Space subdivision, the lecture's second acceleration: a uniform grid of cells over the
//! bounded objects, walked front to back with the 3D-DDA (Amanatides–Woo), so a ray tests only
//! the objects in the cells it passes through and stops at the first cell that contains its
//! nearest hit.
//!
//! An object is listed in every cell its bounding box overlaps. Resolution: about
//! [`CELLS_PER_OBJECT`] cells per object, shaped like the scene's box, at most [`MAX_CELLS`] per
//! axis. A ray remembers which objects it tested (mailbox), so an object spanning many cells is
//! tested once per ray; a hit beyond the current cell is kept as a candidate and accepted when
//! the walk reaches a cell whose exit lies beyond it.

use super::bvh::Bvh;
use super::intersect::Aabb;
use super::query::Query;

/// Target cells per object.
pub const CELLS_PER_OBJECT: f64 = 4.0;
/// Most cells along one axis.
pub const MAX_CELLS: usize = 64;

/// What a cell holds: its objects as a list, or (both accelerations) a hierarchy over them.
#[derive(Clone, Debug)]
enum Cell {
    List(Vec<usize>),
    Tree(Bvh),
}

/// A uniform grid over bounded objects.
#[derive(Clone, Debug)]
pub struct Grid {
    bounds: Aabb,
    dims: [usize; 3],
    size: [f64; 3],
    cells: Vec<Cell>,
    objects: usize,
}

impl Grid {
    /// Builds the grid over `(id, box)` pairs; with `nested`, each cell holding more than one
    /// object gets a bounding-volume hierarchy over them (both accelerations at once).
    pub fn build(items: &[(usize, Aabb)], objects: usize, nested: bool) -> Grid {
        let bounds = items.iter().fold(Aabb::EMPTY, |b, (_, a)| b.union(a));
        let ext = [0, 1, 2].map(|k| (bounds.max[k] - bounds.min[k]).max(0.0));
        let longest = ext.iter().cloned().fold(0.0f64, f64::max);
        // A flat scene still gets a sensible cell shape: no axis thinner than 1/64 of the longest.
        let ext = ext.map(|e| e.max(longest / MAX_CELLS as f64).max(f64::MIN_POSITIVE));
        let volume: f64 = ext.iter().product();
        let per_unit = (CELLS_PER_OBJECT * items.len().max(1) as f64 / volume).cbrt();
        let dims = ext.map(|e| ((e * per_unit).round() as usize).clamp(1, MAX_CELLS));
        let size = [0, 1, 2].map(|k| ext[k] / dims[k] as f64);
        let mut lists = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let mut grid = Grid {
            bounds,
            dims,
            size,
            cells: Vec::new(),
            objects,
        };
        for (id, b) in items {
            let lo = grid.cell_of(b.min);
            let hi = grid.cell_of(b.max);
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        lists[grid.index([x, y, z])].push(*id);
                    }
                }
            }
        }
        let mut by_id = vec![None; objects];
        for (id, b) in items {
            if let Some(slot) = by_id.get_mut(*id) {
                *slot = Some(*b);
            }
        }
        grid.cells = lists
            .into_iter()
            .map(|ids| {
                if nested && ids.len() > 1 {
                    let boxes: Vec<(usize, Aabb)> = ids
                        .iter()
                        .filter_map(|&id| by_id.get(id).copied().flatten().map(|b| (id, b)))
                        .collect();
                    Cell::Tree(Bvh::build(&boxes))
                } else {
                    Cell::List(ids)
                }
            })
            .collect();
        grid
    }

    /// Cells along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The cell holding point `p`, clamped into the grid.
    fn cell_of(&self, p: [f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|k| {
            let c = ((p[k] - self.bounds.min[k]) / self.size[k]).floor();
            if c.is_nan() || c < 0.0 {
                0
            } else {
                (c as usize).min(self.dims[k] - 1)
            }
        })
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Walks the cells the ray crosses, front to back, offering `query` their objects.
    pub fn walk(&self, query: &mut Query) {
        query.counters.box_tests += 1;
        let Some((t_enter, t_leave)) = self.bounds.clip(&query.ray, query.span) else {
            return;
        };
        let (o, d) = (query.ray.origin, query.ray.dir);
        let mut cell = self.cell_of(query.ray.at(t_enter));
        let mut step = [0i64; 3];
        let mut t_next = [f64::INFINITY; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for k in 0..3 {
            if d[k] > 0.0 {
                step[k] = 1;
                let edge = self.bounds.min[k] + (cell[k] + 1) as f64 * self.size[k];
                t_next[k] = (edge - o[k]) / d[k];
                t_delta[k] = self.size[k] / d[k];
            } else if d[k] < 0.0 {
                step[k] = -1;
                let edge = self.bounds.min[k] + cell[k] as f64 * self.size[k];
                t_next[k] = (edge - o[k]) / d[k];
                t_delta[k] = -self.size[k] / d[k];
            }
        }
        query.use_mailbox(self.objects);
        loop {
            query.counters.cells += 1;
            match self.cells.get(self.index(cell)) {
                Some(Cell::List(ids)) => {
                    for &id in ids {
                        query.test(id);
                    }
                }
                Some(Cell::Tree(bvh)) => bvh.walk(query),
                None => return,
            }
            let axis = (0..3)
                .min_by(|&a, &b| t_next[a].total_cmp(&t_next[b]))
                .unwrap_or(0);
            let cell_exit = t_next[axis].min(t_leave);
            if query.done() || query.best.is_some_and(|h| h.t <= cell_exit) {
                return;
            }
            if t_next[axis] > t_leave || step[axis] == 0 {
                return;
            }
            let next = cell[axis] as i64 + step[axis];
            if next < 0 || next >= self.dims[axis] as i64 {
                return;
            }
            cell[axis] = next as usize;
            t_next[axis] += t_delta[axis];
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::trace::accel::{Accel, Structure};
    use crate::trace::query::Counters;
    use crate::trace::scene::TracedScene;
    use crate::trace::vector::{Ray, Span};
    use std::path::Path;

    /// Unit boxes on a 4×4×4 lattice (touching faces) and small spheres between them: rays
    /// along cell boundaries, parallel to axes and from inside must find what brute force finds.
    #[test]
    fn dda_agrees_with_brute_force_on_boundaries_and_axis_parallel_rays() {
        let mut text = String::from("material m 1 1 1 0 1 0 0 1\n");
        for x in 0..4 {
            for y in 0..4 {
                for z in 0..4 {
                    if (x + y + z) % 3 == 0 {
                        text += &format!("box {x} {y} {z} {} {} {} m\n", x + 1, y + 1, z + 1);
                    } else if (x * y + z) % 4 == 1 {
                        text += &format!("sphere {}.5 {}.5 {}.5 0.3 m\n", x, y, z);
                    }
                }
            }
        }
        let scene = TracedScene::parse(&text, Path::new("."), "lattice").unwrap();
        let brute = Accel::build(&scene, Structure::None);
        let grid = Accel::build(&scene, Structure::Grid);
        let both = Accel::build(&scene, Structure::Both);
        let bvh = Accel::build(&scene, Structure::Bvh);
        assert!(grid.grid_dims().unwrap().iter().all(|&d| d > 1));
        let mut rays = Vec::new();
        for a in 0..=8 {
            for b in 0..=8 {
                let (u, v) = (a as f64 * 0.5, b as f64 * 0.5);
                // Axis-parallel rays, on and between cell boundaries, both directions.
                for (o, d) in [
                    ([-1.0, u, v], [1.0, 0.0, 0.0]),
                    ([5.0, u, v], [-1.0, 0.0, 0.0]),
                    ([u, -1.0, v], [0.0, 1.0, 0.0]),
                    ([u, v, 5.0], [0.0, 0.0, -1.0]),
                    ([u, v, 2.0], [0.6, 0.0, 0.8]),
                    ([u, 2.0, v], [-0.48, 0.6, 0.64]),
                ] {
                    rays.push(Ray { origin: o, dir: d });
                }
            }
        }
        let span = Span::open(1e-9, f64::INFINITY);
        let mut hits = 0;
        for ray in &rays {
            let mut c = Counters::default();
            let want = brute.nearest(*ray, span, &mut c);
            hits += want.is_some() as usize;
            assert_eq!(grid.nearest(*ray, span, &mut c), want, "{ray:?}");
            assert_eq!(both.nearest(*ray, span, &mut c), want, "{ray:?}");
            assert_eq!(bvh.nearest(*ray, span, &mut c), want, "{ray:?}");
            let blocked = want.is_some();
            assert_eq!(grid.blocked(*ray, span, &mut c), blocked);
        }
        assert!(hits > rays.len() / 3, "{hits} of {}", rays.len());
    }
}
