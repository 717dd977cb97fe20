//! Stanford PLY, ascii and binary (little and big endian): the `vertex`
//! element's x, y, z and the `face` element's index list (fan-triangulated);
//! every other element and property is read past.
//!
//! Our own reader: ply-rs is unmaintained and allocates whatever the header
//! claims, so a header claiming 10^12 vertices would abort the process. Here
//! every count is checked against the bytes actually present before anything
//! is allocated, and errors name the element and line or byte.

use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::mesh::TriMesh;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(Scalar, String),
    List(Scalar, Scalar, String),
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar(_, n) | Property::List(_, _, n) => n,
        }
    }
    /// The fewest bytes one value can take (an empty list for lists).
    fn min_size(&self, encoding: Encoding) -> usize {
        match (encoding, self) {
            (Encoding::Ascii, _) => 2, // one digit and a separator
            (_, Property::Scalar(s, _)) | (_, Property::List(s, _, _)) => s.size(),
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// Line number of the first data line (ascii).
    data_line: usize,
}

pub fn parse(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let header = parse_header(path, bytes)?;
    let data = &bytes[header.data_start..];
    let mut available = data.len() as u64;
    for el in &header.elements {
        let min: u64 = el
            .properties
            .iter()
            .map(|p| p.min_size(header.encoding) as u64)
            .sum::<u64>()
            .max(1);
        let need = el.count.saturating_mul(min);
        if need > available {
            return Err(Error::format(
                path,
                format!(
                    "the header declares {} {} elements, which need at least {} bytes, but only {} bytes of data follow the header (is the file truncated?)",
                    el.count, el.name, need, available
                ),
            ));
        }
        available -= need;
    }

    let mut reader = match header.encoding {
        Encoding::Ascii => Values::Ascii(AsciiValues::new(data, header.data_line)),
        e => Values::Binary(BinaryValues {
            data,
            pos: 0,
            big_endian: e == Encoding::BigEndian,
            offset: header.data_start,
        }),
    };

    let mut positions: Vec<DVec3> = Vec::new();
    let mut polygons: Vec<(u64, Vec<i64>)> = Vec::new();
    for el in &header.elements {
        let xyz: Option<[usize; 3]> = ["x", "y", "z"]
            .iter()
            .map(|n| el.properties.iter().position(|p| p.name() == *n))
            .collect::<Option<Vec<_>>>()
            .map(|v| [v[0], v[1], v[2]]);
        let indices = el.properties.iter().position(|p| {
            matches!(p, Property::List(..)) && matches!(p.name(), "vertex_indices" | "vertex_index")
        });
        if el.name == "vertex" && xyz.is_none() {
            return Err(Error::format(
                path,
                "the vertex element has no x, y and z properties",
            ));
        }
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        if is_face && indices.is_none() {
            return Err(Error::format(
                path,
                "the face element has no vertex_indices list",
            ));
        }
        if is_vertex {
            positions.reserve(el.count as usize);
        }
        let mut values: Vec<f64> = Vec::new();
        for i in 0..el.count {
            let what = || format!("{} {i}", el.name);
            reader
                .start_record()
                .map_err(|m| reader.error(path, &what(), m))?;
            let mut xyz_vals = [0.0f64; 3];
            for (k, prop) in el.properties.iter().enumerate() {
                match prop {
                    Property::Scalar(s, _) => {
                        let x = reader
                            .scalar(*s)
                            .map_err(|m| reader.error(path, &what(), m))?;
                        if let Some(slot) = xyz.and_then(|c| c.iter().position(|&j| j == k)) {
                            xyz_vals[slot] = x;
                        }
                    }
                    Property::List(count_ty, item_ty, _) => {
                        let n = reader
                            .scalar(*count_ty)
                            .map_err(|m| reader.error(path, &what(), m))?;
                        if !(0.0..=1e6).contains(&n) || n.fract() != 0.0 {
                            return Err(reader.error(
                                path,
                                &what(),
                                format!("list length {n} is invalid"),
                            ));
                        }
                        values.clear();
                        for _ in 0..n as usize {
                            values.push(
                                reader
                                    .scalar(*item_ty)
                                    .map_err(|m| reader.error(path, &what(), m))?,
                            );
                        }
                        if is_face && Some(k) == indices {
                            if values.len() < 3 {
                                return Err(reader.error(
                                    path,
                                    &what(),
                                    format!(
                                        "a face needs at least 3 vertices, this one has {}",
                                        values.len()
                                    ),
                                ));
                            }
                            polygons.push((i, values.iter().map(|&x| x as i64).collect()));
                        }
                    }
                }
            }
            reader
                .end_record()
                .map_err(|m| reader.error(path, &what(), m))?;
            if is_vertex {
                if let Some(axis) = xyz_vals.iter().position(|x| !x.is_finite()) {
                    return Err(reader.error(
                        path,
                        &what(),
                        format!("coordinate {} is {}", ["x", "y", "z"][axis], xyz_vals[axis]),
                    ));
                }
                positions.push(DVec3::from_array(xyz_vals));
            }
        }
    }

    let mut triangles = Vec::with_capacity(polygons.len());
    for (face, poly) in &polygons {
        if let Some(&bad) = poly
            .iter()
            .find(|&&v| v < 0 || v as usize >= positions.len())
        {
            return Err(Error::at_element(
                path,
                format!("face {face}"),
                format!(
                    "vertex index {bad} is out of range (the file has {} vertices)",
                    positions.len()
                ),
            ));
        }
        for k in 1..poly.len() - 1 {
            triangles.push([poly[0] as u32, poly[k] as u32, poly[k + 1] as u32]);
        }
    }
    Ok(TriMesh::new(positions, triangles))
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    if !bytes.starts_with(b"ply") || !matches!(bytes.get(3), Some(b'\n' | b'\r')) {
        return Err(Error::format(
            path,
            "not a PLY file: it does not start with the line 'ply'",
        ));
    }
    // A header is a few hundred bytes; refuse to scan megabytes of junk.
    const MAX_HEADER: usize = 1 << 16;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    loop {
        let rest = &bytes[pos..];
        let Some(len) = rest.iter().position(|&b| b == b'\n') else {
            return Err(Error::format(
                path,
                "the header has no end_header line (is the file truncated?)",
            ));
        };
        line_no += 1;
        let line = String::from_utf8_lossy(&rest[..len]);
        pos += len + 1;
        if pos > MAX_HEADER {
            return Err(Error::format(path, "no end_header within the first 64 KiB"));
        }
        let err = |msg: String| Error::at_line(path, line_no, msg);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line_no == 1 => {}
            ["format", f, version] => {
                if !version.starts_with('1') {
                    return Err(err(format!("unsupported PLY version {version}")));
                }
                encoding = Some(match *f {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    other => return Err(err(format!("unknown PLY format '{other}'"))),
                });
            }
            ["comment", ..] | ["obj_info", ..] => {}
            ["element", name, count] => {
                let count: u64 = count.parse().map_err(|_| {
                    err(format!(
                        "element count '{count}' is not a non-negative integer"
                    ))
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count_ty, item_ty, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err("property before any element".into()))?;
                let c = Scalar::parse(count_ty)
                    .ok_or_else(|| err(format!("unknown type '{count_ty}'")))?;
                let i = Scalar::parse(item_ty)
                    .ok_or_else(|| err(format!("unknown type '{item_ty}'")))?;
                el.properties.push(Property::List(c, i, name.to_string()));
            }
            ["property", ty, name] => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err("property before any element".into()))?;
                let s = Scalar::parse(ty).ok_or_else(|| err(format!("unknown type '{ty}'")))?;
                el.properties.push(Property::Scalar(s, name.to_string()));
            }
            ["end_header"] => break,
            [] => {}
            _ => return Err(err(format!("unexpected header line '{}'", line.trim()))),
        }
    }
    let encoding = encoding.ok_or_else(|| Error::format(path, "the header has no format line"))?;
    Ok(Header {
        encoding,
        elements,
        data_start: pos,
        data_line: line_no + 1,
    })
}

