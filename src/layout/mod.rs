//! Structs the GPU sees. This module is the source of truth: `shaders/layout.glsl` mirrors it and
//! `tests/layout.rs` proves, from the compiled SPIR-V, that every offset and stride agrees. Every
//! struct is declared inside `gpu_structs!`, which also lists them for that test, so a new struct
//! cannot be left out of it.

pub mod constants;

use bytemuck::{Pod, Zeroable};

/// Declares the shared structs (`#[repr(C)]`, Pod) and `gpu_struct_layouts()`, the list of every
/// one of them with its fields' offsets and its size.
macro_rules! gpu_structs {
    ($( $(#[$meta:meta])* pub struct $name:ident { $( $(#[$fmeta:meta])* pub $field:ident : $ty:ty ),* $(,)? } )*) => {
        $(
            $(#[$meta])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
            pub struct $name { $( $(#[$fmeta])* pub $field: $ty ),* }
        )*
        /// Every shared struct as (name, [(field, byte offset)], size in bytes), in declaration order.
        pub fn gpu_struct_layouts() -> Vec<(&'static str, Vec<(&'static str, u32)>, u32)> {
            vec![$(
                (
                    stringify!($name),
                    vec![$( (stringify!($field), core::mem::offset_of!($name, $field) as u32) ),*],
                    size_of::<$name>() as u32,
                )
            ),*]
        }
    };
}

gpu_structs! {
    /// A node of the flattened BVH, 32 bytes. Nodes are stored depth-first, so an interior node's
    /// first child is the next node, and `skip_count >> BVH_COUNT_BITS` is the node that follows
    /// this node's whole subtree (the "miss link"): traversal needs no stack, which SIMD CPU
    /// drivers such as lavapipe run far faster than a per-lane stack. A leaf has
    /// `count = skip_count & BVH_COUNT_MASK > 0` and covers primitives `first .. first + count`.
    pub struct BvhNode {
        pub aabb_min: [f32; 3],
        pub first: u32,
        pub aabb_max: [f32; 3],
        pub skip_count: u32,
    }

    /// One shape of the scene, in BVH leaf order, 64 bytes. `kind` is a `PRIMITIVE_*` kind in its
    /// low bits (`PRIMITIVE_KIND_MASK`) plus `PRIMITIVE_FLAG_*` bits. What `p0..p2` and `data`
    /// hold is said at each `PRIMITIVE_*` constant; `data` is a float offset into the shape data
    /// buffer (or `NO_DATA`), for what does not fit the fixed fields.
    pub struct Primitive {
        pub p0: [f32; 3],
        pub kind: u32,
        pub p1: [f32; 3],
        pub material: u32,
        pub p2: [f32; 3],
        /// Index into the light array when the primitive emits, else `NO_LIGHT`.
        pub light: u32,
        pub data: u32,
        /// With `PRIMITIVE_FLAG_MEDIUM`: the medium inside the shape and outside it (indices
        /// into the media, or `NO_MEDIUM`).
        pub interior: u32,
        pub exterior: u32,
        pub _pad: u32,
    }

    /// A material, 112 bytes. Each parameter is a constant and a texture (`*_tex`, or `NO_TEXTURE`
    /// for the constant alone); with a texture the value is the constant times the texture's. What
    /// the colour slots mean depends on `kind` (see `MATERIAL_*`); `bsdf.glsl` reads them.
    pub struct Material {
        pub kind: u32,
        pub flags: u32,
        /// Opacity in [0, 1] (times `alpha_tex`); below 1 the surface is stochastically transparent.
        pub alpha: f32,
        pub alpha_tex: u32,
        /// Radiance leaving the front face (triangles: the winding side; spheres: outward).
        pub emission: [f32; 3],
        pub emission_tex: u32,
        pub color0: [f32; 3],
        pub color0_tex: u32,
        pub color1: [f32; 3],
        pub color1_tex: u32,
        /// A conductor's tint (Mitsuba's `specular_reflectance`, a factor on its Fresnel term).
        pub color2: [f32; 3],
        pub color2_tex: u32,
        /// GGX widths along dpdu and dpdv (not a perceptual roughness).
        pub roughness: [f32; 2],
        pub roughness_tex: u32,
        pub ior: f32,
        pub bump_tex: u32,
        pub bump_strength: f32,
        pub normal_tex: u32,
        pub weight_tex: u32,
        /// Blend weight of a mix (of material `mix_b` over `mix_a`).
        pub weight: f32,
        pub mix_a: u32,
        pub mix_b: u32,
        /// Word offset into the texture data of a nonlinear rough plastic's coat table
        /// (`PLASTIC_COAT_WORDS` floats, see `cpu::microfacet::plastic_eval`), else `NO_DATA`.
        pub data: u32,
    }

    /// A texture, 80 bytes: `kind` (`TEXTURE_*`) looked up in `space` (`TEXTURE_SPACE_*` in bits
    /// 0-7, an image's `TEXTURE_PROJECTION_*` from bit `TEXTURE_PROJECTION_SHIFT`) at a point
    /// moved by `transform` (the rows of a 3x4 affine map, texture space from lookup space). `data`
    /// and `color_map` are word offsets into the texture data buffer (or `NO_DATA`).
    pub struct Texture {
        pub kind: u32,
        pub space: u32,
        pub data: u32,
        pub color_map: u32,
        pub value: [f32; 3],
        /// `TEXTURE_CHANNEL_*`: which channel of the colour the texture gives.
        pub channel: u32,
        pub transform: [f32; 12],
    }

    /// A light, 80 bytes (`LIGHT_*` says what each kind reads). Area light: the emitting
    /// primitive `primitive`, whose material gives the radiance. Point and spot lights:
    /// `position`, `intensity` (W/sr on the axis), the cone `direction`, `cos_outer`,
    /// `falloff_scale` and `exponent`. Distant light: `direction`, `cos_outer`, `intensity`,
    /// and the bounding sphere (`position`, `radius`) its photons enter through. Environment: its
    /// block in the texture data at word `primitive`, and the bounding sphere. `cdf` is the
    /// running sum of the normalised powers of the lights that cast direct light, up to and
    /// including this one, so a binary search picks them in proportion to power; `photon_cdf`
    /// does the same for the lights that emit photons.
    pub struct Light {
        pub position: [f32; 3],
        pub kind: u32,
        pub intensity: [f32; 3],
        pub primitive: u32,
        /// Unit direction the light travels along (spot axis, distant light's direction).
        pub direction: [f32; 3],
        /// Surface area of an area light (scene units squared; estimated for superellipsoids and
        /// stretched shapes); 0 for the others. It only sets the light's power for picking: each
        /// sample on the light carries its own 1/pdf (`shape_sample`).
        pub area: f32,
        /// Probability of picking this light for a shadow ray (0: photons only).
        pub pick_probability: f32,
        pub cdf: f32,
        /// Probability of picking this light for a photon path (0: direct light only).
        pub photon_probability: f32,
        pub photon_cdf: f32,
        /// Cosine of the cone's half-angle: the spot's outer angle (-1 for a point light), the
        /// distant light's angular radius (1 for a sharp one), an area light's emission about its
        /// normal (0: the front hemisphere; -1: both faces, `MATERIAL_FLAG_TWO_SIDED`).
        pub cos_outer: f32,
        /// 1 / (cos inner - cos outer) of a spot's smooth falloff; huge for a hard edge.
        pub falloff_scale: f32,
        /// Spot intensity is also scaled by cos^exponent (POV-Ray's `tightness`; 0 for none).
        pub exponent: f32,
        /// Radius of the scene's bounding sphere (distant lights, the environment), scene units.
        pub radius: f32,
        /// The medium its photons start in (`NO_MEDIUM`: vacuum), found by the host.
        pub medium: u32,
        /// An area light's POV-Ray grid (`LIGHT_GRID_*`): n | m << 8 | jitter << 16; 0 for none.
        pub grid: u32,
        /// The branches from the light tree's root to this light's leaf (bit d set: the second
        /// child at depth d), or `NO_LIGHT` for a light outside the tree (an infinite one, or
        /// one that casts no direct light). See `render::light_tree`.
        pub tree_trail: u32,
        /// Direct-light selection: 1 for a light in the tree, an infinite light's fraction of the
        /// infinite lights' share, 0 for a light that casts no direct light.
        pub tree_probability: f32,
    }

    /// Per-render constants of every kernel, 144 bytes.
    /// A primary ray through film position (sx, sy) in [-1, 1]^2 depends on `camera_kind`
    /// (`CAMERA_*`): a perspective camera's has direction `forward + sx * right + sy * up` (not
    /// normalised: `right` and `up` carry the field of view), an orthographic one starts at
    /// `position + sx * right + sy * up`.
    pub struct FrameParams {
        pub camera_position: [f32; 3],
        pub width: u32,
        pub camera_forward: [f32; 3],
        pub height: u32,
        pub camera_right: [f32; 3],
        pub max_depth: u32,
        pub camera_up: [f32; 3],
        pub seed: u32,
        pub light_count: u32,
        /// Offset for secondary ray origins, in scene units.
        pub ray_epsilon: f32,
        pub primitive_count: u32,
        pub node_count: u32,
        /// Sum of the powers of the lights that emit photons (mean of the channels); 0 when none.
        pub total_light_power: f32,
        /// 1 when photon maps are bound: caustics and indirect light come from them.
        pub photon_mapping: u32,
        /// Final-gather rays per camera sample; 0 reads the global map directly (fast preview).
        pub gather_rays: u32,
        /// Glossy lobes with GGX width up to this are path lobes, rougher ones estimate lobes.
        pub glossy_threshold: f32,
        /// `CAMERA_*`.
        pub camera_kind: u32,
        /// Thin lens: radius of the aperture (scene units; 0 is a pinhole) and the distance of
        /// the plane in focus along `camera_forward`.
        pub lens_radius: f32,
        pub focal_distance: f32,
        /// Polygonal aperture: number of blades (0 for a round one) and the angle of the first
        /// corner from `camera_up` toward `camera_right`, radians.
        pub aperture_blades: u32,
        pub aperture_rotation: f32,
        /// Index of the environment's light (`LIGHT_ENVIRONMENT`), or `NO_LIGHT`: rays that leave
        /// the scene see it.
        pub environment: u32,
        /// Primitives from here to `primitive_count` are unbounded (infinite planes): outside the
        /// BVH, every ray tests them.
        pub unbounded_first: u32,
        /// The medium around the camera (`NO_MEDIUM`: vacuum), found by the host.
        pub camera_medium: u32,
        /// Instances of objects (0: none). With instances, the nodes after the world's BVH (from
        /// node 0's miss link on) are the top level, one instance per leaf; the objects' BVHs
        /// follow it. A hit on an instance's primitive p is named (instance + 1) x
        /// `primitive_count` + p (see `cpu::instance`).
        pub instance_count: u32,
        /// Offset in the shape data of the first instance's record (`INSTANCE_DATA_*`).
        pub instance_data: u32,
        /// The first CSG leaf primitive: CSG leaves fill `csg_first..primitive_count`, after the
        /// unbounded primitives (`unbounded_first..csg_first`); only their object's walk meets them.
        pub csg_first: u32,
        pub integrator: u32,
        pub techniques: u32,
        /// The reconstruction filter, `FILTER_*`.
        pub pixel_filter: u32,
        /// The filter's width over its `FILTER_*` default (`[render] filter_radius`), > 0: the
        /// filter is stretched by it along both axes.
        pub filter_scale: f32,
        /// Word offset in the texture data of the light tree (`LIGHT_TREE_*`), or `NO_LIGHT` when
        /// no light casts direct light.
        pub light_tree: u32,
    }

    /// Push constants of one camera-kernel dispatch: a band of rows, one sample, and one part of
    /// that sample: part 0 is the camera path with emission, direct light and caustics; part k >= 1
    /// is final-gather ray k - 1. Lavapipe stops any invocation after 65535 loop iterations in all
    /// (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every loop of a shader), so an invocation must do a
    /// bounded amount of work: one ray path and at most one photon lookup per part.
    pub struct DispatchRange {
        pub row_begin: u32,
        pub row_count: u32,
        pub sample_index: u32,
        pub part: u32,
        /// `NO_PIXEL_LIST`: every pixel of the band. Else the dispatch renders only the pixels
        /// at entries `pixel_list..pixel_list + pixel_count` of the pixel list (absolute pixel
        /// indices, ascending, all in the band's rows): adaptive sampling's later passes.
        pub pixel_list: u32,
        pub pixel_count: u32,
    }

    /// A stored photon: 20 bytes, std430 array stride 20 (Jensen's compact photon is 20 too).
    /// Position in scene units; flux as three half floats relative to the map's flux scale; the
    /// direction toward the light in 14 octahedral bits and two `PHOTON_FLAG_*` bits; the halves'
    /// sign bits hold the signs of the normal it landed on. Packing lives in
    /// `shaders/photon.glsl` and its twin `cpu::photon`.
    pub struct Photon {
        pub position: [f32; 3], // scalars only: align 4, no padding
        pub flux_rg: u32,
        pub flux_b_dir: u32,
    }

    /// A hashed spatial grid over one photon map, 32 bytes. A lookup of `radius` reads the
    /// 3x3x3 cells around its point that it reaches, so `cell_size` is at least `radius`. Photon
    /// maps take `cell_size` = `radius` (27 r^3 of candidates, against 64 r^3 for 2x2x2 cells of
    /// 2r: fewer photons read, dense maps); vcm's light vertices take 2r (sparse: the buckets'
    /// misses cost more than the candidates, `cpu::vcm::vertex_grid`). Cell coordinates are
    /// hashed into `table_mask + 1` buckets (a power of two about twice the photon count).
    pub struct GridParams {
        pub cell_size: f32,
        pub radius: f32,
        pub table_mask: u32,
        pub photon_count: u32,
        /// Stored flux is relative to this (see `Photon`).
        pub flux_scale: f32,
        pub _pad: [u32; 3],
    }

    /// Push constants of one `emit_photons` dispatch, 48 bytes.
    pub struct EmitParams {
        /// First photon path of this dispatch and how many it traces.
        pub path_begin: u32,
        pub path_count: u32,
        /// Photon paths over the whole render: each carries 1/`total_paths` of the light's power.
        pub total_paths: u32,
        /// Most surfaces a photon path visits.
        pub max_depth: u32,
        /// Capacity of the two photon buffers; photons past them are counted, not stored.
        pub global_capacity: u32,
        pub caustic_capacity: u32,
        /// Selects an independent set of photon paths (progressive passes use the pass index).
        pub pass: u32,
        /// 1 for a pass that fills only the caustic map (its paths end at the first diffuse surface).
        pub caustics_only: u32,
        /// Capacity of the volume photon buffer (collisions in media, global pass).
        pub volume_capacity: u32,
        pub _pad: [u32; 3],
    }

    /// A participating medium, 80 bytes: absorption and scattering coefficients per channel
    /// (1 / scene unit), the radiance it emits per unit length, and its phase function
    /// (`PHASE_*`, asymmetry `g`). Extinction is `sigma_a + sigma_s`. A heterogeneous medium
    /// scales all three by a density, the first channel of texture `density` at the point
    /// (`NO_TEXTURE`: homogeneous, density 1), inside the box `bounds_min..bounds_max` only (0
    /// outside); `majorant` bounds sigma_t there in every channel (delta and ratio tracking).
    pub struct Medium {
        pub sigma_a: [f32; 3],
        pub phase: u32,
        pub sigma_s: [f32; 3],
        pub g: f32,
        pub emission: [f32; 3],
        pub density: u32,
        pub bounds_min: [f32; 3],
        pub majorant: f32,
        pub bounds_max: [f32; 3],
        pub _pad: u32,
    }

    /// The shape-data block of a smooth triangle (`PRIMITIVE_FLAG_SMOOTH`), 60 bytes of scalars:
    /// the uv of its three vertices, then their unit normals (x, y, z each), which the host turns
    /// to the side of the winding normal. A flat triangle's block, when it has vertex uvs, is
    /// the first 6 floats alone.
    pub struct TriangleShading {
        pub uv: [f32; 6],
        pub normals: [f32; 9],
    }

    /// A vertex of a light sub-path (`integrator = "vcm" | "bpt"`), 64 bytes: the ray that met it
    /// (origin, direction, distance and the hit name, from which `shape_hit` rebuilds the surface
    /// point for connections), the light sub-path's throughput (flux, before the division by the
    /// path count) and the partial MIS quantities of SmallVCM's recursion (dVCM, dVC, dVM).
    /// `path_length` counts scattering vertices from the light (at least 1); `flags` holds the
    /// non-delta vertices before this one (low 16 bits), `VERTEX_SPECULAR_FIRST` and
    /// `VERTEX_MEDIUM` (a scattering point in a medium: `hit` is then the medium's index and the
    /// point `origin + t direction`).
    pub struct LightVertex {
        pub origin: [f32; 3],
        pub hit: u32,
        pub direction: [f32; 3],
        pub t: f32,
        pub throughput: [f32; 3],
        pub path_length: u32,
        pub d_vcm: f32,
        pub d_vc: f32,
        pub d_vm: f32,
        pub flags: u32,
    }

    /// The constants of one sample of vertex connection and merging, 56 bytes (push constants of
    /// the light-path kernel; the camera kernel reads them from its own buffer). See `cpu::vcm`.
    pub struct VcmParams {
        pub sample_index: u32,
        /// Light sub-paths of the sample.
        pub light_paths: u32,
        /// Vertex slots per light path (the frame's `max_depth`).
        pub vertex_slots: u32,
        /// `VCM_*` techniques in use.
        pub techniques: u32,
        /// The merging radius of this sample.
        pub radius: f32,
        /// SmallVCM's misVmWeightFactor and misVcWeightFactor: Mis(eta) and Mis(1 / eta) with
        /// eta = pi r^2 light_paths, 0 for a technique not in use.
        pub vm_weight: f32,
        pub vc_weight: f32,
        /// 1 / (pi r^2 light_paths): a merge's density estimate.
        pub vm_normalization: f32,
        /// First light path of this dispatch and how many it traces.
        pub path_begin: u32,
        pub path_count: u32,
        /// Light or camera paths each invocation of vcm_light and render_vcm traces one after
        /// another (1 on real GPUs; see render/gpu/bidirectional.rs). The CPU twin ignores it.
        pub paths_per_invocation: u32,
        /// Light vertices each camera vertex connects to (`VCM_CONNECTIONS`; at most 2).
        pub connections: u32,
        /// Path vertices an invocation of vcm_light or render_vcm traces per dispatch before it
        /// stores its path and run (0: no bound, one dispatch), and whether this dispatch
        /// resumes the runs the previous one stored (1) or starts them (0): lavapipe's loop
        /// limit per invocation then bounds one dispatch's vertices, not a whole path's
        /// (render/gpu/bidirectional.rs). The CPU twin ignores both.
        pub steps_per_dispatch: u32,
        pub resume: u32,
    }

    /// A surface light vertex's material as its point looked it up, 80 bytes: the kind (after a
    /// mix's choice), the colours and GGX widths (after textures), the index and the shading
    /// normal (after bump and normal maps). vcm_light writes it beside the vertex's slot, and
    /// render_vcm rebuilds the vertex's BSDF from it and `shape_hit`: evaluating the material's
    /// textures again at every connection was about a third of the camera stage on lavapipe.
    /// The CPU twin rebuilds the BSDF (`material_bsdf`) and keeps it per camera path instead.
    pub struct LightMaterial {
        pub color0: [f32; 3],
        pub kind: u32,
        pub color1: [f32; 3],
        pub ior: f32,
        pub ns: [f32; 3],
        pub alpha_u: f32,
        pub alpha_v: f32,
        /// The material's `MATERIAL_FLAG_*` and its `data` (a plastic's coat table).
        pub flags: u32,
        pub data: u32,
        pub _pad: u32,
        pub color2: [f32; 3],
        pub _pad2: u32,
    }
}

impl BvhNode {
    pub fn count(&self) -> u32 {
        self.skip_count & constants::BVH_COUNT_MASK
    }

    pub fn skip(&self) -> u32 {
        self.skip_count >> constants::BVH_COUNT_BITS
    }
}

const _: () = assert!(size_of::<Photon>() == 20);
const _: () = assert!(size_of::<TriangleShading>() == 4 * constants::TRIANGLE_DATA_FLOATS as usize);
const _: () = assert!(core::mem::offset_of!(TriangleShading, uv) == 4 * constants::TRIANGLE_DATA_UV as usize);
const _: () = assert!(core::mem::offset_of!(TriangleShading, normals) == 4 * constants::TRIANGLE_DATA_NORMALS as usize);
const _: () = assert!(size_of::<BvhNode>() == 32);
const _: () = assert!(size_of::<Primitive>() == 64);
const _: () = assert!(size_of::<Material>() == 128);
const _: () = assert!(size_of::<Texture>() == 80);
const _: () = assert!(size_of::<Light>() == 96);
const _: () = assert!(size_of::<Medium>() == 80);
const _: () = assert!(size_of::<FrameParams>().is_multiple_of(16));
// The primitive flags are distinct bits above the kind.
const _: () = {
    use constants::*;
    let flags = [PRIMITIVE_FLAG_ALPHA, PRIMITIVE_FLAG_UV, PRIMITIVE_FLAG_MEDIUM, PRIMITIVE_FLAG_SMOOTH];
    let mut seen = PRIMITIVE_KIND_MASK;
    let mut i = 0;
    while i < flags.len() {
        assert!(flags[i].is_power_of_two() && seen & flags[i] == 0);
        seen |= flags[i];
        i += 1;
    }
};
