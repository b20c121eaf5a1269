// The scene as every kernel that traces rays sees it: declared here once, bound by the host in
// the same order (`DeviceScene::bindings` in src/render/gpu.rs). A kernel's own buffers take the
// bindings from SCENE_BINDINGS on.

// `frame` is a uniform buffer: every lane reads the same words, and gallivm loads a uniform
// buffer's word at a uniform address once for all lanes, where it reads a storage buffer lane by
// lane. The scalar layout is std430's for our structs (no vectors in them).
#extension GL_EXT_scalar_block_layout : require
layout(scalar, binding = BINDING_FRAME) uniform Frame { FrameParams frame; };
// The rest as uniform texel buffers: on lavapipe a texel fetch goes through gallivm's vectorised
// texture path (one gather of four words per lane for an RGBA32UI texel), where a storage-buffer
// read costs about 15 scalar instructions per lane and word; the kernels' process CPU time fell
// by a third (BENCHMARKS.md, "Texel buffers on lavapipe"). Structs are RGBA32UI texels (all
// are multiples of 16 bytes), word arrays R32UI; scene_fetch.glsl reads them back as structs.
// Each is an array of SCENE_PAGES pages: an array larger than one texel view (or than one
// binding's range) is split over several, each of 2^SCENE_PAGE_WORDS_LOG2 words but the last
// (src/render/gpu/scene.rs); pages it does not need repeat its first.
layout(binding = BINDING_NODES) uniform usamplerBuffer node_texels[SCENE_PAGES];
layout(binding = BINDING_PRIMITIVES) uniform usamplerBuffer primitive_texels[SCENE_PAGES];
layout(binding = BINDING_MATERIALS) uniform usamplerBuffer material_texels[SCENE_PAGES];
layout(binding = BINDING_LIGHTS) uniform usamplerBuffer light_texels[SCENE_PAGES];
layout(binding = BINDING_TEXTURES) uniform usamplerBuffer texture_texels[SCENE_PAGES];
layout(binding = BINDING_TEXTURE_DATA) uniform usamplerBuffer texture_words[SCENE_PAGES];
layout(binding = BINDING_SHAPE_DATA) uniform usamplerBuffer shape_words[SCENE_PAGES];
layout(binding = BINDING_MEDIA) uniform usamplerBuffer medium_texels[SCENE_PAGES];

// Features a scene may lack, fixed when the host creates the pipeline (specialization constants,
// `KernelVariant::specialization`): the driver compiles their code out where they are false, so
// scenes without instances or CSG do not pay for the instance walk and the CSG walk in the
// innermost loop (lavapipe runs every branch under masks; code size alone slows it down).
// Unlike the `// variant:` builds they cost no extra SPIR-V. All default to present.
layout(constant_id = 0) const bool SCENE_HAS_INSTANCES = true;
layout(constant_id = 1) const bool SCENE_HAS_CSG = true;
// Perlin noise (pattern.glsl's noise_signed): inlined at every noise call of every pattern and
// turbulence, it was most of the textured kernels' code, and lavapipe ran it for every texture
// lookup of scenes that have none (cornell-glossy: 20% of a pass, 2 s of pipeline creation).
layout(constant_id = 2) const bool SCENE_HAS_NOISE = true;
// Textured emission (material_emission): every texture lookup's code again, twice in render_vcm
// (emission met, light sampling) and in the light kernels; without it cornell-glossy's camera
// kernel took 2.2-2.5 s to create on lavapipe instead of 3.0.
layout(constant_id = 3) const bool SCENE_HAS_EMISSION_TEXTURES = true;
// The material kinds a scene's BSDFs can have (bit MATERIAL_* set; MATERIAL_PHASE with media):
// each kind's evaluation, pdf and sampling are inlined at every call of bsdf.glsl's switches (the
// camera kernel of render_vcm has ten), and lavapipe compiles, and runs under masks, every case.
layout(constant_id = 4) const uint SCENE_MATERIAL_KINDS = 0xffffffffu;
const bool SCENE_HAS_DIFFUSE = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_DIFFUSE)) != 0u;
const bool SCENE_HAS_MIRROR = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_MIRROR)) != 0u;
const bool SCENE_HAS_DIELECTRIC = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_DIELECTRIC)) != 0u;
const bool SCENE_HAS_CONDUCTOR = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_CONDUCTOR)) != 0u;
const bool SCENE_HAS_PLASTIC = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_PLASTIC)) != 0u;
const bool SCENE_HAS_PHASE = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_PHASE)) != 0u;
const bool SCENE_HAS_THIN_DIELECTRIC = (SCENE_MATERIAL_KINDS & (1u << MATERIAL_THIN_DIELECTRIC)) != 0u;
// Beckmann microfacets (microfacet.glsl's mf_d, mf_g1, mf_sample_visible, mf_pdf_visible): no
// kind, but a bit of the same constant; without it every rough BSDF compiles GGX alone.
const bool SCENE_HAS_BECKMANN = (SCENE_MATERIAL_KINDS & (1u << SCENE_KIND_BECKMANN)) != 0u;
// The most pages any scene array uses and the size of a page, in words (`KernelVariant::pages`,
// `page_words_log2`): read by the `paged` builds only, which the host picks where an array spans
// several pages; in the others each fetch is one texelFetch (scene_fetch.glsl says why).
layout(constant_id = 5) const uint SCENE_PAGES_USED = 1u;
layout(constant_id = 6) const uint SCENE_PAGE_WORDS_LOG2 = 25u;

#include "scene_fetch.glsl"
