//! The tetrahedral mesh and its figures: boundary, face adjacency, dihedral
//! angles, radius ratio, volume and the Hausdorff distance of its boundary
//! to the surface it was made from.
//!
//! Invariants (established by the mesher and checked by `validate`): every
//! index is `< positions.len()`, every position is finite, and every
//! tetrahedron `[a, b, c, d]` is positively oriented:
//! `(b - a) . ((c - a) x (d - a)) > 0`, the convention of VTK, gmsh and
//! Medit alike.

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::bvh::Bvh;

/// No tetrahedron across this face (a boundary face).
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// The faces of a positively oriented tet, each opposite the corner of the
/// same index and counter-clockwise seen from outside.
pub const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// The six edges of a tet as corner pairs.
pub const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];

/// A tetrahedral mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetMesh {
    pub positions: Vec<DVec3>,
    /// Positively oriented (see the module's invariants).
    pub tets: Vec<[u32; 4]>,
    /// Fields over the vertices (a depth, a fibre direction...), written to
    /// and read from `.vtk` (POINT_DATA) and `.msh` (NodeData).
    pub vertex_attributes: Vec<Attribute>,
    /// Fields over the tets (a region, a quality...), as CELL_DATA and
    /// ElementData.
    pub tet_attributes: Vec<Attribute>,
}

/// A named field: `components` numbers per element, element by element.
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    /// Letters, digits, `_`, `-` and `.` (file formats split names at
    /// spaces).
    pub name: String,
    pub components: usize,
    pub values: Vec<f64>,
}

impl Attribute {
    /// The numbers of element `i`.
    pub fn get(&self, i: usize) -> &[f64] {
        &self.values[i * self.components..(i + 1) * self.components]
    }

    /// Errors unless the name is usable in files and the values fill
    /// `count` elements; `what` names the elements in the message.
    fn check(&self, count: usize, what: &str) -> Result<()> {
        let usable = |c: char| c.is_ascii_alphanumeric() || "_-.".contains(c);
        if self.name.is_empty() || !self.name.chars().all(usable) {
            return Err(Error::invalid(format!(
                "attribute name '{}' must be letters, digits, '_', '-' or '.'",
                self.name
            )));
        }
        if self.components == 0 || self.values.len() != self.components * count {
            return Err(Error::invalid(format!(
                "attribute '{}' has {} values, {count} {what} of {} components need {}",
                self.name,
                self.values.len(),
                self.components,
                self.components * count
            )));
        }
        Ok(())
    }
}

/// Check the attribute against `count` elements (`what`), then replace the
/// one of its name in `list` or append it.
fn put(
    list: &mut Vec<Attribute>,
    name: &str,
    components: usize,
    values: Vec<f64>,
    count: usize,
    what: &str,
) -> Result<()> {
    let a = Attribute {
        name: name.into(),
        components,
        values,
    };
    a.check(count, what)?;
    match list.iter_mut().find(|b| b.name == a.name) {
        Some(b) => *b = a,
        None => list.push(a),
    }
    Ok(())
}

/// Element quality over a whole mesh. Angles in degrees.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quality {
    pub min_dihedral: f64,
    pub max_dihedral: f64,
    /// Smallest radius ratio, 3 x inradius / circumradius (1 for the regular
    /// tetrahedron, 0 for a flat one).
    pub min_radius_ratio: f64,
    pub mean_radius_ratio: f64,
    /// Smallest signed volume (positive in a valid mesh).
    pub min_volume: f64,
    /// Dihedral angles counted in 1-degree bins from 0 to 180 (six per tet).
    pub histogram: Vec<u64>,
}

/// Hausdorff distances between the mesh's boundary and a surface, in mesh
/// units, measured at sample points (see `TetMesh::hausdorff`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Hausdorff {
    /// Largest distance from a sample of the boundary to the surface.
    pub boundary_to_surface: f64,
    /// Largest distance from a sample of the surface to the boundary.
    pub surface_to_boundary: f64,
    /// Diagonal of the surface's bounding box.
    pub diagonal: f64,
    /// Largest distance between neighbouring samples on a triangle; the
    /// distance is 1-Lipschitz, so no point is farther than the figures by
    /// more than `spacing / sqrt(3)`.
    pub spacing: f64,
}

impl Hausdorff {
    pub fn two_sided(&self) -> f64 {
        self.boundary_to_surface.max(self.surface_to_boundary)
    }

