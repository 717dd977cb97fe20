//! Segmentations to surfaces (issue 40): NIfTI-1 read with its
//! voxel-to-world map, the region's surface closed, manifold and turned
//! outward, in world millimetres, with its voxels' volume; real MRI data
//! (the MNI ICBM152 white matter, and the brain from its T1); bad files
//! refused by name.

mod common;
use common::organtex;

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{DAffine3, DMat3, DQuat, DVec3};
use organtex::mesh::decimate::Hold;
use organtex::mesh::info::analyse;
use organtex::progress::Silent;
use organtex::segment::{self, MeshOptions, Region, ScalarVolume, nifti};

fn volumes(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/volumes")
        .join(name)
}

/// An ellipsoid of label 3 inside a box of label 1, on 0 background.
fn labelled(to_world: DAffine3) -> ScalarVolume {
    let size = [24, 20, 16];
    let mut values = Vec::new();
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let p = DVec3::new(x as f64 - 11.0, y as f64 - 9.5, z as f64 - 7.0);
                let e = (p / DVec3::new(8.0, 6.0, 4.5)).length_squared();
                let inner = (2..22).contains(&x) && (2..18).contains(&y) && (2..14).contains(&z);
                values.push(if e <= 1.0 {
                    3.0
                } else if inner {
                    1.0
                } else {
                    0.0
                });
            }
        }
    }
    ScalarVolume {
        size,
        values,
        to_world,
    }
}

/// Closed, manifold, every face turned out of the region; its genus.
fn check_surface(mesh: &organtex::mesh::TriMesh, what: &str) -> Vec<i64> {
    let r = analyse(mesh.clone(), false)
        .unwrap_or_else(|e| panic!("{what}: {e}"))
        .report;
    assert_eq!(r.boundary_edges, 0, "{what}: open");
    assert_eq!(r.defects.non_manifold_edges, 0, "{what}");
    assert_eq!(r.defects.non_manifold_vertices, 0, "{what}");
    assert_eq!(r.defects.inconsistent_edges, 0, "{what}");
    assert_eq!(r.normals, Some("outward"), "{what}");
    r.genus
}

/// The box of `mesh` taken back into voxel indices through `to_world`.
fn span_in_voxels(mesh: &organtex::mesh::TriMesh, to_world: DAffine3) -> (DVec3, DVec3) {
    let back = to_world.inverse();
    mesh.positions.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(lo, hi), p| {
            let q = back.transform_point3(*p);
            (lo.min(q), hi.max(q))
        },
    )
}

/// The box of the centres of the voxels holding `label` (x fastest).
fn label_box(size: [usize; 3], values: &[f32], label: f32) -> (DVec3, DVec3) {
    let mut box_ = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for (i, _) in values.iter().enumerate().filter(|(_, v)| **v == label) {
        let c = DVec3::new(
            (i % size[0]) as f64,
            (i / size[0] % size[1]) as f64,
            (i / (size[0] * size[1])) as f64,
        );
        box_ = (box_.0.min(c), box_.1.max(c));
    }
    box_
}

/// `organtex mesh ARGS --json`: its figures, after checking that it
/// succeeded and called its surface closed and manifold, with its voxels'
/// volume within `tolerance`.
fn mesh_json(args: &[&str], tolerance: f64) -> serde_json::Value {
    let (ok, stdout, stderr) = organtex(&[&["mesh"], args, &["--json"]].concat());
    assert!(ok, "{stderr}");
    let figures: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(figures["closed"], true, "{stdout}");
    assert_eq!(figures["manifold"], true, "{stdout}");
    let ratio = figures["volume"].as_f64().unwrap() / figures["voxel_volume"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() <= tolerance, "{stdout}");
    figures
}

fn write_nii(dir: &Path, name: &str, volume: &ScalarVolume, gzip: bool) -> PathBuf {
    let path = dir.join(name);
    let bytes = nifti::to_bytes(volume);
    let mut f = std::fs::File::create(&path).unwrap();
    if gzip {
        let mut gz = flate2::write::GzEncoder::new(f, flate2::Compression::fast());
        gz.write_all(&bytes).unwrap();
        gz.finish().unwrap();
    } else {
        f.write_all(&bytes).unwrap();
    }
    path
}

