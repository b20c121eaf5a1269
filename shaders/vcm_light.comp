#version 450
// vcm_light: the light stage of vertex connection and merging (integrators vcm and bpt): one
// light sub-path per invocation. Its non-delta vertices go into the path's run of vertex slots
// and, as grid points (position, path, slot), into `points` for merging; each is connected to the
// camera (light tracing) and splatted into a 64-bit fixed-point image (two words per pixel,
// layer and channel: integer sums do not depend on the order atomics land in). CPU twin:
// src/cpu/vcm.rs (trace_light_path, connect_to_camera); media in the `media` variants (free
// flights, light vertices in media stored with VERTEX_MEDIUM, never merged). Bindings: the
// scene, then the vertex slots, the splats, the points, the point counter and each path's end
// (its last vertex's slot + 1; render_vcm reads no further), then each surface vertex's
// material as looked up (LightMaterial, beside its slot). A path writes its end and every slot up
// to it, the gaps (delta vertices) as empty, so the slots need no clearing between samples.
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
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene_bindings.glsl"
layout(std430, binding = SCENE_BINDINGS + 0) buffer LightVertices { LightVertex vertices[]; };
layout(std430, binding = SCENE_BINDINGS + 1) buffer Splats { uint splats[]; };
layout(std430, binding = SCENE_BINDINGS + 2) writeonly buffer Points { Photon points[]; };
layout(std430, binding = SCENE_BINDINGS + 3) buffer Counter { uint point_count; };
layout(std430, binding = SCENE_BINDINGS + 4) writeonly buffer PathEnds { uint path_ends[]; };
layout(std430, binding = SCENE_BINDINGS + 5) writeonly buffer LightMaterials { LightMaterial light_materials[]; };
layout(push_constant) uniform Push { VcmParams params; };

#include "scene.glsl"
#include "vcm.glsl"

void splat_add(uint index, float v) {
    uvec2 w = splat_words(v);
    if (w == uvec2(0u)) return;
    uint old = atomicAdd(splats[2u * index], w.x);
    // The low word's carry, so the pair adds as one 64-bit integer.
    uint carry = old + w.x < old ? 1u : 0u;
    atomicAdd(splats[2u * index + 1u], w.y + carry);
}

// Light tracing: the light vertex at h (on primitive prim, NO_LIGHT in a medium, reached in
// medium) seen by the camera; contract in vcm.rs, connect_to_camera.
void connect_to_camera(Hit h, Bsdf b, vec3 wo, SubPath sp, uint skip, uint prim, uint medium, vec2 lens_u, uvec3 n, uint layer) {
    vec3 eye = camera_point(h.p, lens_u);
    uint pixel = camera_pixel(h.p, eye);
    if (pixel == NO_LIGHT) return;
    vec3 to_eye = eye - h.p;
    float dist2 = dot(to_eye, to_eye);
    float dist = sqrt(dist2);
    vec3 dir = to_eye / dist;
    vec3 fr = bsdf_eval(b, dir, wo);
    if (fr == vec3(0.0)) return;
    float image_to_surface = camera_area_pdf(-dir, dist2, abs_cos(b, dir));
    float w_light = 0.0;
    if ((params.techniques & VCM_LIGHT_TRACE_ONLY) == 0u) {
        float toward_light = lobe_pdfs(b, dir, wo).x;
        w_light = wmul(mis(image_to_surface / float(params.light_paths)), (merges_at_first_vertex(params) ? merge_weight(params, b) : 0.0) + sp.d_vcm + wmul(sp.d_vc, mis(toward_light)));
    }
    float adjoint = shading_adjoint(b, wo, dir);
    vec3 value = sp.throughput * fr * (image_to_surface * adjoint / (float(params.light_paths) * (1.0 + w_light)));
    if (value == vec3(0.0)) return;
    uint rays = 0u;
    value *= vcm_visibility(h, skip, eye, medium_toward(h, prim, medium, wo, dir), n, rays);
    if (value == vec3(0.0)) return;
    uint base = (pixel * LAYER_COUNT + layer) * 3u;
    splat_add(base, value.x);
    splat_add(base + 1u, value.y);
    splat_add(base + 2u, value.z);
}

