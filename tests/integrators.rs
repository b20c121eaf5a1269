//! The integrators (`[render] integrator`): each against the shared references, an analytic
//! furnace, and the GPU kernels against their CPU twins; the four layers by path signature.

mod common;

use glam::Vec3;
use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::read_exr;
use photonix::render::{render_cpu, RenderOutput, SceneBuffers};
use photonix::scene::{load_scene, parse_scene, Integrator, Projection, Scene};

fn shipped(name: &str, integrator: Integrator) -> Scene {
    let mut scene = load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).expect("shipped scene loads");
    scene.render.integrator = integrator;
    scene
}

fn cpu(buffers: &SceneBuffers, spp: u32) -> RenderOutput {
    render_cpu(buffers, spp, None, 0, &mut |_, _| {})
}

/// One pass of `spp` samples on the kernels and on the CPU twin: (GPU, CPU).
fn both_twins(ctx: &photonix::gpu::GpuContext, buffers: &SceneBuffers, spp: u32) -> (RenderOutput, RenderOutput) {
    let gpu = photonix::render::gpu::render_gpu(ctx, buffers, spp, None, 0, &mut |_, _| {}).unwrap();
    (gpu, cpu(buffers, spp))
}

/// The path tracer's kernel against its CPU twin on scenes that take each kernel variant
/// (plain, textured, media, analytic shapes with sky, sun and spot lights): the same random
/// numbers, so the same image up to float rounding (see `common::assert_twins_agree` for the
/// tolerance).
#[test]
fn pt_gpu_matches_cpu() {
    let ctx = common::gpu();
    // outdoor: one pixel of its glass ball's rim flips a discrete choice under rounding at this
    // size (relMSE about 1e-4, the same with `ppm --no-photons`, so not the path tracer's).
    for (name, max_error) in [
        ("cornell-box", 1e-6),
        ("cornell-glossy", 1e-6),
        ("cornell-fog", 1e-6),
        ("spotlights", 1e-6),
        ("outdoor", 1e-3),
    ] {
        let scene = shipped(name, Integrator::Pt);
        let buffers = common::buffers(&scene, 32, 24);
        let (gpu, cpu) = both_twins(&ctx, &buffers, 1);
        let error = rel_mse(&gpu.image, &cpu.image);
        let ratio = mean_ratio(&gpu.image, &cpu.image);
        println!(
            "{name}: GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}, rays {} / {}",
            gpu.stats.rays, cpu.stats.rays
        );
        assert!(error < max_error, "{name}: relMSE {error:.3e}");
        for r in ratio {
            assert!((r - 1.0).abs() < 1e-3, "{name}: mean ratio {ratio:?}");
        }
    }
}

/// The path tracer against the independent references: 64x64 renders, the 256x256 reference
/// box-filtered down by 4. The means must agree within 2% (16 samples of a 64x64 image leave a
/// standard error of the mean near 0.5% on these scenes), the fog's within 5%: its light comes
/// in rare bright paths (scattering near the lamp), so few samples read low more often than
/// high (256x256 at 32 samples: within 0.4%).
#[test]
fn pt_matches_references() {
    for (name, spp, max_rel_mse, max_mean) in [
        ("cornell-box", 16, 0.02, 0.02),
        ("cornell-caustics", 16, 0.3, 0.02),
        ("cornell-glossy", 16, 0.3, 0.02),
        ("cornell-fog", 16, 0.3, 0.05),
    ] {
        let scene = shipped(name, Integrator::Pt);
        let reference = downsample(&read_exr(&common::reference_path(name)).expect("shared reference"), 4);
        let image = cpu(&common::buffers(&scene, 64, 64), spp).image;
        let error = rel_mse(&image, &reference);
        let ratio = mean_ratio(&image, &reference);
        println!("{name}: relMSE {error:.4}, mean ratio {ratio:.4?}");
        for r in ratio {
            assert!((r - 1.0).abs() < max_mean, "{name}: mean ratio {ratio:?}");
        }
        assert!(error < max_rel_mse, "{name}: relMSE {error}");
    }
}

#[test]
fn pt_furnace_is_one_over_one_minus_albedo_on_both_twins() {
    let scene = common::furnace();
    let buffers = common::buffers(&scene, 16, 16);
    let ctx = common::gpu();
    for (backend, image) in [
        ("cpu", cpu(&buffers, 64).image),
        ("gpu", photonix::render::gpu::render_gpu(&ctx, &buffers, 64, None, 0, &mut |_, _| {}).unwrap().image),
    ] {
        let n = image.pixels.len() as f64;
        let mean: f64 = image.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / n;
        let worst = image.pixels.iter().map(|p| (p[0] as f64 - 2.0).abs()).fold(0.0, f64::max);
        println!("{backend}: furnace mean {mean:.5} (expected 2), worst pixel off by {worst:.4}");
        assert!((mean - 2.0).abs() < 0.01, "{backend}: furnace mean {mean}");
        // Each pixel averages 64 paths (seen: worst 0.32): a pixel far off is a wrong weight.
        assert!(worst < 0.6, "{backend}: a pixel is off by {worst}");
    }
}

