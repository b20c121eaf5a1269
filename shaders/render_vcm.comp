#version 450
// render_vcm: the camera stage of vertex connection and merging (integrators vcm and bpt). At
// each non-delta vertex of a pixel's camera sub-path: light sampling, connections to the vertices
// of the light sub-path of the pixel's index, merging with the light vertices within the radius
// (the grid over `points`); then the light tracing that landed on the pixel. Every contribution
// weighed by SmallVCM's MIS recursion; media in the `media` variants (free flights, scattering
// vertices that connect but do not merge, transmittance on every connection). CPU twin:
// src/cpu/vcm.rs (radiance_vcm). Bindings: the scene, then the accumulation (the whole image:
// LAYER_COUNT vec4 per pixel), the sample's VcmParams, the grid's GridParams, the vertex slots,
// the sorted points, the bucket starts, the splats, the light paths' ends and the light
// vertices' materials, the count of invocations the driver broke off, the runs, and the pixel list.
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
layout(std430, binding = SCENE_BINDINGS + 0) buffer Accumulation { vec4 accumulation[]; };
// What every lane reads alike as uniform buffers, what it reads at random as texel buffers
// (scene_bindings.glsl says why): storage-buffer reads of the params in the loops' tests, of
// 16-word light vertices and of the splats made this kernel about 5x slower on lavapipe,
// against the CPU twin, than the ppm kernel that reads its maps this way (BENCHMARKS.md,
// "render_vcm's reads on lavapipe").
layout(scalar, binding = SCENE_BINDINGS + 1) uniform Params { VcmParams params; };
layout(scalar, binding = SCENE_BINDINGS + 2) uniform Grid { GridParams vgrid; };
layout(binding = SCENE_BINDINGS + 3) uniform usamplerBuffer vertex_texels;
layout(binding = SCENE_BINDINGS + 4) uniform usamplerBuffer point_texels;
layout(binding = SCENE_BINDINGS + 5) uniform usamplerBuffer start_words;
layout(binding = SCENE_BINDINGS + 6) uniform usamplerBuffer splat_texels;
// Each light path's count of vertices, in its first slots (vcm_light.comp), four to a texel.
layout(binding = SCENE_BINDINGS + 7) uniform usamplerBuffer path_count_texels;
layout(binding = SCENE_BINDINGS + 8) uniform usamplerBuffer light_material_texels;
layout(std430, binding = SCENE_BINDINGS + 9) buffer BrokenOff { uint broken_off; };
// Each invocation's run as it stopped after params.steps_per_dispatch vertices
// (VCM_CAMERA_STATE_WORDS words: store_run), and how many stopped so (the host dispatches again,
// resuming, until none does).
layout(std430, binding = SCENE_BINDINGS + 10) buffer RunStates { uint run_states[]; };
layout(std430, binding = SCENE_BINDINGS + 11) buffer Suspended { uint suspended; };
layout(std430, binding = SCENE_BINDINGS + 12) readonly buffer PixelList { uint pixel_list[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "scene.glsl"
#include "pixel_list.glsl"
#include "grid.glsl"
#include "vcm_fetch.glsl"
#include "vcm.glsl"

float emission_weight(SubPath sp, float direct, float emission) {
    return 1.0 / (1.0 + wmul(mis(direct), sp.d_vcm) + wmul(mis(emission), sp.d_vc));
}

// Light sampling at a camera vertex; contract in vcm.rs, light_sampling.
vec3 light_sampling(Hit h, Bsdf b, vec3 wo, SubPath sp, uint skip, uint prim, uint medium, uint stream, uint dim, uvec3 n, float vm, inout uint rays) {
    if (frame.light_count == 0u) return vec3(0.0);
    uint sample_index = params.sample_index;
    float pmf;
    uint light = pick_direct_light(rand1(stream, sample_index, frame.seed, dim + RNG_LIGHT_PICK), h.p, receiver_normal(b), pmf);
    if (pmf <= 0.0) return vec3(0.0);
    Light l = light_at(light);
    vec2 ul = qmc2(stream, sample_index, frame.seed, dim + RNG_LIGHT_U);
    LightSample ls = light_sample(l, h.p, grid_sample(l.grid, ul, stream, sample_index));
    float cos_to_light = abs_cos(b, ls.wi);
    vec3 fr = bsdf_eval(b, wo, ls.wi) * ls.weight * cos_to_light;
    if (fr == vec3(0.0)) return vec3(0.0);
    float dist = length(ls.p - h.p);
    // Contract in vcm.rs, illumination_pdfs.
    float direct = ls.pdf;
    if (l.kind == LIGHT_DISTANT && l.area <= 0.0) direct = 1.0;
    else if (l.kind != LIGHT_AREA && l.kind != LIGHT_ENVIRONMENT && l.kind != LIGHT_DISTANT) direct = dist * dist;
    // Contract in vcm.rs, light_sampling: no density, no sample.
    if (direct <= 0.0) return vec3(0.0);
    // Emission chooses its light by power, light sampling by the tree.
    float emission = emission_pdf_at(l, ls.wi, ls.cos_l, h.p) * l.pick_probability;
    float cos_at_light = l.kind == LIGHT_AREA ? ls.cos_l : 1.0;
    vec2 pdfs = lobe_pdfs(b, wo, ls.wi);
    float forward = light_is_delta(l) ? 0.0 : pdfs.x;
    float w_light = mis(forward / (pmf * direct));
    float w_camera = wmul(mis(emission * cos_to_light / (pmf * direct * cos_at_light)), vm + sp.d_vcm + wmul(sp.d_vc, mis(pdfs.y)));
    float w = 1.0 / (w_light + 1.0 + w_camera);
    vec3 origin = offset_origin(h, ls.wi, BSDF_REFLECTION);
    vec3 to_target = ls.p - origin;
    float len = length(to_target);
    vec3 tr = vcm_transmittance(origin, to_target / len, max(len - ls.eps, 0.0), medium_toward(h, prim, medium, wo, ls.wi), skip, n, rays);
    if (tr == vec3(0.0)) return vec3(0.0);
    return fr * (w / pmf) * tr;
}

// Light vertex lv (in slot `slot`): its point and BSDF, the surface's material as vcm_light
// looked it up (LightMaterial) on the hit shape_hit rebuilds; contract in vcm.rs,
// light_surface (which evaluates the material again: the same values).
void light_vertex_bsdf(LightVertex v, uint slot, out Hit h, out Bsdf b) {
    vec3 o = load3(v.origin);
    vec3 d = load3(v.direction);
#ifdef VARIANT_MEDIA
    if ((v.flags & VERTEX_MEDIUM) != 0u) {
        h = medium_hit(o + d * v.t, -d);
        b = phase_bsdf(v.hit, -d);
        return;
    }
#endif
    h = shape_hit(v.hit, o, d, v.t);
    LightMaterial m = fetch_light_material(light_material_texels, slot);
    b = bsdf_at(h, m.kind, m.flags, m.data, load3(m.color0), load3(m.color1), load3(m.color2), vec2(m.alpha_u, m.alpha_v), m.ior, load3(m.ns));
}

// A camera vertex joined to light vertex lv; contract in vcm.rs, connect_vertices.
vec3 connect_vertices(Hit h, Bsdf b, vec3 wo, SubPath sp, uint skip, uint prim, uint medium, LightVertex lv, uint slot, uvec3 n, float vm, inout uint rays) {
    Hit lh;
    Bsdf lb;
    light_vertex_bsdf(lv, slot, lh, lb);
    vec3 to_light = lh.p - h.p;
    float dist2 = dot(to_light, to_light);
    if (dist2 <= 0.0) return vec3(0.0);
    float dist = sqrt(dist2);
    vec3 dir = to_light / dist;
    vec3 fc = bsdf_eval(b, wo, dir);
    if (fc == vec3(0.0)) return vec3(0.0);
    vec3 l_wo = -load3(lv.direction);
    vec3 fl = bsdf_eval(lb, -dir, l_wo);
    if (fl == vec3(0.0)) return vec3(0.0);
    float cos_cam = abs_cos(b, dir);
    float cos_light = abs_cos(lb, dir);
    float g = cos_cam * cos_light / dist2;
    vec2 cam = lobe_pdfs(b, wo, dir);
    vec2 lig = lobe_pdfs(lb, l_wo, -dir);
    float cam_to_area = cam.x * cos_light / dist2;
    float light_to_area = lig.x * cos_cam / dist2;
    float w_light = wmul(mis(cam_to_area), merge_weight(params, lb) + lv.d_vcm + wmul(lv.d_vc, mis(lig.y)));
    float w_camera = wmul(mis(light_to_area), vm + sp.d_vcm + wmul(sp.d_vc, mis(cam.y)));
    float w = 1.0 / (w_light + 1.0 + w_camera);
    vec3 value = fc * fl * load3(lv.throughput) * (g * w * shading_adjoint(lb, l_wo, -dir));
    if (value == vec3(0.0)) return vec3(0.0);
    vec3 target = lh.p + normalize(h.p - lh.p) * lh.eps;
    return value * vcm_visibility(h, skip, target, medium_toward(h, prim, medium, wo, dir), n, rays);
}

// A pixel's camera sub-path, carried from vertex to vertex (and from loop turn to loop turn of
// main, which runs several pixels' paths one after another in each invocation).
struct CameraPath {
    uint stream;  // the pixel's index in the image: its random stream
    vec3 o;
    vec3 d;
    SubPath sp;
    uint m;  // the vertex the next turn reaches (1: the camera ray's)
    uint skip;
    bool first_specular;
    uint diffuse;
    bool specular_after;
    bool specular_path;
    uint medium;
    uint segment;
    vec3 terms[4];
    uint rays;
    // The last vertex and the normal light sampling chose its light with there (zero in a
    // medium): emission met is weighed with that choice's probability.
    vec3 prev_x;
    vec3 prev_n;
};

CameraPath camera_path_start(uint px, uint py) {
    CameraPath c;
    c.stream = py * frame.width + px;
    uint sample_index = params.sample_index;
    vec2 film = film_offset(qmc2(c.stream, sample_index, frame.seed, RNG_PIXEL_X));
    float sx = 2.0 * (float(px) + film.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + film.y) / float(frame.height);
    camera_ray(sx, sy, lens_sample(c.stream, sample_index), c.o, c.d);
    c.sp.throughput = vec3(1.0);
    c.sp.d_vcm = camera_d_vcm(params.light_paths, c.d);
    c.sp.d_vc = 0.0;
    c.sp.d_vm = 0.0;
    c.m = 1u;
    c.skip = NO_LIGHT;
    c.first_specular = false;
    c.diffuse = 0u;
    c.specular_after = false;
    c.specular_path = true;
    c.medium = frame.camera_medium;
    c.segment = 0u;
    c.terms = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    c.rays = 0u;
    c.prev_x = c.o;
    c.prev_n = vec3(0.0);
    return c;
}

// One vertex of the camera sub-path: returns false when the path ends there.
bool camera_path_step(inout CameraPath c) {
    uint stream = c.stream;
    uint sample_index = params.sample_index;
    uint m = c.m;
    bool light_only = (params.techniques & VCM_LIGHT_TRACE_ONLY) != 0u;
    bool merge_only = (params.techniques & VCM_MERGE_ONLY) != 0u;
    bool connect = (params.techniques & VCM_CONNECT) != 0u;
    bool merge = (params.techniques & (VCM_MERGE | VCM_MERGE_ONLY)) != 0u;
    vec3 medium_emission = vec3(0.0);
    NextVertex nv = next_vertex(c.o, c.d, c.medium, c.skip, uvec2(stream, sample_index), RNG_MEDIUM_DOMAIN, c.segment,
                                c.sp.throughput, medium_emission, c.rays);
    uint layer = path_layer(c.first_specular, c.diffuse, c.specular_after);
    bool single = light_only || merge_only;
    bool emission_allowed = !single || c.specular_path;
    bool take_whole = m == 1u || single;
    // The media's own emission: only camera paths gather it (vcm.rs).
    if (emission_allowed) c.terms[layer] += medium_emission;
    if (!nv.found || c.sp.throughput == vec3(0.0)) return false;
    uint prim = nv.prim;
    float t = nv.t;
    c.o = nv.o;
    c.medium = nv.medium;
    if (prim == NO_LIGHT && !nv.scattered) {
        if (!emission_allowed) return false;
        for (uint i = 0u; i < frame.light_count; i++) {
            Light l = light_at(i);
            if (l.kind != LIGHT_DISTANT || l.area <= 0.0) break;
            if (dot(c.d, load3(l.direction)) <= -l.cos_outer) {
                float w = take_whole ? 1.0 : emission_weight(c.sp, direct_light_pmf(i, c.prev_x, c.prev_n) / l.area, l.pick_probability * emission_pdf_at(l, c.d, 1.0, c.o));
                c.terms[layer] += c.sp.throughput * load3(l.intensity) * (w / l.area);
            }
        }
        WHEN(frame.environment != NO_LIGHT) {
            Light l = light_at(frame.environment);
            float w = take_whole ? 1.0 : emission_weight(c.sp, direct_light_pmf(frame.environment, c.prev_x, c.prev_n) * environment_pdf(l, c.d), l.pick_probability * emission_pdf_at(l, c.d, 1.0, c.o));
            c.terms[layer] += c.sp.throughput * environment_radiance(l, c.d) * w;
        }
        return false;
    }
    vec3 wo = -c.d;
    Hit h;
    Bsdf b;
    vertex_at(nv.scattered, prim, c.medium, c.o, c.d, t, h, b);
    // An orthographic camera's first density is by area (camera_d_vcm).
    sub_arrive(c.sp, nv.dist, abs_cos(b, wo), m > 1u || frame.camera_kind != CAMERA_ORTHOGRAPHIC);
    float cos_l = nv.scattered ? 0.0 : emitter_cosine(material_at(h.material).flags, h.ng, wo);
    if (!nv.scattered && cos_l > 0.0 && emission_allowed) {
        vec3 emitted = material_emission(material_at(h.material), h);
        if (emitted != vec3(0.0)) {
            uint hp = hit_primitive(prim);
            uint light = primitive_at(hp).light;
            float w = 1.0;
            if (!(take_whole || light == NO_LIGHT || hp != prim)) {
                Light l = light_at(light);
                w = emission_weight(c.sp, direct_light_pmf(light, c.prev_x, c.prev_n) / l.area, l.pick_probability * emission_pdf(l, c.d, cos_l));
            }
            c.terms[layer] += c.sp.throughput * emitted * w;
        }
    }
    if (m > frame.max_depth) return false;
    uint flags = bsdf_flags(b);
    if (flags == 0u) return false;
    c.skip = nv.scattered ? NO_LIGHT : ray_skip(prim);
    // Whether this vertex merges, and merging's factor in its weights (vcm.rs, radiance_vcm).
    bool merges = mergeable(b) && (m > 1u || merges_at_first_vertex(params));
    float vm = merges ? params.vm_weight : 0.0;
    uint dim = (m - 1u) * RNG_DIMS_PER_BOUNCE;
    // The transmittance numbers of this vertex's connections (vcm.rs, radiance_vcm).
    uint connection0 = RNG_VCM_TRANSMITTANCE_DOMAIN + (m - 1u) * (params.vertex_slots + 1u) * (MEDIUM_CROSSINGS + 1u);
    if ((flags & BSDF_ESTIMATE) != 0u) {
        uint cam_diffuse = c.diffuse + 1u;
        if (connect) {
            vec3 v = light_sampling(h, b, wo, c.sp, c.skip, prim, c.medium, stream, dim, uvec3(stream, sample_index, connection0), vm, c.rays);
            c.terms[path_layer(c.first_specular, cam_diffuse, false)] += c.sp.throughput * v;
            // Light vertices drawn by block of light paths; contract in vcm.rs, pick_light_vertex.
            uint picks = min(params.connections, 2u);
            uint blocks = (params.light_paths + VCM_PICK_BLOCK - 1u) / VCM_PICK_BLOCK;
            vec4 pick = rand4(stream, sample_index, frame.seed, dim + RNG_CONNECT_PICK);
            for (uint k = 0u; k < picks; k++) {
                uint block = min(uint(pick[2u * k] * float(blocks)), blocks - 1u);
                // VCM_PICK_BLOCK paths' counts: one texel.
                uvec4 counts = texelFetch(path_count_texels, int(block));
                uint total = counts.x + counts.y + counts.z + counts.w;
                if (total == 0u) continue;
                uint j = min(uint(pick[2u * k + 1u] * float(total)), total - 1u);
                uint path = block * VCM_PICK_BLOCK;
                for (uint q = 0u; q < VCM_PICK_BLOCK - 1u && j >= counts[q]; q++) {
                    j -= counts[q];
                    path++;
                }
                uint slot = path * params.vertex_slots + j;
                float share = float(total) * float(blocks) / float(params.light_paths) / float(picks);
                LightVertex lv = fetch_light_vertex(vertex_texels, slot);
                if (lv.path_length + m > frame.max_depth) continue;
                uvec3 n = uvec3(stream, sample_index, connection0 + (k + 1u) * (MEDIUM_CROSSINGS + 1u));
                vec3 joined = connect_vertices(h, b, wo, c.sp, c.skip, prim, c.medium, lv, slot, n, vm, c.rays);
                uint cl = path_layer(c.first_specular, cam_diffuse + (lv.flags & VERTEX_DIFFUSE_MASK) + 1u,
                                     (lv.flags & VERTEX_SPECULAR_FIRST) != 0u);
                c.terms[cl] += c.sp.throughput * joined * share;
            }
        }
        if (merge && vgrid.photon_count > 0u && merges) {
            vec3 merged[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
            float r2 = vgrid.radius * vgrid.radius;
            ivec3 home = grid_cell(h.p, vgrid.cell_size);
            vec3 lower, upper;
            grid_face_gaps(h.p, vgrid.cell_size, lower, upper);
            ivec3 box_lo, box_n;
            grid_reach_box(lower, upper, r2, box_lo, box_n);
            // The points within the radius, in the order of the cells in reach and of their
            // buckets (the twin's), the far ones skipped in a loop of their own. Lavapipe runs a
            // loop's body, under masks, while any lane of 8 goes on: in one loop over all the
            // points, every point of every lane cost the merge's whole body whenever any lane had
            // a near one; here the body runs as often as the busiest lane has near points.
            uint cells = uint(box_n.x * box_n.y * box_n.z);
            uint j = 0u;
            uint i = 0u;
            uint end = 0u;
            ivec3 cell = home;
            for (;;) {
                bool near = false;
                Photon pt;
                for (;;) {
                    if (i >= end) {
                        if (j >= cells) break;
                        uint kc = grid_box_neighbour(box_lo, box_n, j);
                        j++;
                        if (!grid_neighbour_in_reach(lower, upper, r2, kc)) continue;
                        cell = grid_neighbour(home, kc);
                        uint bucket = grid_hash(cell, vgrid.table_mask);
                        i = texelFetch(start_words, int(bucket)).x;
                        end = texelFetch(start_words, int(bucket + 1u)).x;
                        continue;
                    }
                    pt = fetch_photon(point_texels, i);
                    i++;
                    vec3 pos = load3(pt.position);
                    vec3 dd = pos - h.p;
                    near = dot(dd, dd) <= r2 && grid_cell(pos, vgrid.cell_size) == cell;
                    if (near) break;
                }
                if (!near) break;
                LightVertex lv = fetch_light_vertex(vertex_texels, pt.flux_rg * params.vertex_slots + pt.flux_b_dir);
                if (lv.path_length + m - 1u > frame.max_depth) continue;
                vec3 light_dir = -load3(lv.direction);
                vec3 fr = bsdf_eval(b, wo, light_dir);
                if (fr == vec3(0.0)) continue;
                float w = 1.0;
                if (!merge_only) {
                    vec2 pdfs = lobe_pdfs(b, wo, light_dir);
                    float w_light = wmul(lv.d_vcm, params.vc_weight) + wmul(lv.d_vm, mis(pdfs.x));
                    float w_camera = wmul(c.sp.d_vcm, params.vc_weight) + wmul(c.sp.d_vm, mis(pdfs.y));
                    w = 1.0 / (w_light + 1.0 + w_camera);
                }
                uint ml = path_layer(c.first_specular, cam_diffuse + (lv.flags & VERTEX_DIFFUSE_MASK),
                                     (lv.flags & VERTEX_SPECULAR_FIRST) != 0u);
                merged[ml] += fr * load3(lv.throughput) * w;
            }
            for (uint i = 0u; i < 4u; i++) c.terms[i] += c.sp.throughput * merged[i] * params.vm_normalization;
            if (merge_only) return false;
        }
    }
    if (light_only && (flags & BSDF_ESTIMATE) != 0u) return false;
    float q = bsdf_path_probability(b, wo);
    vec4 u = bsdf_numbers(stream, sample_index, uvec2(stream, sample_index), frame.seed, dim + RNG_FRESNEL);
    bool delta = u.w < q;
    BsdfSample smp = bsdf_sample(b, wo, u.xyz, delta ? LOBES_PATH : LOBES_ESTIMATE);
    if (smp.flags == 0u) return false;
    float cos_out = abs_cos(b, smp.wi);
    if ((smp.flags & BSDF_SPECULAR) != 0u) {
        sub_scatter(c.sp, params, true, cos_out, 0.0, 0.0, false);
        c.first_specular = c.first_specular || m == 1u;
        c.specular_after = c.diffuse > 0u;
        c.sp.throughput *= smp.weight / q;
    } else {
        vec2 pdfs = lobe_pdfs(b, wo, smp.wi);
        if (pdfs.x <= 0.0) return false;
        sub_scatter(c.sp, params, false, cos_out, pdfs.x, pdfs.y, merges);
        c.diffuse++;
        c.specular_after = false;
        c.specular_path = false;
        c.sp.throughput *= smp.weight / (1.0 - q);
    }
    if (m >= BPT_ROULETTE_DEPTH) {
        float survive = min(max(c.sp.throughput.x, max(c.sp.throughput.y, c.sp.throughput.z)), PT_ROULETTE_MAX);
        if (rand1(stream, sample_index, frame.seed, dim + RNG_ROULETTE) >= survive) return false;
        c.sp.throughput /= survive;
    }
    if (c.sp.throughput == vec3(0.0)) return false;
#ifdef VARIANT_MEDIA
    if (!nv.scattered && (smp.flags & BSDF_TRANSMISSION) != 0u) c.medium = medium_after(prim, h.ng, smp.wi, c.medium);
#endif
    c.prev_x = h.p;
    c.prev_n = receiver_normal(b);
    c.o = offset_origin(h, wo, smp.flags);
    c.d = smp.wi;
    c.m++;
    return true;
}

// The light tracing that landed on the path's pixel, and the pixel's sums into the accumulation.
void camera_path_finish(CameraPath c) {
    // The pixel's splats: LAYER_COUNT layers of three (low, high) word pairs, six words a layer,
    // so a layer starts at texel 3i/2 of the pixel's, in its first or its third word.
    int base = int(c.stream * LAYER_COUNT * 3u / 2u);
    for (int i = 0; i < 4; i++) {
        uvec4 a = texelFetch(splat_texels, base + 3 * i / 2);
        uvec4 b = texelFetch(splat_texels, base + 3 * i / 2 + 1);
        c.terms[i] += i % 2 == 0 ? vec3(splat_value(a.x, a.y), splat_value(a.z, a.w), splat_value(b.x, b.y))
                                 : vec3(splat_value(a.z, a.w), splat_value(b.x, b.y), splat_value(b.z, b.w));
    }
    uint at = c.stream * LAYER_COUNT;
    accumulation[at + LAYER_DIRECT] += vec4(c.terms[LAYER_DIRECT], float(c.rays));
    accumulation[at + LAYER_SPECULAR] += vec4(c.terms[LAYER_SPECULAR], 0.0);
    accumulation[at + LAYER_INDIRECT] += vec4(c.terms[LAYER_INDIRECT], 0.0);
    accumulation[at + LAYER_CAUSTICS] += vec4(c.terms[LAYER_CAUSTICS], 0.0);
}

// A run stopped at a vertex boundary: the next job and the path under way, word for word, so
// that the resumed path computes exactly what it would have in one go.
void store_run(uint i, uint job, CameraPath c) {
    uint at = i * VCM_CAMERA_STATE_WORDS;
    uint w[VCM_CAMERA_STATE_WORDS];
    w[0] = job;
    w[1] = c.stream;
    w[2] = floatBitsToUint(c.o.x); w[3] = floatBitsToUint(c.o.y); w[4] = floatBitsToUint(c.o.z);
    w[5] = floatBitsToUint(c.d.x); w[6] = floatBitsToUint(c.d.y); w[7] = floatBitsToUint(c.d.z);
    w[8] = floatBitsToUint(c.sp.throughput.x); w[9] = floatBitsToUint(c.sp.throughput.y);
    w[10] = floatBitsToUint(c.sp.throughput.z);
    w[11] = floatBitsToUint(c.sp.d_vcm); w[12] = floatBitsToUint(c.sp.d_vc); w[13] = floatBitsToUint(c.sp.d_vm);
    w[14] = c.m;
    w[15] = c.skip;
    w[16] = c.first_specular ? 1u : 0u;
    w[17] = c.diffuse;
    w[18] = c.specular_after ? 1u : 0u;
    w[19] = c.specular_path ? 1u : 0u;
    w[20] = c.medium;
    w[21] = c.segment;
    for (int t = 0; t < 4; t++) {
        w[22 + 3 * t] = floatBitsToUint(c.terms[t].x);
        w[23 + 3 * t] = floatBitsToUint(c.terms[t].y);
        w[24 + 3 * t] = floatBitsToUint(c.terms[t].z);
    }
    w[34] = c.rays;
    w[35] = 0u;
    w[36] = floatBitsToUint(c.prev_x.x); w[37] = floatBitsToUint(c.prev_x.y); w[38] = floatBitsToUint(c.prev_x.z);
    w[39] = floatBitsToUint(c.prev_n.x); w[40] = floatBitsToUint(c.prev_n.y); w[41] = floatBitsToUint(c.prev_n.z);
    for (uint k = 0u; k < VCM_CAMERA_STATE_WORDS; k++) run_states[at + k] = w[k];
}

// `store_run` read back: returns the job.
uint load_run(uint i, out CameraPath c) {
    uint at = i * VCM_CAMERA_STATE_WORDS;
    uint w[VCM_CAMERA_STATE_WORDS];
    for (uint k = 0u; k < VCM_CAMERA_STATE_WORDS; k++) w[k] = run_states[at + k];
    c.stream = w[1];
    c.o = uintBitsToFloat(uvec3(w[2], w[3], w[4]));
    c.d = uintBitsToFloat(uvec3(w[5], w[6], w[7]));
    c.sp.throughput = uintBitsToFloat(uvec3(w[8], w[9], w[10]));
    c.sp.d_vcm = uintBitsToFloat(w[11]);
    c.sp.d_vc = uintBitsToFloat(w[12]);
    c.sp.d_vm = uintBitsToFloat(w[13]);
    c.m = w[14];
    c.skip = w[15];
    c.first_specular = w[16] != 0u;
    c.diffuse = w[17];
    c.specular_after = w[18] != 0u;
    c.specular_path = w[19] != 0u;
    c.medium = w[20];
    c.segment = w[21];
    for (int t = 0; t < 4; t++) c.terms[t] = uintBitsToFloat(uvec3(w[22 + 3 * t], w[23 + 3 * t], w[24 + 3 * t]));
    c.rays = w[34];
    c.prev_x = uintBitsToFloat(uvec3(w[36], w[37], w[38]));
    c.prev_n = uintBitsToFloat(uvec3(w[39], w[40], w[41]));
    return w[0];
}

// Each invocation renders the paths of pixels i, i + n, i + 2n, ... of the band (n invocations,
// params.paths_per_invocation pixels each), a vertex per loop turn, starting the next pixel's
// path as soon as one ends. Lavapipe runs a loop turn for all 8 lanes of a SIMD group while any
// goes on, so with one path per invocation a group cost its longest path's vertices (twice the
// mean on cornell-glossy); a run of paths evens the lanes out. A real GPU wants the invocations
// instead: there it is 1.
void main() {
    uint band_pixels = dispatch_pixels();
    uint per = max(params.paths_per_invocation, 1u);
    uint lanes = (band_pixels + per - 1u) / per;
    uint i = GLOBAL_INDEX;
    if (i >= lanes) return;
    uint jobs = (band_pixels - i + lanes - 1u) / lanes;  // pixels i + k lanes below band_pixels
    CameraPath c;
    uint job = 0u;
    if (params.resume != 0u) {
        job = load_run(i, c);
        if (job >= jobs) return;  // finished in an earlier dispatch
    } else {
        uint p = dispatch_pixel(i);
        c = camera_path_start(p % frame.width, range.row_begin + p / frame.width);
    }
    // Bounded: each turn is a vertex of one of `jobs` paths of at most max_depth + 1 vertices,
    // and at most params.steps_per_dispatch turns (when not 0) before the run is stored for the
    // next dispatch: lavapipe's loop limit counts every traversal step of every ray, and deep
    // paths through large scenes pass it even one to an invocation (docs/architecture.md).
    uint steps = 0u;
    for (;;) {
        if (steps == params.steps_per_dispatch && steps != 0u) {
            store_run(i, job, c);
            atomicAdd(suspended, 1u);
            return;
        }
        steps++;
        if (camera_path_step(c)) continue;
        camera_path_finish(c);
        job++;
        if (job >= jobs) break;
        uint p = dispatch_pixel(i + job * lanes);
        c = camera_path_start(p % frame.width, range.row_begin + p / frame.width);
    }
    // Ended by the driver's loop limit (lavapipe's 65535 iterations per invocation) with paths
    // left: say so, and the host renders the sample again with shorter runs.
    if (job < jobs) atomicAdd(broken_off, 1u);
    // A later dispatch of a stopped run skips this invocation.
    else if (params.steps_per_dispatch != 0u) run_states[i * VCM_CAMERA_STATE_WORDS] = jobs;
}
