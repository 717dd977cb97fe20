//! A carving session: the simulator removes tets from a node's tet mesh,
//! step by step, and each step returns the faces that appeared, textured,
//! and the faces that vanished.
//!
//! As SOFA's `Tetra2TriangleTopologicalMapping` and iMSTK's
//! `PbdObjectCellRemoval` keep it, the carved surface is the faces of the
//! surviving tets that no surviving tet shares; its vertices are the tet
//! mesh's own. A face is named by its tet and the corner it lies opposite,
//! `4 t + k` (`tetra::mesh::TET_FACES[k]`, counter-clockwise seen from
//! outside the tet, so the surface is outward and consistently oriented).
//! A step touches only the removed tets and their neighbours: its cost
//! follows what it removes, not the mesh's size.
//!
//! A new face gets a chart in the session's cut-texture atlas
//! (`runtime::atlas`) and its texels from the node's interior in its own
//! tet (no point location), and per-vertex colours; a vanished face gives
//! its chart back. A large step can leave its texels to a background job
//! (`CarvingOptions::background_texels`) and return as soon as the faces,
//! their uvs and vertex colours are known; `wait` (or the next step)
//! writes them.
//!
//! Tools remove the tets whose centroid they hold, and then whatever tets
//! would leave an edge of the surface with more than two faces (a fan of
//! tets hanging on by an edge): the surface stays a closed 2-manifold at
//! its edges. Removal by id (SOFA's `TetrahedraRemoved`) removes exactly
//! what it is given.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::atlas::{AtlasOptions, Chart, CutAtlas, Rect};
use super::bake::Node;
use super::tool::Tool;
use crate::error::{Error, Result};
use crate::tetra::mesh::{NO_NEIGHBOUR, TET_FACES};

/// A face of the carved surface: face `k` of tet `t` is `4 t + k`.
pub type FaceId = u32;

/// How a session textures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CarvingOptions {
    pub atlas: AtlasOptions,
    /// Fill the atlas texels of each step in a background job; the step
    /// returns with the faces, uvs and vertex colours.
    pub background_texels: bool,
}

/// A face that appeared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewFace {
    pub id: FaceId,
    /// Tet mesh vertex ids, counter-clockwise seen from outside.
    pub vertices: [u32; 3],
    /// Its atlas page and the corners' texture coordinates there (0..1, v
    /// down).
    pub page: u32,
    pub uvs: [[f32; 2]; 3],
    /// The interior's colour at each corner, in the face's own tet.
    pub colours: [[u8; 3]; 3],
}

/// A face that vanished.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GoneFace {
    pub id: FaceId,
    pub vertices: [u32; 3],
}

/// What one step changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Step {
    /// The tets removed, by id, ascending.
    pub removed: Vec<u32>,
    pub appeared: Vec<NewFace>,
    pub vanished: Vec<GoneFace>,
    /// Each page's rectangle of texels written, to upload.
    pub dirty: Vec<(u32, Rect)>,
    /// Pages no face uses any more.
    pub released: Vec<u32>,
    /// The texels of `appeared` follow in a background job (`wait`).
    pub texels_pending: bool,
    /// Time the step took.
    pub seconds: f64,
}

/// A new face's texels to fill: its chart, corners, tet and the corners'
/// barycentric coordinates in the tet.
type FaceJob = (Chart, [DVec3; 3], usize, [[f64; 4]; 3]);

/// Texels being filled in the background, and the flag that stops them.
struct Pending {
    job: std::thread::JoinHandle<Vec<(Chart, Vec<u8>)>>,
    stop: Arc<AtomicBool>,
}

/// A carving session over one node's tet mesh.
pub struct Carving {
    node: Arc<Node>,
    alive: Vec<bool>,
    removed_count: usize,
    options: CarvingOptions,
    atlas: CutAtlas,
    /// The chart of each carved face on the surface.
    charts: HashMap<FaceId, u32>,
    pending: Option<Pending>,
}

impl Carving {
    /// A session over `node`'s tet mesh, every tet present. Errors when
    /// the node has no tet mesh or the options are out of range.
    pub fn new(node: Arc<Node>, options: CarvingOptions) -> Result<Carving> {
        let mesh = node.require_tets()?;
        node.adjacency()?;
        node.centroids()?;
        let atlas = CutAtlas::new(options.atlas)?;
        atlas.check_fits(node.longest_edge()?)?;
        Ok(Carving {
            alive: vec![true; mesh.num_tets()],
            node,
            removed_count: 0,
            options,
            atlas,
            charts: HashMap::new(),
            pending: None,
        })
    }

    pub fn node(&self) -> &Arc<Node> {
        &self.node
    }

    pub fn options(&self) -> CarvingOptions {
        self.options
    }

