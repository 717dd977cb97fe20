//! Facet submeshes with overlap rings (seed 004, section 3.5): each facet
//! is unwrapped and textured on its own, together with a ring of the facets
//! before it, over which its texture fades out (vertex alpha 1 on the facet
//! to 0 at the ring's outer edge), so differing tissues meet with no
//! visible border. Facets listed later blend over those listed before them:
//! a myoma over the uterine wall.
//!
//! The fade starts a third of the way out and eases in and out
//! (`ring_alpha`): the faces along the facet's border are covered fully, so
//! the border itself shows no step, and the tissue change is spread over the
//! ring with no crease where the fade begins or ends.

use crate::mesh::graph::{EdgeGraph, ShortestPaths};
use crate::mesh::repair::make_manifold_traced;
use crate::mesh::submesh::{extract, smooth_region};
use crate::mesh::{FaceId, Topology, TriMesh, VertexId};

/// One facet's submesh: its own faces first, then its ring.
#[derive(Clone, Debug)]
pub struct FacetPiece {
    pub facet: u32,
    /// Manifold (repaired if the facet pinched); positions as in the node.
    pub mesh: TriMesh,
    /// Node vertex of every piece vertex.
    pub vertex_origin: Vec<u32>,
    /// Node face of every piece face.
    pub face_origin: Vec<u32>,
    /// The first `own` faces are the facet's own, the rest its ring.
    pub own: usize,
    /// Per piece vertex: 1 on the facet, falling to 0 across the ring.
    pub alpha: Vec<f32>,
}

impl FacetPiece {
    /// Corner `i` of piece face `f` is corner `order[i]` of its face in
    /// `node_mesh`.
    pub fn corner_order(&self, node_mesh: &TriMesh, f: usize) -> [usize; 3] {
        let node_face = node_mesh.triangles[self.face_origin[f] as usize];
        self.mesh.triangles[f].map(|v| {
            let origin = self.vertex_origin[v as usize];
            node_face
                .iter()
                .position(|&n| n == origin)
                .expect("a piece face is its node face")
        })
    }
}

/// Alpha at distance `d` from the facet, for a ring `width` wide: 1 up to a
/// third of the width, then a smoothstep down to 0 at the width.
pub fn ring_alpha(d: f64, width: f64) -> f32 {
    let t = ((d / width - 1.0 / 3.0) * 1.5).clamp(0.0, 1.0);
    (1.0 - t * t * (3.0 - 2.0 * t)) as f32
}

/// The pieces of every facet of `mesh` (which must have facets), with
/// rings `overlap[facet]` wide (mesh units, along edges).
pub fn facet_pieces(mesh: &TriMesh, topo: &Topology, overlap: &[f64]) -> Vec<FacetPiece> {
    let facets = mesh.facets.as_ref().expect("a node mesh has facets");
    let graph = EdgeGraph::new(topo);
    let length = graph.lengths(&mesh.positions);
    (0..facets.names.len() as u32)
        .filter(|&f| facets.of_face.contains(&f))
        .map(|facet| {
            let own: Vec<FaceId> = (0..mesh.num_faces())
                .filter(|&g| facets.of_face[g] == facet)
                .map(FaceId::from)
                .collect();
            let width = overlap[facet as usize];
            let (ring, distance) = if width > 0.0 {
                let sources: Vec<(VertexId, u32)> = own
                    .iter()
                    .flat_map(|f| mesh.triangles[f.idx()])
                    .map(|v| (VertexId(v), 0))
                    .collect();
                let d = ShortestPaths::from_sources(&graph, &length, &sources).distance;
                // Faces of earlier facets within reach, the ring's outer
                // border smoothed (no spikes or notches to fold over when
                // the piece is flattened).
                let mut region: Vec<bool> = (0..mesh.num_faces())
                    .map(|g| {
                        facets.of_face[g] == facet
                            || (facets.of_face[g] < facet
                                && mesh.triangles[g].iter().any(|&v| d[v as usize] < width))
                    })
                    .collect();
                smooth_region(topo, &mut region, |g| facets.of_face[g] >= facet, 16);
                let ring: Vec<FaceId> = (0..mesh.num_faces())
                    .filter(|&g| region[g] && facets.of_face[g] < facet)
                    .map(FaceId::from)
                    .collect();
                (ring, d)
            } else {
                (Vec::new(), vec![0.0; mesh.num_vertices()])
            };
            let faces: Vec<FaceId> = own.iter().chain(&ring).copied().collect();
            let (sub, sub_origin) = extract(mesh, &faces);
            let repaired = make_manifold_traced(&sub);
            let vertex_origin: Vec<u32> = repaired
                .vertex_origin
                .iter()
                .map(|&v| sub_origin[v as usize])
                .collect();
            let face_origin: Vec<u32> = repaired
                .face_origin
                .iter()
                .map(|&f| faces[f as usize].0)
                .collect();
            let own_count = repaired
                .face_origin
                .iter()
                .filter(|&&f| (f as usize) < own.len())
                .count();
            let alpha = vertex_origin
                .iter()
                .map(|&v| {
                    if width > 0.0 {
                        ring_alpha(distance[v as usize], width)
                    } else {
                        1.0
                    }
                })
                .collect();
            FacetPiece {
                facet,
                mesh: repaired.mesh,
                vertex_origin,
                face_origin,
                own: own_count,
                alpha,
            }
        })
        .collect()
}
