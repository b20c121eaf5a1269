//! Issue 25 (hardening, third round), class by class. Files: no command writes over a file the
//! scene reads, read-only outputs are refused, and the editor's server reads nothing outside the
//! scene's folder whatever a model names. Values: image texels checked per role like the same
//! value typed in the scene. Messages that misled. Geometry: concave OBJ faces, vertex colours.
//! End to end through the `photonix` binary, the scene loader and the editor's HTTP API.

mod common;
mod editor_support;

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Output;

use common::stderr;
use photonix::io::{write_image, Image};

/// A floor with an image texture, a mesh whose MTL gives it another image, and an area light.
const SCENE: &str = r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 45
resolution = [8, 6]

[render]
spp = 1
passes = 1

[textures.wood]
type = "image"
file = "wood.png"

[materials.floor]
type = "diffuse"
reflectance = { texture = "wood" }

[materials.white]
type = "diffuse"

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]]

[[shapes]]
type = "mesh"
file = "models/tri.obj"
material = "white"

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2, -0.5], [0.5, 2, -0.5], [0.5, 2, 0.5], [-0.5, 2, 0.5]]
radiance = [5, 5, 5]
"#;

fn png(path: &Path) {
    let mut image = Image::new(2, 2);
    image.pixels.iter_mut().for_each(|p| *p = [0.5, 0.4, 0.3]);
    write_image(path, &image, 0.0).unwrap();
}

/// The scene's folder: scene.toml, wood.png, models/tri.obj with models/tri.mtl naming
/// models/skin.png.
fn scene_dir() -> tempfile::TempDir {
    let dir = common::scene_dir(SCENE);
    let p = dir.path();
    png(&p.join("wood.png"));
    std::fs::create_dir(p.join("models")).unwrap();
    std::fs::write(p.join("models/tri.obj"), "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n")
        .unwrap();
    std::fs::write(p.join("models/tri.mtl"), "newmtl skin\nKd 0.5 0.5 0.5\nmap_Kd skin.png\n").unwrap();
    png(&p.join("models/skin.png"));
    dir
}

fn refused(out: &Output, pieces: &[&str]) -> String {
    let err = stderr(out);
    assert!(!out.status.success(), "expected a refusal, got success: {err}");
    assert!(!err.contains("panicked"), "crash: {err}");
    for p in pieces {
        assert!(err.contains(p), "`{p}` missing from: {err}");
    }
    err
}

fn render(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["render", "scene.toml", "--backend", "cpu", "--no-photons"];
    args.extend(extra);
    common::photonix(&args, dir)
}

