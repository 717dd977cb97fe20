//! The cut graph: handle loops for surfaces with genus, and cutting a mesh
//! open along seams into disk-shaped charts.
//!
//! Handle loops come from a tree-cotree decomposition (Eppstein 2003) with
//! Erickson and Whittlesey's greedy choice (2005): a shortest-path tree T
//! from a root, a maximum spanning tree C of the dual over the edges not in
//! T, weighted by the length of the loop each edge closes through T; the 2g
//! edges in neither close the shortest system of loops through the root.
//! Boundary loops join the dual as one node each, so the decomposition
//! treats a surface with holes like the closed surface with the holes
//! capped, and yields only its 2g handle loops.

use crate::error::{Error, Result};
use crate::linalg::VertexOrder;
use crate::mesh::dsu::DisjointSets;
use crate::mesh::edges::EdgeTable;
use crate::mesh::fans::{corner_fans, split_by_fans};
use crate::mesh::graph::{EdgeGraph, ShortestPaths};
use crate::mesh::{Components, EdgeId, Topology, TriMesh, VertexId};

/// Edges of the 2g shortest handle loops through `root` (empty for genus 0).
pub fn handle_loops(
    topo: &Topology,
    graph: &EdgeGraph,
    cost: &[f64],
    root: VertexId,
) -> Vec<EdgeId> {
    let tree = ShortestPaths::from_sources(graph, cost, &[(root, 0)]);
    let mut in_tree = vec![false; graph.num_edges()];
    for e in tree.via.iter().flatten() {
        in_tree[e.idx()] = true;
    }
    // Dual nodes: faces, then one per boundary loop.
    let nf = topo.num_faces();
    let mut loop_of_halfedge = std::collections::HashMap::new();
    for (l, cycle) in topo.boundary_loops().iter().enumerate() {
        for &h in cycle {
            loop_of_halfedge.insert(h, nf + l);
        }
    }
    let dual_ends = |e: EdgeId| {
        let h = topo.edge_halfedge(e);
        let a = topo.face(h).idx();
        let b = match topo.twin(h) {
            Some(t) => topo.face(t).idx(),
            None => loop_of_halfedge[&h],
        };
        (a, b)
    };
    let loop_length = |e: EdgeId| {
        let [a, b] = graph.ends(e);
        tree.distance[a.idx()] + cost[e.idx()] + tree.distance[b.idx()]
    };
    let mut dual: Vec<EdgeId> = (0..graph.num_edges())
        .map(EdgeId::from)
        .filter(|e| !in_tree[e.idx()])
        .collect();
    // Longest loops into the cotree first, leaving the shortest out.
    dual.sort_by(|&x, &y| loop_length(y).total_cmp(&loop_length(x)).then(x.cmp(&y)));
    let mut sets = DisjointSets::new(nf + topo.boundary_loops().len());
    let mut loops = Vec::new();
    for e in dual {
        let (a, b) = dual_ends(e);
        if sets.find(a) != sets.find(b) {
            sets.union(a, b);
        } else {
            let [u, v] = graph.ends(e);
            loops.push(e);
            loops.extend(tree.path_to_source(graph, u));
            loops.extend(tree.path_to_source(graph, v));
        }
    }
    loops.sort_unstable();
    loops.dedup();
    loops
}

/// Seams that leave the surface in one piece: where seams, handle loops
/// and boundary loops together enclose a patch (a seam path touching a
/// boundary or handle loop twice does), the costliest seam edge between
/// the patch and the rest is closed again, until the faces are connected
/// across the remaining open edges. Gluing two disks along an edge leaves
/// a disk, so a cut into disks stays one.
pub fn connect_pieces(topo: &Topology, seams: Vec<EdgeId>, cost: &[f64]) -> Vec<EdgeId> {
    let mut is_seam = vec![false; topo.num_edges()];
    for e in &seams {
        is_seam[e.idx()] = true;
    }
    let mut sets = DisjointSets::new(topo.num_faces());
    for e in (0..topo.num_edges()).map(EdgeId::from) {
        if !is_seam[e.idx()]
            && let Some([a, b]) = topo.edge_faces(e)
        {
            sets.union(a.idx(), b.idx());
        }
    }
    let mut by_cost = seams.clone();
    by_cost.sort_by(|x, y| cost[y.idx()].total_cmp(&cost[x.idx()]).then(x.cmp(y)));
    for e in by_cost {
        if let Some([a, b]) = topo.edge_faces(e)
            && sets.find(a.idx()) != sets.find(b.idx())
        {
            sets.union(a.idx(), b.idx());
            is_seam[e.idx()] = false;
        }
    }
    seams.into_iter().filter(|e| is_seam[e.idx()]).collect()
}

/// A mesh cut open: the cut triangles index cut vertices, and `origin`
/// maps each cut vertex to the vertex of the uncut mesh it copies.
#[derive(Clone, Debug)]
pub struct Cut {
    pub triangles: Vec<[u32; 3]>,
    pub origin: Vec<u32>,
}

