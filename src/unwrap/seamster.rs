//! Seamster (Sheffer and Hart 2002; seed 004, section 3.4.1): choose the
//! seams that cut one connected surface into a disk, hidden where nobody
//! looks and passing where the curvature is.
//!
//! 1. Terminals (`terminals`): cone regions, whose angle defect summed over
//!    a small disc is large (they stretch area when left uncut), and sharp
//!    vertices, whose own defect is large (ABF++ must bend every angle
//!    around them when left uncut).
//! 2. Handle loops if the surface has genus (`cutgraph::handle_loops`).
//! 3. A Steiner tree joining terminals, boundary loops and handle loops
//!    (`steiner`), edge cost |e| * visibility * (1 - curvature), curvature
//!    being |dihedral angle| / pi.
//! 4. Refinement, as Seamster grows its cut: estimate the flattening's area
//!    stretch (`conformal`), take the points conformally farthest from the
//!    cut (largest |log scale|) as new terminals, and join each to the cut by
//!    its cheapest path, the cost discounted where the scale is off so the
//!    new branch runs through the region it relieves; until the flattening
//!    itself (ABF++ and area balancing, tried once the estimate meets the
//!    stretch target) meets the stretch and conformality bounds without
//!    flips, or the rounds or tries run out (the report says so, and the
//!    try nearest the bounds is kept).
//!
//! Scales are relative to the surface (sqrt of its area, its mean edge), so
//! the same settings serve a bunny, a bone and a uterus.

use std::f64::consts::PI;

use super::conformal::{self, OpenedLogScale};
use super::cutgraph::{Cut, Opened, connect_pieces, cut, handle_loops};
use super::steiner::{self, prune_leaves};
use super::terminals::{disc_curvature, select};
use crate::error::Result;
use crate::linalg::VertexOrder;
use crate::mesh::curvature::{angle_defects, corner_angles, dihedral_angles};
use crate::mesh::graph::{EdgeGraph, ShortestPaths};
use crate::mesh::{Components, EdgeId, Topology, TriMesh, VertexId};
use crate::progress::{Progress, check};

#[derive(Clone, Debug)]
pub struct SeamOptions {
    /// Refine until the flattening's mean |log area ratio| (the area_log
    /// figure) is at most this. The conformal estimate of each cut says
    /// when to flatten and try.
    pub max_stretch: f64,
    /// Refine until the flattening's mean sigma1 / sigma2 (the conf_mean
    /// figure) is at most this too.
    pub max_conformal: f64,
    /// At most this many cuts flattened (0 is taken as 1). Flattening is
    /// most of the work, and a bound a surface cannot meet (a scan's
    /// slivers can hold conformality up whatever the cut) would flatten
    /// every round left: the bunny asked for conf_mean 1.0 flattened 15
    /// cuts, 17.6 s of a 20.9 s unwrap.
    pub max_tries: usize,
    /// At most this many refinement rounds.
    pub max_rounds: usize,
    /// New terminals per refinement round.
    pub terminals_per_round: usize,
    /// A cone terminal: angle defect summed over its disc at least this
    /// (radians).
    pub cone_threshold: f64,
    /// A sharp terminal: its own angle defect at least this (radians).
    pub sharp_threshold: f64,
}

impl Default for SeamOptions {
    fn default() -> Self {
        SeamOptions {
            // The bounds the unwrap issue sets for any mesh. Seams are
            // the cost, so refinement stops as soon as both are met.
            max_stretch: 0.35,
            max_conformal: 1.08,
            max_tries: 4,
            max_rounds: 16,
            terminals_per_round: 2,
            cone_threshold: 1.5,
            sharp_threshold: 0.7,
        }
    }
}

/// A flattening's figures (`metrics`), which refinement holds to the
/// options' bounds.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Distortion {
    pub area_log: f64,
    pub conf_mean: f64,
    /// Faces whose uv triangle is reversed, or has no area where the
    /// surface's has: a flattening that left any (a fallback's) misses
    /// the bounds whatever its means.
    pub flipped: usize,
}

impl Distortion {
    fn meets(&self, opts: &SeamOptions) -> bool {
        self.flipped == 0
            && self.area_log <= opts.max_stretch
            && self.conf_mean <= opts.max_conformal
    }

