//! Space subdivision for the fixed tracer: a uniform grid of cubic cells over the scene's
//! bounded objects, built into caller-provided slices and walked front to back with the 3D-DDA.
//!
//! Cell `(i, j, k)` lists, in `items[starts[c]..starts[c + 1]]` with `c = i + nx·(j + ny·k)`,
//! every object whose box overlaps it (an object may be listed in several cells and is then
//! tested once per cell: no mailbox, which would need RAM per object). Unbounded objects
//! (planes) are tested by every ray, as with the hierarchy.
//!
//! ## Bit budget
//!
//! Times are kept in 32 fraction bits in an `i64`, from the same reciprocals as the hierarchy's
//! box test (below 2^32 raw): a distance of at most 2^13 units (2^29 raw) times a reciprocal
//! stays below 2^61. Cell indices are below 2^10 per axis.

use crate::trace::bvh::{bounds, RayInverse};
use crate::trace::intersect::Ray;
use crate::trace::shape::Object;
use crate::trace::vector::Vec3;
use fixed::types::{I16F16, I32F32};

/// The most cells along one axis.
pub const MAX_CELLS_PER_AXIS: u16 = 1024;

/// Why a grid was not built or not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridError {
    /// A buffer is too small.
    Capacity,
    /// The cell size is not positive, or makes more than [`MAX_CELLS_PER_AXIS`] cells on an axis.
    BadCellSize,
    /// `starts` or `items` are inconsistent with the cells or the objects.
    Malformed,
}

impl core::fmt::Display for GridError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            GridError::Capacity => "the grid buffers are too small",
            GridError::BadCellSize => {
                "the grid's cell size is not positive or makes too many cells"
            }
            GridError::Malformed => "the grid's cell lists are inconsistent",
        })
    }
}

impl core::error::Error for GridError {}

/// Where the grid lies and how it is divided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridShape {
    /// Minimum corner.
    pub min: Vec3,
    /// Edge of a cubic cell.
    pub cell: I16F16,
    /// Cells along x, y, z.
    pub dims: [u16; 3],
}

impl GridShape {
    /// The grid of cubic cells of edge `cell` over the box `lo..hi` (at least one cell per axis).
    pub fn around(lo: Vec3, hi: Vec3, cell: I16F16) -> Result<GridShape, GridError> {
        if cell <= I16F16::ZERO {
            return Err(GridError::BadCellSize);
        }
        let span = hi.sub(lo);
        let count = |extent: I16F16| -> Result<u16, GridError> {
            let n = extent.to_bits().checked_div(cell.to_bits()).unwrap_or(-1) + 1;
            u16::try_from(n)
                .ok()
                .filter(|n| *n >= 1 && *n <= MAX_CELLS_PER_AXIS)
                .ok_or(GridError::BadCellSize)
        };
        Ok(GridShape {
            min: lo,
            cell,
            dims: [count(span.x)?, count(span.y)?, count(span.z)?],
        })
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.dims.iter().map(|d| usize::from(*d)).product()
    }

    /// The cell index range along one axis covering `lo..=hi` on that axis.
    fn range(&self, axis: usize, lo: i32, hi: i32) -> (usize, usize) {
        let (min, dim) = (
            self.min.bits().get(axis).copied().unwrap_or(0),
            usize::from(self.dims.get(axis).copied().unwrap_or(1)),
        );
        let cell = self.cell.to_bits().max(1);
        let at = |v: i32| {
            (v.saturating_sub(min))
                .max(0)
                .checked_div(cell)
                .unwrap_or(0) as usize
        };
        let last = dim.saturating_sub(1);
        (at(lo).min(last), at(hi).min(last))
    }

    fn index(&self, c: [usize; 3]) -> usize {
        let [nx, ny, _] = self.dims.map(usize::from);
        c[0] + nx * (c[1] + ny * c[2])
    }
}

/// A uniform grid over a scene's objects, borrowed (it may be `static` data).
#[derive(Clone, Copy, Debug)]
pub struct Grid<'a> {
    shape: GridShape,
    starts: &'a [u32],
    items: &'a [u32],
    unbounded: &'a [u32],
}

/// Calls `f` with each cell index an object's box overlaps.
fn for_cells(shape: &GridShape, lo: Vec3, hi: Vec3, mut f: impl FnMut(usize)) {
    let (l, h) = (lo.bits(), hi.bits());
    let (x0, x1) = shape.range(0, l[0], h[0]);
    let (y0, y1) = shape.range(1, l[1], h[1]);
    let (z0, z1) = shape.range(2, l[2], h[2]);
    for z in z0..=z1 {
        for y in y0..=y1 {
            for x in x0..=x1 {
                f(shape.index([x, y, z]));
            }
        }
    }
}

