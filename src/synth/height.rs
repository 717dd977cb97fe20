//! Height maps for bump mapping. An exemplar's height is its luminance
//! band-passed: fine relief kept, large-scale shading (an endoscope's
//! oblique light) removed, so lighting does not become slope. A synthesis
//! gets its height through its coordinate map, pixel for pixel from the
//! exemplar pixel it copied: the height is synthesised jointly with the
//! colour, tiles exactly like it, and costs nothing extra.

use super::exemplar::Exemplar;
use super::filter::Plane;
use super::fnpts::Synthesis;

/// Height of every exemplar pixel in [0, 1] (1st to 99th percentile of the
/// usable pixels mapped to 0 and 1).
pub fn exemplar_height(ex: &Exemplar) -> Vec<f32> {
    let (w, h) = (ex.width, ex.height);
    let lum = Plane::new(
        w,
        h,
        ex.pixels
            .iter()
            .map(|p| (0.299 * p[0] as f32 + 0.587 * p[1] as f32 + 0.114 * p[2] as f32) / 255.0)
            .collect(),
    );
    let weight: Vec<f32> = ex.valid.iter().map(|&v| v as u8 as f32).collect();
    let detail = lum.blur(1.0, &weight);
    let shading = lum.blur(w.min(h) as f32 / 16.0, &weight);
    let band: Vec<f32> = detail
        .data
        .iter()
        .zip(&shading.data)
        .map(|(d, s)| d - s)
        .collect();
    let mut usable: Vec<f32> = band
        .iter()
        .zip(&ex.valid)
        .filter(|(_, v)| **v)
        .map(|(b, _)| *b)
        .collect();
    usable.sort_by(f32::total_cmp);
    let at = |q: f64| {
        usable
            .get(((usable.len().max(1) - 1) as f64 * q) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    let (lo, hi) = (at(0.01), at(0.99));
    let span = (hi - lo).max(1e-6);
    band.iter()
        .map(|b| ((b - lo) / span).clamp(0.0, 1.0))
        .collect()
}

/// A synthesis's height map, 16 bits, from the exemplar's heights.
pub fn synthesis_height(exemplar_height: &[f32], exemplar_width: usize, s: &Synthesis) -> Vec<u16> {
    s.coords
        .iter()
        .map(|c| {
            let h = exemplar_height[c[1] as usize * exemplar_width + c[0] as usize];
            (h * 65535.0).round() as u16
        })
        .collect()
}
