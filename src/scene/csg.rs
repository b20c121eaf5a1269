//! CSG objects (`type = "csg"`): a boolean tree over closed shapes, each leaf keeping its own
//! material. The renderer intersects the tree as one primitive (see `cpu/csg.rs`).

use glam::Vec3;

use super::Shape;
use crate::layout::constants::{
    CSG_OP_DIFFERENCE, CSG_OP_INTERSECTION, CSG_OP_LEAF, CSG_OP_MERGE, CSG_OP_SHIFT, CSG_OP_UNION,
};

/// The four operations of POV-Ray's CSG.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    /// Every child's surface, inner ones included.
    Union,
    /// The union's solid without the surfaces inside other children.
    Merge,
    Intersection,
    /// The first child minus all the others.
    Difference,
}

/// A node of the tree: a leaf (an index into `Csg::leaves`) or an operation over two or more
/// children.
#[derive(Clone, Debug, PartialEq)]
pub enum CsgNode {
    Leaf(u32),
    Op(CsgOp, Vec<CsgNode>),
}

/// A CSG object: its tree and, for each leaf, the shapes that make that closed solid (a sphere;
/// a box's 12 triangles; a capped cylinder's side and caps; a closed mesh's triangles), in world
/// space, each with its own material.
#[derive(Clone, Debug)]
pub struct Csg {
    pub root: CsgNode,
    pub leaves: Vec<Vec<Shape>>,
}

impl Csg {
    /// Axis-aligned bounds (min, max): those of the solid's tree (an intersection's overlap, a
    /// difference's first child), never larger than the union of the leaves'.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.node_bounds(&self.root);
        if lo.cmple(hi).all() {
            (lo, hi)
        } else {
            // An empty intersection: any box inside the leaves' will do, no ray shows it.
            self.leaf_bounds(0)
        }
    }

    fn leaf_bounds(&self, leaf: usize) -> (Vec3, Vec3) {
        self.leaves[leaf].iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), s| {
            let (a, b) = s.geometry.bounds();
            (lo.min(a), hi.max(b))
        })
    }

    fn node_bounds(&self, node: &CsgNode) -> (Vec3, Vec3) {
        match node {
            CsgNode::Leaf(l) => self.leaf_bounds(*l as usize),
            CsgNode::Op(op, children) => {
                let mut boxes = children.iter().map(|c| self.node_bounds(c));
                let first = boxes.next().unwrap_or((Vec3::INFINITY, Vec3::NEG_INFINITY));
                match op {
                    CsgOp::Union | CsgOp::Merge => boxes.fold(first, |(lo, hi), (a, b)| (lo.min(a), hi.max(b))),
                    CsgOp::Intersection => boxes.fold(first, |(lo, hi), (a, b)| (lo.max(a), hi.min(b))),
                    CsgOp::Difference => first,
                }
            }
        }
    }

    /// The leaves' total area: an upper bound of the solid's, for the automatic photon radius.
    pub fn area(&self) -> f32 {
        self.leaves.iter().flatten().map(|s| s.geometry.area()).sum()
    }

    /// The tree as the kernels' postfix program (`CSG_OP_*` words; an operation over n children
    /// is n - 1 binary ones, left to right), and for each leaf whether it lies on the subtracted
    /// side of an odd number of differences (its normal then points into the solid).
    pub fn program(&self) -> (Vec<u32>, Vec<bool>) {
        let mut words = Vec::new();
        let mut flips = vec![false; self.leaves.len()];
        emit(&self.root, false, &mut words, &mut flips);
        (words, flips)
    }
}

fn emit(node: &CsgNode, flipped: bool, words: &mut Vec<u32>, flips: &mut [bool]) {
    match node {
        CsgNode::Leaf(l) => {
            words.push(CSG_OP_LEAF << CSG_OP_SHIFT | l);
            flips[*l as usize] = flipped;
        }
        CsgNode::Op(op, children) => {
            let code = match op {
                CsgOp::Union => CSG_OP_UNION,
                CsgOp::Merge => CSG_OP_MERGE,
                CsgOp::Intersection => CSG_OP_INTERSECTION,
                CsgOp::Difference => CSG_OP_DIFFERENCE,
            };
            for (k, child) in children.iter().enumerate() {
                let subtracted = *op == CsgOp::Difference && k > 0;
                emit(child, flipped ^ subtracted, words, flips);
                if k > 0 {
                    words.push(code << CSG_OP_SHIFT);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn program_is_postfix_and_flips_subtracted_leaves() {
        // (0 - (1 merge 2)) union 3
        let root = CsgNode::Op(
            CsgOp::Union,
            vec![
                CsgNode::Op(
                    CsgOp::Difference,
                    vec![CsgNode::Leaf(0), CsgNode::Op(CsgOp::Merge, vec![CsgNode::Leaf(1), CsgNode::Leaf(2)])],
                ),
                CsgNode::Leaf(3),
            ],
        );
        let csg = Csg { root, leaves: vec![Vec::new(); 4] };
        let (words, flips) = csg.program();
        let op = |c: u32| c << CSG_OP_SHIFT;
        assert_eq!(words, vec![0, 1, 2, op(CSG_OP_MERGE), op(CSG_OP_DIFFERENCE), 3, op(CSG_OP_UNION)]);
        assert_eq!(flips, vec![false, true, true, false]);
    }
}
