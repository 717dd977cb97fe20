//! Isosurface stuffing (Labelle and Shewchuk, "Isosurface Stuffing: Fast
//! Tetrahedral Meshes with Good Dihedral Angles", SIGGRAPH 2007), uniform
//! variant, with `f = 1/2 - w` (w the generalized winding number, so f is
//! negative inside).
//!
//! 1. The body-centred cubic (BCC) lattice of cell size `h` (sec. 3): the
//!    corners of a cubic grid and the centres of its cubes. Long edges join
//!    neighbours of the same grid (length h), short edges join a centre to
//!    the 8 corners of its cube (length h sqrt(3)/2). Every BCC tetrahedron
//!    is a long corner edge plus a long centre edge, four around each long
//!    corner edge; all are congruent with acute dihedral angles (60 and 90
//!    degrees).
//! 2. `f` at every lattice vertex; a cut point on every edge whose ends have
//!    strictly opposite signs, on the surface (sec. 3: "the cut point is
//!    where f = 0 on the edge").
//! 3. Warping (sec. 3): a cut point closer to an end than alpha times the
//!    edge length (alpha_long, alpha_short by the edge's kind) violates that
//!    end; a violated vertex moves to its closest violating cut point and
//!    takes f = 0, and the cut points on its edges are dropped. Cut points
//!    whose other end is violated too are passed over (see the code).
//! 4. Stencils (sec. 3, fig. 3): each lattice tet is replaced by its part
//!    where f <= 0, by the signs of its four vertices. Quadrilateral faces
//!    of the prisms and pyramids lie in lattice triangles, one long edge
//!    each, and are split the same way from both sides: by the diagonal from
//!    the cut point on the long edge; where the long edge joins the two
//!    lattice vertices of the quadrilateral, by the parity rule (see
//!    `Stencils::touches`).
//!
//! With the paper's alphas (0.24999, 0.41189) the paper proves every
//! dihedral angle lies in [10.7, 164.8] degrees whatever the surface (sec.
//! 4); the proof does not care where on its edge a cut point lies, so cut
//! points are put on the input surface itself. What is checked here: every
//! stencil keeps the bounds for any cut points (unit test below), and warped
//! meshes keep them on every test mesh and on hundreds of randomly placed
//! polyhedra (tests/tetra.rs). A random search over single lattice tets
//! with on-surface vertices warped to the limit along edges of their own
//! tet finds pieces down to 9.3 degrees (a `--0+` pyramid whose apex moved
//! toward an inside vertex), so the bound is asserted on real meshes, not
//! taken as given.
//!
//! Same bytes on any number of threads: every parallel step maps lattice
//! elements in a fixed order and collects in that order.
//!
//! Only the uniform lattice is built; the paper's graded variant (an
//! octree, coarser inside, sec. 5) is left for later.

use glam::DVec3;
use rayon::prelude::*;

use super::mesh::{TetMesh, signed_volume};
use super::winding::{CoarseSigns, Winding, sign_of, signs_along};
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::progress::{self, Progress};

/// Violation threshold on long edges, in edge lengths (sec. 4, the pair
/// proven to give [10.7, 164.8] degrees).
pub const ALPHA_LONG: f64 = 0.24999;
/// Violation threshold on short edges, in edge lengths.
pub const ALPHA_SHORT: f64 = 0.41189;
/// The proven dihedral angle bounds for these alphas, in degrees.
pub const MIN_DIHEDRAL: f64 = 10.7;
pub const MAX_DIHEDRAL: f64 = 164.8;

/// No warp for this vertex.
const NONE: u32 = u32::MAX;
/// Root finding stops when the bracket is this fraction of the edge.
const ROOT_TOL: f64 = 1e-7;

/// The BCC lattice: `cubes` cubes of side `h` from `origin`. Vertex ids:
/// corners `(i, j, k)`, `0 <= i <= nx`, first, then centres of cubes
/// `(i, j, k)`, `0 <= i < nx`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    pub origin: DVec3,
    pub h: f64,
    pub cubes: [usize; 3],
}

impl Lattice {
    /// The lattice of cell size `h` covering the box `lo..hi` with at least
    /// one cell to spare on every side, so the outermost vertices are
    /// outside any surface in the box.
    pub fn covering(lo: DVec3, hi: DVec3, h: f64) -> Lattice {
        let ext = hi - lo;
        // Clamped so an absurd `h` gives an absurd count, which the memory
        // check refuses, rather than an overflow.
        let n = |e: f64| ((e / h).ceil().clamp(0.0, 1e15) as usize).saturating_add(2);
        let cubes = [n(ext.x), n(ext.y), n(ext.z)];
        let size = DVec3::new(cubes[0] as f64, cubes[1] as f64, cubes[2] as f64) * h;
        Lattice {
            origin: (lo + hi) / 2.0 - size / 2.0,
            h,
            cubes,
        }
    }

