// Vertex connection and merging: what the light-path kernel (vcm_light.comp) and the camera
// kernel (render_vcm.comp) share. CPU twin: src/cpu/vcm.rs (the contracts are there).

// The heuristic's power of a density (Veach's beta = 2; SmallVCM's Mis).
float mis(float x) { return x * x; }

// Contracts in vcm.rs, wmul and wdiv: zero factors make zero weights, even against infinity.
float wmul(float a, float b) { return (a == 0.0 || b == 0.0) ? 0.0 : a * b; }

float wdiv(float a, float c) { return a == 0.0 ? 0.0 : a / c; }

// The layer of a path by its signature; contract in src/cpu/render_pt.rs, path_layer.
uint path_layer(bool first_specular, uint diffuse, bool specular_after) {
    if (first_specular) return LAYER_SPECULAR;
    if (diffuse <= 1u && !specular_after) return LAYER_DIRECT;
    if (diffuse == 1u) return LAYER_CAUSTICS;
    return LAYER_INDIRECT;
}

// Contracts in vcm.rs, camera_connectable, lens_point, camera_point.
bool camera_connectable() { return frame.camera_kind != CAMERA_ORTHOGRAPHIC || frame.lens_radius <= 0.0; }

vec3 lens_point(vec2 u) {
    vec3 eye = load3(frame.camera_position);
    return frame.lens_radius > 0.0 ? eye + lens_offset(u) : eye;
}

vec3 camera_point(vec3 x, vec2 u) {
    if (frame.camera_kind == CAMERA_ORTHOGRAPHIC) {
        vec3 fw = normalize(load3(frame.camera_forward));
        return x - fw * dot(x - load3(frame.camera_position), fw);
    }
    if (frame.camera_kind == CAMERA_LATLONG) return load3(frame.camera_position);
    return lens_point(u);
}

float camera_pixel_area() {
    return 4.0 * length(load3(frame.camera_right)) * length(load3(frame.camera_up)) / float(frame.width * frame.height);
}

// Contracts in vcm.rs, camera_pdf_w, camera_area_pdf, camera_d_vcm.
float camera_pdf_w(vec3 d) {
    if (frame.camera_kind == CAMERA_LATLONG) {
        float s = dot(d, load3(frame.camera_up));
        float cos_latitude = sqrt(max(1.0 - s * s, 0.0));
        return float(frame.width * frame.height) / (2.0 * PI * PI * cos_latitude);
    }
    vec3 fw = load3(frame.camera_forward);
    float cos_eye = dot(d, normalize(fw));
    return dot(fw, fw) / (cos_eye * cos_eye * cos_eye * camera_pixel_area());
}

float camera_area_pdf(vec3 d, float dist2, float cos_y) {
    if (frame.camera_kind == CAMERA_ORTHOGRAPHIC) return cos_y / camera_pixel_area();
    return camera_pdf_w(d) * cos_y / dist2;
}

float camera_d_vcm(uint light_paths, vec3 d) {
    if (!camera_connectable()) return 0.0;
    if (frame.camera_kind == CAMERA_ORTHOGRAPHIC) return mis(float(light_paths) * camera_pixel_area());
    return mis(float(light_paths) / camera_pdf_w(d));
}

// The film point (pixels) of the image of x seen from the aperture point lens; false behind the
// camera. Contract in vcm.rs, camera_film.
bool camera_film(vec3 x, vec3 lens, out vec2 film) {
    film = vec2(0.0);
    vec3 fw = load3(frame.camera_forward);
    vec3 r = load3(frame.camera_right);
    vec3 u = load3(frame.camera_up);
    vec3 v = x - load3(frame.camera_position);
    float sx, sy;
    if (frame.camera_kind == CAMERA_LATLONG) {
        vec3 d = normalize(v);
        sx = atan(dot(d, r), dot(d, fw)) / PI;
        sy = asin(clamp(dot(d, u), -1.0, 1.0)) / (0.5 * PI);
    } else if (frame.camera_kind == CAMERA_ORTHOGRAPHIC) {
        if (dot(v, fw) <= 0.0) return false;
        sx = dot(v, r) / dot(r, r);
        sy = dot(v, u) / dot(u, u);
    } else {
        if (frame.lens_radius > 0.0) {
            vec3 d = normalize(x - lens);
            float along = dot(d, fw);
            if (along <= 0.0) return false;
            x = lens + d * (frame.focal_distance / along);
            v = x - load3(frame.camera_position);
        }
        float k = dot(v, fw) / dot(fw, fw);
        if (k <= 0.0) return false;
        sx = dot(v, r) / (k * dot(r, r));
        sy = dot(v, u) / (k * dot(u, u));
    }
    film = vec2(0.5 * (sx + 1.0) * float(frame.width), 0.5 * (1.0 - sy) * float(frame.height));
    return true;
}

