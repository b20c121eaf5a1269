//! Helpers shared by the integration tests.
#![allow(dead_code)] // each test binary uses a different subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use photonix::gpu::{GpuContext, GpuOptions};
use photonix::io::Image;
use photonix::render::{
    gpu::render_gpu, prepare, render_cpu, FrameSettings, PhotonSettings, RenderOutput, SceneBuffers,
};
use photonix::scene::Scene;

pub fn repo_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The shared ground-truth folder, next to the repository.
pub fn reference_path(scene: &str) -> PathBuf {
    repo_path("..").join("shared/reference").join(scene).join("reference.exr")
}

/// A device context with the validation layer on: every test on the GPU runs with it.
pub fn gpu() -> GpuContext {
    GpuContext::new(&GpuOptions { device: None, validation: true }).expect("a Vulkan device (lavapipe) with validation")
}

pub fn buffers(scene: &Scene, width: u32, height: u32) -> SceneBuffers {
    let settings = FrameSettings { width, height, max_depth: scene.render.max_depth, seed: scene.render.seed };
    prepare(scene, &settings).expect("scene prepares")
}

/// Direct light and specular paths only.
pub fn cpu_image(buffers: &SceneBuffers, spp: u32) -> Image {
    render_cpu(buffers, spp, None, 0, &mut |_, _| {}).image
}

/// Direct light and specular paths only.
pub fn gpu_image(ctx: &GpuContext, buffers: &SceneBuffers, spp: u32) -> Image {
    render_gpu(ctx, buffers, spp, None, 0, &mut |_, _| {}).expect("gpu render succeeds").image
}

pub fn cpu_render(buffers: &SceneBuffers, spp: u32, photons: &PhotonSettings) -> RenderOutput {
    render_cpu(buffers, spp, Some(photons), 0, &mut |_, _| {})
}

pub fn gpu_render(ctx: &GpuContext, buffers: &SceneBuffers, spp: u32, photons: &PhotonSettings) -> RenderOutput {
    render_gpu(ctx, buffers, spp, Some(photons), 0, &mut |_, _| {}).expect("gpu render succeeds")
}

/// Renders `buffers` with both twins (one pass, 4000 + 4000 photons, one gather ray) and checks
/// that they agree: relMSE below 1e-6 and each channel's mean within 0.1%. The twins differ only
/// where rounding flips a discrete choice (about 1e-11 on lavapipe); 1e-6 leaves room for other
/// drivers' exp2, log2 and atan and still catches a wrong shape, normal or pdf (those move relMSE
/// above 1e-2). Returns the CPU render.
pub fn assert_twins_agree(label: &str, buffers: &SceneBuffers) -> RenderOutput {
    let photons = PhotonSettings { photons: 4000, caustic_photons: 4000, gather_rays: 1, ..PhotonSettings::default() };
    let ctx = gpu();
    let gpu = gpu_render(&ctx, buffers, 1, &photons);
    let cpu = cpu_render(buffers, 1, &photons);
    let error = photonix::io::metrics::rel_mse(&gpu.image, &cpu.image);
    let ratio = photonix::io::metrics::mean_ratio(&gpu.image, &cpu.image);
    println!("{label}: GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}");
    assert!(error < 1e-6, "{label}: relMSE {error:.3e}");
    for r in ratio {
        assert!((r - 1.0).abs() < 1e-3, "{label}: mean ratio {ratio:?}");
    }
    cpu
}

/// Small photon maps for fast tests.
pub fn test_photons() -> PhotonSettings {
    PhotonSettings { photons: 20_000, caustic_photons: 20_000, gather_rays: 4, ..PhotonSettings::default() }
}

/// Runs the `photonix` binary in `dir` with the validation layer on.
pub fn photonix(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(args)
        .current_dir(dir)
        .env("PHOTONIX_VALIDATION", "1")
        .output()
        .expect("the photonix binary runs")
}

/// A triangle shape of material `material` with the default uv.
pub fn triangle(vertices: [glam::Vec3; 3], material: u32) -> photonix::scene::Shape {
    use photonix::scene::{Geometry, Shape, Triangle};
    Shape { geometry: Geometry::Triangle(Triangle { vertices, uv: None, normals: None }), material, media: None }
}

/// A diffuse material of albedo `rho` in every channel, emitting `emission`.
pub fn diffuse(rho: f32, emission: f32) -> photonix::scene::MaterialDesc {
    use photonix::scene::{ColorParam, MaterialDesc, MaterialKind};
    let mut m = MaterialDesc::new(MaterialKind::Diffuse { reflectance: ColorParam::constant(glam::Vec3::splat(rho)) });
    m.emission = ColorParam::constant(glam::Vec3::splat(emission));
    m
}

