//! Smooth shading of meshes: interpolated vertex normals, and no shadow-terminator artifacts on a
//! low-poly mesh (the neighbouring flat facets must not shadow points whose shading normal
//! faces the light), on both backends.

mod common;

use photonix::layout::constants::NO_LIGHT;
use photonix::scene::{load_scene, Geometry};

/// A UV sphere of radius 1 with `segments` around and `rings` from pole to pole, as OBJ text
/// without normals (the importer computes them).
fn uv_sphere_obj(segments: u32, rings: u32) -> String {
    let mut s = String::new();
    let pi = std::f32::consts::PI;
    s.push_str("v 0 1 0\n");
    for r in 1..rings {
        let theta = pi * r as f32 / rings as f32;
        for k in 0..segments {
            let phi = 2.0 * pi * k as f32 / segments as f32;
            s.push_str(&format!("v {} {} {}\n", theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()));
        }
    }
    s.push_str("v 0 -1 0\n");
    let ring = |r: u32, k: u32| 2 + (r - 1) * segments + k % segments;
    let bottom = 2 + (rings - 1) * segments;
    for k in 0..segments {
        s.push_str(&format!("f 1 {} {}\n", ring(1, k), ring(1, k + 1)));
        for r in 1..rings - 1 {
            s.push_str(&format!("f {} {} {} {}\n", ring(r, k), ring(r + 1, k), ring(r + 1, k + 1), ring(r, k + 1)));
        }
        s.push_str(&format!("f {} {} {}\n", ring(rings - 1, k), bottom, ring(rings - 1, k + 1)));
    }
    s
}

/// A sphere (analytic, or the mesh with `mesh_fields`) lit from the side by a distant light,
/// direct light only, seen from +z.
fn scene(shape: &str) -> String {
    format!(
        r#"
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 35
resolution = [96, 96]

[photons]
enabled = false

[materials.white]
type = "diffuse"
reflectance = 0.8

{shape}

[[lights]]
type = "distant"
direction = [-1, 0, 0.198912]
irradiance = 3
"#
    )
}

const MESH: &str = "[[shapes]]\ntype = \"mesh\"\nmaterial = \"white\"\nfile = \"sphere.obj\"\nsmooth_angle = 60\n";
#[allow(dead_code)] // drawn next to the mesh when PHOTONIX_TEST_IMAGES is set
const SPHERE: &str = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\ncenter = [0, 0, 0]\nradius = 1\n";

fn render(shape: &str, gpu: bool) -> photonix::io::Image {
    let dir = common::scene_dir(&scene(shape));
    std::fs::write(dir.path().join("sphere.obj"), uv_sphere_obj(24, 12)).unwrap();
    let scene = load_scene(&dir.path().join("scene.toml")).unwrap();
    let buffers = common::buffers(&scene, 96, 96);
    if gpu {
        common::gpu_image(&common::gpu(), &buffers, 2)
    } else {
        common::cpu_image(&buffers, 2)
    }
}

