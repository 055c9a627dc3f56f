//! BSP tree ordering (Fuchs, Kedem and Naylor): a painter's algorithm whose order is right for
//! every eye position.
//!
//! A binary space partitioning tree of a static mesh is built once, ahead of time (on the host:
//! `scanline3d_sim::bsp::build`, exportable as `static` data). Every node holds a plane and the
//! triangles lying in it; the triangles in front of the plane are in one subtree, those behind
//! in the other, and triangles that straddle a plane were split when the tree was built. For
//! any eye position, visiting the subtree on the far side of a node's plane, then the node's
//! triangles, then the near subtree draws far to near, so painting in that order is correct:
//! interpenetrating and cyclically overlapping triangles were split apart by the build.
//!
//! Per frame the tree is traversed once (one plane test per node, with an explicit stack of
//! `STACK` entries: no recursion), each triangle's place in the order becomes its sort key,
//! and the rows are painted like the depth sort's, far to near. With back-face culling the
//! same plane test culls: a node's triangles facing away from the eye are left out (see
//! [`BspNode::facing_front`]), not judged by their rounded orientation on screen.

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::options::RenderOptions;
use crate::render::Unbounded;
use crate::render::{
    drive, internal, viewport, ActiveTri, Frame, InstanceSetup, TriangleOrder, NO_ENTRY,
};
use crate::scene::{Scene, Transform};
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{CapacityKind, FrameStats, RenderError};
use crate::vertex::TransformPrecision;
use heapless::Vec;

use crate::resolve::common::check_sizes;
use crate::resolve::depth_sort::Painter;

/// No child.
pub const NO_CHILD: u16 = u16::MAX;

/// One node of a BSP tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BspNode {
    /// The plane `a·x + b·y + c·z + d = 0` in model coordinates; its front side is where the
    /// expression is positive.
    pub plane: [f32; 4],
    /// The subtree in front of the plane ([`NO_CHILD`] if empty).
    pub front: u16,
    /// The subtree behind the plane ([`NO_CHILD`] if empty).
    pub back: u16,
    /// The node's triangles (those in its plane) are the mesh's `first .. first + count`.
    pub first: u16,
    /// How many.
    pub count: u16,
    /// How many of them, the first ones of the range, face the plane's front side (the eye
    /// sees them counter-clockwise from in front of it); the others face its back side. With
    /// back-face culling a node's triangles facing away from the eye are not drawn, whatever
    /// their orientation on screen: a thin piece left by a split can turn over when its
    /// vertices are rounded, and would then show a surface that faces away.
    pub facing_front: u16,
}

/// Why a BSP tree was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BspError {
    /// The tree has no nodes.
    Empty,
    /// Node `node` names a child that is not after it in the node list, or out of range
    /// (children come after their parents, as in pre-order, which rules out cycles).
    BadChild {
        /// The node.
        node: usize,
    },
    /// Node `node` names `child` (as both of its children, or as one while an earlier node
    /// names it too), so `child`'s subtree would be drawn twice and, the triangle ranges being
    /// consecutive, some other triangles never.
    SharedChild {
        /// The second node (in node order) naming `child`; the first if it names it twice.
        node: usize,
        /// The child named twice.
        child: usize,
    },
    /// No node names node `node` as a child (or, past the 65,535th node, none can: children are
    /// 16-bit with [`NO_CHILD`] = 65,535 for none), so its triangles would never be drawn.
    Unreachable {
        /// The first such node.
        node: usize,
    },
    /// Node `node`'s triangle range is not the next one: ranges must follow each other in node
    /// order and end at the mesh's last triangle, so each triangle is drawn exactly once.
    BadRange {
        /// The node.
        node: usize,
    },
    /// Node `node` has more triangles facing its plane's front side than triangles.
    BadFacing {
        /// The node.
        node: usize,
    },
    /// A plane is not finite.
    BadPlane {
        /// The node.
        node: usize,
    },
}

