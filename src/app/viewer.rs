//! The viewer window: panels on the left (file, facets, tissues, the
//! selected facet's texture, layers, cut plane), the scene in the middle,
//! drawn by `crate::render` into a texture egui shows. Everything slow
//! runs as a `Job`; the UI only starts jobs, takes their results, and
//! shows progress and messages.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use eframe::{egui, egui_wgpu};
use glam::DVec3;

use super::document::Document;
use super::file_dialog::{FileDialog, Outcome, Purpose};
use super::jobs::{Job, Running};
use crate::db::Shelf;
use crate::error::{Error, Result};
use crate::render::{CutMesh, Gpu, GpuScene, Layers, Offscreen, OrbitCamera, Renderer, View};
use crate::scene::build::{BakedScene, Tissues, ensure_tissues};
use crate::scene::draw::DrawList;
use crate::solid::InteriorMethod;
use crate::solid::{Placement, Plane, interior_block, plane_section};
use crate::synth::volume::Volume;

/// How the viewer starts.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// A scene (.toml) or mesh to open.
    pub open: Option<PathBuf>,
    /// Save a screenshot of the window after `frames` frames (once
    /// loading and unwrapping are done), then close.
    pub screenshot: Option<PathBuf>,
    pub frames: usize,
    /// Drag the selected facet's texture a little every frame (to time
    /// the drag path).
    pub drag: bool,
}

/// What the mouse does in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Drag turns, right or middle drag pans, the wheel zooms.
    Camera,
    /// Drag moves the selected facet's texture, shift-drag turns it, the
    /// wheel scales it.
    Texture,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutPlane {
    pub on: bool,
    /// The plane's unit normal: the half of the scene it points into is
    /// cut away, and the section faces that way. An axis, or towards the
    /// camera when set from the view.
    pub normal: DVec3,
    /// Where across the scene's bounds along the normal, 0..1.
    pub at: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub error: bool,
}

/// A database entry on the tissue shelf, with its thumbnail.
struct TissueEntry {
    tissue: crate::db::Tissue,
    thumbnail: Option<egui::TextureHandle>,
}

/// Every entry and its thumbnail's pixels, as a background job reads them.
type Thumbnails = Vec<(crate::db::Tissue, Option<egui::ColorImage>)>;

/// What the cut plane shows inside: the interior block, and per node its
/// lapped solid texture where the scene asks for one (`[node.interior.lst]`,
/// laid as the bake lays it, the block as exemplar).
/// Voxels a side of the block a morphed interior is sampled into for the
/// cut plane (128^3 points: about 0.4 s on 2 cores).
const MORPH_VOXELS: usize = 128;

struct Interiors {
    block: Volume,
    lst: Vec<Option<crate::solid::lst::LstModel>>,
    /// Where the block lies when it does not tile from the origin (a
    /// morph sampled over its node's bounds).
    placement: Option<Placement>,
}

#[derive(Default)]
struct Jobs {
    open: Option<Job<Document>>,
    unwrap: Option<Job<BakedScene>>,
    tissues: Option<Job<Tissues>>,
    thumbnails: Option<Job<Thumbnails>>,
    block: Option<Job<Interiors>>,
    bake: Option<Job<PathBuf>>,
}

impl Jobs {
    /// The jobs the status bar shows (thumbnails load unannounced).
    fn shown(&self) -> Vec<&dyn Running> {
        let jobs: [Option<&dyn Running>; 5] = [
            self.open.as_ref().map(|j| j as &dyn Running),
            self.unwrap.as_ref().map(|j| j as &dyn Running),
            self.tissues.as_ref().map(|j| j as &dyn Running),
            self.block.as_ref().map(|j| j as &dyn Running),
            self.bake.as_ref().map(|j| j as &dyn Running),
        ];
        jobs.into_iter().flatten().collect()
    }
}

pub struct Viewer {
    gpu: Gpu,
    egui_renderer: Arc<eframe::epaint::mutex::RwLock<egui_wgpu::Renderer>>,
    renderer: Renderer,
    /// Where the scene is drawn for egui: at the window's resolution,
    /// and at half of it while the mouse moves the view or a texture.
    targets: [Option<SceneTarget>; 2],
    /// Which of `targets` was drawn last.
    shown: usize,
    /// Whether the last frame moved the view or a texture.
    interacting: bool,
    pub doc: Option<Document>,
    pub list: DrawList,
    scene: Option<GpuScene>,
    /// Times the scene's vertex data went to the GPU (a texture drag
    /// must not add to it).
    pub uploads: usize,
    pub camera: OrbitCamera,
    pub layers: Layers,
    pub selected: Option<(usize, usize)>,
    pub mode: Mode,
    pub cut: CutPlane,
    /// Per node, its lapped solid texture (cuts through it are coloured
    /// by the LST shader, not the block).
    lst: Vec<Option<crate::solid::lst::LstModel>>,
    /// Where the interior block was placed when it went to the GPU.
    block_placement: Option<Placement>,
    /// Where the 3D view was last drawn, in points (the texture dial turns
    /// about its centre).
    view_rect: Option<egui::Rect>,
    /// The cut plane the section was last made for.
    cut_made: Option<([f64; 3], f64)>,
    pub message: Option<Message>,
    tissues: Vec<TissueEntry>,
    /// The shelf the tissue panel shows.
    shelf: Shelf,
    dialog: Option<FileDialog>,
    jobs: Jobs,
    /// Bumped by every change that alters the picture; a target whose
    /// picture is of an older generation is drawn again.
    generation: u64,
    opts: Options,
    frames_left: Option<usize>,
    screenshot_result: ScreenshotSlot,
    pub frame_times: Vec<f64>,
    last_frame: Option<Instant>,
    ctx: egui::Context,
}

/// An offscreen picture of the scene, registered with egui.
struct SceneTarget {
    offscreen: Offscreen,
    id: egui::TextureId,
    /// The generation its picture shows.
    drawn: Option<u64>,
}

