//! The `photonix` command line: parses the arguments, runs the command (see `cli`), and maps
//! an error to a message on stderr and a failing exit code.

mod cli;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            // clap quotes the arguments: escape what a terminal would act on.
            eprint!("{}", photonix::limits::printable_message(&e.to_string()));
            return ExitCode::from(e.exit_code() as u8);
        }
        Err(e) => {
            // --help and --version
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
    };
    let result = match cli.command {
        Command::Render(args) => cli::render::run(args),
        Command::Devices => cli::devices::run(),
        Command::Bench(args) => cli::bench::run(args),
        Command::Diff(args) => cli::diff::run(args),
        Command::Merge(args) => cli::merge::run(args),
        Command::Serve(args) => cli::serve::run(args),
        Command::Export(args) => cli::export::run(args),
        Command::Convert(args) => cli::convert::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Names from files and arguments reach the terminal with control characters escaped.
            eprintln!("error: {}", photonix::limits::printable_message(&format!("{e:#}")));
            // An interrupted render has its own status, so a scheduler can tell it from a failure.
            match e.downcast_ref::<cli::render::Interrupted>() {
                Some(_) => ExitCode::from(cli::render::EXIT_INTERRUPTED),
                None => ExitCode::FAILURE,
            }
        }
    }
}
