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

/// Smooth the border of a region of faces: a face with at least two of its
/// three neighbours on the other side of the border changes side, until
/// none does (or after `rounds` passes); faces for which `frozen` holds
/// never change. Removes the spikes and notches a region picked face by
/// face has, which a flattening folds over (`unwrap::overlap`). Faces
/// change one at a time, in order, each change shortening the border, so it
/// settles and the result depends on nothing but the input.
pub fn smooth_region(
    topo: &super::Topology,
    region: &mut [bool],
    frozen: impl Fn(usize) -> bool,
    rounds: usize,
) {
    for _ in 0..rounds {
        let mut changed = false;
        for f in 0..region.len() {
            if frozen(f) {
                continue;
            }
            let other = topo
                .face_halfedges(FaceId::from(f))
                .iter()
                .filter_map(|&h| topo.twin(h))
                .filter(|&t| region[topo.face(t).idx()] != region[f])
                .count();
            if other >= 2 {
                region[f] = !region[f];
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Topology;
    use crate::mesh::shapes::icosphere;

    #[test]
    fn smoothing_removes_spikes_and_keeps_frozen_faces() {
        let sphere = icosphere(3);
        let topo = Topology::build(&sphere).unwrap();
        // A cap, then one face sticking out of it (a spike: two of its
        // neighbours outside).
        let mut region: Vec<bool> = (0..sphere.num_faces())
            .map(|f| sphere.corners(f).iter().all(|p| p.z > 0.5))
            .collect();
        let spike = (0..sphere.num_faces())
            .find(|&f| {
                !region[f]
                    && topo
                        .face_halfedges(FaceId::from(f))
                        .iter()
                        .filter(|&&h| region[topo.face(topo.twin(h).unwrap()).idx()])
                        .count()
                        == 1
            })
            .unwrap();
        region[spike] = true;
        let cap = region.clone();
        smooth_region(&topo, &mut region, |_| false, 8);
        assert!(!region[spike]);
        // No face is left with two neighbours across the border.
        for f in 0..region.len() {
            let across = topo
                .face_halfedges(FaceId::from(f))
                .iter()
                .filter(|&&h| region[topo.face(topo.twin(h).unwrap()).idx()] != region[f])
                .count();
            assert!(across < 2, "face {f}");
        }
        let mut frozen_region = cap.clone();
        smooth_region(&topo, &mut frozen_region, |f| f == spike, 8);
        assert!(frozen_region[spike]);
    }
}
