//! Non-manifold input: found, counted like MeshLab counts it, refused with
//! the first offending element named, or split into a manifold mesh.

use glam::DVec3;
use organtex::mesh::defects::Defects;
use organtex::mesh::repair::make_manifold;
use organtex::mesh::shapes::icosphere;
use organtex::mesh::{Components, Topology, TriMesh};

fn mesh(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> TriMesh {
    TriMesh::new(
        positions.iter().map(|&p| DVec3::from_array(p)).collect(),
        triangles.to_vec(),
    )
}

/// Three faces on one edge.
fn fin() -> TriMesh {
    mesh(
        &[
            [0., 0., 0.],
            [1., 0., 0.],
            [0., 1., 0.],
            [0., -1., 0.],
            [0., 0., 1.],
        ],
        &[[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    )
}

/// Two closed tetrahedra touching at one vertex.
fn bowtie() -> TriMesh {
    mesh(
        &[
            [0., 0., 0.],
            [1., 0., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [-1., 0., 0.],
            [0., -1., 0.],
            [0., 0., -1.],
        ],
        &[
            [0, 2, 1],
            [0, 1, 3],
            [0, 3, 2],
            [1, 2, 3],
            [0, 5, 4],
            [0, 4, 6],
            [0, 6, 5],
            [4, 5, 6],
        ],
    )
}

#[test]
fn counts_match_meshlab_definitions() {
    // pymeshlab on the same two meshes: fin 1 non-manifold edge and 0
    // non-manifold vertices; bowtie 0 edges, 1 vertex.
    let d = Defects::find(&fin());
    assert_eq!(
        (d.non_manifold_edges.len(), d.non_manifold_vertices.len()),
        (1, 0)
    );
    let d = Defects::find(&bowtie());
    assert_eq!(
        (d.non_manifold_edges.len(), d.non_manifold_vertices.len()),
        (0, 1)
    );
}

#[test]
fn refusal_names_the_first_offending_edge() {
    let err = Topology::build(&fin()).unwrap_err().to_string();
    assert!(
        err.contains("non-manifold edge (v0, v1) is shared by 3 faces (f0, f1, f2)"),
        "{err}"
    );
    let err = Topology::build(&bowtie()).unwrap_err().to_string();
    assert!(err.contains("non-manifold vertex v0"), "{err}");
}

#[test]
fn splitting_makes_every_broken_mesh_manifold() {
    let (fixed, report) = make_manifold(&fin());
    assert!(Topology::build(&fixed).is_ok());
    assert_eq!(report.cut_edges, 1);
    assert!(report.split_vertices >= 2);

    let (fixed, report) = make_manifold(&bowtie());
    let topo = Topology::build(&fixed).unwrap();
    assert_eq!(report.split_vertices, 1);
    assert_eq!(Components::find(&topo).count, 2);
    assert_eq!(
        fixed.positions[7], fixed.positions[0],
        "positions are never moved"
    );
}

#[test]
fn flipped_faces_are_turned_back_with_the_majority() {
    let mut sphere = icosphere(2);
    for f in [3, 10, 50] {
        sphere.triangles[f].swap(0, 1);
    }
    assert_eq!(Defects::find(&sphere).inconsistent_edges.len(), 9);
    assert!(Topology::build(&sphere).is_err());
    let (fixed, report) = make_manifold(&sphere);
    assert_eq!(report.flipped_faces, 3);
    // Same orientation as the original sphere, up to where each face starts.
    let canonical = |t: &[u32; 3]| {
        let i = (0..3).min_by_key(|&i| t[i]).unwrap();
        [t[i], t[(i + 1) % 3], t[(i + 2) % 3]]
    };
    let original = icosphere(2);
    assert!(
        fixed
            .triangles
            .iter()
            .zip(&original.triangles)
            .all(|(a, b)| canonical(a) == canonical(b))
    );
}

#[test]
fn duplicate_and_repeated_vertex_faces_are_removed() {
    let mut sphere = icosphere(1);
    let extra = sphere.triangles[5];
    sphere.triangles.push([extra[0], extra[2], extra[1]]);
    sphere.triangles.push([1, 1, 2]);
    let d = Defects::find(&sphere);
    assert_eq!(d.duplicate_faces.len(), 1);
    assert_eq!(d.repeated_vertex_faces.len(), 1);
    let err = Topology::build(&sphere).unwrap_err().to_string();
    assert!(err.contains("names the same vertex twice"), "{err}");
    let (fixed, report) = make_manifold(&sphere);
    assert_eq!(
        (
            report.removed_duplicate_faces,
            report.removed_repeated_vertex_faces
        ),
        (1, 1)
    );
    assert_eq!(fixed.triangles, icosphere(1).triangles);
}

#[test]
fn a_manifold_mesh_is_left_alone() {
    let sphere = icosphere(2);
    let (fixed, report) = make_manifold(&sphere);
    assert!(!report.changed_anything());
    assert_eq!(fixed, sphere);
}