    /// Vertex and cube counts as floats (no overflow for absurd sizes).
    pub fn counts(&self) -> (f64, f64) {
        let [x, y, z] = self.cubes.map(|c| c as f64);
        ((x + 1.0) * (y + 1.0) * (z + 1.0) + x * y * z, x * y * z)
    }

    pub fn num_corners(&self) -> usize {
        let [x, y, z] = self.cubes;
        (x + 1) * (y + 1) * (z + 1)
    }

    pub fn num_vertices(&self) -> usize {
        let [x, y, z] = self.cubes;
        self.num_corners() + x * y * z
    }

    #[inline]
    fn corner(&self, c: [usize; 3]) -> u32 {
        let [x, y, _] = self.cubes;
        (c[0] + (x + 1) * (c[1] + (y + 1) * c[2])) as u32
    }

    #[inline]
    fn centre(&self, c: [usize; 3]) -> u32 {
        let [x, y, _] = self.cubes;
        (self.num_corners() + c[0] + x * (c[1] + y * c[2])) as u32
    }

    /// Whether vertex `v` is a cube centre, and its integer coordinates.
    #[inline]
    fn site(&self, v: u32) -> (bool, [usize; 3]) {
        let v = v as usize;
        let corners = self.num_corners();
        let (centre, i, [x, y]) = if v < corners {
            (false, v, [self.cubes[0] + 1, self.cubes[1] + 1])
        } else {
            (true, v - corners, [self.cubes[0], self.cubes[1]])
        };
        (centre, [i % x, (i / x) % y, i / (x * y)])
    }

    /// Position of vertex `v`.
    #[inline]
    pub fn position(&self, v: u32) -> DVec3 {
        let (centre, c) = self.site(v);
        let half = if centre { 0.5 } else { 0.0 };
        self.origin
            + self.h * DVec3::new(c[0] as f64 + half, c[1] as f64 + half, c[2] as f64 + half)
    }

    /// Whether `u` and `v` (lattice neighbours) form a long edge: both
    /// corners or both centres.
    #[inline]
    fn is_long(&self, u: u32, v: u32) -> bool {
        let corners = self.num_corners() as u32;
        (u < corners) == (v < corners)
    }

    /// For a short edge: whether it is odd, i.e. the direction from its
    /// corner to its centre, (+-1, +-1, +-1) h/2, has an odd number of
    /// negative components. The two short edges from a vertex to the ends
    /// of a long edge differ in one component, so exactly one is odd.
    #[inline]
    fn is_odd(&self, u: u32, v: u32) -> bool {
        let (uc, a) = self.site(u);
        let (_, b) = self.site(v);
        let (corner, centre) = if uc { (b, a) } else { (a, b) };
        // A centre coordinate i stands at i + 1/2: below the corner's
        // coordinate c exactly when i = c - 1.
        (0..3).filter(|&k| centre[k] < corner[k]).count() % 2 == 1
    }

    /// Neighbours of `v` along lattice edges, with whether the edge is long,
    /// only those after `v` in id order (each edge once). Corner: the next
    /// corner on each axis. Centre: the next centre on each axis and the 8
    /// corners of its cube (all before it; listed here so short edges have
    /// one owner, the centre).
    fn forward_edges(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        let (centre, c) = self.site(v);
        let n = self.cubes;
        for axis in 0..3 {
            let mut d = c;
            d[axis] += 1;
            if centre && d[axis] < n[axis] {
                out.push(self.centre(d));
            } else if !centre && d[axis] <= n[axis] {
                out.push(self.corner(d));
            }
        }
        if centre {
            for k in 0..8 {
                out.push(self.corner([c[0] + (k & 1), c[1] + ((k >> 1) & 1), c[2] + (k >> 2)]));
            }
        }
    }

    /// The BCC tets around the long corner edges starting in slab `slab`
    /// along `axis` (edges from corner `c` to `c + e_axis` with
    /// `c[axis] = slab`), positively oriented. Only edges with all four
    /// cubes around them inside the lattice carry tets.
    fn tets_of_slab(&self, axis: usize, slab: usize, mut emit: impl FnMut([u32; 4])) {
        let n = self.cubes;
        if slab >= n[axis] {
            return;
        }
        // (a, b, c) right-handed, so going (-,-), (+,-), (+,+), (-,+) in the
        // (b, c) plane turns counter-clockwise about the edge direction.
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for jc in 1..n[c] {
            for jb in 1..n[b] {
                let mut p0 = [0; 3];
                p0[axis] = slab;
                p0[b] = jb;
                p0[c] = jc;
                let mut p1 = p0;
                p1[axis] += 1;
                let centre = |db: usize, dc: usize| {
                    let mut q = p0;
                    q[b] = jb + db - 1;
                    q[c] = jc + dc - 1;
                    self.centre(q)
                };
                let ring = [centre(0, 0), centre(1, 0), centre(1, 1), centre(0, 1)];
                let (v0, v1) = (self.corner(p0), self.corner(p1));
                for k in 0..4 {
                    emit([v0, v1, ring[k], ring[(k + 1) % 4]]);
                }
            }
        }
    }
}

