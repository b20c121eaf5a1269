//! The Mitsuba front-end (`photonix render scene.xml`): small XML files for each plugin, checked
//! through the translated TOML and the loaded scene; the camera's orientation by a render; and
//! the three rooms of ../shared/real-scenes, loaded from their unmodified scene.xml and rendered
//! tiny, against Tungsten's converged images.

mod common;

use std::path::PathBuf;

use glam::Vec3;
use photonix::scene::mitsuba::{translate_file, Translation};
use photonix::scene::{load_scene, Geometry, Scene};

/// Writes `xml` (and the extra files) into a temporary folder and returns (folder, scene path).
fn write(xml: &str, files: &[(&str, &[u8])]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let path = dir.path().join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    (dir, path)
}

/// A Mitsuba 3 scene with a sensor and a light around `body`.
fn scene3(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="0" y="3" z="3"/><rgb name="intensity" value="10"/></emitter>
{body}
</scene>"#
    )
}

fn translate(xml: &str) -> (tempfile::TempDir, Translation, Scene) {
    let (dir, path) = write(xml, &[]);
    let t = translate_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}\n{}", t.toml));
    (dir, t, scene)
}

fn error_of(xml: &str) -> String {
    let (_dir, path) = write(xml, &[]);
    match load_scene(&path) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

fn triangles(scene: &Scene) -> Vec<[Vec3; 3]> {
    scene
        .shapes
        .iter()
        .filter_map(|s| match &s.geometry {
            Geometry::Triangle(t) => Some(t.vertices),
            _ => None,
        })
        .collect()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-4
}

// ---------------------------------------------------------------------------------------------
// Reading: names of both dialects, parameters, includes, references, positions

#[test]
fn mitsuba_05_and_3_spellings_translate_alike() {
    let old = r#"<scene version="0.5.0">
    <sensor type="perspective"><float name="fov" value="40"/><string name="fovAxis" value="y"/>
        <transform name="toWorld"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/>
            <boolean name="banner" value="false"/><string name="pixelFormat" value="rgb"/></film></sensor>
    <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.5"/><float name="extIOR" value="1"/></bsdf>
    <shape type="sphere"><float name="radius" value="0.5"/><ref id="glass"/></shape>
    <emitter type="point"><point name="position" x="0" y="3" z="3"/><rgb name="intensity" value="10"/></emitter>
</scene>"#;
    let new = old
        .replace("0.5.0", "3.0.0")
        .replace("fovAxis", "fov_axis")
        .replace("toWorld", "to_world")
        .replace("intIOR", "int_ior")
        .replace("extIOR", "ext_ior")
        .replace("pixelFormat", "pixel_format");
    let (_a, t_old, _) = translate(old);
    let (_b, t_new, _) = translate(&new);
    assert_eq!(t_old.toml, t_new.toml);
    assert!(t_old.warnings.is_empty(), "{:?}", t_old.warnings);
    assert!(t_old.toml.contains("ior = 1.5"), "{}", t_old.toml);
}

#[test]
fn defaults_and_parameters_are_substituted() {
    let xml = scene3(
        r#"<default name="r" value="0.25"/><default name="kind" value="sphere"/>
    <shape type="$kind"><float name="radius" value="$r"/></shape>"#,
    );
    let (_d, _t, scene) = translate(&xml);
    let Geometry::Sphere(s) = &scene.shapes[0].geometry else { panic!("a sphere") };
    assert_eq!(s.radius, 0.25);
}

#[test]
fn includes_and_refs_are_followed() {
    let (dir, path) = write(
        &scene3(r#"<include filename="parts.xml"/><shape type="sphere"><ref id="red"/></shape>"#),
        &[(
            "parts.xml",
            br#"<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf></scene>"#,
        )],
    );
    let t = translate_file(&path).unwrap();
    assert!(t.toml.contains("[materials.red]"), "{}", t.toml);
    assert!(t.toml.contains("reflectance = [0.8, 0.1, 0.1]"), "{}", t.toml);
    load_scene(&path).unwrap();
    drop(dir);
}

#[test]
fn errors_name_file_line_column_and_plugin() {
    let e = error_of(&scene3("<shape type=\"sphere\">\n  <ref id=\"nowhere\"/></shape>"));
    assert!(e.contains("scene.xml:9:3:") && e.contains("nowhere"), "{e}");
    let e = error_of(&scene3("<shape type=\"sphere\">\n  <float name=\"radius\" value=\"big\"/></shape>"));
    assert!(e.contains("scene.xml:9:3:") && e.contains("<shape type=\"sphere\">") && e.contains("radius"), "{e}");
    let e = error_of(&scene3("<shape type=\"hair\"/>"));
    assert!(e.contains("`hair` shape is not supported"), "{e}");
    let e = error_of("<scene version=\"3.0.0\"><shape type=\"obj\"></scene>");
    assert!(e.contains("scene.xml:1:") && e.contains("not valid XML"), "{e}");
    let e = error_of(&scene3("<bsdf type=\"conductor\" id=\"m\"><string name=\"material\" value=\"Unobtainium\"/></bsdf><shape type=\"sphere\"><ref id=\"m\"/></shape>"));
    assert!(e.contains("Unobtainium") && e.contains("eta"), "{e}");
}

#[test]
fn an_error_of_the_toml_checks_is_placed_at_the_xml_entry() {
    // A negative radius passes the translation and is refused by the TOML loader.
    let e = error_of(&scene3("<shape type=\"sphere\">\n<float name=\"radius\" value=\"-1\"/></shape>"));
    assert!(e.contains("scene.xml:8:1:") && e.contains("radius") && e.contains("as translated"), "{e}");
}

#[test]
fn unread_properties_are_named_in_warnings() {
    let (_d, t, _) = translate(&scene3(r#"<shape type="sphere"><float name="wobble" value="1"/></shape>"#));
    assert!(t.warnings.iter().any(|w| w.contains("scene.xml:8:22:") && w.contains("`wobble`")), "{:?}", t.warnings);
}

// ---------------------------------------------------------------------------------------------
// Transforms and shapes

#[test]
fn transforms_compose_in_order_and_become_a_matrix() {
    let xml = scene3(
        r#"<shape type="rectangle"><transform name="to_world">
        <scale x="2"/><rotate y="1" angle="90"/><translate x="1" y="2" z="3"/></transform></shape>"#,
    );
    let (_d, t, scene) = translate(&xml);
    assert!(t.toml.contains("transform = { matrix = ["), "{}", t.toml);
    // (-1, -1, 0) -> scaled (-2, -1, 0) -> turned 90 degrees about +y (x -> -z) (0, -1, 2) ->
    // moved (1, 1, 5).
    let tri = triangles(&scene);
    assert!(close(tri[0][0], Vec3::new(1.0, 1.0, 5.0)), "{:?}", tri[0]);
}

#[test]
fn rectangle_disk_cube_cylinder_and_sphere_are_placed_like_mitsubas() {
    let xml = scene3(
        r#"<shape type="rectangle"/>
    <shape type="cube"><transform name="to_world"><translate x="3"/></transform></shape>
    <shape type="disk"><transform name="to_world"><translate y="2"/></transform></shape>
    <shape type="cylinder"><float name="radius" value="0.3"/></shape>
    <shape type="sphere"><point name="center" x="1" y="0" z="0"/><float name="radius" value="0.5"/>
        <transform name="to_world"><scale value="2"/></transform></shape>"#,
    );
    let (_d, t, scene) = translate(&xml);
    assert!(t.toml.contains("type = \"quad\""));
    assert!(t.toml.contains("open = true"), "Mitsuba's cylinder has no caps");
    // Quad: 2 triangles facing +z; box: 12 triangles around x = 3.
    let tri = triangles(&scene);
    assert_eq!(tri.len(), 14);
    let n = (tri[0][1] - tri[0][0]).cross(tri[0][2] - tri[0][0]);
    assert!(n.z > 0.0, "the rectangle faces +z: {n}");
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for s in &scene.shapes[2..14] {
        let (a, b) = s.geometry.bounds();
        (lo, hi) = (lo.min(a), hi.max(b));
    }
    assert!(close(lo, Vec3::new(2.0, -1.0, -1.0)) && close(hi, Vec3::new(4.0, 1.0, 1.0)), "{lo} {hi}");
    let sphere = scene.shapes.iter().find_map(|s| match &s.geometry {
        Geometry::Sphere(s) => Some(s.clone()),
        _ => None,
    });
    let s = sphere.unwrap();
    assert!(close(s.center, Vec3::new(2.0, 0.0, 0.0)) && (s.radius - 1.0).abs() < 1e-6);
}

#[test]
fn a_mesh_whose_faces_all_have_zero_area_is_left_out_with_a_warning() {
    let obj = b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
    let good = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let (dir, path) = write(
        &scene3(
            r#"<shape type="obj"><string name="filename" value="flat.obj"/></shape>
    <shape type="obj"><string name="filename" value="good.obj"/><boolean name="face_normals" value="true"/></shape>"#,
        ),
        &[("flat.obj", obj), ("good.obj", good)],
    );
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(triangles(&scene).len(), 1);
    let w: Vec<_> = scene.warnings.iter().filter(|w| w.contains("zero area")).collect();
    assert_eq!(w.len(), 1, "{:?}", scene.warnings);
    assert!(w[0].contains("scene.xml:8:1:") && w[0].contains("left out"), "{}", w[0]);
    drop(dir);
}

#[test]
fn serialized_meshes_are_read_by_shape_index() {
    use photonix::scene::model::serialized::write_serialized;
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    let bytes = write_serialized(&[(&tri, &[[0, 1, 2]]), (&quad, &[[0, 1, 2], [0, 2, 3]])]);
    let (dir, path) = write(
        &scene3(
            r#"<shape type="serialized"><string name="filename" value="m.serialized"/><integer name="shape_index" value="1"/></shape>
    <shape type="serialized"><string name="filename" value="m.serialized"/></shape>"#,
        ),
        &[("m.serialized", &bytes)],
    );
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    // Shape 1 (two triangles), then shape 0 (one).
    assert_eq!(triangles(&scene).len(), 3);
    let e =
        error_of(&scene3(r#"<shape type="serialized"><string name="filename" value="missing.serialized"/></shape>"#));
    assert!(e.contains("missing.serialized"), "{e}");
    let (dir2, path2) = write(
        &scene3(
            r#"<shape type="serialized"><string name="filename" value="m.serialized"/><integer name="shape_index" value="2"/></shape>"#,
        ),
        &[("m.serialized", &bytes)],
    );
    let e = load_scene(&path2).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("scene.xml:8:1:") && e.contains("`shape_index` is 2"), "{e}");
    drop((dir, dir2));
}

#[test]
fn the_toml_matrix_transform_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.toml");
    let base = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n[materials.w]\ntype = \"diffuse\"\n[[shapes]]\ntype = \"quad\"\nmaterial = \"w\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]\n";
    for (transform, expect) in [
        ("{ matrix = [1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1] }", None),
        ("{ matrix = [1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1], scale = 2 }", Some("drop `scale`")),
        ("{ matrix = [1, 0, 0] }", Some("give 16")),
        ("{ matrix = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1] }", Some("last row")),
        ("{ matrix = [1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] }", Some("not invertible")),
    ] {
        std::fs::write(&path, format!("{base}transform = {transform}\n")).unwrap();
        match (load_scene(&path), expect) {
            (Ok(scene), None) => {
                let tri = triangles(&scene);
                assert!(close(tri[0][0], Vec3::new(1.0, 2.0, 3.0)), "{:?}", tri[0]);
            }
            (Err(e), Some(text)) => assert!(e.to_string().contains(text) && e.to_string().contains("m.toml:"), "{e}"),
            (r, _) => panic!("{transform}: {:?}", r.map(|_| ()).map_err(|e| e.to_string())),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// BSDFs and textures

#[test]
fn bsdfs_map_onto_photonix_materials() {
    let xml = scene3(
        r#"<bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf>
    <bsdf type="conductor" id="mirror"/>
    <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/><float name="alpha" value="0.2"/>
        <string name="distribution" value="ggx"/></bsdf>
    <bsdf type="dielectric" id="water"><string name="int_ior" value="water"/></bsdf>
    <bsdf type="roughplastic" id="red"><rgb name="diffuse_reflectance" value="0.5, 0.1, 0.1"/>
        <float name="alpha" value="0.3"/><string name="distribution" value="ggx"/></bsdf>
    <bsdf type="blendbsdf" id="blend"><float name="weight" value="0.25"/><ref id="white"/><ref id="gold"/></bsdf>
    <bsdf type="mixturebsdf" id="mixture"><string name="weights" value="0.2, 0.3, 0.5"/>
        <ref id="white"/><ref id="gold"/><ref id="red"/></bsdf>
    <bsdf type="mask" id="leaf"><float name="opacity" value="0.4"/><bsdf type="diffuse"/></bsdf>
    <shape type="sphere"><ref id="white"/></shape>
    <shape type="sphere"><ref id="mirror"/></shape>
    <shape type="sphere"><ref id="water"/></shape>
    <shape type="sphere"><ref id="blend"/></shape>
    <shape type="sphere"><ref id="mixture"/></shape>
    <shape type="sphere"><ref id="leaf"/></shape>"#,
    );
    let (_d, t, scene) = translate(&xml);
    let toml = &t.toml;
    for expected in [
        "[materials.white]\ntype = \"diffuse\"\nreflectance = 0.7",
        "[materials.mirror]\ntype = \"mirror\"",
        "type = \"conductor\"\npreset = \"gold\"\nroughness = 0.2",
        "ior = 1.3326", // water (1.333) over air (1.000277)
        "materials = [\"white\", \"gold\"]\nweight = 0.25",
        "materials = [\"mixture line 16 part 1\", \"red\"]\nweight = 0.5",
        "materials = [\"white\", \"gold\"]\nweight = 0.6",
        "opacity = 0.4",
    ] {
        let found = toml.contains(expected) || (expected.starts_with("ior") && toml.contains("ior = 1.33263"));
        assert!(found, "missing {expected:?} in\n{toml}");
    }
    // The one-sided mirror and mask are reported (Mitsuba shades their backs black).
    assert!(t.warnings.iter().any(|w| w.contains("twosided")), "{:?}", t.warnings);
    assert_eq!(scene.shapes.len(), 6);
}

#[test]
fn a_bitmap_texture_becomes_an_image_with_its_uv_transform() {
    let png = {
        let mut bytes = Vec::new();
        let img = image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([(x * 255) as u8, (y * 255) as u8, 0]));
        img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).unwrap();
        bytes
    };
    let xml = scene3(
        r#"<shape type="rectangle"><bsdf type="diffuse"><texture name="reflectance" type="bitmap">
        <string name="filename" value="t.png"/><string name="filter_type" value="nearest"/>
        <transform name="to_uv"><scale x="2" y="4"/></transform></texture></bsdf></shape>
    <shape type="rectangle"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard">
        <rgb name="color0" value="0.1"/><rgb name="color1" value="0.9"/></texture></bsdf></shape>"#,
    );
    let (dir, path) = write(&xml, &[("t.png", &png)]);
    let t = translate_file(&path).unwrap();
    assert!(t.toml.contains("type = \"image\"\nfile = \"t.png\""), "{}", t.toml);
    // A rectangle's uv is Mitsuba's; Mitsuba's image is v-down, ours v-up: the lookup is
    // (2u, 1 - 4v), which the texture's transform places as its inverse, (x / 2, (1 - y) / 4).
    assert!(t.toml.contains("transform = { matrix = [0.5, 0.0, 0.0, 0.0, 0.0, -0.25, 0.0, 0.25,"), "{}", t.toml);
    assert!(t.toml.contains("pattern = \"checker\""), "{}", t.toml);
    assert!(t.warnings.iter().any(|w| w.contains("nearest")), "{:?}", t.warnings);
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    drop(dir);
}

// ---------------------------------------------------------------------------------------------
// Emitters, sensor, media

#[test]
fn emitters_become_lights_emission_and_environment() {
    let xml = r#"<scene version="3.0.0">
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0"/></transform></sensor>
    <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="3, 2, 1"/></emitter></shape>
    <emitter type="spot"><transform name="to_world"><lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
        <rgb name="intensity" value="5"/><float name="cutoff_angle" value="30"/></emitter>
    <emitter type="directional"><vector name="direction" x="0" y="-1" z="0"/><rgb name="irradiance" value="2"/></emitter>
    <emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="0.5"/>
        <transform name="to_world"><rotate y="1" angle="90"/></transform></emitter>
</scene>"#;
    let (dir, path) = write(xml, &[]);
    let t = translate_file(&path).unwrap();
    assert!(t.toml.contains("emission = [3.0, 2.0, 1.0]"), "{}", t.toml);
    assert!(t.toml.contains("type = \"spot\"") && t.toml.contains("direction = [0.0, -1.0, 0.0]"), "{}", t.toml);
    assert!(t.toml.contains("outer_angle = 30.0") && t.toml.contains("inner_angle = 22.5"), "{}", t.toml);
    assert!(t.toml.contains("type = \"distant\""), "{}", t.toml);
    // Mitsuba's map middle looks toward +z, ours toward -z: a turn of 90 becomes -90.
    assert!(t.toml.contains("strength = 0.5") && t.toml.contains("rotation = -90.0"), "{}", t.toml);
    drop(dir);
}

#[test]
fn the_film_size_and_field_of_view_axis_make_the_camera() {
    let (_d, _t, scene) = translate(&scene3(""));
    // fov 40 along x (Mitsuba's default axis) on a 32x24 film: vertical 2 atan(tan 20 * 3/4).
    let expect = 2.0 * ((20f32).to_radians().tan() * 0.75).atan().to_degrees();
    assert!((scene.camera.fov_deg - expect).abs() < 1e-3, "{} vs {expect}", scene.camera.fov_deg);
    assert_eq!((scene.camera.width, scene.camera.height), (32, 24));
    assert!(close(scene.camera.position, Vec3::new(0.0, 0.0, 5.0)));
}

#[test]
fn the_sample_count_becomes_passes_of_a_few_samples() {
    // The same samples in all, in passes short enough for `--time` and the editor's preview.
    for (count, spp, passes) in [(256, 4, 64), (9, 3, 3), (7, 1, 7), (1, 1, 1)] {
        let xml = scene3("").replace(
            "</sensor>",
            &format!(
                r#"<sampler type="independent"><integer name="sample_count" value="{count}"/></sampler></sensor>"#
            ),
        );
        let (_d, _t, scene) = translate(&xml);
        assert_eq!((scene.render.spp, scene.render.passes), (spp, passes), "sample_count {count}");
    }
}

#[test]
fn the_reconstruction_filter_keeps_its_size() {
    let with_filter = |rfilter: &str| {
        scene3("").replace(
            r#"<integer name="height" value="24"/></film>"#,
            &format!(r#"<integer name="height" value="24"/>{rfilter}</film>"#),
        )
    };
    use photonix::scene::Filter;
    let (_d, _t, scene) = translate(&scene3(""));
    assert_eq!((scene.render.filter, scene.render.filter_radius), (Filter::Gaussian, None));
    // A Gaussian reaches four standard deviations, in Mitsuba as here; a tent its radius.
    let (_d, t, scene) =
        translate(&with_filter(r#"<rfilter type="gaussian"><float name="stddev" value="0.8"/></rfilter>"#));
    assert_eq!((scene.render.filter, scene.render.filter_radius), (Filter::Gaussian, Some(3.2)), "{}", t.toml);
    let (_d, _t, scene) =
        translate(&with_filter(r#"<rfilter type="tent"><float name="radius" value="1.5"/></rfilter>"#));
    assert_eq!((scene.render.filter, scene.render.filter_radius), (Filter::Tent, Some(1.5)));
    // Beyond our widest: kept at it, and said.
    let (_d, t, scene) =
        translate(&with_filter(r#"<rfilter type="gaussian"><float name="stddev" value="5"/></rfilter>"#));
    assert_eq!(scene.render.filter_radius, Some(photonix::limits::MAX_FILTER_RADIUS));
    assert!(t.warnings.iter().any(|w| w.contains("the filter reaches 20")), "{:?}", t.warnings);
}

#[test]
fn a_homogeneous_medium_fills_its_shape() {
    let xml = scene3(
        r#"<shape type="cube"><bsdf type="dielectric"/>
        <medium type="homogeneous" name="interior"><rgb name="sigmaA" value="0.5, 0.2, 0.4"/><rgb name="sigma_s" value="0.1"/></medium></shape>"#,
    );
    let (_d, t, scene) = translate(&xml);
    assert!(t.toml.contains("sigma_a = [0.5, 0.2, 0.4]") && t.toml.contains("interior = "), "{}", t.toml);
    assert_eq!(scene.media.len(), 1);
}

/// Mitsuba's camera looks down its +z with +x to the image's left: a red square on the
/// sensor's local +x side must land in the left half of the image (not mirrored).
#[test]
fn the_image_is_not_mirrored() {
    let xml = r#"<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="60"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="8"/></film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="0.4"/><rotate y="1" angle="180"/><translate x="0.6" z="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="1, 0, 0"/></emitter></shape>
</scene>"#;
    let (dir, path) = write(xml, &[]);
    let out = dir.path().join("o.exr");
    let run = common::photonix(
        &[
            "render",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--backend",
            "cpu",
            "--spp",
            "4",
            "--passes",
            "1",
            "--integrator",
            "pt",
        ],
        dir.path(),
    );
    assert!(run.status.success(), "{}", common::stderr(&run));
    let img = photonix::io::image::read_exr(&out).unwrap();
    let half = |left: bool| -> f32 {
        let mut sum = 0.0;
        for y in 0..img.height {
            for x in 0..img.width {
                if (x < img.width / 2) == left {
                    sum += img.pixels[(y * img.width + x) as usize][0];
                }
            }
        }
        sum
    };
    println!("red: left half {}, right half {}", half(true), half(false));
    assert!(half(true) > 1.0 && half(false) == 0.0, "left {} right {}", half(true), half(false));
}

/// tests/mitsuba/conventions.xml holds every convention the two renderers differ in (the
/// camera's handedness, the environment map's orientation, an OBJ's texture v, a rectangle's
/// and a checkerboard's uv under `to_uv`, a one-sided lamp): rendered through the front-end, it
/// must match Mitsuba 3.9.1's render of the very same file
/// (tests/references/make_mitsuba_xml_references.py, 4096 spp).
#[test]
fn conventions_scene_matches_mitsubas_render_of_the_same_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("conventions.exr");
    let scene = common::repo_path("tests/mitsuba/conventions.xml");
    let run = common::photonix(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--backend",
            "cpu",
            "--spp",
            "64",
            "--passes",
            "1",
            "--integrator",
            "pt",
        ],
        dir.path(),
    );
    assert!(run.status.success(), "{}", common::stderr(&run));
    let ours = photonix::io::image::read_exr(&out).unwrap();
    let theirs =
        photonix::io::image::read_exr(&common::repo_path("tests/references/mitsuba/xml-conventions.exr")).unwrap();
    let error = photonix::io::metrics::rel_mse(&ours, &theirs);
    let ratio = photonix::io::metrics::mean_ratio(&ours, &theirs);
    println!("conventions: relMSE {error:.2e}, mean ratio {ratio:.4?}");
    // Measured at 64 spp: relMSE 8.8e-3, ratios 0.998, 1.003, 0.997 (256 spp: 2.5e-3). The
    // same image mirrored left to right measures 0.83: the bound lies between.
    for r in ratio {
        assert!((r - 1.0).abs() < 0.03, "{ratio:?}");
    }
    assert!(error < 2.5e-2, "relMSE {error}");
}

// ---------------------------------------------------------------------------------------------
// The rooms

fn room(name: &str) -> PathBuf {
    common::repo_path(&format!("../shared/real-scenes/{name}/scene.xml"))
}

/// Renders a room at 32x18 with the CPU backend, `pt`; returns its per-channel mean ratios
/// against Tungsten's image averaged down to that size and against Mitsuba 3.9.1's render of the
/// same file at that size (tests/references/mitsuba/room-NAME.exr, 1024 spp,
/// make_mitsuba_xml_references.py --rooms).
fn room_means(name: &str, spp: &str) -> ([f64; 3], [f64; 3]) {
    let scene = room(name);
    if !scene.exists() {
        panic!("{} is missing: the rooms live in ../shared/real-scenes", scene.display());
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("room.exr");
    let run = common::photonix(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--backend",
            "cpu",
            "--resolution",
            "32x18",
            "--spp",
            spp,
            "--passes",
            "1",
            "--integrator",
            "pt",
        ],
        dir.path(),
    );
    assert!(run.status.success(), "{name}: {}", common::stderr(&run));
    let ours = photonix::io::image::read_exr(&out).unwrap();
    let reference = photonix::io::image::read_exr(&scene.with_file_name("TungstenRender.exr")).unwrap();
    let down = photonix::io::metrics::downsample(&reference, reference.width / 32);
    let tungsten = photonix::io::metrics::mean_ratio(&ours, &down);
    let mitsuba =
        photonix::io::image::read_exr(&common::repo_path(&format!("tests/references/mitsuba/room-{name}.exr")))
            .unwrap();
    let mitsuba = photonix::io::metrics::mean_ratio(&ours, &mitsuba);
    println!("{name}: mean ratio against Tungsten {tungsten:.3?}, against Mitsuba {mitsuba:.3?}");
    (tungsten, mitsuba)
}

fn loads(name: &str) -> Scene {
    let scene = load_scene(&room(name)).unwrap_or_else(|e| panic!("{e}"));
    assert!(!scene.shapes.is_empty());
    scene
}

fn within(ratio: [f64; 3], bound: f64) -> bool {
    ratio.iter().all(|r| (r - 1.0).abs() < bound)
}

// Bounds: 32x18 pixels at a few dozen samples are noisy, the rooms (Veach, Ajar above all, lit
// through a gap) far from converged: seeds 0, 1 and 2 measured, against Tungsten and Mitsuba,
// Veach, Ajar 1.048-1.076 and 1.043-1.054 (seed 0), 0.98-1.02 (seeds 1, 2); the Grey & White
// Room 0.94-0.99; Modern Hall 0.97-1.00 against Mitsuba. 10% holds them all and still catches a
// missing feature (no nonlinear plastic made Modern Hall 1.06-1.15, no conductor tint Veach 1.47).
const VEACH: f64 = 0.10;
const GREY_WHITE: f64 = 0.10;
const MODERN_HALL: f64 = 0.10;

#[test]
fn veach_ajar_loads_and_renders_near_tungsten_and_mitsuba() {
    let scene = loads("veach-ajar");
    assert_eq!((scene.camera.width, scene.camera.height), (1280, 720));
    let (tungsten, mitsuba) = room_means("veach-ajar", "64");
    assert!(within(tungsten, VEACH) && within(mitsuba, VEACH), "{tungsten:?} {mitsuba:?}");
}

#[test]
fn grey_white_room_loads_and_renders_near_tungsten_and_mitsuba() {
    let scene = loads("grey-white-room");
    assert!(scene.environment.is_some());
    let (tungsten, mitsuba) = room_means("grey-white-room", "16");
    assert!(within(tungsten, GREY_WHITE) && within(mitsuba, GREY_WHITE), "{tungsten:?} {mitsuba:?}");
}

#[test]
fn modern_hall_loads_and_renders_near_mitsuba() {
    // Tungsten's image of Modern Hall shows another view (the folder's README): Mitsuba's
    // render of the file is the reference.
    let scene = loads("modern-hall");
    assert!(scene.materials.len() > 10);
    let (_, mitsuba) = room_means("modern-hall", "16");
    assert!(within(mitsuba, MODERN_HALL), "{mitsuba:?}");
}
