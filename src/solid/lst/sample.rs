//! Colours of an LST model (seed 000, sec. 5.1): at a point, its tet's
//! layers composited in paste order, each later patch over the earlier
//! ones by its mask's alpha there, each patch's exemplar sampled
//! trilinearly at the interpolated texture coordinates. The result is
//! divided by the total alpha (1 - prod(1 - alpha)): where the masks cover
//! a point only partly it still shows tissue, not the background, and the
//! colour stays continuous across tet faces (a patch's clump holds every
//! tet its mask reaches, so a layer missing on one side of a face has alpha
//! 0 there). Where no mask reaches at all, the first layer shows.
//!
//! Many points in one tet (the texels of a cut face) share the tet's
//! layers: `face_texels` interpolates each layer's texture coordinates
//! across the face once and drops the layers whose masks leave the whole
//! face out, or that a later layer covers fully, with the same colours.

use std::sync::Arc;

use glam::DVec3;

use super::locate::Locator;
use super::mask::{Cover, MaskKind, Splotch, cover};
use super::model::{Layer, LstModel};
use crate::error::{Error, Result};
use crate::solid::Interior;
use crate::synth::volume::Volume;

/// An LST model with its exemplar, ready to colour points. Owns both
/// (shared), so a runtime can keep it as long as it runs.
pub struct LstInterior {
    model: Arc<LstModel>,
    exemplar: Arc<Volume>,
    splotch: Splotch,
    /// Built on the first point query (cuts place their own vertices).
    locator: std::sync::OnceLock<Locator>,
}

impl LstInterior {
    /// Errors on an exemplar with a side under 2 voxels.
    pub fn new(model: Arc<LstModel>, exemplar: Arc<Volume>) -> Result<LstInterior> {
        Self::check_exemplar(&exemplar)?;
        let splotch = Splotch::new(model.seed);
        Ok(LstInterior {
            model,
            exemplar,
            splotch,
            locator: std::sync::OnceLock::new(),
        })
    }

    /// Refuses an exemplar with a side under 2 voxels.
    pub fn check_exemplar(exemplar: &Volume) -> Result<()> {
        if exemplar.size.iter().any(|&s| s < 2) {
            return Err(Error::invalid(format!(
                "the exemplar is {}x{}x{} voxels: an LST exemplar needs at least 2 a side",
                exemplar.size[0], exemplar.size[1], exemplar.size[2]
            )));
        }
        Ok(())
    }

    pub fn model(&self) -> &LstModel {
        &self.model
    }

    pub fn exemplar(&self) -> &Volume {
        &self.exemplar
    }

    /// Bytes held: the model's mesh, depths and layers, the exemplar, and
    /// the point locator once built.
    pub fn bytes(&self) -> usize {
        let m = &self.model;
        24 * m.mesh.positions.len()
            + 16 * m.mesh.tets.len()
            + m.depth.as_ref().map_or(0, |d| 8 * d.len())
            + 4 * m.start.len()
            + std::mem::size_of::<Layer>() * m.layers.len()
            + 3 * self.exemplar.voxels.len()
            + self.locator.get().map_or(0, Locator::bytes)
    }

    /// Layer `layer` of tet `t`'s texture coordinates at barycentric
    /// coordinates `b`: its own, with the depth as s where the layer is
    /// layered (a depth band's patch; a splotch's, of a region inside a
    /// layered organ, is not).
    #[inline]
    fn coords(&self, t: usize, layer: &Layer, b: [f64; 4]) -> [f64; 3] {
        let mut w = layer.at(b);
        if let (true, Some(d)) = (layer.mask != MaskKind::Splotch, &self.model.depth) {
            let tet = self.model.mesh.tets[t];
            w[1] = (0..4).map(|k| b[k] * d[tet[k] as usize]).sum();
        }
        w
    }

    /// The exemplar's colour at a layer's texture coordinates `w`.
    #[inline]
    fn sample(&self, layer: &Layer, w: [f64; 3]) -> [f32; 3] {
        let size = self.exemplar.size.map(|s| s as f64);
        let mut voxel = [w[0] * size[0], w[1] * size[1], w[2] * size[2]];
        if layer.mask != MaskKind::Splotch {
            // Depth runs across the exemplar's y, outer layer at y = 0:
            // clamp rather than wrap.
            voxel[1] = voxel[1].clamp(0.5, size[1] - 0.5);
        }
        self.exemplar.sample(voxel)
    }

