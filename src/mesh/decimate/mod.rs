//! Decimation of a closed manifold surface to a face budget by quadric
//! error edge collapses (Garland and Heckbert 1997), keeping it closed,
//! manifold, of the same genus and without flipped or needle faces; then
//! tangential relaxation, which evens the triangles' shapes without moving
//! the surface off itself.
//!
//! Written here: the crates that decimate (meshopt's simplifier among them)
//! work on index buffers without a manifold guarantee (they may pinch the
//! surface or close a handle), which the unwrap and the tet mesher after
//! this stage cannot take.

use radix_heap::RadixHeapMap;
use std::cmp::Reverse;

use glam::{DMat3, DVec3};

use super::corners::{keeps_facing, move_corners, sharpness};
use super::envelope::Envelope;
use crate::error::{Error, Result};
use crate::mesh::{FaceId, TriMesh};
use crate::progress::{self, Progress};

mod halves;
mod tips;

/// No collapse may leave the faces it moves with an angle below this
/// (degrees), or below the smallest angle they had, if that is less.
/// Issue 40 asks for 20 at 50k faces. A voxel surface's own faces are
/// thinner, and the guard keeps them from being collapsed into better
/// ones: rounds of flips and relaxation between the collapses even them
/// out, and a cleanup at the end mends the faces the budget left under it
/// where a move, a collapse or a flip can (`decimate`; on the MNI white
/// matter at 50k faces, all of them).
pub const MIN_ANGLE: f64 = 20.0;
/// Nor turn a face by more than this (degrees); nor may `segment::fit`'s
/// moves.
pub const MAX_TURN: f64 = 60.0;

/// A symmetric 4x4 quadric, its upper triangle.
#[derive(Clone, Copy, Default)]
struct Quadric([f64; 10]);

impl Quadric {
    fn of_plane(n: DVec3, d: f64, weight: f64) -> Quadric {
        let (a, b, c) = (n.x, n.y, n.z);
        Quadric(
            [
                a * a,
                a * b,
                a * c,
                a * d,
                b * b,
                b * c,
                b * d,
                c * c,
                c * d,
                d * d,
            ]
            .map(|x| x * weight),
        )
    }

    fn add(&self, o: &Quadric) -> Quadric {
        Quadric(std::array::from_fn(|k| self.0[k] + o.0[k]))
    }

    fn error(&self, p: DVec3) -> f64 {
        let q = &self.0;
        let (x, y, z) = (p.x, p.y, p.z);
        q[0] * x * x
            + 2.0 * q[1] * x * y
            + 2.0 * q[2] * x * z
            + 2.0 * q[3] * x
            + q[4] * y * y
            + 2.0 * q[5] * y * z
            + 2.0 * q[6] * y
            + q[7] * z * z
            + 2.0 * q[8] * z
            + q[9]
    }

    /// The point of least error, when the quadric pins one.
    fn optimum(&self) -> Option<DVec3> {
        let q = &self.0;
        let m = DMat3::from_cols(
            DVec3::new(q[0], q[1], q[2]),
            DVec3::new(q[1], q[4], q[5]),
            DVec3::new(q[2], q[5], q[7]),
        );
        let scale = q[0] + q[4] + q[7];
        if m.determinant().abs() <= 1e-9 * scale * scale * scale {
            return None;
        }
        let p = m.inverse() * -DVec3::new(q[3], q[6], q[8]);
        p.is_finite().then_some(p)
    }
}

/// A candidate collapse of edge (a, b) to `to`.
struct Candidate {
    cost: f64,
    a: u32,
    b: u32,
    to: DVec3,
}

/// The queue of candidates, cheapest first: a radix heap keyed by the
/// cost's bits (a non-negative f64's bits order as it does). It holds
/// every edge and the stale entries, millions for a scan's surface; a
/// binary or 4-ary heap's pops walked it from top to bottom and were a
/// fifth to a third of decimating a scan, where a radix heap's buckets are
/// read in order. A radix heap takes no key below the last one popped:
/// merging two ends' quadrics never lowers the least error round them,
/// and the few costs that do fall (the optimum off the edge, its ends or
/// middle taken instead) are queued at the last popped cost, to come next.
/// An entry is current while both ends are there and the cost recomputed
/// when it is popped has the same bits (an end that moved or gathered
/// another's quadric changes it; should it not, the collapse is the
/// current one anyway). Ties pop last in, first out: the same order on
/// every run.
#[derive(Default)]
struct Queue(RadixHeapMap<Reverse<u64>, (u64, u32, u32)>);

