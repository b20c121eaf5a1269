//! Bad media input: clear errors naming the file, the line and the field, and nothing rendered.

mod common;

use std::io::Write;

use photonix::scene::load_scene;

const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\nfov = 40\n";
const BOUNDARY: &str = "[materials.boundary]\ntype = \"null\"\n";

fn error_of(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
    match load_scene(&path) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, pieces: &[&str]) {
    for piece in pieces {
        assert!(message.contains(piece), "`{piece}` missing from: {message}");
    }
    assert!(!message.ends_with('.'), "trailing period: {message}");
}

fn with_medium(medium: &str) -> String {
    format!("{CAMERA}{BOUNDARY}[media.fog]\n{medium}")
}

#[test]
fn negative_coefficients_are_refused_with_their_line() {
    let message = error_of(&with_medium("sigma_a = [0.1, -0.2, 0.1]\n"));
    assert_mentions(&message, &["bad.toml:8:", "medium \"fog\"", "`sigma_a` is negative"]);
    let message = error_of(&with_medium("sigma_t = -1\n"));
    assert_mentions(&message, &["bad.toml:8:", "`sigma_t` is negative"]);
    let message = error_of(&with_medium("sigma_t = 1\nalbedo = 1.5\n"));
    assert_mentions(&message, &["bad.toml:9:", "`albedo` is above 1"]);
}

#[test]
fn asymmetry_outside_minus_one_to_one_is_refused() {
    for g in ["1", "-1", "1.5"] {
        let message = error_of(&with_medium(&format!("sigma_s = 1\nphase = \"henyey-greenstein\"\ng = {g}\n")));
        assert_mentions(&message, &["bad.toml:10:", "`g` is", "strictly between -1 and 1"]);
    }
    let message = error_of(&with_medium("sigma_s = 1\nphase = \"isotropic\"\ng = 0.5\n"));
    assert_mentions(&message, &["bad.toml:10:", "`g` needs `phase = \"henyey-greenstein\"`"]);
    let message = error_of(&with_medium("sigma_s = 1\nphase = \"rayleigh\"\n"));
    assert_mentions(&message, &["bad.toml:9:", "unknown phase \"rayleigh\""]);
}

#[test]
fn conflicting_or_missing_coefficients_are_refused() {
    let message = error_of(&with_medium("sigma_t = 1\nsigma_a = 0.5\n"));
    assert_mentions(&message, &["bad.toml:8:", "not both"]);
    let message = error_of(&with_medium("phase = \"isotropic\"\n"));
    assert_mentions(&message, &["medium \"fog\"", "needs `sigma_t`"]);
    let message = error_of(&with_medium("sigma_s = [1, 0, 1]\nemission = 2\n"));
    assert_mentions(&message, &["bad.toml:9:", "`emission`", "no extinction"]);
}

#[test]
fn a_medium_on_an_open_shape_is_refused() {
    let shape = "[[shapes]]\ntype = \"quad\"\nmaterial = \"boundary\"\ninterior = \"fog\"\n\
                 vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]\n";
    let message = error_of(&format!("{}{shape}", with_medium("sigma_t = 1\n")));
    assert_mentions(&message, &["bad.toml:12:", "shape 0", "a medium needs a closed shape", "a quad"]);
    let cylinder = "[[shapes]]\ntype = \"cylinder\"\nmaterial = \"boundary\"\ninterior = \"fog\"\n\
                    base = [0, 0, 0]\ncap = [0, 1, 0]\nradius = 1\nopen = true\n";
    let message = error_of(&format!("{}{cylinder}", with_medium("sigma_t = 1\n")));
    assert_mentions(&message, &["an open cylinder"]);
}

#[test]
fn an_open_mesh_cannot_hold_a_medium() {
    let dir = tempfile::tempdir().unwrap();
    // A box with its top missing: ten triangles, eight edges on one triangle only.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
               f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 4 1 5\nf 4 5 8\n";
    std::fs::write(dir.path().join("open.obj"), obj).unwrap();
    let text = format!(
        "{}[[shapes]]\ntype = \"mesh\"\nfile = \"open.obj\"\nmaterial = \"boundary\"\ninterior = \"fog\"\n",
        with_medium("sigma_t = 1\n")
    );
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, &text).unwrap();
    let message = load_scene(&path).expect_err("an open mesh").to_string();
    assert_mentions(&message, &["bad.toml:11:", "open.obj", "a medium needs a closed mesh", "edges"]);
}

#[test]
fn unknown_media_are_named_with_a_suggestion() {
    let shape =
        "[[shapes]]\ntype = \"sphere\"\nmaterial = \"boundary\"\ninterior = \"fgo\"\ncenter = [0, 0, 0]\nradius = 1\n";
    let message = error_of(&format!("{}{shape}", with_medium("sigma_t = 1\n")));
    assert_mentions(&message, &["bad.toml:12:", "unknown medium \"fgo\"", "did you mean \"fog\"?"]);
    let message = error_of(&format!("{}[atmosphere]\nmedium = \"smoke\"\n", with_medium("sigma_t = 1\n")));
    assert_mentions(&message, &["[atmosphere]", "unknown medium \"smoke\""]);
    let message = error_of(&format!("{}[media.fog2]\nsigma_t = 1\ncolour = 1\n", with_medium("sigma_t = 1\n")));
    assert_mentions(&message, &["unknown field `colour`"]);
}

#[test]
fn bad_media_write_no_image() {
    // The medium is read before the shapes, so its error comes before the mesh is looked for.
    let text = std::fs::read_to_string(common::repo_path("scenes/cornell-fog.toml")).unwrap();
    let dir = common::scene_dir(&text.replace("albedo = 0.7", "albedo = 0.7\ng = 2"));
    let out = common::photonix(&["render", "scene.toml", "--backend", "cpu", "-o", "out.png"], dir.path());
    assert!(!out.status.success());
    let stderr = common::stderr(&out);
    assert!(stderr.contains("scene.toml:") && stderr.contains("`g`"), "{stderr}");
    assert!(!dir.path().join("out.png").exists(), "an image was written");
}