    /// The two-sided distance as a fraction of the diagonal.
    pub fn relative(&self) -> f64 {
        self.two_sided() / self.diagonal
    }
}

impl TetMesh {
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    pub fn num_tets(&self) -> usize {
        self.tets.len()
    }

    /// The four corner positions of tet `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 4] {
        self.tets[t].map(|v| self.positions[v as usize])
    }

    /// Signed volume of tet `t`.
    pub fn tet_volume(&self, t: usize) -> f64 {
        signed_volume(&self.corners(t))
    }

    /// Total volume.
    pub fn volume(&self) -> f64 {
        (0..self.num_tets())
            .into_par_iter()
            .map(|t| self.tet_volume(t))
            .sum()
    }

    /// The tets `tets` (in that order) as a mesh of their own, and for each
    /// of its vertices the vertex it was here. Attributes are not carried.
    pub fn subset(&self, tets: &[u32]) -> (TetMesh, Vec<u32>) {
        let mut new_of = vec![u32::MAX; self.num_vertices()];
        let mut old_of = Vec::new();
        let sub = tets
            .iter()
            .map(|&t| {
                self.tets[t as usize].map(|v| {
                    let n = &mut new_of[v as usize];
                    if *n == u32::MAX {
                        *n = old_of.len() as u32;
                        old_of.push(v);
                    }
                    *n
                })
            })
            .collect();
        let mesh = TetMesh {
            positions: old_of.iter().map(|&v| self.positions[v as usize]).collect(),
            tets: sub,
            ..Default::default()
        };
        (mesh, old_of)
    }

    /// Add (or replace) the vertex attribute `name`; errors on a bad name or
    /// a value count that is not `components` per vertex.
    pub fn set_vertex_attribute(
        &mut self,
        name: &str,
        components: usize,
        values: Vec<f64>,
    ) -> Result<()> {
        let count = self.positions.len();
        put(
            &mut self.vertex_attributes,
            name,
            components,
            values,
            count,
            "vertices",
        )
    }

    /// Add (or replace) the tet attribute `name`, as `set_vertex_attribute`.
    pub fn set_tet_attribute(
        &mut self,
        name: &str,
        components: usize,
        values: Vec<f64>,
    ) -> Result<()> {
        let count = self.tets.len();
        put(
            &mut self.tet_attributes,
            name,
            components,
            values,
            count,
            "tets",
        )
    }

    pub fn vertex_attribute(&self, name: &str) -> Option<&Attribute> {
        self.vertex_attributes.iter().find(|a| a.name == name)
    }

    pub fn tet_attribute(&self, name: &str) -> Option<&Attribute> {
        self.tet_attributes.iter().find(|a| a.name == name)
    }

    /// Each tet's smallest dihedral angle, in degrees (a tet attribute the
    /// CLI writes, so a viewer can show where the quality is).
    pub fn min_dihedrals(&self) -> Vec<f64> {
        (0..self.num_tets())
            .into_par_iter()
            .map(|t| {
                dihedral_angles(&self.corners(t))
                    .into_iter()
                    .fold(f64::INFINITY, f64::min)
                    .to_degrees()
            })
            .collect()
    }

    /// Check the module's invariants; the error names the first offending
    /// element.
    pub fn validate(&self) -> Result<()> {
        for a in &self.vertex_attributes {
            a.check(self.positions.len(), "vertices")?;
        }
        for a in &self.tet_attributes {
            a.check(self.tets.len(), "tets")?;
        }
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::invalid(format!(
                "tet mesh vertex {v} has a non-finite coordinate"
            )));
        }
        let n = self.positions.len() as u32;
        for (t, tet) in self.tets.iter().enumerate() {
            if let Some(&v) = tet.iter().find(|&&v| v >= n) {
                return Err(Error::invalid(format!(
                    "tet {t} refers to vertex {v}, the mesh has {n}"
                )));
            }
            if self.tet_volume(t) <= 0.0 {
                return Err(Error::invalid(format!(
                    "tet {t} {tet:?} has volume {} (must be positive)",
                    self.tet_volume(t)
                )));
            }
        }
        Ok(())
    }

    /// Every face with its tet and local face index, keyed by sorted corners,
    /// sorted by key.
    fn sorted_faces(&self) -> Vec<([u32; 3], u32, u8)> {
        let mut faces: Vec<([u32; 3], u32, u8)> = self
            .tets
            .par_iter()
            .enumerate()
            .flat_map_iter(|(t, tet)| {
                TET_FACES.iter().enumerate().map(move |(k, f)| {
                    let mut key = [tet[f[0]], tet[f[1]], tet[f[2]]];
                    key.sort_unstable();
                    (key, t as u32, k as u8)
                })
            })
            .collect();
        faces.par_sort_unstable();
        faces
    }

    /// For each tet, the tet across each face (face `k` is opposite corner
    /// `k`), or `NO_NEIGHBOUR`. Errors if a face is shared by more than two
    /// tets (the mesh is not a valid complex).
    pub fn face_adjacency(&self) -> Result<Vec<[u32; 4]>> {
        let faces = self.sorted_faces();
        let mut adj = vec![[NO_NEIGHBOUR; 4]; self.tets.len()];
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            match j - i {
                1 => {}
                2 => {
                    let (a, b) = (faces[i], faces[i + 1]);
                    adj[a.1 as usize][a.2 as usize] = b.1;
                    adj[b.1 as usize][b.2 as usize] = a.1;
                }
                n => {
                    return Err(Error::invalid(format!(
                        "face {:?} is shared by {n} tets (tets {} and {})",
                        faces[i].0,
                        faces[i].1,
                        faces[i + 1].1
                    )));
                }
            }
            i = j;
        }
        Ok(adj)
    }

    /// The faces used by exactly one tet, counter-clockwise seen from
    /// outside, in tet order.
    pub fn boundary_triangles(&self) -> Vec<[u32; 3]> {
        let faces = self.sorted_faces();
        let mut boundary: Vec<(u32, u8)> = Vec::new();
        let mut i = 0;
        while i < faces.len() {
            let mut j = i + 1;
            while j < faces.len() && faces[j].0 == faces[i].0 {
                j += 1;
            }
            if j - i == 1 {
                boundary.push((faces[i].1, faces[i].2));
            }
            i = j;
        }
        boundary.sort_unstable();
        boundary
            .into_iter()
            .map(|(t, k)| {
                let tet = self.tets[t as usize];
                TET_FACES[k as usize].map(|c| tet[c])
            })
            .collect()
    }

    /// The boundary as a triangle mesh holding only the boundary vertices
    /// (numbered in order of first use).
    pub fn boundary_surface(&self) -> TriMesh {
        let tris = self.boundary_triangles();
        let mut map = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        let triangles = tris
            .iter()
            .map(|t| {
                t.map(|v| {
                    if map[v as usize] == u32::MAX {
                        map[v as usize] = positions.len() as u32;
                        positions.push(self.positions[v as usize]);
                    }
                    map[v as usize]
                })
            })
            .collect();
        TriMesh::new(positions, triangles)
    }

    /// Dihedral angles, radius ratios and volumes over all tets.
    pub fn quality(&self) -> Quality {
        struct Acc {
            min_d: f64,
            max_d: f64,
            min_rr: f64,
            sum_rr: f64,
            min_v: f64,
            hist: Vec<u64>,
        }
        let empty = || Acc {
            min_d: f64::INFINITY,
            max_d: f64::NEG_INFINITY,
            min_rr: f64::INFINITY,
            sum_rr: 0.0,
            min_v: f64::INFINITY,
            hist: vec![0; 180],
        };
        let acc = (0..self.num_tets())
            .into_par_iter()
            .fold(empty, |mut acc, t| {
                let c = self.corners(t);
                for a in dihedral_angles(&c) {
                    let deg = a.to_degrees();
                    acc.min_d = acc.min_d.min(deg);
                    acc.max_d = acc.max_d.max(deg);
                    acc.hist[(deg as usize).min(179)] += 1;
                }
                let rr = radius_ratio(&c);
                acc.min_rr = acc.min_rr.min(rr);
                acc.sum_rr += rr;
                acc.min_v = acc.min_v.min(signed_volume(&c));
                acc
            })
            .reduce(empty, |mut a, b| {
                a.min_d = a.min_d.min(b.min_d);
                a.max_d = a.max_d.max(b.max_d);
                a.min_rr = a.min_rr.min(b.min_rr);
                a.sum_rr += b.sum_rr;
                a.min_v = a.min_v.min(b.min_v);
                for (x, y) in a.hist.iter_mut().zip(b.hist) {
                    *x += y;
                }
                a
            });
        Quality {
            min_dihedral: acc.min_d,
            max_dihedral: acc.max_d,
            min_radius_ratio: acc.min_rr,
            mean_radius_ratio: acc.sum_rr / self.num_tets().max(1) as f64,
            min_volume: acc.min_v,
            histogram: acc.hist,
        }
    }

    /// Hausdorff distances between this mesh's boundary and `surface`.
    ///
    /// Sampling (as Metro does): every vertex of both surfaces, and on each
    /// triangle the points of a regular barycentric grid with `n` steps per
    /// side, `n = ceil(longest edge / (diagonal / 500))`, capped so that a
    /// surface gets about a million samples at most (but never fewer than 4
    /// steps), are measured against the other surface by exact
    /// point-triangle distance over a BVH (each search starts from the bound
    /// the nearest corner gives). The largest step is reported as `spacing`.
    pub fn hausdorff(&self, surface: &TriMesh) -> Hausdorff {
        let boundary = self.boundary_surface();
        let diagonal = surface
            .bounding_box()
            .map(|(lo, hi)| lo.distance(hi))
            .unwrap_or(0.0);
        let step = diagonal / 500.0;
        let to_bvh = |m: &TriMesh| Bvh::new((0..m.num_faces()).map(|f| m.corners(f)).collect());
        let (surface_bvh, boundary_bvh) = rayon::join(|| to_bvh(surface), || to_bvh(&boundary));
        let (b2s, s1) = one_sided(&boundary, &surface_bvh, step);
        let (s2b, s2) = one_sided(surface, &boundary_bvh, step);
        Hausdorff {
            boundary_to_surface: b2s,
            surface_to_boundary: s2b,
            diagonal,
            spacing: s1.max(s2),
        }
    }
}

