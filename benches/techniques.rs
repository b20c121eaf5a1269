//! Multiple importance sampling checked by variance: each of vcm's techniques alone against the
//! combination, at equal samples and with the time each took (issue 26's "VCM's variance no
//! higher than the best single technique's").
//!
//! `cargo run --release --example techniques [SIZE] [SPP]` (default 64 x 64, 64 samples per
//! pixel): the shared scenes without media, on the CPU twin; relMSE against the shared
//! references (area-downsampled to SIZE) and each image's mean against the reference's. A
//! technique that cannot make some of a scene's paths (light tracing through the mirror and the
//! glass ball: the camera cannot be reached through a delta lobe) is shown with its mean low.

use std::error::Error;
use std::path::PathBuf;
use std::time::Instant;

use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::read_exr;
use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY, VCM_MERGE_ONLY};
use photonix::render::{prepare, render_cpu, FrameSettings};
use photonix::scene::{load_scene, Integrator};

const SCENES: [&str; 3] = ["cornell-box", "cornell-caustics", "cornell-glossy"];
const TECHNIQUES: [(&str, Integrator, u32); 5] = [
    ("light tracing", Integrator::Bpt, VCM_LIGHT_TRACE_ONLY),
    ("merging", Integrator::Vcm, VCM_MERGE_ONLY),
    ("path tracing", Integrator::Pt, TECHNIQUES_ALL),
    ("bpt (connections)", Integrator::Bpt, TECHNIQUES_ALL),
    ("vcm", Integrator::Vcm, TECHNIQUES_ALL),
];

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let size: u32 = args.first().map_or(Ok(64), |a| a.parse())?;
    let spp: u32 = args.get(1).map_or(Ok(64), |a| a.parse())?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    println!("| scene | technique | relMSE | mean ratio R, G, B | seconds | relMSE x seconds |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for name in SCENES {
        let full = read_exr(&root.join("../shared/reference").join(name).join("reference.exr"))?;
        if full.width % size != 0 || full.width != full.height {
            return Err(format!("SIZE must divide the reference's {} pixels", full.width).into());
        }
        let reference = downsample(&full, full.width / size);
        for (label, integrator, techniques) in TECHNIQUES {
            let mut scene = load_scene(&root.join("scenes").join(format!("{name}.toml")))?;
            scene.render.integrator = integrator;
            let settings =
                FrameSettings { width: size, height: size, max_depth: scene.render.max_depth, seed: scene.render.seed };
            let mut buffers = prepare(&scene, &settings)?;
            buffers.frame.techniques = techniques;
            let t = Instant::now();
            let image = render_cpu(&buffers, spp, None, 0, &mut |_, _| {}).image;
            let seconds = t.elapsed().as_secs_f64();
            let error = rel_mse(&image, &reference);
            let m = mean_ratio(&image, &reference);
            println!(
                "| {name} | {label} | {error:.5} | {:.4}, {:.4}, {:.4} | {seconds:.2} | {:.5} |",
                m[0],
                m[1],
                m[2],
                error * seconds
            );
        }
    }
    Ok(())
}
