//! The side panel: the scene's facets and Unwrap, then the rooms below
//! (shelf, texture, layers, cut plane, carving).

use eframe::egui;

use super::Viewer;

impl Viewer {
    pub(super) fn side_panel(&mut self, ui: &mut egui::Ui) {
        let Some(doc) = &self.doc else {
            ui.label("Open a scene or a mesh (Open…).");
            return;
        };
        ui.heading(&doc.spec.name);
        // What meshing a segmentation found, as `organtex mesh` says it.
        for (node, report) in doc.spec.nodes.iter().zip(&doc.segmented) {
            if let Some(report) = report {
                ui.small(format!("{}: {}", node.name, report.summary()));
            }
        }
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
        self.shelf_panel(ui);
        self.texture_panel(ui);
        ui.separator();
        ui.label("Show");
        let before = self.layers;
        // Two a row, so the cut plane and carving below stay in view.
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.layers.seam_blend, "seam blend");
            ui.checkbox(&mut self.layers.bump, "bump");
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.layers.overlay, "overlay");
            ui.checkbox(&mut self.layers.wireframe, "wireframe");
        });
        ui.horizontal(|ui| {
            ui.checkbox(&mut self.layers.seams, "seams");
            ui.checkbox(&mut self.layers.heat, "distortion");
        });
        if self.layers != before {
            self.touch();
        }
        self.cut_plane_panel(ui);
        self.carve_panel(ui);
    }
}