/// Whether node `node`'s child `c` of a tree of `len` nodes is absent or comes after it.
const fn child_ok(c: u16, node: usize, len: usize) -> bool {
    c == NO_CHILD || (c as usize > node && (c as usize) < len)
}

/// Node `node`'s children in index order, [`NO_CHILD`] for none (so a single child comes
/// first).
const fn children(node: &BspNode) -> (u16, u16) {
    if node.front <= node.back {
        (node.front, node.back)
    } else {
        (node.back, node.front)
    }
}

/// The end of the subtree of node `x` if `nodes` are in pre-order below it: one past the leaf
/// reached by always taking the later child. Counts the steps against `budget` and gives up
/// (`None`) when it runs out. Children must be known to be after their parents and in range.
const fn subtree_end(nodes: &[BspNode], mut x: usize, mut budget: usize) -> Option<(usize, usize)> {
    while x < nodes.len() && budget > 0 {
        budget -= 1;
        let (first, last) = children(&nodes[x]);
        let later = if last != NO_CHILD { last } else { first };
        if later == NO_CHILD {
            return Some((x + 1, budget));
        }
        x = later as usize;
    }
    None
}

/// Whether `nodes` (children after their parents and in range) are a tree in pre-order: each
/// node's first child is the node right after it and its second child, if any, the node right
/// after the first child's subtree, and the root's subtree is every node. Every node is then
/// reached from the root exactly once (by induction from the last node: each node's subtree
/// is the run of nodes from it to its end, each reached once).
///
/// Linear time: in a tree in pre-order each node lies on the later-child path of exactly one
/// node whose path is followed (the root, or a node that is the earlier of two children), so
/// the walks take `nodes.len()` steps in all; a budget of that many stops any other input.
const fn is_pre_order(nodes: &[BspNode]) -> bool {
    let mut budget = nodes.len();
    // Last node first, by slice patterns rather than indexing (no panic path).
    let mut rest = nodes;
    while let [before @ .., node] = rest {
        let i = before.len();
        rest = before;
        let (first, second) = children(node);
        if first == NO_CHILD {
            continue; // a leaf
        }
        if first as usize != i + 1 || first == second {
            return false;
        }
        if second != NO_CHILD {
            match subtree_end(nodes, first as usize, budget) {
                Some((end, left)) if end == second as usize => budget = left,
                _ => return false,
            }
        }
    }
    matches!(subtree_end(nodes, 0, budget), Some((end, _)) if end == nodes.len())
}

/// Checks that every node but the root is named as a child exactly once (children are after
/// their parents and in range, and there are at most 65,535 nodes): then each node is reached
/// from the root exactly once, by induction over the nodes in order. Quadratic time.
const fn check_parents(nodes: &[BspNode]) -> Result<(), BspError> {
    let mut child = 1;
    while child < nodes.len() {
        let mut named = false;
        // Parents come before their children: the nodes before `child`, by slice patterns.
        let (mut node, mut rest) = (0, nodes);
        while let [parent, after @ ..] = rest {
            if node == child {
                break;
            }
            let (a, b) = (parent.front as usize, parent.back as usize);
            let times = (a == child) as usize + (b == child) as usize;
            if times > 0 && (named || times > 1) {
                return Err(BspError::SharedChild { node, child });
            }
            named |= times > 0;
            node += 1;
            rest = after;
        }
        if !named {
            return Err(BspError::Unreachable { node: child });
        }
        child += 1;
    }
    Ok(())
}

/// A BSP tree over one mesh, validated: node 0 is the root, every child comes after its
/// parent and every other node is the child of exactly one node, so each node (and each
/// triangle) is reached exactly once.
#[derive(Clone, Copy, Debug)]
pub struct BspTree<'a> {
    nodes: &'a [BspNode],
}

