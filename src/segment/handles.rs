//! Handles thinner than a size, taken out in the voxels before the surface
//! is made (`organtex mesh --max-handle MM`). A segmentation's spurious
//! handles are voxel-thin: a bridge of tissue across a sulcus (cut it) or
//! a pinhole tunnel through a thin wall (plug it). Wood, Hoppe, Desbrun
//! and Schröder ("Removing excess topology from isosurfaces", ACM TOG
//! 2004) cut or fill each handle, whichever is smaller; here both are
//! found with morphology and kept minimal with simple points:
//!
//! 1. **Cut bridges.** The opening of the region by a ball of diameter MM
//!    loses every bridge thinner than MM. It is grown back towards the
//!    region voxel by voxel, adding only simple voxels (whose adding
//!    changes no topology), breadth first; what cannot be added are the
//!    cuts, a voxel or so across, in the middle of each thin bridge.
//! 2. **Plug tunnels.** The same on the outside: the closing, shrunk back
//!    by removing simple voxels; what is left plugs each narrow tunnel.
//!
//! A cut or plug is kept only when it lowers the genus: its change of the
//! Euler characteristic is positive, and it neither splits a piece (a thin
//! neck) nor opens or closes a void. So pieces and voids stay as they
//! were, and only handles go.
//!
//! Topology here is that of the surface `surface::march` makes: the
//! region is the full subcomplex of Kuhn's triangulation of the voxel grid
//! on its voxels (`pieces`' 14 neighbours). A voxel is simple when the
//! region's neighbours of it, and the others, are each one connected,
//! non-empty set in its link (a triangulated sphere: then both are
//! contractible, by Alexander duality).

use std::collections::VecDeque;

use rayon::prelude::*;

use super::pieces::{self, NEIGHBOURS};
use crate::error::Result;
use crate::progress::{self, Progress};

/// What the fix did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct HandleFix {
    /// The handle size asked for, mm.
    pub max_handle: f64,
    /// The region's genus (summed over its surface's sheets) before and
    /// after.
    pub genus_before: i64,
    pub genus_after: i64,
    /// Handles cut (bridges) and filled (tunnels).
    pub cut: i64,
    pub filled: i64,
    pub voxels_removed: u64,
    pub voxels_added: u64,
}

/// `inside` with its handles thinner than `max_handle` mm cut or plugged,
/// on a grid of `size` voxels of `spacing` mm (for anisotropic voxels, the
/// geometric mean: the ball is round in voxels, not in millimetres).
pub fn remove_handles(
    size: [usize; 3],
    inside: &[bool],
    max_handle: f64,
    spacing: f64,
    progress: &dyn Progress,
) -> Result<(Vec<bool>, HandleFix)> {
    if !inside.contains(&true) {
        let none = HandleFix {
            max_handle,
            genus_before: 0,
            genus_after: 0,
            cut: 0,
            filled: 0,
            voxels_removed: 0,
            voxels_added: 0,
        };
        return Ok((inside.to_vec(), none));
    }
    // The work is done on the region's box with a margin (what lies
    // beyond it is outside, as beyond the grid), then put back.
    let largest = *size.iter().max().expect("three sides") as f64;
    let margin = ((0.5 * max_handle / spacing).ceil().min(largest) as usize).saturating_add(2);
    let (crop, sub) = Crop::around(size, inside, margin);
    let (fixed_sub, fix) = remove_in(crop.size, &sub, max_handle, spacing, progress)?;
    let mut fixed = inside.to_vec();
    crop.put_back(&mut fixed, &fixed_sub);
    Ok((fixed, fix))
}

/// A box of the grid: its first voxel and size.
struct Crop {
    from: [usize; 3],
    size: [usize; 3],
    whole: [usize; 3],
}

