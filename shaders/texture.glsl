// Textures behind one evaluate function, and material parameters that may be textured.
// CPU twin: src/cpu/texture.rs. The including kernel declares the scene bindings.

vec3 texture_lookup_point(Texture t, Hit h) {
    vec3 p = t.space == TEXTURE_SPACE_UV ? vec3(h.uv, 0.0) : h.p;
    return vec3(dot(vec4(p, 1.0), vec4(t.transform[0], t.transform[1], t.transform[2], t.transform[3])),
                dot(vec4(p, 1.0), vec4(t.transform[4], t.transform[5], t.transform[6], t.transform[7])),
                dot(vec4(p, 1.0), vec4(t.transform[8], t.transform[9], t.transform[10], t.transform[11])));
}

// The colour of texture `index` at hit h (scalar textures are grey).
vec3 texture_eval(uint index, Hit h) {
    Texture t = textures[index];
    vec3 p = texture_lookup_point(t, h);
    switch (t.kind) {
    case TEXTURE_CONSTANT:
        return load3(t.value);
    case TEXTURE_CHECKER: {
        ivec3 c = ivec3(floor(p));
        return ((c.x + c.y + c.z) & 1) == 0 ? load3(t.value) : load3(t.value2);
    }
    }
    return vec3(0.0);  // unreachable: the host packs only known kinds
}

// A colour parameter: the constant, times the texture when it has one.
vec3 param_color(float value[3], uint tex, Hit h) {
    vec3 v = load3(value);
    return tex == NO_TEXTURE ? v : v * texture_eval(tex, h);
}

// A scalar parameter: the constant, times the texture's first channel when it has one.
float param_scalar(float value, uint tex, Hit h) {
    return tex == NO_TEXTURE ? value : value * texture_eval(tex, h).x;
}
