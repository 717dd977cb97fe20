//! NIfTI-1 single-file volumes (`.nii`, `.nii.gz`): the 348-byte header,
//! then the voxels. Written here rather than taken from the `nifti` crate,
//! which brings ndarray and reads into its own array types for what is one
//! header struct and a typed copy; the reader below is fuzzed
//! (`fuzz::nifti`) and refuses what it cannot honour with the field named.
//!
//! The voxel-to-world map is the header's sform when its code is set, else
//! its qform (a rotation quaternion, voxel sizes and an offset), else the
//! voxel sizes alone, as the NIfTI-1 standard orders them; world
//! coordinates are the scanner's RAS millimetres that 3D Slicer shows.

use std::io::Read;
use std::path::Path;

use glam::{DAffine3, DMat3, DVec3};

use super::ScalarVolume;
use crate::error::{Error, Result};

const HEADER: usize = 348;
/// The most voxels read (2^31): a 1290^3 volume.
const MAX_VOXELS: u64 = 1 << 31;

/// Read a `.nii` or `.nii.gz` file (gzip recognised by its magic bytes).
pub fn read(path: &Path) -> Result<ScalarVolume> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not a NIfTI file"));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut raw = Vec::new();
    std::io::BufReader::new(file)
        .read_to_end(&mut raw)
        .map_err(|e| Error::io(path, e))?;
    parse(&raw).map_err(|msg| Error::format(path, msg))
}

/// Parse a NIfTI-1 file held in memory, gzipped or not.
pub fn parse(bytes: &[u8]) -> std::result::Result<ScalarVolume, String> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        // The header first, to bound what the voxels may inflate to.
        let mut head = Vec::with_capacity(HEADER);
        let mut gz = flate2::read::MultiGzDecoder::new(bytes);
        (&mut gz)
            .take(HEADER as u64)
            .read_to_end(&mut head)
            .map_err(|e| format!("the gzip stream is damaged: {e}"))?;
        let header = Header::parse(&head)?;
        let mut rest = Vec::new();
        gz.take(header.end() - HEADER as u64)
            .read_to_end(&mut rest)
            .map_err(|e| format!("the gzip stream is damaged: {e}"))?;
        head.extend(rest);
        return header.volume(&head);
    }
    Header::parse(bytes)?.volume(bytes)
}

/// What the header says about the voxels.
struct Header {
    little: bool,
    size: [usize; 3],
    datatype: Datatype,
    offset: u64,
    slope: f64,
    intercept: f64,
    to_world: DAffine3,
}

/// A voxel's storage type (NIfTI's datatypes; NRRD's `type`s map onto them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Datatype {
    U8,
    I8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Datatype {
    fn from_code(code: i16) -> std::result::Result<Datatype, String> {
        use Datatype::*;
        Ok(match code {
            2 => U8,
            4 => I16,
            8 => I32,
            16 => F32,
            64 => F64,
            256 => I8,
            512 => U16,
            768 => U32,
            128 | 2304 => {
                return Err(format!(
                    "datatype {code} is colour (RGB/RGBA): a label map or grey volume has one value per voxel"
                ));
            }
            _ => {
                return Err(format!(
                    "datatype {code} is not one organtex reads (uint8, int8, int16, uint16, int32, uint32, float32, float64)"
                ));
            }
        })
    }

    pub(super) fn bytes(self) -> usize {
        use Datatype::*;
        match self {
            U8 | I8 => 1,
            I16 | U16 => 2,
            I32 | U32 | F32 => 4,
            F64 => 8,
        }
    }

    /// The values stored in `data` (whole voxels of this type), in the
    /// given byte order.
    pub(super) fn values(self, data: &[u8], little: bool) -> impl Iterator<Item = f64> + '_ {
        data.chunks_exact(self.bytes()).map(move |c| {
            let mut a = [0u8; 8];
            if little {
                a[..c.len()].copy_from_slice(c);
            } else {
                for (k, &x) in c.iter().rev().enumerate() {
                    a[k] = x;
                }
            }
            match self {
                Datatype::U8 => a[0] as f64,
                Datatype::I8 => a[0] as i8 as f64,
                Datatype::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                Datatype::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                Datatype::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Datatype::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Datatype::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Datatype::F64 => f64::from_le_bytes(a),
            }
        })
    }
}

