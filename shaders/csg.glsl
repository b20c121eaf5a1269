// CSG objects: the walk of a ray through the leaves of one CSG primitive. CPU twin: src/cpu/csg.rs,
// where the method is explained. Included by trace.glsl in the `analytic` variant only.

uint csg_word(uint a) {
    return floatBitsToUint(shape_word(a));
}

// Next crossing in (t_min, t_max) of leaf primitive i: a sphere, a triangle, a disc or a cone
// side, and in the `csg` variant a torus or a superellipsoid (their root searches are the largest
// code of all: a second copy here slowed every scene of the implicit variant by half on lavapipe).
float csg_leaf_intersect(uint i, vec3 o, vec3 d, float t_min, float t_max) {
    Primitive p = primitive_at(i);
    uint kind = p.kind & PRIMITIVE_KIND_MASK;
    if (kind == PRIMITIVE_SPHERE) return ray_sphere(o, d, load3(p.p0), p.p1[0], t_min, t_max);
    if (kind == PRIMITIVE_TRIANGLE) return ray_triangle(o, d, load3(p.p0), load3(p.p1), load3(p.p2), t_min, t_max);
#ifdef VARIANT_CSG
    return analytic_intersect(p, o, d, t_min, t_max);
#else
    uint a = p.data + SHAPE_DATA_OBJECT_FROM_WORLD;
    vec3 oo = affine_point(a, o);
    vec3 od = affine_vector(a, d);
    if (kind == PRIMITIVE_DISC) return ray_disc(oo, od, p.p0[0], p.p0[1], t_min, t_max);
    return ray_cone(oo, od, p.p0[0], p.p0[1], p.p0[2], t_min, t_max);
#endif
}

// The object's inside value (x) and whether a lone crossing of `leaf` shows (y), for the
// leaves' inside bits `inside`, by the postfix program of `program_length` words at a.
uvec2 csg_evaluate(uint a, uint program_length, uint inside, uint leaf) {
    uint v = 0u;
    uint s = 0u;
    for (uint k = 0u; k < program_length; k++) {
        uint w = csg_word(a + k);
        uint op = w >> CSG_OP_SHIFT;
        if (op == CSG_OP_LEAF) {
            uint l = w & ((1u << CSG_OP_SHIFT) - 1u);
            v = (v << 1u) | ((inside >> l) & 1u);
            s = (s << 1u) | (l == leaf ? 1u : 0u);
        } else {
            uint vb = v & 1u;
            uint va = (v >> 1u) & 1u;
            uint sb = s & 1u;
            uint sa = (s >> 1u) & 1u;
            uint rv = va | vb;
            uint rs = sa | sb;
            if (op == CSG_OP_MERGE) rs = (sa & (vb ^ 1u)) | (sb & (va ^ 1u));
            if (op == CSG_OP_INTERSECTION) {
                rv = va & vb;
                rs = (sa & vb) | (sb & va);
            }
            if (op == CSG_OP_DIFFERENCE) {
                rv = va & (vb ^ 1u);
                rs = (sa & (vb ^ 1u)) | (sb & va);
            }
            v = ((v >> 2u) << 1u) | rv;
            s = ((s >> 2u) << 1u) | rs;
        }
    }
    return uvec2(v & 1u, s & 1u);
}

// First visible surface of CSG primitive i in (0, t_max): its distance (INF: none) and, in
// `hit`, the leaf primitive crossed there.
float csg_intersect(uint i, vec3 o, vec3 d, float t_max, out uint hit) {
    uint a = primitive_at(i).data;
    uint count = csg_word(a + CSG_DATA_PRIMITIVES);
    uint program_length = csg_word(a + CSG_DATA_PROGRAM_LENGTH);
    uint first = frame.csg_first + csg_word(a + CSG_DATA_FIRST);
    uint leaves = a + CSG_DATA_LEAVES;
    uint program = leaves + count;
    hit = NO_LIGHT;
    uint inside = 0u;
    bool value = false;
    float t = -INF;
    for (uint n = 0u; n < CSG_MAX_STEPS; n++) {
        float t_next = INF;
        uint crossed = 0u;
        uint first_prim = NO_LIGHT;
        uint first_leaf = 0u;
        for (uint k = 0u; k < count; k++) {
            float tk = csg_leaf_intersect(first + k, o, d, t, t_max);
            uint leaf = csg_word(leaves + k);
            if (tk < t_next) {
                t_next = tk;
                crossed = 1u << leaf;
                first_prim = first + k;
                first_leaf = leaf;
            } else if (tk == t_next && tk < INF) {
                crossed |= 1u << leaf;
            }
        }
        if (t_next == INF) break;
        uint before = inside;
        inside ^= crossed;
        bool lone = crossed == (1u << first_leaf);
        uvec2 e = csg_evaluate(program, program_length, inside, lone ? first_leaf : CSG_MAX_LEAVES);
        bool after = e.x != 0u;
        bool visible = lone ? e.y != 0u : after != value;
        value = after;
        if (visible && t_next > 0.0) {
            if (!lone) {
                // Coincident surfaces: show the leaf whose lone crossing would have made the change.
                uint shown = first_leaf;
                for (uint m = crossed; m != 0u; m &= m - 1u) {
                    uint l = uint(findLSB(m));
                    if (csg_evaluate(program, program_length, before, l).y != 0u) {
                        shown = l;
                        break;
                    }
                }
                for (uint k = 0u; k < count && shown != first_leaf; k++) {
                    if (csg_word(leaves + k) == shown && csg_leaf_intersect(first + k, o, d, t, t_max) == t_next) {
                        first_prim = first + k;
                        break;
                    }
                }
            }
            hit = first_prim;
            return t_next;
        }
        t = t_next;
    }
    return INF;
}
