//! The simulator's runtime for Python (`organtex::runtime`): a bake's
//! nodes, their colours and tet meshes, and carving sessions whose steps
//! come back as bytes that `organtex/__init__.py` wraps as numpy arrays.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use glam::DVec3;
use organtex::runtime::{AtlasOptions, Bake, Carving, CarvingOptions, Node, Step, Tool};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::{OrgantexError, bytes_of, error, f64s, u32s};

/// A step's arrays: removed, appeared ids, vertices, pages, uvs, colours,
/// vanished ids, vertices, dirty rectangles, released pages, whether
/// texels are pending, seconds.
type StepBytes = (
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    Py<PyBytes>,
    bool,
    f64,
);

fn points(bytes: &[u8], what: &str) -> PyResult<Vec<DVec3>> {
    if !bytes.len().is_multiple_of(24) {
        return Err(OrgantexError::new_err(format!(
            "{what} must be n x 3 float64 values"
        )));
    }
    Ok(f64s(bytes)
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect())
}

fn dirty_bytes(py: Python<'_>, dirty: &[(u32, organtex::runtime::Rect)]) -> Py<PyBytes> {
    let flat: Vec<u32> = dirty
        .iter()
        .flat_map(|(p, r)| [*p, r.x, r.y, r.width, r.height])
        .collect();
    bytes_of(py, &flat)
}

fn step_bytes(py: Python<'_>, s: &Step) -> StepBytes {
    let ids: Vec<u32> = s.appeared.iter().map(|f| f.id).collect();
    let vertices: Vec<u32> = s.appeared.iter().flat_map(|f| f.vertices).collect();
    let pages: Vec<u32> = s.appeared.iter().map(|f| f.page).collect();
    let uvs: Vec<f32> = s.appeared.iter().flat_map(|f| f.uvs.concat()).collect();
    let colours: Vec<u8> = s.appeared.iter().flat_map(|f| f.colours.concat()).collect();
    let gone: Vec<u32> = s.vanished.iter().map(|f| f.id).collect();
    let gone_vertices: Vec<u32> = s.vanished.iter().flat_map(|f| f.vertices).collect();
    (
        bytes_of(py, &s.removed),
        bytes_of(py, &ids),
        bytes_of(py, &vertices),
        bytes_of(py, &pages),
        bytes_of(py, &uvs),
        PyBytes::new(py, &colours).unbind(),
        bytes_of(py, &gone),
        bytes_of(py, &gone_vertices),
        dirty_bytes(py, &s.dirty),
        bytes_of(py, &s.released),
        s.texels_pending,
        s.seconds,
    )
}

/// An opened bake folder.
#[pyclass(name = "Bake", frozen)]
pub struct PyBake(Bake);

#[pymethods]
impl PyBake {
    #[new]
    fn new(py: Python<'_>, dir: PathBuf) -> PyResult<PyBake> {
        py.detach(|| Bake::open(&dir)).map(PyBake).map_err(error)
    }

    /// The nodes with an interior.
    #[getter]
    fn nodes(&self) -> Vec<String> {
        self.0.nodes().iter().map(|s| s.to_string()).collect()
    }

    /// Node `name` (loaded on first use, shared after).
    fn node(&self, py: Python<'_>, name: &str) -> PyResult<PyNode> {
        py.detach(|| self.0.node(name)).map(PyNode).map_err(error)
    }
}

/// A node of a bake: its interior and tet mesh.
#[pyclass(name = "Node", frozen)]
pub struct PyNode(Arc<Node>);

#[pymethods]
impl PyNode {
    #[getter]
    fn name(&self) -> String {
        self.0.name.clone()
    }

    /// Its tet mesh: positions (f64 bytes, n x 3) and tets (u32 bytes,
    /// m x 4).
    fn tet_mesh(&self, py: Python<'_>) -> PyResult<(Py<PyBytes>, Py<PyBytes>)> {
        let mesh = self.0.require_tets().map_err(error)?;
        let positions: Vec<f64> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
        Ok((
            bytes_of(py, &positions),
            bytes_of(py, mesh.tets.as_flattened()),
        ))
    }

