//! Accumulation files: the sum of a set of progressive passes, to be merged with others.
//!
//! Format: an OpenEXR file whose layers `combined`, `direct`, `specular`, `indirect` and
//! `caustics` (channels R, G, B, float32) hold the **sum** over the passes of each pass's mean
//! radiance. Each layer's header carries one text attribute, `photonix_accumulation`, e.g.
//! `passes=64;ranges=0..32,64..96;scene=9c1f0e2d4b6a8c7e;spp=2;size=256x256;seed=0;...`: the pass
//! count, the pass ranges summed, and what the passes were rendered from (a `Provenance`: a hash
//! of the scene as the kernels see it and the settings that change the image), so that merge
//! refuses parts of different renders. (One attribute, not several: the EXR writer orders custom
//! attributes by hash, which would make the bytes of two identical renders differ.) The image is
//! the sum divided by the pass count. A render with feature layers (`--layers` or `--denoise`)
//! also holds their sums in layers `albedo`, `normal`, `depth` and `position`; merge sums them
//! where every part has them, so a merged render can be denoised. A render with adaptive
//! sampling (`--adaptive`), whose pixels hold different pass counts, also holds layer `samples`:
//! each pixel's pass count in all three channels (exact in float32 up to 2^24, beyond
//! `MAX_PASSES`); its image is the sum divided by that, and merge adds the counts. A file
//! without it counts every pass in every pixel.

use std::path::{Path, PathBuf};

use super::photons::PhotonSettings;
use super::prepare::SceneBuffers;
use super::progressive::Accumulator;
use crate::io::image::{format_of, Format, ImageError};
use crate::io::layers::write_layers_exr_with;
use crate::io::Image;

const MARK: &str = "photonix_accumulation";

#[derive(Debug, thiserror::Error)]
pub enum AccumulationError {
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error("{path}: not a Photonix accumulation file (it lacks the `{MARK}` attribute); render one with `photonix render --pass-range A..B -o FILE.exr`")]
    NotAccumulation { path: PathBuf },
    #[error("{path}: layer `{layer}` is missing; the file is damaged or was not written by photonix")]
    MissingLayer { path: PathBuf, layer: &'static str },
    #[error("{path} is {w}x{h} but {first} is {fw}x{fh}; only renders of one size can be merged")]
    SizeMismatch { path: PathBuf, w: u32, h: u32, first: PathBuf, fw: u32, fh: u32 },
    #[error("{path} holds passes {theirs} that another input holds too ({ours}); merging them would count those passes twice")]
    Overlap { path: PathBuf, theirs: String, ours: String },
    #[error("no accumulation files to merge")]
    Empty,
    #[error("{path}: the record of its passes is damaged ({reason}); render that part again")]
    Damaged { path: PathBuf, reason: String },
    #[error(
        "{path} has no record of the scene and settings it was rendered from (an older photonix wrote it); \
         render it again to merge it"
    )]
    NoProvenance { path: PathBuf },
    #[error(
        "{path} was rendered with {what} {theirs} but {first} with {ours}; only parts of one render can be merged"
    )]
    SettingMismatch { path: PathBuf, what: String, theirs: String, first: PathBuf, ours: String },
    #[error(
        "{path} was rendered from a different scene than {first} (scene hash {theirs} vs {ours}: the scene file, a \
         mesh it loads, or the renderer differs); only parts of one render can be merged"
    )]
    SceneMismatch { path: PathBuf, theirs: String, ours: String, first: PathBuf },
    #[error("{path}: an accumulation file is an EXR; give a name ending in .exr")]
    NotExr { path: PathBuf },
}

/// What the passes of an accumulation file were rendered from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Provenance {
    /// 64-bit FNV-1a hash of the prepared scene: every array the kernels bind and the frame
    /// constants (camera, size, seed, depth), so it covers the scene file, its meshes and
    /// textures, and how this version of photonix packs them.
    pub scene: u64,
    /// The settings that change the image, (name, value) in a fixed order.
    pub settings: Vec<(String, String)>,
}

