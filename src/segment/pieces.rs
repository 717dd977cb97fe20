//! A region's pieces and enclosed voids, in voxels, with the connectivity
//! of the surface that `surface::march` puts round them.
//!
//! Marching tetrahedra over Kuhn's split joins two voxel centres by a
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

use crate::error::Result;
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
/// by flood fill in voxel order: the same numbering on any machine.
pub fn pieces(size: [usize; 3], member: &[bool], progress: &dyn Progress) -> Result<Pieces> {
    let [nx, ny, nz] = size;
    assert_eq!(member.len(), nx * ny * nz, "one flag per voxel");
    let mut of_voxel = vec![NONE; member.len()];
    let mut voxels = Vec::new();
    let mut at_border = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let coords = |i: usize| {
        [
            (i % nx) as i64,
            ((i / nx) % ny) as i64,
            (i / (nx * ny)) as i64,
        ]
    };
    let border = |c: [i64; 3]| {
        c[0] == 0
            || c[1] == 0
            || c[2] == 0
            || c[0] == nx as i64 - 1
            || c[1] == ny as i64 - 1
            || c[2] == nz as i64 - 1
    };
    for start in 0..member.len() {
        if start % (nx * ny) == 0 {
            progress::check(progress)?;
        }
        if !member[start] || of_voxel[start] != NONE {
            continue;
        }
        let piece = voxels.len() as u32;
        let (mut count, mut reaches) = (0u64, false);
        of_voxel[start] = piece;
        stack.push(start);
        while let Some(i) = stack.pop() {
            count += 1;
            let c = coords(i);
            reaches |= border(c);
            for d in NEIGHBOURS {
                let n = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
                if n[0] < 0
                    || n[1] < 0
                    || n[2] < 0
                    || n[0] >= nx as i64
                    || n[1] >= ny as i64
                    || n[2] >= nz as i64
                {
                    continue;
                }
                let j = (n[2] as usize * ny + n[1] as usize) * nx + n[0] as usize;
                if member[j] && of_voxel[j] == NONE {
                    of_voxel[j] = piece;
                    stack.push(j);
                }
            }
        }
        voxels.push(count);
        at_border.push(reaches);
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
    let outside: Vec<bool> = inside.iter().map(|&b| !b).collect();
    let p = pieces(size, &outside, progress)?;
    let void: Vec<bool> = p
        .of_voxel
        .iter()
        .map(|&q| q != NONE && !p.at_border[q as usize])
        .collect();
    let count = p.at_border.iter().filter(|&&b| !b).count();
    Ok((void, count))
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
