//! STL, ascii and binary. STL stores every triangle's corners by value, so
//! corners with bit-identical coordinates are welded into one vertex. In an
//! ascii file each `solid` becomes a facet.
//!
//! Our own reader (stl_io would do the parsing) because the format has no
//! real magic number: deciding ascii or binary needs the size check below,
//! and a user handed a wrong file needs to hear which test failed and why.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::mesh::{Facets, TriMesh};

const HEADER: usize = 80;
const RECORD: usize = 50;

pub fn parse(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let declared = bytes
        .get(HEADER..HEADER + 4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64);
    if declared.map(|n| (HEADER + 4) as u64 + n * RECORD as u64) == Some(bytes.len() as u64) {
        return parse_binary(path, bytes);
    }
    let looks_ascii = bytes.trim_ascii_start().starts_with(b"solid");
    let size_mismatch = |n: u64| {
        Error::format(
            path,
            format!(
                "not a valid STL file: read as binary STL its header declares {n} triangles, which take {} bytes, but the file has {} bytes; {}",
                (HEADER + 4) as u64 + n * RECORD as u64,
                bytes.len(),
                if looks_ascii {
                    "and it holds binary data, so it is not ascii STL"
                } else {
                    "and it does not start with 'solid', so it is not ascii STL"
                }
            ),
        )
    };
    match (looks_ascii, declared) {
        // Some binary files start their free-form header with "solid" too;
        // text never holds NUL bytes.
        (true, Some(n)) if bytes.contains(&0) => Err(size_mismatch(n)),
        (true, _) => parse_ascii(path, bytes),
        (false, Some(n)) => Err(size_mismatch(n)),
        (false, None) => Err(Error::format(
            path,
            format!(
                "not an STL file: it does not start with 'solid' (ascii STL) and at {} bytes it is shorter than the 84-byte header of a binary STL",
                bytes.len()
            ),
        )),
    }
}

/// Welds corners by exact coordinates.
#[derive(Default)]
struct Welder {
    index: HashMap<[u64; 3], u32>,
    positions: Vec<DVec3>,
}

impl Welder {
    fn vertex(&mut self, p: DVec3) -> u32 {
        // +0.0 and -0.0 are the same point.
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        *self.index.entry(key).or_insert_with(|| {
            self.positions.push(p);
            (self.positions.len() - 1) as u32
        })
    }
}

fn parse_binary(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut welder = Welder::default();
    let mut triangles = Vec::new();
    for (t, rec) in bytes[HEADER + 4..].chunks_exact(RECORD).enumerate() {
        let f = |i: usize| {
            f32::from_le_bytes([rec[4 * i], rec[4 * i + 1], rec[4 * i + 2], rec[4 * i + 3]]) as f64
        };
        let mut tri = [0u32; 3];
        for (c, slot) in tri.iter_mut().enumerate() {
            // Floats 0..3 are the facet normal, which we recompute.
            let p = DVec3::new(f(3 + 3 * c), f(4 + 3 * c), f(5 + 3 * c));
            if !p.is_finite() {
                return Err(Error::at_element(
                    path,
                    format!("triangle {t}"),
                    format!(
                        "corner {c} has a non-finite coordinate ({}, {}, {})",
                        p.x, p.y, p.z
                    ),
                ));
            }
            *slot = welder.vertex(p);
        }
        triangles.push(tri);
    }
    Ok(TriMesh::new(welder.positions, triangles))
}

fn parse_ascii(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut welder = Welder::default();
    let mut triangles = Vec::new();
    let mut facet_names: Vec<String> = Vec::new();
    let mut of_face = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    #[derive(PartialEq, Debug)]
    enum State {
        Outside,
        InSolid,
        InFacet,
        InLoop,
        LoopDone,
    }
    let mut state = State::Outside;
    let mut last_line = 0;
    for (n, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = n + 1;
        last_line = line_no;
        let err = |msg: String| Error::at_line(path, line_no, msg);
        let line = String::from_utf8_lossy(raw);
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let expected = |what: &str| err(format!("expected {what}, found '{keyword}'"));
        state = match (state, keyword) {
            (State::Outside, "solid") => {
                facet_names.push(words.collect::<Vec<_>>().join(" "));
                State::InSolid
            }
            (State::InSolid, "facet") => State::InFacet,
            (State::InSolid, "endsolid") => State::Outside,
            (State::InFacet, "outer") => {
                corners.clear();
                State::InLoop
            }
            (State::InLoop, "vertex") => {
                let mut xyz = [0.0f64; 3];
                for (i, slot) in xyz.iter_mut().enumerate() {
                    let w = words
                        .next()
                        .ok_or_else(|| err(format!("a vertex needs 3 coordinates, found {i}")))?;
                    *slot = w
                        .parse()
                        .map_err(|_| err(format!("coordinate '{w}' is not a number")))?;
                    if !slot.is_finite() {
                        return Err(err(format!("coordinate '{w}' is not a finite number")));
                    }
                }
                corners.push(welder.vertex(DVec3::from_array(xyz)));
                State::InLoop
            }
            (State::InLoop, "endloop") => {
                if corners.len() != 3 {
                    return Err(err(format!(
                        "a facet needs exactly 3 vertices, this one has {}",
                        corners.len()
                    )));
                }
                triangles.push([corners[0], corners[1], corners[2]]);
                of_face.push((facet_names.len() - 1) as u32);
                State::LoopDone
            }
            (State::LoopDone, "endfacet") => State::InSolid,
            (State::Outside, _) => return Err(expected("'solid'")),
            (State::InSolid, _) => return Err(expected("'facet' or 'endsolid'")),
            (State::InFacet, _) => return Err(expected("'outer loop'")),
            (State::InLoop, _) => return Err(expected("'vertex' or 'endloop'")),
            (State::LoopDone, _) => return Err(expected("'endfacet'")),
        };
    }
    if state != State::Outside {
        return Err(Error::at_line(
            path,
            last_line,
            "the file ends inside a solid (no 'endsolid'; is the file truncated?)",
        ));
    }
    let mut mesh = TriMesh::new(welder.positions, triangles);
    if facet_names.len() > 1 || facet_names.iter().any(|n| !n.is_empty()) {
        for (i, name) in facet_names.iter_mut().enumerate() {
            if name.is_empty() {
                *name = format!("solid{i}");
            }
        }
        mesh.facets = Some(Facets {
            names: facet_names,
            of_face,
        });
    }
    Ok(mesh)
}

/// Write `mesh` as binary STL (each face's normal and corners as float),
/// atomically.
pub fn write(path: &Path, mesh: &TriMesh) -> Result<()> {
    crate::atomic::write_file(path, |w| {
        let mut header = [b' '; HEADER];
        header[..20].copy_from_slice(b"written by organtex ");
        w.write_all(&header)?;
        w.write_all(&(mesh.num_faces() as u32).to_le_bytes())?;
        for f in 0..mesh.num_faces() {
            let n = mesh.face_normal(f);
            let corners = mesh.corners(f);
            for v in std::iter::once(n).chain(corners) {
                for c in v.to_array() {
                    w.write_all(&(c as f32).to_le_bytes())?;
                }
            }
            w.write_all(&[0, 0])?;
        }
        Ok(())
    })
}
