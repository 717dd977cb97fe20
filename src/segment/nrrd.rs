//! NRRD label maps (`.nrrd`, `.nhdr` with its data file, and 3D Slicer's
//! `.seg.nrrd`): one scalar per voxel, placed in the world by the header's
//! `space directions` and `space origin`. A Slicer segmentation names its
//! segments in key/value pairs (`Segment0_Name:=liver`,
//! `Segment0_LabelValue:=1`, `Segment0_Layer:=0`); where segments overlap
//! Slicer stores several layers along a first `list` axis (4D).
//!
//! Written here rather than taken from a crate: the `nrrd` crates on
//! crates.io read neither Slicer's segment fields nor detached headers,
//! and `synth::volume`'s reader is for RGB solid textures.
//!
//! The world is RAS, as Slicer shows coordinates and as NIfTI stores them:
//! a file in `left-posterior-superior` space has its x and y negated.

use std::io::Read;
use std::path::Path;

use glam::{DAffine3, DMat3, DVec3};

use super::ScalarVolume;
use super::nifti::Datatype;
use crate::error::{Error, Result};

/// A named region of a Slicer segmentation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Segment {
    pub name: String,
    /// Its voxels' value in its layer.
    pub label: i64,
    pub layer: usize,
}

/// A label map: one volume per layer (one for a plain label map) and the
/// segments the header names (none for a plain label map).
#[derive(Clone, Debug, PartialEq)]
pub struct LabelMap {
    pub layers: Vec<ScalarVolume>,
    pub segments: Vec<Segment>,
}

/// The longest header read (real ones, Slicer's with dozens of segments
/// included, are a few kilobytes).
const MAX_HEADER: usize = 1 << 20;

/// Read a NRRD label map; errors name the file.
pub fn read(path: &Path) -> Result<LabelMap> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not an NRRD file"));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    parse(&bytes, Some(dir)).map_err(|msg| Error::format(path, msg))
}

/// Parse a NRRD held in memory. A detached data file is read from `dir`
/// (none: refused).
pub fn parse(bytes: &[u8], dir: Option<&Path>) -> std::result::Result<LabelMap, String> {
    if !bytes.starts_with(b"NRRD000") {
        return Err("not an NRRD file (no NRRD000x magic line)".into());
    }
    // The header ends at the first blank line (a detached header may end
    // with the file).
    let mut end = bytes.len();
    let mut data_start = bytes.len();
    let mut line_start = 0;
    for (i, &b) in bytes.iter().enumerate().take(MAX_HEADER) {
        if b == b'\n' {
            let line = &bytes[line_start..i];
            if line.is_empty() || line == b"\r" {
                end = line_start;
                data_start = i + 1;
                break;
            }
            line_start = i + 1;
        }
    }
    if end == bytes.len() && bytes.len() > MAX_HEADER {
        return Err(format!(
            "no blank line ends the header within {MAX_HEADER} bytes: not an NRRD file"
        ));
    }
    let text = std::str::from_utf8(&bytes[..end]).map_err(|_| "the NRRD header is not text")?;
    let header = Header::parse(text)?;
    let raw = match &header.data_file {
        Some(name) => {
            let Some(dir) = dir else {
                return Err(format!(
                    "the voxel data is in the detached file '{name}': read the header from its file"
                ));
            };
            let path = dir.join(name);
            std::fs::read(&path)
                .map_err(|e| format!("data file {}: cannot be read: {e}", path.display()))?
        }
        None if data_start == bytes.len() && end == bytes.len() => {
            return Err("the header does not end in a blank line, and names no data file".into());
        }
        None => bytes[data_start..].to_vec(),
    };
    header.label_map(&raw)
}

struct Header {
    datatype: Datatype,
    little: bool,
    gzip: bool,
    /// Voxels per spatial axis, and layers (1 unless the first axis is a
    /// list).
    size: [usize; 3],
    layers: usize,
    to_world: DAffine3,
    data_file: Option<String>,
    byte_skip: i64,
    line_skip: usize,
    segments: Vec<Segment>,
}

