//! CSG objects: volumes measured by casting rays through them (with the kernels' own trace_ray,
//! CPU twin) against the closed forms (or point-sampled references), tori and superellipsoids
//! among the leaves, the solid's normals pointing out of it at every crossing,
//! GPU = CPU on a small CSG scene, a glass lens that renders, and errors for bad input.

mod common;

use std::io::Write;

use glam::Vec3;
use photonix::cpu::shape::shape_hit;
use photonix::cpu::trace::trace_ray;
use photonix::layout::constants::NO_LIGHT;
use photonix::render::SceneBuffers;
use photonix::scene::{load_scene, parse_scene, Scene};

const HEADER: &str = r#"
[camera]
position = [0, 1, 6]
look_at = [0, 0, 0]
fov = 40
resolution = [48, 36]
[render]
spp = 1
max_depth = 6
[materials.white]
type = "diffuse"
[materials.red]
type = "diffuse"
reflectance = [0.8, 0.1, 0.1]
[materials.glass]
type = "dielectric"
ior = 1.5
[[lights]]
type = "point"
position = [1, 5, 3]
intensity = 30
"#;

fn scene_with(shapes: &str) -> Scene {
    let text = format!("{HEADER}\n{shapes}\n");
    parse_scene(&text, std::path::Path::new("csg-test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// Length of the ray's path inside the solid between `o` and `o + 2 reach d`, walking from hit to
/// hit; counts crossings whose normal says the ray enters when the walk says it leaves, or the
/// other way round.
fn inside_length(buffers: &SceneBuffers, o: Vec3, d: Vec3, reach: f32, wrong_side: &mut u32) -> f32 {
    let view = buffers.view();
    let (mut t0, mut inside, mut total, mut entered_at) = (0.0f32, false, 0.0f32, 0.0f32);
    for _ in 0..64 {
        let origin = o + t0 * d;
        let (hit, t) = trace_ray(&view, origin, d, 2.0 * reach, false, NO_LIGHT);
        if hit == NO_LIGHT {
            break;
        }
        let h = shape_hit(&view, hit, origin, d, t);
        let entering = h.ng.dot(d) < 0.0;
        if entering == inside {
            *wrong_side += 1;
        }
        let at = t0 + t;
        if inside {
            total += at - entered_at;
        } else {
            entered_at = at;
        }
        inside = !inside;
        // Step past the surface: the next walk starts just beyond it.
        t0 = at + 1e-4 * reach;
    }
    total
}

/// SplitMix64 (Steele et al. 2014): uniform numbers in [0, 1) that share nothing with the
/// renderer's own streams.
fn splitmix(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// Volume of the scene's solid by parallel rays of random directions through a square that
/// covers the ball of radius `reach` around `center`: V = area x mean inside length.
fn ray_volume(scene: &Scene, center: Vec3, reach: f32, rays: u32) -> (f64, u32) {
    let buffers = common::buffers(scene, 8, 8);
    let mut sum = 0.0f64;
    let mut wrong_side = 0;
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..rays {
        let draws: [f32; 4] = std::array::from_fn(|_| splitmix(&mut state));
        let u = |dim: usize| draws[dim];
        let z = 1.0 - 2.0 * u(0);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u(1);
        let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let e1 = d.any_orthonormal_vector();
        let e2 = d.cross(e1);
        let (a, b) = ((2.0 * u(2) - 1.0) * reach, (2.0 * u(3) - 1.0) * reach);
        let o = center + a * e1 + b * e2 - reach * d;
        sum += inside_length(&buffers, o, d, reach, &mut wrong_side) as f64;
    }
    let area = (2.0 * reach as f64).powi(2);
    (area * sum / rays as f64, wrong_side)
}

const RAYS: u32 = 1_000_000;

fn check_volume(name: &str, shapes: &str, center: Vec3, reach: f32, expected: f64) -> Option<String> {
    let scene = scene_with(shapes);
    let (volume, wrong_side) = ray_volume(&scene, center, reach, RAYS);
    let error = volume / expected - 1.0;
    println!("{name}: volume {volume:.4} by rays, {expected:.4} closed form ({:+.2}%), {wrong_side} crossings on the wrong side", 100.0 * error);
    // A million rays estimate each volume within about 0.25% (one standard deviation); a wrong
    // operation, a lost crossing or a leaf left out moves it by 10% or more (1.5% is 4 to 6 of them). A few crossings per
    // 10 000 rays may look wrong-sided to this walk (it steps 2e-4 past each hit, over a grazed
    // ball's second crossing).
    (error.abs() > 0.015 || wrong_side > RAYS / 10_000)
        .then(|| format!("{name}: {volume:.4} vs {expected:.4}, {wrong_side} wrong-side crossings"))
}

const BOX_MINUS_BALL: &str = r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "box", min = [-1, -1, -1], max = [1, 1, 1] },
  { type = "sphere", center = [0, 0, 0], radius = 1.2, material = "red" },
]
"#;

const LENS: &str = r#"
[[shapes]]
type = "csg"
operation = "intersection"
material = "glass"
children = [
  { type = "sphere", center = [-0.6, 0, 0], radius = 1 },
  { type = "sphere", center = [0.6, 0, 0], radius = 1 },
]
"#;

#[test]
fn volumes_by_rays_match_closed_forms() {
    let pi = std::f64::consts::PI;
    let ball = 4.0 / 3.0 * pi;
    // A cap of height h of a ball of radius r: pi h^2 (3r - h) / 3.
    let cap = |r: f64, h: f64| pi * h * h * (3.0 * r - h) / 3.0;
    // The lens of two unit balls whose centres are 1.2 apart: pi (4r + d)(2r - d)^2 / 12.
    let lens = pi * (4.0 + 1.2) * 0.8f64.powi(2) / 12.0;
    let cases = [
        // The estimator itself, on a plain ball.
        (
            "ball (no CSG)",
            "[[shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\ncenter = [0, 0, 0]\nradius = 1\n".to_string(),
            ball,
        ),
        // The ball pokes out of every face: the cube keeps its 8 corners.
        ("box minus ball", BOX_MINUS_BALL.to_string(), 8.0 - (ball * 1.2f64.powi(3) - 6.0 * cap(1.2, 0.2))),
        ("lens", LENS.to_string(), lens),
        (
            "box minus capped cylinder",
            r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "box", min = [-1, -1, -1], max = [1, 1, 1] },
  { type = "cylinder", base = [0, 0, -2], cap = [0, 0, 2], radius = 0.5 },
]
"#
            .to_string(),
            8.0 - pi * 0.25 * 2.0,
        ),
        (
            // (a merge b) - (a intersection b): nesting, and every operation but union.
            "symmetric difference of two balls",
            r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "csg", operation = "merge", children = [
    { type = "sphere", center = [-0.6, 0, 0], radius = 1 },
    { type = "sphere", center = [0.6, 0, 0], radius = 1 } ] },
  { type = "csg", operation = "intersection", material = "red", children = [
    { type = "sphere", center = [-0.6, 0, 0], radius = 1 },
    { type = "sphere", center = [0.6, 0, 0], radius = 1 } ] },
]
"#
            .to_string(),
            2.0 * ball - 2.0 * lens,
        ),
        (
            // A cone with a cone-shaped bite out of its base, turned and moved off the origin.
            "cone minus cone",
            r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "cone", base = [0.3, -0.2, 0.1], cap = [0.3, 1.3, 0.1], base_radius = 1, cap_radius = 0.25 },
  { type = "cone", base = [0.3, -0.5, 0.1], cap = [0.3, 0.5, 0.1], base_radius = 0.5, cap_radius = 0 },
]
"#
            .to_string(),
            // Frustum: pi h (R^2 + R r + r^2) / 3; the bite is the part of the inner cone above
            // the base, a cone of height 0.7 and radius 0.35.
            pi * 1.5 * (1.0 + 0.25 + 0.0625) / 3.0 - pi * 0.7 * 0.35f64.powi(2) / 3.0,
        ),
    ];
    let centers = [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::new(0.3, 0.55, 0.1)];
    let failures: Vec<String> = cases
        .iter()
        .zip(centers)
        .filter_map(|((name, shapes, expected), center)| check_volume(name, shapes, center, 2.2, *expected))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Volume of the points of the box (lo, hi) that `inside` holds, by 4 million random points:
