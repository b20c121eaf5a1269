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
    // The image of the finished passes is written, but the render was not all that was asked:
    // it fails with EX_TEMPFAIL (75), so a scheduler retries it.
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    println!("{err}");
    assert_eq!(out.status.code(), Some(75), "{err}");
    assert!(err.contains("interrupted") && err.contains("not all that were asked"), "{err}");
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

/// Several passes rendered into one accumulation on the device (what a real GPU does to save
/// a readback per pass) are the mean of the same passes rendered one by one, to float rounding,
/// for the photon mapper and for vcm; the output says how many passes it holds.
#[test]
fn a_group_of_passes_is_the_mean_of_its_passes() {
    use photonix::render::gpu::GpuRenderer;
    use photonix::render::{Layers, RenderOutput};
    let ctx = common::gpu();
    let photons = common::test_photons();
    use photonix::scene::Integrator;
    for (name, integrator) in [("cornell-caustics", Integrator::Ppm), ("cornell-glossy", Integrator::Vcm)] {
        let mut scene = photonix::scene::load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).unwrap();
        scene.render.integrator = integrator;
        let buffers = common::buffers(&scene, 24, 16);
        let mut renderer = GpuRenderer::new(&ctx, &buffers, Some(&photons)).unwrap();
        let (first, passes) = (5, 3);
        let group: RenderOutput = renderer.render_passes(1, first, passes, None, &mut |_, _| {}).unwrap();
        assert_eq!(group.passes, passes, "{name}");
        assert!(group.complete);
        let mut mean = Layers::new(24, 16);
        for pass in first..first + passes {
            let one = renderer.render_pass(1, pass, &mut |_, _| {}).unwrap();
            assert_eq!(one.passes, 1);
            for ((_, m), (_, o)) in mean.named_mut().into_iter().zip(one.layers.named()) {
                for (a, b) in m.pixels.iter_mut().zip(&o.pixels) {
                    for c in 0..3 {
                        a[c] += b[c] / passes as f32;
                    }
                }
            }
        }
        let error = rel_mse(&group.image, &mean.combined());
        println!("{name} ({integrator:?}): group of {passes} against the mean of its passes: relMSE {error:.3e}");
        assert!(error < 1e-10, "{name}: {error}");
        // Not the same as one pass: the group really holds three.
        let one = renderer.render_pass(1, first, &mut |_, _| {}).unwrap();
        assert!(rel_mse(&group.image, &one.image) > 1e-6, "{name}");
    }
}

/// The progressive driver asks for 1, 2, 4, ... passes up to the group limit, whatever the
/// timing (so reruns group alike), sums outputs by the passes they hold, and splits the error
/// estimate's halves by passes when outputs hold different counts.
#[test]
fn the_driver_doubles_groups_up_to_the_limit() {
    use photonix::render::progressive::{render_progressive, Budget, StopReason};
    use photonix::render::{Layers, RenderOutput, RenderStats};
    let budget = Budget { first: 3, end: 40, time: None, target_error: None, adaptive: false };
    let mut asked = Vec::new();
    let constant = |value: f32, passes: u32| {
        let mut layers = Layers::new(2, 2);
        layers.direct.pixels.iter_mut().for_each(|p| *p = [value; 3]);
        RenderOutput {
            image: layers.combined(),
            layers,
            features: None,
            stats: RenderStats::default(),
            complete: true,
            passes,
            pixels: None,
        }
    };
    let (acc, reason) = render_progressive(
        2,
        2,
        &budget,
        8,
        |first, most, _| {
            asked.push((first, most));
            Ok::<_, ()>(constant(first as f32, most))
        },
        |_, _| Ok(()),
    )
    .unwrap();
    assert_eq!(reason, StopReason::Passes);
    assert_eq!(asked, [(3, 1), (4, 2), (6, 4), (10, 8), (18, 8), (26, 8), (34, 6)]);
    assert_eq!((acc.passes, acc.ranges.clone()), (37, vec![(3, 40)]));
    // The mean weighs each output by its passes: sum of first * passes over 37 passes.
    let expected: f32 = asked.iter().map(|&(f, n)| f as f32 * n as f32).sum::<f32>() / 37.0;
    assert!((acc.mean().direct.pixels[0][0] - expected).abs() < 1e-4);
    // A renderer that renders fewer than asked (one at a time) is followed pass by pass.
    let mut firsts = Vec::new();
    let budget = Budget { first: 0, end: 5, time: None, target_error: None, adaptive: false };
    let (acc, _) = render_progressive(
        2,
        2,
        &budget,
        64,
        |first, _, _| {
            firsts.push(first);
            Ok::<_, ()>(constant(1.0, 1))
        },
        |_, _| Ok(()),
    )
    .unwrap();
    assert_eq!((firsts, acc.passes), (vec![0, 1, 2, 3, 4], 5));
}