/// The data section, read one value at a time in either encoding.
enum Values<'a> {
    Ascii(AsciiValues<'a>),
    Binary(BinaryValues<'a>),
}

struct AsciiValues<'a> {
    /// The data section not read yet.
    rest: &'a [u8],
    /// Line number of the record being read.
    line_no: usize,
    words: Vec<&'a str>,
    next_word: usize,
}

struct BinaryValues<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
    /// Offset of `data` in the file, for error messages.
    offset: usize,
}

impl<'a> AsciiValues<'a> {
    fn new(data: &'a [u8], first_line: usize) -> Self {
        AsciiValues {
            rest: data,
            line_no: first_line - 1,
            words: Vec::new(),
            next_word: 0,
        }
    }
}

impl Values<'_> {
    /// Ascii records are one per line; skip blank lines.
    fn start_record(&mut self) -> std::result::Result<(), String> {
        if let Values::Ascii(a) = self {
            loop {
                if a.rest.is_empty() {
                    return Err("unexpected end of file (is the file truncated?)".into());
                }
                let len = a
                    .rest
                    .iter()
                    .position(|&b| b == b'\n')
                    .unwrap_or(a.rest.len());
                let line = &a.rest[..len];
                a.rest = &a.rest[(len + 1).min(a.rest.len())..];
                a.line_no += 1;
                let line =
                    std::str::from_utf8(line).map_err(|_| "the line is not text".to_string())?;
                a.words = line.split_ascii_whitespace().collect();
                a.next_word = 0;
                if !a.words.is_empty() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    fn end_record(&mut self) -> std::result::Result<(), String> {
        match self {
            Values::Ascii(a) if a.next_word < a.words.len() => Err(format!(
                "{} values more than the header's properties",
                a.words.len() - a.next_word
            )),
            _ => Ok(()),
        }
    }

    fn scalar(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        match self {
            Values::Ascii(a) => {
                let w = a
                    .words
                    .get(a.next_word)
                    .ok_or_else(|| "fewer values than the header's properties".to_string())?;
                a.next_word += 1;
                if matches!(ty, Scalar::F32 | Scalar::F64) {
                    w.parse().map_err(|_| format!("'{w}' is not a number"))
                } else {
                    w.parse::<i64>()
                        .map(|i| i as f64)
                        .map_err(|_| format!("'{w}' is not an integer"))
                }
            }
            Values::Binary(b) => {
                let n = ty.size();
                let bytes = b
                    .data
                    .get(b.pos..b.pos + n)
                    .ok_or_else(|| "unexpected end of file (is the file truncated?)".to_string())?;
                b.pos += n;
                let mut buf = [0u8; 8];
                buf[..n].copy_from_slice(bytes);
                if b.big_endian {
                    buf[..n].reverse();
                }
                Ok(match ty {
                    Scalar::I8 => buf[0] as i8 as f64,
                    Scalar::U8 => buf[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([buf[0], buf[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([buf[0], buf[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(buf),
                })
            }
        }
    }

    fn error(&self, path: &Path, element: &str, msg: String) -> Error {
        match self {
            Values::Ascii(a) => Error::at_line(path, a.line_no, format!("{element}: {msg}")),
            Values::Binary(b) => {
                Error::at_element(path, format!("{element} (byte {})", b.offset + b.pos), msg)
            }
        }
    }
}

/// Write `mesh` as binary little-endian PLY (vertices as float, faces as
/// uchar-counted int lists), atomically.
pub fn write(path: &Path, mesh: &TriMesh) -> Result<()> {
    crate::atomic::write_file(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment written by organtex\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar int vertex_indices\nend_header\n",
            mesh.num_vertices(),
            mesh.num_faces()
        )?;
        for p in &mesh.positions {
            for c in p.to_array() {
                w.write_all(&(c as f32).to_le_bytes())?;
            }
        }
        for t in &mesh.triangles {
            w.write_all(&[3])?;
            for v in t {
                w.write_all(&(*v as i32).to_le_bytes())?;
            }
        }
        Ok(())
    })
}
