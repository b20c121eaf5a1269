//! Every kind of material, light, shape and medium, with its fields and their defaults, declared
//! once. `convert` reads the lists of kinds and fields from here (which fields a kind takes,
//! "did you mean" for the others, an unknown field matched against its entry's kind in
//! `error.rs`) and the defaults it fills in; the editor's materials panel gets the same
//! declarations (`photonix serve`: `/kinds.js`, and `/api/kinds` as JSON); `tests/kinds.rs`
//! checks that docs/scene-format.md's table "Every field and its default" lists them as declared
//! and that the parser takes every declared field; the POV-Ray emitter leaves out what equals a
//! default. A new kind is one entry here plus its conversion (and its row in the docs).

use serde_json::{json, Value as Json};

/// What a field holds, as the file writes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldType {
    Number,
    Integer,
    Bool,
    /// One of a fixed list of strings.
    Choice(&'static [&'static str]),
    /// The name of something defined elsewhere (a material, medium or texture), or a file path.
    Name,
    /// Three numbers: a point or a direction.
    Vector,
    /// Three numbers >= 0, linear RGB.
    Color,
    /// A colour, or `{ texture = "name", scale = .. }`.
    ColorOrTexture,
    /// One number, or `{ texture = "name", scale = .. }`.
    NumberOrTexture,
    /// `{ texture = "name", .. }` only.
    Texture,
    /// A GGX alpha: one number, `[along u, along v]`, or a texture.
    Roughness,
    /// A list of names.
    Names,
    /// A list of numbers or points (vertices, control points, exponents).
    List,
    /// A table (a transform) or a list of tables (a csg's children).
    Table,
}

impl FieldType {
    /// The name the docs' table and the editor use.
    pub fn name(self) -> &'static str {
        match self {
            FieldType::Number => "number",
            FieldType::Integer => "integer",
            FieldType::Bool => "bool",
            FieldType::Choice(_) => "choice",
            FieldType::Name => "name",
            FieldType::Vector => "vector",
            FieldType::Color => "color",
            FieldType::ColorOrTexture => "color or texture",
            FieldType::NumberOrTexture => "number or texture",
            FieldType::Texture => "texture",
            FieldType::Roughness => "roughness",
            FieldType::Names => "names",
            FieldType::List => "list",
            FieldType::Table => "table",
        }
    }
}

/// What a field is when the file leaves it out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Default {
    /// The file must give it.
    Required,
    /// Nothing takes its place (the kind's docs say what its absence means).
    Unset,
    Number(f64),
    Bool(bool),
    /// Three numbers: a colour, a point or a direction.
    Triple([f64; 3]),
    Text(&'static str),
    /// Computed from other fields; the words say how.
    Rule(&'static str),
}

impl Default {
    /// As the docs' table writes it.
    pub fn text(self) -> String {
        let number = |v: f64| if v == v.trunc() && v.abs() < 1e15 { format!("{}", v as i64) } else { format!("{v}") };
        match self {
            Default::Required => "required".to_string(),
            Default::Unset => "none".to_string(),
            Default::Number(v) => format!("`{}`", number(v)),
            Default::Bool(b) => format!("`{b}`"),
            Default::Triple(c) => format!("`[{}, {}, {}]`", number(c[0]), number(c[1]), number(c[2])),
            Default::Text(t) => format!("`\"{t}\"`"),
            Default::Rule(words) => words.to_string(),
        }
    }

    fn json(self) -> Json {
        match self {
            Default::Required | Default::Unset | Default::Rule(_) => Json::Null,
            Default::Number(v) => json!(v),
            Default::Bool(b) => json!(b),
            Default::Triple(c) => json!(c),
            Default::Text(t) => json!(t),
        }
    }
}

/// One field of a kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    pub name: &'static str,
    pub ty: FieldType,
    pub default: Default,
}

