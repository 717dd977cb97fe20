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
    assert_refused(name, path, expect, organtex(args));
}

/// What `check_refused` asserts of a run's outcome (ok, stdout, stderr):
/// a non-zero exit, no panic, one error line naming the file and saying
/// `expect`.
fn assert_refused(
    name: &str,
    path: &Path,
    expect: &str,
    (ok, stdout, stderr): (bool, String, String),
) {
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
    let gravel = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/textures/gravel.png");
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
    let node = "[[node]]\nname = \"organ\"\nmesh = { file = \"organ.obj\" }\n[[node.facet]]\nname = \"*\"\ntexture = \"colon-mucosa\"\n";

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
    write(&node.replace("colon-mucosa", "granite"));
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

/// Run organtex with its address space capped at 8 GiB, so that a refused
/// case that allocated what its file claims would abort instead of
/// erroring, and with `ORGANTEX_MEMORY_LIMIT` when given.
fn organtex_bounded(limit: Option<&str>, args: &[&str]) -> (bool, String, String) {
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg("ulimit -v 8388608 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_organtex"))
        .args(args)
        .env_remove("ORGANTEX_MEMORY_LIMIT");
    if let Some(l) = limit {
        cmd.env("ORGANTEX_MEMORY_LIMIT", l);
    }
    let out = cmd.output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `check_refused` under `organtex_bounded`.
fn check_refused_bounded(
    limit: Option<&str>,
    name: &str,
    path: &Path,
    expect: &str,
    args: &[&str],
) {
    assert_refused(name, path, expect, organtex_bounded(limit, args));
}

/// An argument refused with a clear message and no panic (clap's own
/// errors name the argument rather than a file).
fn check_arg_refused(args: &[&str], expect: &str) {
    let (ok, stdout, stderr) = organtex(args);
    assert!(!ok, "{args:?}: exit code 0\n{stdout}");
    assert!(!stderr.contains("panicked"), "{args:?}: panic\n{stderr}");
    assert!(
        stderr.contains(expect),
        "{args:?}: expected `{expect}` in:\n{stderr}"
    );
}

/// A PNG chunk: length, type, data, CRC-32.
fn png_chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let mut crc = 0xffff_ffffu32;
    for &b in kind.iter().chain(data) {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    let mut c = (data.len() as u32).to_be_bytes().to_vec();
    c.extend(kind);
    c.extend(data);
    c.extend((!crc).to_be_bytes());
    c
}

/// A PNG whose header claims `w` x `h` RGB pixels, followed by a few bytes
/// of image data: a decoder that trusted the header would allocate it all.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(png_chunk(b"IHDR", &ihdr));
    // A stored zlib block of 100 zero bytes.
    let mut idat = vec![0x78, 0x01, 1, 100, 0, !100u8, 0xff];
    idat.extend([0u8; 100]);
    png.extend(png_chunk(b"IDAT", &idat));
    png.extend(png_chunk(b"IEND", b""));
    png
}

