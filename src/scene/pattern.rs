//! Procedural patterns of scene files: their description, defaults, checks, parsing from TOML,
//! and packing into the `texture_data` words that `shaders/pattern.glsl` and its twin
//! `src/cpu/pattern.rs` read (the block layout is documented there). `docs/patterns.md` is the
//! user's reference.
//!
//! Names, parameters and defaults are POV-Ray 3.7's (reference manual, "Patterns" and "Pattern
//! Modifiers"; source/core/material/pattern.cpp for the default colour maps).
//! Errors are plain strings that name the field and say what to do; the scene parser prefixes
//! them with `file:line`.

use glam::{Affine3A, Mat3, Vec3};

use crate::cpu::pattern as shader;
use crate::limits::{fmt_number, MAX_SCENE_VALUE};

/// Every pattern name, in the order of the `PATTERN_*` kind numbers.
pub const PATTERN_NAMES: &[&str] = &[
    "agate", "bozo", "brick", "bumps", "checker", "crackle", "dents", "gradient", "granite", "hexagon", "leopard",
    "marble", "onion", "radial", "ripples", "spotted", "waves", "wood", "wrinkles",
];

/// Every wave shape name, in the order of the `WAVE_*` numbers.
pub const WAVE_NAMES: &[&str] = &["ramp", "sine", "triangle", "scallop", "cubic", "poly"];

/// Every field [`parse_pattern`] reads.
pub const PATTERN_FIELDS: &[&str] = &[
    "pattern",
    "turbulence",
    "octaves",
    "omega",
    "lambda",
    "frequency",
    "phase",
    "wave",
    "exponent",
    "direction",
    "orientation",
    "brick_size",
    "mortar",
    "metric",
    "form",
    "offset",
    "solid",
    "agate_turb",
    "warp",
    "color_map",
];

/// Every warp name, in the order of the `WARP_*` kind numbers.
pub const WARP_NAMES: &[&str] = &["repeat", "black_hole", "cylindrical", "spherical", "toroidal", "planar"];

/// Which warp, with its parameters (POV-Ray 3.7's `warp { ... }`, warp.cpp).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WarpKind {
    /// The slab [0, width) along `axis` (0, 1, 2) repeated; every other copy mirrored where
    /// `flip` is -1, copy k moved by k `offset`.
    Repeat { axis: u32, width: f32, offset: Vec3, flip: Vec3 },
    /// Points within `radius` of `center` pulled towards it (pushed away when `inverse`) by
    /// min(1, strength ((radius - d) / radius)^falloff) of their distance; `repeat` > 0 on an
    /// axis repeats the hole with that period.
    BlackHole { center: Vec3, radius: f32, strength: f32, falloff: f32, inverse: bool, repeat: Vec3 },
    /// (angle around y in turns, y, distance to the y axis), the angle times distance^dist_exp.
    Cylindrical { orientation: Vec3, dist_exp: f32 },
    /// (longitude, latitude in turns, distance to the origin), both angles times distance^dist_exp.
    Spherical { orientation: Vec3, dist_exp: f32 },
    /// (angle around y, angle around the ring of `major_radius`, distance to that ring).
    Toroidal { orientation: Vec3, dist_exp: f32, major_radius: f32 },
    /// (x, y, offset): the x-y plane's pattern, constant along z.
    Planar { orientation: Vec3, offset: f32 },
}

/// A warp and where the pattern sits inside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    pub kind: WarpKind,
    /// The transforms written before the warp in POV-Ray, which place the pattern the warp acts
    /// on: warped_from_pattern (identity for none).
    pub transform: Affine3A,
}

impl WarpKind {
    pub fn code(&self) -> u32 {
        match self {
            WarpKind::Repeat { .. } => shader::WARP_REPEAT,
            WarpKind::BlackHole { .. } => shader::WARP_BLACK_HOLE,
            WarpKind::Cylindrical { .. } => shader::WARP_CYLINDRICAL,
            WarpKind::Spherical { .. } => shader::WARP_SPHERICAL,
            WarpKind::Toroidal { .. } => shader::WARP_TOROIDAL,
            WarpKind::Planar { .. } => shader::WARP_PLANAR,
        }
    }

    pub fn name(&self) -> &'static str {
        WARP_NAMES[self.code() as usize]
    }
}

impl Warp {
    /// Appends the warp's record of `WARP_WORDS` words (src/cpu/pattern.rs, `warp_point`).
    fn pack(&self, data: &mut Vec<u32>) {
        let mut record = [0u32; shader::WARP_WORDS as usize];
        record[0] = self.kind.code();
        let mut set = |offset: u32, value: f32| record[offset as usize] = value.to_bits();
        let a = shader::WARP_PARAMS;
        let set3 = |set: &mut dyn FnMut(u32, f32), offset: u32, v: Vec3| {
            for (i, c) in v.to_array().into_iter().enumerate() {
                set(offset + i as u32, c);
            }
        };
        match self.kind {
            WarpKind::Repeat { width, offset, flip, .. } => {
                set(a + 1, width);
                set3(&mut set, a + 2, offset);
                set3(&mut set, a + 5, flip);
            }
            WarpKind::BlackHole { center, radius, strength, falloff, repeat, .. } => {
                set3(&mut set, a, center);
                set(a + 3, radius);
                set(a + 4, strength);
                set(a + 5, falloff);
                set3(&mut set, a + 7, repeat);
            }
            WarpKind::Cylindrical { orientation, dist_exp } | WarpKind::Spherical { orientation, dist_exp } => {
                set3(&mut set, a, orientation);
                set(a + 3, dist_exp);
            }
            WarpKind::Toroidal { orientation, dist_exp, major_radius } => {
                set3(&mut set, a, orientation);
                set(a + 3, dist_exp);
                set(a + 4, major_radius);
            }
            WarpKind::Planar { orientation, offset } => {
                set3(&mut set, a, orientation);
                set(a + 3, offset);
            }
        }
        let pattern_from_warped = self.transform.inverse();
        let m = pattern_from_warped.matrix3;
        let columns =
            [Vec3::from(m.x_axis), Vec3::from(m.y_axis), Vec3::from(m.z_axis), pattern_from_warped.translation.into()];
        for (i, c) in columns.into_iter().enumerate() {
            set3(&mut set, shader::WARP_MATRIX + 3 * i as u32, c);
        }
        match self.kind {
            WarpKind::Repeat { axis, .. } => record[(a) as usize] = axis,
            WarpKind::BlackHole { inverse, .. } => record[(a + 6) as usize] = inverse as u32,
            _ => {}
        }
        data.extend_from_slice(&record);
    }

