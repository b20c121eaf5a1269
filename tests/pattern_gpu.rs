//! shaders/pattern.glsl on the device (through the test kernel pattern_probe.comp, one invocation
//! per point) against its CPU twin src/cpu/pattern.rs, pattern by pattern, with the validation
//! layer on.
//!
//! What to expect: the integer parts (hashes, cells, gradient choices) are the same code, and the
//! float arithmetic is the same sequence of IEEE operations (the shader's `precise` forbids fused
//! multiply-adds; sines are the same polynomial on both sides), so on lavapipe most values are
//! bit-identical. The exceptions are `pow` (agate, the poly wave, crackle with metric 3), whose
//! GPU version is exp2(y log2 x) with its own rounding, and whatever that difference feeds.

mod common;

use glam::Vec3;
use photonix::cpu::pattern::{
    color_map_eval, noise_signed, noise_unit, pattern_gradient, pattern_value, sin_turns, turbulence,
};
use photonix::gpu::{GpuContext, Kernel};
use photonix::layout::constants::WORKGROUP_SIZE;
use photonix::scene::pattern::{ColorMap, PatternDesc, PatternKind, Warp, WarpKind, WaveShape, PATTERN_NAMES};

const MODE_VALUE: u32 = 0;
const MODE_GRADIENT: u32 = 1;
const MODE_COLOR_MAP: u32 = 2;
const MODE_NOISE: u32 = 3;
const MODE_COLOUR: u32 = 4;

struct Probe {
    gpu: GpuContext,
    kernel: Kernel,
}

impl Probe {
    fn new() -> Probe {
        Probe::with_noise(true)
    }

    /// The probe with Perlin noise compiled in or out (the scene kernels' specialization
    /// constant SCENE_HAS_NOISE).
    fn with_noise(noise: bool) -> Probe {
        let gpu = common::gpu();
        let spirv = photonix::shaders::spirv("pattern_probe").expect("build.rs compiles shaders/pattern_probe.comp");
        let constants = [1, 1, noise as u32];
        let kernel = gpu
            .create_specialized_kernel("pattern_probe", &spirv, 3, Default::default(), 20, &constants)
            .expect("pattern_probe matches its layout");
        Probe { gpu, kernel }
    }

    /// Runs `mode` on every input point; returns the 4 floats each invocation wrote.
    fn run(&self, data: &[u32], mode: u32, at: u32, map_at: u32, h: f32, inputs: &[Vec3]) -> Vec<[f32; 4]> {
        let texture_data = self.gpu.upload("texture_data", data).unwrap();
        let points: Vec<[f32; 4]> = inputs.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let input = self.gpu.upload("pattern_inputs", &points).unwrap();
        let output = self.gpu.create_buffer("pattern_outputs", 16 * inputs.len() as u64).unwrap();
        let count = inputs.len() as u32;
        let push: Vec<u8> = [count, mode, at, map_at, h.to_bits()].iter().flat_map(|w| w.to_le_bytes()).collect();
        let groups = [count.div_ceil(WORKGROUP_SIZE), 1, 1];
        self.gpu
            .run("pattern_probe", |r| r.dispatch(&self.kernel, &[&texture_data, &input, &output], &push, groups))
            .unwrap();
        self.gpu.download(&output).unwrap()
    }
}

/// Reproducible points in [-r, r]^3 (xorshift64*), plus lattice points and cell borders.
fn points(n: usize, r: f32, mut state: u64) -> Vec<Vec3> {
    let mut next = || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        ((state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / 16_777_216.0) * 2.0 - 1.0
    };
    let mut pts: Vec<Vec3> = (0..n).map(|_| Vec3::new(next(), next(), next()) * r).collect();
    pts.extend([Vec3::ZERO, Vec3::ONE, Vec3::new(-1.0, 2.0, -3.0), Vec3::new(0.5, -0.5, 1e-7), Vec3::splat(-1e-7)]);
    pts
}