/// A real JPEG whose frame header (SOF0) is rewritten to claim `w` x `h`
/// (a JPEG cannot say more than 65535 a side).
fn jpeg_claiming(w: u16, h: u16) -> Vec<u8> {
    let mut bytes = Vec::new();
    image::RgbImage::from_pixel(16, 16, image::Rgb([90, 40, 30]))
        .write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
    let sof = bytes.windows(2).position(|m| m == [0xff, 0xc0]).unwrap();
    bytes[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
    bytes[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
    bytes
}

#[test]
fn bad_exemplar_images_are_refused_clearly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let gravel = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/textures/gravel.png");
    let g = gravel.to_str().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();

    let whole = std::fs::read(&gravel).unwrap();
    std::fs::write(d("truncated.png"), &whole[..whole.len() / 3]).unwrap();
    std::fs::write(d("huge.png"), png_claiming(100_000, 100_000)).unwrap();
    std::fs::write(d("huge.jpg"), jpeg_claiming(65_000, 65_000)).unwrap();
    // Within the side limit, but not within a 256 MiB memory limit.
    std::fs::write(d("large.png"), png_claiming(16_384, 16_384)).unwrap();
    image::RgbImage::from_pixel(1, 1, image::Rgb([200, 90, 80]))
        .save(d("one.png"))
        .unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 90, 80]))
        .save(d("two.png"))
        .unwrap();
    image::GrayImage::new(512, 512)
        .save(d("black_mask.png"))
        .unwrap();
    image::GrayImage::new(10, 10)
        .save(d("small_mask.png"))
        .unwrap();

    let synth = |src: &Path, extra: &[&str]| {
        let mut a = vec!["synth".to_string(), s(src), "--size".into(), "64".into()];
        a.extend(extra.iter().map(|x| x.to_string()));
        a.extend(["-o".into(), s(&d("out.png"))]);
        a
    };
    let synth3d = |src: &Path, extra: &[&str]| {
        let mut a = vec!["synth3d".to_string(), s(src), "--size".into(), "32".into()];
        a.extend(extra.iter().map(|x| x.to_string()));
        a.extend(["-o".into(), s(&d("out.nrrd"))]);
        a
    };
    let black = s(&d("black_mask.png"));
    let small = s(&d("small_mask.png"));
    let huge_mask = s(&d("huge.png"));
    // (case, memory limit, the file the error names, message, arguments).
    type Refused<'a> = (&'a str, Option<&'a str>, PathBuf, &'a str, Vec<String>);
    let cases: Vec<Refused> = vec![
        (
            "truncated PNG",
            None,
            d("truncated.png"),
            "cannot read the image: unexpected end of file",
            synth(&d("truncated.png"), &[]),
        ),
        (
            "PNG claiming 100000 x 100000",
            None,
            d("huge.png"),
            "the image is 100000x100000 pixels; organtex reads images of at most 16384 pixels a side",
            synth(&d("huge.png"), &[]),
        ),
        (
            "JPEG claiming 65000 x 65000",
            None,
            d("huge.jpg"),
            "the image is 65000x65000 pixels; organtex reads images of at most 16384 pixels a side",
            synth(&d("huge.jpg"), &[]),
        ),
        (
            "mask claiming 100000 x 100000",
            None,
            d("huge.png"),
            "the image is 100000x100000 pixels",
            synth(&gravel, &["--mask", &huge_mask]),
        ),
        (
            "16384 x 16384 PNG beyond the memory limit",
            Some("256M"),
            d("large.png"),
            "decoding this 16384x16384 image needs about 3.0 GiB, this machine has 0.25 GiB available (capped by ORGANTEX_MEMORY_LIMIT)",
            synth(&d("large.png"), &[]),
        ),
        (
            "1 x 1 exemplar",
            None,
            d("one.png"),
            "the exemplar is 1x1 pixels (after any crop), smaller than one 7x7 neighbourhood: it needs at least 7x7 pixels",
            synth(&d("one.png"), &[]),
        ),
        (
            "1 x 1 crop",
            None,
            gravel.clone(),
            "the exemplar is 1x1 pixels (after any crop)",
            synth(&gravel, &["--crop", "5,5,1,1"]),
        ),
        (
            "1 x 1 exemplar in 3D",
            None,
            d("one.png"),
            "the exemplar is 1x1 pixels (after any crop), smaller than one 5x5 neighbourhood",
            synth3d(&d("one.png"), &[]),
        ),
        (
            "2 x 2 exemplar in 3D",
            None,
            d("two.png"),
            "the exemplar is 2x2 pixels",
            synth3d(&d("two.png"), &[]),
        ),
        (
            "1 x 1 exemplar for the quality figures",
            None,
            d("one.png"),
            "the exemplar is 1x1 pixels",
            vec!["synth-quality".into(), s(&d("one.png")), g.into()],
        ),
        (
            "mask hiding everything in 3D",
            None,
            d("black_mask.png"),
            "the mask hides every pixel",
            synth3d(&gravel, &["--mask", &black]),
        ),
        (
            "mask of another size in 3D",
            None,
            d("small_mask.png"),
            "the mask is 10x10 but the image",
            synth3d(&gravel, &["--mask", &small]),
        ),
    ];
    for (name, limit, file, expect, args) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        check_refused_bounded(limit, name, &file, expect, &args);
    }
    assert!(!d("out.png").exists() && !d("out.nrrd").exists());
}

