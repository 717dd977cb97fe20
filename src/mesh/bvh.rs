//! A bounding volume hierarchy over triangles, shared by the three queries
//! the tet mesher asks of a surface: the generalized winding number (each
//! node carries the first-order far-field data of Barill et al. 2018, sec.
//! 3.2), segment crossings (cut points) and the distance to the closest
//! triangle (Hausdorff distances); the last also by the segmentation's fit
//! to its voxels (`for_distances`, without the moments, and `refit`).
//!
//! Invariants: `tris` holds the triangles in leaf order, each leaf a
//! contiguous range of at most `LEAF` of them; an internal node's left child
//! follows it directly, its right child is at `right`. Written here rather
//! than taken from a crate: the winding number needs its own per-node
//! moments, which no BVH crate carries.

use glam::{DMat3, DVec3};

use super::TriMesh;
use super::closest::closest_point;

/// Triangles per leaf.
const LEAF: usize = 4;

#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub lo: DVec3,
    pub hi: DVec3,
    /// Leaf: first triangle; internal: index of the right child.
    pub index: u32,
    /// Triangles in a leaf, 0 for an internal node.
    pub count: u32,
    /// Sum of the triangles' area vectors (area times unit normal).
    pub area_normal: DVec3,
    /// Area-weighted centroid of the triangles.
    pub center: DVec3,
    /// Radius of the ball about `center` holding all the triangles.
    pub radius: f64,
    /// Total area of the triangles.
    pub area: f64,
    /// First moment of the normals about `center`: the sum over triangles
    /// of area (centroid - center) normal^T (Barill et al. 2018, eq. 11's
    /// second term).
    pub moment: DMat3,
    /// Second moments, one per normal component `i`: the sum over triangles
    /// of `n_i` times the triangle's `integral (x - center)(x - center)^T dA`
    /// (with `n` the area normal), for the expansion's third term.
    pub second: [DMat3; 3],
}

#[derive(Clone, Debug)]
pub(crate) struct Bvh {
    pub nodes: Vec<Node>,
    pub tris: Vec<[DVec3; 3]>,
    /// The index each of `tris` had in the list the tree was built from.
    pub order: Vec<u32>,
}

impl Bvh {
    /// Build over `tris` (their order is not kept).
    pub fn new(tris: Vec<[DVec3; 3]>) -> Bvh {
        let mut bvh = Bvh::for_distances(tris);
        for i in (0..bvh.nodes.len()).rev() {
            bvh.fill_moments(i);
        }
        bvh
    }

