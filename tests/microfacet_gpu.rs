//! The microfacet BSDFs of `shaders/microfacet.glsl`, run on the GPU through
//! `shaders/microfacet_probe.comp`, against their Rust twins in `photonix::cpu::microfacet`.

use glam::{Vec2, Vec3};
use photonix::cpu::microfacet::*;
use photonix::cpu::rng::{pcg4d, rand_unit};
use photonix::gpu::{GpuContext, GpuOptions};
use photonix::layout::constants::{MICROFACET_BECKMANN, MICROFACET_GGX, NO_DATA, PLASTIC_COAT_WORDS, WORKGROUP_SIZE};
use photonix::render::plastic_coat::plastic_coat_table;

/// Floats per input and output record; the layouts are listed in microfacet_probe.comp.
const PROBE_IN: usize = 24;
const PROBE_OUT: usize = 64;

/// Float `slot` of the outputs: names for failure messages.
fn slot_name(slot: usize) -> &'static str {
    match slot {
        0 => "mf_d",
        1 | 2 => "mf_g1",
        3 => "mf_pdf_visible",
        4..=6 => "mf_sample_visible",
        7..=9 => "fresnel_conductor",
        10..=12 => "conductor_eval",
        13 => "conductor_pdf",
        14..=22 => "conductor_sample",
        23 => "dielectric_eval",
        24 => "dielectric_pdf",
        25..=33 => "dielectric_sample",
        34..=36 => "plastic_eval",
        37 => "plastic_pdf",
        38..=46 => "plastic_sample",
        47..=49 => "lambert_eval",
        50 => "lambert_pdf",
        51..=59 => "lambert_sample",
        _ => "unused",
    }
}

/// Slots that hold discrete values: a sample's `valid` and `lobe`.
fn is_discrete(slot: usize) -> bool {
    [14, 25, 38, 51].iter().any(|&s| slot == s || slot == s + 8)
}

fn put3(out: &mut [f32], at: usize, v: Vec3) {
    out[at..at + 3].copy_from_slice(&v.to_array());
}

fn put_sample(out: &mut [f32], at: usize, s: Option<MfSample>) {
    let s =
        s.map_or([0.0; 9], |s| [1.0, s.wi.x, s.wi.y, s.wi.z, s.weight.x, s.weight.y, s.weight.z, s.pdf, s.lobe as f32]);
    out[at..at + 9].copy_from_slice(&s);
}

/// The probe kernel's `main`, on the CPU.
fn probe_cpu(r: &[f32], words: &[u32]) -> [f32; PROBE_OUT] {
    let v3 = |at: usize| Vec3::new(r[at], r[at + 1], r[at + 2]);
    let (wo, wi, u) = (v3(0), v3(3), v3(6));
    let alpha = Vec2::new(r[9], r[10]);
    let ior = r[11];
    let (eta, k, diffuse) = (v3(12), v3(15), v3(18));
    let coat = PlasticCoat { nonlinear: r[21] != 0.0, words, table: if r[22] < 0.0 { NO_DATA } else { r[22] as u32 } };
    let dist = r[23] as u32;
    let mut out = [0.0f32; PROBE_OUT];

    let ar = alpha.max(Vec2::splat(0.01));
    let mut h = (wo + wi).normalize();
    if h.z < 0.0 {
        h = -h;
    }
    out[0] = mf_d(h, ar, dist);
    out[1] = mf_g1(wo, h, ar, dist);
    out[2] = mf_g1(wi, h, ar, dist);
    out[3] = mf_pdf_visible(wo, h, ar, dist);
    put3(&mut out, 4, mf_sample_visible(wo, ar, dist, Vec2::new(u.x, u.y)));
    put3(&mut out, 7, fresnel_conductor(wo.z, eta, k));

    put3(&mut out, 10, conductor_eval(wo, wi, alpha, dist, eta, k));
    out[13] = conductor_pdf(wo, wi, alpha, dist);
    put_sample(&mut out, 14, conductor_sample(wo, alpha, dist, eta, k, Vec2::new(u.x, u.y)));

    out[23] = dielectric_eval(wo, wi, alpha, dist, ior);
    out[24] = dielectric_pdf(wo, wi, alpha, dist, ior);
    put_sample(&mut out, 25, dielectric_sample(wo, alpha, dist, ior, u));

    put3(&mut out, 34, plastic_eval(wo, wi, alpha, dist, ior, diffuse, &coat));
    out[37] = plastic_pdf(wo, wi, alpha, dist, ior, diffuse);
    put_sample(&mut out, 38, plastic_sample(wo, alpha, dist, ior, diffuse, &coat, u));

    put3(&mut out, 47, lambert_eval(wo, wi, diffuse));
    out[50] = lambert_pdf(wo, wi);
    put_sample(&mut out, 51, lambert_sample(wo, diffuse, Vec2::new(u.x, u.y)));
    out
}

