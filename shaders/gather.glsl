// Radiance estimates from the photon maps and the final gather. CPU twin: src/cpu/gather.rs.
// The including kernel declares `grids[2]` (0 global, 1 caustic), `global_photons[]`,
// `global_starts[]`, `caustic_photons[]` and `caustic_starts[]`, and includes grid.glsl and
// photon.glsl.

const uint MAP_GLOBAL = 0u;
const uint MAP_CAUSTIC = 1u;

// Field by field: a whole-struct copy out of either of two blocks makes glslang emit an OpStore
// between different struct types, which the validation layer rejects.
#define COPY_PHOTON(p, array, i) { p.position[0] = array[i].position[0]; p.position[1] = array[i].position[1]; \
    p.position[2] = array[i].position[2]; p.flux_rg = array[i].flux_rg; p.flux_b_dir = array[i].flux_b_dir; }

Photon map_photon(uint map, uint i) {
    Photon p;
    if (map == MAP_GLOBAL) COPY_PHOTON(p, global_photons, i) else COPY_PHOTON(p, caustic_photons, i)
    return p;
}
uint map_start(uint map, uint h) { return map == MAP_GLOBAL ? global_starts[h] : caustic_starts[h]; }

// Irradiance at x (normal n, facing the side photons must arrive from) from the photons of
// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
// photons that arrived from behind the surface or lie off its tangent plane.
vec3 photon_irradiance(uint map, vec3 x, vec3 n, uint exclude) {
    GridParams g = grids[map];
    if (g.photon_count == 0u) return vec3(0.0);
    float r2 = g.radius * g.radius;
    float thickness = PHOTON_DISC_THICKNESS * g.radius;
    ivec3 c = grid_cell(x, g.cell_size);
    vec3 sum = vec3(0.0);
    // Each of the 27 cells is read through its bucket; a photon of another cell that shares the
    // bucket is skipped, so no photon is counted twice and no duplicate buckets need removing.
    for (uint k = 0u; k < 27u; k++) {
        ivec3 cell = grid_neighbour(c, k);
        uint h = grid_hash(cell, g.table_mask);
        uint end = map_start(map, h + 1u);
        for (uint i = map_start(map, h); i < end; i++) {
            Photon p = map_photon(map, i);
            vec3 pos = load3(p.position);
            if (grid_cell(pos, g.cell_size) != cell) continue;
            vec3 d = pos - x;
            float d2 = dot(d, d);
            if (d2 > r2 || abs(dot(d, n)) > thickness) continue;
            if ((photon_flags(p) & exclude) != 0u || dot(photon_wi(p), n) <= 0.0) continue;
            sum += photon_flux(p, g.flux_scale) * (1.0 - d2 / r2);
        }
    }
    return sum * (2.0 / (PI * r2));
}

// Indirect radiance toward the viewer at a diffuse point x (normal n facing the viewer) of
// albedo `albedo`, read from the global map at x without the direct and caustic photons (the
// fast preview when frame.gather_rays is 0).
vec3 indirect_preview(vec3 x, vec3 n, vec3 albedo) {
    return albedo * (1.0 / PI) * photon_irradiance(MAP_GLOBAL, x, n, PHOTON_FLAG_DIRECT | PHOTON_FLAG_CAUSTIC);
}

// One final-gather ray's share of the indirect radiance at x: a cosine-distributed ray j whose
// first diffuse hit reads the global map (mirrors and glass on the way are followed), weighted
// 1/gather_rays. Emission met on the way is not counted: direct light and caustics cover it.
vec3 gather_ray(vec3 x, vec3 n, vec3 albedo, uint stream, uint sample_index, uint j, inout uint rays) {
    uint gdim = RNG_GATHER_DOMAIN + j * RNG_GATHER_DIMS_PER_RAY;
    vec3 d = cosine_direction(n, rand2(stream, sample_index, frame.seed, gdim));
    vec3 o = x + n * frame.ray_epsilon;
    vec3 throughput = vec3(1.0);
    for (uint bounce = 0u; bounce < frame.max_depth; bounce++) {
        float t;
        rays++;
        uint prim = trace_ray(o, d, INF, false, t);
        if (prim == NO_LIGHT) break;
        vec3 y = o + t * d;
        vec3 ny = primitive_normal(prim, y);
        Material m = materials[primitives[prim].material];
        bool front = dot(ny, d) < 0.0;
        vec3 nf = front ? ny : -ny;
        if (m.kind == MATERIAL_DIFFUSE) {
            // Cosine sampling cancels the cosine and the 1/pi of the BRDF at x: weight = albedo.
            vec3 radiance = load3(m.reflectance) * (1.0 / PI) * photon_irradiance(MAP_GLOBAL, y, nf, 0u);
            return albedo * throughput * radiance / float(frame.gather_rays);
        }
        if (m.kind == MATERIAL_MIRROR) {
            throughput *= load3(m.reflectance);
            d = reflect(d, nf);
            o = y + nf * frame.ray_epsilon;
            continue;
        }
        // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
        dielectric_scatter(y, nf, front, m.ior, rand1(stream, sample_index, frame.seed, gdim + 1u + bounce), o, d);
    }
    return vec3(0.0);
}

// Caustic radiance toward the viewer at x from the caustic map.
vec3 caustic_light(vec3 x, vec3 n, vec3 albedo) {
    return albedo * (1.0 / PI) * photon_irradiance(MAP_CAUSTIC, x, n, 0u);
}
