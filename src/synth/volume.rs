//! Solid textures: RGB voxel blocks, and their files in NRRD (raw, uint8),
//! which medical tools (3D Slicer, ITK, teem) read.
//!
//! Written by hand: the format is a short text header and the raw bytes,
//! and the nrrd crates on crates.io are unmaintained or read-only.

use std::path::Path;

use crate::atomic;
use crate::error::{Error, Result};

/// An RGB block of `size[0] x size[1] x size[2]` voxels, x fastest, then y,
/// then z. `spacing` is a voxel's edge length in object units, for
/// placing the block in a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub size: [usize; 3],
    pub spacing: f64,
    pub voxels: Vec<[u8; 3]>,
}

impl Volume {
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.size[1] + y) * self.size[0] + x
    }

    /// The colour at a point in voxel units, trilinear between voxel
    /// centres (voxel i's centre is at i + 0.5), wrapping around so the
    /// block tiles space.
    pub fn sample(&self, p: [f64; 3]) -> [f32; 3] {
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        let mut t = [0f32; 3];
        for a in 0..3 {
            let n = self.size[a] as f64;
            let u = (p[a] - 0.5).rem_euclid(n);
            let i = u.floor();
            lo[a] = (i as usize).min(self.size[a] - 1);
            hi[a] = (lo[a] + 1) % self.size[a];
            t[a] = (u - i) as f32;
        }
        let mut out = [0f32; 3];
        for corner in 0..8 {
            let pick = |a: usize| corner >> a & 1 == 1;
            let mut w = 1.0;
            let mut at = [0usize; 3];
            for a in 0..3 {
                (w, at[a]) = if pick(a) {
                    (w * t[a], hi[a])
                } else {
                    (w * (1.0 - t[a]), lo[a])
                };
            }
            let c = self.voxels[self.index(at[0], at[1], at[2])];
            for k in 0..3 {
                out[k] += w * c[k] as f32;
            }
        }
        out
    }

    /// The slice at `index` across `axis` (0 = x, ...), as a row-major
    /// image: across x it spans (y, z), across y (x, z), across z (x, y).
    pub fn slice(&self, axis: usize, index: usize) -> (usize, usize, Vec<[u8; 3]>) {
        let [nx, ny, nz] = self.size;
        match axis {
            0 => (
                ny,
                nz,
                (0..nz)
                    .flat_map(|z| (0..ny).map(move |y| (y, z)))
                    .map(|(y, z)| self.voxels[self.index(index, y, z)])
                    .collect(),
            ),
            1 => (
                nx,
                nz,
                (0..nz)
                    .flat_map(|z| (0..nx).map(move |x| (x, z)))
                    .map(|(x, z)| self.voxels[self.index(x, index, z)])
                    .collect(),
            ),
            _ => (
                nx,
                ny,
                self.voxels[index * nx * ny..(index + 1) * nx * ny].to_vec(),
            ),
        }
    }

    /// The NRRD file: header, blank line, raw RGB bytes.
    pub fn to_nrrd(&self) -> Vec<u8> {
        let [nx, ny, nz] = self.size;
        let s = self.spacing;
        let header = format!(
            "NRRD0004\n\
             # solid texture written by organtex\n\
             type: uint8\n\
             dimension: 4\n\
             sizes: 3 {nx} {ny} {nz}\n\
             spacings: nan {s} {s} {s}\n\
             kinds: RGB-color domain domain domain\n\
             encoding: raw\n\n"
        );
        let mut bytes = header.into_bytes();
        bytes.extend(self.voxels.iter().flatten());
        bytes
    }

    pub fn write_nrrd(&self, path: &Path) -> Result<()> {
        let bytes = self.to_nrrd();
        atomic::write_file(path, |w| w.write_all(&bytes))
    }

    pub fn read_nrrd(path: &Path) -> Result<Volume> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::from_nrrd(&bytes).map_err(|msg| Error::format(path, msg))
    }

    /// Parse what `to_nrrd` writes, and the same layout from other tools:
    /// uint8 RGB, raw encoding, header fields in any order.
    pub fn from_nrrd(bytes: &[u8]) -> std::result::Result<Volume, String> {
        if !bytes.starts_with(b"NRRD000") {
            return Err("not an NRRD file (no NRRD000x magic line)".into());
        }
        let end = bytes
            .windows(2)
            .position(|w| w == b"\n\n")
            .ok_or("the NRRD header does not end in a blank line")?;
        let header = std::str::from_utf8(&bytes[..end])
            .map_err(|_| "the NRRD header is not text".to_string())?;
        let data = &bytes[end + 2..];
        let mut sizes: Option<Vec<usize>> = None;
        let mut spacing = 1.0;
        let (mut typ, mut encoding, mut dimension) = (None, None, None);
        for (n, line) in header.lines().enumerate().skip(1) {
            if line.starts_with('#') || line.trim().is_empty() {
                continue;
            }
            let Some((key, value)) = line.split_once(':') else {
                // Key/value pairs (`key:=value`) carry no layout.
                return Err(format!(
                    "header line {}: '{line}' is not 'field: value'",
                    n + 1
                ));
            };
            if value.starts_with('=') {
                continue;
            }
            let value = value.trim();
            match key.trim() {
                "type" => typ = Some(value.to_string()),
                "encoding" => encoding = Some(value.to_string()),
                "dimension" => dimension = value.parse::<usize>().ok(),
                "sizes" => {
                    sizes = Some(
                        value
                            .split_whitespace()
                            .map(|s| s.parse::<usize>())
                            .collect::<std::result::Result<_, _>>()
                            .map_err(|_| format!("header line {}: bad sizes '{value}'", n + 1))?,
                    )
                }
                "spacings" => {
                    if let Some(s) = value
                        .split_whitespace()
                        .filter_map(|s| s.parse::<f64>().ok())
                        .find(|s| s.is_finite() && *s > 0.0)
                    {
                        spacing = s;
                    }
                }
                _ => {}
            }
        }
        match typ.as_deref() {
            Some("uint8" | "uchar" | "unsigned char" | "uint8_t") => {}
            Some(t) => return Err(format!("type '{t}' is not supported; uint8 is")),
            None => return Err("the header has no type field".into()),
        }
        match encoding.as_deref() {
            Some("raw") => {}
            Some(e) => return Err(format!("encoding '{e}' is not supported; raw is")),
            None => return Err("the header has no encoding field".into()),
        }
        let sizes = sizes.ok_or("the header has no sizes field")?;
        if dimension != Some(4) || sizes.len() != 4 || sizes[0] != 3 {
            return Err(format!(
                "expected an RGB volume (dimension 4, sizes 3 X Y Z), found sizes {sizes:?}"
            ));
        }
        let size = [sizes[1], sizes[2], sizes[3]];
        if size.contains(&0) || size.iter().any(|&s| s > 4096) {
            return Err(format!("block size {size:?} is outside 1..4096 a side"));
        }
        let count = size[0] * size[1] * size[2];
        if data.len() != 3 * count {
            return Err(format!(
                "{} bytes of voxel data where sizes {size:?} need {}",
                data.len(),
                3 * count
            ));
        }
        Ok(Volume {
            size,
            spacing,
            voxels: data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Volume {
        let size = [4, 3, 2];
        Volume {
            size,
            spacing: 0.5,
            voxels: (0..24)
                .map(|i| [i as u8 * 10, (i % 4) as u8, (i / 12) as u8])
                .collect(),
        }
    }

    #[test]
    fn nrrd_round_trip() {
        let v = ramp();
        assert_eq!(Volume::from_nrrd(&v.to_nrrd()).unwrap(), v);
    }

    #[test]
    fn malformed_nrrd_is_an_error() {
        let good = ramp().to_nrrd();
        assert!(Volume::from_nrrd(b"P6 not nrrd").is_err());
        assert!(Volume::from_nrrd(&good[..good.len() - 1]).is_err());
        let text = String::from_utf8_lossy(&good).replace("uint8", "float");
        assert!(Volume::from_nrrd(text.as_bytes()).is_err());
        let text = String::from_utf8_lossy(&good).replace("sizes: 3 4", "sizes: 4 4");
        assert!(Volume::from_nrrd(text.as_bytes()).is_err());
    }

    #[test]
    fn sampling_at_voxel_centres_is_exact_and_wraps() {
        let v = ramp();
        let at = |x: usize, y: usize, z: usize| v.voxels[v.index(x, y, z)].map(|c| c as f32);
        assert_eq!(v.sample([2.5, 1.5, 0.5]), at(2, 1, 0));
        assert_eq!(v.sample([2.5 + 4.0, 1.5 - 3.0, 0.5 + 2.0]), at(2, 1, 0));
        // Halfway between the last and the first voxel along x.
        let mid = v.sample([4.0, 0.5, 0.5]);
        let (a, b) = (at(3, 0, 0), at(0, 0, 0));
        for k in 0..3 {
            assert!((mid[k] - (a[k] + b[k]) / 2.0).abs() < 1e-4);
        }
    }
}
