#version 450
// vcm_light: the light stage of vertex connection and merging (integrators vcm and bpt): light
// sub-paths, params.paths_per_invocation of them per invocation. Their non-delta vertices go
// into the path's run of vertex slots, one after another, and, as grid points (position, path,
// slot), into `points` for merging; each is connected to the camera (light tracing) and splatted into a 64-bit fixed-point image (two words per pixel,
// layer and channel: integer sums do not depend on the order atomics land in). CPU twin:
// src/cpu/vcm.rs (trace_light_path, connect_to_camera); media in the `media` variants (free
// flights, light vertices in media stored with VERTEX_MEDIUM, never merged). Bindings: the
// scene, then the vertex slots, the splats, the points, the point counter (its second word counts
// invocations the driver broke off) and each path's count of vertices (by which render_vcm
// draws its connections, cpu::vcm::pick_light_vertex), then each surface vertex's material as
// looked up (LightMaterial, beside its slot). A path writes its count and the slots below it, so
// the slots need no clearing between samples.
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
layout(std430, binding = SCENE_BINDINGS + 0) buffer LightVertices { LightVertex vertices[]; };
layout(std430, binding = SCENE_BINDINGS + 1) buffer Splats { uint splats[]; };
layout(std430, binding = SCENE_BINDINGS + 2) writeonly buffer Points { Photon points[]; };
layout(std430, binding = SCENE_BINDINGS + 3) buffer Counter { uint point_count; uint broken_off; };
layout(std430, binding = SCENE_BINDINGS + 4) writeonly buffer PathCounts { uint path_counts[]; };
layout(std430, binding = SCENE_BINDINGS + 5) writeonly buffer LightMaterials { LightMaterial light_materials[]; };
// Each invocation's run as it stopped after params.steps_per_dispatch vertices
// (VCM_LIGHT_STATE_WORDS words: store_run), and how many stopped so (render_vcm does the same).
layout(std430, binding = SCENE_BINDINGS + 6) buffer RunStates { uint run_states[]; };
layout(std430, binding = SCENE_BINDINGS + 7) buffer Suspended { uint suspended; };
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
    vec2 film;
    if (!camera_film(h.p, eye, film) || !film_reaches_image(film)) return;
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
    // Every pixel the filter reaches takes its share (a box's one pixel all of it).
    uvec4 span = film_footprint(film);
    for (uint py = span.y; py <= span.w; py++) {
        for (uint px = span.x; px <= span.z; px++) {
            float w = filter_is_pixel() ? 1.0
                : filter_weight(film.x - (float(px) + 0.5)) * filter_weight(film.y - (float(py) + 0.5));
            if (w <= 0.0) continue;
            uint base = ((py * frame.width + px) * LAYER_COUNT + layer) * 3u;
            splat_add(base, w * value.x);
            splat_add(base + 1u, w * value.y);
            splat_add(base + 2u, w * value.z);
        }
    }
}

// A light sub-path, carried from vertex to vertex (and from loop turn to loop turn of main, which
// traces several paths one after another in each invocation).
struct LightPath {
    uint path;
    vec3 o;
    vec3 d;
    SubPath sp;
    uvec2 seq;
    bool finite;
    uint k;  // the vertex the next turn reaches (1: the emitted ray's)
    uint skip;
    uint medium;
    uint segment;
    uint rays;
    uint diffuse;
    bool specular_first;
    uint slot0;
    uint stored;  // vertices in its slots so far
    uint light;  // the light it left
};

