// Shapes: one switch per operation (intersect, hit record, sample). CPU twin: src/cpu/shape.rs.
// The including kernel declares the scene bindings and includes sampling.glsl.

// Everything the shading of a surface point needs, built in one place (`shape_hit`).
struct Hit {
    vec3 p;
    vec3 ng;    // unit geometric normal: a triangle's winding normal, a sphere's outward normal
    vec3 ns;    // unit shading normal, on the side of ng
    vec2 uv;
    vec3 dpdu;  // surface derivatives along u and v (never zero: a frame from ng when uv is degenerate;
    vec3 dpdv;  // uv, dpdu and dpdv are zero unless the primitive has PRIMITIVE_FLAG_UV)
    uint prim;
    uint material;
    float eps;  // offset of rays leaving the point: frame.ray_epsilon, or the analytic shape's own
    vec3 shift; // smooth triangles: Hanika's shift of the origin of rays leaving to its side; else 0
};

// Möller and Trumbore 1997, two-sided. Returns the hit distance in (t_min, t_max), or INF.
float ray_triangle(vec3 o, vec3 d, vec3 p0, vec3 p1, vec3 p2, float t_min, float t_max) {
    vec3 e1 = p1 - p0;
    vec3 e2 = p2 - p0;
    vec3 pv = cross(d, e2);
    float det = dot(e1, pv);
    if (det == 0.0) return INF;
    float inv_det = 1.0 / det;
    vec3 tv = o - p0;
    float u = dot(tv, pv) * inv_det;
    if (u < 0.0 || u > 1.0) return INF;
    vec3 qv = cross(tv, e1);
    float v = dot(d, qv) * inv_det;
    if (v < 0.0 || u + v > 1.0) return INF;
    float t = dot(e2, qv) * inv_det;
    return (t > t_min && t < t_max) ? t : INF;
}

// Nearest root in (t_min, t_max); the form of Haines et al., Ray Tracing Gems ch. 7, keeps
// precision when the sphere is small compared with its distance.
float ray_sphere(vec3 o, vec3 d, vec3 c, float r, float t_min, float t_max) {
    vec3 f = o - c;
    float b = dot(f, d);
    vec3 l = f - b * d;
    float disc = r * r - dot(l, l);
    if (disc < 0.0) return INF;
    float s = sqrt(disc);
    float t0 = -b - s;
    float t1 = -b + s;
    float t = t0 > t_min ? t0 : t1;
    return (t > t_min && t < t_max) ? t : INF;
}

// Rows of the affine map at shape_word(a) (3x4) applied to a point, to a vector, and its
// transposed linear part applied to a vector (object normals to the world with object_from_world).
// The analytic shapes and the instances use them.
vec3 affine_point(uint a, vec3 x) {
    return vec3(shape_word(a) * x.x + shape_word(a + 1u) * x.y + shape_word(a + 2u) * x.z + shape_word(a + 3u),
                shape_word(a + 4u) * x.x + shape_word(a + 5u) * x.y + shape_word(a + 6u) * x.z + shape_word(a + 7u),
                shape_word(a + 8u) * x.x + shape_word(a + 9u) * x.y + shape_word(a + 10u) * x.z + shape_word(a + 11u));
}
vec3 affine_vector(uint a, vec3 v) {
    return vec3(shape_word(a) * v.x + shape_word(a + 1u) * v.y + shape_word(a + 2u) * v.z,
                shape_word(a + 4u) * v.x + shape_word(a + 5u) * v.y + shape_word(a + 6u) * v.z,
                shape_word(a + 8u) * v.x + shape_word(a + 9u) * v.y + shape_word(a + 10u) * v.z);
}
vec3 affine_transpose_vector(uint a, vec3 v) {
    return vec3(shape_word(a), shape_word(a + 1u), shape_word(a + 2u)) * v.x
         + vec3(shape_word(a + 4u), shape_word(a + 5u), shape_word(a + 6u)) * v.y
         + vec3(shape_word(a + 8u), shape_word(a + 9u), shape_word(a + 10u)) * v.z;
}

#ifdef VARIANT_ANALYTIC
// Analytic shapes (plane, disc, cone, torus, superellipsoid), intersected in their object space.
// Only the `analytic` variant of the scene kernels has them: lavapipe compiles and runs every
// branch under masks, so scenes without them keep kernels without their code. Each function
// explains itself at its twin in src/cpu/shape.rs.

float ray_plane(vec3 o, vec3 d, float t_min, float t_max) {
    float t = -o.y / d.y;
    return (t > t_min && t < t_max) ? t : INF;
}

