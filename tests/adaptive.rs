//! Adaptive sampling (`render::adaptive`): a pass of a pixel list renders those pixels on both
//! twins, sample for sample as a full pass does, and nothing else; the progressive driver
//! chooses lists deterministically, keeps every pixel's error falling, and its sums survive an
//! accumulation file and a merge.

mod common;

use std::sync::Arc;

use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::render::adaptive::{PixelList, UNIFORM_EVERY, WARMUP_PASSES};
use photonix::render::progressive::{render_progressive, Accumulator, Budget};
use photonix::render::{PhotonSettings, RenderOutput, Renderer, SceneBuffers};
use photonix::scene::{load_scene, Integrator};

const W: u32 = 32;
const H: u32 = 24;

fn box_buffers(integrator: Integrator) -> SceneBuffers {
    let mut scene = load_scene(&common::repo_path("scenes/cornell-box.toml")).expect("shipped scene loads");
    scene.render.integrator = integrator;
    common::buffers(&scene, W, H)
}

/// Every third pixel and a block in the middle: pixels in every band, runs and gaps.
fn some_pixels() -> Arc<PixelList> {
    let pixels = (0..W * H).filter(|p| p % 3 == 0 || (p / W > 8 && p / W < 14 && p % W > 10 && p % W < 20)).collect();
    Arc::new(PixelList { width: W, height: H, pixels })
}

fn pass(renderer: &mut Renderer, pixels: Option<Arc<PixelList>>) -> RenderOutput {
    renderer.set_pixels(pixels);
    renderer.render_passes(1, 3, 1, &mut |_, _| {}).expect("pass renders")
}

/// A listed pass renders the listed pixels as the full pass does and leaves the others black,
/// on the CPU twin and on the kernels (lavapipe), for each camera kernel: the photon mapper's,
/// the path tracer's and the bidirectional one's.
#[test]
fn a_listed_pass_renders_its_pixels_alike_on_both_twins() {
    let ctx = common::gpu();
    let photons = PhotonSettings { photons: 4000, caustic_photons: 4000, gather_rays: 1, ..PhotonSettings::default() };
    let list = some_pixels();
    let listed = |p: usize| list.pixels.binary_search(&(p as u32)).is_ok();
    for integrator in [Integrator::Ppm, Integrator::Pt, Integrator::Vcm] {
        let buffers = box_buffers(integrator);
        let mut cpu = Renderer::new(None, &buffers, Some(&photons)).unwrap();
        let mut gpu = Renderer::new(Some(&ctx), &buffers, Some(&photons)).unwrap();
        let full = pass(&mut cpu, None);
        let cpu_listed = pass(&mut cpu, Some(list.clone()));
        let gpu_listed = pass(&mut gpu, Some(list.clone()));
        assert_eq!(cpu_listed.pixels.as_deref(), Some(&*list), "{integrator:?}: the output names its pixels");
        for (p, (listed_value, full_value)) in cpu_listed.image.pixels.iter().zip(&full.image.pixels).enumerate() {
            if listed(p) {
                assert_eq!(listed_value, full_value, "{integrator:?}: pixel {p} differs from the full pass");
            } else {
                assert_eq!(*listed_value, [0.0; 3], "{integrator:?}: pixel {p} is not listed but was rendered");
            }
        }
        let error = rel_mse(&gpu_listed.image, &cpu_listed.image);
        let ratio = mean_ratio(&gpu_listed.image, &cpu_listed.image);
        println!("{integrator:?}: GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}");
        assert!(error < 1e-6, "{integrator:?}: relMSE {error:.3e}");
        let unlisted_lit = gpu_listed.image.pixels.iter().enumerate().filter(|&(p, v)| !listed(p) && *v != [0.0; 3]);
        assert_eq!(unlisted_lit.count(), 0, "{integrator:?}: the kernels rendered pixels outside the list");
    }
}

/// `passes` adaptive passes of the path-traced box on the CPU backend.
fn adaptive_render(passes: u32) -> (Accumulator, Vec<Option<usize>>) {
    let buffers = box_buffers(Integrator::Pt);
    let mut renderer = Renderer::new(None, &buffers, None).unwrap();
    let budget = Budget { first: 0, end: passes, time: None, target_error: None, adaptive: true };
    let mut lists = Vec::new();
    let (acc, _) = render_progressive(
        W,
        H,
        &budget,
        1,
        |first, most, pixels| {
            lists.push(pixels.map(|l| l.pixels.len()));
            renderer.set_pixels(pixels.cloned());
            renderer.render_passes(1, first, most, &mut |_, _| {})
        },
        |_, _| Ok(()),
    )
    .unwrap();
    (acc, lists)
}

