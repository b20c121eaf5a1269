//! The compute pipelines of a render and how they bind the scene.

use std::cell::OnceCell;
use std::time::Instant;

use crate::gpu::{BindingTypes, GpuContext, GpuError, Kernel};
use crate::layout::constants::{
    BINDING_FRAME, BINDING_LIGHTS, BINDING_MATERIALS, BINDING_MEDIA, BINDING_NODES, BINDING_PRIMITIVES,
    BINDING_SHAPE_DATA, BINDING_TEXTURES, BINDING_TEXTURE_DATA, SCENE_BINDINGS, SCENE_PAGES, WORKGROUP_SIZE,
};
use crate::layout::{DispatchRange, EmitParams, VcmParams};
use crate::render::prepare::KernelVariant;

/// One kernel of a render: its SPIR-V module's name, bindings, push constants and
/// specialization constants.
struct Spec {
    name: String,
    bindings: u32,
    types: BindingTypes,
    push: usize,
    constants: Vec<u32>,
}

impl Spec {
    fn create(&self, ctx: &GpuContext) -> Result<Kernel, GpuError> {
        let spirv = crate::shaders::spirv(&self.name).expect("build.rs embeds every kernel in shaders/");
        ctx.create_specialized_kernel(&self.name, &spirv, self.bindings, self.types, self.push as u32, &self.constants)
    }
}

/// The kernels a render may use.
#[derive(Clone, Copy, Debug)]
enum Which {
    EmitPhotons,
    GridCount,
    GridScan,
    GridScanAdd,
    GridScatter,
    GridRank,
    Render,
    VcmLight,
    RenderVcm,
    RenderFeatures,
}

/// How the kernels read the scene (shaders/scene_bindings.glsl): as texel buffers, since on
/// lavapipe a texel fetch goes through gallivm's vectorised texture path where a storage-buffer
/// read costs about 15 scalar instructions per lane and word; `frame`, which every lane reads
/// alike, as a uniform buffer, whose uniform reads gallivm makes once for all lanes. Each texel
/// binding is an array of `SCENE_PAGES` pages (`DeviceScene::bindings`).
pub const SCENE_BINDING_TYPES: BindingTypes = BindingTypes {
    rgba: SCENE_RGBA,
    words: SCENE_WORDS,
    uniform: 1 << BINDING_FRAME,
    arrays: SCENE_RGBA | SCENE_WORDS,
    array_len: SCENE_PAGES,
};
const SCENE_RGBA: u32 = 1 << BINDING_NODES
    | 1 << BINDING_PRIMITIVES
    | 1 << BINDING_MATERIALS
    | 1 << BINDING_LIGHTS
    | 1 << BINDING_TEXTURES
    | 1 << BINDING_MEDIA;
const SCENE_WORDS: u32 = 1 << BINDING_TEXTURE_DATA | 1 << BINDING_SHAPE_DATA;
/// The camera kernel's: also its photon maps and bucket starts (bindings SCENE_BINDINGS + 2..8)
/// as texel buffers and the grid parameters (SCENE_BINDINGS + 1) as a uniform buffer.
const RENDER_BINDING_TYPES: BindingTypes = BindingTypes {
    rgba: SCENE_BINDING_TYPES.rgba | 0b01_0101 << (SCENE_BINDINGS + 2),
    words: SCENE_BINDING_TYPES.words | 0b10_1010 << (SCENE_BINDINGS + 2),
    uniform: SCENE_BINDING_TYPES.uniform | 1 << (SCENE_BINDINGS + 1),
    ..SCENE_BINDING_TYPES
};

/// render_vcm's: its params and grid (SCENE_BINDINGS + 1, + 2) as uniform buffers, the light
/// vertices, grid points, splats, light paths' vertex counts (four to a texel) and light surfaces
/// (+ 3, + 4, + 6, + 7, + 8) as RGBA32UI texels, the bucket starts (+ 5) as words, for the
/// reasons SCENE_BINDING_TYPES gives.
const RENDER_VCM_BINDING_TYPES: BindingTypes = BindingTypes {
    rgba: SCENE_BINDING_TYPES.rgba | 0b1_1101_1000 << SCENE_BINDINGS,
    words: SCENE_BINDING_TYPES.words | 0b10_0000 << SCENE_BINDINGS,
    uniform: SCENE_BINDING_TYPES.uniform | 0b110 << SCENE_BINDINGS,
    ..SCENE_BINDING_TYPES
};