    /// The interior's colours (RGB bytes) at points (f64 bytes, n x 3).
    fn colours(&self, py: Python<'_>, positions: &[u8]) -> PyResult<Py<PyBytes>> {
        let p = points(positions, "points")?;
        let c = py.detach(|| self.0.colours(&p)).map_err(error)?;
        Ok(PyBytes::new(py, c.as_flattened()).unbind())
    }
}

/// A carving session over a node's tet mesh.
#[pyclass(name = "Carving", frozen)]
pub struct PyCarving(Mutex<Carving>);

impl PyCarving {
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut Carving) -> organtex::Result<T> + Send,
    ) -> PyResult<T> {
        py.detach(|| {
            let mut c = self.0.lock().unwrap_or_else(|e| e.into_inner());
            f(&mut c)
        })
        .map_err(error)
    }
}

#[pymethods]
impl PyCarving {
    #[new]
    #[pyo3(signature = (node, texels_per_unit=8.0, page_size=1024, background_texels=false))]
    fn new(
        node: &PyNode,
        texels_per_unit: f64,
        page_size: u32,
        background_texels: bool,
    ) -> PyResult<PyCarving> {
        let options = CarvingOptions {
            atlas: AtlasOptions {
                texels_per_unit,
                page_size,
            },
            background_texels,
        };
        Carving::new(node.0.clone(), options)
            .map(|c| PyCarving(Mutex::new(c)))
            .map_err(error)
    }

    /// Remove exactly the tets `ids` (u32 bytes).
    fn remove(&self, py: Python<'_>, ids: &[u8]) -> PyResult<StepBytes> {
        if !ids.len().is_multiple_of(4) {
            return Err(OrgantexError::new_err("tet ids must be uint32 values"));
        }
        let ids = u32s(ids);
        let s = self.with(py, |c| c.remove(&ids))?;
        Ok(step_bytes(py, &s))
    }

    /// Remove the tets under a sphere.
    fn sphere(&self, py: Python<'_>, centre: [f64; 3], radius: f64) -> PyResult<StepBytes> {
        let tool = Tool::Sphere {
            centre: DVec3::from_array(centre),
            radius,
        };
        let s = self.with(py, |c| c.carve(&tool))?;
        Ok(step_bytes(py, &s))
    }

    /// Remove the tets under a sphere swept from `a` to `b`.
    fn capsule(
        &self,
        py: Python<'_>,
        a: [f64; 3],
        b: [f64; 3],
        radius: f64,
    ) -> PyResult<StepBytes> {
        let tool = Tool::Capsule {
            a: DVec3::from_array(a),
            b: DVec3::from_array(b),
            radius,
        };
        let s = self.with(py, |c| c.carve(&tool))?;
        Ok(step_bytes(py, &s))
    }

    /// Finish background texels: the pages' rectangles written (u32
    /// bytes, page x y width height).
    fn wait(&self, py: Python<'_>) -> PyResult<Py<PyBytes>> {
        let d = self.with(py, |c| Ok(c.wait()))?;
        Ok(dirty_bytes(py, &d))
    }

    /// Page `page`'s RGBA bytes and its side.
    fn page(&self, py: Python<'_>, page: u32) -> PyResult<(Py<PyBytes>, u32)> {
        let c = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let rgba = c
            .atlas()
            .page(page)
            .ok_or_else(|| OrgantexError::new_err(format!("page {page} is not in the atlas")))?;
        Ok((
            PyBytes::new(py, rgba).unbind(),
            c.atlas().options().page_size,
        ))
    }

    /// Live pages' ids.
    fn pages(&self) -> Vec<u32> {
        self.0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .atlas()
            .pages()
    }

    /// The carved surface: face ids (u32 bytes) and vertices (u32 bytes,
    /// n x 3).
    fn surface(&self, py: Python<'_>) -> (Py<PyBytes>, Py<PyBytes>) {
        let c = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let s = c.surface();
        let ids: Vec<u32> = s.iter().map(|f| f.0).collect();
        let v: Vec<u32> = s.iter().flat_map(|f| f.1).collect();
        (bytes_of(py, &ids), bytes_of(py, &v))
    }

    /// Write the carved surface with its atlas as a .glb.
    fn write_glb(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        self.with(py, |c| {
            c.wait();
            let glb = organtex::runtime::surface_glb(c)?;
            organtex::atomic::write_file(&path, |w| w.write_all(&glb))
        })
    }
}
