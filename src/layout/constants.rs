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
    /// Lambertian reflector; `Material::reflectance` is its albedo.
    MATERIAL_DIFFUSE: u32 = 0;
    /// Perfect mirror; `Material::reflectance` is its tint.
    MATERIAL_MIRROR: u32 = 1;
    /// Smooth dielectric with Fresnel reflection and refraction; `Material::ior` is its index.
    MATERIAL_DIELECTRIC: u32 = 2;

    /// A triangle primitive: `p0`, `p1`, `p2` are its vertices.
    PRIMITIVE_TRIANGLE: u32 = 0;
    /// An analytic sphere: `p0` is its centre, `p1[0]` its radius.
    PRIMITIVE_SPHERE: u32 = 1;

    /// A one-sided emissive triangle, sampled uniformly by area.
    LIGHT_TRIANGLE: u32 = 0;
    /// An emissive sphere, sampled uniformly by area.
    LIGHT_SPHERE: u32 = 1;
    /// A point light; `Light::radiance` holds its intensity in W/sr.
    LIGHT_POINT: u32 = 2;

    /// Marks a primitive that is not a light.
    NO_LIGHT: u32 = 0xffff_ffff;

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
    RNG_PIXEL_X: u32 = 0;
    RNG_PIXEL_Y: u32 = 1;
    RNG_LIGHT_PICK: u32 = 2;
    RNG_LIGHT_U: u32 = 3;
    RNG_LIGHT_V: u32 = 4;
    RNG_FRESNEL: u32 = 5;

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
    /// Photons farther than this fraction of the radius off the lookup's tangent plane are
    /// ignored: the disc-shaped filter of Jensen keeps photons on a nearby wall out of a corner.
    PHOTON_DISC_THICKNESS: f32 = 0.25;

    /// Relative offset of secondary ray origins, scaled by the scene's extent (avoids self-hits).
    RAY_EPSILON_SCALE: f32 = 1.0e-5;
}