/// The four layers sum to the image, and each holds the paths of its signature: on the
/// caustics scene the glass ball's caustic (E D S+ L) lands in the caustics layer, the walls'
/// light seen once (E D L) in the direct one, what the mirror and glass show in the specular one.
#[test]
fn pt_layers_split_by_path_signature_and_sum_to_the_image() {
    let scene = shipped("cornell-caustics", Integrator::Pt);
    let out = cpu(&common::buffers(&scene, 32, 32), 8);
    let total = |img: &photonix::io::Image| img.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
    let combined = out.layers.combined();
    let (all, sum) = (total(&out.image), total(&combined));
    assert!((all - sum).abs() <= 1e-4 * all, "layers sum {sum} vs image {all}");
    let share: Vec<f64> = out.layers.named().iter().map(|(_, l)| total(l) / all).collect();
    println!("layer shares (direct, specular, indirect, caustics): {share:.4?}");
    for (i, s) in share.iter().enumerate() {
        assert!(*s > 0.005, "layer {i} holds {s} of the light");
    }
    assert!(share[0] > share[3], "direct light outweighs the caustics");
}

/// bpt's weights once turned NaN: a camera ray just below the horizon met the outdoor scene's
/// infinite ground ten million metres away at a grazing angle, its partial weight overflowed to
/// infinity, and a connection whose density underflowed to zero multiplied it (0 x inf); that
/// one sample of pass 6 made its pixel NaN for good. Zero densities now weigh nothing (`wmul`).
/// And in pass 67 of seed 12 light sampling drew a sky direction whose density reads back as 0
/// (0 / 0 in its weight); such a sample is now dropped, as pt's weight drops it.
#[test]
fn bidirectional_weights_stay_finite_at_the_horizon() {
    for (seed, pass) in [(1, 6), (12, 67)] {
        let mut scene = shipped("outdoor", Integrator::Bpt);
        scene.render.seed = seed;
        let buffers = common::buffers(&scene, 480, 270);
        let out = render_cpu(&buffers, 8, None, pass, &mut |_, _| {});
        let bad = out.image.pixels.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count();
        assert_eq!(bad, 0, "seed {seed}, pass {pass}: pixels that are not finite");
    }
}

/// Infinite lights start their light sub-paths on a disc of the scene's bounding sphere, which
/// an infinite ground plane outruns: beyond the disc's shadow no light sub-path meets the ground.
/// bpt and vcm once weighed light sampling there as if light paths shared the work, and the far
/// ground came out 30-50% dark under the sky and sun; they must agree with pt there.
#[test]
fn bpt_and_vcm_agree_with_pt_on_ground_beyond_the_sky_disc() {
    let text = r#"
[camera]
position = [0, 1.5, 0]
look_at = [9.4, 1.2, 3.42]
fov = 60
resolution = [48, 24]
[render]
max_depth = 6
seed = 2
[materials.grass]
type = "diffuse"
reflectance = [0.16, 0.24, 0.08]
[materials.white]
type = "diffuse"
reflectance = 0.75
[[shapes]]
type = "plane"
normal = [0, 1, 0]
material = "grass"
[[shapes]]
type = "sphere"
center = [3.085, 0.45, 1.76]
radius = 0.45
material = "white"
[environment]
type = "sky"
turbidity = 2.5
latitude = 48.85
longitude = 2.35
date = "2026-06-21"
time = "17:30"
utc_offset = 2
"#;
    let ground = |integrator: Integrator| {
        let mut scene = parse_scene(text, std::path::Path::new("ground.toml")).expect("scene parses");
        scene.render.integrator = integrator;
        let out = cpu(&common::buffers(&scene, 48, 24), 96);
        // The lower half of the image: ground, most of it beyond the disc (radius about 2 m).
        let rows = &out.image.pixels[48 * 12..];
        [0, 1, 2].map(|c| rows.iter().map(|p| p[c] as f64).sum::<f64>() / rows.len() as f64)
    };
    let pt = ground(Integrator::Pt);
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        let other = ground(integrator);
        let ratio: Vec<f64> = (0..3).map(|c| other[c] / pt[c]).collect();
        println!("{}: ground mean / pt's {ratio:.4?}", integrator.name());
        assert!(
            ratio.iter().all(|r| (r - 1.0).abs() < 0.03),
            "{} against pt on the ground: {ratio:?}",
            integrator.name()
        );
    }
}

