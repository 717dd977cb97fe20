//! The first collapses of a large surface in two halves side by side.
//!
//! The greedy collapses are one loop, each choice hanging on the last; on
//! a scan's surface (the MNI white matter's 0.63M faces to 50k) they were
//! most of the decimation's time, on one core of two. Cut at the median of
//! its faces along its longest axis, the surface's two halves collapse
//! apart, each in its own order, neither moving a vertex on the cut (whose
//! faces lie in both), each stopping at its share of the budget with a
//! margin (`HALF_MARGIN`). The halves are then one state again, every
//! surviving vertex with the quadric it gathered (a cut vertex's the sum of
//! its two halves', its faces' planes) and every face with the points of
//! the envelope it carries, and the collapses go on over the whole: the
//! band along the cut, then the last of the budget, cheapest first as
//! before. Each half's result hangs only on its faces, so the bytes are the
//! same on one thread or two.

use glam::DVec3;

use super::{Quadric, State, collapse};
use crate::error::Result;
use crate::mesh::envelope::Envelope;
use crate::mesh::{FaceId, TriMesh};
use crate::progress::Progress;

/// Surfaces with fewer faces than this collapse whole (the halves' and
/// their joining's cost would outweigh the second core's gain).
pub(super) const SPLIT_FACES: usize = 100_000;

/// Each half stops at its share of the budget (by faces) times this,
/// leaving the last collapses to the whole surface, where the order is
/// one again.
const HALF_MARGIN: f64 = 1.25;

/// One half: its faces as a surface of their own, each vertex's number in
/// the whole, and whether it lies on the cut.
struct Half {
    mesh: TriMesh,
    whole: Vec<u32>,
    on_cut: Vec<bool>,
    /// The envelope on its faces (the points numbered as in the whole's).
    envelope: Option<Envelope>,
}

/// The collapse state of `mesh` (closed, manifold) after its two halves'
/// collapses towards `faces`, and its `envelope` as they left it, for
/// `collapse` to go on with.
pub(super) fn collapse_halves(
    mesh: &TriMesh,
    faces: usize,
    envelope: Option<Envelope>,
    progress: &dyn Progress,
) -> Result<(State, Option<Envelope>)> {
    let sides = cut(mesh);
    let mut sides_of = vec![0u8; mesh.num_vertices()];
    for (t, &side) in mesh.triangles.iter().zip(&sides) {
        for &v in t {
            sides_of[v as usize] |= 1 << side as u8;
        }
    }
    let half = |side: bool| {
        let faces: Vec<FaceId> = (0..mesh.num_faces())
            .filter(|&f| sides[f] == side)
            .map(FaceId::from)
            .collect();
        let envelope = envelope.as_ref().map(|e| e.restricted(&faces));
        let (mesh, whole) = crate::mesh::submesh::extract(mesh, &faces);
        let on_cut = whole.iter().map(|&v| sides_of[v as usize] == 3).collect();
        Half {
            mesh,
            whole,
            on_cut,
            envelope,
        }
    };
    let run = |mut h: Half| -> Result<(Half, State, Option<Envelope>)> {
        let share = faces as f64 * h.mesh.num_faces() as f64 / mesh.num_faces() as f64;
        let mut s = State::new(&h.mesh);
        let mut envelope = h.envelope.take();
        let budget = (share * HALF_MARGIN) as usize;
        collapse(&mut s, envelope.as_mut(), budget, Some(&h.on_cut), progress)?;
        Ok((h, s, envelope))
    };
    let (a, b) = (half(false), half(true));
    let (done_a, done_b) = rayon::join(|| run(a), || run(b));
    let halves = [done_a?, done_b?];

    let n = mesh.num_vertices();
    let mut whole = State {
        positions: mesh.positions.clone(),
        triangles: Vec::new(),
        alive: Vec::new(),
        faces_at: vec![Vec::new(); n],
        quadrics: vec![Quadric::default(); n],
        removed: vec![true; n],
    };
    let mut carried = Vec::new();
    for (h, s, envelope) in &halves {
        for (v, &w) in h.whole.iter().enumerate() {
            if !s.removed[v] {
                let w = w as usize;
                whole.removed[w] = false;
                whole.positions[w] = s.positions[v];
                whole.quadrics[w] = whole.quadrics[w].add(&s.quadrics[v]);
            }
        }
        for (f, t) in s.triangles.iter().enumerate().filter(|(f, _)| s.alive[*f]) {
            let g = whole.triangles.len() as u32;
            let t = t.map(|v| h.whole[v as usize]);
            for &v in &t {
                whole.faces_at[v as usize].push(g);
            }
            whole.triangles.push(t);
            if let Some(envelope) = envelope {
                carried.push(envelope.carried(f).to_vec());
            }
        }
    }
    whole.alive = vec![true; whole.triangles.len()];
    let envelope = envelope.map(|e| e.carrying(carried));
    Ok((whole, envelope))
}

/// Which half each face is in: the side of the median of the faces'
/// centres along the surface's longest axis (ties by face number).
fn cut(mesh: &TriMesh) -> Vec<bool> {
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let extent = hi - lo;
    let axis = (0..3)
        .max_by(|&i, &j| extent[i].total_cmp(&extent[j]))
        .expect("three axes");
    let mut order: Vec<(f64, u32)> = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(f, t)| {
            (
                t.iter().map(|&v| mesh.positions[v as usize][axis]).sum(),
                f as u32,
            )
        })
        .collect();
    let middle = order.len() / 2;
    order.select_nth_unstable_by(middle, |x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut sides = vec![false; mesh.num_faces()];
    for &(_, f) in &order[middle..] {
        sides[f as usize] = true;
    }
    sides
}

#[cfg(test)]
mod tests {
    use super::super::{Hold, decimate};
    use crate::mesh::info::analyse;
    use crate::mesh::shapes;
    use crate::progress::Silent;

    #[test]
    fn a_torus_decimated_in_halves_is_the_same_on_one_thread_or_two() {
        let mesh = shapes::torus(1.0, 0.35, 400, 130);
        assert!(mesh.num_faces() >= super::SPLIT_FACES);
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    decimate(&mesh, 8000, 2, Some(Hold::EachRound(0.002)), &Silent)
                        .unwrap()
                        .0
                })
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one.positions, two.positions);
        assert_eq!(one.triangles, two.triangles);
        assert!(one.num_faces() <= 8000);
        // Closed, manifold (`analyse` refuses otherwise), outward and a
        // torus still.
        let r = analyse(one, false).unwrap().report;
        assert_eq!(
            (r.boundary_edges, r.genus, r.normals),
            (0, vec![1], Some("outward"))
        );
    }
}
