//! Image texture lookups in the shared texture buffer; twin of `shaders/image_texture.glsl`,
//! function for function. The host side (loading, packing) is `crate::scene::image_texture`.
//!
//! Every texture lives in one `u32` array (GLSL `uint texture_data[]`). An image is a block at
//! word offset `at`:
//!
//! | words | content |
//! | --- | --- |
//! | `at + 0` | width W in texels, 1 ..= 16384 |
//! | `at + 1` | height H in texels, 1 ..= 16384 |
//! | `at + 2` | wrap mode, `IMAGE_WRAP_*` |
//! | `at + 3` | flags, `IMAGE_FLAG_*` |
//! | `at + 4 + 2 (j W + i)` | texel (column i, row j): half R (bits 0-15), half G (16-31) |
//! | `at + 5 + 2 (j W + i)` | half B (bits 0-15), half A (16-31) |
//!
//! Row j = 0 is the file's top row. Texels are linear (sRGB files are decoded on the host) and
//! stored as IEEE half floats, subnormals included, never Inf or NaN; a block is
//! `IMAGE_HEADER_WORDS + 2 W H` words.
//!
//! Texture coordinates follow OBJ / OpenGL: v = 0 is the image's bottom row, v = 1 its top row.
//! Texel (i, j) has its centre at u = (i + 0.5)/W, v = 1 - (j + 0.5)/H.

use glam::{Vec2, Vec3, Vec4};

// Block layout, wrap modes and limits: shared with the kernel through src/layout/constants.rs.
pub use crate::layout::constants::{
    IMAGE_COORD_LIMIT, IMAGE_FLAG_ALPHA, IMAGE_HEADER_WORDS, IMAGE_WRAP_CLAMP, IMAGE_WRAP_MIRROR, IMAGE_WRAP_REPEAT,
    TEXTURE_PROJECTION_CYLINDRICAL, TEXTURE_PROJECTION_SPHERICAL,
};

/// Half-float bits to f32, exactly, subnormals included (the host writes no Inf or NaN).
pub fn image_half_to_f32(h: u32) -> f32 {
    let e = (h >> 10) & 0x1f;
    let m = h & 0x3ff;
    if e == 0 {
        let v = m as f32 * f32::from_bits(0x3380_0000); // m * 2^-24, exact
        return if h & 0x8000 != 0 { -v } else { v };
    }
    f32::from_bits(((h & 0x8000) << 16) | ((e + 112) << 23) | (m << 13))
}

/// Texel (i, j) of the block at `at` of width `w` (passed in to save a load); `i` < `w`, `j` <
/// height.
pub fn image_fetch(data: &[u32], at: u32, w: u32, i: u32, j: u32) -> Vec4 {
    let k = (at + IMAGE_HEADER_WORDS + 2 * (j * w + i)) as usize;
    let rg = data[k];
    let ba = data[k + 1];
    Vec4::new(
        image_half_to_f32(rg & 0xffff),
        image_half_to_f32(rg >> 16),
        image_half_to_f32(ba & 0xffff),
        image_half_to_f32(ba >> 16),
    )
}

/// `i` modulo `n`, in `[0, n)` for negative `i` too.
pub fn image_repeat(i: i32, n: u32) -> u32 {
    if i >= 0 {
        i as u32 % n
    } else {
        n - 1 - (-(i + 1)) as u32 % n
    }
}

/// An integer texel index mapped into `[0, n)` by the wrap mode; unknown modes repeat.
pub fn image_wrap(i: i32, n: u32, wrap: u32) -> u32 {
    if wrap == IMAGE_WRAP_CLAMP {
        return i.clamp(0, n as i32 - 1) as u32;
    }
    if wrap == IMAGE_WRAP_MIRROR {
        let m = image_repeat(i, 2 * n);
        return if m < n { m } else { 2 * n - 1 - m };
    }
    image_repeat(i, n)
}

