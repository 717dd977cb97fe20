//! What is wrong with a triangle soup, found without building a topology:
//! non-manifold edges and vertices, faces run the wrong way round, repeated
//! and zero-area faces, duplicate faces, unreferenced vertices.
//!
//! Definitions follow MeshLab/vcglib so `organtex info` and pymeshlab count
//! the same things: an edge is non-manifold when more than two faces share it;
//! a vertex is non-manifold when it lies on no non-manifold edge and its faces
//! form more than one fan. On top of vcglib we count edges that two faces run
//! in the same direction (inconsistent orientation), which a half-edge
//! structure cannot represent either.

use serde::Serialize;

use super::edges::{EdgeTable, halfedge_endpoints};
use super::fans::corner_fans;
use super::ids::{FaceId, VertexId};
use super::trimesh::TriMesh;

/// An edge and the faces on it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EdgeFaces {
    pub vertices: [VertexId; 2],
    pub faces: Vec<FaceId>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Defects {
    /// Faces naming one vertex twice (never usable).
    pub repeated_vertex_faces: Vec<FaceId>,
    /// Faces of zero area, the repeated-vertex ones included.
    pub degenerate_faces: Vec<FaceId>,
    /// Pairs (earlier face, later face) over the same three vertices.
    pub duplicate_faces: Vec<[FaceId; 2]>,
    /// Edges with more than two faces.
    pub non_manifold_edges: Vec<EdgeFaces>,
    /// Edges with two faces that run them in the same direction.
    pub inconsistent_edges: Vec<EdgeFaces>,
    /// Vertices whose faces form several fans (and that lie on no
    /// non-manifold edge).
    pub non_manifold_vertices: Vec<VertexId>,
    pub unreferenced_vertices: Vec<VertexId>,
}

/// A face is degenerate when its area is below this fraction of the square
/// of its longest edge: exactly collinear corners give ~1e-17 in f64.
const DEGENERATE_RATIO: f64 = 1e-12;

pub fn is_repeated(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[2] == t[0]
}

pub fn is_degenerate(mesh: &TriMesh, f: usize) -> bool {
    let t = &mesh.triangles[f];
    if is_repeated(t) {
        return true;
    }
    let [a, b, c] = mesh.corners(f);
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    mesh.face_area_vector(f).length() <= DEGENERATE_RATIO * longest
}

impl Defects {
    pub fn find(mesh: &TriMesh) -> Defects {
        Self::find_with(mesh, &EdgeTable::new(&mesh.triangles))
    }

    pub fn find_with(mesh: &TriMesh, edges: &EdgeTable) -> Defects {
        let tris = &mesh.triangles;
        let mut d = Defects::default();
        for (f, t) in tris.iter().enumerate() {
            if is_repeated(t) {
                d.repeated_vertex_faces.push(FaceId::from(f));
            }
            if is_degenerate(mesh, f) {
                d.degenerate_faces.push(FaceId::from(f));
            }
        }
        d.duplicate_faces = duplicate_faces(tris);

        let face_of = |h: &super::ids::HalfedgeId| FaceId::from(h.idx() / 3);
        let mut on_bad_edge = vec![false; mesh.num_vertices()];
        for (_, hs) in edges.iter() {
            let (a, b) = halfedge_endpoints(tris, hs[0].idx());
            if a == b {
                continue; // an edge of a repeated-vertex face, reported above
            }
            let faces = || EdgeFaces {
                vertices: [VertexId(a.min(b)), VertexId(a.max(b))],
                faces: hs.iter().map(face_of).collect(),
            };
            if hs.len() > 2 {
                d.non_manifold_edges.push(faces());
                on_bad_edge[a as usize] = true;
                on_bad_edge[b as usize] = true;
            } else if hs.len() == 2 && halfedge_endpoints(tris, hs[1].idx()).0 == a {
                d.inconsistent_edges.push(faces());
            }
        }

        let usable = |hs: &[super::ids::HalfedgeId]| {
            hs.len() == 2 && hs.iter().all(|h| !is_repeated(&tris[h.idx() / 3]))
        };
        let (fan_of_corner, num_fans) = corner_fans(tris, edges, usable);
        let mut fans_at = vec![0u32; mesh.num_vertices()];
        let mut counted = vec![false; num_fans];
        let mut referenced = vec![false; mesh.num_vertices()];
        for (c, &fan) in fan_of_corner.iter().enumerate() {
            let v = tris[c / 3][c % 3] as usize;
            referenced[v] = true;
            if !counted[fan as usize] && !is_repeated(&tris[c / 3]) {
                counted[fan as usize] = true;
                fans_at[v] += 1;
            }
        }
        for v in 0..mesh.num_vertices() {
            if !referenced[v] {
                d.unreferenced_vertices.push(VertexId::from(v));
            } else if fans_at[v] > 1 && !on_bad_edge[v] {
                d.non_manifold_vertices.push(VertexId::from(v));
            }
        }
        d
    }

    /// The first defect that a half-edge topology cannot represent, as a
    /// sentence naming the element, or `None` when the mesh is manifold.
    pub fn first_blocking(&self) -> Option<String> {
        let faces = |fs: &[FaceId]| {
            fs.iter()
                .map(|f| f.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if let Some(f) = self.repeated_vertex_faces.first() {
            return Some(format!("face {f} names the same vertex twice"));
        }
        if let Some(e) = self.non_manifold_edges.first() {
            let dup = self
                .duplicate_faces
                .iter()
                .find(|[a, b]| e.faces.contains(a) && e.faces.contains(b))
                .map(|[a, b]| format!("; {a} and {b} are duplicates"))
                .unwrap_or_default();
            return Some(format!(
                "non-manifold edge ({}, {}) is shared by {} faces ({}){dup}",
                e.vertices[0],
                e.vertices[1],
                e.faces.len(),
                faces(&e.faces)
            ));
        }
        if let Some(e) = self.inconsistent_edges.first() {
            return Some(format!(
                "faces {} run edge ({}, {}) in the same direction (inconsistent orientation)",
                faces(&e.faces),
                e.vertices[0],
                e.vertices[1]
            ));
        }
        if let Some(v) = self.non_manifold_vertices.first() {
            return Some(format!(
                "non-manifold vertex {v}: its faces form separate fans that touch only at it"
            ));
        }
        None
    }

    /// One line counting every blocking defect, for error messages.
    pub fn blocking_summary(&self) -> String {
        format!(
            "{} non-manifold edges, {} inconsistently oriented edges, {} non-manifold vertices, {} faces with a repeated vertex",
            self.non_manifold_edges.len(),
            self.inconsistent_edges.len(),
            self.non_manifold_vertices.len(),
            self.repeated_vertex_faces.len()
        )
    }
}

/// Pairs of faces over the same vertex set, (first, later), whatever their
/// orientation.
fn duplicate_faces(tris: &[[u32; 3]]) -> Vec<[FaceId; 2]> {
    let mut keyed: Vec<([u32; 3], u32)> = tris
        .iter()
        .enumerate()
        .map(|(f, t)| {
            let mut k = *t;
            k.sort_unstable();
            (k, f as u32)
        })
        .collect();
    keyed.sort_unstable();
    let mut out = Vec::new();
    let mut i = 0;
    while i < keyed.len() {
        let mut j = i + 1;
        while j < keyed.len() && keyed[j].0 == keyed[i].0 {
            out.push([FaceId(keyed[i].1), FaceId(keyed[j].1)]);
            j += 1;
        }
        i = j;
    }
    out.sort_unstable_by_key(|p| p[1]);
    out
}
