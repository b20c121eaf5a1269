// Everything that reads the scene, in dependency order; a kernel includes layout.glsl and
// scene_bindings.glsl before this.

const float INF = 1.0 / 0.0;

#include "rng.glsl"
#include "sampling.glsl"
#include "shape.glsl"
#include "texture.glsl"
#include "bsdf.glsl"
#include "trace.glsl"
#include "light.glsl"
#include "shading.glsl"
