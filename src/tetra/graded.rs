//! The graded background lattice of isosurface stuffing (Labelle and
//! Shewchuk 2007, sec. 5): fine BCC tets of cell size `h` near the surface,
//! coarser ones inside, so the tet count follows the surface's area rather
//! than the enclosed volume.
//!
//! The lattice comes from a balanced octree of cubes (leaves of size
//! `2^k h`, aligned to their size; leaves touching at a face, an edge or a
//! corner differ by at most one level). Its vertices are the leaves'
//! corners and centres. Every leaf is the union of six pyramids, apex its
//! centre, base a face; the tets fill the double pyramids across the faces:
//! - two leaves of one size share a face: the double pyramid is split
//!   around the axis joining their centres, one tet per segment of the
//!   face's boundary. An unsplit edge gives the BCC tet (both centres and
//!   the edge); an edge carrying a vertex at its midpoint (a smaller leaf
//!   touches it) gives two bisected tets;
//! - a leaf meets four leaves of half its size across a face: the face's
//!   quadrants, each a double pyramid from the big centre to a small one,
//!   split the same way around its axis.
//!   Each tet's faces are then either shared with the tet across them or on
//!   the lattice's outer skin: every triangle `(centre, segment)` is cut
//!   from the same segments on both sides, because whether an edge is split
//!   depends on the edge alone.
//!
//! Only the finest BCC tets may be cut or warped (the stencils and the
//! angle proof are theirs), so a leaf may be coarse only far from the
//! surface, inside (where its tets are kept whole) or outside (where they
//! are dropped): its centre farther from the surface than its
//! neighbourhood reaches (`COARSE_MARGIN`). Whatever the surface (open
//! meshes bend the winding number away from their triangles), this is
//! checked after warping: a tet that is not a finest BCC tet must have four
//! unwarped vertices all inside or all outside, and the leaves of any that
//! does not are split and the lattice rebuilt.

use glam::DVec3;
use rayon::prelude::*;

use super::mesh::TetMesh;
use super::stuffing::{Background, Lattice, key, stuff_background};
use super::winding::Winding;
use crate::error::Result;
use crate::progress::Progress;

/// The coarsest leaves are `2^MAX_LEVEL` finest cells wide.
pub const MAX_LEVEL: u32 = 4;
/// A leaf of size `s` may stay whole when its centre is farther than
/// `COARSE_MARGIN * s + 1.5 h` from the surface. Every tet that is not a
/// finest BCC tet has a leaf of size `s >= 2h` among its two centres, and
/// its vertices lie within `sqrt(1.5^2 + 2 * 0.5^2) s = 1.66 s` of that
/// leaf's centre (its corners at 0.87 s, a twice larger face neighbour's
/// centre at 1.66 s); a vertex farther than `h` from the surface has no
/// cut edge, so is neither cut nor warped.
const COARSE_MARGIN: f64 = 1.75;
/// Rebuilds after the check, at most (each splits the offending leaves one
/// level, so `MAX_LEVEL` always suffice).
const MAX_REBUILDS: u32 = MAX_LEVEL + 1;

/// Memory the graded stuffing holds at its peak (bytes), for a lattice of
/// `cubes` finest cubes over a surface of area `area`: a level byte per
/// cube, and for the band of finest cubes the margin keeps along both sides
/// of the surface (about `14 area / h^2`) their 12 tets and 2 vertices, as
/// `stuffing::estimate_bytes` counts them, plus the tets' background copy.
pub(crate) fn estimate_bytes(cubes: f64, area: f64, h: f64) -> f64 {
    let band = 14.0 * area / (h * h);
    cubes + band * (12.0 * (3.0 * 16.0 + 24.0 / 5.0) + 2.0 * (8.0 + 8.0 + 18.0))
}

