//! Layered solid exemplars (issue 23; seed 002, 4.2) from a real layered
//! exemplar, database/sources/layered_wall.png (three histology
//! photographs stacked by depth, tools/make_layered_exemplar.py): the
//! block's layers follow the exemplar's, its slices through depth are as
//! close to the exemplar as a 2D synthesis of their size, the sweep fix
//! removes the diagonal sweep, the depth axis travels in the NRRD header to
//! the LST reader, and bad input is refused clearly.

mod common;
use common::flat_quality;
use organtex::progress::Silent;
use organtex::synth::block::layered::{
    LayeredOptions, measure_layered, sweep_score, synthesize_layered,
};
use organtex::synth::exemplar::Exemplar;
use organtex::synth::volume::Volume;

fn wall(rows: usize) -> Exemplar {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("database/sources/layered_wall.png");
    Exemplar::load(&path, None, None)
        .expect("the layered exemplar")
        .with_height(rows)
        .expect("scaled")
}

#[test]
fn a_layered_block_follows_its_layers_and_the_sweep_fix_removes_the_sweep() {
    let e = wall(64);
    let opts = LayeredOptions::default();
    let block = synthesize_layered(&e, &opts, &Silent).expect("layered block");
    assert_eq!(block.size, [64; 3]);
    let q = measure_layered(&block, &e, 4);
    // 2D synthesis of a 64-pixel tile from the same exemplar, with two
    // pyramid levels (the 2D default's depth there when the 1.5x bounds
    // below were set), and with today's deeper default.
    let q2 = flat_quality(&e, 64, Some(2));
    let deeper = flat_quality(&e, 64, None);
    let swept = synthesize_layered(
        &e,
        &LayeredOptions {
            sweep_fix: false,
            ..opts.clone()
        },
        &Silent,
    )
    .expect("without the fix");
    let sweep_off = sweep_score(&swept, 4);
    eprintln!(
        "layered 64: rows RMS {:.2}, coherence {:.2} / completeness {:.2} (2D: {:.2} / {:.2}, default {:.2} / {:.2}), sweep {:.3} (fix off: {sweep_off:.3})",
        q.rows_rms,
        q.coherence,
        q.completeness,
        q2.coherence,
        q2.completeness,
        deeper.coherence,
        deeper.completeness,
        q.sweep
    );
    assert!(q.rows_rms <= 8.0, "rows RMS {:.2}", q.rows_rms);
    assert!(q.coherence <= 1.5 * q2.coherence, "{q:?} vs 2D {q2:?}");
    assert!(
        q.completeness <= 1.5 * q2.completeness,
        "{q:?} vs 2D {q2:?}"
    );
    // Against today's default the block is about 1.8x in coherence and
    // 1.5x in completeness (2026-11-28): held there so the gap cannot grow
    // unseen.
    assert!(
        q.coherence <= 2.0 * deeper.coherence && q.completeness <= 1.7 * deeper.completeness,
        "{q:?} vs the default 2D {deeper:?}"
    );
    assert!(
        sweep_off > q.sweep + 0.1,
        "the sweep fix must show: {:.3} with, {sweep_off:.3} without",
        q.sweep
    );
    // The outer layer is the exemplar's top: the block's first rows are
    // nearer the exemplar's top band than its bottom one in mean colour.
    let mean_row = |v: &Volume, y: usize| {
        let mut m = [0f64; 3];
        for z in 0..64 {
            for x in 0..64 {
                let c = v.voxels[v.index(x, y, z)];
                for k in 0..3 {
                    m[k] += c[k] as f64 / 4096.0;
                }
            }
        }
        m
    };
    let ex_row = |y: usize| {
        let mut m = [0f64; 3];
        for x in 0..e.width {
            for (mk, &c) in m.iter_mut().zip(&e.pixels[e.index(x, y)]) {
                *mk += c as f64 / e.width as f64;
            }
        }
        m
    };
    let dist = |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).abs()).sum::<f64>();
    let top = mean_row(&block, 2);
    assert!(dist(top, ex_row(2)) < dist(top, ex_row(60)));
}

