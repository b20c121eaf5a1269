// Textures behind one evaluate function, and material parameters that may be textured.
// CPU twin: src/cpu/texture.rs. The including kernel declares the scene bindings and includes
// shape.glsl, pattern.glsl and image_texture.glsl.

vec3 texture_lookup_point(Texture t, Hit h) {
    vec3 p = (t.space & 0xffu) == TEXTURE_SPACE_UV ? vec3(h.uv, 0.0) : h.p;
    return vec3(dot(vec4(p, 1.0), vec4(t.transform[0], t.transform[1], t.transform[2], t.transform[3])),
                dot(vec4(p, 1.0), vec4(t.transform[4], t.transform[5], t.transform[6], t.transform[7])),
                dot(vec4(p, 1.0), vec4(t.transform[8], t.transform[9], t.transform[10], t.transform[11])));
}

// The colour of texture `index` at hit h (scalar textures are grey).
vec3 texture_eval(uint index, Hit h) {
    Texture t = texture_at(index);
    vec3 p = texture_lookup_point(t, h);
    vec3 c = load3(t.value);
#ifdef VARIANT_TEXTURED
    WHEN(t.kind == TEXTURE_IMAGE) {
        vec4 texel = image_lookup(t.data, image_projection(p, t.space >> TEXTURE_PROJECTION_SHIFT));
        c = t.channel == TEXTURE_CHANNEL_RGB ? texel.rgb : vec3(texel[t.channel - 1u]);
    }
    WHEN(t.kind == TEXTURE_PATTERN) {
        c = color_map_eval(t.color_map, pattern_value(t.data, p));
    }
    WHEN(t.kind == TEXTURE_VOXELS) c = vec3(voxel_lookup(t.data, p));
    WHEN(t.kind == TEXTURE_GROUND_FOG) c = vec3(ground_fog_density(p, t.value[0], t.value[1], t.data));
#endif
    // TEXTURE_CONSTANT: the value itself. The host packs only known kinds, and image, pattern,
    // voxel and ground-fog textures only for the textured variant.
    return c;
}

// A colour parameter: the constant, times the texture when it has one.
vec3 param_color(float value[3], uint tex, Hit h) {
    vec3 v = load3(value);
    WHEN(tex != NO_TEXTURE) v *= texture_eval(tex, h);
    return v;
}

// A scalar parameter: the constant, times the texture's first channel when it has one.
float param_scalar(float value, uint tex, Hit h) {
    float v = value;
    WHEN(tex != NO_TEXTURE) v *= texture_eval(tex, h).x;
    return v;
}

// Hit h moved by (du, dv) in uv along the surface's tangent plane.
Hit hit_moved(Hit h, float du, float dv) {
    Hit m = h;
    m.uv += vec2(du, dv);
    m.p += du * h.dpdu + dv * h.dpdv;
    return m;
}

// The shading normal of a bump map: the surface displaced along ns (ng, or a smooth triangle's
// interpolated normal) by `strength` times a height
// (scene units), its slopes from central differences along u and v (pbrt-v4's BumpMap) of the
// heights at u +- BUMP_DELTA and v +- BUMP_DELTA (looked up at hit_moved points). Works alike for
// uv-space images and 3D patterns, since moving in uv moves the point along dpdu and dpdv.
vec3 bump_normal_from_heights(float u_plus, float u_minus, float v_plus, float v_minus, float strength, Hit h) {
    float d = BUMP_DELTA;
    float dhdu = strength * (u_plus - u_minus) / (2.0 * d);
    float dhdv = strength * (v_plus - v_minus) / (2.0 * d);
    vec3 n = cross(h.dpdu + dhdu * h.ns, h.dpdv + dhdv * h.ns);
    float len = length(n);
    if (!(len > 0.0)) return h.ns;
    n /= len;
    return dot(n, h.ns) < 0.0 ? -n : n;
}

// The shading normal of a tangent-space normal map from its texel (OpenGL convention: red along
// +u, green along +v, blue along the normal; texels in [0, 1] map to [-1, 1]).
vec3 normal_map_normal_from_texel(vec3 texel, Hit h) {
    vec3 c = 2.0 * texel - 1.0;
    vec3 t = h.dpdu - h.ns * dot(h.ns, h.dpdu);
    if (!(length(t) > 0.0)) return h.ns;
    t = normalize(t);
    vec3 b = cross(h.ns, t);
    if (dot(b, h.dpdv) < 0.0) b = -b;
    vec3 n = t * c.x + b * c.y + h.ns * c.z;
    float len = length(n);
    if (!(len > 0.0)) return h.ns;
    n /= len;
    // A normal map never turns the shading normal below the surface.
    return dot(n, h.ng) <= 0.0 ? h.ns : n;
}
