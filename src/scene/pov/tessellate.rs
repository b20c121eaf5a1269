//! Triangles for POV-Ray's shapes that Photonix has no analytic form of: lathe, sor, prism,
//! polygon and text (with `ttf.rs`). Everything here is in the shape's own POV-Ray coordinates;
//! `emit` applies the object's transform.
//!
//! Tolerance (docs/pov-ray.md): a curve is cut into pieces whose chords stay within
//! `CURVE_TOLERANCE` of the curve's size (the diagonal of its control points' bounds), and a
//! surface of revolution into `REVOLUTION_STEPS` wedges, whose chords stay within
//! 1 - cos(pi / 64) = 0.12% of the radius. The triangles are flat (no vertex normals).

use glam::{DVec2, DVec3};

/// Largest distance between a curve and its chords, as a share of the curve's size.
pub const CURVE_TOLERANCE: f64 = 1e-3;
/// Most pieces one spline segment is cut into.
pub const MAX_PIECES: usize = 32;
/// Wedges of a lathe or sor around its axis.
pub const REVOLUTION_STEPS: usize = 64;
/// Most triangles one tessellated object may make (a runaway loop of points would otherwise
/// write a scene too large to load).
pub const MAX_TRIANGLES: usize = 2_000_000;

pub type Tri = [DVec3; 3];

/// POV-Ray's spline kinds for lathe and prism (reference manual, "Lathe").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spline {
    Linear,
    Quadratic,
    Cubic,
    Bezier,
}

impl Spline {
    pub fn name(self) -> &'static str {
        match self {
            Spline::Linear => "linear_spline",
            Spline::Quadratic => "quadratic_spline",
            Spline::Cubic => "cubic_spline",
            Spline::Bezier => "bezier_spline",
        }
    }
}

/// One spline segment as POV-Ray's lathe holds it: p(t) = ((a t + b) t + c) t + d, t in [0, 1]
/// (lathe.cpp, Compute_Lathe: the same matrices for the prism).
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    a: DVec2,
    b: DVec2,
    c: DVec2,
    d: DVec2,
}

impl Segment {
    fn at(&self, t: f64) -> DVec2 {
        ((self.a * t + self.b) * t + self.c) * t + self.d
    }

    /// Pieces so that the chord error h^2 max|p''| / 8 stays within `tol`.
    fn pieces(&self, tol: f64) -> usize {
        let m = (2.0 * self.b).length().max((6.0 * self.a + 2.0 * self.b).length());
        if m <= 0.0 || tol <= 0.0 {
            return 1;
        }
        ((m / (8.0 * tol)).sqrt().ceil() as usize).clamp(1, MAX_PIECES)
    }
}

/// The segments of a spline through `p` (POV-Ray's lathe: linear n - 1, quadratic n - 2 with
/// the first point a control point, cubic n - 3 with one control point at each end, Bezier
/// n / 4 of four points each).
pub fn segments(kind: Spline, p: &[DVec2]) -> Vec<Segment> {
    let mut out = Vec::new();
    match kind {
        Spline::Linear => {
            for w in p.windows(2) {
                out.push(Segment { a: DVec2::ZERO, b: DVec2::ZERO, c: w[1] - w[0], d: w[0] });
            }
        }
        Spline::Quadratic => {
            for w in p.windows(3) {
                out.push(Segment {
                    a: DVec2::ZERO,
                    b: 0.5 * w[0] - w[1] + 0.5 * w[2],
                    c: -0.5 * w[0] + 0.5 * w[2],
                    d: w[1],
                });
            }
        }
        Spline::Cubic => {
            for w in p.windows(4) {
                out.push(Segment {
                    a: -0.5 * w[0] + 1.5 * w[1] - 1.5 * w[2] + 0.5 * w[3],
                    b: w[0] - 2.5 * w[1] + 2.0 * w[2] - 0.5 * w[3],
                    c: -0.5 * w[0] + 0.5 * w[2],
                    d: w[1],
                });
            }
        }
        Spline::Bezier => {
            for w in p.chunks_exact(4) {
                out.push(Segment {
                    a: w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0],
                    b: 3.0 * w[2] - 6.0 * w[1] + 3.0 * w[0],
                    c: 3.0 * w[1] - 3.0 * w[0],
                    d: w[0],
                });
            }
        }
    }
    out
}

/// The size a tolerance is relative to: the diagonal of the points' bounds.
fn extent(p: &[DVec2]) -> f64 {
    let (lo, hi) = p.iter().fold((DVec2::splat(f64::MAX), DVec2::splat(f64::MIN)), |(l, h), q| (l.min(*q), h.max(*q)));
    if p.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    }
}

