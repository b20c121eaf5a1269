// Warps of uniform numbers to directions. CPU twin: src/cpu/sampling.rs.

const float PI = 3.14159265358979;

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

// Uniform direction in the cone of unit axis `axis` and half-angle acos(cos_max): pdf
// 1 / (2 pi (1 - cos_max)). cos_max = -1 gives the whole sphere, 1 the axis itself.
vec3 cone_direction(vec3 axis, float cos_max, vec2 u) {
    float z = 1.0 - u.x * (1.0 - cos_max);
    float rho = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    onb(axis, t, b);
    return rho * cos(phi) * t + rho * sin(phi) * b + z * axis;
}

// Uniform point on the unit disc (polar mapping).
vec2 disc_point(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return vec2(r * cos(phi), r * sin(phi));
}

// Uniform point in the regular polygon of `corners` corners on the unit circle, the first at
// angle `rotation` from +y toward +x; fewer than 3 corners mean the unit disc. u.x picks one of
// the triangles (centre, corner k, corner k + 1) and, rescaled, the distance from the centre.
vec2 polygon_point(vec2 u, uint corners, float rotation) {
    if (corners < 3u) return disc_point(u);
    float n = float(corners);
    float k = min(floor(u.x * n), n - 1.0);
    float s = sqrt(u.x * n - k);
    float a0 = rotation + 2.0 * PI * k / n;
    float a1 = a0 + 2.0 * PI / n;
    return s * ((1.0 - u.y) * vec2(sin(a0), cos(a0)) + u.y * vec2(sin(a1), cos(a1)));
}