/// After the warm-up the driver leaves pixels out of passes, but every `UNIFORM_EVERY`th pass
/// renders them all, so each pixel keeps a share of the passes; the choices depend only on the
/// sums, so a rerun writes the same image; the image's mean stays the uniform render's.
#[test]
fn adaptive_passes_leave_pixels_out_deterministically() {
    let passes = 48;
    let (acc, lists) = adaptive_render(passes);
    assert!(lists[..WARMUP_PASSES as usize].iter().all(Option::is_none), "the warm-up renders every pixel: {lists:?}");
    for (pass, list) in lists.iter().enumerate() {
        if pass as u32 % UNIFORM_EVERY == UNIFORM_EVERY - 1 {
            assert!(list.is_none(), "pass {pass} is a uniform one: {lists:?}");
        }
    }
    let adaptive = lists.iter().filter(|l| l.is_some()).count();
    assert!(adaptive > 0, "no pass was adaptive: {lists:?}");
    assert!(!acc.uniform());
    let least = *acc.counts.iter().min().unwrap();
    let most = *acc.counts.iter().max().unwrap();
    assert!(least >= WARMUP_PASSES + (passes - WARMUP_PASSES) / UNIFORM_EVERY, "a pixel got {least} passes");
    assert!(most > least, "counts {least}..{most}");
    let (again, _) = adaptive_render(passes);
    assert_eq!(again.mean(), acc.mean(), "a rerun chose other pixels");

    // The mean: an adaptive render against a uniform one of as many passes.
    let buffers = box_buffers(Integrator::Pt);
    let mut renderer = Renderer::new(None, &buffers, None).unwrap();
    let mut uniform = Accumulator::new(W, H);
    for pass in 0..passes {
        uniform.add(pass, &renderer.render_passes(1, pass, 1, &mut |_, _| {}).unwrap());
    }
    let ratio = mean_ratio(&acc.mean().combined(), &uniform.mean().combined());
    println!("adaptive over uniform mean: {ratio:.4?}");
    for r in ratio {
        assert!((r - 1.0).abs() < 0.03, "mean ratio {ratio:?}");
    }
}

/// An adaptive render's accumulation file keeps each pixel's pass count (layer `samples`), so it
/// reads back as the same image, and a merge adds the counts of its parts.
#[test]
fn accumulation_files_keep_each_pixel_s_passes() {
    use photonix::render::accumulation::{merge, read_accumulation, write_accumulation, Provenance};
    let buffers = box_buffers(Integrator::Pt);
    let provenance = Provenance::new(&buffers, 1, None);
    let dir = tempfile::tempdir().unwrap();
    let (acc, _) = adaptive_render(24);
    let path = dir.path().join("a.exr");
    write_accumulation(&path, &acc, &provenance).unwrap();
    let (back, _) = read_accumulation(&path).unwrap();
    assert_eq!(back.counts, acc.counts);
    assert_eq!(back.mean(), acc.mean());

    // A uniform part of passes 24..26 merged in: every pixel's count grows by two.
    let mut renderer = Renderer::new(None, &buffers, None).unwrap();
    let mut part = Accumulator::new(W, H);
    for pass in 24..26 {
        part.add(pass, &renderer.render_passes(1, pass, 1, &mut |_, _| {}).unwrap());
    }
    let part_path = dir.path().join("b.exr");
    write_accumulation(&part_path, &part, &provenance).unwrap();
    let (merged, _) = merge(&[path, part_path]).unwrap();
    let expected: Vec<u32> = acc.counts.iter().map(|c| c + 2).collect();
    assert_eq!(merged.counts, expected);
    assert_eq!(merged.passes, 26);

    // A count layer that holds no pass count is refused as damaged.
    let mut bad = back.clone();
    bad.counts[5] = 1000;
    let bad_path = dir.path().join("bad.exr");
    write_accumulation(&bad_path, &bad, &provenance).unwrap();
    let e = read_accumulation(&bad_path).unwrap_err().to_string();
    assert!(e.contains("damaged") && e.contains("samples"), "{e}");
}

/// `[render] adaptive = true` asks for it as `--adaptive` does (the command line and Python read
/// `Scene::render.adaptive`); it is off by default.
#[test]
fn the_scene_file_asks_for_adaptive_sampling() {
    use photonix::scene::parse_scene;
    let path = common::repo_path("scenes/cornell-box.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!parse_scene(&text, &path).unwrap().render.adaptive);
    let asked = text.replacen("[render]", "[render]\nadaptive = true", 1);
    assert!(parse_scene(&asked, &path).unwrap().render.adaptive);
    let wrong = text.replacen("[render]", "[render]\nadaptive = 1", 1);
    let e = parse_scene(&wrong, &path).unwrap_err().to_string();
    assert!(e.contains("adaptive") && e.contains("boolean"), "{e}");
}
