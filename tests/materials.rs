//! Materials and textures end to end: the glossy Cornell box against its reference, GPU = CPU on
//! a scene with every material kind and texture, alpha, bump maps and uv on every shape.

mod common;

use std::path::Path;

use glam::{Vec2, Vec3};
use photonix::cpu::bsdf::material_bsdf;
use photonix::cpu::shape::shape_surface;
use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::{read_exr, Image};
use photonix::layout::constants::{PRIMITIVE_KIND_MASK, PRIMITIVE_SPHERE};
use photonix::render::{render_cpu, PhotonSettings, SceneBuffers};
use photonix::scene::{load_scene, parse_scene, Scene};

fn parse(text: &str) -> Scene {
    // Relative texture paths resolve against the repository's scenes/ folder.
    parse_scene(text, &common::repo_path("scenes/test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// The mean of passes 0..passes of a CPU render (each pass its own photons and samples).
fn cpu_mean(buffers: &SceneBuffers, spp: u32, photons: &PhotonSettings, passes: std::ops::Range<u32>) -> Image {
    let count = passes.len() as f32;
    let mut sum: Option<Image> = None;
    for pass in passes {
        let image = render_cpu(buffers, spp, Some(photons), pass, &mut |_, _| {}).image;
        match &mut sum {
            None => sum = Some(image),
            Some(s) => s.pixels.iter_mut().zip(&image.pixels).for_each(|(a, b)| (0..3).for_each(|c| a[c] += b[c])),
        }
    }
    let mut mean = sum.expect("at least one pass");
    mean.pixels.iter_mut().for_each(|p| (0..3).for_each(|c| p[c] /= count));
    mean
}

#[test]
fn cornell_glossy_matches_reference_and_converges() {
    let scene = load_scene(&common::repo_path("scenes/cornell-glossy.toml")).unwrap();
    let reference = downsample(&read_exr(&common::reference_path("cornell-glossy")).unwrap(), 4);
    let buffers = common::buffers(&scene, 64, 64);
    let photons = PhotonSettings { photons: 50_000, caustic_photons: 50_000, gather_rays: 4, ..Default::default() };
    let early = cpu_mean(&buffers, 4, &photons, 0..2);
    let late = cpu_mean(&buffers, 4, &photons, 0..12);
    let (e_early, e_late) = (rel_mse(&early, &reference), rel_mse(&late, &reference));
    let ratio = mean_ratio(&late, &reference);
    println!("cornell-glossy 64x64: relMSE {e_early:.4} after 2 passes, {e_late:.4} after 12; mean ratio {ratio:.4?}");
    for r in ratio {
        assert!((r - 1.0).abs() < 0.03, "mean ratio {ratio:?}");
    }
    assert!(e_late < 0.7 * e_early, "relMSE must fall with passes: {e_early} -> {e_late}");
}

/// Every material kind, texture kind, a bump map, a normal map, alpha and a mix, small.
const EVERYTHING: &str = r#"
[camera]
position = [0, 1.2, 4]
look_at = [0, 0.6, 0]
fov = 45
resolution = [16, 16]

[render]
spp = 1
max_depth = 8
seed = 3

[photons]
count = 3000
caustic_count = 3000
gather_rays = 1

[textures.checks]
type = "pattern"
pattern = "checker"
space = "uv"
colors = [[0.8, 0.8, 0.8], [0.2, 0.2, 0.2]]
transform = { scale = 0.25 }

[textures.wall]
type = "image"
file = "textures/cornell-back-wall.png"

[textures.marble]
type = "pattern"
pattern = "marble"
turbulence = 0.5
transform = { scale = 0.3 }

[textures.dents]
type = "pattern"
pattern = "dents"
transform = { scale = 0.2 }

[materials.floor]
type = "diffuse"
reflectance = { texture = "checks" }

[materials.poster]
type = "diffuse"
reflectance = { texture = "wall" }
normal_map = { texture = "wall" }

[materials.gold]
type = "conductor"
preset = "gold"
roughness = 0.1

[materials.brushed]
type = "conductor"
preset = "aluminium"
roughness = [0.05, 0.4]

[materials.glass]
type = "dielectric"
ior = 1.5
roughness = 0.3

[materials.plastic]
type = "plastic"
reflectance = { texture = "marble" }
bump = { texture = "dents", scale = 0.01 }

[materials.varnish]
type = "plastic"
reflectance = [0.2, 0.4, 0.7]
roughness = 0.4

[materials.blend]
type = "mix"
materials = ["gold", "varnish"]
weight = { texture = "checks" }

[materials.lace]
type = "diffuse"
reflectance = [0.8, 0.2, 0.2]
opacity = { texture = "checks" }

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "quad"
material = "poster"
vertices = [[-2, 0, -1.5], [2, 0, -1.5], [2, 2, -1.5], [-2, 2, -1.5]]

[[shapes]]
type = "sphere"
material = "gold"
center = [-1.2, 0.4, 0]
radius = 0.4

[[shapes]]
type = "sphere"
material = "glass"
center = [0, 0.4, 0.5]
radius = 0.4

[[shapes]]
type = "sphere"
material = "plastic"
center = [1.2, 0.4, 0]
radius = 0.4

[[shapes]]
type = "sphere"
material = "blend"
center = [0.6, 1.2, -0.5]
radius = 0.3

[[shapes]]
type = "box"
material = "brushed"
min = [-0.3, 0, -1.2]
max = [0.3, 0.5, -0.8]

[[shapes]]
type = "sphere"
material = "lace"
center = [-0.5, 1.3, 0.2]
radius = 0.25

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#;

#[test]
fn gpu_matches_cpu_with_every_material_and_texture() {
    let scene = parse(EVERYTHING);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let buffers = common::buffers(&scene, 16, 16);
    // Textures and an opacity texture: the build with the alpha test.
    assert!(buffers.textured && buffers.alpha, "the scene needs the textured alpha kernels");
    let photons = scene.photons.unwrap();
    let cpu = common::cpu_render(&buffers, 1, &photons);
    let ctx = common::gpu();
    let gpu = common::gpu_render(&ctx, &buffers, 1, &photons);
    let error = rel_mse(&gpu.image, &cpu.image);
    println!("every material and texture, 16x16: GPU vs CPU relMSE {error:e}");
    // The pattern twins agree bit for bit except through pow (1.5e-6 at most, see
    // tests/pattern_gpu.rs); a bumped normal or a hashed alpha decision can flip on that.
    assert!(error < 1e-3, "GPU and CPU differ: relMSE {error}");
    assert!(cpu.image.pixels.iter().any(|p| p[0] > 0.0), "the image is not black");
}

/// The scene of a few spheres, optionally with one more that is fully transparent.
fn spheres(with_ghost: bool) -> String {
    let ghost = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"ghost\"\ncenter = [0, 0.5, 0.5]\nradius = 0.5\n";
    format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40
resolution = [24, 24]
[render]
spp = 2
[photons]
count = 5000
caustic_count = 5000
gather_rays = 1
[materials.white]
type = "diffuse"
[materials.ghost]
type = "diffuse"
reflectance = [1, 0, 0]
opacity = 0
[[shapes]]
type = "quad"
material = "white"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]
[[shapes]]
type = "sphere"
material = "white"
center = [0.8, 0.3, -0.5]
radius = 0.3
{}
[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#,
        if with_ghost { ghost } else { "" }
    )
}

#[test]
fn fully_transparent_object_vanishes() {
    let render = |text: &str| {
        let scene = parse(text);
        let buffers = common::buffers(&scene, 24, 24);
        common::cpu_render(&buffers, 2, &scene.photons.unwrap()).image
    };
    let (with, without) = (render(&spheres(true)), render(&spheres(false)));
    // Camera rays, shadow rays and photons all pass the ghost; its red would show anywhere else.
    assert_eq!(with.pixels, without.pixels, "an opacity-0 sphere changed the image");
}

/// The hit record of the first primitive of kind `kind` at point `x`.
fn hit_on(buffers: &SceneBuffers, kind: u32, x: Vec3) -> photonix::cpu::shape::Hit {
    let i = buffers.primitives.iter().position(|p| p.kind & PRIMITIVE_KIND_MASK == kind).expect("a primitive of kind");
    shape_surface(&buffers.view(), i as u32, x)
}

#[test]
fn bump_tilts_the_shading_normal_away_from_rising_ground() {
    // A floor whose height grows along +x (gradient pattern, world space): the bumped normal leans
    // toward -x, by atan(slope); the geometric normal stays +y.
    let text = r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0, 0]
fov = 40
[textures.ramp]
type = "pattern"
pattern = "gradient"
direction = [1, 0, 0]
space = "world"
transform = { scale = 10 }
[materials.bumpy]
type = "diffuse"
bump = { texture = "ramp", scale = 0.5 }
[[shapes]]
type = "quad"
material = "bumpy"
vertices = [[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]]
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = 1
"#;
    let scene = parse(text);
    let buffers = common::buffers(&scene, 8, 8);
    let view = buffers.view();
    let h = hit_on(&buffers, photonix::layout::constants::PRIMITIVE_TRIANGLE, Vec3::new(0.2, 0.0, 0.1));
    let b = material_bsdf(&view, &view.materials[h.material as usize], &h);
    // Height 0.5 * x / 10 rises by 0.05 per unit of x: the normal is (-0.05, 1, 0) normalised.
    let expected = Vec3::new(-0.05, 1.0, 0.0).normalize();
    println!("bumped normal {} (expected {expected}), geometric {}", b.ns, b.ng);
    assert!(b.ns.abs_diff_eq(expected, 1e-3), "bumped normal {}", b.ns);
    assert!(b.ng.abs_diff_eq(Vec3::Y, 1e-6));
}

#[test]
fn uv_on_every_shape_matches_hand_computed_values() {
    let text = format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0, 0]
fov = 40
[materials.textured]
type = "diffuse"
reflectance = {{ texture = "grey" }}
[textures.grey]
type = "pattern"
pattern = "checker"
[[shapes]]
type = "quad"
material = "textured"
vertices = [[0, 0, 0], [2, 0, 0], [2, 0, -1], [0, 0, -1]]
[[shapes]]
type = "sphere"
material = "textured"
center = [0, 5, 0]
radius = 2
[[shapes]]
type = "mesh"
material = "textured"
file = "{}"
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = 1
"#,
        common::repo_path("scenes/meshes/cornell-glossy/floor.obj").display()
    );
    let scene = parse(&text);
    let buffers = common::buffers(&scene, 8, 8);
    let view = buffers.view();
    // Quad: uv (0, 0) at v0, (1, 0) at v1, (1, 1) at v2, (0, 1) at v3; bilinear inside a triangle.
    let on_quad = |x: Vec3| {
        let i = buffers.primitives.iter().position(|p| p.p0 == [0.0, 0.0, 0.0] && p.kind & PRIMITIVE_KIND_MASK == 0);
        shape_surface(&view, i.unwrap() as u32, x).uv
    };
    assert!(on_quad(Vec3::new(2.0, 0.0, -0.5)).abs_diff_eq(Vec2::new(1.0, 0.5), 1e-5));
    assert!(on_quad(Vec3::new(1.0, 0.0, -0.25)).abs_diff_eq(Vec2::new(0.5, 0.25), 1e-5));
    // Sphere: v = 1 at the north pole (+y), 0.5 on the equator; u = 0.5 toward +z, 0.75 toward +x.
    let sphere = |x: Vec3| hit_on(&buffers, PRIMITIVE_SPHERE, x);
    assert!((sphere(Vec3::new(0.0, 7.0, 0.0)).uv.y - 1.0).abs() < 1e-5);
    let front = sphere(Vec3::new(0.0, 5.0, 2.0));
    assert!(front.uv.abs_diff_eq(Vec2::new(0.5, 0.5), 1e-5), "{}", front.uv);
    assert!(sphere(Vec3::new(2.0, 5.0, 0.0)).uv.abs_diff_eq(Vec2::new(0.75, 0.5), 1e-5));
    // dpdu runs along increasing u: at the front, toward +x.
    assert!(front.dpdu.normalize().abs_diff_eq(Vec3::X, 1e-5), "{}", front.dpdu);
    // OBJ mesh: the reference floor's vt, (0, 0) at (552.8, 0, 0) and (1, 1) at (0, 0, 559.2).
    let mesh = buffers.primitives.iter().position(|p| p.p0 == [552.8, 0.0, 0.0]).unwrap() as u32;
    assert!(shape_surface(&view, mesh, Vec3::new(552.8, 0.0, 0.0)).uv.abs_diff_eq(Vec2::ZERO, 1e-5));
    assert!(shape_surface(&view, mesh, Vec3::new(0.0, 0.0, 559.2)).uv.abs_diff_eq(Vec2::ONE, 1e-5));
    let _ = Path::new("");
}

