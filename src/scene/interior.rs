//! A node's interior as a bake writes it and a runtime reads it: the
//! `interiors` lines of report.json, naming the files in the bake's folder
//! (the block, the tet mesh, the lapped solid texture, a morph's sections).
//! The bake (`crate::bake`) fills them; `crate::runtime` opens them.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::solid::InteriorMethod;

/// A node's interior block: a solid texture that tiles space from the
/// origin, one voxel `voxel_size` mesh units, for the simulator's cuts
/// (`solid::plane_section` with `Placement::new(origin 0, voxel_size)`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct InteriorLine {
    pub node: String,
    /// The tissue it was synthesised from.
    pub texture: String,
    /// How the block was made.
    pub method: InteriorMethod,
    /// Relative to the bake's folder.
    pub file: PathBuf,
    pub voxels: usize,
    pub voxel_size: f64,
    /// The node's inside as tetrahedra, when `tet_mesh = true`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tet_mesh: Option<TetLine>,
    /// The lapped solid texture, when `[node.interior.lst]` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lst: Option<LstLine>,
    /// The morph, when `method = "morph"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub morph: Option<MorphLine>,
}

/// A node's interior morphed from photographed cuts (seed 003). Its block
/// is the morph sampled over the node's bounding cube, placed at
/// `block_origin` (it does not tile); the sections file and photographs
/// are copied beside it for a simulator to morph cuts on demand
/// (`solid::morph::Morph`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MorphLine {
    /// The copied sections file, relative to the bake's folder.
    pub sections: PathBuf,
    /// The node's surface (the morph's domain), beside the sections, for
    /// a runtime to morph cuts on demand.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<PathBuf>,
    /// Photographs (exemplar planes) and the regions they split it into.
    pub exemplars: usize,
    pub regions: usize,
    /// Where the block's corner lies (its voxels span `voxel_size`).
    pub block_origin: [f64; 3],
    /// BSP, sweeps and warps.
    pub precompute_s: f64,
}

/// A node's lapped solid texture (`[node.interior.lst]`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LstLine {
    /// The model (.lst, its tet mesh inside), relative to the bake's
    /// folder; its exemplar is the node's block.
    pub file: PathBuf,
    #[serde(rename = "type")]
    pub kind: String,
    pub tets: usize,
    pub bytes: u64,
    /// Of the tets outside every region.
    #[serde(flatten)]
    pub stats: crate::solid::lst::FillStats,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<LstRegionLine>,
    pub seconds: f64,
}

/// A region of a lapped solid texture (`[[node.interior.lst.region]]`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LstRegionLine {
    pub facet: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub tets: usize,
    #[serde(flatten)]
    pub stats: crate::solid::lst::FillStats,
}

/// A node's tetrahedral mesh (`[node.interior] tet_mesh = true`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TetLine {
    /// Legacy VTK, relative to the bake's folder.
    pub file: PathBuf,
    pub vertices: usize,
    pub tets: usize,
    pub min_dihedral: f64,
    pub max_dihedral: f64,
    /// Two-sided Hausdorff distance of its boundary to the node's surface,
    /// over the surface's bounding box diagonal.
    pub hausdorff_relative: Option<f64>,
}

impl InteriorLine {
    /// Every file the line names, relative to the bake's folder.
    pub fn files(&self) -> Vec<&std::path::Path> {
        let mut files = vec![self.file.as_path()];
        files.extend(self.tet_mesh.as_ref().map(|t| t.file.as_path()));
        files.extend(self.lst.as_ref().map(|l| l.file.as_path()));
        if let Some(m) = &self.morph {
            files.push(m.sections.as_path());
            files.extend(m.surface.as_deref());
        }
        files
    }
}
