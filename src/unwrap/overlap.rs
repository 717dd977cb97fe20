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
//! a polyp's head where it spreads over the wall ring. Where a few rounds of
//! this leave a fold, the layout is kept and cut into disks that do not
//! overlap (`peel`), so no two faces of a split layout overlap (a flipped
//! face aside, which the flattening avoids and reports).

use std::collections::{BinaryHeap, HashMap, HashSet};

use glam::DVec2;
use rayon::prelude::*;

use super::abf::AbfOptions;
use super::cutgraph::Opened;
use super::flatten::{Flattened, Method, flatten, flatten_ordered};
use super::intersect::overlapping_pairs;
use crate::error::Result;
use crate::mesh::dsu::DisjointSets;
use crate::mesh::graph::Nearest;
use crate::mesh::repair::make_manifold_traced;
use crate::mesh::submesh::extract;
use crate::mesh::{Components, EdgeId, FaceId, Topology, TriMesh, VertexId};

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
    opened: &Opened,
    abf: &AbfOptions,
    split: Option<&[bool]>,
) -> Result<Vec<FlatChart>> {
    let (drawn, rounds) = match split {
        Some(drawn) => (drawn, MAX_ROUNDS),
        None => (&[][..], 0),
    };
    let chart = &opened.surface;
    let flat = flatten_ordered(chart, &opened.topology, &opened.order, abf)?;
    split_overlaps(chart, &opened.topology, flat, abf, drawn, rounds)
}

fn flatten_part(
    chart: &TriMesh,
    abf: &AbfOptions,
    drawn: &[bool],
    rounds: usize,
) -> Result<Vec<FlatChart>> {
    let topo = Topology::build(chart)?;
    let flat = flatten(chart, &topo, abf)?;
    split_overlaps(chart, &topo, flat, abf, drawn, rounds)
}