#[test]
fn a_label_lands_in_world_millimetres_through_the_files_transform() {
    let dir = tempfile::tempdir().unwrap();
    // Anisotropic voxels, one axis flipped (a left-handed map, as radiology
    // files often are) and an offset: the world box is the voxels' box
    // through it.
    let flipped = DAffine3 {
        matrix3: DMat3::from_diagonal(DVec3::new(-0.8, 1.25, 2.0)),
        translation: DVec3::new(40.0, -12.0, 7.5),
    };
    // A turned frame: the same region, its centre where the map puts it.
    let turned = DAffine3 {
        matrix3: DMat3::from_quat(DQuat::from_euler(glam::EulerRot::ZYX, 0.5, 0.3, -0.2))
            * DMat3::from_diagonal(DVec3::new(0.7, 0.7, 1.5)),
        translation: DVec3::new(-90.0, 126.0, -72.0),
    };
    for (k, to_world) in [flipped, turned].into_iter().enumerate() {
        let volume = labelled(to_world);
        let path = write_nii(dir.path(), &format!("seg{k}.nii.gz"), &volume, k == 0);
        let read = ScalarVolume::read(&path).unwrap();
        assert_eq!(read.size, volume.size);
        assert_eq!(read.values, volume.values);
        for (a, b) in [
            (read.to_world.matrix3.x_axis, to_world.matrix3.x_axis),
            (read.to_world.matrix3.y_axis, to_world.matrix3.y_axis),
            (read.to_world.matrix3.z_axis, to_world.matrix3.z_axis),
            (read.to_world.translation, to_world.translation),
        ] {
            assert!(a.abs_diff_eq(b, 1e-5), "{a} vs {b}");
        }
        let opts = MeshOptions {
            region: Region::Label(3),
            smooth: 0,
            all_components: false,
            fill_voids: false,
            faces: None,
            max_handle: None,
            within_voxels: None,
            smoother: Default::default(),
        };
        let (mesh, report) = segment::mesh(&read, &path, &opts, &Silent).unwrap();
        assert_eq!(check_surface(&mesh, "ellipsoid"), vec![0]);
        let voxel = read.voxel_volume();
        assert!(
            (report.volume / report.voxel_volume - 1.0).abs() < 0.03,
            "{report:?}"
        );
        let (lo, hi) = mesh.bounding_box().unwrap();
        if k == 0 {
            // Axis-aligned: the box of the voxels' faces, within half a
            // voxel (the surface passes halfway between centres).
            let (blo, bhi) = segment::region_box(&read, |v| v == 3.0).unwrap();
            let half = DVec3::new(0.4, 0.625, 1.0);
            assert!(
                (lo - blo).abs().cmple(half + 1e-9).all()
                    && (hi - bhi).abs().cmple(half + 1e-9).all(),
                "mesh box {lo}..{hi}, voxel box {blo}..{bhi}"
            );
            assert!((lo - blo).abs().max_element() < 1e-6, "{lo} vs {blo}");
        } else {
            // Turned: the surface's centroid is the region's, through the
            // map, within half a voxel; and taken back into voxel space the
            // surface spans the label's voxels.
            let centroid = mesh.positions.iter().sum::<DVec3>() / mesh.num_vertices() as f64;
            let want = to_world.transform_point3(DVec3::new(11.0, 9.5, 7.0));
            assert!(centroid.distance(want) < 0.35, "{centroid} vs {want}");
            let (vlo, vhi) = span_in_voxels(&mesh, to_world);
            let (ilo, ihi) = label_box(read.size, &read.values, 3.0);
            assert!(vlo.abs_diff_eq(ilo - 0.5, 1e-6), "{vlo} vs {ilo}");
            assert!(vhi.abs_diff_eq(ihi + 0.5, 1e-6), "{vhi} vs {ihi}");
            assert!(voxel > 0.0 && (lo - hi).length() > 10.0);
        }
    }
}

/// A region round an enclosed void (label 1 is a box round the
/// ellipsoid of label 3): by default the void is an inner shell of the
/// surface, facing into it, and the enclosed volume is the region's own;
/// `--fill-voids` makes one sheet holding the void's voxels too.
#[test]
fn a_void_is_an_inner_shell_unless_filled() {
    let dir = tempfile::tempdir().unwrap();
    let volume = labelled(DAffine3::from_translation(DVec3::new(3.0, -2.0, 1.0)));
    let path = write_nii(dir.path(), "box.nii", &volume, false);
    let count = |l: f32| volume.values.iter().filter(|&&v| v == l).count() as u64;
    let out = dir.path().join("box.stl");
    let (input, output) = (path.to_str().unwrap(), out.to_str().unwrap());
    let base = ["--label", "1", "--smooth", "0", "-o", output];
    let kept = mesh_json(&[&[input], &base[..]].concat(), 0.03);
    assert_eq!(kept["voids"], 1, "{kept}");
    assert_eq!(kept["voids_filled"], false, "{kept}");
    assert_eq!(kept["genus"], serde_json::json!([0, 0]), "{kept}");
    assert_eq!(kept["voxels"], count(1.0), "{kept}");
    assert_eq!(kept["normals"], "outward", "{kept}");
    let filled = mesh_json(&[&[input], &base[..], &["--fill-voids"]].concat(), 0.03);
    assert_eq!(filled["voids"], 1, "{filled}");
    assert_eq!(filled["voids_filled"], true, "{filled}");
    assert_eq!(filled["genus"], serde_json::json!([0]), "{filled}");
    assert_eq!(filled["voxels"], count(1.0) + count(3.0), "{filled}");
    assert_eq!(filled["region_voxels"], count(1.0), "{filled}");
}

/// Each closed piece of `mesh` (faces joined by shared vertices): its
/// face count and enclosed volume, in order of its first vertex.
fn shells(mesh: &organtex::mesh::TriMesh) -> Vec<(usize, f64)> {
    let mut piece: Vec<usize> = (0..mesh.num_vertices()).collect();
    fn root(piece: &mut [usize], mut v: usize) -> usize {
        while piece[v] != v {
            piece[v] = piece[piece[v]];
            v = piece[v];
        }
        v
    }
    for t in &mesh.triangles {
        for k in 1..3 {
            let (a, b) = (
                root(&mut piece, t[0] as usize),
                root(&mut piece, t[k] as usize),
            );
            piece[a] = b;
        }
    }
    let mut pieces = std::collections::BTreeMap::<usize, (usize, f64)>::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = mesh.corners(f);
        let entry = pieces.entry(root(&mut piece, t[0] as usize)).or_default();
        entry.0 += 1;
        entry.1 += a.dot(b.cross(c)) / 6.0;
    }
    pieces.into_values().collect()
}

/// A probability map of a ball of radius 12 voxels in a cube of 32 (voxels
/// 0.5 mm apart), at the level 127.5 on its sphere, with the voxels `set`
/// to the values given: the volume, how many voxels are at the level or
/// over it, and the options that mesh it to 600 faces (`all_components`
/// as asked).
fn probability_ball(
    set: &[([usize; 3], f32)],
    all_components: bool,
) -> (ScalarVolume, u64, MeshOptions) {
    let n = 32;
    let centre = DVec3::splat(15.5);
    let mut values = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let r = (DVec3::new(x as f64, y as f64, z as f64) - centre).length();
                values.push((128.0 + 40.0 * (12.0 - r)).clamp(0.0, 255.0) as f32);
            }
        }
    }
    for &([x, y, z], value) in set {
        values[(z * n + y) * n + x] = value;
    }
    let level = 127.5;
    let inside = values.iter().filter(|&&v| v >= level).count() as u64;
    let volume = ScalarVolume {
        size: [n; 3],
        values,
        to_world: DAffine3::from_scale(DVec3::splat(0.5)),
    };
    let opts = MeshOptions {
        region: Region::Threshold(level as f64),
        smooth: segment::DEFAULT_SMOOTH,
        smoother: Default::default(),
        all_components,
        fill_voids: false,
        faces: Some(600),
        max_handle: None,
        within_voxels: None,
    };
    (volume, inside, opts)
}

