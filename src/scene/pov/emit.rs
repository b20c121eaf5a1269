//! Writes an evaluated POV-Ray scene as a Photonix TOML scene: coordinates mirrored into
//! Photonix's right-handed frame, POV-Ray's finish mapped onto physical materials and its lights
//! onto physical intensities (docs/pov-ray.md gives each rule and why).

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;

use glam::{DMat3, DMat4, DVec3};
use toml::{Table, Value as T};

use super::ast::{
    Colour, CsgOp, Interior, Light, LightKind, Media, Normal, Obj, ObjKind, PigmentKind, PovScene, Rainbow, SkySphere,
    Tex, TexMap,
};
use super::parser::Result;
use super::{Pos, PovError, PovOptions};
use crate::layout::constants::MIX_MAX_DEPTH;
use crate::scene::kinds;

/// POV-Ray is left-handed with +z into the screen; Photonix is right-handed. Mirroring z maps
/// one onto the other and keeps x right and y up on the image, for POV-Ray's usual camera
/// (right = up x direction). A camera whose right is the other way (`right -x*4/3`, or `up z`
/// with the default direction, which POV-Ray's `look_at` turns around) is a right-handed view
/// of the scene: POV-Ray's coordinates are then kept as they are (`Emitter::flip`), so the image
/// is not mirrored.
const MIRROR: DMat4 =
    DMat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);

/// Layered textures (`texture { A } texture { B }`, B over A) as one: POV-Ray draws each layer
/// over those below by its pigment's opacity, and the upper layers are usually a see-through
/// pigment (grid lines, veins) carrying a finish (a floor's reflection, a varnish's highlight).
/// The bottom layer stands, under the upper layers' finishes: each channel's largest
/// `reflection`, the strongest `phong` and `specular` (with their sizes), the largest
/// `metallic`, and the first bump among the layers when the bottom has none. An upper layer
/// whose pigment is a solid opaque colour (no map) covers everything below it and replaces it.
/// Upper layers' patterned pigments are not drawn (a mix would need their opacity as a
/// weight, which the renderer's mixes cannot take from a pigment yet).
fn layered(layers: &[Tex]) -> Tex {
    let mut t = layers[0].clone();
    for u in &layers[1..] {
        let opaque = matches!(u.pigment.kind, PigmentKind::Solid(c) if c[3] + c[4] < 0.02) && u.map.is_none();
        if opaque {
            t = u.clone();
            continue;
        }
        let (f, g) = (&mut t.finish, &u.finish);
        for i in 0..3 {
            f.reflection[i] = f.reflection[i].max(g.reflection[i]);
        }
        if g.phong > f.phong {
            (f.phong, f.phong_size) = (g.phong, g.phong_size);
        }
        if g.specular > f.specular {
            (f.specular, f.roughness) = (g.specular, g.roughness);
        }
        f.metallic = f.metallic.max(g.metallic);
        if t.normal.is_none() && u.normal.is_some() {
            t.normal = u.normal.as_ref().map(|n| Normal { xform: t.xform.inverse() * u.xform * n.xform, ..n.clone() });
        }
    }
    t
}

/// Where the camera looks, in POV-Ray's coordinates: its `look_at`; without one, the point
/// along its direction as far as the centre of the scene's finite objects (when they lie
/// ahead), else one direction length ahead. Lights are matched to POV-Ray's brightness there.
fn view_target(scene: &PovScene, c: &super::ast::Camera) -> DVec3 {
    if let Some(at) = c.look_at {
        return at;
    }
    let ahead = c.direction.normalize_or(DVec3::Z);
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for o in &scene.objects {
        let (a, b) = bounds_of(o);
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if lo.cmple(hi).all() {
        let along = (0.5 * (lo + hi) - c.location).dot(ahead);
        if along.is_finite() && along > c.direction.length() {
            return c.location + ahead * along;
        }
    }
    c.location + c.direction
}

/// A light farther than this many times the camera's distance from where it looks becomes a
/// distant light: across the part of the scene the camera sees its 1/d^2 falloff would change
/// its brightness by a few percent (POV-Ray's light has none), and its direction by a degree.
pub const FAR_LIGHT_RATIO: f64 = 50.0;

/// Whether a POV-Ray camera is left-handed (right . (up x direction) > 0, POV-Ray's default): its
/// scene is mirrored into Photonix's coordinates.
fn left_handed(c: &super::ast::Camera) -> bool {
    c.right.dot(c.up.cross(c.direction)) > 0.0
}

fn num(x: f64) -> T {
    T::Float(x)
}

fn vec3(v: DVec3) -> T {
    T::Array(vec![num(v.x), num(v.y), num(v.z)])
}

/// The area of a surface given in parameters (u, v) in [0, 1]^2, through the affine map `m`:
/// the midpoint rule on a 256 x 256 grid of |dp/du x dp/dv|, the derivatives by central
/// differences of the mapped points (the integrands here are smooth and periodic or linear,
/// so the rule is within 1e-5 of the closed forms; tested).
fn parametric_area(m: &DMat4, f: impl Fn(f64, f64) -> DVec3) -> f64 {
    const N: usize = 256;
    const H: f64 = 1e-5;
    let p = |u: f64, v: f64| m.transform_point3(f(u, v));
    let mut sum = 0.0;
    for i in 0..N {
        for j in 0..N {
            let (u, v) = ((i as f64 + 0.5) / N as f64, (j as f64 + 0.5) / N as f64);
            let du = (p(u + H, v) - p(u - H, v)) / (2.0 * H);
            let dv = (p(u, v + H) - p(u, v - H)) / (2.0 * H);
            sum += du.cross(dv).length();
        }
    }
    sum / (N * N) as f64
}

/// Two unit vectors across an axis.
fn across(axis: DVec3) -> (DVec3, DVec3) {
    let a = axis.normalize_or_zero();
    let e1 = a.any_orthonormal_vector();
    (e1, a.cross(e1))
}

/// The world area of an object's surface (POV-Ray's coordinates, every transform applied), for
/// the shapes a `looks_like` emitter can be: sphere, box, cylinder, cone, disc, torus,
/// triangles, and unions of them (the sum: hidden parts of overlapping children count). `None`
/// for the rest (superellipsoids, patches, equations, the other CSG operations).
pub fn surface_area(o: &Obj) -> Option<f64> {
    let m = &o.xform;
    let tau = 2.0 * PI;
    let disc = |c: DVec3, n: DVec3, r0: f64, r1: f64| {
        let (e1, e2) = across(n);
        parametric_area(m, move |u, v| {
            let r = r0 + (r1 - r0) * u;
            let a = tau * v;
            c + r * (a.cos() * e1 + a.sin() * e2)
        })
    };
    let side = |a: DVec3, ra: f64, b: DVec3, rb: f64| {
        let (e1, e2) = across(b - a);
        parametric_area(m, move |u, v| {
            let r = ra + (rb - ra) * u;
            let t = tau * v;
            a + (b - a) * u + r * (t.cos() * e1 + t.sin() * e2)
        })
    };
    Some(match &o.kind {
        ObjKind::Sphere { center, radius } => parametric_area(m, |u, v| {
            let (th, ph) = (PI * u, tau * v);
            *center + *radius * DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
        }),
        ObjKind::Box { a, b } => {
            // Six parallelograms, exactly.
            let d = *b - *a;
            let e = [
                m.transform_vector3(DVec3::X * d.x),
                m.transform_vector3(DVec3::Y * d.y),
                m.transform_vector3(DVec3::Z * d.z),
            ];
            2.0 * (e[0].cross(e[1]).length() + e[1].cross(e[2]).length() + e[2].cross(e[0]).length())
        }
        ObjKind::Cylinder { a, b, radius, open } => {
            let caps = if *open { 0.0 } else { disc(*a, *b - *a, 0.0, *radius) + disc(*b, *b - *a, 0.0, *radius) };
            side(*a, *radius, *b, *radius) + caps
        }
        ObjKind::Cone { a, ra, b, rb, open } => {
            let caps = if *open { 0.0 } else { disc(*a, *b - *a, 0.0, *ra) + disc(*b, *b - *a, 0.0, *rb) };
            side(*a, *ra, *b, *rb) + caps
        }
        ObjKind::Disc { center, normal, radius, hole } => disc(*center, *normal, *hole, *radius),
        ObjKind::Torus { major, minor } => parametric_area(m, |u, v| {
            let (a, b) = (tau * u, tau * v);
            let r = major + minor * b.cos();
            DVec3::new(r * a.cos(), minor * b.sin(), r * a.sin())
        }),
        ObjKind::Triangles { tris, .. } => tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|p| m.transform_point3(p));
                0.5 * (b - a).cross(c - a).length()
            })
            .sum(),
        ObjKind::Csg { op: CsgOp::Union, children } => {
            let mut sum = 0.0;
            for c in children {
                sum += surface_area(c)?;
            }
            sum
        }
        _ => return None,
    })
}

/// Whether a CSG object's parts hold a disc.
fn holds_disc(o: &Obj) -> bool {
    match &o.kind {
        ObjKind::Disc { .. } => true,
        ObjKind::Csg { children, .. } => children.iter().any(holds_disc),
        _ => false,
    }
}

/// The parts of an intersection, difference or merge with each disc as its plane: POV-Ray's
/// disc is inside on the side opposite its normal, its radius bounding only its surface
/// (disc.cpp, `Disc::Inside`), so within CSG it cuts as `plane { normal, normal . center }`
/// does wherever the disc covers the cut (docs/pov-ray.md).
fn discs_as_planes(o: &Obj) -> Obj {
    let kind = match &o.kind {
        ObjKind::Disc { center, normal, .. } => {
            let n = normal.normalize_or_zero();
            ObjKind::Plane { normal: n, offset: n.dot(*center) }
        }
        ObjKind::Csg { op, children } => {
            ObjKind::Csg { op: *op, children: children.iter().map(discs_as_planes).collect() }
        }
        other => other.clone(),
    };
    Obj { kind, ..o.clone() }
}

/// The first texture in an object's parts.
fn first_tex(o: &Obj) -> Option<&Vec<Tex>> {
    if o.tex.is_some() {
        return o.tex.as_ref();
    }
    match &o.kind {
        ObjKind::Csg { children, .. } => children.iter().find_map(first_tex),
        _ => None,
    }
}