    /// `new` without the winding number's moments, for the distance
    /// queries alone: `refit` moves the boxes and would leave moments
    /// stale.
    pub fn for_distances(tris: Vec<[DVec3; 3]>) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * tris.len() / LEAF + 1),
            tris,
            order: Vec::new(),
        };
        if !bvh.tris.is_empty() {
            let n = bvh.tris.len();
            let mut centroids: Vec<DVec3> = bvh
                .tris
                .iter()
                .map(|t| (t[0] + t[1] + t[2]) / 3.0)
                .collect();
            let mut order: Vec<u32> = (0..n as u32).collect();
            bvh.build(&mut order, &mut centroids, 0);
            bvh.tris = order.iter().map(|&i| bvh.tris[i as usize]).collect();
            bvh.order = order;
        }
        bvh
    }

    /// `for_distances` over `mesh`'s faces, in order: a face's index in
    /// the mesh is the one the queries give.
    pub fn over_faces(mesh: &TriMesh) -> Bvh {
        Bvh::for_distances((0..mesh.num_faces()).map(|f| mesh.corners(f)).collect())
    }

    /// The same tree over the same triangles moved (`for_distances`'s:
    /// the moments are not kept up): each taken again by the index it was
    /// built from, the boxes recomputed. Cheaper than building anew, and
    /// as good while the triangles move little against their size.
    pub fn refit(&mut self, corners: impl Fn(u32) -> [DVec3; 3]) {
        for (t, &i) in self.tris.iter_mut().zip(&self.order) {
            *t = corners(i);
        }
        // Children have larger indices than their parents.
        for i in (0..self.nodes.len()).rev() {
            let node = &self.nodes[i];
            let (lo, hi) = if node.count > 0 {
                let first = node.index as usize;
                self.tris[first..first + node.count as usize]
                    .iter()
                    .flatten()
                    .fold(
                        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                        |(lo, hi), &p| (lo.min(p), hi.max(p)),
                    )
            } else {
                let (l, r) = (&self.nodes[i + 1], &self.nodes[node.index as usize]);
                (l.lo.min(r.lo), l.hi.max(r.hi))
            };
            self.nodes[i].lo = lo;
            self.nodes[i].hi = hi;
        }
    }

    /// Recursive median split on the longest axis of the centroids' box.
    /// `order[..]` and `centroids[..]` are this node's slice; `first` is its
    /// offset in the whole array. Returns the node's index.
    fn build(&mut self, order: &mut [u32], centroids: &mut [DVec3], first: usize) -> usize {
        let me = self.nodes.len();
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &t in order.iter() {
            for p in self.tris[t as usize] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        self.nodes.push(Node {
            lo,
            hi,
            index: first as u32,
            count: order.len() as u32,
            area_normal: DVec3::ZERO,
            center: DVec3::ZERO,
            radius: 0.0,
            area: 0.0,
            moment: DMat3::ZERO,
            second: [DMat3::ZERO; 3],
        });
        if order.len() <= LEAF {
            return me;
        }
        let (mut clo, mut chi) = (centroids[0], centroids[0]);
        for &c in centroids.iter() {
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        // Split the pairs (centroid, triangle) at the median along the
        // axis, ties by triangle (a total order, so the build is
        // deterministic); a half that will be a leaf is sorted, so each
        // leaf is in the order a full sort at every level gave (n log n
        // overall against that sort's n log^2 n: a fifth of the time on
        // the MNI brain's 260k faces, the same tree).
        let mut pairs: Vec<(DVec3, u32)> = centroids
            .iter()
            .copied()
            .zip(order.iter().copied())
            .collect();
        let by_axis = |a: &(DVec3, u32), b: &(DVec3, u32)| {
            a.0[axis].total_cmp(&b.0[axis]).then(a.1.cmp(&b.1))
        };
        let mid = order.len() / 2;
        pairs.select_nth_unstable_by(mid, by_axis);
        let (lo_p, hi_p) = pairs.split_at_mut(mid);
        for half in [lo_p, hi_p] {
            if half.len() <= LEAF {
                half.sort_unstable_by(by_axis);
            }
        }
        for (k, (c, t)) in pairs.into_iter().enumerate() {
            centroids[k] = c;
            order[k] = t;
        }
        let (lo_o, hi_o) = order.split_at_mut(mid);
        let (lo_c, hi_c) = centroids.split_at_mut(mid);
        self.build(lo_o, lo_c, first);
        let right = self.build(hi_o, hi_c, first + mid);
        self.nodes[me].index = right as u32;
        self.nodes[me].count = 0;
        me
    }

    /// Area vector, centroid, radius and area of node `i` (called in
    /// reverse index order: children have larger indices than parents).
    fn fill_moments(&mut self, i: usize) {
        let node = &self.nodes[i];
        let (area_normal, center, radius, area, moment, second) = if node.count > 0 {
            let tris = &self.tris[node.index as usize..(node.index + node.count) as usize];
            let mut an = DVec3::ZERO;
            let mut weighted = DVec3::ZERO;
            let mut area = 0.0;
            let mut mean = DVec3::ZERO;
            for t in tris {
                let v = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
                let a = v.length();
                let c = (t[0] + t[1] + t[2]) / 3.0;
                an += v;
                weighted += a * c;
                area += a;
                mean += c;
            }
            let center = if area > 0.0 {
                weighted / area
            } else {
                mean / tris.len() as f64
            };
            let radius = tris
                .iter()
                .flat_map(|t| t.iter())
                .map(|&p| p.distance(center))
                .fold(0.0, f64::max);
            let mut moment = DMat3::ZERO;
            let mut second = [DMat3::ZERO; 3];
            for t in tris {
                let v = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
                moment += outer((t[0] + t[1] + t[2]) / 3.0 - center, v);
                // integral over the triangle of d d^T dA = A/12 (sum of
                // corner outer products + s s^T), s the corners' sum.
                let a = v.length();
                let [p, q, r] = t.map(|x| x - center);
                let s = p + q + r;
                let s2 = (outer(p, p) + outer(q, q) + outer(r, r) + outer(s, s)) * (a / 12.0);
                for (i, m) in second.iter_mut().enumerate() {
                    *m += s2 * (v[i] / a.max(f64::MIN_POSITIVE));
                }
            }
            (an, center, radius, area, moment, second)
        } else {
            let (l, r) = (&self.nodes[i + 1], &self.nodes[node.index as usize]);
            let area = l.area + r.area;
            let center = if area > 0.0 {
                (l.area * l.center + r.area * r.center) / area
            } else {
                0.5 * (l.center + r.center)
            };
            // The children's balls hold their triangles, so this ball holds
            // the union; it is never much larger than the exact one.
            let radius =
                (l.center.distance(center) + l.radius).max(r.center.distance(center) + r.radius);
            // Moments move to the new centre: d n^T about c' is d n^T
            // about c plus (c - c') N^T.
            let moment = l.moment
                + outer(l.center - center, l.area_normal)
                + r.moment
                + outer(r.center - center, r.area_normal);
            // Second moments about the new centre: with delta = c - c',
            // S' = S + delta m^T + m delta^T + A delta delta^T per triangle;
            // weighted by n_i the middle terms use the first moment's column
            // i and the last the normal sum.
            let mut second = [DMat3::ZERO; 3];
            for child in [l, r] {
                let delta = child.center - center;
                for (i, m) in second.iter_mut().enumerate() {
                    let col = child.moment.col(i);
                    *m += child.second[i]
                        + outer(delta, col)
                        + outer(col, delta)
                        + outer(delta, delta) * child.area_normal[i];
                }
            }
            (
                l.area_normal + r.area_normal,
                center,
                radius,
                area,
                moment,
                second,
            )
        };
        let node = &mut self.nodes[i];
        node.area_normal = area_normal;
        node.center = center;
        node.radius = radius;
        node.area = area;
        node.moment = moment;
        node.second = second;
    }

    /// Parameters `t` in [0, 1] at which the segment `a + t (b - a)` meets a
    /// triangle, sorted, with crossings closer than `1e-9` merged (a
    /// segment through a shared edge meets both triangles).
    pub fn segment_crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<f64>) {
        out.clear();
        let dir = b - a;
        let inv = DVec3::ONE / dir;
        let boxes = |lo, hi| segment_hits_box(a, inv, lo, hi);
        let _ = self.triangles_near_segment(boxes, |t| {
            if let Some(s) = segment_triangle(a, dir, t) {
                out.push(s);
            }
            Some(())
        });
        out.sort_unstable_by(f64::total_cmp);
        out.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
    }

    /// The crossings of the segment `a`..`b` through the triangles, each
    /// as (parameter along the segment, +1 where the triangle's normal
    /// points along the segment, -1 against it, a bound on the parameter's
    /// rounding), unsorted; `None` when one is not clean: the segment
    /// passes within its rounding (or a hair) of a triangle's edge or
    /// corner, or grazes its plane, where a crossing could be counted
    /// twice or missed.
    pub fn signed_crossings(
        &self,
        a: DVec3,
        b: DVec3,
        out: &mut Vec<(f64, i8, f64)>,
    ) -> Option<()> {
        out.clear();
        let dir = b - a;
        let boxes = |lo, hi| segment_meets_box(a, dir, lo, hi);
        self.triangles_near_segment(boxes, |t| {
            if let Some(hit) = signed_crossing(a, dir, t)? {
                out.push(hit);
            }
            Some(())
        })
    }

    /// `visit` each triangle in a leaf whose box the segment meets
    /// (`meets(lo, hi)`), until it returns `None`.
    fn triangles_near_segment(
        &self,
        meets: impl Fn(DVec3, DVec3) -> bool,
        mut visit: impl FnMut(&[DVec3; 3]) -> Option<()>,
    ) -> Option<()> {
        if self.nodes.is_empty() {
            return Some(());
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let i = stack[top];
            let node = &self.nodes[i as usize];
            if !meets(node.lo, node.hi) {
                continue;
            }
            if node.count > 0 {
                for t in &self.tris[node.index as usize..(node.index + node.count) as usize] {
                    visit(t)?;
                }
            } else {
                stack[top] = node.index;
                stack[top + 1] = i + 1;
                top += 2;
            }
        }
        Some(())
    }

    /// The box of every triangle (a point at the origin for none).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.nodes
            .first()
            .map_or((DVec3::ZERO, DVec3::ZERO), |root| (root.lo, root.hi))
    }

    /// Distance from `q` to the closest triangle (infinite for no triangle).
    pub fn distance(&self, q: DVec3) -> f64 {
        self.distance_below(q, f64::INFINITY)
    }

    /// `min(distance(q), upper)`: an upper bound known beforehand (the
    /// distance at a nearby point plus the way there) prunes the search.
    pub fn distance_below(&self, q: DVec3, upper: f64) -> f64 {
        self.distance_between(q, 0.0, upper)
    }

    /// `distance_below(q, upper)` where only a distance above `lower`
    /// matters: the search stops at the first triangle within `lower`
    /// and returns that triangle's distance (some value <= `lower`). For
    /// the largest of many distances (a Hausdorff distance), with the
    /// largest so far as `lower`.
    pub fn distance_between(&self, q: DVec3, lower: f64, upper: f64) -> f64 {
        self.nearest(q, lower, upper).0.sqrt()
    }

    /// The triangle closest to `q`, as the index it had in the list the
    /// tree was built from, and its point closest to `q`, where only one
    /// farther than `lower` matters: none if a triangle lies within
    /// `lower` (the search stops there).
    pub fn closest_beyond(&self, q: DVec3, lower: f64) -> Option<(u32, DVec3)> {
        match self.nearest(q, lower, f64::INFINITY) {
            (d2, Some(k)) if d2 > lower * lower => {
                Some((self.order[k], closest_point(q, &self.tris[k])))
            }
            _ => None,
        }
    }

    /// The triangle closest to `q` (its index in the list the tree was
    /// built from), if one lies within `upper`.
    pub fn closest_within(&self, q: DVec3, upper: f64) -> Option<u32> {
        match self.nearest(q, 0.0, upper) {
            (d2, Some(k)) if d2 <= upper * upper => Some(self.order[k]),
            _ => None,
        }
    }

    /// The squared distance `distance_between` takes the root of, and
    /// the triangle (its place in `tris`) at that distance, if one was
    /// within `upper`.
    fn nearest(&self, q: DVec3, lower: f64, upper: f64) -> (f64, Option<usize>) {
        let mut found = None;
        if self.nodes.is_empty() {
            return (upper * upper, found);
        }
        let lower2 = lower * lower;
        let mut best2 = upper * upper;
        let mut stack = [(0u32, 0.0f64); 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (i, d2) = stack[top];
            if d2 >= best2 {
                continue;
            }
            let node = &self.nodes[i as usize];
            if node.count > 0 {
                let first = node.index as usize;
                for (k, t) in self.tris[first..first + node.count as usize]
                    .iter()
                    .enumerate()
                {
                    let d2 = closest_point(q, t).distance_squared(q);
                    if d2 < best2 {
                        best2 = d2;
                        found = Some(first + k);
                    }
                }
                if best2 <= lower2 {
                    break;
                }
            } else {
                let l = i + 1;
                let r = node.index;
                let dl = box_distance2(q, &self.nodes[l as usize]);
                let dr = box_distance2(q, &self.nodes[r as usize]);
                // Push the farther child first so the nearer is searched
                // first and tightens `best2` sooner.
                let (near, far) = if dl <= dr {
                    ((l, dl), (r, dr))
                } else {
                    ((r, dr), (l, dl))
                };
                if far.1 < best2 {
                    stack[top] = far;
                    top += 1;
                }
                if near.1 < best2 {
                    stack[top] = near;
                    top += 1;
                }
            }
        }
        (best2, found)
    }
}