// Emits light path `path`: false when it has no ray to follow (no light, no power, no density).
bool light_path_start(uint path, out LightPath lp) {
    lp.path = path;
    path_counts[path] = 0u;
    if (frame.light_count == 0u) return false;
    uint sample_index = params.sample_index;
    uint dim0 = RNG_VCM_LIGHT_DOMAIN;
    lp.light = pick_light(rand1(path, sample_index, frame.seed, dim0 + RNG_LIGHT_PICK), false);
    Light l = light_at(lp.light);
    if (l.pick_probability <= 0.0) return false;
    vec3 power;
    float cos_l;
    // The render's light paths are one low-discrepancy sequence (vcm.rs, trace_light_path).
    lp.seq = sequence_point(0u, sample_index, params.light_paths, path);
    light_emit(l, qmc2(lp.seq.x, lp.seq.y, frame.seed, dim0 + RNG_LIGHT_U), qmc2(lp.seq.x, lp.seq.y, frame.seed, dim0 + RNG_LIGHT_V),
               lp.o, lp.d, power, cos_l);
    // Light sampling's density of the start point; contract in vcm.rs, trace_light_path.
    float direct_pdf = 1.0;
    if (l.kind == LIGHT_AREA) direct_pdf = 1.0 / l.area;
    else if (l.kind == LIGHT_ENVIRONMENT) direct_pdf = environment_pdf(l, -lp.d);
    else if (l.kind == LIGHT_DISTANT && l.area > 0.0) direct_pdf = 1.0 / l.area;
    float emission = emission_pdf(l, -lp.d, cos_l);
    if (emission <= 0.0 || power == vec3(0.0)) return false;
    lp.finite = l.kind != LIGHT_DISTANT && l.kind != LIGHT_ENVIRONMENT;
    lp.sp.throughput = power / l.pick_probability;
    lp.sp.d_vcm = mis(direct_pdf / emission);
    lp.sp.d_vc = light_is_delta(l) ? 0.0 : mis((lp.finite ? cos_l : 1.0) / (emission * l.pick_probability));
    lp.sp.d_vm = lp.sp.d_vc * params.vc_weight;
    lp.k = 1u;
    lp.skip = NO_LIGHT;
    lp.medium = l.medium;
    lp.segment = 0u;
    lp.rays = 0u;
    lp.diffuse = 0u;
    lp.specular_first = false;
    lp.slot0 = path * params.vertex_slots;
    lp.stored = 0u;
    return true;
}

