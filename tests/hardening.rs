//! Issue 11, class by class, end to end through the `photonix` binary: no input crashes it,
//! overwrites what the user needs, or comes out silently wrong. Scene-file cases are in
//! `scene_errors.rs`, random inputs in `fuzz.rs`.

mod common;

use std::path::Path;
use std::process::{Command, Output};

const SCENE: &str = r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 45
resolution = [16, 12]

[render]
spp = 1
passes = 2

[photons]
count = 1000
caustic_count = 1000
gather_rays = 1

[materials.white]
type = "diffuse"
reflectance = [0.7, 0.7, 0.7]

[[shapes]]
type = "quad"
material = "white"
vertices = [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]]

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2, -0.5], [0.5, 2, -0.5], [0.5, 2, 0.5], [-0.5, 2, 0.5]]
radiance = [5, 5, 5]
"#;

fn scene_dir() -> tempfile::TempDir {
    common::scene_dir(SCENE)
}

use common::stderr;

fn run(args: &[&str], dir: &Path) -> Output {
    common::photonix(args, dir)
}

fn succeeds(out: &Output) -> String {
    let err = stderr(out);
    assert!(out.status.success(), "expected success: {err}");
    err
}

/// A refusal: non-zero exit, no panic, every piece in the message.
fn refused(out: &Output, pieces: &[&str]) -> String {
    let err = stderr(out);
    assert!(!out.status.success(), "expected a refusal, got success: {err}");
    assert!(!err.contains("panicked") && !err.contains("memory allocation"), "crash: {err}");
    for p in pieces {
        assert!(err.contains(p), "`{p}` missing from: {err}");
    }
    err
}

fn render(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render", "scene.toml"];
    args.extend(extra);
    run(&args, dir)
}

// 1. Every number is checked against its range; nothing panics

#[test]
fn extreme_flag_values_are_refused_with_their_range() {
    let dir = scene_dir();
    let p = dir.path();
    for (flag, value, piece) in [
        ("--time", "1e30s", "from 1ms to 365 days"),
        ("--time", "1e30", "from 1ms to 365 days"),
        ("--time", "100000000000000000000000h", "from 1ms to 365 days"),
        ("--checkpoint-every", "1e300h", "from 1ms to 365 days"),
        ("--checkpoint-every", "0.0001ms", "from 1ms to 365 days"),
        ("--seed", "99999999999999999999999", "from 0 to 4294967295"),
        ("--seed", "-1", "from 0 to 4294967295"),
        ("--spp", "4294967295", "from 1 to 4096"),
        ("--passes", "0", "from 1 to 1000000"),
        ("--passes", "4294967296", "from 1 to 1000000"),
        ("--max-depth", "1000000", "from 1 to 1024"),
        ("--photon-depth", "0", "from 1 to 1024"),
        ("--photons", "4294967296", "from 1 to 1000000000"),
        ("--caustic-photons", "1000000001", "from 1 to 1000000000"),
        ("--gather-rays", "100000", "from 0 to 1024"),
        ("--radius", "1e300", "above 0 to 1e9"),
        ("--radius", "-0", "above 0"),
        ("--caustic-radius", "inf", "above 0"),
        ("--target-error", "nan", "above 0 to 1000"),
        ("--exposure", "1e30", "from -64 to 64"),
        ("--resolution", "65536x65536", "more than 268435456 pixels"),
        ("--pass-range", "0..4294967295", "B <= 1000000"),
    ] {
        let out = render(p, &["-o", "out.png", "--backend", "cpu", flag, value]);
        refused(&out, &[flag, piece]);
    }
    assert!(!p.join("out.png").exists());
    let out = run(&["bench", "scene.toml", "--spp", "0"], p);
    refused(&out, &["--spp", "from 1 to 4096"]);
    let out = run(&["bench", "scene.toml", "--photon-paths", "10,0"], p);
    refused(&out, &["--photon-paths", "from 1 to 1000000000"]);
}

#[test]
fn photon_radii_the_grid_cannot_use_are_refused() {
    let dir = scene_dir();
    let p = dir.path();
    // The scene reaches 3 units from the origin: cells of 1e-9 would index past 2^31.
    let out = render(p, &["-o", "out.png", "--backend", "cpu", "--radius", "1e-9"]);
    refused(&out, &["photon radius 1e-9 is too small", "give at least"]);
    let out = render(p, &["-o", "out.png", "--backend", "cpu", "--caustic-radius", "1000"]);
    refused(&out, &["photon caustic radius 1000 is larger than the whole scene"]);
    assert!(!p.join("out.png").exists());
}

// 2. Resources are estimated before they are taken

