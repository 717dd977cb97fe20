//! The fields that orient and layer lapped solid textures (seed 000, sec.
//! 5.2.2): the depth field, a thin-plate radial basis function in 3D
//! (Turk and O'Brien 1999), and vector and scale fields interpolated over
//! the tet mesh's vertices by Laplacian smoothing with point constraints
//! (eq. 1-2, solved in the least-squares sense).

use glam::{DMat3, DVec3};

use super::locate::Locator;
use crate::error::{Error, Result};
use crate::linalg::SpdPattern;
use crate::tetra::TetMesh;

/// At most this many constraint points enter the RBF's dense system; more
/// are thinned to an even spread (a 1000 x 1000 solve takes a fraction of a
/// second; with 200 per facet the uterine cavity's depth wandered off 1
/// between them, turning the frames of the tets along it).
pub const MAX_DEPTH_CONSTRAINTS: usize = 1000;

/// `d(p) = sum_i w_i |p - c_i|^3 + a . (1, p)`: the 3D thin-plate
/// (biharmonic) interpolant through depth values at points (Turk and
/// O'Brien 1999, sec. 3), 0 at the outer region and 1 at the inner one.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthField {
    centres: Vec<DVec3>,
    weights: Vec<f64>,
    affine: [f64; 4],
}

impl DepthField {
    /// The interpolant through depth 0 at `outer` and 1 at `inner`. Errors
    /// when either is empty, or when they share a point (the depth would
    /// be both).
    pub fn fit(outer: &[DVec3], inner: &[DVec3]) -> Result<DepthField> {
        if outer.is_empty() || inner.is_empty() {
            return Err(Error::invalid(format!(
                "the depth field needs points at depth 0 and at depth 1 (got {} and {})",
                outer.len(),
                inner.len()
            )));
        }
        let thin = thin_evenly;
        let half = MAX_DEPTH_CONSTRAINTS / 2;
        let (outer, inner) = (thin(outer, half), thin(inner, half));
        let scale = outer
            .iter()
            .chain(&inner)
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let size = scale.0.distance(scale.1).max(1e-300);
        for o in &outer {
            if inner.iter().any(|i| i.distance(*o) <= 1e-9 * size) {
                return Err(Error::invalid(format!(
                    "the depth field's outer and inner regions meet at {o}: give them apart"
                )));
            }
        }
        let centres: Vec<DVec3> = outer.iter().chain(&inner).copied().collect();
        let values: Vec<f64> = (0..centres.len())
            .map(|i| if i < outer.len() { 0.0 } else { 1.0 })
            .collect();
        let n = centres.len();
        // [Phi P; P^T 0] [w; a] = [v; 0].
        let m = n + 4;
        let mut a = faer::Mat::<f64>::zeros(m, m);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = centres[i].distance(centres[j]).powi(3);
            }
            let row = [1.0, centres[i].x, centres[i].y, centres[i].z];
            for (k, &x) in row.iter().enumerate() {
                a[(i, n + k)] = x;
                a[(n + k, i)] = x;
            }
        }
        let mut b = faer::Mat::<f64>::zeros(m, 1);
        for (i, &v) in values.iter().enumerate() {
            b[(i, 0)] = v;
        }
        faer::set_global_parallelism(faer::Par::Seq);
        use faer::linalg::solvers::Solve;
        let x = a.as_ref().partial_piv_lu().solve(b.as_ref());
        let weights: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
        let affine = [x[(n, 0)], x[(n + 1, 0)], x[(n + 2, 0)], x[(n + 3, 0)]];
        if !weights.iter().chain(&affine).all(|w| w.is_finite()) {
            return Err(Error::invalid(
                "the depth constraints are degenerate (all on one line?): no depth field fits them",
            ));
        }
        Ok(DepthField {
            centres,
            weights,
            affine,
        })
    }

    /// The depth at `p` (not clamped: it may leave [0, 1] slightly between
    /// the constraints).
    pub fn value(&self, p: DVec3) -> f64 {
        let [a0, ax, ay, az] = self.affine;
        let mut d = a0 + ax * p.x + ay * p.y + az * p.z;
        for (c, w) in self.centres.iter().zip(&self.weights) {
            d += w * c.distance(p).powi(3);
        }
        d
    }

    /// The depth's gradient at `p`: `3 |p - c| (p - c)` per centre.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let [_, ax, ay, az] = self.affine;
        let mut g = DVec3::new(ax, ay, az);
        for (c, w) in self.centres.iter().zip(&self.weights) {
            let d = p - *c;
            g += *w * 3.0 * d.length() * d;
        }
        g
    }

    /// An upper bound of `|gradient(p)|` over the box `lo..hi`: the affine
    /// part plus each centre's term at its farthest corner of the box.
    pub fn gradient_bound(&self, lo: DVec3, hi: DVec3) -> f64 {
        let [_, ax, ay, az] = self.affine;
        let far = |c: DVec3| (c - lo).abs().max((c - hi).abs()).length_squared();
        DVec3::new(ax, ay, az).length()
            + self
                .centres
                .iter()
                .zip(&self.weights)
                .map(|(c, w)| w.abs() * 3.0 * far(*c))
                .sum::<f64>()
    }
}

