//! The committed header is what cbindgen makes of the crate now: a change
//! to the API that leaves include/organtex.h behind fails here.
//! `ORGANTEX_BLESS=1 cargo test -p organtex-capi --test header` rewrites it.

use std::path::PathBuf;

#[test]
fn the_committed_header_is_what_cbindgen_makes() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut fresh = Vec::new();
    cbindgen::Builder::new()
        .with_crate(&dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads the crate")
        .write(&mut fresh);
    let path = dir.join("include/organtex.h");
    if std::env::var_os("ORGANTEX_BLESS").is_some() {
        std::fs::write(&path, &fresh).expect("write the header");
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "{} differs from what cbindgen makes of capi/src: run \
         ORGANTEX_BLESS=1 cargo test -p organtex-capi --test header, and commit it",
        path.display()
    );
}
