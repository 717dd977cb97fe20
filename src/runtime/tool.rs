//! Carving tools and the tets under them.
//!
//! A tool removes the tets whose centroid it holds: a sphere (a burr at
//! rest) or a capsule, the sphere swept between two points (a burr or a
//! blade moved during one step, so a fast stroke leaves no gaps between
//! steps). Centroids are binned in a uniform grid of about two tets a
//! cell, so finding the tets under a tool visits the cells its box meets,
//! whatever the mesh's size (the step's cost depends on what it removes).
//!
//! A grid rather than a crate's tree (kiddo is one of organtex's
//! dependencies): the query is "every point in a box", answered by cells
//! in the order of the box, without a tree's per-query allocation.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::tetra::TetMesh;

/// A carving tool, in the organ's rest frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tool {
    Sphere {
        centre: DVec3,
        radius: f64,
    },
    /// The sphere of `radius` swept from `a` to `b`.
    Capsule {
        a: DVec3,
        b: DVec3,
        radius: f64,
    },
}

impl Tool {
    /// Refuses positions that are not finite and a radius that is not
    /// positive.
    pub fn check(&self) -> Result<()> {
        let (points, radius) = match *self {
            Tool::Sphere { centre, radius } => ([centre, centre], radius),
            Tool::Capsule { a, b, radius } => ([a, b], radius),
        };
        if let Some(p) = points.iter().find(|p| !p.is_finite()) {
            return Err(Error::invalid(format!(
                "the tool's position {p} is not finite"
            )));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::invalid(format!(
                "the tool's radius must be positive, not {radius}"
            )));
        }
        Ok(())
    }

    /// The box holding the tool.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match *self {
            Tool::Sphere { centre, radius } => (centre - radius, centre + radius),
            Tool::Capsule { a, b, radius } => (a.min(b) - radius, a.max(b) + radius),
        }
    }

    /// Whether `p` lies inside the tool (on its surface counts).
    #[inline]
    pub fn contains(&self, p: DVec3) -> bool {
        match *self {
            Tool::Sphere { centre, radius } => p.distance_squared(centre) <= radius * radius,
            Tool::Capsule { a, b, radius } => {
                let ab = b - a;
                let len2 = ab.length_squared();
                let t = if len2 > 0.0 {
                    ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                p.distance_squared(a + ab * t) <= radius * radius
            }
        }
    }
}

/// Tet centroids binned in a uniform grid.
pub struct CentroidGrid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Cell `c`'s tets are `tets[start[c]..start[c + 1]]`, by id.
    start: Vec<u32>,
    tets: Vec<u32>,
    centroids: Vec<DVec3>,
}

impl CentroidGrid {
    pub fn new(mesh: &TetMesh) -> CentroidGrid {
        let centroids: Vec<DVec3> = (0..mesh.num_tets())
            .map(|t| {
                let c = mesh.corners(t);
                (c[0] + c[1] + c[2] + c[3]) * 0.25
            })
            .collect();
        let (lo, hi) = centroids
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let (lo, hi) = if centroids.is_empty() {
            (DVec3::ZERO, DVec3::ONE)
        } else {
            (lo, hi)
        };
        let ext = (hi - lo).max(DVec3::splat(1e-9));
        let n = centroids.len().max(1) as f64;
        let cell = (ext.x * ext.y * ext.z / n * 2.0)
            .cbrt()
            .max(ext.max_element() / 1024.0);
        let dims = (ext / cell)
            .to_array()
            .map(|e| (e.floor() as usize + 1).clamp(1, 1024));
        let mut grid = CentroidGrid {
            lo,
            cell,
            dims,
            start: Vec::new(),
            tets: vec![0; centroids.len()],
            centroids,
        };
        let cells = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; cells + 1];
        let of: Vec<usize> = grid
            .centroids
            .iter()
            .map(|&p| grid.flat(grid.cell_of(p)))
            .collect();
        for &c in &of {
            count[c + 1] += 1;
        }
        for c in 0..cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        for (t, &c) in of.iter().enumerate() {
            grid.tets[fill[c] as usize] = t as u32;
            fill[c] += 1;
        }
        grid.start = count;
        grid
    }

    fn cell_of(&self, p: DVec3) -> [usize; 3] {
        let q = (p - self.lo) / self.cell;
        [0, 1, 2].map(|a| (q[a].floor().max(0.0) as usize).min(self.dims[a] - 1))
    }

    fn flat(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    pub fn centroid(&self, t: usize) -> DVec3 {
        self.centroids[t]
    }

    /// The tets whose centroid `tool` holds, in id order.
    pub fn under(&self, tool: &Tool) -> Vec<u32> {
        let (lo, hi) = tool.bounds();
        let (a, b) = (self.cell_of(lo), self.cell_of(hi));
        let mut out = Vec::new();
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                let row = self.flat([0, y, z]);
                let cells = self.start[row + a[0]] as usize..self.start[row + b[0] + 1] as usize;
                out.extend(
                    self.tets[cells]
                        .iter()
                        .filter(|&&t| tool.contains(self.centroids[t as usize])),
                );
            }
        }
        out.sort_unstable();
        out
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        4 * (self.start.len() + self.tets.len()) + 24 * self.centroids.len()
    }
}
