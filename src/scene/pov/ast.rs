//! What a POV-Ray scene holds once its language is evaluated: objects with their transforms and
//! textures, lights, the camera and the atmosphere, still in POV-Ray's left-handed coordinates.
//! `emit.rs` turns it into the TOML scene format.

use glam::{DMat4, DVec3};

use super::Pos;

/// A colour as POV-Ray holds it: red, green, blue, filter, transmit.
pub type Colour = [f64; 5];

#[derive(Clone, Debug)]
pub struct Obj {
    pub kind: ObjKind,
    /// world_from_object, POV-Ray coordinates. CSG nodes keep the identity: their transforms are
    /// pushed down to the children as POV-Ray does.
    pub xform: DMat4,
    /// The texture layers (first is the bottom); `None` inherits the parent's or the default.
    pub tex: Option<Vec<Tex>>,
    pub interior: Option<Interior>,
    /// `inverse`: inside and outside swapped (written as a difference in CSG, see `emit`).
    pub inverse: bool,
    pub pos: Pos,
}

/// POV-Ray's four CSG operations are the scene's own.
pub use crate::scene::CsgOp;

#[derive(Clone, Debug)]
pub enum ObjKind {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    Box {
        a: DVec3,
        b: DVec3,
    },
    Cylinder {
        a: DVec3,
        b: DVec3,
        radius: f64,
        open: bool,
    },
    Cone {
        a: DVec3,
        ra: f64,
        b: DVec3,
        rb: f64,
        open: bool,
    },
    Plane {
        normal: DVec3,
        offset: f64,
    },
    Disc {
        center: DVec3,
        normal: DVec3,
        radius: f64,
        hole: f64,
    },
    Torus {
        major: f64,
        minor: f64,
    },
    Superellipsoid {
        e: f64,
        n: f64,
    },
    /// Triangles of a triangle, smooth_triangle, mesh or tessellated shape, with their
    /// corners' normals (object space, any length) when they are shaded smooth.
    Triangles {
        tris: std::rc::Rc<Vec<[DVec3; 3]>>,
        normals: Option<std::rc::Rc<Vec<[DVec3; 3]>>>,
    },
    /// A bicubic_patch: 16 control points, rows of constant v (Photonix's own bicubic_patch).
    Patch {
        points: Box<[DVec3; 16]>,
    },
    /// A surface POV-Ray defines by an equation (quadric, cubic, quartic, poly) or a field
    /// (blob), tessellated by `implicit.rs` inside `bound` (object space; from bounded_by,
    /// clipped_by or the other parts of an intersection when absent).
    Implicit {
        shape: std::rc::Rc<super::implicit::Implicit>,
        bound: Option<(DVec3, DVec3)>,
    },
    Csg {
        op: CsgOp,
        children: Vec<Obj>,
    },
    Light(Box<Light>),
    /// An object POV-Ray has and Photonix not yet (a quadric, text, ...): an error if placed.
    Unsupported(&'static str),
}

#[derive(Clone, Debug)]
pub struct Tex {
    pub pigment: Pigment,
    pub finish: Finish,
    /// `normal { ... }`: a bump pattern, or `None` for a smooth surface.
    pub normal: Option<Normal>,
    /// world_from_texture: the transforms written in the texture and applied to the object
    /// after the texture was given.
    pub xform: DMat4,
    /// A patterned texture's entries (texture_map, or textures as a checker's, brick's or
    /// hexagon's entries): the pigment then holds the pattern, its fields and transforms, with
    /// each entry's mean colour as its colour map (what stands in where the entries cannot be
    /// mixed), and the finish and normal are the first entry's.
    pub map: Option<std::rc::Rc<TexMap>>,
}

/// The textures a pattern chooses between: each entry's layers at its value (a listed
/// pattern's entries at i / (n - 1), as its `colors` are spread).
#[derive(Clone, Debug)]
pub struct TexMap {
    pub entries: Vec<(f64, Vec<Tex>)>,
    /// The entries were listed (`checker texture { A } texture { B }`), not placed by a map.
    pub listed: bool,
}

#[derive(Clone, Debug)]
pub struct Pigment {
    pub kind: PigmentKind,
    /// texture_from_pattern: the pigment's own transforms.
    pub xform: DMat4,
    pub pos: Pos,
    /// A pigment_map's entries (the pattern's colour map then holds their mean colours), for
    /// the texture to mix them (`emit`'s texture mixes).
    pub entries: Option<std::rc::Rc<Vec<(f64, Pigment)>>>,
}

#[derive(Clone, Debug)]
pub enum PigmentKind {
    Solid(Colour),
    /// A pattern Photonix has, with its colour map and the fields `docs/patterns.md` lists.
    Pattern {
        name: String,
        map: Vec<(f64, Colour)>,
        fields: Vec<(String, toml::Value)>,
    },
    /// An image_map Photonix projects itself: the image file (for the TOML), its projection
    /// ("planar", "spherical" or "cylindrical", POV-Ray's map_type 0, 1, 2), whether `once`
    /// was given, and the image's mean colour with filter all / transmit all (for what needs one
    /// colour).
    Image {
        file: String,
        projection: &'static str,
        once: bool,
        mean: Colour,
    },
}

impl Pigment {
    pub fn solid(c: Colour, pos: Pos) -> Pigment {
        Pigment { kind: PigmentKind::Solid(c), xform: DMat4::IDENTITY, pos, entries: None }
    }

