// Microfacet BSDFs as pure functions: GGX and Beckmann distributions with visible-normal
// sampling, rough conductor, rough dielectric, plastic (diffuse base under a dielectric coat) and
// Lambert. CPU twin: src/cpu/microfacet.rs, which states the contracts; this file only points to
// them.
//
// Everything works in a local shading frame: z is the surface normal (the front side), and both
// directions point AWAY from the surface: `wo` toward the previous vertex (the viewer), `wi`
// toward the next one (the light, or the sampled direction). `alpha` = (alpha_x, alpha_y) are the
// microfacet widths themselves, not a roughness to square, of the distribution `dist`
// (MICROFACET_GGX or MICROFACET_BECKMANN). eval returns f without the cosine; pdf is per unit
// solid angle of wi. A sampler returns false (and zeros) when it fails; otherwise wi, weight =
// f |wi.z| / pdf, pdf (0 for a delta lobe) and the lobe (MF_REFLECTION or MF_TRANSMISSION).
// Nothing here reads a buffer or a global, and every private name starts with mf_ or MF_, so any
// kernel can include this file; the kernel defines the constant SCENE_HAS_BECKMANN (false compiles
// the Beckmann code out) and, for plastics, mf_coat_word.

const float MF_PI = 3.14159265358979;
const uint MF_REFLECTION = 0u;
const uint MF_TRANSMISSION = 1u;

// ---------------------------------------------------------------------------------------------
// Helpers

// pbrt-v4 (TrowbridgeReitzDistribution): below 1e-3 a lobe is a delta; a rough one has both
// widths at least 1e-4, so that D stays finite in float.
bool mf_is_smooth(vec2 alpha) { return max(alpha.x, alpha.y) < 1e-3; }
vec2 mf_rough_alpha(vec2 alpha) { return max(alpha, vec2(1e-4)); }

// Unpolarised Fresnel reflectance from index eta_i into eta_t at cos_i >= 0; 1 under total
// internal reflection. Sets cos_t. The smooth dielectric of bsdf.glsl uses it too.
float mf_fresnel_dielectric(float cos_i, float eta_i, float eta_t, out float cos_t) {
    float eta = eta_i / eta_t;
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) { cos_t = 0.0; return 1.0; }
    cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Exact unpolarised reflectance of a conductor eta + i k, one channel (Mitsuba 3 fresnel.h).
float mf_fresnel_conductor1(float c, float eta, float k) {
    c = clamp(abs(c), 0.0, 1.0);
    float c2 = c * c;
    float s2 = 1.0 - c2;
    float t0 = eta * eta - k * k - s2;
    float a2pb2 = sqrt(t0 * t0 + 4.0 * eta * eta * k * k);
    float a = sqrt(max(0.0, 0.5 * (a2pb2 + t0)));
    float t1 = a2pb2 + c2;
    float t2 = 2.0 * c * a;
    float rs = (t1 - t2) / (t1 + t2);
    float t3 = c2 * a2pb2 + s2 * s2;
    float t4 = t2 * s2;
    float rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5 * (rs + rp);
}

// Hemispherical-cosine average of mf_fresnel_dielectric(c, 1, n) for n > 1, in closed form
// (see the twin for its accuracy, and for the chord used below n = 1.05).
float mf_fresnel_diffuse_closed(float n) {
    float n2 = n * n;
    float n4 = n2 * n2;
    float a = n2 + 1.0;
    float b = n4 - 1.0;
    return 0.5 + (n - 1.0) * (3.0 * n + 1.0) / (6.0 * (n + 1.0) * (n + 1.0))
        + n2 * (n2 - 1.0) * (n2 - 1.0) / (a * a * a) * log((n - 1.0) / (n + 1.0))
        - 2.0 * n * n2 * (n2 + 2.0 * n - 1.0) / (a * b)
        + 8.0 * n4 * (n4 + 1.0) / (a * b * b) * log(n);
}

