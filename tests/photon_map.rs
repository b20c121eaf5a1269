//! Photon maps: the GPU builds the same maps as the CPU reference, and the stored flux obeys
//! energy conservation.

mod common;

use glam::Vec3;
use photonix::cpu::grid::for_each_photon_near;
use photonix::cpu::photon::{photon_flags, photon_flux};
use photonix::layout::constants::PHOTON_FLAG_DIRECT;
use photonix::layout::{GridParams, Photon};
use photonix::render::gpu::{build_maps_gpu, DeviceScene};
use photonix::render::photons::build_maps_cpu;
use photonix::render::PhotonSettings;
use photonix::scene::{load_scene, Camera, LightDesc, LightKind, Projection, RenderSettings, Scene};

/// Fraction of `gpu` photons that have a twin in `cpu`: same flags, flux within 0.1%, position
/// within 1e-4 of the scene size (float rounding along a path of a few bounces; a half-float
/// rounding may flip, so flux is not compared bit for bit). Twins are looked up through the CPU
/// grid, whose query covers neighbouring cells: a photon on a wall that lies on a cell boundary
/// (the Cornell box's x = 0) can fall on either side.
fn matched_fraction(gpu: &[Photon], cpu: &[Photon], starts: &[u32], grid: &GridParams, scale: f32) -> f64 {
    let mut matched = 0;
    for p in gpu {
        let mut twin = false;
        for_each_photon_near(Vec3::from(p.position), grid, cpu, starts, |q, d2| {
            twin |= d2.sqrt() <= 1e-4 * scale
                && photon_flags(q) == photon_flags(p)
                && (photon_flux(q, 1.0) - photon_flux(p, 1.0)).abs().max_element()
                    <= 1e-3 * photon_flux(p, 1.0).max_element();
        });
        matched += twin as usize;
    }
    matched as f64 / gpu.len().max(1) as f64
}

#[test]
fn gpu_photon_maps_equal_cpu_photon_maps() {
    let scene = load_scene(&common::repo_path("scenes/cornell-caustics.toml")).unwrap();
    let buffers = common::buffers(&scene, 64, 64);
    let settings = PhotonSettings { photons: 30_000, caustic_photons: 30_000, ..PhotonSettings::default() };
    let cpu = build_maps_cpu(&buffers, &settings, 0);
    let ctx = common::gpu();
    let device_scene = DeviceScene::upload(&ctx, &buffers, Some(&settings)).unwrap();
    let gpu = build_maps_gpu(&ctx, &device_scene, &buffers, &settings, 0).unwrap().download(&ctx).unwrap();
    for (name, g, c, starts, grid) in [
        ("global", &gpu.global_photons, &cpu.global_photons, &cpu.global_starts, &cpu.grids[0]),
        ("caustic", &gpu.caustic_photons, &cpu.caustic_photons, &cpu.caustic_starts, &cpu.grids[1]),
    ] {
        let matched = matched_fraction(g, c, starts, grid, buffers.bounding_radius);
        println!(
            "{name} map: gpu {} photons, cpu {}, {:.4}% of gpu photons have a cpu twin",
            g.len(),
            c.len(),
            100.0 * matched
        );
        // The same random numbers give the same paths; only a path that float rounding sends
        // another way (grazing an edge) differs, far fewer than 1 in 1000.
        assert!((g.len() as f64 / c.len() as f64 - 1.0).abs() < 1e-3, "{name}: counts differ");
        assert!(matched > 0.999, "{name}: only {matched} matched");
    }
    assert_eq!(gpu.grids, cpu.grids, "same radius, table size and flux scale");
    assert_eq!(gpu.global_starts.len(), cpu.global_starts.len());
}

#[test]
fn gpu_photon_maps_are_deterministic() {
    let scene = load_scene(&common::repo_path("scenes/cornell-box.toml")).unwrap();
    let buffers = common::buffers(&scene, 32, 32);
    let settings = PhotonSettings { photons: 20_000, caustic_photons: 5_000, ..PhotonSettings::default() };
    let ctx = common::gpu();
    let device_scene = DeviceScene::upload(&ctx, &buffers, Some(&settings)).unwrap();
    let a = build_maps_gpu(&ctx, &device_scene, &buffers, &settings, 0).unwrap().download(&ctx).unwrap();
    let b = build_maps_gpu(&ctx, &device_scene, &buffers, &settings, 0).unwrap().download(&ctx).unwrap();
    // Scatter order depends on atomics; sorting each bucket removes that.
    assert!(a == b, "two builds of the same maps differ");
}

