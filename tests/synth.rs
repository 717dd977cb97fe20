//! Texture synthesis on the database's real photographs: masked pixels are
//! never copied, tileable outputs tile, heights follow the colours, vessels
//! are found, the same seed gives the same bytes, and sparse-feature
//! tissues keep up with Embark's synthesiser.

mod common;
use common::source;
use std::process::Command;

use organtex::progress::Silent;
use organtex::synth::exemplar::{Crop, Exemplar};
use organtex::synth::fnpts::{SynthOptions, Synthesis, synthesize};
use organtex::synth::height::{exemplar_height, synthesis_height};
use organtex::synth::quality::{Rgb, measure, seam};
use organtex::synth::vessel_tree;
use organtex::synth::vessels::{self, vesselness};

fn crop(name: &str, x: u32, y: u32, side: u32) -> Exemplar {
    Exemplar::load(
        &source(name),
        None,
        Some(Crop {
            x,
            y,
            width: side,
            height: side,
        }),
    )
    .unwrap()
}

fn tileable(size: usize, seed: u64) -> SynthOptions {
    SynthOptions {
        width: size,
        height: size,
        tileable: true,
        seed,
        ..SynthOptions::default()
    }
}

fn rgb(s: &Synthesis) -> Rgb<'_> {
    Rgb {
        width: s.width,
        height: s.height,
        pixels: &s.pixels,
    }
}

#[test]
fn no_masked_pixel_is_ever_copied() {
    // Paint blobs of the exemplar magenta, a colour found nowhere in gravel,
    // and mask them out.
    let mut ex = crop("gravel.png", 0, 0, 160);
    let magenta = [255, 0, 255];
    assert!(!ex.pixels.contains(&magenta));
    for y in 0..ex.height {
        for x in 0..ex.width {
            let blob = ((x as i64 - 40).pow(2) + (y as i64 - 50).pow(2)) < 400
                || (x / 16 + y / 16) % 7 == 0;
            if blob {
                let i = ex.index(x, y);
                ex.pixels[i] = magenta;
                ex.valid[i] = false;
            }
        }
    }
    for seed in 0..3 {
        let out = synthesize(&ex, &tileable(200, seed), &Silent).unwrap();
        for (c, p) in out.coords.iter().zip(&out.pixels) {
            assert!(
                ex.valid[ex.index(c[0] as usize, c[1] as usize)],
                "copied masked pixel {c:?}"
            );
            assert_ne!(*p, magenta);
            assert_eq!(
                *p,
                ex.pixels[ex.index(c[0] as usize, c[1] as usize)],
                "colours come from their coordinates"
            );
        }
    }
}

#[test]
fn tileable_outputs_tile_on_every_exemplar() {
    for (name, x, y) in [
        ("retina.jpg", 760, 200),
        ("ihc.png", 100, 100),
        ("gravel.png", 0, 0),
    ] {
        let ex = crop(name, x, y, 128);
        for seed in 0..3 {
            let out = synthesize(&ex, &tileable(256, seed), &Silent).unwrap();
            let s = seam(&rgb(&out));
            assert!(s <= 1.15, "{name} seed {seed}: seam {s}");
        }
    }
}

#[test]
fn the_output_resembles_the_exemplar_more_than_noise_does() {
    let ex = crop("ihc.png", 100, 100, 128);
    let out = synthesize(&ex, &tileable(256, 0), &Silent).unwrap();
    let q = measure(&ex, &rgb(&out));
    // The same pixels shuffled: every colour right, no structure left.
    let mut shuffled = out.pixels.clone();
    let n = shuffled.len();
    for i in (1..n).rev() {
        shuffled.swap(i, organtex::rng::below(9, &[i as u64], i + 1));
    }
    let noise = measure(
        &ex,
        &Rgb {
            width: out.width,
            height: out.height,
            pixels: &shuffled,
        },
    );
    assert!(q.coherence < noise.coherence / 3.0, "{q:?} vs {noise:?}");
    assert!(q.completeness < noise.completeness, "{q:?} vs {noise:?}");
}