fn sphere(u0: f32, u1: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u1;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Input records covering every model: alphas smooth, fixed and random, both sides, and wi drawn
/// uniformly (mostly outside narrow lobes), near the mirror direction, or from the CPU's
/// dielectric sampler (inside both the reflection and the transmission lobe). Plastics are
/// linear, nonlinear with a smooth coat's closed forms, or nonlinear with a rough coat's table
/// for their index and distribution (alpha 0.2), the tables appended after the records. Every
/// other run of 24 records is Beckmann's, the rest GGX's.
fn inputs(n: u32) -> Vec<f32> {
    let iors = [1.5, 1.33, 2.0];
    let dists = [MICROFACET_GGX, MICROFACET_BECKMANN];
    let tables: Vec<Vec<u32>> = dists
        .iter()
        .flat_map(|&dist| iors.map(move |ior| plastic_coat_table(0.2, dist, ior).expect("a rough coat has a table")))
        .collect();
    let alphas = [
        Vec2::ZERO,
        Vec2::splat(0.05),
        Vec2::splat(0.15),
        Vec2::splat(0.5),
        Vec2::splat(1.0),
        Vec2::new(0.1, 0.4),
        Vec2::splat(0.0005),
    ];
    let mut out = Vec::with_capacity(n as usize * PROBE_IN);
    for i in 0..n {
        let rand = |d: u32| pcg4d([i, 0xface, 77, d]).map(rand_unit);
        let (r0, r1, r2) = (rand(0), rand(1), rand(2));
        let alpha = if i % 8 == 7 { Vec2::new(0.02 + r0[3], 0.02 + r1[3]) } else { alphas[i as usize % 8 % 7] };
        let ior = iors[i as usize % 3];
        let dist = dists[(i as usize / 24) % 2];
        let wo = sphere(r0[0], r0[1]);
        let u = Vec3::new(r1[0], r1[1], r1[2]);
        let wi = match (i / 8) % 3 {
            0 => sphere(r0[2], r1[3]),
            1 => (Vec3::new(-wo.x, -wo.y, wo.z) + 0.3 * sphere(r0[2], r1[3]) * r2[0]).normalize(),
            _ => dielectric_sample(wo, alpha.max(Vec2::splat(0.05)), dist, ior, Vec3::new(r2[0], r2[1], r2[2]))
                .map_or(sphere(r0[2], r1[3]), |s| s.wi),
        };
        let (eta, k) = if i % 2 == 0 {
            (Vec3::new(0.143, 0.374, 1.442), Vec3::new(3.983, 2.385, 1.603))
        } else {
            (Vec3::new(0.2 + 2.0 * r2[0], 1.0 + r2[1], 0.5 + r2[2]), Vec3::new(5.0 * r2[3], 1.0, 0.0))
        };
        let diffuse = Vec3::new(r2[1], r2[2], r2[3]);
        out.extend_from_slice(&[wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, u.x, u.y, u.z, alpha.x, alpha.y, ior]);
        let table_at = n as usize * PROBE_IN + (3 * dist as usize + i as usize % 3) * PLASTIC_COAT_WORDS as usize;
        let (nonlinear, table) = match i % 4 {
            0 => (0.0, -1.0),
            1 => (1.0, -1.0),
            _ => (1.0, table_at as f32),
        };
        out.extend_from_slice(&[
            eta.x,
            eta.y,
            eta.z,
            k.x,
            k.y,
            k.z,
            diffuse.x,
            diffuse.y,
            diffuse.z,
            nonlinear,
            table,
            dist as f32,
        ]);
    }
    for t in &tables {
        out.extend(t.iter().map(|&w| f32::from_bits(w)));
    }
    out
}

#[test]
fn gpu_microfacet_functions_equal_cpu_twins() {
    let gpu = GpuContext::new(&GpuOptions { device: None, validation: true })
        .expect("a Vulkan device (lavapipe) with validation");
    let spirv = photonix::shaders::spirv("microfacet_probe").expect("build.rs compiles microfacet_probe.comp");
    let kernel = gpu.create_kernel("microfacet_probe", &spirv, 2, 4).expect("the probe matches its layout");
    let n = 1u32 << 15;
    let records = inputs(n);
    let words: Vec<u32> = records.iter().map(|x| x.to_bits()).collect();
    let input = gpu.upload("probe_inputs", &records).unwrap();
    let output = gpu.create_buffer("probe_outputs", (n as usize * PROBE_OUT * 4) as u64).unwrap();
    gpu.run("microfacet probe", |r| {
        r.dispatch(&kernel, &[&input, &output], bytemuck::bytes_of(&n), [n.div_ceil(WORKGROUP_SIZE), 1, 1])
    })
    .unwrap();
    let gpu_out: Vec<f32> = gpu.download(&output).unwrap();

    // Both sides run the same float operations in the same order; they differ only where the
    // driver's sin, cos, sqrt or division round differently from Rust's (lavapipe's sin and cos
    // are a few ulps off), or where it fuses a * b + c. Such an ulp grows by the conditioning of
    // the formula, which is large at a few points: a visible normal near the horizon of the
    // projected disk (u near 1: sqrt(1 - p1² - p2²) cancels), a refraction near the critical
    // angle (sqrt(1 - sin²) cancels), a direction near the horizon (G1 divides by wi.z²). So the
    // tolerance is 1e-4 relative (a thousand ulps, far below any changed term: a missing factor or
    // a swapped argument is off by more than 1e-2) plus 1e-6 absolute (results that are 0 on one
    // side and a rounding residue on the other) plus the CPU's own sensitivity: how far the CPU's
    // result moves when one component of u is nudged by 4 ulps. Discrete results (valid, lobe) must match
    // unless the decision sat within rounding of its threshold (u.x against F, a direction on the
    // horizon), which we count and bound.
    let (mut worst, mut worst_at) = (0.0f32, (0, 0));
    let mut flipped = Vec::new();
    let mut mismatches = Vec::new();
    let mut conditioned = 0;
    for i in 0..n as usize {
        let record = &records[i * PROBE_IN..(i + 1) * PROBE_IN];
        let cpu = probe_cpu(record, &words);
        let g = &gpu_out[i * PROBE_OUT..(i + 1) * PROBE_OUT];
        let mut spread = [0.0f32; PROBE_OUT];
        for (c, sign) in [(6, 1.0), (6, -1.0), (7, 1.0), (7, -1.0), (8, 1.0), (8, -1.0)] {
            let mut nudged = record.to_vec();
            nudged[c] = (nudged[c] * (1.0 + sign * 4.0 * f32::EPSILON)).min(1.0 - f32::EPSILON);
            let other = probe_cpu(&nudged, &words);
            for s in [14, 25, 38, 51] {
                if other[s] != cpu[s] || other[s + 8] != cpu[s + 8] {
                    continue;
                }
                for slot in s..s + 9 {
                    spread[slot] = spread[slot].max((other[slot] - cpu[slot]).abs());
                }
            }
            for slot in 4..7 {
                spread[slot] = spread[slot].max((other[slot] - cpu[slot]).abs());
            }
        }
        // A sample whose discrete outcome differs is compared no further.
        let mut skip = [false; PROBE_OUT];
        for s in [14, 25, 38, 51] {
            if g[s] != cpu[s] || g[s + 8] != cpu[s + 8] {
                flipped.push(format!("record {i} {}: gpu {:?} cpu {:?}", slot_name(s), &g[s..s + 9], &cpu[s..s + 9]));
                skip[s..s + 9].iter_mut().for_each(|x| *x = true);
            }
        }
        for slot in 0..PROBE_OUT {
            if skip[slot] || is_discrete(slot) {
                continue;
            }
            let (a, b) = (g[slot], cpu[slot]);
            // The sampled normal is a unit vector: its components are compared relative to a tenth
            // of its length at least. (A component near 0 of a Beckmann normal, alpha 0.01, seen
            // from near the normal, was 1.6e-6 off: the slopes go through the driver's log and
            // exp in erfinv and Newton's steps.)
            let scale = if (4..7).contains(&slot) { a.abs().max(b.abs()).max(0.1) } else { a.abs().max(b.abs()) };
            let err = (a - b).abs();
            if !(a.is_finite() && b.is_finite()) {
                mismatches.push(format!("record {i} slot {slot} ({}): gpu {a} cpu {b}", slot_name(slot)));
                continue;
            }
            if scale > 1e-3 && err / scale > worst {
                worst = err / scale;
                worst_at = (i, slot);
            }
            if err > 1e-4 * scale + 1e-6 {
                conditioned += 1;
            }
            if err > 1e-4 * scale + 1e-6 + spread[slot] {
                mismatches
                    .push(format!("record {i} slot {slot} ({}): gpu {a} cpu {b} input {record:?}", slot_name(slot)));
            }
        }
    }
    println!(
        "{n} records: worst relative difference {worst:.2e} (of values above 1e-3) at record {} slot {} ({}); {conditioned} values beyond \
         1e-4 accepted by the sensitivity term; {} samples with a flipped decision",
        worst_at.0,
        worst_at.1,
        slot_name(worst_at.1),
        flipped.len()
    );
    for f in flipped.iter().take(5) {
        println!("  {f}");
    }
    assert!(
        mismatches.is_empty(),
        "{} mismatches, first: {:#?}",
        mismatches.len(),
        &mismatches[..mismatches.len().min(10)]
    );
    // A decision flips only within rounding of its threshold: a few in 1e5 at most.
    assert!(flipped.len() <= 4, "{} flipped decisions: {flipped:#?}", flipped.len());
}
