//! Which tet holds a point: a uniform grid of cells, each listing the tets
//! whose bounding boxes meet it. Written here rather than taken from a
//! crate: the spatial-index crates index points or boxes without the
//! barycentric test and the nearest-tet fallback a cut needs.

use glam::DVec3;

use crate::tetra::TetMesh;

/// Barycentric coordinates down to this count as inside (points on a face).
const INSIDE_EPS: f64 = 1e-9;

/// Built over one mesh, and given that mesh at every query (it holds no
/// reference, so a model can own both).
pub struct Locator {
    /// The mesh's tet count, to catch a query with another mesh.
    tets_of_mesh: usize,
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Cell `c`'s tets are `tets[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    tets: Vec<u32>,
    /// The tets across each tet's faces (`TetMesh::face_adjacency`), built
    /// on the first point outside the mesh.
    adjacency: std::sync::OnceLock<Vec<[u32; 4]>>,
}

impl Locator {
    /// About two tets per cell along each axis.
    pub fn new(mesh: &TetMesh) -> Locator {
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let ext = (hi - lo).max(DVec3::splat(1e-12));
        let n = mesh.num_tets().max(1) as f64;
        let cell = (ext.x * ext.y * ext.z / n * 4.0)
            .cbrt()
            .max(ext.max_element() / 512.0);
        let dims = (ext / cell)
            .to_array()
            .map(|e| (e.ceil() as usize).clamp(1, 512));
        let index = |p: DVec3| -> [usize; 3] {
            let q = (p - lo) / cell;
            [0, 1, 2].map(|a| (q[a].floor().max(0.0) as usize).min(dims[a] - 1))
        };
        let cells = dims[0] * dims[1] * dims[2];
        let flat = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        let mut count = vec![0u32; cells + 1];
        let boxes: Vec<([usize; 3], [usize; 3])> = (0..mesh.num_tets())
            .map(|t| {
                let c = mesh.corners(t);
                let (a, b) = c
                    .iter()
                    .fold((c[0], c[0]), |(a, b), &p| (a.min(p), b.max(p)));
                (index(a), index(b))
            })
            .collect();
        let each = |(a, b): &([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        f(flat([x, y, z]));
                    }
                }
            }
        };
        for b in &boxes {
            each(b, &mut |c| count[c + 1] += 1);
        }
        for c in 0..cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut tets = vec![0u32; count[cells] as usize];
        for (t, b) in boxes.iter().enumerate() {
            each(b, &mut |c| {
                tets[fill[c] as usize] = t as u32;
                fill[c] += 1;
            });
        }
        Locator {
            tets_of_mesh: mesh.num_tets(),
            lo,
            cell,
            dims,
            start: count,
            tets,
            adjacency: std::sync::OnceLock::new(),
        }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        4 * (self.start.len() + self.tets.len()) + self.adjacency.get().map_or(0, |a| 16 * a.len())
    }

    fn cell_of(&self, p: DVec3) -> Option<[usize; 3]> {
        let q = (p - self.lo) / self.cell;
        let c = [0, 1, 2].map(|a| q[a].floor());
        (0..3)
            .all(|a| c[a] >= 0.0 && (c[a] as usize) < self.dims[a])
            .then(|| c.map(|x| x as usize))
    }

    fn in_cell(&self, c: [usize; 3]) -> &[u32] {
        let i = c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2]);
        &self.tets[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// The tet holding `p` and `p`'s barycentric coordinates in it.
    pub fn locate(&self, mesh: &TetMesh, p: DVec3) -> Option<(usize, [f64; 4])> {
        debug_assert_eq!(mesh.num_tets(), self.tets_of_mesh, "the locator's own mesh");
        let c = self.cell_of(p)?;
        self.in_cell(c).iter().find_map(|&t| {
            let b = barycentric(&mesh.corners(t as usize), p);
            b.iter()
                .all(|&x| x >= -INSIDE_EPS)
                .then_some((t as usize, b))
        })
    }

    /// `locate`, or for a point outside the mesh the closest point of the
    /// tets around the one with the nearest barycentre (it and two rings of
    /// its face neighbours), and its tet: section points on the input
    /// surface can fall just outside the tet boundary, which lies within
    /// about a cell of it, and the colour there is then the boundary's,
    /// continuous along the section's edge.
    pub fn locate_or_nearest(&self, mesh: &TetMesh, p: DVec3) -> (usize, [f64; 4]) {
        if let Some(hit) = self.locate(mesh, p) {
            return hit;
        }
        let q = (p - self.lo) / self.cell;
        let centre = [0, 1, 2].map(|a| (q[a].floor().max(0.0) as usize).min(self.dims[a] - 1));
        let mut nearest: Option<(f64, usize)> = None;
        for ring in 0..self.dims.iter().copied().max().unwrap_or(1) {
            let lo = centre.map(|c| c.saturating_sub(ring));
            let hi = [0, 1, 2].map(|a| (centre[a] + ring).min(self.dims[a] - 1));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        for &t in self.in_cell([x, y, z]) {
                            let c = mesh.corners(t as usize);
                            let d = ((c[0] + c[1] + c[2] + c[3]) / 4.0).distance_squared(p);
                            if nearest
                                .is_none_or(|(bd, bt)| d < bd || (d == bd && (t as usize) < bt))
                            {
                                nearest = Some((d, t as usize));
                            }
                        }
                    }
                }
            }
            if nearest.is_some() {
                break;
            }
        }
        let Some((_, first)) = nearest else {
            return (0, [0.25; 4]);
        };
        let adjacency = self
            .adjacency
            .get_or_init(|| mesh.face_adjacency().unwrap_or_default());
        let mut around = vec![first];
        for _ in 0..2 {
            let ring: Vec<usize> = around
                .iter()
                .flat_map(|&t| {
                    adjacency
                        .get(t)
                        .copied()
                        .unwrap_or([crate::tetra::mesh::NO_NEIGHBOUR; 4])
                })
                .filter(|&n| n != crate::tetra::mesh::NO_NEIGHBOUR)
                .map(|n| n as usize)
                .collect();
            around.extend(ring);
            around.sort_unstable();
            around.dedup();
        }
        let (t, at) = around
            .iter()
            .map(|&t| (t, closest_in_tet(&mesh.corners(t), p)))
            .min_by(|a, b| {
                a.1.distance_squared(p)
                    .total_cmp(&b.1.distance_squared(p))
                    .then(a.0.cmp(&b.0))
            })
            .expect("one tet at least");
        let b = barycentric(&mesh.corners(t), at).map(|x| x.max(0.0));
        let sum: f64 = b.iter().sum();
        (
            t,
            if sum > 0.0 {
                b.map(|x| x / sum)
            } else {
                [0.25; 4]
            },
        )
    }
}

/// The point of the tet `c` closest to `p`.
fn closest_in_tet(c: &[DVec3; 4], p: DVec3) -> DVec3 {
    if barycentric(c, p).iter().all(|&x| x >= 0.0) {
        return p;
    }
    crate::tetra::mesh::TET_FACES
        .iter()
        .map(|f| crate::mesh::closest::closest_point(p, &[c[f[0]], c[f[1]], c[f[2]]]))
        .min_by(|a, b| a.distance_squared(p).total_cmp(&b.distance_squared(p)))
        .unwrap_or(p)
}

/// Barycentric coordinates of `p` in the tet `c`.
pub fn barycentric(c: &[DVec3; 4], p: DVec3) -> [f64; 4] {
    let m = glam::DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
    let det = m.determinant();
    if det == 0.0 {
        return [f64::NAN; 4];
    }
    let l = m.inverse() * (p - c[0]);
    [1.0 - l.x - l.y - l.z, l.x, l.y, l.z]
}
