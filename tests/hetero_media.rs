//! Heterogeneous media and POV-Ray's fog: ratio tracking of shadow rays and delta tracking of
//! camera rays against numerical quadrature of known densities (a voxel gradient, a gradient
//! pattern), POV-Ray's constant and ground fog against their closed forms, the GPU against the
//! CPU on scenes with heterogeneous media, and bad voxel files.

mod common;

use std::path::Path;

use glam::Vec3;
use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::render::PhotonSettings;
use photonix::scene::voxel::VoxelGrid;
use photonix::scene::{load_scene, parse_scene, Scene};

fn scene_in(dir: &Path, text: &str) -> Scene {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    scene
}

/// A grid of `n` voxels along x over x in [1, 2] (|y|, |z| <= 0.5) whose values rise linearly,
/// 0.5, 1.5, ..., n - 0.5.
fn gradient_grid(n: u32) -> VoxelGrid {
    VoxelGrid {
        dims: [n, 1, 1],
        bounds_min: Vec3::new(1.0, -0.5, -0.5),
        bounds_max: Vec3::new(2.0, 0.5, 0.5),
        values: (0..n).map(|i| i as f32 + 0.5).collect(),
        max: n as f32 - 0.5,
    }
}

/// The grid's density at x, written independently of the kernels: linear between voxel centres
/// (i + 1/2) / n, held beyond the first and last.
fn gradient_density(n: u32, x: f64) -> f64 {
    let c = ((x - 1.0) * n as f64 - 0.5).clamp(0.0, n as f64 - 1.0);
    c + 0.5
}