/// Refuse what no mesher can fill: no faces, indices out of range,
/// non-finite coordinates, no extent. Returns the bounding box.
pub fn check_input(mesh: &TriMesh) -> Result<(DVec3, DVec3)> {
    if mesh.triangles.is_empty() {
        return Err(Error::invalid(format!(
            "cannot tetrahedralise an empty mesh ({} vertices, no triangles)",
            mesh.num_vertices()
        )));
    }
    let n = mesh.num_vertices() as u32;
    for (f, t) in mesh.triangles.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v >= n) {
            return Err(Error::invalid(format!(
                "face {f} refers to vertex {v}, the mesh has {n} vertices"
            )));
        }
    }
    if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::invalid(format!(
            "vertex {v} has a coordinate that is not a finite number ({}): cannot tetrahedralise",
            mesh.positions[v]
        )));
    }
    let (lo, hi) = mesh
        .triangles
        .iter()
        .flatten()
        .map(|&v| mesh.positions[v as usize])
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    if lo.distance(hi) <= 0.0 {
        return Err(Error::invalid(
            "all faces collapse to one point: nothing to tetrahedralise",
        ));
    }
    Ok((lo, hi))
}

/// Memory the stuffing of `lattice` holds at its peak (bytes), assuming
/// `fill` of the lattice's cubes is inside: per vertex its winding number,
/// sign, warp and new index; per output tet its pre-index and final copy,
/// and a vertex for every five tets.
pub fn estimate_bytes(lattice: &Lattice, fill: f64) -> f64 {
    let (vertices, cubes) = lattice.counts();
    let tets = 12.0 * cubes * fill.clamp(0.0, 1.0) * 1.3;
    vertices * (8.0 + 1.0 + 4.0 + 5.0) + tets * (2.0 * 16.0 + 24.0 / 5.0)
}

/// Steps 2 to 4 on a lattice that fits (checked by `stuff`).
pub(crate) fn stuff_lattice(
    winding: &Winding,
    lattice: &impl Background,
    progress: &dyn Progress,
) -> Result<TetMesh> {
    stuff_background(winding, lattice, progress).map(|(m, _)| m)
}

/// What the stuffing steps read from a background mesh of tets: the
/// uniform BCC lattice here, or the graded one (`super::graded`). Its
/// finest tets must be BCC tets of cell size `h()`, the only ones cut.
pub(crate) trait Background: Sync {
    fn num_vertices(&self) -> usize;
    fn position(&self, v: u32) -> DVec3;
    /// The finest cell size (long edge length).
    fn h(&self) -> f64;
    /// For an edge of a finest tet: both ends cube corners or both centres.
    fn is_long(&self, u: u32, v: u32) -> bool;
    /// For a short edge of a finest tet: see `Lattice::is_odd`.
    fn is_odd(&self, u: u32, v: u32) -> bool;
    /// The sorted keys of the edges whose ends have strictly opposite signs.
    fn cut_edges(&self, sign: &[i8]) -> Vec<u64>;
    /// The tets come in this many chunks, filled in parallel.
    fn num_chunks(&self) -> usize;
    /// The tets of chunk `i`, positively oriented, in a fixed order.
    fn tets_of_chunk(&self, i: usize, emit: &mut dyn FnMut([u32; 4]));
    /// The vertices as rows along x, when they are: consecutive blocks of
    /// (vertices in the block, vertices in each of its rows), each row's
    /// vertices `h` apart in index order, its ends outside the surface.
    fn rows(&self) -> Option<[(usize, usize); 2]> {
        None
    }
}

/// The slabs `tets_of_slab` walks, as chunks: every axis, every slab.
impl Background for Lattice {
    fn num_vertices(&self) -> usize {
        Lattice::num_vertices(self)
    }
    fn position(&self, v: u32) -> DVec3 {
        Lattice::position(self, v)
    }
    fn h(&self) -> f64 {
        self.h
    }
    fn is_long(&self, u: u32, v: u32) -> bool {
        Lattice::is_long(self, u, v)
    }
    fn is_odd(&self, u: u32, v: u32) -> bool {
        Lattice::is_odd(self, u, v)
    }
    fn cut_edges(&self, sign: &[i8]) -> Vec<u64> {
        let mut edges: Vec<u64> = (0..Lattice::num_vertices(self) as u32)
            .into_par_iter()
            .flat_map_iter(|v| {
                let mut out = Vec::with_capacity(11);
                self.forward_edges(v, &mut out);
                let sv = sign[v as usize];
                out.into_iter()
                    .filter(move |&u| sv as i32 * sign[u as usize] as i32 == -1)
                    .map(move |u| key(v, u))
            })
            .collect();
        edges.par_sort_unstable();
        edges
    }
    fn num_chunks(&self) -> usize {
        self.cubes.iter().sum()
    }
    fn tets_of_chunk(&self, i: usize, emit: &mut dyn FnMut([u32; 4])) {
        let (mut axis, mut slab) = (0, i);
        while slab >= self.cubes[axis] {
            slab -= self.cubes[axis];
            axis += 1;
        }
        self.tets_of_slab(axis, slab, emit);
    }
    /// Corners in rows of x + 1, then centres in rows of x; a spare cell
    /// on every side keeps each row's ends outside (`Lattice::covering`).
    fn rows(&self) -> Option<[(usize, usize); 2]> {
        let [x, y, z] = self.cubes;
        Some([(self.num_corners(), x + 1), (x * y * z, x)])
    }
}