impl Queue {
    fn push(&mut self, c: &Candidate) {
        let bits = c.cost.to_bits();
        let key = self.0.top().map_or(bits, |Reverse(top)| bits.max(top));
        self.0.push(Reverse(key), (bits, c.a, c.b));
    }

    /// The cheapest entry: its cost's bits and edge.
    fn pop(&mut self) -> Option<(u64, u32, u32)> {
        self.0.pop().map(|(_, v)| v)
    }
}

/// The smallest angle of triangle (a, b, c), degrees.
pub fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    sharpness(a, b, c).clamp(-1.0, 1.0).acos().to_degrees()
}

struct State {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Faces at each vertex (dead ones dropped lazily).
    faces_at: Vec<Vec<u32>>,
    quadrics: Vec<Quadric>,
    removed: Vec<bool>,
}

impl State {
    fn live_faces(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        self.faces_at[v as usize]
            .iter()
            .copied()
            .filter(|&f| self.alive[f as usize])
    }

    /// `v`'s neighbours into `out`, sorted, once each (a buffer reused:
    /// this runs twice per collapse tried).
    fn neighbours(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.live_faces(v)
                .flat_map(|f| self.triangles[f as usize])
                .filter(|&w| w != v),
        );
        out.sort_unstable();
        out.dedup();
    }

    fn candidate(&self, a: u32, b: u32) -> Candidate {
        let (a, b) = (a.min(b), a.max(b));
        let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let mid = (pa + pb) / 2.0;
        // The optimum when it lies near the edge (far away it is a
        // degenerate quadric's artefact), else the best of ends and middle.
        let near = |p: DVec3| p.distance(mid) <= pa.distance(pb);
        let to = match q.optimum().filter(|&p| near(p)) {
            Some(p) => p,
            None => [pa, pb, mid]
                .into_iter()
                .min_by(|x, y| q.error(*x).total_cmp(&q.error(*y)))
                .expect("three points"),
        };
        Candidate {
            cost: q.error(to).max(0.0),
            a,
            b,
            to,
        }
    }

    /// Whether collapsing (a, b) to `to` keeps the surface manifold (the
    /// link condition: the ends share exactly the two opposite vertices)
    /// and no face it moves flips or turns far; if so, the worst
    /// sharpness (`sharpness`) among the faces round the edge before and
    /// among those it moves after, for the caller's shape rule.
    fn shapes(
        &self,
        a: u32,
        b: u32,
        to: DVec3,
        turn: f64,
        scratch: &mut [Vec<u32>; 2],
    ) -> Option<(f64, f64)> {
        let [na, nb] = scratch;
        self.neighbours(a, na);
        self.neighbours(b, nb);
        let shared = na.iter().filter(|v| nb.binary_search(v).is_ok()).count();
        let across = self
            .live_faces(a)
            .filter(|&f| self.triangles[f as usize].contains(&b))
            .count();
        if across != 2 || shared != 2 {
            return None;
        }
        // A face of no area has no direction of its own to keep: it keeps
        // the two ends' faces' mean one.
        let around = || -> DVec3 {
            [a, b]
                .iter()
                .flat_map(|&v| self.live_faces(v))
                .map(|f| {
                    let [x, y, z] = self.triangles[f as usize].map(|w| self.positions[w as usize]);
                    (y - x).cross(z - x)
                })
                .sum()
        };
        let (mut worst_old, mut worst_new) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for v in [a, b] {
            for f in self.live_faces(v) {
                let t = self.triangles[f as usize];
                let old = t.map(|w| self.positions[w as usize]);
                worst_old = worst_old.max(sharpness(old[0], old[1], old[2]));
                if t.contains(&a) && t.contains(&b) {
                    continue;
                }
                let new = t.map(|w| {
                    if w == a || w == b {
                        to
                    } else {
                        self.positions[w as usize]
                    }
                });
                let (n0, n1) = (
                    (old[1] - old[0]).cross(old[2] - old[0]),
                    (new[1] - new[0]).cross(new[2] - new[0]),
                );
                if !keeps_facing(n0, n1, around, turn) {
                    return None;
                }
                worst_new = worst_new.max(sharpness(new[0], new[1], new[2]));
            }
        }
        Some((worst_old, worst_new))
    }

    /// The faces round edge (a, b) into `around`, and those that survive
    /// its collapse to `to`, with their corners then, into `after`.
    fn faces_round(
        &self,
        a: u32,
        b: u32,
        to: DVec3,
        around: &mut Vec<u32>,
        after: &mut Vec<(u32, [DVec3; 3])>,
    ) {
        around.clear();
        after.clear();
        for f in self.live_faces(a).chain(self.live_faces(b)) {
            if around.contains(&f) {
                continue;
            }
            around.push(f);
            let t = self.triangles[f as usize];
            if !(t.contains(&a) && t.contains(&b)) {
                let corners = t.map(|w| {
                    if w == a || w == b {
                        to
                    } else {
                        self.positions[w as usize]
                    }
                });
                after.push((f, corners));
            }
        }
    }

    /// Each live edge once, as (smaller end, larger end), on a closed
    /// surface; an open one's boundary edges that run down are left out
    /// (a half's, whose ends are locked).
    fn live_edges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.triangles
            .iter()
            .zip(&self.alive)
            .filter(|(_, alive)| **alive)
            .flat_map(|(t, _)| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|(a, b)| a < b)
    }

    /// The faces left, vertices in order of use.
    fn into_mesh(self) -> TriMesh {
        let faces: Vec<FaceId> = (0..self.triangles.len())
            .filter(|&f| self.alive[f])
            .map(FaceId::from)
            .collect();
        let current = TriMesh::new(self.positions, self.triangles);
        super::submesh::extract(&current, &faces).0
    }

    /// The collapse state of `mesh`: each vertex's quadric the sum of its
    /// faces' planes, weighted by their areas.
    fn new(mesh: &TriMesh) -> State {
        let n = mesh.num_vertices();
        let mut s = State {
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            alive: vec![true; mesh.num_faces()],
            faces_at: vec![Vec::new(); n],
            quadrics: vec![Quadric::default(); n],
            removed: vec![false; n],
        };
        for (f, t) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let cross = (b - a).cross(c - a);
            let area = cross.length() / 2.0;
            if area > 0.0 {
                let nrm = cross / (2.0 * area);
                let q = Quadric::of_plane(nrm, -nrm.dot(a), area);
                for &v in t {
                    s.quadrics[v as usize] = s.quadrics[v as usize].add(&q);
                }
            }
            for &v in t {
                s.faces_at[v as usize].push(f as u32);
            }
        }
        s
    }

    fn collapse(&mut self, a: u32, b: u32, to: DVec3) {
        for f in self.faces_at[b as usize].clone() {
            if !self.alive[f as usize] {
                continue;
            }
            let t = &mut self.triangles[f as usize];
            if t.contains(&a) {
                self.alive[f as usize] = false;
            } else {
                for w in t.iter_mut() {
                    if *w == b {
                        *w = a;
                    }
                }
                self.faces_at[a as usize].push(f);
            }
        }
        self.faces_at[b as usize].clear();
        self.removed[b as usize] = true;
        self.positions[a as usize] = to;
        self.quadrics[a as usize] = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        let alive = &self.alive;
        self.faces_at[a as usize].retain(|&f| alive[f as usize]);
    }
}

