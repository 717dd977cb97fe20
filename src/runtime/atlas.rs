//! The cut-texture atlas: square RGBA pages that grow, chart by chart, as
//! a simulator's cuts expose new faces, and shrink when faces vanish.
//!
//! Each face gets a chart of its own, laid flat at its true shape and the
//! atlas's texel density, its longest edge along x (the smallest box for a
//! triangle, near enough), with `PAD` texels of border that carry the
//! colour the face would have there, so bilinear filtering inside the face
//! never reads a neighbour (as `solid::cut_texture` does for a whole cut,
//! there in one image and here page by page, at run time).
//!
//! Slots are boxes on shelves. Their sides are rounded up to `QUANTUM`
//! texels, so the boxes of vanished faces are reused by new faces of the
//! same size class at once (a carving tool makes faces of a few sizes
//! only). A page whose charts have all gone is released, unless it is
//! the page being filled. Every write widens its page's dirty rectangle,
//! which the caller takes (`take_dirty`) and uploads.
//!
//! Chart ids are stable while the chart lives; page ids are never reused.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};

/// Texels of border round a face inside its chart: every texel a bilinear
/// lookup inside the face reads (centres within sqrt 2 of it) is covered.
pub const PAD: f64 = 1.5;
/// Slot sides are multiples of this many texels.
const QUANTUM: u32 = 2;
/// The default page side.
pub const DEFAULT_PAGE: u32 = 1024;
/// The largest page side.
pub const MAX_PAGE: u32 = 8192;

/// How dense and how large.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasOptions {
    /// Texels per object unit.
    pub texels_per_unit: f64,
    /// Texels a page side.
    pub page_size: u32,
}

impl Default for AtlasOptions {
    fn default() -> Self {
        AtlasOptions {
            texels_per_unit: 8.0,
            page_size: DEFAULT_PAGE,
        }
    }
}

impl AtlasOptions {
    /// Refuses a density that is not positive and finite, and a page side
    /// under 16 or over `MAX_PAGE`.
    pub fn check(&self) -> Result<()> {
        if !(self.texels_per_unit > 0.0 && self.texels_per_unit.is_finite()) {
            return Err(Error::invalid(format!(
                "the atlas's texel density must be a positive number of texels per unit, not {}",
                self.texels_per_unit
            )));
        }
        if !(16..=MAX_PAGE).contains(&self.page_size) {
            return Err(Error::invalid(format!(
                "the atlas's page side must be 16 to {MAX_PAGE} texels, not {}",
                self.page_size
            )));
        }
        Ok(())
    }
}

/// A rectangle of texels: x, y, width, height.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct Rect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl Rect {
    fn union(self, o: Rect) -> Rect {
        let x = self.x.min(o.x);
        let y = self.y.min(o.y);
        let right = (self.x + self.width).max(o.x + o.width);
        let bottom = (self.y + self.height).max(o.y + o.height);
        Rect {
            x,
            y,
            width: right - x,
            height: bottom - y,
        }
    }
}

/// Where a face lies in the atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chart {
    pub page: u32,
    /// Its box in the page.
    pub slot: Rect,
    /// The face's corners in page texels (x right, y down).
    pub corners: [DVec2; 3],
}

impl Chart {
    /// The corners' texture coordinates: 0..1 across the page, v down
    /// (glTF's convention; OpenGL's is 1 - v).
    pub fn uvs(&self, page_size: u32) -> [[f32; 2]; 3] {
        let s = page_size as f64;
        self.corners.map(|c| [(c.x / s) as f32, (c.y / s) as f32])
    }

    /// Every texel of the slot the face's colour reaches (its centre within
    /// `PAD` of the face), with the face's barycentric coordinates there
    /// (outside the face some are negative: the face's plane continued),
    /// and whether its centre lies on the face.
    pub fn texels(&self, mut visit: impl FnMut(u32, u32, [f64; 3], bool)) {
        let s = self.slot;
        let local = self.corners.map(|c| c - DVec2::new(s.x as f64, s.y as f64));
        crate::raster::triangle_padded(
            local,
            s.width as usize,
            s.height as usize,
            PAD,
            |x, y, outside| {
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                if let Some(b) = crate::raster::barycentric(local, centre) {
                    visit(s.x + x as u32, s.y + y as u32, b, outside == 0.0);
                }
            },
        );
    }
}

