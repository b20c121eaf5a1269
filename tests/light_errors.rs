//! Bad lights and cameras give an error that names the file, the line and the field, and
//! suggests the fix.

use std::io::Write;
use std::path::PathBuf;

use photonix::scene::{load_scene, Scene};

const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\nfov = 40\n";

fn write_scene(dir: &tempfile::TempDir, text: &str) -> PathBuf {
    let path = dir.path().join("bad.toml");
    std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
    path
}

fn load(text: &str) -> Result<Scene, String> {
    let dir = tempfile::tempdir().unwrap();
    load_scene(&write_scene(&dir, text)).map_err(|e| e.to_string())
}

fn error_of(text: &str) -> String {
    match load(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

fn assert_mentions(message: &str, pieces: &[&str]) {
    for piece in pieces {
        assert!(message.contains(piece), "`{piece}` missing from: {message}");
    }
}

const SPOT: &str =
    "[[lights]]\nname = \"key\"\ntype = \"spot\"\nposition = [0, 3, 0]\npoint_at = [0, 0, 0]\nintensity = 10\n";

#[test]
fn spot_outer_angle_below_inner_says_which_to_change() {
    let m = error_of(&format!("{CAMERA}{SPOT}inner_angle = 30\nouter_angle = 20\n"));
    assert_mentions(
        &m,
        &[
            "bad.toml:12:",
            "light 0 (\"key\")",
            "`outer_angle` (20) is below `inner_angle` (30)",
            "raise `outer_angle` to at least 30 or lower `inner_angle`",
        ],
    );
    // POV-Ray's spelling names its own fields.
    let m = error_of(&format!("{CAMERA}{SPOT}radius = 40\nfalloff = 25\n"));
    assert_mentions(&m, &["bad.toml:12:", "`falloff` (25) is below `radius` (40)"]);
    // Falloff alone keeps POV-Ray's default radius of 30.
    let m = error_of(&format!("{CAMERA}{SPOT}falloff = 25\n"));
    assert_mentions(&m, &["`falloff` (25) is below `radius` (30)"]);
}

#[test]
fn spot_angles_and_spellings_are_checked() {
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angle = 120\n"));
    assert_mentions(&m, &["bad.toml:11:", "`outer_angle` is 120", "(0, 90]"]);
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angle = 0\n"));
    assert_mentions(&m, &["`outer_angle` is 0", "(0, 90]"]);
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angle = 30\nfalloff = 40\n"));
    assert_mentions(&m, &["not both"]);
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angle = 30\ntightness = -1\n"));
    assert_mentions(&m, &["bad.toml:12:", "`tightness` is -1"]);
    let m = error_of(&format!("{CAMERA}{SPOT}"));
    assert_mentions(&m, &["bad.toml:5:", "missing field `outer_angle`"]);
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angle = 30\ndirection = [0, -1, 0]\n"));
    assert_mentions(&m, &["bad.toml:9:", "give `direction` or `point_at`, not both"]);
    let m = error_of(&format!("{CAMERA}[[lights]]\ntype = \"spot\"\nposition = [0, 3, 0]\ndirection = [0, 0, 0]\nintensity = 1\nouter_angle = 30\n"));
    assert_mentions(&m, &["bad.toml:8:", "`direction` is zero"]);
    // A typo gets a suggestion, a synonym from another renderer too.
    let m = error_of(&format!("{CAMERA}{SPOT}outer_angel = 30\n"));
    assert_mentions(&m, &["bad.toml:11:", "unknown field `outer_angel`", "did you mean `outer_angle`?"]);
    let m = error_of(&format!("{CAMERA}{SPOT}cutoff_angle = 30\n"));
    assert_mentions(&m, &["did you mean `outer_angle`?"]);
}

#[test]
fn distant_light_fields_are_checked() {
    let distant = "[[lights]]\ntype = \"distant\"\ndirection = [0, -1, 0]\n";
    let m = error_of(&format!("{CAMERA}{distant}"));
    assert_mentions(&m, &["bad.toml:5:", "missing field `irradiance`", "irradiance = 3"]);
    let m = error_of(&format!("{CAMERA}{distant}irradiance = 1\nangular_diameter = 100\n"));
    assert_mentions(&m, &["bad.toml:9:", "`angular_diameter` is 100", "[0, 90]", "0.53"]);
    let m = error_of(&format!("{CAMERA}{distant}irradiance = 1\nposition = [0, 1, 0]\n"));
    assert_mentions(&m, &["bad.toml:9:", "`position` does not apply to a distant light"]);
    let m = error_of(&format!("{CAMERA}{distant}irradiance = 1\ndirect = false\nphotons = false\n"));
    assert_mentions(&m, &["bad.toml:9:", "`direct = false` and `photons = false`"]);
    let m = error_of(&format!("{CAMERA}[[lights]]\ntype = \"directional\"\n"));
    assert_mentions(&m, &["bad.toml:6:", "did you mean \"distant\"?"]);
}

#[test]
fn aperture_without_focus_says_what_to_add() {
    let m = error_of(&format!("{CAMERA}aperture_radius = 0.1\n"));
    assert_mentions(
        &m,
        &["bad.toml:5:", "[camera]", "`aperture_radius` needs a plane in focus", "focal_distance = 5", "focal_point"],
    );
    let m = error_of(&format!("{CAMERA}aperture = 0.4\n"));
    assert_mentions(&m, &["bad.toml:5:", "`aperture` needs a plane in focus"]);
    let m = error_of(&format!("{CAMERA}f_number = 2.8\nfocal_distance = 5\n"));
    assert_mentions(&m, &["bad.toml:5:", "`f_number` needs the lens's `focal_length`"]);
    let m = error_of(&format!("{CAMERA}aperture_radius = 0.1\nf_number = 2\nfocal_distance = 5\n"));
    assert_mentions(&m, &["bad.toml:6:", "not both `aperture_radius` and `f_number`"]);
    let m = error_of(&format!("{CAMERA}aperture_radius = 0.1\nfocal_distance = 5\nfocal_point = [0, 1, 0]\n"));
    assert_mentions(&m, &["bad.toml:7:", "give `focal_distance` or `focal_point`, not both"]);
    let m = error_of(&format!("{CAMERA}aperture_radius = 0.1\nfocal_point = [0, 1, 9]\n"));
    assert_mentions(&m, &["bad.toml:6:", "not in front of the camera"]);
    let m = error_of(&format!("{CAMERA}aperture_radius = 0.1\nfocal_distance = 5\naperture_blades = 2\n"));
    assert_mentions(&m, &["bad.toml:7:", "`aperture_blades` is 2", "0 (a round aperture) or 3 to 64"]);
    let m = error_of(&format!("{CAMERA}aperture_radius = -1\nfocal_distance = 5\n"));
    assert_mentions(&m, &["bad.toml:5:", "`aperture_radius` is -1; it must be > 0"]);
}

#[test]
fn camera_types_take_their_own_fields() {
    let m = error_of("[camera]\ntype = \"orthographic\"\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\nfov = 40\n");
    assert_mentions(&m, &["bad.toml:5:", "`fov` does not apply to an orthographic camera", "`view_height`"]);
    let m = error_of("[camera]\ntype = \"orthographic\"\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n");
    assert_mentions(&m, &["bad.toml:1:", "missing field `view_height`"]);
    let m = error_of("[camera]\ntype = \"latlong\"\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\naperture_radius = 1\n");
    assert_mentions(&m, &["bad.toml:5:", "`aperture_radius` does not apply to a latlong camera"]);
    let m = error_of("[camera]\ntype = \"equirectangular\"\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\n");
    assert_mentions(&m, &["bad.toml:2:", "did you mean \"latlong\"?"]);
}

#[test]
fn focus_without_aperture_warns_and_blur_samples_raise_spp() {
    let scene = load(&format!("{CAMERA}focal_distance = 5\n")).unwrap();
    assert!(scene.camera.lens.is_none());
    assert!(
        scene.warnings.iter().any(|w| w.contains("bad.toml:5:") && w.contains("`focal_distance` has no effect")),
        "{:?}",
        scene.warnings
    );
    // POV-Ray's blur_samples over the default 4 passes: 37 lens samples need 10 spp per pass.
    let scene = load(&format!("{CAMERA}aperture = 0.4\nfocal_distance = 5\nblur_samples = 37\n")).unwrap();
    let lens = scene.camera.lens.expect("a thin lens");
    assert_eq!((lens.radius, lens.focal_distance, scene.render.spp), (0.1, 5.0, 10));
}

#[test]
fn environment_errors_name_the_field_and_the_fix() {
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"map\"\nfile = \"nowhere/sky.hdr\"\n"));
    assert_mentions(
        &m,
        &["bad.toml:7:", "[environment]", "`file`", "nowhere/sky.hdr", "cannot read", "relative to the scene file"],
    );
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"map\"\n"));
    assert_mentions(&m, &["bad.toml:5:", "missing field `file`", "file = \"textures/sky.hdr\""]);
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"skye\"\n"));
    assert_mentions(&m, &["bad.toml:6:", "unknown type \"skye\"", "did you mean \"sky\"?"]);
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"uniform\"\nradiance = 1\nstrength = -2\n"));
    assert_mentions(&m, &["bad.toml:8:", "`strength` is -2", ">= 0"]);
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"gradient\"\ncolors = [[1, 1, 1]]\n"));
    assert_mentions(&m, &["bad.toml:7:", "at least 2 colours"]);
    let m = error_of(&format!(
        "{CAMERA}[environment]\ntype = \"gradient\"\ncolors = [[1, 1, 1], [0, 0, 1]]\nelevations = [40, 10]\n"
    ));
    assert_mentions(&m, &["bad.toml:8:", "`elevations` is [40, 10]", "increasing"]);
    let m = error_of(&format!("{CAMERA}[environment]\ntype = \"uniform\"\nradiance = 1\nfile = \"sky.hdr\"\n"));
    assert_mentions(&m, &["bad.toml:8:", "`file` does not apply to a uniform environment"]);
}
