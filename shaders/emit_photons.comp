#version 450
// emit_photons: trace photon paths from the lights and store their photons in the global and
// caustic maps. CPU twin: src/cpu/emit_photons.rs. Bindings: the scene (scene_bindings.glsl),
// then global photons, caustic photons, counters (photons for the global, the caustic and the
// volume map; one past a buffer's capacity is counted but not stored, so the host can grow the
// buffer and trace again) and volume photons (collisions in media, `media` variant).
// variant: textured
// variant: textured alpha
// variant: analytic
// variant: textured analytic
// variant: textured alpha analytic
// variant: analytic implicit
// variant: textured analytic implicit
// variant: textured alpha analytic implicit
// variant: analytic implicit csg
// variant: textured analytic implicit csg
// variant: textured alpha analytic implicit csg
// variant: media
// variant: textured media
// variant: textured alpha media
// variant: analytic media
// variant: textured analytic media
// variant: textured alpha analytic media
// variant: analytic implicit media
// variant: textured analytic implicit media
// variant: textured alpha analytic implicit media
// variant: analytic implicit csg media
// variant: textured analytic implicit csg media
// variant: textured alpha analytic implicit csg media
// every build also: paged
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene_bindings.glsl"
layout(std430, binding = SCENE_BINDINGS + 0) writeonly buffer GlobalPhotons { Photon global_photons[]; };
layout(std430, binding = SCENE_BINDINGS + 1) writeonly buffer CausticPhotons { Photon caustic_photons[]; };
// counters[3]: photon paths the driver broke off (photon_path.glsl).
layout(std430, binding = SCENE_BINDINGS + 2) buffer Counters { uint counters[4]; };
layout(std430, binding = SCENE_BINDINGS + 3) writeonly buffer VolumePhotons { Photon volume_photons[]; };
layout(push_constant) uniform Push { EmitParams params; };

#include "scene.glsl"
#include "photon.glsl"

void store_photon(vec3 x, vec3 flux, vec3 wi, vec3 side, uint flags, bool volume) {
    // Flux relative to the mean power per path keeps the half floats near 1.
    float inv_scale = float(params.total_paths) / frame.total_light_power;
    Photon p = pack_photon(x, flux, inv_scale, wi, side, flags);
    if (volume) {
        uint vslot = atomicAdd(counters[2], 1u);
        if (vslot < params.volume_capacity) STORE_PHOTON(volume_photons, vslot, p)
        return;
    }
    if (params.caustics_only == 0u) {
        uint slot = atomicAdd(counters[0], 1u);
        if (slot < params.global_capacity) STORE_PHOTON(global_photons, slot, p)
    }
    if (flags == PHOTON_FLAG_CAUSTIC) {
        uint cslot = atomicAdd(counters[1], 1u);
        if (cslot < params.caustic_capacity) STORE_PHOTON(caustic_photons, cslot, p)
    }
}

#include "photon_path.glsl"

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= params.path_count) return;
    trace_photon_path(params.path_begin + i, params);
}