impl Crop {
    /// The box of `set`'s voxels grown by `margin` (within the grid), and
    /// `set` within it.
    fn around(whole: [usize; 3], set: &[bool], margin: usize) -> (Crop, Vec<bool>) {
        let (mut lo, mut hi) = (whole, [0; 3]);
        let [nx, ny, _] = whole;
        for (i, _) in set.iter().enumerate().filter(|(_, b)| **b) {
            let c = [i % nx, (i / nx) % ny, i / (nx * ny)];
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k] + 1);
            }
        }
        let from: [usize; 3] = std::array::from_fn(|k| lo[k].saturating_sub(margin));
        let size: [usize; 3] = std::array::from_fn(|k| (hi[k] + margin).min(whole[k]) - from[k]);
        let crop = Crop { from, size, whole };
        let mut sub = Vec::with_capacity(size.iter().product());
        crop.each(|i| sub.push(set[i]));
        (crop, sub)
    }

    /// Visit the box's voxels in its own x-fastest order, by their index
    /// in the whole grid.
    fn each(&self, mut f: impl FnMut(usize)) {
        let [nx, ny, _] = self.whole;
        for z in self.from[2]..self.from[2] + self.size[2] {
            for y in self.from[1]..self.from[1] + self.size[1] {
                let row = (z * ny + y) * nx;
                for x in self.from[0]..self.from[0] + self.size[0] {
                    f(row + x);
                }
            }
        }
    }

    fn put_back(&self, whole: &mut [bool], sub: &[bool]) {
        let mut k = 0;
        self.each(|i| {
            whole[i] = sub[k];
            k += 1;
        });
    }
}

/// `remove_handles` on a grid cropped round the region.
fn remove_in(
    size: [usize; 3],
    inside: &[bool],
    max_handle: f64,
    spacing: f64,
    progress: &dyn Progress,
) -> Result<(Vec<bool>, HandleFix)> {
    let grid = Grid::new(size);
    // Chamfer units (3 per voxel step) of a ball of diameter max_handle,
    // reached a voxel at a time: the thinnest handles go first, each by
    // its own small cut, so a larger size never leaves more handles (one
    // large opening joins neighbouring handles' cuts into groups that
    // split a piece, and are refused whole).
    // Past the grid's longest side the opening is empty: no larger ball
    // is tried.
    let longest = *size.iter().max().expect("three sides") as f64;
    let last = (3.0 * 0.5 * max_handle / spacing)
        .round()
        .min(3.0 * longest) as u32;
    let radii: Vec<u32> = (1..)
        .map(|k| 3 * k)
        .take_while(|&r| r < last)
        .chain(std::iter::once(last))
        .filter(|&r| r >= 3)
        .collect();
    progress.stage("removing thin handles", 2 + radii.len() as u64);
    let genus_before = genus_of(&grid, inside, progress)?;
    progress.advance(1);
    let (mut fixed, mut cut, mut filled) = (inside.to_vec(), 0, 0);
    for &radius in &radii {
        // 1. Bridges: the opening grown back; the cuts are what is left.
        let opened = opening(&grid, &fixed, radius);
        let grown = grow_simple(&grid, opened, &fixed, true, progress)?;
        let cuts: Vec<bool> = fixed.iter().zip(&grown).map(|(&i, &g)| i && !g).collect();
        let (after_cut, n) = keep_lowering(&grid, &fixed, &cuts, true, progress)?;
        cut += n;
        // 2. Tunnels: the closing (the outside's opening) shrunk back.
        let outside: Vec<bool> = after_cut.iter().map(|&b| !b).collect();
        let closed: Vec<bool> = opening(&grid, &outside, radius)
            .iter()
            .map(|&b| !b)
            .collect();
        let shrunk = grow_simple(&grid, closed, &after_cut, false, progress)?;
        let plugs: Vec<bool> = after_cut
            .iter()
            .zip(&shrunk)
            .map(|(&a, &s)| !a && s)
            .collect();
        let (after_fill, n) = keep_lowering(&grid, &after_cut, &plugs, false, progress)?;
        filled += n;
        fixed = after_fill;
        progress.advance(1);
    }
    let genus_after = genus_of(&grid, &fixed, progress)?;
    progress.advance(1);
    let (mut removed, mut added) = (0, 0);
    for (&a, &b) in inside.iter().zip(&fixed) {
        removed += (a && !b) as u64;
        added += (!a && b) as u64;
    }
    Ok((
        fixed,
        HandleFix {
            max_handle,
            genus_before,
            genus_after,
            cut,
            filled,
            voxels_removed: removed,
            voxels_added: added,
        },
    ))
}

/// Index arithmetic over the grid.
struct Grid {
    size: [usize; 3],
}

