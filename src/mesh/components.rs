//! Connected components and their topology: Euler characteristic, boundary
//! loops, genus.
//!
//! Faces are connected through shared edges (vertices alone do not join, as
//! in MeshLab). For a component with V vertices, E edges, F faces and b
//! boundary loops: chi = V - E + F and genus = (2 - chi - b) / 2.

use serde::Serialize;

use super::dsu::DisjointSets;
use super::halfedge::Topology;
use super::ids::{FaceId, HalfedgeId, VertexId};

#[derive(Clone, Debug)]
pub struct Components {
    /// Component of every face, numbered in order of first face.
    pub of_face: Vec<u32>,
    pub count: usize,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ComponentTopology {
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    pub boundary_loops: usize,
    pub euler: i64,
    pub genus: i64,
}

impl Components {
    pub fn find(topo: &Topology) -> Components {
        let mut sets = DisjointSets::new(topo.num_faces());
        for h in 0..topo.num_halfedges() {
            let h = HalfedgeId::from(h);
            if let Some(t) = topo.twin(h) {
                sets.union(topo.face(h).idx(), topo.face(t).idx());
            }
        }
        let (of_face, count) = sets.labels();
        Components { of_face, count }
    }

    /// Component of a referenced vertex.
    pub fn of_vertex(&self, topo: &Topology, v: VertexId) -> Option<u32> {
        let h = topo.outgoing(v).next()?;
        Some(self.of_face[topo.face(h).idx()])
    }

    /// Euler characteristic, boundary loops and genus of every component.
    pub fn topology(&self, topo: &Topology) -> Vec<ComponentTopology> {
        let mut out = vec![
            ComponentTopology {
                vertices: 0,
                edges: 0,
                faces: 0,
                boundary_loops: 0,
                euler: 0,
                genus: 0,
            };
            self.count
        ];
        let comp_of_halfedge = |h: HalfedgeId| self.of_face[topo.face(h).idx()] as usize;
        for f in &self.of_face {
            out[*f as usize].faces += 1;
        }
        for e in 0..topo.num_edges() {
            out[comp_of_halfedge(topo.edge_halfedge(e.into()))].edges += 1;
        }
        for v in 0..topo.num_vertices() {
            if let Some(c) = self.of_vertex(topo, VertexId::from(v)) {
                out[c as usize].vertices += 1;
            }
        }
        for cycle in topo.boundary_loops() {
            out[comp_of_halfedge(cycle[0])].boundary_loops += 1;
        }
        for c in &mut out {
            c.euler = c.vertices as i64 - c.edges as i64 + c.faces as i64;
            c.genus = (2 - c.euler - c.boundary_loops as i64) / 2;
        }
        out
    }

    /// The faces of component `c`.
    pub fn faces(&self, c: u32) -> impl Iterator<Item = FaceId> + '_ {
        self.of_face
            .iter()
            .enumerate()
            .filter(move |(_, k)| **k == c)
            .map(|(f, _)| FaceId::from(f))
    }
}
