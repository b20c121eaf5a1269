// Materials as BSDFs: every material kind, one switch per operation. CPU twin: src/cpu/bsdf.rs.
// Directions point away from the surface: `wo` toward the previous vertex (the viewer), `wi`
// toward the next one. The path loops never ask which kind they hold, only what its lobes are:
// BSDF_ESTIMATE lobes end a camera path (light sampling, photon lookups, final gather) and store
// photons; BSDF_PATH lobes are followed. The including kernel declares the scene bindings and
// includes sampling.glsl, shape.glsl, texture.glsl and microfacet.glsl.

// A material evaluated at one surface point: its textures looked up, its frame set.
struct Bsdf {
    uint kind;
    uint flags;       // the material's MATERIAL_FLAG_*
    uint data;        // the material's data: a rough nonlinear plastic's coat table
    vec3 color0;
    vec3 color1;
    vec3 color2;      // a conductor's tint
    vec2 alpha;
    float ior;
    vec3 ng;          // geometric normal (a triangle's winding side, a sphere's outside)
    vec3 ns;          // shading normal, on the side of ng
    vec3 ts;          // direction of the first GGX width (dpdu; zero without uv: any tangent)
    bool glossy_path; // glossy lobes are path lobes (GGX width <= frame.glossy_threshold)
};

struct BsdfSample {
    vec3 wi;
    vec3 weight;   // f |cos| / pdf of the lobes sampled from
    float pdf;     // 0 for a specular (delta) lobe
    uint flags;    // BSDF_* flags of the lobe sampled; 0 when no direction was sampled
};

// Radiance the material emits at h toward its front side.
vec3 material_emission(Material m, Hit h) {
    if (!SCENE_HAS_EMISSION_TEXTURES) return vec3(m.emission[0], m.emission[1], m.emission[2]);
    return param_color(m.emission, m.emission_tex, h);
}

// A number in [0, 1) fixed for each point of space and key: a hash of the point's cell in a grid
// of 4 ray offsets (a 2.5e-5 of the scene's size). Stochastic alpha and mixes decide by it, so
// camera rays, shadow rays and photons see the same surface at the same point, and no random
// dimension of a path is spent (pbrt-v4 hashes for its alpha test too). The cell, not the
// point's bits, is hashed: the GPU and the CPU round a hit point differently in its last bits.
float hash_point(vec3 p, uint key) {
    ivec3 c = ivec3(floor(p / (4.0 * frame.ray_epsilon)));
    return rand_unit(pcg4d(uvec4(uvec3(c), key)).x);
}

// The texture lookups of material_bsdf, one bit each in a mask: colour 0, colour 1, roughness,
// normal map, the bump map's four heights (u+, u-, v+, v-) and colour 2.
const uint LOOKUP_COLOR0 = 0u;
const uint LOOKUP_COLOR1 = 1u;
const uint LOOKUP_ROUGHNESS = 2u;
const uint LOOKUP_NORMAL = 3u;
const uint LOOKUP_BUMP = 4u;  // to LOOKUP_BUMP + 3
const uint LOOKUP_COLOR2 = 8u;
const uint LOOKUP_MIX = 9u;   // a mix's weight

uint material_lookups(Material m) {
    return (m.color0_tex != NO_TEXTURE ? 1u << LOOKUP_COLOR0 : 0u)
        | (m.color1_tex != NO_TEXTURE ? 1u << LOOKUP_COLOR1 : 0u)
        | (m.roughness_tex != NO_TEXTURE ? 1u << LOOKUP_ROUGHNESS : 0u)
        | (m.normal_tex != NO_TEXTURE ? 1u << LOOKUP_NORMAL : 0u)
        | (m.color2_tex != NO_TEXTURE ? 1u << LOOKUP_COLOR2 : 0u)
        | (m.bump_tex != NO_TEXTURE ? 15u << LOOKUP_BUMP : 0u);
}

