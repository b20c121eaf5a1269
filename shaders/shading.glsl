// Camera rays, path vertices and direct light. CPU twin: src/cpu/shading.rs.
// The including kernel declares the scene bindings and includes rng, sampling, shape, texture,
// bsdf, trace and light (in that order).

// Primary ray through film position (sx, sy) in [-1, 1]^2, sy = +1 at the top row.
vec3 camera_direction(float sx, float sy) {
    return normalize(load3(frame.camera_forward) + sx * load3(frame.camera_right) + sy * load3(frame.camera_up));
}

// Origin of the ray that leaves h in a direction sampled from a lobe with `lobe_flags`: offset
// off the surface to the side the ray goes (wo's side for reflection, the other for transmission),
// by the hit's own offset.
vec3 offset_origin(Hit h, vec3 wo, uint lobe_flags) {
    vec3 nf = dot(wo, h.ng) > 0.0 ? h.ng : -h.ng;
    return (lobe_flags & BSDF_TRANSMISSION) != 0u ? h.p - nf * h.eps : h.p + nf * h.eps;
}

// A shadow ray toward a point sampled on a light, and the radiance the light reflects at the
// shading point toward wo through the estimate lobes of its BSDF if nothing blocks the ray: a
// one-sample estimate of the direct light. `t_max` is NO_RAY when no ray is needed (no light,
// or nothing to reflect).
// The length of a shadow ray that is not cast: trace_ray meets nothing before it.
const float NO_RAY = -1.0;

struct ShadowRay {
    vec3 origin;
    vec3 direction;
    float t_max;
    vec3 unoccluded;
};

ShadowRay direct_light_sample(Hit h, Bsdf b, vec3 wo, uint stream, uint sample_index, uint dim) {
    ShadowRay none = ShadowRay(h.p, vec3(0.0, 1.0, 0.0), NO_RAY, vec3(0.0));
    if (frame.light_count == 0u) return none;
    uint li = pick_light(rand1(stream, sample_index, frame.seed, dim + RNG_LIGHT_PICK));
    Light l = lights[li];
    LightPoint s = light_point(l, rand2(stream, sample_index, frame.seed, dim + RNG_LIGHT_U));
    vec3 to_light = s.p - h.p;
    float dist2 = dot(to_light, to_light);
    float dist = sqrt(dist2);
    vec3 wi = to_light / dist;
    vec3 f = bsdf_eval(b, wo, wi);
    if (f == vec3(0.0)) return none;
    // Point light: E = I cos / d^2. Area light: L cos cos' / d^2 over the point's pdf by area.
    float geometry = abs(dot(b.ns, wi)) / dist2;
    // The shadow ray stops short of the light's point by its offset over the cosine there (see
    // the twin).
    float shadow_end = s.eps;
    if (l.kind != LIGHT_POINT) {
        float cos_l = -dot(s.n, wi);
        if (cos_l <= 0.0) return none;
        geometry *= cos_l * s.inv_pdf;
        shadow_end = s.eps / max(cos_l, 1e-2);
    }
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    vec3 origin = offset_origin(h, wi, BSDF_REFLECTION);
    vec3 to_target = s.p - origin;
    float shadow_length = length(to_target);
    float t_max = max(shadow_length - shadow_end, 0.0);
    return ShadowRay(origin, to_target / shadow_length, t_max, f * s.emitted * (geometry / l.pick_probability));
}