/// The 2 x 2 x 2 voxels from `corner` up, each set to `value`.
fn block(corner: [usize; 3], value: f32) -> impl Iterator<Item = ([usize; 3], f32)> {
    (0..8).map(move |d| {
        let [x, y, z] = corner;
        ([x + (d & 1), y + (d >> 1 & 1), z + (d >> 2)], value)
    })
}

/// A probability map's voids can be specks: a voxel just under the level
/// encloses a shell far smaller than a voxel, and the smoothing shrinks
/// a void of one voxel to a speck too (the MNI grey matter at 0.5 has
/// 231 voids, 173 of them under a sixteenth of a voxel smoothed). Those
/// are filled; a void of a few voxels stays an inner shell, and
/// decimated (the smallest pieces are the cheapest to collapse) keeps at
/// least four faces enclosing a volume, with the angles kept: not a
/// doubled triangle (there were 211 in the grey matter, with angles of
/// 5 degrees).
#[test]
fn a_probability_maps_voids_stay_shells_unless_finer_than_a_voxel() {
    // Three voxels a hair under the level, one far under it, and two
    // blocks of 2 x 2 x 2 far under it.
    let mut set: Vec<([usize; 3], f32)> = [[11, 15, 15], [20, 15, 15], [15, 11, 15]]
        .map(|v| (v, 127.4))
        .to_vec();
    set.push(([15, 20, 15], 0.0));
    set.extend(block([14, 14, 10], 0.0).chain(block([14, 14, 19], 0.0)));
    let (volume, inside, opts) = probability_ball(&set, false);
    let (mesh, report) = segment::mesh(&volume, Path::new("ball.nii"), &opts, &Silent).unwrap();
    assert_eq!(
        (report.voids, report.voids_unresolved),
        (6, 4),
        "{report:?}"
    );
    assert_eq!(report.voxels, inside + 4, "{report:?}");
    assert_eq!(check_surface(&mesh, "ball with voids"), vec![0; 3]);
    assert!(
        report.min_angle >= organtex::mesh::decimate::MIN_ANGLE,
        "{report:?}"
    );
    // The ball, and the blocks' shells facing into them, each of at
    // least four faces enclosing a sixteenth of a voxel or more (1/128
    // mm^3 here). A doubled triangle encloses exactly nothing.
    let void_shells = |mesh: &organtex::mesh::TriMesh| {
        let mut shells = shells(mesh);
        shells.sort_by(|a, b| a.1.total_cmp(&b.1));
        shells.pop();
        for &(faces, volume) in &shells {
            assert!(
                faces >= 4 && volume <= -1.0 / 128.0,
                "a void's shell of {faces} faces enclosing {volume}"
            );
        }
        shells.len()
    };
    assert_eq!(void_shells(&mesh), 2);
    // A windowed sinc shrinks a speck as far, and can mirror it: none is
    // left all the same.
    let sinc = MeshOptions {
        smoother: segment::Smoother::WindowedSinc,
        ..opts.clone()
    };
    let (mesh, report) = segment::mesh(&volume, Path::new("ball.nii"), &sinc, &Silent).unwrap();
    check_surface(&mesh, "ball with voids, windowed sinc");
    assert_eq!(
        void_shells(&mesh),
        6 - report.voids_unresolved,
        "{report:?}"
    );
    assert!(report.voids_unresolved >= 4, "{report:?}");
    // Neither smoothed nor decimated, the deep voxel's shell is an
    // octahedron of a sixth of a voxel (1/48 mm^3) and stays; the three a
    // hair under the level are still specks. (The default smoothing
    // shrinks that octahedron to a speck, as it does every shell all of
    // whose bends are the staircase's.)
    let raw = MeshOptions {
        smooth: 0,
        faces: None,
        ..opts.clone()
    };
    let (mesh, report) = segment::mesh(&volume, Path::new("ball.nii"), &raw, &Silent).unwrap();
    assert_eq!(
        (report.voids, report.voids_unresolved),
        (6, 3),
        "{report:?}"
    );
    let mut enclosed: Vec<f64> = shells(&mesh).iter().map(|s| s.1).collect();
    enclosed.sort_by(f64::total_cmp);
    assert!((enclosed[2] + 1.0 / 48.0).abs() < 1e-9, "{enclosed:?}");
    // Filled by the flag, every void is gone.
    let filled = MeshOptions {
        fill_voids: true,
        ..opts
    };
    let (mesh, report) = segment::mesh(&volume, Path::new("ball.nii"), &filled, &Silent).unwrap();
    assert_eq!(
        (report.voids, report.voids_unresolved),
        (6, 0),
        "{report:?}"
    );
    assert_eq!(report.voxels, inside + 3 + 1 + 16, "{report:?}");
    assert_eq!(check_surface(&mesh, "ball with voids filled"), vec![0]);
}

