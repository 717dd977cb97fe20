//! From angles to uv coordinates (ABF++ section 5): each triangle's angles
//! fix its shape up to similarity; the uvs making every triangle as similar
//! as possible to its shape are found by least squares with two vertices
//! pinned, as in LSCM (Lévy, Petitjean, Ray, Maillot 2002). Fed the 3D
//! angles instead of ABF++'s, this is LSCM itself, the fallback.
//!
//! Per triangle with reference shape q0, q1, q2 (complex) and uvs u0, u1,
//! u2, the map is conformal when sum_j (q_{j+2} - q_{j+1}) u_j = 0; the
//! residual is weighted by 1/sqrt(2 area) so each triangle counts by area.

use glam::{DVec2, DVec3};

use crate::error::Result;
use crate::linalg::{SpdPattern, VertexOrder};
use crate::mesh::{Topology, TriMesh, VertexId};

/// Uvs of a disk-shaped chart whose corners should have `angles`; `order`,
/// when given, orders the chart's vertices for the factorisation.
pub fn from_angles(
    mesh: &TriMesh,
    topo: &Topology,
    angles: &[[f64; 3]],
    order: Option<&VertexOrder>,
) -> Result<Vec<DVec2>> {
    Layout::new(mesh, topo, order)?.solve(mesh, angles)
}

/// A chart's least-squares system with its pins and sparsity, which do not
/// depend on the angles: made once, while ABF++ finds them.
pub struct Layout {
    pin_a: usize,
    pin_b: usize,
    /// Unknown pair of every vertex (x at 2k, y at 2k + 1), `u32::MAX` for
    /// the pins and unreferenced vertices.
    free: Vec<u32>,
    pattern: SpdPattern,
}

impl Layout {
    pub fn new(mesh: &TriMesh, topo: &Topology, order: Option<&VertexOrder>) -> Result<Layout> {
        let n = mesh.num_vertices();
        let (pin_a, pin_b) = pins(mesh, topo);
        // Free unknowns: x and y of every other referenced vertex.
        let mut free = vec![u32::MAX; n];
        let mut count = 0u32;
        for (v, slot) in free.iter_mut().enumerate() {
            if v != pin_a && v != pin_b && topo.is_referenced(VertexId::from(v)) {
                *slot = count;
                count += 1;
            }
        }
        let unknowns = 2 * count as usize;
        let mut positions = Vec::with_capacity(mesh.num_faces() * 21);
        each_entry(mesh, &free, |r, c, _, _| positions.push((r, c)));
        let pattern = SpdPattern::of_vertices(unknowns, &positions, order, &free, 2)?;
        Ok(Layout {
            pin_a,
            pin_b,
            free,
            pattern,
        })
    }

    fn pinned_uv(&self, mesh: &TriMesh, v: usize) -> Option<DVec2> {
        if v == self.pin_a {
            Some(DVec2::ZERO)
        } else if v == self.pin_b {
            Some(DVec2::new(
                (mesh.positions[self.pin_b] - mesh.positions[self.pin_a]).length(),
                0.0,
            ))
        } else {
            None
        }
    }

    /// The chart's uvs for these angles.
    pub fn solve(&self, mesh: &TriMesh, angles: &[[f64; 3]]) -> Result<Vec<DVec2>> {
        let rows: Vec<[[f64; 6]; 2]> = (0..mesh.num_faces())
            .map(|f| conformality_rows(mesh, f, angles[f]))
            .collect();
        let mut values = Vec::with_capacity(self.pattern.entries());
        each_entry(mesh, &self.free, |_, _, f, (p, q)| {
            let [re, im] = &rows[f];
            values.push(re[p] * re[q] + im[p] * im[q]);
        });
        // The pins' known uvs move to the right-hand side.
        let mut rhs = vec![0.0; self.pattern.size()];
        for (t, face_rows) in mesh.triangles.iter().zip(&rows) {
            for row in face_rows {
                let known: f64 = (0..6)
                    .filter_map(|k| {
                        self.pinned_uv(mesh, t[k / 2] as usize)
                            .map(|uv| row[k] * uv[k % 2])
                    })
                    .sum();
                for (p, coefficient) in row.iter().enumerate() {
                    if let Some(r) = column(&self.free, t, p) {
                        rhs[r as usize] -= coefficient * known;
                    }
                }
            }
        }
        self.pattern.factor(&values)?.solve(&mut rhs);
        Ok((0..mesh.num_vertices())
            .map(|v| {
                self.pinned_uv(mesh, v)
                    .unwrap_or_else(|| match self.free[v] {
                        u32::MAX => DVec2::ZERO,
                        k => DVec2::new(rhs[2 * k as usize], rhs[2 * k as usize + 1]),
                    })
            })
            .collect())
    }
}

