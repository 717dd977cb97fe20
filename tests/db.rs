//! The tissue database: the shipped index opens, building an entry twice
//! gives the same bytes, and built outputs know when they are out of date.

use std::path::PathBuf;

use organtex::db::build::is_current;
use organtex::db::index::Lighting;
use organtex::db::{Database, Output, Shelf, build};
use organtex::progress::Silent;

fn shipped() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database")
}

/// A database folder of one source, the shipped `file` copied in as
/// `sources/NAME`, for an index a test writes.
fn with_source(file: &str, name: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("sources")).unwrap();
    std::fs::copy(
        shipped().join("sources").join(file),
        dir.path().join("sources").join(name),
    )
    .unwrap();
    dir
}

#[test]
fn the_shipped_database_lists_eight_real_entries() {
    let db = Database::open(&shipped()).unwrap();
    assert!(db.tissues.len() >= 8);
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
    let dir = with_source("retina.jpg", "retina.jpg");
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

#[test]
fn every_endoscope_frame_entry_has_its_lighting_flattened() {
    // Issue 28: an entry whose lighting is flattened leaves at most half
    // the lighting's unevenness in its tile (`report.json` lighting), and
    // every shipped real entry names its licence and credit line.
    let shipped_db = Database::open(&shipped()).unwrap();
    let frames: Vec<_> = shipped_db
        .tissues
        .iter()
        .filter(|t| t.lighting == Lighting::Flatten && t.outputs.contains(&Output::Colour))
        .collect();
    assert!(frames.len() >= 3, "{} flattened frames", frames.len());
    for t in frames {
        let dir = tempfile::tempdir().unwrap();
        let source = dir.path().join(&t.source);
        std::fs::create_dir_all(source.parent().unwrap()).unwrap();
        std::fs::copy(shipped().join(&t.source), &source).unwrap();
        let mut entry = t.clone();
        let synthesis = entry.synthesis.as_mut().unwrap();
        (synthesis.width, synthesis.height) = (192, 192);
        #[derive(serde::Serialize)]
        struct Index {
            tissue: Vec<organtex::db::Tissue>,
        }
        let index = Index {
            tissue: vec![entry],
        };
        std::fs::write(
            dir.path().join("index.toml"),
            toml::to_string(&index).unwrap(),
        )
        .unwrap();
        let db = Database::open(dir.path()).unwrap();
        let built = build(&db, &[], &Silent).unwrap();
        let lit = built[0].lighting.as_ref().expect("a lighting report");
        assert!(
            lit.flattened && lit.spread_after <= 0.5 * lit.spread_before,
            "{}: spread {:.2} -> {:.2}",
            t.id,
            lit.spread_before,
            lit.spread_after
        );
        assert!(t.licence.is_some() && t.credit.is_some(), "{}", t.id);
    }
}

#[test]
fn every_source_is_licensed_and_every_shelf_stocked() {
    // Issue 28: every file in database/sources/ has its row in
    // LICENSES.md (the licence notices beside it excepted), every entry
    // names its licence and credit line, the test textures that are not
    // tissue stay off the shelf, and each of the viewer's shelves has
    // entries.
    let db = Database::open(&shipped()).unwrap();
    let sources = shipped().join("sources");
    let licences = std::fs::read_to_string(sources.join("LICENSES.md")).unwrap();
    for file in std::fs::read_dir(&sources).unwrap() {
        let name = file.unwrap().file_name().into_string().unwrap();
        if name == "LICENSES.md" || name.starts_with("LICENSE-") {
            continue;
        }
        assert!(
            licences.contains(&format!("| {name} |")) || licences.contains(&format!("`{name}`")),
            "database/sources/{name} has no row in LICENSES.md"
        );
    }
    for t in &db.tissues {
        assert!(t.licence.is_some() && t.credit.is_some(), "{}", t.id);
        for not_tissue in ["gravel", "grass", "brick"] {
            assert!(!t.source.to_string_lossy().contains(not_tissue), "{}", t.id);
        }
    }
    for shelf in Shelf::ALL {
        assert!(
            db.tissues.iter().filter(|t| t.shelf() == shelf).count() >= 2,
            "the {shelf:?} shelf"
        );
    }
}

#[test]
fn a_shelf_that_does_not_fit_the_outputs_is_refused_by_name() {
    let dir = with_source("layered_wall.png", "wall.png");
    let index = |shelf: &str, outputs: &str| {
        std::fs::write(
            dir.path().join("index.toml"),
            format!(
                "[[tissue]]\nid = \"wall\"\nname = \"Wall\"\nkind = \"layered wall\"\n\
                 source = \"sources/wall.png\"\n{shelf}outputs = [{outputs}]\n"
            ),
        )
        .unwrap();
        Database::open(dir.path())
    };
    // A layered exemplar goes on the interior shelf by itself, and builds
    // its layers output: the exemplar unchanged.
    let db = index("", "\"layers\"").unwrap();
    assert_eq!(db.tissue("wall").unwrap().shelf(), Shelf::Interior);
    build(&db, &[], &Silent).unwrap();
    let layers = image::open(db.output_path("wall", Output::Layers)).unwrap();
    let source = image::open(dir.path().join("sources/wall.png")).unwrap();
    assert_eq!(layers.to_rgb8(), source.to_rgb8());
    for (shelf, outputs) in [
        ("shelf = \"surface\"\n", "\"layers\""),
        ("shelf = \"overlay\"\n", "\"layers\""),
        ("shelf = \"interior\"\n", "\"overlay\""),
    ] {
        let err = index(shelf, outputs).unwrap_err().to_string();
        assert!(
            err.contains("tissue 'wall': shelf = ")
                && err.contains(&format!("outputs [{outputs}]")),
            "{err}"
        );
        assert!(err.contains("index.toml"), "{err}");
    }
}

/// An occurrence weight out of range is refused when the index is read,
/// naming the index and the entry, before anything is built.
#[test]
fn an_occurrence_weight_out_of_range_is_refused_by_name() {
    let dir = with_source("layered_wall.png", "wall.png");
    let index = |occurrence: &str| {
        std::fs::write(
            dir.path().join("index.toml"),
            format!(
                "[[tissue]]\nid = \"wall\"\nname = \"Wall\"\nkind = \"muscle\"\n\
                 source = \"sources/wall.png\"\noutputs = [\"colour\"]\n\
                 [tissue.synthesis]\nwidth = 64\nheight = 64\noccurrence = {occurrence}\n"
            ),
        )
        .unwrap();
        Database::open(dir.path())
    };
    assert_eq!(
        index("0.5")
            .unwrap()
            .tissue("wall")
            .unwrap()
            .synthesis
            .as_ref()
            .unwrap()
            .occurrence,
        0.5
    );
    for bad in ["-1.0", "11.0", "nan"] {
        let err = index(bad).unwrap_err().to_string();
        assert!(
            err.contains("index.toml")
                && err.contains("tissue 'wall'")
                && err.contains("synthesis.occurrence must be from 0 to 10"),
            "{err}"
        );
    }
}

/// Every entry says how its photograph was taken, and surface tissues
/// carry a wet finish (the renderer's and the .glb's clear coat).
#[test]
fn every_entry_states_its_capture_and_surfaces_are_wet() {
    let db = Database::open(&shipped()).unwrap();
    for t in &db.tissues {
        assert!(t.capture.is_some(), "{} has no capture", t.id);
        if t.shelf() == Shelf::Surface {
            assert!(t.finish().coat > 0.0, "{} is dry", t.id);
        }
    }
    let porcine = db.tissue("porcine-colon").unwrap();
    assert_eq!(porcine.capture, Some(organtex::db::Capture::ExVivo));
}

/// Issue 39's colour grading on the shipped textures: matching the ex-vivo
/// porcine colon onto the in-vivo colonic mucosa puts its CIELAB mean
/// within 2 units of the mucosa's and its spread within 10%, keeps its
/// tiling, and gives the same bytes on any thread count and on a second
/// call.
///
/// Tiling: the seam score (`quality::seam`, RGB wrap jumps over interior
/// jumps) moves at most 0.02, here and on the default scene's myomas
/// (the fundus tissue matched onto the mucosa and lightened 1.1x). That
/// holds because the texture was rolled to a wrap as smooth against the
/// interior in every direction of CIELAB (`synth::wrap`); rolled to the
/// smoothest RGB sum, the porcine colon's score moved 0.638 to 0.667.
/// Each CIELAB channel's own score must stay below 1 (the wrap no rougher
/// than the interior): it moves by up to 0.025 (b*, whose spread the
/// transfer narrows to 0.76x, so the 8-bit rounding is a larger share of
/// its jumps).
#[test]
fn matching_a_tissue_moves_its_colours_and_keeps_its_tiling() {
    use organtex::db::build::{graded_colour, stats_of};
    use organtex::db::colour::{Grade, Grading, LabStats, to_lab};
    use organtex::synth::quality::{Rgb, seam, seam_by};
    let db = Database::open(&shipped()).unwrap();
    for id in ["porcine-colon", "colon-mucosa", "fundus-tissue"] {
        if !is_current(&db, db.tissue(id).unwrap()).unwrap() {
            build(&db, &[id.to_string()], &Silent).unwrap();
        }
    }
    let seam_of = |img: &image::RgbImage| {
        let pixels: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
        seam(&Rgb {
            width: img.width() as usize,
            height: img.height() as usize,
            pixels: &pixels,
        })
    };
    let lab_seams = |img: &image::RgbImage| -> [f64; 3] {
        let labs: Vec<[f32; 3]> = img.pixels().map(|p| to_lab(p.0)).collect();
        let (w, h) = (img.width() as usize, img.height() as usize);
        std::array::from_fn(|c| seam_by(w, h, |i, j| (labs[i][c] - labs[j][c]).abs() as f64))
    };
    let source_of = |id: &str| {
        image::open(db.output_path(id, Output::Colour))
            .unwrap()
            .to_rgb8()
    };
    // The graded texture of `id` and its source, with the tiling checked.
    let graded_tiling = |id: &str, grading: &Grading| {
        let path = graded_colour(&db, id, grading).unwrap();
        let graded = image::open(&path).unwrap().to_rgb8();
        let source = source_of(id);
        let (before, after) = (seam_of(&source), seam_of(&graded));
        let lab_after = lab_seams(&graded);
        println!(
            "{id}: seam RGB {before:.3} -> {after:.3}, L*a*b* {:.3?} -> {lab_after:.3?}",
            lab_seams(&source)
        );
        assert!(
            (after - before).abs() <= 0.02,
            "{id}: RGB seam {before} -> {after}"
        );
        assert!(
            lab_after.iter().all(|&s| s < 1.0),
            "{id}: L*a*b* seam {lab_after:?}"
        );
        (path, source, graded)
    };
    let grading = Grading {
        matched: Some("colon-mucosa".into()),
        ..Grading::default()
    };
    let (path, source, graded) = graded_tiling("porcine-colon", &grading);
    let got = LabStats::of(&graded);
    let want = stats_of(&db, "colon-mucosa").unwrap();
    for c in 0..3 {
        assert!(
            (got.mean[c] - want.mean[c]).abs() <= 2.0,
            "mean {got:?} vs {want:?}"
        );
        assert!(
            (got.spread[c] / want.spread[c] - 1.0).abs() <= 0.1,
            "spread {got:?} vs {want:?}"
        );
    }
    let myoma = Grading {
        brightness: 1.1,
        ..grading.clone()
    };
    graded_tiling("fundus-tissue", &myoma);
    // Same bytes: again, and on one thread.
    assert_eq!(graded_colour(&db, "porcine-colon", &grading).unwrap(), path);
    let grade = Grade {
        hue: 0.0,
        saturation: 1.0,
        brightness: 1.0,
        transfer: Some((LabStats::of(&source), want)),
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| grade.apply(&source));
    assert_eq!(one.as_raw(), graded.as_raw());
}