/// The polyline that approximates a run of segments, first point included.
pub fn flatten(segs: &[Segment], size: f64) -> Vec<DVec2> {
    let tol = CURVE_TOLERANCE * size;
    let mut out = Vec::new();
    for (i, s) in segs.iter().enumerate() {
        if i == 0 {
            out.push(s.at(0.0));
        }
        let n = s.pieces(tol);
        for k in 1..=n {
            out.push(s.at(k as f64 / n as f64));
        }
    }
    out
}

/// A profile (x = radius, y = height) turned about the y axis.
pub fn revolve(profile: &[DVec2]) -> Vec<Tri> {
    let n = REVOLUTION_STEPS;
    let ring = |q: DVec2, k: usize| {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        DVec3::new(q.x * a.cos(), q.y, q.x * a.sin())
    };
    let mut tris = Vec::new();
    for w in profile.windows(2) {
        for k in 0..n {
            let (p00, p01) = (ring(w[0], k), ring(w[0], k + 1));
            let (p10, p11) = (ring(w[1], k), ring(w[1], k + 1));
            tris.push([p00, p10, p11]);
            tris.push([p00, p11, p01]);
        }
    }
    tris
}

/// POV-Ray's lathe: the spline through `points` (x radius, y height) turned about y.
pub fn lathe(kind: Spline, points: &[DVec2]) -> Vec<Tri> {
    let size = extent(points);
    revolve(&flatten(&segments(kind, points), size))
}

/// POV-Ray's sor: between points 1 and n - 2, r^2 is a cubic in the height through the
/// neighbouring points with slopes from their neighbours (sor.cpp, Compute_Sor), turned about y;
/// closed by discs at the bottom and top unless `open`.
pub fn sor(points: &[DVec2], open: bool) -> Vec<Tri> {
    let size = extent(points);
    let tol = CURVE_TOLERANCE * size;
    let mut profile = Vec::new();
    for w in points.windows(4) {
        let (h0, h1, h2, h3) = (w[0].y, w[1].y, w[2].y, w[3].y);
        let (r0, r1, r2, r3) = (w[0].x * w[0].x, w[1].x * w[1].x, w[2].x * w[2].x, w[3].x * w[3].x);
        if h2 - h1 == 0.0 {
            continue;
        }
        // Hermite on [h1, h2] for r^2 with end slopes k1, k2.
        let k1 = if h2 != h0 { (r2 - r0) / (h2 - h0) } else { 0.0 };
        let k2 = if h3 != h1 { (r3 - r1) / (h3 - h1) } else { 0.0 };
        let dh = h2 - h1;
        let r_at = |t: f64| {
            let (t2, t3) = (t * t, t * t * t);
            let f = (2.0 * t3 - 3.0 * t2 + 1.0) * r1
                + (t3 - 2.0 * t2 + t) * dh * k1
                + (-2.0 * t3 + 3.0 * t2) * r2
                + (t3 - t2) * dh * k2;
            DVec2::new(f.max(0.0).sqrt(), h1 + t * dh)
        };
        // Pieces by the second difference of the radius over the segment, as for splines.
        let (a, m, b) = (r_at(0.0), r_at(0.5), r_at(1.0));
        let bend = (m - 0.5 * (a + b)).length();
        let n = if bend <= 0.0 || tol <= 0.0 {
            1
        } else {
            (((bend / tol).sqrt() * 2.0).ceil() as usize).clamp(2, MAX_PIECES)
        };
        if profile.is_empty() {
            profile.push(a);
        }
        for k in 1..=n {
            profile.push(r_at(k as f64 / n as f64));
        }
    }
    let mut tris = revolve(&profile);
    if !open {
        if let (Some(first), Some(last)) = (profile.first().copied(), profile.last().copied()) {
            tris.extend(revolve(&[DVec2::new(0.0, first.y), first]));
            tris.extend(revolve(&[last, DVec2::new(0.0, last.y)]));
        }
    }
    tris
}