impl Provenance {
    pub fn new(buffers: &SceneBuffers, spp: u32, photons: Option<&PhotonSettings>) -> Provenance {
        let mut hash = Fnv1a::default();
        hash.add(bytemuck::bytes_of(&buffers.frame));
        hash.add(bytemuck::cast_slice(&buffers.nodes));
        hash.add(bytemuck::cast_slice(&buffers.primitives));
        hash.add(bytemuck::cast_slice(&buffers.materials));
        hash.add(bytemuck::cast_slice(&buffers.lights));
        hash.add(bytemuck::cast_slice(&buffers.textures));
        hash.add(bytemuck::cast_slice(&buffers.texture_data));
        hash.add(bytemuck::cast_slice(&buffers.shape_data));
        // Scenes without media hash as they did before media existed.
        if !buffers.media.is_empty() {
            hash.add(bytemuck::cast_slice(&buffers.media));
        }
        let f = &buffers.frame;
        let mut settings = vec![
            ("spp", spp.to_string()),
            ("size", format!("{}x{}", f.width, f.height)),
            ("seed", f.seed.to_string()),
            ("max_depth", f.max_depth.to_string()),
        ];
        // Photon mapping's files read as they did before there was a choice of integrator.
        if f.integrator != crate::layout::constants::INTEGRATOR_PPM {
            settings.push(("integrator", f.integrator.to_string()));
        }
        // `{:?}` of an f32 is its shortest exact form: equal values, equal text.
        let radius = |r: Option<f32>| r.map_or("auto".to_string(), |r| format!("{r:?}"));
        match photons {
            None => settings.push(("photons", "off".to_string())),
            Some(p) => settings.extend([
                ("photons", format!("{}/{}", p.photons, p.caustic_photons)),
                ("radius", format!("{}/{}", radius(p.radius), radius(p.caustic_radius))),
                ("gather_rays", p.gather_rays.to_string()),
                ("photon_depth", p.max_depth.to_string()),
                ("alpha", format!("{:?}", p.alpha)),
            ]),
        }
        if let Some(r) = photons.and_then(|p| p.volume_radius) {
            settings.push(("volume_radius", format!("{r:?}")));
        }
        Provenance { scene: hash.0, settings: settings.into_iter().map(|(k, v)| (k.to_string(), v)).collect() }
    }

    fn text(&self) -> String {
        let settings: Vec<String> = self.settings.iter().map(|(k, v)| format!("{k}={v}")).collect();
        format!("scene={:016x};{}", self.scene, settings.join(";"))
    }
}

