//! `<bsdf>` plugins as `[materials.name]` entries. Wrappers (`twosided`, `mask`, `bumpmap`,
//! `normalmap`) become fields of the material they wrap; `blendbsdf` and `mixturebsdf` become
//! `mix` materials over materials written before them.

use super::out::{field, num, string, Fields};
use super::props::Plugin;
use super::textures::Param;
use super::xml::Element;
use super::{Pos, Result, Translator, Uv};

/// Mitsuba's named indices of refraction (its `ior.h`).
const IOR_NAMES: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Mitsuba's named conductors that Photonix has as presets (the rest: give `eta` and `k`).
const METALS: &[(&str, &str)] =
    &[("Ag", "silver"), ("Al", "aluminium"), ("Au", "gold"), ("Cr", "chrome"), ("Cu", "copper"), ("Cu2O", "copper")];

/// A material being built: its type and fields, and whether Mitsuba shades its back.
pub(crate) struct Material {
    pub kind: &'static str,
    pub fields: Fields,
    pub two_sided: bool,
}

impl<'a> Translator<'a> {
    /// The name of the material for `bsdf` (an element or a `<ref>`), writing it on first use;
    /// `emission` (TOML text) makes a copy that glows.
    pub(crate) fn material_name(
        &mut self,
        bsdf: Option<&'a Element>,
        uv: Uv,
        emission: Option<&str>,
        at: Pos,
    ) -> Result<String> {
        let Some(bsdf) = bsdf else {
            return Ok(match emission {
                None => self.default_material(at),
                Some(e) => {
                    let name = self.out.unique("materials", "emitter");
                    let fields = vec![
                        ("type".into(), string("diffuse")),
                        ("reflectance".into(), "0.5".into()),
                        ("emission".into(), e.to_string()),
                    ];
                    self.out.entry(&format!("[materials.{}]", super::out::key(&name)), &fields, at);
                    name
                }
            });
        };
        let el = self.resolve(bsdf, "bsdf")?;
        let key = (el as *const Element as usize, uv, emission.unwrap_or("").to_string());
        if let Some(name) = self.materials.get(&key) {
            return Ok(name.clone());
        }
        let mut m = self.bsdf(el, uv)?;
        let base = el
            .attr("id")
            .map(str::to_string)
            .unwrap_or_else(|| format!("{} line {}", el.attr("type").unwrap_or("bsdf"), el.pos.line));
        let base = if emission.is_some() { format!("{base} (emitter)") } else { base };
        if let Some(e) = emission {
            if matches!(m.kind, "mix" | "null") {
                self.warn(
                    el.pos,
                    format!("an area emitter on a `{}` material glows over a black diffuse surface", m.kind),
                );
                m = Material { kind: "diffuse", fields: vec![("reflectance".into(), "0".into())], two_sided: true };
            }
            field(&mut m.fields, "emission", e.to_string());
        }
        let name = self.out.unique("materials", &base);
        if !m.two_sided && matches!(m.kind, "diffuse" | "conductor" | "mirror" | "plastic") {
            self.one_sided.push(name.clone());
        }
        let mut fields = vec![("type".to_string(), string(m.kind))];
        fields.extend(m.fields);
        self.out.entry(&format!("[materials.{}]", super::out::key(&name)), &fields, el.pos);
        self.materials.insert(key, name.clone());
        Ok(name)
    }

    /// Mitsuba's material for a shape without a BSDF: diffuse, reflectance 0.5.
    fn default_material(&mut self, at: Pos) -> String {
        if let Some(name) = &self.default_material {
            return name.clone();
        }
        let name = self.out.unique("materials", "default");
        let fields = vec![("type".into(), string("diffuse")), ("reflectance".into(), "0.5".into())];
        self.out.entry(&format!("[materials.{}]", super::out::key(&name)), &fields, at);
        self.default_material = Some(name.clone());
        name
    }

