//! A region's boundary by marching tetrahedra over the voxel grid.
//!
//! Each cube of eight voxel centres is split into six tetrahedra round its
//! main diagonal (Kuhn's split, the same diagonal in every cube, so the
//! split faces of neighbours match). On tetrahedra the piecewise-linear
//! field has no ambiguous case, and its level set, with no voxel exactly on
//! it (a voxel at the level counts as inside), is a closed 2-manifold: every
//! edge in two triangles, every vertex's triangles one fan. Marching cubes
//! needs its ambiguous cases resolved to promise that; VTK's flying edges
//! and scikit-image's marching cubes both leave non-manifold vertices where
//! voxels touch by an edge or a corner (issue 40). The price is about twice
//! the triangles, which smoothing and decimation then work on.
//!
//! Vertices sit on grid edges, one per edge crossed, shared by every
//! tetrahedron round that edge; the volume is padded by a layer of outside
//! so the surface closes at the volume's border.

// Fx hashing: a vertex per cut edge of the grid, millions for a scan;
// the maps' order is never read.
use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;

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

/// Corner offsets of the six tetrahedra of a cube: the paths from (0,0,0)
/// to (1,1,1) one axis at a time, in every order.
const KUHN: [[[usize; 3]; 4]; 6] = {
    const fn path(order: [usize; 3]) -> [[usize; 3]; 4] {
        let mut out = [[0; 3]; 4];
        let mut p = [0usize; 3];
        let mut k = 0;
        while k < 3 {
            p[order[k]] = 1;
            out[k + 1] = p;
            k += 1;
        }
        out
    }
    [
        path([0, 1, 2]),
        path([0, 2, 1]),
        path([1, 0, 2]),
        path([1, 2, 0]),
        path([2, 0, 1]),
        path([2, 1, 0]),
    ]
};

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
    let key = |p: [i64; 3]| -> u64 {
        let (px, py) = (nx as u64 + 2, ny as u64 + 2);
        ((p[2] + 1) as u64 * py + (p[1] + 1) as u64) * px + (p[0] + 1) as u64
    };
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut on_edge: HashMap<(u64, u64), u32> = HashMap::default();
    for z in -1..nz as i64 {
        progress::check(progress)?;
        for y in -1..ny as i64 {
            for x in -1..nx as i64 {
                let corner = |c: [usize; 3]| [x + c[0] as i64, y + c[1] as i64, z + c[2] as i64];
                let values: [(bool, f32); 8] = std::array::from_fn(|k| {
                    let c = corner([k & 1, (k >> 1) & 1, (k >> 2) & 1]);
                    at(c[0], c[1], c[2])
                });
                let inside = values.iter().filter(|v| v.0).count();
                if inside == 0 || inside == 8 {
                    continue;
                }
                for tet in &KUHN {
                    let p = tet.map(corner);
                    let v = tet.map(|c| values[c[0] | c[1] << 1 | c[2] << 2]);
                    let (faces, outward) = crossings(&p, &v);
                    for edges in faces {
                        // The crossing on each grid edge, made once.
                        let mut ids = edges.map(|(a, b)| {
                            let (ka, kb) = (key(p[a]), key(p[b]));
                            *on_edge.entry((ka.min(kb), ka.max(kb))).or_insert_with(|| {
                                let (fa, fb) = (v[a].1, v[b].1);
                                // Against the padding (no value) the
                                // crossing sits where the binary level
                                // would, halfway.
                                let t = if fa.is_finite() && fb.is_finite() {
                                    (fa / (fa - fb)).clamp(1e-3, 1.0 - 1e-3) as f64
                                } else {
                                    0.5
                                };
                                let (pa, pb) = (point(p[a]), point(p[b]));
                                positions.push(pa + (pb - pa) * t);
                                positions.len() as u32 - 1
                            })
                        });
                        let [a, b, c] = ids.map(|i| positions[i as usize]);
                        if (b - a).cross(c - a).dot(outward) < 0.0 {
                            ids.swap(1, 2);
                        }
                        triangles.push(ids);
                    }
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

/// The triangles of one tetrahedron (corners `p`, values `v`) as the
/// corner pairs of the edges their vertices lie on: one round an inside or
/// an outside corner alone, two across a pair; and the direction from the
/// inside corners to the outside ones, which the triangles face.
fn crossings(p: &[[i64; 3]; 4], v: &[(bool, f32); 4]) -> (Vec<[(usize, usize); 3]>, DVec3) {
    let ins: Vec<usize> = (0..4).filter(|&k| v[k].0).collect();
    let outs: Vec<usize> = (0..4).filter(|&k| !v[k].0).collect();
    let faces = match (ins.as_slice(), outs.as_slice()) {
        (&[i], &[a, b, c]) => vec![[(i, a), (i, b), (i, c)]],
        (&[a, b, c], &[o]) => vec![[(a, o), (b, o), (c, o)]],
        (&[a, b], &[c, d]) => vec![[(a, c), (a, d), (b, d)], [(a, c), (b, d), (b, c)]],
        _ => Vec::new(),
    };
    let centre =
        |ks: &[usize]| ks.iter().map(|&k| point(p[k])).sum::<DVec3>() / ks.len().max(1) as f64;
    (faces, centre(&outs) - centre(&ins))
}