// Where lookup `k` reads: a bump height's point moved by BUMP_DELTA along u or v.
Hit lookup_hit(Hit h, uint k) {
    if (k < LOOKUP_BUMP || k >= LOOKUP_COLOR2) return h;
    uint j = k - LOOKUP_BUMP;
    float d = (j & 1u) == 0u ? BUMP_DELTA : -BUMP_DELTA;
    return j < 2u ? hit_moved(h, d, 0.0) : hit_moved(h, 0.0, d);
}

uint lookup_texture(Material m, uint k) {
    if (k == LOOKUP_COLOR0) return m.color0_tex;
    if (k == LOOKUP_COLOR1) return m.color1_tex;
    if (k == LOOKUP_ROUGHNESS) return m.roughness_tex;
    if (k == LOOKUP_NORMAL) return m.normal_tex;
    if (k == LOOKUP_MIX) return m.weight_tex;
    if (k == LOOKUP_COLOR2) return m.color2_tex;
    return m.bump_tex;
}

// The BSDF at hit h of a material whose values are looked up (textures, a mix's choice, bump and
// normal maps done): material_bsdf's, and render_vcm's light vertices' from what vcm_light stored.
Bsdf bsdf_at(Hit h, uint kind, uint flags, uint data, vec3 color0, vec3 color1, vec3 color2, vec2 alpha, float ior,
             vec3 ns) {
    Bsdf b;
    b.kind = kind;
    b.flags = flags;
    b.data = data;
    b.color0 = color0;
    b.color1 = color1;
    b.color2 = color2;
    b.alpha = alpha;
    b.ior = ior;
    // The normal that decides sides: the geometric one, or a smooth triangle's interpolated one
    // (its BSDF sees the curved surface the normals describe; see the twin).
    b.ng = h.ns;
    b.ns = ns;
    b.ts = h.dpdu;
    b.glossy_path = max(alpha.x, alpha.y) <= frame.glossy_threshold;
    return b;
}

// The mix's choices, then every texture of the chosen material, go through the one texture_eval
// in this loop: lavapipe inlines a function at each call site, and one call per parameter (nine,
// with the bump map's four) made the textured kernels several times larger and slower.
Bsdf material_bsdf(Material m, Hit h) {
    vec3 looked[9];
    uint level = 0u;
    bool mixing = m.kind == MATERIAL_MIX;
    uint pending = mixing ? 0u : material_lookups(m);
    for (uint step = 0u; step < MIX_MAX_DEPTH + 9u && (mixing || pending != 0u); step++) {
        uint k = mixing ? LOOKUP_MIX : uint(findLSB(pending));
        uint tex = lookup_texture(m, k);
        vec3 v = vec3(1.0);
        WHEN(tex != NO_TEXTURE) v = texture_eval(tex, lookup_hit(h, k));
        if (mixing) {
            m = material_at(hash_point(h.p, level) < m.weight * v.x ? m.mix_b : m.mix_a);
            level++;
            mixing = level < MIX_MAX_DEPTH && m.kind == MATERIAL_MIX;
            if (!mixing) pending = material_lookups(m);
        } else {
            looked[k] = v;
            pending &= pending - 1u;
        }
    }
    uint lookups = material_lookups(m);
    vec3 color0 = load3(m.color0);
    if ((lookups & (1u << LOOKUP_COLOR0)) != 0u) color0 *= looked[LOOKUP_COLOR0];
    vec3 color1 = load3(m.color1);
    if ((lookups & (1u << LOOKUP_COLOR1)) != 0u) color1 *= looked[LOOKUP_COLOR1];
    vec3 color2 = load3(m.color2);
    if ((lookups & (1u << LOOKUP_COLOR2)) != 0u) color2 *= looked[LOOKUP_COLOR2];
    vec2 alpha = vec2(m.roughness[0], m.roughness[1]);
    if ((lookups & (1u << LOOKUP_ROUGHNESS)) != 0u) alpha *= looked[LOOKUP_ROUGHNESS].x;
    // Bump and normal maps change the shading normal only: the geometric normal keeps deciding
    // sides, offsets and leaks. A bump map wins over a normal map.
    vec3 ns = h.ns;
    WHEN((lookups & (1u << LOOKUP_NORMAL)) != 0u) ns = normal_map_normal_from_texel(looked[LOOKUP_NORMAL], h);
    WHEN((lookups & (15u << LOOKUP_BUMP)) != 0u) {
        ns = bump_normal_from_heights(looked[LOOKUP_BUMP].x, looked[LOOKUP_BUMP + 1u].x, looked[LOOKUP_BUMP + 2u].x,
                                      looked[LOOKUP_BUMP + 3u].x, m.bump_strength, h);
    }
    return bsdf_at(h, m.kind, m.flags, m.data, color0, color1, color2, alpha, m.ior, ns);
}

