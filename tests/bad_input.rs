//! Bad input through the CLI: each case must exit non-zero with one clear
//! message naming the file and what is wrong, never panic, and leave no
//! output behind.

mod common;
use common::organtex;
use std::path::{Path, PathBuf};
use std::process::Command;

struct Case {
    name: &'static str,
    file: &'static str,
    content: Option<Vec<u8>>,
    /// Text the error must contain (besides the file name).
    expect: &'static str,
}

fn case(name: &'static str, file: &'static str, content: &[u8], expect: &'static str) -> Case {
    Case {
        name,
        file,
        content: Some(content.to_vec()),
        expect,
    }
}

fn binary_stl_claiming(triangles: u32, actual: usize) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend(triangles.to_le_bytes());
    b.extend(vec![0u8; actual * 50]);
    b
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "missing file",
            file: "nowhere.obj",
            content: None,
            expect: "No such file",
        },
        case("empty file", "empty.obj", b"", "the file is empty"),
        case(
            "truncated obj",
            "trunc.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2",
            "line 4: a face needs at least 3 vertices, this one has 2",
        ),
        case(
            "truncated vertex",
            "trunc_v.obj",
            b"v 0 0 0\nv 1 0",
            "line 2: a vertex needs 3 coordinates, found 2",
        ),
        case(
            "non-numeric coordinate",
            "text.obj",
            b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n",
            "line 2: vertex coordinate 'zero' is not a number",
        ),
        case(
            "NaN coordinate",
            "nan.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n",
            "line 3: vertex coordinate 'NaN' is not a finite number",
        ),
        case(
            "infinite coordinate",
            "inf.obj",
            b"v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n",
            "line 2: vertex coordinate 'inf' is not a finite number",
        ),
        case(
            "face index out of range",
            "range.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "line 4: face refers to vertex 9 but the file defines only 3 vertices",
        ),
        case(
            "face index zero",
            "zero.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "line 4: vertex index 0 is invalid (OBJ indices start at 1)",
        ),
        case(
            "relative index before the start",
            "relative.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -7\n",
            "line 4: relative vertex index -7 reaches before the first vertex",
        ),
        case(
            "malformed face vertex",
            "slash.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2 3\n",
            "line 4: malformed face vertex '1/'",
        ),
        case(
            "PLY header claiming 10^12 vertices",
            "huge.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\x00\x00\x00\x00",
            "declares 1000000000000 vertex elements",
        ),
        case(
            "wrong PLY magic",
            "magic.ply",
            b"plx\nformat ascii 1.0\nend_header\n",
            "not a PLY file",
        ),
        case(
            "truncated binary PLY",
            "short.ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n\x00\x00\x00\x00",
            "need at least 24 bytes, but only 4 bytes",
        ),
        case(
            "PLY face index out of range",
            "index.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
            "face 0: vertex index 7 is out of range (the file has 3 vertices)",
        ),
        case(
            "PLY NaN coordinate",
            "nan.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
            "line 11: vertex 1: coordinate y is NaN",
        ),
        case(
            "wrong STL magic",
            "junk.stl",
            b"GIF89a not a mesh",
            "not an STL file",
        ),
        case(
            "binary STL size disagrees with its triangle count",
            "count.stl",
            &binary_stl_claiming(10, 3),
            "declares 10 triangles, which take 584 bytes, but the file has 234 bytes",
        ),
        case(
            "ascii STL without endsolid",
            "open.stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n",
            "the file ends inside a solid",
        ),
        case(
            "non-manifold edge",
            "fin.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            "non-manifold edge (v0, v1) is shared by 3 faces (f0, f1, f2)",
        ),
        case(
            "all-degenerate mesh",
            "flat.obj",
            b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n",
            "all 2 faces have zero area",
        ),
        case(
            "vertices but no faces",
            "cloud.obj",
            b"v 0 0 0\nv 1 0 0\n",
            "no faces: the file holds 2 vertices",
        ),
        case(
            "unknown file extension",
            "mesh.xyz",
            b"0 0 0\n",
            "unknown mesh format '.xyz' (organtex reads .obj, .ply, .stl)",
        ),
    ]
}

fn check_refused(name: &str, path: &Path, expect: &str, args: &[&str]) {
    let (ok, stdout, stderr) = organtex(args);
    assert!(!ok, "{name}: exit code 0\n{stdout}");
    assert!(!stderr.contains("panicked"), "{name}: panic\n{stderr}");
    let file = path.display().to_string();
    assert!(
        stderr.contains(&file),
        "{name}: the error does not name {file}:\n{stderr}"
    );
    assert!(
        stderr.contains(expect),
        "{name}: expected `{expect}` in:\n{stderr}"
    );
    assert_eq!(
        stderr.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{name}: one error\n{stderr}"
    );
}

