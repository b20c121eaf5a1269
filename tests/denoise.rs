//! Feature layers and denoising (docs/denoising.md): the layers GPU = CPU, the image the same
//! bits with or without them, a denoised furnace keeping its mean, and the library's lookup
//! (missing: a clear error; not asked for: not needed). The tests that denoise find Open Image
//! Denoise as the binary does (ci/setup installs it into target/oidn).

mod common;

use photonix::gpu::oidn::Denoiser;
use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::render::denoise::denoise_image;
use photonix::render::{render_features_cpu, Features, Renderer};
use photonix::scene::load_scene;

fn shipped(name: &str) -> photonix::scene::Scene {
    load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).expect("shipped scene loads")
}

fn assert_features_agree(label: &str, gpu: &Features, cpu: &Features) {
    for ((name, g), (_, c)) in gpu.named().into_iter().zip(cpu.named()) {
        // Sums of the same samples: they differ where rounding flips a discrete choice (a
        // glass's Fresnel pick, a hit on an edge), and then in a few pixels only.
        let error = rel_mse(g, c);
        let worst =
            g.pixels.iter().zip(&c.pixels).map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max));
        let differing = worst.filter(|d| *d > 1e-3).count();
        println!("{label} {name}: GPU vs CPU relMSE {error:.3e}, {differing} pixels differ by more than 1e-3");
        assert!(error < 1e-4, "{label} {name}: relMSE {error:.3e}");
        assert!(differing * 100 <= g.pixels.len(), "{label} {name}: {differing} pixels differ");
    }
}

