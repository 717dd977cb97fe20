//! Interiors morphed from a few photographed cuts (seed 003, Pietroni,
//! Otaduy, Bickel, Ganovelli and Gross 2007): photographs of cuts through a
//! real specimen, placed as planes in the organ, give the colour of any
//! point inside it on demand, with no volume stored: no resolution limit
//! and no tiling repeat.
//!
//! - `sections`: the sections file, the photographs placed in space;
//! - `cells`: plane regions rasterised, measured and tested for disks;
//! - `bsp`: the planes split the interior into regions (4.1);
//! - `sweep`: a point's source point on each bounding exemplar (4.2), and
//!   the photograph fitted to the mesh (4.3);
//! - `bands`: each photograph's low-frequency and detail bands;
//! - `warp`: the pairwise warps between exemplars of a region (5.1.1);
//! - `point`: the single-point morph (eq. 4) with local histogram matching
//!   (5.3);
//! - here: the precomputation, and `Morph` as a `solid::Interior`.

pub mod bands;
pub mod bsp;
pub mod cells;
pub mod point;
pub mod sections;
pub mod sweep;
pub mod warp;

use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

pub use sections::{Exemplar, copy_sections, read_sections};

use crate::error::{Error, Result};
use crate::mesh::{Topology, TriMesh};
use crate::progress::{Progress, check};
use crate::solid::{Interior, Placement};
use crate::synth::volume::Volume;
use bands::Bands;
use bsp::Bsp;
use sweep::Sweep;
use warp::{Stack, Warp};

/// The most exemplars that may bound one region.
pub const MAX_BOUNDS: usize = 8;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MorphOptions {
    /// Standard deviation, in photograph pixels, of the blur that splits
    /// the low band from the detail band.
    pub low_sigma: f32,
    /// Match the detail band's local histogram (5.3); off, the detail is a
    /// plain weighted sum and loses contrast between exemplars.
    pub matching: bool,
}

impl Default for MorphOptions {
    fn default() -> Self {
        MorphOptions {
            low_sigma: 8.0,
            matching: true,
        }
    }
}

/// An interior morphed from placed photographs: everything precomputed
/// once, then any point's colour on demand.
pub struct Morph {
    exemplars: Vec<Exemplar>,
    bands: Vec<Bands>,
    sweeps: Vec<Sweep>,
    bsp: Bsp,
    /// Per region, the warps between its bounds: `warps[r][s * k + t]`
    /// maps bound `s`'s exemplar onto bound `t`'s (k bounds; none on the
    /// diagonal).
    warps: Vec<Vec<Option<Warp>>>,
    options: MorphOptions,
}

