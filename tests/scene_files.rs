//! The scene files in `scenes/` load with the geometry their references describe.

use std::path::Path;

use glam::Vec3;
use photonix::scene::{load_scene, ColorParam, LightDesc, LightKind, MaterialKind, Scene};

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn winding_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0]).normalize()
}

#[test]
fn cornell_box_has_16_quads_and_its_light() {
    let scene = load("cornell-box.toml");
    assert_eq!(scene.name, "cornell-box");
    assert_eq!(scene.triangles().count(), 32, "16 quads, light included");
    assert_eq!(scene.spheres().count(), 0);
    // Its only light is the area light of [[lights]], whose options are kept with its material.
    assert!(matches!(scene.lights[..], [LightDesc { kind: LightKind::Area { .. }, direct: true, photons: true }]));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!((scene.camera.width, scene.camera.height), (256, 256));
    assert_eq!(scene.camera.fov_deg, 39.307648);
    assert_eq!(scene.camera.position, Vec3::new(278.0, 273.0, -800.0));
    assert_eq!((scene.render.spp, scene.render.passes, scene.render.max_depth), (2, 4, 16));

    // The light is the last quad: black, emitting (17, 12, 4), facing down.
    let emitting: Vec<_> = scene.triangles().filter(|(_, m)| scene.materials[*m as usize].emits()).collect();
    assert_eq!(emitting.len(), 2);
    for (t, material) in emitting {
        let m = &scene.materials[material as usize];
        assert_eq!(m.emission.value, Vec3::new(17.0, 12.0, 4.0));
        assert_eq!(m.kind, MaterialKind::Diffuse { reflectance: ColorParam::constant(Vec3::ZERO) });
        assert!(winding_normal(&t.vertices).abs_diff_eq(Vec3::NEG_Y, 1e-6));
    }
}

#[test]
fn cornell_quads_keep_their_vertex_order() {
    let scene = load("cornell-box.toml");
    // Floor [v0..v3] = (552.8,0,0) (0,0,0) (0,0,559.2) (549.6,0,559.2): triangles (v0,v1,v2),
    // (v0,v2,v3), winding normal +y (into the box).
    let (v0, v1, v2, v3) =
        (Vec3::new(552.8, 0.0, 0.0), Vec3::ZERO, Vec3::new(0.0, 0.0, 559.2), Vec3::new(549.6, 0.0, 559.2));
    let triangles: Vec<_> = scene.triangles().collect();
    assert_eq!(triangles[0].0.vertices, [v0, v1, v2]);
    assert_eq!(triangles[1].0.vertices, [v0, v2, v3]);
    assert!(winding_normal(&triangles[0].0.vertices).abs_diff_eq(Vec3::Y, 1e-6));
    // The red wall's normal points into the box (-x), per the reference.
    let red = scene.material_names.iter().position(|n| n == "red").unwrap() as u32;
    let (wall, _) = scene.triangles().find(|(_, m)| *m == red).unwrap();
    assert!(winding_normal(&wall.vertices).x < -0.99);
}

#[test]
fn cornell_caustics_has_6_quads_and_2_spheres() {
    let scene = load("cornell-caustics.toml");
    assert_eq!(scene.triangles().count(), 12);
    let spheres: Vec<_> = scene.spheres().collect();
    assert_eq!(spheres.len(), 2);
    let kind = |s: usize| &scene.materials[spheres[s].1 as usize].kind;
    assert_eq!(kind(0), &MaterialKind::Dielectric { ior: 1.5, roughness: photonix::scene::Roughness::SMOOTH });
    assert_eq!(kind(1), &MaterialKind::Mirror { tint: ColorParam::constant(Vec3::ONE) });
    assert_eq!(spheres[0].0.center, Vec3::new(370.0, 90.0, 170.0));
    assert_eq!(spheres[1].0.radius, 90.0);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn showcase_uses_every_feature() {
    let scene = load("showcase.toml");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // floor 2 + wall 2 + mirror 2 + box 12 + icosahedron 20 + triangle 1 + light 2
    assert_eq!(scene.triangles().count(), 41);
    assert_eq!(scene.spheres().count(), 1);
    assert_eq!(scene.lights.iter().filter(|l| matches!(l.kind, LightKind::Point { .. })).count(), 1);
    assert_eq!(scene.material_names.last().unwrap(), "light 0");
    // The icosahedron (circumradius 1, scaled 0.4) stays outward-facing after its transform.
    let copper = scene.material_names.iter().position(|n| n == "copper").unwrap() as u32;
    let center = Vec3::new(0.9, 0.4, -0.9);
    for (t, _) in scene.triangles().filter(|(_, m)| *m == copper) {
        let centroid = (t.vertices[0] + t.vertices[1] + t.vertices[2]) / 3.0;
        assert!(winding_normal(&t.vertices).dot(centroid - center) > 0.0);
        for v in t.vertices {
            assert!(((v - center).length() - 0.4).abs() < 1e-5);
        }
    }
}

#[test]
fn materials_showroom_has_every_material_kind_on_its_spheres() {
    let scene = load("materials.toml");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mut kinds: Vec<&str> = scene
        .spheres()
        .map(|(_, m)| match scene.materials[m as usize].kind {
            MaterialKind::Diffuse { .. } => "diffuse",
            MaterialKind::Mirror { .. } => "mirror",
            MaterialKind::Dielectric { .. } => "dielectric",
            MaterialKind::ThinDielectric { .. } => "thin_dielectric",
            MaterialKind::Conductor { .. } => "conductor",
            MaterialKind::Plastic { .. } => "plastic",
            MaterialKind::Mix { .. } => "mix",
            MaterialKind::Null => "null",
        })
        .collect();
    kinds.sort();
    kinds.dedup();
    assert_eq!(kinds, ["conductor", "dielectric", "diffuse", "mix", "plastic"]);
    assert!(scene.materials.iter().any(|m| matches!(m.normal, photonix::scene::NormalMod::Bump { .. })));
    assert_eq!(scene.spheres().count(), 12);
}

#[test]
fn smoke_fills_a_ball_with_a_turbulent_pattern_density() {
    use photonix::scene::TextureKind;
    let scene = load("smoke.toml");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.media.len(), 1);
    let density = scene.media[0].density.expect("the smoke is heterogeneous");
    let TextureKind::Pattern { pattern, color_map } = &scene.textures[density.texture as usize].kind else {
        panic!("the density is a pattern");
    };
    assert!(pattern.turbulence.x > 0.0);
    assert_eq!(density.max, color_map.max_first_channel());
    assert_eq!(scene.spheres().count(), 1, "the ball that bounds the smoke");
}
