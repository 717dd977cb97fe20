//! Tetrahedral meshes of organ interiors (issue 21): isosurface stuffing
//! driven by the generalized winding number, on every mesh in tests/data
//! and on small unclean meshes made here.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::DVec3;
use organtex::mesh::{TriMesh, io::read, shapes::icosphere};
use organtex::progress::Silent;
use organtex::tetra::{self, MAX_DIHEDRAL, MIN_DIHEDRAL, Quality, TetMesh, TetOptions};

fn data_meshes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/data")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|e| {
                ["obj", "ply", "stl"].contains(&e.to_string_lossy().to_ascii_lowercase().as_str())
            })
        })
        .collect();
    paths.sort();
    paths
}

/// Every edge in exactly two faces.
fn is_closed(mesh: &TriMesh) -> bool {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count.values().all(|&c| c == 2)
}

/// The properties every stuffed mesh must have: the proven dihedral bounds
/// (asserted exactly), positive volumes, a valid complex.
fn check_valid(name: &str, m: &TetMesh) -> Quality {
    assert!(m.num_tets() > 0, "{name}: no tets");
    let q = m.quality();
    assert!(
        q.min_dihedral >= MIN_DIHEDRAL && q.max_dihedral <= MAX_DIHEDRAL,
        "{name}: dihedral angles {:.3} to {:.3} degrees, outside the proven [{MIN_DIHEDRAL}, {MAX_DIHEDRAL}]",
        q.min_dihedral,
        q.max_dihedral
    );
    assert!(
        q.min_volume > 0.0,
        "{name}: a tet of volume {}",
        q.min_volume
    );
    m.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
    m.face_adjacency().unwrap_or_else(|e| panic!("{name}: {e}"));
    q
}

fn vtk_round_trip(name: &str, m: &TetMesh) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("m.vtk");
    tetra::io::write(&path, m).expect("write vtk");
    let back = tetra::io::read_vtk(&path).expect("read vtk");
    assert!(back == *m, "{name}: the .vtk round trip changed the mesh");
}

#[test]
fn every_test_mesh_is_stuffed_within_the_proven_angles() {
    let paths = data_meshes();
    assert!(paths.len() >= 3, "{paths:?}");
    for path in paths {
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mesh = read(&path).expect("mesh");
        let start = Instant::now();
        let (m, report) = tetra::tetrahedralise_report(&mesh, &TetOptions::default(), &Silent)
            .expect("tetrahedralise");
        let seconds = start.elapsed().as_secs_f64();
        let q = check_valid(&name, &m);
        let h = report
            .hausdorff
            .expect("the default resolution measures it");
        let closed = is_closed(&mesh);
        let volume_error = (m.volume() - mesh.signed_volume()) / mesh.signed_volume();
        println!(
            "{name}: {} tets, {} vertices, h = {:.4} ({} tries), dihedral {:.2}-{:.2} deg, \
             Hausdorff {:.3}% of the diagonal (boundary->surface {:.3}%, surface->boundary {:.3}%), \
             volume {}, {seconds:.2} s",
            m.num_tets(),
            m.num_vertices(),
            report.edge_length,
            report.attempts,
            q.min_dihedral,
            q.max_dihedral,
            100.0 * h.relative(),
            100.0 * h.boundary_to_surface / h.diagonal,
            100.0 * h.surface_to_boundary / h.diagonal,
            if closed {
                format!("{:+.3}%", 100.0 * volume_error)
            } else {
                "n/a (open)".into()
            },
        );
        if closed {
            assert!(
                h.relative() <= 0.01,
                "{name}: Hausdorff distance {:.3}% of the diagonal",
                100.0 * h.relative()
            );
            assert!(
                volume_error.abs() <= 0.02,
                "{name}: volume off by {:.3}%",
                100.0 * volume_error
            );
        } else {
            // A solid's boundary must span the holes of an open input, and
            // the middle of that cap is about a hole's radius from the
            // input (bunny10k: 3.5% of the diagonal at every edge length
            // tried, diagonal/40 to /80): no mesh of the inside meets 1%
            // that way. The other way, every point of the input is within
            // 1% of the boundary.
            assert!(
                h.surface_to_boundary <= 0.01 * h.diagonal,
                "{name}: input to boundary {:.3}% of the diagonal",
                100.0 * h.surface_to_boundary / h.diagonal
            );
        }
        vtk_round_trip(&name, &m);
    }
}

fn unit(seed: u64, k: u64) -> f64 {
    organtex::rng::unit(seed, &[k])
}

