// Radiance estimates from the photon maps. CPU twin: src/cpu/gather.rs. The camera kernel reads
// them at the end of its loop (render.comp): caustics, the preview of the indirect light, and the
// global map where a final-gather path ends.
// The including kernel declares `grids[2]` (0 global, 1 caustic), `global_photons[]`,
// `global_starts[]`, `caustic_photons[]` and `caustic_starts[]`, and includes shading.glsl,
// grid.glsl and photon.glsl.

// The volume map exists in the `media` variant only (its buffers are bound, and empty, in the
// others), so scenes without media keep the two-map lookup.
Photon map_photon(uint map, uint i) {
#ifdef VARIANT_MEDIA
    if (map == MAP_VOLUME) return fetch_photon(volume_photons, i);
#endif
    return map == MAP_GLOBAL ? fetch_photon(global_photons, i) : fetch_photon(caustic_photons, i);
}
uint map_start(uint map, uint h) {
#ifdef VARIANT_MEDIA
    if (map == MAP_VOLUME) return texelFetch(volume_starts, int(h)).x;
#endif
    return map == MAP_GLOBAL ? texelFetch(global_starts, int(h)).x : texelFetch(caustic_starts, int(h)).x;
}

// A surface lookup's sums: over the disc (the estimate), over its thin core (what the estimate
// becomes where probes found an edge: photons of a surface across the edge lie in the disc but
// not in the core), and whether photons lay in reach off the disc (another surface nearby).
struct Gathered {
    vec3 disc;
    vec3 thin;
    bool off_disc;
};

Gathered gathered_scaled(Gathered g, vec3 k) {
    return Gathered(g.disc * k, g.thin * k, g.off_disc);
}

// Direction i of the probes around n, turned by `turn` (see the twin).
vec3 probe_direction(vec3 n, float turn, uint i) {
    vec3 t1, t2;
    onb(n, t1, t2);
    float phi = 2.0 * PI * (float(i) + turn) / float(EDGE_PROBES);
    return t1 * cos(phi) + t2 * sin(phi);
}

// How far the surface of primitive i (NO_LIGHT: none) reaches from x in each probe direction
// before one of its open edges, at most `reach` (see the twin).
void open_edge_reach(uint i, vec3 x, vec3 n, float reach, float turn, out float surface_reach[EDGE_PROBES]) {
    for (uint k = 0u; k < EDGE_PROBES; k++) surface_reach[k] = reach;
    if (i == NO_LIGHT) return;
    uint kind = primitive_kind(i);
    if ((kind & PRIMITIVE_KIND_MASK) != PRIMITIVE_TRIANGLE || (kind & (7u * PRIMITIVE_FLAG_OPEN_EDGE)) == 0u) return;
    Primitive p = primitive_at(i);
    vec3 v[3] = vec3[3](load3(p.p0), load3(p.p1), load3(p.p2));
    vec3 dirs[EDGE_PROBES];
    for (uint k = 0u; k < EDGE_PROBES; k++) dirs[k] = probe_direction(n, turn, k);
    for (uint e = 0u; e < 3u; e++) {
        if ((kind & (PRIMITIVE_FLAG_OPEN_EDGE << e)) == 0u) continue;
        vec3 a = v[e];
        vec3 b = v[(e + 1u) % 3u];
        vec3 c = v[(e + 2u) % 3u];
        // The edge's normal in the plane, toward the triangle's inside.
        // glam's normalize_or_zero, as the twin.
        vec3 m = cross(n, b - a);
        float rcp = 1.0 / length(m);
        m = (isinf(rcp) || isnan(rcp)) ? vec3(0.0) : m * rcp;
        if (dot(m, c - a) < 0.0) m = -m;
        float inside = max(dot(x - a, m), 0.0);
        for (uint k = 0u; k < EDGE_PROBES; k++) {
            float toward = -dot(dirs[k], m);
            if (toward > 0.0) surface_reach[k] = min(surface_reach[k], inside / toward);
        }
    }
}

// Probe ray k (0..2 EDGE_PROBES) of a lookup at x (facing normal n) whose largest radius is
// `reach`, its directions turned by `turn`: even probes leave a point just above the surface and
// meet a wall that rises from it (a concave edge); odd probes run back toward x just below the
// surface from `reach` away and meet the side of a solid whose face ends (a convex edge).
void edge_probe_ray(vec3 x, vec3 n, float reach, float turn, uint k, out vec3 o, out vec3 d) {
    vec3 dir = probe_direction(n, turn, k / 2u);
    vec3 lift = n * (PHOTON_DISC_THICKNESS * reach);
    if ((k % 2u) == 0u) {
        o = x + lift;
        d = dir;
    } else {
        o = x + dir * reach - lift;
        d = -dir;
    }
}

// The share of a disc of radius r that the surface covers, as the probes found it (see the twin).
float edge_mass(float surface_reach[EDGE_PROBES], float r) {
    float mass = 0.0;
    for (uint i = 0u; i < EDGE_PROBES; i++) {
        float s2 = (min(surface_reach[i], r) / r) * (min(surface_reach[i], r) / r);
        mass += 2.0 * s2 - s2 * s2;
    }
    return mass / float(EDGE_PROBES);
}