/// A texel coordinate clamped to +-`IMAGE_COORD_LIMIT`, NaN mapped to 0, so that no `uv` (1e30,
/// Inf, NaN) can make an index outside the block.
pub fn image_coord(x: f32) -> f32 {
    if (-IMAGE_COORD_LIMIT..=IMAGE_COORD_LIMIT).contains(&x) {
        x
    } else if x > IMAGE_COORD_LIMIT {
        IMAGE_COORD_LIMIT
    } else if x < -IMAGE_COORD_LIMIT {
        -IMAGE_COORD_LIMIT
    } else {
        0.0
    }
}

/// The uv of texture-space point `p` under projection `projection` (`TEXTURE_PROJECTION_*`,
/// POV-Ray's image_map `map_type` 0, 1, 2; unknown ones are planar). Planar: (p.x, p.y).
/// Spherical: u = atan2(p.z, p.x) / 2 pi, in [0, 1) (0 on +x, 1/4 on +z), v = 1/2 +
/// asin(p.y / |p|) / pi (0 at the south pole, 1 at the north). Cylindrical: u as spherical,
/// v = p.y. On the y axis u is 0; at the origin the spherical v is 1/2.
pub fn image_projection(p: Vec3, projection: u32) -> Vec2 {
    if projection != TEXTURE_PROJECTION_SPHERICAL && projection != TEXTURE_PROJECTION_CYLINDRICAL {
        return p.truncate();
    }
    let mut u = 0.0;
    if p.x * p.x + p.z * p.z > 0.0 {
        u = p.z.atan2(p.x) / std::f32::consts::TAU;
        if u < 0.0 {
            u += 1.0;
        }
    }
    if projection == TEXTURE_PROJECTION_CYLINDRICAL {
        return Vec2::new(u, p.y);
    }
    let len = p.length();
    let mut v = 0.5;
    if len > 0.0 {
        v = 0.5 + (p.y / len).clamp(-1.0, 1.0).asin() / std::f32::consts::PI;
    }
    Vec2::new(u, v)
}

/// The texel whose square holds `uv` (column floor(W u), row floor(H (1 - v)), wrapped), no
/// filtering.
pub fn image_texel(data: &[u32], at: u32, uv: Vec2) -> Vec4 {
    let w = data[at as usize];
    let h = data[at as usize + 1];
    let wrap = data[at as usize + 2];
    let x = image_coord(w as f32 * uv.x);
    let y = image_coord(h as f32 * (1.0 - uv.y));
    image_fetch(data, at, w, image_wrap(x.floor() as i32, w, wrap), image_wrap(y.floor() as i32, h, wrap))
}