// One vertex of the light sub-path: returns false when the path ends there.
bool light_path_step(inout LightPath lp) {
    uint sample_index = params.sample_index;
    uint dim0 = RNG_VCM_LIGHT_DOMAIN;
    vec3 unused = vec3(0.0);
    NextVertex nv = next_vertex(lp.o, lp.d, lp.medium, lp.skip, lp.seq, RNG_VCM_LIGHT_MEDIUM_DOMAIN, lp.segment, lp.sp.throughput, unused, lp.rays);
    if (!nv.found || (nv.prim == NO_LIGHT && !nv.scattered) || lp.sp.throughput == vec3(0.0)) return false;
    uint prim = nv.prim;
    lp.o = nv.o;
    lp.medium = nv.medium;
    float t = nv.t;
    vec3 wo = -lp.d;
    Hit h;
    Bsdf b;
    vertex_at(nv.scattered, prim, lp.medium, lp.o, lp.d, t, h, b);
    uint flags = bsdf_flags(b);
    if (flags == 0u) return false;
    sub_arrive(lp.sp, nv.dist, abs_cos(b, wo), lp.k > 1u || lp.finite);
    // Contract in vcm.rs, trace_light_path: light sampling's choice of the light from here.
    if (lp.k == 1u) lp.sp.d_vcm = wmul(lp.sp.d_vcm, mis(direct_light_pmf(lp.light, h.p, receiver_normal(b)) / light_at(lp.light).pick_probability));
    if ((flags & BSDF_ESTIMATE) != 0u) {
        uint slot = lp.slot0 + lp.stored;
        lp.stored++;
        vertices[slot].origin = float[3](lp.o.x, lp.o.y, lp.o.z);
        vertices[slot].hit = nv.scattered ? lp.medium : prim;
        vertices[slot].direction = float[3](lp.d.x, lp.d.y, lp.d.z);
        vertices[slot].t = t;
        vertices[slot].throughput = float[3](lp.sp.throughput.x, lp.sp.throughput.y, lp.sp.throughput.z);
        vertices[slot].path_length = lp.k;
        vertices[slot].d_vcm = lp.sp.d_vcm;
        vertices[slot].d_vc = lp.sp.d_vc;
        vertices[slot].d_vm = lp.sp.d_vm;
        vertices[slot].flags = lp.diffuse | (nv.scattered ? VERTEX_MEDIUM : 0u) | (lp.specular_first ? VERTEX_SPECULAR_FIRST : 0u);
        path_counts[lp.path] = lp.stored;
        if (!nv.scattered) {
            light_materials[slot].color0 = float[3](b.color0.x, b.color0.y, b.color0.z);
            light_materials[slot].kind = b.kind;
            light_materials[slot].flags = b.flags;
            light_materials[slot].data = b.data;
            light_materials[slot].color1 = float[3](b.color1.x, b.color1.y, b.color1.z);
            light_materials[slot].color2 = float[3](b.color2.x, b.color2.y, b.color2.z);
            light_materials[slot].ior = b.ior;
            light_materials[slot].ns = float[3](b.ns.x, b.ns.y, b.ns.z);
            light_materials[slot].alpha_u = b.alpha.x;
            light_materials[slot].alpha_v = b.alpha.y;
        }
        if ((params.techniques & (VCM_MERGE | VCM_MERGE_ONLY)) != 0u && !nv.scattered) {
            uint at = atomicAdd(point_count, 1u);
            points[at].position = float[3](h.p.x, h.p.y, h.p.z);
            points[at].flux_rg = lp.path;
            points[at].flux_b_dir = slot - lp.slot0;
        }
        if ((params.techniques & (VCM_CONNECT | VCM_LIGHT_TRACE_ONLY)) != 0u && camera_connectable()) {
            // The lens sample: dimensions of the vertex that sampling its BSDF leaves free.
            vec2 lens_u = rand2(lp.path, sample_index, frame.seed, dim0 + lp.k * RNG_DIMS_PER_BOUNCE + RNG_PIXEL_X);
            uvec3 n = uvec3(lp.path, sample_index, RNG_VCM_LIGHT_TRANSMITTANCE_DOMAIN + lp.k * (MEDIUM_CROSSINGS + 1u));
            connect_to_camera(h, b, wo, lp.sp, nv.scattered ? NO_LIGHT : ray_skip(prim), prim, lp.medium, lens_u, n,
                              path_layer(false, lp.diffuse + 1u, lp.specular_first));
        }
    }
    if (lp.k >= params.vertex_slots) return false;
    uint dim = dim0 + lp.k * RNG_DIMS_PER_BOUNCE;
    float q = bsdf_path_probability(b, wo);
    vec4 u = bsdf_numbers(lp.path, sample_index, lp.seq, frame.seed, dim + RNG_FRESNEL);
    bool delta = u.w < q;
    BsdfSample smp = bsdf_sample(b, wo, u.xyz, delta ? LOBES_PATH : LOBES_ESTIMATE);
    if (smp.flags == 0u) return false;
    float cos_out = abs_cos(b, smp.wi);
    float adjoint = shading_adjoint(b, wo, smp.wi);
    vec3 factor;
    if ((smp.flags & BSDF_SPECULAR) != 0u) {
        sub_scatter(lp.sp, params, true, cos_out, 0.0, 0.0, false);
        lp.specular_first = lp.specular_first || lp.diffuse == 0u;
        factor = smp.weight * (adjoint / q);
    } else {
        vec2 pdfs = lobe_pdfs(b, wo, smp.wi);
        if (pdfs.x <= 0.0) return false;
        sub_scatter(lp.sp, params, false, cos_out, pdfs.x, pdfs.y, mergeable(b));
        lp.diffuse++;
        factor = bsdf_eval(b, smp.wi, wo) * (cos_out * adjoint / pdfs.x);
    }
    lp.sp.throughput *= factor;
    if (lp.k >= BPT_ROULETTE_DEPTH) {
        float survive = min(max(factor.x, max(factor.y, factor.z)), PT_ROULETTE_MAX);
        if (rand1(lp.path, sample_index, frame.seed, dim + RNG_ROULETTE) >= survive) return false;
        lp.sp.throughput /= survive;
    }
    if (lp.sp.throughput == vec3(0.0)) return false;
    if (nv.scattered) {
        lp.skip = NO_LIGHT;
    } else {
        lp.skip = ray_skip(prim);
#ifdef VARIANT_MEDIA
        if ((smp.flags & BSDF_TRANSMISSION) != 0u) lp.medium = medium_after(prim, h.ng, smp.wi, lp.medium);
#endif
    }
    lp.o = offset_origin(h, wo, smp.flags);
    lp.d = smp.wi;
    lp.k++;
    return lp.k <= params.vertex_slots;
}

