//! Terminals: the vertices that carry most of the surface's curvature, where
//! the seams must pass so the surface can open flat (Seamster's
//! "distortion" points, seed 004 section 3.4.1).
//!
//! A vertex's strength is the absolute value of the angle defects summed
//! over a small geodesic disc around it. Summing signed defects before
//! taking the absolute value lets scan noise, which alternates in sign,
//! cancel, while a real cone (an ear tip) or saddle keeps its total.
//! Terminals are the strongest vertices, each at least `spacing` from the
//! others (non-maximum suppression), down to a strength threshold.

use glam::DVec3;
use rayon::prelude::*;

use crate::mesh::VertexId;
use crate::mesh::graph::{DiscScratch, EdgeGraph, disc};

/// Disc-summed curvature of every vertex: |sum of `defect` over its disc
/// of `radius`|.
pub fn disc_curvature(
    graph: &EdgeGraph,
    positions: &[DVec3],
    defect: &[f64],
    radius: f64,
) -> Vec<f64> {
    (0..graph.num_vertices())
        .into_par_iter()
        .map_init(
            || DiscScratch::new(graph.num_vertices()),
            |scratch, v| {
                disc(graph, positions, VertexId::from(v), radius, scratch)
                    .iter()
                    .map(|u| defect[u.idx()])
                    .sum::<f64>()
                    .abs()
            },
        )
        .collect()
}

/// The strongest vertices, strongest first, no two within `spacing` of each
/// other, none within `spacing` of `taken`, all at least `threshold` strong.
/// `eligible` filters candidates (e.g. no boundary vertices).
pub fn select(
    graph: &EdgeGraph,
    positions: &[DVec3],
    strength: &[f64],
    spacing: f64,
    threshold: f64,
    taken: &[VertexId],
    eligible: impl Fn(VertexId) -> bool,
) -> Vec<VertexId> {
    let n = graph.num_vertices();
    let mut order: Vec<usize> = (0..n).filter(|&v| strength[v] >= threshold).collect();
    order.sort_by(|&a, &b| strength[b].total_cmp(&strength[a]).then(a.cmp(&b)));
    let mut blocked = vec![false; n];
    let mut scratch = DiscScratch::new(n);
    let mut block_around = |v: VertexId, blocked: &mut Vec<bool>| {
        for u in disc(graph, positions, v, spacing, &mut scratch) {
            blocked[u.idx()] = true;
        }
    };
    for &t in taken {
        block_around(t, &mut blocked);
    }
    let mut chosen = Vec::new();
    for v in order {
        let v = VertexId::from(v);
        if blocked[v.idx()] || !eligible(v) {
            continue;
        }
        chosen.push(v);
        block_around(v, &mut blocked);
    }
    chosen
}