// The shading normal turned to the side of w.
vec3 facing(Bsdf b, vec3 w) { return dot(w, b.ng) > 0.0 ? b.ns : -b.ns; }

BsdfSample no_sample() { return BsdfSample(vec3(0.0), vec3(0.0), 0.0, 0u); }

// Diffuse: Lambertian reflection of albedo color0 on both sides.

// Reflection needs wi on wo's side of the shading normal and of the geometric one, so a bumped
// normal cannot let light in from under the surface.
bool same_side(Bsdf b, vec3 wo, vec3 wi) {
    return dot(wi, facing(b, wo)) > 0.0 && dot(wi, b.ng) * dot(wo, b.ng) > 0.0;
}

vec3 diffuse_eval(Bsdf b, vec3 wo, vec3 wi) {
    return same_side(b, wo, wi) ? b.color0 * (1.0 / PI) : vec3(0.0);
}

float diffuse_pdf(Bsdf b, vec3 wo, vec3 wi) {
    return same_side(b, wo, wi) ? dot(wi, facing(b, wo)) * (1.0 / PI) : 0.0;
}

BsdfSample diffuse_sample(Bsdf b, vec3 wo, vec3 u) {
    vec3 n = facing(b, wo);
    vec3 wi = cosine_direction(n, u.yz);
    if (!same_side(b, wo, wi)) return no_sample();
    // Cosine sampling cancels the cosine and the 1/pi: the weight is the albedo.
    return BsdfSample(wi, b.color0, max(0.0, dot(wi, n)) * (1.0 / PI), BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE);
}

// Mirror: perfect reflection tinted by color0, on both sides.

BsdfSample mirror_sample(Bsdf b, vec3 wo) {
    return BsdfSample(reflect(-wo, facing(b, wo)), b.color0, 0.0, BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH);
}

// Dielectric: smooth interface of index ior inside (the side opposite ng), reflection or
// refraction chosen with the Fresnel probability against u.x, weight 1.
BsdfSample smooth_dielectric_sample(Bsdf b, vec3 wo, vec3 u) {
    vec3 d = -wo;
    bool front = dot(b.ng, d) < 0.0;
    vec3 nf = front ? b.ng : -b.ng;
    float eta_i = front ? 1.0 : b.ior;
    float eta_t = front ? b.ior : 1.0;
    float cos_i = -dot(d, nf);
    float cos_t;
    if (u.x < mf_fresnel_dielectric(cos_i, eta_i, eta_t, cos_t)) {
        return BsdfSample(reflect(d, nf), vec3(1.0), 0.0, BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH);
    }
    float eta = eta_i / eta_t;
    vec3 wi = normalize(eta * d + (eta * cos_i - cos_t) * nf);
    return BsdfSample(wi, vec3(1.0), 0.0, BSDF_SPECULAR | BSDF_TRANSMISSION | BSDF_PATH);
}

// Thin dielectric: a pane of index ior (Mitsuba's thindielectric). Its reflectance sums the
// light bouncing inside the pane, R' = R + T^2 R / (1 - R^2) with T = 1 - R; the rest passes
// straight through. Chosen against u.x, weight 1.
BsdfSample thin_dielectric_sample(Bsdf b, vec3 wo, vec3 u) {
    vec3 n = facing(b, wo);
    float cos_t;
    float r = mf_fresnel_dielectric(abs(dot(wo, n)), 1.0, b.ior, cos_t);
    if (r < 1.0) r += (1.0 - r) * (1.0 - r) * r / (1.0 - r * r);
    if (u.x < r) return BsdfSample(reflect(-wo, n), vec3(1.0), 0.0, BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH);
    return BsdfSample(-wo, vec3(1.0), 0.0, BSDF_SPECULAR | BSDF_TRANSMISSION | BSDF_PATH);
}