/// The bounds of an object's finite parts in POV-Ray's coordinates (planes and lights left
/// out; empty, min > max, when there are none): each part's own box through its transform.
pub fn bounds_of(o: &Obj) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::MAX);
    let mut hi = DVec3::splat(f64::MIN);
    let mut add_box = |a: DVec3, b: DVec3, m: &DMat4| {
        for i in 0..8 {
            let p = DVec3::new(
                if i & 1 == 0 { a.x } else { b.x },
                if i & 2 == 0 { a.y } else { b.y },
                if i & 4 == 0 { a.z } else { b.z },
            );
            let q = m.transform_point3(p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
    };
    let mut stack = vec![o];
    while let Some(o) = stack.pop() {
        let m = &o.xform;
        match &o.kind {
            ObjKind::Sphere { center, radius } => add_box(*center - *radius, *center + *radius, m),
            ObjKind::Box { a, b } => add_box(*a, *b, m),
            ObjKind::Cylinder { a, b, radius, .. } => add_box(a.min(*b) - *radius, a.max(*b) + *radius, m),
            ObjKind::Cone { a, ra, b, rb, .. } => {
                let r = ra.abs().max(rb.abs());
                add_box(a.min(*b) - r, a.max(*b) + r, m)
            }
            ObjKind::Disc { center, radius, .. } => add_box(*center - *radius, *center + *radius, m),
            ObjKind::Torus { major, minor } => {
                let r = major.abs() + minor.abs();
                add_box(DVec3::new(-r, -minor.abs(), -r), DVec3::new(r, minor.abs(), r), m)
            }
            ObjKind::Superellipsoid { .. } => add_box(DVec3::splat(-1.0), DVec3::ONE, m),
            ObjKind::Triangles { tris, .. } => {
                for t in tris.iter() {
                    for p in t {
                        add_box(*p, *p, m);
                    }
                }
            }
            ObjKind::Patch { points } => {
                for p in points.iter() {
                    add_box(*p, *p, m);
                }
            }
            ObjKind::Csg { children, .. } => stack.extend(children.iter()),
            ObjKind::Implicit { bound, .. } => {
                if let Some((a, b)) = bound {
                    add_box(*a, *b, m);
                }
            }
            ObjKind::Plane { .. } | ObjKind::Light(_) | ObjKind::Unsupported(_) => {}
        }
    }
    (lo, hi)
}

/// Whether the TOML loader would find a triangle of no area: its own test (convert.rs,
/// `is_degenerate`) in f32, with a margin of 2.
fn too_thin(v: &[DVec3]) -> bool {
    let f = |p: DVec3| p.as_vec3();
    let (e0, e1, e2) = (f(v[1]) - f(v[0]), f(v[2]) - f(v[0]), f(v[2]) - f(v[1]));
    let longest = e0.length_squared().max(e1.length_squared()).max(e2.length_squared());
    let twice_area = e0.cross(e1).length();
    !(twice_area.is_finite() && twice_area > 2e-7 * longest)
}

/// A vertex of a tessellated shape to 7 significant digits (the renderer holds f32), which
/// keeps the TOML of a shape of thousands of triangles short.
fn short3(v: DVec3) -> DVec3 {
    let short = |x: f64| format!("{x:.6e}").parse::<f64>().unwrap_or(x);
    DVec3::new(short(v.x), short(v.y), short(v.z))
}

/// The crease angle of POV-Ray's smooth tessellated surfaces (degrees): faces that meet at a
/// sharper angle keep their edge, as the model importer's default `smooth_angle` does.
pub const SMOOTH_CREASE_DEG: f32 = 30.0;

/// A triangle's corner normals `n` (object space) in the scene's space by `normal_matrix`, unit,
/// to 7 digits; `None` (flat) when they all equal the face's normal of the vertices `v` (either
/// side) or one has no direction.
fn smooth_corners(n: &[DVec3; 3], normal_matrix: &DMat3, v: &[DVec3]) -> Option<[DVec3; 3]> {
    let face = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    let moved = n.map(|x| (*normal_matrix * x).normalize_or_zero());
    if moved.iter().any(|x| *x == DVec3::ZERO || !x.is_finite()) {
        return None;
    }
    let flat = moved.iter().all(|x| x.dot(face).abs() > 1.0 - 1e-9);
    (!flat).then(|| moved.map(short3))
}

fn rgb(c: [f64; 3]) -> T {
    T::Array(c.iter().map(|x| num(*x)).collect())
}

/// A linear map as scale, then rotation about x, y, z (degrees), then translation: the TOML
/// `transform` (world_from_object = T Rz Ry Rx S). `None` when the map shears (no such product).
pub fn decompose(m: &DMat4) -> Option<(DVec3, DVec3, DVec3)> {
    let l = DMat3::from_mat4(*m);
    let (c0, c1, c2) = (l.x_axis, l.y_axis, l.z_axis);
    let mut s = DVec3::new(c0.length(), c1.length(), c2.length());
    if s.min_element() <= 1e-300 {
        return None;
    }
    let tol = 1e-6;
    if c0.dot(c1).abs() > tol * s.x * s.y || c0.dot(c2).abs() > tol * s.x * s.z || c1.dot(c2).abs() > tol * s.y * s.z {
        return None;
    }
    let mut r = DMat3::from_cols(c0 / s.x, c1 / s.y, c2 / s.z);
    if r.determinant() < 0.0 {
        s.z = -s.z;
        r.z_axis = -r.z_axis;
    }
    // R = Rz(c) Ry(b) Rx(a): R[2][0] = -sin b, R[2][1] = cos b sin a, R[1][0] = sin c cos b.
    let sb = (-r.x_axis.z).clamp(-1.0, 1.0);
    let b = sb.asin();
    let (a, c) = if sb.abs() < 1.0 - 1e-9 {
        (r.y_axis.z.atan2(r.z_axis.z), r.x_axis.y.atan2(r.x_axis.x))
    } else {
        (0.0, (-r.y_axis.x).atan2(r.y_axis.y))
    };
    let rot = DVec3::new(a, b, c) * 180.0 / PI;
    Some((s, rot, m.w_axis.truncate()))
}

/// The rotation and scale nearest a shearing map (the polar decomposition L = R P, by Higham's
/// iteration R <- (R + R^-T) / 2, with P's diagonal as the scale), the translation kept: how a
/// sheared pattern is approximated, since the scene format's transforms do not shear.
fn unshear(m: &DMat4) -> DMat4 {
    let l = DMat3::from_mat4(*m);
    if l.determinant().abs() <= 1e-300 {
        return *m;
    }
    let mut r = l;
    for _ in 0..30 {
        r = (r + r.inverse().transpose()) * 0.5;
    }
    let p = r.transpose() * l;
    let s = DMat3::from_diagonal(DVec3::new(p.x_axis.x, p.y_axis.y, p.z_axis.z));
    let mut out = DMat4::from_mat3(r * s);
    out.w_axis = m.w_axis;
    out
}

fn transform_table(m: &DMat4, pos: Pos, what: &str) -> Result<Option<T>> {
    if m.abs_diff_eq(DMat4::IDENTITY, 1e-12) {
        return Ok(None);
    }
    let Some((s, r, t)) = decompose(m) else {
        return Err(PovError::at(
            pos,
            format!("this {what}'s transforms shear it (a rotation followed by a non-uniform scale), which Photonix's {what} cannot take yet"),
        ));
    };
    let mut tab = Table::new();
    if !s.abs_diff_eq(DVec3::ONE, 1e-12) {
        tab.insert("scale".into(), vec3(s));
    }
    if !r.abs_diff_eq(DVec3::ZERO, 1e-12) {
        tab.insert("rotate".into(), vec3(r));
    }
    if !t.abs_diff_eq(DVec3::ZERO, 0.0) {
        tab.insert("translate".into(), vec3(t));
    }
    Ok(Some(T::Table(tab)))
}

/// A sky pigment's colour at pattern-space point `q`: a constant, a gradient through its
/// colour map (POV-Ray's value: the distance along the normalised direction, wrapped into
/// [0, 1)), or another pattern's mean colour.
fn sky_colour(p: &super::ast::Pigment, q: DVec3) -> Colour {
    match &p.kind {
        PigmentKind::Pattern { name, map, fields } if name == "gradient" && !map.is_empty() => {
            let dir = fields
                .iter()
                .find(|(k, _)| k == "direction")
                .and_then(|(_, v)| v.as_array())
                .map(|a| {
                    DVec3::new(
                        a.first().and_then(T::as_float).unwrap_or(0.0),
                        a.get(1).and_then(T::as_float).unwrap_or(0.0),
                        a.get(2).and_then(T::as_float).unwrap_or(0.0),
                    )
                })
                .unwrap_or(DVec3::Y)
                .normalize_or(DVec3::Y);
            let v = q.dot(dir).rem_euclid(1.0);
            super::ast::map_eval(map, v)
        }
        _ => p.mean(),
    }
}

struct Emitter<'a> {
    scene: &'a PovScene,
    files: &'a [PathBuf],
    text: String,
    origins: Vec<(usize, Pos)>,
    materials: HashMap<String, String>,
    /// Each written material's mix depth (0 for a material that is no mix) and whether it is a
    /// `null` (which a mix cannot hold).
    material_info: HashMap<String, (u32, bool)>,
    textures: HashMap<String, String>,
    media: HashMap<String, String>,
    gamma: f64,
    /// Where the camera looks (POV-Ray coordinates): lights are matched to POV-Ray there.
    target: DVec3,
    /// The camera's distance to `target`: the size of the scene the lights are judged against.
    view_distance: f64,
    lights: Vec<(Table, Pos)>,
    skipped_triangles: usize,
    warnings: Vec<String>,
    /// Newlines in `text`.
    newlines: usize,
    /// Half the side of the boxes that stand for planes in the CSG object being written.
    plane_box: Option<f64>,
    /// The emission (radiance) of the `looks_like` object being written in its light's place.
    light_emission: Option<[f64; 3]>,
    /// The atmosphere's medium, the medium outside every shape.
    atmosphere: Option<String>,
    /// Writing a hole of a media container (`media_csg`): its media are set there.
    hole: bool,
    /// POV-Ray's coordinates to Photonix's: `MIRROR` for a left-handed camera, else the
    /// identity (`left_handed`).
    flip: DMat4,
}

/// The pattern that weighs a texture map's mixes, and its entries' values (sorted).
struct Weights {
    pattern: String,
    fields: Vec<(String, toml::Value)>,
    values: Vec<f64>,
    /// The entries are a listed pattern's (`colors`), not a map's.
    listed: bool,
    world_from_pattern: DMat4,
    /// Where the pattern was given, and its object.
    ppos: Pos,
    pos: Pos,
}

/// How far the emitter had written (`Emitter::snapshot`).
struct Snapshot {
    text: usize,
    origins: usize,
    newlines: usize,
    materials: usize,
    textures: usize,
}

/// The TOML text; for each entry, its first line and the `.pov` position it came from; warnings.
pub type Emitted = (String, Vec<(usize, Pos)>, Vec<String>);