/// Agreement of one quantity over all points.
#[derive(Default)]
struct Agreement {
    count: usize,
    identical: usize,
    max_diff: f32,
    /// Points that differ by more than the tolerance.
    outliers: usize,
}

impl Agreement {
    fn add(&mut self, gpu: f32, cpu: f32, tolerance: f32) {
        self.count += 1;
        if gpu.to_bits() == cpu.to_bits() {
            self.identical += 1;
        }
        let diff = (gpu - cpu).abs();
        if diff > tolerance || diff.is_nan() {
            self.outliers += 1;
        } else {
            self.max_diff = self.max_diff.max(diff);
        }
    }

    fn line(&self, name: &str) -> String {
        format!(
            "{name:<44} {:>5}/{:<5} bit-identical, max |diff| {:.1e}, {} beyond tolerance",
            self.identical, self.count, self.max_diff, self.outliers
        )
    }
}

/// Every pattern with its defaults, and with turbulence, other wave shapes and frequencies.
fn variants() -> Vec<(String, PatternDesc)> {
    let mut all = Vec::new();
    for name in PATTERN_NAMES {
        let base = PatternDesc::new(PatternKind::from_name(name).unwrap());
        all.push((name.to_string(), base));
        all.push((
            format!("{name} turbulence"),
            PatternDesc { turbulence: Vec3::new(0.6, 0.3, 0.9), octaves: 10, ..base },
        ));
        if !base.kind.is_discrete() {
            let sine = PatternDesc { frequency: -2.5, phase: 0.3, wave: WaveShape::Sine, ..base };
            all.push((format!("{name} sine -2.5 0.3"), sine));
            let poly = PatternDesc { frequency: 3.0, wave: WaveShape::Poly { exponent: 2.5 }, ..base };
            all.push((format!("{name} poly 2.5 x3"), poly));
            let mixed = PatternDesc { wave: WaveShape::Scallop, lambda: 2.3, omega: 0.6, ..base };
            all.push((format!("{name} scallop"), mixed));
        }
    }
    let crackle = |metric, offset, solid| {
        PatternDesc::new(PatternKind::Crackle { form: Vec3::new(-1.0, 1.0, 0.5), metric, offset, solid })
    };
    all.push(("crackle metric 1 offset 0.2".to_string(), crackle(1.0, 0.2, false)));
    all.push(("crackle metric 3 offset 0.1".to_string(), crackle(3.0, 0.1, false)));
    all.push(("crackle solid".to_string(), crackle(2.0, 0.0, true)));
    all.push((
        "gradient [1, 2, -0.5]".to_string(),
        PatternDesc::new(PatternKind::Gradient { direction: Vec3::new(1.0, 2.0, -0.5) }),
    ));
    all.push((
        "brick [1, 0.5, 0.7] mortar 0.05".to_string(),
        PatternDesc::new(PatternKind::Brick { brick_size: Vec3::new(1.0, 0.5, 0.7), mortar: 0.05 }),
    ));
    // Every warp kind, alone and in pairs with transforms between them.
    let placed = glam::Affine3A::from_scale_rotation_translation(
        Vec3::new(0.5, 2.0, 1.5),
        glam::Quat::from_rotation_y(0.7),
        Vec3::new(0.3, -1.0, 2.0),
    );
    let warp = |kind, transform| Some(Warp { kind, transform });
    let repeat =
        WarpKind::Repeat { axis: 0, width: 2.0, offset: Vec3::new(0.0, 0.5, 0.25), flip: Vec3::new(1.0, -1.0, 1.0) };
    let hole = WarpKind::BlackHole {
        center: Vec3::new(0.5, 0.0, 0.0),
        radius: 3.0,
        strength: 1.5,
        falloff: 2.0,
        inverse: false,
        repeat: Vec3::new(7.0, 0.0, 5.0),
    };
    let identity = glam::Affine3A::IDENTITY;
    for (name, kind, warps) in [
        (
            "gradient x, repeat x*2 flip y offset",
            PatternKind::Gradient { direction: Vec3::X },
            [warp(repeat, identity), None, None, None],
        ),
        ("bozo, black_hole repeat", PatternKind::Bozo, [warp(hole, placed), None, None, None]),
        (
            "checker, cylindrical",
            PatternKind::Checker,
            [warp(WarpKind::Cylindrical { orientation: Vec3::Z, dist_exp: 0.0 }, identity), None, None, None],
        ),
        (
            "onion, cylindrical y dist_exp 1",
            PatternKind::Onion,
            [warp(WarpKind::Cylindrical { orientation: Vec3::Y, dist_exp: 1.0 }, placed), None, None, None],
        ),
        (
            "marble, spherical",
            PatternKind::Marble,
            [warp(WarpKind::Spherical { orientation: Vec3::Z, dist_exp: 0.0 }, identity), None, None, None],
        ),
        (
            "leopard, toroidal 2",
            PatternKind::Leopard,
            [
                warp(WarpKind::Toroidal { orientation: Vec3::X, dist_exp: 0.0, major_radius: 2.0 }, placed),
                None,
                None,
                None,
            ],
        ),
        (
            "brick, planar then repeat",
            PatternKind::from_name("brick").unwrap(),
            [warp(WarpKind::Planar { orientation: Vec3::Y, offset: 0.3 }, placed), warp(repeat, identity), None, None],
        ),
        (
            "wood, four warps",
            PatternKind::Wood,
            [
                warp(repeat, placed),
                warp(WarpKind::Spherical { orientation: Vec3::Z, dist_exp: 1.0 }, identity),
                warp(hole, identity),
                warp(WarpKind::Planar { orientation: Vec3::Z, offset: 0.0 }, placed),
            ],
        ),
    ] {
        let desc = PatternDesc { warps, turbulence: Vec3::splat(0.2), ..PatternDesc::new(kind) };
        all.push((format!("warps: {name}"), desc));
    }
    all
}