float mf_fresnel_diffuse(float n) {
    if (n < 1.05) return max(n - 1.0, 0.0) * 20.0 * mf_fresnel_diffuse_closed(1.05);
    return mf_fresnel_diffuse_closed(n);
}

vec3 mf_mirror(vec3 w) { return vec3(-w.x, -w.y, w.z); }

// Cosine-distributed direction about +z (Malley's method).
vec3 mf_cosine_direction(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * MF_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// Probability with which plastic_sample picks the coat: its Fresnel reflectance at wo against
// the base's mean albedo times the coat's transmittance.
float mf_plastic_coat_probability(vec3 wo, float ior, vec3 diffuse) {
    float cos_t;
    float f = mf_fresnel_dielectric(wo.z, 1.0, ior, cos_t);
    float d = (1.0 - f) * (diffuse.x + diffuse.y + diffuse.z) / 3.0;
    return d > 0.0 ? f / (f + d) : 1.0;
}

// ---------------------------------------------------------------------------------------------
// GGX (Trowbridge-Reitz) distribution

float ggx_d(vec3 m, vec2 alpha) {
    if (m.z <= 0.0) return 0.0;
    float x = m.x / alpha.x;
    float y = m.y / alpha.y;
    float t = x * x + y * y + m.z * m.z;
    return 1.0 / (MF_PI * alpha.x * alpha.y * t * t);
}

float ggx_g1(vec3 v, vec3 m, vec2 alpha) {
    if (dot(v, m) * v.z <= 0.0) return 0.0;
    float a2tan2 = (alpha.x * alpha.x * v.x * v.x + alpha.y * alpha.y * v.y * v.y) / (v.z * v.z);
    return 2.0 / (1.0 + sqrt(1.0 + a2tan2));
}

vec3 ggx_sample_visible(vec3 wo, vec2 alpha, vec2 u) {
    // Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)), listing 1.
    vec3 v = wo.z < 0.0 ? -wo : wo;
    vec3 vh = normalize(vec3(alpha.x * v.x, alpha.y * v.y, v.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) / sqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * MF_PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha.x * nh.x, alpha.y * nh.y, max(0.0, nh.z)));
}

float ggx_pdf_visible(vec3 wo, vec3 m, vec2 alpha) {
    if (wo.z == 0.0) return 0.0;
    return ggx_g1(wo, m, alpha) * abs(dot(wo, m)) * ggx_d(m, alpha) / abs(wo.z);
}

// ---------------------------------------------------------------------------------------------
// Beckmann distribution (Mitsuba 3.9.1's microfacet.h); see the twin for the contracts

const float MF_INV_SQRT_PI = 0.5641896;

// erfc(x) / exp(-x^2) for x >= 0, after Abramowitz and Stegun 7.1.26.
float mf_erfc_scaled(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    return ((((1.0614054 * t - 1.453152) * t + 1.4214138) * t - 0.28449674) * t + 0.2548296) * t;
}

float mf_erf(float x) {
    float y = 1.0 - mf_erfc_scaled(abs(x)) * exp(-x * x);
    return x < 0.0 ? -y : y;
}

// Giles 2010, single precision.
float mf_erfinv(float x) {
    x = clamp(x, -0.9999999, 0.9999999);
    float w = -log((1.0 - x) * (1.0 + x));
    float p;
    if (w < 5.0) {
        w = w - 2.5;
        p = 2.8102264e-8;
        p = 3.4327394e-7 + p * w;
        p = -3.5233877e-6 + p * w;
        p = -4.3915065e-6 + p * w;
        p = 2.1858087e-4 + p * w;
        p = -1.253725e-3 + p * w;
        p = -4.1776816e-3 + p * w;
        p = 0.24664073 + p * w;
        p = 1.5014094 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -2.0021426e-4;
        p = 1.0095056e-4 + p * w;
        p = 1.3493432e-3 + p * w;
        p = -3.6734284e-3 + p * w;
        p = 5.7395077e-3 + p * w;
        p = -7.6224613e-3 + p * w;
        p = 9.4388705e-3 + p * w;
        p = 1.0016741 + p * w;
        p = 2.8329768 + p * w;
    }
    return p * x;
}