    /// The mean colour: a constant colour's own, a colour map's mean entry.
    pub fn mean(&self) -> Colour {
        match &self.kind {
            PigmentKind::Solid(c) | PigmentKind::Image { mean: c, .. } => *c,
            PigmentKind::Pattern { map, .. } if !map.is_empty() => {
                let mut m = [0.0; 5];
                for (_, c) in map {
                    for i in 0..5 {
                        m[i] += c[i] / map.len() as f64;
                    }
                }
                m
            }
            PigmentKind::Pattern { .. } => [0.5, 0.5, 0.5, 0.0, 0.0],
        }
    }
}

/// POV-Ray's finish, with its defaults (3.7 reference manual, "Finish").
#[derive(Clone, Debug, PartialEq)]
pub struct Finish {
    pub ambient: [f64; 3],
    pub emission: [f64; 3],
    pub diffuse: f64,
    pub phong: f64,
    pub phong_size: f64,
    pub specular: f64,
    pub roughness: f64,
    pub reflection: [f64; 3],
    pub metallic: f64,
}

impl Default for Finish {
    fn default() -> Finish {
        Finish {
            ambient: [0.1; 3],
            emission: [0.0; 3],
            diffuse: 0.6,
            phong: 0.0,
            phong_size: 40.0,
            specular: 0.0,
            roughness: 0.05,
            reflection: [0.0; 3],
            metallic: 0.0,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Interior {
    pub ior: f64,
    /// `media { ... }` blocks, in order (Photonix takes the first).
    pub media: Vec<Media>,
    /// `fade_distance` (0: no fade) and `fade_color` (default black): the attenuation of light
    /// through a transparent object's inside.
    pub fade_distance: f64,
    pub fade_colour: [f64; 3],
}

/// POV-Ray's `normal { PATTERN amount ... }`: a pattern whose gradient tilts the shading normal.
#[derive(Clone, Debug)]
pub struct Normal {
    pub pattern: String,
    /// The bump amount (`bumps 0.5`, or `bump_size`).
    pub amount: f64,
    /// The pattern's fields as docs/patterns.md names them (turbulence, frequency, ...).
    pub fields: Vec<(String, toml::Value)>,
    /// texture_from_pattern: the normal's own transforms.
    pub xform: DMat4,
    pub pos: Pos,
}

/// POV-Ray's `media { ... }` (interior or atmospheric), per unit length.
#[derive(Clone, Debug)]
pub struct Media {
    pub absorption: [f64; 3],
    pub emission: [f64; 3],
    pub scattering: [f64; 3],
    /// Henyey-Greenstein asymmetry (0 isotropic).
    pub g: f64,
    /// `density { PATTERN color_map { ... } }`: the first density block, as a pigment.
    pub density: Option<Pigment>,
    /// world_from_media: transforms given in the media and applied after it.
    pub xform: DMat4,
    pub pos: Pos,
}

/// `sky_sphere { pigment { ... } ... }`: its pigments, bottom first.
#[derive(Clone, Debug)]
pub struct SkySphere {
    pub pigments: Vec<Pigment>,
    /// The sky_sphere's own transforms (applied to the pigments).
    pub xform: DMat4,
    pub emission: [f64; 3],
    pub pos: Pos,
}

/// `rainbow { ... }` (POV-Ray's reference manual, "Rainbow").
#[derive(Clone, Debug)]
pub struct Rainbow {
    pub direction: DVec3,
    pub angle: f64,
    pub width: f64,
    pub map: Vec<(f64, Colour)>,
    pub up: Option<DVec3>,
    pub arc_angle: Option<f64>,
    pub falloff_angle: Option<f64>,
    pub pos: Pos,
}

#[derive(Clone, Debug)]
pub enum LightKind {
    Point,
    Spot { point_at: DVec3, radius: f64, falloff: f64, tightness: f64 },
    Parallel { point_at: DVec3 },
}

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub axis1: DVec3,
    pub axis2: DVec3,
    pub n1: u32,
    pub n2: u32,
    pub adaptive: u32,
    pub jitter: bool,
}

#[derive(Clone, Debug)]
pub struct Light {
    pub position: DVec3,
    pub colour: [f64; 3],
    pub kind: LightKind,
    pub area: Option<AreaLight>,
    pub fade_distance: f64,
    pub fade_power: f64,
    pub shadowless: bool,
    /// `looks_like { OBJECT }`: the object, already moved to the light (POV-Ray translates it by
    /// the light's position when it is read; later transforms of the light move both).
    pub looks_like: Option<Box<Obj>>,
    pub pos: Pos,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub orthographic: bool,
    pub location: DVec3,
    pub direction: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    pub sky: DVec3,
    /// The point `look_at` named, where the light's brightness is matched (docs/pov-ray.md).
    pub look_at: Option<DVec3>,
    /// `angle` on an orthographic camera (degrees): POV-Ray sizes the view to what a
    /// perspective camera of that angle sees at the look_at distance.
    pub ortho_angle: Option<f64>,
    pub aperture: f64,
    pub focal_point: Option<DVec3>,
    pub blur_samples: i64,
    pub pos: Pos,
}

impl Default for Camera {
    fn default() -> Camera {
        // POV-Ray's default camera (reference manual, "Camera").
        Camera {
            orthographic: false,
            location: DVec3::ZERO,
            direction: DVec3::Z,
            right: DVec3::new(1.33, 0.0, 0.0),
            up: DVec3::Y,
            sky: DVec3::Y,
            look_at: None,
            ortho_angle: None,
            aperture: 0.0,
            focal_point: None,
            blur_samples: 0,
            pos: Pos::default(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Fog {
    pub ground: bool,
    pub distance: f64,
    pub colour: Colour,
    pub offset: f64,
    pub alt: f64,
    pub turbulence: Option<DVec3>,
    pub pos: Pos,
}

/// Everything the scene's statements produced.
#[derive(Clone, Debug, Default)]
pub struct PovScene {
    pub camera: Option<Camera>,
    pub objects: Vec<Obj>,
    pub background: Option<(Colour, Pos)>,
    pub fog: Option<Fog>,
    pub sky_sphere: Option<SkySphere>,
    pub rainbow: Option<Rainbow>,
    /// Atmospheric `media { ... }` at the top level.
    pub media: Option<Media>,
    pub assumed_gamma: Option<f64>,
    pub max_trace_level: Option<i64>,
    /// The texture of objects without one (POV-Ray's: black, with `#default` applied).
    pub default_tex: Option<Tex>,
    pub warnings: Vec<String>,
}

/// A colour map's colour at value `v`, as POV-Ray's `BlendMap::Search`: the first colour below
/// the first position, the last at and above the last, linear in between (entries sorted by
/// position first, as Photonix's maps are).
pub fn map_eval(map: &[(f64, Colour)], v: f64) -> Colour {
    let mut m = map.to_vec();
    m.sort_by(|a, b| a.0.total_cmp(&b.0));
    let Some(first) = m.first() else { return [0.0; 5] };
    if v <= first.0 {
        return first.1;
    }
    for w in m.windows(2) {
        let ((a, ca), (b, cb)) = (w[0], w[1]);
        if v < b {
            let t = if b > a { (v - a) / (b - a) } else { 1.0 };
            return [0, 1, 2, 3, 4].map(|i| ca[i] + t * (cb[i] - ca[i]));
        }
    }
    m[m.len() - 1].1
}