/// the reference for solids without a closed form, by point-in-solid tests that share nothing
/// with the walk of rays (about 0.1% standard deviation for these solids).
fn point_volume(lo: Vec3, hi: Vec3, inside: impl Fn(f64, f64, f64) -> bool) -> f64 {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let n = 4_000_000;
    let size = (hi - lo).as_dvec3();
    let mut count = 0u64;
    for _ in 0..n {
        let u = [splitmix(&mut state), splitmix(&mut state), splitmix(&mut state)];
        let p = lo.as_dvec3() + size * glam::DVec3::new(u[0] as f64, u[1] as f64, u[2] as f64);
        count += u64::from(inside(p.x, p.y, p.z));
    }
    size.x * size.y * size.z * count as f64 / n as f64
}

/// POV-Ray's superellipsoid with exponents (e, n) around the origin, z its pole.
fn in_superellipsoid(x: f64, y: f64, z: f64, e: f64, n: f64) -> bool {
    (x.abs().powf(2.0 / e) + y.abs().powf(2.0 / e)).powf(e / n) + z.abs().powf(2.0 / n) <= 1.0
}

/// The torus of radii (big, small) around the origin, z its axis.
fn in_torus_z(x: f64, y: f64, z: f64, big: f64, small: f64) -> bool {
    let g = x * x + y * y + z * z + big * big - small * small;
    g * g <= 4.0 * big * big * (x * x + y * y)
}