/// The material kinds are a specialization constant (`KernelVariant::material_kinds`): each
/// kind's code is compiled only into the kernels of scenes that have it. A kind met only through a
/// mix counts, media bring the phase function, and the kernels built for a mix of plastic and a
/// mirror (no dielectric, conductor or phase) render it as the CPU twin does with vcm and ppm.
#[test]
fn material_kinds_are_compiled_in_only_where_a_scene_has_them() {
    use photonix::layout::constants::*;
    let bits = |kinds: &[u32]| kinds.iter().fold(0u32, |b, k| b | 1 << k);
    for integrator in ["vcm", "ppm"] {
        let scene = parse(&format!(
            r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40

[render]
integrator = "{integrator}"

[materials.floor]
type = "diffuse"
reflectance = 0.7

[materials.coat]
type = "plastic"
reflectance = [0.7, 0.2, 0.1]
roughness = 0.2

[materials.mirror]
type = "mirror"

[materials.blend]
type = "mix"
materials = ["coat", "mirror"]
weight = 0.5

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "sphere"
material = "blend"
center = [0, 0.6, 0]
radius = 0.6

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#
        ));
        let buffers = common::buffers(&scene, 24, 24);
        let kinds = buffers.variant().material_kinds;
        let want = bits(&[MATERIAL_DIFFUSE, MATERIAL_PLASTIC, MATERIAL_MIRROR, MATERIAL_MIX]);
        // The area light's own material is diffuse too (black, emitting).
        assert_eq!(kinds & !want, 0, "{integrator}: kinds {kinds:#b}");
        assert_eq!(kinds & want, want, "{integrator}: kinds {kinds:#b}");
        let out = common::assert_twins_agree(&format!("a mix of plastic and a mirror, {integrator}"), &buffers);
        assert!(out.image.pixels.iter().any(|p| p[0] > 0.0), "{integrator}: the image is not black");
    }
    let kinds_of =
        |path: &str| common::buffers(&load_scene(&common::repo_path(path)).unwrap(), 8, 8).variant().material_kinds;
    let glossy = kinds_of("scenes/cornell-glossy.toml");
    assert_eq!(
        glossy,
        bits(&[MATERIAL_DIFFUSE, MATERIAL_DIELECTRIC, MATERIAL_CONDUCTOR]),
        "cornell-glossy: {glossy:#b}"
    );
    let fog = kinds_of("scenes/cornell-fog.toml");
    assert_ne!(fog & bits(&[MATERIAL_PHASE]), 0, "cornell-fog's medium scatters: {fog:#b}");
}