    /// How far outside the bounds, for keeping the best of the tries when
    /// none meets them: flips first, then the larger of the two figures'
    /// excess, each as a fraction of its bound's room (1 = on the bound).
    fn overshoot(&self, opts: &SeamOptions) -> (bool, f64) {
        let room = |bound: f64| bound.max(1e-9);
        (
            self.flipped > 0,
            (self.area_log / room(opts.max_stretch))
                .max((self.conf_mean - 1.0) / room(opts.max_conformal - 1.0)),
        )
    }
}

/// One cut flattened: the refinement round it came from and its figures
/// (`None`: the flattening failed).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Try {
    pub round: usize,
    pub figures: Option<Distortion>,
}

/// The seams chosen for one connected surface.
#[derive(Clone, Debug)]
pub struct Seams {
    /// Interior edges to cut.
    pub edges: Vec<EdgeId>,
    pub terminals: Vec<VertexId>,
    /// Refinement rounds that made the kept cut.
    pub rounds: usize,
    /// The cuts flattened, in order. The last is kept when it meets the
    /// bounds; when none does, the one nearest them (the earliest, with
    /// the fewest seams, among equals), whose round `rounds` is.
    pub tries: Vec<Try>,
    /// Whether the kept flattening's figures meet the options' bounds
    /// (they may not when the rounds or tries ran out, or no new terminal
    /// was far enough from the cut).
    pub within_bounds: bool,
    pub cut: Cut,
}

/// What every step of the search shares about the surface.
struct Surface<'a> {
    mesh: &'a TriMesh,
    topo: &'a Topology,
    graph: EdgeGraph,
    length: Vec<f64>,
    /// Steiner edge cost: length x visibility x (1 - curvature).
    cost: Vec<f64>,
    /// Angle defects of interior vertices (0 on the boundary, which the
    /// estimate holds fixed): what the curvature discs sum and the
    /// estimate's source.
    defect: Vec<f64>,
    /// Every round's estimate: the surface's log scale opened through
    /// the cut.
    log_scale: OpenedLogScale,
}

impl Surface<'_> {
    fn interior(&self, v: VertexId) -> bool {
        self.topo.is_referenced(v) && !self.topo.is_boundary_vertex(v)
    }

    fn boundary_vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        self.topo
            .boundary_loops()
            .iter()
            .flatten()
            .map(|&h| self.topo.origin(h))
    }
}

