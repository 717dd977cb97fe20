//! The top bar: Open, Save, Bake, the jobs' progress with Cancel, and the
//! last message.

use std::path::PathBuf;

use eframe::egui;

use super::{Job, Message, Viewer};
use crate::app::file_dialog::{FileDialog, Purpose};
use crate::error::Error;

impl Viewer {
    pub(super) fn top_bar(&mut self, ui: &mut egui::Ui) {
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
            ui.label("Lighting:");
            for l in crate::render::Lighting::ALL {
                let hint = match l {
                    crate::render::Lighting::Endoscope => {
                        "the scope's light: falls off with distance, wet highlights"
                    }
                    crate::render::Lighting::Even => "an even light, for judging the texture alone",
                };
                if ui
                    .selectable_value(&mut self.layers.lighting, l, l.name())
                    .on_hover_text(hint)
                    .changed()
                {
                    self.touch();
                }
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

    pub(super) fn save_as(&mut self, path: PathBuf) {
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
    pub(super) fn dialog_dir(&self) -> PathBuf {
        let here = std::env::current_dir().unwrap_or_default();
        self.doc
            .as_ref()
            .and_then(|d| d.spec.path.parent())
            .and_then(|p| std::fs::canonicalize(here.join(p)).ok())
            .unwrap_or(here)
    }
}
