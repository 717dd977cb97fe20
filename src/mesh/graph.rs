//! The mesh's edge graph with a cost per edge, and shortest paths on it
//! (Dijkstra, from one source or many), shared by terminal selection, the
//! Steiner tree and the handle loops.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::{EdgeId, Topology, VertexId};

/// Vertices and their incident edges, compressed (CSR).
pub struct EdgeGraph {
    start: Vec<u32>,
    /// (neighbour, edge) pairs.
    links: Vec<(VertexId, EdgeId)>,
    ends: Vec<[VertexId; 2]>,
}

impl EdgeGraph {
    pub fn new(topo: &Topology) -> EdgeGraph {
        let n = topo.num_vertices();
        let ends: Vec<[VertexId; 2]> = (0..topo.num_edges())
            .map(|e| topo.edge_vertices(EdgeId::from(e)))
            .collect();
        let mut degree = vec![0u32; n + 1];
        for [a, b] in &ends {
            degree[a.idx() + 1] += 1;
            degree[b.idx() + 1] += 1;
        }
        for v in 0..n {
            degree[v + 1] += degree[v];
        }
        let start = degree.clone();
        let mut fill = degree;
        let mut links = vec![(VertexId(0), EdgeId(0)); ends.len() * 2];
        for (e, [a, b]) in ends.iter().enumerate() {
            links[fill[a.idx()] as usize] = (*b, EdgeId::from(e));
            fill[a.idx()] += 1;
            links[fill[b.idx()] as usize] = (*a, EdgeId::from(e));
            fill[b.idx()] += 1;
        }
        EdgeGraph { start, links, ends }
    }

    pub fn num_vertices(&self) -> usize {
        self.start.len() - 1
    }

    pub fn num_edges(&self) -> usize {
        self.ends.len()
    }

    #[inline]
    pub fn neighbours(&self, v: VertexId) -> &[(VertexId, EdgeId)] {
        &self.links[self.start[v.idx()] as usize..self.start[v.idx() + 1] as usize]
    }

    #[inline]
    pub fn ends(&self, e: EdgeId) -> [VertexId; 2] {
        self.ends[e.idx()]
    }

    /// The length of every edge, its ends at `positions`.
    pub fn lengths(&self, positions: &[glam::DVec3]) -> Vec<f64> {
        self.ends
            .iter()
            .map(|[a, b]| (positions[a.idx()] - positions[b.idx()]).length())
            .collect()
    }

    /// The end of `e` that is not `v`.
    #[inline]
    pub fn other(&self, e: EdgeId, v: VertexId) -> VertexId {
        let [a, b] = self.ends[e.idx()];
        if a == v { b } else { a }
    }
}

/// A `BinaryHeap` entry popped smallest distance first, ties by id so the
/// search order is deterministic.
#[derive(PartialEq)]
pub struct Nearest(pub f64, pub u32);
impl Eq for Nearest {}
impl Ord for Nearest {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}
impl PartialOrd for Nearest {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Shortest paths from a set of labelled sources.
pub struct ShortestPaths {
    pub distance: Vec<f64>,
    /// The edge by which each vertex was reached (`None` for sources and
    /// unreached vertices).
    pub via: Vec<Option<EdgeId>>,
    /// The label of the source each vertex is nearest to (its Voronoi cell).
    pub source: Vec<u32>,
}

impl ShortestPaths {
    /// Multi-source Dijkstra: `sources` are (vertex, label) pairs at distance
    /// zero; edges cost `cost[e]` (non-negative).
    pub fn from_sources(graph: &EdgeGraph, cost: &[f64], sources: &[(VertexId, u32)]) -> Self {
        let n = graph.num_vertices();
        let mut distance = vec![f64::INFINITY; n];
        let mut via = vec![None; n];
        let mut source = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        for &(v, label) in sources {
            if distance[v.idx()] > 0.0 {
                distance[v.idx()] = 0.0;
                source[v.idx()] = label;
                heap.push(Nearest(0.0, v.0));
            }
        }
        while let Some(Nearest(d, v)) = heap.pop() {
            let v = VertexId(v);
            if d > distance[v.idx()] {
                continue;
            }
            for &(u, e) in graph.neighbours(v) {
                let nd = d + cost[e.idx()];
                if nd < distance[u.idx()] {
                    distance[u.idx()] = nd;
                    via[u.idx()] = Some(e);
                    source[u.idx()] = source[v.idx()];
                    heap.push(Nearest(nd, u.0));
                }
            }
        }
        ShortestPaths {
            distance,
            via,
            source,
        }
    }

    /// Edges from `v` back to its source.
    pub fn path_to_source(&self, graph: &EdgeGraph, mut v: VertexId) -> Vec<EdgeId> {
        let mut path = Vec::new();
        while let Some(e) = self.via[v.idx()] {
            path.push(e);
            v = graph.other(e, v);
        }
        path
    }
}

/// The geodesic disc of `radius` around `center`: the vertices reachable
/// from it through vertices within that (straight-line) distance. For the
/// small radii used here this is the geodesic disc; growing it by breadth
/// first search needs no priority queue, which matters when every vertex
/// gets a disc (Seamster sums some 16k of them on the bunny). The disc
/// lives in `scratch` until the next call.
pub fn disc<'s>(
    graph: &EdgeGraph,
    positions: &[glam::DVec3],
    center: VertexId,
    radius: f64,
    scratch: &'s mut DiscScratch,
) -> &'s [VertexId] {
    scratch.generation += 1;
    let stamp = scratch.generation;
    let origin = positions[center.idx()];
    let r2 = radius * radius;
    let DiscScratch { seen, out, .. } = scratch;
    out.clear();
    out.push(center);
    seen[center.idx()] = stamp;
    let mut next = 0;
    while next < out.len() {
        let v = out[next];
        next += 1;
        for &(u, _) in graph.neighbours(v) {
            // A vertex is measured once: one outside the radius is marked
            // too, for the other vertices of the disc's rim that reach it.
            if seen[u.idx()] != stamp {
                seen[u.idx()] = stamp;
                if (positions[u.idx()] - origin).length_squared() <= r2 {
                    out.push(u);
                }
            }
        }
    }
    out
}

/// Reusable visit marks and output for `disc`.
pub struct DiscScratch {
    seen: Vec<u32>,
    generation: u32,
    out: Vec<VertexId>,
}

impl DiscScratch {
    pub fn new(n: usize) -> Self {
        DiscScratch {
            seen: vec![0; n],
            generation: 0,
            out: Vec::new(),
        }
    }
}
