//! Times the creation of one scene kernel's compute pipeline (on lavapipe: its NIR passes and,
//! when Mesa's disk cache misses, LLVM), from the embedded SPIR-V or from a file, with the
//! specialization constants given. A file lets a changed shader be timed without rebuilding the
//! crate: `glslangValidator -V --target-env vulkan1.2 -I<OUT_DIR> -Ishaders -o x.spv
//! shaders/render_vcm.comp`, then
//!
//! `cargo run --release --example kernel_creation -- render_vcm --spirv x.spv --constants
//! 0,0,0,0,26,1,25 --repeat 4`
//!
//! Prints each creation's wall and thread CPU seconds (the first creation of a new module also
//! compiles it with LLVM; later ones find it in the disk cache, as a render's set-up usually does).
//! The bindings are those of `src/render/gpu/kernels.rs` for the kernel's base name.

use std::time::Instant;

use photonix::gpu::{BindingTypes, GpuContext, GpuOptions};
use photonix::layout::constants::{
    BINDING_FRAME, BINDING_LIGHTS, BINDING_MATERIALS, BINDING_MEDIA, BINDING_NODES, BINDING_PRIMITIVES,
    BINDING_SHAPE_DATA, BINDING_TEXTURES, BINDING_TEXTURE_DATA, SCENE_BINDINGS, SCENE_PAGES,
};
use photonix::layout::{DispatchRange, EmitParams, VcmParams};

const SCENE_RGBA: u32 = 1 << BINDING_NODES
    | 1 << BINDING_PRIMITIVES
    | 1 << BINDING_MATERIALS
    | 1 << BINDING_LIGHTS
    | 1 << BINDING_TEXTURES
    | 1 << BINDING_MEDIA;
const SCENE_WORDS: u32 = 1 << BINDING_TEXTURE_DATA | 1 << BINDING_SHAPE_DATA;
const SCENE: BindingTypes = BindingTypes {
    rgba: SCENE_RGBA,
    words: SCENE_WORDS,
    uniform: 1 << BINDING_FRAME,
    arrays: SCENE_RGBA | SCENE_WORDS,
    array_len: SCENE_PAGES,
};

/// (bindings, binding types, push-constant bytes) of a kernel, as kernels.rs makes it.
fn layout(base: &str) -> Option<(u32, BindingTypes, usize)> {
    Some(match base {
        "emit_photons" => (SCENE_BINDINGS + 4, SCENE, size_of::<EmitParams>()),
        "render" | "render_pt" => (
            SCENE_BINDINGS + 8,
            BindingTypes {
                rgba: SCENE.rgba | 0b01_0101 << (SCENE_BINDINGS + 2),
                words: SCENE.words | 0b10_1010 << (SCENE_BINDINGS + 2),
                uniform: SCENE.uniform | 1 << (SCENE_BINDINGS + 1),
                ..SCENE
            },
            size_of::<DispatchRange>(),
        ),
        "vcm_light" => (SCENE_BINDINGS + 8, SCENE, size_of::<VcmParams>()),
        "render_vcm" => (
            SCENE_BINDINGS + 12,
            BindingTypes {
                rgba: SCENE.rgba | 0b1_1101_1000 << SCENE_BINDINGS,
                words: SCENE.words | 0b10_0000 << SCENE_BINDINGS,
                uniform: SCENE.uniform | 0b110 << SCENE_BINDINGS,
                ..SCENE
            },
            size_of::<DispatchRange>(),
        ),
        _ => return None,
    })
}

/// This thread's CPU seconds (user + system), from /proc; 0 where there is none.
fn thread_cpu() -> f64 {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").unwrap_or_default();
    // Fields after the command's closing parenthesis; utime and stime are the 14th and 15th.
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: kernel_creation KERNEL [--spirv FILE] [--constants c0,c1,...] [--repeat N]";
    let name = args.first().ok_or_else(|| anyhow::anyhow!("{usage}"))?.clone();
    let mut spirv_file = None;
    let mut constants: Vec<u32> = Vec::new();
    let mut repeat = 3usize;
    let mut i = 1;
    while i < args.len() {
        let value = args.get(i + 1).ok_or_else(|| anyhow::anyhow!("{} needs a value; {usage}", args[i]))?;
        match args[i].as_str() {
            "--spirv" => spirv_file = Some(value.clone()),
            "--constants" => {
                constants = value
                    .split(',')
                    .map(|c| c.trim().parse::<u32>().map_err(|e| anyhow::anyhow!("--constants `{c}`: {e}")))
                    .collect::<Result<_, _>>()?
            }
            "--repeat" => repeat = value.parse().map_err(|e| anyhow::anyhow!("--repeat `{value}`: {e}"))?,
            other => anyhow::bail!("unknown argument `{other}`; {usage}"),
        }
        i += 2;
    }
    let base = ["render_pt", "render_vcm", "render", "vcm_light", "emit_photons"]
        .into_iter()
        .find(|b| name == *b || name.starts_with(&format!("{b}_")))
        .ok_or_else(|| anyhow::anyhow!("`{name}` is not a scene kernel (render, render_pt, render_vcm, vcm_light, emit_photons, or a variant of one)"))?;
    let (bindings, types, push) = layout(base).expect("every base has a layout");
    let spirv: Vec<u32> = match &spirv_file {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| anyhow::anyhow!("{path}: {e}"))?;
            bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect()
        }
        None => photonix::shaders::spirv(&name).ok_or_else(|| anyhow::anyhow!("no embedded kernel `{name}`"))?,
    };
    let ctx = GpuContext::new(&GpuOptions::from_env(None)?)?;
    println!("{name} on {}: {} SPIR-V words, constants {constants:?}", ctx.info().name, spirv.len());
    for run in 0..repeat {
        let (wall, cpu) = (Instant::now(), thread_cpu());
        let kernel = ctx.create_specialized_kernel(&name, &spirv, bindings, types, push as u32, &constants)?;
        println!("run {run}: {:.3} s wall, {:.2} s CPU", wall.elapsed().as_secs_f64(), thread_cpu() - cpu);
        drop(kernel);
    }
    Ok(())
}