/// 64-bit FNV-1a (Fowler, Noll, Vo): simple, and the same on every machine and Rust version.
struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn add(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        // The length ends each array, so moving bytes from one array to the next changes the hash.
        for b in (bytes.len() as u64).to_le_bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

pub fn format_ranges(ranges: &[(u32, u32)]) -> String {
    ranges.iter().map(|(a, b)| format!("{a}..{b}")).collect::<Vec<_>>().join(",")
}

fn parse_ranges(text: &str) -> Option<Vec<(u32, u32)>> {
    text.split(',')
        .map(|r| {
            let (a, b) = r.split_once("..")?;
            Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
        })
        .collect()
}

/// Writes `acc`, rendered as `provenance` says, as an accumulation file, atomically.
pub fn write_accumulation(path: &Path, acc: &Accumulator, provenance: &Provenance) -> Result<(), AccumulationError> {
    use exr::meta::attribute::{AttributeValue, Text};
    if format_of(path)? != Format::Exr {
        return Err(AccumulationError::NotExr { path: path.to_owned() });
    }
    let combined = acc.sum.combined();
    let mut named: Vec<(&str, &Image)> = vec![("combined", &combined)];
    named.extend(acc.sum.named());
    if let Some(features) = &acc.features {
        named.extend(features.named());
    }
    // Uniform renders write no count layer, so their files stay as they were.
    let samples = (!acc.uniform()).then(|| Image {
        pixels: acc.counts.iter().map(|&n| [n as f32; 3]).collect(),
        ..Image::new(combined.width, combined.height)
    });
    if let Some(samples) = &samples {
        named.push(("samples", samples));
    }
    let mark = format!("passes={};ranges={};{}", acc.passes, format_ranges(&acc.ranges), provenance.text());
    let attributes = vec![(MARK, AttributeValue::Text(Text::from(mark.as_str())))];
    Ok(write_layers_exr_with(path, &named, attributes)?)
}

/// Reads an accumulation file back, with its provenance when it has one.
pub fn read_accumulation(path: &Path) -> Result<(Accumulator, Option<Provenance>), AccumulationError> {
    use exr::meta::attribute::AttributeValue;
    crate::io::image::check_exr_input(path)?;
    let read = exr::prelude::read_all_flat_layers_from_file(path)
        .map_err(|e| ImageError::Read { path: path.to_owned(), reason: e.to_string() })?;
    let attr =
        |name: &str| read.layer_data.first()?.attributes.other.iter().find(|(k, _)| *k == name).map(|(_, v)| v.clone());
    let not_acc = || AccumulationError::NotAccumulation { path: path.to_owned() };
    let Some(AttributeValue::Text(mark)) = attr(MARK) else { return Err(not_acc()) };
    let mark = mark.to_string();
    let fields: Vec<(&str, &str)> = mark.split(';').filter_map(|kv| kv.split_once('=')).collect();
    let field = |key: &str| fields.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
    let parsed = field("passes").and_then(|p| p.parse::<u32>().ok()).zip(field("ranges").and_then(parse_ranges));
    let Some((passes, ranges)) = parsed else { return Err(not_acc()) };
    // The pass count is what the sums are divided by: it must be what the ranges say.
    let damaged = |reason: String| AccumulationError::Damaged { path: path.to_owned(), reason };
    let mut counted = 0u64;
    let mut sorted = ranges.clone();
    sorted.sort_unstable();
    for (i, &(a, b)) in sorted.iter().enumerate() {
        if a >= b || b > crate::limits::MAX_PASSES {
            return Err(damaged(format!("pass range {a}..{b} is empty or beyond {}", crate::limits::MAX_PASSES)));
        }
        if i > 0 && a < sorted[i - 1].1 {
            return Err(damaged(format!("pass ranges {}..{} and {a}..{b} overlap", sorted[i - 1].0, sorted[i - 1].1)));
        }
        counted += (b - a) as u64;
    }
    if counted != passes as u64 || passes == 0 {
        return Err(damaged(format!("it counts {passes} passes but its ranges hold {counted}")));
    }
    let provenance = field("scene").and_then(|h| u64::from_str_radix(h, 16).ok()).map(|scene| Provenance {
        scene,
        settings: fields
            .iter()
            .filter(|(k, _)| !matches!(*k, "passes" | "ranges" | "scene"))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    });
    let size = read.attributes.display_window.size;
    let (w, h) = (size.width() as u32, size.height() as u32);
    let mut acc = Accumulator::new(w, h);
    // One RGB layer of the file into `dst`, its pixels in order.
    let find =
        |name: &str| read.layer_data.iter().find(|l| l.attributes.layer_name.as_ref().is_some_and(|n| n.eq(name)));
    let read_layer = |name: &'static str, dst: &mut Image| -> Result<(), AccumulationError> {
        let missing = || AccumulationError::MissingLayer { path: path.to_owned(), layer: name };
        let layer = find(name).ok_or_else(missing)?;
        for (c, channel_name) in ["R", "G", "B"].iter().enumerate() {
            let channel =
                layer.channel_data.list.iter().find(|ch| ch.name.to_string() == *channel_name).ok_or_else(missing)?;
            for (p, v) in dst.pixels.iter_mut().zip(channel.sample_data.values_as_f32()) {
                p[c] = v;
            }
        }
        Ok(())
    };
    for (name, dst) in acc.sum.named_mut() {
        read_layer(name, dst)?;
    }
    // The feature layers, where the part has all of them.
    if ["albedo", "normal", "depth", "position"].iter().all(|n| find(n).is_some()) {
        let mut features = super::Features::new(w, h);
        for (name, dst) in features.named_mut() {
            read_layer(name, dst)?;
        }
        acc.features = Some(features);
    }
    acc.passes = passes;
    acc.ranges = ranges;
    acc.counts = vec![passes; (w * h) as usize];
    if find("samples").is_some() {
        let mut samples = Image::new(w, h);
        read_layer("samples", &mut samples)?;
        for (count, p) in acc.counts.iter_mut().zip(&samples.pixels) {
            // A count is a whole number of passes, at most the file's.
            if !(p[0] >= 0.0 && p[0] <= passes as f32 && p[0].fract() == 0.0) {
                return Err(damaged(format!(
                    "layer `samples` holds {} where a pass count of 0..={passes} belongs",
                    p[0]
                )));
            }
            *count = p[0] as u32;
        }
    }
    Ok((acc, provenance))
}

