// One photon path from the lights: emission, bounces with Russian roulette, and the photons it
// leaves at surfaces with estimate lobes. CPU twin: src/cpu/emit_photons.rs (`trace_photon_path`).
// The including kernel defines `store_photon(vec3 x, vec3 flux, vec3 wi, vec3 side, uint flags, bool volume)` and
// declares the scene bindings; rng, sampling, shape, texture, bsdf, trace, light and shading
// come first.

void trace_photon_path(uint path, EmitParams params) {
    if (frame.light_count == 0u) return;
    uint seed = frame.seed;
    uint dim = RNG_PHOTON_DOMAIN;
    Light l = light_at(pick_light(rand1(path, params.pass, seed, dim + RNG_PHOTON_LIGHT_PICK), true));
    // A scene whose lights all give direct light only picks one with probability 0.
    if (l.photon_probability <= 0.0) return;
    vec3 o, d, flux;
    float cos_l;
    // The render's photon paths of one kind are one low-discrepancy sequence in the numbers that
    // spread photons evenly (cpu::emit_photons::photon_sequence).
    uvec2 seq = sequence_point(params.pass & 1u, params.pass >> 1u, params.total_paths, path);
    light_emit(l, qmc2(seq.x, seq.y, seed, dim + RNG_PHOTON_POSITION),
               qmc2(seq.x, seq.y, seed, dim + RNG_PHOTON_DIRECTION), o, d, flux, cos_l);
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    flux /= l.photon_probability * float(params.total_paths);
    bool specular_only = true;
    uint medium = l.medium;
    // The smooth triangle the current ray leaves, which it must not meet again (see trace_ray).
    uint skip = NO_LIGHT;
    uint depth = 0u;  // scattering events so far (surfaces and media; null boundaries are none)
    uint step = 0u;
    for (; step < params.max_depth + MEDIUM_CROSSINGS && depth < params.max_depth; step++) {
        float t;
        uint prim = trace_ray(o, d, INF, false, skip, t);
        bool scattered = false;
        vec3 collision = vec3(0.0);
        vec3 medium_weight = vec3(1.0);
#ifdef VARIANT_MEDIA
        // A free flight through the medium: a collision before the surface scatters the photon
        // (or absorbs it, by roulette on the albedo below); passing it, the flux keeps its mean.
        if (medium != NO_MEDIUM) {
            MediumEvent e = medium_sample(medium, o, d, t, rand2(path, params.pass, seed, dim + RNG_PHOTON_MEDIUM + step));
            scattered = e.scattered;
            t = e.t;
            if (scattered) {
                collision = e.collision;
                medium_weight = e.weight;
            } else {
                flux *= e.weight;
            }
        }
#endif
        if (!scattered && prim == NO_LIGHT) return;
        skip = scattered ? NO_LIGHT : ray_skip(prim);
        Hit h;
        Bsdf b;
        vec3 wo = -d;
#ifdef VARIANT_MEDIA
        if (scattered) {
            h = medium_hit(o + d * t, wo);
            b = phase_bsdf(medium, wo);
        } else
#endif
        {
            h = shape_hit(prim, o, d, t);
#ifdef VARIANT_MEDIA
            if (material_at(h.material).kind == MATERIAL_NULL) {
                // An invisible boundary: straight through into the medium beyond, not a bounce.
                medium = medium_after(prim, h.ng, d, medium);
                o = offset_origin(h, wo, BSDF_TRANSMISSION);
                continue;
            }
#endif
            b = material_bsdf(material_at(h.material), h);
        }
        uint lobes = bsdf_flags(b);
        uint bdim = dim + (depth + 1u) * RNG_DIMS_PER_BOUNCE;
        // A black surface reflects nothing but keeps its photons (see the twin).
        if (lobes == 0u || (lobes & BSDF_ESTIMATE) != 0u) {
            uint flags = depth == 0u ? PHOTON_FLAG_DIRECT : (specular_only ? PHOTON_FLAG_CAUSTIC : 0u);
            // A collision in a medium stores a volume photon carrying its sigma_t-weighted flux,
            // in the global pass only: the caustic map is of surfaces.
            if (scattered) {
                if (params.caustics_only == 0u) store_photon(h.p, flux * collision, wo, vec3(0.0), flags, true);
            } else if (params.caustics_only == 0u || flags == PHOTON_FLAG_CAUSTIC) {
                store_photon(h.p, flux, wo, facing(b, wo), flags, false);
            }
            // A caustic-only pass has no use for the path once it has met an estimate lobe.
            if (params.caustics_only != 0u || lobes == 0u) return;
        }
        BsdfSample s = bsdf_sample(b, wo, bsdf_numbers(path, params.pass, seq, seed, bdim + RNG_PHOTON_BOUNCE).xyz, LOBES_ALL);
        if (s.flags == 0u) return;
        // Russian roulette on the sample's weight (with a collision's albedo and the adjoint's
        // factor on a bumped surface): survivors keep their flux up to its colour.
        vec3 w = s.weight * medium_weight * shading_adjoint(b, wo, s.wi);
        float survive = min(max(w.r, max(w.g, w.b)), 1.0);
        if (rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive) return;
        flux *= w / survive;
        if ((s.flags & BSDF_ESTIMATE) != 0u) specular_only = false;
#ifdef VARIANT_MEDIA
        if (!scattered && (s.flags & BSDF_TRANSMISSION) != 0u) medium = medium_after(prim, h.ng, s.wi, medium);
#endif
        o = offset_origin(h, wo, s.flags);
        d = s.wi;
        depth++;
    }
    // The loop ends by its condition or by a return. Here with the condition still true, the
    // loop was broken off: lavapipe stops every loop of an invocation after 65535 iterations in
    // all, and the path's photons beyond are lost. Counted, so the host refuses the pass rather
    // than give an image darker than the CPU backend's (issue 25). The CPU twin has no such limit.
    if (step < params.max_depth + MEDIUM_CROSSINGS && depth < params.max_depth) atomicAdd(counters[3], 1u);
}