/// A smooth and a rough nonlinear plastic (the rough one reads its coat table from the texture
/// data, in a scene with no texture), and a linear one beside them.
fn plastics(integrator: &str, nonlinear: bool) -> String {
    format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40

[render]
integrator = "{integrator}"

[materials.floor]
type = "diffuse"
reflectance = 0.7

[materials.smooth]
type = "plastic"
reflectance = [0.7, 0.2, 0.1]
nonlinear = {nonlinear}

[materials.rough]
type = "plastic"
reflectance = [0.2, 0.4, 0.7]
roughness = 0.3
nonlinear = {nonlinear}

[materials.linear]
type = "plastic"
reflectance = 0.5
roughness = 0.1

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "sphere"
material = "smooth"
center = [-0.7, 0.5, 0]
radius = 0.5

[[shapes]]
type = "sphere"
material = "rough"
center = [0.7, 0.5, 0]
radius = 0.5

[[shapes]]
type = "sphere"
material = "linear"
center = [0, 1.2, -0.8]
radius = 0.3

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#
    )
}

#[test]
fn nonlinear_plastic_twins_agree_on_every_integrator() {
    for integrator in ["ppm", "pt", "bpt", "vcm"] {
        let scene = parse(&plastics(integrator, true));
        let buffers = common::buffers(&scene, 24, 24);
        assert!(!buffers.textured, "the coat table needs no textured kernels");
        let out = common::assert_twins_agree(&format!("nonlinear plastics, {integrator}"), &buffers);
        assert!(out.image.pixels.iter().any(|p| p[0] > 0.0), "{integrator}: the image is not black");
    }
}

