// Lights behind one interface: pick by power, a light sample toward a point, a photon leaving a
// light. CPU twin: src/cpu/light.rs. The including kernel declares the scene bindings and
// includes shape.glsl and bsdf.glsl.

// Index of the light whose cdf interval holds u: lights are picked in proportion to power, among
// those that cast direct light (`photons` false: `cdf`) or emit photons (`photons` true:
// `photon_cdf`). A light left out of a distribution has an empty interval and is never picked.
uint pick_light(float u, bool photons) {
    uint lo = 0u;
    uint hi = frame.light_count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (u < (photons ? light_at(mid).photon_cdf : light_at(mid).cdf)) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

// A bound on the light that the lights under light-tree node `node` send to a point x of
// normal n (n = 0 in a medium): their power over the squared distance to their box, times the
// cosine of the smallest angle between their emission cone and x as seen from anywhere in the box,
// times the cosine of the smallest angle at x to the box (Conty and Kulla 2018, as pbrt-v4's
// LightBounds::Importance; the squared distance is at least the box's half-diagonal squared).
// CPU twin: src/cpu/light.rs.
float tree_word(uint w) { return uintBitsToFloat(texture_word(w)); }

float light_node_importance(uint node, vec3 x, vec3 n) {
    vec3 lo = vec3(tree_word(node + LIGHT_NODE_MIN), tree_word(node + LIGHT_NODE_MIN + 1u), tree_word(node + LIGHT_NODE_MIN + 2u));
    vec3 hi = vec3(tree_word(node + LIGHT_NODE_MAX), tree_word(node + LIGHT_NODE_MAX + 1u), tree_word(node + LIGHT_NODE_MAX + 2u));
    vec3 axis = vec3(tree_word(node + LIGHT_NODE_AXIS), tree_word(node + LIGHT_NODE_AXIS + 1u), tree_word(node + LIGHT_NODE_AXIS + 2u));
    float power = tree_word(node + LIGHT_NODE_POWER);
    float cos_o = tree_word(node + LIGHT_NODE_COS_SPREAD);
    vec3 to_x = x - 0.5 * (lo + hi);
    float d2 = dot(to_x, to_x);
    vec3 half_diagonal = 0.5 * (hi - lo);
    float r2 = dot(half_diagonal, half_diagonal);
    // The box as seen from x: a cone of cos_b around the direction to its centre (the whole
    // sphere from inside its bounding sphere).
    float cos_b = d2 <= r2 ? -1.0 : sqrt(max(1.0 - r2 / d2, 0.0));
    float sin_b = sqrt(max(1.0 - cos_b * cos_b, 0.0));
    vec3 w = d2 > 0.0 ? to_x / sqrt(d2) : vec3(0.0, 0.0, 1.0);
    float cos_w = dot(axis, w);
    float sin_w = sqrt(max(1.0 - cos_w * cos_w, 0.0));
    float sin_o = sqrt(max(1.0 - cos_o * cos_o, 0.0));
    // theta_x = max(0, theta_w - theta_o), then theta' = max(0, theta_x - theta_b).
    float cos_x = cos_w > cos_o ? 1.0 : cos_w * cos_o + sin_w * sin_o;
    float sin_x = cos_w > cos_o ? 0.0 : sin_w * cos_o - cos_w * sin_o;
    float cos_p = cos_x > cos_b ? 1.0 : cos_x * cos_b + sin_x * sin_b;
    // Past the cone by the falloff, pi/2 (cos 0), nothing leaves.
    if (cos_p <= 0.0) return 0.0;
    float importance = power * cos_p / max(max(d2, r2), 1e-20);
    if (n != vec3(0.0)) {
        float cos_i = abs(dot(w, n));
        float sin_i = sqrt(max(1.0 - cos_i * cos_i, 0.0));
        importance *= cos_i > cos_b ? 1.0 : cos_i * cos_b + sin_i * sin_b;
    }
    return max(importance, 0.0);
}

// The light tree's share of direct-light selection; the infinite lights have the rest.
float tree_share() { return tree_word(frame.light_tree + LIGHT_TREE_SHARE); }

// The light that casts direct light on point x of normal n (n = 0 in a medium), and the
// probability `pmf` of that choice (0 with NO_LIGHT when none can): an infinite light by power
// outside the tree's share, else a walk down the light tree, each step in proportion to the
// children's importance. Contract: src/cpu/light.rs, pick_direct_light.
uint pick_direct_light(float u, vec3 x, vec3 n, out float pmf) {
    pmf = 0.0;
    uint base = frame.light_tree;
    if (base == NO_LIGHT) return NO_LIGHT;
    float share = tree_share();
    if (u >= share) {
        // The lights beside the tree (the infinite ones; every light under light_sampler =
        // "power"): their running probabilities cover the rest, [share, 1), searched for the
        // first that passes v.
        float v = (u - share) / (1.0 - share);
        uint count = texture_word(base + LIGHT_TREE_INFINITE_COUNT);
        if (count == 0u) return NO_LIGHT;
        uint lo = 0u;
        uint hi = count - 1u;
        while (lo < hi) {
            uint mid = (lo + hi) / 2u;
            if (v < tree_word(base + LIGHT_TREE_INFINITE + 2u * mid + 1u)) hi = mid; else lo = mid + 1u;
        }
        uint light = texture_word(base + LIGHT_TREE_INFINITE + 2u * lo);
        pmf = (1.0 - share) * light_at(light).tree_probability;
        return light;
    }
    u = u / share;
    pmf = share;
    uint node = texture_word(base + LIGHT_TREE_ROOT);
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        uint child = texture_word(node + LIGHT_NODE_CHILD);
        if ((child & LIGHT_NODE_LEAF) != 0u) return child & ~LIGHT_NODE_LEAF;
        uint first = node + LIGHT_NODE_WORDS;
        float a = light_node_importance(first, x, n);
        float b = light_node_importance(child, x, n);
        if (!(a + b > 0.0)) break;
        float p = a / (a + b);
        if (u < p) {
            u = min(u / p, 0.99999994);
            pmf *= p;
            node = first;
        } else {
            u = min((u - p) / (1.0 - p), 0.99999994);
            pmf *= b / (a + b);
            node = child;
        }
    }
    pmf = 0.0;
    return NO_LIGHT;
}

