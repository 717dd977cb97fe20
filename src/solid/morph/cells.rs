//! Plane regions rasterised in an exemplar's pixel coordinates: the mesh's
//! section by an exemplar plane (or by that plane swept along its normal),
//! cut down to BSP regions. What the BSP, the sweep and the warps measure
//! (extent, centroid, outline, whether a subdomain is a disk) they measure
//! on these cells.
//!
//! Cells rather than exact polygons: the BSP clips a section by any number
//! of planes, and the disk test (seed 003, Fig. 2) is a flood fill; on a
//! grid both are a few lines and cannot fail on degenerate geometry.

use glam::{DVec2, DVec3};

use super::sections::Exemplar;
use crate::error::Result;
use crate::mesh::{Topology, TriMesh};
use crate::solid::section::{Plane, plane_section};
use crate::synth::components::components;

#[derive(Clone, Debug)]
pub struct Cells {
    /// Pixel coordinates of cell (0, 0)'s low corner.
    pub lo: DVec2,
    /// Pixels a cell spans.
    pub step: f64,
    pub w: usize,
    pub h: usize,
    pub inside: Vec<bool>,
}

impl Cells {
    /// The mesh's section by `exemplar`'s plane moved `t` along its normal,
    /// at most `max_side` cells a side; `None` when the plane misses it.
    pub fn section(
        mesh: &TriMesh,
        topology: &Topology,
        exemplar: &Exemplar,
        t: f64,
        max_side: usize,
    ) -> Result<Option<Cells>> {
        let plane = Plane::new(exemplar.normal, exemplar.offset + t)?;
        let section = plane_section(mesh, topology, plane)?;
        if section.is_empty() {
            return Ok(None);
        }
        let pts: Vec<DVec2> = section
            .positions
            .iter()
            .map(|&p| exemplar.pixel_coords(p))
            .collect();
        let (lo, hi) = pts
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let extent = (hi - lo).max_element();
        if !(extent > 0.0 && extent.is_finite()) {
            return Ok(None);
        }
        let step = extent / max_side as f64;
        // One empty cell of margin all round, so outlines close inside.
        let lo = lo - DVec2::splat(step);
        let w = ((hi.x - lo.x) / step).ceil() as usize + 2;
        let h = ((hi.y - lo.y) / step).ceil() as usize + 2;
        let mut inside = vec![false; w * h];
        for t in &section.triangles {
            let corners = t.map(|i| (pts[i as usize] - lo) / step);
            crate::raster::triangle(corners, w, h, |x, y, _| inside[y * w + x] = true);
        }
        Ok(Some(Cells {
            lo,
            step,
            w,
            h,
            inside,
        }))
    }

    /// Pixel coordinates of cell (x, y)'s centre.
    #[inline]
    pub fn centre(&self, x: usize, y: usize) -> DVec2 {
        self.lo + DVec2::new(x as f64 + 0.5, y as f64 + 0.5) * self.step
    }

    /// Whether the cell holding pixel coordinates `q` is inside.
    #[inline]
    pub fn contains(&self, q: DVec2) -> bool {
        let c = (q - self.lo) / self.step;
        c.x >= 0.0
            && c.y >= 0.0
            && (c.x as usize) < self.w
            && (c.y as usize) < self.h
            && self.inside[c.y as usize * self.w + c.x as usize]
    }

    /// Keep only the cells whose 3D centre (on `exemplar`'s plane moved
    /// `t` along its normal) passes `keep`.
    pub fn retain(&mut self, exemplar: &Exemplar, t: f64, keep: impl Fn(DVec3) -> bool) {
        for y in 0..self.h {
            for x in 0..self.w {
                let i = y * self.w + x;
                if self.inside[i] && !keep(exemplar.point(self.centre(x, y)) + exemplar.normal * t)
                {
                    self.inside[i] = false;
                }
            }
        }
    }

    pub fn count(&self) -> usize {
        self.inside.iter().filter(|&&b| b).count()
    }

    /// The inside cells' centres.
    pub fn centres(&self) -> impl Iterator<Item = DVec2> + '_ {
        (0..self.h).flat_map(move |y| {
            (0..self.w)
                .filter(move |&x| self.inside[y * self.w + x])
                .map(move |x| self.centre(x, y))
        })
    }

    /// Mean of the inside cells' centres (`None` when none is inside).
    pub fn centroid(&self) -> Option<DVec2> {
        let (sum, n) = self
            .centres()
            .fold((DVec2::ZERO, 0usize), |(s, n), c| (s + c, n + 1));
        (n > 0).then(|| sum / n as f64)
    }

    /// The distance from `centre` to the outermost inside cell along each
    /// of `angles` directions (angle k at 2 pi k / angles, in pixel
    /// coordinates), to the cell's far edge; 0 where the ray meets none.
    pub fn outline(&self, centre: DVec2, angles: usize) -> Vec<f32> {
        let reach = (self.w.max(self.h) as f64) * self.step * 1.5;
        let dr = self.step * 0.5;
        (0..angles)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / angles as f64;
                let dir = DVec2::new(a.cos(), a.sin());
                let mut last = 0.0;
                let mut r = 0.0;
                while r < reach {
                    if self.contains(centre + dir * r) {
                        last = r + dr;
                    }
                    r += dr;
                }
                last as f32
            })
            .collect()
    }

    /// Connected pieces and holes, ignoring specks of fewer than `speck`
    /// cells (raster noise where a plane grazes the surface). Pieces are
    /// 4-connected and holes 8-connected, so a diagonal pinch is one piece
    /// and not a hole.
    pub fn pieces_and_holes(&self, speck: usize) -> (usize, usize) {
        let pieces = components(&self.inside, self.w, self.h, false)
            .into_iter()
            .filter(|c| c.cells.len() >= speck)
            .count();
        let outside: Vec<bool> = self.inside.iter().map(|&b| !b).collect();
        let holes = components(&outside, self.w, self.h, true)
            .into_iter()
            .filter(|c| !c.touches_border && c.cells.len() >= speck)
            .count();
        (pieces, holes)
    }
}
