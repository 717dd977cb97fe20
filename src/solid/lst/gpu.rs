//! LST cuts on the GPU: the WGSL that colours a cut's fragments as
//! `LstInterior::colour_in` colours points (`sample.wgsl`), and the
//! buffers it reads, packed from models and their cuts. A renderer (the
//! viewer's, or a simulator's) uploads `CutBuffers` and draws its vertices
//! as a triangle list; nothing here needs a GPU.

use glam::DVec3;

use super::locate::barycentric;
use super::mask::{self, Splotch};
use super::model::LstModel;
use crate::tetra::march::Cut;

/// `sample.wgsl` with the mask's constants (mask.rs) it needs.
pub fn sample_lst_wgsl() -> String {
    format!(
        "const LST_ROW: u32 = {ROW}u;\nconst LST_RADIUS: f32 = {:?};\nconst LST_WANDER: f32 = {:?};\n\
         const LST_FALLOFF: f32 = {:?};\nconst LST_BAND_OUTER: f32 = {:?};\n\
         const LST_BAND_MIDDLE_LO: f32 = {:?};\nconst LST_BAND_MIDDLE_HI: f32 = {:?};\n\
         const LST_BAND_INNER: f32 = {:?};\n{}",
        mask::RADIUS as f32,
        mask::WANDER as f32,
        mask::FALLOFF as f32,
        mask::BAND_OUTER as f32,
        mask::BAND_MIDDLE.0 as f32,
        mask::BAND_MIDDLE.1 as f32,
        mask::BAND_INNER as f32,
        include_str!("sample.wgsl")
    )
}

/// Texels per row of the tables `sample.wgsl` reads (`CutBuffers::rows`).
pub const ROW: usize = 1024;

/// 32-bit words per vertex: position 3, normal 3, barycentric 4, depth 1
/// (f32 bits), tet slot 1 (u32).
pub const VERTEX_WORDS: usize = 12;

/// What `sample.wgsl` reads for one or more cuts, each through its model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CutBuffers {
    /// `VERTEX_WORDS` per vertex, three vertices per triangle, each
    /// placed in its triangle's tet (a vertex shared by triangles of
    /// different tets is repeated, its barycentric coordinates each
    /// tet's).
    pub vertices: Vec<u32>,
    /// Per slot: first layer, layer count, splotch, 0.
    pub tets: Vec<[u32; 4]>,
    /// Per layer: the four corners' (r, s, t), the mask kind in the first
    /// corner's fourth float.
    pub layers: Vec<[f32; 16]>,
    /// Per splotch, 6 waves as 2 vec4: (direction, phase), (amplitude, 0,
    /// 0, 0).
    pub waves: Vec<[f32; 4]>,
}

impl CutBuffers {
    pub fn vertex_count(&self) -> u32 {
        (self.vertices.len() / VERTEX_WORDS) as u32
    }

    /// A table of `texels` as a 2D texture's width and height, `ROW`
    /// texels a row (the last padded); at least 1 x 1.
    pub fn rows(texels: usize) -> [u32; 2] {
        [
            texels.clamp(1, ROW) as u32,
            texels.div_ceil(ROW).max(1) as u32,
        ]
    }

    /// Add `cut` (`tetra::march` through `model`'s mesh), its triangles
    /// shaded with `normal`.
    pub fn add(&mut self, model: &LstModel, cut: &Cut, normal: DVec3) {
        let splotch = (self.waves.len() / 12) as u32;
        for &(dir, phase, amp) in Splotch::new(model.seed).waves() {
            self.waves
                .push([dir[0] as f32, dir[1] as f32, dir[2] as f32, phase as f32]);
            self.waves.push([amp as f32, 0.0, 0.0, 0.0]);
        }
        let mut slot_of = std::collections::HashMap::new();
        for (tri, &t) in cut.triangles.iter().zip(&cut.tet_of) {
            let t = t as usize;
            let slot = *slot_of.entry(t).or_insert_with(|| {
                let layers = model.layers_of(t);
                self.tets
                    .push([self.layers.len() as u32, layers.len() as u32, splotch, 0]);
                for l in layers {
                    let mut packed = [0f32; 16];
                    for (k, c) in l.coords.iter().enumerate() {
                        packed[4 * k..4 * k + 3].copy_from_slice(c);
                    }
                    packed[3] = l.mask as u8 as f32;
                    self.layers.push(packed);
                }
                self.tets.len() as u32 - 1
            });
            let corners = model.mesh.corners(t);
            let tet = model.mesh.tets[t];
            for &v in tri {
                let p = cut.positions[v as usize];
                let b = barycentric(&corners, p);
                let depth = model.depth.as_ref().map_or(0.0, |d| {
                    (0..4).map(|k| b[k] * d[tet[k] as usize]).sum::<f64>()
                });
                let floats = [
                    p.x, p.y, p.z, normal.x, normal.y, normal.z, b[0], b[1], b[2], b[3], depth,
                ];
                self.vertices
                    .extend(floats.iter().map(|&x| (x as f32).to_bits()));
                self.vertices.push(slot);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::solid::lst::{TextureType, anchors};

    #[test]
    fn a_cut_packs_each_triangle_in_its_tet() {
        let a = anchors::cake(TextureType::Layered, 1500).unwrap();
        let model = crate::solid::lst::fill(&a.tets, &a.options, &Silent).unwrap();
        let (lo, hi) = a.surface.bounding_box().unwrap();
        let cut = crate::tetra::march::plane_cut(&model.mesh, DVec3::X, (lo.x + hi.x) / 2.0);
        let mut b = CutBuffers::default();
        b.add(&model, &cut, DVec3::X);
        assert_eq!(b.vertex_count() as usize, 3 * cut.triangles.len());
        assert_eq!(b.waves.len(), 12);
        for v in b.vertices.chunks(VERTEX_WORDS) {
            let f = |k: usize| f32::from_bits(v[k]) as f64;
            let bary = [f(6), f(7), f(8), f(9)];
            assert!((bary.iter().sum::<f64>() - 1.0).abs() < 1e-5);
            assert!(bary.iter().all(|&x| x > -1e-4), "{bary:?}");
            let slot = b.tets[v[11] as usize];
            assert!(slot[1] > 0, "every cut tet has layers");
        }
        let layers: usize = b.tets.iter().map(|t| t[1] as usize).sum();
        assert_eq!(layers, b.layers.len());
    }
}
