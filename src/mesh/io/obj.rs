//! Wavefront OBJ: `v`, `vt`, `f` (any polygon, fan-triangulated; `v`,
//! `v/vt`, `v//vn`, `v/vt/vn`, negative indices), `g`/`o` and `usemtl`
//! (each distinct group/material pair becomes a facet), `mtllib` on output.
//!
//! Our own reader rather than tobj's, for four reasons that matter here:
//! tobj splits the file into one mesh per group/material and renumbers each,
//! so the vertices facets share along their borders become copies (welding
//! them back by position would also merge distinct coincident vertices);
//! its errors carry no line number; it drops unreferenced vertices, which
//! `info` must report; and out-of-range negative indices overflow its index
//! arithmetic. This reader keeps the file's vertex numbering exactly.

use std::collections::HashMap;
use std::path::Path;

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::mesh::{Facets, TriMesh, UvLayer};

pub fn parse(path: &Path, bytes: &[u8]) -> Result<TriMesh> {
    let mut positions: Vec<DVec3> = Vec::new();
    let mut texcoords: Vec<DVec2> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut uv_triangles: Vec<[u32; 3]> = Vec::new();
    let mut faces_without_uv = 0usize;
    // Positive indices may point forward; they are checked once all vertices
    // are known, against the line of the face that used them.
    let mut triangle_line: Vec<u32> = Vec::new();
    let mut group = String::new();
    let mut material = String::new();
    let mut facet_ids: HashMap<(String, String), u32> = HashMap::new();
    let mut facet_names: Vec<String> = Vec::new();
    let mut facet_of_face: Vec<u32> = Vec::new();
    let mut current_facet: Option<u32> = None;
    let mut corners: Vec<(u32, Option<u32>)> = Vec::new();

    for (n, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = n + 1;
        let err = |msg: String| Error::at_line(path, line_no, msg);
        let line = String::from_utf8_lossy(raw);
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let p = parse_coords::<3>(&mut words, 3, "vertex").map_err(err)?;
                positions.push(DVec3::from_array(p));
            }
            "vt" => {
                let t = parse_coords::<2>(&mut words, 1, "texture coordinate").map_err(err)?;
                texcoords.push(DVec2::from_array(t));
            }
            "f" => {
                corners.clear();
                for word in words {
                    corners
                        .push(parse_corner(word, positions.len(), texcoords.len()).map_err(err)?);
                }
                if corners.len() < 3 {
                    return Err(err(format!(
                        "a face needs at least 3 vertices, this one has {} (is the file truncated?)",
                        corners.len()
                    )));
                }
                let with_uv = corners.iter().all(|c| c.1.is_some());
                if !with_uv {
                    faces_without_uv += corners.len() - 2;
                }
                let facet = *current_facet.get_or_insert_with(|| {
                    facet_id(&mut facet_ids, &mut facet_names, &group, &material)
                });
                for k in 1..corners.len() - 1 {
                    let (a, b, c) = (corners[0], corners[k], corners[k + 1]);
                    triangles.push([a.0, b.0, c.0]);
                    uv_triangles.push([a.1.unwrap_or(0), b.1.unwrap_or(0), c.1.unwrap_or(0)]);
                    triangle_line.push(line_no as u32);
                    facet_of_face.push(facet);
                }
            }
            "g" | "o" => {
                group = words.collect::<Vec<_>>().join(" ");
                current_facet = None;
            }
            "usemtl" => {
                material = words.collect::<Vec<_>>().join(" ");
                current_facet = None;
            }
            // Normals, smoothing groups, material libraries, lines, points,
            // free-form geometry: not needed for a triangle mesh.
            _ => {}
        }
    }

    for (t, &line) in triangles.iter().zip(&triangle_line) {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(Error::at_line(
                path,
                line as usize,
                format!(
                    "face refers to vertex {} but the file defines only {} vertices",
                    v as u64 + 1,
                    positions.len()
                ),
            ));
        }
    }
    for (t, &line) in uv_triangles.iter().zip(&triangle_line) {
        if faces_without_uv == 0 && t.iter().any(|&v| v as usize >= texcoords.len()) {
            return Err(Error::at_line(
                path,
                line as usize,
                format!(
                    "face refers to a texture coordinate beyond the {} the file defines",
                    texcoords.len()
                ),
            ));
        }
    }

    let mut mesh = TriMesh::new(positions, triangles);
    let has_named_facet = facet_names.iter().any(|n| !n.is_empty());
    if has_named_facet {
        for name in facet_names.iter_mut().filter(|n| n.is_empty()) {
            *name = "default".into();
        }
        mesh.facets = Some(Facets {
            names: facet_names,
            of_face: facet_of_face,
        });
    }
    // A uv layer only when every face has one: a partial layer cannot be
    // textured.
    if faces_without_uv == 0 && !mesh.triangles.is_empty() {
        mesh.uvs = Some(UvLayer {
            coords: texcoords,
            triangles: uv_triangles,
        });
    }
    Ok(mesh)
}