float beckmann_d(vec3 m, vec2 alpha) {
    if (m.z <= 0.0) return 0.0;
    float c2 = m.z * m.z;
    float x = m.x / alpha.x;
    float y = m.y / alpha.y;
    float den = MF_PI * alpha.x * alpha.y * c2 * c2;
    if (den <= 0.0) return 0.0;
    float d = exp(-(x * x + y * y) / c2) / den;
    return d * m.z > 1e-20 ? d : 0.0;
}

float beckmann_g1(vec3 v, vec3 m, vec2 alpha) {
    if (dot(v, m) * v.z <= 0.0) return 0.0;
    float xy = alpha.x * alpha.x * v.x * v.x + alpha.y * alpha.y * v.y * v.y;
    if (xy == 0.0) return 1.0;
    float a = abs(v.z) / sqrt(xy);
    // Exact (not Mitsuba's rational fit: see the twin).
    float lambda = 0.5 * exp(-a * a) * (MF_INV_SQRT_PI / a - mf_erfc_scaled(a));
    return 1.0 / (1.0 + max(lambda, 0.0));
}

vec2 mf_beckmann_sample_11(float cos_theta, vec2 u) {
    u = clamp(u, vec2(1e-6), vec2(1.0 - 1e-6));
    float tan_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta)) / max(cos_theta, 1e-7);
    float cot_theta = 1.0 / max(tan_theta, 1e-7);
    float maxval = mf_erf(cot_theta);
    float x = maxval - (maxval + 1.0) * mf_erf(sqrt(-log(u.x)));
    float target = u.x * (1.0 + maxval + MF_INV_SQRT_PI * tan_theta * exp(-cot_theta * cot_theta));
    for (uint i = 0u; i < 3u; i++) {
        float slope = mf_erfinv(x);
        float value = 1.0 + x + MF_INV_SQRT_PI * tan_theta * exp(-slope * slope) - target;
        float derivative = 1.0 - slope * tan_theta;
        x -= value / derivative;
    }
    return vec2(mf_erfinv(x), mf_erfinv(2.0 * u.y - 1.0));
}

vec3 beckmann_sample_visible(vec3 wo, vec2 alpha, vec2 u) {
    vec3 v = wo.z < 0.0 ? -wo : wo;
    vec3 vs = normalize(vec3(alpha.x * v.x, alpha.y * v.y, v.z));
    float sin2 = vs.x * vs.x + vs.y * vs.y;
    float sin_phi = sin2 > 0.0 ? vs.y / sqrt(sin2) : 0.0;
    float cos_phi = sin2 > 0.0 ? vs.x / sqrt(sin2) : 1.0;
    vec2 s = mf_beckmann_sample_11(vs.z, u);
    float sx = (cos_phi * s.x - sin_phi * s.y) * alpha.x;
    float sy = (sin_phi * s.x + cos_phi * s.y) * alpha.y;
    return normalize(vec3(-sx, -sy, 1.0));
}

float beckmann_pdf_visible(vec3 wo, vec3 m, vec2 alpha) {
    if (wo.z == 0.0) return 0.0;
    return beckmann_g1(wo, m, alpha) * abs(dot(wo, m)) * beckmann_d(m, alpha) / abs(wo.z);
}

// ---------------------------------------------------------------------------------------------
// The distribution of a material (dist: MICROFACET_GGX or MICROFACET_BECKMANN). The Beckmann
// branches compile only where SCENE_HAS_BECKMANN, which the including kernel defines (a
// specialization constant in the scene kernels: scenes without Beckmann build GGX alone).

float mf_d(vec3 m, vec2 alpha, uint dist) {
    if (SCENE_HAS_BECKMANN && dist == MICROFACET_BECKMANN) return beckmann_d(m, alpha);
    return ggx_d(m, alpha);
}