/// The outer product `a b^T`.
#[inline]
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Squared distance from `q` to the box of `node` (0 inside).
#[inline]
fn box_distance2(q: DVec3, node: &Node) -> f64 {
    let d = (node.lo - q).max(q - node.hi).max(DVec3::ZERO);
    d.length_squared()
}

/// Parameter of the segment `a + t dir` (t in [0, 1]) where it meets the
/// triangle, edges and corners included (Moeller and Trumbore 1997).
#[inline]
fn segment_triangle(a: DVec3, dir: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() <= 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = a - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let tt = e2.dot(q) * inv;
    (0.0..=1.0).contains(&tt).then_some(tt)
}

/// Slab test of the segment `a + t dir`, t in [0, 1], against a box;
/// `inv` is `1 / dir`. Fast, but a segment lying in the plane of one of
/// the box's faces gives 0 * inf = NaN there, which the vector min and max
/// may carry through, culling the box: a miss `segment_crossings`' root
/// finding survives (it bisects), `signed_crossings` would not
/// (`segment_meets_box`).
#[inline]
fn segment_hits_box(a: DVec3, inv: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let t0 = (lo - a) * inv;
    let t1 = (hi - a) * inv;
    let tmin = t0.min(t1);
    let tmax = t0.max(t1);
    let enter = tmin.max_element().max(0.0);
    let exit = tmax.min_element().min(1.0);
    enter <= exit + 1e-12
}

