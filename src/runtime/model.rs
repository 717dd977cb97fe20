//! A node's interior as the runtime holds it: one of the `solid::Interior`
//! models, and the two things a simulator asks of it many times a second,
//! the colour at a tet mesh's vertex and the texels of a face's chart.
//!
//! Where the face is a tet's face (a carving step) the tet is known and no
//! point is located: a lapped solid texture composites that tet's layers
//! directly (`LstInterior::face_texels`), skipping the layers its masks
//! leave out over the whole face. Elsewhere (any triangle a caller hands
//! in) the texel's 3D point is coloured by `Interior::colours`.

use glam::DVec3;

use super::atlas::Chart;
use crate::solid::lst::LstInterior;
use crate::solid::morph::Morph;
use crate::solid::{Block, Interior, Placement};
use crate::synth::volume::Volume;

/// One node's interior model.
pub enum Model {
    /// A block tiled through space from its placement: block synthesis
    /// (fnpts, optimize), a layered block, stereology's particles.
    Block {
        volume: Volume,
        placement: Placement,
    },
    /// A lapped solid texture over the node's tet mesh.
    Lapped(LstInterior),
    /// Photographed cuts morphed on demand (seed 003).
    Morph(Box<Morph>),
}

impl Model {
    /// The block and its placement, when the model is one (a GPU samples
    /// it per fragment).
    pub fn block(&self) -> Option<(&Volume, Placement)> {
        match self {
            Model::Block { volume, placement } => Some((volume, *placement)),
            _ => None,
        }
    }

    /// Bytes the model holds.
    pub fn bytes(&self) -> usize {
        match self {
            Model::Block { volume, .. } => 3 * volume.voxels.len(),
            Model::Lapped(l) => l.bytes(),
            Model::Morph(m) => m.bytes(),
        }
    }

    /// The colour at barycentric coordinates `b` of tet `t` (at `p`).
    pub fn colour_in(&self, t: usize, b: [f64; 4], p: DVec3) -> [u8; 3] {
        match self {
            Model::Lapped(l) => to_u8(l.colour_in(t, b)),
            _ => self.colour(p),
        }
    }

    /// The RGBA texels of `chart`'s slot (row by row): the face with
    /// corners `corners` coloured at each texel's 3D point, opaque on the
    /// face, its border as the face's plane continued, the rest clear.
    /// `tet`: the tet the face belongs to and the corners' barycentric
    /// coordinates in it, when known.
    pub fn face_texels(
        &self,
        chart: &Chart,
        corners: [DVec3; 3],
        tet: Option<(usize, [[f64; 4]; 3])>,
    ) -> Vec<u8> {
        let s = chart.slot;
        let mut rgba = vec![0u8; 4 * (s.width * s.height) as usize];
        let mut at = Vec::with_capacity((s.width * s.height) as usize);
        // Border texels are opaque too: a bilinear lookup at the face's
        // edge mixes them in, and clear ones would darken it.
        chart.texels(|x, y, b, _| {
            at.push((4 * ((y - s.y) * s.width + (x - s.x)) as usize, b));
        });
        let colours: Vec<[u8; 3]> = match (self, tet) {
            (Model::Lapped(l), Some((t, corner_b))) => {
                let bary: Vec<[f64; 3]> = at.iter().map(|&(_, b)| b).collect();
                l.face_texels(t, corner_b, &bary)
            }
            (Model::Block { volume, placement }, _) => at
                .iter()
                .map(|&(_, b)| {
                    let p = corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2];
                    to_u8(volume.sample(placement.voxel(p).to_array()))
                })
                .collect(),
            _ => {
                let points: Vec<DVec3> = at
                    .iter()
                    .map(|&(_, b)| corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2])
                    .collect();
                points.iter().map(|&p| self.colour(p)).collect()
            }
        };
        for (&(k, _), c) in at.iter().zip(&colours) {
            rgba[k..k + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
        }
        rgba
    }
}

impl Interior for Model {
    fn colour(&self, p: DVec3) -> [u8; 3] {
        match self {
            Model::Block { volume, placement } => Block {
                volume,
                placement: *placement,
            }
            .colour(p),
            Model::Lapped(l) => l.colour(p),
            Model::Morph(m) => m.colour(p),
        }
    }
}

#[inline]
fn to_u8(c: [f32; 3]) -> [u8; 3] {
    c.map(|x| x.round().clamp(0.0, 255.0) as u8)
}
