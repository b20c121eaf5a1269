//! The glTF 2.0 export (`photonix export`, the editor's *Download glTF*), read back with the
//! `gltf` crate: meshes per entry, vertex counts, bounds, materials' colours, the camera; the
//! editor's download is the same file; bad input gets a clear error and no output file.

mod editor_support;

use std::path::Path;
use std::process::Command;

use editor_support::{Fixture, SCENE};
use photonix::editor::gltf::scene_glb;
use photonix::editor::SceneDocument;

/// A mesh's name, vertex positions and material name.
type Mesh = (String, Vec<[f32; 3]>, String);

/// Every mesh read back from `bytes`.
fn read_back(bytes: &[u8]) -> (gltf::Gltf, Vec<Mesh>) {
    let file = gltf::Gltf::from_slice(bytes).expect("a valid glTF binary");
    let blob = file.blob.clone().expect("a binary chunk");
    let mut meshes = Vec::new();
    for mesh in file.document.meshes() {
        for primitive in mesh.primitives() {
            let reader = primitive.reader(|_| Some(&blob[..]));
            let positions: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            // The accessor's bounds are the data's (glTF requires them for positions).
            let bounds = primitive.bounding_box();
            for axis in 0..3 {
                let lo = positions.iter().map(|p| p[axis]).fold(f32::INFINITY, f32::min);
                let hi = positions.iter().map(|p| p[axis]).fold(f32::NEG_INFINITY, f32::max);
                assert_eq!((bounds.min[axis], bounds.max[axis]), (lo, hi), "{:?}", mesh.name());
            }
            let material = primitive.material().name().unwrap_or("").to_string();
            meshes.push((mesh.name().unwrap_or("").to_string(), positions, material));
        }
    }
    (file, meshes)
}

fn scene_file(dir: &Path, text: &str) -> std::path::PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn export_reads_back_with_the_scenes_geometry_materials_and_camera() {
    let dir = tempfile::tempdir().unwrap();
    let doc = SceneDocument::load(&scene_file(dir.path(), SCENE)).unwrap();
    let bytes = scene_glb(&doc).unwrap();
    let (file, meshes) = read_back(&bytes);
    let names: Vec<&str> = meshes.iter().map(|m| m.0.as_str()).collect();
    assert_eq!(names, ["floor", "ball", "block", "lamp"]);
    let count = |name: &str| meshes.iter().find(|m| m.0 == name).unwrap().1.len();
    // Two triangles of a quad, twelve of a box, two of the lamp's quad; the ball tessellated
    // as the solid view draws it.
    assert_eq!((count("floor"), count("block"), count("lamp")), (6, 36, 6));
    let page = photonix::editor::geometry::scene_json(&doc);
    assert_eq!(count("ball") * 3, page["shapes"][1]["positions"].as_array().unwrap().len());
    assert!(count("ball") > 500, "{}", count("ball"));

    // Bounds: the floor spans x and z in [-2, 2], the lamp is at y = 2; the block is turned by
    // 30 degrees about y and moved 1 along x; the ball's vertices lie on its sphere.
    let all: Vec<[f32; 3]> = meshes.iter().flat_map(|m| m.1.iter().copied()).collect();
    for axis in 0..3 {
        let lo = all.iter().map(|p| p[axis]).fold(f32::INFINITY, f32::min);
        let hi = all.iter().map(|p| p[axis]).fold(f32::NEG_INFINITY, f32::max);
        let want = [[-2.0, 2.0], [0.0, 2.0], [-2.0, 2.0]][axis];
        assert!((lo - want[0]).abs() < 1e-5 && (hi - want[1]).abs() < 1e-5, "axis {axis}: {lo}..{hi}");
    }
    let block = &meshes.iter().find(|m| m.0 == "block").unwrap().1;
    let max_x = block.iter().map(|p| p[0]).fold(f32::NEG_INFINITY, f32::max);
    let turned = 1.0 + 0.25 * (30f32.to_radians().cos() + 30f32.to_radians().sin());
    assert!((max_x - turned).abs() < 1e-5, "{max_x} vs {turned}");
    let ball = &meshes.iter().find(|m| m.0 == "ball").unwrap().1;
    for p in ball {
        let r = (p[0] * p[0] + (p[1] - 0.5) * (p[1] - 0.5) + p[2] * p[2]).sqrt();
        assert!((r - 0.5).abs() < 1e-5, "{p:?}");
    }

    // Materials: the scene's names and colours; the lamp emits with its radiance as strength.
    let material = |mesh: &str| meshes.iter().find(|m| m.0 == mesh).unwrap().2.clone();
    assert_eq!(
        (material("floor"), material("ball"), material("block")),
        ("white".into(), "red".into(), "white".into())
    );
    let find = |name: &str| file.document.materials().find(|m| m.name() == Some(name)).unwrap();
    assert_eq!(find("red").pbr_metallic_roughness().base_color_factor(), [0.7, 0.1, 0.1, 1.0]);
    assert_eq!(find("white").pbr_metallic_roughness().base_color_factor(), [0.7, 0.7, 0.7, 1.0]);
    assert_eq!(find("red").pbr_metallic_roughness().metallic_factor(), 0.0);
    let lamp = file.document.materials().find(|m| m.name() == Some(material("lamp").as_str())).unwrap();
    assert_eq!(lamp.emissive_factor(), [1.0, 1.0, 1.0]);
    assert_eq!(lamp.emissive_strength(), Some(5.0));
    // Glass is used by no shape, so it is not exported.
    assert_eq!(file.document.materials().count(), 3);

    // The camera: 45 degrees vertically, at (0, 1, 4), looking at (0, 0.5, 0).
    let camera = file.document.cameras().next().expect("a camera");
    let gltf::camera::Projection::Perspective(p) = camera.projection() else { panic!("not perspective") };
    assert!((p.yfov() - 45f32.to_radians()).abs() < 1e-6);
    assert!((p.aspect_ratio().unwrap() - 1.5).abs() < 1e-6);
    let node = file.document.nodes().find(|n| n.camera().is_some()).unwrap();
    let (t, r, _) = node.transform().decomposed();
    assert_eq!(t, [0.0, 1.0, 4.0]);
    // Its -z (the direction a glTF camera looks) points at look_at.
    let q = glam::Quat::from_array(r);
    let look = q * glam::Vec3::NEG_Z;
    let want = (glam::Vec3::new(0.0, 0.5, 0.0) - glam::Vec3::new(0.0, 1.0, 4.0)).normalize();
    assert!((look - want).length() < 1e-5, "{look} vs {want}");
}

