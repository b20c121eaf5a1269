// Everything that reads the scene, in dependency order; a kernel includes layout.glsl and
// scene_bindings.glsl before this.

const float INF = 1.0 / 0.0;

#include "rng.glsl"
#include "sampling.glsl"
#include "phase.glsl"
#include "shape.glsl"
// Image and pattern textures only in the `textured` variant of a kernel: lavapipe runs every
// branch of a shader under masks, so their code costs every lookup even where no lane needs it
// (the cornell-box kernels ran 8x slower with it). The host picks the variant by the scene.
#ifdef VARIANT_TEXTURED
#include "pattern.glsl"
#include "image_texture.glsl"
#include "voxel.glsl"
#endif
#include "texture.glsl"
#include "microfacet.glsl"
#include "bsdf.glsl"
#include "trace.glsl"
#include "light.glsl"
#include "shading.glsl"
#include "medium.glsl"
