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

// Distance to the first surface of primitive i along o + t d with t in (t_min, t_max), or INF.
float shape_intersect(uint i, vec3 o, vec3 d, float t_min, float t_max) {
    Primitive p = primitives[i];
    switch (p.kind & PRIMITIVE_KIND_MASK) {
    case PRIMITIVE_SPHERE:
        return ray_sphere(o, d, load3(p.p0), p.p1[0], t_min, t_max);
    }
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
    uv0 = vec2(shape_data[a], shape_data[a + 1u]);
    uv1 = vec2(shape_data[a + 2u], shape_data[a + 3u]);
    uv2 = vec2(shape_data[a + 4u], shape_data[a + 5u]);
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
    return transpose(mat3(shape_data[a], shape_data[a + 1u], shape_data[a + 2u],
                          shape_data[a + 3u], shape_data[a + 4u], shape_data[a + 5u],
                          shape_data[a + 6u], shape_data[a + 7u], shape_data[a + 8u]));
}

// Fills the surface fields of h for point x on primitive i (x is on the surface).
void shape_surface(uint i, vec3 x, inout Hit h) {
    Primitive p = primitives[i];
    h.p = x;
    h.prim = i;
    h.material = p.material;
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    bool wants_uv = (p.kind & PRIMITIVE_FLAG_UV) != 0u;
    h.uv = vec2(0.0);
    h.dpdu = vec3(0.0);
    h.dpdv = vec3(0.0);
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
    WHEN(kind == PRIMITIVE_TRIANGLE) {
        vec3 p0 = load3(p.p0), p1 = load3(p.p1), p2 = load3(p.p2);
        vec3 e1 = p1 - p0, e2 = p2 - p0;
        h.ng = normalize(cross(e1, e2));
        WHEN(wants_uv) {
            // Barycentrics of x from the normal equations of x - p0 = b1 e1 + b2 e2.
            vec3 v = x - p0;
            float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2);
            float d20 = dot(v, e1), d21 = dot(v, e2);
            float inv = 1.0 / (d00 * d11 - d01 * d01);
            float b1 = (d11 * d20 - d01 * d21) * inv;
            float b2 = (d00 * d21 - d01 * d20) * inv;
            vec2 uv0, uv1, uv2;
            triangle_uvs(p, uv0, uv1, uv2);
            h.uv = (1.0 - b1 - b2) * uv0 + b1 * uv1 + b2 * uv2;
            triangle_derivatives(p0, p1, p2, uv0, uv1, uv2, h.ng, h.dpdu, h.dpdv);
        }
    }
    h.ns = h.ng;
}

// The hit record of the ray o + t d on primitive i.
Hit shape_hit(uint i, vec3 o, vec3 d, float t) {
    Hit h;
    shape_surface(i, o + t * d, h);
    return h;
}

// A point on primitive i, uniform by area (Turk 1990 for triangles), as a hit record.
Hit shape_sample(uint i, vec2 u) {
    Primitive p = primitives[i];
    vec3 x;
    switch (p.kind & PRIMITIVE_KIND_MASK) {
    case PRIMITIVE_SPHERE:
        x = load3(p.p0) + p.p1[0] * sphere_direction(u);
        break;
    default: {
        float su = sqrt(u.x);
        float b0 = 1.0 - su;
        float b1 = u.y * su;
        x = b0 * load3(p.p0) + b1 * load3(p.p1) + (1.0 - b0 - b1) * load3(p.p2);
        break;
    }
    }
    Hit h;
    shape_surface(i, x, h);
    return h;
}