/// Choose seams for a connected, manifold surface, and flatten it along
/// them: `flatten` lays a cut out and gives its figures, which must meet
/// the options' bounds (the estimate only says when to try). When no cut
/// tried meets them, the one nearest them is returned (`Seams::tries`).
/// `edge_visibility` is by `topo`'s edges; `views` is how many views it
/// was counted over.
#[allow(clippy::too_many_arguments)]
pub fn choose<T>(
    mesh: &TriMesh,
    topo: &Topology,
    vertex_visibility: &[f32],
    edge_visibility: &[f32],
    views: usize,
    opts: &SeamOptions,
    progress: &dyn Progress,
    mut flatten: impl FnMut(&Opened) -> Result<(T, Distortion)>,
) -> Result<(Seams, T)> {
    let graph = EdgeGraph::new(topo);
    // The vertex order (AMD, serial) is made on one core while the other
    // measures the surface.
    let (order, (angles, angle_defect, dihedral)) = rayon::join(
        || {
            VertexOrder::amd(
                mesh.num_vertices(),
                (0..graph.num_edges()).map(|e| {
                    let [a, b] = graph.ends(EdgeId::from(e));
                    (a.0, b.0)
                }),
            )
        },
        || {
            let angles = corner_angles(mesh);
            let defect = angle_defects(mesh, topo, &angles);
            (angles, defect, dihedral_angles(mesh, topo))
        },
    );
    let order = order?;
    let defect: Vec<f64> = (0..mesh.num_vertices())
        .map(|v| {
            let v = VertexId::from(v);
            if topo.is_referenced(v) && !topo.is_boundary_vertex(v) {
                angle_defect[v.idx()]
            } else {
                0.0
            }
        })
        .collect();
    let length = graph.lengths(&mesh.positions);
    // Never-seen edges still cost their length, a little.
    let hidden = 1.0 / views.max(1) as f64;
    let cost = (0..graph.num_edges())
        .map(|e| length[e] * (edge_visibility[e] as f64 + hidden) * (1.0 - dihedral[e].abs() / PI))
        .collect();
    let mean_edge = length.iter().sum::<f64>() / length.len().max(1) as f64;
    let radius = (0.05 * mesh.area().sqrt()).max(mean_edge);
    let spacing = 2.0 * radius;
    // The estimate's symbolic factorisation (serial) is made while the
    // discs are summed.
    let (cone, log_scale) = rayon::join(
        || {
            disc_curvature(
                &graph,
                &mesh.positions,
                &defect,
                radius,
                opts.cone_threshold,
            )
        },
        || OpenedLogScale::new(mesh, &angles, &defect, &order),
    );
    let s = Surface {
        mesh,
        topo,
        graph,
        length,
        cost,
        defect,
        log_scale: log_scale?,
    };
    let interior = |v: VertexId| s.interior(v);
    let mut terminals = select(
        &s.graph,
        &mesh.positions,
        &cone,
        spacing,
        opts.cone_threshold,
        &[],
        interior,
    );
    // A corner keeps its defect when its ring's are added (they are
    // flat); a spike of scan noise does not (its ring bends the other
    // way), so a sharp terminal needs both large.
    let sharpness: Vec<f64> = (0..mesh.num_vertices())
        .map(|v| {
            let ring: f64 = s
                .graph
                .neighbours(VertexId::from(v))
                .iter()
                .map(|(u, _)| s.defect[u.idx()])
                .sum();
            s.defect[v].abs().min((s.defect[v] + ring).abs())
        })
        .collect();
    let sharp = select(
        &s.graph,
        &mesh.positions,
        &sharpness,
        0.0,
        opts.sharp_threshold,
        &terminals,
        interior,
    );
    terminals.extend(sharp);

    let genus = Components::find(topo)
        .topology(topo)
        .first()
        .map_or(0, |c| c.genus);
    let loops = if genus > 0 {
        // Root the loops where the surface is least visible.
        let root = (0..mesh.num_vertices())
            .map(VertexId::from)
            .filter(|&v| topo.is_referenced(v))
            .min_by(|a, b| {
                vertex_visibility[a.idx()]
                    .total_cmp(&vertex_visibility[b.idx()])
                    .then(a.cmp(b))
            })
            .expect("a surface has vertices");
        handle_loops(topo, &s.graph, &s.cost, root)
    } else {
        Vec::new()
    };
    if genus == 0 && topo.boundary_loops().is_empty() && terminals.len() < 2 {
        terminals = two_far_terminals(&s, &cone, terminals.first().copied());
    }

    progress.stage("seams and flattening", opts.max_rounds as u64 + 1);
    let mut edges = steiner_seams(&s, &terminals, &loops);
    let mut rounds = 0;
    let mut tried = Tries::default();
    let max_tries = opts.max_tries.max(1);
    loop {
        check(progress)?;
        // The estimate's solve is serial: the cut is made, checked and
        // ordered for flattening on the other core meanwhile (whether or
        // not the estimate then asks for the flattening).
        let (estimated, opened) = rayon::join(
            || estimate_stretch(&s, &edges),
            || Opened::new(cut(mesh, &edges), &mesh.positions),
        );
        let opened = opened?;
        let (log_scale, estimate) = estimated?;
        progress.advance(1);
        let last = rounds >= opts.max_rounds;
        // The estimate says when a cut may do; the flattening decides. A
        // try that fails outright counts as missing the bounds while
        // tries are left: a later cut may flatten.
        let mut met = false;
        if estimate <= opts.max_stretch || last {
            let flat = flatten(&opened);
            let out_of_tries = tried.list.len() + 1 >= max_tries;
            match tried.record(flat, opts, rounds, &edges, &terminals, &opened.cut) {
                Ok(m) => met = m,
                Err(e) if (last || out_of_tries) && tried.kept.is_none() => return Err(e),
                Err(_) => {}
            }
        }
        let done = met || last || tried.list.len() >= max_tries;
        let added = if done {
            Vec::new()
        } else {
            farthest_from_cut(
                &s,
                &edges,
                &terminals,
                &log_scale,
                spacing,
                opts.terminals_per_round,
            )
        };
        if added.is_empty() {
            if tried.kept.is_none() {
                // No terminal far enough to add before any cut flattened.
                let flat = flatten(&opened);
                tried.record(flat, opts, rounds, &edges, &terminals, &opened.cut)?;
            }
            let (mut seams, flattened, _) = tried.kept.expect("a flattening was kept");
            seams.tries = tried.list;
            return Ok((seams, flattened));
        }
        edges = grow(&s, edges, &terminals, &added, &log_scale);
        terminals.extend(added);
        rounds += 1;
    }
}