float mf_g1(vec3 v, vec3 m, vec2 alpha, uint dist) {
    if (SCENE_HAS_BECKMANN && dist == MICROFACET_BECKMANN) return beckmann_g1(v, m, alpha);
    return ggx_g1(v, m, alpha);
}

vec3 mf_sample_visible(vec3 wo, vec2 alpha, uint dist, vec2 u) {
    if (SCENE_HAS_BECKMANN && dist == MICROFACET_BECKMANN) return beckmann_sample_visible(wo, alpha, u);
    return ggx_sample_visible(wo, alpha, u);
}

float mf_pdf_visible(vec3 wo, vec3 m, vec2 alpha, uint dist) {
    if (SCENE_HAS_BECKMANN && dist == MICROFACET_BECKMANN) return beckmann_pdf_visible(wo, m, alpha);
    return ggx_pdf_visible(wo, m, alpha);
}

// ---------------------------------------------------------------------------------------------
// Rough conductor

vec3 fresnel_conductor(float cos_theta, vec3 eta, vec3 k) {
    return vec3(mf_fresnel_conductor1(cos_theta, eta.x, k.x), mf_fresnel_conductor1(cos_theta, eta.y, k.y),
                mf_fresnel_conductor1(cos_theta, eta.z, k.z));
}

vec3 conductor_eval(vec3 wo, vec3 wi, vec2 alpha, uint dist, vec3 eta, vec3 k) {
    if (wo.z <= 0.0 || wi.z <= 0.0 || mf_is_smooth(alpha)) return vec3(0.0);
    alpha = mf_rough_alpha(alpha);
    vec3 h = normalize(wo + wi);
    float dg = mf_d(h, alpha, dist) * mf_g1(wo, h, alpha, dist) * mf_g1(wi, h, alpha, dist);
    return fresnel_conductor(dot(wo, h), eta, k) * (dg / (4.0 * wo.z * wi.z));
}

float conductor_pdf(vec3 wo, vec3 wi, vec2 alpha, uint dist) {
    if (wo.z <= 0.0 || wi.z <= 0.0 || mf_is_smooth(alpha)) return 0.0;
    alpha = mf_rough_alpha(alpha);
    vec3 h = normalize(wo + wi);
    float pdf_m = mf_pdf_visible(wo, h, alpha, dist);
    return pdf_m > 0.0 ? pdf_m / (4.0 * dot(wo, h)) : 0.0;
}

bool conductor_sample(vec3 wo, vec2 alpha, uint dist, vec3 eta, vec3 k, vec2 u, out vec3 wi, out vec3 weight, out float pdf,
                      out uint lobe) {
    wi = vec3(0.0); weight = vec3(0.0); pdf = 0.0; lobe = MF_REFLECTION;
    if (wo.z <= 0.0) return false;
    if (mf_is_smooth(alpha)) {
        wi = mf_mirror(wo);
        weight = fresnel_conductor(wo.z, eta, k);
        return true;
    }
    alpha = mf_rough_alpha(alpha);
    vec3 m = mf_sample_visible(wo, alpha, dist, u);
    float dot_o = dot(wo, m);
    vec3 w = 2.0 * dot_o * m - wo;
    if (dot_o <= 0.0 || w.z <= 0.0) return false;
    float p = mf_pdf_visible(wo, m, alpha, dist) / (4.0 * dot_o);
    if (!(p > 0.0)) return false;
    // f |cos| / pdf = F D G1(wo) G1(wi) / (4 wo.z) / (G1(wo) D / (4 wo.z)) = F G1(wi).
    wi = w;
    weight = fresnel_conductor(dot_o, eta, k) * mf_g1(w, m, alpha, dist);
    pdf = p;
    return true;
}

// ---------------------------------------------------------------------------------------------
// Rough dielectric (Walter et al. 2007), radiance form: see dielectric_eval in the twin