/// Every entry (r, c), r >= c, of the normal matrix each face adds to, in
/// one order, with the face and its two local columns (x0, y0, x1, y1, x2,
/// y2); `free` as in `Layout`.
fn each_entry(
    mesh: &TriMesh,
    free: &[u32],
    mut entry: impl FnMut(u32, u32, usize, (usize, usize)),
) {
    for (f, t) in mesh.triangles.iter().enumerate() {
        for p in 0..6 {
            let Some(r) = column(free, t, p) else {
                continue;
            };
            for q in 0..6 {
                if let Some(c) = column(free, t, q)
                    && r >= c
                {
                    entry(r, c, f, (p, q));
                }
            }
        }
    }
}

/// The unknown of local column `k` of triangle `t`, if it is free.
fn column(free: &[u32], t: &[u32; 3], k: usize) -> Option<u32> {
    let v = t[k / 2] as usize;
    (free[v] != u32::MAX).then(|| 2 * free[v] + (k % 2) as u32)
}

/// The two real rows (over x0, y0, x1, y1, x2, y2) of face `f`'s
/// conformality residual for a triangle with the given angles, sized like
/// the 3D triangle.
fn conformality_rows(mesh: &TriMesh, f: usize, a: [f64; 3]) -> [[f64; 6]; 2] {
    let [p0, p1, _] = mesh.corners(f);
    let scale = (p1 - p0).length().max(1e-300);
    let q = [
        DVec2::ZERO,
        DVec2::new(scale, 0.0),
        DVec2::new(a[0].cos(), a[0].sin()) * scale * a[1].sin() / a[2].sin().max(1e-12),
    ];
    let double_area = super::metrics::double_area(q).abs().max(1e-300);
    let norm = 1.0 / double_area.sqrt();
    let mut re = [0.0; 6];
    let mut im = [0.0; 6];
    for j in 0..3 {
        let w = (q[(j + 2) % 3] - q[(j + 1) % 3]) * norm;
        // (a + ib)(x + iy) = (ax - by) + i(bx + ay)
        re[2 * j] = w.x;
        re[2 * j + 1] = -w.y;
        im[2 * j] = w.y;
        im[2 * j + 1] = w.x;
    }
    [re, im]
}

/// Two boundary vertices far apart to pin (any two vertices if the chart
/// has no boundary, which a chart never lacks).
fn pins(mesh: &TriMesh, topo: &Topology) -> (usize, usize) {
    let boundary: Vec<usize> = match topo.boundary_loops().first() {
        Some(cycle) => cycle.iter().map(|&h| topo.origin(h).idx()).collect(),
        None => (0..mesh.num_vertices())
            .filter(|&v| topo.is_referenced(VertexId::from(v)))
            .collect(),
    };
    let far_from = |from: DVec3| {
        *boundary
            .iter()
            .max_by(|&&a, &&b| {
                (mesh.positions[a] - from)
                    .length_squared()
                    .total_cmp(&(mesh.positions[b] - from).length_squared())
                    .then(b.cmp(&a))
            })
            .expect("a chart has vertices")
    };
    let a = far_from(mesh.positions[boundary[0]]);
    let b = far_from(mesh.positions[a]);
    (a, b)
}