/// `sign_of` the winding number at every vertex of the background: by
/// rows (`signs_along`) where the surface is closed and the vertices lie
/// in rows, else vertex by vertex (`CoarseSigns` sparing most queries of a
/// closed surface). Stops early, leaving zeros, when cancelled.
fn lattice_signs(winding: &Winding, lattice: &impl Background, progress: &dyn Progress) -> Vec<i8> {
    let n = lattice.num_vertices();
    let rows = lattice.rows().filter(|_| winding.closed());
    let coarse =
        (winding.closed() && rows.is_none()).then(|| CoarseSigns::new(winding, lattice.h()));
    let mut sign = vec![0i8; n];
    if let Some(blocks) = rows {
        debug_assert!(
            blocks.iter().map(|b| b.0).sum::<usize>() == n
                && blocks.iter().all(|&(count, len)| if len == 0 {
                    count == 0
                } else {
                    count % len == 0
                })
        );
        let mut first = 0;
        for (count, len) in blocks {
            // An empty block (a lattice one cube thin) has no rows to cut.
            if count > 0 {
                sign[first..first + count]
                    .par_chunks_mut(len)
                    .enumerate()
                    .for_each_init(Vec::new, |crossings, (r, row)| {
                        if progress.cancelled() {
                            return;
                        }
                        let start = first + r * len;
                        let point = |k: usize| lattice.position((start + k) as u32);
                        signs_along(winding, point, row, crossings);
                        progress.advance(len as u64);
                    });
            }
            first += count;
        }
    } else {
        sign.par_chunks_mut(4096)
            .enumerate()
            .for_each(|(c, chunk)| {
                if progress.cancelled() {
                    return;
                }
                for (k, s) in chunk.iter_mut().enumerate() {
                    let p = lattice.position((c * 4096 + k) as u32);
                    *s = match coarse.as_ref().and_then(|g| g.sign_at(p)) {
                        Some(known) => known,
                        None => sign_of(winding.at(p)),
                    };
                }
                progress.advance(chunk.len() as u64);
            });
    }
    sign
}