// The generalised half vector of the pair (wo, wi) at a dielectric of index `ior` (Walter et al.
// 2007), turned to face +z, with the indices of wo's side and the other (eta = eta_t / eta_o) and
// the cosines of wo and wi to it; valid is false where it is undefined (either direction in the
// surface's plane, or wo + eta wi = 0). CPU twin: dielectric_pair.
struct DielectricPair {
    vec3 h;
    float eta_o;
    float eta_t;
    float eta;
    float dot_o;
    float dot_i;
    bool reflection;
    bool valid;
};

DielectricPair dielectric_pair(vec3 wo, vec3 wi, float ior) {
    DielectricPair p;
    p.valid = wo.z != 0.0 && wi.z != 0.0;
    p.eta_o = wo.z > 0.0 ? 1.0 : ior;
    p.eta_t = wo.z > 0.0 ? ior : 1.0;
    p.eta = p.eta_t / p.eta_o;
    p.reflection = wo.z * wi.z > 0.0;
    vec3 h = p.reflection ? wo + wi : wo + p.eta * wi;
    float len2 = dot(h, h);
    p.valid = p.valid && len2 != 0.0;
    h = len2 != 0.0 ? h / sqrt(len2) : vec3(0.0, 0.0, 1.0);
    p.h = h.z < 0.0 ? -h : h;
    p.dot_o = dot(wo, p.h);
    p.dot_i = dot(wi, p.h);
    return p;
}

float dielectric_eval(vec3 wo, vec3 wi, vec2 alpha, uint dist, float ior) {
    if (mf_is_smooth(alpha)) return 0.0;
    DielectricPair p = dielectric_pair(wo, wi, ior);
    if (!p.valid) return 0.0;
    alpha = mf_rough_alpha(alpha);
    float dg = mf_d(p.h, alpha, dist) * mf_g1(wo, p.h, alpha, dist) * mf_g1(wi, p.h, alpha, dist);
    if (dg == 0.0) return 0.0;
    float cos_t;
    float f = mf_fresnel_dielectric(abs(p.dot_o), p.eta_o, p.eta_t, cos_t);
    float cos_oi = abs(wo.z * wi.z);
    if (p.reflection) return f * dg / (4.0 * cos_oi);
    float denom = p.dot_o + p.eta * p.dot_i;
    return (1.0 - f) * dg * abs(p.dot_o * p.dot_i) / (cos_oi * denom * denom);
}

float dielectric_pdf(vec3 wo, vec3 wi, vec2 alpha, uint dist, float ior) {
    if (mf_is_smooth(alpha)) return 0.0;
    DielectricPair p = dielectric_pair(wo, wi, ior);
    if (!p.valid) return 0.0;
    // The sampler only makes pairs that see the front of their microfacet.
    if (p.dot_o * wo.z <= 0.0 || p.dot_i * wi.z <= 0.0) return 0.0;
    float pdf_m = mf_pdf_visible(wo, p.h, mf_rough_alpha(alpha), dist);
    float cos_t;
    float f = mf_fresnel_dielectric(abs(p.dot_o), p.eta_o, p.eta_t, cos_t);
    if (p.reflection) return f * pdf_m / (4.0 * abs(p.dot_o));
    float denom = p.dot_o + p.eta * p.dot_i;
    return (1.0 - f) * pdf_m * p.eta * p.eta * abs(p.dot_i) / (denom * denom);
}

