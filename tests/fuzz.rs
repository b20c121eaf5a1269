//! Fuzz targets, run as ordinary tests (there is no nightly toolchain for cargo-fuzz here): the
//! scene parser (`parse_scene`), the OBJ importer (a `type = "mesh"` shape behind `load_scene`)
//! and the other model importers (PLY ASCII and binary, glTF `.gltf` and `.glb`, 3DS, IFS and
//! Bezier patches, fed mutations of real exporters' files), the editor's HTTP and WebSocket
//! API (`photonix serve`: requests and page messages against one running server), the POV-Ray
//! front-end (`fuzz_pov_front_end`: include graphs with cycles and tail includes, deep nesting,
//! values that double, devices and FIFOs named as includes and height fields), whole glTF
//! scenes (`fuzz_gltf_scene`: buffer and image URIs naming devices, FIFOs, huge sparse files and
//! data URIs, wrong sizes and accessors, cameras, lights and factors out of range) and the
//! Mitsuba front-end (`scene.xml`: XML from Mitsuba's plugin vocabulary, and mutations of it).
//! Inputs come from a generator that follows each format's grammar and from
//! byte-level mutations of the shipped files, drawn from the crate's counter-based hash, so a
//! (seed, case) pair replays exactly. Every case must give a scene that keeps the documented
//! invariants (finite geometry, a usable camera, finite light power) or an error that names the
//! file; a panic, or an error that names no file, fails.
//!
//! CI runs a few hundred cases per target. A long run (see `ci/fuzz`):
//!
//! ```sh
//! PHOTONIX_FUZZ_CASES=1000000000 PHOTONIX_FUZZ_SECONDS=3600 PHOTONIX_FUZZ_SEED=1 \
//!   PHOTONIX_FUZZ_FINDINGS=target/fuzz-findings \
//!   cargo test --release --test fuzz -- --exact fuzz_scene_parser --nocapture
//! ```
//!
//! With `PHOTONIX_FUZZ_FINDINGS` set, each new kind of failure is written to that folder and the
//! run goes on. Every input that once failed is kept in `tests/fuzz_corpus/{scene,obj,model,mitsuba}/`
//! (a model input's extension names its format), and
//! `fuzz_corpus_replays_cleanly` replays them all.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Once;
use std::time::{Duration, Instant};

use photonix::cpu::rng::pcg4d;
use photonix::render::memory;
use photonix::render::photons::check_radii;
use photonix::render::{prepare, FrameSettings};
use photonix::scene::{load_scene, parse_scene, Geometry, LightKind, Scene};

mod editor_support;

// Random choices

/// A stream of random numbers for case `case` of run `seed`.
struct Rng {
    case: u32,
    seed: u32,
    counter: u32,
}

impl Rng {
    fn new(seed: u32, case: u32) -> Rng {
        Rng { case, seed, counter: 0 }
    }

    fn next(&mut self) -> u32 {
        self.counter += 1;
        pcg4d([self.case, self.counter, self.seed, 0xF022])[0]
    }