#[test]
fn low_poly_sphere_has_smooth_normals_and_no_dark_terminator_facets() {
    let dir = common::scene_dir(&scene(MESH));
    std::fs::write(dir.path().join("sphere.obj"), uv_sphere_obj(24, 12)).unwrap();
    let loaded = load_scene(&dir.path().join("scene.toml")).unwrap();
    let smooth =
        loaded.shapes.iter().filter(|s| matches!(&s.geometry, Geometry::Triangle(t) if t.normals.is_some())).count();
    assert_eq!(smooth, loaded.shapes.len(), "every triangle of the sphere is smooth");

    let mesh = render(MESH, false);
    if let Ok(dir) = std::env::var("PHOTONIX_TEST_IMAGES") {
        let sphere = render(SPHERE, false);
        let dir = std::path::Path::new(&dir);
        photonix::io::write_image(&dir.join("terminator-mesh.png"), &mesh, 0.0).unwrap();
        photonix::io::write_image(&dir.join("terminator-sphere.png"), &sphere, 0.0).unwrap();
    }
    // Each pixel's centre ray finds the mesh's shading normal there; where it faces the light,
    // Lambert's law with that normal, rho E cos / pi, is what smooth shading promises. A pixel far
    // below it is the shadow-terminator artifact: the facet's neighbours shadowing it, or its
    // flat plane facing away from the light. The light comes from the side, 11.25 degrees off a
    // column of vertices, so the terminator crosses the image's middle a quarter of a facet past
    // the facets' centres: there the facet faces 3.75 degrees away from the light while the
    // shading normal faces up to 3.75 degrees toward it, and a shadow ray leaving the flat facet
    // runs into the mesh. (Without the shifted origin 125 of the 1482 pixels with cos > 0.02 are
    // dark; with the shift but the ray's side judged by the facet instead of the shading normal,
    // 127.) Pixels average two jittered samples, whose normals differ by
    // about 0.015 here: a bar of half the value at cos > 0.02 leaves room for that. On the other
    // side of the terminator the sphere must stay dark (no light leaking through the shift).
    let buffers = common::buffers(&loaded, 96, 96);
    let view = buffers.view();
    let to_light = glam::Vec3::new(1.0, 0.0, -0.198912).normalize();
    let (mut checked, mut dark, mut unlit, mut leaks) = (0, 0, 0, 0);
    for y in 0..96u32 {
        for x in 0..96u32 {
            let (sx, sy) = ((x as f32 + 0.5) / 48.0 - 1.0, 1.0 - (y as f32 + 0.5) / 48.0);
            let (o, d) = photonix::cpu::shading::camera_ray(&view, sx, sy, [0.5, 0.5]);
            let (prim, t) = photonix::cpu::trace::trace_ray(&view, o, d, f32::INFINITY, false, NO_LIGHT);
            // Silhouette pixels mix the background in.
            if prim == NO_LIGHT {
                continue;
            }
            let h = photonix::cpu::shape::shape_hit(&view, prim, o, d, t);
            if h.ns.dot(-d) < 0.3 {
                continue;
            }
            let cos = h.ns.dot(to_light);
            let expected = 0.8 * 3.0 * cos / std::f32::consts::PI;
            let value = mesh.pixel(x, y)[0];
            if cos > 0.02 {
                checked += 1;
                dark += (value < 0.5 * expected) as u32;
            } else if cos < -0.02 {
                unlit += 1;
                leaks += (value > 0.0) as u32;
            }
        }
    }
    println!("{dark} of {checked} pixels whose shading normal faces the light are dark; {leaks} of {unlit} facing away are lit");
    assert!(checked > 1000 && unlit > 1000, "the test sees both sides of the terminator");
    assert_eq!(dark, 0, "dark terminator facets on the smooth mesh");
    assert_eq!(leaks, 0, "light on the far side of the terminator");
}

#[test]
fn gpu_matches_cpu_on_a_smooth_mesh() {
    let cpu = render(MESH, false);
    let gpu = render(MESH, true);
    let error = photonix::io::metrics::rel_mse(&gpu, &cpu);
    println!("smooth sphere: gpu vs cpu relMSE {error:.3e}");
    // The twins compute the same normals and shifts in the same order (see gpu_vs_cpu.rs for
    // the bound).
    assert!(error < 1e-6, "relMSE {error:.3e}");
}

#[test]
fn default_smooth_angle_leaves_flat_faced_models_flat() {
    // smooth_angle defaults to 30 degrees: the shipped OBJ models (the showcase's icosahedron,
    // whose faces meet at 41.8 degrees, Cornell walls, a fog box) keep flat triangles, so they
    // draw as before smooth shading existed; the Loop-subdivided icosahedron of shapes.toml is
    // smooth.
    for file in ["scenes/showcase.toml", "scenes/cornell-glossy.toml", "scenes/cornell-fog.toml"] {
        let scene = load_scene(&common::repo_path(file)).unwrap();
        let (mut flat, mut smooth) = (0, 0);
        for s in &scene.shapes {
            if let Geometry::Triangle(t) = &s.geometry {
                if t.normals.is_some() {
                    smooth += 1;
                } else {
                    flat += 1;
                }
            }
        }
        println!("{file}: {flat} flat, {smooth} smooth triangles");
        assert!(flat > 0 && smooth == 0, "{file}: {flat} flat, {smooth} smooth triangles");
    }
    let scene = load_scene(&common::repo_path("scenes/shapes.toml")).unwrap();
    let smooth =
        scene.shapes.iter().filter(|s| matches!(&s.geometry, Geometry::Triangle(t) if t.normals.is_some())).count();
    assert!(smooth > 1000, "shapes.toml's teapot and subdivided icosahedron are smooth ({smooth} triangles)");
}