/// The closed outlines of a prism's points (x, z), each flattened: POV-Ray closes a
/// sub-polygon where a point repeats the sub-polygon's first point on the curve (prism.cpp).
pub fn prism_outlines(kind: Spline, p: &[DVec2]) -> Vec<Vec<DVec2>> {
    let size = extent(p);
    let mut out = Vec::new();
    let mut start = 0;
    // (points a sub-polygon starts with before its first curve point, points after its closing point)
    let (lead, tail, min_len) = match kind {
        Spline::Linear => (0, 0, 3),
        Spline::Quadratic => (1, 0, 4),
        Spline::Cubic => (1, 1, 5),
        Spline::Bezier => (0, 0, 4),
    };
    while start < p.len() {
        let first = p[start + lead.min(p.len() - 1 - start)];
        let mut close = None;
        match kind {
            Spline::Bezier => {
                let mut i = start + 3;
                while i < p.len() {
                    if p[i] == first {
                        close = Some(i);
                        break;
                    }
                    i += 4;
                }
            }
            _ => {
                for (i, q) in p.iter().enumerate().skip(start + lead + 2) {
                    if *q == first {
                        close = Some(i);
                        break;
                    }
                }
            }
        }
        let end = close.unwrap_or(p.len().saturating_sub(1 + tail)); // index of the closing point
        let last = (end + tail).min(p.len() - 1);
        let run = &p[start..=last];
        if run.len() >= min_len {
            let mut poly = match kind {
                Spline::Linear => run.to_vec(),
                _ => flatten(&segments(kind, run), size),
            };
            if close.is_none() && kind == Spline::Linear {
                // An open outline: POV-Ray warns and closes it.
                poly.push(run[0]);
            }
            if poly.len() >= 2 && poly.first() == poly.last() {
                poly.pop();
            }
            if poly.len() >= 3 {
                out.push(poly);
            }
        }
        start = last + 1;
    }
    out
}

/// Which points a set of outlines encloses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillRule {
    /// Inside where a ray crosses the outlines an odd number of times (POV-Ray's prism, polygon).
    EvenOdd,
    /// Inside where the outlines wind around the point (TrueType glyphs).
    NonZero,
}

/// Triangles covering the region `outlines` enclose: cut into horizontal slabs at every vertex
/// and every crossing of two edges, so that within a slab the edges do not cross and the inside
/// is a run of trapezoids. Exact for any outlines (holes, several pieces, self-crossing).
pub fn fill(outlines: &[Vec<DVec2>], rule: FillRule) -> Vec<[DVec2; 3]> {
    let mut edges: Vec<(DVec2, DVec2)> = Vec::new();
    for poly in outlines {
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            if a.y != b.y && a.is_finite() && b.is_finite() {
                edges.push((a, b));
            }
        }
    }
    let mut ys: Vec<f64> = edges.iter().flat_map(|(a, b)| [a.y, b.y]).collect();
    // Crossings of two edges (bounded: beyond 4000 edges, 16 million pairs, they are skipped).
    if edges.len() <= 4000 {
        for i in 0..edges.len() {
            for j in i + 1..edges.len() {
                if let Some(y) = crossing_y(edges[i], edges[j]) {
                    ys.push(y);
                }
            }
        }
    }
    ys.sort_by(f64::total_cmp);
    ys.dedup();
    let x_at = |(a, b): (DVec2, DVec2), y: f64| a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
    let mut tris = Vec::new();
    // A trapezoid between edges l and r from y0 to y1; consecutive slabs whose span lies between
    // the same two edges make one trapezoid.
    let mut trapezoid = |l: usize, r: usize, y0: f64, y1: f64| {
        let (p00, p10) = (DVec2::new(x_at(edges[l], y0), y0), DVec2::new(x_at(edges[r], y0), y0));
        let (p01, p11) = (DVec2::new(x_at(edges[l], y1), y1), DVec2::new(x_at(edges[r], y1), y1));
        if p10.x - p00.x > 0.0 {
            tris.push([p00, p10, p11]);
        }
        if p11.x - p01.x > 0.0 {
            tris.push([p00, p11, p01]);
        }
    };
    let mut active: Vec<(usize, usize, f64)> = Vec::new();
    for w in ys.windows(2) {
        let (y0, y1) = (w[0], w[1]);
        if y1 <= y0 {
            continue;
        }
        let ym = 0.5 * (y0 + y1);
        let mut cross: Vec<(f64, usize, i32)> = edges
            .iter()
            .enumerate()
            .filter(|(_, (a, b))| a.y.min(b.y) <= y0 && a.y.max(b.y) >= y1)
            .map(|(i, e)| (x_at(*e, ym), i, if e.1.y > e.0.y { 1 } else { -1 }))
            .collect();
        cross.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut next: Vec<(usize, usize, f64)> = Vec::new();
        let mut winding = 0;
        for k in 0..cross.len().saturating_sub(1) {
            winding += cross[k].2;
            let inside = match rule {
                FillRule::EvenOdd => (k + 1) % 2 == 1,
                FillRule::NonZero => winding != 0,
            };
            if !inside {
                continue;
            }
            let (l, r) = (cross[k].1, cross[k + 1].1);
            let start = match active.iter().position(|s| s.0 == l && s.1 == r) {
                Some(i) => active.swap_remove(i).2,
                None => y0,
            };
            next.push((l, r, start));
        }
        for (l, r, start) in active.drain(..) {
            trapezoid(l, r, start, y0);
        }
        active = next;
        if let Some(&top) = ys.last() {
            if y1 == top {
                for (l, r, start) in active.drain(..) {
                    trapezoid(l, r, start, y1);
                }
            }
        }
    }
    tris
}