/// `auto` (the default) chooses by the scene's contents, as measured on the shared scenes: vcm
/// for rough glossy surfaces under area lights, bpt for them under spot lights and for media,
/// ppm for the rest; a named integrator is kept.
#[test]
fn auto_integrator_picks_vcm_or_bpt_for_glossy_bpt_for_fog_and_ppm_elsewhere() {
    for (name, chosen) in [
        ("cornell-box", Integrator::Ppm),
        ("cornell-caustics", Integrator::Ppm),
        ("cornell-glossy", Integrator::Vcm),
        ("cornell-fog", Integrator::Bpt),
        ("materials", Integrator::Vcm),
        ("spotlights", Integrator::Bpt),
    ] {
        let scene = load_scene(&common::repo_path(&format!("scenes/{name}.toml"))).expect("shipped scene loads");
        assert_eq!(scene.render.integrator, chosen, "{name}");
        println!("{name}: {} ({})", chosen.name(), scene.render.integrator_auto.expect("chosen automatically"));
    }
    let camera = "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 40\n";
    let fog = "[fog]\ndistance = 20\ncolor = [0.7, 0.75, 0.8]\n";
    for (render, expected, auto) in [
        ("", Integrator::Bpt, true),
        ("[render]\nintegrator = \"auto\"\n", Integrator::Bpt, true),
        ("[render]\nintegrator = \"ppm\"\n", Integrator::Ppm, false),
        ("[photons]\nenabled = false\n", Integrator::Ppm, true),
    ] {
        let dir = common::scene_dir(&format!("{camera}{fog}{render}"));
        let scene = load_scene(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((scene.render.integrator, scene.render.integrator_auto.is_some()), (expected, auto), "{render}");
    }
}

#[test]
fn integrator_is_read_from_the_scene_and_unknown_names_are_refused() {
    let dir = common::scene_dir(
        "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 40\n[render]\nintegrator = \"pt\"\n",
    );
    let scene = load_scene(&dir.path().join("scene.toml")).unwrap();
    assert_eq!(scene.render.integrator, Integrator::Pt);
    let dir = common::scene_dir(
        "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 40\n[render]\nintegrator = \"ptt\"\n",
    );
    let err = load_scene(&dir.path().join("scene.toml")).unwrap_err().to_string();
    println!("{err}");
    assert!(err.contains("scene.toml:6:") && err.contains("integrator") && err.contains("\"pt\""), "{err}");
}

#[test]
fn photon_flags_with_the_path_tracer_are_an_error() {
    let dir = common::scene_dir(
        "[camera]\nposition = [0, 0, 1]\nlook_at = [0, 0, 0]\nfov = 40\nresolution = [8, 8]\n[render]\nspp = 1\npasses = 1\n",
    );
    let out = common::photonix(
        &["render", "scene.toml", "--integrator", "pt", "--photons", "1000", "--backend", "cpu", "-o", "x.png"],
        dir.path(),
    );
    let err = common::stderr(&out);
    assert!(!out.status.success() && err.contains("--photons") && err.contains("pt"), "{err}");
    assert!(!dir.path().join("x.png").exists());
    let out = common::photonix(&["render", "scene.toml", "--integrator", "vcmx", "-o", "x.png"], dir.path());
    assert!(!out.status.success() && common::stderr(&out).contains("ppm, pt"), "{}", common::stderr(&out));
    let out = common::photonix(
        &["render", "scene.toml", "--integrator", "pt", "--backend", "cpu", "-o", "x.png"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", common::stderr(&out));
}

/// A farm of pass ranges with the path tracer: the merged parts equal one run of the same
/// passes, and a part of another integrator is refused by `merge`.
#[test]
fn pt_pass_ranges_merge_to_one_run_and_integrators_do_not_mix() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let scene = common::repo_path("scenes/cornell-box.toml");
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out, "--backend", "cpu", "--resolution", "32x32"];
        args.extend_from_slice(extra);
        let o = common::photonix(&args, p);
        assert!(o.status.success(), "{}", common::stderr(&o));
    };
    render("full.exr", &["--integrator", "pt", "--passes", "4"]);
    render("a.exr", &["--integrator", "pt", "--pass-range", "0..2"]);
    render("b.exr", &["--integrator", "pt", "--pass-range", "2..4"]);
    render("ppm.exr", &["--pass-range", "2..4"]);
    let merged = common::photonix(&["merge", "b.exr", "a.exr", "-o", "merged.exr"], p);
    assert!(merged.status.success(), "{}", common::stderr(&merged));
    let (full, merged) = (read_exr(&p.join("full.exr")).unwrap(), read_exr(&p.join("merged.exr")).unwrap());
    let error = rel_mse(&merged, &full);
    println!("merged vs one run: relMSE {error:.3e}");
    assert!(error < 1e-10, "{error}");
    let mixed = common::photonix(&["merge", "a.exr", "ppm.exr", "-o", "mixed.exr"], p);
    let err = common::stderr(&mixed);
    println!("{err}");
    assert!(!mixed.status.success() && err.contains("integrator"), "{err}");
    assert!(!p.join("mixed.exr").exists());
}

/// Multiple importance sampling checked: light sampling alone and BSDF sampling alone (each
/// carrying every path it can make) converge to the image that both make under MIS, and MIS's
/// error is no higher than the better technique's at equal samples. On cornell-glossy: a small
/// light (light sampling's case) over rough gold and glass (BSDF sampling's).
#[test]
fn pt_each_technique_alone_converges_to_the_mis_image() {
    use photonix::layout::constants::{TECHNIQUES_ALL, TECHNIQUE_BSDF, TECHNIQUE_LIGHT};
    let scene = shipped("cornell-glossy", Integrator::Pt);
    let reference = downsample(&read_exr(&common::reference_path("cornell-glossy")).expect("shared reference"), 8);
    let mut results = Vec::new();
    for (label, techniques) in [("light", TECHNIQUE_LIGHT), ("bsdf", TECHNIQUE_BSDF), ("mis", TECHNIQUES_ALL)] {
        let mut buffers = common::buffers(&scene, 32, 32);
        buffers.frame.techniques = techniques;
        let image = cpu(&buffers, 64).image;
        let (error, ratio) = (rel_mse(&image, &reference), mean_ratio(&image, &reference));
        println!("{label}: relMSE {error:.5}, mean ratio {ratio:.4?}");
        results.push((label, error, ratio));
    }
    for (label, _, ratio) in &results {
        // Measured within 2% for each; BSDF sampling alone meets the small light rarely, so its
        // mean wanders most.
        for r in ratio {
            assert!((r - 1.0).abs() < 0.05, "{label}: mean ratio {ratio:?}");
        }
    }
    let (light, bsdf, mis) = (results[0].1, results[1].1, results[2].1);
    assert!(mis <= 1.1 * light.min(bsdf), "MIS relMSE {mis} against light {light}, bsdf {bsdf}");
}

