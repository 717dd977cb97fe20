//! Half-edge topology of a manifold, consistently oriented triangle mesh.
//!
//! Half-edges are implicit in the triangle array: half-edge `h` is corner
//! `h % 3` of face `h / 3` running to the next corner, so `next`, `prev`,
//! `face` and `origin` cost nothing to store. Only `twin` is a table; a
//! half-edge on the boundary has none. There are no explicit boundary
//! half-edges: a boundary loop is the cycle of twinless half-edges, in order.
//!
//! Invariants after `Topology::build`: every edge has one or two half-edges,
//! and two only when they run in opposite directions; the faces around every
//! vertex form one fan; `vertex_halfedge[v]` is the first outgoing half-edge
//! of that fan (for a boundary vertex, the one whose `prev` is twinless), so
//! `outgoing(v)` visits the whole fan.

use super::defects::{Defects, is_repeated};
use super::edges::EdgeTable;
use super::ids::{EdgeId, FaceId, HalfedgeId, VertexId};
use super::trimesh::TriMesh;
use crate::error::{Error, Result};

const NONE: u32 = u32::MAX;

#[derive(Clone, Debug)]
pub struct Topology {
    origin: Vec<VertexId>,
    twin: Vec<u32>,
    edge_of: Vec<EdgeId>,
    edge_halfedge: Vec<HalfedgeId>,
    vertex_halfedge: Vec<u32>,
    boundary_loops: Vec<Vec<HalfedgeId>>,
}

impl Topology {
    /// Build the topology, or fail naming the first element it cannot hold
    /// (see `Defects`); `repair::make_manifold` splits those first.
    pub fn build(mesh: &TriMesh) -> Result<Topology> {
        let edges = EdgeTable::new(&mesh.triangles);
        let fail = || {
            let d = Defects::find_with(mesh, &edges);
            Error::NotManifold {
                path: None,
                first: d
                    .first_blocking()
                    .unwrap_or_else(|| "the mesh is not manifold".into()),
                summary: d.blocking_summary(),
            }
        };
        if mesh.triangles.iter().any(is_repeated) {
            return Err(fail());
        }
        let origin: Vec<VertexId> = mesh
            .triangles
            .iter()
            .flat_map(|t| t.iter().map(|&v| VertexId(v)))
            .collect();
        let nh = origin.len();
        let mut twin = vec![NONE; nh];
        let mut edge_halfedge = Vec::with_capacity(edges.num_edges());
        for (_, hs) in edges.iter() {
            match *hs {
                [h] => edge_halfedge.push(h),
                [g, h] if origin[g.idx()] != origin[h.idx()] => {
                    twin[g.idx()] = h.0;
                    twin[h.idx()] = g.0;
                    edge_halfedge.push(g);
                }
                _ => return Err(fail()),
            }
        }
        let edge_of = (0..nh)
            .map(|h| edges.edge_of(HalfedgeId::from(h)))
            .collect();

        let mut topo = Topology {
            origin,
            twin,
            edge_of,
            edge_halfedge,
            vertex_halfedge: vec![NONE; mesh.num_vertices()],
            boundary_loops: Vec::new(),
        };
        let mut degree = vec![0u32; mesh.num_vertices()];
        for h in 0..nh {
            let h = HalfedgeId::from(h);
            let v = topo.origin(h).idx();
            degree[v] += 1;
            if topo.vertex_halfedge[v] == NONE || topo.twin(topo.prev(h)).is_none() {
                topo.vertex_halfedge[v] = h.0;
            }
        }
        // One fan per vertex: the rotation from the first half-edge must meet
        // every outgoing half-edge.
        for (v, &d) in degree.iter().enumerate() {
            if d > 0 && topo.outgoing(VertexId::from(v)).count() != d as usize {
                return Err(fail());
            }
        }
        topo.boundary_loops = topo.trace_boundary_loops();
        Ok(topo)
    }

    pub fn num_halfedges(&self) -> usize {
        self.origin.len()
    }
    pub fn num_faces(&self) -> usize {
        self.origin.len() / 3
    }
    pub fn num_edges(&self) -> usize {
        self.edge_halfedge.len()
    }
    pub fn num_vertices(&self) -> usize {
        self.vertex_halfedge.len()
    }

