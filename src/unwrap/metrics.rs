//! Distortion figures of a uv layout, defined once for tests, reports, the
//! bench and the comparisons with other tools (`organtex uv-metrics`).
//!
//! All means are weighted by 3D triangle area, after the uvs are scaled so
//! the total uv area equals the total 3D area.
//! - charts: uv-connected pieces (faces joined across an edge whose two uv
//!   ends agree on both sides);
//! - flips: faces whose uv orientation disagrees with most of their chart;
//! - overlaps: faces whose uv triangle overlaps another face's (not a
//!   neighbour's) with positive area: the layout folds over itself, which
//!   an atlas cannot hold;
//! - conf_mean: mean sigma1 / sigma2 of the 3D-to-uv Jacobian (1 =
//!   conformal);
//! - area_log: mean |log(A_uv / A_3d)|;
//! - seam_ratio: total seam length / sqrt(total area), seams being the
//!   interior edges where the uvs jump;
//! - seam_vis: seam length weighted by each seam edge's visibility, over
//!   sqrt(total area).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::mesh::dsu::DisjointSets;
use crate::mesh::{EdgeId, Topology, TriMesh, UvLayer};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UvMetrics {
    pub charts: usize,
    pub flips: usize,
    pub overlaps: usize,
    /// Faces whose uv triangle has no area.
    pub degenerate: usize,
    pub conf_mean: f64,
    pub area_log: f64,
    pub seam_length: f64,
    pub seam_ratio: f64,
    pub seam_vis: f64,
}

/// The uvs of corner `i` of face `f`.
#[inline]
fn uv(layer: &UvLayer, f: usize, i: usize) -> DVec2 {
    layer.coords[layer.triangles[f][i] as usize]
}

/// Interior edges of `topo` across which the uvs jump.
pub fn seam_edges(topo: &Topology, layer: &UvLayer) -> Vec<EdgeId> {
    split_edges(topo, |(f, i), (g, j)| uv(layer, f, i) != uv(layer, g, j))
}

/// Interior edges whose ends differ between their two faces by `differs`,
/// which is given the (face, corner) pairs of the same vertex.
pub fn split_edges(
    topo: &Topology,
    differs: impl Fn((usize, usize), (usize, usize)) -> bool,
) -> Vec<EdgeId> {
    let corner = |h: crate::mesh::HalfedgeId| (h.idx() / 3, h.idx() % 3);
    (0..topo.num_edges())
        .map(EdgeId::from)
        .filter(|&e| {
            let h = topo.edge_halfedge(e);
            let Some(t) = topo.twin(h) else {
                return false;
            };
            // h runs a -> b in its face, t runs b -> a in its own.
            let ((f, i), (g, j)) = (corner(h), corner(t));
            differs((f, i), (g, (j + 1) % 3)) || differs((f, (i + 1) % 3), (g, j))
        })
        .collect()
}

