//! Both backends against the independent path-traced references in ../shared/reference, read
//! at test time. Renders are 64x64; the 256x256 reference is box-filtered down by 4, which is
//! exactly the 64x64 box-filtered image.

mod common;

use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::read_exr;
use photonix::io::Image;
use photonix::render::PhotonSettings;
use photonix::scene::load_scene;

const SIZE: u32 = 64;
const SPP: u32 = 16;

fn settings() -> PhotonSettings {
    PhotonSettings { photons: 100_000, caustic_photons: 100_000, gather_rays: 8, ..PhotonSettings::default() }
}

fn check(name: &str, max_rel_mse: f64) {
    let scene = load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).unwrap();
    let reference =
        downsample(&read_exr(&common::reference_path(name)).expect("shared reference is readable"), 256 / SIZE);
    let buffers = common::buffers(&scene, SIZE, SIZE);
    let ctx = common::gpu();
    for (backend, image) in [
        ("cpu", common::cpu_render(&buffers, SPP, &settings()).image),
        ("gpu", common::gpu_render(&ctx, &buffers, SPP, &settings()).image),
    ] {
        let error = rel_mse(&image, &reference);
        let ratio = mean_ratio(&image, &reference);
        println!("{name} {backend}: relMSE {error:.5}, mean ratio {ratio:.4?}");
        for r in ratio {
            assert!((r - 1.0).abs() < 0.03, "{name} {backend}: mean ratio {ratio:?}");
        }
        assert!(error < max_rel_mse, "{name} {backend}: relMSE {error}");
    }
}

#[test]
fn cornell_box_matches_reference() {
    check("cornell-box", 0.01);
}

#[test]
fn cornell_caustics_matches_reference() {
    check("cornell-caustics", 0.02);
}

/// The mean over pixels at the reference's edges (a neighbour's brightness differs by more than
/// a tenth; the light and its neighbours left out) of `image` over that of `reference`: the
/// edges where the room's surfaces end against the black outside (a neighbour is black) when
/// `open`, the others when not.
fn edge_ratio(image: &Image, reference: &Image, open: bool) -> f64 {
    let lum = |img: &Image, x: u32, y: u32| {
        let p = img.pixels[(y * img.width + x) as usize];
        (p[0] + p[1] + p[2]) as f64 / 3.0
    };
    let (mut sum, mut sum_ref, mut count) = (0.0, 0.0, 0);
    for y in 1..reference.height - 1 {
        for x in 1..reference.width - 1 {
            let r = lum(reference, x, y);
            let near = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)].map(|(nx, ny)| lum(reference, nx, ny));
            if r <= 0.0 || r > 1.0 || near.iter().any(|&n| n > 1.0) {
                continue;
            }
            if near.iter().any(|&n| (n - r).abs() > 0.1 * r) && near.contains(&0.0) == open {
                sum += lum(image, x, y);
                sum_ref += r;
                count += 1;
            }
        }
    }
    assert!(count > 60, "{count} edge pixels");
    sum / sum_ref
}

/// Reading the global map at the visible point (the shipped `gather_rays = 0`), a lookup's disc
/// near an edge reaches past the surface; the edge probes give the estimate the kernel's share
/// that lies on it, so the room's corners and the blocks' edges are not drawn darker. One pass
/// with a radius of 20 mm (two pixels: a wide band of edge bias), both twins.
#[test]
fn ppm_estimates_at_edges_are_not_darkened() {
    let scene = load_scene(&common::repo_path("scenes/cornell-box.toml")).unwrap();
    let reference = downsample(
        &read_exr(&common::reference_path("cornell-box")).expect("shared reference is readable"),
        256 / SIZE,
    );
    let buffers = common::buffers(&scene, SIZE, SIZE);
    let photons = PhotonSettings {
        photons: 200_000,
        caustic_photons: 1,
        radius: Some(20.0),
        gather_rays: 0,
        ..PhotonSettings::default()
    };
    let ctx = common::gpu();
    let cpu = common::cpu_render(&buffers, 32, &photons).image;
    let gpu = common::gpu_render(&ctx, &buffers, 32, &photons).image;
    let twins = rel_mse(&gpu, &cpu);
    let (ratio_cpu, ratio_gpu) = (edge_ratio(&cpu, &reference, false), edge_ratio(&gpu, &reference, false));
    let (open_cpu, open_gpu) = (edge_ratio(&cpu, &reference, true), edge_ratio(&gpu, &reference, true));
    println!("edges: cpu {ratio_cpu:.4}, gpu {ratio_gpu:.4}; open edges: cpu {open_cpu:.4}, gpu {open_gpu:.4}; twins relMSE {twins:.3e}");
    assert!(twins < 1e-6, "GPU and CPU differ: relMSE {twins:.3e}");
    // Measured 0.9965 with the probes and 0.9813 without (lavapipe and the CPU twin alike); the
    // open edges 1.0033 with their flags (`render/open_edges.rs`) and 0.9238 without.
    assert!((ratio_cpu - 1.0).abs() < 0.008, "edge pixels at {ratio_cpu:.4} of the reference");
    assert!((open_cpu - 1.0).abs() < 0.02, "open edges' pixels at {open_cpu:.4} of the reference");
}
