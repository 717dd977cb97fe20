//! The generalized winding number of a triangle soup (Jacobson, Kavan and
//! Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized
//! Winding Numbers", SIGGRAPH 2013): the signed solid angle the triangles
//! subtend at a point, over 4 pi. It is 1 inside and 0 outside a closed,
//! outward-oriented surface, and degrades gracefully where the surface is
//! not closed: a small hole leaves the inside near 1, self-intersections
//! and duplicated shells only raise it (2 where two shells overlap). Inside
//! is `w > 1/2`.
//!
//! Fast evaluation (Barill, Dickson, Schmidt, Levin and Jacobson, "Fast
//! Winding Numbers for Soups and Clouds", SIGGRAPH 2018, sec. 3.2): a BVH
//! node whose ball (centre `c`, radius `r`) is farther than `BETA * r` from
//! the query point counts as a far field, its area-weighted normal sum `N`
//! seen from `q`, `N . (c - q) / |c - q|^3`, plus the expansion's next two
//! terms; nearer nodes are opened, and leaves are summed exactly. The
//! dipole term alone is off by up to 3.5e-2 on the bunny at BETA = 2; with
//! the paper's second-order expansion the error is 2.2e-3 (tested below to
//! stay under 1e-2).

use glam::DVec3;

use rayon::prelude::*;

use crate::mesh::TriMesh;
use crate::mesh::bvh::Bvh;

/// Far-field acceptance ratio: a node is one dipole when the query is
/// farther than `BETA` times its radius (Barill et al. 2018 use 2).
pub const BETA: f64 = 2.0;

/// The winding number of one triangle mesh, ready for many queries.
#[derive(Clone, Debug)]
pub struct Winding {
    pub(crate) bvh: Bvh,
    /// Whether every edge is crossed as often one way as the other (a
    /// closed surface, self-intersecting or not): then the winding number
    /// is an integer off the surface, the same all over any ball the
    /// surface does not enter (`Winding::closed`).
    closed: bool,
}

impl Winding {
    /// Index every face of `mesh` (degenerate ones contribute nothing).
    pub fn new(mesh: &TriMesh) -> Winding {
        let tris = (0..mesh.num_faces()).map(|f| mesh.corners(f)).collect();
        Winding {
            bvh: Bvh::new(tris),
            closed: balanced_edges(mesh),
        }
    }

    /// Whether the surface is closed (see the field): a point farther from
    /// every triangle than from a point whose winding number is known has
    /// the same one, which spares most queries away from the surface.
    pub fn closed(&self) -> bool {
        self.closed
    }

    /// The winding number at `q` with the far-field approximation.
    pub fn at(&self, q: DVec3) -> f64 {
        let nodes = &self.bvh.nodes;
        if nodes.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let i = stack[top] as usize;
            let node = &nodes[i];
            let d = node.center - q;
            let dist2 = d.length_squared();
            if dist2 > BETA * BETA * node.radius * node.radius {
                sum += far_field(node, d, dist2);
            } else if node.count > 0 {
                let first = node.index as usize;
                for t in &self.bvh.tris[first..first + node.count as usize] {
                    sum += solid_angle(q, t);
                }
            } else {
                stack[top] = node.index;
                stack[top + 1] = i as u32 + 1;
                top += 2;
            }
        }
        sum / (4.0 * std::f64::consts::PI)
    }

    /// The winding number at `q` summed over every triangle (slow; the
    /// reference `at` is tested against).
    pub fn exact(&self, q: DVec3) -> f64 {
        self.bvh.tris.iter().map(|t| solid_angle(q, t)).sum::<f64>() / (4.0 * std::f64::consts::PI)
    }

    /// Whether `q` is inside: winding number above 1/2.
    pub fn inside(&self, q: DVec3) -> bool {
        self.at(q) > 0.5
    }
}

/// The sign of `f = 1/2 - w`: -1 inside, 1 outside, 0 on the surface.
#[inline]
pub(crate) fn sign_of(w: f64) -> i8 {
    if w > 0.5 {
        -1
    } else if w < 0.5 {
        1
    } else {
        0
    }
}

/// Signs of `f` on a grid `COARSE` lattice edges apart, each with its
/// clearance (its distance from the surface, up to the grid's spacing),
/// for a closed surface: its winding number is the same all over a ball
/// the surface does not enter, so a lattice vertex nearer a grid point
/// than that point's clearance takes the point's sign without a query of
/// its own. Most of the lattice lies well away from the surface, where a
/// winding number costs a walk of the far field and a distance query
/// stops at once; the signs are exactly those the queries give (the
/// far field's error, under 1e-2, cannot move an integer past 1/2).
pub(crate) struct CoarseSigns {
    origin: DVec3,
    step: f64,
    dims: [usize; 3],
    /// Per grid point, x fastest: its sign and clearance.
    points: Vec<(i8, f64)>,
}

