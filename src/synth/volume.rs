//! Solid textures: RGB voxel blocks, and their files in NRRD (uint8; raw
//! written, raw or gzip read, attached or in a detached data file), which
//! medical tools (3D Slicer, ITK, teem) read and write.
//!
//! Written by hand: the format is a short text header and the raw bytes,
//! and the nrrd crates on crates.io are unmaintained or read-only.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::atomic;
use crate::error::{Error, Result};

/// An RGB block of `size[0] x size[1] x size[2]` voxels, x fastest, then y,
/// then z. `spacing` is a voxel's edge length in object units, for
/// placing the block in a scene. Every side is at least 1 and `voxels`
/// holds one entry per voxel (what `from_nrrd` and the synthesisers make,
/// and what `sample` and `slice` index by).
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
            // A hair below 0 wraps to exactly n in floating point: that is
            // voxel 0 again, not voxel n - 1.
            lo[a] = if i >= n { 0 } else { i as usize };
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

    /// Mean colour jump between voxel planes `i` and `i + 1` (wrapped)
    /// across `axis`.
    fn plane_jump(&self, axis: usize, i: usize) -> f64 {
        let next = (i + 1) % self.size[axis];
        let (_, _, a) = self.slice(axis, i);
        let (_, _, b) = self.slice(axis, next);
        let sum: u64 = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (0..3).map(|k| p[k].abs_diff(q[k]) as u64).sum::<u64>())
            .sum();
        sum as f64 / (3 * a.len()) as f64
    }

    /// The tiling seam across `axis`: the jump across the wrap-around face
    /// over the mean jump between inner neighbouring planes (1 = seamless),
    /// as `quality::seam` in 2D.
    pub fn seam(&self, axis: usize) -> f64 {
        let n = self.size[axis];
        if n < 2 {
            return 1.0;
        }
        let inner = (0..n - 1).map(|i| self.plane_jump(axis, i)).sum::<f64>() / (n - 1) as f64;
        if inner == 0.0 {
            return 1.0;
        }
        self.plane_jump(axis, n - 1) / inner
    }

    /// A block that wraps around is as seamless wherever it starts, but
    /// where it starts is where copies meet when tiled: roll it along each
    /// axis so the tile faces fall where neighbouring planes differ least.
    pub fn rolled_to_smoothest_wrap(self) -> Volume {
        self.rolled_to_smoothest_wrap_along([true; 3])
    }

    /// `rolled_to_smoothest_wrap` along the axes marked only (a layered
    /// block keeps its depth axis where it is: its top is the outer layer).
    pub fn rolled_to_smoothest_wrap_along(self, axes: [bool; 3]) -> Volume {
        let shift: [usize; 3] = std::array::from_fn(|axis| {
            let n = self.size[axis];
            if !axes[axis] {
                return 0;
            }
            // Cutting between planes i and i + 1 starts the block at i + 1.
            let jumps: Vec<f64> = (0..n).map(|i| self.plane_jump(axis, i)).collect();
            let cut = (0..n)
                .min_by(|&a, &b| jumps[a].total_cmp(&jumps[b]).then(a.cmp(&b)))
                .unwrap_or(0);
            (cut + 1) % n
        });
        let [nx, ny, nz] = self.size;
        let voxels = (0..nx * ny * nz)
            .map(|i| {
                let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
                self.voxels[self.index(
                    (x + shift[0]) % nx,
                    (y + shift[1]) % ny,
                    (z + shift[2]) % nz,
                )]
            })
            .collect();
        Volume { voxels, ..self }
    }

    /// The NRRD file: header, blank line, raw RGB bytes.
    pub fn to_nrrd(&self) -> Vec<u8> {
        self.to_nrrd_with_depth(None)
    }

    /// The NRRD file of a layered (depth-varying) exemplar: the header
    /// names its depth axis (`DEPTH_AXIS_KEY`, x, y or z) for the LST
    /// reader (`read_exemplar`).
    pub fn to_nrrd_with_depth(&self, depth_axis: Option<usize>) -> Vec<u8> {
        let [nx, ny, nz] = self.size;
        let s = self.spacing;
        let depth = depth_axis.map_or(String::new(), |a| {
            format!("{DEPTH_AXIS_KEY}:={}\n", ["x", "y", "z"][a.min(2)])
        });
        let header = format!(
            "NRRD0004\n\
             # solid texture written by organtex\n\
             type: uint8\n\
             dimension: 4\n\
             sizes: 3 {nx} {ny} {nz}\n\
             spacings: nan {s} {s} {s}\n\
             kinds: RGB-color domain domain domain\n\
             encoding: raw\n\
             {depth}\n"
        );
        let mut bytes = header.into_bytes();
        bytes.extend(self.voxels.iter().flatten());
        bytes
    }

    pub fn write_nrrd(&self, path: &Path) -> Result<()> {
        self.write_nrrd_with_depth(path, None)
    }

    /// `write_nrrd`, naming the depth axis of a layered exemplar.
    pub fn write_nrrd_with_depth(&self, path: &Path, depth_axis: Option<usize>) -> Result<()> {
        let bytes = self.to_nrrd_with_depth(depth_axis);
        atomic::write_file(path, |w| w.write_all(&bytes))
    }

    /// A solid exemplar for lapped solid textures: the NRRD with its depth
    /// axis, if its header names one, turned to run along y (where the
    /// LST sampler reads depth, y = 0 outer).
    pub fn read_exemplar(path: &Path) -> Result<Volume> {
        let (volume, depth) = Volume::read_nrrd_with_depth(path)?;
        Ok(match depth {
            Some(axis) => volume.depth_along_y(axis),
            None => volume,
        })
    }

    /// The volume with axis `axis` and y swapped (x stays x for a depth
    /// along z; z stays z for one along x).
    pub fn depth_along_y(self, axis: usize) -> Volume {
        if axis == 1 || axis > 2 {
            return self;
        }
        let mut size = self.size;
        size.swap(axis, 1);
        let mut voxels = vec![[0u8; 3]; self.voxels.len()];
        for z in 0..self.size[2] {
            for y in 0..self.size[1] {
                for x in 0..self.size[0] {
                    let mut p = [x, y, z];
                    p.swap(axis, 1);
                    voxels[(p[2] * size[1] + p[1]) * size[0] + p[0]] =
                        self.voxels[self.index(x, y, z)];
                }
            }
        }
        Volume {
            size,
            spacing: self.spacing,
            voxels,
        }
    }

    /// Read an NRRD file: the header, then the voxel data after it or in
    /// the detached file its `data file` field names (relative to the
    /// header's folder, as 3D Slicer's .nhdr files have it).
    pub fn read_nrrd(path: &Path) -> Result<Volume> {
        Volume::read_nrrd_with_depth(path).map(|(v, _)| v)
    }

    /// `read_nrrd`, with the depth axis its header names (`DEPTH_AXIS_KEY`).
    pub fn read_nrrd_with_depth(path: &Path) -> Result<(Volume, Option<usize>)> {
        if path.is_dir() {
            return Err(Error::format(path, "is a directory, not an NRRD file"));
        }
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        let mut reader = BufReader::new(file);
        let bad = |msg: String| Error::format(path, msg);
        let (text, consumed, blank) = read_header(&mut reader).map_err(bad)?;
        let header = parse_header(&text).map_err(bad)?;
        let voxels = match &header.data_file {
            Some(name) => {
                let dir = path.parent().unwrap_or(Path::new("."));
                let data_path = dir.join(name);
                let in_data = |msg: String| {
                    Error::format(path, format!("data file {}: {msg}", data_path.display()))
                };
                let data = File::open(&data_path)
                    .map_err(|e| in_data(format!("cannot be opened: {e}")))?;
                let len = data
                    .metadata()
                    .map_err(|e| in_data(format!("cannot be read: {e}")))?
                    .len();
                read_data(&header, BufReader::new(data), len).map_err(in_data)?
            }
            None if !blank => return Err(bad(NO_BLANK_LINE.into())),
            None => read_data(&header, reader, len.saturating_sub(consumed)).map_err(bad)?,
        };
        Ok((header.volume(voxels), header.depth_axis))
    }

    /// Parse an NRRD held in memory (its data attached): what `to_nrrd`
    /// writes, and the same layout from other tools (3D Slicer, ITK, teem):
    /// uint8 RGB, raw or gzip encoding, header fields in any order.
    pub fn from_nrrd(bytes: &[u8]) -> std::result::Result<Volume, String> {
        let mut reader = bytes;
        let (text, _, blank) = read_header(&mut reader)?;
        let header = parse_header(&text)?;
        if let Some(name) = &header.data_file {
            return Err(format!(
                "the voxel data is in the detached file '{name}': read the header from its file"
            ));
        }
        if !blank {
            return Err(NO_BLANK_LINE.into());
        }
        let voxels = read_data(&header, reader, reader.len() as u64)?;
        Ok(header.volume(voxels))
    }
}