impl Field {
    /// The default number; the caller knows the field has one (a declaration that changes its
    /// default to another type fails every scene test at once).
    pub fn number(&self) -> f64 {
        match self.default {
            Default::Number(v) => v,
            _ => unreachable!("field `{}` is declared with a number default", self.name),
        }
    }

    pub fn triple(&self) -> [f32; 3] {
        match self.default {
            Default::Triple(c) => c.map(|v| v as f32),
            _ => unreachable!("field `{}` is declared with a three-number default", self.name),
        }
    }

    pub fn flag(&self) -> bool {
        match self.default {
            Default::Bool(b) => b,
            _ => unreachable!("field `{}` is declared with a bool default", self.name),
        }
    }

    pub fn text(&self) -> &'static str {
        match self.default {
            Default::Text(t) => t,
            _ => unreachable!("field `{}` is declared with a text default", self.name),
        }
    }

    /// The values of a `Choice` field (empty for other types).
    pub fn choices(&self) -> &'static [&'static str] {
        match self.ty {
            FieldType::Choice(list) => list,
            _ => &[],
        }
    }
}

/// One kind: the value of its family's key (`type = "diffuse"`), how messages call it, and its
/// fields: first those it shares with other kinds (`common`), then its own.
#[derive(Clone, Copy, Debug)]
pub struct Kind {
    pub name: &'static str,
    pub what: &'static str,
    pub common: &'static [Field],
    pub fields: &'static [Field],
}

impl Kind {
    pub fn all_fields(&self) -> impl Iterator<Item = &'static Field> {
        self.common.iter().chain(self.fields.iter())
    }

    pub fn field_names(&self) -> Vec<&'static str> {
        self.all_fields().map(|f| f.name).collect()
    }
}

/// The kinds of one table (`[materials.*]`) told apart by one key (`type`).
#[derive(Clone, Copy, Debug)]
pub struct Family {
    /// As the docs' table names it: `materials`, `lights`, `lights (area)`, `shapes`, `media`.
    pub table: &'static str,
    pub key: &'static str,
    pub kinds: &'static [Kind],
}

impl Family {
    pub fn names(&self) -> Vec<&'static str> {
        self.kinds.iter().map(|k| k.name).collect()
    }

    /// The kind named `name`; the caller has checked it against `names()` (the invariant the
    /// message names).
    pub fn kind(&self, name: &str) -> &'static Kind {
        self.kinds
            .iter()
            .find(|k| k.name == name)
            .unwrap_or_else(|| panic!("callers check kind names against `names()`; {} has no {name}", self.table))
    }
}

const fn field(name: &'static str, ty: FieldType, default: Default) -> Field {
    Field { name, ty, default }
}

use self::Default::{Bool, Number, Required, Rule, Text, Triple, Unset};
use FieldType as T;

// Materials

pub const TYPE: Field = field("type", T::Name, Required);
pub const EMISSION: Field = field("emission", T::ColorOrTexture, Triple([0.0; 3]));
/// Emission leaves both faces (a glowing dome seen from inside, a lamp shade), not the front alone.
pub const TWO_SIDED: Field = field("two_sided", T::Bool, Bool(false));
pub const OPACITY: Field = field("opacity", T::NumberOrTexture, Number(1.0));
pub const BUMP: Field = field("bump", T::Texture, Unset);
pub const NORMAL_MAP: Field = field("normal_map", T::Texture, Unset);
/// Diffuse albedo (and the base of plastic): Mitsuba's default, 0.5, reads dark in a lit room.
pub const REFLECTANCE: Field = field("reflectance", T::ColorOrTexture, Triple([0.8; 3]));
pub const TINT: Field = field("tint", T::ColorOrTexture, Triple([1.0; 3]));
pub const IOR: Field = field("ior", T::Number, Number(1.5));
pub const ROUGHNESS: Field = field("roughness", T::Roughness, Number(0.0));
/// The distribution of a rough surface's microfacet normals (Mitsuba's `distribution`).
pub const DISTRIBUTION: Field = field("distribution", T::Choice(&["ggx", "beckmann"]), Text("ggx"));
/// Mitsuba's plastic `nonlinear`: the base tints the light bouncing under the coat.
pub const NONLINEAR: Field = field("nonlinear", T::Bool, Bool(false));
/// Names of `METAL_PRESETS` (convert/materials.rs), which holds their optical constants.
pub const METAL_PRESET_NAMES: &[&str] =
    &["gold", "silver", "copper", "aluminium", "aluminum", "chrome", "iron", "platinum", "titanium"];