#[test]
fn same_bytes_on_any_thread_count() {
    let e = wall(32);
    let opts = LayeredOptions {
        size: 32,
        iterations: 2,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| synthesize_layered(&e, &opts, &Silent).expect("block"))
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn the_depth_axis_travels_in_the_nrrd_header_to_the_lst_reader() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A 4 x 3 x 2 block whose colour says where each voxel was.
    let size = [4, 3, 2];
    let voxels = (0..24u8).map(|i| [i % 4, i / 4 % 3, i / 12]).collect();
    let v = Volume {
        size,
        spacing: 1.0,
        voxels,
    };
    for (axis, &side) in size.iter().enumerate() {
        let path = dir.path().join(format!("d{axis}.nrrd"));
        v.write_nrrd_with_depth(&path, Some(axis)).expect("write");
        let (back, depth) = Volume::read_nrrd_with_depth(&path).expect("read");
        assert_eq!((back.clone(), depth), (v.clone(), Some(axis)));
        // The LST reader turns the depth onto y: voxel (x, y, z) of the
        // result has its depth coordinate in y.
        let lst = Volume::read_exemplar(&path).expect("exemplar");
        assert_eq!(lst.size[1], side);
        for z in 0..lst.size[2] {
            for y in 0..lst.size[1] {
                for x in 0..lst.size[0] {
                    assert_eq!(lst.voxels[lst.index(x, y, z)][axis], y as u8);
                }
            }
        }
    }
    let plain = dir.path().join("plain.nrrd");
    v.write_nrrd(&plain).expect("write");
    assert_eq!(Volume::read_nrrd_with_depth(&plain).expect("read").1, None);
    let bad = String::from_utf8_lossy(&v.to_nrrd_with_depth(Some(1)))
        .replace("organtex_depth_axis:=y", "organtex_depth_axis:=w");
    let bad_path = dir.path().join("bad.nrrd");
    std::fs::write(&bad_path, bad).expect("write");
    let e = Volume::read_nrrd(&bad_path)
        .expect_err("a bad axis")
        .to_string();
    assert!(e.contains("bad.nrrd") && e.contains("x, y or z"), "{e}");
}

#[test]
fn bad_layered_input_gives_clear_errors() {
    // Too short for the pyramid: 3 levels of a 5 x 5 neighbourhood need 20
    // pixels a side.
    let src = wall(32);
    let narrow = Exemplar::new(
        8,
        32,
        (0..32)
            .flat_map(|y| {
                let src = &src;
                (0..8).map(move |x| src.pixels[src.index(x, y)])
            })
            .collect(),
        vec![true; 8 * 32],
    )
    .expect("narrow");
    let e = synthesize_layered(
        &narrow,
        &LayeredOptions {
            size: 32,
            levels: Some(3),
            ..Default::default()
        },
        &Silent,
    )
    .expect_err("too narrow")
    .to_string();
    assert!(e.contains("too small for 3 pyramid levels"), "{e}");
    // Rows that are not the block's depth.
    let e = synthesize_layered(&wall(48), &LayeredOptions::default(), &Silent)
        .expect_err("48 rows for 64 voxels")
        .to_string();
    assert!(e.contains("64 rows tall"), "{e}");
    // Through the CLI: one line naming the file, non-zero exit, no output.
    let dir = tempfile::tempdir().expect("tempdir");
    let tiny = dir.path().join("tiny.png");
    image::RgbImage::from_pixel(3, 2, image::Rgb([9, 9, 9]))
        .save(&tiny)
        .expect("png");
    let out = dir.path().join("b.nrrd");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(["synth3d", "--layered", "--size", "64", "-o"])
        .arg(&out)
        .arg(&tiny)
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("tiny.png"), "{stderr}");
    assert!(!out.exists());
}
