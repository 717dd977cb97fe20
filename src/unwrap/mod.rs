//! Unwrapping: cut a surface along hidden seams into disk-shaped charts
//! (Seamster) and flatten each with ABF++ (seed 004, section 3.4).
//!
//! `unwrap(mesh)` runs the whole stage: visibility over the whole mesh (so
//! pieces hide each other), then for every connected piece its seams, its
//! cut and its flattening, one chart per piece; the charts are scaled so uv
//! area equals 3D area (uv units are mesh units, ready for a tileable
//! texture with a world-space tile size) and placed side by side.

pub mod abf;
pub mod balance;
pub mod conformal;
pub mod cutgraph;
pub mod debug;
pub mod flatten;
pub mod intersect;
pub mod layout;
pub mod metrics;
pub mod overlap;
pub mod pack;
pub mod seamster;
pub mod steiner;
pub mod terminals;
pub mod untangle;
pub mod visibility;

use std::time::Instant;

use glam::DVec2;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::Result;
use crate::mesh::submesh::extract;
use crate::mesh::{Components, EdgeId, FaceId, Topology, TriMesh, UvLayer, VertexId};
use crate::progress::{CancelOnly, Progress};
use abf::AbfOptions;
use flatten::Method;
use metrics::UvMetrics;
use seamster::SeamOptions;
use visibility::{Viewpoints, Visibility};

#[derive(Clone, Debug)]
pub struct UnwrapOptions {
    pub viewpoints: Viewpoints,
    pub seams: SeamOptions,
    pub abf: AbfOptions,
    /// Split a chart whose layout overlaps itself into charts that do not
    /// (`overlap`): needed by atlases, not by tiled textures, and costs
    /// seams, so off by default.
    pub split_overlaps: bool,
    /// Only the mesh's first this many faces are drawn into an atlas (a
    /// facet piece's own faces: its ring is drawn, through the ring's uvs,
    /// into the earlier facet's atlas, where overlapping uvs do no harm),
    /// so only overlaps among them are split. `None`: every face.
    pub atlas_faces: Option<usize>,
}

impl Default for UnwrapOptions {
    fn default() -> Self {
        UnwrapOptions {
            viewpoints: Viewpoints::Orbit { views: 128 },
            seams: SeamOptions::default(),
            abf: AbfOptions::default(),
            split_overlaps: false,
            atlas_faces: None,
        }
    }
}

