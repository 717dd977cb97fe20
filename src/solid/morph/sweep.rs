//! Source points (seed 003, 4.2) and the fit of a photograph to the mesh
//! (4.3).
//!
//! A point p takes its colour on exemplar X_i from a source point found by
//! sweeping the exemplar plane along its normal (the straight path γ) until
//! it holds p: the ray from the swept section's barycentre through p is
//! mapped back onto X_i, keeping p's distance to the barycentre as a
//! fraction of the distance to the section's outline. So an organ that
//! narrows away from the cut still shows the cut's rim at its own rim.
//!
//! The swept sections are precomputed: the region X_i split, cut at
//! `2 HALF_LEVELS + 1` heights, each reduced to its barycentre and its
//! outline (the outermost boundary distance in `ANGLES` directions); a
//! point interpolates between two heights and two directions.
//!
//! An exemplar may instead sweep by rotating about an axis in its plane
//! (4.2's great arc): a point is turned about the axis onto the plane, its
//! distance to the axis kept; the arc it swept is its height.
//!
//! With a mask, the photograph is fitted to the mesh (4.3): the section's
//! outline maps onto the outline of the masked tissue, radially from the
//! barycentres, so the image boundary lies on the mesh boundary and the
//! interior follows smoothly. Without one, the photograph is taken as
//! placed.

use glam::{DVec2, DVec3};

use super::bsp::Side;
use super::cells::Cells;
use super::sections::{Exemplar, SweepPath};
use crate::error::Result;
use crate::mesh::{Topology, TriMesh};

/// Directions of an outline.
const ANGLES: usize = 64;
/// Swept sections each side of the exemplar plane.
const HALF_LEVELS: usize = 24;
/// Cells a side of a swept section.
const LEVEL_SIDE: usize = 256;

/// A plane region seen from its barycentre.
#[derive(Clone, Debug)]
struct Outline {
    centre: DVec2,
    radius: Vec<f32>,
}

impl Outline {
    fn of(cells: &Cells) -> Option<Outline> {
        let centre = cells.centroid()?;
        Some(Outline {
            centre,
            radius: cells.outline(centre, ANGLES),
        })
    }
}

#[derive(Clone, Debug)]
pub struct Sweep {
    /// Height between swept sections.
    dt: f64,
    /// The swept sections, from height `-HALF_LEVELS dt` up; the middle one
    /// is the exemplar's own.
    levels: Vec<Outline>,
    /// The masked tissue's outline in the photograph (4.3), if masked.
    fit: Option<Outline>,
}

impl Sweep {
    /// The sweep of `exemplar` through the region it split (`split`).
    pub fn new(
        mesh: &TriMesh,
        topology: &Topology,
        exemplars: &[Exemplar],
        i: usize,
        split: &[Side],
    ) -> Result<Sweep> {
        let e = &exemplars[i];
        let reach = mesh
            .positions
            .iter()
            .map(|&p| e.height(p).abs())
            .fold(0.0, f64::max);
        let dt = reach / HALF_LEVELS as f64;
        // An arc sweeps by rotation and reads only the exemplar's own
        // section (for the mask's fit): the other heights stay empty and
        // are filled from it below.
        let arc = matches!(e.path, SweepPath::Arc { .. });
        let mut levels: Vec<Option<Outline>> = (0..=2 * HALF_LEVELS)
            .map(|k| {
                if arc && k != HALF_LEVELS {
                    return Ok(None);
                }
                let t = (k as f64 - HALF_LEVELS as f64) * dt;
                let Some(mut cells) = Cells::section(mesh, topology, e, t, LEVEL_SIDE)? else {
                    return Ok(None);
                };
                cells.retain(e, t, |p| {
                    split
                        .iter()
                        .all(|&(j, s)| (exemplars[j].height(p) >= 0.0) == s)
                });
                Ok(Outline::of(&cells))
            })
            .collect::<Result<_>>()?;
        // Heights where the region has no section (beyond its ends, or past
        // a neighbour plane) take the nearest one towards the exemplar.
        for k in (0..HALF_LEVELS).rev() {
            if levels[k].is_none() {
                levels[k] = levels[k + 1].clone();
            }
        }
        for k in HALF_LEVELS + 1..=2 * HALF_LEVELS {
            if levels[k].is_none() {
                levels[k] = levels[k - 1].clone();
            }
        }
        let levels: Option<Vec<Outline>> = levels.into_iter().collect();
        // The exemplar's own section is not empty (the BSP checked), so
        // every level was filled from it.
        let levels = levels.expect("the exemplar's own section is not empty");
        let fit = e.mask.as_ref().and_then(|mask| {
            Outline::of(&Cells {
                lo: DVec2::ZERO,
                step: 1.0,
                w: e.width,
                h: e.height,
                inside: mask.clone(),
            })
        });
        Ok(Sweep { dt, levels, fit })
    }

