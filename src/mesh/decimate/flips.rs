//! Edge flips: an edge between two faces flipped where that evens their
//! angles out, the way remeshers mend the thin faces collapses leave.

use super::cleanup_floor;
use crate::mesh::TriMesh;
use crate::mesh::corners::sharpness;
use crate::mesh::envelope::Envelope;

/// Passes of edge flips: an edge between two faces that meet at no more
/// than `MAX_CREASE` degrees is flipped when that raises the smaller of the
/// two faces' smallest angles (Delaunay's criterion on a surface), no face
/// turns over and the new edge is not already one. Flipping an almost flat
/// pair moves the surface by little; it is how remeshers even out the
/// thin faces that collapses leave. With `steep`, a pair with an angle
/// under the cleanup's floor may flip over a steeper crease where that
/// moves the surface by little (`FLIP_MOVE`). The number of flips made.
pub fn flip_edges(
    mesh: &mut TriMesh,
    passes: usize,
    steep: bool,
    mut envelope: Option<&mut Envelope>,
) -> usize {
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
        let table = crate::mesh::edges::EdgeTable::new(&mesh.triangles);
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
            if let Some(envelope) = envelope.as_deref_mut() {
                let after = [
                    (f0 as u32, [p(c), p(a), p(d)]),
                    (f1 as u32, [p(d), p(b), p(c)]),
                ];
                if !envelope.admit(&[f0 as u32, f1 as u32], &after) {
                    continue;
                }
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