struct Page {
    rgba: Vec<u8>,
    /// Charts alive on it.
    live: u32,
    /// Shelves: top, height, next free x.
    shelves: Vec<(u32, u32, u32)>,
    /// Below the last shelf.
    next_y: u32,
    dirty: Option<Rect>,
}

/// A vacated slot: page, x, y.
type Vacated = (u32, u32, u32);

/// Pages of per-face charts; see the module's comment.
pub struct CutAtlas {
    options: AtlasOptions,
    pages: Vec<Option<Page>>,
    /// The page new shelves open on.
    open: Option<u32>,
    /// Vacated slots by size class (width, height).
    free: HashMap<(u32, u32), Vec<Vacated>>,
    charts: Vec<Option<Chart>>,
    /// Chart ids to reuse.
    vacant: Vec<u32>,
    /// Pages released since the last `take_released`.
    released: Vec<u32>,
}

impl CutAtlas {
    pub fn new(options: AtlasOptions) -> Result<CutAtlas> {
        options.check()?;
        Ok(CutAtlas {
            options,
            pages: Vec::new(),
            open: None,
            free: HashMap::new(),
            charts: Vec::new(),
            vacant: Vec::new(),
            released: Vec::new(),
        })
    }

    pub fn options(&self) -> AtlasOptions {
        self.options
    }

    /// Refuse options under which a face with edges up to `longest` units
    /// would not fit a page (its chart is at most that many texels wide and
    /// high, with the border): checked once, so no step fails half done.
    pub fn check_fits(&self, longest: f64) -> Result<()> {
        let side = self.options.page_size;
        let needed = (longest * self.options.texels_per_unit + 2.0 * PAD).ceil();
        if !(needed.is_finite() && needed + QUANTUM as f64 <= side as f64) {
            return Err(Error::invalid(format!(
                "the atlas's pages of {side} texels cannot hold a face {longest:.3} units long at                  {} texels a unit ({needed} texels): raise the page size or lower the density",
                self.options.texels_per_unit
            )));
        }
        Ok(())
    }

    /// The face (a, b, c) laid flat in texels: its longest edge along +x
    /// from the origin, the third corner below it (y down keeps the
    /// winding seen from the face's front counter-clockwise on screen
    /// with v up, as glTF reads it).
    pub fn flatten(&self, [a, b, c]: [DVec3; 3]) -> [DVec2; 3] {
        let s = self.options.texels_per_unit;
        let p = [a, b, c];
        let len = |i: usize| (p[(i + 1) % 3] - p[i]).length_squared();
        let k = (0..3)
            .max_by(|&i, &j| len(i).total_cmp(&len(j)))
            .unwrap_or(0);
        let (o, x, y) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
        let ex = (x - o).normalize_or_zero();
        let ey = (x - o).cross(y - o).cross(ex).normalize_or_zero();
        let mut flat = [DVec2::ZERO; 3];
        flat[k] = DVec2::ZERO;
        flat[(k + 1) % 3] = DVec2::new((x - o).length(), 0.0) * s;
        flat[(k + 2) % 3] = DVec2::new((y - o).dot(ex), -(y - o).dot(ey)) * s;
        let lo = flat[0].min(flat[1]).min(flat[2]);
        flat.map(|q| q - lo)
    }

    /// A chart for a face flattened by `flatten`: its id and where it lies.
    /// Errors when the face is larger than a page.
    pub fn add(&mut self, flat: [DVec2; 3]) -> Result<(u32, Chart)> {
        let hi = flat[0].max(flat[1]).max(flat[2]);
        let round = |v: f64| -> u32 {
            let t = (v + 2.0 * PAD).ceil() as u32;
            t.div_ceil(QUANTUM) * QUANTUM
        };
        let (w, h) = (round(hi.x), round(hi.y));
        let side = self.options.page_size;
        if !(hi.is_finite()) || w > side || h > side {
            return Err(Error::invalid(format!(
                "a face of {:.1}x{:.1} texels does not fit a page of {side}: lower the texel \
                 density or raise the page size",
                hi.x, hi.y
            )));
        }
        let (page, x, y) = self.slot(w, h);
        let slot = Rect {
            x,
            y,
            width: w,
            height: h,
        };
        let offset = DVec2::new(x as f64 + PAD, y as f64 + PAD);
        let chart = Chart {
            page,
            slot,
            corners: flat.map(|q| q + offset),
        };
        let p = self.pages[page as usize].as_mut().expect("a live page");
        p.live += 1;
        // The slot starts clear: a reused one holds its last face.
        for row in y..y + h {
            let start = 4 * (row * side + x) as usize;
            p.rgba[start..start + 4 * w as usize].fill(0);
        }
        p.dirty = Some(p.dirty.map_or(slot, |d| d.union(slot)));
        let id = match self.vacant.pop() {
            Some(id) => {
                self.charts[id as usize] = Some(chart);
                id
            }
            None => {
                self.charts.push(Some(chart));
                self.charts.len() as u32 - 1
            }
        };
        Ok((id, chart))
    }

