//! Building BSP trees on the host, for `scanline3d::resolve::bsp`.
//!
//! The tree is built in f64 model coordinates: each node's plane is that of one of its
//! triangles (the candidate among the first few that splits fewest others), triangles in the
//! plane stay in the node, the rest go to the front or back subtree, and triangles that
//! straddle the plane are cut in two (Sutherland–Hodgman, then fan-triangulated). The output
//! is a new mesh (split pieces keep their original triangle's colour; `origin` maps each piece
//! back to its original triangle id) and the nodes in pre-order, each node's triangles being a
//! consecutive range: the layout `BspTree::new` requires. No recursion: a convex mesh makes a
//! chain as deep as its triangle count.

use crate::scene::MeshData;
use scanline3d::resolve::bsp::{BspNode, BspTree, NO_CHILD};
use std::collections::HashMap;

type V3 = [f64; 3];

/// A built tree.
#[derive(Clone, Debug)]
pub struct Bsp {
    /// The split mesh, triangles in node order.
    pub mesh: MeshData,
    /// For each triangle of `mesh`, the id of the input triangle it is (part of).
    pub origin: Vec<u32>,
    /// The nodes, root first, in pre-order.
    pub nodes: Vec<BspNode>,
    /// Deepest node (the root is at depth 1).
    pub depth: usize,
    /// Triangles that were cut.
    pub splits: usize,
}

impl Bsp {
    /// Traversal stack a `BspWorkspace` needs for this tree (`STACK`): two entries per level
    /// plus one.
    pub fn stack_needed(&self) -> usize {
        2 * self.depth + 1
    }

    /// The tree as the library takes it, validated.
    pub fn tree(&self) -> Result<BspTree<'_>, String> {
        BspTree::new(&self.nodes, self.mesh.triangles.len()).map_err(|e| format!("BSP tree: {e:?}"))
    }
}

/// A node still to build: its triangles, its parent and on which side, its depth.
type Work = (Vec<Poly>, Option<(usize, bool)>, usize);

