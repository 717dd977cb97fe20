//! The tissue shelf: database entries by kind (Surface, Interior, Overlay)
//! with thumbnails, loaded by a background job; a click gives the selected
//! facet its tissue, or lays an overlay on it.

use eframe::egui;

use super::{Job, Viewer};
use crate::db::Shelf;
use crate::error::Result;
use crate::scene::build::ensure_tissues;

/// A database entry on the tissue shelf, with its thumbnail.
pub(super) struct TissueEntry {
    pub(super) tissue: crate::db::Tissue,
    pub(super) thumbnail: Option<egui::TextureHandle>,
}

/// Every entry and its thumbnail's pixels, as a background job reads them.
pub(super) type Thumbnails = Vec<(crate::db::Tissue, Option<egui::ColorImage>)>;

impl Viewer {
    /// The tissue shelf: one kind at a time, thumbnails with credit lines; a click gives the selected facet its tissue or overlay.
    pub(super) fn shelf_panel(&mut self, ui: &mut egui::Ui) {
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
    pub(super) fn rebuild_tissues(&mut self) {
        let Some(doc) = &self.doc else { return };
        let spec = doc.spec.clone();
        self.jobs.tissues = Some(Job::spawn("tissue textures", self.wake(), move |p| {
            let db = crate::db::Database::open(&spec.database)?;
            ensure_tissues(&spec, &db, p)
        }));
    }
}

/// Every tissue, with a 64-pixel thumbnail of its built texture, layers
/// or overlay (its photograph while not yet built).
pub(super) fn thumbnails(database: &std::path::Path) -> Result<Thumbnails> {
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