impl Header {
    fn parse(b: &[u8]) -> std::result::Result<Header, String> {
        let word = |b: &[u8]| -> [u8; 4] { b[0..4].try_into().expect("four bytes") };
        let little = match b.get(0..4).map(word) {
            Some(w) if i32::from_le_bytes(w) == 348 => true,
            Some(w) if i32::from_be_bytes(w) == 348 => false,
            Some([0x1c, 0x02, 0, 0] | [0, 0, 0x02, 0x1c]) => {
                return Err("a NIfTI-2 file: organtex reads NIfTI-1 (.nii)".into());
            }
            _ => return Err("not a NIfTI-1 file (sizeof_hdr is not 348)".into()),
        };
        if b.len() < HEADER {
            return Err(format!(
                "only {} bytes: a NIfTI-1 header alone is {HEADER}",
                b.len()
            ));
        }
        let i16_at = |o: usize| {
            let a = [b[o], b[o + 1]];
            if little {
                i16::from_le_bytes(a)
            } else {
                i16::from_be_bytes(a)
            }
        };
        let f32_at = |o: usize| {
            let a = b[o..o + 4].try_into().unwrap();
            (if little {
                f32::from_le_bytes(a)
            } else {
                f32::from_be_bytes(a)
            }) as f64
        };
        match &b[344..348] {
            b"n+1\0" => {}
            b"ni1\0" => {
                return Err(
                    "a header-only .hdr (its voxels in a separate .img): give a single-file .nii"
                        .into(),
                );
            }
            _ => return Err("the NIfTI-1 magic is not 'n+1'".into()),
        }
        let dim: Vec<i16> = (0..8).map(|k| i16_at(40 + 2 * k)).collect();
        let rank = dim[0];
        if !(1..=7).contains(&rank) {
            return Err(format!("dim[0] is {rank}: a volume has 1 to 7 dimensions"));
        }
        let extent = |k: usize| if k as i16 <= rank { dim[k] } else { 1 };
        let size = [extent(1), extent(2), extent(3)];
        if let Some(k) = size.iter().position(|&s| s < 1) {
            return Err(format!(
                "dim[{}] is {}: sizes are at least 1",
                k + 1,
                size[k]
            ));
        }
        if let Some(k) = (4..=7).find(|&k| extent(k) > 1) {
            let what = if k == 4 { " time points" } else { "" };
            return Err(format!(
                "a {k}D volume (dim[{k}] = {}{what}): give one 3D volume",
                extent(k)
            ));
        }
        let size = size.map(|s| s as usize);
        let voxels = size.iter().map(|&s| s as u64).product::<u64>();
        if voxels > MAX_VOXELS {
            return Err(format!(
                "{voxels} voxels: more than organtex reads ({MAX_VOXELS})"
            ));
        }
        let datatype = Datatype::from_code(i16_at(70))?;
        let offset = f32_at(108);
        if !(offset >= HEADER as f64 && offset < 1e12) || offset.fract() != 0.0 {
            return Err(format!(
                "vox_offset is {offset}: the voxels start after the 348-byte header, at a whole byte"
            ));
        }
        let (slope, intercept) = match (f32_at(112), f32_at(116)) {
            // Zero or not a number: no scaling (the standard's rule).
            (s, _) if s == 0.0 || !s.is_finite() => (1.0, 0.0),
            (s, i) if i.is_finite() => (s, i),
            (_, i) => return Err(format!("scl_inter is {i}")),
        };
        let pixdim: Vec<f64> = (0..8).map(|k| f32_at(76 + 4 * k)).collect();
        let to_world = transform(i16_at(252), i16_at(254), &pixdim, &f32_at)?;
        Ok(Header {
            little,
            size,
            datatype,
            offset: offset as u64,
            slope,
            intercept,
            to_world,
        })
    }

    /// The byte just past the voxels.
    fn end(&self) -> u64 {
        self.offset
            + self.size.iter().map(|&s| s as u64).product::<u64>() * self.datatype.bytes() as u64
    }

    fn volume(&self, b: &[u8]) -> std::result::Result<ScalarVolume, String> {
        let n = self.size.iter().product::<usize>();
        let width = self.datatype.bytes();
        let start = self.offset as usize;
        if (b.len() as u64) < self.end() {
            return Err(format!(
                "truncated: {} bytes of voxel data where the header's {}x{}x{} voxels need {}",
                b.len().saturating_sub(start),
                self.size[0],
                self.size[1],
                self.size[2],
                n * width
            ));
        }
        let data = &b[start..start + n * width];
        let values: Vec<f32> = self
            .datatype
            .values(data, self.little)
            .map(|v| (v * self.slope + self.intercept) as f32)
            .collect();
        if values.iter().any(|v| v.is_nan()) {
            return Err("the voxels hold NaN values".into());
        }
        Ok(ScalarVolume {
            size: self.size,
            values,
            to_world: self.to_world,
        })
    }
}