/// The cuts flattened so far, and the one kept: the one nearest the bounds
/// (the earliest, with the fewest seams, among equals).
struct Tries<T> {
    list: Vec<Try>,
    kept: Option<(Seams, T, Distortion)>,
}

impl<T> Default for Tries<T> {
    fn default() -> Self {
        Tries {
            list: Vec::new(),
            kept: None,
        }
    }
}

impl<T> Tries<T> {
    /// Record a flattening of `cut`; whether it meets the bounds.
    fn record(
        &mut self,
        flat: Result<(T, Distortion)>,
        opts: &SeamOptions,
        round: usize,
        edges: &[EdgeId],
        terminals: &[VertexId],
        cut: &Cut,
    ) -> Result<bool> {
        let (flattened, figures) = match flat {
            Ok(f) => f,
            Err(e) => {
                self.list.push(Try {
                    round,
                    figures: None,
                });
                return Err(e);
            }
        };
        self.list.push(Try {
            round,
            figures: Some(figures),
        });
        let met = figures.meets(opts);
        let nearer = self
            .kept
            .as_ref()
            .is_none_or(|(_, _, kept)| figures.overshoot(opts) < kept.overshoot(opts));
        if nearer {
            let seams = Seams {
                edges: edges.to_vec(),
                terminals: terminals.to_vec(),
                rounds: round,
                tries: Vec::new(),
                within_bounds: met,
                cut: cut.clone(),
            };
            self.kept = Some((seams, flattened, figures));
        }
        Ok(met)
    }
}

/// A closed sphere needs at least one seam edge, so two terminals: the
/// strongest cone (or `first`), and the vertex farthest from it.
fn two_far_terminals(s: &Surface, cone: &[f64], first: Option<VertexId>) -> Vec<VertexId> {
    let interior: Vec<VertexId> = (0..s.mesh.num_vertices())
        .map(VertexId::from)
        .filter(|&v| s.interior(v))
        .collect();
    let first = first.unwrap_or_else(|| {
        *interior
            .iter()
            .max_by(|a, b| cone[a.idx()].total_cmp(&cone[b.idx()]).then(b.cmp(a)))
            .expect("a closed surface has interior vertices")
    });
    let distance = ShortestPaths::from_sources(&s.graph, &s.length, &[(first, 0)]).distance;
    let far = *interior
        .iter()
        .filter(|v| distance[v.idx()].is_finite())
        .max_by(|a, b| {
            distance[a.idx()]
                .total_cmp(&distance[b.idx()])
                .then(b.cmp(a))
        })
        .expect("a closed surface has interior vertices");
    vec![first, far]
}

/// Interior edges of the Steiner tree joining the terminals, the boundary
/// loops and the handle loops, plus the handle loops themselves.
fn steiner_seams(s: &Surface, terminals: &[VertexId], loops: &[EdgeId]) -> Vec<EdgeId> {
    let mut groups: Vec<Vec<VertexId>> = terminals.iter().map(|&t| vec![t]).collect();
    for cycle in s.topo.boundary_loops() {
        groups.push(cycle.iter().map(|&h| s.topo.origin(h)).collect());
    }
    if !loops.is_empty() {
        let mut on_loops: Vec<VertexId> = loops.iter().flat_map(|&e| s.graph.ends(e)).collect();
        on_loops.sort_unstable();
        on_loops.dedup();
        groups.push(on_loops);
    }
    let mut edges = steiner::tree(&s.graph, &s.cost, &groups);
    edges.extend_from_slice(loops);
    finish(s, edges, terminals)
}