    /// Whether tet `t` is still there.
    pub fn alive(&self, t: u32) -> bool {
        self.alive.get(t as usize).copied().unwrap_or(false)
    }

    /// Tets removed so far.
    pub fn removed(&self) -> usize {
        self.removed_count
    }

    pub fn atlas(&self) -> &CutAtlas {
        &self.atlas
    }

    /// Remove the tets `ids` (SOFA's `TetrahedraRemoved`): exactly these.
    /// Refuses, changing nothing, an id past the mesh, one already
    /// removed, and one given twice.
    pub fn remove(&mut self, ids: &[u32]) -> Result<Step> {
        let start = Instant::now();
        let n = self.alive.len();
        let mut sorted = ids.to_vec();
        sorted.sort_unstable();
        for (i, &t) in sorted.iter().enumerate() {
            if t as usize >= n {
                return Err(Error::invalid(format!(
                    "tet {t} is out of range: the mesh has {n} tets"
                )));
            }
            if !self.alive[t as usize] {
                return Err(Error::invalid(format!("tet {t} was already removed")));
            }
            if i > 0 && sorted[i - 1] == t {
                return Err(Error::invalid(format!("tet {t} is given twice")));
            }
        }
        self.apply(sorted, start)
    }

    /// Remove the tets under `tool`, and those that would leave an edge
    /// with more than two faces. Refuses a tool that is not finite or has
    /// no positive radius.
    pub fn carve(&mut self, tool: &Tool) -> Result<Step> {
        let start = Instant::now();
        tool.check()?;
        let mut removed: Vec<u32> = self
            .node
            .centroids()?
            .under(tool)
            .into_iter()
            .filter(|&t| self.alive[t as usize])
            .collect();
        for &t in &removed {
            self.alive[t as usize] = false;
        }
        let extra = self.keep_edges_manifold(&removed)?;
        // `apply` marks them again.
        for &t in removed.iter().chain(&extra) {
            self.alive[t as usize] = true;
        }
        removed.extend(extra);
        removed.sort_unstable();
        self.apply(removed, start)
    }

    /// With `removed` already marked dead: every further tet whose removal
    /// leaves each edge of the removed tets with at most one fan of live
    /// tets round it, marked dead too; returned.
    fn keep_edges_manifold(&mut self, removed: &[u32]) -> Result<Vec<u32>> {
        let mesh = self.node.require_tets()?;
        let adjacency = self.node.adjacency()?;
        let mut extra = Vec::new();
        let mut work: Vec<[u32; 2]> = Vec::new();
        let push_edges = |t: u32, work: &mut Vec<[u32; 2]>| {
            let tet = mesh.tets[t as usize];
            for [i, j] in crate::tetra::mesh::TET_EDGES {
                let (a, b) = (tet[i].min(tet[j]), tet[i].max(tet[j]));
                work.push([a, b]);
            }
        };
        let mut owner: HashMap<[u32; 2], u32> = HashMap::new();
        for &t in removed {
            let before = work.len();
            push_edges(t, &mut work);
            for e in &work[before..] {
                owner.entry(*e).or_insert(t);
            }
        }
        work.sort_unstable();
        work.dedup();
        while let Some(edge) = work.pop() {
            let Some(&seed) = owner.get(&edge) else {
                continue;
            };
            let ring = edge_ring(&mesh.tets, adjacency, seed, edge);
            let fans = live_fans(&ring, &self.alive);
            if fans.len() < 2 {
                continue;
            }
            // Keep the largest fan (ties: the one with the lowest tet id).
            let keep = (0..fans.len())
                .max_by(|&i, &j| {
                    fans[i]
                        .len()
                        .cmp(&fans[j].len())
                        .then(fans[j].iter().min().cmp(&fans[i].iter().min()))
                })
                .expect("two fans at least");
            for (k, fan) in fans.iter().enumerate() {
                if k == keep {
                    continue;
                }
                for &t in fan {
                    self.alive[t as usize] = false;
                    extra.push(t);
                    let before = work.len();
                    push_edges(t, &mut work);
                    for e in &work[before..] {
                        owner.entry(*e).or_insert(t);
                    }
                }
            }
        }
        Ok(extra)
    }

