//! Binned-SAH bounding volume hierarchy, flattened depth-first into the array the kernels traverse.
//! The CPU reference (`cpu::trace`) walks the very same `BvhNode` array.

use glam::Vec3;

use crate::layout::constants::BVH_COUNT_BITS;
use crate::layout::{BvhNode, Primitive};

/// SAH bins per axis; 16 is the usual sweet spot between build time and tree quality.
const BINS: usize = 16;
/// A leaf never holds more primitives than this unless they cannot be separated at all.
const MAX_LEAF_SIZE: usize = 4;
/// Cost of visiting a node relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

/// The flattened hierarchy and the primitives reordered so that every leaf covers a contiguous range.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub primitives: Vec<Primitive>,
    /// Index in the input of each reordered primitive (`u32::MAX` for the placeholder of an
    /// empty scene).
    pub order: Vec<u32>,
    /// Deepest leaf (root = 1).
    pub depth: u32,
}

#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("the scene has {count} primitives; the BVH addresses at most {limit}")]
    TooManyPrimitives { count: usize, limit: u32 },
}

#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    fn grow(&mut self, other: &Bounds) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

struct Item {
    bounds: Bounds,
    centroid: Vec3,
    index: u32,
}

/// Builds the hierarchy over `primitives` (any order), whose axis-aligned bounds (min, max) are
/// `bounds`, and returns it with the primitives reordered.
pub fn build_bvh(primitives: &[Primitive], bounds: &[(Vec3, Vec3)]) -> Result<Bvh, BvhError> {
    build_bvh_with_leaves(primitives, bounds, MAX_LEAF_SIZE)
}

