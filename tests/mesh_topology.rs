//! Topology of real and generated meshes: counts, components, boundary
//! loops, genus, and the half-edge invariants every later stage relies on.

use std::path::PathBuf;

use organtex::mesh::shapes::{holed_slab, icosphere, open_cylinder, torus};
use organtex::mesh::{Components, HalfedgeId, Topology, TriMesh, VertexId, io};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

struct Summary {
    components: usize,
    genus: Vec<i64>,
    boundary_loops: usize,
    boundary_edges: usize,
}

fn summarise(mesh: &TriMesh) -> Summary {
    let topo = Topology::build(mesh).expect("manifold");
    check_invariants(mesh, &topo);
    let comps = Components::find(&topo);
    Summary {
        components: comps.count,
        genus: comps.topology(&topo).iter().map(|c| c.genus).collect(),
        boundary_loops: topo.boundary_loops().len(),
        boundary_edges: topo.boundary_loops().iter().map(Vec::len).sum(),
    }
}

/// The half-edge structure must be self-consistent for every element.
fn check_invariants(mesh: &TriMesh, topo: &Topology) {
    for h in 0..topo.num_halfedges() {
        let h = HalfedgeId::from(h);
        assert_eq!(topo.next(topo.prev(h)), h);
        assert_eq!(topo.next(topo.next(topo.next(h))), h);
        if let Some(t) = topo.twin(h) {
            assert_eq!(topo.twin(t), Some(h));
            assert_eq!(topo.origin(t), topo.tip(h));
            assert_eq!(topo.edge(t), topo.edge(h));
        }
        let [a, b] = topo.edge_vertices(topo.edge(h));
        assert!([a, b] == [topo.origin(h), topo.tip(h)] || [b, a] == [topo.origin(h), topo.tip(h)]);
    }
    let mut seen = 0;
    for v in 0..mesh.num_vertices() {
        let v = VertexId::from(v);
        for h in topo.outgoing(v) {
            assert_eq!(topo.origin(h), v);
            seen += 1;
        }
    }
    assert_eq!(
        seen,
        topo.num_halfedges(),
        "the fans visit every half-edge once"
    );
    for cycle in topo.boundary_loops() {
        for (i, &h) in cycle.iter().enumerate() {
            assert!(topo.twin(h).is_none());
            let next = cycle[(i + 1) % cycle.len()];
            assert_eq!(
                topo.tip(h),
                topo.origin(next),
                "boundary loops are ordered cycles"
            );
            assert!(topo.is_boundary_vertex(topo.origin(h)));
        }
    }
}

#[test]
fn bunny_is_one_closed_genus_zero_piece() {
    let mesh = io::read(&data("bunny.obj")).unwrap();
    assert_eq!(mesh.num_vertices(), 28_088);
    assert_eq!(mesh.num_faces(), 56_172);
    let s = summarise(&mesh);
    assert_eq!(s.components, 1);
    assert_eq!(s.boundary_loops, 0);
    assert_eq!(s.genus, vec![0]);
}

#[test]
fn textured_bunny_has_five_holes_and_keeps_its_uv_atlas() {
    let mesh = io::read(&data("bunny10k_textured.obj")).unwrap();
    // pymeshlab: 5051 vertices, 9999 faces, 109 boundary edges, 5 holes.
    assert_eq!(mesh.num_vertices(), 5_051);
    assert_eq!(mesh.num_faces(), 9_999);
    let s = summarise(&mesh);
    assert_eq!(
        (s.components, s.boundary_loops, s.boundary_edges),
        (1, 5, 109)
    );
    assert_eq!(s.genus, vec![0]);
    let uv = mesh.uvs.as_ref().expect("the file has vt");
    assert_eq!(uv.coords.len(), 6_451);
    assert!(
        uv.triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < uv.coords.len())
    );
    let facets = mesh
        .facets
        .as_ref()
        .expect("the file has a group and a material");
    assert_eq!(facets.names, vec!["objdefault/01_-_Default".to_string()]);
}

#[test]
fn cube_is_closed_with_unit_volume() {
    let mesh = io::read(&data("cube.obj")).unwrap();
    let s = summarise(&mesh);
    assert_eq!(
        (s.components, s.boundary_loops, s.genus.clone()),
        (1, 0, vec![0])
    );
    assert!((mesh.signed_volume() - 1.0).abs() < 1e-12);
}

#[test]
fn torus_has_genus_one() {
    let s = summarise(&torus(1.0, 0.3, 48, 16));
    assert_eq!((s.components, s.boundary_loops, s.genus), (1, 0, vec![1]));
}

#[test]
fn slabs_have_one_handle_per_hole() {
    for holes in 0..4 {
        let mesh = holed_slab(holes, 3, 4);
        assert!(mesh.signed_volume() > 0.0, "normals point outwards");
        let s = summarise(&mesh);
        assert_eq!(s.genus, vec![holes as i64], "slab with {holes} holes");
        assert_eq!(s.boundary_loops, 0);
    }
}

#[test]
fn open_cylinder_has_two_boundary_loops() {
    let s = summarise(&open_cylinder(1.0, 2.0, 32, 8));
    assert_eq!(
        (s.components, s.boundary_loops, s.boundary_edges),
        (1, 2, 64)
    );
    assert_eq!(s.genus, vec![0]);
}

#[test]
fn icosphere_is_a_closed_outward_sphere() {
    let mesh = icosphere(3);
    assert!(mesh.signed_volume() > 0.0);
    let s = summarise(&mesh);
    assert_eq!((s.components, s.boundary_loops, s.genus), (1, 0, vec![0]));
}

#[test]
fn separate_pieces_are_separate_components() {
    let mut mesh = torus(1.0, 0.3, 24, 8);
    let sphere = icosphere(1);
    let offset = mesh.num_vertices() as u32;
    mesh.positions
        .extend(sphere.positions.iter().map(|p| *p + glam::DVec3::X * 5.0));
    mesh.triangles
        .extend(sphere.triangles.iter().map(|t| t.map(|v| v + offset)));
    let s = summarise(&mesh);
    assert_eq!(s.components, 2);
    assert_eq!(s.genus, vec![1, 0]);
}
