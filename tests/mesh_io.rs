//! Readers and writers: every format gives the same mesh, OBJ round-trips
//! with uvs and facets, and writes are atomic.

use std::path::{Path, PathBuf};

use glam::DVec3;
use organtex::mesh::shapes::torus;
use organtex::mesh::{Facets, TriMesh, io};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn cube() -> TriMesh {
    io::read(&data("cube.obj")).unwrap()
}

fn ply_header(format: &str, mesh: &TriMesh) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment made by a test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face {}\nproperty list uchar int vertex_indices\nelement edge 0\nproperty int vertex1\nend_header\n",
        mesh.num_vertices(),
        mesh.num_faces()
    )
}

fn ply_binary(mesh: &TriMesh, big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = ply_header(fmt, mesh).into_bytes();
    let f32b = |x: f32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for p in &mesh.positions {
        for c in p.to_array() {
            out.extend(f32b(c as f32));
        }
        out.push(200); // red
    }
    for t in &mesh.triangles {
        out.push(3);
        for &v in t {
            out.extend(i32b(v as i32));
        }
    }
    out
}

fn ply_ascii(mesh: &TriMesh) -> Vec<u8> {
    let mut s = ply_header("ascii", mesh);
    for p in &mesh.positions {
        s += &format!("{} {} {} 200\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    s.into_bytes()
}

fn stl_binary(mesh: &TriMesh) -> Vec<u8> {
    let mut out = vec![b' '; 80];
    out.extend((mesh.num_faces() as u32).to_le_bytes());
    for f in 0..mesh.num_faces() {
        let n = mesh.face_normal(f);
        for c in std::iter::once(n).chain(mesh.corners(f)) {
            for x in c.to_array() {
                out.extend((x as f32).to_le_bytes());
            }
        }
        out.extend([0, 0]);
    }
    out
}

fn stl_ascii(mesh: &TriMesh, solids: &[(&str, std::ops::Range<usize>)]) -> Vec<u8> {
    let mut s = String::new();
    for (name, faces) in solids {
        s += &format!("solid {name}\n");
        for f in faces.clone() {
            let n = mesh.face_normal(f);
            s += &format!("  facet normal {} {} {}\n    outer loop\n", n.x, n.y, n.z);
            for p in mesh.corners(f) {
                s += &format!("      vertex {} {} {}\n", p.x, p.y, p.z);
            }
            s += "    endloop\n  endfacet\n";
        }
        s += &format!("endsolid {name}\n");
    }
    s.into_bytes()
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Same shape up to vertex order: compare triangles by their corner positions.
fn same_triangles(a: &TriMesh, b: &TriMesh) -> bool {
    let key = |m: &TriMesh| {
        let mut tris: Vec<[[i64; 3]; 3]> = (0..m.num_faces())
            .map(|f| {
                m.corners(f)
                    .map(|p| (p * 1e6).round().as_i64vec3().to_array())
            })
            .collect();
        tris.sort();
        tris
    };
    a.num_faces() == b.num_faces() && key(a) == key(b)
}

#[test]
fn ply_in_every_encoding_reads_the_same_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = torus(1.0, 0.5, 12, 6);
    let ascii = io::read(&write(dir.path(), "a.ply", &ply_ascii(&mesh))).unwrap();
    let le = io::read(&write(dir.path(), "le.ply", &ply_binary(&mesh, false))).unwrap();
    let be = io::read(&write(dir.path(), "be.ply", &ply_binary(&mesh, true))).unwrap();
    assert_eq!(le, be);
    assert_eq!(ascii.triangles, mesh.triangles);
    assert_eq!(le.triangles, mesh.triangles);
    for (p, q) in le.positions.iter().zip(&mesh.positions) {
        assert!((*p - *q).length() < 1e-6);
    }
}

#[test]
fn stl_welds_corners_and_keeps_solids_as_facets() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = cube();
    let bin = io::read(&write(dir.path(), "b.stl", &stl_binary(&mesh))).unwrap();
    assert_eq!(
        bin.num_vertices(),
        8,
        "corners welded back into the cube's 8 vertices"
    );
    assert!(same_triangles(&bin, &mesh));
    let ascii = io::read(&write(
        dir.path(),
        "a.stl",
        &stl_ascii(&mesh, &[("top", 0..4), ("rest", 4..12)]),
    ))
    .unwrap();
    assert_eq!(ascii.num_vertices(), 8);
    assert!(same_triangles(&ascii, &mesh));
    let facets = ascii.facets.unwrap();
    assert_eq!(facets.names, ["top", "rest"]);
    assert_eq!(facets.of_face.iter().filter(|&&f| f == 0).count(), 4);
}

#[test]
fn binary_stl_whose_header_starts_with_solid_is_still_binary() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = stl_binary(&cube());
    bytes[..5].copy_from_slice(b"solid");
    let mesh = io::read(&write(dir.path(), "s.stl", &bytes)).unwrap();
    assert_eq!(mesh.num_faces(), 12);
}

#[test]
fn obj_round_trips_uvs_facets_and_positions_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let original = io::read(&data("bunny10k_textured.obj")).unwrap();
    let out = dir.path().join("copy.obj");
    io::write_obj(&out, &original, Some(Path::new("tissue.png"))).unwrap();
    let back = io::read(&out).unwrap();
    // Compare field by field: a failing whole-mesh assert would print 10k faces.
    assert!(
        back.positions == original.positions,
        "positions survive bit for bit"
    );
    assert!(back.triangles == original.triangles, "triangles survive");
    assert!(back.uvs == original.uvs, "uvs survive");
    assert!(back.facets == original.facets, "facets survive");
    let mtl = std::fs::read_to_string(dir.path().join("copy.mtl")).unwrap();
    assert!(mtl.contains("map_Kd tissue.png"));
    let no_leftovers = std::fs::read_dir(dir.path())
        .unwrap()
        .all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".part"));
    assert!(no_leftovers);
}

#[test]
fn obj_polygons_groups_and_negative_indices() {
    let dir = tempfile::tempdir().unwrap();
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng floor\nusemtl wall\nf -4 -3 -2 -1\nv 0 0 1\ng roof\nf 1 2 5\nusemtl tissue\nf 2/1 3/1 5/1\n";
    let mesh = io::read(&write(dir.path(), "q.obj", text.as_bytes())).unwrap();
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 1, 4], [1, 2, 4]]
    );
    let Facets { names, of_face } = mesh.facets.unwrap();
    assert_eq!(names, ["floor/wall", "roof/wall", "roof/tissue"]);
    assert_eq!(of_face, [0, 0, 1, 2]);
    assert!(mesh.uvs.is_none(), "only some faces have uvs: no uv layer");
}

#[test]
fn failed_writes_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.txt");
    let result = organtex::atomic::write_file(&target, |w| {
        w.write_all(b"half of it")?;
        Err(std::io::Error::other("disk full"))
    });
    assert!(result.is_err());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let missing = dir.path().join("no/such/dir/out.obj");
    let mesh = TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]);
    let err = io::write_obj(&missing, &mesh, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("no/such/dir/out.obj"), "{err}");
}
