// The scene as every kernel that traces rays sees it: declared here once, bound by the host in
// the same order (`DeviceScene::bindings` in src/render/gpu.rs). A kernel's own buffers take the
// bindings from SCENE_BINDINGS on.

layout(std430, binding = BINDING_FRAME) readonly buffer Frame { FrameParams frame; };
layout(std430, binding = BINDING_NODES) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = BINDING_PRIMITIVES) readonly buffer Primitives { Primitive primitives[]; };
layout(std430, binding = BINDING_MATERIALS) readonly buffer Materials { Material materials[]; };
layout(std430, binding = BINDING_LIGHTS) readonly buffer Lights { Light lights[]; };
layout(std430, binding = BINDING_TEXTURES) readonly buffer Textures { Texture textures[]; };
layout(std430, binding = BINDING_TEXTURE_DATA) readonly buffer TextureData { uint texture_data[]; };
layout(std430, binding = BINDING_SHAPE_DATA) readonly buffer ShapeData { float shape_data[]; };
layout(std430, binding = BINDING_MEDIA) readonly buffer Media { Medium media[]; };

// Features a scene may lack, fixed when the host creates the pipeline (specialization constants,
// `KernelVariant::specialization`): the driver compiles their code out where they are false, so
// scenes without instances or CSG do not pay for the instance walk and the CSG walk in the
// innermost loop (lavapipe runs every branch under masks; code size alone slows it down).
// Unlike the `// variant:` builds they cost no extra SPIR-V. Both default to present.
layout(constant_id = 0) const bool SCENE_HAS_INSTANCES = true;
layout(constant_id = 1) const bool SCENE_HAS_CSG = true;
