// Ray casting against the flattened BVH. CPU twin: src/cpu/trace.rs.
// The including kernel declares `BvhNode nodes[]` and `Primitive primitives[]`.
// Directions are unit length; rays start at their origin (callers offset origins off surfaces).

const float INF = 1.0 / 0.0;

// Distance at which the ray enters the box, or INF when it misses it within [0, t_max).
float ray_box(vec3 o, vec3 inv_d, vec3 lo, vec3 hi, float t_max) {
    vec3 t0 = (lo - o) * inv_d;
    vec3 t1 = (hi - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float leave = min(min(tf.x, tf.y), min(tf.z, t_max));
    return enter <= leave ? enter : INF;
}

// Möller and Trumbore 1997, two-sided. Returns the hit distance, or INF.
float ray_triangle(vec3 o, vec3 d, vec3 p0, vec3 p1, vec3 p2, float t_max) {
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
    return (t > 0.0 && t < t_max) ? t : INF;
}

// Nearest positive root; the form of Haines et al., Ray Tracing Gems ch. 7, keeps precision
// when the sphere is small compared with its distance.
float ray_sphere(vec3 o, vec3 d, vec3 c, float r, float t_max) {
    vec3 f = o - c;
    float b = dot(f, d);
    vec3 l = f - b * d;
    float disc = r * r - dot(l, l);
    if (disc < 0.0) return INF;
    float s = sqrt(disc);
    float t0 = -b - s;
    float t1 = -b + s;
    float t = t0 > 0.0 ? t0 : t1;
    return (t > 0.0 && t < t_max) ? t : INF;
}

float ray_primitive(uint i, vec3 o, vec3 d, float t_max) {
    Primitive p = primitives[i];
    if (p.kind == PRIMITIVE_SPHERE) return ray_sphere(o, d, load3(p.p0), p.p1[0], t_max);
    return ray_triangle(o, d, load3(p.p0), load3(p.p1), load3(p.p2), t_max);
}

// Closest hit in [0, t_max): returns the primitive index or NO_LIGHT (as "none") and sets t_hit.
// With `any_hit` it returns the first hit found (shadow rays). Stackless: a missed box, or a
// finished leaf, continues at the node's miss link.
uint trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out float t_hit) {
    vec3 inv_d = 1.0 / d;
    t_hit = t_max;
    uint hit = NO_LIGHT;
    uint node = 0u;
    while (node < frame.node_count) {
        BvhNode n = nodes[node];
        uint count = n.skip_count & BVH_COUNT_MASK;
        uint skip = n.skip_count >> BVH_COUNT_BITS;
        if (ray_box(o, inv_d, load3(n.aabb_min), load3(n.aabb_max), t_hit) == INF) {
            node = skip;
            continue;
        }
        if (count == 0u) {
            node++;
            continue;
        }
        for (uint i = n.first; i < n.first + count; i++) {
            float t = ray_primitive(i, o, d, t_hit);
            if (t < t_hit) {
                t_hit = t;
                hit = i;
                if (any_hit) return hit;
            }
        }
        node = skip;
    }
    return hit;
}