// Irradiance at x (normal n, facing the side photons must arrive from) from the photons of
// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
// photons that arrived from behind the surface, landed on its other side or lie off its tangent
// plane.
Gathered photon_irradiance(uint map, vec3 x, vec3 n, uint exclude) {
    GridParams g = grids[map];
    Gathered found = Gathered(vec3(0.0), vec3(0.0), false);
    if (g.photon_count == 0u) return found;
    float r2 = g.radius * g.radius;
    float thickness = PHOTON_DISC_THICKNESS * g.radius;
    float thin = PHOTON_EDGE_THICKNESS * g.radius;
    ivec3 c = grid_cell(x, g.cell_size);
    vec3 lower, upper;
    grid_face_gaps(x, g.cell_size, lower, upper);
    // Each of the 27 cells in reach is read through its bucket; a photon of another cell that
    // shares the bucket is skipped, so no photon is counted twice and no duplicate buckets need
    // removing.
    for (uint k = 0u; k < 27u; k++) {
        if (!grid_neighbour_in_reach(lower, upper, r2, k)) continue;
        ivec3 cell = grid_neighbour(c, k);
        uint h = grid_hash(cell, g.table_mask);
        uint end = map_start(map, h + 1u);
        for (uint i = map_start(map, h); i < end; i++) {
            Photon p = map_photon(map, i);
            vec3 pos = load3(p.position);
            if (grid_cell(pos, g.cell_size) != cell) continue;
            vec3 d = pos - x;
            float d2 = dot(d, d);
            if (d2 > r2 || (photon_flags(p) & exclude) != 0u) continue;
            float off = abs(dot(d, n));
            if (off > thickness) {
                found.off_disc = true;
                continue;
            }
            if (dot(photon_wi(p), n) <= 0.0 || !photon_on_side(photon_side(p), n)) continue;
            vec3 c = photon_flux(p, g.flux_scale) * (1.0 - d2 / r2);
            found.disc += c;
            if (off <= thin) found.thin += c;
        }
    }
    return gathered_scaled(found, vec3(2.0 / (PI * r2)));
}

// Radiance toward wo at h through the estimate lobes of b, from the photons of `map` (those
// with flags in `exclude` skipped): each photon weighted by the BSDF's value for its direction.
// The volume map is read over the ball with the 3D Epanechnikov kernel (see the twin).
Gathered photon_radiance(uint map, Hit h, Bsdf b, vec3 wo, uint exclude) {
    bool volume = map == MAP_VOLUME;
    vec3 nf = facing(b, wo);
    // A Lambertian BSDF has one value for every photon: sum the irradiance, apply it once.
    if (!volume && bsdf_estimate_is_constant(b)) return gathered_scaled(photon_irradiance(map, h.p, nf, exclude), bsdf_eval(b, wo, nf));
    GridParams g = grids[map];
    Gathered found = Gathered(vec3(0.0), vec3(0.0), false);
    if (g.photon_count == 0u) return found;
    float r2 = g.radius * g.radius;
    float thickness = volume ? INF : PHOTON_DISC_THICKNESS * g.radius;
    float thin = volume ? INF : PHOTON_EDGE_THICKNESS * g.radius;
    // Photons arriving from behind count only where the BSDF transmits.
    bool both_sides = volume || (bsdf_flags(b) & BSDF_TRANSMISSION) != 0u;
    ivec3 c = grid_cell(h.p, g.cell_size);
    vec3 lower, upper;
    grid_face_gaps(h.p, g.cell_size, lower, upper);
    for (uint k = 0u; k < 27u; k++) {
        if (!grid_neighbour_in_reach(lower, upper, r2, k)) continue;
        ivec3 cell = grid_neighbour(c, k);
        uint bucket = grid_hash(cell, g.table_mask);
        uint end = map_start(map, bucket + 1u);
        for (uint i = map_start(map, bucket); i < end; i++) {
            Photon p = map_photon(map, i);
            vec3 pos = load3(p.position);
            if (grid_cell(pos, g.cell_size) != cell) continue;
            vec3 d = pos - h.p;
            float d2 = dot(d, d);
            if (d2 > r2 || (photon_flags(p) & exclude) != 0u) continue;
            float off = abs(dot(d, nf));
            if (off > thickness) {
                found.off_disc = true;
                continue;
            }
            vec3 wi = photon_wi(p);
            if (!both_sides && (dot(wi, nf) <= 0.0 || !photon_on_side(photon_side(p), nf))) continue;
            vec3 c = bsdf_eval(b, wo, wi) * photon_flux(p, g.flux_scale) * (1.0 - d2 / r2);
            found.disc += c;
            if (off <= thin) found.thin += c;
        }
    }
    return gathered_scaled(found, vec3(volume ? 15.0 / (8.0 * PI * r2 * g.radius) : 2.0 / (PI * r2)));
}