bool dielectric_sample(vec3 wo, vec2 alpha, uint dist, float ior, vec3 u, out vec3 wi, out vec3 weight, out float pdf,
                       out uint lobe) {
    wi = vec3(0.0); weight = vec3(0.0); pdf = 0.0; lobe = MF_REFLECTION;
    float cos_o = wo.z;
    if (cos_o == 0.0) return false;
    float eta_o = cos_o > 0.0 ? 1.0 : ior;
    float eta_t = cos_o > 0.0 ? ior : 1.0;
    float eta = eta_t / eta_o;
    float side = cos_o > 0.0 ? 1.0 : -1.0;
    if (mf_is_smooth(alpha)) {
        float cos_t;
        float f = mf_fresnel_dielectric(abs(cos_o), eta_o, eta_t, cos_t);
        if (u.x < f) {
            wi = mf_mirror(wo);
            weight = vec3(1.0);
            return true;
        }
        // Snell: the tangential part shrinks by 1/eta, the ray crosses to the other side.
        wi = vec3(-wo.x / eta, -wo.y / eta, -side * cos_t);
        weight = vec3(1.0 / (eta * eta));
        lobe = MF_TRANSMISSION;
        return true;
    }
    alpha = mf_rough_alpha(alpha);
    vec3 m = mf_sample_visible(wo, alpha, dist, u.yz);
    float dot_o = dot(wo, m);
    if (dot_o * side <= 0.0) return false;
    float pdf_m = mf_pdf_visible(wo, m, alpha, dist);
    float cos_t;
    float f = mf_fresnel_dielectric(abs(dot_o), eta_o, eta_t, cos_t);
    if (u.x < f) {
        vec3 w = 2.0 * dot_o * m - wo;
        if (w.z * side <= 0.0) return false;
        float p = f * pdf_m / (4.0 * abs(dot_o));
        if (!(p > 0.0)) return false;
        wi = w;
        // f |cos| / pdf = G1(wi): F, D and G1(wo) cancel.
        weight = vec3(mf_g1(w, m, alpha, dist));
        pdf = p;
        return true;
    }
    // Refraction through m turned to wo's side (pbrt-v3 Refract with relative index 1/eta).
    vec3 w = -wo / eta + (abs(dot_o) / eta - cos_t) * (side * m);
    if (w.z * side >= 0.0) return false;
    float dot_i = dot(w, m);
    float denom = dot_o + eta * dot_i;
    float p = (1.0 - f) * pdf_m * eta * eta * abs(dot_i) / (denom * denom);
    if (!(p > 0.0)) return false;
    wi = w;
    // f |cos| / pdf = G1(wi) / eta^2: (1 - F), D, G1(wo) and the Jacobian cancel.
    weight = vec3(mf_g1(w, m, alpha, dist) / (eta * eta));
    pdf = p;
    lobe = MF_TRANSMISSION;
    return true;
}

// ---------------------------------------------------------------------------------------------
// Plastic: GGX dielectric coat over a Lambertian base (Mitsuba 3 plastic / roughplastic, linear or
// nonlinear, with the changes listed at plastic_eval in the twin). `nonlinear` and `table` (a
// rough nonlinear coat's table, or NO_DATA) are the twin's PlasticCoat; the table's words come
// from mf_coat_word, which the including kernel defines.

float mf_coat_word(uint i);

float mf_coat_transmittance(uint table, float mu, float f) {
    if (table == NO_DATA) return 1.0 - f;
    float x = clamp(mu, 0.0, 1.0) * float(PLASTIC_COAT_TABLE - 1u);
    uint i = min(uint(x), PLASTIC_COAT_TABLE - 2u);
    float v0 = mf_coat_word(table + 1u + i), v1 = mf_coat_word(table + 2u + i);
    return v0 + (v1 - v0) * (x - float(i));
}

vec3 mf_plastic_base(float wo_z, float wi_z, float f_o, float f_i, float ior, vec3 diffuse, bool nonlinear, uint table) {
    float fdr_ext = mf_fresnel_diffuse(ior);
    if (!nonlinear) return diffuse * ((1.0 - f_o) * (1.0 - f_i) / (MF_PI * (1.0 - fdr_ext)));
    float t_o = mf_coat_transmittance(table, wo_z, f_o);
    float t_i = mf_coat_transmittance(table, wi_z, f_i);
    float eta2 = ior * ior;
    float r_int = table == NO_DATA ? 1.0 - (1.0 - fdr_ext) / eta2 : mf_coat_word(table);
    vec3 bounce = max(vec3(1.0) - diffuse * r_int, vec3(1e-6));
    return diffuse * (t_o * t_i / (MF_PI * eta2)) / bounce;
}

