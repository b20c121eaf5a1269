//! Packs a CSG object: one primitive of kind `PRIMITIVE_CSG` for the BVH, its block in the shape
//! data (`CSG_DATA_*`: counts, the leaf of each leaf primitive, the postfix program), and its leaf
//! primitives, appended to the CSG leaf array that `prepare` places after all other primitives.

use super::pack::pack_shape;
use crate::layout::constants::*;
use crate::layout::Primitive;
use crate::scene::Csg;

/// The CSG primitive of `csg`; `uses_uv(material)` says whether a leaf's material reads uv.
pub fn pack_csg(
    csg: &Csg,
    uses_uv: impl Fn(u32) -> bool,
    shape_data: &mut Vec<f32>,
    csg_primitives: &mut Vec<Primitive>,
) -> Primitive {
    let (program, flips) = csg.program();
    let first = csg_primitives.len() as u32;
    let mut leaf_of = Vec::new();
    for (leaf, (shapes, flip)) in csg.leaves.iter().zip(flips).enumerate() {
        for shape in shapes {
            // Scene loading refuses leaves with alpha (or media, or emission).
            let mut p = pack_shape(shape, false, uses_uv(shape.material), shape_data);
            if flip {
                p.kind |= PRIMITIVE_FLAG_CSG_FLIP;
            }
            csg_primitives.push(p);
            leaf_of.push(leaf as u32);
        }
    }
    let data = shape_data.len() as u32;
    let words = [leaf_of.len() as u32, program.len() as u32, first];
    shape_data.extend(words.iter().chain(&leaf_of).chain(&program).map(|&w| f32::from_bits(w)));
    Primitive { kind: PRIMITIVE_CSG, material: csg.leaves[0][0].material, light: NO_LIGHT, data, ..Default::default() }
}