#[test]
fn a_render_too_big_for_memory_is_refused_before_it_starts() {
    let dir = scene_dir();
    let p = dir.path();
    // 2^28 pixels at about 316 bytes each, and 2 x 1e9 photon paths: hundreds of GiB. (On a
    // machine with that much free, the test would render; it does not run there.)
    if photonix::render::memory::available_host_memory().is_some_and(|a| a > 64 << 30) {
        println!("skipped: this machine has more than 64 GiB free");
        return;
    }
    let args = ["-o", "out.png", "--resolution", "16384x16384", "--photons", "1000000000"];
    for backend in ["cpu", "gpu"] {
        let mut all = args.to_vec();
        all.extend(["--backend", backend, "--caustic-photons", "1000000000"]);
        let t = std::time::Instant::now();
        let err = refused(&render(p, &all), &["this render needs about", "GiB", "is available"]);
        println!("{backend}: {err}");
        assert!(t.elapsed().as_secs() < 20, "refused only after {:?}", t.elapsed());
    }
    // Half the photons of the default: the message says what size would fit.
    let out = render(p, &["-o", "out.png", "--resolution", "16384x16384", "--backend", "cpu"]);
    refused(&out, &["this render needs about 79", "pixels with these photon maps"]);
    assert!(!p.join("out.png").exists());
}

#[test]
fn photon_maps_beyond_one_gpu_buffer_are_refused_before_tracing() {
    let dir = scene_dir();
    let p = dir.path();
    // Lavapipe's storage buffers hold 128 MiB: 6.7 M photons.
    let t = std::time::Instant::now();
    let out = render(p, &["-o", "out.png", "--backend", "gpu", "--photons", "100000000"]);
    refused(&out, &["--photons 100000000 would store at least", "more than one storage buffer holds"]);
    assert!(t.elapsed().as_secs() < 20, "refused only after {:?}", t.elapsed());
    let out = run(&["bench", "scene.toml", "--gpu-only", "--spp", "1", "--photon-paths", "100000000"], p);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("more than one storage buffer holds"), "{text}");
}

#[test]
fn device_files_are_not_read_forever() {
    let dir = scene_dir();
    let out = run(&["render", "/dev/zero", "-o", "out.png"], dir.path());
    refused(&out, &["/dev/zero", "a device, not a regular file"]);
}

// 3. No silently wrong images

#[test]
fn nan_and_infinite_exposure_are_refused() {
    let dir = scene_dir();
    for value in ["nan", "inf", "-inf"] {
        let out = render(dir.path(), &["-o", "out.png", "--backend", "cpu", "--exposure", value]);
        refused(&out, &["--exposure", "from -64 to 64"]);
    }
}

#[test]
fn merge_refuses_parts_of_different_renders_and_names_the_difference() {
    let dir = scene_dir();
    let p = dir.path();
    let part = |name: &str, range: &str, extra: &[&str]| {
        let mut args = vec!["-o", name, "--backend", "cpu", "--pass-range", range];
        args.extend(extra);
        succeeds(&render(p, &args));
    };
    part("a.exr", "0..1", &[]);
    part("a2.exr", "0..1", &[]);
    // Identical renders give identical bytes, provenance included.
    assert!(std::fs::read(p.join("a.exr")).unwrap() == std::fs::read(p.join("a2.exr")).unwrap());
    part("seed.exr", "1..2", &["--seed", "5"]);
    part("spp.exr", "1..2", &["--spp", "2"]);
    part("nophotons.exr", "1..2", &["--no-photons"]);
    std::fs::write(p.join("brighter.toml"), SCENE.replace("radiance = [5, 5, 5]", "radiance = [6, 5, 5]")).unwrap();
    succeeds(&run(&["render", "brighter.toml", "-o", "scene.exr", "--backend", "cpu", "--pass-range", "1..2"], p));
    for (other, pieces) in [
        ("seed.exr", vec!["seed.exr was rendered with seed 5 but a.exr with 0"]),
        ("spp.exr", vec!["spp.exr was rendered with spp 2 but a.exr with 1"]),
        ("nophotons.exr", vec!["nophotons.exr was rendered with photons off but a.exr with 1000/1000"]),
        ("scene.exr", vec!["scene.exr was rendered from a different scene than a.exr", "scene hash"]),
    ] {
        refused(&run(&["merge", "a.exr", other, "-o", "m.exr"], p), &pieces);
    }
    assert!(!p.join("m.exr").exists());
    // The same render's parts merge.
    part("b.exr", "1..2", &[]);
    succeeds(&run(&["merge", "a.exr", "b.exr", "-o", "m.exr"], p));
}

