//! The POV-Ray front-end end to end: objects and transforms against the same scene written in
//! TOML, include search, errors at `.pov` positions (in the scene and in includes, and errors the
//! TOML checks find), the command line, and a small fuzz (no panic on garbage).

use std::path::{Path, PathBuf};

use glam::Vec3;
use photonix::scene::pov::{load_pov, translate_file, PovOptions};
use photonix::scene::{load_scene, parse_scene, Geometry, LightKind, Scene};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn options() -> PovOptions {
    PovOptions { width: 64, height: 48, ..PovOptions::default() }
}

fn load(dir: &Path, text: &str) -> Scene {
    let p = write(dir, "scene.pov", text);
    match load_pov(&p, &options()) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

fn error(dir: &Path, text: &str) -> String {
    let p = write(dir, "scene.pov", text);
    match load_pov(&p, &options()) {
        Ok(_) => panic!("no error for {text}"),
        Err(e) => e.to_string(),
    }
}

/// The bounds of every shape, in order: geometry compared without caring how it is stored.
fn bounds(s: &Scene) -> Vec<(Vec3, Vec3)> {
    s.shapes.iter().map(|sh| sh.geometry.bounds()).collect()
}

const CAMERA: &str = "camera { location <0, 2, -6> look_at <0, 1, 0> }\nlight_source { <3, 6, -4>, rgb 1 }\n";

#[test]
fn shapes_and_transforms_match_the_same_scene_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    // POV-Ray is left-handed: the same scene in Photonix's frame has z negated, and POV-Ray's
    // rotations (x, then y, then z, about the axes) become rotations with the y and x angles negated.
    let pov = load(
        dir.path(),
        &format!(
            "{CAMERA}
sphere {{ <1, 2, 3>, 0.5 pigment {{ rgb 1 }} }}
box {{ <-1, 0, -1>, <1, 0.5, 2> rotate <0, 30, 0> translate <0, 0, 4> pigment {{ rgb 1 }} }}
cylinder {{ <0, 0, 0>, <0, 1, 1>, 0.25 scale 2 translate x pigment {{ rgb 1 }} }}
cone {{ <0, 0, 0>, 1, <0, 2, 0>, 0 open rotate x * 90 pigment {{ rgb 1 }} }}
torus {{ 1, 0.2 rotate <20, 40, 0> translate <2, 1, 2> pigment {{ rgb 1 }} }}
disc {{ <0, 1, 2>, <0, 0, -1>, 0.5 pigment {{ rgb 1 }} }}
superellipsoid {{ <0.5, 0.5> scale <1, 2, 3> translate -x * 3 pigment {{ rgb 1 }} }}
triangle {{ <0, 0, 0>, <1, 0, 0>, <0, 1, 1> pigment {{ rgb 1 }} }}
union {{ sphere {{ 0, 1 }} sphere {{ x, 1 }} translate z * 5 pigment {{ rgb 1 }} }}
"
        ),
    );
    let toml = r#"
[camera]
position = [0, 2, 6]
look_at = [0, 1, 0]
fov = 53.13
[materials.w]
type = "diffuse"
[[shapes]]
type = "sphere"
material = "w"
center = [1, 2, -3]
radius = 0.5
[[shapes]]
type = "box"
material = "w"
min = [-1, 0, -2]
max = [1, 0.5, 1]
transform = { rotate = [0, -30, 0], translate = [0, 0, -4] }
[[shapes]]
type = "cylinder"
material = "w"
base = [1, 0, 0]
cap = [1, 2, -2]
radius = 0.5
[[shapes]]
type = "cone"
material = "w"
base = [0, 0, 0]
cap = [0, 0, -2]
base_radius = 1
cap_radius = 0
open = true
[[shapes]]
type = "torus"
material = "w"
major_radius = 1
minor_radius = 0.2
transform = { rotate = [-20, -40, 0], translate = [2, 1, -2] }
[[shapes]]
type = "disc"
material = "w"
center = [0, 1, -2]
normal = [0, 0, 1]
radius = 0.5
[[shapes]]
type = "superellipsoid"
material = "w"
exponents = [0.5, 0.5]
transform = { scale = [1, 2, 3], translate = [-3, 0, 0] }
[[shapes]]
type = "triangle"
material = "w"
vertices = [[0, 0, 0], [1, 0, 0], [0, 1, -1]]
[[shapes]]
type = "sphere"
material = "w"
center = [0, 0, -5]
radius = 1
[[shapes]]
type = "sphere"
material = "w"
center = [1, 0, -5]
radius = 1
"#;
    let want = parse_scene(toml, Path::new("same.toml")).unwrap();
    let (a, b) = (bounds(&pov), bounds(&want));
    assert_eq!(a.len(), b.len(), "{a:?}\nvs\n{b:?}");
    for (i, ((amin, amax), (bmin, bmax))) in a.iter().zip(&b).enumerate() {
        // Both go through f32 and the same analytic bounds; 1e-4 covers the rounding of angles.
        assert!(
            amin.abs_diff_eq(*bmin, 1e-4) && amax.abs_diff_eq(*bmax, 1e-4),
            "shape {i}: {amin} {amax} vs {bmin} {bmax}"
        );
    }
    // The camera looks the same way: POV-Ray's +z into the screen is Photonix's -z.
    assert!(pov.camera.position.abs_diff_eq(Vec3::new(0.0, 2.0, 6.0), 1e-6));
    let f = (pov.camera.look_at - pov.camera.position).normalize();
    let g = (want.camera.look_at - want.camera.position).normalize();
    assert!(f.abs_diff_eq(g, 1e-6), "{f} vs {g}");
    // POV-Ray's default camera: up 1 and direction 1 span 2 atan(0.5) vertically.
    assert!((pov.camera.fov_deg - 53.130_1).abs() < 1e-3, "{}", pov.camera.fov_deg);
}