// Vertex connection and merging (`vcm`) and bidirectional path tracing (`bpt`), src/cpu/vcm.rs.

/// Both bidirectional integrators against the shared references (the scenes without media;
/// media are refused, see below). At 64x64 a sample has 4096 light paths, so vcm's merging
/// radius is wide and its bias largest here; it shrinks with the samples.
#[test]
fn bpt_and_vcm_match_references() {
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        for (name, max_rel_mse) in [("cornell-box", 0.02), ("cornell-caustics", 0.3), ("cornell-glossy", 0.3)] {
            let scene = shipped(name, integrator);
            let reference = downsample(&read_exr(&common::reference_path(name)).expect("shared reference"), 4);
            let image = cpu(&common::buffers(&scene, 64, 64), 16).image;
            let error = rel_mse(&image, &reference);
            let ratio = mean_ratio(&image, &reference);
            println!("{} {name}: relMSE {error:.4}, mean ratio {ratio:.4?}", integrator.name());
            for r in ratio {
                assert!((r - 1.0).abs() < 0.025, "{} {name}: mean ratio {ratio:?}", integrator.name());
            }
            assert!(error < max_rel_mse, "{} {name}: relMSE {error}", integrator.name());
        }
    }
}

/// The white furnace with every technique: light tracing, connections and merging all carry the
/// emitting walls' light, and the weights must still sum to one per path.
#[test]
fn bpt_and_vcm_furnace_is_one_over_one_minus_albedo() {
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        let mut scene = common::furnace();
        scene.render.integrator = integrator;
        let image = cpu(&common::buffers(&scene, 16, 16), 64).image;
        let n = image.pixels.len() as f64;
        let mean: f64 = image.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / n;
        let worst = image.pixels.iter().map(|p| (p[0] as f64 - 2.0).abs()).fold(0.0, f64::max);
        println!("{}: furnace mean {mean:.5} (expected 2), worst pixel off by {worst:.4}", integrator.name());
        assert!((mean - 2.0).abs() < 0.02, "{}: furnace mean {mean}", integrator.name());
        assert!(worst < 0.6, "{}: a pixel is off by {worst}", integrator.name());
    }
}

/// Multiple importance sampling of vcm checked: light tracing alone, merging alone, the path
/// tracer and bpt each converge to vcm's image, and vcm's error is no higher than the best
/// single technique's at equal samples (cornell-box: no delta surfaces, so light tracing alone
/// reaches every path but the light seen directly, which the camera takes).
#[test]
fn vcm_each_technique_alone_converges_to_the_vcm_image() {
    use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY, VCM_MERGE_ONLY};
    let reference = downsample(&read_exr(&common::reference_path("cornell-box")).expect("shared reference"), 8);
    let mut results = Vec::new();
    for (label, integrator, techniques) in [
        ("light tracing", Integrator::Bpt, VCM_LIGHT_TRACE_ONLY),
        ("merging", Integrator::Vcm, VCM_MERGE_ONLY),
        ("path tracing", Integrator::Pt, TECHNIQUES_ALL),
        ("bpt", Integrator::Bpt, TECHNIQUES_ALL),
        ("vcm", Integrator::Vcm, TECHNIQUES_ALL),
    ] {
        let scene = shipped("cornell-box", integrator);
        let mut buffers = common::buffers(&scene, 32, 32);
        buffers.frame.techniques = techniques;
        let image = cpu(&buffers, 64).image;
        let (error, ratio) = (rel_mse(&image, &reference), mean_ratio(&image, &reference));
        println!("{label}: relMSE {error:.5}, mean ratio {ratio:.4?}");
        results.push((label, error, ratio));
    }
    for (label, _, ratio) in &results {
        for r in ratio {
            assert!((r - 1.0).abs() < 0.025, "{label}: mean ratio {ratio:?}");
        }
    }
    let best_single = results[..3].iter().map(|r| r.1).fold(f64::MAX, f64::min);
    let vcm = results[4].1;
    assert!(vcm <= 1.1 * best_single, "vcm relMSE {vcm} against the best single technique's {best_single}");
}

/// vcm's layers sum to the image and hold their signatures: the glass ball's caustic seen on the
/// floor lands in the caustics layer, by merging and light tracing alike.
#[test]
fn vcm_layers_split_by_path_signature_and_sum_to_the_image() {
    let scene = shipped("cornell-caustics", Integrator::Vcm);
    let out = cpu(&common::buffers(&scene, 32, 32), 8);
    let total = |img: &photonix::io::Image| img.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
    let (all, sum) = (total(&out.image), total(&out.layers.combined()));
    assert!((all - sum).abs() <= 1e-4 * all, "layers sum {sum} vs image {all}");
    let share: Vec<f64> = out.layers.named().iter().map(|(_, l)| total(l) / all).collect();
    println!("vcm layer shares (direct, specular, indirect, caustics): {share:.4?}");
    for (i, s) in share.iter().enumerate() {
        assert!(*s > 0.005, "layer {i} holds {s} of the light");
    }
}

