//! An organ's interior block from its tissue: the tissue's tileable
//! colour texture, brought down to twice the block's side (a block copies
//! neighbourhoods of the exemplar's scale; a much larger exemplar only
//! costs search time), synthesised into a tiling block (seed 004, 3.3).

use std::path::Path;

use crate::error::Result;
use crate::progress::Progress;
use crate::synth::block::{BlockOptions, Method, synthesize_block};
use crate::synth::exemplar::{Exemplar, read_image};
use crate::synth::volume::Volume;

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