/// `stuff_lattice`, also giving the final sign of every background vertex
/// (0 where it was warped to the surface), which the graded lattice checks.
pub(crate) fn stuff_background(
    winding: &Winding,
    lattice: &impl Background,
    progress: &dyn Progress,
) -> Result<(TetMesh, Vec<i8>)> {
    let n = lattice.num_vertices();

    // 2. f = 1/2 - w at every lattice vertex: its sign is all later steps use.
    progress.stage("winding numbers", n as u64);
    let mut sign = lattice_signs(winding, lattice, progress);
    progress::check(progress)?;
    if !sign.contains(&-1) {
        return Err(Error::invalid(format!(
            "the mesh encloses no lattice vertex at edge length {}: it has no inside (a flat or \
             open sheet, or a mesh whose faces point inwards: winding number below 1/2 everywhere), \
             or the edge length is larger than its thinnest part",
            lattice.h()
        )));
    }

    // Cut points on edges with strictly opposite signs, sorted by edge key.
    let edges = lattice.cut_edges(&sign);
    progress.stage("cut points", edges.len() as u64);
    let cut_t: Vec<f64> = edges
        .par_iter()
        .map_init(Vec::new, |scratch, &k| {
            if progress.cancelled() {
                return 0.5;
            }
            let (a, b) = unkey(k);
            let (pa, pb) = (lattice.position(a), lattice.position(b));
            let t = if sign[a as usize] < 0 {
                root(winding, pa, pb, scratch)
            } else {
                1.0 - root(winding, pb, pa, scratch)
            };
            progress.advance(1);
            t
        })
        .collect();
    progress::check(progress)?;
    let cut_pos: Vec<DVec3> = edges
        .iter()
        .zip(&cut_t)
        .map(|(&k, &t)| {
            let (a, b) = unkey(k);
            lattice.position(a).lerp(lattice.position(b), t)
        })
        .collect();

    // 3. Warping (sec. 3): a cut point closer to an end than alpha times its
    // edge violates that end (alpha < 1/2, so never both). A violated vertex
    // moves to its closest violating cut point and takes f = 0, which drops
    // the cut points on its edges. Where the paper leaves the choice open,
    // a cut point whose other end is violated too is passed over: that end
    // may move and drop it, and moving towards a vertex that moves itself
    // makes the flattest tets. A vertex left with only such cut points is
    // warped afterwards only if one of them survives. On 4000 randomly
    // placed polyhedra the plain closest-point rule reached 10.30 degrees
    // (below the bound; tests/tetra.rs keeps two of them), this one 13.3.
    let mut candidates: Vec<(u32, f64, u32)> = Vec::new();
    for (c, (&k, &t)) in edges.iter().zip(&cut_t).enumerate() {
        let (a, b) = unkey(k);
        let (alpha, len) = if lattice.is_long(a, b) {
            (ALPHA_LONG, lattice.h())
        } else {
            (ALPHA_SHORT, lattice.h() * 3f64.sqrt() / 2.0)
        };
        if t < alpha {
            candidates.push((a, t * len, c as u32));
        } else if 1.0 - t < alpha {
            candidates.push((b, (1.0 - t) * len, c as u32));
        }
    }
    // By vertex, then distance, then cut index: the first acceptable
    // candidate of a vertex is its closest.
    candidates.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)).then(x.2.cmp(&y.2)));
    let other_end = |v: u32, c: u32| {
        let (a, b) = unkey(edges[c as usize]);
        if a == v { b } else { a }
    };
    let mut violated = vec![false; n];
    for &(v, _, _) in &candidates {
        violated[v as usize] = true;
    }
    let mut warp = vec![NONE; n];
    for &(v, _, c) in &candidates {
        if warp[v as usize] == NONE && !violated[other_end(v, c) as usize] {
            warp[v as usize] = c;
        }
    }
    for &(v, _, c) in &candidates {
        if warp[v as usize] == NONE && warp[other_end(v, c) as usize] == NONE {
            warp[v as usize] = c;
        }
    }
    drop(violated);
    for (s, &w) in sign.iter_mut().zip(&warp) {
        if w != NONE {
            *s = 0;
        }
    }

    // 4. Stencils, slab by slab, collected in slab order.
    let stencils = Stencils {
        lattice,
        sign: &sign,
        keys: &edges,
    };
    let position = |v: u32| -> DVec3 {
        let v = v as usize;
        if v < n {
            match warp[v] {
                NONE => lattice.position(v as u32),
                c => cut_pos[c as usize],
            }
        } else {
            cut_pos[v - n]
        }
    };
    progress.stage("stencils", lattice.num_chunks() as u64);
    let pieces: Vec<Vec<[u32; 4]>> = (0..lattice.num_chunks())
        .into_par_iter()
        .map(|chunk| {
            let mut out = Vec::new();
            if progress.cancelled() {
                return out;
            }
            lattice.tets_of_chunk(chunk, &mut |tet| stencils.fill(tet, &mut out));
            progress.advance(1);
            out
        })
        .collect();
    progress::check(progress)?;

    // Number the vertices used, lattice vertices first, in id order.
    let total = n + edges.len();
    let mut new_id = vec![NONE; total];
    for piece in &pieces {
        for tet in piece {
            for &v in tet {
                new_id[v as usize] = 0;
            }
        }
    }
    let mut positions = Vec::new();
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = positions.len() as u32;
            positions.push(position(v as u32));
        }
    }
    let mut tets: Vec<[u32; 4]> = pieces
        .into_iter()
        .flatten()
        .map(|t| t.map(|v| new_id[v as usize]))
        .collect();
    tets.par_iter_mut().for_each(|t| {
        let c = t.map(|v| positions[v as usize]);
        if signed_volume(&c) < 0.0 {
            t.swap(2, 3);
        }
    });
    Ok((
        TetMesh {
            positions,
            tets,
            ..Default::default()
        },
        sign,
    ))
}

#[inline]
pub(crate) fn key(a: u32, b: u32) -> u64 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    ((a as u64) << 32) | b as u64
}

#[inline]
pub(crate) fn unkey(k: u64) -> (u32, u32) {
    ((k >> 32) as u32, k as u32)
}