    /// A whole number in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        ((self.next() as u64 * n as u64) >> 32) as usize
    }

    fn chance(&mut self, percent: usize) -> bool {
        self.below(100) < percent
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

// The scene grammar

fn words(list: &str) -> Vec<&str> {
    list.split_whitespace().collect()
}

/// Numbers a scene file may hold, sensible ones most of the time.
fn number(r: &mut Rng) -> String {
    // Separated by spaces; `words` splits them.
    const EXTREME: &str =
        "0 -0.0 1e30 -1e30 1e300 -1e300 1e-300 3.4e38 3.5e38 1.7976931348623157e308 5e-324 1e-45 nan +nan \
        -nan inf -inf +inf 9223372036854775807 -9223372036854775808 4294967295 4294967296 -4294967296 \
        2147483648 65536 65537 1000000000 1000000001 16777217 1e9 1.0000001e9 1e-9 1e-10 0.01 179.99 180 \
        0x7fffffff 0o777 0b1 1_000 1e --1 1. .5 0.000_1";
    match r.below(10) {
        0..=5 => {
            // A value of a typical scene: a few digits, either sign.
            let v = (r.next() as f64 / u32::MAX as f64 - 0.3) * 10f64.powi(r.below(4) as i32);
            if r.chance(40) {
                format!("{}", v.round() as i64)
            } else {
                format!("{v:.3}")
            }
        }
        6..=8 => r.pick(&words(EXTREME)).to_string(),
        _ => {
            // Any magnitude.
            let mantissa = r.next() as f64 / u32::MAX as f64 * 2.0 - 1.0;
            format!("{:e}", mantissa * 10f64.powi(r.below(640) as i32 - 320))
        }
    }
}

fn integer(r: &mut Rng) -> String {
    // Separated by spaces; `words` splits them.
    const INTERESTING: &str =
        "0 1 2 -1 3 4 16 64 1024 1025 4096 4097 65535 65536 65537 1000000 1000001 200000 2147483647 \
        2147483648 4294967295 4294967296 9223372036854775807 -9223372036854775808 1000000000 1000000001 \
        16384";
    if r.chance(50) {
        format!("{}", r.below(20))
    } else {
        r.pick(&words(INTERESTING)).to_string()
    }
}

fn vec3(r: &mut Rng) -> String {
    match r.below(20) {
        0 => number(r),
        1 => format!("[{}, {}]", number(r), number(r)),
        2 => format!("[{}, {}, {}, {}]", number(r), number(r), number(r), number(r)),
        3 => "[]".to_string(),
        4 => format!("[[{}], {}, {}]", number(r), number(r), number(r)),
        _ => format!("[{}, {}, {}]", number(r), number(r), number(r)),
    }
}

/// A point that keeps most shapes small and in front of the camera.
fn point(r: &mut Rng) -> String {
    if r.chance(80) {
        let mut c = || format!("{:.2}", r.next() as f64 / u32::MAX as f64 * 4.0 - 2.0);
        format!("[{}, {}, {}]", c(), c(), c())
    } else {
        vec3(r)
    }
}

fn name(r: &mut Rng) -> String {
    #[rustfmt::skip]
    const NAMES: &[&str] = &[
        "white", "glass", "mirror", "lamp", "checks", "light 0", "light 1", "", " ", "white ", "Wall",
        "\\u001b[31mred\\u001b[0m", "tab\\there", "new\\nline", "nul\\u0000", "\\u0007bell", "ünïcödé",
        "\\uD7FF", "quote\\\"d", "back\\\\slash",
    ];
    match r.below(20) {
        0 => "k".repeat(r.below(3000)),
        _ => r.pick(NAMES).to_string(),
    }
}

fn file(r: &mut Rng) -> String {
    // Separated by spaces; `words` splits them.
    const FILES: &str = "mesh.obj meshes/icosahedron.obj missing.obj /dev/zero /dev/null . .. /  mesh.obj\\u0000x \
        scene.toml /proc/self/status mesh.OBJ ./mesh.obj meshes/";
    if r.chance(5) {
        return String::new();
    }
    r.pick(&words(FILES)).to_string()
}

/// A value of any type, for a field that expects another one.
fn wrong_value(r: &mut Rng) -> String {
    match r.below(9) {
        0 => format!("\"{}\"", name(r)),
        1 => "true".to_string(),
        2 => "{}".to_string(),
        3 => format!("{{ texture = \"{}\" }}", name(r)),
        4 => format!("{{ texture = \"checks\", scale = {} }}", vec3(r)),
        5 => "1979-05-27T07:32:00Z".to_string(),
        6 => format!("[{}]", "[".repeat(r.below(5)) + &"]".repeat(r.below(5))),
        7 => format!("'''{}'''", name(r)),
        _ => format!("[\"a\", {}]", number(r)),
    }
}

/// `field = value` where the value is of the field's kind most of the time.
fn field(r: &mut Rng, out: &mut String, key: &str, value: impl FnOnce(&mut Rng) -> String) {
    if r.chance(92) {
        let v = if r.chance(94) { value(r) } else { wrong_value(r) };
        out.push_str(&format!("{key} = {v}\n"));
    }
}

fn param(r: &mut Rng) -> String {
    match r.below(10) {
        0 => format!("{{ texture = \"{}\" }}", if r.chance(70) { "checks".to_string() } else { name(r) }),
        1 => format!("{{ texture = \"checks\", scale = {} }}", if r.chance(50) { number(r) } else { vec3(r) }),
        2..=4 => format!("{:.2}", r.next() as f64 / u32::MAX as f64),
        _ => vec3(r),
    }
}

fn transform(r: &mut Rng) -> String {
    let mut parts = Vec::new();
    if r.chance(50) {
        parts.push(format!("scale = {}", if r.chance(50) { number(r) } else { vec3(r) }));
    }
    if r.chance(50) {
        parts.push(format!("rotate = {}", vec3(r)));
    }
    if r.chance(50) {
        parts.push(format!("translate = {}", vec3(r)));
    }
    if r.chance(5) {
        parts.push(format!("{} = 1", name(r).replace(['"', '\\'], "")));
    }
    format!("{{ {} }}", parts.join(", "))
}

/// A whole scene file from the grammar of docs/scene-format.md, with wrong turns.
fn grammar_scene(r: &mut Rng) -> String {
    let mut s = String::new();
    if r.chance(95) {
        s.push_str("[camera]\n");
        // Cameras that are nearly degenerate: look_at next to position, up nearly along the view.
        const NEAR: &[(&str, &str)] = &[
            ("[0, 1, 5]", "[0, 1, 5.0000001]"),
            ("[0, 1, 5]", "[0, 1, 4.9999999]"),
            ("[1e-30, 0, 0]", "[0, 0, 0]"),
            ("[3e38, 0, 0]", "[-3e38, 0, 0]"),
            ("[1e9, 1e9, 1e9]", "[-1e9, -1e9, -1e9]"),
            ("[0, 0, 5]", "[0, 0, -5]"),
            ("[0, 5, 0]", "[0, 0, 0]"),
        ];
        let (position, look_at) = if r.chance(15) { *r.pick(NEAR) } else { ("[0, 1, 5]", "[0, 0.5, 0]") };
        field(r, &mut s, "position", |r| if r.chance(80) { position.into() } else { vec3(r) });
        field(r, &mut s, "look_at", |r| if r.chance(80) { look_at.into() } else { vec3(r) });
        if r.chance(40) {
            const UPS: &[&str] =
                &["[0, 1e-30, 0]", "[1e-20, 0, 0]", "[0, 0, 1]", "[0, 1e-7, 1]", "[0, 0, -1e30]", "[1e38, 1e38, 0]"];
            field(r, &mut s, "up", |r| if r.chance(50) { r.pick(UPS).to_string() } else { vec3(r) });
        }
        field(r, &mut s, "fov", |r| if r.chance(70) { "45".into() } else { number(r) });
        if r.chance(60) {
            field(r, &mut s, "resolution", |r| match r.below(6) {
                0 => format!("[{}]", integer(r)),
                1 => format!("[{}, {}, {}]", integer(r), integer(r), integer(r)),
                _ => format!("[{}, {}]", integer(r), integer(r)),
            });
        }
    }
    if r.chance(50) {
        s.push_str("[render]\n");
        for key in ["spp", "passes", "max_depth", "seed"] {
            if r.chance(60) {
                field(r, &mut s, key, integer);
            }
        }
    }
    if r.chance(50) {
        s.push_str("[photons]\n");
        for key in ["count", "caustic_count", "gather_rays", "max_depth"] {
            if r.chance(50) {
                field(r, &mut s, key, integer);
            }
        }
        for key in ["radius", "caustic_radius", "alpha"] {
            if r.chance(40) {
                field(r, &mut s, key, number);
            }
        }
        if r.chance(30) {
            field(r, &mut s, "enabled", |r| if r.chance(50) { "true".into() } else { "false".into() });
        }
    }
    if r.chance(30) {
        s.push_str("[textures.checks]\n");
        field(r, &mut s, "type", |r| format!("\"{}\"", r.pick(&["checker", "constant", "image", "checkers"])));
        field(r, &mut s, "colors", |r| format!("[{}, {}]", vec3(r), vec3(r)));
        if r.chance(30) {
            field(r, &mut s, "color", vec3);
        }
        if r.chance(40) {
            field(r, &mut s, "space", |r| format!("\"{}\"", r.pick(&["uv", "world", "object"])));
        }
        if r.chance(30) {
            field(r, &mut s, "transform", transform);
        }
    }
    let materials = ["white", "glass", "mirror", "lamp"];
    for m in materials {
        if !r.chance(60) {
            continue;
        }
        s.push_str(&format!("[materials.{}]\n", if r.chance(95) { m.to_string() } else { format!("\"{}\"", name(r)) }));
        let kind = *r.pick(&["diffuse", "dielectric", "mirror", "metal"]);
        field(r, &mut s, "type", |_| format!("\"{kind}\""));
        match kind {
            "diffuse" => field(r, &mut s, "reflectance", param),
            "mirror" => field(r, &mut s, "tint", param),
            _ => field(r, &mut s, "ior", number),
        }
        if r.chance(40) {
            field(r, &mut s, "emission", param);
        }
        if r.chance(20) {
            field(r, &mut s, "opacity", param);
        }
    }
    for _ in 0..r.below(6) {
        s.push_str("[[shapes]]\n");
        if r.chance(20) {
            field(r, &mut s, "name", |r| format!("\"{}\"", name(r)));
        }
        let kind = *r.pick(&["quad", "triangle", "sphere", "box", "mesh", "cylinder"]);
        field(r, &mut s, "type", |_| format!("\"{kind}\""));
        field(r, &mut s, "material", |r| {
            format!("\"{}\"", if r.chance(90) { r.pick(&materials).to_string() } else { name(r) })
        });
        match kind {
            "quad" | "triangle" => {
                let n = if r.chance(90) {
                    if kind == "quad" {
                        4
                    } else {
                        3
                    }
                } else {
                    r.below(6)
                };
                field(r, &mut s, "vertices", |r| {
                    format!("[{}]", (0..n).map(|_| point(r)).collect::<Vec<_>>().join(", "))
                });
                // Vertex normals (triangles take them; a quad refuses them), wrong counts and
                // zero lengths included.
                if r.chance(30) {
                    let m = if r.chance(80) { 3 } else { r.below(5) };
                    field(r, &mut s, "normals", |r| {
                        format!("[{}]", (0..m).map(|_| vec3(r)).collect::<Vec<_>>().join(", "))
                    });
                }
            }
            "sphere" => {
                field(r, &mut s, "center", point);
                field(r, &mut s, "radius", |r| if r.chance(60) { "0.5".into() } else { number(r) });
            }
            "box" => {
                field(r, &mut s, "min", |r| if r.chance(60) { "[-1, 0, -1]".into() } else { point(r) });
                field(r, &mut s, "max", |r| if r.chance(60) { "[1, 1, 1]".into() } else { point(r) });
            }
            _ => field(r, &mut s, "file", |r| format!("\"{}\"", file(r))),
        }
        if r.chance(35) {
            if r.chance(50) {
                field(r, &mut s, "transform", transform);
            } else {
                s.push_str("[shapes.transform]\n");
                let t = transform(r);
                s.push_str(&t[1..t.len() - 1].replace(", ", "\n"));
                s.push('\n');
            }
        }
    }
    for _ in 0..r.below(3) {
        s.push_str("[[lights]]\n");
        if r.chance(20) {
            field(r, &mut s, "name", |r| format!("\"{}\"", name(r)));
        }
        if r.chance(50) {
            field(r, &mut s, "type", |_| "\"point\"".into());
            field(r, &mut s, "position", point);
            field(r, &mut s, "intensity", |r| if r.chance(60) { "[5, 5, 5]".into() } else { vec3(r) });
        } else {
            field(r, &mut s, "type", |_| "\"area\"".into());
            let shape = *r.pick(&["quad", "sphere", "disk"]);
            field(r, &mut s, "shape", |_| format!("\"{shape}\""));
            if shape == "quad" {
                field(r, &mut s, "vertices", |r| {
                    if r.chance(70) {
                        "[[-0.5, 2, -0.5], [0.5, 2, -0.5], [0.5, 2, 0.5], [-0.5, 2, 0.5]]".into()
                    } else {
                        format!("[{}]", (0..4).map(|_| point(r)).collect::<Vec<_>>().join(", "))
                    }
                });
            } else {
                field(r, &mut s, "center", point);
                field(r, &mut s, "radius", |r| if r.chance(60) { "0.25".into() } else { number(r) });
            }
            field(r, &mut s, "radiance", |r| if r.chance(60) { "[5, 5, 5]".into() } else { vec3(r) });
            if r.chance(25) {
                field(r, &mut s, "transform", transform);
            }
        }
    }
    // Wrong turns that belong to no table.
    match r.below(30) {
        0 => s.push_str(&format!("{} = 1\n", "k".repeat(r.below(2_000_000)))),
        1 => s.push_str(&format!("x = {}1{}\n", "[".repeat(r.below(20_000)), "]".repeat(r.below(20_000)))),
        2 => s.push_str(&format!("x = {}\n", "{ a = ".repeat(r.below(5000)))),
        3 => s.push_str("[camera]\nfov = 40\n"),
        4 => s.push_str(&format!("[{}]\n", name(r))),
        5 => s.push_str(&format!("\"{}\" = 1\n", name(r))),
        _ => {}
    }
    s
}

// Byte-level mutations

/// Bytes that mean something in TOML or OBJ, for insertions.
#[rustfmt::skip]
const TOKENS: &[&[u8]] = &[
    b"[", b"]", b"[[", b"]]", b"\"", b"'", b"=", b"\n", b"\r\n", b".", b"-", b"e", b"0", b"9", b",",
    b"{", b"}", b"#", b"\\", b"\xff", b"\x00", b"\x1b", b" ", b"\t", b"nan", b"inf", b"1e308",
    b"-1e308", b"4294967296", b"9999999999999999999999", b"/", b"//", b"f ", b"v ", b"vt ", b"\\\n",
    b"-1", b"0", b"1e-45", b"\xc3\x28",
];

/// Mutated inputs stop growing here: repeating a long line of a repeated line grows without
/// bound (a 1.4 GB OBJ once), and file sizes have their own tests.
const MAX_INPUT_BYTES: usize = 2 << 20;

fn mutate(r: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..1 + r.below(8) {
        if b.len() > MAX_INPUT_BYTES {
            b.truncate(MAX_INPUT_BYTES);
            break;
        }
        let len = b.len();
        match r.below(9) {
            0 if len > 0 => {
                let i = r.below(len);
                b[i] ^= 1 << r.below(8);
            }
            1 => {
                let i = r.below(len + 1);
                let token = r.pick(TOKENS);
                b.splice(i..i, token.iter().copied());
            }
            2 if len > 0 => {
                let i = r.below(len);
                let n = (1 + r.below(16)).min(len - i);
                b.drain(i..i + n);
            }
            3 if len > 0 => {
                // Repeat a line, many times now and then.
                let lines: Vec<&[u8]> = b.split_inclusive(|&c| c == b'\n').collect();
                let line = lines[r.below(lines.len())].to_vec();
                let times = if r.chance(10) { 1 + r.below(5000) } else { 1 };
                // A long line (a glTF data URI) repeated thousands of times would take the
                // harness's own memory (6 GB once): the copies stop at the input limit.
                let times = times.min((MAX_INPUT_BYTES / line.len().max(1)).max(1));
                let at = r.below(len + 1);
                let copies: Vec<u8> = line.iter().copied().cycle().take(line.len() * times).collect();
                b.splice(at..at, copies);
            }
            4 if len > 0 => {
                // Replace a number with another, often an extreme one.
                let starts: Vec<usize> =
                    (0..len).filter(|&i| b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_digit())).collect();
                if let Some(&i) = starts.get(r.below(starts.len().max(1))) {
                    let end = (i..len).find(|&j| !(b[j].is_ascii_digit() || b[j] == b'.')).unwrap_or(len);
                    let replacement = number(r).into_bytes();
                    b.splice(i..end, replacement);
                }
            }
            5 if len > 0 => {
                let at = r.below(len);
                b.truncate(at);
            }
            6 if len > 0 => {
                // Swap two lines.
                let mut lines: Vec<Vec<u8>> = b.split_inclusive(|&c| c == b'\n').map(<[u8]>::to_vec).collect();
                let (i, j) = (r.below(lines.len()), r.below(lines.len()));
                lines.swap(i, j);
                b = lines.concat();
            }
            7 if len > 0 => {
                let i = r.below(len);
                b[i] = r.next() as u8;
            }
            _ => {
                let i = r.below(len + 1);
                b.splice(i..i, number(r).into_bytes());
            }
        }
    }
    b
}

