//! The importers on files that real tools wrote: the Open Asset Import Library's test models
//! (Debian's `assimp-testmodels`, installed by ci/setup; a few copied under tests/models/assimp,
//! see its LICENSE.md). Valid ones import with the geometry they hold and render; broken ones
//! give an error naming the file, and nothing panics on any file of a format Photonix reads.

mod common;

use std::path::{Path, PathBuf};

use photonix::scene::load_scene;
use photonix::scene::model::{load_model, mesh_triangles, LoadOptions, Model, Shading};

const ASSIMP_MODELS: &str = "/usr/share/assimp/models";

fn copied(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/assimp").join(name)
}

fn triangles(model: &Model) -> usize {
    let shading = Shading { file_normals: true, smooth_angle_deg: 30.0 };
    model.meshes.iter().map(|m| mesh_triangles(m, shading).len()).sum()
}

/// A scene with one mesh shape from `file` (absolute), lit by a point light, seen from +z.
fn mesh_scene(file: &Path, extra: &str) -> String {
    format!(
        r#"
[camera]
position = [0, 1, 6]
look_at = [0, 0, 0]
fov = 40
resolution = [24, 24]

[photons]
enabled = false

[[shapes]]
type = "mesh"
file = "{}"
{extra}

[[lights]]
type = "point"
position = [2, 4, 6]
intensity = 40
"#,
        file.display()
    )
}

#[test]
fn files_from_real_exporters_import_with_their_geometry() {
    // (file, triangles): cubes from several exporters, a textured glTF box in both containers,
    // a concave OBJ polygon and a 3DS scene of several objects.
    let cases = [
        ("cube.ply", 12),
        ("cube_binary.ply", 12),
        ("cube_uv.ply", 12),
        ("float-color.ply", 1),
        ("box.obj", 12),
        ("cube_usemtl.obj", 12),
        ("concave_polygon.obj", 64),
        ("BoxTextured.glb", 12),
        ("BoxTextured-glTF/BoxTextured.gltf", 12),
        ("cube_with_diffuse_texture.3DS", 12),
        ("test1.3ds", 108),
    ];
    let mut failures = Vec::new();
    for (name, expected) in cases {
        let path = copied(name);
        let model = load_model(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let n = triangles(&model);
        let finite = model.meshes.iter().all(|m| m.positions.iter().all(|p| p.is_finite()));
        println!("{name}: {} meshes, {n} triangles, {} materials", model.meshes.len(), model.materials.len());
        if (expected > 0 && n != expected) || n == 0 || !finite {
            failures.push(format!("{name}: {n} triangles (expected {expected}), finite {finite}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn file_materials_reach_the_scene_and_an_imported_model_renders() {
    // cube_usemtl.obj gives its faces MTL materials of different colours; BoxTextured its
    // base-colour texture. Without `material` in the scene the file's apply.
    // The 3DS cube is in the exporter's units, about 90 across and off the origin.
    let turn = "transform = { scale = 1.2, rotate = [20, 30, 0] }";
    for (name, transform) in [
        ("cube_usemtl.obj", turn),
        ("BoxTextured.glb", turn),
        ("cube_with_diffuse_texture.3DS", "transform = { scale = 0.025, translate = [1.5, -0.42, 1.08] }"),
        ("cube_uv.ply", turn),
    ] {
        let dir = common::scene_dir(&mesh_scene(&copied(name), transform));
        let scene = load_scene(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(scene.shapes.len() >= 12, "{name}: {} shapes", scene.shapes.len());
        let (mut lo, mut hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        for s in &scene.shapes {
            if let photonix::scene::Geometry::Triangle(t) = &s.geometry {
                for v in t.vertices {
                    (lo, hi) = (lo.min(v), hi.max(v));
                }
            }
        }
        println!("{name}: bounds {lo} {hi}");
        let buffers = common::buffers(&scene, 24, 24);
        let image = common::cpu_image(&buffers, 1);
        let lit =
            (0..24).flat_map(|y| (0..24).map(move |x| (x, y))).filter(|&(x, y)| image.pixel(x, y)[0] > 0.0).count();
        println!("{name}: {} shapes, {} materials, {lit} lit pixels", scene.shapes.len(), scene.materials.len());
        assert!(lit > 20, "{name}: the model is in the picture");
    }
}

#[test]
fn broken_files_give_an_error_naming_the_file() {
    // (file, what the message must say): empty files, a glTF whose indices run past its
    // vertices, one whose buffer file is missing, and a box with infinite positions.
    let cases = [
        ("empty.obj", "no triangles"),
        ("empty.ply", "empty.ply"),
        ("empty.3ds", "empty.3ds"),
        ("IndexOutOfRange.gltf", "index"),
        ("MissingBin.gltf", "BoxTextured0.bin"),
        ("BoxWithInfinites.glb", "not a valid glTF"),
        // Deliberately odd numbers: `3.1+e2` is none.
        ("number_formats.obj", "number_formats.obj:11"),
        // Blender's export of assimp issue 623: face lists declared on the vertex element.
        ("issue623.ply", "not a whole number"),
    ];
    for (name, expected) in cases {
        let dir = common::scene_dir(&mesh_scene(
            &copied(name),
            "material = \"white\"\n\n[materials.white]\ntype = \"diffuse\"\nreflectance = 0.8",
        ));
        let out = dir.path().join("out.png");
        let err = match load_scene(&dir.path().join("scene.toml")) {
            Ok(_) => panic!("{name} imported"),
            Err(e) => e.to_string(),
        };
        println!("{name}: {err}");
        assert!(err.contains(name.rsplit('/').next().unwrap()), "{name}: the message names the file: {err}");
        assert!(err.to_lowercase().contains(&expected.to_lowercase()), "{name}: the message says {expected:?}: {err}");
        assert!(!out.exists());
    }
}

/// Every file of a format Photonix reads in the installed test set imports or gives an error;
/// none panics (the broken ones are there to try importers).
#[test]
fn no_file_in_assimp_testmodels_panics_an_importer() {
    let root = Path::new(ASSIMP_MODELS);
    assert!(root.is_dir(), "{ASSIMP_MODELS} is missing: run ci/setup (it installs assimp-testmodels)");
    let mut files = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap().flatten() {
            let p = entry.path();
            if p.is_dir() {
                dirs.push(p);
            } else if photonix::scene::model::Format::from_path(&p).is_some()
                && entry.metadata().map(|m| m.len() < 4 << 20).unwrap_or(false)
            {
                files.push(p);
            }
        }
    }
    files.sort();
    let (mut ok, mut errors, mut panics) = (0, 0, Vec::new());
    for p in &files {
        let result = std::panic::catch_unwind(|| {
            load_model(p, &LoadOptions::default()).map(|m| {
                let n = triangles(&m);
                (n, m.meshes.iter().all(|m| m.positions.iter().all(|p| p.is_finite())))
            })
        });
        match result {
            Ok(Ok((_, finite))) => {
                assert!(finite, "{}: imported with non-finite positions", p.display());
                ok += 1
            }
            Ok(Err(e)) => {
                let message = e.to_string();
                println!("{message}");
                let file = p.file_name().unwrap().to_string_lossy().to_string();
                assert!(message.contains(&file), "the error names the file: {message}");
                errors += 1
            }
            Err(_) => panics.push(p.display().to_string()),
        }
    }
    println!("{} files: {ok} imported, {errors} refused with an error, {} panicked", files.len(), panics.len());
    assert!(files.len() > 90, "the test set has its files");
    assert!(panics.is_empty(), "importers panicked on {panics:#?}");
}
