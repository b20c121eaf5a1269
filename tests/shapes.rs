//! Analytic shapes: the kernels' intersections (on the CPU twin) against a double-precision
//! reference that shares no code with them, rays leaving hit points do not meet their own
//! surface again, GPU = CPU on a scene with every shape, and each shape renders like a finely
//! tessellated mesh of itself.

mod common;

use glam::{DVec3, Vec3};
use photonix::cpu::rng::rand1;
use photonix::cpu::shading::offset_origin;
use photonix::cpu::shape::{shape_hit, shape_intersect};
use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::layout::constants::{BSDF_REFLECTION, BSDF_TRANSMISSION, PRIMITIVE_KIND_MASK, PRIMITIVE_SPHERE};
use photonix::render::SceneBuffers;
use photonix::scene::{parse_scene, Analytic, Geometry, Scene, Shape, Triangle};

const HEADER: &str = r#"
[camera]
position = [0, 1, 6]
look_at = [0, 0.5, 0]
fov = 40
resolution = [48, 36]
[render]
spp = 1
max_depth = 4
[materials.white]
type = "diffuse"
[[lights]]
type = "point"
position = [0, 5, 3]
intensity = 20
"#;

/// Each analytic shape, placed with rotations, non-uniform scales and far translations.
const SHAPES: &[(&str, &str)] = &[
    ("tilted plane", "type = \"plane\"\nnormal = [0.3, 1, -0.2]\noffset = 0.5"),
    ("stretched annulus", "type = \"disc\"\ncenter = [0.2, 0.5, 0]\nnormal = [0.2, 0.5, 1]\nradius = 1\ninner_radius = 0.3\ntransform = { scale = [1.5, 1, 0.7] }"),
    ("tilted cylinder", "type = \"cylinder\"\nbase = [-0.5, 0, 0]\ncap = [0.6, 1.3, -0.4]\nradius = 0.4\nopen = true"),
    ("truncated cone", "type = \"cone\"\nbase = [0, 0, 0]\ncap = [0, 1.2, 0]\nbase_radius = 0.7\ncap_radius = 0.2\nopen = true\ntransform = { rotate = [20, 0, 35] }"),
    ("pointed cone", "type = \"cone\"\nbase = [0, 1.4, 0]\ncap = [0.1, 0, 0.2]\nbase_radius = 0.6\ncap_radius = 0\nopen = true"),
    ("torus", "type = \"torus\"\ncenter = [0, 0.5, 0]\nmajor_radius = 1\nminor_radius = 0.3\naxis = [0.3, 1, 0.5]"),
    ("thin far torus", "type = \"torus\"\ncenter = [40, -12, -30]\nmajor_radius = 1\nminor_radius = 0.02\naxis = [1, 0.2, 0]"),
    ("squashed torus", "type = \"torus\"\nmajor_radius = 0.8\nminor_radius = 0.35\ntransform = { scale = [1, 0.5, 1.3], rotate = [30, 10, 0] }"),
    ("boxy superellipsoid", "type = \"superellipsoid\"\nexponents = [0.1, 0.1]\ncenter = [0, 0.5, 0]\ntransform = { rotate = [10, 30, 0] }"),
    ("round superellipsoid", "type = \"superellipsoid\"\nexponents = [1, 1]\ntransform = { scale = [1.2, 0.6, 0.9], translate = [0, 0.5, 0] }"),
    ("octahedron", "type = \"superellipsoid\"\nexponents = [2, 2]\ncenter = [0, 0.5, 0]"),
    ("pillow", "type = \"superellipsoid\"\nexponents = [0.5, 1.6]\ncenter = [3, -2, 1]\ntransform = { rotate = [70, 0, 20] }"),
    ("tiny box", "type = \"superellipsoid\"\nexponents = [0.01, 0.3]\ntransform = { scale = 0.01, translate = [0.2, 0.3, 0.1] }"),
];