pub const PRESET: Field = field("preset", T::Choice(METAL_PRESET_NAMES), Unset);
pub const ETA: Field = field("eta", T::ColorOrTexture, Unset);
pub const K: Field = field("k", T::ColorOrTexture, Unset);
pub const MIXED: Field = field("materials", T::Names, Required);
pub const WEIGHT: Field = field("weight", T::NumberOrTexture, Number(0.5));

const SURFACE: &[Field] = &[TYPE, EMISSION, TWO_SIDED, OPACITY, BUMP, NORMAL_MAP];

pub const MATERIALS: Family = Family {
    table: "materials",
    key: "type",
    kinds: &[
        Kind { name: "diffuse", what: "a diffuse material", common: SURFACE, fields: &[REFLECTANCE] },
        Kind { name: "mirror", what: "a mirror material", common: SURFACE, fields: &[TINT] },
        Kind {
            name: "dielectric",
            what: "a dielectric material",
            common: SURFACE,
            fields: &[IOR, ROUGHNESS, DISTRIBUTION],
        },
        Kind {
            name: "conductor",
            what: "a conductor material",
            common: SURFACE,
            fields: &[ETA, K, PRESET, ROUGHNESS, DISTRIBUTION, TINT],
        },
        Kind {
            name: "plastic",
            what: "a plastic material",
            common: SURFACE,
            fields: &[REFLECTANCE, IOR, ROUGHNESS, DISTRIBUTION, NONLINEAR],
        },
        Kind { name: "thin_dielectric", what: "a thin dielectric material", common: SURFACE, fields: &[IOR] },
        Kind { name: "mix", what: "a mix material", common: &[TYPE], fields: &[MIXED, WEIGHT] },
        Kind { name: "null", what: "a null material (an invisible medium boundary)", common: &[TYPE], fields: &[] },
    ],
};

// Lights

pub const LIGHT_NAME: Field = field("name", T::Name, Unset);
pub const PHOTONS: Field = field("photons", T::Bool, Bool(true));
pub const DIRECT: Field = field("direct", T::Bool, Bool(true));
pub const POSITION: Field = field("position", T::Vector, Required);
pub const INTENSITY: Field = field("intensity", T::Color, Required);
pub const DIRECTION: Field = field("direction", T::Vector, Required);
pub const POINT_AT: Field = field("point_at", T::Vector, Rule("instead of `direction`"));
pub const OUTER_ANGLE: Field = field("outer_angle", T::Number, Rule("required unless `radius` or `falloff`"));
/// Mitsuba 3's default beam width: the inner angle is this fraction of the outer one.
pub const INNER_FRACTION: f32 = 0.75;
pub const INNER_ANGLE: Field = field("inner_angle", T::Number, Rule("0.75 × `outer_angle`"));
/// POV-Ray's defaults for a spot light's `radius` and `falloff` (degrees).
pub const SPOT_RADIUS: Field = field("radius", T::Number, Number(30.0));
pub const SPOT_FALLOFF: Field = field("falloff", T::Number, Number(45.0));
pub const TIGHTNESS: Field = field("tightness", T::Number, Number(0.0));
pub const IRRADIANCE: Field = field("irradiance", T::Color, Required);
pub const ANGULAR_DIAMETER: Field = field("angular_diameter", T::Number, Number(0.0));
pub const VISIBLE: Field = field("visible", T::Bool, Bool(true));
pub const AREA_SHAPE: Field = field("shape", T::Choice(&["quad", "sphere", "disc"]), Required);
pub const RADIANCE: Field = field("radiance", T::Color, Required);
pub const TRANSFORM: Field = field("transform", T::Table, Unset);
pub const SAMPLES: Field = field("samples", T::List, Rule("`[1, 1]`"));
pub const JITTER: Field = field("jitter", T::Bool, Bool(true));
pub const ADAPTIVE: Field = field("adaptive", T::Integer, Number(0.0));