/// The error estimate with halves of different pass counts: two outputs of constant images a
/// and b holding n_a and n_b passes give relMSE(a, b) n_a n_b / (n_a + n_b)^2.
#[test]
fn the_error_estimate_weighs_unequal_halves() {
    use photonix::render::progressive::Accumulator;
    use photonix::render::{Layers, RenderOutput, RenderStats};
    let output = |value: f32, passes: u32| {
        let mut layers = Layers::new(2, 2);
        layers.direct.pixels.iter_mut().for_each(|p| *p = [value; 3]);
        RenderOutput {
            image: layers.combined(),
            layers,
            features: None,
            stats: RenderStats::default(),
            complete: true,
            passes,
            pixels: None,
        }
    };
    let mut acc = Accumulator::new(2, 2);
    acc.add(0, &output(1.0, 1));
    assert_eq!(acc.error_estimate(), None, "one half is empty");
    acc.add(1, &output(2.0, 3));
    // Halves: 1 pass of 1.0, 3 passes of 2.0; relMSE(1, 2) = 1 / (4 + 0.01).
    let expected = (1.0 / 4.01) * 3.0 / 16.0;
    let estimate = acc.error_estimate().unwrap();
    assert!((estimate - expected).abs() < 1e-6 * expected, "{estimate} against {expected}");
    assert_eq!(acc.ranges, [(0, 4)]);
}

/// A discrete GPU's path (staging and readback buffers, kept between copies, instead of
/// lavapipe's mapped device memory) renders the same bytes, for groups of passes too.
#[test]
fn the_staging_path_renders_the_same() {
    use photonix::render::gpu::GpuRenderer;
    use photonix::scene::Integrator;
    let photons = common::test_photons();
    for (name, integrator) in [("cornell-caustics", Integrator::Ppm), ("cornell-glossy", Integrator::Vcm)] {
        let mut scene = photonix::scene::load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).unwrap();
        scene.render.integrator = integrator;
        let buffers = common::buffers(&scene, 16, 16);
        let mut images = Vec::new();
        for staging in [false, true] {
            let ctx = common::gpu();
            ctx.set_force_staging(staging);
            let mut renderer = GpuRenderer::new(&ctx, &buffers, Some(&photons)).unwrap();
            let group = renderer.render_passes(1, 0, 2, None, &mut |_, _| {}).unwrap();
            let one = renderer.render_pass(1, 2, &mut |_, _| {}).unwrap();
            images.push((group.layers, one.layers));
        }
        assert!(images[0] == images[1], "{name}: staging changed the image");
    }
}

/// A pass range on the CPU backend, 16x16: each pass is its own group there, as on lavapipe.
fn render_range_cpu(dir: &Path, output: &str, range: &str, extra: &[&str]) -> Output {
    let scene = common::repo_path("scenes/cornell-caustics.toml");
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", output, "--backend", "cpu", "--pass-range", range];
    args.extend_from_slice(&["--resolution", "16x16"]);
    args.extend_from_slice(&FAST[2..]);
    args.extend_from_slice(extra);
    common::photonix(&args, dir)
}

