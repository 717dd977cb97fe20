//! Fuzz targets: one function per file format a user hands organtex.
//!
//! Each takes arbitrary bytes and must never panic: bad input is an
//! `Err`, and where the parse succeeds the function asserts what the rest
//! of organtex relies on, so the fuzzer also finds wrong results, not just
//! crashes. `fuzz/fuzz_targets/<name>.rs` calls `<name>` under libFuzzer
//! (`tools/fuzz.sh`); `tests/fuzz_regressions.rs` replays the seed corpus
//! and every crash found through the same functions.

use std::io::Cursor;
use std::path::Path;

use crate::Error;
use crate::db::index::{Database, Output};
use crate::mesh::TriMesh;
use crate::mesh::io::{obj as obj_io, ply as ply_io, stl as stl_io};
use crate::scene::file::{MeshSpec, SceneSpec};
use crate::synth::block::MAX_BLOCK;
use crate::synth::exemplar::Exemplar;
use crate::synth::volume::Volume;
use glam::DVec3;

/// OBJ (`mesh::io::obj::parse`): on success, see `check_mesh`.
pub fn obj(bytes: &[u8]) {
    check_mesh(obj_io::parse(Path::new("fuzz.obj"), bytes));
}

/// PLY (`mesh::io::ply::parse`): on success, see `check_mesh`.
pub fn ply(bytes: &[u8]) {
    check_mesh(ply_io::parse(Path::new("fuzz.ply"), bytes));
}

/// STL (`mesh::io::stl::parse`): on success, see `check_mesh`.
pub fn stl(bytes: &[u8]) {
    check_mesh(stl_io::parse(Path::new("fuzz.stl"), bytes));
}

/// A parsed mesh: positions finite, every face index below the vertex
/// count, one facet id per face naming an existing facet, one uv triangle
/// per face with indices below the uv count and finite uvs.
fn check_mesh(parsed: crate::Result<TriMesh>) {
    let mesh = match parsed {
        Ok(mesh) => mesh,
        Err(e) => return check_error(e),
    };
    let n = mesh.positions.len();
    assert!(
        mesh.positions.iter().all(|p| p.is_finite()),
        "a position is not finite"
    );
    assert!(
        mesh.triangles.iter().flatten().all(|&v| (v as usize) < n),
        "a face index is out of range ({n} vertices)"
    );
    if let Some(f) = &mesh.facets {
        assert_eq!(f.of_face.len(), mesh.triangles.len(), "facet ids per face");
        assert!(
            f.of_face.iter().all(|&i| (i as usize) < f.names.len()),
            "facet id out of range"
        );
    }
    if let Some(uv) = &mesh.uvs {
        assert_eq!(
            uv.triangles.len(),
            mesh.triangles.len(),
            "uv triangles per face"
        );
        let m = uv.coords.len();
        assert!(
            uv.triangles.iter().flatten().all(|&t| (t as usize) < m),
            "a uv index is out of range"
        );
        assert!(
            uv.coords.iter().all(|t| t.is_finite()),
            "a uv is not finite"
        );
    }
}

/// Every error must be printable (its message names the file).
fn check_error(e: Error) {
    assert!(!e.to_string().is_empty());
}

thread_local! {
    /// This thread's folder of the fixed files the targets need, made once:
    /// an input then costs one file write, not a folder of files.
    static DIR: tempfile::TempDir = fixture_dir();
}

