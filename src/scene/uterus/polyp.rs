//! A polyp grown out of the wall: a surface of revolution over a profile
//! (a rounded head on a stalk, flaring into the wall), stitched to the rim
//! of the hole its footprint leaves, its head lobed and leaning by seeded
//! amounts.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::{Polyp, Site, smoothstep, tangent_frame};
use crate::rng;

/// Footprint radius of a polyp on the wall: room for the flare beyond the
/// stalk, or beyond a sessile polyp's base.
pub(super) fn polyp_footprint(pl: &Polyp) -> f64 {
    if pl.sessile {
        pl.head_radius + pl.stalk_radius
    } else {
        pl.head_radius + 2.0 * pl.stalk_radius
    }
}

/// How far a polyp rises off the wall, at most: a stalk and a whole head,
/// or a sessile head's part above its base.
pub(super) fn polyp_rise(pl: &Polyp) -> f64 {
    if pl.sessile {
        polyp_profile(pl, polyp_footprint(pl)).point(0.0).1
    } else {
        pl.stalk_length + 2.0 * pl.head_radius * pl.elongation
    }
}

/// A polyp: the wall's faces within its footprint are removed, and the
/// polyp is built as rings of vertices over its profile (a surface of
/// revolution), the first ring being the hole's own rim, so it is stitched
/// to the wall exactly. Rings are spaced by their own vertex spacing, which
/// keeps the triangles close to equilateral from the flare to the head's
/// top, closed by a pole. Faces up to the stalk's foot are the polyp's
/// facet; the flare stays wall.
pub(super) fn grow_polyp(
    positions: &mut Vec<DVec3>,
    triangles: &mut Vec<[u32; 3]>,
    of_face: &mut Vec<u32>,
    facet: u32,
    site: &Site,
    pl: &Polyp,
    seed: u64,
) -> Result<(), String> {
    let (e1, e2) = tangent_frame(site.normal);
    // The head's lobes: two seeded harmonics round the axis, turning as
    // they go up the head (`up`, 0 at its top to 1 at the stalk), and a
    // seeded swelling along it, so no view shows an ellipse.
    let lobe = |k: u64| TAU * (rng::hash(seed, &[k]) % 1000) as f64 / 1000.0;
    let (phase2, phase3, twist, swell) = (lobe(2), lobe(3), lobe(4) - PI, lobe(5));
    let lobes = |a: f64, up: f64| {
        let round = 0.6 * (2.0 * a + phase2 + twist * up).cos()
            + 0.4 * (3.0 * a + phase3 - twist * up).cos();
        let along = (PI * 1.5 * up + swell).sin();
        1.0 + pl.irregularity * (0.7 * round + 0.3 * along)
    };
    // The lean: each ring moves sideways by a shear that grows with the
    // square of its height, so the axis bends from upright at the base to
    // `lean` at the top. A shear by height moves each level rigidly, so
    // the surface stays embedded.
    let lean_to = {
        let a = lobe(6);
        e1 * a.cos() + e2 * a.sin()
    };
    let profile = polyp_profile(pl, site.footprint);
    let top = profile.point(0.0).1;
    let shear = |h: f64| lean_to * (pl.lean.to_radians().tan() * h.max(0.0).powi(2) / (2.0 * top));
    let inside = |p: DVec3| {
        let d = p - site.centre;
        let flat = d - site.normal * d.dot(site.normal);
        flat.length() < site.footprint && d.dot(site.normal).abs() < site.footprint
    };
    let keep: Vec<bool> = triangles
        .iter()
        .map(|t| !inside(t.iter().map(|&v| positions[v as usize]).sum::<DVec3>() / 3.0))
        .collect();
    let mut k = 0;
    triangles.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    let mut k = 0;
    of_face.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    // The hole's rim, in the order the wall runs it.
    let rim = hole_rim(positions, triangles, site)?;
    let n = rim.len();
    let angle = |p: DVec3| {
        let d = p - site.centre;
        d.dot(e2).atan2(d.dot(e1))
    };
    let mut phi: Vec<f64> = rim.iter().map(|&v| angle(positions[v as usize])).collect();
    for j in 1..n {
        while phi[j] - phi[j - 1] > PI {
            phi[j] -= TAU;
        }
        while phi[j] - phi[j - 1] < -PI {
            phi[j] += TAU;
        }
    }
    // Angles increasing in the rim's own direction.
    let turn = if phi[n - 1] >= phi[0] { 1.0 } else { -1.0 };
    let start = phi[0];
    let rim_angles: Vec<f64> = phi.iter().map(|a| (a - start) * turn).collect();
    // Triangles the size of the wall's around the rim.
    let size = (0..n)
        .map(|j| (positions[rim[j] as usize] - positions[rim[(j + 1) % n] as usize]).length())
        .sum::<f64>()
        / n as f64;

    let total = profile.arc[profile.arc.len() - 1];
    let foot = profile.arc_at_stalk_foot;
    let step = size * 0.87;
    let rings = ((total / step).round() as usize).max(3);
    // The rim is where the curved, faceted wall really is: its distance
    // from the axis and its height off the tangent plane at each angle. The
    // flare eases from the rim into the profile by the stalk's foot, so the
    // wall runs into the polyp with no crease.
    let rim_offset: Vec<(f64, f64)> = rim
        .iter()
        .map(|&v| {
            let d = positions[v as usize] - site.centre;
            let h = d.dot(site.normal);
            ((d - site.normal * h).length() - site.footprint, h)
        })
        .collect();
    let rim_at = |a: f64| {
        // Rim angles increase from 0 to under a turn; wrap between the last
        // and the first.
        let j = rim_angles.partition_point(|&x| x <= a).max(1) - 1;
        let (a0, a1) = (
            rim_angles[j],
            if j + 1 < n { rim_angles[j + 1] } else { TAU },
        );
        let t = if a1 > a0 {
            ((a - a0) / (a1 - a0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (p, q) = (rim_offset[j], rim_offset[(j + 1) % n]);
        (p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t)
    };
    let mut previous: (Vec<u32>, Vec<f64>) = (rim.clone(), rim_angles.clone());
    for k in 1..rings {
        let along = total * (1.0 - k as f64 / rings as f64);
        let (r, h) = profile.point(along);
        let ease = smoothstep(foot, total, along);
        // Full lobes on the head, none from the stalk down.
        let on_head = 1.0 - smoothstep(0.5 * foot, foot, along);
        let count = ((TAU * r / size).round() as usize).clamp(6, n.max(6));
        let angles: Vec<f64> = (0..count).map(|j| TAU * j as f64 / count as f64).collect();
        let ids: Vec<u32> = angles
            .iter()
            .map(|&a| {
                let (dr, dh) = rim_at(a);
                let a = start + turn * a;
                let r = r * (1.0 + (lobes(a, along / foot) - 1.0) * on_head);
                positions.push(
                    site.centre
                        + (e1 * a.cos() + e2 * a.sin()) * (r + dr * ease)
                        + site.normal * (h + dh * ease)
                        + shear(h),
                );
                (positions.len() - 1) as u32
            })
            .collect();
        let owner = if along <= foot { facet } else { 0 };
        let before = triangles.len();
        zip_rings(&previous, (&ids, &angles), triangles);
        of_face.extend(std::iter::repeat_n(owner, triangles.len() - before));
        previous = (ids, angles);
    }
    positions.push(site.centre + site.normal * top + shear(top));
    let pole = (positions.len() - 1) as u32;
    let (last, _) = &previous;
    for j in 0..last.len() {
        triangles.push([last[(j + 1) % last.len()], last[j], pole]);
        of_face.push(facet);
    }
    Ok(())
}

/// Triangulate the band between two rings, the outer one (`outer`, run in
/// the wall's direction) and the next one in: walk both in angle order,
/// each step advancing the ring whose next vertex comes first (a zipper),
/// so rings of any vertex counts join without slivers.
fn zip_rings(outer: &(Vec<u32>, Vec<f64>), inner: (&[u32], &[f64]), triangles: &mut Vec<[u32; 3]>) {
    let (p, pa) = (&outer.0, &outer.1);
    let (c, ca) = inner;
    let (np, nc) = (p.len(), c.len());
    let angle = |a: &[f64], k: usize, n: usize| a[k % n] + TAU * (k / n) as f64;
    let (mut i, mut j) = (0, 0);
    while i < np || j < nc {
        let advance_outer = j == nc || (i < np && angle(pa, i + 1, np) <= angle(ca, j + 1, nc));
        if advance_outer {
            triangles.push([p[(i + 1) % np], p[i % np], c[j % nc]]);
            i += 1;
        } else {
            triangles.push([p[i % np], c[j % nc], c[(j + 1) % nc]]);
            j += 1;
        }
    }
}

/// The boundary loop left by removing a polyp's footprint: the loop nearest
/// the site, as vertex ids in the order the wall's faces run it.
fn hole_rim(positions: &[DVec3], triangles: &[[u32; 3]], site: &Site) -> Result<Vec<u32>, String> {
    let mut next: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    let mut directed = std::collections::HashSet::new();
    for t in triangles {
        for i in 0..3 {
            directed.insert((t[i], t[(i + 1) % 3]));
        }
    }
    for &(a, b) in &directed {
        if !directed.contains(&(b, a)) {
            let near = (positions[a as usize] - site.centre).length() < 2.0 * site.footprint;
            if near && next.insert(a, b).is_some() {
                return Err(
                    "the wall around the polyp is pinched; move it or change its size".into(),
                );
            }
        }
    }
    let start = *next
        .keys()
        .min()
        .ok_or("the polyp's footprint removed no faces; make it larger")?;
    let mut rim = vec![start];
    let mut v = next[&start];
    while v != start {
        rim.push(v);
        v = *next
            .get(&v)
            .ok_or("the hole under the polyp is not one loop")?;
        if rim.len() > next.len() {
            return Err("the hole under the polyp is not one loop".into());
        }
    }
    if rim.len() != next.len() {
        return Err("the polyp's footprint left more than one hole".into());
    }
    Ok(rim)
}

/// A polyline (r, h) by arc length.
struct Profile {
    points: Vec<(f64, f64)>,
    arc: Vec<f64>,
    /// Arc length from the head's top to where the stalk meets the flare.
    arc_at_stalk_foot: f64,
}

impl Profile {
    /// Point at arc length `target` from the head's top.
    fn point(&self, target: f64) -> (f64, f64) {
        let target = target.clamp(0.0, self.arc[self.arc.len() - 1]);
        let i = self
            .arc
            .partition_point(|&a| a < target)
            .clamp(1, self.arc.len() - 1);
        let t = (target - self.arc[i - 1]) / (self.arc[i] - self.arc[i - 1]).max(1e-300);
        let (a, b) = (self.points[i - 1], self.points[i]);
        (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
    }
}

/// Head top, the head (a half ellipse, `elongation` times as high as
/// wide) down to where it meets the stalk, the stalk, then a quarter-round
/// fillet out to the footprint's rim on the wall. A sessile head stops
/// above its widest part, where it is the stalk's width, and sits on the
/// fillet itself (a dome on a skirt, no neck). A simple curve in the
/// half-plane r >= 0, so the surface it sweeps is embedded.
fn polyp_profile(pl: &Polyp, footprint: f64) -> Profile {
    let (rh, rs) = (pl.head_radius, pl.stalk_radius);
    let fillet = rs.min(0.5 * pl.stalk_length);
    let tall = rh * pl.elongation;
    // Where the head's ellipse is the stalk's width: above its centre for
    // a sessile head, below it on a stalk.
    let lift = tall * (1.0 - (rs / rh).powi(2)).sqrt();
    let at = ((rh * rh - rs * rs).sqrt() / rh).asin();
    let (centre, end) = if pl.sessile {
        (fillet - lift, at)
    } else {
        (pl.stalk_length + lift, -at)
    };
    let mut points = Vec::new();
    for k in 0..=60 {
        let a = PI / 2.0 + (end - PI / 2.0) * k as f64 / 60.0;
        points.push((rh * a.cos(), centre + tall * a.sin()));
    }
    points.push((rs, fillet));
    let foot_index = points.len() - 1;
    for k in 1..=20 {
        let t = k as f64 / 20.0 * PI / 2.0;
        points.push((
            rs + (footprint - rs) * (1.0 - t.cos()),
            fillet * (1.0 - t.sin()),
        ));
    }
    let mut arc = vec![0.0];
    for w in points.windows(2) {
        let d = ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt();
        arc.push(arc[arc.len() - 1] + d);
    }
    Profile {
        arc_at_stalk_foot: arc[foot_index],
        points,
        arc,
    }
}
