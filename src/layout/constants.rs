//! Numbers shared by the Rust code and the shaders. `build.rs` includes this file and writes every
//! constant into `constants.glsl`, so each number is typed exactly once.

macro_rules! shared_constants {
    ($( $(#[$doc:meta])* $name:ident : $ty:ident = $value:expr; )*) => {
        $( $(#[$doc])* pub const $name: $ty = $value; )*
        /// Every shared constant as (name, GLSL type, GLSL literal), for `build.rs`.
        #[allow(dead_code)]
        pub fn glsl_constants() -> Vec<(&'static str, &'static str, String)> {
            vec![$( (stringify!($name), shared_constants!(@glsl_type $ty), shared_constants!(@literal $ty, $value)) ),*]
        }
    };
    (@glsl_type u32) => { "uint" };
    (@glsl_type f32) => { "float" };
    (@literal u32, $value:expr) => { format!("{}u", $value as u32) };
    (@literal f32, $value:expr) => { format!("{:?}", $value as f32) };
}

shared_constants! {
    /// Lambertian reflector; `Material::color0` is its albedo.
    MATERIAL_DIFFUSE: u32 = 0;
    /// Perfect mirror; `Material::color0` is its tint.
    MATERIAL_MIRROR: u32 = 1;
    /// Dielectric interface, index `Material::ior` inside, tint `color0`: smooth (Fresnel
    /// reflection and refraction) when `roughness` is 0, else GGX (Walter et al. 2007).
    MATERIAL_DIELECTRIC: u32 = 2;
    /// Metal: complex index of refraction `color0` (eta) + i `color1` (k) per channel, smooth or
    /// GGX with widths `roughness` (anisotropic along dpdu and dpdv).
    MATERIAL_CONDUCTOR: u32 = 3;
    /// A diffuse base of albedo `color0` under a dielectric coat of index `ior`, smooth or GGX.
    MATERIAL_PLASTIC: u32 = 4;
    /// Material `mix_b` where a hash of the point falls below `weight` (times `weight_tex`), else
    /// `mix_a`: a stochastic blend, the same for camera rays and photons at a point.
    MATERIAL_MIX: u32 = 5;
    /// An invisible interface (Mitsuba's `null`): rays pass straight through it, unbent and
    /// uncounted; it only bounds the medium of its shape (`Primitive::interior`).
    MATERIAL_NULL: u32 = 6;
    /// Never packed from a file: the `Bsdf` of a scattering point inside a medium, whose "BSDF"
    /// is the medium's phase function (`PHASE_*` in `color1.x`, asymmetry g in `ior`), so that
    /// light sampling and photon lookups treat it as any estimate vertex.
    MATERIAL_PHASE: u32 = 7;
    /// A thin pane of index `ior` (Mitsuba's `thindielectric`): it reflects the Fresnel
    /// reflectance summed over the pane's inner reflections, R + T^2 R / (1 - R^2), and lets
    /// the rest through with the direction unchanged; no medium inside.
    MATERIAL_THIN_DIELECTRIC: u32 = 8;
    /// Reconstruction filters (`FrameParams::filter`, `[render] filter`): a camera sample's film
    /// point is drawn from the filter around its pixel's centre (filter importance sampling), and
    /// a light-tracing splat is spread over the pixels whose filter reaches its film point,
    /// weighted by the filter. The box is one pixel wide (every pixel its own square).
    FILTER_BOX: u32 = 0;
    /// 1 - |x| per axis, radius 1 pixel (Mitsuba's `tent`).
    FILTER_TENT: u32 = 1;
    /// A Gaussian of standard deviation `FILTER_GAUSSIAN_STDDEV` per axis, truncated at
    /// `FILTER_GAUSSIAN_RADIUS` pixels (Mitsuba's `gaussian` defaults).
    FILTER_GAUSSIAN: u32 = 2;
    FILTER_GAUSSIAN_STDDEV: f32 = 0.5;
    FILTER_GAUSSIAN_RADIUS: f32 = 2.0;
    /// erf(radius / (stddev sqrt 2)): the Gaussian's mass inside its radius.
    FILTER_GAUSSIAN_MASS: f32 = 0.999_936_66;
    /// 1 / (stddev sqrt(2 pi) mass): the truncated Gaussian's peak, so it integrates to 1.
    FILTER_GAUSSIAN_NORM: f32 = 0.797_935_1;
    /// Deepest nesting of mixes the kernels resolve (the host refuses deeper ones).
    MIX_MAX_DEPTH: u32 = 4;
    /// `Material::flags`: a plastic whose base light bounces under the coat tint it again
    /// (Mitsuba's `nonlinear`; see `cpu::microfacet::plastic_eval`).
    MATERIAL_FLAG_NONLINEAR: u32 = 1;
    /// `Material::flags`: a rough conductor, dielectric or plastic whose microfacets follow
    /// Beckmann's distribution rather than GGX's (scene `distribution = "beckmann"`).
    MATERIAL_FLAG_BECKMANN: u32 = 2;
    /// `Material::flags`: emission leaves both faces (scene `two_sided = true`), not the front
    /// (the side the geometric normal points to) alone.
    MATERIAL_FLAG_TWO_SIDED: u32 = 4;
    /// The `dist` argument of the microfacet functions (`cpu::microfacet`): GGX ...
    MICROFACET_GGX: u32 = 0;
    /// ... or Beckmann (Mitsuba's default for its rough plugins).
    MICROFACET_BECKMANN: u32 = 1;
    /// The bit of `KernelVariant::material_kinds` (`SCENE_MATERIAL_KINDS`) set where a material
    /// has `MATERIAL_FLAG_BECKMANN`: no kind, but compiled in or out like one, so scenes without
    /// Beckmann microfacets build the GGX code alone. Above every `MATERIAL_*` kind.
    SCENE_KIND_BECKMANN: u32 = 31;
    /// Entries of a rough nonlinear plastic's coat transmittance table, at cosines i / (n - 1)
    /// (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
    PLASTIC_COAT_TABLE: u32 = 64;
    /// Words of a coat table in the texture data: its internal diffuse reflectance, then the
    /// `PLASTIC_COAT_TABLE` transmittances (f32 bits).
    PLASTIC_COAT_WORDS: u32 = 65;
    /// Default of `[photons] glossy_threshold`: glossy lobes with GGX width up to this are followed
    /// by paths (sharp reflections and caustics through them); rougher ones end camera paths and
    /// read the photon maps with the BSDF's value (docs/materials.md).
    GLOSSY_THRESHOLD: f32 = 0.25;
    /// Rounding slack of `disc_reaches` (cpu/vcm.rs), relative to the bounding radius, so that
    /// the points infinite lights' sub-paths start from on the disc's rim stay inside.
    DISC_SLACK: f32 = 1e-4;

    /// Lobe flags of a BSDF (`bsdf_flags`), in the spirit of Mitsuba 3's `BSDFFlags`.
    BSDF_DIFFUSE: u32 = 1;
    BSDF_GLOSSY: u32 = 2;
    BSDF_SPECULAR: u32 = 4;
    BSDF_REFLECTION: u32 = 8;
    BSDF_TRANSMISSION: u32 = 16;
    /// The lobes a camera path ends at: they store photons, are lit by light sampling and read the
    /// photon maps with the BSDF's value (diffuse, and glossy lobes too rough to follow).
    BSDF_ESTIMATE: u32 = 32;
    /// The lobes a path follows (mirrors, glass, smooth glossy): they store no photons.
    BSDF_PATH: u32 = 64;
    /// Which lobes `bsdf_sample` draws from.
    LOBES_ESTIMATE: u32 = 32;
    LOBES_PATH: u32 = 64;
    LOBES_ALL: u32 = 96;

    /// A triangle primitive: `p0`, `p1`, `p2` are its vertices; `data` (when not `NO_DATA`) holds
    /// the uv of its three vertices (6 floats), else uv is (b1, b2) of the barycentrics.
    PRIMITIVE_TRIANGLE: u32 = 0;
    /// An analytic sphere: `p0` is its centre, `p1[0]` its radius; `data` holds the rows of its
    /// `object_from_world` rotation (9 floats) that orients its longitude/latitude uv.
    PRIMITIVE_SPHERE: u32 = 1;
    /// The analytic shapes below are intersected in their own object space: `data` holds a block
    /// of `SHAPE_DATA_FLOATS` (see `SHAPE_DATA_*`) with the transform both ways; `p0..p2` hold
    /// the shape's own numbers. They live in the `analytic` variant of the scene kernels (tori
    /// and superellipsoids in `analytic_implicit`).
    /// An infinite plane y = 0 (normal +y); unbounded, so it stays out of the BVH (the primitives
    /// from `FrameParams::unbounded_first` on are tested by every ray). No numbers.
    PRIMITIVE_PLANE: u32 = 2;
    /// A disc (or an annulus) in y = 0 around the origin, normal +y: `p0 = [radius, inner radius, 0]`.
    PRIMITIVE_DISC: u32 = 3;
    /// The side of a truncated cone (a cylinder when both radii are equal) around +y from y = 0
    /// to y = h: `p0 = [radius at 0, radius at h, h]`. Caps are discs of their own.
    PRIMITIVE_CONE: u32 = 4;
    /// A torus around the y axis: `p0 = [major radius R, minor radius r, 0]`, r < R.
    PRIMITIVE_TORUS: u32 = 5;
    /// POV-Ray's superellipsoid inside [-1, 1]^3, (|x|^(2/e) + |y|^(2/e))^(e/n) + |z|^(2/n) = 1:
    /// `p0 = [2/e, e/2, 2/n]`, `p1 = [n/2, 0, 0]`.
    PRIMITIVE_SUPERELLIPSOID: u32 = 6;
    /// Offsets in an analytic shape's data block: the rows of `object_from_world` (3x4), the rows
    /// of `world_from_object` (3x4), |det| of its linear part, and the shape's size (the largest
    /// coordinate of its world bounds; 0 for a plane), which scales its ray offsets.
    SHAPE_DATA_OBJECT_FROM_WORLD: u32 = 0;
    SHAPE_DATA_WORLD_FROM_OBJECT: u32 = 12;
    SHAPE_DATA_DET: u32 = 24;
    SHAPE_DATA_SIZE: u32 = 25;
    SHAPE_DATA_FLOATS: u32 = 26;
    /// Offsets in an instance's record in the shape data (`FrameParams::instance_data` +
    /// instance x `INSTANCE_DATA_FLOATS`): the rows of `object_from_world` and of
    /// `world_from_object` (3x4 each); then, as float bits, its object's BVH (root node, and the
    /// root's miss link, where the object's nodes end) and its material override (`NO_DATA`:
    /// its object's materials); then the largest factor its linear part stretches a length by,
    /// which scales the ray offsets of its analytic shapes.
    INSTANCE_DATA_OBJECT_FROM_WORLD: u32 = 0;
    INSTANCE_DATA_WORLD_FROM_OBJECT: u32 = 12;
    INSTANCE_DATA_ROOT: u32 = 24;
    INSTANCE_DATA_END: u32 = 25;
    INSTANCE_DATA_MATERIAL: u32 = 26;
    INSTANCE_DATA_SCALE: u32 = 27;
    INSTANCE_DATA_FLOATS: u32 = 28;
    /// Most loop turns of one `trace_ray` over both levels of the BVH (nodes visited, the
    /// world's and the instances' objects' alike): lavapipe stops an invocation after 65535 loop
    /// iterations in all, and overlapping instances multiply the nodes a ray may visit. A ray
    /// that reaches it keeps the closest hit found so far (docs/limits.md).
    TRACE_STEPS: u32 = 4096;
    /// Ray origins leave an analytic shape's hit point by this times (its largest coordinate +
    /// the shape's size): its hit points are projected onto the surface in object space, so
    /// their error scales with those, not with the scene (this is about 17 float ulps of each).
    SHAPE_EPSILON_SCALE: f32 = 1.0e-6;
    /// Half the loop turns (gauge evaluations) of a superellipsoid's search for its entry and
    /// exit (each Newton's method from one side of a convex function, so monotone; a grazing
    /// ray's double root still halves the gap each step).
    SUPERELLIPSOID_STEPS: u32 = 24;
    /// Superellipsoid Newton steps stop once the gauge is this close to 1 (about 1e-6 object
    /// units off the surface).
    SUPERELLIPSOID_TOLERANCE: f32 = 1.0e-6;
    /// Half side of the box the superellipsoid's root search starts from: the unit box grown so
    /// that its entry point lies clearly outside even a boxy shape, whose faces fill the unit
    /// box's faces to float precision.
    SUPERELLIPSOID_BOX: f32 = 1.001;
    /// Radius, over the bounding sphere's, of the sphere on whose chord the torus's roots are
    /// sought: the outer equator touches the bounding sphere, and a chord ending on a root would
    /// leave its sign to rounding.
    TORUS_CHORD: f32 = 1.001;
    /// Most safeguarded Newton steps per bracketed root of the torus quartic and of its
    /// derivative; bisection alone needs 24 to reach float precision on [-1, 1]. The brackets
    /// span the whole chord (the searches do not start at t_min, so the CSG walk can restart
    /// them), where Newton may fall back to bisection for a while: with 16 steps, the root of
    /// the surface a ray leaves was left up to 3e-5 off, past the ray's offset.
    TORUS_ROOT_STEPS: u32 = 32;
    /// Newton steps that invert the torus's area cdf (Kepler's equation) when it is sampled.
    TORUS_SAMPLE_STEPS: u32 = 8;
    /// Low bits of `Primitive::kind` holding the shape kind; the bits above are flags.
    PRIMITIVE_KIND_MASK: u32 = 0xff;
    /// Flag of `Primitive::kind`: the material has an opacity below 1 somewhere (alpha), so every
    /// ray that meets the primitive decides by the opacity whether it passes.
    PRIMITIVE_FLAG_ALPHA: u32 = 0x100;
    /// Flag of `Primitive::kind`: the shape bounds a medium. A ray that crosses it against its
    /// outward normal (triangles: the winding side) enters `Primitive::interior`, one that
    /// crosses it along the normal leaves for `Primitive::exterior`; primitives without the flag
    /// leave the ray's medium as it is.
    PRIMITIVE_FLAG_MEDIUM: u32 = 0x400;
    /// Flag of `Primitive::kind`: its material reads uv or the surface derivatives (textures, bump
    /// and normal maps); without it a hit record leaves them at zero, which saves their cost.
    PRIMITIVE_FLAG_UV: u32 = 0x200;
    /// Flag of a triangle's `Primitive::kind`: smooth shading. Its `data` block is a
    /// `TriangleShading` (vertex uvs, then unit vertex normals on the winding side); the shading
    /// normal interpolates the vertex normals, and rays leave from Hanika's shifted point
    /// (`Hit::shift`), which hides the shadow terminator of low-poly meshes.
    PRIMITIVE_FLAG_SMOOTH: u32 = 0x800;
    /// A CSG object (union, intersection, difference, merge of closed shapes): one BVH primitive
    /// whose `data` is a CSG block in the shape data (`CSG_DATA_*`). Its leaves' primitives sit
    /// after the scene's own, from `FrameParams::primitive_count` on, where no ray meets them
    /// except through the block's walk (`shaders/csg.glsl`). In the `analytic` kernel variant.
    PRIMITIVE_CSG: u32 = 7;
    /// Flag of a CSG leaf's `Primitive::kind`: the leaf lies on the subtracted side of an odd
    /// number of differences, so the solid's outward normal is the leaf's inward one.
    PRIMITIVE_FLAG_CSG_FLIP: u32 = 0x1000;
    /// Flags of a triangle's `Primitive::kind`, this one shifted by e: no other triangle has its
    /// side e (from vertex e to the next), so the surface ends there (`render/open_edges.rs`).
    PRIMITIVE_FLAG_OPEN_EDGE: u32 = 0x2000;
    /// Words of a CSG block (u32 bits stored in the f32 shape data): the count of its leaf
    /// primitives, the length of its postfix program, the index of its first leaf primitive
    /// counted from `FrameParams::primitive_count`, then the leaf index of each leaf primitive
    /// (leaves are contiguous runs), then the program.
    CSG_DATA_PRIMITIVES: u32 = 0;
    CSG_DATA_PROGRAM_LENGTH: u32 = 1;
    CSG_DATA_FIRST: u32 = 2;
    CSG_DATA_LEAVES: u32 = 3;
    /// A program word is `op << CSG_OP_SHIFT | leaf`: `CSG_OP_LEAF` pushes the leaf's inside bit,
    /// the others pop two values (a below b) and push a op b.
    CSG_OP_SHIFT: u32 = 16;
    CSG_OP_LEAF: u32 = 0;
    /// Union (POV-Ray's): every child's surface stays visible, inner ones included.
    CSG_OP_UNION: u32 = 1;
    /// Merge: a union without the surfaces inside other children.
    CSG_OP_MERGE: u32 = 2;
    CSG_OP_INTERSECTION: u32 = 3;
    /// a minus b.
    CSG_OP_DIFFERENCE: u32 = 4;
    /// Most leaves of one CSG object (its inside state is one 32-bit mask).
    CSG_MAX_LEAVES: u32 = 32;
    /// Most primitives over all leaves of one CSG object (a box is 12 triangles, a capped
    /// cylinder 3 primitives): each step of the walk tests every one.
    CSG_MAX_PRIMITIVES: u32 = 64;
    /// Most nested CSG nodes from an object's root to a leaf.
    CSG_MAX_DEPTH: u32 = 16;
    /// Most tori and superellipsoids among the leaves of one CSG object: the walk runs their
    /// root searches (up to 7 x `TORUS_ROOT_STEPS` or 2 x `SUPERELLIPSOID_STEPS` loop turns) at
    /// every crossing, where a sphere or a triangle costs one turn.
    CSG_MAX_IMPLICIT: u32 = 4;
    /// Most distinct crossings the walk of one ray through one CSG object visits (those behind
    /// the ray's origin included); a ray that needs more passes the rest of the object as a miss.
    /// With the caps above a walk runs at most 32 x (64 + 63) loop iterations.
    CSG_MAX_STEPS: u32 = 32;
    /// Float offsets inside a smooth triangle's `TriangleShading` block (checked against the
    /// struct by a const assertion in src/layout/mod.rs).
    TRIANGLE_DATA_UV: u32 = 0;
    TRIANGLE_DATA_NORMALS: u32 = 6;
    TRIANGLE_DATA_FLOATS: u32 = 15;

    /// A light that is an emitting primitive (`Light::primitive`), sampled by `shape_sample` (a
    /// point and its 1/pdf by area).
    LIGHT_AREA: u32 = 0;
    /// Flag of `Light::grid`: a POV-Ray grid's samples are jittered within their cells (else
    /// they sit at the cells' centres). The grid itself is n | m << 8, n and m in 1..=64.
    LIGHT_GRID_JITTER: u32 = 0x10000;
    /// Flag of `Light::grid`: POV-Ray's `adaptive`. Once a pixel's shadow rays toward adaptive
    /// lights in this pass were some blocked and some not, its samples from the light's next
    /// cycle of n m samples on cast one ray per cell of the grid toward it, each weighted
    /// 1/(n m); before, one ray (see `direct_light_sample`).
    LIGHT_GRID_ADAPTIVE: u32 = 0x20000;
    /// Most cells of an adaptive light's grid: the shadow rays of one camera vertex.
    ADAPTIVE_MAX_RAYS: u32 = 256;
    /// No sample: a pixel not (yet) found in a penumbra (see `LIGHT_GRID_ADAPTIVE`).
    NO_SAMPLE: u32 = 0xffff_ffff;
    /// `DispatchRange::pixel_list` of a dispatch that renders every pixel of its band.
    NO_PIXEL_LIST: u32 = 0xffff_ffff;
    /// A point light: `Light::intensity` (W/sr) at `position`. It is a spot light whose cone is
    /// the whole sphere (`cos_outer` = -1), so point and spot share one code path.
    LIGHT_POINT: u32 = 2;
    /// A spot light: a point light whose intensity along direction w is `intensity` times
    /// `spot_falloff` (a smooth step in cos from `cos_outer` to the inner cone, times
    /// cos^`exponent`), zero outside the cone of `cos_outer` around `direction`.
    LIGHT_SPOT: u32 = 3;
    /// A distant (directional) light: light travels along `direction` from a cone of directions
    /// of half-angle acos(`cos_outer`) (0 for a sharp light); `intensity` holds its radiance times
    /// the cone's solid angle (W/m^2 per unit solid-angle pdf, see `prepare.rs`). Its photons leave
    /// a disc of radius `radius` around the scene's bounding sphere centred at `position`.
    LIGHT_DISTANT: u32 = 4;
    /// The environment: radiance from every direction, a latitude-longitude image. `primitive`
    /// is the word offset of its block in the texture data (`ENV_*` below); `position` and
    /// `radius` are the bounding sphere its photons enter through, as for a distant light.
    LIGHT_ENVIRONMENT: u32 = 5;
    /// Words of an environment block, from its offset: width W, height H, cos and sin of its
    /// rotation about +y (f32 bits), then W x H texels of RGB radiance (f32 bits, row 0 = the
    /// zenith, column W/2 = -z), the marginal cdf over rows (H + 1 floats) and each row's
    /// conditional cdf over columns (W + 1 floats per row), of luminance times sin(theta).
    ENV_WIDTH: u32 = 0;
    ENV_HEIGHT: u32 = 1;
    ENV_COS_ROTATION: u32 = 2;
    ENV_SIN_ROTATION: u32 = 3;
    ENV_TEXELS: u32 = 4;

    /// Words of the light tree's block in the texture data, from `FrameParams::light_tree`
    /// (see `render::light_tree`): the word of the root node (`NO_LIGHT`: no finite light casts
    /// direct light), the tree's share of direct-light selection (f32 bits), the number k of
    /// infinite lights chosen beside it, then k pairs (light index, running probability as f32
    /// bits ending at 1) from which an infinite light is drawn in the rest of the choice.
    LIGHT_TREE_ROOT: u32 = 0;
    LIGHT_TREE_SHARE: u32 = 1;
    LIGHT_TREE_INFINITE_COUNT: u32 = 2;
    LIGHT_TREE_INFINITE: u32 = 3;
    /// Words of one light-tree node, from its word: bounds min and max (3 + 3 f32), power
    /// (f32), the emission cone's axis (3 f32), cos of its spread (f32; Conty and Kulla's
    /// theta_o; their falloff theta_e is pi/2 for every light we have), then the child word:
    /// the second child's node word (the first follows this node), or a leaf's light index with
    /// `LIGHT_NODE_LEAF` set.
    LIGHT_NODE_MIN: u32 = 0;
    LIGHT_NODE_MAX: u32 = 3;
    LIGHT_NODE_POWER: u32 = 6;
    LIGHT_NODE_AXIS: u32 = 7;
    LIGHT_NODE_COS_SPREAD: u32 = 10;
    LIGHT_NODE_CHILD: u32 = 11;
    LIGHT_NODE_WORDS: u32 = 12;
    LIGHT_NODE_LEAF: u32 = 0x8000_0000;
    /// Deepest light tree the kernels walk (the host builds balanced ones, far shallower).
    LIGHT_TREE_MAX_DEPTH: u32 = 32;

    /// `FrameParams::camera_kind`: a perspective camera (pinhole, or thin lens with
    /// `lens_radius` > 0): film position (sx, sy) looks along `forward + sx right + sy up`.
    CAMERA_PERSPECTIVE: u32 = 0;
    /// Orthographic: rays start at `position + sx right + sy up` and run along `forward`.
    CAMERA_ORTHOGRAPHIC: u32 = 1;
    /// 360-degree latitude-longitude: sx spans longitude -180..180 degrees around `up`
    /// (0 = `forward`, +90 = `right`), sy latitude -90..90 degrees; `right` and `up` are unit.
    CAMERA_LATLONG: u32 = 2;

    /// A texture of one colour, `Texture::value`.
    TEXTURE_CONSTANT: u32 = 0;
    /// An image: `Texture::data` is its block (shaders/image_texture.glsl), looked up with
    /// bilinear filtering at the uv its projection (`TEXTURE_PROJECTION_*`) makes of the
    /// texture-space point, (x, y) for a planar one.
    TEXTURE_IMAGE: u32 = 1;
    /// A procedural 3D pattern (shaders/pattern.glsl): `data` is its block, `color_map` the map
    /// from its value in [0, 1] to a colour.
    TEXTURE_PATTERN: u32 = 2;
    /// A voxel grid (shaders/voxel.glsl): `data` is its block, looked up with trilinear
    /// filtering in the unit cube of texture space (0 outside it); grey.
    TEXTURE_VOXELS: u32 = 3;
    /// POV-Ray's ground fog as a density: 1 at heights (texture-space y, after a turbulence warp
    /// when `data` holds a pattern block) up to `value[0]` (fog_offset), 1 / (1 + (y -
    /// offset) / alt)^2 above, alt = `value[1]` (fog_alt); grey.
    TEXTURE_GROUND_FOG: u32 = 4;
    /// Words of a voxel block's header: nx, ny, nz; the nx ny nz floats follow, x fastest.
    VOXEL_HEADER_WORDS: u32 = 3;
    /// `Texture::channel`: the colour as it is, or one channel of an image spread to grey.
    TEXTURE_CHANNEL_RGB: u32 = 0;
    TEXTURE_CHANNEL_R: u32 = 1;
    TEXTURE_CHANNEL_G: u32 = 2;
    TEXTURE_CHANNEL_B: u32 = 3;
    TEXTURE_CHANNEL_A: u32 = 4;
    /// Step in u and v of the central differences that give a bump map's slope (pbrt's default
    /// when a ray has no differentials).
    BUMP_DELTA: f32 = 0.0005;
    /// Where a texture looks itself up: (u, v, 0) of the surface, or the hit point in world space.
    TEXTURE_SPACE_UV: u32 = 0;
    TEXTURE_SPACE_WORLD: u32 = 1;
    /// An image texture's projection, in bits `TEXTURE_PROJECTION_SHIFT` and up of
    /// `Texture::space` (the space is bits 0-7): how the texture-space point p becomes uv.
    /// Planar: (p.x, p.y). Spherical (POV-Ray's map_type 1): u = atan2(p.z, p.x) / 2 pi in [0, 1),
    /// v = 1/2 + asin(p.y / |p|) / pi. Cylindrical (map_type 2): u as spherical, v = p.y. u = 0
    /// where p.x = p.z = 0, v = 1/2 at the origin.
    TEXTURE_PROJECTION_SHIFT: u32 = 8;
    TEXTURE_PROJECTION_PLANAR: u32 = 0;
    TEXTURE_PROJECTION_SPHERICAL: u32 = 1;
    TEXTURE_PROJECTION_CYLINDRICAL: u32 = 2;

    /// Marks no medium (vacuum): the camera, a light, or the inside of a shape outside every medium.
    NO_MEDIUM: u32 = 0xffff_ffff;
    /// Phase functions of a medium (`Medium::phase`): isotropic, 1 / (4 pi); Henyey and
    /// Greenstein 1941 with asymmetry `Medium::g` in (-1, 1) (g > 0 scatters forward).
    PHASE_ISOTROPIC: u32 = 0;
    PHASE_HENYEY_GREENSTEIN: u32 = 1;
    /// Medium boundaries a path may cross beyond its `max_depth` bounces (each crossing is one
    /// step of the camera kernel's loop; a path past it ends, as one past `max_depth` does).
    MEDIUM_CROSSINGS: u32 = 16;
    /// Most tentative collisions of one delta- or ratio-tracking walk through a heterogeneous
    /// medium: lavapipe stops an invocation after 65535 loop iterations in all, and the camera
    /// kernel may track on each of its steps (docs/limits.md).
    MEDIUM_TRACKING_STEPS: u32 = 128;
    /// Ratio tracking plays Russian roulette once the transmittance falls below this in every
    /// channel (it survives with probability max / this), so thick media end their walks early.
    MEDIUM_ROULETTE: f32 = 0.1;
    /// Salt of the tracking walks' random numbers (hashed with the walk's key and step).
    MEDIUM_WALK_SALT: u32 = 0x6d65_6469;
    /// Equiangular samples toward a spot light stay inside its cone, widened by this much in
    /// cosine (`spot_span`).
    SPOT_SPAN_MARGIN: f32 = 0.001;

    /// Marks a primitive that is not a light.
    NO_LIGHT: u32 = 0xffff_ffff;
    /// Marks a material parameter without a texture (the constant alone), or a missing data block.
    NO_TEXTURE: u32 = 0xffff_ffff;
    NO_DATA: u32 = 0xffff_ffff;

    /// Bindings every kernel that sees the scene declares (shaders/scene_bindings.glsl) and the
    /// host binds in this order (`DeviceScene::bindings`); a kernel's own bindings follow.
    BINDING_FRAME: u32 = 0;
    BINDING_NODES: u32 = 1;
    BINDING_PRIMITIVES: u32 = 2;
    BINDING_MATERIALS: u32 = 3;
    BINDING_LIGHTS: u32 = 4;
    BINDING_TEXTURES: u32 = 5;
    BINDING_TEXTURE_DATA: u32 = 6;
    BINDING_SHAPE_DATA: u32 = 7;
    BINDING_MEDIA: u32 = 8;
    SCENE_BINDINGS: u32 = 9;
    /// Pages (texel buffers) each scene array's binding holds: an array larger than one view
    /// (the device's page, `DeviceScene::page_bytes`) is split over up to this many
    /// (shaders/scene_fetch.glsl's `PAGED_TEXEL` has a case per page).
    SCENE_PAGES: u32 = 8;

    /// Words of the state an invocation of render_vcm and of vcm_light stores when it stops
    /// after `VcmParams::steps_per_dispatch` vertices: the run's next path and the path under
    /// way (`CameraPath`, `LightPath`, word by word in the kernels' `store_run`).
    VCM_CAMERA_STATE_WORDS: u32 = 42;
    VCM_LIGHT_STATE_WORDS: u32 = 28;

    /// Threads per workgroup of the one-dimensional kernels.
    WORKGROUP_SIZE: u32 = 64;
    /// Threads of a `grid_scan` workgroup, and the values one workgroup scans.
    SCAN_THREADS: u32 = 256;
    SCAN_BLOCK: u32 = 1024;
    /// Low bits of `BvhNode::skip_count` holding a leaf's primitive count (leaves hold at most 7).
    BVH_COUNT_BITS: u32 = 3;
    BVH_COUNT_MASK: u32 = 7;

    /// Random dimensions drawn per path vertex; the dimensions below are offsets inside that block.
    RNG_DIMS_PER_BOUNCE: u32 = 8;
    /// One hash gives four numbers: x and y jitter the film position, z and w sample the lens.
    RNG_PIXEL_X: u32 = 0;
    RNG_PIXEL_Y: u32 = 1;
    RNG_LIGHT_PICK: u32 = 2;
    RNG_LIGHT_U: u32 = 3;
    RNG_LIGHT_V: u32 = 4;
    /// One hash gives four numbers: x is the Fresnel (or lobe) choice, y and z the BSDF's
    /// direction sample, w the choice between a BSDF's path and estimate lobes.
    RNG_FRESNEL: u32 = 5;
    /// Russian roulette of a path-traced camera path (`integrator = "pt"`).
    RNG_ROULETTE: u32 = 6;
    /// bpt's and vcm's choice of the light vertices a camera vertex connects to (one hash: up
    /// to four choices, `VCM_CONNECTIONS`).
    RNG_CONNECT_PICK: u32 = 7;
    /// A path-traced camera path plays Russian roulette from this many vertices on, surviving
    /// with its throughput's largest channel, at most `PT_ROULETTE_MAX` (Mitsuba 3's rr_depth 5
    /// and 0.95: a path's first bounces carry most of the light, and a cap keeps bright paths
    /// from being cut).
    PT_ROULETTE_DEPTH: u32 = 5;
    PT_ROULETTE_MAX: f32 = 0.95;
    /// bpt's and vcm's sub-paths, camera and light alike, play it from this vertex on: their
    /// later vertices add connections (a shadow ray each) rather than one light sample, so a
    /// vertex costs more there and early roulette buys more samples than it adds noise (at 30 s
    /// on cornell-glossy, 1.3x lower error than from vertex 5; pt loses 1.7x with it on the box:
    /// BENCHMARKS.md, "Russian roulette from the first vertex").
    BPT_ROULETTE_DEPTH: u32 = 1;

    /// Photon paths draw from dimensions above this, so they never share numbers with camera paths.
    RNG_PHOTON_DOMAIN: u32 = 0x8000_0000;
    /// Final-gather rays draw from dimensions above this.
    RNG_GATHER_DOMAIN: u32 = 0x4000_0000;
    /// Offsets inside a photon path vertex's block of `RNG_DIMS_PER_BOUNCE` dimensions.
    RNG_PHOTON_LIGHT_PICK: u32 = 0;
    RNG_PHOTON_POSITION: u32 = 1;
    RNG_PHOTON_DIRECTION: u32 = 2;
    RNG_PHOTON_BOUNCE: u32 = 3;
    RNG_PHOTON_ROULETTE: u32 = 4;
    /// Random dimensions per final-gather ray (direction, then one Fresnel choice per bounce).
    RNG_GATHER_DIMS_PER_RAY: u32 = 32;
    /// Free-flight distances of camera and gather rays in media: dimension
    /// `RNG_MEDIUM_DOMAIN + part * RNG_MEDIUM_DIMS_PER_PART + segment` (gather rays; camera rays
    /// use part 0, so every part retraces the same camera path), where `segment` counts the
    /// path's free flights (a segment cut by a medium boundary draws anew).
    RNG_MEDIUM_DOMAIN: u32 = 0x2000_0000;
    RNG_MEDIUM_DIMS_PER_PART: u32 = 4096;
    /// Equiangular samples of camera segments toward point and spot lights:
    /// `RNG_EQUIANGULAR_DOMAIN + segment` (x picks the light, y the distance).
    RNG_EQUIANGULAR_DOMAIN: u32 = 0x3000_0000;
    /// Ratio tracking of shadow rays through heterogeneous media: `RNG_TRANSMITTANCE_DOMAIN +
    /// step` seeds the walk (only part 0 casts shadow rays). The camera-side transmittance of an
    /// equiangular sample uses z and w of its `RNG_EQUIANGULAR_DOMAIN` numbers; a free flight's
    /// two numbers seed its delta-tracking walk.
    RNG_TRANSMITTANCE_DOMAIN: u32 = 0x3800_0000;
    /// Free-flight distances of photon paths: `RNG_PHOTON_DOMAIN + RNG_PHOTON_MEDIUM + step`.
    RNG_PHOTON_MEDIUM: u32 = 0x1000_0000;
    /// The light sample of an adaptive light's shadow ray j >= 1 at the estimate vertex:
    /// `RNG_ADAPTIVE_DOMAIN + j` (ray 0 takes the vertex's own `RNG_LIGHT_U`).
    RNG_ADAPTIVE_DOMAIN: u32 = 0x5000_0000;
    /// The rotation of a photon lookup's edge probes.
    RNG_EDGE_PROBE: u32 = 0x5800_0000;

    /// Photon flag: stored at the first surface its path met (direct light).
    PHOTON_FLAG_DIRECT: u32 = 1;
    /// Photon flag: its path reached this diffuse surface through mirrors and glass only (L S+ D).
    PHOTON_FLAG_CAUSTIC: u32 = 2;

    /// Image layers of the camera kernel, one vec4 each per pixel; combined is their sum.
    LAYER_DIRECT: u32 = 0;
    LAYER_SPECULAR: u32 = 1;
    LAYER_INDIRECT: u32 = 2;
    LAYER_CAUSTICS: u32 = 3;
    LAYER_COUNT: u32 = 4;

    /// Feature layers of render_features (the denoiser's guides), one vec4 each per pixel:
    /// albedo (rgb) and shading normal (xyz) of the first non-specular vertex, position (xyz)
    /// and depth (w) of the first surface seen. Sums over samples, like the layers above.
    FEATURE_ALBEDO: u32 = 0;
    FEATURE_NORMAL: u32 = 1;
    FEATURE_POSITION: u32 = 2;
    FEATURE_COUNT: u32 = 3;

    /// `FrameParams::integrator`: the estimator of a render (`[render] integrator`). Photon
    /// mapping: camera paths through delta and smooth glossy lobes, then light sampling, the
    /// caustic map and a final gather (render.comp).
    INTEGRATOR_PPM: u32 = 0;
    /// Path tracing with light sampling and multiple importance sampling (render_pt.comp).
    INTEGRATOR_PT: u32 = 1;
    /// `FrameParams::techniques`: which of an integrator's sampling techniques contribute. With
    /// both (the default) each path is weighed by multiple importance sampling; with one alone it
    /// carries every path it can make (weight 1) and the other contributes only the paths it
    /// alone can make (delta lights, emission seen through delta lobes), so each converges to the
    /// same image by itself: the check that the weights are right (tests/integrators.rs).
    /// Light sampling (next-event estimation) at path vertices.
    TECHNIQUE_LIGHT: u32 = 1;
    /// Emission met by BSDF-sampled path rays.
    TECHNIQUE_BSDF: u32 = 2;
    TECHNIQUES_ALL: u32 = 3;
    /// Bidirectional path tracing: vertex connection (SmallVCM's bpt mode), vcm.rs.
    INTEGRATOR_BPT: u32 = 2;
    /// Vertex connection and merging (Georgiev et al. 2012), vcm.rs.
    INTEGRATOR_VCM: u32 = 3;
    /// `VcmParams::techniques`: connections (light sampling, emission met, light sub-path
    /// vertices joined to camera vertices and to the camera itself: the bpt estimators).
    VCM_CONNECT: u32 = 1;
    /// Merging: camera vertices take the light vertices within the radius (a photon estimate).
    VCM_MERGE: u32 = 2;
    /// Checks only (tests/integrators.rs): light tracing alone (light vertices seen by the camera,
    /// and the emission the camera sees directly), weight 1.
    VCM_LIGHT_TRACE_ONLY: u32 = 4;
    /// Checks only: merging alone, at the first non-delta camera vertex, weight 1 (SmallVCM's ppm).
    VCM_MERGE_ONLY: u32 = 8;
    /// `LightVertex::flags`: the light sub-path met a delta vertex before its first non-delta one.
    VERTEX_SPECULAR_FIRST: u32 = 0x1_0000;
    VERTEX_DIFFUSE_MASK: u32 = 0xffff;
    /// `LightVertex::flags`: a scattering point in a medium (no surface); its `hit` holds the
    /// medium's index, and the point is `origin + t direction`. Such vertices are connected to,
    /// never merged (docs/integrators.md, "Media").
    VERTEX_MEDIUM: u32 = 0x2_0000;
    /// Free flights of light sub-paths in media: `RNG_VCM_LIGHT_MEDIUM_DOMAIN + segment`, drawn
    /// at the light path's sequence point (as its other numbers), `segment` counting its flights.
    RNG_VCM_LIGHT_MEDIUM_DOMAIN: u32 = 0x7000_0000;
    /// Ratio tracking along connection segments through heterogeneous media: `domain +
    /// connection * (MEDIUM_CROSSINGS + 1) + crossing`, the light side's (light tracing, stream
    /// = light path) under `RNG_VCM_LIGHT_TRANSMITTANCE_DOMAIN`, the camera side's (light
    /// sampling and connections, stream = pixel) under `RNG_VCM_TRANSMITTANCE_DOMAIN`.
    RNG_VCM_LIGHT_TRANSMITTANCE_DOMAIN: u32 = 0x7400_0000;
    RNG_VCM_TRANSMITTANCE_DOMAIN: u32 = 0x7800_0000;
    /// Random dimensions of light sub-paths: `RNG_VCM_LIGHT_DOMAIN + vertex *
    /// RNG_DIMS_PER_BOUNCE + offset`, with stream = the light path's index.
    RNG_VCM_LIGHT_DOMAIN: u32 = 0x6000_0000;
    /// Light tracing splats into an image of 64-bit fixed-point sums, two words each (low, high):
    /// integer additions are exact and commute, so the image does not depend on the order the
    /// atomics land in. A splat value v adds floor(v) to the high word and fract(v) 2^32 to the
    /// low, carrying; values are clamped to `SPLAT_MAX`.
    SPLAT_MAX: f32 = 1.0e9;
    /// The merging radius (`cpu::vcm::vcm_base_radius`): at most `VCM_RADIUS_PIXELS` pixels'
    /// footprint where the camera looks, and at most the radius holding `VCM_RADIUS_VERTICES`
    /// light vertices were one vertex per light path spread evenly over the scene's surfaces;
    /// shrinking as (sample + 1)^((alpha - 1) / 2) with `VCM_ALPHA` (SmallVCM's 0.75).
    VCM_RADIUS_VERTICES: f32 = 0.5;
    VCM_RADIUS_PIXELS: f32 = 1.0;
    VCM_ALPHA: f32 = 0.75;
    /// Most light vertices stored per sample (64 bytes each): a larger image draws fewer light
    /// paths than it has pixels.
    VCM_MAX_LIGHT_VERTICES: u32 = 1 << 21;
    /// Light vertices a camera vertex connects to (at most 2), each drawn from a block of
    /// `VCM_PICK_BLOCK` light paths drawn uniformly, uniformly among the block's vertices, and
    /// weighted by 1 / its probability (`cpu::vcm::pick_light_vertex`; nearly a light vertex
    /// cache, Davidovic et al. 2014): the same mean as SmallVCM's connections to every vertex of
    /// one light path, with a loop of the same length on every lane (lavapipe ran the old loop
    /// as long as the longest light path of its 8 lanes) and neighbouring pixels' connections
    /// spread over all light paths. cornell-glossy: a little lower error at equal samples, the
    /// camera stage about a fifth faster through lavapipe (BENCHMARKS.md, "A light vertex cache").
    VCM_CONNECTIONS: u32 = 1;
    /// Light paths a connection's draw spans: one texel of their counts.
    VCM_PICK_BLOCK: u32 = 4;
    /// Pixels per light sub-path (measured when each camera path connected to the vertices of
    /// light path pixel mod light_paths). Half the light stage and half the light-tracing rays
    /// for a little more correlation: error x
    /// CPU time 12-17% lower for bpt on cornell-box and cornell-glossy (BENCHMARKS.md).
    VCM_PIXELS_PER_LIGHT_PATH: u32 = 2;
    /// Photon maps of the camera kernel's lookups (`grids[]` index).
    MAP_GLOBAL: u32 = 0;
    MAP_CAUSTIC: u32 = 1;
    /// Photons stored where photon paths scattered inside media (their own hashed grid).
    MAP_VOLUME: u32 = 2;
    MAP_COUNT: u32 = 3;
    /// Photons farther than this fraction of the radius off the lookup's tangent plane are
    /// ignored: the disc-shaped filter of Jensen keeps photons on a nearby wall out of a corner.
    PHOTON_DISC_THICKNESS: f32 = 0.25;
    /// Where a camera path's lookup finds photons off its disc (another surface within reach),
    /// rays probe `EDGE_PROBES` directions of the tangent plane for the surface's edges, and the
    /// estimate divides by the share of the kernel that lies on the surface (BENCHMARKS.md,
    /// "Edges"). There it counts only photons within `PHOTON_EDGE_THICKNESS` of the tangent plane:
    /// the disc's slab would also take in photons of the wall across a concave edge.
    EDGE_PROBES: u32 = 4;
    PHOTON_EDGE_THICKNESS: f32 = 0.02;
    /// A surface met by a probe at less than 60 degrees to the tangent plane is not an edge (the
    /// surface's own curve, or a surface above or below it).
    EDGE_PROBE_COS: f32 = 0.5;
    /// The least kernel share divided by: a point in a sliver of surface keeps a bounded weight.
    EDGE_MIN_MASS: f32 = 0.1;
    /// Slack, relative to the point's largest coordinate plus the cell size, by which a lookup
    /// shortens its distances to the faces of the point's cell before skipping neighbour cells
    /// out of reach (2^-20, eight ulps: more than the rounding of the cells' division).
    GRID_REACH_TOLERANCE: f32 = 9.536_743e-7;

    /// Relative offset of secondary ray origins, scaled by the scene's extent (avoids self-hits).
    RAY_EPSILON_SCALE: f32 = 1.0e-5;

    // Procedural patterns (src/cpu/pattern.rs, shaders/pattern.glsl). Pattern kinds (word 0).
    PATTERN_AGATE: u32 = 0;
    PATTERN_BOZO: u32 = 1;
    PATTERN_BRICK: u32 = 2;
    PATTERN_BUMPS: u32 = 3;
    PATTERN_CHECKER: u32 = 4;
    PATTERN_CRACKLE: u32 = 5;
    PATTERN_DENTS: u32 = 6;
    PATTERN_GRADIENT: u32 = 7;
    PATTERN_GRANITE: u32 = 8;
    PATTERN_HEXAGON: u32 = 9;
    PATTERN_LEOPARD: u32 = 10;
    PATTERN_MARBLE: u32 = 11;
    PATTERN_ONION: u32 = 12;
    PATTERN_RADIAL: u32 = 13;
    PATTERN_RIPPLES: u32 = 14;
    PATTERN_SPOTTED: u32 = 15;
    PATTERN_WAVES: u32 = 16;
    PATTERN_WOOD: u32 = 17;
    PATTERN_WRINKLES: u32 = 18;
    /// Number of pattern kinds; kinds are 0..PATTERN_KIND_COUNT.
    PATTERN_KIND_COUNT: u32 = 19;

    // Wave shapes (word 1), POV-Ray's ramp_wave, sine_wave, ...
    WAVE_RAMP: u32 = 0;
    WAVE_SINE: u32 = 1;
    WAVE_TRIANGLE: u32 = 2;
    WAVE_SCALLOP: u32 = 3;
    WAVE_CUBIC: u32 = 4;
    WAVE_POLY: u32 = 5;

    // Word offsets inside a pattern block.
    PATTERN_KIND: u32 = 0;
    PATTERN_WAVE: u32 = 1;
    PATTERN_OCTAVES: u32 = 2;
    PATTERN_OMEGA: u32 = 3;
    PATTERN_LAMBDA: u32 = 4;
    PATTERN_TURBULENCE: u32 = 5;
    PATTERN_FREQUENCY: u32 = 8;
    PATTERN_PHASE: u32 = 9;
    PATTERN_EXPONENT: u32 = 10;
    PATTERN_PARAMS: u32 = 12;
    /// Word 11: how many warp records follow the block (0..=MAX_WARPS).
    PATTERN_WARP_COUNT: u32 = 11;
    /// Words of one pattern block.
    PATTERN_WORDS: u32 = 20;
    /// Most warps of one pattern (besides turbulence); bounds the shader's loop.
    MAX_WARPS: u32 = 4;
    /// Words of one warp record: kind, 11 parameters, then the 3x4 matrix (columns x, y, z,
    /// translation) that undoes the transforms written before the warp.
    WARP_WORDS: u32 = 24;
    /// Word offsets in a warp record.
    WARP_PARAMS: u32 = 1;
    WARP_MATRIX: u32 = 12;
    // Warp kinds (POV-Ray's warp { repeat | black_hole | cylindrical | spherical | toroidal | planar }).
    WARP_REPEAT: u32 = 0;
    WARP_BLACK_HOLE: u32 = 1;
    WARP_CYLINDRICAL: u32 = 2;
    WARP_SPHERICAL: u32 = 3;
    WARP_TOROIDAL: u32 = 4;
    WARP_PLANAR: u32 = 5;
    /// Number of warp kinds.
    WARP_KIND_COUNT: u32 = 6;
    /// Most octaves of turbulence (POV-Ray 3.7 allows 1 to 10); bounds the shader's loops.
    MAX_OCTAVES: u32 = 10;
    /// Most entries of a colour map (POV-Ray's MAX_BLEND_MAP_ENTRIES).
    MAX_COLOR_MAP_ENTRIES: u32 = 256;
    /// Wave sources of ripples and waves (POV-Ray's default `number_of_waves`).
    WAVE_SOURCES: u32 = 10;

    /// Scale of the signed noise (standard deviation 0.270, measured) in `noise_unit`: gives the
    /// standard deviation 0.126 of POV-Ray 3.7's default (range-corrected) noise, 0.2568 x 0.4899 in
    /// its noise.cpp, so that the default colour maps band as they do in POV-Ray.
    NOISE_UNIT_SCALE: f32 = 0.466;
    /// Scale of each component of `noise_vector`: standard deviation 0.257 like POV-Ray's DNoise
    /// (the same sum as its Noise before the range correction), so a turbulence amount warps as far.
    NOISE_VECTOR_SCALE: f32 = 0.95;

    // Image textures (src/cpu/image_texture.rs, shaders/image_texture.glsl).
    /// Words before the first texel of a block.
    IMAGE_HEADER_WORDS: u32 = 4;
    /// Wrap mode: indices modulo the size (tiling).
    IMAGE_WRAP_REPEAT: u32 = 0;
    /// Wrap mode: indices clamped to the edge texels.
    IMAGE_WRAP_CLAMP: u32 = 1;
    /// Wrap mode: indices reflected at the edges: ..., 1, 0, 0, 1, ..., W-1, W-1, W-2, ...
    IMAGE_WRAP_MIRROR: u32 = 2;
    /// Flag: some texel has an alpha other than 1 (an alpha test may skip images without it).
    IMAGE_FLAG_ALPHA: u32 = 1;
    /// Texel coordinates are clamped to +-2^24: beyond it an f32 has no fraction left, and the
    /// integer indices stay far from overflow.
    IMAGE_COORD_LIMIT: f32 = 16_777_216.0;
}