#[test]
fn glass_and_metal_materials_export_their_gltf_counterparts() {
    let text = SCENE.replace("material = \"red\"", "material = \"glass\"").replace(
        "[materials.glass]",
        "[materials.gold]\ntype = \"conductor\"\npreset = \"gold\"\nroughness = 0.04\n\n[materials.glass]",
    );
    let text = text.replacen("material = \"white\"\nmin", "material = \"gold\"\nmin", 1);
    let dir = tempfile::tempdir().unwrap();
    let doc = SceneDocument::load(&scene_file(dir.path(), &text)).unwrap();
    let (file, _) = read_back(&scene_glb(&doc).unwrap());
    let glass = file.document.materials().find(|m| m.name() == Some("glass")).unwrap();
    assert_eq!(glass.ior(), Some(1.5));
    assert_eq!(glass.transmission().map(|t| t.transmission_factor()), Some(1.0));
    let gold = file.document.materials().find(|m| m.name() == Some("gold")).unwrap();
    let pbr = gold.pbr_metallic_roughness();
    assert_eq!(pbr.metallic_factor(), 1.0);
    assert!((pbr.roughness_factor() - 0.2).abs() < 1e-6, "{}", pbr.roughness_factor());
    let [r, g, b, _] = pbr.base_color_factor();
    // Gold reflects red and green more than blue.
    assert!(r > 0.9 && g > 0.6 && b < 0.5, "{r} {g} {b}");
}

#[test]
fn the_editors_download_is_the_same_file() {
    let f = Fixture::new();
    let r = f.call("GET", "/api/scene.glb", b"");
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.header("content-type"), Some("model/gltf-binary"));
    assert!(r.header("content-disposition").unwrap().contains("scene.glb"));
    let doc = SceneDocument::load(&f.scene).unwrap();
    assert_eq!(r.body, scene_glb(&doc).unwrap());
    // An edit shows in the next download.
    let moved = f.edit(serde_json::json!({ "op": "set_transform", "target": { "shape": 1 }, "translate": [0, 3, 0] }));
    assert_eq!(moved.status, 200, "{}", moved.text());
    let (_, meshes) = read_back(&f.call("GET", "/api/scene.glb", b"").body);
    let top = meshes[1].1.iter().map(|p| p[1]).fold(f32::NEG_INFINITY, f32::max);
    assert!((top - 4.0).abs() < 1e-5, "{top}");
    // Without the token: refused.
    let r = editor_support::http(f.addr(), "GET", "/api/scene.glb", &[], b"");
    assert_eq!(r.status, 401);
}

