//! The GPU layout round trip: `layout_probe.comp` copies element 0 of every shared struct to
//! element 1, field by field, in GLSL. If any Rust offset or stride disagreed with std430, the
//! copy would land shifted and element 1 would differ from element 0. tests/layout.rs proves
//! the same from the SPIR-V offsets; this test proves it on a device, through real loads and
//! stores.

use photonix::gpu::{GpuContext, GpuOptions};
use photonix::layout::gpu_struct_layouts;

/// Two elements of a struct of `size` bytes: element 0 has a distinct word in every 4-byte slot,
/// element 1 is zero. Each word is `0x40SSKKJJ` (struct S, word K, J = K ^ 0xa5): a normal float
/// between 2 and 4, so float fields carry no NaN that a device might canonicalise, and no two
/// words anywhere are equal, so a shifted field cannot copy the right value by accident.
fn pattern(struct_index: u32, size: u32) -> Vec<u32> {
    let words = size / 4;
    let mut elements = vec![0u32; 2 * words as usize];
    for k in 0..words {
        elements[k as usize] = 0x4000_0000 | (struct_index << 16) | (k << 8) | (k ^ 0xa5);
    }
    elements
}

#[test]
fn gpu_copies_every_shared_struct_field_by_field() {
    let gpu = GpuContext::new(&GpuOptions { device: None, validation: true })
        .unwrap_or_else(|e| panic!("cannot open the GPU: {e}"));
    let spirv = photonix::shaders::spirv("layout_probe").expect("build.rs compiles shaders/layout_probe.comp");
    let layouts = gpu_struct_layouts();
    let probe = gpu.create_kernel("layout_probe", &spirv, layouts.len() as u32, 0).unwrap();
    // layout_probe.comp binds the structs in the order of gpu_structs! (tests/layout.rs checks it).
    let sent: Vec<Vec<u32>> =
        layouts.iter().enumerate().map(|(i, (_, _, size))| pattern(i as u32 + 1, *size)).collect();
    let buffers: Vec<_> =
        layouts.iter().zip(&sent).map(|((name, _, _), words)| gpu.upload(name, words).unwrap()).collect();
    let bound: Vec<_> = buffers.iter().collect();
    gpu.run("layout_probe", |r| r.dispatch(&probe, &bound, &[], [1, 1, 1])).unwrap();
    for (((name, _, size), words), buffer) in layouts.iter().zip(&sent).zip(&buffers) {
        let back: Vec<u32> = gpu.download(buffer).unwrap();
        let half = (*size / 4) as usize;
        assert_eq!(back.len(), 2 * half, "{name}");
        assert_eq!(back[..half], words[..half], "{name}: element 0 changed on the device");
        assert_eq!(back[half..], back[..half], "{name}: the GLSL copy of element 0 differs, so the layouts disagree");
    }
}
