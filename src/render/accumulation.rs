//! Accumulation files: the sum of a set of progressive passes, to be merged with others.
//!
//! Format: an OpenEXR file whose layers `combined`, `direct`, `specular`, `indirect` and
//! `caustics` (channels R, G, B, float32) hold the **sum** over the passes of each pass's mean
//! radiance. Each layer's header carries one text attribute, `photonix_accumulation`, e.g.
//! `passes=64;ranges=0..32,64..96`: the pass count and the pass ranges summed. (One attribute,
//! not several: the EXR writer orders custom attributes by hash, which would make the bytes of
//! two identical renders differ.) The image is the sum divided by the pass count.

use std::path::{Path, PathBuf};

use super::progressive::Accumulator;
use crate::io::image::ImageError;
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

/// Writes `acc` as an accumulation file, atomically.
pub fn write_accumulation(path: &Path, acc: &Accumulator) -> Result<(), ImageError> {
    use exr::meta::attribute::{AttributeValue, Text};
    let combined = acc.sum.combined();
    let mut named: Vec<(&str, &Image)> = vec![("combined", &combined)];
    named.extend(acc.sum.named());
    let mark = format!("passes={};ranges={}", acc.passes, format_ranges(&acc.ranges));
    let attributes = vec![(MARK, AttributeValue::Text(Text::from(mark.as_str())))];
    write_layers_exr_with(path, &named, attributes)
}

/// Reads an accumulation file back.
pub fn read_accumulation(path: &Path) -> Result<Accumulator, AccumulationError> {
    use exr::meta::attribute::AttributeValue;
    let read = exr::prelude::read_all_flat_layers_from_file(path)
        .map_err(|e| ImageError::Read { path: path.to_owned(), reason: e.to_string() })?;
    let attr =
        |name: &str| read.layer_data.first()?.attributes.other.iter().find(|(k, _)| *k == name).map(|(_, v)| v.clone());
    let not_acc = || AccumulationError::NotAccumulation { path: path.to_owned() };
    let Some(AttributeValue::Text(mark)) = attr(MARK) else { return Err(not_acc()) };
    let mark = mark.to_string();
    let parsed = mark.split_once(';').and_then(|(count, ranges)| {
        Some((count.strip_prefix("passes=")?.parse::<u32>().ok()?, parse_ranges(ranges.strip_prefix("ranges=")?)?))
    });
    let Some((passes, ranges)) = parsed else { return Err(not_acc()) };
    let size = read.attributes.display_window.size;
    let (w, h) = (size.width() as u32, size.height() as u32);
    let mut acc = Accumulator::new(w, h);
    for (name, dst) in acc.sum.named_mut() {
        let layer = read
            .layer_data
            .iter()
            .find(|l| l.attributes.layer_name.as_ref().is_some_and(|n| n.eq(name)))
            .ok_or(AccumulationError::MissingLayer { path: path.to_owned(), layer: name })?;
        for (c, channel_name) in ["R", "G", "B"].iter().enumerate() {
            let channel = layer
                .channel_data
                .list
                .iter()
                .find(|ch| ch.name.to_string() == *channel_name)
                .ok_or(AccumulationError::MissingLayer { path: path.to_owned(), layer: name })?;
            for (p, v) in dst.pixels.iter_mut().zip(channel.sample_data.values_as_f32()) {
                p[c] = v;
            }
        }
    }
    acc.passes = passes;
    acc.ranges = ranges;
    Ok(acc)
}

/// Sums accumulation files into one, refusing different sizes and overlapping pass ranges.
pub fn merge(paths: &[PathBuf]) -> Result<Accumulator, AccumulationError> {
    let first_path = paths.first().ok_or(AccumulationError::Empty)?;
    let mut total = read_accumulation(first_path)?;
    for path in &paths[1..] {
        let next = read_accumulation(path)?;
        let (fw, fh) = (total.sum.direct.width, total.sum.direct.height);
        let (w, h) = (next.sum.direct.width, next.sum.direct.height);
        if (w, h) != (fw, fh) {
            return Err(AccumulationError::SizeMismatch {
                path: path.clone(),
                w,
                h,
                first: first_path.clone(),
                fw,
                fh,
            });
        }
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
        total.passes += next.passes;
        total.ranges.extend(next.ranges);
        total.ranges.sort_unstable();
    }
    Ok(total)
}
