//! The colour inside an organ, whatever model makes it: `Interior` is
//! what sections (`render_section`), cut surfaces (`texture_cut`), the
//! bake, the viewer's cut plane and the simulator's runtime call. A tiling
//! block placed in space (`Block`, which stereology's particles also fill),
//! a lapped solid texture (`lst::LstInterior`) and photographed cuts
//! morphed on demand (`morph::Morph`) are its models.
//!
//! `interior_block` makes a block from a tissue: the tissue's tileable
//! colour texture, brought down to twice the block's side (a block copies
//! neighbourhoods of the exemplar's scale; a much larger exemplar only
//! costs search time), synthesised into a tiling block (seed 004, 3.3);
//! or particles from stereology (seed 001) measured in photographs of
//! sections, at the photographs' own scale. A morph (seed 003,
//! `solid::morph::Morph`) is a third model: it colours points from placed
//! photographs and stores no block.

use std::path::{Path, PathBuf};

use glam::DVec3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::synth::block::{BlockOptions, Method, synthesize_block};
use crate::synth::exemplar::{Exemplar, read_image};
use crate::synth::volume::Volume;

/// A model of the colour inside an organ.
pub trait Interior: Sync {
    /// The colour at an object-space point.
    fn colour(&self, p: DVec3) -> [u8; 3];

    /// The colours at many points, in parallel.
    fn colours(&self, points: &[DVec3]) -> Vec<[u8; 3]> {
        points.par_iter().map(|&p| self.colour(p)).collect()
    }
}

/// Where the block sits in object space: the object point `p` is at voxel
/// coordinates `(p - origin) / scale`, so `scale` is the object units one
/// voxel spans and `origin` is where the block's corner (voxel 0's low
/// corner) lies. The block repeats in every direction from there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub origin: DVec3,
    pub scale: f64,
}

impl Placement {
    /// Refuses a non-finite origin and a scale that is not positive.
    pub fn new(origin: DVec3, scale: f64) -> Result<Placement> {
        if !(origin.is_finite() && scale > 0.0 && scale.is_finite()) {
            return Err(Error::invalid(format!(
                "the block placement needs a finite origin and a positive scale, \
                 not origin {origin} and scale {scale}"
            )));
        }
        Ok(Placement { origin, scale })
    }

    /// The block at the origin, a voxel spanning its own spacing (NRRD's
    /// `spacings`, in object units).
    pub fn of_volume(volume: &Volume) -> Placement {
        Placement {
            origin: DVec3::ZERO,
            scale: volume.spacing,
        }
    }

    /// Voxel coordinates of an object-space point.
    #[inline]
    pub fn voxel(&self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.scale
    }

    /// The uniform `SAMPLE_BLOCK_WGSL` reads: origin x, y, z, then scale.
    pub fn uniform(&self) -> [f32; 4] {
        let o = self.origin.as_vec3();
        [o.x, o.y, o.z, self.scale as f32]
    }
}

/// A block tiled through space from its placement (seed 004, 3.3).
pub struct Block<'a> {
    pub volume: &'a Volume,
    pub placement: Placement,
}

impl Interior for Block<'_> {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        self.volume
            .sample(self.placement.voxel(p).to_array())
            .map(|x| x.round().clamp(0.0, 255.0) as u8)
    }
}

/// How a node's interior block is made (`[node.interior] method`; scene
/// files name it in lower case).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InteriorMethod {
    /// Block synthesis by FNPTS (sharp; streaks on cuts across x).
    #[default]
    Fnpts,
    /// Block synthesis by texture optimisation (no streaks, softer).
    Optimize,
    /// Particles in a binder from stereology (seed 001), measured in the
    /// node's photographs of sections.
    Stereology,
    /// Morphed on demand from photographs of a few cuts placed as planes
    /// in the node (seed 003, `solid::morph`); no block of its own.
    Morph,
    /// A layered block (seed 002, 4.2) from the tissue's layered exemplar
    /// (rows = depth, top = outer; the database's `layers` output), its y
    /// axis depth: what a type 1b or 2b lapped solid texture lays through
    /// the wall from the outer facet to the inner one.
    Layered,
}

impl InteriorMethod {
    /// The block synthesis method, if it is one.
    pub fn block(self) -> Option<Method> {
        match self {
            InteriorMethod::Fnpts => Some(Method::Fnpts),
            InteriorMethod::Optimize => Some(Method::Optimize),
            InteriorMethod::Stereology | InteriorMethod::Morph | InteriorMethod::Layered => None,
        }
    }

    /// The database output the block is made from.
    pub fn output(self) -> crate::db::Output {
        match self {
            InteriorMethod::Layered => crate::db::Output::Layers,
            _ => crate::db::Output::Colour,
        }
    }
}

/// A `size`^3 block by `method` from the tissue's built file at `texture`
/// (`InteriorMethod::output`): its colour texture, or for stereology
/// `photographs` (the colour texture where none are given), or for a
/// layered block its layered exemplar (scaled to `size` rows, the block's
/// depth along y).
pub fn interior_block(
    texture: &Path,
    photographs: &[PathBuf],
    particles: super::stereology::Particles,
    size: usize,
    method: InteriorMethod,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Volume> {
    if method == InteriorMethod::Morph {
        return Err(crate::error::Error::invalid(
            "a morphed interior is made from the node's mesh and sections file \
             (solid::morph::Morph), not as a block",
        ));
    }
    if method == InteriorMethod::Layered {
        let exemplar = Exemplar::load(texture, None, None)?;
        // As `synth3d --layered`: scaling up by more than 2 would invent
        // the layers' detail.
        if 2 * exemplar.height < size {
            return Err(crate::error::Error::invalid(format!(
                "the layered exemplar has {} rows; a layered block of {size} voxels takes its \
                 depth from at least {} of them: ask for fewer interior voxels or a taller exemplar",
                exemplar.height,
                size.div_ceil(2)
            ))
            .in_file(texture));
        }
        let exemplar = exemplar.with_height(size).map_err(|e| e.in_file(texture))?;
        let opts = crate::synth::block::layered::LayeredOptions {
            size,
            seed,
            ..Default::default()
        };
        return crate::synth::block::layered::synthesize_layered(&exemplar, &opts, progress)
            .map_err(|e| e.in_file(texture));
    }
    let Some(method) = method.block() else {
        let paths = if photographs.is_empty() {
            vec![texture.to_path_buf()]
        } else {
            photographs.to_vec()
        };
        let sections = super::stereology::read_sections(&paths, None, particles, seed)?;
        let opts = super::stereology::StereologyOptions {
            size,
            seed,
            ..Default::default()
        };
        return super::stereology::synthesize(&sections, &opts, progress)
            .map(|(volume, _)| volume)
            .map_err(|e| e.in_file(&paths[0]));
    };
    let side = 2 * size as u32;
    let img = read_image(texture)?
        .resize_exact(side, side, image::imageops::FilterType::Triangle)
        .to_rgb8();
    let pixels = img.pixels().map(|p| p.0).collect::<Vec<_>>();
    let n = pixels.len();
    let exemplar = Exemplar::new(side as usize, side as usize, pixels, vec![true; n])?;
    let opts = BlockOptions {
        size,
        seed,
        method,
        ..BlockOptions::default()
    };
    synthesize_block(&[exemplar], &opts, progress)
}
