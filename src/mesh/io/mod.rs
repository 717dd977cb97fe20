//! Reading and writing meshes. `read` picks the format from the extension,
//! parses, and checks what every stage relies on (see `TriMesh`), so a mesh
//! that loads is one the rest of organtex can use.

// Visible to the crate for `fuzz`, which fuzzes each parser alone.
pub(crate) mod obj;
pub(crate) mod ply;
pub(crate) mod stl;

use std::path::Path;

use crate::error::{Error, Result};
use crate::mesh::{TriMesh, defects::is_degenerate};

/// The formats `read` understands, by extension.
pub const READABLE: &[&str] = &["obj", "ply", "stl"];

/// Read a mesh from an OBJ, PLY or STL file.
pub fn read(path: &Path) -> Result<TriMesh> {
    let parse = match crate::error::extension(path).as_str() {
        "obj" => obj::parse,
        "ply" => ply::parse,
        "stl" => stl::parse,
        _ => return Err(Error::unknown_format(path, "mesh", "reads", READABLE)),
    };
    if path.is_dir() {
        return Err(Error::format(path, "is a directory, not a mesh file"));
    }
    // A device or a pipe (/dev/zero, a FIFO) would be read without end.
    if path.exists() && !path.is_file() {
        return Err(Error::format(
            path,
            "is not a regular file (a device or a pipe?), not a mesh file",
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.is_empty() {
        return Err(Error::format(path, "the file is empty"));
    }
    let mesh = parse(path, &bytes)?;
    check_usable(path, &mesh)?;
    Ok(mesh)
}

/// A mesh with no faces, or only zero-area ones, is no mesh to texture.
fn check_usable(path: &Path, mesh: &TriMesh) -> Result<()> {
    if mesh.triangles.is_empty() {
        return Err(Error::format(
            path,
            format!(
                "no faces: the file holds {} vertices and no triangles",
                mesh.num_vertices()
            ),
        ));
    }
    if (0..mesh.num_faces()).all(|f| is_degenerate(mesh, f)) {
        return Err(Error::format(
            path,
            format!("all {} faces have zero area (degenerate)", mesh.num_faces()),
        ));
    }
    Ok(())
}

/// Write `mesh` by its name's ending: .obj, .ply (binary) or .stl
/// (binary); atomic.
pub fn write(path: &Path, mesh: &TriMesh) -> Result<()> {
    match output_format(path)? {
        "obj" => obj::write(path, mesh, None),
        "ply" => ply::write(path, mesh),
        _ => stl::write(path, mesh),
    }
}

/// The format `write` would give `path` ("obj", "ply" or "stl"), or the
/// error it would: for commands that check their output before long work.
pub fn output_format(path: &Path) -> Result<&'static str> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    ["obj", "ply", "stl"]
        .into_iter()
        .find(|f| ext.as_deref() == Some(*f))
        .ok_or_else(|| Error::format(path, "organtex writes meshes as .obj, .ply or .stl"))
}

/// Write `mesh` as OBJ (with its uvs), plus an .mtl mapping `texture` when
/// given. Atomic: no half-written file is ever left behind.
pub fn write_obj(path: &Path, mesh: &TriMesh, texture: Option<&Path>) -> Result<()> {
    obj::write(path, mesh, texture)
}
