//! Just enough of TrueType to draw POV-Ray's `text`: the character map (formats 0, 4, 6 and
//! 12), glyph outlines (simple and composite, quadratic curves flattened) and advance widths
//! (Apple's and Microsoft's TrueType reference, tables `cmap`, `glyf`, `loca`, `head`, `hhea`,
//! `hmtx`). Every read is bounds-checked: a damaged font is an error, never a panic.

use glam::DVec2;

/// Flattening of a glyph's quadratic curves: pieces per curve. A quadratic deviates from its
/// chords by at most |a - 2c + b| / (4 n^2): for a curve whose control polygon bends by a tenth
/// of the em (a large bowl), 0.16% of the em with n = 4.
const CURVE_PIECES: usize = 4;
/// Most components a composite glyph may nest (runaway recursion in a damaged font).
const MAX_NESTING: usize = 8;

pub struct Font {
    data: Vec<u8>,
    units_per_em: f64,
    long_loca: bool,
    glyf: usize,
    loca: usize,
    hmtx: usize,
    metrics: usize,
    glyphs: usize,
    cmap: usize,
}

fn u16_at(d: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*d.get(o)?, *d.get(o + 1)?]))
}

fn i16_at(d: &[u8], o: usize) -> Option<i16> {
    u16_at(d, o).map(|v| v as i16)
}

fn u32_at(d: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_be_bytes([*d.get(o)?, *d.get(o + 1)?, *d.get(o + 2)?, *d.get(o + 3)?]))
}

impl Font {
    /// Reads a font file's bytes; `None` when it is not a TrueType font this reader knows.
    pub fn parse(data: Vec<u8>) -> Option<Font> {
        let n = u16_at(&data, 4)? as usize;
        let table = |tag: &[u8; 4]| -> Option<usize> {
            (0..n).find_map(|i| {
                let r = 12 + 16 * i;
                (data.get(r..r + 4)? == tag).then(|| u32_at(&data, r + 8).map(|o| o as usize)).flatten()
            })
        };
        let head = table(b"head")?;
        let maxp = table(b"maxp")?;
        let hhea = table(b"hhea")?;
        let (glyf, loca, hmtx, cmap) = (table(b"glyf")?, table(b"loca")?, table(b"hmtx")?, table(b"cmap")?);
        let units_per_em = u16_at(&data, head + 18)? as f64;
        let long_loca = i16_at(&data, head + 50)? != 0;
        let glyphs = u16_at(&data, maxp + 4)? as usize;
        let metrics = u16_at(&data, hhea + 34)? as usize;
        if units_per_em <= 0.0 {
            return None;
        }
        // The best character map: Unicode (3, 1 or 0, *), else symbol (3, 0), else Macintosh (1, 0).
        let count = u16_at(&data, cmap + 2)? as usize;
        let mut best: Option<(u32, usize)> = None;
        for i in 0..count {
            let r = cmap + 4 + 8 * i;
            let (platform, encoding) = (u16_at(&data, r)?, u16_at(&data, r + 2)?);
            let offset = cmap + u32_at(&data, r + 4)? as usize;
            let rank = match (platform, encoding) {
                (3, 10) => 5,
                (3, 1) => 4,
                (0, _) => 3,
                (3, 0) => 2,
                (1, 0) => 1,
                _ => 0,
            };
            if rank > 0 && best.is_none_or(|(r, _)| rank > r) {
                best = Some((rank, offset));
            }
        }
        let cmap = best?.1;
        Some(Font { data, units_per_em, long_loca, glyf, loca, hmtx, metrics, glyphs, cmap })
    }

    /// The glyph of a character (0, the missing glyph, when the font has none). Symbol fonts
    /// map their characters at U+F000 and up, as POV-Ray also tries.
    pub fn glyph(&self, c: char) -> u16 {
        let g = self.lookup(c as u32).unwrap_or(0);
        if g == 0 && (c as u32) < 0x100 {
            return self.lookup(0xF000 + c as u32).unwrap_or(0);
        }
        g
    }

