//! The image texture lookups of `shaders/image_texture.glsl` against their CPU twin, through the
//! test kernel `image_texture_probe`: the same packed blocks, the same points, every wrap mode,
//! including the seams, texel centres, far-away and non-finite coordinates.

mod common;

use glam::{Vec2, Vec4};
use photonix::cpu::image_texture::{image_lookup, image_texel};
use photonix::layout::constants::WORKGROUP_SIZE;
use photonix::scene::image_texture::{load_image_texture, ColorSpace, ImageTexture, Wrap};

/// xorshift64*: reproducible numbers without a dependency.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A 5x3 image (sizes that are not powers of two) of varied values: negative, subnormal halves,
/// values near the largest half, alpha below 1.
fn odd_image() -> ImageTexture {
    let mut rng = Rng(0x1234_5678);
    let mut texels: Vec<[f32; 4]> = (0..15).map(|_| [0.0; 4].map(|_: f32| 4.0 * rng.next_f32() - 1.0)).collect();
    texels[3] = [3e-6, 1e-7, 60000.0, 0.0];
    texels[7] = [-2.5, 0.0, 1.0, 1.0];
    ImageTexture { width: 5, height: 3, texels }
}

/// Points to look up in a block of `w` x `h` texels.
fn points(w: u32, h: u32, rng: &mut Rng) -> Vec<Vec2> {
    let (wf, hf) = (w as f32, h as f32);
    let mut p = Vec::new();
    // A grid over [-2.3, 2.3]^2 whose steps do not line up with texels.
    for a in 0..67 {
        for b in 0..41 {
            p.push(Vec2::new(-2.3 + a as f32 * 0.0697, -2.3 + b as f32 * 0.1131));
        }
    }
    // Texel centres and the points halfway between them.
    for j in 0..2 * h + 1 {
        for i in 0..2 * w + 1 {
            p.push(Vec2::new(i as f32 * 0.5 / wf, 1.0 - j as f32 * 0.5 / hf));
        }
    }
    // Seams and edges: u, v in {0, 1, -1, 2, half a texel in}, and just beside them.
    let edges = [0.0, 1.0, -1.0, 2.0, 0.5 / wf, 1.0 - 0.5 / wf, 0.5 / hf, 1.0 - 0.5 / hf];
    for &a in &edges {
        for &b in &edges {
            for d in [0.0, 1e-7, -1e-7, 1e-3] {
                p.push(Vec2::new(a + d, b - d));
            }
        }
    }
    // Far away and not finite: the lookups must stay inside the block.
    let wild =
        [1e6, -1e6, 123_456.79, 1e30, -1e30, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e-40, -0.0, 16_777_217.0];
    for &a in &wild {
        for &b in &wild {
            p.push(Vec2::new(a, b));
        }
        p.push(Vec2::new(a, 0.3));
        p.push(Vec2::new(0.7, a));
    }
    for _ in 0..2000 {
        p.push(Vec2::new(6.0 * rng.next_f32() - 3.0, 6.0 * rng.next_f32() - 3.0));
    }
    p
}

/// Distance in units in the last place between two finite floats of the same sign, else a big
/// number (0 for +0 and -0).
fn ulps(a: f32, b: f32) -> u32 {
    if a == b {
        return 0;
    }
    if a.is_nan() || b.is_nan() || (a < 0.0) != (b < 0.0) {
        return u32::MAX;
    }
    a.to_bits().abs_diff(b.to_bits())
}