/// Collapse edges of `mesh` (closed and manifold) until it has at most
/// `faces` faces, each round's collapses keeping that round's surface's
/// vertices within `envelope` of the result (`envelope::Envelope`; the last
/// round without, so the budget is reached); then `relax` rounds of edge
/// flips and tangential relaxation. Where the collapses get stuck above the
/// budget (every candidate would make an angle under `MIN_ANGLE`), a round
/// of flips and relaxation evens the faces out and the collapses go on, up
/// to `ROUNDS` times. Then the edges much shorter than the rest are
/// collapsed (`collapse_short_edges`), and the low tips (`tips`). Last,
/// the faces still under `MIN_ANGLE` (the budget stops the collapses
/// before their guard has mended every face it was given) are mended
/// where a corner's move, a collapse or a flip can (a best effort: the
/// result's smallest angle is the caller's to report). Deterministic: the same bytes on any thread
/// count (`halves`; equal costs pop last in, first out, `Queue`). The
/// error names why the budget was not reached.
pub fn decimate(
    mesh: &TriMesh,
    faces: usize,
    relax: usize,
    envelope: Option<f64>,
    progress: &dyn Progress,
) -> Result<TriMesh> {
    progress.stage("decimating", mesh.num_faces().saturating_sub(faces) as u64);
    let mut out = mesh.clone();
    for round in 0..ROUNDS {
        // Even out the thin faces first, so the angle guard does not hold
        // collapses back around them.
        flip_edges(&mut out, 3, false);
        relax_tangentially(&mut out, 1);
        // The envelope round this round's surface (`envelope`), and none
        // in the last round, so it never stops a budget the guards alone
        // would reach.
        let tolerance = envelope.filter(|_| round + 1 < ROUNDS);
        out = collapse_to(&out, faces, tolerance, progress)?;
        if out.num_faces() <= faces {
            break;
        }
    }
    if out.num_faces() > faces {
        return Err(Error::invalid(format!(
            "decimation stopped at {} faces, above the budget of {faces}: no further \
             collapse keeps the surface manifold with its angles at least {MIN_ANGLE} degrees",
            out.num_faces()
        )));
    }
    for _ in 0..relax {
        flip_edges(&mut out, 1, false);
        relax_tangentially(&mut out, 1);
    }
    if collapse_short_edges(&mut out)
        + tips::flatten_tips(&mut out, TIP_HEIGHT * envelope.unwrap_or(f64::INFINITY))
        > 0
    {
        flip_edges(&mut out, 1, false);
        relax_tangentially(&mut out, 1);
    }
    // The faces still under MIN_ANGLE, which the budget left: their
    // corners moved, needles collapsed, caps flipped over creases, each
    // step only raising the worst angle where it acts, while there are
    // any (the flips and relaxation go on evening the rest out, on every
    // face, for nothing).
    for _ in 0..CLEANUP_ROUNDS {
        let floor = cleanup_floor();
        if (0..out.num_faces()).all(|f| {
            let [a, b, c] = out.corners(f);
            sharpness(a, b, c) <= floor
        }) {
            break;
        }
        let changed = move_corners(&mut out, floor, MAX_TURN.to_radians().cos())
            + collapse_needles(&mut out)
            + flip_edges(&mut out, 2, true);
        relax_tangentially(&mut out, 1);
        if changed == 0 {
            break;
        }
    }
    Ok(out)
}

