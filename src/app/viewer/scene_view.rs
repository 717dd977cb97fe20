//! The scene in the middle: drawn offscreen by `crate::render` into a
//! texture egui shows (at half resolution while the mouse moves it), and
//! the mouse's modes over it (camera, texture, cut plane, carving).

use eframe::egui;
use glam::DVec3;

use super::texture::dial_turn;
use super::{Mode, Viewer};
use crate::error::{Error, Result};
use crate::render::{Offscreen, View};

/// Wheel zoom and texture scale per point of scroll.
const WHEEL_RATE: f64 = 0.002;

/// Pixels of the interactive target per pixel of the full one, along
/// each axis. On a software rasteriser (llvmpipe) a drag frame of the
/// default scene costs about 146 ms at full resolution and 100 ms at half;
/// the full picture follows one frame after the mouse stops.
const INTERACTIVE_SCALE: u32 = 2;

/// An offscreen picture of the scene, registered with egui.
pub(super) struct SceneTarget {
    pub(super) offscreen: Offscreen,
    pub(super) id: egui::TextureId,
    /// The generation its picture shows.
    pub(super) drawn: Option<u64>,
}

impl Viewer {
    /// Draw the scene for egui into a texture `size` pixels, or, while
    /// the user moves the view (`coarse`), a texture
    /// `INTERACTIVE_SCALE` times smaller that egui scales up.
    pub(super) fn draw_scene(&mut self, size: [u32; 2], coarse: bool) -> Option<egui::TextureId> {
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

    pub(super) fn scene_panel(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.radio_value(&mut self.mode, Mode::Camera, "Camera")
                .on_hover_text("drag: turn · right/middle drag: pan · wheel: zoom");
            ui.radio_value(&mut self.mode, Mode::Texture, "Texture")
                .on_hover_text(
                    "drag: move · shift-drag: turn · wheel: scale the selected facet's texture",
                );
            ui.radio_value(&mut self.mode, Mode::Carve, "Carve").on_hover_text(
                "drag over the organ: a sphere (radius in the side panel) removes the tets under it, \
                 as a simulator's burr does · right/middle drag: pan · wheel: zoom",
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
        let carving = self.mode == Mode::Carve && !(ctrl && self.cut.on);
        if carving
            && (response.dragged_by(egui::PointerButton::Primary) || response.clicked())
            && let Some(pos) = response.interact_pointer_pos()
        {
            // Each frame of the drag, the sphere under the pointer.
            let r = response.rect;
            let x = ((pos.x - r.left()) / r.width()) as f64 * 2.0 - 1.0;
            let y = 1.0 - ((pos.y - r.top()) / r.height()) as f64 * 2.0;
            self.carve_at(x, y, (r.width() / r.height().max(1.0)) as f64);
        }
        if response.drag_stopped() || response.clicked() {
            self.carve.release();
        }
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
            } else if carving && response.dragged_by(egui::PointerButton::Primary) {
                // Carved above.
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

    /// The last frame drawn, read back (tests).
    pub fn read_scene(&self) -> Result<image::RgbaImage> {
        let target = self.targets[self.shown]
            .as_ref()
            .ok_or_else(|| Error::invalid("nothing drawn yet"))?;
        target.offscreen.read(&self.gpu.device, &self.gpu.queue)
    }

    /// Triangles of the cut surface drawn.
    /// Where the 3D view was last drawn.
    pub fn view_rect(&self) -> Option<egui::Rect> {
        self.view_rect
    }
}
