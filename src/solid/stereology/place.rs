//! Placement (seed 001, sec. 4.1): every particle put in the periodic box
//! at once, overlaps ignored, then annealed: each round finds every
//! overlapping pair through a spatial hash and moves both apart by half
//! their overlap, wrapping round the box so the density stays, until the
//! overlapping volume is under `TARGET` of the particles' volume.
//!
//! Each round computes every particle's move from the positions before it
//! (in parallel, each particle summing its own pairs in a fixed order), so
//! the result does not depend on the thread count.

use glam::DVec3;
use rayon::prelude::*;

use super::unfold::Distribution;
use crate::rng;

/// Overlap volume over particle volume at which annealing stops.
pub const TARGET: f64 = 0.005;
const MAX_ROUNDS: usize = 400;

#[derive(Clone, Debug, PartialEq)]
pub struct Particle {
    pub centre: DVec3,
    /// Of the sphere of the particle's volume (what annealing separates).
    pub radius: f64,
    /// A non-spherical particle: world offsets to its unit-ball
    /// coordinates (a mesh's: to its frame at size 1), and how far it
    /// reaches.
    pub ellipsoid: Option<(glam::DMat3, f64)>,
    /// A mesh particle's inside.
    pub inside: Option<std::sync::Arc<super::mesh_shape::Inside>>,
}

impl Particle {
    /// How far from its centre it reaches.
    pub fn reach(&self) -> f64 {
        self.ellipsoid.map_or(self.radius, |(_, a)| a)
    }

    /// Whether the offset `d` from its centre is inside.
    pub fn contains(&self, d: DVec3) -> bool {
        match (&self.ellipsoid, &self.inside) {
            (None, _) => d.length_squared() < self.radius * self.radius,
            (Some((to_unit, _)), None) => (*to_unit * d).length_squared() < 1.0,
            (Some((to_frame, _)), Some(inside)) => inside.contains(*to_frame * d),
        }
    }
}

/// Particles of `dist`'s sizes in a periodic box of side `side`, each of
/// one of the shape `types` with its proportion (seed 001, eq. 10: type
/// and size uncorrelated), scaled so their volume is `fraction` of the
/// box; each bin's sizes uniform within it, each non-spherical particle
/// turned at random (Shoemake's uniform rotation).
pub fn draw(
    dist: &Distribution,
    side: f64,
    fraction: f64,
    types: &[(super::shape::ShapeStats, f64)],
    seed: u64,
) -> Vec<Particle> {
    let box_volume = side.powi(3);
    let total: f64 = types.iter().map(|t| t.1).sum();
    let natural: f64 = types
        .iter()
        .map(|(stats, p)| p / total * dist.volume_fraction(stats.volume))
        .sum();
    let scale = if natural > 0.0 {
        fraction / natural
    } else {
        0.0
    };
    let mut out = Vec::new();
    for (b, (e, &n)) in dist.edges.windows(2).zip(&dist.per_volume).enumerate() {
        let expected = n * scale * box_volume;
        // Randomised rounding keeps the expected count.
        let count = expected.floor() as usize
            + (rng::unit(seed, &[b as u64, u64::MAX]) < expected.fract()) as usize;
        for k in 0..count {
            let u = |c: u64| rng::unit(seed, &[b as u64, k as u64, c]);
            let d = e[0] + (e[1] - e[0]) * u(0);
            let mut pick = u(7) * total;
            let stats = &types
                .iter()
                .find(|t| {
                    pick -= t.1;
                    pick < 0.0
                })
                .unwrap_or(&types[types.len() - 1])
                .0;
            // Equal semi-axes: a sphere, drawn without an orientation.
            let sphere = stats.axes[0] == stats.axes[2] && stats.inside.is_none();
            // The radius of the sphere of the same volume, per unit size.
            let equal = (stats.volume * 3.0 / (4.0 * std::f64::consts::PI)).cbrt();
            let ellipsoid = (!sphere).then(|| {
                let (u1, u2, u3) = (
                    u(4),
                    u(5) * std::f64::consts::TAU,
                    u(6) * std::f64::consts::TAU,
                );
                let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
                let turn =
                    glam::DQuat::from_xyzw(a * u2.sin(), a * u2.cos(), b * u3.sin(), b * u3.cos());
                let axes = DVec3::from_array(stats.axes) * d;
                // An ellipsoid's offsets go to the unit ball, a mesh's to
                // its frame at size 1.
                let to_frame = match stats.inside {
                    None => axes.recip(),
                    Some(_) => DVec3::splat(1.0 / d),
                };
                (
                    glam::DMat3::from_diagonal(to_frame) * glam::DMat3::from_quat(turn).transpose(),
                    axes.max_element(),
                )
            });
            out.push(Particle {
                centre: DVec3::new(u(1), u(2), u(3)) * side,
                radius: equal * d,
                ellipsoid,
                inside: stats.inside.clone(),
            });
        }
    }
    out
}