#[test]
fn tori_and_superellipsoids_as_leaves_cut_like_their_solids() {
    let pi = std::f64::consts::PI;
    // Jaklic et al. 2000 (superquadrics), with POV-Ray's east-west e and north-south n:
    // 2 e n B(n/2 + 1, n) B(e/2, e/2).
    let beta = |a: f64, b: f64| (ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b)).exp();
    let superellipsoid = |e: f64, n: f64| 2.0 * e * n * beta(n / 2.0 + 1.0, n) * beta(e / 2.0, e / 2.0);
    let cube = Vec3::splat(1.0);
    let cases = [
        (
            // The estimator on the restartable superellipsoid search itself, and its closed form.
            "superellipsoid (no CSG)",
            "[[shapes]]\ntype = \"superellipsoid\"\nmaterial = \"white\"\nexponents = [0.3, 0.6]\n".to_string(),
            superellipsoid(0.3, 0.6),
        ),
        (
            // A torus is symmetric through its centre: a half-space through it keeps half, whatever
            // the axis (2 pi^2 R r^2 in all).
            "tilted torus minus a half-space box",
            r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "torus", axis = [1, 1, 0.3], major_radius = 1, minor_radius = 0.35 },
  { type = "box", min = [0, -2, -2], max = [2, 2, 2], material = "red" },
]
"#
            .to_string(),
            pi * pi * 0.35f64.powi(2),
        ),
        (
            "ball intersection superellipsoid",
            r#"
[[shapes]]
type = "csg"
operation = "intersection"
material = "white"
children = [
  { type = "sphere", center = [0, 0, 0], radius = 1.15 },
  { type = "superellipsoid", exponents = [0.3, 0.6], material = "red" },
]
"#
            .to_string(),
            point_volume(-cube, cube, |x, y, z| {
                x * x + y * y + z * z <= 1.15 * 1.15 && in_superellipsoid(x, y, z, 0.3, 0.6)
            }),
        ),
        (
            // A rounded cylinder with a torus's groove around its waist: both implicit kinds in
            // one object, the torus subtracted.
            "superellipsoid minus torus",
            r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "white"
children = [
  { type = "superellipsoid", exponents = [1, 0.3] },
  { type = "torus", axis = [0, 0, 1], major_radius = 1, minor_radius = 0.3, material = "red" },
]
"#
            .to_string(),
            point_volume(-cube, cube, |x, y, z| in_superellipsoid(x, y, z, 1.0, 0.3) && !in_torus_z(x, y, z, 1.0, 0.3)),
        ),
    ];
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|(name, shapes, expected)| check_volume(name, shapes, Vec3::ZERO, 1.9, *expected))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9; 15 digits), for the closed forms above.
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    for (k, c) in C.iter().enumerate().skip(1) {
        a += c / (x + k as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

#[test]
fn a_closed_mesh_child_cuts_like_its_solid() {
    // A unit cube as an OBJ, subtracted from a ball that holds its corner at the centre.
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
               f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 3 4 8 7\nf 2 3 7 6\nf 1 5 8 4\n";
    std::fs::write(dir.path().join("cube.obj"), obj).unwrap();
    let text = format!(
        "{HEADER}\n[[shapes]]\ntype = \"csg\"\noperation = \"difference\"\nmaterial = \"white\"\nchildren = [\n  {{ type = \"sphere\", center = [0, 0, 0], radius = 1 }},\n  {{ type = \"mesh\", file = \"cube.obj\" }},\n]\n"
    );
    let path = dir.path().join("mesh-csg.toml");
    std::fs::File::create(&path).unwrap().write_all(text.as_bytes()).unwrap();
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let (volume, wrong_side) = ray_volume(&scene, Vec3::ZERO, 1.5, RAYS);
    // The cube takes one octant of the ball.
    let expected = 7.0 / 8.0 * 4.0 / 3.0 * std::f64::consts::PI;
    println!("ball minus mesh cube: volume {volume:.4} by rays, {expected:.4} closed form");
    assert!(
        (volume / expected - 1.0).abs() < 0.015 && wrong_side <= RAYS / 10_000,
        "{volume} vs {expected}, {wrong_side}"
    );
}

#[test]
fn union_keeps_inner_surfaces_and_merge_drops_them() {
    // Two overlapping balls along x; a ray along the x axis from outside.
    let pair = |op: &str| {
        format!(
            "[[shapes]]\ntype = \"csg\"\noperation = \"{op}\"\nmaterial = \"white\"\nchildren = [\n  {{ type = \"sphere\", center = [-0.5, 0, 0], radius = 1 }},\n  {{ type = \"sphere\", center = [0.5, 0, 0], radius = 1 }},\n]\n"
        )
    };
    let hits = |op: &str| -> Vec<f32> {
        let buffers = common::buffers(&scene_with(&pair(op)), 8, 8);
        let view = buffers.view();
        let (o, d) = (Vec3::new(-3.0, 0.01, 0.0), Vec3::X);
        let mut out = Vec::new();
        let mut t0 = 0.0;
        loop {
            let (hit, t) = trace_ray(&view, o + t0 * d, d, 10.0, false, NO_LIGHT);
            if hit == NO_LIGHT {
                return out;
            }
            t0 += t + 1e-4;
            out.push(t0 - 3.0);
        }
    };
    let near = |a: &[f32], b: &[f32]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-3);
    let union = hits("union");
    let merge = hits("merge");
    let intersection = hits("intersection");
    let difference = hits("difference");
    assert!(near(&union, &[-1.5, -0.5, 0.5, 1.5]), "union {union:?}");
    assert!(near(&merge, &[-1.5, 1.5]), "merge {merge:?}");
    assert!(near(&intersection, &[-0.5, 0.5]), "intersection {intersection:?}");
    assert!(near(&difference, &[-1.5, -0.5]), "difference {difference:?}");
}

/// A small CSG scene: a box minus a ball in red and white, a glass lens, on a floor.
fn csg_scene() -> Scene {
    let text = format!(
        "{HEADER}\n[[shapes]]\ntype = \"box\"\nmaterial = \"white\"\nmin = [-4, -1.6, -4]\nmax = [4, -1.5, 4]\n{}\n{}",
        BOX_MINUS_BALL
            .replace("min = [-1, -1, -1], max = [1, 1, 1]", "min = [-2, -1, -1], max = [0, 1, 1]")
            .replace("center = [0, 0, 0]", "center = [-1, 0, 0]"),
        LENS.replace("[-0.6, 0, 0]", "[1.4, 0, 0]").replace("[0.6, 0, 0]", "[2.6, 0, 0]")
    );
    parse_scene(&text, std::path::Path::new("csg-scene.toml")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn gpu_matches_cpu_on_a_csg_scene() {
    let scene = csg_scene();
    let buffers = common::buffers(&scene, 48, 36);
    assert!(buffers.analytic, "CSG objects need the analytic kernels");
    let cpu = common::assert_twins_agree("csg 48x36", &buffers);
    // The CSG objects are in view: red (the ball's cut) and the lens's refraction.
    let red = cpu.image.pixels.iter().filter(|p| p[0] > 2.0 * p[1] && p[0] > 0.01).count();
    assert!(red > 20, "only {red} red pixels: the subtracted ball's surface is not seen");
}

#[test]
fn gpu_matches_cpu_on_implicit_leaves() {
    // A torus with a box's bite, and a glass ball cut by a superellipsoid, on a floor.
    let text = format!(
        "{HEADER}\n[[shapes]]\ntype = \"box\"\nmaterial = \"white\"\nmin = [-4, -1.6, -4]\nmax = [4, -1.5, 4]\n{}",
        r#"
[[shapes]]
type = "csg"
operation = "difference"
material = "red"
children = [
  { type = "torus", center = [-1.2, -0.5, 0], axis = [0.2, 1, 0.4], major_radius = 0.9, minor_radius = 0.3 },
  { type = "box", min = [-1.2, -2, 0], max = [0, 2, 2], material = "white" },
]
[[shapes]]
type = "csg"
operation = "intersection"
material = "glass"
children = [
  { type = "sphere", center = [1.3, -0.3, 0], radius = 1.1 },
  { type = "superellipsoid", exponents = [0.3, 0.5], transform = { scale = 0.9, rotate = [20, 30, 0], translate = [1.3, -0.3, 0] } },
]
"#
    );
    let scene = parse_scene(&text, std::path::Path::new("csg-implicit.toml")).unwrap_or_else(|e| panic!("{e}"));
    let buffers = common::buffers(&scene, 48, 36);
    assert!(buffers.implicit, "tori and superellipsoids need the implicit kernels");
    let cpu = common::assert_twins_agree("csg with implicit leaves 48x36", &buffers);
    // The torus's cut shows its inside: the white box's faces inside the red ring.
    let red = cpu.image.pixels.iter().filter(|p| p[0] > 2.0 * p[1] && p[0] > 0.01).count();
    assert!(red > 20, "only {red} red pixels: the torus is not seen");
}

#[test]
fn a_glass_lens_renders_with_its_caustic() {
    // A lens above the floor under a point light straight above: the light it refracts onto
    // the floor (the only caustic of the scene) is concentrated in a spot under it.
    let text = format!(
        "{}\n[[shapes]]\ntype = \"quad\"\nmaterial = \"white\"\nvertices = [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]]\n{}",
        HEADER
            .replace("position = [1, 5, 3]\nintensity = 30", "position = [0, 6, 0]\nintensity = 60")
            .replace("position = [0, 1, 6]\nlook_at = [0, 0, 0]", "position = [0, 4, 4]\nlook_at = [0, 0, 0]"),
        r#"
[[shapes]]
type = "csg"
operation = "intersection"
material = "glass"
children = [
  { type = "sphere", center = [0, 3.5, 0], radius = 2 },
  { type = "sphere", center = [0, 0.5, 0], radius = 2 },
]
"#
    );
    let scene = parse_scene(&text, std::path::Path::new("lens.toml")).unwrap_or_else(|e| panic!("{e}"));
    let buffers = common::buffers(&scene, 48, 36);
    let photons = photonix::render::PhotonSettings {
        photons: 20_000,
        caustic_photons: 40_000,
        gather_rays: 1,
        ..Default::default()
    };
    let out = common::cpu_render(&buffers, 2, &photons);
    let pixels = &out.image.pixels;
    assert!(pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0), "NaN, infinite or negative pixels");
    let mean = pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / pixels.len() as f64;
    let caustics = &out.layers.caustics.pixels;
    let caustic_mean = caustics.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum::<f64>() / caustics.len() as f64;
    let caustic_max = caustics.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    println!("lens: mean {mean:.4}, caustics mean {caustic_mean:.4}, max {caustic_max:.4}");
    assert!(mean > 0.01 && mean < 10.0, "mean {mean}");
    // Only light refracted through the lens makes caustics here, and it is concentrated.
    assert!(
        caustic_mean > 1e-4 && caustic_max as f64 > 4.0 * caustic_mean,
        "caustics mean {caustic_mean}, max {caustic_max}"
    );
}

fn error_of(shapes: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, format!("{HEADER}\n{shapes}")).unwrap();
    match load_scene(&path) {
        Ok(_) => panic!("expected an error for:\n{shapes}"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, pieces: &[&str]) {
    for piece in pieces {
        assert!(message.contains(piece), "`{piece}` missing from: {message}");
    }
}

#[test]
fn bad_csg_input_names_file_line_and_field() {
    let line = |n: usize| format!("bad.toml:{}:", HEADER.lines().count() + 1 + n);
    let m = error_of(
        "[[shapes]]\ntype = \"csg\"\noperation = \"xor\"\nmaterial = \"white\"\nchildren = [{ type = \"sphere\", radius = 1, center = [0, 0, 0] }, { type = \"sphere\", radius = 1, center = [1, 0, 0] }]\n",
    );
    assert_mentions(&m, &[&line(3), "shape 0", "unknown operation \"xor\"", "difference"]);
    let m = error_of(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [\n { type = \"sphere\", radius = 1, center = [0, 0, 0] },\n { type = \"cylinder\", base = [0, 0, 0], cap = [0, 1, 0], radius = 0.5, open = true },\n]\n",
    );
    assert_mentions(&m, &[&line(7), "shape 0, child 1", "open cylinder", "drop `open`"]);
    let m = error_of(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [\n { type = \"sphere\", radius = 1, center = [0, 0, 0] },\n { type = \"quad\", vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]] },\n]\n",
    );
    assert_mentions(&m, &[&line(7), "child 1", "quad encloses no volume"]);
    let tori: Vec<String> = (0..5)
        .map(|k| format!("{{ type = \"torus\", major_radius = 1, minor_radius = 0.2, center = [{k}, 0, 0] }}"))
        .collect();
    let m = error_of(&format!(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [{}]\n",
        tori.join(", ")
    ));
    assert_mentions(&m, &[&line(5), "5 tori and superellipsoids", "at most 4"]);
    // 17 nested nodes.
    let mut nested = "{ type = \"sphere\", radius = 1, center = [0, 0, 0] }".to_string();
    for _ in 0..16 {
        nested = format!(
            "{{ type = \"csg\", operation = \"union\", children = [{nested}, {{ type = \"sphere\", radius = 1, center = [0, 0, 0] }}] }}"
        );
    }
    let m = error_of(&format!(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [{nested}, {{ type = \"sphere\", radius = 1, center = [0, 0, 0] }}]\n"
    ));
    assert_mentions(&m, &[&line(5), "nested 17 deep", "at most 16"]);
    let many: Vec<String> =
        (0..33).map(|k| format!("{{ type = \"sphere\", radius = 0.1, center = [{k}, 0, 0] }}")).collect();
    let m = error_of(&format!(
        "[[shapes]]\ntype = \"csg\"\noperation = \"merge\"\nmaterial = \"white\"\nchildren = [{}]\n",
        many.join(", ")
    ));
    assert_mentions(&m, &[&line(5), "33 leaf shapes", "at most 32"]);
    let m = error_of(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nchildren = [\n { type = \"sphere\", radius = 1, center = [0, 0, 0] },\n { type = \"sphere\", radius = 1, center = [1, 0, 0] },\n]\n",
    );
    assert_mentions(&m, &["child 0", "missing field `material`"]);
    let m = error_of(
        "[materials.lamp]\ntype = \"diffuse\"\nemission = 3\n[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [\n { type = \"sphere\", radius = 1, center = [0, 0, 0], material = \"lamp\" },\n { type = \"sphere\", radius = 1, center = [1, 0, 0] },\n]\n",
    );
    assert_mentions(&m, &[&line(9), "child 0", "emits light"]);
    let m = error_of(
        "[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\ntransform = { scale = 2 }\nchildren = [\n { type = \"sphere\", radius = 1, center = [0, 0, 0] },\n { type = \"sphere\", radius = 1, center = [1, 0, 0] },\n]\n",
    );
    assert_mentions(&m, &[&line(5), "`transform` does not apply to a csg"]);
    // An open mesh: a single triangle.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(
        &path,
        format!("{HEADER}\n[[shapes]]\ntype = \"csg\"\noperation = \"union\"\nmaterial = \"white\"\nchildren = [\n {{ type = \"sphere\", radius = 1, center = [0, 0, 0] }},\n {{ type = \"mesh\", file = \"tri.obj\" }},\n]\n"),
    )
    .unwrap();
    let m = load_scene(&path).err().map(|e| e.to_string()).unwrap_or_default();
    assert_mentions(&m, &[&line(7), "child 1", "a csg child needs a closed mesh", "3 edges"]);
}
