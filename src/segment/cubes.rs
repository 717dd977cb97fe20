//! The marching-cubes table with the topology of marching tetrahedra.
//!
//! Marching tetrahedra over Kuhn's split of each cube (six tetrahedra
//! round its main diagonal, the same diagonal in every cube) never leaves
//! an ambiguous case: its level set is a closed 2-manifold, and the region's
//! pieces are those of `pieces`' 14 neighbours. But it puts vertices on the
//! face and main diagonals too, three times marching cubes' triangles on a
//! scan (1.93M against 0.63M on the MNI white matter), and every stage
//! after it (smoothing, flips, collapses) pays for them. Marching cubes
//! has as few, but a case table whose ambiguous faces disagree between
//! neighbours makes holes, and one that agrees may still pinch (VTK's
//! flying edges and scikit-image leave non-manifold vertices, issue 40).
//!
//! This table keeps both: for each of the 256 cases it takes the surface
//! marching tetrahedra puts in the cube and rebuilds each of its pieces
//! over the cube's twelve edges alone. A piece meets the cube's faces in
//! closed loops through edge crossings and face-diagonal crossings; a
//! face-diagonal crossing always lies between two edge crossings of that
//! face, so dropping it joins them by a segment that depends on the face's
//! four corners alone, the same segment in the cube on its other side. A
//! piece with one loop (a disk) is triangulated as a polygon, with two (an
//! annulus: a tube round the main diagonal) as a strip. No new edge may
//! join two crossings on one cube face: the cube beside it could join them
//! too, and the edge would have four triangles. Where a polygon has no
//! triangulation without one, it is fanned from a vertex at its centre,
//! which no other cube sees. The pieces are then the same disks and
//! annuli glued along the same loops: the surface is the same closed
//! manifold, up to the places its vertices sit, as marching tetrahedra's,
//! with its pieces, voids and genus, and marching cubes' triangle count.
//!
//! Each case's triangulation is the one whose smallest angle is largest
//! with every crossing at its edge's middle.

use std::sync::OnceLock;

use glam::DVec3;

use crate::mesh::dsu::DisjointSets;

/// A cube's corner `k` sits at (k & 1, k >> 1 & 1, k >> 2 & 1); a case's
/// bit `k` is set when corner `k` is inside.
pub fn corner(k: usize) -> [usize; 3] {
    [k & 1, (k >> 1) & 1, (k >> 2) & 1]
}

/// The cube's twelve edges as (lower corner, axis): the edge runs from
/// the corner to the corner one step further along the axis.
pub const EDGES: [(u8, u8); 12] = {
    let mut out = [(0u8, 0u8); 12];
    let mut n = 0;
    let mut axis = 0;
    while axis < 3 {
        let mut k = 0u8;
        while k < 8 {
            if k & (1 << axis) == 0 {
                out[n] = (k, axis as u8);
                n += 1;
            }
            k += 1;
        }
        axis += 1;
    }
    out
};

/// One case: its triangles, counter-clockwise seen from outside, over
/// vertex ids `0..12` (the crossing on `EDGES[id]`) and `12 + c` (the mean
/// of the crossings `centres[c]` lists).
#[derive(Debug, Default)]
pub struct Case {
    pub triangles: Vec<[u8; 3]>,
    pub centres: Vec<Vec<u8>>,
}

/// The 256 cases, built once.
pub fn table() -> &'static [Case] {
    static TABLE: OnceLock<Vec<Case>> = OnceLock::new();
    TABLE.get_or_init(|| (0..=255u8).map(case).collect())
}

/// The six tetrahedra of Kuhn's split as corner indices: the paths from
/// corner 0 to corner 7 one axis at a time, in every order.
const KUHN: [[usize; 4]; 6] = {
    const fn path(order: [usize; 3]) -> [usize; 4] {
        let mut out = [0; 4];
        let mut k = 0;
        while k < 3 {
            out[k + 1] = out[k] | 1 << order[k];
            k += 1;
        }
        out
    }
    [
        path([0, 1, 2]),
        path([0, 2, 1]),
        path([1, 0, 2]),
        path([1, 2, 0]),
        path([2, 0, 1]),
        path([2, 1, 0]),
    ]
};

/// A vertex of marching tetrahedra's surface in a cube: the crossing on
/// the Kuhn edge between two corners (the lower one first; its bits are a
/// subset of the upper one's).
type TetVertex = (u8, u8);

