// Phase functions of media. CPU twin: src/cpu/phase.rs. Included by scene.glsl after sampling.glsl.
// Directions point away from the scattering point, as at surfaces: `wo` toward the previous
// vertex, `wi` toward the next one (or the light), so the light turns by the angle between -wi
// and wo, and cos(theta) = -dot(wo, wi) (pbrt-v4's convention).

// Henyey-Greenstein phase function of asymmetry g in (-1, 1), over the sphere (1/sr), for
// c = dot(wo, wi); g = 0 is isotropic, 1 / (4 pi).
float phase_hg(float c, float g) {
    float denom = 1.0 + g * g + 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(max(denom, 1e-12)));
}

// A direction wi drawn with pdf phase_hg(dot(wo, wi), g) exactly (the inversion of pbrt-v4's
// SampleHenyeyGreenstein); |g| below 1e-3 samples the isotropic sphere.
vec3 phase_hg_sample(vec3 wo, float g, vec2 u) {
    float c;
    if (abs(g) < 1e-3) {
        c = 1.0 - 2.0 * u.x;
    } else {
        float s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
        c = -(1.0 + g * g - s * s) / (2.0 * g);
    }
    c = clamp(c, -1.0, 1.0);
    float sine = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    onb(wo, t, b);
    return normalize(sine * cos(phi) * t + sine * sin(phi) * b + c * wo);
}
