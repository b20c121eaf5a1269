//! The scene's statements: camera, lights, objects and their modifiers, textures (pigment,
//! finish, interior), background, fog and global settings, read into `ast` values.

use glam::{DMat4, DVec3, DVec4};

use super::ast::{
    AreaLight, Camera, Colour, CsgOp, Finish, Fog, Interior, Light, LightKind, Media, Normal, Obj, ObjKind, Pigment,
    PigmentKind, Rainbow, SkySphere, Tex, TexMap,
};
use super::implicit::{self, BlobComp, Implicit};
use super::lexer::Tok;
use super::parser::{describe, rotation, Parser, PovArray, Result, Value, MAX_ARRAY};
use super::tessellate::{self, FillRule, Spline, Tri};
use super::ttf;
use super::{Pos, PovError};

/// Objects POV-Ray has and this front-end does not read yet.
const UNSUPPORTED_OBJECTS: &[&str] =
    &["isosurface", "parametric", "julia_fractal", "polynomial", "sphere_sweep", "ovus", "lemon"];

const OBJECTS: &[&str] = &[
    "sphere",
    "box",
    "cylinder",
    "cone",
    "plane",
    "disc",
    "torus",
    "superellipsoid",
    "triangle",
    "smooth_triangle",
    "mesh",
    "mesh2",
    "lathe",
    "sor",
    "prism",
    "polygon",
    "bicubic_patch",
    "text",
    "quadric",
    "cubic",
    "quartic",
    "poly",
    "blob",
    "height_field",
    "union",
    "merge",
    "intersection",
    "difference",
    "object",
];

/// Patterns Photonix has (docs/patterns.md), by POV-Ray's name.
const PATTERNS: &[&str] = crate::scene::pattern::PATTERN_NAMES;

/// POV-Ray patterns this front-end does not have: their mean colour stands in, with a warning.
const OTHER_PATTERNS: [&str; 23] = [
    "spiral1",
    "spiral2",
    "cells",
    "planar",
    "spherical",
    "cylindrical",
    "boxed",
    "quilted",
    "facets",
    "tiling",
    "pavement",
    "julia",
    "mandel",
    "magnet",
    "object",
    "slope",
    "aoi",
    "average",
    "density_file",
    "image_map",
    "image_pattern",
    "cubic",
    "function",
];

/// A mesh's triangles, their corners' normals when it is shaded smooth, and each triangle's
/// own texture (an index into `textures`; `None` takes the mesh's texture).
struct MeshTris {
    tris: Vec<[DVec3; 3]>,
    normals: Option<Vec<[DVec3; 3]>>,
    tex_of: Vec<Option<usize>>,
    textures: Vec<Vec<Tex>>,
}

impl MeshTris {
    /// The mesh as one object kind: its triangles, or, when triangles have textures of their
    /// own, a union of one set of triangles per texture (in the order first used; those
    /// without one take the mesh's texture, as the union's parts do).
    fn into_kind(self, pos: Pos) -> ObjKind {
        let MeshTris { tris, normals, tex_of, textures } = self;
        if tex_of.iter().all(Option::is_none) {
            return ObjKind::Triangles { tris: std::rc::Rc::new(tris), normals: normals.map(std::rc::Rc::new) };
        }
        let mut order: Vec<Option<usize>> = Vec::new();
        for t in &tex_of {
            if !order.contains(t) {
                order.push(*t);
            }
        }
        let children = order
            .into_iter()
            .map(|key| {
                let picked: Vec<usize> = (0..tris.len()).filter(|&k| tex_of[k] == key).collect();
                let group_tris = picked.iter().map(|&k| tris[k]).collect();
                let group_normals = normals.as_ref().map(|n| std::rc::Rc::new(picked.iter().map(|&k| n[k]).collect()));
                Obj {
                    kind: ObjKind::Triangles { tris: std::rc::Rc::new(group_tris), normals: group_normals },
                    xform: DMat4::IDENTITY,
                    tex: key.map(|i| textures[i].clone()),
                    interior: None,
                    inverse: false,
                    pos,
                }
            })
            .collect();
        ObjKind::Csg { op: CsgOp::Union, children }
    }
}

fn num(v: f64) -> toml::Value {
    toml::Value::Float(v)
}

/// Sets a pattern field, replacing an earlier value of the same name.
fn set_field(fields: &mut Vec<(String, toml::Value)>, name: &str, v: toml::Value) {
    fields.retain(|(k, _)| k != name);
    fields.push((name.into(), v));
}

impl Parser {
    /// One statement of the scene at the top level.
    pub fn statement(&mut self) -> Result<()> {
        let t = self.expect_any("a statement")?;
        let pos = t.pos;
        let word = match t.tok {
            Tok::Word(w) => w,
            Tok::Sym(";") => return Ok(()),
            other => {
                return self.err(pos, format!("expected an object or a statement here, found {}", describe(&other)))
            }
        };
        match word.as_str() {
            "camera" => {
                let c = self.camera(pos)?;
                self.scene.camera = Some(c);
            }
            "background" => {
                self.expect_sym("{")?;
                let c = self.colour()?;
                self.expect_sym("}")?;
                self.scene.background = Some((c, pos));
            }
            "fog" => {
                let f = self.fog(pos)?;
                self.scene.fog = Some(f);
            }
            "global_settings" => self.global_settings()?,
            // `default { ... }` without `#`, as POV-Ray also reads it.
            "default" => self.default_block()?,
            "sky_sphere" => {
                let sky = self.sky_sphere(pos)?;
                self.scene.sky_sphere = Some(sky);
            }
            "rainbow" => {
                let r = self.rainbow(pos)?;
                self.scene.rainbow = Some(r);
            }
            "media" => {
                let m = self.media(pos)?;
                if self.scene.media.is_some() {
                    self.scene.warnings.push(format!(
                        "{}: a second atmospheric media is left out (Photonix has one atmosphere)",
                        self.loc(pos)
                    ));
                } else {
                    self.scene.media = Some(m);
                }
            }
            w if OBJECTS.contains(&w) || w == "light_source" || UNSUPPORTED_OBJECTS.contains(&w) => {
                let o = self.object(w, pos)?;
                self.count_scene_object(&o)?;
                self.scene.objects.push(o);
            }
            other => {
                return self.err(pos, format!("expected an object or a statement here, found `{other}`"));
            }
        }
        Ok(())
    }

