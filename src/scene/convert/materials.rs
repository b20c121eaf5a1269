//! `[materials.NAME]`: each material kind's fields and defaults, metal presets and mixes.

use glam::Vec3;
use toml::Spanned;

use super::params::TexelRole;
use super::{span_of, Builder, Result};
use crate::layout::constants::MIX_MAX_DEPTH;
use crate::limits::{fmt_f32, printable, MAX_IOR};
use crate::scene::error::suggest;
use crate::scene::format::{MaterialDef, ParamDef};
use crate::scene::kinds::{self, MATERIALS};
use crate::scene::material::{ColorParam, Distribution, MaterialDesc, MaterialKind, NormalMod, Roughness, ScalarParam};

/// Complex indices of refraction (eta, k) of common metals at the wavelengths of the R, G and B
/// primaries (about 650, 550 and 450 nm), from published optical constants: gold, silver and
/// copper after Johnson and Christy (1972), aluminium after Rakic (1995), the others from
/// refractiveindex.info's tables of Palik's data (rounded; RGB rendering has no spectrum).
/// `kinds::METAL_PRESET_NAMES` lists the same names (tested).
const METAL_PRESETS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("gold", [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
    ("silver", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
    ("copper", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
    ("aluminium", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("aluminum", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("chrome", [3.18, 3.18, 2.22], [3.30, 3.33, 3.05]),
    ("iron", [2.91, 2.95, 2.59], [3.08, 2.93, 2.77]),
    ("platinum", [2.38, 2.08, 1.85], [4.26, 3.72, 3.15]),
    ("titanium", [2.74, 2.54, 2.16], [3.82, 3.43, 2.98]),
];

impl Builder<'_> {
    pub(super) fn material(&mut self, key: &Spanned<String>, def: &Spanned<MaterialDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("material \"{}\"", printable(&name));
        let m = def.get_ref();
        let kind_def = self.require(&m.r#type, &def.span(), &object, "type", "type = \"diffuse\"")?;
        let kind = self.one_of(kind_def, &object, "type", &MATERIALS.names())?;
        let present = [
            ("type", span_of(&m.r#type)),
            ("reflectance", span_of(&m.reflectance)),
            ("tint", span_of(&m.tint)),
            ("ior", span_of(&m.ior)),
            ("emission", span_of(&m.emission)),
            ("two_sided", span_of(&m.two_sided)),
            ("opacity", span_of(&m.opacity)),
            ("bump", span_of(&m.bump)),
            ("normal_map", span_of(&m.normal_map)),
            ("roughness", span_of(&m.roughness)),
            ("distribution", span_of(&m.distribution)),
            ("eta", span_of(&m.eta)),
            ("k", span_of(&m.k)),
            ("preset", span_of(&m.preset)),
            ("materials", span_of(&m.materials)),
            ("weight", span_of(&m.weight)),
            ("nonlinear", span_of(&m.nonlinear)),
        ];
        let decl = MATERIALS.kind(kind);
        self.only_fields(&object, decl.what, &present, &decl.field_names())?;
        let emission = match &m.emission {
            Some(e) => self.color_param(e, &object, "emission", false)?,
            None => ColorParam::constant(Vec3::from(kinds::EMISSION.triple())),
        };
        let opacity = match &m.opacity {
            Some(o) => self.scalar_param(o, &object, "opacity", 0.0, 1.0, "a fraction in [0, 1] (1 is opaque)")?,
            None => ScalarParam::constant(kinds::OPACITY.number() as f32),
        };
        let normal = match (&m.bump, &m.normal_map) {
            (Some(_), Some(n)) => {
                return Err(self.invalid(
                    &n.span(),
                    &object,
                    "a material takes `bump` or `normal_map`, not both".to_string(),
                ));
            }
            (Some(b), None) => {
                let what = "a texture, e.g. `bump = { texture = \"dents\", scale = 0.02 }` (scale in scene units)";
                let ParamDef::Texture { .. } = b.get_ref() else {
                    return Err(self.invalid(&b.span(), &object, format!("`bump` must be {what}")));
                };
                let p = self.scalar_param(b, &object, "bump", -f32::MAX, f32::MAX, "a finite number")?;
                NormalMod::Bump { texture: p.texture.expect("a texture parameter"), strength: p.value }
            }
            (None, Some(n)) => match n.get_ref() {
                ParamDef::Texture { name, scale: None } => {
                    let texture = self.texture_id(name, &n.span(), &object)?;
                    let role = TexelRole::Scalar { min: -f32::MAX, max: f32::MAX, what: "a finite number" };
                    self.check_texels(texture, Vec3::ONE, role, &n.span(), &object, "normal_map")?;
                    NormalMod::NormalMap { texture }
                }
                _ => {
                    return Err(self.invalid(
                        &n.span(),
                        &object,
                        "`normal_map` must be a texture, e.g. `normal_map = { texture = \"tiles_normal\" }`"
                            .to_string(),
                    ));
                }
            },
            (None, None) => NormalMod::None,
        };
        let kind = match kind {
            "diffuse" => {
                let reflectance = match &m.reflectance {
                    Some(r) => self.color_param(r, &object, "reflectance", true)?,
                    None => ColorParam::constant(Vec3::from(kinds::REFLECTANCE.triple())),
                };
                MaterialKind::Diffuse { reflectance }
            }
            "mirror" => {
                let tint = match &m.tint {
                    Some(t) => self.color_param(t, &object, "tint", true)?,
                    None => ColorParam::constant(Vec3::from(kinds::TINT.triple())),
                };
                MaterialKind::Mirror { tint }
            }
            "dielectric" => {
                let ior = self.ior(m, &object)?;
                let roughness = self.roughness(m, &object)?;
                MaterialKind::Dielectric { ior, roughness }
            }
            "conductor" => {
                let (eta, k) = match (&m.preset, &m.eta, &m.k) {
                    (Some(preset), None, None) => {
                        let names: Vec<&str> = METAL_PRESETS.iter().map(|(n, _, _)| *n).collect();
                        let name = self.one_of(preset, &object, "preset", &names)?;
                        let (_, eta, k) = METAL_PRESETS.iter().find(|(n, _, _)| *n == name).expect("one_of found it");
                        (ColorParam::constant(Vec3::from(*eta)), ColorParam::constant(Vec3::from(*k)))
                    }
                    (None, Some(eta), Some(k)) => {
                        (self.color_param(eta, &object, "eta", false)?, self.color_param(k, &object, "k", false)?)
                    }
                    (Some(p), _, _) => {
                        return Err(self.invalid(
                            &p.span(),
                            &object,
                            "give either `preset` or `eta` and `k`, not both".to_string(),
                        ));
                    }
                    _ => {
                        return Err(self.invalid(
                            &def.span(),
                            &object,
                            format!(
                                "a conductor needs `preset` (one of {}) or both `eta` and `k`",
                                METAL_PRESETS.iter().map(|(n, _, _)| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
                            ),
                        ));
                    }
                };
                if let ColorParam { value, texture: None } = eta {
                    if value.min_element() <= 0.0 {
                        let span = span_of(&m.eta).unwrap_or(def.span());
                        return Err(self.invalid(
                            &span,
                            &object,
                            format!("`eta` is {value}; it must be > 0 per channel"),
                        ));
                    }
                }
                let roughness = self.roughness(m, &object)?;
                let tint = match &m.tint {
                    Some(t) => self.color_param(t, &object, "tint", true)?,
                    None => ColorParam::constant(Vec3::from(kinds::TINT.triple())),
                };
                MaterialKind::Conductor { eta, k, roughness, tint }
            }
            "plastic" => {
                let reflectance = match &m.reflectance {
                    Some(r) => self.color_param(r, &object, "reflectance", true)?,
                    None => ColorParam::constant(Vec3::from(kinds::REFLECTANCE.triple())),
                };
                let ior = self.ior(m, &object)?;
                let roughness = self.roughness(m, &object)?;
                let nonlinear = m.nonlinear.as_ref().map_or(kinds::NONLINEAR.flag(), |n| *n.get_ref());
                MaterialKind::Plastic { reflectance, ior, roughness, nonlinear }
            }
            "thin_dielectric" => MaterialKind::ThinDielectric { ior: self.ior(m, &object)? },
            "null" => MaterialKind::Null,
            _ => {
                let example = "materials = [\"rust\", \"paint\"]";
                let list = self.require(&m.materials, &def.span(), &object, "materials", example)?;
                if list.get_ref().len() != 2 {
                    return Err(self.invalid(
                        &list.span(),
                        &object,
                        format!(
                            "`materials` names {} materials; a mix takes 2, e.g. `{example}`",
                            list.get_ref().len()
                        ),
                    ));
                }
                let mut ids = [0u32; 2];
                for (id, mixed) in ids.iter_mut().zip(list.get_ref()) {
                    *id = self.material_id(&Spanned::new(list.span(), mixed.clone()), &object)?;
                    if self.materials[*id as usize].kind == MaterialKind::Null {
                        return Err(self.invalid(
                            &list.span(),
                            &object,
                            format!("\"{}\" is a null material, which a mix cannot hold", printable(mixed)),
                        ));
                    }
                    if self.mix_depth(*id) + 1 > MIX_MAX_DEPTH {
                        return Err(self.invalid(
                            &list.span(),
                            &object,
                            format!("mixes nest at most {MIX_MAX_DEPTH} deep; \"{mixed}\" is already a deep mix"),
                        ));
                    }
                }
                let weight = match &m.weight {
                    Some(w) => self.scalar_param(
                        w,
                        &object,
                        "weight",
                        0.0,
                        1.0,
                        "a fraction in [0, 1] (of the second material)",
                    )?,
                    None => ScalarParam::constant(kinds::WEIGHT.number() as f32),
                };
                MaterialKind::Mix { a: ids[0], b: ids[1], weight }
            }
        };
        let two_sided = m.two_sided.as_ref().map_or(kinds::TWO_SIDED.flag(), |t| *t.get_ref());
        self.add_material(name, MaterialDesc { kind, emission, two_sided, opacity, normal });
        Ok(())
    }

    pub(super) fn ior(&self, m: &MaterialDef, object: &str) -> Result<f32> {
        let Some(ior_def) = &m.ior else {
            return Ok(kinds::IOR.number() as f32);
        };
        let ior = self.number(ior_def, object, "ior")?;
        if !(ior as f64 >= 1.0 / MAX_IOR && ior as f64 <= MAX_IOR) {
            return Err(self.invalid(
                &ior_def.span(),
                object,
                format!(
                    "`ior` is {}; the index of refraction must be > 0, from {} to {MAX_IOR} (glass is about 1.5)",
                    fmt_f32(ior),
                    1.0 / MAX_IOR
                ),
            ));
        }
        Ok(ior)
    }

    /// `roughness`: the microfacet width alpha, one number, [along u, along v], or a texture;
    /// and `distribution`, that of the microfacet normals.
    pub(super) fn roughness(&mut self, m: &MaterialDef, object: &str) -> Result<Roughness> {
        let distribution_name = match &m.distribution {
            Some(d) => self.one_of(d, object, "distribution", kinds::DISTRIBUTION.choices())?,
            None => kinds::DISTRIBUTION.text(),
        };
        let distribution = if distribution_name == "beckmann" { Distribution::Beckmann } else { Distribution::Ggx };
        let Some(def) = &m.roughness else {
            return Ok(Roughness { distribution, ..Roughness::SMOOTH });
        };
        let span = def.span();
        let what = "`roughness` is the GGX width alpha in [0, 1]: one number, [along u, along v], or \
                    { texture = \"name\", scale = 0.3 }";
        let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        let (alpha, texture) = match def.get_ref() {
            toml::Value::Array(list) if list.len() == 2 => match (number(&list[0]), number(&list[1])) {
                (Some(u), Some(v)) => ([u, v], None),
                _ => return Err(self.invalid(&span, object, what.to_string())),
            },
            toml::Value::Table(t) => {
                let Some(toml::Value::String(name)) = t.get("texture") else {
                    return Err(self.invalid(&span, object, what.to_string()));
                };
                if let Some(bad) = t.keys().find(|k| *k != "texture" && *k != "scale") {
                    return Err(self.invalid(&span, object, format!("unknown field `{bad}` in `roughness`; {what}")));
                }
                let scale = match t.get("scale") {
                    Some(v) => number(v).ok_or_else(|| self.invalid(&span, object, what.to_string()))?,
                    None => 1.0,
                };
                let id = self.texture_id(name, &span, object)?;
                let role = TexelRole::Scalar { min: 0.0, max: 1.0, what: "a GGX alpha in [0, 1]" };
                self.check_texels(id, Vec3::splat(scale as f32), role, &span, object, "roughness")?;
                ([scale, scale], Some(id))
            }
            v => match number(v) {
                Some(a) => ([a, a], None),
                None => return Err(self.invalid(&span, object, what.to_string())),
            },
        };
        if let Some(bad) = alpha.iter().find(|a| !(**a >= 0.0 && **a <= 1.0)) {
            return Err(self.invalid(&span, object, format!("`roughness` is {bad}; {what}")));
        }
        Ok(Roughness { alpha: alpha.map(|a| a as f32), texture, distribution })
    }

    /// How deep the mixes under material `id` nest (0 for a material that is no mix).
    pub(super) fn mix_depth(&self, id: u32) -> u32 {
        match self.materials[id as usize].kind {
            MaterialKind::Mix { a, b, .. } => 1 + self.mix_depth(a).max(self.mix_depth(b)),
            _ => 0,
        }
    }

    pub(super) fn add_material(&mut self, name: String, material: MaterialDesc) -> u32 {
        self.materials.push(material);
        self.material_names.push(name);
        self.material_used.push(false);
        (self.materials.len() - 1) as u32
    }

    pub(super) fn material_id(&mut self, value: &Spanned<String>, object: &str) -> Result<u32> {
        let name = value.get_ref();
        if let Some(id) = self.material_names.iter().position(|n| n == name) {
            self.material_used[id] = true;
            return Ok(id as u32);
        }
        let shown = printable(name);
        let hint = match suggest(name, &self.material_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None if self.material_names.is_empty() => {
                format!("define it with a [materials.{shown}] table")
            }
            None => format!(
                "defined materials: {}; or add a [materials.{shown}] table",
                self.material_names
                    .iter()
                    .take(20)
                    .map(|n| format!("\"{}\"", printable(n)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        Err(self.invalid(&value.span(), object, format!("unknown material \"{shown}\" ({hint})")))
    }
}

#[cfg(test)]
mod tests {
    use super::METAL_PRESETS;
    use crate::scene::kinds::METAL_PRESET_NAMES;

    #[test]
    fn declared_presets_are_those_with_optical_constants() {
        let names: Vec<&str> = METAL_PRESETS.iter().map(|(n, _, _)| *n).collect();
        assert_eq!(names, METAL_PRESET_NAMES);
    }
}