// Whether some pixel's filter reaches film point `film`; contract in vcm.rs.
bool film_reaches_image(vec2 film) {
    vec2 size = vec2(float(frame.width), float(frame.height));
    if (filter_is_pixel()) return film.x >= 0.0 && film.y >= 0.0 && film.x < size.x && film.y < size.y;
    float r = filter_radius() - 0.5;
    return film.x > -r && film.y > -r && film.x < size.x + r && film.y < size.y + r;
}

// The pixels whose filter reaches `film` (a box's: the one it lies in), as an inclusive range
// of columns and rows; contract in vcm.rs, film_footprint.
uvec4 film_footprint(vec2 film) {
    if (filter_is_pixel()) {
        uvec2 p = min(uvec2(film), uvec2(frame.width - 1u, frame.height - 1u));
        return uvec4(p, p);
    }
    float r = filter_radius();
    ivec2 lo = max(ivec2(ceil(film - 0.5 - r)), ivec2(0));
    ivec2 hi = min(ivec2(floor(film - 0.5 + r)), ivec2(int(frame.width) - 1, int(frame.height) - 1));
    return uvec4(uvec2(lo), uvec2(hi));
}

// (low, high) words of a splat's 64-bit fixed-point value; contract in vcm.rs, splat_words.
uvec2 splat_words(float v) {
    if (!(v > 0.0)) return uvec2(0u);
    v = min(v, SPLAT_MAX);
    float whole = floor(v);
    return uvec2(uint((v - whole) * 4294967296.0), uint(whole));
}

float splat_value(uint low, uint high) { return float(high) + float(low) * (1.0 / 4294967296.0); }

// The densities of a non-delta lobe choice: x = sampling wi from wo, y = the reverse. Both go
// through one call of bsdf_pdf, in a loop whose exit is a flag rather than a counter so that the
// driver cannot count its turns and unroll it: lavapipe inlines every call, lobe_pdfs has five
// callers in render_vcm, and a second call was five more copies of every kind's pdf to compile.
vec2 lobe_pdfs(Bsdf b, vec3 wo, vec3 wi) {
    vec2 pdfs;
    bool reverse = false;
    for (;;) {
        vec3 from = reverse ? wi : wo;
        vec3 to = reverse ? wo : wi;
        float pdf = (1.0 - bsdf_path_probability(b, from)) * bsdf_pdf(b, from, to);
        if (reverse) {
            pdfs.y = pdf;
            break;
        }
        pdfs.x = pdf;
        reverse = true;
    }
    return pdfs;
}

float abs_cos(Bsdf b, vec3 w) { return b.kind == MATERIAL_PHASE ? 1.0 : abs(dot(b.ns, w)); }

// Density of a light sub-path leaving l along -w (w toward the light), before the pick
// probability; contract in vcm.rs, emission_pdf.
float emission_pdf(Light l, vec3 w, float cos_l) {
    float disc = PI * l.radius * l.radius;
    if (l.kind == LIGHT_AREA) return max(cos_l, 0.0) / (PI * l.area * (1.0 - l.cos_outer));
    if (l.kind == LIGHT_ENVIRONMENT) return environment_pdf(l, w) / disc;
    if (l.kind == LIGHT_DISTANT) return l.area > 0.0 ? 1.0 / (l.area * disc) : 1.0 / disc;
    return 1.0 / (2.0 * PI * (1.0 - l.cos_outer));
}

// Contracts in vcm.rs, disc_reaches and emission_pdf_at.