    fn lookup(&self, c: u32) -> Option<u16> {
        let d = &self.data;
        let t = self.cmap;
        match u16_at(d, t)? {
            0 => (c < 256).then(|| d.get(t + 6 + c as usize).map(|g| *g as u16)).flatten(),
            4 => {
                let segs = u16_at(d, t + 6)? as usize / 2;
                let ends = t + 14;
                let starts = ends + 2 * segs + 2;
                let deltas = starts + 2 * segs;
                let ranges = deltas + 2 * segs;
                for i in 0..segs {
                    let end = u16_at(d, ends + 2 * i)? as u32;
                    if c > end {
                        continue;
                    }
                    let start = u16_at(d, starts + 2 * i)? as u32;
                    if c < start {
                        return Some(0);
                    }
                    let delta = u16_at(d, deltas + 2 * i)?;
                    let range = u16_at(d, ranges + 2 * i)? as usize;
                    if range == 0 {
                        return Some((c as u16).wrapping_add(delta));
                    }
                    let at = ranges + 2 * i + range + 2 * (c - start) as usize;
                    let g = u16_at(d, at)?;
                    return Some(if g == 0 { 0 } else { g.wrapping_add(delta) });
                }
                Some(0)
            }
            6 => {
                let first = u16_at(d, t + 6)? as u32;
                let n = u16_at(d, t + 8)? as u32;
                (c >= first && c < first + n).then(|| u16_at(d, t + 10 + 2 * (c - first) as usize)).flatten()
            }
            12 => {
                let groups = u32_at(d, t + 12)? as usize;
                for i in 0..groups.min(1 << 16) {
                    let r = t + 16 + 12 * i;
                    let (s, e, g) = (u32_at(d, r)?, u32_at(d, r + 4)?, u32_at(d, r + 8)?);
                    if c >= s && c <= e {
                        return Some((g + (c - s)) as u16);
                    }
                }
                Some(0)
            }
            _ => None,
        }
    }

    /// The advance width of a glyph, in ems.
    pub fn advance(&self, g: u16) -> f64 {
        let i = (g as usize).min(self.metrics.saturating_sub(1));
        u16_at(&self.data, self.hmtx + 4 * i).unwrap_or(0) as f64 / self.units_per_em
    }

    /// The closed outlines of a glyph, in ems (the baseline at y = 0); `None` if the font's data
    /// for it is damaged.
    pub fn outline(&self, g: u16) -> Option<Vec<Vec<DVec2>>> {
        let mut out = Vec::new();
        self.outline_into(g, [1.0, 0.0, 0.0, 1.0], DVec2::ZERO, 0, &mut out)?;
        let s = 1.0 / self.units_per_em;
        Some(out.into_iter().map(|c| c.into_iter().map(|p| p * s).collect()).collect())
    }

    fn glyph_range(&self, g: u16) -> Option<(usize, usize)> {
        let g = g as usize;
        if g >= self.glyphs {
            return None;
        }
        let (a, b) = if self.long_loca {
            (u32_at(&self.data, self.loca + 4 * g)? as usize, u32_at(&self.data, self.loca + 4 * g + 4)? as usize)
        } else {
            (
                2 * u16_at(&self.data, self.loca + 2 * g)? as usize,
                2 * u16_at(&self.data, self.loca + 2 * g + 2)? as usize,
            )
        };
        Some((self.glyf + a, self.glyf + b))
    }

    fn outline_into(&self, g: u16, m: [f64; 4], off: DVec2, depth: usize, out: &mut Vec<Vec<DVec2>>) -> Option<()> {
        if depth > MAX_NESTING {
            return None;
        }
        let (start, end) = self.glyph_range(g)?;
        if end <= start {
            return Some(()); // an empty glyph (a space)
        }
        let d = &self.data;
        let contours = i16_at(d, start)?;
        let place = |p: DVec2| DVec2::new(m[0] * p.x + m[2] * p.y, m[1] * p.x + m[3] * p.y) + off;
        if contours >= 0 {
            let n = contours as usize;
            let mut ends = Vec::with_capacity(n);
            for i in 0..n {
                ends.push(u16_at(d, start + 10 + 2 * i)? as usize);
            }
            let points = ends.last().map_or(0, |e| e + 1);
            let ins = u16_at(d, start + 10 + 2 * n)? as usize;
            let mut o = start + 12 + 2 * n + ins;
            let mut flags = Vec::with_capacity(points);
            while flags.len() < points {
                let f = *d.get(o)?;
                o += 1;
                flags.push(f);
                if f & 8 != 0 {
                    let r = *d.get(o)?;
                    o += 1;
                    for _ in 0..r {
                        flags.push(f);
                    }
                }
            }
            flags.truncate(points);
            let mut coord = |short: u8, same: u8| -> Option<Vec<f64>> {
                let mut v = 0i32;
                let mut out = Vec::with_capacity(points);
                for f in &flags {
                    if f & short != 0 {
                        let b = *d.get(o)? as i32;
                        o += 1;
                        v += if f & same != 0 { b } else { -b };
                    } else if f & same == 0 {
                        v += i16_at(d, o)? as i32;
                        o += 2;
                    }
                    out.push(v as f64);
                }
                Some(out)
            };
            let xs = coord(2, 16)?;
            let ys = coord(4, 32)?;
            let mut first = 0;
            for e in ends {
                if e < first || e >= points {
                    return None;
                }
                let pts: Vec<(DVec2, bool)> =
                    (first..=e).map(|i| (place(DVec2::new(xs[i], ys[i])), flags[i] & 1 != 0)).collect();
                first = e + 1;
                let c = flatten_contour(&pts);
                if c.len() >= 3 {
                    out.push(c);
                }
            }
        } else {
            // A composite: components, each a glyph moved (and maybe scaled).
            let mut o = start + 10;
            loop {
                let flags = u16_at(d, o)?;
                let child = u16_at(d, o + 2)?;
                o += 4;
                let (dx, dy) = if flags & 1 != 0 {
                    let v = (i16_at(d, o)? as f64, i16_at(d, o + 2)? as f64);
                    o += 4;
                    v
                } else {
                    let v = (*d.get(o)? as i8 as f64, *d.get(o + 1)? as i8 as f64);
                    o += 2;
                    v
                };
                let f2 = |o: usize| i16_at(d, o).map(|v| v as f64 / 16384.0);
                let mut cm = [1.0, 0.0, 0.0, 1.0];
                if flags & 8 != 0 {
                    let s = f2(o)?;
                    cm = [s, 0.0, 0.0, s];
                    o += 2;
                } else if flags & 0x40 != 0 {
                    cm = [f2(o)?, 0.0, 0.0, f2(o + 2)?];
                    o += 4;
                } else if flags & 0x80 != 0 {
                    cm = [f2(o)?, f2(o + 2)?, f2(o + 4)?, f2(o + 6)?];
                    o += 8;
                }
                // Point-matched placement (ARGS_ARE_XY_VALUES clear) is rare: placed at the origin.
                let shift = if flags & 2 != 0 { DVec2::new(dx, dy) } else { DVec2::ZERO };
                let comb = [
                    m[0] * cm[0] + m[2] * cm[1],
                    m[1] * cm[0] + m[3] * cm[1],
                    m[0] * cm[2] + m[2] * cm[3],
                    m[1] * cm[2] + m[3] * cm[3],
                ];
                self.outline_into(child, comb, place(shift), depth + 1, out)?;
                if flags & 0x20 == 0 {
                    break;
                }
            }
        }
        Some(())
    }
}