#[test]
fn photonix_export_writes_a_glb_and_refuses_bad_input_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), SCENE);
    let out = dir.path().join("out.glb");
    let run = |args: &[&Path]| Command::new(env!("CARGO_BIN_EXE_photonix")).arg("export").args(args).output().unwrap();
    let o = run(&[&scene, Path::new("-o"), &out]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doc = SceneDocument::load(&scene).unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), scene_glb(&doc).unwrap());

    // Not .glb: named, with the fix.
    let wrong = dir.path().join("out.gltf");
    let o = run(&[&scene, Path::new("-o"), &wrong]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("out.gltf") && err.contains(".glb"), "{err}");
    assert!(!wrong.exists());

    // A broken scene: the parser's message with file and line, and no output.
    let broken = dir.path().join("broken.toml");
    std::fs::write(&broken, SCENE.replace("radius = 0.5", "radius = -1")).unwrap();
    let none = dir.path().join("none.glb");
    let o = run(&[&broken, Path::new("-o"), &none]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("broken.toml:") && err.contains("radius"), "{err}");
    assert!(!none.exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 3, "{leftovers:?}");
}

#[test]
fn instances_export_as_one_mesh_per_object_and_one_node_per_copy() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{SCENE}{}", editor_support::INSTANCES);
    let doc = SceneDocument::load(&scene_file(dir.path(), &text)).unwrap();
    let (file, meshes) = read_back(&scene_glb(&doc).unwrap());
    // The post once in object space (box white, ball red), and once more in the glass the fence
    // gives it; the CSG box as a shape, world space.
    let mesh_names: Vec<String> = file.document.meshes().map(|m| m.name().unwrap_or("").to_string()).collect();
    assert_eq!(mesh_names, ["floor", "ball", "block", "cut box", "lamp", "post", "post (glass)"]);
    let post: Vec<&Mesh> = meshes.iter().filter(|m| m.0 == "post").collect();
    assert_eq!(post.iter().map(|m| m.2.as_str()).collect::<Vec<_>>(), ["white", "red"]);
    assert_eq!(post[0].1.len(), 36);
    let top = post[1].1.iter().map(|p| p[1]).fold(f32::NEG_INFINITY, f32::max);
    assert!((top - 1.2).abs() < 1e-5, "{top}");
    let glass: Vec<&Mesh> = meshes.iter().filter(|m| m.0 == "post (glass)").collect();
    assert_eq!(glass.len(), 1);
    assert_eq!(glass[0].1.len(), post[0].1.len() + post[1].1.len());

    // One node per [[instances]] entry, one child per copy with its world_from_object.
    let node = |name: &str| file.document.nodes().find(|n| n.name() == Some(name)).unwrap();
    let children = |name: &str| -> Vec<([f32; 3], String)> {
        node(name)
            .children()
            .map(|c| (c.transform().decomposed().0, c.mesh().unwrap().name().unwrap().to_string()))
            .collect()
    };
    assert_eq!(children("single"), [([3.0, 0.0, 0.0], "post".to_string())]);
    let fence = children("fence");
    assert_eq!(fence.len(), 6);
    for (k, (t, mesh)) in fence.iter().enumerate() {
        let want = [-1.5 + 0.5 * (k % 3) as f32, 0.0, -1.5 + (k / 3) as f32];
        assert!((0..3).all(|a| (t[a] - want[a]).abs() < 1e-5), "{k}: {t:?} vs {want:?}");
        assert_eq!(mesh, "post (glass)");
    }
    let pairs = children("pairs");
    assert_eq!(pairs.len(), 2);
    for (t, z) in pairs.iter().map(|p| p.0).zip([1.2, 1.8]) {
        assert!(t[0].abs() < 1e-5 && (t[2] - z).abs() < 1e-5, "{t:?}");
    }
    // The scene lists the entries, the instance groups and the camera; the copies hang below.
    let roots: Vec<&str> = file.document.scenes().next().unwrap().nodes().map(|n| n.name().unwrap()).collect();
    assert_eq!(roots, ["floor", "ball", "block", "cut box", "lamp", "single", "fence", "pairs", "camera"]);
}