#[test]
fn every_bad_input_gets_one_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let all = cases();
    assert!(all.len() >= 15);
    for c in &all {
        let path = dir.path().join(c.file);
        if let Some(bytes) = &c.content {
            std::fs::write(&path, bytes).unwrap();
        }
        check_refused(c.name, &path, c.expect, &["info", path.to_str().unwrap()]);
    }
}

#[test]
fn a_directory_is_not_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    check_refused(
        "directory",
        &folder,
        "is a directory",
        &["info", folder.to_str().unwrap()],
    );
}

#[test]
fn non_manifold_input_is_repaired_on_request() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fin.obj");
    std::fs::write(
        &path,
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let (ok, stdout, stderr) = organtex(&["info", "--repair", "--json", path.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["defects"]["non_manifold_edges"], 1);
    assert_eq!(report["repair"]["cut_edges"], 1);
    assert_eq!(report["components"], 3, "three fins once the edge is split");
}

#[test]
fn failed_curvature_export_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj");
    let target = dir.path().join("missing/k.csv");
    let (ok, _, stderr) = organtex(&[
        "info",
        bunny.to_str().unwrap(),
        "--curvature-out",
        target.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(stderr.contains("missing/k.csv"), "{stderr}");
    assert!(!target.exists());
}

#[test]
fn unwrap_refuses_bad_input_clearly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let fin = dir.path().join("fin.obj");
    std::fs::write(
        &fin,
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let out = dir.path().join("out.obj");
    let cube = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj");
    let (f, o, c) = (
        fin.to_str().unwrap(),
        out.to_str().unwrap(),
        cube.to_str().unwrap(),
    );

    check_refused(
        "non-manifold unwrap",
        &fin,
        "non-manifold edge (v0, v1)",
        &["unwrap", f, "-o", o],
    );
    let (_, _, stderr) = organtex(&["unwrap", f, "-o", o]);
    assert!(stderr.contains("--repair"), "{stderr}");

    let cameras = dir.path().join("cams.txt");
    std::fs::write(&cameras, b"# endoscope\n0 0 0\n1 two 3\n").unwrap();
    let cams = cameras.to_str().unwrap();
    check_refused(
        "bad camera file",
        &cameras,
        "line 3: '1 two 3' is not three finite numbers",
        &["unwrap", c, "-o", o, "--cameras", cams],
    );
    std::fs::write(&cameras, b"0 0\n").unwrap();
    check_refused(
        "short camera line",
        &cameras,
        "line 1: expected a camera position 'x y z', found 2 numbers",
        &["unwrap", c, "-o", o, "--cameras", cams],
    );

    let (ok, _, stderr) = organtex(&["unwrap", c, "-o", o, "--max-stretch", "0"]);
    assert!(
        !ok && stderr.contains("--max-stretch must be a positive number"),
        "{stderr}"
    );
    let (ok, _, stderr) = organtex(&["unwrap", c, "-o", o, "--max-conformal", "0.9"]);
    assert!(
        !ok && stderr.contains("--max-conformal must be a number of at least 1"),
        "{stderr}"
    );

    let nowhere = dir.path().join("missing/out.obj");
    check_refused(
        "output folder missing",
        &nowhere,
        "No such file",
        &["unwrap", c, "-o", nowhere.to_str().unwrap()],
    );
    assert!(!out.exists(), "nothing was written by the failed runs");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        leftovers
            .iter()
            .all(|n| !n.to_string_lossy().ends_with(".part")),
        "{leftovers:?}"
    );

    // With --repair the same fin unwraps: three fins, three charts.
    let (ok, stdout, stderr) = organtex(&["unwrap", f, "-o", o, "--repair"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("3 charts, 0 flips"), "{stdout}");
}

#[test]
fn unwrap_gives_the_same_bytes_on_one_or_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny10k_textured.obj");
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("uv{threads}.obj"));
        let status = Command::new(env!("CARGO_BIN_EXE_organtex"))
            .args([
                "unwrap",
                bunny.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(status.status.success());
        outputs.push(std::fs::read(out).unwrap());
    }
    assert!(
        outputs[0] == outputs[1],
        "same uvs whatever the thread count"
    );
}

#[test]
fn synthesis_refuses_bad_input_clearly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let gravel = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database/sources/gravel.png");
    let g = gravel.to_str().unwrap();
    let out = d("out.png");
    let o = out.to_str().unwrap();

    std::fs::write(d("junk.png"), b"this is not an image").unwrap();
    // A PNG header claiming a 0 x 0 image.
    let mut empty = vec![
        0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, b'I', b'H', b'D', b'R',
    ];
    empty.extend([0, 0, 0, 0, 0, 0, 0, 0, 8, 2, 0, 0, 0, 0, 0, 0, 0]);
    std::fs::write(d("empty.png"), &empty).unwrap();
    image::GrayImage::new(10, 10)
        .save(d("small_mask.png"))
        .unwrap();
    image::GrayImage::new(512, 512)
        .save(d("black_mask.png"))
        .unwrap();

    let path = |n: &str| d(n).to_str().unwrap().to_string();
    let cases: Vec<(&str, PathBuf, &str, Vec<String>)> = vec![
        (
            "missing image",
            d("nowhere.png"),
            "No such file",
            vec!["synth".into(), path("nowhere.png")],
        ),
        (
            "unreadable image",
            d("junk.png"),
            "cannot read the image",
            vec!["synth".into(), path("junk.png")],
        ),
        (
            "zero-size image",
            d("empty.png"),
            "cannot read the image",
            vec!["synth".into(), path("empty.png")],
        ),
        (
            "mask of another size",
            d("small_mask.png"),
            "the mask is 10x10 but the image",
            vec![
                "synth".into(),
                g.into(),
                "--mask".into(),
                path("small_mask.png"),
            ],
        ),
        (
            "mask hiding everything",
            d("black_mask.png"),
            "the mask hides every pixel",
            vec![
                "synth".into(),
                g.into(),
                "--mask".into(),
                path("black_mask.png"),
            ],
        ),
        (
            "crop outside the image",
            gravel.clone(),
            "the crop 100x100 at (450, 0) lies outside the 512x512 image",
            vec![
                "synth".into(),
                g.into(),
                "--crop".into(),
                "450,0,100,100".into(),
            ],
        ),
    ];
    for (name, file, expect, mut args) in cases {
        args.extend(["--size".into(), "64".into(), "-o".into(), o.into()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        check_refused(name, &file, expect, &args);
    }
    for size in ["0", "20000x64"] {
        let (ok, _, stderr) = organtex(&["synth", g, "--size", size, "-o", o]);
        assert!(
            !ok && stderr.contains("outside 1..16384 pixels a side"),
            "{size}: {stderr}"
        );
        assert!(!stderr.contains("panicked"));
    }
    assert!(!out.exists(), "no partial output");
}

#[test]
fn database_errors_name_the_key_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let index = dir.path().join("index.toml");
    let db = dir.path().to_str().unwrap();
    std::fs::write(&index, "[[tissue]]\nid = \"a\"\nname = \"A\"\nkind = \"x\"\nsource = \"a.png\"\noutputs = [\"colour\"]\ncolour = \"red\"\n").unwrap();
    check_refused(
        "unknown key",
        &index,
        "line 7: unknown field `colour`",
        &["db", "--database", db, "list"],
    );
    std::fs::write(&index, "[[tissue]]\nid = \"a\"\nname = \"A\"\nkind = \"x\"\nsource = \"missing.png\"\noutputs = [\"height\"]\n").unwrap();
    check_refused(
        "missing source",
        &index,
        "tissue 'a': missing.png does not exist",
        &["db", "--database", db, "list"],
    );
    std::fs::write(&index, "").unwrap();
    let (ok, _, stderr) = organtex(&["db", "--database", db, "build", "nosuch"]);
    assert!(!ok && stderr.contains("no tissue 'nosuch'"), "{stderr}");
}

#[test]
fn bake_refuses_bad_scenes_clearly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let database = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database");
    let out = dir.path().join("out");
    let out_arg = out.to_str().unwrap();
    let scene = dir.path().join("scene.toml");
    let write =
        |body: &str| std::fs::write(&scene, format!("database = {database:?}\n{body}")).unwrap();
    let node = "[[node]]\nname = \"organ\"\nmesh = { file = \"organ.obj\" }\n[[node.facet]]\nname = \"*\"\ntexture = \"gravel\"\n";

    write(node);
    check_refused(
        "mesh not found",
        &scene,
        "line 4: node 'organ': mesh.file:",
        &["bake", scene.to_str().unwrap(), "-o", out_arg],
    );
    std::fs::write(
        dir.path().join("organ.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    write(&node.replace("gravel", "granite"));
    check_refused(
        "unknown tissue",
        &scene,
        "line 7: node 'organ': facet '*' texture: 'granite' is not in the tissue database",
        &["bake", scene.to_str().unwrap(), "-o", out_arg],
    );
    write(&format!("{node}overlap = -2\n"));
    check_refused(
        "negative overlap",
        &scene,
        "line 8: node 'organ': facet '*' overlap: must be 0 or more, not -2",
        &["bake", scene.to_str().unwrap(), "-o", out_arg],
    );
    write(&format!("include = [\"scene.toml\"]\n{node}"));
    check_refused(
        "self include",
        &scene,
        "line 2: include: the scene includes itself",
        &["bake", scene.to_str().unwrap(), "-o", out_arg],
    );
    write(&format!("{node}colour = \"red\"\n"));
    check_refused(
        "unknown key",
        &scene,
        "line 8: unknown field `colour`",
        &["bake", scene.to_str().unwrap(), "-o", out_arg],
    );
    assert!(!out.exists(), "a refused bake created its output folder");
    let (ok, _, stderr) = organtex(&[
        "bake",
        scene.to_str().unwrap(),
        "-o",
        out_arg,
        "--atlas",
        "17",
    ]);
    assert!(!ok && stderr.contains("--atlas"), "{stderr}");
}

/// Ctrl-C during a bake stops it at the next safe point: exit code 130 and
/// nothing in the output folder but what was there before.
#[test]
fn an_interrupted_bake_leaves_no_file_behind() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join("bunny.toml");
    let child = Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(["bake", scene.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Long enough for the handler to be installed, well before the bunny's
    // two-second bake ends.
    std::thread::sleep(std::time::Duration::from_millis(400));
    Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("cancelled"), "{stderr}");
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["keep.txt"]);
}

#[test]
fn section_refuses_bad_input_clearly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let (cube, holed) = (data.join("cube.obj"), data.join("bunny10k_textured.obj"));
    let block = organtex::synth::volume::Volume {
        size: [2, 2, 2],
        spacing: 0.25,
        voxels: vec![[200, 40, 60]; 8],
    };
    block.write_nrrd(&d("block.nrrd")).unwrap();
    let mut bytes = block.to_nrrd();
    bytes.truncate(bytes.len() - 5);
    std::fs::write(d("short.nrrd"), bytes).unwrap();
    let out = d("cut.png");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let run = |mesh: &Path, nrrd: &Path, plane: &str, out: &Path| {
        vec![
            "section".to_string(),
            s(mesh),
            "--block".into(),
            s(nrrd),
            "--plane".into(),
            plane.into(),
            "-o".into(),
            s(out),
        ]
    };
    let cases: Vec<(&str, PathBuf, &str, Vec<String>)> = vec![
        (
            "missing block",
            d("nowhere.nrrd"),
            "No such file",
            run(&cube, &d("nowhere.nrrd"), "0,0,1,0", &out),
        ),
        (
            "truncated block",
            d("short.nrrd"),
            "19 bytes of voxel data where sizes [2, 2, 2] need 24",
            run(&cube, &d("short.nrrd"), "0,0,1,0", &out),
        ),
        (
            "open mesh",
            holed.clone(),
            "the mesh is not closed (5 boundary loops); a section needs a closed organ",
            run(&holed, &d("block.nrrd"), "0,0,1,0", &out),
        ),
        (
            "plane missing the mesh",
            cube.clone(),
            "the plane misses the mesh: the section is empty, nothing written",
            run(&cube, &d("block.nrrd"), "0,0,1,-3", &out),
        ),
        (
            "unknown output format",
            d("cut.jpg"),
            "unknown output format (organtex section writes .png or .glb)",
            run(&cube, &d("block.nrrd"), "0,0,1,0", &d("cut.jpg")),
        ),
    ];
    for (name, file, expect, args) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        check_refused(name, &file, expect, &args);
    }
    for (plane, expect) in [
        ("0,0,0,1", "the plane needs a non-zero finite normal"),
        ("0,0,1", "is not NX,NY,NZ,D"),
        ("0,nan,1,0", "is not NX,NY,NZ,D"),
    ] {
        let args = run(&cube, &d("block.nrrd"), plane, &out);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, _, stderr) = organtex(&args);
        assert!(!ok && stderr.contains(expect), "{plane}: {stderr}");
        assert!(!stderr.contains("panicked"));
    }
    let mut args = run(&cube, &d("block.nrrd"), "0,0,1,0", &out);
    args.extend(["--scale".into(), "-1".into()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (ok, _, stderr) = organtex(&args);
    assert!(!ok && stderr.contains("positive scale"), "{stderr}");
    assert!(!out.exists() && !d("cut.jpg").exists(), "no output written");
}
