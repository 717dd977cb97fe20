//! Seam bands (seed 004, section 3.5): along every seam of a chart, the
//! triangles up to k rings away on each side are drawn a second time with
//! the texture coordinates continued from across the seam, vertex alpha 0.5
//! on the seam falling to 0 at the band's edge. At the seam both sides then
//! show the same half-and-half mix of the two parametrisations, so the
//! texture is continuous across it, and each side fades back to its own.
//! The half-and-half holds over the first ring too (`band_alpha`), so the
//! faces along the seam are mixed evenly right up to it, and the fade eases
//! in and out.
//!
//! Continuing the coordinates from across a seam edge (a, b): the two faces
//! on it give a and b one uv on each side; the similarity (rotation, scale,
//! shift) taking this side's uvs of a and b to the other side's takes every
//! nearby uv of this side to where the other side's chart would have put it.
//! Each band face uses the seam edge nearest to it.

use std::collections::VecDeque;

use glam::DVec2;

use crate::mesh::{HalfedgeId, Topology, TriMesh};
use crate::unwrap::metrics::seam_edges;

/// A face drawn again over itself with continued texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct BandFace {
    /// The face (of the chart's mesh) it covers.
    pub face: u32,
    pub uv: [DVec2; 3],
    pub alpha: [f32; 3],
}

/// The seam bands of `mesh`'s uv layer, `rings` rings wide (0: none).
pub fn seam_bands(mesh: &TriMesh, topo: &Topology, rings: usize) -> Vec<BandFace> {
    let Some(layer) = mesh.uvs.as_ref() else {
        return Vec::new();
    };
    if rings == 0 {
        return Vec::new();
    }
    let seams = seam_edges(topo, layer);
    let mut is_seam = vec![false; topo.num_edges()];
    for e in &seams {
        is_seam[e.idx()] = true;
    }
    let uv = |h: HalfedgeId| layer.coords[layer.triangles[h.idx() / 3][h.idx() % 3] as usize];

    // Rings of vertices from the seams.
    let mut ring = vec![usize::MAX; mesh.num_vertices()];
    let mut queue = VecDeque::new();
    for &e in &seams {
        for v in topo.edge_vertices(e) {
            if ring[v.idx()] != 0 {
                ring[v.idx()] = 0;
                queue.push_back(v);
            }
        }
    }
    while let Some(v) = queue.pop_front() {
        for h in topo.outgoing(v) {
            for u in [topo.tip(h), topo.origin(topo.prev(h))] {
                if ring[u.idx()] == usize::MAX && ring[v.idx()] < rings {
                    ring[u.idx()] = ring[v.idx()] + 1;
                    queue.push_back(u);
                }
            }
        }
    }

    // Faces reached from each side of each seam edge without crossing a
    // seam, each keeping the similarity of the seam edge it came from. A
    // face on two seam edges whose far sides differ (between two branches
    // of the cut at a junction) can continue only one far side: it takes
    // the edge whose far side lies farthest off in the texture, so the step
    // left on the other is the smaller one (on a branch one edge long to a
    // terminal, whose sides meet at its tip, it falls to nothing there; on
    // the default scene's polyp, the edge left unblended had been the
    // main cut's and showed its whole step).
    let mut reached: Vec<Option<(DVec2, DVec2, DVec2, DVec2)>> = vec![None; mesh.num_faces()];
    let mut apart = vec![0.0; mesh.num_faces()];
    let mut faces = VecDeque::new();
    for &e in &seams {
        let h = topo.edge_halfedge(e);
        let t = topo.twin(h).expect("seams are interior edges");
        for (this, other) in [(h, t), (t, h)] {
            // `this` runs a -> b in its face; `other` runs b -> a in its own.
            let (a_here, b_here) = (uv(this), uv(topo.next(this)));
            let (b_there, a_there) = (uv(other), uv(topo.next(other)));
            let f = topo.face(this).idx();
            if a_here == b_here {
                continue;
            }
            let gap = (a_there - a_here).length() + (b_there - b_here).length();
            if reached[f].is_none() {
                faces.push_back(f);
            } else if gap <= apart[f] {
                continue;
            }
            reached[f] = Some((a_here, b_here, a_there, b_there));
            apart[f] = gap;
        }
    }
    while let Some(f) = faces.pop_front() {
        for h in topo.face_halfedges(crate::mesh::FaceId::from(f)) {
            let Some(t) = topo.twin(h) else { continue };
            let g = topo.face(t).idx();
            let near = mesh.triangles[g].iter().any(|&v| ring[v as usize] < rings);
            if !is_seam[topo.edge(h).idx()] && reached[g].is_none() && near {
                reached[g] = reached[f];
                faces.push_back(g);
            }
        }
    }

    // Where a seam vertex sits on the far side of the seam, seen from face
    // `f`: turn around it from `f`, not crossing ordinary edges' faces'
    // uvs, until the first seam edge, and read its uv in the face across.
    let across = |f: usize, v: u32| -> Option<DVec2> {
        let start = topo
            .face_halfedges(crate::mesh::FaceId::from(f))
            .into_iter()
            .find(|&h| topo.origin(h).0 == v)?;
        let mut h = start;
        for _ in 0..64 {
            // The edge entering v in h's face, crossed to the face beyond.
            let t = topo.twin(topo.prev(h))?;
            if is_seam[topo.edge(t).idx()] {
                return Some(uv(t));
            }
            h = t;
            if h == start {
                return None;
            }
        }
        None
    };
    let mut band = Vec::new();
    for (f, r) in reached.iter().enumerate() {
        let Some((a_here, b_here, a_there, b_there)) = *r else {
            continue;
        };
        let scale = complex_div(b_there - a_there, b_here - a_here);
        let continued = |z: DVec2| a_there + complex_mul(z - a_here, scale);
        let corners = layer.triangles[f].map(|c| layer.coords[c as usize]);
        // Corners on the seam take the far side's uv exactly (a face with
        // two seam edges is continued across both); the rest by the
        // similarity of the face's seam edge.
        let uv = std::array::from_fn(|i| {
            let v = mesh.triangles[f][i];
            let on_edge = corners[i] == a_here || corners[i] == b_here;
            match (ring[v as usize] == 0 && !on_edge)
                .then(|| across(f, v))
                .flatten()
            {
                Some(exact) => exact,
                None => continued(corners[i]),
            }
        });
        let alpha = mesh.triangles[f].map(|v| band_alpha(ring[v as usize], rings));
        band.push(BandFace {
            face: f as u32,
            uv,
            alpha,
        });
    }
    band
}