/// Light tracing lands through atomics in any order, yet the image is the same bits every run:
/// the splats are 64-bit fixed-point sums.
#[test]
fn vcm_images_do_not_depend_on_thread_order() {
    let scene = shipped("cornell-caustics", Integrator::Vcm);
    let buffers = common::buffers(&scene, 24, 24);
    let a = cpu(&buffers, 2).image;
    let b = cpu(&buffers, 2).image;
    assert_eq!(a.pixels, b.pixels);
    // The words of a splat are exact: whole part high, 32 bits of fraction low.
    use photonix::cpu::vcm::{splat_value, splat_words};
    for v in [0.0f32, 0.5, 1.25, 3.0e-7, 12345.678, 7.0e8] {
        let (low, high) = splat_words(v);
        assert!((splat_value(low, high) - v).abs() <= v * 1e-6 + 2.5e-10, "{v}");
    }
}

/// Participating media through the bidirectional integrators (docs/integrators.md, "Media"):
/// cornell-fog (a homogeneous fog inside a null box, the area light hanging in it) against the
/// shared reference. Measured at 64x64 and 32 samples: means within 0.6% at 16 samples and about
/// 0.2% at 32 (relMSE 0.002; pt's is 0.018 at equal samples: light tracing and connections reach
/// the lamp's glow in the fog that pt finds by chance).
#[test]
fn bpt_and_vcm_match_the_fog_reference() {
    let reference = downsample(&read_exr(&common::reference_path("cornell-fog")).expect("shared reference"), 4);
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        let image = cpu(&common::buffers(&shipped("cornell-fog", integrator), 64, 64), 32).image;
        let error = rel_mse(&image, &reference);
        let ratio = mean_ratio(&image, &reference);
        println!("{} cornell-fog: relMSE {error:.4}, mean ratio {ratio:.4?}", integrator.name());
        for r in ratio {
            assert!((r - 1.0).abs() < 0.01, "{} cornell-fog: mean ratio {ratio:?}", integrator.name());
        }
        assert!(error < 0.01, "{} cornell-fog: relMSE {error}", integrator.name());
    }
}

/// scenes/fog.toml with its glass ball made diffuse: the spot lights' caustic through the ball is
/// a path pt cannot sample (a point light seen through glass from a diffuse floor), so with the
/// glass the two rightly differ (bpt reads 6-20% brighter, the warm spot's caustic).
fn fog_without_glass(integrator: Integrator) -> Scene {
    let path = common::repo_path("scenes/fog.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let glass = "type = \"dielectric\"\nior = 1.5";
    assert!(text.contains(glass), "scenes/fog.toml's glass changed; update this test");
    let mut scene = parse_scene(&text.replace(glass, "type = \"diffuse\"\nreflectance = 0.5"), &path).unwrap();
    scene.render.integrator = integrator;
    scene
}

/// bpt and vcm against pt in media: a homogeneous fog behind null boundaries (cornell-fog), a
/// chromatic smoke box in a Henyey-Greenstein haze that fills all space, the camera and the spot
/// lights inside it (fog without its glass), and a heterogeneous smoke lit by a spot and a point
/// light (smoke). The bound is pt's noise: its light in fog comes in rare bright paths (the
/// fog's pt at 256 and 4096 samples of 40x30 differ by 1.6-2.8%), while bpt's repeats within
/// 0.2%.
#[test]
fn bpt_and_vcm_agree_with_pt_in_media() {
    for (name, scene, pt_spp, spp, max_mean) in [
        ("cornell-fog", shipped as fn(&str, Integrator) -> Scene, 64, 16, 0.03),
        ("fog without glass", |_: &str, i| fog_without_glass(i), 256, 32, 0.04),
        ("smoke", shipped, 64, 16, 0.02),
    ] {
        let pt = cpu(&common::buffers(&scene(name, Integrator::Pt), 40, 30), pt_spp).image;
        for integrator in [Integrator::Bpt, Integrator::Vcm] {
            let image = cpu(&common::buffers(&scene(name, integrator), 40, 30), spp).image;
            let ratio = mean_ratio(&image, &pt);
            println!("{} {name}: mean ratio to pt {ratio:.4?}, relMSE {:.4}", integrator.name(), rel_mse(&image, &pt));
            for r in ratio {
                assert!((r - 1.0).abs() < max_mean, "{} {name}: mean ratio to pt {ratio:?}", integrator.name());
            }
        }
    }
}

/// The weights at medium vertices checked: light tracing alone (every path whose first camera
/// vertex is non-delta, a scattering point in the fog included, weight 1) converges to bpt's
/// image on cornell-fog, and so does vcm, whose merging is left out at medium vertices; were a
/// technique's terms wrong there, the weights of a path would not sum to one and bpt or vcm would
/// drift from light tracing. Measured at 32x32: light tracing's 512 samples within 0.25% of bpt's
/// and vcm's 128 (at 64 and 32 samples it read 1% low: its noise).
#[test]
fn light_tracing_alone_agrees_with_bpt_and_vcm_in_fog() {
    use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY};
    let image = |integrator, techniques, spp| {
        let mut buffers = common::buffers(&shipped("cornell-fog", integrator), 32, 32);
        buffers.frame.techniques = techniques;
        cpu(&buffers, spp).image
    };
    let light_tracing = image(Integrator::Bpt, VCM_LIGHT_TRACE_ONLY, 512);
    for (label, integrator) in [("bpt", Integrator::Bpt), ("vcm", Integrator::Vcm)] {
        let all = image(integrator, TECHNIQUES_ALL, 128);
        let ratio = mean_ratio(&light_tracing, &all);
        println!(
            "light tracing alone against {label}: mean ratio {ratio:.4?}, relMSE {:.4}",
            rel_mse(&light_tracing, &all)
        );
        for r in ratio {
            assert!((r - 1.0).abs() < 0.01, "light tracing alone against {label}: mean ratio {ratio:?}");
        }
    }
}