/// Largest sampled distance from `from`'s triangles to `to`, and the
/// largest sample spacing (see `TetMesh::hausdorff`).
fn one_sided(from: &TriMesh, to: &Bvh, step: f64) -> (f64, f64) {
    const SAMPLES: f64 = 1e6;
    if from.triangles.is_empty() {
        return (0.0, 0.0);
    }
    let max_steps = ((2.0 * SAMPLES / from.triangles.len() as f64).sqrt() as usize).max(4);
    let at_vertex: Vec<f64> = from.positions.par_iter().map(|&p| to.distance(p)).collect();
    // The largest distance found so far by any triangle: a sample whose
    // bound from the corners cannot pass it needs no query. Non-negative
    // floats order as their bits do. The result is the largest sampled
    // distance whichever thread finds what first (a skipped sample could
    // not have raised it). From 0, not the vertices' largest: a vertex no
    // triangle uses must not prune the triangles' samples.
    let largest = AtomicU64::new(0f64.to_bits());
    from.triangles
        .par_iter()
        .map(|t| {
            let p = t.map(|v| from.positions[v as usize]);
            let d = t.map(|v| at_vertex[v as usize]);
            let longest = p[0]
                .distance(p[1])
                .max(p[1].distance(p[2]))
                .max(p[2].distance(p[0]));
            let n = if step > 0.0 {
                ((longest / step).ceil() as usize).clamp(1, max_steps)
            } else {
                1
            };
            let mut best = d[0].max(d[1]).max(d[2]);
            for i in 0..=n {
                for j in 0..=n - i {
                    let k = n - i - j;
                    if i == n || j == n || k == n {
                        continue; // a corner, measured above
                    }
                    let (a, b, c) = (
                        i as f64 / n as f64,
                        j as f64 / n as f64,
                        k as f64 / n as f64,
                    );
                    let q = a * p[0] + b * p[1] + c * p[2];
                    let upper = (0..3)
                        .map(|m| d[m] + q.distance(p[m]))
                        .fold(f64::INFINITY, f64::min);
                    // Only a sample farther than the largest so far raises it.
                    let known = f64::from_bits(largest.load(Ordering::Relaxed)).max(best);
                    if upper > known {
                        let d = to.distance_between(q, known, upper);
                        if d > known {
                            best = d;
                            largest.fetch_max(d.to_bits(), Ordering::Relaxed);
                        }
                    }
                }
            }
            (best, longest / n as f64)
        })
        .reduce(|| (0.0, 0.0), |x, y| (x.0.max(y.0), x.1.max(y.1)))
}

