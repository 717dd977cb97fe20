//! Shapes generated in code, with known topology, for tests and benchmarks:
//! a torus (genus 1), slabs with g holes (genus g), an open cylinder (two
//! boundary loops) and an icosphere (genus 0). All are manifold, counter-
//! clockwise seen from outside, and deterministic.

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;

use super::TriMesh;

/// Torus around the z axis with tube radius `minor` at distance `major`,
/// `n_major` segments around the axis and `n_minor` around the tube.
pub fn torus(major: f64, minor: f64, n_major: usize, n_minor: usize) -> TriMesh {
    let mut positions = Vec::with_capacity(n_major * n_minor);
    for i in 0..n_major {
        let u = TAU * i as f64 / n_major as f64;
        for j in 0..n_minor {
            let v = TAU * j as f64 / n_minor as f64;
            let r = major + minor * v.cos();
            positions.push(DVec3::new(r * u.cos(), r * u.sin(), minor * v.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % n_major) * n_minor + j % n_minor) as u32;
    TriMesh::new(positions, grid_triangles(n_major, n_minor, id))
}

/// Cylinder of `radius` along z from 0 to `height`, without caps: two
/// boundary loops.
pub fn open_cylinder(radius: f64, height: f64, n_around: usize, n_along: usize) -> TriMesh {
    let mut positions = Vec::with_capacity(n_around * (n_along + 1));
    for i in 0..n_around {
        let u = TAU * i as f64 / n_around as f64;
        for j in 0..=n_along {
            let z = height * j as f64 / n_along as f64;
            positions.push(DVec3::new(radius * u.cos(), radius * u.sin(), z));
        }
    }
    let id = |i: usize, j: usize| ((i % n_around) * (n_along + 1) + j) as u32;
    TriMesh::new(positions, grid_triangles(n_around, n_along, id))
}

/// Two triangles per cell of an `n_u` x `n_v` grid, counter-clockwise with
/// the normal along d/du x d/dv.
fn grid_triangles(n_u: usize, n_v: usize, id: impl Fn(usize, usize) -> u32) -> Vec<[u32; 3]> {
    let mut tris = Vec::with_capacity(2 * n_u * n_v);
    for i in 0..n_u {
        for j in 0..n_v {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

/// A closed surface of genus `holes`: a slab pierced by `holes` square holes
/// in a row, built from `cells` x `cells` x `cells` cubes per hole-sized
/// block, then rounded by `smoothing` Taubin steps (which keep the topology).
pub fn holed_slab(holes: usize, cells: usize, smoothing: usize) -> TriMesh {
    let h = cells.max(1) as i64;
    let nx = (2 * holes as i64 + 1) * h;
    let ny = 3 * h;
    let solid = |i: i64, j: i64| {
        if i < 0 || j < 0 || i >= nx || j >= ny {
            return false;
        }
        let in_hole_row = (h..2 * h).contains(&j);
        let in_hole_column = i >= h && (i / h) % 2 == 1;
        !(in_hole_row && in_hole_column)
    };
    let mut index: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |i: i64, j: i64, k: i64| {
        *index.entry((i, j, k)).or_insert_with(|| {
            positions.push(DVec3::new(i as f64, j as f64, k as f64) / h as f64);
            (positions.len() - 1) as u32
        })
    };
    let mut tris = Vec::new();
    let mut quad = |a: u32, b: u32, c: u32, d: u32| {
        tris.push([a, b, c]);
        tris.push([a, c, d]);
    };
    for i in 0..nx {
        for j in 0..ny {
            if !solid(i, j) {
                continue;
            }
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            // Top (k = h) counter-clockwise from +z, bottom (k = 0) reversed.
            let top = corners.map(|(x, y)| vertex(x, y, h));
            quad(top[0], top[1], top[2], top[3]);
            let bottom = corners.map(|(x, y)| vertex(x, y, 0));
            quad(bottom[0], bottom[3], bottom[2], bottom[1]);
            // Walls where the neighbour across a cell edge is empty.
            let across = [(i, j - 1), (i + 1, j), (i, j + 1), (i - 1, j)];
            for e in 0..4 {
                if solid(across[e].0, across[e].1) {
                    continue;
                }
                let (p, q) = (corners[e], corners[(e + 1) % 4]);
                for k in 0..h {
                    let (pk, qk) = (vertex(p.0, p.1, k + 1), vertex(q.0, q.1, k + 1));
                    let (pb, qb) = (vertex(p.0, p.1, k), vertex(q.0, q.1, k));
                    quad(qk, pk, pb, qb);
                }
            }
        }
    }
    let mut mesh = TriMesh::new(positions, tris);
    taubin_smooth(&mut mesh, smoothing);
    mesh
}

/// Taubin's lambda|mu smoothing (1995) with the uniform Laplacian: shrinks
/// nothing on average, rounds corners, never changes connectivity.
pub fn taubin_smooth(mesh: &mut TriMesh, steps: usize) {
    let n = mesh.num_vertices();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in &mesh.triangles {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            if !neighbours[a as usize].contains(&b) {
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
            }
        }
    }
    for step in 0..2 * steps {
        let factor = if step % 2 == 0 { 0.5 } else { -0.53 };
        let moved: Vec<DVec3> = (0..n)
            .map(|v| {
                let p = mesh.positions[v];
                let nb = &neighbours[v];
                if nb.is_empty() {
                    return p;
                }
                let mean = nb
                    .iter()
                    .map(|&u| mesh.positions[u as usize])
                    .sum::<DVec3>()
                    / nb.len() as f64;
                p + factor * (mean - p)
            })
            .collect();
        mesh.positions = moved;
    }
}

/// Unit sphere: an icosahedron with every triangle split in four
/// `subdivisions` times, vertices pushed onto the sphere.
pub fn icosphere(subdivisions: usize) -> TriMesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<DVec3>| {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    TriMesh::new(positions, tris)
}