    /// A free box of `w` x `h` texels: a vacated one of the same class, or
    /// room on a shelf of the open page, or a new shelf, or a new page.
    fn slot(&mut self, w: u32, h: u32) -> (u32, u32, u32) {
        let side = self.options.page_size;
        if let Some(list) = self.free.get_mut(&(w, h)) {
            while let Some((page, x, y)) = list.pop() {
                if self.pages[page as usize].is_some() {
                    return (page, x, y);
                }
            }
        }
        if let Some(open) = self.open {
            let p = self.pages[open as usize]
                .as_mut()
                .expect("the open page lives");
            // The shelf of this height with room, else a new shelf.
            if let Some(shelf) = p
                .shelves
                .iter_mut()
                .rev()
                .find(|s| s.1 == h && s.2 + w <= side)
            {
                let x = shelf.2;
                shelf.2 += w;
                return (open, x, shelf.0);
            }
            if p.next_y + h <= side {
                let y = p.next_y;
                p.shelves.push((y, h, w));
                p.next_y += h;
                return (open, 0, y);
            }
        }
        let id = self.pages.len() as u32;
        self.pages.push(Some(Page {
            rgba: vec![0; 4 * (side * side) as usize],
            live: 0,
            shelves: vec![(0, h, w)],
            next_y: h,
            dirty: None,
        }));
        // The last page opened stays open: a page that is full is left
        // to the reuse of its vacated slots.
        if let Some(old) = self.open.replace(id) {
            self.release_if_empty(old);
        }
        (id, 0, 0)
    }

    /// Free chart `id`; its page goes when its last chart does (unless it
    /// is the open page). Errors on an id that is not a live chart.
    pub fn remove(&mut self, id: u32) -> Result<()> {
        let chart = self
            .charts
            .get_mut(id as usize)
            .and_then(Option::take)
            .ok_or_else(|| Error::invalid(format!("chart {id} is not in the atlas")))?;
        self.vacant.push(id);
        let s = chart.slot;
        self.free
            .entry((s.width, s.height))
            .or_default()
            .push((chart.page, s.x, s.y));
        let page = self.pages[chart.page as usize]
            .as_mut()
            .expect("a live chart's page lives");
        page.live -= 1;
        self.release_if_empty(chart.page);
        Ok(())
    }

    fn release_if_empty(&mut self, page: u32) {
        let empty = self.pages[page as usize]
            .as_ref()
            .is_some_and(|p| p.live == 0);
        if empty && self.open != Some(page) {
            self.pages[page as usize] = None;
            self.released.push(page);
        }
    }

    pub fn chart(&self, id: u32) -> Option<&Chart> {
        self.charts.get(id as usize).and_then(Option::as_ref)
    }

    /// Live charts.
    pub fn len(&self) -> usize {
        self.charts.len() - self.vacant.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A page's texels, RGBA8, row by row, `page_size` a side; `None` for
    /// a page never made or released.
    pub fn page(&self, id: u32) -> Option<&[u8]> {
        self.pages
            .get(id as usize)
            .and_then(Option::as_ref)
            .map(|p| &p.rgba[..])
    }

    /// The ids of the pages that live.
    pub fn pages(&self) -> Vec<u32> {
        (0..self.pages.len() as u32)
            .filter(|&i| self.pages[i as usize].is_some())
            .collect()
    }

    /// Write the texels of `chart` (`rgba`: the slot's box, row by row).
    pub fn write(&mut self, chart: &Chart, rgba: &[u8]) {
        let side = self.options.page_size;
        let s = chart.slot;
        debug_assert_eq!(rgba.len(), 4 * (s.width * s.height) as usize);
        let Some(p) = self
            .pages
            .get_mut(chart.page as usize)
            .and_then(Option::as_mut)
        else {
            return;
        };
        for row in 0..s.height {
            let dst = 4 * ((s.y + row) * side + s.x) as usize;
            let src = 4 * (row * s.width) as usize;
            p.rgba[dst..dst + 4 * s.width as usize]
                .copy_from_slice(&rgba[src..src + 4 * s.width as usize]);
        }
        p.dirty = Some(p.dirty.map_or(s, |d| d.union(s)));
    }

    /// Each page's rectangle written since the last call, to upload.
    pub fn take_dirty(&mut self) -> Vec<(u32, Rect)> {
        self.pages
            .iter_mut()
            .enumerate()
            .filter_map(|(i, p)| Some((i as u32, p.as_mut()?.dirty.take()?)))
            .collect()
    }

    /// The pages released since the last call.
    pub fn take_released(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.released)
    }

