//! Progressive rendering end to end through the command line, on the GPU (lavapipe) with
//! validation on: convergence against the shared reference, merging, determinism, interrupts and
//! bad input.

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};

use photonix::io::metrics::{downsample, mean_ratio, rel_mse, rel_mse_per_pixel};
use photonix::io::read_exr;

/// Small, fast passes: 64x64, one sample, few photons, a fixed first radius.
const FAST: &[&str] = &[
    "--resolution",
    "64x64",
    "--spp",
    "1",
    "--photons",
    "20000",
    "--caustic-photons",
    "20000",
    "--gather-rays",
    "2",
    "--radius",
    "25",
    "--caustic-radius",
    "15",
];

fn render(dir: &Path, output: &str, extra: &[&str]) -> Output {
    let scene = common::repo_path("scenes/cornell-caustics.toml");
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", output, "--backend", "gpu"];
    // An explicit resolution replaces FAST's (its first two words).
    let skip = if extra.contains(&"--resolution") { 2 } else { 0 };
    args.extend_from_slice(&FAST[skip..]);
    args.extend_from_slice(extra);
    common::photonix(&args, dir)
}

fn ok(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    err
}

fn fails(out: &Output, pieces: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for p in pieces {
        assert!(err.contains(p), "`{p}` missing from: {err}");
    }
}

#[test]
fn error_falls_as_passes_grow() {
    let dir = tempfile::tempdir().unwrap();
    let reference = downsample(&read_exr(&common::reference_path("cornell-caustics")).unwrap(), 4);
    let mut errors = Vec::new();
    for passes in [1, 4, 16] {
        // Three seeds, the median error, each pixel's capped at 1 (wrong by its own brightness):
        // at 4 samples per pixel a sample that sees the light through the glass ball is a firefly
        // of 17 in a pixel whose mean is 0.19, which alone made relMSE range 0.022-0.076 over
        // seeds 1-6 at 4 passes; the cap keeps the test on convergence, not on that draw.
        let mut runs = Vec::new();
        for seed in 0..3 {
            let name = format!("p{passes}-{seed}.exr");
            ok(&render(dir.path(), &name, &["--passes", &passes.to_string(), "--seed", &seed.to_string()]));
            let image = read_exr(&dir.path().join(&name)).unwrap();
            let ratio = mean_ratio(&image, &reference);
            let capped = rel_mse_per_pixel(&image, &reference).iter().map(|e| e.min(1.0)).sum::<f64>();
            let error = capped / (image.pixels.len() as f64);
            let bias = ratio.iter().map(|r| (r - 1.0).abs()).fold(0.0, f64::max);
            println!("{passes:>2} passes, seed {seed}: relMSE {error:.5} (capped; uncapped {:.5}), mean ratio {ratio:.4?} (largest bias {:.2}%)", rel_mse(&image, &reference), 100.0 * bias);
            runs.push((error, bias));
        }
        runs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let worst_bias = runs.iter().map(|r| r.1).fold(0.0, f64::max);
        errors.push((runs[1].0, worst_bias));
    }
    // Capped medians measured 0.042, 0.012, 0.0034 (each within 5% over the three seeds): noise
    // falls as 1/passes and the radius shrinks. Each step must at least halve the error.
    assert!(errors[1].0 < 0.5 * errors[0].0, "{errors:?}");
    assert!(errors[2].0 < 0.6 * errors[1].0, "{errors:?}");
    // One pass of 20,000 photons is one draw of the photon maps, whose mean over the image moves
    // by up to 5.5% from seed to seed (seeds 0-3 measured: 0.95 to 1.067); averaged over 16
    // passes the mean is within 2% (measured 0.99).
    assert!(errors.iter().all(|(_, bias)| *bias < 0.08), "{errors:?}");
    assert!(errors[2].1 < 0.02, "{errors:?}");
}

#[test]
fn merged_halves_equal_one_run_and_reruns_are_identical() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    ok(&render(p, "full.exr", &["--passes", "4"]));
    ok(&render(p, "a.exr", &["--pass-range", "0..2"]));
    ok(&render(p, "b.exr", &["--pass-range", "2..4"]));
    ok(&common::photonix(&["merge", "b.exr", "a.exr", "-o", "merged.exr"], p));
    let (full, merged) = (read_exr(&p.join("full.exr")).unwrap(), read_exr(&p.join("merged.exr")).unwrap());
    // Same passes, summed in another order: equal to float summation.
    let error = rel_mse(&merged, &full);
    println!("merged vs one run: relMSE {error:.3e}");
    assert!(error < 1e-10, "{error}");
    // The same seed and pass range give the same bytes.
    ok(&render(p, "a2.exr", &["--pass-range", "0..2"]));
    assert!(std::fs::read(p.join("a.exr")).unwrap() == std::fs::read(p.join("a2.exr")).unwrap());
}

