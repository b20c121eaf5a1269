//! The scene file as written: serde structs that mirror the TOML tables one to one. Every field is
//! optional and spanned, so `convert` can check it, apply defaults and point at its line.
//! `deny_unknown_fields` turns typos into errors; `error.rs` adds the suggestion.

use std::collections::BTreeMap;
use std::fmt;

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    pub camera: Option<Spanned<CameraDef>>,
    pub render: Option<Spanned<RenderDef>>,
    pub photons: Option<Spanned<PhotonsDef>>,
    #[serde(default)]
    pub materials: BTreeMap<Spanned<String>, Spanned<MaterialDef>>,
    #[serde(default)]
    pub textures: BTreeMap<Spanned<String>, Spanned<TextureDef>>,
    #[serde(default)]
    pub shapes: Vec<Spanned<ShapeDef>>,
    #[serde(default)]
    pub lights: Vec<Spanned<LightDef>>,
    pub environment: Option<Spanned<EnvironmentDef>>,
    pub rainbow: Option<Spanned<RainbowDef>>,
    #[serde(default)]
    pub media: BTreeMap<Spanned<String>, Spanned<MediumDef>>,
    pub atmosphere: Option<Spanned<AtmosphereDef>>,
    pub fog: Option<Spanned<FogDef>>,
    #[serde(default)]
    pub objects: BTreeMap<Spanned<String>, Spanned<ObjectDef>>,
    #[serde(default)]
    pub instances: Vec<Spanned<InstanceDef>>,
}

/// `[objects.NAME]`: shapes (and placements of other objects) defined once, in object space.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObjectDef {
    #[serde(default)]
    pub shapes: Vec<Spanned<ShapeDef>>,
    #[serde(default)]
    pub instances: Vec<Spanned<InstanceDef>>,
}

/// `[[instances]]`: an object placed once, or on a grid of `count` places `spacing` apart.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct InstanceDef {
    pub name: Option<Spanned<String>>,
    /// The editor's group (a folder of entries moved as one); the renderer ignores it.
    pub group: Option<Spanned<String>>,
    pub object: Option<Spanned<String>>,
    pub transform: Option<Spanned<TransformDef>>,
    pub material: Option<Spanned<String>>,
    pub count: Option<Spanned<Vec<Spanned<i64>>>>,
    pub spacing: Option<Spanned<Vec3Def>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MediumDef {
    pub r#type: Option<Spanned<String>>,
    pub sigma_a: Option<Spanned<Vec3Def>>,
    pub sigma_s: Option<Spanned<Vec3Def>>,
    pub sigma_t: Option<Spanned<Vec3Def>>,
    pub albedo: Option<Spanned<Vec3Def>>,
    pub emission: Option<Spanned<Vec3Def>>,
    pub phase: Option<Spanned<String>>,
    pub g: Option<Spanned<f64>>,
    pub density: Option<Spanned<String>>,
}

