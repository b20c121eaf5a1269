//! Bad materials, textures and images give an error that names the file, the line and the field,
//! and suggests the fix; an image too large for the device is refused before rendering.

mod common;

use std::io::Write;
use std::path::PathBuf;

use photonix::scene::load_scene;

const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\nfov = 40\n";

fn write_scene(dir: &tempfile::TempDir, text: &str) -> PathBuf {
    let path = dir.path().join("bad.toml");
    std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
    path
}

fn error_of(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    match load_scene(&write_scene(&dir, text)) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, pieces: &[&str]) {
    for piece in pieces {
        assert!(message.contains(piece), "`{piece}` missing from: {message}");
    }
}

#[test]
fn unknown_material_type_suggests_the_closest() {
    let m = error_of(&format!("{CAMERA}[materials.m]\ntype = \"conductr\"\n"));
    assert_mentions(&m, &["bad.toml:6:", "material \"m\"", "did you mean \"conductor\"?"]);
}

#[test]
fn unknown_texture_and_pattern_and_preset_suggest_the_closest() {
    let texture = "[textures.check]\ntype = \"pattern\"\npattern = \"checker\"\n";
    let m = error_of(&format!(
        "{CAMERA}{texture}[materials.m]\ntype = \"diffuse\"\nreflectance = {{ texture = \"chek\" }}\n"
    ));
    assert_mentions(&m, &["bad.toml:10:", "unknown texture \"chek\"", "did you mean \"check\"?"]);
    let m = error_of(&format!("{CAMERA}[textures.t]\ntype = \"pattern\"\npattern = \"wod\"\n"));
    assert_mentions(&m, &["bad.toml:7:", "texture \"t\"", "unknown pattern \"wod\"", "did you mean \"wood\"?"]);
    let m = error_of(&format!("{CAMERA}[materials.m]\ntype = \"conductor\"\npreset = \"gld\"\n"));
    assert_mentions(&m, &["bad.toml:7:", "did you mean \"gold\"?"]);
}

#[test]
fn out_of_range_roughness_and_ior_are_refused() {
    let m = error_of(&format!("{CAMERA}[materials.m]\ntype = \"conductor\"\npreset = \"gold\"\nroughness = 1.5\n"));
    assert_mentions(&m, &["bad.toml:8:", "`roughness` is 1.5", "[0, 1]"]);
    let m = error_of(&format!("{CAMERA}[materials.m]\ntype = \"dielectric\"\nior = 200\n"));
    assert_mentions(&m, &["bad.toml:7:", "`ior` is 200", "from 0.01 to 100"]);
    let m = error_of(&format!("{CAMERA}[materials.m]\ntype = \"conductor\"\neta = [0, 1, 1]\nk = 1\n"));
    assert_mentions(&m, &["bad.toml:7:", "`eta`", "> 0"]);
}

#[test]
fn color_map_out_of_order_is_refused() {
    let text = format!(
        "{CAMERA}[textures.t]\ntype = \"pattern\"\npattern = \"wood\"\ncolor_map = [[0.8, [1, 0, 0]], [0.6, [0, 1, 0]]]\n"
    );
    let m = error_of(&text);
    assert_mentions(&m, &["bad.toml:8:", "texture \"t\"", "`color_map`", "in order"]);
}

#[test]
fn missing_or_unsupported_image_names_the_file() {
    let m = error_of(&format!("{CAMERA}[textures.t]\ntype = \"image\"\nfile = \"nowhere.png\"\n"));
    assert_mentions(&m, &["bad.toml:7:", "texture \"t\"", "nowhere.png", "cannot read"]);

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("notes.png"), "this is text, not a picture").unwrap();
    let path = write_scene(&dir, &format!("{CAMERA}[textures.t]\ntype = \"image\"\nfile = \"notes.png\"\n"));
    let m = load_scene(&path).unwrap_err().to_string();
    assert_mentions(&m, &["bad.toml:7:", "notes.png"]);
}

#[test]
fn image_larger_than_one_binding_renders_on_the_device() {
    // 4096 x 4096 texels of 8 bytes are 128 MiB, one header more than lavapipe binds in one
    // storage buffer: the texture array takes two pages (docs/limits.md) instead of a refusal.
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::new(4096, 4096).save(dir.path().join("huge.png")).unwrap();
    let scene = format!(
        "{CAMERA}[textures.t]\ntype = \"image\"\nfile = \"huge.png\"\n[materials.m]\ntype = \"diffuse\"\n\
         reflectance = {{ texture = \"t\" }}\n[[shapes]]\ntype = \"quad\"\nmaterial = \"m\"\n\
         vertices = [[-1, 0, -1], [1, 0, -1], [1, 2, -1], [-1, 2, -1]]\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 1, 2]\nintensity = 1\n"
    );
    write_scene(&dir, &scene);
    let args = [
        "render",
        "bad.toml",
        "--backend",
        "gpu",
        "--integrator",
        "pt",
        "--resolution",
        "8x8",
        "--spp",
        "1",
        "-o",
        "out.png",
    ];
    let out = common::photonix(&args, dir.path());
    assert!(out.status.success(), "a 128 MiB texture was refused: {}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.path().join("out.png").exists(), "no image was written");
}
