//! The colour inside an organ, whatever model makes it: `Interior` is
//! what sections, the bake, the viewer's cut plane and the simulator's
//! runtime call. A tiling block placed in space (`Block`) and a lapped
//! solid texture (`lst::LstInterior`) are two models of it.
//!
//! `interior_block` makes a block from a tissue: the tissue's tileable
//! colour texture, brought down to twice the block's side (a block copies
//! neighbourhoods of the exemplar's scale; a much larger exemplar only
//! costs search time), synthesised into a tiling block (seed 004, 3.3).

use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use crate::error::Result;
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

/// A block tiled through space from its placement (seed 004, 3.3).
pub struct Block<'a> {
    pub volume: &'a Volume,
    pub placement: super::cut::Placement,
}

impl Interior for Block<'_> {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        self.volume
            .sample(self.placement.voxel(p).to_array())
            .map(|x| x.round().clamp(0.0, 255.0) as u8)
    }
}

/// A `size`^3 block from the colour texture at `colour`, by `method`.
pub fn interior_block(
    colour: &Path,
    size: usize,
    method: Method,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Volume> {
    let side = 2 * size as u32;
    let img = read_image(colour)?
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
