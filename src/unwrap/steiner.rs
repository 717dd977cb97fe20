//! Approximate minimal Steiner tree over the edge graph (Mehlhorn 1988, a
//! 2-approximation): the seams joining all terminals by the cheapest edges.
//!
//! Each terminal is a group of vertices already joined for free (a single
//! curvature terminal, a whole boundary loop, the handle loops of a torus).
//! 1. Dijkstra from all groups at once: every vertex learns its nearest
//!    group (its Voronoi cell) and the distance to it.
//! 2. Every edge between two cells offers a bridge between their groups,
//!    costing both distances plus the edge; keep the cheapest per pair.
//! 3. A minimum spanning tree over the groups with those bridges.
//! 4. Expand each chosen bridge into its shortest paths, take a minimum
//!    spanning tree of that subgraph (groups pre-joined), and prune leaves
//!    that belong to no group.

use std::collections::HashMap;

use crate::mesh::dsu::DisjointSets;
use crate::mesh::graph::{EdgeGraph, ShortestPaths};
use crate::mesh::{EdgeId, VertexId};

/// Edges of an approximate minimal Steiner tree joining every group, none
/// of them between two vertices of the same group. Fewer than two groups
/// need no edges.
pub fn tree(graph: &EdgeGraph, cost: &[f64], groups: &[Vec<VertexId>]) -> Vec<EdgeId> {
    if groups.len() < 2 {
        return Vec::new();
    }
    let sources: Vec<(VertexId, u32)> = groups
        .iter()
        .enumerate()
        .flat_map(|(g, vs)| vs.iter().map(move |&v| (v, g as u32)))
        .collect();
    let paths = ShortestPaths::from_sources(graph, cost, &sources);

    // Cheapest bridge per pair of groups.
    let mut bridges: HashMap<(u32, u32), (f64, EdgeId)> = HashMap::new();
    for e in 0..graph.num_edges() {
        let e = EdgeId::from(e);
        let [a, b] = graph.ends(e);
        let (ga, gb) = (paths.source[a.idx()], paths.source[b.idx()]);
        if ga == gb || ga == u32::MAX || gb == u32::MAX {
            continue;
        }
        let length = paths.distance[a.idx()] + cost[e.idx()] + paths.distance[b.idx()];
        let key = (ga.min(gb), ga.max(gb));
        let better = bridges
            .get(&key)
            .is_none_or(|&(l, old)| (length, e.0) < (l, old.0));
        if better {
            bridges.insert(key, (length, e));
        }
    }
    let mut bridges: Vec<((u32, u32), (f64, EdgeId))> = bridges.into_iter().collect();
    bridges.sort_by(|x, y| x.1.0.total_cmp(&y.1.0).then(x.1.1.cmp(&y.1.1)));

    // Minimum spanning tree over groups, each bridge expanded to its paths.
    let mut group_sets = DisjointSets::new(groups.len());
    let mut candidate = Vec::new();
    for ((ga, gb), (_, e)) in bridges {
        if group_sets.find(ga as usize) == group_sets.find(gb as usize) {
            continue;
        }
        group_sets.union(ga as usize, gb as usize);
        let [a, b] = graph.ends(e);
        candidate.push(e);
        candidate.extend(paths.path_to_source(graph, a));
        candidate.extend(paths.path_to_source(graph, b));
    }
    candidate.sort_unstable();
    candidate.dedup();

    // Minimum spanning tree of the expanded subgraph, groups pre-joined.
    let mut vertex_sets = DisjointSets::new(graph.num_vertices());
    for vs in groups {
        for w in vs.windows(2) {
            vertex_sets.union(w[0].idx(), w[1].idx());
        }
    }
    candidate.sort_by(|x, y| cost[x.idx()].total_cmp(&cost[y.idx()]).then(x.cmp(y)));
    let mut edges: Vec<EdgeId> = candidate
        .into_iter()
        .filter(|&e| {
            let [a, b] = graph.ends(e);
            let joined = vertex_sets.find(a.idx()) == vertex_sets.find(b.idx());
            if !joined {
                vertex_sets.union(a.idx(), b.idx());
            }
            !joined
        })
        .collect();

    let mut in_group = vec![false; graph.num_vertices()];
    for vs in groups {
        for v in vs {
            in_group[v.idx()] = true;
        }
    }
    prune_leaves(graph, &mut edges, |v| in_group[v.idx()]);
    edges.sort_unstable();
    edges
}

/// Repeatedly drop edges hanging from a vertex of degree one that is not
/// `kept`.
pub fn prune_leaves(graph: &EdgeGraph, edges: &mut Vec<EdgeId>, kept: impl Fn(VertexId) -> bool) {
    let mut degree = vec![0u32; graph.num_vertices()];
    let mut alive = vec![false; graph.num_edges()];
    for &e in edges.iter() {
        alive[e.idx()] = true;
        for v in graph.ends(e) {
            degree[v.idx()] += 1;
        }
    }
    let mut stack: Vec<VertexId> = (0..graph.num_vertices())
        .map(VertexId::from)
        .filter(|&v| degree[v.idx()] == 1 && !kept(v))
        .collect();
    while let Some(v) = stack.pop() {
        if degree[v.idx()] != 1 {
            continue;
        }
        let Some(&(u, e)) = graph.neighbours(v).iter().find(|(_, e)| alive[e.idx()]) else {
            continue;
        };
        alive[e.idx()] = false;
        degree[v.idx()] -= 1;
        degree[u.idx()] -= 1;
        if degree[u.idx()] == 1 && !kept(u) {
            stack.push(u);
        }
    }
    edges.retain(|e| alive[e.idx()]);
}
