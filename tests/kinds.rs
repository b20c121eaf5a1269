//! The declarations of every kind's fields and defaults (`scene::kinds`) against the parser that
//! reads them, the docs that list them and the editor that shows them.

use std::path::Path;

use photonix::scene::kinds::{self, Family, Field, FieldType, FAMILIES};
use photonix::scene::parse_scene;

const CAMERA: &str = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n";

/// A value of the right TOML type for `field`, so the file gets past the parser's types to the
/// checks of fields against kinds.
fn value_for(field: &Field) -> String {
    match (field.name, field.ty) {
        ("vertices", _) => "[[0, 0, 0], [1, 0, 0], [1, 1, 0]]".to_string(),
        ("points", _) => "[[0, 0, 0]]".to_string(),
        ("samples", _) => "[2, 2]".to_string(),
        ("exponents", _) => "[0.5, 0.5]".to_string(),
        ("children", _) => "[]".to_string(),
        (_, FieldType::Number | FieldType::NumberOrTexture | FieldType::Roughness) => "0.5".to_string(),
        (_, FieldType::Integer) => "1".to_string(),
        (_, FieldType::Bool) => "true".to_string(),
        (_, FieldType::Choice(list)) => format!("\"{}\"", list[0]),
        (_, FieldType::Name) => "\"x\"".to_string(),
        (_, FieldType::Vector | FieldType::Color | FieldType::ColorOrTexture) => "[0.5, 0.5, 0.5]".to_string(),
        (_, FieldType::Texture) => "{ texture = \"t\" }".to_string(),
        (_, FieldType::Names) => "[\"a\", \"b\"]".to_string(),
        (_, FieldType::List) => "[0.5]".to_string(),
        (_, FieldType::Table) => "{}".to_string(),
    }
}

/// A scene whose one entry of `family` is of `kind` and sets `field`.
fn scene_with(family: &Family, kind: &str, field: &Field) -> String {
    let value = value_for(field);
    let set = |key: &str| if field.name == key { String::new() } else { format!("{key} = \"{kind}\"\n") };
    match family.table {
        "materials" => format!("{CAMERA}[materials.m]\n{}{} = {value}\n", set("type"), field.name),
        "lights" => format!("{CAMERA}[[lights]]\n{}{} = {value}\n", set("type"), field.name),
        "lights (area)" => {
            let shape = set("shape");
            let ty = if field.name == "type" { String::new() } else { "type = \"area\"\n".to_string() };
            format!("{CAMERA}[[lights]]\n{ty}{shape}{} = {value}\n", field.name)
        }
        "shapes" => format!("{CAMERA}[[shapes]]\n{}{} = {value}\n", set("type"), field.name),
        "media" => format!("{CAMERA}[media.m]\n{} = {value}\n", field.name),
        other => panic!("no scene for table {other}"),
    }
}

#[test]
fn the_parser_takes_every_declared_field_of_every_kind() {
    let mut checked = 0;
    for family in FAMILIES {
        for kind in family.kinds {
            for field in kind.all_fields() {
                let text = scene_with(family, kind.name, field);
                if let Err(e) = parse_scene(&text, Path::new("kinds.toml")) {
                    let message = e.to_string();
                    assert!(
                        !message.contains("unknown field") && !message.contains("does not apply"),
                        "{} {}: `{}` is declared but refused:\n{text}\n{message}",
                        family.table,
                        kind.name,
                        field.name
                    );
                }
                checked += 1;
            }
        }
    }
    println!("{checked} declared fields taken by the parser");
}

