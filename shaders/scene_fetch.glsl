// The scene's structs read back from their texel buffers (scene_bindings.glsl), field by field in
// the order of layout.glsl; tests/texel_fetch.rs checks every struct round-trips through them.

// Texel `i` of a scene array. In the builds for scenes whose arrays each fit one page (every
// scene of a few million triangles or less) it is the single texelFetch it always was: lavapipe
// inlines every call of these functions before it folds specialization constants, so a page
// selection there, even one a constant removes, doubled the inlined code and the pipelines'
// creation time (BENCHMARKS.md, "Kernel creation: the page selection in its own builds").
//
// The `paged` builds (`// every build also: paged`; `KernelVariant::kernel_name`, for scenes
// with an array over several pages) take texel `i` as texel `i & mask` of page `i >> log2`
// (log2 = texels per page). Lavapipe runs an if-chain's branches under masks, so only the cases
// of pages in use are compiled (SCENE_PAGES_USED). Constant indices only: indexing an array of
// texel buffers by a variable needs a device feature that is not required.
#ifdef VARIANT_PAGED
#define PAGED_TEXEL(name, pages, log2)                                                              \
    uvec4 name(uint i) {                                                                            \
        uint page = i >> (log2);                                                                    \
        int j = int(i & ((1u << (log2)) - 1u));                                                     \
        uvec4 t;                                                                                    \
        if (page == 0u) t = texelFetch(pages[0], j);                                                \
        else if (SCENE_PAGES_USED == 2u || page == 1u) t = texelFetch(pages[1], j);                 \
        else if (SCENE_PAGES_USED == 3u || page == 2u) t = texelFetch(pages[2], j);                 \
        else if (SCENE_PAGES_USED == 4u || page == 3u) t = texelFetch(pages[3], j);                 \
        else if (SCENE_PAGES_USED == 5u || page == 4u) t = texelFetch(pages[4], j);                 \
        else if (SCENE_PAGES_USED == 6u || page == 5u) t = texelFetch(pages[5], j);                 \
        else if (SCENE_PAGES_USED == 7u || page == 6u) t = texelFetch(pages[6], j);                 \
        else t = texelFetch(pages[7], j);                                                           \
        return t;                                                                                   \
    }
#else
#define PAGED_TEXEL(name, pages, log2) \
    uvec4 name(uint i) { return texelFetch(pages[0], int(i)); }
#endif
// The chain above has a case per page: a different SCENE_PAGES makes this array's size negative.
const uint SCENE_PAGES_CHECK[SCENE_PAGES == 8u ? 1 : -1] = uint[1](0u);