// The OBJ grammar

fn obj_number(r: &mut Rng) -> String {
    if r.chance(80) {
        format!("{:.3}", r.next() as f64 / u32::MAX as f64 * 2.0 - 1.0)
    } else {
        number(r)
    }
}

fn obj_index(r: &mut Rng, vertices: usize) -> String {
    match r.below(20) {
        0 => "0".to_string(),
        1 => format!("-{}", 1 + r.below(vertices + 2)),
        2 => r.pick(&["4294967296", "-4294967296", "99999999999999999999", "2147483648", "x", "", "1.5"]).to_string(),
        _ => format!("{}", 1 + r.below(vertices + 1)),
    }
}

/// An OBJ file from the grammar tobj reads, with wrong turns.
fn grammar_obj(r: &mut Rng) -> Vec<u8> {
    let mut s = String::new();
    let vertices = r.below(12);
    let texcoords = r.below(6);
    let eol = if r.chance(10) { "\r\n" } else { "\n" };
    for _ in 0..vertices {
        let n = if r.chance(92) { 3 } else { r.below(6) };
        let coords: Vec<String> = (0..n).map(|_| obj_number(r)).collect();
        s.push_str(&format!("v {}{eol}", coords.join(" ")));
    }
    for _ in 0..texcoords {
        let n = if r.chance(90) { 2 } else { r.below(5) };
        let coords: Vec<String> = (0..n).map(|_| obj_number(r)).collect();
        s.push_str(&format!("vt {}{eol}", coords.join(" ")));
    }
    if r.chance(30) {
        s.push_str(&format!("vn {} {} {}{eol}", obj_number(r), obj_number(r), obj_number(r)));
    }
    for _ in 0..r.below(8) {
        match r.below(12) {
            0 => s.push_str(&format!("o {}{eol}", name(r))),
            1 => s.push_str(&format!("g {}{eol}", name(r))),
            2 => s.push_str(&format!("usemtl {}{eol}mtllib {}.mtl{eol}", name(r), name(r))),
            3 => s.push_str(&format!("s 1{eol}# comment{eol}{eol}")),
            4 => s.push_str(&format!(
                "l {} {}{eol}p {}{eol}",
                obj_index(r, vertices),
                obj_index(r, vertices),
                obj_index(r, vertices)
            )),
            5 => s.push_str(&format!("v {} \\{eol}{} {}{eol}", obj_number(r), obj_number(r), obj_number(r))),
            _ => {
                let n = if r.chance(80) { 3 + r.below(3) } else { r.below(9) };
                let form = r.below(5);
                let refs: Vec<String> = (0..n)
                    .map(|_| {
                        let v = obj_index(r, vertices);
                        match form {
                            0 => format!("{v}/{}", obj_index(r, texcoords)),
                            1 => format!("{v}//1"),
                            2 => format!("{v}/{}/1", obj_index(r, texcoords)),
                            3 if r.chance(10) => format!("{v}/{}/{}/", obj_index(r, texcoords), 1),
                            _ => v,
                        }
                    })
                    .collect();
                s.push_str(&format!("f {}{eol}", refs.join(if r.chance(95) { " " } else { "\t" })));
            }
        }
    }
    s.into_bytes()
}

// Running cases

/// How many cases, for how long, and where findings go: from the environment, see the top.
struct Config {
    /// The first case (`PHOTONIX_FUZZ_START`), to replay one case of a run.
    start: u64,
    cases: u64,
    time: Option<Duration>,
    seed: u32,
    findings: Option<PathBuf>,
}

fn config(default_cases: u64) -> Config {
    let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
    let parse =
        |name: &str, v: String| -> f64 { v.trim().parse().unwrap_or_else(|_| panic!("{name}={v} is not a number")) };
    Config {
        start: var("PHOTONIX_FUZZ_START").map_or(0, |v| parse("PHOTONIX_FUZZ_START", v) as u64),
        cases: var("PHOTONIX_FUZZ_CASES").map_or(default_cases, |v| parse("PHOTONIX_FUZZ_CASES", v) as u64),
        time: var("PHOTONIX_FUZZ_SECONDS").map(|v| Duration::from_secs_f64(parse("PHOTONIX_FUZZ_SECONDS", v))),
        seed: var("PHOTONIX_FUZZ_SEED").map_or(0, |v| parse("PHOTONIX_FUZZ_SEED", v) as u32),
        findings: var("PHOTONIX_FUZZ_FINDINGS").map(PathBuf::from),
    }
}

thread_local! {
    /// The message and place of the last panic on this thread.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// A panic hook that records the panic for `run_case` instead of printing it.
fn quiet_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            let message = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let place = info.location().map(|l| format!("{}:{}", l.file(), l.line())).unwrap_or_default();
            LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("panic at {place}: {message}")));
        }));
    });
}

/// Time this thread has spent on a CPU (Linux's schedstat), else wall time: a case is slow by
/// its own work, not because a build shared the machine (a long run goes at `nice -n 19`).
fn cpu_time() -> Duration {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    let on_cpu = std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|ns| ns.parse::<u64>().ok()));
    match on_cpu {
        Some(ns) => Duration::from_nanos(ns),
        None => START.get_or_init(Instant::now).elapsed(),
    }
}

/// A failure: `key` groups failures of one kind (a panic's place, an error's text without numbers).
struct Failure {
    key: String,
    message: String,
}

/// Runs `check`, turning a panic into a failure.
fn run_case(check: impl FnOnce() -> Result<(), Failure>) -> Result<(), Failure> {
    match catch_unwind(AssertUnwindSafe(check)) {
        Ok(result) => result,
        Err(_) => {
            let message = LAST_PANIC.with(|p| p.borrow_mut().take()).unwrap_or_else(|| "panic".to_string());
            let key = message.split(": ").next().unwrap_or_default().to_string();
            Err(Failure { key, message })
        }
    }
}

/// The invariants a loaded scene keeps, whatever its file held; `None` when all hold.
fn broken_invariant(scene: &Scene) -> Option<String> {
    let c = &scene.camera;
    let finite = |v: glam::Vec3| v.is_finite();
    if !(finite(c.position) && finite(c.look_at) && finite(c.up)) {
        return Some("camera vector not finite".into());
    }
    let forward = (c.look_at - c.position).normalize_or_zero();
    let right = forward.cross(c.up).normalize_or_zero();
    if forward == glam::Vec3::ZERO || right == glam::Vec3::ZERO {
        return Some(format!("degenerate camera accepted: {c:?}"));
    }
    if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) || c.width == 0 || c.height == 0 {
        return Some(format!("camera out of range accepted: {c:?}"));
    }
    for shape in &scene.shapes {
        match &shape.geometry {
            Geometry::Triangle(t) => {
                let area = shape.geometry.area();
                if !(t.vertices.iter().all(|v| v.is_finite()) && area.is_finite() && area > 0.0) {
                    return Some(format!("bad triangle accepted: {t:?}"));
                }
                if t.uv.is_some_and(|uv| !uv.iter().all(|v| v.is_finite())) {
                    return Some(format!("triangle with non-finite uv accepted: {t:?}"));
                }
            }
            Geometry::Sphere(s) => {
                if !(s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0) {
                    return Some(format!("bad sphere accepted: {s:?}"));
                }
            }
            Geometry::Analytic(a) => {
                // The infinite plane is unbounded; every other analytic shape is finite.
                let (lo, hi) = a.bounds();
                let bounded_ok = a.is_unbounded() || (lo.is_finite() && hi.is_finite());
                if !a.world_from_object.is_finite() || !bounded_ok {
                    return Some(format!("bad analytic shape accepted: {a:?}"));
                }
            }
            Geometry::Csg(c) => {
                let (lo, hi) = c.bounds();
                if c.leaves.iter().any(|l| l.is_empty()) || !(lo.is_finite() && hi.is_finite()) {
                    return Some(format!("bad csg accepted: {c:?}"));
                }
            }
        }
    }
    for l in &scene.lights {
        let finite = match l.kind {
            LightKind::Point { position, intensity } => position.is_finite() && intensity.is_finite(),
            LightKind::Spot { position, direction, intensity, cos_inner, cos_outer, exponent } => {
                position.is_finite()
                    && direction.is_finite()
                    && intensity.is_finite()
                    && cos_inner.is_finite()
                    && cos_outer.is_finite()
                    && exponent.is_finite()
            }
            LightKind::Distant { direction, irradiance, half_angle_deg, .. } => {
                direction.is_finite() && irradiance.is_finite() && half_angle_deg.is_finite()
            }
            LightKind::Area { .. } => true,
        };
        if !finite {
            return Some(format!("bad light accepted: {l:?}"));
        }
    }
    None
}

