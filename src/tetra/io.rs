//! Tet mesh files the simulators' tools read: legacy VTK unstructured grids
//! (SOFA, 3D Slicer, ParaView; written and read), gmsh `.msh` 4.1 ASCII and
//! Medit `.mesh` (written). All writes are atomic (`crate::atomic`).
//!
//! Coordinates are written with Rust's shortest round-trip formatting, so
//! reading a written `.vtk` back gives the same mesh bit for bit.

use std::path::Path;

use glam::DVec3;

use super::mesh::{Attribute, TetMesh};
use crate::atomic::write_file;
use crate::error::{Error, Result};

/// The extensions `write` understands.
pub const WRITABLE: &[&str] = &["vtk", "msh", "mesh"];

/// VTK's cell type for a linear tetrahedron.
const VTK_TETRA: u32 = 10;

/// Write `mesh` in the format its extension names (`.vtk`, `.msh`,
/// `.mesh`).
pub fn write(path: &Path, mesh: &TetMesh) -> Result<()> {
    writer(path)?(path, mesh)
}

/// The writer for `path`'s extension, or an error naming the formats:
/// callers check it before long work.
pub fn writer(path: &Path) -> Result<fn(&Path, &TetMesh) -> Result<()>> {
    match crate::error::extension(path).as_str() {
        "vtk" => Ok(write_vtk),
        "msh" => Ok(write_msh),
        "mesh" => Ok(write_medit),
        _ => Err(Error::unknown_format(path, "tet mesh", "writes", WRITABLE)),
    }
}