/// `build_bvh` with leaves of at most `max_leaf` primitives wherever their centroids can be
/// separated (the top level over instances takes 1: a leaf is one instance to enter).
pub fn build_bvh_with_leaves(
    primitives: &[Primitive],
    bounds: &[(Vec3, Vec3)],
    max_leaf: usize,
) -> Result<Bvh, BvhError> {
    assert_eq!(primitives.len(), bounds.len(), "one bounding box per primitive");
    let mut items: Vec<Item> = bounds
        .iter()
        .enumerate()
        .map(|(i, &(min, max))| {
            let bounds = Bounds { min, max };
            Item { bounds, centroid: (bounds.min + bounds.max) * 0.5, index: i as u32 }
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * primitives.len().max(1));
    let mut depth = 0;
    if items.is_empty() {
        // One leaf over one zero-area triangle, which no ray can hit: traversal needs no special case.
        let never_hit = Primitive { light: crate::layout::constants::NO_LIGHT, ..Default::default() };
        nodes.push(BvhNode { skip_count: (1 << BVH_COUNT_BITS) | 1, ..Default::default() });
        return Ok(Bvh { nodes, primitives: vec![never_hit], order: vec![u32::MAX], depth: 1 });
    }
    // Node indices share a u32 with the count bits, and there are fewer than 2n nodes.
    let limit = 1u32 << (31 - BVH_COUNT_BITS);
    if primitives.len() >= limit as usize {
        return Err(BvhError::TooManyPrimitives { count: primitives.len(), limit });
    }
    build_node(&mut items, 0, &mut nodes, 1, &mut depth, max_leaf);
    let ordered = items.iter().map(|it| primitives[it.index as usize]).collect();
    Ok(Bvh { nodes, primitives: ordered, order: items.iter().map(|it| it.index).collect(), depth })
}

/// Appends the subtree over `items` (which start at primitive `first`) in depth-first order.
fn build_node(
    items: &mut [Item],
    first: usize,
    nodes: &mut Vec<BvhNode>,
    level: u32,
    depth: &mut u32,
    max_leaf: usize,
) {
    *depth = (*depth).max(level);
    let mut bounds = Bounds::EMPTY;
    let mut centroid_bounds = Bounds::EMPTY;
    for it in items.iter() {
        bounds.grow(&it.bounds);
        centroid_bounds.grow_point(it.centroid);
    }
    let node_index = nodes.len();
    nodes.push(BvhNode {
        aabb_min: bounds.min.into(),
        aabb_max: bounds.max.into(),
        first: first as u32,
        skip_count: 0,
    });
    let split = if items.len() == 1 { None } else { choose_split(items, &bounds, &centroid_bounds, max_leaf) };
    let count = match split {
        None => items.len() as u32, // a leaf
        Some(mid) => {
            let (left, right) = items.split_at_mut(mid);
            build_node(left, first, nodes, level + 1, depth, max_leaf);
            build_node(right, first + mid, nodes, level + 1, depth, max_leaf);
            0
        }
    };
    // The miss link: the first node after this subtree.
    nodes[node_index].skip_count = ((nodes.len() as u32) << BVH_COUNT_BITS) | count;
}

/// Partitions `items` and returns the split position, or `None` when a leaf is cheaper.
fn choose_split(items: &mut [Item], bounds: &Bounds, centroid_bounds: &Bounds, max_leaf: usize) -> Option<usize> {
    let n = items.len();
    let extent = centroid_bounds.max - centroid_bounds.min;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin boundary)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |c: Vec3| (((c[axis] - centroid_bounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_bounds = [Bounds::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for it in items.iter() {
            let b = bin_of(it.centroid);
            bin_bounds[b].grow(&it.bounds);
            bin_count[b] += 1;
        }
        // Sweep from the right to get the cost of every right-hand side, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Bounds::EMPTY;
        let mut count = 0;
        for b in (1..BINS).rev() {
            acc.grow(&bin_bounds[b]);
            count += bin_count[b];
            right_area[b] = acc.half_area();
            right_count[b] = count;
        }
        let mut acc = Bounds::EMPTY;
        let mut count = 0;
        for b in 0..BINS - 1 {
            acc.grow(&bin_bounds[b]);
            count += bin_count[b];
            if count == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_area[b + 1] * right_count[b + 1] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    let leaf_cost = n as f32;
    match best {
        Some((cost, axis, boundary)) => {
            let split_cost = TRAVERSAL_COST + cost / bounds.half_area().max(f32::MIN_POSITIVE);
            if split_cost >= leaf_cost && n <= max_leaf {
                return None;
            }
            let scale = BINS as f32 / extent[axis];
            let mid = partition(items, |it| {
                ((((it.centroid[axis] - centroid_bounds.min[axis]) * scale) as usize).min(BINS - 1)) < boundary
            });
            Some(mid)
        }
        // All centroids coincide: no plane separates them. Split in the middle so leaves stay
        // small; the two halves overlap completely, which costs time but stays correct.
        None if n > max_leaf => Some(n / 2),
        None => None,
    }
}

fn partition(items: &mut [Item], goes_left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if goes_left(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::constants::PRIMITIVE_TRIANGLE;

    fn triangle(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Primitive {
        Primitive { p0: a, p1: b, p2: c, kind: PRIMITIVE_TRIANGLE, ..Default::default() }
    }

    fn triangle_bounds(p: &Primitive) -> (Vec3, Vec3) {
        let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3::from);
        (a.min(b).min(c), a.max(b).max(c))
    }

    fn build(prims: &[Primitive]) -> Bvh {
        let bounds: Vec<_> = prims.iter().map(triangle_bounds).collect();
        build_bvh(prims, &bounds).unwrap()
    }

    #[test]
    fn every_primitive_lands_in_exactly_one_leaf_inside_its_node_box() {
        let prims: Vec<Primitive> = (0..1000)
            .map(|i| {
                let x = (i % 10) as f32;
                let y = ((i / 10) % 10) as f32;
                let z = (i / 100) as f32;
                triangle([x, y, z], [x + 0.5, y, z], [x, y + 0.5, z + 0.2])
            })
            .collect();
        let bvh = build(&prims);
        let mut covered = vec![0u32; prims.len()];
        for node in &bvh.nodes {
            if node.count() > 0 {
                for i in node.first..node.first + node.count() {
                    covered[i as usize] += 1;
                    let (lo, hi) = triangle_bounds(&bvh.primitives[i as usize]);
                    assert!(lo.cmpge(Vec3::from(node.aabb_min)).all() && hi.cmple(Vec3::from(node.aabb_max)).all());
                }
            }
        }
        assert!(covered.iter().all(|&c| c == 1));
        assert!(bvh.depth < 30, "depth {}", bvh.depth);
    }

    #[test]
    fn identical_primitives_still_build() {
        let prims = vec![triangle([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]); 100];
        let bvh = build(&prims);
        assert_eq!(bvh.primitives.len(), 100);
        assert!(bvh.nodes.iter().filter(|n| n.count() > 0).all(|n| n.count() as usize <= MAX_LEAF_SIZE));
    }
}