// The local frame of b around normal n (x along ts where it is known).
void bsdf_frame(Bsdf b, vec3 n, out vec3 t, out vec3 bt) {
    vec3 tt = b.ts - n * dot(n, b.ts);
    if (dot(tt, tt) > 1e-12) {
        t = normalize(tt);
        bt = cross(n, t);
    } else {
        onb(n, t, bt);
    }
}

vec3 to_local(vec3 v, vec3 t, vec3 bt, vec3 n) { return vec3(dot(v, t), dot(v, bt), dot(v, n)); }
vec3 to_world(vec3 v, vec3 t, vec3 bt, vec3 n) { return v.x * t + v.y * bt + v.z * n; }

bool is_smooth(Bsdf b) { return mf_is_smooth(b.alpha); }

// A microfacet sample as a BsdfSample: `glossy` lobe flags unless its pdf is 0 (a delta).
BsdfSample microfacet_result(bool ok, vec3 wi_local, vec3 weight, float pdf, uint lobe, vec3 t, vec3 bt, vec3 n, uint rough) {
    if (!ok) return no_sample();
    uint side = lobe == MF_TRANSMISSION ? BSDF_TRANSMISSION : BSDF_REFLECTION;
    uint kind = pdf == 0.0 ? BSDF_SPECULAR | BSDF_PATH : rough;
    return BsdfSample(to_world(wi_local, t, bt, n), weight, pdf, kind | side);
}

// The flags of a glossy lobe: followed by paths up to the threshold, an estimate lobe above it.
uint glossy_flags(Bsdf b) { return BSDF_GLOSSY | (b.glossy_path ? BSDF_PATH : BSDF_ESTIMATE); }

// The microfacet distribution of a rough material (MICROFACET_*, from its flags).
uint microfacet_dist(Bsdf b) { return (b.flags & MATERIAL_FLAG_BECKMANN) != 0u ? MICROFACET_BECKMANN : MICROFACET_GGX; }

// Conductor: GGX or Beckmann metal with complex index color0 + i color1, its Fresnel term tinted
// by color2, reflecting on both sides.

vec3 conductor_bsdf_eval(Bsdf b, vec3 wo, vec3 wi) {
    if (dot(wi, b.ng) * dot(wo, b.ng) <= 0.0) return vec3(0.0);
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    return b.color2 * conductor_eval(to_local(wo, t, bt, n), to_local(wi, t, bt, n), b.alpha, microfacet_dist(b), b.color0, b.color1);
}

float conductor_bsdf_pdf(Bsdf b, vec3 wo, vec3 wi) {
    if (dot(wi, b.ng) * dot(wo, b.ng) <= 0.0) return 0.0;
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    return conductor_pdf(to_local(wo, t, bt, n), to_local(wi, t, bt, n), b.alpha, microfacet_dist(b));
}

BsdfSample conductor_bsdf_sample(Bsdf b, vec3 wo, vec3 u) {
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    vec3 wi, weight;
    float pdf;
    uint lobe;
    bool ok = conductor_sample(to_local(wo, t, bt, n), b.alpha, microfacet_dist(b), b.color0, b.color1, u.yz, wi, weight, pdf, lobe);
    BsdfSample s = microfacet_result(ok, wi, b.color2 * weight, pdf, lobe, t, bt, n, glossy_flags(b));
    if (dot(s.wi, b.ng) * dot(wo, b.ng) <= 0.0) return no_sample();
    return s;
}

// Rough dielectric: GGX or Beckmann reflection and refraction (the smooth one is smooth_dielectric_sample).

float rough_dielectric_eval(Bsdf b, vec3 wo, vec3 wi) {
    vec3 t, bt;
    bsdf_frame(b, b.ns, t, bt);
    return dielectric_eval(to_local(wo, t, bt, b.ns), to_local(wi, t, bt, b.ns), b.alpha, microfacet_dist(b), b.ior);
}