#[test]
fn csg_lights_and_finishes_map_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        "camera { location <0, 0, -10> look_at <0, 0, 0> }
light_source { <0, 0, -10>, rgb <1, 0.5, 0.25> }
light_source { <10, 0, 0>, rgb 1 spotlight point_at <0, 0, 0> radius 10 falloff 20 }
light_source { <0, 10, 0>, rgb 1 parallel point_at <0, 0, 0> }
difference { sphere { 0, 1 } box { 0, 2 } pigment { rgb <1, 0, 0> } }
sphere { <3, 0, 0>, 1 pigment { rgbf <1, 1, 1, 0.9> } interior { ior 1.5 } }
sphere { <-3, 0, 0>, 1 pigment { rgb 1 } finish { reflection 1 } }
sphere { <0, 3, 0>, 1 pigment { rgb <0, 1, 0> } finish { ambient 1 diffuse 0 } }
sphere { <0, -3, 0>, 1 pigment { rgb 0.5 } finish { phong 1 phong_size 60 } }
",
    );
    let kinds: Vec<&str> = s
        .shapes
        .iter()
        .map(|sh| match &sh.geometry {
            Geometry::Csg(_) => "csg",
            Geometry::Sphere(_) => "sphere",
            _ => "other",
        })
        .collect();
    assert_eq!(&kinds[..5], ["csg", "sphere", "sphere", "sphere", "sphere"]);
    let material = |i: usize| &s.materials[s.shapes[i].material as usize];
    use photonix::scene::MaterialKind;
    assert!(matches!(material(1).kind, MaterialKind::Dielectric { .. }), "{:?}", material(1).kind);
    assert!(matches!(material(2).kind, MaterialKind::Mirror { .. }), "{:?}", material(2).kind);
    // ambient 1, diffuse 0: it glows with its pigment.
    assert!(material(3).emission.value.abs_diff_eq(Vec3::new(0.0, 1.0, 0.0), 1e-6));
    assert!(matches!(material(4).kind, MaterialKind::Plastic { .. }), "{:?}", material(4).kind);
    // A light of colour c, 10 units from where the camera looks: I = pi c d^2.
    let pi = std::f32::consts::PI;
    match &s.lights[0].kind {
        LightKind::Point { intensity, position } => {
            assert!(intensity.abs_diff_eq(Vec3::new(1.0, 0.5, 0.25) * pi * 100.0, 1e-2), "{intensity}");
            assert!(position.abs_diff_eq(Vec3::new(0.0, 0.0, 10.0), 1e-6));
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(s.lights[1].kind, LightKind::Spot { .. }));
    match &s.lights[2].kind {
        LightKind::Distant { direction, irradiance, .. } => {
            assert!(direction.abs_diff_eq(Vec3::new(0.0, -1.0, 0.0), 1e-6));
            assert!(irradiance.abs_diff_eq(Vec3::splat(pi), 1e-5));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn macros_loops_and_rand_place_objects() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        &format!(
            "{CAMERA}
#declare S = seed(42);
#macro Ball(P) sphere {{ P, 0.1 pigment {{ rgb 1 }} }} #end
#for (I, 0, 2) Ball(<rand(S), I, 0>) #end
"
        ),
    );
    // POV-Ray 3.7's rand(seed(42)): 0.723582911241, 0.329979259598, 0.755761670357.
    let xs: Vec<f32> = s.spheres().map(|(sp, _)| sp.center.x).collect();
    let want = [0.723_582_9, 0.329_979_26, 0.755_761_7];
    for (x, w) in xs.iter().zip(want) {
        assert!((x - w).abs() < 1e-6, "{xs:?}");
    }
    assert_eq!(xs.len(), 3);
}

#[test]
fn includes_are_found_beside_the_scene_and_in_the_include_folders() {
    let dir = tempfile::tempdir().unwrap();
    let inc = tempfile::tempdir().unwrap();
    write(dir.path(), "local.inc", "#declare Local = 2;\n");
    write(inc.path(), "lib.inc", "#declare Lib = 3;\n#include \"local.inc\"\n");
    let p = write(
        dir.path(),
        "scene.pov",
        &format!("#include \"lib.inc\"\n{CAMERA}sphere {{ <Local, Lib, 0>, 1 pigment {{ rgb 1 }} }}\n"),
    );
    let o = PovOptions { include_dirs: vec![inc.path().to_path_buf()], ..options() };
    let s = load_pov(&p, &o).unwrap();
    let c = s.spheres().next().unwrap().0.center;
    assert!(c.abs_diff_eq(Vec3::new(2.0, 3.0, 0.0), 1e-6), "{c}");
    // A missing include names the folders it looked in.
    let p = write(dir.path(), "missing.pov", "#include \"nope.inc\"\n");
    let e = load_pov(&p, &o).unwrap_err().to_string();
    assert!(
        e.contains("missing.pov:1:1") && e.contains("nope.inc") && e.contains(&inc.path().display().to_string()),
        "{e}"
    );
}

#[test]
fn standard_includes_are_read_where_debian_installs_them() {
    if !Path::new(photonix::scene::pov::STANDARD_INCLUDE_DIR).join("colors.inc").is_file() {
        // ci/setup installs povray-includes; without it this test has nothing to read.
        eprintln!("skipped: povray-includes is not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        &format!("#include \"colors.inc\"\n#include \"textures.inc\"\n{CAMERA}sphere {{ 0, 1 pigment {{ Red }} }}\nplane {{ y, -1 texture {{ pigment {{ Jade }} }} }}\nsphere {{ x * 3, 1 texture {{ Polished_Chrome }} }}\n"),
    );
    let m = &s.materials[s.shapes[0].material as usize];
    // Red is rgb <1, 0, 0> with POV-Ray's default diffuse 0.6.
    match &m.kind {
        photonix::scene::MaterialKind::Diffuse { reflectance } => {
            assert!(reflectance.value.abs_diff_eq(Vec3::new(0.6, 0.0, 0.0), 1e-6), "{:?}", reflectance.value)
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn errors_point_at_the_pov_file_and_its_includes() {
    let dir = tempfile::tempdir().unwrap();
    let e = error(dir.path(), &format!("{CAMERA}\nsphere {{ <0, 0, 0>, 1\n  pigment {{ rgb Nope }} }}\n"));
    assert!(e.contains("scene.pov:5:17") && e.contains("unknown identifier `Nope`"), "{e}");
    write(dir.path(), "bad.inc", "#declare A = 1;\n#declare B = A +;\n");
    let e = error(dir.path(), "#include \"bad.inc\"\n");
    assert!(e.contains("bad.inc:2:17"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}isosurface {{ function {{ x }} }}\n"));
    assert!(e.contains("scene.pov:3:1") && e.contains("isosurface is not supported yet"), "{e}");
    // Found by the TOML checks, reported at the .pov line of the object.
    let e = error(dir.path(), &format!("{CAMERA}\n\ntorus {{ 1, 2 pigment {{ rgb 1 }} }}\n"));
    assert!(e.contains("scene.pov:5:1") && e.contains("minor_radius"), "{e}");
    let e = error(dir.path(), "camera { location 0 look_at z fisheye }");
    assert!(e.contains("scene.pov:1:31") && e.contains("fisheye"), "{e}");
}

#[test]
fn load_scene_and_the_command_line_read_pov_files() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "tiny.pov", &format!("{CAMERA}sphere {{ 0, 1 pigment {{ rgb 1 }} }}\n"));
    let s = load_scene(&p).unwrap();
    assert_eq!((s.camera.width, s.camera.height), (320, 240));
    assert_eq!(s.name, "tiny");
    let out = dir.path().join("tiny.toml");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_photonix"))
        .args(["convert", p.to_str().unwrap(), "-o", out.to_str().unwrap(), "--resolution", "32x24"])
        .status()
        .unwrap();
    assert!(status.success());
    // The TOML it writes is a scene of its own, with the same shapes.
    let t = load_scene(&out).unwrap();
    assert_eq!(bounds(&t), bounds(&s));
    assert_eq!((t.camera.width, t.camera.height), (32, 24));
}

/// A small xorshift for the fuzz cases (reproducible by case number).
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[test]
fn fuzzed_pov_text_never_panics() {
    let seed_text = format!(
        "{CAMERA}#declare S = seed(3);\n#macro M(A) sphere {{ A, 0.5 pigment {{ rgb <1, 0.5, 0> }} }} #end\n\
         #for (I, 0, 3) M(<I, rand(S), 0>) #end\n#while (0) #end\n#switch (2) #case (2) box {{ 0, 1 }} #break #end\n\
         union {{ cylinder {{ 0, y, 0.2 }} cone {{ 0, 1, y, 0 }} rotate <10, 20, 30> texture {{ pigment {{ checker rgb 1 rgb 0 scale 0.2 }} finish {{ phong 1 }} }} }}\n\
         #declare A = array[2] {{ 1, 2 }}\ntorus {{ A[0], 0.25 }}\n"
    );
    let alphabet: &[u8] = b"{}()<>[],;.#\"+-*/=!&|?: 0123456789xyzabcdeif\n";
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fuzz.pov");
    let cases = std::env::var("PHOTONIX_POV_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(300u64);
    for case in 0..cases {
        let mut st = 0x9e37_79b9_7f4a_7c15 ^ (case + 1).wrapping_mul(0x2545_f491_4f6c_dd1d);
        let mut bytes = seed_text.as_bytes().to_vec();
        for _ in 0..1 + xorshift(&mut st) % 6 {
            let i = (xorshift(&mut st) % bytes.len() as u64) as usize;
            match xorshift(&mut st) % 4 {
                0 => {
                    bytes.remove(i);
                }
                1 => bytes.insert(i, alphabet[(xorshift(&mut st) % alphabet.len() as u64) as usize]),
                2 => bytes[i] = alphabet[(xorshift(&mut st) % alphabet.len() as u64) as usize],
                _ => {
                    let j = (xorshift(&mut st) % bytes.len() as u64) as usize;
                    let k = (j + (xorshift(&mut st) % 40) as usize).min(bytes.len());
                    let chunk = bytes[j..k].to_vec();
                    bytes.splice(i..i, chunk);
                }
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        let result = std::panic::catch_unwind(|| {
            let mut o = options();
            o.include_dirs.clear();
            match translate_file(&path, &o) {
                // Every error names the file.
                Err(e) => assert!(e.to_string().contains("fuzz.pov"), "{e}"),
                Ok(t) => {
                    let _ = parse_scene(&t.toml, &path);
                }
            }
        });
        assert!(result.is_ok(), "case {case} panicked on:\n{}", String::from_utf8_lossy(&bytes));
    }
}

#[test]
fn the_editor_opens_a_pov_scene_as_its_toml_translation() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "edit.pov", &format!("{CAMERA}sphere {{ 0, 1 pigment {{ rgb 1 }} }}\n"));
    let doc = photonix::editor::SceneDocument::load(&p).unwrap();
    // It saves beside the .pov as TOML, and nothing is written until the user saves.
    assert_eq!(doc.path(), dir.path().join("edit.toml"));
    assert!(doc.text().contains("[[shapes]]"));
    assert!(doc.dirty());
    assert!(!dir.path().join("edit.toml").exists());
}

#[test]
fn inverse_in_csg_is_written_as_a_difference() {
    let dir = tempfile::tempdir().unwrap();
    let toml = |text: &str| {
        let p = write(dir.path(), "inv.pov", &format!("{CAMERA}{text}"));
        let t = translate_file(&p, &options()).unwrap().toml;
        // Drop the comment lines, which name .pov positions.
        t.lines().filter(|l| !l.starts_with('#')).collect::<Vec<_>>().join("\n")
    };
    let a = toml("intersection { sphere { 0, 1 } sphere { x, 1 inverse } pigment { rgb 1 } }\n");
    let b = toml("difference { sphere { 0, 1 } sphere { x, 1 } pigment { rgb 1 } }\n");
    assert_eq!(a, b);
    // difference { A, inverse B } keeps what is in both.
    let c = toml("difference { sphere { 0, 1 } sphere { x, 1 inverse } pigment { rgb 1 } }\n");
    let d = toml("intersection { sphere { 0, 1 } sphere { x, 1 } pigment { rgb 1 } }\n");
    assert_eq!(c, d);
}

#[test]
fn arrays_hold_objects_and_textures() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        &format!(
            "{CAMERA}#declare O = array[2] {{ sphere {{ 0, 1 }}, sphere {{ x * 3, 1 }} }}
#declare T = array[1] {{ texture {{ pigment {{ rgb <0, 0, 1> }} }} }}
object {{ O[1] texture {{ T[0] }} }}
"
        ),
    );
    let (sphere, m) = s.spheres().next().unwrap();
    assert!(sphere.center.abs_diff_eq(Vec3::new(3.0, 0.0, 0.0), 1e-6));
    match &s.materials[m as usize].kind {
        photonix::scene::MaterialKind::Diffuse { reflectance } => {
            assert!(reflectance.value.abs_diff_eq(Vec3::new(0.0, 0.0, 0.6), 1e-6))
        }
        other => panic!("{other:?}"),
    }
}

/// The bounds of all shapes together.
fn total_bounds(s: &Scene) -> (Vec3, Vec3) {
    bounds(s).into_iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(a, b), (c, d)| (a.min(c), b.max(d)))
}

/// The area of a scene's triangles (every shape here is a triangle).
fn triangle_area(s: &Scene) -> f32 {
    s.shapes
        .iter()
        .map(|sh| match &sh.geometry {
            Geometry::Triangle(t) => {
                0.5 * (t.vertices[1] - t.vertices[0]).cross(t.vertices[2] - t.vertices[0]).length()
            }
            other => panic!("not a triangle: {other:?}"),
        })
        .sum()
}

#[test]
fn tessellated_shapes_match_the_same_shapes_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    // A linear prism of a 2 x 2 square from y = 0 to 1 is a box: same bounds and the box's area.
    let prism = load(
        dir.path(),
        &format!(
            "{CAMERA}prism {{ 0, 1, 5, <-1, -1>, <1, -1>, <1, 1>, <-1, 1>, <-1, -1> translate z pigment {{ rgb 1 }} }}"
        ),
    );
    let boxed = parse_scene(
        "[camera]\nposition = [0, 2, 6]\nlook_at = [0, 1, 0]\nfov = 40\n[materials.w]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"box\"\nmaterial = \"w\"\nmin = [-1, 0, -2]\nmax = [1, 1, 0]\n",
        Path::new("box.toml"),
    )
    .unwrap();
    let (a, b) = (total_bounds(&prism), total_bounds(&boxed));
    assert!(a.0.abs_diff_eq(b.0, 1e-6) && a.1.abs_diff_eq(b.1, 1e-6), "{a:?} vs {b:?}");
    let area = triangle_area(&prism);
    println!("prism area {area} (box 16)");
    assert!((area - 16.0).abs() < 1e-4);

    // A lathe of the profile <1, 0> <1, 2> is an open cylinder: within the revolution's chord
    // tolerance (1 - cos(pi / 64) of the radius) of the TOML cylinder's bounds.
    let lathe = load(dir.path(), &format!("{CAMERA}lathe {{ linear_spline 2, <1, 0>, <1, 2> pigment {{ rgb 1 }} }}"));
    let cyl = parse_scene(
        "[camera]\nposition = [0, 2, 6]\nlook_at = [0, 1, 0]\nfov = 40\n[materials.w]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"cylinder\"\nmaterial = \"w\"\nbase = [0, 0, 0]\ncap = [0, 2, 0]\nradius = 1\nopen = true\n",
        Path::new("cyl.toml"),
    )
    .unwrap();
    let (a, b) = (total_bounds(&lathe), total_bounds(&cyl));
    assert!(a.0.abs_diff_eq(b.0, 2e-3) && a.1.abs_diff_eq(b.1, 2e-3), "{a:?} vs {b:?}");
    // Its area is the 64-gon prism's: 2 h 64 sin(pi / 64) against the cylinder's 2 pi r h.
    let want = 2.0 * 64.0 * (std::f32::consts::PI / 64.0).sin() * 2.0;
    assert!((triangle_area(&lathe) - want).abs() < 1e-3, "{} vs {want}", triangle_area(&lathe));

    // bicubic_patch is Photonix's own patch, points mirrored in z.
    let pts = "<0,0,0>, <1,0,0>, <2,0,0>, <3,0,0>, <0,1,1>, <1,1,1>, <2,1,1>, <3,1,1>, <0,2,1>, <1,2,1>, <2,2,1>, <3,2,1>, <0,3,0>, <1,3,0>, <2,3,0>, <3,3,0>";
    let patch = load(
        dir.path(),
        &format!("{CAMERA}bicubic_patch {{ type 1 flatness 0.01 u_steps 4 v_steps 4 {pts} pigment {{ rgb 1 }} }}"),
    );
    let toml_pts = "[0,0,0], [1,0,0], [2,0,0], [3,0,0], [0,1,-1], [1,1,-1], [2,1,-1], [3,1,-1], [0,2,-1], [1,2,-1], [2,2,-1], [3,2,-1], [0,3,0], [1,3,0], [2,3,0], [3,3,0]";
    let same = parse_scene(
        &format!("[camera]\nposition = [0, 2, 6]\nlook_at = [0, 1, 0]\nfov = 40\n[materials.w]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"bicubic_patch\"\nmaterial = \"w\"\npoints = [{toml_pts}]\n"),
        Path::new("patch.toml"),
    )
    .unwrap();
    assert_eq!(patch.shapes.len(), same.shapes.len());
    assert_eq!(bounds(&patch), bounds(&same));

    // mesh2 is its triangles; polygon a square of area 4.
    let mesh2 = load(
        dir.path(),
        &format!("{CAMERA}mesh2 {{ vertex_vectors {{ 4, <0,0,0>, <1,0,0>, <1,1,0>, <0,1,0> }} face_indices {{ 2, <0,1,2>, <0,2,3> }} pigment {{ rgb 1 }} }}"),
    );
    assert_eq!(mesh2.shapes.len(), 2);
    assert!((triangle_area(&mesh2) - 1.0).abs() < 1e-6);
    let polygon =
        load(dir.path(), &format!("{CAMERA}polygon {{ 5, <0,0>, <2,0>, <2,2>, <0,2>, <0,0> pigment {{ rgb 1 }} }}"));
    assert!((triangle_area(&polygon) - 4.0).abs() < 1e-5);

    // sor with a constant radius 1 from y = 0 to 1, closed: a capped 64-gon prism's area.
    let sor = load(dir.path(), &format!("{CAMERA}sor {{ 4, <1, -1>, <1, 0>, <1, 1>, <1, 2> pigment {{ rgb 1 }} }}"));
    // The 64-gon's perimeter times the height 1, and two 64-gon caps.
    let pi = std::f32::consts::PI;
    let want = 128.0 * (pi / 64.0).sin() + 2.0 * 32.0 * (2.0 * pi / 64.0).sin();
    assert!((triangle_area(&sor) - want).abs() < 1e-3, "{} vs {want}", triangle_area(&sor));
}

#[test]
fn text_is_drawn_from_povray_fonts() {
    let font = Path::new(photonix::scene::pov::STANDARD_INCLUDE_DIR).join("timrom.ttf");
    if !font.is_file() {
        println!("skipped: {} is not installed (apt-get install povray-includes)", font.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let s = load(dir.path(), &format!("{CAMERA}text {{ ttf \"timrom.ttf\" \"Hi\" 0.25, 0 pigment {{ rgb 1 }} }}"));
    let (lo, hi) = total_bounds(&s);
    // On the baseline from x = 0, under one em high, from z = 0 to 0.25 (mirrored: -0.25 to 0).
    println!("text bounds {lo} {hi}");
    assert!(lo.x >= 0.0 && hi.x < 2.0 && lo.y >= -0.3 && hi.y <= 1.0);
    assert!((lo.z + 0.25).abs() < 1e-6 && hi.z.abs() < 1e-6);
    let e = error(dir.path(), &format!("{CAMERA}text {{ ttf \"nosuchfont\" \"Hi\" 1, 0 }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("nosuchfont.ttf"), "{e}");
}

#[test]
fn equations_blobs_and_clipped_by_are_meshed_within_their_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    // The unit sphere as a quadric and as a quartic (x^2 + y^2 + z^2)^2 = 1 without bounds:
    // the mesh lies on the unit sphere to the bisection's tolerance.
    let on_sphere = |s: &Scene, r: f32, tol: f32| {
        let worst = s
            .shapes
            .iter()
            .flat_map(|sh| match &sh.geometry {
                Geometry::Triangle(t) => t.vertices.to_vec(),
                other => panic!("{other:?}"),
            })
            .map(|v| (v.length() - r).abs())
            .fold(0.0f32, f32::max);
        println!("{} triangles, at most {worst:.2e} off the sphere of radius {r}", s.shapes.len());
        assert!(worst < tol, "{worst}");
    };
    let q = load(
        dir.path(),
        &format!(
            "{CAMERA}quadric {{ <1,1,1>, <0,0,0>, <0,0,0>, -1 bounded_by {{ box {{ -2, 2 }} }} pigment {{ rgb 1 }} }}"
        ),
    );
    // Cell 4/40, bisected 10 times, plus f32 rounding.
    on_sphere(&q, 1.0, 4.0 / 40.0 / 1024.0 * 2.0 + 1e-5);
    let mut c = vec!["0"; 35];
    // (x^2 + y^2 + z^2)^2 - 1: x^4, 2x^2y^2, 2x^2z^2, y^4, 2y^2z^2, z^4 in POV-Ray's order.
    for (i, v) in [(0, "1"), (4, "2"), (7, "2"), (20, "1"), (23, "2"), (30, "1"), (34, "-1")] {
        c[i] = v;
    }
    let quartic = load(dir.path(), &format!("{CAMERA}quartic {{ <{}> pigment {{ rgb 1 }} }}", c.join(", ")));
    on_sphere(&quartic, 1.0, 0.01);
    // One blob component of strength 1 and radius 2, threshold 0.25: the field 1 (1 - d^2/4)^2
    // is 0.25 where d^2 = 2.
    let blob = load(dir.path(), &format!("{CAMERA}blob {{ threshold 0.25 sphere {{ 0, 2, 1 }} pigment {{ rgb 1 }} }}"));
    on_sphere(&blob, 2f32.sqrt(), 0.01);
    // clipped_by a plane is the intersection, in Photonix's own CSG.
    let clipped =
        load(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 clipped_by {{ plane {{ y, 0 }} }} pigment {{ rgb 1 }} }}"));
    assert!(matches!(clipped.shapes[0].geometry, Geometry::Csg(_)));
    let (lo, hi) = clipped.shapes[0].geometry.bounds();
    println!("clipped sphere bounds {lo} {hi}");
    // The unbounded: an infinite cylinder with nothing to cut it is refused where it is.
    let e = error(dir.path(), &format!("{CAMERA}quadric {{ <1,0,1>, <0,0,0>, <0,0,0>, -1 }}"));
    assert!(e.contains("scene.pov:3:1") && e.contains("unbounded"), "{e}");
    // A lathe in a difference is meshed with the rest (ray parity inside the lathe).
    let d = load(
        dir.path(),
        &format!("{CAMERA}difference {{ box {{ -1, 1 }} lathe {{ linear_spline 4, <0, -2>, <0.5, -2>, <0.5, 2>, <0, 2> }} pigment {{ rgb 1 }} }}"),
    );
    let (lo, hi) = total_bounds(&d);
    assert!(lo.abs_diff_eq(Vec3::splat(-1.0), 0.06) && hi.abs_diff_eq(Vec3::ONE, 0.06), "{lo} {hi}");
}

#[test]
fn file_output_and_errors_of_the_new_shapes_have_positions() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        &format!("{CAMERA}#fopen F \"page.html\" write\n#write (F, \"<p>\", 2, \"</p>\")\n#fclose F\nsphere {{ 0, 1 pigment {{ rgb 1 }} }}"),
    );
    assert_eq!(s.shapes.len(), 1);
    assert!(!dir.path().join("page.html").exists(), "nothing is written");
    let e = error(dir.path(), &format!("{CAMERA}lathe {{ bezier_spline 3, <0,0>, <1,1>, <0,2> }}"));
    assert!(e.contains("scene.pov:3:1") && e.contains("four per segment"), "{e}");
    let e = error(
        dir.path(),
        &format!("{CAMERA}mesh2 {{ vertex_vectors {{ 1, <0,0,0> }} face_indices {{ 1, <0,1,2> }} }}"),
    );
    assert!(e.contains("scene.pov:3:") && e.contains("out of range"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}poly {{ 4, <1, 2, 3> }}"));
    assert!(e.contains("takes 35 coefficients"), "{e}");
}

/// The translated TOML of a scene, parsed, and the translation's warnings.
fn translated(dir: &Path, text: &str) -> (toml::Table, Vec<String>) {
    let p = write(dir, "scene.pov", text);
    let t = translate_file(&p, &options()).unwrap_or_else(|e| panic!("{e}"));
    // The translation must also load.
    load_pov(&p, &options()).unwrap_or_else(|e| panic!("{e}"));
    (t.toml.parse::<toml::Table>().unwrap(), t.warnings)
}

fn float(v: &toml::Value) -> f64 {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64)).unwrap_or(f64::NAN)
}