/// A closed diffuse box of albedo rho with a point light inside: every photon path ends on the
/// walls, so the first photons carry the light's whole power and each bounce keeps rho of it.
fn closed_box(rho: f32) -> Scene {
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let corners: Vec<Vec3> =
        (0..8).map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2])).collect();
    let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
    let mut triangles = Vec::new();
    for f in faces {
        let v = f.map(|i| corners[i]);
        triangles.push(common::triangle([v[0], v[1], v[2]], 0));
        triangles.push(common::triangle([v[0], v[2], v[3]], 0));
    }
    Scene {
        name: "closed-box".into(),
        path: "closed-box.toml".into(),
        camera: Camera {
            position: Vec3::new(0.0, 0.0, -0.9),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_deg: 60.0,
            projection: Projection::Perspective,
            lens: None,
            width: 8,
            height: 8,
        },
        render: RenderSettings {
            spp: 1,
            passes: 1,
            max_depth: 4,
            seed: 3,
            integrator: Default::default(),
            integrator_auto: None,
            filter: Default::default(),
            filter_radius: None,
            denoise: false,
            light_sampler: Default::default(),
            adaptive: false,
        },
        photons: None,
        materials: vec![common::diffuse(rho, 0.0)],
        material_names: vec!["wall".into()],
        textures: vec![],
        shapes: triangles,
        lights: vec![LightDesc::new(LightKind::Point {
            position: Vec3::new(0.1, 0.2, -0.3),
            intensity: Vec3::new(1.0, 2.0, 3.0),
        })],
        environment: None,
        warnings: vec![],
        objects: vec![],
        instances: vec![],
        inputs: vec![],
        media: vec![],
        medium_names: vec![],
        atmosphere: None,
    }
}

#[test]
fn stored_flux_conserves_energy() {
    let rho = 0.5;
    let scene = closed_box(rho);
    let buffers = common::buffers(&scene, 8, 8);
    let paths = 100_000;
    let settings = PhotonSettings { photons: paths, caustic_photons: 1, max_depth: 30, ..PhotonSettings::default() };
    let maps = build_maps_cpu(&buffers, &settings, 0);
    let scale = maps.grids[0].flux_scale;
    let power = 4.0 * std::f64::consts::PI * 2.0; // 4 pi I, mean over the channels
    let (mut first, mut later) = (0.0f64, 0.0f64);
    for p in &maps.global_photons {
        let flux = photon_flux(p, scale);
        let mean = (flux.x + flux.y + flux.z) as f64 / 3.0;
        if photon_flags(p) == PHOTON_FLAG_DIRECT {
            first += mean;
        } else {
            later += mean;
        }
    }
    // First hits: exactly the light's power (every path hits a wall), up to half-float rounding.
    println!("first-bounce flux {first:.5} vs power {power:.5}");
    assert!((first / power - 1.0).abs() < 1e-3);
    // Later bounces: rho + rho^2 + ... = rho / (1 - rho) of the power, through Russian roulette;
    // about 1e5 paths give a standard error near 0.5%.
    let expected = power * rho as f64 / (1.0 - rho as f64);
    println!("later-bounce flux {later:.5} vs {expected:.5} ({:+.2}%)", 100.0 * (later / expected - 1.0));
    assert!((later / expected - 1.0).abs() < 0.02);
    // The GPU stores the same.
    let ctx = common::gpu();
    let device_scene = DeviceScene::upload(&ctx, &buffers, Some(&settings)).unwrap();
    let gpu = build_maps_gpu(&ctx, &device_scene, &buffers, &settings, 0).unwrap().download(&ctx).unwrap();
    assert_eq!(gpu.global_photons.len(), maps.global_photons.len());
}

#[test]
fn scenes_that_skip_the_caustic_pass_would_store_no_caustic_photons() {
    // A scene whose materials cannot end a caustic path skips the caustic pass: check on every
    // shipped scene that the full pass would have stored nothing there, and that the check does
    // not skip the scenes made for caustics.
    use photonix::cpu::emit_photons::emit_photons;
    use photonix::render::photons::{caustic_emit_params, emit_params};
    let settings = PhotonSettings { photons: 1_000, caustic_photons: 20_000, ..PhotonSettings::default() };
    let mut skipped = Vec::new();
    for entry in std::fs::read_dir(common::repo_path("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let scene = load_scene(&path).unwrap();
        let buffers = common::buffers(&scene, 16, 16);
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if buffers.can_store_caustics() {
            assert_eq!(caustic_emit_params(&buffers, &settings, 0).total_paths, 20_000, "{name}");
            continue;
        }
        assert_eq!(caustic_emit_params(&buffers, &settings, 0).total_paths, 0, "{name}");
        let full = emit_photons(&buffers.view(), &emit_params(&settings, 0, true));
        assert!(full.caustic.is_empty(), "{name}: skipped, yet its caustic pass stores {}", full.caustic.len());
        skipped.push(name);
    }
    println!("scenes that skip the caustic pass: {skipped:?}");
    assert!(skipped.contains(&"cornell-box".to_string()), "{skipped:?}");
    assert!(!skipped.contains(&"cornell-caustics".to_string()), "{skipped:?}");
}