#[test]
fn nonlinear_plastic_is_darker_than_linear() {
    // Under its coat a base of albedo a bounces back up 1 / (1 - a Fdr_int) instead of
    // 1 / (1 - Fdr_int): every channel of both spheres darkens (the smooth red by about 0.45,
    // 0.2 and 0.18 of the linear's base for a = 0.7, 0.2, 0.1 at ior 1.5).
    let render = |nonlinear: bool| {
        let scene = parse(&plastics("pt", nonlinear));
        let buffers = common::buffers(&scene, 24, 24);
        common::cpu_render(&buffers, 4, &common::test_photons()).image
    };
    let (linear, nonlinear) = (render(false), render(true));
    let ratio = photonix::io::metrics::mean_ratio(&nonlinear, &linear);
    println!("nonlinear / linear mean: {ratio:.4?}");
    for r in ratio {
        assert!(r < 0.97 && r > 0.3, "mean ratio {ratio:?}");
    }
}

/// A thin pane in front of a tinted metal ball whose tint is a checker texture, over a floor.
fn panes(integrator: &str) -> String {
    format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40

[render]
integrator = "{integrator}"

[textures.checks]
type = "pattern"
pattern = "checker"
space = "uv"
colors = [[0.9, 0.5, 0.2], [0.3, 0.6, 0.9]]
transform = {{ scale = 0.25 }}

[materials.floor]
type = "diffuse"
reflectance = 0.7

[materials.window]
type = "thin_dielectric"
ior = 1.5

[materials.brass]
type = "conductor"
preset = "gold"
roughness = 0.3
tint = {{ texture = "checks" }}

[materials.chrome]
type = "conductor"
preset = "chrome"
tint = [0.5, 0.7, 0.9]

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "quad"
material = "window"
vertices = [[-1.5, 0, 1], [1.5, 0, 1], [1.5, 1.6, 1.3], [-1.5, 1.6, 1.3]]

[[shapes]]
type = "sphere"
material = "brass"
center = [-0.6, 0.5, 0]
radius = 0.5

[[shapes]]
type = "sphere"
material = "chrome"
center = [0.6, 0.5, 0]
radius = 0.5

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#
    )
}