/// How one connected piece was unwrapped.
#[derive(Clone, Debug, Serialize)]
pub struct PieceReport {
    pub faces: usize,
    pub genus: i64,
    pub boundary_loops: usize,
    pub terminals: usize,
    /// Refinement rounds that made the kept cut.
    pub refinement_rounds: usize,
    /// The cuts flattened, in order, with their figures; at most
    /// `SeamOptions::max_tries`. The kept one is the last when it meets the
    /// bounds, else the one nearest them.
    pub tries: Vec<seamster::Try>,
    /// Whether the flattening met the stretch and conformality bounds
    /// without flips (`SeamOptions`); false when refinement ran out of
    /// rounds, tries or terminals far enough from the cut.
    pub within_bounds: bool,
    pub seam_edges: usize,
    /// Charts: 1, or more when a flattening overlapped itself and was split
    /// (`overlap`).
    pub charts: usize,
    /// How each chart was flattened.
    pub flattening: Vec<Method>,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    pub visibility_s: f64,
    pub seams_s: f64,
    pub flatten_s: f64,
    pub total_s: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct UnwrapReport {
    pub views: usize,
    pub pieces: Vec<PieceReport>,
    pub metrics: UvMetrics,
    pub timings: Timings,
}

/// A mesh with its new uv layer, and what was decided on the way.
pub struct Unwrapped {
    /// The input mesh with `uvs` set: one chart per connected piece.
    pub mesh: TriMesh,
    pub topology: Topology,
    /// Edges cut open (by the input's topology).
    pub seams: Vec<EdgeId>,
    pub terminals: Vec<VertexId>,
    pub visibility: Visibility,
    pub report: UnwrapReport,
}

/// One connected piece, unwrapped, in the piece's own numbering.
struct PieceResult {
    faces: Vec<FaceId>,
    /// Mesh vertex of every piece vertex.
    origin: Vec<u32>,
    /// Uv vertices of every piece face.
    cut_triangles: Vec<[u32; 3]>,
    uv: Vec<DVec2>,
    seams: Vec<[u32; 2]>,
    terminals: Vec<u32>,
    report: PieceReport,
    seams_s: f64,
    flatten_s: f64,
}

/// Cut `mesh` into disk charts and flatten them. The mesh must be manifold
/// (see `mesh::repair`).
pub fn unwrap(mesh: &TriMesh, opts: &UnwrapOptions, progress: &dyn Progress) -> Result<Unwrapped> {
    let start = Instant::now();
    let topology = Topology::build(mesh)?;
    let visibility = visibility::compute(mesh, &topology, &opts.viewpoints, progress);
    let visibility_s = start.elapsed().as_secs_f64();
    let mut out = unwrap_seen(mesh, topology, visibility, opts, progress)?;
    out.report.timings.visibility_s = visibility_s;
    out.report.timings.total_s += visibility_s;
    Ok(out)
}

/// `unwrap` with visibility already known (by `topology`'s vertices and
/// edges): a piece of a larger scene is seen, and hidden, with the rest of
/// the scene around it.
pub fn unwrap_seen(
    mesh: &TriMesh,
    topology: Topology,
    visibility: Visibility,
    opts: &UnwrapOptions,
    progress: &dyn Progress,
) -> Result<Unwrapped> {
    let start = Instant::now();

    let components = Components::find(&topology);
    let mut faces_of: Vec<Vec<FaceId>> = vec![Vec::new(); components.count];
    for (f, &c) in components.of_face.iter().enumerate() {
        faces_of[c as usize].push(FaceId::from(f));
    }
    // One piece reports its stages; many report one step per piece.
    let many = faces_of.len() > 1;
    let quiet = CancelOnly(progress);
    let piece_progress: &dyn Progress = if many { &quiet } else { progress };
    if many {
        progress.stage("charts", faces_of.len() as u64);
    }
    let pieces: Vec<PieceResult> = faces_of
        .into_par_iter()
        .map(|faces| {
            let piece = unwrap_piece(mesh, &topology, faces, &visibility, opts, piece_progress);
            if many {
                progress.advance(1);
            }
            piece
        })
        .collect::<Result<_>>()?;

    // One uv layer: every piece's cut vertices, charts side by side.
    let placements = pack::outlines(
        &pieces
            .iter()
            .map(|p| (&p.cut_triangles[..], &p.uv[..]))
            .collect::<Vec<_>>(),
    );
    let mut coords = Vec::new();
    let mut uv_triangles = vec![[0u32; 3]; mesh.num_faces()];
    let mut seams = Vec::new();
    let mut terminals = Vec::new();
    let mut timings = Timings::default();
    for (piece, placement) in pieces.iter().zip(placements) {
        let base = coords.len() as u32;
        coords.extend(placement.apply(&piece.uv));
        for (k, f) in piece.faces.iter().enumerate() {
            uv_triangles[f.idx()] = piece.cut_triangles[k].map(|v| v + base);
        }
        for [a, b] in &piece.seams {
            let (a, b) = (piece.origin[*a as usize], piece.origin[*b as usize]);
            seams.push(
                topology
                    .edge_between(VertexId(a), VertexId(b))
                    .expect("a piece's seams are edges of the mesh"),
            );
        }
        terminals.extend(
            piece
                .terminals
                .iter()
                .map(|&t| VertexId(piece.origin[t as usize])),
        );
        timings.seams_s += piece.seams_s;
        timings.flatten_s += piece.flatten_s;
    }
    seams.sort_unstable();
    let mut out = mesh.clone();
    out.uvs = Some(UvLayer {
        coords,
        triangles: uv_triangles,
    });
    let metrics =
        metrics::measure(&out, &topology, &visibility.edge).expect("the uv layer was just set");
    timings.total_s = start.elapsed().as_secs_f64();
    Ok(Unwrapped {
        report: UnwrapReport {
            views: visibility.views,
            pieces: pieces.into_iter().map(|p| p.report).collect(),
            metrics,
            timings,
        },
        mesh: out,
        topology,
        seams,
        terminals,
        visibility,
    })
}

fn unwrap_piece(
    mesh: &TriMesh,
    topology: &Topology,
    faces: Vec<FaceId>,
    visibility: &Visibility,
    opts: &UnwrapOptions,
    progress: &dyn Progress,
) -> Result<PieceResult> {
    let t0 = Instant::now();
    let (piece, origin) = extract(mesh, &faces);
    let topo = Topology::build(&piece)?;
    let seen = visibility.restrict(topology, &origin, &topo);
    let component = Components::find(&topo).topology(&topo)[0].clone();
    let split = opts.split_overlaps.then(|| {
        let drawn = opts.atlas_faces.unwrap_or(usize::MAX);
        faces.iter().map(|f| f.idx() < drawn).collect::<Vec<bool>>()
    });
    // Each try of a cut: its charts at mesh scale, and their figures.
    let mut flatten_s = 0.0;
    let flatten = |opened: &cutgraph::Opened| {
        let t = Instant::now();
        let cut_surface = &opened.surface;
        let charts = overlap::flatten_charts(opened, &opts.abf, split.as_deref())?;
        let normalised: Vec<(TriMesh, Vec<DVec2>)> = charts
            .iter()
            .map(|c| {
                let positions = c
                    .origin
                    .iter()
                    .map(|&v| cut_surface.positions[v as usize])
                    .collect();
                let chart = TriMesh::new(positions, c.triangles.clone());
                let uv = pack::normalise(&chart, c.uv.clone());
                (chart, uv)
            })
            .collect();
        // (3D area, Jacobian) of every chart face.
        let chart_faces: Vec<(f64, (f64, f64, f64))> = normalised
            .iter()
            .flat_map(|(chart, uv)| {
                (0..chart.num_faces()).map(|f| {
                    let corners = chart.triangles[f].map(|v| uv[v as usize]);
                    (
                        chart.face_area(f),
                        metrics::jacobian(chart.corners(f), corners),
                    )
                })
            })
            .collect();
        let distortion = seamster::Distortion {
            area_log: metrics::area_log(chart_faces.iter().map(|&(area, j)| (area, j.2))),
            conf_mean: metrics::conf_mean(chart_faces.iter().copied()),
            flipped: chart_faces
                .iter()
                .filter(|&&(area, j)| j.2 < 0.0 || (j.2 == 0.0 && area > 0.0))
                .count(),
        };
        flatten_s += t.elapsed().as_secs_f64();
        Ok(((charts, normalised), distortion))
    };
    let (seams, (charts, normalised)) = seamster::choose(
        &piece,
        &topo,
        &seen.vertex,
        &seen.edge,
        seen.views,
        &opts.seams,
        progress,
        flatten,
    )?;
    let seams_s = t0.elapsed().as_secs_f64() - flatten_s;

    let t1 = Instant::now();
    let placements = pack::outlines(
        &normalised
            .iter()
            .map(|(c, uv)| (&c.triangles[..], &uv[..]))
            .collect::<Vec<_>>(),
    );
    let mut uv = Vec::new();
    let mut cut_triangles = vec![[0u32; 3]; faces.len()];
    for ((chart, (_, chart_uv)), placement) in charts.iter().zip(&normalised).zip(placements) {
        let base = uv.len() as u32;
        uv.extend(placement.apply(chart_uv));
        for (k, &f) in chart.faces.iter().enumerate() {
            cut_triangles[f as usize] = chart.triangles[k].map(|v| v + base);
        }
    }
    let flatten_s = flatten_s + t1.elapsed().as_secs_f64();

    // The Seamster cut and any chart splits.
    let seam_edges = metrics::split_edges(&topo, |(f, i), (g, j)| {
        cut_triangles[f][i] != cut_triangles[g][j]
    });
    Ok(PieceResult {
        report: PieceReport {
            faces: faces.len(),
            genus: component.genus,
            boundary_loops: component.boundary_loops,
            terminals: seams.terminals.len(),
            refinement_rounds: seams.rounds,
            tries: seams.tries,
            within_bounds: seams.within_bounds,
            seam_edges: seam_edges.len(),
            charts: charts.len(),
            flattening: charts.into_iter().map(|c| c.method).collect(),
        },
        faces,
        seams: seam_edges
            .iter()
            .map(|&e| topo.edge_vertices(e).map(|v| v.0))
            .collect(),
        terminals: seams.terminals.iter().map(|t| t.0).collect(),
        cut_triangles,
        origin,
        uv,
        seams_s,
        flatten_s,
    })
}