#[test]
fn no_command_writes_over_a_file_the_scene_reads() {
    let dir = scene_dir();
    let p = dir.path();
    std::os::unix::fs::symlink(p.join("models/skin.png"), p.join("skin-link.png")).unwrap();
    let originals: Vec<(&str, Vec<u8>)> = ["wood.png", "models/tri.obj", "models/tri.mtl", "models/skin.png"]
        .into_iter()
        .map(|f| (f, std::fs::read(p.join(f)).unwrap()))
        .collect();
    // render -o onto the texture, the MTL's image (by a link and by `..`), and --contact-sheet.
    for output in ["wood.png", "./models/../wood.png", "skin-link.png", "models/skin.png"] {
        refused(&render(p, &["-o", output]), &["a file the scene reads", "give another name"]);
        refused(&render(p, &["-o", "ok.png", "--contact-sheet", output]), &["a file the scene reads"]);
    }
    assert!(!p.join("ok.png").exists(), "refused before rendering");
    // export -o onto a model: its extension must be .glb, so a glTF model read by the scene.
    std::fs::copy(p.join("models/tri.obj"), p.join("tri.obj")).unwrap();
    let out = common::photonix(&["export", "scene.toml", "-o", "models/tri.obj"], p);
    refused(&out, &[".glb"]);
    let glb = p.join("models/tri.glb");
    let ok = common::photonix(&["export", "scene.toml", "-o", "models/tri.glb"], p);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let scene = SCENE.replace("models/tri.obj", "models/tri.glb");
    std::fs::write(p.join("scene2.toml"), scene).unwrap();
    let before = std::fs::read(&glb).unwrap();
    let out = common::photonix(&["export", "scene2.toml", "-o", "models/../models/tri.glb"], p);
    refused(&out, &["a file the scene reads"]);
    assert_eq!(std::fs::read(&glb).unwrap(), before);
    for (f, bytes) in originals {
        assert_eq!(std::fs::read(p.join(f)).unwrap(), bytes, "{f} was changed");
    }
    // A render that writes elsewhere still works.
    let out = render(p, &["-o", "fine.png"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn read_only_outputs_are_refused_and_modes_kept() {
    let dir = scene_dir();
    let p = dir.path();
    png(&p.join("locked.png"));
    std::fs::set_permissions(p.join("locked.png"), std::fs::Permissions::from_mode(0o444)).unwrap();
    let before = std::fs::read(p.join("locked.png")).unwrap();
    refused(&render(p, &["-o", "locked.png"]), &["locked.png", "read-only"]);
    refused(&render(p, &["-o", "x.png", "--contact-sheet", "locked.png"]), &["read-only"]);
    std::fs::write(p.join("locked.glb"), b"x").unwrap();
    std::fs::set_permissions(p.join("locked.glb"), std::fs::Permissions::from_mode(0o444)).unwrap();
    refused(&common::photonix(&["export", "scene.toml", "-o", "locked.glb"], p), &["read-only"]);
    assert_eq!(std::fs::read(p.join("locked.glb")).unwrap(), b"x");
    assert_eq!(std::fs::read(p.join("locked.png")).unwrap(), before);
    let mode = |f: &str| std::fs::metadata(p.join(f)).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode("locked.png"), 0o444);
    // merge and diff write through the same gate.
    let ok = render(p, &["-o", "a.exr", "--pass-range", "0..1"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    std::fs::copy(p.join("a.exr"), p.join("b.exr")).unwrap();
    refused(&common::photonix(&["merge", "a.exr", "-o", "locked.png"], p), &["read-only"]);
    refused(&common::photonix(&["diff", "a.exr", "b.exr", "--heatmap", "locked.png"], p), &["read-only"]);
    // A writable file that is replaced keeps its mode (here, private to its owner).
    png(&p.join("mine.png"));
    std::fs::set_permissions(p.join("mine.png"), std::fs::Permissions::from_mode(0o600)).unwrap();
    let ok = render(p, &["-o", "mine.png"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    assert_eq!(mode("mine.png"), 0o600);
}

#[test]
fn scene_inputs_list_every_file_read() {
    let dir = scene_dir();
    let scene = photonix::scene::load_scene(&dir.path().join("scene.toml")).unwrap();
    let canonical = |f: &str| dir.path().join(f).canonicalize().unwrap();
    for f in ["scene.toml", "wood.png", "models/tri.obj", "models/tri.mtl", "models/skin.png"] {
        assert!(scene.inputs.contains(&canonical(f)), "{f} missing from {:?}", scene.inputs);
    }
    assert_eq!(scene.inputs[0], canonical("scene.toml"));
}

// The editor reads nothing outside the scene's folder

/// A folder `outside` next to the fixture's folder holding `secret.*` files that a model tries
/// to reach; the secret word must never appear in a reply.
const SECRET: &str = "SECRETWORD";

fn outside_files(root: &Path) -> String {
    let outside = root.join("outside");
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(outside.join("secret.mtl"), format!("newmtl {SECRET}\nKd 0.1 0.2 0.3\nmap_Kd {SECRET}.png\n"))
        .unwrap();
    std::fs::write(outside.join("secret.bin"), SECRET.repeat(8)).unwrap();
    png(&outside.join("secret.png"));
    outside.to_string_lossy().into_owned()
}

#[test]
fn the_editor_follows_no_model_reference_out_of_its_folder() {
    let parent = tempfile::tempdir().unwrap();
    let outside = outside_files(parent.path());
    let f = editor_support::Fixture::with(photonix::editor::BackendChoice::Cpu, |o| {
        let folder = parent.path().join("scene");
        std::fs::create_dir(&folder).unwrap();
        o.scene = folder.join("scene.toml");
        std::fs::write(&o.scene, editor_support::SCENE).unwrap();
    });
    let folder = parent.path().join("scene");
    // OBJ imports naming an MTL outside: by `..`, by absolute path, through a link.
    std::os::unix::fs::symlink(format!("{outside}/secret.mtl"), folder.join("link.mtl")).unwrap();
    for mtllib in ["../outside/secret.mtl", &format!("{outside}/secret.mtl"), "link.mtl"] {
        let obj = format!("mtllib {mtllib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl {SECRET}\nf 1 2 3\n");
        let r = f.call("POST", "/api/import?name=m.obj&material=white", obj.as_bytes());
        assert!(!r.text().contains(SECRET) && !r.text().contains("0.1"), "{}", r.text());
        let scene = f.call("GET", "/api/scene", b"").text();
        assert!(!scene.contains(SECRET), "the MTL outside was read: {mtllib}");
    }
    // A glTF inside the folder whose buffer and image lie outside: by `..`, `file:` and a link.
    std::os::unix::fs::symlink(format!("{outside}/secret.bin"), folder.join("link.bin")).unwrap();
    for uri in ["../outside/secret.bin", &format!("file://{outside}/secret.bin"), "link.bin", "../outside/missing.bin"]
    {
        let gltf = serde_json::json!({
            "asset": { "version": "2.0" },
            "buffers": [{ "uri": uri, "byteLength": 36 }],
            "bufferViews": [{ "buffer": 0, "byteLength": 36 }],
            "accessors": [{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                            "min": [0, 0, 0], "max": [1, 1, 1] }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
            "nodes": [{ "mesh": 0 }],
            "scenes": [{ "nodes": [0] }],
        });
        std::fs::write(folder.join("m.gltf"), gltf.to_string()).unwrap();
        let r = f.edit(
            serde_json::json!({ "op": "add", "kind": "shape", "table": { "type": "mesh", "material": "white", "file": "m.gltf" } }),
        );
        assert_eq!(r.status, 422, "{uri}: {}", r.text());
        let text = r.text();
        assert!(text.contains("not inside the scene's folder"), "{uri}: {text}");
        assert!(!text.contains(SECRET) && !text.contains("secret.bin") && !text.contains("missing"), "{uri}: {text}");
    }
    assert!(!f.text().contains("m.gltf"));
}

#[test]
fn a_served_scene_that_names_a_file_outside_is_refused_at_start() {
    let parent = tempfile::tempdir().unwrap();
    let outside = outside_files(parent.path());
    let folder = parent.path().join("scene");
    std::fs::create_dir(&folder).unwrap();
    let text = format!(
        "{}\n[textures.t]\ntype = \"image\"\nfile = \"{outside}/secret.png\"\n",
        editor_support::SCENE.replace("reflectance = [0.7, 0.1, 0.1]", "reflectance = { texture = \"t\" }")
    );
    std::fs::write(folder.join("scene.toml"), &text).unwrap();
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let mut options = photonix::editor::ServeOptions::new(folder.join("scene.toml"));
    options.backend = photonix::editor::BackendChoice::Cpu;
    let e = match runtime.block_on(photonix::editor::Server::start(options)) {
        Ok(_) => panic!("served a scene reading {outside}/secret.png"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("not inside the scene's folder"), "{e}");
    // `photonix render` of the same scene reads it: only the editor is confined.
    assert!(photonix::scene::load_scene(&folder.join("scene.toml")).is_ok());
}

// Texel values are checked per role, with the scene's own words

/// A 2x1 EXR texture whose first texel is `value` (the second a plain 0.5).
fn exr(path: &Path, value: f32) {
    let mut image = Image::new(2, 1);
    image.pixels = vec![[value, 0.5, 0.5], [0.5, 0.5, 0.5]];
    write_image(path, &image, 0.0).unwrap();
}

fn textured(dir: &Path, material: &str) -> Result<photonix::scene::Scene, String> {
    let text = format!(
        "[camera]\nposition = [0, 1, 4]\nlook_at = [0, 0, 0]\nfov = 40\n[textures.t]\ntype = \"image\"\nfile = \"t.exr\"\n\
         [materials.m]\n{material}\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = 1\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\nintensity = 1\n"
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
    photonix::scene::load_scene(&dir.join("s.toml")).map_err(|e| e.to_string())
}

#[test]
fn texel_values_out_of_their_roles_range_are_refused_like_typed_values() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let diffuse = "type = \"diffuse\"\nreflectance = { texture = \"t\" }";
    let emissive = "type = \"diffuse\"\nreflectance = 0.5\nemission = { texture = \"t\" }";
    let rough = "type = \"conductor\"\npreset = \"gold\"\nroughness = { texture = \"t\" }";
    // What the scene says of the same value typed in: the texel's message uses the same words.
    std::fs::write(p.join("typed.toml"), "[camera]\nposition = [0, 1, 4]\nlook_at = [0, 0, 0]\nfov = 40\n[materials.m]\ntype = \"diffuse\"\nreflectance = 3\n").unwrap();
    let typed = photonix::scene::load_scene(&p.join("typed.toml")).unwrap_err().to_string();
    assert!(typed.contains("it is a fraction of light, in [0, 1] per channel"), "{typed}");
    let cases: [(f32, &str, &[&str]); 7] = [
        (
            3.0,
            diffuse,
            &[
                "`reflectance` is 3 at texel (0, 0) of texture \"t\"",
                "it is a fraction of light, in [0, 1] per channel",
            ],
        ),
        (-0.5, diffuse, &["`reflectance` is -0.5", "it must be >= 0 in every channel"]),
        (f32::INFINITY, diffuse, &["`reflectance` is inf", "give finite numbers"]),
        (-2.0, emissive, &["`emission` is -2", "it must be >= 0 in every channel"]),
        (f32::INFINITY, emissive, &["`emission` is inf", "give finite numbers"]),
        (1.5, rough, &["`roughness` is 1.5 at texel (0, 0)", "a GGX alpha in [0, 1]"]),
        (f32::NEG_INFINITY, rough, &["`roughness` is -inf"]),
    ];
    for (value, material, pieces) in cases {
        exr(&p.join("t.exr"), value);
        let e = textured(p, material).expect_err(&format!("{value} accepted in {material}"));
        for piece in pieces {
            assert!(e.contains(piece), "{value} in {material}: `{piece}` missing from {e}");
        }
        assert!(e.contains("s.toml:"), "no location: {e}");
    }
    // In range: accepted (an emission of 3 is fine, a reflectance of 1 too).
    exr(&p.join("t.exr"), 3.0);
    assert!(textured(p, emissive).is_ok());
    exr(&p.join("t.exr"), 1.0);
    assert!(textured(p, diffuse).is_ok());
    // NaN means nothing: taken as 0, with a warning, as the environment map does.
    exr(&p.join("t.exr"), f32::NAN);
    let scene = textured(p, diffuse).unwrap();
    assert!(
        scene.warnings.iter().any(|w| w.contains("1 texel channels of the image are NaN; they are taken as 0")),
        "{:?}",
        scene.warnings
    );
    let photonix::scene::TextureKind::Image { image, .. } = &scene.textures[0].kind else { panic!("an image") };
    assert_eq!(image.texels[0][0], 0.0);
}

// Messages that misled

#[test]
fn a_truncated_glb_is_reported_at_its_end_without_the_gltf_1_hint() {
    let dir = scene_dir();
    let p = dir.path();
    let ok = common::photonix(&["export", "scene.toml", "-o", "whole.glb"], p);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let bytes = std::fs::read(p.join("whole.glb")).unwrap();
    for cut in [bytes.len() - 7, bytes.len() / 2, 30, 9] {
        std::fs::write(p.join("cut.glb"), &bytes[..cut]).unwrap();
        let e = photonix::scene::model::load_model(&p.join("cut.glb"), &Default::default()).unwrap_err().to_string();
        assert!(e.contains("byte ") && e.contains("truncated"), "cut at {cut}: {e}");
        assert!(!e.contains("1.0"), "cut at {cut}: {e}");
    }
    // A real glTF 1.0 file still gets the hint.
    std::fs::write(p.join("old.gltf"), r#"{"asset": {"version": "1.0"}, "meshes": {}}"#).unwrap();
    let e = photonix::scene::model::load_model(&p.join("old.gltf"), &Default::default()).unwrap_err().to_string();
    assert!(e.contains("glTF 1.0 file"), "{e}");
}

#[test]
fn editor_errors_say_what_is_wrong_and_are_json() {
    let f = editor_support::Fixture::new();
    // A budget of 1e300 s is positive: it is too long.
    let r = f.call("POST", "/api/render", br#"{"seconds": 1e300}"#);
    assert_eq!(r.status, 409, "{}", r.text());
    let e = r.json()["error"].as_str().unwrap().to_string();
    assert!(e.contains("1e300 s, more than the longest") && !e.contains("positive"), "{e}");
    let r = f.call("POST", "/api/render", br#"{"seconds": -1}"#);
    assert!(r.json()["error"].as_str().unwrap().contains("positive"), "{}", r.text());
    // Bodies over the limit: 413, as JSON like every other error.
    let big = format!(r#"{{"op":"set","target":"camera","field":"fov","value":"{}"}}"#, "x".repeat(2 << 20));
    let r = f.call("POST", "/api/edit", big.as_bytes());
    assert_eq!(r.status, 413);
    assert_eq!(r.header("content-type"), Some("application/json"), "{}", r.text());
    assert_eq!(r.json()["ok"], false);
    assert!(r.json()["error"].as_str().unwrap().contains("too large"), "{}", r.text());
}

// Geometry read right

#[test]
fn a_ring_drawn_as_one_obj_face_keeps_its_hole() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    // A 4x4 square with a 2x2 hole as one face (outer loop, a bridge, the hole backwards), in the
    // plane y = 0 facing up; vertex colours on every `v` line.
    let obj = "v 0 0 0 1 0 0\nv 4 0 0 1 0 0\nv 4 0 -4 1 0 0\nv 0 0 -4 1 0 0\n\
               v 1 0 -1 1 0 0\nv 1 0 -3 1 0 0\nv 3 0 -3 1 0 0\nv 3 0 -1 1 0 0\n\
               f 1 2 3 4 1 5 6 7 8 5\n";
    std::fs::write(p.join("ring.obj"), obj).unwrap();
    let text = "[camera]\nposition = [2, 5, 2]\nlook_at = [2, 0, -2]\nfov = 40\n[materials.m]\ntype = \"diffuse\"\n\
                [[shapes]]\ntype = \"mesh\"\nfile = \"ring.obj\"\nmaterial = \"m\"\n\
                [[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\nintensity = 1\n";
    std::fs::write(p.join("s.toml"), text).unwrap();
    let scene = photonix::scene::load_scene(&p.join("s.toml")).unwrap();
    let tris: Vec<_> = scene.triangles().map(|(t, _)| t.vertices).collect();
    let area: f32 = tris.iter().map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length()).sum();
    assert!((area - 12.0).abs() < 1e-4, "the ring covers {area}, not 16 - 4 = 12");
    let hole = glam::Vec3::new(2.0, 0.0, -2.0);
    for [a, b, c] in &tris {
        let n = (*b - *a).cross(*c - *a);
        assert!(n.y > 0.0, "a triangle turned over: {n}");
        let inside = [(a, b), (b, c), (c, a)].iter().all(|(u, v)| (**v - **u).cross(hole - **u).dot(n) > 0.0);
        assert!(!inside, "a triangle covers the hole");
    }
    assert!(
        scene.warnings.iter().any(|w| w.contains("vertices carry colours") && w.contains("does not use")),
        "{:?}",
        scene.warnings
    );
    assert!(!scene.warnings.iter().any(|w| w.contains("zero area")), "{:?}", scene.warnings);
}

#[test]
fn scene_messages_point_at_the_fault_and_quote_cleanly() {
    // Dotted keys nested thousands deep: the parser gives no place; the message points at the
    // deepest key (line 3 here), not at 1:1.
    let deep = format!("[camera]\nfov = 40\na{} = 1\n", ".a".repeat(3000));
    let e = photonix::scene::parse_scene(&deep, Path::new("deep.toml")).unwrap_err().to_string();
    assert!(e.starts_with("deep.toml:3:"), "{e}");
    assert!(e.contains("nested too deeply"), "{e}");
    // A missing field's example is quoted whole: backticks in pairs.
    let spot = "[camera]\nposition = [0, 1, 4]\nlook_at = [0, 0, 0]\nfov = 40\n\
                [[lights]]\ntype = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -1, 0]\nintensity = 1\n";
    let e = photonix::scene::parse_scene(spot, Path::new("spot.toml")).unwrap_err().to_string();
    assert!(e.contains("missing field `outer_angle`"), "{e}");
    assert_eq!(e.matches('`').count() % 2, 0, "a stray backtick: {e}");
}

// Twins at scale: a pass lavapipe would get wrong is refused

/// `benches/instancing/frames-1500.toml`: 1500 overlapping hollow frames in a closed room.
/// Photon paths of 48 bounces through the stack run past lavapipe's 65535 loop iterations per
/// invocation; lavapipe broke them off and its image came out 38% darker than the CPU backend's
/// (relMSE 0.19). The kernel now counts paths whose loop ended with its condition still true, and
/// the pass is refused with a message that says why and what to do. With 4 bounces the two
/// backends agree as usual.
#[test]
fn photon_paths_lavapipe_would_break_off_are_refused_not_rendered_dark() {
    let path = common::repo_path("benches/instancing/frames-1500.toml");
    let scene = photonix::scene::load_scene(&path).unwrap();
    let buffers = common::buffers(&scene, 8, 6);
    let mut photons = scene.photons.expect("the scene has photons");
    let ctx = common::gpu();
    let render = |p: &photonix::render::PhotonSettings| {
        photonix::render::gpu::render_gpu(&ctx, &buffers, 1, Some(p), 0, &mut |_, _| {})
    };
    match render(&photons) {
        // A real GPU has no such limit and renders the pass; lavapipe must refuse it.
        Ok(_) => assert!(!ctx.info().name.contains("llvmpipe"), "lavapipe rendered paths it broke off"),
        Err(e) => {
            let e = e.to_string();
            assert!(e.contains("broke off") && e.contains("--backend cpu"), "{e}");
        }
    }
    photons.max_depth = 4;
    let gpu = render(&photons).expect("short paths stay within the limit");
    let cpu = common::cpu_render(&buffers, 1, &photons);
    let error = photonix::io::metrics::rel_mse(&gpu.image, &cpu.image);
    println!("frames, 4 bounces: GPU vs CPU relMSE {error:.3e}");
    assert!(error < 1e-6, "relMSE {error:.3e}");
}
