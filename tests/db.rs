//! The tissue database: the shipped index opens, building an entry twice
//! gives the same bytes, and built outputs know when they are out of date.

use std::path::PathBuf;

use organtex::db::build::is_current;
use organtex::db::{Database, Output, build};
use organtex::progress::Silent;

fn shipped() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database")
}

#[test]
fn the_shipped_database_lists_six_real_entries() {
    let db = Database::open(&shipped()).unwrap();
    assert!(db.tissues.len() >= 6);
    assert!(
        db.tissues
            .iter()
            .any(|t| t.outputs.contains(&Output::Overlay))
    );
    let fundus = db.tissue("fundus-tissue").unwrap();
    assert!(
        !fundus.mask_rules.is_empty(),
        "the fundus border, disc and vessels are masked"
    );
}

#[test]
fn building_is_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("sources")).unwrap();
    std::fs::copy(
        shipped().join("sources/retina.jpg"),
        dir.path().join("sources/retina.jpg"),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("index.toml"),
        r#"
[[tissue]]
id = "small"
name = "Small fundus patch"
kind = "retina"
source = "sources/retina.jpg"
crop = { x = 700, y = 120, width = 200, height = 200 }
mask_rules = ["dark", "vessels"]
outputs = ["colour", "height", "overlay"]
[tissue.synthesis]
width = 96
height = 96
seed = 3
"#,
    )
    .unwrap();
    let db = Database::open(dir.path()).unwrap();
    let read = |o| std::fs::read(db.output_path("small", o)).unwrap();
    let mut runs = Vec::new();
    for _ in 0..2 {
        build(&db, &[], &Silent).unwrap();
        runs.push([
            read(Output::Colour),
            read(Output::Height),
            read(Output::Overlay),
        ]);
    }
    assert!(runs[0] == runs[1]);
    let built = build(&db, &["small".into()], &Silent).unwrap();
    assert!(built[0].quality.as_ref().unwrap().seam <= 1.15);

    // Built outputs are current until the entry or its source changes.
    let small = db.tissue("small").unwrap();
    assert!(is_current(&db, small).unwrap());
    let index = dir.path().join("index.toml");
    let text = std::fs::read_to_string(&index).unwrap();
    std::fs::write(&index, text.replace("seed = 3", "seed = 4")).unwrap();
    let edited = Database::open(dir.path()).unwrap();
    assert!(!is_current(&edited, edited.tissue("small").unwrap()).unwrap());
    std::fs::write(&index, text).unwrap();
    std::fs::remove_file(db.output_path("small", Output::Height)).unwrap();
    assert!(!is_current(&db, small).unwrap(), "an output is missing");
}