/// 16-bit and grey-alpha PNGs are converted: 16-bit channels to their
/// 8-bit value, grey to equal RGB, alpha below half masking the pixel.
#[test]
fn sixteen_bit_and_grey_alpha_exemplars_are_converted() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 32u32);
    // Left half one colour, right half another; 16-bit values are exact
    // multiples of 257, so each maps to one 8-bit value.
    let left = |x: u32| x < w / 2;
    let rgb16 = image::ImageBuffer::from_fn(w, h, |x, _| {
        image::Rgb(if left(x) {
            [200 * 257, 30 * 257, 60 * 257]
        } else {
            [20 * 257, 120 * 257, 240 * 257]
        })
    });
    let grey16 = image::ImageBuffer::from_fn(w, h, |x, _| {
        image::Luma([if left(x) { 40 * 257 } else { 220 * 257 }])
    });
    // Alpha hides the right half: only the left half's colour may appear.
    let la8 = image::ImageBuffer::from_fn(w, h, |x, _| {
        image::LumaA(if left(x) { [50u8, 255] } else { [200, 0] })
    });
    let la16 = image::ImageBuffer::from_fn(w, h, |x, _| {
        image::LumaA(if left(x) {
            [90 * 257, 65535]
        } else {
            [10 * 257, 0u16]
        })
    });
    let rgba16 = image::ImageBuffer::from_fn(w, h, |x, _| {
        image::Rgba(if left(x) {
            [10 * 257, 100 * 257, 200 * 257, 65535u16]
        } else {
            [255 * 257, 0, 0, 100]
        })
    });
    let cases: Vec<(&str, image::DynamicImage, Vec<[u8; 3]>)> = vec![
        (
            "rgb16",
            image::DynamicImage::ImageRgb16(rgb16),
            vec![[200, 30, 60], [20, 120, 240]],
        ),
        (
            "grey16",
            image::DynamicImage::ImageLuma16(grey16),
            vec![[40; 3], [220; 3]],
        ),
        (
            "grey_alpha8",
            image::DynamicImage::ImageLumaA8(la8),
            vec![[50; 3]],
        ),
        (
            "grey_alpha16",
            image::DynamicImage::ImageLumaA16(la16),
            vec![[90; 3]],
        ),
        (
            "rgba16",
            image::DynamicImage::ImageRgba16(rgba16),
            vec![[10, 100, 200]],
        ),
    ];
    for (name, img, colours) in cases {
        let src = dir.path().join(format!("{name}.png"));
        img.save(&src).unwrap();
        let out = dir.path().join(format!("{name}_out.png"));
        let (ok, _, stderr) = organtex(&[
            "synth",
            src.to_str().unwrap(),
            "--size",
            "48",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{name}: {stderr}");
        let result = image::open(&out).unwrap().to_rgb8();
        assert_eq!(result.dimensions(), (48, 48));
        for c in &colours {
            assert!(
                result.pixels().any(|p| p.0 == *c),
                "{name}: colour {c:?} missing"
            );
        }
        let stray = result.pixels().find(|p| !colours.contains(&p.0));
        assert!(stray.is_none(), "{name}: unexpected colour {stray:?}");
    }
}

#[test]
fn out_of_range_numbers_on_the_command_line_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let gravel = data.join("tests/data/textures/gravel.png");
    let cube = data.join("tests/data/cube.obj");
    let scene = data.join("scenes/bunny.toml");
    let (g, c, sc) = (
        gravel.to_str().unwrap(),
        cube.to_str().unwrap(),
        scene.to_str().unwrap(),
    );
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let (png, nrrd, obj, bake_dir) = (out("o.png"), out("o.nrrd"), out("o.obj"), out("baked"));
    let block = dir.path().join("b.nrrd");
    organtex::synth::volume::Volume {
        size: [2, 2, 2],
        spacing: 0.25,
        voxels: vec![[200, 40, 60]; 8],
    }
    .write_nrrd(&block)
    .unwrap();
    let b = block.to_str().unwrap();
    let section = |extra: &[&str]| {
        let mut a = vec!["section", c, "--block", b, "--plane", "0,0,1,0", "-o"];
        a.push(&png);
        a.extend(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let mut cases: Vec<(Vec<String>, &str)> = Vec::new();
    for v in ["nan", "inf", "0", "-1"] {
        cases.push((
            section(&["--scale", v]),
            "--scale must be a positive scale (object units per voxel), not",
        ));
    }
    for v in ["0", "16385", "-4", "nan"] {
        cases.push((section(&["--resolution", v]), "invalid value"));
    }
    let args = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    for v in ["0", "0x64", "16385x64"] {
        cases.push((
            args(&["synth", g, "--size", v, "-o", &png]),
            "outside 1..16384 pixels a side",
        ));
    }
    for v in ["-5", "nan", "inf", "64xnan"] {
        cases.push((
            args(&["synth", g, "--size", v, "-o", &png]),
            "is not WIDTHxHEIGHT",
        ));
    }
    for v in ["0", "17", "x"] {
        cases.push((
            args(&["synth", g, "--size", "64", "--levels", v, "-o", &png]),
            "is not a number of levels from 1 to 16",
        ));
    }
    for v in ["nan", "-1", "inf"] {
        cases.push((
            args(&["synth", g, "--size", "64", "--occurrence", v, "-o", &png]),
            "the occurrence weight must be from 0 to 10",
        ));
    }
    for v in ["0", "3", "300"] {
        cases.push((
            args(&["synth3d", g, "--size", v, "-o", &nrrd]),
            "the block size must be from 5 (the neighbourhood) to 256 voxels",
        ));
    }
    cases.push((
        args(&["synth3d", g, "--size", "-8", "-o", &nrrd]),
        "invalid value",
    ));
    for v in ["nan", "inf", "0", "-1"] {
        cases.push((
            args(&["synth3d", g, "--size", "16", "--spacing", v, "-o", &nrrd]),
            "--spacing must be a positive number",
        ));
    }
    for v in ["0", "17", "-64", "nan", "99999"] {
        cases.push((
            args(&["bake", sc, "-o", &bake_dir, "--atlas", v]),
            "invalid value",
        ));
    }
    for v in ["nan", "inf", "-1", "100"] {
        cases.push((
            args(&["generate", "uterus", "-o", &obj, "--wall-thickness", v]),
            "--wall-thickness: must be from 0 to the cavity's depth and width (16), not",
        ));
    }
    for v in ["nan", "inf", "-1", "0"] {
        cases.push((
            args(&["unwrap", c, "-o", &obj, "--max-stretch", v]),
            "--max-stretch must be a positive number",
        ));
        cases.push((
            args(&["unwrap", c, "-o", &obj, "--max-conformal", v]),
            "--max-conformal must be a number of at least 1",
        ));
    }
    for (args, expect) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        check_arg_refused(&args, expect);
    }
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["b.nrrd"], "nothing written");
}