/// The NRRD key (`key:=value`) naming a layered exemplar's depth axis:
/// x, y or z, the outer layer at index 0.
pub const DEPTH_AXIS_KEY: &str = "organtex_depth_axis";

const NO_BLANK_LINE: &str = "the NRRD header does not end in a blank line";

/// The longest header read: real ones are a few hundred bytes, and a file
/// without a newline must not be read whole looking for one.
const MAX_HEADER: u64 = 1 << 20;

/// The header's text up to the blank line that ends it (or the end of the
/// input, for a detached header), the bytes consumed, and whether the blank
/// line was there.
fn read_header(r: &mut impl BufRead) -> std::result::Result<(String, u64, bool), String> {
    let mut bytes = Vec::new();
    let mut consumed = 0u64;
    let mut limited = r.take(MAX_HEADER);
    loop {
        let start = bytes.len();
        let n = limited
            .read_until(b'\n', &mut bytes)
            .map_err(|e| format!("cannot read the header: {e}"))?;
        consumed += n as u64;
        if start == 0 && !bytes.starts_with(b"NRRD000") {
            return Err("not an NRRD file (no NRRD000x magic line)".into());
        }
        let line = &bytes[start..];
        if n == 0 || !line.ends_with(b"\n") {
            if consumed >= MAX_HEADER {
                return Err(format!(
                    "the header is longer than {MAX_HEADER} bytes: not an NRRD file"
                ));
            }
            let text = String::from_utf8(bytes).map_err(|_| "the NRRD header is not text")?;
            return Ok((text, consumed, false));
        }
        if line == b"\n" || line == b"\r\n" {
            bytes.truncate(start);
            let text = String::from_utf8(bytes).map_err(|_| "the NRRD header is not text")?;
            return Ok((text, consumed, true));
        }
    }
}

