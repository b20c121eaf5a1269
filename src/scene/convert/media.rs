//! `[media.NAME]`, `[atmosphere]` and `[fog]`: participating media, and the boundaries of shapes
//! that hold them.

use glam::{Affine3A, Vec3};
use toml::Spanned;

use super::values::vec3_text;
use super::{span_of, Builder, Present, Result};
use crate::limits::{fmt_number, printable, MAX_MEDIUM_COEFFICIENT};
use crate::scene::error::suggest;
use crate::scene::format::{AtmosphereDef, FogDef, MediumDef, ShapeDef, Vec3Def};
use crate::scene::kinds;
use crate::scene::material::{TextureDesc, TextureKind, TextureSpace};
use crate::scene::pattern::{PatternDesc, PatternKind};
use crate::scene::{Density, Geometry, MediumDesc, MediumInterface, Phase};

impl Builder<'_> {
    pub(super) fn medium(&mut self, key: &Spanned<String>, def: &Spanned<MediumDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("medium \"{}\"", printable(&name));
        let m = def.get_ref();
        if let Some(kind) = &m.r#type {
            let kind = self.one_of(kind, &object, "type", &["homogeneous", "heterogeneous"])?;
            match (kind, &m.density) {
                ("homogeneous", Some(d)) => {
                    return Err(self.invalid(
                        &d.span(),
                        &object,
                        "a `density` makes the medium heterogeneous; drop it, or say `type = \"heterogeneous\"`"
                            .to_string(),
                    ))
                }
                ("heterogeneous", None) => return Err(self.invalid(
                    &def.span(),
                    &object,
                    "a heterogeneous medium needs `density = \"name\"`, a [textures.name] pattern or voxels texture"
                        .to_string(),
                )),
                _ => {}
            }
        }
        let density = match &m.density {
            Some(name) => Some(self.density(name, &object)?),
            None => None,
        };
        let coefficient = |builder: &Self, value: &Spanned<Vec3Def>, field: &str| -> Result<Vec3> {
            let c = builder.vector(value, &object, field)?;
            if c.min_element() < 0.0 {
                return Err(builder.invalid(
                    &value.span(),
                    &object,
                    format!(
                        "`{field}` is negative ({}); a coefficient is >= 0 per channel (1 / scene unit)",
                        vec3_text(c)
                    ),
                ));
            }
            if c.max_element() > MAX_MEDIUM_COEFFICIENT {
                return Err(builder.invalid(
                    &value.span(),
                    &object,
                    format!(
                        "`{field}` is {}; coefficients are at most {} per scene unit (see docs/limits.md)",
                        vec3_text(c),
                        fmt_number(MAX_MEDIUM_COEFFICIENT as f64)
                    ),
                ));
            }
            Ok(c)
        };
        let (sigma_a, sigma_s) = match (&m.sigma_a, &m.sigma_s, &m.sigma_t, &m.albedo) {
            (None, None, Some(t), albedo) => {
                let sigma_t = coefficient(self, t, "sigma_t")?;
                let albedo = match albedo {
                    Some(a) => Vec3::from(self.color(a, &object, "albedo", true)?),
                    None => Vec3::from(kinds::ALBEDO.triple()),
                };
                (sigma_t * (Vec3::ONE - albedo), sigma_t * albedo)
            }
            (a, s, None, None) if a.is_some() || s.is_some() => (
                a.as_ref().map_or(Ok(Vec3::from(kinds::SIGMA_A.triple())), |a| coefficient(self, a, "sigma_a"))?,
                s.as_ref().map_or(Ok(Vec3::from(kinds::SIGMA_S.triple())), |s| coefficient(self, s, "sigma_s"))?,
            ),
            (_, _, None, Some(albedo)) => {
                return Err(self.invalid(
                    &albedo.span(),
                    &object,
                    "`albedo` goes with `sigma_t`; give `sigma_t` and `albedo`, or `sigma_a` and `sigma_s`".to_string(),
                ))
            }
            (None, None, None, None) => {
                return Err(self.invalid(
                    &def.span(),
                    &object,
                    "a medium needs `sigma_t` (and `albedo`) or `sigma_a` and `sigma_s`, e.g. `sigma_t = 0.1`"
                        .to_string(),
                ))
            }
            _ => {
                let span = span_of(&m.sigma_t).unwrap_or(def.span());
                return Err(self.invalid(
                    &span,
                    &object,
                    "give either `sigma_t` (with `albedo`) or `sigma_a` and `sigma_s`, not both".to_string(),
                ));
            }
        };
        let emission = match &m.emission {
            Some(e) => {
                let c = Vec3::from(self.color(e, &object, "emission", false)?);
                // Emission is estimated at collisions, so a channel without extinction has none.
                let st = sigma_a + sigma_s;
                if (0..3).any(|i| c[i] > 0.0 && st[i] <= 0.0) {
                    return Err(self.invalid(
                        &e.span(),
                        &object,
                        format!(
                            "`emission` ({}) is positive in a channel where the medium has no extinction ({}); give that channel some `sigma_a`",
                            vec3_text(c),
                            vec3_text(st)
                        ),
                    ));
                }
                c
            }
            None => Vec3::from(kinds::MEDIUM_EMISSION.triple()),
        };
        let phase_name = match &m.phase {
            Some(p) => self.one_of(p, &object, "phase", kinds::PHASE.choices())?,
            None if m.g.is_some() => "henyey-greenstein",
            None => kinds::PHASE.text(),
        };
        let phase = match (phase_name, &m.g) {
            ("isotropic", Some(g)) => {
                return Err(self.invalid(
                    &g.span(),
                    &object,
                    "`g` needs `phase = \"henyey-greenstein\"` (the isotropic phase has none)".to_string(),
                ))
            }
            ("isotropic", None) => Phase::Isotropic,
            (_, g) => {
                let g = match g {
                    Some(g) => {
                        let v = *g.get_ref();
                        if !(v.is_finite() && v > -1.0 && v < 1.0) {
                            return Err(self.invalid(
                                &g.span(),
                                &object,
                                format!("`g` is {}; the asymmetry lies strictly between -1 and 1 (0 is isotropic, > 0 scatters forward)", fmt_number(v)),
                            ));
                        }
                        v as f32
                    }
                    None => kinds::G.number() as f32,
                };
                Phase::HenyeyGreenstein { g }
            }
        };
        self.media.push(MediumDesc { sigma_a, sigma_s, emission, phase, density });
        self.medium_names.push(name);
        Ok(())
    }

    /// A medium's `density`: a texture that has a value at every point of space.
    pub(super) fn density(&mut self, name: &Spanned<String>, object: &str) -> Result<Density> {
        let texture = self.texture_id(name.get_ref(), &name.span(), object)?;
        let t = &self.textures[texture as usize];
        let refuse = |why: &str| {
            Err(self.invalid(
                &name.span(),
                object,
                format!("`density` texture \"{}\" {why}; use a pattern or a voxels texture", printable(name.get_ref())),
            ))
        };
        if matches!(t.kind, TextureKind::Image { .. })
            || t.space == TextureSpace::Uv && !matches!(t.kind, TextureKind::Constant(_))
        {
            return refuse("is looked up in uv space, which a medium does not have");
        }
        let max = t.kind.max_value();
        if !(max.is_finite() && max > 0.0) {
            return refuse("is 0 everywhere (the medium would be vacuum)");
        }
        Ok(Density { texture, max })
    }

    pub(super) fn medium_id(&self, value: &Spanned<String>, object: &str, field: &str) -> Result<Option<u32>> {
        let name = value.get_ref();
        if name == "vacuum" {
            return Ok(None);
        }
        if let Some(id) = self.medium_names.iter().position(|n| n == name) {
            return Ok(Some(id as u32));
        }
        let shown = printable(name);
        let hint = match suggest(name, &self.medium_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None => format!("define it with a [media.{shown}] table, or use \"vacuum\""),
        };
        Err(self.invalid(&value.span(), object, format!("unknown medium \"{shown}\" in `{field}` ({hint})")))
    }

    pub(super) fn atmosphere(&mut self, def: &Spanned<AtmosphereDef>) -> Result<()> {
        let object = "[atmosphere]";
        let medium = self.require(&def.get_ref().medium, &def.span(), object, "medium", "medium = \"fog\"")?;
        self.atmosphere = self.medium_id(medium, object, "medium")?;
        Ok(())
    }

    /// POV-Ray's `fog` as the atmosphere: a medium that absorbs with sigma_a = 1 / `distance` and
    /// glows with `color` / `distance`, so that a camera ray of length d returns exp(-d / D) of
    /// what it meets plus (1 - exp(-d / D)) of the colour, POV-Ray's blend. Ground fog scales
    /// both by POV-Ray's density (1 below `fog_offset`, 1 / (1 + (y - offset) / alt)^2 above).
    pub(super) fn fog(&mut self, def: &Spanned<FogDef>, has_atmosphere: bool) -> Result<()> {
        let object = "[fog]";
        let f = def.get_ref();
        let table = def.span();
        if has_atmosphere {
            return Err(self.invalid(
                &table,
                object,
                "[fog] fills all space, as [atmosphere] does; keep one of them".to_string(),
            ));
        }
        let kind = match &f.r#type {
            Some(t) => self.one_of(t, object, "type", &["constant", "ground"])?,
            None => "constant",
        };
        let distance = self.require(&f.distance, &table, object, "distance", "distance = 20")?;
        let distance = self.positive(distance, object, "distance")?;
        let color = match &f.color {
            Some(c) => Vec3::from(self.color(c, object, "color", false)?),
            None => Vec3::ZERO,
        };
        let present = [
            ("fog_offset", span_of(&f.fog_offset)),
            ("fog_alt", span_of(&f.fog_alt)),
            ("turbulence", span_of(&f.turbulence)),
            ("octaves", span_of(&f.octaves)),
            ("omega", span_of(&f.omega)),
            ("lambda", span_of(&f.lambda)),
        ];
        let sigma_a = Vec3::splat(1.0 / distance);
        if sigma_a.x > MAX_MEDIUM_COEFFICIENT {
            return Err(self.invalid(
                &span_of(&f.distance).unwrap_or(table.clone()),
                object,
                format!(
                    "`distance` is {distance}; it must be at least 1 / {MAX_MEDIUM_COEFFICIENT} (see docs/limits.md)"
                ),
            ));
        }
        let density = if kind == "ground" {
            let offset = match &f.fog_offset {
                Some(v) => self.number(v, object, "fog_offset")?,
                None => 0.0,
            };
            let alt = self.require(&f.fog_alt, &table, object, "fog_alt", "fog_alt = 1.5")?;
            let alt = self.positive(alt, object, "fog_alt")?;
            let turbulence = match &f.turbulence {
                Some(t) => {
                    let mut p = PatternDesc::new(PatternKind::Bozo);
                    p.turbulence = self.vector(t, object, "turbulence")?;
                    if let Some(o) = &f.octaves {
                        p.octaves = self.integer(o, object, "octaves", 1, 10, "", "")?;
                    }
                    if let Some(o) = &f.omega {
                        p.omega = self.number(o, object, "omega")?;
                    }
                    if let Some(l) = &f.lambda {
                        p.lambda = self.number(l, object, "lambda")?;
                    }
                    p.validate().map_err(|message| self.invalid(&t.span(), object, message))?;
                    Some(p)
                }
                None => {
                    self.fog_fields_unused(&present[3..], "ground fog without `turbulence`", "add `turbulence`")?;
                    None
                }
            };
            self.textures.push(TextureDesc {
                kind: TextureKind::GroundFog { offset, alt, turbulence },
                space: TextureSpace::World,
                lookup_from_texture: Affine3A::IDENTITY,
            });
            self.texture_names.push("[fog] ground fog".to_string());
            self.texture_used.push(true);
            Some(Density { texture: (self.textures.len() - 1) as u32, max: 1.0 })
        } else {
            self.fog_fields_unused(&present, "constant fog", "say `type = \"ground\"` for ground fog")?;
            None
        };
        self.media.push(MediumDesc {
            sigma_a,
            sigma_s: Vec3::ZERO,
            emission: color * sigma_a,
            phase: Phase::Isotropic,
            density,
        });
        self.medium_names.push("[fog]".to_string());
        self.atmosphere = Some((self.media.len() - 1) as u32);
        Ok(())
    }

    pub(super) fn fog_fields_unused(&self, present: &[Present<'_>], what: &str, fix: &str) -> Result<()> {
        for (name, span) in present {
            if let Some(span) = span {
                return Err(self.invalid(
                    span,
                    "[fog]",
                    format!("`{name}` does not apply to {what}; {fix}, or remove it"),
                ));
            }
        }
        Ok(())
    }

    /// The media a shape bounds (`interior`, `exterior`), refused on shapes that enclose nothing.
    pub(super) fn medium_interface(&self, kind: &str, s: &ShapeDef, object: &str) -> Result<Option<MediumInterface>> {
        let (interior, exterior) = match (&s.interior, &s.exterior) {
            (None, None) => return Ok(None),
            (None, Some(e)) => {
                return Err(self.invalid(
                    &e.span(),
                    object,
                    "`exterior` needs `interior`: name the medium inside the shape too (or \"vacuum\")".to_string(),
                ))
            }
            (Some(i), e) => (i, e),
        };
        let open = match kind {
            "quad" | "triangle" | "disc" | "bicubic_patch" => true,
            "cylinder" | "cone" => s.open.as_ref().is_some_and(|o| *o.get_ref()),
            _ => false,
        };
        if open {
            return Err(self.invalid(
                &interior.span(),
                object,
                format!(
                    "a medium needs a closed shape, and {} encloses no volume; use a box, a sphere, a closed mesh or another solid",
                    if kind == "cylinder" || kind == "cone" { format!("an open {kind}") } else { format!("a {kind}") }
                ),
            ));
        }
        let interior = self.medium_id(interior, object, "interior")?;
        let exterior = match exterior {
            Some(e) => self.medium_id(e, object, "exterior")?,
            None => self.atmosphere,
        };
        Ok(Some(MediumInterface { interior, exterior }))
    }

    /// Checks that the triangles from `first` on (one mesh) close up, every edge shared by two
    /// triangles that run it in opposite directions, and turns them around when they face
    /// inward (negative volume), so that the winding normal points out of the medium.
    pub(super) fn close_mesh(
        &mut self,
        first: usize,
        file: &Spanned<String>,
        object: &str,
        needs: &str,
        or_else: &str,
    ) -> Result<()> {
        use std::collections::HashMap;
        let key = |v: Vec3| v.to_array().map(f32::to_bits);
        let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        let mut volume = 0.0f64;
        for shape in &self.shapes[first..] {
            let Geometry::Triangle(t) = &shape.geometry else { continue };
            let [a, b, c] = t.vertices;
            volume += a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0;
            for (p, q) in [(a, b), (b, c), (c, a)] {
                // +1 for p -> q, -1 for q -> p, under one key: a closed, consistently wound mesh
                // sums every edge to 0.
                let (k, sign) = if key(p) < key(q) { ((key(p), key(q)), 1) } else { ((key(q), key(p)), -1) };
                *edges.entry(k).or_insert(0) += sign;
            }
        }
        let open = edges.values().filter(|&&n| n != 0).count();
        if open > 0 {
            return Err(self.invalid(
                &file.span(),
                object,
                format!(
                    "mesh {}: {needs} needs a closed mesh, but {open} edges border a single triangle or triangles wound against their neighbours; close the mesh{or_else}",
                    printable(file.get_ref())
                ),
            ));
        }
        if volume < 0.0 {
            for shape in &mut self.shapes[first..] {
                if let Geometry::Triangle(t) = &mut shape.geometry {
                    t.vertices.swap(1, 2);
                    if let Some(uv) = &mut t.uv {
                        uv.swap(1, 2);
                    }
                    if let Some(normals) = &mut t.normals {
                        normals.swap(1, 2);
                    }
                }
            }
        }
        Ok(())
    }
}
