//! The `photonix` command end to end: renders that write files, and bad input that must fail
//! with a clear message, a non-zero exit and no output file.

mod common;

use std::path::Path;
use std::process::{Command, Output};

const SCENE: &str = r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 45
resolution = [24, 16]

[render]
spp = 2

[photons]
count = 2000
caustic_count = 2000
gather_rays = 2

[materials.white]
type = "diffuse"
reflectance = [0.7, 0.7, 0.7]

[materials.glass]
type = "dielectric"
ior = 1.5

[[shapes]]
type = "quad"
material = "white"
vertices = [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]]

[[shapes]]
type = "sphere"
material = "glass"
center = [0, 0.5, 0]
radius = 0.5

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

/// A failed run: non-zero exit, no panic, the message pieces present, and no file written.
fn assert_fails(out: &Output, pieces: &[&str], dir: &Path, never_written: &str) {
    let err = stderr(out);
    assert!(!out.status.success(), "expected failure, got success: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for p in pieces {
        assert!(err.contains(p), "`{p}` missing from: {err}");
    }
    assert!(!dir.join(never_written).exists(), "{never_written} was written");
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn renders_png_exr_layers_and_contact_sheet_on_both_backends() {
    let dir = scene_dir();
    for backend in ["gpu", "cpu"] {
        let out = common::photonix(
            &["render", "scene.toml", "--backend", backend, "-o", &format!("{backend}.png")],
            dir.path(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(stderr(&out).contains("rays/s"), "summary line: {}", stderr(&out));
        let png = image::open(dir.path().join(format!("{backend}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (24, 16));
    }
    let out = common::photonix(
        &["render", "scene.toml", "--backend", "gpu", "-o", "layers.exr", "--layers", "--contact-sheet", "sheet.png"],
        dir.path(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let layers = exr::prelude::read_all_flat_layers_from_file(dir.path().join("layers.exr")).unwrap();
    let names: Vec<String> =
        layers.layer_data.iter().map(|l| l.attributes.layer_name.as_ref().unwrap().to_string()).collect();
    assert_eq!(
        names,
        ["combined", "direct", "specular", "indirect", "caustics", "albedo", "normal", "depth", "position"]
    );
    let sheet = image::open(dir.path().join("sheet.png")).unwrap();
    assert_eq!(sheet.width(), 4 * 24 + 3 * 4);
    // The diff tool compares the two backends' images.
    let out = common::photonix(&["render", "scene.toml", "-o", "a.exr", "--backend", "gpu"], dir.path());
    assert!(out.status.success());
    let out = common::photonix(&["render", "scene.toml", "-o", "b.exr", "--backend", "cpu"], dir.path());
    assert!(out.status.success());
    let out = common::photonix(&["diff", "a.exr", "b.exr", "--heatmap", "heat.png"], dir.path());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("relMSE") && text.contains("mean ratio"), "{text}");
    assert!(dir.path().join("heat.png").exists());
}

#[test]
fn unwritable_output_fails_before_rendering() {
    let dir = scene_dir();
    let out = common::photonix(&["render", "scene.toml", "-o", "missing/out.png"], dir.path());
    assert_fails(&out, &["missing/out.png", "cannot write output"], dir.path(), "missing");
    // Nothing was rendered: the failure comes before any summary line.
    assert!(!stderr(&out).contains("rays/s"));
    let out = common::photonix(&["render", "scene.toml", "-o", "out.jpg"], dir.path());
    assert_fails(&out, &["out.jpg", ".exr", ".png"], dir.path(), "out.jpg");
}

#[test]
fn bad_scene_reports_file_and_line() {
    let dir = scene_dir();
    std::fs::write(dir.path().join("bad.toml"), SCENE.replace("radius = 0.5", "radius = -0.5")).unwrap();
    let out = common::photonix(&["render", "bad.toml", "-o", "out.png"], dir.path());
    assert_fails(&out, &["bad.toml:33", "radius"], dir.path(), "out.png");
    let out = common::photonix(&["render", "nowhere.toml", "-o", "out.png"], dir.path());
    assert_fails(&out, &["nowhere.toml"], dir.path(), "out.png");
}

#[test]
fn bad_photon_settings_are_refused() {
    let dir = scene_dir();
    for (args, pieces) in [
        (vec!["--photons", "0"], vec!["--photons", "from 1 to 1000000000"]),
        (vec!["--radius", "-1"], vec!["--radius", "positive"]),
        (vec!["--radius", "NaN"], vec!["--radius"]),
        (vec!["--layers"], vec!["--layers", ".exr"]),
    ] {
        let mut all = vec!["render", "scene.toml", "-o", "out.png"];
        all.extend(args);
        let out = common::photonix(&all, dir.path());
        assert_fails(&out, &pieces, dir.path(), "out.png");
    }
    std::fs::write(dir.path().join("zero.toml"), SCENE.replace("count = 2000\ncaustic", "count = 0\ncaustic")).unwrap();
    let out = common::photonix(&["render", "zero.toml", "-o", "out.png"], dir.path());
    assert_fails(&out, &["zero.toml:", "count", "at least 1"], dir.path(), "out.png");
}

#[test]
fn zero_power_light_warns() {
    let dir = scene_dir();
    std::fs::write(dir.path().join("dark.toml"), SCENE.replace("radiance = [5, 5, 5]", "radiance = [0, 0, 0]"))
        .unwrap();
    let out = common::photonix(&["render", "dark.toml", "-o", "out.png", "--backend", "cpu"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("warning:") && stderr(&out).contains("emits nothing"), "{}", stderr(&out));
}

#[test]
fn missing_vulkan_driver_says_what_to_install() {
    let dir = scene_dir();
    let without_driver = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_photonix"))
            .args(args)
            .current_dir(dir.path())
            .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
            .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
            .env_remove("PHOTONIX_VALIDATION")
            .output()
            .unwrap()
    };
    let out = without_driver(&["render", "scene.toml", "-o", "out.png", "--backend", "gpu"]);
    assert_fails(&out, &["mesa-vulkan-drivers", "--backend cpu"], dir.path(), "out.png");
    // The default (auto) renders on the CPU backend instead, and says why.
    let out = without_driver(&["render", "scene.toml", "-o", "out.png"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("cpu backend (auto: no Vulkan driver found)"), "{}", stderr(&out));
    assert!(dir.path().join("out.png").exists());
}

#[test]
fn auto_backend_says_which_backend_ran_and_why() {
    let dir = scene_dir();
    let out = common::photonix(&["render", "scene.toml", "-o", "out.png"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let devices = photonix::gpu::list_devices();
    let (backend, why) = photonix::render::auto_backend(&devices, false);
    let expected = format!("{} backend (auto: {why})", backend.name());
    assert!(stderr(&out).contains(&expected), "`{expected}` missing from: {}", stderr(&out));
    let out = common::photonix(&["render", "scene.toml", "-o", "out.png", "--backend", "gpu"], dir.path());
    assert!(stderr(&out).contains("gpu backend (--backend gpu)"), "{}", stderr(&out));
}

#[test]
fn same_seed_gives_identical_bytes() {
    let dir = scene_dir();
    for name in ["one.exr", "two.exr"] {
        let out = common::photonix(&["render", "scene.toml", "-o", name, "--backend", "gpu"], dir.path());
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let read = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
    assert!(read("one.exr") == read("two.exr"), "two GPU renders with one seed differ");
}