fn floats(v: &toml::Value) -> Vec<f64> {
    v.as_array().map(|a| a.iter().map(float).collect()).unwrap_or_default()
}

/// The one material of a translated scene that has `field`.
fn material_with<'a>(t: &'a toml::Table, field: &str) -> &'a toml::Table {
    let ms = t["materials"].as_table().unwrap();
    let found: Vec<_> = ms.values().filter_map(|m| m.as_table()).filter(|m| m.contains_key(field)).collect();
    assert_eq!(found.len(), 1, "{ms:?}");
    found[0]
}

#[test]
fn normals_become_bump_maps_of_the_documented_strength() {
    let dir = tempfile::tempdir().unwrap();
    // bumps: strength 0.5 x amount x the pattern's scale; the pattern placed as in POV-Ray.
    let (t, _) = translated(
        dir.path(),
        &format!("{CAMERA}sphere {{ 0, 1 pigment {{ rgb 1 }} normal {{ bumps 0.4 scale 0.5 }} }}"),
    );
    let bump = material_with(&t, "bump")["bump"].as_table().unwrap();
    assert!((float(&bump["scale"]) - 0.5 * 0.4 * 0.5).abs() < 1e-12, "{bump:?}");
    let tex = &t["textures"][bump["texture"].as_str().unwrap()];
    assert_eq!(tex["pattern"].as_str(), Some("bumps"));
    assert_eq!(tex["space"].as_str(), Some("world"));
    assert_eq!(floats(&tex["transform"]["scale"]), [0.5, 0.5, -0.5]);
    // The same scene written in TOML loads to the same material.
    let same = parse_scene(
        "[camera]\nposition = [0, 2, 6]\nlook_at = [0, 1, 0]\nfov = 40\n[textures.b]\ntype = \"pattern\"\npattern = \"bumps\"\nspace = \"world\"\ntransform = { scale = [0.5, 0.5, -0.5] }\n[materials.w]\ntype = \"diffuse\"\nreflectance = 0.6\nbump = { texture = \"b\", scale = 0.1 }\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"w\"\ncenter = [0, 0, 0]\nradius = 1\n",
        Path::new("same.toml"),
    )
    .unwrap();
    let pov =
        load(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 pigment {{ rgb 1 }} normal {{ bumps 0.4 scale 0.5 }} }}"));
    let (a, b) = (&pov.materials[pov.shapes[0].material as usize], &same.materials[0]);
    assert_eq!(format!("{:?}", a.normal), format!("{:?}", b.normal));

    // Any other pattern: 5 x 0.02 x 4/3 x amount (POV-Ray's slope sampling); ripples: amount /
    // (pi frequency); a declared normal; bump_size; a normal in a texture.
    let (t, _) = translated(
        dir.path(),
        &format!(
            "{CAMERA}#declare N = normal {{ ripples frequency 2 bump_size 0.6 }}
sphere {{ 0, 1 pigment {{ rgb 1 }} normal {{ granite 0.6 }} }}
sphere {{ x, 1 texture {{ pigment {{ rgb <1, 0, 0> }} normal {{ N }} }} }}"
        ),
    );
    let scales: Vec<f64> =
        t["materials"].as_table().unwrap().values().filter_map(|m| m.get("bump")).map(|b| float(&b["scale"])).collect();
    assert_eq!(scales.len(), 2);
    assert!((scales[0] - 0.6 * 0.1 * 4.0 / 3.0).abs() < 1e-12, "{scales:?}");
    assert!((scales[1] - 0.6 / (std::f64::consts::PI * 2.0)).abs() < 1e-12, "{scales:?}");

    // A normal Photonix has no pattern for leaves the surface smooth, with a warning.
    let (t, warnings) =
        translated(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 pigment {{ rgb 1 }} normal {{ quilted 0.5 }} }}"));
    assert!(!t.to_string().contains("bump"));
    assert!(warnings.iter().any(|w| w.contains("scene.pov:3:") && w.contains("quilted")), "{warnings:?}");
    let e = error(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 normal {{ bumps 0.5 colour_of_nothing }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("`colour_of_nothing` does not belong in a normal"), "{e}");
}