#[test]
fn heights_follow_the_coordinates_and_tile_too() {
    let ex = crop("gravel.png", 100, 100, 128);
    let out = synthesize(&ex, &tileable(192, 1), &Silent).unwrap();
    let eh = exemplar_height(&ex);
    let h = synthesis_height(&eh, ex.width, &out);
    for (c, v) in out.coords.iter().zip(&h) {
        let expected = (eh[ex.index(c[0] as usize, c[1] as usize)] * 65535.0).round() as u16;
        assert_eq!(*v, expected);
    }
    // As a grey image, the height tiles like the colour.
    let grey: Vec<[u8; 3]> = h.iter().map(|&v| [(v >> 8) as u8; 3]).collect();
    let s = seam(&Rgb {
        width: out.width,
        height: out.height,
        pixels: &grey,
    });
    assert!(s <= 1.15, "height seam {s}");
    assert!(
        h.iter().any(|&v| v > 50_000) && h.iter().any(|&v| v < 15_000),
        "heights span their range"
    );
}

#[test]
fn vesselness_finds_a_dark_line_and_nothing_else() {
    // A dark horizontal band (a vessel) on bright tissue with mild noise.
    let (w, h) = (96, 64);
    let pixels: Vec<[u8; 3]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let noise = (organtex::rng::below(3, &[i as u64], 9)) as u8;
            if (30..34).contains(&y) && (10..86).contains(&x) {
                [120, 60 + noise, 50]
            } else {
                [220, 150 + noise, 120]
            }
        })
        .collect();
    let ex = Exemplar::new(w, h, pixels, vec![true; w * h]).unwrap();
    let v = vesselness(&ex, &[1.5, 2.5]);
    let on = v[32 * w + 48];
    let off = (0..w * h)
        .filter(|i| (i / w) < 20 || (i / w) > 44)
        .map(|i| v[i])
        .fold(0.0f32, f32::max);
    assert!(on > 0.5, "on the vessel: {on}");
    assert!(off < 0.1 * on, "off the vessel: {off}");
}

#[test]
fn the_same_seed_gives_the_same_bytes_on_one_or_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for threads in ["1", "2", "2"] {
        let out = dir.path().join(format!("t{}.png", outputs.len()));
        let coords = dir.path().join(format!("c{}.png", outputs.len()));
        let status = Command::new(env!("CARGO_BIN_EXE_organtex"))
            .args([
                "synth",
                source("ihc.png").to_str().unwrap(),
                "--crop",
                "0,0,128,128",
                "--size",
                "200x150",
                "--tileable",
                "--seed",
                "7",
                "-o",
            ])
            .arg(&out)
            .arg("--coords-out")
            .arg(&coords)
            .env("RAYON_NUM_THREADS", threads)
            .status()
            .unwrap();
        assert!(status.success());
        outputs.push((std::fs::read(out).unwrap(), std::fs::read(coords).unwrap()));
    }
    assert!(outputs[0] == outputs[1] && outputs[1] == outputs[2]);
    let other_seed = synthesize(&crop("ihc.png", 0, 0, 128), &tileable(64, 8), &Silent).unwrap();
    let again = synthesize(&crop("ihc.png", 0, 0, 128), &tileable(64, 9), &Silent).unwrap();
    assert_ne!(
        other_seed.pixels, again.pixels,
        "different seeds give different textures"
    );
}

/// The overlay over white, as RGB.
fn over_white(rgba: &[[u8; 4]]) -> Vec<[u8; 3]> {
    rgba.iter()
        .map(|p| {
            let a = p[3] as f64 / 255.0;
            [0, 1, 2].map(|k| (p[k] as f64 * a + 255.0 * (1.0 - a)).round() as u8)
        })
        .collect()
}