// A run stopped at a vertex boundary: the next job, whether its path goes on, and the path,
// word for word, so that the resumed path computes exactly what it would have in one go.
void store_run(uint i, uint job, bool alive, LightPath lp) {
    uint at = i * VCM_LIGHT_STATE_WORDS;
    uint w[VCM_LIGHT_STATE_WORDS];
    w[0] = job;
    w[1] = alive ? 1u : 0u;
    w[2] = lp.path;
    w[3] = floatBitsToUint(lp.o.x); w[4] = floatBitsToUint(lp.o.y); w[5] = floatBitsToUint(lp.o.z);
    w[6] = floatBitsToUint(lp.d.x); w[7] = floatBitsToUint(lp.d.y); w[8] = floatBitsToUint(lp.d.z);
    w[9] = floatBitsToUint(lp.sp.throughput.x); w[10] = floatBitsToUint(lp.sp.throughput.y);
    w[11] = floatBitsToUint(lp.sp.throughput.z);
    w[12] = floatBitsToUint(lp.sp.d_vcm); w[13] = floatBitsToUint(lp.sp.d_vc); w[14] = floatBitsToUint(lp.sp.d_vm);
    w[15] = lp.seq.x;
    w[16] = lp.seq.y;
    w[17] = lp.finite ? 1u : 0u;
    w[18] = lp.k;
    w[19] = lp.skip;
    w[20] = lp.medium;
    w[21] = lp.segment;
    w[22] = lp.rays;
    w[23] = lp.diffuse;
    w[24] = lp.specular_first ? 1u : 0u;
    w[25] = lp.slot0;
    w[26] = lp.stored;
    w[27] = lp.light;
    for (uint k = 0u; k < VCM_LIGHT_STATE_WORDS; k++) run_states[at + k] = w[k];
}

// `store_run` read back: returns the job; `alive` whether its path goes on.
uint load_run(uint i, out bool alive, out LightPath lp) {
    uint at = i * VCM_LIGHT_STATE_WORDS;
    uint w[VCM_LIGHT_STATE_WORDS];
    for (uint k = 0u; k < VCM_LIGHT_STATE_WORDS; k++) w[k] = run_states[at + k];
    alive = w[1] != 0u;
    lp.path = w[2];
    lp.o = uintBitsToFloat(uvec3(w[3], w[4], w[5]));
    lp.d = uintBitsToFloat(uvec3(w[6], w[7], w[8]));
    lp.sp.throughput = uintBitsToFloat(uvec3(w[9], w[10], w[11]));
    lp.sp.d_vcm = uintBitsToFloat(w[12]);
    lp.sp.d_vc = uintBitsToFloat(w[13]);
    lp.sp.d_vm = uintBitsToFloat(w[14]);
    lp.seq = uvec2(w[15], w[16]);
    lp.finite = w[17] != 0u;
    lp.k = w[18];
    lp.skip = w[19];
    lp.medium = w[20];
    lp.segment = w[21];
    lp.rays = w[22];
    lp.diffuse = w[23];
    lp.specular_first = w[24] != 0u;
    lp.slot0 = w[25];
    lp.stored = w[26];
    lp.light = w[27];
    return w[0];
}

// Each invocation traces light paths i, i + n, i + 2n, ... of the dispatch (n invocations,
// params.paths_per_invocation paths each), a vertex per loop turn, starting the next path as soon
// as one ends: on lavapipe a SIMD group of 8 lanes runs a loop turn while any lane goes on, and a
// run of paths evens their lengths out (render_vcm does the same with camera paths).
void main() {
    uint per = max(params.paths_per_invocation, 1u);
    uint lanes = (params.path_count + per - 1u) / per;
    uint i = GLOBAL_INDEX;
    if (i >= lanes) return;
    uint jobs = (params.path_count - i + lanes - 1u) / lanes;  // paths i + j lanes below path_count
    LightPath lp;
    bool alive;
    uint job = 0u;
    if (params.resume != 0u) {
        job = load_run(i, alive, lp);
        if (job >= jobs) return;  // finished in an earlier dispatch
    } else {
        alive = light_path_start(params.path_begin + i, lp);
    }
    // Bounded: each turn is a vertex of one of `jobs` paths of at most vertex_slots vertices,
    // and at most params.steps_per_dispatch turns (when not 0) before the run is stored for the
    // next dispatch (render_vcm says why).
    uint steps = 0u;
    for (;;) {
        if (steps == params.steps_per_dispatch && steps != 0u) {
            store_run(i, job, alive, lp);
            atomicAdd(suspended, 1u);
            return;
        }
        steps++;
        if (alive && light_path_step(lp)) continue;
        job++;
        if (job >= jobs) break;
        alive = light_path_start(params.path_begin + i + job * lanes, lp);
    }
    // Ended by the driver's loop limit (lavapipe's 65535 iterations per invocation) with paths
    // left: say so, and the host renders the sample again with shorter runs.
    if (job < jobs) atomicAdd(broken_off, 1u);
    // A later dispatch of a stopped run skips this invocation.
    else if (params.steps_per_dispatch != 0u) run_states[i * VCM_LIGHT_STATE_WORDS] = jobs;
}