/// Legacy VTK, ASCII, an unstructured grid of tetrahedra (cell type 10).
pub fn write_vtk(path: &Path, mesh: &TetMesh) -> Result<()> {
    write_file(path, |w| {
        writeln!(w, "# vtk DataFile Version 3.0")?;
        writeln!(w, "organtex tetrahedral mesh")?;
        writeln!(w, "ASCII")?;
        writeln!(w, "DATASET UNSTRUCTURED_GRID")?;
        writeln!(w, "POINTS {} double", mesh.positions.len())?;
        for p in &mesh.positions {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
        writeln!(w, "CELLS {} {}", mesh.tets.len(), 5 * mesh.tets.len())?;
        for [a, b, c, d] in &mesh.tets {
            writeln!(w, "4 {a} {b} {c} {d}")?;
        }
        writeln!(w, "CELL_TYPES {}", mesh.tets.len())?;
        for _ in &mesh.tets {
            writeln!(w, "{VTK_TETRA}")?;
        }
        for (section, count, attributes) in [
            ("POINT_DATA", mesh.positions.len(), &mesh.vertex_attributes),
            ("CELL_DATA", mesh.tets.len(), &mesh.tet_attributes),
        ] {
            if attributes.is_empty() {
                continue;
            }
            // FIELD arrays: any number of components, read by VTK, ParaView
            // and meshio alike.
            writeln!(
                w,
                "{section} {count}\nFIELD attributes {}",
                attributes.len()
            )?;
            for a in attributes {
                writeln!(w, "{} {} {count} double", a.name, a.components)?;
                for element in a.values.chunks(a.components) {
                    let row: Vec<String> = element.iter().map(f64::to_string).collect();
                    writeln!(w, "{}", row.join(" "))?;
                }
            }
        }
        Ok(())
    })
}

/// gmsh 4.1 ASCII: one volume entity holding every node and tet (element
/// type 4); tags are 1-based.
pub fn write_msh(path: &Path, mesh: &TetMesh) -> Result<()> {
    let (lo, hi) = bounds(&mesh.positions);
    let (n, m) = (mesh.positions.len(), mesh.tets.len());
    write_file(path, |w| {
        writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
        // numPoints numCurves numSurfaces numVolumes; the volume: tag, box,
        // no physical tags, no bounding surfaces.
        writeln!(w, "$Entities\n0 0 0 1")?;
        writeln!(
            w,
            "1 {} {} {} {} {} {} 0 0",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        )?;
        writeln!(w, "$EndEntities")?;
        writeln!(w, "$Nodes\n1 {n} 1 {n}\n3 1 0 {n}")?;
        for tag in 1..=n {
            writeln!(w, "{tag}")?;
        }
        for p in &mesh.positions {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
        writeln!(w, "$EndNodes")?;
        writeln!(w, "$Elements\n1 {m} 1 {m}\n3 1 4 {m}")?;
        for (t, [a, b, c, d]) in mesh.tets.iter().enumerate() {
            writeln!(w, "{} {} {} {} {}", t + 1, a + 1, b + 1, c + 1, d + 1)?;
        }
        writeln!(w, "$EndElements")?;
        // gmsh views take 1, 3 or 9 components; other attributes are left
        // out of .msh files (`.vtk` holds any).
        for (section, attributes) in [
            ("NodeData", &mesh.vertex_attributes),
            ("ElementData", &mesh.tet_attributes),
        ] {
            for a in attributes
                .iter()
                .filter(|a| [1, 3, 9].contains(&a.components))
            {
                let count = a.values.len() / a.components;
                writeln!(
                    w,
                    "${section}\n1\n\"{}\"\n1\n0\n3\n0\n{}\n{count}",
                    a.name, a.components
                )?;
                for (i, element) in a.values.chunks(a.components).enumerate() {
                    let row: Vec<String> = element.iter().map(f64::to_string).collect();
                    writeln!(w, "{} {}", i + 1, row.join(" "))?;
                }
                writeln!(w, "$End{section}")?;
            }
        }
        Ok(())
    })
}

/// Medit (INRIA) `.mesh`, double precision: vertices, the boundary
/// triangles and the tets, 1-based, every reference 0 (the format has no
/// place for attributes).
pub fn write_medit(path: &Path, mesh: &TetMesh) -> Result<()> {
    let boundary = mesh.boundary_triangles();
    write_file(path, |w| {
        writeln!(w, "MeshVersionFormatted 2\nDimension 3")?;
        writeln!(w, "Vertices\n{}", mesh.positions.len())?;
        for p in &mesh.positions {
            writeln!(w, "{} {} {} 0", p.x, p.y, p.z)?;
        }
        writeln!(w, "Triangles\n{}", boundary.len())?;
        for [a, b, c] in &boundary {
            writeln!(w, "{} {} {} 0", a + 1, b + 1, c + 1)?;
        }
        writeln!(w, "Tetrahedra\n{}", mesh.tets.len())?;
        for [a, b, c, d] in &mesh.tets {
            writeln!(w, "{} {} {} {} 0", a + 1, b + 1, c + 1, d + 1)?;
        }
        writeln!(w, "End")?;
        Ok(())
    })
}

fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    match points.first() {
        None => (DVec3::ZERO, DVec3::ZERO),
        Some(&f) => points
            .iter()
            .fold((f, f), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    }
}

/// Read a legacy VTK unstructured grid of tetrahedra (ASCII; the classic
/// CELLS layout and VTK 5's OFFSETS/CONNECTIVITY alike). Point and cell
/// data in FIELD, SCALARS and VECTORS arrays become the mesh's attributes;
/// reading stops at any other kind of data.
pub fn read_vtk(path: &Path) -> Result<TetMesh> {
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not a VTK file"));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_vtk(path, &bytes)
}

/// Parse VTK text; `path` names the file in errors.
pub fn parse_vtk(path: &Path, bytes: &[u8]) -> Result<TetMesh> {
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let line = 1 + bytes[..e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            return Err(Error::at_line(
                path,
                line,
                "not text (binary VTK is not read; write the file as ASCII)",
            ));
        }
    };
    let mut r = Tokens::new(path, text);
    let (_, header) = r
        .line()
        .ok_or_else(|| Error::format(path, "the file is empty"))?;
    if !header.trim_start().starts_with("# vtk DataFile") {
        return Err(Error::at_line(
            path,
            1,
            format!(
                "not a legacy VTK file: expected '# vtk DataFile Version ...', found '{}'",
                clip(header)
            ),
        ));
    }
    r.line().ok_or_else(|| r.eof("the title line"))?;
    let (n, encoding) = r.line().ok_or_else(|| r.eof("ASCII or BINARY"))?;
    match encoding.trim().to_ascii_uppercase().as_str() {
        "ASCII" => {}
        "BINARY" => {
            return Err(Error::at_line(
                path,
                n,
                "binary VTK is not read; write the file as ASCII",
            ));
        }
        other => {
            return Err(Error::at_line(
                path,
                n,
                format!("expected ASCII or BINARY, found '{}'", clip(other)),
            ));
        }
    }
    let (n, word) = r.token("DATASET")?;
    if !word.eq_ignore_ascii_case("DATASET") {
        return Err(Error::at_line(
            path,
            n,
            format!("expected DATASET, found '{}'", clip(word)),
        ));
    }
    let (n, kind) = r.token("the dataset type")?;
    if !kind.eq_ignore_ascii_case("UNSTRUCTURED_GRID") {
        return Err(Error::at_line(
            path,
            n,
            format!(
                "dataset {} is not read: only UNSTRUCTURED_GRID holds tetrahedra",
                clip(kind)
            ),
        ));
    }

    let mut positions: Option<Vec<DVec3>> = None;
    // Each cell's corners and the line it starts on.
    let mut cells: Option<Vec<(usize, Vec<u64>)>> = None;
    let mut types: Option<(usize, Vec<(usize, u64)>)> = None;
    // (the section's line and element count, its arrays).
    type Data = (Option<(usize, usize)>, Vec<Attribute>);
    let (mut vertex_data, mut tet_data): (Data, Data) = Default::default();
    while let Some((n, word)) = r.next() {
        match word.to_ascii_uppercase().as_str() {
            "POINTS" => {
                let count: usize = r.number("the point count")?;
                r.token("the point type")?;
                let mut p = Vec::with_capacity(count.min(1 << 24));
                for i in 0..count {
                    let mut c = [0.0; 3];
                    for x in &mut c {
                        let (line, v): (usize, f64) = r.number_at("a point coordinate")?;
                        if !v.is_finite() {
                            return Err(Error::at_line(
                                path,
                                line,
                                format!("point {i} has a non-finite coordinate"),
                            ));
                        }
                        *x = v;
                    }
                    p.push(DVec3::from_array(c));
                }
                positions = Some(p);
            }
            "CELLS" => {
                let count: usize = r.number("the cell count")?;
                let size: usize = r.number("the cell list size")?;
                let mut list = Vec::with_capacity(count.min(1 << 24));
                if r.peek().is_some_and(|w| w.eq_ignore_ascii_case("OFFSETS")) {
                    // VTK 5: `count` offsets, then `size` connectivity entries.
                    r.next();
                    r.token("the offsets' type")?;
                    let mut offsets = Vec::with_capacity(count.min(1 << 24));
                    for _ in 0..count {
                        offsets.push(r.number_at::<u64>("an offset")?);
                    }
                    let (n, word) = r.token("CONNECTIVITY")?;
                    if !word.eq_ignore_ascii_case("CONNECTIVITY") {
                        return Err(Error::at_line(
                            path,
                            n,
                            format!("expected CONNECTIVITY, found '{}'", clip(word)),
                        ));
                    }
                    r.token("the connectivity's type")?;
                    let mut conn = Vec::with_capacity(size.min(1 << 26));
                    for _ in 0..size {
                        conn.push(r.number_at::<u64>("a point index")?);
                    }
                    for pair in offsets.windows(2) {
                        let (line, a) = pair[0];
                        let b = pair[1].1;
                        if a > b || b as usize > conn.len() {
                            return Err(Error::at_line(
                                path,
                                line,
                                format!(
                                    "offsets {a} and {b} do not fit {} connectivity entries",
                                    conn.len()
                                ),
                            ));
                        }
                        list.push((
                            line,
                            conn[a as usize..b as usize].iter().map(|x| x.1).collect(),
                        ));
                    }
                } else {
                    let mut read = 0;
                    for _ in 0..count {
                        let (line, k): (usize, usize) = r.number_at("a cell's point count")?;
                        let mut corners = Vec::with_capacity(k.min(64));
                        for _ in 0..k {
                            corners.push(r.number_at::<u64>("a point index")?.1);
                        }
                        read += k + 1;
                        list.push((line, corners));
                    }
                    if read != size {
                        return Err(Error::at_line(
                            path,
                            n,
                            format!(
                                "CELLS says its list holds {size} numbers, the cells hold {read}"
                            ),
                        ));
                    }
                }
                cells = Some(list);
            }
            "CELL_TYPES" => {
                let count: usize = r.number("the cell type count")?;
                let mut t = Vec::with_capacity(count.min(1 << 24));
                for _ in 0..count {
                    t.push(r.number_at::<u64>("a cell type")?);
                }
                types = Some((n, t));
            }
            "POINT_DATA" | "CELL_DATA" => {
                let count: usize = r.number("the data's element count")?;
                let into = if word.eq_ignore_ascii_case("POINT_DATA") {
                    &mut vertex_data
                } else {
                    &mut tet_data
                };
                into.0 = Some((n, count));
                if !read_arrays(&mut r, count, &mut into.1)? {
                    break;
                }
            }
            "FIELD" | "METADATA" => break,
            _ => {
                return Err(Error::at_line(
                    path,
                    n,
                    format!(
                        "unexpected '{}' (expected POINTS, CELLS, CELL_TYPES or data)",
                        clip(word)
                    ),
                ));
            }
        }
    }
    let positions = positions.ok_or_else(|| Error::format(path, "no POINTS section"))?;
    let cells = cells.ok_or_else(|| Error::format(path, "no CELLS section"))?;
    let (types_line, types) = types.ok_or_else(|| Error::format(path, "no CELL_TYPES section"))?;
    if types.len() != cells.len() {
        return Err(Error::at_line(
            path,
            types_line,
            format!("{} cell types for {} cells", types.len(), cells.len()),
        ));
    }
    let mut tets = Vec::with_capacity(cells.len());
    for (i, ((line, corners), (type_line, kind))) in cells.into_iter().zip(types).enumerate() {
        if kind != VTK_TETRA as u64 {
            return Err(Error::at_line(
                path,
                type_line,
                format!("cell {i} has VTK type {kind}; only tetrahedra (type 10) are read"),
            ));
        }
        if corners.len() != 4 {
            return Err(Error::at_line(
                path,
                line,
                format!("cell {i} has {} points, a tetrahedron 4", corners.len()),
            ));
        }
        let mut tet = [0u32; 4];
        for (slot, &v) in tet.iter_mut().zip(&corners) {
            if v >= positions.len() as u64 {
                return Err(Error::at_line(
                    path,
                    line,
                    format!(
                        "cell {i} refers to point {v}, the file has {}",
                        positions.len()
                    ),
                ));
            }
            *slot = v as u32;
        }
        tets.push(tet);
    }
    for (section, elements, what) in [
        (vertex_data.0, positions.len(), "points"),
        (tet_data.0, tets.len(), "cells"),
    ] {
        if let Some((line, count)) = section.filter(|s| s.1 != elements) {
            return Err(Error::at_line(
                path,
                line,
                format!("data for {count} {what}, the file has {elements}"),
            ));
        }
    }
    Ok(TetMesh {
        positions,
        tets,
        vertex_attributes: vertex_data.1,
        tet_attributes: tet_data.1,
    })
}

/// Read the arrays of a POINT_DATA or CELL_DATA section of `count`
/// elements into `out`: FIELD arrays, SCALARS (with their lookup table
/// line) and VECTORS. Returns false at anything else (the reading stops
/// there, keeping what was read).
fn read_arrays(r: &mut Tokens, count: usize, out: &mut Vec<Attribute>) -> Result<bool> {
    let values = |r: &mut Tokens, name: &str, components: usize| -> Result<Attribute> {
        let n = components.saturating_mul(count);
        let mut v = Vec::with_capacity(n.min(1 << 26));
        for _ in 0..n {
            v.push(r.number_at::<f64>("an attribute value")?.1);
        }
        Ok(Attribute {
            name: name.into(),
            components,
            values: v,
        })
    };
    loop {
        let Some(word) = r.peek() else {
            return Ok(true);
        };
        match word.to_ascii_uppercase().as_str() {
            "FIELD" => {
                r.next();
                r.token("the field's name")?;
                let arrays: usize = r.number("the field's array count")?;
                for _ in 0..arrays {
                    let name = r.token("an array's name")?.1.to_string();
                    let components: usize = r.number("an array's component count")?;
                    let (line, tuples): (usize, usize) = r.number_at("an array's tuple count")?;
                    if tuples != count {
                        return Err(Error::at_line(
                            r.path,
                            line,
                            format!("array {name} has {tuples} tuples, the section {count}"),
                        ));
                    }
                    r.token("an array's type")?;
                    out.push(values(r, &name, components)?);
                }
            }
            "SCALARS" => {
                r.next();
                let name = r.token("the scalars' name")?.1.to_string();
                r.token("the scalars' type")?;
                let mut components = 1;
                if let Some(c) = r.peek().and_then(|w| w.parse::<usize>().ok()) {
                    components = c;
                    r.next();
                }
                if r.peek()
                    .is_some_and(|w| w.eq_ignore_ascii_case("LOOKUP_TABLE"))
                {
                    r.next();
                    r.token("the lookup table's name")?;
                }
                out.push(values(r, &name, components)?);
            }
            "VECTORS" => {
                r.next();
                let name = r.token("the vectors' name")?.1.to_string();
                r.token("the vectors' type")?;
                out.push(values(r, &name, 3)?);
            }
            "POINT_DATA" | "CELL_DATA" => return Ok(true),
            _ => return Ok(false),
        }
    }
}

/// The first 40 characters of a token, for messages.
fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

/// Whitespace-separated tokens with their 1-based line numbers.
struct Tokens<'a> {
    path: &'a Path,
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    words: Option<(usize, std::str::SplitWhitespace<'a>)>,
    peeked: Option<(usize, &'a str)>,
    last: usize,
}

impl<'a> Tokens<'a> {
    fn new(path: &'a Path, text: &'a str) -> Self {
        Tokens {
            path,
            lines: text.lines().enumerate(),
            words: None,
            peeked: None,
            last: 0,
        }
    }

    /// A whole line (the header's lines are free text).
    fn line(&mut self) -> Option<(usize, &'a str)> {
        let (i, l) = self.lines.next()?;
        self.last = i + 1;
        Some((i + 1, l))
    }

    fn next(&mut self) -> Option<(usize, &'a str)> {
        if let Some(t) = self.peeked.take() {
            return Some(t);
        }
        loop {
            if let Some((n, words)) = &mut self.words
                && let Some(w) = words.next()
            {
                return Some((*n, w));
            }
            let (n, l) = self.line()?;
            self.words = Some((n, l.split_whitespace()));
        }
    }

    fn peek(&mut self) -> Option<&'a str> {
        if self.peeked.is_none() {
            self.peeked = self.next();
        }
        self.peeked.map(|p| p.1)
    }

    fn eof(&self, what: &str) -> Error {
        Error::at_line(
            self.path,
            self.last.max(1),
            format!("the file ends where {what} was expected"),
        )
    }

    fn token(&mut self, what: &str) -> Result<(usize, &'a str)> {
        self.next().ok_or_else(|| self.eof(what))
    }

    fn number_at<T: std::str::FromStr>(&mut self, what: &str) -> Result<(usize, T)> {
        let (n, w) = self.token(what)?;
        w.parse().map(|v| (n, v)).map_err(|_| {
            Error::at_line(
                self.path,
                n,
                format!("expected {what}, found '{}'", clip(w)),
            )
        })
    }

    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T> {
        self.number_at(what).map(|x| x.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> TetMesh {
        TetMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(0.1, 0.0, 0.0),
                DVec3::new(0.0, 1.0 / 3.0, 0.0),
                DVec3::new(0.0, 0.0, 1e-17),
                DVec3::new(1.0, 1.0, 1.0),
            ],
            tets: vec![[0, 1, 2, 3], [1, 4, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn vtk_round_trips_bit_for_bit() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("m.vtk");
        let mut m = small();
        write(&path, &m).expect("write");
        assert_eq!(read_vtk(&path).expect("read"), m);
        // With attributes: a scalar and a vector per vertex, one per tet.
        m.set_vertex_attribute("depth", 1, vec![0.0, 0.25, 1.0 / 3.0, 1e-300, 1.0])
            .expect("depth");
        m.set_vertex_attribute("fibre", 3, (0..15).map(|i| i as f64 / 7.0).collect())
            .expect("fibre");
        m.set_tet_attribute("region", 1, vec![1.0, 2.0])
            .expect("region");
        write(&path, &m).expect("write");
        assert_eq!(read_vtk(&path).expect("read"), m);
    }

    #[test]
    fn attributes_are_checked_and_scalars_read() {
        let mut m = small();
        let e = m
            .set_vertex_attribute("depth", 1, vec![0.0; 4])
            .unwrap_err();
        assert!(e.to_string().contains("4 values, 5 vertices"), "{e}");
        let e = m
            .set_tet_attribute("two words", 1, vec![0.0; 2])
            .unwrap_err();
        assert!(e.to_string().contains("attribute name"), "{e}");
        let text = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n\
                    POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\n\
                    CELL_TYPES 1\n10\nCELL_DATA 1\nSCALARS q float\nLOOKUP_TABLE default\n0.5\n\
                    POINT_DATA 4\nVECTORS v double\n0 0 1 0 1 0 1 0 0 1 1 1\nNORMALS n double\n";
        let m = parse_vtk(Path::new("a.vtk"), text.as_bytes()).expect("parse");
        assert_eq!(
            m.tet_attribute("q").map(|a| a.values.clone()),
            Some(vec![0.5])
        );
        assert_eq!(
            m.vertex_attribute("v").map(|a| a.get(3).to_vec()),
            Some(vec![1.0; 3])
        );
        let short = text.replace("POINT_DATA 4", "POINT_DATA 3");
        let e = parse_vtk(Path::new("a.vtk"), short.as_bytes()).unwrap_err();
        assert!(
            e.to_string().contains("data for 3 points, the file has 4"),
            "{e}"
        );
    }

    #[test]
    fn vtk5_offsets_are_read() {
        let text = "# vtk DataFile Version 5.1\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n\
                    POINTS 4 float\n0 0 0 1 0 0\n0 1 0 0 0 1\nCELLS 2 4\nOFFSETS vtktypeint64\n0 4\n\
                    CONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\n";
        let m = parse_vtk(Path::new("a.vtk"), text.as_bytes()).expect("parse");
        assert_eq!(m.tets, vec![[0, 1, 2, 3]]);
    }

    #[test]
    fn malformed_vtk_names_file_and_line() {
        let good = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n\
                    POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
        assert!(parse_vtk(Path::new("a.vtk"), good.as_bytes()).is_ok());
        let cases = [
            (
                good.replace("0 1 0\n", "0 x 0\n"),
                "line 8",
                "expected a point coordinate",
            ),
            (
                good.replace("4 0 1 2 3", "4 0 1 2 9"),
                "line 11",
                "refers to point 9",
            ),
            (
                good.replace("CELL_TYPES 1\n10", "CELL_TYPES 1\n12"),
                "line 13",
                "VTK type 12",
            ),
            (
                good.replace("CELLS 1 5\n4 0 1 2 3", "CELLS 1 4\n3 0 1 2"),
                "line 11",
                "3 points",
            ),
            (good.replace("ASCII", "BINARY"), "line 3", "binary"),
            (
                good.replace("UNSTRUCTURED_GRID", "POLYDATA"),
                "line 4",
                "POLYDATA",
            ),
            (good[..good.len() - 3].to_string(), "line 12", "ends where"),
        ];
        for (text, line, what) in cases {
            let e = parse_vtk(Path::new("bad.vtk"), text.as_bytes())
                .expect_err(what)
                .to_string();
            assert!(
                e.contains("bad.vtk") && e.contains(line) && e.contains(what),
                "{e}"
            );
        }
    }

    #[test]
    fn msh_and_medit_hold_every_element() {
        let dir = tempfile::tempdir().expect("tempdir");
        let m = small();
        write(&dir.path().join("m.msh"), &m).expect("msh");
        write(&dir.path().join("m.mesh"), &m).expect("mesh");
        let msh = std::fs::read_to_string(dir.path().join("m.msh")).expect("read");
        assert!(msh.starts_with("$MeshFormat\n4.1 0 8\n"));
        assert!(msh.contains("$Elements\n1 2 1 2\n3 1 4 2\n1 1 2 3 4\n2 2 5 3 4\n$EndElements"));
        let medit = std::fs::read_to_string(dir.path().join("m.mesh")).expect("read");
        assert!(medit.contains("Tetrahedra\n2\n1 2 3 4 0\n2 5 3 4 0\nEnd"));
        assert!(medit.contains("Triangles\n6\n"));
        let e = write(&dir.path().join("m.obj"), &m)
            .expect_err("obj")
            .to_string();
        assert!(e.contains(".vtk, .msh, .mesh"), "{e}");
    }
}
