//! What the block's slices show, measured as the photographs were: the
//! issue's check that the block is the material the sections came from
//! (particles as round along x, y and z; slices' profile sizes those of
//! the photographs).

use super::profiles::{self, Section};
use super::split::Photo;
use super::unfold::total_variation;
use crate::synth::volume::Volume;

/// Every this many-th slice across each axis is measured (particles a few
/// voxels across are then seen in several).
const STEP: usize = 4;

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SliceCheck {
    /// Mean profile area (pixels) of slices across x, y and z.
    pub mean_profile_area: [f64; 3],
    /// Profile area fraction of slices across x, y and z.
    pub area_fraction: [f64; 3],
    /// Total variation between the slices' profile-size histogram and the
    /// photographs' (`bins` bins up to the photographs' largest profile;
    /// border-corrected weights on both sides).
    pub profile_tv: f64,
    /// Those histograms (shares of the profiles by diameter, `bins` equal
    /// bins up to the photographs' largest): the slices' and the
    /// photographs'.
    pub profile_shares: Vec<f64>,
    pub photograph_shares: Vec<f64>,
}

/// Every `STEP`-th slice across each axis of `block`, its profiles found
/// as the photographs' were (by their split).
pub fn check(block: &Volume, sections: &[Section], bins: usize) -> SliceCheck {
    let reference: Vec<(f64, f64)> = sections
        .iter()
        .flat_map(|s| s.profiles.iter().map(|p| (p.diameter, p.weight)))
        .collect();
    let d_max = reference.iter().map(|p| p.0).fold(0.0, f64::max);
    let mut found = Vec::new();
    let mut mean_profile_area = [0.0; 3];
    let mut area_fraction = [0.0; 3];
    for axis in 0..3 {
        let n = block.size[axis];
        let (mut area, mut count, mut fraction) = (0.0, 0usize, 0.0);
        let slices = n.div_ceil(STEP);
        for k in 0..slices {
            let (w, h, pixels) = block.slice(axis, k * STEP);
            // A slice with no profile to measure (no particle, or every
            // one cut by the slice's edge) is a finding, not an error: its
            // particle pixels still count towards the area fraction, as
            // the photographs' do.
            let photo = Photo {
                width: w,
                height: h,
                pixels: &pixels,
                valid: &vec![true; w * h],
            };
            let Ok(s) = profiles::find_with(photo, &sections[0].split) else {
                continue;
            };
            area += s.profiles.iter().map(|p| p.area).sum::<f64>();
            count += s.profiles.len();
            fraction += s.area_fraction;
            found.extend(s.profiles.iter().map(|p| (p.diameter, p.weight)));
        }
        mean_profile_area[axis] = area / count.max(1) as f64;
        area_fraction[axis] = fraction / slices as f64;
    }
    let histogram = |ps: &[(f64, f64)]| {
        let mut h = vec![0.0; bins];
        for &(d, w) in ps {
            h[((d / d_max * bins as f64) as usize).min(bins - 1)] += w;
        }
        let total: f64 = h.iter().sum();
        h.iter()
            .map(|x| x / total.max(f64::MIN_POSITIVE))
            .collect::<Vec<_>>()
    };
    let (profile_shares, photograph_shares) = (histogram(&found), histogram(&reference));
    SliceCheck {
        mean_profile_area,
        area_fraction,
        profile_tv: total_variation(&photograph_shares, &profile_shares),
        profile_shares,
        photograph_shares,
    }
}
