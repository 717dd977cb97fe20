//! Alpha masks of pasted patches (seed 000, sec. 5.2.1 and 5.2.7): a
//! procedural 3D "splotch", a blob whose radius wanders with direction,
//! alpha 1 inside and falling to 0 over `FALLOFF` of the texture's size
//! (the paper found 5-10% best); and for depth-varying exemplars the same
//! blob across the texture's r-t plane, cut to an outer, middle or inner
//! band of depth (the s axis), so a patch pasted near the surface shows the
//! exemplar's outer layer right up to it.

use crate::rng;

/// Width of the alpha fall-off, in texture units (the patch spans [0, 1]).
pub const FALLOFF: f64 = 0.075;
/// The blob's mean radius; with the wander below it stays inside the unit
/// cube, so no patch shows the texture's wrap.
pub(super) const RADIUS: f64 = 0.4;
/// Relative wander of the radius with direction.
pub(super) const WANDER: f64 = 0.12;
/// Depth bands of the three layered masks (outer ends at `BAND_OUTER`,
/// middle spans `BAND_MIDDLE`, inner starts at `BAND_INNER`), overlapping
/// so every depth is fully inside one of them.
pub(super) const BAND_OUTER: f64 = 0.4;
pub(super) const BAND_MIDDLE: (f64, f64) = (0.3, 0.7);
pub(super) const BAND_INNER: f64 = 0.6;

/// Which mask a patch uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MaskKind {
    /// The 3D splotch (types 0, 1-a, 2-a).
    Splotch = 0,
    /// Depth bands of a layered exemplar (types 1-b, 2-b).
    Outer = 1,
    Middle = 2,
    Inner = 3,
}

impl MaskKind {
    pub fn from_u8(k: u8) -> Option<MaskKind> {
        [
            MaskKind::Splotch,
            MaskKind::Outer,
            MaskKind::Middle,
            MaskKind::Inner,
        ]
        .get(k as usize)
        .copied()
    }

    /// The band for a patch whose seed lies at depth `d`; its band holds
    /// `d` with alpha 1.
    pub fn for_depth(d: f64) -> MaskKind {
        if d < 1.0 / 3.0 {
            MaskKind::Outer
        } else if d > 2.0 / 3.0 {
            MaskKind::Inner
        } else {
            MaskKind::Middle
        }
    }
}

/// The splotch's shape: a few random cosine waves over the unit sphere of
/// directions, fixed by a seed.
#[derive(Clone, Debug, PartialEq)]
pub struct Splotch {
    waves: Vec<([f64; 3], f64, f64)>,
}

/// Smooth step from 1 (at `x <= 0`) down to 0 (at `x >= 1`).
#[inline]
fn fall(x: f64) -> f64 {
    let t = x.clamp(0.0, 1.0);
    1.0 - t * t * (3.0 - 2.0 * t)
}

impl Splotch {
    pub fn new(seed: u64) -> Splotch {
        let waves = (0..6u64)
            .map(|k| {
                let u = rng::unit(seed, &[k, 0]) * 2.0 - 1.0;
                let phi = rng::unit(seed, &[k, 1]) * std::f64::consts::TAU;
                let s = (1.0 - u * u).sqrt();
                let freq = 1.0 + 2.0 * rng::unit(seed, &[k, 2]);
                let dir = [s * phi.cos() * freq, s * phi.sin() * freq, u * freq];
                (
                    dir,
                    rng::unit(seed, &[k, 3]) * std::f64::consts::TAU,
                    1.0 / 6.0,
                )
            })
            .collect();
        Splotch { waves }
    }

    /// Its waves: direction times frequency, phase, amplitude.
    pub fn waves(&self) -> &[([f64; 3], f64, f64)] {
        &self.waves
    }

    /// The blob's radius towards the unit direction `d`.
    fn radius(&self, d: [f64; 3]) -> f64 {
        let wander: f64 = self
            .waves
            .iter()
            .map(|(w, phase, amp)| amp * (w[0] * d[0] + w[1] * d[1] + w[2] * d[2] + phase).cos())
            .sum();
        RADIUS * (1.0 + WANDER * wander)
    }

    /// The mask's alpha at texture coordinates `w` (r, s, t).
    pub fn alpha(&self, kind: MaskKind, w: [f64; 3]) -> f64 {
        mask_alpha(kind, w, |d| self.radius(d))
    }

    /// The same masks with the bands' edge read from a table (`Lateral`).
    pub fn tabulated(&self) -> TabulatedSplotch<'_> {
        TabulatedSplotch {
            splotch: self,
            lateral: Lateral::new(self),
        }
    }
}

/// A splotch whose bands' edge (a function of the direction in the r-t
/// plane) comes from a table: the pasting's coverage counts (sec. 5.2.6)
/// evaluate it at 165 points of every tet in every clump, and the six
/// cosines per point were a third of the fill's time. The table's alpha
/// is within 1e-5 of `Splotch::alpha`'s (test), far below the 1/510 that
/// coverage's rounding to bytes already allows; the colours themselves
/// always take the exact mask.
pub struct TabulatedSplotch<'a> {
    splotch: &'a Splotch,
    lateral: Lateral,
}

