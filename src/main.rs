//! The organtex command line: parses arguments, calls the library, shows the
//! result. No processing lives here.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    cli::progress::catch_interrupts();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(organtex::Error::Cancelled) => {
            eprintln!("cancelled: no output written");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            if let organtex::Error::NotManifold { .. } = e {
                eprintln!("hint: add --repair to split non-manifold elements and continue");
            }
            ExitCode::FAILURE
        }
    }
}