float rough_dielectric_pdf(Bsdf b, vec3 wo, vec3 wi) {
    vec3 t, bt;
    bsdf_frame(b, b.ns, t, bt);
    return dielectric_pdf(to_local(wo, t, bt, b.ns), to_local(wi, t, bt, b.ns), b.alpha, microfacet_dist(b), b.ior);
}

BsdfSample rough_dielectric_sample(Bsdf b, vec3 wo, vec3 u) {
    vec3 t, bt;
    bsdf_frame(b, b.ns, t, bt);
    vec3 wi, weight;
    float pdf;
    uint lobe;
    bool ok = dielectric_sample(to_local(wo, t, bt, b.ns), b.alpha, microfacet_dist(b), b.ior, u, wi, weight, pdf, lobe);
    BsdfSample s = microfacet_result(ok, wi, weight * b.color0, pdf, lobe, t, bt, b.ns, glossy_flags(b));
    return s;
}

// Plastic: diffuse base color0 under a dielectric coat of index ior, on both sides. A smooth
// coat is a path lobe (a delta); a rough coat is read with the base as an estimate lobe.

// microfacet.glsl's coat tables live in the texture data.
float mf_coat_word(uint i) { return uintBitsToFloat(texture_word(i)); }

bool plastic_nonlinear(Bsdf b) { return (b.flags & MATERIAL_FLAG_NONLINEAR) != 0u; }

vec3 plastic_bsdf_eval(Bsdf b, vec3 wo, vec3 wi) {
    if (dot(wi, b.ng) * dot(wo, b.ng) <= 0.0) return vec3(0.0);
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    return plastic_eval(to_local(wo, t, bt, n), to_local(wi, t, bt, n), b.alpha, microfacet_dist(b), b.ior, b.color0, plastic_nonlinear(b), b.data);
}

float plastic_bsdf_pdf(Bsdf b, vec3 wo, vec3 wi) {
    if (dot(wi, b.ng) * dot(wo, b.ng) <= 0.0) return 0.0;
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    vec3 wo_l = to_local(wo, t, bt, n), wi_l = to_local(wi, t, bt, n);
    // With a smooth coat the estimate lobe is the base alone, sampled by cosine.
    return is_smooth(b) ? max(0.0, wi_l.z) * (1.0 / PI) : plastic_pdf(wo_l, wi_l, b.alpha, microfacet_dist(b), b.ior, b.color0);
}

float plastic_coat_probability(Bsdf b, vec3 wo) {
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    return mf_plastic_coat_probability(to_local(wo, t, bt, n), b.ior, b.color0);
}

BsdfSample plastic_bsdf_sample(Bsdf b, vec3 wo, vec3 u, uint lobes) {
    vec3 n = facing(b, wo), t, bt;
    bsdf_frame(b, n, t, bt);
    vec3 wo_l = to_local(wo, t, bt, n);
    if (is_smooth(b) && lobes == LOBES_PATH) {
        // The coat alone: a mirror weighted by its Fresnel reflectance.
        float cos_t;
        float f = mf_fresnel_dielectric(wo_l.z, 1.0, b.ior, cos_t);
        return BsdfSample(reflect(-wo, n), vec3(f), 0.0, BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH);
    }
    if (is_smooth(b) && lobes == LOBES_ESTIMATE) {
        // The base alone, by cosine: weight f cos / pdf = pi f.
        vec3 wi_l = mf_cosine_direction(u.yz);
        vec3 f = plastic_eval(wo_l, wi_l, b.alpha, microfacet_dist(b), b.ior, b.color0, plastic_nonlinear(b), b.data);
        BsdfSample s = BsdfSample(to_world(wi_l, t, bt, n), PI * f, wi_l.z * (1.0 / PI), BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE);
        return dot(s.wi, b.ng) * dot(wo, b.ng) > 0.0 && wi_l.z > 0.0 ? s : no_sample();
    }
    vec3 wi, weight;
    float pdf;
    uint lobe;
    bool ok = plastic_sample(wo_l, b.alpha, microfacet_dist(b), b.ior, b.color0, plastic_nonlinear(b), b.data, u, wi, weight, pdf, lobe);
    BsdfSample s = microfacet_result(ok, wi, weight, pdf, lobe, t, bt, n, BSDF_GLOSSY | BSDF_DIFFUSE | BSDF_ESTIMATE);
    if (dot(s.wi, b.ng) * dot(wo, b.ng) <= 0.0) return no_sample();
    return s;
}