float ray_disc(vec3 o, vec3 d, float radius, float inner, float t_min, float t_max) {
    float t = ray_plane(o, d, t_min, t_max);
    float x = o.x + t * d.x;
    float z = o.z + t * d.z;
    float r2 = x * x + z * z;
    return (r2 <= radius * radius && r2 >= inner * inner) ? t : INF;
}

float ray_cone(vec3 o, vec3 d, float r0, float r1, float h, float t_min, float t_max) {
    vec3 c = vec3(0.0, 0.5 * h, 0.0);
    float ts = dot(c - o, d) / dot(d, d);
    vec3 p = o + ts * d;
    float rb = max(r0, r1);
    vec3 pc = p - c;
    if (dot(pc, pc) > rb * rb + 0.25 * h * h) return INF;
    float k = (r1 - r0) / h;
    float rho = r0 + k * p.y;
    float a = d.x * d.x + d.z * d.z - k * k * d.y * d.y;
    float b = 2.0 * (p.x * d.x + p.z * d.z - k * rho * d.y);
    float cc = p.x * p.x + p.z * p.z - rho * rho;
    float disc = b * b - 4.0 * a * cc;
    if (disc < 0.0) return INF;
    float sq = sqrt(disc);
    float q = -0.5 * (b + (b >= 0.0 ? sq : -sq));
    float s0 = q / a;
    float s1 = cc / q;
    if (s0 > s1) { float tmp = s0; s0 = s1; s1 = tmp; }
    float t0 = ts + s0;
    float y0 = p.y + s0 * d.y;
    if (t0 > t_min && t0 < t_max && y0 >= 0.0 && y0 <= h) return t0;
    float t1 = ts + s1;
    float y1 = p.y + s1 * d.y;
    if (t1 > t_min && t1 < t_max && y1 >= 0.0 && y1 <= h) return t1;
    return INF;
}

// The torus and the superellipsoid: only in the `implicit` variant (their root finders are the
// largest code of all, and lavapipe pays for code size in every ray).
#ifdef VARIANT_IMPLICIT
// (value, derivative) at x of lead x^4 + c.w x^3 + c.z x^2 + c.y x + c.x.
vec2 poly4(float lead, vec4 c, float x) {
    float f = (((lead * x + c.w) * x + c.z) * x + c.y) * x + c.x;
    float df = ((4.0 * lead * x + 3.0 * c.w) * x + 2.0 * c.z) * x + c.y;
    return vec2(f, df);
}

float poly_root_in(float lead, vec4 c, float a, float b, float none) {
    float fa = poly4(lead, c, a).x;
    float fb = poly4(lead, c, b).x;
    if ((fa < 0.0) == (fb < 0.0)) return none;
    float lo = a;
    float hi = b;
    float x = 0.5 * (a + b);
    for (uint k = 0u; k < TORUS_ROOT_STEPS; k++) {
        vec2 f = poly4(lead, c, x);
        if ((f.x < 0.0) == (fa < 0.0)) lo = x; else hi = x;
        float next = x - f.x / f.y;
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        bool done = abs(next - x) <= 1e-7;
        x = next;
        if (done) break;
    }
    return x;
}

float ray_torus(vec3 o, vec3 d, float big_r, float small_r, float t_min, float t_max) {
    float scale = big_r + small_r;
    float len = length(d);
    vec3 dn = d / len;
    float tc = -dot(o, dn);
    vec3 p = (o + tc * dn) / scale;
    float m2 = dot(p, p);
    float reach = TORUS_CHORD * TORUS_CHORD;
    if (m2 >= reach) return INF;
    float hi = sqrt(reach - m2);
    float lo = -hi;
    if (!((tc + scale * hi) / len > t_min && (tc + scale * lo) / len < t_max)) return INF;
    float br = big_r / scale;
    float sr = small_r / scale;
    float g = m2 + br * br - sr * sr;
    float k = dot(p, dn);
    float four_r2 = 4.0 * br * br;
    vec4 c = vec4(g * g - four_r2 * (p.x * p.x + p.z * p.z),
                  4.0 * k * g - 2.0 * four_r2 * (p.x * dn.x + p.z * dn.z),
                  4.0 * k * k + 2.0 * g - four_r2 * (dn.x * dn.x + dn.z * dn.z),
                  4.0 * k);
    float qa = 12.0;
    float qb = 6.0 * c.w;
    float qc = 2.0 * c.z;
    float disc = qb * qb - 4.0 * qa * qc;
    float x1 = lo;
    float x2 = lo;
    if (disc > 0.0) {
        float sq = sqrt(disc);
        float q = -0.5 * (qb + (qb >= 0.0 ? sq : -sq));
        float ra = q / qa;
        float rb = qc / q;
        x1 = clamp(min(ra, rb), lo, hi);
        x2 = clamp(max(ra, rb), lo, hi);
    }
    vec4 dc = vec4(c.y, 2.0 * c.z, 3.0 * c.w, 4.0);
    float e0 = lo;
    float e1 = x1;
    float e2 = x2;
    float t = INF;
    for (uint k = 0u; k < 7u; k++) {
        bool derivative = k < 3u;
        uint j = derivative ? k : k - 3u;
        float a = j == 0u ? lo : (j == 1u ? (derivative ? x1 : e0) : (j == 2u ? (derivative ? x2 : e1) : e2));
        float b = j == 0u ? (derivative ? x1 : e0) : (j == 1u ? (derivative ? x2 : e1) : (j == 2u ? (derivative ? hi : e2) : hi));
        float none = derivative ? a : INF;
        bool search = derivative || ((tc + scale * b) / len > t_min && (tc + scale * a) / len < t_max);
        float r = none;
        if (search) r = poly_root_in(derivative ? 0.0 : 1.0, derivative ? dc : c, a, b, none);
        if (k == 0u) e0 = r;
        if (k == 1u) e1 = r;
        if (k == 2u) e2 = r;
        float tk = (tc + scale * r) / len;
        if (!derivative && r != INF && tk > t_min) {
            t = tk;
            break;
        }
    }
    return t < t_max ? t : INF;
}

