//! Turn a broken triangle soup into a manifold, consistently oriented mesh by
//! splitting, never by guessing new geometry:
//! 1. faces naming a vertex twice, and later copies of duplicate faces, go;
//! 2. faces are flipped so neighbours agree on orientation, keeping the
//!    orientation most faces of each component already had;
//! 3. edges still shared by more than two faces, or run the same way by two,
//!    are cut open, and each vertex is split into one copy per fan.
//!
//! Positions are never moved, so the repaired mesh looks the same; only its
//! connectivity changes. What was done is counted in `RepairReport`.

use std::collections::VecDeque;

use serde::Serialize;

use super::defects::is_repeated;
use super::edges::{EdgeTable, halfedge_endpoints};
use super::fans::{corner_fans, split_by_fans};
use super::halfedge::Topology;
use super::ids::HalfedgeId;
use super::trimesh::TriMesh;

#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RepairReport {
    pub removed_repeated_vertex_faces: usize,
    pub removed_duplicate_faces: usize,
    pub flipped_faces: usize,
    /// Edges opened because more than two faces, or two faces running the
    /// same way, shared them.
    pub cut_edges: usize,
    /// Vertices added by splitting vertices with several fans.
    pub split_vertices: usize,
    /// Faces cut loose from all neighbours because splitting alone could not
    /// separate them (fans joined elsewhere around both ends of a bad edge).
    pub detached_faces: usize,
}

impl RepairReport {
    pub fn changed_anything(&self) -> bool {
        *self != RepairReport::default()
    }
}

/// A repaired mesh and where its elements came from.
pub struct Repaired {
    pub mesh: TriMesh,
    pub report: RepairReport,
    /// The input vertex each output vertex copies.
    pub vertex_origin: Vec<u32>,
    /// The input face each output face is.
    pub face_origin: Vec<u32>,
}

/// Repair `mesh` as the module describes; the result always builds a
/// `Topology`.
pub fn make_manifold(mesh: &TriMesh) -> (TriMesh, RepairReport) {
    let r = make_manifold_traced(mesh);
    (r.mesh, r.report)
}

/// `make_manifold`, also saying where every vertex and face came from.
pub fn make_manifold_traced(mesh: &TriMesh) -> Repaired {
    let mut report = RepairReport::default();
    let (mut out, face_origin) = drop_unusable_faces(mesh, &mut report);
    let mut vertex_origin: Vec<u32> = (0..mesh.num_vertices() as u32).collect();
    orient_consistently(&mut out, &mut report);

    let mut detached = vec![false; out.num_faces()];
    let mut first_pass = true;
    loop {
        let edges = EdgeTable::new(&out.triangles);
        let tris = &out.triangles;
        let opposite_pair = |hs: &[HalfedgeId]| {
            hs.len() == 2
                && halfedge_endpoints(tris, hs[0].idx()).0
                    != halfedge_endpoints(tris, hs[1].idx()).0
        };
        if first_pass {
            report.cut_edges = edges
                .iter()
                .filter(|(_, hs)| hs.len() >= 2 && !opposite_pair(hs))
                .count();
            first_pass = false;
        }
        let joins =
            |hs: &[HalfedgeId]| opposite_pair(hs) && hs.iter().all(|h| !detached[h.idx() / 3]);
        let (fan_of_corner, num_fans) = corner_fans(tris, &edges, joins);
        let n = out.num_vertices();
        let split_from = split_by_fans(&mut out.triangles, n, &fan_of_corner, num_fans);
        report.split_vertices += split_from.len();
        let origins: Vec<u32> = split_from
            .iter()
            .map(|&v| vertex_origin[v as usize])
            .collect();
        vertex_origin.extend(origins);
        let copies: Vec<_> = split_from
            .iter()
            .map(|&v| out.positions[v as usize])
            .collect();
        out.positions.extend(copies);

        // Faces on an edge that splitting could not open get detached, and
        // the loop splits again around what is left.
        let edges = EdgeTable::new(&out.triangles);
        let mut newly_detached = 0;
        for (_, hs) in edges.iter() {
            let tris = &out.triangles;
            let bad = hs.len() > 2
                || (hs.len() == 2
                    && halfedge_endpoints(tris, hs[0].idx()).0
                        == halfedge_endpoints(tris, hs[1].idx()).0);
            if bad {
                for h in hs {
                    if !std::mem::replace(&mut detached[h.idx() / 3], true) {
                        newly_detached += 1;
                    }
                }
            }
        }
        report.detached_faces += newly_detached;
        if newly_detached == 0 {
            break;
        }
    }
    debug_assert!(Topology::build(&out).is_ok());
    Repaired {
        mesh: out,
        report,
        vertex_origin,
        face_origin,
    }
}

