#version 450
// Reads element 1 of every scene struct through its texel-buffer loader (scene_fetch.glsl) and
// stores it, field by field, to element 0 of a storage buffer of that struct; word 21 of the
// texture and shape words; photons 0..3 through fetch_photon (grid.glsl), which start at
// each of the four words of a texel; and light vertex 1 and light material 1 through
// fetch_light_vertex and fetch_light_material. tests/texel_fetch.rs compares what comes back with what
// was sent, through this build (one page per array) and the paged one (pages of 64 bytes).
// every build also: paged
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 1) in;

#include "scene_bindings.glsl"
layout(std430, binding = SCENE_BINDINGS + 0) writeonly buffer OutNodes { BvhNode out_nodes[]; };
layout(std430, binding = SCENE_BINDINGS + 1) writeonly buffer OutPrimitives { Primitive out_primitives[]; };
layout(std430, binding = SCENE_BINDINGS + 2) writeonly buffer OutMaterials { Material out_materials[]; };
layout(std430, binding = SCENE_BINDINGS + 3) writeonly buffer OutLights { Light out_lights[]; };
layout(std430, binding = SCENE_BINDINGS + 4) writeonly buffer OutTextures { Texture out_textures[]; };
layout(std430, binding = SCENE_BINDINGS + 5) writeonly buffer OutMedia { Medium out_media[]; };
layout(std430, binding = SCENE_BINDINGS + 6) writeonly buffer OutWords { uint out_words[]; };
layout(binding = SCENE_BINDINGS + 7) uniform usamplerBuffer photon_texels;
layout(std430, binding = SCENE_BINDINGS + 8) writeonly buffer OutPhotons { Photon out_photons[]; };
layout(binding = SCENE_BINDINGS + 9) uniform usamplerBuffer vertex_texels;
layout(std430, binding = SCENE_BINDINGS + 10) writeonly buffer OutVertices { LightVertex out_vertices[]; };
layout(binding = SCENE_BINDINGS + 11) uniform usamplerBuffer light_material_texels;
layout(std430, binding = SCENE_BINDINGS + 12) writeonly buffer OutLightMaterials { LightMaterial out_light_materials[]; };

#include "grid.glsl"
#include "vcm_fetch.glsl"

void main() {
    out_nodes[0] = bvh_node(1u);
    out_primitives[0] = primitive_at(1u);
    out_materials[0] = material_at(1u);
    out_lights[0] = light_at(1u);
    out_textures[0] = texture_at(1u);
    out_media[0] = medium_at(1u);
    out_words[0] = texture_word(21u);
    out_words[1] = floatBitsToUint(shape_word(21u));
    out_words[2] = bvh_node_skip_count(1u);
    out_words[3] = primitive_kind(1u);
    for (uint i = 0u; i < 4u; i++) out_photons[i] = fetch_photon(photon_texels, i);
    out_vertices[0] = fetch_light_vertex(vertex_texels, 1u);
    out_light_materials[0] = fetch_light_material(light_material_texels, 1u);
}