/// Pixels of the interactive target per pixel of the full one, along
/// each axis. On a software rasteriser (llvmpipe) a drag frame of the
/// default scene costs about 146 ms at full resolution and 100 ms at half;
/// the full picture follows one frame after the mouse stops.
const INTERACTIVE_SCALE: u32 = 2;

/// Error out of the screenshot, reported by `run` after the window closes.
pub type ScreenshotSlot = Arc<Mutex<Option<Result<()>>>>;

impl Viewer {
    /// A viewer on eframe's wgpu device (the window's, or the test
    /// harness's).
    pub fn new(cc: &eframe::CreationContext<'_>, opts: Options) -> Result<Viewer> {
        let rs = cc
            .wgpu_render_state
            .as_ref()
            .ok_or_else(|| Error::invalid("the viewer needs eframe's wgpu renderer"))?;
        let gpu = Gpu::from_parts(rs.device.clone(), rs.queue.clone(), &rs.adapter);
        let renderer = Renderer::new(&gpu.device);
        let mut viewer = Viewer {
            gpu,
            egui_renderer: rs.renderer.clone(),
            renderer,
            targets: [None, None],
            shown: 0,
            interacting: false,
            doc: None,
            list: DrawList::default(),
            scene: None,
            uploads: 0,
            camera: OrbitCamera::fit(DVec3::splat(-1.0), DVec3::splat(1.0)),
            layers: Layers::default(),
            selected: None,
            mode: Mode::Camera,
            cut: CutPlane {
                on: false,
                normal: DVec3::X,
                at: 0.5,
            },
            lst: Vec::new(),
            block_placement: None,
            view_rect: None,
            cut_made: None,
            message: None,
            tissues: Vec::new(),
            shelf: Shelf::Surface,
            dialog: None,
            jobs: Jobs::default(),
            generation: 0,
            frames_left: opts.screenshot.as_ref().map(|_| opts.frames.max(1)),
            opts: opts.clone(),
            screenshot_result: Arc::new(Mutex::new(None)),
            frame_times: Vec::new(),
            last_frame: None,
            ctx: cc.egui_ctx.clone(),
        };
        if let Some(path) = opts.open {
            viewer.open(path);
        }
        Ok(viewer)
    }

    pub fn screenshot_slot(&self) -> ScreenshotSlot {
        self.screenshot_result.clone()
    }

    /// Whether any job is running.
    pub fn busy(&self) -> bool {
        !self.jobs.shown().is_empty() || self.jobs.thumbnails.is_some()
    }

    pub fn adapter(&self) -> &str {
        &self.gpu.adapter
    }

