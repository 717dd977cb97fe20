//! A bake opened for a simulator: the folder `organtex bake` writes, its
//! nodes named by report.json's `interiors`, each node's interior model
//! and tet mesh read from the files the report names, on first use.
//!
//! A node is immutable once loaded and shared (`Arc<Node>`): colour
//! queries run from any thread at once; carving sessions hold their own
//! state beside it.

use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use glam::DVec3;

use super::model::Model;
use super::tool::CentroidGrid;
use crate::error::{Error, Result};
use crate::scene::interior::InteriorLine;
use crate::solid::lst::{LstInterior, LstModel};
use crate::solid::morph::Morph;
use crate::solid::{Interior, InteriorMethod, Placement};
use crate::synth::volume::Volume;
use crate::tetra::TetMesh;

/// An opened bake folder.
pub struct Bake {
    dir: PathBuf,
    entries: Vec<(InteriorLine, Mutex<Option<Arc<Node>>>)>,
}

/// Only the part of report.json the runtime reads.
#[derive(serde::Deserialize)]
struct Report {
    interiors: Vec<InteriorLine>,
}

impl Bake {
    /// Open the bake in `dir`: reads its report.json and checks that the
    /// files it names are there; nodes load on first use.
    pub fn open(dir: &Path) -> Result<Bake> {
        if !dir.is_dir() {
            return Err(Error::invalid(format!(
                "{}: not a folder (a bake is the folder `organtex bake SCENE -o DIR` writes)",
                dir.display()
            )));
        }
        let path = dir.join("report.json");
        if !path.is_file() {
            return Err(Error::invalid(format!(
                "{}: not a bake, it has no report.json (`organtex bake SCENE -o DIR` writes one)",
                dir.display()
            )));
        }
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let report: Report = serde_json::from_str(&text)
            .map_err(|e| Error::at_line(&path, e.line(), format!("not a bake's report: {e}")))?;
        let mut entries = Vec::with_capacity(report.interiors.len());
        for line in report.interiors {
            for file in line.files() {
                let inside = file.is_relative()
                    && file.components().all(|c| matches!(c, Component::Normal(_)));
                if !inside {
                    return Err(Error::format(
                        &path,
                        format!(
                            "node '{}': file {} is not inside the bake's folder",
                            line.node,
                            file.display()
                        ),
                    ));
                }
                if !dir.join(file).is_file() {
                    return Err(Error::invalid(format!(
                        "{}: node '{}' names {}, which is missing",
                        path.display(),
                        line.node,
                        file.display()
                    )));
                }
            }
            entries.push((line, Mutex::new(None)));
        }
        Ok(Bake {
            dir: dir.to_path_buf(),
            entries,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The names of the nodes with an interior, in the report's order.
    pub fn nodes(&self) -> Vec<&str> {
        self.entries.iter().map(|(l, _)| l.node.as_str()).collect()
    }

    /// Node `name`, loaded on the first call (later calls share it).
    pub fn node(&self, name: &str) -> Result<Arc<Node>> {
        let Some((line, slot)) = self.entries.iter().find(|(l, _)| l.node == name) else {
            return Err(Error::invalid(format!(
                "{}: no node '{name}' with an interior (the bake has: {})",
                self.dir.display(),
                self.nodes().join(", ")
            )));
        };
        let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(node) = &*slot {
            return Ok(node.clone());
        }
        let node = Arc::new(Node::load(&self.dir, line)?);
        *slot = Some(node.clone());
        Ok(node)
    }
}

/// One node of a bake: its interior model and, when baked, its tet mesh.
pub struct Node {
    pub name: String,
    pub method: InteriorMethod,
    model: Model,
    /// The tet mesh, when the model does not hold it (a lapped solid
    /// texture does).
    tets: Option<TetMesh>,
    /// Per tet, the tet across each face (`TetMesh::face_adjacency`).
    adjacency: OnceLock<Vec<[u32; 4]>>,
    /// The tets' centroids binned, for tools.
    centroids: OnceLock<CentroidGrid>,
    /// The tet mesh's longest edge.
    longest_edge: OnceLock<f64>,
}

impl Node {
    fn load(dir: &Path, line: &InteriorLine) -> Result<Node> {
        let err = |e: Error| match e {
            e @ (Error::Io { .. } | Error::Format { .. }) => e,
            e => Error::invalid(format!("node '{}': {e}", line.node)),
        };
        let block_path = dir.join(&line.file);
        let read_block = || Volume::read_nrrd(&block_path);
        let (model, tets) = if let Some(lst) = &line.lst {
            let model = LstModel::read(&dir.join(&lst.file))?;
            let lapped = LstInterior::new(Arc::new(model), Arc::new(read_block()?))
                .map_err(|e| e.in_file(&block_path))?;
            (Model::Lapped(lapped), None)
        } else if let Some(morph) = &line.morph {
            let sections = dir.join(&morph.sections);
            let Some(surface) = &morph.surface else {
                return Err(Error::invalid(format!(
                    "node '{}': the bake predates morph surfaces; bake the scene again",
                    line.node
                )));
            };
            let surface_path = dir.join(surface);
            let surface = crate::mesh::io::read(&surface_path)?;
            let topology =
                crate::mesh::Topology::build(&surface).map_err(|e| e.in_file(&surface_path))?;
            let m = Morph::read(
                &surface,
                &topology,
                &sections,
                Default::default(),
                &crate::progress::Silent,
            )
            .map_err(err)?;
            (Model::Morph(Box::new(m)), None)
        } else {
            let volume = read_block()?;
            let placement = Placement::new(DVec3::ZERO, line.voxel_size)
                .map_err(|e| e.in_file(&dir.join("report.json")))?;
            (Model::Block { volume, placement }, None)
        };
        let tets = match (&line.tet_mesh, tets) {
            (Some(t), None) if !matches!(model, Model::Lapped(_)) => {
                Some(crate::tetra::io::read_vtk(&dir.join(&t.file))?)
            }
            (_, tets) => tets,
        };
        Ok(Node {
            name: line.node.clone(),
            method: line.method,
            model,
            tets,
            adjacency: OnceLock::new(),
            centroids: OnceLock::new(),
            longest_edge: OnceLock::new(),
        })
    }

    /// A node over a model held in memory (the viewer's, tests'): `tets`
    /// unless the model holds its own.
    pub fn new(name: &str, method: InteriorMethod, model: Model, tets: Option<TetMesh>) -> Node {
        Node {
            name: name.into(),
            method,
            model,
            tets,
            adjacency: OnceLock::new(),
            centroids: OnceLock::new(),
            longest_edge: OnceLock::new(),
        }
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The tet mesh, as the simulator's physics loads it (the same ids
    /// as the bake's .vtk).
    pub fn tet_mesh(&self) -> Option<&TetMesh> {
        match &self.model {
            Model::Lapped(l) => Some(&l.model().mesh),
            _ => self.tets.as_ref(),
        }
    }

    /// The tet mesh, or an error naming the node.
    pub fn require_tets(&self) -> Result<&TetMesh> {
        self.tet_mesh().ok_or_else(|| {
            Error::invalid(format!(
                "node '{}' has no tet mesh: bake it with `tet_mesh = true` or a lapped solid \
                 texture in [node.interior]",
                self.name
            ))
        })
    }

    /// Per tet, the tet across each face, or `NO_NEIGHBOUR`.
    pub fn adjacency(&self) -> Result<&[[u32; 4]]> {
        if let Some(a) = self.adjacency.get() {
            return Ok(a);
        }
        let adjacency = self.require_tets()?.face_adjacency()?;
        Ok(self.adjacency.get_or_init(|| adjacency))
    }

    /// The tets' centroids in a grid, for the tets under a tool.
    pub fn centroids(&self) -> Result<&CentroidGrid> {
        if let Some(g) = self.centroids.get() {
            return Ok(g);
        }
        let grid = CentroidGrid::new(self.require_tets()?);
        Ok(self.centroids.get_or_init(|| grid))
    }

    /// The tet mesh's longest edge (an atlas's page must hold its faces).
    pub fn longest_edge(&self) -> Result<f64> {
        let mesh = self.require_tets()?;
        Ok(*self.longest_edge.get_or_init(|| {
            use rayon::prelude::*;
            (0..mesh.num_tets())
                .into_par_iter()
                .map(|t| {
                    let c = mesh.corners(t);
                    crate::tetra::mesh::TET_EDGES
                        .iter()
                        .map(|&[i, j]| c[i].distance(c[j]))
                        .fold(0.0, f64::max)
                })
                .reduce(|| 0.0, f64::max)
        }))
    }

    /// The colours at `points`; refuses a point that is not finite.
    pub fn colours(&self, points: &[DVec3]) -> Result<Vec<[u8; 3]>> {
        check_points(points)?;
        Ok(self.model.colours(points))
    }

    /// 3D texture coordinates of `points` in the node's block, in voxel
    /// units (`solid::cut`'s convention: divide by the block's size and
    /// sample with repeat, as `SAMPLE_BLOCK_GLSL` and `_WGSL` do). Refuses
    /// a model that is not a block, and points that are not finite.
    pub fn block_coordinates(&self, points: &[DVec3]) -> Result<Vec<[f32; 3]>> {
        check_points(points)?;
        let (_, placement) = self.model.block().ok_or_else(|| {
            Error::invalid(format!(
                "node '{}' is {:?}, not a block: colour its faces from the atlas instead",
                self.name, self.method
            ))
        })?;
        Ok(crate::solid::texture_coordinates(points, &placement))
    }

    /// Bytes held: the model, the tet mesh and its adjacency.
    pub fn bytes(&self) -> usize {
        let tets = self
            .tets
            .as_ref()
            .map_or(0, |t| 24 * t.positions.len() + 16 * t.tets.len());
        self.model.bytes()
            + tets
            + self.adjacency.get().map_or(0, |a| 16 * a.len())
            + self.centroids.get().map_or(0, CentroidGrid::bytes)
    }
}

/// Refuse a point that is not finite, naming it.
pub fn check_points(points: &[DVec3]) -> Result<()> {
    match points.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(Error::invalid(format!(
            "point {i} is {}: positions must be finite",
            points[i]
        ))),
        None => Ok(()),
    }
}