    /// Checks the numbers the way [`parse_warp`] does.
    fn validate(&self) -> Result<(), String> {
        match self.kind {
            WarpKind::Repeat { axis, width, offset, flip } => {
                if axis > 2 || !(width.is_finite() && width != 0.0) {
                    return Err("a repeat warp's `direction` must be a non-zero vector along one axis".to_string());
                }
                finite_vec("offset", offset)?;
                if flip.to_array().iter().any(|f| f.abs() != 1.0) {
                    return Err("a repeat warp's flip factors must be 1 or -1".to_string());
                }
            }
            WarpKind::BlackHole { center, radius, strength, falloff, repeat, .. } => {
                finite_vec("center", center)?;
                positive("radius", radius)?;
                finite("strength", strength)?;
                finite("falloff", falloff)?;
                finite_vec("repeat", repeat)?;
                if repeat.min_element() < 0.0 {
                    return Err("a black_hole warp's `repeat` must be >= 0 on each axis (0: no repeat)".to_string());
                }
            }
            WarpKind::Cylindrical { orientation, dist_exp } | WarpKind::Spherical { orientation, dist_exp } => {
                finite_vec("orientation", orientation)?;
                finite("dist_exp", dist_exp)?;
            }
            WarpKind::Toroidal { orientation, dist_exp, major_radius } => {
                finite_vec("orientation", orientation)?;
                finite("dist_exp", dist_exp)?;
                finite("major_radius", major_radius)?;
            }
            WarpKind::Planar { orientation, offset } => {
                finite_vec("orientation", orientation)?;
                finite("offset", offset)?;
            }
        }
        if !(self.transform.is_finite() && self.transform.matrix3.determinant().abs() > 1e-30) {
            return Err("a warp's `transform` must be invertible (no zero scale)".to_string());
        }
        Ok(())
    }
}

/// Which pattern, with the parameters only it has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PatternKind {
    /// Agate veins: turbulence scaled by `agate_turb` (default 1) bends bands along z.
    Agate { agate_turb: f32 },
    /// Noise, with POV-Ray's banded white-green-blue-red default map.
    Bozo,
    /// Bricks of `brick_size` (default [8, 3, 4.5]) and joints `mortar` thick (default 0.5):
    /// 0 in the mortar, 1 in a brick.
    Brick { brick_size: Vec3, mortar: f32 },
    /// Noise, meant for normals.
    Bumps,
    /// Unit cubes alternating 0 and 1.
    Checker,
    /// Cells around random points: `form` . (d1, d2, d3) of the distances to the three nearest
    /// points under the `metric` (default form [-1, 1, 0], metric 2); `offset` is added to each
    /// distance; `solid` gives each cell one noise value instead.
    Crackle { form: Vec3, metric: f32, offset: f32, solid: bool },
    /// Noise cubed.
    Dents,
    /// p . direction, ramps of period 1 / |direction| along `direction`.
    Gradient { direction: Vec3 },
    /// Six octaves of folded noise.
    Granite,
    /// Hexagons in the x-z plane in three colours: 0, 0.5, 1.
    Hexagon,
    /// ((sin x + sin y + sin z) / 3)^2: regular spots.
    Leopard,
    /// x plus turbulence, with a triangle wave: veins across x.
    Marble,
    /// Concentric spheres of unit spacing.
    Onion,
    /// The angle around the y axis, from +z towards +x: one turn is one unit of value.
    Radial,
    /// Concentric sine waves around 10 points of the unit sphere.
    Ripples,
    /// Noise.
    Spotted,
    /// Like ripples, each source with its own frequency and weight.
    Waves,
    /// Cylinders around the z axis, bent by turbulence, with a triangle wave.
    Wood,
    /// Ten octaves of noise.
    Wrinkles,
}

impl PatternKind {
    /// The kind named `name` (one of [`PATTERN_NAMES`]) with POV-Ray's default parameters.
    /// Gradient has no default direction in POV-Ray; this gives it +y.
    pub fn from_name(name: &str) -> Option<PatternKind> {
        Some(match name {
            "agate" => PatternKind::Agate { agate_turb: 1.0 },
            "bozo" => PatternKind::Bozo,
            "brick" => PatternKind::Brick { brick_size: Vec3::new(8.0, 3.0, 4.5), mortar: 0.5 },
            "bumps" => PatternKind::Bumps,
            "checker" => PatternKind::Checker,
            "crackle" => {
                PatternKind::Crackle { form: Vec3::new(-1.0, 1.0, 0.0), metric: 2.0, offset: 0.0, solid: false }
            }
            "dents" => PatternKind::Dents,
            "gradient" => PatternKind::Gradient { direction: Vec3::Y },
            "granite" => PatternKind::Granite,
            "hexagon" => PatternKind::Hexagon,
            "leopard" => PatternKind::Leopard,
            "marble" => PatternKind::Marble,
            "onion" => PatternKind::Onion,
            "radial" => PatternKind::Radial,
            "ripples" => PatternKind::Ripples,
            "spotted" => PatternKind::Spotted,
            "waves" => PatternKind::Waves,
            "wood" => PatternKind::Wood,
            "wrinkles" => PatternKind::Wrinkles,
            _ => return None,
        })
    }

    /// The `PATTERN_*` number the shader switches on.
    pub fn code(&self) -> u32 {
        match self {
            PatternKind::Agate { .. } => shader::PATTERN_AGATE,
            PatternKind::Bozo => shader::PATTERN_BOZO,
            PatternKind::Brick { .. } => shader::PATTERN_BRICK,
            PatternKind::Bumps => shader::PATTERN_BUMPS,
            PatternKind::Checker => shader::PATTERN_CHECKER,
            PatternKind::Crackle { .. } => shader::PATTERN_CRACKLE,
            PatternKind::Dents => shader::PATTERN_DENTS,
            PatternKind::Gradient { .. } => shader::PATTERN_GRADIENT,
            PatternKind::Granite => shader::PATTERN_GRANITE,
            PatternKind::Hexagon => shader::PATTERN_HEXAGON,
            PatternKind::Leopard => shader::PATTERN_LEOPARD,
            PatternKind::Marble => shader::PATTERN_MARBLE,
            PatternKind::Onion => shader::PATTERN_ONION,
            PatternKind::Radial => shader::PATTERN_RADIAL,
            PatternKind::Ripples => shader::PATTERN_RIPPLES,
            PatternKind::Spotted => shader::PATTERN_SPOTTED,
            PatternKind::Waves => shader::PATTERN_WAVES,
            PatternKind::Wood => shader::PATTERN_WOOD,
            PatternKind::Wrinkles => shader::PATTERN_WRINKLES,
        }
    }