/// What an NRRD header says about an RGB uint8 volume and its data.
struct Header {
    size: [usize; 3],
    depth_axis: Option<usize>,
    spacing: f64,
    gzip: bool,
    /// The detached data file, relative to the header's folder.
    data_file: Option<String>,
    line_skip: u64,
    /// Bytes skipped before the data (after decompression for gzip); -1:
    /// the data is the last bytes of the file (raw only).
    byte_skip: i64,
}

impl Header {
    fn volume(&self, data: Vec<u8>) -> Volume {
        Volume {
            size: self.size,
            spacing: self.spacing,
            voxels: data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        }
    }

    /// Bytes of voxel data the sizes need (at most 3 x 4096^3: no overflow).
    fn data_len(&self) -> u64 {
        3 * self.size.iter().map(|&s| s as u64).product::<u64>()
    }
}

/// Check the header's fields: every field organtex needs, in range, and
/// none it cannot honour.
fn parse_header(header: &str) -> std::result::Result<Header, String> {
    let mut sizes: Option<Vec<usize>> = None;
    let mut spacing = None;
    let mut direction_spacing = None;
    let (mut typ, mut encoding, mut dimension) = (None, None, None);
    let mut data_file = None;
    let mut depth_axis = None;
    let (mut line_skip, mut byte_skip) = (0u64, 0i64);
    for (n, line) in header.lines().enumerate().skip(1) {
        let line = line.trim_end_matches('\r');
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let at = |msg: String| format!("header line {}: {msg}", n + 1);
        let Some((key, value)) = line.split_once(':') else {
            return Err(at(format!("'{line}' is not 'field: value'")));
        };
        // Key/value pairs (`key:=value`) carry no layout; one names a
        // layered exemplar's depth axis.
        if let Some(v) = value.strip_prefix('=') {
            if key == DEPTH_AXIS_KEY {
                depth_axis = Some(
                    ["x", "y", "z"]
                        .iter()
                        .position(|a| *a == v.trim())
                        .ok_or_else(|| {
                            at(format!("{DEPTH_AXIS_KEY} is '{}': x, y or z", v.trim()))
                        })?,
                );
            }
            continue;
        }
        let value = value.trim();
        match key.trim() {
            "type" => typ = Some(value.to_string()),
            "encoding" => encoding = Some(value.to_string()),
            "dimension" => {
                dimension = Some(
                    value
                        .parse::<usize>()
                        .map_err(|_| at(format!("dimension '{value}' is not a whole number")))?,
                )
            }
            "sizes" => {
                sizes = Some(
                    value
                        .split_whitespace()
                        .map(|s| s.parse::<usize>())
                        .collect::<std::result::Result<_, _>>()
                        .map_err(|_| at(format!("bad sizes '{value}': expected whole numbers")))?,
                )
            }
            "spacings" => {
                spacing = value
                    .split_whitespace()
                    .filter_map(|s| s.parse::<f64>().ok())
                    .find(|s| s.is_finite() && *s > 0.0)
            }
            "space directions" => {
                direction_spacing = first_direction_length(value).map_err(at)?;
            }
            "endian" if value != "little" && value != "big" => {
                return Err(at(format!("endian '{value}' is not 'little' or 'big'")));
            }
            "data file" | "datafile" => {
                let mut words = value.split_whitespace();
                let multiple = value == "LIST"
                    || (words.next().is_some_and(|w| w.contains('%')) && words.next().is_some());
                if multiple {
                    return Err(at(format!(
                        "data file '{value}' names several files; organtex reads one"
                    )));
                }
                if value.is_empty() {
                    return Err(at("data file: no file named".into()));
                }
                data_file = Some(value.to_string());
            }
            "line skip" | "lineskip" => {
                line_skip = value
                    .parse()
                    .map_err(|_| at(format!("line skip '{value}' is not a count of lines")))?
            }
            "byte skip" | "byteskip" => {
                byte_skip = value
                    .parse()
                    .ok()
                    .filter(|&b: &i64| b >= -1)
                    .ok_or_else(|| at(format!("byte skip '{value}' is not -1 or a count")))?
            }
            // space, space dimension, space origin, kinds, content, ...:
            // nothing organtex places a block by.
            _ => {}
        }
    }
    match typ.as_deref() {
        Some("uint8" | "uchar" | "unsigned char" | "uint8_t") => {}
        Some(t) => return Err(format!("type '{t}' is not supported; uint8 is")),
        None => return Err("the header has no type field".into()),
    }
    let gzip = match encoding.as_deref() {
        Some("raw") => false,
        Some("gzip" | "gz") => true,
        Some(e) => return Err(format!("encoding '{e}' is not supported; raw and gzip are")),
        None => return Err("the header has no encoding field".into()),
    };
    let sizes = sizes.ok_or("the header has no sizes field")?;
    let dimension = dimension.ok_or("the header has no dimension field")?;
    if dimension != 4 || sizes.len() != 4 || sizes[0] != 3 {
        return Err(format!(
            "expected an RGB volume (dimension 4, sizes 3 X Y Z), found dimension {dimension}, sizes {sizes:?}"
        ));
    }
    let size = [sizes[1], sizes[2], sizes[3]];
    if size.contains(&0) || size.iter().any(|&s| s > 4096) {
        return Err(format!("block size {size:?} is outside 1..4096 a side"));
    }
    if byte_skip == -1 && gzip {
        return Err("byte skip -1 (data at the end of the file) is for raw data only".into());
    }
    Ok(Header {
        size,
        depth_axis,
        spacing: spacing.or(direction_spacing).unwrap_or(1.0),
        gzip,
        data_file,
        line_skip,
        byte_skip,
    })
}

