//! Colours of an LST model (seed 000, sec. 5.1): at a point, its tet's
//! layers composited in paste order, each later patch over the earlier
//! ones by its mask's alpha there, each patch's exemplar sampled
//! trilinearly at the interpolated texture coordinates. The result is
//! divided by the total alpha (1 - prod(1 - alpha)): where the masks cover
//! a point only partly it still shows tissue, not the background, and the
//! colour stays continuous across tet faces (a patch's clump holds every
//! tet its mask reaches, so a layer missing on one side of a face has alpha
//! 0 there). Where no mask reaches at all, the first layer shows.

use glam::DVec3;

use super::locate::Locator;
use super::mask::{MaskKind, Splotch};
use super::model::LstModel;
use crate::error::{Error, Result};
use crate::solid::Interior;
use crate::synth::volume::Volume;

/// An LST model with its exemplar, ready to colour points.
pub struct LstInterior<'a> {
    pub model: &'a LstModel,
    pub exemplar: &'a Volume,
    splotch: Splotch,
    /// Built on the first point query (cuts place their own vertices).
    locator: std::sync::OnceLock<Locator<'a>>,
}

impl<'a> LstInterior<'a> {
    /// Errors on an exemplar with a side under 2 voxels.
    pub fn new(model: &'a LstModel, exemplar: &'a Volume) -> Result<LstInterior<'a>> {
        if exemplar.size.iter().any(|&s| s < 2) {
            return Err(Error::invalid(format!(
                "the exemplar is {}x{}x{} voxels: an LST exemplar needs at least 2 a side",
                exemplar.size[0], exemplar.size[1], exemplar.size[2]
            )));
        }
        Ok(LstInterior {
            model,
            exemplar,
            splotch: Splotch::new(model.seed),
            locator: std::sync::OnceLock::new(),
        })
    }

    /// The colour in tet `t` at barycentric coordinates `b`.
    pub fn colour_in(&self, t: usize, b: [f64; 4]) -> [f32; 3] {
        let size = self.exemplar.size.map(|s| s as f64);
        let mut out = [0f32; 3];
        let mut clear = 1.0f32;
        let mut first = None;
        for layer in self.model.layers_of(t) {
            let mut w = layer.at(b);
            // A depth band's patch is layered (1-b, 2-b); a splotch's, of
            // a region inside a layered organ, is not.
            let layered = layer.mask != MaskKind::Splotch;
            if let (true, Some(d)) = (layered, &self.model.depth) {
                let tet = self.model.mesh.tets[t];
                w[1] = (0..4).map(|k| b[k] * d[tet[k] as usize]).sum();
            }
            let mut voxel = [w[0] * size[0], w[1] * size[1], w[2] * size[2]];
            if layered {
                // Depth runs across the exemplar's y, outer layer at y = 0:
                // clamp rather than wrap.
                voxel[1] = voxel[1].clamp(0.5, size[1] - 0.5);
            }
            let c = self.exemplar.sample(voxel);
            first.get_or_insert(c);
            let alpha = self.splotch.alpha(layer.mask, w) as f32;
            for a in 0..3 {
                out[a] = out[a] * (1.0 - alpha) + c[a] * alpha;
            }
            clear *= 1.0 - alpha;
        }
        let covered = 1.0 - clear;
        if covered > 1e-4 {
            out.map(|x| x / covered)
        } else {
            first.unwrap_or([0.0; 3])
        }
    }
}

impl LstInterior<'_> {
    /// The colour at every vertex of a cut through the model's tet mesh
    /// (`tetra::march`), read in the tet each vertex was placed in.
    pub fn cut_colours(&self, cut: &crate::tetra::march::Cut) -> Vec<[u8; 3]> {
        use rayon::prelude::*;
        cut.at
            .par_iter()
            .map(|&(t, b)| {
                self.colour_in(t as usize, b)
                    .map(|x| x.round().clamp(0.0, 255.0) as u8)
            })
            .collect()
    }
}

impl Interior for LstInterior<'_> {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        let locator = self.locator.get_or_init(|| Locator::new(&self.model.mesh));
        let (t, b) = locator.locate_or_nearest(p);
        self.colour_in(t, b)
            .map(|x| x.round().clamp(0.0, 255.0) as u8)
    }
}
