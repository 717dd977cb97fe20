//! Vessels in fundus and endoscopy photographs: Frangi's multiscale
//! vesselness (Frangi, Niessen, Vincken, Viergever 1998) on the green
//! channel, where vessels are darkest against tissue; and the RGBA vessel
//! overlay made from it (vessel colours where vessels are, transparent
//! elsewhere).

use super::exemplar::Exemplar;
use super::filter::Plane;

/// Vesselness of dark tubes, in [0, 1] (the strongest response is 1), the
/// maximum over Gaussian scales `sigmas` (pixels). Masked pixels, and
/// pixels within three scales of the mask, are 0: the edge of a black
/// border is no vessel.
pub fn vesselness(ex: &Exemplar, sigmas: &[f32]) -> Vec<f32> {
    let (w, h) = (ex.width, ex.height);
    let green = Plane::new(
        w,
        h,
        ex.pixels.iter().map(|p| p[1] as f32 / 255.0).collect(),
    );
    let weight: Vec<f32> = ex.valid.iter().map(|&v| v as u8 as f32).collect();
    let mut best = vec![0.0f32; w * h];
    for &sigma in sigmas {
        let s = green.blur(sigma, &weight);
        // Hessian by central differences of the blurred image, scaled by
        // sigma^2 so scales compare.
        let mut response = vec![0.0f32; w * h];
        let mut largest = 0.0f32;
        let mut eig = vec![(0.0f32, 0.0f32); w * h];
        for y in 1..h.saturating_sub(1) {
            for x in 1..w.saturating_sub(1) {
                let c = s.at(x, y);
                let dxx = s.at(x + 1, y) - 2.0 * c + s.at(x - 1, y);
                let dyy = s.at(x, y + 1) - 2.0 * c + s.at(x, y - 1);
                let dxy = (s.at(x + 1, y + 1) - s.at(x - 1, y + 1) - s.at(x + 1, y - 1)
                    + s.at(x - 1, y - 1))
                    / 4.0;
                let (a, b, d) = (
                    dxx * sigma * sigma,
                    dxy * sigma * sigma,
                    dyy * sigma * sigma,
                );
                let mean = (a + d) / 2.0;
                let root = (((a - d) / 2.0).powi(2) + b * b).sqrt();
                // |l1| <= |l2|
                let (p, q) = (mean - root, mean + root);
                let (l1, l2) = if p.abs() <= q.abs() { (p, q) } else { (q, p) };
                eig[y * w + x] = (l1, l2);
                largest = largest.max((l1 * l1 + l2 * l2).sqrt());
            }
        }
        let beta = 0.5f32;
        let c = (largest / 2.0).max(1e-6);
        for (r, &(l1, l2)) in response.iter_mut().zip(&eig) {
            // Dark tubes curve up across the vessel: l2 > 0.
            if l2 > 0.0 {
                let rb = l1 / l2;
                let s2 = l1 * l1 + l2 * l2;
                *r = (-(rb * rb) / (2.0 * beta * beta)).exp() * (1.0 - (-s2 / (2.0 * c * c)).exp());
            }
        }
        // Keep well away from the mask's edge at this scale.
        let near_mask = super::filter::dilate(
            &ex.valid.iter().map(|v| !v).collect::<Vec<_>>(),
            w,
            h,
            (3.0 * sigma).ceil() as usize,
        );
        for i in 0..w * h {
            if !near_mask[i] {
                best[i] = best[i].max(response[i]);
            }
        }
    }
    let top = best.iter().copied().fold(0.0f32, f32::max).max(1e-12);
    best.iter().map(|v| v / top).collect()
}

/// An RGBA overlay of the vessels: the photograph's own vessel colour,
/// opaque along the vessels and fading to transparent off them.
pub fn overlay(ex: &Exemplar, vessel: &[f32]) -> Vec<[u8; 4]> {
    // Opacity ramps over the vesselness range that marks vessels.
    let (low, high) = threshold_range(vessel);
    ex.pixels
        .iter()
        .zip(vessel)
        .map(|(p, &v)| {
            let alpha = ((v - low) / (high - low)).clamp(0.0, 1.0);
            [p[0], p[1], p[2], (alpha * 255.0).round() as u8]
        })
        .collect()
}

/// The vesselness values between which a pixel turns from tissue to vessel:
/// from the 85th to the 95th percentile of the non-zero responses.
pub fn threshold_range(vessel: &[f32]) -> (f32, f32) {
    let mut v: Vec<f32> = vessel.iter().copied().filter(|&x| x > 0.0).collect();
    if v.is_empty() {
        return (1.0, 2.0);
    }
    v.sort_by(f32::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q) as usize];
    let (low, high) = (at(0.85), at(0.95));
    (low, high.max(low + 1e-6))
}
