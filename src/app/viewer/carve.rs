//! The Carve tool: drag over the organ and a sphere of set radius removes
//! the tets under it, as a simulator's burr does, through the same runtime
//! a simulator calls (`runtime::Carving`). The faces each step exposes are
//! drawn at once, textured from the node's interior through the step's
//! atlas pages; the organ's surface is not drawn in the carved space (a
//! mask of the removed tets, a voxel wider). The step's time and the
//! frame's are shown.
//!
//! The node carved is the scene's first with an interior: its lapped solid
//! texture over its own tets when the scene laps one, else its block over
//! the node's tets (made when carving starts).

use std::collections::HashMap;
use std::sync::Arc;

use eframe::egui;
use glam::DVec3;

use super::{Job, Mode, Viewer};
use crate::error::{Error, Result};
use crate::mesh::ray::ray_triangle;
use crate::render::{CarveMask, CarvedFace};
use crate::runtime::{AtlasOptions, Carving, CarvingOptions, FaceId, Model, Node, Tool};

/// Voxels of the carve mask along the tet mesh's longest side.
const MASK_VOXELS: f64 = 160.0;
/// Texels along a tet's mean edge in the cut-texture atlas (the default
/// wall's 1.23 mm edge: 8 texels a millimetre).
const TEXELS_PER_EDGE: f64 = 10.0;
/// Steps whose times the panel's median is over.
const RECENT_STEPS: usize = 50;

/// The Carve tool's state.
pub struct CarveTool {
    /// The sphere's radius, in mesh units.
    pub radius: f64,
    session: Option<Session>,
    job: Option<Job<Arc<Node>>>,
    /// Tets removed and steps taken since the session started.
    pub removed: usize,
    pub steps: usize,
    /// Every step's time, seconds.
    pub step_times: Vec<f64>,
    /// Where the last drag's sphere was, so the next sweeps from there.
    last_hit: Option<DVec3>,
}

impl Default for CarveTool {
    fn default() -> Self {
        CarveTool {
            radius: 1.5,
            session: None,
            job: None,
            removed: 0,
            steps: 0,
            step_times: Vec::new(),
            last_hit: None,
        }
    }
}

impl CarveTool {
    /// Whether the node is ready to carve.
    pub fn ready(&self) -> bool {
        self.session.is_some()
    }

    /// Whether the node is being made.
    pub fn busy(&self) -> bool {
        self.job.is_some()
    }

    /// Faces the carving exposed that are on the surface now.
    pub fn carved_faces(&self) -> usize {
        self.session.as_ref().map_or(0, |s| s.carved.len())
    }

    /// Median of the recent steps' times, seconds.
    pub fn median_step(&self) -> Option<f64> {
        let recent = self.step_times.len().saturating_sub(RECENT_STEPS);
        let mut t = self.step_times[recent..].to_vec();
        t.sort_unstable_by(f64::total_cmp);
        t.get(t.len() / 2).copied()
    }

    /// A line on the carving so far, when there was any.
    pub fn summary(&self) -> Option<String> {
        if self.steps == 0 {
            return None;
        }
        let mut t = self.step_times.clone();
        t.sort_unstable_by(f64::total_cmp);
        Some(format!(
            "carving: {} steps, {} tets removed, {} faces exposed; step time median {:.2} ms, worst {:.2} ms",
            self.steps,
            self.removed,
            self.carved_faces(),
            t[t.len() / 2] * 1e3,
            t[t.len() - 1] * 1e3
        ))
    }

    /// The drag ended: the next one starts a new sweep.
    pub fn release(&mut self) {
        self.last_hit = None;
    }
}

/// A carving of one node and what the viewer keeps of it.
struct Session {
    carving: Carving,
    /// The carved surface now, for picking.
    surface: HashMap<FaceId, [u32; 3]>,
    /// The faces the carving exposed: page and uvs.
    carved: HashMap<FaceId, (u32, [[f32; 2]; 3])>,
    mask: Mask,
}

/// The carved space: voxels inside removed tets (`inside`), and the mask
/// drawn, those a voxel wider (`data`).
struct Mask {
    size: [u32; 3],
    origin: DVec3,
    voxel: f64,
    inside: Vec<bool>,
    data: Vec<u8>,
}

impl Mask {
    fn over(lo: DVec3, hi: DVec3) -> Mask {
        let voxel = (hi - lo).max_element().max(1e-9) / MASK_VOXELS;
        let origin = lo - DVec3::splat(2.0 * voxel);
        let size = ((hi - lo) / voxel).to_array().map(|e| e.ceil() as u32 + 4);
        let n = size.iter().map(|&s| s as usize).product();
        Mask {
            size,
            origin,
            voxel,
            inside: vec![false; n],
            data: vec![0; n],
        }
    }

    fn index(&self, [x, y, z]: [u32; 3]) -> usize {
        x as usize + self.size[0] as usize * (y as usize + self.size[1] as usize * z as usize)
    }

    fn cell(&self, p: DVec3) -> [u32; 3] {
        let q = (p - self.origin) / self.voxel;
        [0, 1, 2].map(|a| (q[a].floor().max(0.0) as u32).min(self.size[a] - 1))
    }

