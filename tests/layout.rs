//! The GLSL mirror of every shared struct has the same member names, order, offsets and array
//! stride as the Rust struct. Read from the compiled SPIR-V (glslang records OpMemberName,
//! Offset and ArrayStride), so this runs without a GPU; tests/layout_roundtrip.rs does the same
//! through a kernel on the device.

use std::collections::HashMap;
use std::mem::{offset_of, size_of};

use photonix::layout::*;

/// Struct layout as the SPIR-V module declares it.
#[derive(Debug, Default)]
struct SpirvStruct {
    members: Vec<(String, u32)>,
    array_stride: Option<u32>,
}

fn spirv_structs(words: &[u32]) -> HashMap<String, SpirvStruct> {
    const OP_NAME: u32 = 5;
    const OP_MEMBER_NAME: u32 = 6;
    const OP_DECORATE: u32 = 71;
    const OP_MEMBER_DECORATE: u32 = 72;
    const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
    const DECORATION_ARRAY_STRIDE: u32 = 6;
    const DECORATION_OFFSET: u32 = 35;
    let string = |ws: &[u32]| -> String {
        let bytes: Vec<u8> = ws.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
        String::from_utf8(bytes).unwrap()
    };
    let mut names = HashMap::new();
    let mut member_names: HashMap<(u32, u32), String> = HashMap::new();
    let mut offsets: HashMap<(u32, u32), u32> = HashMap::new();
    let mut strides = HashMap::new();
    let mut runtime_arrays = Vec::new();
    let mut i = 5; // the header is five words
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let args = &words[i + 1..i + count];
        match op {
            OP_NAME => {
                names.insert(args[0], string(&args[1..]));
            }
            OP_MEMBER_NAME => {
                member_names.insert((args[0], args[1]), string(&args[2..]));
            }
            OP_MEMBER_DECORATE if args[2] == DECORATION_OFFSET => {
                offsets.insert((args[0], args[1]), args[3]);
            }
            OP_DECORATE if args[1] == DECORATION_ARRAY_STRIDE => {
                strides.insert(args[0], args[2]);
            }
            OP_TYPE_RUNTIME_ARRAY => runtime_arrays.push((args[0], args[1])),
            _ => {}
        }
        i += count.max(1);
    }
    let mut structs: HashMap<String, SpirvStruct> = HashMap::new();
    for (&(ty, member), &offset) in &offsets {
        let Some(name) = names.get(&ty) else { continue };
        let member_name = member_names.get(&(ty, member)).cloned().unwrap_or_default();
        let s = structs.entry(name.clone()).or_default();
        if s.members.len() <= member as usize {
            s.members.resize(member as usize + 1, (String::new(), 0));
        }
        s.members[member as usize] = (member_name, offset);
    }
    for (array, element) in runtime_arrays {
        if let (Some(name), Some(&stride)) = (names.get(&element), strides.get(&array)) {
            structs.entry(name.clone()).or_default().array_stride = Some(stride);
        }
    }
    structs
}

macro_rules! rust_layout {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        (stringify!($ty), vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),*], size_of::<$ty>() as u32)
    };
}

#[test]
fn glsl_struct_layouts_match_rust() {
    let words = photonix::shaders::spirv("layout_probe").expect("layout_probe kernel is embedded");
    let glsl = spirv_structs(&words);
    let rust = [
        rust_layout!(BvhNode { aabb_min, first, aabb_max, skip_count }),
        rust_layout!(Primitive { p0, kind, p1, material, p2, light }),
        rust_layout!(Material { reflectance, kind, emission, ior }),
        rust_layout!(Light { p0, kind, p1, pick_probability, p2, area, radiance, cdf }),
        rust_layout!(FrameParams {
            camera_position,
            width,
            camera_forward,
            height,
            camera_right,
            max_depth,
            camera_up,
            seed,
            light_count,
            ray_epsilon,
            primitive_count,
            node_count,
            total_light_power,
            photon_mapping,
            gather_rays,
            _pad,
        }),
        rust_layout!(DispatchRange { row_begin, row_count, sample_index, part }),
        rust_layout!(Photon { position, flux_rg, flux_b_dir }),
        rust_layout!(GridParams { cell_size, radius, table_mask, photon_count, flux_scale, _pad }),
        rust_layout!(EmitParams {
            path_begin,
            path_count,
            total_paths,
            max_depth,
            global_capacity,
            caustic_capacity,
            pass,
            caustics_only,
        }),
    ];
    for (name, fields, size) in rust {
        let g = glsl.get(name).unwrap_or_else(|| panic!("struct {name} is missing from layout_probe.comp"));
        assert_eq!(g.members, fields, "member names and offsets of {name}");
        assert_eq!(g.array_stride, Some(size), "std430 array stride of {name} vs size_of");
        println!("{name}: {} members, stride {size} bytes: match", fields.len());
    }
}
