//! Tetrahedral meshes of an organ's interior, for the simulator's physics
//! (FEM) and for interior textures (lapped solid textures cut by marching
//! tetrahedra).
//!
//! `tetrahedralise(mesh, opts, progress)` fills the inside of any triangle
//! mesh, clean or not, by isosurface stuffing (Labelle and Shewchuk 2007)
//! driven by the generalized winding number (Jacobson et al. 2013, fast
//! form of Barill et al. 2018): inside is where the winding number exceeds
//! 1/2, so self-intersections, duplicated shells, non-manifold parts and
//! small holes are all filled as a person would expect, and every dihedral
//! angle lies within the paper's proven [10.7, 164.8] degrees (asserted on
//! every mesh the tests make; see `stuffing` for what is and is not
//! checked).
//!
//! - `mesh`: `TetMesh`, its boundary, adjacency, quality and Hausdorff
//!   distance to the input;
//! - `winding`: the inside test;
//! - `stuffing`: the BCC lattice, cut points, warping and stencils;
//! - `io`: VTK (read and write), gmsh 4.1 and Medit writers.

pub mod graded;
pub mod io;
pub mod march;
pub mod mesh;
pub mod stuffing;
pub mod winding;

use serde::Serialize;

pub use mesh::{Attribute, Hausdorff, Quality, TetMesh};
pub use stuffing::{MAX_DIHEDRAL, MIN_DIHEDRAL};
pub use winding::Winding;

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::progress::Progress;

/// The default edge length is the bounding box diagonal over this.
pub const DEFAULT_DIVISIONS: f64 = 40.0;
/// The default resolution keeps the boundary within this fraction of the
/// diagonal from the input (two-sided Hausdorff distance).
pub const DEFAULT_HAUSDORFF: f64 = 0.01;
/// Finer lattices tried at most to meet `DEFAULT_HAUSDORFF`.
const MAX_REFINEMENTS: usize = 4;
/// The default resolution refines no further than this many tets.
const MAX_DEFAULT_TETS: f64 = 4e6;

/// How fine a mesh to make. With neither size set the lattice cell is the
/// bounding box diagonal / 40, made finer (up to four times) while the
/// boundary is farther than 1% of the diagonal from the input and refining
/// helps (see `default_resolution`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TetOptions {
    /// The lattice cell size: long edges have this length, short ones
    /// sqrt(3)/2 of it; tets at the boundary are smaller.
    pub edge_length: Option<f64>,
    /// About this many tets instead (the edge length is chosen from the
    /// enclosed volume, then corrected once from the count obtained).
    pub cells: Option<usize>,
    /// Grade the interior (`graded`): tets of the edge length along the
    /// surface, up to 16 times larger deep inside.
    pub graded: bool,
}

/// What `tetrahedralise_report` measured besides the mesh.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TetReport {
    /// The lattice cell size used.
    pub edge_length: f64,
    /// Lattices tried (more than one when the default resolution was
    /// refined, or a cell count corrected).
    pub attempts: usize,
    /// The Hausdorff distance, when the default resolution measured it.
    pub hausdorff: Option<Hausdorff>,
    /// Whether the lattice was graded (asked for, or chosen by the default
    /// resolution when a uniform one would pass `MAX_DEFAULT_TETS`).
    pub graded: bool,
}

/// Fill the inside of `mesh` with tetrahedra. Errors on an empty mesh,
/// non-finite coordinates, a mesh with no inside, options that are not
/// positive numbers, and a lattice too large for memory (with its
/// estimate).
pub fn tetrahedralise(
    mesh: &TriMesh,
    opts: &TetOptions,
    progress: &dyn Progress,
) -> Result<TetMesh> {
    tetrahedralise_report(mesh, opts, progress).map(|(m, _)| m)
}

/// `tetrahedralise`, with the edge length chosen and what it measured.
pub fn tetrahedralise_report(
    mesh: &TriMesh,
    opts: &TetOptions,
    progress: &dyn Progress,
) -> Result<(TetMesh, TetReport)> {
    let (lo, hi) = stuffing::check_input(mesh)?;
    let diagonal = lo.distance(hi);
    match (opts.edge_length, opts.cells) {
        (Some(_), Some(_)) => Err(Error::invalid(
            "give an edge length or a cell count, not both",
        )),
        (Some(h), None) => {
            let m = nonempty(stuff(mesh, h, opts.graded, progress)?, h)?;
            Ok((
                m,
                TetReport {
                    edge_length: h,
                    attempts: 1,
                    hausdorff: None,
                    graded: opts.graded,
                },
            ))
        }
        (None, Some(cells)) => by_count(mesh, cells, opts.graded, lo, hi, progress),
        (None, None) => default_resolution(mesh, diagonal, opts.graded, progress),
    }
}

