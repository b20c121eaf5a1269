#version 450
// render_pt: the path-tracing integrator (`integrator = "pt"`). Camera paths through every lobe,
// light sampling at each vertex with non-delta lobes, the emission paths meet, both weighed by
// multiple importance sampling (the power heuristic); no photon maps. Each contribution goes into
// the layer of its path's signature (E S... specular, E L and E D L direct, E D S+ L caustics,
// the rest indirect). CPU twin: src/cpu/render_pt.rs. Bindings: those of render.comp (the
// scene, the accumulation, then the photon maps, which this kernel does not read), so the host
// drives both alike.
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
// The photon maps' bindings (SCENE_BINDINGS + 1 to + 7) are render.comp's, unused here.
layout(std430, binding = SCENE_BINDINGS + 8) readonly buffer PixelList { uint pixel_list[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "scene.glsl"
#include "pixel_list.glsl"

// Loop steps of one camera path: a path ray and a shadow ray per vertex, plus the crossings of
// null boundaries where there are media. Contract: src/cpu/render_pt.rs, pt_steps.
#ifdef VARIANT_MEDIA
#define LOOP_STEPS (2u * (frame.max_depth + 1u) * (1u + MEDIUM_CROSSINGS))
#else
#define LOOP_STEPS (2u * (frame.max_depth + 1u))
#endif

// The power heuristic; contract in src/cpu/render_pt.rs, mis_power.
float mis_power(float a, float b) {
    if (a <= 0.0) return 0.0;
    if (b <= 0.0 || isinf(b)) return 1.0;
    float r = b / a;
    return 1.0 / (1.0 + r * r);
}

// The weight of a path made by technique `own`; contract in src/cpu/render_pt.rs, mis_weight.
float mis_weight(uint techniques, uint own, float p_own, float p_other) {
    if (p_other <= 0.0 || techniques == own) return 1.0;
    if ((techniques & own) == 0u) return 0.0;
    return mis_power(p_own, p_other);
}

// The layer of a path that ends at a light; contract in src/cpu/render_pt.rs, path_layer.
uint path_layer(bool first_specular, uint diffuse, bool specular_after) {
    if (first_specular) return LAYER_SPECULAR;
    if (diffuse <= 1u && !specular_after) return LAYER_DIRECT;
    if (diffuse == 1u) return LAYER_CAUSTICS;
    return LAYER_INDIRECT;
}

// The path ray and its shadow rays are one loop with one trace_ray and one material_bsdf, for
// lavapipe's sake (see render.comp).
void radiance_pt(uint px, uint py, uint sample_index, inout vec3 terms[4], inout uint rays) {
    uint stream = py * frame.width + px;
    vec2 film = film_offset(qmc2(stream, sample_index, frame.seed, RNG_PIXEL_X));
    float sx = 2.0 * (float(px) + film.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + film.y) / float(frame.height);
    vec3 o, d;
    camera_ray(sx, sy, lens_sample(stream, sample_index), o, d);
    float t_max = INF;
    bool shadow = false;
    vec3 throughput = vec3(1.0);
    uint medium = frame.camera_medium;
    uint vertex = 0u;   // scattering vertices so far
    uint segment = 0u;  // free flights so far
    uint skip = NO_LIGHT;
    // The last scattering vertex and the density its lobes drew the path ray with (0: delta).
    vec3 prev_p = o;
    // The normal light selection used at prev_p (zero in a medium), for the pick probability
    // that weighs emission met against light sampling there.
    vec3 prev_n = vec3(0.0);
    float prev_pdf = 0.0;
    bool first_specular = false;
    uint diffuse = 0u;
    bool specular_after = false;
    vec3 unoccluded = vec3(0.0);
    uint shadow_layer = LAYER_DIRECT;
    vec3 next_o = vec3(0.0);
    vec3 next_d = vec3(0.0);
    uint next_medium = NO_MEDIUM;
    uint next_skip = NO_LIGHT;
    bool next_end = false;
    uint shadow_medium = NO_MEDIUM;

    for (uint step = 0u; step < LOOP_STEPS; step++) {
        if (t_max != NO_RAY) rays++;
        bool any_hit = shadow;
#ifdef VARIANT_MEDIA
        any_hit = false;
#endif
        float t;
        uint prim = trace_ray(o, d, t_max, any_hit, skip, t);
        bool scattered = false;
#ifdef VARIANT_MEDIA
        uint cur_medium = shadow ? shadow_medium : medium;
        if (cur_medium != NO_MEDIUM && t_max != NO_RAY) {
            if (shadow) {
                unoccluded *= medium_transmittance(cur_medium, o, d, t, rand2(stream, sample_index, frame.seed, RNG_TRANSMITTANCE_DOMAIN + step));
            } else {
                MediumEvent e = medium_sample(cur_medium, o, d, t, qmc2(stream, sample_index, frame.seed, RNG_MEDIUM_DOMAIN + segment));
                segment++;
                terms[path_layer(first_specular, diffuse, specular_after)] += throughput * e.emission;
                throughput *= e.weight;
                scattered = e.scattered;
                t = e.t;
                if (throughput == vec3(0.0)) break;
            }
        }
#endif
        Hit h;
#ifdef VARIANT_MEDIA
        bool null_hit = false;
        if (scattered) {
            h = medium_hit(o + d * t, -d);
        } else if (prim != NO_LIGHT) {
            h = shape_hit(prim, o, d, t);
            null_hit = material_at(h.material).kind == MATERIAL_NULL;
        }
        if (null_hit) {
            // An invisible boundary: straight through into the medium beyond, not a vertex.
            if (shadow) shadow_medium = medium_after(prim, h.ng, d, shadow_medium);
            else medium = medium_after(prim, h.ng, d, medium);
            skip = ray_skip(prim);
            vec3 next = offset_origin(h, -d, BSDF_TRANSMISSION);
            if (shadow) t_max = max(t_max - dot(next - o, d), 0.0);
            o = next;
            continue;
        }
#else
        if (prim != NO_LIGHT && !shadow) h = shape_hit(prim, o, d, t);
#endif
        if (shadow) {
            if (prim == NO_LIGHT) terms[shadow_layer] += unoccluded;
            if (next_end) break;
            o = next_o;
            d = next_d;
            medium = next_medium;
            skip = next_skip;
            t_max = INF;
            shadow = false;
            continue;
        }
        if (prim == NO_LIGHT && !scattered) {
            // The path leaves the scene: the environment and the discs of distant lights, each
            // weighed against its own light sampling.
            uint layer = path_layer(first_specular, diffuse, specular_after);
            for (uint i = 0u; i < frame.light_count; i++) {
                Light l = light_at(i);
                if (l.kind != LIGHT_DISTANT || l.area <= 0.0) break;
                if (dot(d, load3(l.direction)) <= -l.cos_outer) {
                    float w = prev_pdf > 0.0 ? mis_weight(frame.techniques, TECHNIQUE_BSDF, prev_pdf, direct_light_pmf(i, prev_p, prev_n) / l.area) : 1.0;
                    terms[layer] += throughput * load3(l.intensity) * (w / l.area);
                }
            }
            WHEN(frame.environment != NO_LIGHT) {
                Light l = light_at(frame.environment);
                float w = prev_pdf > 0.0 ? mis_weight(frame.techniques, TECHNIQUE_BSDF, prev_pdf, direct_light_pmf(frame.environment, prev_p, prev_n) * light_pdf(l, d, 0.0, 0.0)) : 1.0;
                terms[layer] += throughput * environment_radiance(l, d) * w;
            }
            break;
        }
        vec3 wo = -d;
        Bsdf b;
#ifdef VARIANT_MEDIA
        if (scattered) {
            b = phase_bsdf(medium, wo);
        } else
#endif
        {
            Material m = material_at(h.material);
            // Emission leaves the emitting faces only (emitter_cosine); a light that light sampling could have drawn
            // is weighed against it.
            float cos_l = emitter_cosine(m.flags, h.ng, wo);
            if (cos_l > 0.0) {
                vec3 emitted = material_emission(m, h);
                if (emitted != vec3(0.0)) {
                    uint hp = hit_primitive(prim);
                    uint light = primitive_at(hp).light;
                    float w = 1.0;
                    if (prev_pdf > 0.0 && light != NO_LIGHT && hp == prim) {
                        Light l = light_at(light);
                        w = mis_weight(frame.techniques, TECHNIQUE_BSDF, prev_pdf, direct_light_pmf(light, prev_p, prev_n) * light_pdf(l, d, length(h.p - prev_p), cos_l));
                    }
                    terms[path_layer(first_specular, diffuse, specular_after)] += throughput * emitted * w;
                }
            }
            b = material_bsdf(m, h);
        }
        uint flags = bsdf_flags(b);
        if (flags == 0u) break;
        vec3 receiver = scattered ? vec3(0.0) : b.ns;
        skip = scattered ? NO_LIGHT : ray_skip(prim);
        uint dim = vertex * RNG_DIMS_PER_BOUNCE;
        float q = bsdf_path_probability(b, wo);

        // The next path ray: the delta lobes with probability q, else the others.
        vec4 u = bsdf_numbers(stream, sample_index, uvec2(stream, sample_index), frame.seed, dim + RNG_FRESNEL);
        bool delta = u.w < q;
        BsdfSample smp = bsdf_sample(b, wo, u.xyz, delta ? LOBES_PATH : LOBES_ESTIMATE);
        float choice = delta ? q : 1.0 - q;
        next_end = smp.flags == 0u || vertex + 1u >= frame.max_depth;
        if (!next_end) {
            next_d = smp.wi;
            next_o = offset_origin(h, wo, smp.flags);
            next_medium = medium;
#ifdef VARIANT_MEDIA
            if ((smp.flags & BSDF_TRANSMISSION) != 0u && !scattered) next_medium = medium_after(prim, h.ng, smp.wi, medium);
#endif
            next_skip = skip;
        }

        // Light sampling, where the lobes are not all delta.
        bool light_ray = false;
        if ((flags & BSDF_ESTIMATE) != 0u && frame.light_count > 0u) {
            float pmf;
            uint light = pick_direct_light(rand1(stream, sample_index, frame.seed, dim + RNG_LIGHT_PICK), h.p, receiver, pmf);
            if (pmf > 0.0) {
                Light l = light_at(light);
                vec2 ul = qmc2(stream, sample_index, frame.seed, dim + RNG_LIGHT_U);
                LightSample ls = light_sample(l, h.p, grid_sample(l.grid, ul, stream, sample_index));
                float cosine = scattered ? 1.0 : abs(dot(b.ns, ls.wi));
                vec3 fr = bsdf_eval(b, wo, ls.wi) * ls.weight * cosine;
                if (fr != vec3(0.0)) {
                    float p_bsdf = ls.pdf > 0.0 ? (1.0 - q) * bsdf_pdf(b, wo, ls.wi) : 0.0;
                    float w = mis_weight(frame.techniques, TECHNIQUE_LIGHT, pmf * ls.pdf, p_bsdf);
                    vec3 origin = offset_origin(h, ls.wi, BSDF_REFLECTION);
                    vec3 to_target = ls.p - origin;
                    float len = length(to_target);
                    unoccluded = throughput * fr * (w / pmf);
                    shadow_layer = path_layer(first_specular, diffuse + 1u, false);
                    shadow_medium = medium;
                    o = origin;
                    d = to_target / len;
                    t_max = max(len - ls.eps, 0.0);
                    light_ray = true;
                }
            }
        }

        // The path's signature and throughput after this vertex.
        if ((smp.flags & BSDF_SPECULAR) != 0u) {
            first_specular = first_specular || vertex == 0u;
            specular_after = diffuse > 0u;
            prev_pdf = 0.0;
        } else {
            diffuse++;
            specular_after = false;
            prev_pdf = choice * bsdf_pdf(b, wo, smp.wi);
        }
        prev_p = h.p;
        prev_n = receiver;
        throughput *= smp.weight / choice;
        vertex++;
        // Russian roulette, on the throughput's largest channel.
        if (!next_end && vertex >= PT_ROULETTE_DEPTH) {
            float survive = min(max(throughput.x, max(throughput.y, throughput.z)), PT_ROULETTE_MAX);
            if (rand1(stream, sample_index, frame.seed, dim + RNG_ROULETTE) >= survive) next_end = true;
            else throughput /= survive;
        }
        if (light_ray) {
            shadow = true;
            continue;
        }
        if (next_end) break;
        o = next_o;
        d = next_d;
        medium = next_medium;
    }
}

void main() {
    if (GLOBAL_INDEX >= dispatch_pixels()) return;
    uint i = dispatch_pixel(GLOBAL_INDEX);
    uint px = i % frame.width;
    uint py = range.row_begin + i / frame.width;
    vec3 terms[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    uint rays = 0u;
    radiance_pt(px, py, range.sample_index, terms, rays);
    // Each pixel belongs to one invocation, so plain read-modify-write is race-free; w of the
    // direct layer counts rays (exact up to 2^24 per pixel).
    uint base = i * LAYER_COUNT;
    accumulation[base + LAYER_DIRECT] += vec4(terms[LAYER_DIRECT], float(rays));
    accumulation[base + LAYER_SPECULAR] += vec4(terms[LAYER_SPECULAR], 0.0);
    accumulation[base + LAYER_INDIRECT] += vec4(terms[LAYER_INDIRECT], 0.0);
    accumulation[base + LAYER_CAUSTICS] += vec4(terms[LAYER_CAUSTICS], 0.0);
}