#[test]
fn gpu_image_lookups_equal_cpu_lookups() {
    let back_wall = common::repo_path("../shared/reference/cornell-glossy/textures/back_wall.png");
    let back_wall = load_image_texture(&back_wall, ColorSpace::Srgb).expect("the shared back-wall texture loads");
    let odd = odd_image();
    let one = ImageTexture { width: 1, height: 1, texels: vec![[0.25, 0.5, 0.75, 1.0]] };
    let row = ImageTexture { width: 7, height: 1, texels: (0..7).map(|i| [i as f32, 1.0, 2.0, 0.5]).collect() };

    let mut data = Vec::new();
    let mut blocks = Vec::new(); // (at, width, height, label)
    for (image, name) in [(&odd, "5x3"), (&back_wall, "back wall"), (&one, "1x1"), (&row, "7x1")] {
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            let at = image.pack(wrap, &mut data);
            blocks.push((at, image.width, image.height, format!("{name} {wrap:?}")));
        }
    }

    let mut rng = Rng(42);
    let mut queries: Vec<u32> = Vec::new();
    let mut owners = Vec::new();
    for (b, &(at, w, h, _)) in blocks.iter().enumerate() {
        for p in points(w, h, &mut rng) {
            queries.extend([p.x.to_bits(), p.y.to_bits(), at, 0]);
            owners.push(b);
        }
    }
    let count = owners.len() as u32;

    let ctx = common::gpu();
    let spirv = photonix::shaders::spirv("image_texture_probe").expect("build.rs compiles the probe");
    let probe = ctx.create_kernel("image_texture_probe", &spirv, 3, 4).expect("probe matches its layout");
    let texture_data = ctx.upload("texture_data", &data).unwrap();
    let query_buffer = ctx.upload("queries", &queries).unwrap();
    let results = ctx.create_buffer("results", u64::from(count) * 32).unwrap();
    ctx.run("image_texture_probe", |r| {
        let groups = [count.div_ceil(WORKGROUP_SIZE), 1, 1];
        r.dispatch(&probe, &[&texture_data, &query_buffer, &results], bytemuck::bytes_of(&count), groups)
    })
    .unwrap();
    let gpu: Vec<[f32; 4]> = ctx.download(&results).unwrap();

    let mut worst_ulps = 0;
    let mut worst_abs = 0.0f32;
    let mut identical = 0;
    for (q, &b) in owners.iter().enumerate() {
        let (at, _, _, ref label) = blocks[b];
        let uv = Vec2::new(f32::from_bits(queries[4 * q]), f32::from_bits(queries[4 * q + 1]));
        let lookup = image_lookup(&data, at, uv);
        let texel = image_texel(&data, at, uv);
        let (gpu_lookup, gpu_texel) = (Vec4::from(gpu[2 * q]), Vec4::from(gpu[2 * q + 1]));
        // The nearest texel involves one exact product and a floor: identical bits.
        let same_bits =
            |a: Vec4, b: Vec4| a.to_array().iter().zip(b.to_array()).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same_bits(gpu_texel, texel), "{label}, uv {uv}: texel gpu {gpu_texel} cpu {texel}");
        if same_bits(gpu_lookup, lookup) {
            identical += 1;
        }
        for c in 0..4 {
            worst_ulps = worst_ulps.max(ulps(gpu_lookup[c], lookup[c]));
            worst_abs = worst_abs.max((gpu_lookup[c] - lookup[c]).abs());
        }
        // Both sides decode the same halves exactly and evaluate the same expression in the
        // same order without fused multiply-adds (`precise` in GLSL), and Vulkan rounds + and *
        // correctly, so the results should be bit for bit equal (lavapipe: all are). 4 ulps
        // leaves room for a driver that ignores `precise` while catching any change of formula
        // (a texel off by one, a weight swapped) which moves values by 1e-3 or more.
        for c in 0..4 {
            assert!(
                ulps(gpu_lookup[c], lookup[c]) <= 4 || (gpu_lookup[c] - lookup[c]).abs() <= 1e-30,
                "{label}, uv {uv}: lookup gpu {gpu_lookup} cpu {lookup}"
            );
        }
    }
    println!(
        "{count} lookups in {} blocks: {identical} bit-identical, worst {worst_ulps} ulp, worst |gpu - cpu| {worst_abs:e}",
        blocks.len()
    );
}

/// A 2x2 sRGB PNG: red top-left, green top-right, blue bottom-left, white bottom-right.
fn write_quadrant_png(path: &std::path::Path) {
    let colours = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]];
    image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(colours[(2 * y + x) as usize])).save(path).unwrap();
}

/// An 8x4 sRGB PNG of varied colours, so that any wrong u or v shows.
fn write_varied_png(path: &std::path::Path) {
    image::RgbImage::from_fn(8, 4, |x, y| {
        image::Rgb([(30 * x + 20) as u8, (60 * y + 30) as u8, ((x * y * 37) % 256) as u8])
    })
    .save(path)
    .unwrap();
}

/// A planar world-space image (POV-Ray's map_type 0) on a quad facing the camera: the quad is
/// [-1, 1]^2 at z = 0 and the texture's transform stretches the image's unit square onto it, so
/// each quadrant of the render shows one texel, the image's top row at +y.
#[test]
fn planar_world_image_lands_where_its_projection_says() {
    let dir = tempfile::tempdir().unwrap();
    write_quadrant_png(&dir.path().join("quadrants.png"));
    let scene = "[camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 25\n\
        [render]\nmax_depth = 1\n\
        [textures.q]\ntype = \"image\"\nfile = \"quadrants.png\"\nspace = \"world\"\nprojection = \"planar\"\n\
        transform = { scale = [2, 2, 1], translate = [-1, -1, 0] }\n\
        [materials.screen]\ntype = \"diffuse\"\nreflectance = 0\nemission = { texture = \"q\" }\n\
        [[shapes]]\ntype = \"quad\"\nmaterial = \"screen\"\nvertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]\n";
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let scene = photonix::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let size = 64;
    let image = common::cpu_image(&common::buffers(&scene, size, size), 1);
    // The quad spans about 2 / (2 * 6 * tan 12.5 deg) = 75% of the view: quadrant centres at
    // +-0.5 lie at about 32 +- 12 pixels.
    let expected =
        [((20, 20), [1.0, 0.0, 0.0]), ((44, 20), [0.0, 1.0, 0.0]), ((20, 44), [0.0, 0.0, 1.0]), ((44, 44), [1.0; 3])];
    for ((x, y), want) in expected {
        let got = image.pixel(x, y);
        for c in 0..3 {
            // A pixel's jittered sample lies up to a pixel (1/24 of a texel) off the texel centre:
            // a few percent of the neighbours bleed in; a wrong texel would be off by 1.
            assert!((got[c] - want[c]).abs() < 0.1, "pixel ({x}, {y}): got {got:?}, expected {want:?}");
        }
    }
    // Outside the quad: nothing.
    assert_eq!(image.pixel(1, 1), [0.0; 3]);
}

