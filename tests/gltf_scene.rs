//! Whole glTF 2.0 scenes (scene::gltf_scene, docs/gltf.md): a scene exported by Blender renders
//! with its own camera, lights and materials; hand-written files check the node hierarchy, the
//! camera chosen when the file has none, orthographic cameras, the light units, emissive
//! strength and the warnings that name what is not read.

mod common;

use std::path::Path;

use glam::Vec3;
use photonix::scene::{load_scene, LightKind, Projection};

fn close(a: f32, b: f32, tolerance: f32) -> bool {
    (a - b).abs() <= tolerance
}

/// Mean colour of the pixels within `r` of (x, y), as fractions of the image size.
fn mean(img: &image::RgbImage, x: f32, y: f32, r: u32) -> [f32; 3] {
    let (cx, cy) = ((x * img.width() as f32) as i64, (y * img.height() as f32) as i64);
    let mut sum = [0.0f32; 3];
    let mut n = 0.0;
    for dy in -(r as i64)..=r as i64 {
        for dx in -(r as i64)..=r as i64 {
            let p = img.get_pixel((cx + dx) as u32, (cy + dy) as u32);
            for c in 0..3 {
                sum[c] += p[c] as f32;
            }
            n += 1.0;
        }
    }
    sum.map(|s| s / n)
}