impl Grid {
    fn new(size: [usize; 3]) -> Grid {
        Grid { size }
    }

    fn len(&self) -> usize {
        self.size[0] * self.size[1] * self.size[2]
    }

    fn coords(&self, i: usize) -> [i64; 3] {
        let [nx, ny, _] = self.size;
        [
            (i % nx) as i64,
            ((i / nx) % ny) as i64,
            (i / (nx * ny)) as i64,
        ]
    }

    /// The voxel at `c + d`, if in the grid.
    fn offset(&self, c: [i64; 3], d: [i64; 3]) -> Option<usize> {
        let [nx, ny, nz] = self.size.map(|n| n as i64);
        let [x, y, z] = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
        ((0..nx).contains(&x) && (0..ny).contains(&y) && (0..nz).contains(&z))
            .then(|| ((z * ny + y) * nx + x) as usize)
    }

    /// The Kuhn neighbours of voxel `i` as a 14-bit mask of where `set` is
    /// true (beyond the grid: false).
    fn mask(&self, set: &[bool], i: usize) -> u16 {
        let c = self.coords(i);
        let mut m = 0u16;
        for (k, d) in NEIGHBOURS.iter().enumerate() {
            if self.offset(c, *d).is_some_and(|j| set[j]) {
                m |= 1 << k;
            }
        }
        m
    }
}

/// The opening of `set` by a ball of `radius` chamfer units: erosion then
/// dilation, each a distance transform.
fn opening(grid: &Grid, set: &[bool], radius: u32) -> Vec<bool> {
    let outside: Vec<bool> = set.iter().map(|&b| !b).collect();
    let to_outside = chamfer(grid, &outside);
    let eroded: Vec<bool> = to_outside.iter().map(|&d| d > radius).collect();
    chamfer(grid, &eroded)
        .iter()
        .map(|&d| d <= radius)
        .collect()
}

/// The chamfer distance (Borgefors 1986, "Distance transformations in
/// digital images": steps of 3, 4 and 5 for a face, edge and corner
/// neighbour, within 8% of Euclidean) from each voxel to the nearest
/// where `source` is true, in two raster passes. Voxels beyond the grid
/// are not sources. A few lines, where a crate would bring its own grid.
fn chamfer(grid: &Grid, source: &[bool]) -> Vec<u32> {
    const FAR: u32 = u32::MAX / 2;
    let mut d: Vec<u32> = source.iter().map(|&s| if s { 0 } else { FAR }).collect();
    // The 13 neighbours before a voxel in raster order, with their steps.
    let mut before = Vec::new();
    for dz in -1..=1i64 {
        for dy in -1..=1i64 {
            for dx in -1..=1i64 {
                if (dz, dy, dx) < (0, 0, 0) {
                    let n = dx.abs() + dy.abs() + dz.abs();
                    before.push(([dx, dy, dz], [0, 3, 4, 5][n as usize]));
                }
            }
        }
    }
    // Interior voxels step by fixed index offsets; the border's check
    // the grid's bounds.
    let [nx, ny, nz] = grid.size;
    let linear: Vec<(isize, u32)> = before
        .iter()
        .map(|&(o, w)| ((o[0] + (o[1] + o[2] * ny as i64) * nx as i64) as isize, w))
        .collect();
    let interior = |i: usize| {
        let [x, y, z] = grid.coords(i);
        x > 0 && y > 0 && z > 0 && x + 1 < nx as i64 && y + 1 < ny as i64 && z + 1 < nz as i64
    };
    let n = grid.len();
    for pass in 0..2 {
        let sign: isize = if pass == 0 { 1 } else { -1 };
        for k in 0..n {
            let i = if pass == 0 { k } else { n - 1 - k };
            let mut best = d[i];
            if interior(i) {
                for &(o, w) in &linear {
                    best = best.min(d[(i as isize + sign * o) as usize] + w);
                }
            } else {
                let c = grid.coords(i);
                for &(o, w) in &before {
                    if let Some(j) = grid.offset(c, o.map(|x| x * sign as i64)) {
                        best = best.min(d[j] + w);
                    }
                }
            }
            d[i] = best;
        }
    }
    d
}