const LIGHT: &[Field] = &[LIGHT_NAME, TYPE, PHOTONS, DIRECT];
const AREA: &[Field] = &[LIGHT_NAME, TYPE, PHOTONS, DIRECT, AREA_SHAPE, RADIANCE, TRANSFORM, SAMPLES, JITTER, ADAPTIVE];

pub const LIGHTS: Family = Family {
    table: "lights",
    key: "type",
    kinds: &[
        Kind { name: "area", what: "an area light", common: AREA, fields: &[] },
        Kind { name: "point", what: "a point light", common: LIGHT, fields: &[POSITION, INTENSITY] },
        Kind {
            name: "spot",
            what: "a spot light",
            common: LIGHT,
            fields: &[
                POSITION,
                DIRECTION,
                POINT_AT,
                INTENSITY,
                INNER_ANGLE,
                OUTER_ANGLE,
                SPOT_RADIUS,
                SPOT_FALLOFF,
                TIGHTNESS,
            ],
        },
        Kind {
            name: "distant",
            what: "a distant light",
            common: LIGHT,
            fields: &[DIRECTION, IRRADIANCE, ANGULAR_DIAMETER, VISIBLE],
        },
    ],
};

pub const VERTICES: Field = field("vertices", T::List, Required);
/// A triangle's vertex normals: unset is flat.
pub const NORMALS: Field = field("normals", T::List, Unset);
pub const CENTER: Field = field("center", T::Vector, Required);
pub const RADIUS: Field = field("radius", T::Number, Required);
pub const NORMAL: Field = field("normal", T::Vector, Required);

/// An area light's own fields, by its `shape` (after those of every area light).
pub const AREA_LIGHT_SHAPES: Family = Family {
    table: "lights (area)",
    key: "shape",
    kinds: &[
        Kind { name: "quad", what: "a quad area light", common: AREA, fields: &[VERTICES] },
        Kind { name: "sphere", what: "a sphere area light", common: AREA, fields: &[CENTER, RADIUS] },
        Kind { name: "disc", what: "a disc area light", common: AREA, fields: &[CENTER, RADIUS, NORMAL] },
    ],
};

// Shapes