#[test]
fn thin_dielectric_and_tinted_conductor_twins_agree_on_every_integrator() {
    use photonix::layout::constants::*;
    for integrator in ["ppm", "pt", "bpt", "vcm"] {
        let scene = parse(&panes(integrator));
        let buffers = common::buffers(&scene, 24, 24);
        let kinds = buffers.variant().material_kinds;
        assert_ne!(kinds & 1 << MATERIAL_THIN_DIELECTRIC, 0, "kinds {kinds:#b}");
        let out = common::assert_twins_agree(&format!("a pane and tinted metals, {integrator}"), &buffers);
        assert!(out.image.pixels.iter().any(|p| p[0] > 0.0), "{integrator}: the image is not black");
    }
    // Without a pane the kind compiles out.
    let scene = parse(&plastics("pt", true));
    assert_eq!(common::buffers(&scene, 8, 8).variant().material_kinds & 1 << MATERIAL_THIN_DIELECTRIC, 0);
}

#[test]
fn thin_dielectric_in_a_white_furnace_is_invisible() {
    // A pane absorbs nothing: under a uniform sky of radiance 1 every path that leaves through
    // it or off it sees 1, so a ball of thin glass (seen through twice, reflecting inside)
    // renders 1: every weight is 1, and only Russian roulette (from a path's fifth vertex, a
    // path reflected inside the ball) moves a sample off 1, in expectation not at all. Measured
    // at 16 spp: mean 1.0003 over 64 spp, half the pixels exactly 1.
    let scene = parse(
        r#"
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
fov = 40

[render]
integrator = "pt"
max_depth = 64

[materials.pane]
type = "thin_dielectric"
ior = 1.7

[[shapes]]
type = "sphere"
material = "pane"
center = [0, 0, 0]
radius = 1

[environment]
type = "uniform"
radiance = [1, 1, 1]
"#,
    );
    let buffers = common::buffers(&scene, 12, 12);
    let out = common::cpu_render(&buffers, 16, &common::test_photons());
    let values: Vec<f32> = out.image.pixels.iter().flat_map(|p| p.iter().take(3).copied()).collect();
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
    let exact = values.iter().filter(|&&v| v == 1.0).count();
    println!("thin dielectric furnace: mean {mean:.5}, {exact} of {} values exactly 1", values.len());
    assert!((mean - 1.0).abs() < 5e-3, "a pane absorbed or added light: mean {mean}");
    assert!(exact * 2 > values.len(), "most pixels should be exactly 1: {exact} of {}", values.len());
}