/// The shortest vector from `a` to `b` in the periodic box.
#[inline]
fn wrapped(a: DVec3, b: DVec3, side: f64) -> DVec3 {
    let d = b - a;
    d - (d / side).round() * side
}

/// Volume of the lens where two balls of radii `r1`, `r2` at distance `d`
/// overlap.
pub fn lens(r1: f64, r2: f64, d: f64) -> f64 {
    if d >= r1 + r2 {
        return 0.0;
    }
    if d <= (r1 - r2).abs() {
        return 4.0 / 3.0 * std::f64::consts::PI * r1.min(r2).powi(3);
    }
    std::f64::consts::PI
        * (r1 + r2 - d).powi(2)
        * (d * d + 2.0 * d * (r1 + r2) - 3.0 * (r1 - r2).powi(2))
        / (12.0 * d)
}

/// Pairs of particles that may touch, by a spatial hash of cells at least
/// the largest diameter wide.
fn neighbours(ps: &[Particle], side: f64) -> Vec<Vec<u32>> {
    let largest = ps
        .iter()
        .map(|p| 2.0 * p.radius)
        .fold(0.0, f64::max)
        .max(1e-9);
    let cells = ((side / largest).floor() as usize).clamp(1, 64);
    let cell = side / cells as f64;
    let key = |p: DVec3| {
        let c = (p / cell).floor().as_ivec3();
        let m = cells as i32;
        [c.x.rem_euclid(m), c.y.rem_euclid(m), c.z.rem_euclid(m)]
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells * cells];
    let index = |k: [i32; 3]| (k[2] as usize * cells + k[1] as usize) * cells + k[0] as usize;
    for (i, p) in ps.iter().enumerate() {
        grid[index(key(p.centre))].push(i as u32);
    }
    ps.par_iter()
        .enumerate()
        .map(|(i, p)| {
            let k = key(p.centre);
            let m = cells as i32;
            let reach = if cells >= 3 { 1 } else { 0 };
            let mut out = Vec::new();
            let span: Vec<i32> = if cells >= 3 {
                (-reach..=reach).collect()
            } else {
                vec![0]
            };
            for &dz in &span {
                for &dy in &span {
                    for &dx in &span {
                        let c = [
                            (k[0] + dx).rem_euclid(m),
                            (k[1] + dy).rem_euclid(m),
                            (k[2] + dz).rem_euclid(m),
                        ];
                        for &j in &grid[index(c)] {
                            if j as usize != i {
                                out.push(j);
                            }
                        }
                    }
                }
            }
            out.sort_unstable();
            out.dedup();
            out
        })
        .collect()
}

/// Overlapping volume over particle volume.
pub fn overlap_fraction(ps: &[Particle], side: f64) -> f64 {
    let near = neighbours(ps, side);
    let overlap: f64 = (0..ps.len())
        .into_par_iter()
        .map(|i| {
            near[i]
                .iter()
                .filter(|&&j| (j as usize) > i)
                .map(|&j| {
                    let q = &ps[j as usize];
                    lens(
                        ps[i].radius,
                        q.radius,
                        wrapped(ps[i].centre, q.centre, side).length(),
                    )
                })
                .sum::<f64>()
        })
        .sum();
    let total: f64 = ps
        .iter()
        .map(|p| 4.0 / 3.0 * std::f64::consts::PI * p.radius.powi(3))
        .sum();
    if total > 0.0 { overlap / total } else { 0.0 }
}

