//! Adaptive sampling: after a few uniform passes, each pass renders only the pixels where one
//! more pass lowers the image's error most, judged from the difference of each pixel's two
//! halves of passes (`Accumulator::pass_variances`), smoothed over its neighbours. The choice
//! depends on nothing but the sums so far, so a rerun makes the same choices; both backends
//! render a given list the same, sample for sample (`cpu::pixel_list`, `shaders/pixel_list.glsl`).
//! See docs/progressive.md, "Adaptive sampling".

use super::progressive::Accumulator;
use crate::layout::DispatchRange;

/// Passes every pixel gets before any is left out.
pub const WARMUP_PASSES: u32 = 8;
/// Every this many passes (by pass index) one renders every pixel, so no pixel's error stops
/// falling, whatever its first passes showed (a caustic its first samples missed).
pub const UNIFORM_EVERY: u32 = 8;
/// The share of pixels an adaptive pass renders: those with the largest gain.
pub const ACTIVE_FRACTION: f64 = 0.5;
/// An adaptive pass is rendered only where its pixels' mean gain is at least this many times
/// the mean over all pixels: a pixel of an adaptive pass costs more than one of a uniform pass
/// (about 1.16x on the CPU backend: the pass's fixed work, the choice, scattered pixels), and
/// the estimates' own noise makes the chosen half look better than it is (1.2-1.4x on the
/// plain box, whose noise is even). At 1.25 the box came out 8% worse than uniform at equal
/// time; at 1.5 it renders as uniform does (BENCHMARKS.md, "Adaptive sampling").
pub const MIN_ADVANTAGE: f64 = 1.5;
/// The half-width of the square over which a pixel's variance estimate is averaged.
pub const SMOOTH_RADIUS: usize = 2;

/// The pixels one pass renders: absolute indices (y * width + x), ascending.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PixelList {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u32>,
}

impl PixelList {
    /// `unit` narrowed to the list's pixels in its band.
    pub fn restrict(&self, unit: DispatchRange) -> DispatchRange {
        let begin = unit.row_begin * self.width;
        let end = (unit.row_begin + unit.row_count) * self.width;
        let first = self.pixels.partition_point(|&p| p < begin);
        let last = self.pixels.partition_point(|&p| p < end);
        DispatchRange { pixel_list: first as u32, pixel_count: (last - first) as u32, ..unit }
    }
}

/// `unit`, narrowed to `list`'s pixels where there is one.
pub fn restrict(unit: DispatchRange, list: Option<&PixelList>) -> DispatchRange {
    list.map_or(unit, |l| l.restrict(unit))
}

/// The pixels pass `pass` renders after the passes in `acc`, or `None` for every pixel: during
/// the warm-up, on every `UNIFORM_EVERY`th pass, and where the halves give no estimate (a
/// resumed render). Else the `ACTIVE_FRACTION` of pixels with the largest gain from one more
/// pass, v / (n (n + 1)) for a pixel of n passes and smoothed pass variance v: giving each pass
/// to the largest gains tends to n proportional to sqrt(v), the allocation of least relMSE for
/// a given number of samples. With a `target` relMSE, pixels whose own error v / n is below it
/// are left out too.
pub fn select(acc: &Accumulator, pass: u32, target: Option<f64>) -> Option<PixelList> {
    if pass % UNIFORM_EVERY == UNIFORM_EVERY - 1 || acc.counts.iter().any(|&n| n < WARMUP_PASSES) {
        return None;
    }
    let (width, height) = (acc.sum.direct.width, acc.sum.direct.height);
    let variance = neighbour_mean(&acc.pass_variances()?, width as usize, height as usize, SMOOTH_RADIUS);
    let gain: Vec<f32> = variance.iter().zip(&acc.counts).map(|(&v, &n)| v / (n as f32 * (n + 1) as f32)).collect();
    let mut sorted = gain.clone();
    let k = ((gain.len() as f64 * ACTIVE_FRACTION) as usize).clamp(1, gain.len());
    let (_, &mut threshold, _) = sorted.select_nth_unstable_by(gain.len() - k, f32::total_cmp);
    let converged = |p: usize| target.is_some_and(|t| ((variance[p] / acc.counts[p] as f32) as f64) < t);
    let pixels: Vec<u32> =
        (0..gain.len()).filter(|&p| gain[p] > 0.0 && gain[p] >= threshold && !converged(p)).map(|p| p as u32).collect();
    // None left (all converged or all flat), or too little to gain: a uniform pass.
    let all: f64 = gain.iter().map(|&g| g as f64).sum::<f64>() / gain.len() as f64;
    let chosen: f64 = pixels.iter().map(|&p| gain[p as usize] as f64).sum::<f64>() / pixels.len().max(1) as f64;
    if pixels.is_empty() || chosen < MIN_ADVANTAGE * all {
        return None;
    }
    Some(PixelList { width, height, pixels })
}