/// Bilinear lookup of the image block at `at`: with x = W u - 0.5 and y = H (1 - v) - 0.5 (texel
/// coordinates, y counted down from the top row), i0 = floor(x), j0 = floor(y), fx = x - i0,
/// fy = y - j0, the value is
/// (1-fx)(1-fy) T[j0][i0] + fx(1-fy) T[j0][i0+1] + (1-fx)fy T[j0+1][i0] + fx fy T[j0+1][i0+1],
/// each index wrapped by the block's wrap mode. So a texel centre returns the texel, and with
/// repeat u = 0 is the 50/50 mix of columns 0 and W-1 (the cornell-glossy reference's seam
/// rule). Linear, so filtering happens after sRGB decoding. Any `uv`, NaN included, reads inside
/// the block. Evaluated in this order, without fused multiply-adds, on both sides.
pub fn image_lookup(data: &[u32], at: u32, uv: Vec2) -> Vec4 {
    let w = data[at as usize];
    let h = data[at as usize + 1];
    let wrap = data[at as usize + 2];
    let x = image_coord(w as f32 * uv.x - 0.5);
    let y = image_coord(h as f32 * (1.0 - uv.y) - 0.5);
    let x0 = x.floor();
    let y0 = y.floor();
    let fx = x - x0;
    let fy = y - y0;
    let i0 = image_wrap(x0 as i32, w, wrap);
    let i1 = image_wrap(x0 as i32 + 1, w, wrap);
    let j0 = image_wrap(y0 as i32, h, wrap);
    let j1 = image_wrap(y0 as i32 + 1, h, wrap);
    (1.0 - fx) * (1.0 - fy) * image_fetch(data, at, w, i0, j0)
        + fx * (1.0 - fy) * image_fetch(data, at, w, i1, j0)
        + (1.0 - fx) * fy * image_fetch(data, at, w, i0, j1)
        + fx * fy * image_fetch(data, at, w, i1, j1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::image_texture::{ImageTexture, Wrap};

    /// 4x2 texels, all exact in half floats: T[j][i] = (v, 10 v, v/4, 1 - v/16), v = 1 + i + 4 j.
    fn texel_value(i: u32, j: u32) -> Vec4 {
        let v = (1 + i + 4 * j) as f32;
        Vec4::new(v, 10.0 * v, v / 4.0, 1.0 - v / 16.0)
    }

    /// The test image packed after a block of other values, once per wrap mode: (data, ats).
    fn packed() -> (Vec<u32>, [u32; 3]) {
        let texels = (0..2).flat_map(|j| (0..4).map(move |i| texel_value(i, j).to_array())).collect();
        let image = ImageTexture { width: 4, height: 2, texels };
        let mut data = Vec::new();
        ImageTexture { width: 1, height: 1, texels: vec![[-9.0; 4]] }.pack(Wrap::Repeat, &mut data);
        let ats = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror].map(|wrap| image.pack(wrap, &mut data));
        (data, ats)
    }

    fn t(i: u32, j: u32) -> Vec4 {
        texel_value(i, j)
    }

    /// uv of the texel coordinate (x, y) of the 4x2 image: x = 4 u - 0.5, y = 2 (1 - v) - 0.5.
    fn uv(x: f32, y: f32) -> Vec2 {
        Vec2::new((x + 0.5) / 4.0, 1.0 - (y + 0.5) / 2.0)
    }

    #[track_caller]
    fn assert_near(got: Vec4, want: Vec4) {
        // The weights are multiples of 1/4 here, so only the final sums round: a few f32 ulps.
        assert!(got.abs_diff_eq(want, 1e-5 * want.abs().max_element().max(1.0)), "got {got}, expected {want}");
    }

    #[test]
    fn projections_follow_pov_rays_map_types() {
        use crate::layout::constants::TEXTURE_PROJECTION_PLANAR as PLANAR;
        use std::f32::consts::FRAC_1_SQRT_2 as H;
        let (sph, cyl) = (TEXTURE_PROJECTION_SPHERICAL, TEXTURE_PROJECTION_CYLINDRICAL);
        let p = Vec3::new(0.3, -2.0, 5.0);
        assert_eq!(image_projection(p, PLANAR), Vec2::new(0.3, -2.0));
        let near = |a: Vec2, b: Vec2| assert!(a.abs_diff_eq(b, 1e-6), "{a} != {b}");
        // u: 0 on +x, 1/4 on +z, 1/2 on -x, 3/4 on -z; v: latitude, 1 at the north pole.
        near(image_projection(Vec3::X, sph), Vec2::new(0.0, 0.5));
        near(image_projection(Vec3::Z * 3.0, sph), Vec2::new(0.25, 0.5));
        near(image_projection(-Vec3::X, sph), Vec2::new(0.5, 0.5));
        near(image_projection(-Vec3::Z, sph), Vec2::new(0.75, 0.5));
        near(image_projection(Vec3::new(H, H, 0.0), sph), Vec2::new(0.0, 0.75));
        near(image_projection(Vec3::new(0.0, -1.0, 0.0), sph), Vec2::new(0.0, 0.0));
        near(image_projection(Vec3::ZERO, sph), Vec2::new(0.0, 0.5));
        // Cylindrical: the same u, v = y.
        near(image_projection(Vec3::new(0.0, 0.7, -2.0), cyl), Vec2::new(0.75, 0.7));
        near(image_projection(Vec3::new(0.0, 3.0, 0.0), cyl), Vec2::new(0.0, 3.0));
        // Non-finite points give some uv (image_lookup reads inside the block for any uv).
        assert!(image_projection(Vec3::NAN, sph).x.is_nan() || image_projection(Vec3::NAN, sph).x == 0.0);
    }

    #[test]
    fn halves_decode_exactly() {
        for (bits, value) in
            [(0x3c00, 1.0), (0xc000, -2.0), (0x7bff, 65504.0), (0x0400, 2f32.powi(-14)), (0x0001, 2f32.powi(-24))]
        {
            assert_eq!(image_half_to_f32(bits), value, "{bits:#x}");
        }
        assert_eq!(image_half_to_f32(0x83ff), -1023.0 * 2f32.powi(-24));
        assert_eq!(image_half_to_f32(0x8000).to_bits(), (-0.0f32).to_bits());
    }

    #[test]
    fn wrap_modes_map_indices_as_documented() {
        let run = |wrap| (-9..13).map(|i| image_wrap(i, 4, wrap)).collect::<Vec<_>>();
        // i = -9 ..= 12
        assert_eq!(run(IMAGE_WRAP_REPEAT), [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]);
        assert_eq!(run(IMAGE_WRAP_CLAMP), [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3]);
        assert_eq!(run(IMAGE_WRAP_MIRROR), [0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3]);
        assert_eq!(image_wrap(i32::MIN + 1, 4, IMAGE_WRAP_REPEAT), 1); // -(2^31 - 1) = 1 mod 4
        assert_eq!(image_wrap(i32::MAX, 1, IMAGE_WRAP_MIRROR), 0);
        assert_eq!(image_wrap(-1, 4, 77), 3); // unknown modes repeat
    }

    #[test]
    fn bilinear_returns_texels_at_centres_and_means_between() {
        let (data, ats) = packed();
        for at in ats {
            for j in 0..2 {
                for i in 0..4 {
                    let centre = uv(i as f32, j as f32);
                    assert_eq!(image_lookup(&data, at, centre), t(i, j), "texel ({i}, {j}) at {centre}");
                    assert_eq!(image_texel(&data, at, centre), t(i, j));
                }
                for i in 0..3 {
                    let between = image_lookup(&data, at, uv(i as f32 + 0.5, j as f32));
                    assert_near(between, (t(i, j) + t(i + 1, j)) / 2.0);
                }
            }
            let middle = image_lookup(&data, at, uv(1.5, 0.5));
            assert_near(middle, (t(1, 0) + t(2, 0) + t(1, 1) + t(2, 1)) / 4.0);
            // Weights 3/4 and 1/4 along x, 1/2 along y.
            let quarter = image_lookup(&data, at, uv(0.25, 0.5));
            assert_near(quarter, (0.75 * (t(0, 0) + t(0, 1)) + 0.25 * (t(1, 0) + t(1, 1))) / 2.0);
        }
    }

    #[test]
    fn v_one_is_the_top_row() {
        let (data, [at, ..]) = packed();
        // uv (0.125, 0.75) is the centre of texel (0, 0), the file's top-left texel.
        assert_eq!(image_lookup(&data, at, Vec2::new(0.125, 0.75)), t(0, 0));
        assert_eq!(image_lookup(&data, at, Vec2::new(0.125, 0.25)), t(0, 1));
        assert_eq!(image_texel(&data, at, Vec2::new(0.01, 0.99)), t(0, 0));
        assert_eq!(image_texel(&data, at, Vec2::new(0.99, 0.01)), t(3, 1));
    }

    #[test]
    fn repeat_blends_the_opposite_edge_across_the_seam() {
        let (data, [at, ..]) = packed();
        // u = 0 on row 0's centre: x = -0.5, the 50/50 mix of columns 0 and W-1.
        let seam = (t(0, 0) + t(3, 0)) / 2.0;
        assert_near(image_lookup(&data, at, Vec2::new(0.0, 0.75)), seam);
        assert_near(image_lookup(&data, at, Vec2::new(1.0, 0.75)), seam);
        // The image's corner uv (0, 1): the four corner texels, equally.
        let corners = (t(0, 0) + t(3, 0) + t(0, 1) + t(3, 1)) / 4.0;
        assert_near(image_lookup(&data, at, Vec2::new(0.0, 1.0)), corners);
        // A whole number of periods away gives the same value (x = 12.75 and 0.75).
        assert_near(image_lookup(&data, at, uv(12.75, 0.0)), 0.25 * t(0, 0) + 0.75 * t(1, 0));
        assert_near(image_lookup(&data, at, uv(-3.25, 0.0)), 0.25 * t(0, 0) + 0.75 * t(1, 0));
    }

    #[test]
    fn clamp_and_mirror_at_hand_computed_points() {
        let (data, [_, clamp, mirror]) = packed();
        let lookup = |at, x, y| image_lookup(&data, at, uv(x, y));
        // Clamp: everything left of column 0's centre is column 0, right of column 3's is column 3.
        assert_eq!(lookup(clamp, -0.5, 0.0), t(0, 0));
        assert_eq!(lookup(clamp, -7.0, 0.0), t(0, 0));
        assert_eq!(lookup(clamp, 3.4, 1.0), t(3, 1));
        assert_eq!(lookup(clamp, 9.0, 5.0), t(3, 1));
        assert_near(lookup(clamp, 2.5, -3.0), (t(2, 0) + t(3, 0)) / 2.0);
        // Mirror: x = -1.75 lies between mirrored columns -2 -> 1 and -1 -> 0, with fx = 1/4.
        assert_near(lookup(mirror, -1.75, 0.0), 0.75 * t(1, 0) + 0.25 * t(0, 0));
        // x = 4.25: columns 4 -> 3 and 5 -> 2.
        assert_near(lookup(mirror, 4.25, 1.0), 0.75 * t(3, 1) + 0.25 * t(2, 1));
        // At u = 0 the mirror image of column 0 is column 0 itself; one period is 2 in u.
        assert_eq!(lookup(mirror, -0.5, 0.0), t(0, 0));
        assert_eq!(lookup(mirror, 8.0, 0.0), t(0, 0));
        // y = -0.75: rows -1 -> 0 and 0, so row 0.
        assert_eq!(lookup(mirror, 2.0, -0.75), t(2, 0));
    }

    #[test]
    fn wild_uv_reads_inside_the_block() {
        let (data, ats) = packed();
        let (min, max) = (t(0, 0).min(t(3, 1)), t(0, 0).max(t(3, 1)));
        let wild = [0.5, 1e6, -1e6, 1e30, -1e30, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e-40, -0.0, 16777217.0];
        for at in ats {
            for u in wild {
                for v in wild {
                    // A read outside the block would see the -9 of the image before it, or panic.
                    let got = image_lookup(&data, at, Vec2::new(u, v));
                    let slack = Vec4::splat(1e-5) * max;
                    assert!(got.cmpge(min - slack).all() && got.cmple(max + slack).all(), "{u}, {v}: {got}");
                    let texel = image_texel(&data, at, Vec2::new(u, v));
                    assert!((0..8).any(|k| texel == t(k % 4, k / 4)), "{u}, {v}: {texel}");
                }
            }
        }
        // NaN is texel coordinate 0.
        assert_eq!(image_lookup(&data, ats[0], Vec2::NAN), t(0, 0));
    }
}