    fn bsdf(&mut self, el: &'a Element, uv: Uv) -> Result<Material> {
        let p = Plugin::new(el);
        let mut m = Material { kind: "diffuse", fields: Fields::new(), two_sided: false };
        match p.kind.as_str() {
            "diffuse" | "roughdiffuse" => {
                if p.kind == "roughdiffuse" {
                    self.warn(el.pos, "`roughdiffuse` (Oren-Nayar) is rendered as `diffuse` (Lambertian)".into());
                    p.scalar_prop_quiet(&["alpha", "use_fast_approx"]);
                }
                let r = self.color(&p, "reflectance", uv)?.unwrap_or(Param::Constant([0.5; 3]));
                m.fields.push(("reflectance".into(), r.toml()));
            }
            "conductor" | "roughconductor" => self.conductor(&p, uv, &mut m)?,
            "dielectric" | "roughdielectric" | "thindielectric" => self.dielectric(&p, uv, &mut m)?,
            "plastic" | "roughplastic" => self.plastic(&p, uv, &mut m)?,
            "null" => m.kind = "null",
            "twosided" => {
                let inner = self.nested_plugins(&p, "bsdf")?;
                let Some(&first) = inner.first() else { return Err(p.error(el.pos, "needs a nested <bsdf>".into())) };
                if inner.len() > 1 {
                    self.warn(
                        inner[1].pos,
                        "a second (back-face) BSDF is not supported; both faces use the first".into(),
                    );
                }
                let first = self.resolve(first, "bsdf")?;
                m = self.bsdf(first, uv)?;
                m.two_sided = true;
            }
            "mask" => {
                let opacity = self.scalar(&p, "opacity", uv)?.unwrap_or(Param::Constant([0.5; 3]));
                m = self.wrapped(&p, uv)?;
                field(&mut m.fields, "opacity", opacity.toml());
            }
            "bumpmap" => {
                let textures = self.nested_plugins(&p, "texture")?;
                let Some(&t) = textures.first() else { return Err(p.error(el.pos, "needs a nested <texture>".into())) };
                let t = self.resolve(t, "texture")?;
                let scale = p.float_or("scale", 1.0)?;
                let Param::Texture(tex) = self.texture(t, uv, true)? else {
                    self.warn(el.pos, "a bump map of a constant does nothing".into());
                    return self.wrapped(&p, uv);
                };
                m = self.wrapped(&p, uv)?;
                self.warn(el.pos, "`bumpmap`: Mitsuba's heights are in uv units, Photonix's bump `scale` in scene units; the scale is taken as it is".into());
                field(&mut m.fields, "bump", tex.replacen('}', &format!(", scale = {} }}", num(scale)), 1));
            }
            "normalmap" => {
                let textures = p.plugins("texture", Some("normalmap"));
                let textures = if textures.is_empty() { self.nested_plugins(&p, "texture")? } else { textures };
                let Some(&t) = textures.first() else {
                    return Err(p.error(el.pos, "needs a `normalmap` <texture>".into()));
                };
                let t = self.resolve(t, "texture")?;
                let Param::Texture(tex) = self.texture(t, uv, false)? else {
                    return Err(p.error(el.pos, "the normal map must be a bitmap texture".into()));
                };
                m = self.wrapped(&p, uv)?;
                field(&mut m.fields, "normal_map", tex);
            }
            "blendbsdf" => {
                let weight = self.scalar(&p, "weight", uv)?.unwrap_or(Param::Constant([0.5; 3]));
                let names = self.children(&p, uv, 2)?;
                m = Material { kind: "mix", fields: Fields::new(), two_sided: true };
                m.fields.push(("materials".into(), format!("[{}, {}]", string(&names[0]), string(&names[1]))));
                m.fields.push(("weight".into(), weight.toml()));
            }
            "mixturebsdf" => m = self.mixture(&p, uv)?,
            other => {
                self.warn(
                    el.pos,
                    format!(
                        "the `{}` BSDF is not supported; it is rendered as a grey diffuse (0.5)",
                        crate::limits::printable(other)
                    ),
                );
                m.fields.push(("reflectance".into(), "0.5".into()));
                return Ok(m);
            }
        }
        self.finish(&p);
        Ok(m)
    }

    /// The one BSDF a wrapper holds.
    fn wrapped(&mut self, p: &Plugin<'a>, uv: Uv) -> Result<Material> {
        let inner = self.nested_plugins(p, "bsdf")?;
        let Some(&first) = inner.first() else { return Err(p.error(p.pos(), "needs a nested <bsdf>".into())) };
        let first = self.resolve(first, "bsdf")?;
        self.bsdf(first, uv)
    }

