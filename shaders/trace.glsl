// Ray casting against the flattened BVH. CPU twin: src/cpu/trace.rs.
// The including kernel declares the scene bindings and includes shape.glsl, texture.glsl and
// bsdf.glsl. Directions are unit length; rays start at their origin (callers offset origins).

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

// Stochastic transparency: the ray passes through primitive i at distance t with probability
// 1 - opacity. Camera rays, shadow rays and photons all decide here.
bool passes_through(uint i, vec3 o, vec3 d, float t) {
    bool passes = false;
    WHEN((primitives[i].kind & PRIMITIVE_FLAG_ALPHA) != 0u) {
        Hit h = shape_hit(i, o, d, t);
        passes = hash_point(h.p, i) >= material_opacity(materials[h.material], h);
    }
    return passes;
}

#ifdef VARIANT_ANALYTIC
#include "csg.glsl"
#endif

// Tests primitive i against the ray and keeps it in (hit, t_hit) when it is closer; the
// primitive `ignore` is not tested (see trace_ray).
void visit(uint i, vec3 o, vec3 d, uint ignore, inout uint hit, inout float t_hit) {
    float t = i == ignore ? INF : shape_intersect(i, o, d, 0.0, t_hit);
#ifdef VARIANT_ALPHA
    // A ray that passes a transparent point may meet the shape again behind it (a
    // sphere's far side); a shape has at most two surfaces along a ray. Alpha lives in
    // its own variant: its test in the innermost loop slows lavapipe down.
    for (uint k = 0u; k < 2u && t < t_hit && passes_through(i, o, d, t); k++) {
        t = shape_intersect(i, o, d, t, t_hit);
    }
#endif
    if (t < t_hit) {
        t_hit = t;
        hit = i;
    }
}

// Closest hit in [0, t_max): returns the primitive index or NO_LIGHT (as "none") and sets t_hit.
// With `any_hit` it returns the first hit found (shadow rays). Primitive `ignore` (NO_LIGHT: none)
// is ignored: the smooth triangle a ray leaves (see the twin). The unbounded primitives (planes,
// after the BVH's, in the analytic variant) come first; then the BVH, stackless: a missed box, or
// a finished leaf, continues at the node's miss link.
uint trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, uint ignore, out float t_hit) {
    vec3 inv_d = 1.0 / d;
    t_hit = t_max;
    uint hit = NO_LIGHT;
#ifdef VARIANT_ANALYTIC
    for (uint i = frame.unbounded_first; i < frame.primitive_count; i++) {
        visit(i, o, d, ignore, hit, t_hit);
        if (any_hit && hit != NO_LIGHT) return hit;
    }
#endif
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
            uint before = hit;
#ifdef VARIANT_ANALYTIC
            // A CSG object reports the leaf primitive it shows (csg.glsl), so callers see an
            // ordinary primitive. Behind WHEN: lavapipe would run its walk under masks for
            // every primitive of every scene of the analytic variant.
            bool is_csg = (primitives[i].kind & PRIMITIVE_KIND_MASK) == PRIMITIVE_CSG;
            WHEN(is_csg) {
                uint leaf;
                float tc = csg_intersect(i, o, d, t_hit, leaf);
                if (tc < t_hit) {
                    t_hit = tc;
                    hit = leaf;
                }
            }
            if (!is_csg)
#endif
            visit(i, o, d, ignore, hit, t_hit);
            if (any_hit && hit != before) return hit;
        }
        node = skip;
    }
    return hit;
}