/// A one-triangle `a.obj` and `b.ply` for scenes to reference, a 2 x 2
/// `a.png` for the database index, and the 6 x 6 `image.png` that `mask`
/// masks.
fn fixture_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("cannot create a temporary folder");
    write(
        &dir.path().join("a.obj"),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    write(
        &dir.path().join("b.ply"),
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
          property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
          0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    write_png(&dir.path().join("a.png"), 2);
    write_png(&dir.path().join("image.png"), 6);
    dir
}

/// Write `bytes` as `name` beside the fixed files, run `f` on the folder,
/// and remove the file again, so no input sees another's.
fn with_file<R>(name: &str, bytes: &[u8], f: impl FnOnce(&Path) -> R) -> R {
    DIR.with(|dir| {
        let path = dir.path().join(name);
        write(&path, bytes);
        let result = f(dir.path());
        let _ = std::fs::remove_file(&path);
        result
    })
}

fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

/// A `side` x `side` colour ramp.
fn ramp(side: u32) -> image::RgbImage {
    image::RgbImage::from_fn(side, side, |x, y| {
        image::Rgb([(40 * x) as u8, (40 * y) as u8, 128])
    })
}

/// `ramp(side)` as a PNG.
fn write_png(path: &Path, side: u32) {
    ramp(side)
        .save(path)
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

/// The scene file (`scene::file::load`), written as `scene.toml` beside a
/// one-triangle `a.obj` and `b.ply` it may reference. On success: at least
/// one node, node names unique, every mesh file an existing file, cameras
/// finite with fov 1..=170 and look_at apart from position, every facet
/// number finite and in its range (tile sizes and max_stretch positive,
/// bump 0..=10, overlay_opacity 0..=1, overlap >= 0, max_conformal >= 1),
/// interior block sizes finite and positive, interior_voxels a multiple of
/// 16 from 16 to `MAX_BLOCK`.
pub fn scene(bytes: &[u8]) {
    match with_file("scene.toml", bytes, |dir| {
        crate::scene::file::load(&dir.join("scene.toml"))
    }) {
        Ok(spec) => check_scene(&spec),
        Err(e) => check_error(e),
    }
}

fn check_scene(spec: &SceneSpec) {
    assert!(!spec.nodes.is_empty(), "a scene without nodes loaded");
    let mut names = std::collections::HashSet::new();
    for node in &spec.nodes {
        assert!(names.insert(&node.name), "node '{}' twice", node.name);
        if let MeshSpec::File(p) = &node.mesh {
            assert!(p.is_file(), "mesh file {} is no file", p.display());
        }
        for f in &node.facets {
            let numbers = [
                f.tile_size,
                f.rotation,
                f.offset[0],
                f.offset[1],
                f.bump,
                f.overlay_opacity,
                f.overlay_tile_size,
                f.overlap,
                f.max_stretch,
                f.max_conformal,
            ];
            assert!(
                numbers.iter().all(|x| x.is_finite()),
                "facet '{}': a number is not finite: {f:?}",
                f.name
            );
            assert!(
                f.tile_size > 0.0 && f.overlay_tile_size > 0.0,
                "facet '{}': tile size",
                f.name
            );
            assert!((0.0..=10.0).contains(&f.bump), "facet '{}': bump", f.name);
            assert!(
                (0.0..=1.0).contains(&f.overlay_opacity),
                "facet '{}': opacity",
                f.name
            );
            assert!(f.overlap >= 0.0, "facet '{}': overlap", f.name);
            assert!(
                f.max_stretch > 0.0 && f.max_conformal >= 1.0,
                "facet '{}': bounds",
                f.name
            );
        }
        if let Some(i) = &node.interior {
            assert!(
                i.block_size.is_finite() && i.block_size > 0.0,
                "node '{}': interior block_size {}",
                node.name,
                i.block_size
            );
        }
    }
    for c in &spec.cameras {
        assert!(
            c.position.iter().chain(&c.look_at).all(|x| x.is_finite()),
            "camera {c:?} is not finite"
        );
        assert!(
            (1.0..=170.0).contains(&c.fov) && c.position != c.look_at,
            "camera {c:?}"
        );
    }
    let v = spec.bake.interior_voxels;
    assert!(
        (16..=MAX_BLOCK).contains(&v) && v.is_multiple_of(16),
        "interior_voxels {v}"
    );
}

/// The tissue database index (`db::index::Database::open`), written as
/// `index.toml` in a folder that also holds a 2 x 2 `a.png`. On success:
/// ids unique, non-empty, of letters, digits, '-' and '_'; every source and
/// mask an existing file; every tissue has outputs, and synthesis
/// parameters when it makes colour or height.
pub fn db_index(bytes: &[u8]) {
    let db = match with_file("index.toml", bytes, Database::open) {
        Ok(db) => db,
        Err(e) => return check_error(e),
    };
    let mut ids = std::collections::HashSet::new();
    for t in &db.tissues {
        assert!(ids.insert(&t.id), "id '{}' twice", t.id);
        assert!(
            !t.id.is_empty()
                && t.id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_".contains(c)),
            "id '{}'",
            t.id
        );
        for file in std::iter::once(&t.source).chain(&t.mask) {
            assert!(
                db.root.join(file).is_file(),
                "{} is no file",
                file.display()
            );
        }
        assert!(!t.outputs.is_empty(), "tissue '{}' has no outputs", t.id);
        let synthesised = t
            .outputs
            .iter()
            .any(|o| matches!(o, Output::Colour | Output::Height));
        assert!(
            !synthesised || t.synthesis.is_some(),
            "tissue '{}' has no synthesis",
            t.id
        );
    }
}

/// NRRD volumes (`synth::volume::Volume::from_nrrd`). On success: every
/// side at least 1, one voxel per cell (`voxels.len()` the product of
/// `size`), the spacing finite and positive, and writing the volume back
/// with `to_nrrd` and reading it again gives the same volume.
pub fn nrrd(bytes: &[u8]) {
    let Ok(v) = Volume::from_nrrd(bytes) else {
        return;
    };
    assert!(v.size.iter().all(|&s| s >= 1), "size {:?}", v.size);
    let cells = v.size.iter().try_fold(1usize, |n, &s| n.checked_mul(s));
    assert_eq!(Some(v.voxels.len()), cells, "voxels for size {:?}", v.size);
    assert!(
        v.spacing.is_finite() && v.spacing > 0.0,
        "spacing {}",
        v.spacing
    );
    assert_eq!(
        Volume::from_nrrd(&v.to_nrrd()).as_ref(),
        Ok(&v),
        "to_nrrd does not read back"
    );
}

/// NIfTI-1 volumes (`segment::nifti::parse`). On success: every side at
/// least 1, one value per voxel, no NaN, a finite and invertible
/// voxel-to-world map, and writing the volume back with `to_bytes` and
/// reading it again gives the same values and (to float precision) the
/// same map.
pub fn nifti(bytes: &[u8]) {
    let Ok(v) = crate::segment::nifti::parse(bytes) else {
        return;
    };
    assert!(v.size.iter().all(|&s| s >= 1), "size {:?}", v.size);
    assert_eq!(v.values.len(), v.size.iter().product::<usize>());
    assert!(v.values.iter().all(|x| !x.is_nan()), "a NaN value");
    let m = v.to_world.matrix3;
    assert!(m.is_finite() && v.to_world.translation.is_finite());
    assert!(m.determinant() != 0.0, "singular map {m}");
    let back = crate::segment::nifti::parse(&crate::segment::nifti::to_bytes(&v))
        .expect("to_bytes reads back");
    assert_eq!(back.size, v.size);
    assert_eq!(back.values, v.values);
    let close = |a: glam::DVec3, b: glam::DVec3| {
        (a - b).abs().max_element() <= 1e-6 * (1.0 + a.abs().max_element())
    };
    let n = back.to_world.matrix3;
    assert!(
        close(n.x_axis, m.x_axis) && close(n.y_axis, m.y_axis) && close(n.z_axis, m.z_axis),
        "the map does not read back: {m} vs {n}"
    );
}

/// Tet meshes in legacy VTK (`tetra::io::parse_vtk`). On success: every
/// position finite, every tet's four corners distinct vertices of the
/// mesh.
pub fn vtk(bytes: &[u8]) {
    let Ok(m) = crate::tetra::io::parse_vtk(Path::new("fuzz.vtk"), bytes) else {
        return;
    };
    assert!(
        m.positions.iter().all(|p| p.is_finite()),
        "a non-finite point"
    );
    for t in &m.tets {
        assert!(
            t.iter().all(|&i| (i as usize) < m.positions.len()),
            "tet {t:?} beyond {} points",
            m.positions.len()
        );
    }
}

/// Lapped solid texture models (`solid::lst::LstModel::parse`). On
/// success: a valid tet mesh, layer offsets that rise to the layer count,
/// depths exactly for layered types, and writing it gives the same bytes'
/// model back.
pub fn lst(bytes: &[u8]) {
    use crate::solid::lst::LstModel;
    let Ok(m) = LstModel::parse(bytes) else {
        return;
    };
    m.mesh
        .validate()
        .expect("a parsed model's tet mesh is valid");
    assert_eq!(m.start.len(), m.mesh.num_tets() + 1);
    assert!(m.start.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(*m.start.last().unwrap_or(&0) as usize, m.layers.len());
    assert_eq!(m.depth.is_some(), m.kind.layered());
    with_file("fuzz.lst", &[], |dir| {
        let path = dir.join("back.lst");
        m.write(&path).expect("a parsed model writes");
        assert!(
            LstModel::read(&path).expect("and reads back") == m,
            "round trip"
        );
        let _ = std::fs::remove_file(&path);
    });
}

/// The size an image file's header claims, read independently of
/// `Exemplar::load`.
fn claimed_size(bytes: &[u8]) -> Option<(u32, u32)> {
    image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .ok()?
        .into_dimensions()
        .ok()
}

/// Exemplar images (`synth::exemplar::Exemplar::load(path, None, None)`).
/// On success: not empty, the size the file's header claims, one pixel and
/// one validity flag per pixel, some pixel usable.
pub fn image(bytes: &[u8]) {
    let ex = match with_file("exemplar.png", bytes, |dir| {
        Exemplar::load(&dir.join("exemplar.png"), None, None)
    }) {
        Ok(ex) => ex,
        Err(e) => return check_error(e),
    };
    check_exemplar(&ex);
    let claimed = claimed_size(bytes).map(|(w, h)| (w as usize, h as usize));
    assert_eq!(
        Some((ex.width, ex.height)),
        claimed,
        "size differs from the header's"
    );
}

fn check_exemplar(ex: &Exemplar) {
    assert!(ex.width > 0 && ex.height > 0, "empty exemplar");
    assert_eq!(
        ex.pixels.len(),
        ex.width * ex.height,
        "pixels for {}x{}",
        ex.width,
        ex.height
    );
    assert_eq!(ex.valid.len(), ex.pixels.len(), "validity flags");
    assert!(ex.valid.contains(&true), "no usable pixel");
}

/// Exemplar masks (`Exemplar::load(image, Some(mask), None)`), the bytes
/// being the mask of a fixed 6 x 6 RGB image. On success: the image's size
/// and colours unchanged, some pixel usable, and only pixels whose mask
/// value is at least half white usable.
pub fn mask(bytes: &[u8]) {
    let ex = match with_file("mask.png", bytes, |dir| {
        Exemplar::load(&dir.join("image.png"), Some(&dir.join("mask.png")), None)
    }) {
        Ok(ex) => ex,
        Err(e) => return check_error(e),
    };
    check_exemplar(&ex);
    let expected = ramp(6);
    assert_eq!((ex.width, ex.height), (6, 6), "size");
    assert!(
        ex.pixels
            .iter()
            .zip(expected.pixels())
            .all(|(a, b)| *a == b.0),
        "colours changed"
    );
    let luma = image::load_from_memory(bytes)
        .expect("the mask loaded once")
        .to_luma8();
    assert!(
        ex.valid
            .iter()
            .zip(luma.pixels())
            .all(|(&v, m)| !v || m[0] >= 128),
        "a pixel masked out (darker than half) is usable"
    );
}

/// A carving session (`runtime::Carving`) driven by bytes: each op a
/// removal by ids (some past the mesh or repeated), a sphere or a capsule
/// (positions and radii including 0, negative, huge, NaN and infinite),
/// or a wait, over a cube of 6 x 4 x 4 x 4 tets. After an accepted step
/// the carved surface is closed and consistently oriented and equals the
/// last one less the vanished faces plus the appeared ones; after a
/// refused one it is unchanged and the session goes on.
pub fn carving(bytes: &[u8]) {
    use crate::runtime::{Carving, CarvingOptions, Tool};
    use std::collections::HashMap;
    let node = fuzz_cube();
    let background = bytes.first().is_some_and(|b| b & 1 == 1);
    let options = CarvingOptions {
        background_texels: background,
        atlas: crate::runtime::AtlasOptions {
            texels_per_unit: 20.0,
            page_size: 64,
        },
    };
    let mut c = Carving::new(node.clone(), options).expect("a carving of the cube");
    let n = node.tet_mesh().expect("tets").num_tets() as u32;
    let surface = |c: &Carving| -> HashMap<u32, [u32; 3]> {
        c.surface().into_iter().map(|(id, f, _)| (id, f)).collect()
    };
    let mut now = surface(&c);
    let mut at = 1;
    let mut take = |k: usize| -> &[u8] {
        let s = &bytes[at.min(bytes.len())..(at + k).min(bytes.len())];
        at += k;
        s
    };
    let coordinate = |b: u8| match b {
        250 => f64::NAN,
        251 => f64::INFINITY,
        252 => -1e300,
        _ => b as f64 / 200.0 * 1.4 - 0.2,
    };
    let radius = |b: u8| match b {
        0 => 0.0,
        1 => -0.5,
        2 => f64::NAN,
        3 => 1e9,
        _ => b as f64 / 255.0 * 0.6,
    };
    for _ in 0..24 {
        let op = take(1);
        let Some(&op) = op.first() else { break };
        let result = match op % 4 {
            0 => {
                let count = take(1).first().map_or(0, |&k| k as usize % 9);
                let ids: Vec<u32> = take(2 * count)
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]) as u32 % (n + 8))
                    .collect();
                c.remove(&ids)
            }
            1 => {
                let b = take(4);
                let at = |i: usize| b.get(i).copied().unwrap_or(100);
                let centre = DVec3::new(coordinate(at(0)), coordinate(at(1)), coordinate(at(2)));
                c.carve(&Tool::Sphere {
                    centre,
                    radius: radius(at(3)),
                })
            }
            2 => {
                let b = take(7);
                let at = |i: usize| b.get(i).copied().unwrap_or(100);
                let p = |k: usize| {
                    DVec3::new(
                        coordinate(at(k)),
                        coordinate(at(k + 1)),
                        coordinate(at(k + 2)),
                    )
                };
                c.carve(&Tool::Capsule {
                    a: p(0),
                    b: p(3),
                    radius: radius(at(6)),
                })
            }
            _ => {
                c.wait();
                continue;
            }
        };
        if let Ok(step) = result {
            for gone in &step.vanished {
                assert_eq!(
                    now.remove(&gone.id),
                    Some(gone.vertices),
                    "vanished {}",
                    gone.id
                );
            }
            for f in &step.appeared {
                assert!(
                    now.insert(f.id, f.vertices).is_none(),
                    "appeared twice {}",
                    f.id
                );
                assert!(f.uvs.iter().flatten().all(|u| (0.0..=1.0).contains(u)));
            }
        }
        assert_eq!(now, surface(&c), "the session's surface");
        // Closed and oriented: each directed edge once, its reverse once
        // (removal by ids may leave two fans at an edge: then twice each).
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for f in now.values() {
            for k in 0..3 {
                *directed.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &k) in &directed {
            assert_eq!(directed.get(&(b, a)), Some(&k), "edge {a}->{b}");
        }
    }
    c.wait();
}

/// The unit cube as 4 x 4 x 4 cells of six tets each (Kuhn's
/// subdivision, conforming), its interior a small block.
fn fuzz_cube() -> std::sync::Arc<crate::runtime::Node> {
    use crate::runtime::{Model, Node};
    static CUBE: std::sync::OnceLock<std::sync::Arc<Node>> = std::sync::OnceLock::new();
    CUBE.get_or_init(|| {
        let k = 4;
        let id = |x: usize, y: usize, z: usize| (x + (k + 1) * (y + (k + 1) * z)) as u32;
        let mut positions = Vec::new();
        for z in 0..=k {
            for y in 0..=k {
                for x in 0..=k {
                    positions.push(DVec3::new(x as f64, y as f64, z as f64) / k as f64);
                }
            }
        }
        let mut tets = Vec::new();
        for z in 0..k {
            for y in 0..k {
                for x in 0..k {
                    let c = |i: usize| id(x + (i & 1), y + (i >> 1 & 1), z + (i >> 2 & 1));
                    // The six paths from corner 0 to corner 7 through the
                    // cube's edges.
                    for path in [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]] {
                        let mut t = [c(0), c(path[0]), c(path[1]), c(7)];
                        let q = t.map(|v| positions[v as usize]);
                        if crate::tetra::mesh::signed_volume(&q) < 0.0 {
                            t.swap(2, 3);
                        }
                        tets.push(t);
                    }
                }
            }
        }
        let mesh = crate::tetra::TetMesh {
            positions,
            tets,
            ..Default::default()
        };
        let volume = Volume {
            size: [4, 4, 4],
            spacing: 0.1,
            voxels: (0..64u8).map(|i| [i * 4, 255 - i * 4, i]).collect(),
        };
        let placement = crate::solid::Placement::new(DVec3::ZERO, 0.1).expect("a placement");
        std::sync::Arc::new(Node::new(
            "cube",
            crate::solid::InteriorMethod::Fnpts,
            Model::Block { volume, placement },
            Some(mesh),
        ))
    })
    .clone()
}