/// Band alpha of a vertex `ring` rings from the seam, for bands `rings`
/// wide: 1/2 on the seam and (for bands of two rings or more) on the first
/// ring, then a smoothstep down to 0 at the band's edge.
pub fn band_alpha(ring: usize, rings: usize) -> f32 {
    let plateau = usize::from(rings >= 2);
    if ring <= plateau {
        return 0.5;
    }
    let t = ((ring - plateau) as f32 / (rings - plateau) as f32).min(1.0);
    0.5 * (1.0 - t * t * (3.0 - 2.0 * t))
}

fn complex_mul(a: DVec2, b: DVec2) -> DVec2 {
    DVec2::new(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x)
}

fn complex_div(a: DVec2, b: DVec2) -> DVec2 {
    let d = b.length_squared();
    DVec2::new((a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::icosphere;
    use crate::progress::Silent;
    use crate::unwrap::{UnwrapOptions, unwrap};

    /// At every seam edge, each side's band continues the other side's
    /// parametrisation exactly: the band's uvs of the edge's ends are the
    /// far side's own uvs, and its alpha there is one half.
    #[test]
    fn bands_continue_the_far_side_exactly_at_the_seam() {
        let sphere = icosphere(3);
        let u = unwrap(&sphere, &UnwrapOptions::default(), &Silent).unwrap();
        let layer = u.mesh.uvs.as_ref().unwrap();
        let band = seam_bands(&u.mesh, &u.topology, 2);
        let by_face: std::collections::HashMap<u32, &BandFace> =
            band.iter().map(|b| (b.face, b)).collect();
        let seams = seam_edges(&u.topology, layer);
        assert!(!seams.is_empty());
        let corner = |f: usize, v: u32| u.mesh.triangles[f].iter().position(|&w| w == v).unwrap();
        // At a junction of three or more seam edges a face between two of
        // them can continue only one far side: left out.
        let mut seam_degree = vec![0; u.mesh.num_vertices()];
        for &e in &seams {
            for v in u.topology.edge_vertices(e) {
                seam_degree[v.idx()] += 1;
            }
        }
        for e in seams.clone() {
            let h = u.topology.edge_halfedge(e);
            let t = u.topology.twin(h).unwrap();
            for (here, there) in [(h, t), (t, h)] {
                let (f, g) = (u.topology.face(here).idx(), u.topology.face(there).idx());
                let b = by_face
                    .get(&(f as u32))
                    .expect("faces on a seam are in the band");
                for v in u.topology.edge_vertices(e).map(|v| v.0) {
                    if seam_degree[v as usize] > 2 {
                        continue;
                    }
                    let far = layer.coords[layer.triangles[g][corner(g, v)] as usize];
                    let mine = b.uv[corner(f, v)];
                    assert!(
                        (far - mine).length() < 1e-9,
                        "edge {e:?} face {f} vertex {v} tri {:?} ends {:?}: {mine} vs {far}; seam edges of f: {:?}",
                        u.mesh.triangles[f],
                        u.topology.edge_vertices(e),
                        u.topology
                            .face_halfedges(crate::mesh::FaceId::from(f))
                            .map(|h| seam_edges(&u.topology, layer).contains(&u.topology.edge(h)))
                    );
                    assert_eq!(b.alpha[corner(f, v)], 0.5);
                }
            }
        }
        // Alpha falls to 0 at the band's edge.
        assert!(band.iter().any(|b| b.alpha.contains(&0.0)));
    }

    /// A face on two seam edges whose far sides differ (between two
    /// branches of the cut at a junction) continues the edge whose far side
    /// lies farther off, exactly at both its ends: the step it must leave
    /// on the other edge is the smaller one.
    #[test]
    fn a_face_between_two_branches_continues_the_wider_seam() {
        let sphere = icosphere(3);
        let u = unwrap(&sphere, &UnwrapOptions::default(), &Silent).unwrap();
        let (topo, layer) = (&u.topology, u.mesh.uvs.as_ref().unwrap());
        let band = seam_bands(&u.mesh, topo, 2);
        let seams = seam_edges(topo, layer);
        let uv = |h: HalfedgeId| layer.coords[layer.triangles[h.idx() / 3][h.idx() % 3] as usize];
        let mut sectors = 0;
        for b in &band {
            let f = crate::mesh::FaceId::from(b.face as usize);
            // Its seam edges: the far side's uvs of their ends, and how far
            // off they lie.
            let far: Vec<([DVec2; 2], f64)> = topo
                .face_halfedges(f)
                .into_iter()
                .filter(|&h| seams.contains(&topo.edge(h)))
                .map(|h| {
                    let t = topo.twin(h).unwrap();
                    let there = [uv(topo.next(t)), uv(t)];
                    let gap = (there[0] - uv(h)).length() + (there[1] - uv(topo.next(h))).length();
                    (there, gap)
                })
                .collect();
            if far.len() < 2
                || far.iter().all(|(there, _)| {
                    // Far sides that agree at the shared corner: a bend.
                    far.iter()
                        .all(|(other, _)| other.iter().any(|p| there.contains(p)))
                })
            {
                continue;
            }
            sectors += 1;
            let (there, gap) = far
                .iter()
                .copied()
                .find(|(there, _)| there.iter().all(|p| b.uv.contains(p)))
                .expect("one seam edge continued exactly");
            assert!(
                far.iter().all(|&(_, g)| g <= gap),
                "face {}: {far:?}",
                b.face
            );
            assert!(there.iter().all(|p| b.uv.contains(p)));
        }
        assert!(
            sectors > 0,
            "the sphere's cut has no face between two branches"
        );
    }
}
