//! The scene's texel buffers read back as structs: `texel_probe.comp` reads element 1 of every
//! scene struct through its loader in shaders/scene_fetch.glsl (RGBA32UI texels, field by field)
//! and stores it to a storage buffer of that struct, and photons 0..3 through `fetch_photon`
//! (20-byte photons in RGBA32UI texels: each starts at a different word of its texel), and
//! light vertex 1 and light material 1 through `fetch_light_vertex` and `fetch_light_material`
//! (render_vcm's vertex slots). A loader
//! that took a field from the wrong word, or a wrong texel stride, would bring back a different
//! element. The same again with every scene array split into pages of 64 bytes (the paged
//! fetches of scene_fetch.glsl, in the probe's `paged` build), so that structs straddle pages.

use photonix::gpu::BindingTypes;
use photonix::gpu::{GpuContext, GpuOptions};
use photonix::layout::constants::{SCENE_BINDINGS, SCENE_PAGES};
use photonix::layout::{gpu_struct_layouts, FrameParams};
use photonix::render::gpu::SCENE_BINDING_TYPES;

/// Two elements of `words` words each, every word distinct (`0x40SSKKJJ`: struct S, word K of
/// the pair, J = K ^ 0xa5), normal floats, so a misplaced field cannot match by accident.
fn pattern(struct_index: u32, words: u32) -> Vec<u32> {
    (0..2 * words).map(|k| 0x4000_0000 | (struct_index << 16) | (k << 8) | (k ^ 0xa5)).collect()
}

#[test]
fn every_scene_struct_round_trips_through_its_texel_loader() {
    round_trip(None);
}

#[test]
fn every_scene_struct_round_trips_through_pages_of_64_bytes() {
    round_trip(Some(64));
}

