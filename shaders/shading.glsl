// Camera rays, path vertices and direct light. CPU twin: src/cpu/shading.rs.
// The including kernel declares the scene bindings and includes rng, sampling, shape, texture,
// bsdf, trace and light (in that order).

// The reconstruction filter: contracts in shading.rs (filter_sample, film_offset, filter_weight,
// filter_radius, filter_is_pixel); the Gaussian's inverse cdf is microfacet.glsl's mf_erfinv.

float filter_sample(float u) {
    float s = frame.filter_scale;
    if (frame.pixel_filter == FILTER_TENT) return 0.5 + s * (u < 0.5 ? sqrt(2.0 * u) - 1.0 : 1.0 - sqrt(2.0 - 2.0 * u));
    if (frame.pixel_filter == FILTER_GAUSSIAN) {
        return 0.5 + s * FILTER_GAUSSIAN_STDDEV * 1.4142135 * mf_erfinv((2.0 * u - 1.0) * FILTER_GAUSSIAN_MASS);
    }
    return s == 1.0 ? u : 0.5 + s * (u - 0.5);
}

vec2 film_offset(vec2 u) { return vec2(filter_sample(u.x), filter_sample(u.y)); }

float filter_weight(float d) {
    float s = frame.filter_scale;
    float x = d / s;
    float w;
    if (frame.pixel_filter == FILTER_TENT) {
        w = max(1.0 - abs(x), 0.0);
    } else if (frame.pixel_filter == FILTER_GAUSSIAN) {
        w = abs(x) > FILTER_GAUSSIAN_RADIUS ? 0.0
            : FILTER_GAUSSIAN_NORM * exp(-x * x / (2.0 * FILTER_GAUSSIAN_STDDEV * FILTER_GAUSSIAN_STDDEV));
    } else {
        w = abs(x) < 0.5 ? 1.0 : 0.0;
    }
    return w / s;
}

float filter_radius() {
    float r = 0.5;
    if (frame.pixel_filter == FILTER_TENT) r = 1.0;
    if (frame.pixel_filter == FILTER_GAUSSIAN) r = FILTER_GAUSSIAN_RADIUS;
    return frame.filter_scale * r;
}

bool filter_is_pixel() { return frame.pixel_filter == FILTER_BOX && frame.filter_scale == 1.0; }

// The lens sample of a camera path: a pinhole draws none.
vec2 lens_sample(uint stream, uint sample_index) {
    return frame.lens_radius > 0.0 ? qmc2(stream, sample_index, frame.seed, RNG_PIXEL_Y) : vec2(0.0);
}

// Where lens sample u puts a ray's origin on the aperture, from its centre; contract in
// shading.rs, lens_offset.
vec3 lens_offset(vec2 u) {
    vec2 a = polygon_point(u, frame.aperture_blades, frame.aperture_rotation) * frame.lens_radius;
    return a.x * normalize(load3(frame.camera_right)) + a.y * normalize(load3(frame.camera_up));
}

// Primary ray through film position (sx, sy) in [-1, 1]^2, sy = +1 at the top row, with lens
// sample u (see FrameParams and the CAMERA_* kinds).
void camera_ray(float sx, float sy, vec2 u, out vec3 o, out vec3 d) {
    vec3 forward = load3(frame.camera_forward);
    vec3 right = load3(frame.camera_right);
    vec3 up = load3(frame.camera_up);
    o = load3(frame.camera_position);
    d = normalize(forward + sx * right + sy * up);
    // The other projections and the lens are loops of at most one turn: lavapipe runs both sides
    // of an `if` under masks, but skips a loop no lane enters, so a pinhole pays for none of them.
    WHEN(frame.camera_kind == CAMERA_ORTHOGRAPHIC) {
        o += sx * right + sy * up;
        d = forward;
    }
    WHEN(frame.camera_kind == CAMERA_LATLONG) {
        float phi = PI * sx;
        float theta = 0.5 * PI * sy;
        d = cos(theta) * (sin(phi) * right + cos(phi) * forward) + sin(theta) * up;
    }
    // Thin lens (never latlong): the ray from a point of the aperture aims where the pinhole ray
    // meets the plane in focus.
    WHEN(frame.lens_radius > 0.0) {
        vec3 focus = o + d * (frame.focal_distance / dot(d, forward));
        o += lens_offset(u);
        d = normalize(focus - o);
    }
}

// Origin of the ray that leaves h in a direction sampled from a lobe with `lobe_flags`: offset
// off the surface to the side the ray goes (wo's side for reflection, the other for transmission),
// by the hit's own offset, plus a smooth triangle's shift when the ray leaves to its side. The
// side is judged by the shading normal h.ns, which on smooth triangles keeps a ray toward a light
// above the shading horizon but below the facet on the outside (see the twin).
vec3 offset_origin(Hit h, vec3 wo, uint lobe_flags) {
    vec3 nf = dot(wo, h.ns) > 0.0 ? h.ng : -h.ng;
    vec3 side = (lobe_flags & BSDF_TRANSMISSION) != 0u ? -nf : nf;
    return h.p + side * h.eps + (dot(h.shift, side) > 0.0 ? h.shift : vec3(0.0));
}