// A medium's scattering point scatters into every direction and ends camera paths (light
// sampling, the volume photon map) like a diffuse surface.
const uint PHASE_FLAGS = BSDF_GLOSSY | BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_ESTIMATE;

// The lobes of b (BSDF_* flags); 0 for a black surface, which ends paths and stores nothing.
uint bsdf_flags(Bsdf b) {
    switch (b.kind) {
    case MATERIAL_DIFFUSE:
        return b.color0 == vec3(0.0) ? 0u : BSDF_DIFFUSE | BSDF_REFLECTION | BSDF_ESTIMATE;
    case MATERIAL_MIRROR:
        return BSDF_SPECULAR | BSDF_REFLECTION | BSDF_PATH;
    case MATERIAL_DIELECTRIC:
        return BSDF_REFLECTION | BSDF_TRANSMISSION | (is_smooth(b) ? BSDF_SPECULAR | BSDF_PATH : glossy_flags(b));
    case MATERIAL_CONDUCTOR:
        return BSDF_REFLECTION | (is_smooth(b) ? BSDF_SPECULAR | BSDF_PATH : glossy_flags(b));
    case MATERIAL_PLASTIC:
        return BSDF_REFLECTION | (is_smooth(b) ? BSDF_SPECULAR | BSDF_PATH : BSDF_GLOSSY | BSDF_ESTIMATE)
            | (b.color0 == vec3(0.0) ? 0u : BSDF_DIFFUSE | BSDF_ESTIMATE);
    case MATERIAL_PHASE:
        return PHASE_FLAGS;
    case MATERIAL_THIN_DIELECTRIC:
        return BSDF_SPECULAR | BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_PATH;
    }
    return 0u;  // unreachable: the host packs only known kinds (tested)
}

// Probability that a camera path seen from wo follows the path lobes rather than ending in the
// estimate lobes: 0 for a surface with estimate lobes alone, 1 for path lobes alone.
float bsdf_path_probability(Bsdf b, vec3 wo) {
    uint flags = bsdf_flags(b);
    if ((flags & BSDF_PATH) == 0u) return 0.0;
    if ((flags & BSDF_ESTIMATE) == 0u) return 1.0;
    // Both: a smooth plastic; its coat is chosen as the plastic's own sampling chooses it.
    return SCENE_HAS_PLASTIC ? plastic_coat_probability(b, wo) : 0.0;
}

// True when the estimate lobes have the same value for every wi on wo's side (Lambertian), so a
// photon estimate may sum the irradiance first and apply the BSDF once.
bool bsdf_estimate_is_constant(Bsdf b) { return b.kind == MATERIAL_DIFFUSE; }

// The factor that makes a light path's scattering the adjoint of the camera's where a bump or
// normal map bends ns away from ng (Veach 1997, 5.3): |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|), wo
// toward the light side, wi where the light leaves; exactly 1 where the normals are one.
float shading_adjoint(Bsdf b, vec3 wo, vec3 wi) {
    if (b.kind == MATERIAL_PHASE || b.ns == b.ng) return 1.0;
    float den = abs(dot(wo, b.ng)) * abs(dot(wi, b.ns));
    if (den <= 0.0) return 0.0;
    return abs(dot(wo, b.ns)) * abs(dot(wi, b.ng)) / den;
}

