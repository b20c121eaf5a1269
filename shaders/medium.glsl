// Participating media: free-flight sampling, transmittance, the phase function as a Bsdf, and
// which medium a ray is in after crossing a surface. CPU twin: src/cpu/medium.rs.
// The including kernel declares the scene bindings (media[]) and includes sampling, phase,
// shape and bsdf.

// What happened on a ray segment of length t_seg inside a medium (see medium_sample).
struct MediumEvent {
    bool scattered;  // a collision before the segment's end, at distance t
    float t;
    vec3 weight;     // what the path's throughput is multiplied by
    vec3 collision;  // a scattering event: sigma_t T / pdf (the photon stored there carries it)
    vec3 emission;   // a scattering event: the medium's emission T / pdf (a collision estimate)
};

vec3 medium_sigma_t(Medium m) { return load3(m.sigma_a) + load3(m.sigma_s); }

// Beer-Lambert transmittance exp(-sigma_t t) per channel; a channel with sigma_t = 0 is 1 even
// over an infinite distance.
vec3 medium_beer_lambert(vec3 st, float t) {
    return vec3(st.r > 0.0 ? exp(-st.r * t) : 1.0, st.g > 0.0 ? exp(-st.g * t) : 1.0, st.b > 0.0 ? exp(-st.b * t) : 1.0);
}

// The scattering point at p seen from wo as a hit record: no surface, no offset.
Hit medium_hit(vec3 p, vec3 wo) {
    Hit h;
    h.p = p;
    h.ng = wo;
    h.ns = wo;
    h.uv = vec2(0.0);
    h.dpdu = vec3(0.0);
    h.dpdv = vec3(0.0);
    h.prim = NO_LIGHT;
    h.material = NO_LIGHT;
    h.eps = 0.0;
    h.shift = vec3(0.0);
    return h;
}

// ---- Heterogeneous media: density, delta and ratio tracking (contracts in the twin) ----------

float medium_density(uint medium, vec3 p) {
    Medium m = medium_at(medium);
    if (m.density == NO_TEXTURE) return 1.0;
    vec3 lo = load3(m.bounds_min);
    vec3 hi = load3(m.bounds_max);
    if (any(lessThan(p, lo)) || any(greaterThan(p, hi))) return 0.0;
    return max(texture_eval(m.density, medium_hit(p, vec3(0.0, 0.0, 1.0))).x, 0.0);
}

vec3 medium_sigma_t_at(uint medium, vec3 p) { return medium_sigma_t(medium_at(medium)) * medium_density(medium, p); }

