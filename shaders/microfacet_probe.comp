#version 450
// microfacet_probe.comp: evaluates every function of microfacet.glsl on one input record per
// invocation, so that tests/microfacet_gpu.rs can compare them with the Rust twin
// (src/cpu/microfacet.rs). Test-only kernel. Bindings: 0 inputs, 1 outputs. Push constants: count.
//
// Plain float arrays (no struct layout to mirror). Input record, PROBE_IN floats:
//   0 wo[3], 3 wi[3], 6 u[3], 9 alpha[2], 11 ior, 12 eta[3], 15 k[3], 18 diffuse[3], 21 nonlinear
//   (0 or 1), 22 a plastic coat table's index in `inputs` (-1: none), 23 the distribution
//   (MICROFACET_GGX or MICROFACET_BECKMANN, as a float)
// Output record, PROBE_OUT floats (a sample is: valid, wi[3], weight[3], pdf, lobe):
//   0 mf_d(h), 1 mf_g1(wo, h), 2 mf_g1(wi, h), 3 mf_pdf_visible(wo, h), 4 mf_sample_visible[3]
//   7 fresnel_conductor(wo.z)[3]
//   10 conductor_eval[3], 13 conductor_pdf, 14 conductor_sample[9]
//   23 dielectric_eval, 24 dielectric_pdf, 25 dielectric_sample[9]
//   34 plastic_eval[3], 37 plastic_pdf, 38 plastic_sample[9]
//   47 lambert_eval[3], 50 lambert_pdf, 51 lambert_sample[9], 60 unused[4]
// h = normalize(wo + wi) turned to z >= 0; the distribution's probes (0 to 6) use
// max(alpha, 0.01), as they need alpha > 0. Every function of both distributions is compiled in.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"
const bool SCENE_HAS_BECKMANN = true;
#include "microfacet.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

const uint PROBE_IN = 24u;
const uint PROBE_OUT = 64u;

layout(std430, binding = 0) readonly buffer Inputs { float inputs[]; };
layout(std430, binding = 1) writeonly buffer Outputs { float outputs[]; };

layout(push_constant) uniform Params {
    uint count;
} params;

// The plastic's coat tables are read from the inputs themselves (the test appends them).
float mf_coat_word(uint i) { return inputs[i]; }

vec3 in3(uint base, uint at) { return vec3(inputs[base + at], inputs[base + at + 1u], inputs[base + at + 2u]); }

void out1(uint base, uint at, float v) { outputs[base + at] = v; }

void out3(uint base, uint at, vec3 v) {
    outputs[base + at] = v.x;
    outputs[base + at + 1u] = v.y;
    outputs[base + at + 2u] = v.z;
}

void out_sample(uint base, uint at, bool valid, vec3 wi, vec3 weight, float pdf, uint lobe) {
    out1(base, at, valid ? 1.0 : 0.0);
    out3(base, at + 1u, wi);
    out3(base, at + 4u, weight);
    out1(base, at + 7u, pdf);
    out1(base, at + 8u, float(lobe));
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    uint a = i * PROBE_IN;
    uint o = i * PROBE_OUT;
    vec3 wo = in3(a, 0u);
    vec3 wi = in3(a, 3u);
    vec3 u = in3(a, 6u);
    vec2 alpha = vec2(inputs[a + 9u], inputs[a + 10u]);
    float ior = inputs[a + 11u];
    vec3 eta = in3(a, 12u);
    vec3 k = in3(a, 15u);
    vec3 diffuse = in3(a, 18u);
    bool nonlinear = inputs[a + 21u] != 0.0;
    uint table = inputs[a + 22u] < 0.0 ? NO_DATA : uint(inputs[a + 22u]);
    uint dist = uint(inputs[a + 23u]);

    // The distribution
    vec2 ar = max(alpha, vec2(0.01));
    vec3 h = normalize(wo + wi);
    if (h.z < 0.0) h = -h;
    out1(o, 0u, mf_d(h, ar, dist));
    out1(o, 1u, mf_g1(wo, h, ar, dist));
    out1(o, 2u, mf_g1(wi, h, ar, dist));
    out1(o, 3u, mf_pdf_visible(wo, h, ar, dist));
    out3(o, 4u, mf_sample_visible(wo, ar, dist, u.xy));
    out3(o, 7u, fresnel_conductor(wo.z, eta, k));

    vec3 s_wi, s_weight;
    float s_pdf;
    uint s_lobe;
    bool valid;

    // Conductor
    out3(o, 10u, conductor_eval(wo, wi, alpha, dist, eta, k));
    out1(o, 13u, conductor_pdf(wo, wi, alpha, dist));
    valid = conductor_sample(wo, alpha, dist, eta, k, u.xy, s_wi, s_weight, s_pdf, s_lobe);
    out_sample(o, 14u, valid, s_wi, s_weight, s_pdf, s_lobe);

    // Dielectric
    out1(o, 23u, dielectric_eval(wo, wi, alpha, dist, ior));
    out1(o, 24u, dielectric_pdf(wo, wi, alpha, dist, ior));
    valid = dielectric_sample(wo, alpha, dist, ior, u, s_wi, s_weight, s_pdf, s_lobe);
    out_sample(o, 25u, valid, s_wi, s_weight, s_pdf, s_lobe);

    // Plastic
    out3(o, 34u, plastic_eval(wo, wi, alpha, dist, ior, diffuse, nonlinear, table));
    out1(o, 37u, plastic_pdf(wo, wi, alpha, dist, ior, diffuse));
    valid = plastic_sample(wo, alpha, dist, ior, diffuse, nonlinear, table, u, s_wi, s_weight, s_pdf, s_lobe);
    out_sample(o, 38u, valid, s_wi, s_weight, s_pdf, s_lobe);

    // Lambert
    out3(o, 47u, lambert_eval(wo, wi, diffuse));
    out1(o, 50u, lambert_pdf(wo, wi));
    valid = lambert_sample(wo, diffuse, u.xy, s_wi, s_weight, s_pdf, s_lobe);
    out_sample(o, 51u, valid, s_wi, s_weight, s_pdf, s_lobe);
    for (uint j = 60u; j < PROBE_OUT; j++) out1(o, j, 0.0);
}