float safe_pow(float x, float y) {
    return exp2(y * log2(max(x, 1e-30)));
}

// The superellipsoid's gauge h (w) and its gradient (xyz). ex = (2/e, e/2, 2/n, n/2).
vec4 superellipsoid_gauge(vec3 p, vec4 ex) {
    vec3 a = abs(p);
    float m = max(a.x, a.y);
    float rho = m * safe_pow(1.0 + safe_pow(min(a.x, a.y) / max(m, 1e-30), ex.x), ex.y);
    float big = max(rho, a.z);
    float h = big * safe_pow(1.0 + safe_pow(min(rho, a.z) / max(big, 1e-30), ex.z), ex.w);
    float hs = max(h, 1e-30);
    float rs = max(rho, 1e-30);
    float hr = safe_pow(rho / hs, ex.z - 1.0);
    vec3 grad = vec3(hr * safe_pow(a.x / rs, ex.x - 1.0) * sign(p.x),
                     hr * safe_pow(a.y / rs, ex.x - 1.0) * sign(p.y),
                     safe_pow(a.z / hs, ex.z - 1.0) * sign(p.z));
    return vec4(grad, h);
}


float ray_superellipsoid(vec3 o, vec3 d, vec4 ex, float t_min, float t_max) {
    vec3 inv = 1.0 / d;
    vec3 ta = (vec3(-SUPERELLIPSOID_BOX) - o) * inv;
    vec3 tb = (vec3(SUPERELLIPSOID_BOX) - o) * inv;
    vec3 tn = min(ta, tb);
    vec3 tf = max(ta, tb);
    float t_in = max(max(tn.x, tn.y), tn.z);
    float t_out = min(min(tf.x, tf.y), tf.z);
    if (!(t_in < t_out && t_out > t_min && t_in < t_max)) return INF;
    if (t_min > t_in) {
        vec4 g = superellipsoid_gauge(o + t_min * d, ex);
        if (g.w - 1.0 > 2.0 * SUPERELLIPSOID_TOLERANCE && dot(g.xyz, d) >= 0.0) return INF;
    }
    vec3 p = o + t_in * d;
    float span = t_out - t_in;
    float s = 0.0;
    bool forward = true;
    float t = INF;
    for (uint k = 0u; k < 2u * SUPERELLIPSOID_STEPS; k++) {
        vec4 g = superellipsoid_gauge(p + s * d, ex);
        float phi = g.w - 1.0;
        float slope = dot(g.xyz, d);
        if (phi <= SUPERELLIPSOID_TOLERANCE) {
            t = t_in + s;
            if (!forward || t > t_min) break;
            forward = false;
            s = span;
            continue;
        }
        if (forward ? slope >= 0.0 : slope <= 0.0) break;
        s -= phi / slope;
        if (!(s >= 0.0 && s <= span)) break;
    }
    return (t > t_min && t < t_max) ? t : INF;
}

#endif

float analytic_intersect(Primitive p, vec3 o, vec3 d, float t_min, float t_max) {
    uint a = p.data + SHAPE_DATA_OBJECT_FROM_WORLD;
    vec3 oo = affine_point(a, o);
    vec3 od = affine_vector(a, d);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    float t = INF;
    WHEN(kind == PRIMITIVE_PLANE) { t = ray_plane(oo, od, t_min, t_max); }
    WHEN(kind == PRIMITIVE_DISC) { t = ray_disc(oo, od, p.p0[0], p.p0[1], t_min, t_max); }
    WHEN(kind == PRIMITIVE_CONE) { t = ray_cone(oo, od, p.p0[0], p.p0[1], p.p0[2], t_min, t_max); }
#ifdef VARIANT_IMPLICIT
    WHEN(kind == PRIMITIVE_TORUS) { t = ray_torus(oo, od, p.p0[0], p.p0[1], t_min, t_max); }
    WHEN(kind == PRIMITIVE_SUPERELLIPSOID) {
        t = ray_superellipsoid(oo, od, vec4(p.p0[0], p.p0[1], p.p0[2], p.p1[0]), t_min, t_max);
    }
#endif
    return t;
}
#endif