/// Builds the grid `shape` over `objects`: `starts` needs `cells + 1` entries, `items` one per
/// (object, overlapped cell) pair, `unbounded` one per plane. Returns how many `items` and
/// `unbounded` entries it used.
pub fn build(
    objects: &[Object<'_>],
    shape: GridShape,
    starts: &mut [u32],
    items: &mut [u32],
    unbounded: &mut [u32],
) -> Result<(usize, usize), GridError> {
    let cells = shape.cells();
    let starts = starts.get_mut(..=cells).ok_or(GridError::Capacity)?;
    starts.fill(0);
    // Count per cell (shifted by one), then prefix sums, then fill.
    let mut planes = 0;
    for (id, o) in objects.iter().enumerate() {
        match bounds(&o.shape) {
            Some((lo, hi)) => for_cells(&shape, lo, hi, |c| {
                if let Some(s) = starts.get_mut(c + 1) {
                    *s += 1;
                }
            }),
            None => {
                *unbounded.get_mut(planes).ok_or(GridError::Capacity)? = id as u32;
                planes += 1;
            }
        }
    }
    let mut total = 0u32;
    for s in starts.iter_mut() {
        total += *s;
        *s = total;
    }
    if total as usize > items.len() {
        return Err(GridError::Capacity);
    }
    // starts[c] is now the end of cell c − 1 = the start of cell c; fill by advancing a cursor
    // kept in starts[c] itself, then shift back.
    for (id, o) in objects.iter().enumerate() {
        if let Some((lo, hi)) = bounds(&o.shape) {
            for_cells(&shape, lo, hi, |c| {
                if let Some(s) = starts.get_mut(c) {
                    if let Some(slot) = items.get_mut(*s as usize) {
                        *slot = id as u32;
                    }
                    *s += 1;
                }
            });
        }
    }
    // Each starts[c] now holds the end of cell c: shift right by one.
    for c in (1..=cells).rev() {
        let prev = starts.get(c - 1).copied().unwrap_or(0);
        if let Some(s) = starts.get_mut(c) {
            *s = prev;
        }
    }
    if let Some(s) = starts.first_mut() {
        *s = 0;
    }
    Ok((total as usize, planes))
}

impl<'a> Grid<'a> {
    /// A grid from its parts as [`build`] made them, checked: `starts` has `cells + 1`
    /// non-decreasing entries ending at `items.len()`, and every id names an object.
    pub fn new(
        shape: GridShape,
        starts: &'a [u32],
        items: &'a [u32],
        unbounded: &'a [u32],
        objects: usize,
    ) -> Result<Grid<'a>, GridError> {
        let ok = starts.len() == shape.cells() + 1
            && starts.first() == Some(&0)
            && starts.last().map(|l| *l as usize) == Some(items.len())
            && starts.windows(2).all(|w| w.first() <= w.get(1))
            && items
                .iter()
                .chain(unbounded)
                .all(|i| (*i as usize) < objects);
        if !ok || shape.cell <= I16F16::ZERO {
            return Err(GridError::Malformed);
        }
        Ok(Grid {
            shape,
            starts,
            items,
            unbounded,
        })
    }

    /// The objects outside the grid (planes), which every ray tests.
    pub fn unbounded(&self) -> &'a [u32] {
        self.unbounded
    }

    /// Calls `visit` with the objects of each cell the ray crosses within `[t_min, t_max)`,
    /// front to back; `visit` returns the new `t_max` or `None` to stop. The walk ends at the
    /// first cell whose far side lies beyond `t_max`. Returns the number of cells visited.
    pub fn walk(
        &self,
        ray: &Ray,
        t_min: I16F16,
        mut t_max: I16F16,
        mut visit: impl FnMut(u32, I16F16) -> Option<I16F16>,
    ) -> u32 {
        let inv = RayInverse::new(ray);
        let s = &self.shape;
        let cell = i64::from(s.cell.to_bits());
        let (min, o, d) = (s.min.bits(), ray.origin.bits(), ray.dir.bits());
        let dims = s.dims.map(i64::from);
        let hi = |a: usize| i64::from(min[a]) + cell * dims[a];
        // The ray's interval inside the grid's box, 32 fraction bits.
        let Some((enter, exit)) = inv.span(min, [hi(0), hi(1), hi(2)], t_min, t_max) else {
            return 0;
        };
        // Start cell: where the ray is at `enter` (I16F16 position = o + d·enter).
        let mut c = [0i64; 3];
        let mut next = [i64::MAX; 3]; // t of the next boundary per axis
        let mut delta = [i64::MAX; 3];
        let mut step = [0i64; 3];
        for a in 0..3 {
            let p = i64::from(o[a]) + ((i64::from(d[a]) * enter) >> 32);
            c[a] = (p - i64::from(min[a]))
                .checked_div(cell)
                .unwrap_or(0)
                .max(0)
                .min(dims[a] - 1);
            if let Some(r) = inv.reciprocal(a) {
                delta[a] = (cell * r).abs();
                let boundary = i64::from(min[a]) + cell * (c[a] + i64::from(r > 0));
                next[a] = (boundary - i64::from(o[a])) * r;
                step[a] = if r > 0 { 1 } else { -1 };
            }
        }
        let mut cells = 0;
        loop {
            cells += 1;
            let index = (c[0] + dims[0] * (c[1] + dims[1] * c[2])) as usize;
            let start = self.starts.get(index).copied().unwrap_or(0) as usize;
            let end = self.starts.get(index + 1).copied().unwrap_or(0) as usize;
            for id in self.items.get(start..end).unwrap_or(&[]) {
                match visit(*id, t_max) {
                    Some(t) => t_max = t,
                    None => return cells,
                }
            }
            // Leave along the axis whose boundary comes first.
            let a = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            let leave = next[a];
            // A hit before this cell's far side cannot be beaten by a later cell.
            if leave >= I32F32::from(t_max).to_bits() || leave > exit || step[a] == 0 {
                return cells;
            }
            c[a] += step[a];
            if c[a] < 0 || c[a] >= dims[a] {
                return cells;
            }
            next[a] = next[a].saturating_add(delta[a]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::shape::{Plane, Shape, Sphere};
    use std::vec::Vec;

    #[test]
    fn build_then_walk_meets_the_objects_on_the_ray_front_to_back() {
        // 10 spheres on the x axis, one off it, and a plane.
        let sphere = |x: i32, y: i32| Object {
            shape: Shape::Sphere(
                Sphere::new(Vec3::from_bits(x << 16, y << 16, 0), I16F16::from_num(0.4)).unwrap(),
            ),
            material: 0,
        };
        let mut objects: Vec<Object<'static>> = (0..10).map(|i| sphere(2 * i, 0)).collect();
        objects.push(sphere(5, 6));
        objects.push(Object {
            shape: Shape::Plane(
                Plane::new(Vec3::from_bits(0, 1 << 16, 0), I16F16::from_num(9)).unwrap(),
            ),
            material: 0,
        });
        let lo = Vec3::from_bits(-(1 << 16), -(1 << 16), -(1 << 16));
        let hi = Vec3::from_bits(19 << 16, 7 << 16, 1 << 16);
        let shape = GridShape::around(lo, hi, I16F16::from_num(2)).unwrap();
        let mut starts = std::vec![0u32; shape.cells() + 1];
        let mut items = std::vec![0u32; 200];
        let mut unbounded = [0u32; 4];
        let (used, planes) =
            build(&objects, shape, &mut starts, &mut items, &mut unbounded).unwrap();
        assert_eq!(planes, 1);
        assert_eq!(unbounded[0], 11);
        let grid = Grid::new(
            shape,
            &starts,
            &items[..used],
            &unbounded[..planes],
            objects.len(),
        )
        .unwrap();
        let ray = Ray {
            origin: Vec3::from_bits(-(3 << 16), 0, 0),
            dir: Vec3::from_bits(1 << 16, 0, 0),
        };
        let mut seen = Vec::new();
        grid.walk(&ray, I16F16::ZERO, I16F16::MAX, |id, t| {
            if seen.last() != Some(&id) {
                seen.push(id);
            }
            Some(t)
        });
        seen.dedup();
        let mut sorted = seen.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(
            sorted,
            (0..10).collect::<Vec<u32>>(),
            "every sphere on the axis, not the one off it"
        );
        assert_eq!(seen.first(), Some(&0), "front to back");
        // Errors.
        assert_eq!(
            GridShape::around(lo, hi, I16F16::ZERO),
            Err(GridError::BadCellSize)
        );
        assert_eq!(
            build(
                &objects,
                shape,
                &mut starts,
                &mut items[..3],
                &mut unbounded
            )
            .err(),
            Some(GridError::Capacity)
        );
        assert!(Grid::new(shape, &starts[1..], &items[..used], &[], objects.len()).is_err());
    }
}
