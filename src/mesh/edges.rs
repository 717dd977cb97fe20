//! Undirected edges of a triangle soup, each with every half-edge lying on it.
//!
//! This is the one place that pairs half-edges. Defect detection, repair and
//! the half-edge topology all read it, so they agree on what an edge is even
//! for broken input (an edge with three faces, two faces running the same way).

use super::ids::{EdgeId, HalfedgeId};

/// Half-edge `h` is corner `h % 3` of face `h / 3` running to the next corner.
#[inline]
pub fn halfedge_endpoints(triangles: &[[u32; 3]], h: usize) -> (u32, u32) {
    let t = &triangles[h / 3];
    (t[h % 3], t[(h % 3 + 1) % 3])
}

/// All half-edges grouped by the undirected edge they lie on.
pub struct EdgeTable {
    /// Half-edges sorted by (min vertex, max vertex).
    sorted: Vec<HalfedgeId>,
    /// `sorted[starts[e]..starts[e + 1]]` are the half-edges of edge `e`.
    starts: Vec<u32>,
    /// The edge each half-edge lies on.
    edge_of: Vec<EdgeId>,
}

impl EdgeTable {
    pub fn new(triangles: &[[u32; 3]]) -> Self {
        let key = |h: usize| {
            let (a, b) = halfedge_endpoints(triangles, h);
            ((a.min(b) as u64) << 32) | a.max(b) as u64
        };
        let mut keyed: Vec<(u64, u32)> = (0..triangles.len() * 3)
            .map(|h| (key(h), h as u32))
            .collect();
        // Sorting the (key, half-edge) pairs keeps runs in half-edge order, so
        // the table, and everything numbered from it, is deterministic.
        keyed.sort_unstable();
        let mut starts = Vec::with_capacity(keyed.len() / 2 + 1);
        for (i, &(k, _)) in keyed.iter().enumerate() {
            if i == 0 || keyed[i - 1].0 != k {
                starts.push(i as u32);
            }
        }
        starts.push(keyed.len() as u32);
        let mut edge_of = vec![EdgeId(0); keyed.len()];
        for e in 0..starts.len() - 1 {
            for &(_, h) in &keyed[starts[e] as usize..starts[e + 1] as usize] {
                edge_of[h as usize] = EdgeId(e as u32);
            }
        }
        EdgeTable {
            sorted: keyed.into_iter().map(|(_, h)| HalfedgeId(h)).collect(),
            starts,
            edge_of,
        }
    }

    /// The edge half-edge `h` lies on.
    #[inline]
    pub fn edge_of(&self, h: HalfedgeId) -> EdgeId {
        self.edge_of[h.idx()]
    }

    pub fn num_edges(&self) -> usize {
        self.starts.len() - 1
    }

    /// The half-edges on edge `e`, in increasing id order.
    #[inline]
    pub fn halfedges(&self, e: EdgeId) -> &[HalfedgeId] {
        &self.sorted[self.starts[e.idx()] as usize..self.starts[e.idx() + 1] as usize]
    }

    pub fn iter(&self) -> impl Iterator<Item = (EdgeId, &[HalfedgeId])> {
        (0..self.num_edges()).map(move |e| (EdgeId::from(e), self.halfedges(EdgeId::from(e))))
    }
}