// The normal that light selection weighs a vertex's view of the lights with: the shading
// normal, or zero at a medium's scattering point (light arrives from every side).
vec3 receiver_normal(Bsdf b) { return b.kind == MATERIAL_PHASE ? vec3(0.0) : b.ns; }

// The probability that pick_direct_light at x of normal n chooses light i: its trail through
// the tree, step by step. Contract: src/cpu/light.rs, direct_light_pmf.
float direct_light_pmf(uint i, vec3 x, vec3 n) {
    Light l = light_at(i);
    if (l.tree_probability <= 0.0) return 0.0;
    float share = tree_share();
    if (l.tree_trail == NO_LIGHT) return (1.0 - share) * l.tree_probability;
    float pmf = share;
    uint node = texture_word(frame.light_tree + LIGHT_TREE_ROOT);
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        uint child = texture_word(node + LIGHT_NODE_CHILD);
        if ((child & LIGHT_NODE_LEAF) != 0u) return pmf;
        uint first = node + LIGHT_NODE_WORDS;
        float a = light_node_importance(first, x, n);
        float b = light_node_importance(child, x, n);
        if (!(a + b > 0.0)) return 0.0;
        if (((l.tree_trail >> depth) & 1u) == 0u) {
            pmf *= a / (a + b);
            node = first;
        } else {
            pmf *= b / (a + b);
            node = child;
        }
    }
    return 0.0;
}

// The cosine between a surface's geometric normal and w that its emission sees: emission leaves
// where it is > 0, the front face of a one-sided emitter, either face of a two-sided one.
// Contract: src/cpu/light.rs, emitter_cosine.
float emitter_cosine(uint flags, vec3 ng, vec3 w) {
    float c = dot(ng, w);
    return (flags & MATERIAL_FLAG_TWO_SIDED) != 0u ? abs(c) : c;
}

// Intensity profile of point and spot lights along unit direction w (away from the light):
// a smooth step (3t^2 - 2t^3, as pbrt-v4 and POV-Ray's cubic_spline) in cos from the outer
// cone to the inner one, times cos^exponent (POV-Ray's tightness). A point light's cone is
// the whole sphere, so its profile is 1.
float spot_falloff(Light l, vec3 w) {
    float c = dot(w, load3(l.direction));
    float t = clamp((c - l.cos_outer) * l.falloff_scale, 0.0, 1.0);
    float tight = l.exponent > 0.0 ? pow(max(c, 0.0), l.exponent) : 1.0;
    return t * t * (3.0 - 2.0 * t) * tight;
}

