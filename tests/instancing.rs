//! Instancing: objects placed with transforms render as the same geometry written out flat (camera
//! rays, shadow rays and photons), the GPU matches the CPU twin on them, memory follows the unique
//! geometry (10 000 instances of a 10 000-triangle mesh), and bad objects and placements are
//! refused with their file, line and field.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use photonix::io::metrics::{mean_ratio, rel_mse};
use photonix::layout::{BvhNode, Primitive};
use photonix::render::PhotonSettings;
use photonix::scene::{parse_scene, Scene};

const HEADER: &str = r#"
[camera]
position = [0, 2.2, 6]
look_at = [0, 0.6, 0]
fov = 45
resolution = [64, 48]
[render]
spp = 1
max_depth = 6
[materials.white]
type = "diffuse"
reflectance = 0.7
[materials.red]
type = "diffuse"
reflectance = [0.8, 0.2, 0.1]
[materials.blue]
type = "plastic"
reflectance = [0.1, 0.2, 0.8]
roughness = 0.2
[materials.glass]
type = "dielectric"
ior = 1.5
[[shapes]]
type = "quad"
material = "white"
vertices = [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]
[[lights]]
type = "point"
position = [1, 5, 3]
intensity = 40
"#;

/// The object's shapes in object space: a box, a glass sphere on it and an open cylinder beside
/// it (triangles, a sphere and an analytic shape).
const OBJECT_SHAPES: &[&str] = &[
    "type = \"box\"\nmaterial = \"red\"\nmin = [-0.5, 0, -0.5]\nmax = [0.5, 1, 0.5]",
    "type = \"sphere\"\nmaterial = \"glass\"\ncenter = [0, 1.4, 0]\nradius = 0.4",
    "type = \"cylinder\"\nmaterial = \"white\"\nbase = [0.7, 0, 0]\ncap = [0.7, 0.9, 0.1]\nradius = 0.15",
];

/// (transform, material override) of each placement.
const PLACEMENTS: &[(&str, Option<&str>)] = &[
    ("{ translate = [-1.6, 0, 0] }", None),
    ("{ scale = 0.8, rotate = [0, 40, 0], translate = [0, 0, -1] }", None),
    ("{ scale = 1.2, rotate = [8, -30, 5], translate = [1.6, 0.1, 0.5] }", Some("blue")),
];

fn instanced_text() -> String {
    let mut text = HEADER.to_string();
    for shape in OBJECT_SHAPES {
        writeln!(text, "[[objects.thing.shapes]]\n{shape}").unwrap();
    }
    for (transform, material) in PLACEMENTS {
        writeln!(text, "[[instances]]\nobject = \"thing\"\ntransform = {transform}").unwrap();
        if let Some(m) = material {
            writeln!(text, "material = \"{m}\"").unwrap();
        }
    }
    text
}

/// The same scene with every placed shape written out in the world.
fn flat_text() -> String {
    let mut text = HEADER.to_string();
    for (transform, material) in PLACEMENTS {
        for shape in OBJECT_SHAPES {
            let shape = match material {
                Some(m) => shape
                    .lines()
                    .map(|l| if l.starts_with("material") { format!("material = \"{m}\"") } else { l.to_string() })
                    .collect::<Vec<_>>()
                    .join("\n"),
                None => shape.to_string(),
            };
            writeln!(text, "[[shapes]]\n{shape}\ntransform = {transform}").unwrap();
        }
    }
    text
}