/// From `start`, towards `target`, breadth first: add (`grow`) voxels of
/// `target` not in the set, or remove (`!grow`) voxels of the set not in
/// `target`, each only while it is simple. Returns the set reached.
fn grow_simple(
    grid: &Grid,
    mut set: Vec<bool>,
    target: &[bool],
    grow: bool,
    progress: &dyn Progress,
) -> Result<Vec<bool>> {
    // A voxel still to change: in the target and not the set when growing,
    // in the set and not the target when shrinking.
    let pending = |set: &[bool], i: usize| set[i] != target[i] && set[i] != grow;
    let mut queue: VecDeque<usize> = (0..grid.len())
        .filter(|&i| pending(&set, i) && grid.mask(&set, i) != if grow { 0 } else { FULL })
        .collect();
    let mut steps = 0usize;
    while let Some(i) = queue.pop_front() {
        steps += 1;
        if steps.is_multiple_of(1 << 20) {
            progress::check(progress)?;
        }
        if !pending(&set, i) || !simple(grid.mask(&set, i)) {
            continue;
        }
        set[i] = grow;
        let c = grid.coords(i);
        for d in NEIGHBOURS {
            if let Some(j) = grid.offset(c, d)
                && pending(&set, j)
            {
                queue.push_back(j);
            }
        }
    }
    Ok(set)
}

/// All 14 neighbours.
const FULL: u16 = (1 << 14) - 1;

/// Whether a voxel whose neighbours in the set are `mask` is simple:
/// adding or removing it changes no topology (the module's comment).
fn simple(mask: u16) -> bool {
    static TABLE: std::sync::OnceLock<Vec<bool>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=FULL)
            .map(|m| connected(m) && connected(!m & FULL))
            .collect()
    });
    table[mask as usize]
}

/// Whether the neighbours in `mask` are non-empty and joined by the link's
/// edges (two neighbours of a voxel are joined when they are neighbours
/// of each other).
fn connected(mask: u16) -> bool {
    if mask == 0 {
        return false;
    }
    let first = mask.trailing_zeros();
    let (mut reached, mut frontier) = (1u16 << first, 1u16 << first);
    while frontier != 0 {
        let k = frontier.trailing_zeros() as usize;
        frontier &= frontier - 1;
        let new = LINK[k] & mask & !reached;
        reached |= new;
        frontier |= new;
    }
    reached == mask
}

/// For each of the 14 neighbours, the others it is a neighbour of.
static LINK: [u16; 14] = {
    let mut link = [0u16; 14];
    let mut a = 0;
    while a < 14 {
        let mut b = 0;
        while b < 14 {
            let d = [
                NEIGHBOURS[b][0] - NEIGHBOURS[a][0],
                NEIGHBOURS[b][1] - NEIGHBOURS[a][1],
                NEIGHBOURS[b][2] - NEIGHBOURS[a][2],
            ];
            let mut k = 0;
            while k < 14 {
                if NEIGHBOURS[k][0] == d[0] && NEIGHBOURS[k][1] == d[1] && NEIGHBOURS[k][2] == d[2]
                {
                    link[a] |= 1 << b;
                }
                k += 1;
            }
            b += 1;
        }
        a += 1;
    }
    link
};