/// The pieces `--all-components` keeps are held to the same resolution as
/// the voids: a probability map's voxel a hair over the level, and a lone
/// voxel (its octahedron, a sixth of a voxel, smoothed to a speck), are
/// dropped, not left as four faces enclosing nothing with a mean
/// curvature in the thousands (the MNI white matter kept whole has 49
/// pieces besides the largest: a spread of 42 against 0.31); a block of
/// eight voxels stays, a closed shell enclosing a volume.
#[test]
fn islands_finer_than_a_voxel_are_dropped_from_every_piece_kept() {
    // In the corners, far from the ball and from each other: three voxels
    // a hair over the level, one far over it, a block of 2 x 2 x 2.
    let mut set: Vec<([usize; 3], f32)> = [[2, 2, 2], [29, 2, 2], [2, 29, 2]]
        .map(|v| (v, 127.6))
        .to_vec();
    set.push(([29, 29, 2], 255.0));
    set.extend(block([2, 2, 27], 255.0));
    let (volume, inside, opts) = probability_ball(&set, true);
    let mesh_of = |opts: &MeshOptions| {
        let (mesh, report) =
            segment::mesh(&volume, Path::new("islands.nii"), opts, &Silent).unwrap();
        // Every shell left encloses a sixteenth of a voxel or more (1/128
        // mm^3 here), with four faces at least.
        let shells = shells(&mesh);
        for &(faces, enclosed) in &shells {
            assert!(
                faces >= 4 && enclosed >= 1.0 / 128.0,
                "a shell of {faces} faces enclosing {enclosed}: {report:?}"
            );
        }
        assert_eq!(shells.len(), report.components_kept, "{report:?}");
        (mesh, report)
    };
    let (mesh, report) = mesh_of(&opts);
    let counts = (
        report.components,
        report.components_kept,
        report.islands_unresolved,
    );
    assert_eq!(counts, (6, 2, 4), "{report:?}");
    assert_eq!(report.voxels, inside - 4, "{report:?}");
    assert_eq!(check_surface(&mesh, "ball and islands"), vec![0, 0]);
    assert!(
        report.min_angle >= organtex::mesh::decimate::MIN_ANGLE,
        "{report:?}"
    );
    // Unsmoothed, the lone voxel's octahedron stays; the three a hair
    // over the level are still specks.
    let raw = MeshOptions {
        smooth: 0,
        faces: None,
        ..opts.clone()
    };
    let (_, report) = mesh_of(&raw);
    assert_eq!(
        (report.components_kept, report.islands_unresolved),
        (3, 3),
        "{report:?}"
    );
    // A windowed sinc shrinks the block too (5.7 voxels as marched, here
    // to a speck of 0.005), but the scan resolves it: kept, tissue.
    let sinc = MeshOptions {
        smoother: segment::Smoother::WindowedSinc,
        ..opts.clone()
    };
    let (mesh, report) = segment::mesh(&volume, Path::new("islands.nii"), &sinc, &Silent).unwrap();
    let counts = (
        report.components,
        report.components_kept,
        report.islands_unresolved,
    );
    assert_eq!(counts, (6, 2, 4), "{report:?}");
    assert_eq!(
        check_surface(&mesh, "ball and islands, windowed sinc"),
        vec![0, 0]
    );
    let kept = shells(&mesh);
    assert!(
        kept.iter()
            .all(|&(faces, enclosed)| faces >= 4 && enclosed > 0.0),
        "{kept:?}"
    );
    // The largest piece alone: nothing to drop.
    let largest = MeshOptions {
        all_components: false,
        ..opts
    };
    let (_, report) = mesh_of(&largest);
    let counts = (
        report.components,
        report.components_kept,
        report.islands_unresolved,
    );
    assert_eq!(counts, (6, 1, 0), "{report:?}");
}

#[test]
fn the_mni_white_matter_is_closed_manifold_and_keeps_its_volume() {
    let path = volumes("mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz");
    let volume = ScalarVolume::read(&path).unwrap();
    assert_eq!(volume.size, [197, 233, 189]);
    // The probability is stored as 0..255: 0.5 is 127.5.
    let opts = MeshOptions {
        region: Region::Threshold(127.5),
        smooth: 20,
        all_components: false,
        fill_voids: false,
        faces: None,
        max_handle: None,
        within_voxels: None,
        smoother: Default::default(),
    };
    let (mesh, report) = segment::mesh(&volume, &path, &opts, &Silent).unwrap();
    let genus = check_surface(&mesh, "white matter");
    println!("white matter: {report:?}, genus {genus:?}");
    assert!(genus[0] > 0, "the white matter's surface has handles");
    let ratio = report.volume / report.voxel_volume;
    assert!((ratio - 1.0).abs() <= 0.01, "volume {ratio}");
    // In the MNI frame: the brain's box spans about -70..70 mm in x.
    let (lo, hi) = mesh.bounding_box().unwrap();
    assert!(
        lo.x < -55.0 && hi.x > 55.0 && lo.x > -99.0 && hi.x < 99.0,
        "{lo}..{hi}"
    );
    // Same bytes on one thread.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| segment::mesh(&volume, &path, &opts, &Silent).unwrap().0);
    assert_eq!(one.positions, mesh.positions);
    assert_eq!(one.triangles, mesh.triangles);
    // Decimated to 50k faces (issue 40's budget) as the CLI does it:
    // closed, manifold, of the same genus, its volume kept, and no angle
    // under 20 degrees on this convoluted surface, where marching
    // tetrahedra's slivers and the gyri's thin crests leave caps that only
    // the decimation's cleanup (corner moves, collapses, flips over
    // creases) mends.
    // As `segment::mesh` decimates: each round within a quarter-voxel
    // envelope.
    let envelope = Hold::EachRound(0.25 * volume.voxel_volume().cbrt());
    let (small, _) =
        organtex::mesh::decimate::decimate(&mesh, 50_000, 5, Some(envelope), &Silent).unwrap();
    assert!(small.num_faces() <= 50_000);
    assert_eq!(check_surface(&small, "white matter, 50k faces"), genus);
    let ratio = small.signed_volume() / report.voxel_volume;
    assert!((ratio - 1.0).abs() <= 0.01, "volume at 50k faces {ratio}");
    let worst = (0..small.num_faces())
        .map(|f| {
            let [a, b, c] = small.corners(f);
            organtex::mesh::decimate::min_angle(a, b, c)
        })
        .fold(180.0, f64::min);
    assert!(
        worst >= organtex::mesh::decimate::MIN_ANGLE,
        "smallest angle at 50k faces {worst}"
    );
}