/// A mesh with no tets is an error: every lattice vertex inside was warped
/// onto the surface, so the inside is thinner than the lattice.
fn nonempty(m: TetMesh, h: f64) -> Result<TetMesh> {
    if m.num_tets() == 0 {
        return Err(Error::invalid(format!(
            "no tets at edge length {h}: the mesh's inside is thinner than that everywhere \
             (every lattice vertex inside lies within a quarter edge of the surface); \
             choose a smaller edge length"
        )));
    }
    Ok(m)
}

/// The default resolution: diagonal / 40, then finer while the boundary is
/// farther than 1% of the diagonal from the input, in either direction,
/// and refining brings that direction down. The distance falls like h^2 on
/// smooth parts (chords) and like h at sharp features and parts thinner
/// than a cell; each step aims for 0.9% as if it fell like h^2. A
/// direction that has not fallen by a tenth from its best over two
/// lattices in a row is one no lattice can close (the cap over a hole in
/// an open surface, or parts of the input inside the solid such as the
/// hidden halves of interpenetrating shells): it stops the refinement,
/// and the lattice least past 1% in the other directions is kept (the
/// coarser of equals). One lattice is not enough to tell: at a sharp rim
/// the distance wobbles by a tenth with where the lattice happens to fall
/// (the default uterus's wall: 1.24%, then 1.17% at a 0.85 finer lattice,
/// 1.02%, then 0.81%). A lattice with no tets (the inside thinner than the
/// cell everywhere) is refined by half.
/// Never more than `MAX_DEFAULT_TETS`: a uniform lattice that would pass
/// it goes on graded.
fn default_resolution(
    mesh: &TriMesh,
    diagonal: f64,
    mut graded: bool,
    progress: &dyn Progress,
) -> Result<(TetMesh, TetReport)> {
    let directions =
        |d: &Hausdorff| [d.boundary_to_surface, d.surface_to_boundary].map(|x| x / d.diagonal);
    let mut h = diagonal / DEFAULT_DIVISIONS;
    // The lattice nearest the surface so far and its distances, each
    // direction's best distance, and how many lattices in a row each has
    // not fallen by a tenth from it.
    let mut best: Option<(TetMesh, TetReport, [f64; 2])> = None;
    let mut lowest = [f64::INFINITY; 2];
    let mut stalled = [0usize; 2];
    for attempts in 1..=1 + MAX_REFINEMENTS {
        let m = stuff(mesh, h, graded, progress)?;
        if m.num_tets() == 0 {
            if attempts > MAX_REFINEMENTS {
                return Err(nonempty(m, h).unwrap_err());
            }
            h *= 0.5;
            continue;
        }
        let d = m.hausdorff(mesh);
        let now = directions(&d);
        let report = TetReport {
            edge_length: h,
            attempts,
            hausdorff: Some(d),
            graded,
        };
        if now.iter().all(|&x| x <= DEFAULT_HAUSDORFF) {
            return Ok((m, report));
        }
        for i in 0..2 {
            if now[i] < 0.9 * lowest[i] {
                stalled[i] = 0;
            } else {
                stalled[i] += 1;
            }
            lowest[i] = lowest[i].min(now[i]);
        }
        // Directions still to close; those that fell last time set the
        // step, so a direction about to show it cannot be closed does not
        // drive the lattice to eight times the tets.
        let open: Vec<(f64, usize)> = (0..2)
            .filter(|&i| now[i] > DEFAULT_HAUSDORFF && stalled[i] < 2)
            .map(|i| (now[i], stalled[i]))
            .collect();
        // Lattices compare by how far they are past 1% in the directions a
        // lattice can still close; a tie keeps the coarser.
        let excess = |x: &[f64; 2]| -> f64 {
            (0..2)
                .filter(|&i| stalled[i] < 2)
                .map(|i| (x[i] - DEFAULT_HAUSDORFF).max(0.0))
                .sum()
        };
        let tets = m.num_tets() as f64;
        if best.as_ref().is_none_or(|b| excess(&now) < excess(&b.2)) {
            best = Some((m, report, now));
        }
        let keep_best = |best: Option<(TetMesh, TetReport, [f64; 2])>| {
            let (m, mut report, _) = best.expect("a lattice with tets was measured");
            report.attempts = attempts;
            Ok((m, report))
        };
        if open.is_empty() || attempts > MAX_REFINEMENTS {
            return keep_best(best);
        }
        let fewest = open.iter().map(|o| o.1).min().unwrap_or(0);
        let worst = open
            .iter()
            .filter(|o| o.1 == fewest)
            .map(|o| o.0)
            .fold(0.0, f64::max);
        let factor = (0.9 * DEFAULT_HAUSDORFF / worst).sqrt().clamp(0.5, 0.85);
        // A graded lattice's count follows the surface (1/h^2), a uniform
        // one's the volume (1/h^3).
        let next = |graded: bool| tets / factor.powi(if graded { 2 } else { 3 });
        if !graded && next(false) > MAX_DEFAULT_TETS {
            graded = true;
        }
        if graded && next(true) > MAX_DEFAULT_TETS {
            return keep_best(best);
        }
        h *= factor;
    }
    unreachable!("the last attempt returns")
}