#[test]
fn a_field_another_kind_takes_is_refused_with_the_kinds_own_fields() {
    // `reflectance` belongs to diffuse and plastic, not to a mirror; `radius` to a sphere, not a
    // torus, whose closest field is suggested; a field no kind has is the parser's unknown field.
    let text = format!("{CAMERA}[materials.m]\ntype = \"mirror\"\nreflectance = 0.5\n");
    let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
    assert!(m.contains("k.toml:7:") && m.contains("`reflectance` does not apply to a mirror material"), "{m}");
    assert!(
        m.contains(
            &kinds::MATERIALS
                .kind("mirror")
                .field_names()
                .iter()
                .map(|f| format!("`{f}`"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        "{m}"
    );
    // A typo no kind has is matched against the kind's own fields: a sphere's `radius`, none of
    // a torus's (whose fields are listed).
    let text = format!("{CAMERA}[[shapes]]\ntype = \"sphere\"\nmaterial = \"x\"\nradiuss = 1\n");
    let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
    assert!(
        m.contains("k.toml:8:") && m.contains("unknown field `radiuss`") && m.contains("did you mean `radius`?"),
        "{m}"
    );
    let text = format!("{CAMERA}[[shapes]]\ntype = \"torus\"\nmaterial = \"x\"\nradiuss = 1\n");
    let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
    assert!(
        m.contains("k.toml:8:") && m.contains("(valid fields: `name`, `type`") && m.contains("`minor_radius`)"),
        "{m}"
    );
    let text = format!(
        "{CAMERA}[[shapes]]\ntype = \"torus\"\nmaterial = \"x\"\nmajor_radius = 1\nminor_radius = 0.2\nradius = 2\n"
    );
    let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
    assert!(
        m.contains("k.toml:10:") && m.contains("`radius` does not apply to a torus (did you mean `minor_radius`?"),
        "{m}"
    );
}

#[test]
fn an_unknown_field_is_matched_against_the_fields_of_its_kind() {
    // `colour` means the colour field of the entry's own kind: a mirror's `tint`, a diffuse
    // material's `reflectance`, a point light's `intensity`.
    for (table, fix) in [
        ("[materials.m]\ntype = \"mirror\"", "tint"),
        ("[materials.m]\ntype = \"diffuse\"", "reflectance"),
        ("[[lights]]\ntype = \"point\"", "intensity"),
    ] {
        let text = format!("{CAMERA}{table}\ncolour = [1, 1, 1]\n");
        let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
        assert!(m.contains("k.toml:7:") && m.contains(&format!("did you mean `{fix}`?")), "{m}");
    }
    // Nothing of a null material's is close: its fields are listed, not every material's.
    let text = format!("{CAMERA}[materials.m]\ntype = \"null\"\nreflectence = 0.5\n");
    let m = parse_scene(&text, Path::new("k.toml")).unwrap_err().to_string();
    assert!(m.contains("unknown field `reflectence`") && m.contains("valid fields: `type`)"), "{m}");
}

#[test]
fn docs_list_every_declared_field_with_its_default() {
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scene-format.md")).unwrap();
    let table = kinds::docs_table();
    assert!(
        docs.contains(&table),
        "docs/scene-format.md's \"Every field and its default\" differs from src/scene/kinds.rs; write it as:\n{table}"
    );
}

#[test]
fn declared_defaults_are_what_the_renderer_gets() {
    // A material, a spot light and a medium that leave every optional field out get the
    // declared defaults.
    let text = format!(
        "{CAMERA}[materials.p]\ntype = \"plastic\"\n[materials.d]\ntype = \"dielectric\"\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"p\"\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [3, 0, 0]\nradius = 1\nmaterial = \"d\"\n\
         [[lights]]\ntype = \"spot\"\nposition = [0, 5, 0]\ndirection = [0, -1, 0]\nintensity = 5\nouter_angle = 40\n"
    );
    let scene = parse_scene(&text, Path::new("k.toml")).unwrap();
    let debug = format!("{:?}", scene.materials);
    let r = kinds::REFLECTANCE.triple()[0];
    let ior = kinds::IOR.number() as f32;
    assert!(debug.contains(&format!("{r:?}")) && debug.contains(&format!("ior: {ior:?}")), "{debug}");
    let light = format!("{:?}", scene.lights[0].kind);
    let inner = (kinds::INNER_FRACTION * 40.0f32).to_radians().cos();
    assert!(light.contains(&format!("cos_inner: {inner:?}")), "{light}");
}
