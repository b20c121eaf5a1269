//! Photonix against Mitsuba 3 on small scenes of features the shared references do not cover:
//! a spot light, a thin lens, the Hosek-Wilkie sky alone and with its sun, nonlinear plastics
//! (smooth and rough), tinted conductors, Beckmann microfacets and a thin dielectric. The scenes are Photonix files in
//! tests/references/; make_mitsuba_references.py there translated each into Mitsuba 3.9.1's path
//! tracer and rendered the committed EXRs (4096 spp). Here each is rendered with the CPU backend,
//! 8 progressive passes, and compared by per-channel mean and relMSE.

mod common;

use photonix::io::image::read_exr;
use photonix::io::metrics::{mean_ratio, rel_mse};

/// Renders `name` and returns (relMSE, mean ratios) against Mitsuba's image.
fn compare(name: &str) -> (f64, [f64; 3]) {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::repo_path(&format!("tests/references/{name}.toml"));
    let out = dir.path().join(format!("{name}.exr"));
    let run = common::photonix(
        &["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--passes", "8", "--backend", "cpu"],
        dir.path(),
    );
    assert!(run.status.success(), "{name}: {}", common::stderr(&run));
    let ours = read_exr(&out).unwrap();
    let theirs = read_exr(&common::repo_path(&format!("tests/references/mitsuba/{name}.exr"))).unwrap();
    let (error, ratio) = (rel_mse(&ours, &theirs), mean_ratio(&ours, &theirs));
    println!("{name}: relMSE {error:.2e} against Mitsuba, mean ratio {ratio:.4?}");
    (error, ratio)
}

fn check(name: &str, max_error: f64, max_mean_off: f64) {
    let (error, ratio) = compare(name);
    assert!(error < max_error, "{name}: relMSE {error:.3e} against Mitsuba");
    for r in ratio {
        assert!((r - 1.0).abs() < max_mean_off, "{name}: mean ratio {ratio:?} against Mitsuba");
    }
}

// Bounds: the means within 3% (the issue's), relMSE about three times what was measured
// (spot 1.3e-4, thin lens 7.8e-4, sky 7.5e-4): noise of 8 passes at 48 x 48, not a convention
// (a mirrored image, a wrong falloff or focus moves relMSE above 1e-2).

#[test]
fn spot_light_matches_mitsuba() {
    // Measured: mean ratio 1.0009 in every channel.
    check("spot", 5e-4, 0.03);
}

#[test]
fn thin_lens_matches_mitsuba() {
    // Measured: mean ratio 0.9996-0.9998; the blur of the near and far balls is in the relMSE.
    check("thinlens", 2.5e-3, 0.03);
}

#[test]
fn sky_matches_mitsuba_sunsky() {
    // The sky dome alone: the same Hosek-Wilkie RGB model in the same units (directions
    // evaluated one by one agree within 0.1%); the ground it lights measured 0.988.
    check("sky", 2.5e-3, 0.03);
}

#[test]
fn sun_and_sky_match_mitsuba_sunsky_within_its_sun_model() {
    // With the sun, measured 0.942, 0.950, 0.963: Mitsuba's RGB-mode sun is 5.6% (R) to 8.2%
    // (B) brighter than its own spectral mode, which Photonix's sun matches within 0.4% (see
    // the_sun_matches_mitsubas_spectral_sunsky and BENCHMARKS.md). The bound keeps that
    // and catches anything larger.
    check("sunsky", 1e-2, 0.08);
}

// Nonlinear plastic (Mitsuba's `plastic` and `roughplastic` with `nonlinear`): the sphere fills
// most of the frame, so a base off by its internal reflectance (the linear model's 1 / (1 -
// Fdr_int) against 1 / (1 - a Fdr_int)) moves the mean by 10% or more; the means are what
// these four tests hold to 2%. Their relMSE is the noise of 8 passes of 16 spp through glossy
// coats and caustics (`auto` picks ppm or vcm), bounded at about twice what was measured.

#[test]
fn smooth_nonlinear_plastic_matches_mitsuba() {
    // Measured: relMSE 3.6e-3, mean ratio 0.9989, 0.9938, 0.9909.
    check("plastic_smooth", 7e-3, 0.02);
}

#[test]
fn rough_nonlinear_plastic_matches_mitsuba() {
    // The rough coat's transmittance table and internal reflectance are Mitsuba's integrals; a
    // smooth-Fresnel base would be 15-30% brighter at alpha 0.2. Measured: relMSE 8.1e-3, mean
    // ratio 1.0046, 0.9953, 0.9889.
    check("plastic_rough", 1.6e-2, 0.02);
}

#[test]
fn beckmann_conductor_and_plastic_match_mitsuba() {
    // Beckmann gold (alpha 0.2) and a Beckmann nonlinear plastic (alpha 0.3). Measured: relMSE
    // 5.5e-3, mean ratio 0.9999, 1.0002, 1.0014. The same scene with GGX of the same alphas (the
    // Mitsuba front-end's former stand-in) measured relMSE 7.9e-3, mean ratio 0.9874, 0.9871,
    // 0.9816, which the 0.8% bound on the means rejects (the renders are seeded: the same every
    // run).
    check("beckmann", 1.1e-2, 0.008);
}

#[test]
fn tinted_conductor_matches_mitsuba() {
    // Smooth tinted chrome and rough tinted gold: a tint left out moves the means by 2x.
    // Measured: relMSE 6.9e-3, mean ratio 1.0020, 1.0027, 1.0013.
    check("conductor_tint", 1.4e-2, 0.02);
}

#[test]
fn thin_dielectric_matches_mitsuba() {
    // A ball of thin glass: the red ball behind it seen undisplaced, the sky reflected by
    // R + T^2 R / (1 - R^2); a closed dielectric there would refract the red ball away.
    // Measured: relMSE 2.3e-2 (the caustic the pane throws on the ground, through ppm's
    // photons), mean ratio 1.0076, 1.0019, 1.0015.
    check("thin_dielectric", 5e-2, 0.02);
}

/// The filters' scenes are a grey ball's edge against a white sky, where a wrong filter or splats
/// left unfiltered show above the noise of 8 passes of 64 spp (the renders are deterministic):
/// measured relMSE against Mitsuba's tent 6.07e-4 with our tent, 7.63e-4 with our box; against
/// its Gaussian 6.03e-4 with ours, 9.64e-4 with the box. Means agree within 3e-4.
const FILTER_MAX_ERROR: f64 = 7e-4;

#[test]
fn tent_filter_matches_mitsuba_through_bpt() {
    // Each pixel Mitsuba's tent of radius 1; `bpt` draws its camera samples from the tent and
    // spreads its light-tracing splats by it.
    check("filter_tent", FILTER_MAX_ERROR, 0.02);
}

#[test]
fn gaussian_filter_matches_mitsuba_through_vcm() {
    check("filter_gaussian", FILTER_MAX_ERROR, 0.02);
}

#[test]
fn stretched_filters_match_mitsuba() {
    // `filter_radius`: a Gaussian of four times Mitsuba's `stddev` 0.8 through `vcm`'s splats, a
    // tent of Mitsuba's `radius` 0.6 through `bpt`'s.
    check("filter_wide", FILTER_MAX_ERROR, 0.02);
    check("filter_narrow", FILTER_MAX_ERROR, 0.02);
}