    /// The colour in tet `t` at barycentric coordinates `b`.
    pub fn colour_in(&self, t: usize, b: [f64; 4]) -> [f32; 3] {
        let layers = self.model.layers_of(t);
        let n = layers.len();
        let w = |i: usize| self.coords(t, &layers[n - 1 - i], b);
        composite(
            n,
            |i| self.splotch.alpha(layers[n - 1 - i].mask, w(i)) as f32,
            |i| self.sample(&layers[n - 1 - i], w(i)),
        )
    }

    /// The colours at points of one face of tet `t`: `corners` are the
    /// face's corners in the tet's barycentric coordinates, `at` each
    /// point's barycentric coordinates in the face (outside it too). The
    /// same as `colour_in` at each point, rounded, computed per face.
    pub fn face_texels(&self, t: usize, corners: [[f64; 4]; 3], at: &[[f64; 3]]) -> Vec<[u8; 3]> {
        let layers = self.model.layers_of(t);
        // Each layer's texture coordinates at the corners; a texel's are
        // their blend (both the layer's coordinates and the depth are
        // linear in the tet).
        let mut kept: Vec<(&Layer, [[f64; 3]; 3])> = Vec::with_capacity(layers.len());
        let reach = reach(at);
        for layer in layers {
            let w = corners.map(|b| self.coords(t, layer, b));
            match cover(layer.mask, &w, reach) {
                Cover::None => continue,
                // A full cover hides every layer before it.
                Cover::Full => kept.clear(),
                Cover::Part => {}
            }
            kept.push((layer, w));
        }
        let n = kept.len();
        at.iter()
            .map(|b| {
                let w = |i: usize| {
                    let w = &kept[n - 1 - i].1;
                    [0, 1, 2].map(|a| b[0] * w[0][a] + b[1] * w[1][a] + b[2] * w[2][a])
                };
                let c = composite(
                    n,
                    |i| self.splotch.alpha(kept[n - 1 - i].0.mask, w(i)) as f32,
                    |i| self.sample(kept[n - 1 - i].0, w(i)),
                );
                c.map(|x| x.round().clamp(0.0, 255.0) as u8)
            })
            .collect()
    }

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

/// `n` layers composited as the module's comment says, front to back:
/// layer 0 is the last pasted. `alpha(i)` first; `colour(i)` only where
/// it shows, and the walk stops where a layer covers everything beneath
/// (alpha 1), which most points reach after a layer or two. Equal to
/// compositing back to front, up to rounding.
#[inline]
fn composite(
    n: usize,
    alpha: impl Fn(usize) -> f32,
    colour: impl Fn(usize) -> [f32; 3],
) -> [f32; 3] {
    let mut out = [0f32; 3];
    // What still shows through of the layers beneath.
    let mut through = 1.0f32;
    for i in 0..n {
        let a = alpha(i);
        if a <= 0.0 {
            continue;
        }
        let c = colour(i);
        for k in 0..3 {
            out[k] += through * a * c[k];
        }
        through *= 1.0 - a;
        if through <= 0.0 {
            return out;
        }
    }
    let covered = 1.0 - through;
    if covered > 1e-4 {
        out.map(|x| x / covered)
    } else if n > 0 {
        // No mask reaches: the first layer pasted shows.
        colour(n - 1)
    } else {
        [0.0; 3]
    }
}

/// How far past the face's corners its points reach: the face scaled
/// about its centroid by `1 + reach` holds every point of `at`.
fn reach(at: &[[f64; 3]]) -> f64 {
    // A point b = c + s (b' - c) with b' on the face and c = (1/3, 1/3,
    // 1/3) has b_i >= 1/3 - s/3 for the s it needs; so s <= 1 - 3 min b.
    at.iter()
        .flat_map(|b| b.iter().copied())
        .fold(0.0f64, |lo, x| lo.min(x))
        .abs()
        * 3.0
}

impl Interior for LstInterior {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        let locator = self.locator.get_or_init(|| Locator::new(&self.model.mesh));
        let (t, b) = locator.locate_or_nearest(&self.model.mesh, p);
        self.colour_in(t, b)
            .map(|x| x.round().clamp(0.0, 255.0) as u8)
    }
}
