// Lights behind one interface: pick by power, a light sample toward a point, a photon leaving a
// light. CPU twin: src/cpu/light.rs. The including kernel declares the scene bindings and
// includes shape.glsl and bsdf.glsl.

// Index of the light whose cdf interval holds u: lights are picked in proportion to power, among
// those that cast direct light (`photons` false: `cdf`) or emit photons (`photons` true:
// `photon_cdf`). A light left out of a distribution has an empty interval and is never picked.
uint pick_light(float u, bool photons) {
    uint lo = 0u;
    uint hi = frame.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < (photons ? lights[mid].photon_cdf : lights[mid].cdf)) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

// Intensity profile of point and spot lights along unit direction w (away from the light):
// a smooth step (3t^2 - 2t^3, as pbrt-v4 and POV-Ray's cubic_spline) in cos from the outer
// cone to the inner one, times cos^exponent (POV-Ray's tightness). A point light's cone is
// the whole sphere, so its profile is 1.
float spot_falloff(Light l, vec3 w) {
    float c = dot(w, load3(l.direction));
    float t = clamp((c - l.cos_outer) * l.falloff_scale, 0.0, 1.0);
    float tight = l.exponent > 0.0 ? pow(max(c, 0.0), l.exponent) : 1.0;
    return t * t * (3.0 - 2.0 * t) * tight;
}

// Light l as seen from x: the direction wi toward it, a point p to aim the shadow ray at (beyond
// the scene for a distant light) and `weight`, the radiance arriving along -wi divided by the
// solid-angle pdf of the sample (so the direct light is f |cos| weight / pick probability).
struct LightSample {
    vec3 p;
    vec3 wi;
    vec3 weight;
};

LightSample light_sample(Light l, vec3 x, vec2 u) {
    switch (l.kind) {
    case LIGHT_AREA: {
        // Uniform by area: L cos' / d^2 times the area.
        Hit h = shape_sample(l.primitive, u);
        vec3 to_light = h.p - x;
        float dist2 = dot(to_light, to_light);
        vec3 wi = to_light / sqrt(dist2);
        float cos_l = -dot(h.ng, wi);
        vec3 weight = cos_l > 0.0 ? material_emission(materials[h.material], h) * (cos_l * l.area / dist2) : vec3(0.0);
        return LightSample(h.p, wi, weight);
    }
    case LIGHT_DISTANT: {
        // Uniform in the cone of directions; intensity holds radiance times the cone's solid angle.
        vec3 wi = -cone_direction(load3(l.direction), l.cos_outer, u);
        float beyond = length(x - load3(l.position)) + 2.0 * l.radius;
        return LightSample(x + wi * beyond, wi, load3(l.intensity));
    }
    }
    // Point and spot lights: I(w) / d^2.
    vec3 p = load3(l.position);
    vec3 to_light = p - x;
    float dist2 = dot(to_light, to_light);
    vec3 wi = to_light / sqrt(dist2);
    return LightSample(p, wi, load3(l.intensity) * (spot_falloff(l, -wi) / dist2));
}

// A photon leaving light l: its origin, direction and the power it carries before the division
// by the pick probability and the path count. Area lights emit from a uniform point in a
// cosine-distributed direction (Lambertian); point and spot lights uniformly in their cone,
// weighted by the spot's profile; distant lights from a uniform point of the disc of the
// scene's bounding sphere that faces them, uniformly in their cone of directions.
void light_emit(Light l, vec2 u_pos, vec2 u_dir, out vec3 o, out vec3 d, out vec3 power) {
    vec3 axis = load3(l.direction);
    switch (l.kind) {
    case LIGHT_AREA: {
        Hit h = shape_sample(l.primitive, u_pos);
        o = h.p + h.ng * frame.ray_epsilon;
        d = cosine_direction(h.ng, u_dir);
        power = PI * l.area * material_emission(materials[h.material], h);
        return;
    }
    case LIGHT_DISTANT: {
        vec3 t, b;
        onb(axis, t, b);
        vec2 q = disc_point(u_pos) * l.radius;
        o = load3(l.position) - axis * l.radius + q.x * t + q.y * b;
        d = cone_direction(axis, l.cos_outer, u_dir);
        // Flux through the disc: radiance times solid angle times the projected disc area.
        power = load3(l.intensity) * (PI * l.radius * l.radius * dot(d, axis));
        return;
    }
    }
    o = load3(l.position);
    d = cone_direction(axis, l.cos_outer, u_dir);
    power = load3(l.intensity) * (2.0 * PI * (1.0 - l.cos_outer) * spot_falloff(l, d));
}
