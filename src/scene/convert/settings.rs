//! `[render]` and `[photons]`: samples, passes, depth, the integrator and the photon maps.

use toml::Spanned;

use super::{Builder, Result};
use crate::limits::{
    fmt_f32, MAX_DEPTH, MAX_FILTER_RADIUS, MAX_GATHER_RAYS, MAX_PASSES, MAX_PHOTON_PATHS, MAX_SPP, MIN_FILTER_RADIUS,
};
use crate::scene::{Filter, Integrator, LightSampler, PhotonSettings, RenderSettings};

const DEFAULT_SPP: u32 = 4;
const DEFAULT_PASSES: u32 = 4;
const DEFAULT_MAX_DEPTH: u32 = 16;

impl Builder<'_> {
    /// The `[render]` settings, and whether the integrator is `auto_integrator`'s to choose.
    pub(super) fn render(
        &self,
        def: Option<&Spanned<crate::scene::format::RenderDef>>,
    ) -> Result<(RenderSettings, bool)> {
        let object = "[render]";
        let mut settings = RenderSettings {
            spp: DEFAULT_SPP,
            passes: DEFAULT_PASSES,
            max_depth: DEFAULT_MAX_DEPTH,
            seed: 0,
            integrator: Integrator::default(),
            integrator_auto: None,
            filter: Filter::default(),
            filter_radius: None,
            denoise: false,
            light_sampler: LightSampler::default(),
            adaptive: false,
        };
        let mut auto = true;
        let Some(def) = def else {
            return Ok((settings, auto));
        };
        let r = def.get_ref();
        if let Some(spp) = &r.spp {
            settings.spp = self.integer(spp, object, "spp", 1, MAX_SPP, " samples per pixel", "")?;
        }
        if let Some(depth) = &r.max_depth {
            settings.max_depth = self.integer(depth, object, "max_depth", 1, MAX_DEPTH, "", "")?;
        }
        if let Some(passes) = &r.passes {
            settings.passes = self.integer(passes, object, "passes", 1, MAX_PASSES, "", "")?;
        }
        if let Some(seed) = &r.seed {
            settings.seed = self.integer(seed, object, "seed", 0, u32::MAX, "", "")?;
        }
        if let Some(name) = &r.integrator {
            let names: Vec<&str> = Integrator::NAMES.iter().map(|(n, _)| *n).chain([Integrator::AUTO]).collect();
            let name = self.one_of(name, object, "integrator", &names)?;
            if name != Integrator::AUTO {
                settings.integrator = Integrator::from_name(name).expect("one_of returns one of the names");
                auto = false;
            }
        }
        if let Some(name) = &r.filter {
            let names: Vec<&str> = Filter::NAMES.iter().map(|(n, _)| *n).collect();
            let name = self.one_of(name, object, "filter", &names)?;
            settings.filter =
                Filter::NAMES.iter().find(|(n, _)| *n == name).expect("one_of returns one of the names").1;
        }
        if let Some(radius) = &r.filter_radius {
            let v = self.number(radius, object, "filter_radius")?;
            if !(MIN_FILTER_RADIUS..=MAX_FILTER_RADIUS).contains(&v) {
                return Err(self.invalid(
                    &radius.span(),
                    object,
                    format!(
                        "`filter_radius` is {} pixels; it must lie in {MIN_FILTER_RADIUS} to {MAX_FILTER_RADIUS} \
                         (the `{}` filter's own is {}; leave the field out for it)",
                        fmt_f32(v),
                        Filter::NAMES.iter().find(|(_, f)| *f == settings.filter).map_or("box", |(n, _)| n),
                        fmt_f32(settings.filter.default_radius())
                    ),
                ));
            }
            settings.filter_radius = Some(v);
        }
        if let Some(denoise) = &r.denoise {
            settings.denoise = *denoise.get_ref();
        }
        if let Some(adaptive) = &r.adaptive {
            settings.adaptive = *adaptive.get_ref();
        }
        if let Some(name) = &r.light_sampler {
            let names: Vec<&str> = LightSampler::NAMES.iter().map(|(n, _)| *n).collect();
            let name = self.one_of(name, object, "light_sampler", &names)?;
            settings.light_sampler =
                LightSampler::NAMES.iter().find(|(n, _)| *n == name).expect("one_of returns one of the names").1;
        }
        Ok((settings, auto))
    }

    pub(super) fn photons(
        &self,
        def: Option<&Spanned<crate::scene::format::PhotonsDef>>,
    ) -> Result<Option<PhotonSettings>> {
        let object = "[photons]";
        let mut settings = PhotonSettings::default();
        let Some(def) = def else {
            return Ok(Some(settings));
        };
        let p = def.get_ref();
        if let Some(count) = &p.count {
            settings.photons = self.integer(
                count,
                object,
                "count",
                1,
                MAX_PHOTON_PATHS,
                " photon paths",
                "; set `enabled = false` to turn photon mapping off",
            )?;
        }
        if let Some(count) = &p.caustic_count {
            settings.caustic_photons =
                self.integer(count, object, "caustic_count", 1, MAX_PHOTON_PATHS, " photon paths", "")?;
        }
        let radius = |value: &Spanned<f64>, field: &str| -> Result<f32> {
            let r = self.number(value, object, field)?;
            if r <= 0.0 {
                return Err(self.invalid(
                    &value.span(),
                    object,
                    format!(
                        "`{field}` is {}; give a positive radius in scene units, or leave it out to derive one",
                        fmt_f32(r)
                    ),
                ));
            }
            Ok(r)
        };
        if let Some(r) = &p.radius {
            settings.radius = Some(radius(r, "radius")?);
        }
        if let Some(r) = &p.caustic_radius {
            settings.caustic_radius = Some(radius(r, "caustic_radius")?);
        }
        if let Some(r) = &p.volume_radius {
            settings.volume_radius = Some(radius(r, "volume_radius")?);
        }
        if let Some(rays) = &p.gather_rays {
            settings.gather_rays =
                self.integer(rays, object, "gather_rays", 0, MAX_GATHER_RAYS, "", "; 0 reads the global map directly")?;
        }
        if let Some(depth) = &p.max_depth {
            settings.max_depth = self.integer(depth, object, "max_depth", 1, MAX_DEPTH, "", "")?;
        }
        if let Some(a) = &p.alpha {
            let alpha = self.number(a, object, "alpha")?;
            if !(alpha > 0.0 && alpha < 1.0) {
                return Err(self.invalid(
                    &a.span(),
                    object,
                    format!("`alpha` is {}; it must be in (0, 1), e.g. 0.667", fmt_f32(alpha)),
                ));
            }
            settings.alpha = alpha;
        }
        if let Some(g) = &p.glossy_threshold {
            let threshold = self.number(g, object, "glossy_threshold")?;
            if !(0.0..=1.0).contains(&threshold) {
                return Err(self.invalid(
                    &g.span(),
                    object,
                    format!("`glossy_threshold` is {threshold}; it is a GGX width in [0, 1], e.g. 0.25"),
                ));
            }
            settings.glossy_threshold = threshold;
        }
        if p.enabled.as_ref().is_some_and(|e| !*e.get_ref()) {
            return Ok(None);
        }
        Ok(Some(settings))
    }
}
