// One photon path from the lights: emission, bounces with Russian roulette, and the photons it
// leaves at diffuse surfaces. CPU twin: src/cpu/emit_photons.rs (`trace_photon_path`).
// The including kernel defines `store_photon(vec3 x, vec3 flux, vec3 wi, uint flags)` and
// declares the scene bindings; rng.glsl, trace.glsl and shading.glsl come first.

void trace_photon_path(uint path, EmitParams params) {
    if (frame.light_count == 0u) return;
    uint seed = frame.seed;
    uint dim = RNG_PHOTON_DOMAIN;
    Light l = lights[pick_light(rand1(path, params.pass, seed, dim + RNG_PHOTON_LIGHT_PICK))];
    vec2 u_pos = rand2(path, params.pass, seed, dim + RNG_PHOTON_POSITION);
    vec2 u_dir = rand2(path, params.pass, seed, dim + RNG_PHOTON_DIRECTION);
    vec3 ln;
    vec3 o = sample_light_point(l, u_pos, ln);
    vec3 d;
    // Each path carries 1/N of the picked light's power, divided by the pick probability.
    vec3 flux;
    if (l.kind == LIGHT_POINT) {
        d = sphere_direction(u_dir);
        flux = 4.0 * PI * load3(l.radiance);
    } else {
        d = cosine_direction(ln, u_dir);
        o += ln * frame.ray_epsilon;
        flux = PI * l.area * load3(l.radiance);
    }
    flux /= l.pick_probability * float(params.total_paths);
    bool specular_only = true;
    for (uint depth = 0u; depth < params.max_depth; depth++) {
        float t;
        uint prim = trace_ray(o, d, INF, false, t);
        if (prim == NO_LIGHT) return;
        vec3 x = o + t * d;
        vec3 n = primitive_normal(prim, x);
        Material m = materials[primitives[prim].material];
        vec3 nf = dot(n, d) < 0.0 ? n : -n;
        uint bdim = dim + (depth + 1u) * RNG_DIMS_PER_BOUNCE;
        if (m.kind == MATERIAL_DIFFUSE) {
            vec3 albedo = load3(m.reflectance);
            float survive = max(albedo.r, max(albedo.g, albedo.b));
            if (survive <= 0.0) return;  // a black surface keeps nothing and reflects nothing
            uint flags = depth == 0u ? PHOTON_FLAG_DIRECT : (specular_only ? PHOTON_FLAG_CAUSTIC : 0u);
            if (params.caustics_only == 0u || flags == PHOTON_FLAG_CAUSTIC) store_photon(x, flux, -d, flags);
            // A caustic-only pass has no use for the path once it has met a diffuse surface.
            if (params.caustics_only != 0u) return;
            // Russian roulette on the albedo: survivors keep their flux up to the colour filter.
            if (rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive) return;
            flux *= albedo / survive;
            d = cosine_direction(nf, rand2(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE));
            o = x + nf * frame.ray_epsilon;
            specular_only = false;
        } else if (m.kind == MATERIAL_MIRROR) {
            vec3 tint = load3(m.reflectance);
            float survive = max(tint.r, max(tint.g, tint.b));
            if (rand1(path, params.pass, seed, bdim + RNG_PHOTON_ROULETTE) >= survive) return;
            flux *= tint / survive;
            d = reflect(d, nf);
            o = x + nf * frame.ray_epsilon;
        } else {
            bool front = dot(n, d) < 0.0;
            // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
            dielectric_scatter(x, nf, front, m.ior, rand1(path, params.pass, seed, bdim + RNG_PHOTON_BOUNCE), o, d);
        }
    }
}
