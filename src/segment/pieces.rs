//! A region's pieces and enclosed voids, in voxels, with the connectivity
//! of the surface that `surface::march` puts round them.
//!
//! Marching tetrahedra over Kuhn's split (whose topology `surface` keeps,
//! `cubes`) joins two voxel centres by a
//! tetrahedron edge when their offset is a non-zero 0/1 vector or its
//! negative (the six face neighbours, six face diagonals and two main
//! diagonals: 14 neighbours). The surface separates inside from outside
//! along exactly those edges, so two inside voxels lie in one solid piece
//! when a path of such edges joins them through inside voxels, and the
//! same holds for outside voxels: a void is an outside piece that does not
//! reach the volume's border. Each sheet of the surface parts one inside
//! piece from one outside piece: sheets = inside pieces + outside pieces
//! less one. Counting pieces on the surface instead would split a piece
//! from the shells of its own voids (keeping the largest surface would drop
//! them and count the voids as tissue).

use std::collections::BTreeSet;

use crate::error::Result;
use crate::mesh::dsu::DisjointSets;
use crate::mesh::submesh::extract;
use crate::mesh::{FaceId, TriMesh};
use crate::progress::{self, Progress};

/// The 14 neighbours of the Kuhn split (see the module's comment).
pub(super) const NEIGHBOURS: [[i64; 3]; 14] = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 0],
    [1, 0, 1],
    [0, 1, 1],
    [1, 1, 1],
    [-1, 0, 0],
    [0, -1, 0],
    [0, 0, -1],
    [-1, -1, 0],
    [-1, 0, -1],
    [0, -1, -1],
    [-1, -1, -1],
];

/// Not in any piece.
pub const NONE: u32 = u32::MAX;

/// The pieces of the voxels where `member` is true: per voxel its piece
/// (`NONE` where not a member), numbered in order of their first voxel,
/// and each piece's voxel count and whether it reaches the volume's border.
pub struct Pieces {
    pub of_voxel: Vec<u32>,
    pub voxels: Vec<u64>,
    pub at_border: Vec<bool>,
}

impl Pieces {
    pub fn count(&self) -> usize {
        self.voxels.len()
    }

    /// The piece with the most voxels (the first of equals).
    pub fn largest(&self) -> Option<u32> {
        (0..self.voxels.len() as u32)
            .max_by_key(|&p| (self.voxels[p as usize], std::cmp::Reverse(p)))
    }
}

/// Label the pieces of `member` over a grid of `size` voxels (x fastest),
/// numbered in order of their first voxel: the same numbering on any
/// machine.
///
/// Two passes in voxel order over the grid padded by a layer of
/// non-members (Rosenfeld and Pfaltz's labelling, with union-find): the
/// first gives each member the label of its neighbours before it (seven of
/// the fourteen), joining their labels where they differ; the second
/// numbers the joined labels. A flood fill visits a scan's outside (most
/// of its voxels, for the voids) in an order that misses the cache at
/// every step across slices.
pub fn pieces(size: [usize; 3], member: &[bool], progress: &dyn Progress) -> Result<Pieces> {
    let [nx, ny, nz] = size;
    assert_eq!(member.len(), nx * ny * nz, "one flag per voxel");
    let (px, py) = (nx + 2, ny + 2);
    let padded = |x: usize, y: usize, z: usize| ((z + 1) * py + y + 1) * px + x + 1;
    // The neighbours before a voxel in voxel order, as steps back.
    let before: Vec<usize> = NEIGHBOURS
        .iter()
        .filter(|d| d.iter().all(|&c| c <= 0))
        .map(|d| (-(d[2] * py as i64 + d[1]) * px as i64 - d[0]) as usize)
        .collect();
    // 0: not a member; else a provisional label plus one.
    let mut label = vec![0u32; px * py * (nz + 2)];
    let mut sets = DisjointSets::new(0);
    for z in 0..nz {
        progress::check(progress)?;
        for y in 0..ny {
            let row = (z * ny + y) * nx;
            let at = padded(0, y, z);
            for x in 0..nx {
                if !member[row + x] {
                    continue;
                }
                let i = at + x;
                // The root of the neighbours' joined labels so far.
                let mut mine = None;
                for &back in &before {
                    let l = label[i - back];
                    if l == 0 {
                        continue;
                    }
                    let r = sets.find(l as usize - 1);
                    mine = match mine {
                        Some(m) if m != r => {
                            sets.union(m, r);
                            Some(sets.find(m))
                        }
                        _ => Some(r),
                    };
                }
                label[i] = mine.unwrap_or_else(|| sets.add()) as u32 + 1;
            }
        }
    }
    let mut number = vec![NONE; sets.len()];
    let mut of_voxel = vec![NONE; member.len()];
    let mut voxels = Vec::new();
    let mut at_border = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            let row = (z * ny + y) * nx;
            let at = padded(0, y, z);
            for x in 0..nx {
                let l = label[at + x];
                if l == 0 {
                    continue;
                }
                let r = sets.find(l as usize - 1);
                if number[r] == NONE {
                    number[r] = voxels.len() as u32;
                    voxels.push(0);
                    at_border.push(false);
                }
                let piece = number[r];
                of_voxel[row + x] = piece;
                voxels[piece as usize] += 1;
                let border =
                    x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz;
                at_border[piece as usize] |= border;
            }
        }
    }
    Ok(Pieces {
        of_voxel,
        voxels,
        at_border,
    })
}

