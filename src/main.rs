//! The organtex command line: parses arguments, calls the library, shows the
//! result. No processing lives here.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    quiet_headless_vulkan();
    // A closed pipe (`organtex bake ... | head -1`) ends the program
    // quietly, as it does other command-line tools, instead of a panic in
    // the next print (Rust ignores SIGPIPE by default).
    #[cfg(unix)]
    // SAFETY: restores the default action of one signal before any thread
    // starts; no handler runs Rust code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
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

/// Without a desktop session (no XDG_RUNTIME_DIR: a server, CI, a bake
/// farm), Mesa's implicit device-select Vulkan layer tries to reach a
/// Wayland display to rank the GPUs and prints "error: XDG_RUNTIME_DIR is
/// invalid" on every run that renders, though nothing failed. organtex
/// picks its adapter itself, so the layer is turned off there (its own
/// switch, NODEVICE_SELECT), unless the user set that switch.
fn quiet_headless_vulkan() {
    use std::env;
    if env::var_os("XDG_RUNTIME_DIR").is_none() && env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: first thing in main, before any other thread exists.
        unsafe { env::set_var("NODEVICE_SELECT", "1") };
    }
}
