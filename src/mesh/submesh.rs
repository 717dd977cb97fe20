//! Pieces of a mesh as meshes of their own.

use super::{FaceId, TriMesh};

/// The faces `faces` of `mesh` as a mesh of their own, vertices renumbered
/// in order of first use; also returns the original vertex of each new one.
/// Facets and uvs are not carried over.
pub fn extract(mesh: &TriMesh, faces: &[FaceId]) -> (TriMesh, Vec<u32>) {
    let mut new_index = vec![u32::MAX; mesh.num_vertices()];
    let mut origin = Vec::new();
    let triangles = faces
        .iter()
        .map(|f| {
            mesh.triangles[f.idx()].map(|v| {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = origin.len() as u32;
                    origin.push(v);
                }
                new_index[v as usize]
            })
        })
        .collect();
    let positions = origin.iter().map(|&v| mesh.positions[v as usize]).collect();
    (TriMesh::new(positions, triangles), origin)
}