/// The voxel-to-world map (NIfTI-1, method 3, 2 or 1).
fn transform(
    qform_code: i16,
    sform_code: i16,
    pixdim: &[f64],
    f32_at: &dyn Fn(usize) -> f64,
) -> std::result::Result<DAffine3, String> {
    let affine = if sform_code > 0 {
        let row = |o: usize| [0, 1, 2, 3].map(|k| f32_at(o + 4 * k));
        let (x, y, z) = (row(280), row(296), row(312));
        DAffine3 {
            matrix3: DMat3::from_cols(
                DVec3::new(x[0], y[0], z[0]),
                DVec3::new(x[1], y[1], z[1]),
                DVec3::new(x[2], y[2], z[2]),
            ),
            translation: DVec3::new(x[3], y[3], z[3]),
        }
    } else {
        let spacing = DVec3::new(pixdim[1], pixdim[2], pixdim[3]);
        if spacing.min_element() <= 0.0 || !spacing.is_finite() {
            return Err(format!(
                "pixdim[1..3] is {spacing}: voxel sizes are positive lengths"
            ));
        }
        if qform_code > 0 {
            let (b, c, d) = (f32_at(256), f32_at(260), f32_at(264));
            let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
            let q = glam::DQuat::from_xyzw(b, c, d, a);
            let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
            DAffine3 {
                matrix3: DMat3::from_quat(q.normalize())
                    * DMat3::from_diagonal(spacing * DVec3::new(1.0, 1.0, qfac)),
                translation: DVec3::new(f32_at(268), f32_at(272), f32_at(276)),
            }
        } else {
            DAffine3::from_scale(spacing)
        }
    };
    let det = affine.matrix3.determinant();
    if !affine.matrix3.is_finite() || !affine.translation.is_finite() {
        return Err("the voxel-to-world transform holds non-finite numbers".into());
    }
    let scale = affine.matrix3.x_axis.length()
        * affine.matrix3.y_axis.length()
        * affine.matrix3.z_axis.length();
    if det.abs() <= 1e-9 * scale || scale == 0.0 {
        let which = if sform_code > 0 { "sform" } else { "qform" };
        return Err(format!(
            "the {which}'s direction matrix is singular: its axes do not span space"
        ));
    }
    Ok(affine)
}

/// A NIfTI-1 file of `volume` (float32, sform set, little-endian): for
/// tests and tools that need one.
pub fn to_bytes(volume: &ScalarVolume) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let put_i16 = |h: &mut Vec<u8>, o: usize, v: i16| h[o..o + 2].copy_from_slice(&v.to_le_bytes());
    let put_f32 =
        |h: &mut Vec<u8>, o: usize, v: f64| h[o..o + 4].copy_from_slice(&(v as f32).to_le_bytes());
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    put_i16(&mut h, 40, 3);
    for k in 0..3 {
        put_i16(&mut h, 42 + 2 * k, volume.size[k] as i16);
    }
    for k in 3..7 {
        put_i16(&mut h, 42 + 2 * k, 1);
    }
    put_i16(&mut h, 70, 16);
    put_i16(&mut h, 72, 32);
    let m = volume.to_world.matrix3;
    put_f32(&mut h, 76, 1.0);
    for (k, axis) in [m.x_axis, m.y_axis, m.z_axis].iter().enumerate() {
        put_f32(&mut h, 80 + 4 * k, axis.length());
    }
    put_f32(&mut h, 108, 352.0);
    put_f32(&mut h, 112, 1.0);
    put_i16(&mut h, 254, 2);
    let t = volume.to_world.translation;
    for (r, o) in [280, 296, 312].into_iter().enumerate() {
        let row = [m.x_axis[r], m.y_axis[r], m.z_axis[r], t[r]];
        for (k, v) in row.into_iter().enumerate() {
            put_f32(&mut h, o + 4 * k, v);
        }
    }
    h[344..348].copy_from_slice(b"n+1\0");
    for v in &volume.values {
        h.extend_from_slice(&v.to_le_bytes());
    }
    h
}