pub const SHAPE_NAME: Field = field("name", T::Name, Unset);
pub const MATERIAL: Field = field("material", T::Name, Rule("required (a mesh: the file's own)"));
pub const INTERIOR: Field = field("interior", T::Name, Text("vacuum"));
pub const EXTERIOR: Field = field("exterior", T::Name, Text("vacuum"));
pub const MIN: Field = field("min", T::Vector, Required);
pub const MAX: Field = field("max", T::Vector, Required);
pub const PLANE_OFFSET: Field = field("offset", T::Number, Number(0.0));
pub const INNER_RADIUS: Field = field("inner_radius", T::Number, Number(0.0));
pub const BASE: Field = field("base", T::Vector, Required);
pub const CAP: Field = field("cap", T::Vector, Required);
pub const BASE_RADIUS: Field = field("base_radius", T::Number, Required);
pub const CAP_RADIUS: Field = field("cap_radius", T::Number, Required);
pub const OPEN: Field = field("open", T::Bool, Bool(false));
pub const AXIS: Field = field("axis", T::Vector, Triple([0.0, 1.0, 0.0]));
pub const MAJOR_RADIUS: Field = field("major_radius", T::Number, Required);
pub const MINOR_RADIUS: Field = field("minor_radius", T::Number, Required);
pub const EXPONENTS: Field = field("exponents", T::List, Required);
pub const POINTS: Field = field("points", T::List, Required);
/// Blender's auto-smooth default (degrees).
pub const SMOOTH_ANGLE: Field = field("smooth_angle", T::Number, Number(30.0));
pub const FILE: Field = field("file", T::Name, Required);
pub const FILE_NORMALS: Field = field("file_normals", T::Bool, Bool(true));
pub const SUBDIVISION: Field = field("subdivision", T::Choice(&["catmull-clark", "loop"]), Unset);
pub const LEVELS: Field = field("levels", T::Integer, Number(2.0));
pub const CREASE_ANGLE: Field = field("crease_angle", T::Number, Unset);
/// Bezier patches (`.bpt` and `bicubic_patch`): largest distance to their triangles.
pub const FLATNESS: Field = field("flatness", T::Number, Number(0.01));
pub const MODEL_LIGHTS: Field = field("lights", T::Bool, Bool(true));
/// One mesh of a file that holds several (a Mitsuba `.serialized` file's shape); unset: all.
pub const SHAPE_INDEX: Field = field("shape_index", T::Integer, Unset);
pub const OPERATION: Field = field("operation", T::Choice(&["union", "intersection", "difference", "merge"]), Required);
pub const CHILDREN: Field = field("children", T::Table, Required);

const SHAPE: &[Field] = &[SHAPE_NAME, TYPE, MATERIAL, TRANSFORM, INTERIOR, EXTERIOR];

pub const SHAPES: Family = Family {
    table: "shapes",
    key: "type",
    kinds: &[
        Kind { name: "quad", what: "a quad", common: SHAPE, fields: &[VERTICES] },
        Kind { name: "triangle", what: "a triangle", common: SHAPE, fields: &[VERTICES, NORMALS] },
        Kind { name: "sphere", what: "a sphere", common: SHAPE, fields: &[CENTER, RADIUS] },
        Kind { name: "box", what: "a box", common: SHAPE, fields: &[MIN, MAX] },
        Kind {
            name: "mesh",
            what: "a mesh",
            common: SHAPE,
            fields: &[
                FILE,
                SMOOTH_ANGLE,
                FILE_NORMALS,
                SUBDIVISION,
                LEVELS,
                CREASE_ANGLE,
                FLATNESS,
                MODEL_LIGHTS,
                SHAPE_INDEX,
            ],
        },
        Kind {
            name: "bicubic_patch",
            what: "a bicubic patch",
            common: SHAPE,
            fields: &[POINTS, FLATNESS, SMOOTH_ANGLE],
        },
        Kind { name: "plane", what: "a plane", common: SHAPE, fields: &[NORMAL, PLANE_OFFSET] },
        Kind { name: "disc", what: "a disc", common: SHAPE, fields: &[CENTER, NORMAL, RADIUS, INNER_RADIUS] },
        Kind { name: "cylinder", what: "a cylinder", common: SHAPE, fields: &[BASE, CAP, RADIUS, OPEN] },
        Kind { name: "cone", what: "a cone", common: SHAPE, fields: &[BASE, CAP, BASE_RADIUS, CAP_RADIUS, OPEN] },
        Kind { name: "torus", what: "a torus", common: SHAPE, fields: &[CENTER, AXIS, MAJOR_RADIUS, MINOR_RADIUS] },
        Kind { name: "superellipsoid", what: "a superellipsoid", common: SHAPE, fields: &[CENTER, EXPONENTS] },
        Kind { name: "csg", what: "a csg", common: &[SHAPE_NAME, TYPE, MATERIAL], fields: &[OPERATION, CHILDREN] },
    ],
};

// Media

