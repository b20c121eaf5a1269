//! Colours (`rgb`, `srgb`, `spectrum`, `float`) and textures (`bitmap`, `checkerboard`, `scale`)
//! as TOML values: a constant or `{ texture = "name" }` with a `[textures.name]` entry.

use glam::{DMat4, DVec4};

use super::out::{field, list, num, string, vec3, Fields};
use super::props::{numbers, parse_number, value, Plugin};
use super::xml::Element;
use super::{MitsubaError, Result, Translator, Uv};

/// Where a parameter came from: a constant, or a texture (its TOML value).
pub(crate) enum Param {
    Constant([f64; 3]),
    Texture(String),
}

impl Param {
    pub fn toml(&self) -> String {
        match self {
            Param::Constant(c) if c[0] == c[1] && c[1] == c[2] => num(c[0]),
            Param::Constant(c) => vec3(*c),
            Param::Texture(t) => t.clone(),
        }
    }
}

impl<'a> Translator<'a> {
    /// A colour parameter `name` of `p`: a property or a nested texture.
    pub(crate) fn color(&mut self, p: &Plugin<'a>, name: &str, uv: Uv) -> Result<Option<Param>> {
        self.param(p, name, uv, false)
    }

    /// A scalar parameter (opacity, roughness, a weight): a number or a texture.
    pub(crate) fn scalar(&mut self, p: &Plugin<'a>, name: &str, uv: Uv) -> Result<Option<Param>> {
        self.param(p, name, uv, true)
    }

    fn param(&mut self, p: &Plugin<'a>, name: &str, uv: Uv, scalar: bool) -> Result<Option<Param>> {
        if let Some(e) = p.prop(name) {
            return self.constant(e).map(|c| Some(Param::Constant(c)));
        }
        let nested = p.plugins("texture", Some(name));
        let Some(&t) = nested.first() else { return Ok(None) };
        let t = self.resolve(t, "texture")?;
        Ok(Some(self.texture(t, uv, scalar)?))
    }

    /// The RGB of a `<rgb>`, `<srgb>`, `<spectrum>` or `<float>` property.
    pub(crate) fn constant(&mut self, e: &Element) -> Result<[f64; 3]> {
        let v = value(e)?;
        let bad = || {
            MitsubaError::at(
                e.pos,
                format!("<{}>: `value` = \"{}\" is not a colour", e.tag, crate::limits::printable(v)),
            )
        };
        match e.tag.as_str() {
            "float" | "integer" => parse_number(v).map(|x| [x; 3]).ok_or_else(bad),
            "rgb" | "color" | "srgb" => {
                let c = if let Some(hex) = v.trim().strip_prefix('#') {
                    let n = u32::from_str_radix(hex, 16).ok().filter(|_| hex.len() == 6).ok_or_else(bad)?;
                    let c = [(n >> 16) & 255, (n >> 8) & 255, n & 255].map(|b| srgb_to_linear(b as f64 / 255.0));
                    return Ok(c);
                } else {
                    match numbers(v).as_deref() {
                        Some([x]) => [*x; 3],
                        Some([r, g, b]) => [*r, *g, *b],
                        _ => return Err(bad()),
                    }
                };
                Ok(if e.tag == "srgb" { c.map(srgb_to_linear) } else { c })
            }
            "spectrum" => {
                if let Some(x) = parse_number(v) {
                    return Ok([x; 3]);
                }
                let mut samples = Vec::new();
                for item in v.split(',') {
                    let (l, x) = item.split_once(':').ok_or_else(bad)?;
                    samples.push((parse_number(l).ok_or_else(bad)?, parse_number(x).ok_or_else(bad)?));
                }
                if samples.is_empty() {
                    return Err(bad());
                }
                samples.sort_by(|a, b| a.0.total_cmp(&b.0));
                self.warn(e.pos, "a sampled <spectrum> is read at 650, 550 and 450 nm as red, green and blue".into());
                Ok([650.0, 550.0, 450.0].map(|l| interpolate(&samples, l)))
            }
            other => Err(MitsubaError::at(
                e.pos,
                format!(
                    "<{}> is not a colour Photonix reads; give <rgb>, <srgb>, <spectrum> (a value or wavelength:value pairs) or <float>",
                    crate::limits::printable(other)
                ),
            )),
        }
    }