    pub fn loc(&self, pos: Pos) -> String {
        let path = self.files.get(pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
        format!("{path}:{}:{}", pos.line, pos.col)
    }

    /// Skips `{ ... }`, nested blocks included (directives in it still run).
    pub fn skip_block(&mut self) -> Result<()> {
        self.expect_sym("{")?;
        self.skip_to_brace()
    }

    /// A value that starts with a keyword (an object, a texture, ...), or `None` for an
    /// expression.
    pub fn block_value(&mut self, w: &str) -> Result<Option<Value>> {
        let Some(t) = self.peek()? else { return Ok(None) };
        let pos = t.pos;
        let v = match w {
            _ if OBJECTS.contains(&w) || w == "light_source" || UNSUPPORTED_OBJECTS.contains(&w) => {
                self.next()?;
                Value::Object(Box::new(self.object(w, pos)?))
            }
            "texture" => {
                self.next()?;
                let mut layers = self.texture()?;
                // `#declare T = texture { ... } texture { ... }`: layers, bottom first.
                while matches!(self.peek_raw()?, Some(t) if t.tok == Tok::Word("texture".into())) {
                    self.next()?;
                    layers.extend(self.texture()?);
                }
                Value::Texture(layers)
            }
            "pigment" => {
                self.next()?;
                Value::Pigment(self.pigment(pos)?)
            }
            "finish" => {
                self.next()?;
                Value::Finish(self.finish()?)
            }
            "interior" => {
                self.next()?;
                Value::Interior(self.interior()?)
            }
            "material" => {
                self.next()?;
                let (t, i) = self.material()?;
                Value::Material(t, i)
            }
            "camera" => {
                self.next()?;
                Value::Camera(Box::new(self.camera(pos)?))
            }
            "color_map" | "colour_map" => {
                self.next()?;
                Value::ColorMap(self.colour_map()?)
            }
            "transform" => {
                self.next()?;
                Value::Transform(self.transform_block()?)
            }
            "array" => {
                self.next()?;
                self.array(pos)?
            }
            "function" => {
                // Declared, not evaluated: calling it is the error (functions.inc declares dozens).
                self.next()?;
                if self.accept_sym("(")? {
                    while !self.accept_sym(")")? {
                        self.expect_any("`)`")?;
                    }
                }
                self.skip_block()?;
                Value::Other("a function")
            }
            "normal" => {
                self.next()?;
                match self.normal(pos)? {
                    Some(n) => Value::Normal(Box::new(n)),
                    None => Value::Other("a normal"),
                }
            }
            "media" => {
                self.next()?;
                Value::Media(Box::new(self.media(pos)?))
            }
            "sky_sphere" => {
                self.next()?;
                Value::Sky(Box::new(self.sky_sphere(pos)?))
            }
            "density" => {
                // A density is a pigment body (its colour map a density map).
                self.next()?;
                self.expect_sym("{")?;
                Value::Pigment(self.pigment_body(pos, "}")?)
            }
            "pigment_map" | "normal_map" | "texture_map" | "slope_map" | "rainbow" | "spline" | "interior_texture"
            | "fog" | "photons" | "radiosity" | "warp" => {
                self.next()?;
                self.skip_block()?;
                Value::Other(match w {
                    "spline" => "a spline",
                    _ => "a block this front-end does not read",
                })
            }
            _ => return Ok(None),
        };
        Ok(Some(v))
    }

    fn array(&mut self, pos: Pos) -> Result<Value> {
        let mut dims = Vec::new();
        while self.accept_sym("[")? {
            let n = self.float()?;
            self.expect_sym("]")?;
            if n.is_nan() || n < 1.0 || n > MAX_ARRAY as f64 {
                return self.err(
                    pos,
                    format!("an array dimension must be 1 to {MAX_ARRAY}, not {}", crate::limits::fmt_number(n)),
                );
            }
            dims.push(n as usize);
        }
        if dims.is_empty() {
            return self.err(pos, "give the array's size: array[N] or array[N][M]".into());
        }
        let total: usize = dims.iter().try_fold(1usize, |a, d| a.checked_mul(*d)).unwrap_or(usize::MAX);
        if total > MAX_ARRAY {
            return self.err(pos, format!("the array has more than {MAX_ARRAY} elements"));
        }
        self.charge(total, pos)?;
        // The slots are allocated before the value is measured and stored: they must fit the
        // language's memory now (4 million slots take about 1 GB).
        self.check_allocation(total.saturating_mul(std::mem::size_of::<Option<Value>>()), pos)?;
        let mut items: Vec<Option<Value>> = vec![None; total];
        if self.accept_sym("{")? {
            // Nested braces initialise a multi-dimensional array in row order.
            let mut i = 0;
            let mut depth = 1;
            while depth > 0 {
                if self.accept_sym("{")? {
                    depth += 1;
                    continue;
                }
                if self.accept_sym("}")? {
                    depth -= 1;
                    self.accept_sym(",")?;
                    continue;
                }
                let v = self.rvalue()?;
                if i >= total {
                    return self.err(pos, format!("the array's initialiser has more than its {total} elements"));
                }
                items[i] = Some(v);
                i += 1;
                self.accept_sym(",")?;
            }
        }
        Ok(Value::Array(Box::new(PovArray { dims, items })))
    }

    // -------------------------------------------------------------------------------------------
    // Objects

    /// An object, refused past the limits of `measure` (an object declared from itself in a
    /// loop doubles or deepens with each turn).
    fn object(&mut self, kind: &str, pos: Pos) -> Result<Obj> {
        let o = self.object_unchecked(kind, pos)?;
        self.check_object(&o)?;
        Ok(o)
    }

    fn object_unchecked(&mut self, kind: &str, pos: Pos) -> Result<Obj> {
        if UNSUPPORTED_OBJECTS.contains(&kind) {
            // Read past it: the standard includes declare shapes (quadrics, text) that scenes
            // rarely place; placing one is the error (`emit`).
            self.skip_block()?;
            let kind =
                ObjKind::Unsupported(UNSUPPORTED_OBJECTS.iter().find(|k| **k == kind).copied().unwrap_or("object"));
            return Ok(Obj { kind, xform: DMat4::IDENTITY, tex: None, interior: None, inverse: false, pos });
        }
        if kind == "light_source" {
            let l = self.light(pos)?;
            return Ok(Obj {
                kind: ObjKind::Light(Box::new(l)),
                xform: DMat4::IDENTITY,
                tex: None,
                interior: None,
                inverse: false,
                pos,
            });
        }
        self.expect_sym("{")?;
        let mut open = false;
        let body = match kind {
            "sphere" => {
                let center = self.vec3()?;
                self.accept_sym(",")?;
                ObjKind::Sphere { center, radius: self.float()? }
            }
            "height_field" => ObjKind::Triangles { tris: std::rc::Rc::new(self.height_field(pos)?), normals: None },
            "box" => {
                let a = self.vec3()?;
                self.accept_sym(",")?;
                let b = self.vec3()?;
                ObjKind::Box { a: a.min(b), b: a.max(b) }
            }
            "cylinder" => {
                let a = self.vec3()?;
                self.accept_sym(",")?;
                let b = self.vec3()?;
                self.accept_sym(",")?;
                ObjKind::Cylinder { a, b, radius: self.float()?, open: false }
            }
            "cone" => {
                let a = self.vec3()?;
                self.accept_sym(",")?;
                let ra = self.float()?;
                self.accept_sym(",")?;
                let b = self.vec3()?;
                self.accept_sym(",")?;
                ObjKind::Cone { a, ra, b, rb: self.float()?, open: false }
            }
            "plane" => {
                let normal = self.vec3()?;
                self.accept_sym(",")?;
                ObjKind::Plane { normal, offset: self.float()? }
            }
            "disc" => {
                let center = self.vec3()?;
                self.accept_sym(",")?;
                let normal = self.vec3()?;
                self.accept_sym(",")?;
                let radius = self.float()?;
                let hole = if self.accept_sym(",")? { self.float()? } else { 0.0 };
                ObjKind::Disc { center, normal, radius, hole }
            }
            "torus" => {
                let major = self.float()?;
                self.accept_sym(",")?;
                ObjKind::Torus { major, minor: self.float()? }
            }
            "superellipsoid" => {
                let v = self.vector(2)?;
                ObjKind::Superellipsoid { e: v[0], n: v[1] }
            }
            "triangle" => {
                let a = self.vec3()?;
                self.accept_sym(",")?;
                let b = self.vec3()?;
                self.accept_sym(",")?;
                let c = self.vec3()?;
                ObjKind::Triangles { tris: std::rc::Rc::new(vec![[a, b, c]]), normals: None }
            }
            "smooth_triangle" => {
                let (t, n) = self.smooth_triangle()?;
                ObjKind::Triangles { tris: std::rc::Rc::new(vec![t]), normals: Some(std::rc::Rc::new(vec![n])) }
            }
            "mesh" | "mesh2" => {
                let mesh = if kind == "mesh" { self.mesh(pos)? } else { self.mesh2(pos)? };
                mesh.into_kind(pos)
            }
            "lathe" | "sor" | "prism" | "polygon" | "text" => {
                let (tris, smooth) = self.tessellated(kind, pos, &mut open)?;
                if tris.len() > tessellate::MAX_TRIANGLES {
                    return self.err(
                        pos,
                        format!(
                            "this {kind} makes {} triangles; at most {} are taken",
                            tris.len(),
                            tessellate::MAX_TRIANGLES
                        ),
                    );
                }
                // POV-Ray's lathes, sors, spline prisms and glyphs are curved surfaces, shaded
                // smooth but where their profiles turn sharply.
                let normals = smooth.then(|| tessellate::corner_normals(&tris, super::emit::SMOOTH_CREASE_DEG));
                ObjKind::Triangles { tris: std::rc::Rc::new(tris), normals: normals.map(std::rc::Rc::new) }
            }
            "bicubic_patch" => ObjKind::Patch { points: Box::new(self.bicubic_patch(pos)?) },
            "quadric" | "cubic" | "quartic" | "poly" => {
                let shape = self.polynomial(kind, pos)?;
                ObjKind::Implicit { shape: std::rc::Rc::new(shape), bound: None }
            }
            "blob" => {
                let shape = self.blob(pos)?;
                let bound = shape.blob_bounds();
                ObjKind::Implicit { shape: std::rc::Rc::new(shape), bound }
            }
            "union" | "merge" | "intersection" | "difference" => {
                let op = match kind {
                    "union" => CsgOp::Union,
                    "merge" => CsgOp::Merge,
                    "intersection" => CsgOp::Intersection,
                    _ => CsgOp::Difference,
                };
                ObjKind::Csg { op, children: Vec::new() }
            }
            _ => {
                // object { Ident modifiers } or object { sphere { ... } modifiers }
                let t = self.expect_any("an object")?;
                let inner = match &t.tok {
                    Tok::Word(w) if OBJECTS.contains(&w.as_str()) || UNSUPPORTED_OBJECTS.contains(&w.as_str()) => {
                        self.object(w, t.pos)?
                    }
                    Tok::Word(w) if w == "light_source" => self.object(w, t.pos)?,
                    Tok::Word(w) => match self.lookup(w).cloned().map(|v| self.postfix(v)).transpose()? {
                        Some(Value::Object(o)) => *o,
                        Some(other) => {
                            return self.err(t.pos, format!("`{w}` is {}, not an object", other.kind()));
                        }
                        None => return self.err(t.pos, format!("unknown object `{w}` (not declared)")),
                    },
                    other => return self.err(t.pos, format!("expected an object here, found {}", describe(other))),
                };
                let mut o = inner;
                self.modifiers(&mut o, &mut open)?;
                return Ok(o);
            }
        };
        let mut o = Obj { kind: body, xform: DMat4::IDENTITY, tex: None, interior: None, inverse: false, pos };
        self.modifiers(&mut o, &mut open)?;
        match &mut o.kind {
            ObjKind::Cylinder { open: o_, .. } | ObjKind::Cone { open: o_, .. } => *o_ = open,
            _ => {}
        }
        Ok(o)
    }

    /// `smooth_triangle { p0, n0, p1, n1, p2, n2 }`: the points and their normals.
    fn smooth_triangle(&mut self) -> Result<([DVec3; 3], [DVec3; 3])> {
        let (mut p, mut n) = ([DVec3::ZERO; 3], [DVec3::ZERO; 3]);
        for i in 0..3 {
            if i > 0 {
                self.accept_sym(",")?;
            }
            p[i] = self.vec3()?;
            self.accept_sym(",")?;
            n[i] = self.vec3()?;
        }
        Ok((p, n))
    }

    /// A mesh's triangles, and their corner normals when any is a smooth_triangle (a flat one's
    /// corners take its face normal).
    fn mesh(&mut self, pos: Pos) -> Result<MeshTris> {
        let mut tris = Vec::new();
        let mut normals: Vec<[DVec3; 3]> = Vec::new();
        let mut smooth = false;
        // The textures met so far, and each one's Debug text, the key that finds it again.
        let (mut tex_of, mut textures, mut keys) = (Vec::new(), Vec::new(), Vec::new());
        loop {
            match self.peek_word()?.as_deref() {
                Some("triangle") => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let a = self.vec3()?;
                    self.accept_sym(",")?;
                    let b = self.vec3()?;
                    self.accept_sym(",")?;
                    let c = self.vec3()?;
                    tex_of.push(self.triangle_tail(&mut textures, &mut keys)?);
                    tris.push([a, b, c]);
                    normals.push([(b - a).cross(c - a); 3]);
                }
                Some("smooth_triangle") => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let (t, n) = self.smooth_triangle()?;
                    tex_of.push(self.triangle_tail(&mut textures, &mut keys)?);
                    tris.push(t);
                    normals.push(n);
                    smooth = true;
                }
                Some("inside_vector") => {
                    self.next()?;
                    self.vec3()?;
                }
                Some("hierarchy") => {
                    self.next()?;
                    self.float()?;
                }
                _ => break,
            }
        }
        if tris.is_empty() {
            return self.err(pos, "this mesh has no triangles".into());
        }
        Ok(MeshTris { tris, normals: smooth.then_some(normals), tex_of, textures })
    }

    /// A count before a list of points: a whole number from `min` to `max`.
    fn count(&mut self, what: &str, min: usize, max: usize) -> Result<usize> {
        let pos = self.here();
        // `4 <1, 0>`: the count, then the first point (not a comparison).
        self.stop_at_less = true;
        let n = self.float();
        self.stop_at_less = false;
        let n = n?;
        if !(n >= min as f64 && n <= max as f64) {
            return self.err(pos, format!("{what} must be {min} to {max}, not {}", crate::limits::fmt_number(n)));
        }
        Ok(n as usize)
    }

    fn points2(&mut self, n: usize) -> Result<Vec<glam::DVec2>> {
        let mut v = Vec::with_capacity(n);
        for _ in 0..n {
            self.accept_sym(",")?;
            let p = self.vector(2)?;
            v.push(glam::DVec2::new(p[0], p[1]));
        }
        Ok(v)
    }

    fn spline_word(&mut self) -> Result<Option<Spline>> {
        let s = match self.peek_word()?.as_deref() {
            Some("linear_spline") => Spline::Linear,
            Some("quadratic_spline") => Spline::Quadratic,
            Some("cubic_spline") => Spline::Cubic,
            Some("bezier_spline") => Spline::Bezier,
            _ => return Ok(None),
        };
        self.next()?;
        Ok(Some(s))
    }

    /// `open` and `sturm` right after a shape's points (`open` is also read with the modifiers).
    fn open_sturm(&mut self, open: &mut bool) -> Result<()> {
        loop {
            if self.accept_word("open")? {
                *open = true;
            } else if !self.accept_word("sturm")? {
                return Ok(());
            }
        }
    }

    /// lathe, sor, prism, polygon and text, tessellated (`tessellate.rs`; docs/pov-ray.md gives
    /// the tolerance), in the shape's own coordinates.
    /// The triangles of a lathe, sor, prism, polygon or text, and whether POV-Ray shades the
    /// surface smooth (a curved one: not a polygon or a prism of straight sides).
    fn tessellated(&mut self, kind: &str, pos: Pos, open: &mut bool) -> Result<(Vec<Tri>, bool)> {
        const MAX_POINTS: usize = 1 << 20;
        match kind {
            "lathe" => {
                let spline = self.spline_word()?.unwrap_or(Spline::Linear);
                let n = self.count("a lathe's number of points", 2, MAX_POINTS)?;
                let p = self.points2(n)?;
                let ok = match spline {
                    Spline::Linear => n >= 2,
                    Spline::Quadratic => n >= 3,
                    Spline::Cubic => n >= 4,
                    Spline::Bezier => n % 4 == 0,
                };
                if !ok {
                    return self.err(
                        pos,
                        format!(
                            "a lathe with {} needs {}, not {n} points",
                            spline.name(),
                            match spline {
                                Spline::Linear => "at least 2",
                                Spline::Quadratic => "at least 3",
                                Spline::Cubic => "at least 4",
                                Spline::Bezier => "four per segment",
                            }
                        ),
                    );
                }
                self.open_sturm(open)?;
                Ok((tessellate::lathe(spline, &p), true))
            }
            "sor" => {
                let n = self.count("a sor's number of points", 4, MAX_POINTS)?;
                let p = self.points2(n)?;
                if p.windows(2).skip(1).take(n.saturating_sub(3)).any(|w| w[1].y <= w[0].y) {
                    return self.err(pos, "a sor's points must rise: each height above the one before".into());
                }
                self.open_sturm(open)?;
                Ok((tessellate::sor(&p, *open), true))
            }
            "prism" => {
                let (mut spline, mut conic) = (Spline::Linear, false);
                loop {
                    if let Some(s) = self.spline_word()? {
                        spline = s;
                    } else if self.accept_word("linear_sweep")? {
                        conic = false;
                    } else if self.accept_word("conic_sweep")? {
                        conic = true;
                    } else {
                        break;
                    }
                }
                let h1 = self.float()?;
                self.accept_sym(",")?;
                let h2 = self.float()?;
                self.accept_sym(",")?;
                let min = match spline {
                    Spline::Linear => 3,
                    Spline::Quadratic => 5,
                    Spline::Cubic => 6,
                    Spline::Bezier => 4,
                };
                let n = self.count(&format!("a prism's number of points ({})", spline.name()), min, MAX_POINTS)?;
                let p = self.points2(n)?;
                self.open_sturm(open)?;
                let outlines = tessellate::prism_outlines(spline, &p);
                if outlines.is_empty() {
                    return self.err(pos, "this prism's points enclose nothing".into());
                }
                let tris = tessellate::extrude(&outlines, FillRule::EvenOdd, h1.min(h2), h1.max(h2), *open, conic);
                Ok((tris, !matches!(spline, Spline::Linear)))
            }
            "polygon" => {
                let n = self.count("a polygon's number of points", 3, MAX_POINTS)?;
                let mut p = Vec::with_capacity(n);
                for _ in 0..n {
                    self.accept_sym(",")?;
                    p.push(self.vec3()?);
                }
                Ok((tessellate::polygon(&p), false))
            }
            _ => Ok((self.text()?, true)),
        }
    }

    /// `height_field { [type] "file" [gamma g] [premultiplied b] ... }`: the image's samples as
    /// a grid over the unit square of x and z, height y from 0 to 1 (image row 0 at z = 1, as
    /// POV-Ray lays it), two triangles a cell, closed by walls and a floor at y = 0 so that it
    /// has an inside for CSG. At most `HF_MAX_CELLS` cells a side: a larger image is sampled at
    /// evenly spaced pixels (docs/pov-ray.md).
    fn height_field(&mut self, pos: Pos) -> Result<Vec<Tri>> {
        let Some(t) = self.peek()? else { return self.err(pos, "this height_field is never closed; add `}`".into()) };
        let (kind, fpos) = match &t.tok {
            Tok::Word(w) if w == "function" => {
                return self.err(
                    t.pos,
                    "height_field { function ... } is not supported yet (user-defined functions); use an image".into(),
                )
            }
            Tok::Word(w) if super::image::FORMATS.contains(&w.as_str()) => {
                self.next()?;
                (w.clone(), self.here())
            }
            // A file name: a string, or a string expression.
            _ => (String::new(), t.pos),
        };
        let name = self.image_name()?;
        while let Some("gamma") | Some("premultiplied") = self.peek_word()?.as_deref() {
            self.next()?;
            if !self.accept_word("srgb")? {
                self.float()?;
            }
        }
        let path = self.find_image(&name, fpos)?;
        let h = super::image::heights(&path, &kind).map_err(|m| PovError::at(fpos, m))?;
        if h.width < 2 || h.height < 2 {
            return self.err(
                fpos,
                format!("a height field needs an image of at least 2 x 2 pixels, not {} x {}", h.width, h.height),
            );
        }
        Ok(height_field_triangles(&h))
    }

    /// `text { ttf "font.ttf" "string" thickness, offset }`: the glyphs' outlines from x = 0 on
    /// the baseline, one em high, extruded from z = 0 to the thickness (POV-Ray's reference
    /// manual, "Text").
    fn text(&mut self) -> Result<Vec<Tri>> {
        if !self.accept_word("ttf")? {
            let t = self.expect_any("ttf")?;
            return self.err(t.pos, format!("expected ttf \"font.ttf\" here, found {}", describe(&t.tok)));
        }
        let fpos = self.here();
        let font_name = self.string()?;
        self.accept_sym(",")?;
        let string = self.string()?;
        self.accept_sym(",")?;
        let thickness = self.float()?;
        self.accept_sym(",")?;
        let offset = self.vector(2)?;
        // POV-Ray adds `.ttf` to a name without an extension.
        let font_name =
            if std::path::Path::new(&font_name).extension().is_none() { format!("{font_name}.ttf") } else { font_name };
        let path = self
            .find_include(&font_name, fpos)
            .map_err(|e| PovError { message: e.message.replacen("#include", "font", 1), ..e })?;
        let bytes = super::parser::read_gated(&path, crate::limits::MAX_FONT_FILE_BYTES, "the font")
            .map_err(|m| PovError::at(fpos, m))?;
        let Some(font) = ttf::Font::parse(bytes) else {
            return self.err(fpos, format!("{} is not a TrueType font this front-end reads", path.display()));
        };
        let mut tris = Vec::new();
        let mut pen = glam::DVec2::ZERO;
        let (lo, hi) = (0.0f64.min(thickness), 0.0f64.max(thickness));
        for c in string.chars() {
            let g = font.glyph(c);
            let Some(o) = font.outline(g) else {
                return self.err(fpos, format!("the font {} is damaged (glyph {g})", path.display()));
            };
            // Glyph by glyph: a fill over the whole string would cut every glyph at every other's
            // vertex heights.
            let outlines: Vec<Vec<glam::DVec2>> =
                o.into_iter().map(|c| c.into_iter().map(|p| p + pen).collect()).collect();
            // extrude() sweeps along y with the outline in (x, z): turn that to (x, y) and z.
            let glyph = tessellate::extrude(&outlines, FillRule::NonZero, lo, hi, false, false);
            tris.extend(glyph.into_iter().map(|t| t.map(|v| DVec3::new(v.x, v.z, v.y))));
            pen += glam::DVec2::new(font.advance(g) + offset[0], offset[1]);
        }
        Ok(tris)
    }

    /// quadric { <A, B, C>, <D, E, F>, <G, H, I>, J }, cubic { <20> }, quartic { <35> },
    /// poly { n, <...> }.
    fn polynomial(&mut self, kind: &str, pos: Pos) -> Result<Implicit> {
        if kind == "quadric" {
            let a = self.vec3()?;
            self.accept_sym(",")?;
            let d = self.vec3()?;
            self.accept_sym(",")?;
            let g = self.vec3()?;
            self.accept_sym(",")?;
            let j = self.float()?;
            let terms = vec![
                (a.x, [2, 0, 0]),
                (a.y, [0, 2, 0]),
                (a.z, [0, 0, 2]),
                (d.x, [1, 1, 0]),
                (d.y, [1, 0, 1]),
                (d.z, [0, 1, 1]),
                (g.x, [1, 0, 0]),
                (g.y, [0, 1, 0]),
                (g.z, [0, 0, 1]),
                (j, [0, 0, 0]),
            ];
            return Ok(Implicit::Poly { terms: terms.into_iter().filter(|t| t.0 != 0.0).collect() });
        }
        let order = match kind {
            "cubic" => 3,
            "quartic" => 4,
            _ => {
                let n = self.float()?;
                self.accept_sym(",")?;
                if !(2.0..=7.0).contains(&n) || n.fract() != 0.0 {
                    return self
                        .err(pos, format!("a poly's order must be 2 to 7, not {}", crate::limits::fmt_number(n)));
                }
                n as i32
            }
        };
        let want = Implicit::coefficients(order);
        let lt = self.expect_sym("<")?;
        let c = self.angle_list_max(want + 1)?;
        match Implicit::poly(order, &c) {
            Some(p) => {
                self.accept_word("sturm")?;
                Ok(p)
            }
            None => self.err(lt, format!("a {kind} of order {order} takes {want} coefficients, not {}", c.len())),
        }
    }

    /// blob { threshold t  sphere { c, r, [strength] s }  cylinder { a, b, r, [strength] s }
    /// component s, r, c ... } (component textures are read and not kept).
    fn blob(&mut self, pos: Pos) -> Result<Implicit> {
        let mut threshold = 1.0;
        let mut comps = Vec::new();
        while let Some(w) = self.peek_word()? {
            match w.as_str() {
                "threshold" => {
                    self.next()?;
                    threshold = self.float()?;
                }
                "sturm" | "hierarchy" => {
                    self.next()?;
                    self.optional_bool()?;
                }
                "component" => {
                    self.next()?;
                    let strength = self.float()?;
                    self.accept_sym(",")?;
                    let radius = self.float()?;
                    self.accept_sym(",")?;
                    let a = self.vec3()?;
                    comps.push(BlobComp { strength, radius, a, b: None, inv: DMat4::IDENTITY });
                }
                "sphere" | "cylinder" => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let a = self.vec3()?;
                    self.accept_sym(",")?;
                    let b = if w == "cylinder" {
                        let b = self.vec3()?;
                        self.accept_sym(",")?;
                        Some(b)
                    } else {
                        None
                    };
                    let radius = self.float()?;
                    self.accept_sym(",")?;
                    self.accept_word("strength")?;
                    let strength = self.float()?;
                    let mut m = DMat4::IDENTITY;
                    loop {
                        let t = self.expect_any("`}`")?;
                        match t.tok {
                            Tok::Sym("}") => break,
                            Tok::Word(w) => {
                                if let Some(t2) = self.transform_word(&w)? {
                                    m = t2 * m;
                                } else if matches!(w.as_str(), "texture" | "pigment" | "finish" | "normal") {
                                    self.skip_block()?;
                                } else {
                                    return self.err(t.pos, format!("`{w}` does not belong in a blob component"));
                                }
                            }
                            other => {
                                return self.err(
                                    t.pos,
                                    format!("expected `}}` closing the component, found {}", describe(&other)),
                                )
                            }
                        }
                    }
                    if radius <= 0.0 {
                        return self.err(
                            pos,
                            format!(
                                "a blob component's radius must be positive, not {}",
                                crate::limits::fmt_number(radius)
                            ),
                        );
                    }
                    comps.push(BlobComp { strength, radius, a, b, inv: m.inverse() });
                }
                _ => break,
            }
        }
        if comps.is_empty() {
            return self.err(pos, "this blob has no components".into());
        }
        Ok(Implicit::Blob { threshold, comps })
    }

    /// `mesh2 { vertex_vectors { n, ... } ... face_indices { n, <a, b, c> ... } ... }`: the faces
    /// (normals, uv and per-face textures are read and not kept yet).
    /// `mesh2 { vertex_vectors normal_vectors uv_vectors texture_list face_indices
    /// normal_indices ... }`: the faces, and their corners' normals when the mesh has
    /// normal_vectors (indexed by normal_indices, or by the face indices without them, as
    /// POV-Ray reads them).
    fn mesh2(&mut self, pos: Pos) -> Result<MeshTris> {
        const MAX_ITEMS: usize = 1 << 24;
        let mut vertices: Vec<DVec3> = Vec::new();
        let mut normal_vectors: Vec<DVec3> = Vec::new();
        let mut normal_indices: Vec<(DVec3, Pos)> = Vec::new();
        let mut faces: Vec<(DVec3, Pos)> = Vec::new();
        let mut textures: Vec<Vec<Tex>> = Vec::new();
        // Each face's texture index (the first of three: POV-Ray blends three across the face)
        // and where it was written.
        let mut tex_of: Vec<Option<(f64, Pos)>> = Vec::new();
        while let Some(w) = self.peek_word()? {
            match w.as_str() {
                "vertex_vectors" | "normal_vectors" | "uv_vectors" | "normal_indices" | "uv_indices" => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let n = self.count(&format!("the number of {w}"), 0, MAX_ITEMS)?;
                    for _ in 0..n {
                        self.accept_sym(",")?;
                        let ipos = self.here();
                        let v = self.vec3()?;
                        match w.as_str() {
                            "vertex_vectors" => vertices.push(v),
                            "normal_vectors" => normal_vectors.push(v),
                            "normal_indices" => normal_indices.push((v, ipos)),
                            _ => {}
                        }
                    }
                    self.accept_sym(",")?;
                    self.expect_sym("}")?;
                }
                "texture_list" => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let n = self.count("the number of textures", 0, MAX_ITEMS)?;
                    for _ in 0..n {
                        self.accept_sym(",")?;
                        textures.push(self.expect_word_tex()?);
                    }
                    self.accept_sym(",")?;
                    self.expect_sym("}")?;
                }
                "face_indices" => {
                    self.next()?;
                    self.expect_sym("{")?;
                    let n = self.count("the number of face_indices", 0, MAX_ITEMS)?;
                    for _ in 0..n {
                        self.accept_sym(",")?;
                        let fpos = self.here();
                        faces.push((self.vec3()?, fpos));
                        // Texture indices (one or three) may follow each face.
                        let mut first = None;
                        while self.peek()?.is_some_and(|t| t.tok == Tok::Sym(",")) {
                            self.next()?;
                            if self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Sym("<") | Tok::Sym("}"))) {
                                break;
                            }
                            let ipos = self.here();
                            let i = self.float()?;
                            first.get_or_insert((i, ipos));
                        }
                        tex_of.push(first);
                    }
                    self.accept_sym(",")?;
                    self.expect_sym("}")?;
                }
                "inside_vector" => {
                    self.next()?;
                    self.vec3()?;
                }
                _ => break,
            }
        }
        // Each face's three points from `list` by its indices.
        let pick = |this: &Self, list: &[DVec3], (f, fpos): &(DVec3, Pos), what: (&str, &str)| -> Result<[DVec3; 3]> {
            let mut t = [DVec3::ZERO; 3];
            for (k, i) in [f.x, f.y, f.z].into_iter().enumerate() {
                if !(i >= 0.0 && (i as usize) < list.len()) {
                    let (index, items) = what;
                    return this.err(
                        *fpos,
                        format!("{index} index {i} is out of range: this mesh2 has {} {items}", list.len()),
                    );
                }
                t[k] = list[i as usize];
            }
            Ok(t)
        };
        let tris = faces.iter().map(|f| pick(self, &vertices, f, ("face", "vertices"))).collect::<Result<Vec<_>>>()?;
        if tris.is_empty() {
            return self.err(pos, "this mesh2 has no faces (face_indices)".into());
        }
        let normals = if normal_vectors.is_empty() {
            None
        } else if normal_indices.is_empty() {
            Some(
                faces
                    .iter()
                    .map(|f| pick(self, &normal_vectors, f, ("normal", "normal_vectors")))
                    .collect::<Result<Vec<_>>>()?,
            )
        } else if normal_indices.len() == faces.len() {
            Some(
                normal_indices
                    .iter()
                    .map(|f| pick(self, &normal_vectors, f, ("normal", "normal_vectors")))
                    .collect::<Result<Vec<_>>>()?,
            )
        } else {
            return self.err(
                normal_indices[0].1,
                format!(
                    "this mesh2 has {} normal_indices for {} faces; give one per face (or none, to index the normals as the vertices)",
                    normal_indices.len(),
                    faces.len()
                ),
            );
        };
        let tex_of = tex_of
            .into_iter()
            .map(|t| match t {
                None => Ok(None),
                Some((i, _)) if i >= 0.0 && (i as usize) < textures.len() => Ok(Some(i as usize)),
                Some((i, ipos)) => self.err(
                    ipos,
                    format!(
                        "texture index {i} is out of range: this mesh2's texture_list has {} textures",
                        textures.len()
                    ),
                ),
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(MeshTris { tris, normals, tex_of, textures })
    }

    fn expect_word_tex(&mut self) -> Result<Vec<Tex>> {
        let t = self.expect_any("a texture")?;
        match &t.tok {
            Tok::Word(w) if w == "texture" => self.texture(),
            other => self.err(t.pos, format!("expected a texture in texture_list, found {}", describe(other))),
        }
    }

    /// `bicubic_patch { type n [flatness f] u_steps n v_steps m [accuracy a] 16 points }`.
    fn bicubic_patch(&mut self, pos: Pos) -> Result<[DVec3; 16]> {
        while let Some("type" | "flatness" | "u_steps" | "v_steps" | "accuracy") = self.peek_word()?.as_deref() {
            self.next()?;
            self.stop_at_less = true;
            let v = self.float();
            self.stop_at_less = false;
            v?;
        }
        self.accept_sym(",")?;
        let mut p = [DVec3::ZERO; 16];
        for (i, q) in p.iter_mut().enumerate() {
            if i > 0 {
                self.accept_sym(",")?;
            }
            *q = self.vec3()?;
        }
        if p.iter().any(|q| !q.is_finite()) {
            return self.err(pos, "a bicubic_patch point is not a number".into());
        }
        Ok(p)
    }

    /// The end of a mesh triangle: an optional texture and `}`; the texture's index in
    /// `textures` (a texture given twice is kept once; a declared one compares equal only by its
    /// contents, so identical textures share their triangles).
    fn triangle_tail(&mut self, textures: &mut Vec<Vec<Tex>>, keys: &mut Vec<String>) -> Result<Option<usize>> {
        let mut index = None;
        loop {
            if self.accept_sym("}")? {
                return Ok(index);
            }
            if self.accept_word("texture")? {
                let t = self.texture()?;
                let key = format!("{t:?}");
                index = Some(match keys.iter().position(|k| *k == key) {
                    Some(i) => i,
                    None => {
                        keys.push(key);
                        textures.push(t);
                        textures.len() - 1
                    }
                });
                continue;
            }
            let t = self.expect_any("`}`")?;
            return self.err(t.pos, format!("expected `}}` closing the triangle, found {}", describe(&t.tok)));
        }
    }

    /// Modifiers up to and including the closing `}`. CSG children are read here too.
    fn modifiers(&mut self, o: &mut Obj, open: &mut bool) -> Result<()> {
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(()),
                Tok::Word(w) => w,
                other => {
                    return self
                        .err(pos, format!("expected an object modifier or `}}` here, found {}", describe(&other)))
                }
            };
            if let Some(m) = self.transform_word(&w)? {
                transform_obj(o, &m);
                continue;
            }
            match w.as_str() {
                _ if matches!(o.kind, ObjKind::Csg { .. })
                    && (OBJECTS.contains(&w.as_str())
                        || w == "light_source"
                        || UNSUPPORTED_OBJECTS.contains(&w.as_str())) =>
                {
                    let child = self.object(&w, pos)?;
                    if let ObjKind::Csg { children, .. } = &mut o.kind {
                        children.push(child);
                    }
                }
                "texture" => {
                    let layers = self.texture()?;
                    o.tex.get_or_insert_with(Vec::new).extend(layers);
                }
                "pigment" => {
                    let p = self.pigment(pos)?;
                    self.top_layer(o).pigment = p;
                }
                "finish" => {
                    let f = self.finish()?;
                    self.top_layer(o).finish = f;
                }
                "interior" => o.interior = Some(self.interior()?),
                "material" => {
                    let (t, i) = self.material()?;
                    if !t.is_empty() {
                        o.tex = Some(t);
                    }
                    if i.is_some() {
                        o.interior = i;
                    }
                }
                "open" => *open = true,
                "water_level" if matches!(o.kind, ObjKind::Triangles { .. }) => {
                    // A height field's parts below the level are not shown: its triangles wholly
                    // below it are left out (object space, where the field spans y 0 to 1).
                    let level = self.float()?;
                    if let ObjKind::Triangles { tris, normals } = &mut o.kind {
                        let keep: Vec<bool> = tris.iter().map(|t| t.iter().any(|p| p.y >= level)).collect();
                        let kept = |v: &[[DVec3; 3]]| -> Vec<[DVec3; 3]> {
                            v.iter().zip(&keep).filter(|(_, k)| **k).map(|(t, _)| *t).collect()
                        };
                        *tris = std::rc::Rc::new(kept(tris));
                        if let Some(n) = normals {
                            *n = std::rc::Rc::new(kept(n));
                        }
                    }
                }
                "smooth" if matches!(o.kind, ObjKind::Triangles { .. }) => {
                    // A smooth height field: its top's vertex normals from the faces around
                    // each (all of them, as POV-Ray's normals from the height differences
                    // are); the walls and the floor (which POV-Ray has not) stay flat.
                    if self.optional_bool()? {
                        if let ObjKind::Triangles { tris, normals } = &mut o.kind {
                            let top = |t: &[DVec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).y > 0.0;
                            let tops: Vec<[DVec3; 3]> = tris.iter().filter(|t| top(t)).copied().collect();
                            let mut smooth = tessellate::corner_normals(&tops, 180.0).into_iter();
                            let all = tris
                                .iter()
                                .map(|t| {
                                    if top(t) {
                                        smooth.next().unwrap_or([DVec3::Y; 3])
                                    } else {
                                        [(t[1] - t[0]).cross(t[2] - t[0]); 3]
                                    }
                                })
                                .collect();
                            *normals = Some(std::rc::Rc::new(all));
                        }
                    }
                }
                "hierarchy" if matches!(o.kind, ObjKind::Triangles { .. }) => {
                    // An acceleration hint.
                    self.optional_bool()?;
                }
                "bounded_by" if matches!(o.kind, ObjKind::Implicit { .. }) => {
                    // An equation's surface is cut at its bounds, as POV-Ray does.
                    self.expect_sym("{")?;
                    let mut parts = Vec::new();
                    loop {
                        let t = self.expect_any("`}`")?;
                        match &t.tok {
                            Tok::Sym("}") => break,
                            Tok::Word(w) if OBJECTS.contains(&w.as_str()) => parts.push(self.object(w, t.pos)?),
                            other => {
                                return self
                                    .err(t.pos, format!("expected an object in bounded_by, found {}", describe(other)))
                            }
                        }
                    }
                    let inv = o.xform.inverse();
                    for part in &parts {
                        let (lo, hi) = super::emit::bounds_of(part);
                        if lo.x > hi.x {
                            continue;
                        }
                        let (lo, hi) = implicit::moved_box(lo, hi, &inv);
                        if let ObjKind::Implicit { bound, .. } = &mut o.kind {
                            *bound = Some(match *bound {
                                Some((a, b)) => (a.max(lo), b.min(hi)),
                                None => (lo, hi),
                            });
                        }
                    }
                }
                "normal" => {
                    let n = self.normal(pos)?;
                    self.top_layer(o).normal = n;
                }
                "bounded_by" | "photons" | "radiosity" | "interior_texture" => self.skip_block()?,
                "hollow" | "no_shadow" | "no_image" | "no_reflection" | "double_illuminate" | "sturm"
                | "no_radiosity" => {
                    self.optional_bool()?;
                }
                "split_union" | "cutaway_textures" => {
                    if let Some(Tok::Num(_) | Tok::Word(_)) = self.peek()?.map(|t| t.tok) {
                        if !matches!(self.peek_word()?.as_deref(), Some(w) if OBJECTS.contains(&w)) {
                            self.float()?;
                        }
                    }
                }
                "inverse" => o.inverse = !o.inverse,
                "clipped_by" => {
                    // The object's surface where it is inside the clipping objects: written as
                    // the intersection of the object and them (docs/pov-ray.md: the cut is
                    // closed here where POV-Ray leaves it open).
                    self.expect_sym("{")?;
                    let mut clips = Vec::new();
                    loop {
                        let t = self.expect_any("`}`")?;
                        match &t.tok {
                            Tok::Sym("}") => break,
                            Tok::Word(w) if w == "bounded_by" => {
                                // clipped_by { bounded_by }: the bounds are not kept, so no clip.
                            }
                            Tok::Word(w)
                                if OBJECTS.contains(&w.as_str()) || UNSUPPORTED_OBJECTS.contains(&w.as_str()) =>
                            {
                                clips.push(self.object(w, t.pos)?);
                            }
                            other => {
                                return self
                                    .err(t.pos, format!("expected an object in clipped_by, found {}", describe(other)))
                            }
                        }
                    }
                    if !clips.is_empty() && !matches!(o.kind, ObjKind::Light(_)) {
                        let inner = Obj { interior: None, ..o.clone() };
                        let mut children = vec![inner];
                        children.extend(clips);
                        *o = Obj {
                            kind: ObjKind::Csg { op: CsgOp::Intersection, children },
                            xform: DMat4::IDENTITY,
                            tex: None,
                            interior: o.interior.clone(),
                            inverse: false,
                            pos: o.pos,
                        };
                        // The clipped object keeps its texture; one given later reaches it too
                        // (the node's texture is the default of children without one).
                    }
                }
                other => {
                    return self.err(pos, format!("`{other}` is not an object modifier this front-end knows"));
                }
            }
        }
    }

    /// An optional on/off after a flag (`hollow`, `shadowless on`, `jitter off`); true when absent.
    fn optional_bool(&mut self) -> Result<bool> {
        if self.starts_float()? {
            return Ok(self.float()? != 0.0);
        }
        match self.peek()?.map(|t| t.tok) {
            Some(Tok::Word(w)) if matches!(w.as_str(), "on" | "off" | "yes" | "no" | "true" | "false") => {
                self.next()?;
                Ok(matches!(w.as_str(), "on" | "yes" | "true"))
            }
            _ => Ok(true),
        }
    }

    /// Whether a float expression comes next (for the optional numbers after `metallic`,
    /// `fresnel`, `poly_wave`...): a number, `(`, `-`, or a declared float.
    fn starts_float(&mut self) -> Result<bool> {
        Ok(match self.peek()?.map(|t| t.tok) {
            Some(Tok::Num(_)) | Some(Tok::Sym("(")) | Some(Tok::Sym("-")) => true,
            Some(Tok::Word(w)) => matches!(self.lookup(&w), Some(Value::Float(_))),
            _ => false,
        })
    }

    /// The texture layer a bare `pigment` or `finish` in an object changes (made on first use).
    fn top_layer<'a>(&self, o: &'a mut Obj) -> &'a mut Tex {
        let default = self.default_tex(o.pos);
        let layers = o.tex.get_or_insert_with(Vec::new);
        if layers.is_empty() {
            layers.push(default);
        }
        layers.last_mut().expect("a layer was just pushed")
    }

    pub fn default_tex(&self, pos: Pos) -> Tex {
        Tex {
            pigment: self.default_pigment.clone().unwrap_or_else(|| Pigment::solid([0.0, 0.0, 0.0, 0.0, 0.0], pos)),
            finish: self.default_finish.clone(),
            normal: None,
            xform: DMat4::IDENTITY,
            map: None,
        }
    }

    /// `translate`, `rotate`, `scale`, `matrix`, `transform`: the matrix (world_from_object of
    /// the change), or `None` for another word. The word is already consumed.
    fn transform_word(&mut self, w: &str) -> Result<Option<DMat4>> {
        Ok(Some(match w {
            "translate" => DMat4::from_translation(self.vec3()?),
            "rotate" => rotation(self.vec3()?),
            "scale" => {
                let pos = self.here();
                let s = self.vec3()?;
                if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
                    // POV-Ray warns and uses 1 for a zero scale component.
                    self.warnings
                        .push(format!("{}: a zero scale component is taken as 1, as POV-Ray does", self.loc(pos)));
                }
                let fix = |v: f64| if v == 0.0 { 1.0 } else { v };
                DMat4::from_scale(DVec3::new(fix(s.x), fix(s.y), fix(s.z)))
            }
            "matrix" => self.matrix()?,
            "transform" => {
                if self.peek()?.is_some_and(|t| t.tok == Tok::Sym("{")) {
                    self.transform_block()?
                } else {
                    let t = self.expect_any("a transform")?;
                    match (&t.tok, &t.tok) {
                        (Tok::Word(n), _) => match self.lookup(n) {
                            Some(Value::Transform(m)) => *m,
                            _ => return self.err(t.pos, format!("`{n}` is not a declared transform")),
                        },
                        _ => return self.err(t.pos, format!("expected a transform, found {}", describe(&t.tok))),
                    }
                }
            }
            _ => return Ok(None),
        }))
    }

    /// `{ translate ... rotate ... [Ident] [inverse] }`.
    fn transform_block(&mut self) -> Result<DMat4> {
        self.expect_sym("{")?;
        let mut m = DMat4::IDENTITY;
        loop {
            let t = self.expect_any("`}`")?;
            match t.tok {
                Tok::Sym("}") => return Ok(m),
                Tok::Word(w) if w == "inverse" => m = m.inverse(),
                Tok::Word(w) => {
                    if let Some(t2) = self.transform_word(&w)? {
                        m = t2 * m;
                    } else if let Some(Value::Transform(t2)) = self.lookup(&w) {
                        m = *t2 * m;
                    } else {
                        return self.err(t.pos, format!("`{w}` does not belong in a transform"));
                    }
                }
                other => return self.err(t.pos, format!("expected a transform item, found {}", describe(&other))),
            }
        }
    }

    /// `matrix <m00, m01, m02, m10, ..., m32>`: POV-Ray's rows, the last row the translation.
    fn matrix(&mut self) -> Result<DMat4> {
        let pos = self.expect_sym("<")?;
        let v = self.angle_list()?;
        if v.len() != 12 {
            return self.err(pos, format!("`matrix` takes 12 numbers, not {}", v.len()));
        }
        // POV-Ray multiplies row vectors: p' = p M, so M's columns here are its rows there.
        Ok(DMat4::from_cols(
            DVec4::new(v[0], v[1], v[2], 0.0),
            DVec4::new(v[3], v[4], v[5], 0.0),
            DVec4::new(v[6], v[7], v[8], 0.0),
            DVec4::new(v[9], v[10], v[11], 1.0),
        ))
    }

    // -------------------------------------------------------------------------------------------
    // Textures

    /// `{ ... }` after `texture`: one or more layers (a declared layered texture).
    pub fn texture(&mut self) -> Result<Vec<Tex>> {
        let open = self.expect_sym("{")?;
        self.texture_body(open, "}")
    }

    /// A texture's items up to `close` (consumed): `}`, or `]` in a texture_map's entry.
    fn texture_body(&mut self, open: Pos, close: &'static str) -> Result<Vec<Tex>> {
        let mut layers = vec![self.default_tex(open)];
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            let w = match t.tok {
                Tok::Sym(c) if c == close => return Ok(layers),
                Tok::Word(w) => w,
                other => return self.err(pos, format!("expected a texture item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                layers.iter_mut().for_each(|l| l.xform = m * l.xform);
                continue;
            }
            let top = layers.last_mut().expect("a texture has a layer");
            match w.as_str() {
                "pigment" => top.pigment = self.pigment(pos)?,
                "finish" => top.finish = self.finish()?,
                "normal" => top.normal = self.normal(pos)?,
                "uv_mapping" => {}
                "material_map" => {
                    return self.err(
                        pos,
                        "material_map is not supported yet (an image's palette indices choosing textures); \
                         use a texture_map over a pattern instead"
                            .into(),
                    )
                }
                "tiles" => layers = vec![self.tiles(pos)?],
                _ if PATTERNS.contains(&w.as_str()) || OTHER_PATTERNS.contains(&w.as_str()) => {
                    // A patterned texture (texture_map, or textures as a checker's entries): the
                    // pattern and its entries, mixed by `emit` (docs/pov-ray.md); the pigment's
                    // colour map holds each entry's mean colour, in the first entry's finish and
                    // normal, for where they cannot be mixed.
                    let (pigment, map) = self.pattern_body(pos, close, Some((w.clone(), pos)))?;
                    let first = map.as_ref().and_then(|m| m.entries.first()).and_then(|(_, l)| l.first());
                    let mut t = first.cloned().unwrap_or_else(|| self.default_tex(pos));
                    t.pigment = pigment;
                    t.xform = DMat4::IDENTITY;
                    // A pattern Photonix lacks leaves the mean colour (a solid pigment): no mix.
                    let patterned = matches!(t.pigment.kind, PigmentKind::Pattern { .. });
                    t.map = map.filter(|m| patterned && !m.entries.is_empty()).map(std::rc::Rc::new);
                    return Ok(vec![t]);
                }
                _ => match self.lookup(&w).cloned().map(|v| self.postfix(v)).transpose()? {
                    Some(Value::Texture(t)) => layers = t,
                    Some(other) => return self.err(pos, format!("`{w}` is {}, not a texture", other.kind())),
                    None => return self.err(pos, format!("`{w}` does not belong in a texture")),
                },
            }
        }
    }

    /// `tiles { texture { A } ... tile2 texture { B } ... }` (after `tiles`): POV-Ray 3.7 reads
    /// it as a checker of the two textures (parstxtr.cpp), A in the cubes where floor(x) +
    /// floor(y) + floor(z) is even, B in the others; so it becomes a checker texture with the two
    /// as its listed entries, mixed as a checker's textures are (docs/pov-ray.md).
    fn tiles(&mut self, pos: Pos) -> Result<Tex> {
        self.expect_sym("{")?;
        let mut tiles: [Vec<Tex>; 2] = [Vec::new(), Vec::new()];
        let mut second = false;
        loop {
            let t = self.expect_any("`}`")?;
            match t.tok {
                Tok::Sym("}") => break,
                Tok::Word(w) if w == "texture" => {
                    let layers = self.texture()?;
                    tiles[second as usize].extend(layers);
                }
                Tok::Word(w) if w == "tile2" && !second => second = true,
                other => {
                    return self.err(
                        t.pos,
                        format!(
                            "expected `texture {{ ... }}`{} or `}}` in tiles, found {}",
                            if second { "" } else { ", `tile2`" },
                            describe(&other)
                        ),
                    )
                }
            }
        }
        let [a, b] = tiles;
        if a.is_empty() || b.is_empty() {
            return self.err(
                pos,
                "tiles needs a texture on each side of `tile2`: tiles { texture { A } tile2 texture { B } }".into(),
            );
        }
        let (mean_a, mean_b) = (a[0].pigment.mean(), b[0].pigment.mean());
        let mut t = a[0].clone();
        t.pigment = Pigment {
            kind: PigmentKind::Pattern {
                name: "checker".into(),
                map: vec![(0.0, mean_a), (1.0, mean_b)],
                fields: vec![("colors".into(), toml::Value::Boolean(true))],
            },
            xform: DMat4::IDENTITY,
            pos,
            entries: None,
        };
        t.xform = DMat4::IDENTITY;
        t.map = Some(std::rc::Rc::new(TexMap { entries: vec![(0.0, a), (1.0, b)], listed: true }));
        Ok(t)
    }

    /// Skips to the `]` (or other closing symbol in `close`) that ends the entry we are in,
    /// nested brackets and braces included (consumed).
    fn skip_entry(&mut self, close: &[&str]) -> Result<()> {
        let mut depth = 0i32;
        loop {
            let t = self.expect_any("`]`")?;
            match t.tok {
                Tok::Sym(c) if depth == 0 && close.contains(&c) => return Ok(()),
                Tok::Sym("{") | Tok::Sym("[") => depth += 1,
                Tok::Sym("}") | Tok::Sym("]") => depth -= 1,
                _ => {}
            }
        }
    }

    /// Skips to the `}` that closes the block we are in (consumed).
    fn skip_to_brace(&mut self) -> Result<()> {
        let mut depth = 1;
        while depth > 0 {
            let t = self.expect_any("`}`")?;
            match t.tok {
                Tok::Sym("{") => depth += 1,
                Tok::Sym("}") => depth -= 1,
                _ => {}
            }
        }
        Ok(())
    }

    pub fn pigment(&mut self, pos: Pos) -> Result<Pigment> {
        self.expect_sym("{")?;
        self.pigment_body(pos, "}")
    }

    /// A pigment's items up to `close` (consumed): `}` for `pigment { ... }`, `]` for an entry
    /// of a pigment_map.
    fn pigment_body(&mut self, pos: Pos, close: &'static str) -> Result<Pigment> {
        self.pattern_body(pos, close, None).map(|(p, _)| p)
    }

    /// A pigment's items, or a patterned texture's (`pending`: its pattern word, already read):
    /// a texture_map's or a checker's textures are returned as the map's entries, and stand in
    /// by their pigments' mean colours in the pigment's colour map (docs/pov-ray.md).
    fn pattern_body(
        &mut self,
        pos: Pos,
        close: &'static str,
        mut pending: Option<(String, Pos)>,
    ) -> Result<(Pigment, Option<TexMap>)> {
        let mut tex_map: Option<TexMap> = None;
        let mut listed_tex: Vec<Vec<Tex>> = Vec::new();
        let mut listed_pig: Vec<Pigment> = Vec::new();
        let mut pending_array = false;
        let mut p = Pigment::solid([0.0; 5], pos);
        let mut fields: Vec<(String, toml::Value)> = Vec::new();
        let mut pattern: Option<String> = None;
        let mut map: Vec<(f64, Colour)> = Vec::new();
        let mut list: Vec<Colour> = Vec::new();
        // filter all / transmit all of an image_map.
        let mut image_ft: [Option<f64>; 2] = [None, None];
        loop {
            if let Some((w, tpos)) = pending.take() {
                // The pattern word a texture read before it knew the texture was patterned.
                if w == "gradient" {
                    pattern = Some(w);
                    let v = self.vec3()?;
                    fields.push(("direction".into(), toml::Value::Array(vec![num(v.x), num(v.y), num(v.z)])));
                } else if PATTERNS.contains(&w.as_str()) {
                    pattern = Some(w);
                } else {
                    pattern = Some(format!("unsupported:{w}"));
                    if self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Sym("<") | Tok::Num(_))) {
                        self.expr()?;
                    }
                    if self.peek()?.is_some_and(|t| t.tok == Tok::Sym("{")) {
                        self.skip_block()?;
                    }
                }
                let _ = tpos;
                continue;
            }
            let Some(t) = self.peek()? else {
                return self.err(pos, format!("this pigment is never closed; add `{close}`"));
            };
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym(c) if c == close => {
                    self.next()?;
                    break;
                }
                Tok::Word(w) => w,
                _ => {
                    let c = self.colour()?;
                    if pattern.is_some() {
                        list.push(c);
                    } else {
                        p.kind = PigmentKind::Solid(c);
                    }
                    self.accept_sym(",")?;
                    continue;
                }
            };
            let mut declared = self.lookup(&w).cloned();
            if let Some(Value::Array(_)) = declared {
                // An element of an array of pigments: `pigmentArr[i]`.
                self.next()?;
                let v = self.lookup(&w).cloned().expect("looked up above");
                match self.postfix(v)? {
                    Value::Pigment(base) => declared = Some(Value::Pigment(base)),
                    other => return self.err(tpos, format!("`{w}[...]` is {}, not a pigment", other.kind())),
                }
                pending_array = true;
            }
            if let Some(Value::Pigment(base)) = declared {
                if !std::mem::take(&mut pending_array) {
                    self.next()?;
                }
                p = base;
                if let PigmentKind::Pattern { name, map: m, fields: f } = &p.kind {
                    pattern = Some(name.clone());
                    map = m.clone();
                    fields = f.clone();
                }
                continue;
            }
            if let Some(Value::ColorMap(m)) = self.lookup(&w).cloned() {
                self.next()?;
                map = m;
                continue;
            }
            if matches!(self.lookup(&w), Some(Value::Vector(_)) | Some(Value::Float(_))) {
                // A declared colour, possibly in an expression (`White * 1.4`).
                let c = self.colour()?;
                if pattern.is_some() {
                    list.push(c);
                } else {
                    p.kind = PigmentKind::Solid(c);
                }
                self.accept_sym(",")?;
                continue;
            }
            self.next()?;
            if let Some(m) = self.transform_word(&w)? {
                p.xform = m * p.xform;
                continue;
            }
            if self.pattern_field(&w, tpos, &mut fields, &mut p.xform)? {
                continue;
            }
            match w.as_str() {
                "color" | "colour" | "rgb" | "rgbf" | "rgbt" | "rgbft" | "srgb" | "srgbf" | "srgbt" | "srgbft" => {
                    let v = self.word_colour(&w, tpos)?;
                    if pattern.is_some() {
                        list.push(v);
                    } else {
                        p.kind = PigmentKind::Solid(v);
                    }
                }
                "color_map" | "colour_map" => map = self.colour_map()?,
                "pigment_map" | "density_map" => {
                    // A colour map of the entries' mean colours, and the entries for a texture to
                    // mix (emit.rs).
                    let entries = self.pigment_map(tpos)?;
                    map = entries.iter().map(|(v, p)| (*v, p.mean())).collect();
                    p.entries = Some(std::rc::Rc::new(entries));
                }
                "texture_map" => {
                    let entries = self.texture_map(tpos)?;
                    map = entries.iter().map(|(v, l)| (*v, l[0].pigment.mean())).collect();
                    tex_map = Some(TexMap { entries, listed: false });
                }
                "pigment" if pattern.is_some() => {
                    // A checker's, brick's or hexagon's pigments (`checker pigment { A } pigment
                    // { B }`): listed entries, mixed by the pattern's own values as its
                    // textures are.
                    let inner = self.pigment(tpos)?;
                    list.push(inner.mean());
                    listed_pig.push(inner);
                }
                "texture" if pattern.is_some() => {
                    // A checker's, brick's or hexagon's textures.
                    let layers = self.texture()?;
                    if let Some(t) = layers.first() {
                        list.push(t.pigment.mean());
                        listed_tex.push(layers);
                    }
                }
                "image_map" => {
                    let (mut mean, ft, image) = self.image_map(tpos)?;
                    image_ft = ft;
                    p.kind = match image {
                        Some((file, projection, once)) => {
                            // filter all / transmit all: the mean carries them, as for a colour.
                            for (i, v) in ft.iter().enumerate() {
                                if let Some(v) = v {
                                    mean[3 + i] = *v;
                                }
                            }
                            PigmentKind::Image { file, projection, once, mean }
                        }
                        None => PigmentKind::Solid(mean),
                    };
                    pattern = None;
                }
                "uv_mapping" => {}
                "density_file" => {
                    // density_file df3 "file": not read (docs/pov-ray.md); its mean stands in.
                    self.expect_any("df3")?;
                    self.string()?;
                    pattern = Some("unsupported:density_file".into());
                }
                "interpolate" | "control0" | "control1" => {
                    self.float()?;
                }
                "interior" | "exterior" => {
                    // A fractal pattern's interior and exterior types (`interior 1, 0.5`).
                    self.float()?;
                    if self.accept_sym(",")? {
                        self.float()?;
                    }
                }
                "red" | "green" | "blue" | "filter" | "transmit" => {
                    let i = ["red", "green", "blue", "filter", "transmit"].iter().position(|k| *k == w).unwrap_or(0);
                    let v = self.float()?;
                    if let PigmentKind::Solid(c) = &mut p.kind {
                        c[i] = v;
                    }
                }
                "pigment_pattern" => {
                    self.skip_block()?;
                    pattern = Some("unsupported:pigment_pattern".into());
                }
                "quick_color" | "quick_colour" => {
                    self.colour()?;
                }
                "gradient" => {
                    pattern = Some(w.clone());
                    let v = self.vec3()?;
                    fields.push(("direction".into(), toml::Value::Array(vec![num(v.x), num(v.y), num(v.z)])));
                }
                _ if PATTERNS.contains(&w.as_str()) => {
                    pattern = Some(w.clone());
                    if w == "brick" || w == "checker" || w == "hexagon" {
                        // Inline colours: `checker color A, color B`.
                        while !self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Sym(c) if c == close))
                            && self.starts_colour()?
                        {
                            list.push(self.colour()?);
                            self.accept_sym(",")?;
                        }
                    }
                }
                _ if OTHER_PATTERNS.contains(&w.as_str()) => {
                    pattern = Some(format!("unsupported:{w}"));
                    // Arguments of these patterns (a vector, a float) are skipped with the map.
                    if self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Sym("<") | Tok::Num(_))) {
                        self.expr()?;
                    }
                    if self.peek()?.is_some_and(|t| t.tok == Tok::Sym("{")) {
                        self.skip_block()?;
                    }
                }
                _ => match self.lookup(&w).cloned() {
                    Some(Value::Vector(_)) | Some(Value::Float(_)) => {
                        let c = super::parser::to_colour(
                            self.lookup(&w).cloned().unwrap_or(Value::Float(0.0)),
                            tpos,
                            self,
                        )?;
                        if pattern.is_some() {
                            list.push(c);
                        } else {
                            p.kind = PigmentKind::Solid(c);
                        }
                    }
                    _ => return self.err(tpos, format!("`{w}` does not belong in a pigment")),
                },
            }
        }
        if let PigmentKind::Solid(c) = &mut p.kind {
            if let Some(f) = image_ft[0] {
                c[3] = f;
            }
            if let Some(t) = image_ft[1] {
                c[4] = t;
            }
        }
        if let Some(name) = pattern {
            if !list.is_empty() && map.is_empty() {
                let n = list.len();
                let at = |i: usize| i as f64 / (n.max(2) - 1) as f64;
                map = list.iter().enumerate().map(|(i, c)| (at(i), *c)).collect();
                fields.push(("colors".into(), toml::Value::Boolean(true)));
                if listed_tex.len() == n {
                    let entries = listed_tex.into_iter().enumerate().map(|(i, l)| (at(i), l)).collect();
                    tex_map = Some(TexMap { entries, listed: true });
                } else if listed_pig.len() == n {
                    let entries = listed_pig.into_iter().enumerate().map(|(i, q)| (at(i), q)).collect();
                    p.entries = Some(std::rc::Rc::new(entries));
                }
            }
            if let Some(other) = name.strip_prefix("unsupported:") {
                self.warnings.push(format!(
                    "{}: the {other} pattern is not supported yet; its mean colour stands in",
                    self.loc(pos)
                ));
                let mean =
                    Pigment { kind: PigmentKind::Pattern { name: other.into(), map, fields: Vec::new() }, ..p }.mean();
                return Ok((Pigment::solid(mean, pos), tex_map));
            }
            p.kind = PigmentKind::Pattern { name, map, fields };
        }
        Ok((p, tex_map))
    }

    /// `texture_map { [v texture-body] ... }`: each entry's layers at its value.
    fn texture_map(&mut self, pos: Pos) -> Result<Vec<(f64, Vec<Tex>)>> {
        self.expect_sym("{")?;
        let mut map = Vec::new();
        loop {
            if self.accept_sym("}")? {
                return Ok(map);
            }
            let epos = self.here();
            self.expect_sym("[")?;
            let v = if self.starts_float()? { self.float()? } else { map.len() as f64 };
            self.accept_sym(",")?;
            let layers = self.texture_body(epos, "]")?;
            if !layers.is_empty() {
                map.push((v, layers));
            }
            if map.len() > 256 {
                return self.err(pos, "a texture_map has at most 256 entries".into());
            }
        }
    }

    /// A pattern's own modifier (turbulence, octaves, wave shape, brick size, a warp, ...) into
    /// `fields` as docs/patterns.md names them; false for another word. The word is consumed.
    /// `xform` holds the pattern's transforms read so far: a warp takes them (docs/pov-ray.md).
    fn pattern_field(
        &mut self,
        w: &str,
        pos: Pos,
        fields: &mut Vec<(String, toml::Value)>,
        xform: &mut DMat4,
    ) -> Result<bool> {
        let vec = |v: DVec3| toml::Value::Array(vec![num(v.x), num(v.y), num(v.z)]);
        match w {
            "turbulence" => {
                let v = self.vec3()?;
                set_field(fields, "turbulence", vec(v));
            }
            "octaves" => {
                let v = self.float()?;
                set_field(fields, "octaves", toml::Value::Integer(v.round().clamp(1.0, 10.0) as i64));
            }
            "omega" | "lambda" | "frequency" | "phase" | "mortar" | "agate_turb" | "metric" | "offset" => {
                let v = self.float()?;
                set_field(fields, w, num(v));
            }
            "brick_size" | "form" => {
                let v = self.vec3()?;
                set_field(fields, w, vec(v));
            }
            "solid" => set_field(fields, "solid", toml::Value::Boolean(true)),
            "ramp_wave" | "sine_wave" | "triangle_wave" | "scallop_wave" | "cubic_wave" => {
                set_field(fields, "wave", toml::Value::String(w.trim_end_matches("_wave").into()));
            }
            "poly_wave" => {
                set_field(fields, "wave", toml::Value::String("poly".into()));
                if self.starts_float()? {
                    let e = self.float()?;
                    set_field(fields, "exponent", num(e));
                }
            }
            "warp" => self.warp(pos, fields, xform)?,
            "noise_generator" => {
                // Photonix has one noise (docs/patterns.md); POV-Ray's generators 1 to 3 differ
                // in detail, not in kind.
                self.float()?;
            }
            _ => return Ok(false),
        }
        Ok(true)
    }

    /// `warp { ... }`: a turbulence warp becomes the pattern's own turbulence (docs/pov-ray.md:
    /// POV-Ray applies it at its place among the pattern's transforms, Photonix after the other
    /// warps); repeat, black_hole, cylindrical, spherical, toroidal and planar become an entry
    /// of the pattern's `warp` list, with the transforms written before it (`xform`, which it
    /// takes) as its own `transform`. A cubic warp is left out with a warning.
    fn warp(&mut self, pos: Pos, fields: &mut Vec<(String, toml::Value)>, xform: &mut DMat4) -> Result<()> {
        let vec = |v: DVec3| toml::Value::Array(vec![num(v.x), num(v.y), num(v.z)]);
        self.expect_sym("{")?;
        let t = self.expect_any("a warp type")?;
        let kind = match t.tok {
            Tok::Sym("}") => return Ok(()),
            Tok::Word(w) => w,
            other => return self.err(t.pos, format!("expected a warp type or `}}`, found {}", describe(&other))),
        };
        let mut w = toml::Table::new();
        w.insert("type".into(), toml::Value::String(kind.clone()));
        match kind.as_str() {
            "turbulence" => {
                let v = self.vec3()?;
                set_field(fields, "turbulence", vec(v));
            }
            "repeat" => {
                let v = self.vec3()?;
                if [v.x, v.y, v.z].iter().filter(|c| **c != 0.0).count() != 1 {
                    return self.err(t.pos, "a repeat warp repeats along one axis: give a vector such as x * 2".into());
                }
                w.insert("direction".into(), vec(v));
            }
            "black_hole" => {
                let c = self.vec3()?;
                self.accept_sym(",")?;
                let r = self.float()?;
                if r <= 0.0 {
                    return self.err(t.pos, format!("a black_hole's radius must be > 0, got {}", crate::limits::fmt_number(r)));
                }
                w.insert("center".into(), vec(c));
                w.insert("radius".into(), num(r));
            }
            "planar" => {
                if !self.peek()?.is_some_and(|t| t.tok == Tok::Sym("}")) {
                    let o = self.vec3()?;
                    w.insert("orientation".into(), vec(o));
                    if self.accept_sym(",")? {
                        let offset = self.float()?;
                        w.insert("offset".into(), num(offset));
                    }
                }
            }
            "cylindrical" | "spherical" | "toroidal" => {}
            "cubic" => {
                self.warnings.push(format!("{}: the cubic warp is not supported yet; it is left out", self.loc(pos)));
                return self.skip_to_brace();
            }
            other => return self.err(t.pos, format!("`{other}` is not a warp; warps are turbulence, repeat, black_hole, cylindrical, spherical, toroidal, planar and cubic")),
        }
        // The warp's modifiers.
        loop {
            let m = self.expect_any("`}`")?;
            let word = match m.tok {
                Tok::Sym("}") => break,
                Tok::Word(word) => word,
                other => {
                    return self
                        .err(m.pos, format!("expected a {kind} warp's modifier or `}}`, found {}", describe(&other)))
                }
            };
            match (kind.as_str(), word.as_str()) {
                ("turbulence", "octaves" | "omega" | "lambda") => {
                    let mut unused = DMat4::IDENTITY;
                    self.pattern_field(&word, m.pos, fields, &mut unused)?;
                }
                ("repeat", "offset" | "flip")
                | ("black_hole", "repeat")
                | ("cylindrical" | "spherical" | "toroidal", "orientation") => {
                    let v = self.vec3()?;
                    let v = if kind == "black_hole" { v.abs() } else { v };
                    w.insert(word.clone(), vec(v));
                }
                ("black_hole", "strength" | "falloff")
                | ("cylindrical" | "spherical" | "toroidal", "dist_exp")
                | ("toroidal", "major_radius") => {
                    let v = self.float()?;
                    w.insert(word.clone(), num(v));
                }
                ("black_hole", "inverse") => {
                    w.insert("inverse".into(), toml::Value::Boolean(true));
                }
                ("black_hole", "turbulence") => {
                    // POV-Ray moves each repeated hole by its own random numbers; not reproduced.
                    self.vec3()?;
                    self.warnings.push(format!(
                        "{}: a black_hole's turbulence (random offsets of its copies) is not supported yet; the copies stay in place",
                        self.loc(m.pos)
                    ));
                }
                ("black_hole", "type") => {
                    self.float()?;
                }
                _ => return self.err(m.pos, format!("`{word}` does not belong in a {kind} warp")),
            }
        }
        if kind == "turbulence" {
            return Ok(());
        }
        // The transforms written before the warp place the pattern it acts on.
        let Some((scale, rotate, translate)) = super::emit::decompose(xform) else {
            self.warnings.push(format!(
                "{}: the transforms before this {kind} warp shear the pattern, which a warp's transform cannot take yet; the warp is left out",
                self.loc(pos)
            ));
            return Ok(());
        };
        let mut tr = toml::Table::new();
        if !scale.abs_diff_eq(DVec3::ONE, 1e-12) {
            tr.insert("scale".into(), vec(scale));
        }
        if !rotate.abs_diff_eq(DVec3::ZERO, 1e-12) {
            tr.insert("rotate".into(), vec(rotate));
        }
        if translate != DVec3::ZERO {
            tr.insert("translate".into(), vec(translate));
        }
        if !tr.is_empty() {
            w.insert("transform".into(), toml::Value::Table(tr));
        }
        let mut list = match fields.iter().position(|(k, _)| k == "warp") {
            Some(i) => match fields.remove(i).1 {
                toml::Value::Array(a) => a,
                _ => Vec::new(),
            },
            None => Vec::new(),
        };
        if list.len() >= crate::cpu::pattern::MAX_WARPS as usize {
            self.warnings.push(format!(
                "{}: a pattern takes at most {} warps besides turbulence; this {kind} warp is left out",
                self.loc(pos),
                crate::cpu::pattern::MAX_WARPS
            ));
        } else {
            list.push(toml::Value::Table(w));
            *xform = DMat4::IDENTITY;
        }
        fields.push(("warp".into(), toml::Value::Array(list)));
        Ok(())
    }

    /// `normal { [declared normal] PATTERN [amount] [bump_size b] modifiers }`: a bump pattern,
    /// or `None` (with a warning) for one Photonix has no pattern for.
    pub fn normal(&mut self, pos: Pos) -> Result<Option<Normal>> {
        self.expect_sym("{")?;
        let mut n = Normal { pattern: String::new(), amount: 0.5, fields: Vec::new(), xform: DMat4::IDENTITY, pos };
        let mut other: Option<String> = None;
        let mut nested: Option<Normal> = None;
        loop {
            // A bare amount (`pigment_pattern { ... } 10`, `..., 0.5`) may follow any item.
            if self.accept_sym(",")? {
                continue;
            }
            if self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Num(_) | Tok::Sym("-") | Tok::Sym("(")))
                || (self.starts_float()? && (!n.pattern.is_empty() || other.is_some()))
            {
                n.amount = self.float()?;
                continue;
            }
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => break,
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a normal item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                n.xform = m * n.xform;
                continue;
            }
            if self.pattern_field(&w, tpos, &mut n.fields, &mut n.xform)? {
                continue;
            }
            match w.as_str() {
                "bump_size" => n.amount = self.float()?,
                "accuracy" | "control0" | "control1" | "coords" | "size" => {
                    self.float()?;
                }
                "interior" | "exterior" => {
                    // A fractal pattern's interior and exterior types.
                    self.float()?;
                    if self.accept_sym(",")? {
                        self.float()?;
                    }
                }
                "normal" => {
                    // A checker's, brick's or hexagon's normals: the first stands in.
                    let inner = self.normal(tpos)?;
                    nested = nested.or(inner);
                }
                "average" => other = Some(w.clone()),
                "no_bump_scale" | "uv_mapping" => {}
                "slope_map" | "normal_map" => self.skip_block()?,
                "gradient" => {
                    n.pattern = w.clone();
                    let v = self.vec3()?;
                    n.fields.push(("direction".into(), toml::Value::Array(vec![num(v.x), num(v.y), num(v.z)])));
                    self.accept_sym(",")?;
                    if self.starts_float()? {
                        n.amount = self.float()?;
                    }
                }
                _ if PATTERNS.contains(&w.as_str()) => {
                    n.pattern = w.clone();
                    self.accept_sym(",")?;
                    if self.starts_float()? {
                        n.amount = self.float()?;
                    }
                }
                "bump_map" | "pigment_pattern" | "image_pattern" => {
                    other = Some(w.clone());
                    self.skip_block()?;
                }
                _ if OTHER_PATTERNS.contains(&w.as_str()) || matches!(w.as_str(), "quilted" | "facets") => {
                    other = Some(w.clone());
                    // The pattern's arguments: a vector, a float, a block.
                    while self.peek()?.is_some_and(|t| matches!(t.tok, Tok::Sym("<") | Tok::Num(_) | Tok::Sym(","))) {
                        if !self.accept_sym(",")? {
                            self.expr()?;
                        }
                    }
                    if self.peek()?.is_some_and(|t| t.tok == Tok::Sym("{")) {
                        self.skip_block()?;
                    }
                }
                _ => match self.lookup(&w).cloned().map(|v| self.postfix(v)).transpose()? {
                    Some(Value::Normal(base)) => n = Normal { pos, ..*base },
                    Some(Value::Other("a normal")) => other = Some("declared".into()),
                    Some(v) => return self.err(tpos, format!("`{w}` is {}, not a normal", v.kind())),
                    None => return self.err(tpos, format!("`{w}` does not belong in a normal")),
                },
            }
        }
        if matches!(n.pattern.as_str(), "checker" | "brick" | "hexagon") && nested.is_some() {
            return Ok(nested);
        }
        if let Some(o) = other {
            if o != "declared" {
                self.warnings.push(format!(
                    "{}: the {o} normal is not supported yet; the surface is left smooth",
                    self.loc(pos)
                ));
            }
            return Ok(None);
        }
        Ok((!n.pattern.is_empty()).then_some(n))
    }

    /// `pigment_map { [v pigment-body] ... }`: each entry's pigment by its mean colour, a
    /// colour map (docs/pov-ray.md).
    /// `pigment_map { [v pigment-body] ... }`: each entry's pigment at its value.
    fn pigment_map(&mut self, pos: Pos) -> Result<Vec<(f64, Pigment)>> {
        self.expect_sym("{")?;
        let mut map = Vec::new();
        loop {
            if self.accept_sym("}")? {
                return Ok(map);
            }
            let epos = self.here();
            self.expect_sym("[")?;
            // average's entries may leave out their weight.
            let v = if self.starts_float()? { self.float()? } else { map.len() as f64 };
            self.accept_sym(",")?;
            if self.peek_word()?.as_deref() == Some("function") {
                // A pattern of a user-defined function: grey stands in.
                self.warnings.push(format!(
                    "{}: a function pattern (user-defined functions) is not supported yet; grey stands in",
                    self.loc(epos)
                ));
                self.skip_entry(&["]"])?;
                map.push((v, Pigment::solid([0.5, 0.5, 0.5, 0.0, 0.0], epos)));
                continue;
            }
            let p = self.pigment_body(epos, "]")?;
            map.push((v, p));
            if map.len() > 256 {
                return self.err(pos, "a pigment_map has at most 256 entries".into());
            }
        }
    }

    /// `image_map { [type] "file" [map_type 0|1|2] [once] [interpolate n] [filter/transmit all|i v] }`:
    /// the image's mean colour, filter all / transmit all, and, when Photonix can project the
    /// image itself (a PNG, JPEG, OpenEXR or HDR file; map_type 0, 1 or 2), (file for the TOML,
    /// projection, once). Otherwise the mean colour stands in, with a warning.
    #[allow(clippy::type_complexity)]
    fn image_map(&mut self, pos: Pos) -> Result<(Colour, [Option<f64>; 2], Option<(String, &'static str, bool)>)> {
        self.expect_sym("{")?;
        let mut ft = [None, None];
        let mut mean = None;
        let mut file: Option<(String, std::path::PathBuf)> = None;
        let mut map_type = 0.0;
        let mut once = false;
        let mut use_index = false;
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            match t.tok {
                Tok::Sym("}") => break,
                Tok::Word(w) if super::image::FORMATS.contains(&w.as_str()) => {
                    let fpos = self.here();
                    let name = self.image_name()?;
                    mean = Some(self.image_mean(&w, &name, fpos)?);
                    file = Some((w.clone(), self.find_image(&name, fpos)?));
                }
                Tok::Str(name) => {
                    mean = Some(self.image_mean("", &name, tpos)?);
                    file = Some((String::new(), self.find_image(&name, tpos)?));
                }
                Tok::Word(w) if w == "once" => once = true,
                Tok::Word(w) if w == "use_index" => use_index = true,
                Tok::Word(w) if w == "use_color" || w == "use_colour" => {}
                Tok::Word(w) if w == "map_type" => map_type = self.float()?,
                Tok::Word(w) if w == "interpolate" || w == "gamma" || w == "premultiplied" => {
                    if w == "gamma" && self.accept_word("srgb")? {
                        continue;
                    }
                    self.float()?;
                }
                Tok::Word(w) if w == "filter" || w == "transmit" => {
                    let i = if w == "filter" { 0 } else { 1 };
                    if self.accept_word("all")? {
                        ft[i] = Some(self.float()?);
                    } else {
                        // filter i v: one palette entry; not kept.
                        self.float()?;
                        self.accept_sym(",")?;
                        self.float()?;
                    }
                }
                other => {
                    return self.err(tpos, format!("expected an image_map item or `}}`, found {}", describe(&other)))
                }
            }
        }
        let (Some(mean), Some((kind, path))) = (mean, file) else {
            return self
                .err(pos, "this image_map names no image file; give one: image_map { png \"file.png\" }".into());
        };
        let projection = match map_type.round() as i64 {
            0 => Some("planar"),
            1 => Some("spherical"),
            2 => Some("cylindrical"),
            _ => None,
        };
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let readable = match kind.as_str() {
            "png" | "jpeg" | "exr" | "hdr" | "gif" => true,
            // TGA has no signature: the image texture reads it by its extension.
            "tga" => extension == "tga",
            "" => matches!(extension.as_str(), "png" | "jpg" | "jpeg" | "exr" | "hdr" | "gif" | "tga"),
            _ => false,
        };
        let file = self.image_file_for_toml(&path);
        let at = self.loc(pos);
        match (projection, readable, file) {
            (Some(projection), true, Some(file)) => {
                if use_index {
                    self.warnings
                        .push(format!("{at}: image_map: use_index is not supported; the image's colours are used"));
                }
                Ok((mean, ft, Some((file, projection, once))))
            }
            (None, ..) => {
                self.warnings.push(format!(
                    "{at}: image_map: map_type {map_type} is not supported (0 planar, 1 spherical and 2 cylindrical are); the image's mean colour stands in"
                ));
                Ok((mean, ft, None))
            }
            _ => {
                self.warnings.push(format!(
                    "{at}: image_map: Photonix reads PNG, JPEG, OpenEXR, HDR, GIF and TGA images (TGA named `.tga`), not this one; the image's mean colour stands in"
                ));
                Ok((mean, ft, None))
            }
        }
    }

    /// An image's path as the translated TOML names it: relative to the scene's folder when it
    /// lies in it, else absolute; `None` when it is not UTF-8.
    fn image_file_for_toml(&self, path: &std::path::Path) -> Option<String> {
        let folder = self.files.first().and_then(|f| f.parent()).unwrap_or(std::path::Path::new(""));
        let path = match path.strip_prefix(folder) {
            Ok(relative) if !folder.as_os_str().is_empty() => relative.to_path_buf(),
            _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        };
        path.to_str().map(str::to_string)
    }

    /// An image's file name: a string expression.
    fn image_name(&mut self) -> Result<String> {
        self.string()
    }

    fn find_image(&self, name: &str, pos: Pos) -> Result<std::path::PathBuf> {
        self.find_include(name, pos).map_err(|e| PovError { message: e.message.replacen("#include", "image", 1), ..e })
    }

    /// The mean colour of an image, in the file's colour convention (linear values raised to
    /// 1 / assumed_gamma, so that emit's gamma rule gives the linear mean back).
    fn image_mean(&mut self, kind: &str, name: &str, pos: Pos) -> Result<Colour> {
        let path = self.find_image(name, pos)?;
        let rgb = super::image::mean_colour(&path, kind).map_err(|m| PovError::at(pos, m))?;
        let g = self.scene.assumed_gamma.filter(|g| *g > 0.0).unwrap_or(1.0);
        Ok([rgb[0].powf(1.0 / g), rgb[1].powf(1.0 / g), rgb[2].powf(1.0 / g), 0.0, 0.0])
    }

    /// Whether the next token starts a colour (a colour keyword, a number, a vector, a declared colour).
    fn starts_colour(&mut self) -> Result<bool> {
        Ok(match self.peek()?.map(|t| t.tok) {
            Some(Tok::Word(w)) => {
                matches!(w.as_str(), "color" | "colour" | "rgb" | "rgbf" | "rgbt" | "rgbft" | "srgb")
                    || matches!(self.lookup(&w), Some(Value::Vector(_)))
            }
            Some(Tok::Sym("<")) | Some(Tok::Num(_)) => true,
            _ => false,
        })
    }

    fn word_colour(&mut self, w: &str, _pos: Pos) -> Result<Colour> {
        // The keyword is consumed: read the rest as `color` would.
        let mut c = [0.0; 5];
        let v = match w {
            "color" | "colour" => return self.colour(),
            _ => {
                let v = self.expr()?;
                super::parser::to_colour(v, self.here(), self)?
            }
        };
        let n = match w.trim_start_matches('s') {
            "rgb" => 3,
            "rgbf" | "rgbt" => 4,
            _ => 5,
        };
        c[..3].copy_from_slice(&v[..3]);
        if n >= 4 {
            if w.ends_with("rgbt") {
                c[4] = v[3];
            } else {
                c[3] = v[3];
            }
        }
        if n == 5 {
            c[4] = v[4];
        }
        // Trailing `filter 0.5` / `transmit 0.5`.
        loop {
            match self.peek_word()?.as_deref() {
                Some("filter") => {
                    self.next()?;
                    c[3] = self.float()?;
                }
                Some("transmit") => {
                    self.next()?;
                    c[4] = self.float()?;
                }
                _ => return Ok(c),
            }
        }
    }

    pub fn colour_map(&mut self) -> Result<Vec<(f64, Colour)>> {
        self.expect_sym("{")?;
        let mut map = Vec::new();
        loop {
            if self.accept_sym("}")? {
                return Ok(map);
            }
            if let Some(w) = self.peek_word()? {
                if let Some(Value::ColorMap(m)) = self.lookup(&w).cloned() {
                    self.next()?;
                    map = m;
                    continue;
                }
            }
            self.expect_sym("[")?;
            let a = self.float()?;
            self.accept_sym(",")?;
            if self.starts_float()? {
                // The old form: [a b color c1 color c2].
                let b = self.float()?;
                let c1 = self.colour()?;
                let c2 = self.colour()?;
                map.push((a, c1));
                map.push((b, c2));
            } else {
                map.push((a, self.colour()?));
            }
            self.expect_sym("]")?;
            if map.len() > 256 {
                return self.err(self.here(), "a color_map has at most 256 entries".into());
            }
        }
    }

    pub fn finish(&mut self) -> Result<Finish> {
        self.expect_sym("{")?;
        let mut f = self.default_finish.clone();
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(f),
                Tok::Word(w) => w,
                other => return self.err(pos, format!("expected a finish item or `}}`, found {}", describe(&other))),
            };
            let rgb = |c: Colour| [c[0], c[1], c[2]];
            match w.as_str() {
                "ambient" => f.ambient = rgb(self.colour()?),
                "emission" => f.emission = rgb(self.colour()?),
                "diffuse" => {
                    self.accept_word("albedo")?;
                    f.diffuse = self.float()?;
                    if self.accept_sym(",")? {
                        self.float()?;
                    }
                }
                "phong" => {
                    self.accept_word("albedo")?;
                    f.phong = self.float()?;
                }
                "specular" => {
                    self.accept_word("albedo")?;
                    f.specular = self.float()?;
                }
                "phong_size" => f.phong_size = self.float()?,
                "roughness" => f.roughness = self.float()?,
                "metallic" => {
                    f.metallic = 1.0;
                    if self.starts_float()? {
                        f.metallic = self.float()?;
                    }
                }
                "reflection" => {
                    if self.accept_sym("{")? {
                        // reflection { [min,] max [fresnel] [falloff f] [exponent e] [metallic m] }
                        let mut first = true;
                        loop {
                            if self.accept_sym("}")? {
                                break;
                            }
                            match self.peek_word()?.as_deref() {
                                Some("fresnel") => {
                                    self.next()?;
                                    if self.starts_float()? {
                                        self.float()?;
                                    }
                                }
                                Some("falloff") | Some("exponent") => {
                                    self.next()?;
                                    self.float()?;
                                }
                                Some("metallic") => {
                                    self.next()?;
                                    f.metallic = 1.0;
                                    if self.starts_float()? {
                                        f.metallic = self.float()?;
                                    }
                                }
                                _ => {
                                    let c = rgb(self.colour()?);
                                    self.accept_sym(",")?;
                                    // With two colours, the second (the maximum) is kept.
                                    if first || c != [0.0; 3] {
                                        f.reflection = c;
                                    }
                                    first = false;
                                }
                            }
                        }
                    } else {
                        f.reflection = rgb(self.colour()?);
                    }
                }
                "brilliance" | "crand" | "reflection_exponent" => {
                    self.float()?;
                }
                "conserve_energy" => {}
                "irid" | "subsurface" => self.skip_block()?,
                _ => match self.lookup(&w).cloned() {
                    Some(Value::Finish(base)) => f = base,
                    _ => return self.err(pos, format!("`{w}` does not belong in a finish")),
                },
            }
        }
    }

    pub fn interior(&mut self) -> Result<Interior> {
        self.expect_sym("{")?;
        let mut i = Interior { ior: 1.0, media: Vec::new(), fade_distance: 0.0, fade_colour: [0.0; 3] };
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(i),
                Tok::Word(w) => w,
                other => {
                    return self.err(pos, format!("expected an interior item or `}}`, found {}", describe(&other)))
                }
            };
            match w.as_str() {
                "ior" => i.ior = self.float()?,
                "caustics" | "dispersion" | "dispersion_samples" | "fade_power" => {
                    self.float()?;
                }
                "fade_distance" => i.fade_distance = self.float()?,
                "fade_color" | "fade_colour" => {
                    let c = self.colour()?;
                    i.fade_colour = [c[0], c[1], c[2]];
                }
                "media" => {
                    let m = self.media(pos)?;
                    i.media.push(m);
                }
                _ => match self.lookup(&w).cloned() {
                    Some(Value::Interior(base)) => i = base,
                    _ => return self.err(pos, format!("`{w}` does not belong in an interior")),
                },
            }
        }
    }

    fn material(&mut self) -> Result<(Vec<Tex>, Option<Interior>)> {
        self.expect_sym("{")?;
        let (mut tex, mut int) = (Vec::new(), None);
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok((tex, int)),
                Tok::Word(w) => w,
                other => return self.err(pos, format!("expected a material item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                tex.iter_mut().for_each(|l: &mut Tex| l.xform = m * l.xform);
                continue;
            }
            match w.as_str() {
                "texture" => tex.extend(self.texture()?),
                "interior" => int = Some(self.interior()?),
                "interior_texture" => self.skip_block()?,
                _ => match self.lookup(&w).cloned().map(|v| self.postfix(v)).transpose()? {
                    Some(Value::Material(t, i)) => {
                        tex = t;
                        int = i;
                    }
                    _ => return self.err(pos, format!("`{w}` does not belong in a material")),
                },
            }
        }
    }

    /// `#default { texture { ... } }`, `#default { finish { ... } }`, `#default { pigment { ... } }`.
    pub fn default_block(&mut self) -> Result<()> {
        self.expect_sym("{")?;
        loop {
            let t = self.expect_any("`}`")?;
            let pos = t.pos;
            match t.tok {
                Tok::Sym("}") => return Ok(()),
                Tok::Word(w) if w == "finish" => self.default_finish = self.finish()?,
                Tok::Word(w) if w == "pigment" => self.default_pigment = Some(self.pigment(pos)?),
                Tok::Word(w) if w == "texture" => {
                    let layers = self.texture()?;
                    if let Some(l) = layers.last() {
                        self.default_finish = l.finish.clone();
                        self.default_pigment = Some(l.pigment.clone());
                    }
                }
                Tok::Word(w) if w == "normal" => self.skip_block()?,
                other => {
                    return self.err(
                        pos,
                        format!("expected texture, pigment or finish in #default, found {}", describe(&other)),
                    )
                }
            }
        }
    }

    // -------------------------------------------------------------------------------------------
    // Camera, lights, atmosphere

    fn camera(&mut self, pos: Pos) -> Result<Camera> {
        self.expect_sym("{")?;
        let mut c = Camera { pos, ..Camera::default() };
        if let Some(w) = self.peek_word()? {
            if let Some(Value::Camera(base)) = self.lookup(&w).cloned() {
                self.next()?;
                c = *base;
                c.pos = pos;
            }
        }
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(c),
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a camera item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                c.location = m.transform_point3(c.location);
                c.direction = m.transform_vector3(c.direction);
                c.right = m.transform_vector3(c.right);
                c.up = m.transform_vector3(c.up);
                if let Some(f) = &mut c.focal_point {
                    *f = m.transform_point3(*f);
                }
                continue;
            }
            match w.as_str() {
                "perspective" => c.orthographic = false,
                "orthographic" => c.orthographic = true,
                "fisheye" | "ultra_wide_angle" | "omnimax" | "panoramic" | "cylinder" | "spherical" | "mesh_camera" => {
                    return self
                        .err(tpos, format!("the {w} camera is not supported yet; use perspective or orthographic"));
                }
                "location" => c.location = self.vec3()?,
                "direction" => c.direction = self.vec3()?,
                "right" => c.right = self.vec3()?,
                "up" => c.up = self.vec3()?,
                "sky" => c.sky = self.vec3()?,
                "angle" => {
                    let a = self.float()?;
                    if self.starts_float()? {
                        self.float()?;
                    }
                    if !(a > 0.0 && a < 180.0) {
                        return self.err(tpos, format!("camera angle {a} must be between 0 and 180 degrees"));
                    }
                    if !c.orthographic {
                        // |direction| = 0.5 |right| / tan(angle / 2) (POV-Ray's reference manual).
                        let len = 0.5 * c.right.length() / (a.to_radians() / 2.0).tan();
                        c.direction = c.direction.normalize_or(DVec3::Z) * len;
                        c.ortho_angle = None;
                    } else {
                        // An orthographic camera with an angle sees as wide as a perspective one
                        // would at the look_at distance, which may come later: emit sizes it.
                        c.ortho_angle = Some(a);
                    }
                }
                "look_at" => {
                    let lpos = self.here();
                    let at = self.vec3()?;
                    // POV-Ray refuses this too ("camera location and look_at point must be
                    // different"); the direction would be made up.
                    let apart = (at - c.location).length();
                    let scale = at.abs().max_element().max(c.location.abs().max_element());
                    if apart.is_nan() || apart <= scale * 1e-12 {
                        return self.err(
                            lpos,
                            "the camera's look_at is its location; POV-Ray refuses this too: move one of them".into(),
                        );
                    }
                    // POV-Ray keeps the lengths of direction, right and up and turns them.
                    let (ld, lr, lu) = (c.direction.length(), c.right.length(), c.up.length());
                    // POV-Ray's test (parse.cpp): up x direction . right > 0 keeps right as the
                    // sky makes it; 0 (up along direction: `up z` with the default direction)
                    // or less turns it around.
                    let handed = c.up.cross(c.direction).dot(c.right) > 0.0;
                    let d = (at - c.location).normalize_or(DVec3::Z);
                    let mut r = c.sky.cross(d).normalize_or(DVec3::X);
                    if !handed {
                        r = -r;
                    }
                    let u = d.cross(r).normalize_or(DVec3::Y) * if handed { 1.0 } else { -1.0 };
                    c.look_at = Some(at);
                    c.direction = d * ld;
                    c.right = r * lr;
                    c.up = u * lu;
                }
                "aperture" => c.aperture = self.float()?,
                "focal_point" => c.focal_point = Some(self.vec3()?),
                "blur_samples" => {
                    c.blur_samples = self.float()? as i64;
                    if self.accept_sym(",")? {
                        c.blur_samples = self.float()? as i64;
                    }
                }
                "confidence" | "variance" => {
                    self.float()?;
                }
                "normal" => self.skip_block()?,
                _ => return self.err(tpos, format!("`{w}` does not belong in a camera")),
            }
        }
    }

    fn light(&mut self, pos: Pos) -> Result<Light> {
        self.expect_sym("{")?;
        // `light_source { Declared modifiers }`: a copy of a declared light, then its
        // modifiers (the radiosity Cornell box places its declared patch nine times so).
        let mut base = None;
        if let Some(w) = self.peek_word()? {
            if let Some(Value::Object(o)) = self.lookup(&w) {
                match &o.kind {
                    ObjKind::Light(l) => base = Some((**l).clone()),
                    _ => {
                        let wpos = self.peek()?.map_or(pos, |t| t.pos);
                        return self.err(wpos, format!("`{w}` is a declared object, not a light_source"));
                    }
                }
                self.next()?;
            }
        }
        let mut l = match base {
            Some(mut l) => {
                l.pos = pos;
                l
            }
            None => {
                let position = self.vec3()?;
                self.accept_sym(",")?;
                let c = self.colour()?;
                Light {
                    position,
                    colour: [c[0], c[1], c[2]],
                    kind: LightKind::Point,
                    area: None,
                    fade_distance: 0.0,
                    fade_power: 0.0,
                    shadowless: false,
                    looks_like: None,
                    pos,
                }
            }
        };
        let (mut point_at, mut radius, mut falloff, mut tightness) = (DVec3::ZERO, 30.0, 45.0, 0.0);
        let mut spot = 0;
        match l.kind {
            LightKind::Spot { point_at: p, radius: r, falloff: f, tightness: t } => {
                (point_at, radius, falloff, tightness, spot) = (p, r, f, t, 1);
            }
            LightKind::Parallel { point_at: p } => (point_at, spot) = (p, 2),
            LightKind::Point => {}
        }
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => break,
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a light item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                l.position = m.transform_point3(l.position);
                point_at = m.transform_point3(point_at);
                if let Some(a) = &mut l.area {
                    a.axis1 = m.transform_vector3(a.axis1);
                    a.axis2 = m.transform_vector3(a.axis2);
                }
                if let Some(o) = &mut l.looks_like {
                    transform_obj(o, &m);
                }
                continue;
            }
            match w.as_str() {
                "spotlight" => spot = 1,
                "parallel" => spot = 2,
                "cylinder" => {
                    return self.err(tpos, "cylinder lights are not supported yet; use spotlight".into());
                }
                "point_at" => point_at = self.vec3()?,
                "radius" => radius = self.float()?,
                "falloff" => falloff = self.float()?,
                "tightness" => tightness = self.float()?,
                "area_light" => {
                    let axis1 = self.vec3()?;
                    self.accept_sym(",")?;
                    let axis2 = self.vec3()?;
                    self.accept_sym(",")?;
                    let n1 = self.float()?;
                    self.accept_sym(",")?;
                    let n2 = self.float()?;
                    let clamp = |n: f64| n.round().clamp(1.0, 64.0) as u32;
                    l.area = Some(AreaLight { axis1, axis2, n1: clamp(n1), n2: clamp(n2), adaptive: 0, jitter: false });
                }
                "adaptive" => {
                    let a = self.float()?;
                    if let Some(area) = &mut l.area {
                        area.adaptive = a.max(0.0) as u32;
                    }
                }
                "jitter" => {
                    self.optional_bool()?;
                    if let Some(area) = &mut l.area {
                        area.jitter = true;
                    }
                }
                "circular" | "orient" => {}
                "area_illumination" | "shadowless" | "media_interaction" | "media_attenuation" => {
                    let on = self.optional_bool()?;
                    if w == "shadowless" {
                        l.shadowless = on;
                    }
                }
                "fade_distance" => l.fade_distance = self.float()?,
                "fade_power" => l.fade_power = self.float()?,
                "looks_like" => {
                    if l.looks_like.is_some() {
                        return self.err(tpos, "only one looks_like is allowed in a light_source".into());
                    }
                    // `looks_like { OBJECT modifiers }` reads as `object { ... }` does; POV-Ray
                    // then moves the object to where the light is (parse.cpp, Parse_Light_Source).
                    let mut o = self.object("object", tpos)?;
                    if matches!(o.kind, ObjKind::Light(_)) {
                        return self.err(tpos, "a light_source cannot look like another light_source".into());
                    }
                    transform_obj(&mut o, &DMat4::from_translation(l.position));
                    l.looks_like = Some(Box::new(o));
                }
                "projected_through" | "photons" => self.skip_block()?,
                "color" | "colour" | "rgb" => {
                    let c = self.word_colour(&w, tpos)?;
                    l.colour = [c[0], c[1], c[2]];
                }
                _ => return self.err(tpos, format!("`{w}` does not belong in a light_source")),
            }
        }
        l.kind = match spot {
            1 => LightKind::Spot { point_at, radius, falloff, tightness },
            2 => LightKind::Parallel { point_at },
            _ => LightKind::Point,
        };
        Ok(l)
    }

    fn fog(&mut self, pos: Pos) -> Result<Fog> {
        self.expect_sym("{")?;
        let mut f =
            Fog { ground: false, distance: 0.0, colour: [0.0; 5], offset: 0.0, alt: 0.0, turbulence: None, pos };
        loop {
            // A declared colour, possibly in an expression (`Wheat * 0.5`).
            if let Some(w) = self.peek_word()? {
                if matches!(self.lookup(&w), Some(Value::Vector(_)) | Some(Value::Float(_))) {
                    f.colour = self.colour()?;
                    continue;
                }
            }
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(f),
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a fog item or `}}`, found {}", describe(&other))),
            };
            if self.transform_word(&w)?.is_some() {
                continue;
            }
            match w.as_str() {
                "fog_type" => f.ground = self.float()? == 2.0,
                "distance" => f.distance = self.float()?,
                "color" | "colour" | "rgb" | "rgbf" | "rgbt" | "rgbft" => f.colour = self.word_colour(&w, tpos)?,
                "fog_offset" => f.offset = self.float()?,
                "fog_alt" => f.alt = self.float()?,
                "turbulence" => f.turbulence = Some(self.vec3()?),
                "octaves" | "omega" | "lambda" | "turb_depth" => {
                    self.float()?;
                }
                "up" => {
                    self.vec3()?;
                }
                _ => return self.err(tpos, format!("`{w}` does not belong in a fog")),
            }
        }
    }

    /// `media { ... }` (POV-Ray's reference manual, "Media"): absorption, emission, scattering
    /// and the first density; the sampling controls are read and not needed.
    pub fn media(&mut self, pos: Pos) -> Result<Media> {
        self.expect_sym("{")?;
        let mut m = Media {
            absorption: [0.0; 3],
            emission: [0.0; 3],
            scattering: [0.0; 3],
            g: 0.0,
            density: None,
            xform: DMat4::IDENTITY,
            pos,
        };
        let rgb = |c: Colour| [c[0], c[1], c[2]];
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(m),
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a media item or `}}`, found {}", describe(&other))),
            };
            if let Some(x) = self.transform_word(&w)? {
                m.xform = x * m.xform;
                continue;
            }
            match w.as_str() {
                "absorption" => m.absorption = rgb(self.colour()?),
                "emission" => m.emission = rgb(self.colour()?),
                "scattering" => {
                    self.expect_sym("{")?;
                    let kind = self.float()?;
                    self.accept_sym(",")?;
                    m.scattering = rgb(self.colour()?);
                    // Photonix has no Mie tables: hazy and murky Mie become Henyey-Greenstein
                    // with about their forward peaks; Rayleigh is symmetric, taken as isotropic.
                    m.g = match kind.round() as i64 {
                        1 | 4 => 0.0,
                        2 => 0.6,
                        3 => 0.8,
                        5 => 0.0,
                        k => {
                            return self.err(
                                tpos,
                                format!("scattering type {k} is not one of POV-Ray's 1 to 5 (isotropic, Mie hazy, Mie murky, Rayleigh, Henyey-Greenstein)"),
                            )
                        }
                    };
                    loop {
                        let t = self.expect_any("`}`")?;
                        match t.tok {
                            Tok::Sym("}") => break,
                            Tok::Word(w) if w == "eccentricity" => {
                                let e = self.float()?;
                                if kind.round() as i64 == 5 {
                                    m.g = e.clamp(-0.99, 0.99);
                                }
                            }
                            Tok::Word(w) if w == "extinction" => {
                                self.float()?;
                            }
                            other => {
                                return self.err(
                                    t.pos,
                                    format!("expected eccentricity, extinction or `}}`, found {}", describe(&other)),
                                )
                            }
                        }
                    }
                }
                "density" => {
                    self.expect_sym("{")?;
                    let d = self.pigment_body(tpos, "}")?;
                    if m.density.is_some() {
                        self.warnings.push(format!(
                            "{}: a second density is left out (POV-Ray multiplies them; Photonix takes one)",
                            self.loc(tpos)
                        ));
                    } else {
                        m.density = Some(d);
                    }
                }
                "method" | "intervals" | "confidence" | "variance" | "ratio" | "jitter" | "aa_level"
                | "aa_threshold" | "collect" => {
                    self.float()?;
                }
                "samples" => {
                    self.float()?;
                    if self.accept_sym(",")? {
                        self.float()?;
                    }
                }
                _ => match self.lookup(&w).cloned() {
                    Some(Value::Media(base)) => m = Media { pos, ..*base },
                    _ => return self.err(tpos, format!("`{w}` does not belong in a media")),
                },
            }
        }
    }

    /// `sky_sphere { pigment { ... } ... [emission c] transforms }`.
    fn sky_sphere(&mut self, pos: Pos) -> Result<SkySphere> {
        self.expect_sym("{")?;
        let mut sky = SkySphere { pigments: Vec::new(), xform: DMat4::IDENTITY, emission: [1.0; 3], pos };
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(sky),
                Tok::Word(w) => w,
                other => {
                    return self.err(tpos, format!("expected a sky_sphere item or `}}`, found {}", describe(&other)))
                }
            };
            if let Some(m) = self.transform_word(&w)? {
                sky.xform = m * sky.xform;
                continue;
            }
            match w.as_str() {
                "pigment" => {
                    let p = self.pigment(tpos)?;
                    sky.pigments.push(p);
                }
                "emission" => {
                    let c = self.colour()?;
                    sky.emission = [c[0], c[1], c[2]];
                }
                _ => match self.lookup(&w).cloned() {
                    Some(Value::Sky(base)) => sky = SkySphere { pos, ..*base },
                    Some(Value::Other(_)) | None => {
                        return self.err(tpos, format!("`{w}` does not belong in a sky_sphere"));
                    }
                    Some(v) => return self.err(tpos, format!("`{w}` is {}; a sky_sphere takes pigments", v.kind())),
                },
            }
        }
    }

    /// `rainbow { direction d angle a width w distance r jitter j color_map { ... } [up u]
    /// [arc_angle a] [falloff_angle f] }`.
    fn rainbow(&mut self, pos: Pos) -> Result<Rainbow> {
        self.expect_sym("{")?;
        let mut r = Rainbow {
            direction: DVec3::Z,
            angle: 42.5,
            width: 5.0,
            map: Vec::new(),
            up: None,
            arc_angle: None,
            falloff_angle: None,
            pos,
        };
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(r),
                Tok::Word(w) => w,
                other => return self.err(tpos, format!("expected a rainbow item or `}}`, found {}", describe(&other))),
            };
            if let Some(m) = self.transform_word(&w)? {
                r.direction = m.transform_vector3(r.direction);
                r.up = r.up.map(|u| m.transform_vector3(u));
                continue;
            }
            match w.as_str() {
                "direction" => r.direction = self.vec3()?,
                "angle" => r.angle = self.float()?,
                "width" => r.width = self.float()?,
                "up" => r.up = Some(self.vec3()?),
                "arc_angle" => r.arc_angle = Some(self.float()?),
                "falloff_angle" => r.falloff_angle = Some(self.float()?),
                "distance" | "jitter" => {
                    // The bow is at infinity here (docs/scene-format.md, "rainbow").
                    self.float()?;
                }
                "color_map" | "colour_map" => r.map = self.colour_map()?,
                _ => match self.lookup(&w).cloned() {
                    Some(Value::ColorMap(m)) => r.map = m,
                    _ => return self.err(tpos, format!("`{w}` does not belong in a rainbow")),
                },
            }
        }
    }

    fn global_settings(&mut self) -> Result<()> {
        self.expect_sym("{")?;
        loop {
            let t = self.expect_any("`}`")?;
            let tpos = t.pos;
            let w = match t.tok {
                Tok::Sym("}") => return Ok(()),
                Tok::Word(w) => w,
                other => {
                    return self.err(tpos, format!("expected a global setting or `}}`, found {}", describe(&other)))
                }
            };
            match w.as_str() {
                "assumed_gamma" => self.scene.assumed_gamma = Some(self.float()?),
                "max_trace_level" => self.scene.max_trace_level = Some(self.float()? as i64),
                "ambient_light" | "irid_wavelength" => {
                    self.colour()?;
                }
                "hf_gray_16" => {
                    self.optional_bool()?;
                }
                "adc_bailout" | "number_of_waves" | "max_intersections" | "noise_generator" => {
                    self.float()?;
                }
                "charset" => {
                    self.next()?;
                }
                // Photon and radiosity settings are hints: Photonix always maps photons.
                "photons" | "radiosity" | "subsurface" | "mm_per_unit" => {
                    if self.peek()?.is_some_and(|t| t.tok == Tok::Sym("{")) {
                        self.skip_block()?;
                    } else {
                        self.float()?;
                    }
                }
                _ => return self.err(tpos, format!("`{w}` is not a global setting this front-end knows")),
            }
        }
    }
}

