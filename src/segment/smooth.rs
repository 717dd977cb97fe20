//! Low-pass smoothing of a mesh, so the voxel staircase (high
//! frequencies) goes and the organ's shape and volume (low frequencies)
//! stay: Taubin's lambda/mu (Taubin 1995, "A signal processing approach
//! to fair surface design"), a Laplacian step that shrinks then a slightly
//! larger one back that inflates; and the windowed sinc (Taubin, Zhang and
//! Golub 1996), the same design by other weights, as VTK and 3D Slicer
//! smooth. Written here: a few lines over the mesh's vertex neighbours,
//! where a geometry crate would add a mesh type of its own.

use glam::DVec3;
use rayon::prelude::*;

use crate::error::Result;
use crate::mesh::TriMesh;
use crate::progress::{self, Progress};

/// The shrinking step.
const LAMBDA: f64 = 0.5;
/// The inflating step: 1/lambda + 1/mu = 0.1, the pass band's edge (Taubin
/// sec. 4: frequencies below it are kept).
const MU: f64 = -0.5263;

/// `iterations` lambda/mu pairs over the uniform (umbrella) Laplacian.
/// The same bytes on any thread count: each vertex's move reads only the
/// positions before the step.
pub fn taubin(mesh: &mut TriMesh, iterations: usize, progress: &dyn Progress) -> Result<()> {
    if iterations == 0 {
        return Ok(());
    }
    let neighbours = vertex_neighbours(mesh);
    progress.stage("smoothing", iterations as u64);
    for _ in 0..iterations {
        progress::check(progress)?;
        for factor in [LAMBDA, MU] {
            mesh.positions = umbrella_step(&mesh.positions, &neighbours, factor);
        }
        progress.advance(1);
    }
    Ok(())
}

/// The windowed sinc's pass band: VTK's default 0.1 (of the umbrella
/// Laplacian's 0..2; Slicer's default smoothing is 0.01).
pub const PASS_BAND: f64 = 0.1;

/// Windowed-sinc smoothing (Taubin, Zhang and Golub 1996, "Optimal
/// surface smoothing as filter design", sec. 4): a low-pass filter of the
/// mesh signal, f(k) = sum over j of w_j c_j T_j(1 - k/2) / f(0) for the
/// umbrella Laplacian's eigenvalues k in 0..2, with c_j the Fourier
/// coefficients of the ideal low pass up to `pass_band` and w_j a Hamming
/// window, n + 1 terms by the Chebyshev recurrence in n = `iterations`
/// Laplacian steps. It keeps the lowest frequencies (the organ's shape,
/// its volume) and takes out the rest more sharply than lambda/mu. Unlike
/// VTK, the cutoff is not moved to give the pass band a gain of 1: at 20
/// iterations the gain is 0.5 at the pass band and 0.8 at half of it
/// (VTK's: 1.0 at both), so it smooths harder than VTK at the same pass
/// band. Fewer than about 10 iterations make a plain shrinking filter.
/// The same bytes on any thread count: each step reads only the last two.
pub fn windowed_sinc(
    mesh: &mut TriMesh,
    iterations: usize,
    pass_band: f64,
    progress: &dyn Progress,
) -> Result<()> {
    assert!(
        pass_band > 0.0 && pass_band < 2.0,
        "a pass band within the Laplacian's 0..2"
    );
    if iterations == 0 {
        return Ok(());
    }
    let n = iterations;
    let theta = (1.0 - 0.5 * pass_band).acos();
    let weight = |j: usize| {
        let window = 0.54 + 0.46 * (j as f64 * std::f64::consts::PI / (n + 1) as f64).cos();
        let ideal = if j == 0 {
            theta / std::f64::consts::PI
        } else {
            2.0 * (j as f64 * theta).sin() / (j as f64 * std::f64::consts::PI)
        };
        window * ideal
    };
    // f(0) = 1: a translation of the whole mesh passes unchanged.
    let total: f64 = (0..=n).map(weight).sum();
    let neighbours = vertex_neighbours(mesh);
    // (I - K/2) x: half way to the neighbours' mean.
    let half_step = |x: &[DVec3]| umbrella_step(x, &neighbours, 0.5);
    progress.stage("smoothing", n as u64);
    let mut older = mesh.positions.clone();
    let mut old = half_step(&older);
    progress.advance(1);
    let mut sum: Vec<DVec3> = older
        .iter()
        .zip(&old)
        .map(|(&a, &b)| weight(0) * a + weight(1) * b)
        .collect();
    for j in 2..=n {
        progress::check(progress)?;
        // T_j = 2 (I - K/2) T_(j-1) - T_(j-2).
        let next: Vec<DVec3> = half_step(&old)
            .iter()
            .zip(&older)
            .map(|(&h, &o)| 2.0 * h - o)
            .collect();
        let w = weight(j);
        for (s, &x) in sum.iter_mut().zip(&next) {
            *s += w * x;
        }
        older = std::mem::replace(&mut old, next);
        progress.advance(1);
    }
    mesh.positions = sum.into_iter().map(|s| s / total).collect();
    Ok(())
}

/// Each vertex moved `factor` of the way to its neighbours' mean (the
/// umbrella Laplacian step both smoothers are made of); a vertex without
/// neighbours stays.
fn umbrella_step(x: &[DVec3], neighbours: &[Vec<u32>], factor: f64) -> Vec<DVec3> {
    (0..x.len())
        .into_par_iter()
        .map(|v| {
            let ring = &neighbours[v];
            if ring.is_empty() {
                return x[v];
            }
            let mean = ring.iter().map(|&m| x[m as usize]).sum::<DVec3>() / ring.len() as f64;
            x[v] + factor * (mean - x[v])
        })
        .collect()
}

/// Each vertex's neighbours along edges, sorted, once each.
pub(super) fn vertex_neighbours(mesh: &TriMesh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); mesh.num_vertices()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            out[a as usize].push(b);
            out[b as usize].push(a);
        }
    }
    for ring in &mut out {
        ring.sort_unstable();
        ring.dedup();
    }
    out
}