    pub fn name(&self) -> &'static str {
        PATTERN_NAMES[self.code() as usize]
    }

    /// Checker, brick and hexagon take a few discrete values and, as in POV-Ray, ignore
    /// frequency, phase and wave shape.
    pub fn is_discrete(&self) -> bool {
        matches!(self, PatternKind::Checker | PatternKind::Brick { .. } | PatternKind::Hexagon)
    }

    /// POV-Ray's wave shape for this pattern: triangle for marble and wood, ramp for the rest.
    pub fn default_wave(&self) -> WaveShape {
        match self {
            PatternKind::Marble | PatternKind::Wood => WaveShape::Triangle,
            _ => WaveShape::Ramp,
        }
    }

    /// POV-Ray's default colour map of this pattern (pattern.cpp, gaDefaultBlendMapEntries_*);
    /// black to white for the patterns that have none. Hexagon's three colours sit at 0, 0.5, 1.
    pub fn default_color_map(&self) -> ColorMap {
        let entries: Vec<(f32, [f32; 3])> = match self {
            PatternKind::Agate { .. } => vec![
                (0.0, [1.0, 1.0, 1.0]),
                (0.5, [0.95, 0.75, 0.5]),
                (0.5, [0.9, 0.7, 0.5]),
                (0.6, [0.9, 0.7, 0.4]),
                (0.6, [1.0, 0.7, 0.4]),
                (1.0, [0.6, 0.3, 0.0]),
            ],
            PatternKind::Bozo => vec![
                (0.4, [1.0, 1.0, 1.0]),
                (0.4, [0.0, 1.0, 0.0]),
                (0.6, [0.0, 1.0, 0.0]),
                (0.6, [0.0, 0.0, 1.0]),
                (0.8, [0.0, 0.0, 1.0]),
                (0.8, [1.0, 0.0, 0.0]),
            ],
            PatternKind::Brick { .. } => vec![(0.0, [0.5, 0.5, 0.5]), (1.0, [0.6, 0.15, 0.15])],
            PatternKind::Checker => vec![(0.0, [0.0, 0.0, 1.0]), (1.0, [0.0, 1.0, 0.0])],
            PatternKind::Hexagon => vec![(0.0, [0.0, 0.0, 1.0]), (0.5, [0.0, 1.0, 0.0]), (1.0, [1.0, 0.0, 0.0])],
            PatternKind::Marble => vec![(0.0, [0.9, 0.8, 0.8]), (0.9, [0.9, 0.08, 0.08]), (0.9, [0.0, 0.0, 0.0])],
            PatternKind::Wood => vec![(0.6, [0.666, 0.312, 0.2]), (0.6, [0.4, 0.1333, 0.066])],
            PatternKind::Radial => {
                vec![(0.0, [0.0, 1.0, 1.0]), (0.333, [1.0, 1.0, 0.0]), (0.666, [1.0, 0.0, 1.0]), (1.0, [0.0, 1.0, 1.0])]
            }
            _ => vec![(0.0, [0.0, 0.0, 0.0]), (1.0, [1.0, 1.0, 1.0])],
        };
        ColorMap { entries }
    }
}

/// POV-Ray's wave types: how the value, after frequency and phase, maps into [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WaveShape {
    /// v (POV-Ray's default).
    Ramp,
    /// (1 + sin(2 pi v)) / 2.
    Sine,
    /// 0 to 1 and back within each period.
    Triangle,
    /// |sin(pi v)|.
    Scallop,
    /// v^2 (3 - 2v).
    Cubic,
    /// v^exponent (POV-Ray's `poly_wave`, default exponent 1).
    Poly { exponent: f32 },
}

impl WaveShape {
    pub fn code(&self) -> u32 {
        match self {
            WaveShape::Ramp => shader::WAVE_RAMP,
            WaveShape::Sine => shader::WAVE_SINE,
            WaveShape::Triangle => shader::WAVE_TRIANGLE,
            WaveShape::Scallop => shader::WAVE_SCALLOP,
            WaveShape::Cubic => shader::WAVE_CUBIC,
            WaveShape::Poly { .. } => shader::WAVE_POLY,
        }
    }

    pub fn name(&self) -> &'static str {
        WAVE_NAMES[self.code() as usize]
    }
}

/// A pattern and its modifiers, in pattern space (the texture transform is the caller's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternDesc {
    pub kind: PatternKind,
    /// Turbulence amount per axis (POV-Ray's `turbulence`), default 0 (none).
    pub turbulence: Vec3,
    /// Octaves of turbulence, 1..=10, default 6.
    pub octaves: u32,
    /// Amplitude ratio of successive octaves, default 0.5.
    pub omega: f32,
    /// Frequency ratio of successive octaves, default 2.
    pub lambda: f32,
    /// Multiplies the value before the wave shape, default 1; 0 skips the wrapping.
    pub frequency: f32,
    /// Added after `frequency`, default 0.
    pub phase: f32,
    pub wave: WaveShape,
    /// Warps other than turbulence, in the order POV-Ray writes them (at most `MAX_WARPS`); the
    /// point meets the last one first.
    pub warps: [Option<Warp>; shader::MAX_WARPS as usize],
}

impl PatternDesc {
    /// `kind` with POV-Ray's default modifiers.
    pub fn new(kind: PatternKind) -> PatternDesc {
        PatternDesc {
            kind,
            turbulence: Vec3::ZERO,
            octaves: 6,
            omega: 0.5,
            lambda: 2.0,
            frequency: 1.0,
            phase: 0.0,
            wave: kind.default_wave(),
            warps: [None; shader::MAX_WARPS as usize],
        }
    }

    /// The warps, in the order written.
    pub fn warp_list(&self) -> impl DoubleEndedIterator<Item = &Warp> {
        self.warps.iter().flatten()
    }

    /// Appends the pattern's block of `PATTERN_WORDS` words to `data` and returns its offset,
    /// the `at` of `pattern_value`. Octaves are clamped to 1..=10, as the shader does.
    pub fn pack(&self, data: &mut Vec<u32>) -> u32 {
        let at = data.len() as u32;
        let mut block = [0u32; shader::PATTERN_WORDS as usize];
        let mut set = |offset: u32, value: f32| block[offset as usize] = value.to_bits();
        set(shader::PATTERN_OMEGA, self.omega);
        set(shader::PATTERN_LAMBDA, self.lambda);
        for (i, v) in self.turbulence.to_array().into_iter().enumerate() {
            set(shader::PATTERN_TURBULENCE + i as u32, v);
        }
        set(shader::PATTERN_FREQUENCY, self.frequency);
        set(shader::PATTERN_PHASE, self.phase);
        set(shader::PATTERN_EXPONENT, if let WaveShape::Poly { exponent } = self.wave { exponent } else { 1.0 });
        let params = shader::PATTERN_PARAMS;
        match self.kind {
            PatternKind::Agate { agate_turb } => set(params, agate_turb),
            PatternKind::Brick { brick_size, mortar } => {
                for (i, v) in brick_size.to_array().into_iter().enumerate() {
                    set(params + i as u32, v);
                }
                set(params + 3, mortar);
            }
            PatternKind::Crackle { form, metric, offset, solid } => {
                for (i, v) in form.to_array().into_iter().enumerate() {
                    set(params + i as u32, v);
                }
                set(params + 3, metric);
                set(params + 4, offset);
                block[(params + 5) as usize] = solid as u32;
            }
            PatternKind::Gradient { direction } => {
                for (i, v) in direction.to_array().into_iter().enumerate() {
                    set(params + i as u32, v);
                }
            }
            _ => {}
        }
        block[shader::PATTERN_KIND as usize] = self.kind.code();
        block[shader::PATTERN_WAVE as usize] = self.wave.code();
        block[shader::PATTERN_OCTAVES as usize] = self.octaves.clamp(1, shader::MAX_OCTAVES);
        block[shader::PATTERN_WARP_COUNT as usize] = self.warp_list().count() as u32;
        data.extend_from_slice(&block);
        // The records follow the block, the last warp written first: POV-Ray applies a pattern's
        // warps from the last to the first (warp.cpp, Warp_EPoint).
        for warp in self.warp_list().rev() {
            warp.pack(data);
        }
        at
    }