// Structs are RGBA32UI texels (four words each), word arrays R32UI.
const uint SCENE_PAGE_TEXELS_LOG2 = SCENE_PAGE_WORDS_LOG2 - 2u;
PAGED_TEXEL(node_texel, node_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(primitive_texel, primitive_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(material_texel, material_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(light_texel, light_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(texture_texel, texture_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(medium_texel, medium_texels, SCENE_PAGE_TEXELS_LOG2)
PAGED_TEXEL(texture_word_texel, texture_words, SCENE_PAGE_WORDS_LOG2)
PAGED_TEXEL(shape_word_texel, shape_words, SCENE_PAGE_WORDS_LOG2)

#define FETCH_TEXEL(texels, i) texelFetch(texels, int(i))
#define F3(v) float[3](uintBitsToFloat((v).x), uintBitsToFloat((v).y), uintBitsToFloat((v).z))

BvhNode bvh_node(uint i) {
    uvec4 a = node_texel(2u * i);
    uvec4 b = node_texel(2u * i + 1u);
    BvhNode n;
    n.aabb_min = F3(a);
    n.first = a.w;
    n.aabb_max = F3(b);
    n.skip_count = b.w;
    return n;
}

// The word holding a node's skip link and leaf count, without the rest of the node.
uint bvh_node_skip_count(uint i) { return node_texel(2u * i + 1u).w; }

Primitive primitive_at(uint i) {
    uvec4 a = primitive_texel(4u * i);
    uvec4 b = primitive_texel(4u * i + 1u);
    uvec4 c = primitive_texel(4u * i + 2u);
    uvec4 e = primitive_texel(4u * i + 3u);
    Primitive p;
    p.p0 = F3(a);
    p.kind = a.w;
    p.p1 = F3(b);
    p.material = b.w;
    p.p2 = F3(c);
    p.light = c.w;
    p.data = e.x;
    p.interior = e.y;
    p.exterior = e.z;
    p._pad = e.w;
    return p;
}

uint primitive_kind(uint i) { return primitive_texel(4u * i).w; }

Material material_at(uint i) {
    uvec4 a = material_texel(8u * i);
    uvec4 b = material_texel(8u * i + 1u);
    uvec4 c = material_texel(8u * i + 2u);
    uvec4 d = material_texel(8u * i + 3u);
    uvec4 c2 = material_texel(8u * i + 4u);
    uvec4 e = material_texel(8u * i + 5u);
    uvec4 f = material_texel(8u * i + 6u);
    uvec4 g = material_texel(8u * i + 7u);
    Material m;
    m.kind = a.x;
    m.flags = a.y;
    m.alpha = uintBitsToFloat(a.z);
    m.alpha_tex = a.w;
    m.emission = F3(b);
    m.emission_tex = b.w;
    m.color0 = F3(c);
    m.color0_tex = c.w;
    m.color1 = F3(d);
    m.color1_tex = d.w;
    m.color2 = F3(c2);
    m.color2_tex = c2.w;
    m.roughness = float[2](uintBitsToFloat(e.x), uintBitsToFloat(e.y));
    m.roughness_tex = e.z;
    m.ior = uintBitsToFloat(e.w);
    m.bump_tex = f.x;
    m.bump_strength = uintBitsToFloat(f.y);
    m.normal_tex = f.z;
    m.weight_tex = f.w;
    m.weight = uintBitsToFloat(g.x);
    m.mix_a = g.y;
    m.mix_b = g.z;
    m.data = g.w;
    return m;
}

Light light_at(uint i) {
    uvec4 a = light_texel(6u * i);
    uvec4 b = light_texel(6u * i + 1u);
    uvec4 c = light_texel(6u * i + 2u);
    uvec4 d = light_texel(6u * i + 3u);
    uvec4 e = light_texel(6u * i + 4u);
    uvec4 f = light_texel(6u * i + 5u);
    Light l;
    l.position = F3(a);
    l.kind = a.w;
    l.intensity = F3(b);
    l.primitive = b.w;
    l.direction = F3(c);
    l.area = uintBitsToFloat(c.w);
    l.pick_probability = uintBitsToFloat(d.x);
    l.cdf = uintBitsToFloat(d.y);
    l.photon_probability = uintBitsToFloat(d.z);
    l.photon_cdf = uintBitsToFloat(d.w);
    l.cos_outer = uintBitsToFloat(e.x);
    l.falloff_scale = uintBitsToFloat(e.y);
    l.exponent = uintBitsToFloat(e.z);
    l.radius = uintBitsToFloat(e.w);
    l.medium = f.x;
    l.grid = f.y;
    l.tree_trail = f.z;
    l.tree_probability = uintBitsToFloat(f.w);
    return l;
}

Texture texture_at(uint i) {
    uvec4 a = texture_texel(5u * i);
    uvec4 b = texture_texel(5u * i + 1u);
    uvec4 c = texture_texel(5u * i + 2u);
    uvec4 d = texture_texel(5u * i + 3u);
    uvec4 e = texture_texel(5u * i + 4u);
    Texture t;
    t.kind = a.x;
    t.space = a.y;
    t.data = a.z;
    t.color_map = a.w;
    t.value = F3(b);
    t.channel = b.w;
    t.transform = float[12](uintBitsToFloat(c.x), uintBitsToFloat(c.y), uintBitsToFloat(c.z), uintBitsToFloat(c.w),
                            uintBitsToFloat(d.x), uintBitsToFloat(d.y), uintBitsToFloat(d.z), uintBitsToFloat(d.w),
                            uintBitsToFloat(e.x), uintBitsToFloat(e.y), uintBitsToFloat(e.z), uintBitsToFloat(e.w));
    return t;
}

Medium medium_at(uint i) {
    uvec4 a = medium_texel(5u * i);
    uvec4 b = medium_texel(5u * i + 1u);
    uvec4 c = medium_texel(5u * i + 2u);
    uvec4 d = medium_texel(5u * i + 3u);
    uvec4 e = medium_texel(5u * i + 4u);
    Medium m;
    m.sigma_a = F3(a);
    m.phase = a.w;
    m.sigma_s = F3(b);
    m.g = uintBitsToFloat(b.w);
    m.emission = F3(c);
    m.density = c.w;
    m.bounds_min = F3(d);
    m.majorant = uintBitsToFloat(d.w);
    m.bounds_max = F3(e);
    m._pad = e.w;
    return m;
}

uint texture_word(uint i) { return texture_word_texel(i).x; }
float shape_word(uint i) { return uintBitsToFloat(shape_word_texel(i).x); }
