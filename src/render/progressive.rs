//! Progressive photon mapping in the probabilistic formulation of Knaus and Zwicker (2011): pass
//! p is an ordinary photon-mapping render with its own photons, its own camera samples and the
//! lookup radius r_1 (p + 1)^((alpha - 1) / 2); the image is the mean of the pass images. Passes
//! are independent, so any subset can be rendered anywhere and summed; memory does not grow
//! with the number of passes. See docs/progressive.md.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::adaptive::{self, PixelList};
use super::{stop_requested, Features, Layers, RenderOutput};
use crate::io::Image;

/// When a progressive render stops (the first limit reached wins).
#[derive(Clone, Debug, Default)]
pub struct Budget {
    /// Render passes `first..end`.
    pub first: u32,
    pub end: u32,
    /// Stop after the pass that crosses this much wall time.
    pub time: Option<Duration>,
    /// Stop when the error estimate falls below this relMSE.
    pub target_error: Option<f64>,
    /// Adaptive sampling: after a warm-up, passes render the pixels where the error falls most
    /// (`render::adaptive`).
    pub adaptive: bool,
}

/// Why a progressive render stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    Passes,
    Time,
    TargetError,
    Interrupted,
}

/// The running sums of a progressive render: constant memory whatever the pass count.
#[derive(Clone, Debug)]
pub struct Accumulator {
    /// Sum over passes of each pass's mean image, per layer.
    pub sum: Layers,
    /// Sum over passes of each pass's mean feature layers, where the outputs carried them. The
    /// feature kernel renders every pixel in every pass, so these divide by `passes`.
    pub features: Option<Features>,
    /// Passes summed into each pixel: `passes` everywhere but where adaptive sampling left a
    /// pixel out of some (`RenderOutput::pixels`).
    pub counts: Vec<u32>,
    /// Per pixel, sums of the combined image over two halves of its passes (each pass goes to
    /// the half with fewer), for the error estimates, and the passes in each.
    even: Image,
    odd: Image,
    even_counts: Vec<u32>,
    odd_counts: Vec<u32>,
    /// Passes summed, and the ranges they came from.
    pub passes: u32,
    pub ranges: Vec<(u32, u32)>,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Accumulator {
        let pixels = (width * height) as usize;
        Accumulator {
            sum: Layers::new(width, height),
            features: None,
            counts: vec![0; pixels],
            even: Image::new(width, height),
            odd: Image::new(width, height),
            even_counts: vec![0; pixels],
            odd_counts: vec![0; pixels],
            passes: 0,
            ranges: Vec::new(),
        }
    }

    /// Adds `out`, the mean of `out.passes` passes from `pass` on, weighted by its passes, to the
    /// pixels it rendered.
    pub fn add(&mut self, pass: u32, out: &RenderOutput) {
        let n = out.passes.max(1);
        let listed = out.pixels.as_ref().map(|l| l.pixels.as_slice());
        for ((_, dst), (_, src)) in self.sum.named_mut().into_iter().zip(out.layers.named()) {
            add_into(dst, src, n, listed);
        }
        if let Some(features) = &out.features {
            let (w, h) = (features.albedo.width, features.albedo.height);
            let sum = self.features.get_or_insert_with(|| Features::new(w, h));
            for ((_, dst), (_, src)) in sum.named_mut().into_iter().zip(features.named()) {
                add_into(dst, src, n, None);
            }
        }
        match listed {
            Some(list) => list.iter().for_each(|&p| self.add_to_half(p as usize, &out.image, n)),
            None => (0..self.counts.len()).for_each(|p| self.add_to_half(p, &out.image, n)),
        }
        self.passes += n;
        match self.ranges.last_mut() {
            Some(r) if r.1 == pass => r.1 = pass + n,
            _ => self.ranges.push((pass, pass + n)),
        }
    }

    /// Adds pixel `p` of `image`, `n` passes, to the half of the pixel's passes with fewer, so
    /// each pixel's halves stay even when outputs hold different pass counts (one pass each:
    /// even and odd passes from an even first).
    fn add_to_half(&mut self, p: usize, image: &Image, n: u32) {
        let (half, count) = if self.even_counts[p] <= self.odd_counts[p] {
            (&mut self.even, &mut self.even_counts[p])
        } else {
            (&mut self.odd, &mut self.odd_counts[p])
        };
        add_pixel(&mut half.pixels[p], &image.pixels[p], n);
        *count += n;
        self.counts[p] += n;
    }