vec2 medium_box_span(Medium m, vec3 o, vec3 d, float t_seg) {
    float t0 = 0.0;
    float t1 = t_seg;
    for (uint a = 0u; a < 3u; a++) {
        float lo = m.bounds_min[a] - o[a];
        float hi = m.bounds_max[a] - o[a];
        if (d[a] == 0.0) {
            if (lo > 0.0 || hi < 0.0) t1 = -1.0;
        } else {
            float ta = lo / d[a];
            float tb = hi / d[a];
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    return vec2(t0, t1);
}

uvec2 medium_walk_key(vec2 u) { return uvec2(u * 16777216.0); }

float medium_walk_rand(uvec2 key, uint i) { return rand_unit(pcg4d(uvec4(key, i, MEDIUM_WALK_SALT)).x); }

vec3 medium_ratio_tracking(uint medium, vec3 o, vec3 d, float t_seg, vec2 u) {
    Medium m = medium_at(medium);
    vec3 st = medium_sigma_t(m);
    vec2 span = medium_box_span(m, o, d, t_seg);
    vec3 tr = vec3(1.0);
    if (!(span.x < span.y) || !(m.majorant > 0.0)) return tr;
    uvec2 key = medium_walk_key(u);
    float s = span.x;
    for (uint i = 0u; i < MEDIUM_TRACKING_STEPS; i++) {
        s -= log(1.0 - medium_walk_rand(key, 2u * i)) / m.majorant;
        if (!(s < span.y)) break;
        tr *= max(vec3(1.0) - st * (medium_density(medium, o + d * s) / m.majorant), vec3(0.0));
        float top = max(tr.r, max(tr.g, tr.b));
        if (top < MEDIUM_ROULETTE) {
            float q = top / MEDIUM_ROULETTE;
            if (!(medium_walk_rand(key, 2u * i + 1u) < q)) return vec3(0.0);
            tr /= q;
        }
    }
    return tr;
}

MediumEvent medium_delta_tracking(uint medium, vec3 o, vec3 d, float t_seg, vec2 u) {
    Medium m = medium_at(medium);
    vec3 ss = load3(m.sigma_s);
    vec3 st = medium_sigma_t(m);
    float mu = m.majorant;
    MediumEvent e;
    e.scattered = false;
    e.t = t_seg;
    e.weight = vec3(1.0);
    e.collision = vec3(0.0);
    e.emission = vec3(0.0);
    vec2 span = medium_box_span(m, o, d, t_seg);
    if (!(span.x < span.y) || !(mu > 0.0)) return e;
    uvec2 key = medium_walk_key(u);
    vec3 w = vec3(1.0);
    float s = span.x;
    for (uint i = 0u; i < MEDIUM_TRACKING_STEPS; i++) {
        s -= log(1.0 - medium_walk_rand(key, 2u * i)) / mu;
        if (!(s < span.y)) break;
        float rho = medium_density(medium, o + d * s);
        vec3 stx = st * rho;
        float wsum = w.r + w.g + w.b;
        if (!(wsum > 0.0)) break;
        float pr = dot(w, stx) / (mu * wsum);
        if (medium_walk_rand(key, 2u * i + 1u) < pr) {
            float over = 1.0 / (mu * pr);
            e.scattered = true;
            e.t = s;
            e.weight = w * ss * (rho * over);
            e.collision = w * stx * over;
            e.emission = w * load3(m.emission) * (rho * over);
            return e;
        }
        w *= max(vec3(mu) - stx, vec3(0.0)) / (mu * (1.0 - pr));
    }
    e.weight = w;
    return e;
}

// Transmittance along o + t d, t in [0, t), of the medium (contract: the twin's
// medium_transmittance). u seeds a heterogeneous medium's ratio tracking.
vec3 medium_transmittance(uint medium, vec3 o, vec3 d, float t, vec2 u) {
    if (medium_at(medium).density != NO_TEXTURE) return medium_ratio_tracking(medium, o, d, t, u);
    return medium_beer_lambert(medium_sigma_t(medium_at(medium)), t);
}

// Free-flight sampling over a segment of length t_seg (infinite for a ray that leaves the
// scene). Homogeneous media: u.x picks a channel, u.y a distance exp(sigma_t of that channel).
// The pdf is the mean of the three channels' (the one-sample spectral MIS of pbrt-v4), so
// chromatic media stay unbiased; grey media get weights of exactly the albedo (scattering) and
// 1 (passing). Heterogeneous media: delta tracking seeded by u (see the twin).
MediumEvent medium_sample(uint medium, vec3 o, vec3 d, float t_seg, vec2 u) {
    Medium m = medium_at(medium);
    if (m.density != NO_TEXTURE) return medium_delta_tracking(medium, o, d, t_seg, u);
    vec3 sa = load3(m.sigma_a);
    vec3 ss = load3(m.sigma_s);
    vec3 st = sa + ss;
    float sc = u.x < 1.0 / 3.0 ? st.r : (u.x < 2.0 / 3.0 ? st.g : st.b);
    float t = sc > 0.0 ? -log(1.0 - u.y) / sc : INF;
    MediumEvent e;
    e.collision = vec3(0.0);
    e.emission = vec3(0.0);
    if (t < t_seg) {
        vec3 tr = exp(-st * t);
        float pdf = dot(st * tr, vec3(1.0 / 3.0));
        e.scattered = true;
        e.t = t;
        e.weight = pdf > 0.0 ? ss * tr / pdf : vec3(0.0);
        e.collision = pdf > 0.0 ? st * tr / pdf : vec3(0.0);
        e.emission = pdf > 0.0 ? load3(m.emission) * tr / pdf : vec3(0.0);
        return e;
    }
    vec3 tr = medium_beer_lambert(st, t_seg);
    float p = dot(tr, vec3(1.0 / 3.0));
    e.scattered = false;
    e.t = t_seg;
    e.weight = p > 0.0 ? tr / p : vec3(0.0);
    return e;
}

// The medium's phase function as a Bsdf (MATERIAL_PHASE, see bsdf.glsl); color1.y is 1 where
// the scattering point samples point and spot lights itself (heterogeneous media, which have no
// equiangular shafts).
Bsdf phase_bsdf(uint medium, vec3 wo) {
    Medium m = medium_at(medium);
    Bsdf b;
    b.kind = MATERIAL_PHASE;
    b.flags = 0u;
    b.data = NO_DATA;
    b.color0 = vec3(1.0);
    b.color1 = vec3(float(m.phase), m.density != NO_TEXTURE ? 1.0 : 0.0, 0.0);
    b.color2 = vec3(1.0);
    b.alpha = vec2(0.0);
    b.ior = m.g;
    b.ng = wo;
    b.ns = wo;
    b.ts = vec3(0.0);
    b.glossy_path = false;
    return b;
}

// The medium a ray is in after it crossed primitive `prim` (geometric normal ng) going along d:
// a medium boundary's interior when it went against the outward normal, its exterior when it
// went along it; any other surface leaves the medium as it was.
uint medium_after(uint prim, vec3 ng, vec3 d, uint medium) {
    Primitive p = primitive_at(hit_primitive(prim));
    if ((p.kind & PRIMITIVE_FLAG_MEDIUM) == 0u) return medium;
    return dot(d, ng) < 0.0 ? p.interior : p.exterior;
}

// The part [t0, t1) of o + t d, t in [0, t_max), inside the cone of a spot light (apex c, unit
// axis a, cos of the half-angle cos_outer), a little widened; contract: the twin's spot_span.
vec2 spot_span(vec3 o, vec3 d, float t_max, vec3 c, vec3 a, float cos_outer) {
    if (!(cos_outer > SPOT_SPAN_MARGIN)) return vec2(0.0, t_max);
    float k = cos_outer - SPOT_SPAN_MARGIN;
    float k2 = k * k;
    vec3 v = o - c;
    float da = dot(d, a);
    float va = dot(v, a);
    float A = da * da - k2;
    float B = da * va - k2 * dot(d, v);
    float C = va * va - k2 * dot(v, v);
    float lo = 0.0;
    float hi = t_max;
    if (da > 0.0) lo = max(lo, -va / da);
    else if (da < 0.0) hi = min(hi, -va / da);
    else if (va < 0.0) return vec2(0.0, -1.0);
    float disc = B * B - A * C;
    if (abs(A) < 1e-12) {
        if (B > 0.0) lo = max(lo, -C / (2.0 * B));
        else if (B < 0.0) hi = min(hi, -C / (2.0 * B));
        else if (C < 0.0) return vec2(0.0, -1.0);
        return vec2(lo, hi);
    }
    if (disc < 0.0) return A > 0.0 ? vec2(lo, hi) : vec2(0.0, -1.0);
    float q = sqrt(disc);
    float r1 = (-B - q) / A;
    float r2 = (-B + q) / A;
    float ra = min(r1, r2);
    float rb = max(r1, r2);
    if (A < 0.0) return vec2(max(lo, ra), min(hi, rb));
    bool first = lo < min(hi, ra);
    bool second = max(lo, rb) < hi;
    if (first && second) return vec2(lo, hi);
    if (first) return vec2(lo, min(hi, ra));
    if (second) return vec2(max(lo, rb), hi);
    return vec2(0.0, -1.0);
}

// Equiangular sampling (Kulla and Fajardo 2012) of a distance t in [0, t_end) along o + t d
// toward the point c: uniform in the angle under which c sees the ray, so the samples crowd
// where the ray passes the light (pdf = D / ((theta_b - theta_a) (D^2 + (t - delta)^2))).
// t_end may be infinite.
float equiangular_sample(vec3 o, vec3 d, float t_end, vec3 c, float u, out float pdf) {
    float delta = dot(c - o, d);
    float dist = max(length(c - o - delta * d), 1e-7 * (abs(delta) + 1.0));
    float a = atan(-delta, dist);
    float b = t_end == INF ? 0.5 * PI : atan(t_end - delta, dist);
    float t = clamp(delta + dist * tan(mix(a, b, u)), 0.0, t_end);
    float e = t - delta;
    pdf = b > a ? dist / ((b - a) * (dist * dist + e * e)) : 0.0;
    return t;
}