impl<'a> BspTree<'a> {
    /// Checks `nodes` against a mesh of `triangles` triangles: children after their parents,
    /// triangle ranges consecutive in node order and covering the mesh, planes finite, and
    /// every node but the root named as a child exactly once (so the traversal draws each
    /// triangle exactly once). A tree in pre-order, as `scanline3d_sim::bsp::build` makes
    /// it (each node's first child right after it, a second child right after the first
    /// child's subtree), is checked in time linear in the node count; any other layout in
    /// quadratic time.
    ///
    /// ```
    /// use scanline3d::resolve::bsp::{BspError, BspNode, BspTree, NO_CHILD};
    /// let leaf = BspNode { plane: [0.0, 0.0, 1.0, 0.0], front: NO_CHILD, back: NO_CHILD, first: 0, count: 2, facing_front: 2 };
    /// assert!(BspTree::new(&[leaf], 2).is_ok());
    /// assert_eq!(BspTree::new(&[leaf], 1).unwrap_err(), BspError::BadRange { node: 0 });
    /// let cycle = BspNode { front: 0, ..leaf };
    /// assert_eq!(BspTree::new(&[cycle], 2).unwrap_err(), BspError::BadChild { node: 0 });
    /// // A root with two leaves; then one leaf named by both sides of the root.
    /// let one = BspNode { count: 1, facing_front: 1, ..leaf };
    /// let root = BspNode { front: 1, back: 2, ..one };
    /// let tree = [root, BspNode { first: 1, ..one }, BspNode { first: 2, ..one }];
    /// assert!(BspTree::new(&tree, 3).is_ok());
    /// let shared = [BspNode { back: 1, ..root }, tree[1], tree[2]];
    /// assert_eq!(BspTree::new(&shared, 3).unwrap_err(), BspError::SharedChild { node: 0, child: 1 });
    /// ```
    pub const fn new(nodes: &'a [BspNode], triangles: usize) -> Result<Self, BspError> {
        if nodes.is_empty() {
            return Err(BspError::Empty);
        }
        // `while` rather than iterators: a `const fn`, so a tree exported as `static` data is
        // validated when the firmware is built.
        let mut next_first = 0usize;
        let mut i = 0;
        while i < nodes.len() {
            let n = &nodes[i];
            if !child_ok(n.front, i, nodes.len()) || !child_ok(n.back, i, nodes.len()) {
                return Err(BspError::BadChild { node: i });
            }
            if n.first as usize != next_first || next_first + n.count as usize > triangles {
                return Err(BspError::BadRange { node: i });
            }
            next_first += n.count as usize;
            if n.facing_front > n.count {
                return Err(BspError::BadFacing { node: i });
            }
            let [a, b, c, d] = n.plane;
            if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) {
                return Err(BspError::BadPlane { node: i });
            }
            i += 1;
        }
        if next_first != triangles {
            return Err(BspError::BadRange {
                node: nodes.len() - 1,
            });
        }
        if nodes.len() > NO_CHILD as usize {
            return Err(BspError::Unreachable {
                node: NO_CHILD as usize,
            });
        }
        if !is_pre_order(nodes) {
            // Not the builder's layout: it may still be a tree. Check every link.
            if let Err(e) = check_parents(nodes) {
                return Err(e);
            }
        }
        Ok(BspTree { nodes })
    }

    /// Triangles of the mesh the tree orders.
    pub fn triangles(&self) -> usize {
        self.nodes.iter().map(|n| n.count as usize).sum()
    }

    /// The nodes.
    pub fn nodes(&self) -> &'a [BspNode] {
        self.nodes
    }

    /// Calls `f(node, eye_in_front)` for each node, far to near as seen from `eye` (model
    /// coordinates), with the side of its plane the eye is on. `Err(needed)` if `stack` is too
    /// small for this tree and eye.
    pub fn back_to_front(
        &self,
        eye: [f32; 3],
        stack: &mut [u32],
        mut f: impl FnMut(&BspNode, bool),
    ) -> Result<(), usize> {
        // Entries are node indices; the high bit marks "draw this node's triangles now", the
        // next one that the eye is in front of its plane.
        const DRAW: u32 = 1 << 31;
        const IN_FRONT: u32 = 1 << 30;
        let mut top = 0usize;
        let push = |stack: &mut [u32], top: &mut usize, v: u32| match stack.get_mut(*top) {
            Some(slot) => {
                *slot = v;
                *top += 1;
                Ok(())
            }
            None => Err(*top + 1),
        };
        push(stack, &mut top, 0)?;
        while top > 0 {
            top -= 1;
            // `top` entries were pushed, and a checked tree names only its own nodes.
            let entry = internal(stack.get(top).copied(), 0);
            let Some(node) = self.nodes.get((entry & !(DRAW | IN_FRONT)) as usize) else {
                debug_assert!(false, "internal error: node {entry:#x} not in the tree");
                continue;
            };
            if entry & DRAW != 0 {
                f(node, entry & IN_FRONT != 0);
                continue;
            }
            let [a, b, c, d] = node.plane;
            let in_front = a * eye[0] + b * eye[1] + c * eye[2] + d >= 0.0;
            let (near, far) = if in_front {
                (node.front, node.back)
            } else {
                (node.back, node.front)
            };
            // Popped in reverse: far subtree, then this node, then the near subtree.
            if near != NO_CHILD {
                push(stack, &mut top, near as u32)?;
            }
            // Node indices are below 2^16, so the two flags are free.
            let side = if in_front { IN_FRONT } else { 0 };
            push(stack, &mut top, entry | DRAW | side)?;
            if far != NO_CHILD {
                push(stack, &mut top, far as u32)?;
            }
        }
        Ok(())
    }
}