/// The mean over the (2r + 1)^2 square around each pixel, clipped at the image's edges, less the
/// pixel itself: a pixel's passes are then chosen from its neighbours' samples, which are
/// independent of its own, and its mean is not biased by choices its own samples made (more
/// passes after a bright sample dilute it: about -0.7% in the caustic box where the pixel took
/// part in its own choice).
fn neighbour_mean(values: &[f32], width: usize, height: usize, r: usize) -> Vec<f32> {
    let mean = box_smooth(values, width, height, r);
    let span = |i: usize, len: usize| (i + r).min(len - 1) + 1 - i.saturating_sub(r);
    (0..values.len())
        .map(|p| {
            let n = (span(p % width, width) * span(p / width, height)) as f32;
            if n <= 1.0 {
                return values[p];
            }
            ((mean[p] * n - values[p]) / (n - 1.0)).max(0.0)
        })
        .collect()
}

/// The mean over the (2r + 1)^2 square around each pixel, clipped at the image's edges.
fn box_smooth(values: &[f32], width: usize, height: usize, r: usize) -> Vec<f32> {
    let pass = |src: &[f32], along_x: bool| -> Vec<f32> {
        let mut out = vec![0.0; src.len()];
        let (len, lines) = if along_x { (width, height) } else { (height, width) };
        let at = |line: usize, i: usize| if along_x { line * width + i } else { i * width + line };
        for line in 0..lines {
            // A running sum over the window, in f64 so that it does not drift.
            let mut sum = 0.0f64;
            let mut count = 0usize;
            for i in 0..r.min(len) {
                sum += src[at(line, i)] as f64;
                count += 1;
            }
            for i in 0..len {
                if i + r < len {
                    sum += src[at(line, i + r)] as f64;
                    count += 1;
                }
                if i > r {
                    sum -= src[at(line, i - r - 1)] as f64;
                    count -= 1;
                }
                out[at(line, i)] = (sum / count as f64) as f32;
            }
        }
        out
    };
    pass(&pass(values, true), false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_smooth_averages_the_clipped_square() {
        let (w, h) = (5, 4);
        let values: Vec<f32> = (0..w * h).map(|i| (i * i % 7) as f32).collect();
        let smooth = box_smooth(&values, w, h, 1);
        for y in 0..h {
            for x in 0..w {
                let mut sum = 0.0;
                let mut n = 0.0;
                for yy in y.saturating_sub(1)..(y + 2).min(h) {
                    for xx in x.saturating_sub(1)..(x + 2).min(w) {
                        sum += values[yy * w + xx];
                        n += 1.0;
                    }
                }
                assert!((smooth[y * w + x] - sum / n).abs() < 1e-5, "({x}, {y})");
            }
        }
    }

    #[test]
    fn restrict_takes_the_band_s_entries() {
        let list = PixelList { width: 4, height: 3, pixels: vec![1, 2, 5, 9, 11] };
        let unit =
            DispatchRange { row_begin: 1, row_count: 2, sample_index: 0, part: 0, pixel_list: 0, pixel_count: 0 };
        let r = list.restrict(unit);
        assert_eq!((r.pixel_list, r.pixel_count), (2, 3));
        let r = list.restrict(DispatchRange { row_begin: 0, row_count: 1, ..unit });
        assert_eq!((r.pixel_list, r.pixel_count), (0, 2));
    }
}
