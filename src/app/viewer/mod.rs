//! The viewer window: panels on the left (file, facets, tissues, the
//! selected facet's texture, layers, cut plane), the scene in the middle,
//! drawn by `crate::render` into a texture egui shows. Everything slow
//! runs as a `Job`; the UI only starts jobs, takes their results, and
//! shows progress and messages.
//!
//! This file holds the viewer's state and its frame; each room of the
//! window is a file of its own, an `impl Viewer` block on that state:
//! `top_bar`, `side_panel` (facets), `shelf` (tissues), `texture`,
//! `cut_plane`, `scene_view` (the picture and the mouse) and
//! `screenshot`.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use eframe::{egui, egui_wgpu};
use glam::DVec3;

mod carve;
mod cut_plane;
mod scene_view;
mod screenshot;
mod shelf;
mod side_panel;
mod texture;
mod top_bar;

pub use carve::CarveTool;
pub use cut_plane::CutPlane;

use super::document::Document;
use super::file_dialog::{FileDialog, Outcome, Purpose};
use super::jobs::{Job, Running};
use super::region_dialog::{self, RegionDialog};
use crate::db::Shelf;
use crate::error::{Error, Result};
use crate::render::{Filtering, Gpu, GpuScene, Layers, OrbitCamera, Renderer};
use crate::scene::build::{BakedScene, Tissues};
use crate::scene::draw::DrawList;
use crate::scene::file::Segmentation;
use crate::segment::contents::Contents;
use crate::solid::Placement;
use cut_plane::Interiors;
use scene_view::SceneTarget;
use shelf::{Thumbnails, TissueEntry, thumbnails};

/// How the viewer starts.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// A scene (.toml), mesh or segmentation to open.
    pub open: Option<PathBuf>,
    /// When `open` is a segmentation: the region to mesh (None: the
    /// viewer asks) and the face budget (None: the scene's default).
    pub region: Option<crate::segment::Choice>,
    pub faces: Option<usize>,
    /// Save a screenshot of the window after `frames` frames (once
    /// loading and unwrapping are done), then close.
    pub screenshot: Option<PathBuf>,
    pub frames: usize,
    /// Drag the selected facet's texture a little every frame (to time
    /// the drag path).
    pub drag: bool,
    /// Before the screenshot: look at the organ from outside, turn to the
    /// Carve tool and carve a pit under the view's centre, a step a frame.
    pub carve: bool,
}

/// What the mouse does in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Drag turns, right or middle drag pans, the wheel zooms.
    Camera,
    /// Drag moves the selected facet's texture, shift-drag turns it, the
    /// wheel scales it.
    Texture,
    /// Drag over the organ removes the tets under a sphere (`carve`).
    Carve,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    pub text: String,
    pub error: bool,
}

#[derive(Default)]
struct Jobs {
    open: Option<Job<Document>>,
    /// Listing a segmentation's regions, to ask which one to mesh.
    contents: Option<Job<(PathBuf, Contents)>>,
    unwrap: Option<Job<BakedScene>>,
    tissues: Option<Job<Tissues>>,
    thumbnails: Option<Job<Thumbnails>>,
    block: Option<Job<Interiors>>,
    bake: Option<Job<PathBuf>>,
}

impl Jobs {
    /// The jobs the status bar shows (thumbnails load unannounced).
    fn shown(&self) -> Vec<&dyn Running> {
        let jobs: [Option<&dyn Running>; 6] = [
            self.open.as_ref().map(|j| j as &dyn Running),
            self.contents.as_ref().map(|j| j as &dyn Running),
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
    lst: Vec<Option<std::sync::Arc<crate::solid::lst::LstModel>>>,
    /// Where the interior block was placed when it went to the GPU.
    block_placement: Option<Placement>,
    /// That block on the CPU, with its placement (the carving colours
    /// from it).
    interior_block: Option<(crate::synth::volume::Volume, Placement)>,
    /// The Carve tool's state (`carve`).
    pub carve: CarveTool,
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
    /// Asking which region of a segmentation to mesh.
    region_dialog: Option<RegionDialog>,
    jobs: Jobs,
    /// Bumped by every change that alters the picture; a target whose
    /// picture is of an older generation is drawn again.
    generation: u64,
    opts: Options,
    frames_left: Option<usize>,
    /// `--carve`: the scripted carving has begun.
    carve_script: bool,
    screenshot_result: ScreenshotSlot,
    pub frame_times: Vec<f64>,
    last_frame: Option<Instant>,
    ctx: egui::Context,
}

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
        let renderer = Renderer::new(&gpu.device, Filtering::for_frames(&gpu));
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
            interior_block: None,
            carve: CarveTool::default(),
            view_rect: None,
            cut_made: None,
            message: None,
            tissues: Vec::new(),
            shelf: Shelf::Surface,
            dialog: None,
            region_dialog: None,
            jobs: Jobs::default(),
            generation: 0,
            frames_left: opts.screenshot.as_ref().map(|_| opts.frames.max(1)),
            carve_script: false,
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
        !self.jobs.shown().is_empty() || self.jobs.thumbnails.is_some() || self.carve.busy()
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
    /// A segmentation is listed first, and the user asked which region to
    /// mesh (unless the viewer was started with one).
    pub fn open(&mut self, path: PathBuf) {
        if crate::segment::contents::is_segmentation(&path) {
            if let Some(choice) = self.opts.region.take() {
                let mut seg = Segmentation::of(path, &choice);
                seg.faces = self.opts.faces.unwrap_or(seg.faces);
                self.open_segmentation(seg);
                return;
            }
            let what = format!("reading {}", path.display());
            self.jobs.contents = Some(Job::spawn(what, self.wake(), move |_| {
                let contents = crate::segment::contents::contents(&path)?;
                Ok((path, contents))
            }));
            return;
        }
        let what = format!("opening {}", path.display());
        self.jobs.open = Some(Job::spawn(what, self.wake(), move |_| {
            Document::open(&path)
        }));
    }

    /// Start meshing a region of a segmentation as a bare mesh's scene.
    pub fn open_segmentation(&mut self, segmentation: Segmentation) {
        let what = format!("meshing {}", segmentation.file.display());
        self.jobs.open = Some(Job::spawn(what, self.wake(), move |p| {
            Document::of_segmentation(segmentation, p)
        }));
    }

    /// The region dialog, while it asks.
    pub fn region_dialog(&mut self) -> Option<&mut RegionDialog> {
        self.region_dialog.as_mut()
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
        if let Some(r) = self.jobs.contents.as_mut().and_then(Job::poll) {
            self.jobs.contents = None;
            match r {
                Ok((path, contents)) => {
                    self.region_dialog = Some(RegionDialog::new(path, contents, self.opts.faces))
                }
                Err(e) => self.error(e),
            }
        }
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
                    self.interior_block = None;
                    self.carve = CarveTool::default();
                    if self.mode == Mode::Carve {
                        self.mode = Mode::Camera;
                    }
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

    /// The picture changed: every target must be drawn again.
    fn touch(&mut self) {
        self.generation += 1;
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
        self.poll_carving();
        if self.mode == Mode::Carve {
            self.ensure_carving();
        }
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
                        Purpose::Save => self.save_as(path),
                    }
                }
            }
        }
        if let Some(dialog) = &mut self.region_dialog {
            match dialog.show(&ctx) {
                region_dialog::Outcome::Pending => {}
                region_dialog::Outcome::Cancelled => self.region_dialog = None,
                region_dialog::Outcome::Chosen(segmentation) => {
                    self.region_dialog = None;
                    self.open_segmentation(segmentation);
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