/// A TrueType contour (on-curve points and quadratic control points, two controls in a row
/// implying an on-curve point between them) as a polyline.
fn flatten_contour(pts: &[(DVec2, bool)]) -> Vec<DVec2> {
    let n = pts.len();
    if n == 0 {
        return Vec::new();
    }
    // Start on an on-curve point (or the midpoint of the first two controls).
    let start = match pts.iter().position(|p| p.1) {
        Some(i) => pts[i].0,
        None => 0.5 * (pts[0].0 + pts[1 % n].0),
    };
    let first_on = pts.iter().position(|p| p.1).unwrap_or(0);
    let mut out = vec![start];
    let mut cur = start;
    let mut control: Option<DVec2> = None;
    for k in 1..=n {
        let (p, on) = pts[(first_on + k) % n];
        match (on, control) {
            (true, None) => {
                out.push(p);
                cur = p;
            }
            (true, Some(c)) => {
                quad(&mut out, cur, c, p);
                cur = p;
                control = None;
            }
            (false, None) => control = Some(p),
            (false, Some(c)) => {
                let mid = 0.5 * (c + p);
                quad(&mut out, cur, c, mid);
                cur = mid;
                control = Some(p);
            }
        }
    }
    if let Some(c) = control {
        quad(&mut out, cur, c, start);
    }
    if out.len() >= 2 && out.first() == out.last() {
        out.pop();
    }
    out
}

fn quad(out: &mut Vec<DVec2>, a: DVec2, c: DVec2, b: DVec2) {
    for k in 1..=CURVE_PIECES {
        let t = k as f64 / CURVE_PIECES as f64;
        out.push((1.0 - t) * (1.0 - t) * a + 2.0 * t * (1.0 - t) * c + t * t * b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contour_of_controls_only_closes() {
        // Four controls around the origin: a closed rounded shape through the implied midpoints.
        let pts = [
            (DVec2::new(1.0, 0.0), false),
            (DVec2::new(0.0, 1.0), false),
            (DVec2::new(-1.0, 0.0), false),
            (DVec2::new(0.0, -1.0), false),
        ];
        let c = flatten_contour(&pts);
        assert_eq!(c.len(), 4 * CURVE_PIECES);
        assert!(c.iter().all(|p| p.length() <= 1.0 + 1e-12 && p.length() >= 0.5 - 1e-12));
    }

    #[test]
    fn damaged_fonts_are_refused() {
        assert!(Font::parse(vec![0; 3]).is_none());
        assert!(Font::parse(vec![0xff; 64]).is_none());
    }

    #[test]
    fn povray_fonts_draw_letters_when_installed() {
        let path = std::path::Path::new(super::super::STANDARD_INCLUDE_DIR).join("timrom.ttf");
        let Ok(data) = std::fs::read(&path) else {
            println!("skipped: {} is not installed", path.display());
            return;
        };
        let f = Font::parse(data).expect("timrom.ttf parses");
        let g = f.glyph('O');
        assert!(g != 0);
        let o = f.outline(g).unwrap();
        assert_eq!(o.len(), 2, "an O has an outer and an inner contour");
        let adv = f.advance(g);
        assert!(adv > 0.5 && adv < 1.0, "advance {adv}");
    }
}
