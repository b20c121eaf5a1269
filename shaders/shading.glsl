// Camera rays, light sampling and specular scattering. CPU twin: src/cpu/shading.rs.
// The including kernel declares `frame`, `primitives[]`, `materials[]` and `lights[]`, and
// includes rng.glsl and trace.glsl first.

const float PI = 3.14159265358979;

// Primary ray through film position (sx, sy) in [-1, 1]^2, sy = +1 at the top row.
vec3 camera_direction(float sx, float sy) {
    return normalize(load3(frame.camera_forward) + sx * load3(frame.camera_right) + sy * load3(frame.camera_up));
}

// Geometric normal at point x of primitive i: the winding normal (v1-v0)x(v2-v0) of a triangle,
// the outward normal of a sphere.
vec3 primitive_normal(uint i, vec3 x) {
    Primitive p = primitives[i];
    if (p.kind == PRIMITIVE_SPHERE) return normalize(x - load3(p.p0));
    return normalize(cross(load3(p.p1) - load3(p.p0), load3(p.p2) - load3(p.p0)));
}

// Orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
void onb(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-distributed direction around unit n (Malley's method): pdf cos(theta) / pi.
vec3 cosine_direction(vec3 n, vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    onb(n, t, b);
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - u.x)) * n);
}

// Uniform direction on the unit sphere.
vec3 sphere_direction(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float rho = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(rho * cos(phi), rho * sin(phi), z);
}

// A point on light l, uniform by area (Turk 1990 for triangles), and the light's normal there;
// a point light returns its position and a zero normal.
vec3 sample_light_point(Light l, vec2 u, out vec3 normal) {
    if (l.kind == LIGHT_TRIANGLE) {
        float su = sqrt(u.x);
        float b0 = 1.0 - su;
        float b1 = u.y * su;
        vec3 p0 = load3(l.p0), p1 = load3(l.p1), p2 = load3(l.p2);
        normal = normalize(cross(p1 - p0, p2 - p0));
        return b0 * p0 + b1 * p1 + (1.0 - b0 - b1) * p2;
    }
    if (l.kind == LIGHT_SPHERE) {
        normal = sphere_direction(u);
        return load3(l.p0) + l.p1[0] * normal;
    }
    normal = vec3(0.0);
    return load3(l.p0);
}

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

// Radiance reflected at x toward the camera from one sampled light: a one-sample estimate of
// the direct light for a Lambertian surface of albedo `albedo`. `n` faces the viewer. Counts the
// shadow ray it casts in `rays`.
vec3 direct_light(vec3 x, vec3 n, vec3 albedo, uint stream, uint sample_index, uint dim, inout uint rays) {
    if (frame.light_count == 0u) return vec3(0.0);
    uint li = pick_light(rand1(stream, sample_index, frame.seed, dim + RNG_LIGHT_PICK));
    Light l = lights[li];
    vec2 u = rand2(stream, sample_index, frame.seed, dim + RNG_LIGHT_U);
    vec3 ln;
    vec3 target = sample_light_point(l, u, ln);
    vec3 to_light = target - x;
    float dist2 = dot(to_light, to_light);
    float dist = sqrt(dist2);
    vec3 wi = to_light / dist;
    float cos_x = dot(n, wi);
    if (cos_x <= 0.0) return vec3(0.0);
    // Point light: E = I cos / d^2. Area light: L cos cos' / d^2 times area (uniform-area pdf).
    float geometry = cos_x / dist2;
    if (l.kind != LIGHT_POINT) {
        float cos_l = -dot(ln, wi);
        if (cos_l <= 0.0) return vec3(0.0);
        geometry *= cos_l * l.area;
    }
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    vec3 origin = x + n * frame.ray_epsilon;
    vec3 to_target = target - origin;
    float shadow_length = length(to_target);
    float t_unused;
    rays++;
    if (trace_ray(origin, to_target / shadow_length, shadow_length - frame.ray_epsilon, true, t_unused) != NO_LIGHT) return vec3(0.0);
    return albedo * (1.0 / PI) * load3(l.radiance) * (geometry / l.pick_probability);
}

// Unpolarised Fresnel reflectance for a ray that meets the interface with cos_i > 0 going
// from index eta_i into index eta_t; 1 under total internal reflection. Sets cos_t.
float fresnel_dielectric(float cos_i, float eta_i, float eta_t, out float cos_t) {
    float eta = eta_i / eta_t;
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) { cos_t = 0.0; return 1.0; }
    cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Scatters direction d at a smooth dielectric of index `ior` hit at x (nf faces the incoming ray;
// `front`: the ray arrives from outside): reflection or refraction, chosen with the Fresnel
// probability against u (weight 1). Sets d to the new direction and o to x offset to its side.
void dielectric_scatter(vec3 x, vec3 nf, bool front, float ior, float u, inout vec3 o, inout vec3 d) {
    float eta_i = front ? 1.0 : ior;
    float eta_t = front ? ior : 1.0;
    float cos_i = -dot(d, nf);
    float cos_t;
    if (u < fresnel_dielectric(cos_i, eta_i, eta_t, cos_t)) {
        d = reflect(d, nf);
        o = x + nf * frame.ray_epsilon;
    } else {
        float eta = eta_i / eta_t;
        d = normalize(eta * d + (eta * cos_i - cos_t) * nf);
        o = x - nf * frame.ray_epsilon;
    }
}