// The environment (LIGHT_ENVIRONMENT): a latitude-longitude image of radiance, its block at
// word `base` of the texture data (layout at ENV_TEXELS). Texel (i, j) covers the directions of
// polar angle theta in pi [j, j + 1] / H from +y and longitude phi in pi (2 [i, i + 1] / W - 1)
// around +y, phi = 0 toward -z, pi/2 toward +x, before the rotation about +y.
float env_float(uint word) { return uintBitsToFloat(texture_word(word)); }

// The direction of image position (u, v) in [0, 1]^2, in world space.
vec3 env_direction(uint base, vec2 uv) {
    float theta = PI * uv.y;
    float phi = PI * (2.0 * uv.x - 1.0);
    vec3 local = vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
    float c = env_float(base + ENV_COS_ROTATION);
    float s = env_float(base + ENV_SIN_ROTATION);
    return vec3(c * local.x + s * local.z, local.y, c * local.z - s * local.x);
}

// The texel (column, row) that world direction d falls in.
uvec2 env_texel(uint base, vec3 d) {
    uint w = texture_word(base + ENV_WIDTH);
    uint h = texture_word(base + ENV_HEIGHT);
    float c = env_float(base + ENV_COS_ROTATION);
    float s = env_float(base + ENV_SIN_ROTATION);
    vec3 local = vec3(c * d.x - s * d.z, d.y, c * d.z + s * d.x);
    float u = 0.5 * (atan(local.x, -local.z) / PI + 1.0);
    float v = acos(clamp(local.y, -1.0, 1.0)) / PI;
    return uvec2(min(uint(u * float(w)), w - 1u), min(uint(v * float(h)), h - 1u));
}

vec3 env_radiance_at(uint base, uvec2 t) {
    uint k = base + ENV_TEXELS + 3u * (t.y * texture_word(base + ENV_WIDTH) + t.x);
    return vec3(env_float(k), env_float(k + 1u), env_float(k + 2u));
}

// Radiance of the environment of light l arriving along -d (d points away from the scene).
vec3 environment_radiance(Light l, vec3 d) {
    return env_radiance_at(l.primitive, env_texel(l.primitive, d));
}

// Radiance of the discs of distant lights that a ray leaving the scene along d meets. The host
// puts the lights with a visible disc at the front of the list (see render::prepare), each with
// its cone's solid angle in `area`, so the search stops at the first light without one.
vec3 distant_discs_radiance(vec3 d) {
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < frame.light_count; i++) {
        if (light_at(i).kind != LIGHT_DISTANT || light_at(i).area <= 0.0) break;
        if (dot(d, load3(light_at(i).direction)) <= -light_at(i).cos_outer) sum += load3(light_at(i).intensity) / light_at(i).area;
    }
    return sum;
}

// Index of the interval [cdf[k], cdf[k + 1]) of the n + 1 values from `first` that holds u.
uint env_search(uint first, uint n, float u) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        if (env_float(first + mid) <= u) lo = mid; else hi = mid - 1u;
    }
    return lo;
}

// A direction toward the environment of light l, drawn in proportion to luminance times
// sin(theta) per texel (a piecewise-constant 2D distribution, pbrt's Distribution2D), with
// the radiance from it divided by its solid-angle pdf.
void environment_sample(Light l, vec2 u, out vec3 d, out vec3 weight) {
    uint base = l.primitive;
    uint w = texture_word(base + ENV_WIDTH);
    uint h = texture_word(base + ENV_HEIGHT);
    uint marginal = base + ENV_TEXELS + 3u * w * h;
    uint j = env_search(marginal, h, u.y);
    float m0 = env_float(marginal + j);
    float m1 = env_float(marginal + j + 1u);
    uint row = marginal + h + 1u + j * (w + 1u);
    uint i = env_search(row, w, u.x);
    float c0 = env_float(row + i);
    float c1 = env_float(row + i + 1u);
    vec2 uv = vec2((float(i) + clamp((u.x - c0) / (c1 - c0), 0.0, 1.0)) / float(w),
                   (float(j) + clamp((u.y - m0) / (m1 - m0), 0.0, 1.0)) / float(h));
    d = env_direction(base, uv);
    // pdf in (u, v) is W H (m1 - m0)(c1 - c0); the map to directions has Jacobian 2 pi^2 sin(theta).
    float sin_theta = sin(PI * uv.y);
    float pdf = float(w * h) * (m1 - m0) * (c1 - c0) / (2.0 * PI * PI * sin_theta);
    weight = sin_theta > 0.0 && pdf > 0.0 ? env_radiance_at(base, uvec2(i, j)) / pdf : vec3(0.0);
}