#[test]
fn out_of_range_numbers_in_a_scene_are_refused_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let database = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database");
    std::fs::write(
        dir.path().join("organ.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let scene = dir.path().join("scene.toml");
    let out = dir.path().join("out");
    // Line 2: [[camera]]; line 6: [[node]]; line 9: [[node.facet]] whose
    // texture is line 11; line 12: [node.interior]; line 15: [bake].
    let base = format!(
        "database = {database:?}\n[[camera]]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         fov = 60.0\n[[node]]\nname = \"organ\"\nmesh = {{ file = \"organ.obj\" }}\n[[node.facet]]\n\
         name = \"*\"\ntexture = \"colon-mucosa\"\n[node.interior]\ntexture = \"colon-mucosa\"\nblock_size = 5.0\n\
         [bake]\nviews = 8\ninterior_voxels = 16\n"
    );
    let facet = |key: &str, v: &str| {
        base.replace(
            "texture = \"colon-mucosa\"\n[node",
            &format!("texture = \"colon-mucosa\"\n{key} = {v}\n[node"),
        )
    };
    let mut cases: Vec<(String, String)> = Vec::new();
    for v in ["nan", "inf", "0.0", "-1.0"] {
        for key in ["tile_size", "overlay_tile_size", "max_stretch"] {
            cases.push((
                facet(key, v),
                format!("line 12: node 'organ': facet '*' {key}: must be a positive number, not"),
            ));
        }
        cases.push((
            base.replace("block_size = 5.0", &format!("block_size = {v}")),
            "line 12: node 'organ': interior block_size: must be a positive number of mesh units, not".into(),
        ));
    }
    for v in ["nan", "inf", "-inf"] {
        cases.push((
            facet("rotation", v),
            "facet '*' rotation: must be a finite number of degrees, not".into(),
        ));
        cases.push((
            facet("offset", &format!("[0.0, {v}]")),
            "facet '*' offset: must be two finite numbers, not".into(),
        ));
        cases.push((
            facet("overlap", v),
            "facet '*' overlap: must be 0 or more, not".into(),
        ));
        cases.push((
            facet("bump", v),
            "facet '*' bump: must be from 0 to 10, not".into(),
        ));
        cases.push((
            base.replace(
                "position = [0.0, 0.0, 5.0]",
                &format!("position = [0.0, {v}, 5.0]"),
            ),
            "line 2: camera: position and look_at must be finite numbers".into(),
        ));
        cases.push((
            base.replace(
                "look_at = [0.0, 0.0, 0.0]",
                &format!("look_at = [{v}, 0.0, 0.0]"),
            ),
            "line 2: camera: position and look_at must be finite numbers".into(),
        ));
    }
    for v in ["nan", "0.0", "-60.0", "inf"] {
        cases.push((
            base.replace("fov = 60.0", &format!("fov = {v}")),
            "line 2: camera at [0.0, 0.0, 5.0]: fov must be from 1 to 170 degrees".into(),
        ));
    }
    for v in ["0", "5000"] {
        cases.push((
            base.replace("views = 8", &format!("views = {v}")),
            format!("line 16: [bake] views: must be from 1 to 1024, not {v}"),
        ));
    }
    for v in ["0", "8", "512"] {
        cases.push((
            base.replace("interior_voxels = 16", &format!("interior_voxels = {v}")),
            format!("line 17: [bake] interior_voxels: {v} is not a multiple of 16 from 16 to 256"),
        ));
    }
    cases.push((
        base.replace("views = 8", "views = -1"),
        "line 16: invalid value: integer `-1`".into(),
    ));
    // A generated organ's numbers.
    let cavity = |params: &str| {
        base.replace(
            "mesh = { file = \"organ.obj\" }",
            &format!("mesh = {{ uterine_cavity = {{ {params} }} }}"),
        )
    };
    for v in ["nan", "inf", "0.0", "-1.0"] {
        for key in ["length", "width", "depth", "cervix_radius"] {
            cases.push((
                cavity(&format!("{key} = {v}")),
                format!("line 8: node 'organ': mesh.uterine_cavity.{key}: must be a positive number, not"),
            ));
        }
        for key in ["radius", "height"] {
            cases.push((
                cavity(&if key == "radius" {
                    format!("myoma = [{{ at = [0.2, 0.5], radius = {v}, height = 2.0 }}]")
                } else {
                    format!("myoma = [{{ at = [0.2, 0.5], radius = 3.0, height = {v} }}]")
                }),
                format!("line 8: node 'organ': mesh.uterine_cavity.myoma[0].{key}: must be a positive number, not"),
            ));
        }
    }
    for key in ["length", "width", "depth"] {
        cases.push((
            cavity(&format!("{key} = 1e300")),
            format!("mesh.uterine_cavity.{key}: must be at most 1000000, not 1000"),
        ));
    }
    cases.push((
        cavity("polyp = [{ at = [0.5, 0.9], stalk_radius = 0.5, stalk_length = 1e200, head_radius = 1.0 }]"),
        "mesh.uterine_cavity.polyp[0].stalk_length: must be at most 1000000".into(),
    ));
    for v in ["nan", "-0.1", "5.0"] {
        cases.push((
            cavity(&format!("folds = {v}")),
            "mesh.uterine_cavity.folds: must be from 0 to".into(),
        ));
    }
    for v in ["-5.0", "60.0", "nan"] {
        cases.push((
            cavity(&format!(
                "polyp = [{{ at = [0.5, 0.9], stalk_radius = 0.5, stalk_length = 1.0, head_radius = 1.0, lean = {v} }}]"
            )),
            "mesh.uterine_cavity.polyp[0].lean: must be from 0 to 45 degrees".into(),
        ));
    }
    for v in ["nan", "inf", "-1.0"] {
        cases.push((
            cavity(&format!("wall_thickness = {v}")),
            "mesh.uterine_cavity.wall_thickness: must be from 0 to the cavity's depth and width"
                .into(),
        ));
    }
    let s = scene.to_str().unwrap();
    for (text, expect) in &cases {
        std::fs::write(&scene, text).unwrap();
        check_refused(
            expect,
            &scene,
            expect,
            &["bake", s, "-o", out.to_str().unwrap()],
        );
    }
    assert!(!out.exists(), "a refused bake created its output folder");
}

#[test]
fn a_cycle_of_includes_through_two_files_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let database = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database");
    let (a, b) = (dir.path().join("a.toml"), dir.path().join("b.toml"));
    std::fs::write(
        dir.path().join("organ.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        &a,
        format!("database = {database:?}\ninclude = [\"b.toml\"]\n[[node]]\nname = \"organ\"\nmesh = {{ file = \"organ.obj\" }}\n"),
    )
    .unwrap();
    std::fs::write(&b, "# included by a\ninclude = [\"a.toml\"]\n").unwrap();
    let out = dir.path().join("out");
    let chain = format!(
        "{} -> {} -> {}",
        a.canonicalize().unwrap().display(),
        b.canonicalize().unwrap().display(),
        a.canonicalize().unwrap().display()
    );
    check_refused(
        "two-file include cycle",
        &b,
        &format!("line 2: include: the includes form a cycle ({chain})"),
        &["bake", a.to_str().unwrap(), "-o", out.to_str().unwrap()],
    );
    assert!(!out.exists());
}

#[test]
fn bad_nrrd_blocks_are_refused_clearly_and_slicer_files_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let cube = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj");
    let voxels: Vec<u8> = (0..8).flat_map(|i| [200, 40 + 20 * i as u8, 60]).collect();
    // What 3D Slicer writes: gzip, endian, space and space directions.
    let header = |encoding: &str, sizes: &str, extra: &str| {
        format!(
            "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\n\
             type: unsigned char\ndimension: 4\nspace: left-posterior-superior\nsizes: {sizes}\n\
             space directions: none (0.25,0,0) (0,0.25,0) (0,0,0.25)\nkinds: RGB-color domain domain domain\n\
             endian: little\nencoding: {encoding}\nspace origin: (0,0,0)\n{extra}"
        )
    };
    let gzip = |bytes: &[u8]| {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(bytes).unwrap();
        e.finish().unwrap()
    };
    let attached = |name: &str, head: String, data: &[u8]| {
        let mut bytes = head.into_bytes();
        bytes.extend(b"\n");
        bytes.extend(data);
        std::fs::write(d(name), bytes).unwrap();
    };
    attached("slicer.nrrd", header("gzip", "3 2 2 2", ""), &gzip(&voxels));
    std::fs::write(d("block.raw.gz"), gzip(&voxels)).unwrap();
    std::fs::write(
        d("detached.nhdr"),
        header("gzip", "3 2 2 2", "data file: block.raw.gz\n"),
    )
    .unwrap();
    std::fs::write(
        d("missing.nhdr"),
        header("raw", "3 2 2 2", "data file: nowhere.raw\n"),
    )
    .unwrap();
    attached("sizes.nrrd", header("raw", "3 2 two 2", ""), &voxels);
    attached("short_sizes.nrrd", header("raw", "3 2 2", ""), &voxels);
    attached(
        "float.nrrd",
        header("raw", "3 2 2 2", "").replace("unsigned char", "float"),
        &voxels,
    );
    attached("bzip2.nrrd", header("bzip2", "3 2 2 2", ""), &voxels);
    attached(
        "gzip_short.nrrd",
        header("gzip", "3 2 2 2", ""),
        &gzip(&voxels[..20]),
    );
    attached(
        "gzip_bad.nrrd",
        header("gzip", "3 2 2 2", ""),
        b"not compressed",
    );
    // Item 6: a tiny gzip stream whose header claims 4096^3 voxels.
    attached(
        "gzip_huge.nrrd",
        header("gzip", "3 4096 4096 4096", ""),
        &gzip(&voxels),
    );

    let s = |p: &Path| p.to_str().unwrap().to_string();
    let out = d("cut.png");
    let run = |nrrd: &Path| {
        vec![
            "section".to_string(),
            s(&cube),
            "--block".into(),
            s(nrrd),
            "--plane".into(),
            "0,0,1,0".into(),
            "-o".into(),
            s(&out),
        ]
    };
    let cases: Vec<(&str, Option<&str>, &str, &str)> = vec![
        (
            "wrong sizes line",
            None,
            "sizes.nrrd",
            "header line 7: bad sizes '3 2 two 2': expected whole numbers",
        ),
        (
            "three sizes",
            None,
            "short_sizes.nrrd",
            "expected an RGB volume (dimension 4, sizes 3 X Y Z), found dimension 4, sizes [3, 2, 2]",
        ),
        (
            "unsupported type",
            None,
            "float.nrrd",
            "type 'float' is not supported; uint8 is",
        ),
        (
            "unsupported encoding",
            None,
            "bzip2.nrrd",
            "encoding 'bzip2' is not supported; raw and gzip are",
        ),
        (
            "missing detached data file",
            None,
            "missing.nhdr",
            "nowhere.raw: cannot be opened: No such file or directory",
        ),
        (
            "gzip data too short",
            None,
            "gzip_short.nrrd",
            "the gzip data holds 20 bytes of voxel data where sizes [2, 2, 2] need 24",
        ),
        (
            "corrupt gzip data",
            None,
            "gzip_bad.nrrd",
            "the gzip data cannot be decompressed",
        ),
        (
            "gzip header claiming 4096^3 voxels",
            Some("4G"),
            "gzip_huge.nrrd",
            "a 4096x4096x4096 volume needs about 384 GiB, this machine has 4.0 GiB available (capped by ORGANTEX_MEMORY_LIMIT)",
        ),
    ];
    for (name, limit, file, expect) in cases {
        let args = run(&d(file));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        check_refused_bounded(limit, name, &d(file), expect, &args);
    }
    assert!(!out.exists());
    // Without a cap the same file is refused by what the machine has
    // (MemAvailable), on any machine with less than 384 GiB free.
    let args = run(&d("gzip_huge.nrrd"));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (ok, _, stderr) = organtex_bounded(None, &args);
    assert!(
        !ok && stderr.contains("a 4096x4096x4096 volume needs about 384 GiB, this machine has"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("capped") && !stderr.contains("panicked"),
        "{stderr}"
    );

    // Slicer's attached gzip and a detached gzip file both cut.
    for file in ["slicer.nrrd", "detached.nhdr"] {
        let args = run(&d(file));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, _, stderr) = organtex(&args);
        assert!(ok, "{file}: {stderr}");
        let cut = image::open(&out).unwrap().to_rgba8();
        assert!(cut.pixels().any(|p| p[3] == 255 && p[0] == 200), "{file}");
        std::fs::remove_file(&out).unwrap();
    }
}