#[test]
fn height_fields_are_meshed_from_images() {
    let dir = tempfile::tempdir().unwrap();
    // A 3 x 2 PGM: row 0 (the image's top) lies at z = 1 in POV-Ray, -1 here.
    std::fs::write(dir.path().join("h.pgm"), "P2 3 2 10\n0 5 10\n10 10 10\n").unwrap();
    let s = load(dir.path(), &format!("{CAMERA}height_field {{ pgm \"h.pgm\" smooth pigment {{ rgb 1 }} }}"));
    let tops: Vec<[Vec3; 3]> = s
        .shapes
        .iter()
        .filter_map(|sh| match &sh.geometry {
            Geometry::Triangle(t) => Some(t.vertices),
            _ => None,
        })
        .collect();
    // Heights at the grid points, x = i / 2, z = -(1 - j).
    let h = |i: usize, j: usize| [[0.0, 0.5, 1.0], [1.0, 1.0, 1.0]][j][i];
    let p = |i: usize, j: usize| Vec3::new(i as f32 / 2.0, h(i, j), -(1.0 - j as f32));
    for j in 0..2 {
        for i in 0..3 {
            assert!(
                tops.iter().any(|t| t.iter().any(|v| v.abs_diff_eq(p(i, j), 1e-6))),
                "no vertex at {} for pixel ({i}, {j})",
                p(i, j)
            );
        }
    }
    let (lo, hi) = total_bounds(&s);
    assert!(lo.abs_diff_eq(Vec3::new(0.0, 0.0, -1.0), 1e-6) && hi.abs_diff_eq(Vec3::new(1.0, 1.0, 0.0), 1e-6));
    // Closed: the top's 4 triangles, walls (those of no height dropped), the floor's 2.
    let area = triangle_area(&s);
    // Top: two cells; walls: front (z = -1, heights 0, 0.5, 1), back (all 1), sides; floor 1.
    let top = {
        let tri = |a: Vec3, b: Vec3, c: Vec3| 0.5 * (b - a).cross(c - a).length();
        tri(p(0, 0), p(1, 0), p(1, 1))
            + tri(p(0, 0), p(1, 1), p(0, 1))
            + tri(p(1, 0), p(2, 0), p(2, 1))
            + tri(p(1, 0), p(2, 1), p(1, 1))
    };
    let walls = (0.5 * 0.5 * 0.5 + 0.5 * (0.5 + 1.0) * 0.5) + 1.0 + (0.0 + 1.0) / 2.0 + 1.0;
    println!("height field area {area}, want {}", top + walls + 1.0);
    assert!((area - (top + walls + 1.0)).abs() < 1e-5);

    // water_level leaves out what lies wholly below it.
    let wet =
        load(dir.path(), &format!("{CAMERA}height_field {{ pgm \"h.pgm\" water_level 0.75 pigment {{ rgb 1 }} }}"));
    assert!(wet.shapes.len() < s.shapes.len());

    // A palette PNG: the height is the palette index, not the colour (POV-Ray's rule).
    {
        let f = std::fs::File::create(dir.path().join("p.png")).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), 2, 2);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        let mut palette = vec![0u8; 256 * 3];
        palette[3 * 51..3 * 51 + 3].copy_from_slice(&[255, 255, 255]);
        enc.set_palette(palette);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[51, 51, 51, 51]).unwrap();
    }
    let flat = load(dir.path(), &format!("{CAMERA}height_field {{ png \"p.png\" pigment {{ rgb 1 }} }}"));
    let (_, hi) = total_bounds(&flat);
    assert!((hi.y - 0.2).abs() < 1e-6, "{hi}");

    // Errors name the place and the way out.
    let e = error(dir.path(), &format!("{CAMERA}height_field {{ png \"missing.png\" }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("missing.png"), "{e}");
    std::fs::write(dir.path().join("h.tiff"), [0u8; 18]).unwrap();
    let e = error(dir.path(), &format!("{CAMERA}height_field {{ tiff \"h.tiff\" }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("tiff images are not supported yet"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}height_field {{ function 10, 10 {{ x }} }}"));
    assert!(e.contains("scene.pov:3:16") && e.contains("user-defined functions"), "{e}");
    std::fs::write(dir.path().join("bad.pgm"), "P5 4 4 255\n\x01").unwrap();
    let e = error(dir.path(), &format!("{CAMERA}height_field {{ pgm \"bad.pgm\" }}"));
    assert!(e.contains("shorter than its header"), "{e}");
}

#[test]
fn sky_sphere_rainbow_and_media_map_onto_environment_and_media() {
    let dir = tempfile::tempdir().unwrap();
    let (t, _) = translated(
        dir.path(),
        &format!(
            "{CAMERA}sky_sphere {{ pigment {{ gradient y color_map {{ [0 rgb <1, 0, 0>] [1 rgb <0, 0, 1>] }} }} }}
rainbow {{ direction <0, 0, 1> angle 42.5 width 5 color_map {{ [0 rgbt <1, 0, 0, 0.5>] [1 rgbt <0, 0, 1, 0.5>] }} }}
media {{ scattering {{ 1, 0.01 }} }}
sphere {{ 0, 1 pigment {{ rgbt 1 }} hollow interior {{ media {{ absorption 0.5 scattering {{ 5, 0.3 eccentricity 0.4 }} emission 0.1 }} }} }}
box {{ 2, 3 pigment {{ rgbt 1 }} hollow interior {{ media {{ emission <1, 0, 0> density {{ spherical }} }} }} }}"
        ),
    );
    // The gradient's value at elevation e is sin e: at 30 degrees, halfway from red to blue.
    let env = t["environment"].as_table().unwrap();
    assert_eq!(env["type"].as_str(), Some("gradient"));
    let els = floats(&env["elevations"]);
    let at30 = els.iter().position(|e| *e == 30.0).unwrap();
    let c = floats(&env["colors"].as_array().unwrap()[at30]);
    assert!((c[0] - 0.5).abs() < 1e-3 && c[1].abs() < 1e-9 && (c[2] - 0.5).abs() < 1e-3, "{c:?}");
    // The rainbow: direction mirrored, strength from the map's transmit.
    let r = t["rainbow"].as_table().unwrap();
    assert_eq!(r["type"].as_str(), Some("pov"));
    assert_eq!(floats(&r["direction"]), [0.0, 0.0, -1.0]);
    assert!((float(&r["strength"]) - 0.5).abs() < 1e-12);
    // The atmosphere, and the sphere's medium inside a null boundary.
    let media = t["media"].as_table().unwrap();
    let atmo = &media[t["atmosphere"]["medium"].as_str().unwrap()];
    assert_eq!(floats(&atmo["sigma_s"]), [0.01; 3]);
    let shapes = t["shapes"].as_array().unwrap();
    let ball = &media[shapes[0]["interior"].as_str().unwrap()];
    assert_eq!(floats(&ball["sigma_a"]), [0.5; 3]);
    assert_eq!(floats(&ball["sigma_s"]), [0.3; 3]);
    assert_eq!(floats(&ball["emission"]), [0.1; 3]);
    assert_eq!(ball["phase"].as_str(), Some("henyey-greenstein"));
    assert!((float(&ball["g"]) - 0.4).abs() < 1e-12);
    let m = &t["materials"][shapes[0]["material"].as_str().unwrap()];
    assert_eq!(m["type"].as_str(), Some("null"));
    // A glow alone gets an absorption of 0.3 across its container (the box's diagonal is sqrt 3),
    // scaled like the rest by the density (a pattern Photonix lacks: its mean, 0.5).
    let glow = &media[shapes[1]["interior"].as_str().unwrap()];
    assert!((floats(&glow["sigma_a"])[0] - 0.5 * 0.3 / 3f64.sqrt()).abs() < 1e-9, "{glow:?}");
    assert_eq!(floats(&glow["sigma_a"])[1], 0.0);
    // The same scene's medium written in TOML loads alike.
    let s = load(dir.path(), &std::fs::read_to_string(dir.path().join("scene.pov")).unwrap());
    assert!(s.environment.is_some());

    // Errors with positions.
    let e = error(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 interior {{ media {{ scattering {{ 7, 1 }} }} }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("scattering type 7"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}sky_sphere {{ colour_of_nothing }}"));
    assert!(e.contains("scene.pov:3:14") && e.contains("does not belong in a sky_sphere"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}rainbow {{ direction 0 color_map {{ [0 rgb 1] [1 rgb 0] }} }}"));
    assert!(e.contains("scene.pov:3:1") && e.contains("direction is zero"), "{e}");
}

#[test]
fn pigment_maps_texture_maps_warps_and_image_maps_map_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    // A 2 x 1 PNG, red and blue: its mean linear colour is (0.5, 0, 0.5).
    image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255]).unwrap().save(dir.path().join("rb.png")).unwrap();
    let (t, warnings) = translated(
        dir.path(),
        &format!(
            "{CAMERA}sphere {{ 0, 1 pigment {{ image_map {{ png \"rb.png\" map_type 5 interpolate 2 once }} }} }}
sphere {{ x, 1 pigment {{ gradient x pigment_map {{ [0 rgb <1, 0, 0>] [1 checker rgb <0, 0, 1>, rgb <0, 1, 0>] }} warp {{ turbulence 0.5 octaves 3 }} }} }}
sphere {{ y, 1 texture {{ bozo texture_map {{ [0 pigment {{ rgb 1 }} finish {{ phong 1 }}] [1 pigment {{ rgb 0 }}] }} }} }}
sphere {{ z, 1 pigment {{ bozo warp {{ black_hole <0, 0, 0>, 1 }} }} }}"
        ),
    );
    let ms = t["materials"].as_table().unwrap();
    let image = ms.values().find(|m| m["type"].as_str() == Some("diffuse") && m["reflectance"].is_array()).unwrap();
    let c = floats(&image["reflectance"]);
    assert!((c[0] - 0.3).abs() < 1e-9 && c[1] == 0.0 && (c[2] - 0.3).abs() < 1e-9, "{c:?}");
    assert!(warnings.iter().any(|w| w.contains("image_map: map_type 5 is not supported")), "{warnings:?}");
    // pigment_map with a patterned entry: the entries' materials mixed by the gradient (its ramp
    // from the first entry's value to the second's), the warp's turbulence kept.
    let textures = t["textures"].as_table().unwrap();
    let mix_by = |pattern: &str| {
        ms.values()
            .filter(|m| m["type"].as_str() == Some("mix") && m["weight"].is_table())
            .find(|m| textures[m["weight"]["texture"].as_str().unwrap()]["pattern"].as_str() == Some(pattern))
            .unwrap_or_else(|| panic!("no mix weighed by {pattern}: {ms:?}"))
    };
    let grad = &textures[mix_by("gradient")["weight"]["texture"].as_str().unwrap()];
    let map = grad["color_map"].as_array().unwrap();
    assert_eq!(floats(&map[0].as_array().unwrap()[1]), [0.0; 3]);
    assert_eq!(floats(&map[1].as_array().unwrap()[1]), [1.0; 3]);
    assert_eq!(floats(&grad["turbulence"]), [0.5; 3]);
    assert_eq!(grad["octaves"].as_integer(), Some(3));
    let checker = &ms[mix_by("gradient")["materials"][1].as_str().unwrap()];
    let checks = &textures[checker["reflectance"]["texture"].as_str().unwrap()];
    assert_eq!(checks["pattern"].as_str(), Some("checker"));
    // texture_map: the entries' materials mixed by the pattern (tested below).
    let mix = mix_by("bozo");
    let [a, b] = [0, 1].map(|i| &ms[mix["materials"][i].as_str().unwrap()]);
    assert_eq!((a["type"].as_str(), b["type"].as_str()), (Some("plastic"), Some("diffuse")));
    // The black_hole warp: an entry of the bozo texture's `warp` list.
    let hole = textures.values().find(|t| t.get("warp").is_some()).unwrap_or_else(|| panic!("{textures:?}"));
    assert_eq!(hole["pattern"].as_str(), Some("bozo"));
    let w = &hole["warp"][0];
    assert_eq!((w["type"].as_str(), float(&w["radius"])), (Some("black_hole"), 1.0));
    assert_eq!(floats(&w["center"]), [0.0; 3]);
    let e = error(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 pigment {{ image_map {{ png \"none.png\" }} }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("none.png"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 pigment {{ image_map {{ once }} }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("names no image file"), "{e}");
    let e = error(dir.path(), &format!("{CAMERA}sphere {{ 0, 1 texture {{ material_map {{ png \"rb.png\" }} }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("material_map is not supported yet"), "{e}");
}

#[test]
fn declared_skies_densities_normals_and_function_entries_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let (t, warnings) = translated(
        dir.path(),
        &format!(
            "{CAMERA}#declare Sky = sky_sphere {{ pigment {{ rgb <0.2, 0.4, 0.8> }} }}
sky_sphere {{ Sky }}
#declare D = density {{ bozo color_map {{ [0 rgb 0] [1 rgb 1] }} }}
#declare Ns = array[2] {{ normal {{ dents 0.5 }}, normal {{ wrinkles 0.5 }} }}
sphere {{ 0, 1 pigment {{ rgbt 1 }} hollow interior {{ media {{ scattering {{ 1, 0.5 }} density {{ D scale 0.5 }} }} }} }}
sphere {{ x, 1 pigment {{ gradient x pigment_map {{ [0 function {{ x }} color_map {{ [0 rgb 0] [1 rgb 1] }}] [1 rgb 1] }} }} normal {{ Ns[1] }} }}"
        ),
    );
    assert_eq!(t["environment"]["type"].as_str(), Some("uniform"));
    assert_eq!(floats(&t["environment"]["radiance"]), [0.2, 0.4, 0.8]);
    let media = t["media"].as_table().unwrap();
    let density = media.values().next().unwrap()["density"].as_str().unwrap();
    assert_eq!(t["textures"][density]["pattern"].as_str(), Some("bozo"));
    assert!(t["textures"].as_table().unwrap().values().any(|x| x["pattern"].as_str() == Some("wrinkles")));
    assert!(warnings.iter().any(|w| w.contains("function pattern")), "{warnings:?}");
}

/// A planar image_map (map_type 0) becomes a world-space image texture: the translated scene
/// renders as the same scene whose texture is written by hand in TOML (the image's unit square
/// stretched onto the box's face), and the texture shows the image, not its mean colour.
#[test]
fn planar_image_map_renders_as_the_same_image_texture_written_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    let colours = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]];
    image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(colours[(2 * y + x) as usize]))
        .save(dir.path().join("q.png"))
        .unwrap();
    let (t, warnings) = translated(
        dir.path(),
        "camera { location <0, 0, -6> look_at <0, 0, 0> }\nlight_source { <0, 0, -6>, rgb 1 }\n\
         box { <-1, -1, 0>, <1, 1, 0.1> pigment { image_map { png \"q.png\" map_type 0 interpolate 2 once } \
         translate <-0.5, -0.5, 0> scale 2 } finish { ambient 0 diffuse 1 } }\n",
    );
    assert!(!warnings.iter().any(|w| w.contains("image_map")), "{warnings:?}");
    let textures = t["textures"].as_table().unwrap();
    let image = textures.values().find(|x| x["type"].as_str() == Some("image")).expect("an image texture");
    assert_eq!(image["file"].as_str(), Some("q.png"));
    assert_eq!(image["space"].as_str(), Some("world"));
    assert_eq!(image["projection"].as_str(), Some("planar"));
    assert_eq!(image["wrap"].as_str(), Some("clamp"));

    let pov = load(
        dir.path(),
        "camera { location <0, 0, -6> look_at <0, 0, 0> }\nlight_source { <0, 0, -6>, rgb 1 }\n\
         box { <-1, -1, 0>, <1, 1, 0.1> pigment { image_map { png \"q.png\" map_type 0 interpolate 2 once } \
         translate <-0.5, -0.5, 0> scale 2 } finish { ambient 0 diffuse 1 } }\n",
    );
    // The same texture by hand: texture-space (x, y) = ((X + 1) / 2, (Y + 1) / 2) of the hit
    // point (Photonix's z is POV-Ray's mirrored, which a planar image does not read).
    let toml = "[camera]\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 40\n\
        [textures.q]\ntype = \"image\"\nfile = \"q.png\"\nspace = \"world\"\nprojection = \"planar\"\nwrap = \"clamp\"\n\
        transform = { scale = 2, translate = [-1, -1, -1] }\n\
        [materials.m]\ntype = \"diffuse\"\nreflectance = { texture = \"q\" }\n\
        [[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = 1\n";
    let path = write(dir.path(), "by_hand.toml", toml);
    let by_hand = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(pov.textures.len(), 1, "{:?}", pov.textures);
    let mut swapped = pov.clone();
    swapped.textures = by_hand.textures.clone();
    let render = |s: &Scene| {
        let settings = photonix::render::FrameSettings { width: 32, height: 32, max_depth: 2, seed: 7 };
        let buffers = photonix::render::prepare(s, &settings).unwrap();
        photonix::render::render_cpu(&buffers, 1, None, 0, &mut |_, _| {}).image
    };
    let (a, b) = (render(&pov), render(&swapped));
    let error = photonix::io::metrics::rel_mse(&a, &b);
    assert!(error < 1e-6, "relMSE {error:.3e}");
    // The image reads as drawn, seen from POV-Ray's camera: the red texel's pixels lie above
    // the blue's and left of the green's.
    let centroid = |channel: usize| {
        let (mut sum, mut n) = ((0.0, 0.0), 0.0);
        for y in 0..32 {
            for x in 0..32 {
                let p = a.pixel(x, y);
                let others = (0..3).filter(|c| *c != channel).map(|c| p[c]).fold(0.0, f32::max);
                if p[channel] > 0.01 && p[channel] > 4.0 * others {
                    (sum, n) = ((sum.0 + x as f32, sum.1 + y as f32), n + 1.0);
                }
            }
        }
        assert!(n > 0.0, "no pixels of channel {channel}");
        (sum.0 / n, sum.1 / n)
    };
    let (red, green, blue) = (centroid(0), centroid(1), centroid(2));
    assert!(red.0 < green.0 - 1.0 && (red.1 - green.1).abs() < 1.0, "red {red:?}, green {green:?}");
    assert!(red.1 < blue.1 - 1.0 && (red.0 - blue.0).abs() < 1.0, "red {red:?}, blue {blue:?}");
}

/// The box of `TEXTURE_MAP`: red on its left half, a blue and white checker of unit squares
/// (POV-Ray's `scale 0.25` inside the map's `scale 4`) with a 30% reflection on its right.
const TEXTURE_MAP: &str = "camera { location <0, 0, -5> look_at <0, 0, 0> }\nlight_source { <0, 3, -6>, rgb 1 }\n\
box { <-2, -1, 0>, <2, 1, 0.1>
  texture {
    gradient x
    texture_map {
      [0.5 pigment { rgb <1, 0.1, 0.1> } finish { diffuse 1 }]
      [0.5 pigment { checker rgb <0.1, 0.1, 1>, rgb 1 scale 0.25 } finish { diffuse 1 reflection 0.3 }]
    }
    scale 4 translate -2 * x
  }
}\n";

/// A texture_map becomes mixes of its entries' materials weighed by the map's pattern: the
/// translated scene renders as the same scene written by hand in TOML, and its two halves show
/// the two textures.
#[test]
fn texture_map_renders_as_the_same_mix_written_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    let pov = load(dir.path(), TEXTURE_MAP);
    // By hand: POV-Ray's z mirrored (the scale's -1 on z); the light's intensity is pi d0^2,
    // d0 the distance from the light to where the camera looks (docs/pov-ray.md).
    let toml = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 53.13010235415598\n\
        [textures.checks]\ntype = \"pattern\"\npattern = \"checker\"\ncolors = [[0.1, 0.1, 1], [1, 1, 1]]\n\
        transform = { scale = [1, 1, -1], translate = [-2, 0, 0] }\n\
        [textures.halves]\ntype = \"pattern\"\npattern = \"gradient\"\ndirection = [1, 0, 0]\n\
        color_map = [[0.5, [0, 0, 0]], [0.5, [1, 1, 1]]]\ntransform = { scale = [4, 4, -4], translate = [-2, 0, 0] }\n\
        [materials.red]\ntype = \"diffuse\"\nreflectance = [1, 0.1, 0.1]\n\
        [materials.checks]\ntype = \"diffuse\"\nreflectance = { texture = \"checks\" }\n\
        [materials.shiny]\ntype = \"mirror\"\n\
        [materials.checks_reflecting]\ntype = \"mix\"\nmaterials = [\"checks\", \"shiny\"]\nweight = 0.3\n\
        [materials.halves]\ntype = \"mix\"\nmaterials = [\"red\", \"checks_reflecting\"]\nweight = { texture = \"halves\" }\n\
        [[shapes]]\ntype = \"box\"\nmaterial = \"halves\"\nmin = [-2, -1, -0.1]\nmax = [2, 1, 0]\n\
        [[lights]]\ntype = \"point\"\nposition = [0, 3, 6]\nintensity = 141.3716694115407\n";
    let by_hand = load_scene(&write(dir.path(), "by_hand.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
    let render = |s: &Scene| {
        let settings = photonix::render::FrameSettings { width: 40, height: 30, max_depth: 3, seed: 3 };
        let buffers = photonix::render::prepare(s, &settings).unwrap();
        photonix::render::render_cpu(&buffers, 2, None, 0, &mut |_, _| {}).image
    };
    let (a, b) = (render(&pov), render(&by_hand));
    let error = photonix::io::metrics::rel_mse(&a, &b);
    eprintln!("texture_map against the mix by hand: relMSE {error:.3e}");
    assert!(error < 1e-6, "relMSE {error:.3e}");
    // The box spans columns 8 to 32 and rows 9 to 21; x = 0 is column 20.
    let (mut red, mut blue, mut white) = (0, 0, 0);
    for y in 11..20 {
        for x in 10..19 {
            let p = a.pixel(x, y);
            assert!(p[0] > 3.0 * p[2] && p[0] > 0.05, "left half, pixel ({x}, {y}): {p:?}");
            red += 1;
        }
        for x in 22..31 {
            let p = a.pixel(x, y);
            assert!(p[2] >= p[0], "right half, pixel ({x}, {y}): {p:?}");
            if p[2] > 3.0 * p[0] {
                blue += 1;
            } else if p[0] > 0.05 && p[2] < 1.5 * p[0] {
                white += 1;
            }
        }
    }
    assert!(red == 81 && blue > 20 && white > 20, "red {red}, blue {blue}, white {white}");
}

/// The mixes' weights: a ramp of the pattern across the two entries each mix splits (POV-Ray's
/// linear blend), a listed pattern's own values, entries of one finish and constant colours as
/// one colour map, and the cap on nesting with its warning.
#[test]
fn texture_map_weights_ramp_between_entries_and_deep_maps_warn() {
    let dir = tempfile::tempdir().unwrap();
    let (t, warnings) = translated(
        dir.path(),
        &format!(
            "{CAMERA}sphere {{ 0, 1 texture {{ bozo turbulence 0.3 texture_map {{
  [0.2 pigment {{ rgb <1, 0, 0> }}] [0.6 pigment {{ rgb <0, 1, 0> }} finish {{ phong 1 }}] [0.9 pigment {{ rgb <0, 0, 1> }}] }} scale 2 }} }}