/// Of `changes` (voxels to remove from `set` when `cut`, to add when
/// not), keep each connected group whose change lowers the genus without
/// splitting or joining pieces or opening or closing voids. Returns the
/// changed set and the handles it took out.
fn keep_lowering(
    grid: &Grid,
    set: &[bool],
    changes: &[bool],
    cut: bool,
    progress: &dyn Progress,
) -> Result<(Vec<bool>, i64)> {
    let groups = pieces::pieces(grid.size, changes, progress)?;
    let mut result = set.to_vec();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); groups.count()];
    for (i, &g) in groups.of_voxel.iter().enumerate() {
        if g != pieces::NONE {
            members[g as usize].push(i);
        }
    }
    // Each group's change of the Euler characteristic, alone.
    let gains: Vec<i64> = members
        .par_iter()
        .map(|voxels| euler_change(grid, set, voxels, cut))
        .collect();
    let mut kept: Vec<bool> = gains.iter().map(|&g| g > 0).collect();
    for (g, voxels) in members.iter().enumerate() {
        if kept[g] {
            for &i in voxels {
                result[i] = !cut;
            }
        }
    }
    if !kept.iter().any(|&k| k) {
        return Ok((result, 0));
    }
    // A group that changed more than a handle is undone (below). One
    // round: an undone group only restores what it had changed.
    let (after, new_void) = if cut {
        (
            pieces::pieces(grid.size, &result, progress)?.of_voxel,
            Vec::new(),
        )
    } else {
        let (before, _) = pieces::voids(grid.size, set, progress)?;
        let (after, _) = pieces::voids(grid.size, &result, progress)?;
        let new: Vec<bool> = after.iter().zip(&before).map(|(&a, &b)| a && !b).collect();
        (pieces::pieces(grid.size, set, progress)?.of_voxel, new)
    };
    for (g, voxels) in members.iter().enumerate() {
        if !kept[g] {
            continue;
        }
        // A cut must leave tissue beside it (else it deletes a whole
        // piece) in one piece, and face the outside (else it is a new
        // void); a plug must join the tissue of one piece (else it is a
        // piece of its own, or joins two) and face the outside left (else
        // it fills a whole void).
        let mut seen = pieces::NONE;
        let (mut wrong, mut tissue, mut open) = (false, false, false);
        for &i in voxels {
            let c = grid.coords(i);
            for d in NEIGHBOURS {
                let Some(j) = grid.offset(c, d) else {
                    open = true;
                    continue;
                };
                let p = after[j];
                if p != pieces::NONE && (cut || set[j]) {
                    wrong |= seen != pieces::NONE && seen != p;
                    seen = p;
                    tissue = true;
                }
                open |= if cut { !set[j] } else { !result[j] };
                wrong |= !cut && new_void[j];
            }
        }
        if wrong || !tissue || !open {
            kept[g] = false;
            for &i in voxels {
                result[i] = cut;
            }
        }
    }
    let handles = gains
        .iter()
        .zip(&kept)
        .filter(|&(_, &k)| k)
        .map(|(&g, _)| g)
        .sum();
    Ok((result, handles))
}

/// The change of the Euler characteristic (vertices - edges + triangles -
/// tetrahedra of the full subcomplex) when `voxels` leave `set` (`cut`)
/// or join it: over the simplices with a vertex among them, each counted
/// at its lowest vertex.
fn euler_change(grid: &Grid, set: &[bool], voxels: &[usize], cut: bool) -> i64 {
    let changed: std::collections::HashSet<usize> = voxels.iter().copied().collect();
    let member_before = |j: usize| set[j];
    let member_after = |j: usize| if changed.contains(&j) { !cut } else { set[j] };
    // Every lowest vertex of a simplex touching a changed voxel.
    let mut bases: Vec<usize> = Vec::with_capacity(voxels.len() * 8);
    for &i in voxels {
        let c = grid.coords(i);
        for o in 0..8 {
            let d = [-(o & 1), -((o >> 1) & 1), -((o >> 2) & 1)];
            if let Some(b) = grid.offset(c, d) {
                bases.push(b);
            }
        }
    }
    bases.sort_unstable();
    bases.dedup();
    bases
        .iter()
        .map(|&b| euler_at(grid, b, &member_after) - euler_at(grid, b, &member_before))
        .sum()
}

/// The signed count of the simplices whose lowest vertex is voxel `b` and
/// whose vertices are all members: Kuhn's simplices at `b` are the chains
/// b < b + u < b + v < ... with u, v, ... growing 0/1 vectors.
fn euler_at(grid: &Grid, b: usize, member: &impl Fn(usize) -> bool) -> i64 {
    if !member(b) {
        return 0;
    }
    let c = grid.coords(b);
    let vertex = |bits: i64| {
        grid.offset(c, [bits & 1, (bits >> 1) & 1, (bits >> 2) & 1])
            .is_some_and(member)
    };
    let mut chi = 1;
    // Chains of non-empty subsets of {x, y, z}, strictly growing.
    for a in 1..8i64 {
        if !vertex(a) {
            continue;
        }
        chi -= 1;
        for s in 1..8i64 {
            if s == a || s & a != a || !vertex(s) {
                continue;
            }
            chi += 1;
            for t in 1..8i64 {
                if t != s && t & s == s && vertex(t) {
                    chi -= 1;
                }
            }
        }
    }
    chi
}

