//! Bakes and their nodes: open a bake folder, list its nodes, and read a
//! node's tet mesh, colours and block.

use std::ffi::{CString, c_char};
use std::sync::{Arc, OnceLock};

use organtex::runtime::{Bake, Node};

use crate::{Failure, arg, guard, not_found, points, put, slice_mut, text};

/// An opened bake folder (`organtex bake SCENE -o DIR` wrote it).
pub struct organtex_bake {
    bake: Bake,
    names: Vec<CString>,
}

/// One node of a bake: its interior and tet mesh, read-only.
pub struct organtex_node {
    pub(crate) node: Arc<Node>,
    name: CString,
    /// The tet mesh's boundary faces and their ids, made on first ask.
    boundary: OnceLock<(Vec<[u32; 3]>, Vec<u32>)>,
}

/// A node's tet mesh, as the simulator's physics loads it (the ids of the
/// bake's .vtk). The arrays belong to the node and live as long as it.
#[repr(C)]
pub struct organtex_tet_mesh {
    /// x, y, z per vertex.
    pub positions: *const f64,
    pub vertex_count: usize,
    /// Four vertex ids per tet, positively oriented.
    pub tets: *const u32,
    pub tet_count: usize,
}

/// A node's interior block: RGB bytes, x fastest, then y, then z; it
/// tiles space from `origin`, a voxel spanning `voxel_size` units. Belongs
/// to the node.
#[repr(C)]
pub struct organtex_block {
    pub rgb: *const u8,
    pub size: [u32; 3],
    pub voxel_size: f64,
    pub origin: [f64; 3],
}

/// Open the bake in the folder `dir` (UTF-8): reads its report.json and
/// checks the files it names. Nodes load on first use.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_bake_open(
    dir: *const c_char,
    out: *mut *mut organtex_bake,
) -> crate::organtex_status {
    guard("organtex_bake_open", || {
        arg(out, "out")?;
        let dir = text(dir, "dir")?;
        let bake = Bake::open(std::path::Path::new(dir))?;
        let names = bake
            .nodes()
            .iter()
            .map(|n| CString::new(n.replace('\0', " ")).unwrap_or_default())
            .collect();
        put(
            out,
            Box::into_raw(Box::new(organtex_bake { bake, names })),
            "out",
        )
    })
}

/// Free a bake (NULL is fine). Nodes opened from it stay valid.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_bake_free(bake: *mut organtex_bake) {
    if !bake.is_null() {
        // SAFETY: made by organtex_bake_open, freed once by the caller.
        drop(unsafe { Box::from_raw(bake) });
    }
}

/// How many nodes the bake has (those with an interior).
#[unsafe(no_mangle)]
pub extern "C" fn organtex_bake_node_count(
    bake: *const organtex_bake,
    out: *mut usize,
) -> crate::organtex_status {
    guard("organtex_bake_node_count", || {
        let bake = arg(bake, "bake")?;
        put(out, bake.names.len(), "out")
    })
}

/// Node `index`'s name, valid as long as the bake.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_bake_node_name(
    bake: *const organtex_bake,
    index: usize,
    out: *mut *const c_char,
) -> crate::organtex_status {
    guard("organtex_bake_node_name", || {
        let bake = arg(bake, "bake")?;
        let name = bake.names.get(index).ok_or_else(|| {
            crate::invalid(format!(
                "node index {index} is past the bake's {} nodes",
                bake.names.len()
            ))
        })?;
        put(out, name.as_ptr(), "out")
    })
}

/// Open node `name` of the bake (loads its files the first time; later
/// opens share them). Free it with `organtex_node_free`.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_bake_node(
    bake: *const organtex_bake,
    name: *const c_char,
    out: *mut *mut organtex_node,
) -> crate::organtex_status {
    guard("organtex_bake_node", || {
        let bake = arg(bake, "bake")?;
        let name = text(name, "name")?;
        arg(out, "out")?;
        if !bake.bake.nodes().contains(&name) {
            return Err(not_found(format!(
                "no node '{name}' in the bake (it has: {})",
                bake.bake.nodes().join(", ")
            )));
        }
        let node = bake.bake.node(name)?;
        let handle = organtex_node {
            name: CString::new(name).unwrap_or_default(),
            node,
            boundary: OnceLock::new(),
        };
        put(out, Box::into_raw(Box::new(handle)), "out")
    })
}

/// Free a node (NULL is fine). Carvings made from it keep what they need.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_free(node: *mut organtex_node) {
    if !node.is_null() {
        // SAFETY: made by organtex_bake_node, freed once by the caller.
        drop(unsafe { Box::from_raw(node) });
    }
}

