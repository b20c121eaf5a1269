//! Progressive photon mapping in the probabilistic formulation of Knaus and Zwicker (2011): pass
//! p is an ordinary photon-mapping render with its own photons, its own camera samples and the
//! lookup radius r_1 (p + 1)^((alpha - 1) / 2); the image is the mean of the pass images. Passes
//! are independent, so any subset can be rendered anywhere and summed; memory does not grow
//! with the number of passes. See docs/progressive.md.

use std::time::{Duration, Instant};

use super::{stop_requested, Features, Layers, RenderOutput};
use crate::io::metrics::rel_mse;
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
    /// Sum over passes of each pass's mean feature layers, where the outputs carried them.
    pub features: Option<Features>,
    /// Sums of the combined image over two halves of the passes (alternate outputs), for the
    /// error estimate, and the passes in each.
    even: Image,
    odd: Image,
    even_passes: u32,
    odd_passes: u32,
    /// Passes summed, and the ranges they came from.
    pub passes: u32,
    pub ranges: Vec<(u32, u32)>,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Accumulator {
        Accumulator {
            sum: Layers::new(width, height),
            features: None,
            even: Image::new(width, height),
            odd: Image::new(width, height),
            even_passes: 0,
            odd_passes: 0,
            passes: 0,
            ranges: Vec::new(),
        }
    }

    /// Adds `out`, the mean of `out.passes` passes from `pass` on, weighted by its passes.
    pub fn add(&mut self, pass: u32, out: &RenderOutput) {
        let n = out.passes.max(1);
        for ((_, dst), (_, src)) in self.sum.named_mut().into_iter().zip(out.layers.named()) {
            add_into(dst, src, n);
        }
        if let Some(features) = &out.features {
            let (w, h) = (features.albedo.width, features.albedo.height);
            let sum = self.features.get_or_insert_with(|| Features::new(w, h));
            for ((_, dst), (_, src)) in sum.named_mut().into_iter().zip(features.named()) {
                add_into(dst, src, n);
            }
        }
        // The half with fewer passes takes it, so the halves stay even when outputs hold
        // different pass counts (one pass each: even and odd passes from an even first pass).
        if self.even_passes <= self.odd_passes {
            add_into(&mut self.even, &out.image, n);
            self.even_passes += n;
        } else {
            add_into(&mut self.odd, &out.image, n);
            self.odd_passes += n;
        }
        self.passes += n;
        match self.ranges.last_mut() {
            Some(r) if r.1 == pass => r.1 = pass + n,
            _ => self.ranges.push((pass, pass + n)),
        }
    }

    /// The mean over the passes so far, per layer.
    pub fn mean(&self) -> Layers {
        let mut mean = self.sum.clone();
        let inv = 1.0 / self.passes.max(1) as f32;
        for (_, layer) in mean.named_mut() {
            for p in &mut layer.pixels {
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

    /// An estimate of the mean image's relMSE against the converged image, from the relMSE
    /// between the means of the two halves: their difference has the variance of one pass
    /// times (1/n_a + 1/n_b), the whole mean that times 1/(n_a + n_b), so the estimate is
    /// relMSE x n_a n_b / (n_a + n_b)^2 (a quarter for equal halves). Needs four passes.
    pub fn error_estimate(&self) -> Option<f64> {
        let (n_even, n_odd) = (self.even_passes, self.odd_passes);
        // A resumed accumulator's halves miss the passes read from its file.
        if self.passes < 4 || n_even == 0 || n_odd == 0 || n_even + n_odd != self.passes {
            return None;
        }
        let scale = |image: &Image, n: u32| Image {
            pixels: image.pixels.iter().map(|p| p.map(|c| c / n as f32)).collect(),
            ..image.clone()
        };
        let (a, b) = (n_even as f64, n_odd as f64);
        Some(rel_mse(&scale(&self.even, n_even), &scale(&self.odd, n_odd)) * a * b / ((a + b) * (a + b)))
    }
}

/// `dst += n * src` (exactly `dst += src` for one pass).
fn add_into(dst: &mut Image, src: &Image, n: u32) {
    if n == 1 {
        for (d, s) in dst.pixels.iter_mut().zip(&src.pixels) {
            for c in 0..3 {
                d[c] += s[c];
            }
        }
        return;
    }
    let n = n as f32;
    for (d, s) in dst.pixels.iter_mut().zip(&src.pixels) {
        for c in 0..3 {
            d[c] += s[c] * n;
        }
    }
}

/// Renders passes with `render_passes(first, most)` (up to `most` consecutive passes from
/// `first`, returning their mean and how many it rendered) until the budget is spent or a stop
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
    render_passes: impl FnMut(u32, u32) -> Result<RenderOutput, E>,
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
    mut render_passes: impl FnMut(u32, u32) -> Result<RenderOutput, E>,
    mut after_pass: impl FnMut(&Accumulator, Duration) -> Result<(), E>,
) -> Result<(Accumulator, StopReason), E> {
    let start = Instant::now();
    let mut pass = budget.first;
    let mut most = 1;
    while pass < budget.end {
        if stop_requested() {
            return Ok((acc, StopReason::Interrupted));
        }
        let t = Instant::now();
        let out = render_passes(pass, most.min(budget.end - pass))?;
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
    }
    Ok((acc, StopReason::Passes))
}