fn point(k: u8) -> DVec3 {
    let [x, y, z] = corner(k as usize);
    DVec3::new(x as f64, y as f64, z as f64)
}

fn middle((a, b): TetVertex) -> DVec3 {
    (point(a) + point(b)) / 2.0
}

/// Marching tetrahedra's triangles in a cube of case `mask`, facing out.
pub(crate) fn tet_triangles(mask: u8) -> Vec<[TetVertex; 3]> {
    let inside = |k: usize| mask & (1 << k) != 0;
    let mut out = Vec::new();
    for tet in KUHN {
        let (ins, outs): (Vec<usize>, Vec<usize>) = tet.iter().partition(|&&k| inside(k));
        let on = |a: usize, b: usize| (a.min(b) as u8, a.max(b) as u8);
        let triangles = match (ins.as_slice(), outs.as_slice()) {
            (&[i], &[a, b, c]) => vec![[on(i, a), on(i, b), on(i, c)]],
            (&[a, b, c], &[o]) => vec![[on(a, o), on(b, o), on(c, o)]],
            (&[a, b], &[c, d]) => vec![
                [on(a, c), on(a, d), on(b, d)],
                [on(a, c), on(b, d), on(b, c)],
            ],
            _ => Vec::new(),
        };
        let centre = |ks: &[usize]| {
            ks.iter().map(|&k| point(k as u8)).sum::<DVec3>() / ks.len().max(1) as f64
        };
        let outward = centre(&outs) - centre(&ins);
        for mut t in triangles {
            let [a, b, c] = t.map(middle);
            if (b - a).cross(c - a).dot(outward) < 0.0 {
                t.swap(1, 2);
            }
            out.push(t);
        }
    }
    out
}

/// The id (`EDGES` index) of an axis edge, None for a diagonal.
fn edge_id((a, b): TetVertex) -> Option<u8> {
    let step = a ^ b;
    if step.count_ones() != 1 {
        return None;
    }
    let axis = step.trailing_zeros() as u8;
    EDGES.iter().position(|&e| e == (a, axis)).map(|i| i as u8)
}

/// Whether two edges lie on one face of the cube.
fn share_a_face(e: u8, f: u8) -> bool {
    let faces = |id: u8| {
        let (k, axis) = EDGES[id as usize];
        let c = corner(k as usize);
        (0..3)
            .filter(move |&a| a != axis as usize)
            .map(move |a| (a, c[a]))
    };
    faces(e).any(|x| faces(f).any(|y| x == y))
}

/// The smallest angle (degrees) of a triangle over edge crossings at the
/// edges' middles.
fn quality(t: [u8; 3]) -> f64 {
    let [a, b, c] = t.map(|id| {
        let (k, axis) = EDGES[id as usize];
        middle((k, k | 1 << axis))
    });
    crate::mesh::decimate::min_angle(a, b, c)
}

/// Case `mask`: marching tetrahedra's pieces rebuilt over the edges.
fn case(mask: u8) -> Case {
    let triangles = tet_triangles(mask);
    let mut out = Case::default();
    for piece in pieces(&triangles) {
        let loops = boundary_loops(&piece);
        // A piece of a closed surface inside a cube is a sphere with holes:
        // its Euler characteristic is 2 less its loops (checked, since
        // the triangulations below rest on it).
        let mut vertices: Vec<TetVertex> = piece.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let mut edges: Vec<(TetVertex, TetVertex)> = piece
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let euler = vertices.len() as i64 - edges.len() as i64 + piece.len() as i64;
        assert_eq!(
            euler,
            2 - loops.len() as i64,
            "case {mask}: a piece with a handle"
        );
        // Face-diagonal crossings dropped (the main diagonal's is never on
        // the cube's faces).
        let loops: Vec<Vec<u8>> = loops
            .iter()
            .map(|l| l.iter().filter_map(|&v| edge_id(v)).collect())
            .collect();
        match loops.as_slice() {
            [polygon] => out.add_disk(polygon),
            [a, b] => out.add_annulus(a, b, mask),
            _ => panic!("case {mask}: a piece with {} loops", loops.len()),
        }
    }
    // Each directed edge once: a strip that came back to a rung, or a
    // triangulation that joined two crossings twice, would give an edge
    // four triangles (the test holds every case to the tetrahedra's loops).
    let mut half: Vec<(u8, u8)> = out
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    half.sort_unstable();
    assert!(
        half.windows(2).all(|w| w[0] != w[1]),
        "case {mask}: an edge twice"
    );
    out
}