/// `sign_of` the winding number at the points `point(k)` (k from 0 to
/// `out.len() - 1`, evenly spaced on a line, both ends outside the box of
/// a closed surface: `Winding::closed`), from one pass of the line through
/// its triangles: there the winding number is the signed count of the
/// crossings ahead (scan conversion: one query per row of points instead
/// of one per point). A row whose line passes within its rounding of an
/// edge or grazes a face, a row whose ends are not outside the box, and a
/// point within its rounding of a crossing take `Winding::at` instead, so
/// the signs are the ones it gives. Whether the crossings served (any
/// point of the row).
pub(crate) fn signs_along(
    winding: &Winding,
    point: impl Fn(usize) -> DVec3,
    out: &mut [i8],
    crossings: &mut Vec<(f64, i8, f64)>,
) -> bool {
    debug_assert!(winding.closed);
    let by_points = |out: &mut [i8]| {
        for (k, s) in out.iter_mut().enumerate() {
            *s = sign_of(winding.at(point(k)));
        }
        false
    };
    if out.len() < 2 {
        return by_points(out);
    }
    let (a, b) = (point(0), point(out.len() - 1));
    let (lo, hi) = winding.bvh.bounds();
    let outside = |p: DVec3| !(p.cmpge(lo) & p.cmple(hi)).all();
    if !outside(a) || !outside(b) || winding.bvh.signed_crossings(a, b, crossings).is_none() {
        return by_points(out);
    }
    crossings.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    // From the far end (winding number 0) back: each crossing passed adds
    // its sign.
    let last = (out.len() - 1) as f64;
    let mut w = 0i32;
    let mut next = crossings.len();
    for k in (0..out.len()).rev() {
        let at = k as f64 / last;
        while next > 0 && crossings[next - 1].0 > at {
            next -= 1;
            w += crossings[next].1 as i32;
        }
        let near =
            |c: Option<&(f64, i8, f64)>| c.is_some_and(|c| (c.0 - at).abs() <= c.2 + 1e-9 / last);
        out[k] = if near(crossings.get(next)) || next > 0 && near(crossings.get(next - 1)) {
            sign_of(winding.at(point(k)))
        } else if w >= 1 {
            -1
        } else {
            1
        };
    }
    true
}

/// Lattice edges between grid points of `CoarseSigns`: at 4, a grid point
/// stands for the 64 or so lattice vertices around it.
const COARSE: f64 = 4.0;

impl CoarseSigns {
    /// The grid over the surface's box grown by a few lattice edges (the
    /// lattice's margin; vertices past the grid take a query each).
    pub(crate) fn new(winding: &Winding, h: f64) -> CoarseSigns {
        let step = COARSE * h;
        let (lo, hi) = winding.bvh.bounds();
        let origin = lo - DVec3::splat(step);
        let dims = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / step).ceil() as usize + 3);
        let points = (0..dims[0] * dims[1] * dims[2])
            .into_par_iter()
            .map(|i| {
                let k = [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])];
                let g = origin + step * DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64);
                let s = sign_of(winding.at(g));
                // Only clearances up to the farthest a vertex can lie from
                // its nearest grid point (under a step) matter.
                let clearance = if s == 0 {
                    0.0
                } else {
                    winding.bvh.distance_below(g, step)
                };
                (s, clearance)
            })
            .collect();
        CoarseSigns {
            origin,
            step,
            dims,
            points,
        }
    }

    /// The sign at `p` from its nearest grid point, where `p` lies inside
    /// that point's clearance.
    #[inline]
    pub(crate) fn sign_at(&self, p: DVec3) -> Option<i8> {
        let u = ((p - self.origin) / self.step).round();
        let mut k = [0usize; 3];
        for a in 0..3 {
            if !(u[a] >= 0.0 && u[a] < self.dims[a] as f64) {
                return None;
            }
            k[a] = u[a] as usize;
        }
        let (s, clearance) = self.points[k[0] + self.dims[0] * (k[1] + self.dims[1] * k[2])];
        let g = self.origin + self.step * u;
        // Strictly inside, by a hair for the distances' rounding.
        (s != 0 && p.distance(g) < clearance * (1.0 - 1e-9)).then_some(s)
    }
}

/// Whether each undirected edge of `mesh` is used by as many faces in one
/// direction as in the other: the faces then form a cycle with no boundary,
/// whose winding number is an integer everywhere off it.
fn balanced_edges(mesh: &TriMesh) -> bool {
    // Sorted keys rather than a hash map: one pass, no hashing of 3F edges.
    let mut edges: Vec<(u64, i32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|(a, b)| a != b)
        .map(|(a, b)| {
            let key = (a.min(b) as u64) << 32 | a.max(b) as u64;
            (key, if a < b { 1 } else { -1 })
        })
        .collect();
    edges.sort_unstable_by_key(|e| e.0);
    edges
        .chunk_by(|x, y| x.0 == y.0)
        .all(|run| run.iter().map(|e| e.1).sum::<i32>() == 0)
}

