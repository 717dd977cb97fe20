//! A small file chooser inside the window. Written here rather than taken
//! from a crate: egui-file-dialog trails egui's releases (0.15 needs egui
//! 0.36), and rfd's native dialogs need a desktop portal or GTK that Xvfb
//! sessions and the test harness lack; this one is drawn by egui, so the
//! kittest harness can drive it like the rest of the viewer.

use std::path::{Path, PathBuf};

use eframe::egui;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    Open,
    Save,
}

pub struct FileDialog {
    pub purpose: Purpose,
    dir: PathBuf,
    /// The file name or path typed or clicked.
    pub name: String,
    entries: Vec<(String, bool)>,
    /// Save: the existing file the user chose, until they confirm
    /// replacing it.
    replacing: Option<PathBuf>,
}

/// What the user did this frame.
pub enum Outcome {
    Pending,
    Cancelled,
    Chosen(PathBuf),
}

fn listing(dir: &Path, purpose: Purpose) -> Vec<(String, bool)> {
    let mut entries: Vec<(String, bool)> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    let is_dir = e.file_type().ok()?.is_dir();
                    let ext = Path::new(&name)
                        .extension()
                        .map(|x| x.to_string_lossy().to_ascii_lowercase());
                    let wanted = match purpose {
                        Purpose::Open => {
                            ext.as_deref().is_some_and(|x| {
                                x == "toml" || crate::mesh::io::READABLE.contains(&x)
                            }) || crate::segment::contents::is_segmentation(Path::new(&name))
                        }
                        Purpose::Save => ext.as_deref() == Some("toml"),
                    };
                    (!name.starts_with('.') && (is_dir || wanted)).then_some((name, is_dir))
                })
                .collect()
        })
        .unwrap_or_default();
    entries.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    entries
}

impl FileDialog {
    pub fn new(purpose: Purpose, dir: PathBuf, name: String) -> FileDialog {
        FileDialog {
            purpose,
            entries: listing(&dir, purpose),
            dir,
            name,
            replacing: None,
        }
    }

    /// What choosing the typed or clicked name means: open it, or save to
    /// it once the user agreed to replace an existing file.
    fn choose(&mut self) -> Outcome {
        let path = self.dir.join(self.name.trim());
        if self.purpose == Purpose::Save && path.exists() {
            self.replacing = Some(path);
            Outcome::Pending
        } else {
            Outcome::Chosen(path)
        }
    }

    pub fn show(&mut self, ctx: &egui::Context) -> Outcome {
        let mut outcome = Outcome::Pending;
        let title = match self.purpose {
            Purpose::Open => "Open a scene, mesh or segmentation",
            Purpose::Save => "Save the scene",
        };
        let mut go_to: Option<PathBuf> = None;
        let (mut chosen, mut keep) = (false, false);
        egui::Window::new(title)
            .collapsible(false)
            .default_width(420.0)
            .show(ctx, |ui| {
                ui.label(self.dir.display().to_string());
                egui::ScrollArea::vertical()
                    .max_height(260.0)
                    .show(ui, |ui| {
                        if ui.selectable_label(false, "..").clicked() {
                            go_to = self.dir.parent().map(Path::to_path_buf);
                        }
                        for (name, is_dir) in &self.entries {
                            let label = if *is_dir {
                                format!("{name}/")
                            } else {
                                name.clone()
                            };
                            let r = ui.selectable_label(&self.name == name, label);
                            if r.clicked() {
                                if *is_dir {
                                    go_to = Some(self.dir.join(name));
                                } else {
                                    self.name = name.clone();
                                }
                            }
                            if r.double_clicked() && !is_dir {
                                self.name = name.clone();
                                chosen = true;
                            }
                        }
                    });
                if let Some(path) = &self.replacing {
                    let name = path.file_name().unwrap_or_default().to_string_lossy();
                    ui.label(format!("{name} already exists. Replace it?"));
                    ui.horizontal(|ui| {
                        if ui.button("Replace").clicked() {
                            outcome = Outcome::Chosen(path.clone());
                        }
                        if ui.button("Keep it").clicked() {
                            keep = true;
                        }
                    });
                    return;
                }
                ui.horizontal(|ui| {
                    let label = ui.label("File:");
                    let field = ui
                        .text_edit_singleline(&mut self.name)
                        .labelled_by(label.id);
                    // Enter in the field chooses, as in any file dialog.
                    chosen |= field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                });
                ui.horizontal(|ui| {
                    let verb = match self.purpose {
                        Purpose::Open => "Open",
                        Purpose::Save => "Save",
                    };
                    chosen |= ui.button(verb).clicked();
                    if ui.button("Cancel").clicked() {
                        outcome = Outcome::Cancelled;
                    }
                });
            });
        if keep {
            self.replacing = None;
        }
        if chosen && !self.name.trim().is_empty() {
            outcome = self.choose();
        }
        if let Some(dir) = go_to {
            self.entries = listing(&dir, self.purpose);
            self.dir = dir;
        }
        outcome
    }
}