    /// Checks every number the way [`parse_pattern`] does; the error names the field.
    pub fn validate(&self) -> Result<(), String> {
        finite_vec("turbulence", self.turbulence)?;
        if !(1..=shader::MAX_OCTAVES).contains(&self.octaves) {
            return Err(format!("`octaves` must be an integer from 1 to 10, got {}", self.octaves));
        }
        finite("omega", self.omega)?;
        finite("lambda", self.lambda)?;
        finite("frequency", self.frequency)?;
        finite("phase", self.phase)?;
        if let WaveShape::Poly { exponent } = self.wave {
            positive("exponent", exponent)?;
        }
        for warp in self.warp_list() {
            warp.validate()?;
        }
        match self.kind {
            PatternKind::Agate { agate_turb } => finite("agate_turb", agate_turb)?,
            PatternKind::Brick { brick_size, mortar } => {
                for v in brick_size.to_array() {
                    positive("brick_size", v)?;
                }
                if !(mortar.is_finite() && mortar >= 0.0) {
                    return Err(format!("`mortar` must be a number >= 0, got {mortar}"));
                }
            }
            PatternKind::Crackle { form, metric, offset, .. } => {
                finite_vec("form", form)?;
                positive("metric", metric)?;
                if !(offset.is_finite() && offset >= 0.0) {
                    return Err(format!("`offset` must be a number >= 0, got {offset}"));
                }
            }
            PatternKind::Gradient { direction } => {
                finite_vec("direction", direction)?;
                if direction == Vec3::ZERO {
                    return Err("`direction` must not be [0, 0, 0]; give the axis the gradient runs along, \
                                e.g. [0, 1, 0]"
                        .to_string());
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// A colour map (POV-Ray's `color_map`): colours at positions in [0, 1], in non-decreasing
/// order; linear in between, constant beyond the ends. Two entries at one position make a sharp
/// step. A scalar map is a colour map with grey entries ([`ColorMap::grey`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorMap {
    pub entries: Vec<(f32, [f32; 3])>,
}

impl ColorMap {
    /// A checked colour map.
    pub fn new(entries: Vec<(f32, [f32; 3])>) -> Result<ColorMap, String> {
        let map = ColorMap { entries };
        map.validate()?;
        Ok(map)
    }

    /// A checked scalar map: value `v` at each position, stored as the grey colour [v, v, v].
    pub fn grey(entries: &[(f32, f32)]) -> Result<ColorMap, String> {
        ColorMap::new(entries.iter().map(|&(position, v)| (position, [v; 3])).collect())
    }

    /// At least one entry and at most 256 (POV-Ray's limit), positions in [0, 1] and in order,
    /// colours finite and >= 0.
    pub fn validate(&self) -> Result<(), String> {
        if self.entries.is_empty() {
            return Err("`color_map` needs at least one entry, e.g. [[0, [0, 0, 0]], [1, [1, 1, 1]]]".to_string());
        }
        if self.entries.len() > shader::MAX_COLOR_MAP_ENTRIES as usize {
            return Err(format!("`color_map` has {} entries; use at most 256", self.entries.len()));
        }
        let mut previous: Option<f32> = None;
        for (i, &(position, colour)) in self.entries.iter().enumerate() {
            if !(position.is_finite() && (0.0..=1.0).contains(&position)) {
                return Err(format!("`color_map` entry {}: position {position} must be in [0, 1]", i + 1));
            }
            if let Some(before) = previous {
                if position < before {
                    return Err(format!(
                        "`color_map` positions must be in order: {position} comes after {before}; sort the entries"
                    ));
                }
            }
            if colour.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
                return Err(format!(
                    "`color_map` entry {}: colour [{}, {}, {}] must have finite components >= 0",
                    i + 1,
                    colour[0],
                    colour[1],
                    colour[2]
                ));
            }
            previous = Some(position);
        }
        Ok(())
    }

    /// The largest red (first) component of its entries: the map's maximum, since it is linear
    /// between entries and constant beyond them.
    pub fn max_first_channel(&self) -> f32 {
        self.entries.iter().map(|(_, c)| c[0]).fold(0.0, f32::max)
    }

    /// Appends the map's block (count, then position, r, g, b per entry) to `data` and returns
    /// its offset, the `at` of `color_map_eval`.
    pub fn pack(&self, data: &mut Vec<u32>) -> u32 {
        let at = data.len() as u32;
        data.push(self.entries.len() as u32);
        for &(position, [r, g, b]) in &self.entries {
            data.extend([position, r, g, b].map(f32::to_bits));
        }
        at
    }
}

// ---------------------------------------------------------------------------------------------
// Parsing
// ---------------------------------------------------------------------------------------------

/// Reads a pattern table of a scene file, e.g.
/// `{ pattern = "wood", turbulence = 0.1, color_map = [[0, [0.9, 0.6, 0.3]], [1, [0.5, 0.3, 0.1]]] }`,
/// with the fields of [`PATTERN_FIELDS`] (documented in `docs/patterns.md`). Returns the
/// pattern and its colour map when the table has one. Unknown fields are errors; use
/// [`parse_pattern_with`] when the table also holds fields of the caller.
pub fn parse_pattern(table: &toml::Value) -> Result<(PatternDesc, Option<ColorMap>), String> {
    parse_pattern_with(table, &[])
}

/// [`parse_pattern`] for a table that may also hold the caller's `other_fields` (e.g. `scale`,
/// `rotate`, `translate`), which it skips; they are also candidates of "did you mean".
pub fn parse_pattern_with(
    table: &toml::Value,
    other_fields: &[&str],
) -> Result<(PatternDesc, Option<ColorMap>), String> {
    let Some(t) = table.as_table() else {
        return Err(format!("a pattern must be a table such as {{ pattern = \"wood\" }}, got {}", describe(table)));
    };
    for key in t.keys() {
        if !PATTERN_FIELDS.contains(&key.as_str()) && !other_fields.contains(&key.as_str()) {
            let candidates: Vec<&str> = PATTERN_FIELDS.iter().chain(other_fields).copied().collect();
            return Err(match suggest(key, &candidates) {
                Some(hit) => format!("unknown field `{key}` in pattern (did you mean `{hit}`?)"),
                None => format!("unknown field `{key}` in pattern; pattern fields are {}", PATTERN_FIELDS.join(", ")),
            });
        }
    }

    // Pattern name and kind parameters
    let name = match t.get("pattern") {
        None => return Err(format!("missing `pattern`; name one of {}", PATTERN_NAMES.join(", "))),
        Some(toml::Value::String(s)) => s.as_str(),
        Some(other) => return Err(format!("`pattern` must be a name such as \"wood\", got {}", describe(other))),
    };
    let Some(mut kind) = PatternKind::from_name(name) else {
        return Err(match suggest(name, PATTERN_NAMES) {
            Some(hit) => format!("unknown pattern \"{name}\" (did you mean \"{hit}\"?)"),
            None => format!("unknown pattern \"{name}\"; patterns are {}", PATTERN_NAMES.join(", ")),
        });
    };
    let only_for = |field: &str, owner: &str| -> Result<(), String> {
        if t.contains_key(field) && name != owner {
            return Err(format!("`{field}` applies only to the {owner} pattern, not \"{name}\"; remove it"));
        }
        Ok(())
    };
    for (field, owner) in [
        ("agate_turb", "agate"),
        ("brick_size", "brick"),
        ("mortar", "brick"),
        ("metric", "crackle"),
        ("form", "crackle"),
        ("offset", "crackle"),
        ("solid", "crackle"),
        ("direction", "gradient"),
        ("orientation", "gradient"),
    ] {
        only_for(field, owner)?;
    }
    match &mut kind {
        PatternKind::Agate { agate_turb } => {
            if let Some(v) = number(t, "agate_turb")? {
                *agate_turb = v;
            }
        }
        PatternKind::Brick { brick_size, mortar } => {
            if let Some(v) = vector_or_number(t, "brick_size")? {
                *brick_size = v;
            }
            if let Some(v) = number(t, "mortar")? {
                *mortar = v;
            }
        }
        PatternKind::Crackle { form, metric, offset, solid } => {
            if let Some(v) = vector(t, "form")? {
                *form = v;
            }
            if let Some(v) = number(t, "metric")? {
                *metric = v;
            }
            if let Some(v) = number(t, "offset")? {
                *offset = v;
            }
            match t.get("solid") {
                None => {}
                Some(toml::Value::Boolean(b)) => *solid = *b,
                Some(other) => return Err(format!("`solid` must be true or false, got {}", describe(other))),
            }
        }
        PatternKind::Gradient { direction } => {
            if t.contains_key("direction") && t.contains_key("orientation") {
                return Err("give either `direction` or `orientation` (they mean the same), not both".to_string());
            }
            let field = if t.contains_key("orientation") { "orientation" } else { "direction" };
            match vector(t, field)? {
                Some(v) => *direction = v,
                None => {
                    return Err("the gradient pattern needs `direction`, the axis it runs along, e.g. \
                                direction = [0, 1, 0]"
                        .to_string())
                }
            }
        }
        _ => {}
    }
    let mut desc = PatternDesc::new(kind);

    // Turbulence
    if let Some(v) = vector_or_number(t, "turbulence")? {
        desc.turbulence = v;
    }
    match t.get("octaves") {
        None => {}
        Some(toml::Value::Integer(n)) if (1..=10).contains(n) => desc.octaves = *n as u32,
        Some(other) => return Err(format!("`octaves` must be an integer from 1 to 10, got {}", describe(other))),
    }
    if let Some(v) = number(t, "omega")? {
        desc.omega = v;
    }
    if let Some(v) = number(t, "lambda")? {
        desc.lambda = v;
    }

    // Frequency, phase and wave shape
    if kind.is_discrete() {
        for field in ["frequency", "phase", "wave", "exponent"] {
            if t.contains_key(field) {
                return Err(format!(
                    "`{field}` has no effect on the {name} pattern, whose values are discrete (POV-Ray ignores \
                     it too); remove it"
                ));
            }
        }
    }
    if let Some(v) = number(t, "frequency")? {
        desc.frequency = v;
    }
    if let Some(v) = number(t, "phase")? {
        desc.phase = v;
    }
    match t.get("wave") {
        None => {}
        Some(toml::Value::String(s)) => {
            // POV-Ray's keywords end in `_wave`; accept them too.
            let shape = s.strip_suffix("_wave").unwrap_or(s);
            desc.wave = match shape {
                "ramp" => WaveShape::Ramp,
                "sine" => WaveShape::Sine,
                "triangle" => WaveShape::Triangle,
                "scallop" => WaveShape::Scallop,
                "cubic" => WaveShape::Cubic,
                "poly" => WaveShape::Poly { exponent: 1.0 },
                _ => {
                    return Err(match suggest(shape, WAVE_NAMES) {
                        Some(hit) => format!("unknown wave \"{s}\" (did you mean \"{hit}\"?)"),
                        None => format!("unknown wave \"{s}\"; waves are {}", WAVE_NAMES.join(", ")),
                    })
                }
            };
        }
        Some(other) => return Err(format!("`wave` must be a name such as \"sine\", got {}", describe(other))),
    }
    if let Some(v) = number(t, "exponent")? {
        match &mut desc.wave {
            WaveShape::Poly { exponent } => *exponent = v,
            _ => return Err("`exponent` applies only to wave = \"poly\"; add that or remove `exponent`".to_string()),
        }
    }
    // Warps
    match t.get("warp") {
        None => {}
        Some(toml::Value::Array(list)) => {
            if list.len() > shader::MAX_WARPS as usize {
                return Err(format!("`warp` lists {} warps; a pattern takes at most 4", list.len()));
            }
            for (i, w) in list.iter().enumerate() {
                desc.warps[i] = Some(parse_warp(w).map_err(|e| format!("`warp` entry {}: {e}", i + 1))?);
            }
        }
        Some(other) => {
            return Err(format!(
                "`warp` must be a list of tables such as [{{ type = \"repeat\", direction = [1, 0, 0] }}], got {}",
                describe(other)
            ))
        }
    }
    desc.validate()?;

    // Colour map
    let color_map = match t.get("color_map") {
        None => None,
        Some(value) => Some(parse_color_map(value)?),
    };
    Ok((desc, color_map))
}

/// Every field of a warp table, by warp (`type` and `transform` are every warp's).
const WARP_FIELDS: &[(&str, &[&str])] = &[
    ("repeat", &["direction", "offset", "flip"]),
    ("black_hole", &["center", "radius", "strength", "falloff", "inverse", "repeat"]),
    ("cylindrical", &["orientation", "dist_exp"]),
    ("spherical", &["orientation", "dist_exp"]),
    ("toroidal", &["orientation", "dist_exp", "major_radius"]),
    ("planar", &["orientation", "offset"]),
];

/// Reads one warp table, e.g. `{ type = "repeat", direction = [2, 0, 0], flip = [0, 1, 0] }`
/// (docs/patterns.md, "Warps").
fn parse_warp(value: &toml::Value) -> Result<Warp, String> {
    let Some(t) = value.as_table() else {
        return Err(format!(
            "a warp must be a table such as {{ type = \"repeat\", direction = [1, 0, 0] }}, got {}",
            describe(value)
        ));
    };
    let name = match t.get("type") {
        None => return Err(format!("missing `type`; name one of {}", WARP_NAMES.join(", "))),
        Some(toml::Value::String(s)) => s.as_str(),
        Some(other) => return Err(format!("`type` must be a warp name such as \"repeat\", got {}", describe(other))),
    };
    let Some((_, fields)) = WARP_FIELDS.iter().find(|(n, _)| *n == name) else {
        return Err(match suggest(name, WARP_NAMES) {
            Some(hit) => format!("unknown warp \"{name}\" (did you mean \"{hit}\"?)"),
            None => format!(
                "unknown warp \"{name}\"; warps are {} (turbulence is the pattern's own `turbulence`)",
                WARP_NAMES.join(", ")
            ),
        });
    };
    for key in t.keys() {
        if key != "type" && key != "transform" && !fields.contains(&key.as_str()) {
            let mut candidates: Vec<&str> = fields.to_vec();
            candidates.extend(["type", "transform"]);
            return Err(match suggest(key, &candidates) {
                Some(hit) => format!("unknown field `{key}` in a {name} warp (did you mean `{hit}`?)"),
                None => format!(
                    "unknown field `{key}` in a {name} warp; its fields are type, transform, {}",
                    fields.join(", ")
                ),
            });
        }
    }
    let orientation = vector(t, "orientation")?.unwrap_or(Vec3::Z);
    let dist_exp = number(t, "dist_exp")?.unwrap_or(0.0);
    let kind = match name {
        "repeat" => {
            let Some(d) = vector(t, "direction")? else {
                return Err(
                    "a repeat warp needs `direction`, the axis and width of the slab it repeats, e.g. [2, 0, 0]"
                        .to_string(),
                );
            };
            let axes: Vec<usize> = (0..3).filter(|&i| d[i] != 0.0).collect();
            let [axis] = axes[..] else {
                return Err(format!(
                    "a repeat warp's `direction` must be along one axis (POV-Ray repeats along one), got [{}, {}, {}]",
                    d.x, d.y, d.z
                ));
            };
            let flip = vector(t, "flip")?.unwrap_or(Vec3::ZERO);
            WarpKind::Repeat {
                axis: axis as u32,
                width: d[axis],
                offset: vector(t, "offset")?.unwrap_or(Vec3::ZERO),
                flip: Vec3::from(flip.to_array().map(|f| if f != 0.0 { -1.0 } else { 1.0 })),
            }
        }
        "black_hole" => {
            let Some(center) = vector(t, "center")? else {
                return Err("a black_hole warp needs `center`, e.g. [0, 0, 0]".to_string());
            };
            let Some(radius) = number(t, "radius")? else {
                return Err("a black_hole warp needs `radius`, e.g. 1".to_string());
            };
            let inverse = match t.get("inverse") {
                None => false,
                Some(toml::Value::Boolean(b)) => *b,
                Some(other) => return Err(format!("`inverse` must be true or false, got {}", describe(other))),
            };
            WarpKind::BlackHole {
                center,
                radius,
                strength: number(t, "strength")?.unwrap_or(1.0),
                falloff: number(t, "falloff")?.unwrap_or(2.0),
                inverse,
                repeat: vector(t, "repeat")?.unwrap_or(Vec3::ZERO),
            }
        }
        "cylindrical" => WarpKind::Cylindrical { orientation, dist_exp },
        "spherical" => WarpKind::Spherical { orientation, dist_exp },
        "toroidal" => {
            WarpKind::Toroidal { orientation, dist_exp, major_radius: number(t, "major_radius")?.unwrap_or(1.0) }
        }
        _ => WarpKind::Planar { orientation, offset: number(t, "offset")?.unwrap_or(0.0) },
    };
    let transform = match t.get("transform") {
        None => Affine3A::IDENTITY,
        Some(value) => parse_transform(value)?,
    };
    let warp = Warp { kind, transform };
    warp.validate()?;
    Ok(warp)
}

/// `{ scale = s or [x, y, z], rotate = [x, y, z] degrees, translate = [x, y, z] }`, composed as a
/// shape's transform is (docs/scene-format.md): scale, then rotate about x, y, z, then translate.
fn parse_transform(value: &toml::Value) -> Result<Affine3A, String> {
    let Some(t) = value.as_table() else {
        return Err(format!(
            "`transform` must be a table such as {{ scale = 2, translate = [0, 1, 0] }}, got {}",
            describe(value)
        ));
    };
    if let Some(key) = t.keys().find(|k| !["scale", "rotate", "translate"].contains(&k.as_str())) {
        return Err(format!("unknown field `{key}` in a warp's `transform`; its fields are scale, rotate, translate"));
    }
    let scale = vector_or_number(t, "scale")?.unwrap_or(Vec3::ONE);
    if scale.abs().min_element() == 0.0 {
        return Err("a warp's `transform.scale` is 0 along an axis; give non-zero factors".to_string());
    }
    let r = vector(t, "rotate")?.unwrap_or(Vec3::ZERO) * (std::f32::consts::PI / 180.0);
    let rotation = Mat3::from_rotation_z(r.z) * Mat3::from_rotation_y(r.y) * Mat3::from_rotation_x(r.x);
    let translate = vector(t, "translate")?.unwrap_or(Vec3::ZERO);
    Ok(Affine3A::from_mat3_translation(rotation * Mat3::from_diagonal(scale), translate))
}

/// Reads `[[position, colour], ...]` where a colour is [r, g, b] or one number (grey); an entry
/// may also be written flat as [position, r, g, b].
fn parse_color_map(value: &toml::Value) -> Result<ColorMap, String> {
    const SHAPE: &str = "[[0, [r, g, b]], [1, [r, g, b]]]";
    let Some(list) = value.as_array() else {
        return Err(format!("`color_map` must be a list of [position, [r, g, b]] such as {SHAPE}"));
    };
    let mut entries = Vec::with_capacity(list.len());
    for (i, entry) in list.iter().enumerate() {
        let bad = || format!("`color_map` entry {} must be [position, [r, g, b]] or [position, r, g, b]", i + 1);
        let Some(items) = entry.as_array() else { return Err(bad()) };
        let numbers: Option<Vec<f64>> = match items.as_slice() {
            [p, toml::Value::Array(c)] if c.len() == 3 => std::iter::once(p).chain(c.iter()).map(as_number).collect(),
            [p, v] => [p, v, v, v].into_iter().map(as_number).collect(),
            [_, _, _, _] => items.iter().map(as_number).collect(),
            _ => None,
        };
        let Some(n) = numbers else { return Err(bad()) };
        let n = n.into_iter().map(|v| in_scene_range("color_map", v)).collect::<Result<Vec<f32>, String>>()?;
        entries.push((n[0], [n[1], n[2], n[3]]));
    }
    ColorMap::new(entries)
}

/// The closest valid name to `unknown`, if close enough to be a typo (strsim, as the scene
/// parser's suggestions).
fn suggest(unknown: &str, valid: &[&str]) -> Option<String> {
    let lower = unknown.to_lowercase();
    valid
        .iter()
        .map(|v| (strsim::normalized_damerau_levenshtein(&lower, v), *v))
        .filter(|(score, _)| *score >= 0.5)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, v)| v.to_string())
}

fn describe(value: &toml::Value) -> String {
    match value {
        toml::Value::String(s) => format!("\"{s}\""),
        toml::Value::Table(_) => "a table".to_string(),
        other => other.to_string(),
    }
}

fn as_number(value: &toml::Value) -> Option<f64> {
    match value {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}

/// Finite and within the scene range (docs/limits.md), checked before narrowing to f32.
fn in_scene_range(field: &str, v: f64) -> Result<f32, String> {
    if !v.is_finite() {
        return Err(format!("`{field}` must be a finite number, got {}", v as f32));
    }
    if v.abs() > MAX_SCENE_VALUE {
        return Err(format!("`{field}` is {}; every number in a scene must be within +-1e9", fmt_number(v)));
    }
    Ok(v as f32)
}

fn finite(field: &str, v: f32) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("`{field}` must be a finite number, got {v}"))
    }
}

