//! The BVH traversal finds exactly the closest hit that brute force over all primitives finds,
//! through the kernels' binary walk and through the CPU backend's wide one alike.

mod common;

use glam::Vec3;
use photonix::accel::build_bvh;
use photonix::accel::wide::WideBvh;
use photonix::cpu::rng::rand1;
use photonix::cpu::shape::shape_intersect;
use photonix::cpu::trace::trace_ray;
use photonix::cpu::SceneView;
use photonix::layout::constants::{NO_LIGHT, PRIMITIVE_SPHERE, PRIMITIVE_TRIANGLE};
use photonix::layout::{FrameParams, Primitive};

fn random_vec(key: u32, dim: u32) -> Vec3 {
    Vec3::new(rand1(key, 0, 99, dim), rand1(key, 0, 99, dim + 1), rand1(key, 0, 99, dim + 2))
}

fn random_scene(count: u32) -> Vec<Primitive> {
    (0..count)
        .map(|i| {
            let c = random_vec(i, 0) * 20.0 - 10.0;
            if i % 4 == 0 {
                let r = 0.2 + rand1(i, 0, 99, 3) * 1.5;
                Primitive { p0: c.into(), p1: [r, 0.0, 0.0], kind: PRIMITIVE_SPHERE, ..Default::default() }
            } else {
                let a = c + random_vec(i, 4) * 3.0 - 1.5;
                let b = c + random_vec(i, 7) * 3.0 - 1.5;
                Primitive { p0: c.into(), p1: a.into(), p2: b.into(), kind: PRIMITIVE_TRIANGLE, ..Default::default() }
            }
        })
        .collect()
}

fn brute_force(prims: &[Primitive], o: Vec3, d: Vec3) -> (Option<Primitive>, f32) {
    let frame = FrameParams::default();
    let view = SceneView::geometry(&frame, &[], prims);
    let mut best = (None, f32::INFINITY);
    for (i, p) in prims.iter().enumerate() {
        let t = shape_intersect(&view, i as u32, o, d, 0.0, best.1);
        if t < best.1 {
            best = (Some(*p), t);
        }
    }
    best
}

fn bounds(p: &Primitive) -> (Vec3, Vec3) {
    let p0 = Vec3::from(p.p0);
    if p.kind == PRIMITIVE_SPHERE {
        return (p0 - Vec3::splat(p.p1[0]), p0 + Vec3::splat(p.p1[0]));
    }
    let (p1, p2) = (Vec3::from(p.p1), Vec3::from(p.p2));
    (p0.min(p1).min(p2), p0.max(p1).max(p2))
}

#[test]
fn closest_hit_matches_brute_force() {
    let prims = random_scene(3000);
    let bvh = build_bvh(&prims, &prims.iter().map(bounds).collect::<Vec<_>>()).unwrap();
    let frame = FrameParams::default();
    let wide = WideBvh::build(&frame, &bvh.nodes, &bvh.primitives, &[]);
    let binary = SceneView::geometry(&frame, &bvh.nodes, &bvh.primitives);
    let mut hits = 0;
    for (ray, view) in (0..10000u32).map(|r| (r / 2, SceneView { wide: (r % 2 == 1).then_some(&wide), ..binary })) {
        // Origins inside and around the cloud, so rays start both inside and outside boxes.
        let o = random_vec(ray, 100) * 30.0 - 15.0;
        let d = (random_vec(ray, 103) * 2.0 - 1.0).normalize();
        let (expected, t_expected) = brute_force(&prims, o, d);
        let (index, t) = trace_ray(&view, o, d, f32::INFINITY, false, NO_LIGHT);
        match expected {
            None => assert_eq!(index, NO_LIGHT, "ray {ray}: BVH hit where brute force missed"),
            Some(p) => {
                assert_ne!(index, NO_LIGHT, "ray {ray}: BVH missed a hit at t = {t_expected}");
                // Same distance bit for bit: both evaluate the same primitive with the same code.
                assert_eq!(t, t_expected, "ray {ray}");
                assert_eq!(bvh.primitives[index as usize], p, "ray {ray}");
                hits += 1;
            }
        }
        // Any-hit agrees on whether something blocks the ray.
        let (any, _) = trace_ray(&view, o, d, f32::INFINITY, true, NO_LIGHT);
        assert_eq!(any == NO_LIGHT, expected.is_none(), "ray {ray}: any-hit disagrees");
    }
    println!("{hits} of 2 x 5000 rays hit; all match brute force");
    assert!(hits > 2000, "the test must exercise hits, got {hits}");
}

#[test]
fn empty_scene_misses_everything() {
    let bvh = build_bvh(&[], &[]).unwrap();
    let frame = FrameParams::default();
    let view = SceneView::geometry(&frame, &bvh.nodes, &bvh.primitives);
    let (index, _) = trace_ray(&view, Vec3::ZERO, Vec3::X, f32::INFINITY, false, NO_LIGHT);
    assert_eq!(index, NO_LIGHT);
}

/// The wide walk and the binary one find the same hits in the shipped scenes: instances, CSG,
/// analytic and implicit shapes, alpha-tested and smooth triangles, unbounded planes, and
/// coplanar faces (fog.toml's fog box stands on its floor), where only the same order of leaves
/// finds the same surface. Rays start
/// anywhere in and around the scene, some ignore a hit name (as rays leaving a smooth triangle
/// do), some end early.
#[test]
fn wide_walk_finds_the_kernels_hits_in_shipped_scenes() {
    use photonix::scene::load_scene;
    for file in [
        "scenes/shapes.toml",
        "scenes/materials.toml",
        "scenes/cornell-box.toml",
        "scenes/outdoor.toml",
        "scenes/fog.toml",
        "scenes/smoke.toml",
        "scenes/spotlights.toml",
    ] {
        let scene = load_scene(&common::repo_path(file)).expect("shipped scene loads");
        let buffers = common::buffers(&scene, 16, 16);
        let wide = buffers.view();
        assert!(wide.wide.is_some(), "the CPU backend's view carries the wide BVH");
        let binary = SceneView { wide: None, ..wide };
        let (lo, hi) =
            buffers.nodes.first().map_or((Vec3::ZERO, Vec3::ZERO), |n| (n.aabb_min.into(), n.aabb_max.into()));
        let mut hits = 0;
        for ray in 0..4000u32 {
            let o = lo + (hi - lo) * (random_vec(ray, 200) * 1.2 - 0.1);
            let d = (random_vec(ray, 203) * 2.0 - 1.0).normalize();
            let t_max = if ray % 3 == 0 { (hi - lo).length() * rand1(ray, 0, 99, 206) } else { f32::INFINITY };
            let (first, _) = trace_ray(&binary, o, d, f32::INFINITY, false, NO_LIGHT);
            let ignore = if ray % 5 == 0 { first } else { NO_LIGHT };
            let expected = trace_ray(&binary, o, d, t_max, false, ignore);
            let found = trace_ray(&wide, o, d, t_max, false, ignore);
            // The same hit name and the same distance, bit for bit: the leaves in one order.
            assert_eq!((found.0, found.1.to_bits()), (expected.0, expected.1.to_bits()), "{file}, ray {ray}");
            hits += u32::from(expected.0 != NO_LIGHT);
            let blocked = |v: &SceneView| trace_ray(v, o, d, t_max, true, ignore).0 != NO_LIGHT;
            assert_eq!(blocked(&wide), blocked(&binary), "{file}, ray {ray}: any-hit disagrees");
        }
        println!("{file}: {hits} of 4000 rays hit");
        assert!(hits > 1000, "{file}: the test must exercise hits, got {hits}");
    }
}