#[derive(Clone, Copy, Debug)]
struct Poly {
    v: [V3; 3],
    origin: u32,
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Unit normal and offset of `p`'s plane, or `None` for a degenerate triangle.
fn plane(p: &Poly) -> Option<(V3, f64)> {
    let n = cross(sub(p.v[1], p.v[0]), sub(p.v[2], p.v[0]));
    let len = dot(n, n).sqrt();
    if len == 0.0 || !len.is_finite() {
        return None;
    }
    let n = n.map(|c| c / len);
    Some((n, -dot(n, p.v[0])))
}

/// Where a triangle lies relative to a plane.
enum Side {
    On,
    Front,
    Back,
    Both,
}

/// Distances within this of the plane count as on it (model units; I16F16 resolution is
/// 1.5e-5, so this only absorbs f64 rounding).
const ON_PLANE: f64 = 1e-9;

fn side(p: &Poly, n: V3, d: f64) -> (Side, [f64; 3]) {
    let dist = p.v.map(|v| dot(n, v) + d);
    let front = dist.iter().any(|&x| x > ON_PLANE);
    let back = dist.iter().any(|&x| x < -ON_PLANE);
    let s = match (front, back) {
        (false, false) => Side::On,
        (true, false) => Side::Front,
        (false, true) => Side::Back,
        (true, true) => Side::Both,
    };
    (s, dist)
}

/// Cuts `p` by the plane with vertex distances `dist`: (front pieces, back pieces), each a fan
/// of the clipped polygon, winding preserved. New vertices are added to `created`.
fn split(p: &Poly, dist: [f64; 3], created: &mut Vec<V3>) -> (Vec<Poly>, Vec<Poly>) {
    let (mut front, mut back) = (Vec::new(), Vec::new());
    for k in 0..3 {
        let (a, b) = (p.v[k], p.v[(k + 1) % 3]);
        let (da, db) = (dist[k], dist[(k + 1) % 3]);
        if da >= -ON_PLANE {
            front.push(a);
        }
        if da <= ON_PLANE {
            back.push(a);
        }
        if (da > ON_PLANE && db < -ON_PLANE) || (da < -ON_PLANE && db > ON_PLANE) {
            let t = da / (da - db);
            let x = [0, 1, 2].map(|i| a[i] + t * (b[i] - a[i]));
            created.push(x);
            front.push(x);
            back.push(x);
        }
    }
    let fan = |poly: Vec<V3>| -> Vec<Poly> {
        (1..poly.len().saturating_sub(1))
            .map(|i| Poly {
                v: [poly[0], poly[i], poly[i + 1]],
                origin: p.origin,
            })
            .collect()
    };
    (fan(front), fan(back))
}

/// A split puts a new vertex on an edge that a neighbouring triangle (not split there) shares:
/// a T-junction. Snapped independently, the vertex and the neighbour's straight edge leave
/// pixel-sized cracks. This inserts every created vertex that lies inside another triangle's
/// edge into that triangle (a fan over the extra points), so neighbours share it; the pieces
/// stay in their node, so the order is unchanged. Node ranges are recomputed.
fn close_t_junctions(out: Vec<Poly>, nodes: &mut [BspNode], mut created: Vec<V3>) -> Vec<Poly> {
    const ON_EDGE: f64 = 1e-9;
    // Created vertices in a grid of cells about one typical edge long, so each edge looks at
    // the few vertices near it.
    let edges: f64 = out
        .iter()
        .map(|p| dot(sub(p.v[1], p.v[0]), sub(p.v[1], p.v[0])).sqrt())
        .sum();
    let cell = (edges / out.len().max(1) as f64).max(1e-6);
    let key = |p: V3| p.map(|c| (c / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<V3>> = HashMap::new();
    created.sort_by(|a, b| {
        a.iter()
            .zip(b)
            .fold(std::cmp::Ordering::Equal, |o, (x, y)| {
                o.then(x.total_cmp(y))
            })
    });
    created.dedup();
    for &p in &created {
        grid.entry(key(p)).or_default().push(p);
    }
    let on_edge = |a: V3, b: V3| -> Vec<(f64, V3)> {
        let (lo, hi) = (
            key([0, 1, 2].map(|i| a[i].min(b[i]) - ON_EDGE)),
            key([0, 1, 2].map(|i| a[i].max(b[i]) + ON_EDGE)),
        );
        let ab = sub(b, a);
        let len2 = dot(ab, ab);
        let mut hits = Vec::new();
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    for &p in grid.get(&[x, y, z]).into_iter().flatten() {
                        let t = dot(sub(p, a), ab) / len2;
                        let closest = [0, 1, 2].map(|i| a[i] + t * ab[i]);
                        let d = sub(p, closest);
                        let inside = t * len2.sqrt() > ON_EDGE && (1.0 - t) * len2.sqrt() > ON_EDGE;
                        if inside && dot(d, d) < ON_EDGE * ON_EDGE {
                            hits.push((t, p));
                        }
                    }
                }
            }
        }
        hits.sort_by(|x, y| x.0.total_cmp(&y.0));
        hits
    };
    let mut fixed = Vec::with_capacity(out.len());
    for node in nodes.iter_mut() {
        let range = node.first as usize..node.first as usize + node.count as usize;
        let first = fixed.len();
        let mut facing_front = first;
        for (k, p) in out[range].iter().enumerate() {
            if k == node.facing_front as usize {
                facing_front = fixed.len();
            }
            let mut outline = Vec::new();
            for k in 0..3 {
                let (a, b) = (p.v[k], p.v[(k + 1) % 3]);
                outline.push(a);
                outline.extend(on_edge(a, b).into_iter().map(|(_, x)| x));
            }
            if outline.len() == 3 {
                fixed.push(*p);
                continue;
            }
            // Fan from the corner with the fewest extra points on its two edges: those points
            // make the fan's only degenerate (zero-area) pieces.
            let n = outline.len();
            let apex = (0..n)
                .filter(|&i| p.v.contains(&outline[i]))
                .min_by_key(|&i| {
                    let corner = |j: usize| p.v.contains(&outline[(i + j) % n]);
                    (1..n).take_while(|&j| !corner(j)).count()
                        + (1..n).rev().take_while(|&j| !corner(j)).count()
                })
                .unwrap_or(0);
            for j in 1..n - 1 {
                let (b, c) = (outline[(apex + j) % n], outline[(apex + j + 1) % n]);
                fixed.push(Poly {
                    v: [outline[apex], b, c],
                    origin: p.origin,
                });
            }
        }
        if node.facing_front == node.count {
            facing_front = fixed.len();
        }
        node.first = first as u16;
        node.count = (fixed.len() - first) as u16;
        node.facing_front = (facing_front - first) as u16;
    }
    fixed
}

