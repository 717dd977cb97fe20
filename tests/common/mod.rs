//! Helpers shared by the integration tests. Each test file compiles this
//! module on its own and uses only some of it.
#![allow(dead_code)]

use std::process::Command;

/// Run the organtex binary: whether it succeeded, its stdout and stderr.
pub fn organtex(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(args)
        .output()
        .expect("run organtex");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Luminance (mean of R, G, B) of the pixels brighter than the
/// background, with their mean and variance.
pub fn lit_pixels(img: &image::RgbaImage) -> (usize, f64, f64) {
    let lum: Vec<f64> = img
        .pixels()
        .map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0)
        .filter(|&l| l > 12.0)
        .collect();
    let n = lum.len().max(1) as f64;
    let mean = lum.iter().sum::<f64>() / n;
    let var = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n;
    (lum.len(), mean, var)
}

/// How many pixels differ between two pictures of the same size.
pub fn changed_pixels(a: &image::RgbaImage, b: &image::RgbaImage) -> usize {
    a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
}

/// A photograph of the tissue database, or a texture of tests/data/textures
/// (gravel, grass, brick: not tissue, kept for synthesis tests).
pub fn source(name: &str) -> std::path::PathBuf {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let texture = root.join("tests/data/textures").join(name);
    if texture.is_file() {
        texture
    } else {
        root.join("database/sources").join(name)
    }
}

/// The quality of a tileable `side`-pixel 2D synthesis from `ex` with
/// `levels` pyramid levels (`None`: the default): the reference 3D
/// synthesis is held to.
pub fn flat_quality(
    ex: &organtex::synth::exemplar::Exemplar,
    side: usize,
    levels: Option<usize>,
) -> organtex::synth::quality::Quality {
    use organtex::synth::fnpts::{SynthOptions, synthesize};
    use organtex::synth::quality::{Rgb, measure};
    let texture = synthesize(
        ex,
        &SynthOptions {
            width: side,
            height: side,
            tileable: true,
            levels,
            ..SynthOptions::default()
        },
        &organtex::progress::Silent,
    )
    .expect("2D synthesis");
    measure(
        ex,
        &Rgb {
            width: side,
            height: side,
            pixels: &texture.pixels,
        },
    )
}