/// Whether the segment `a + s dir` (s in 0..1) meets the box grown by a
/// hair (slab test; an axis the segment does not move along is an
/// interval test, with no infinite reciprocal). Every triangle the
/// segment meets or all but meets is in such a box, so `signed_crossing`
/// sees it.
fn segment_meets_box(a: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let pad = CLEAN * (hi - lo).max_element() + f64::MIN_POSITIVE;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let (l, h) = (lo[k] - pad, hi[k] + pad);
        if dir[k] == 0.0 {
            if a[k] < l || a[k] > h {
                return false;
            }
        } else {
            let (u, v) = ((l - a[k]) / dir[k], (h - a[k]) / dir[k]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
    }
    t0 <= t1
}

/// Barycentric distance from a triangle's edges within which a crossing
/// is not clean, beside the tests' own rounding (`signed_crossing`).
const CLEAN: f64 = 1e-9;

/// Sine of the angle between a segment and a triangle's plane below which
/// the barycentric tests are not used at all: a segment grazing a face is
/// clean only with both ends clearly on one side of its plane.
const GRAZING: f64 = 1e-6;

/// The crossing of the segment `a + s dir` (s in 0..1) through `t`, as
/// `signed_crossings` gives it: `Some(None)` for none, `None` for one not
/// clean. Moller-Trumbore, whose barycentric coordinates and parameter
/// round by about eps |a - t0| |dir| |e| / |det| and eps |a - t0| |e|^2 /
/// |det| (the row's length over the triangle's size, over the sine of
/// their angle): an edge test within that bound, widened by `CLEAN`, calls
/// the crossing not clean, and the parameter's bound goes with it, so a
/// point of the row that close takes its winding number instead.
fn signed_crossing(a: DVec3, dir: DVec3, t: &[DVec3; 3]) -> Option<Option<(f64, i8, f64)>> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    let normal = e1.cross(e2);
    let s = a - t[0];
    let (ls, le, ld) = (s.length(), e1.length() + e2.length(), dir.length());
    if det.abs() <= GRAZING * normal.length() * ld {
        let (from, to) = (s.dot(normal), (s + dir).dot(normal));
        let margin = CLEAN * normal.length() * (ld + le);
        let one_side = from.min(to) > margin || from.max(to) < -margin;
        return one_side.then_some(None);
    }
    let inv = 1.0 / det;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    let tt = e2.dot(q) * inv;
    let w = 1.0 - u - v;
    // Each quotient's rounding: a few eps of its numerator's and the
    // determinant's terms, over the determinant (all units cancel).
    let eps = 16.0 * f64::EPSILON / det.abs();
    let edge = CLEAN + eps * (ls + le) * le * (ld + le);
    let end = CLEAN + eps * (ls + ld) * le * le;
    if u < -edge || v < -edge || w < -edge || !(-end..=1.0 + end).contains(&tt) {
        return Some(None);
    }
    if u <= edge || v <= edge || w <= edge || tt <= end || tt >= 1.0 - end {
        return None;
    }
    // det = -dir . (e1 x e2): the normal points along the segment when det < 0.
    Some(Some((tt, if det < 0.0 { 1 } else { -1 }, end)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_distance(tris: &[[DVec3; 3]], q: DVec3) -> f64 {
        tris.iter()
            .map(|t| closest_point(q, t).distance(q))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn distance_and_crossings_match_brute_force() {
        let sphere = crate::mesh::shapes::icosphere(3);
        let tris: Vec<[DVec3; 3]> = (0..sphere.num_faces()).map(|f| sphere.corners(f)).collect();
        let bvh = Bvh::new(tris.clone());
        let mut out = Vec::new();
        for i in 0..200u64 {
            let r = |k: u64| (crate::rng::hash(5, &[i, k]) as f64 / u64::MAX as f64) * 3.0 - 1.5;
            let q = DVec3::new(r(0), r(1), r(2));
            assert!((bvh.distance(q) - brute_distance(&tris, q)).abs() < 1e-12);
            // The closest triangle by its index in the list given.
            let (f, point) = bvh.closest_beyond(q, 0.0).unwrap();
            assert!((point.distance(q) - brute_distance(&tris, q)).abs() < 1e-12);
            assert_eq!(closest_point(q, &tris[f as usize]), point);
            let beyond = |lower: f64| bvh.closest_beyond(q, lower).map(|(g, _)| g);
            assert_eq!(beyond(point.distance(q) * 0.99), Some(f));
            assert_eq!(beyond(point.distance(q) * 1.01), None);
            // Moved and refitted, it still finds the closest.
            let moved: Vec<[DVec3; 3]> =
                tris.iter().map(|t| t.map(|p| p * 1.3 + q * 0.1)).collect();
            let mut refitted = Bvh::for_distances(tris.clone());
            refitted.refit(|i| moved[i as usize]);
            assert!((refitted.distance(q) - brute_distance(&moved, q)).abs() < 1e-12);
            let b = DVec3::new(r(3), r(4), r(5));
            bvh.segment_crossings(q, b, &mut out);
            let mut brute: Vec<f64> = tris
                .iter()
                .filter_map(|t| segment_triangle(q, b - q, t))
                .collect();
            brute.sort_unstable_by(f64::total_cmp);
            brute.dedup_by(|x, y| (*x - *y).abs() < 1e-9);
            assert_eq!(out.len(), brute.len());
        }
    }
}