/// Moves an object by `m` (world_from_object of the change), as POV-Ray's Transform_Object does:
/// CSG children one by one, and every texture given so far with its object.
/// The most cells a height field has along a side (docs/pov-ray.md).
pub const HF_MAX_CELLS: usize = 256;

/// A height field's closed surface (see `Parser::height_field`).
fn height_field_triangles(h: &super::image::Heights) -> Vec<Tri> {
    // Evenly spaced sample columns and rows, the first and last always among them.
    let picks = |n: usize| -> Vec<usize> {
        let cells = (n - 1).min(HF_MAX_CELLS);
        (0..=cells).map(|k| (k * (n - 1) + cells / 2) / cells).collect()
    };
    let (xs, rows) = (picks(h.width), picks(h.height));
    let x_of = |i: usize| i as f64 / (h.width - 1) as f64;
    let z_of = |j: usize| 1.0 - j as f64 / (h.height - 1) as f64;
    let p = |i: usize, j: usize| DVec3::new(x_of(i), h.values[j * h.width + i], z_of(j));
    let mut tris = Vec::with_capacity(2 * xs.len() * rows.len() + 8 * (xs.len() + rows.len()));
    for w in rows.windows(2) {
        for v in xs.windows(2) {
            let (a, b, c, d) = (p(v[0], w[0]), p(v[1], w[0]), p(v[0], w[1]), p(v[1], w[1]));
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    // Walls down to y = 0 along the four edges, and the floor.
    let floor = |q: DVec3| DVec3::new(q.x, 0.0, q.z);
    let mut wall = |edge: Vec<DVec3>| {
        for e in edge.windows(2) {
            // A triangle with a corner at height 0 on the floor has no area: left out.
            if e[0].y != 0.0 {
                tris.push([e[0], floor(e[0]), floor(e[1])]);
            }
            if e[1].y != 0.0 {
                tris.push([e[0], floor(e[1]), e[1]]);
            }
        }
    };
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let (left, right) = (xs[0], xs[xs.len() - 1]);
    wall(xs.iter().map(|&i| p(i, first)).collect());
    wall(xs.iter().map(|&i| p(i, last)).collect());
    wall(rows.iter().map(|&j| p(left, j)).collect());
    wall(rows.iter().map(|&j| p(right, j)).collect());
    let c = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 0.0, 1.0), DVec3::Z];
    tris.push([c[0], c[1], c[2]]);
    tris.push([c[0], c[2], c[3]]);
    tris
}

pub fn transform_obj(o: &mut Obj, m: &DMat4) {
    if let Some(layers) = &mut o.tex {
        layers.iter_mut().for_each(|l| l.xform = *m * l.xform);
    }
    if let Some(i) = &mut o.interior {
        i.media.iter_mut().for_each(|md| md.xform = *m * md.xform);
    }
    match &mut o.kind {
        ObjKind::Csg { children, .. } => children.iter_mut().for_each(|c| transform_obj(c, m)),
        ObjKind::Light(l) => {
            l.position = m.transform_point3(l.position);
            if let LightKind::Spot { point_at, .. } | LightKind::Parallel { point_at } = &mut l.kind {
                *point_at = m.transform_point3(*point_at);
            }
            if let Some(a) = &mut l.area {
                a.axis1 = m.transform_vector3(a.axis1);
                a.axis2 = m.transform_vector3(a.axis2);
            }
            if let Some(shape) = &mut l.looks_like {
                transform_obj(shape, m);
            }
        }
        _ => o.xform = *m * o.xform,
    }
}