/// The balanced octree over the finest cube grid, as the level of the leaf
/// holding each finest cube, and the lattice built on it.
pub(crate) struct Graded {
    /// The finest lattice (origin, `h`, cube counts, padded to multiples
    /// of `2^MAX_LEVEL`).
    fine: Lattice,
    /// Vertices as doubled finest-grid coordinates (corners even, finest
    /// centres odd), packed by `pack`, sorted.
    keys: Vec<u64>,
    /// The tets, in leaf order, positively oriented.
    tets: Vec<[u32; 4]>,
    /// For every vertex that is a leaf's centre, that leaf's index.
    leaf_of: Vec<u32>,
    /// The leaves: origin (finest cubes) and level.
    leaves: Vec<([u32; 3], u8)>,
}

/// Fill the inside with the graded lattice: as `stuffing::stuff_lattice`,
/// refining the octree wherever a coarse tet would be cut or warped.
pub(crate) fn stuff_graded(
    winding: &Winding,
    fine: &Lattice,
    progress: &dyn Progress,
) -> Result<TetMesh> {
    let pad = |n: usize| n.div_ceil(1 << MAX_LEVEL) << MAX_LEVEL;
    let fine = Lattice {
        cubes: fine.cubes.map(pad),
        ..*fine
    };
    let mut split: Vec<([u32; 3], u8)> = Vec::new();
    let mut rebuilds = 0;
    loop {
        progress.stage("graded octree", 0);
        let levels = octree(winding, &fine, &split);
        let graded = Graded::new(fine, levels);
        let (mesh, sign) = stuff_background(winding, &graded, progress)?;
        let bad = graded.offending_leaves(&sign);
        if bad.is_empty() || rebuilds == MAX_REBUILDS {
            return Ok(mesh);
        }
        split.extend(bad);
        split.sort_unstable();
        split.dedup();
        rebuilds += 1;
    }
}

/// The level of every finest cube's leaf: top-down, a cell splits unless
/// it is deep inside (see `COARSE_MARGIN`) and not listed in `split`; then
/// leaves split until neighbours differ by at most one level.
fn octree(winding: &Winding, fine: &Lattice, split: &[([u32; 3], u8)]) -> Vec<u8> {
    let [nx, ny, nz] = fine.cubes;
    let top = 1usize << MAX_LEVEL;
    let blocks: Vec<[usize; 3]> = (0..nz / top)
        .flat_map(|z| (0..ny / top).flat_map(move |y| (0..nx / top).map(move |x| [x, y, z])))
        .collect();
    let h = fine.h;
    let whole = |o: [usize; 3], k: u32| -> bool {
        if k == 0 {
            return true;
        }
        let s = (1usize << k) as f64 * h;
        let centre = fine.origin
            + DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64) * h
            + DVec3::splat(s / 2.0);
        let margin = COARSE_MARGIN * s + 1.5 * h;
        winding.bvh.distance_below(centre, margin) >= margin
    };
    // Per top block, the leaves as (origin, level), depth first.
    let per_block: Vec<Vec<([usize; 3], u32)>> = blocks
        .par_iter()
        .map(|&b| {
            let mut out = Vec::new();
            let mut stack = vec![(b.map(|c| c * top), MAX_LEVEL)];
            while let Some((o, k)) = stack.pop() {
                if whole(o, k) {
                    out.push((o, k));
                } else {
                    let m = 1usize << (k - 1);
                    for c in (0..8).rev() {
                        stack.push((
                            [
                                o[0] + (c & 1) * m,
                                o[1] + (c >> 1 & 1) * m,
                                o[2] + (c >> 2) * m,
                            ],
                            k - 1,
                        ));
                    }
                }
            }
            out
        })
        .collect();
    let index = |c: [usize; 3]| c[0] + nx * (c[1] + ny * c[2]);
    let mut level = vec![0u8; nx * ny * nz];
    // Give the cubes of the leaf at `o` of level `k` the level `to`.
    let set = |level: &mut [u8], o: [usize; 3], k: u32, to: u32| {
        let m = 1usize << k;
        for z in o[2]..o[2] + m {
            for y in o[1]..o[1] + m {
                let row = index([o[0], y, z]);
                level[row..row + m].fill(to as u8);
            }
        }
    };
    for (o, k) in per_block.into_iter().flatten() {
        if k > 0 {
            set(&mut level, o, k, k);
        }
    }
    // Leaves the last build found coarse where they were cut: split the
    // leaf holding each one's origin until it is finer than it was.
    for &(o, k) in split {
        let cube = o.map(|c| c as usize);
        loop {
            let now = level[index(cube)] as u32;
            if now < k as u32 || now == 0 {
                break;
            }
            let mask = !((1usize << now) - 1);
            set(&mut level, cube.map(|c| c & mask), now, now - 1);
        }
    }
    // Balance: a leaf with a neighbour two or more levels finer splits.
    // Splitting only refines, so this ends; each pass runs over the leaves
    // in index order, so the result does not depend on threads.
    loop {
        let leaves = leaves_of(&level, fine.cubes);
        let too_coarse: Vec<([usize; 3], u32)> = leaves
            .par_iter()
            .filter(|&&(o, k)| {
                k >= 2 && finest_around(&level, fine.cubes, o, k).saturating_add(1) < k
            })
            .map(|&(o, k)| (o, k as u32))
            .collect();
        if too_coarse.is_empty() {
            return level;
        }
        for (o, k) in too_coarse {
            set(&mut level, o, k, k - 1);
        }
    }
}