impl Cut {
    /// The cut surface as a mesh of its own, its vertices at the uncut
    /// mesh's `positions`.
    pub fn mesh(&self, positions: &[glam::DVec3]) -> TriMesh {
        TriMesh::new(
            self.origin.iter().map(|&v| positions[v as usize]).collect(),
            self.triangles.clone(),
        )
    }
}

/// Cut `mesh` open along `seams`: each vertex splits into one copy per
/// wedge of faces between seams.
pub fn cut(mesh: &TriMesh, seams: &[EdgeId]) -> Cut {
    let table = EdgeTable::new(&mesh.triangles);
    let mut is_seam = vec![false; table.num_edges()];
    for e in seams {
        is_seam[e.idx()] = true;
    }
    let (fans, count) = corner_fans(&mesh.triangles, &table, |hs| {
        hs.len() == 2 && !is_seam[table.edge_of(hs[0]).idx()]
    });
    let mut triangles = mesh.triangles.clone();
    let split_from = split_by_fans(&mut triangles, mesh.num_vertices(), &fans, count);
    let origin = (0..mesh.num_vertices() as u32).chain(split_from).collect();
    Cut { triangles, origin }
}

/// Fail unless every connected piece of the cut mesh is a topological disk:
/// one boundary loop and Euler characteristic 1.
pub fn assert_disks(cut: &Cut, positions: &[glam::DVec3]) -> Result<()> {
    check_disks(&Topology::build(&cut.mesh(positions))?)
}

fn check_disks(topo: &Topology) -> Result<()> {
    let comps = Components::find(topo);
    for (i, c) in comps.topology(topo).iter().enumerate() {
        if c.euler != 1 || c.boundary_loops != 1 {
            return Err(Error::invalid(format!(
                "cutting left chart {i} with {} boundary loops and Euler characteristic {} instead of a disk",
                c.boundary_loops, c.euler
            )));
        }
    }
    Ok(())
}

/// A cut made ready to flatten: its surface, that surface's topology
/// (checked to be disks) and the order its vertices are eliminated in,
/// which the flattening's systems share (`flatten::flatten_ordered`).
pub struct Opened {
    pub cut: Cut,
    pub surface: TriMesh,
    pub topology: Topology,
    pub order: VertexOrder,
}

impl Opened {
    /// Fails as `assert_disks` does.
    pub fn new(cut: Cut, positions: &[glam::DVec3]) -> Result<Opened> {
        let surface = cut.mesh(positions);
        let topology = Topology::build(&surface)?;
        check_disks(&topology)?;
        let order = VertexOrder::of_triangles(surface.num_vertices(), &surface.triangles)?;
        Ok(Opened {
            cut,
            surface,
            topology,
            order,
        })
    }
}

/// An icosphere cut open along a chain of edges from one pole to the
/// other: a disk chart for flattening tests.
#[cfg(test)]
pub(crate) fn cut_open_sphere(subdivisions: usize) -> TriMesh {
    let sphere = crate::mesh::shapes::icosphere(subdivisions);
    let topo = Topology::build(&sphere).unwrap();
    let graph = EdgeGraph::new(&topo);
    let length = graph.lengths(&sphere.positions);
    let paths = ShortestPaths::from_sources(&graph, &length, &[(VertexId(0), 0)]);
    let far = (0..sphere.num_vertices())
        .max_by(|&a, &b| paths.distance[a].total_cmp(&paths.distance[b]))
        .unwrap();
    let seams = paths.path_to_source(&graph, VertexId::from(far));
    cut(&sphere, &seams).mesh(&sphere.positions)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::icosphere;

    #[test]
    fn a_patch_enclosed_by_seams_is_opened_back_onto_the_rest() {
        // Seams around the fan of vertex 0 (its link) cut the sphere into
        // two disks; connecting reopens exactly one edge, the costliest.
        let sphere = icosphere(2);
        let topo = Topology::build(&sphere).unwrap();
        let graph = EdgeGraph::new(&topo);
        let ring: Vec<VertexId> = graph
            .neighbours(VertexId(0))
            .iter()
            .map(|&(u, _)| u)
            .collect();
        let link: Vec<EdgeId> = ring
            .iter()
            .flat_map(|&a| ring.iter().filter_map(move |&b| (a < b).then_some((a, b))))
            .filter_map(|(a, b)| topo.edge_between(a, b))
            .collect();
        assert_eq!(link.len(), ring.len(), "the link is a cycle");
        let cut_before = cut(&sphere, &link);
        let pieces =
            |c: &Cut| Components::find(&Topology::build(&c.mesh(&sphere.positions)).unwrap()).count;
        assert_eq!(pieces(&cut_before), 2);
        let mut cost = vec![1.0; topo.num_edges()];
        cost[link[2].idx()] = 5.0;
        let seams = connect_pieces(&topo, link.clone(), &cost);
        assert_eq!(seams.len(), link.len() - 1);
        assert!(!seams.contains(&link[2]), "the costliest edge reopened");
        let after = cut(&sphere, &seams);
        assert_eq!(pieces(&after), 1);
        assert_disks(&after, &sphere.positions).unwrap();
    }
}