impl Morph {
    /// Precompute the morph of `exemplars` inside the closed `mesh`: the
    /// BSP, the sweeps, the bands and the warps.
    pub fn new(
        mesh: &TriMesh,
        topology: &Topology,
        exemplars: Vec<Exemplar>,
        options: MorphOptions,
        progress: &dyn Progress,
    ) -> Result<Morph> {
        Morph::check_mesh(topology)?;
        if !(options.low_sigma > 0.0 && options.low_sigma.is_finite()) {
            return Err(Error::invalid(format!(
                "the low band's blur must be positive, not {}",
                options.low_sigma
            )));
        }
        // Per photograph pixel: its colour (12 bytes), both bands (24), the
        // blur's planes while they are made (16) and the stack (8).
        let pixels: u64 = exemplars
            .iter()
            .map(|e| e.width as u64 * e.height as u64)
            .sum();
        crate::memory::ensure_fits(
            &format!("the morph's bands of {} photographs", exemplars.len()),
            crate::memory::product(&[pixels, 60]),
        )?;
        progress.stage("morph: regions", exemplars.len() as u64);
        let bsp = Bsp::build(mesh, topology, &exemplars)?;
        if let Some(r) = bsp.regions.iter().find(|r| r.bounds.len() > MAX_BOUNDS) {
            return Err(Error::invalid(format!(
                "a region is bounded by {} exemplars, over {MAX_BOUNDS}; place fewer planes around it",
                r.bounds.len()
            )));
        }
        progress.advance(exemplars.len() as u64);
        check(progress)?;
        progress.stage("morph: sweeps and bands", exemplars.len() as u64);
        let (sweeps, bands): (Vec<Sweep>, Vec<Bands>) = (0..exemplars.len())
            .map(|i| {
                check(progress)?;
                let sweep = Sweep::new(mesh, topology, &exemplars, i, &bsp.split[i])?;
                let bands = Bands::new(&exemplars[i], options.low_sigma);
                progress.advance(1);
                Ok((sweep, bands))
            })
            .collect::<Result<Vec<_>>>()?
            .into_iter()
            .unzip();
        let stacks: Vec<Stack> = bands.par_iter().map(Stack::new).collect();
        let pairs: usize = bsp
            .regions
            .iter()
            .map(|r| r.bounds.len() * r.bounds.len().saturating_sub(1))
            .sum();
        progress.stage("morph: warps", pairs as u64);
        let warps = bsp
            .regions
            .iter()
            .map(|region| {
                let k = region.bounds.len();
                let extents: Vec<_> = region
                    .bounds
                    .iter()
                    .map(|b| extent(&b.cells, &sweeps[b.exemplar]))
                    .collect();
                (0..k * k)
                    .map(|st| {
                        let (s, t) = (st / k, st % k);
                        if s == t {
                            return Ok(None);
                        }
                        check(progress)?;
                        let (a, b) = (&region.bounds[s], &region.bounds[t]);
                        let warp = Warp::matched(
                            &stacks[a.exemplar],
                            extents[s],
                            &stacks[b.exemplar],
                            extents[t],
                        );
                        progress.advance(1);
                        Ok(Some(warp))
                    })
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Morph {
            exemplars,
            bands,
            sweeps,
            bsp,
            warps,
            options,
        })
    }

    /// Refuse a mesh that is not closed: its inside, the morph's domain, is
    /// not defined.
    pub fn check_mesh(topology: &Topology) -> Result<()> {
        let open = topology.boundary_loops().len();
        if open > 0 {
            return Err(Error::invalid(format!(
                "the mesh is not closed ({open} boundary loops): a morph fills a closed organ"
            )));
        }
        Ok(())
    }

    /// Read the sections file at `path` and precompute its morph in `mesh`;
    /// errors about the sections name the file.
    pub fn read(
        mesh: &TriMesh,
        topology: &Topology,
        path: &Path,
        options: MorphOptions,
        progress: &dyn Progress,
    ) -> Result<Morph> {
        Morph::check_mesh(topology)?;
        let exemplars = read_sections(path)?;
        Morph::new(mesh, topology, exemplars, options, progress).map_err(|e| e.in_file(path))
    }

    pub fn exemplars(&self) -> &[Exemplar] {
        &self.exemplars
    }

    /// How many regions the exemplar planes split the interior into.
    pub fn regions(&self) -> usize {
        self.bsp.regions.len()
    }

    /// The region holding `p`.
    pub fn region_of(&self, p: DVec3) -> usize {
        self.bsp.locate(&self.exemplars, p)
    }

    /// The exemplars bounding region `r`, in insertion order.
    pub fn bounds_of(&self, r: usize) -> Vec<usize> {
        self.bsp.regions[r]
            .bounds
            .iter()
            .map(|b| b.exemplar)
            .collect()
    }
}

impl Morph {
    /// Bytes held by its images, bands and warps (the BSP and sweeps are
    /// small beside them).
    pub fn bytes(&self) -> usize {
        let images: usize = self
            .exemplars
            .iter()
            .map(|e| 12 * e.rgb.len() + e.mask.as_ref().map_or(0, Vec::len))
            .sum();
        let bands: usize = self
            .bands
            .iter()
            .map(|b| 12 * (b.low.len() + b.detail.len()))
            .sum();
        let warps: usize = self.warps.iter().flatten().flatten().map(Warp::bytes).sum();
        images + bands + warps
    }

    /// The morph sampled into a `voxels`-a-side block over the cube of
    /// side the box's longest extent from `lo`, with its placement: for
    /// consumers that need a 3D texture (a GPU cut, an NRRD for other
    /// tools). Unlike a synthesised block it does not tile: read it inside
    /// the box only.
    pub fn block(&self, lo: DVec3, hi: DVec3, voxels: usize) -> Result<(Volume, Placement)> {
        let scale = (hi - lo).max_element() / voxels as f64;
        let placement = Placement::new(lo, scale)?;
        crate::memory::ensure_fits(
            &format!("a {voxels}^3 morph block"),
            crate::memory::product(&[voxels as u64, voxels as u64, voxels as u64, 27]),
        )?;
        let points: Vec<DVec3> = (0..voxels * voxels * voxels)
            .map(|i| {
                let (x, y, z) = (i % voxels, (i / voxels) % voxels, i / (voxels * voxels));
                lo + DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * scale
            })
            .collect();
        let volume = Volume {
            size: [voxels; 3],
            spacing: scale,
            voxels: self.colours(&points),
        };
        Ok((volume, placement))
    }
}

/// Bounds of a subdomain in its photograph's pixel coordinates: where its
/// plane points land once the photograph is fitted to the mesh (the warps
/// and the source points both live there).
fn extent(cells: &cells::Cells, sweep: &Sweep) -> (glam::DVec2, glam::DVec2) {
    cells.centres().map(|c| sweep.fitted(c, 0.0)).fold(
        (glam::DVec2::INFINITY, glam::DVec2::NEG_INFINITY),
        |(lo, hi), c| (lo.min(c), hi.max(c)),
    )
}

impl Interior for Morph {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        point::colour(self, p)
    }
}