    /// A texture plugin as a TOML value, writing its `[textures.name]` once per uv kind.
    pub(crate) fn texture(&mut self, t: &'a Element, uv: Uv, scalar: bool) -> Result<Param> {
        let p = Plugin::new(t);
        match p.kind.as_str() {
            // Mitsuba 0.5's `scale`: another texture times a factor.
            "scale" => {
                let factor = p.float_or("scale", 1.0)?;
                let inner = self.nested_plugins(&p, "texture")?;
                let Some(&inner) = inner.first() else {
                    return Err(p.error(t.pos, "needs a nested <texture>".into()));
                };
                let inner = self.resolve(inner, "texture")?;
                self.finish(&p);
                return Ok(match self.texture(inner, uv, scalar)? {
                    Param::Constant(c) => Param::Constant(c.map(|x| x * factor)),
                    Param::Texture(tx) => Param::Texture(tx.replacen('}', &format!(", scale = {} }}", num(factor)), 1)),
                });
            }
            "bitmap" | "checkerboard" => {}
            other => {
                self.warn(
                    t.pos,
                    format!(
                        "the `{}` texture is not supported; it is rendered as a constant 0.5",
                        crate::limits::printable(other)
                    ),
                );
                return Ok(Param::Constant([0.5; 3]));
            }
        }
        let key = (t as *const Element as usize, uv, scalar);
        if let Some(name) = self.textures.get(&key) {
            return Ok(Param::Texture(format!("{{ texture = {} }}", string(name))));
        }
        let base = p.id().map(str::to_string).unwrap_or_else(|| format!("{} line {}", p.kind, t.pos.line));
        let name = self.out.unique("textures", &base);
        let mut fields = Fields::new();
        let to_uv = self.to_uv(&p)?;
        let from_uv = match uv {
            Uv::Flipped => flip_v(),
            Uv::AsIs => DMat4::IDENTITY,
        };
        if p.kind == "bitmap" {
            let Some((file, at)) = p.string("filename")? else {
                return Err(p.error(t.pos, "needs a `filename`".into()));
            };
            let file = self.file_name(file, at);
            field(&mut fields, "type", string("image"));
            field(&mut fields, "file", string(&file));
            if p.boolean("raw")?.unwrap_or(false) {
                field(&mut fields, "color_space", string("linear"));
            }
            if let Some((mode, at)) = p.string("wrap_mode")? {
                let ours = match mode {
                    "repeat" => "repeat",
                    "mirror" => "mirror",
                    "clamp" => "clamp",
                    "zero" | "one" => {
                        self.warn(at, format!("`wrap_mode` \"{mode}\" is rendered as \"clamp\""));
                        "clamp"
                    }
                    other => {
                        return Err(p.error(
                            at,
                            format!(
                                "`wrap_mode` \"{}\": give repeat, mirror or clamp",
                                crate::limits::printable(other)
                            ),
                        ))
                    }
                };
                field(&mut fields, "wrap", string(ours));
            }
            if let Some((filter, at)) = p.string("filter_type")? {
                if filter == "nearest" {
                    self.warn(at, "`filter_type` \"nearest\" is rendered with bilinear filtering".into());
                }
            }
            if let Some((channel, at)) = p.string("channel")? {
                let ours = match channel {
                    "r" | "g" | "b" => channel,
                    "a" => "alpha",
                    other => {
                        return Err(p.error(
                            at,
                            format!("`channel` \"{}\": give r, g, b or a", crate::limits::printable(other)),
                        ))
                    }
                };
                field(&mut fields, "channel", string(ours));
            } else if scalar && has_alpha(&self.resolved_path(&file)) {
                // A cut-out (`mask` opacity) is the image's alpha, as Tungsten and Mitsuba 0.5
                // read such images; Mitsuba 3 would read the colour's luminance.
                field(&mut fields, "channel", string("alpha"));
                self.warn(at, "the image has an alpha channel; the scalar parameter reads it".into());
            }
            for quiet in ["gamma", "cache", "max_anisotropy"] {
                let _ = p.prop(quiet);
            }
            // Our image lookup is v-up (row 0 at v = 1), Mitsuba's v-down: flip on both sides.
            let lookup = flip_v() * to_uv * from_uv;
            self.transform_field(&mut fields, &lookup, &p)?;
        } else {
            let c0 = self.color(&p, "color0", uv)?.map_or(Ok([0.4; 3]), |c| constant_only(&p, c))?;
            let c1 = self.color(&p, "color1", uv)?.map_or(Ok([0.2; 3]), |c| constant_only(&p, c))?;
            field(&mut fields, "type", string("pattern"));
            field(&mut fields, "pattern", string("checker"));
            field(&mut fields, "space", string("uv"));
            field(&mut fields, "colors", format!("[{}, {}]", vec3(c0), vec3(c1)));
            // Mitsuba's squares are half a uv unit; the checker pattern's are one.
            let lookup = DMat4::from_scale(glam::DVec3::new(2.0, 2.0, 1.0)) * to_uv * from_uv;
            self.transform_field(&mut fields, &lookup, &p)?;
        }
        self.finish(&p);
        self.out.entry(&format!("[textures.{}]", super::out::key(&name)), &fields, t.pos);
        self.textures.insert(key, name.clone());
        Ok(Param::Texture(format!("{{ texture = {} }}", string(&name))))
    }