/// Planar, spherical and cylindrical world-space images (POV-Ray's map_type 0, 1, 2), each
/// placed by a transform, render alike on the GPU and on the CPU.
#[test]
fn world_space_image_projections_gpu_equals_cpu() {
    let dir = tempfile::tempdir().unwrap();
    write_varied_png(&dir.path().join("varied.png"));
    let texture = |name: &str, projection: &str, transform: &str| {
        format!(
            "[textures.{name}]\ntype = \"image\"\nfile = \"varied.png\"\nspace = \"world\"\nprojection = \"{projection}\"\n\
             transform = {transform}\n[materials.{name}]\ntype = \"diffuse\"\nreflectance = {{ texture = \"{name}\" }}\n"
        )
    };
    let mut scene = String::from("[camera]\nposition = [0, 1, 6]\nlook_at = [0, 1, 0]\nfov = 40\n");
    scene += "[[lights]]\ntype = \"point\"\nposition = [0, 4, 5]\nintensity = [30, 30, 30]\n";
    scene += &texture("flat", "planar", "{ scale = [0.5, 0.5, 1], translate = [-1, 0, -1] }");
    scene += &texture("globe", "spherical", "{ rotate = [0, 30, 0], scale = 0.8, translate = [-1.2, 1, 0] }");
    scene += &texture("drum", "cylindrical", "{ scale = [0.6, 2, 0.6], translate = [1.2, 0, 0] }");
    scene += "[[shapes]]\ntype = \"quad\"\nmaterial = \"flat\"\nvertices = [[-3, -1, -1], [3, -1, -1], [3, 3, -1], [-3, 3, -1]]\n";
    scene += "[[shapes]]\ntype = \"sphere\"\nmaterial = \"globe\"\ncenter = [-1.2, 1, 0]\nradius = 0.8\n";
    scene +=
        "[[shapes]]\ntype = \"cylinder\"\nmaterial = \"drum\"\nbase = [1.2, 0, 0]\ncap = [1.2, 2, 0]\nradius = 0.6\n";
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, &scene).unwrap();
    let scene = photonix::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let cpu = common::assert_twins_agree("world-space image projections", &common::buffers(&scene, 48, 36));
    // Not black: the textures were read.
    let mean: f32 = cpu.image.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / cpu.image.pixels.len() as f32;
    assert!(mean > 0.05, "mean {mean}");
}

/// Textured emission is a specialization constant (`KernelVariant::emission_textures`): set only
/// where a material's emission reads a texture, and the kernels built with it light a textured
/// screen as the CPU twin does, with photon mapping and with vcm (light sampling, emission met and
/// light paths all read it).
#[test]
fn textured_emission_is_compiled_in_only_where_a_material_has_it() {
    let dir = tempfile::tempdir().unwrap();
    write_quadrant_png(&dir.path().join("quadrants.png"));
    for integrator in ["ppm", "vcm"] {
        let scene = format!(
            "[camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 30\n\
             [render]\nintegrator = \"{integrator}\"\n\
             [textures.q]\ntype = \"image\"\nfile = \"quadrants.png\"\nspace = \"world\"\nprojection = \"planar\"\n\
             transform = {{ scale = [2, 2, 1], translate = [-1, -1, 0] }}\n\
             [materials.screen]\ntype = \"diffuse\"\nreflectance = 0\nemission = {{ texture = \"q\" }}\n\
             [materials.wall]\ntype = \"diffuse\"\nreflectance = 0.8\n\
             [[shapes]]\ntype = \"quad\"\nmaterial = \"screen\"\nvertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]\n\
             [[shapes]]\ntype = \"quad\"\nmaterial = \"wall\"\nvertices = [[-3, -1.5, 2], [-3, -1.5, -2], [3, -1.5, -2], [3, -1.5, 2]]\n"
        );
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, scene).unwrap();
        let scene = photonix::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let buffers = common::buffers(&scene, 32, 32);
        assert!(buffers.variant().emission_textures, "{integrator}: the screen's emission is textured");
        let out = common::assert_twins_agree(&format!("textured emission, {integrator}"), &buffers);
        // The screen's top-left quadrant is the image's red texel (a little of the others
        // bleeds in through the pixel's jitter).
        let red = out.image.pixel(12, 12);
        assert!(red[0] > 0.5 && red[0] > 3.0 * red[1].max(red[2]), "{integrator}: top-left quadrant {red:?}");
    }
    let glossy = photonix::scene::load_scene(&common::repo_path("scenes/cornell-glossy.toml")).unwrap();
    assert!(!common::buffers(&glossy, 8, 8).variant().emission_textures, "cornell-glossy's light is a plain colour");
}