/// Whether a description's GPU arithmetic includes the driver's `pow`.
fn uses_pow(desc: &PatternDesc) -> bool {
    let warp_pow = desc.warp_list().any(|w| match w.kind {
        WarpKind::BlackHole { .. } => true,
        WarpKind::Cylindrical { dist_exp, .. }
        | WarpKind::Spherical { dist_exp, .. }
        | WarpKind::Toroidal { dist_exp, .. } => dist_exp != 0.0 && dist_exp != 1.0,
        _ => false,
    });
    warp_pow
        || matches!(desc.wave, WaveShape::Poly { .. })
        || matches!(desc.kind, PatternKind::Agate { .. })
        || matches!(desc.kind, PatternKind::Crackle { metric, .. } if metric != 1.0 && metric != 2.0)
}

#[test]
fn gpu_patterns_equal_the_cpu_twin() {
    let probe = Probe::new();
    let pts = points(4000, 30.0, 1);
    let mut data = Vec::new();
    let blocks: Vec<(String, PatternDesc, u32)> = variants()
        .into_iter()
        .map(|(name, desc)| {
            let at = desc.pack(&mut data);
            (name, desc, at)
        })
        .collect();
    let mut failures = Vec::new();
    for (name, desc, at) in &blocks {
        let gpu = probe.run(&data, MODE_VALUE, *at, 0, 0.0, &pts);
        // Without pow every operation is a correctly rounded IEEE operation on both sides: expect
        // the same bits. With pow, the driver's pow differs from Rust's powf by a few ulp (relative
        // 1e-6), which the wave stage can amplify by the frequency (3): 2e-5 is ample.
        let tolerance = if uses_pow(desc) { 2e-5 } else { 0.0 };
        let mut agreement = Agreement::default();
        for (p, g) in pts.iter().zip(&gpu) {
            agreement.add(g[0], pattern_value(&data, *at, *p), tolerance);
        }
        println!("{}", agreement.line(name));
        // A value that wraps (fmod, fract) or a discrete pattern may flip where a last-bit
        // difference crosses an edge: a handful of points at most.
        if agreement.outliers > 2 {
            failures.push(agreement.line(name));
        }
    }
    assert!(failures.is_empty(), "GPU and CPU disagree:\n{}", failures.join("\n"));
}