/// The length of the first vector of `space directions` (`none` for the
/// colour axis, then one `(x,y,z)` per voxel axis): the voxel's edge, as
/// `spacings` gives it (the first axis's, like `spacings`).
fn first_direction_length(value: &str) -> std::result::Result<Option<f64>, String> {
    let mut first = None;
    for word in value.split_whitespace() {
        if word == "none" {
            continue;
        }
        let parts: Option<Vec<f64>> = word
            .strip_prefix('(')
            .and_then(|w| w.strip_suffix(')'))
            .map(|w| w.split(',').map(|c| c.trim().parse::<f64>().ok()).collect())
            .and_then(|v: Option<Vec<f64>>| v);
        let v = parts
            .filter(|v| !v.is_empty() && v.iter().all(|c| c.is_finite()))
            .ok_or_else(|| {
                format!("space directions: '{word}' is not 'none' or a vector like (0.5,0,0)")
            })?;
        let length = v.iter().map(|c| c * c).sum::<f64>().sqrt();
        if first.is_none() && length.is_finite() && length > 0.0 {
            first = Some(length);
        }
    }
    Ok(first)
}

/// The voxel data from `r`, which holds `left` bytes: line and byte skips,
/// then exactly the bytes the sizes need, decompressed when gzip (never
/// more: a gzip stream that would expand further is cut off and refused).
fn read_data(h: &Header, mut r: impl BufRead, left: u64) -> std::result::Result<Vec<u8>, String> {
    let expected = h.data_len();
    let [x, y, z] = h.size;
    // The data and the voxels made from it.
    crate::memory::check(&format!("a {x}x{y}x{z} volume"), 2 * expected)?;
    let mut left = left;
    for line in 0..h.line_skip {
        let n = r
            .skip_until(b'\n')
            .map_err(|e| format!("cannot read the data: {e}"))?;
        if n == 0 {
            return Err(format!(
                "line skip {}: the data ends after {line} lines",
                h.line_skip
            ));
        }
        left = left.saturating_sub(n as u64);
    }
    let skip = |r: &mut dyn Read, n: u64| -> std::result::Result<(), String> {
        let skipped = std::io::copy(&mut r.take(n), &mut std::io::sink())
            .map_err(|e| format!("cannot read the data: {e}"))?;
        if skipped < n {
            return Err(format!("byte skip {n}: the data has only {skipped} bytes"));
        }
        Ok(())
    };
    let expected_usize = usize::try_from(expected).map_err(|_| "the volume is too large")?;
    let mut data = Vec::new();
    if h.gzip {
        let mut decoder = flate2::bufread::MultiGzDecoder::new(r);
        skip(&mut decoder, h.byte_skip.max(0) as u64)?;
        data.reserve_exact(expected_usize);
        decoder
            .take(expected + 1)
            .read_to_end(&mut data)
            .map_err(|e| format!("the gzip data cannot be decompressed: {e}"))?;
        if data.len() as u64 > expected {
            return Err(format!(
                "the gzip data holds more than the {expected} bytes of voxel data sizes {:?} need",
                h.size
            ));
        }
        if data.len() as u64 != expected {
            return Err(format!(
                "the gzip data holds {} bytes of voxel data where sizes {:?} need {expected}",
                data.len(),
                h.size
            ));
        }
    } else {
        let skipped = if h.byte_skip == -1 {
            left.saturating_sub(expected)
        } else {
            h.byte_skip as u64
        };
        skip(&mut r, skipped)?;
        left = left.saturating_sub(skipped);
        if left != expected {
            return Err(format!(
                "{left} bytes of voxel data where sizes {:?} need {expected}",
                h.size
            ));
        }
        data.reserve_exact(expected_usize);
        r.take(expected)
            .read_to_end(&mut data)
            .map_err(|e| format!("cannot read the data: {e}"))?;
        if data.len() != expected_usize {
            return Err(format!(
                "the data ends after {} of its {expected} bytes",
                data.len()
            ));
        }
    }
    Ok(data)
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

    fn gzip(bytes: &[u8]) -> Vec<u8> {
        use std::io::Write;
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        e.write_all(bytes).unwrap();
        e.finish().unwrap()
    }

    /// What 3D Slicer writes for an RGB volume by default: gzip, endian,
    /// space and space directions instead of spacings.
    fn slicer_header(v: &Volume, encoding: &str, extra: &str) -> String {
        let [x, y, z] = v.size;
        format!(
            "NRRD0004\n# Complete NRRD file format specification at:\n\
             type: unsigned char\ndimension: 4\nspace: left-posterior-superior\n\
             sizes: 3 {x} {y} {z}\n\
             space directions: none (0.5,0,0) (0,0.5,0) (0,0,0.5)\n\
             kinds: RGB-color domain domain domain\nendian: little\n\
             encoding: {encoding}\nspace origin: (0,0,0)\n{extra}"
        )
    }

    #[test]
    fn a_gzip_nrrd_round_trips() {
        let v = ramp();
        let raw: Vec<u8> = v.voxels.iter().flatten().copied().collect();
        let mut bytes = slicer_header(&v, "gzip", "\n").into_bytes();
        bytes.extend(gzip(&raw));
        assert_eq!(Volume::from_nrrd(&bytes).unwrap(), v);

        // A stream that expands beyond the sizes is cut off and refused.
        let mut long = slicer_header(&v, "gzip", "\n").into_bytes();
        long.extend(gzip(&vec![7u8; 1 << 20]));
        let err = Volume::from_nrrd(&long).unwrap_err();
        assert!(err.contains("holds more than the 72 bytes"), "{err}");
        let mut short = slicer_header(&v, "gz", "\n").into_bytes();
        short.extend(gzip(&raw[..70]));
        let err = Volume::from_nrrd(&short).unwrap_err();
        assert!(err.contains("holds 70 bytes of voxel data where sizes [4, 3, 2] need 72"));
        let mut corrupt = slicer_header(&v, "gzip", "\n").into_bytes();
        corrupt.extend(b"not gzip at all");
        let err = Volume::from_nrrd(&corrupt).unwrap_err();
        assert!(err.contains("cannot be decompressed"), "{err}");
    }

    #[test]
    fn a_detached_nrrd_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let v = ramp();
        let raw: Vec<u8> = v.voxels.iter().flatten().copied().collect();
        std::fs::create_dir(dir.path().join("data")).unwrap();
        std::fs::write(dir.path().join("data/block.raw.gz"), gzip(&raw)).unwrap();
        let header = dir.path().join("block.nhdr");
        std::fs::write(
            &header,
            slicer_header(&v, "gzip", "data file: data/block.raw.gz\n"),
        )
        .unwrap();
        assert_eq!(Volume::read_nrrd(&header).unwrap(), v);

        // Raw, with a line and byte skip before the data.
        let mut skipped = b"a preamble line\nxy".to_vec();
        skipped.extend(&raw);
        std::fs::write(dir.path().join("block.raw"), &skipped).unwrap();
        let text = slicer_header(
            &v,
            "raw",
            "datafile: block.raw\nline skip: 1\nbyte skip: 2\n",
        );
        std::fs::write(&header, &text).unwrap();
        assert_eq!(Volume::read_nrrd(&header).unwrap(), v);
        std::fs::write(&header, text.replace("byte skip: 2", "byte skip: -1")).unwrap();
        assert_eq!(Volume::read_nrrd(&header).unwrap(), v);

        std::fs::remove_file(dir.path().join("block.raw")).unwrap();
        let err = Volume::read_nrrd(&header).unwrap_err().to_string();
        assert!(err.contains("block.raw: cannot be opened"), "{err}");
        assert!(Volume::from_nrrd(text.as_bytes()).is_err());
    }

    #[test]
    fn header_fields_are_checked() {
        let v = ramp();
        let refused = |extra: &str, expect: &str| {
            let mut bytes = slicer_header(&v, "raw", extra).into_bytes();
            bytes.extend(b"\n");
            bytes.extend(v.voxels.iter().flatten());
            let err = Volume::from_nrrd(&bytes).unwrap_err();
            assert!(err.contains(expect), "{extra}: {err}");
        };
        refused(
            "endian: middle\n",
            "endian 'middle' is not 'little' or 'big'",
        );
        refused("data file: LIST\n", "names several files");
        refused("data file: s%03d.raw 1 4 1\n", "names several files");
        refused("byte skip: -2\n", "byte skip '-2' is not -1 or a count");
        refused("line skip: 3\n", "the data ends after");
        refused("byte skip: 1000\n", "byte skip 1000: the data has only");
        let text = slicer_header(&v, "raw", "\n").replace("(0,0.5,0)", "(0,x,0)");
        assert!(
            Volume::from_nrrd(text.as_bytes())
                .unwrap_err()
                .contains("space directions")
        );
        // A direction too long to measure is skipped for the next one.
        let mut bytes = slicer_header(&v, "raw", "\n")
            .replace("(0.5,0,0)", "(1e200,0,0)")
            .into_bytes();
        bytes.extend(v.voxels.iter().flatten());
        let read = Volume::from_nrrd(&bytes).unwrap();
        assert_eq!(read.spacing, 0.5);
        assert_eq!(Volume::from_nrrd(&read.to_nrrd()).unwrap(), read);
        let text = slicer_header(&v, "bzip2", "\n");
        let err = Volume::from_nrrd(text.as_bytes()).unwrap_err();
        assert!(err.contains("encoding 'bzip2' is not supported; raw and gzip are"));
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