    /// Names of exactly `n` nested BSDFs, written before the mix that uses them.
    fn children(&mut self, p: &Plugin<'a>, uv: Uv, n: usize) -> Result<Vec<String>> {
        let inner = self.nested_plugins(p, "bsdf")?;
        if inner.len() != n {
            return Err(p.error(p.pos(), format!("needs {n} nested <bsdf>s; it has {}", inner.len())));
        }
        inner.iter().map(|b| self.material_name(Some(b), uv, None, b.pos)).collect()
    }

    /// `mixturebsdf`: weights w_i over n BSDFs as nested two-way mixes, each adding the next
    /// BSDF with weight w_i / (w_0 + ... + w_i).
    fn mixture(&mut self, p: &Plugin<'a>, uv: Uv) -> Result<Material> {
        let Some((w, at)) = p.string("weights")? else { return Err(p.error(p.pos(), "needs `weights`".into())) };
        let weights = super::props::numbers(w).filter(|w| w.iter().all(|x| *x >= 0.0)).unwrap_or_default();
        let n = weights.len();
        if n < 2 || weights.iter().sum::<f64>() <= 0.0 {
            return Err(p.error(at, "`weights`: give 2 or more non-negative numbers, not all 0".into()));
        }
        let names = self.children(p, uv, n)?;
        let total: f64 = weights.iter().sum();
        if (total - 1.0).abs() > 1e-6 {
            self.warn(at, format!("the weights add up to {total}; they are scaled to add up to 1"));
        }
        let mut current = names[0].clone();
        let mut sum = weights[0];
        for i in 1..n {
            sum += weights[i];
            let fields = vec![
                ("type".to_string(), string("mix")),
                ("materials".into(), format!("[{}, {}]", string(&current), string(&names[i]))),
                ("weight".into(), num(if sum > 0.0 { weights[i] / sum } else { 0.0 })),
            ];
            if i + 1 == n {
                return Ok(Material { kind: "mix", fields: fields[1..].to_vec(), two_sided: true });
            }
            let name = self.out.unique("materials", &format!("mixture line {} part {i}", p.pos().line));
            self.out.entry(&format!("[materials.{}]", super::out::key(&name)), &fields, p.pos());
            current = name;
        }
        unreachable!("a mixture has at least two weights (checked above)")
    }

    fn roughness(&mut self, p: &Plugin<'a>, uv: Uv, m: &mut Material, default_distribution: &str) -> Result<()> {
        let alpha = self.scalar(p, "alpha", uv)?;
        let au = self.scalar(p, "alpha_u", uv)?;
        let av = self.scalar(p, "alpha_v", uv)?;
        let value = match (alpha, au, av) {
            (_, Some(Param::Constant(u)), Some(Param::Constant(v))) => format!("[{}, {}]", num(u[0]), num(v[0])),
            (Some(a), _, _) => a.toml(),
            (None, Some(a), _) | (None, None, Some(a)) => a.toml(),
            (None, None, None) => num(0.1),
        };
        m.fields.push(("roughness".into(), value));
        let (dist, at) = p
            .string("distribution")?
            .map_or((default_distribution.to_string(), p.pos()), |(d, at)| (d.to_string(), at));
        match dist.as_str() {
            "ggx" => {}
            "beckmann" => m.fields.push(("distribution".into(), string("beckmann"))),
            "phong" | "as" => {
                self.warn(at, format!("the `{dist}` microfacet distribution is rendered as GGX of the same alpha"))
            }
            other => {
                return Err(p.error(
                    at,
                    format!("`distribution` \"{}\": give ggx or beckmann", crate::limits::printable(other)),
                ))
            }
        }
        Ok(())
    }