impl Header {
    fn parse(text: &str) -> std::result::Result<Header, String> {
        let mut datatype = None;
        let mut dimension = None;
        let mut sizes: Option<Vec<usize>> = None;
        let mut little = true;
        let mut endian_given = false;
        let mut encoding = None;
        let mut directions: Option<Vec<Option<DVec3>>> = None;
        let mut spacings: Option<Vec<f64>> = None;
        let mut origin = DVec3::ZERO;
        let mut lps = false;
        let mut data_file = None;
        let (mut byte_skip, mut line_skip) = (0i64, 0usize);
        // Segment fields by index: name, label value, layer.
        let mut fields: Vec<(usize, &str, &str)> = Vec::new();
        for (n, line) in text.lines().enumerate().skip(1) {
            let line = line.trim_end_matches('\r');
            if line.starts_with('#') || line.trim().is_empty() {
                continue;
            }
            let at = |msg: String| format!("header line {}: {msg}", n + 1);
            if let Some((key, value)) = line.split_once(":=") {
                if let Some(rest) = key.strip_prefix("Segment")
                    && let Some((index, field)) = rest.split_once('_')
                    && let Ok(index) = index.parse::<usize>()
                {
                    fields.push((index, field, value));
                }
                continue;
            }
            let Some((key, value)) = line.split_once(':') else {
                return Err(at(format!("'{line}' is not 'field: value'")));
            };
            let value = value.trim();
            let number = |s: &str| -> std::result::Result<f64, String> {
                s.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| at(format!("'{s}' is not a number")))
            };
            // `(x,y,z)`: a direction or the origin.
            let vector = |what: &str, v: &str| -> std::result::Result<DVec3, String> {
                let inner = v
                    .strip_prefix('(')
                    .and_then(|v| v.strip_suffix(')'))
                    .ok_or_else(|| at(format!("{what} '{v}' is not (x,y,z)")))?;
                let c: Vec<f64> = inner
                    .split(',')
                    .map(number)
                    .collect::<std::result::Result<_, _>>()?;
                match c[..] {
                    [x, y, z] => Ok(DVec3::new(x, y, z)),
                    _ => Err(at(format!("{what} '{v}' has not 3 components"))),
                }
            };
            match key.trim() {
                "type" => datatype = Some(scalar_type(value).map_err(at)?),
                "dimension" => {
                    dimension =
                        Some(value.parse::<usize>().map_err(|_| {
                            at(format!("dimension '{value}' is not a whole number"))
                        })?)
                }
                "sizes" => {
                    sizes = Some(
                        value
                            .split_whitespace()
                            .map(|s| {
                                s.parse::<usize>().ok().filter(|&k| k > 0).ok_or_else(|| {
                                    at(format!("size '{s}' is not a positive whole number"))
                                })
                            })
                            .collect::<std::result::Result<_, _>>()?,
                    )
                }
                "endian" => {
                    endian_given = true;
                    little = match value {
                        "little" => true,
                        "big" => false,
                        _ => return Err(at(format!("endian '{value}': little or big"))),
                    }
                }
                "encoding" => encoding = Some(value.to_string()),
                "space" => {
                    lps = match value {
                        "left-posterior-superior" | "LPS" => true,
                        "right-anterior-superior" | "RAS" | "scanner-xyz" | "3D-right-handed" => {
                            false
                        }
                        other => {
                            return Err(at(format!(
                                "space '{other}': organtex places right-anterior-superior, \
                                 left-posterior-superior and scanner-xyz volumes"
                            )));
                        }
                    }
                }
                "space dimension" if value != "3" => {
                    return Err(at(format!("space dimension {value}: a volume needs 3")));
                }
                "space directions" => {
                    directions = Some(
                        vectors(value)
                            .iter()
                            .map(|d| {
                                let d = d.as_str();
                                if d == "none" {
                                    return Ok(None);
                                }
                                vector("direction", d).map(Some)
                            })
                            .collect::<std::result::Result<_, String>>()?,
                    )
                }
                "space origin" => origin = vector("origin", value)?,
                "spacings" => {
                    spacings = Some(
                        value
                            .split_whitespace()
                            .map(|s| if s == "nan" { Ok(f64::NAN) } else { number(s) })
                            .collect::<std::result::Result<_, _>>()?,
                    )
                }
                "data file" | "datafile" => {
                    if value.starts_with("LIST") || value.contains('%') {
                        return Err(at("a data file split over several files is not read".into()));
                    }
                    data_file = Some(value.to_string());
                }
                "byte skip" | "byteskip" => {
                    byte_skip = value
                        .parse::<i64>()
                        .ok()
                        .filter(|&b| b >= -1)
                        .ok_or_else(|| at(format!("byte skip '{value}'")))?
                }
                "line skip" | "lineskip" => {
                    line_skip = value
                        .parse::<usize>()
                        .map_err(|_| at(format!("line skip '{value}'")))?
                }
                _ => {}
            }
        }
        let datatype = datatype.ok_or("the header has no 'type'")?;
        let dimension = dimension.ok_or("the header has no 'dimension'")?;
        let sizes = sizes.ok_or("the header has no 'sizes'")?;
        if sizes.len() != dimension {
            return Err(format!(
                "'sizes' gives {} numbers for dimension {dimension}",
                sizes.len()
            ));
        }
        // A 4D segmentation's first axis lists its layers.
        let (layers, spatial) = match dimension {
            3 => (1, 0),
            4 => (sizes[0], 1),
            d => {
                return Err(format!(
                    "dimension {d}: a label map is 3D (or 4D with its first axis listing layers)"
                ));
            }
        };
        if datatype.bytes() > 1 && !endian_given {
            return Err("the header gives no 'endian' for multi-byte voxels".into());
        }
        let gzip = match encoding.as_deref() {
            Some("raw") => false,
            Some("gzip" | "gz") => true,
            Some(other) => {
                return Err(format!(
                    "encoding '{other}': organtex reads raw and gzip NRRD data"
                ));
            }
            None => return Err("the header has no 'encoding'".into()),
        };
        let size = [sizes[spatial], sizes[spatial + 1], sizes[spatial + 2]];
        let count = size
            .iter()
            .chain([&layers])
            .try_fold(1u64, |n, &k| n.checked_mul(k as u64));
        if count.is_none_or(|n| n > 1 << 32) {
            return Err(format!(
                "{}x{}x{} voxels in {layers} layers: more than organtex reads",
                size[0], size[1], size[2]
            ));
        }
        let axes: [DVec3; 3] = match (&directions, &spacings) {
            (Some(d), _) => {
                if d.len() != dimension {
                    return Err(format!(
                        "'space directions' gives {} axes for dimension {dimension}",
                        d.len()
                    ));
                }
                if dimension == 4 && d[0].is_some() {
                    return Err(
                        "a 4D label map's first axis must list layers ('none' in 'space directions')"
                            .into(),
                    );
                }
                let spatial_axes: Vec<DVec3> = d[spatial..].iter().flatten().copied().collect();
                match spatial_axes[..] {
                    [x, y, z] => [x, y, z],
                    _ => {
                        return Err(
                            "'space directions' gives no direction for a spatial axis".into()
                        );
                    }
                }
            }
            (None, Some(s)) if s.len() == dimension && s[spatial..].iter().all(|v| *v > 0.0) => [
                DVec3::X * s[spatial],
                DVec3::Y * s[spatial + 1],
                DVec3::Z * s[spatial + 2],
            ],
            (None, Some(_)) => {
                return Err("'spacings' must give a positive spacing per spatial axis".into());
            }
            (None, None) => [DVec3::X, DVec3::Y, DVec3::Z],
        };
        let mut matrix = DMat3::from_cols(axes[0], axes[1], axes[2]);
        let det = matrix.determinant();
        let scale = axes.iter().map(|a| a.length()).product::<f64>();
        if !det.is_finite() || det.abs() <= 1e-9 * scale || scale == 0.0 {
            return Err(
                "the space directions are singular (two axes parallel or one of zero length)"
                    .into(),
            );
        }
        if lps {
            // To RAS, as Slicer shows it and as NIfTI stores it.
            let flip = DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0));
            matrix = flip * matrix;
            origin = flip * origin;
        }
        let segments = segments(&fields, layers)?;
        Ok(Header {
            datatype,
            little,
            gzip,
            size,
            layers,
            to_world: DAffine3::from_mat3_translation(matrix, origin),
            data_file,
            byte_skip,
            line_skip,
            segments,
        })
    }

    fn label_map(&self, raw: &[u8]) -> std::result::Result<LabelMap, String> {
        // Line skip counts lines of the data file (before decompression).
        let mut raw = raw;
        for _ in 0..self.line_skip {
            let Some(i) = raw.iter().position(|&b| b == b'\n') else {
                return Err("the line skip passes the end of the data".into());
            };
            raw = &raw[i + 1..];
        }
        let voxels = self.size.iter().product::<usize>();
        let need = voxels * self.layers * self.datatype.bytes();
        let inflated;
        let data: &[u8] = if self.gzip {
            if self.byte_skip == -1 {
                return Err("byte skip -1 (data at the end) cannot be used with gzip".into());
            }
            // Skipped bytes are read and dropped, not held: the skip is the
            // header's word, the data may be far shorter.
            let mut gz = flate2::read::MultiGzDecoder::new(raw);
            let skipped = std::io::copy(
                &mut (&mut gz).take(self.byte_skip as u64),
                &mut std::io::sink(),
            )
            .map_err(|e| format!("the gzip data is damaged: {e}"))?;
            if skipped < self.byte_skip as u64 {
                return Err(format!(
                    "the byte skip {} passes the end of the data",
                    self.byte_skip
                ));
            }
            let mut out = Vec::new();
            gz.take(need as u64)
                .read_to_end(&mut out)
                .map_err(|e| format!("the gzip data is damaged: {e}"))?;
            inflated = out;
            &inflated[..]
        } else if self.byte_skip == -1 {
            &raw[raw.len().saturating_sub(need)..]
        } else {
            raw.get(self.byte_skip as usize..).unwrap_or(&[])
        };
        if data.len() < need {
            return Err(format!(
                "truncated: {} bytes of voxel data where {}x{}x{} voxels{} need {need}",
                data.len(),
                self.size[0],
                self.size[1],
                self.size[2],
                if self.layers > 1 {
                    format!(" in {} layers", self.layers)
                } else {
                    String::new()
                }
            ));
        }
        let values: Vec<f32> = self
            .datatype
            .values(&data[..need], self.little)
            .map(|v| v as f32)
            .collect();
        if values.iter().any(|v| v.is_nan()) {
            return Err("the voxels hold NaN values".into());
        }
        // Layers interleave (the list axis is the fastest): split them.
        let layers = (0..self.layers)
            .map(|l| ScalarVolume {
                size: self.size,
                values: values
                    .iter()
                    .skip(l)
                    .step_by(self.layers)
                    .copied()
                    .collect(),
                to_world: self.to_world,
            })
            .collect();
        Ok(LabelMap {
            layers,
            segments: self.segments.clone(),
        })
    }
}