/// Sends the pattern through the loaders with each scene array in one buffer (`page_bytes`
/// None) or split into buffers of `page_bytes` (16 words: element 1 of a material, texels
/// 7..13, spans pages 1 to 3).
fn round_trip(page_bytes: Option<usize>) {
    let gpu = GpuContext::new(&GpuOptions { device: None, validation: true })
        .unwrap_or_else(|e| panic!("cannot open the GPU: {e}"));
    // One page per array reads through the plain build, several through the paged one (as
    // `KernelVariant::kernel_name` picks the scene kernels' builds).
    let kernel = if page_bytes.is_some() { "texel_probe_paged" } else { "texel_probe" };
    let spirv =
        photonix::shaders::spirv(kernel).expect("build.rs compiles shaders/texel_probe.comp and its paged build");
    let size = |name: &str| {
        let layouts = gpu_struct_layouts();
        layouts.iter().find(|(n, _, _)| *n == name).unwrap_or_else(|| panic!("{name} is a shared struct")).2 / 4
    };
    // Scene bindings in order: frame, nodes, primitives, materials, lights, textures, texture
    // words, shape words, media (shaders/scene_bindings.glsl).
    let structs = ["BvhNode", "Primitive", "Material", "Light", "Texture", "Medium"];
    let sent: Vec<(&str, Vec<u32>)> =
        structs.iter().enumerate().map(|(i, name)| (*name, pattern(i as u32 + 1, size(name)))).collect();
    let words_of = |name: &str| &sent.iter().find(|(n, _)| *n == name).unwrap().1;
    let texture_words: Vec<u32> = (0..24).map(|k| 0x4070_0000 | k).collect();
    let shape_words: Vec<u32> = (0..24).map(|k| 0x4080_0000 | k).collect();

    let frame = gpu.upload("frame", &[FrameParams::default()]).unwrap();
    // Each array as its SCENE_PAGES pages: its pages, then its first again.
    let page_words = page_bytes.map_or(usize::MAX, |b| b / 4);
    let mut pages_used = 1;
    let scene: Vec<Vec<_>> = [
        words_of("BvhNode"),
        words_of("Primitive"),
        words_of("Material"),
        words_of("Light"),
        words_of("Texture"),
        &texture_words,
        &shape_words,
        words_of("Medium"),
    ]
    .iter()
    .map(|w| {
        let pages: Vec<_> = w.chunks(page_words).map(|page| gpu.upload("scene page", page).unwrap()).collect();
        assert!(pages.len() <= SCENE_PAGES as usize, "the pattern fits the pages");
        pages_used = pages_used.max(pages.len() as u32);
        pages
    })
    .collect();
    let scene: Vec<_> =
        scene.iter().flat_map(|pages| (0..SCENE_PAGES as usize).map(|k| pages.get(k).unwrap_or(&pages[0]))).collect();
    // Four photons: 20 words, so photon i starts at word 5i, at offset i of its texel.
    let photon_words: Vec<u32> = (0..20).map(|k| 0x4090_0000 | (k << 8) | (k ^ 0xa5)).collect();
    let photons_in = gpu.upload("photons", &photon_words).unwrap();
    let photons_out = gpu.upload("photons out", &[0u32; 20]).unwrap();
    let vertex_words = pattern(9, size("LightVertex"));
    let vertices_in = gpu.upload("light vertices", &vertex_words).unwrap();
    let vertices_out = gpu.upload("light vertex out", &vec![0u32; size("LightVertex") as usize]).unwrap();
    let material_words = pattern(10, size("LightMaterial"));
    let light_materials_in = gpu.upload("light materials", &material_words).unwrap();
    let light_materials_out = gpu.upload("light material out", &vec![0u32; size("LightMaterial") as usize]).unwrap();
    let outputs: Vec<_> = structs
        .iter()
        .map(|name| gpu.upload(name, &vec![0u32; size(name) as usize]).unwrap())
        .chain(std::iter::once(gpu.upload("words", &[0u32; 4]).unwrap()))
        .collect();
    let bound: Vec<_> = std::iter::once(&frame)
        .chain(scene)
        .chain(&outputs)
        .chain([&photons_in, &photons_out, &vertices_in, &vertices_out, &light_materials_in, &light_materials_out])
        .collect();
    assert_eq!(bound.len() as u32, 1 + 8 * SCENE_PAGES + 13);
    // The input texels: photons, light vertices, light materials.
    let rgba = SCENE_BINDING_TYPES.rgba | 0b1010_1000_0000 << SCENE_BINDINGS;
    let types = BindingTypes { rgba, ..SCENE_BINDING_TYPES };
    // constant_id 5 and 6 (scene_bindings.glsl): pages in use, words per page (log2).
    let constants = match page_bytes {
        None => vec![],
        Some(bytes) => {
            assert!(pages_used > 1, "the pattern spans pages");
            vec![1, 1, 1, 1, u32::MAX, pages_used, (bytes / 4).ilog2()]
        }
    };
    let probe = gpu
        .create_specialized_kernel(kernel, &spirv, SCENE_BINDINGS + 13, types, 0, &constants)
        .expect("the probe matches its layout");
    gpu.run("texel_probe", |r| r.dispatch(&probe, &bound, &[], [1, 1, 1])).unwrap();

    for ((name, words), out) in sent.iter().zip(&outputs) {
        let back: Vec<u32> = gpu.download(out).unwrap();
        let half = words.len() / 2;
        assert_eq!(back, words[half..], "{name}: the loader's element 1 differs from the one sent");
    }
    let words: Vec<u32> = gpu.download(outputs.last().unwrap()).unwrap();
    let node = words_of("BvhNode");
    let primitive = words_of("Primitive");
    let expected = [texture_words[21], shape_words[21], node[node.len() - 1], primitive[primitive.len() / 2 + 3]];
    assert_eq!(words, expected, "texture word, shape word, node skip/count, primitive kind");
    let photons: Vec<u32> = gpu.download(&photons_out).unwrap();
    assert_eq!(photons, photon_words, "fetch_photon of photons 0..3 (each at another word of its texel)");
    let vertex: Vec<u32> = gpu.download(&vertices_out).unwrap();
    assert_eq!(vertex, vertex_words[vertex_words.len() / 2..], "fetch_light_vertex of vertex 1");
    let light_material: Vec<u32> = gpu.download(&light_materials_out).unwrap();
    assert_eq!(light_material, material_words[material_words.len() / 2..], "fetch_light_material of material 1");
}
