//! Marching tetrahedra (Treece et al. 1999; seed 000, sec. 5.1.1): the
//! surface where a scalar field given at a tet mesh's vertices crosses 0,
//! one or two triangles per tet it crosses, vertices shared along the
//! mesh's edges. A plane cut is the field of signed distances to it.

use glam::DVec3;
use rayon::prelude::*;

use super::TetMesh;
use super::stuffing::{key, unkey};

/// A cut surface, each vertex placed in a tet of the mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Cut {
    pub positions: Vec<DVec3>,
    /// Facing the positive side of the field.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's tet.
    pub tet_of: Vec<u32>,
    /// Per vertex, a tet holding it and its barycentric coordinates there
    /// (where a texture defined per tet, such as an LST model's layers, is
    /// read).
    pub at: Vec<(u32, [f64; 4])>,
}

/// Where `field` (one value per vertex) crosses 0. A vertex at exactly 0
/// counts as positive, so no triangle degenerates to a point.
pub fn isosurface(mesh: &TetMesh, field: &[f64]) -> Cut {
    assert_eq!(
        field.len(),
        mesh.num_vertices(),
        "one field value per vertex"
    );
    let negative = |v: u32| field[v as usize] < 0.0;
    // The tets the surface crosses, in order: most it misses, and they are
    // passed over once, without more work (splitting every tet's corners
    // into two vectors was most of a plane cut's time).
    let crossed: Vec<u32> = (0..mesh.num_tets() as u32)
        .into_par_iter()
        .filter(|&t| {
            let below = mesh.tets[t as usize]
                .iter()
                .filter(|&&v| negative(v))
                .count();
            below != 0 && below != 4
        })
        .collect();
    // The crossed edges, sorted: the cut's vertices.
    let mut edges: Vec<u64> = crossed
        .par_iter()
        .flat_map_iter(|&t| {
            let t = mesh.tets[t as usize];
            super::mesh::TET_EDGES
                .iter()
                .filter(move |e| negative(t[e[0]]) != negative(t[e[1]]))
                .map(move |e| key(t[e[0]], t[e[1]]))
        })
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let vertex = |a: u32, b: u32| edges.binary_search(&key(a, b)).expect("a crossed edge") as u32;
    let crossing = |a: u32, b: u32| -> f64 {
        let (fa, fb) = (field[a as usize], field[b as usize]);
        (fa / (fa - fb)).clamp(0.0, 1.0)
    };
    let positions: Vec<DVec3> = edges
        .par_iter()
        .map(|&k| {
            let (a, b) = unkey(k);
            let t = crossing(a, b);
            mesh.positions[a as usize].lerp(mesh.positions[b as usize], t)
        })
        .collect();
    // Triangles per tet, in tet order.
    let per_tet: Vec<Vec<([u32; 3], u32)>> = crossed
        .par_chunks(1024)
        .map(|ids| {
            let mut out = Vec::new();
            for &id in ids {
                let t = &mesh.tets[id as usize];
                let (neg, pos): (Vec<u32>, Vec<u32>) = t.iter().partition(|&&v| negative(v));
                let polygon: Vec<u32> = match (neg.len(), pos.len()) {
                    (1, 3) => pos.iter().map(|&p| vertex(neg[0], p)).collect(),
                    (3, 1) => neg.iter().map(|&n| vertex(n, pos[0])).collect(),
                    // A quadrilateral, in order round it.
                    (2, 2) => vec![
                        vertex(neg[0], pos[0]),
                        vertex(neg[0], pos[1]),
                        vertex(neg[1], pos[1]),
                        vertex(neg[1], pos[0]),
                    ],
                    _ => continue,
                };
                let centroid = |vs: &[u32]| {
                    vs.iter()
                        .fold(DVec3::ZERO, |a, &v| a + mesh.positions[v as usize])
                        / vs.len() as f64
                };
                let up = centroid(&pos) - centroid(&neg);
                for k in 1..polygon.len() - 1 {
                    let mut tri = [polygon[0], polygon[k], polygon[k + 1]];
                    let p = tri.map(|v| positions[v as usize]);
                    if (p[1] - p[0]).cross(p[2] - p[0]).dot(up) < 0.0 {
                        tri.swap(1, 2);
                    }
                    out.push((tri, id));
                }
            }
            out
        })
        .collect();
    let mut cut = Cut {
        positions,
        ..Default::default()
    };
    let mut placed = vec![false; edges.len()];
    cut.at = vec![(0, [0.0; 4]); edges.len()];
    for (tri, tet) in per_tet.into_iter().flatten() {
        for &v in &tri {
            if !placed[v as usize] {
                placed[v as usize] = true;
                let (a, b) = unkey(edges[v as usize]);
                let t = crossing(a, b);
                let corners = mesh.tets[tet as usize];
                let mut bary = [0.0; 4];
                for (k, &c) in corners.iter().enumerate() {
                    if c == a {
                        bary[k] = 1.0 - t;
                    } else if c == b {
                        bary[k] = t;
                    }
                }
                cut.at[v as usize] = (tet, bary);
            }
        }
        cut.triangles.push(tri);
        cut.tet_of.push(tet);
    }
    cut
}

/// The cut by the plane `normal . p = offset`, triangles facing `normal`.
pub fn plane_cut(mesh: &TetMesh, normal: DVec3, offset: f64) -> Cut {
    let field: Vec<f64> = mesh
        .positions
        .par_iter()
        .map(|&p| normal.dot(p) - offset)
        .collect();
    isosurface(mesh, &field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    /// A plane through a stuffed ball: the cut is a closed disc (its area
    /// matches the section of the tet mesh's own boundary, every edge in
    /// two triangles but the rim), every vertex on the plane, every
    /// triangle facing the normal, every vertex's barycentric placement
    /// giving back its position.
    #[test]
    fn a_plane_cuts_a_ball_in_a_disc() {
        let ball = crate::mesh::shapes::icosphere(3);
        let opts = crate::tetra::TetOptions {
            edge_length: Some(0.15),
            ..Default::default()
        };
        let m = crate::tetra::tetrahedralise(&ball, &opts, &Silent).expect("ball");
        let n = DVec3::new(0.3, -0.4, 0.85).normalize();
        let cut = plane_cut(&m, n, 0.1);
        assert!(cut.triangles.len() > 100);
        let mut area = 0.0;
        for t in &cut.triangles {
            let p = t.map(|v| cut.positions[v as usize]);
            let a = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(a.dot(n) > 0.0, "a triangle faces away");
            area += a.length() / 2.0;
        }
        // The disc of radius sqrt(1 - 0.1^2), a little smaller for the
        // stuffed boundary's chords.
        let disc = std::f64::consts::PI * (1.0 - 0.01);
        assert!(
            (area - disc).abs() < 0.03 * disc,
            "area {area} against {disc}"
        );
        for (v, p) in cut.positions.iter().enumerate() {
            assert!((n.dot(*p) - 0.1).abs() < 1e-12);
            let (t, b) = cut.at[v];
            let c = m.corners(t as usize);
            let q = c[0] * b[0] + c[1] * b[1] + c[2] * b[2] + c[3] * b[3];
            assert!(q.distance(*p) < 1e-12);
        }
    }
}