/// The kernels of bpt and vcm (vcm_light, render_vcm) against their CPU twin: the same random
/// numbers, light sub-paths, splats and merges, so the same image up to float rounding (a few
/// pixels may flip a discrete choice: a light vertex on a grid cell's face, a connection ray
/// grazing an edge).
#[test]
fn bpt_and_vcm_gpu_match_cpu() {
    let ctx = common::gpu();
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        // outdoor: sky, sun and an environment light; its glass ball's rim flips a discrete choice
        // under rounding (as with pt), hence the looser bound there.
        for (name, max_error, max_mean) in [
            ("cornell-box", 1e-6, 1e-3),
            ("cornell-caustics", 1e-6, 1e-3),
            ("cornell-glossy", 1e-6, 1e-3),
            ("spotlights", 1e-6, 1e-3),
            ("outdoor", 1e-3, 1e-3),
            // Media: a fog behind null boundaries; a haze everywhere with spot lights, a smoke box
            // and a glass ball (media change through glass), also without the ball;
            // heterogeneous smoke (delta and ratio tracking). In the haze a few light paths
            // diverge under rounding (bpt's light tracing alone shows it: relMSE 5.4e-5), as
            // pt's camera paths do more there (relMSE 3.4e-3 at this size, which is why pt's
            // check leaves fog out), hence fog's looser bounds. A diverged light path reaches
            // the connections drawn from its block (VCM_PICK_BLOCK) anywhere in the image, so
            // at 2 samples of 32 x 24 pixels the means part by up to 0.8% (0.1% at 16 samples
            // of 64 x 48, BENCHMARKS.md, "A light vertex cache").
            ("cornell-fog", 1e-6, 1e-3),
            ("fog", 1e-3, 1e-2),
            ("fog without glass", 1e-3, 1e-2),
            ("smoke", 1e-6, 1e-3),
        ] {
            let scene =
                if name == "fog without glass" { fog_without_glass(integrator) } else { shipped(name, integrator) };
            let buffers = common::buffers(&scene, 32, 24);
            let (gpu, cpu) = both_twins(&ctx, &buffers, 2);
            let error = rel_mse(&gpu.image, &cpu.image);
            let ratio = mean_ratio(&gpu.image, &cpu.image);
            println!(
                "{} {name}: GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}, rays {} / {}",
                integrator.name(),
                gpu.stats.rays,
                cpu.stats.rays
            );
            assert!(error < max_error, "{} {name}: relMSE {error:.3e}", integrator.name());
            for r in ratio {
                assert!((r - 1.0).abs() < max_mean, "{} {name}: mean ratio {ratio:?}", integrator.name());
            }
        }
    }
}

/// Pass ranges with vcm (each sample has its own radius, from its index): the merged parts equal
/// one run of the same passes.
#[test]
fn vcm_pass_ranges_merge_to_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let scene = common::repo_path("scenes/cornell-box.toml");
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out, "--backend", "cpu", "--resolution", "24x24"];
        args.extend_from_slice(extra);
        let o = common::photonix(&args, p);
        assert!(o.status.success(), "{}", common::stderr(&o));
    };
    render("full.exr", &["--integrator", "vcm", "--passes", "4"]);
    render("a.exr", &["--integrator", "vcm", "--pass-range", "0..2"]);
    render("b.exr", &["--integrator", "vcm", "--pass-range", "2..4"]);
    let merged = common::photonix(&["merge", "b.exr", "a.exr", "-o", "merged.exr"], p);
    assert!(merged.status.success(), "{}", common::stderr(&merged));
    let (full, merged) = (read_exr(&p.join("full.exr")).unwrap(), read_exr(&p.join("merged.exr")).unwrap());
    let error = rel_mse(&merged, &full);
    println!("merged vs one run: relMSE {error:.3e}");
    assert!(error < 1e-10, "{error}");
}