/// Rounds of collapses, each after a round of flips and relaxation.
const ROUNDS: usize = 6;
/// The tallest tip flattened (`tips`), in envelope tolerances: on the MNI
/// white matter at 50k faces, half a voxel takes its mean curvature's
/// spread from 0.48 to 0.43 and leaves its distances to the voxels as they
/// were; a voxel, to 0.39 with 3.6 voxels from them (2.9 before); no bound,
/// 0.37 with 4.1.
const TIP_HEIGHT: f64 = 2.0;
/// Rounds of corner moves, collapses and flips of the faces under the
/// cleanup's floor at the end, until a round changes nothing (on the MNI
/// white matter at 50k faces that took 20, each a few milliseconds).
const CLEANUP_ROUNDS: usize = 32;
/// The cleanup works on the faces under MIN_ANGLE plus this (degrees), so
/// the angles stay at MIN_ANGLE once positions are written as 32-bit
/// floats (a face a fiftieth of a millimetre across loses 0.02 degrees).
const CLEANUP_MARGIN: f64 = 0.5;

/// The sharpness (`sharpness`) above which the cleanup works on a face.
fn cleanup_floor() -> f64 {
    (MIN_ANGLE + CLEANUP_MARGIN).to_radians().cos()
}

/// Collapses until `faces` or until none is allowed.
fn collapse_to(
    mesh: &TriMesh,
    faces: usize,
    tolerance: Option<f64>,
    progress: &dyn Progress,
) -> Result<TriMesh> {
    let (mut s, mut envelope) = if mesh.num_faces() >= halves::SPLIT_FACES {
        halves::collapse_halves(mesh, faces, tolerance, progress)?
    } else {
        (State::new(mesh), tolerance.map(|t| Envelope::new(mesh, t)))
    };
    collapse(&mut s, envelope.as_mut(), faces, None, progress)?;
    Ok(s.into_mesh())
}

/// The greedy collapses on `s`, cheapest first, until it has `faces` live
/// faces or none is allowed; none moves a `locked` vertex.
fn collapse(
    s: &mut State,
    mut envelope: Option<&mut Envelope>,
    faces: usize,
    locked: Option<&[bool]>,
    progress: &dyn Progress,
) -> Result<()> {
    let free = |v: u32| locked.is_none_or(|l| !l[v as usize]);
    let (mut around, mut after) = (Vec::new(), Vec::new());
    let mut heap = Queue::default();
    for (a, b) in s.live_edges() {
        if free(a) && free(b) {
            heap.push(&s.candidate(a, b));
        }
    }
    let mut scratch = [Vec::new(), Vec::new()];
    let turn = MAX_TURN.to_radians().cos();
    let floor = MIN_ANGLE.to_radians().cos();
    let mut live = s.alive.iter().filter(|&&a| a).count();
    // A tetrahedron is the smallest closed surface: the link condition
    // would let it fold into a doubled triangle.
    let mut vertices = s.removed.iter().filter(|&&r| !r).count();
    let mut since_check = 0;
    while live > faces {
        let Some((cost, a, b)) = heap.pop() else {
            break;
        };
        if s.removed[a as usize] || s.removed[b as usize] || vertices <= 4 {
            continue;
        }
        let current = s.candidate(a, b);
        if current.cost.to_bits() != cost {
            continue;
        }
        let to = current.to;
        // The worst angle among the faces moved may fall only to
        // MIN_ANGLE (or to what it was).
        if !matches!(s.shapes(a, b, to, turn, &mut scratch), Some((old, new)) if new <= old.max(floor))
        {
            continue;
        }
        if let Some(envelope) = envelope.as_mut() {
            s.faces_round(a, b, to, &mut around, &mut after);
            if !envelope.allows(&around, &after) {
                continue;
            }
            envelope.commit(&around);
        }
        s.collapse(a, b, to);
        live -= 2;
        vertices -= 1;
        s.neighbours(a, &mut scratch[0]);
        for &w in &scratch[0] {
            if free(w) {
                heap.push(&s.candidate(a, w));
            }
        }
        since_check += 2;
        if since_check >= 4096 {
            progress::check(progress)?;
            progress.advance(since_check as u64);
            since_check = 0;
        }
    }
    Ok(())
}