    /// Mark the voxels whose centres lie in the tets `corners`, and
    /// widen the drawn mask by a voxel round them; the region written.
    fn carve(&mut self, tets: &[[DVec3; 4]]) -> Option<([u32; 3], [u32; 3])> {
        let mut region: Option<([u32; 3], [u32; 3])> = None;
        for c in tets {
            let lo = self.cell(c[0].min(c[1]).min(c[2]).min(c[3]));
            let hi = self.cell(c[0].max(c[1]).max(c[2]).max(c[3]));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let centre = self.origin
                            + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * self.voxel;
                        let b = crate::solid::lst::locate::barycentric(c, centre);
                        if b.iter().all(|&w| w >= -1e-9) {
                            let i = self.index([x, y, z]);
                            self.inside[i] = true;
                        }
                    }
                }
            }
            region = Some(match region {
                None => (lo, hi),
                Some((a, b)) => (
                    [0, 1, 2].map(|k| a[k].min(lo[k])),
                    [0, 1, 2].map(|k| b[k].max(hi[k])),
                ),
            });
        }
        let (lo, hi) = region?;
        let lo = lo.map(|v| v.saturating_sub(1));
        let hi = [0, 1, 2].map(|k| (hi[k] + 1).min(self.size[k] - 1));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let near = (z.saturating_sub(1)..=(z + 1).min(self.size[2] - 1)).any(|zz| {
                        (y.saturating_sub(1)..=(y + 1).min(self.size[1] - 1)).any(|yy| {
                            (x.saturating_sub(1)..=(x + 1).min(self.size[0] - 1))
                                .any(|xx| self.inside[self.index([xx, yy, zz])])
                        })
                    });
                    let i = self.index([x, y, z]);
                    self.data[i] = if near { 255 } else { 0 };
                }
            }
        }
        Some((lo, hi))
    }

    fn view(&self) -> CarveMask<'_> {
        CarveMask {
            size: self.size,
            origin: self.origin,
            voxel: self.voxel,
            data: &self.data,
        }
    }
}

impl Viewer {
    /// The Carve tool's panel: radius, figures, reset.
    pub(super) fn carve_panel(&mut self, ui: &mut egui::Ui) {
        ui.separator();
        ui.label("Carve (Carve mode: drag over the organ)");
        ui.add(
            egui::Slider::new(&mut self.carve.radius, 0.25..=6.0)
                .text("radius")
                .logarithmic(true),
        )
        .on_hover_text("the burr's radius, in the mesh's units (the bundled scenes: mm)");
        if self.carve.busy() {
            ui.label("preparing the node's tets and interior…");
        } else if self.carve.ready() {
            let frame_ms = ui.input(|i| i.unstable_dt) as f64 * 1e3;
            let step = self.carve.median_step().map_or(0.0, |s| s * 1e3);
            ui.label(format!(
                "{} tets removed in {} steps; {} faces exposed\nstep {step:.1} ms (median) · frame {frame_ms:.0} ms",
                self.carve.removed,
                self.carve.steps,
                self.carve.carved_faces()
            ));
            if ui.button("Reset carving").clicked() {
                self.reset_carving();
            }
        } else if self.mode == Mode::Carve {
            ui.label("the interior is on its way…");
        }
    }

    /// Every tet back.
    pub fn reset_carving(&mut self) {
        let node = self
            .carve
            .session
            .as_ref()
            .map(|s| s.carving.node().clone());
        self.carve.session = None;
        self.carve.removed = 0;
        self.carve.steps = 0;
        self.carve.step_times.clear();
        self.carve.last_hit = None;
        if let Some(scene) = &mut self.scene {
            scene.carved_mut().clear();
        }
        if let Some(node) = node
            && let Err(e) = self.start_session(node)
        {
            self.error(e);
        }
        self.touch();
    }

    /// In Carve mode: make the node to carve once the interior is there.
    pub(super) fn ensure_carving(&mut self) {
        if self.carve.session.is_some() || self.carve.job.is_some() {
            return;
        }
        let Some((volume, placement)) = self.interior_block.clone() else {
            self.start_interior();
            return;
        };
        let Some(doc) = &self.doc else { return };
        let Some(k) = (0..doc.closed.len())
            .find(|&k| doc.spec.nodes[k].interior.is_some())
            .or((!doc.closed.is_empty()).then_some(0))
        else {
            return self.error("nothing to carve: the scene has no closed node");
        };
        let name = doc.spec.nodes[k].name.clone();
        let method = doc.spec.nodes[k]
            .interior
            .as_ref()
            .map_or_else(Default::default, |i| i.method);
        let lapped = self.lst.get(k).cloned().flatten();
        let surface = doc.closed[k].0.clone();
        self.carve.job = Some(Job::spawn("carving's tets", self.wake(), move |p| {
            let node = match lapped {
                Some(model) => {
                    let lst = crate::solid::lst::LstInterior::new(model, Arc::new(volume))?;
                    Node::new(&name, method, Model::Lapped(lst), None)
                }
                None => {
                    let (tets, _) = crate::tetra::tetrahedralise_report(
                        &surface,
                        &crate::tetra::TetOptions::default(),
                        p,
                    )
                    .map_err(|e| e.within(format!("node '{name}': tet mesh")))?;
                    Node::new(
                        &name,
                        method,
                        Model::Block { volume, placement },
                        Some(tets),
                    )
                }
            };
            node.adjacency()?;
            node.centroids()?;
            Ok(Arc::new(node))
        }));
    }