#[test]
fn held_within_its_voxels_the_white_matter_keeps_its_gyri_at_50k_faces() {
    // By default the decimation cuts the thin gyri's crests off, leaving
    // voxel corners 2.5 voxels from the surface; with every corner held
    // through it the farthest is about one voxel, and the surface is as
    // closed, manifold and well shaped as ever.
    let path = volumes("mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz");
    let volume = ScalarVolume::read(&path).unwrap();
    let opts = MeshOptions {
        region: Region::Threshold(127.5),
        smooth: segment::DEFAULT_SMOOTH,
        smoother: Default::default(),
        all_components: false,
        fill_voids: false,
        faces: Some(50_000),
        max_handle: None,
        within_voxels: Some(segment::fit::TOLERANCE),
    };
    let (mesh, report) = segment::mesh(&volume, &path, &opts, &Silent).unwrap();
    println!("white matter held within its voxels: {report:?}");
    assert!(mesh.num_faces() <= 50_000);
    check_surface(&mesh, "white matter within its voxels");
    let fit = report.fit;
    // The fit then holds every point of the voxel faces (1,259,022, four
    // per corner): a dozen lie beyond 0.9 voxel, none beyond one (the
    // farthest 0.98; 2.5 without the hold). And the other way: the
    // surface strays beyond 0.9 voxel from the voxel faces on a few dozen
    // faces, nowhere by a voxel (0.99; 1.10 when drawn to them one way).
    assert!(fit.points > 3 * 313_904, "{fit:?}");
    assert!(fit.far <= 20, "{fit:?}");
    assert!(fit.farthest.is_none_or(|d| d <= 1.0), "{fit:?}");
    assert!(fit.faces_off.is_some_and(|n| n <= 100), "{fit:?}");
    assert!(fit.farthest_off.is_none_or(|d| d <= 1.0), "{fit:?}");
    let ratio = report.volume / report.voxel_volume;
    assert!((ratio - 1.0).abs() <= 0.01, "volume {ratio}");
    assert!(
        report.min_angle >= organtex::mesh::decimate::MIN_ANGLE,
        "{}",
        report.min_angle
    );
    // Held within 1.4 voxels (the surface not drawn to them first): no
    // corner got farther through the decimation.
    let loose = MeshOptions {
        within_voxels: Some(1.4),
        ..opts
    };
    let (mesh, report) = segment::mesh(&volume, &path, &loose, &Silent).unwrap();
    check_surface(&mesh, "white matter within 1.4 voxels");
    assert!(
        report.fit.farthest_before.is_none_or(|d| d <= 1.4 + 1e-9),
        "{:?}",
        report.fit
    );
    // Closer than a staircase allows is refused.
    let tight = MeshOptions {
        within_voxels: Some(0.5),
        ..opts
    };
    let e = segment::mesh(&volume, &path, &tight, &Silent).unwrap_err();
    assert!(
        e.to_string().contains("cannot be held within 0.5 voxel"),
        "{e}"
    );
}

#[test]
fn the_brain_from_the_mni_t1_is_a_sphere_written_by_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("brain.ply");
    let path = volumes("mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz");
    let figures = mesh_json(
        &[
            path.to_str().unwrap(),
            "--threshold",
            "40",
            "-o",
            out.to_str().unwrap(),
        ],
        0.01,
    );
    assert_eq!(figures["genus"], serde_json::json!([0]), "{figures}");
    assert_eq!(figures["normals"], "outward");
    // The written file reads back as the same closed surface.
    let mesh = organtex::mesh::io::read(&out).unwrap();
    assert_eq!(check_surface(&mesh, "brain.ply"), vec![0]);
    assert_eq!(mesh.num_faces() as u64, figures["faces"].as_u64().unwrap());
    // Decimated to 50k faces: still closed, manifold, genus 0, its volume
    // and no angle under the decimation's floor.
    let small = dir.path().join("brain50k.stl");
    let f = mesh_json(
        &[
            path.to_str().unwrap(),
            "--threshold",
            "40",
            "--faces",
            "50000",
            "-o",
            small.to_str().unwrap(),
        ],
        0.01,
    );
    assert!(f["faces"].as_u64().unwrap() <= 50_000, "{f}");
    assert_eq!(f["genus"], serde_json::json!([0]), "{f}");
    assert!(
        f["min_angle"].as_f64().unwrap() >= organtex::mesh::decimate::MIN_ANGLE,
        "{f}"
    );
    // Every corner of the voxel boundary within a voxel of the surface
    // (issue 40; 1.06 before the fit to the voxels, `segment::fit`).
    let fit = &f["fit"];
    assert!(fit["farthest_before"].as_f64() > Some(1.0), "{fit}");
    assert!(fit["farthest"].as_f64().is_none_or(|d| d <= 1.0), "{fit}");
    let mesh = organtex::mesh::io::read(&small).unwrap();
    assert_eq!(check_surface(&mesh, "brain50k.stl"), vec![0]);
}