/// Where `f = 1/2 - w` crosses zero on the segment from `inside` (f < 0)
/// to `outside` (f > 0), as a fraction from `inside`. Where the segment
/// meets the input triangles, the crossing that brackets the sign change is
/// taken exactly (the cut point lies on the surface); elsewhere (across an
/// open hole, where w changes continuously) it is bisected.
fn root(winding: &Winding, inside: DVec3, outside: DVec3, crossings: &mut Vec<f64>) -> f64 {
    winding.bvh.segment_crossings(inside, outside, crossings);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..80 {
        let first = crossings.partition_point(|&t| t <= lo);
        let end = crossings.partition_point(|&t| t < hi);
        let inner = &crossings[first..end.max(first)];
        if inner.len() == 1 {
            return inner[0];
        }
        if hi - lo <= ROOT_TOL {
            break;
        }
        let mid = if inner.len() >= 2 {
            let k = inner.len() / 2;
            0.5 * (inner[k - 1] + inner[k])
        } else {
            0.5 * (lo + hi)
        };
        let w = winding.at(inside.lerp(outside, mid));
        if w > 0.5 {
            lo = mid;
        } else if w < 0.5 {
            hi = mid;
        } else {
            return mid;
        }
    }
    0.5 * (lo + hi)
}

/// What the stencils read: lattice vertex signs after warping (0 for warped
/// vertices) and the sorted keys of the edges carrying cut points. Output
/// tets use pre-indices: a lattice vertex is itself, the cut point of
/// `keys[i]` is `num_vertices + i`.
struct Stencils<'a, B: Background> {
    lattice: &'a B,
    sign: &'a [i8],
    keys: &'a [u64],
}