// f(wo, wi) of the estimate lobes, without the cosine; 0 for path lobes (they are sampled).
vec3 bsdf_eval(Bsdf b, vec3 wo, vec3 wi) {
    if ((bsdf_flags(b) & BSDF_ESTIMATE) == 0u) return vec3(0.0);
    // Each case only where the scene has the kind (SCENE_MATERIAL_KINDS): the others compile out.
    switch (b.kind) {
    case MATERIAL_DIFFUSE:
        if (SCENE_HAS_DIFFUSE) return diffuse_eval(b, wo, wi);
        break;
    case MATERIAL_DIELECTRIC:
        if (SCENE_HAS_DIELECTRIC) return b.color0 * rough_dielectric_eval(b, wo, wi);
        break;
    case MATERIAL_CONDUCTOR:
        if (SCENE_HAS_CONDUCTOR) return conductor_bsdf_eval(b, wo, wi);
        break;
    case MATERIAL_PLASTIC:
        if (SCENE_HAS_PLASTIC) return plastic_bsdf_eval(b, wo, wi);
        break;
    case MATERIAL_PHASE:
        if (SCENE_HAS_PHASE) return vec3(phase_hg(dot(wo, wi), b.ior));
        break;
    }
    return vec3(0.0);
}

// Solid-angle pdf of bsdf_sample(.., LOBES_ESTIMATE) choosing wi.
float bsdf_pdf(Bsdf b, vec3 wo, vec3 wi) {
    if ((bsdf_flags(b) & BSDF_ESTIMATE) == 0u) return 0.0;
    switch (b.kind) {
    case MATERIAL_DIFFUSE:
        if (SCENE_HAS_DIFFUSE) return diffuse_pdf(b, wo, wi);
        break;
    case MATERIAL_DIELECTRIC:
        if (SCENE_HAS_DIELECTRIC) return rough_dielectric_pdf(b, wo, wi);
        break;
    case MATERIAL_CONDUCTOR:
        if (SCENE_HAS_CONDUCTOR) return conductor_bsdf_pdf(b, wo, wi);
        break;
    case MATERIAL_PLASTIC:
        if (SCENE_HAS_PLASTIC) return plastic_bsdf_pdf(b, wo, wi);
        break;
    case MATERIAL_PHASE:
        if (SCENE_HAS_PHASE) return phase_hg(dot(wo, wi), b.ior);
        break;
    }
    return 0.0;
}

// A direction from the lobes in `lobes` (LOBES_*): u.x picks among lobes (or Fresnel), u.yz
// place the direction. The weight is that of the chosen lobes alone; no_sample() when b has none
// of them.
BsdfSample bsdf_sample(Bsdf b, vec3 wo, vec3 u, uint lobes) {
    if ((bsdf_flags(b) & lobes) == 0u) return no_sample();
    switch (b.kind) {
    case MATERIAL_DIFFUSE:
        if (SCENE_HAS_DIFFUSE) return diffuse_sample(b, wo, u);
        break;
    case MATERIAL_MIRROR:
        if (SCENE_HAS_MIRROR) return mirror_sample(b, wo);
        break;
    case MATERIAL_DIELECTRIC:
        if (SCENE_HAS_DIELECTRIC) return is_smooth(b) ? smooth_dielectric_sample(b, wo, u) : rough_dielectric_sample(b, wo, u);
        break;
    case MATERIAL_CONDUCTOR:
        if (SCENE_HAS_CONDUCTOR) return conductor_bsdf_sample(b, wo, u);
        break;
    case MATERIAL_PLASTIC:
        if (SCENE_HAS_PLASTIC) return plastic_bsdf_sample(b, wo, u, lobes);
        break;
    case MATERIAL_THIN_DIELECTRIC:
        if (SCENE_HAS_THIN_DIELECTRIC) return thin_dielectric_sample(b, wo, u);
        break;
    case MATERIAL_PHASE:
        if (SCENE_HAS_PHASE) {
            // Sampled exactly by its own pdf: the weight is 1.
            vec3 wi = phase_hg_sample(wo, b.ior, u.yz);
            return BsdfSample(wi, vec3(1.0), phase_hg(dot(wo, wi), b.ior), PHASE_FLAGS);
        }
        break;
    }
    return no_sample();
}

// Opacity of the material at h, in [0, 1].
float material_opacity(Material m, Hit h) {
    return param_scalar(m.alpha, m.alpha_tex, h);
}