// Distance to the first surface of primitive i along o + t d with t in (t_min, t_max), or INF.
float shape_intersect(uint i, vec3 o, vec3 d, float t_min, float t_max) {
    Primitive p = primitive_at(i);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
#ifdef VARIANT_ANALYTIC
    float t = INF;
    WHEN(kind > PRIMITIVE_SPHERE) { t = analytic_intersect(p, o, d, t_min, t_max); }
    if (kind > PRIMITIVE_SPHERE) return t;
#endif
    if (kind == PRIMITIVE_SPHERE) return ray_sphere(o, d, load3(p.p0), p.p1[0], t_min, t_max);
    return ray_triangle(o, d, load3(p.p0), load3(p.p1), load3(p.p2), t_min, t_max);
}

// dpdu and dpdv of a flat triangle with vertex uvs (pbrt-v4's Triangle::InteractionFromIntersection);
// a frame around ng when the uvs are degenerate.
void triangle_derivatives(vec3 p0, vec3 p1, vec3 p2, vec2 uv0, vec2 uv1, vec2 uv2, vec3 ng, out vec3 dpdu, out vec3 dpdv) {
    vec2 duv02 = uv0 - uv2;
    vec2 duv12 = uv1 - uv2;
    vec3 dp02 = p0 - p2;
    vec3 dp12 = p1 - p2;
    float det = duv02.x * duv12.y - duv02.y * duv12.x;
    if (abs(det) > 1e-12) {
        float inv = 1.0 / det;
        dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
        dpdv = (duv02.x * dp12 - duv12.x * dp02) * inv;
        if (length(cross(dpdu, dpdv)) > 0.0) return;
    }
    onb(ng, dpdu, dpdv);
}

// The three vertex uvs of triangle p: from the shape data, else the barycentric default
// (0, 0), (1, 0), (0, 1).
void triangle_uvs(Primitive p, out vec2 uv0, out vec2 uv1, out vec2 uv2) {
    if (p.data == NO_DATA) {
        uv0 = vec2(0.0); uv1 = vec2(1.0, 0.0); uv2 = vec2(0.0, 1.0);
        return;
    }
    uint a = p.data;
    uv0 = vec2(shape_word(a), shape_word(a + 1u));
    uv1 = vec2(shape_word(a + 2u), shape_word(a + 3u));
    uv2 = vec2(shape_word(a + 4u), shape_word(a + 5u));
}

// The shading normal of smooth triangle p at x (barycentrics b), and h.shift; projects dpdu and
// dpdv onto the shading normal's tangent plane (see the twin for the method and its sources).
vec3 triangle_smooth(Primitive p, vec3 x, vec3 b, vec3 p0, vec3 p1, vec3 p2, inout Hit h) {
    uint a = p.data + TRIANGLE_DATA_NORMALS;
    vec3 n0 = vec3(shape_word(a), shape_word(a + 1u), shape_word(a + 2u));
    vec3 n1 = vec3(shape_word(a + 3u), shape_word(a + 4u), shape_word(a + 5u));
    vec3 n2 = vec3(shape_word(a + 6u), shape_word(a + 7u), shape_word(a + 8u));
    vec3 n = b.x * n0 + b.y * n1 + b.z * n2;
    float len = length(n);
    n = len > 0.0 ? n / len : h.ng;
    if (!(dot(n, h.ng) > 0.0)) n = h.ng;
    h.shift = -(b.x * min(0.0, dot(x - p0, n0)) * n0 + b.y * min(0.0, dot(x - p1, n1)) * n1
              + b.z * min(0.0, dot(x - p2, n2)) * n2);
    h.dpdu -= n * dot(n, h.dpdu);
    h.dpdv -= n * dot(n, h.dpdv);
    return n;
}

// Longitude/latitude uv of unit vector `w` (object space, +y the pole): u grows with the angle
// atan2(x, z) from 0 at -z, v from 0 at the south pole to 1 at the north pole. Sets the
// derivatives of the unit direction along u and v.
vec2 sphere_uv(vec3 w, out vec3 dwdu, out vec3 dwdv) {
    float rho = sqrt(w.x * w.x + w.z * w.z);
    float u = 0.5 + atan(w.x, w.z) * (0.5 / PI);
    float v = 0.5 + asin(clamp(w.y, -1.0, 1.0)) / PI;
    dwdu = 2.0 * PI * vec3(w.z, 0.0, -w.x);
    dwdv = rho > 0.0 ? PI * vec3(-w.y * w.x / rho, rho, -w.y * w.z / rho) : vec3(0.0);
    return vec2(u, v);
}