/// Cubes, octahedra and icosahedra, randomly turned, stretched and placed
/// on the lattice, with random edge lengths: sharp corners and edges warp
/// lattice vertices in every direction. Seeds 1067 and 1700 went below the
/// bound (10.66 and 10.30 degrees) before warping passed over cut points
/// whose other end is violated too.
#[test]
fn randomly_placed_polyhedra_keep_the_proven_angles() {
    let cube =
        read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj")).expect("cube");
    let shapes = [cube, icosphere(0), icosphere(1)];
    let (mut min, mut max) = (180.0f64, 0.0f64);
    for seed in (0..300u64).chain([1067, 1700]) {
        let shape = &shapes[(seed % 3) as usize];
        let axis = DVec3::new(
            unit(seed, 1) - 0.5,
            unit(seed, 2) - 0.5,
            unit(seed, 3) - 0.5,
        )
        .normalize();
        let turn = glam::DMat3::from_axis_angle(axis, unit(seed, 4) * std::f64::consts::TAU);
        let stretch = DVec3::new(
            0.5 + unit(seed, 5),
            0.5 + unit(seed, 6),
            0.5 + unit(seed, 7),
        );
        let offset = DVec3::new(unit(seed, 8), unit(seed, 9), unit(seed, 10));
        let mesh = TriMesh::new(
            shape
                .positions
                .iter()
                .map(|&p| turn * (p * stretch) + offset)
                .collect(),
            shape.triangles.clone(),
        );
        let opts = TetOptions {
            edge_length: Some(0.08 + 0.25 * unit(seed, 11)),
            cells: None,
            ..Default::default()
        };
        let m = tetra::tetrahedralise(&mesh, &opts, &Silent)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let q = check_valid(&format!("seed {seed}"), &m);
        min = min.min(q.min_dihedral);
        max = max.max(q.max_dihedral);
    }
    println!("random polyhedra: dihedral angles {min:.2} to {max:.2} degrees");
}

fn sphere(centre: DVec3, radius: f64) -> TriMesh {
    let mut s = icosphere(4);
    for p in &mut s.positions {
        *p = centre + radius * *p;
    }
    s
}

fn concat(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let n = a.num_vertices() as u32;
    let mut positions = a.positions.clone();
    positions.extend(&b.positions);
    let mut triangles = a.triangles.clone();
    triangles.extend(b.triangles.iter().map(|t| t.map(|v| v + n)));
    TriMesh::new(positions, triangles)
}

#[test]
fn two_interpenetrating_spheres_give_their_union() {
    let (r, d) = (1.0, 1.2);
    let mesh = concat(&sphere(DVec3::ZERO, r), &sphere(DVec3::new(d, 0.0, 0.0), r));
    let m = tetra::tetrahedralise(&mesh, &TetOptions::default(), &Silent).expect("union");
    check_valid("two spheres", &m);
    // Union of two unit balls at distance d: two balls less the lens.
    let ball = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let lens = std::f64::consts::PI * (4.0 * r + d) * (2.0 * r - d).powi(2) / 12.0;
    let union = 2.0 * ball - lens;
    let error = (m.volume() - union) / union;
    println!(
        "two spheres: {} tets, volume error {:+.3}%",
        m.num_tets(),
        100.0 * error
    );
    assert!(
        error.abs() < 0.02,
        "union volume off by {:.3}%",
        100.0 * error
    );
}

#[test]
fn a_duplicated_shell_is_filled_once() {
    let one = sphere(DVec3::new(0.1, -0.2, 0.3), 1.0);
    let two = concat(&one, &one);
    let opts = TetOptions {
        edge_length: Some(0.08),
        cells: None,
        ..Default::default()
    };
    let single = tetra::tetrahedralise(&one, &opts, &Silent).expect("single");
    let double = tetra::tetrahedralise(&two, &opts, &Silent).expect("double");
    check_valid("duplicated shell", &double);
    // Inside is w = 2 instead of 1, outside still 0, and the doubled
    // triangles meet each lattice edge at the same point: the same mesh.
    assert!(double == single, "a duplicated shell changed the mesh");
}

