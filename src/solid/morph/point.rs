//! The colour of one point (seed 003, 5.2 and 5.3).
//!
//! 1. The point's region; per bounding exemplar its source point p_i and
//!    its height t_i above the plane (4.2); Shepard weights w_i ∝ 1/|t_i|,
//!    so a point on an exemplar takes that exemplar alone and the colour is
//!    continuous across every region boundary (each boundary is an
//!    exemplar).
//! 2. The inverse warp by its first-order approximation (eq. 4):
//!    q_i = w_i p_i + Σ_j≠i w_j f_ji(p_j), exact where one weight is 1.
//! 3. Beyond the paper: the low band is interpolated (sampled at the
//!    source points p_i, not morphed) and only the detail band is
//!    morphed (sampled at the q_i). On the brain MRI ground truth
//!    (`tools/compare_morph.py`) morphing the low band too moved coarse
//!    structure that is not a deformation of its neighbour's (a ventricle
//!    that closes) and scored a blurred RMS of 31.4 against 26.5 so.
//! 4. Mixing detail that does not line up lowers its contrast, so the
//!    detail's local histogram is matched to the exemplars' (5.3): over a
//!    window of 9 taps (its centre, 4 at distance 3 along the axes and 4
//!    at (±2, ±2), in units of the low band's σ / 2 so the window spans
//!    the detail band's features; 7x7 at σ = 2) the mixed detail is
//!    scaled about its mean until its deviation
//!    is the weighted mean of the exemplars' deviations over the same
//!    taps. The paper precomputes 7x7 histograms per pixel and takes the
//!    target's from neighbouring surface points; reading both from the
//!    same taps at the warped points keeps one point independent of any
//!    other, makes the match exact (gain 1) where one weight is 1, and
//!    stores nothing per pixel. Matching the first two moments is the
//!    Gaussian case of histogram matching; the gain is at least 1 (a
//!    mix's deviation never exceeds the mixed deviations' weighted sum)
//!    and is capped at `MAX_GAIN`.

use glam::{DVec2, DVec3};

use super::{MAX_BOUNDS, Morph};

/// Weights below this are dropped (and the rest renormalised): they change
/// no colour by a thousandth of a level.
const NEGLIGIBLE: f64 = 1e-6;
const MAX_GAIN: f32 = 3.0;

/// The window's taps, in exemplar pixels; the centre first.
const TAPS: [(f64, f64); 9] = [
    (0.0, 0.0),
    (3.0, 0.0),
    (-3.0, 0.0),
    (0.0, 3.0),
    (0.0, -3.0),
    (2.0, 2.0),
    (-2.0, 2.0),
    (2.0, -2.0),
    (-2.0, -2.0),
];

pub(super) fn colour(m: &Morph, p: DVec3) -> [u8; 3] {
    let r = m.bsp.locate(&m.exemplars, p);
    let bounds = &m.bsp.regions[r].bounds;
    let k = bounds.len();
    let mut source = [DVec2::ZERO; MAX_BOUNDS];
    let mut w = [0.0f64; MAX_BOUNDS];
    let mut on_plane = None;
    for (s, b) in bounds.iter().enumerate() {
        let (t, q) = m.sweeps[b.exemplar].source(&m.exemplars[b.exemplar], p);
        source[s] = q;
        if t == 0.0 && on_plane.is_none() {
            on_plane = Some(s);
        }
        w[s] = 1.0 / t.abs();
    }
    if let Some(s) = on_plane {
        w = [0.0; MAX_BOUNDS];
        w[s] = 1.0;
    }
    normalise(&mut w[..k]);
    for x in &mut w[..k] {
        if *x < NEGLIGIBLE {
            *x = 0.0;
        }
    }
    normalise(&mut w[..k]);

    // Eq. 4.
    let warps = &m.warps[r];
    let mut q = [DVec2::ZERO; MAX_BOUNDS];
    for s in 0..k {
        if w[s] == 0.0 {
            continue;
        }
        let mut acc = source[s] * w[s];
        for j in 0..k {
            if j != s && w[j] > 0.0 {
                // Present for every j != s of the region (built so).
                let f = warps[j * k + s].as_ref().expect("warp between bounds");
                acc += f.at(source[j]) * w[j];
            }
        }
        q[s] = acc;
    }

    let low = mix(m, r, &w[..k], &source[..k], |b| &b.low);
    let detail = if m.options.matching {
        matched_detail(m, r, &w[..k], &q[..k])
    } else {
        mix(m, r, &w[..k], &q[..k], |b| &b.detail)
    };
    std::array::from_fn(|c| (low[c] + detail[c]).round().clamp(0.0, 255.0) as u8)
}

/// The weighted sum of a band of region `r`'s bounds, each sampled at its
/// own point.
#[inline]
fn mix(
    m: &Morph,
    r: usize,
    w: &[f64],
    at: &[DVec2],
    band: impl Fn(&super::bands::Bands) -> &[[f32; 3]],
) -> [f32; 3] {
    let bounds = &m.bsp.regions[r].bounds;
    let mut sum = [0.0f32; 3];
    for (s, (&ws, &q)) in w.iter().zip(at).enumerate() {
        if ws > 0.0 {
            let bands = &m.bands[bounds[s].exemplar];
            let x = bands.sample(band(bands), q);
            for c in 0..3 {
                sum[c] += ws as f32 * x[c];
            }
        }
    }
    sum
}

fn normalise(w: &mut [f64]) {
    let sum: f64 = w.iter().sum();
    for x in w {
        *x /= sum;
    }
}

/// The mixed detail band at the centre tap, its local histogram matched
/// (see the module's comment).
fn matched_detail(m: &Morph, r: usize, w: &[f64], q: &[DVec2]) -> [f32; 3] {
    let bounds = &m.bsp.regions[r].bounds;
    let n = TAPS.len() as f32;
    let reach = (m.options.low_sigma as f64 / 2.0).max(1.0);
    let mut mix = [[0.0f32; 3]; TAPS.len()];
    let mut target = [0.0f32; 3];
    for (s, (&ws, &qs)) in w.iter().zip(q).enumerate() {
        if ws == 0.0 {
            continue;
        }
        let bands = &m.bands[bounds[s].exemplar];
        let ws = ws as f32;
        let mut sum = [0.0f32; 3];
        let mut sq = [0.0f32; 3];
        for (tap, &(dx, dy)) in mix.iter_mut().zip(&TAPS) {
            let x = bands.sample(&bands.detail, qs + DVec2::new(dx, dy) * reach);
            for c in 0..3 {
                tap[c] += ws * x[c];
                sum[c] += x[c];
                sq[c] += x[c] * x[c];
            }
        }
        for c in 0..3 {
            let mean = sum[c] / n;
            target[c] += ws * (sq[c] / n - mean * mean).max(0.0).sqrt();
        }
    }
    std::array::from_fn(|c| {
        let mean = mix.iter().map(|t| t[c]).sum::<f32>() / n;
        let var = mix.iter().map(|t| (t[c] - mean).powi(2)).sum::<f32>() / n;
        let sd = var.sqrt();
        let gain = if sd > 1e-3 {
            (target[c] / sd).clamp(1.0, MAX_GAIN)
        } else {
            1.0
        };
        mean + (mix[0][c] - mean) * gain
    })
}
