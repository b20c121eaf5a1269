// Lights behind one interface: pick by power, a point on a light, a photon leaving it.
// CPU twin: src/cpu/light.rs. The including kernel declares the scene bindings and includes
// shape.glsl and bsdf.glsl.

// Index of the light whose cdf interval holds u: lights are picked in proportion to power.
uint pick_light(float u) {
    uint lo = 0u;
    uint hi = frame.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < lights[mid].cdf) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

// A point on a light: its position, its normal (zero for a point light) and what it emits
// there: radiance toward its front side, or a point light's intensity (W/sr).
// inv_pdf: 1/pdf of the point by area (1 for a point light); eps: the offset of rays that
// start or end there.
struct LightPoint {
    vec3 p;
    vec3 n;
    vec3 emitted;
    float inv_pdf;
    float eps;
};

// A point on light l (see shape_sample for the density of area lights' points).
LightPoint light_point(Light l, vec2 u) {
    switch (l.kind) {
    case LIGHT_AREA: {
        float inv_pdf;
        Hit h = shape_sample(l.primitive, u, inv_pdf);
        return LightPoint(h.p, h.ng, material_emission(materials[h.material], h), inv_pdf, h.eps);
    }
    }
    return LightPoint(load3(l.position), vec3(0.0), load3(l.intensity), 1.0, frame.ray_epsilon);
}

// A photon leaving light l: its origin, direction and the power it carries before the division
// by the pick probability and the path count. Area lights emit from a uniform point in a
// cosine-distributed direction (Lambertian), point lights uniformly in all directions.
void light_emit(Light l, vec2 u_pos, vec2 u_dir, out vec3 o, out vec3 d, out vec3 power) {
    LightPoint s = light_point(l, u_pos);
    o = s.p;
    switch (l.kind) {
    case LIGHT_AREA:
        d = cosine_direction(s.n, u_dir);
        o += s.n * s.eps;
        power = PI * s.inv_pdf * s.emitted;
        return;
    }
    d = sphere_direction(u_dir);
    power = 4.0 * PI * s.emitted;
}