/// grid_rank's (shaders/grid_rank.comp): bucket starts (binding 1) as words, the scattered photons
/// (binding 2) as RGBA32UI texels, since every invocation reads its whole bucket.
const GRID_RANK_BINDING_TYPES: BindingTypes =
    BindingTypes { rgba: 1 << 2, words: 1 << 1, uniform: 0, arrays: 0, array_len: 0 };

/// Workgroups for a one-dimensional launch, spread over x and y so that neither passes 32768
/// (the kernels rebuild the index with GLOBAL_INDEX and skip the surplus).
pub(super) fn groups(invocations: u32) -> [u32; 3] {
    const MAX_X: u32 = 1 << 15;
    let total = invocations.div_ceil(WORKGROUP_SIZE).max(1);
    let x = total.min(MAX_X);
    [x, total.div_ceil(x), 1]
}

/// The compute pipelines of a render, each created on first use and then kept: creating them
/// (shader compilation, on lavapipe through LLVM) is the largest fixed cost of a pass.
#[derive(Default)]
pub struct GpuKernels {
    emit_photons: OnceCell<Kernel>,
    grid_count: OnceCell<Kernel>,
    grid_scan: OnceCell<Kernel>,
    grid_scan_add: OnceCell<Kernel>,
    grid_scatter: OnceCell<Kernel>,
    grid_rank: OnceCell<Kernel>,
    render: OnceCell<Kernel>,
    vcm_light: OnceCell<Kernel>,
    render_vcm: OnceCell<Kernel>,
    render_features: OnceCell<Kernel>,
    /// Which build of the scene kernels (`SceneBuffers::variant`).
    variant: KernelVariant,
}

impl GpuKernels {
    /// The kernels of one variant (`SceneBuffers::variant`).
    pub fn for_scene(variant: KernelVariant) -> GpuKernels {
        GpuKernels { variant, ..Default::default() }
    }

    pub(super) fn variant(&self) -> KernelVariant {
        self.variant
    }

    /// `name` in the build this scene needs.
    fn scene_kernel(&self, name: &str) -> String {
        self.variant.kernel_name(name)
    }

    /// The kernel `which` of this variant: its cell and how to create it.
    fn spec(&self, which: Which) -> (&OnceCell<Kernel>, Spec) {
        let scene = |name: &str| self.scene_kernel(name);
        let constants = self.variant.specialization().to_vec();
        let plain = |name: &str, bindings: u32, types: BindingTypes, push: usize| Spec {
            name: name.to_string(),
            bindings,
            types,
            push,
            constants: Vec::new(),
        };
        match which {
            Which::EmitPhotons => (
                &self.emit_photons,
                Spec {
                    name: scene("emit_photons"),
                    bindings: SCENE_BINDINGS + 4,
                    types: SCENE_BINDING_TYPES,
                    push: size_of::<EmitParams>(),
                    constants,
                },
            ),
            Which::GridCount => (&self.grid_count, plain("grid_count", 3, BindingTypes::default(), 0)),
            Which::GridScan => (&self.grid_scan, plain("grid_scan", 2, BindingTypes::default(), 4)),
            Which::GridScanAdd => (&self.grid_scan_add, plain("grid_scan_add", 2, BindingTypes::default(), 4)),
            Which::GridScatter => (&self.grid_scatter, plain("grid_scatter", 5, BindingTypes::default(), 0)),
            Which::GridRank => (&self.grid_rank, plain("grid_rank", 4, GRID_RANK_BINDING_TYPES, 0)),
            // The integrator's camera kernel; both take the same bindings (render_pt reads no maps).
            Which::Render => (
                &self.render,
                Spec {
                    name: scene(if self.variant.path_traced { "render_pt" } else { "render" }),
                    bindings: SCENE_BINDINGS + 9,
                    types: RENDER_BINDING_TYPES,
                    push: size_of::<DispatchRange>(),
                    constants,
                },
            ),
            // The light stage of the bidirectional integrators (shaders/vcm_light.comp).
            Which::VcmLight => (
                &self.vcm_light,
                Spec {
                    name: scene("vcm_light"),
                    bindings: SCENE_BINDINGS + 8,
                    types: SCENE_BINDING_TYPES,
                    push: size_of::<VcmParams>(),
                    constants,
                },
            ),
            // The camera stage of the bidirectional integrators (shaders/render_vcm.comp).
            Which::RenderVcm => (
                &self.render_vcm,
                Spec {
                    name: scene("render_vcm"),
                    bindings: SCENE_BINDINGS + 13,
                    types: RENDER_VCM_BINDING_TYPES,
                    push: size_of::<DispatchRange>(),
                    constants,
                },
            ),
            // The feature layers (shaders/render_features.comp), only where they are asked for.
            Which::RenderFeatures => (
                &self.render_features,
                Spec {
                    name: scene("render_features"),
                    bindings: SCENE_BINDINGS + 1,
                    types: SCENE_BINDING_TYPES,
                    push: size_of::<DispatchRange>(),
                    constants,
                },
            ),
        }
    }

