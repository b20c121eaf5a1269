//! Scene arrays larger than one texel view are split into pages (src/render/gpu/scene.rs,
//! shaders/scene_fetch.glsl). A scene that needs several pages on lavapipe would take hundreds
//! of MiB and minutes, so this test lowers the page size (`PHOTONIX_GPU_PAGE_BYTES`) until small
//! scenes span several pages per array (cornell-glossy: its image texture over 5 pages; cornell-box:
//! its primitives over 8, its BVH and lights over several), and checks that paging changes no
//! bit of the image, and that GPU = CPU.
//!
//! One test in its own binary: the page size is read from the environment, which the
//! process shares.

mod common;

use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::layout::constants::SCENE_PAGES;
use photonix::render::gpu::{DeviceScene, PAGE_BYTES_VAR};
use photonix::render::photons::PhotonSettings;
use photonix::render::SceneBuffers;
use photonix::scene::{load_scene, Integrator};

const SIZE: u32 = 24;

fn scene_buffers(name: &str, integrator: Integrator) -> SceneBuffers {
    let mut scene = load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).expect("shipped scene loads");
    scene.render.integrator = integrator;
    common::buffers(&scene, SIZE, SIZE)
}

/// The largest array's bytes over SCENE_PAGES, rounded up to a power of two: the largest
/// arrays then take between SCENE_PAGES / 2 and SCENE_PAGES pages.
fn tiny_page(buffers: &SceneBuffers) -> u64 {
    let largest = [
        size_of_val(buffers.nodes.as_slice()),
        size_of_val(buffers.primitives.as_slice()),
        size_of_val(buffers.lights.as_slice()),
        size_of_val(buffers.texture_data.as_slice()),
        size_of_val(buffers.shape_data.as_slice()),
    ]
    .into_iter()
    .max()
    .unwrap() as u64;
    largest.div_ceil(SCENE_PAGES as u64).next_power_of_two().max(16)
}

#[test]
fn a_scene_split_into_pages_renders_the_same_bytes_and_matches_the_cpu() {
    let ctx = common::gpu();
    let photons = PhotonSettings { photons: 4000, caustic_photons: 4000, gather_rays: 1, ..PhotonSettings::default() };
    let runs =
        [("cornell-glossy", Integrator::Pt), ("cornell-glossy", Integrator::Vcm), ("cornell-box", Integrator::Ppm)];
    for (name, integrator) in runs {
        let buffers = scene_buffers(name, integrator);
        let render = || {
            photonix::render::gpu::render_gpu(&ctx, &buffers, 1, Some(&photons), 0, &mut |_, _| {})
                .expect("gpu render succeeds")
        };
        std::env::remove_var(PAGE_BYTES_VAR);
        let whole = render();
        let page = tiny_page(&buffers);
        std::env::set_var(PAGE_BYTES_VAR, page.to_string());
        let device = DeviceScene::upload(&ctx, &buffers, Some(&photons)).expect("the pages fit");
        let arrays = [&device.nodes, &device.primitives, &device.lights, &device.texture_data, &device.shape_data];
        let pages: Vec<u32> = arrays.iter().map(|a| a.page_count()).collect();
        println!(
            "{name} {integrator:?}: pages of {page} bytes: nodes, primitives, lights, texture data, shape data {pages:?}; kernels for {} pages",
            device.variant.pages
        );
        assert!(device.variant.pages > SCENE_PAGES / 2, "the largest array spans more than half the pages");
        drop(device);
        let paged = render();
        std::env::remove_var(PAGE_BYTES_VAR);
        // The same texels through other views: the same bytes.
        assert!(paged.layers == whole.layers, "{name} {integrator:?}: paging changed the image");

        let cpu = photonix::render::render_cpu(&buffers, 1, Some(&photons), 0, &mut |_, _| {});
        let error = rel_mse(&paged.image, &cpu.image);
        let ratio = mean_ratio(&paged.image, &cpu.image);
        println!("{name} {integrator:?}: paged GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}");
        // As tests/gpu_vs_cpu.rs for textured scenes: only rounding flips of discrete choices.
        assert!(error < 1e-5, "{name} {integrator:?}: relMSE {error:.3e}");
        for r in ratio {
            assert!((r - 1.0).abs() < 1e-3, "{name} {integrator:?}: mean ratio {ratio:?}");
        }
    }
}

#[test]
fn a_bad_page_size_is_refused_with_the_variable_named() {
    // The parser alone: the environment belongs to the test above.
    let message = photonix::render::gpu::PageSize::parse_override("1000").unwrap_err().to_string();
    assert!(message.contains(PAGE_BYTES_VAR) && message.contains("power of two"), "{message}");
    assert_eq!(photonix::render::gpu::PageSize::parse_override("4096").unwrap(), 4096);
}

#[test]
fn a_scene_larger_than_one_binding_is_refused_only_beyond_the_device_memory() {
    use photonix::render::memory::{check_fits, estimate, scene_part};
    // cornell-glossy's arrays, then 300 MiB of them: more than lavapipe's 128 MiB binding, less
    // than its 2 GiB of memory.
    let buffers = scene_buffers("cornell-glossy", Integrator::Pt);
    let (what, host, device) = scene_part(&buffers);
    assert_eq!((what, host), ("scene", 0));
    assert!(device > size_of_val(buffers.primitives.as_slice()) as u64, "{device}");
    let mut e = estimate(64, 64, None, Some(128 << 20));
    let image = e.device();
    e.parts.push(("scene", 0, 300 << 20));
    assert_eq!(e.device(), image + (300 << 20));
    assert!(check_fits(&e, 64, 64, None, None, Some(2 << 30)).is_ok());
    let message = check_fits(&e, 64, 64, None, None, Some(256 << 20)).unwrap_err().to_string();
    assert!(message.contains("scene 300.0 MiB"), "{message}");
    assert!(message.contains("the device has 256.0 MiB"), "{message}");
}