impl TabulatedSplotch<'_> {
    pub fn alpha(&self, kind: MaskKind, w: [f64; 3]) -> f64 {
        match kind {
            MaskKind::Splotch => self.splotch.alpha(kind, w),
            _ => mask_alpha(kind, w, |d| self.lateral.radius(d)),
        }
    }
}

/// The blob's radius over directions in the r-t plane, sampled at even
/// steps of the "diamond angle" (a monotonic stand-in for the angle that
/// needs no arc tangent) and interpolated linearly.
struct Lateral {
    radius: Vec<f64>,
}

impl Lateral {
    const STEPS: usize = 4096;

    fn new(splotch: &Splotch) -> Lateral {
        let radius = (0..=Self::STEPS)
            .map(|i| {
                let q = 4.0 * i as f64 / Self::STEPS as f64;
                // The direction whose `diamond` is q.
                let (x, z) = if q < 2.0 {
                    (1.0 - q, 1.0 - (1.0 - q).abs())
                } else {
                    (q - 3.0, -(1.0 - (q - 3.0).abs()))
                };
                let r = (x * x + z * z).sqrt();
                splotch.radius([x / r, 0.0, z / r])
            })
            .collect();
        Lateral { radius }
    }

    /// Towards the unit direction `d` (its s component 0).
    #[inline]
    fn radius(&self, d: [f64; 3]) -> f64 {
        let at = diamond(d[0], d[2]) * (Self::STEPS as f64 / 4.0);
        let i = (at as usize).min(Self::STEPS - 1);
        let f = at - i as f64;
        self.radius[i] * (1.0 - f) + self.radius[i + 1] * f
    }
}

/// The diamond angle of the direction (x, z): 0 towards +x, rising to 4
/// the way the angle does (1 at +z, 2 at -x, 3 at -z).
#[inline]
fn diamond(x: f64, z: f64) -> f64 {
    let u = x / (x.abs() + z.abs());
    if z >= 0.0 { 1.0 - u } else { 3.0 + u }
}

/// `Splotch::alpha` with the blob's edge towards a unit direction given.
#[inline]
fn mask_alpha(kind: MaskKind, w: [f64; 3], radius: impl Fn([f64; 3]) -> f64) -> f64 {
    let c = [w[0] - 0.5, w[1] - 0.5, w[2] - 0.5];
    // The radius stays within RADIUS (1 +- WANDER) (the waves' amplitudes
    // add up to 1): inside its least, less the fall-off, alpha is 1;
    // past its most, 0, without evaluating the waves.
    let (least, most) = (RADIUS * (1.0 - WANDER) - FALLOFF, RADIUS * (1.0 + WANDER));
    match kind {
        MaskKind::Splotch => {
            let r = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            if r <= least {
                return 1.0;
            }
            if r >= most {
                return 0.0;
            }
            let edge = radius([c[0] / r, c[1] / r, c[2] / r]);
            fall((r - (edge - FALLOFF)) / FALLOFF)
        }
        band => {
            // The depth factor first: past the band it is 0 without the
            // lateral edge's look-up.
            let s = w[1];
            let depth = match band {
                MaskKind::Outer => fall((s - BAND_OUTER) / FALLOFF),
                MaskKind::Inner => fall((BAND_INNER - s) / FALLOFF),
                _ => fall((s - BAND_MIDDLE.1) / FALLOFF).min(fall((BAND_MIDDLE.0 - s) / FALLOFF)),
            };
            let r = (c[0] * c[0] + c[2] * c[2]).sqrt();
            if depth == 0.0 || r >= most {
                return 0.0;
            }
            let lateral = if r <= least {
                1.0
            } else {
                let edge = radius([c[0] / r, 0.0, c[2] / r]);
                fall((r - (edge - FALLOFF)) / FALLOFF)
            };
            lateral * depth
        }
    }
}

/// For a depth band's mask over depths `s_lo..=s_hi`: whether its depth
/// factor is 1 over all of them, and whether it is 0 over all of them
/// (`Splotch::alpha`'s depth term; conservative by a hair, for callers
/// that interpolate the depth themselves).
pub fn band_bounds(band: MaskKind, s_lo: f64, s_hi: f64) -> (bool, bool) {
    const HAIR: f64 = 1e-9;
    match band {
        MaskKind::Outer => (
            s_hi <= BAND_OUTER - HAIR,
            s_lo >= BAND_OUTER + FALLOFF + HAIR,
        ),
        MaskKind::Inner => (
            s_lo >= BAND_INNER + HAIR,
            s_hi <= BAND_INNER - FALLOFF - HAIR,
        ),
        MaskKind::Middle => (
            s_lo >= BAND_MIDDLE.0 + HAIR && s_hi <= BAND_MIDDLE.1 - HAIR,
            s_lo >= BAND_MIDDLE.1 + FALLOFF + HAIR || s_hi <= BAND_MIDDLE.0 - FALLOFF - HAIR,
        ),
        MaskKind::Splotch => (true, false),
    }
}