/// Largest translation, in bytes of TOML (about a million triangles): the TOML loader then
/// holds it and its parsed form at once, within the memory budget (docs/limits.md).
pub const MAX_TRANSLATION_BYTES: usize = 256 << 20;

/// The TOML text and, for each entry, its first line and the `.pov` position it came from.
pub fn emit(scene: &PovScene, options: &PovOptions, files: &[PathBuf]) -> Result<Emitted> {
    let camera = scene.camera.clone().unwrap_or_default();
    let target = view_target(scene, &camera);
    let mut e = Emitter {
        scene,
        files,
        text: String::new(),
        origins: Vec::new(),
        materials: HashMap::new(),
        material_info: HashMap::new(),
        textures: HashMap::new(),
        media: HashMap::new(),
        gamma: scene.assumed_gamma.unwrap_or(1.0),
        target,
        view_distance: (target - camera.location).length(),
        lights: Vec::new(),
        skipped_triangles: 0,
        warnings: Vec::new(),
        newlines: 0,
        plane_box: None,
        light_emission: None,
        atmosphere: None,
        hole: false,
        flip: if left_handed(&camera) { MIRROR } else { DMat4::IDENTITY },
    };
    e.text.push_str("# Translated from POV-Ray by photonix (docs/pov-ray.md); each entry names its source line.\n");
    e.newlines = 1;
    e.camera(&camera, options)?;
    if let Some(depth) = scene.max_trace_level {
        let mut r = Table::new();
        r.insert("max_depth".into(), T::Integer(depth.clamp(1, 1024)));
        e.entry("render", T::Table(r), camera.pos)?;
    }
    if let Some(sky) = &scene.sky_sphere {
        e.sky(sky)?;
    } else if let Some((c, pos)) = scene.background {
        let mut t = Table::new();
        t.insert("type".into(), T::String("uniform".into()));
        t.insert("radiance".into(), rgb(e.linear(c)));
        e.entry("environment", T::Table(t), pos)?;
    }
    if let Some(f) = &scene.fog {
        if f.distance > 0.0 {
            let mut t = Table::new();
            if f.ground {
                t.insert("type".into(), T::String("ground".into()));
                t.insert("fog_offset".into(), num(f.offset));
                t.insert("fog_alt".into(), num(f.alt));
            }
            t.insert("distance".into(), num(f.distance));
            t.insert("color".into(), rgb(e.linear(f.colour)));
            if let Some(turb) = f.turbulence {
                t.insert("turbulence".into(), vec3(turb));
            }
            e.entry("fog", T::Table(t), f.pos)?;
        }
    }
    if let Some(r) = &scene.rainbow {
        e.rainbow(r)?;
    }
    if let Some(md) = &scene.media {
        if scene.fog.as_ref().is_some_and(|f| f.distance > 0.0) {
            let at = e.location(md.pos);
            e.warnings
                .push(format!("{at}: atmospheric media beside a fog is left out (the fog is Photonix's atmosphere)"));
        } else if let Some(name) = e.media(md, 1.0)? {
            e.atmosphere = Some(name.clone());
            let mut t = Table::new();
            t.insert("medium".into(), T::String(name));
            e.entry("atmosphere", T::Table(t), md.pos)?;
        }
    }
    let default_tex = scene.default_tex.clone().map(|t| vec![t]);
    for o in &scene.objects {
        e.object(o, default_tex.as_ref(), None)?;
    }
    for (light, pos) in std::mem::take(&mut e.lights) {
        e.entry("lights", T::Array(vec![T::Table(light)]), pos)?;
    }
    if e.skipped_triangles > 0 {
        e.warnings.push(format!("{} triangles with no area were left out", e.skipped_triangles));
    }
    Ok((e.text, e.origins, e.warnings))
}