/// The Cornell box with every white wall strongly bumped: the shading normal leaves the
/// geometric one, so light paths need the adjoint's factor (`shading_adjoint`).
fn bumped_box(integrator: Integrator) -> Scene {
    let text = std::fs::read_to_string(common::repo_path("scenes/cornell-box.toml")).expect("shipped scene");
    let white = "[materials.white]\ntype = \"diffuse\"\nreflectance = [0.725, 0.71, 0.68]\n";
    assert!(text.contains(white), "cornell-box.toml's white material as written here");
    let bumped = format!(
        "[textures.dents]\ntype = \"pattern\"\npattern = \"dents\"\ntransform = {{ scale = 40 }}\n\n{white}\
         bump = {{ texture = \"dents\", scale = 30 }}\n"
    );
    let mut scene = parse_scene(&text.replace(white, &bumped), &common::repo_path("scenes/bumped-box.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    scene.render.integrator = integrator;
    scene
}

/// On bumped walls connections agree with the path tracer (the camera's direction of transport)
/// only with the adjoint's factor: without it bpt read 1.6% low here (with it 0.2-0.4% low, as
/// light tracing alone). And the kernels apply it as the CPU twin does.
#[test]
fn light_paths_on_bumped_surfaces_are_the_adjoint_of_camera_paths() {
    use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY};
    let (w, h) = (32, 32);
    let reference = cpu(&common::buffers(&bumped_box(Integrator::Pt), w, h), 1024).image;
    for (label, integrator, techniques, spp) in
        [("light tracing", Integrator::Bpt, VCM_LIGHT_TRACE_ONLY, 256), ("bpt", Integrator::Bpt, TECHNIQUES_ALL, 128)]
    {
        let mut buffers = common::buffers(&bumped_box(integrator), w, h);
        buffers.frame.techniques = techniques;
        let ratio = mean_ratio(&cpu(&buffers, spp).image, &reference);
        println!("{label} against pt on the bumped box: mean ratio {ratio:.4?}");
        for r in ratio {
            assert!((r - 1.0).abs() < 0.01, "{label}: mean ratio {ratio:?} against pt");
        }
    }
    let ctx = common::gpu();
    for integrator in [Integrator::Pt, Integrator::Bpt] {
        let buffers = common::buffers(&bumped_box(integrator), 24, 16);
        let (gpu, cpu) = both_twins(&ctx, &buffers, 2);
        let error = rel_mse(&gpu.image, &cpu.image);
        println!("{} bumped box: GPU vs CPU relMSE {error:.3e}", integrator.name());
        // The bump pattern's noise rounds differently on the two sides (pt shows 3e-6 too).
        assert!(error < 1e-5, "{} bumped box: GPU vs CPU relMSE {error:.3e}", integrator.name());
    }
}

/// Light tracing through a thin lens: light vertices reach the camera through a point of the
/// aperture (the pixel is where the ray crosses the plane in focus), so bpt and vcm keep the
/// technique with focal blur. Light tracing alone and bpt agree with the path tracer, and the
/// kernels with the CPU twin.
#[test]
fn light_tracing_reaches_a_thin_lens_camera() {
    use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY};
    use photonix::scene::ThinLens;
    let with_lens = |integrator| {
        let mut scene = shipped("cornell-box", integrator);
        // In focus on the tall block's front, the back wall blurred; a hexagonal aperture.
        scene.camera.lens = Some(ThinLens { radius: 25.0, focal_distance: 1100.0, blades: 6, rotation_deg: 10.0 });
        scene
    };
    let (w, h) = (32, 32);
    let reference = cpu(&common::buffers(&with_lens(Integrator::Pt), w, h), 1024).image;
    for (label, integrator, techniques, spp) in [
        ("light tracing", Integrator::Bpt, VCM_LIGHT_TRACE_ONLY, 256),
        ("bpt", Integrator::Bpt, TECHNIQUES_ALL, 128),
        ("vcm", Integrator::Vcm, TECHNIQUES_ALL, 128),
    ] {
        let mut buffers = common::buffers(&with_lens(integrator), w, h);
        buffers.frame.techniques = techniques;
        let image = cpu(&buffers, spp).image;
        let (error, ratio) = (rel_mse(&image, &reference), mean_ratio(&image, &reference));
        println!("{label} against pt through a thin lens: relMSE {error:.5}, mean ratio {ratio:.4?}");
        for r in ratio {
            assert!((r - 1.0).abs() < 0.01, "{label}: mean ratio {ratio:?} against pt");
        }
        // Light tracing puts the light where the lens does: the image, not only its mean.
        assert!(error < 0.006, "{label}: relMSE {error} against pt");
    }
    let ctx = common::gpu();
    for integrator in [Integrator::Bpt, Integrator::Vcm] {
        let buffers = common::buffers(&with_lens(integrator), 24, 16);
        let (gpu, cpu) = both_twins(&ctx, &buffers, 2);
        let error = rel_mse(&gpu.image, &cpu.image);
        println!("{} through a thin lens: GPU vs CPU relMSE {error:.3e}", integrator.name());
        assert!(error < 1e-6, "{} through a thin lens: GPU vs CPU relMSE {error:.3e}", integrator.name());
    }
}