/// Signed volume of the tet with corners `c`.
#[inline]
pub fn signed_volume(c: &[DVec3; 4]) -> f64 {
    (c[1] - c[0]).dot((c[2] - c[0]).cross(c[3] - c[0])) / 6.0
}

/// The six interior dihedral angles (radians), in `TET_EDGES` order: the
/// angle at edge `ij` between the faces through it.
pub fn dihedral_angles(c: &[DVec3; 4]) -> [f64; 6] {
    TET_EDGES.map(|[i, j]| {
        let (k, l) = other_two(i, j);
        let e = c[j] - c[i];
        // Normals of the planes (e, c_k) and (e, c_l) turn the same way about
        // e as the projections of c_k and c_l, so their angle is the
        // dihedral one.
        let n1 = e.cross(c[k] - c[i]);
        let n2 = e.cross(c[l] - c[i]);
        n1.cross(n2).length().atan2(n1.dot(n2))
    })
}

/// The two corners of a tet not in edge `ij`.
#[inline]
fn other_two(i: usize, j: usize) -> (usize, usize) {
    let mut rest = (0..4).filter(|&k| k != i && k != j);
    let k = rest.next().unwrap_or(0);
    let l = rest.next().unwrap_or(0);
    (k, l)
}

/// 3 x inradius / circumradius: 1 for the regular tet, 0 for a flat one.
pub fn radius_ratio(c: &[DVec3; 4]) -> f64 {
    let vol = signed_volume(c).abs();
    if vol == 0.0 {
        return 0.0;
    }
    let area: f64 = TET_FACES
        .iter()
        .map(|f| 0.5 * (c[f[1]] - c[f[0]]).cross(c[f[2]] - c[f[0]]).length())
        .sum();
    let inradius = 3.0 * vol / area;
    // Circumcentre relative to c[3]: |a|^2 (b x c) + |b|^2 (c x a) + |c|^2
    // (a x b), over 12 times the volume.
    let (a, b, d) = (c[0] - c[3], c[1] - c[3], c[2] - c[3]);
    let num = a.length_squared() * b.cross(d)
        + b.length_squared() * d.cross(a)
        + d.length_squared() * a.cross(b);
    let circumradius = num.length() / (12.0 * vol);
    3.0 * inradius / circumradius
}

