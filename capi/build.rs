//! The shared library's soname carries the ABI's version, as installed
//! (liborgantex.so.1 -> liborgantex.so.0.1.0): a simulator linked against
//! one ABI never loads another.

fn main() {
    let target = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target == "linux" {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,liborgantex.so.1");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