/// The corners of the box round `points` (lower-left, upper-right); empty:
/// infinite corners the wrong way round.
pub fn bounds(points: impl IntoIterator<Item = DVec2>) -> (DVec2, DVec2) {
    points.into_iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// Signed double area of a uv triangle (positive counter-clockwise).
#[inline]
pub fn double_area(q: [DVec2; 3]) -> f64 {
    (q[1] - q[0]).perp_dot(q[2] - q[0])
}

/// Signed double area of triangle `t` in the layout `uv`.
#[inline]
pub fn face_double_area(t: &[u32; 3], uv: &[DVec2]) -> f64 {
    double_area(t.map(|v| uv[v as usize]))
}

/// Singular values (largest first) of the map from a 3D triangle to its uv
/// triangle, and the uv triangle's signed area.
pub fn jacobian(p: [DVec3; 3], u: [DVec2; 3]) -> (f64, f64, f64) {
    // The 3D triangle in its own plane.
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let len1 = e1.length();
    let x1 = DVec2::new(len1, 0.0);
    let x2 = DVec2::new(e2.dot(e1) / len1, e1.cross(e2).length() / len1);
    let du1 = u[1] - u[0];
    let du2 = u[2] - u[0];
    // J [x1 x2] = [du1 du2]  =>  J = [du1 du2] [x1 x2]^-1
    let det_x = x1.x * x2.y - x2.x * x1.y;
    let inv = [[x2.y / det_x, -x2.x / det_x], [-x1.y / det_x, x1.x / det_x]];
    let j = [
        [
            du1.x * inv[0][0] + du2.x * inv[1][0],
            du1.x * inv[0][1] + du2.x * inv[1][1],
        ],
        [
            du1.y * inv[0][0] + du2.y * inv[1][0],
            du1.y * inv[0][1] + du2.y * inv[1][1],
        ],
    ];
    // Singular values of a 2x2 matrix in closed form.
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let e = (a + d) / 2.0;
    let f = (a - d) / 2.0;
    let g = (c + b) / 2.0;
    let h = (c - b) / 2.0;
    let q = (e * e + h * h).sqrt();
    let r = (f * f + g * g).sqrt();
    (q + r, (q - r).abs(), du1.perp_dot(du2) / 2.0)
}

/// The conf_mean figure: sigma1 / sigma2 averaged with the 3D areas as
/// weights, over (3D area, `jacobian`) per face; faces of no area in 3D or
/// uv are left out.
pub fn conf_mean(faces: impl Iterator<Item = (f64, (f64, f64, f64))>) -> f64 {
    let (mut sum, mut weight) = (0.0, 0.0);
    for (area, (s1, s2, _)) in faces {
        if s2 > 0.0 && area > 0.0 {
            sum += area * s1 / s2;
            weight += area;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        f64::INFINITY
    }
}

/// The area_log figure over (3D area, signed uv area) per face: mean
/// |log(A_uv / A_3d)| weighted by 3D area, the uvs scaled so the total uv
/// area equals the total 3D area; faces of no area in 3D or uv are left
/// out of the mean but not of the scale.
pub fn area_log(faces: impl Iterator<Item = (f64, f64)> + Clone) -> f64 {
    let (total_3d, total_uv) = faces
        .clone()
        .fold((0.0, 0.0), |(a, u), (area, uv)| (a + area, u + uv.abs()));
    let scale2 = if total_uv > 0.0 {
        total_3d / total_uv
    } else {
        1.0
    };
    // fold from +0.0: an empty f64 sum is -0.0.
    let sum = faces
        .filter(|&(area, uv)| uv != 0.0 && area > 0.0)
        .map(|(area, uv)| area * (uv.abs() * scale2 / area).ln().abs())
        .fold(0.0, |a, b| a + b);
    sum / total_3d
}

/// Every figure of `mesh`'s uv layer; `edge_visibility` by `topo`'s edges.
pub fn measure(mesh: &TriMesh, topo: &Topology, edge_visibility: &[f32]) -> Option<UvMetrics> {
    let layer = mesh.uvs.as_ref()?;
    let nf = mesh.num_faces();
    let area_3d: Vec<f64> = (0..nf).map(|f| mesh.face_area(f)).collect();
    let total_3d: f64 = area_3d.iter().sum();
    let jac: Vec<(f64, f64, f64)> = (0..nf)
        .map(|f| {
            let u = [uv(layer, f, 0), uv(layer, f, 1), uv(layer, f, 2)];
            jacobian(mesh.corners(f), u)
        })
        .collect();

    // Charts: faces joined across edges that are not seams.
    let seams = seam_edges(topo, layer);
    let mut is_seam = vec![false; topo.num_edges()];
    for e in &seams {
        is_seam[e.idx()] = true;
    }
    let mut sets = DisjointSets::new(nf);
    for (e, &seam) in is_seam.iter().enumerate() {
        if let Some([f, g]) = topo.edge_faces(EdgeId::from(e))
            && !seam
        {
            sets.union(f.idx(), g.idx());
        }
    }
    let (chart_of, charts) = sets.labels();
    let mut positive = vec![0usize; charts];
    let mut negative = vec![0usize; charts];
    for (f, j) in jac.iter().enumerate() {
        if j.2 > 0.0 {
            positive[chart_of[f] as usize] += 1;
        } else if j.2 < 0.0 {
            negative[chart_of[f] as usize] += 1;
        }
    }
    let flips = (0..charts).map(|c| positive[c].min(negative[c])).sum();
    let degenerate = jac.iter().filter(|j| j.2 == 0.0).count();
    let mut overlapping = vec![false; nf];
    for [f, g] in super::intersect::overlapping_pairs(&layer.triangles, &layer.coords) {
        overlapping[f as usize] = true;
        overlapping[g as usize] = true;
    }

    let edge_length = |e: EdgeId| {
        let [a, b] = topo.edge_vertices(e);
        (mesh.positions[a.idx()] - mesh.positions[b.idx()]).length()
    };
    // fold from +0.0: an empty f64 sum is -0.0.
    let seam_length = seams
        .iter()
        .map(|&e| edge_length(e))
        .fold(0.0, |a, b| a + b);
    let seam_vis = seams
        .iter()
        .map(|&e| edge_length(e) * edge_visibility[e.idx()] as f64)
        .fold(0.0, |a, b| a + b);
    let root_area = total_3d.sqrt();
    Some(UvMetrics {
        charts,
        flips,
        overlaps: overlapping.iter().filter(|&&o| o).count(),
        degenerate,
        conf_mean: conf_mean(area_3d.iter().copied().zip(jac.iter().copied())),
        area_log: area_log(area_3d.iter().zip(&jac).map(|(&a, j)| (a, j.2))),
        seam_length,
        seam_ratio: seam_length / root_area,
        seam_vis: seam_vis / root_area,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_of_similarities_and_stretches() {
        let p = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 1.0),
        ];
        // A rotated, scaled copy of the triangle in its plane is conformal.
        let x = [
            DVec2::ZERO,
            DVec2::new(2.0, 0.0),
            DVec2::new(0.0, 2f64.sqrt()),
        ];
        let rot = DVec2::from_angle(0.7);
        let u = x.map(|q| rot.rotate(q) * 3.0);
        let (s1, s2, area) = jacobian(p, u);
        assert!((s1 - 3.0).abs() < 1e-12 && (s2 - 3.0).abs() < 1e-12);
        assert!(area > 0.0);
        // Stretch x by 2: sigma = (2, 1).
        let u = x.map(|q| DVec2::new(2.0 * q.x, q.y));
        let (s1, s2, _) = jacobian(p, u);
        assert!((s1 - 2.0).abs() < 1e-12 && (s2 - 1.0).abs() < 1e-12);
        // Mirrored: negative area, same singular values.
        let u = x.map(|q| DVec2::new(-q.x, q.y));
        let (s1, s2, area) = jacobian(p, u);
        assert!((s1 - 1.0).abs() < 1e-12 && (s2 - 1.0).abs() < 1e-12 && area < 0.0);
    }
}