sphere {{ x, 1 texture {{ hexagon texture {{ pigment {{ rgb 1 }} }} texture {{ pigment {{ rgb 0 }} finish {{ phong 1 }} }} texture {{ pigment {{ bozo }} }} }} }}
sphere {{ y, 1 texture {{ gradient y texture_map {{ [0 pigment {{ rgb 0 }}] [1 pigment {{ rgb 1 }}] }} }} }}
sphere {{ z, 1 texture {{ gradient y texture_map {{ #for (I, 0, 16) [I / 16 pigment {{ rgb I / 16 }} finish {{ phong I / 16 + 0.1 }}] #end }} }} }}"
        ),
    );
    let textures = t["textures"].as_table().unwrap();
    let ms = t["materials"].as_table().unwrap();
    let mixes: Vec<&toml::Table> =
        ms.values().filter_map(|m| m.as_table()).filter(|m| m["type"].as_str() == Some("mix")).collect();
    let weight_of = |m: &toml::Table| &textures[m["weight"]["texture"].as_str().unwrap()];
    let ramps = |pattern: &str| -> Vec<Vec<f64>> {
        let mut r: Vec<Vec<f64>> = mixes
            .iter()
            .map(|m| weight_of(m))
            .filter(|w| w["pattern"].as_str() == Some(pattern))
            .map(|w| {
                let map = w["color_map"].as_array().unwrap();
                map.iter().map(|e| e.as_array().unwrap()).flat_map(|e| [float(&e[0]), floats(&e[1])[0]]).collect()
            })
            .collect();
        r.sort_by(|a, b| a.partial_cmp(b).unwrap());
        r
    };
    // Three entries: a mix of (entries 0, 1) and entry 2, weighed by the ramp from 0.6 to 0.9,
    // the inner one by the ramp from 0.2 to 0.6; the pattern keeps its turbulence and scale.
    assert_eq!(ramps("bozo"), [vec![0.2, 0.0, 0.6, 1.0], vec![0.6, 0.0, 0.9, 1.0]]);
    let bozo_weight = mixes.iter().map(|m| weight_of(m)).find(|w| w["pattern"].as_str() == Some("bozo")).unwrap();
    assert_eq!(floats(&bozo_weight["turbulence"]), [0.3; 3]);
    assert_eq!(floats(&bozo_weight["transform"]["scale"]), [2.0, 2.0, -2.0]);
    // A hexagon's three textures: its values 0, 0.5, 1; the upper half of each split weighs 1.
    let hexagon: Vec<Vec<f64>> = mixes
        .iter()
        .map(|m| weight_of(m))
        .filter(|w| w["pattern"].as_str() == Some("hexagon"))
        .map(|w| w["colors"].as_array().unwrap().iter().map(|c| floats(c)[0]).collect())
        .collect();
    assert_eq!(hexagon.len(), 2, "{hexagon:?}");
    assert!(hexagon.contains(&vec![0.0, 0.0, 1.0]) && hexagon.contains(&vec![0.0, 1.0, 1.0]), "{hexagon:?}");
    // Constant colours in one finish: the colour map itself, no mix.
    assert!(textures.values().any(|x| x["pattern"].as_str() == Some("gradient")
        && x.get("color_map").is_some_and(|m| floats(&m.as_array().unwrap()[1].as_array().unwrap()[1]) == [1.0; 3])));
    // 17 entries would nest 5 deep: the mean colours stand in, with a warning that says why.
    assert!(
        warnings.iter().any(|w| w.contains("scene.pov:7:")
            && w.contains("17 entries need mixes nested 5 deep and the renderer resolves 4")),
        "{warnings:?}"
    );
    assert_eq!(mixes.len(), 4, "{mixes:?}");
}

/// A palette GIF of `indices` (w x h) whose palette entry i is `colours[i]` (black beyond).
fn write_gif(path: &Path, w: u16, h: u16, indices: &[u8], colours: &[[u8; 3]]) {
    let mut palette = vec![0u8; 256 * 3];
    for (i, c) in colours.iter().enumerate() {
        palette[3 * i..3 * i + 3].copy_from_slice(c);
    }
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = gif::Encoder::new(file, w, h, &palette).unwrap();
    let frame = gif::Frame { width: w, height: h, buffer: std::borrow::Cow::Borrowed(indices), ..Default::default() };
    encoder.write_frame(&frame).unwrap();
}

/// TGA and GIF files as height fields (POV-Ray's heights: a GIF's palette index, a colour TGA's
/// red as the high byte and green as the low byte) and as image maps (the image itself, seen
/// where it is placed).
#[test]
fn tga_and_gif_images_make_height_fields_and_image_maps() {
    let dir = tempfile::tempdir().unwrap();
    // GIF: every pixel index 51 of a palette whose entry 51 is white: height 51 / 255 = 0.2.
    write_gif(
        &dir.path().join("h.gif"),
        2,
        2,
        &[51; 4],
        &[[0, 0, 0]; 51].iter().chain(&[[255, 255, 255]]).copied().collect::<Vec<_>>(),
    );
    let s = load(dir.path(), &format!("{CAMERA}height_field {{ gif \"h.gif\" pigment {{ rgb 1 }} }}"));
    let (_, hi) = total_bounds(&s);
    assert!((hi.y - 0.2).abs() < 1e-6, "{hi}");
    // TGA, 2 x 2 colour: red 128 and green 64 at the highest pixel: (255 x 128 + 64) / 65535.
    let mut tga = image::RgbImage::new(2, 2);
    tga.put_pixel(1, 0, image::Rgb([128, 64, 255]));
    tga.put_pixel(0, 1, image::Rgb([0, 200, 0]));
    tga.save(dir.path().join("h.tga")).unwrap();
    let s = load(dir.path(), &format!("{CAMERA}height_field {{ tga \"h.tga\" pigment {{ rgb 1 }} }}"));
    let (_, hi) = total_bounds(&s);
    let want = (255.0 * 128.0 + 64.0) / 65535.0;
    assert!((hi.y as f64 - want).abs() < 1e-6, "{hi}, want {want}");
    // A bare name's extension picks the format, as for PNG.
    load(dir.path(), &format!("{CAMERA}height_field {{ \"h.gif\" pigment {{ rgb 1 }} }}"));

    // Image maps: a 2 x 1 image, red then blue, over the box's face (as the planar PNG test).
    write_gif(&dir.path().join("rb.gif"), 2, 1, &[0, 1], &[[255, 0, 0], [0, 0, 255]]);
    image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255]).unwrap().save(dir.path().join("rb.tga")).unwrap();
    for (kind, file) in [("gif", "rb.gif"), ("tga", "rb.tga")] {
        let text = format!(
            "camera {{ location <0, 0, -6> look_at <0, 0, 0> }}\nlight_source {{ <0, 0, -6>, rgb 1 }}\n\
             box {{ <-1, -1, 0>, <1, 1, 0.1> pigment {{ image_map {{ {kind} \"{file}\" once }} \
             translate <-0.5, -0.5, 0> scale 2 }} finish {{ ambient 0 diffuse 1 }} }}\n"
        );
        let (t, warnings) = translated(dir.path(), &text);
        assert!(!warnings.iter().any(|w| w.contains("image_map")), "{warnings:?}");
        let image = t["textures"].as_table().unwrap().values().find(|x| x["type"].as_str() == Some("image")).unwrap();
        assert_eq!(image["file"].as_str(), Some(file));
        let scene = load(dir.path(), &text);
        let settings = photonix::render::FrameSettings { width: 16, height: 16, max_depth: 2, seed: 1 };
        let buffers = photonix::render::prepare(&scene, &settings).unwrap();
        let a = photonix::render::render_cpu(&buffers, 1, None, 0, &mut |_, _| {}).image;
        // Rows 6 to 9 cross the box's middle: red on the left, blue on the right.
        for y in 6..10 {
            let (l, r) = (a.pixel(6, y), a.pixel(9, y));
            assert!(l[0] > 4.0 * l[2] && l[0] > 0.01, "{kind}: left ({y}) {l:?}");
            assert!(r[2] > 4.0 * r[0] && r[2] > 0.01, "{kind}: right ({y}) {r:?}");
        }
    }
}

/// The vertex normals of each triangle shape, `None` for a flat one.
fn triangle_normals(s: &Scene) -> Vec<(Option<[Vec3; 3]>, [Vec3; 3])> {
    s.shapes
        .iter()
        .filter_map(|sh| match &sh.geometry {
            Geometry::Triangle(t) => Some((t.normals, t.vertices)),
            _ => None,
        })
        .collect()
}

/// Smooth shading comes through: smooth_triangle's and mesh2's normals as written, the same as
/// the triangle written by hand in TOML; lathes, sors and smooth height fields with normals from
/// their faces (a lathe of a cylinder's profile gets the cylinder's radial normals); polygons,
/// straight prisms and rough height fields stay flat.
#[test]
fn smooth_triangles_meshes_lathes_and_height_fields_are_shaded_smooth() {
    let dir = tempfile::tempdir().unwrap();
    let pov = load(
        dir.path(),
        &format!("{CAMERA}smooth_triangle {{ <0, 0, 0>, <0, 0, -1>, <1, 0, 0>, <0.3, 0, -1>, <0, 1, 0>, <0, 0.3, -1> pigment {{ rgb 1 }} }}"),
    );
    // By hand: z mirrored, the normals' too (and the vertices' order kept).
    let toml = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n[materials.m]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"triangle\"\nmaterial = \"m\"\n\
        vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\nnormals = [[0, 0, 1], [0.3, 0, 1], [0, 0.3, 1]]\n";
    let by_hand = load_scene(&write(dir.path(), "by_hand.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (triangle_normals(&pov), triangle_normals(&by_hand));
    let (na, nb) = (a[0].0.expect("smooth"), b[0].0.expect("smooth"));
    for k in 0..3 {
        assert!(na[k].abs_diff_eq(nb[k], 1e-6) && a[0].1[k].abs_diff_eq(b[0].1[k], 1e-6), "{a:?} against {b:?}");
    }
    // The scene format's checks on `normals`.
    for (normals, kind, want) in [
        ("[[0, 0, 1], [0, 0, 1]]", "triangle", "`normals` has 2 directions; a triangle takes one per vertex"),
        ("[[0, 0, 1], [0, 0, 0], [0, 0, 1]]", "triangle", "`normals`: direction 1 has no length"),
        ("[[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1]]", "quad", "normals"),
    ] {
        let vertices = if kind == "quad" {
            "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]"
        } else {
            "[[0, 0, 0], [1, 0, 0], [0, 1, 0]]"
        };
        let bad = format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n[materials.m]\ntype = \"diffuse\"\n\
             [[shapes]]\ntype = \"{kind}\"\nmaterial = \"m\"\nvertices = {vertices}\nnormals = {normals}\n"
        );
        let e = load_scene(&write(dir.path(), "bad.toml", &bad)).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("bad.toml:") && e.contains(want), "{e}");
    }
    // The winding side: the normals point as the face's winding normal does.
    let face = (b[0].1[1] - b[0].1[0]).cross(b[0].1[2] - b[0].1[0]);
    assert!(nb.iter().all(|n| n.dot(face) > 0.0), "{nb:?}");

    // mesh2: normal_vectors indexed by the face indices.
    let mesh2 = load(
        dir.path(),
        &format!(
            "{CAMERA}mesh2 {{ vertex_vectors {{ 3, <0, 0, 0>, <1, 0, 0>, <0, 1, 0> }} \
             normal_vectors {{ 3, <0, 0, -1>, <0.3, 0, -1>, <0, 0.3, -1> }} face_indices {{ 1, <0, 1, 2> }} pigment {{ rgb 1 }} }}"
        ),
    );
    let m = triangle_normals(&mesh2);
    assert!((0..3).all(|k| m[0].0.unwrap()[k].abs_diff_eq(nb[k], 1e-6)), "{m:?}");
    let e = error(
        dir.path(),
        &format!(
            "{CAMERA}mesh2 {{ vertex_vectors {{ 3, 0, x, y }} normal_vectors {{ 1, z }} \
             face_indices {{ 1, <0, 1, 2> }} normal_indices {{ 1, <0, 1, 5> }} }}"
        ),
    );
    assert!(e.contains("scene.pov:3:") && e.contains("normal index 1 is out of range"), "{e}");

    // A lathe of a cylinder's profile: every vertex normal is radial (to the 7 digits written).
    let lathe = load(dir.path(), &format!("{CAMERA}lathe {{ linear_spline 2, <1, 0>, <1, 1> pigment {{ rgb 1 }} }}"));
    let tris = triangle_normals(&lathe);
    assert!(tris.len() >= 64, "{}", tris.len());
    for (n, v) in &tris {
        let n = n.expect("a lathe is smooth");
        for k in 0..3 {
            let radial = Vec3::new(v[k].x, 0.0, v[k].z).normalize();
            assert!(n[k].dot(radial).abs() > 1.0 - 1e-5, "normal {} at {}", n[k], v[k]);
        }
    }
    // Straight-sided prisms and polygons stay flat; spline prisms and sors are smooth.
    let flat =
        load(dir.path(), &format!("{CAMERA}prism {{ 0, 1, 4, <0, 0>, <1, 0>, <1, 1>, <0, 0> pigment {{ rgb 1 }} }}"));
    assert!(triangle_normals(&flat).iter().all(|(n, _)| n.is_none()));
    let sor =
        load(dir.path(), &format!("{CAMERA}sor {{ 4, <0, 0>, <1, 0.2>, <0.8, 1>, <0, 1.2> pigment {{ rgb 1 }} }}"));
    assert!(triangle_normals(&sor).iter().filter(|(n, _)| n.is_some()).count() > 64);

    // Height fields: smooth ones' tops get normals, the walls and floor stay flat.
    std::fs::write(dir.path().join("h.pgm"), "P2 3 3 10\n0 5 10\n5 10 5\n10 5 0\n").unwrap();
    let rough = load(dir.path(), &format!("{CAMERA}height_field {{ pgm \"h.pgm\" pigment {{ rgb 1 }} }}"));
    assert!(triangle_normals(&rough).iter().all(|(n, _)| n.is_none()));
    let smooth = load(dir.path(), &format!("{CAMERA}height_field {{ pgm \"h.pgm\" smooth pigment {{ rgb 1 }} }}"));
    let ts = triangle_normals(&smooth);
    let top = ts.iter().filter(|(n, _)| n.is_some()).count();
    assert_eq!(top, 8, "the top's 8 triangles are smooth: {ts:?}");
    // At the middle vertex (the peak, height 1) the normals of the faces around it average to +y.
    for (n, v) in &ts {
        for k in 0..3 {
            if let Some(n) = n {
                assert!(n[k].y > 0.0, "{n:?}");
                if v[k].abs_diff_eq(Vec3::new(0.5, 1.0, -0.5), 1e-6) {
                    assert!(n[k].abs_diff_eq(Vec3::Y, 1e-5), "peak normal {}", n[k]);
                }
            }
        }
    }
}

/// Renders a scene at 40 x 30, 2 passes, on the CPU.
fn render_small(s: &Scene) -> photonix::io::image::Image {
    let settings = photonix::render::FrameSettings { width: 40, height: 30, max_depth: 3, seed: 3 };
    let buffers = photonix::render::prepare(s, &settings).unwrap();
    photonix::render::render_cpu(&buffers, 2, None, 0, &mut |_, _| {}).image
}

/// Counts the pixels of the box (columns 10 to 29, rows 9 to 20) that are clearly red and
/// clearly blue.
fn red_and_blue(image: &photonix::io::image::Image) -> (usize, usize) {
    let (mut red, mut blue) = (0, 0);
    for y in 9..21 {
        for x in 10..30 {
            let p = image.pixel(x, y);
            if p[0] > 3.0 * p[2] && p[0] > 0.05 {
                red += 1;
            } else if p[2] > 3.0 * p[0] && p[2] > 0.05 {
                blue += 1;
            }
        }
    }
    (red, blue)
}

/// Writes `image` to $PHOTONIX_TEST_PNGS/`name`.png when that is set, to look at.
fn look_at(name: &str, image: &photonix::io::image::Image) {
    if let Some(dir) = std::env::var_os("PHOTONIX_TEST_PNGS") {
        let path = Path::new(&dir).join(format!("{name}.png"));
        photonix::io::image::write_image(&path, image, 0.0).unwrap();
    }
}

const FLAT_CAMERA: &str = "camera { location <0, 0, -5> look_at <0, 0, 0> }\nlight_source { <0, 3, -6>, rgb 1 }\n";

/// The same camera and light in Photonix's coordinates (POV-Ray's z mirrored; the light's
/// intensity pi d0^2, d0 the distance from the light to where the camera looks).
const FLAT_CAMERA_TOML: &str = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 53.13010235415598\n\
    [[lights]]\ntype = \"point\"\nposition = [0, 3, 6]\nintensity = 141.3716694115407\n";

/// POV-Ray's `radial` (the angle around y) turned towards the camera, with frequency 4: eight
/// wedges, red and blue, as the same pattern written in TOML; and `tiles`, POV-Ray's checker of
/// two textures, as a checker pattern in TOML.
#[test]
fn radial_and_tiles_render_as_the_same_patterns_written_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    let radial = load(
        dir.path(),
        &format!(
            "{FLAT_CAMERA}box {{ <-2, -1.5, 0>, <2, 1.5, 0.1>
  pigment {{ radial frequency 4 color_map {{ [0.5 rgb <1, 0.1, 0.1>] [0.5 rgb <0.1, 0.1, 1>] }} rotate -90 * x }}
  finish {{ diffuse 1 }}
}}\n"
        ),
    );
    // world_from_pattern = mirror(z) * rotate(-90 x) = rotate(90 x) * mirror(z).
    let toml = format!(
        "{FLAT_CAMERA_TOML}[textures.wedges]\ntype = \"pattern\"\npattern = \"radial\"\nfrequency = 4\n\
        color_map = [[0.5, [1, 0.1, 0.1]], [0.5, [0.1, 0.1, 1]]]\n\
        transform = {{ scale = [1, 1, -1], rotate = [90, 0, 0] }}\n\
        [materials.wedges]\ntype = \"diffuse\"\nreflectance = {{ texture = \"wedges\" }}\n\
        [[shapes]]\ntype = \"box\"\nmaterial = \"wedges\"\nmin = [-2, -1.5, -0.1]\nmax = [2, 1.5, 0]\n"
    );
    let by_hand = load_scene(&write(dir.path(), "radial.toml", &toml)).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (render_small(&radial), render_small(&by_hand));
    let rel_mse = photonix::io::metrics::rel_mse(&a, &b);
    let (red, blue) = red_and_blue(&a);
    eprintln!("radial against TOML: relMSE {rel_mse:.3e}; {red} red and {blue} blue pixels");
    assert!(rel_mse < 1e-6, "relMSE {rel_mse:.3e}");
    // Eight wedges of equal angle: about as much red as blue.
    assert!(red > 80 && blue > 80 && red.abs_diff(blue) < 40, "red {red}, blue {blue}");
    look_at("radial", &a);

    let tiles = load(
        dir.path(),
        &format!(
            "{FLAT_CAMERA}box {{ <-2, -1.5, 0.2>, <2, 1.5, 0.3>
  texture {{
    tiles {{
      texture {{ pigment {{ rgb <1, 0.1, 0.1> }} finish {{ diffuse 1 }} }}
      tile2
      texture {{ pigment {{ rgb <0.1, 0.1, 1> }} finish {{ diffuse 1 }} }}
    }}
    scale 0.5
  }}
}}\n"
        ),
    );
    let toml = format!(
        "{FLAT_CAMERA_TOML}[textures.tiles]\ntype = \"pattern\"\npattern = \"checker\"\n\
        colors = [[1, 0.1, 0.1], [0.1, 0.1, 1]]\ntransform = {{ scale = [0.5, 0.5, -0.5] }}\n\
        [materials.tiles]\ntype = \"diffuse\"\nreflectance = {{ texture = \"tiles\" }}\n\
        [[shapes]]\ntype = \"box\"\nmaterial = \"tiles\"\nmin = [-2, -1.5, -0.3]\nmax = [2, 1.5, -0.2]\n"
    );
    let by_hand = load_scene(&write(dir.path(), "tiles.toml", &toml)).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (render_small(&tiles), render_small(&by_hand));
    let rel_mse = photonix::io::metrics::rel_mse(&a, &b);
    let (red, blue) = red_and_blue(&a);
    eprintln!("tiles against TOML: relMSE {rel_mse:.3e}; {red} red and {blue} blue pixels");
    assert!(rel_mse < 1e-6, "relMSE {rel_mse:.3e}");
    assert!(red > 80 && blue > 80 && red.abs_diff(blue) < 40, "red {red}, blue {blue}");
    look_at("tiles", &a);

    // What stays malformed names its place.
    let e = error(
        dir.path(),
        &format!("{FLAT_CAMERA}box {{ 0, 1 texture {{ tiles {{ texture {{ pigment {{ rgb 1 }} }} }} }} }}"),
    );
    assert!(e.contains("scene.pov:3:") && e.contains("tiles needs a texture on each side of `tile2`"), "{e}");
    let e = error(dir.path(), &format!("{FLAT_CAMERA}box {{ 0, 1 texture {{ tiles {{ pigment {{ rgb 1 }} }} }} }}"));
    assert!(e.contains("scene.pov:3:") && e.contains("expected `texture { ... }`, `tile2` or `}` in tiles"), "{e}");
}

