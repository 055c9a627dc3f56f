//! Bounding volumes, the lecture's first acceleration: a hierarchy of axis-aligned boxes over
//! objects (every mesh triangle is an object), so one cheap box test rejects a whole subtree
//! instead of running each exact test behind it.
//!
//! Built top-down: split at the median of the box centres along the widest axis of the centres
//! until a leaf holds at most [`LEAF_SIZE`] objects. Walked nearest child first, pruning any
//! box that starts beyond the best hit so far.

use super::intersect::Aabb;
use super::query::Query;
use super::vector::{dot, sub};

/// Most objects in a leaf.
pub const LEAF_SIZE: usize = 2;

#[derive(Clone, Copy, Debug)]
enum Node {
    /// `ids[first..first + count]`.
    Leaf {
        bounds: Aabb,
        first: usize,
        count: usize,
    },
    /// Children at these node indices.
    Inner { bounds: Aabb, children: [usize; 2] },
}

impl Node {
    fn bounds(&self) -> &Aabb {
        match self {
            Node::Leaf { bounds, .. } | Node::Inner { bounds, .. } => bounds,
        }
    }
}

/// A bounding-volume hierarchy over a set of bounded objects.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    ids: Vec<usize>,
}

impl Bvh {
    /// Builds the hierarchy over `(id, box)` pairs.
    pub fn build(items: &[(usize, Aabb)]) -> Bvh {
        let mut bvh = Bvh::default();
        let mut work: Vec<(usize, Aabb)> = items.to_vec();
        if !work.is_empty() {
            bvh.split(&mut work);
        }
        bvh
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Builds the subtree of `items` and returns its node index.
    fn split(&mut self, items: &mut [(usize, Aabb)]) -> usize {
        let bounds = items.iter().fold(Aabb::EMPTY, |b, (_, a)| b.union(a));
        let index = self.nodes.len();
        if items.len() <= LEAF_SIZE {
            let first = self.ids.len();
            self.ids.extend(items.iter().map(|(id, _)| *id));
            self.nodes.push(Node::Leaf {
                bounds,
                first,
                count: items.len(),
            });
            return index;
        }
        let centres = Aabb::of_points(&items.iter().map(|(_, a)| a.centre()).collect::<Vec<_>>());
        let axis = (0..3)
            .max_by(|&a, &b| {
                (centres.max[a] - centres.min[a]).total_cmp(&(centres.max[b] - centres.min[b]))
            })
            .unwrap_or(0);
        items.sort_by(|a, b| a.1.centre()[axis].total_cmp(&b.1.centre()[axis]));
        // Placeholder, replaced once the children exist.
        self.nodes.push(Node::Leaf {
            bounds,
            first: 0,
            count: 0,
        });
        let (left, right) = items.split_at_mut(items.len() / 2);
        let children = [self.split(left), self.split(right)];
        self.nodes[index] = Node::Inner { bounds, children };
        index
    }

    /// Offers `query` every object whose boxes the ray reaches, nearest subtree first.
    pub fn walk(&self, query: &mut Query) {
        let mut stack = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(n) = stack.pop() {
            if query.done() {
                return;
            }
            let Some(node) = self.nodes.get(n) else {
                continue;
            };
            query.counters.box_tests += 1;
            if node.bounds().clip(&query.ray, query.span).is_none() {
                continue;
            }
            match *node {
                Node::Leaf { first, count, .. } => {
                    for &id in self.ids.get(first..first + count).unwrap_or(&[]) {
                        query.test(id);
                    }
                }
                Node::Inner { children, .. } => {
                    // Push the farther child (by box centre along the ray) first, so the
                    // nearer one is walked first; no box test is spent on the ordering.
                    let along = |c: usize| {
                        self.nodes.get(c).map_or(f64::INFINITY, |n| {
                            dot(sub(n.bounds().centre(), query.ray.origin), query.ray.dir)
                        })
                    };
                    let (a, b) = (children[0], children[1]);
                    if along(a) <= along(b) {
                        stack.extend([b, a]);
                    } else {
                        stack.extend([a, b]);
                    }
                }
            }
        }
    }
}