void main() {
    uint index = GLOBAL_INDEX;
    if (index >= params.path_count) return;
    uint path = params.path_begin + index;
    path_ends[path] = 0u;
    if (frame.light_count == 0u) return;
    uint sample_index = params.sample_index;
    uint dim0 = RNG_VCM_LIGHT_DOMAIN;
    Light l = light_at(pick_light(rand1(path, sample_index, frame.seed, dim0 + RNG_LIGHT_PICK), false));
    if (l.pick_probability <= 0.0) return;
    vec3 o, d, power;
    float cos_l;
    // The render's light paths are one low-discrepancy sequence (vcm.rs, trace_light_path).
    uvec2 seq = sequence_point(0u, sample_index, params.light_paths, path);
    light_emit(l, qmc2(seq.x, seq.y, frame.seed, dim0 + RNG_LIGHT_U), qmc2(seq.x, seq.y, frame.seed, dim0 + RNG_LIGHT_V), o, d, power, cos_l);
    // Light sampling's density of the start point; contract in vcm.rs, trace_light_path.
    float direct_pdf = 1.0;
    if (l.kind == LIGHT_AREA) direct_pdf = 1.0 / l.area;
    else if (l.kind == LIGHT_ENVIRONMENT) direct_pdf = environment_pdf(l, -d);
    else if (l.kind == LIGHT_DISTANT && l.area > 0.0) direct_pdf = 1.0 / l.area;
    float emission = emission_pdf(l, -d, cos_l);
    if (emission <= 0.0 || power == vec3(0.0)) return;
    bool finite = l.kind != LIGHT_DISTANT && l.kind != LIGHT_ENVIRONMENT;
    SubPath sp;
    sp.throughput = power / l.pick_probability;
    sp.d_vcm = mis(direct_pdf / emission);
    sp.d_vc = light_is_delta(l) ? 0.0 : mis((finite ? cos_l : 1.0) / (emission * l.pick_probability));
    sp.d_vm = sp.d_vc * params.vc_weight;
    uint skip = NO_LIGHT;
    uint medium = l.medium;
    uint segment = 0u;
    uint rays = 0u;
    uint diffuse = 0u;
    bool specular_first = false;
    uint slot0 = path * params.vertex_slots;
    for (uint k = 1u; k <= params.vertex_slots; k++) {
        vec3 unused = vec3(0.0);
        NextVertex nv = next_vertex(o, d, medium, skip, seq, RNG_VCM_LIGHT_MEDIUM_DOMAIN, segment, sp.throughput, unused, rays);
        if (!nv.found || (nv.prim == NO_LIGHT && !nv.scattered) || sp.throughput == vec3(0.0)) break;
        uint prim = nv.prim;
        o = nv.o;
        medium = nv.medium;
        float t = nv.t;
        vec3 wo = -d;
        Hit h;
        Bsdf b;
        vertex_at(nv.scattered, prim, medium, o, d, t, h, b);
        uint flags = bsdf_flags(b);
        if (flags == 0u) break;
        sub_arrive(sp, nv.dist, abs_cos(b, wo), k > 1u || finite);
        if ((flags & BSDF_ESTIMATE) != 0u) {
            uint slot = slot0 + k - 1u;
            vertices[slot].origin = float[3](o.x, o.y, o.z);
            vertices[slot].hit = nv.scattered ? medium : prim;
            vertices[slot].direction = float[3](d.x, d.y, d.z);
            vertices[slot].t = t;
            vertices[slot].throughput = float[3](sp.throughput.x, sp.throughput.y, sp.throughput.z);
            vertices[slot].path_length = k;
            vertices[slot].d_vcm = sp.d_vcm;
            vertices[slot].d_vc = sp.d_vc;
            vertices[slot].d_vm = sp.d_vm;
            vertices[slot].flags = diffuse | (nv.scattered ? VERTEX_MEDIUM : 0u) | (specular_first ? VERTEX_SPECULAR_FIRST : 0u);
            path_ends[path] = k;
            if (!nv.scattered) {
                light_materials[slot].color0 = float[3](b.color0.x, b.color0.y, b.color0.z);
                light_materials[slot].kind = b.kind;
                light_materials[slot].color1 = float[3](b.color1.x, b.color1.y, b.color1.z);
                light_materials[slot].ior = b.ior;
                light_materials[slot].ns = float[3](b.ns.x, b.ns.y, b.ns.z);
                light_materials[slot].alpha_u = b.alpha.x;
                light_materials[slot].alpha_v = b.alpha.y;
            }
            if ((params.techniques & (VCM_MERGE | VCM_MERGE_ONLY)) != 0u && !nv.scattered) {
                uint at = atomicAdd(point_count, 1u);
                points[at].position = float[3](h.p.x, h.p.y, h.p.z);
                points[at].flux_rg = path;
                points[at].flux_b_dir = k - 1u;
            }
            if ((params.techniques & (VCM_CONNECT | VCM_LIGHT_TRACE_ONLY)) != 0u && camera_connectable()) {
                // The lens sample: dimensions of the vertex that sampling its BSDF leaves free.
                vec2 lens_u = rand2(path, sample_index, frame.seed, dim0 + k * RNG_DIMS_PER_BOUNCE + RNG_PIXEL_X);
                uvec3 n = uvec3(path, sample_index, RNG_VCM_LIGHT_TRANSMITTANCE_DOMAIN + k * (MEDIUM_CROSSINGS + 1u));
                connect_to_camera(h, b, wo, sp, nv.scattered ? NO_LIGHT : ray_skip(prim), prim, medium, lens_u, n,
                                  path_layer(false, diffuse + 1u, specular_first));
            }
        } else {
            vertices[slot0 + k - 1u].path_length = 0u;
        }
        if (k >= params.vertex_slots) break;
        uint dim = dim0 + k * RNG_DIMS_PER_BOUNCE;
        float q = bsdf_path_probability(b, wo);
        vec4 u = bsdf_numbers(path, sample_index, seq, frame.seed, dim + RNG_FRESNEL);
        bool delta = u.w < q;
        BsdfSample smp = bsdf_sample(b, wo, u.xyz, delta ? LOBES_PATH : LOBES_ESTIMATE);
        if (smp.flags == 0u) break;
        float cos_out = abs_cos(b, smp.wi);
        float adjoint = shading_adjoint(b, wo, smp.wi);
        vec3 factor;
        if ((smp.flags & BSDF_SPECULAR) != 0u) {
            sub_scatter(sp, params, true, cos_out, 0.0, 0.0, false);
            specular_first = specular_first || diffuse == 0u;
            factor = smp.weight * (adjoint / q);
        } else {
            vec2 pdfs = lobe_pdfs(b, wo, smp.wi);
            if (pdfs.x <= 0.0) break;
            sub_scatter(sp, params, false, cos_out, pdfs.x, pdfs.y, mergeable(b));
            diffuse++;
            factor = bsdf_eval(b, smp.wi, wo) * (cos_out * adjoint / pdfs.x);
        }
        sp.throughput *= factor;
        if (k >= BPT_ROULETTE_DEPTH) {
            float survive = min(max(factor.x, max(factor.y, factor.z)), PT_ROULETTE_MAX);
            if (rand1(path, sample_index, frame.seed, dim + RNG_ROULETTE) >= survive) break;
            sp.throughput /= survive;
        }
        if (sp.throughput == vec3(0.0)) break;
        if (nv.scattered) {
            skip = NO_LIGHT;
        } else {
            skip = ray_skip(prim);
#ifdef VARIANT_MEDIA
            if ((smp.flags & BSDF_TRANSMISSION) != 0u) medium = medium_after(prim, h.ng, smp.wi, medium);
#endif
        }
        o = offset_origin(h, wo, smp.flags);
        d = smp.wi;
    }
}