/// At most `n` of `points`, spread evenly: the point nearest each occupied
/// cell's centre of a grid whose cell is grown until at most `n` cells are
/// occupied, in cell order.
pub fn thin_evenly(points: &[DVec3], n: usize) -> Vec<DVec3> {
    if points.len() <= n {
        return points.to_vec();
    }
    let (lo, hi) = points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let diag = lo.distance(hi).max(1e-300);
    let mut cell = diag / (n as f64).sqrt();
    loop {
        let mut cells: std::collections::BTreeMap<[i64; 3], (f64, DVec3)> = Default::default();
        for &p in points {
            let q = (p - lo) / cell;
            let key = [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64];
            let centre =
                lo + (DVec3::new(key[0] as f64, key[1] as f64, key[2] as f64) + 0.5) * cell;
            let d = p.distance_squared(centre);
            let e = cells.entry(key).or_insert((f64::INFINITY, p));
            if d < e.0 {
                *e = (d, p);
            }
        }
        if cells.len() <= n {
            return cells.into_values().map(|(_, p)| p).collect();
        }
        cell *= 1.25;
    }
}

/// A value wanted inside the mesh (eq. 2): a tet, the point's barycentric
/// coordinates in it, the value's components.
pub type Constraint = (usize, [f64; 4], Vec<f64>);

/// A least-squares row: (column, coefficient) pairs and a target per
/// component.
type Row = (Vec<(u32, f64)>, Vec<f64>);

/// Laplacian smoothing (eq. 1-2): per vertex the value closest, in least
/// squares, to the weighted mean of its neighbours' while the constraints
/// hold (each `tet`'s barycentric combination equal to its value), for
/// `components` numbers per vertex. `weight(i, j)` gives `w_ij` before
/// normalisation over `j` (1 for the paper's uniform weights). One sparse
/// factorisation serves every component.
pub fn laplacian_smooth(
    mesh: &TetMesh,
    neighbours: &[Vec<u32>],
    weight: &dyn Fn(usize, usize) -> f64,
    constraints: &[Constraint],
    components: usize,
) -> Result<Vec<Vec<f64>>> {
    let n = mesh.num_vertices();
    if constraints.is_empty() {
        return Err(Error::invalid(
            "Laplacian smoothing needs at least one constraint",
        ));
    }
    // Rows of the least-squares system: (columns, coefficients), rhs.
    let mut rows: Vec<Row> = Vec::with_capacity(n + constraints.len());
    for (i, ring) in neighbours.iter().enumerate() {
        let ws: Vec<f64> = ring.iter().map(|&j| weight(i, j as usize)).collect();
        let total: f64 = ws.iter().sum();
        let mut row = vec![(i as u32, 1.0)];
        if total > 0.0 {
            row.extend(ring.iter().zip(&ws).map(|(&j, &w)| (j, -w / total)));
        }
        rows.push((row, vec![0.0; components]));
    }
    for (t, bary, value) in constraints {
        let tet = mesh.tets[*t];
        let row = (0..4).map(|k| (tet[k], bary[k])).collect();
        rows.push((row, value.clone()));
    }
    // Normal equations A^T A x = A^T b, lower triangle.
    let mut entries: Vec<((u32, u32), f64)> = Vec::new();
    let mut rhs = vec![vec![0.0; n]; components];
    for (row, b) in &rows {
        for &(ci, vi) in row {
            for &(cj, vj) in row {
                if ci >= cj {
                    entries.push(((ci, cj), vi * vj));
                }
            }
            for (c, &bc) in b.iter().enumerate() {
                rhs[c][ci as usize] += vi * bc;
            }
        }
    }
    let positions: Vec<(u32, u32)> = entries.iter().map(|e| e.0).collect();
    let values: Vec<f64> = entries.iter().map(|e| e.1).collect();
    let pattern = SpdPattern::new(n, &positions)?;
    let chol = pattern.factor(&values).map_err(|_| {
        Error::invalid(
            "the smoothing system is singular: a part of the tet mesh holds no constraint \
             (draw a stroke or give a value in every separate piece)",
        )
    })?;
    for r in &mut rhs {
        chol.solve(r);
    }
    Ok(rhs)
}