impl Case {
    /// A polygon's best triangulation without an edge along a cube face,
    /// or a fan from its centre where it has none.
    fn add_disk(&mut self, polygon: &[u8]) {
        let k = polygon.len();
        assert!(k >= 3, "a loop round fewer than three edges");
        let chord = |i: usize, j: usize| {
            j == i + 1 || (i == 0 && j == k - 1) || !share_a_face(polygon[i], polygon[j])
        };
        // best[i][j]: the best smallest angle over triangulations of the
        // polygon's vertices i..=j (closed by the chord i-j), and the apex
        // over chord i-j that gives it.
        let mut best = vec![vec![(f64::NEG_INFINITY, usize::MAX); k]; k];
        for i in 0..k - 1 {
            best[i][i + 1] = (f64::INFINITY, usize::MAX);
        }
        for span in 2..k {
            for i in 0..k - span {
                let j = i + span;
                if !chord(i, j) {
                    continue;
                }
                for m in i + 1..j {
                    let t = [polygon[i], polygon[m], polygon[j]];
                    let q = best[i][m].0.min(best[m][j].0).min(quality(t));
                    if q > best[i][j].0 {
                        best[i][j] = (q, m);
                    }
                }
            }
        }
        if best[0][k - 1].0 > f64::NEG_INFINITY {
            let mut spans = vec![(0, k - 1)];
            while let Some((i, j)) = spans.pop() {
                if j > i + 1 {
                    let m = best[i][j].1;
                    self.triangles.push([polygon[i], polygon[m], polygon[j]]);
                    spans.extend([(i, m), (m, j)]);
                }
            }
        } else {
            let centre = 12 + self.centres.len() as u8;
            self.centres.push(polygon.to_vec());
            for i in 0..k {
                self.triangles
                    .push([polygon[i], polygon[(i + 1) % k], centre]);
            }
        }
    }

    /// The best strip between an annulus's two loops (each in the order
    /// the piece's orientation runs it, so opposite ways round the tube)
    /// whose rungs join no two crossings of one cube face.
    fn add_annulus(&mut self, a: &[u8], b: &[u8], mask: u8) {
        let (n, m) = (a.len(), b.len());
        // b reversed runs the same way round as a.
        let b: Vec<u8> = b.iter().rev().copied().collect();
        let rung = |i: usize, j: usize| !share_a_face(a[i % n], b[j % m]);
        let mut found: Option<(f64, Vec<[u8; 3]>)> = None;
        for start in 0..m {
            if !rung(0, start) {
                continue;
            }
            // best[i][j]: the strip from rung (0, start) to rung (i,
            // start + j); each step adds a triangle on an edge of a or b.
            let mut best = vec![vec![(f64::NEG_INFINITY, false); m + 1]; n + 1];
            best[0][0] = (f64::INFINITY, false);
            for i in 0..=n {
                for j in 0..=m {
                    if (i, j) == (0, 0) || !rung(i, start + j) {
                        continue;
                    }
                    let (bj, bj1) = (b[(start + j) % m], b[(start + j + m - 1) % m]);
                    if i > 0 {
                        let t = [a[i - 1], a[i % n], bj];
                        let q = best[i - 1][j].0.min(quality(t));
                        if q > best[i][j].0 {
                            best[i][j] = (q, true);
                        }
                    }
                    if j > 0 {
                        let t = [bj, bj1, a[i % n]];
                        let q = best[i][j - 1].0.min(quality(t));
                        if q > best[i][j].0 {
                            best[i][j] = (q, false);
                        }
                    }
                }
            }
            let q = best[n][m].0;
            if q > found.as_ref().map_or(f64::NEG_INFINITY, |f| f.0) {
                let mut strip = Vec::new();
                let (mut i, mut j) = (n, m);
                while (i, j) != (0, 0) {
                    let (bj, bj1) = (b[(start + j) % m], b[(start + j + m - 1) % m]);
                    if best[i][j].1 {
                        strip.push([a[i - 1], a[i % n], bj]);
                        i -= 1;
                    } else {
                        strip.push([bj, bj1, a[i % n]]);
                        j -= 1;
                    }
                }
                found = Some((q, strip));
            }
        }
        let (_, strip) = found.unwrap_or_else(|| panic!("case {mask}: no strip"));
        self.triangles.extend(strip);
    }
}

