//! A region's boundary: marching cubes over the voxel grid, with the cube
//! table of `cubes`, which gives each cube the surface marching
//! tetrahedra over Kuhn's split would, rebuilt over the cube's twelve
//! edges. On tetrahedra the piecewise-linear field has no ambiguous case,
//! and its level set, with no voxel exactly on it (a voxel at the level
//! counts as inside), is a closed 2-manifold: every edge in two
//! triangles, every vertex's triangles one fan. Marching cubes needs its
//! ambiguous cases resolved to promise that; VTK's flying edges and
//! scikit-image's marching cubes both leave non-manifold vertices where
//! voxels touch by an edge or a corner (issue 40). The table keeps the
//! tetrahedra's topology at marching cubes' triangle count, a third of
//! theirs, which smoothing and decimation then work on.
//!
//! Vertices sit on grid edges, one per edge crossed, shared by every cube
//! round that edge (and one at the centre of the few cube pieces that
//! need one, `cubes`); the volume is padded by a layer of outside so the
//! surface closes at the volume's border.

// Fx hashing: a vertex per cut edge of the grid, millions for a scan;
// the maps' order is never read.
use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;

use super::cubes;
use crate::error::Result;
use crate::mesh::TriMesh;
use crate::progress::{self, Progress};

/// The field the surface is a level set of.
#[derive(Clone, Copy)]
pub enum Field<'a> {
    /// Inside or not, per voxel: the level 1/2, halfway between centres.
    Binary(&'a [bool]),
    /// Values and the level: inside where a value is at least the level.
    Scalar(&'a [f32], f32),
}

impl Field<'_> {
    /// Inside, and the value's distance above the level (for the crossing).
    #[inline]
    fn at(&self, i: usize) -> (bool, f32) {
        match *self {
            Field::Binary(b) => (b[i], if b[i] { 0.5 } else { -0.5 }),
            Field::Scalar(v, level) => (v[i] >= level, v[i] - level),
        }
    }
}

/// The level set of `field` over a grid of `size` voxels, in voxel
/// coordinates (voxel centres at whole numbers), faces counter-clockwise
/// seen from outside.
pub fn march(size: [usize; 3], field: Field, progress: &dyn Progress) -> Result<TriMesh> {
    let [nx, ny, nz] = size;
    // The padded grid runs from -1 to n along each axis; outside there.
    let at = |x: i64, y: i64, z: i64| -> (bool, f32) {
        if x < 0 || y < 0 || z < 0 || x >= nx as i64 || y >= ny as i64 || z >= nz as i64 {
            return (false, f32::NEG_INFINITY);
        }
        field.at((z as usize * ny + y as usize) * nx + x as usize)
    };
    // An edge of the padded grid: its lower corner's index, times three,
    // plus its axis.
    let key = |p: [i64; 3], axis: u8| -> u64 {
        let (px, py) = (nx as u64 + 2, ny as u64 + 2);
        (((p[2] + 1) as u64 * py + (p[1] + 1) as u64) * px + (p[0] + 1) as u64) * 3 + axis as u64
    };
    let table = cubes::table();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut on_edge: HashMap<u64, u32> = HashMap::default();
    for z in -1..nz as i64 {
        progress::check(progress)?;
        for y in -1..ny as i64 {
            for x in -1..nx as i64 {
                let corner = |k: u8| {
                    let [cx, cy, cz] = cubes::corner(k as usize);
                    [x + cx as i64, y + cy as i64, z + cz as i64]
                };
                let values: [(bool, f32); 8] = std::array::from_fn(|k| {
                    let c = corner(k as u8);
                    at(c[0], c[1], c[2])
                });
                let mask = (0..8).fold(0u8, |m, k| m | (values[k].0 as u8) << k);
                let case = &table[mask as usize];
                if case.triangles.is_empty() {
                    continue;
                }
                // The crossing on each grid edge, made once.
                let mut ids = [u32::MAX; 12];
                let mut crossing = |id: u8, positions: &mut Vec<DVec3>| -> u32 {
                    let slot = &mut ids[id as usize];
                    if *slot == u32::MAX {
                        let (k, axis) = cubes::EDGES[id as usize];
                        let (a, b) = (k, k | 1 << axis);
                        *slot = *on_edge.entry(key(corner(a), axis)).or_insert_with(|| {
                            let (fa, fb) = (values[a as usize].1, values[b as usize].1);
                            // Against the padding (no value) the crossing
                            // sits where the binary level would, halfway.
                            let t = if fa.is_finite() && fb.is_finite() {
                                (fa / (fa - fb)).clamp(1e-3, 1.0 - 1e-3) as f64
                            } else {
                                0.5
                            };
                            let (pa, pb) = (point(corner(a)), point(corner(b)));
                            positions.push(pa + (pb - pa) * t);
                            positions.len() as u32 - 1
                        });
                    }
                    *slot
                };
                let centres: Vec<u32> = case
                    .centres
                    .iter()
                    .map(|edges| {
                        let mean = edges
                            .iter()
                            .map(|&e| {
                                let id = crossing(e, &mut positions);
                                positions[id as usize]
                            })
                            .sum::<DVec3>()
                            / edges.len() as f64;
                        positions.push(mean);
                        positions.len() as u32 - 1
                    })
                    .collect();
                for t in &case.triangles {
                    triangles.push(t.map(|v| match v {
                        0..12 => crossing(v, &mut positions),
                        _ => centres[v as usize - 12],
                    }));
                }
            }
        }
        progress.advance(1);
    }
    Ok(TriMesh::new(positions, triangles))
}