impl Emitter<'_> {
    /// A point or direction of POV-Ray's in Photonix's coordinates.
    fn mirror(&self, p: DVec3) -> DVec3 {
        self.flip.transform_point3(p)
    }

    /// Appends one top-level entry (`key` holding `value`), remembering where it came from.
    fn entry(&mut self, key: &str, value: T, pos: Pos) -> Result<()> {
        if self.text.len() > MAX_TRANSLATION_BYTES {
            return Err(PovError::at(
                pos,
                format!(
                    "the scene translates to more than {} of TOML (too many objects or triangles); see docs/limits.md",
                    crate::limits::fmt_bytes(MAX_TRANSLATION_BYTES as u64)
                ),
            ));
        }
        let mut doc = Table::new();
        doc.insert(key.into(), value);
        let text = toml::to_string(&doc).map_err(|e| PovError::at(pos, format!("cannot write this as TOML: {e}")))?;
        self.text.push('\n');
        // Lines so far, counted as the text grows (counting the whole text each time made a
        // scene of many triangles quadratic).
        self.newlines += 1;
        let line = self.newlines + 1;
        self.origins.push((line, pos));
        let path = self.files.get(pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
        self.text.push_str(&format!("# {}:{}:{}\n", crate::limits::printable_message(&path), pos.line, pos.col));
        self.newlines += 1 + text.matches('\n').count();
        self.text.push_str(&text);
        Ok(())
    }

    /// A colour of the file in linear RGB: with `assumed_gamma` g other than 1, colours were
    /// written gamma-encoded (POV-Ray 3.6 and earlier): c^g.
    fn linear(&self, c: Colour) -> [f64; 3] {
        let g = if self.gamma > 0.0 { self.gamma } else { 1.0 };
        [c[0].max(0.0).powf(g), c[1].max(0.0).powf(g), c[2].max(0.0).powf(g)]
    }

    fn camera(&mut self, c: &super::ast::Camera, options: &PovOptions) -> Result<()> {
        let mut t = Table::new();
        let forward = c.direction;
        if forward.length() <= 0.0 || c.up.length() <= 0.0 || c.right.length() <= 0.0 {
            return Err(PovError::at(c.pos, "the camera's direction, right and up must not be zero".into()));
        }
        t.insert("position".into(), vec3(self.mirror(c.location)));
        // One unit ahead stops telling a direction in 32-bit floats far from the origin: the step
        // grows with the distance (to 1% of it), so the direction survives the rounding.
        let step = (c.location.abs().max_element() * 0.01).max(1.0);
        t.insert("look_at".into(), vec3(self.mirror(c.location + forward.normalize() * step)));
        t.insert("up".into(), vec3(self.mirror(c.up)));
        t.insert(
            "resolution".into(),
            T::Array(vec![T::Integer(options.width as i64), T::Integer(options.height as i64)]),
        );
        if c.orthographic {
            t.insert("type".into(), T::String("orthographic".into()));
            // With `angle`, POV-Ray sees as wide as a perspective camera of that angle at the
            // look_at distance (checked with POV-Ray 3.7.0: 30 degrees from 10 units is 5.3
            // units wide, from 20 units 10.6), up keeping its ratio to right.
            let height = match c.ortho_angle {
                Some(a) => {
                    let d = c.look_at.map_or(forward.length(), |at| (at - c.location).length());
                    let width = 2.0 * d * (0.5 * a.to_radians()).tan();
                    width * c.up.length() / c.right.length()
                }
                None => c.up.length(),
            };
            t.insert("view_height".into(), num(height));
        } else {
            // The vertical field of view that up and direction span.
            let fov = 2.0 * (0.5 * c.up.length() / forward.length()).atan();
            t.insert("fov".into(), num(fov.to_degrees()));
        }
        if c.aperture > 0.0 {
            t.insert("aperture".into(), num(c.aperture));
            // POV-Ray's default focal point is the origin.
            t.insert("focal_point".into(), vec3(self.mirror(c.focal_point.unwrap_or(DVec3::ZERO))));
            if c.blur_samples > 0 {
                t.insert("blur_samples".into(), T::Integer(c.blur_samples));
            }
        }
        self.entry("camera", T::Table(t), c.pos)
    }

    fn object(&mut self, o: &Obj, inherited: Option<&Vec<Tex>>, interior: Option<&Interior>) -> Result<()> {
        if matches!(&o.kind, ObjKind::Csg { op, .. } if *op != CsgOp::Union) && holds_disc(o) {
            return self.object(&discs_as_planes(o), inherited, interior);
        }
        let tex = o.tex.as_ref().or(inherited);
        let int = o.interior.as_ref().or(interior);
        if super::implicit::needs_mesher(o) {
            // Equations, blobs and the CSG objects that hold them: triangles of their surface,
            // in the texture of the object (or of its first part that has one).
            let tris = super::implicit::mesh(o).map_err(|(pos, m)| PovError::at(pos, m))?;
            let tex = first_tex(o).or(inherited);
            // POV-Ray shades these surfaces by their equations' normals: smooth, but for the
            // edges CSG makes (sharper than the crease angle).
            let normals = super::tessellate::corner_normals(&tris, SMOOTH_CREASE_DEG);
            let flat = Obj {
                kind: ObjKind::Triangles { tris: std::rc::Rc::new(tris), normals: Some(std::rc::Rc::new(normals)) },
                xform: DMat4::IDENTITY,
                tex: tex.cloned(),
                interior: int.cloned(),
                inverse: false,
                pos: o.pos,
            };
            return self.object(&flat, None, None);
        }
        match &o.kind {
            ObjKind::Unsupported(kind) => Err(PovError::at(o.pos, format!("{kind} is not supported yet"))),
            ObjKind::Light(l) => self.light(l),
            ObjKind::Csg { op: CsgOp::Union, children } => {
                for c in children {
                    self.object(c, tex, int)?;
                }
                Ok(())
            }
            ObjKind::Triangles { tris, normals } => {
                let material = self.material(tex, int, o.pos, true)?;
                let m = self.flip * o.xform;
                // Normals move by the inverse transpose.
                let normal_matrix = DMat3::from_mat4(m).inverse().transpose();
                for (k, t) in tris.iter().enumerate() {
                    let v: Vec<DVec3> = t.iter().map(|p| short3(m.transform_point3(*p))).collect();
                    if too_thin(&v) {
                        self.skipped_triangles += 1;
                        continue;
                    }
                    let mut s = Table::new();
                    s.insert("type".into(), T::String("triangle".into()));
                    s.insert("material".into(), T::String(material.clone()));
                    let corners = normals.as_ref().and_then(|n| n.get(k));
                    if let Some(n) = corners.and_then(|n| smooth_corners(n, &normal_matrix, &v)) {
                        s.insert("normals".into(), T::Array(n.into_iter().map(vec3).collect()));
                    }
                    s.insert("vertices".into(), T::Array(v.into_iter().map(vec3).collect()));
                    self.entry("shapes", T::Array(vec![T::Table(s)]), o.pos)?;
                }
                Ok(())
            }
            ObjKind::Csg { op: op @ (CsgOp::Merge | CsgOp::Difference), children }
                if self.media_container(children, tex, int)? =>
            {
                self.media_csg(*op, children, tex, int.expect("media_container checked the interior"))
            }
            ObjKind::Patch { points } => {
                // A Bezier patch maps to one under any affine map: its control points are baked.
                let material = self.material(tex, int, o.pos, true)?;
                let m = self.flip * o.xform;
                let mut s = Table::new();
                s.insert("type".into(), T::String("bicubic_patch".into()));
                s.insert("material".into(), T::String(material));
                s.insert("points".into(), T::Array(points.iter().map(|p| vec3(m.transform_point3(*p))).collect()));
                self.entry("shapes", T::Array(vec![T::Table(s)]), o.pos)
            }
            _ => {
                let shape = self.shape(o, tex, int)?;
                self.entry("shapes", T::Array(vec![T::Table(shape)]), o.pos)
            }
        }
    }

    /// A shape table: a primitive, or a CSG node with its children inline.
    fn shape(&mut self, o: &Obj, tex: Option<&Vec<Tex>>, int: Option<&Interior>) -> Result<Table> {
        let mut s = Table::new();
        let m = self.flip * o.xform * self.flip;
        let kind = |s: &mut Table, k: &str| {
            s.insert("type".into(), T::String(k.into()));
        };
        match &o.kind {
            ObjKind::Sphere { center, radius } => {
                let l = DMat3::from_mat4(m);
                let scale = l.x_axis.length();
                let uniform = decompose(&m)
                    .is_some_and(|(sc, _, _)| (sc.abs() - DVec3::splat(scale)).abs().max_element() <= 1e-9 * scale);
                if uniform {
                    kind(&mut s, "sphere");
                    s.insert("center".into(), vec3(m.transform_point3(self.mirror(*center))));
                    s.insert("radius".into(), num(radius * scale));
                } else {
                    // An ellipsoid: the round superellipsoid, scaled.
                    kind(&mut s, "superellipsoid");
                    s.insert("exponents".into(), T::Array(vec![num(1.0), num(1.0)]));
                    let local =
                        m * DMat4::from_translation(self.mirror(*center)) * DMat4::from_scale(DVec3::splat(*radius));
                    if let Some(t) = transform_table(&local, o.pos, "sphere")? {
                        s.insert("transform".into(), t);
                    }
                }
            }
            ObjKind::Box { a, b } => {
                kind(&mut s, "box");
                let (p, q) = (self.mirror(*a), self.mirror(*b));
                s.insert("min".into(), vec3(p.min(q)));
                s.insert("max".into(), vec3(p.max(q)));
                if let Some(t) = transform_table(&m, o.pos, "box")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Cylinder { a, b, radius, open } => {
                kind(&mut s, "cylinder");
                s.insert("base".into(), vec3(self.mirror(*a)));
                s.insert("cap".into(), vec3(self.mirror(*b)));
                s.insert("radius".into(), num(*radius));
                if *open {
                    s.insert("open".into(), T::Boolean(true));
                }
                if let Some(t) = transform_table(&m, o.pos, "cylinder")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Cone { a, ra, b, rb, open } => {
                kind(&mut s, "cone");
                s.insert("base".into(), vec3(self.mirror(*a)));
                s.insert("cap".into(), vec3(self.mirror(*b)));
                s.insert("base_radius".into(), num(*ra));
                s.insert("cap_radius".into(), num(*rb));
                if *open {
                    s.insert("open".into(), T::Boolean(true));
                }
                if let Some(t) = transform_table(&m, o.pos, "cone")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Plane { normal, offset } => {
                // Baked exactly: any affine map takes a plane to a plane.
                kind(&mut s, "plane");
                let n = self.mirror(*normal);
                let len = n.length();
                if len <= 0.0 {
                    return Err(PovError::at(o.pos, "the plane's normal is zero".into()));
                }
                let point = m.transform_point3(n / len * *offset);
                let nw = DMat3::from_mat4(m).inverse().transpose() * n;
                let nw = nw.normalize_or_zero();
                s.insert("normal".into(), vec3(nw));
                s.insert("offset".into(), num(nw.dot(point)));
            }
            ObjKind::Disc { center, normal, radius, hole } => {
                kind(&mut s, "disc");
                s.insert("center".into(), vec3(self.mirror(*center)));
                s.insert("normal".into(), vec3(self.mirror(*normal)));
                s.insert("radius".into(), num(*radius));
                if *hole > 0.0 {
                    s.insert("inner_radius".into(), num(*hole));
                }
                if let Some(t) = transform_table(&m, o.pos, "disc")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Torus { major, minor } => {
                kind(&mut s, "torus");
                s.insert("major_radius".into(), num(*major));
                s.insert("minor_radius".into(), num(*minor));
                if let Some(t) = transform_table(&m, o.pos, "torus")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Superellipsoid { e, n } => {
                kind(&mut s, "superellipsoid");
                s.insert("exponents".into(), T::Array(vec![num(*e), num(*n)]));
                if let Some(t) = transform_table(&m, o.pos, "superellipsoid")? {
                    s.insert("transform".into(), t);
                }
            }
            ObjKind::Csg { op: op @ (CsgOp::Intersection | CsgOp::Difference), children }
                if children.iter().any(|c| c.inverse) =>
            {
                return self.inverted_csg(o, *op, children, tex, int);
            }
            ObjKind::Csg { op, children } => {
                kind(&mut s, "csg");
                let name = match op {
                    CsgOp::Union => "union",
                    CsgOp::Merge => "merge",
                    CsgOp::Intersection => "intersection",
                    CsgOp::Difference => "difference",
                };
                s.insert("operation".into(), T::String(name.into()));
                let mut kids = Vec::new();
                // Planes become boxes as large as four times the rest of the outermost CSG
                // object (its bounds' half-diagonal from the origin), computed once per object.
                let outermost = self.plane_box.is_none();
                if outermost {
                    let (lo, hi) = bounds_of(o);
                    let r = if lo.x <= hi.x { lo.abs().max(hi.abs()).length() } else { 1.0 };
                    self.plane_box = Some(4.0 * r.max(1.0));
                }
                let result = self.csg_children(children, tex, int, &mut kids);
                if outermost {
                    self.plane_box = None;
                }
                result?;
                s.insert("children".into(), T::Array(kids));
                return Ok(s);
            }
            ObjKind::Unsupported(kind) => {
                return Err(PovError::at(o.pos, format!("{kind} is not supported yet")));
            }
            ObjKind::Triangles { .. } | ObjKind::Patch { .. } | ObjKind::Light(_) | ObjKind::Implicit { .. } => {
                // `object` writes these; reaching here is a front-end bug, reported, not a panic.
                return Err(PovError::at(o.pos, "internal: this shape cannot be written here".into()));
            }
        }
        // An infinite plane cannot glow (its power would be infinite): POV-Ray's ambient-lit
        // sky planes keep their colour and lose the glow.
        let glow_ok = !matches!(o.kind, ObjKind::Plane { .. });
        let material = self.material(tex, int, o.pos, glow_ok)?;
        s.insert("material".into(), T::String(material));
        if let Some(md) = int.and_then(|i| i.media.first()).filter(|_| !self.hole) {
            self.interior_media(o, md, int.map_or(0, |i| i.media.len()), &mut s)?;
        } else if let Some(md) = int.and_then(|i| self.fade_medium(i, o.pos)).filter(|_| !self.hole) {
            self.interior_media(o, &md, 1, &mut s)?;
        }
        Ok(s)
    }

    /// A glass's `fade_distance` f and `fade_color` c as an absorbing medium inside it. POV-Ray
    /// multiplies the light that crosses a distance d of the inside by c + (1 - c) / (1 +
    /// (d / f)^p); an absorption sigma = -ln((1 + c) / 2) / f per channel gives the same at
    /// d = f (half way to the fade colour), and the exponential Beer-Lambert fall-off
    /// elsewhere. Only on a dielectric (ior > 1) without media of its own.
    fn fade_medium(&self, int: &Interior, pos: Pos) -> Option<Media> {
        if int.ior <= 1.0 || int.fade_distance <= 0.0 || !int.media.is_empty() {
            return None;
        }
        let sigma = int.fade_colour.map(|c| {
            let c = self.linear([c, c, c, 0.0, 0.0])[0].clamp(0.0, 1.0);
            -((1.0 + c) / 2.0).ln() / int.fade_distance
        });
        Some(Media {
            absorption: sigma,
            emission: [0.0; 3],
            scattering: [0.0; 3],
            g: 0.0,
            density: None,
            xform: DMat4::IDENTITY,
            pos,
        })
    }

    /// An object's interior media as the shape's `interior`: on the closed shapes Photonix fills
    /// with a medium, outside CSG (docs/pov-ray.md); elsewhere left out with a warning.
    fn interior_media(&mut self, o: &Obj, md: &Media, count: usize, s: &mut Table) -> Result<()> {
        let closed = match &o.kind {
            ObjKind::Sphere { .. } | ObjKind::Box { .. } | ObjKind::Torus { .. } | ObjKind::Superellipsoid { .. } => {
                true
            }
            ObjKind::Cylinder { open, .. } | ObjKind::Cone { open, .. } => !open,
            ObjKind::Plane { .. } => true,
            _ => false,
        };
        let at = self.location(md.pos);
        if !closed || self.plane_box.is_some() {
            self.warnings.push(format!(
                "{at}: media in this shape is left out (Photonix fills spheres, boxes, tori, superellipsoids, closed cylinders and cones and planes, outside CSG)"
            ));
            return Ok(());
        }
        if count > 1 {
            self.warnings.push(format!("{at}: only the first of this interior's {count} media is kept"));
        }
        let (lo, hi) = bounds_of(o);
        let size = if lo.x <= hi.x { (hi - lo).length() } else { 1.0 };
        if let Some(name) = self.media(md, size)? {
            s.insert("interior".into(), T::String(name));
        }
        Ok(())
    }

    /// Whether a merge or difference is an invisible container of media (`pigment { rgbt 1 }`,
    /// ior 1, `interior { media { ... } }`) whose parts are closed primitives: then
    /// `media_csg` writes it as nested media boundaries instead of a CSG object, which cannot
    /// hold media (docs/limits.md).
    fn media_container(&mut self, children: &[Obj], tex: Option<&Vec<Tex>>, int: Option<&Interior>) -> Result<bool> {
        if int.is_none_or(|i| i.media.is_empty()) || children.is_empty() {
            return Ok(false);
        }
        for c in children {
            let closed = match &c.kind {
                ObjKind::Sphere { .. }
                | ObjKind::Box { .. }
                | ObjKind::Torus { .. }
                | ObjKind::Superellipsoid { .. }
                | ObjKind::Plane { .. } => true,
                ObjKind::Cylinder { open, .. } | ObjKind::Cone { open, .. } => !open,
                _ => false,
            };
            if !closed || c.inverse {
                return Ok(false);
            }
            let ctex = c.tex.as_ref().or(tex);
            let cint = c.interior.as_ref().or(int);
            let m = self.material(ctex, cint, c.pos, false)?;
            if !self.material_info.get(&m).is_some_and(|i| i.1) {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// An invisible container of media made by CSG, as media boundaries (docs/pov-ray.md,
    /// "Media in CSG"): a merge's parts each hold the medium; a difference's first part holds
    /// it and each part taken away is a hole in it, its inside the medium outside (the
    /// atmosphere or vacuum) and its outside the container's medium. Exact where the parts of
    /// a merge do not overlap and the holes lie inside the first part without overlapping.
    fn media_csg(&mut self, op: CsgOp, children: &[Obj], tex: Option<&Vec<Tex>>, int: &Interior) -> Result<()> {
        let mut medium: Option<T> = None;
        for (i, c) in children.iter().enumerate() {
            let ctex = c.tex.as_ref().or(tex);
            let cint = c.interior.as_ref().or(Some(int));
            let hole = op == CsgOp::Difference && i > 0;
            if hole {
                let Some(inside) = medium.clone() else {
                    // The container's medium was left out (it does nothing): so are the holes.
                    break;
                };
                self.hole = true;
                let s = self.shape(c, ctex, cint);
                self.hole = false;
                let mut s = s?;
                let outside = self.atmosphere.clone().unwrap_or_else(|| "vacuum".into());
                s.insert("interior".into(), T::String(outside));
                s.insert("exterior".into(), inside);
                self.entry("shapes", T::Array(vec![T::Table(s)]), c.pos)?;
            } else {
                let s = self.shape(c, ctex, cint)?;
                if i == 0 {
                    medium = s.get("interior").cloned();
                }
                self.entry("shapes", T::Array(vec![T::Table(s)]), c.pos)?;
            }
        }
        Ok(())
    }

    /// The children of a CSG node as shape tables (lights are placed as lights).
    fn csg_children(
        &mut self,
        children: &[Obj],
        tex: Option<&Vec<Tex>>,
        int: Option<&Interior>,
        kids: &mut Vec<T>,
    ) -> Result<()> {
        {
            {
                for c in children {
                    let ctex = c.tex.as_ref().or(tex);
                    let cint = c.interior.as_ref().or(int);
                    match &c.kind {
                        ObjKind::Light(l) => self.light(l)?,
                        ObjKind::Plane { normal, offset } => {
                            // The half-space behind the plane, as a box: y up to the plane in a
                            // frame whose y is the normal.
                            let half = self.plane_box.unwrap_or(1e3);
                            let n = normal.normalize_or_zero();
                            if n == DVec3::ZERO {
                                return Err(PovError::at(c.pos, "the plane's normal is zero".into()));
                            }
                            let u = n.any_orthonormal_vector();
                            let w = u.cross(n);
                            let frame = DMat4::from_cols(
                                u.extend(0.0),
                                n.extend(0.0),
                                w.extend(0.0),
                                // POV-Ray keeps the distance along the unit normal
                                // (`plane { 2 * y, 1 }` is y = 1), as the plane outside CSG does.
                                (n * *offset).extend(1.0),
                            );
                            let b = Obj {
                                kind: ObjKind::Box {
                                    a: DVec3::new(-half, -2.0 * half, -half),
                                    b: DVec3::new(half, 0.0, half),
                                },
                                xform: c.xform * frame,
                                ..c.clone()
                            };
                            kids.push(T::Table(self.shape(&b, ctex, cint)?));
                        }
                        ObjKind::Triangles { .. } | ObjKind::Patch { .. } => {
                            return Err(PovError::at(
                                c.pos,
                                "a triangle, mesh or tessellated shape (lathe, sor, prism, polygon, text, bicubic_patch) inside intersection, difference or merge is not supported yet"
                                    .into(),
                            ))
                        }
                        _ => kids.push(T::Table(self.shape(c, ctex, cint)?)),
                    }
                }
            }
        }
        Ok(())
    }

    /// An intersection or difference with `inverse` children, rewritten without them:
    /// difference { A B } is intersection { A, inverse B }, and intersection { N..., inverse I... }
    /// is difference { intersection { N... }, I... }.
    fn inverted_csg(
        &mut self,
        o: &Obj,
        op: CsgOp,
        children: &[Obj],
        tex: Option<&Vec<Tex>>,
        int: Option<&Interior>,
    ) -> Result<Table> {
        let mut plain = Vec::new();
        let mut inverted = Vec::new();
        for (i, c) in children.iter().enumerate() {
            let inv = c.inverse != (op == CsgOp::Difference && i > 0);
            let mut c = c.clone();
            c.inverse = false;
            if inv {
                inverted.push(c);
            } else {
                plain.push(c);
            }
        }
        if plain.is_empty() {
            return Err(PovError::at(
                o.pos,
                "every part of this CSG is `inverse`: an unbounded solid is not supported".into(),
            ));
        }
        if inverted.is_empty() {
            let all =
                Obj { kind: ObjKind::Csg { op: CsgOp::Intersection, children: plain }, inverse: false, ..o.clone() };
            return self.shape(&all, tex, int);
        }
        let base = if plain.len() == 1 {
            plain.pop().expect("one element")
        } else {
            Obj {
                kind: ObjKind::Csg { op: CsgOp::Intersection, children: plain },
                tex: None,
                interior: None,
                ..o.clone()
            }
        };
        let mut kids = vec![base];
        kids.extend(inverted);
        let rewritten =
            Obj { kind: ObjKind::Csg { op: CsgOp::Difference, children: kids }, inverse: false, ..o.clone() };
        self.shape(&rewritten, tex, int)
    }

    /// The material for a texture and an interior (docs/pov-ray.md, "Finish"), written once
    /// per distinct result.
    fn material(&mut self, tex: Option<&Vec<Tex>>, int: Option<&Interior>, pos: Pos, glow_ok: bool) -> Result<String> {
        let default = self.scene.default_tex.clone();
        let layers = tex.filter(|l| !l.is_empty()).map(|l| layered(l));
        let Some(t) = layers.or(default) else {
            return Err(PovError::at(pos, "internal: no default texture".into()));
        };
        // A light's looks_like object is one emitter: its maps stand in by their mean colours.
        let mixes = self.light_emission.is_none();
        if let Some(map) = t.map.as_ref().filter(|_| mixes) {
            if let Some(name) = self.texture_mix(&t, map, int, pos, glow_ok)? {
                return Ok(name);
            }
        } else if let Some(entries) = t
            .pigment
            .entries
            .as_ref()
            .filter(|e| mixes && e.iter().any(|(_, p)| !matches!(p.kind, PigmentKind::Solid(_))))
        {
            // (Constant colours only: the colour map of the pattern is exact.)
            // A pigment_map: its pigments in the texture's finish and normal, mixed as a
            // texture_map's textures are. texture_mix moves each entry by the texture's and
            // the pigment's transforms; the normal follows the texture only, so it is given
            // the pigment's inverse first.
            let unmove = t.pigment.xform.inverse();
            let normal = t.normal.clone().map(|n| Normal { xform: unmove * n.xform, ..n });
            let entries = entries
                .iter()
                .map(|(v, p)| {
                    let layer = Tex {
                        pigment: p.clone(),
                        finish: t.finish.clone(),
                        normal: normal.clone(),
                        xform: DMat4::IDENTITY,
                        map: None,
                    };
                    (*v, vec![layer])
                })
                .collect();
            // A checker's listed pigments weigh by the pattern's own values, a map's by ramps.
            let listed = matches!(&t.pigment.kind, PigmentKind::Pattern { fields, .. }
                if fields.iter().any(|(k, _)| k == "colors"));
            if let Some(name) = self.texture_mix(&t, &TexMap { entries, listed }, int, pos, glow_ok)? {
                return Ok(name);
            }
        }
        let f = &t.finish;
        let mean = t.pigment.mean();
        let colour = self.linear(mean);
        let transparency = (mean[3] + mean[4]).clamp(0.0, 1.0);
        let ior = int.map_or(1.0, |i| i.ior);
        let mut m = Table::new();
        if mixes && transparency >= 0.98 && ior <= 1.0 && int.is_some_and(|i| !i.media.is_empty()) {
            // POV-Ray's media container (`pigment { rgbt 1 } hollow interior { media ... }`): an
            // invisible boundary.
            m.insert("type".into(), T::String("null".into()));
            return self.write_material(m, pos);
        }
        let bump = match &t.normal {
            Some(n) => Some(self.bump(&t, n)?),
            None => None,
        };
        if let Some(b) = &bump {
            m.insert("bump".into(), b.clone());
        }

        // The base: diffuse, or plastic when the finish has a highlight.
        let reflectance = match &t.pigment.kind {
            PigmentKind::Solid(_) => rgb(colour.map(|c| (c * f.diffuse).clamp(0.0, 1.0))),
            PigmentKind::Pattern { .. } | PigmentKind::Image { .. } => {
                let name = self.pattern_texture(&t, pos)?;
                let mut p = Table::new();
                p.insert("texture".into(), T::String(name));
                p.insert("scale".into(), num(f.diffuse.clamp(0.0, 1.0)));
                T::Table(p)
            }
        };
        if let Some(e) = self.light_emission {
            // A looks_like object in its light's place (docs/pov-ray.md, "Light power"): its
            // colour and bumps, diffuse, glowing with the light's power.
            m.insert("type".into(), T::String("diffuse".into()));
            m.insert("reflectance".into(), reflectance);
            m.insert("emission".into(), rgb(e));
            return self.write_material(m, pos);
        }
        if transparency >= 0.5 && ior > 1.0 {
            m.insert("type".into(), T::String("dielectric".into()));
            m.insert("ior".into(), num(ior));
            return self.write_material(m, pos);
        }
        let glossy = f.phong > 0.0 || f.specular > 0.0;
        if glossy {
            // Blinn-Phong exponent n to GGX alpha: sqrt(2 / (n + 2)) (Walter et al. 2007); POV's
            // phong_size is that exponent, its specular highlight's is 1 / roughness.
            let n = if f.phong > 0.0 { f.phong_size } else { 1.0 / f.roughness.max(1e-4) };
            let alpha = (2.0 / (n.max(0.0) + 2.0)).sqrt().clamp(0.001, 1.0);
            m.insert("type".into(), T::String("plastic".into()));
            m.insert("roughness".into(), num(alpha));
        } else {
            m.insert("type".into(), T::String("diffuse".into()));
        }
        m.insert("reflectance".into(), reflectance);
        let glow = f.emission.iter().any(|e| *e > 0.0) || f.ambient.iter().cloned().fold(0.0, f64::max) > f.diffuse;
        if glow && glow_ok {
            let e = [0, 1, 2]
                .map(|i| colour[i] * (f.emission[i] + if f.ambient[i] > f.diffuse { f.ambient[i] } else { 0.0 }));
            if e.iter().any(|x| *x > 0.0) {
                m.insert("emission".into(), rgb(e));
                // POV-Ray's glow is the same from either side: a sky sphere lights what it holds.
                m.insert("two_sided".into(), T::Boolean(true));
            }
        }
        let reflection = f.reflection.iter().cloned().fold(0.0, f64::max);
        if reflection > 0.02 && transparency >= 0.5 {
            // POV-Ray's glass without an ior (`pigment { rgbf <1, 1, 1, 0.9> } finish {
            // reflection 0.1 }`): mostly let through, unbent, with a reflection. A mix of a
            // mirror over a base with an opacity cannot say it (the renderer takes the opacity
            // of the material a shape names, not of a mix's entries: the sphere came out opaque),
            // so it is a thin pane: Fresnel reflection (about 8% head on, more at grazing
            // angles) and the rest through unbent. The filter's tint is not kept.
            let mut pane = Table::new();
            pane.insert("type".into(), T::String("thin_dielectric".into()));
            if let Some(b) = bump {
                pane.insert("bump".into(), b);
            }
            return self.write_material(pane, pos);
        }
        if reflection > 0.02 {
            // A mirror for the reflected share, mixed over the base by its strength.
            let tint = if f.metallic > 0.0 {
                [0, 1, 2].map(|i| (f.reflection[i] * (1.0 - f.metallic + f.metallic * colour[i])).clamp(0.0, 1.0))
            } else {
                [0, 1, 2].map(|i| (f.reflection[i] / reflection).clamp(0.0, 1.0))
            };
            let mut mirror = Table::new();
            mirror.insert("type".into(), T::String("mirror".into()));
            mirror.insert("tint".into(), rgb(tint));
            if let Some(b) = &bump {
                mirror.insert("bump".into(), b.clone());
            }
            let mirror_name = self.write_material(mirror, pos)?;
            if reflection >= 0.95 {
                return Ok(mirror_name);
            }
            m.remove("emission");
            let base = self.write_material(m, pos)?;
            let mut mix = Table::new();
            mix.insert("type".into(), T::String("mix".into()));
            mix.insert("materials".into(), T::Array(vec![T::String(base), T::String(mirror_name)]));
            mix.insert("weight".into(), num(reflection.clamp(0.0, 1.0)));
            return self.write_material(mix, pos);
        }
        if transparency > 0.02 {
            m.insert("opacity".into(), num(1.0 - transparency));
        }
        self.write_material(m, pos)
    }

    /// A patterned texture's entries (texture_map, or a checker's, brick's or hexagon's
    /// textures) as a tree of `mix` materials whose weights follow the pattern (docs/pov-ray.md,
    /// "Maps"). POV-Ray blends the two entries about the pattern's value v linearly; with the
    /// entries sorted by value p_0 <= ... <= p_(n-1), the node that splits them after entry k
    /// mixes its upper half in with weight clamp((v - p_k) / (p_(k+1) - p_k), 0, 1): for v
    /// between p_j and p_(j+1) every node but the one splitting at j has weight 0 or 1, so the
    /// tree picks entries j and j + 1 and that node blends them as POV-Ray does. A balanced tree
    /// nests ceil(log2 n) deep. `None` where the colour map of the entries' mean colours stands
    /// in: entries that differ only by a constant colour (the same material then, exactly and
    /// without the mix's noise), and, with a warning, a tree deeper than the renderer's mixes
    /// nest or an entry that is a `null` boundary.
    fn texture_mix(
        &mut self,
        t: &Tex,
        map: &TexMap,
        int: Option<&Interior>,
        pos: Pos,
        glow_ok: bool,
    ) -> Result<Option<String>> {
        let PigmentKind::Pattern { name, fields, .. } = &t.pigment.kind else {
            return Ok(None);
        };
        let mut entries: Vec<&(f64, Vec<Tex>)> = map.entries.iter().filter(|(_, l)| !l.is_empty()).collect();
        // Stable: entries at one value keep their order and make a sharp step, as in POV-Ray.
        entries.sort_by(|a, b| a.0.total_cmp(&b.0));
        let Some((_, first)) = entries.first() else { return Ok(None) };
        let plain = |x: &Tex| {
            let c = x.pigment.mean();
            let f = first[0].pigment.mean();
            x.map.is_none()
                && x.normal.is_none()
                && matches!(x.pigment.kind, PigmentKind::Solid(_))
                && x.finish == first[0].finish
                && (c[3] + c[4] - f[3] - f[4]).abs() < 1e-9
        };
        if entries.iter().all(|(_, l)| plain(&l[0])) {
            return Ok(None);
        }

        // The entries' materials: each entry's texture moved with the map's (POV-Ray transforms
        // a texture_map's textures with the map).
        let outer = t.xform * t.pigment.xform;
        let saved = self.snapshot();
        let mut leaves = Vec::with_capacity(entries.len());
        for (_, layers) in &entries {
            let moved: Vec<Tex> = layers.iter().map(|x| Tex { xform: outer * x.xform, ..x.clone() }).collect();
            let m = self.material(Some(&moved), int, pos, glow_ok)?;
            let info = self.material_info.get(&m).copied().unwrap_or((0, false));
            leaves.push((m, info));
        }
        fn depth(leaves: &[(String, (u32, bool))]) -> u32 {
            match leaves {
                [one] => one.1 .0,
                _ => {
                    let (lo, hi) = leaves.split_at(leaves.len().div_ceil(2));
                    1 + depth(lo).max(depth(hi))
                }
            }
        }
        let needed = depth(&leaves);
        let null = leaves.iter().any(|(_, (_, n))| *n);
        if needed > MIX_MAX_DEPTH || null {
            self.restore(saved);
            let at = self.location(t.pigment.pos);
            let why = if null {
                "an entry is an invisible media boundary, which a mix cannot hold".to_string()
            } else {
                format!(
                    "its {} entries need mixes nested {needed} deep and the renderer resolves {MIX_MAX_DEPTH}",
                    entries.len()
                )
            };
            self.warnings.push(format!(
                "{at}: this texture map cannot be mixed ({why}); its entries' mean colours stand in, in the first entry's finish"
            ));
            return Ok(None);
        }

        // The weights: the pattern (its fields and transforms) through a ramp from 0 to 1
        // across the two entries a node splits; a listed pattern's values are its entries' own.
        let weights = Weights {
            pattern: name.clone(),
            fields: fields.clone(),
            values: entries.iter().map(|(v, _)| *v).collect(),
            listed: map.listed,
            world_from_pattern: self.flip * t.xform * t.pigment.xform,
            ppos: t.pigment.pos,
            pos,
        };
        self.mix_range(&leaves, 0, leaves.len(), &weights).map(Some)
    }

    /// The mix of entries `lo..hi` of `leaves` (sorted by value), split in halves (see
    /// `texture_mix`).
    fn mix_range(&mut self, leaves: &[(String, (u32, bool))], lo: usize, hi: usize, w: &Weights) -> Result<String> {
        if hi - lo == 1 {
            return Ok(leaves[lo].0.clone());
        }
        let mid = lo + (hi - lo).div_ceil(2);
        let a = self.mix_range(leaves, lo, mid, w)?;
        let b = self.mix_range(leaves, mid, hi, w)?;
        let (black, white) = ([0.0; 5], [1.0, 1.0, 1.0, 0.0, 0.0]);
        let weight_map: Vec<(f64, Colour)> = if w.listed {
            // `colors`: each entry at its own value; the upper half's weigh 1.
            w.values.iter().enumerate().map(|(i, v)| (*v, if i >= mid { white } else { black })).collect()
        } else {
            vec![(w.values[mid - 1], black), (w.values[mid], white)]
        };
        let kind = PigmentKind::Pattern { name: w.pattern.clone(), map: weight_map, fields: w.fields.clone() };
        let weight = self.world_pattern(&kind, &w.world_from_pattern, w.ppos, w.pos)?;
        let mut mix = Table::new();
        mix.insert("type".into(), T::String("mix".into()));
        mix.insert("materials".into(), T::Array(vec![T::String(a), T::String(b)]));
        let mut tex = Table::new();
        tex.insert("texture".into(), T::String(weight));
        mix.insert("weight".into(), T::Table(tex));
        self.write_material(mix, w.pos)
    }

    /// What `restore` needs to take back the entries written after it.
    fn snapshot(&self) -> Snapshot {
        Snapshot {
            text: self.text.len(),
            origins: self.origins.len(),
            newlines: self.newlines,
            materials: self.materials.len(),
            textures: self.textures.len(),
        }
    }

    /// Takes back the materials and textures written since `s` (named in order: m0, m1, ...).
    fn restore(&mut self, s: Snapshot) {
        self.text.truncate(s.text);
        self.origins.truncate(s.origins);
        self.newlines = s.newlines;
        let later = |name: &str, prefix: char, count: usize| {
            name.strip_prefix(prefix).and_then(|n| n.parse::<usize>().ok()).is_some_and(|n| n >= count)
        };
        self.materials.retain(|_, name| !later(name, 'm', s.materials));
        self.material_info.retain(|name, _| !later(name, 'm', s.materials));
        self.textures.retain(|_, name| !later(name, 't', s.textures));
    }

    fn write_material(&mut self, m: Table, pos: Pos) -> Result<String> {
        let key = toml::to_string(&m).unwrap_or_default();
        if let Some(name) = self.materials.get(&key) {
            return Ok(name.clone());
        }
        let name = format!("m{}", self.materials.len());
        let depth = match (m.get("type").and_then(T::as_str), m.get("materials").and_then(T::as_array)) {
            (Some("mix"), Some(mixed)) => {
                let of = |v: &T| v.as_str().and_then(|n| self.material_info.get(n)).map_or(0, |i| i.0);
                1 + mixed.iter().map(of).max().unwrap_or(0)
            }
            _ => 0,
        };
        let null = m.get("type").and_then(T::as_str) == Some("null");
        self.material_info.insert(name.clone(), (depth, null));
        self.materials.insert(key, name.clone());
        let mut wrap = Table::new();
        wrap.insert(name.clone(), T::Table(m));
        self.entry("materials", T::Table(wrap), pos)?;
        Ok(name)
    }

    /// A pattern texture in world space that follows the object as POV-Ray's does.
    fn pattern_texture(&mut self, t: &Tex, pos: Pos) -> Result<String> {
        // The pattern is evaluated at pattern_from_world(p) in POV-Ray's coordinates:
        // world_from_pattern = mirror * texture transforms * pigment transforms.
        let w = self.flip * t.xform * t.pigment.xform;
        self.world_pattern(&t.pigment.kind, &w, t.pigment.pos, pos)
    }

    /// A world-space pattern texture of a pattern pigment, placed by `world_from_pattern`
    /// (Photonix's coordinates); `ppos` is where the pattern was given, `pos` its object.
    fn world_pattern(&mut self, kind: &PigmentKind, world_from_pattern: &DMat4, ppos: Pos, pos: Pos) -> Result<String> {
        let mut tab = Table::new();
        let (name, map, fields) = match kind {
            PigmentKind::Pattern { name, map, fields } => (name, map, fields),
            PigmentKind::Image { file, projection, once, .. } => {
                // An image_map: an image texture projected in world space; `once` clamps it
                // (its edge texels stretch outward where POV-Ray shows nothing).
                tab.insert("type".into(), T::String("image".into()));
                tab.insert("file".into(), T::String(file.clone()));
                tab.insert("space".into(), T::String("world".into()));
                tab.insert("projection".into(), T::String(projection.to_string()));
                if *once {
                    tab.insert("wrap".into(), T::String("clamp".into()));
                }
                return self.place_texture(tab, world_from_pattern, ppos, pos);
            }
            PigmentKind::Solid(_) => {
                return Err(PovError::at(ppos, "internal: a constant colour is not a pattern".into()));
            }
        };
        tab.insert("type".into(), T::String("pattern".into()));
        tab.insert("pattern".into(), T::String(name.clone()));
        tab.insert("space".into(), T::String("world".into()));
        let listed = fields.iter().any(|(k, _)| k == "colors");
        for (k, v) in fields {
            if k != "colors" {
                tab.insert(k.clone(), v.clone());
            }
        }
        // POV-Ray reads a colour map's entries in any order; ours must be sorted (stable, so
        // equal positions keep their order and make a sharp step).
        let mut map = map.clone();
        map.sort_by(|a, b| a.0.total_cmp(&b.0));
        if !map.is_empty() {
            if listed {
                tab.insert("colors".into(), T::Array(map.iter().map(|(_, c)| rgb(self.linear(*c))).collect()));
            } else {
                tab.insert(
                    "color_map".into(),
                    T::Array(
                        map.iter().map(|(v, c)| T::Array(vec![num(v.clamp(0.0, 1.0)), rgb(self.linear(*c))])).collect(),
                    ),
                );
            }
        }
        self.place_texture(tab, world_from_pattern, ppos, pos)
    }

    /// Writes texture `tab` placed by `world_from_pattern` (once per distinct table); its name.
    fn place_texture(&mut self, mut tab: Table, world_from_pattern: &DMat4, ppos: Pos, pos: Pos) -> Result<String> {
        let placed = match decompose(world_from_pattern) {
            Some(_) => *world_from_pattern,
            None => {
                let at = self.location(ppos);
                self.warnings.push(format!(
                    "{at}: this pattern's transforms shear it (a rotation followed by a non-uniform scale); the nearest rotation and scale stand in"
                ));
                unshear(world_from_pattern)
            }
        };
        if let Some(tr) = transform_table(&placed, ppos, "pattern")? {
            tab.insert("transform".into(), tr);
        }
        let key = toml::to_string(&tab).unwrap_or_default();
        if let Some(n) = self.textures.get(&key) {
            return Ok(n.clone());
        }
        let n = format!("t{}", self.textures.len());
        self.textures.insert(key, n.clone());
        let mut wrap = Table::new();
        wrap.insert(n.clone(), T::Table(tab));
        self.entry("textures", T::Table(wrap), pos)?;
        Ok(n)
    }

    /// A `normal { PATTERN amount }` as a bump map: the pattern (black to white, its value) as
    /// a height of `strength` scene units. POV-Ray tilts the normal by amount x a pattern's
    /// slope in pattern space; `strength` = k x amount x the pattern's scale gives the same tilt
    /// in world space, with k from how POV-Ray perturbs (docs/pov-ray.md, "Normals").
    fn bump(&mut self, t: &Tex, n: &Normal) -> Result<T> {
        let w = self.flip * t.xform * n.xform;
        let scale = DMat3::from_mat4(w).determinant().abs().cbrt();
        let frequency = n
            .fields
            .iter()
            .find(|(k, _)| k == "frequency")
            .and_then(|(_, v)| v.as_float())
            .filter(|f| f.abs() > 1e-6)
            .unwrap_or(1.0);
        let k = match n.pattern.as_str() {
            // POV-Ray adds amount x its vector noise (spread 0.257 a component); the scalar
            // noise's slope here spreads about 0.5 a component.
            "bumps" | "wrinkles" => 0.5,
            // amount x noise^3 x vector noise: about a fifth of bumps' tilt.
            "dents" => 0.1,
            // amount / 10 x sin(2 pi f d) per source against the value's slope pi f / 10 cos(...).
            "ripples" | "waves" => 1.0 / (PI * frequency.abs()),
            // Any other pattern: -5 amount x the value at four points 0.02 away (a tetrahedron's
            // corners), which is amount x 5 x 0.02 x 4/3 times the gradient.
            _ => 0.02 * 5.0 * 4.0 / 3.0,
        };
        let kind = PigmentKind::Pattern { name: n.pattern.clone(), map: Vec::new(), fields: n.fields.clone() };
        let name = self.world_pattern(&kind, &w, n.pos, n.pos)?;
        let strength = (k * n.amount * scale).clamp(-1e6, 1e6);
        let mut b = Table::new();
        b.insert("texture".into(), T::String(name));
        b.insert("scale".into(), num(strength));
        Ok(T::Table(b))
    }

    /// A POV-Ray media as a `[media.NAME]` entry; `size` (scene units) is the container's
    /// size, for the small absorption a glow alone needs. `None` (with a warning) for a media
    /// that does nothing.
    fn media(&mut self, md: &Media, size: f64) -> Result<Option<String>> {
        let mut t = Table::new();
        let mut sa = md.absorption.map(|x| x.max(0.0));
        let ss = md.scattering.map(|x| x.max(0.0));
        let em = md.emission.map(|x| x.max(0.0));
        let mut density_scale = 1.0;
        if let Some(d) = &md.density {
            match &d.kind {
                PigmentKind::Solid(c) | PigmentKind::Image { mean: c, .. } => {
                    density_scale = (c[0] + c[1] + c[2]) / 3.0
                }
                kind => {
                    let w = self.flip * md.xform * d.xform;
                    let name = self.world_pattern(kind, &w, d.pos, md.pos)?;
                    t.insert("density".into(), T::String(name));
                }
            }
        }
        // Photonix's emission needs extinction in its channels (it is estimated at collisions);
        // a glow alone gets an absorption of 0.3 across the container (74% seen through it).
        for i in 0..3 {
            if em[i] > 0.0 && sa[i] + ss[i] <= 0.0 {
                sa[i] = 0.3 / size.max(1e-6);
            }
        }
        let scaled = |v: [f64; 3]| rgb(v.map(|x| (x * density_scale).min(crate::limits::MAX_SCENE_VALUE * 0.5)));
        if sa.iter().chain(ss.iter()).all(|x| *x <= 0.0) || density_scale <= 0.0 {
            let path = self.files.get(md.pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
            self.warnings.push(format!(
                "{}:{}:{}: this media absorbs, scatters and emits nothing; left out",
                crate::limits::printable_message(&path),
                md.pos.line,
                md.pos.col
            ));
            return Ok(None);
        }
        t.insert("sigma_a".into(), scaled(sa));
        t.insert("sigma_s".into(), scaled(ss));
        if em.iter().any(|x| *x > 0.0) {
            t.insert("emission".into(), scaled(em));
        }
        if md.g != 0.0 && ss.iter().any(|x| *x > 0.0) {
            t.insert("phase".into(), T::String("henyey-greenstein".into()));
            t.insert("g".into(), num(md.g.clamp(-0.99, 0.99)));
        }
        let key = toml::to_string(&t).unwrap_or_default();
        if let Some(n) = self.media.get(&key) {
            return Ok(Some(n.clone()));
        }
        let n = format!("md{}", self.media.len());
        self.media.insert(key, n.clone());
        let mut wrap = Table::new();
        wrap.insert(n.clone(), T::Table(t));
        self.entry("media", T::Table(wrap), md.pos)?;
        Ok(Some(n))
    }

    /// `sky_sphere` as a gradient environment: its bottom pigment's colour at each elevation
    /// (every 10 degrees, the mean of 16 directions around), upper pigments mixed in by their
    /// mean colour and opacity (docs/pov-ray.md).
    fn sky(&mut self, sky: &SkySphere) -> Result<()> {
        let Some(bottom) = sky.pigments.first() else {
            return Err(PovError::at(
                sky.pos,
                "this sky_sphere has no pigment; give one: sky_sphere { pigment { ... } }".into(),
            ));
        };
        let pattern_from_world = (sky.xform * bottom.xform).inverse();
        let mut colors = Vec::new();
        let mut elevations = Vec::new();
        for e in 0..=18 {
            let el = (-90.0 + 10.0 * e as f64).to_radians();
            let mut c = [0.0; 5];
            for a in 0..16 {
                let az = (a as f64 + 0.5) * PI / 8.0;
                let d = DVec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin());
                let v = sky_colour(bottom, pattern_from_world.transform_point3(d));
                for i in 0..5 {
                    c[i] += v[i] / 16.0;
                }
            }
            for layer in &sky.pigments[1..] {
                let top = layer.mean();
                let see = (top[3] + top[4]).clamp(0.0, 1.0);
                for i in 0..3 {
                    c[i] = c[i] * see + top[i] * (1.0 - see);
                }
            }
            let lin = self.linear(c);
            let round = |x: f64| (x * 1e4).round() / 1e4;
            colors.push(rgb([0, 1, 2].map(|i| round((lin[i] * sky.emission[i]).clamp(0.0, 1e6)))));
            elevations.push(num(-90.0 + 10.0 * e as f64));
        }
        if !matches!(bottom.kind, PigmentKind::Solid(_))
            && !matches!(&bottom.kind, PigmentKind::Pattern { name, .. } if name == "gradient")
        {
            self.warnings.push(format!(
                "{}: this sky_sphere's pattern is not a gradient; its mean colour stands in",
                self.location(bottom.pos)
            ));
        }
        let mut t = Table::new();
        if colors.windows(2).all(|w| w[0] == w[1]) {
            t.insert("type".into(), T::String("uniform".into()));
            t.insert("radiance".into(), colors.swap_remove(0));
            return self.entry("environment", T::Table(t), sky.pos);
        }
        t.insert("type".into(), T::String("gradient".into()));
        t.insert("colors".into(), T::Array(colors));
        t.insert("elevations".into(), T::Array(elevations));
        self.entry("environment", T::Table(t), sky.pos)
    }

    fn rainbow(&mut self, r: &Rainbow) -> Result<()> {
        let mut t = Table::new();
        t.insert("type".into(), T::String("pov".into()));
        if r.direction.length() <= 0.0 {
            return Err(PovError::at(
                r.pos,
                "the rainbow's direction is zero; give the direction toward its centre".into(),
            ));
        }
        t.insert("direction".into(), vec3(self.mirror(r.direction)));
        t.insert("angle".into(), num(r.angle));
        t.insert("width".into(), num(r.width));
        let mut map = r.map.clone();
        map.sort_by(|a, b| a.0.total_cmp(&b.0));
        if map.len() >= 2 {
            t.insert("colors".into(), T::Array(map.iter().map(|(_, c)| rgb(self.linear(*c))).collect()));
            // POV-Ray's map blends the bow over the sky by its filter and transmit.
            let see = map.iter().map(|(_, c)| (c[3] + c[4]).clamp(0.0, 1.0)).sum::<f64>() / map.len() as f64;
            t.insert("strength".into(), num((1.0 - see).clamp(0.0, 1.0)));
        }
        if let Some(up) = r.up {
            t.insert("up".into(), vec3(self.mirror(up)));
        }
        if let Some(a) = r.arc_angle {
            t.insert("arc_angle".into(), num(a));
        }
        if let Some(a) = r.falloff_angle {
            t.insert("falloff_angle".into(), num(a));
        }
        self.entry("rainbow", T::Table(t), r.pos)
    }

    fn location(&self, pos: Pos) -> String {
        let path = self.files.get(pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
        format!("{}:{}:{}", crate::limits::printable_message(&path), pos.line, pos.col)
    }

    /// A light whose brightness matches POV-Ray's where the camera looks: a POV-Ray light of
    /// colour c lights a white diffuse surface facing it with c; a point light of intensity I at
    /// distance d gives radiance I / (pi d^2) there, so I = pi c d^2 (times POV-Ray's fade).
    fn light(&mut self, l: &Light) -> Result<()> {
        // POV-Ray's negative lights take light away, which no physical light does: refused here,
        // at the light, rather than written as a light of intensity 0.
        if l.colour.iter().any(|c| *c < 0.0) {
            let shown: Vec<String> = l.colour.iter().map(|c| crate::limits::fmt_number(*c)).collect();
            return Err(PovError::at(
                l.pos,
                format!(
                    "this light's colour <{}> is negative; a negative light (POV-Ray's way to take light away) has no physical meaning in Photonix: give 0 or more per channel",
                    shown.join(", ")
                ),
            ));
        }
        let colour = self.linear([l.colour[0], l.colour[1], l.colour[2], 0.0, 0.0]);
        let d = (l.position - self.target).length().max(1e-6);
        let fade = if l.fade_distance > 0.0 && l.fade_power > 0.0 {
            2.0 / (1.0 + (d / l.fade_distance).powf(l.fade_power))
        } else {
            1.0
        };
        let mut intensity = colour.map(|c| PI * c * d * d * fade);
        let limit = crate::limits::MAX_SCENE_VALUE * 0.999;
        let most = intensity.iter().cloned().fold(0.0, f64::max);
        // A point or area light far from the scene (POV-Ray's suns, 10^4 to 10^6 units away) is a
        // distant light of irradiance pi c along its direction to where the camera looks: the
        // same white-surface radiance c as POV-Ray's everywhere in the scene, where a point
        // light's intensity pi c d^2 would hit the number limit and take the other lights'
        // share of the photons. An area light keeps its size as the sun's angular diameter.
        let far = d > FAR_LIGHT_RATIO * self.view_distance.max(1e-9) || most > limit;
        if far && matches!(l.kind, LightKind::Point) && l.looks_like.is_none() {
            let mut t = Table::new();
            t.insert("type".into(), T::String("distant".into()));
            t.insert("direction".into(), vec3(self.mirror(self.target - l.position)));
            t.insert("irradiance".into(), rgb(colour.map(|c| PI * c * fade)));
            if let Some(a) = &l.area {
                let r = 0.5 * a.axis1.length().max(a.axis2.length());
                let diameter = (2.0 * (r / d).atan()).to_degrees();
                if diameter > 1e-6 {
                    t.insert("angular_diameter".into(), num(diameter.min(90.0)));
                }
            }
            // POV-Ray's light is a point: nothing shows where the sun would be.
            if l.area.is_some() {
                t.insert("visible".into(), T::Boolean(false));
            }
            self.lights.push((t, l.pos));
            return Ok(());
        }
        // A spotlight (which a distant light cannot be) far from a large scene can still ask for
        // more than the scene format's number limit: it is dimmed to the limit, with a warning.
        if most > limit {
            intensity = intensity.map(|i| i * limit / most);
            let path = self.files.get(l.pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
            self.warnings.push(format!(
                "{}:{}:{}: this light is {d:.0} units from where the camera looks; its intensity is capped at {limit:.0e} (the image is {:.0}% as bright there as POV-Ray's)",
                crate::limits::printable_message(&path),
                l.pos.line,
                l.pos.col,
                100.0 * limit / most
            ));
        }
        if let Some(shape) = &l.looks_like {
            let at = self.location(shape.pos);
            let area = surface_area(shape).filter(|a| a.is_finite() && *a > 0.0);
            match (&l.kind, area) {
                (LightKind::Point, Some(area)) => {
                    // The object is the light: a Lambertian surface of area A and radiance L
                    // emits pi L A, the point light 4 pi I, so L = 4 I / A. A uniform sphere of
                    // that radiance lights everything outside it exactly as the point at its
                    // centre does (its intensity is pi r^2 L = I in every direction).
                    self.light_emission = Some(intensity.map(|i| 4.0 * i / area));
                    let written = self.object(shape, None, None);
                    self.light_emission = None;
                    written?;
                    if l.area.is_some() {
                        self.warnings.push(format!(
                            "{at}: the looks_like object is this area light's emitter; the area_light's array is not used"
                        ));
                    }
                    return Ok(());
                }
                (LightKind::Point, None) => self.warnings.push(format!(
                    "{at}: looks_like is left out: this object's area cannot be computed to make it the light (spheres, boxes, cylinders, cones, discs, tori, meshes and their unions can); the light is invisible"
                )),
                _ => self.warnings.push(format!(
                    "{at}: looks_like on a spotlight or parallel light is left out (an emitting object cannot shine into a cone or along one direction); the light is invisible"
                )),
            }
        }
        let mut t = Table::new();
        match &l.kind {
            LightKind::Parallel { point_at } => {
                t.insert("type".into(), T::String("distant".into()));
                let dir = self.mirror(*point_at - l.position);
                if dir.length() <= 0.0 {
                    return Err(PovError::at(l.pos, "a parallel light needs point_at away from its position".into()));
                }
                t.insert("direction".into(), vec3(dir));
                t.insert("irradiance".into(), rgb(colour.map(|c| PI * c)));
            }
            LightKind::Spot { point_at, radius, falloff, tightness } => {
                t.insert("type".into(), T::String("spot".into()));
                t.insert("position".into(), vec3(self.mirror(l.position)));
                t.insert("point_at".into(), vec3(self.mirror(*point_at)));
                t.insert("intensity".into(), rgb(intensity));
                let falloff = falloff.clamp(1e-3, 90.0);
                t.insert("radius".into(), num(radius.clamp(0.0, falloff)));
                t.insert("falloff".into(), num(falloff));
                // What equals the format's default (scene::kinds) is left out.
                if *tightness > kinds::TIGHTNESS.number() {
                    t.insert("tightness".into(), num(tightness.min(1000.0)));
                }
            }
            LightKind::Point => match &l.area {
                Some(a) => {
                    // A sphere as wide as the larger side of POV-Ray's light array: the same
                    // intensity I = pi r^2 L in every direction.
                    let r = 0.5 * a.axis1.length().max(a.axis2.length()).max(1e-6);
                    t.insert("type".into(), T::String("area".into()));
                    t.insert("shape".into(), T::String("sphere".into()));
                    t.insert("center".into(), vec3(self.mirror(l.position)));
                    t.insert("radius".into(), num(r));
                    t.insert("radiance".into(), rgb(intensity.map(|i| i / (PI * r * r))));
                    t.insert("samples".into(), T::Array(vec![T::Integer(a.n1 as i64), T::Integer(a.n2 as i64)]));
                    if a.jitter != kinds::JITTER.flag() {
                        t.insert("jitter".into(), T::Boolean(a.jitter));
                    }
                    if a.adaptive > 0 && a.n1 * a.n2 >= 2 {
                        t.insert("adaptive".into(), T::Integer(a.adaptive as i64));
                    }
                }
                None => {
                    t.insert("type".into(), T::String("point".into()));
                    t.insert("position".into(), vec3(self.mirror(l.position)));
                    t.insert("intensity".into(), rgb(intensity));
                }
            },
        }
        self.lights.push((t, l.pos));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decompose_recomposes_scale_rotation_translation() {
        let m = DMat4::from_translation(DVec3::new(1.0, -2.0, 3.0))
            * DMat4::from_rotation_z(0.4)
            * DMat4::from_rotation_y(-1.1)
            * DMat4::from_rotation_x(2.0)
            * DMat4::from_scale(DVec3::new(2.0, 0.5, -3.0));
        let (s, r, t) = decompose(&m).unwrap();
        let back = DMat4::from_translation(t)
            * DMat4::from_rotation_z(r.z.to_radians())
            * DMat4::from_rotation_y(r.y.to_radians())
            * DMat4::from_rotation_x(r.x.to_radians())
            * DMat4::from_scale(s);
        assert!(back.abs_diff_eq(m, 1e-9), "{back:?} vs {m:?}");
        // A shear has no such decomposition.
        let shear = DMat4::from_scale(DVec3::new(2.0, 1.0, 1.0)) * DMat4::from_rotation_z(0.5);
        assert!(decompose(&shear).is_none());
    }
}
