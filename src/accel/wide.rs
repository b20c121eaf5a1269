//! The CPU backend's four-wide BVH: the kernels' binary hierarchy (`bvh.rs`) collapsed so that
//! one node holds up to four children's boxes in SIMD lanes, tested against a ray at once.
//!
//! Only the CPU twin walks it (`cpu::trace`); the kernels keep the binary, stackless walk. Both
//! find the same closest hit: the leaves are the binary tree's leaves, over the same primitives,
//! a node's lanes keep the binary tree's depth-first order, and the four lanes of a box test
//! compute what the binary test computes.

use glam::{Vec3, Vec4};

use crate::layout::constants::{
    INSTANCE_DATA_FLOATS, INSTANCE_DATA_ROOT, PRIMITIVE_FLAG_ALPHA, PRIMITIVE_KIND_MASK, PRIMITIVE_TRIANGLE,
};
use crate::layout::{BvhNode, FrameParams, Primitive};

/// Up to four children: their boxes by axis in SIMD lanes, and what each child is.
#[derive(Clone, Copy, Debug)]
pub struct WideNode {
    /// The children's box minima: x of each child, then y, then z.
    pub lo: [Vec4; 3],
    pub hi: [Vec4; 3],
    /// An inner child's node (in `WideBvh::nodes`), or a leaf's first primitive (a top-level
    /// leaf's: its instance record).
    pub child: [u32; 4],
    /// A leaf's primitive count; 0 for an inner child.
    pub count: [u32; 4],
    /// A leaf of opaque triangles only: its `TriangleBlock`; `NO_BLOCK` for other leaves.
    pub block: [u32; 4],
    /// Bit k set when lane k holds a child.
    pub lanes: u32,
}

/// `WideNode::block` of a leaf whose primitives are tested one by one.
pub const NO_BLOCK: u32 = u32::MAX;

/// Up to four opaque triangles of one leaf, in leaf order, for one SIMD Möller-Trumbore test:
/// each lane's first vertex and the two edges from it, as `ray_triangle` computes them.
#[derive(Clone, Copy, Debug)]
pub struct TriangleBlock {
    pub p0: [Vec4; 3],
    pub e1: [Vec4; 3],
    pub e2: [Vec4; 3],
}

/// The collapsed hierarchies: the world's, the top level's over the instances, and each
/// instanced object's.
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriangleBlock>,
    /// The root of the world's hierarchy.
    pub world: u32,
    /// The root of the top level; meaningless without instances.
    pub top: u32,
    /// Per instance record (a top-level leaf's `first`), the root of its object's hierarchy.
    pub instance_roots: Vec<u32>,
}

impl WideBvh {
    /// Collapses the kernels' node array `nodes`: the world's tree at node 0, and with instances
    /// the top level after it and the objects' trees the instance records in `shape_data` name.
    /// The leaves' opaque triangles (of `primitives`) go into `TriangleBlock`s.
    pub fn build(frame: &FrameParams, nodes: &[BvhNode], primitives: &[Primitive], shape_data: &[f32]) -> WideBvh {
        let mut wide = WideBvh::default();
        if nodes.is_empty() {
            return wide;
        }
        wide.world = wide.collapse(nodes, 0, primitives);
        if frame.instance_count > 0 {
            // The top level's leaves are instances, not primitives.
            wide.top = wide.collapse(nodes, nodes[0].skip() as usize, &[]);
            let mut roots = std::collections::HashMap::new();
            for k in 0..frame.instance_count {
                let at = (frame.instance_data + k * INSTANCE_DATA_FLOATS + INSTANCE_DATA_ROOT) as usize;
                let root = shape_data[at].to_bits() as usize;
                let wide_root = match roots.get(&root) {
                    Some(&r) => r,
                    None => {
                        let r = wide.collapse(nodes, root, primitives);
                        roots.insert(root, r);
                        r
                    }
                };
                wide.instance_roots.push(wide_root);
            }
        }
        wide
    }

