//! The compiled compute kernels, embedded at build time by `build.rs`.

include!(concat!(env!("OUT_DIR"), "/kernels.rs"));

/// The SPIR-V words of the kernel `name` (the file stem in `shaders/`), if it exists.
pub fn spirv(name: &str) -> Option<Vec<u32>> {
    let bytes = KERNELS.iter().find(|(n, _)| *n == name)?.1;
    // SPIR-V is a stream of little-endian words; copying avoids any alignment assumption.
    Some(bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect())
}
