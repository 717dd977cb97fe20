//! The LST model (seed 000, sec. 5.1): per tet, the patches pasted over it
//! in paste order, each with its mask and the texture coordinates of the
//! tet's four vertices; and its `.lst` file.
//!
//! `.lst`, version 1, little-endian, written atomically:
//! - magic `ORGANTEX-LST\n` (13 bytes), `u32` version;
//! - `u8` texture type (0, 1 = 1-a, 2 = 1-b, 3 = 2-a, 4 = 2-b), `u64` seed;
//! - the tet mesh: `u64` vertex count, `3 f64` per vertex, `u64` tet count,
//!   `4 u32` per tet;
//! - `u8` 1 if depths follow, then `f64` per vertex (layered types);
//! - `u64` layer count, then per tet its `u32` layer count, then the
//!   layers: `u32` patch, `u8` mask (`MaskKind`), `12 f32` texture
//!   coordinates (vertex by vertex, r s t). A layer with a depth band
//!   mask (1 to 3) is layered: its s is the depth there. A layered model
//!   may hold splotch layers too, from regions of type 0 or 1-a.

use std::path::Path;

use glam::DVec3;

use super::TextureType;
use super::mask::MaskKind;
use crate::error::{Error, Result};
use crate::tetra::TetMesh;

const MAGIC: &[u8; 13] = b"ORGANTEX-LST\n";
const VERSION: u32 = 1;

/// One pasted patch over one tet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    pub patch: u32,
    pub mask: MaskKind,
    /// Texture coordinates (the patch spans [0, 1]^3) of the tet's corners.
    pub coords: [[f32; 3]; 4],
}

impl Layer {
    /// The texture coordinates at barycentric coordinates `b` in the tet.
    pub fn at(&self, b: [f64; 4]) -> [f64; 3] {
        let mut w = [0.0; 3];
        for (c, &bk) in self.coords.iter().zip(&b) {
            for (wa, &ca) in w.iter_mut().zip(c) {
                *wa += bk * ca as f64;
            }
        }
        w
    }
}

/// A lapped solid texture over a tet mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct LstModel {
    pub kind: TextureType,
    /// The seed the fill used (the splotch mask's shape follows it).
    pub seed: u64,
    pub mesh: TetMesh,
    /// For layered types (1-b, 2-b), each vertex's depth: the s texture
    /// coordinate of every layer there (the layers' own s is its f32 copy).
    pub depth: Option<Vec<f64>>,
    /// Tet `t`'s layers are `layers[start[t]..start[t + 1]]`, in paste
    /// order.
    pub start: Vec<u32>,
    pub layers: Vec<Layer>,
    pub patches: u32,
}

impl LstModel {
    pub fn layers_of(&self, t: usize) -> &[Layer] {
        &self.layers[self.start[t] as usize..self.start[t + 1] as usize]
    }

    /// Bytes of the `.lst` file.
    pub fn file_size(&self) -> u64 {
        (13 + 4
            + 1
            + 8
            + 8
            + 24 * self.mesh.num_vertices()
            + 8
            + 16 * self.mesh.num_tets()
            + 1
            + self.depth.as_ref().map_or(0, |d| 8 * d.len())
            + 8
            + 4 * self.mesh.num_tets()
            + 53 * self.layers.len()) as u64
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        crate::atomic::write_file(path, |w| {
            w.write_all(MAGIC)?;
            w.write_all(&VERSION.to_le_bytes())?;
            w.write_all(&[self.kind as u8])?;
            w.write_all(&self.seed.to_le_bytes())?;
            w.write_all(&(self.mesh.num_vertices() as u64).to_le_bytes())?;
            for p in &self.mesh.positions {
                for x in p.to_array() {
                    w.write_all(&x.to_le_bytes())?;
                }
            }
            w.write_all(&(self.mesh.num_tets() as u64).to_le_bytes())?;
            for t in &self.mesh.tets {
                for v in t {
                    w.write_all(&v.to_le_bytes())?;
                }
            }
            w.write_all(&[self.depth.is_some() as u8])?;
            for d in self.depth.iter().flatten() {
                w.write_all(&d.to_le_bytes())?;
            }
            w.write_all(&(self.layers.len() as u64).to_le_bytes())?;
            for s in self.start.windows(2) {
                w.write_all(&(s[1] - s[0]).to_le_bytes())?;
            }
            for l in &self.layers {
                w.write_all(&l.patch.to_le_bytes())?;
                w.write_all(&[l.mask as u8])?;
                for c in l.coords.iter().flatten() {
                    w.write_all(&c.to_le_bytes())?;
                }
            }
            Ok(())
        })
    }