/// The voids of `inside`: outside voxels no path of outside voxels joins
/// to the volume's border (the padding `surface::march` adds round the
/// volume is outside, so the border's outside voxels are the exterior).
/// Per voxel whether it is in a void, and the number of voids.
pub fn voids(
    size: [usize; 3],
    inside: &[bool],
    progress: &dyn Progress,
) -> Result<(Vec<bool>, usize)> {
    let (void_of, count) = numbered_voids(size, inside, progress)?;
    Ok((void_of.iter().map(|&v| v != NONE).collect(), count))
}

/// The voids of `inside` as `voids` finds them, numbered `0..count` in
/// order of their first voxel: per voxel its void (`NONE` where in none),
/// and the number of voids.
pub fn numbered_voids(
    size: [usize; 3],
    inside: &[bool],
    progress: &dyn Progress,
) -> Result<(Vec<u32>, usize)> {
    let outside: Vec<bool> = inside.iter().map(|&b| !b).collect();
    let p = pieces(size, &outside, progress)?;
    let mut count = 0;
    let number: Vec<u32> = p
        .at_border
        .iter()
        .map(|&border| match border {
            true => NONE,
            false => {
                count += 1;
                count - 1
            }
        })
        .collect();
    let void_of = p
        .of_voxel
        .iter()
        .map(|&q| if q == NONE { NONE } else { number[q as usize] })
        .collect();
    Ok((void_of, count as usize))
}

/// The least a void's inner shell may enclose once smoothed, voxels, for
/// the void to stay a void: a sixteenth. A label map's smallest void, one
/// voxel, is marched as an octahedron of a sixth of a voxel (crossing the
/// six edges from the voxel's centre half way); a probability map's
/// voxel just under the level as next to nothing (crossing them a hair
/// from the centre: half the MNI grey matter's 231 voids at 0.5 enclose
/// under 0.04 voxel). And a shell all of whose bends are the staircase's
/// is what the smoothing takes away: Taubin's default shrinks that
/// octahedron to 5e-5 voxel and a void of 2 x 2 x 2 voxels from 5.7 to
/// 3.3 (the windowed sinc to 0.012), and the decimation makes such a
/// speck four faces whose curvature outweighs the whole surface's (173
/// of the grey matter's 231 under a sixteenth smoothed). A sixteenth of a
/// voxel is under half a voxel across, finer than the scan resolves.
pub const LEAST_VOID: f64 = 1.0 / 16.0;

/// An island (a piece kept beside the largest) is dropped as finer than
/// the scan resolves only if it also enclosed under this as marched,
/// voxels: a voxel a hair over the level encloses next to nothing, a lone
/// voxel of a label an octahedron of a sixth. A larger one the scan does
/// resolve, though the windowed sinc can shrink a block of 2 x 2 x 2
/// voxels (5.7 as marched) to a speck (0.005 of a voxel in the tests, a
/// void's to 0.012): kept, a speck (tissue, where a void so shrunk is
/// filled).
pub const LEAST_ISLAND: f64 = 1.0;

/// The closed shells of a surface `segment::mesh` marched, told apart
/// before the smoothing moves them: each vertex's shell, the void each
/// inner shell faces into, and the island (a piece other than the largest,
/// kept by `--all-components`) each outer shell is round.
pub struct Shells {
    shell_of: Vec<u32>,
    /// Each shell's enclosed volume as marched, voxels.
    marched: Vec<f64>,
    void: Vec<Option<u32>>,
    island: Vec<Option<u32>>,
    /// The void an island's shell lies in, if any.
    island_in: Vec<Option<u32>>,
}

