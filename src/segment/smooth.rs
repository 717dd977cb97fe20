//! Taubin's lambda/mu smoothing (Taubin 1995, "A signal processing
//! approach to fair surface design"): a Laplacian step that shrinks, then
//! a slightly larger one back that inflates, so the voxel staircase (high
//! frequencies) goes and the organ's shape and volume (low frequencies)
//! stay. 3D Slicer's surface smoothing (VTK's windowed sinc) is the same
//! filter design by other weights. Written here: a few lines over the
//! mesh's vertex neighbours, where a geometry crate would add a mesh type
//! of its own.

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
            let before = &mesh.positions;
            let moved: Vec<DVec3> = (0..before.len())
                .into_par_iter()
                .map(|v| {
                    let ring = &neighbours[v];
                    if ring.is_empty() {
                        return before[v];
                    }
                    let mean =
                        ring.iter().map(|&n| before[n as usize]).sum::<DVec3>() / ring.len() as f64;
                    before[v] + factor * (mean - before[v])
                })
                .collect();
            mesh.positions = moved;
        }
        progress.advance(1);
    }
    Ok(())
}

/// Each vertex's neighbours along edges, sorted, once each.
fn vertex_neighbours(mesh: &TriMesh) -> Vec<Vec<u32>> {
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
