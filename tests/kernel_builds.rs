//! The scene kernels' builds (build.rs) come in pairs: `NAME`, whose scene fetches read page 0
//! only, and `NAME_paged`, which selects among the SCENE_PAGES pages. Lavapipe inlines every
//! fetch before it folds specialization constants, so a page selection left in the one-page
//! builds, even one a constant removes, doubled the code it works through when it creates a
//! pipeline, for every scene (BENCHMARKS.md, "Kernel creation: the page selection in its own
//! builds"). Read from the SPIR-V, without a GPU.

use photonix::layout::constants::SCENE_PAGES;
use photonix::shaders::{spirv, KERNELS};

/// The scene's texel-buffer arrays (shaders/scene_bindings.glsl).
const SCENE_ARRAYS: [&str; 8] = [
    "node_texels",
    "primitive_texels",
    "material_texels",
    "light_texels",
    "texture_texels",
    "texture_words",
    "shape_words",
    "medium_texels",
];

/// The pages (constant element indices) a module's access chains take into the scene arrays.
fn pages_indexed(words: &[u32]) -> Vec<u32> {
    const OP_NAME: u32 = 5;
    const OP_CONSTANT: u32 = 43;
    const OP_ACCESS_CHAIN: u32 = 65;
    const OP_IN_BOUNDS_ACCESS_CHAIN: u32 = 66;
    let string = |ws: &[u32]| -> String {
        let bytes: Vec<u8> = ws.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
        String::from_utf8_lossy(&bytes).into_owned()
    };
    let (mut arrays, mut constants, mut chains) = (Vec::new(), std::collections::HashMap::new(), Vec::new());
    let mut i = 5; // the header is five words
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let args = &words[i + 1..(i + count).min(words.len())];
        match op {
            OP_NAME if SCENE_ARRAYS.contains(&string(&args[1..]).as_str()) => arrays.push(args[0]),
            OP_CONSTANT if args.len() == 3 => {
                constants.insert(args[1], args[2]);
            }
            OP_ACCESS_CHAIN | OP_IN_BOUNDS_ACCESS_CHAIN if args.len() >= 4 => chains.push((args[2], args[3])),
            _ => {}
        }
        i += count.max(1);
    }
    let mut pages: Vec<u32> = chains
        .into_iter()
        .filter(|(base, _)| arrays.contains(base))
        .map(|(_, index)| *constants.get(&index).expect("scene arrays are indexed by constants only"))
        .collect();
    pages.sort_unstable();
    pages.dedup();
    pages
}

#[test]
fn only_the_paged_builds_select_pages() {
    let mut pairs = 0;
    for (name, _) in KERNELS.iter().filter(|(n, _)| !n.ends_with("_paged")) {
        let Some(paged) = spirv(&format!("{name}_paged")) else { continue };
        let one = spirv(name).unwrap();
        assert_eq!(pages_indexed(&one), [0], "{name}: its scene fetches read page 0 and no other");
        let all: Vec<u32> = (0..SCENE_PAGES).collect();
        assert_eq!(pages_indexed(&paged), all, "{name}_paged: its scene fetches select among all pages");
        pairs += 1;
    }
    // emit_photons, render, render_pt, render_vcm and vcm_light in 24 builds each, texel_probe in one.
    assert_eq!(pairs, 5 * 24 + 1, "every scene kernel build has a paged twin");
}