/// The shells of `mesh` as marched (voxel coordinates), their voids
/// (`void_of`, as `numbered_voids` gives them) and islands (`islands`:
/// the voxels of the pieces but the largest, each with its piece, in
/// voxel order). An inner shell faces into its void there (a windowed
/// sinc can mirror a shell it shrinks to a speck, so the smoothed sign
/// would not tell), and a vertex on a grid edge (two whole coordinates; a
/// cube centre's has none) lies between a voxel outside and one inside,
/// the edge's ends the third coordinate's floor and ceiling.
pub fn shells(
    mesh: &TriMesh,
    void_of: &[u32],
    islands: &[(usize, u32)],
    size: [usize; 3],
) -> Shells {
    let mut sets = DisjointSets::new(mesh.num_vertices());
    for t in &mesh.triangles {
        sets.union(t[0] as usize, t[1] as usize);
        sets.union(t[0] as usize, t[2] as usize);
    }
    let (shell_of, shells) = sets.labels();
    let marched = shell_volumes(mesh, &shell_of, shells);
    let inner: Vec<bool> = marched.iter().map(|&v| v < 0.0).collect();
    let [nx, ny, nz] = size.map(|n| n as i64);
    let voxel = |c: glam::I64Vec3| -> Option<usize> {
        let within = (0..nx).contains(&c.x) && (0..ny).contains(&c.y) && (0..nz).contains(&c.z);
        within.then_some(((c.z * ny + c.y) * nx + c.x) as usize)
    };
    let void_at = |i: usize| Some(void_of[i]).filter(|&q| q != NONE);
    let island_at = |i: usize| {
        let found = islands.binary_search_by_key(&i, |&(voxel, _)| voxel);
        found.ok().map(|k| islands[k].1)
    };
    let (mut void, mut island) = (vec![None; shells], vec![None; shells]);
    let mut island_in = vec![None; shells];
    let mut told = vec![false; shells];
    for (v, p) in mesh.positions.iter().enumerate() {
        let shell = shell_of[v] as usize;
        if told[shell] {
            continue;
        }
        let mut whole = (0..3).filter(|&k| p[k].fract() == 0.0);
        let (Some(a), Some(b), None) = (whole.next(), whole.next(), whole.next()) else {
            continue;
        };
        let low = p.floor().as_i64vec3();
        let mut high = low;
        high[3 - a - b] += 1;
        // One end is inside, the other outside: the shell's void, or its
        // island (none: the largest piece) and the void that lies in.
        let ends = || [low, high].map(voxel).into_iter().flatten();
        match inner[shell] {
            true => void[shell] = ends().find_map(void_at),
            false => {
                island[shell] = ends().find_map(island_at);
                island_in[shell] = ends().find_map(void_at);
            }
        }
        told[shell] = true;
    }
    Shells {
        shell_of,
        marched,
        void,
        island,
        island_in,
    }
}

/// Each shell's enclosed volume, about one of its own vertices (a speck
/// far from the origin would lose its volume to rounding).
fn shell_volumes(mesh: &TriMesh, shell_of: &[u32], shells: usize) -> Vec<f64> {
    let mut origin = vec![None; shells];
    let mut enclosed = vec![0.0; shells];
    for t in &mesh.triangles {
        let shell = shell_of[t[0] as usize] as usize;
        let o = *origin[shell].get_or_insert(mesh.positions[t[0] as usize]);
        let [a, b, c] = t.map(|v| mesh.positions[v as usize] - o);
        enclosed[shell] += a.dot(b.cross(c)) / 6.0;
    }
    enclosed
}

/// What `drop_unresolved` did: the voids it filled, and the islands
/// (pieces) it dropped.
#[derive(Default)]
pub struct Unresolved {
    pub voids: usize,
    pub islands: usize,
}

