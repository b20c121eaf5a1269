//! `<medium type="homogeneous">` as a `[media.name]` entry.

use super::out::{num, string, vec3, Fields};
use super::props::Plugin;
use super::textures::Param;
use super::xml::Element;
use super::{Result, Translator, Uv};

impl<'a> Translator<'a> {
    /// The name of the medium `el`, writing it on first use.
    pub(crate) fn medium(&mut self, el: &'a Element) -> Result<String> {
        let key = el as *const Element as usize;
        if let Some(name) = self.media.get(&key) {
            return Ok(name.clone());
        }
        let p = Plugin::new(el);
        if p.kind != "homogeneous" {
            return Err(
                p.error(el.pos, "Photonix reads `homogeneous` media (heterogeneous grids are not translated)".into())
            );
        }
        let scale = p.float_or("scale", 1.0)?;
        let constant = |this: &mut Self, name: &str| -> Result<Option<[f64; 3]>> {
            match this.color(&p, name, Uv::AsIs)? {
                None => Ok(None),
                Some(Param::Constant(c)) => Ok(Some(c)),
                Some(Param::Texture(_)) => Err(p.error(el.pos, format!("`{name}` must be a constant"))),
            }
        };
        let sigma_a = constant(self, "sigma_a")?;
        let sigma_s = constant(self, "sigma_s")?;
        let sigma_t = constant(self, "sigma_t")?;
        let albedo = constant(self, "albedo")?;
        if p.string("material")?.is_some() {
            return Err(p.error(el.pos, "named media (`material`) are not supported; give sigma_a and sigma_s".into()));
        }
        let mut fields = Fields::new();
        match (sigma_a, sigma_s) {
            (None, None) => {
                let t = sigma_t.unwrap_or([1.0; 3]);
                let a = albedo.unwrap_or([0.75; 3]);
                fields.push(("sigma_t".into(), vec3(t.map(|x| x * scale))));
                fields.push(("albedo".into(), vec3(a)));
            }
            (a, s) => {
                fields.push(("sigma_a".into(), vec3(a.unwrap_or([0.0; 3]).map(|x| x * scale))));
                fields.push(("sigma_s".into(), vec3(s.unwrap_or([0.0; 3]).map(|x| x * scale))));
            }
        }
        for ph in self.nested_plugins(&p, "phase")? {
            let phase = Plugin::new(ph);
            match phase.kind.as_str() {
                "isotropic" => {}
                "hg" => {
                    fields.push(("phase".into(), string("henyey-greenstein")));
                    fields.push(("g".into(), num(phase.float_or("g", 0.8)?)));
                }
                other => self.warn(
                    ph.pos,
                    format!("the `{}` phase function is rendered isotropic", crate::limits::printable(other)),
                ),
            }
            self.finish(&phase);
        }
        let base = p.id().map(str::to_string).unwrap_or_else(|| format!("medium line {}", el.pos.line));
        let name = self.out.unique("media", &base);
        self.finish(&p);
        self.out.entry(&format!("[media.{}]", super::out::key(&name)), &fields, el.pos);
        self.media.insert(key, name.clone());
        Ok(name)
    }
}