fn facet_id(
    ids: &mut HashMap<(String, String), u32>,
    names: &mut Vec<String>,
    group: &str,
    material: &str,
) -> u32 {
    *ids.entry((group.to_string(), material.to_string()))
        .or_insert_with(|| {
            names.push(match (group.is_empty(), material.is_empty()) {
                (true, true) => String::new(),
                (false, true) => group.to_string(),
                (true, false) => material.to_string(),
                (false, false) => format!("{group}/{material}"),
            });
            (names.len() - 1) as u32
        })
}

/// Parse up to `N` numbers (at least `required`), padding with zeros.
fn parse_coords<const N: usize>(
    words: &mut std::str::SplitAsciiWhitespace,
    required: usize,
    what: &str,
) -> std::result::Result<[f64; N], String> {
    let mut out = [0.0; N];
    for (i, slot) in out.iter_mut().enumerate() {
        match words.next() {
            Some(w) => {
                let x: f64 = w
                    .parse()
                    .map_err(|_| format!("{what} coordinate '{w}' is not a number"))?;
                if !x.is_finite() {
                    return Err(format!("{what} coordinate '{w}' is not a finite number"));
                }
                *slot = x;
            }
            None if i < required => {
                return Err(format!(
                    "a {what} needs {required} coordinates, found {i} (is the file truncated?)"
                ));
            }
            None => break,
        }
    }
    Ok(out)
}

/// One face corner: `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative
/// (relative to the vertices so far). Returns 0-based (position, uv) indices.
fn parse_corner(
    word: &str,
    num_positions: usize,
    num_texcoords: usize,
) -> std::result::Result<(u32, Option<u32>), String> {
    let malformed =
        || format!("malformed face vertex '{word}' (expected v, v/vt, v//vn or v/vt/vn)");
    let mut parts = word.split('/');
    let v = parts.next().ok_or_else(malformed)?;
    let vt = parts.next();
    let vn = parts.next();
    if parts.next().is_some() || v.is_empty() || vn == Some("") || (vt == Some("") && vn.is_none())
    {
        return Err(malformed());
    }
    let position = resolve_index(v, num_positions, "vertex")?;
    let uv = match vt {
        Some(t) if !t.is_empty() => Some(resolve_index(t, num_texcoords, "texture coordinate")?),
        _ => None,
    };
    Ok((position, uv))
}

fn resolve_index(word: &str, count: usize, what: &str) -> std::result::Result<u32, String> {
    let i: i64 = word
        .parse()
        .map_err(|_| format!("{what} index '{word}' is not an integer"))?;
    let resolved = match i {
        0 => {
            return Err(format!(
                "{what} index 0 is invalid (OBJ indices start at 1)"
            ));
        }
        i if i > 0 => i - 1,
        i => {
            let r = count as i64 + i;
            if r < 0 {
                return Err(format!(
                    "relative {what} index {i} reaches before the first {what} (only {count} defined so far)"
                ));
            }
            r
        }
    };
    u32::try_from(resolved).map_err(|_| format!("{what} index {i} is too large"))
}

/// Write `mesh` as OBJ: vertices, uvs if any, faces grouped by facet (`g`).
/// With a texture, also write `<stem>.mtl` beside it with one material per
/// facet, each mapping that image, and name the facets by `usemtl` instead,
/// so reading the file back gives the same facets. Both files are written
/// atomically.
pub fn write(path: &Path, mesh: &TriMesh, texture: Option<&Path>) -> Result<()> {
    let facet_names: Vec<&str> = match &mesh.facets {
        Some(f) => f.names.iter().map(String::as_str).collect(),
        None => vec!["organtex"],
    };
    let mtl_path = texture.map(|_| path.with_extension("mtl"));
    if let (Some(tex), Some(mtl)) = (texture, &mtl_path) {
        crate::atomic::write_file(mtl, |w| {
            writeln!(w, "# written by organtex")?;
            for name in &facet_names {
                writeln!(w, "newmtl {name}\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1")?;
                writeln!(w, "map_Kd {}\n", tex.display())?;
            }
            Ok(())
        })?;
    }
    let facet_keyword = if texture.is_some() { "usemtl" } else { "g" };
    crate::atomic::write_file(path, |w| {
        writeln!(w, "# written by organtex")?;
        if let Some(mtl) = &mtl_path {
            let file = mtl.file_name().unwrap_or_default().to_string_lossy();
            writeln!(w, "mtllib {file}")?;
        }
        for p in &mesh.positions {
            writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
        }
        if let Some(uv) = &mesh.uvs {
            for t in &uv.coords {
                writeln!(w, "vt {} {}", t.x, t.y)?;
            }
        }
        let mut last_facet = None;
        for (f, t) in mesh.triangles.iter().enumerate() {
            let facet = mesh.facets.as_ref().map_or(0, |fs| fs.of_face[f]);
            if (mesh.facets.is_some() || texture.is_some()) && last_facet != Some(facet) {
                writeln!(w, "{facet_keyword} {}", facet_names[facet as usize])?;
                last_facet = Some(facet);
            }
            match &mesh.uvs {
                Some(uv) => {
                    let u = uv.triangles[f];
                    writeln!(
                        w,
                        "f {}/{} {}/{} {}/{}",
                        t[0] + 1,
                        u[0] + 1,
                        t[1] + 1,
                        u[1] + 1,
                        t[2] + 1,
                        u[2] + 1
                    )?;
                }
                None => writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?,
            }
        }
        Ok(())
    })
}