fn scene_with(shape: &str) -> Scene {
    let text = format!("{HEADER}\n[[shapes]]\nmaterial = \"white\"\n{shape}\n");
    parse_scene(&text, std::path::Path::new("shapes-test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn analytic(scene: &Scene) -> &Analytic {
    match &scene.shapes[0].geometry {
        Geometry::Analytic(a) => a,
        other => panic!("not analytic: {other:?}"),
    }
}

fn random3(key: u32, dim: u32) -> DVec3 {
    DVec3::new(rand1(key, 7, 1, dim) as f64, rand1(key, 7, 1, dim + 1) as f64, rand1(key, 7, 1, dim + 2) as f64)
}

/// A uniform direction on the sphere.
fn random_direction(key: u32, dim: u32) -> DVec3 {
    let u = random3(key, dim);
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u.y;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The index of the scene's one analytic primitive (an unbounded one follows the BVH's
/// placeholder).
fn prim_index(buffers: &SceneBuffers) -> u32 {
    buffers
        .primitives
        .iter()
        .position(|p| p.kind & PRIMITIVE_KIND_MASK > PRIMITIVE_SPHERE)
        .expect("an analytic primitive") as u32
}

/// How a ray of the twin compares with the reference.
#[derive(Default, Debug)]
struct Tally {
    rays: u32,
    hits: u32,
    /// Disagreements on rays that pass within rounding of a silhouette or a rim.
    ambiguous: u32,
    /// Of those, on the random rays (not built to graze).
    random_ambiguous: u32,
    random_rays: u32,
    failures: Vec<String>,
    /// Largest object-space distance of a twin's hit point from the surface.
    worst_off_surface: f64,
    /// Largest distance between the twin's and the reference's hit points over the shape's
    /// size, on rays at least 10 degrees from grazing.
    worst_point: f64,
    /// Largest angle between the twin's normal and the exact one at its point (radians).
    worst_normal: f64,
}

/// The diagonal of the shape's world bounds (6 for the plane): the scale of its tolerances.
fn extent(shape: &Analytic) -> f64 {
    if shape.is_unbounded() {
        return 6.0;
    }
    let (lo, hi) = shape.bounds();
    (hi - lo).length() as f64
}

/// The length of the first piece of the ray inside the shape, from its first hit to the next
/// (by the reference, or by the twin when `twin` is set); infinite without a second hit.
fn first_chord(buffers: &SceneBuffers, shape: &Analytic, o: Vec3, d: Vec3, t: f64, twin: bool) -> f64 {
    if twin {
        let view = buffers.view();
        let t2 = shape_intersect(&view, prim_index(buffers), o, d, t as f32, f32::INFINITY);
        return (t2 as f64 - t) * d.length() as f64;
    }
    let (od, dd) = (o.as_dvec3(), d.as_dvec3());
    let step = 1e-9 * (1.0 + t);
    match shape.intersect_reference(od + (t + step) * dd, dd) {
        Ok((t2, _)) => (t2 + step) * dd.length(),
        Err(_) => f64::INFINITY,
    }
}

/// Compares the twin's first hit of (o, d) with the reference's:
/// - the twin's point lies on the surface to 1e-5 object units (plus 1e-6 of its distance
///   from the object's origin: its world coordinates round by that much);
/// - it is the reference's first hit: the points agree to 1e-4 of the shape's size divided by
///   the cosine of incidence (a root moves along a grazing ray), plus 1e-5 of the distance;
/// - the twin's normal is the exact normal at its point to 1e-3 rad (except within 1e-5 of an
///   edge or apex, where the normal turns by more than that).
///
/// Hit or miss may go either way on rays that go into the shape by less than rounding: within
/// 1e-4 object units of a rim, into the surface by less than 1e-4 object units, or inside it
/// for less than 2e-3 of its size (a near-double root, which f32 coefficients cannot resolve).
/// Those count as ambiguous.
fn compare_ray(buffers: &SceneBuffers, shape: &Analytic, o: Vec3, d: Vec3, tally: &mut Tally, what: &str) {
    let view = buffers.view();
    let t32 = shape_intersect(&view, prim_index(buffers), o, d, 0.0, f32::INFINITY);
    let (od, dd) = (o.as_dvec3(), d.as_dvec3());
    let reference = shape.intersect_reference(od, dd);
    tally.rays += 1;
    let before = tally.ambiguous;
    compare_outcome(buffers, shape, o, d, t32, reference, tally, what);
    if what == "random" {
        tally.random_rays += 1;
        tally.random_ambiguous += tally.ambiguous - before;
    }
}

#[allow(clippy::too_many_arguments)]
fn compare_outcome(
    buffers: &SceneBuffers,
    shape: &Analytic,
    o: Vec3,
    d: Vec3,
    t32: f32,
    reference: Result<(f64, DVec3), f64>,
    tally: &mut Tally,
    what: &str,
) {
    let view = buffers.view();
    let i = prim_index(buffers);
    let size = extent(shape);
    let (od, dd) = (o.as_dvec3(), d.as_dvec3());
    let near_rim = |p: DVec3| shape.rim_distance(p) < 1e-4;
    let shallow = |chord: f64| chord < 2e-3 * size;
    // Goes into the surface near t by less than 1e-4 object units: a touch, not a crossing.
    let touch = |t: f64| shape.local_depth(od, dd, t, 0.05 * size / dd.length()) < 1e-4;
    match (t32.is_finite(), reference) {
        (false, Err(_)) => {}
        (true, Ok((t64, n64))) => {
            tally.hits += 1;
            let h = shape_hit(&view, i, o, d, t32);
            let (p32, p64) = (h.p.as_dvec3(), od + t64 * dd);
            let off = shape.object_distance_bound(p32);
            let limit_off = 1e-5 + 1e-6 * p32.abs().max_element();
            let cos = n64.dot(dd.normalize()).abs();
            let dp = (p32 - p64).length();
            let limit_dp = (1e-4 * size + 1e-5 * t64 * dd.length()) / cos.max(1e-3);
            let exact = shape.normal_at(p32);
            let angle = h.ng.as_dvec3().cross(exact).length().atan2(h.ng.as_dvec3().dot(exact));
            let normal_defined = shape.normal_sensitivity(p32) < 1e-3;
            let wrong_root = dp > limit_dp;
            if wrong_root
                && (near_rim(p64)
                    || near_rim(p32)
                    || touch(t64)
                    || touch(t32 as f64)
                    || shallow(first_chord(buffers, shape, o, d, t64, false))
                    || shallow(first_chord(buffers, shape, o, d, t32 as f64, true)))
            {
                tally.ambiguous += 1;
                return;
            }
            tally.worst_off_surface = tally.worst_off_surface.max(off);
            if cos > 0.17 {
                tally.worst_point = tally.worst_point.max(dp / size);
            }
            if normal_defined {
                tally.worst_normal = tally.worst_normal.max(angle);
            }
            if off > limit_off || wrong_root || (normal_defined && angle > 1e-3) {
                tally.failures.push(format!(
                    "{what}: o {o} d {d}: twin t {t32} at {p32} ({off:.1e} off the surface), reference t {t64} at {p64} ({dp:.1e} apart, limit {limit_dp:.1e}); normal {angle:.1e} rad from the exact one",
                ));
            }
        }
        (true, Err(margin)) => {
            let p = o + t32 * d;
            if margin < 1e-4
                || near_rim(p.as_dvec3())
                || touch(t32 as f64)
                || shallow(first_chord(buffers, shape, o, d, t32 as f64, true))
            {
                tally.ambiguous += 1;
            } else {
                tally
                    .failures
                    .push(format!("{what}: o {o} d {d}: twin hits at t {t32} ({p}), reference misses by {margin:.2e}"));
            }
        }
        (false, Ok((t64, _))) => {
            let p64 = od + t64 * dd;
            if near_rim(p64) || touch(t64) || shallow(first_chord(buffers, shape, o, d, t64, false)) {
                tally.ambiguous += 1;
            } else {
                tally.failures.push(format!("{what}: o {o} d {d}: twin misses, reference hits at t {t64} ({p64})"));
            }
        }
    }
}

#[test]
fn intersections_match_a_double_precision_reference() {
    let mut summary = Vec::new();
    for (index, (name, shape_text)) in SHAPES.iter().enumerate() {
        let scene = scene_with(shape_text);
        let shape = analytic(&scene);
        let buffers = common::buffers(&scene, 8, 8);
        let view = buffers.view();
        let mut tally = Tally::default();
        let (lo, hi) = if shape.is_unbounded() { (Vec3::splat(-3.0), Vec3::splat(3.0)) } else { shape.bounds() };
        let (center, extent) = (((lo + hi) * 0.5).as_dvec3(), ((hi - lo).length() as f64).max(1e-3));
        let key = index as u32 * 100_000;
        // Rays from all around toward random points of the bounds: hits, misses and silhouettes.
        for i in 0..3000 {
            let target = lo.as_dvec3() + (hi - lo).as_dvec3() * random3(key + i, 0);
            let o = center + 2.0 * extent * random_direction(key + i, 3);
            compare_ray(&buffers, shape, o.as_vec3(), (target - o).normalize().as_vec3(), &mut tally, "random");
        }
        // Grazing rays: along a tangent of a random surface point, tilted by up to 1 degree.
        for i in 0..3000 {
            let (p, n, _) = shape.sample([random3(key + i, 10).x, random3(key + i, 10).y]);
            let tangent = n.cross(random_direction(key + i, 13)).normalize();
            let tilt = (random3(key + i, 16).x - 0.5) * 0.035;
            let d = (tangent + tilt * n).normalize();
            let o = p - d * extent;
            compare_ray(&buffers, shape, o.as_vec3(), d.as_vec3(), &mut tally, "grazing");
        }
        // Rays leaving hit points, to both sides and at every angle (grazing ones included):
        // a hit right after the offset origin would be the shape meeting itself.
        for i in 0..1500 {
            let (p, n, _) = shape.sample([random3(key + i, 20).x, random3(key + i, 20).y]);
            let o = p + n * 0.5 * extent;
            let d = (p - o).normalize().as_vec3();
            let prim = prim_index(&buffers);
            let t = shape_intersect(&view, prim, o.as_vec3(), d, 0.0, f32::INFINITY);
            if !t.is_finite() {
                continue;
            }
            let h = shape_hit(&view, prim, o.as_vec3(), d, t);
            let mut w = random_direction(key + i, 23).as_vec3();
            // Leave to either side: reflection keeps wo's side, transmission crosses.
            let flags = if i % 2 == 0 { BSDF_REFLECTION } else { BSDF_TRANSMISSION };
            let side = if flags == BSDF_REFLECTION { h.ng } else { -h.ng };
            if w.dot(side) < 0.0 {
                w = -w;
            }
            let origin = offset_origin(&h, -d, flags);
            compare_ray(&buffers, shape, origin, w, &mut tally, "leaving");
        }
        println!(
            "{name:22}: {} rays, {} hits, {} ambiguous ({} of {} random); worst: {:.1e} off the surface, {:.1e} of the size from the reference's point, normal {:.1e} rad",
            tally.rays, tally.hits, tally.ambiguous, tally.random_ambiguous, tally.random_rays, tally.worst_off_surface, tally.worst_point, tally.worst_normal
        );
        // Rays within rounding of a silhouette or rim are a sliver of random rays (the grazing
        // ones are built to skim the surface, within a degree: on a thin tube, many touch it).
        if tally.random_ambiguous * 100 >= tally.random_rays || tally.ambiguous * 10 >= tally.rays {
            summary.push(format!(
                "{name}: {} of {} random rays and {} of {} in all ambiguous",
                tally.random_ambiguous, tally.random_rays, tally.ambiguous, tally.rays
            ));
        }
        if tally.hits * 4 <= tally.rays {
            summary.push(format!("{name}: only {} hits of {} rays", tally.hits, tally.rays));
        }
        summary.extend(tally.failures.iter().take(5).map(|f| format!("{name}: {f}")));
        if !tally.failures.is_empty() {
            summary.push(format!("{name}: {} failures in all", tally.failures.len()));
        }
    }
    assert!(summary.is_empty(), "{}", summary.join("\n"));
}

/// Scene with the one shape (all its pieces, a closed cylinder's caps too), under a point light.
const MESH_HEADER: &str = r#"
[camera]
position = [0, 1.5, 4]
look_at = [0, 0.4, 0]
fov = 45
resolution = [96, 72]
[render]
spp = 4
max_depth = 2
[materials.white]
type = "diffuse"
reflectance = 0.7
[[lights]]
type = "point"
position = [2, 4, 3]
intensity = 15
"#;

#[test]
fn analytic_shapes_render_like_their_fine_tessellations() {
    let shapes = [
        ("disc", "type = \"disc\"\ncenter = [0, 0.5, 0]\nnormal = [0.3, 1, 0.6]\nradius = 1\ninner_radius = 0.4"),
        ("capped cylinder", "type = \"cylinder\"\nbase = [0, 0, 0]\ncap = [0.3, 1.2, -0.2]\nradius = 0.5"),
        ("open cone", "type = \"cone\"\nbase = [0, 0, 0]\ncap = [0, 1.2, 0]\nbase_radius = 0.8\ncap_radius = 0.3\nopen = true\ntransform = { rotate = [-25, 0, 0] }"),
        ("torus", "type = \"torus\"\ncenter = [0, 0.5, 0]\nmajor_radius = 0.9\nminor_radius = 0.3\naxis = [0, 1, 0.8]"),
        ("boxy superellipsoid", "type = \"superellipsoid\"\nexponents = [0.2, 0.3]\ncenter = [0, 0.5, 0]\ntransform = { scale = 0.7, rotate = [20, 35, 0] }"),
        ("pillow", "type = \"superellipsoid\"\nexponents = [1, 0.4]\ncenter = [0, 0.5, 0]\ntransform = { scale = [0.9, 0.9, 0.5], rotate = [-60, 20, 0] }"),
    ];
    let mut failures = Vec::new();
    for (name, shape_text) in shapes {
        let text = format!("{MESH_HEADER}\n[[shapes]]\nmaterial = \"white\"\n{shape_text}\n");
        let analytic_scene = parse_scene(&text, std::path::Path::new("mesh-test.toml")).unwrap();
        let mut mesh_scene = analytic_scene.clone();
        mesh_scene.shapes = analytic_scene
            .shapes
            .iter()
            .flat_map(|s| match &s.geometry {
                Geometry::Analytic(a) => a
                    .tessellate(512)
                    .into_iter()
                    .map(|vertices| Shape {
                        geometry: Geometry::Triangle(Triangle { vertices, uv: None, normals: None }),
                        material: s.material,
                        media: None,
                    })
                    .collect::<Vec<_>>(),
                _ => vec![s.clone()],
            })
            .collect();
        let (w, h) = (96, 72);
        let a = common::cpu_image(&common::buffers(&analytic_scene, w, h), 4);
        let m = common::cpu_image(&common::buffers(&mesh_scene, w, h), 4);
        // Same camera rays (same random streams): only silhouette pixels, where a jittered ray
        // passes within a facet's sagitta (2e-5 of the size at 512 segments), and the facets'
        // shading (their normals turn by up to 0.7 degrees) may differ. A hole or a speckle
        // would differ by the whole radiance of the surface.
        let lit = a.pixels.iter().filter(|p| p[0] > 0.01).count();
        let stray = a
            .pixels
            .iter()
            .zip(&m.pixels)
            .filter(|(x, y)| (0..3).any(|c| (x[c] - y[c]).abs() > 0.05 * x[c].max(y[c]).max(0.2)))
            .count();
        let error = rel_mse(&a, &m);
        let ratio = mean_ratio(&a, &m);
        println!(
            "{name:20}: {lit} lit pixels, {stray} differ by more than 5%; relMSE {error:.2e}, mean ratio {:.4}",
            ratio[0]
        );
        if lit < 300 || stray > 6 || (ratio[0] - 1.0).abs() > 0.01 {
            failures.push(format!("{name}: {lit} lit, {stray} stray, mean ratio {ratio:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn gpu_matches_cpu_on_every_shape() {
    let scene = photonix::scene::load_scene(&common::repo_path("scenes/shapes.toml")).expect("shipped scene loads");
    let buffers = common::buffers(&scene, 40, 30);
    assert!(buffers.analytic && buffers.implicit, "the scene needs the analytic_implicit kernels");
    let cpu = common::assert_twins_agree("shapes 40x30", &buffers);
    assert!(cpu.image.pixels.iter().filter(|p| p[0] > 0.0).count() > 600, "the image is mostly black");
}

#[test]
fn surface_derivatives_match_the_uv_they_come_from() {
    // A uv-space texture makes the kernels compute uv, dpdu and dpdv.
    let header = HEADER.replace(
        "[materials.white]\ntype = \"diffuse\"",
        "[textures.checks]\ntype = \"pattern\"\npattern = \"checker\"\n[materials.white]\ntype = \"diffuse\"\nreflectance = { texture = \"checks\" }",
    );
    for (name, shape_text) in SHAPES {
        let text = format!("{header}\n[[shapes]]\nmaterial = \"white\"\n{shape_text}\n");
        let scene = parse_scene(&text, std::path::Path::new("uv-test.toml")).unwrap_or_else(|e| panic!("{e}"));
        let shape = analytic(&scene);
        if shape.size() as f64 > 10.0 * extent(shape) {
            // Far from the origin for its size (the thin torus at x = 40): f32 coordinates
            // there are too coarse for finite differences over its 0.02-wide tube.
            continue;
        }
        let buffers = common::buffers(&scene, 8, 8);
        let view = buffers.view();
        let i = prim_index(&buffers);
        let mirrored = shape.world_from_object.matrix3.determinant() < 0.0;
        let (mut worst, mut checked) = (0.0f32, 0);
        for k in 0..400u32 {
            let u = random3(k, 30);
            let (p, n, _) = shape.sample([0.05 + 0.9 * u.x, 0.05 + 0.9 * u.y]);
            let h = photonix::cpu::shape::shape_surface(&view, i, p.as_vec3());
            // The tangent frame turns the same way as the outward normal.
            let frame = h.dpdu.cross(h.dpdv).normalize().dot(n.as_vec3());
            assert!(if mirrored { frame < -0.99 } else { frame > 0.99 }, "{name}: dpdu x dpdv . n = {frame} at {p}");
            // Small steps along +-dpdu (dpdv) move uv by the step in u (v), to second order.
            let step = 1e-3;
            for (dp, expected) in [(h.dpdu, glam::Vec2::X), (h.dpdv, glam::Vec2::Y)] {
                let ahead = photonix::cpu::shape::shape_surface(&view, i, h.p + step * dp).uv;
                let behind = photonix::cpu::shape::shape_surface(&view, i, h.p - step * dp).uv;
                let duv = (ahead - behind) / (2.0 * step);
                if (ahead - behind).abs().max_element() > 0.1 {
                    continue; // across the seam of a periodic u or v
                }
                worst = worst.max((duv - expected).length());
                checked += 1;
            }
        }
        println!("{name:22}: {checked} steps, uv moves as the derivatives say to {worst:.1e}");
        // Central differences in f32: error about step^2 times the curvature, plus rounding.
        assert!(checked > 600 && worst < 5e-3, "{name}: worst {worst} over {checked} steps");
    }
}

/// A floor lit only by one emitting shape, seen from above; direct light only.
fn lit_floor(light: &str) -> Scene {
    let text = format!(
        r#"
[camera]
position = [0, 6, 0.01]
look_at = [0, 0, 0]
fov = 60
resolution = [32, 32]
[render]
spp = 1
max_depth = 2
[materials.floor]
type = "diffuse"
reflectance = 0.5
[materials.glow]
type = "diffuse"
reflectance = 0
emission = 2
[[shapes]]
type = "quad"
material = "floor"
vertices = [[-4, 0, 4], [4, 0, 4], [4, 0, -4], [-4, 0, -4]]
[[shapes]]
material = "glow"
{light}
"#
    );
    parse_scene(&text, std::path::Path::new("emitter-test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn analytic_emitters_light_like_their_references() {
    // Each emitter against the same surface in a form lit by long-tested code: the unit
    // superellipsoid (e = n = 1) is a sphere; a torus, a stretched cone and a disc against their
    // fine tessellations (triangles, sampled uniformly by area). The analytic ones are sampled
    // non-uniformly (by direction, by angles, under a non-uniform scale) with their own 1/pdf,
    // so equal images mean the densities are right. The camera sees the floor and the emitter.
    let cases = [
        ("superellipsoid as sphere", "type = \"superellipsoid\"\nexponents = [1, 1]\ntransform = { scale = 0.5, translate = [0, 1.5, 0] }", Some("type = \"sphere\"\ncenter = [0, 1.5, 0]\nradius = 0.5")),
        ("boxy superellipsoid", "type = \"superellipsoid\"\nexponents = [0.3, 0.5]\ncenter = [0, 1.5, 0]\ntransform = { scale = [0.6, 0.3, 0.4], rotate = [30, 0, 10] }", None),
        ("torus", "type = \"torus\"\ncenter = [0, 1.5, 0]\nmajor_radius = 0.6\nminor_radius = 0.25\naxis = [0.3, 1, 0]", None),
        ("stretched cone", "type = \"cone\"\nbase = [0, 1, 0]\ncap = [0.2, 2, 0]\nbase_radius = 0.5\ncap_radius = 0.1\ntransform = { scale = [1.5, 1, 0.7] }", None),
        ("disc", "type = \"disc\"\ncenter = [0, 1.5, 0]\nnormal = [0.2, -1, 0]\nradius = 0.7\ninner_radius = 0.2", None),
    ];
    let spp = 512;
    for (name, light, reference) in cases {
        let analytic_scene = lit_floor(light);
        let reference_scene = match reference {
            Some(text) => lit_floor(text),
            None => {
                let mut s = analytic_scene.clone();
                s.shapes = s
                    .shapes
                    .iter()
                    .flat_map(|shape| match &shape.geometry {
                        Geometry::Analytic(a) => a
                            .tessellate(256)
                            .into_iter()
                            .map(|vertices| Shape {
                                geometry: Geometry::Triangle(Triangle { vertices, uv: None, normals: None }),
                                material: shape.material,
                                media: None,
                            })
                            .collect::<Vec<_>>(),
                        _ => vec![shape.clone()],
                    })
                    .collect();
                s
            }
        };
        let a = common::cpu_image(&common::buffers(&analytic_scene, 32, 32), spp);
        let b = common::cpu_image(&common::buffers(&reference_scene, 32, 32), spp);
        let ratio = mean_ratio(&a, &b);
        let error = rel_mse(&a, &b);
        println!("{name:26}: mean ratio {:.4} against the reference, relMSE {error:.2e}", ratio[0]);
        // 1024 pixels x 512 light samples: measured within 0.6% (the boxy superellipsoid's
        // samples vary most in weight; at 64 samples its mean was still 4% off by noise); a
        // wrong pdf (area, stretch, direction density) is off by tens of percent.
        assert!((ratio[0] - 1.0).abs() < 0.015, "{name}: mean ratio {ratio:?}");
    }
}