vec3 plastic_eval(vec3 wo, vec3 wi, vec2 alpha, uint dist, float ior, vec3 diffuse, bool nonlinear, uint table) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    float cos_t;
    float f_o = mf_fresnel_dielectric(wo.z, 1.0, ior, cos_t);
    float f_i = mf_fresnel_dielectric(wi.z, 1.0, ior, cos_t);
    vec3 f = mf_plastic_base(wo.z, wi.z, f_o, f_i, ior, diffuse, nonlinear, table);
    if (mf_is_smooth(alpha)) return f;
    alpha = mf_rough_alpha(alpha);
    vec3 h = normalize(wo + wi);
    float dg = mf_d(h, alpha, dist) * mf_g1(wo, h, alpha, dist) * mf_g1(wi, h, alpha, dist);
    // The coat's Fresnel at the microfacet, as Mitsuba's: see plastic_eval in the twin.
    float f_h = mf_fresnel_dielectric(abs(dot(wo, h)), 1.0, ior, cos_t);
    return f + vec3(f_h * dg / (4.0 * wo.z * wi.z));
}

float plastic_pdf(vec3 wo, vec3 wi, vec2 alpha, uint dist, float ior, vec3 diffuse) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    float p_coat = mf_plastic_coat_probability(wo, ior, diffuse);
    float pdf = (1.0 - p_coat) * wi.z / MF_PI;
    if (mf_is_smooth(alpha)) return pdf;
    alpha = mf_rough_alpha(alpha);
    vec3 h = normalize(wo + wi);
    float pdf_m = mf_pdf_visible(wo, h, alpha, dist);
    if (pdf_m > 0.0) pdf += p_coat * pdf_m / (4.0 * dot(wo, h));
    return pdf;
}

bool plastic_sample(vec3 wo, vec2 alpha, uint dist, float ior, vec3 diffuse, bool nonlinear, uint table, vec3 u, out vec3 wi,
                    out vec3 weight, out float pdf, out uint lobe) {
    wi = vec3(0.0); weight = vec3(0.0); pdf = 0.0; lobe = MF_REFLECTION;
    if (wo.z <= 0.0) return false;
    float p_coat = mf_plastic_coat_probability(wo, ior, diffuse);
    vec3 w;
    if (u.x < p_coat) {
        if (mf_is_smooth(alpha)) {
            float cos_t;
            wi = mf_mirror(wo);
            weight = vec3(mf_fresnel_dielectric(wo.z, 1.0, ior, cos_t) / p_coat);
            return true;
        }
        vec3 m = mf_sample_visible(wo, mf_rough_alpha(alpha), dist, u.yz);
        w = 2.0 * dot(wo, m) * m - wo;
    } else {
        w = mf_cosine_direction(u.yz);
    }
    if (w.z <= 0.0) return false;
    // Both lobes count in pdf and weight (one-sample MIS over the two lobes).
    float p = plastic_pdf(wo, w, alpha, dist, ior, diffuse);
    if (!(p > 0.0)) return false;
    wi = w;
    weight = plastic_eval(wo, w, alpha, dist, ior, diffuse, nonlinear, table) * (w.z / p);
    pdf = p;
    return true;
}

// ---------------------------------------------------------------------------------------------
// Lambert

vec3 lambert_eval(vec3 wo, vec3 wi, vec3 albedo) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    return albedo / MF_PI;
}

float lambert_pdf(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    return wi.z / MF_PI;
}

bool lambert_sample(vec3 wo, vec3 albedo, vec2 u, out vec3 wi, out vec3 weight, out float pdf, out uint lobe) {
    wi = vec3(0.0); weight = vec3(0.0); pdf = 0.0; lobe = MF_REFLECTION;
    if (wo.z <= 0.0) return false;
    vec3 w = mf_cosine_direction(u);
    if (w.z <= 0.0) return false;
    wi = w;
    weight = albedo;
    pdf = w.z / MF_PI;
    return true;
}
