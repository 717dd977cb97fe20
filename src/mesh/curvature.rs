//! Discrete curvature (Meyer, Desbrun, Schröder, Barr 2003, "Discrete
//! differential-geometry operators for triangulated 2-manifolds").
//!
//! - Gaussian curvature as the angle defect: 2*pi minus the angles at an
//!   interior vertex, pi minus them at a boundary vertex (the boundary's
//!   geodesic curvature), so the defects always sum to 2*pi*chi
//!   (Gauss-Bonnet). Divided by the mixed Voronoi area it is a pointwise K.
//! - Mean curvature from the cotangent Laplacian of the positions.
//! - Signed dihedral (bending) angle per edge.
//!
//! Angles use atan2(|a x b|, a . b), accurate near 0 and pi where acos is not.

use glam::DVec3;
use serde::Serialize;

use super::halfedge::Topology;
use super::ids::{EdgeId, VertexId};
use super::trimesh::TriMesh;

/// The interior angle at each corner of each face.
pub fn corner_angles(mesh: &TriMesh) -> Vec<[f64; 3]> {
    (0..mesh.num_faces())
        .map(|f| {
            let p = mesh.corners(f);
            std::array::from_fn(|i| angle_between(p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]))
        })
        .collect()
}

#[inline]
pub fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Angle defect of every vertex (0 for unreferenced ones).
pub fn angle_defects(mesh: &TriMesh, topo: &Topology, angles: &[[f64; 3]]) -> Vec<f64> {
    let mut sum = vec![0.0; mesh.num_vertices()];
    for (t, a) in mesh.triangles.iter().zip(angles) {
        for i in 0..3 {
            sum[t[i] as usize] += a[i];
        }
    }
    sum.iter()
        .enumerate()
        .map(|(v, &s)| {
            let v = VertexId::from(v);
            if !topo.is_referenced(v) {
                0.0
            } else if topo.is_boundary_vertex(v) {
                std::f64::consts::PI - s
            } else {
                std::f64::consts::TAU - s
            }
        })
        .collect()
}

/// Mixed Voronoi area of every vertex (Meyer et al. 2003, section 3.3): a
/// non-obtuse triangle gives each corner its Voronoi region,
/// (|ij|^2 cot k + |ik|^2 cot j) / 8; an obtuse one gives half its area to
/// the obtuse corner and a quarter to the others. The areas sum to the
/// mesh's area.
pub fn mixed_areas(mesh: &TriMesh, angles: &[[f64; 3]]) -> Vec<f64> {
    let mut area = vec![0.0; mesh.num_vertices()];
    let right = std::f64::consts::FRAC_PI_2;
    for (f, (t, a)) in mesh.triangles.iter().zip(angles).enumerate() {
        let p = mesh.corners(f);
        let face_area = mesh.face_area(f);
        let obtuse = a.iter().position(|&x| x > right);
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let share = match obtuse {
                Some(o) if o == i => face_area / 2.0,
                Some(_) => face_area / 4.0,
                None => {
                    ((p[j] - p[i]).length_squared() * cot(a[k])
                        + (p[k] - p[i]).length_squared() * cot(a[j]))
                        / 8.0
                }
            };
            area[t[i] as usize] += share;
        }
    }
    area
}

#[inline]
fn cot(angle: f64) -> f64 {
    angle.cos() / angle.sin()
}

/// Pointwise Gaussian curvature: angle defect over mixed area (0 where the
/// area vanishes: unreferenced vertices, fans of degenerate faces).
pub fn gaussian_curvature(defects: &[f64], areas: &[f64]) -> Vec<f64> {
    defects
        .iter()
        .zip(areas)
        .map(|(&d, &a)| if a > 0.0 { d / a } else { 0.0 })
        .collect()
}

/// Mean curvature H of every vertex from the cotangent Laplacian:
/// K(x_i) = 1/(2 A_i) sum_j (cot a_ij + cot b_ij)(x_i - x_j) = 2 H n_i,
/// here H = K(x_i) . n_i / 2 with n_i the area-weighted vertex normal, so
/// convex regions are positive when the faces are counter-clockwise seen
/// from outside. Degenerate faces are skipped (their cotangents blow up).
pub fn mean_curvature(mesh: &TriMesh, angles: &[[f64; 3]], areas: &[f64]) -> Vec<f64> {
    let n = mesh.num_vertices();
    let mut laplace = vec![DVec3::ZERO; n];
    let mut normal = vec![DVec3::ZERO; n];
    for (f, (t, a)) in mesh.triangles.iter().zip(angles).enumerate() {
        let area_vector = mesh.face_area_vector(f);
        let p = mesh.corners(f);
        let degenerate = a.iter().any(|&x| x.sin() < 1e-12);
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            normal[t[i] as usize] += area_vector;
            if !degenerate {
                laplace[t[i] as usize] += cot(a[k]) * (p[i] - p[j]) + cot(a[j]) * (p[i] - p[k]);
            }
        }
    }
    (0..n)
        .map(|v| {
            if areas[v] > 0.0 {
                laplace[v].dot(normal[v].normalize_or_zero()) / (4.0 * areas[v])
            } else {
                0.0
            }
        })
        .collect()
}

/// Signed bending angle of every edge between its faces' normals: 0 where
/// flat, positive where convex (seen from the side the normals point to),
/// negative where concave; 0 on boundary edges.
pub fn dihedral_angles(mesh: &TriMesh, topo: &Topology) -> Vec<f64> {
    (0..topo.num_edges())
        .map(|e| {
            let h = topo.edge_halfedge(EdgeId::from(e));
            let Some(t) = topo.twin(h) else {
                return 0.0;
            };
            let n1 = mesh.face_normal(topo.face(h).idx());
            let n2 = mesh.face_normal(topo.face(t).idx());
            let a = mesh.positions[topo.origin(h).idx()];
            let b = mesh.positions[topo.tip(h).idx()];
            let axis = (b - a).normalize_or_zero();
            n1.cross(n2).dot(axis).atan2(n1.dot(n2))
        })
        .collect()
}

/// Summary of a per-element quantity over its finite values.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stats {
    pub min: f64,
    pub p05: f64,
    pub median: f64,
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
}

impl Stats {
    pub fn of(values: impl IntoIterator<Item = f64>) -> Option<Stats> {
        let mut v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_unstable_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        Some(Stats {
            min: v[0],
            p05: at(0.05),
            median: at(0.5),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            p95: at(0.95),
            max: v[v.len() - 1],
        })
    }
}

/// Every per-vertex and per-edge curvature of a mesh.
pub struct Curvature {
    pub angle_defect: Vec<f64>,
    pub mixed_area: Vec<f64>,
    pub gaussian: Vec<f64>,
    pub mean: Vec<f64>,
    pub dihedral: Vec<f64>,
}

impl Curvature {
    pub fn compute(mesh: &TriMesh, topo: &Topology) -> Curvature {
        let angles = corner_angles(mesh);
        let angle_defect = angle_defects(mesh, topo, &angles);
        let mixed_area = mixed_areas(mesh, &angles);
        Curvature {
            gaussian: gaussian_curvature(&angle_defect, &mixed_area),
            mean: mean_curvature(mesh, &angles, &mixed_area),
            dihedral: dihedral_angles(mesh, topo),
            angle_defect,
            mixed_area,
        }
    }
}