/// Every leaf (origin, level), in index order of its origin.
fn leaves_of(level: &[u8], cubes: [usize; 3]) -> Vec<([usize; 3], u8)> {
    let [nx, ny, nz] = cubes;
    let mut out = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let k = level[x + nx * (y + ny * z)];
                let m = (1usize << k) - 1;
                if x & m == 0 && y & m == 0 && z & m == 0 {
                    out.push(([x, y, z], k));
                }
            }
        }
    }
    out
}

/// The finest level among the cubes touching the leaf at `o` of level `k`
/// from outside (faces, edges and corners), within the grid.
fn finest_around(level: &[u8], cubes: [usize; 3], o: [usize; 3], k: u8) -> u8 {
    let m = 1i64 << k;
    let [nx, ny, nz] = cubes.map(|c| c as i64);
    let o = o.map(|c| c as i64);
    let mut finest = u8::MAX;
    for z in o[2] - 1..=o[2] + m {
        for y in o[1] - 1..=o[1] + m {
            let inner_row = (o[2]..o[2] + m).contains(&z) && (o[1]..o[1] + m).contains(&y);
            let mut x = o[0] - 1;
            while x <= o[0] + m {
                if (0..nx).contains(&x) && (0..ny).contains(&y) && (0..nz).contains(&z) {
                    finest = finest.min(level[(x + nx * (y + ny * z)) as usize]);
                }
                // Inside the leaf's rows only the two cubes beside it count.
                x += if inner_row && x == o[0] - 1 { m + 1 } else { 1 };
            }
        }
    }
    finest
}

/// Pack doubled coordinates (each below 2^21) into a vertex key.
#[inline]
fn pack(c: [u64; 3]) -> u64 {
    c[0] | c[1] << 21 | c[2] << 42
}

#[inline]
fn unpack(k: u64) -> [u64; 3] {
    let mask = (1 << 21) - 1;
    [k & mask, k >> 21 & mask, k >> 42]
}

impl Graded {
    fn new(fine: Lattice, level: Vec<u8>) -> Graded {
        let cubes = fine.cubes;
        let leaves: Vec<([u32; 3], u8)> = leaves_of(&level, cubes)
            .into_iter()
            .map(|(o, k)| (o.map(|c| c as u32), k))
            .collect();
        let mut keys: Vec<u64> = leaves
            .par_iter()
            .flat_map_iter(|&(o, k)| {
                let d = o.map(|c| 2 * c as u64);
                let m = 2u64 << k;
                (0..8)
                    .map(move |c| {
                        pack([
                            d[0] + (c & 1) * m,
                            d[1] + (c >> 1 & 1) * m,
                            d[2] + (c >> 2) * m,
                        ])
                    })
                    .chain(std::iter::once(pack(d.map(|x| x + m / 2))))
            })
            .collect();
        keys.par_sort_unstable();
        keys.dedup();
        let mut graded = Graded {
            fine,
            keys,
            tets: Vec::new(),
            leaf_of: Vec::new(),
            leaves,
        };
        graded.leaf_of = vec![u32::MAX; graded.keys.len()];
        for (i, &(o, k)) in graded.leaves.iter().enumerate() {
            let c = graded.centre(o, k);
            graded.leaf_of[c as usize] = i as u32;
        }
        let per_leaf: Vec<Vec<[u32; 4]>> = (0..graded.leaves.len())
            .into_par_iter()
            .map(|i| graded.tets_of_leaf(i, &level))
            .collect();
        graded.tets = per_leaf.into_iter().flatten().collect();
        graded
    }