fn parse(text: &str) -> Scene {
    parse_scene(text, Path::new("instancing-test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn photons() -> PhotonSettings {
    PhotonSettings { photons: 20_000, caustic_photons: 20_000, gather_rays: 2, ..PhotonSettings::default() }
}

#[test]
fn instances_render_as_their_geometry_written_out_flat() {
    let instanced = parse(&instanced_text());
    let flat = parse(&flat_text());
    assert_eq!(instanced.instances.len(), 3);
    assert!(instanced.shapes.len() < flat.shapes.len(), "the objects' shapes stay out of the world's");
    let (a, b) = (common::buffers(&instanced, 64, 48), common::buffers(&flat, 64, 48));
    assert_eq!(a.frame.instance_count, 3);
    assert!(a.analytic && b.analytic);
    let (ia, ib) = (common::cpu_render(&a, 2, &photons()), common::cpu_render(&b, 2, &photons()));
    let error = rel_mse(&ia.image, &ib.image);
    let ratio = mean_ratio(&ia.image, &ib.image);
    println!("instanced vs flat (CPU, 64x48, photons): relMSE {error:.3e}, mean ratio {ratio:.5?}");
    // Both scenes trace the same surfaces with the same random numbers: they differ only where
    // rounding in the object-space transform flips a discrete choice (measured 5e-13). A
    // missing instance, a wrong normal, a lost material override or a shadow ray that misses
    // the instances moves relMSE above 1e-2.
    assert!(error < 1e-6, "relMSE {error:.3e}");
    for r in ratio {
        assert!((r - 1.0).abs() < 1e-3, "mean ratio {ratio:?}");
    }
    // The override shows: the third instance's box is blue, not red, in both.
    let blue = ia.image.pixels.iter().filter(|p| p[2] > 2.0 * p[0] && p[2] > 0.05).count();
    assert!(blue > 20, "only {blue} blue pixels");
}

/// A CSG lens in the world: its leaf primitives sit after every other primitive, and their hit
/// names must stay world names when instances number the others' hits above them.
const LENS: &str = "[[shapes]]\ntype = \"csg\"\noperation = \"intersection\"\nmaterial = \"glass\"\nchildren = [\n  { type = \"sphere\", center = [0, 0.8, 1.2], radius = 0.8 },\n  { type = \"sphere\", center = [0, 0.8, 2.2], radius = 0.8 },\n]\n";

#[test]
fn csg_objects_and_instances_render_together_as_flat() {
    let instanced = parse(&format!("{}{LENS}", instanced_text()));
    let flat = parse(&format!("{}{LENS}", flat_text()));
    let (a, b) = (common::buffers(&instanced, 64, 48), common::buffers(&flat, 64, 48));
    assert!(a.frame.csg_first < a.frame.primitive_count, "the lens has leaves");
    let (ia, ib) = (common::cpu_render(&a, 2, &photons()), common::cpu_render(&b, 2, &photons()));
    let error = rel_mse(&ia.image, &ib.image);
    println!("instanced vs flat with a CSG lens (CPU): relMSE {error:.3e}");
    assert!(error < 1e-6, "relMSE {error:.3e}");
    let gpu = common::gpu_render(&common::gpu(), &a, 2, &photons());
    let e = rel_mse(&gpu.image, &ia.image);
    assert!(e < 1e-6, "gpu against cpu: relMSE {e:.3e}");
}

/// A CSG object for objects: a box minus a ball, with a torus ring around it (merged) and a
/// superellipsoid knob on top; `extra` goes into every child table (the flat copy's transform).
fn cut_thing(extra: &str) -> String {
    let children = [
        "type = \"box\", min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5]",
        "type = \"sphere\", center = [0.3, 0.8, 0.4], radius = 0.45, material = \"red\"",
        "type = \"torus\", center = [0, 0.5, 0], major_radius = 0.6, minor_radius = 0.12, material = \"blue\"",
        "type = \"superellipsoid\", exponents = [0.4, 0.6], transform = { scale = 0.25, translate = [0, 1.1, 0] }",
    ];
    let child = |c: &str| {
        // A child's own transform is applied first, then the placement's.
        match (c.find("transform = { scale = 0.25, translate = [0, 1.1, 0] }"), extra.is_empty()) {
            (Some(_), false) => format!("{{ {c} }}"),
            _ => format!("{{ {c}{extra} }}"),
        }
    };
    format!(
        "type = \"csg\"\noperation = \"merge\"\nmaterial = \"white\"\nchildren = [\n  {{ type = \"csg\", operation = \"difference\", children = [{}, {}] }},\n  {},\n  {},\n]\n",
        child(children[0]),
        child(children[1]),
        child(children[2]),
        child(children[3])
    )
}

#[test]
fn instanced_csg_objects_render_as_their_flat_copies() {
    // Placements that a child's `transform` can repeat in the world (no CSG takes a transform).
    let placements =
        ["{ translate = [-1.3, 0, 0] }", "{ scale = 0.9, rotate = [0, 40, 0], translate = [1.2, 0, -0.4] }"];
    let mut instanced = format!("{HEADER}[[objects.cut.shapes]]\n{}", cut_thing(""));
    let mut flat = HEADER.to_string();
    for (k, t) in placements.iter().enumerate() {
        writeln!(instanced, "[[instances]]\nobject = \"cut\"\ntransform = {t}").unwrap();
        if k == 1 {
            writeln!(instanced, "material = \"blue\"").unwrap();
        }
        let mut shape = cut_thing(&format!(", transform = {t}"));
        if k == 1 {
            // The override replaces every leaf's material.
            shape = shape.replace("\"red\"", "\"blue\"").replace("\"white\"", "\"blue\"");
        }
        writeln!(flat, "[[shapes]]\n{shape}").unwrap();
    }
    // The superellipsoid knob has its own transform: in the flat copy it is composed by hand.
    flat = flat.replace(
        "{ type = \"superellipsoid\", exponents = [0.4, 0.6], transform = { scale = 0.25, translate = [0, 1.1, 0] } }",
        "KNOB",
    );
    let knobs = [
        "{ type = \"superellipsoid\", exponents = [0.4, 0.6], transform = { scale = 0.25, translate = [-1.3, 1.1, 0] } }",
        "{ type = \"superellipsoid\", exponents = [0.4, 0.6], transform = { scale = 0.225, rotate = [0, 40, 0], translate = [1.2, 0.99, -0.4] } }",
    ];
    for knob in knobs {
        flat = flat.replacen("KNOB", knob, 1);
    }
    let (instanced, flat) = (parse(&instanced), parse(&flat));
    assert_eq!(instanced.instances.len(), 2);
    assert!(instanced.shapes.len() < flat.shapes.len(), "the CSG object lives in the object");
    let (a, b) = (common::buffers(&instanced, 64, 48), common::buffers(&flat, 64, 48));
    assert!(a.implicit && b.implicit, "the CSG's torus needs the implicit kernels");
    let (ia, ib) = (common::cpu_render(&a, 2, &photons()), common::cpu_render(&b, 2, &photons()));
    let error = rel_mse(&ia.image, &ib.image);
    let ratio = mean_ratio(&ia.image, &ib.image);
    println!("instanced vs flat CSG objects (CPU, 64x48, photons): relMSE {error:.3e}, mean ratio {ratio:.5?}");
    assert!(error < 1e-6, "relMSE {error:.3e}");
    for r in ratio {
        assert!((r - 1.0).abs() < 1e-3, "mean ratio {ratio:?}");
    }
    let red = ia.image.pixels.iter().filter(|p| p[0] > 2.0 * p[2] && p[0] > 2.0 * p[1] && p[0] > 0.02).count();
    assert!(red > 10, "only {red} red pixels: the subtracted ball's surface is not seen");
    let gpu = common::gpu_render(&common::gpu(), &a, 2, &photons());
    let e = rel_mse(&gpu.image, &ia.image);
    println!("instanced CSG objects: GPU vs CPU relMSE {e:.3e}");
    assert!(e < 1e-6, "gpu against cpu: relMSE {e:.3e}");
}

#[test]
fn gpu_matches_cpu_on_instances() {
    let scene = parse(&instanced_text());
    let buffers = common::buffers(&scene, 48, 36);
    let ctx = common::gpu();
    let gpu = common::gpu_render(&ctx, &buffers, 1, &photons());
    let cpu = common::cpu_render(&buffers, 1, &photons());
    let error = rel_mse(&gpu.image, &cpu.image);
    let ratio = mean_ratio(&gpu.image, &cpu.image);
    println!("instances 48x36: GPU vs CPU relMSE {error:.3e}, mean ratio {ratio:.6?}");
    // As in tests/shapes.rs: the twins differ only where rounding flips a discrete choice.
    assert!(error < 1e-6, "relMSE {error:.3e}");
    for r in ratio {
        assert!((r - 1.0).abs() < 1e-3, "mean ratio {ratio:?}");
    }
}

/// A 100 x 50 grid of quads (10 000 triangles) as an OBJ file, wavy so its BVH is a real one.
fn grid_obj(path: &Path) {
    let (nx, nz) = (100, 50);
    let mut text = String::new();
    for j in 0..=nz {
        for i in 0..=nx {
            let (x, z) = (i as f32 / nx as f32, j as f32 / nz as f32 * 0.5);
            let y = 0.05 * (x * 25.0).sin() * (z * 31.0).cos();
            writeln!(text, "v {x} {y} {z}").unwrap();
        }
    }
    let v = |i: usize, j: usize| j * (nx + 1) + i + 1;
    for j in 0..nz {
        for i in 0..nx {
            writeln!(text, "f {} {} {}", v(i, j), v(i, j + 1), v(i + 1, j + 1)).unwrap();
            writeln!(text, "f {} {} {}", v(i, j), v(i + 1, j + 1), v(i + 1, j)).unwrap();
        }
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn ten_thousand_instances_of_a_ten_thousand_triangle_mesh_take_the_memory_of_one() {
    let dir = tempfile::tempdir().unwrap();
    grid_obj(&dir.path().join("grid.obj"));
    let text = r#"
[camera]
position = [50, 40, -30]
look_at = [50, 0, 40]
fov = 60
resolution = [32, 24]
[materials.white]
type = "diffuse"
[[lights]]
type = "distant"
direction = [0.3, -1, 0.4]
irradiance = 3
[[objects.field.shapes]]
type = "mesh"
file = "grid.obj"
material = "white"
[[instances]]
object = "field"
transform = { rotate = [0, 10, 0] }
count = [100, 1, 100]
spacing = [1.1, 0, 0.8]
"#;
    let path = dir.path().join("field.toml");
    std::fs::write(&path, text).unwrap();
    let scene = photonix::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let triangles = scene.objects[0].shapes.len();
    assert_eq!(triangles, 10_000);
    assert_eq!(scene.instances.len(), 10_000);
    let start = std::time::Instant::now();
    let buffers = common::buffers(&scene, 32, 24);
    let build = start.elapsed();
    let bytes = |n: usize, size: usize| (n * size) as u64;
    let nodes = bytes(buffers.nodes.len(), size_of::<BvhNode>());
    let primitives = bytes(buffers.primitives.len(), size_of::<Primitive>());
    let shape_data = bytes(buffers.shape_data.len(), 4);
    let used = nodes + primitives + shape_data;
    // Written out flat: every instance's primitives, and a BVH of at least one node per
    // primitive (a leaf holds at most four, and there are 2 leaves - 1 inner nodes).
    let flat_primitives = 10_000u64 * triangles as u64;
    let flattened = flat_primitives * size_of::<Primitive>() as u64 + flat_primitives / 2 * size_of::<BvhNode>() as u64;
    println!(
        "10 000 instances x 10 000 triangles (10^8 triangles placed): nodes {nodes} B, primitives {primitives} B, \
         shape data (instance records) {shape_data} B, total {:.1} MiB; flattened at least {:.1} GiB (ratio 1/{:.0}); \
         prepared in {build:.2?}",
        used as f64 / (1u64 << 20) as f64,
        flattened as f64 / (1u64 << 30) as f64,
        flattened as f64 / used as f64
    );
    assert!(used * 100 < flattened, "{used} B is not below 1/100 of the flattened {flattened} B");
    // The unique geometry once: the object's primitives, plus per instance a record and about two nodes.
    assert!(buffers.primitives.len() <= triangles + 2, "{} primitives", buffers.primitives.len());
    // A tiny render on the CPU twin sees the field.
    let image = common::cpu_image(&buffers, 1);
    let lit = image.pixels.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > image.pixels.len() / 4, "only {lit} of {} pixels see the field", image.pixels.len());
}

fn error_of(body: &str) -> String {
    let text = format!("{HEADER}{body}");
    match parse_scene(&text, Path::new("bad.toml")) {
        Ok(_) => panic!("accepted:\n{body}"),
        Err(e) => e.to_string(),
    }
}

/// The 1-based line of the first line of `body` that contains `needle`, in HEADER + body.
fn line_of(body: &str, needle: &str) -> usize {
    let text = format!("{HEADER}{body}");
    text.lines().position(|l| l.contains(needle)).expect("needle in text") + 1
}

#[test]
fn bad_objects_and_placements_are_refused_with_file_line_and_field() {
    let thing = "[[objects.thing.shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\ncenter = [0, 0, 0]\nradius = 1\n";
    let cases: Vec<(String, &str, &[&str])> = vec![
        (format!("{thing}[[instances]]\nobject = \"thnig\"\n"), "object = \"thnig\"", &["unknown object", "did you mean \"thing\""]),
        (
            "[[objects.a.instances]]\nobject = \"b\"\n[[objects.b.shapes]]\ntype = \"sphere\"\nmaterial = \"white\"\nradius = 1\ncenter = [0, 0, 0]\n[[objects.b.instances]]\nobject = \"a\"\n[[instances]]\nobject = \"a\"\n".to_string(),
            "object = \"a\"",
            &["cannot contain itself", "\"a\" places \"b\" places \"a\""],
        ),
        (format!("{thing}[[instances]]\nobject = \"thing\"\ntransform = {{ scale = [1, 0, 1] }}\n"), "transform =", &["transform.scale", "0 along an axis"]),
        (format!("{thing}[[instances]]\nobject = \"thing\"\ntransform = {{ translate = [0, nan, 0] }}\n"), "transform =", &["transform.translate", "finite"]),
        (format!("{thing}[[instances]]\nobject = \"thing\"\ncount = [10, 1]\nspacing = 1\n"), "count =", &["`count` has 2 numbers"]),
        (format!("{thing}[[instances]]\nobject = \"thing\"\ncount = [10, 1, 10]\n"), "[[instances]]", &["needs `spacing`"]),
        (format!("{thing}[[instances]]\nobject = \"thing\"\ncount = [2000, 1, 2000]\nspacing = 1\n"), "count =", &["at most 1048576"]),
        (
            "[materials.lamp]\ntype = \"diffuse\"\nemission = 5\n[[objects.glow.shapes]]\ntype = \"sphere\"\nmaterial = \"lamp\"\ncenter = [0, 0, 0]\nradius = 1\n[[instances]]\nobject = \"glow\"\n".to_string(),
            "[[objects.glow.shapes]]",
            &["emits light", "cannot be lights"],
        ),
        (
            "[[objects.floor.shapes]]\ntype = \"plane\"\nmaterial = \"white\"\nnormal = [0, 1, 0]\noffset = 0\n[[instances]]\nobject = \"floor\"\n".to_string(),
            "[[objects.floor.shapes]]",
            &["infinite plane"],
        ),
        ("[[instances]]\ntransform = { translate = [0, 1, 0] }\n".to_string(), "[[instances]]", &["missing field `object`"]),
        (
            "[materials.veil]\ntype = \"diffuse\"\nopacity = 0.5\n[[objects.cut.shapes]]\ntype = \"csg\"\noperation = \"difference\"\nmaterial = \"white\"\nchildren = [{ type = \"box\", min = [0, 0, 0], max = [1, 1, 1] }, { type = \"sphere\", center = [1, 1, 1], radius = 0.5 }]\n[[instances]]\nobject = \"cut\"\nmaterial = \"veil\"\n".to_string(),
            "material = \"veil\"",
            &["opacity below 1", "object \"cut\" holds a CSG object", "opaque material"],
        ),
        (format!("{thing}[[objects.thing.shapes]]\ntype = \"sphere\"\nmaterial = \"whte\"\ncenter = [0, 0, 0]\nradius = 1\n[[instances]]\nobject = \"thing\"\n"), "material = \"whte\"", &["[objects.thing] shape 1", "unknown material"]),
    ];
    for (body, at, expected) in cases {
        let message = error_of(&body);
        let line = line_of(&body, at);
        assert!(message.starts_with(&format!("bad.toml:{line}")), "wanted line {line} ({at}): {message}");
        for e in expected {
            assert!(message.contains(e), "wanted {e:?} in: {message}");
        }
    }
}
