//! Both backends against the independent path-traced references in ../shared/reference, read
//! at test time. Renders are 64x64; the 256x256 reference is box-filtered down by 4, which is
//! exactly the 64x64 box-filtered image.

mod common;

use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::read_exr;
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
