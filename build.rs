//! Embeds a digest of the library's source as ORGANTEX_SOURCE_DIGEST, so
//! a bake reuses interiors (tet meshes, lapped solid textures) and unwraps
//! only when the code that would make them again is the code that made
//! them: its files, the locked dependencies (Cargo.lock: faer factors the
//! unwraps' systems), the compiler and the target.

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

fn main() {
    let src = Path::new(&std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo")).join("src");
    println!("cargo:rerun-if-changed={}", src.display());
    let mut files = Vec::new();
    collect(&src, &mut files);
    files.sort();
    // SipHash with fixed keys: the same digest for the same bytes.
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    for file in &files {
        file.strip_prefix(&src)
            .expect("under src")
            .hash(&mut hasher);
        std::fs::read(file)
            .expect("readable source")
            .hash(&mut hasher);
    }
    // The workspace's lock file, beside the library's manifest (the
    // workspace's root, also when python/ or capi/ build it).
    let lock = src.with_file_name("Cargo.lock");
    println!("cargo:rerun-if-changed={}", lock.display());
    if let Ok(bytes) = std::fs::read(&lock) {
        bytes.hash(&mut hasher);
    }
    for var in ["RUSTC", "TARGET", "PROFILE"] {
        std::env::var(var).unwrap_or_default().hash(&mut hasher);
    }
    if let Ok(out) = std::process::Command::new(std::env::var("RUSTC").unwrap_or("rustc".into()))
        .arg("--version")
        .output()
    {
        out.stdout.hash(&mut hasher);
    }
    println!(
        "cargo:rustc-env=ORGANTEX_SOURCE_DIGEST={:016x}",
        hasher.finish()
    );
}

fn collect(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable src").flatten() {
        let path = entry.path();
        if path.is_dir() {
            collect(&path, files);
        } else {
            files.push(path);
        }
    }
}