/// Light tracing reaches the orthographic camera (the film point whose parallel ray meets the
/// vertex, a density by area) and the latlong camera (the eye, a pixel's solid angle at the
/// vertex's latitude), so bpt and vcm keep the technique with them. Light tracing alone and
/// bpt agree with the path tracer, and the kernels with the CPU twin.
#[test]
fn light_tracing_reaches_orthographic_and_latlong_cameras() {
    const LT_SPP: u32 = 1024;
    use photonix::layout::constants::{TECHNIQUES_ALL, VCM_LIGHT_TRACE_ONLY};
    // The box from the front through parallel rays, and all around from inside it.
    let cameras = [
        ("orthographic", Projection::Orthographic { view_height: 600.0 }, Vec3::new(278.0, 273.0, -800.0), 32, 32),
        ("latlong", Projection::LatLong, Vec3::new(150.0, 300.0, 150.0), 48, 24),
    ];
    let ctx = common::gpu();
    for (camera, projection, position, w, h) in cameras {
        let scene = |integrator| {
            let mut scene = shipped("cornell-box", integrator);
            scene.camera.projection = projection;
            scene.camera.position = position;
            scene.camera.look_at = position + Vec3::Z;
            scene
        };
        let reference = cpu(&common::buffers(&scene(Integrator::Pt), w, h), 1024).image;
        for (label, integrator, techniques, spp) in [
            ("light tracing", Integrator::Bpt, VCM_LIGHT_TRACE_ONLY, LT_SPP),
            ("bpt", Integrator::Bpt, TECHNIQUES_ALL, 128),
            ("vcm", Integrator::Vcm, TECHNIQUES_ALL, 128),
        ] {
            let mut buffers = common::buffers(&scene(integrator), w, h);
            buffers.frame.techniques = techniques;
            let image = cpu(&buffers, spp).image;
            let (error, ratio) = (rel_mse(&image, &reference), mean_ratio(&image, &reference));
            println!("{camera}, {label} against pt: relMSE {error:.5}, mean ratio {ratio:.4?}");
            for r in ratio {
                assert!((r - 1.0).abs() < 0.01, "{camera}, {label}: mean ratio {ratio:?} against pt");
            }
            assert!(error < 0.006, "{camera}, {label}: relMSE {error} against pt");
        }
        for integrator in [Integrator::Bpt, Integrator::Vcm] {
            let buffers = common::buffers(&scene(integrator), 24, 16);
            let (gpu, cpu) = both_twins(&ctx, &buffers, 2);
            let error = rel_mse(&gpu.image, &cpu.image);
            println!("{camera}, {}: GPU vs CPU relMSE {error:.3e}", integrator.name());
            assert!(error < 1e-6, "{camera}, {}: GPU vs CPU relMSE {error:.3e}", integrator.name());
        }
    }
}

/// vcm_light and render_vcm trace several light and camera paths per invocation on lavapipe (one
/// after another, to keep its SIMD lanes busy) and one on GPUs: each path is the same computation
/// whichever invocation runs it, so the images are equal bit for bit, with counts that divide the
/// paths and pixels and counts that do not.
#[test]
fn paths_per_invocation_leave_the_image_alone() {
    use photonix::render::gpu::GpuRenderer;
    let ctx = common::gpu();
    for (name, integrator) in [("cornell-glossy", Integrator::Vcm), ("fog", Integrator::Bpt)] {
        let buffers = common::buffers(&shipped(name, integrator), 30, 23);
        let render = |per: u32| {
            let mut renderer = GpuRenderer::new(&ctx, &buffers, None).unwrap();
            renderer.set_paths_per_invocation(per);
            renderer.render_pass(2, 0, &mut |_, _| {}).unwrap()
        };
        let one = render(1);
        for per in [3, 8, 64] {
            let other = render(per);
            assert!(other.layers == one.layers, "{name}: {per} paths per invocation change the image");
            assert_eq!(other.stats.rays, one.stats.rays, "{name}: {per} paths per invocation");
        }
        // Runs stopped after a few vertices and resumed by the next dispatch: the same paths.
        for (per, steps) in [(1, 1), (8, 3)] {
            let mut renderer = GpuRenderer::new(&ctx, &buffers, None).unwrap();
            renderer.set_paths_per_invocation(per);
            renderer.set_steps_per_dispatch(steps);
            let other = renderer.render_pass(2, 0, &mut |_, _| {}).unwrap();
            assert!(other.layers == one.layers, "{name}: {steps} vertices per dispatch change the image");
            assert_eq!(other.stats.rays, one.stats.rays, "{name}: {steps} vertices per dispatch");
        }
    }
}

/// Camera paths through 1500 overlapping frames run past lavapipe's 65535 loop iterations per
/// invocation, sooner with many paths per invocation: the renderer then renders the samples again
/// with fewer paths per invocation (paths of 2 vertices: 64 to an invocation break off, 1 does
/// not), and, where even one path breaks off (12 vertices), with fewer vertices per dispatch,
/// each invocation storing its path for the next dispatch to resume. Never a partial image. A
/// real GPU has no such limit and renders both at once.
#[test]
fn camera_paths_the_loop_limit_breaks_off_are_rendered_again_or_refused() {
    use photonix::render::gpu::GpuRenderer;
    let mut scene = load_scene(&common::repo_path("benches/instancing/frames-1500.toml")).unwrap();
    scene.render.integrator = Integrator::Bpt;
    let ctx = common::gpu();
    let lavapipe = ctx.info().name.contains("llvmpipe");
    for depth in [2, 12] {
        scene.render.max_depth = depth;
        let buffers = common::buffers(&scene, 8, 6);
        let mut renderer = GpuRenderer::new(&ctx, &buffers, None).unwrap();
        renderer.set_paths_per_invocation(64);
        let gpu = renderer.render_pass(1, 0, &mut |_, _| {}).expect("the runs are split until they fit");
        let cpu = cpu(&buffers, 1);
        let error = rel_mse(&gpu.image, &cpu.image);
        let (per, steps) = (renderer.paths_per_invocation(), renderer.steps_per_dispatch());
        println!("max_depth {depth}: rendered {per} paths per invocation, {steps} vertices per dispatch (0: all), GPU vs CPU relMSE {error:.3e}");
        assert!(error < 1e-4, "max_depth {depth}: relMSE {error:.3e} against the CPU twin");
        assert!(if lavapipe { per < 64 } else { per == 64 }, "{per}: no fallback, or one without cause");
        // Two vertices fit a path per invocation; twelve need their vertices spread over dispatches.
        assert_eq!(steps > 0, lavapipe && depth == 12, "{steps} vertices per dispatch at max_depth {depth}");
    }
}