/// Warps with transforms before and between them: the POV-Ray scene renders as the same pattern
/// written in TOML, each warp carrying the transforms written before it; and malformed warps
/// are errors at their place.
#[test]
fn warps_render_as_the_same_pattern_written_in_toml() {
    let dir = tempfile::tempdir().unwrap();
    let pov = load(
        dir.path(),
        &format!(
            "{FLAT_CAMERA}box {{ <-2, -1.5, 0>, <2, 1.5, 0.1>
  pigment {{
    gradient x color_map {{ [0.5 rgb <1, 0.1, 0.1>] [0.5 rgb <0.1, 0.1, 1>] }}
    scale 0.5
    warp {{ repeat x flip x }}
    rotate 30 * z
    warp {{ black_hole <0, 0, 0>, 1 strength 0.5 }}
  }}
  finish {{ diffuse 1 }}
}}\n"
        ),
    );
    let toml = format!(
        "{FLAT_CAMERA_TOML}[textures.warped]\ntype = \"pattern\"\npattern = \"gradient\"\ndirection = [1, 0, 0]\n\
        color_map = [[0.5, [1, 0.1, 0.1]], [0.5, [0.1, 0.1, 1]]]\n\
        warp = [{{ type = \"repeat\", direction = [1, 0, 0], flip = [1, 0, 0], transform = {{ scale = 0.5 }} }},\n\
        {{ type = \"black_hole\", center = [0, 0, 0], radius = 1, strength = 0.5, transform = {{ rotate = [0, 0, 30] }} }}]\n\
        transform = {{ scale = [1, 1, -1] }}\n\
        [materials.warped]\ntype = \"diffuse\"\nreflectance = {{ texture = \"warped\" }}\n\
        [[shapes]]\ntype = \"box\"\nmaterial = \"warped\"\nmin = [-2, -1.5, -0.1]\nmax = [2, 1.5, 0]\n"
    );
    let by_hand = load_scene(&write(dir.path(), "warped.toml", &toml)).unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (render_small(&pov), render_small(&by_hand));
    let rel_mse = photonix::io::metrics::rel_mse(&a, &b);
    let (red, blue) = red_and_blue(&a);
    eprintln!("warps against TOML: relMSE {rel_mse:.3e}; {red} red and {blue} blue pixels");
    look_at("warps", &a);
    assert!(rel_mse < 1e-6, "relMSE {rel_mse:.3e}");
    assert!(red > 60 && blue > 60, "red {red}, blue {blue}");
    // Without the warps the stripes would be straight and evenly spaced: the repeat's flip makes
    // pairs of equal colour meet at every other slab edge, so the two colours' shares differ
    // from the plain stripes' only where the black hole bends them; check the bending instead:
    // the TOML without the black hole renders differently.
    let straight = toml.replace(
        ",\n{ type = \"black_hole\", center = [0, 0, 0], radius = 1, strength = 0.5, transform = { rotate = [0, 0, 30] } }",
        "",
    );
    assert_ne!(straight, toml);
    let straight = load_scene(&write(dir.path(), "straight.toml", &straight)).unwrap_or_else(|e| panic!("{e}"));
    let c = render_small(&straight);
    assert!(photonix::io::metrics::rel_mse(&a, &c) > 1e-3, "the black hole changes nothing");

    // A warp that changes nothing here (planar: z = 0 on the box's face, which gradient x does
    // not read) after transforms: the same picture as those transforms without it, so the warp
    // takes the transforms before it exactly.
    let plain = |warp: &str| {
        format!(
            "{FLAT_CAMERA}box {{ <-2, -1.5, 0>, <2, 1.5, 0.1>
  pigment {{ gradient x color_map {{ [0.5 rgb <1, 0.1, 0.1>] [0.5 rgb <0.1, 0.1, 1>] }} scale 0.5 rotate 30 * z translate 0.1 * x {warp} }}
  finish {{ diffuse 1 }}
}}
"
        )
    };
    let (a, b) =
        (render_small(&load(dir.path(), &plain(""))), render_small(&load(dir.path(), &plain("warp { planar }"))));
    let rel_mse = photonix::io::metrics::rel_mse(&a, &b);
    assert!(rel_mse < 1e-6, "planar warp after transforms: relMSE {rel_mse:.3e}");
    look_at("rotated", &a);

    for (warp, message) in [
        ("warp { repeat <1, 1, 0> }", "a repeat warp repeats along one axis"),
        ("warp { repeat x sideways 1 }", "`sideways` does not belong in a repeat warp"),
        ("warp { spiral }", "`spiral` is not a warp"),
        ("warp { black_hole 0, -1 }", "a black_hole's radius must be > 0"),
    ] {
        let e = error(dir.path(), &format!("{FLAT_CAMERA}sphere {{ 0, 1 pigment {{ bozo {warp} }} }}"));
        assert!(e.contains("scene.pov:3:") && e.contains(message), "{warp}: {e}");
    }
}