bool disc_reaches(Light l, vec3 w, vec3 at) {
    vec3 axis = l.kind == LIGHT_ENVIRONMENT ? -w : load3(l.direction);
    vec3 centre = load3(l.position) - axis * l.radius;
    float s = dot(at - centre, axis) / -dot(w, axis);
    vec3 q = at - centre + w * s;
    return s >= -DISC_SLACK * l.radius && dot(q, q) <= l.radius * l.radius * (1.0 + DISC_SLACK);
}

float emission_pdf_at(Light l, vec3 w, float cos_l, vec3 at) {
    bool infinite = l.kind == LIGHT_DISTANT || l.kind == LIGHT_ENVIRONMENT;
    return infinite && !disc_reaches(l, w, at) ? 0.0 : emission_pdf(l, w, cos_l);
}

bool light_is_delta(Light l) {
    if (l.kind == LIGHT_AREA || l.kind == LIGHT_ENVIRONMENT) return false;
    if (l.kind == LIGHT_DISTANT) return l.area <= 0.0;
    return true;
}

// Whether merging can happen at a vertex (not at a medium's scattering points); contracts in
// vcm.rs, mergeable and merge_weight.
bool mergeable(Bsdf b) { return b.kind != MATERIAL_PHASE; }

float merge_weight(VcmParams p, Bsdf b) { return mergeable(b) ? p.vm_weight : 0.0; }

// Whether camera paths merge at their first vertex; contract in vcm.rs, merges_at_first_vertex.
bool merges_at_first_vertex(VcmParams p) { return (p.techniques & VCM_CONNECT) == 0u || !camera_connectable(); }

struct SubPath {
    vec3 throughput;
    float d_vcm;
    float d_vc;
    float d_vm;
};

void sub_arrive(inout SubPath sp, float dist, float cos_in, bool far) {
    if (far) sp.d_vcm = wmul(sp.d_vcm, mis(dist * dist));
    float c = mis(cos_in);
    sp.d_vcm = wdiv(sp.d_vcm, c);
    sp.d_vc = wdiv(sp.d_vc, c);
    sp.d_vm = wdiv(sp.d_vm, c);
}

// Contract in vcm.rs, SubPath::scatter (merge: whether merging is a technique at the vertex).
void sub_scatter(inout SubPath sp, VcmParams p, bool delta, float cos_out, float pdf, float reverse, bool merge) {
    if (delta) {
        sp.d_vcm = 0.0;
        sp.d_vc = wmul(sp.d_vc, mis(cos_out));
        sp.d_vm = wmul(sp.d_vm, mis(cos_out));
    } else {
        float g = mis(cos_out / pdf);
        float vm = merge ? p.vm_weight : 0.0;
        float one = merge ? 1.0 : 0.0;
        sp.d_vc = wmul(g, wmul(sp.d_vc, mis(reverse)) + sp.d_vcm + vm);
        sp.d_vm = wmul(g, wmul(sp.d_vm, mis(reverse)) + wmul(sp.d_vcm, p.vc_weight) + one);
        sp.d_vcm = mis(1.0 / pdf);
    }
}

// The medium a segment leaving vertex h (on primitive prim, NO_LIGHT in a medium, reached from
// wo in medium) along dir starts in; contract in vcm.rs, medium_toward.
uint medium_toward(Hit h, uint prim, uint medium, vec3 wo, vec3 dir) {
#ifdef VARIANT_MEDIA
    if (prim != NO_LIGHT && dot(dir, h.ng) * dot(wo, h.ng) < 0.0) return medium_after(prim, h.ng, dir, medium);
#endif
    return medium;
}

