//! "Which region?": asked when the user opens a segmentation (a NIfTI
//! label or probability map, a NRRD label map, a Slicer `.seg.nrrd`).
//! It lists the file's segments or labels, largest first, or offers a
//! threshold over its range, with the face budget, pieces, voids and
//! thin handles as `organtex mesh` takes them; its answer is a scene's
//! `[node.mesh.segmentation]`.

use std::path::PathBuf;

use eframe::egui;

use crate::scene::file::Segmentation;
use crate::segment::Choice;
use crate::segment::contents::Contents;

pub struct RegionDialog {
    path: PathBuf,
    contents: Contents,
    /// The region chosen: one of `contents.regions`' choices, or a
    /// threshold.
    pub choice: Choice,
    /// The threshold offered, kept while a label is chosen.
    pub threshold: f64,
    pub faces: usize,
    pub all_components: bool,
    pub fill_voids: bool,
    /// Hold the voxel corners through the decimation.
    pub within_voxels: bool,
    /// Cut or plug handles thinner than `handle` mm.
    pub fix_handles: bool,
    pub handle: f64,
}

/// What the user did this frame.
pub enum Outcome {
    Pending,
    Cancelled,
    Chosen(Segmentation),
}

/// The face budgets offered: the scene's default is 20,000.
const FACES: std::ops::RangeInclusive<usize> = 1_000..=500_000;

impl RegionDialog {
    /// Asking about `path`, which holds `contents`; `faces`: the budget
    /// offered (None: a scene's default).
    pub fn new(path: PathBuf, contents: Contents, faces: Option<usize>) -> RegionDialog {
        let defaults = Segmentation::of(path.clone(), &contents.default_choice());
        RegionDialog {
            choice: contents.default_choice(),
            threshold: contents.threshold,
            faces: faces.unwrap_or(defaults.faces),
            all_components: defaults.all_components,
            fill_voids: defaults.fill_voids,
            within_voxels: defaults.within_voxels.is_some(),
            fix_handles: false,
            handle: 2.0,
            path,
            contents,
        }
    }

    /// The scene's segmentation entry for what is chosen now.
    pub fn chosen(&self) -> Segmentation {
        Segmentation {
            faces: self.faces,
            all_components: self.all_components,
            fill_voids: self.fill_voids,
            within_voxels: self.within_voxels.then_some(crate::segment::fit::TOLERANCE),
            max_handle: self.fix_handles.then_some(self.handle),
            ..Segmentation::of(self.path.clone(), &self.choice)
        }
    }

    pub fn show(&mut self, ctx: &egui::Context) -> Outcome {
        let mut outcome = Outcome::Pending;
        let name = self
            .path
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        egui::Window::new(format!("Mesh a region of {name}"))
            .collapsible(false)
            .default_width(380.0)
            .show(ctx, |ui| {
                let [x, y, z] = self.contents.size;
                ui.label(format!("{x} x {y} x {z} voxels"));
                if !self.contents.regions.is_empty() {
                    egui::ScrollArea::vertical()
                        .max_height(240.0)
                        .show(ui, |ui| {
                            for r in &self.contents.regions {
                                ui.radio_value(&mut self.choice, r.choice.clone(), &r.name);
                            }
                        });
                }
                let (lo, hi) = self.contents.range;
                ui.horizontal(|ui| {
                    let on = matches!(self.choice, Choice::Threshold(_));
                    let radio = ui
                        .radio(on, "voxels at or above")
                        .on_hover_text("a probability map at 0.5, or a grey volume");
                    if radio.clicked() {
                        self.choice = Choice::Threshold(self.threshold);
                    }
                    let speed = (hi as f64 - lo as f64).max(1e-6) / 200.0;
                    let drag = ui
                        .add(
                            egui::DragValue::new(&mut self.threshold)
                                .range(lo as f64..=hi as f64)
                                .speed(speed),
                        )
                        .labelled_by(radio.id);
                    if drag.changed() {
                        self.choice = Choice::Threshold(self.threshold);
                    }
                });
                ui.horizontal(|ui| {
                    let label = ui.label("faces at most");
                    ui.add(
                        egui::DragValue::new(&mut self.faces)
                            .range(FACES)
                            .speed(100.0),
                    )
                    .labelled_by(label.id)
                    .on_hover_text("quadric-error decimation to this many faces");
                });
                ui.checkbox(&mut self.all_components, "keep every piece")
                    .on_hover_text(
                        "default: the largest piece, by voxels; kept, a piece finer than a \
                         voxel is dropped all the same",
                    );
                ui.checkbox(&mut self.fill_voids, "fill enclosed voids")
                    .on_hover_text(
                        "default: each void is an inner shell of the surface, but for those \
                         finer than a voxel",
                    );
                ui.checkbox(&mut self.within_voxels, "keep thin crests")
                    .on_hover_text(
                        "hold every voxel corner within 0.9 voxel through the decimation: \
                         thin crests such as gyri kept, a rougher surface",
                    );
                ui.horizontal(|ui| {
                    let check = ui
                        .checkbox(&mut self.fix_handles, "remove handles thinner than")
                        .on_hover_text(
                            "cut thin bridges and plug narrow tunnels (e.g. across sulci); \
                             pieces and voids stay",
                        );
                    ui.add(
                        egui::DragValue::new(&mut self.handle)
                            .range(0.1..=50.0)
                            .speed(0.1)
                            .suffix(" mm"),
                    )
                    .labelled_by(check.id);
                });
                ui.horizontal(|ui| {
                    if ui.button("Mesh").clicked() {
                        outcome = Outcome::Chosen(self.chosen());
                    }
                    if ui.button("Cancel").clicked() {
                        outcome = Outcome::Cancelled;
                    }
                });
            });
        outcome
    }
}