    /// `to_uv` (Mitsuba 3) or `uscale`, `vscale`, `uoffset`, `voffset` (0.5), as a matrix on
    /// (u, v, 0): Mitsuba keeps its 2D part (rows and columns x, y and the translation).
    #[allow(clippy::wrong_self_convention)] // named after Mitsuba's `to_uv` property
    fn to_uv(&mut self, p: &Plugin<'a>) -> Result<DMat4> {
        let mut m = match p.prop("to_uv") {
            Some(t) => {
                let m = super::transform::parse(t)?;
                let mut out = DMat4::IDENTITY;
                for (r, c) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    out.col_mut(c)[r] = m.col(c)[r];
                }
                out.w_axis = DVec4::new(m.w_axis.x, m.w_axis.y, 0.0, 1.0);
                out
            }
            None => DMat4::IDENTITY,
        };
        let us = p.float_or("uscale", 1.0)?;
        let vs = p.float_or("vscale", 1.0)?;
        let uo = p.float_or("uoffset", 0.0)?;
        let vo = p.float_or("voffset", 0.0)?;
        if (us, vs, uo, vo) != (1.0, 1.0, 0.0, 0.0) {
            m = DMat4::from_translation(glam::DVec3::new(uo, vo, 0.0))
                * DMat4::from_scale(glam::DVec3::new(us, vs, 1.0))
                * m;
        }
        Ok(m)
    }

    /// `transform = { matrix = [...] }` placing a texture whose lookup point is `lookup` of the uv.
    fn transform_field(&mut self, fields: &mut Fields, lookup: &DMat4, p: &Plugin) -> Result<()> {
        if lookup.abs_diff_eq(DMat4::IDENTITY, 1e-12) {
            return Ok(());
        }
        if lookup.determinant().abs() < 1e-12 {
            return Err(p.error(p.pos(), "`to_uv` is not invertible".into()));
        }
        let place = lookup.inverse();
        fields.push(("transform".into(), format!("{{ matrix = {} }}", list(&super::transform::row_major(&place)))));
        Ok(())
    }

    /// A TOML file name as a path to read now.
    pub(crate) fn resolved_path(&self, file: &str) -> std::path::PathBuf {
        let folder = self.files.first().and_then(|f| f.parent()).unwrap_or(std::path::Path::new(""));
        folder.join(file)
    }
}

fn constant_only(p: &Plugin, c: Param) -> Result<[f64; 3]> {
    match c {
        Param::Constant(c) => Ok(c),
        Param::Texture(_) => Err(p.error(p.pos(), "a checkerboard's colours must be constants".into())),
    }
}

/// (u, v) -> (u, 1 - v).
fn flip_v() -> DMat4 {
    DMat4::from_cols(DVec4::X, -DVec4::Y, DVec4::Z, DVec4::new(0.0, 1.0, 0.0, 1.0))
}

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn interpolate(samples: &[(f64, f64)], l: f64) -> f64 {
    let i = samples.partition_point(|s| s.0 < l);
    if i == 0 {
        return samples[0].1;
    }
    if i == samples.len() {
        return samples[i - 1].1;
    }
    let (a, b) = (samples[i - 1], samples[i]);
    a.1 + (b.1 - a.1) * (l - a.0) / (b.0 - a.0)
}

/// Whether an image file has an alpha channel (read from its header only).
fn has_alpha(path: &std::path::Path) -> bool {
    let Ok(reader) = image::ImageReader::open(path).and_then(|r| r.with_guessed_format()) else { return false };
    let Ok(decoder) = reader.into_decoder() else { return false };
    image::ImageDecoder::color_type(&decoder).has_alpha()
}