/// `flat`, `chart`'s flattening, as it is, or split as `flatten_charts`
/// says.
fn split_overlaps(
    chart: &TriMesh,
    topo: &Topology,
    flat: Flattened,
    abf: &AbfOptions,
    drawn: &[bool],
    rounds: usize,
) -> Result<Vec<FlatChart>> {
    let whole = || {
        vec![FlatChart {
            faces: (0..chart.num_faces() as u32).collect(),
            origin: (0..chart.num_vertices() as u32).collect(),
            triangles: chart.triangles.clone(),
            uv: flat.uv.clone(),
            method: flat.method.clone(),
        }]
    };
    if drawn.is_empty() {
        return Ok(whole());
    }
    let mut pairs = overlapping_pairs(&chart.triangles, &flat.uv);
    pairs.retain(|&[f, g]| drawn[f as usize] && drawn[g as usize]);
    if pairs.is_empty() {
        return Ok(whole());
    }
    if rounds == 0 {
        return Ok(peel(chart, topo, &flat.uv, &flat.method, &pairs));
    }
    // One flap per pair of overlapping patches not already inside a flap,
    // flaps apart from each other: the rest is flattened again once for all
    // of them.
    let mut in_flap = vec![false; chart.num_faces()];
    let mut flaps: Vec<Vec<FaceId>> = Vec::new();
    for [f, g] in one_pair_per_patch_pair(topo, &pairs) {
        if in_flap[f as usize] || in_flap[g as usize] {
            continue;
        }
        let flap = flap(chart, topo, [f as usize, g as usize]);
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
            // Cutting here would not leave disks.
            None => return Ok(peel(chart, topo, &flat.uv, &flat.method, &pairs)),
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

/// The last resort, when re-flattening has not removed every overlap in
/// `MAX_ROUNDS` or a flap would not leave disks: the layout `uv` as it is,
/// cut into disks none of which holds both faces of an overlapping pair.
/// Each disk grows from its lowest unclaimed face across edges, taking a
/// face whose partners in `pairs` it does not hold, and which leaves it a
/// disk: joined by one or two edges, and at each of the face's corners the
/// disk's faces one unbroken run of the corner's fan (so no corner is
/// pinched and no hole closes). Without flipped faces the layout is
/// locally injective, so the pairs are its only overlaps; a bust scan's
/// four leftover folds cost a few small charts and no distortion. Each
/// disk repeats the layout's `method`.
fn peel(
    chart: &TriMesh,
    topo: &Topology,
    uv: &[DVec2],
    method: &Method,
    pairs: &[[u32; 2]],
) -> Vec<FlatChart> {
    const NONE: u32 = u32::MAX;
    let n = chart.num_faces();
    let mut partners: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &[f, g] in pairs {
        partners[f as usize].push(g);
        partners[g as usize].push(f);
    }
    let neighbours = |f: usize| {
        topo.face_halfedges(FaceId::from(f))
            .into_iter()
            .filter_map(|h| topo.twin(h).map(|t| topo.face(t).idx()))
    };
    let mut region = vec![NONE; n];
    // Whether the faces of `r`, with `f`, make one run round corner `v`.
    let one_run = |region: &[u32], r: u32, f: usize, v: VertexId| {
        let fan: Vec<bool> = topo
            .outgoing(v)
            .map(|h| {
                let g = topo.face(h).idx();
                g == f || region[g] == r
            })
            .collect();
        let closed = !topo.is_boundary_vertex(v);
        let starts = (0..fan.len())
            .filter(|&i| {
                let before = match i {
                    0 if closed => fan[fan.len() - 1],
                    0 => false,
                    _ => fan[i - 1],
                };
                fan[i] && !before
            })
            .count();
        starts <= 1
    };
    let mut charts = Vec::new();
    for seed in 0..n {
        if region[seed] != NONE {
            continue;
        }
        let r = charts.len() as u32;
        region[seed] = r;
        let mut faces = vec![FaceId::from(seed)];
        let mut queue: std::collections::VecDeque<usize> = neighbours(seed).collect();
        while let Some(f) = queue.pop_front() {
            if region[f] != NONE || partners[f].iter().any(|&g| region[g as usize] == r) {
                continue;
            }
            let joined = neighbours(f).filter(|&g| region[g] == r).count();
            let corners = chart.triangles[f].map(VertexId);
            if !(1..=2).contains(&joined) || !corners.iter().all(|&v| one_run(&region, r, f, v)) {
                continue;
            }
            region[f] = r;
            faces.push(FaceId::from(f));
            // A face turned away may fit once the disk has grown round it.
            queue.extend(neighbours(f).filter(|&g| region[g] == NONE));
        }
        faces.sort_unstable();
        let (part, origin) = extract(chart, &faces);
        charts.push(FlatChart {
            faces: faces.iter().map(|f| f.0).collect(),
            uv: origin.iter().map(|&v| uv[v as usize]).collect(),
            origin,
            triangles: part.triangles,
            method: method.clone(),
        });
    }
    charts
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
    use crate::unwrap::intersect::triangles_overlap;

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

    #[test]
    fn peeling_a_strip_wound_over_itself_leaves_disks_that_do_not_overlap() {
        // A flat strip of 40 x 3 quads (so with interior vertices) whose
        // layout winds 1.25 times round a ring: its last quarter lies over
        // its first.
        let (quads, rows) = (40, 4);
        let mut positions = Vec::new();
        let mut uv = Vec::new();
        for i in 0..=quads {
            let angle = i as f64 / quads as f64 * 2.5 * std::f64::consts::PI;
            let radial = DVec2::new(angle.cos(), angle.sin());
            for side in 0..rows {
                positions.push(glam::DVec3::new(i as f64, side as f64, 0.0));
                uv.push(radial * (3.0 + side as f64));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..quads as u32 {
            for side in 0..rows - 1 {
                let a = rows * i + side;
                let (b, c, d) = (a + 1, a + rows, a + rows + 1);
                triangles.push([a, c, d]);
                triangles.push([a, d, b]);
            }
        }
        let chart = TriMesh::new(positions, triangles);
        let topo = Topology::build(&chart).unwrap();
        let pairs = overlapping_pairs(&chart.triangles, &uv);
        assert!(!pairs.is_empty());
        let method = Method::Lscm {
            reason: String::new(),
            unfolded: 0,
            flipped: 0,
        };
        let parts = peel(&chart, &topo, &uv, &method, &pairs);
        assert!((2..=3).contains(&parts.len()), "{} parts", parts.len());
        let mut seen = vec![0; chart.num_faces()];
        for part in &parts {
            for &f in &part.faces {
                seen[f as usize] += 1;
            }
            assert!(overlapping_pairs(&part.triangles, &part.uv).is_empty());
        }
        assert!(seen.iter().all(|&k| k == 1));
        assert_disks(&chart, &parts);

        // A face in the middle of a grid kept from the disk of the first:
        // the disk must not close round it (a hole).
        let n = 6u32;
        let grid = TriMesh::new(
            (0..=n)
                .flat_map(|y| (0..=n).map(move |x| glam::DVec3::new(x as f64, y as f64, 0.0)))
                .collect(),
            (0..n)
                .flat_map(|y| {
                    (0..n).flat_map(move |x| {
                        let a = y * (n + 1) + x;
                        [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
                    })
                })
                .collect(),
        );
        let flat: Vec<DVec2> = grid.positions.iter().map(|p| p.truncate()).collect();
        let middle = 2 * (3 * n + 3);
        let parts = peel(
            &grid,
            &Topology::build(&grid).unwrap(),
            &flat,
            &method,
            &[[0, middle]],
        );
        assert!(parts.len() >= 2);
        assert!(
            !parts
                .iter()
                .any(|p| p.faces.contains(&0) && p.faces.contains(&middle))
        );
        assert_disks(&grid, &parts);
    }

    fn assert_disks(chart: &TriMesh, parts: &[FlatChart]) {
        for part in parts {
            let mesh = TriMesh::new(
                part.origin
                    .iter()
                    .map(|&v| chart.positions[v as usize])
                    .collect(),
                part.triangles.clone(),
            );
            let topo = Topology::build(&mesh).unwrap();
            let shapes = Components::find(&topo).topology(&topo);
            assert_eq!(shapes.len(), 1);
            assert_eq!((shapes[0].genus, shapes[0].boundary_loops), (0, 1));
        }
    }
}