    /// Whether every pixel holds every pass (no adaptive sampling left one out).
    pub fn uniform(&self) -> bool {
        self.counts.iter().all(|&c| c == self.passes)
    }

    /// The mean over each pixel's passes, per layer.
    pub fn mean(&self) -> Layers {
        let mut mean = self.sum.clone();
        for (_, layer) in mean.named_mut() {
            for (p, &n) in layer.pixels.iter_mut().zip(&self.counts) {
                let inv = 1.0 / n.max(1) as f32;
                *p = p.map(|c| c * inv);
            }
        }
        mean
    }

    /// The mean feature layers over the passes so far, where every output carried them.
    pub fn mean_features(&self) -> Option<Features> {
        let mut mean = self.features.clone()?;
        let inv = 1.0 / self.passes.max(1) as f32;
        for (_, layer) in mean.named_mut() {
            for p in &mut layer.pixels {
                *p = p.map(|c| c * inv);
            }
        }
        Some(mean)
    }

    /// Per pixel, the means of its two halves and their pass counts; `None` unless every pixel
    /// has both halves and they hold all its passes (a resumed accumulator's halves miss the
    /// passes read from its file).
    fn halves(&self) -> Option<impl Iterator<Item = ([f32; 3], [f32; 3], u32, u32)> + '_> {
        let complete = (0..self.counts.len()).all(|p| {
            let (a, b) = (self.even_counts[p], self.odd_counts[p]);
            a > 0 && b > 0 && a + b == self.counts[p]
        });
        if !complete || self.counts.is_empty() {
            return None;
        }
        let mean = |sum: &[f32; 3], n: u32| sum.map(|c| c / n as f32);
        Some((0..self.counts.len()).map(move |p| {
            let (a, b) = (self.even_counts[p], self.odd_counts[p]);
            (mean(&self.even.pixels[p], a), mean(&self.odd.pixels[p], b), a, b)
        }))
    }

    /// An estimate of the mean image's relMSE against the converged image, from the relMSE
    /// between the means of each pixel's two halves: their difference has the variance of one
    /// pass times (1/n_a + 1/n_b), the whole mean that times 1/(n_a + n_b), so a pixel's term is
    /// scaled by n_a n_b / (n_a + n_b)^2 (a quarter for equal halves). Needs four passes.
    pub fn error_estimate(&self) -> Option<f64> {
        if self.passes < 4 {
            return None;
        }
        let mut sum = 0.0f64;
        for (a, b, na, nb) in self.halves()? {
            let (na, nb) = (na as f64, nb as f64);
            let scale = na * nb / ((na + nb) * (na + nb));
            for c in 0..3 {
                let (t, r) = (a[c] as f64, b[c] as f64);
                sum += (t - r).powi(2) / (r * r + 0.01) * scale;
            }
        }
        Some(sum / (3 * self.counts.len()) as f64)
    }

    /// Per pixel, an estimate of one pass's relative variance (its squared error over the
    /// pixel's value squared plus 0.01, relMSE's weighting, averaged over channels) from the
    /// difference of its halves; `None` where `error_estimate` is. One pixel's estimate has
    /// one degree of freedom: adaptive sampling smooths it over neighbours.
    pub fn pass_variances(&self) -> Option<Vec<f32>> {
        Some(
            self.halves()?
                .map(|(a, b, na, nb)| {
                    let inv = 1.0 / na as f32 + 1.0 / nb as f32;
                    let n = (na + nb) as f32;
                    (0..3)
                        .map(|c| {
                            let m = (a[c] * na as f32 + b[c] * nb as f32) / n;
                            (a[c] - b[c]).powi(2) / inv / (m * m + 0.01)
                        })
                        .sum::<f32>()
                        / 3.0
                })
                .collect(),
        )
    }
}

/// `d += n * s` (exactly `d += s` for one pass: a product by 1 is exact).
fn add_pixel(d: &mut [f32; 3], s: &[f32; 3], n: u32) {
    for c in 0..3 {
        d[c] += s[c] * n as f32;
    }
}