/// NRRD label maps and Slicer segmentations (`segment::nrrd::parse`). On
/// success: at least one layer, every side at least 1, one value per
/// voxel, no NaN, a finite and invertible voxel-to-world map, every
/// segment in a layer there is; a map of whole 16-bit values written back
/// with `to_bytes` reads the same.
pub fn label_map(bytes: &[u8]) {
    use crate::segment::nrrd;
    let Ok(map) = nrrd::parse(bytes, None) else {
        return;
    };
    assert!(!map.layers.is_empty(), "no layer");
    let first = &map.layers[0];
    for v in &map.layers {
        assert!(v.size.iter().all(|&s| s >= 1), "size {:?}", v.size);
        assert_eq!(v.size, first.size);
        assert_eq!(v.values.len(), v.size.iter().product::<usize>());
        assert!(v.values.iter().all(|x| !x.is_nan()), "a NaN value");
        let m = v.to_world.matrix3;
        assert!(m.is_finite() && v.to_world.translation.is_finite());
        assert!(m.determinant() != 0.0, "singular map {m}");
    }
    assert!(map.segments.iter().all(|s| s.layer < map.layers.len()));
    let shorts = map.layers.iter().all(|v| {
        v.values
            .iter()
            .all(|&x| x.fract() == 0.0 && x.abs() <= i16::MAX as f32)
    });
    if shorts {
        let back = nrrd::parse(&nrrd::to_bytes(&map.layers, &map.segments, true), None)
            .expect("to_bytes reads back");
        assert_eq!(back.segments, map.segments);
        for (a, b) in back.layers.iter().zip(&map.layers) {
            assert_eq!(a.values, b.values);
            assert!(
                a.to_world.abs_diff_eq(
                    b.to_world,
                    1e-9 * (1.0 + b.to_world.translation.abs().max_element())
                ),
                "the map does not read back"
            );
        }
    }
}