    /// Appends the wide form of the binary subtree at `root` and returns its index. The binary
    /// arrays are depth first: an inner node's left child follows it, its right child starts at
    /// the left child's miss link. Each wide node opens the largest inner child until it holds
    /// four (the surface area heuristic's choice: the largest box is the likeliest to be entered).
    fn collapse(&mut self, nodes: &[BvhNode], root: usize, primitives: &[Primitive]) -> u32 {
        let children = |i: usize| [i + 1, nodes[i + 1].skip() as usize];
        let mut kids = Vec::with_capacity(4);
        if nodes[root].count() > 0 {
            kids.push(root);
        } else {
            kids.extend(children(root));
        }
        while kids.len() < 4 {
            let largest = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| nodes[k].count() == 0)
                .max_by(|(_, &a), (_, &b)| half_area(&nodes[a]).total_cmp(&half_area(&nodes[b])))
                .map(|(at, _)| at);
            let Some(at) = largest else { break };
            // In place, so that the lanes keep the binary tree's depth-first order.
            let open = kids[at];
            kids.splice(at..=at, children(open));
        }
        let index = self.nodes.len();
        let empty = Vec4::splat(f32::NAN);
        self.nodes.push(WideNode {
            lo: [empty; 3],
            hi: [empty; 3],
            child: [0; 4],
            count: [0; 4],
            block: [NO_BLOCK; 4],
            lanes: 0,
        });
        let mut node = self.nodes[index];
        for (lane, &k) in kids.iter().enumerate() {
            let n = &nodes[k];
            for axis in 0..3 {
                node.lo[axis][lane] = n.aabb_min[axis];
                node.hi[axis][lane] = n.aabb_max[axis];
            }
            node.lanes |= 1 << lane;
            if n.count() > 0 {
                (node.child[lane], node.count[lane]) = (n.first, n.count());
                node.block[lane] = self.block(primitives.get(n.first as usize..(n.first + n.count()) as usize));
            } else {
                node.child[lane] = self.collapse(nodes, k, primitives);
            }
        }
        self.nodes[index] = node;
        index as u32
    }

    /// The block of a leaf's primitives when they are up to four opaque triangles, else `NO_BLOCK`.
    fn block(&mut self, leaf: Option<&[Primitive]>) -> u32 {
        let Some(leaf) = leaf.filter(|l| {
            l.len() <= 4
                && l.iter()
                    .all(|p| p.kind & PRIMITIVE_KIND_MASK == PRIMITIVE_TRIANGLE && p.kind & PRIMITIVE_FLAG_ALPHA == 0)
        }) else {
            return NO_BLOCK;
        };
        // Empty lanes repeat the first triangle; the walk masks them by the leaf's count.
        let lane = |k: usize| &leaf[if k < leaf.len() { k } else { 0 }];
        let vertex = |k: usize| [lane(k).p0, lane(k).p1, lane(k).p2].map(Vec3::from);
        let mut block = TriangleBlock { p0: [Vec4::ZERO; 3], e1: [Vec4::ZERO; 3], e2: [Vec4::ZERO; 3] };
        for k in 0..4 {
            let [p0, p1, p2] = vertex(k);
            let (e1, e2) = (p1 - p0, p2 - p0);
            for axis in 0..3 {
                block.p0[axis][k] = p0[axis];
                block.e1[axis][k] = e1[axis];
                block.e2[axis][k] = e2[axis];
            }
        }
        self.blocks.push(block);
        self.blocks.len() as u32 - 1
    }
}

fn half_area(n: &BvhNode) -> f32 {
    let e = (Vec3::from(n.aabb_max) - Vec3::from(n.aabb_min)).max(Vec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::build_bvh;
    use crate::layout::constants::PRIMITIVE_TRIANGLE;
    use crate::layout::Primitive;

    #[test]
    fn every_leaf_of_the_binary_tree_appears_once_inside_its_wide_box() {
        let prims: Vec<Primitive> = (0..500)
            .map(|i| {
                let p = Vec3::new((i % 8) as f32, ((i / 8) % 8) as f32, (i / 64) as f32 * 1.5);
                Primitive {
                    p0: p.into(),
                    p1: (p + Vec3::X * 0.7).into(),
                    p2: (p + Vec3::Y * 0.4).into(),
                    kind: PRIMITIVE_TRIANGLE,
                    ..Default::default()
                }
            })
            .collect();
        let bounds: Vec<_> = prims
            .iter()
            .map(|p| {
                let [a, b, c] = [p.p0, p.p1, p.p2].map(Vec3::from);
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let bvh = build_bvh(&prims, &bounds).unwrap();
        let wide = WideBvh::build(&FrameParams::default(), &bvh.nodes, &bvh.primitives, &[]);
        let mut covered = vec![0; prims.len()];
        let mut stack = vec![wide.world];
        let mut visited = 0;
        while let Some(i) = stack.pop() {
            visited += 1;
            let n = &wide.nodes[i as usize];
            assert!(n.lanes != 0 && n.lanes.count_ones() <= 4);
            for lane in 0..4 {
                if n.lanes & (1 << lane) == 0 {
                    continue;
                }
                let lo = Vec3::new(n.lo[0][lane], n.lo[1][lane], n.lo[2][lane]);
                let hi = Vec3::new(n.hi[0][lane], n.hi[1][lane], n.hi[2][lane]);
                if n.count[lane] == 0 {
                    stack.push(n.child[lane]);
                    continue;
                }
                for p in n.child[lane]..n.child[lane] + n.count[lane] {
                    covered[p as usize] += 1;
                    let (a, b) = (Vec3::from(bvh.primitives[p as usize].p0), Vec3::from(bvh.primitives[p as usize].p1));
                    assert!(a.cmpge(lo).all() && a.cmple(hi).all() && b.cmple(hi).all());
                }
            }
        }
        assert!(covered.iter().all(|&c| c == 1), "every primitive in exactly one leaf");
        assert_eq!(visited, wide.nodes.len(), "every wide node reachable once");
        // A node holds fewer than four children only where none of them could be opened.
        for n in &wide.nodes {
            let lanes = n.lanes.count_ones() as usize;
            assert!(lanes == 4 || (0..lanes).all(|k| n.count[k] > 0), "an inner child left closed: {n:?}");
        }
        let inner = bvh.nodes.iter().filter(|n| n.count() == 0).count();
        assert!(wide.nodes.len() < inner, "{} wide nodes for {inner} binary inner nodes", wide.nodes.len());
    }
}