/// A node's solid angle seen from `q`, `r = center - q`: the expansion of
/// `n . (x - q) / |x - q|^3` about the centre to second order (Barill et
/// al. 2018, eq. 11): with `g(r) = r / |r|^3`, `J` its Jacobian and `H` its
/// Hessian, `N . g + tr(J M) + 1/2 sum_i H_i : C_i` (`M`, `C` the node's
/// first and second moments, see `Node`).
#[inline]
pub(crate) fn far_field(node: &crate::mesh::bvh::Node, r: DVec3, dist2: f64) -> f64 {
    let inv3 = 1.0 / (dist2 * dist2.sqrt());
    let inv5 = inv3 / dist2;
    let inv7 = inv5 / dist2;
    let m = &node.moment;
    let first = node.area_normal.dot(r) * inv3;
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    let second = trace * inv3 - 3.0 * r.dot(*m * r) * inv5;
    // H_ijk = -3 (d_ij r_k + d_ik r_j + d_jk r_i) / |r|^5 + 15 r_i r_j r_k / |r|^7.
    let mut diag = 0.0; // sum_i (C_i r)_i, counted twice by symmetry in j, k
    let mut traced = 0.0; // sum_i r_i tr(C_i)
    let mut cubic = 0.0; // sum_i r_i r^T C_i r
    for (i, c) in node.second.iter().enumerate() {
        let cr = *c * r;
        diag += cr[i];
        traced += r[i] * (c.x_axis.x + c.y_axis.y + c.z_axis.z);
        cubic += r[i] * r.dot(cr);
    }
    let third = 0.5 * (-3.0 * (2.0 * diag + traced) * inv5 + 15.0 * cubic * inv7);
    first + second + third
}