fn positive(field: &str, v: f32) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("`{field}` must be a number > 0, got {v}"))
    }
}

fn finite_vec(field: &str, v: Vec3) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("`{field}` must have finite components, got [{}, {}, {}]", v.x, v.y, v.z))
    }
}

/// An optional number field; integers are fine. NaN and infinities are refused.
fn number(t: &toml::Table, field: &str) -> Result<Option<f32>, String> {
    let Some(value) = t.get(field) else { return Ok(None) };
    let Some(v) = as_number(value) else {
        return Err(format!("`{field}` must be a number, got {}", describe(value)));
    };
    Ok(Some(in_scene_range(field, v)?))
}

/// An optional [x, y, z] field.
fn vector(t: &toml::Table, field: &str) -> Result<Option<Vec3>, String> {
    let Some(value) = t.get(field) else { return Ok(None) };
    let parsed =
        value.as_array().filter(|a| a.len() == 3).and_then(|a| a.iter().map(as_number).collect::<Option<Vec<f64>>>());
    let Some(v) = parsed else {
        return Err(format!("`{field}` must be an array of 3 numbers [x, y, z], got {}", describe(value)));
    };
    let [x, y, z] = [v[0], v[1], v[2]].map(|c| in_scene_range(field, c));
    Ok(Some(Vec3::new(x?, y?, z?)))
}