/// Loads a scene the way `check` says, then demands a scene that keeps the invariants and
/// prepares, or an error naming `names` (one of them).
fn check_scene(
    load: impl FnOnce() -> Result<Scene, photonix::scene::SceneError>,
    names: &[&Path],
) -> Result<(), Failure> {
    match load() {
        Ok(scene) => {
            if let Some(broken) = broken_invariant(&scene) {
                let key = broken.split(':').next().unwrap_or_default().to_string();
                return Err(Failure { key, message: broken });
            }
            let settings = FrameSettings { width: 8, height: 8, max_depth: scene.render.max_depth, seed: 0 };
            // The checks a render makes before it starts must not panic either.
            let (w, h) = (scene.camera.width, scene.camera.height);
            let estimate = memory::estimate(w, h, scene.photons.as_ref(), None);
            let _ = memory::check_fits(&estimate, w, h, scene.photons.as_ref(), Some(1 << 30), Some(1 << 30));
            if let Ok(buffers) = prepare(&scene, &settings) {
                if let Some(p) = &scene.photons {
                    let _ = check_radii(&buffers, p);
                }
                let f = &buffers.frame;
                let vectors = [f.camera_position, f.camera_forward, f.camera_right, f.camera_up];
                let frame_ok = vectors.iter().flatten().all(|x| x.is_finite())
                    && f.ray_epsilon.is_finite()
                    && f.total_light_power.is_finite()
                    && buffers.lights.iter().all(|l| {
                        [l.pick_probability, l.cdf, l.photon_probability, l.photon_cdf].iter().all(|x| x.is_finite())
                    });
                if !frame_ok {
                    return Err(Failure {
                        key: "non-finite frame or light".into(),
                        message: format!("prepared scene has non-finite values: {f:?}"),
                    });
                }
            }
            Ok(())
        }
        Err(e) => {
            let message = e.to_string();
            let fail = |what: &str| {
                let key = format!("{what}: {}", error_kind(&message));
                let shown: String = message.chars().take(2000).collect();
                Err(Failure { key, message: format!("{what}: {shown}") })
            };
            if !names.iter().any(|n| message.contains(&n.display().to_string())) {
                return fail("error names no file");
            }
            // Messages stay readable: no raw control characters, no number printed in hundreds
            // of digits, no megabyte of echoed input.
            if message.chars().any(|c| c.is_control() && c != '\n') {
                return fail("raw control character in message");
            }
            let longest_digits = message.split(|c: char| !c.is_ascii_digit()).map(str::len).max().unwrap_or(0);
            if longest_digits > 24 {
                return fail("number printed in full");
            }
            if message.len() > 4096 {
                return fail("message too long");
            }
            Ok(())
        }
    }
}

/// What a message says with the place, the quoted names and the numbers left out, so that one
/// kind of message found in many files counts once.
fn error_kind(message: &str) -> String {
    let after_place = message.split_once(": ").map_or(message, |(_, rest)| rest);
    let mut kind = String::new();
    let mut quoted = false;
    for c in after_place.chars() {
        if c == '"' {
            quoted = !quoted;
        } else if !quoted && !c.is_ascii_digit() {
            kind.push(c);
        }
    }
    kind.chars().take(50).collect()
}

/// A folder with the files scenes refer to: `mesh.obj` and `meshes/icosahedron.obj`.
fn workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let ico = std::fs::read(repo("scenes/meshes/icosahedron.obj")).unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    std::fs::write(dir.path().join("meshes/icosahedron.obj"), &ico).unwrap();
    std::fs::write(dir.path().join("mesh.obj"), &ico).unwrap();
    dir
}

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Scene target: `bytes` parsed as the scene file `dir/scene.toml`.
fn check_scene_input(bytes: &[u8], dir: &Path) -> Result<(), Failure> {
    let path = dir.join("scene.toml");
    match std::str::from_utf8(bytes) {
        Ok(text) => check_scene(|| parse_scene(text, &path), &[&path]),
        Err(_) => {
            std::fs::write(&path, bytes).unwrap();
            check_scene(|| load_scene(&path), &[&path])
        }
    }
}

/// The scene that wraps an OBJ input.
const OBJ_SCENE: &str = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n\
    [materials.white]\ntype = \"diffuse\"\n\
    [[shapes]]\ntype = \"mesh\"\nmaterial = \"white\"\nfile = \"input.obj\"\n\
    [[lights]]\ntype = \"point\"\nposition = [0, 5, 0]\nintensity = 1\n";

/// OBJ target: `bytes` as the mesh file of a scene.
fn check_obj_input(bytes: &[u8], dir: &Path) -> Result<(), Failure> {
    let (scene, obj) = (dir.join("obj-scene.toml"), dir.join("input.obj"));
    std::fs::write(&scene, OBJ_SCENE).unwrap();
    std::fs::write(&obj, bytes).unwrap();
    check_scene(|| load_scene(&scene), &[&scene, &obj])
}

// The Mitsuba grammar

/// A value of a Mitsuba property: numbers, colours, names, parameters, nonsense.
fn mitsuba_value(r: &mut Rng) -> String {
    let s = match r.below(12) {
        0..=3 => number(r),
        4..=5 => format!("{}, {}, {}", number(r), number(r), number(r)),
        6 => r.pick(&words("true false ggx beckmann none Au Cu bk7 water air x y diagonal smaller repeat mirror clamp nearest bilinear")).to_string(),
        7 => file(r).replace(".obj", if r.chance(50) { ".obj" } else { ".png" }),
        8 => format!("${}", r.pick(&words("a b missing r"))),
        9 => format!("400:{}, 700:{}", number(r), number(r)),
        10 => "#ff8000".into(),
        _ => name(r),
    };
    s.replace(['"', '<', '&'], "")
}

/// One property element.
fn mitsuba_property(r: &mut Rng) -> String {
    #[rustfmt::skip]
    const NAMES: &str = "reflectance diffuse_reflectance diffuseReflectance specular_reflectance eta k alpha alpha_u \
        alpha_v distribution material int_ior intIOR ext_ior nonlinear opacity weight weights radiance intensity \
        irradiance scale filename radius center p0 p1 fov fov_axis width height sample_count max_depth cutoff_angle \
        beam_width direction position face_normals flip_tex_coords raw wrap_mode filter_type uscale vscale color0 \
        color1 sigma_a sigmaS sigma_t albedo g turbidity sun_direction aperture_radius focus_distance \
        focal_length channel unknown_thing";
    let tag = *r.pick(&words("float integer boolean string rgb srgb spectrum point vector"));
    let key = *r.pick(&words(NAMES));
    if tag == "point" || tag == "vector" {
        return format!(
            "<{tag} name=\"{key}\" x=\"{}\" y=\"{}\" z=\"{}\"/>",
            mitsuba_value(r),
            mitsuba_value(r),
            mitsuba_value(r)
        );
    }
    format!("<{tag} name=\"{key}\" value=\"{}\"/>", mitsuba_value(r))
}

/// A `<transform>` of a few operations.
fn mitsuba_transform(r: &mut Rng, name: &str) -> String {
    let mut s = format!("<transform name=\"{name}\">");
    for _ in 0..r.below(4) {
        s.push_str(&match r.below(6) {
            0 => format!("<translate x=\"{}\" y=\"{}\"/>", mitsuba_value(r), mitsuba_value(r)),
            1 => format!("<rotate y=\"{}\" angle=\"{}\"/>", mitsuba_value(r), mitsuba_value(r)),
            2 => format!("<scale value=\"{}\"/>", mitsuba_value(r)),
            3 => format!("<lookat origin=\"{}\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>", mitsuba_value(r)),
            4 => {
                let n: Vec<String> = (0..if r.chance(80) { 16 } else { r.below(20) }).map(|_| number(r)).collect();
                format!("<matrix value=\"{}\"/>", n.join(" "))
            }
            _ => "<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\"/>".into(),
        });
    }
    s.push_str("</transform>");
    s
}

/// A plugin of `tag` with properties and, to `depth`, nested plugins.
fn mitsuba_plugin(r: &mut Rng, tag: &str, depth: usize) -> String {
    let kinds = match tag {
        "shape" => "obj ply rectangle disk cube sphere cylinder serialized hair",
        "bsdf" => {
            "diffuse roughdiffuse conductor roughconductor dielectric thindielectric roughdielectric plastic \
            roughplastic twosided mask bumpmap normalmap blendbsdf mixturebsdf null principled"
        }
        "texture" => "bitmap checkerboard scale noise",
        "emitter" => "area point spot directional envmap constant sunsky projector",
        "medium" => "homogeneous heterogeneous",
        _ => "perspective thinlens orthographic",
    };
    let kind = *r.pick(&words(kinds));
    let id = if r.chance(30) { format!(" id=\"{}\"", r.pick(&words("a b c"))) } else { String::new() };
    let named = if r.chance(30) {
        format!(" name=\"{}\"", r.pick(&words("reflectance opacity interior exterior weight")))
    } else {
        String::new()
    };
    let mut s = format!("<{tag} type=\"{kind}\"{id}{named}>");
    for _ in 0..r.below(5) {
        s.push_str(&mitsuba_property(r));
    }
    if r.chance(40) {
        let name = if r.chance(80) { "to_world" } else { "to_uv" };
        s.push_str(&mitsuba_transform(r, name));
    }
    if depth > 0 {
        for _ in 0..r.below(3) {
            let inner = *r.pick(&words("bsdf bsdf texture emitter medium"));
            if r.chance(20) {
                s.push_str(&format!("<ref id=\"{}\"/>", r.pick(&words("a b c d"))));
            } else {
                s.push_str(&mitsuba_plugin(r, inner, depth - 1));
            }
        }
    }
    s.push_str(&format!("</{tag}>"));
    s
}