/// Collapses of the edges shorter than `SHORT_EDGE` times the median
/// edge, shortest first, where that keeps the surface manifold, turns no
/// face by more than a right angle and makes no angle under
/// `SHORT_EDGE_ANGLE` (or under what the faces had), which the cleanup
/// after it then mends. The greedy collapses leave such edges in clusters
/// of small faces where a thin crest folds sharply (the white matter's
/// gyri): there every collapse turns the crest's small faces past
/// MAX_TURN or makes a thin face next to the large ones round them, yet
/// the surface moves by less than the edge; their ends hold a mean
/// curvature tens of times the rest's (on the MNI white matter at 50k
/// faces the spread of the mean curvature falls from 1.48 to 0.67). The
/// number made.
fn collapse_short_edges(mesh: &mut TriMesh) -> usize {
    let mut s = State::new(mesh);
    let mut lengths: Vec<(f64, u32, u32)> = s
        .live_edges()
        .map(|(a, b)| {
            let length = mesh.positions[a as usize].distance(mesh.positions[b as usize]);
            (length, a, b)
        })
        .collect();
    if lengths.is_empty() {
        return 0;
    }
    let middle = lengths.len() / 2;
    let median = lengths
        .select_nth_unstable_by(middle, |x, y| x.0.total_cmp(&y.0))
        .1
        .0;
    let limit = SHORT_EDGE * median;
    lengths.retain(|e| e.0 < limit);
    lengths.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    let floor = SHORT_EDGE_ANGLE.to_radians().cos();
    let mut scratch = [Vec::new(), Vec::new()];
    let mut vertices = mesh.num_vertices();
    let mut made = 0;
    for (_, a, b) in lengths {
        if s.removed[a as usize] || s.removed[b as usize] || vertices <= 4 {
            continue;
        }
        if s.positions[a as usize].distance(s.positions[b as usize]) >= limit {
            continue;
        }
        let to = s.candidate(a, b).to;
        if matches!(s.shapes(a, b, to, 0.0, &mut scratch), Some((old, new)) if new <= old.max(floor))
        {
            s.collapse(a, b, to);
            vertices -= 1;
            made += 1;
        }
    }
    if made > 0 {
        *mesh = s.into_mesh();
    }
    made
}

/// An edge shorter than this share of the median edge is collapsed after
/// the budget is met (`collapse_short_edges`).
const SHORT_EDGE: f64 = 0.35;
/// The smallest angle (degrees) such a collapse may leave (or less where
/// a face round the edge had less), for the cleanup to mend: with
/// MIN_ANGLE itself as the bound half the short edges stay (the faces
/// round a cluster of small ones are large).
const SHORT_EDGE_ANGLE: f64 = 5.0;

