//! `organtex._core`: the library's stages for Python. Arrays cross as
//! little-endian bytes with their shapes; `python/organtex/__init__.py`
//! turns them into numpy arrays, so this crate needs no numpy bindings
//! (whose versions must match numpy's and pyo3's). Every call releases the
//! GIL while it works, reports progress to an optional callable
//! `progress(stage, done, total)`, stops on Ctrl-C, and raises
//! `OrgantexError` with the library's message.

mod runtime;

use std::path::PathBuf;
use std::sync::Mutex;

use glam::DVec3;
use organtex::progress::Progress;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

// Named by its importable path, so it pickles (Ray ships exceptions
// between processes).
pyo3::create_exception!(
    organtex._core,
    OrgantexError,
    PyException,
    "What organtex refused or failed at; the message names the file and what is wrong."
);

fn error(e: organtex::Error) -> PyErr {
    OrgantexError::new_err(e.to_string())
}

/// Progress reported to a Python callable, from whichever thread works.
struct Callback {
    call: Option<Py<PyAny>>,
    /// The current stage, its total, and units done.
    state: Mutex<(String, u64, u64)>,
}

impl Callback {
    fn new(call: Option<Py<PyAny>>) -> Callback {
        Callback {
            call,
            state: Mutex::new((String::new(), 0, 0)),
        }
    }

    fn report(&self) {
        let Some(call) = &self.call else { return };
        let (stage, total, done) = self.state.lock().expect("progress state").clone();
        Python::attach(|py| {
            // A failing callback must not stop the work; Python shows it.
            if let Err(e) = call.call1(py, (stage, done, total)) {
                e.print(py);
            }
        });
    }
}

impl Progress for Callback {
    fn stage(&self, name: &str, total: u64) {
        *self.state.lock().expect("progress state") = (name.to_string(), total, 0);
        self.report();
    }

    fn advance(&self, n: u64) {
        self.state.lock().expect("progress state").2 += n;
        self.report();
    }

    fn cancelled(&self) -> bool {
        Python::attach(|py| py.check_signals().is_err())
    }
}