    /// The device the viewer draws on (tests provoke GPU errors on it).
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    fn wake(&self) -> impl Fn() + Send + 'static {
        let ctx = self.ctx.clone();
        move || ctx.request_repaint()
    }

    fn error(&mut self, e: impl std::fmt::Display) {
        self.message = Some(Message {
            text: e.to_string(),
            error: true,
        });
    }

    /// Start opening `path`; the current scene stays until it has loaded.
    pub fn open(&mut self, path: PathBuf) {
        let what = format!("opening {}", path.display());
        self.jobs.open = Some(Job::spawn(what, self.wake(), move |_| {
            Document::open(&path)
        }));
    }

    /// Start unwrapping (cutting and flattening) every facet.
    pub fn unwrap(&mut self) {
        let Some(doc) = &self.doc else { return };
        if self.jobs.unwrap.is_some() {
            return;
        }
        let spec = doc.spec.clone();
        self.jobs.unwrap = Some(Job::spawn("unwrapping", self.wake(), move |p| {
            crate::scene::build::build_scene(&spec, false, p)
        }));
    }

    /// Give the selected facet tissue `id`.
    pub fn pick_tissue(&mut self, id: &str) {
        let (Some(doc), Some(f)) = (&mut self.doc, self.selected) else {
            return;
        };
        let mut s = doc.settings(f).clone();
        s.texture = id.to_string();
        doc.set_settings(f, s);
        if doc.baked.is_some() {
            self.rebuild_tissues();
        }
    }

    /// Lay vessel overlay `id` over the selected facet, or take it off if
    /// it is the facet's overlay already.
    pub fn pick_overlay(&mut self, id: &str) {
        let (Some(doc), Some(f)) = (&mut self.doc, self.selected) else {
            return;
        };
        let mut s = doc.settings(f).clone();
        s.overlay = (s.overlay.as_deref() != Some(id)).then(|| id.to_string());
        doc.set_settings(f, s);
        if doc.baked.is_some() {
            self.rebuild_tissues();
        }
    }

    /// The tissue textures the scene now uses (built if missing), then a
    /// fresh draw list.
    fn rebuild_tissues(&mut self) {
        let Some(doc) = &self.doc else { return };
        let spec = doc.spec.clone();
        self.jobs.tissues = Some(Job::spawn("tissue textures", self.wake(), move |p| {
            let db = crate::db::Database::open(&spec.database)?;
            ensure_tissues(&spec, &db, p)
        }));
    }

    /// Apply a change to the selected facet's texture transform: one
    /// uniform per material of that facet, nothing that grows with the
    /// mesh.
    pub fn edit_texture(&mut self, edit: impl FnOnce(&mut crate::scene::file::FacetSettings)) {
        let (Some(doc), Some(f)) = (&mut self.doc, self.selected) else {
            return;
        };
        let mut s = doc.settings(f).clone();
        edit(&mut s);
        tidy(&mut s);
        doc.set_settings(f, s.clone());
        if let Some(scene) = &self.scene {
            for m in 0..self.list.materials.len() {
                if self.list.materials[m].facet == Some(f) {
                    let t = self.list.materials[m].transform_for(&s);
                    self.list.materials[m].transform = t;
                    scene.set_transform(&self.gpu.queue, &self.list, m, t.as_ref());
                }
            }
        }
        self.touch();
    }

    /// Select facet `f`.
    pub fn select(&mut self, f: (usize, usize)) {
        self.selected = Some(f);
        if self.doc.as_ref().is_some_and(|d| d.baked.is_none()) {
            self.rebuild_list();
        }
    }

    /// Draw list and GPU scene from the document as it is.
    fn rebuild_list(&mut self) {
        let Some(doc) = &self.doc else {
            self.list = DrawList::default();
            self.scene = None;
            return;
        };
        self.list = match &doc.baked {
            Some(b) => DrawList::of(b, None),
            None => DrawList::plain(&doc.meshes.iter().collect::<Vec<_>>(), self.selected),
        };
        match GpuScene::new(
            &self.renderer,
            &self.gpu.device,
            &self.gpu.queue,
            &self.list,
        ) {
            Ok(mut s) => {
                // The interior block stays.
                if let Some(old) = self.scene.take() {
                    s.keep_block(old);
                }
                self.scene = Some(s);
                self.uploads += 1;
                self.cut_made = None;
            }
            Err(e) => self.error(e),
        }
        self.touch();
    }

    /// Back to the camera the document opened with.
    pub fn reset_view(&mut self) {
        if let Some(doc) = &self.doc {
            self.camera = OrbitCamera::for_scene(&doc.spec.cameras, doc.bounds());
            self.touch();
        }
    }

    /// Take finished jobs' results.
    fn poll_jobs(&mut self) {
        if let Some(r) = self.jobs.open.as_mut().and_then(Job::poll) {
            self.jobs.open = None;
            match r {
                Ok(doc) => {
                    let is_scene = doc.spec.path.extension().is_some_and(|e| e == "toml");
                    self.jobs.unwrap = None;
                    self.jobs.tissues = None;
                    let db = doc.spec.database.clone();
                    self.doc = Some(doc);
                    self.reset_view();
                    self.selected = Some((0, 0));
                    // A new scene starts without the old interior block.
                    self.scene = None;
                    self.lst.clear();
                    self.cut.on = false;
                    self.message = None;
                    self.rebuild_list();
                    self.jobs.thumbnails = Some(Job::spawn("thumbnails", self.wake(), move |_| {
                        thumbnails(&db)
                    }));
                    // A designed scene shows textured at once; a bare
                    // mesh waits for its tissues and the Unwrap button.
                    if is_scene {
                        self.unwrap();
                    }
                }
                Err(e) => self.error(e),
            }
        }
        if let Some(r) = self.jobs.unwrap.as_mut().and_then(Job::poll) {
            self.jobs.unwrap = None;
            match r {
                Ok(baked) => {
                    if let Some(doc) = &mut self.doc {
                        // Settings changed during the unwrap win.
                        let mut baked = baked;
                        for (k, node) in baked.nodes.iter_mut().enumerate() {
                            for f in &mut node.facets {
                                f.settings =
                                    doc.spec.nodes[k].facets[f.piece.facet as usize].clone();
                            }
                        }
                        doc.baked = Some(baked);
                        // Tissues picked while unwrapping.
                        self.rebuild_tissues();
                    }
                }
                Err(Error::Cancelled) => {
                    self.message = Some(Message {
                        text: "unwrap cancelled".into(),
                        error: false,
                    })
                }
                Err(e) => self.error(e),
            }
        }
        if let Some(r) = self.jobs.tissues.as_mut().and_then(Job::poll) {
            self.jobs.tissues = None;
            match r {
                Ok(t) => {
                    if let Some(b) = self.doc.as_mut().and_then(|d| d.baked.as_mut()) {
                        b.tissues = t;
                    }
                    self.rebuild_list();
                }
                Err(Error::Cancelled) => {}
                Err(e) => self.error(e),
            }
        }
        if let Some(r) = self.jobs.thumbnails.as_mut().and_then(Job::poll) {
            self.jobs.thumbnails = None;
            match r {
                Ok(list) => {
                    self.tissues = list
                        .into_iter()
                        .map(|(tissue, img)| TissueEntry {
                            thumbnail: img.map(|i| {
                                self.ctx.load_texture(
                                    format!("tissue:{}", tissue.id),
                                    i,
                                    Default::default(),
                                )
                            }),
                            tissue,
                        })
                        .collect()
                }
                Err(e) => self.error(e),
            }
        }
        if let Some(r) = self.jobs.block.as_mut().and_then(Job::poll) {
            self.jobs.block = None;
            match r {
                Ok(interiors) => {
                    self.lst = interiors.lst;
                    self.set_block(interiors.block, interiors.placement)
                }
                Err(Error::Cancelled) => self.cut.on = false,
                Err(e) => {
                    self.cut.on = false;
                    self.error(e)
                }
            }
        }
        if let Some(r) = self.jobs.bake.as_mut().and_then(Job::poll) {
            self.jobs.bake = None;
            match r {
                Ok(dir) => {
                    self.message = Some(Message {
                        text: format!("baked into {}", dir.display()),
                        error: false,
                    })
                }
                Err(e) => self.error(e),
            }
        }
    }

    /// Mesh units one interior block covers (the scene's interior setting,
    /// else a third of the scene's diagonal), and where it starts: the
    /// origin, the placement the bake gives `interior/NODE.nrrd` (the
    /// viewer's block is a quicker 32^3 one).
    fn block_units(&self) -> Option<(f64, DVec3)> {
        let doc = self.doc.as_ref()?;
        let (lo, hi) = doc.bounds()?;
        let units = doc
            .spec
            .nodes
            .iter()
            .find_map(|n| n.interior.as_ref().map(|i| i.block_size))
            .unwrap_or((hi - lo).length() / 3.0);
        Some((units, DVec3::ZERO))
    }

    fn set_block(&mut self, volume: Volume, placed: Option<Placement>) {
        let Some((units, lo)) = self.block_units() else {
            return;
        };
        let placement =
            match placed.map_or_else(|| Placement::new(lo, units / volume.size[0] as f64), Ok) {
                Ok(p) => p,
                Err(e) => return self.error(e),
            };
        self.block_placement = Some(placement);
        if let Some(scene) = &mut self.scene
            && let Err(e) = scene.set_block(
                &self.renderer,
                &self.gpu.device,
                &self.gpu.queue,
                &volume,
                &placement,
            )
        {
            self.error(e);
        }
        self.cut_made = None;
        self.touch();
    }

    /// Whether the interior block is on the GPU.
    fn has_block(&self) -> bool {
        self.scene.as_ref().is_some_and(GpuScene::has_block)
    }

    /// Turn the cut plane on; the first time, synthesise the interior.
    pub fn set_cut(&mut self, on: bool) {
        self.cut.on = on;
        self.cut_made = None;
        self.touch();
        if !on || self.has_block() || self.jobs.block.is_some() {
            return;
        }
        let Some(doc) = &self.doc else { return };
        // A morphed interior (seed 003) is sampled over its node's bounds
        // at MORPH_VOXELS a side: the cut plane's GPU path reads a block.
        let morphed = doc
            .spec
            .nodes
            .iter()
            .zip(&doc.closed)
            .find_map(|(n, closed)| {
                n.interior
                    .as_ref()
                    .filter(|i| i.method == InteriorMethod::Morph)
                    .and_then(|i| i.sections.clone())
                    .map(|sections| (closed.clone(), sections))
            });
        if let Some(((mesh, topology), sections)) = morphed {
            self.jobs.block = Some(Job::spawn("interior morph", self.wake(), move |p| {
                let morph = crate::solid::morph::Morph::read(
                    &mesh,
                    &topology,
                    &sections,
                    Default::default(),
                    p,
                )?;
                let (lo, hi) = mesh
                    .bounding_box()
                    .ok_or_else(|| Error::invalid("the mesh has no vertices"))?;
                let (block, placement) = morph.block(lo, hi, MORPH_VOXELS)?;
                Ok(Interiors {
                    block,
                    lst: Vec::new(),
                    placement: Some(placement),
                })
            }));
            return;
        }
        let interior = doc.spec.nodes.iter().find_map(|n| {
            n.interior
                .as_ref()
                .map(|i| (i.texture.clone(), i.method, i.photographs.clone()))
        });
        let Some((tissue, method, photographs)) = interior.or_else(|| {
            self.selected.map(|f| {
                (
                    doc.settings(f).texture.clone(),
                    InteriorMethod::default(),
                    Vec::new(),
                )
            })
        }) else {
            return;
        };
        let database = doc.spec.database.clone();
        // The nodes to lap: their name, surface, interior settings.
        let lapped: Vec<_> = doc
            .spec
            .nodes
            .iter()
            .zip(&doc.meshes)
            .map(|(n, mesh)| {
                n.interior
                    .as_ref()
                    .filter(|i| i.lst.is_some())
                    .map(|i| (n.name.clone(), mesh.clone(), i.clone()))
            })
            .collect();
        self.jobs.block = Some(Job::spawn(
            "interior solid texture",
            self.wake(),
            move |p| {
                let db = crate::db::Database::open(&database)?;
                let t = db.tissue(&tissue)?;
                if !crate::db::build::is_current(&db, t)? {
                    crate::db::build(&db, std::slice::from_ref(&tissue), p)?;
                }
                // Stereology's voxels are the photographs' pixels: 32 would
                // hold few particles.
                let size = if method == InteriorMethod::Stereology {
                    64
                } else {
                    32
                };
                let block = interior_block(
                    &db.output_path(&tissue, method.output()),
                    &photographs,
                    size,
                    method,
                    0,
                    p,
                )?;
                let lst = lapped
                    .iter()
                    .enumerate()
                    .map(|(k, node)| {
                        let Some((name, surface, interior)) = node else {
                            return Ok(None);
                        };
                        let spec = interior.lst.as_ref().expect("filtered on lst");
                        let (tets, _) = crate::tetra::tetrahedralise_report(
                            surface,
                            &crate::tetra::TetOptions::default(),
                            p,
                        )
                        .map_err(|e| Error::invalid(format!("node '{name}': tet mesh: {e}")))?;
                        // The bake's seed, so the cut shows what it bakes.
                        let (model, _, _) = crate::bake::lap(
                            spec,
                            surface,
                            &tets,
                            interior.block_size,
                            k as u64,
                            name,
                            p,
                        )?;
                        Ok(Some(model))
                    })
                    .collect::<Result<_>>()?;
                Ok(Interiors {
                    block,
                    lst,
                    placement: None,
                })
            },
        ));
    }

    /// Turn the cut plane to face the camera, half way across the scene, so
    /// the section shows what lies straight ahead.
    pub fn cut_facing_view(&mut self) {
        self.cut.normal = (self.camera.eye() - self.camera.target)
            .try_normalize()
            .unwrap_or(DVec3::Z);
        self.cut.at = 0.5;
        self.touch();
    }

    /// The plane's normal and offset in object space.
    pub fn cut_plane(&self) -> Option<(DVec3, f64)> {
        if !self.cut.on {
            return None;
        }
        let (lo, hi) = self.doc.as_ref()?.bounds()?;
        let n = self.cut.normal;
        // The bounds' extent along the normal: their corners' nearest and
        // farthest.
        let (near, far) = (0..8)
            .map(|k| {
                let corner = DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                n.dot(corner)
            })
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
                (a.min(d), b.max(d))
            });
        Some((n, near + self.cut.at * (far - near)))
    }

    /// Remake the section when the plane moved.
    fn update_section(&mut self) {
        let plane = self.cut_plane().filter(|_| self.has_block());
        let key = plane.map(|(n, d)| (n.to_array(), d));
        if key == self.cut_made {
            return;
        }
        self.cut_made = key;
        let (Some(doc), Some(scene)) = (&self.doc, &mut self.scene) else {
            return;
        };
        let Some((normal, offset)) = plane else {
            scene.set_cut(&self.gpu.device, None);
            // Setting none cannot fail.
            let _ = scene.set_lst_cut(&self.renderer, &self.gpu.device, &self.gpu.queue, None);
            return;
        };
        let mut cut = CutMesh {
            positions: Vec::new(),
            normals: Vec::new(),
            triangles: Vec::new(),
        };
        let mut problem = None;
        let mut lst_cut = crate::solid::lst::gpu::CutBuffers::default();
        for (k, (mesh, topology)) in doc.closed.iter().enumerate() {
            if let Some(Some(model)) = self.lst.get(k) {
                let c = crate::tetra::march::plane_cut(&model.mesh, normal, offset);
                lst_cut.add(model, &c, normal);
                continue;
            }
            let section = Plane::new(normal, offset).and_then(|p| plane_section(mesh, topology, p));
            match section {
                Ok(s) => {
                    let base = cut.positions.len() as u32;
                    cut.normals
                        .extend(std::iter::repeat_n(s.normal, s.positions.len()));
                    cut.positions.extend(&s.positions);
                    cut.triangles
                        .extend(s.triangles.iter().map(|t| t.map(|v| v + base)));
                }
                Err(e) => problem = Some(format!("node '{}': {e}", doc.spec.nodes[k].name)),
            }
        }
        scene.set_cut(&self.gpu.device, Some(&cut));
        if let Err(e) = scene.set_lst_cut(
            &self.renderer,
            &self.gpu.device,
            &self.gpu.queue,
            Some(&lst_cut),
        ) {
            problem = Some(e.to_string());
        }
        if let Some(p) = problem {
            self.error(format!("cannot cut: {p}"));
        }
        self.touch();
    }

    /// The picture changed: every target must be drawn again.
    fn touch(&mut self) {
        self.generation += 1;
    }

    /// Draw the scene for egui into a texture `size` pixels, or, while
    /// the user moves the view (`coarse`), a texture
    /// `INTERACTIVE_SCALE` times smaller that egui scales up.
    fn draw_scene(&mut self, size: [u32; 2], coarse: bool) -> Option<egui::TextureId> {
        let slot = coarse as usize;
        let size = if coarse {
            size.map(|s| s.div_ceil(INTERACTIVE_SCALE))
        } else {
            size
        };
        if self.targets[slot]
            .as_ref()
            .is_none_or(|t| t.offscreen.size != size)
        {
            let offscreen = Offscreen::new(&self.gpu, &self.renderer, size);
            let mut r = self.egui_renderer.write();
            let id = match self.targets[slot].take() {
                Some(old) => {
                    r.update_egui_texture_from_wgpu_texture(
                        &self.gpu.device,
                        offscreen.display_view(),
                        wgpu::FilterMode::Linear,
                        old.id,
                    );
                    old.id
                }
                None => r.register_native_texture(
                    &self.gpu.device,
                    offscreen.display_view(),
                    wgpu::FilterMode::Linear,
                ),
            };
            self.targets[slot] = Some(SceneTarget {
                offscreen,
                id,
                drawn: None,
            });
        }
        let target = self.targets[slot].as_ref()?;
        if target.drawn != Some(self.generation)
            && let Some(scene) = &self.scene
        {
            let view = View {
                camera: self.camera,
                layers: self.layers,
                clip: self.cut_plane().filter(|_| self.has_block()),
            };
            target.offscreen.draw(
                &self.renderer,
                &self.gpu.device,
                &self.gpu.queue,
                scene,
                &view,
            );
            let generation = self.generation;
            if let Some(t) = self.targets[slot].as_mut() {
                t.drawn = Some(generation);
            }
        }
        self.shown = slot;
        self.targets[slot].as_ref().map(|t| t.id)
    }

    /// Triangles of the cut surface drawn.
    /// Where the 3D view was last drawn.
    pub fn view_rect(&self) -> Option<egui::Rect> {
        self.view_rect
    }

    /// Where the interior block on the GPU lies, if one is.
    pub fn block_placement(&self) -> Option<Placement> {
        self.block_placement.filter(|_| self.has_block())
    }

    pub fn cut_triangles(&self) -> usize {
        self.scene.as_ref().map_or(0, GpuScene::cut_triangles)
    }

    /// Of those, the ones through lapped solid textures.
    pub fn lst_cut_triangles(&self) -> usize {
        self.scene.as_ref().map_or(0, GpuScene::lst_cut_triangles)
    }

    /// The last frame drawn, read back (tests).
    pub fn read_scene(&self) -> Result<image::RgbaImage> {
        let target = self.targets[self.shown]
            .as_ref()
            .ok_or_else(|| Error::invalid("nothing drawn yet"))?;
        target.offscreen.read(&self.gpu.device, &self.gpu.queue)
    }

    fn save(&mut self, path: PathBuf) {
        let path = if path.extension().is_none() {
            path.with_extension("toml")
        } else {
            path
        };
        if let Some(doc) = &self.doc {
            self.message = Some(match doc.save(&path) {
                Ok(()) => Message {
                    text: format!("saved {}", path.display()),
                    error: false,
                },
                Err(e) => Message {
                    text: e.to_string(),
                    error: true,
                },
            });
        }
    }

    /// Save the scene into out/<name>/scene.toml and bake it there.
    pub fn bake(&mut self) {
        let Some(doc) = &self.doc else { return };
        let dir = PathBuf::from("out").join(doc.spec.name.replace(['/', '\\', ' '], "_"));
        let scene = dir.join("scene.toml");
        if let Err(e) = std::fs::create_dir_all(&dir)
            .map_err(|e| Error::io(&dir, e))
            .and_then(|_| doc.save(&scene))
        {
            return self.error(e);
        }
        self.jobs.bake = Some(Job::spawn("baking", self.wake(), move |p| {
            crate::bake::bake(&scene, &dir, &Default::default(), p).map(|_| dir)
        }));
    }

    /// File dialogs start in the open document's folder (else the
    /// working directory), so Save lands beside the scene it came from.
    fn dialog_dir(&self) -> PathBuf {
        let here = std::env::current_dir().unwrap_or_default();
        self.doc
            .as_ref()
            .and_then(|d| d.spec.path.parent())
            .and_then(|p| std::fs::canonicalize(here.join(p)).ok())
            .unwrap_or(here)
    }

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if ui.button("Open…").clicked() {
                let dir = self.dialog_dir();
                self.dialog = Some(FileDialog::new(Purpose::Open, dir, String::new()));
            }
            let has_doc = self.doc.is_some();
            if ui
                .add_enabled(has_doc, egui::Button::new("Save…"))
                .clicked()
            {
                let dir = self.dialog_dir();
                let name = self
                    .doc
                    .as_ref()
                    .map_or("scene".into(), |d| format!("{}.toml", d.spec.name));
                self.dialog = Some(FileDialog::new(Purpose::Save, dir, name));
            }
            if ui
                .add_enabled(
                    has_doc && self.jobs.bake.is_none(),
                    egui::Button::new("Bake"),
                )
                .clicked()
            {
                self.bake();
            }
            ui.separator();
            let running = self.jobs.shown();
            for job in &running {
                let (what, fraction) = job.status();
                let bar = egui::ProgressBar::new(fraction.unwrap_or(0.0))
                    .desired_width(160.0)
                    .text(what);
                ui.add(if fraction.is_none() {
                    bar.animate(true)
                } else {
                    bar
                });
            }
            if !running.is_empty() && ui.button("Cancel").clicked() {
                running.iter().for_each(|j| j.cancel());
            }
            if let Some(m) = &self.message {
                let colour = if m.error {
                    egui::Color32::from_rgb(255, 110, 100)
                } else {
                    egui::Color32::from_rgb(150, 220, 150)
                };
                ui.colored_label(colour, &m.text);
                if ui.small_button("Dismiss").clicked() {
                    self.message = None;
                }
            }
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        let Some(doc) = &self.doc else {
            ui.label("Open a scene or a mesh (Open…).");
            return;
        };
        ui.heading(&doc.spec.name);
        ui.label("Facets");
        let facets = doc.facets();
        let mut select = None;
        for (f, name) in facets {
            if ui
                .selectable_label(self.selected == Some(f), name)
                .clicked()
            {
                select = Some(f);
            }
        }
        if let Some(f) = select {
            self.select(f);
        }
        ui.separator();
        let unwrapping = self.jobs.unwrap.is_some();
        if ui
            .add_enabled(!unwrapping, egui::Button::new("Unwrap"))
            .on_hover_text("Cut every facet along hidden seams and flatten it (Seamster + ABF++)")
            .clicked()
        {
            self.unwrap();
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.label("Tissue");
            for shelf in Shelf::ALL {
                let count = self
                    .tissues
                    .iter()
                    .filter(|t| t.tissue.shelf() == shelf)
                    .count();
                ui.selectable_value(&mut self.shelf, shelf, format!("{} ({count})", shelf.title()))
                    .on_hover_text(match shelf {
                        Shelf::Surface => "textures for organ surfaces: click to give one to the selected facet",
                        Shelf::Interior => "histology for cut surfaces and the inside: click to give one to the selected facet",
                        Shelf::Overlay => "vessel overlays: click to lay one over the selected facet, again to take it off",
                    });
            }
        });
        let current = self
            .selected
            .and_then(|f| self.doc.as_ref().map(|d| d.settings(f).clone()));
        let shelf = self.shelf;
        let mut pick = None;
        // The shelf scrolls on its own, so the texture's settings and the
        // cut plane below it stay in view however many tissues there are.
        egui::ScrollArea::vertical()
            .id_salt("tissue shelf")
            .max_height(192.0)
            .show(ui, |ui| {
                egui::Grid::new("tissues").num_columns(2).show(ui, |ui| {
                    let on_shelf = self.tissues.iter().filter(|t| t.tissue.shelf() == shelf);
                    for (
                        i,
                        TissueEntry {
                            tissue: t,
                            thumbnail,
                        },
                    ) in on_shelf.enumerate()
                    {
                        let on = current.as_ref().is_some_and(|s| match shelf {
                            Shelf::Overlay => s.overlay.as_deref() == Some(t.id.as_str()),
                            _ => s.texture == t.id,
                        });
                        let r = match thumbnail {
                            Some(tex) => ui.add(
                                egui::Button::image_and_text(
                                    egui::Image::new((tex.id(), egui::vec2(40.0, 40.0))),
                                    &t.name,
                                )
                                .selected(on),
                            ),
                            None => ui.add(egui::Button::new(&t.name).selected(on)),
                        };
                        if r.on_hover_text(t.credit_line()).clicked() {
                            pick = Some((
                                t.id.clone(),
                                shelf,
                                t.outputs.contains(&crate::db::Output::Colour),
                            ));
                        }
                        if i % 2 == 1 {
                            ui.end_row();
                        }
                    }
                });
            });
        match pick {
            Some(_) if self.selected.is_none() => {
                self.error("select a facet first (the list above): the tissue goes on it")
            }
            Some((id, Shelf::Overlay, _)) => self.pick_overlay(&id),
            Some((id, _, true)) => self.pick_tissue(&id),
            Some((id, _, false)) => self.error(format!(
                "'{id}' is a layered exemplar for interiors, not a facet's texture: \
                 a scene lays it through a node with [node.interior] texture = \"{id}\", \
                 method = \"layered\""
            )),
            None => {}
        }
        if let (Some(f), Some(doc)) = (self.selected, &self.doc) {
            ui.separator();
            ui.label("Texture (or drag it in Texture mode)");
            let s = doc.settings(f).clone();
            let (mut tile, mut rotation, mut offset) = (s.tile_size, s.rotation, s.offset);
            let mut changed = false;
            changed |= ui
                .add(
                    egui::Slider::new(&mut tile, s.tile_size * 0.5..=s.tile_size * 2.0)
                        .text("tile size"),
                )
                .changed();
            changed |= ui
                .add(egui::Slider::new(&mut rotation, -180.0..=180.0).text("rotation °"))
                .changed();
            changed |= ui
                .add(egui::Slider::new(&mut offset[0], -1.0..=1.0).text("offset u"))
                .changed();
            changed |= ui
                .add(egui::Slider::new(&mut offset[1], -1.0..=1.0).text("offset v"))
                .changed();
            if changed {
                self.edit_texture(|s| {
                    s.tile_size = tile;
                    s.rotation = rotation;
                    s.offset = offset;
                });
            }
            // The facet's unwrap bound: seams against an even texture
            // scale, taken up by the next unwrap.
            let mut stretch = s.max_stretch;
            let moved = ui
                .add(egui::Slider::new(&mut stretch, 0.1..=0.5).text("max stretch"))
                .on_hover_text(
                    "how far the texture's scale may drift over this facet (mean |log area ratio|): \
                     lower cuts more seams, which the bake blends away; applies at the next Unwrap",
                )
                .changed();
            if moved && let Some(doc) = &mut self.doc {
                let mut now = doc.settings(f).clone();
                now.max_stretch = stretch;
                doc.set_settings(f, now);
            }
        }
        ui.separator();
        ui.label("Show");
        let before = self.layers;
        ui.checkbox(&mut self.layers.seam_blend, "seam blend");
        ui.checkbox(&mut self.layers.bump, "bump");
        ui.checkbox(&mut self.layers.overlay, "overlay");
        ui.checkbox(&mut self.layers.wireframe, "wireframe");
        ui.checkbox(&mut self.layers.seams, "seams");
        ui.checkbox(&mut self.layers.heat, "distortion");
        if self.layers != before {
            self.touch();
        }
        ui.separator();
        let mut on = self.cut.on;
        if ui.checkbox(&mut on, "cut plane").changed() {
            self.set_cut(on);
        }
        if self.cut.on {
            let before = self.cut;
            ui.horizontal(|ui| {
                for (normal, name) in [(DVec3::X, "x"), (DVec3::Y, "y"), (DVec3::Z, "z")] {
                    ui.radio_value(&mut self.cut.normal, normal, name);
                }
                if ui
                    .button("facing me")
                    .on_hover_text(
                        "turn the plane to face the camera, through the middle of the scene",
                    )
                    .clicked()
                {
                    self.cut_facing_view();
                }
            });
            ui.add(egui::Slider::new(&mut self.cut.at, 0.0..=1.0).text("position"));
            if self.cut != before {
                self.touch();
            }
        }
    }

    fn scene_panel(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.radio_value(&mut self.mode, Mode::Camera, "Camera")
                .on_hover_text("drag: turn · right/middle drag: pan · wheel: zoom");
            ui.radio_value(&mut self.mode, Mode::Texture, "Texture")
                .on_hover_text(
                    "drag: move · shift-drag: turn · wheel: scale the selected facet's texture",
                );
            if ui
                .button("Reset view")
                .on_hover_text("back to the scene's first camera (key: Home)")
                .clicked()
                || ui.input(|i| i.key_pressed(egui::Key::Home))
            {
                self.reset_view();
            }
            if self.cut.on {
                ui.label("ctrl-drag: move the cut plane");
            }
        });
        let avail = ui.available_size();
        let ppp = ui.ctx().pixels_per_point();
        let size = [
            (avail.x * ppp).max(1.0) as u32,
            (avail.y * ppp).max(1.0) as u32,
        ];
        let Some(id) = self.draw_scene(size, self.interacting) else {
            return;
        };
        let was_interacting = std::mem::take(&mut self.interacting);
        let response = ui.add(egui::Image::new((id, avail)).sense(egui::Sense::click_and_drag()));
        self.view_rect = Some(response.rect);
        let (shift, ctrl) = ui.input(|i| (i.modifiers.shift, i.modifiers.command));
        let delta = response.drag_delta();
        let d = (delta.x as f64, delta.y as f64);
        let height = avail.y as f64;
        if response.dragged() && delta != egui::Vec2::ZERO {
            if ctrl && self.cut.on {
                let (n, _) = self.cut_plane().unwrap_or((DVec3::X, 0.0));
                let (right, up) = self.camera.right_up();
                let along = (right * d.0 - up * d.1).dot(n) / height;
                self.cut.at = (self.cut.at + along).clamp(0.0, 1.0);
            } else if self.mode == Mode::Texture
                && response.dragged_by(egui::PointerButton::Primary)
            {
                let k = self.camera.units_per_pixel(height);
                if shift {
                    let turn = dial_turn(
                        response.rect.center(),
                        response.interact_pointer_pos(),
                        delta,
                    );
                    self.edit_texture(|s| s.rotation += turn);
                } else {
                    self.edit_texture(|s| {
                        s.offset[0] -= d.0 * k / s.tile_size;
                        s.offset[1] += d.1 * k / s.tile_size;
                    });
                }
            } else if response.dragged_by(egui::PointerButton::Primary) {
                self.camera.orbit(d.0 * 0.01, d.1 * 0.01);
            } else {
                self.camera.pan(d.0, d.1, height);
            }
            self.touch();
            self.interacting = true;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y) as f64;
            if scroll != 0.0 {
                // About 15% per wheel notch (80 points on X11).
                let factor = (-scroll * WHEEL_RATE).exp();
                if self.mode == Mode::Texture {
                    // As the camera's zoom: the wheel forward makes the
                    // texture look bigger.
                    self.edit_texture(|s| s.tile_size /= factor);
                } else {
                    self.camera.zoom(factor);
                }
                self.touch();
                self.interacting = true;
            }
        }
        if was_interacting && !self.interacting {
            // The mouse stopped: draw the full picture next frame.
            ui.ctx().request_repaint();
        }
    }

    /// Count frames for --screenshot and --frames; take the screenshot
    /// once loading is done and the frames have passed.
    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let now = Instant::now();
        if let Some(last) = self.last_frame
            && !self.busy()
        {
            self.frame_times.push((now - last).as_secs_f64());
        }
        self.last_frame = Some(now);
        if let Some(done) = self
            .screenshot_result
            .lock()
            .expect("not poisoned")
            .as_ref()
        {
            let _ = done;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        let Some(left) = self.frames_left else { return };
        ctx.request_repaint();
        if self.busy() {
            self.frame_times.clear();
            return;
        }
        if self.opts.drag && left > 1 {
            self.edit_texture(|s| s.offset[0] += 0.002);
            self.interacting = true;
        }
        // Every frame drawn anew, so frame times are those of real frames.
        self.touch();
        if left > 1 {
            self.frames_left = Some(left - 1);
        } else if left == 1 {
            self.frames_left = Some(0);
            let path = self.opts.screenshot.clone().expect("set with frames_left");
            let slot = self.screenshot_result.clone();
            ctx.request_screenshot(move |img| {
                let rgba: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
                let r = image::RgbaImage::from_raw(img.size[0] as u32, img.size[1] as u32, rgba)
                    .ok_or_else(|| Error::invalid("the screenshot has the wrong size"))
                    .and_then(|i| {
                        crate::atomic::write_png(&path, &image::DynamicImage::ImageRgba8(i))
                    });
                *slot.lock().expect("not poisoned") = Some(r);
            });
        }
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        // A GPU error (the device's, a validation or memory one) is shown
        // at the top instead of ending the program.
        if let Err(e) = self.gpu.take_error() {
            self.error(e);
        }
        self.poll_jobs();
        self.update_section();
        self.screenshot_step(&ctx);
        if let Some(dialog) = &mut self.dialog {
            match dialog.show(&ctx) {
                Outcome::Pending => {}
                Outcome::Cancelled => self.dialog = None,
                Outcome::Chosen(path) => {
                    let purpose = dialog.purpose;
                    self.dialog = None;
                    match purpose {
                        Purpose::Open => self.open(path),
                        Purpose::Save => self.save(path),
                    }
                }
            }
        }
        egui::Panel::top("top").show(ui, |ui| self.top_bar(ui));
        egui::Panel::left("side")
            .default_size(260.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        egui::CentralPanel::default().show(ui, |ui| self.scene_panel(ui));
        if self.busy() {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
    }
}

/// Keep a texture transform the mouse made readable in a saved scene and
/// within one period, as the sliders show it: offsets wrap into [-1, 1)
/// texture widths (the tissue repeats every width and the mirrored
/// overlay every two, so nothing moves), rotation into (-180, 180]
/// degrees; values are rounded far below what shows (1e-4 of a width,
/// 1e-3 degree, 5 significant digits of tile size).
fn tidy(s: &mut crate::scene::file::FacetSettings) {
    for o in &mut s.offset {
        let wrapped = round_to((*o + 1.0).rem_euclid(2.0) - 1.0, 4);
        *o = if wrapped >= 1.0 {
            wrapped - 2.0
        } else {
            wrapped
        };
    }
    s.rotation = round_to(180.0 - (180.0 - s.rotation).rem_euclid(360.0), 3);
    let tile = s.tile_size.max(1e-9);
    let decimals = 4 - tile.log10().floor() as i32;
    s.tile_size = round_to(tile, decimals).max(10f64.powi(-decimals));
}

/// `x` rounded to `decimals` decimal places (negative: to tens, hundreds
/// ...); dividing by the exact power of ten gives the double nearest the
/// decimal, so it prints short.
fn round_to(x: f64, decimals: i32) -> f64 {
    if decimals >= 0 {
        let p = 10f64.powi(decimals);
        (x * p).round() / p
    } else {
        let p = 10f64.powi(-decimals);
        (x / p).round() * p
    }
}

/// Wheel zoom and texture scale per point of scroll.
const WHEEL_RATE: f64 = 0.002;

/// Degrees a shift-drag turns the texture: the angle the pointer sweeps
/// about the view's centre, like turning a dial, so any direction of
/// drag turns it; near the centre, where that angle jumps, the
/// horizontal motion instead.
fn dial_turn(centre: egui::Pos2, pointer: Option<egui::Pos2>, delta: egui::Vec2) -> f64 {
    let Some(now) = pointer else {
        return delta.x as f64 * 0.5;
    };
    let (a, b) = (now - delta - centre, now - centre);
    if a.length() < 40.0 || b.length() < 40.0 {
        return delta.x as f64 * 0.5;
    }
    let swept = (a.x * b.y - a.y * b.x).atan2(a.dot(b)) as f64;
    -swept.to_degrees()
}

/// Every tissue, with a 64-pixel thumbnail of its built texture, layers
/// or overlay (its photograph while not yet built).
fn thumbnails(database: &std::path::Path) -> Result<Thumbnails> {
    use crate::db::Output;
    let db = crate::db::Database::open(database)?;
    Ok(db
        .tissues
        .iter()
        .map(|t| {
            let output = [Output::Colour, Output::Layers, Output::Overlay]
                .into_iter()
                .find(|o| t.outputs.contains(o))
                .unwrap_or(Output::Colour);
            let built = db.output_path(&t.id, output);
            let path = if built.exists() {
                built
            } else {
                db.root.join(&t.source)
            };
            let thumbnail = crate::synth::exemplar::read_image(&path).ok().map(|i| {
                let small = i.thumbnail(64, 64).to_rgba8();
                egui::ColorImage::from_rgba_unmultiplied(
                    [small.width() as usize, small.height() as usize],
                    small.as_raw(),
                )
            });
            (t.clone(), thumbnail)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::file::FacetSettings;
    use crate::unwrap::seamster::SeamOptions;

    fn settings(tile_size: f64, rotation: f64, offset: [f64; 2]) -> FacetSettings {
        FacetSettings {
            name: "f".into(),
            texture: "t".into(),
            tile_size,
            rotation,
            offset,
            bump: 0.0,
            overlay: None,
            overlay_opacity: 0.0,
            overlay_tile_size: 1.0,
            overlap: 0.0,
            max_stretch: SeamOptions::default().max_stretch,
            max_conformal: SeamOptions::default().max_conformal,
            origin: Default::default(),
        }
    }

    #[test]
    fn a_dragged_transform_is_kept_within_one_period_and_short() {
        let mut s = settings(4.950267134449128, 190.0004, [3.18321148083675, -1.2]);
        tidy(&mut s);
        assert_eq!(s.tile_size, 4.9503);
        assert_eq!(s.rotation, -170.0);
        // 3.1832 and -1.2 texture widths, two-width period: 1.1832 is -0.8168.
        assert_eq!(s.offset, [-0.8168, 0.8]);
        assert_eq!(format!("{:?}", s.offset), "[-0.8168, 0.8]");
        let mut s = settings(0.000123456, -180.0, [0.99999, 1.0]);
        tidy(&mut s);
        assert_eq!((s.tile_size, s.rotation), (0.00012346, 180.0));
        assert_eq!(s.offset, [-1.0, -1.0]);
    }
}