/// The tokens of a `space directions` value: `none` and `(x,y,z)` vectors,
/// spaces allowed inside the brackets (`(1, 0, 0)`), which are taken out.
fn vectors(value: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = String::new();
    let mut depth = 0;
    for ch in value.chars() {
        match ch {
            '(' => {
                depth += 1;
                current.push(ch);
            }
            ')' => {
                depth -= 1;
                current.push(ch);
            }
            c if c.is_whitespace() && depth == 0 => {
                if !current.is_empty() {
                    out.push(std::mem::take(&mut current));
                }
            }
            c if c.is_whitespace() => {}
            c => current.push(c),
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// NRRD's type names (the spec's synonyms included) as storage types.
fn scalar_type(name: &str) -> std::result::Result<Datatype, String> {
    use Datatype::*;
    Ok(match name {
        "signed char" | "int8" | "int8_t" => I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => I16,
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => U16,
        "int" | "signed int" | "int32" | "int32_t" => I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => U32,
        "float" => F32,
        "double" => F64,
        other => {
            return Err(format!(
                "type '{other}' is not one organtex reads (8, 16 or 32-bit integers, float, double)"
            ));
        }
    })
}

/// The segments from their `SegmentN_*` fields: a name for each, its label
/// value (1 where none is given) and layer (0 in a 3D map).
fn segments(
    fields: &[(usize, &str, &str)],
    layers: usize,
) -> std::result::Result<Vec<Segment>, String> {
    // Grouped by index: only the indices named (a header may say
    // Segment4000000000_Name), each group searched alone.
    let mut sorted = fields.to_vec();
    sorted.sort_by_key(|f| f.0);
    let mut out = Vec::new();
    for group in sorted.chunk_by(|x, y| x.0 == y.0) {
        let i = group[0].0;
        let field = |name: &str| group.iter().find(|f| f.1 == name).map(|f| f.2.trim());
        let Some(name) = field("Name") else { continue };
        let label = match field("LabelValue") {
            Some(v) => v
                .parse::<i64>()
                .map_err(|_| format!("Segment{i}_LabelValue '{v}' is not a whole number"))?,
            None => 1,
        };
        let layer = match field("Layer") {
            Some(v) => v
                .parse::<usize>()
                .ok()
                .filter(|&l| l < layers)
                .ok_or_else(|| format!("Segment{i}_Layer '{v}': the map has {layers} layer(s)"))?,
            None => 0,
        };
        out.push(Segment {
            name: name.to_string(),
            label,
            layer,
        });
    }
    Ok(out)
}

/// A NRRD of `layers` (one 3D map, or several interleaved along a first
/// list axis), gzip-encoded, in RAS or LPS space, with the segments' fields:
/// what Slicer writes, for tests and the fuzzer's corpus.
pub fn to_bytes(layers: &[ScalarVolume], segments: &[Segment], lps: bool) -> Vec<u8> {
    use std::io::Write;
    let v = &layers[0];
    let flip = if lps {
        DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0))
    } else {
        DMat3::IDENTITY
    };
    let m = flip * v.to_world.matrix3;
    let o = flip * v.to_world.translation;
    let axis = |c: DVec3| format!("({},{},{})", c.x, c.y, c.z);
    let four = layers.len() > 1;
    let mut h = String::from(
        "NRRD0004\n# Complete NRRD file format specification at:\n# http://teem.sourceforge.net/nrrd/format.html\ntype: short\n",
    );
    h += &format!("dimension: {}\n", if four { 4 } else { 3 });
    h += &format!(
        "space: {}\n",
        if lps {
            "left-posterior-superior"
        } else {
            "right-anterior-superior"
        }
    );
    let sizes = format!("{} {} {}", v.size[0], v.size[1], v.size[2]);
    h += &if four {
        format!("sizes: {} {sizes}\n", layers.len())
    } else {
        format!("sizes: {sizes}\n")
    };
    h += &format!(
        "space directions: {}{} {} {}\n",
        if four { "none " } else { "" },
        axis(m.x_axis),
        axis(m.y_axis),
        axis(m.z_axis)
    );
    h += &format!(
        "kinds: {}domain domain domain\n",
        if four { "list " } else { "" }
    );
    h += "endian: little\nencoding: gzip\n";
    h += &format!("space origin: {}\n", axis(o));
    for (i, s) in segments.iter().enumerate() {
        h += &format!(
            "Segment{i}_Name:={}\nSegment{i}_LabelValue:={}\nSegment{i}_Layer:={}\n",
            s.name, s.label, s.layer
        );
    }
    h += "\n";
    let mut raw = Vec::new();
    for k in 0..v.values.len() {
        for l in layers {
            raw.extend_from_slice(&(l.values[k] as i16).to_le_bytes());
        }
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&raw).expect("in memory");
    let mut out = h.into_bytes();
    out.extend(gz.finish().expect("in memory"));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels() -> ScalarVolume {
        let size = [4, 3, 2];
        ScalarVolume {
            size,
            values: (0..24).map(|i| (i % 3) as f32).collect(),
            to_world: DAffine3::from_mat3_translation(
                DMat3::from_cols(
                    DVec3::new(0.0, 0.8, 0.0),
                    DVec3::new(-1.2, 0.0, 0.0),
                    DVec3::new(0.0, 0.0, 2.0),
                ),
                DVec3::new(10.0, -20.0, 30.0),
            ),
        }
    }

    #[test]
    fn a_written_segmentation_reads_back_in_ras_either_space() {
        let v = labels();
        let segs = vec![
            Segment {
                name: "liver".into(),
                label: 1,
                layer: 0,
            },
            Segment {
                name: "tumour core".into(),
                label: 2,
                layer: 0,
            },
        ];
        for lps in [false, true] {
            let map = parse(&to_bytes(std::slice::from_ref(&v), &segs, lps), None).unwrap();
            assert_eq!(map.segments, segs);
            assert_eq!(map.layers.len(), 1);
            let got = &map.layers[0];
            assert_eq!(got.values, v.values);
            assert!(
                got.to_world.abs_diff_eq(v.to_world, 1e-12),
                "{:?}",
                got.to_world
            );
        }
        // Two layers interleave along the list axis.
        let mut other = v.clone();
        other.values.iter_mut().for_each(|x| *x = 5.0 - *x);
        let map = parse(&to_bytes(&[v.clone(), other.clone()], &segs, true), None).unwrap();
        assert_eq!(map.layers.len(), 2);
        assert_eq!(map.layers[0].values, v.values);
        assert_eq!(map.layers[1].values, other.values);
    }

    #[test]
    fn spaced_vectors_and_far_segment_numbers_read() {
        let v = labels();
        let bytes = to_bytes(std::slice::from_ref(&v), &[], false);
        let at = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
        let header = String::from_utf8(bytes[..at].to_vec())
            .unwrap()
            .replace("(0,0,2)", "( 0, 0, 2 )")
            + "\nSegment4000000000_Name:=far\nSegment4000000000_LabelValue:=2\n";
        let mut edited = header.into_bytes();
        edited.extend_from_slice(&bytes[at + 1..]);
        let map = parse(&edited, None).unwrap();
        assert!(map.layers[0].to_world.abs_diff_eq(v.to_world, 1e-12));
        assert_eq!(
            map.segments,
            [Segment {
                name: "far".into(),
                label: 2,
                layer: 0
            }]
        );
    }

    #[test]
    fn bad_headers_are_refused_with_the_reason() {
        let v = labels();
        let good = String::from_utf8_lossy(&to_bytes(std::slice::from_ref(&v), &[], false))
            .split("\n\n")
            .next()
            .unwrap()
            .to_string();
        let with = |from: &str, to: &str| {
            let mut b = good.replace(from, to).into_bytes();
            b.extend_from_slice(b"\n\n");
            b
        };
        for (bytes, why) in [
            (b"P3\n".to_vec(), "magic"),
            (with("type: short", "type: block"), "type 'block'"),
            (with("dimension: 3", "dimension: 2"), "'sizes' gives 3"),
            (with("encoding: gzip", "encoding: bzip2"), "bzip2"),
            (with("(0,0,2)", "(0,0.8,0)"), "singular"),
            (with("encoding: gzip", "encoding: raw"), "truncated"),
            (with("endian: little\n", ""), "endian"),
            (
                with(
                    "sizes: 4 3 2",
                    "sizes: 4000000000000 4000000000000 4000000000000",
                ),
                "more than organtex reads",
            ),
            (
                with("encoding: gzip\n", "encoding: gzip\nbyte skip: -1\n"),
                "byte skip -1",
            ),
        ] {
            let err = parse(&bytes, None).unwrap_err();
            assert!(err.contains(why), "{why}: {err}");
        }
    }
}