/// The kernels compile Perlin noise out of scenes whose textures `texture_uses_noise` says do
/// not read it: every such pattern gives the same bits without noise, and the others do read it
/// (the constant takes effect).
#[test]
fn noise_is_compiled_out_only_where_no_pattern_reads_it() {
    use photonix::layout::{constants::TEXTURE_PATTERN, Texture};
    let (with, without) = (Probe::with_noise(true), Probe::with_noise(false));
    let pts = points(1000, 30.0, 3);
    let mut data = Vec::new();
    let blocks: Vec<(String, u32)> = variants().into_iter().map(|(name, desc)| (name, desc.pack(&mut data))).collect();
    let (mut free, mut differ) = (0, Vec::new());
    for (name, at) in &blocks {
        let texture = Texture { kind: TEXTURE_PATTERN, data: *at, ..Default::default() };
        let noise = photonix::render::pack::texture_uses_noise(&texture, &data);
        let a = with.run(&data, MODE_VALUE, *at, 0, 0.0, &pts);
        let b = without.run(&data, MODE_VALUE, *at, 0, 0.0, &pts);
        let same = a.iter().zip(&b).all(|(x, y)| x[0].to_bits() == y[0].to_bits());
        if !noise {
            assert!(same, "{name}: texture_uses_noise says no noise, but it reads noise");
            free += 1;
        } else if !same {
            differ.push(name.clone());
        }
    }
    println!("{free} of {} pattern variants lose their noise; reads it: {}", blocks.len(), differ.join(", "));
    assert!(free >= 9, "only {free} pattern variants are free of noise");
    for name in ["bozo", "granite", "marble turbulence", "checker turbulence"] {
        assert!(differ.iter().any(|d| d == name), "{name} reads noise but the probe without it gave the same values");
    }
}

#[test]
fn gpu_noise_turbulence_and_sine_are_bit_identical() {
    let probe = Probe::new();
    let mut pts = points(4000, 100.0, 2);
    pts.extend((0..1000).map(|i| Vec3::new(i as f32 * 1e-3 - 0.5, 0.25, -0.75)));
    let gpu = probe.run(&[0], MODE_NOISE, 0, 0, 0.0, &pts);
    let names = ["noise_signed", "noise_unit", "turbulence (6 octaves)", "sin_turns"];
    let mut all = [(); 4].map(|_| Agreement::default());
    for (p, g) in pts.iter().zip(&gpu) {
        let cpu = [noise_signed(*p, 0), noise_unit(*p), turbulence(*p, 6, 0.5, 2.0), sin_turns(p.x)];
        for k in 0..4 {
            all[k].add(g[k], cpu[k], 0.0);
        }
    }
    for (a, name) in all.iter().zip(names) {
        println!("{}", a.line(name));
        assert_eq!(a.identical, a.count, "{name}");
    }
}

#[test]
fn gpu_gradients_equal_the_cpu_twin() {
    let probe = Probe::new();
    let pts = points(2000, 10.0, 3);
    let mut data = Vec::new();
    let h = 1e-3;
    for name in ["bumps", "dents", "wrinkles", "ripples", "waves", "leopard", "crackle", "granite", "wood", "marble"] {
        let desc =
            PatternDesc { turbulence: Vec3::splat(0.3), ..PatternDesc::new(PatternKind::from_name(name).unwrap()) };
        let at = desc.pack(&mut data);
        let gpu = probe.run(&data, MODE_GRADIENT, at, 0, h, &pts);
        let mut agreement = Agreement::default();
        for (p, g) in pts.iter().zip(&gpu) {
            let cpu = pattern_gradient(&data, at, *p, h);
            for k in 0..3 {
                agreement.add(g[k], cpu[k], 0.0);
            }
        }
        println!("{}", agreement.line(&format!("gradient of {name} with turbulence 0.3")));
        // Six bit-identical values, one division by 2h each: bit-identical, but for a wrap of
        // one of the six values (crackle, wood and marble wrap or fold).
        assert!(agreement.outliers <= 2, "{}", agreement.line(name));
    }
}