/// Collapses of an edge of each face whose smallest angle is under the
/// cleanup's floor (`cleanup_floor`; a needle's short edge, or a cap's apex onto an end), where that
/// keeps the surface manifold, turns no face far and makes the worst angle
/// round the edge strictly larger: what the budget stopped the greedy
/// collapses short of. The number made.
fn collapse_needles(mesh: &mut TriMesh) -> usize {
    let floor = cleanup_floor();
    let turn = MAX_TURN.to_radians().cos();
    let mut s = State::new(mesh);
    let mut scratch = [Vec::new(), Vec::new()];
    let mut vertices = mesh.num_vertices();
    let mut made = 0;
    for f in 0..s.triangles.len() {
        let t = s.triangles[f];
        let p = t.map(|v| s.positions[v as usize]);
        if !s.alive[f] || vertices <= 4 || sharpness(p[0], p[1], p[2]) <= floor {
            continue;
        }
        // The edge whose collapse leaves the best worst angle.
        let best = (0..3)
            .filter_map(|k| {
                let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
                let to = s.candidate(a, b).to;
                let (old, new) = s.shapes(a, b, to, turn, &mut scratch)?;
                (new < old).then_some((new, a, b, to))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((_, a, b, to)) = best {
            s.collapse(a, b, to);
            vertices -= 1;
            made += 1;
        }
    }
    if made > 0 {
        *mesh = s.into_mesh();
    }
    made
}

/// Rounds of tangential relaxation: each vertex moves halfway to its
/// neighbours' centroid within its tangent plane (the normal component of
/// the move dropped), where that flips no face round it and leaves the
/// smallest angle among them no smaller. Evens the faces' shapes; the surface
/// stays where it was to second order.
fn relax_tangentially(mesh: &mut TriMesh, rounds: usize) {
    let faces_at = mesh.faces_at_vertices();
    for _ in 0..rounds {
        for (v, ring) in faces_at.iter().enumerate() {
            let mut normal = DVec3::ZERO;
            let mut centroid = DVec3::ZERO;
            let mut count = 0.0;
            for &f in ring {
                let t = mesh.triangles[f as usize];
                let [a, b, c] = t.map(|w| mesh.positions[w as usize]);
                normal += (b - a).cross(c - a);
                for &w in &t {
                    if w as usize != v {
                        centroid += mesh.positions[w as usize];
                        count += 1.0;
                    }
                }
            }
            if count == 0.0 || normal.length_squared() == 0.0 {
                continue;
            }
            let normal = normal.normalize();
            let p = mesh.positions[v];
            let step = (centroid / count - p) * 0.5;
            let to = p + step - normal * normal.dot(step);
            // The ring's worst angle may only grow; no face may flip.
            let mut worst = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            let mut flipped = false;
            for &f in ring {
                let t = mesh.triangles[f as usize];
                let old = t.map(|w| mesh.positions[w as usize]);
                let new = t.map(|w| {
                    if w as usize == v {
                        to
                    } else {
                        mesh.positions[w as usize]
                    }
                });
                let (n0, n1) = (
                    (old[1] - old[0]).cross(old[2] - old[0]),
                    (new[1] - new[0]).cross(new[2] - new[0]),
                );
                flipped |= n0.dot(n1) <= 0.0;
                worst.0 = worst.0.max(sharpness(old[0], old[1], old[2]));
                worst.1 = worst.1.max(sharpness(new[0], new[1], new[2]));
            }
            let ok = !flipped && worst.1 <= worst.0;
            if ok {
                mesh.positions[v] = to;
            }
        }
    }
}

/// Passes of edge flips: an edge between two faces that meet at no more
/// than `MAX_CREASE` degrees is flipped when that raises the smaller of the
/// two faces' smallest angles (Delaunay's criterion on a surface), no face
/// turns over and the new edge is not already one. Flipping an almost flat
/// pair moves the surface by little; it is how remeshers even out the
/// thin faces that collapses leave. With `steep`, a pair with an angle
/// under the cleanup's floor may flip over a steeper crease where that
/// moves the surface by little (`FLIP_MOVE`). The number of flips made.
pub fn flip_edges(mesh: &mut TriMesh, passes: usize, steep: bool) -> usize {
    let crease = MAX_CREASE.to_radians().cos();
    let floor = cleanup_floor();
    let mut flips = 0;
    for _ in 0..passes {
        // Half-edge `h` is corner h % 3 of face h / 3 running to the next
        // corner (`edges::halfedge_endpoints`). Each pass visits the edges
        // in order of their ends; a flip renames its edge to the new
        // diagonal (not visited again this pass) and moves the half-edges
        // of two others between the faces, so the arrays follow it:
        // `opposite` and `edge_of` per half-edge, `half_of` per edge.
        let table = super::edges::EdgeTable::new(&mesh.triangles);
        let n = mesh.triangles.len() * 3;
        let mut opposite = vec![u32::MAX; n];
        let mut edge_of = vec![0u32; n];
        let mut half_of = Vec::with_capacity(table.num_edges());
        for (e, hs) in table.iter() {
            for h in hs {
                edge_of[h.idx()] = e.idx() as u32;
            }
            if let [g, h] = *hs {
                opposite[g.idx()] = h.idx() as u32;
                opposite[h.idx()] = g.idx() as u32;
            }
            half_of.push(hs[0].idx() as u32);
        }
        drop(table);
        let mut made = 0;
        for e in 0..half_of.len() {
            let h = half_of[e] as usize;
            let g = opposite[h];
            if g == u32::MAX {
                continue;
            }
            let g = g as usize;
            let (f0, k) = (h / 3, h % 3);
            let (f1, l) = (g / 3, g % 3);
            // f0 runs a -> b -> c, f1 runs b -> a -> d.
            let t0 = mesh.triangles[f0];
            let (a, b, c) = (t0[k], t0[(k + 1) % 3], t0[(k + 2) % 3]);
            let d = mesh.triangles[f1][(l + 2) % 3];
            if c == d || joined(mesh, &opposite, 3 * f0 + (k + 2) % 3, d) {
                continue;
            }
            let p = |v: u32| mesh.positions[v as usize];
            let normal = |x: u32, y: u32, z: u32| (p(y) - p(x)).cross(p(z) - p(x));
            let (n0, n1) = (normal(a, b, c), normal(b, a, d));
            if n0.length_squared() == 0.0 || n1.length_squared() == 0.0 {
                continue;
            }
            let before = sharpness(p(a), p(b), p(c)).max(sharpness(p(b), p(a), p(d)));
            // Across a steeper crease only a pair with an angle under the
            // cleanup's floor, and only where the two diagonals nearly meet: the
            // surface moves by the tetrahedron (a, b, c, d) between the
            // pair and the flipped pair, as thick as the diagonals' lines
            // are apart.
            if n0.normalize().dot(n1.normalize()) < crease {
                let across = (p(b) - p(a)).cross(p(d) - p(c));
                let apart = (p(c) - p(a)).dot(across).abs() / across.length();
                // False where the diagonals are parallel (NaN).
                let moves_little = apart <= FLIP_MOVE * p(a).distance(p(b));
                // A pair folded onto itself is flat too, but a flip there
                // would turn the smaller face over.
                let folded = n0.normalize().dot(n1.normalize()) <= MAX_STEEP_CREASE_COS;
                if !steep || before <= floor || !moves_little || folded {
                    continue;
                }
            }
            let after = sharpness(p(c), p(a), p(d)).max(sharpness(p(d), p(b), p(c)));
            let up = n0 + n1;
            if after >= before - 1e-12
                || normal(c, a, d).dot(up) <= 0.0
                || normal(d, b, c).dot(up) <= 0.0
            {
                continue;
            }
            // The four outer half-edges, before: b -> c, c -> a in f0;
            // a -> d, d -> b in f1.
            let outer = [
                3 * f0 + (k + 2) % 3,
                3 * f1 + (l + 1) % 3,
                3 * f1 + (l + 2) % 3,
                3 * f0 + (k + 1) % 3,
            ];
            let (outer_opposite, outer_edge) =
                (outer.map(|h| opposite[h]), outer.map(|h| edge_of[h]));
            mesh.triangles[f0] = [c, a, d];
            mesh.triangles[f1] = [d, b, c];
            // After: f0's c -> a, a -> d; f1's d -> b, b -> c; and the
            // new diagonal d -> c, c -> d, which takes edge e's name.
            let slots = [3 * f0, 3 * f0 + 1, 3 * f1, 3 * f1 + 1];
            for ((&h, o), edge) in slots.iter().zip(outer_opposite).zip(outer_edge) {
                opposite[h] = o;
                // A boundary edge (or one of three faces) has no opposite.
                if o != u32::MAX {
                    opposite[o as usize] = h as u32;
                }
                edge_of[h] = edge;
                half_of[edge as usize] = h as u32;
            }
            let (x, y) = (3 * f0 + 2, 3 * f1 + 2);
            opposite[x] = y as u32;
            opposite[y] = x as u32;
            edge_of[x] = e as u32;
            edge_of[y] = e as u32;
            half_of[e] = x as u32;
            made += 1;
        }
        flips += made;
        if made == 0 {
            break;
        }
    }
    flips
}

/// Whether vertex `d` is a neighbour of the vertex half-edge `start`
/// leaves: turning round it by the opposites one way, and where that meets
/// a boundary, the other way too.
fn joined(mesh: &TriMesh, opposite: &[u32], start: usize, d: u32) -> bool {
    let corner = |h: usize, step: usize| mesh.triangles[h / 3][(h % 3 + step) % 3];
    let mut h = start;
    loop {
        if corner(h, 1) == d {
            return true;
        }
        // The next half-edge out of the same vertex: after the opposite.
        let Some(o) = opposite.get(h).copied().filter(|&o| o != u32::MAX) else {
            break;
        };
        h = 3 * (o as usize / 3) + (o as usize % 3 + 1) % 3;
        if h == start {
            return false;
        }
    }
    h = start;
    loop {
        // The half-edge into the vertex before `h`, from a neighbour.
        let into = 3 * (h / 3) + (h % 3 + 2) % 3;
        if corner(into, 0) == d {
            return true;
        }
        match opposite[into] {
            u32::MAX => return false,
            o => h = o as usize,
        }
    }
}

/// The largest angle (degrees) between two faces whose edge may flip
/// (unless, in the cleanup, one has an angle under its floor: FLIP_MOVE).
const MAX_CREASE: f64 = 15.0;
/// How far a flip across a steeper crease may move the surface, as a
/// share of the flipped edge's length: a cap (a face with an angle near
/// 180 degrees) is flat against its long edge, so flipping that edge moves
/// the surface by little whatever the crease.
const FLIP_MOVE: f64 = 0.1;
/// The cosine of the steepest crease (120 degrees) such a flip may cross.
const MAX_STEEP_CREASE_COS: f64 = -0.5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::info::analyse;
    use crate::mesh::shapes;
    use crate::progress::Silent;

    fn genus_closed_outward(mesh: &TriMesh) -> Vec<i64> {
        let r = analyse(mesh.clone(), false).unwrap().report;
        assert_eq!(r.boundary_edges, 0);
        assert_eq!(
            r.defects.non_manifold_edges + r.defects.non_manifold_vertices,
            0
        );
        assert_eq!(r.normals, Some("outward"));
        r.genus
    }

    #[test]
    fn a_sphere_and_a_torus_keep_their_genus_shape_and_angles() {
        for (mesh, genus) in [
            (shapes::icosphere(5), 0),
            (shapes::torus(1.0, 0.35, 96, 36), 1),
        ] {
            let before = mesh.signed_volume();
            let out = decimate(&mesh, mesh.num_faces() / 8, 5, None, &Silent).unwrap();
            assert!(out.num_faces() <= mesh.num_faces() / 8);
            assert_eq!(genus_closed_outward(&out), vec![genus]);
            let volume = out.signed_volume() / before;
            assert!((volume - 1.0).abs() < 0.02, "volume ratio {volume}");
            let worst = (0..out.num_faces())
                .map(|f| {
                    let [a, b, c] = out.corners(f);
                    min_angle(a, b, c)
                })
                .fold(180.0, f64::min);
            assert!(worst >= MIN_ANGLE, "smallest angle {worst}");
            // Same bytes again.
            let again = decimate(&mesh, mesh.num_faces() / 8, 5, None, &Silent).unwrap();
            assert_eq!(again.positions, out.positions);
        }
    }

    /// The farthest of `points` from the surface `to`.
    fn farthest<'a>(points: impl Iterator<Item = &'a DVec3>, to: &TriMesh) -> f64 {
        points
            .map(|&p| {
                (0..to.num_faces())
                    .map(|f| crate::mesh::closest::closest_point(p, &to.corners(f)).distance(p))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_envelope_keeps_every_vertex_near_the_decimated_surface() {
        // A ball decimated towards a sixteenth: unbounded, the collapses
        // leave vertices more than three times the tolerance from the
        // result; within the envelope every vertex stays within it.
        let mesh = shapes::icosphere(4);
        let budget = mesh.num_faces() / 16;
        let tolerance = 0.005;
        let free = collapse_to(&mesh, budget, None, &Silent).unwrap();
        let far = farthest(mesh.positions.iter(), &free);
        assert!(far > 3.0 * tolerance, "{far}");
        let kept = collapse_to(&mesh, budget, Some(tolerance), &Silent).unwrap();
        let far = farthest(mesh.positions.iter(), &kept);
        assert!(far <= tolerance, "{far}");
        // Stopped by the envelope short of the budget, not at once.
        assert!(
            kept.num_faces() > budget && kept.num_faces() < mesh.num_faces() / 4,
            "{}",
            kept.num_faces()
        );
        // `decimate` meets the budget all the same (its last round has no
        // envelope).
        let met = decimate(&mesh, budget, 0, Some(tolerance), &Silent).unwrap();
        assert!(met.num_faces() <= budget, "{}", met.num_faces());
    }

    #[test]
    fn a_budget_below_a_tetrahedron_is_refused() {
        let mesh = shapes::icosphere(1);
        let e = decimate(&mesh, 2, 0, None, &Silent)
            .unwrap_err()
            .to_string();
        assert!(e.contains("above the budget of 2"), "{e}");
    }
}
