//! Carving sessions: remove tets by id or under a tool, get the faces that
//! appeared (atlas uvs, corner colours) and vanished, and the atlas pages.

use std::ffi::c_char;

use glam::DVec3;
use organtex::runtime::{AtlasOptions, Carving, CarvingOptions, Rect, Step, Tool};

use crate::bake::{node_of, organtex_node};
use crate::{Failure, arg, arg_mut, guard, invalid, put, slice, text};

/// How a carving session textures.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct organtex_carving_options {
    /// Atlas texels per unit of the mesh (default 8).
    pub texels_per_unit: f64,
    /// Texels a page side, 16 to 8192 (default 1024).
    pub page_size: u32,
    /// Fill each step's texels in a background job; the step returns with
    /// faces, uvs and colours, and `organtex_carving_wait` (or the next
    /// step) writes the texels (default false).
    pub background_texels: bool,
}

/// A face that appeared: face `id` (`4 * tet + k`) with its tet mesh
/// vertex ids (counter-clockwise seen from outside), its atlas page, its
/// corners' texture coordinates there (u, v per corner; 0..1, v down as
/// glTF; OpenGL samples 1 - v) and the interior's RGB at each corner.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct organtex_face {
    pub id: u32,
    pub vertices: [u32; 3],
    pub page: u32,
    pub uvs: [f32; 6],
    pub colours: [u8; 9],
}

/// A face that vanished.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct organtex_face_ref {
    pub id: u32,
    pub vertices: [u32; 3],
}

/// A page's rectangle of texels to upload.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct organtex_rect {
    pub page: u32,
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// What one step changed. The arrays belong to the carving and stay valid
/// until its next step, wait or free.
#[repr(C)]
pub struct organtex_step {
    /// The tets removed, ascending (a tool's step says which).
    pub removed: *const u32,
    pub removed_count: usize,
    pub appeared: *const organtex_face,
    pub appeared_count: usize,
    pub vanished: *const organtex_face_ref,
    pub vanished_count: usize,
    /// Pages' rectangles written, to upload.
    pub dirty: *const organtex_rect,
    pub dirty_count: usize,
    /// Pages no face uses any more.
    pub released: *const u32,
    pub released_count: usize,
    /// The appeared faces' texels follow in a background job.
    pub texels_pending: bool,
    /// The step's time in seconds.
    pub seconds: f64,
}

/// A carving session over a node's tet mesh.
pub struct organtex_carving {
    carving: Carving,
    removed: Vec<u32>,
    appeared: Vec<organtex_face>,
    vanished: Vec<organtex_face_ref>,
    dirty: Vec<organtex_rect>,
    released: Vec<u32>,
}

impl organtex_carving {
    /// Keep `step`'s arrays and describe them.
    fn publish(&mut self, step: Step) -> organtex_step {
        self.removed = step.removed;
        self.appeared = step
            .appeared
            .iter()
            .map(|f| organtex_face {
                id: f.id,
                vertices: f.vertices,
                page: f.page,
                uvs: std::array::from_fn(|i| f.uvs[i / 2][i % 2]),
                colours: std::array::from_fn(|i| f.colours[i / 3][i % 3]),
            })
            .collect();
        self.vanished = step
            .vanished
            .iter()
            .map(|f| organtex_face_ref {
                id: f.id,
                vertices: f.vertices,
            })
            .collect();
        self.dirty = rects(&step.dirty);
        self.released = step.released;
        organtex_step {
            removed: self.removed.as_ptr(),
            removed_count: self.removed.len(),
            appeared: self.appeared.as_ptr(),
            appeared_count: self.appeared.len(),
            vanished: self.vanished.as_ptr(),
            vanished_count: self.vanished.len(),
            dirty: self.dirty.as_ptr(),
            dirty_count: self.dirty.len(),
            released: self.released.as_ptr(),
            released_count: self.released.len(),
            texels_pending: step.texels_pending,
            seconds: step.seconds,
        }
    }
}

pub(crate) fn rects(dirty: &[(u32, Rect)]) -> Vec<organtex_rect> {
    dirty
        .iter()
        .map(|&(page, r)| organtex_rect {
            page,
            x: r.x,
            y: r.y,
            width: r.width,
            height: r.height,
        })
        .collect()
}

/// The defaults: 8 texels a unit, pages of 1024, texels at once.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_options_default() -> organtex_carving_options {
    let d = CarvingOptions::default();
    organtex_carving_options {
        texels_per_unit: d.atlas.texels_per_unit,
        page_size: d.atlas.page_size,
        background_texels: d.background_texels,
    }
}

/// Start a carving session over `node`'s tet mesh, every tet present.
/// `options` may be NULL for the defaults.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_new(
    node: *const organtex_node,
    options: *const organtex_carving_options,
    out: *mut *mut organtex_carving,
) -> crate::organtex_status {
    guard("organtex_carving_new", || {
        let node = node_of(node)?;
        arg(out, "out")?;
        // SAFETY: NULL or a live options struct, the header's contract.
        let o = unsafe { options.as_ref() }
            .copied()
            .unwrap_or_else(|| organtex_carving_options_default());
        let options = CarvingOptions {
            atlas: AtlasOptions {
                texels_per_unit: o.texels_per_unit,
                page_size: o.page_size,
            },
            background_texels: o.background_texels,
        };
        let carving = Carving::new(node, options)?;
        let handle = organtex_carving {
            carving,
            removed: Vec::new(),
            appeared: Vec::new(),
            vanished: Vec::new(),
            dirty: Vec::new(),
            released: Vec::new(),
        };
        put(out, Box::into_raw(Box::new(handle)), "out")
    })
}