/// Sums accumulation files into one, refusing different sizes, overlapping pass ranges, and parts
/// of different renders (scene or settings); returns the sum and the provenance they share.
pub fn merge(paths: &[PathBuf]) -> Result<(Accumulator, Provenance), AccumulationError> {
    let first_path = paths.first().ok_or(AccumulationError::Empty)?;
    let (mut total, first) = read_accumulation(first_path)?;
    let first = first.ok_or_else(|| AccumulationError::NoProvenance { path: first_path.clone() })?;
    for path in &paths[1..] {
        let (next, provenance) = read_accumulation(path)?;
        let provenance = provenance.ok_or_else(|| AccumulationError::NoProvenance { path: path.clone() })?;
        check_same_render((first_path, &total, &first), (path, &next, &provenance))?;
        let overlaps = next.ranges.iter().any(|&(a, b)| total.ranges.iter().any(|&(c, d)| a < d && c < b));
        if overlaps {
            return Err(AccumulationError::Overlap {
                path: path.clone(),
                theirs: format_ranges(&next.ranges),
                ours: format_ranges(&total.ranges),
            });
        }
        for ((_, dst), (_, src)) in total.sum.named_mut().into_iter().zip(next.sum.named()) {
            for (d, s) in dst.pixels.iter_mut().zip(&src.pixels) {
                for c in 0..3 {
                    d[c] += s[c];
                }
            }
        }
        // Feature layers survive only where every part has them.
        total.features = match (total.features.take(), next.features) {
            (Some(mut sum), Some(part)) => {
                for ((_, dst), (_, src)) in sum.named_mut().into_iter().zip(part.named()) {
                    for (d, s) in dst.pixels.iter_mut().zip(&src.pixels) {
                        for c in 0..3 {
                            d[c] += s[c];
                        }
                    }
                }
                Some(sum)
            }
            _ => None,
        };
        for (d, s) in total.counts.iter_mut().zip(&next.counts) {
            *d += s;
        }
        total.passes += next.passes;
        total.ranges.extend(next.ranges);
        total.ranges.sort_unstable();
    }
    Ok((total, first))
}

