// Mirror of src/layout/mod.rs: same names, same order. tests/layout.rs checks every offset.
#include "constants.glsl"

struct BvhNode {
    float aabb_min[3];
    uint first;
    float aabb_max[3];
    uint skip_count;
};

struct Primitive {
    float p0[3];
    uint kind;
    float p1[3];
    uint material;
    float p2[3];
    uint light;
    uint data;
    uint interior;
    uint exterior;
    uint _pad;
};

struct Material {
    uint kind;
    uint flags;
    float alpha;
    uint alpha_tex;
    float emission[3];
    uint emission_tex;
    float color0[3];
    uint color0_tex;
    float color1[3];
    uint color1_tex;
    float color2[3];
    uint color2_tex;
    float roughness[2];
    uint roughness_tex;
    float ior;
    uint bump_tex;
    float bump_strength;
    uint normal_tex;
    uint weight_tex;
    float weight;
    uint mix_a;
    uint mix_b;
    uint data;
};

struct Texture {
    uint kind;
    uint space;
    uint data;
    uint color_map;
    float value[3];
    uint channel;
    float transform[12];
};

struct Light {
    float position[3];
    uint kind;
    float intensity[3];
    uint primitive;
    float direction[3];
    float area;
    float pick_probability;
    float cdf;
    float photon_probability;
    float photon_cdf;
    float cos_outer;
    float falloff_scale;
    float exponent;
    float radius;
    uint medium;
    uint grid;
    uint tree_trail;
    float tree_probability;
};

struct Medium {
    float sigma_a[3];
    uint phase;
    float sigma_s[3];
    float g;
    float emission[3];
    uint density;
    float bounds_min[3];
    float majorant;
    float bounds_max[3];
    uint _pad;
};

struct FrameParams {
    float camera_position[3];
    uint width;
    float camera_forward[3];
    uint height;
    float camera_right[3];
    uint max_depth;
    float camera_up[3];
    uint seed;
    uint light_count;
    float ray_epsilon;
    uint primitive_count;
    uint node_count;
    float total_light_power;
    uint photon_mapping;
    uint gather_rays;
    float glossy_threshold;
    uint camera_kind;
    float lens_radius;
    float focal_distance;
    uint aperture_blades;
    float aperture_rotation;
    uint environment;
    uint unbounded_first;
    uint camera_medium;
    uint instance_count;
    uint instance_data;
    uint csg_first;
    uint integrator;
    uint techniques;
    uint pixel_filter;
    float filter_scale;
    uint light_tree;
};

struct DispatchRange {
    uint row_begin;
    uint row_count;
    uint sample_index;
    uint part;
    uint pixel_list;
    uint pixel_count;
};

struct Photon {
    float position[3];
    uint flux_rg;
    uint flux_b_dir;
};

struct GridParams {
    float cell_size;
    float radius;
    uint table_mask;
    uint photon_count;
    float flux_scale;
    uint _pad[3];
};

struct TriangleShading {
    float uv[6];
    float normals[9];
};

struct EmitParams {
    uint path_begin;
    uint path_count;
    uint total_paths;
    uint max_depth;
    uint global_capacity;
    uint caustic_capacity;
    uint pass;
    uint caustics_only;
    uint volume_capacity;
    uint _pad[3];
};

struct LightVertex {
    float origin[3];
    uint hit;
    float direction[3];
    float t;
    float throughput[3];
    uint path_length;
    float d_vcm;
    float d_vc;
    float d_vm;
    uint flags;
};

struct VcmParams {
    uint sample_index;
    uint light_paths;
    uint vertex_slots;
    uint techniques;
    float radius;
    float vm_weight;
    float vc_weight;
    float vm_normalization;
    uint path_begin;
    uint path_count;
    uint paths_per_invocation;
    uint connections;
    uint steps_per_dispatch;
    uint resume;
};

struct LightMaterial {
    float color0[3];
    uint kind;
    float color1[3];
    float ior;
    float ns[3];
    float alpha_u;
    float alpha_v;
    uint flags;
    uint data;
    uint _pad;
    float color2[3];
    uint _pad2;
};

// Stores a Photon field by field: glslang emits an invalid whole-struct OpStore when the value
// comes from a block of another layout (the validation layer rejects the module).
#define STORE_PHOTON(array, index, value) { Photon v_ = value; uint i_ = index; \
    array[i_].position[0] = v_.position[0]; array[i_].position[1] = v_.position[1]; \
    array[i_].position[2] = v_.position[2]; array[i_].flux_rg = v_.flux_rg; array[i_].flux_b_dir = v_.flux_b_dir; }

// Index of this invocation in a one-dimensional launch of WORKGROUP_SIZE-wide groups that the
// host spreads over a 2D grid of workgroups (maxComputeWorkGroupCount[0] is often 65535).
#define GLOBAL_INDEX ((gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * WORKGROUP_SIZE + gl_LocalInvocationID.x)

vec3 load3(float v[3]) { return vec3(v[0], v[1], v[2]); }

// `WHEN(cond) { ... }` runs the block where cond holds, as a loop of zero or one turn: lavapipe
// runs both sides of every branch under masks, but leaves a loop at once when no lane enters it,
// so costly optional work (textures, bump maps, alpha, the other shape kinds) costs nothing where
// no lane needs it. Each entry counts one loop turn toward lavapipe's limit of 65535.
#define WHEN(cond) for (uint when_ = ((cond) ? 0u : 1u); when_ < 1u; when_++)