#[test]
fn bad_segmentations_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let good = nifti::to_bytes(&labelled(DAffine3::IDENTITY));
    let with = |edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = good.clone();
        edit(&mut b);
        b
    };
    let cases: Vec<(&str, Vec<u8>, &[&str], &str)> = vec![
        (
            "truncated",
            good[..good.len() - 100].to_vec(),
            &["--label", "3"],
            "truncated",
        ),
        (
            "short",
            good[..200].to_vec(),
            &["--label", "3"],
            "a NIfTI-1 header alone is 348",
        ),
        (
            "magic",
            with(&|b| b[344..348].copy_from_slice(b"xyz\0")),
            &["--label", "3"],
            "magic",
        ),
        (
            "notnifti",
            b"GIF89a not a volume at all".to_vec(),
            &["--label", "3"],
            "not a NIfTI-1 file",
        ),
        (
            "4d",
            with(&|b| {
                b[40..42].copy_from_slice(&4i16.to_le_bytes());
                b[48..50].copy_from_slice(&2i16.to_le_bytes());
            }),
            &["--label", "3"],
            "a 4D volume (dim[4] = 2 time points)",
        ),
        (
            "singular",
            with(&|b| b[296..312].copy_from_slice(&[0u8; 16])),
            &["--label", "3"],
            "direction matrix is singular",
        ),
        (
            "absent",
            good.clone(),
            &["--label", "7"],
            "no voxel has label 7 (labels present: 0, 1, 3)",
        ),
        (
            "empty",
            good.clone(),
            &["--threshold", "9"],
            "no voxel reaches the threshold 9",
        ),
        (
            "full",
            good.clone(),
            &["--threshold", "-1"],
            "the region fills the whole volume",
        ),
    ];
    for (name, bytes, args, expect) in cases {
        let file = dir.path().join(format!("{name}.nii"));
        std::fs::write(&file, bytes).unwrap();
        let out = dir.path().join(format!("{name}.obj"));
        let mut all = vec!["mesh", file.to_str().unwrap(), "-o", out.to_str().unwrap()];
        all.extend(args);
        let (ok, _, stderr) = organtex(&all);
        assert!(!ok, "{name}: accepted");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(stderr.contains(file.to_str().unwrap()), "{name}: {stderr}");
        assert!(
            stderr.contains(expect),
            "{name}: expected `{expect}` in {stderr}"
        );
        assert!(!out.exists(), "{name}: wrote {}", out.display());
    }
}

/// A 3D Slicer segmentation as Slicer writes one: LPS space, a turned
/// and anisotropic direction matrix, two overlapping segments in two
/// layers along a first `list` axis, gzip. Layer 0: the MNI white matter
/// (>= 0.5) in a crop of the real map; layer 1: a ball across it.
/// Returns the file, the layers' values and the voxel-to-RAS map the
/// header means (LPS with x and y negated, written out by hand here).
fn slicer_segmentation(dir: &Path) -> (PathBuf, [Vec<f32>; 2], [usize; 3], DAffine3) {
    let wm =
        ScalarVolume::read(&volumes("mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz")).unwrap();
    let (origin, size) = ([70, 90, 70], [44usize, 40, 36]);
    let mut white = Vec::new();
    let mut ball = Vec::new();
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let v = wm.values[wm.index(origin[0] + x, origin[1] + y, origin[2] + z)];
                white.push(if v >= 127.5 { 1.0 } else { 0.0 });
                let p = DVec3::new(x as f64 - 20.0, y as f64 - 18.0, z as f64 - 15.0);
                ball.push(if p.length() <= 9.0 { 4.0 } else { 0.0 });
            }
        }
    }
    // LPS columns: 30 degrees about the axial axis, spacings 0.9, 1.1, 1.3.
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let lps = DMat3::from_cols(
        DVec3::new(c, s, 0.0) * 0.9,
        DVec3::new(-s, c, 0.0) * 1.1,
        DVec3::new(0.0, 0.0, 1.3),
    );
    let lps_origin = DVec3::new(12.5, -40.0, 33.0);
    let axis = |v: DVec3| format!("({},{},{})", v.x, v.y, v.z);
    let header = format!(
        "NRRD0004\n# Complete NRRD file format specification at:\n\
         # http://teem.sourceforge.net/nrrd/format.html\n\
         type: short\ndimension: 4\nspace: left-posterior-superior\n\
         sizes: 2 {} {} {}\nspace directions: none {} {} {}\n\
         kinds: list domain domain domain\nencoding: gzip\nendian: little\n\
         space origin: {}\nSegment0_Color:=0.9 0.9 0.8\nSegment0_ID:=Segment_1\n\
         Segment0_LabelValue:=1\nSegment0_Layer:=0\nSegment0_Name:=white matter\n\
         Segment1_ID:=Segment_2\nSegment1_LabelValue:=4\nSegment1_Layer:=1\n\
         Segment1_Name:=lesion\nSegmentation_MasterRepresentation:=Binary labelmap\n\n",
        size[0],
        size[1],
        size[2],
        axis(lps.x_axis),
        axis(lps.y_axis),
        axis(lps.z_axis),
        axis(lps_origin)
    );
    let mut raw = Vec::new();
    for k in 0..white.len() {
        for layer in [&white, &ball] {
            raw.extend_from_slice(&(layer[k] as i16).to_le_bytes());
        }
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&raw).unwrap();
    let mut bytes = header.into_bytes();
    bytes.extend(gz.finish().unwrap());
    let path = dir.join("brain.seg.nrrd");
    std::fs::write(&path, bytes).unwrap();
    let flip = DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0));
    let ras = DAffine3::from_mat3_translation(flip * lps, flip * lps_origin);
    (path, [white, ball], size, ras)
}

