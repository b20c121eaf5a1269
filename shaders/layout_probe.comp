#version 450
// Declares one buffer of every shared struct so that glslang records their std430 layouts in the
// SPIR-V; tests/layout.rs reads the offsets back and compares them with the Rust structs.
// It also copies each element through, so the same module can run as a round-trip kernel
// (tests/layout_roundtrip.rs). Bindings follow the order of `gpu_structs!` in src/layout/mod.rs;
// tests/layout.rs fails when a struct is missing here or in that order.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 1) in;

layout(std430, binding = 0) buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = 1) buffer Primitives { Primitive primitives[]; };
layout(std430, binding = 2) buffer Materials { Material materials[]; };
layout(std430, binding = 3) buffer Textures { Texture textures[]; };
layout(std430, binding = 4) buffer Lights { Light lights[]; };
layout(std430, binding = 5) buffer Frames { FrameParams frames[]; };
layout(std430, binding = 6) buffer Ranges { DispatchRange ranges[]; };
layout(std430, binding = 7) buffer Photons { Photon photons[]; };
layout(std430, binding = 8) buffer Grids { GridParams grids[]; };
layout(std430, binding = 9) buffer Emits { EmitParams emits[]; };
layout(std430, binding = 10) buffer Media { Medium media[]; };
layout(std430, binding = 11) buffer Shadings { TriangleShading shadings[]; };
layout(std430, binding = 12) buffer LightVertices { LightVertex light_vertices[]; };
layout(std430, binding = 13) buffer VcmParamsArray { VcmParams vcm_params[]; };
layout(std430, binding = 14) buffer LightMaterials { LightMaterial light_materials[]; };

void main() {
    // Element 1 of each buffer becomes a field-by-field copy of element 0.
    nodes[1] = nodes[0];
    primitives[1] = primitives[0];
    materials[1] = materials[0];
    textures[1] = textures[0];
    lights[1] = lights[0];
    frames[1] = frames[0];
    ranges[1] = ranges[0];
    photons[1] = photons[0];
    grids[1] = grids[0];
    shadings[1] = shadings[0];
    emits[1] = emits[0];
    media[1] = media[0];
    light_vertices[1] = light_vertices[0];
    vcm_params[1] = vcm_params[0];
    light_materials[1] = light_materials[0];
}
