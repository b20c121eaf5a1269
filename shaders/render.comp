#version 450
// render: the four terms of each pixel, accumulated over a band of rows, one sample and one part
// of it (see DispatchRange). A camera
// path follows path lobes (mirrors, glass) to the first estimate lobe; there the direct light comes from
// light sampling, the caustics from the caustic map, the indirect light from a final gather on
// the global map. Terms reached through a mirror or glass are the specular term.
// CPU twin: src/cpu/render.rs. Bindings: the scene (scene_bindings.glsl), then the
// accumulation (LAYER_COUNT vec4 per pixel of the band; rgb = sum of samples; w of the direct
// layer = rays cast), grids, global photons, global starts, caustic photons, caustic starts,
// volume photons, volume starts, the pixel list (pixel_list.glsl). The `media` variant adds participating media: free flights
// of camera and gather rays (a scattering point is an estimate vertex whose BSDF is the phase
// function), transmittance of shadow rays, null boundaries, and the volume photon map.
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
layout(scalar, binding = SCENE_BINDINGS + 1) uniform Grids { GridParams grids[MAP_COUNT]; };
// The photon maps as uniform texel buffers of RGBA32UI texels (fetch_photon in grid.glsl) and
// their bucket starts as texel buffers of words (R32UI): see scene_bindings.glsl on why.
layout(binding = SCENE_BINDINGS + 2) uniform usamplerBuffer global_photons;
layout(binding = SCENE_BINDINGS + 3) uniform usamplerBuffer global_starts;
layout(binding = SCENE_BINDINGS + 4) uniform usamplerBuffer caustic_photons;
layout(binding = SCENE_BINDINGS + 5) uniform usamplerBuffer caustic_starts;
layout(binding = SCENE_BINDINGS + 6) uniform usamplerBuffer volume_photons;
layout(binding = SCENE_BINDINGS + 7) uniform usamplerBuffer volume_starts;
layout(std430, binding = SCENE_BINDINGS + 8) readonly buffer PixelList { uint pixel_list[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "scene.glsl"
#include "pixel_list.glsl"
#include "photon.glsl"
#include "grid.glsl"
#include "gather.glsl"

// What the ray of the current step is (see radiance).
const uint RAY_CAMERA = 0u; // camera path: through path lobes to the first estimate lobe
const uint RAY_SHADOW = 1u; // the shadow ray of the direct light at the estimate vertex
const uint RAY_GATHER = 2u; // a final-gather ray: through path lobes to an estimate lobe
const uint RAY_SHAFT = 3u;  // the shadow ray of an equiangular sample of a camera segment (media)
const uint RAY_LOOKUP = 4u; // no ray (NO_RAY): the photon lookups at the estimate vertex
const uint RAY_PROBE = 5u;  // an edge probe of the lookups' discs (edge_probe_ray)

// Steps of the loop: a path of max_depth bounces and its crossings of medium boundaries; with
// media each camera segment may take three (its equiangular shadow ray, then its retrace); and
// the extra shadow rays of an adaptive light (each with its crossings). Then the lookups and
// their edge probes.
#ifdef VARIANT_MEDIA
#define LOOP_STEPS (3u * (2u * frame.max_depth + 1u + MEDIUM_CROSSINGS) + (ADAPTIVE_MAX_RAYS - 1u) * (1u + MEDIUM_CROSSINGS) + 1u + 2u * EDGE_PROBES)
#else
#define LOOP_STEPS (2u * frame.max_depth + 1u + ADAPTIVE_MAX_RAYS - 1u + 1u + 2u * EDGE_PROBES)
#endif

// Adds part `part` of the sample's terms to `terms` and the rays it casts to `rays` (see
// DispatchRange: part 0 is everything but the final gather, part k >= 1 is gather ray k - 1).
// `penumbra_since`: the sample at which the pixel's earlier shadow rays toward adaptive lights
// were first found some blocked, some not (NO_SAMPLE: not yet); this sample's rays toward them
// are counted into `blocked` and `lit`.
// The camera path, its shadow ray and its gather path are one loop with one `trace_ray`, one
// `material_bsdf` and one `photon_radiance` in it (src/cpu/render.rs is the same loop): lavapipe
// inlines every call site, so three traversals and two material evaluations made the kernel
// three times the code, and as much slower to compile and to run.
void radiance(uint px, uint py, uint sample_index, uint part, uint penumbra_since, inout vec3 terms[4], inout uint rays, inout uint blocked, inout uint lit) {
    uint stream = py * frame.width + px;
    // The film position, then the lens.
    vec2 film = film_offset(qmc2(stream, sample_index, frame.seed, RNG_PIXEL_X));
    float sx = 2.0 * (float(px) + film.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + film.y) / float(frame.height);
    vec3 o, d;
    camera_ray(sx, sy, lens_sample(stream, sample_index), o, d);
    float t_max = INF;
    uint ray = RAY_CAMERA;
    uint depth = 0u;           // path-lobe bounces of the current path so far
    vec3 throughput = vec3(1.0);
    uint medium = frame.camera_medium;  // the medium the current ray runs through
    uint segment = 0u;         // free flights of the path so far (their random dimensions)
    // The camera segment an equiangular sample interrupted, resumed after its shadow ray.
    bool shaft_done = false;
    vec3 shaft_o = vec3(0.0);
    vec3 shaft_d = vec3(0.0);
    uint shaft_medium = NO_MEDIUM;
    uint shaft_layer = LAYER_DIRECT;
    // The estimate vertex: the camera path's (then the gather path's) last vertex.
    Hit he;
    Bsdf be;
    vec3 wo_e = vec3(0.0);
    vec3 weight = vec3(0.0);   // throughput up to the estimate vertex
    bool via_specular = false; // the estimate vertex was reached through mirrors or glass
    bool volume_e = false;     // the estimate vertex is a scattering point in a medium
    vec3 inv_sigma_t_e = vec3(0.0);
    vec3 unoccluded = vec3(0.0);
    // The estimate vertex's shadow rays: this one, how many, toward an adaptive light, and the
    // medium they start in.
    uint shadow_ray = 0u;
    uint shadow_rays = 1u;
    bool shadow_adaptive = false;
    uint medium_e = NO_MEDIUM;
    vec3 gather_weight = vec3(0.0);
    uint gdim = 0u;
    // Photon lookups at the estimate vertex, done after the loop: caustics and the preview, or
    // the gather path's end.
    uint lookups = 0u;
    uint lookup_map[2];
    uint lookup_exclude[2];
    uint lookup_layer[2];
    vec3 lookup_weight[2];
    Gathered found[2];
    found[0] = Gathered(vec3(0.0), vec3(0.0), false);
    found[1] = found[0];
    // The lookups are the camera path's own, on a surface: their discs are probed for edges
    // where they find photons of another surface in reach. The probes' frame (facing normal,
    // largest radius, turn), the next probe, and how far the surface reaches in each direction.
    bool probe_edges = false;
    vec3 probe_n = vec3(0.0);
    float probe_reach = 0.0;
    float probe_turn = 0.0;
    uint probe = 0u;
    float surface_reach[EDGE_PROBES];

    // The smooth triangle the current ray leaves, which it must not meet again (see trace_ray).
    uint skip = NO_LIGHT;
    for (uint step = 0u; step < LOOP_STEPS; step++) {
        float t;
        // A shadow ray of length NO_RAY was not needed: trace_ray returns at once, uncounted.
        if (t_max != NO_RAY) rays++;
        bool any_hit = ray == RAY_SHADOW || ray == RAY_SHAFT;
#ifdef VARIANT_MEDIA
        // Shadow rays take the closest hit: they pass null boundaries and sum the media between.
        any_hit = false;
#endif
        // A shaft ray leaves a point in a medium, which has no triangle to skip; a probe leaves
        // the surface's plane.
        uint prim = trace_ray(o, d, t_max, any_hit, ray == RAY_SHAFT || ray == RAY_PROBE ? NO_LIGHT : skip, t);
        bool scattered = false;
#ifdef VARIANT_MEDIA
        // The medium up to the hit (or to the light, or to infinity): shadow rays take its
        // transmittance, camera and gather rays sample a free flight through it.
        // A probe looks for the surface's edges, not through the medium.
        if (medium != NO_MEDIUM && t_max != NO_RAY && ray != RAY_PROBE) {
            if (ray == RAY_SHADOW || ray == RAY_SHAFT) {
                unoccluded *= medium_transmittance(medium, o, d, t, rand2(stream, sample_index, frame.seed, RNG_TRANSMITTANCE_DOMAIN + step));
            } else {
                // Single scattering from point and spot lights along the whole camera segment,
                // by equiangular sampling (the light shafts; the free flight's scattering
                // point leaves these lights out): the sample's shadow ray runs first, then the
                // segment is traced again and goes on. Not in heterogeneous media: equiangular
                // samples ignore the density, and in sparse smoke most would land in clear
                // air while the rest carry all the light (speckles); there the free flight's
                // scattering point, placed by the density, samples these lights too.
                // (A scene of no lights, or whose lights all give no power, has nothing to pick.)
                if (ray == RAY_CAMERA && part == 0u && !shaft_done && frame.light_count > 0u && medium_at(medium).density == NO_TEXTURE) {
                    vec4 ue = rand4(stream, sample_index, frame.seed, RNG_EQUIANGULAR_DOMAIN + segment);
                    Light l = light_at(pick_light(ue.x, false));
                    // A spot's samples stay in its cone, where its light is.
                    vec2 span = l.kind == LIGHT_SPOT ? spot_span(o, d, t, load3(l.position), load3(l.direction), l.cos_outer) : vec2(0.0, t);
                    if ((l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT) && l.pick_probability > 0.0 && span.x < span.y) {
                        float pdf;
                        float te = span.x + equiangular_sample(o + d * span.x, d, span.y - span.x, load3(l.position), ue.y, pdf);
                        vec3 x = o + d * te;
                        vec3 to_light = load3(l.position) - x;
                        float r2 = dot(to_light, to_light);
                        float r = sqrt(r2);
                        vec3 wi = to_light / r;
                        Medium md = medium_at(medium);
                        vec3 c = throughput * medium_transmittance(medium, o, d, te, ue.zw) * load3(md.sigma_s)
                            * (phase_hg(dot(-d, wi), md.g) * spot_falloff(l, -wi) / (r2 * pdf * l.pick_probability))
                            * load3(l.intensity);
                        if (pdf > 0.0 && r > 0.0 && c != vec3(0.0)) {
                            shaft_o = o;
                            shaft_d = d;
                            shaft_medium = medium;
                            shaft_layer = depth > 0u ? LAYER_SPECULAR : LAYER_DIRECT;
                            unoccluded = c;
                            o = x;
                            d = wi;
                            t_max = max(r - frame.ray_epsilon, 0.0);
                            ray = RAY_SHAFT;
                            continue;
                        }
                    }
                }
                shaft_done = false;
                uint key = RNG_MEDIUM_DOMAIN + (ray == RAY_GATHER ? part : 0u) * RNG_MEDIUM_DIMS_PER_PART + segment;
                segment++;
                MediumEvent e = medium_sample(medium, o, d, t, qmc2(stream, sample_index, frame.seed, key));
                if (ray == RAY_CAMERA && part == 0u) terms[depth > 0u ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * e.emission;
                throughput *= e.weight;
                scattered = e.scattered;
                t = e.t;
                if (throughput == vec3(0.0)) break;
            }
        }
#endif
        if (ray == RAY_LOOKUP) {
            bool off_disc = false;
            for (uint k = 0u; k < lookups; k++) {
                found[k] = photon_radiance(lookup_map[k], he, be, wo_e, lookup_exclude[k]);
                off_disc = off_disc || found[k].off_disc;
            }
            if (!probe_edges) break;
            probe_n = facing(be, wo_e);
            probe_reach = grids[lookup_map[0]].radius;
            if (lookups > 1u) probe_reach = max(probe_reach, grids[lookup_map[1]].radius);
            probe_turn = rand1(stream, sample_index, frame.seed, RNG_EDGE_PROBE);
            // An instance's triangle carries no open-edge flags; no probes with instances (see the twin).
            open_edge_reach(he.prim < frame.primitive_count ? he.prim : NO_LIGHT, he.p, probe_n, probe_reach, probe_turn, surface_reach);
            if (frame.instance_count > 0u || !off_disc) break;
            edge_probe_ray(he.p, probe_n, probe_reach, probe_turn, 0u, o, d);
            t_max = probe_reach;
            ray = RAY_PROBE;
            continue;
        }
        Hit h;
        bool null_hit = false;
#ifdef VARIANT_MEDIA
        if (scattered) {
            h = medium_hit(o + d * t, -d);
        } else if (prim != NO_LIGHT) {
            h = shape_hit(prim, o, d, t);
            null_hit = material_at(h.material).kind == MATERIAL_NULL;
        }
#else
        if (prim != NO_LIGHT && ray != RAY_SHADOW) h = shape_hit(prim, o, d, t);
#endif
        if (ray == RAY_PROBE) {
            // A wall across the probe's way (an invisible boundary is none) ends the surface there.
            if (prim != NO_LIGHT && !null_hit && abs(dot(h.ng, probe_n)) < EDGE_PROBE_COS) {
                uint i = probe / 2u;
                surface_reach[i] = min(surface_reach[i], (probe % 2u) == 0u ? t : probe_reach - t);
            }
            probe++;
            if (probe == 2u * EDGE_PROBES) break;
            edge_probe_ray(he.p, probe_n, probe_reach, probe_turn, probe, o, d);
            t_max = probe_reach;
            continue;
        }
#ifdef VARIANT_MEDIA
        if (null_hit) {
            // An invisible boundary: straight through into the medium beyond, not a bounce.
            medium = medium_after(prim, h.ng, d, medium);
            if (ray != RAY_SHAFT) skip = ray_skip(prim);
            vec3 next = offset_origin(h, -d, BSDF_TRANSMISSION);
            if (ray == RAY_SHADOW || ray == RAY_SHAFT) t_max = max(t_max - dot(next - o, d), 0.0);
            o = next;
            continue;
        }
        if (ray == RAY_SHAFT) {
            // The equiangular sample's shadow ray: its light if nothing blocked it; then back to
            // the camera segment it interrupted.
            if (prim == NO_LIGHT) terms[shaft_layer] += unoccluded;
            o = shaft_o;
            d = shaft_d;
            medium = shaft_medium;
            t_max = INF;
            ray = RAY_CAMERA;
            shaft_done = true;
            continue;
        }
#endif
        if (ray == RAY_SHADOW) {
            if (prim == NO_LIGHT) terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += weight * unoccluded;
            if (shadow_adaptive && t_max != NO_RAY) {
                if (prim == NO_LIGHT) lit++; else blocked++;
            }
            shadow_ray++;
            if (shadow_ray < shadow_rays) {
                ShadowRay sr = direct_light_sample(he, be, wo_e, stream, sample_index, depth * RNG_DIMS_PER_BOUNCE, penumbra_since, shadow_ray);
                unoccluded = sr.unoccluded;
                o = sr.origin;
                d = sr.direction;
                t_max = sr.t_max;
                medium = medium_e;
                continue;
            }
            if (frame.photon_mapping == 0u) break;
            if (volume_e) {
                // A scattering point: the volume map without the single scattering, which the
                // light sample gave; sigma_t-weighted collisions become radiance over sigma_t.
                lookup_map[0] = MAP_VOLUME;
                lookup_exclude[0] = PHOTON_FLAG_DIRECT;
                lookup_layer[0] = via_specular ? LAYER_SPECULAR : LAYER_INDIRECT;
                lookup_weight[0] = weight * inv_sigma_t_e;
                lookups = 1u;
                ray = RAY_LOOKUP;
                t_max = NO_RAY;
                continue;
            }
            lookup_map[0] = MAP_CAUSTIC;
            lookup_exclude[0] = 0u;
            lookup_layer[0] = via_specular ? LAYER_SPECULAR : LAYER_CAUSTICS;
            lookup_weight[0] = weight;
            lookup_map[1] = MAP_GLOBAL;
            lookup_exclude[1] = PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC;
            lookup_layer[1] = via_specular ? LAYER_SPECULAR : LAYER_INDIRECT;
            lookup_weight[1] = weight;
            lookups = frame.gather_rays == 0u ? 2u : 1u;
            probe_edges = true;
            ray = RAY_LOOKUP;
            t_max = NO_RAY;
            continue;
        }
        if (prim == NO_LIGHT && !scattered) {
            // A camera path that leaves the scene sees the environment and the discs of distant
            // lights (a path lobe's view of a light); a gather path counts none of it, as it
            // counts no emission.
            if (ray == RAY_CAMERA && part == 0u) {
                vec3 seen = distant_discs_radiance(d);
                WHEN(frame.environment != NO_LIGHT) {
                    seen += environment_radiance(light_at(frame.environment), d);
                }
                terms[depth > 0u ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * seen;
            }
            break;
        }
        skip = scattered ? NO_LIGHT : ray_skip(prim);
        vec3 wo = -d;
        bool camera = ray == RAY_CAMERA;
        Bsdf b;
        vec3 inv_sigma_t = vec3(1.0);
#ifdef VARIANT_MEDIA
        if (scattered) {
            b = phase_bsdf(medium, wo);
            vec3 st = medium_sigma_t_at(medium, h.p);
            inv_sigma_t = vec3(st.r > 0.0 ? 1.0 / st.r : 0.0, st.g > 0.0 ? 1.0 / st.g : 0.0, st.b > 0.0 ? 1.0 / st.b : 0.0);
        } else
#endif
        {
            Material m = material_at(h.material);
            // Everything a mirror or glass shows is the specular term. Emission leaves the emitting
            // faces only; it counts wherever a camera path meets it, since estimate lobes end the
            // path and light sampling covers them. A gather path counts none: direct light and
            // caustics do.
            if (camera && emitter_cosine(m.flags, h.ng, wo) > 0.0 && part == 0u) terms[depth > 0u ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * material_emission(m, h);
            b = material_bsdf(m, h);
        }
        uint dim = depth * RNG_DIMS_PER_BOUNCE;
        uint key = camera ? dim + RNG_FRESNEL : gdim + 1u + depth;
        vec4 u = bsdf_numbers(stream, sample_index, uvec2(stream, sample_index), frame.seed, key);
        // Follow the path lobes (mirrors, glass) with their probability; else end here.
        float q = bsdf_path_probability(b, wo);
        if (u.w < q) {
            BsdfSample s = bsdf_sample(b, wo, u.xyz, LOBES_PATH);
            if (s.flags == 0u) break;
            throughput *= s.weight / q;
#ifdef VARIANT_MEDIA
            if ((s.flags & BSDF_TRANSMISSION) != 0u) medium = medium_after(prim, h.ng, s.wi, medium);
#endif
            o = offset_origin(h, wo, s.flags);
            d = s.wi;
            depth++;
            if (depth >= frame.max_depth) break;
            continue;
        }
        if ((bsdf_flags(b) & BSDF_ESTIMATE) == 0u) break;
        if (!camera) {
            // The gather path's end: the global map there (the volume map at a scattering
            // point), weighted 1/gather_rays.
            he = h;
            be = b;
            wo_e = wo;
            lookup_map[0] = scattered ? MAP_VOLUME : MAP_GLOBAL;
            lookup_exclude[0] = 0u;
            lookup_layer[0] = via_specular ? LAYER_SPECULAR : LAYER_INDIRECT;
            lookup_weight[0] = weight * (gather_weight * (throughput / (1.0 - q)) / float(frame.gather_rays)) * inv_sigma_t;
            lookups = 1u;
            ray = RAY_LOOKUP;
            t_max = NO_RAY;
            continue;
        }
        he = h;
        be = b;
        wo_e = wo;
        weight = throughput / (1.0 - q);
        via_specular = depth > 0u;
        volume_e = scattered;
        inv_sigma_t_e = inv_sigma_t;
        if (part == 0u) {
            ShadowRay sr = direct_light_sample(h, b, wo, stream, sample_index, dim, penumbra_since, 0u);
            shadow_rays = sr.rays;
            shadow_adaptive = sr.adaptive;
            medium_e = medium;
            unoccluded = sr.unoccluded;
            o = sr.origin;
            d = sr.direction;
            t_max = sr.t_max;
            ray = RAY_SHADOW;
            continue;
        }
        // A scattering point reads the volume map in part 0 and has no final gather.
        if (frame.photon_mapping == 0u || scattered) break;
        // Final-gather ray part - 1, sampled from the estimate lobes.
        gdim = RNG_GATHER_DOMAIN + (part - 1u) * RNG_GATHER_DIMS_PER_RAY;
        // A pixel's gather rays are one sequence: ray j of sample i is its point i x rays + j.
        vec4 u0 = rand4(stream, sample_index, frame.seed, gdim);
        vec2 ug = qmc2(stream, sample_index * frame.gather_rays + part - 1u, frame.seed, RNG_GATHER_DOMAIN);
        BsdfSample first = bsdf_sample(b, wo, vec3(u0.z, ug.x, ug.y), LOBES_ESTIMATE);
        if (first.flags == 0u) break;
        gather_weight = first.weight;
        o = offset_origin(h, wo, first.flags);
        d = first.wi;
        throughput = vec3(1.0);
        depth = 0u;
        ray = RAY_GATHER;
    }
    // Where the probes found an edge, the thin core's photons over the kernel's share on the
    // surface; elsewhere the disc's.
    for (uint k = 0u; k < lookups; k++) {
        // Without probes the surface's reach is its open edges' alone, and the disc's photons are
        // all the surface's.
        float mass = probe_edges ? edge_mass(surface_reach, grids[lookup_map[k]].radius) : 1.0;
        vec3 v = mass < 1.0 ? (probe == 2u * EDGE_PROBES ? found[k].thin : found[k].disc) / max(mass, EDGE_MIN_MASS) : found[k].disc;
        terms[lookup_layer[k]] += lookup_weight[k] * v;
    }
}

void main() {
    if (GLOBAL_INDEX >= dispatch_pixels()) return;
    uint i = dispatch_pixel(GLOBAL_INDEX);
    uint px = i % frame.width;
    uint py = range.row_begin + i / frame.width;
    vec3 terms[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    uint rays = 0u;
    uint base = i * LAYER_COUNT;
    // w of the indirect and caustic layers: the pixel's shadow rays toward adaptive lights so
    // far in this pass, blocked and not; w of the specular layer: 1 + the sample at which both
    // were first seen (0: not yet), set by the first part 0 after it happens.
    float since_w = accumulation[base + LAYER_SPECULAR].w;
    uint penumbra_since = since_w > 0.0 ? uint(since_w) - 1u : NO_SAMPLE;
    float since_set = 0.0;
    if (range.part == 0u && penumbra_since == NO_SAMPLE && accumulation[base + LAYER_INDIRECT].w > 0.0 && accumulation[base + LAYER_CAUSTICS].w > 0.0) {
        penumbra_since = range.sample_index;
        since_set = float(range.sample_index + 1u);
    }
    uint blocked = 0u;
    uint lit = 0u;
    radiance(px, py, range.sample_index, range.part, penumbra_since, terms, rays, blocked, lit);
    // w of the direct layer counts rays; a float holds counts exactly up to 2^24 per pixel.
    // Each pixel belongs to one invocation, so plain read-modify-write is race-free.
    accumulation[base + LAYER_DIRECT] += vec4(terms[LAYER_DIRECT], float(rays));
    accumulation[base + LAYER_SPECULAR] += vec4(terms[LAYER_SPECULAR], since_set);
    accumulation[base + LAYER_INDIRECT] += vec4(terms[LAYER_INDIRECT], float(blocked));
    accumulation[base + LAYER_CAUSTICS] += vec4(terms[LAYER_CAUSTICS], float(lit));
}