#[test]
fn gpu_color_maps_equal_the_cpu_twin() {
    let probe = Probe::new();
    let mut data = Vec::new();
    let mut maps: Vec<(String, u32)> = PATTERN_NAMES
        .iter()
        .map(|name| {
            (
                format!("default map of {name}"),
                PatternKind::from_name(name).unwrap().default_color_map().pack(&mut data),
            )
        })
        .collect();
    let custom = ColorMap::new(vec![
        (0.1, [0.2, 0.4, 0.6]),
        (0.3, [1.0, 0.5, 0.0]),
        (0.3, [0.0, 0.0, 1.0]),
        (0.95, [0.7, 0.7, 0.1]),
    ])
    .unwrap();
    maps.push(("custom map".to_string(), custom.pack(&mut data)));
    // Values across and beyond [0, 1], including every entry position exactly.
    let mut values: Vec<Vec3> = (0..3000).map(|i| Vec3::new(i as f32 / 2000.0 - 0.25, 0.0, 0.0)).collect();
    values.extend([0.0, 0.1, 0.3, 0.4, 0.5, 0.6, 0.8, 0.9, 0.95, 1.0].map(|v| Vec3::new(v, 0.0, 0.0)));
    for (name, at) in maps {
        let gpu = probe.run(&data, MODE_COLOR_MAP, at, 0, 0.0, &values);
        let mut agreement = Agreement::default();
        for (v, g) in values.iter().zip(&gpu) {
            let cpu = color_map_eval(&data, at, v.x);
            for k in 0..3 {
                agreement.add(g[k], cpu[k], 0.0);
            }
        }
        println!("{}", agreement.line(&name));
        assert_eq!(agreement.identical, agreement.count, "{name}");
    }
}

/// One tile of the pattern sheet: a pattern with its default colour map on a plane.
struct Tile {
    label: String,
    desc: PatternDesc,
    /// Half the side of the square shown, in pattern units.
    half_size: f32,
    /// The plane is x-y unless this is set (x-z, where hexagons lie and radial turns).
    xz: bool,
    /// Shade the pattern's gradient as a bump map instead of showing its colours.
    bumps: bool,
}