/// Connected groups of pixels showing vessel, 8-neighbours, wrapping around.
fn vessel_pieces(rgba: &[[u8; 4]], w: usize, h: usize) -> usize {
    let opaque: Vec<bool> = rgba
        .iter()
        .map(|p| p[3] >= vessel_tree::VESSEL_SEEN)
        .collect();
    let mut seen = vec![false; w * h];
    let mut pieces = 0;
    for start in 0..w * h {
        if !opaque[start] || seen[start] {
            continue;
        }
        pieces += 1;
        seen[start] = true;
        let mut stack = vec![start];
        while let Some(i) = stack.pop() {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let j = (y + dy).rem_euclid(h as i64) as usize * w
                        + (x + dx).rem_euclid(w as i64) as usize;
                    if opaque[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
    }
    pieces
}

#[test]
fn the_vessel_overlay_tiles_in_at_most_one_piece_per_tree_as_the_photograph_covers() {
    // The database's fundus crop.
    let ex = crop("retina.jpg", 560, 180, 640);
    let (w, h) = (ex.width, ex.height);
    let scales = [1.0, 1.6, 2.56, 3.84];
    let photo = vessels::overlay(&ex, &vesselness(&ex, &scales));
    let tiled = vessel_tree::tileable_overlay(&photo, w, h, 0);
    let seam_of = |rgba: &[[u8; 4]]| {
        seam(&Rgb {
            width: w,
            height: h,
            pixels: &over_white(rgba),
        })
    };
    // Vessels cross the tile's edges and continue across them (the
    // photograph's stop short of its edges, where its vesselness is 0).
    let after = seam_of(&tiled);
    assert!(after <= 1.15, "the grown vessels do not tile ({after})");
    let crossing = |rgba: &[[u8; 4]]| {
        (0..w).any(|x| rgba[x][3] >= vessel_tree::VESSEL_SEEN)
            && (0..h).any(|y| rgba[y * w][3] >= vessel_tree::VESSEL_SEEN)
    };
    assert!(crossing(&tiled));
    assert!(!crossing(&photo));
    // Whole vessels: at most a piece per root (trees may meet), where the
    // photograph's vesselness breaks into many.
    let roots = vessel_tree::TreeOptions::new(w, h, 0).roots;
    let pieces = vessel_pieces(&tiled, w, h);
    assert!((1..=roots).contains(&pieces), "{pieces} pieces");
    // As much vessel as the photograph shows.
    let opacity = |rgba: &[[u8; 4]]| vessel_tree::opacity(rgba.iter().map(|p| p[3]));
    let (c0, c1) = (opacity(&photo), opacity(&tiled));
    assert!((c1 - c0).abs() <= 0.05 * c0, "opacity {c1} against {c0}");
    // The colour of the photograph's vessels.
    let opaque: Vec<&[u8; 4]> = photo
        .iter()
        .filter(|p| p[3] >= vessel_tree::VESSEL_SEEN)
        .collect();
    let mean = |k: usize| opaque.iter().map(|p| p[k] as f64).sum::<f64>() / opaque.len() as f64;
    for (k, &c) in tiled[0][..3].iter().enumerate() {
        assert!((c as f64 - mean(k)).abs() <= 20.0, "channel {k}");
    }
    assert_eq!(vessel_tree::tileable_overlay(&photo, w, h, 0), tiled);
    assert_ne!(vessel_tree::tileable_overlay(&photo, w, h, 1), tiled);
}

/// Issue 28: on tissues with sparse features on an even background (thin
/// vessels on mucosa, a few vessels on serosa, fat lobules), where the
/// added occurrence cost and a shallow pyramid lost to Embark's
/// synthesiser, the output's coherence and completeness stay at or below
/// Embark's, as tools/compare_synth.py measured them (median of 3 seeds,
/// 512-pixel tiles from the same masked exemplar; the lower of the
/// 2026-11-24 and 2026-11-28 runs' figures). The
/// figures before the fix, seed 1: coherence 1.61, 3.12, 2.41 and 1.14.
#[test]
fn sparse_feature_tissues_match_embark_on_coherence_and_completeness() {
    let db = organtex::db::Database::open(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("database"),
    )
    .unwrap();
    // (entry, Embark's coherence, Embark's completeness)
    for (id, coherence, completeness) in [
        ("colon-mucosa", 1.39, 2.20),
        ("omental-fat", 2.05, 12.49),
        ("gastric-serosa", 1.45, 9.90),
        ("porcine-colon", 1.06, 2.49),
    ] {
        let ex = organtex::db::build::exemplar(&db, db.tissue(id).unwrap()).unwrap();
        let s = synthesize(&ex, &tileable(512, 1), &Silent).unwrap();
        let q = measure(&ex, &rgb(&s));
        assert!(
            q.coherence <= coherence && q.completeness <= completeness,
            "{id}: coherence {:.2} (Embark {coherence}), completeness {:.2} (Embark {completeness})",
            q.coherence,
            q.completeness
        );
    }
}