// Light l as seen from x: the direction wi toward it, a point p to aim the shadow ray at (beyond
// the scene for a distant light) and `weight`, the radiance arriving along -wi divided by the
// solid-angle pdf of the sample (so the direct light is f |cos| weight / pick probability);
// `eps`, how far short of p a shadow ray stops (an area light's point's own offset over the
// cosine there, else the frame's ray_epsilon); `pdf`, the solid-angle density multiple importance
// sampling weighs it with (see light_pdf; 0 for a light no ray can meet).
struct LightSample {
    vec3 p;
    vec3 wi;
    vec3 weight;
    float eps;
    float pdf;
    float cos_l;  // cosine at an area light toward -wi (1 for the others): vertex connection's
};

// Solid-angle pdf of environment_sample drawing direction d. CPU twin: src/cpu/light.rs.
float environment_pdf(Light l, vec3 d) {
    uint base = l.primitive;
    uint w = texture_word(base + ENV_WIDTH);
    uint h = texture_word(base + ENV_HEIGHT);
    uvec2 ij = env_texel(base, d);
    uint marginal = base + ENV_TEXELS + 3u * w * h;
    uint row = marginal + h + 1u + ij.y * (w + 1u);
    float pm = env_float(marginal + ij.y + 1u) - env_float(marginal + ij.y);
    float pc = env_float(row + ij.x + 1u) - env_float(row + ij.x);
    float sin_theta = sqrt(max(1.0 - d.y * d.y, 0.0));
    if (sin_theta <= 0.0) return 0.0;
    return float(w * h) * pm * pc / (2.0 * PI * PI * sin_theta);
}

// The solid-angle density light_sample would have drawn wi with from a point dist away, toward
// light l met by a ray (area lights: at a point of cosine cos_l toward it); area lights by their
// uniform density by area. Contract: src/cpu/light.rs, light_pdf.
float light_pdf(Light l, vec3 wi, float dist, float cos_l) {
    switch (l.kind) {
    case LIGHT_AREA:
        return cos_l > 0.0 && l.area > 0.0 ? dist * dist / (cos_l * l.area) : 0.0;
    case LIGHT_DISTANT:
        return l.area > 0.0 ? 1.0 / l.area : 0.0;
    }
    float env = 0.0;
    WHEN(l.kind == LIGHT_ENVIRONMENT) {
        env = environment_pdf(l, wi);
    }
    return env;
}