#[test]
fn diff_reads_an_accumulation_file_as_its_mean_image() {
    let dir = scene_dir();
    let p = dir.path();
    succeeds(&render(p, &["-o", "parts.exr", "--backend", "cpu", "--pass-range", "0..2"]));
    succeeds(&render(p, &["-o", "plain.exr", "--backend", "cpu", "--passes", "2"]));
    // Its sums over two passes would read twice as bright; its mean equals the plain render.
    let out = run(&["diff", "parts.exr", "plain.exr"], p);
    let err = succeeds(&out);
    assert!(err.contains("parts.exr is an accumulation file of 2 passes; comparing its mean image"), "{err}");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(text.contains("relMSE 0.000000"), "{text}");
    assert!(text.contains("R 1.0000 G 1.0000 B 1.0000"), "{text}");
}

#[test]
fn a_merged_accumulation_file_is_never_written_under_a_png_name() {
    let dir = scene_dir();
    let p = dir.path();
    succeeds(&render(p, &["-o", "a.exr", "--backend", "cpu", "--pass-range", "0..1"]));
    succeeds(&render(p, &["-o", "b.exr", "--backend", "cpu", "--pass-range", "1..2"]));
    refused(&run(&["merge", "a.exr", "b.exr", "--accumulation", "-o", "m.png"], p), &["--accumulation", ".exr"]);
    assert!(!p.join("m.png").exists());
    // Without --accumulation a .png name gets a real PNG.
    succeeds(&run(&["merge", "a.exr", "b.exr", "-o", "m.png"], p));
    assert!(std::fs::read(p.join("m.png")).unwrap().starts_with(b"\x89PNG"));
}

#[test]
fn lights_without_power_do_not_poison_light_picking() {
    // Found by the fuzz target: a lone point light of intensity -0 (or 0) made the pick
    // probabilities 0 / 0 = NaN.
    for intensity in ["0", "-0e0", "1e-45"] {
        let text = format!(
            "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0.5, 0]\nfov = 45\n[materials.white]\ntype = \"diffuse\"\n\
             [[shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\ncenter = [0, 0, 0]\nradius = 1\n\
             [[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\nintensity = {intensity}\n"
        );
        let scene = photonix::scene::parse_scene(&text, Path::new("dark.toml")).unwrap();
        let buffers = common::buffers(&scene, 8, 8);
        assert!(buffers.frame.total_light_power.is_finite(), "{intensity}");
        assert!(buffers.lights.iter().all(|l| l.pick_probability.is_finite() && l.cdf.is_finite()), "{intensity}");
        let image = common::cpu_image(&buffers, 1);
        assert!(image.pixels.iter().flatten().all(|c| *c == 0.0), "{intensity}: a dark scene renders black, not NaN");
    }
}

// 4. Nothing the user needs is overwritten

#[test]
fn outputs_never_overwrite_inputs_whatever_the_spelling() {
    let dir = scene_dir();
    let p = dir.path();
    // A scene file with an image name, written over by -o in three spellings.
    std::fs::write(p.join("scene.png"), SCENE).unwrap();
    std::fs::create_dir(p.join("sub")).unwrap();
    std::os::unix::fs::symlink(p.join("scene.png"), p.join("link.png")).unwrap();
    for output in ["scene.png", "./sub/../scene.png", "link.png"] {
        let out = run(&["render", "scene.png", "-o", output, "--backend", "cpu"], p);
        refused(&out, &["is the scene file too"]);
        assert_eq!(std::fs::read_to_string(p.join("scene.png")).unwrap(), SCENE);
    }
    // The contact sheet onto the output, which does not exist yet.
    let out = render(p, &["-o", "out.png", "--contact-sheet", "./out.png", "--backend", "cpu"]);
    refused(&out, &["out.png is the output image too"]);
    assert!(!p.join("out.png").exists());
    // merge -o onto one of its inputs.
    succeeds(&render(p, &["-o", "a.exr", "--backend", "cpu", "--pass-range", "0..1"]));
    succeeds(&render(p, &["-o", "b.exr", "--backend", "cpu", "--pass-range", "1..2"]));
    let before = std::fs::read(p.join("b.exr")).unwrap();
    let out = run(&["merge", "a.exr", "b.exr", "-o", "sub/../b.exr", "--accumulation"], p);
    refused(&out, &["is input 2 of the merge too"]);
    assert!(std::fs::read(p.join("b.exr")).unwrap() == before);
    // diff's heatmap onto a compared image.
    succeeds(&run(&["merge", "a.exr", "b.exr", "-o", "final.png"], p));
    let out = run(&["diff", "a.exr", "b.exr", "--heatmap", "a.exr"], p);
    refused(&out, &["a.exr is the test image too"]);
}

// 5. Messages say what is wrong