/// A whole Mitsuba scene: a sensor, defaults, plugins and shapes, with wrong turns.
fn grammar_mitsuba(r: &mut Rng) -> String {
    let version = *r.pick(&words("3.0.0 0.5.0 0.6.0 2.1.0 x"));
    let mut s = format!("<scene version=\"{version}\">\n");
    if r.chance(70) {
        s.push_str("<default name=\"a\" value=\"1\"/><default name=\"r\" value=\"0.5\"/>\n");
    }
    if r.chance(90) {
        s.push_str(&format!(
            "<sensor type=\"perspective\"><float name=\"fov\" value=\"{}\"/>{}<film type=\"hdrfilm\"><integer name=\"width\" value=\"{}\"/><integer name=\"height\" value=\"8\"/>{}</film></sensor>\n",
            if r.chance(80) { "45".to_string() } else { mitsuba_value(r) },
            mitsuba_transform(r, "to_world"),
            if r.chance(80) { "8".to_string() } else { integer(r) },
            if r.chance(50) { "<rfilter type=\"tent\"/>" } else { "" }
        ));
    }
    for _ in 0..r.below(8) {
        let tag = *r.pick(&words("shape shape shape bsdf emitter texture medium include"));
        if tag == "include" {
            s.push_str(&format!("<include filename=\"{}\"/>\n", r.pick(&words("scene.xml missing.xml mesh.obj"))));
        } else {
            s.push_str(&mitsuba_plugin(r, tag, 2));
            s.push('\n');
        }
    }
    s.push_str("</scene>\n");
    s
}

/// Mitsuba target: `bytes` as the scene file `dir/scene.xml` (its meshes and includes beside it).
fn check_mitsuba_input(bytes: &[u8], dir: &Path) -> Result<(), Failure> {
    let path = dir.join("scene.xml");
    std::fs::write(&path, bytes).unwrap();
    check_scene(|| load_scene(&path), &[&path, dir])
}

/// Runs `cases` cases of one target; returns the failures by kind, with the first input of each.
fn fuzz(
    target: &str,
    extension: &str,
    default_cases: u64,
    generate: impl Fn(&mut Rng) -> Vec<u8>,
    check: impl Fn(&[u8], &Path) -> Result<(), Failure>,
) {
    quiet_panics();
    let cfg = config(default_cases);
    let dir = workspace();
    let start = Instant::now();
    let mut found: BTreeMap<String, (u64, String)> = BTreeMap::new();
    let mut slowest = (Duration::ZERO, 0u64);
    let mut case = cfg.start;
    while case < cfg.start + cfg.cases && cfg.time.is_none_or(|t| start.elapsed() < t) {
        let mut r = Rng::new(cfg.seed, case as u32);
        let input = generate(&mut r);
        if let Some(findings) = &cfg.findings {
            // Kept until the next case, so a crash that kills the process leaves its input.
            std::fs::write(findings.join(format!("current-{target}.{extension}")), &input).unwrap();
        }
        let t = cpu_time();
        let mut result = run_case(|| check(&input, dir.path()));
        let took = cpu_time() - t;
        if took > slowest.0 {
            slowest = (took, case);
        }
        if took > Duration::from_secs(5) {
            let what = result.err().map_or(String::new(), |f| format!(" (and failed: {})", f.message));
            let message = format!("took {:.1} s of CPU time{what}", took.as_secs_f64());
            result = Err(Failure { key: "slow".into(), message });
        }
        if let Err(failure) = result {
            let Some(findings) = &cfg.findings else {
                let shown = String::from_utf8_lossy(&input[..input.len().min(4000)]).to_string();
                panic!(
                    "{target} case {case} (seed {}): {}\ninput ({} bytes):\n{shown}",
                    cfg.seed,
                    failure.message,
                    input.len()
                );
            };
            let entry = found.entry(failure.key.clone()).or_insert((0, failure.message.clone()));
            entry.0 += 1;
            if entry.0 == 1 {
                let stem = format!("{target}-seed{}-case{case}", cfg.seed);
                std::fs::write(findings.join(format!("{stem}.{extension}")), &input).unwrap();
                std::fs::write(findings.join(format!("{stem}.txt")), &failure.message).unwrap();
                eprintln!("{target}: new finding at case {case}: {}", failure.message);
            }
        }
        case += 1;
    }
    let summary = format!(
        "{target}: seed {}, {} cases in {:.1} s, slowest case {} ({:.3} s), {} kinds of failure{}",
        cfg.seed,
        case - cfg.start,
        start.elapsed().as_secs_f64(),
        slowest.1,
        slowest.0.as_secs_f64(),
        found.len(),
        found.iter().map(|(k, (n, m))| format!("\n  {n} x {k}: {m}")).collect::<String>()
    );
    eprintln!("{summary}");
    if let Some(findings) = &cfg.findings {
        std::fs::write(findings.join(format!("summary-{target}-seed{}.txt", cfg.seed)), &summary).unwrap();
        let _ = std::fs::remove_file(findings.join(format!("current-{target}.{extension}")));
    }
}

/// Model target: `bytes` as the mesh file `input.<extension>` of a scene, so the file's extension
/// picks the importer. A `.gltf` finds the buffer and image its seed referenced beside it.
fn check_model_input(bytes: &[u8], extension: &str, dir: &Path) -> Result<(), Failure> {
    let (scene, model) = (dir.join("model-scene.toml"), dir.join(format!("input.{extension}")));
    std::fs::write(&scene, OBJ_SCENE.replace("input.obj", &format!("input.{extension}"))).unwrap();
    std::fs::write(&model, bytes).unwrap();
    check_scene(|| load_scene(&scene), &[&scene, &model])
}

/// Mutations for binary files: besides `mutate`'s, whole 32-bit words made extreme (counts,
/// indices and offsets of u32::MAX or 2^31, NaN and infinite floats, zero).
fn mutate_binary(r: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = if r.chance(40) { mutate(r, input) } else { input.to_vec() };
    for _ in 0..1 + r.below(4) {
        if b.len() < 4 {
            break;
        }
        let at = r.below(b.len() - 3) & !if r.chance(70) { 3 } else { 0 };
        let word: u32 =
            *r.pick(&[u32::MAX, 0x8000_0000, 0x7fc0_0000, 0x7f80_0000, 0xff80_0000, 0, 0x4b00_0000, 1 << 20]);
        b[at..at + 4].copy_from_slice(&word.to_le_bytes());
    }
    b
}

/// Seeds of the model target: (extension, file) from real exporters (tests/models/assimp), the
/// teapot's patches and an IFS file written by the crate's writer.
fn model_seeds() -> Vec<(&'static str, Vec<u8>)> {
    let assimp = |name: &str| std::fs::read(repo("tests/models/assimp").join(name)).unwrap();
    let tetrahedron = photonix::scene::model::ifs::write_ifs(
        "tetrahedron",
        &[glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z],
        &[[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
    );
    vec![
        ("ply", assimp("cube.ply")),
        ("ply", assimp("cube_binary.ply")),
        ("ply", assimp("cube_uv.ply")),
        ("ply", assimp("float-color.ply")),
        ("glb", assimp("BoxTextured.glb")),
        ("gltf", assimp("BoxTextured-glTF/BoxTextured.gltf")),
        ("3ds", assimp("cube_with_diffuse_texture.3DS")),
        ("3ds", assimp("test1.3ds")),
        ("ifs", tetrahedron),
        ("bpt", std::fs::read(repo("scenes/meshes/teapot.bpt")).unwrap()),
    ]
}

/// A model input carries its extension in front of the bytes ("ply\n..."), so that a finding
/// written to a file replays with the right importer.
fn check_tagged_model_input(tagged: &[u8], dir: &Path) -> Result<(), Failure> {
    let split = tagged.iter().position(|&c| c == b'\n').unwrap_or(tagged.len());
    let extension = String::from_utf8_lossy(&tagged[..split]).to_string();
    let bytes = tagged.get(split + 1..).unwrap_or_default();
    // The .gltf seed references these by name.
    for name in ["BoxTextured0.bin", "CesiumLogoFlat.png"] {
        let target = dir.join(name);
        if !target.exists() {
            std::fs::copy(repo("tests/models/assimp/BoxTextured-glTF").join(name), target).unwrap();
        }
    }
    check_model_input(bytes, &extension, dir)
}

/// The shipped scene files, as seeds for mutation.
fn shipped_scenes() -> Vec<Vec<u8>> {
    ["scenes/cornell-box.toml", "scenes/cornell-caustics.toml", "scenes/showcase.toml"]
        .iter()
        .map(|p| std::fs::read(repo(p)).unwrap())
        .collect()
}

#[test]
fn fuzz_scene_parser() {
    let seeds = shipped_scenes();
    fuzz(
        "scene",
        "toml",
        300,
        |r| {
            if r.chance(50) {
                grammar_scene(r).into_bytes()
            } else {
                let base = r.pick(&seeds).clone();
                mutate(r, &base)
            }
        },
        check_scene_input,
    );
}

#[test]
fn fuzz_mitsuba_front_end() {
    let seeds: Vec<Vec<u8>> = std::fs::read_dir(repo("tests/fuzz_corpus/mitsuba"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "xml"))
                .collect::<Vec<_>>()
        })
        .unwrap_or_default()
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    fuzz(
        "mitsuba",
        "xml",
        300,
        |r| {
            if seeds.is_empty() || r.chance(60) {
                let base = grammar_mitsuba(r).into_bytes();
                if r.chance(20) {
                    mutate(r, &base)
                } else {
                    base
                }
            } else {
                let base = r.pick(&seeds).clone();
                mutate(r, &base)
            }
        },
        check_mitsuba_input,
    );
}