    fn conductor(&mut self, p: &Plugin<'a>, uv: Uv, m: &mut Material) -> Result<()> {
        m.kind = "conductor";
        let eta = self.color(p, "eta", uv)?;
        let k = self.color(p, "k", uv)?;
        let material = p.string("material")?;
        let _ = p.float("ext_eta")?;
        match (eta, k, material) {
            (Some(eta), Some(k), _) => {
                m.fields.push(("eta".into(), eta.toml()));
                m.fields.push(("k".into(), k.toml()));
            }
            (eta @ Some(_), None, _) | (eta @ None, Some(_), _) => {
                return Err(p.error(
                    p.pos(),
                    format!(
                        "gives `{}` without `{}`; give both",
                        if eta.is_some() { "eta" } else { "k" },
                        if eta.is_some() { "k" } else { "eta" }
                    ),
                ));
            }
            (None, None, Some(("none", _))) => {}
            (None, None, Some((name, at))) => match METALS.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)) {
                Some((_, preset)) => m.fields.push(("preset".into(), string(preset))),
                None => {
                    let known: Vec<&str> = METALS.iter().map(|(n, _)| *n).collect();
                    return Err(p.error(
                        at,
                        format!(
                            "the metal \"{}\" is not one Photonix knows ({}, none); give its `eta` and `k`",
                            crate::limits::printable(name),
                            known.join(", ")
                        ),
                    ));
                }
            },
            // Mitsuba 3's default is a perfect mirror ("none"), Mitsuba 0.5's copper.
            (None, None, None) if self.legacy => m.fields.push(("preset".into(), string("copper"))),
            (None, None, None) => {}
        }
        let mirror = !m.fields.iter().any(|(k, _)| k == "eta" || k == "preset");
        if mirror && p.kind == "conductor" {
            m.kind = "mirror";
        } else if mirror {
            // A rough perfect reflector: a conductor whose Fresnel term is 1 at every angle.
            m.fields.push(("eta".into(), num(0.0)));
            m.fields.push(("k".into(), num(1.0)));
        }
        let tint = self.color(p, "specular_reflectance", uv)?;
        if p.kind == "roughconductor" {
            self.roughness(p, uv, m, "beckmann")?;
        }
        match tint {
            Some(Param::Constant([1.0, 1.0, 1.0])) | None => {}
            Some(t) => m.fields.push(("tint".into(), t.toml())),
        }
        Ok(())
    }

    fn ior(&mut self, p: &Plugin<'a>, name: &str, default: f64) -> Result<f64> {
        let Some(e) = p.prop(name) else { return Ok(default) };
        let v = super::props::value(e)?;
        if let Some(x) = super::props::parse_number(v).filter(|x| *x > 0.0) {
            return Ok(x);
        }
        IOR_NAMES.iter().find(|(n, _)| n.eq_ignore_ascii_case(v.trim())).map(|(_, x)| *x).ok_or_else(|| {
            p.error(
                e.pos,
                format!(
                    "`{name}` = \"{}\" is not a positive number or a material Mitsuba names (bk7, water, air, ...)",
                    crate::limits::printable(v)
                ),
            )
        })
    }

    fn dielectric(&mut self, p: &Plugin<'a>, uv: Uv, m: &mut Material) -> Result<()> {
        m.kind = "dielectric";
        m.two_sided = true;
        let ior = self.ior(p, "int_ior", 1.5046)? / self.ior(p, "ext_ior", 1.000277)?;
        if p.kind == "thindielectric" {
            m.kind = "thin_dielectric";
        }
        m.fields.push(("ior".into(), num(ior)));
        if p.kind == "roughdielectric" {
            self.roughness(p, uv, m, "beckmann")?;
        }
        for name in ["specular_reflectance", "specular_transmittance"] {
            if let Some(c) = self.color(p, name, uv)? {
                if !matches!(c, Param::Constant([1.0, 1.0, 1.0])) {
                    self.warn(p.pos(), format!("`{name}` of a dielectric is not rendered; it is taken as 1"));
                }
            }
        }
        Ok(())
    }

    fn plastic(&mut self, p: &Plugin<'a>, uv: Uv, m: &mut Material) -> Result<()> {
        m.kind = "plastic";
        let base = self.color(p, "diffuse_reflectance", uv)?.unwrap_or(Param::Constant([0.5; 3]));
        m.fields.push(("reflectance".into(), base.toml()));
        let ior = self.ior(p, "int_ior", 1.49)? / self.ior(p, "ext_ior", 1.000277)?;
        m.fields.push(("ior".into(), num(ior)));
        if p.kind == "roughplastic" {
            self.roughness(p, uv, m, "beckmann")?;
        }
        if p.boolean("nonlinear")?.unwrap_or(false) {
            m.fields.push(("nonlinear".into(), "true".into()));
        }
        if let Some(c) = self.color(p, "specular_reflectance", uv)? {
            if !matches!(c, Param::Constant([1.0, 1.0, 1.0])) {
                self.warn(p.pos(), "`specular_reflectance` of a plastic is not rendered; it is taken as 1".into());
            }
        }
        Ok(())
    }
}

impl Plugin<'_> {
    /// Marks properties as read without using them (approximations that drop them say so).
    fn scalar_prop_quiet(&self, names: &[&str]) {
        for n in names {
            let _ = self.prop(n);
        }
    }
}