// A sphere's object_from_world rotation (rows in the shape data), identity without data.
mat3 sphere_rotation(Primitive p) {
    if (p.data == NO_DATA) return mat3(1.0);
    uint a = p.data;
    // GLSL matrices are column-major: the transposed rows are its columns.
    return transpose(mat3(shape_word(a), shape_word(a + 1u), shape_word(a + 2u),
                          shape_word(a + 3u), shape_word(a + 4u), shape_word(a + 5u),
                          shape_word(a + 6u), shape_word(a + 7u), shape_word(a + 8u)));
}

#ifdef VARIANT_ANALYTIC
// The surface fields of h at world point x of analytic primitive p, x projected onto the
// surface in object space (see the twin for why).
void analytic_surface(Primitive p, vec3 x, bool wants_uv, inout Hit h) {
    uint ow = p.data + SHAPE_DATA_OBJECT_FROM_WORLD;
    uint wo = p.data + SHAPE_DATA_WORLD_FROM_OBJECT;
    float size = shape_word(p.data + SHAPE_DATA_SIZE);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    vec3 q = affine_point(ow, x);
    vec3 n = vec3(0.0, 1.0, 0.0);
    vec2 uv = vec2(0.0);
    vec3 dqdu = vec3(0.0);
    vec3 dqdv = vec3(0.0);
    float rho = sqrt(q.x * q.x + q.z * q.z);
    float sin_phi = rho > 0.0 ? q.x / rho : 0.0;
    float cos_phi = rho > 0.0 ? q.z / rho : 1.0;
    float u_around = 0.5 + atan(q.x, q.z) * (0.5 / PI);
    WHEN(kind == PRIMITIVE_PLANE) {
        q.y = 0.0;
        uv = vec2(q.x, -q.z);
        dqdu = vec3(1.0, 0.0, 0.0);
        dqdv = vec3(0.0, 0.0, -1.0);
    }
    WHEN(kind == PRIMITIVE_DISC) {
        q.y = 0.0;
        float r = p.p0[0];
        float ri = p.p0[1];
        uv = vec2(u_around, (r - rho) / (r - ri));
        dqdu = 2.0 * PI * vec3(q.z, 0.0, -q.x);
        dqdv = -(r - ri) * vec3(sin_phi, 0.0, cos_phi);
    }
    WHEN(kind == PRIMITIVE_CONE) {
        float r0 = p.p0[0];
        float r1 = p.p0[1];
        float height = p.p0[2];
        float y = clamp(q.y, 0.0, height);
        float radius = r0 + (r1 - r0) * (y / height);
        q = vec3(radius * sin_phi, y, radius * cos_phi);
        n = vec3(height * sin_phi, -(r1 - r0), height * cos_phi);
        uv = vec2(u_around, y / height);
        dqdu = 2.0 * PI * vec3(q.z, 0.0, -q.x);
        dqdv = vec3((r1 - r0) * sin_phi, height, (r1 - r0) * cos_phi);
    }
#ifdef VARIANT_IMPLICIT
    WHEN(kind == PRIMITIVE_TORUS) {
        float big_r = p.p0[0];
        float small_r = p.p0[1];
        vec3 out_dir = vec3(sin_phi, 0.0, cos_phi);
        vec3 ring = big_r * out_dir;
        vec3 w = q - ring;
        float wl = length(w);
        w = wl > 0.0 ? w / wl : out_dir;
        q = ring + small_r * w;
        n = w;
        float cos_psi = dot(w, out_dir);
        uv = vec2(u_around, 0.5 + atan(w.y, cos_psi) * (0.5 / PI));
        dqdu = 2.0 * PI * vec3(q.z, 0.0, -q.x);
        dqdv = 2.0 * PI * small_r * vec3(-w.y * sin_phi, cos_psi, -w.y * cos_phi);
    }
    WHEN(kind == PRIMITIVE_SUPERELLIPSOID) {
        vec4 ex = vec4(p.p0[0], p.p0[1], p.p0[2], p.p1[0]);
        q /= max(superellipsoid_gauge(q, ex).w, 1e-30);
        vec3 g = superellipsoid_gauge(q, ex).xyz;
        n = g;
        float r = length(q);
        vec3 w = q / r;
        vec3 dwdu, dwdv;
        uv = sphere_uv(vec3(w.y, w.z, w.x), dwdu, dwdv);
        dwdu = vec3(dwdu.z, dwdu.x, dwdu.y);
        dwdv = vec3(dwdv.z, dwdv.x, dwdv.y);
        dqdu = r * (dwdu - q * dot(g, dwdu));
        dqdv = r * (dwdv - q * dot(g, dwdv));
    }
#endif
    h.p = affine_point(wo, q);
    h.ng = normalize(affine_transpose_vector(ow, n));
    if (wants_uv) {
        h.uv = uv;
        h.dpdu = affine_vector(wo, dqdu);
        h.dpdv = affine_vector(wo, dqdv);
        if (length(cross(h.dpdu, h.dpdv)) == 0.0) onb(h.ng, h.dpdu, h.dpdv);
    }
    vec3 ap = abs(h.p);
    h.eps = SHAPE_EPSILON_SCALE * (max(max(ap.x, ap.y), ap.z) + size);
}

