//! Fans: the groups of faces around a vertex that are connected through the
//! edges at that vertex. A manifold vertex has exactly one fan; two cones
//! touching at their apex give it two.

use super::dsu::DisjointSets;
use super::edges::{EdgeTable, halfedge_endpoints};
use super::ids::HalfedgeId;

/// Label every corner (`3 * face + i`) with its fan. Two faces' corners at a
/// vertex join when the faces share an edge at that vertex for which
/// `joins(halfedges on the edge)` holds. Returns the labels (`0..count`, in
/// order of first corner) and their count.
pub fn corner_fans(
    triangles: &[[u32; 3]],
    edges: &EdgeTable,
    joins: impl Fn(&[HalfedgeId]) -> bool,
) -> (Vec<u32>, usize) {
    let mut sets = DisjointSets::new(triangles.len() * 3);
    let corner = |h: usize, end: usize| 3 * (h / 3) + (h % 3 + end) % 3;
    for (_, hs) in edges.iter() {
        if hs.len() < 2 || !joins(hs) {
            continue;
        }
        let first = hs[0].idx();
        let (a, _) = halfedge_endpoints(triangles, first);
        for other in &hs[1..] {
            let other = other.idx();
            let (c, _) = halfedge_endpoints(triangles, other);
            // Match the corners by vertex, whichever way `other` runs.
            let (oa, ob) = if c == a { (0, 1) } else { (1, 0) };
            sets.union(corner(first, 0), corner(other, oa));
            sets.union(corner(first, 1), corner(other, ob));
        }
    }
    sets.labels()
}

/// Give every fan its own vertex: the first fan met at a vertex keeps its
/// index, each further fan gets a new index from `num_vertices` on.
/// Rewrites `triangles` and returns, for each new index in order, the
/// vertex it was split from.
pub fn split_by_fans(
    triangles: &mut [[u32; 3]],
    num_vertices: usize,
    fan_of_corner: &[u32],
    num_fans: usize,
) -> Vec<u32> {
    let mut vertex_of_fan = vec![u32::MAX; num_fans];
    let mut claimed = vec![false; num_vertices];
    let mut split_from = Vec::new();
    for (c, &fan) in fan_of_corner.iter().enumerate() {
        let (f, i) = (c / 3, c % 3);
        let v = triangles[f][i];
        let fan = fan as usize;
        if vertex_of_fan[fan] == u32::MAX {
            vertex_of_fan[fan] = if std::mem::replace(&mut claimed[v as usize], true) {
                split_from.push(v);
                (num_vertices + split_from.len() - 1) as u32
            } else {
                v
            };
        }
        triangles[f][i] = vertex_of_fan[fan];
    }
    split_from
}
