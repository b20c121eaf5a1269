//! Compiles every `shaders/*.comp` to SPIR-V with glslangValidator and embeds the modules.
//! Shared numbers come from `src/layout/constants.rs`, written here into `constants.glsl`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

#[allow(dead_code)]
#[path = "src/layout/constants.rs"]
mod constants;

fn main() {
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed=shaders");
    println!("cargo:rerun-if-changed=src/layout/constants.rs");

    // Written only when its text changes: every kernel's depfile names it, so a fresh mtime on each
    // run would make cargo rerun this script, and recompile the crate, on every build.
    write_if_changed(&out_dir.join("constants.glsl"), &render_constants());

    let mut kernels: Vec<PathBuf> = std::fs::read_dir("shaders")
        .expect("the shaders/ folder exists")
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "comp"))
        .collect();
    kernels.sort();

    let mut index =
        String::from("/// Every compute kernel as (name, SPIR-V bytes).\npub const KERNELS: &[(&str, &[u8])] = &[\n");
    // Every build, in order: (kernel source, module name, defines).
    let mut jobs: Vec<(&Path, String, Vec<String>)> = Vec::new();
    for kernel in &kernels {
        let stem = kernel.file_stem().unwrap().to_string_lossy().to_string();
        // A line `// variant: NAME` compiles the kernel once more as `<stem>_NAME` with
        // `VARIANT_NAME` defined (e.g. with the procedural textures that slow down lavapipe);
        // `// variant: A B` compiles `<stem>_A_B` with both defined.
        // A line `// every build also: NAME` compiles each of these builds once more as
        // `<build>_NAME` with `VARIANT_NAME` defined too (the scene kernels' `paged`: the page
        // selection of scene arrays larger than one texel view, which lavapipe would otherwise
        // inline at every fetch of every scene before it folds the specialization constant
        // that removes it).
        let source = std::fs::read_to_string(kernel).unwrap_or_default();
        let variants = source.lines().filter_map(|l| l.strip_prefix("// variant: ")).map(str::trim);
        let mut builds: Vec<(String, Vec<String>)> = std::iter::once((stem.clone(), Vec::new()))
            .chain(variants.map(|v| {
                let names: Vec<&str> = v.split_whitespace().collect();
                let defines = names.iter().map(|n| format!("VARIANT_{}", n.to_uppercase())).collect();
                (format!("{stem}_{}", names.join("_")), defines)
            }))
            .collect();
        for also in source.lines().filter_map(|l| l.strip_prefix("// every build also: ")).map(str::trim) {
            let extra: Vec<(String, Vec<String>)> = builds
                .iter()
                .map(|(name, defines)| {
                    let mut defines = defines.clone();
                    defines.push(format!("VARIANT_{}", also.to_uppercase()));
                    (format!("{name}_{also}"), defines)
                })
                .collect();
            builds.extend(extra);
        }
        jobs.extend(builds.into_iter().map(|(name, defines)| (kernel.as_path(), name, defines)));
    }
    // On as many threads as there are cores: the paged builds doubled the modules (253), each a
    // separate glslangValidator run. Results are kept in job order, so kernels.rs is the same.
    let results: Vec<Mutex<Option<Result<(), String>>>> = jobs.iter().map(|_| Mutex::new(None)).collect();
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(jobs.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some((kernel, name, defines)) = jobs.get(i) else { break };
                let result = compile(kernel, &out_dir.join(format!("{name}.spv")), &out_dir, defines);
                *results[i].lock().unwrap() = Some(result);
            });
        }
    });
    let mut failures = Vec::new();
    for ((_, name, _), result) in jobs.iter().zip(results) {
        match result.into_inner().unwrap().expect("every job ran") {
            Ok(()) => {
                let spv = out_dir.join(format!("{name}.spv"));
                writeln!(index, "    ({name:?}, include_bytes!({:?})),", spv.display().to_string()).unwrap();
            }
            Err(message) => failures.push(message),
        }
    }
    index.push_str("];\n");
    if !failures.is_empty() {
        for f in &failures {
            for line in f.lines() {
                println!("cargo:warning={line}");
            }
        }
        panic!("shader compilation failed:\n{}", failures.join("\n"));
    }
    write_if_changed(&out_dir.join("kernels.rs"), &index);
}

fn write_if_changed(path: &Path, text: &str) {
    if std::fs::read_to_string(path).ok().as_deref() != Some(text) {
        std::fs::write(path, text).expect("OUT_DIR is writable");
    }
}

fn compile(kernel: &Path, spv: &Path, include_dir: &Path, defines: &[String]) -> Result<(), String> {
    let depfile = spv.with_extension("d");
    let output = Command::new("glslangValidator")
        .args(["-V", "--target-env", "vulkan1.2"])
        .args(defines.iter().map(|d| format!("-D{d}")))
        .arg(format!("-I{}", include_dir.display()))
        .arg("-Ishaders")
        .arg("--depfile")
        .arg(&depfile)
        .arg("-o")
        .arg(spv)
        .arg(kernel)
        .output();
    let output = match output {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err("glslangValidator not found: install the Debian package `glslang-tools` \
                        (apt-get install glslang-tools), or run ci/setup"
                .to_string())
        }
        Err(e) => return Err(format!("cannot run glslangValidator: {e}")),
    };
    if !output.status.success() {
        // glslang prints "ERROR: shaders/x.comp:12: ..." which names the file and line already.
        let text = String::from_utf8_lossy(&output.stdout).to_string() + &String::from_utf8_lossy(&output.stderr);
        return Err(format!("{}:\n{}", kernel.display(), text.trim()));
    }
    if let Ok(deps) = std::fs::read_to_string(&depfile) {
        for dep in deps.split_whitespace().skip(1) {
            let dep = dep.trim_end_matches('\\');
            // Files generated into OUT_DIR are this script's own outputs, not its inputs.
            if !dep.is_empty() && Path::new(dep).exists() && !Path::new(dep).starts_with(include_dir) {
                println!("cargo:rerun-if-changed={dep}");
            }
        }
    }
    Ok(())
}

fn render_constants() -> String {
    let mut s = String::from("// Generated by build.rs from src/layout/constants.rs. Do not edit.\n");
    for (name, ty, literal) in constants::glsl_constants() {
        writeln!(s, "const {ty} {name} = {literal};").unwrap();
    }
    s
}