/// The height where two edges cross strictly inside both, if they do.
fn crossing_y((a, b): (DVec2, DVec2), (c, d): (DVec2, DVec2)) -> Option<f64> {
    let r = b - a;
    let s = d - c;
    let den = r.perp_dot(s);
    if den == 0.0 {
        return None;
    }
    let t = (c - a).perp_dot(s) / den;
    let u = (c - a).perp_dot(r) / den;
    if t > 1e-12 && t < 1.0 - 1e-12 && u > 1e-12 && u < 1.0 - 1e-12 {
        Some(a.y + t * r.y)
    } else {
        None
    }
}

/// A region in the plane (x, z) extruded along y: caps at `bottom` and `top` (unless `open`) and
/// a wall along every outline edge. `conic` scales the outline by the height (POV-Ray's
/// conic_sweep: the outline at y is the points times y).
pub fn extrude(outlines: &[Vec<DVec2>], rule: FillRule, bottom: f64, top: f64, open: bool, conic: bool) -> Vec<Tri> {
    let at = |q: DVec2, y: f64| {
        let s = if conic { y } else { 1.0 };
        DVec3::new(q.x * s, y, q.y * s)
    };
    let mut tris = Vec::new();
    for poly in outlines {
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            tris.push([at(a, bottom), at(b, bottom), at(b, top)]);
            tris.push([at(a, bottom), at(b, top), at(a, top)]);
        }
    }
    if !open {
        for t in fill(outlines, rule) {
            tris.push(t.map(|q| at(q, bottom)));
            tris.push(t.map(|q| at(q, top)));
        }
    }
    tris
}