// A point of analytic primitive p for u in the world, and 1/pdf by world area.
vec3 analytic_sample(Primitive p, vec2 u, out float inv_pdf) {
    uint ow = p.data + SHAPE_DATA_OBJECT_FROM_WORLD;
    uint wo = p.data + SHAPE_DATA_WORLD_FROM_OBJECT;
    float det = shape_word(p.data + SHAPE_DATA_DET);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    float phi = 2.0 * PI * u.y;
    float sin_phi = sin(phi);
    float cos_phi = cos(phi);
    vec3 q = vec3(0.0);
    vec3 n = vec3(0.0, 1.0, 0.0);
    float inv = 0.0;
    WHEN(kind == PRIMITIVE_DISC) {
        float r = p.p0[0];
        float ri = p.p0[1];
        float rho = sqrt(ri * ri + u.x * (r * r - ri * ri));
        q = vec3(rho * sin_phi, 0.0, rho * cos_phi);
        inv = PI * (r * r - ri * ri);
    }
    WHEN(kind == PRIMITIVE_CONE) {
        float r0 = p.p0[0];
        float r1 = p.p0[1];
        float height = p.p0[2];
        float den = r0 + sqrt(r0 * r0 + u.x * (r1 * r1 - r0 * r0));
        float v = den > 0.0 ? u.x * (r0 + r1) / den : 0.0;
        float rho = r0 + (r1 - r0) * v;
        float slant = sqrt(height * height + (r1 - r0) * (r1 - r0));
        n = vec3(height * sin_phi, -(r1 - r0), height * cos_phi) / slant;
        q = vec3(rho * sin_phi, v * height, rho * cos_phi);
        inv = PI * (r0 + r1) * slant;
    }
#ifdef VARIANT_IMPLICIT
    WHEN(kind == PRIMITIVE_TORUS) {
        float big_r = p.p0[0];
        float small_r = p.p0[1];
        float theta = 2.0 * PI * u.x;
        float sin_theta = sin(theta);
        float cos_theta = cos(theta);
        n = vec3(cos_phi * sin_theta, sin_phi, cos_phi * cos_theta);
        q = big_r * vec3(sin_theta, 0.0, cos_theta) + small_r * n;
        inv = 4.0 * PI * PI * small_r * (big_r + small_r * cos_phi);
    }
    WHEN(kind == PRIMITIVE_SUPERELLIPSOID) {
        vec4 ex = vec4(p.p0[0], p.p0[1], p.p0[2], p.p1[0]);
        vec3 w = sphere_direction(u);
        vec4 g = superellipsoid_gauge(w, ex);
        float r = 1.0 / g.w;
        q = w * r;
        n = g.xyz;
        inv = 4.0 * PI * length(g.xyz) * r * r * r;
    }
#endif
    vec3 nw = affine_transpose_vector(ow, n);
    inv_pdf = inv * det * length(nw) / length(n);
    return affine_point(wo, q);
}
#endif