    /// The vertex at doubled coordinates `c`, if there is one.
    #[inline]
    fn vertex(&self, c: [u64; 3]) -> Option<u32> {
        self.keys.binary_search(&pack(c)).ok().map(|i| i as u32)
    }

    fn centre(&self, o: [u32; 3], k: u8) -> u32 {
        let half = 1u64 << k;
        self.vertex(o.map(|c| 2 * c as u64 + half))
            .expect("every leaf's centre is a vertex")
    }

    /// The tets in the double pyramids across leaf `i`'s faces that it
    /// owns: toward a same-size leaf on the positive side, and toward any
    /// smaller leaves.
    fn tets_of_leaf(&self, i: usize, level: &[u8]) -> Vec<[u32; 4]> {
        let (o, k) = self.leaves[i];
        let [nx, ny, nz] = self.fine.cubes;
        let m = 1u32 << k;
        let c = self.centre(o, k);
        let level_at = |p: [i64; 3]| -> Option<u8> {
            let inside = (0..nx as i64).contains(&p[0])
                && (0..ny as i64).contains(&p[1])
                && (0..nz as i64).contains(&p[2]);
            inside.then(|| level[p[0] as usize + nx * (p[1] as usize + ny * p[2] as usize)])
        };
        let mut out = Vec::new();
        for axis in 0..3 {
            let (b, cc) = ((axis + 1) % 3, (axis + 2) % 3);
            for positive in [false, true] {
                // The face's plane and a cube just across it.
                let plane = if positive { o[axis] + m } else { o[axis] };
                let mut across = o.map(|x| x as i64);
                across[axis] = if positive {
                    plane as i64
                } else {
                    plane as i64 - 1
                };
                let Some(k2) = level_at(across) else { continue };
                // Squares of the face to fill: (corner in cubes, size).
                let squares: Vec<([u32; 3], u32)> = if k2 == k && positive {
                    vec![(o, m)]
                } else if k2 < k {
                    let h = m / 2;
                    (0..4)
                        .map(|q| {
                            let mut s = o;
                            s[b] += (q & 1) * h;
                            s[cc] += (q >> 1) * h;
                            (s, h)
                        })
                        .collect()
                } else {
                    continue;
                };
                for (s, size) in squares {
                    let mut cube = s.map(|x| x as i64);
                    cube[axis] = across[axis];
                    let k3 = level_at(cube).expect("a face's neighbour is in the grid");
                    let mut no = cube.map(|x| x as u32);
                    let m3 = 1u32 << k3;
                    for x in &mut no {
                        *x &= !(m3 - 1);
                    }
                    let c2 = self.centre(no, k3);
                    // The square's corners in doubled coordinates, in turn.
                    let corner = |db: u32, dc: u32| -> [u64; 3] {
                        let mut p = s;
                        p[axis] = plane;
                        p[b] += db * size;
                        p[cc] += dc * size;
                        p.map(|x| 2 * x as u64)
                    };
                    let ring = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                    for e in 0..4 {
                        self.segments(ring[e], ring[(e + 1) % 4], &mut |p, q| {
                            out.push([c, c2, p, q]);
                        });
                    }
                }
            }
        }
        // Orient positively. A finest BCC tet takes the uniform lattice's
        // order (`Lattice::tets_of_slab`: its long corner edge, lower end
        // first, then the centres), which the stencils' choices follow, so
        // the graded mesh's boundary is the uniform one's.
        for t in &mut out {
            if self.is_finest_bcc(t) {
                let c = t.map(|v| unpack(self.keys[v as usize]));
                if c[2] > c[3] {
                    t.swap(2, 3);
                }
                *t = [t[2], t[3], t[0], t[1]];
            }
            let p = t.map(|v| self.position_of(v));
            if super::mesh::signed_volume(&p) < 0.0 {
                t.swap(2, 3);
            }
        }
        out
    }