/// Anneal until the overlap is under `TARGET`; the overlap fraction
/// left. Dense packings jam when every particle pushes at full size from
/// the start, so the radii grow to full size in `GROWTH` stages, each
/// relaxed before the next (as Lubachevsky-Stillinger packings grow
/// them), then the full size relaxes for up to `MAX_ROUNDS`.
pub fn anneal(ps: &mut [Particle], side: f64, seed: u64) -> f64 {
    let full: Vec<f64> = ps.iter().map(|p| p.radius).collect();
    for stage in 0..GROWTH {
        let scale = 0.7 + 0.3 * stage as f64 / GROWTH as f64;
        for (p, &r) in ps.iter_mut().zip(&full) {
            p.radius = r * scale;
        }
        relax(ps, side, seed, stage as u64 + 1, STAGE_ROUNDS);
    }
    for (p, &r) in ps.iter_mut().zip(&full) {
        p.radius = r;
    }
    relax(ps, side, seed, 0, MAX_ROUNDS)
}

/// Radius growth stages, and the relaxation rounds each takes at most.
const GROWTH: usize = 6;
const STAGE_ROUNDS: usize = 60;

/// Push overlapping pairs apart for up to `rounds` rounds or until the
/// overlap is under `TARGET`; the overlap fraction left.
fn relax(ps: &mut [Particle], side: f64, seed: u64, stage: u64, rounds: usize) -> f64 {
    for round in 0..rounds {
        let near = neighbours(ps, side);
        let moves: Vec<DVec3> = (0..ps.len())
            .into_par_iter()
            .map(|i| {
                let p = &ps[i];
                let mut m = DVec3::ZERO;
                for &j in &near[i] {
                    let q = &ps[j as usize];
                    let d = wrapped(p.centre, q.centre, side);
                    let gap = d.length() - (p.radius + q.radius);
                    if gap < 0.0 {
                        // Coincident centres: a seeded direction.
                        let dir = d.try_normalize().unwrap_or_else(|| {
                            let u = |c: u64| {
                                rng::unit(seed, &[stage, round as u64, i as u64, j as u64, c]) - 0.5
                            };
                            DVec3::new(u(0), u(1), u(2)).normalize_or(DVec3::X)
                        });
                        // Half the overlap each, a little more so touching
                        // pairs come apart.
                        m += dir * (0.5 * gap * 1.05);
                    }
                }
                m
            })
            .collect();
        let moved = moves.iter().any(|m| m.length_squared() > 0.0);
        for (p, m) in ps.iter_mut().zip(&moves) {
            p.centre = (p.centre + *m).rem_euclid(DVec3::splat(side));
        }
        if !moved || (round % 10 == 9 && overlap_fraction(ps, side) < TARGET) {
            break;
        }
    }
    overlap_fraction(ps, side)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_volume_is_right_at_its_limits() {
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert_eq!(lens(1.0, 1.0, 2.0), 0.0);
        assert!((lens(1.0, 1.0, 0.0) - ball).abs() < 1e-12);
        assert!((lens(1.0, 1.0, 1e-9) - ball).abs() < 1e-6);
        // Two unit balls one radius apart overlap in 5/12 pi.
        assert!((lens(1.0, 1.0, 1.0) - 5.0 / 12.0 * std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn annealing_removes_overlaps_at_a_third_full() {
        let dist = Distribution {
            edges: vec![0.0, 4.0, 8.0, 12.0],
            per_volume: vec![1.0, 1.0, 0.5],
        };
        let stats = super::super::shape::Shape::Sphere.stats(0);
        let mut ps = draw(&dist, 64.0, 0.3, &[(stats, 1.0)], 5);
        assert!(ps.len() > 100, "{}", ps.len());
        let before = overlap_fraction(&ps, 64.0);
        let after = anneal(&mut ps, 64.0, 5);
        assert!(before > 0.05 && after < 0.01, "{before} -> {after}");
    }
}