/// The node's name, valid as long as the node.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_name(node: *const organtex_node) -> *const c_char {
    // SAFETY: NULL or a live node, the header's contract.
    match unsafe { node.as_ref() } {
        Some(n) => n.name.as_ptr(),
        None => c"".as_ptr(),
    }
}

/// The node's tet mesh. `ORGANTEX_INVALID_ARGUMENT` when it has none.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_tet_mesh(
    node: *const organtex_node,
    out: *mut organtex_tet_mesh,
) -> crate::organtex_status {
    guard("organtex_node_tet_mesh", || {
        let node = arg(node, "node")?;
        let mesh = node.node.require_tets()?;
        put(
            out,
            organtex_tet_mesh {
                positions: mesh.positions.as_ptr().cast(),
                vertex_count: mesh.positions.len(),
                tets: mesh.tets.as_ptr().cast(),
                tet_count: mesh.tets.len(),
            },
            "out",
        )
    })
}

/// The tet mesh's boundary before any carving: `count` faces, three
/// vertex ids each (counter-clockwise seen from outside), and each face's
/// id (`4 * tet + k`, the ids carving steps use). Arrays belong to the
/// node.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_boundary(
    node: *const organtex_node,
    faces: *mut *const u32,
    ids: *mut *const u32,
    count: *mut usize,
) -> crate::organtex_status {
    guard("organtex_node_boundary", || {
        let node = arg(node, "node")?;
        arg(faces, "faces")?;
        arg(ids, "ids")?;
        arg(count, "count")?;
        let mesh = node.node.require_tets()?;
        let adjacency = node.node.adjacency()?;
        let (f, i) = node.boundary.get_or_init(|| {
            let mut f = Vec::new();
            let mut i = Vec::new();
            for (t, tet) in mesh.tets.iter().enumerate() {
                for (k, &n) in adjacency[t].iter().enumerate() {
                    if n == organtex::tetra::mesh::NO_NEIGHBOUR {
                        f.push(organtex::tetra::mesh::TET_FACES[k].map(|c| tet[c]));
                        i.push(4 * t as u32 + k as u32);
                    }
                }
            }
            (f, i)
        });
        put(faces, f.as_ptr().cast(), "faces")?;
        put(ids, i.as_ptr(), "ids")?;
        put(count, f.len(), "count")
    })
}

/// The interior's colours at `count` points (x, y, z each, in the organ's
/// rest frame): `count` RGB triples into `rgb`. Any thread, concurrently.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_colours(
    node: *const organtex_node,
    positions: *const f64,
    count: usize,
    rgb: *mut u8,
) -> crate::organtex_status {
    guard("organtex_node_colours", || {
        let node = arg(node, "node")?;
        let points = points(positions, count, "positions")?;
        let out = slice_mut(rgb, 3 * count, "rgb")?;
        for (o, c) in out.chunks_exact_mut(3).zip(node.node.colours(&points)?) {
            o.copy_from_slice(&c);
        }
        Ok(())
    })
}

/// The node's block, when its interior is one (block synthesis, layered,
/// stereology); `ORGANTEX_INVALID_ARGUMENT` otherwise (a lapped solid
/// texture or a morph: use the atlas).
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_block(
    node: *const organtex_node,
    out: *mut organtex_block,
) -> crate::organtex_status {
    guard("organtex_node_block", || {
        let node = arg(node, "node")?;
        arg(out, "out")?;
        let (volume, placement) = node.node.model().block().ok_or_else(|| {
            crate::invalid(format!(
                "node '{}' is not a block (it is {:?}): texture its faces from the atlas",
                node.node.name, node.node.method
            ))
        })?;
        put(
            out,
            organtex_block {
                rgb: volume.voxels.as_ptr().cast(),
                size: volume.size.map(|s| s as u32),
                voxel_size: placement.scale,
                origin: placement.origin.to_array(),
            },
            "out",
        )
    })
}

/// 3D texture coordinates (voxel units, three floats a point) of `count`
/// points in the node's block, for `organtex_block_shader_glsl()` to
/// sample per fragment. `ORGANTEX_INVALID_ARGUMENT` when the node is not
/// a block.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_node_block_coordinates(
    node: *const organtex_node,
    positions: *const f64,
    count: usize,
    coords: *mut f32,
) -> crate::organtex_status {
    guard("organtex_node_block_coordinates", || {
        let node = arg(node, "node")?;
        let points = points(positions, count, "positions")?;
        let out = slice_mut(coords, 3 * count, "coords")?;
        for (o, c) in out
            .chunks_exact_mut(3)
            .zip(node.node.block_coordinates(&points)?)
        {
            o.copy_from_slice(&c);
        }
        Ok(())
    })
}

/// The node behind a handle, for the carving and texture calls.
pub(crate) fn node_of(node: *const organtex_node) -> Result<Arc<Node>, Failure> {
    Ok(arg(node, "node")?.node.clone())
}