    /// The segments of the edge from `a` to `b` (doubled coordinates): the
    /// edge itself, or its halves, recursively, where its midpoint is a
    /// vertex.
    fn segments(&self, a: [u64; 3], b: [u64; 3], emit: &mut dyn FnMut(u32, u32)) {
        let mid = [0, 1, 2].map(|i| (a[i] + b[i]) / 2);
        let long = (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap_or(0);
        if long >= 4 && self.vertex(mid).is_some() {
            self.segments(a, mid, emit);
            self.segments(mid, b, emit);
            return;
        }
        let va = self.vertex(a).expect("a leaf's corner is a vertex");
        let vb = self.vertex(b).expect("a leaf's corner is a vertex");
        emit(va, vb);
    }

    fn position_of(&self, v: u32) -> DVec3 {
        let c = unpack(self.keys[v as usize]);
        self.fine.origin + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * (self.fine.h / 2.0)
    }

    /// Whether tet `t` is a finest BCC tet: two long edges of one cell
    /// (doubled coordinates differ by 2 on one axis) and four short ones
    /// (by 1 on every axis).
    fn is_finest_bcc(&self, t: &[u32; 4]) -> bool {
        let c = t.map(|v| unpack(self.keys[v as usize]));
        let mut long = 0;
        for i in 0..4 {
            for j in i + 1..4 {
                let d = [0, 1, 2].map(|a| c[i][a].abs_diff(c[j][a]));
                let mut s = d;
                s.sort_unstable();
                match s {
                    [0, 0, 2] => long += 1,
                    [1, 1, 1] => {}
                    _ => return false,
                }
            }
        }
        long == 2
    }

    /// The leaves to split: those whose centres are vertices of a tet that
    /// is not a finest BCC tet yet is not wholly inside or wholly outside
    /// after warping (`sign` as `stuff_background` left it; a warped vertex
    /// is 0).
    fn offending_leaves(&self, sign: &[i8]) -> Vec<([u32; 3], u8)> {
        let mut bad: Vec<([u32; 3], u8)> = self
            .tets
            .par_iter()
            .filter(|t| {
                let s = sign[t[0] as usize];
                (s == 0 || t.iter().any(|&v| sign[v as usize] != s)) && !self.is_finest_bcc(t)
            })
            .flat_map_iter(|t| {
                t.iter()
                    .filter_map(|&v| match self.leaf_of[v as usize] {
                        u32::MAX => None,
                        l => Some(self.leaves[l as usize]),
                    })
                    .filter(|&(_, k)| k > 0)
                    .collect::<Vec<_>>()
            })
            .collect();
        bad.sort_unstable();
        bad.dedup();
        bad
    }
}

impl Background for Graded {
    fn num_vertices(&self) -> usize {
        self.keys.len()
    }
    fn position(&self, v: u32) -> DVec3 {
        self.position_of(v)
    }
    fn h(&self) -> f64 {
        self.fine.h
    }
    fn is_long(&self, u: u32, v: u32) -> bool {
        let odd = |v: u32| unpack(self.keys[v as usize])[0] % 2 == 1;
        odd(u) == odd(v)
    }
    fn is_odd(&self, u: u32, v: u32) -> bool {
        let (a, b) = (unpack(self.keys[u as usize]), unpack(self.keys[v as usize]));
        let (corner, centre) = if a[0] % 2 == 1 { (b, a) } else { (a, b) };
        (0..3).filter(|&i| centre[i] < corner[i]).count() % 2 == 1
    }
    fn cut_edges(&self, sign: &[i8]) -> Vec<u64> {
        let mut edges: Vec<u64> = self
            .tets
            .par_iter()
            .flat_map_iter(|t| {
                (0..4)
                    .flat_map(move |i| (i + 1..4).map(move |j| (t[i], t[j])))
                    .filter(|&(u, v)| sign[u as usize] as i32 * sign[v as usize] as i32 == -1)
                    .map(|(u, v)| key(u, v))
            })
            .collect();
        edges.par_sort_unstable();
        edges.dedup();
        edges
    }
    fn num_chunks(&self) -> usize {
        self.tets.len().div_ceil(CHUNK)
    }
    fn tets_of_chunk(&self, i: usize, emit: &mut dyn FnMut([u32; 4])) {
        let end = (i * CHUNK + CHUNK).min(self.tets.len());
        for &t in &self.tets[i * CHUNK..end] {
            emit(t);
        }
    }
}

/// Tets per chunk for the stencil step.
const CHUNK: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tetra::mesh::dihedral_angles;