// Fills the surface fields of h for point x on primitive i (x is on the surface).
void shape_surface(uint i, vec3 x, inout Hit h) {
    Primitive p = primitive_at(i);
    h.p = x;
    h.prim = i;
    h.material = p.material;
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    bool wants_uv = (p.kind & PRIMITIVE_FLAG_UV) != 0u;
    h.uv = vec2(0.0);
    h.dpdu = vec3(0.0);
    h.dpdv = vec3(0.0);
    h.eps = frame.ray_epsilon;
    WHEN(kind == PRIMITIVE_SPHERE) {
        vec3 c = load3(p.p0);
        h.ng = normalize(x - c);
        WHEN(wants_uv) {
            float r = p.p1[0];
            mat3 object_from_world = sphere_rotation(p);
            vec3 dwdu, dwdv;
            h.uv = sphere_uv(object_from_world * h.ng, dwdu, dwdv);
            h.dpdu = r * (transpose(object_from_world) * dwdu);
            h.dpdv = r * (transpose(object_from_world) * dwdv);
            if (length(cross(h.dpdu, h.dpdv)) == 0.0) onb(h.ng, h.dpdu, h.dpdv);
        }
    }
    bool is_smooth = (p.kind & PRIMITIVE_FLAG_SMOOTH) != 0u;
    vec3 ns = vec3(0.0);
    h.shift = vec3(0.0);
    WHEN(kind == PRIMITIVE_TRIANGLE) {
        vec3 p0 = load3(p.p0), p1 = load3(p.p1), p2 = load3(p.p2);
        vec3 e1 = p1 - p0, e2 = p2 - p0;
        h.ng = normalize(cross(e1, e2));
        WHEN(wants_uv || is_smooth) {
            // Barycentrics of x from the normal equations of x - p0 = b1 e1 + b2 e2.
            vec3 v = x - p0;
            float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2);
            float d20 = dot(v, e1), d21 = dot(v, e2);
            float inv = 1.0 / (d00 * d11 - d01 * d01);
            float b1 = (d11 * d20 - d01 * d21) * inv;
            float b2 = (d00 * d21 - d01 * d20) * inv;
            WHEN(wants_uv) {
                vec2 uv0, uv1, uv2;
                triangle_uvs(p, uv0, uv1, uv2);
                h.uv = (1.0 - b1 - b2) * uv0 + b1 * uv1 + b2 * uv2;
                triangle_derivatives(p0, p1, p2, uv0, uv1, uv2, h.ng, h.dpdu, h.dpdv);
            }
            WHEN(is_smooth) { ns = triangle_smooth(p, x, vec3(1.0 - b1 - b2, b1, b2), p0, p1, p2, h); }
        }
    }
#ifdef VARIANT_ANALYTIC
    WHEN(kind > PRIMITIVE_SPHERE) { analytic_surface(p, x, wants_uv, h); }
#endif
    h.ns = is_smooth ? ns : h.ng;
    // A leaf on the subtracted side of a CSG difference: the solid lies on its other side.
    if ((p.kind & PRIMITIVE_FLAG_CSG_FLIP) != 0u) {
        h.ng = -h.ng;
        h.ns = -h.ns;
        h.dpdv = -h.dpdv;
    }
}

// Instances (twin: src/cpu/instance.rs, which explains them). A hit on primitive p of instance k
// is named (k + 1) * frame.primitive_count + p; names below primitive_count are the world's.

// The instance of hit name id, or NO_DATA for a primitive of the world.
uint hit_instance(uint id) {
    return (!SCENE_HAS_INSTANCES || frame.instance_count == 0u || id < frame.primitive_count) ? NO_DATA : id / frame.primitive_count - 1u;
}

// The primitive a hit name refers to.
uint hit_primitive(uint id) {
    uint k = hit_instance(id);
    return k == NO_DATA ? id : id - (k + 1u) * frame.primitive_count;
}

// Offset of instance k's record in the shape data (INSTANCE_DATA_*).
uint instance_record(uint k) {
    return frame.instance_data + k * INSTANCE_DATA_FLOATS;
}

// h, filled in object space at the object point of world point x, moved to the world by the
// instance whose record is at a (see the twin's to_world).
void instance_to_world(uint a, vec3 x, uint kind, inout Hit h) {
    uint ofw = a + INSTANCE_DATA_OBJECT_FROM_WORLD;
    uint wfo = a + INSTANCE_DATA_WORLD_FROM_OBJECT;
    // The analytic shapes' point projected onto the surface, moved back (see the twin).
    h.p = kind > PRIMITIVE_SPHERE ? affine_point(wfo, h.p) : x;
    h.ng = normalize(affine_transpose_vector(ofw, h.ng));
    h.ns = normalize(affine_transpose_vector(ofw, h.ns));
    h.dpdu = affine_vector(wfo, h.dpdu);
    h.dpdv = affine_vector(wfo, h.dpdv);
    h.shift = affine_vector(wfo, h.shift);
    if (kind > PRIMITIVE_SPHERE) {
        vec3 ax = abs(x);
        h.eps = max(h.eps * shape_word(a + INSTANCE_DATA_SCALE), SHAPE_EPSILON_SCALE * max(max(ax.x, ax.y), ax.z));
    }
    uint material = floatBitsToUint(shape_word(a + INSTANCE_DATA_MATERIAL));
    if (material != NO_DATA) h.material = material;
}