/// About `cells` tets: each BCC tet has volume h^3 / 12, so h =
/// (12 V / cells)^(1/3) from the enclosed volume; the boundary's smaller
/// tets make the count run high, so one correction follows when it is more
/// than 10% off.
fn by_count(
    mesh: &TriMesh,
    cells: usize,
    graded: bool,
    lo: glam::DVec3,
    hi: glam::DVec3,
    progress: &dyn Progress,
) -> Result<(TetMesh, TetReport)> {
    if cells == 0 {
        return Err(Error::invalid("the cell count must be at least 1"));
    }
    let ext = hi - lo;
    let mut volume = mesh.signed_volume().abs();
    if volume.is_nan() || volume <= 1e-9 * ext.x * ext.y * ext.z {
        // Open or inside-out: take half the box as a first guess.
        volume = 0.5 * ext.x.max(1e-12) * ext.y.max(1e-12) * ext.z.max(1e-12);
    }
    let mut h = (12.0 * volume / cells as f64).cbrt();
    let first = nonempty(stuff(mesh, h, graded, progress)?, h)?;
    let ratio = first.num_tets() as f64 / cells as f64;
    if (ratio - 1.0).abs() <= 0.1 {
        return Ok((
            first,
            TetReport {
                edge_length: h,
                attempts: 1,
                hausdorff: None,
                graded,
            },
        ));
    }
    // Graded counts grow like 1/h^2 where the surface sets them.
    h *= ratio.powf(if graded { 0.5 } else { 1.0 / 3.0 });
    drop(first);
    let m = nonempty(stuff(mesh, h, graded, progress)?, h)?;
    Ok((
        m,
        TetReport {
            edge_length: h,
            attempts: 2,
            hausdorff: None,
            graded,
        },
    ))
}

/// Stuff the inside of `mesh` (winding number above 1/2) with tets on the
/// lattice of cell size `h`, uniform (`stuffing`) or graded (`graded`),
/// refusing a lattice too large for the machine or the mesher's indices.
fn stuff(mesh: &TriMesh, h: f64, graded: bool, progress: &dyn Progress) -> Result<TetMesh> {
    let (lo, hi) = stuffing::check_input(mesh)?;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid(format!(
            "the edge length must be a positive number, not {h}"
        )));
    }
    let lattice = stuffing::Lattice::covering(lo, hi, h);
    let box_volume = (hi - lo).x * (hi - lo).y * (hi - lo).z;
    let fill = if box_volume > 0.0 {
        (mesh.signed_volume().abs() / box_volume).max(0.1)
    } else {
        0.1
    };
    let (vertices, cubes) = lattice.counts();
    let bytes = if graded {
        graded::estimate_bytes(cubes, mesh.area(), h)
    } else {
        stuffing::estimate_bytes(&lattice, fill)
    };
    crate::memory::ensure_fits(
        &format!(
            "a {}tet mesh with edge length {h} ({vertices:.3e} lattice vertices, {}x{}x{} cells)",
            if graded { "graded " } else { "" },
            lattice.cubes[0],
            lattice.cubes[1],
            lattice.cubes[2]
        ),
        bytes.min(u64::MAX as f64) as u64,
    )?;
    let most = if graded {
        ((1u64 << 20) - 32) as f64
    } else {
        u32::MAX as f64 / 1.5
    };
    let widest = lattice.cubes.iter().copied().max().unwrap_or(0) as f64;
    if (!graded && vertices >= most) || (graded && widest >= most) {
        return Err(Error::invalid(format!(
            "edge length {h} needs {vertices:.3e} lattice vertices ({}x{}x{} cells), more than \
             the mesher's indices hold; choose a larger edge length",
            lattice.cubes[0], lattice.cubes[1], lattice.cubes[2]
        )));
    }
    let winding = winding::Winding::new(mesh);
    if graded {
        graded::stuff_graded(&winding, &lattice, progress)
    } else {
        stuffing::stuff_lattice(&winding, &lattice, progress)
    }
}