    /// The graded lattice over a sphere, before any stuffing, is a valid
    /// complex that fills the box: positive tets whose volumes sum to the
    /// box's (less the half-cell skin the BCC tets leave), every face shared
    /// by two tets except on that skin, coarse leaves deep inside and
    /// outside. Its dihedral angles are reported against the BCC tets'.
    #[test]
    fn the_graded_lattice_is_a_conforming_complex() {
        let mesh = crate::mesh::shapes::icosphere(4);
        let winding = Winding::new(&mesh);
        let h = 0.05;
        let fine = Lattice::covering(DVec3::splat(-1.0), DVec3::splat(1.0), h);
        let pad = |n: usize| n.div_ceil(1 << MAX_LEVEL) << MAX_LEVEL;
        let fine = Lattice {
            cubes: fine.cubes.map(pad),
            ..fine
        };
        let graded = Graded::new(fine, octree(&winding, &fine, &[]));
        let levels: Vec<u8> = graded.leaves.iter().map(|l| l.1).collect();
        assert!(levels.iter().any(|&k| k >= 2), "some coarse leaves");
        let m = TetMesh {
            positions: (0..graded.keys.len() as u32)
                .map(|v| graded.position_of(v))
                .collect(),
            tets: graded.tets.clone(),
            ..Default::default()
        };
        m.validate().expect("positive tets");
        m.face_adjacency().expect("no face shared by three tets");
        // Boundary faces lie on the skin: within half a coarsest leaf of the
        // box's sides (with the volume below, no hole hides inside).
        let [nx, ny, nz] = fine.cubes.map(|c| c as f64 * h);
        let hi = fine.origin + DVec3::new(nx, ny, nz);
        for f in m.boundary_triangles() {
            for v in f {
                let p = m.positions[v as usize];
                let skin = h * (1 << (MAX_LEVEL - 1)) as f64 * 1.01;
                let near = (p - fine.origin).min_element() < skin || (hi - p).min_element() < skin;
                assert!(near, "an inner face is on the boundary at {p}");
            }
        }
        // The double pyramids across inner faces fill the box less the
        // pyramids (centre, face) of leaf faces on the box's sides.
        let mut expected = nx * ny * nz;
        for &(o, k) in &graded.leaves {
            let m = 1u32 << k;
            let s = m as f64 * h;
            for (&at, &n) in o.iter().zip(&fine.cubes) {
                let sides = (at == 0) as u32 + (at + m == n as u32) as u32;
                expected -= sides as f64 * s * s * s / 6.0;
            }
        }
        let v = m.volume();
        assert!(
            (v - expected).abs() < 1e-9 * expected,
            "volume {v} against {expected}"
        );
        let uniform = 12.0 * (fine.cubes.iter().product::<usize>() as f64);
        assert!(
            (m.num_tets() as f64) < 0.5 * uniform,
            "{} tets",
            m.num_tets()
        );
        let (mut lo, mut hi_angle) = (180.0f64, 0.0f64);
        for t in &m.tets {
            for a in dihedral_angles(&t.map(|v| m.positions[v as usize])) {
                lo = lo.min(a.to_degrees());
                hi_angle = hi_angle.max(a.to_degrees());
            }
        }
        eprintln!(
            "graded lattice: {} tets, dihedral {lo:.2} to {hi_angle:.2} deg",
            m.num_tets()
        );
        assert!(lo >= crate::tetra::MIN_DIHEDRAL && hi_angle <= crate::tetra::MAX_DIHEDRAL);
    }
}