// The hit record of the ray o + t d on primitive i, or on an instance's primitive (i a hit
// name): filled at the object point, then moved to the world.
Hit shape_hit(uint i, vec3 o, vec3 d, float t) {
    Hit h;
    vec3 x = o + t * d;
    uint k = hit_instance(i);
    uint prim = hit_primitive(i);
    uint a = 0u;
    vec3 xo = x;
    WHEN(k != NO_DATA) {
        a = instance_record(k);
        xo = affine_point(a + INSTANCE_DATA_OBJECT_FROM_WORLD, x);
    }
    shape_surface(prim, xo, h);
    WHEN(k != NO_DATA) { instance_to_world(a, x, primitive_kind(prim) & PRIMITIVE_KIND_MASK, h); }
    h.prim = i;
    return h;
}

// A point p of the cap of the sphere (centre c, radius r) that x sees, drawn uniformly in the
// cap's solid angle (pbrt-v4's Sphere::Sample, after Shirley's cone sampling); returns the cap's
// solid angle, 1/pdf, or 0 where x is inside the sphere (the caller then samples by area).
// Every sample from outside lands on a face x sees, where by area half of them fall behind.
// CPU twin: src/cpu/shape.rs, sphere_cap_point.
float sphere_cap_point(vec3 c, float r, vec3 x, vec2 u, out vec3 p) {
    p = c;
    vec3 to_c = c - x;
    float d2 = dot(to_c, to_c);
    if (d2 <= 1.0001 * r * r) return 0.0;
    float sin2_max = r * r / d2;
    float sin_max = sqrt(sin2_max);
    float cos_max = sqrt(max(1.0 - sin2_max, 0.0));
    float one_minus_cos_max = 1.0 - cos_max;
    float cos_t = (cos_max - 1.0) * u.x + 1.0;
    float sin2_t = 1.0 - cos_t * cos_t;
    // A far, small sphere: 1 - cos_max cancels in single precision; its series instead.
    if (sin2_max < 0.00068523) {
        sin2_t = sin2_max * u.x;
        cos_t = sqrt(1.0 - sin2_t);
        one_minus_cos_max = 0.5 * sin2_max;
    }
    // The angle at the centre between x and the point whose direction from x makes angle t.
    float cos_a = sin2_t / sin_max + cos_t * sqrt(max(1.0 - sin2_t / sin2_max, 0.0));
    float sin_a = sqrt(max(1.0 - cos_a * cos_a, 0.0));
    float phi = 2.0 * PI * u.y;
    vec3 z = to_c / sqrt(d2);
    vec3 t, b;
    onb(z, t, b);
    p = c - r * (sin_a * cos(phi) * t + sin_a * sin(phi) * b + cos_a * z);
    return 2.0 * PI * one_minus_cos_max;
}

// A point on primitive i for the uniform numbers u, as a hit record, and 1/pdf of such points
// by area (see the twin): triangles (Turk 1990) and spheres uniformly, so 1/pdf is their area.
Hit shape_sample(uint i, vec2 u, out float inv_pdf) {
    Primitive p = primitive_at(i);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    vec3 x;
    if (kind == PRIMITIVE_SPHERE) {
        float r = p.p1[0];
        x = load3(p.p0) + r * sphere_direction(u);
        inv_pdf = 4.0 * PI * r * r;
    } else {
        float su = sqrt(u.x);
        float b0 = 1.0 - su;
        float b1 = u.y * su;
        vec3 p0 = load3(p.p0), p1 = load3(p.p1), p2 = load3(p.p2);
        x = b0 * p0 + b1 * p1 + (1.0 - b0 - b1) * p2;
        inv_pdf = 0.5 * length(cross(p1 - p0, p2 - p0));
    }
#ifdef VARIANT_ANALYTIC
    WHEN(kind > PRIMITIVE_SPHERE) { x = analytic_sample(p, u, inv_pdf); }
#endif
    Hit h;
    shape_surface(i, x, h);
    return h;
}

// shape_sample as seen from x: a sphere seen from outside by the solid angle of the cap x sees
// (`solid_angle` that cap's solid angle, 1/pdf by solid angle; inv_pdf unset), any other shape,
// or a sphere from inside, by shape_sample (`solid_angle` 0, inv_pdf by area).
// CPU twin: src/cpu/shape.rs, shape_sample_from.
Hit shape_sample_from(uint i, vec3 x, vec2 u, out float inv_pdf, out float solid_angle) {
    solid_angle = 0.0;
    inv_pdf = 0.0;
    if ((primitive_kind(i) & PRIMITIVE_KIND_MASK) == PRIMITIVE_SPHERE) {
        Primitive p = primitive_at(i);
        vec3 cap;
        solid_angle = sphere_cap_point(load3(p.p0), p.p1[0], x, u, cap);
        if (solid_angle > 0.0) {
            Hit h;
            shape_surface(i, cap, h);
            return h;
        }
    }
    return shape_sample(i, u, inv_pdf);
}