/// `dst += n * src` at the listed pixels, or at every pixel.
fn add_into(dst: &mut Image, src: &Image, n: u32, pixels: Option<&[u32]>) {
    match pixels {
        Some(list) => list.iter().for_each(|&p| add_pixel(&mut dst.pixels[p as usize], &src.pixels[p as usize], n)),
        None => dst.pixels.iter_mut().zip(&src.pixels).for_each(|(d, s)| add_pixel(d, s, n)),
    }
}

/// Renders passes with `render_passes(first, most, pixels)` (up to `most` consecutive passes from
/// `first` of the pixels of `pixels`, all with `None`, returning their mean and how many it
/// rendered) until the budget is spent or a stop
/// is requested, calling `after_pass(accumulator, elapsed)` after each output (for progress and
/// checkpoints). An interrupted output is dropped; outputs already summed are kept.
///
/// `most` starts at 1 and doubles after each output up to `max_group` (1 where grouping gains
/// nothing: the CPU backend, lavapipe). The sequence depends on nothing but the budget, so a
/// rerun of the same passes groups them the same way and writes the same bytes; with a time
/// budget it is also capped by the passes the time left allows at the rate measured.
pub fn render_progressive<E>(
    width: u32,
    height: u32,
    budget: &Budget,
    max_group: u32,
    render_passes: impl FnMut(u32, u32, Option<&Arc<PixelList>>) -> Result<RenderOutput, E>,
    after_pass: impl FnMut(&Accumulator, Duration) -> Result<(), E>,
) -> Result<(Accumulator, StopReason), E> {
    render_progressive_from(Accumulator::new(width, height), budget, max_group, render_passes, after_pass)
}

/// `render_progressive` that adds the passes to `acc`, which may hold passes already: a resumed
/// render (`render --resume`) starts from the passes its interrupted run wrote, `budget.first`
/// being the first pass not yet rendered. The sums are float32 in memory and in the file, so the
/// passes are added in the order an uninterrupted render adds them and, where each pass is its
/// own group (the CPU backend, lavapipe), the sums are the same bits. The error estimate's
/// halves are not in the file: a resumed accumulator has none (`error_estimate` is `None`).
pub fn render_progressive_from<E>(
    mut acc: Accumulator,
    budget: &Budget,
    max_group: u32,
    mut render_passes: impl FnMut(u32, u32, Option<&Arc<PixelList>>) -> Result<RenderOutput, E>,
    mut after_pass: impl FnMut(&Accumulator, Duration) -> Result<(), E>,
) -> Result<(Accumulator, StopReason), E> {
    let start = Instant::now();
    let mut pass = budget.first;
    let mut most = 1;
    let mut pixels = None;
    while pass < budget.end {
        if stop_requested() {
            return Ok((acc, StopReason::Interrupted));
        }
        let t = Instant::now();
        let out = render_passes(pass, most.min(budget.end - pass), pixels.as_ref())?;
        if !out.complete {
            return Ok((acc, StopReason::Interrupted));
        }
        let rendered = out.passes.max(1);
        let per_pass = t.elapsed().as_secs_f64() / rendered as f64;
        acc.add(pass, &out);
        pass += rendered;
        after_pass(&acc, start.elapsed())?;
        if budget.time.is_some_and(|t| start.elapsed() >= t) {
            return Ok((acc, StopReason::Time));
        }
        if let (Some(target), Some(estimate)) = (budget.target_error, acc.error_estimate()) {
            if estimate < target {
                return Ok((acc, StopReason::TargetError));
            }
        }
        most = (most * 2).min(max_group.max(1));
        if let Some(t) = budget.time {
            let left = t.saturating_sub(start.elapsed()).as_secs_f64();
            most = most.min(((left / per_pass.max(1e-9)) as u32).max(1));
        }
        if budget.adaptive {
            pixels = adaptive::select(&acc, pass, budget.target_error).map(Arc::new);
            // A group of passes shares one list: it ends before the next uniform pass.
            if pixels.is_some() {
                let left = adaptive::UNIFORM_EVERY - 1 - pass % adaptive::UNIFORM_EVERY;
                most = most.min(left.max(1));
            }
        }
    }
    Ok((acc, StopReason::Passes))
}
