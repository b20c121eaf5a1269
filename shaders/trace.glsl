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

// Stochastic transparency: the ray passes through the primitive of hit name id at distance t
// with probability 1 - opacity. Camera rays, shadow rays and photons all decide here.
bool passes_through(uint id, vec3 o, vec3 d, float t) {
    bool passes = false;
    WHEN((primitive_kind(hit_primitive(id)) & PRIMITIVE_FLAG_ALPHA) != 0u) {
        Hit h = shape_hit(id, o, d, t);
        passes = hash_point(h.p, id) >= material_opacity(material_at(h.material), h);
    }
    return passes;
}

#ifdef VARIANT_ANALYTIC
#include "csg.glsl"
#endif

// Tests primitive i (hit name id) against the walk's ray (ro, rd: the world's, or an instance's
// object-space form whose distances are len times the world's) and keeps it in (hit, t_hit,
// world distances) when it is closer; the hit name `ignore` is not tested (see trace_ray).
// (o, d) is the world ray.
void visit(uint i, uint id, vec3 ro, vec3 rd, float len, vec3 o, vec3 d, uint ignore, inout uint hit, inout float t_hit) {
    float t_max = t_hit * len;
    float t = id == ignore ? INF : shape_intersect(i, ro, rd, 0.0, t_max);
#ifdef VARIANT_ALPHA
    // A ray that passes a transparent point may meet the shape again behind it (a
    // sphere's far side); a shape has at most two surfaces along a ray. Alpha lives in
    // its own variant: its test in the innermost loop slows lavapipe down.
    for (uint k = 0u; k < 2u && t < t_max && passes_through(id, o, d, t / len); k++) {
        t = shape_intersect(i, ro, rd, t, t_max);
    }
#endif
    t /= len;
    if (t < t_hit) {
        t_hit = t;
        hit = id;
    }
}

// Closest hit in [0, t_max): returns the hit name or NO_LIGHT (as "none") and sets t_hit.
// With `any_hit` it returns the first hit found (shadow rays). Hit name `ignore` (NO_LIGHT: none)
// is ignored: the smooth triangle a ray leaves (see the twin). The unbounded primitives (planes,
// after the BVH's, in the analytic variant) come first; then the BVH, stackless: a missed box, or
// a finished leaf, continues at the node's miss link. With instances, the top level follows the
// world's BVH and each of its leaves walks its instance's object in object space, in the same
// loop of at most TRACE_STEPS turns (see the twin).
uint trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, uint ignore, out float t_hit) {
    t_hit = t_max;
    uint hit = NO_LIGHT;
#ifdef VARIANT_ANALYTIC
    for (uint i = frame.unbounded_first; i < frame.csg_first; i++) {
        visit(i, i, o, d, 1.0, o, d, ignore, hit, t_hit);
        if (any_hit && hit != NO_LIGHT) return hit;
    }
#endif
    uint flat_end = bvh_node_skip_count(0u) >> BVH_COUNT_BITS;
    // Without instances node flat_end does not exist: only read it behind a loop of one turn
    // (a select would read it unconditionally).
    uint world_end = flat_end;
    WHEN(SCENE_HAS_INSTANCES && frame.instance_count > 0u) { world_end = bvh_node_skip_count(flat_end) >> BVH_COUNT_BITS; }
    vec3 ro = o;
    vec3 rd = d;
    vec3 inv_d = 1.0 / d;
    float len = 1.0;
    uint base = 0u;
    uint resume = NO_DATA;
    uint end = world_end;
    uint node = 0u;
    for (uint step = 0u; step < TRACE_STEPS; step++) {
        if (node >= end) {
            if (resume == NO_DATA) break;
            node = resume;
            resume = NO_DATA;
            end = world_end;
            ro = o;
            rd = d;
            inv_d = 1.0 / d;
            len = 1.0;
            base = 0u;
            continue;
        }
        BvhNode n = bvh_node(node);
        uint count = n.skip_count & BVH_COUNT_MASK;
        uint skip = n.skip_count >> BVH_COUNT_BITS;
        if (ray_box(ro, inv_d, load3(n.aabb_min), load3(n.aabb_max), t_hit * len) == INF) {
            node = skip;
            continue;
        }
        if (count == 0u) {
            node++;
            continue;
        }
        // A leaf of the top level: walk its instance's object (a loop of at most one turn, so
        // scenes without instances skip its reads).
        bool entered = false;
        WHEN(SCENE_HAS_INSTANCES && node >= flat_end && resume == NO_DATA) {
            uint a = instance_record(n.first);
            vec3 od = affine_vector(a + INSTANCE_DATA_OBJECT_FROM_WORLD, d);
            len = length(od);
            ro = affine_point(a + INSTANCE_DATA_OBJECT_FROM_WORLD, o);
            rd = od / len;
            inv_d = 1.0 / rd;
            base = (n.first + 1u) * frame.primitive_count;
            resume = skip;
            node = floatBitsToUint(shape_word(a + INSTANCE_DATA_ROOT));
            end = floatBitsToUint(shape_word(a + INSTANCE_DATA_END));
            entered = true;
        }
        if (entered) continue;
        for (uint i = n.first; i < n.first + count; i++) {
            uint before = hit;
#ifdef VARIANT_ANALYTIC
            // A CSG object reports the leaf primitive it shows (csg.glsl), so callers see an
            // ordinary primitive (an instance's: base + leaf). Behind WHEN: lavapipe would run its
            // walk under masks for every primitive of every scene of the analytic variant.
            bool is_csg = SCENE_HAS_CSG && (primitive_kind(i) & PRIMITIVE_KIND_MASK) == PRIMITIVE_CSG;
            WHEN(is_csg) {
                uint leaf;
                float tc = csg_intersect(i, ro, rd, t_hit * len, leaf) / len;
                if (tc < t_hit) {
                    t_hit = tc;
                    hit = base + leaf;
                }
            }
            if (!is_csg)
#endif
            visit(i, base + i, ro, rd, len, o, d, ignore, hit, t_hit);
            if (any_hit && hit != before) return hit;
        }
        node = skip;
    }
    return hit;
}