// Transmittance of the ray from o along d up to t_max, starting in medium: 0 when blocked, the
// media's transmittance through null boundaries; numbers n = (stream, sample, first dimension).
// Contract in vcm.rs, transmittance.
vec3 vcm_transmittance(vec3 o, vec3 d, float t_max, uint medium, uint skip, uvec3 n, inout uint rays) {
    float t;
#ifdef VARIANT_MEDIA
    vec3 tr = vec3(1.0);
    for (uint crossing = 0u; crossing <= MEDIUM_CROSSINGS; crossing++) {
        rays++;
        uint prim = trace_ray(o, d, t_max, false, skip, t);
        if (medium != NO_MEDIUM) {
            float seg = prim == NO_LIGHT ? t_max : t;
            tr *= medium_transmittance(medium, o, d, seg, rand2(n.x, n.y, frame.seed, n.z + crossing));
        }
        if (prim == NO_LIGHT) return tr;
        Hit h = shape_hit(prim, o, d, t);
        if (material_at(h.material).kind != MATERIAL_NULL || tr == vec3(0.0)) return vec3(0.0);
        medium = medium_after(prim, h.ng, d, medium);
        skip = ray_skip(prim);
        vec3 next = offset_origin(h, -d, BSDF_TRANSMISSION);
        t_max = max(t_max - dot(next - o, d), 0.0);
        o = next;
    }
    return vec3(0.0);
#else
    rays++;
    return trace_ray(o, d, t_max, true, skip, t) == NO_LIGHT ? vec3(1.0) : vec3(0.0);
#endif
}

// Transmittance from h (leaving toward target, in medium) to target; contract in vcm.rs,
// visibility.
vec3 vcm_visibility(Hit h, uint skip, vec3 target, uint medium, uvec3 n, inout uint rays) {
    vec3 origin = offset_origin(h, target - h.p, BSDF_REFLECTION);
    vec3 to = target - origin;
    float dist = length(to);
    return vcm_transmittance(origin, to / dist, dist * (1.0 - 1e-4) - frame.ray_epsilon, medium, skip, n, rays);
}

// Where a sub-path's ray ends; contract in vcm.rs, NextVertex and next_vertex.
struct NextVertex {
    bool found;      // false: past MEDIUM_CROSSINGS null boundaries
    uint prim;       // NO_LIGHT: none met, or a scattering point (scattered)
    bool scattered;
    vec3 o;          // the last ray's origin; the vertex is o + t d
    float t;
    float dist;      // from the first origin
    uint medium;
};

NextVertex next_vertex(vec3 o, vec3 d, uint medium, uint skip, uvec2 seq, uint domain, inout uint segment,
                       inout vec3 throughput, inout vec3 emitted, inout uint rays) {
    NextVertex nv;
    nv.found = false;
    float travelled = 0.0;
#ifdef VARIANT_MEDIA
    uint crossings = MEDIUM_CROSSINGS;
#else
    uint crossings = 0u;
#endif
    for (uint c = 0u; c <= crossings; c++) {
        rays++;
        float t;
        uint prim = trace_ray(o, d, INF, false, skip, t);
        bool scattered = false;
#ifdef VARIANT_MEDIA
        if (medium != NO_MEDIUM) {
            MediumEvent e = medium_sample(medium, o, d, t, qmc2(seq.x, seq.y, frame.seed, domain + segment));
            segment++;
            emitted += throughput * e.emission;
            throughput *= e.weight;
            scattered = e.scattered;
            t = e.t;
        }
        if (!scattered && prim != NO_LIGHT) {
            Hit h = shape_hit(prim, o, d, t);
            if (material_at(h.material).kind == MATERIAL_NULL) {
                // An invisible boundary: straight through into the medium beyond, not a vertex.
                medium = medium_after(prim, h.ng, d, medium);
                skip = ray_skip(prim);
                vec3 next = offset_origin(h, -d, BSDF_TRANSMISSION);
                travelled += dot(next - o, d);
                o = next;
                continue;
            }
        }
#endif
        nv.found = true;
        nv.prim = scattered ? NO_LIGHT : prim;
        nv.scattered = scattered;
        nv.o = o;
        nv.t = t;
        nv.dist = travelled + t;
        nv.medium = medium;
        return nv;
    }
    return nv;
}

// The scattering vertex a ray reached at distance t, with its BSDF: a collision in medium
// (scattered, the phase function) or the surface of hit name prim; contract in vcm.rs, vertex_at.
void vertex_at(bool scattered, uint prim, uint medium, vec3 o, vec3 d, float t, out Hit h, out Bsdf b) {
#ifdef VARIANT_MEDIA
    if (scattered) {
        h = medium_hit(o + d * t, -d);
        b = phase_bsdf(medium, -d);
        return;
    }
#endif
    h = shape_hit(prim, o, d, t);
    b = material_bsdf(material_at(h.material), h);
}
