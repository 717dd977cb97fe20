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
                let edge = self.radius([c[0] / r, c[1] / r, c[2] / r]);
                fall((r - (edge - FALLOFF)) / FALLOFF)
            }
            band => {
                let r = (c[0] * c[0] + c[2] * c[2]).sqrt();
                if r >= most {
                    return 0.0;
                }
                let lateral = if r <= least {
                    1.0
                } else {
                    let edge = self.radius([c[0] / r, 0.0, c[2] / r]);
                    fall((r - (edge - FALLOFF)) / FALLOFF)
                };
                let s = w[1];
                let depth = match band {
                    MaskKind::Outer => fall((s - BAND_OUTER) / FALLOFF),
                    MaskKind::Inner => fall((BAND_INNER - s) / FALLOFF),
                    _ => {
                        fall((s - BAND_MIDDLE.1) / FALLOFF).min(fall((BAND_MIDDLE.0 - s) / FALLOFF))
                    }
                };
                lateral * depth
            }
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
}