impl<B: Background> Stencils<'_, B> {
    /// The cut point on the edge `uv` (both ends unwarped, opposite signs,
    /// so it was computed and kept).
    #[inline]
    fn cut(&self, u: u32, v: u32) -> u32 {
        let i = self
            .keys
            .binary_search(&key(u, v))
            .expect("an edge with opposite signs at its ends has a cut point");
        (self.lattice.num_vertices() + i) as u32
    }

    /// The quadrilateral in lattice triangle `(p, u, w)`, `p` positive and
    /// `u`, `w` not, has corners `u`, `w`, cut(p, w), cut(p, u). Returns the
    /// lattice vertex its diagonal touches (the diagonal runs from it to the
    /// cut point on the other one's edge to `p`). Depends on the triangle
    /// alone, so both tets sharing it agree:
    /// - the triangle's long edge is `pu`: the diagonal leaves its cut
    ///   point, so it touches `w` (and symmetrically);
    /// - the long edge is `uw`: parity rule: it touches the one of `u`, `w`
    ///   whose short edge to `p` is odd (`Lattice::is_odd`).
    #[inline]
    fn touches(&self, p: u32, u: u32, w: u32) -> u32 {
        let l = self.lattice;
        if l.is_long(p, u) {
            w
        } else if l.is_long(p, w) || l.is_odd(u, p) {
            u
        } else {
            w
        }
    }

    /// Append the tets filling lattice tet `t` where f <= 0. A tet with no
    /// inside vertex gives none, even with all four on the surface (its
    /// warped corners may flatten it below the bound).
    fn fill(&self, t: [u32; 4], out: &mut Vec<[u32; 4]>) {
        let s = t.map(|v| self.sign[v as usize]);
        let neg = s.iter().filter(|&&x| x < 0).count();
        let pos = s.iter().filter(|&&x| x > 0).count();
        if neg == 0 {
            return;
        }
        if pos == 0 {
            out.push(t);
            return;
        }
        let pick =
            |want: i8| -> Vec<u32> { (0..4).filter(|&i| s[i] == want).map(|i| t[i]).collect() };
        let (negs, zeros, poss) = (pick(-1), pick(0), pick(1));
        match (neg, pos) {
            (1, _) => {
                // One inside vertex: one tet, the outside vertices replaced
                // by the cut points on their edges to it.
                let a = negs[0];
                let mut tet = [a; 4];
                for (slot, &v) in tet[1..].iter_mut().zip(zeros.iter().chain(&poss)) {
                    *slot = if self.sign[v as usize] > 0 {
                        self.cut(a, v)
                    } else {
                        v
                    };
                }
                out.push(tet);
            }
            (2, 1) => self.pyramid(negs[0], negs[1], zeros[0], poss[0], out),
            (2, 2) => self.prism(negs[0], negs[1], poss[0], poss[1], out),
            (3, 1) => self.truncated(&negs, poss[0], out),
            _ => unreachable!("signs of four vertices: {s:?}"),
        }
    }

    /// Two inside vertices `a`, `b`, one on the surface `z`, one outside
    /// `p`: the pyramid with apex `z` over the quadrilateral in `(p, a, b)`.
    fn pyramid(&self, a: u32, b: u32, z: u32, p: u32, out: &mut Vec<[u32; 4]>) {
        let (ca, cb) = (self.cut(a, p), self.cut(b, p));
        if self.touches(p, a, b) == a {
            out.push([z, a, b, cb]);
            out.push([z, a, cb, ca]);
        } else {
            out.push([z, a, b, ca]);
            out.push([z, b, cb, ca]);
        }
    }

    /// Three inside vertices, one outside `p`: the tet minus its corner at
    /// `p`, a prism. `p`'s long edge goes to one of them, `m`; the other two,
    /// `l` and `r`, share the other long edge. The quadrilaterals in
    /// `(p, l, m)` and `(p, m, r)` both take the diagonal from cut(p, m), so
    /// the prism is the tet `(l, m, r, cut(p, m))` plus a pyramid with that
    /// apex over the quadrilateral in `(p, l, r)`, split by parity.
    fn truncated(&self, negs: &[u32], p: u32, out: &mut Vec<[u32; 4]>) {
        let l = self.lattice;
        let k = (0..3).find(|&k| l.is_long(p, negs[k])).unwrap_or(0);
        let m = negs[k];
        let (a, b) = (negs[(k + 1) % 3], negs[(k + 2) % 3]);
        let (cm, ca, cb) = (self.cut(p, m), self.cut(p, a), self.cut(p, b));
        out.push([a, m, b, cm]);
        if self.touches(p, a, b) == a {
            out.push([cm, a, b, cb]);
            out.push([cm, a, cb, ca]);
        } else {
            out.push([cm, a, b, ca]);
            out.push([cm, b, cb, ca]);
        }
    }

    /// Two inside vertices `a`, `b`, two outside `c`, `d`: a prism with
    /// triangles `A = (a, ac, ad)` and `B = (b, bc, bd)` (`ac` the cut point
    /// on `ac`, ...). Its quadrilaterals: Q1 in face `abc`, Q2 in face `abd`
    /// (both set by `touches`), Q3 on the surface, free, split so that the
    /// three diagonals do not turn one way round the prism (which no
    /// triangulation without a new vertex fits). Each diagonal touches one
    /// corner of A; the corner touched twice sees all of B: one tet, plus a
    /// pyramid with that apex over the quadrilateral it does not touch.
    fn prism(&self, a: u32, b: u32, c: u32, d: u32, out: &mut Vec<[u32; 4]>) {
        let (ac, ad, bc, bd) = (
            self.cut(a, c),
            self.cut(a, d),
            self.cut(b, c),
            self.cut(b, d),
        );
        // Corners of A: 0 = a, 1 = ac, 2 = ad. Q1 joins a-ac, Q2 a-ad, Q3 ac-ad.
        let q1 = if self.touches(c, a, b) == a { 0 } else { 1 };
        let q2 = if self.touches(d, a, b) == a { 0 } else { 2 };
        let q3 = match (q1, q2) {
            (0, 2) => 2,
            (1, 0) => 1,
            // Not reached on the BCC lattice (Q1 and Q2 touch different
            // ends when ab is long, and when ab is short Q1 = ac, Q2 = a),
            // but any choice is valid here.
            _ => 1,
        };
        let twice = [0, 1, 2]
            .into_iter()
            .find(|&v| [q1, q2, q3].iter().filter(|&&q| q == v).count() == 2)
            .unwrap_or(0);
        match twice {
            0 => {
                out.push([a, b, bc, bd]);
                if q3 == 1 {
                    out.push([a, ac, bc, bd]);
                    out.push([a, ac, bd, ad]);
                } else {
                    out.push([a, ac, bc, ad]);
                    out.push([a, ad, bc, bd]);
                }
            }
            1 => {
                out.push([ac, b, bc, bd]);
                if q2 == 0 {
                    out.push([ac, a, b, bd]);
                    out.push([ac, a, bd, ad]);
                } else {
                    out.push([ac, a, b, ad]);
                    out.push([ac, b, bd, ad]);
                }
            }
            _ => {
                out.push([ad, b, bc, bd]);
                if q1 == 0 {
                    out.push([ad, a, b, bc]);
                    out.push([ad, a, bc, ac]);
                } else {
                    out.push([ad, a, b, ac]);
                    out.push([ad, b, bc, ac]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tetra::mesh::dihedral_angles;

    fn unit(seed: u64, i: u64, k: u64) -> f64 {
        crate::rng::unit(seed, &[i, k])
    }

    /// The signs by rows, wired through the lattice's blocks of corners and
    /// centres: every vertex has its own winding number's sign.
    #[test]
    fn every_vertex_takes_its_sign_from_its_own_row() {
        let winding = Winding::new(&crate::mesh::shapes::icosphere(3));
        let (lo, hi) = winding.bvh.bounds();
        let lattice = Lattice::covering(lo, hi, 0.1);
        let sign = lattice_signs(&winding, &lattice, &crate::progress::Silent);
        for (v, &s) in sign.iter().enumerate() {
            let p = lattice.position(v as u32);
            assert_eq!(s, sign_of(winding.at(p)), "vertex {v} at {p}");
        }
        assert!(sign.contains(&-1) && sign.contains(&1));
    }

    #[test]
    fn bcc_tets_are_congruent_acute_and_tile_the_lattice() {
        let lattice = Lattice {
            origin: DVec3::new(0.3, -1.0, 2.0),
            h: 0.5,
            cubes: [3, 4, 5],
        };
        let mut tets = Vec::new();
        for axis in 0..3 {
            for slab in 0..lattice.cubes[axis] {
                lattice.tets_of_slab(axis, slab, |t| tets.push(t));
            }
        }
        let mut volume = 0.0;
        for t in &tets {
            let c = t.map(|v| lattice.position(v));
            let v = signed_volume(&c);
            assert!((v - 0.5f64.powi(3) / 12.0).abs() < 1e-12, "volume {v}");
            volume += v;
            let mut angles = dihedral_angles(&c).map(|a| a.to_degrees().round() as i32);
            angles.sort_unstable();
            assert_eq!(angles, [60, 60, 60, 60, 90, 90]);
            let long = (0..4)
                .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                .filter(|&(i, j)| lattice.is_long(t[i], t[j]))
                .count();
            assert_eq!(long, 2);
        }
        // The tets fill the lattice's box less a half-cell skin on the four
        // sides around each edge axis: check against that count.
        let [x, y, z] = lattice.cubes.map(|c| c as f64);
        let expected_tets = 4.0
            * (x * (y - 1.0) * (z - 1.0) + y * (z - 1.0) * (x - 1.0) + z * (x - 1.0) * (y - 1.0));
        assert_eq!(tets.len() as f64, expected_tets);
        assert!(volume > 0.0);
    }

    /// Every sign pattern of one lattice tet, its cut points anywhere alpha
    /// or more from both ends (ends drawn a third of the time each) and its
    /// on-surface vertices unwarped: every stencil piece keeps the proven
    /// bounds. This is what checks the diagonal rules (the other diagonal
    /// for a long edge at the outside vertex gives 8.9 degrees here).
    /// Warped vertices are checked end to end in tests/tetra.rs.
    #[test]
    fn stencils_keep_the_proven_angles_for_any_cut_points() {
        let lattice = Lattice {
            origin: DVec3::ZERO,
            h: 1.0,
            cubes: [6, 6, 6],
        };
        let mut tets = Vec::new();
        for axis in 0..3 {
            for slab in [2, 3] {
                lattice.tets_of_slab(axis, slab, |t| tets.push(t));
            }
        }
        let n = lattice.num_vertices();
        let alpha = |u: u32, v: u32| {
            if lattice.is_long(u, v) {
                ALPHA_LONG
            } else {
                ALPHA_SHORT
            }
        };
        let draw = |x: f64, y: f64, lo: f64, hi: f64| {
            if x < 1.0 / 3.0 {
                lo
            } else if x < 2.0 / 3.0 {
                hi
            } else {
                lo + y * (hi - lo)
            }
        };
        let (mut min, mut max) = (180.0f64, 0.0f64);
        let mut outputs = 0usize;
        let mut sign = vec![1i8; n];
        for iter in 0..200_000u64 {
            let r = |k: u64| unit(11, iter, k);
            let t = tets[(r(0) * tets.len() as f64) as usize % tets.len()];
            for (i, &v) in t.iter().enumerate() {
                let x = r(1 + i as u64);
                sign[v as usize] = if x < 0.4 {
                    -1
                } else if x < 0.65 {
                    0
                } else {
                    1
                };
            }
            let mut keys = Vec::new();
            for i in 0..4 {
                for j in i + 1..4 {
                    if sign[t[i] as usize] as i32 * sign[t[j] as usize] as i32 == -1 {
                        keys.push(key(t[i], t[j]));
                    }
                }
            }
            keys.sort_unstable();
            let cut_at: Vec<DVec3> = keys
                .iter()
                .enumerate()
                .map(|(k, &e)| {
                    let (u, v) = unkey(e);
                    let a = alpha(u, v);
                    let s = draw(r(50 + k as u64), r(60 + k as u64), a, 1.0 - a);
                    lattice.position(u).lerp(lattice.position(v), s)
                })
                .collect();
            let stencils = Stencils {
                lattice: &lattice,
                sign: &sign,
                keys: &keys,
            };
            let mut out = Vec::new();
            stencils.fill(t, &mut out);
            for o in &out {
                let c = o.map(|v| {
                    if (v as usize) < n {
                        lattice.position(v)
                    } else {
                        cut_at[v as usize - n]
                    }
                });
                assert!(signed_volume(&c).abs() > 1e-9, "flat tet {o:?} from {t:?}");
                for a in dihedral_angles(&c) {
                    min = min.min(a.to_degrees());
                    max = max.max(a.to_degrees());
                }
                outputs += 1;
            }
            for &v in &t {
                sign[v as usize] = 1;
            }
        }
        assert!(outputs > 50_000);
        assert!(
            min >= MIN_DIHEDRAL && max <= MAX_DIHEDRAL,
            "dihedral angles {min:.3} to {max:.3} degrees"
        );
    }
}