#[test]
fn a_sphere_with_a_small_hole_is_still_filled() {
    let closed = sphere(DVec3::ZERO, 1.0);
    let mut holed = closed.clone();
    holed.triangles.retain(|t| {
        let c = t
            .iter()
            .map(|&v| closed.positions[v as usize])
            .sum::<DVec3>()
            / 3.0;
        c.z < 0.97
    });
    assert!(holed.num_faces() < closed.num_faces());
    let opts = TetOptions {
        edge_length: Some(0.08),
        cells: None,
        ..Default::default()
    };
    let whole = tetra::tetrahedralise(&closed, &opts, &Silent).expect("closed");
    let m = tetra::tetrahedralise(&holed, &opts, &Silent).expect("holed");
    check_valid("holed sphere", &m);
    let error = (m.volume() - whole.volume()) / whole.volume();
    println!(
        "holed sphere: {} tets, volume {:+.3}% against the closed sphere",
        m.num_tets(),
        100.0 * error
    );
    assert!(
        error.abs() < 0.01,
        "the hole changed the volume by {:.3}%",
        100.0 * error
    );
}

#[test]
fn bad_input_gives_clear_errors() {
    let opts = TetOptions::default();
    let message = |mesh: &TriMesh, opts: &TetOptions| {
        tetra::tetrahedralise(mesh, opts, &Silent)
            .expect_err("must be refused")
            .to_string()
    };
    let e = message(&TriMesh::default(), &opts);
    assert!(e.contains("empty mesh"), "{e}");

    let sheet = TriMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let e = message(&sheet, &opts);
    assert!(e.contains("no inside"), "{e}");

    let mut nan = icosphere(1);
    nan.positions[3].y = f64::NAN;
    let e = message(&nan, &opts);
    assert!(
        e.contains("vertex 3") && e.contains("not a finite number"),
        "{e}"
    );

    let ball = icosphere(2);
    let tiny = TetOptions {
        edge_length: Some(1e-6),
        cells: None,
        ..Default::default()
    };
    let e = message(&ball, &tiny);
    assert!(e.contains("needs about") && e.contains("GiB"), "{e}");

    for bad in [0.0, -1.0, f64::NAN] {
        let e = message(
            &ball,
            &TetOptions {
                edge_length: Some(bad),
                cells: None,
                ..Default::default()
            },
        );
        assert!(e.contains("positive number"), "{e}");
    }
    let e = message(
        &ball,
        &TetOptions {
            edge_length: Some(0.1),
            cells: Some(1000),
            ..Default::default()
        },
    );
    assert!(e.contains("not both"), "{e}");
}

#[test]
fn same_bytes_on_any_thread_count() {
    let mesh =
        read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny10k_textured.obj"))
            .expect("mesh");
    let opts = TetOptions {
        edge_length: None,
        cells: Some(30_000),
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| tetra::tetrahedralise(&mesh, &opts, &Silent).expect("tetrahedralise"))
    };
    let one = run(1);
    assert!(run(3) == one, "3 threads gave another mesh than 1");
}

/// TetGen 5.7 s for 174,388 tets on this bunny (issue 21's measurements).
#[test]
fn bunny_at_tetgens_tet_count() {
    let mesh =
        read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.obj")).expect("bunny");
    let opts = TetOptions {
        edge_length: None,
        cells: Some(174_388),
        ..Default::default()
    };
    let start = Instant::now();
    let (m, report) = tetra::tetrahedralise_report(&mesh, &opts, &Silent).expect("bunny");
    let seconds = start.elapsed().as_secs_f64();
    let q = check_valid("bunny", &m);
    let start = Instant::now();
    let h = m.hausdorff(&mesh);
    let hausdorff_seconds = start.elapsed().as_secs_f64();
    let opts = TetOptions {
        edge_length: Some(report.edge_length),
        cells: None,
        ..Default::default()
    };
    let start = Instant::now();
    let again = tetra::tetrahedralise(&mesh, &opts, &Silent).expect("bunny");
    let single = start.elapsed().as_secs_f64();
    assert!(again == m);
    println!(
        "bunny: {} tets, {} vertices, h = {:.5}, dihedral {:.2}-{:.2} deg, Hausdorff {:.3}% ({hausdorff_seconds:.2} s), \
         volume {:+.3}%, {seconds:.2} s for {} lattices, {single:.2} s for one (TetGen: 5.7 s, 174,388 tets, 1.40-178.45 deg)",
        m.num_tets(),
        m.num_vertices(),
        report.edge_length,
        q.min_dihedral,
        q.max_dihedral,
        100.0 * h.relative(),
        100.0 * (m.volume() - mesh.signed_volume()) / mesh.signed_volume(),
        report.attempts,
    );
    let ratio = m.num_tets() as f64 / 174_388.0;
    assert!((0.85..1.15).contains(&ratio), "{} tets", m.num_tets());
}