/// How a layer's mask covers a face or a tet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cover {
    /// Alpha 0 everywhere.
    None,
    /// Alpha 1 everywhere.
    Full,
    Part,
}

/// Whether the mask is 0 or 1 all over the face or tet with corner
/// texture coordinates `w`, grown by `reach` about its centroid. Conservative:
/// `Part` whenever unsure. A point's distance from the mask's centre is
/// convex along the face or tet, so its largest value is at a corner and its
/// smallest at least the centre's distance from the box.
pub fn cover<const N: usize>(kind: MaskKind, w: &[[f64; 3]; N], reach: f64) -> Cover {
    let centroid = [0, 1, 2].map(|a| w.iter().map(|p| p[a]).sum::<f64>() / N as f64);
    let grown = w.map(|p| [0, 1, 2].map(|a| centroid[a] + (1.0 + reach) * (p[a] - centroid[a])));
    let (least, most) = (RADIUS * (1.0 - WANDER) - FALLOFF, RADIUS * (1.0 + WANDER));
    // Points inside are blended from the corners: a hair of rounding
    // apart from exact.
    const HAIR: f64 = 1e-9;
    // Distances from the centre over the axes `axes`: nearest (to the box)
    // and farthest (at a corner).
    let range = |axes: &[usize]| {
        let mut near = 0.0;
        let mut far: f64 = 0.0;
        for p in &grown {
            far = far.max(axes.iter().map(|&a| (p[a] - 0.5).powi(2)).sum::<f64>());
        }
        for &a in axes {
            let lo = grown.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min);
            let hi = grown.iter().map(|p| p[a]).fold(f64::NEG_INFINITY, f64::max);
            let d = (lo - 0.5).max(0.5 - hi).max(0.0);
            near += d * d;
        }
        (near.sqrt(), far.sqrt())
    };
    match kind {
        MaskKind::Splotch => {
            let (near, far) = range(&[0, 1, 2]);
            if near >= most + HAIR {
                Cover::None
            } else if far <= least - HAIR {
                Cover::Full
            } else {
                Cover::Part
            }
        }
        band => {
            let (near, far) = range(&[0, 2]);
            let s_lo = grown.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
            let s_hi = grown.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
            let (in_band, out_band) = band_bounds(band, s_lo, s_hi);
            if near >= most + HAIR || out_band {
                Cover::None
            } else if far <= least - HAIR && in_band {
                Cover::Full
            } else {
                Cover::Part
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks_are_one_at_the_centre_and_zero_at_the_faces() {
        let m = Splotch::new(7);
        assert_eq!(m.alpha(MaskKind::Splotch, [0.5; 3]), 1.0);
        let mut inside = 0;
        for i in 0..=20 {
            for j in 0..=20 {
                let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                for w in [
                    [0.0, u, v],
                    [1.0, u, v],
                    [u, 0.0, v],
                    [u, 1.0, v],
                    [u, v, 0.0],
                    [u, v, 1.0],
                ] {
                    assert_eq!(m.alpha(MaskKind::Splotch, w), 0.0, "{w:?}");
                }
                inside += (m.alpha(MaskKind::Splotch, [0.5, u * 0.5 + 0.25, v * 0.5 + 0.25]) == 1.0)
                    as usize;
            }
        }
        assert!(inside > 300, "{inside}");
        // Bands: every depth has alpha 1 at the lateral centre in its band.
        for k in 0..=100 {
            let d = k as f64 / 100.0;
            assert_eq!(
                m.alpha(MaskKind::for_depth(d), [0.5, d, 0.5]),
                1.0,
                "depth {d}"
            );
        }
        assert_eq!(m.alpha(MaskKind::Outer, [0.5, -0.1, 0.5]), 1.0);
        assert_eq!(m.alpha(MaskKind::Outer, [0.5, 0.6, 0.5]), 0.0);
        assert_eq!(m.alpha(MaskKind::Inner, [0.5, 1.1, 0.5]), 1.0);
    }

    #[test]
    fn the_tabulated_bands_match_the_exact_mask() {
        for seed in [1, 7, 2024] {
            let m = Splotch::new(seed);
            let tab = m.tabulated();
            let mut worst: f64 = 0.0;
            let mut partial = 0;
            for i in 0..400 {
                for j in 0..400 {
                    let w = [i as f64 / 399.0, 0.5, j as f64 / 399.0];
                    for kind in [MaskKind::Outer, MaskKind::Middle, MaskKind::Inner] {
                        let exact = m.alpha(kind, w);
                        partial += (exact > 0.0 && exact < 1.0) as usize;
                        worst = worst.max((tab.alpha(kind, w) - exact).abs());
                    }
                }
            }
            assert!(partial > 10_000, "{partial}");
            assert!(worst < 1e-5, "seed {seed}: {worst}");
        }
    }
}