/// Refuses `theirs` unless it is a part of the same render as `ours`: the same image size, the
/// same settings (compared by name first: a difference there is easier to act on than a scene
/// hash) and the same scene hash. Used by merge and by `render --resume`.
pub fn check_same_render(
    ours: (&Path, &Accumulator, &Provenance),
    theirs: (&Path, &Accumulator, &Provenance),
) -> Result<(), AccumulationError> {
    let (first_path, total, first) = ours;
    let (path, next, provenance) = theirs;
    let (fw, fh) = (total.sum.direct.width, total.sum.direct.height);
    let (w, h) = (next.sum.direct.width, next.sum.direct.height);
    if (w, h) != (fw, fh) {
        return Err(AccumulationError::SizeMismatch {
            path: path.to_owned(),
            w,
            h,
            first: first_path.to_owned(),
            fw,
            fh,
        });
    }
    let value = |p: &Provenance, key: &str| {
        p.settings.iter().find(|(k, _)| k == key).map_or("(none)".to_string(), |(_, v)| v.clone())
    };
    let keys = first.settings.iter().chain(&provenance.settings).map(|(k, _)| k.as_str());
    for key in keys {
        let (ours, theirs) = (value(first, key), value(provenance, key));
        if ours != theirs {
            return Err(AccumulationError::SettingMismatch {
                path: path.to_owned(),
                what: key.replace('_', " "),
                theirs,
                first: first_path.to_owned(),
                ours,
            });
        }
    }
    if provenance.scene != first.scene {
        return Err(AccumulationError::SceneMismatch {
            path: path.to_owned(),
            theirs: format!("{:016x}", provenance.scene),
            ours: format!("{:016x}", first.scene),
            first: first_path.to_owned(),
        });
    }
    Ok(())
}

/// The passes of `first..end` that `ranges` (disjoint, in any order) do not hold, as ranges.
pub fn missing_passes(ranges: &[(u32, u32)], first: u32, end: u32) -> Vec<(u32, u32)> {
    let mut sorted = ranges.to_vec();
    sorted.sort_unstable();
    let mut missing = Vec::new();
    let mut cursor = first;
    for (a, b) in sorted {
        if a > cursor && cursor < end {
            missing.push((cursor, a.min(end)));
        }
        cursor = cursor.max(b);
    }
    if cursor < end {
        missing.push((cursor, end));
    }
    missing
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file_with_mark(dir: &Path, name: &str, mark: &str) -> PathBuf {
        use exr::meta::attribute::{AttributeValue, Text};
        let path = dir.join(name);
        let image = Image::new(2, 2);
        let layers: Vec<(&str, &Image)> =
            ["combined", "direct", "specular", "indirect", "caustics"].iter().map(|n| (*n, &image)).collect();
        write_layers_exr_with(&path, &layers, vec![(MARK, AttributeValue::Text(Text::from(mark)))]).unwrap();
        path
    }

    #[test]
    fn damaged_pass_records_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let good = file_with_mark(dir.path(), "good.exr", "passes=2;ranges=0..2;scene=00000000000000ff;spp=1");
        let (acc, provenance) = read_accumulation(&good).unwrap();
        assert_eq!((acc.passes, provenance.unwrap().scene), (2, 255));
        for (mark, piece) in [
            ("passes=0;ranges=0..1;scene=1", "counts 0 passes"),
            ("passes=4294967295;ranges=0..4294967295;scene=1", "beyond 1000000"),
            ("passes=10;ranges=0..5,0..5;scene=1", "overlap"),
            ("passes=3;ranges=5..2;scene=1", "empty"),
        ] {
            let path = file_with_mark(dir.path(), "bad.exr", mark);
            let e = read_accumulation(&path).unwrap_err().to_string();
            assert!(e.contains("damaged") && e.contains(piece), "{mark}: {e}");
        }
        // Without a provenance a file reads, but merge refuses it.
        let old = file_with_mark(dir.path(), "old.exr", "passes=1;ranges=2..3");
        assert!(read_accumulation(&old).unwrap().1.is_none());
        let e = merge(&[good, old]).unwrap_err().to_string();
        assert!(e.contains("no record of the scene and settings"), "{e}");
    }

    #[test]
    fn missing_passes_are_named_as_ranges() {
        assert_eq!(missing_passes(&[(0, 2), (2, 4)], 0, 4), vec![]);
        assert_eq!(missing_passes(&[(4, 6), (0, 2)], 0, 8), vec![(2, 4), (6, 8)]);
        assert_eq!(missing_passes(&[(1, 2)], 0, 4), vec![(0, 1), (2, 4)]);
        assert_eq!(missing_passes(&[(0, 9)], 0, 4), vec![]);
        assert_eq!(missing_passes(&[], 3, 5), vec![(3, 5)]);
    }
}