/// How many candidates, spread evenly over a node's list, are tried as its splitter.
const CANDIDATES: usize = 16;

/// Triangles, spread evenly over a node's list, on which candidates are scored.
const SAMPLE: usize = 512;

/// The candidate plane that cuts fewest triangles of (a sample of) `list`; ties: the more even
/// split.
fn choose(list: &[Poly]) -> Option<(V3, f64)> {
    let stride = (list.len() / CANDIDATES).max(1);
    let sample_stride = (list.len() / SAMPLE).max(1);
    list.iter()
        .step_by(stride)
        .filter_map(plane)
        .take(CANDIDATES)
        .min_by_key(|&(n, d)| {
            let (mut cut, mut front, mut back) = (0usize, 0usize, 0usize);
            for p in list.iter().step_by(sample_stride) {
                match side(p, n, d).0 {
                    Side::Both => cut += 1,
                    Side::Front => front += 1,
                    Side::Back => back += 1,
                    Side::On => {}
                }
            }
            (cut, front.abs_diff(back))
        })
}

/// Builds the tree of `mesh`. Errors if the split mesh no longer fits the renderer's 16-bit
/// indices.
pub fn build(mesh: &MeshData) -> Result<Bsp, String> {
    let pos = |i: u16| mesh.vertices[i as usize].map(|c| c.to_num::<f64>());
    let input: Vec<Poly> = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(k, t)| Poly {
            v: t.map(pos),
            origin: k as u32,
        })
        .collect();
    let mut nodes: Vec<BspNode> = Vec::new();
    let mut out: Vec<Poly> = Vec::new();
    let (mut depth, mut splits) = (0usize, 0usize);
    let mut created: Vec<V3> = Vec::new();
    // Work items: (triangles, parent node and which side, depth). Popping the front list
    // before the back list keeps the nodes in pre-order.
    let mut work: Vec<Work> = vec![(input.clone(), None, 1)];
    while let Some((list, parent, level)) = work.pop() {
        if list.is_empty() {
            continue;
        }
        depth = depth.max(level);
        let (n, d) = choose(&list).unwrap_or(([0.0, 0.0, 1.0], 0.0));
        let (mut on, mut front, mut back) = (Vec::new(), Vec::new(), Vec::new());
        for p in &list {
            match side(p, n, d) {
                (Side::On, _) => on.push(*p),
                (Side::Front, _) => front.push(*p),
                (Side::Back, _) => back.push(*p),
                (Side::Both, dist) => {
                    splits += 1;
                    let (f, b) = split(p, dist, &mut created);
                    front.extend(f);
                    back.extend(b);
                }
            }
        }
        // A list of degenerate triangles only: they all stay in this node.
        if plane(&list[0]).is_none() && on.is_empty() && choose(&list).is_none() {
            on = list.clone();
            front.clear();
            back.clear();
        }
        // The triangles facing the plane's front side first: with back-face culling the
        // library draws only those facing the eye, by the side of the plane it is on. A
        // piece faces as its original does (a split keeps the winding), decided here in f64
        // from the original, which rounding cannot turn over.
        let faces_front =
            |p: &Poly| plane(&input[p.origin as usize]).is_some_and(|(m, _)| dot(m, n) > 0.0);
        on.sort_by_key(|p| !faces_front(p));
        let facing_front = on.iter().filter(|p| faces_front(p)).count();
        let index = nodes.len();
        let (first, count) = (out.len(), on.len());
        if out.len() + count >= u16::MAX as usize || index >= u16::MAX as usize {
            return Err(format!(
                "the BSP mesh exceeds {} triangles or nodes",
                u16::MAX - 1
            ));
        }
        out.extend(on);
        nodes.push(BspNode {
            plane: [n[0] as f32, n[1] as f32, n[2] as f32, d as f32],
            front: NO_CHILD,
            back: NO_CHILD,
            first: first as u16,
            count: count as u16,
            facing_front: facing_front as u16,
        });
        if let Some((p, is_front)) = parent {
            if is_front {
                nodes[p].front = index as u16;
            } else {
                nodes[p].back = index as u16;
            }
        }
        work.push((back, Some((index, false)), level + 1));
        work.push((front, Some((index, true)), level + 1));
    }
    let out = close_t_junctions(out, &mut nodes, created);
    if out.len() >= u16::MAX as usize {
        return Err(format!("the BSP mesh exceeds {} triangles", u16::MAX - 1));
    }
    // The split mesh: vertices shared where they round to the same I16F16 point.
    let mut positions: Vec<V3> = Vec::new();
    let mut index_of: HashMap<[i64; 3], u16> = HashMap::new();
    let mut triangles = Vec::with_capacity(out.len());
    for p in &out {
        let mut tri = [0u16; 3];
        for (k, v) in p.v.iter().enumerate() {
            let key = v.map(|c| (c * 65536.0).round() as i64);
            let next = positions.len();
            if next >= u16::MAX as usize {
                return Err("the BSP mesh exceeds 65535 vertices".into());
            }
            tri[k] = *index_of.entry(key).or_insert_with(|| {
                positions.push(key.map(|c| c as f64 / 65536.0));
                next as u16
            });
        }
        triangles.push(tri);
    }
    let origin: Vec<u32> = out.iter().map(|p| p.origin).collect();
    let mut split_mesh = MeshData::new(
        &positions,
        triangles,
        embedded_graphics::pixelcolor::Rgb888::new(0, 0, 0),
    )?;
    split_mesh.colors = origin.iter().map(|&o| mesh.colors[o as usize]).collect();
    Ok(Bsp {
        mesh: split_mesh,
        origin,
        nodes,
        depth,
        splits,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corpus;
    use scanline3d::resolve::bsp::BspTree;

    #[test]
    fn every_corpus_tree_is_valid_and_splits_only_what_crosses() {
        for scene in corpus::all() {
            let bsp = build(&scene.mesh).unwrap();
            let tree = BspTree::new(&bsp.nodes, bsp.mesh.triangles.len());
            assert!(tree.is_ok(), "{}: {:?}", scene.name, tree.err());
            // Every input triangle is still there, whole or in pieces.
            let mut seen = vec![false; scene.mesh.triangles.len()];
            for &o in &bsp.origin {
                seen[o as usize] = true;
            }
            assert!(seen.iter().all(|&s| s), "{}", scene.name);
            assert!(bsp.mesh.triangles.len() >= scene.mesh.triangles.len());
            if scene.name == "interpenetrating" || scene.name == "cyclic" {
                assert!(bsp.splits > 0, "{}: nothing split", scene.name);
            }
            // Each node's first `facing_front` triangles are (pieces of) triangles facing
            // its plane's front side, the others face its back (or have no plane).
            let input_normal = |o: u32| {
                let t = scene.mesh.triangles[o as usize];
                let v = t.map(|i| scene.mesh.vertices[i as usize].map(|c| c.to_num::<f64>()));
                cross(sub(v[1], v[0]), sub(v[2], v[0]))
            };
            for node in &bsp.nodes {
                let n = node.plane.map(f64::from);
                for k in 0..node.count {
                    let m = input_normal(bsp.origin[(node.first + k) as usize]);
                    let front = dot(m, [n[0], n[1], n[2]]) > 0.0;
                    assert_eq!(front, k < node.facing_front, "{}: {node:?}", scene.name);
                }
            }
        }
    }

    #[test]
    fn a_convex_mesh_needs_no_split() {
        let bsp = build(&corpus::icosphere(2)).unwrap();
        assert_eq!(bsp.splits, 0);
        assert_eq!(bsp.mesh.triangles.len(), 320);
    }
}
