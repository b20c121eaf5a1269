// vcm's light stage as render_vcm reads it back: its vertex slots and their looked-up materials,
// bound as RGBA32UI texels (the kernel reads them at random; scene_bindings.glsl says why), four
// texels a struct, field by field in layout.glsl's order as scene_fetch.glsl reads the scene's.
// tests/texel_fetch.rs checks both round-trip.

LightVertex fetch_light_vertex(usamplerBuffer texels, uint i) {
    uvec4 a = FETCH_TEXEL(texels, 4u * i);
    uvec4 b = FETCH_TEXEL(texels, 4u * i + 1u);
    uvec4 c = FETCH_TEXEL(texels, 4u * i + 2u);
    uvec4 e = FETCH_TEXEL(texels, 4u * i + 3u);
    LightVertex v;
    v.origin = F3(a);
    v.hit = a.w;
    v.direction = F3(b);
    v.t = uintBitsToFloat(b.w);
    v.throughput = F3(c);
    v.path_length = c.w;
    v.d_vcm = uintBitsToFloat(e.x);
    v.d_vc = uintBitsToFloat(e.y);
    v.d_vm = uintBitsToFloat(e.z);
    v.flags = e.w;
    return v;
}

LightMaterial fetch_light_material(usamplerBuffer texels, uint i) {
    uvec4 a = FETCH_TEXEL(texels, 5u * i);
    uvec4 b = FETCH_TEXEL(texels, 5u * i + 1u);
    uvec4 c = FETCH_TEXEL(texels, 5u * i + 2u);
    uvec4 e = FETCH_TEXEL(texels, 5u * i + 3u);
    uvec4 g = FETCH_TEXEL(texels, 5u * i + 4u);
    LightMaterial m;
    m.color0 = F3(a);
    m.kind = a.w;
    m.color1 = F3(b);
    m.ior = uintBitsToFloat(b.w);
    m.ns = F3(c);
    m.alpha_u = uintBitsToFloat(c.w);
    m.alpha_v = uintBitsToFloat(e.x);
    m.flags = e.y;
    m.data = e.z;
    m._pad = e.w;
    m.color2 = F3(g);
    m._pad2 = g.w;
    return m;
}