#[test]
fn feature_layers_match_on_both_twins() {
    let ctx = common::gpu();
    // The plain box (diffuse), the caustics box (a mirror sphere and a glass one: the layers are
    // those of what is seen through them), and the glossy box (rough conductors).
    for name in ["cornell-box", "cornell-caustics", "cornell-glossy"] {
        let scene = shipped(name);
        let buffers = common::buffers(&scene, 24, 24);
        let mut gpu = photonix::render::gpu::GpuRenderer::new(&ctx, &buffers, None).unwrap();
        let g = gpu.render_features(2, 3, 2).unwrap().expect("not stopped");
        let c = render_features_cpu(&buffers, None, 2, 3, 2).expect("not stopped");
        assert_features_agree(name, &g, &c);
        // Albedo in [0, 1], normals of unit length or less (means of unit vectors), depth > 0
        // where the camera sees the box.
        assert!(c.albedo.pixels.iter().flatten().all(|v| (0.0..=1.0).contains(v)), "{name}: albedo out of [0, 1]");
        let longest =
            c.normal.pixels.iter().map(|n| (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()).fold(0.0, f32::max);
        assert!(longest <= 1.0 + 1e-4 && longest > 0.9, "{name}: longest normal {longest}");
        assert!(c.depth.pixels.iter().all(|d| d[0] > 0.0), "{name}: a pixel with no depth");
    }
}

#[test]
fn features_see_the_wall_colour_through_a_mirror() {
    // Pixels on cornell-caustics' mirror sphere take the albedo of what it reflects, never the
    // mirror's own (OIDN's convention): some are red or green, from the side walls.
    let scene = shipped("cornell-caustics");
    let buffers = common::buffers(&scene, 48, 48);
    let f = render_features_cpu(&buffers, None, 4, 0, 1).unwrap();
    let tinted = f.albedo.pixels.iter().filter(|a| a[0] > 2.0 * a[1] || a[1] > 2.0 * a[0]).count();
    let walls = f.albedo.pixels.len() / 4;
    println!("{tinted} tinted pixels of {}", f.albedo.pixels.len());
    // The side walls alone cover about a quarter of the image; the mirror adds some more.
    assert!(tinted > walls / 2, "{tinted} red or green pixels");
}

#[test]
fn feature_layers_leave_the_image_unchanged() {
    let scene = shipped("cornell-box");
    let buffers = common::buffers(&scene, 20, 20);
    let photons = common::test_photons();
    let mut plain = Renderer::new(None, &buffers, Some(&photons)).unwrap();
    let mut with = Renderer::new(None, &buffers, Some(&photons)).unwrap();
    with.set_features(true);
    let a = plain.render_passes(2, 1, 1, &mut |_, _| {}).unwrap();
    let b = with.render_passes(2, 1, 1, &mut |_, _| {}).unwrap();
    assert!(a.features.is_none() && b.features.is_some());
    assert_eq!(a.layers, b.layers, "the image changed with the feature layers on");
}

#[test]
fn denoised_furnace_keeps_its_mean() {
    // The white furnace (tests/common: L = 2 everywhere), path traced with 4 samples: noisy, and
    // its denoised image must keep the mean within 0.5% and come closer to 2 than the raw one.
    let mut scene = common::furnace();
    scene.camera.width = 64;
    scene.camera.height = 64;
    let buffers = common::buffers(&scene, 64, 64);
    let mut renderer = Renderer::new(None, &buffers, None).unwrap();
    renderer.set_features(true);
    let out = renderer.render_passes(4, 0, 1, &mut |_, _| {}).unwrap();
    let mut denoiser = Denoiser::open(false).expect("Open Image Denoise (ci/setup installs it into target/oidn)");
    let denoised = denoise_image(&mut denoiser, &out.image, out.features.as_ref()).unwrap();
    let ratio = mean_ratio(&denoised, &out.image);
    let flat = photonix::io::Image { pixels: vec![[2.0; 3]; out.image.pixels.len()], ..out.image.clone() };
    let (raw_error, denoised_error) = (rel_mse(&out.image, &flat), rel_mse(&denoised, &flat));
    println!("denoised/raw mean {ratio:?}; relMSE against L = 2: raw {raw_error:.3e}, denoised {denoised_error:.3e}");
    for r in ratio {
        assert!((r - 1.0).abs() < 0.005, "denoised mean off by {r}");
    }
    assert!(denoised_error < raw_error / 4.0, "denoising left relMSE {denoised_error:.3e} of {raw_error:.3e}");
}

/// A folder with no library in it, for PHOTONIX_OIDN.
fn empty_lookup() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn photonix_with_lookup(args: &[&str], dir: &std::path::Path, lookup: &std::path::Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(args)
        .current_dir(dir)
        .env("PHOTONIX_OIDN", lookup)
        .output()
        .expect("the photonix binary runs")
}

#[test]
fn a_missing_library_names_what_to_install() {
    let scene = common::repo_path("scenes/cornell-box.toml");
    let dir = tempfile::tempdir().unwrap();
    let lookup = empty_lookup();
    let args = ["render", scene.to_str().unwrap(), "--backend", "cpu", "--resolution", "8x8", "--passes", "1"];
    let out = photonix_with_lookup(&[&args[..], &["--denoise", "-o", "x.png"]].concat(), dir.path(), lookup.path());
    let err = common::stderr(&out);
    assert!(!out.status.success(), "a render with --denoise and no library succeeded");
    assert!(err.contains("Open Image Denoise") && err.contains("pip install pyoidn"), "{err}");
    assert!(err.contains(&lookup.path().display().to_string()), "the error does not say where it looked: {err}");
    assert!(!dir.path().join("x.png").exists(), "an image was written");
    // Without --denoise no library is needed.
    let out = photonix_with_lookup(&[&args[..], &["-o", "y.png"]].concat(), dir.path(), lookup.path());
    assert!(out.status.success(), "{}", common::stderr(&out));
    assert!(dir.path().join("y.png").exists());
}

#[test]
fn pass_ranges_carry_the_feature_layers_to_a_denoised_merge() {
    let scene = common::repo_path("scenes/cornell-box.toml");
    let dir = tempfile::tempdir().unwrap();
    let s = scene.to_str().unwrap();
    let base =
        ["render", s, "--backend", "cpu", "--resolution", "16x16", "--photons", "2000", "--caustic-photons", "2000"];
    for (range, out) in [("0..1", "a.exr"), ("1..2", "b.exr")] {
        let o = common::photonix(&[&base[..], &["--pass-range", range, "--denoise", "-o", out]].concat(), dir.path());
        assert!(o.status.success(), "{}", common::stderr(&o));
    }
    let whole = common::photonix(&[&base[..], &["--passes", "2", "--layers", "-o", "whole.exr"]].concat(), dir.path());
    assert!(whole.status.success(), "{}", common::stderr(&whole));
    // The merged sums' feature layers are the whole render's (CPU backend: the same bits).
    let o = common::photonix(&["merge", "a.exr", "b.exr", "--accumulation", "-o", "ab.exr"], dir.path());
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (merged, _) = photonix::render::accumulation::read_accumulation(&dir.path().join("ab.exr")).unwrap();
    let merged = merged.mean_features().expect("the merge kept the feature layers");
    let layers = exr::prelude::read_all_flat_layers_from_file(dir.path().join("whole.exr")).unwrap();
    for (name, image) in merged.named() {
        let layer = layers.layer_data.iter().find(|l| l.attributes.layer_name.as_ref().is_some_and(|n| n.eq(name)));
        let red: Vec<f32> = layer
            .expect(name)
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq("R"))
            .unwrap()
            .sample_data
            .values_as_f32()
            .collect();
        let ours: Vec<f32> = image.pixels.iter().map(|p| p[0]).collect();
        assert_eq!(ours, red, "layer {name} of the merge differs from the whole render's");
    }
    let o = common::photonix(&["merge", "a.exr", "b.exr", "--denoise", "-o", "merged.png"], dir.path());
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(common::stderr(&o).contains("denoised in"), "{}", common::stderr(&o));
}