#[cfg(test)]
mod tests {
    use super::*;

    fn regular() -> TetMesh {
        TetMesh {
            positions: vec![
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(1.0, -1.0, -1.0),
                DVec3::new(-1.0, 1.0, -1.0),
                DVec3::new(-1.0, -1.0, 1.0),
            ],
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn the_regular_tet_has_known_figures() {
        let mut m = regular();
        if m.tet_volume(0) < 0.0 {
            m.tets[0].swap(2, 3);
        }
        let q = m.quality();
        let expected = (1.0f64 / 3.0).acos().to_degrees();
        assert!((q.min_dihedral - expected).abs() < 1e-9);
        assert!((q.max_dihedral - expected).abs() < 1e-9);
        assert!((q.min_radius_ratio - 1.0).abs() < 1e-9);
        assert!((m.volume() - 8.0 / 3.0).abs() < 1e-12);
        assert_eq!(m.boundary_triangles().len(), 4);
        // Outward: the boundary encloses the tet's volume positively.
        assert!((m.boundary_surface().signed_volume() - m.volume()).abs() < 1e-12);
        m.validate().expect("valid");
    }

    #[test]
    fn two_tets_share_one_face() {
        let m = TetMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::Z,
                DVec3::new(1.0, 1.0, 1.0),
            ],
            tets: vec![[0, 1, 2, 3], [1, 4, 2, 3]],
            ..Default::default()
        };
        m.validate().expect("positive");
        let adj = m.face_adjacency().expect("manifold");
        assert_eq!(adj[0][0], 1);
        assert_eq!(adj[1][1], 0);
        assert_eq!(m.boundary_triangles().len(), 6);
        assert!((m.boundary_surface().signed_volume() - m.volume()).abs() < 1e-12);
    }

    #[test]
    fn hausdorff_of_a_tet_against_its_own_faces_is_zero_and_sees_an_offset() {
        let m = TetMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            tets: vec![[0, 1, 2, 3]],
            ..Default::default()
        };
        let surface = m.boundary_surface();
        let h = m.hausdorff(&surface);
        assert!(h.two_sided() < 1e-12);
        // The same surface moved off by 0.1 along z: every boundary point
        // of the face z = 0 is 0.1 from the moved face's plane or farther
        // from the other faces.
        let mut moved = surface.clone();
        for p in &mut moved.positions {
            p.z += 0.1;
        }
        let h = m.hausdorff(&moved);
        assert!(
            h.two_sided() >= 0.1 - 1e-12 && h.two_sided() <= 0.1 + 1e-12,
            "{h:?}"
        );
    }
}