#[test]
fn a_slicer_segmentation_meshes_each_segment_by_name_in_ras_millimetres() {
    let dir = tempfile::tempdir().unwrap();
    let (path, layers, size, ras) = slicer_segmentation(dir.path());
    // Each segment: its layer, its label value, the header's map in RAS.
    for (name, layer, label) in [("white matter", 0, 1), ("lesion", 1, 4)] {
        let (volume, region) =
            segment::open(&path, &segment::Choice::Segment(name.into())).unwrap();
        assert_eq!(region, Region::Label(label));
        assert_eq!(volume.size, size);
        assert_eq!(volume.values, layers[layer]);
        let m = volume.to_world;
        for (a, b) in [
            (m.matrix3.x_axis, ras.matrix3.x_axis),
            (m.matrix3.y_axis, ras.matrix3.y_axis),
            (m.matrix3.z_axis, ras.matrix3.z_axis),
            (m.translation, ras.translation),
        ] {
            assert!(a.abs_diff_eq(b, 1e-12), "{name}: {a} vs {b}");
        }
    }
    // Through the CLI, by name (any case): the white matter of the real
    // map (its crop in pieces, all kept) closed, manifold, outward and of
    // its voxels' volume.
    let out = dir.path().join("wm.obj");
    mesh_json(
        &[
            path.to_str().unwrap(),
            "--segment",
            "White Matter",
            "--all-components",
            "-o",
            out.to_str().unwrap(),
        ],
        0.02,
    );
    check_surface(
        &organtex::mesh::io::read(&out).unwrap(),
        "white matter crop",
    );
    // The lesion (one piece, in its own layer): taken back through the
    // map, its surface spans its voxels within half a voxel (the
    // smoothing moves it that little).
    let out = dir.path().join("lesion.stl");
    let (ok, _, stderr) = organtex(&[
        "mesh",
        path.to_str().unwrap(),
        "--segment",
        "lesion",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let mesh = organtex::mesh::io::read(&out).unwrap();
    check_surface(&mesh, "lesion");
    let (vlo, vhi) = span_in_voxels(&mesh, ras);
    let (ilo, ihi) = label_box(size, &layers[1], 4.0);
    assert!(
        (vlo - (ilo - 0.5)).abs().max_element() <= 0.5
            && (vhi - (ihi + 0.5)).abs().max_element() <= 0.5,
        "surface spans {vlo}..{vhi} in voxels, the segment {ilo}..{ihi}"
    );
    // A name not there: refused, the names there listed; a label of a
    // two-layer file: which layer is ambiguous. Nothing written either way.
    let missing = dir.path().join("missing.obj");
    for (choice, wants) in [
        (
            ["--segment", "liver"],
            &[
                "brain.seg.nrrd",
                "no segment 'liver'",
                "'white matter', 'lesion'",
            ][..],
        ),
        (
            ["--label", "1"],
            &["brain.seg.nrrd", "2 layers", "--segment"][..],
        ),
    ] {
        let (ok, _, stderr) = organtex(
            &[
                &["mesh", path.to_str().unwrap()],
                &choice[..],
                &["-o", missing.to_str().unwrap()],
            ]
            .concat(),
        );
        assert!(!ok);
        assert!(wants.iter().all(|w| stderr.contains(w)), "{stderr}");
        assert!(!missing.exists());
    }
}

#[test]
fn a_scene_from_the_mni_brain_bakes_end_to_end() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/mni_brain.toml");
    // The node's mesh: the segmentation's surface, closed, genus 0, within
    // the face budget, in the scan's millimetres.
    let spec = organtex::scene::file::load(&scene).unwrap();
    let (mesh, _) = organtex::scene::build::node_mesh(&spec.nodes[0], &Silent).unwrap();
    assert_eq!(check_surface(&mesh, "brain"), vec![0]);
    assert!(mesh.num_faces() <= 20_000 && mesh.num_faces() > 15_000);
    let t1 =
        ScalarVolume::read(&volumes("mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")).unwrap();
    let (blo, bhi) = segment::region_box(&t1, |v| v >= 40.0).unwrap();
    let (lo, hi) = mesh.bounding_box().unwrap();
    // The largest piece, smoothed and decimated, inside the region's box
    // and spanning most of it.
    assert!(
        lo.cmpge(blo - 1.0).all() && hi.cmple(bhi + 1.0).all(),
        "{lo}..{hi} vs {blo}..{bhi}"
    );
    assert!(
        ((hi - lo) / (bhi - blo)).min_element() > 0.9,
        "{lo}..{hi} vs {blo}..{bhi}"
    );
    // The bake: .glb, preview, the interior block and its tets.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("brain");
    let (ok, stdout, stderr) =
        organtex(&["bake", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("brain/surface"), "{stdout}");
    let glb = std::fs::read(out.join("scene.glb")).unwrap();
    assert_eq!(&glb[0..4], b"glTF");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(
        report["facets"][0]["faces"].as_u64().unwrap() as usize,
        mesh.num_faces()
    );
    // What meshing the segmentation measured, in the report and on screen:
    // the same surface, its volume within 1% of the voxels'.
    let seg = &report["segmentations"][0];
    assert_eq!(seg["node"], "brain", "{report}");
    assert_eq!(
        seg["mesh"]["faces"].as_u64().unwrap() as usize,
        mesh.num_faces()
    );
    let (volume, voxels) = (
        seg["mesh"]["volume"].as_f64().unwrap(),
        seg["mesh"]["voxel_volume"].as_f64().unwrap(),
    );
    assert!((volume / voxels - 1.0).abs() < 0.01, "{seg}");
    assert!(
        seg["mesh"]["fit"]["points"].as_u64().unwrap() > 10_000,
        "{seg}"
    );
    assert!(
        stdout.contains("node 'brain' meshed from its segmentation"),
        "{stdout}"
    );
    let tets = &report["interiors"][0]["tet_mesh"];
    assert!(tets["tets"].as_u64().unwrap() > 10_000, "{report}");
    assert!(tets["min_dihedral"].as_f64().unwrap() > 10.0, "{report}");
    for file in ["interior/brain.nrrd", "interior/brain.vtk", "preview.png"] {
        assert!(out.join(file).is_file(), "{file}");
    }
    // A segmentation that names no region, or a file not there: one error
    // naming the scene's line.
    for (edit, why) in [
        (
            "threshold = 40.0",
            "exactly one of `label`, `segment` or `threshold`",
        ),
        ("volumes/mni_icbm152_t1", "not found"),
    ] {
        let text = std::fs::read_to_string(&scene).unwrap();
        let bad = match edit {
            "threshold = 40.0" => text.replace(edit, ""),
            _ => text.replace(edit, "volumes/missing_t1"),
        };
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, bad).unwrap();
        let err = organtex::scene::file::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("mesh.segmentation") && err.contains(why),
            "{err}"
        );
        assert!(err.contains("line"), "{err}");
    }
}

