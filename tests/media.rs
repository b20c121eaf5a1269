//! Participating media against analytic answers and the shared reference: Beer-Lambert
//! transmittance of camera and shadow rays, single scattering against numerical quadrature, an
//! energy-conserving furnace, the cornell-fog ground truth, and the GPU against the CPU.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;
use photonix::cpu::grid::for_each_photon_near;
use photonix::cpu::photon::{photon_flags, photon_flux};
use photonix::io::metrics::{downsample, mean_ratio, rel_mse};
use photonix::io::{read_exr, Image};
use photonix::render::{render_cpu, PhotonSettings};
use photonix::scene::{load_scene, parse_scene, Scene};

fn scene(text: &str) -> Scene {
    let scene = parse_scene(text, Path::new("media-test.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    scene
}

// Camera rays: an emitter of radiance 1 seen through a slab of absorbing medium

/// An emitter of radiance 1 at z = 0 facing +z, behind a null box z in [1, 1 + depth] holding a
/// purely absorbing medium, seen head-on by an orthographic camera that sees only the emitter.
fn emitter_behind_slab(sigma_a: [f64; 3], depth: f64) -> Scene {
    scene(&format!(
        r#"
[camera]
type = "orthographic"
position = [0, 0, 10]
look_at = [0, 0, 0]
view_height = 1
resolution = [32, 32]
[render]
spp = 16
[photons]
enabled = false
[materials.lamp]
type = "diffuse"
reflectance = 0
emission = 1
[materials.boundary]
type = "null"
[media.ink]
sigma_a = [{}, {}, {}]
[[shapes]]
type = "quad"
material = "lamp"
vertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
[[shapes]]
type = "box"
material = "boundary"
interior = "ink"
min = [-2, -2, 1]
max = [2, 2, {}]
"#,
        sigma_a[0],
        sigma_a[1],
        sigma_a[2],
        1.0 + depth
    ))
}

#[test]
fn camera_rays_through_absorbing_slab_follow_beer_lambert() {
    let ctx = common::gpu();
    // Grey and chromatic absorption; the chromatic one checks the spectral MIS of free flights.
    for sigma_a in [[0.5, 0.5, 0.5], [0.2, 1.0, 2.0]] {
        let depth = 1.5;
        let s = emitter_behind_slab(sigma_a, depth);
        let buffers = common::buffers(&s, 32, 32);
        for (backend, image) in
            [("cpu", common::cpu_image(&buffers, 16)), ("gpu", common::gpu_image(&ctx, &buffers, 16))]
        {
            let mean = image.channel_means();
            for c in 0..3 {
                let expected = (-sigma_a[c] * depth).exp();
                // A free flight through a non-scattering medium passes (weight T / mean T) or is
                // absorbed; 16384 samples give a standard deviation of the mean below 0.005 (at
                // most sqrt(T (1 - T) / N) times the largest weight, 2): 4 sigma is 0.02.
                println!("{backend} sigma_a {:?}: channel {c}: {:.4} vs exp(-sigma d) {expected:.4}", sigma_a, mean[c]);
                assert!((mean[c] - expected).abs() < 0.02, "{backend} channel {c}: {} vs {expected}", mean[c]);
            }
        }
    }
}

// Shadow rays: a wall lit by a point light through a slab the camera does not look through

/// A wall x = 0 facing +x, lit by a point light at (3, 0, 0) through a null box x in [1, 2]
/// (|y|, |z| <= 0.5) of absorbing medium; the camera looks at the wall's centre obliquely from
/// (5, 0, 5), past the box, with a field of view so narrow that every shadow ray runs 1.0006 or
/// less through the slab.
fn wall_behind_slab(sigma_a: f64) -> Scene {
    scene(&format!(
        r#"
[camera]
position = [5, 0, 5]
look_at = [0, 0, 0]
fov = 1.5
resolution = [16, 16]
[render]
spp = 4
[photons]
enabled = false
[materials.wall]
type = "diffuse"
reflectance = 0.8
[materials.boundary]
type = "null"
[media.ink]
sigma_a = {sigma_a}
[[shapes]]
type = "quad"
material = "wall"
vertices = [[0, -2, -2], [0, 2, -2], [0, 2, 2], [0, -2, 2]]
[[shapes]]
type = "box"
material = "boundary"
interior = "ink"
min = [1, -0.5, -0.5]
max = [2, 0.5, 0.5]
[[lights]]
type = "point"
position = [3, 0, 0]
intensity = 10
"#
    ))
}

#[test]
fn shadow_rays_through_absorbing_slab_follow_beer_lambert() {
    let ctx = common::gpu();
    let clear = common::buffers(&wall_behind_slab(0.0), 16, 16);
    let reference = common::cpu_image(&clear, 4);
    assert!(reference.channel_means()[0] > 0.01, "the wall is lit");
    for sigma_a in [0.3, 1.0, 3.0] {
        let buffers = common::buffers(&wall_behind_slab(sigma_a), 16, 16);
        for (backend, image) in [("cpu", common::cpu_image(&buffers, 4)), ("gpu", common::gpu_image(&ctx, &buffers, 4))]
        {
            // The same camera samples and light samples with and without the medium: the ratio is
            // the transmittance alone, exp(-sigma len) with len in [1, 1.0006].
            let ratio = image.channel_means()[0] / reference.channel_means()[0];
            let expected = (-sigma_a).exp();
            println!("{backend} sigma_a {sigma_a}: ratio {ratio:.5} vs exp(-sigma) {expected:.5}");
            assert!((ratio / expected - 1.0).abs() < 0.003, "{backend}: {ratio} vs {expected}");
        }
    }
}

// Single scattering: a point light in an unbounded medium, against quadrature

const SS_SIZE: u32 = 8;
const SS_FOV_DEG: f64 = 30.0;
// Out of view (37 degrees off the axis, the view's corners are at 21), so that no ray passes
// through the light's singularity, which neither quadrature nor sampling resolves well.
const SS_LIGHT: DVec3 = DVec3::new(3.0, 0.0, 4.0);
const SS_INTENSITY: f64 = 20.0;
const SS_SIGMA_A: f64 = 0.05;
const SS_SIGMA_S: f64 = 0.15;

fn point_light_in_fog(g: f64) -> Scene {
    let phase = if g == 0.0 { String::new() } else { format!("phase = \"henyey-greenstein\"\ng = {g}\n") };
    scene(&format!(
        r#"
[camera]
position = [0, 0, 0]
look_at = [0, 0, 1]
fov = {SS_FOV_DEG}
resolution = [{SS_SIZE}, {SS_SIZE}]
[render]
spp = 2048
[photons]
enabled = false
[media.fog]
sigma_a = {SS_SIGMA_A}
sigma_s = {SS_SIGMA_S}
{phase}
[atmosphere]
medium = "fog"
[[lights]]
type = "point"
position = [{}, {}, {}]
intensity = {SS_INTENSITY}
"#,
        SS_LIGHT.x, SS_LIGHT.y, SS_LIGHT.z
    ))
}

fn hg(cos_theta: f64, g: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// Single-scattered radiance along the ray from the origin in direction `d`: the integral over t
/// of T(t) sigma_s p(theta) I / r^2 T(r), by the midpoint rule in the variable u = 1 - exp(-t)
/// (which maps [0, inf) onto [0, 1) and puts the steps where the integrand lives).
fn single_scattering(d: DVec3, g: f64) -> f64 {
    let sigma_t = SS_SIGMA_A + SS_SIGMA_S;
    let steps = 20_000;
    let mut sum = 0.0;
    for i in 0..steps {
        let u = (i as f64 + 0.5) / steps as f64;
        let t = -(1.0 - u).ln();
        let dt_du = 1.0 / (1.0 - u);
        let x = d * t;
        let to_light = SS_LIGHT - x;
        let r2 = to_light.length_squared();
        let r = r2.sqrt();
        // The light travels along -to_light, then along -d toward the camera.
        let cos_theta = (-to_light / r).dot(-d);
        let f = (-sigma_t * t).exp() * SS_SIGMA_S * hg(cos_theta, g) * SS_INTENSITY / r2 * (-sigma_t * r).exp();
        sum += f * dt_du;
    }
    sum / steps as f64
}

/// The expected image: each pixel the mean of the quadrature over a 6x6 grid of points in it
/// (the camera's mapping of film positions to rays, `camera_ray`).
fn single_scattering_image(g: f64) -> Vec<f64> {
    let half = (SS_FOV_DEG.to_radians() * 0.5).tan();
    let (forward, right, up) = (DVec3::Z, DVec3::new(-1.0, 0.0, 0.0), DVec3::Y);
    let mut out = Vec::new();
    for py in 0..SS_SIZE {
        for px in 0..SS_SIZE {
            let mut sum = 0.0;
            for j in 0..36 {
                let (jx, jy) = ((j % 6) as f64 + 0.5, (j / 6) as f64 + 0.5);
                let sx = 2.0 * (px as f64 + jx / 6.0) / SS_SIZE as f64 - 1.0;
                let sy = 1.0 - 2.0 * (py as f64 + jy / 6.0) / SS_SIZE as f64;
                let d = (forward + sx * half * right + sy * half * up).normalize();
                sum += single_scattering(d, g);
            }
            out.push(sum / 36.0);
        }
    }
    out
}

#[test]
fn single_scattering_from_a_point_light_matches_quadrature() {
    for g in [0.0, 0.6] {
        let s = point_light_in_fog(g);
        let buffers = common::buffers(&s, SS_SIZE, SS_SIZE);
        // Without photon maps, single scattering from a point light is all there is: the
        // equiangular samples of the camera rays (scattering points leave point lights to them).
        let image = common::cpu_image(&buffers, 2048);
        let expected = single_scattering_image(g);
        let measured: Vec<f64> = image.pixels.iter().map(|p| p[0] as f64).collect();
        let (m_sum, e_sum): (f64, f64) = (measured.iter().sum(), expected.iter().sum());
        let worst = measured.iter().zip(&expected).map(|(m, e)| (m / e - 1.0).abs()).fold(0.0, f64::max);
        println!(
            "g {g}: image mean {:.5} vs quadrature {:.5}; worst pixel off by {worst:.3}",
            m_sum / 64.0,
            e_sum / 64.0
        );
        // 131072 samples in all: the mean is within 2%; a pixel's 2048 within 15%.
        assert!((m_sum / e_sum - 1.0).abs() < 0.02, "g {g}: {m_sum} vs {e_sum}");
        assert!(worst < 0.15, "g {g}: a pixel is {worst} off");
        // The light sits right of the centre (+x is image left with this camera): the left
        // half is brighter, and the GPU is checked against the CPU elsewhere.
        let left: f64 = (0..SS_SIZE as usize).flat_map(|y| (0..4).map(move |x| y * 8 + x)).map(|i| measured[i]).sum();
        let right: f64 = (0..SS_SIZE as usize).flat_map(|y| (4..8).map(move |x| y * 8 + x)).map(|i| measured[i]).sum();
        assert!(left > right, "the side of the light is brighter: {left} vs {right}");
    }
}

// Furnace: a closed emitting box filled with a medium that absorbs nothing

/// A closed box of walls that reflect rho = 0.5 and emit 0.5 into the box (radiance 1 everywhere
/// inside at equilibrium: L = Le / (1 - rho)), filled with a medium of albedo 1; the camera
/// stands inside it. A medium that only scatters leaves an isotropic, uniform radiance field
/// unchanged, so the image is 1 everywhere.
fn furnace() -> Scene {
    let mut text = String::from(
        r#"
[camera]
position = [0.1, -0.2, 0.05]
look_at = [1, 0.3, 0.8]
fov = 90
resolution = [24, 24]
[render]
max_depth = 8
integrator = "ppm"   # the volume photon map's furnace (bpt's paths would end at 8 vertices)
[photons]
count = 100000
caustic_count = 1
gather_rays = 4
max_depth = 32
[materials.wall]
type = "diffuse"
reflectance = 0.5
emission = 0.5
[materials.boundary]
type = "null"
[media.mist]
sigma_s = 0.5
[[shapes]]
type = "box"
material = "boundary"
interior = "mist"
min = [-0.99, -0.99, -0.99]
max = [0.99, 0.99, 0.99]
"#,
    );
    // The six walls of [-1, 1]^3, wound inward so that they emit into the box (checked below).
    let faces = [
        "[[1, -1, -1], [1, 1, -1], [-1, 1, -1], [-1, -1, -1]]",
        "[[-1, 1, 1], [1, 1, 1], [1, -1, 1], [-1, -1, 1]]",
        "[[-1, -1, 1], [1, -1, 1], [1, -1, -1], [-1, -1, -1]]",
        "[[1, 1, -1], [1, 1, 1], [-1, 1, 1], [-1, 1, -1]]",
        "[[-1, 1, -1], [-1, 1, 1], [-1, -1, 1], [-1, -1, -1]]",
        "[[1, -1, 1], [1, 1, 1], [1, 1, -1], [1, -1, -1]]",
    ];
    for f in faces {
        text.push_str(&format!("[[shapes]]\ntype = \"quad\"\nmaterial = \"wall\"\nvertices = {f}\n"));
    }
    scene(&text)
}

#[test]
fn furnace_box_with_albedo_one_medium_conserves_energy() {
    let s = furnace();
    for shape in &s.shapes[12..] {
        let photonix::scene::Geometry::Triangle(t) = &shape.geometry else { panic!("walls are triangles") };
        let [a, b, c] = t.vertices;
        let centre = (a + b + c) / 3.0;
        assert!((b - a).cross(c - a).dot(-centre) > 0.0, "a wall faces out of the box");
    }
    let buffers = common::buffers(&s, 24, 24);
    let settings = s.photons.unwrap();
    let out = render_cpu(&buffers, 4, Some(&settings), 0, &mut |_, _| {});
    let mean = out.image.channel_means();
    let lowest = out.image.pixels.iter().map(|p| p[0]).fold(f32::INFINITY, f32::min);
    println!("furnace: mean {mean:.4?}, darkest pixel {lowest:.3}");
    for c in mean {
        // Photon density estimates lose a little at the box's edges and corners.
        assert!((c - 1.0).abs() < 0.05, "mean radiance {c}, expected 1");
    }
}

// The reference: cornell-fog

const FOG_SIZE: u32 = 64;

fn fog_settings() -> PhotonSettings {
    PhotonSettings { photons: 100_000, caustic_photons: 20_000, gather_rays: 4, ..PhotonSettings::default() }
}

#[test]
fn cornell_fog_matches_reference_and_converges_with_passes() {
    let scene = load_scene(&common::repo_path("scenes/cornell-fog.toml")).unwrap();
    let reference =
        downsample(&read_exr(&common::reference_path("cornell-fog")).expect("shared reference is readable"), 4);
    let buffers = common::buffers(&scene, FOG_SIZE, FOG_SIZE);
    let settings = fog_settings();
    let mut sum = Image::new(FOG_SIZE, FOG_SIZE);
    let mut errors = Vec::new();
    for pass in 0..8 {
        let out = render_cpu(&buffers, 4, Some(&settings), pass, &mut |_, _| {});
        for (s, p) in sum.pixels.iter_mut().zip(&out.image.pixels) {
            for c in 0..3 {
                s[c] += p[c];
            }
        }
        let mut mean = sum.clone();
        for p in &mut mean.pixels {
            *p = p.map(|c| c / (pass + 1) as f32);
        }
        if (pass + 1).is_power_of_two() {
            let error = rel_mse(&mean, &reference);
            let ratio = mean_ratio(&mean, &reference);
            println!("cornell-fog cpu, {} passes: relMSE {error:.5}, mean ratio {ratio:.4?}", pass + 1);
            errors.push(error);
            // Light sampling at scattering points just below the lamp has heavy tails (its 1/d^2
            // is not cancelled), so single passes swing by several per cent; the mean of 8
            // passes (128 samples per 256x256-pixel area) is held to the 3%.
            if pass + 1 == 8 {
                for r in ratio {
                    assert!((r - 1.0).abs() < 0.03, "mean ratio {ratio:?} after {} passes", pass + 1);
                }
            }
        }
    }
    for pair in errors.windows(2) {
        assert!(pair[1] < pair[0], "relMSE does not fall with passes: {errors:?}");
    }
    assert!(errors[3] < 0.6 * errors[0], "8 passes should cut the error well below 1 pass's: {errors:?}");
}

#[test]
fn gpu_renders_cornell_fog_as_the_cpu_does() {
    let scene = load_scene(&common::repo_path("scenes/cornell-fog.toml")).unwrap();
    let buffers = common::buffers(&scene, 32, 32);
    let settings = PhotonSettings { photons: 20_000, caustic_photons: 2_000, gather_rays: 2, ..Default::default() };
    let ctx = common::gpu();
    let gpu = common::gpu_render(&ctx, &buffers, 2, &settings);
    let cpu = common::cpu_render(&buffers, 2, &settings);
    // The same random numbers and the same photons: the images differ only where float rounding
    // flips a discrete choice (a free flight ending just before or after a surface).
    let error = rel_mse(&gpu.image, &cpu.image);
    let ratio = mean_ratio(&gpu.image, &cpu.image);
    println!("cornell-fog gpu vs cpu: relMSE {error:.2e}, mean ratio {ratio:.5?}");
    assert!(error < 1e-3, "relMSE {error}");
    for r in ratio {
        assert!((r - 1.0).abs() < 0.005, "{ratio:?}");
    }
}

#[test]
fn gpu_volume_photon_map_equals_cpu() {
    use photonix::render::gpu::{build_maps_gpu, DeviceScene};
    use photonix::render::photons::build_maps_cpu;
    let scene = load_scene(&common::repo_path("scenes/cornell-fog.toml")).unwrap();
    let buffers = common::buffers(&scene, 16, 16);
    let settings = PhotonSettings { photons: 20_000, caustic_photons: 1_000, ..Default::default() };
    let ctx = common::gpu();
    let device_scene = DeviceScene::upload(&ctx, &buffers, Some(&settings)).unwrap();
    let gpu = build_maps_gpu(&ctx, &device_scene, &buffers, &settings, 0).unwrap().download(&ctx).unwrap();
    let cpu = build_maps_cpu(&buffers, &settings, 0);
    println!(
        "volume photons: gpu {}, cpu {}; radius {}",
        gpu.volume_photons.len(),
        cpu.volume_photons.len(),
        cpu.grids[2].radius
    );
    assert!(cpu.volume_photons.len() > 10_000, "the fog stores collisions");
    // Free flights that end within rounding of a surface may differ, and positions round
    // differently on the two sides: a GPU photon matches a CPU photon within 1e-4 of the scene's
    // size with the same flags and flux within 0.1% (as tests/photon_map.rs does).
    let diff = (gpu.volume_photons.len() as f64 - cpu.volume_photons.len() as f64).abs();
    assert!(diff <= cpu.volume_photons.len() as f64 * 1e-3, "{diff} photons differ");
    let grid = &cpu.grids[2];
    let mut matched = 0;
    for p in &gpu.volume_photons {
        let mut twin = false;
        for_each_photon_near(glam::Vec3::from(p.position), grid, &cpu.volume_photons, &cpu.volume_starts, |q, d2| {
            twin |= d2.sqrt() <= 1e-4 * 560.0
                && photon_flags(q) == photon_flags(p)
                && (photon_flux(q, 1.0) - photon_flux(p, 1.0)).abs().max_element()
                    <= 1e-3 * photon_flux(p, 1.0).max_element();
        });
        matched += twin as usize;
    }
    let fraction = matched as f64 / gpu.volume_photons.len() as f64;
    println!("volume photons with a CPU twin: {:.4}%", 100.0 * fraction);
    assert!(fraction > 0.995, "{fraction}");
}

/// A glowing medium in a scene with no light at all: the light shafts' equiangular sampling has
/// no light to pick and is skipped by both twins (it indexed past the empty light list before);
/// the glow is seen, and the GPU's image is the CPU's.
#[test]
fn gpu_renders_a_glowing_medium_without_lights_as_the_cpu_does() {
    let scene = parse_scene(
        r#"
[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]
fov = 30

[materials.boundary]
type = "null"

[media.glow]
sigma_a = 0.3
emission = 1

[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = 2
material = "boundary"
interior = "glow"
"#,
        Path::new("glow.toml"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let buffers = common::buffers(&scene, 24, 24);
    let settings = PhotonSettings { photons: 1_000, caustic_photons: 100, gather_rays: 1, ..Default::default() };
    let cpu = common::cpu_render(&buffers, 2, &settings);
    // Through the centre, a chord of 4 in sigma_a 0.3: radiance e / sigma_a (1 - exp(-1.2)) =
    // 2.33 in the mean; a sample that collides in the glow (70% of them) carries e / sigma_a =
    // 3.33, one that does not carries 0, so one pixel of a few samples is a multiple of that.
    let centre = cpu.image.pixel(12, 12)[0];
    println!("glow at the centre {centre:.3} (mean 2.33)");
    assert!(centre > 0.5, "{centre}");
    let ctx = common::gpu();
    let gpu = common::gpu_render(&ctx, &buffers, 2, &settings);
    let error = rel_mse(&gpu.image, &cpu.image);
    println!("glow without lights gpu vs cpu: relMSE {error:.2e}");
    assert!(error < 1e-3, "relMSE {error}");
}