    /// Bytes held: pages and bookkeeping.
    pub fn bytes(&self) -> usize {
        let side = self.options.page_size as usize;
        self.pages.iter().flatten().count() * 4 * side * side
            + self.charts.capacity() * std::mem::size_of::<Option<Chart>>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn atlas(page: u32) -> CutAtlas {
        CutAtlas::new(AtlasOptions {
            texels_per_unit: 8.0,
            page_size: page,
        })
        .unwrap()
    }

    #[test]
    fn a_flattened_face_keeps_its_edge_lengths() {
        let a = atlas(256);
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.5, 0.2),
            DVec3::new(-0.3, 1.1, 0.7),
        ];
        let f = a.flatten(p);
        for i in 0..3 {
            let j = (i + 1) % 3;
            let d3 = (p[j] - p[i]).length() * 8.0;
            let d2 = (f[j] - f[i]).length();
            assert!((d3 - d2).abs() < 1e-9, "{d3} {d2}");
        }
        assert!(f.iter().all(|q| q.x >= -1e-12 && q.y >= -1e-12));
    }

    #[test]
    fn charts_never_overlap_and_slots_are_reused_and_pages_released() {
        let mut a = atlas(64);
        let face = a.flatten([DVec3::ZERO, DVec3::X, DVec3::Y]);
        let mut ids = Vec::new();
        for _ in 0..200 {
            ids.push(a.add(face).unwrap().0);
        }
        let charts: Vec<Chart> = ids.iter().map(|&i| *a.chart(i).unwrap()).collect();
        for (i, c) in charts.iter().enumerate() {
            for d in &charts[..i] {
                let apart = c.page != d.page
                    || c.slot.x + c.slot.width <= d.slot.x
                    || d.slot.x + d.slot.width <= c.slot.x
                    || c.slot.y + c.slot.height <= d.slot.y
                    || d.slot.y + d.slot.height <= c.slot.y;
                assert!(apart, "{c:?} {d:?}");
            }
        }
        let pages = a.pages().len();
        assert!(pages > 1, "{pages}");
        // Free every chart of the first page: it is released.
        for (&id, c) in ids.iter().zip(&charts) {
            if c.page == 0 {
                a.remove(id).unwrap();
            }
        }
        assert_eq!(a.take_released(), vec![0]);
        assert!(a.page(0).is_none());
        // Free one on the open page and add one: the slot comes back.
        let last = *ids.last().unwrap();
        let slot = a.chart(last).unwrap().slot;
        a.remove(last).unwrap();
        let (_, again) = a.add(face).unwrap();
        assert_eq!(again.slot, slot);
        assert!(a.remove(9999).is_err());
    }

    #[test]
    fn texels_cover_the_face_and_its_border_inside_the_slot() {
        let mut a = atlas(64);
        let face = a.flatten([DVec3::ZERO, DVec3::X, DVec3::Y]);
        let (_, c) = a.add(face).unwrap();
        let (mut inside, mut all) = (0, 0);
        c.texels(|x, y, b, on| {
            assert!(x >= c.slot.x && x < c.slot.x + c.slot.width);
            assert!(y >= c.slot.y && y < c.slot.y + c.slot.height);
            assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            all += 1;
            inside += on as usize;
        });
        // Half of 8 x 8 texels, give or take the diagonal.
        assert!((28..=40).contains(&inside), "{inside}");
        assert!(all > inside + 20, "{all}");
    }

    #[test]
    fn bad_options_are_refused() {
        for (t, p) in [
            (0.0, 256),
            (f64::NAN, 256),
            (-1.0, 256),
            (8.0, 4),
            (8.0, 1 << 20),
        ] {
            let o = AtlasOptions {
                texels_per_unit: t,
                page_size: p,
            };
            assert!(CutAtlas::new(o).is_err(), "{t} {p}");
        }
    }
}
