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

use std::collections::{HashMap, HashSet};

use glam::DVec3;
use rayon::prelude::*;

use crate::mesh::VertexId;
use crate::mesh::graph::{DiscScratch, EdgeGraph, disc};

/// Disc-summed curvature: |sum of `defect` over the disc of `radius`| at
/// every vertex that could reach `threshold`, 0 elsewhere.
///
/// Summing every vertex's own disc costs the vertex count times the disc's
/// (on the bunny, 28k discs of about 240 vertices: a sixth of its unwrap),
/// and terminals only need the sums that reach the threshold. The sum
/// moves little over a quarter of its radius, so a grid that wide samples
/// it first, one disc per cell (its first vertex); then every vertex in or
/// beside a cell whose sample reached `REFINE_SHARE` of the threshold gets
/// its own disc summed. A vertex over the threshold has such a sample
/// within a cell of it, so terminals chosen from these sums are those
/// the exact sums give (a threshold of 0 sums every disc).
pub fn disc_curvature(
    graph: &EdgeGraph,
    positions: &[DVec3],
    defect: &[f64],
    radius: f64,
    threshold: f64,
) -> Vec<f64> {
    let n = graph.num_vertices();
    let sums = |vertices: &[usize]| -> Vec<f64> {
        vertices
            .par_iter()
            .map_init(
                || DiscScratch::new(n),
                |scratch, &v| {
                    disc(graph, positions, VertexId::from(v), radius, scratch)
                        .iter()
                        .map(|u| defect[u.idx()])
                        .sum::<f64>()
                        .abs()
                },
            )
            .collect()
    };
    let cell = radius / 4.0;
    let key = |v: usize| (positions[v] / cell).floor().as_i64vec3().to_array();
    let with_edges: Vec<usize> = (0..n)
        .filter(|&v| !graph.neighbours(VertexId::from(v)).is_empty())
        .collect();
    // The first vertex with edges in each cell.
    let mut first = HashMap::new();
    let sampled: Vec<usize> = with_edges
        .iter()
        .copied()
        .filter(|&v| *first.entry(key(v)).or_insert(v) == v)
        .collect();
    let sampled_sums = sums(&sampled);
    // The cells in or beside one whose sample is strong enough.
    let mut near_strong = HashSet::new();
    for (&v, &sum) in sampled.iter().zip(&sampled_sums) {
        if sum >= REFINE_SHARE * threshold {
            let [x, y, z] = key(v);
            for d in 0..27 {
                near_strong.insert([x + d % 3 - 1, y + d / 3 % 3 - 1, z + d / 9 - 1]);
            }
        }
    }
    let refined: Vec<usize> = with_edges
        .into_iter()
        .filter(|&v| first[&key(v)] != v && near_strong.contains(&key(v)))
        .collect();
    let refined_sums = sums(&refined);
    // A vertex with no sum of its own stays 0: one that borrowed its
    // cell's sum could be chosen where its own is under the threshold.
    let mut strength = vec![0.0; n];
    for (&v, &sum) in sampled
        .iter()
        .chain(&refined)
        .zip(sampled_sums.iter().chain(&refined_sums))
    {
        strength[v] = sum;
    }
    strength
}

/// The share of the threshold a cell's sampled disc sum must reach for
/// the vertices in and beside the cell to be summed (`disc_curvature`).
const REFINE_SHARE: f64 = 0.5;

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