/// `organtex tetra` through the command line: each format written and the
/// figures printed as JSON agree with the file; bad arguments and a mesh
/// with no inside are one clear error each, with nothing written.
#[test]
fn the_cli_writes_each_format_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let cube = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_organtex"))
            .arg("tetra")
            .args(args)
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    for ext in ["vtk", "msh", "mesh"] {
        let out = dir.path().join(format!("cube.{ext}"));
        let (ok, stdout, stderr) = run(&[
            cube.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--cells",
            "3000",
            "--json",
        ]);
        assert!(ok, "{stderr}");
        let figures: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        let tets = figures["tets"].as_u64().unwrap();
        assert!((2000..=4000).contains(&tets), "{tets} tets for about 3000");
        assert!(figures["min_dihedral"].as_f64().unwrap() >= MIN_DIHEDRAL);
        assert!(figures["max_dihedral"].as_f64().unwrap() <= MAX_DIHEDRAL);
        if ext == "vtk" {
            let back = tetra::io::read_vtk(&out).unwrap();
            assert_eq!(back.num_tets() as u64, tets);
        }
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    let sheet = dir.path().join("sheet.obj");
    std::fs::write(
        &sheet,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let out = dir.path().join("refused.vtk");
    let o = out.to_str().unwrap();
    let c = cube.to_str().unwrap();
    for (args, expect) in [
        (vec![c, "-o", "x.stl"], "unknown tet mesh format '.stl'"),
        (
            vec![c, "-o", o, "--edge-length", "-1"],
            "'-1' is not a positive length",
        ),
        (
            vec![c, "-o", o, "--edge-length", "nan"],
            "'nan' is not a positive length",
        ),
        (
            vec![c, "-o", o, "--cells", "0"],
            "0 is not in 1..=100000000",
        ),
        (vec![c, "-o", o, "--edge-length", "1e-7"], "needs about"),
        (vec![sheet.to_str().unwrap(), "-o", o], "no inside"),
    ] {
        let (ok, _, stderr) = run(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            stderr.contains(expect),
            "{args:?}: expected `{expect}` in {stderr}"
        );
    }
    assert!(!out.exists(), "a refused run wrote its output");
}

/// The graded lattice (`--graded`) changes only the inside: along the
/// surface it is the uniform lattice, so the boundary is the same triangles
/// at the same places and the volume the same, with fewer tets, the same
/// proven angles, and the same bytes on any thread count.
#[test]
fn graded_meshes_keep_the_uniform_boundary_with_fewer_tets() {
    let mesh =
        read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.obj")).expect("mesh");
    let at = |graded: bool| TetOptions {
        edge_length: Some(0.006),
        graded,
        ..Default::default()
    };
    let uniform = tetra::tetrahedralise(&mesh, &at(false), &Silent).expect("uniform");
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| tetra::tetrahedralise(&mesh, &at(true), &Silent).expect("graded"))
    };
    let graded = run(2);
    assert!(run(1) == graded, "1 thread gave another graded mesh than 2");
    check_valid("graded bunny", &graded);
    // Cut points are interpolated from either end of their edge (by vertex
    // number), so positions agree to rounding: compare on a 1e-9 grid.
    let boundary = |m: &TetMesh| {
        let key = |v: u32| {
            m.positions[v as usize]
                .to_array()
                .map(|x| (x * 1e9).round() as i64)
        };
        let mut faces: Vec<[[i64; 3]; 3]> = m
            .boundary_triangles()
            .iter()
            .map(|t| {
                let mut f = t.map(key);
                f.sort_unstable();
                f
            })
            .collect();
        faces.sort_unstable();
        faces
    };
    let (bu, bg) = (boundary(&uniform), boundary(&graded));
    assert_eq!(bu.len(), bg.len(), "boundary triangle counts");
    let differ = bu.iter().zip(&bg).filter(|(a, b)| a != b).count();
    assert!(
        differ == 0,
        "{differ} of {} boundary triangles differ",
        bu.len()
    );
    let (vu, vg) = (uniform.volume(), graded.volume());
    assert!((vu - vg).abs() <= 1e-9 * vu, "volumes {vu} and {vg}");
    println!(
        "bunny at h = 0.006: uniform {} tets, graded {} tets ({:.2}x)",
        uniform.num_tets(),
        graded.num_tets(),
        uniform.num_tets() as f64 / graded.num_tets() as f64
    );
    assert!(graded.num_tets() * 3 < uniform.num_tets() * 2);
}