/// Signed solid angle of triangle `t` seen from `q` (Van Oosterom and
/// Strackee 1983): `tan(Omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| +
/// (b.c)|a| + (c.a)|b|)` with `a, b, c` the corners relative to `q`.
/// Positive when `q` is behind the triangle (on the side its normal points
/// away from), so a closed outward mesh sums to 4 pi inside.
#[inline]
pub fn solid_angle(q: DVec3, t: &[DVec3; 3]) -> f64 {
    let a = t[0] - q;
    let b = t[1] - q;
    let c = t[2] - q;
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    if num == 0.0 {
        // In the triangle's plane: 0 outside the triangle, undefined on it
        // (+-2 pi); 0 puts points on the surface at w = 1/2.
        return 0.0;
    }
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;
    use crate::mesh::shapes::icosphere;
    use glam::DMat3;

    fn unit(seed: u64, i: u64, k: u64) -> f64 {
        crate::rng::unit(seed, &[i, k])
    }

    #[test]
    fn fast_matches_exact_on_the_bunny() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.obj");
        let mesh = crate::mesh::io::read(&path).expect("bunny");
        let winding = Winding::new(&mesh);
        let (lo, hi) = mesh.bounding_box().expect("vertices");
        let pad = 0.2 * (hi - lo);
        let mut worst: f64 = 0.0;
        for i in 0..400 {
            let u = DVec3::new(unit(1, i, 0), unit(1, i, 1), unit(1, i, 2));
            let q = lo - pad + u * (hi - lo + 2.0 * pad);
            worst = worst.max((winding.at(q) - winding.exact(q)).abs());
        }
        // Points close to the surface as well: vertices pushed off it.
        for i in 0..200u64 {
            let v = mesh.positions[(i as usize * 997) % mesh.num_vertices()];
            let q = v + (unit(2, i, 0) - 0.5) * 1e-3 * (hi - lo);
            worst = worst.max((winding.at(q) - winding.exact(q)).abs());
        }
        assert!(worst < 1e-2, "largest difference {worst}");
    }

    #[test]
    fn sphere_inside_is_one_and_outside_zero() {
        let winding = Winding::new(&icosphere(3));
        for i in 0..100 {
            let dir = DVec3::new(
                unit(3, i, 0) - 0.5,
                unit(3, i, 1) - 0.5,
                unit(3, i, 2) - 0.5,
            )
            .normalize();
            let inner = winding.at(dir * 0.9 * unit(3, i, 3));
            let outer = winding.at(dir * (1.1 + 3.0 * unit(3, i, 4)));
            assert!((inner - 1.0).abs() < 1e-2, "inside {inner}");
            assert!(outer.abs() < 1e-2, "outside {outer}");
            assert!(winding.inside(dir * 0.5) && !winding.inside(dir * 1.5));
        }
    }

    #[test]
    fn a_small_hole_does_not_leak() {
        let mut sphere = icosphere(3);
        // Remove the faces around the top: a hole about 0.2 wide.
        sphere.triangles.retain(|t| {
            let c = t
                .iter()
                .map(|&v| sphere.positions[v as usize])
                .sum::<DVec3>()
                / 3.0;
            c.z < 0.98
        });
        let winding = Winding::new(&sphere);
        for i in 0..100 {
            let q = DVec3::new(
                unit(4, i, 0) - 0.5,
                unit(4, i, 1) - 0.5,
                unit(4, i, 2) - 0.5,
            ) * 0.8;
            let w = winding.at(q);
            assert!(w > 0.9, "inside point {q} has w = {w}");
        }
        assert!(winding.at(DVec3::new(0.0, 0.0, 1.5)) < 0.5);
    }

    /// The signs from one line per row of points (rows along x, h apart,
    /// ends a cell outside the surface's box, as the stuffing lattice's)
    /// are the winding numbers' signs at every point, and most rows take
    /// them from the line: on a sphere, a torus, two spheres overlapping
    /// (winding number 2 inside both), a cube whose faces and edges lie on
    /// lattice rows (crossings there not clean: those rows take the
    /// winding number point by point), and the cube turned 1e-8 radians
    /// about z, its faces grazing the rows.
    #[test]
    fn signs_by_rows_are_the_winding_numbers_signs() {
        use crate::mesh::shapes::{icosphere, torus};
        let moved = |mut m: TriMesh, f: &dyn Fn(DVec3) -> DVec3| {
            for p in &mut m.positions {
                *p = f(*p);
            }
            m
        };
        let mut spheres = icosphere(3);
        let other = moved(icosphere(3), &|p| p + DVec3::new(0.7, 0.2, 0.1));
        let base = spheres.positions.len() as u32;
        spheres.positions.extend(&other.positions);
        spheres
            .triangles
            .extend(other.triangles.iter().map(|f| f.map(|v| v + base)));
        let corners: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64) - 0.5)
            .collect();
        let cube = TriMesh {
            positions: corners,
            triangles: vec![
                [0, 2, 1],
                [1, 2, 3],
                [4, 5, 6],
                [5, 7, 6],
                [0, 1, 4],
                [1, 5, 4],
                [2, 6, 3],
                [3, 6, 7],
                [0, 4, 2],
                [2, 4, 6],
                [1, 3, 5],
                [3, 7, 5],
            ],
            facets: None,
            uvs: None,
        };
        let turn = DMat3::from_rotation_z(1e-8);
        let turned = moved(cube.clone(), &|p| turn * p);
        // The least share of rows whose line serves: the cubes' rows in
        // their faces' planes, or grazing them, do not.
        for (name, mesh, h, least) in [
            ("sphere", icosphere(3), 0.07, 0.9),
            ("torus", torus(1.0, 0.3, 40, 16), 0.05, 0.9),
            ("two spheres", spheres, 0.06, 0.9),
            ("cube", cube, 0.125, 0.5),
            ("turned cube", turned, 0.125, 0.5),
        ] {
            let winding = Winding::new(&mesh);
            assert!(winding.closed(), "{name}");
            let (lo, hi) = winding.bvh.bounds();
            let cells = ((hi - lo) / h).ceil().as_uvec3() + 2;
            let corner = (lo + hi) / 2.0 - cells.as_dvec3() * h / 2.0;
            let mut crossings = Vec::new();
            let (mut inside, mut rows, mut by_lines) = (0, 0, 0);
            // The corners' rows, then the cube centres' (the BCC lattice's).
            let corners = (0..=cells.y).flat_map(|j| (0..=cells.z).map(move |k| (j, k, 0.0)));
            let centres = (0..cells.y).flat_map(|j| (0..cells.z).map(move |k| (j, k, 0.5)));
            for (j, k, half) in corners.chain(centres) {
                let len = cells.x as usize + 1 - (half > 0.0) as usize;
                let at = |i: usize| corner + (DVec3::new(i as f64, j as f64, k as f64) + half) * h;
                let mut by_rows = vec![0i8; len];
                rows += 1;
                by_lines += signs_along(&winding, at, &mut by_rows, &mut crossings) as usize;
                for (i, s) in by_rows.iter().enumerate() {
                    assert_eq!(*s, sign_of(winding.at(at(i))), "{name}: at {}", at(i));
                    inside += (*s == -1) as usize;
                }
            }
            println!("{name}: {by_lines} of {rows} rows by their line, {inside} vertices inside");
            assert!(inside > 100, "{name}: {inside} vertices inside");
            assert!(
                by_lines as f64 >= least * rows as f64,
                "{name}: {by_lines} of {rows} rows by their line"
            );
        }
    }
}
