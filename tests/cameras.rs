//! The cameras against geometry: the thin lens keeps the plane in focus sharp and blurs a point
//! off it to the circle of confusion of the thin-lens formula (round and polygonal apertures),
//! the orthographic camera's image size does not change with distance, the latlong camera puts
//! directions where their longitude and latitude say and covers the sphere with the right solid
//! angle; GPU = CPU for every camera.

mod common;

use std::f64::consts::PI;

use photonix::io::metrics::rel_mse;
use photonix::io::Image;
use photonix::render::SceneBuffers;
use photonix::scene::{parse_scene, Scene};

const SIZE: u32 = 64;
const FOV_DEG: f64 = 20.0;
const SPP: u32 = 512;

fn parse(text: &str) -> Scene {
    parse_scene(text, &common::repo_path("scenes/test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// Small emitting spheres (radiance 1) in the dark, seen by `camera` (the body of `[camera]`
/// without resolution), direct light only.
fn emitters(camera: &str, spheres: &[([f64; 3], f64)]) -> Scene {
    let mut text = format!(
        "[camera]\n{camera}\nresolution = [{SIZE}, {SIZE}]\n\n[render]\nmax_depth = 2\nseed = 11\n\n[photons]\nenabled = false\n"
    );
    for (c, r) in spheres {
        text += &format!(
            "\n[[lights]]\ntype = \"area\"\nshape = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {r}\nradiance = 1\n",
            c[0], c[1], c[2]
        );
    }
    parse(&text)
}

/// A square emitter (radiance 1) of side `side` centred on the view axis at depth `z`, facing the
/// camera at the origin (which looks down -z), and nothing else: its depth is exact, unlike a
/// sphere's.
fn square(camera: &str, z: f64, side: f64) -> Scene {
    let h = 0.5 * side;
    parse(&format!(
        "[camera]\n{camera}\nresolution = [{SIZE}, {SIZE}]\n\n[render]\nmax_depth = 2\nseed = 11\n\n[photons]\nenabled = false\n\n\
         [[lights]]\ntype = \"area\"\nshape = \"quad\"\nradiance = 1\n\
         vertices = [[{h}, {h}, {z}], [-{h}, {h}, {z}], [-{h}, -{h}, {z}], [{h}, -{h}, {z}]]\n",
        z = -z
    ))
}

fn render(buffers: &SceneBuffers, spp: u32, gpu: bool) -> Image {
    if gpu {
        common::gpu_image(&common::gpu(), buffers, spp)
    } else {
        common::cpu_image(buffers, spp)
    }
}

/// (total, centroid x, centroid y, mean squared distance from the centroid) of the image's
/// green channel, in pixels (pixel centres at +0.5).
fn moments(image: &Image) -> (f64, f64, f64, f64) {
    let (mut w, mut sx, mut sy, mut sxx) = (0.0, 0.0, 0.0, 0.0);
    for py in 0..image.height {
        for px in 0..image.width {
            let v = image.pixel(px, py)[1] as f64;
            let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
            w += v;
            sx += v * x;
            sy += v * y;
            sxx += v * (x * x + y * y);
        }
    }
    let (cx, cy) = (sx / w, sy / w);
    (w, cx, cy, sxx / w - cx * cx - cy * cy)
}

// Thin lens

/// Pixels per unit of tan(angle) at the image centre.
fn pixels_per_tan() -> f64 {
    0.5 * SIZE as f64 / (0.5 * FOV_DEG).to_radians().tan()
}

/// A small emitter at depth z seen through a lens of radius A focused at f. Every lens point
/// a sees the scene from a pinhole at a aimed at the plane in focus, which moves the image of
/// every point at depth z by a (1/f - 1/z) (in tan units): the image is the pinhole image
/// convolved with the aperture scaled by A |1/f - 1/z|, the angular circle of confusion of the
/// thin-lens formula (c / v = D |z - f| / (z f) for a lens of diameter D focused at f, image
/// distance v). Convolution adds second moments: E[r^2] grows by R^2 k, R the blur radius in
/// pixels and k the aperture's own E[r^2] on the unit circle (1/2 for the disc,
/// (1 + 2 cos^2(pi/n)) / 6 for n blades).
fn check_lens(gpu: bool) {
    let backend = if gpu { "gpu" } else { "cpu" };
    let (z, side) = (10.0, 0.4);
    let base = format!("position = [0, 0, 0]\nlook_at = [0, 0, -1]\nfov = {FOV_DEG}");
    let pinhole = render(&common::buffers(&square(&base, z, side), SIZE, SIZE), SPP, gpu);
    let (w0, _, _, m0) = moments(&pinhole);
    // (aperture radius, focal distance, blades, rotation)
    for (a, f, blades, rotation) in
        [(0.8, 20.0, 0u32, 0.0), (0.3, 5.0, 6, 10.0), (0.8, 10.0, 0, 0.0), (0.3, 10.0, 5, 0.0)]
    {
        let lens = format!(
            "{base}\naperture_radius = {a}\nfocal_distance = {f}\naperture_blades = {blades}\naperture_rotation = {rotation}"
        );
        let image = render(&common::buffers(&square(&lens, z, side), SIZE, SIZE), SPP, gpu);
        let (w, cx, cy, m) = moments(&image);
        let k = if blades == 0 { 0.5 } else { (1.0 + 2.0 * (PI / blades as f64).cos().powi(2)) / 6.0 };
        let predicted = a * (1.0 / f - 1.0 / z).abs() * pixels_per_tan();
        let measured = ((m - m0).max(0.0) / k).sqrt();
        println!(
            "{backend}: aperture {a}, focus {f}, {blades} blades: blur radius {measured:.3} px, thin lens {predicted:.3} px; \
             centroid ({cx:.3}, {cy:.3}); energy ratio {:.4}",
            w / w0
        );
        // The lens moves light around without losing any (the image is a mean over the
        // aperture). Each sample hits the square or not: about 20000 hits, 0.7% noise.
        assert!((w / w0 - 1.0).abs() < 0.03, "{backend}: the lens changed the image's energy by {}", w / w0);
        // The centroid's noise is sqrt(E[x^2] / hits), about 0.03 px.
        assert!((cx - 32.0).abs() < 0.15 && (cy - 32.0).abs() < 0.15, "{backend}: the blur moved the image");
        if f == z {
            // In focus: as sharp as the pinhole (a 1% focus error would give 0.07 px here).
            assert!(measured < 0.2, "{backend}: the plane in focus blurred by {measured:.3} px");
        } else {
            // The hits pin E[r^2] to about 1%, the blur radius to about 0.5%; a blur off by the
            // aperture's diameter for its radius, or a lens that does not aim at the plane in
            // focus, is off by far more.
            let error = measured / predicted - 1.0;
            assert!(error.abs() < 0.03, "{backend}: blur radius off the thin lens by {:.2}%", 100.0 * error);
        }
    }
}

#[test]
fn thin_lens_blurs_to_the_circle_of_confusion_cpu() {
    check_lens(false);
}

#[test]
fn thin_lens_blurs_to_the_circle_of_confusion_gpu() {
    check_lens(true);
}

// Orthographic and latlong

/// An orthographic camera of view height V shows a sphere of radius r as a disc of r / V times
/// the image height, wherever the sphere is along the view.
#[test]
fn orthographic_image_size_does_not_change_with_distance() {
    let camera = "type = \"orthographic\"\nposition = [0, 0, 0]\nlook_at = [0, 0, -1]\nview_height = 4";
    for z in [3.0, 30.0] {
        let image = common::cpu_image(&common::buffers(&emitters(camera, &[([0.5, 0.0, -z], 0.5)]), SIZE, SIZE), 64);
        let (w, cx, cy, m) = moments(&image);
        // The disc's radius in pixels: E[r^2] = R^2 / 2 plus the pixel's own 1/6.
        let radius = (2.0 * (m - 1.0 / 6.0)).sqrt();
        let expected = 0.5 / 4.0 * SIZE as f64;
        println!("orthographic, sphere at depth {z}: area {w:.2} px^2 of radiance 1, radius {radius:.3} px (expected {expected}), centre ({cx:.2}, {cy:.2})");
        assert!((w / (PI * expected * expected) - 1.0).abs() < 0.01, "disc area {w}");
        assert!((radius / expected - 1.0).abs() < 0.01, "disc radius {radius}");
        // World +x is the image's right here (forward -z, up +y): 0.5 units is 8 pixels.
        assert!((cx - 40.0).abs() < 0.05 && (cy - 32.0).abs() < 0.05, "centre ({cx}, {cy})");
    }
}

/// A latlong image maps pixel (x, y) to longitude (x / W - 1/2) 360 degrees (0 straight ahead,
/// +90 camera-right) and latitude (1/2 - y / H) 180 degrees: weighting each pixel by its solid
/// angle, cos(latitude) dlat dlon, the image of a spherical emitter integrates to its solid angle
/// (times radiance 1) and its mean direction is the emitter's centre.
#[test]
fn latlong_camera_covers_the_sphere() {
    let camera = "type = \"latlong\"\nposition = [0, 0, 0]\nlook_at = [0, 0, -1]";
    let (d, r) = (10.0f64, 2.0);
    let (lat, lon) = (30.0f64.to_radians(), 60.0f64.to_radians());
    // Camera-right is +x, forward -z, up +y.
    let direction = |lat: f64, lon: f64| glam::DVec3::new(lat.cos() * lon.sin(), lat.sin(), -lat.cos() * lon.cos());
    let center = direction(lat, lon) * d;
    let image = common::cpu_image(&common::buffers(&emitters(camera, &[(center.to_array(), r)]), SIZE, SIZE), 256);
    let mut integral = 0.0;
    let mut mean = glam::DVec3::ZERO;
    let pixel_angle = (2.0 * PI / SIZE as f64) * (PI / SIZE as f64);
    for py in 0..SIZE {
        let latitude = PI / 2.0 - PI * (py as f64 + 0.5) / SIZE as f64;
        for px in 0..SIZE {
            let longitude = 2.0 * PI * (px as f64 + 0.5) / SIZE as f64 - PI;
            let w = image.pixel(px, py)[1] as f64 * latitude.cos() * pixel_angle;
            integral += w;
            mean += w * direction(latitude, longitude);
        }
    }
    let expected = 2.0 * PI * (1.0 - (1.0 - r * r / (d * d)).sqrt());
    let off = mean.normalize().angle_between(center.normalize()).to_degrees();
    println!("latlong: integral {integral:.5} sr, emitter's solid angle {expected:.5} sr; mean direction {off:.3} degrees off its centre");
    // About 60 lit pixels of 256 samples each: noise well under 1%. A latitude measured from
    // the pole, or longitude over 180 degrees, misses by tens of percent and degrees.
    assert!((integral / expected - 1.0).abs() < 0.02, "solid angle {integral} against {expected}");
    assert!(off < 0.5, "mean direction {off} degrees off the emitter's centre");
}

/// Every camera kind with a lit scene: GPU and CPU trace the same rays.
#[test]
fn gpu_matches_cpu_with_every_camera() {
    let ctx = common::gpu();
    let cameras = [
        "type = \"orthographic\"\nposition = [0, 2, 6]\nlook_at = [0, 0.5, 0]\nview_height = 4",
        "type = \"latlong\"\nposition = [0, 1, 1.5]\nlook_at = [0, 1, 0]",
        "position = [0, 1.5, 5]\nlook_at = [0, 0.5, 0]\nfov = 40\nf_number = 1.4\nfocal_length = 0.5\nfocal_point = [0, 0.5, 0]\naperture_blades = 7",
        "position = [0, 1.5, 5]\nlook_at = [0, 0.5, 0]\nfov = 40\naperture = 0.4\nfocal_point = [0.5, 0.5, -1]\nblur_samples = 4",
    ];
    for camera in cameras {
        let scene = parse(&format!(
            r#"
[camera]
{camera}
resolution = [32, 32]

[render]
seed = 2

[materials.white]
type = "diffuse"

[[shapes]]
type = "quad"
material = "white"
vertices = [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]

[[shapes]]
type = "sphere"
material = "white"
center = [0.5, 0.5, -1]
radius = 0.5

[[shapes]]
type = "box"
material = "white"
min = [-1.5, 0, -0.5]
max = [-0.7, 1.2, 0.3]

[[lights]]
type = "spot"
position = [1, 3, 1]
point_at = [0, 0, 0]
intensity = 20
outer_angle = 40

[[lights]]
type = "distant"
direction = [-0.5, -1, -0.3]
irradiance = 1
angular_diameter = 5
"#
        ));
        let buffers = common::buffers(&scene, 32, 32);
        let photons = common::test_photons();
        let gpu = common::gpu_render(&ctx, &buffers, 2, &photons).image;
        let cpu = common::cpu_render(&buffers, 2, &photons).image;
        let error = rel_mse(&gpu, &cpu);
        println!("{}: gpu vs cpu relMSE {error:.3e}", camera.lines().next().unwrap());
        assert!(gpu.channel_means()[1] > 0.01, "the scene is lit");
        // As tests/gpu_vs_cpu.rs: only float rounding separates the twins.
        assert!(error < 1e-6, "{camera}: relMSE {error:.3e}");
    }
}