/// Item 6 of issue 20: sizes that would not fit are refused before the
/// allocation, with the estimate, under an 8 GiB address-space cap.
#[test]
fn work_too_large_for_memory_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let gravel = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/textures/gravel.png");
    let g = gravel.to_str().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();

    let ply = |format: &str, vertices: &str, faces: &str, body: &[u8]| {
        let mut b = format!(
            "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        b.extend(body);
        b
    };
    std::fs::write(
        d("v31.ply"),
        ply("binary_little_endian", "2147483648", "1", &[0; 4]),
    )
    .unwrap();
    std::fs::write(d("v31a.ply"), ply("ascii", "2147483648", "1", b"0 0 0\n")).unwrap();
    std::fs::write(
        d("f31.ply"),
        ply("binary_little_endian", "3", "2147483647", &[0; 36]),
    )
    .unwrap();
    std::fs::write(d("t31.stl"), binary_stl_claiming(1 << 31, 1)).unwrap();
    let mesh_cases = [
        ("v31.ply", "the header declares 2147483648 vertex elements"),
        ("v31a.ply", "the header declares 2147483648 vertex elements"),
        ("f31.ply", "the header declares 2147483647 face elements"),
        ("t31.stl", "declares 2147483648 triangles"),
    ];
    for (file, expect) in mesh_cases {
        check_refused_bounded(None, file, &d(file), expect, &["info", &s(&d(file))]);
    }

    // Generated work, under a memory cap so the case does not depend on
    // the machine.
    let capped = |args: &[&str], expect: &str| {
        let (ok, stdout, stderr) = organtex_bounded(Some("60M"), args);
        assert!(!ok, "{args:?}: exit code 0\n{stdout}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            stderr.contains(expect),
            "{args:?}: expected `{expect}` in:\n{stderr}"
        );
        assert!(
            stderr.contains(
                "GiB, this machine has 0.06 GiB available (capped by ORGANTEX_MEMORY_LIMIT)"
            ),
            "{stderr}"
        );
    };
    let nrrd = s(&d("b.nrrd"));
    capped(
        &["synth3d", g, "--size", "256", "-o", &nrrd],
        "synthesising a 256x256x256 block (--size) needs about 0.42 GiB",
    );
    capped(
        &[
            "synth3d", g, "--size", "128", "--method", "optimize", "-o", &nrrd,
        ],
        "synthesising a 128x128x128 block (--size) needs about 0.13 GiB",
    );
    let png = s(&d("t.png"));
    capped(
        &["synth", g, "--size", "4000", "-o", &png],
        "synthesising a 4000x4000 texture (--size) needs about 0.54 GiB",
    );
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/bunny.toml");
    capped(
        &[
            "bake",
            scene.to_str().unwrap(),
            "-o",
            &s(&d("out")),
            "--atlas",
            "8000",
        ],
        "--atlas 8000 (one facet's 8000x8000 atlas) needs about 0.83 GiB",
    );
    let block = d("block.nrrd");
    organtex::synth::volume::Volume {
        size: [2, 2, 2],
        spacing: 0.25,
        voxels: vec![[200, 40, 60]; 8],
    }
    .write_nrrd(&block)
    .unwrap();
    let cube = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube.obj");
    capped(
        &[
            "section",
            cube.to_str().unwrap(),
            "--block",
            &s(&block),
            "--plane",
            "0,0,1,0",
            "--resolution",
            "4096",
            "-o",
            &png,
        ],
        "section image (--resolution) needs about 0.2",
    );

    // A scene's interior blocks, refused when the scene is read.
    let database = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database");
    std::fs::write(d("organ.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = d("big.toml");
    std::fs::write(
        &scene,
        format!(
            "database = {database:?}\n[[node]]\nname = \"organ\"\nmesh = {{ file = \"organ.obj\" }}\n\
             [node.interior]\ntexture = \"colon-mucosa\"\nmethod = \"optimize\"\n[bake]\ninterior_voxels = 256\n"
        ),
    )
    .unwrap();
    check_refused_bounded(
        Some("512M"),
        "interior blocks",
        &scene,
        "[bake] interior_voxels: synthesising 1 interior block of 256^3 voxels needs about 1.1 GiB, this machine has 0.50 GiB available",
        &["bake", &s(&scene), "-o", &s(&d("out"))],
    );
    // A database entry's texture size.
    let db = d("db");
    std::fs::create_dir(&db).unwrap();
    std::fs::copy(&gravel, db.join("gravel.png")).unwrap();
    let index = db.join("index.toml");
    std::fs::write(
        &index,
        "[[tissue]]\nid = \"g\"\nname = \"G\"\nkind = \"x\"\nsource = \"gravel.png\"\noutputs = [\"colour\"]\n\
         [tissue.synthesis]\nwidth = 16384\nheight = 16384\n",
    )
    .unwrap();
    check_refused_bounded(
        Some("1G"),
        "database texture",
        &index,
        "tissue 'g': a 16384x16384 texture needs about 9.0 GiB, this machine has 1.0 GiB available",
        &["db", "--database", &s(&db), "build"],
    );
    assert!(!db.join("build").exists(), "nothing built");
    let (ok, _, stderr) = organtex_bounded(Some("lots"), &["synth", g, "--size", "64", "-o", &png]);
    assert!(
        !ok && stderr.contains("ORGANTEX_MEMORY_LIMIT='lots' is not a size such as 512M or 4G"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".ply") && !n.ends_with(".stl") && !n.ends_with(".obj"))
        .collect();
    let mut left = left;
    left.sort();
    assert_eq!(left, ["big.toml", "block.nrrd", "db"], "nothing written");
}
