//! Charts whose flattening overlaps itself, and splitting them.
//!
//! ABF++ gives a locally injective map (no flipped triangle), but a chart
//! with a long boundary can still fold over itself globally: a polyp's head
//! opened by one slit spreads over the wall ring around its stalk. Tiled
//! textures do not mind (each face samples the texture at its own uvs), but
//! an atlas does: two places would share texels. So a chart that overlaps
//! loses a flap around one of every two faces that overlap (bounded by the
//! line halfway between them over the surface), and the flaps and the rest
//! are flattened again, until nothing overlaps (as xatlas and Blender split
//! charts). Seamster's refinement has already cut where area stretch is
//! worst, so flaps are few: small ones where a jagged facet border folds,
//! a polyp's head where it spreads over the wall ring.

use std::collections::{BinaryHeap, HashMap, HashSet};

use glam::DVec2;
use rayon::prelude::*;

use super::abf::AbfOptions;
use super::flatten::{Method, flatten};
use crate::error::Result;
use crate::mesh::dsu::DisjointSets;
use crate::mesh::graph::Nearest;
use crate::mesh::repair::make_manifold_traced;
use crate::mesh::submesh::extract;
use crate::mesh::{Components, EdgeId, FaceId, Topology, TriMesh};

/// Pairs of triangles (lower index first, sorted) whose uv triangles
/// overlap with positive area. Triangles sharing a uv corner are never
/// counted (they are neighbours in the chart; a fold between them is a
/// flip, counted separately).
pub fn overlapping_pairs(triangles: &[[u32; 3]], uv: &[DVec2]) -> Vec<[u32; 2]> {
    if triangles.is_empty() {
        return Vec::new();
    }
    let corners = |t: &[u32; 3]| t.map(|c| uv[c as usize]);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut extent = 0.0;
    for t in triangles {
        let p = corners(t);
        let (a, b) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        lo = lo.min(a);
        hi = hi.max(b);
        extent += (b - a).max_element();
    }
    let span = (hi - lo).max_element();
    if !(span > 0.0 && span.is_finite()) {
        return Vec::new();
    }
    let eps = 1e-9 * span;
    // A uniform grid of cells about a mean triangle wide: each triangle
    // meets a few cells, each cell a few triangles.
    let cell = (extent / triangles.len() as f64).max(span / 4096.0);
    let index = |p: DVec2| (((p - lo) / cell).floor()).as_ivec2();
    let mut cells: HashMap<(i32, i32), Vec<u32>> = HashMap::new();
    for (f, t) in triangles.iter().enumerate() {
        let p = corners(t);
        let (a, b) = (
            index(p[0].min(p[1]).min(p[2])),
            index(p[0].max(p[1]).max(p[2])),
        );
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                cells.entry((x, y)).or_default().push(f as u32);
            }
        }
    }
    let mut keys: Vec<_> = cells.keys().copied().collect();
    keys.sort_unstable();
    let mut pairs = Vec::new();
    for key in keys {
        let list = &cells[&key];
        for (i, &f) in list.iter().enumerate() {
            for &g in &list[i + 1..] {
                let (tf, tg) = (triangles[f as usize], triangles[g as usize]);
                if tf.iter().any(|c| tg.contains(c)) {
                    continue;
                }
                if triangles_overlap(corners(&tf), corners(&tg), eps) {
                    pairs.push([f.min(g), f.max(g)]);
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Whether two triangles share interior area (more than `eps` deep): no
/// edge of either separates them (separating axis theorem).
pub(crate) fn triangles_overlap(a: [DVec2; 3], b: [DVec2; 3], eps: f64) -> bool {
    for tri in [a, b] {
        for i in 0..3 {
            let axis = (tri[(i + 1) % 3] - tri[i]).perp();
            let len = axis.length();
            if len == 0.0 {
                continue;
            }
            let project = |t: [DVec2; 3]| {
                let d = t.map(|p| p.dot(axis) / len);
                (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
            };
            let ((a0, a1), (b0, b1)) = (project(a), project(b));
            if a1 <= b0 + eps || b1 <= a0 + eps {
                return false;
            }
        }
    }
    true
}

/// One flattened chart of a larger cut surface.
#[derive(Clone, Debug)]
pub struct FlatChart {
    /// Faces of the cut surface it holds.
    pub faces: Vec<u32>,
    /// Vertex of the cut surface of each of its vertices.
    pub origin: Vec<u32>,
    /// Its triangles, in its own vertex numbering, in `faces` order.
    pub triangles: Vec<[u32; 3]>,
    pub uv: Vec<DVec2>,
    pub method: Method,
}

/// At most this many rounds of splitting per cut surface: each flattens
/// the remaining chart again.
const MAX_ROUNDS: usize = 4;

/// Flatten the disk `chart`; with `split` (per face: whether it is drawn
/// into the atlas), split it where its flattening overlaps itself between
/// drawn faces. Uvs come back in raw flattening units (callers normalise).
pub fn flatten_charts(
    chart: &TriMesh,
    abf: &AbfOptions,
    split: Option<&[bool]>,
) -> Result<Vec<FlatChart>> {
    match split {
        Some(drawn) => flatten_part(chart, abf, drawn, MAX_ROUNDS),
        None => flatten_part(chart, abf, &[], 0),
    }
}

fn flatten_part(
    chart: &TriMesh,
    abf: &AbfOptions,
    drawn: &[bool],
    rounds: usize,
) -> Result<Vec<FlatChart>> {
    let topo = Topology::build(chart)?;
    let flat = flatten(chart, &topo, abf)?;
    let whole = || {
        vec![FlatChart {
            faces: (0..chart.num_faces() as u32).collect(),
            origin: (0..chart.num_vertices() as u32).collect(),
            triangles: chart.triangles.clone(),
            uv: flat.uv.clone(),
            method: flat.method.clone(),
        }]
    };
    if rounds == 0 {
        return Ok(whole());
    }
    let mut pairs = overlapping_pairs(&chart.triangles, &flat.uv);
    pairs.retain(|&[f, g]| drawn[f as usize] && drawn[g as usize]);
    if pairs.is_empty() {
        return Ok(whole());
    }
    // One flap per pair of overlapping patches not already inside a flap,
    // flaps apart from each other: the rest is flattened again once for all
    // of them.
    let mut in_flap = vec![false; chart.num_faces()];
    let mut flaps: Vec<Vec<FaceId>> = Vec::new();
    for [f, g] in one_pair_per_patch_pair(&topo, &pairs) {
        if in_flap[f as usize] || in_flap[g as usize] {
            continue;
        }
        let flap = flap(chart, &topo, [f as usize, g as usize]);
        if flap.iter().any(|h| in_flap[h.idx()])
            || flap.len() * 2 > chart.num_faces() + 1 && !flaps.is_empty()
        {
            continue;
        }
        for h in &flap {
            in_flap[h.idx()] = true;
        }
        flaps.push(flap);
    }
    let rest: Vec<FaceId> = (0..chart.num_faces())
        .filter(|&f| !in_flap[f])
        .map(FaceId::from)
        .collect();
    let mut parts = Vec::new();
    for faces in flaps.into_iter().chain([rest]) {
        match disks(chart, &faces) {
            Some(d) => parts.extend(d),
            // Cutting here would not leave disks; keep the overlap (the uv
            // metrics report it).
            None => return Ok(whole()),
        }
    }
    // The parts flatten independently; collected in order, so the result
    // does not depend on the thread count.
    let flattened: Vec<Vec<FlatChart>> = parts
        .into_par_iter()
        .map(|(faces, part, origin)| {
            let drawn: Vec<bool> = faces.iter().map(|f| drawn[f.idx()]).collect();
            Ok(flatten_part(&part, abf, &drawn, rounds - 1)?
                .into_iter()
                .map(|sub| FlatChart {
                    faces: sub.faces.iter().map(|&f| faces[f as usize].0).collect(),
                    origin: sub.origin.iter().map(|&v| origin[v as usize]).collect(),
                    ..sub
                })
                .collect())
        })
        .collect::<Result<_>>()?;
    Ok(flattened.into_iter().flatten().collect())
}

/// The first of `pairs` for every two patches that overlap, a patch being
/// faces in some overlapping pair that are joined across edges. A fold of
/// two patches gives as many pairs as their faces cross, and one flap
/// usually separates them all (what it leaves, the next round finds): a
/// flap search per pair searched a 10k-face dragon scan's surface 3032
/// times for 45 flaps.
fn one_pair_per_patch_pair(topo: &Topology, pairs: &[[u32; 2]]) -> Vec<[u32; 2]> {
    let mut involved = vec![false; topo.num_faces()];
    for &f in pairs.iter().flatten() {
        involved[f as usize] = true;
    }
    let mut patches = DisjointSets::new(topo.num_faces());
    for e in (0..topo.num_edges()).map(EdgeId::from) {
        if let Some([f, g]) = topo.edge_faces(e)
            && involved[f.idx()]
            && involved[g.idx()]
        {
            patches.union(f.idx(), g.idx());
        }
    }
    let mut seen = HashSet::new();
    pairs
        .iter()
        .copied()
        .filter(|&[f, g]| {
            let (p, q) = (patches.find(f as usize), patches.find(g as usize));
            seen.insert((p.min(q), p.max(q)))
        })
        .collect()
}

/// The region `faces` of `chart` as disks (its faces, mesh and chart
/// vertices each): a region touching itself at a vertex is split there; a
/// region that is not made of disks gives `None`.
#[allow(clippy::type_complexity)]
fn disks(chart: &TriMesh, faces: &[FaceId]) -> Option<Vec<(Vec<FaceId>, TriMesh, Vec<u32>)>> {
    let (sub, sub_origin) = extract(chart, faces);
    let repaired = make_manifold_traced(&sub);
    let topo = Topology::build(&repaired.mesh).ok()?;
    let components = Components::find(&topo);
    let mut out = Vec::new();
    for (c, shape) in components.topology(&topo).iter().enumerate() {
        if shape.genus != 0 || shape.boundary_loops != 1 {
            return None;
        }
        let mine: Vec<FaceId> = (0..repaired.mesh.num_faces())
            .filter(|&f| components.of_face[f] as usize == c)
            .map(FaceId::from)
            .collect();
        let (part, origin) = extract(&repaired.mesh, &mine);
        out.push((
            mine.iter()
                .map(|f| faces[repaired.face_origin[f.idx()] as usize])
                .collect(),
            part,
            origin
                .iter()
                .map(|&v| sub_origin[repaired.vertex_origin[v as usize] as usize])
                .collect(),
        ));
    }
    Some(out)
}

/// The flap to cut off so that two overlapping faces land in different
/// charts: around one of them, the faces nearer to it than to the other and
/// no farther from it than the other is (over the surface, centroid to
/// centroid); of the two candidates, the smaller. Local: a small fold near
/// the boundary costs a small flap, a polyp's head folded over the wall
/// ring costs the head.
fn flap(chart: &TriMesh, topo: &Topology, pair: [usize; 2]) -> Vec<FaceId> {
    let [a, b] = pair;
    let r = distances(chart, topo, a, f64::INFINITY, Some(b))[&b];
    let around = |seed: usize, other: usize| {
        let near = distances(chart, topo, seed, r, None);
        let far = distances(chart, topo, other, 2.0 * r, None);
        let mut faces: Vec<FaceId> = near
            .iter()
            .filter(|&(f, d)| far.get(f).is_none_or(|e| d < e))
            .map(|(&f, _)| FaceId::from(f))
            .collect();
        faces.sort_unstable();
        faces
    };
    let (fa, fb) = (around(a, b), around(b, a));
    if fb.len() <= fa.len() { fb } else { fa }
}

/// Distances over the surface (between face centroids, across edges) from
/// face `seed` to every face within `limit`; stops early once `until` is
/// settled.
fn distances(
    chart: &TriMesh,
    topo: &Topology,
    seed: usize,
    limit: f64,
    until: Option<usize>,
) -> HashMap<usize, f64> {
    let centroid = |f: usize| {
        let [a, b, c] = chart.corners(f);
        (a + b + c) / 3.0
    };
    let mut dist: HashMap<usize, f64> = HashMap::from([(seed, 0.0)]);
    let mut heap = BinaryHeap::from([Nearest(0.0, seed as u32)]);
    while let Some(Nearest(d, f)) = heap.pop() {
        let f = f as usize;
        if d > dist[&f] {
            continue;
        }
        if Some(f) == until {
            break;
        }
        for h in topo.face_halfedges(FaceId::from(f)) {
            let Some(t) = topo.twin(h) else { continue };
            let g = topo.face(t).idx();
            let nd = d + (centroid(f) - centroid(g)).length();
            if nd <= limit && dist.get(&g).is_none_or(|&old| nd < old) {
                dist.insert(g, nd);
                heap.push(Nearest(nd, g as u32));
            }
        }
    }
    dist
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separating_axis_finds_overlap_and_ignores_touching() {
        let t = [DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)];
        let shifted = t.map(|p| p + DVec2::new(0.25, 0.25));
        assert!(triangles_overlap(t, shifted, 1e-12));
        // Sharing the hypotenuse only.
        let across = [
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!(!triangles_overlap(t, across, 1e-12));
        // Apart.
        let far = t.map(|p| p + DVec2::new(3.0, 0.0));
        assert!(!triangles_overlap(t, far, 1e-12));
    }

    #[test]
    fn a_folded_strip_overlaps_and_a_flat_one_does_not() {
        // Two unit squares of two triangles each, the second laid over the
        // first in uv (a chart folded back onto itself) but not sharing
        // corners.
        let uv = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(0.5, 0.0),
            DVec2::new(1.5, 0.0),
            DVec2::new(1.5, 1.0),
            DVec2::new(0.5, 1.0),
        ];
        let tris = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let pairs = overlapping_pairs(&tris, &uv);
        assert!(!pairs.is_empty());
        assert!(pairs.iter().all(|p| p[0] < 2 && p[1] >= 2));
        let apart: Vec<DVec2> = uv
            .iter()
            .enumerate()
            .map(|(i, &p)| if i >= 4 { p + DVec2::new(1.0, 0.0) } else { p })
            .collect();
        assert!(overlapping_pairs(&tris, &apart).is_empty());
    }
}