// The primitive rays leaving a hit on primitive i must skip: i itself when it is a smooth
// triangle (see trace_ray's twin), else none.
uint ray_skip(uint i) {
    return (primitive_kind(hit_primitive(i)) & PRIMITIVE_FLAG_SMOOTH) != 0u ? i : NO_LIGHT;
}

// A shadow ray toward a point sampled on a light, and the radiance the light reflects at the
// shading point toward wo through the estimate lobes of its BSDF if nothing blocks the ray: a
// one-sample estimate of the direct light. `t_max` is NO_RAY when no ray is needed (no light,
// a light picked with probability 0, or nothing to reflect).
// The length of a shadow ray that is not cast: trace_ray meets nothing before it.
const float NO_RAY = -1.0;

struct ShadowRay {
    vec3 origin;
    vec3 direction;
    float t_max;
    vec3 unoccluded;
    // The vertex's shadow rays (see LIGHT_GRID_ADAPTIVE), and whether the picked light is
    // adaptive (its rays' visibility is the pixel's history).
    uint rays;
    bool adaptive;
};

// A light's sample numbers `u` moved into one cell of its POV-Ray grid (`Light::grid`; 0: `u`
// as it is): cell (sample_index + a hash of the pixel) mod (n m), so each pixel's consecutive
// n m samples visit every cell once, at a jittered point in it or at its centre.
vec2 grid_sample(uint grid, vec2 u, uint stream, uint sample_index) {
    if (grid == 0u) return u;
    uint n = grid & 0xffu;
    uint m = (grid >> 8u) & 0xffu;
    uint k = (sample_index + stream * 0x9E3779B1u) % (n * m);
    vec2 j = (grid & LIGHT_GRID_JITTER) != 0u ? u : vec2(0.5);
    return vec2((float(k % n) + j.x) / float(n), (float(k / n) + j.y) / float(m));
}

// Shadow ray `ray` of the vertex: every ray picks the same light. Toward an adaptive light, a
// pixel found in a penumbra at sample `penumbra_since` casts one ray per cell from the first
// sample of the light's next cycle of n m samples on (ray j of sample s takes the sequence's
// entry s rays + j, so the rays visit every cell once); before that, one ray in the sample's
// cell. The switch falls on a cycle's first sample and depends on earlier samples alone, so
// every cycle of single rays visits each cell once and every sample of many rays is unbiased
// by itself: the mean stays unbiased.
ShadowRay direct_light_sample(Hit h, Bsdf b, vec3 wo, uint stream, uint sample_index, uint dim, uint penumbra_since, uint ray) {
    ShadowRay none = ShadowRay(h.p, vec3(0.0, 1.0, 0.0), NO_RAY, vec3(0.0), 1u, false);
    if (frame.light_count == 0u) return none;
    vec3 receiver = b.kind == MATERIAL_PHASE ? vec3(0.0) : b.ns;
    float pmf;
    uint light = pick_direct_light(rand1(stream, sample_index, frame.seed, dim + RNG_LIGHT_PICK), h.p, receiver, pmf);
    // A scene whose lights all give photons only picks none.
    if (pmf <= 0.0) return none;
    Light l = light_at(light);
    // A scattering point in a homogeneous medium leaves point and spot lights to the camera
    // segment's equiangular sample (render.comp).
    if (b.kind == MATERIAL_PHASE && b.color1.y == 0.0 && (l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT)) return none;
    none.adaptive = (l.grid & LIGHT_GRID_ADAPTIVE) != 0u;
    if (none.adaptive) {
        // An adaptive light has a grid of at least 2 cells (scene loading checks it).
        uint cells = (l.grid & 0xffu) * ((l.grid >> 8u) & 0xffu);
        if (penumbra_since <= sample_index - sample_index % cells) none.rays = cells;
    }
    vec2 u = qmc2(stream, sample_index, frame.seed, ray == 0u ? dim + RNG_LIGHT_U : RNG_ADAPTIVE_DOMAIN + ray);
    LightSample s = light_sample(l, h.p, grid_sample(l.grid, u, stream, sample_index * none.rays + ray));
    vec3 f = bsdf_eval(b, wo, s.wi) * s.weight;
    if (f == vec3(0.0)) return none;
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    vec3 origin = offset_origin(h, s.wi, BSDF_REFLECTION);
    vec3 to_target = s.p - origin;
    float shadow_length = length(to_target);
    float t_max = max(shadow_length - s.eps, 0.0);
    // A medium's phase function has no cosine: it is per solid angle already.
    float cosine = b.kind == MATERIAL_PHASE ? 1.0 : abs(dot(b.ns, s.wi));
    return ShadowRay(origin, to_target / shadow_length, t_max, f * (cosine / (pmf * float(none.rays))), none.rays, none.adaptive);
}