LightSample light_sample(Light l, vec3 x, vec2 u) {
    // The environment's searches are loops: no lane enters them unless it holds the environment.
    LightSample env = LightSample(x, vec3(0.0, 1.0, 0.0), vec3(0.0), frame.ray_epsilon, 0.0, 1.0);
    WHEN(l.kind == LIGHT_ENVIRONMENT) {
        environment_sample(l, u, env.wi, env.weight);
        env.p = x + env.wi * (length(x - load3(l.position)) + 2.0 * l.radius);
        env.pdf = environment_pdf(l, env.wi);
    }
    switch (l.kind) {
    case LIGHT_ENVIRONMENT:
        return env;
    case LIGHT_AREA: {
        // shape_sample_from: a sphere seen from outside by its cap's solid angle, L over the
        // pdf by solid angle.
        // Else by area (see shape_sample for the density): L cos' / d^2 over the pdf by area.
        // The MIS density stays light_pdf's by area either way: the two strategies weigh a
        // path by the same function, and both reach exactly the faces x sees.
        float inv_pdf, solid_angle;
        Hit h = shape_sample_from(l.primitive, x, u, inv_pdf, solid_angle);
        vec3 to_light = h.p - x;
        float dist2 = dot(to_light, to_light);
        vec3 wi = to_light / sqrt(dist2);
        Material m = material_at(h.material);
        float cos_l = emitter_cosine(m.flags, h.ng, -wi);
        float jacobian = solid_angle > 0.0 ? solid_angle : cos_l * inv_pdf / dist2;
        vec3 weight = cos_l > 0.0 ? material_emission(m, h) * jacobian : vec3(0.0);
        // The shadow ray stops short of the point by its offset over the cosine there: a hit on
        // the light's own surface moves along a grazing ray by its error over that cosine.
        return LightSample(h.p, wi, weight, h.eps / max(cos_l, 1e-2), light_pdf(l, wi, sqrt(dist2), cos_l), cos_l);
    }
    case LIGHT_DISTANT: {
        // Uniform in the cone of directions; intensity holds radiance times the cone's solid angle.
        vec3 wi = -cone_direction(load3(l.direction), l.cos_outer, u);
        float beyond = length(x - load3(l.position)) + 2.0 * l.radius;
        return LightSample(x + wi * beyond, wi, load3(l.intensity), frame.ray_epsilon, l.area > 0.0 ? 1.0 / l.area : 0.0, 1.0);
    }
    }
    // Point and spot lights: I(w) / d^2.
    vec3 p = load3(l.position);
    vec3 to_light = p - x;
    float dist2 = dot(to_light, to_light);
    vec3 wi = to_light / sqrt(dist2);
    return LightSample(p, wi, load3(l.intensity) * (spot_falloff(l, -wi) / dist2), frame.ray_epsilon, 0.0, 1.0);
}

// A photon leaving light l: its origin, direction and the power it carries before the division
// by the pick probability and the path count. Area lights emit from a point drawn by
// shape_sample (their power over that point's pdf by area) in a cosine-distributed direction
// (Lambertian); point and spot lights uniformly in their cone, weighted by the spot's profile;
// distant lights from a uniform point of the disc of the scene's bounding sphere that faces
// them, uniformly in their cone of directions.
void light_emit(Light l, vec2 u_pos, vec2 u_dir, out vec3 o, out vec3 d, out vec3 power, out float cos_l) {
    cos_l = 1.0;
    vec3 axis = load3(l.direction);
    // The environment: a direction toward it, then a disc facing it, as for a distant light.
    vec3 env_weight = vec3(0.0);
    WHEN(l.kind == LIGHT_ENVIRONMENT) {
        environment_sample(l, u_dir, axis, env_weight);
        axis = -axis;
    }
    switch (l.kind) {
    case LIGHT_AREA: {
        float inv_pdf;
        Hit h = shape_sample(l.primitive, u_pos, inv_pdf);
        Material m = material_at(h.material);
        // A two-sided emitter (cos_outer -1, see light_record) leaves by either face, each half
        // the time by the first number, the number stretched back over [0, 1).
        vec3 n = h.ng;
        vec2 ud = u_dir;
        if (l.cos_outer < 0.0) {
            if (ud.x < 0.5) {
                ud.x = 2.0 * ud.x;
            } else {
                ud.x = 2.0 * ud.x - 1.0;
                n = -n;
            }
        }
        o = h.p + n * h.eps;
        d = cosine_direction(n, ud);
        cos_l = dot(d, n);
        power = (1.0 - l.cos_outer) * PI * inv_pdf * material_emission(m, h);
        return;
    }
    case LIGHT_ENVIRONMENT:
    case LIGHT_DISTANT: {
        vec3 t, b;
        onb(axis, t, b);
        vec2 q = disc_point(u_pos) * l.radius;
        o = load3(l.position) - axis * l.radius + q.x * t + q.y * b;
        if (l.kind == LIGHT_ENVIRONMENT) {
            // Radiance over the direction's pdf, through the whole disc.
            d = axis;
            power = env_weight * (PI * l.radius * l.radius);
            return;
        }
        d = cone_direction(axis, l.cos_outer, u_dir);
        // Flux through the disc: radiance times solid angle times the projected disc area.
        power = load3(l.intensity) * (PI * l.radius * l.radius * dot(d, axis));
        return;
    }
    }
    o = load3(l.position);
    d = cone_direction(axis, l.cos_outer, u_dir);
    power = load3(l.intensity) * (2.0 * PI * (1.0 - l.cos_outer) * spot_falloff(l, d));
}