#[test]
fn interrupt_keeps_the_finished_passes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::repo_path("scenes/cornell-caustics.toml");
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", "out.exr", "--backend", "gpu", "--passes", "100000"];
    args.extend_from_slice(&["--checkpoint-every", "1ms"]);
    args.extend_from_slice(FAST);
    let child = Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(&args)
        .current_dir(dir.path())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The first checkpoint means at least one pass is done; then interrupt.
    let start = std::time::Instant::now();
    while !dir.path().join("out.exr").exists() {
        assert!(start.elapsed().as_secs() < 120, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    let err = ok(&out);
    println!("{err}");
    assert!(err.contains("interrupted"), "{err}");
    let image = read_exr(&dir.path().join("out.exr")).unwrap();
    assert_eq!((image.width, image.height), (64, 64));
    assert!(image.channel_means().iter().all(|m| m.is_finite() && *m > 0.0));
}

#[test]
fn bad_progressive_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    for (extra, pieces) in [
        (vec!["--pass-range", "5..2"], vec!["5..2", "A < B"]),
        (vec!["--pass-range", "a..b"], vec!["a..b"]),
        (vec!["--time", "0s"], vec!["positive duration"]),
        (vec!["--time", "-5s"], vec!["positive duration"]),
        (vec!["--target-error", "-1"], vec!["--target-error"]),
        (vec!["--passes", "0"], vec!["--passes"]),
    ] {
        fails(&render(p, "x.exr", &extra), &pieces);
    }
    fails(&render(p, "x.png", &["--pass-range", "0..2"]), &["--pass-range", ".exr"]);
    assert!(!p.join("x.exr").exists() && !p.join("x.png").exists());
    // Merging: a plain image, different sizes, overlapping ranges.
    ok(&render(p, "plain.exr", &["--passes", "1"]));
    ok(&render(p, "a.exr", &["--pass-range", "0..1"]));
    ok(&render(p, "small.exr", &["--pass-range", "1..2", "--resolution", "32x32"]));
    fails(
        &common::photonix(&["merge", "a.exr", "plain.exr", "-o", "m.exr"], p),
        &["plain.exr", "not a Photonix accumulation file"],
    );
    fails(&common::photonix(&["merge", "a.exr", "small.exr", "-o", "m.exr"], p), &["32x32", "64x64"]);
    fails(&common::photonix(&["merge", "a.exr", "a.exr", "-o", "m.exr"], p), &["twice"]);
    assert!(!p.join("m.exr").exists());
}

/// A renderer kept across passes (kernels, scene buffers and accumulation made once) renders
/// the same bytes as a renderer made for each pass, and a scene replaced in place renders as a
/// renderer made for the new scene.
#[test]
fn kept_renderer_equals_a_renderer_per_pass() {
    use photonix::render::gpu::{render_gpu, GpuRenderer};
    let scene = photonix::scene::load_scene(&common::repo_path("scenes/cornell-caustics.toml")).unwrap();
    let buffers = common::buffers(&scene, 32, 32);
    let ctx = common::gpu();
    let photons = common::test_photons();
    let mut renderer = GpuRenderer::new(&ctx, &buffers, Some(&photons)).unwrap();
    for pass in 0..3 {
        let kept = renderer.render_pass(1, pass, &mut |_, _| {}).unwrap();
        let fresh = render_gpu(&ctx, &buffers, 1, Some(&photons), pass, &mut |_, _| {}).unwrap();
        assert!(kept.layers == fresh.layers, "pass {pass}: the kept renderer's image differs");
    }
    // Another seed changes only the frame constants: written in place, all 9 arrays kept.
    let mut reseeded = buffers.clone();
    reseeded.frame.seed += 1;
    assert_eq!(renderer.update_scene(&reseeded, Some(&photons)).unwrap(), 9);
    let kept = renderer.render_pass(1, 0, &mut |_, _| {}).unwrap();
    let fresh = render_gpu(&ctx, &reseeded, 1, Some(&photons), 0, &mut |_, _| {}).unwrap();
    assert!(kept.layers == fresh.layers, "the updated scene renders differently from a fresh renderer");
    let before = render_gpu(&ctx, &buffers, 1, Some(&photons), 0, &mut |_, _| {}).unwrap();
    assert!(kept.layers != before.layers, "the new seed was not used");
}

/// A scene of another kernel variant and back (an edit and its undo in the editor): the
/// renderer keeps the first variant's kernels, switches back to them, and renders as a fresh
/// renderer would.
#[test]
fn switching_variants_keeps_the_earlier_kernels() {
    use photonix::render::gpu::{render_gpu, GpuRenderer};
    let path = common::repo_path("scenes/cornell-caustics.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let plain = photonix::scene::parse_scene(&text, &path).unwrap();
    let disc = "\n[[shapes]]\ntype = \"disc\"\nmaterial = \"white\"\ncenter = [0.5, 0.01, 0.5]\nnormal = [0, 1, 0]\nradius = 0.05\n";
    let analytic = photonix::scene::parse_scene(&format!("{text}{disc}"), &path).unwrap();
    let (a, b) = (common::buffers(&plain, 16, 16), common::buffers(&analytic, 16, 16));
    assert_ne!(a.variant(), b.variant(), "a disc needs the analytic kernels");
    let ctx = common::gpu();
    let photons = common::test_photons();
    let mut renderer = GpuRenderer::new(&ctx, &a, Some(&photons)).unwrap();
    assert_eq!(renderer.kernel_variants(), [a.variant()]);
    renderer.update_scene(&b, Some(&photons)).unwrap();
    assert_eq!(renderer.kernel_variants(), [b.variant(), a.variant()]);
    renderer.update_scene(&a, Some(&photons)).unwrap();
    assert_eq!(renderer.kernel_variants(), [a.variant(), b.variant()]);
    let kept = renderer.render_pass(1, 0, &mut |_, _| {}).unwrap();
    let fresh = render_gpu(&ctx, &a, 1, Some(&photons), 0, &mut |_, _| {}).unwrap();
    assert!(kept.layers == fresh.layers, "the kept kernels render differently from fresh ones");
}