#[test]
fn fuzz_obj_importer() {
    let ico = std::fs::read(repo("scenes/meshes/icosahedron.obj")).unwrap();
    fuzz(
        "obj",
        "obj",
        300,
        |r| {
            if r.chance(60) {
                let base = grammar_obj(r);
                if r.chance(30) {
                    mutate(r, &base)
                } else {
                    base
                }
            } else {
                mutate(r, &ico)
            }
        },
        check_obj_input,
    );
}

#[test]
fn fuzz_model_importers() {
    let seeds = model_seeds();
    fuzz(
        "model",
        "model",
        300,
        |r| {
            let (extension, base) = r.pick(&seeds);
            let text = matches!(*extension, "gltf" | "bpt")
                || (*extension == "ply" && !base.windows(6).any(|w| w == b"binary"));
            let bytes = if text && r.chance(70) { mutate(r, base) } else { mutate_binary(r, base) };
            [extension.as_bytes(), b"\n", &bytes].concat()
        },
        check_tagged_model_input,
    );
}

// The editor's API

/// Words a file outside the editor's folder holds; no reply may ever show them.
const SECRET: &str = "OUTSIDESECRET";

/// A server on a scene in `<tmp>/scene/`, with `<tmp>/outside/` holding files that edits and
/// imports try to reach (an MTL, a glTF buffer, an image, a scene).
struct EditorTarget {
    fixture: editor_support::Fixture,
    /// The served scene file (`fixture.scene` is the fixture's unused default).
    scene: PathBuf,
    outside: PathBuf,
    /// Answers seen, by kind ("http 422", "ws reply ok"), for the run's summary.
    answers: RefCell<BTreeMap<String, u64>>,
    _root: tempfile::TempDir,
}

impl EditorTarget {
    fn new() -> EditorTarget {
        let root = tempfile::tempdir().unwrap();
        let outside = root.path().join("outside");
        std::fs::create_dir(&outside).unwrap();
        std::fs::write(outside.join("secret.mtl"), format!("newmtl {SECRET}\nKd 0.1 0.2 0.3\n")).unwrap();
        std::fs::write(outside.join("secret.obj"), format!("o {SECRET}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"))
            .unwrap();
        std::fs::write(outside.join("secret.bin"), SECRET.repeat(4)).unwrap();
        std::fs::write(outside.join("secret.toml"), format!("# {SECRET}\n")).unwrap();
        let folder = root.path().join("scene");
        std::fs::create_dir(&folder).unwrap();
        let fixture = editor_support::Fixture::with(photonix::editor::BackendChoice::Cpu, |o| {
            o.scene = folder.join("scene.toml");
            std::fs::write(&o.scene, editor_support::SCENE).unwrap();
            o.max_upload_bytes = 64 << 10;
        });
        std::os::unix::fs::symlink(outside.join("secret.mtl"), folder.join("link.mtl")).unwrap();
        EditorTarget {
            fixture,
            scene: folder.join("scene.toml"),
            outside,
            answers: RefCell::new(BTreeMap::new()),
            _root: root,
        }
    }
}

/// A file name as the page might send it: ordinary, missing, or leading out of the folder.
fn editor_file(r: &mut Rng) -> String {
    const FILES: &str = "mesh.obj scene.toml link.mtl missing.obj ../outside/secret.obj ../outside/secret.mtl \
        /etc/passwd ../outside/secret.bin file:///etc/passwd . .. / ../../ %2e%2e/outside/secret.obj \
        ../outside/missing.obj textures/a.png ./scene.toml";
    r.pick(&words(FILES)).to_string()
}

/// A JSON value for a field: right kind most of the time, else anything.
fn editor_value(r: &mut Rng) -> serde_json::Value {
    use serde_json::json;
    match r.below(12) {
        0 => json!(r.below(100) as f64 / 10.0),
        1 => json!([r.below(5), r.below(5), r.below(5)]),
        2 => json!(words("1e300 -1e300 1e-300 0 -0 3.4e39 -1")[r.below(7)].parse::<f64>().unwrap()),
        3 => json!(editor_file(r)),
        4 => json!({ "texture": "checks" }),
        5 => json!(null),
        6 => json!(true),
        7 => json!("k".repeat(r.below(5000))),
        8 => json!([[[[]]]]),
        9 => json!({ "a": { "b": [1, { "c": "\u{1b}[31m" }] } }),
        10 => json!(i64::MAX),
        _ => json!(r.below(3)),
    }
}

fn editor_target(r: &mut Rng) -> serde_json::Value {
    use serde_json::json;
    match r.below(9) {
        0 => json!({ "shape": r.below(6) }),
        1 => json!({ "light": r.below(4) }),
        2 => json!({ "instance": r.below(2) }),
        3 => json!({ "material": *r.pick(&["white", "red", "glass", "nope", ""]) }),
        4 => json!(*r.pick(&["camera", "render", "photons", "environment", "objects", "x"])),
        5 => json!({ "shape": -1 }),
        6 => json!({ "shape": u64::MAX }),
        7 => json!([1, 2]),
        _ => json!({ "shape": 0, "light": 0 }),
    }
}

/// An edit command of the page's protocol (docs/editor.md), sometimes malformed.
fn editor_command(r: &mut Rng) -> serde_json::Value {
    use serde_json::json;
    const FIELDS: &str = "position look_at up fov resolution spp passes max_depth seed count radius file \
        reflectance emission roughness ior type material center radius vertices transform strength \
        rotation count caustic_count gather_rays name bogus";
    let field = r.pick(&words(FIELDS)).to_string();
    let mut command = match r.below(9) {
        0 => json!({ "op": "set", "target": editor_target(r), "field": field, "value": editor_value(r) }),
        1 => json!({ "op": "set_transform", "target": editor_target(r), "translate": [r.below(3), 0, 0],
                     "rotate": editor_value(r), "scale": editor_value(r) }),
        2 => json!({ "op": "set_fields", "target": editor_target(r), "fields": { field: editor_value(r) } }),
        3 => json!({ "op": "delete", "target": editor_target(r) }),
        4 => json!({ "op": "duplicate", "target": editor_target(r) }),
        5 => json!({ "op": "add", "kind": *r.pick(&["shape", "light", "material", "camera"]),
                     "table": { "type": *r.pick(&["mesh", "sphere", "diffuse", "area", "x"]),
                                "material": "white", "file": editor_file(r), "radius": editor_value(r) },
                     "name": *r.pick(&["new", "white", "", "a b"]) }),
        6 => json!({ "op": "set_texture", "material": *r.pick(&["white", "red", "nope"]),
                     "field": *r.pick(&["reflectance", "emission", "roughness", "bump", "x"]),
                     "file": editor_file(r), "linear": r.chance(50) }),
        7 => json!({ "op": "set", "target": "environment", "field": "file", "value": editor_file(r) }),
        _ => json!({ "op": *r.pick(&["set", "nope", ""]), "bogus": editor_value(r) }),
    };
    if r.chance(10) {
        command[*r.pick(&["op", "target", "value", "extra"])] = editor_value(r);
    }
    command
}

/// An OBJ body for an import: the grammar's, or one naming files out of the folder.
fn editor_obj(r: &mut Rng) -> Vec<u8> {
    let mut obj = if r.chance(50) { grammar_obj(r) } else { b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec() };
    if r.chance(50) {
        let mtl = *r.pick(&["../outside/secret.mtl", "link.mtl", "/etc/passwd", "missing.mtl", "../outside"]);
        obj.splice(0..0, format!("mtllib {mtl}\nusemtl {SECRET}\n").into_bytes());
    }
    obj
}