/// The summed genus of the surface round `set`: sheets (pieces and voids)
/// less the Euler characteristic of the solid.
fn genus_of(grid: &Grid, set: &[bool], progress: &dyn Progress) -> Result<i64> {
    let chi: i64 = (0..grid.len())
        .into_par_iter()
        .map(|b| euler_at(grid, b, &|j| set[j]))
        .sum();
    let components = pieces::pieces(grid.size, set, progress)?.count() as i64;
    let (_, voids) = pieces::voids(grid.size, set, progress)?;
    Ok(components + voids as i64 - chi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    const N: usize = 24;

    fn grid_of(f: impl Fn(usize, usize, usize) -> bool) -> Vec<bool> {
        let mut v = Vec::with_capacity(N * N * N);
        for z in 0..N {
            for y in 0..N {
                for x in 0..N {
                    v.push(f(x, y, z));
                }
            }
        }
        v
    }

    /// A square frame in the xy plane, `thick` voxels in z, round a hole
    /// of `hole` voxels; its right bar `bar` voxels wide.
    fn frame(hole: usize, bar: usize, thick: usize) -> Vec<bool> {
        let (lo, hi) = (4, 4 + 5 + hole + bar);
        grid_of(|x, y, z| {
            let in_box =
                (lo..hi).contains(&x) && (4..14 + hole).contains(&y) && (4..4 + thick).contains(&z);
            let in_hole = (lo + 5..lo + 5 + hole).contains(&x) && (9..9 + hole).contains(&y);
            in_box && !in_hole
        })
    }

    fn fix(set: &[bool], mm: f64) -> (Vec<bool>, HandleFix) {
        remove_handles([N; 3], set, mm, 1.0, &Silent).unwrap()
    }

    /// The genus counted in voxels is the surface's.
    fn surface_genus(set: &[bool]) -> i64 {
        let mesh = super::super::surface::march(
            [N; 3],
            super::super::surface::Field::Binary(set),
            &Silent,
        )
        .unwrap();
        crate::mesh::info::analyse(mesh, false)
            .unwrap()
            .report
            .genus
            .iter()
            .sum()
    }

    /// `set` has one handle, which the fix takes out by cutting (`cut`)
    /// or plugging, and no more than `most` voxels; then a thicker
    /// `kept` is left as it is.
    fn one_handle_goes(set: &[bool], cut: bool, most: u64, kept: &[bool]) {
        assert_eq!(genus_of(&Grid::new([N; 3]), set, &Silent).unwrap(), 1);
        assert_eq!(surface_genus(set), 1);
        let (fixed, f) = fix(set, 2.0);
        let (n_cut, n_filled) = if cut { (1, 0) } else { (0, 1) };
        assert_eq!(
            (f.genus_before, f.genus_after, f.cut, f.filled),
            (1, 0, n_cut, n_filled),
            "{f:?}"
        );
        let (changed, other) = if cut {
            (f.voxels_removed, f.voxels_added)
        } else {
            (f.voxels_added, f.voxels_removed)
        };
        assert_eq!(other, 0, "{f:?}");
        assert!(changed >= 1 && changed <= most, "{f:?}");
        assert_eq!(surface_genus(&fixed), 0);
        assert_eq!(pieces::pieces([N; 3], &fixed, &Silent).unwrap().count(), 1);
        let (same, f) = fix(kept, 2.0);
        assert_eq!((f.genus_before, f.genus_after), (1, 1), "{f:?}");
        assert_eq!(same, kept);
    }

    #[test]
    fn a_thin_bridge_is_cut_by_a_voxel_or_so() {
        // A 1-voxel bar (thinner than 2 mm) closes the frame; one
        // cross-section of it is 4 voxels (its z thickness). A 4-voxel
        // bar stays.
        one_handle_goes(&frame(4, 1, 4), true, 8, &frame(4, 4, 4));
    }

    #[test]
    fn a_pinhole_is_plugged_and_a_wide_hole_kept() {
        one_handle_goes(&frame(1, 5, 5), false, 5, &frame(6, 5, 5));
    }

    #[test]
    fn a_thin_neck_and_a_thin_walled_void_stay() {
        // Two cubes joined by a 1-voxel neck: no handle, one piece.
        let necked = grid_of(|x, y, z| {
            let cube = |x0: usize| {
                (x0..x0 + 6).contains(&x) && (8..14).contains(&y) && (8..14).contains(&z)
            };
            cube(3) || cube(14) || ((9..14).contains(&x) && y == 10 && z == 10)
        });
        let (same, f) = fix(&necked, 2.0);
        assert_eq!((f.genus_before, f.genus_after), (0, 0), "{f:?}");
        assert_eq!(same, necked);
        // A hollow cube with a 1-voxel wall: its void stays a void.
        let hollow = grid_of(|x, y, z| {
            let c = [x, y, z];
            c.iter().all(|&v| (5..15).contains(&v)) && !c.iter().all(|&v| (6..14).contains(&v))
        });
        let (same, f) = fix(&hollow, 2.0);
        assert_eq!((f.genus_before, f.genus_after), (0, 0), "{f:?}");
        assert_eq!(same, hollow);
        assert_eq!(pieces::voids([N; 3], &same, &Silent).unwrap().1, 1);
    }

    /// The fast passes (index offsets inside, bounds checks at the border)
    /// give the two-pass chamfer distance computed with bounds checks
    /// everywhere, on an uneven grid with sources at its border.
    /// A piece the opening loses whole (a wire figure eight, genus 2) is
    /// not deleted; a size past the grid ends; an empty region is left
    /// empty.
    #[test]
    fn thin_pieces_huge_sizes_and_nothing_are_left_alone() {
        let eight = grid_of(|x, y, z| {
            let ring = |y0: usize| {
                z == 10
                    && (4..=12).contains(&x)
                    && (y0..=y0 + 6).contains(&y)
                    && (x == 4 || x == 12 || y == y0 || y == y0 + 6)
            };
            ring(3) || ring(9)
        });
        assert_eq!(genus_of(&Grid::new([N; 3]), &eight, &Silent).unwrap(), 2);
        let (same, f) = fix(&eight, 2.0);
        assert!(same == eight, "{f:?}");
        // Every tunnel is narrower than a size past the grid: the frame's
        // hole is plugged by one 4 x 4 membrane, nothing of it removed.
        let thick = frame(4, 4, 4);
        let (_, f) = fix(&thick, 1e12);
        assert_eq!(
            (f.genus_after, f.voxels_removed, f.voxels_added),
            (0, 0, 16),
            "{f:?}"
        );
        let empty = vec![false; N * N * N];
        assert!(fix(&empty, 2.0).0 == empty);
    }

    #[test]
    fn the_chamfer_passes_agree_with_checked_ones() {
        let grid = Grid::new([9, 7, 5]);
        let source: Vec<bool> = (0..grid.len())
            .map(|i| crate::rng::unit(3, &[i as u64]) < 0.05)
            .collect();
        let fast = chamfer(&grid, &source);
        let mut d: Vec<u32> = source
            .iter()
            .map(|&s| if s { 0 } else { u32::MAX / 2 })
            .collect();
        for pass in [1i64, -1] {
            for k in 0..grid.len() {
                let i = if pass == 1 { k } else { grid.len() - 1 - k };
                let c = grid.coords(i);
                for dz in -1..=1i64 {
                    for dy in -1..=1i64 {
                        for dx in -1..=1i64 {
                            if (dz, dy, dx) < (0, 0, 0)
                                && let Some(j) = grid.offset(c, [dx * pass, dy * pass, dz * pass])
                            {
                                let w = [0, 3, 4, 5][(dx.abs() + dy.abs() + dz.abs()) as usize];
                                d[i] = d[i].min(d[j] + w);
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(fast, d);
        assert!(d.iter().any(|&x| x >= 6), "distances beyond one step");
    }

    #[test]
    fn simple_voxels_are_those_whose_neighbours_and_others_are_each_connected() {
        // Alone, or buried: adding or removing it changes topology.
        assert!(!simple(0));
        assert!(!simple(FULL));
        // One neighbour: a tip, simple.
        assert!(simple(1));
        // Two opposite face neighbours (+x and -x), not joined in the link:
        // adding the voxel joins them.
        assert!(!simple(1 | 1 << 7));
    }
}