pub const SIGMA_A: Field = field("sigma_a", T::Color, Triple([0.0; 3]));
pub const SIGMA_S: Field = field("sigma_s", T::Color, Triple([0.0; 3]));
pub const SIGMA_T: Field = field("sigma_t", T::Color, Rule("`sigma_a` + `sigma_s`"));
pub const ALBEDO: Field = field("albedo", T::Color, Triple([1.0; 3]));
pub const MEDIUM_EMISSION: Field = field("emission", T::Color, Triple([0.0; 3]));
pub const PHASE: Field = field("phase", T::Choice(&["isotropic", "henyey-greenstein"]), Text("isotropic"));
pub const G: Field = field("g", T::Number, Number(0.0));
pub const DENSITY: Field = field("density", T::Name, Required);
pub const MEDIUM_TYPE: Field = field("type", T::Name, Rule("heterogeneous with `density`, else homogeneous"));

const MEDIUM: &[Field] = &[MEDIUM_TYPE, SIGMA_A, SIGMA_S, SIGMA_T, ALBEDO, MEDIUM_EMISSION, PHASE, G];

pub const MEDIA: Family = Family {
    table: "media",
    key: "type",
    kinds: &[
        Kind { name: "homogeneous", what: "a homogeneous medium", common: MEDIUM, fields: &[] },
        Kind { name: "heterogeneous", what: "a heterogeneous medium", common: MEDIUM, fields: &[DENSITY] },
    ],
};

/// Every family, in the order of the docs' table.
pub const FAMILIES: &[Family] = &[MATERIALS, LIGHTS, AREA_LIGHT_SHAPES, SHAPES, MEDIA];

/// The declarations as the editor reads them: `{ "materials": { "diffuse": [ { "name", "type",
/// "default", "required", "shared", "choices" }, .. ], .. }, .. }`, fields in declaration order
/// (`shared`: one of the fields every kind of the family takes); a default that is required,
/// unset or a rule is `null`.
pub fn json() -> Json {
    let mut out = serde_json::Map::new();
    for family in FAMILIES {
        let mut kinds = serde_json::Map::new();
        for kind in family.kinds {
            let fields: Vec<Json> = kind
                .all_fields()
                .map(|f| {
                    json!({
                        "name": f.name,
                        "type": f.ty.name(),
                        "default": f.default.json(),
                        "required": f.default == Required,
                        "shared": kind.common.contains(f),
                        "choices": f.choices(),
                    })
                })
                .collect();
            kinds.insert(kind.name.to_string(), Json::Array(fields));
        }
        out.insert(family.table.to_string(), Json::Object(kinds));
    }
    Json::Object(out)
}

/// docs/scene-format.md's table of every field and its default, as the declarations make it:
/// per family, a row for each set of fields that several kinds share, then a row per kind with
/// its own.
pub fn docs_table() -> String {
    let list = |fields: &[Field]| -> String {
        if fields.is_empty() {
            return "none".to_string();
        }
        let each: Vec<String> =
            fields.iter().map(|f| format!("`{}`: {}, {}", f.name, f.ty.name(), f.default.text())).collect();
        each.join("; ")
    };
    let mut out = String::from("| table | kind | fields: type, default |\n| --- | --- | --- |\n");
    for family in FAMILIES {
        let mut shared: Vec<&[Field]> = Vec::new();
        for kind in family.kinds {
            if !shared.contains(&kind.common) {
                shared.push(kind.common);
            }
        }
        for common in shared {
            let by: Vec<String> =
                family.kinds.iter().filter(|k| k.common == common).map(|k| format!("`{}`", k.name)).collect();
            out.push_str(&format!("| {} | every one of {} | {} |\n", family.table, by.join(", "), list(common)));
        }
        for kind in family.kinds {
            out.push_str(&format!("| {} | `{}` | {} |\n", family.table, kind.name, list(kind.fields)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_kind_declares_a_field_twice() {
        for family in FAMILIES {
            for kind in family.kinds {
                let names = kind.field_names();
                for (i, n) in names.iter().enumerate() {
                    assert!(!names[..i].contains(n), "{} {} declares `{n}` twice", family.table, kind.name);
                }
            }
        }
    }
}