/// One case: `http METHOD PATH` or `ws` on the first line, the body or message after it.
fn editor_case(r: &mut Rng) -> Vec<u8> {
    use serde_json::json;
    let command = editor_command(r);
    let (head, body): (String, Vec<u8>) = match r.below(12) {
        0..=2 => ("http POST /api/edit".into(), command.to_string().into_bytes()),
        3..=4 => {
            let id = if r.chance(80) { json!(r.below(1000)) } else { editor_value(r) };
            let message = match r.below(7) {
                0..=2 => json!({ "type": "edit", "id": id, "command": command }),
                3 => json!({ "type": *r.pick(&["undo", "redo", "save"]), "id": id }),
                4 => json!({ "type": "view", "view": { "position": [0, 1, 4], "look_at": editor_value(r),
                             "up": [0, 1, 0], "fov": editor_value(r), "width": 16, "height": editor_value(r) } }),
                5 => json!({ "type": "bogus" }),
                _ => editor_value(r),
            };
            ("ws".into(), message.to_string().into_bytes())
        }
        5 => {
            let name = *r.pick(&["m.obj", "../m.obj", "m.toml", ".m.obj", "a%2Fb.obj", "scene.toml", "M.OBJ"]);
            let material = *r.pick(&["white", "nope", ""]);
            (format!("http POST /api/import?name={name}&material={material}"), editor_obj(r))
        }
        6 => {
            let body = match r.below(4) {
                0 => json!({ "seconds": editor_value(r) }),
                1 => json!({ "passes": editor_value(r) }),
                2 => json!({ "passes": 1, "bogus": 1 }),
                _ => json!({}),
            };
            (format!("http POST {}", r.pick(&["/api/render", "/api/render/cancel"])), body.to_string().into_bytes())
        }
        7 => (format!("http POST {}", r.pick(&["/api/undo", "/api/redo", "/api/save"])), Vec::new()),
        8 => {
            let path = *r.pick(&[
                "/api/scene",
                "/api/scene.toml",
                "/api/images",
                "/api/render/status",
                "/api/render/image.png",
                "/api/render/image.exr",
                "/api/nope",
                "/../outside/secret.toml",
                "/%2e%2e/outside/secret.toml",
            ]);
            (format!("http GET {path}"), Vec::new())
        }
        _ => {
            // A valid edit, mutated byte by byte.
            let body = mutate(r, command.to_string().as_bytes());
            (format!("http POST {}", r.pick(&["/api/edit", "/api/render"])), body)
        }
    };
    let mut out = head.into_bytes();
    out.push(b'\n');
    out.extend(body);
    out
}

/// Sends one case and checks the server's answer: a status below 500, JSON errors with
/// `ok: false` and a message, nothing from outside the folder in any reply, a document that still
/// parses, no file written outside the folder, and a server that still answers.
fn check_editor_case(t: &EditorTarget, input: &[u8]) -> Result<(), Failure> {
    let f = &t.fixture;
    let fail = |key: &str, message: String| Err(Failure { key: key.to_string(), message });
    let split = input.iter().position(|&c| c == b'\n').unwrap_or(input.len());
    let head = String::from_utf8_lossy(&input[..split]).to_string();
    let body = input.get(split + 1..).unwrap_or_default();
    let mut replies: Vec<String> = Vec::new();
    if let Some(request) = head.strip_prefix("http ") {
        let (method, path) = request.split_once(' ').unwrap_or(("GET", "/"));
        // The request line takes no spaces or control characters; the generator makes none.
        let r = f.call(method, path, body);
        *t.answers.borrow_mut().entry(format!("http {}", r.status)).or_default() += 1;
        let text = r.text();
        if r.status >= 500 {
            return fail("5xx", format!("{method} {path}: {} {text}", r.status));
        }
        let json_expected = path.starts_with("/api/") && (r.status >= 400 || !path.contains('.'));
        if json_expected && path != "/api/images" {
            let Ok(value) = serde_json::from_slice::<serde_json::Value>(&r.body) else {
                return fail("not json", format!("{method} {path}: {} {text}", r.status));
            };
            if r.status >= 400 && (value["ok"] != false || !value["error"].is_string()) {
                return fail("error shape", format!("{method} {path}: {} {text}", r.status));
            }
        }
        replies.push(text);
    } else {
        let messages = f.runtime.block_on(websocket_exchange(f, body));
        match messages {
            Ok(m) => {
                let last: serde_json::Value = m.last().and_then(|l| serde_json::from_str(l).ok()).unwrap_or_default();
                let kind = match (last["type"].as_str(), last["ok"].as_bool()) {
                    (Some("reply"), Some(true)) => "ws reply ok",
                    (Some("reply"), _) => "ws reply refused",
                    (Some("error"), _) => "ws error",
                    _ => "ws no reply",
                };
                *t.answers.borrow_mut().entry(kind.to_string()).or_default() += 1;
                replies.extend(m)
            }
            Err(e) => return fail("websocket", e),
        }
    }
    for reply in &replies {
        if reply.contains(SECRET) {
            return fail("leak", format!("{head}: a reply shows a file outside the folder: {reply}"));
        }
    }
    let text = f.text();
    if text.contains(SECRET) {
        return fail("leak", "the scene text holds the outside file's words".into());
    }
    if let Err(e) = parse_scene(&text, &t.scene) {
        return fail("document", format!("{head}: the document no longer parses: {e}"));
    }
    let outside: Vec<_> = std::fs::read_dir(&t.outside).unwrap().flatten().map(|e| e.file_name()).collect();
    if outside.len() != 4 {
        return fail("wrote outside", format!("{head}: the outside folder now holds {outside:?}"));
    }
    if f.call("GET", "/api/render/status", b"").status != 200 {
        return fail("dead", format!("{head}: the server stopped answering"));
    }
    Ok(())
}

/// Sends `message` on a fresh WebSocket and collects the text messages until the reply (or an
/// error) arrives; a view gets no reply, so it waits a moment only.
async fn websocket_exchange(f: &editor_support::Fixture, message: &[u8]) -> Result<Vec<String>, String> {
    use futures_util::{SinkExt, StreamExt};
    use tokio_tungstenite::tungstenite::Message;
    let url = format!("ws://{}/ws?token={}", f.addr(), f.token());
    let (mut socket, _) = tokio_tungstenite::connect_async(url).await.map_err(|e| format!("connect: {e}"))?;
    let text = String::from_utf8_lossy(message).to_string();
    socket.send(Message::Text(text.clone().into())).await.map_err(|e| format!("send: {e}"))?;
    let is_view = text.contains("\"view\"");
    let wait = Duration::from_millis(if is_view { 300 } else { 20_000 });
    let mut got = Vec::new();
    loop {
        match tokio::time::timeout(wait, socket.next()).await {
            Err(_) if is_view => break,
            Err(_) => return Err(format!("no reply within {wait:?} to {text}")),
            Ok(None) | Ok(Some(Err(_))) => break,
            Ok(Some(Ok(Message::Text(t)))) => {
                let t = t.to_string();
                let value: serde_json::Value =
                    serde_json::from_str(&t).map_err(|e| format!("a message that is not JSON ({e}): {t}"))?;
                let kind = value["type"].as_str().unwrap_or_default().to_string();
                got.push(t);
                if kind == "reply" || kind == "error" {
                    if value["type"] == "reply" && value["ok"] == false && !value["error"].is_string() {
                        return Err(format!("a failed reply without a message: {value}"));
                    }
                    break;
                }
            }
            Ok(Some(Ok(_))) => {}
        }
    }
    let _ = socket.close(None).await;
    Ok(got)
}

#[test]
fn fuzz_editor_api() {
    let target = EditorTarget::new();
    fuzz("editor", "editor", 200, editor_case, |input, _| check_editor_case(&target, input));
    let answers = target.answers.borrow();
    eprintln!("editor answers: {}", answers.iter().map(|(k, n)| format!("{n} x {k}")).collect::<Vec<_>>().join(", "));
}

#[test]
fn fuzz_corpus_replays_cleanly() {
    quiet_panics();
    let dir = workspace();
    let mut replayed = 0;
    for (folder, check) in [
        ("scene", check_scene_input as fn(&[u8], &Path) -> Result<(), Failure>),
        ("obj", check_obj_input),
        ("model", check_tagged_model_input),
        ("mitsuba", check_mitsuba_input),
        ("pov", check_pov_input),
    ] {
        let Ok(entries) = std::fs::read_dir(repo("tests/fuzz_corpus").join(folder)) else { continue };
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        paths.sort();
        for path in paths.iter().filter(|p| p.extension().is_some_and(|e| e != "txt" && e != "md")) {
            let input = std::fs::read(path).unwrap();
            if let Err(failure) = run_case(|| check(&input, dir.path())) {
                panic!("{}: {}", path.display(), failure.message);
            }
            replayed += 1;
        }
    }
    println!("replayed {replayed} corpus inputs");
}

// The POV-Ray front-end: include graphs, nesting, values that grow

/// Names of the files a POV-Ray case may include: each case writes some of them, and an include
/// of one it did not write (or of a device) must be an error naming the file it stands in.
const POV_FILES: [&str; 4] = ["a.inc", "b.inc", "scene.pov", "c.inc"];