/// The pieces of a cube's triangles: those joined by shared edges.
fn pieces(triangles: &[[TetVertex; 3]]) -> Vec<Vec<[TetVertex; 3]>> {
    let edge = |t: &[TetVertex; 3], k: usize| {
        let (x, y) = (t[k], t[(k + 1) % 3]);
        (x.min(y), x.max(y))
    };
    let mut sets = DisjointSets::new(triangles.len());
    for i in 0..triangles.len() {
        for j in 0..i {
            if (0..3).any(|k| (0..3).any(|l| edge(&triangles[i], k) == edge(&triangles[j], l))) {
                sets.union(i, j);
            }
        }
    }
    let (of_triangle, count) = sets.labels();
    let mut out = vec![Vec::new(); count];
    for (t, &p) in triangles.iter().zip(&of_triangle) {
        out[p as usize].push(*t);
    }
    out
}

/// A piece's boundary loops, each in the direction its triangles run it.
fn boundary_loops(piece: &[[TetVertex; 3]]) -> Vec<Vec<TetVertex>> {
    let half: Vec<(TetVertex, TetVertex)> = piece
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    let mut next: Vec<(TetVertex, TetVertex)> = half
        .iter()
        .filter(|&&(x, y)| !half.contains(&(y, x)))
        .copied()
        .collect();
    let mut loops = Vec::new();
    while let Some((start, mut at)) = next.pop() {
        let mut l = vec![start];
        while at != start {
            l.push(at);
            let k = next
                .iter()
                .position(|&(x, _)| x == at)
                .expect("a boundary vertex has one edge out");
            at = next.swap_remove(k).1;
        }
        loops.push(l);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_has_marching_tetrahedras_pieces_over_the_edges_alone() {
        for (mask, case) in table().iter().enumerate() {
            let tets = tet_triangles(mask as u8);
            assert_eq!(
                !pieces(&tets).is_empty(),
                !case.triangles.is_empty(),
                "case {mask}"
            );
            // Every crossed edge is used, and only those.
            let crossed = |id: u8| {
                let (k, axis) = EDGES[id as usize];
                (mask >> k & 1) != (mask >> (k | 1 << axis) & 1)
            };
            for t in &case.triangles {
                for &v in t {
                    assert!(v >= 12 || crossed(v), "case {mask}: edge {v} not crossed");
                }
            }
            for id in 0..12 {
                let used = case.triangles.iter().any(|t| t.contains(&id));
                assert_eq!(used, crossed(id), "case {mask}: edge {id}");
            }
            // Each inner edge in two triangles, opposite ways; the
            // boundary's edges run along cube faces.
            let half: Vec<(u8, u8)> = case
                .triangles
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .collect();
            let mut boundary: Vec<(u8, u8)> = Vec::new();
            for &(x, y) in &half {
                assert_eq!(
                    half.iter().filter(|&&h| h == (x, y)).count(),
                    1,
                    "case {mask}"
                );
                if !half.contains(&(y, x)) {
                    boundary.push((x, y));
                }
            }
            // The boundary is marching tetrahedra's loops, the same way
            // round, less their face-diagonal crossings.
            let mut loops: Vec<(u8, u8)> = pieces(&tets)
                .iter()
                .flat_map(|p| boundary_loops(p))
                .flat_map(|l| {
                    let l: Vec<u8> = l.iter().filter_map(|&v| edge_id(v)).collect();
                    (0..l.len()).map(move |k| (l[k], l[(k + 1) % l.len()]))
                })
                .collect();
            loops.sort_unstable();
            boundary.sort_unstable();
            assert_eq!(boundary, loops, "case {mask}");
            for (x, y) in boundary {
                assert!(share_a_face(x, y), "case {mask}: {x}-{y}");
            }
        }
    }

    #[test]
    fn complementary_cases_have_as_many_pieces() {
        let count = |m: u8| pieces(&tet_triangles(m)).len();
        for m in 0..=255u8 {
            assert_eq!(count(m), count(!m), "case {m}");
        }
    }
}
