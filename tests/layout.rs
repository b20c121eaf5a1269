//! The GLSL mirror of every shared struct has the same member names, order, offsets and array
//! stride as the Rust struct. Read from the compiled SPIR-V (glslang records OpMemberName,
//! Offset and ArrayStride), so this runs without a GPU; tests/layout_roundtrip.rs does the same
//! through a kernel on the device.

use std::collections::HashMap;

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

/// The binding of each buffer in layout_probe.comp, by the name of its element struct.
fn probe_bindings(words: &[u32]) -> HashMap<String, u32> {
    // The probe declares `buffer X { T x[]; }` with a binding per block; glslang names the block
    // X and the runtime array's element type T. Reading the block's member type chain is more
    // SPIR-V than this test needs: the source itself is the simpler witness, and it is compiled
    // into the very module checked above.
    let _ = words;
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/layout_probe.comp")).unwrap();
    let mut bindings = HashMap::new();
    for line in source.lines().filter(|l| l.starts_with("layout(std430, binding = ")) {
        let binding: u32 = line["layout(std430, binding = ".len()..].split(')').next().unwrap().trim().parse().unwrap();
        let element = line.split('{').nth(1).unwrap().split_whitespace().next().unwrap();
        bindings.insert(element.to_string(), binding);
    }
    bindings
}

/// Every `struct X {` of shaders/layout.glsl.
fn glsl_struct_names() -> Vec<String> {
    let source = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/layout.glsl")).unwrap();
    source.lines().filter_map(|l| l.strip_prefix("struct ")).map(|l| l.trim_end_matches(" {").to_string()).collect()
}

#[test]
fn glsl_struct_layouts_match_rust() {
    let words = photonix::shaders::spirv("layout_probe").expect("layout_probe kernel is embedded");
    let glsl = spirv_structs(&words);
    let rust = gpu_struct_layouts();
    let bindings = probe_bindings(&words);
    for (index, (name, fields, size)) in rust.iter().enumerate() {
        let g = glsl.get(*name).unwrap_or_else(|| panic!("struct {name} is missing from layout_probe.comp"));
        let fields: Vec<(String, u32)> = fields.iter().map(|(f, o)| (f.to_string(), *o)).collect();
        assert_eq!(g.members, fields, "member names and offsets of {name}");
        assert_eq!(g.array_stride, Some(*size), "std430 array stride of {name} vs size_of");
        assert_eq!(
            bindings.get(*name),
            Some(&(index as u32)),
            "layout_probe.comp binds {name} at its index in gpu_structs!"
        );
        println!("{name}: {} members, stride {size} bytes: match", fields.len());
    }
    let rust_names: Vec<&str> = rust.iter().map(|(n, _, _)| *n).collect();
    for name in glsl_struct_names() {
        assert!(rust_names.contains(&name.as_str()), "layout.glsl declares {name}, which gpu_structs! lacks");
    }
}