/// An optional [x, y, z] field that may also be one number v, meaning [v, v, v].
fn vector_or_number(t: &toml::Table, field: &str) -> Result<Option<Vec3>, String> {
    match t.get(field) {
        Some(value) if as_number(value).is_some() => Ok(number(t, field)?.map(Vec3::splat)),
        Some(toml::Value::Array(_)) | None => vector(t, field),
        Some(value) => Err(format!("`{field}` must be a number or an array [x, y, z], got {}", describe(value))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<(PatternDesc, Option<ColorMap>), String> {
        let value: toml::Value = toml::from_str(text).expect("test TOML is valid");
        parse_pattern(&value)
    }

    #[test]
    fn names_follow_the_kind_numbers() {
        assert_eq!(PATTERN_NAMES.len() as u32, shader::PATTERN_KIND_COUNT);
        for (code, name) in PATTERN_NAMES.iter().enumerate() {
            let kind = PatternKind::from_name(name).unwrap();
            assert_eq!(kind.code(), code as u32, "{name}");
            assert_eq!(kind.name(), *name);
            kind.default_color_map().validate().unwrap();
        }
        for (code, name) in WAVE_NAMES.iter().enumerate() {
            let (desc, _) = parse(&format!("pattern = \"bozo\"\nwave = \"{name}\"")).unwrap();
            assert_eq!(desc.wave.code(), code as u32);
            assert_eq!(desc.wave.name(), *name);
        }
    }

    #[test]
    fn full_table_parses_with_povray_defaults_elsewhere() {
        let (desc, map) = parse(
            r#"
pattern = "brick"
turbulence = [0.1, 0.2, 0.3]
octaves = 4
lambda = 3
brick_size = 2
color_map = [[0.0, [1, 0, 0]], [0.5, 0.25], [1, 0, 0, 1]]
"#,
        )
        .unwrap();
        assert_eq!(desc.kind, PatternKind::Brick { brick_size: Vec3::splat(2.0), mortar: 0.5 });
        assert_eq!(desc.turbulence, Vec3::new(0.1, 0.2, 0.3));
        assert_eq!((desc.octaves, desc.omega, desc.lambda), (4, 0.5, 3.0));
        assert_eq!((desc.frequency, desc.phase, desc.wave), (1.0, 0.0, WaveShape::Ramp));
        let map = map.unwrap();
        assert_eq!(map.entries, vec![(0.0, [1.0, 0.0, 0.0]), (0.5, [0.25; 3]), (1.0, [0.0, 0.0, 1.0])]);

        let (desc, map) = parse("pattern = \"wood\"\nturbulence = 0.3\nwave = \"poly_wave\"\nexponent = 2").unwrap();
        assert_eq!(desc.turbulence, Vec3::splat(0.3));
        assert_eq!(desc.wave, WaveShape::Poly { exponent: 2.0 });
        assert!(map.is_none());
        assert_eq!(PatternDesc::new(PatternKind::Marble).wave, WaveShape::Triangle);

        let (desc, _) = parse("pattern = \"gradient\"\norientation = [1, 0, 0]").unwrap();
        assert_eq!(desc.kind, PatternKind::Gradient { direction: Vec3::X });
        let (desc, _) = parse("pattern = \"crackle\"\nmetric = 1\nform = [1, 0, 0]\nsolid = true").unwrap();
        assert_eq!(desc.kind, PatternKind::Crackle { form: Vec3::X, metric: 1.0, offset: 0.0, solid: true });
    }

    #[test]
    fn errors_name_the_field_and_say_what_to_do() {
        let cases = [
            ("pattern = \"wod\"", "unknown pattern \"wod\" (did you mean \"wood\"?)"),
            ("pattern = \"zzzzzz\"", "unknown pattern \"zzzzzz\"; patterns are agate, bozo"),
            (
                "turbulance = 0.3\npattern = \"wood\"",
                "unknown field `turbulance` in pattern (did you mean `turbulence`?)",
            ),
            ("turbulence = 0.3", "missing `pattern`; name one of agate"),
            ("pattern = 3", "`pattern` must be a name such as \"wood\", got 3"),
            ("pattern = \"wood\"\noctaves = 12", "`octaves` must be an integer from 1 to 10, got 12"),
            ("pattern = \"wood\"\noctaves = 2.5", "`octaves` must be an integer from 1 to 10, got 2.5"),
            ("pattern = \"wood\"\nomega = \"big\"", "`omega` must be a number, got \"big\""),
            ("pattern = \"wood\"\nphase = nan", "`phase` must be a finite number, got NaN"),
            ("pattern = \"wood\"\nturbulence = [1, 2]", "`turbulence` must be an array of 3 numbers"),
            ("pattern = \"wood\"\nwave = \"sin\"", "unknown wave \"sin\" (did you mean \"sine\"?)"),
            ("pattern = \"wood\"\nexponent = 2", "`exponent` applies only to wave = \"poly\""),
            ("pattern = \"wood\"\nwave = \"poly\"\nexponent = 0", "`exponent` must be a number > 0, got 0"),
            ("pattern = \"wood\"\nmortar = 0.2", "`mortar` applies only to the brick pattern, not \"wood\"; remove it"),
            ("pattern = \"checker\"\nfrequency = 2", "`frequency` has no effect on the checker pattern"),
            ("pattern = \"gradient\"", "the gradient pattern needs `direction`"),
            ("pattern = \"gradient\"\ndirection = [0, 0, 0]", "`direction` must not be [0, 0, 0]"),
            ("pattern = \"brick\"\nbrick_size = [1, 0, 1]", "`brick_size` must be a number > 0, got 0"),
            ("pattern = \"brick\"\nmortar = -1", "`mortar` must be a number >= 0, got -1"),
            ("pattern = \"crackle\"\nmetric = -1", "`metric` must be a number > 0, got -1"),
            ("pattern = \"crackle\"\nsolid = 1", "`solid` must be true or false, got 1"),
            (
                "pattern = \"bozo\"\ncolor_map = [[0.0, [0, 0, 0]], [0.8, 1], [0.6, 0.5]]",
                "`color_map` positions must be in order: 0.6 comes after 0.8; sort the entries",
            ),
            ("pattern = \"bozo\"\ncolor_map = [[1.5, 1]]", "`color_map` entry 1: position 1.5 must be in [0, 1]"),
            ("pattern = \"bozo\"\ncolor_map = []", "`color_map` needs at least one entry"),
            ("pattern = \"bozo\"\ncolor_map = [[0, [1, 1]]]", "`color_map` entry 1 must be [position, [r, g, b]]"),
            ("pattern = \"bozo\"\ncolor_map = [[0, [1, -1, 1]]]", "`color_map` entry 1: colour [1, -1, 1] must have"),
            ("pattern = \"bozo\"\ncolor_map = 3", "`color_map` must be a list of [position, [r, g, b]]"),
        ];
        for (text, expected) in cases {
            let err = parse(text).expect_err(text);
            println!("{err}");
            assert!(err.starts_with(expected), "{text}:\n  got      {err}\n  expected {expected}");
            assert!(!err.ends_with('.') && err.starts_with(|c: char| !c.is_uppercase()), "{err}");
        }
        let not_a_table = parse_pattern(&toml::Value::Integer(3)).unwrap_err();
        assert!(not_a_table.starts_with("a pattern must be a table"), "{not_a_table}");
    }

    #[test]
    fn caller_fields_are_skipped_and_suggested() {
        let value: toml::Value = toml::from_str("pattern = \"bozo\"\nscale = 2").unwrap();
        assert!(parse_pattern(&value).unwrap_err().contains("unknown field `scale`"));
        parse_pattern_with(&value, &["scale", "rotate"]).unwrap();
        let value: toml::Value = toml::from_str("pattern = \"bozo\"\nrotat = 2").unwrap();
        let err = parse_pattern_with(&value, &["scale", "rotate"]).unwrap_err();
        assert_eq!(err, "unknown field `rotat` in pattern (did you mean `rotate`?)");
    }

    #[test]
    fn pack_writes_the_documented_block() {
        let mut data = vec![7u32; 3];
        let desc = PatternDesc {
            turbulence: Vec3::new(0.1, 0.2, 0.3),
            octaves: 4,
            frequency: 2.0,
            phase: 0.25,
            wave: WaveShape::Poly { exponent: 3.0 },
            ..PatternDesc::new(PatternKind::Crackle {
                form: Vec3::new(-1.0, 1.0, 0.0),
                metric: 1.5,
                offset: 0.5,
                solid: true,
            })
        };
        let at = desc.pack(&mut data);
        assert_eq!(at, 3);
        assert_eq!(data.len() as u32, 3 + shader::PATTERN_WORDS);
        let f = |i: u32| f32::from_bits(data[(at + i) as usize]);
        assert_eq!(data[(at + shader::PATTERN_KIND) as usize], shader::PATTERN_CRACKLE);
        assert_eq!(data[(at + shader::PATTERN_WAVE) as usize], shader::WAVE_POLY);
        assert_eq!(data[(at + shader::PATTERN_OCTAVES) as usize], 4);
        assert_eq!((f(shader::PATTERN_OMEGA), f(shader::PATTERN_LAMBDA)), (0.5, 2.0));
        assert_eq!([5, 6, 7].map(f), [0.1, 0.2, 0.3]);
        assert_eq!(
            (f(shader::PATTERN_FREQUENCY), f(shader::PATTERN_PHASE), f(shader::PATTERN_EXPONENT)),
            (2.0, 0.25, 3.0)
        );
        assert_eq!([12, 13, 14, 15, 16].map(f), [-1.0, 1.0, 0.0, 1.5, 0.5]);
        assert_eq!(data[(at + 17) as usize], 1);

        let map = ColorMap::grey(&[(0.0, 0.25), (1.0, 0.75)]).unwrap();
        let at = map.pack(&mut data);
        assert_eq!(
            data[at as usize..],
            [
                2,
                0.0f32.to_bits(),
                0.25f32.to_bits(),
                0.25f32.to_bits(),
                0.25f32.to_bits(),
                1.0f32.to_bits(),
                0.75f32.to_bits(),
                0.75f32.to_bits(),
                0.75f32.to_bits()
            ]
        );
    }

    #[test]
    fn warps_are_read_with_their_transforms_and_checked() {
        let (desc, _) = parse(
            "pattern = \"bozo\"\nwarp = [{ type = \"repeat\", direction = [0, -2, 0], offset = [1, 0, 0], flip = [1, 0, 1] },\n\
             { type = \"toroidal\", major_radius = 3, transform = { scale = 2, translate = [0, 1, 0] } }]",
        )
        .unwrap();
        let warps: Vec<&Warp> = desc.warp_list().collect();
        assert_eq!(
            warps[0].kind,
            WarpKind::Repeat { axis: 1, width: -2.0, offset: Vec3::X, flip: Vec3::new(-1.0, 1.0, -1.0) }
        );
        assert_eq!(warps[1].kind, WarpKind::Toroidal { orientation: Vec3::Z, dist_exp: 0.0, major_radius: 3.0 });
        assert_eq!(warps[1].transform.transform_point3(Vec3::ONE), Vec3::new(2.0, 3.0, 2.0));
        // Packed after the block, the last written first.
        let mut data = Vec::new();
        desc.pack(&mut data);
        assert_eq!(data[shader::PATTERN_WARP_COUNT as usize], 2);
        assert_eq!(data.len() as u32, shader::PATTERN_WORDS + 2 * shader::WARP_WORDS);
        assert_eq!(data[shader::PATTERN_WORDS as usize], shader::WARP_TOROIDAL);
        assert_eq!(data[(shader::PATTERN_WORDS + shader::WARP_WORDS) as usize], shader::WARP_REPEAT);

        for (text, message) in [
            ("warp = [{ type = \"repaet\" }]", "`warp` entry 1: unknown warp \"repaet\" (did you mean \"repeat\"?)"),
            ("warp = [{ type = \"repeat\" }]", "a repeat warp needs `direction`"),
            ("warp = [{ type = \"repeat\", direction = [1, 1, 0] }]", "must be along one axis"),
            ("warp = [{ type = \"planar\", radius = 1 }]", "unknown field `radius` in a planar warp"),
            ("warp = [{ type = \"black_hole\", center = [0, 0, 0] }]", "a black_hole warp needs `radius`"),
            ("warp = [{ type = \"black_hole\", center = [0, 0, 0], radius = -1 }]", "`radius` must be a number > 0"),
            ("warp = [{ type = \"spherical\", transform = { scale = 0 } }]", "`transform.scale` is 0"),
            ("warp = { type = \"planar\" }", "`warp` must be a list of tables"),
            (
                "warp = [{ type = \"planar\" }, { type = \"planar\" }, { type = \"planar\" }, { type = \"planar\" }, { type = \"planar\" }]",
                "a pattern takes at most 4",
            ),
        ] {
            let e = parse(&format!("pattern = \"bozo\"\n{text}")).unwrap_err();
            assert!(e.contains(message), "{text}: {e}");
        }
    }
}
