//! The GPU layout round trip: `layout_probe.comp` copies element 0 of every shared struct to
//! element 1, field by field, in GLSL. If any Rust offset or stride disagreed with std430, the
//! copy would land shifted and element 1 would differ from element 0. tests/layout.rs proves
//! the same from the SPIR-V offsets; this test proves it on a device, through real loads and
//! stores.

use bytemuck::Pod;
use photonix::gpu::{GpuContext, GpuOptions};
use photonix::layout::{
    BvhNode, DispatchRange, EmitParams, FrameParams, GridParams, Light, Material, Photon, Primitive,
};

/// Two elements: element 0 has a distinct word in every 4-byte slot, element 1 is zero.
/// Each word is `0x40SSKKJJ` (struct S, word K, J = K ^ 0xa5): a normal float between 2 and 4,
/// so float fields carry no NaN that a device might canonicalise, and no two words anywhere
/// are equal, so a shifted field cannot copy the right value by accident.
fn pattern<T: Pod>(struct_index: u32) -> [T; 2] {
    let mut elements = [T::zeroed(); 2];
    let words: &mut [u32] = bytemuck::cast_slice_mut(&mut elements[..1]);
    for (k, word) in words.iter_mut().enumerate() {
        let k = k as u32;
        *word = 0x4000_0000 | (struct_index << 16) | (k << 8) | (k ^ 0xa5);
    }
    elements
}

fn check<T: Pod + PartialEq + std::fmt::Debug>(name: &str, sent: &[T; 2], back: &[T]) {
    assert_eq!(back.len(), 2, "{name}");
    assert_eq!(back[0], sent[0], "{name}: element 0 changed on the device");
    assert_eq!(back[1], back[0], "{name}: the GLSL copy of element 0 differs, so the layouts disagree");
}

#[test]
fn gpu_copies_every_shared_struct_field_by_field() {
    let gpu = GpuContext::new(&GpuOptions { device: None, validation: true })
        .unwrap_or_else(|e| panic!("cannot open the GPU: {e}"));
    let spirv = photonix::shaders::spirv("layout_probe").expect("build.rs compiles shaders/layout_probe.comp");
    let probe = gpu.create_kernel("layout_probe", &spirv, 9, 0).unwrap();

    let nodes = pattern::<BvhNode>(1);
    let primitives = pattern::<Primitive>(2);
    let materials = pattern::<Material>(3);
    let lights = pattern::<Light>(4);
    let frames = pattern::<FrameParams>(5);
    let ranges = pattern::<DispatchRange>(6);
    let photons = pattern::<Photon>(7);
    let grids = pattern::<GridParams>(8);
    let emits = pattern::<EmitParams>(9);
    let buffers = [
        gpu.upload("nodes", &nodes).unwrap(),
        gpu.upload("primitives", &primitives).unwrap(),
        gpu.upload("materials", &materials).unwrap(),
        gpu.upload("lights", &lights).unwrap(),
        gpu.upload("frames", &frames).unwrap(),
        gpu.upload("ranges", &ranges).unwrap(),
        gpu.upload("photons", &photons).unwrap(),
        gpu.upload("grids", &grids).unwrap(),
        gpu.upload("emits", &emits).unwrap(),
    ];
    let bound: Vec<_> = buffers.iter().collect();
    gpu.run("layout_probe", |r| r.dispatch(&probe, &bound, &[], [1, 1, 1])).unwrap();

    check("BvhNode", &nodes, &gpu.download::<BvhNode>(&buffers[0]).unwrap());
    check("Primitive", &primitives, &gpu.download::<Primitive>(&buffers[1]).unwrap());
    check("Material", &materials, &gpu.download::<Material>(&buffers[2]).unwrap());
    check("Light", &lights, &gpu.download::<Light>(&buffers[3]).unwrap());
    check("FrameParams", &frames, &gpu.download::<FrameParams>(&buffers[4]).unwrap());
    check("DispatchRange", &ranges, &gpu.download::<DispatchRange>(&buffers[5]).unwrap());
    check("Photon", &photons, &gpu.download::<Photon>(&buffers[6]).unwrap());
    check("GridParams", &grids, &gpu.download::<GridParams>(&buffers[7]).unwrap());
    check("EmitParams", &emits, &gpu.download::<EmitParams>(&buffers[8]).unwrap());
}