/// A temporary folder holding `scene` as scene.toml.
pub fn scene_dir(scene: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    dir
}

/// What a finished command wrote to standard error.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// Exports the scene of tests/blender/export_scene.py with Blender (Debian's `blender`, which
/// ci/setup installs) into `out` (.glb). Fails, not skips, without Blender: CI runs ci/setup first.
pub fn blender_export(out: &Path) {
    let blender = Path::new("/usr/bin/blender");
    assert!(blender.exists(), "/usr/bin/blender is missing; run ci/setup (it installs blender and python3-numpy)");
    let script = repo_path("tests/blender/export_scene.py");
    let run = Command::new(blender)
        .args(["--background", "--factory-startup", "--python-exit-code", "1", "--python"])
        .arg(&script)
        .arg("--")
        .arg(out)
        .output()
        .expect("blender runs");
    let log = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert!(
        run.status.success() && out.exists() && !log.contains("Traceback"),
        "blender did not export {}; run ci/setup (the exporter needs python3-numpy):\n{log}",
        out.display()
    );
}

/// A closed room whose every wall is a Lambertian emitter of radiance E and albedo rho, seen
/// from inside: L = E (1 + rho + rho^2 + ...) = E / (1 - rho) everywhere (a white furnace), which
/// every path reaches by both emission met and light sampling, so multiple importance sampling
/// must weigh each path to 1 in total. With rho = 0.5 and E = 1, L = 2; max_depth 24 cuts the
/// series 2^-24 short.
pub fn furnace() -> photonix::scene::Scene {
    use glam::Vec3;
    use photonix::scene::{Camera, Integrator, Projection, RenderSettings, Scene, Shape};
    let (rho, emission) = (0.5, 1.0);
    let c = [
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    ];
    let faces = [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [3, 2, 6, 7], [0, 3, 7, 4], [1, 2, 6, 5]];
    let mut shapes: Vec<Shape> = Vec::new();
    for f in faces {
        for tri in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            let mut v = tri.map(|i| c[i]);
            // Wind each triangle so its normal faces the room's centre: emission leaves the front.
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            if n.dot(-v[0]) < 0.0 {
                v.swap(1, 2);
            }
            shapes.push(triangle(v, 0));
        }
    }
    Scene {
        name: "furnace".into(),
        path: "furnace.toml".into(),
        camera: Camera {
            position: Vec3::new(0.1, -0.2, 0.05),
            look_at: Vec3::new(0.6, 0.3, 1.0),
            up: Vec3::Y,
            fov_deg: 90.0,
            projection: Projection::Perspective,
            lens: None,
            width: 16,
            height: 16,
        },
        render: RenderSettings {
            spp: 16,
            passes: 1,
            max_depth: 24,
            seed: 5,
            integrator: Integrator::Pt,
            integrator_auto: None,
            filter: Default::default(),
            filter_radius: None,
            denoise: false,
            light_sampler: Default::default(),
            adaptive: false,
        },
        photons: None,
        materials: vec![diffuse(rho, emission)],
        material_names: vec!["wall".into()],
        textures: vec![],
        shapes,
        lights: vec![],
        environment: None,
        warnings: vec![],
        objects: vec![],
        instances: vec![],
        media: vec![],
        medium_names: vec![],
        atmosphere: None,
        inputs: vec![],
    }
}

/// A camera straight above the plane y = 0 (camera-right is -x, image up is +z) of a square
/// image: where its film positions look, and a pixel's mean of a closed form over the plane.
pub struct OverheadView {
    pub size: u32,
    pub fov_deg: f64,
    pub height: f64,
}

impl OverheadView {
    /// Where film position (sx, sy) in [-1, 1]^2 looks at on the plane.
    pub fn point(&self, sx: f64, sy: f64) -> glam::DVec3 {
        let t = (self.fov_deg * 0.5).to_radians().tan() * self.height;
        glam::DVec3::new(-sx * t, 0.0, sy * t)
    }

    /// The mean over pixel (px, py) of `radiance(x)` on the plane, by an 8 x 8 grid of points.
    pub fn pixel_mean(&self, px: u32, py: u32, radiance: impl Fn(glam::DVec3) -> f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..8 {
            for j in 0..8 {
                let sx = 2.0 * (px as f64 + (i as f64 + 0.5) / 8.0) / self.size as f64 - 1.0;
                let sy = 1.0 - 2.0 * (py as f64 + (j as f64 + 0.5) / 8.0) / self.size as f64;
                sum += radiance(self.point(sx, sy));
            }
        }
        sum / 64.0
    }
}