/// Beckmann microfacets on every rough kind: a conductor, a nonlinear plastic (its coat table
/// computed for Beckmann), a rough glass, beside a GGX conductor of the same width.
fn beckmann_scene(integrator: &str) -> String {
    format!(
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 40

[render]
integrator = "{integrator}"

[materials.floor]
type = "diffuse"
reflectance = 0.7

[materials.metal]
type = "conductor"
preset = "gold"
roughness = [0.15, 0.3]
distribution = "beckmann"

[materials.ggx_metal]
type = "conductor"
preset = "gold"
roughness = 0.15

[materials.coat]
type = "plastic"
reflectance = [0.2, 0.4, 0.7]
roughness = 0.2
distribution = "beckmann"
nonlinear = true

[materials.glass]
type = "dielectric"
roughness = 0.1
distribution = "beckmann"

[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, 3], [3, 0, 3], [3, 0, -3], [-3, 0, -3]]

[[shapes]]
type = "sphere"
material = "metal"
center = [-0.7, 0.5, 0]
radius = 0.5

[[shapes]]
type = "sphere"
material = "coat"
center = [0.7, 0.5, 0]
radius = 0.5

[[shapes]]
type = "sphere"
material = "glass"
center = [0, 0.3, 0.9]
radius = 0.3

[[shapes]]
type = "sphere"
material = "ggx_metal"
center = [0, 1.2, -0.8]
radius = 0.3

[[lights]]
type = "area"
shape = "quad"
vertices = [[-0.5, 2.5, -0.5], [0.5, 2.5, -0.5], [0.5, 2.5, 0.5], [-0.5, 2.5, 0.5]]
radiance = 10
"#
    )
}

#[test]
fn beckmann_twins_agree_on_every_integrator_and_compile_only_where_used() {
    use photonix::layout::constants::*;
    for integrator in ["ppm", "pt", "bpt", "vcm"] {
        let scene = parse(&beckmann_scene(integrator));
        let buffers = common::buffers(&scene, 24, 24);
        let kinds = buffers.variant().material_kinds;
        assert_ne!(kinds & 1 << SCENE_KIND_BECKMANN, 0, "kinds {kinds:#b}");
        let flagged = buffers.materials.iter().filter(|m| m.flags & MATERIAL_FLAG_BECKMANN != 0).count();
        assert_eq!(flagged, 3, "three Beckmann materials");
        let out = common::assert_twins_agree(&format!("Beckmann metal, plastic and glass, {integrator}"), &buffers);
        assert!(out.image.pixels.iter().any(|p| p[0] > 0.0), "{integrator}: the image is not black");
    }
    // The same scene with GGX everywhere: no Beckmann bit, and a different image (the CPU twin,
    // the Beckmann lobes are tighter with less glow at the same alpha).
    let ggx_text = beckmann_scene("pt").replace("distribution = \"beckmann\"\n", "");
    let ggx = common::buffers(&parse(&ggx_text), 24, 24);
    assert_eq!(ggx.variant().material_kinds & 1 << SCENE_KIND_BECKMANN, 0);
    assert!(ggx.materials.iter().all(|m| m.flags & MATERIAL_FLAG_BECKMANN == 0));
    let beckmann = common::buffers(&parse(&beckmann_scene("pt")), 24, 24);
    let photons = common::test_photons();
    let (a, b) = (common::cpu_render(&ggx, 4, &photons), common::cpu_render(&beckmann, 4, &photons));
    let differ = photonix::io::metrics::rel_mse(&a.image, &b.image);
    println!("GGX vs Beckmann relMSE {differ:.3e}");
    assert!(differ > 1e-4, "{differ}");
}
