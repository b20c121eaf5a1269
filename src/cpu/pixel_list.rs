//! The pixels of one dispatch, as `shaders/pixel_list.glsl` picks them: every pixel of the band,
//! or the band's entries of the pixel list (adaptive sampling's later passes).

use rayon::prelude::*;

use crate::layout::constants::{LAYER_COUNT, NO_PIXEL_LIST};
use crate::layout::DispatchRange;

/// How many pixels `range` renders in an image `width` pixels wide (`dispatch_pixels` in the
/// shader): the invocations its dispatch needs.
pub fn dispatch_pixels(width: u32, range: &DispatchRange) -> u32 {
    if range.pixel_list == NO_PIXEL_LIST {
        range.row_count * width
    } else {
        range.pixel_count
    }
}

/// Calls `shade(px, py, pixel)` for each pixel that `range` renders, with `pixel` its
/// `LAYER_COUNT` sums in `accumulation` (the band's, from its first row), rows in parallel.
/// `list` is the pixel list the dispatch's `pixel_list` entries index.
pub fn for_each_pixel(
    width: u32,
    range: &DispatchRange,
    list: &[u32],
    accumulation: &mut [[f32; 4]],
    shade: impl Fn(u32, u32, &mut [[f32; 4]]) + Sync,
) {
    let row_len = (width * LAYER_COUNT) as usize;
    let rows = accumulation.par_chunks_mut(row_len).take(range.row_count as usize).enumerate();
    if range.pixel_list == NO_PIXEL_LIST {
        rows.for_each(|(row, pixels)| {
            let py = range.row_begin + row as u32;
            for (px, acc) in pixels.chunks_exact_mut(LAYER_COUNT as usize).enumerate() {
                shade(px as u32, py, acc);
            }
        });
        return;
    }
    let entries = &list[range.pixel_list as usize..(range.pixel_list + range.pixel_count) as usize];
    rows.for_each(|(row, pixels)| {
        let py = range.row_begin + row as u32;
        let (begin, end) = (py * width, (py + 1) * width);
        let first = entries.partition_point(|&p| p < begin);
        let last = entries.partition_point(|&p| p < end);
        for &p in &entries[first..last] {
            let px = p - begin;
            let at = (px * LAYER_COUNT) as usize;
            shade(px, py, &mut pixels[at..at + LAYER_COUNT as usize]);
        }
    });
}