#[test]
fn blender_scene_renders_with_its_camera_lights_and_materials() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("scene.glb");
    let start = std::time::Instant::now();
    common::blender_export(&glb);
    println!("blender export: {:.1} s", start.elapsed().as_secs_f32());

    // The camera: Blender's (0, -4.5, 1.6) z-up is glTF's (0, 1.6, 4.5); a 35 mm lens on the
    // 36 mm sensor fitted to the width of a 16:9 image: yfov = 2 atan(18 / 35 / (16 / 9)).
    let scene = load_scene(&glb).unwrap();
    let c = &scene.camera;
    assert_eq!((c.width, c.height), (640, 360));
    assert_eq!(c.projection, Projection::Perspective);
    let yfov = 2.0 * (18.0f32 / 35.0 / (16.0 / 9.0)).atan().to_degrees();
    assert!(close(c.fov_deg, yfov, 0.01), "fov {} against {yfov}", c.fov_deg);
    assert!((c.position - Vec3::new(0.0, 1.6, 4.5)).length() < 1e-4, "{:?}", c.position);
    // It looks at Blender's (0, 0, 0.5), glTF's (0, 0.5, 0).
    let forward = (c.look_at - c.position).normalize();
    let expected = (Vec3::new(0.0, 0.5, 0.0) - c.position).normalize();
    assert!(forward.dot(expected) > 0.9999, "{forward} against {expected}");

    // The lights, in W/sr and W/m^2: Blender's watts over 4 pi (its exporter writes candela as
    // W / (4 pi) * 683), its sun's 2 W/m^2.
    assert_eq!(scene.lights.len(), 3, "{:?}", scene.lights);
    let mut kinds = [0; 3];
    for light in &scene.lights {
        match light.kind {
            LightKind::Point { position, intensity } => {
                kinds[0] += 1;
                assert!((position - Vec3::new(-2.0, 3.0, 2.0)).length() < 1e-4);
                assert!(close(intensity.x, 300.0 / (4.0 * std::f32::consts::PI), 1e-3), "{intensity}");
            }
            LightKind::Spot { intensity, cos_outer, .. } => {
                kinds[1] += 1;
                assert!(close(intensity.x, 400.0 / (4.0 * std::f32::consts::PI), 1e-3), "{intensity}");
                // Blender's spot_size is the full cone, 50 degrees.
                assert!(close(cos_outer, 25f32.to_radians().cos(), 1e-4), "{cos_outer}");
            }
            LightKind::Distant { irradiance, .. } => {
                kinds[2] += 1;
                assert!(close(irradiance.x, 2.0, 1e-4), "{irradiance}");
            }
            LightKind::Area { .. } => panic!("no area lights in the file"),
        }
    }
    assert_eq!(kinds, [1, 1, 1]);
    // The emissive material: colour times Blender's emission strength 4 (KHR_materials_emissive_strength).
    let glow = scene.material_names.iter().position(|n| n.ends_with("Glow")).expect("the Glow material");
    let e = scene.materials[glow].emission.value;
    assert!((e - Vec3::new(4.0, 3.6, 2.4)).length() < 1e-3, "{e}");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);

    // Render it small: each object lands where Blender's camera sees it (red ball left, gold
    // cube right, the glowing cube between them at the back, black sky above).
    let out = common::photonix(
        &[
            "render",
            "scene.glb",
            "--backend",
            "cpu",
            "--resolution",
            "160x90",
            "--spp",
            "2",
            "--passes",
            "1",
            "-o",
            "out.png",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", common::stderr(&out));
    let img = image::open(dir.path().join("out.png")).unwrap().to_rgb8();
    std::fs::create_dir_all(common::repo_path("target/gltf-scene")).unwrap();
    img.save(common::repo_path("target/gltf-scene/blender.png")).unwrap();
    let ball = mean(&img, 0.31, 0.47, 3);
    let cube = mean(&img, 0.70, 0.50, 3);
    let glow = mean(&img, 0.50, 0.46, 1);
    let sky = mean(&img, 0.5, 0.05, 3);
    println!("ball {ball:?} cube {cube:?} glow {glow:?} sky {sky:?}");
    assert!(ball[0] > 60.0 && ball[0] > 2.0 * ball[1] && ball[0] > 2.0 * ball[2], "ball {ball:?}");
    assert!(cube[0] > 40.0 && cube[0] > 1.3 * cube[2], "gold cube {cube:?}");
    assert!(glow.iter().all(|&v| v > 200.0), "glowing cube {glow:?}");
    assert!(sky.iter().all(|&v| v < 5.0), "sky {sky:?}");

    // Converted to TOML beside it, the same scene loads from the TOML.
    let out = common::photonix(&["convert", "scene.glb", "-o", "scene.toml"], dir.path());
    assert!(out.status.success(), "{}", common::stderr(&out));
    assert!(common::stderr(&out).contains("3 lights"), "{}", common::stderr(&out));
    let toml = load_scene(&dir.path().join("scene.toml")).unwrap();
    assert_eq!(toml.lights.len(), 3);
    assert_eq!(toml.shapes.len(), scene.shapes.len());
    assert_eq!(toml.camera.position, scene.camera.position);
}

/// A .gltf with its buffer beside it: one quad (two triangles) in the xy plane, 1 x 1 around
/// the origin, in a child node scaled 2x under a parent moved by (10, 0, 0); `extra` is spliced
/// into the top-level JSON (cameras, lights, extensions).
fn write_gltf(dir: &Path, nodes: &str, extra: &str, material: &str) -> std::path::PathBuf {
    let positions: [[f32; 3]; 4] = [[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("quad.bin"), &bin).unwrap();
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{nodes}],
  "meshes": [{{"name": "quad", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{material}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
  "buffers": [{{"uri": "quad.bin", "byteLength": 60}}]{extra}
}}"#
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn gltf_node_transforms_compose_and_a_scene_without_camera_is_framed() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(
        dir.path(),
        r#"{"translation": [10, 0, 0], "children": [1]}, {"scale": [2, 2, 2], "mesh": 0},
           {"translation": [10, 0, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
        r#", "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_clearcoat"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 1366, "range": 5}]}},
  "animations": []"#,
        r#"{"name": "lit", "emissiveFactor": [1, 0.5, 0.25],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}, "KHR_materials_clearcoat": {"clearcoatFactor": 1}}}"#,
    );
    // The light node is not under the root scene's node 0; add it to the scene.
    let text = std::fs::read_to_string(&path).unwrap().replace(r#""nodes": [0]}"#, r#""nodes": [0, 2]}"#);
    std::fs::write(&path, text).unwrap();
    let scene = load_scene(&path).unwrap();

    // The quad: scaled 2x about its node, then moved to x = 10: corners at 9..11.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for (t, _) in scene.triangles() {
        for v in t.vertices {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    assert!((lo - Vec3::new(9.0, -1.0, 0.0)).length() < 1e-5 && (hi - Vec3::new(11.0, 1.0, 0.0)).length() < 1e-5);

    // No camera: one that sees the whole box, looking at its centre, and a warning saying so.
    let c = &scene.camera;
    assert!((c.look_at - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-4, "{:?}", c.look_at);
    let half_fov = (c.fov_deg * 0.5).to_radians();
    let distance = (c.position - c.look_at).length();
    assert!(distance * half_fov.sin() >= 2f32.sqrt(), "the bounding sphere (radius sqrt 2) fits the view");
    let warnings = scene.warnings.join("\n");
    assert!(warnings.contains("no camera"), "{warnings}");
    // Unsupported things are named; supported extensions are not.
    assert!(warnings.contains("KHR_materials_clearcoat"), "{warnings}");
    assert!(!warnings.contains("KHR_materials_emissive_strength"), "{warnings}");
    assert!(warnings.contains("`range` 5 is ignored"), "{warnings}");

    // Emission: the factor times emissiveStrength.
    let e = scene.materials[scene.triangles().next().unwrap().1 as usize].emission.value;
    assert!((e - Vec3::new(8.0, 4.0, 2.0)).length() < 1e-5, "{e}");
    // The point light: 1366 cd is 2 W/sr.
    match scene.lights[0].kind {
        LightKind::Point { position, intensity } => {
            assert!((position - Vec3::new(10.0, 0.0, 3.0)).length() < 1e-5);
            assert!((intensity - Vec3::splat(2.0)).length() < 1e-5, "{intensity}");
        }
        ref k => panic!("{k:?}"),
    }
}

#[test]
fn gltf_orthographic_camera_and_spot_cone_angles_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(
        dir.path(),
        r#"{"mesh": 0, "children": [1, 2]}, {"translation": [0, 0, 5], "camera": 0},
           {"translation": [0, 0, 2], "extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
        r#", "extensionsUsed": ["KHR_lights_punctual"],
  "cameras": [{"type": "orthographic", "orthographic": {"xmag": 2, "ymag": 1, "znear": 0.1, "zfar": 100}}],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 683, "color": [1, 0.5, 0],
      "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}]}}"#,
        r#"{"name": "plain"}"#,
    );
    let scene = load_scene(&path).unwrap();
    let c = &scene.camera;
    // view_height = 2 ymag; the aspect xmag / ymag = 2 sets the image size.
    assert_eq!(c.projection, Projection::Orthographic { view_height: 2.0 });
    assert_eq!((c.width, c.height), (720, 360));
    assert!((c.position - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-6);
    assert!((c.look_at - c.position).normalize().dot(Vec3::NEG_Z) > 0.99999);
    match scene.lights[0].kind {
        LightKind::Spot { direction, intensity, cos_inner, cos_outer, .. } => {
            assert!(direction.dot(Vec3::NEG_Z) > 0.99999, "{direction}");
            assert!((intensity - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-5, "{intensity}");
            assert!(close(cos_inner, 0.1f32.cos(), 1e-5) && close(cos_outer, 0.5f32.cos(), 1e-5));
        }
        ref k => panic!("{k:?}"),
    }
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn a_damaged_gltf_scene_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.glb");
    std::fs::write(&path, b"glTF\x02\x00\x00\x00\xff\x00\x00\x00").unwrap();
    let e = load_scene(&path).unwrap_err().to_string();
    assert!(e.contains("broken.glb") && e.contains("truncated"), "{e}");
}

#[test]
fn khr_texture_transform_moves_the_uvs_of_its_material() {
    // A quad with uvs (0, 0) .. (1, 1) and a texture whose transform takes the right half:
    // offset (0.5, 0), scale (0.5, 1), so u' = 0.5 + 0.5 u; v' = v, then glTF's v flips to 1 - v.
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_fn(2, 1, |x, _| if x == 0 { image::Rgb([255, 0, 0]) } else { image::Rgb([0, 0, 255]) })
        .save(dir.path().join("half.png"))
        .unwrap();
    let positions: [[f32; 3]; 4] = [[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.path().join("quad.bin"), &bin).unwrap();
    let json = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_texture_transform"],
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
  "materials": [{"name": "half", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
      "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [0.5, 1]}}}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "half.png"}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
  ],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
  "buffers": [{"uri": "quad.bin", "byteLength": 92}]
}"#;
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = load_scene(&path).unwrap();
    let mut us = Vec::new();
    for (t, _) in scene.triangles() {
        let uv = t.uv.expect("the file's uvs");
        for (p, q) in t.vertices.iter().zip(uv) {
            // Corner x = -0.5 had u = 0, x = 0.5 had u = 1; y = -0.5 had glTF v = 1, so v = 0.
            assert!(close(q.x, 0.5 + 0.5 * (p.x + 0.5), 1e-6), "{p} -> {q}");
            assert!(close(q.y, p.y + 0.5, 1e-6), "{p} -> {q}");
            us.push(q.x);
        }
    }
    assert!(us.iter().all(|u| (0.5..=1.0).contains(u)), "{us:?}");
    assert!(scene.warnings.iter().all(|w| !w.contains("KHR_texture_transform")), "{:?}", scene.warnings);
}

/// KHR_materials_transmission (with _ior): the material is a mix of its opaque form and glass of
/// its index, by the transmission factor; the volume's attenuation is warned about.
#[test]
fn gltf_transmission_becomes_glass_of_the_materials_index() {
    use photonix::scene::MaterialKind;
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(
        dir.path(),
        r#"{"mesh": 0}"#,
        r#", "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]"#,
        r#"{"name": "bottle", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 0,
            "roughnessFactor": 0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.75},
                           "KHR_materials_ior": {"ior": 1.33},
                           "KHR_materials_volume": {"attenuationColor": [0.5, 0.8, 1], "attenuationDistance": 2}}}"#,
    );
    let scene = load_scene(&path).unwrap();
    let m = &scene.materials[scene.triangles().next().unwrap().1 as usize];
    let MaterialKind::Mix { b, weight, .. } = &m.kind else { panic!("{:?}", m.kind) };
    assert!((weight.value - 0.75).abs() < 1e-6, "{weight:?}");
    match &scene.materials[*b as usize].kind {
        MaterialKind::Dielectric { ior, roughness } => {
            assert!((ior - 1.33).abs() < 1e-6, "{ior}");
            assert_eq!(roughness.alpha, [0.0; 2]);
        }
        k => panic!("{k:?}"),
    }
    let warnings = scene.warnings.join("\n");
    assert!(warnings.contains("KHR_materials_volume") && warnings.contains("bottle"), "{warnings}");
    assert!(!warnings.contains("render opaque"), "{warnings}");
}
