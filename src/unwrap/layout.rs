//! From angles to uv coordinates (ABF++ section 5): each triangle's angles
//! fix its shape up to similarity; the uvs making every triangle as similar
//! as possible to its shape are found by least squares with two vertices
//! pinned, as in LSCM (Lévy, Petitjean, Ray, Maillot 2002). Fed the 3D
//! angles instead of ABF++'s, this is LSCM itself, the fallback.
//!
//! Per triangle with reference shape q0, q1, q2 (complex) and uvs u0, u1,
//! u2, the map is conformal when sum_j (q_{j+2} - q_{j+1}) u_j = 0; the
//! residual is weighted by 1/sqrt(2 area) so each triangle counts by area.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DVec2, DVec3};

use crate::error::Result;
use crate::linalg::{SpdPattern, VertexOrder};
use crate::mesh::{FaceId, HalfedgeId, Topology, TriMesh, VertexId};

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

    /// Uvs for angles that close up (ABF++ converged far past its
    /// tolerance): face by face across the edges, each face's edge vectors
    /// from the one it was reached by, turned by its angle and scaled by
    /// the law of sines (ABF++ section 5's propagation). Edge vectors are
    /// carried, not differences of placed corners: a corner placed from two
    /// placed ones inherits both their errors, and along a chain of faces
    /// that doubles them step by step, where carried vectors only add each
    /// step's rounding. A corner opposite an angle near 0 or pi is still
    /// placed badly (the sines' ratio amplifies the angles' error), so the
    /// faces are taken best placed first, as Prim's algorithm grows a tree.
    /// Then moved, turned and scaled so the pins lie where `solve` pins
    /// them. Where the angles close up this is the layout the least
    /// squares find, up to the residual carried along the way (ABF++
    /// prefers the least squares for angles that do not), and it takes no
    /// factorisation.
    pub fn propagate(&self, mesh: &TriMesh, topo: &Topology, angles: &[[f64; 3]]) -> Vec<DVec2> {
        let n = mesh.num_vertices();
        let mut uv = vec![DVec2::ZERO; n];
        if mesh.num_faces() == 0 {
            return uv;
        }
        let mut placed = vec![false; n];
        let mut reached = vec![false; mesh.num_faces()];
        // The vector along each half-edge of a reached face.
        let mut along = vec![DVec2::ZERO; topo.num_halfedges()];
        // Candidates: a face across a reached face's edge, by the half-edge
        // it would be reached by, keyed by the sine at the corner it would
        // place (1 once that corner is placed: it only passes the tree
        // on), ties by half-edge.
        let mut heap = BinaryHeap::new();
        let first = topo.face_halfedges(FaceId(0))[0];
        let [a, b] = [topo.origin(first), topo.tip(first)].map(|v| v.idx());
        along[first.idx()] = DVec2::new((mesh.positions[b] - mesh.positions[a]).length(), 0.0);
        placed[a] = true;
        uv[b] = along[first.idx()];
        placed[b] = true;
        heap.push((1f64.to_bits(), Reverse(first.0)));
        while let Some((_, Reverse(h))) = heap.pop() {
            let h = HalfedgeId(h);
            let f = topo.face(h).idx();
            if reached[f] {
                continue;
            }
            reached[f] = true;
            if let Some(t) = topo.twin(h)
                && h != first
            {
                along[h.idx()] = -along[t.idx()];
            }
            // Corners i -> j along h, k the third; angles at each.
            let c = h.idx() % 3;
            let angle = |x: usize| angles[f][(c + x) % 3];
            let (next, prev) = (topo.next(h), topo.prev(h));
            let i_to_k = DVec2::from_angle(angle(0)).rotate(along[h.idx()])
                * (angle(1).sin() / angle(2).sin());
            along[next.idx()] = i_to_k - along[h.idx()];
            along[prev.idx()] = -i_to_k;
            let (i, k) = (topo.origin(h).idx(), topo.origin(prev).idx());
            if !placed[k] {
                uv[k] = uv[i] + i_to_k;
                placed[k] = true;
            }
            for g in topo.face_halfedges(FaceId::from(f)) {
                let Some(across) = topo.twin(g) else {
                    continue;
                };
                if reached[topo.face(across).idx()] {
                    continue;
                }
                let opposite = topo.origin(topo.prev(across)).idx();
                let sine = if placed[opposite] {
                    1.0
                } else {
                    let (g2, c2) = (topo.face(across).idx(), across.idx() % 3);
                    angles[g2][(c2 + 2) % 3].sin().max(0.0)
                };
                heap.push((sine.to_bits(), Reverse(across.0)));
            }
        }
        // The similarity z -> (z - uv[pin_a]) * w: pin_a to 0, pin_b to
        // its 3D distance along u.
        let from = uv[self.pin_a];
        let w = complex_div(self.pin_b_uv(mesh), uv[self.pin_b] - from);
        for (p, &laid) in uv.iter_mut().zip(&placed) {
            *p = if laid {
                w.rotate(*p - from)
            } else {
                DVec2::ZERO
            };
        }
        uv
    }

    fn pin_b_uv(&self, mesh: &TriMesh) -> DVec2 {
        DVec2::new(
            (mesh.positions[self.pin_b] - mesh.positions[self.pin_a]).length(),
            0.0,
        )
    }

    fn pinned_uv(&self, mesh: &TriMesh, v: usize) -> Option<DVec2> {
        if v == self.pin_a {
            Some(DVec2::ZERO)
        } else if v == self.pin_b {
            Some(self.pin_b_uv(mesh))
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

/// a / b as complex numbers.
fn complex_div(a: DVec2, b: DVec2) -> DVec2 {
    DVec2::new(a.x * b.x + a.y * b.y, a.y * b.x - a.x * b.y) / b.length_squared()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unwrap::abf::{self, AbfOptions};

    /// Converged ABF++ angles close up: the propagated layout is the least
    /// squares' to a millionth of an edge, on a cut-open sphere of 20k
    /// faces (placing each corner from the placed ones instead of carrying
    /// edge vectors drifts by a million edges there).
    #[test]
    fn propagation_of_converged_angles_is_the_least_squares_layout() {
        let chart = crate::unwrap::cutgraph::cut_open_sphere(5);
        let topo = Topology::build(&chart).unwrap();
        let solution = abf::solve(&chart, &topo, &AbfOptions::default()).unwrap();
        assert!(
            solution.converged && solution.residual <= 1e-9,
            "{}",
            solution.residual
        );
        let layout = Layout::new(&chart, &topo, None).unwrap();
        let least = layout.solve(&chart, &solution.angles).unwrap();
        let laid = layout.propagate(&chart, &topo, &solution.angles);
        let edge = (least[chart.triangles[0][1] as usize] - least[chart.triangles[0][0] as usize])
            .length();
        let worst = least
            .iter()
            .zip(&laid)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6 * edge, "{worst} against an edge of {edge}");
    }
}