fn point(p: [i64; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::info::analyse;
    use crate::progress::Silent;
    use crate::rng;

    /// Marching tetrahedra itself over Kuhn's split, the reference the
    /// table's topology is held to: a crossing, at the middle, on every
    /// Kuhn edge of the padded grid crossed.
    fn tetrahedra(size: [usize; 3], inside: &[bool]) -> TriMesh {
        let [nx, ny, nz] = size;
        let at = |p: [i64; 3]| {
            p.iter().zip(size).all(|(&c, n)| c >= 0 && c < n as i64)
                && inside[(p[2] as usize * ny + p[1] as usize) * nx + p[0] as usize]
        };
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let mut on_edge: HashMap<([i64; 3], [i64; 3]), u32> = HashMap::default();
        for z in -1..nz as i64 {
            for y in -1..ny as i64 {
                for x in -1..nx as i64 {
                    let corner = |k: u8| {
                        let [cx, cy, cz] = cubes::corner(k as usize);
                        [x + cx as i64, y + cy as i64, z + cz as i64]
                    };
                    let mask = (0..8).fold(0u8, |m, k| m | (at(corner(k)) as u8) << k);
                    for t in cubes::tet_triangles(mask) {
                        triangles.push(t.map(|(a, b)| {
                            let (pa, pb) = (corner(a), corner(b));
                            *on_edge.entry((pa, pb)).or_insert_with(|| {
                                positions.push((point(pa) + point(pb)) / 2.0);
                                positions.len() as u32 - 1
                            })
                        }));
                    }
                }
            }
        }
        TriMesh::new(positions, triangles)
    }

    #[test]
    fn random_regions_get_marching_tetrahedras_surface_at_under_half_its_faces() {
        let size = [7, 6, 8];
        let (mut cube_faces, mut tet_faces) = (0, 0);
        for seed in 0..60 {
            let fill = 0.2 + 0.6 * rng::unit(seed, &[0]);
            let inside: Vec<bool> = (0..size.iter().product::<usize>())
                .map(|i| rng::unit(seed, &[1, i as u64]) < fill)
                .collect();
            let cubes = march(size, Field::Binary(&inside), &Silent).unwrap();
            let tets = tetrahedra(size, &inside);
            cube_faces += cubes.num_faces();
            tet_faces += tets.num_faces();
            // Closed and manifold (`analyse` refuses a non-manifold mesh),
            // with the same sheets and genera as marching tetrahedra's,
            // as many of them facing out (a piece's outer shell) and in (a
            // void's).
            let [c, t] = [cubes, tets].map(|m| {
                let a = analyse(m, false).unwrap();
                let sheets = crate::mesh::components::Components::find(&a.topology);
                let outward = (0..sheets.count as u32)
                    .filter(|&k| {
                        let volume: f64 = sheets
                            .faces(k)
                            .map(|f| {
                                let [p, q, r] = a.mesh.corners(f.idx());
                                p.dot(q.cross(r))
                            })
                            .sum();
                        volume > 0.0
                    })
                    .count();
                let mut genus = a.report.genus.clone();
                genus.sort_unstable();
                (a.report.boundary_edges, a.report.euler, genus, outward)
            });
            assert_eq!(c.0, 0, "seed {seed}");
            assert_eq!(c, t, "seed {seed}");
        }
        // A third on a scan; more on noise, whose lone voxels are octahedra.
        assert!(
            2 * cube_faces < tet_faces,
            "{cube_faces} against {tet_faces}"
        );
    }
}