/// Each vertex's neighbours along tet edges, sorted.
pub fn vertex_neighbours(mesh: &TetMesh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); mesh.num_vertices()];
    for t in &mesh.tets {
        for i in 0..4 {
            for j in 0..4 {
                if i != j {
                    out[t[i] as usize].push(t[j]);
                }
            }
        }
    }
    for ring in &mut out {
        ring.sort_unstable();
        ring.dedup();
    }
    out
}

/// Point constraints from polylines: a direction constraint every
/// `spacing` along each stroke, the stroke's unit direction there. Errors
/// name the stroke and point outside the mesh.
pub fn stroke_constraints(
    strokes: &[Vec<DVec3>],
    spacing: f64,
    mesh: &TetMesh,
    locator: &Locator,
) -> Result<Vec<Constraint>> {
    let mut out = Vec::new();
    for (s, stroke) in strokes.iter().enumerate() {
        if stroke.len() < 2 {
            return Err(Error::invalid(format!(
                "stroke {s} has {} point(s): a stroke needs two or more",
                stroke.len()
            )));
        }
        for (k, seg) in stroke.windows(2).enumerate() {
            let d = seg[1] - seg[0];
            let len = d.length();
            if !(len > 0.0 && len.is_finite()) {
                continue;
            }
            let steps = ((len / spacing).ceil() as usize).max(1);
            for i in 0..steps {
                let p = seg[0] + d * ((i as f64 + 0.5) / steps as f64);
                let (t, bary) = locator.locate(mesh, p).ok_or_else(|| {
                    Error::invalid(format!(
                        "stroke {s}, segment {k}: the point {p} lies outside the mesh"
                    ))
                })?;
                out.push((t, bary, (d / len).to_array().to_vec()));
            }
        }
    }
    Ok(out)
}

/// Orthonormal frame from a primary direction and a secondary one (made
/// orthogonal to it), the third their cross product; columns (primary,
/// secondary, third). Falls back to any perpendicular when the secondary
/// is parallel.
pub fn frame(primary: DVec3, secondary: DVec3) -> DMat3 {
    let a = primary.normalize_or(DVec3::X);
    let mut b = secondary - a * a.dot(secondary);
    if b.length_squared() < 1e-20 {
        b = a.any_orthonormal_vector();
    }
    let b = b.normalize();
    DMat3::from_cols(a, b, a.cross(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_depth_field_interpolates_and_its_gradient_matches_differences() {
        // Depth 0 on a sphere of radius 1, 1 on a small inner one.
        let sphere = |r: f64, n: usize| -> Vec<DVec3> {
            (0..n)
                .map(|i| {
                    let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                    let phi = i as f64 * 2.399963;
                    let s = (1.0 - z * z).sqrt();
                    DVec3::new(s * phi.cos(), s * phi.sin(), z) * r
                })
                .collect()
        };
        let (outer, inner) = (sphere(1.0, 150), sphere(0.2, 40));
        let f = DepthField::fit(&outer, &inner).expect("fit");
        for p in outer.iter().take(20) {
            assert!(f.value(*p).abs() < 1e-6, "{}", f.value(*p));
        }
        for p in inner.iter().take(20) {
            assert!((f.value(*p) - 1.0).abs() < 1e-6);
        }
        let p = DVec3::new(0.3, -0.2, 0.4);
        let e = 1e-6;
        let fd = DVec3::new(
            f.value(p + DVec3::X * e) - f.value(p - DVec3::X * e),
            f.value(p + DVec3::Y * e) - f.value(p - DVec3::Y * e),
            f.value(p + DVec3::Z * e) - f.value(p - DVec3::Z * e),
        ) / (2.0 * e);
        assert!((fd - f.gradient(p)).length() < 1e-5 * fd.length().max(1.0));
        // Depth grows inwards.
        assert!(
            f.value(DVec3::new(0.6, 0.0, 0.0)) > 0.0 && f.value(DVec3::new(0.6, 0.0, 0.0)) < 1.0
        );
        assert!(DepthField::fit(&outer, &[]).is_err());
        assert!(DepthField::fit(&outer, &outer[..3]).is_err());
    }
}