/// `checker pigment { A } pigment { B }` (POV-Ray's pigments as a checker's entries): the two
/// pigments mixed by the checker's own values, as a checker's textures are.
#[test]
fn a_checkers_pigments_are_mixed_by_the_checker() {
    let dir = tempfile::tempdir().unwrap();
    let (t, _) = translated(
        dir.path(),
        &format!(
            "{CAMERA}box {{ 0, 1 pigment {{ checker pigment {{ rgb <1, 0, 0> }} pigment {{ bozo color_map {{ [0 rgb 0] [1 rgb 1] }} }} }} }}"
        ),
    );
    let ms = t["materials"].as_table().unwrap();
    let textures = t["textures"].as_table().unwrap();
    let mix = ms
        .values()
        .find(|m| m["type"].as_str() == Some("mix") && m["weight"].is_table())
        .unwrap_or_else(|| panic!("no mix: {ms:?}"));
    let weight = &textures[mix["weight"]["texture"].as_str().unwrap()];
    assert_eq!(weight["pattern"].as_str(), Some("checker"));
    let [a, b] = [0, 1].map(|i| &ms[mix["materials"][i].as_str().unwrap()]);
    assert_eq!(floats(&a["reflectance"])[1], 0.0, "{a:?}");
    let bozo = &textures[b["reflectance"]["texture"].as_str().unwrap()];
    assert_eq!(bozo["pattern"].as_str(), Some("bozo"));
}

/// `looks_like`: the object, moved to the light, becomes the light: a diffuse emitter of the
/// object's colour whose radiance L = 4 I / A gives the point light's power 4 pi I over its area
/// A (a uniform sphere then lights everything outside it as the point at its centre does).
#[test]
fn looks_like_objects_become_their_lights() {
    let dir = tempfile::tempdir().unwrap();
    let pi = std::f64::consts::PI;
    // The light ends at <0, 1, 0>, 5 units from where the camera looks: I = pi d^2 = 25 pi.
    let scene = |shape: &str| {
        format!(
            "camera {{ location <0, 1, -6> look_at <0, 1, 5> }}
light_source {{ <0, 4, 0>, rgb <1, 0.5, 0.25> looks_like {{ {shape} }} translate <0, -3, 0> }}
plane {{ y, 0 pigment {{ rgb 0.8 }} }}"
        )
    };
    let (t, warnings) = translated(dir.path(), &scene("sphere { 0, 0.5 pigment { rgb <0.9, 0.9, 0.7> } }"));
    assert!(t.get("lights").is_none(), "{t:?}");
    assert!(warnings.is_empty(), "{warnings:?}");
    let shapes = t["shapes"].as_array().unwrap();
    let ball = shapes.iter().find(|s| s["type"].as_str() == Some("sphere")).unwrap();
    // Moved to the light's position, then with the light's transforms: <0, 4, 0> -> <0, 1, 0>.
    let c = floats(&ball["center"]);
    assert!(c[0].abs() < 1e-9 && (c[1] - 1.0).abs() < 1e-9 && c[2].abs() < 1e-9, "{c:?}");
    let m = &t["materials"][ball["material"].as_str().unwrap()];
    assert_eq!(m["type"].as_str(), Some("diffuse"));
    assert_eq!(floats(&m["reflectance"])[2], 0.7 * 0.6);
    // L = 4 I / (4 pi r^2) = I / (pi r^2); the area is integrated, within 1e-5.
    let e = floats(&m["emission"]);
    let want = 25.0 * pi / (pi * 0.25);
    for (got, c) in e.iter().zip([1.0, 0.5, 0.25]) {
        assert!((got / (want * c) - 1.0).abs() < 1e-5, "{e:?} vs {want}");
    }

    // A box's, a torus's and a closed cylinder's areas, and a union's (the sum).
    let emission = |shape: &str| {
        let (t, _) = translated(dir.path(), &scene(shape));
        let ms = t["materials"].as_table().unwrap();
        let m = ms.values().find(|m| m.get("emission").is_some()).unwrap();
        floats(&m["emission"])[0]
    };
    let area = |shape: &str| 4.0 * 25.0 * pi / emission(shape);
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-5;
    assert!(close(area("box { -1, <1, 0.5, 2> scale <1, 2, 1> }"), 2.0 * (2.0 * 3.0 + 3.0 * 3.0 + 2.0 * 3.0)));
    assert!(close(area("torus { 1, 0.25 }"), 4.0 * pi * pi * 0.25));
    let cyl = 2.0 * pi * 0.5 * 2.0 + 2.0 * pi * 0.25;
    assert!(close(area("cylinder { <0, -1, 0>, <0, 1, 0>, 0.5 scale 2 }"), 4.0 * cyl));
    assert!(close(area("union { sphere { 0, 1 } sphere { x, 1 } }"), 8.0 * pi));

    // Lit as by the plain point light: the floor below the light is as bright (within the
    // noise of a small render) with the sphere as without it.
    let floor = |text: &str| {
        let s = load(dir.path(), text);
        let image = render_small(&s);
        let mut sum = 0.0;
        for y in 22..30 {
            for x in 0..40 {
                sum += image.pixel(x, y)[0] as f64;
            }
        }
        (sum / 320.0, image)
    };
    let (with, image) = floor(&scene("sphere { 0, 0.5 pigment { rgb 1 } }"));
    look_at("looks_like", &image);
    let (without, _) = floor(&scene("sphere { 0, 0 }").replace("looks_like { sphere { 0, 0 } }", ""));
    println!("floor: {with:.4} with the looks_like sphere, {without:.4} with the point light");
    assert!(with > 0.0 && (with / without - 1.0).abs() < 0.1, "{with} vs {without}");

    // Where it cannot be the light: left out with a warning naming it; errors with positions.
    let (t, w) = translated(dir.path(), &scene("superellipsoid { <0.5, 0.5> }"));
    assert!(
        t.get("lights").is_some() && w.iter().any(|w| w.contains("scene.pov:2:") && w.contains("area cannot")),
        "{w:?}"
    );
    let (_, w) = translated(
        dir.path(),
        "camera { location <0, 1, -6> look_at <0, 1, 0> }\nlight_source { <0, 3, 0>, 1 spotlight looks_like { sphere { 0, 0.1 } } }",
    );
    assert!(w.iter().any(|w| w.contains("spotlight")), "{w:?}");
    let e = error(dir.path(), "light_source { 0, 1 looks_like { sphere { 0, 1 } } looks_like { sphere { 0, 1 } } }");
    assert!(e.contains("scene.pov:1:52") && e.contains("only one looks_like"), "{e}");
    let e = error(dir.path(), "light_source { 0, 1 looks_like { sphere { 0, 1 } bogus } }");
    assert!(e.contains("scene.pov:1:") && e.contains("bogus"), "{e}");
}

