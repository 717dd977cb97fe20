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
