// One photon path from the lights: emission, bounces with Russian roulette, and the photons it
// leaves at surfaces with estimate lobes. CPU twin: src/cpu/emit_photons.rs (`trace_photon_path`).
// The including kernel defines `store_photon(vec3 x, vec3 flux, vec3 wi, uint flags)` and
// declares the scene bindings; rng, sampling, shape, texture, bsdf, trace, light and shading
// come first.

void trace_photon_path(uint path, EmitParams params) {
    if (frame.light_count == 0u) return;
    uint seed = frame.seed;
    uint dim = RNG_PHOTON_DOMAIN;
    Light l = lights[pick_light(rand1(path, params.pass, seed, dim + RNG_PHOTON_LIGHT_PICK), true)];
    // A scene whose lights all give direct light only picks one with probability 0.
    if (l.photon_probability <= 0.0) return;
    vec3 o, d, flux;
    light_emit(l, rand2(path, params.pass, seed, dim + RNG_PHOTON_POSITION),
               rand2(path, params.pass, seed, dim + RNG_PHOTON_DIRECTION), o, d, flux);
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    flux /= l.photon_probability * float(params.total_paths);
    bool specular_only = true;
    uint skip = NO_LIGHT;
    for (uint depth = 0u; depth < params.max_depth; depth++) {
        float t;
        uint prim = trace_ray(o, d, INF, false, skip, t);
        if (prim == NO_LIGHT) return;
        Hit h = shape_hit(prim, o, d, t);
        skip = ray_skip(prim);
        vec3 wo = -d;
        Bsdf b = material_bsdf(materials[h.material], h);
        uint lobes = bsdf_flags(b);
        if (lobes == 0u) return;  // a black surface keeps nothing and reflects nothing
        uint bdim = dim + (depth + 1u) * RNG_DIMS_PER_BOUNCE;
        if ((lobes & BSDF_ESTIMATE) != 0u) {
            uint flags = depth == 0u ? PHOTON_FLAG_DIRECT : (specular_only ? PHOTON_FLAG_CAUSTIC : 0u);
            if (params.caustics_only == 0u || flags == PHOTON_FLAG_CAUSTIC) store_photon(h.p, flux, wo, flags);
            // A caustic-only pass has no use for the path once it has met an estimate lobe.
            if (params.caustics_only != 0u) return;
        }
        BsdfSample s = bsdf_sample(b, wo, rand4(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE).xyz, LOBES_ALL);
        if (s.flags == 0u) return;
        // Russian roulette on the sample's weight: survivors keep their flux up to its colour.
        float survive = max(s.weight.r, max(s.weight.g, s.weight.b));
        if (rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive) return;
        flux *= s.weight / survive;
        if ((s.flags & BSDF_ESTIMATE) != 0u) specular_only = false;
        o = offset_origin(h, wo, s.flags);
        d = s.wi;
    }
}
