//! The command line of the `photonix` binary: the clap definitions here, one file per command.
//!
//! Each command's file holds its flags and a `run` that returns `anyhow::Result`; `main` turns
//! an error into `error: ...` on stderr and a failing exit code.

use clap::{Parser, Subcommand};

// Defined before the `mod` lines below, so the command modules can use it.
/// `println!` that ignores a closed stdout (`photonix diff ... | head -1`) instead of panicking,
/// and escapes control characters (names from files and arguments reach a terminal).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), "{}", photonix::limits::printable_message(&format!($($arg)*)));
    }};
}

/// `eprintln!` with control characters escaped, for notes, warnings and summaries.
macro_rules! note {
    ($($arg:tt)*) => {{
        eprintln!("{}", photonix::limits::printable_message(&format!($($arg)*)));
    }};
}

pub mod bench;
pub mod convert;
pub mod devices;
pub mod diff;
pub mod export;
pub mod merge;
mod parse;
pub mod render;
pub mod serve;

/// `--backend` of render and serve: where the kernels run (`auto`: a real GPU when there is one,
/// else the CPU backend).
#[derive(Clone, Copy, clap::ValueEnum)]
enum BackendArg {
    Auto,
    Gpu,
    Cpu,
}

// No doc comments on the clap types: clap would show them as help text.
#[derive(Parser)]
#[command(name = "photonix", version, about = "Physically based photon mapping on Vulkan compute shaders")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene file to an image (.exr linear radiance, .png sRGB)
    Render(render::RenderArgs),
    /// List the Vulkan devices and the limits that matter to Photonix
    Devices,
    /// Measure primary and shadow rays per second on the GPU and the CPU reference
    Bench(bench::BenchArgs),
    /// Compare a render with a reference: relMSE, RMSE, per-channel mean ratio, error image
    Diff(diff::DiffArgs),
    /// Combine accumulation files of disjoint pass ranges into one image
    Merge(merge::MergeArgs),
    /// Edit a scene in the browser with a live rendered preview (prints the URL to open)
    Serve(serve::ServeArgs),
    /// Write a scene's geometry, materials and camera as glTF 2.0 binary (.glb)
    Export(export::ExportArgs),
    /// Translate a POV-Ray scene (.pov) into Photonix's TOML scene format
    Convert(convert::ConvertArgs),
}