/// What the viewer offers when it opens a file: a Slicer segmentation's
/// segments by name with their voxels, largest first; the MNI white
/// matter (a probability map stored as 0..255) a threshold inside its
/// range, no labels.
#[test]
fn a_files_regions_are_listed_for_the_user_to_choose() {
    use segment::contents::contents;
    let dir = tempfile::tempdir().unwrap();
    let (path, layers, _, _) = slicer_segmentation(dir.path());
    let c = contents(&path).unwrap();
    let count =
        |layer: usize, label: f32| layers[layer].iter().filter(|&&v| v == label).count() as u64;
    let mut want = vec![
        (
            segment::Choice::Segment("white matter".into()),
            count(0, 1.0),
        ),
        (segment::Choice::Segment("lesion".into()), count(1, 4.0)),
    ];
    want.sort_by_key(|w| std::cmp::Reverse(w.1));
    let got: Vec<_> = c
        .regions
        .iter()
        .map(|r| (r.choice.clone(), r.voxels))
        .collect();
    assert_eq!(got, want);
    assert!(c.regions.iter().all(|r| r.name.contains("voxels")));

    let wm = contents(&volumes("mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz")).unwrap();
    assert!(
        wm.regions.is_empty(),
        "{:?}",
        &wm.regions[..3.min(wm.regions.len())]
    );
    assert_eq!(wm.range, (0.0, 255.0));
    assert!(
        wm.threshold > 50.0 && wm.threshold < 200.0,
        "{}",
        wm.threshold
    );
    assert_eq!(
        wm.default_choice(),
        segment::Choice::Threshold(wm.threshold)
    );
}

/// `--max-handle` on the MNI white matter at 0.5: most of its handles
/// (voxel-thin bridges across sulci) go by a few hundred voxels' cuts and
/// plugs, the surface stays closed, manifold and outward, its pieces and
/// volume as they were; a larger size leaves no more handles.
#[test]
fn thin_handles_of_the_white_matter_are_cut_or_plugged() {
    let path = volumes("mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz");
    let figures = |mm: &str| {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("wm.ply");
        let (ok, stdout, stderr) = organtex(&[
            "mesh",
            path.to_str().unwrap(),
            "--threshold",
            "127.5",
            "--json",
            "--max-handle",
            mm,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{stderr}");
        let mesh = organtex::mesh::io::read(&out).unwrap();
        let genus = check_surface(&mesh, "white matter");
        let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        (json, genus)
    };
    let (two, genus) = figures("2");
    let h = &two["handles"];
    let (before, after) = (
        h["genus_before"].as_i64().unwrap(),
        h["genus_after"].as_i64().unwrap(),
    );
    println!("2 mm: {h}, surface genus {genus:?}");
    // The largest piece's surface has the region's handles less what the
    // small pieces have (one, as 229 of 230 without the fix).
    assert!(before >= 200, "{h}");
    assert!(
        after * 5 <= before,
        "at most a fifth of the handles left: {h}"
    );
    assert!(genus[0] <= after, "{genus:?} {h}");
    let changed = h["voxels_removed"].as_u64().unwrap() + h["voxels_added"].as_u64().unwrap();
    let region = two["region_voxels"].as_u64().unwrap();
    assert!(
        changed * 1000 < region,
        "{changed} of {region} voxels changed"
    );
    let ratio = two["volume"].as_f64().unwrap() / two["voxel_volume"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() <= 0.01, "volume {ratio}");
    assert_eq!(two["components"], 50, "pieces are not split or joined");
    let (three, _) = figures("3");
    assert!(
        three["handles"]["genus_after"].as_i64().unwrap() <= after,
        "{}",
        three["handles"]
    );
}

/// `--smoother sinc` (windowed sinc) takes a ball's voxel staircase
/// further away than Taubin's lambda/mu in the same iterations: its
/// vertices lie nearer one sphere, the surface stays closed, manifold and
/// outward, and the volume stays the voxels'.
#[test]
fn the_windowed_sinc_leaves_a_rounder_ball_than_taubin() {
    let size = [28, 28, 28];
    let centre = DVec3::splat(13.5);
    let mut values = Vec::new();
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let p = DVec3::new(x as f64, y as f64, z as f64);
                values.push(if (p - centre).length() <= 10.0 {
                    1.0
                } else {
                    0.0
                });
            }
        }
    }
    let volume = ScalarVolume {
        size,
        values,
        to_world: DAffine3::IDENTITY,
    };
    let spread = |smoother| {
        let opts = MeshOptions {
            region: Region::Label(1),
            smooth: 20,
            smoother,
            all_components: false,
            fill_voids: false,
            faces: None,
            max_handle: None,
            within_voxels: None,
        };
        let (mesh, report) = segment::mesh(&volume, Path::new("ball.nii"), &opts, &Silent).unwrap();
        assert_eq!(check_surface(&mesh, "ball"), vec![0]);
        let ratio = report.volume / report.voxel_volume;
        assert!((ratio - 1.0).abs() < 0.03, "{smoother:?}: volume {ratio}");
        let r: Vec<f64> = mesh
            .positions
            .iter()
            .map(|p| (*p - centre).length())
            .collect();
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt()
    };
    let taubin = spread(segment::Smoother::Taubin);
    let sinc = spread(segment::Smoother::WindowedSinc);
    println!("radius spread: Taubin {taubin:.4}, windowed sinc {sinc:.4} voxels");
    assert!(sinc < 0.7 * taubin, "Taubin {taubin}, sinc {sinc}");
}
