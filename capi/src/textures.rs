//! Texture for new faces anywhere (a curved incision): triangles in, atlas
//! charts out, coloured from the node's interior.

use organtex::runtime::{AtlasOptions, CutTextures};

use crate::bake::{node_of, organtex_node};
use crate::carving::{organtex_rect, rects};
use crate::{arg, arg_mut, guard, invalid, points, put, slice, slice_mut};

/// An atlas of new faces' textures over one node.
pub struct organtex_cut_textures {
    textures: CutTextures,
    dirty: Vec<organtex_rect>,
    released: Vec<u32>,
}

/// One triangle's chart: its id (to release it), page and corners'
/// texture coordinates (u, v per corner, 0..1, v down).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct organtex_chart {
    pub chart: u32,
    pub page: u32,
    pub uvs: [f32; 6],
}

/// A cut-texture atlas over `node`: `texels_per_unit` texels a unit of the
/// mesh, pages of `page_size` texels a side (16 to 8192).
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_new(
    node: *const organtex_node,
    texels_per_unit: f64,
    page_size: u32,
    out: *mut *mut organtex_cut_textures,
) -> crate::organtex_status {
    guard("organtex_cut_textures_new", || {
        let node = node_of(node)?;
        arg(out, "out")?;
        let textures = CutTextures::new(
            node,
            AtlasOptions {
                texels_per_unit,
                page_size,
            },
        )?;
        let handle = organtex_cut_textures {
            textures,
            dirty: Vec::new(),
            released: Vec::new(),
        };
        put(out, Box::into_raw(Box::new(handle)), "out")
    })
}

/// Free it (NULL is fine).
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_free(textures: *mut organtex_cut_textures) {
    if !textures.is_null() {
        // SAFETY: made by organtex_cut_textures_new, freed once.
        drop(unsafe { Box::from_raw(textures) });
    }
}

/// Charts for `count` triangles (`corners`: nine doubles a triangle, x, y,
/// z of each corner in the organ's rest frame), their texels filled;
/// `charts` receives `count` charts. Refuses, adding none, corners that
/// are not finite and a triangle larger than a page.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_add(
    textures: *mut organtex_cut_textures,
    corners: *const f64,
    count: usize,
    charts: *mut organtex_chart,
) -> crate::organtex_status {
    guard("organtex_cut_textures_add", || {
        let t = arg_mut(textures, "textures")?;
        let n = count
            .checked_mul(3)
            .ok_or_else(|| invalid("too many triangles"))?;
        let p = points(corners, n, "corners")?;
        let out = slice_mut(charts, count, "charts")?;
        let tris: Vec<[glam::DVec3; 3]> = p.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        for (o, placed) in out.iter_mut().zip(t.textures.add(&tris)?) {
            let u = placed.uvs;
            *o = organtex_chart {
                chart: placed.chart,
                page: placed.page,
                uvs: [u[0][0], u[0][1], u[1][0], u[1][1], u[2][0], u[2][1]],
            };
        }
        Ok(())
    })
}

/// Give back `count` charts (their faces vanished). Refuses, giving back
/// none, an id that is not a live chart or is given twice.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_release(
    textures: *mut organtex_cut_textures,
    charts: *const u32,
    count: usize,
) -> crate::organtex_status {
    guard("organtex_cut_textures_release", || {
        let t = arg_mut(textures, "textures")?;
        let ids = slice(charts, count, "charts")?;
        t.textures.release(ids)?;
        Ok(())
    })
}

/// Pages' rectangles written and pages released since the last call,
/// valid until the next call on this handle that returns arrays.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_changes(
    textures: *mut organtex_cut_textures,
    dirty: *mut *const organtex_rect,
    dirty_count: *mut usize,
    released: *mut *const u32,
    released_count: *mut usize,
) -> crate::organtex_status {
    guard("organtex_cut_textures_changes", || {
        let t = arg_mut(textures, "textures")?;
        for (p, name) in [
            (dirty as *const (), "dirty"),
            (dirty_count as *const (), "dirty_count"),
            (released as *const (), "released"),
            (released_count as *const (), "released_count"),
        ] {
            arg(p, name)?;
        }
        t.dirty = rects(&t.textures.take_dirty());
        t.released = t.textures.take_released();
        put(dirty, t.dirty.as_ptr(), "dirty")?;
        put(dirty_count, t.dirty.len(), "dirty_count")?;
        put(released, t.released.as_ptr(), "released")?;
        put(released_count, t.released.len(), "released_count")
    })
}

/// Page `page`: `side` x `side` RGBA8 texels, valid until the next add or
/// release.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_cut_textures_page(
    textures: *const organtex_cut_textures,
    page: u32,
    rgba: *mut *const u8,
    side: *mut u32,
) -> crate::organtex_status {
    guard("organtex_cut_textures_page", || {
        let t = arg(textures, "textures")?;
        arg(rgba, "rgba")?;
        arg(side, "side")?;
        let atlas = t.textures.atlas();
        let texels = atlas
            .page(page)
            .ok_or_else(|| invalid(format!("page {page} is not in the atlas")))?;
        put(rgba, texels.as_ptr(), "rgba")?;
        put(side, atlas.options().page_size, "side")
    })
}
