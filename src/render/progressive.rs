//! Progressive photon mapping in the probabilistic formulation of Knaus and Zwicker (2011): pass
//! p is an ordinary photon-mapping render with its own photons, its own camera samples and the
//! lookup radius r_1 (p + 1)^((alpha - 1) / 2); the image is the mean of the pass images. Passes
//! are independent, so any subset can be rendered anywhere and summed; memory does not grow
//! with the number of passes. See docs/progressive.md.

use std::time::{Duration, Instant};

use super::{stop_requested, Layers, RenderOutput};
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
    /// Sums of the combined image over even and odd passes, for the error estimate.
    even: Image,
    odd: Image,
    /// Passes summed, and the ranges they came from.
    pub passes: u32,
    pub ranges: Vec<(u32, u32)>,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Accumulator {
        Accumulator {
            sum: Layers::new(width, height),
            even: Image::new(width, height),
            odd: Image::new(width, height),
            passes: 0,
            ranges: Vec::new(),
        }
    }

    pub fn add(&mut self, pass: u32, out: &RenderOutput) {
        for ((_, dst), (_, src)) in self.sum.named_mut().into_iter().zip(out.layers.named()) {
            add_into(dst, src);
        }
        add_into(if pass.is_multiple_of(2) { &mut self.even } else { &mut self.odd }, &out.image);
        self.passes += 1;
        match self.ranges.last_mut() {
            Some(r) if r.1 == pass => r.1 = pass + 1,
            _ => self.ranges.push((pass, pass + 1)),
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

    /// An estimate of the mean image's relMSE against the converged image: the relMSE between
    /// the means of the even and of the odd passes, divided by 4 (two independent halves differ
    /// by twice the variance of one half, which is twice that of the whole). Needs four passes.
    pub fn error_estimate(&self) -> Option<f64> {
        if self.passes < 4 {
            return None;
        }
        let (n_even, n_odd) = (self.passes.div_ceil(2), self.passes / 2);
        let scale = |image: &Image, n: u32| Image {
            pixels: image.pixels.iter().map(|p| p.map(|c| c / n as f32)).collect(),
            ..image.clone()
        };
        Some(rel_mse(&scale(&self.even, n_even), &scale(&self.odd, n_odd)) / 4.0)
    }
}

fn add_into(dst: &mut Image, src: &Image) {
    for (d, s) in dst.pixels.iter_mut().zip(&src.pixels) {
        for c in 0..3 {
            d[c] += s[c];
        }
    }
}

/// Renders passes with `render_pass(pass)` until the budget is spent or a stop is requested,
/// calling `after_pass(accumulator, elapsed)` after each finished pass (for progress and
/// checkpoints). An interrupted pass is dropped; passes already summed are kept.
pub fn render_progressive<E>(
    width: u32,
    height: u32,
    budget: &Budget,
    mut render_pass: impl FnMut(u32) -> Result<RenderOutput, E>,
    mut after_pass: impl FnMut(&Accumulator, Duration) -> Result<(), E>,
) -> Result<(Accumulator, StopReason), E> {
    let start = Instant::now();
    let mut acc = Accumulator::new(width, height);
    for pass in budget.first..budget.end {
        if stop_requested() {
            return Ok((acc, StopReason::Interrupted));
        }
        let out = render_pass(pass)?;
        if !out.complete {
            return Ok((acc, StopReason::Interrupted));
        }
        acc.add(pass, &out);
        after_pass(&acc, start.elapsed())?;
        if budget.time.is_some_and(|t| start.elapsed() >= t) {
            return Ok((acc, StopReason::Time));
        }
        if let (Some(target), Some(estimate)) = (budget.target_error, acc.error_estimate()) {
            if estimate < target {
                return Ok((acc, StopReason::TargetError));
            }
        }
    }
    Ok((acc, StopReason::Passes))
}