/// Free a carving session (NULL is fine); stops its background job.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_free(carving: *mut organtex_carving) {
    if !carving.is_null() {
        // SAFETY: made by organtex_carving_new, freed once by the caller.
        let c = unsafe { Box::from_raw(carving) };
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(c)));
    }
}

fn step(
    what: &str,
    carving: *mut organtex_carving,
    out: *mut organtex_step,
    run: impl FnOnce(&mut Carving) -> organtex::Result<Step>,
) -> crate::organtex_status {
    guard(what, || {
        let c = arg_mut(carving, "carving")?;
        arg(out, "out")?;
        let s = run(&mut c.carving)?;
        let published = c.publish(s);
        put(out, published, "out")
    })
}

/// Remove exactly the tets `ids` (SOFA's TetrahedraRemoved). Refuses,
/// changing nothing, an id past the mesh, one already removed, one given
/// twice.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_remove(
    carving: *mut organtex_carving,
    ids: *const u32,
    count: usize,
    out: *mut organtex_step,
) -> crate::organtex_status {
    let ids = match slice(ids, count, "ids") {
        Ok(ids) => ids.to_vec(),
        Err(f) => return guard("organtex_carving_remove", || Err(f)),
    };
    step("organtex_carving_remove", carving, out, |c| c.remove(&ids))
}

fn point(p: *const f64, name: &str) -> Result<DVec3, Failure> {
    let s = slice(p, 3, name)?;
    Ok(DVec3::new(s[0], s[1], s[2]))
}

/// Remove the tets whose centroid lies within `radius` of `centre` (x, y,
/// z), and those that would leave an edge with more than two faces.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_sphere(
    carving: *mut organtex_carving,
    centre: *const f64,
    radius: f64,
    out: *mut organtex_step,
) -> crate::organtex_status {
    let what = "organtex_carving_sphere";
    match point(centre, "centre") {
        Ok(centre) => step(what, carving, out, |c| {
            c.carve(&Tool::Sphere { centre, radius })
        }),
        Err(f) => guard(what, || Err(f)),
    }
}

/// As the sphere, swept from `a` to `b` (a burr or blade moved in one
/// step).
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_capsule(
    carving: *mut organtex_carving,
    a: *const f64,
    b: *const f64,
    radius: f64,
    out: *mut organtex_step,
) -> crate::organtex_status {
    let what = "organtex_carving_capsule";
    match (point(a, "a"), point(b, "b")) {
        (Ok(a), Ok(b)) => step(what, carving, out, |c| {
            c.carve(&Tool::Capsule { a, b, radius })
        }),
        (Err(f), _) | (_, Err(f)) => guard(what, || Err(f)),
    }
}

/// Finish the background texels (if any) and give each page's rectangle
/// written since the last step, valid until the next call that returns
/// arrays.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_wait(
    carving: *mut organtex_carving,
    dirty: *mut *const organtex_rect,
    count: *mut usize,
) -> crate::organtex_status {
    guard("organtex_carving_wait", || {
        let c = arg_mut(carving, "carving")?;
        arg(dirty, "dirty")?;
        arg(count, "count")?;
        c.dirty = rects(&c.carving.wait());
        put(dirty, c.dirty.as_ptr(), "dirty")?;
        put(count, c.dirty.len(), "count")
    })
}

/// Atlas page `page`: `side` x `side` RGBA8 texels, row by row, valid
/// until the next step or wait. `ORGANTEX_INVALID_ARGUMENT` for a page
/// never made or released.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_page(
    carving: *const organtex_carving,
    page: u32,
    rgba: *mut *const u8,
    side: *mut u32,
) -> crate::organtex_status {
    guard("organtex_carving_page", || {
        let c = arg(carving, "carving")?;
        arg(rgba, "rgba")?;
        arg(side, "side")?;
        let texels = c
            .carving
            .atlas()
            .page(page)
            .ok_or_else(|| invalid(format!("page {page} is not in the atlas")))?;
        put(rgba, texels.as_ptr(), "rgba")?;
        put(side, c.carving.atlas().options().page_size, "side")
    })
}

/// Whether tet `tet` is still there.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_alive(
    carving: *const organtex_carving,
    tet: u32,
    out: *mut bool,
) -> crate::organtex_status {
    guard("organtex_carving_alive", || {
        let c = arg(carving, "carving")?;
        let n = c.carving.node().require_tets()?.num_tets();
        if tet as usize >= n {
            return Err(invalid(format!(
                "tet {tet} is out of range: the mesh has {n} tets"
            )));
        }
        put(out, c.carving.alive(tet), "out")
    })
}

/// Write the carved surface as a .glb (UTF-8 path): carved faces textured
/// from the atlas, the mesh's own boundary coloured per vertex. Waits for
/// background texels first.
#[unsafe(no_mangle)]
pub extern "C" fn organtex_carving_write_glb(
    carving: *mut organtex_carving,
    path: *const c_char,
) -> crate::organtex_status {
    guard("organtex_carving_write_glb", || {
        let c = arg_mut(carving, "carving")?;
        let path = std::path::PathBuf::from(text(path, "path")?);
        c.dirty = rects(&c.carving.wait());
        let glb = organtex::runtime::surface_glb(&c.carving)?;
        organtex::atomic::write_file(&path, |w| w.write_all(&glb))?;
        Ok(())
    })
}