/// POV-Ray's `fog`, turned into an atmosphere (see `Builder::fog`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FogDef {
    pub r#type: Option<Spanned<String>>,
    pub distance: Option<Spanned<f64>>,
    pub color: Option<Spanned<Vec3Def>>,
    pub fog_offset: Option<Spanned<f64>>,
    pub fog_alt: Option<Spanned<f64>>,
    pub turbulence: Option<Spanned<Vec3Def>>,
    pub octaves: Option<Spanned<i64>>,
    pub omega: Option<Spanned<f64>>,
    pub lambda: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AtmosphereDef {
    pub medium: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EnvironmentDef {
    pub r#type: Option<Spanned<String>>,
    pub file: Option<Spanned<String>>,
    pub radiance: Option<Spanned<Vec3Def>>,
    pub colors: Option<Spanned<Vec<Vec3Def>>>,
    pub elevations: Option<Spanned<Vec<f64>>>,
    pub strength: Option<Spanned<f64>>,
    pub rotation: Option<Spanned<f64>>,
    pub photons: Option<Spanned<bool>>,
    pub direct: Option<Spanned<bool>>,
    // the physical sky
    pub turbidity: Option<Spanned<f64>>,
    pub ground_albedo: Option<Spanned<Vec3Def>>,
    pub sun: Option<Spanned<bool>>,
    pub sun_direction: Option<Spanned<Vec3Def>>,
    pub sun_elevation: Option<Spanned<f64>>,
    pub sun_azimuth: Option<Spanned<f64>>,
    pub latitude: Option<Spanned<f64>>,
    pub longitude: Option<Spanned<f64>>,
    pub date: Option<Spanned<String>>,
    pub time: Option<Spanned<String>>,
    pub utc_offset: Option<Spanned<f64>>,
    pub north: Option<Spanned<Vec3Def>>,
}

/// `[rainbow]`: bows drawn into the environment, from the physics of drops or POV-Ray's way.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RainbowDef {
    pub r#type: Option<Spanned<String>>,
    pub strength: Option<Spanned<f64>>,
    // POV-Ray's rainbow
    pub direction: Option<Spanned<Vec3Def>>,
    pub angle: Option<Spanned<f64>>,
    pub width: Option<Spanned<f64>>,
    pub colors: Option<Spanned<Vec<Vec3Def>>>,
    pub up: Option<Spanned<Vec3Def>>,
    pub arc_angle: Option<Spanned<f64>>,
    pub falloff_angle: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CameraDef {
    pub r#type: Option<Spanned<String>>,
    pub position: Option<Spanned<Vec3Def>>,
    pub look_at: Option<Spanned<Vec3Def>>,
    pub up: Option<Spanned<Vec3Def>>,
    pub fov: Option<Spanned<f64>>,
    pub resolution: Option<Spanned<Vec<i64>>>,
    // orthographic
    pub view_height: Option<Spanned<f64>>,
    // thin lens
    pub aperture_radius: Option<Spanned<f64>>,
    pub f_number: Option<Spanned<f64>>,
    pub focal_length: Option<Spanned<f64>>,
    pub focal_distance: Option<Spanned<f64>>,
    pub focal_point: Option<Spanned<Vec3Def>>,
    pub aperture_blades: Option<Spanned<i64>>,
    pub aperture_rotation: Option<Spanned<f64>>,
    // POV-Ray's focal blur
    pub aperture: Option<Spanned<f64>>,
    pub blur_samples: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RenderDef {
    pub spp: Option<Spanned<i64>>,
    pub passes: Option<Spanned<i64>>,
    pub max_depth: Option<Spanned<i64>>,
    pub seed: Option<Spanned<i64>>,
    pub integrator: Option<Spanned<String>>,
    pub filter: Option<Spanned<String>>,
    pub filter_radius: Option<Spanned<f64>>,
    pub denoise: Option<Spanned<bool>>,
    pub light_sampler: Option<Spanned<String>>,
    pub adaptive: Option<Spanned<bool>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PhotonsDef {
    pub alpha: Option<Spanned<f64>>,
    pub enabled: Option<Spanned<bool>>,
    pub count: Option<Spanned<i64>>,
    pub caustic_count: Option<Spanned<i64>>,
    pub radius: Option<Spanned<f64>>,
    pub caustic_radius: Option<Spanned<f64>>,
    pub volume_radius: Option<Spanned<f64>>,
    pub gather_rays: Option<Spanned<i64>>,
    pub max_depth: Option<Spanned<i64>>,
    pub glossy_threshold: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MaterialDef {
    pub r#type: Option<Spanned<String>>,
    pub reflectance: Option<Spanned<ParamDef>>,
    pub tint: Option<Spanned<ParamDef>>,
    pub ior: Option<Spanned<f64>>,
    pub emission: Option<Spanned<ParamDef>>,
    pub two_sided: Option<Spanned<bool>>,
    pub opacity: Option<Spanned<ParamDef>>,
    pub bump: Option<Spanned<ParamDef>>,
    pub normal_map: Option<Spanned<ParamDef>>,
    pub roughness: Option<Spanned<toml::Value>>,
    pub distribution: Option<Spanned<String>>,
    pub eta: Option<Spanned<ParamDef>>,
    pub k: Option<Spanned<ParamDef>>,
    pub preset: Option<Spanned<String>>,
    pub materials: Option<Spanned<Vec<String>>>,
    pub weight: Option<Spanned<ParamDef>>,
    pub nonlinear: Option<Spanned<bool>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TextureDef {
    pub r#type: Option<Spanned<String>>,
    pub space: Option<Spanned<String>>,
    pub transform: Option<Spanned<TransformDef>>,
    // constant
    pub color: Option<Spanned<Vec3Def>>,
    // image
    pub file: Option<Spanned<String>>,
    pub color_space: Option<Spanned<String>>,
    pub wrap: Option<Spanned<String>>,
    pub channel: Option<Spanned<String>>,
    pub projection: Option<Spanned<String>>,
    // pattern: read by `pattern::parse_pattern`, which names bad fields itself
    pub colors: Option<Spanned<Vec<Vec3Def>>>,
    pub pattern: Option<Spanned<toml::Value>>,
    pub turbulence: Option<Spanned<toml::Value>>,
    pub octaves: Option<Spanned<toml::Value>>,
    pub omega: Option<Spanned<toml::Value>>,
    pub lambda: Option<Spanned<toml::Value>>,
    pub frequency: Option<Spanned<toml::Value>>,
    pub phase: Option<Spanned<toml::Value>>,
    pub wave: Option<Spanned<toml::Value>>,
    pub exponent: Option<Spanned<toml::Value>>,
    pub direction: Option<Spanned<toml::Value>>,
    pub orientation: Option<Spanned<toml::Value>>,
    pub brick_size: Option<Spanned<toml::Value>>,
    pub mortar: Option<Spanned<toml::Value>>,
    pub metric: Option<Spanned<toml::Value>>,
    pub form: Option<Spanned<toml::Value>>,
    pub offset: Option<Spanned<toml::Value>>,
    pub solid: Option<Spanned<toml::Value>>,
    pub agate_turb: Option<Spanned<toml::Value>>,
    pub warp: Option<Spanned<toml::Value>>,
    pub color_map: Option<Spanned<toml::Value>>,
}

impl TextureDef {
    /// The pattern fields as written, as `pattern::parse_pattern` reads them, and the span of the
    /// first one (or none).
    pub fn pattern_fields(&self) -> Vec<(&'static str, &Spanned<toml::Value>)> {
        let fields = [
            ("pattern", &self.pattern),
            ("turbulence", &self.turbulence),
            ("octaves", &self.octaves),
            ("omega", &self.omega),
            ("lambda", &self.lambda),
            ("frequency", &self.frequency),
            ("phase", &self.phase),
            ("wave", &self.wave),
            ("exponent", &self.exponent),
            ("direction", &self.direction),
            ("orientation", &self.orientation),
            ("brick_size", &self.brick_size),
            ("mortar", &self.mortar),
            ("metric", &self.metric),
            ("form", &self.form),
            ("offset", &self.offset),
            ("solid", &self.solid),
            ("agate_turb", &self.agate_turb),
            ("warp", &self.warp),
            ("color_map", &self.color_map),
        ];
        fields.into_iter().filter_map(|(name, value)| value.as_ref().map(|v| (name, v))).collect()
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShapeDef {
    pub name: Option<Spanned<String>>,
    /// The editor's group (top-level `[[shapes]]` only); the renderer ignores it.
    pub group: Option<Spanned<String>>,
    pub r#type: Option<Spanned<String>>,
    pub material: Option<Spanned<String>>,
    pub vertices: Option<Spanned<Vec<Vec3Def>>>,
    /// A triangle's vertex normals (smooth shading).
    pub normals: Option<Spanned<Vec<Vec3Def>>>,
    pub center: Option<Spanned<Vec3Def>>,
    pub radius: Option<Spanned<f64>>,
    pub min: Option<Spanned<Vec3Def>>,
    pub max: Option<Spanned<Vec3Def>>,
    pub file: Option<Spanned<String>>,
    pub transform: Option<Spanned<TransformDef>>,
    // analytic shapes
    pub normal: Option<Spanned<Vec3Def>>,
    pub offset: Option<Spanned<f64>>,
    pub inner_radius: Option<Spanned<f64>>,
    pub base: Option<Spanned<Vec3Def>>,
    pub cap: Option<Spanned<Vec3Def>>,
    pub base_radius: Option<Spanned<f64>>,
    pub cap_radius: Option<Spanned<f64>>,
    pub open: Option<Spanned<bool>>,
    pub axis: Option<Spanned<Vec3Def>>,
    pub major_radius: Option<Spanned<f64>>,
    pub minor_radius: Option<Spanned<f64>>,
    pub exponents: Option<Spanned<Vec<f64>>>,
    // meshes and patches
    pub smooth_angle: Option<Spanned<f64>>,
    pub file_normals: Option<Spanned<bool>>,
    pub subdivision: Option<Spanned<String>>,
    pub levels: Option<Spanned<i64>>,
    pub crease_angle: Option<Spanned<f64>>,
    pub flatness: Option<Spanned<f64>>,
    pub lights: Option<Spanned<bool>>,
    pub shape_index: Option<Spanned<i64>>,
    pub points: Option<Spanned<Vec<Vec3Def>>>,
    // media
    pub interior: Option<Spanned<String>>,
    pub exterior: Option<Spanned<String>>,
    // csg
    pub operation: Option<Spanned<String>>,
    pub children: Option<Spanned<Vec<Spanned<ShapeDef>>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LightDef {
    pub name: Option<Spanned<String>>,
    /// The editor's group; the renderer ignores it.
    pub group: Option<Spanned<String>>,
    pub r#type: Option<Spanned<String>>,
    pub shape: Option<Spanned<String>>,
    pub vertices: Option<Spanned<Vec<Vec3Def>>>,
    pub center: Option<Spanned<Vec3Def>>,
    pub radius: Option<Spanned<f64>>,
    pub normal: Option<Spanned<Vec3Def>>,
    pub radiance: Option<Spanned<Vec3Def>>,
    // POV-Ray's area_light grid
    pub samples: Option<Spanned<Vec<i64>>>,
    pub jitter: Option<Spanned<bool>>,
    pub adaptive: Option<Spanned<i64>>,
    pub position: Option<Spanned<Vec3Def>>,
    pub intensity: Option<Spanned<Vec3Def>>,
    pub transform: Option<Spanned<TransformDef>>,
    // spot and distant
    pub direction: Option<Spanned<Vec3Def>>,
    pub point_at: Option<Spanned<Vec3Def>>,
    pub inner_angle: Option<Spanned<f64>>,
    pub outer_angle: Option<Spanned<f64>>,
    pub falloff: Option<Spanned<f64>>,
    pub tightness: Option<Spanned<f64>>,
    pub irradiance: Option<Spanned<Vec3Def>>,
    pub angular_diameter: Option<Spanned<f64>>,
    pub visible: Option<Spanned<bool>>,
    // every kind
    pub photons: Option<Spanned<bool>>,
    pub direct: Option<Spanned<bool>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TransformDef {
    /// A 4x4 matrix, row by row (the last row 0 0 0 1); exclusive with the other three.
    pub matrix: Option<Spanned<Vec<f64>>>,
    pub scale: Option<Spanned<Vec3Def>>,
    pub rotate: Option<Spanned<Vec3Def>>,
    pub translate: Option<Spanned<Vec3Def>>,
}

/// `[x, y, z]`, or a single number meaning `[v, v, v]` (grey, or uniform scale). `scalar`
/// remembers which, so fields that are points can refuse the single number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Vec3Def {
    pub value: [f64; 3],
    pub scalar: bool,
}

impl<'de> Deserialize<'de> for Vec3Def {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Vec3Visitor;
        impl<'de> Visitor<'de> for Vec3Visitor {
            type Value = Vec3Def;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an array of 3 numbers [x, y, z] or a single number")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Vec3Def, E> {
                Ok(Vec3Def { value: [v; 3], scalar: true })
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Vec3Def, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Vec3Def, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec3Def, A::Error> {
                let mut value = [0.0; 3];
                let mut count = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if count < 3 {
                        value[count] = x;
                    }
                    count += 1;
                }
                if count != 3 {
                    return Err(de::Error::invalid_length(count, &"an array of 3 numbers"));
                }
                Ok(Vec3Def { value, scalar: false })
            }
        }
        deserializer.deserialize_any(Vec3Visitor)
    }
}

/// A material parameter: a value as `Vec3Def` takes it (a colour, or one number), or a texture,
/// `{ texture = "name" }`, optionally scaled, `{ texture = "name", scale = 0.8 }`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ParamDef {
    Value(Vec3Def),
    Texture { name: String, scale: Option<Vec3Def> },
}

impl<'de> Deserialize<'de> for ParamDef {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct ParamVisitor;
        impl<'de> Visitor<'de> for ParamVisitor {
            type Value = ParamDef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, an array of 3 numbers, or a texture { texture = \"name\" }")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ParamDef, E> {
                Ok(ParamDef::Value(Vec3Def { value: [v; 3], scalar: true }))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ParamDef, E> {
                self.visit_f64(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ParamDef, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ParamDef, A::Error> {
                Vec3Def::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(ParamDef::Value)
            }
            fn visit_map<A: de::MapAccess<'de>>(self, mut map: A) -> Result<ParamDef, A::Error> {
                let (mut name, mut scale) = (None, None);
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "texture" => name = Some(map.next_value::<String>()?),
                        "scale" => scale = Some(map.next_value::<Vec3Def>()?),
                        other => return Err(de::Error::unknown_field(other, &["texture", "scale"])),
                    }
                }
                let name = name.ok_or_else(|| de::Error::missing_field("texture"))?;
                Ok(ParamDef::Texture { name, scale })
            }
        }
        deserializer.deserialize_any(ParamVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct Holder {
        v: Vec3Def,
    }

    #[test]
    fn vec3_accepts_arrays_integers_and_scalars() {
        let h: Holder = toml::from_str("v = [1, 2.5, -3]").unwrap();
        assert_eq!(h.v.value, [1.0, 2.5, -3.0]);
        assert!(!h.v.scalar);
        let h: Holder = toml::from_str("v = 0.5").unwrap();
        assert_eq!(h.v.value, [0.5; 3]);
        assert!(h.v.scalar);
        assert!(toml::from_str::<Holder>("v = [1, 2]").is_err());
        assert!(toml::from_str::<Holder>("v = \"red\"").is_err());
    }

    #[derive(Deserialize)]
    struct ParamHolder {
        p: ParamDef,
    }

    #[test]
    fn param_accepts_values_and_textures() {
        let h: ParamHolder = toml::from_str("p = [1, 2, 3]").unwrap();
        assert_eq!(h.p, ParamDef::Value(Vec3Def { value: [1.0, 2.0, 3.0], scalar: false }));
        let h: ParamHolder = toml::from_str("p = 0.5").unwrap();
        assert_eq!(h.p, ParamDef::Value(Vec3Def { value: [0.5; 3], scalar: true }));
        let h: ParamHolder = toml::from_str("p = { texture = \"checks\" }").unwrap();
        assert_eq!(h.p, ParamDef::Texture { name: "checks".into(), scale: None });
        assert!(toml::from_str::<ParamHolder>("p = { texture = \"a\", colour = 1 }").is_err());
        assert!(toml::from_str::<ParamHolder>("p = { scale = 1 }").is_err());
        assert!(toml::from_str::<ParamHolder>("p = [1, 2]").is_err());
    }
}