/// Fills the voids whose inner shells (`shells`, told apart as marched)
/// enclose under `LEAST_VOID` in `mesh` as smoothed (voxel coordinates),
/// and drops the islands whose outer shells do and enclosed under
/// `LEAST_ISLAND` as marched (finer than the scan resolves, the same way:
/// a probability map's voxel a hair over the level, a lone voxel; the MNI
/// white matter at 0.5 kept whole has 49 pieces, whose smallest the
/// decimation left as four faces of no volume, a mean curvature up to
/// 1,600 per mm). Their shells leave the mesh; the voids' voxels
/// (`void_of`, of `voids`) join `kept`, the islands' (`islands`, as
/// `shells` took them) leave it, unless they lie in a void filled. (A
/// larger piece of tissue inside a filled void keeps its own shell.)
pub fn drop_unresolved(
    mesh: &mut TriMesh,
    shells: &Shells,
    kept: &mut [bool],
    (void_of, voids): (&[u32], usize),
    islands: &[(usize, u32)],
) -> Unresolved {
    let enclosed = shell_volumes(mesh, &shells.shell_of, shells.void.len());
    let mut fill = vec![false; voids];
    let mut gone = BTreeSet::new();
    let dropped: Vec<bool> = (0..enclosed.len())
        .map(|shell| {
            if enclosed[shell].abs() >= LEAST_VOID {
                return false;
            }
            match (shells.void[shell], shells.island[shell]) {
                (Some(void), _) => fill[void as usize] = true,
                (_, Some(island)) if shells.marched[shell] < LEAST_ISLAND => {
                    _ = gone.insert(island)
                }
                _ => return false,
            }
            true
        })
        .collect();
    for (k, &v) in kept.iter_mut().zip(void_of) {
        if v != NONE && fill[v as usize] {
            *k = true;
        }
    }
    // An island dropped in a void filled is tissue with it.
    for (island, void) in shells.island.iter().zip(&shells.island_in) {
        if let (Some(island), Some(void)) = (island, void)
            && fill[*void as usize]
        {
            gone.remove(island);
        }
    }
    for &(voxel, island) in islands {
        if gone.contains(&island) {
            kept[voxel] = false;
        }
    }
    let faces: Vec<FaceId> = (0..mesh.num_faces())
        .filter(|&f| !dropped[shells.shell_of[mesh.triangles[f][0] as usize] as usize])
        .map(FaceId::from)
        .collect();
    if faces.len() < mesh.num_faces() {
        *mesh = extract(mesh, &faces).0;
    }
    Unresolved {
        voids: fill.iter().filter(|&&f| f).count(),
        islands: dropped
            .iter()
            .zip(&shells.island)
            .filter(|&(&d, i)| d && i.is_some())
            .count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    /// A hollow cube with a voxel inside its void, and a separate voxel
    /// touching the cube only along a direction the Kuhn split does not
    /// join (offset (1, -1, 0)): three pieces, one void.
    #[test]
    fn a_hollow_cube_has_one_void_and_the_kuhn_neighbours_decide_pieces() {
        let size = [9, 9, 9];
        let idx = |x: usize, y: usize, z: usize| (z * 9 + y) * 9 + x;
        let mut inside = vec![false; 9 * 9 * 9];
        for z in 1..6 {
            for y in 1..6 {
                for x in 1..6 {
                    let shell = [x, y, z].iter().any(|&c| c == 1 || c == 5);
                    inside[idx(x, y, z)] = shell;
                }
            }
        }
        inside[idx(3, 3, 3)] = true;
        // Off the cube's corner (5, 1, 1) by (1, -1, 0): not a neighbour.
        inside[idx(6, 0, 1)] = true;
        let p = pieces(size, &inside, &Silent).unwrap();
        assert_eq!(p.count(), 3);
        assert_eq!(p.voxels[p.largest().unwrap() as usize], 5 * 5 * 5 - 27);
        let (void, n) = voids(size, &inside, &Silent).unwrap();
        assert_eq!(n, 1);
        assert_eq!(void.iter().filter(|&&v| v).count(), 26);
        // The surface agrees: an outer shell per piece and one round the
        // void.
        let march = super::super::surface::march(
            size,
            super::super::surface::Field::Binary(&inside),
            &Silent,
        )
        .unwrap();
        let sheets = crate::mesh::info::analyse(march, false)
            .unwrap()
            .report
            .components;
        assert_eq!(sheets, 3 + 1);
        // (1, 1, 0) from the corner is a neighbour: one piece fewer.
        inside[idx(6, 0, 1)] = false;
        inside[idx(6, 6, 1)] = true;
        assert_eq!(pieces(size, &inside, &Silent).unwrap().count(), 2);
    }
}