/// Renders every pattern with its default colour map into 128 x 128 tiles of one PNG, on the
/// GPU, and checks the pixels against the CPU twin. The sheet goes to $PHOTONIX_PATTERN_SHEET
/// when that is set (to look at), else to a temporary folder.
#[test]
fn pattern_sheet_shows_every_pattern() {
    const TILE: u32 = 128;
    const COLUMNS: u32 = 7;
    let mut tiles: Vec<Tile> = PATTERN_NAMES
        .iter()
        .map(|name| {
            let kind = PatternKind::from_name(name).unwrap();
            let half_size = match *name {
                "brick" => 12.0,
                "hexagon" | "wood" => 4.0,
                "leopard" => 15.0,
                "ripples" | "waves" => 6.0,
                _ => 3.0,
            };
            Tile {
                label: name.to_string(),
                desc: PatternDesc::new(kind),
                half_size,
                xz: matches!(*name, "hexagon" | "agate" | "radial"),
                bumps: false,
            }
        })
        .collect();
    // As POV-Ray users write them: `marble turbulence 1`, `wood turbulence 0.1`.
    let marble = PatternDesc { turbulence: Vec3::splat(1.0), ..PatternDesc::new(PatternKind::Marble) };
    tiles.push(Tile { label: "marble turbulence 1".into(), desc: marble, half_size: 3.0, xz: false, bumps: false });
    let wood = PatternDesc { turbulence: Vec3::splat(0.1), ..PatternDesc::new(PatternKind::Wood) };
    tiles.push(Tile { label: "wood turbulence 0.1".into(), desc: wood, half_size: 4.0, xz: false, bumps: false });
    // `normal { bumps 0.5 scale 0.2 }` seen from above, lit from the upper left.
    tiles.push(Tile {
        label: "bumps as a normal".into(),
        desc: PatternDesc::new(PatternKind::Bumps),
        half_size: 10.0,
        xz: false,
        bumps: true,
    });

    let probe = Probe::new();
    let rows = (tiles.len() as u32).div_ceil(COLUMNS);
    let mut sheet = image::RgbImage::new(COLUMNS * TILE, rows * TILE);
    let mut data = Vec::new();
    let mut worst = 0.0f32;
    for (index, tile) in tiles.iter().enumerate() {
        let at = tile.desc.pack(&mut data);
        let map_at = tile.desc.kind.default_color_map().pack(&mut data);
        let pts: Vec<Vec3> = (0..TILE * TILE)
            .map(|i| {
                let u = ((i % TILE) as f32 + 0.5) / TILE as f32 * 2.0 - 1.0;
                let v = 1.0 - ((i / TILE) as f32 + 0.5) / TILE as f32 * 2.0;
                let (a, b) = (u * tile.half_size, v * tile.half_size);
                if tile.xz {
                    Vec3::new(a, 0.37, b)
                } else {
                    Vec3::new(a, b, 0.37)
                }
            })
            .collect();
        let h = 1e-3 * tile.half_size;
        let colours: Vec<Vec3> = if tile.bumps {
            probe
                .run(&data, MODE_GRADIENT, at, 0, h, &pts)
                .iter()
                .map(|g| {
                    // Bump amount 0.5 and scale 0.2: the gradient in world units is 5x larger.
                    let n = (Vec3::Z - 0.5 * 5.0 * Vec3::new(g[0], g[1], 0.0)).normalize();
                    Vec3::splat(n.dot(Vec3::new(-0.5, 0.5, 0.7).normalize()).max(0.0))
                })
                .collect()
        } else {
            let gpu = probe.run(&data, MODE_COLOUR, at, map_at, 0.0, &pts);
            for (p, g) in pts.iter().zip(&gpu) {
                let cpu = color_map_eval(&data, map_at, pattern_value(&data, at, *p));
                worst = worst.max((Vec3::new(g[0], g[1], g[2]) - cpu).abs().max_element());
            }
            gpu.iter().map(|g| Vec3::new(g[0], g[1], g[2])).collect()
        };
        let (x0, y0) = ((index as u32 % COLUMNS) * TILE, (index as u32 / COLUMNS) * TILE);
        for (i, c) in colours.iter().enumerate() {
            let rgb = c.to_array().map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8);
            sheet.put_pixel(x0 + i as u32 % TILE, y0 + i as u32 / TILE, image::Rgb(rgb));
        }
        println!("tile {index}: {}", tile.label);
    }
    println!("largest colour difference GPU vs CPU over the sheet: {worst:.1e}");
    // The default maps hold sharp steps (bozo, marble, wood): a value one ulp apart on either
    // side of a step changes the colour completely, so a few pixels could differ; none do on
    // lavapipe, where the values agree bit for bit (see gpu_patterns_equal_the_cpu_twin).
    assert!(worst < 1e-3, "{worst}");

    let dir = tempfile::tempdir().unwrap();
    let path = std::env::var_os("PHOTONIX_PATTERN_SHEET")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| dir.path().join("patterns.png"));
    sheet.save(&path).unwrap();
    println!("pattern sheet: {}", path.display());
}