/// `p` in the coordinates of `t`'s model space (`t` maps model to world), or `None` if `t`
/// is singular.
fn to_model(t: &Transform, p: [f32; 3]) -> Option<[f32; 3]> {
    let m = t.m;
    let v = [p[0] - m[0][3], p[1] - m[1][3], p[2] - m[2][3]];
    // Cramer's rule on the 3×3 part.
    let col = |j: usize| [m[0][j], m[1][j], m[2][j]];
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (c0, c1, c2) = (col(0), col(1), col(2));
    let det = dot(c0, cross(c1, c2));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some([
        dot(v, cross(c1, c2)) / det,
        dot(c0, cross(v, c2)) / det,
        dot(c0, cross(c1, v)) / det,
    ])
}

/// Pass 1's order for a BSP scene: the tree's back-to-front order over instance 0's mesh.
struct BspOrder<'t, 'w> {
    /// Back-face culling: a node's triangles facing away from the eye are left out.
    cull: bool,
    /// Triangles left out so.
    culled: u32,
    tree: &'t BspTree<'t>,
    eye: [f32; 3],
    stack: &'w mut [u32],
}

impl TriangleOrder for BspOrder<'_, '_> {
    fn visit<'s, T: TransformPrecision, E>(
        &mut self,
        setups: &[InstanceSetup<'s, T>],
        mut f: impl FnMut(&InstanceSetup<'s, T>, usize, Option<u32>),
    ) -> Result<(), RenderError<E>> {
        let Some(setup) = setups.first() else {
            // BspWorkspace::render_sized requires exactly one instance.
            debug_assert!(false, "internal error: a BSP scene without its instance");
            return Ok(());
        };
        let capacity = self.stack.len();
        // One rank per node: its triangles are coplanar, so where two overlap their depths tie
        // exactly, and equal keys give the z-buffers' tie rule (first activated is drawn last).
        // Visiting them in reverse keeps each row's bucket in index order, as for the others.
        let mut rank = 0u32;
        let (cull, culled) = (self.cull, &mut self.culled);
        self.tree
            .back_to_front(self.eye, self.stack, |node, eye_in_front| {
                let (first, count) = (node.first as usize, node.count as usize);
                let split = first + node.facing_front as usize;
                let drawn = match (cull, eye_in_front) {
                    (false, _) => first..first + count,
                    (true, true) => first..split,
                    (true, false) => split..first + count,
                };
                *culled += (count - drawn.len()) as u32;
                for tri in drawn.rev() {
                    f(setup, tri, Some(rank));
                }
                rank += 1;
            })
            .map_err(|needed| RenderError::Capacity {
                what: CapacityKind::BspStack,
                needed,
                capacity,
            })
    }
}

/// Painter's algorithm in BSP order: correct for every eye position, with the tree built ahead
/// of time. The scene must have exactly one instance, whose mesh is the one the tree was built
/// for (its transform may change from frame to frame). `STACK` bounds the traversal: about
/// twice the tree's depth (`scanline3d_sim::bsp` reports the depth).
///
/// ```
/// use embedded_graphics::pixelcolor::Gray8;
/// use scanline3d::resolve::bsp::{BspNode, BspTree, BspWorkspace, NO_CHILD};
/// use scanline3d::{scene::*, sink::HashSink, Flat, RenderOptions};
/// use fixed::types::I16F16;
/// // Two triangles in the plane z = 0: one node.
/// let v = |x: f32, y: f32| [I16F16::from_num(x), I16F16::from_num(y), I16F16::ZERO];
/// let verts = [v(-1.0, -1.0), v(1.0, -1.0), v(-1.0, 1.0), v(1.0, 1.0)];
/// let tris = [[0u16, 1, 2], [2, 1, 3]];
/// let mesh = Mesh::new(&verts, &tris, MeshColors::Uniform(embedded_graphics::pixelcolor::Rgb888::new(200, 200, 200)), None)?;
/// let nodes = [BspNode { plane: [0.0, 0.0, 1.0, 0.0], front: NO_CHILD, back: NO_CHILD, first: 0, count: 2, facing_front: 2 }];
/// let tree = BspTree::new(&nodes, tris.len()).unwrap();
/// let instances = [Instance { mesh: &mesh, transform: Transform::IDENTITY }];
/// let camera = Camera::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])?.perspective(60.0, 0.5, 10.0)?;
/// let scene = Scene { instances: &instances, camera, light: Light::new([0.0, 0.0, 1.0], 0.2, 0.8)? };
/// let mut ws: Box<BspWorkspace<Gray8, Flat, 32, 32, 8, 8, 8>> = Box::new(BspWorkspace::new(Gray8::new(0)));
/// let stats = ws.render(&scene, &tree, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// assert_eq!(stats.activated, 2);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct BspWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const STACK: usize = 256,
> {
    pixels: [P; W],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    keys: [u32; TRIS],
    stack: [u32; STACK],
    active: Vec<ActiveTri<S::Payload<P>, u32>, ACTIVE>,
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const STACK: usize,
    > BspWorkspace<P, S, W, H, TRIS, ACTIVE, STACK>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = check_sizes(W, H, TRIS);

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        BspWorkspace {
            pixels: [background; W],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            keys: [0; TRIS],
            stack: [0; STACK],
            active: Vec::new(),
        }
    }