    /// The source point of `p` on the exemplar, in its image's pixel
    /// coordinates, and `p`'s height above the exemplar plane.
    #[inline]
    pub fn source(&self, e: &Exemplar, p: DVec3) -> (f64, DVec2) {
        if let SweepPath::Arc { point, direction } = e.path {
            // Rotate p about the axis onto the nearer half of the plane:
            // its distance to the axis is kept, and its height above the
            // plane is the arc it swept (signed as the BSP sides it).
            let q = p - point;
            let along = q.dot(direction);
            let radial = q - direction * along;
            let across = e.normal.cross(direction);
            let (x, y) = (radial.dot(across), radial.dot(e.normal));
            let r = radial.length();
            let on_plane = point + direction * along + across * (r * x.signum());
            let t = y.atan2(x.abs()) * r;
            let ab = e.pixel_coords(on_plane);
            return (t, self.fitted(ab, 0.0));
        }
        let t = e.height(p);
        (t, self.fitted(e.pixel_coords(p), t))
    }

    /// The image point of the plane point `ab` swept `t` along the normal:
    /// the ratio of its distance to the swept section's outline kept, and
    /// the section fitted to the mask's outline (4.3) if there is one.
    #[inline]
    pub fn fitted(&self, ab: DVec2, t: f64) -> DVec2 {
        if t == 0.0 && self.fit.is_none() {
            return ab;
        }
        let x = (t / self.dt + HALF_LEVELS as f64).clamp(0.0, (2 * HALF_LEVELS) as f64);
        let k = (x as usize).min(2 * HALF_LEVELS - 1);
        let f = x - k as f64;
        let (l0, l1) = (&self.levels[k], &self.levels[k + 1]);
        let centre = l0.centre.lerp(l1.centre, f);
        let rel = ab - centre;
        let r = rel.length();
        if r == 0.0 {
            return self.target().centre;
        }
        let s = (rel.y.atan2(rel.x) / std::f64::consts::TAU).rem_euclid(1.0) * ANGLES as f64;
        let swept = lerp(radius(l0, s), radius(l1, s), f);
        let rho = if swept > 0.0 {
            (r / swept).min(1.0)
        } else {
            1.0
        };
        let target = self.target();
        target.centre + rel * (rho * radius(target, s) / r)
    }

    /// The outline a swept point lands on: the masked tissue's, or the
    /// exemplar's own section's.
    #[inline]
    fn target(&self) -> &Outline {
        self.fit.as_ref().unwrap_or(&self.levels[HALF_LEVELS])
    }
}

#[inline]
fn lerp(a: f64, b: f64, f: f64) -> f64 {
    a + (b - a) * f
}

/// An outline's radius at fractional direction `s` (0..ANGLES).
#[inline]
fn radius(o: &Outline, s: f64) -> f64 {
    let k = s as usize % ANGLES;
    let f = s - s.floor();
    lerp(o.radius[k] as f64, o.radius[(k + 1) % ANGLES] as f64, f)
}
