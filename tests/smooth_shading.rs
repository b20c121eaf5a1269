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
direction = [-1, 0, 0.1317]
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
    // Each pixel's centre ray finds the mesh's shading normal there; where it faces the light
    // (cos > 0.15), Lambert's law with that normal, rho E cos / pi, is what smooth shading
    // promises. A pixel far below it is the shadow-terminator artifact: the facet's neighbours
    // shadowing it, or its flat plane facing away from the light. The light grazes the sphere
    // from the side, along the middle of a column of facets (15 degrees from their edges), so
    // the terminator crosses the middle of the image and of those facets. (Pixels average two
    // jittered samples, so a bar of half the value leaves room for normals varying across one.)
    let buffers = common::buffers(&loaded, 96, 96);
    let view = buffers.view();
    let to_light = glam::Vec3::new(1.0, 0.0, -0.1317).normalize();
    let (mut checked, mut dark) = (0, 0);
    for y in 0..96u32 {
        for x in 0..96u32 {
            let (sx, sy) = ((x as f32 + 0.5) / 48.0 - 1.0, 1.0 - (y as f32 + 0.5) / 48.0);
            let (o, d) = photonix::cpu::shading::camera_ray(&view, sx, sy, [0.5, 0.5]);
            let (prim, t) = photonix::cpu::trace::trace_ray(&view, o, d, f32::INFINITY, false, NO_LIGHT);
            if prim == NO_LIGHT {
                continue;
            }
            let h = photonix::cpu::shape::shape_hit(&view, prim, o, d, t);
            let cos = h.ns.dot(to_light);
            // Silhouette pixels mix the background in.
            let limit = 0.15;
            if cos > limit && h.ns.dot(-d) > 0.3 {
                checked += 1;
                let expected = 0.8 * 3.0 * cos / std::f32::consts::PI;
                if mesh.pixel(x, y)[0] < 0.5 * expected {
                    dark += 1;
                }
            }
        }
    }
    println!("{dark} of {checked} pixels whose shading normal faces the light are dark");
    assert!(checked > 500, "the test sees the lit side");
    assert_eq!(dark, 0, "dark terminator facets on the smooth mesh");
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