/// POV-Ray's polygon: points in 3D, sub-polygons closed where a point repeats the sub-polygon's
/// first, filled even-odd in their plane.
pub fn polygon(points: &[DVec3]) -> Vec<Tri> {
    // The plane: Newell's normal of all the points.
    let mut n = DVec3::ZERO;
    for i in 0..points.len() {
        let (a, b) = (points[i], points[(i + 1) % points.len()]);
        n += DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    let Some(n) = n.try_normalize() else { return Vec::new() };
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let o = points.first().copied().unwrap_or(DVec3::ZERO);
    let to2 = |p: DVec3| DVec2::new((p - o).dot(u), (p - o).dot(v));
    let mut outlines = Vec::new();
    let mut start = 0;
    while start < points.len() {
        let first = points[start];
        let end = (start + 3..points.len()).find(|&i| points[i] == first);
        let stop = end.unwrap_or(points.len());
        let poly: Vec<DVec2> = points[start..stop].iter().map(|p| to2(*p)).collect();
        if poly.len() >= 3 {
            outlines.push(poly);
        }
        start = stop + 1;
    }
    // Back in 3D: the points on the plane through the first point.
    let off = o.dot(n);
    let back = |q: DVec2| o + u * q.x + v * q.y + n * (off - o.dot(n));
    fill(&outlines, FillRule::EvenOdd).into_iter().map(|t| t.map(back)).collect()
}

/// Vertex normals for smooth shading of `tris`, one per corner: where triangles share a vertex
/// (points within 1e-7 of the shape's size of each other, so that a lathe's seam at 0 and 2 pi
/// closes), each corner takes the mean of the normals of the faces around it whose normal is
/// within `crease_deg` of its own face's, weighted by their angles there: the model importer's
/// "auto smooth" (`model::normals`). A degenerate face's corners are zero (the writer leaves
/// such a triangle flat).
pub fn corner_normals(tris: &[Tri], crease_deg: f32) -> Vec<[DVec3; 3]> {
    let (lo, hi) =
        tris.iter().flatten().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
    let quantum = ((hi - lo).max_element() * 1e-7).max(f64::MIN_POSITIVE);
    let mut index: std::collections::HashMap<[i64; 3], u32> = std::collections::HashMap::new();
    let mut mesh = crate::scene::model::ModelMesh::default();
    for t in tris {
        let ids = t.map(|p| {
            let key = ((p - lo) / quantum).round().to_array().map(|c| c as i64);
            *index.entry(key).or_insert_with(|| {
                mesh.positions.push(p.as_vec3());
                (mesh.positions.len() - 1) as u32
            })
        });
        mesh.push_face(&ids, None);
    }
    let normals = crate::scene::model::normals::corner_normals(&mesh, crease_deg);
    normals.chunks(3).map(|c| [c[0].as_dvec3(), c[1].as_dvec3(), c[2].as_dvec3()]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(tris: &[[DVec2; 3]]) -> f64 {
        tris.iter().map(|t| 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs()).sum()
    }

    #[test]
    fn fill_covers_a_square_with_a_hole_exactly() {
        let sq = |h: f64| vec![DVec2::new(-h, -h), DVec2::new(h, -h), DVec2::new(h, h), DVec2::new(-h, h)];
        // 4x4 square less a 2x2 hole (wound the same way: even-odd still makes it a hole).
        let a = area(&fill(&[sq(2.0), sq(1.0)], FillRule::EvenOdd));
        assert!((a - 12.0).abs() < 1e-12, "area {a}");
        // Non-zero: the hole must wind the other way.
        let mut hole = sq(1.0);
        hole.reverse();
        let a = area(&fill(&[sq(2.0), hole], FillRule::NonZero));
        assert!((a - 12.0).abs() < 1e-12, "area {a}");
        let a = area(&fill(&[sq(2.0), sq(1.0)], FillRule::NonZero));
        assert!((a - 16.0).abs() < 1e-12, "area {a}");
    }

    #[test]
    fn fill_handles_a_self_crossing_outline() {
        // A bow tie: two triangles of area 1 each.
        let bow = vec![DVec2::new(0.0, 0.0), DVec2::new(2.0, 2.0), DVec2::new(2.0, 0.0), DVec2::new(0.0, 2.0)];
        let a = area(&fill(&[bow], FillRule::EvenOdd));
        assert!((a - 2.0).abs() < 1e-12, "area {a}");
    }

    #[test]
    fn lathe_of_a_circle_stays_within_the_tolerance() {
        // A Bezier quarter circle (the usual 0.5523 handles) turned about y: a hemisphere of
        // radius 1; every vertex lies within the Bezier's own error (2.7e-4) of the sphere.
        let k = 0.5523;
        let p = [DVec2::new(1.0, 0.0), DVec2::new(1.0, k), DVec2::new(k, 1.0), DVec2::new(0.0, 1.0)];
        let tris = lathe(Spline::Bezier, &p);
        let worst = tris.iter().flatten().map(|v| (v.length() - 1.0).abs()).fold(0.0, f64::max);
        println!("lathe vertices off the sphere by at most {worst:.2e}");
        assert!(worst < 3e-4);
    }

    #[test]
    fn cubic_spline_passes_through_its_inner_points() {
        let p = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(2.0, 0.5), DVec2::new(3.0, 3.0)];
        let s = segments(Spline::Cubic, &p);
        assert_eq!(s.len(), 1);
        assert!((s[0].at(0.0) - p[1]).length() < 1e-12 && (s[0].at(1.0) - p[2]).length() < 1e-12);
        let q = segments(Spline::Quadratic, &p[..3]);
        assert!((q[0].at(0.0) - p[1]).length() < 1e-12 && (q[0].at(1.0) - p[2]).length() < 1e-12);
    }

    #[test]
    fn prism_outlines_split_at_repeated_points() {
        // Two squares in one linear prism: the second closes where it repeats its first point.
        let p: Vec<DVec2> = [
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 4.0),
            (0.0, 4.0),
            (0.0, 0.0),
            (1.0, 1.0),
            (3.0, 1.0),
            (3.0, 3.0),
            (1.0, 3.0),
            (1.0, 1.0),
        ]
        .iter()
        .map(|(x, y)| DVec2::new(*x, *y))
        .collect();
        let o = prism_outlines(Spline::Linear, &p);
        assert_eq!(o.len(), 2);
        assert_eq!(o[0].len(), 4);
        let a = area(&fill(&o, FillRule::EvenOdd));
        assert!((a - 12.0).abs() < 1e-12, "area {a}");
    }

    #[test]
    fn polygon_fills_in_its_plane() {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.0, 2.0, 2.0),
            DVec3::new(0.0, 0.0, 2.0),
        ];
        let tris = polygon(&p);
        let a: f64 = tris.iter().map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()).sum();
        assert!((a - 4.0).abs() < 1e-9, "area {a}");
        assert!(tris.iter().flatten().all(|v| v.x.abs() < 1e-12));
    }
}