    /// Remove `removed` (sorted, distinct, alive): the step's faces,
    /// charts, colours and texels.
    fn apply(&mut self, removed: Vec<u32>, start: Instant) -> Result<Step> {
        let dirty_before = self.wait_texels();
        let node = self.node.clone();
        let mesh = node.require_tets()?;
        let adjacency = node.adjacency()?;
        for &t in &removed {
            self.alive[t as usize] = false;
        }
        self.removed_count += removed.len();
        let mut appeared: Vec<(u32, usize)> = Vec::new();
        let mut vanished = Vec::new();
        for &t in &removed {
            let tet = mesh.tets[t as usize];
            for (k, &n) in adjacency[t as usize].iter().enumerate() {
                if n == NO_NEIGHBOUR
                    || (!self.alive[n as usize] && removed.binary_search(&n).is_err())
                {
                    // On the surface before this step.
                    vanished.push(GoneFace {
                        id: 4 * t + k as u32,
                        vertices: TET_FACES[k].map(|c| tet[c]),
                    });
                } else if self.alive[n as usize] {
                    let back = adjacency[n as usize]
                        .iter()
                        .position(|&m| m == t)
                        .expect("adjacency is symmetric");
                    appeared.push((n, back));
                }
            }
        }
        for gone in &vanished {
            if let Some(chart) = self.charts.remove(&gone.id) {
                self.atlas.remove(chart)?;
            }
        }
        // Charts, in face order so the same steps give the same atlas.
        appeared.sort_unstable();
        let mut faces = Vec::with_capacity(appeared.len());
        let mut jobs = Vec::with_capacity(appeared.len());
        for &(t, k) in &appeared {
            let tet = mesh.tets[t as usize];
            let corners_k = TET_FACES[k];
            let vertices = corners_k.map(|c| tet[c]);
            let points = vertices.map(|v| mesh.positions[v as usize]);
            let (chart_id, chart) = self.atlas.add(self.atlas.flatten(points))?;
            let id = 4 * t + k as u32;
            self.charts.insert(id, chart_id);
            let bary = corners_k.map(|c| {
                let mut b = [0.0; 4];
                b[c] = 1.0;
                b
            });
            faces.push(NewFace {
                id,
                vertices,
                page: chart.page,
                uvs: chart.uvs(self.options.atlas.page_size),
                colours: [[0; 3]; 3],
            });
            jobs.push((chart, points, t as usize, bary));
        }
        // Corner colours in each face's own tet: a lapped texture's regions
        // meet sharply (a myoma's capsule), so a vertex on their border has
        // a colour on each side.
        let model = node.model();
        let colours: Vec<[[u8; 3]; 3]> = jobs
            .par_iter()
            .map(|(_, points, t, bary)| [0, 1, 2].map(|c| model.colour_in(*t, bary[c], points[c])))
            .collect();
        for (f, c) in faces.iter_mut().zip(colours) {
            f.colours = c;
        }
        let background = self.options.background_texels && !jobs.is_empty();
        if background {
            let node = node.clone();
            let stop = Arc::new(AtomicBool::new(false));
            let flag = stop.clone();
            let job = std::thread::spawn(move || fill(&node, &jobs, &flag));
            self.pending = Some(Pending { job, stop });
        } else {
            for (chart, rgba) in fill(&node, &jobs, &AtomicBool::new(false)) {
                self.atlas.write(&chart, &rgba);
            }
        }
        let mut dirty = dirty_before;
        merge_dirty(&mut dirty, self.atlas.take_dirty());
        Ok(Step {
            removed,
            appeared: faces,
            vanished,
            dirty,
            released: self.atlas.take_released(),
            texels_pending: background,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Finish the background texels, if any: write them, and return each
    /// page's rectangle written since the last step.
    pub fn wait(&mut self) -> Vec<(u32, Rect)> {
        let mut dirty = self.wait_texels();
        merge_dirty(&mut dirty, self.atlas.take_dirty());
        dirty
    }

    /// Whether a background job is still filling texels.
    pub fn texels_pending(&self) -> bool {
        self.pending.as_ref().is_some_and(|p| !p.job.is_finished())
    }

    fn wait_texels(&mut self) -> Vec<(u32, Rect)> {
        if let Some(p) = self.pending.take() {
            // A panic in the job is a bug; its faces keep clear texels
            // rather than taking the session down.
            let filled = p.job.join().unwrap_or_default();
            for (chart, rgba) in filled {
                self.atlas.write(&chart, &rgba);
            }
            return self.atlas.take_dirty();
        }
        Vec::new()
    }

    /// The carved surface now: every face of a live tet that no live tet
    /// shares, with its chart when it was carved (original faces of the
    /// mesh's boundary have none). In face id order.
    pub fn surface(&self) -> Vec<(FaceId, [u32; 3], Option<&Chart>)> {
        let Ok(mesh) = self.node.require_tets() else {
            return Vec::new();
        };
        let Ok(adjacency) = self.node.adjacency() else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (t, tet) in mesh.tets.iter().enumerate() {
            if !self.alive[t] {
                continue;
            }
            for k in 0..4 {
                let n = adjacency[t][k];
                if n == NO_NEIGHBOUR || !self.alive[n as usize] {
                    let id = 4 * t as u32 + k as u32;
                    let chart = self.charts.get(&id).and_then(|&c| self.atlas.chart(c));
                    out.push((id, TET_FACES[k].map(|c| tet[c]), chart));
                }
            }
        }
        out
    }

    /// The chart of carved face `id`, while it is on the surface.
    pub fn surface_chart(&self, id: FaceId) -> Option<&Chart> {
        self.charts.get(&id).and_then(|&c| self.atlas.chart(c))
    }

    /// Bytes the session holds beside its node (whose tet index sessions
    /// share).
    pub fn bytes(&self) -> usize {
        self.alive.len() + self.atlas.bytes() + 12 * self.charts.capacity()
    }
}

impl Drop for Carving {
    /// A background job's texels are for this session alone: stop it.
    fn drop(&mut self) {
        if let Some(p) = self.pending.take() {
            p.stop.store(true, Ordering::Relaxed);
            let _ = p.job.join();
        }
    }
}

/// The texels of each job's chart; none once `stop` is set.
fn fill(node: &Node, jobs: &[FaceJob], stop: &AtomicBool) -> Vec<(Chart, Vec<u8>)> {
    jobs.par_iter()
        .map(|(chart, points, t, bary)| {
            let texels = if stop.load(Ordering::Relaxed) {
                Vec::new()
            } else {
                node.model().face_texels(chart, *points, Some((*t, *bary)))
            };
            (*chart, texels)
        })
        .collect()
}

fn merge_dirty(into: &mut Vec<(u32, Rect)>, more: Vec<(u32, Rect)>) {
    for (page, r) in more {
        match into.iter_mut().find(|(p, _)| *p == page) {
            Some((_, d)) => {
                let x = d.x.min(r.x);
                let y = d.y.min(r.y);
                let right = (d.x + d.width).max(r.x + r.width);
                let bottom = (d.y + d.height).max(r.y + r.height);
                *d = Rect {
                    x,
                    y,
                    width: right - x,
                    height: bottom - y,
                };
            }
            None => into.push((page, r)),
        }
    }
}

/// The tets round `edge` in order, starting at `seed` (which holds it):
/// walking across the faces that hold the edge one way until the ring
/// closes or meets the mesh's boundary, then the other way. `closed` when
/// it came round.
fn edge_ring(tets: &[[u32; 4]], adjacency: &[[u32; 4]], seed: u32, edge: [u32; 2]) -> Ring {
    // The two faces of tet t holding the edge are those opposite its two
    // other corners; crossing one leads to the next tet round the edge.
    let others = |t: u32| -> [usize; 2] {
        let tet = tets[t as usize];
        let mut o = [0usize; 2];
        let mut n = 0;
        for (c, &v) in tet.iter().enumerate() {
            if v != edge[0] && v != edge[1] && n < 2 {
                o[n] = c;
                n += 1;
            }
        }
        o
    };
    let walk = |first_exit: usize| -> (Vec<u32>, bool) {
        let mut out = Vec::new();
        let (mut from, mut t) = (seed, adjacency[seed as usize][first_exit]);
        while t != NO_NEIGHBOUR {
            if t == seed {
                return (out, true);
            }
            out.push(t);
            // Leave t by its other face round the edge.
            let exit = others(t)
                .into_iter()
                .find(|&c| adjacency[t as usize][c] != from)
                .expect("a tet has two faces round an edge");
            (from, t) = (t, adjacency[t as usize][exit]);
            if out.len() > tets.len() {
                break;
            }
        }
        (out, false)
    };
    let [a, b] = others(seed);
    let (forward, closed) = walk(a);
    if closed {
        let mut tets = vec![seed];
        tets.extend(forward);
        return Ring { tets, closed: true };
    }
    let (backward, _) = walk(b);
    let mut ring: Vec<u32> = backward.into_iter().rev().collect();
    ring.push(seed);
    ring.extend(forward);
    Ring {
        tets: ring,
        closed: false,
    }
}

struct Ring {
    tets: Vec<u32>,
    closed: bool,
}

/// The runs of live tets round a ring (a closed ring's run may wrap).
fn live_fans(ring: &Ring, alive: &[bool]) -> Vec<Vec<u32>> {
    let live = |t: u32| alive[t as usize];
    let n = ring.tets.len();
    if ring.tets.iter().all(|&t| live(t)) {
        return vec![ring.tets.clone()];
    }
    // Start after a dead tet, so a closed ring's wrapping run stays whole.
    let start = if ring.closed {
        (0..n).find(|&i| !live(ring.tets[i])).map_or(0, |i| i + 1)
    } else {
        0
    };
    let mut fans = Vec::new();
    let mut run = Vec::new();
    for i in 0..n {
        let t = ring.tets[(start + i) % n];
        if live(t) {
            run.push(t);
        } else if !run.is_empty() {
            fans.push(std::mem::take(&mut run));
        }
    }
    if !run.is_empty() {
        fans.push(run);
    }
    fans
}
