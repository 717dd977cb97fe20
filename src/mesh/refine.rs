//! Local refinement: split marked faces one into four at their edge
//! midpoints, and their neighbours one into two so the mesh stays
//! conforming (red-green refinement, Bank, Sherman, Weiser 1983). A face
//! that would need two of its edges split is split into four too, until no
//! such face is left, so no badly shaped three-way splits appear.

use std::collections::HashMap;

use glam::DVec3;

use super::TriMesh;

/// Refine the faces marked in `marked`. New vertices are placed by
/// `midpoint(a, b)` (e.g. the plain midpoint, or one pushed back onto a
/// sphere). Facets are inherited; uvs are dropped. Returns the new mesh and
/// the parent of every new face.
pub fn refine(
    mesh: &TriMesh,
    marked: &[bool],
    midpoint: impl Fn(DVec3, DVec3) -> DVec3,
) -> (TriMesh, Vec<u32>) {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut split: std::collections::HashSet<(u32, u32)> = std::collections::HashSet::new();
    for (t, &m) in mesh.triangles.iter().zip(marked) {
        if m {
            for i in 0..3 {
                split.insert(key(t[i], t[(i + 1) % 3]));
            }
        }
    }
    // Closure: a face with two split edges gets its third split too.
    loop {
        let mut added = false;
        for t in &mesh.triangles {
            let n = (0..3)
                .filter(|&i| split.contains(&key(t[i], t[(i + 1) % 3])))
                .count();
            if n == 2 {
                for i in 0..3 {
                    added |= split.insert(key(t[i], t[(i + 1) % 3]));
                }
            }
        }
        if !added {
            break;
        }
    }
    let mut positions = mesh.positions.clone();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edges: Vec<(u32, u32)> = split.into_iter().collect();
    edges.sort_unstable();
    for (a, b) in edges {
        mid.insert((a, b), positions.len() as u32);
        positions.push(midpoint(
            mesh.positions[a as usize],
            mesh.positions[b as usize],
        ));
    }
    let mut triangles = Vec::with_capacity(mesh.num_faces() * 2);
    let mut parent = Vec::with_capacity(mesh.num_faces() * 2);
    for (f, t) in mesh.triangles.iter().enumerate() {
        let m: [Option<u32>; 3] =
            std::array::from_fn(|i| mid.get(&key(t[i], t[(i + 1) % 3])).copied());
        let children: Vec<[u32; 3]> = match m {
            [Some(ab), Some(bc), Some(ca)] => {
                vec![[t[0], ab, ca], [ab, t[1], bc], [ca, bc, t[2]], [ab, bc, ca]]
            }
            [None, None, None] => vec![*t],
            _ => {
                // Exactly one split edge (the closure left no twos): halve.
                let i = m.iter().position(Option::is_some).expect("one split edge");
                let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
                let ab = m[i].expect("split");
                vec![[a, ab, c], [ab, b, c]]
            }
        };
        parent.extend(std::iter::repeat_n(f as u32, children.len()));
        triangles.extend(children);
    }
    let mut out = TriMesh::new(positions, triangles);
    out.facets = mesh.facets.as_ref().map(|fs| super::Facets {
        names: fs.names.clone(),
        of_face: parent.iter().map(|&p| fs.of_face[p as usize]).collect(),
    });
    (out, parent)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::icosphere;
    use crate::mesh::{Components, Topology};

    #[test]
    fn refining_part_of_a_sphere_keeps_it_closed_and_manifold() {
        let sphere = icosphere(2);
        let marked: Vec<bool> = (0..sphere.num_faces())
            .map(|f| sphere.corners(f).iter().all(|p| p.z > 0.5))
            .collect();
        let (fine, parent) = refine(&sphere, &marked, |a, b| ((a + b) / 2.0).normalize());
        assert_eq!(parent.len(), fine.num_faces());
        assert!(fine.num_faces() > sphere.num_faces());
        let topo = Topology::build(&fine).expect("conforming and manifold");
        assert!(topo.boundary_loops().is_empty());
        assert_eq!(Components::find(&topo).topology(&topo)[0].genus, 0);
        assert!(fine.signed_volume() > 0.0, "orientation kept");
    }
}
