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
///
/// Summing every vertex's own disc costs the vertex count times the disc's,
/// and a disc covers a fixed share of the surface, so the cost grows with
/// the square of the mesh's size: on a 900k-face bunny it was a third of
/// the unwrap. Where a typical disc holds more than `exact_limit`
/// vertices, a grid a quarter of the radius wide samples the sums instead:
/// only each cell's first vertex gets its disc summed, the others 0. The
/// sum moves little over a quarter of its radius, so terminals chosen
/// among the samples lie within a cell of the exact ones.
pub fn disc_curvature(
    graph: &EdgeGraph,
    positions: &[DVec3],
    defect: &[f64],
    radius: f64,
    exact_limit: usize,
) -> Vec<f64> {
    let n = graph.num_vertices();
    let disc_sum = |scratch: &mut DiscScratch, v: usize| {
        disc(graph, positions, VertexId::from(v), radius, scratch)
            .iter()
            .map(|u| defect[u.idx()])
            .sum::<f64>()
            .abs()
    };
    let mut scratch = DiscScratch::new(n);
    let probes: Vec<usize> = (0..16)
        .map(|k| k * n / 16)
        .filter(|&v| v < n && !graph.neighbours(VertexId::from(v)).is_empty())
        .collect();
    let typical = probes
        .iter()
        .map(|&v| disc(graph, positions, VertexId::from(v), radius, &mut scratch).len())
        .sum::<usize>()
        / probes.len().max(1);
    if typical <= exact_limit {
        return (0..n)
            .into_par_iter()
            .map_init(|| DiscScratch::new(n), disc_sum)
            .collect();
    }
    // The first vertex with edges in each grid cell.
    let cell = radius / 4.0;
    let key = |p: DVec3| (p / cell).floor().as_i64vec3().to_array();
    let mut first = std::collections::HashMap::new();
    let sampled: Vec<usize> = (0..n)
        .filter(|&v| {
            let edges = !graph.neighbours(VertexId::from(v)).is_empty();
            edges && *first.entry(key(positions[v])).or_insert(v) == v
        })
        .collect();
    let sums: Vec<f64> = sampled
        .par_iter()
        .map_init(|| DiscScratch::new(n), |scratch, &v| disc_sum(scratch, v))
        .collect();
    // Only the sampled vertices are candidates: a vertex that borrowed its
    // cell's sum could be chosen where its own is under the threshold.
    let mut strength = vec![0.0; n];
    for (&v, &sum) in sampled.iter().zip(&sums) {
        strength[v] = sum;
    }
    strength
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