    fn get(&self, ctx: &GpuContext, which: Which) -> Result<&Kernel, GpuError> {
        let (cell, spec) = self.spec(which);
        if let Some(k) = cell.get() {
            return Ok(k);
        }
        let k = spec.create(ctx)?;
        Ok(cell.get_or_init(|| k))
    }

    pub(super) fn emit_photons(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::EmitPhotons)
    }
    pub(super) fn grid_count(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::GridCount)
    }
    pub(super) fn grid_scan(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::GridScan)
    }
    pub(super) fn grid_scan_add(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::GridScanAdd)
    }
    pub(super) fn grid_scatter(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::GridScatter)
    }
    pub(super) fn grid_rank(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::GridRank)
    }
    pub(super) fn render(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::Render)
    }
    pub(super) fn vcm_light(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::VcmLight)
    }
    pub(super) fn render_vcm(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::RenderVcm)
    }
    pub(super) fn render_features(&self, ctx: &GpuContext) -> Result<&Kernel, GpuError> {
        self.get(ctx, Which::RenderFeatures)
    }

    /// Creates each kernel once on a fresh set and returns (name, seconds) per kernel: what
    /// keeping the kernels saves per pass (`photonix bench --passes`).
    pub fn time_creation(ctx: &GpuContext) -> Result<Vec<(&'static str, f64)>, GpuError> {
        let k = GpuKernels::default();
        let mut out = Vec::new();
        let mut timed = |name: &'static str, f: &dyn Fn() -> Result<(), GpuError>| -> Result<(), GpuError> {
            let t = Instant::now();
            f()?;
            out.push((name, t.elapsed().as_secs_f64()));
            Ok(())
        };
        timed("emit_photons", &|| k.emit_photons(ctx).map(drop))?;
        timed("grid_count", &|| k.grid_count(ctx).map(drop))?;
        timed("grid_scan", &|| k.grid_scan(ctx).map(drop))?;
        timed("grid_scan_add", &|| k.grid_scan_add(ctx).map(drop))?;
        timed("grid_scatter", &|| k.grid_scatter(ctx).map(drop))?;
        timed("grid_rank", &|| k.grid_rank(ctx).map(drop))?;
        timed("render", &|| k.render(ctx).map(drop))?;
        Ok(out)
    }

    /// Creates now every kernel a render with (`photons` true) or without photon maps uses, so
    /// that the cost falls into set-up rather than into the first pass.
    pub fn create_all(&self, ctx: &GpuContext, photons: bool) -> Result<(), GpuError> {
        use Which::*;
        let wanted: &[Which] = if self.variant.bidirectional {
            &[VcmLight, RenderVcm, GridCount, GridScan, GridScanAdd, GridScatter, GridRank]
        } else if photons {
            &[EmitPhotons, Render, GridCount, GridScan, GridScanAdd, GridScatter, GridRank]
        } else {
            &[Render]
        };
        let missing: Vec<(&OnceCell<Kernel>, Spec)> =
            wanted.iter().map(|&w| self.spec(w)).filter(|(cell, _)| cell.get().is_none()).collect();
        // Side by side: lavapipe builds a pipeline on the calling thread (seconds for the large
        // scene kernels, mostly its own passes over the shader, which its disk cache does not
        // skip), and Vulkan lets pipelines be created from several threads at once.
        let made: Vec<Result<Kernel, GpuError>> = std::thread::scope(|scope| {
            let jobs: Vec<_> = missing.iter().map(|(_, spec)| scope.spawn(|| spec.create(ctx))).collect();
            jobs.into_iter().map(|j| j.join().expect("a kernel-creation thread panicked")).collect()
        });
        for ((cell, _), kernel) in missing.into_iter().zip(made) {
            let kernel = kernel?;
            let _ = cell.set(kernel);
        }
        Ok(())
    }
}