    /// Take the carve job's node.
    pub(super) fn poll_carving(&mut self) {
        let Some(r) = self.carve.job.as_mut().and_then(Job::poll) else {
            return;
        };
        self.carve.job = None;
        match r.and_then(|node| self.start_session(node)) {
            Ok(()) => {}
            Err(Error::Cancelled) => self.mode = Mode::Camera,
            Err(e) => {
                self.mode = Mode::Camera;
                self.error(e)
            }
        }
    }

    fn start_session(&mut self, node: Arc<Node>) -> Result<()> {
        let mesh = node.require_tets()?;
        let edge = crate::solid::lst::mean_edge(mesh);
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| {
                (a.min(p), b.max(p))
            });
        let options = CarvingOptions {
            atlas: AtlasOptions {
                texels_per_unit: TEXELS_PER_EDGE / edge.max(1e-12),
                ..Default::default()
            },
            ..Default::default()
        };
        let carving = Carving::new(node, options)?;
        let surface = carving
            .surface()
            .into_iter()
            .map(|(id, f, _)| (id, f))
            .collect();
        self.carve.session = Some(Session {
            carving,
            surface,
            carved: HashMap::new(),
            mask: Mask::over(lo, hi),
        });
        Ok(())
    }

    /// Carve where the view's point `(x, y)` (-1..1, y up) meets the
    /// organ: a sphere there, swept from the last one of this drag. Whether
    /// anything was hit.
    pub fn carve_at(&mut self, x: f64, y: f64, aspect: f64) -> bool {
        let radius = self.carve.radius;
        let (origin, dir) = self.camera.ray(x, y, aspect);
        let Some(session) = &mut self.carve.session else {
            return false;
        };
        // The node is shared (Arc): hold it apart from the session.
        let node = session.carving.node().clone();
        let Ok(mesh) = node.require_tets() else {
            return false;
        };
        let p = |v: u32| mesh.positions[v as usize];
        let nearest = session
            .surface
            .values()
            .filter_map(|f| ray_triangle(origin, dir, f.map(p)).filter(|&t| t > 0.0))
            .fold(None, |best: Option<f64>, t| {
                Some(best.map_or(t, |b| b.min(t)))
            });
        let Some(t) = nearest else {
            return false;
        };
        let at = origin + dir * t;
        let tool = Tool::Capsule {
            a: self.carve.last_hit.unwrap_or(at),
            b: at,
            radius,
        };
        self.carve.last_hit = Some(at);
        match session.carving.carve(&tool) {
            Ok(step) => {
                for gone in &step.vanished {
                    session.surface.remove(&gone.id);
                    session.carved.remove(&gone.id);
                }
                for f in &step.appeared {
                    session.surface.insert(f.id, f.vertices);
                    session.carved.insert(f.id, (f.page, f.uvs));
                }
                let removed: Vec<[DVec3; 4]> = step
                    .removed
                    .iter()
                    .map(|&t| mesh.corners(t as usize))
                    .collect();
                let region = session.mask.carve(&removed);
                self.carve.removed += step.removed.len();
                self.carve.steps += 1;
                self.carve.step_times.push(step.seconds);
                if let Some(scene) = &mut self.scene {
                    let scene = scene.carved_mut();
                    let atlas = session.carving.atlas();
                    let side = atlas.options().page_size;
                    for &(page, r) in &step.dirty {
                        if let Some(rgba) = atlas.page(page) {
                            scene.set_page(
                                &self.renderer,
                                &self.gpu.device,
                                &self.gpu.queue,
                                page,
                                side,
                                rgba,
                                [r.x, r.y, r.width, r.height],
                            );
                        }
                    }
                    for &page in &step.released {
                        scene.drop_page(page);
                    }
                    let faces: Vec<CarvedFace> = session
                        .carved
                        .iter()
                        .map(|(id, &(page, uvs))| CarvedFace {
                            page,
                            corners: session.surface[id].map(p),
                            uvs,
                        })
                        .collect();
                    scene.set_faces(&self.gpu.device, &faces);
                    if region.is_some() {
                        scene.set_mask(
                            &self.renderer,
                            &self.gpu.device,
                            &self.gpu.queue,
                            Some(&session.mask.view()),
                            region,
                        );
                    }
                }
                self.touch();
            }
            Err(e) => self.error(e),
        }
        true
    }

    /// Triangles of carved faces drawn.
    pub fn carved_triangles(&self) -> usize {
        self.scene
            .as_ref()
            .map_or(0, crate::render::GpuScene::carved_triangles)
    }
}