/// Media in an invisible CSG container (`pigment { rgbt 1 } interior { media { ... } }` on a
/// merge or difference): written as media boundaries, since a CSG object holds no media. A
/// difference's holes take the container's medium as their exterior, so a shell of absorption
/// 0.5 between radii 1 and 2 lets exp(-0.5 x 2) through its centre (the sphere it came from
/// would let exp(-0.5 x 4) through).
#[test]
fn media_in_csg_containers_are_bounded_by_their_parts() {
    let dir = tempfile::tempdir().unwrap();
    let shell = "camera { location <0, 0, -10> look_at <0, 0, 0> angle 8 }
background { rgb 1 }
difference { sphere { 0, 2 } sphere { 0, 1 } pigment { rgbt 1 } hollow interior { media { absorption 0.5 } } }";
    let (t, warnings) = translated(dir.path(), shell);
    assert!(warnings.is_empty(), "{warnings:?}");
    let shapes = t["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 2, "{shapes:?}");
    let md = shapes[0]["interior"].as_str().unwrap();
    assert_eq!(floats(&t["media"][md]["sigma_a"]), [0.5; 3]);
    assert_eq!(shapes[1]["interior"].as_str(), Some("vacuum"));
    assert_eq!(shapes[1]["exterior"].as_str(), Some(md));
    for s in shapes {
        assert_eq!(t["materials"][s["material"].as_str().unwrap()]["type"].as_str(), Some("null"));
    }
    let s = load(dir.path(), shell);
    let image = render_small(&s);
    look_at("media_shell", &image);
    let mut sum = 0.0;
    for y in 9..21 {
        for x in 14..26 {
            sum += image.pixel(x, y).iter().sum::<f32>() as f64 / 3.0;
        }
    }
    let centre = sum / 144.0;
    // Free-flight sampling makes each sample 0 or 1: 144 pixels of a few samples each; the
    // chords of the outer pixels are up to 1% longer than the centre's.
    println!("through the shell's centre: {centre:.3} (exact {:.3})", (-1f64).exp());
    assert!((centre - (-1f64).exp()).abs() < 0.1, "{centre}");

    // A merge's parts and a union's each hold the medium; with an atmosphere, a hole holds it.
    let (t, w) = translated(
        dir.path(),
        "camera { location <0, 0, -10> look_at <0, 0, 0> }
background { rgb 1 }
media { absorption 0.01 }
merge { sphere { -x, 0.5 } sphere { x, 0.5 } pigment { rgbt 1 } hollow interior { media { scattering { 1, 0.2 } } } }
union { sphere { -3*x, 0.5 } box { 3*x - 0.5, 3*x + 0.5 } pigment { rgbt 1 } hollow interior { media { scattering { 1, 0.2 } } } }
difference { box { -1, 1 } sphere { 0, 0.5 } pigment { rgbt 1 } hollow interior { media { absorption 1 } } translate 5*y }",
    );
    assert!(w.is_empty(), "{w:?}");
    let shapes = t["shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 6);
    let atmosphere = t["atmosphere"]["medium"].as_str().unwrap();
    let fog = shapes[0]["interior"].as_str().unwrap();
    assert_ne!(fog, atmosphere);
    assert!(shapes[..4].iter().all(|s| s["interior"].as_str() == Some(fog)), "{shapes:?}");
    assert_eq!(shapes[5]["interior"].as_str(), Some(atmosphere));
    assert_eq!(shapes[5]["exterior"].as_str(), shapes[4]["interior"].as_str());

    // A visible container (glass) stays a CSG object, its media left out with a warning.
    let (_, w) = translated(
        dir.path(),
        "camera { location <0, 0, -10> look_at <0, 0, 0> }\nlight_source { <0, 5, -5>, 1 }
difference { sphere { 0, 2 } sphere { 0, 1 } pigment { rgbf 0.9 } interior { ior 1.5 media { absorption 0.5 } } }",
    );
    assert!(w.iter().any(|w| w.contains("scene.pov:3:") && w.contains("media in this shape is left out")), "{w:?}");
}

/// Per-triangle textures: a mesh's `triangle { ... texture { T } }` and a mesh2's
/// `texture_list` with texture indices after `face_indices` give each triangle its texture;
/// triangles without one take the mesh's.
#[test]
fn mesh_triangles_keep_their_own_textures() {
    let dir = tempfile::tempdir().unwrap();
    let red = "texture { pigment { rgb <1, 0, 0> } }";
    let blue = "texture { pigment { rgb <0, 0, 1> } }";
    let mesh = format!(
        "{CAMERA}mesh {{
  triangle {{ <0, 0, 0>, <1, 0, 0>, <0, 1, 0> {red} }}
  triangle {{ <1, 0, 0>, <1, 1, 0>, <0, 1, 0> {blue} }}
  triangle {{ <2, 0, 0>, <3, 0, 0>, <2, 1, 0> }}
  smooth_triangle {{ <0, 2, 0>, y, <1, 2, 0>, y, <0, 3, 0>, y {red} }}
  pigment {{ rgb <0, 1, 0> }}
}}"
    );
    let mesh2 = format!(
        "{CAMERA}mesh2 {{
  vertex_vectors {{ 4, <0, 0, 0>, <1, 0, 0>, <1, 1, 0>, <0, 1, 0> }}
  texture_list {{ 2, {red} {blue} }}
  face_indices {{ 3, <0, 1, 3>, 0, <1, 2, 3>, 1, 1, 0, <0, 2, 3> }}
  pigment {{ rgb <0, 1, 0> }}
}}"
    );
    // Each triangle's reflectance (green, blue and red shares of the diffuse 0.6), in order of
    // the triangles' lowest corner.
    let colours = |text: &str| {
        let s = load(dir.path(), text);
        let mut out: Vec<(Vec3, Vec3)> = s
            .shapes
            .iter()
            .map(|sh| {
                let m = &s.materials[sh.material as usize];
                let c = match &m.kind {
                    photonix::scene::MaterialKind::Diffuse { reflectance } => reflectance.value,
                    other => panic!("{other:?}"),
                };
                (sh.geometry.bounds().0, c / 0.6)
            })
            .collect();
        out.sort_by(|a, b| (a.0.y, a.0.x).partial_cmp(&(b.0.y, b.0.x)).unwrap());
        out.into_iter().map(|(_, c)| c).collect::<Vec<_>>()
    };
    let (r, g, b) = (Vec3::X, Vec3::Y, Vec3::Z);
    let got = colours(&mesh);
    let want = [r, b, g, r];
    assert!(got.iter().zip(want).all(|(a, w)| a.abs_diff_eq(w, 1e-6)) && got.len() == 4, "{got:?}");
    // mesh2: the second face's indices 1, 1, 0 take the first (POV-Ray blends the three);
    // the third face has none.
    let got = colours(&mesh2);
    assert_eq!(got.len(), 3);
    let sorted: Vec<Vec3> = got.clone();
    assert!(sorted.iter().filter(|c| c.abs_diff_eq(r, 1e-6)).count() == 1, "{got:?}");
    assert!(sorted.iter().filter(|c| c.abs_diff_eq(b, 1e-6)).count() == 1, "{got:?}");
    assert!(sorted.iter().filter(|c| c.abs_diff_eq(g, 1e-6)).count() == 1, "{got:?}");
    // The same mesh moved and given a texture afterwards: the triangles' textures stay theirs.
    let moved = mesh.replace("pigment { rgb <0, 1, 0> }\n}", "pigment { rgb <0, 1, 0> }\ntranslate <0, 0, 1> }");
    assert_eq!(colours(&moved), colours(&mesh));

    // A texture index past the list: an error at the index.
    let e = error(
        dir.path(),
        &format!("mesh2 {{ vertex_vectors {{ 3, 0, x, y }} texture_list {{ 1, {red} }} face_indices {{ 1, <0, 1, 2>, 3 }} }}"),
    );
    assert!(e.contains("scene.pov:1:") && e.contains("texture index 3 is out of range"), "{e}");
}

/// Directives inside a declared value (`advanced/whiltile`): `#declare X = #ifdef (A) value
/// #else value #end`, with either branch taken, `#if` and `#switch`, objects and floats.
#[test]
fn declared_values_may_be_chosen_by_directives() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |flag: &str| {
        format!(
            "{CAMERA}{flag}
#declare Shape =
#ifdef (SIMPLE)
  sphere {{ 0, 1 }}
#else
  box {{ -1, 1 }}
#end
#declare R = #if (1 > 2) 5 #else 0.25 #end;
#declare K = 2;
#declare H = #switch (K) #case (1) 10 #break #case (2) 20 #break #else 30 #end
object {{ Shape scale R translate H * y pigment {{ rgb 1 }} }}
"
        )
    };
    for (flag, spheres) in [("#declare SIMPLE = 1;", 1), ("", 0)] {
        let s = load(dir.path(), &scene(flag));
        // (The box is held as 12 triangles.)
        let b = total_bounds(&s);
        assert!(b.0.abs_diff_eq(Vec3::new(-0.25, 19.75, -0.25), 1e-5), "{b:?}");
        assert_eq!(s.spheres().count(), spheres, "{flag}");
    }
    // A condition that is not a number is an error at its place.
    let e = error(dir.path(), "#declare X = #if (\"a\") 1 #else 2 #end");
    assert!(e.contains("scene.pov:1:18") && e.contains("expected a float"), "{e}");
}

/// A disc inside intersection, difference or merge cuts as its plane (POV-Ray's disc is inside
/// on the side opposite its normal, whatever its radius): `desk.pov`'s paperweight.
#[test]
fn discs_in_csg_cut_as_their_planes() {
    let dir = tempfile::tempdir().unwrap();
    let with = |cut: &str| {
        let (t, _) = translated(
            dir.path(),
            &format!(
                "{CAMERA}intersection {{ sphere {{ <0, -5, 0>, 10 }} {cut} translate <0, -1, 0> pigment {{ rgb 1 }} }}"
            ),
        );
        t["shapes"].clone()
    };
    assert_eq!(with("disc { <0, 0.5, 0>, -2*y, 10.1 }"), with("plane { -y, -0.5 }"));
    assert_eq!(with("disc { <3, 0.5, 1>, -y, 10.1, 2 }"), with("plane { -y, -0.5 }"));
}

/// A medium in a scene with no light (a glowing media shell lit by nothing, as
/// `camera/mesh_camera/baking_demo` holds once its CSG media are kept): the light shafts'
/// sampling has no light to pick and is skipped; the glow is still seen.
#[test]
fn glowing_media_render_without_lights() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(
        dir.path(),
        "camera { location <0, 0, -10> look_at <0, 0, 0> angle 30 }
difference { sphere { 0, 2 } sphere { 0, 1 } pigment { rgbt 1 } hollow interior { media { emission 1 } } }",
    );
    let image = render_small(&s);
    // Few of the camera rays collide in this thin glow (its emission is estimated at
    // collisions): the image's sum, not one pixel.
    let sum: f32 = (0..30).flat_map(|y| (0..40).map(move |x| (x, y))).map(|(x, y)| image.pixel(x, y)[0]).sum();
    assert!(sum > 0.0, "{sum}");
}

/// `checker rgb 0.8 rgb 0.6`: two colours without a comma, as POV-Ray reads them (a second colour
/// vector starts the next colour); the component keywords still amend the colour before them.
#[test]
fn inline_colours_need_no_commas() {
    let dir = tempfile::tempdir().unwrap();
    let (t, _) = translated(
        dir.path(),
        &format!(
            "{CAMERA}plane {{ y, 0 pigment {{ checker rgb 0.8 rgb <0.1, 0.2, 0.3> }} }}
sphere {{ y, 1 pigment {{ hexagon rgb 1 green 0.5 rgb 0.25 color rgb 0.5 }} }}"
        ),
    );
    let textures = t["textures"].as_table().unwrap();
    let colours = |pattern: &str| {
        let tex = textures.values().find(|t| t["pattern"].as_str() == Some(pattern)).unwrap();
        tex["colors"].as_array().unwrap().iter().map(floats).collect::<Vec<_>>()
    };
    assert_eq!(colours("checker"), [vec![0.8; 3], vec![0.1, 0.2, 0.3]]);
    assert_eq!(colours("hexagon"), [vec![1.0, 0.5, 1.0], vec![0.25; 3], vec![0.5; 3]]);
}

/// `plane { <0, 2, 0>, 1 }` lies at y = 1 in POV-Ray (the distance runs along the unit normal;
/// rendered with `povray` to check), inside CSG as outside it.
#[test]
fn a_planes_distance_runs_along_its_unit_normal_in_csg_too() {
    let dir = tempfile::tempdir().unwrap();
    let (t, _) = translated(
        dir.path(),
        &format!("{CAMERA}intersection {{ sphere {{ 0, 3 }} plane {{ <0, 2, 0>, 1 }} pigment {{ rgb 1 }} }}"),
    );
    // The half-space behind the plane is a box whose top face the transform moves onto the plane.
    let csg = &t["shapes"].as_array().unwrap()[0];
    let cut = &csg["children"].as_array().unwrap()[1];
    assert_eq!(cut["type"].as_str(), Some("box"));
    assert_eq!(floats(&cut["max"])[1], 0.0);
    assert_eq!(floats(&cut["transform"]["translate"]), [0.0, 1.0, 0.0], "{cut:?}");
}