    /// Renders `scene` (one instance, the mesh `tree` was built for) in BSP order.
    pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        tree: &BspTree<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, tree, options, sink)
    }

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized).
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        tree: &BspTree<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let [instance] = scene.instances else {
            return Err(RenderError::TreeMismatch);
        };
        if tree.triangles() != instance.mesh.triangles().len() {
            return Err(RenderError::TreeMismatch);
        }
        let eye = to_model(&instance.transform, scene.camera.view().eye)
            .ok_or(RenderError::InvalidTarget)?;
        let (Some(pixels), Some(heads)) =
            (self.pixels.get_mut(..width), self.heads.get_mut(..height))
        else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut self.keys,
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut resolve = Painter {
            pixels,
            background: self.background,
            spans: 0,
        };
        let mut order = BspOrder {
            cull: options.cull_back_faces,
            culled: 0,
            tree,
            eye,
            stack: &mut self.stack,
        };
        let mut stats = drive::<P, S, SUB_BITS, C, A, K, 1, _, _, Unbounded>(
            frame,
            &mut resolve,
            &mut order,
            scene,
            options,
            &vp,
            sink,
        )?;
        stats.culled += order.culled;
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec;

    const N: u16 = NO_CHILD;

    /// Nodes with these `(front, back)` links, one triangle each, in node order.
    fn tree(links: &[(u16, u16)]) -> Vec<BspNode> {
        let node = |(i, &(front, back)): (usize, &(u16, u16))| BspNode {
            plane: [0.0, 0.0, 1.0, 0.0],
            front,
            back,
            first: i as u16,
            count: 1,
            facing_front: 1,
        };
        links.iter().enumerate().map(node).collect()
    }

    /// How often the traversal draws each triangle, from in front of and behind the planes.
    fn draws(tree: &BspTree<'_>) -> [Vec<u32>; 2] {
        [1.0, -1.0].map(|z| {
            let mut seen = vec![0u32; tree.triangles()];
            let mut stack = vec![0u32; 64];
            tree.back_to_front([0.0, 0.0, z], &mut stack, |node, _| {
                for t in node.first..node.first + node.count {
                    seen[t as usize] += 1;
                }
            })
            .unwrap();
            seen
        })
    }

    #[test]
    fn trees_in_pre_order_are_accepted_and_draw_each_triangle_once() {
        for links in [
            &[(N, N)][..],
            &[(1, N), (N, N)],
            &[(N, 1), (N, N)],
            &[(1, 2), (N, N), (N, N)],
            &[(2, 1), (N, N), (N, N)],
            &[(1, 4), (2, 3), (N, N), (N, N), (N, N)],
            &[(1, 5), (N, 2), (3, 4), (N, N), (N, N), (N, 6), (N, N)],
        ] {
            let nodes = tree(links);
            assert!(is_pre_order(&nodes), "{links:?}");
            let tree = BspTree::new(&nodes, nodes.len()).unwrap();
            for seen in draws(&tree) {
                assert!(seen.iter().all(|&n| n == 1), "{links:?}: {seen:?}");
            }
        }
    }

    #[test]
    fn other_layouts_of_a_tree_are_accepted() {
        // Breadth first: node 1's children are not right after it.
        let nodes = tree(&[(1, 2), (3, 4), (N, N), (N, N), (N, N)]);
        assert!(!is_pre_order(&nodes));
        let tree = BspTree::new(&nodes, 5).unwrap();
        for seen in draws(&tree) {
            assert_eq!(seen, [1; 5]);
        }
    }

    #[test]
    fn a_shared_child_is_rejected() {
        // The defect: this tree draws triangle 2 twice from either side, so another is never
        // drawn when the ranges are consecutive.
        let shared = tree(&[(1, 2), (N, 2), (N, N)]);
        let unchecked = BspTree { nodes: &shared };
        assert_eq!(draws(&unchecked), [[1, 1, 2], [1, 1, 2]]);
        assert_eq!(
            BspTree::new(&shared, 3).unwrap_err(),
            BspError::SharedChild { node: 1, child: 2 }
        );
        for (links, node, child) in [
            (&[(1, 1), (N, N)][..], 0, 1),
            (&[(1, 3), (2, 3), (N, N), (N, N)], 1, 3),
            (&[(1, 4), (2, 3), (N, N), (N, 4), (N, N)], 3, 4),
        ] {
            let nodes = tree(links);
            assert_eq!(
                BspTree::new(&nodes, nodes.len()).unwrap_err(),
                BspError::SharedChild { node, child },
                "{links:?}"
            );
        }
    }

    #[test]
    fn an_unreachable_node_is_rejected() {
        for (links, node) in [
            (&[(1, N), (N, N), (N, N)][..], 2),
            (&[(2, N), (N, N), (N, N)], 1),
            (&[(N, N), (2, N), (N, N)], 1),
        ] {
            let nodes = tree(links);
            assert_eq!(
                BspTree::new(&nodes, nodes.len()).unwrap_err(),
                BspError::Unreachable { node },
                "{links:?}"
            );
        }
    }

    #[test]
    fn more_triangles_facing_front_than_triangles_is_rejected() {
        let nodes = [BspNode {
            facing_front: 2,
            ..tree(&[(N, N)])[0]
        }];
        assert_eq!(
            BspTree::new(&nodes, 1).unwrap_err(),
            BspError::BadFacing { node: 0 }
        );
    }

    /// The stats of rendering one triangle, counter-clockwise on screen from the eye at
    /// `z = 3`, as the only triangle of a node whose `facing_front` is given.
    fn render_one(facing_front: u16, cull: bool) -> FrameStats {
        use crate::scene::{Camera, Instance, Light, Mesh, MeshColors};
        use crate::{sink::HashSink, Flat};
        use embedded_graphics::pixelcolor::{Gray8, Rgb888};
        use fixed::types::I16F16;
        let v = |x: f32, y: f32| [I16F16::from_num(x), I16F16::from_num(y), I16F16::ZERO];
        let verts = [v(-1.0, -1.0), v(1.0, -1.0), v(-1.0, 1.0)];
        let tris = [[0u16, 1, 2]];
        let colors = MeshColors::Uniform(Rgb888::new(200, 200, 200));
        let mesh = Mesh::new(&verts, &tris, colors, None).unwrap();
        let nodes = [BspNode {
            plane: [0.0, 0.0, 1.0, 0.0],
            front: NO_CHILD,
            back: NO_CHILD,
            first: 0,
            count: 1,
            facing_front,
        }];
        let tree = BspTree::new(&nodes, 1).unwrap();
        let instances = [Instance {
            mesh: &mesh,
            transform: crate::scene::Transform::IDENTITY,
        }];
        let camera = Camera::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .perspective(60.0, 0.5, 10.0)
            .unwrap();
        let light = Light::new([0.0, 0.0, 1.0], 0.2, 0.8).unwrap();
        let scene = Scene {
            instances: &instances,
            camera,
            light,
        };
        let mut ws: std::boxed::Box<BspWorkspace<Gray8, Flat, 32, 32, 8, 8, 8>> =
            std::boxed::Box::new(BspWorkspace::new(Gray8::new(0)));
        let options = RenderOptions::default().with_back_face_culling(cull);
        ws.render(&scene, &tree, &options, &mut HashSink::new())
            .unwrap()
    }

    #[test]
    fn culling_follows_the_nodes_facing_not_the_screen() {
        // Facing the eye on screen and in the tree: drawn.
        let shown = render_one(1, true);
        assert_eq!((shown.activated, shown.culled), (1, 0));
        // The tree says it faces away (a piece whose rounded vertices turned it over): culled,
        // though counter-clockwise on screen; without culling drawn.
        let turned = render_one(0, true);
        assert_eq!((turned.activated, turned.culled), (0, 1));
        assert_eq!(render_one(0, false).activated, 1);
    }

    /// A complete binary tree of `depth` levels in pre-order, appended to `nodes`.
    fn complete(depth: u32, nodes: &mut Vec<BspNode>) -> u16 {
        let at = nodes.len();
        nodes.extend(tree(&[(N, N)]).into_iter().map(|n| BspNode {
            first: at as u16,
            ..n
        }));
        if depth > 1 {
            let front = complete(depth - 1, nodes);
            let back = complete(depth - 1, nodes);
            nodes[at].front = front;
            nodes[at].back = back;
        }
        at as u16
    }

    #[test]
    fn up_to_65535_nodes() {
        // At the limit: a complete tree of 16 levels and a chain, both checked in linear time.
        let mut full = Vec::new();
        complete(16, &mut full);
        assert_eq!(full.len(), 65_535);
        assert!(is_pre_order(&full));
        let tree65535 = BspTree::new(&full, 65_535).unwrap();
        for seen in draws(&tree65535) {
            assert!(seen.iter().all(|&n| n == 1));
        }
        let chain = |n: usize| {
            let links: Vec<(u16, u16)> = (1..=n)
                .map(|i| (if i < n { i as u16 } else { N }, N))
                .collect();
            tree(&links)
        };
        assert!(BspTree::new(&chain(65_535), 65_535).is_ok());
        // Past it: the last node's index is NO_CHILD, so no node can name it.
        assert_eq!(
            BspTree::new(&chain(65_536), 65_536).unwrap_err(),
            BspError::Unreachable { node: 65_535 }
        );
    }
}