    #[inline]
    pub fn next(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(h.0 - h.0 % 3 + (h.0 % 3 + 1) % 3)
    }
    #[inline]
    pub fn prev(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId(h.0 - h.0 % 3 + (h.0 % 3 + 2) % 3)
    }
    #[inline]
    pub fn twin(&self, h: HalfedgeId) -> Option<HalfedgeId> {
        let t = self.twin[h.idx()];
        (t != NONE).then_some(HalfedgeId(t))
    }
    #[inline]
    pub fn origin(&self, h: HalfedgeId) -> VertexId {
        self.origin[h.idx()]
    }
    /// The vertex `h` points to.
    #[inline]
    pub fn tip(&self, h: HalfedgeId) -> VertexId {
        self.origin[self.next(h).idx()]
    }
    #[inline]
    pub fn face(&self, h: HalfedgeId) -> FaceId {
        FaceId(h.0 / 3)
    }
    #[inline]
    pub fn edge(&self, h: HalfedgeId) -> EdgeId {
        self.edge_of[h.idx()]
    }
    /// A half-edge of edge `e` (its only one on the boundary).
    #[inline]
    pub fn edge_halfedge(&self, e: EdgeId) -> HalfedgeId {
        self.edge_halfedge[e.idx()]
    }
    /// The faces on either side of edge `e`; `None` on the boundary.
    #[inline]
    pub fn edge_faces(&self, e: EdgeId) -> Option<[FaceId; 2]> {
        let h = self.edge_halfedge(e);
        self.twin(h).map(|t| [self.face(h), self.face(t)])
    }
    #[inline]
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.twin(self.edge_halfedge(e)).is_none()
    }
    /// The two end vertices of edge `e`.
    pub fn edge_vertices(&self, e: EdgeId) -> [VertexId; 2] {
        let h = self.edge_halfedge(e);
        [self.origin(h), self.tip(h)]
    }
    /// The three half-edges of face `f`, in order.
    #[inline]
    pub fn face_halfedges(&self, f: FaceId) -> [HalfedgeId; 3] {
        [
            HalfedgeId(3 * f.0),
            HalfedgeId(3 * f.0 + 1),
            HalfedgeId(3 * f.0 + 2),
        ]
    }

    /// The half-edges leaving `v`, each next one across the previous one's
    /// twin; for a boundary vertex from one boundary edge to the other.
    /// Empty for an unreferenced vertex.
    pub fn outgoing(&self, v: VertexId) -> Outgoing<'_> {
        let start = self.vertex_halfedge[v.idx()];
        Outgoing {
            topo: self,
            start,
            current: start,
        }
    }

    /// The edge joining `a` and `b`, if any: a walk round both fans, so
    /// O(valence) and no edge map to build.
    pub fn edge_between(&self, a: VertexId, b: VertexId) -> Option<EdgeId> {
        // At a boundary vertex the fan misses the one boundary edge that ends
        // there, so look from both ends.
        self.outgoing(a)
            .find(|&h| self.tip(h) == b)
            .or_else(|| self.outgoing(b).find(|&h| self.tip(h) == a))
            .map(|h| self.edge(h))
    }

    /// Whether `v` lies on a boundary loop (unreferenced vertices do not).
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        let h = self.vertex_halfedge[v.idx()];
        h != NONE && self.twin(self.prev(HalfedgeId(h))).is_none()
    }

    pub fn is_referenced(&self, v: VertexId) -> bool {
        self.vertex_halfedge[v.idx()] != NONE
    }

    /// Boundary loops, each the cycle of its twinless half-edges in order
    /// (each one's tip is the next one's origin).
    pub fn boundary_loops(&self) -> &[Vec<HalfedgeId>] {
        &self.boundary_loops
    }

    fn trace_boundary_loops(&self) -> Vec<Vec<HalfedgeId>> {
        let mut seen = vec![false; self.num_halfedges()];
        let mut loops = Vec::new();
        for start in 0..self.num_halfedges() {
            let start = HalfedgeId::from(start);
            if seen[start.idx()] || self.twin(start).is_some() {
                continue;
            }
            let mut cycle = Vec::new();
            let mut h = start;
            loop {
                seen[h.idx()] = true;
                cycle.push(h);
                // Rotate around the tip to its twinless outgoing half-edge.
                let mut g = self.next(h);
                while let Some(t) = self.twin(g) {
                    g = self.next(t);
                }
                h = g;
                if h == start {
                    break;
                }
            }
            loops.push(cycle);
        }
        loops
    }
}

/// Iterator of `Topology::outgoing`.
pub struct Outgoing<'a> {
    topo: &'a Topology,
    start: u32,
    current: u32,
}

impl Iterator for Outgoing<'_> {
    type Item = HalfedgeId;
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.current == NONE {
            return None;
        }
        let h = HalfedgeId(self.current);
        self.current = match self.topo.twin(h) {
            Some(t) => {
                let n = self.topo.next(t).0;
                if n == self.start { NONE } else { n }
            }
            None => NONE,
        };
        Some(h)
    }
}