/// The interior edges of `edges`, with any patch they enclose together
/// with boundary and handle loops opened back onto the rest
/// (`connect_pieces`), and the branches that then lead nowhere (to no
/// terminal or boundary) dropped.
fn finish(s: &Surface, mut edges: Vec<EdgeId>, terminals: &[VertexId]) -> Vec<EdgeId> {
    edges.retain(|&e| !s.topo.is_boundary_edge(e));
    edges.sort_unstable();
    edges.dedup();
    let mut edges = connect_pieces(s.topo, edges, &s.cost);
    let mut kept = vec![false; s.mesh.num_vertices()];
    for v in terminals.iter().copied().chain(s.boundary_vertices()) {
        kept[v.idx()] = true;
    }
    prune_leaves(&s.graph, &mut edges, |v| kept[v.idx()]);
    edges
}

/// Vertices already on the cut: seam ends, terminals, boundary vertices.
fn on_cut(s: &Surface, edges: &[EdgeId], terminals: &[VertexId]) -> Vec<(VertexId, u32)> {
    edges
        .iter()
        .flat_map(|&e| s.graph.ends(e))
        .chain(terminals.iter().copied())
        .chain(s.boundary_vertices())
        .map(|v| (v, 0))
        .collect()
}

/// Up to `count` vertices where the log scale is largest in magnitude, each
/// at least `spacing` from the cut and from each other.
fn farthest_from_cut(
    s: &Surface,
    edges: &[EdgeId],
    terminals: &[VertexId],
    log_scale: &[f64],
    spacing: f64,
    count: usize,
) -> Vec<VertexId> {
    let distance =
        ShortestPaths::from_sources(&s.graph, &s.length, &on_cut(s, edges, terminals)).distance;
    let badness: Vec<f64> = log_scale
        .iter()
        .zip(&distance)
        .map(|(u, d)| if *d >= spacing { u.abs() } else { 0.0 })
        .collect();
    let mut picked = select(
        &s.graph,
        &s.mesh.positions,
        &badness,
        spacing,
        f64::MIN_POSITIVE,
        &[],
        |v| s.interior(v),
    );
    picked.truncate(count);
    picked
}

/// The cut grown by a path from each new terminal to it (the cut so far,
/// branches added before included). Path costs are the Steiner costs times
/// e^-|log scale|: a branch prefers the distorted region it is to relieve.
fn grow(
    s: &Surface,
    mut edges: Vec<EdgeId>,
    terminals: &[VertexId],
    added: &[VertexId],
    log_scale: &[f64],
) -> Vec<EdgeId> {
    let discounted: Vec<f64> = (0..s.graph.num_edges())
        .map(|e| {
            let [a, b] = s.graph.ends(EdgeId::from(e));
            s.cost[e] * (-(log_scale[a.idx()].abs() + log_scale[b.idx()].abs()) / 2.0).exp()
        })
        .collect();
    for &t in added {
        let paths =
            ShortestPaths::from_sources(&s.graph, &discounted, &on_cut(s, &edges, terminals));
        edges.extend(paths.path_to_source(&s.graph, t));
    }
    let all: Vec<VertexId> = terminals.iter().chain(added).copied().collect();
    finish(s, edges, &all)
}

/// The log scale factor of the least-distortion conformal flattening of
/// the surface cut along `edges` (`conformal`), per vertex (0 on the cut
/// and the boundary), and the area_log figure it implies.
fn estimate_stretch(s: &Surface, edges: &[EdgeId]) -> Result<(Vec<f64>, f64)> {
    let mut opened: Vec<bool> = (0..s.mesh.num_vertices())
        .map(|v| s.topo.is_boundary_vertex(VertexId::from(v)))
        .collect();
    for v in edges.iter().flat_map(|&e| s.graph.ends(e)) {
        opened[v.idx()] = true;
    }
    let u = s.log_scale.solve(&opened)?;
    let mut area_log = 0.0;
    let mut area = 0.0;
    for (f, l) in conformal::face_log_area_ratios(s.mesh, &u)
        .iter()
        .enumerate()
    {
        let a = s.mesh.face_area(f);
        area_log += a * l.abs();
        area += a;
    }
    Ok((u, area_log / area.max(1e-300)))
}