    pub fn read(path: &Path) -> Result<LstModel> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        LstModel::parse(&bytes).map_err(|why| Error::format(path, why))
    }

    /// Parse `.lst` bytes; the error says what is wrong and where.
    pub fn parse(bytes: &[u8]) -> std::result::Result<LstModel, String> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(13)? != MAGIC {
            return Err("not an organtex .lst file (bad magic)".into());
        }
        let version = r.u32()?;
        if version != VERSION {
            return Err(format!(
                "version {version}; this organtex reads version {VERSION}"
            ));
        }
        let kind = TextureType::from_u8(r.u8()?).ok_or("unknown texture type")?;
        let seed = r.u64()?;
        let nv = r.count(24, "vertices")?;
        let mut positions = Vec::with_capacity(nv);
        for i in 0..nv {
            let p = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
            if !p.is_finite() {
                return Err(format!("vertex {i} is not finite"));
            }
            positions.push(p);
        }
        let nt = r.count(16, "tets")?;
        let mut tets = Vec::with_capacity(nt);
        for i in 0..nt {
            let t = [r.u32()?, r.u32()?, r.u32()?, r.u32()?];
            if t.iter().any(|&v| v as usize >= nv) {
                return Err(format!("tet {i} refers to a vertex past {nv}"));
            }
            tets.push(t);
        }
        let depth = match r.u8()? {
            0 => None,
            1 => {
                r.need(8 * nv, "depths")?;
                let mut d = Vec::with_capacity(nv);
                for i in 0..nv {
                    let x = r.f64()?;
                    if !x.is_finite() {
                        return Err(format!("the depth of vertex {i} is not finite"));
                    }
                    d.push(x);
                }
                Some(d)
            }
            k => return Err(format!("depth flag {k}, expected 0 or 1")),
        };
        if depth.is_some() != kind.layered() {
            return Err(format!(
                "texture type {} {} depths",
                kind.name(),
                if kind.layered() { "needs" } else { "has no" }
            ));
        }
        let nl = r.count(53, "layers")?;
        let mut start = Vec::with_capacity(nt + 1);
        start.push(0u32);
        for _ in 0..nt {
            let k = r.u32()? as u64;
            let next = *start.last().unwrap_or(&0) as u64 + k;
            if next > nl as u64 {
                return Err(format!("per-tet layer counts add up past the {nl} layers"));
            }
            start.push(next as u32);
        }
        if *start.last().unwrap_or(&0) as usize != nl {
            return Err(format!(
                "per-tet layer counts add up to {}, the file has {nl} layers",
                start[nt]
            ));
        }
        let mut layers = Vec::with_capacity(nl);
        let mut patches = 0;
        for i in 0..nl {
            let patch = r.u32()?;
            let mask = MaskKind::from_u8(r.u8()?)
                .ok_or_else(|| format!("layer {i} has an unknown mask"))?;
            let mut coords = [[0f32; 3]; 4];
            for c in coords.iter_mut().flatten() {
                *c = r.f32()?;
                if !c.is_finite() {
                    return Err(format!(
                        "layer {i} has a texture coordinate that is not finite"
                    ));
                }
            }
            // Patches are numbered from 0, one per paste: no file holds
            // u32::MAX of them.
            if patch == u32::MAX {
                return Err(format!("layer {i} has patch number {patch}"));
            }
            patches = patches.max(patch + 1);
            layers.push(Layer {
                patch,
                mask,
                coords,
            });
        }
        if r.at != bytes.len() {
            return Err(format!("{} bytes after the last layer", bytes.len() - r.at));
        }
        if depth.is_none()
            && let Some(i) = layers.iter().position(|l| l.mask != MaskKind::Splotch)
        {
            return Err(format!(
                "layer {i} has a depth band mask, but the file has no depths"
            ));
        }
        let mesh = TetMesh {
            positions,
            tets,
            ..Default::default()
        };
        mesh.validate().map_err(|e| e.to_string())?;
        Ok(LstModel {
            kind,
            seed,
            mesh,
            depth,
            start,
            layers,
            patches,
        })
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> std::result::Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("cut short at byte {} (needs {n} more)", self.at))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self) -> std::result::Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f32(&mut self) -> std::result::Result<f32, String> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn f64(&mut self) -> std::result::Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    /// A count of items of `size` bytes each that must fit in what is left.
    fn count(&mut self, size: usize, what: &str) -> std::result::Result<usize, String> {
        let n = self.u64()?;
        self.need((n as usize).saturating_mul(size), what)?;
        Ok(n as usize)
    }
    fn need(&self, bytes: usize, what: &str) -> std::result::Result<(), String> {
        let left = self.bytes.len() - self.at;
        if bytes > left {
            return Err(format!("{what} need {bytes} bytes, {left} are left"));
        }
        Ok(())
    }
}