fn f64s(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

fn u32s(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect()
}

fn mesh_of(vertices: &[u8], faces: &[u8]) -> PyResult<organtex::mesh::TriMesh> {
    let v = f64s(vertices);
    let f = u32s(faces);
    if !v.len().is_multiple_of(3) || !f.len().is_multiple_of(3) {
        return Err(OrgantexError::new_err(
            "vertices must be an (n, 3) float array and faces an (m, 3) integer array",
        ));
    }
    let n = v.len() / 3;
    if let Some(bad) = f.iter().find(|&&i| i as usize >= n) {
        return Err(OrgantexError::new_err(format!(
            "a face names vertex {bad}, but there are {n} vertices"
        )));
    }
    let positions = v
        .chunks_exact(3)
        .map(|p| DVec3::new(p[0], p[1], p[2]))
        .collect();
    let triangles = f.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    Ok(organtex::mesh::TriMesh::new(positions, triangles))
}

/// A number as the little-endian bytes numpy's "<f8", "<u4" and uint8
/// read.
trait LittleEndian: Copy {
    fn push(self, out: &mut Vec<u8>);
}

impl LittleEndian for f64 {
    fn push(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl LittleEndian for u32 {
    fn push(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl LittleEndian for f32 {
    fn push(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl LittleEndian for u8 {
    fn push(self, out: &mut Vec<u8>) {
        out.push(self);
    }
}

fn bytes_of<T: LittleEndian>(py: Python<'_>, items: &[T]) -> Py<PyBytes> {
    let mut out = Vec::with_capacity(std::mem::size_of_val(items));
    for &x in items {
        x.push(&mut out);
    }
    PyBytes::new(py, &out).unbind()
}

/// Vertices, faces, each face's facet (bytes) and the facet names.
type MeshBytes = (Py<PyBytes>, Py<PyBytes>, Py<PyBytes>, Vec<String>);

/// Read a mesh (OBJ, PLY, STL): vertices (f64 bytes, n x 3), faces (u32
/// bytes, m x 3), each face's facet (u32 bytes, m) and the facet names.
#[pyfunction]
fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<MeshBytes> {
    let mesh = py
        .detach(|| organtex::mesh::io::read(&path))
        .map_err(error)?;
    let positions: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let (ids, names) = match &mesh.facets {
        Some(f) => (f.of_face.clone(), f.names.clone()),
        None => (vec![0; mesh.triangles.len()], vec!["*".to_string()]),
    };
    Ok((
        bytes_of(py, positions.as_flattened()),
        bytes_of(py, mesh.triangles.as_flattened()),
        bytes_of(py, &ids),
        names,
    ))
}

/// Cut and flatten a mesh (Seamster seams, ABF++, layout): uvs (f64
/// bytes, k x 2), uv faces (u32 bytes, m x 3) and the report as JSON.
#[pyfunction]
#[pyo3(signature = (vertices, faces, split_overlaps=false, atlas_faces=None, progress=None))]
fn unwrap(
    py: Python<'_>,
    vertices: &[u8],
    faces: &[u8],
    split_overlaps: bool,
    atlas_faces: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Py<PyBytes>, Py<PyBytes>, String)> {
    let mesh = mesh_of(vertices, faces)?;
    let opts = organtex::unwrap::UnwrapOptions {
        split_overlaps,
        atlas_faces,
        ..Default::default()
    };
    let callback = Callback::new(progress);
    let out = py
        .detach(|| organtex::unwrap::unwrap(&mesh, &opts, &callback))
        .map_err(error)?;
    let uvs = out.mesh.uvs.expect("an unwrap sets uvs");
    let coords: Vec<[f64; 2]> = uvs.coords.iter().map(|c| c.to_array()).collect();
    let report = serde_json::to_string(&out.report).expect("the report serialises");
    Ok((
        bytes_of(py, coords.as_flattened()),
        bytes_of(py, uvs.triangles.as_flattened()),
        report,
    ))
}

/// FNPTS synthesis: `size` x `size` RGB bytes from an RGB exemplar
/// (`width` x `height` bytes) and an optional mask (one byte a pixel,
/// nonzero usable).
#[pyfunction]
#[pyo3(signature = (exemplar, width, height, size, tileable=true, seed=0, mask=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn synth(
    py: Python<'_>,
    exemplar: &[u8],
    width: usize,
    height: usize,
    size: usize,
    tileable: bool,
    seed: u64,
    mask: Option<&[u8]>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyBytes>> {
    let ex = exemplar_of(exemplar, width, height, mask)?;
    let opts = organtex::synth::fnpts::SynthOptions {
        width: size,
        height: size,
        tileable,
        seed,
        ..Default::default()
    };
    let callback = Callback::new(progress);
    let out = py
        .detach(|| organtex::synth::fnpts::synthesize(&ex, &opts, &callback))
        .map_err(error)?;
    Ok(bytes_of(py, out.pixels.as_flattened()))
}

fn exemplar_of(
    pixels: &[u8],
    width: usize,
    height: usize,
    mask: Option<&[u8]>,
) -> PyResult<organtex::synth::exemplar::Exemplar> {
    if pixels.len() != width * height * 3 {
        return Err(OrgantexError::new_err(format!(
            "a {width}x{height} RGB exemplar has {} bytes, not {}",
            width * height * 3,
            pixels.len()
        )));
    }
    let valid = match mask {
        Some(m) if m.len() != width * height => {
            return Err(OrgantexError::new_err(format!(
                "the mask must be {width}x{height}, one value a pixel"
            )));
        }
        Some(m) => m.iter().map(|&v| v != 0).collect(),
        None => vec![true; width * height],
    };
    let rgb = pixels.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    organtex::synth::exemplar::Exemplar::new(width, height, rgb, valid).map_err(error)
}

/// A solid texture block, `size`^3 RGB bytes (x fastest), from an RGB
/// exemplar: method "fnpts" or "optimize".
#[pyfunction]
#[pyo3(signature = (exemplar, width, height, size, seed=0, method="fnpts", progress=None))]
#[allow(clippy::too_many_arguments)]
fn synth3d(
    py: Python<'_>,
    exemplar: &[u8],
    width: usize,
    height: usize,
    size: usize,
    seed: u64,
    method: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyBytes>> {
    let ex = exemplar_of(exemplar, width, height, None)?;
    let method = match method {
        "fnpts" => organtex::synth::block::Method::Fnpts,
        "optimize" => organtex::synth::block::Method::Optimize,
        m => {
            return Err(OrgantexError::new_err(format!(
                "the method is fnpts or optimize, not {m:?}"
            )));
        }
    };
    let opts = organtex::synth::block::BlockOptions {
        size,
        seed,
        method,
        ..Default::default()
    };
    let callback = Callback::new(progress);
    let out = py
        .detach(|| organtex::synth::block::synthesize_block(&[ex], &opts, &callback))
        .map_err(error)?;
    Ok(bytes_of(py, out.voxels.as_flattened()))
}

/// The section of a closed mesh by the plane normal . p = offset,
/// coloured from a tiling block (`size`^3 RGB bytes, a voxel `scale` mesh
/// units): positions (f64 bytes, n x 3), triangles (u32 bytes, m x 3) and
/// each position's colour (RGB bytes).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn section(
    py: Python<'_>,
    vertices: &[u8],
    faces: &[u8],
    block: &[u8],
    size: usize,
    normal: [f64; 3],
    offset: f64,
    scale: f64,
) -> PyResult<(Py<PyBytes>, Py<PyBytes>, Py<PyBytes>)> {
    let mesh = mesh_of(vertices, faces)?;
    if block.len() != size * size * size * 3 {
        return Err(OrgantexError::new_err(format!(
            "a {size}^3 RGB block has {} bytes, not {}",
            size * size * size * 3,
            block.len()
        )));
    }
    let volume = organtex::synth::volume::Volume {
        size: [size; 3],
        spacing: scale,
        voxels: block.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    let (cut, colours) = py
        .detach(|| -> organtex::Result<_> {
            let topology = organtex::mesh::halfedge::Topology::build(&mesh)?;
            let plane = organtex::solid::Plane::new(DVec3::from_array(normal), offset)?;
            let cut = organtex::solid::plane_section(&mesh, &topology, plane)?;
            let placement = organtex::solid::Placement::new(DVec3::ZERO, scale)?;
            let colours = organtex::solid::sample_colours(&cut, &volume, &placement);
            Ok((cut, colours))
        })
        .map_err(error)?;
    let positions: Vec<[f64; 3]> = cut.positions.iter().map(|p| p.to_array()).collect();
    Ok((
        bytes_of(py, positions.as_flattened()),
        bytes_of(py, cut.triangles.as_flattened()),
        bytes_of(py, colours.as_flattened()),
    ))
}

/// An interior morphed from photographed cuts placed in a closed mesh
/// (seed 003): precomputed once, then any points coloured on demand.
#[pyclass(name = "Morph", frozen)]
struct PyMorph(organtex::solid::morph::Morph);

#[pymethods]
impl PyMorph {
    /// Precompute the morph of the sections file `sections` inside the
    /// closed mesh (vertices f64 bytes n x 3, faces u32 bytes m x 3).
    #[new]
    #[pyo3(signature = (vertices, faces, sections, progress=None))]
    fn new(
        py: Python<'_>,
        vertices: &[u8],
        faces: &[u8],
        sections: PathBuf,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<PyMorph> {
        let mesh = mesh_of(vertices, faces)?;
        let callback = Callback::new(progress);
        py.detach(|| -> organtex::Result<_> {
            let topology = organtex::mesh::halfedge::Topology::build(&mesh)?;
            organtex::solid::morph::Morph::read(
                &mesh,
                &topology,
                &sections,
                Default::default(),
                &callback,
            )
        })
        .map(PyMorph)
        .map_err(error)
    }

    /// The colours (RGB bytes) at points (f64 bytes, n x 3).
    fn colours(&self, py: Python<'_>, points: &[u8]) -> PyResult<Py<PyBytes>> {
        if !points.len().is_multiple_of(24) {
            return Err(OrgantexError::new_err(
                "points must be n x 3 float64 values",
            ));
        }
        let points: Vec<DVec3> = f64s(points)
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect();
        use organtex::solid::Interior;
        let colours = py.detach(|| self.0.colours(&points));
        Ok(bytes_of(py, colours.as_flattened()))
    }

    /// How many photographs, and how many regions their planes split the
    /// mesh into.
    #[getter]
    fn exemplars(&self) -> usize {
        self.0.exemplars().len()
    }

    #[getter]
    fn regions(&self) -> usize {
        self.0.regions()
    }
}

/// Bake a scene into `out_dir` (scene.glb, report.json, preview.png,
/// interiors, kept unwraps): the report as JSON.
#[pyfunction]
#[pyo3(signature = (scene, out_dir, atlas=None, progress=None))]
fn bake(
    py: Python<'_>,
    scene: PathBuf,
    out_dir: PathBuf,
    atlas: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let opts = organtex::bake::BakeOptions {
        atlas,
        ..Default::default()
    };
    let callback = Callback::new(progress);
    let baked = py
        .detach(|| organtex::bake::bake(&scene, &out_dir, &opts, &callback))
        .map_err(error)?;
    Ok(serde_json::to_string(&baked.report).expect("the report serialises"))
}

/// Fill a closed mesh with tetrahedra (isosurface stuffing): positions
/// (f64 bytes, n x 3), tets (u32 bytes, t x 4, positively oriented) and
/// the report as JSON (edge length, attempts, Hausdorff distance).
#[pyfunction]
#[pyo3(signature = (vertices, faces, edge_length=None, cells=None, graded=false, progress=None))]
fn tetra(
    py: Python<'_>,
    vertices: &[u8],
    faces: &[u8],
    edge_length: Option<f64>,
    cells: Option<usize>,
    graded: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Py<PyBytes>, Py<PyBytes>, String)> {
    let mesh = mesh_of(vertices, faces)?;
    let opts = organtex::tetra::TetOptions {
        edge_length,
        cells,
        graded,
    };
    let callback = Callback::new(progress);
    let (tets, report) = py
        .detach(|| organtex::tetra::tetrahedralise_report(&mesh, &opts, &callback))
        .map_err(error)?;
    let positions: Vec<[f64; 3]> = tets.positions.iter().map(|p| p.to_array()).collect();
    Ok((
        bytes_of(py, positions.as_flattened()),
        bytes_of(py, tets.tets.as_flattened()),
        serde_json::to_string(&report).expect("the report serialises"),
    ))
}

/// Check a scene as a bake would before its long steps: the file, its
/// includes, and every node's mesh read or generated with its facets
/// matched. Raises what the bake would.
#[pyfunction]
fn check_scene(py: Python<'_>, scene: PathBuf) -> PyResult<()> {
    py.detach(|| -> organtex::Result<()> {
        let spec = organtex::scene::file::load(&scene)?;
        for node in &spec.nodes {
            let (mesh, _) = organtex::scene::build::node_mesh(node, &organtex::progress::Silent)?;
            organtex::scene::build::match_facets(node, &mesh)?;
        }
        Ok(())
    })
    .map_err(error)
}

/// The scenes a manifest lists (one path per line, relative to it).
#[pyfunction]
fn manifest(path: PathBuf) -> PyResult<Vec<PathBuf>> {
    organtex::scene::manifest::scenes(&path).map_err(error)
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("OrgantexError", m.py().get_type::<OrgantexError>())?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(unwrap, m)?)?;
    m.add_function(wrap_pyfunction!(synth, m)?)?;
    m.add_function(wrap_pyfunction!(synth3d, m)?)?;
    m.add_function(wrap_pyfunction!(section, m)?)?;
    m.add_class::<PyMorph>()?;
    m.add_class::<runtime::PyBake>()?;
    m.add_class::<runtime::PyNode>()?;
    m.add_class::<runtime::PyCarving>()?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(tetra, m)?)?;
    m.add_function(wrap_pyfunction!(check_scene, m)?)?;
    m.add_function(wrap_pyfunction!(manifest, m)?)?;
    Ok(())
}