#[test]
fn a_malformed_driver_manifest_is_not_called_out_of_memory() {
    let dir = scene_dir();
    std::fs::write(dir.path().join("icd.json"), "{ \"file_format_version\": ").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(["render", "scene.toml", "-o", "out.png", "--backend", "gpu"])
        .current_dir(dir.path())
        .env("VK_DRIVER_FILES", dir.path().join("icd.json"))
        .env("VK_ICD_FILENAMES", dir.path().join("icd.json"))
        .env_remove("PHOTONIX_VALIDATION")
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(!out.status.success(), "{err}");
    // Either the loader skips the bad file (no driver) or it fails parsing it; never "out of memory".
    assert!(!err.contains("out of device memory"), "{err}");
    assert!(err.contains("driver manifest") || err.contains("no Vulkan driver found"), "{err}");
    assert!(err.contains("--backend cpu"), "{err}");
}

// 6. No setting is silently ignored

#[test]
fn validation_setting_takes_the_usual_words_and_refuses_others() {
    use photonix::gpu::parse_switch;
    for on in ["1", "true", "YES", "On", " yes "] {
        assert_eq!(parse_switch(on), Some(true), "{on}");
    }
    for off in ["0", "false", "No", "OFF", ""] {
        assert_eq!(parse_switch(off), Some(false), "{off}");
    }
    for bad in ["2", "maybe", "y", "enabled"] {
        assert_eq!(parse_switch(bad), None, "{bad}");
    }
    let dir = scene_dir();
    for backend in ["gpu", "cpu"] {
        let out = Command::new(env!("CARGO_BIN_EXE_photonix"))
            .args(["render", "scene.toml", "-o", "out.png", "--backend", backend])
            .current_dir(dir.path())
            .env("PHOTONIX_VALIDATION", "maybe")
            .output()
            .unwrap();
        refused(&out, &["PHOTONIX_VALIDATION is `maybe`", "1, true, yes or on"]);
    }
}

#[test]
fn flags_that_would_be_ignored_are_refused() {
    let dir = scene_dir();
    let p = dir.path();
    for (extra, pieces) in [
        (vec!["-o", "out.png", "--backend", "cpu", "--device", "0"], vec!["--device", "--backend cpu"]),
        (vec!["-o", "out.exr", "--exposure", "2"], vec!["--exposure scales PNG output only"]),
        (vec!["-o", "out.png", "--no-photons", "--gather-rays", "2"], vec!["--no-photons", "--gather-rays"]),
    ] {
        refused(&render(p, &extra), &pieces);
    }
    succeeds(&render(p, &["-o", "a.exr", "--backend", "cpu", "--pass-range", "0..1"]));
    refused(&run(&["merge", "a.exr", "-o", "m.exr", "--exposure", "1"], p), &["--exposure scales PNG output only"]);
    // Only a final image is denoised; sums for a later merge are not.
    refused(
        &run(&["merge", "a.exr", "-o", "m.exr", "--accumulation", "--denoise"], p),
        &["--denoise", "--accumulation"],
    );
}

// 7. Smaller

#[test]
fn os_errors_are_told_once() {
    let dir = scene_dir();
    let err = refused(&run(&["render", "nowhere.toml", "-o", "out.png"], dir.path()), &["nowhere.toml"]);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
}

#[test]
fn control_characters_never_reach_the_terminal() {
    let dir = scene_dir();
    let text = SCENE.replace("material = \"white\"", "material = \"wh\\u001b[2Jite\"");
    std::fs::write(dir.path().join("esc.toml"), text).unwrap();
    let err = refused(&run(&["render", "esc.toml", "-o", "out.png"], dir.path()), &["unknown material", "\\u{1b}[2J"]);
    assert!(!err.contains('\u{1b}'), "{err:?}");
    let out = run(&["render", "esc.toml", "-o", "out\u{7}.png", "--contact-sheet", "out\u{7}.png"], dir.path());
    assert!(!stderr(&out).contains('\u{7}'), "{:?}", stderr(&out));
}

#[test]
fn a_png_given_to_merge_or_diff_is_called_a_png() {
    let dir = scene_dir();
    let p = dir.path();
    succeeds(&render(p, &["-o", "a.png", "--backend", "cpu", "--passes", "1"]));
    succeeds(&render(p, &["-o", "b.exr", "--backend", "cpu", "--passes", "1"]));
    for args in [vec!["merge", "a.png", "-o", "m.exr"], vec!["diff", "a.png", "b.exr"], vec!["diff", "b.exr", "a.png"]]
    {
        let err = refused(&run(&args, p), &["a.png is a PNG image, not an EXR"]);
        assert!(!err.contains("identifier"), "{err}");
    }
}