/// One POV-Ray statement or directive from the grammar's risky corners.
fn pov_statement(r: &mut Rng, depth: usize) -> String {
    let n = |r: &mut Rng| number(r);
    match r.below(if depth > 3 { 12 } else { 16 }) {
        0 => format!("#include \"{}\"\n", r.pick(&[POV_FILES[0], POV_FILES[1], POV_FILES[2], POV_FILES[3], "/dev/zero", "fifo.inc", "missing.inc", "..", "/tmp"])),
        1 => {
            let k = [1, 10, 100, 255, 256, 257, 1300][r.below(7)];
            format!("#declare X = {}{}{};\n", "(".repeat(k), n(r), ")".repeat(k))
        }
        2 => {
            let k = [1, 10, 120, 257, 2000][r.below(5)];
            let op = r.pick(&["union", "intersection", "difference", "merge"]).to_string();
            format!("{}sphere {{ 0, {} }}{}\n", format!("{op} {{ ").repeat(k), n(r), " }".repeat(k))
        }
        3 => {
            let k = [1, 100, 300, 100_000][r.below(4)];
            format!("#declare X = {}{};\n", r.pick(&["- ", "! ", "+ "]).repeat(k), n(r))
        }
        4 => {
            let turns = [1, 8, 21, 40][r.below(4)];
            let grow = r.pick(&["concat(S, S)", "S + S", "concat(S, str(I, 0, 3))", "substr(S, 1, 2)"]).to_string();
            format!("#declare S = \"ab\";\n#for (I, 1, {turns})\n#declare S = {grow};\n#end\n")
        }
        5 => {
            let turns = [1, 10, 30, 300][r.below(4)];
            let body = r.pick(&[
                "union { object { U } object { U translate x } }",
                "union { object { U } }",
                "intersection { object { U } sphere { 0, 2 } }",
            ]).to_string();
            format!("#declare U = sphere {{ 0, 0.1 }}\n#for (I, 1, {turns})\n#declare U = {body}\n#end\nobject {{ U }}\n")
        }
        6 => {
            let turns = [1, 10, 300][r.below(3)];
            let body = r.pick(&["#declare A = array[2] { A, A }", "#declare A[0] = A;", "#declare A = array[1] { A }"]).to_string();
            format!("#declare A = array[2] {{ 1, 2 }}\n#for (I, 1, {turns})\n{body}\n#end\n")
        }
        7 => format!("#declare A = array[{}];\n", r.pick(&["4", "0", "-1", "1e9", "4194304", "4194305", "nan"])),
        8 => {
            let turns = [1, 20, 200][r.below(3)];
            format!("#macro M(N) #if (N > 0) M(N - 1) #end #end\nM({turns})\n")
        }
        9 => format!("#macro T() #include \"{}\" #end\nT()\n", r.pick(&POV_FILES)),
        10 => format!("sphere {{ <{}, {}, {}>, {} pigment {{ rgb {} }} }}\n", n(r), n(r), n(r), n(r), n(r)),
        11 => format!("light_source {{ <{}, {}, {}> color rgb {} }}\n", n(r), n(r), n(r), n(r)),
        12 => format!("camera {{ location <{}, {}, {}> look_at <{}, {}, {}> }}\n", n(r), n(r), n(r), n(r), n(r), n(r)),
        13 => format!("height_field {{ png \"{}\" }}\n", r.pick(&["/dev/zero", "fifo.inc", "missing.png", "a.inc"])),
        14 => format!(
            "#declare T = texture {{ pigment {{ rgb 1 }} }}\n#for (I, 1, {})\n#declare T = texture {{ checker texture {{ T }} texture {{ T }} }}\n#end\n",
            [1, 5, 30][r.below(3)]
        ),
        _ => (0..1 + r.below(3)).map(|_| pov_statement(r, depth + 1)).collect(),
    }
}

/// A POV-Ray case: the scene and its include files, one per line of `POV_FILES` order, each
/// after a line `=== name`, so a finding replays from one file.
fn grammar_pov(r: &mut Rng) -> Vec<u8> {
    let mut out = String::new();
    for name in POV_FILES {
        if name != "scene.pov" && r.chance(40) {
            continue;
        }
        out.push_str(&format!("=== {name}\n"));
        if name == "scene.pov" {
            out.push_str("camera { location <0, 1, -4> look_at 0 }\nlight_source { <2, 4, -3> color rgb 1 }\n");
        }
        for _ in 0..1 + r.below(4) {
            out.push_str(&pov_statement(r, 0));
        }
    }
    let bytes = out.into_bytes();
    if r.chance(20) {
        mutate(r, &bytes)
    } else {
        bytes
    }
}

/// POV-Ray target: the files of the case written, `scene.pov` loaded (on the test's thread, whose
/// stack is the smallest a parser runs on), with a FIFO beside it that no read may wait on.
fn check_pov_input(bytes: &[u8], dir: &Path) -> Result<(), Failure> {
    let dir = dir.join("pov");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("fifo.inc");
    let _ = std::process::Command::new("mkfifo").arg(&fifo).status();
    let text = String::from_utf8_lossy(bytes);
    let mut current: Option<std::fs::File> = None;
    for line in text.split_inclusive('\n') {
        if let Some(name) = line.strip_prefix("=== ").map(str::trim).filter(|n| POV_FILES.contains(n)) {
            current = Some(std::fs::File::create(dir.join(name)).unwrap());
            continue;
        }
        if let Some(f) = current.as_mut() {
            std::io::Write::write_all(f, line.as_bytes()).unwrap();
        }
    }
    let scene = dir.join("scene.pov");
    if !scene.exists() {
        std::fs::write(&scene, "").unwrap();
    }
    let names: Vec<PathBuf> = POV_FILES.iter().map(|n| dir.join(n)).chain([fifo.clone()]).collect();
    let refs: Vec<&Path> = names.iter().map(PathBuf::as_path).collect();
    // The front-end runs on a thread of its own, whose CPU time `fuzz` does not see: a hang is
    // caught here by the wall clock instead (a case takes well under a second when it does not).
    let (tx, rx) = std::sync::mpsc::channel();
    let path = scene.clone();
    std::thread::spawn(move || {
        let _ = tx.send(load_scene(&path));
    });
    match rx.recv_timeout(Duration::from_secs(120)) {
        Ok(loaded) => check_scene(|| loaded, &refs),
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            Err(Failure { key: "hang".into(), message: "the load took more than 120 s of wall time".into() })
        }
        Err(_) => Err(Failure { key: "panic".into(), message: "the load panicked (on its own thread)".into() }),
    }
}

#[test]
fn fuzz_pov_front_end() {
    fuzz("pov", "povcase", 200, grammar_pov, check_pov_input);
}

// The glTF reader: URIs, sizes, accessors, out-of-range values

/// A glTF case: JSON with buffers, images, accessors, cameras, lights and materials drawn from
/// the risky corners.
fn grammar_gltf(r: &mut Rng) -> Vec<u8> {
    let uri = |r: &mut Rng| -> serde_json::Value {
        serde_json::json!(r.pick(&[
            "tri.bin",
            "tri.bin",
            "/dev/zero",
            "fifo.bin",
            "huge.bin",
            "missing.bin",
            "file:///dev/zero",
            "file://tri.bin",
            "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA",
            "data:,",
            "%ZZ",
            "..",
            "/",
            "http://example.com/x.bin",
            "tri.png",
        ]))
    };
    let f = |r: &mut Rng| -> serde_json::Value {
        serde_json::json!(r.pick(&[0.0, 1.0, 0.5, -1.0, 2.0, 1e30, -1e30, 1e-30, 3.2, 1.6, 90.0]))
    };
    let int = |r: &mut Rng| -> serde_json::Value {
        serde_json::json!(r.pick(&[0u64, 1, 3, 36, 35, 37, 4, 1 << 20, 1 << 31, u32::MAX as u64, 1 << 40]))
    };
    let mut g = serde_json::json!({
        "asset": { "version": "2.0" },
        "buffers": [{ "uri": uri(r), "byteLength": int(r) }],
        "bufferViews": [{ "buffer": 0, "byteLength": int(r), "byteOffset": int(r) }],
        "accessors": [{ "bufferView": 0, "componentType": *r.pick(&[5126, 5125, 5123, 5121, 5120, 1]),
                        "count": int(r), "byteOffset": int(r), "type": *r.pick(&["VEC3", "SCALAR", "VEC2", "MAT4"]),
                        "min": [0, 0, 0], "max": [1, 1, 0] }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 } }] }],
        "nodes": [{ "mesh": 0 }, { "camera": 0, "translation": [0, 0, 3] }],
        "scenes": [{ "nodes": [0, 1] }],
        "cameras": [{ "type": "perspective", "perspective": { "yfov": f(r), "znear": 0.1, "aspectRatio": f(r) } }],
    });
    if r.chance(50) {
        g["images"] = serde_json::json!([{ "uri": uri(r) }]);
        g["textures"] = serde_json::json!([{ "source": 0 }]);
        g["materials"] = serde_json::json!([{
            "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "baseColorFactor": [f(r), f(r), f(r), f(r)],
                                      "metallicFactor": f(r), "roughnessFactor": f(r) },
            "emissiveFactor": [f(r), f(r), f(r)],
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": f(r) } },
        }]);
        g["meshes"][0]["primitives"][0]["material"] = serde_json::json!(0);
    }
    if r.chance(50) {
        g["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
        g["extensions"] = serde_json::json!({ "KHR_lights_punctual": { "lights": [{
            "type": *r.pick(&["spot", "point", "directional"]), "intensity": f(r), "color": [f(r), 1, 1],
            "spot": { "innerConeAngle": f(r), "outerConeAngle": f(r) } }] } });
        g["nodes"][0]["extensions"] = serde_json::json!({ "KHR_lights_punctual": { "light": 0 } });
    }
    let bytes = g.to_string().into_bytes();
    if r.chance(20) {
        mutate(r, &bytes)
    } else {
        bytes
    }
}

/// glTF target: `bytes` as `scene.gltf`, beside a triangle's buffer, a PNG, a FIFO and a huge
/// sparse file, loaded as a whole scene (the front-end `render x.gltf` uses).
fn check_gltf_input(bytes: &[u8], dir: &Path) -> Result<(), Failure> {
    let dir = dir.join("gltf");
    if !dir.exists() {
        std::fs::create_dir_all(&dir).unwrap();
        let tri: Vec<u8> =
            [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(dir.join("tri.bin"), tri).unwrap();
        std::fs::copy(repo("tests/models/assimp/BoxTextured-glTF/CesiumLogoFlat.png"), dir.join("tri.png")).unwrap();
        let _ = std::process::Command::new("mkfifo").arg(dir.join("fifo.bin")).status();
        std::fs::File::create(dir.join("huge.bin")).unwrap().set_len(1 << 40).unwrap();
    }
    let scene = dir.join("scene.gltf");
    std::fs::write(&scene, bytes).unwrap();
    check_scene(|| load_scene(&scene), &[&scene])
}

#[test]
fn fuzz_gltf_scene() {
    fuzz("gltf", "gltf", 200, grammar_gltf, check_gltf_input);
}
