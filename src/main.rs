//! The `photonix` command line: parses the arguments, runs the command (see `cli`), and maps
//! an error to a message on stderr and a failing exit code.

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Render(args) => cli::render::run(args),
        Command::Devices => cli::devices::run(),
        Command::Bench(args) => cli::bench::run(args),
        Command::Diff(args) => cli::diff::run(args),
        Command::Merge(args) => cli::merge::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