/// Midpoint quadrature of sigma times the density over [a, b].
fn optical_depth(sigma: f64, a: f64, b: f64, density: impl Fn(f64) -> f64) -> f64 {
    let steps = 100_000;
    let h = (b - a) / steps as f64;
    sigma * (0..steps).map(|i| density(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
}

// Shadow rays: ratio tracking through a voxel gradient

/// A wall x = 0 facing +x, lit by a point light at (3, 0, 0) through a null box x in [1, 2]
/// holding `medium`; the camera looks at the wall's centre obliquely from (5, 0, 5), past the
/// box, with a field of view so narrow that every shadow ray runs along x within 2e-4 of the
/// axis (tests/media.rs has the homogeneous twin of this scene).
fn wall_behind(medium: &str) -> String {
    format!(
        r#"
[camera]
position = [5, 0, 5]
look_at = [0, 0, 0]
fov = 1.5
resolution = [16, 16]
[render]
spp = 64
[photons]
enabled = false
[materials.wall]
type = "diffuse"
reflectance = 0.8
[materials.boundary]
type = "null"
{medium}
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
    )
}

#[test]
fn ratio_tracking_through_a_voxel_gradient_matches_quadrature() {
    let dir = tempfile::tempdir().unwrap();
    let n = 8;
    std::fs::write(dir.path().join("ramp.pxvol"), gradient_grid(n).to_bytes()).unwrap();
    let sigma = 0.25;
    let medium = format!(
        "[textures.ramp]\ntype = \"voxels\"\nfile = \"ramp.pxvol\"\n[media.ink]\ndensity = \"ramp\"\nsigma_a = {sigma}\n"
    );
    let lit = scene_in(dir.path(), &wall_behind(&medium));
    // The same wall with the box empty (vacuum inside): the light the slab lets through is the ratio.
    let clear = scene_in(dir.path(), &wall_behind("[media.ink]\nsigma_a = 0\n"));
    let expected = (-optical_depth(sigma, 1.0, 2.0, |x| gradient_density(n, x))).exp();
    let ctx = common::gpu();
    let (lit, clear) = (common::buffers(&lit, 16, 16), common::buffers(&clear, 16, 16));
    for (backend, through, open) in [
        ("cpu", common::cpu_image(&lit, 64), common::cpu_image(&clear, 64)),
        ("gpu", common::gpu_image(&ctx, &lit, 64), common::gpu_image(&ctx, &clear, 64)),
    ] {
        let ratio = mean_ratio(&through, &open);
        println!("{backend}: transmittance {ratio:.4?} vs quadrature {expected:.4}");
        // Each shadow ray's ratio-tracking estimate lies in [0, 1] (up to roulette's 1/q, which
        // keeps it below 1 too): 16384 rays give a standard deviation of the mean below 0.004;
        // 0.02 is 5 of them.
        for r in ratio {
            assert!((r - expected).abs() < 0.02, "{backend}: {r} vs {expected}");
        }
    }
}

// Camera rays: delta tracking through a gradient pattern

/// An emitter of radiance 1 at z = 0 facing +z behind a null box z in [1, 3] whose medium's
/// density is a `gradient` pattern along z (0 at z = 1 rising to 1 at z = 2, held at 1 beyond
/// by the colour map), seen head-on by an orthographic camera.
fn emitter_behind_gradient(albedo: f64) -> String {
    format!(
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
[textures.ramp]
type = "pattern"
pattern = "gradient"
direction = [0, 0, 1]
frequency = 0
color_map = [[0, 0], [1, 1]]
transform = {{ translate = [0, 0, 1] }}
[media.ink]
density = "ramp"
sigma_t = [0.5, 0.8, 1.2]
albedo = {albedo}
[[shapes]]
type = "quad"
material = "lamp"
vertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
[[shapes]]
type = "box"
material = "boundary"
interior = "ink"
min = [-2, -2, 1]
max = [2, 2, 1.9]
"#
    )
}

#[test]
fn delta_tracking_through_a_gradient_pattern_matches_quadrature() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_in(dir.path(), &emitter_behind_gradient(0.0));
    let buffers = common::buffers(&s, 32, 32);
    let ctx = common::gpu();
    let sigma = [0.5, 0.8, 1.2];
    for (backend, image) in [("cpu", common::cpu_image(&buffers, 16)), ("gpu", common::gpu_image(&ctx, &buffers, 16))] {
        let mean = image.channel_means();
        for c in 0..3 {
            // The density is z - 1 inside the box (the pattern's value, mapped one to one).
            let expected = (-optical_depth(sigma[c], 1.0, 1.9, |z| z - 1.0)).exp();
            println!("{backend} channel {c}: {:.4} vs quadrature {expected:.4}", mean[c]);
            // A pass weighs w (spectral tracking keeps it near 1 for these mild colours) and an
            // absorbed path 0: 16384 paths give a standard deviation below 0.006; 0.025 is 4.
            assert!((mean[c] - expected).abs() < 0.025, "{backend} channel {c}: {} vs {expected}", mean[c]);
        }
    }
}

// POV-Ray's fog: constant and ground fog against their closed forms

/// The emitter of radiance 1 at z = 0 seen through [fog] from z = 10 (10 units of it), by an
/// orthographic camera `view_height` 1 centred at height `y`.
fn emitter_in_fog(fog: &str, y: f64) -> String {
    format!(
        r#"
[camera]
type = "orthographic"
position = [0, {y}, 10]
look_at = [0, {y}, 0]
view_height = 0.02
resolution = [16, 16]
[render]
spp = 64
[photons]
enabled = false
[materials.lamp]
type = "diffuse"
reflectance = 0
emission = 1
[fog]
{fog}
[[shapes]]
type = "quad"
material = "lamp"
vertices = [[-1, -10, 0], [1, -10, 0], [1, 10, 0], [-1, 10, 0]]
"#
    )
}

#[test]
fn pov_fog_blends_toward_its_colour_as_pov_ray_does() {
    let dir = tempfile::tempdir().unwrap();
    let ctx = common::gpu();
    let colour = [0.2, 0.5, 0.9];
    // POV-Ray: exp(-d / D) object + (1 - exp(-d / D)) fog colour, d = 10; ground fog scales the
    // density by 1 / (1 + (y - offset) / alt)^2 above the offset (a horizontal ray keeps y).
    let cases = [
        ("distance = 8\ncolor = [0.2, 0.5, 0.9]\n".to_string(), 0.0, 1.0),
        (
            "type = \"ground\"\ndistance = 4\ncolor = [0.2, 0.5, 0.9]\nfog_offset = 1\nfog_alt = 2\n".to_string(),
            3.0,
            0.25,
        ),
        (
            "type = \"ground\"\ndistance = 4\ncolor = [0.2, 0.5, 0.9]\nfog_offset = 1\nfog_alt = 2\n".to_string(),
            0.5,
            1.0,
        ),
    ];
    for (fog, y, density) in cases {
        let s = scene_in(dir.path(), &emitter_in_fog(&fog, y));
        let distance: f64 = if fog.contains("distance = 8") { 8.0 } else { 4.0 };
        let t = (-10.0 * density / distance).exp();
        let buffers = common::buffers(&s, 16, 16);
        for (backend, image) in
            [("cpu", common::cpu_image(&buffers, 64)), ("gpu", common::gpu_image(&ctx, &buffers, 64))]
        {
            let mean = image.channel_means();
            for c in 0..3 {
                let expected = t + (1.0 - t) * colour[c];
                println!("{backend} y {y}: channel {c}: {:.4} vs {expected:.4}", mean[c]);
                // Each path returns 1 or the colour: 16384 paths give a standard deviation of
                // the mean below 0.004; 0.02 is 5 of them.
                assert!((mean[c] - expected).abs() < 0.02, "{backend} y {y} channel {c}: {} vs {expected}", mean[c]);
            }
        }
    }
}

// GPU = CPU

fn assert_gpu_matches_cpu(name: &str, scene: &Scene, photons: &PhotonSettings) {
    let buffers = common::buffers(scene, 32, 24);
    let ctx = common::gpu();
    let gpu = common::gpu_render(&ctx, &buffers, 8, photons);
    let cpu = common::cpu_render(&buffers, 8, photons);
    // The same random numbers and photons: the images differ where float rounding moves a
    // tentative collision across a density step or a surface, flipping one path's choice.
    let error = rel_mse(&gpu.image, &cpu.image);
    let ratio = mean_ratio(&gpu.image, &cpu.image);
    println!("{name} gpu vs cpu: relMSE {error:.2e}, mean ratio {ratio:.5?}");
    assert!(error < 2e-3, "{name}: relMSE {error}");
    for r in ratio {
        assert!((r - 1.0).abs() < 0.01, "{name}: {ratio:?}");
    }
}

#[test]
fn gpu_renders_smoke_as_the_cpu_does() {
    let scene = load_scene(&common::repo_path("scenes/smoke.toml")).unwrap();
    let photons = PhotonSettings { photons: 5_000, caustic_photons: 500, gather_rays: 0, ..Default::default() };
    assert_gpu_matches_cpu("smoke", &scene, &photons);
}

#[test]
fn gpu_renders_voxels_and_ground_fog_as_the_cpu_does() {
    let dir = tempfile::tempdir().unwrap();
    let n = 6;
    let grid = VoxelGrid {
        dims: [n, n, n],
        bounds_min: Vec3::splat(-0.5),
        bounds_max: Vec3::splat(0.5),
        values: (0..n * n * n)
            .map(|i| {
                let (x, y, z) = (i % n, i / n % n, i / (n * n));
                ((x * 7 + y * 3 + z * 5) % 4) as f32 * 0.5
            })
            .collect(),
        max: 1.5,
    };
    std::fs::write(dir.path().join("cloud.pxvol"), grid.to_bytes()).unwrap();
    let s = scene_in(
        dir.path(),
        r#"
[camera]
position = [0, 1, 4]
look_at = [0, 0.3, 0]
fov = 45
[render]
max_depth = 4
[textures.cloud]
type = "voxels"
file = "cloud.pxvol"
transform = { scale = 1.6, translate = [0, 0.8, 0] }
[media.cloud]
density = "cloud"
sigma_t = 2
albedo = [0.9, 0.8, 0.7]
[fog]
type = "ground"
distance = 6
color = [0.5, 0.55, 0.6]
fog_offset = 0.2
fog_alt = 0.5
turbulence = 0.4
octaves = 3
[materials.floor]
type = "diffuse"
reflectance = 0.6
[materials.boundary]
type = "null"
[[shapes]]
type = "quad"
material = "floor"
vertices = [[-3, 0, -3], [-3, 0, 3], [3, 0, 3], [3, 0, -3]]
[[shapes]]
type = "sphere"
material = "boundary"
center = [0, 0.8, 0]
radius = 0.8
interior = "cloud"
[[lights]]
type = "spot"
position = [2, 3, 2]
point_at = [0, 0.6, 0]
intensity = 20
outer_angle = 25
[[lights]]
type = "point"
position = [-2, 2, 1]
intensity = 4
"#,
    );
    let photons = PhotonSettings { photons: 5_000, caustic_photons: 500, gather_rays: 1, ..Default::default() };
    assert_gpu_matches_cpu("voxel cloud in ground fog", &s, &photons);
}

// Bad density files: the error names the file and what is wrong, and nothing is written

fn render_error(grid_bytes: Option<Vec<u8>>) -> (String, bool) {
    let dir = common::scene_dir(
        r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 40
resolution = [8, 8]
[textures.smoke]
type = "voxels"
file = "volumes/smoke.pxvol"
[media.smoke]
density = "smoke"
sigma_t = 1
[materials.boundary]
type = "null"
[[shapes]]
type = "sphere"
material = "boundary"
center = [0, 0, 0]
radius = 1
interior = "smoke"
[[lights]]
type = "point"
position = [0, 3, 3]
intensity = 5
"#,
    );
    if let Some(bytes) = grid_bytes {
        std::fs::create_dir(dir.path().join("volumes")).unwrap();
        std::fs::write(dir.path().join("volumes/smoke.pxvol"), bytes).unwrap();
    }
    let out = common::photonix(&["render", "scene.toml", "-o", "out.png", "--backend", "cpu"], dir.path());
    assert!(!out.status.success());
    (common::stderr(&out), dir.path().join("out.png").exists())
}

#[test]
fn bad_voxel_files_are_refused_naming_the_file_and_the_fault() {
    let good = VoxelGrid {
        dims: [4, 3, 2],
        bounds_min: Vec3::splat(-1.0),
        bounds_max: Vec3::splat(1.0),
        values: vec![0.5; 24],
        max: 0.5,
    };
    let with_value = |i: usize, v: f32| {
        let mut g = good.clone();
        g.values[i] = v;
        g.to_bytes()
    };
    let mut wrong_dims = good.to_bytes();
    wrong_dims[8..12].copy_from_slice(&5u32.to_le_bytes()); // says 5 x 3 x 2: 6 values short
    let truncated = good.to_bytes()[..100].to_vec();
    let cases: Vec<(Option<Vec<u8>>, &[&str])> = vec![
        (None, &["scene.toml:9:", "texture \"smoke\"", "smoke.pxvol", "not found"]),
        (Some(truncated), &["scene.toml:9:", "smoke.pxvol", "truncated", "4 x 3 x 2 voxels need 140 bytes"]),
        (Some(wrong_dims), &["smoke.pxvol", "truncated", "5 x 3 x 2 voxels"]),
        (Some(b"P6 4 3 255\n".to_vec()), &["smoke.pxvol", "not a PXVOL1 voxel file"]),
        (Some(with_value(13, f32::NAN)), &["smoke.pxvol", "voxel (1, 0, 1) is NaN"]),
        (Some(with_value(5, -0.25)), &["smoke.pxvol", "voxel (1, 1, 0) is -0.25", "finite and >= 0"]),
    ];
    for (bytes, pieces) in cases {
        let (message, written) = render_error(bytes);
        for piece in pieces {
            assert!(message.contains(piece), "`{piece}` missing from: {message}");
        }
        assert!(!message.contains("panicked"), "{message}");
        assert!(!written, "an image was written despite: {message}");
    }
}

#[test]
fn density_and_fog_mistakes_are_refused_with_their_line() {
    let error = |text: &str| match parse_scene(text, Path::new("bad.toml")) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    };
    let camera = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 1, 0]\nfov = 40\n";
    let message = error(&format!(
        "{camera}[textures.flat]\ntype = \"pattern\"\npattern = \"bozo\"\nspace = \"uv\"\n[media.m]\ndensity = \"flat\"\nsigma_t = 1\n"
    ));
    assert!(message.contains("bad.toml:10:") && message.contains("uv space"), "{message}");
    let message = error(&format!("{camera}[media.m]\ndensity = \"nothing\"\nsigma_t = 1\n"));
    assert!(message.contains("unknown texture \"nothing\""), "{message}");
    let message = error(&format!("{camera}[media.m]\ntype = \"heterogeneous\"\nsigma_t = 1\n"));
    assert!(message.contains("needs `density"), "{message}");
    let message = error(&format!("{camera}[fog]\ncolor = 0.5\n"));
    assert!(message.contains("missing field `distance`"), "{message}");
    let message = error(&format!("{camera}[fog]\ndistance = 5\nfog_alt = 1\n"));
    assert!(message.contains("bad.toml:7:") && message.contains("`fog_alt` does not apply"), "{message}");
    let message = error(&format!("{camera}[fog]\ntype = \"ground\"\ndistance = 5\nfog_alt = 0\n"));
    assert!(message.contains("`fog_alt` is 0; it must be > 0"), "{message}");
    let message =
        error(&format!("{camera}[media.m]\nsigma_t = 1\n[atmosphere]\nmedium = \"m\"\n[fog]\ndistance = 5\n"));
    assert!(message.contains("keep one of them"), "{message}");
}
