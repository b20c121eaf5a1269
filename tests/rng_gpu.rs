//! The quasi-random numbers of `shaders/rng.glsl`, run on the GPU through
//! `shaders/rng_probe.comp`, against their Rust twins in `photonix::cpu::rng`: integer
//! arithmetic only, so they must agree bit for bit.

use photonix::cpu::rng::{pcg4d, qmc2, qmc2_choice, sequence_point};
use photonix::gpu::{GpuContext, GpuOptions};
use photonix::layout::constants::WORKGROUP_SIZE;

#[test]
fn gpu_quasi_random_numbers_equal_cpu_twins() {
    let gpu = GpuContext::new(&GpuOptions { device: None, validation: true })
        .expect("a Vulkan device (lavapipe) with validation");
    let spirv = photonix::shaders::spirv("rng_probe").expect("build.rs compiles rng_probe.comp");
    let kernel = gpu.create_kernel("rng_probe", &spirv, 2, 4).expect("the probe matches its layout");
    // Hashed records, small ones (the first samples of a pixel) and the words' extremes, where
    // the index's wrap and the products' high words are.
    let mut records: Vec<[u32; 4]> = (0..4096u32).map(|i| pcg4d([i, 7, 11, 13])).collect();
    records.extend((0..1024u32).map(|i| [i % 7, i, i % 3, i / 7]));
    records.extend([[0, u32::MAX, u32::MAX, u32::MAX], [1, 65_535, 65_537, 1], [u32::MAX, 0, 0, 0]]);
    let n = records.len() as u32;
    let input = gpu.upload("probe_inputs", &records).unwrap();
    let output = gpu.create_buffer("probe_outputs", n as u64 * 32).unwrap();
    gpu.run("rng probe", |r| {
        r.dispatch(&kernel, &[&input, &output], bytemuck::bytes_of(&n), [n.div_ceil(WORKGROUP_SIZE), 1, 1])
    })
    .unwrap();
    let gpu_out: Vec<[u32; 8]> = gpu.download(&output).unwrap();
    for (r, g) in records.iter().zip(&gpu_out) {
        let q = qmc2(r[0], r[1], r[2], r[3]);
        let (stream, index) = sequence_point(r[0] & 1, r[1], r[2], r[3]);
        let (pair, choice) = qmc2_choice(r[0], r[1], r[2], r[3]);
        let cpu =
            [q[0].to_bits(), q[1].to_bits(), stream, index, pair[0].to_bits(), pair[1].to_bits(), choice.to_bits(), 0];
        assert_eq!(*g, cpu, "record {r:?}: GPU {g:?}, CPU {cpu:?}");
    }
}