/// What an interrupted `--pass-range 2..5` leaves (passes 2..3, as its part or its checkpoint),
/// continued with `--resume`, is byte for byte the uninterrupted part: the float32 sums are read
/// back exactly and the passes added in the same order.
#[test]
fn a_resumed_range_equals_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    ok(&render_range_cpu(p, "whole.exr", "2..5", &[]));
    ok(&render_range_cpu(p, "part.exr", "2..3", &[]));
    let err = ok(&render_range_cpu(p, "part.exr", "2..5", &["--resume"]));
    assert!(err.contains("resuming") && err.contains("rendering 3..5"), "{err}");
    let whole = std::fs::read(p.join("whole.exr")).unwrap();
    assert!(std::fs::read(p.join("part.exr")).unwrap() == whole, "the resumed part differs from the uninterrupted one");
    // Complete already: nothing rendered, nothing rewritten.
    let err = ok(&render_range_cpu(p, "part.exr", "2..5", &["--resume"]));
    assert!(err.contains("nothing to render"), "{err}");
    // No output yet: --resume renders the whole range.
    ok(&render_range_cpu(p, "fresh.exr", "2..5", &["--resume"]));
    assert!(std::fs::read(p.join("fresh.exr")).unwrap() == whole);
    // Refused: another render's file, a file of another range, --resume without a range.
    fails(&render_range_cpu(p, "part.exr", "2..6", &["--resume", "--seed", "9"]), &["part.exr", "seed", "--resume"]);
    fails(&render_range_cpu(p, "part.exr", "0..6", &["--resume"]), &["holds passes 2..5", "0..6"]);
    fails(&render_range_cpu(p, "part.exr", "3..6", &["--resume"]), &["holds passes 2..5", "3..6"]);
    assert!(std::fs::read(p.join("part.exr")).unwrap() == whole, "a refused resume changed the file");
    let scene = common::repo_path("scenes/cornell-caustics.toml");
    fails(
        &common::photonix(&["render", scene.to_str().unwrap(), "-o", "x.exr", "--resume"], p),
        &["--resume", "--pass-range"],
    );
}

/// A merge short of passes writes nothing and names the missing ones: a gap between parts, or,
/// with --passes N, any pass of 0..N no part holds (a farm task lost or cut short).
#[test]
fn a_merge_with_missing_passes_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    for (name, range) in [("a.exr", "0..1"), ("b.exr", "1..2"), ("c.exr", "2..3"), ("d.exr", "3..4")] {
        ok(&render_range_cpu(p, name, range, &[]));
    }
    let merge = |args: &[&str]| {
        let mut all = vec!["merge"];
        all.extend_from_slice(args);
        common::photonix(&all, p)
    };
    fails(&merge(&["a.exr", "b.exr", "d.exr", "-o", "m.exr"]), &["passes 2..3 are missing", "nothing was written"]);
    fails(&merge(&["a.exr", "b.exr", "-o", "m.exr", "--passes", "4"]), &["passes 2..4 are missing of 0..4"]);
    fails(&merge(&["b.exr", "d.exr", "-o", "m.exr", "--passes", "4"]), &["passes 0..1,2..3 are missing"]);
    fails(&merge(&["a.exr", "b.exr", "-o", "m.exr", "--passes", "1"]), &["beyond the 1 passes"]);
    assert!(!p.join("m.exr").exists());
    // Staged merges may hold gaps; the final one is checked.
    ok(&merge(&["a.exr", "d.exr", "-o", "ad.exr", "--accumulation"]));
    fails(&merge(&["ad.exr", "b.exr", "-o", "m.exr"]), &["passes 2..3 are missing"]);
    assert!(!p.join("m.exr").exists());
    let err = ok(&merge(&["ad.exr", "b.exr", "c.exr", "-o", "m.exr", "--passes", "4"]));
    assert!(err.contains("merged 4 passes"), "{err}");
}
