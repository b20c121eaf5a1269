// The scene's structs read back from their texel buffers (scene_bindings.glsl), field by field in
// the order of layout.glsl; tests/texel_fetch.rs checks every struct round-trips through them.

#define FETCH_TEXEL(texels, i) texelFetch(texels, int(i))
#define F3(v) float[3](uintBitsToFloat((v).x), uintBitsToFloat((v).y), uintBitsToFloat((v).z))

BvhNode bvh_node(uint i) {
    uvec4 a = FETCH_TEXEL(node_texels, 2u * i);
    uvec4 b = FETCH_TEXEL(node_texels, 2u * i + 1u);
    BvhNode n;
    n.aabb_min = F3(a);
    n.first = a.w;
    n.aabb_max = F3(b);
    n.skip_count = b.w;
    return n;
}

// The word holding a node's skip link and leaf count, without the rest of the node.
uint bvh_node_skip_count(uint i) { return FETCH_TEXEL(node_texels, 2u * i + 1u).w; }

Primitive primitive_at(uint i) {
    uvec4 a = FETCH_TEXEL(primitive_texels, 4u * i);
    uvec4 b = FETCH_TEXEL(primitive_texels, 4u * i + 1u);
    uvec4 c = FETCH_TEXEL(primitive_texels, 4u * i + 2u);
    uvec4 e = FETCH_TEXEL(primitive_texels, 4u * i + 3u);
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

uint primitive_kind(uint i) { return FETCH_TEXEL(primitive_texels, 4u * i).w; }

Material material_at(uint i) {
    uvec4 a = FETCH_TEXEL(material_texels, 8u * i);
    uvec4 b = FETCH_TEXEL(material_texels, 8u * i + 1u);
    uvec4 c = FETCH_TEXEL(material_texels, 8u * i + 2u);
    uvec4 d = FETCH_TEXEL(material_texels, 8u * i + 3u);
    uvec4 c2 = FETCH_TEXEL(material_texels, 8u * i + 4u);
    uvec4 e = FETCH_TEXEL(material_texels, 8u * i + 5u);
    uvec4 f = FETCH_TEXEL(material_texels, 8u * i + 6u);
    uvec4 g = FETCH_TEXEL(material_texels, 8u * i + 7u);
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
    uvec4 a = FETCH_TEXEL(light_texels, 6u * i);
    uvec4 b = FETCH_TEXEL(light_texels, 6u * i + 1u);
    uvec4 c = FETCH_TEXEL(light_texels, 6u * i + 2u);
    uvec4 d = FETCH_TEXEL(light_texels, 6u * i + 3u);
    uvec4 e = FETCH_TEXEL(light_texels, 6u * i + 4u);
    uvec4 f = FETCH_TEXEL(light_texels, 6u * i + 5u);
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
    l._pad = uint[2](f.z, f.w);
    return l;
}

Texture texture_at(uint i) {
    uvec4 a = FETCH_TEXEL(texture_texels, 5u * i);
    uvec4 b = FETCH_TEXEL(texture_texels, 5u * i + 1u);
    uvec4 c = FETCH_TEXEL(texture_texels, 5u * i + 2u);
    uvec4 d = FETCH_TEXEL(texture_texels, 5u * i + 3u);
    uvec4 e = FETCH_TEXEL(texture_texels, 5u * i + 4u);
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
    uvec4 a = FETCH_TEXEL(medium_texels, 5u * i);
    uvec4 b = FETCH_TEXEL(medium_texels, 5u * i + 1u);
    uvec4 c = FETCH_TEXEL(medium_texels, 5u * i + 2u);
    uvec4 d = FETCH_TEXEL(medium_texels, 5u * i + 3u);
    uvec4 e = FETCH_TEXEL(medium_texels, 5u * i + 4u);
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

uint texture_word(uint i) { return FETCH_TEXEL(texture_words, i).x; }
float shape_word(uint i) { return uintBitsToFloat(FETCH_TEXEL(shape_words, i).x); }