/// Copy `mesh` without faces that repeat a vertex or repeat an earlier face;
/// also the input face of every kept one.
fn drop_unusable_faces(mesh: &TriMesh, report: &mut RepairReport) -> (TriMesh, Vec<u32>) {
    let mut seen = std::collections::HashSet::new();
    let keep: Vec<bool> = mesh
        .triangles
        .iter()
        .map(|t| {
            if is_repeated(t) {
                report.removed_repeated_vertex_faces += 1;
                return false;
            }
            let mut key = *t;
            key.sort_unstable();
            if !seen.insert(key) {
                report.removed_duplicate_faces += 1;
                return false;
            }
            true
        })
        .collect();
    let pick = |v: &Vec<[u32; 3]>| -> Vec<[u32; 3]> {
        v.iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(t, _)| *t)
            .collect()
    };
    let mut out = TriMesh::new(mesh.positions.clone(), pick(&mesh.triangles));
    out.facets = mesh.facets.as_ref().map(|f| super::Facets {
        names: f.names.clone(),
        of_face: f
            .of_face
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect(),
    });
    out.uvs = mesh.uvs.as_ref().map(|uv| super::UvLayer {
        coords: uv.coords.clone(),
        triangles: pick(&uv.triangles),
    });
    let kept = (0..mesh.num_faces() as u32)
        .filter(|&f| keep[f as usize])
        .collect();
    (out, kept)
}

/// Flip faces so that every edge with two faces is run in opposite
/// directions, where the surface is orientable; per connected piece, keep
/// the orientation of the majority of its faces.
fn orient_consistently(mesh: &mut TriMesh, report: &mut RepairReport) {
    let tris = &mesh.triangles;
    let edges = EdgeTable::new(tris);
    let neighbour = |h: usize| -> Option<(usize, bool)> {
        let hs = edges.halfedges(edges.edge_of(HalfedgeId::from(h)));
        if hs.len() != 2 {
            return None;
        }
        let other = if hs[0].idx() == h { hs[1] } else { hs[0] }.idx();
        let same_direction = halfedge_endpoints(tris, h).0 == halfedge_endpoints(tris, other).0;
        Some((other / 3, same_direction))
    };
    let n = tris.len();
    let mut flip: Vec<Option<bool>> = vec![None; n];
    let mut queue = VecDeque::new();
    for seed in 0..n {
        if flip[seed].is_some() {
            continue;
        }
        let mut piece = vec![seed];
        flip[seed] = Some(false);
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            let flip_f = flip[f].unwrap_or(false);
            for h in 3 * f..3 * f + 3 {
                if let Some((g, same_direction)) = neighbour(h)
                    && flip[g].is_none()
                {
                    flip[g] = Some(flip_f ^ same_direction);
                    piece.push(g);
                    queue.push_back(g);
                }
            }
        }
        let flipped = piece.iter().filter(|&&f| flip[f] == Some(true)).count();
        if 2 * flipped > piece.len() {
            for &f in &piece {
                flip[f] = flip[f].map(|x| !x);
            }
        }
    }
    for (f, fl) in flip.iter().enumerate() {
        if *fl == Some(true) {
            report.flipped_faces += 1;
            mesh.triangles[f].swap(1, 2);
            if let Some(uv) = &mut mesh.uvs {
                uv.triangles[f].swap(1, 2);
            }
        }
    }
}
