//! The selected facet's texture: its transform (sliders, or dragged in
//! Texture mode), kept tidy for the saved scene, and its unwrap bound.

use eframe::egui;

use super::Viewer;

impl Viewer {
    /// The selected facet's texture transform and unwrap bound.
    pub(super) fn texture_panel(&mut self, ui: &mut egui::Ui) {
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
            self.colour_panel(ui, f, &s);
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
    }

    /// The facet's colour grading: hue, saturation, brightness, and a
    /// match onto another tissue's colours; the graded texture is made in
    /// the background (`rebuild_tissues`).
    fn colour_panel(
        &mut self,
        ui: &mut egui::Ui,
        f: (usize, usize),
        s: &crate::scene::file::FacetSettings,
    ) {
        let mut g = s.grading.clone();
        // A slider's value is kept as it moves; the texture is graded once
        // it is let go (each grading writes a texture into the database's
        // build folder).
        let (mut changed, mut regrade) = (false, false);
        // Folded by default: the side panel stays short enough for the
        // cut plane and carving controls below.
        egui::CollapsingHeader::new("Colour").show(ui, |ui| {
            for r in [
                ui.add(egui::Slider::new(&mut g.hue, -60.0..=60.0).text("hue °")),
                ui.add(egui::Slider::new(&mut g.saturation, 0.0..=2.0).text("saturation")),
                ui.add(egui::Slider::new(&mut g.brightness, 0.25..=2.0).text("brightness")),
            ] {
                changed |= r.changed();
                regrade |= r.drag_stopped() || (r.changed() && !r.dragged());
            }
            let colours: Vec<String> = self
                .tissues
                .iter()
                .filter(|e| e.tissue.outputs.contains(&crate::db::Output::Colour))
                .map(|e| e.tissue.id.clone())
                .collect();
            egui::ComboBox::from_label("match")
                .selected_text(g.matched.as_deref().unwrap_or("none"))
                .show_ui(ui, |ui| {
                    regrade |= ui.selectable_value(&mut g.matched, None, "none").changed();
                    for id in colours {
                        regrade |= ui
                            .selectable_value(&mut g.matched, Some(id.clone()), id)
                            .changed();
                    }
                })
                .response
                .on_hover_text(
                    "take on that tissue's colour statistics (mean and spread in CIELAB)",
                );
        });
        if (changed || regrade)
            && let Some(doc) = &mut self.doc
        {
            let mut now = s.clone();
            now.grading = g;
            doc.set_settings(f, now);
            if regrade && doc.baked.is_some() {
                self.rebuild_tissues();
            }
        }
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

/// Degrees a shift-drag turns the texture: the angle the pointer sweeps
/// about the view's centre, like turning a dial, so any direction of
/// drag turns it; near the centre, where that angle jumps, the
/// horizontal motion instead.
pub(super) fn dial_turn(centre: egui::Pos2, pointer: Option<egui::Pos2>, delta: egui::Vec2) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::file::FacetSettings;
    use crate::unwrap::seamster::SeamOptions;

    pub(super) fn settings(tile_size: f64, rotation: f64, offset: [f64; 2]) -> FacetSettings {
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
            grading: Default::default(),
            origin: Default::default(),
        }
    }

    #[test]
    pub(super) fn a_dragged_transform_is_kept_within_one_period_and_short() {
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
