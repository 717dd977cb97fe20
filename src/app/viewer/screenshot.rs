//! `--screenshot OUT.png --frames N`: count frames once loading is done,
//! time them, save the window and close; with `--drag` a texture is
//! dragged meanwhile, with `--carve` the organ carved.

use std::time::Instant;

use eframe::egui;

use super::Viewer;
use crate::error::Error;

impl Viewer {
    /// Count frames for --screenshot and --frames; take the screenshot
    /// once loading is done and the frames have passed.
    pub(super) fn screenshot_step(&mut self, ctx: &egui::Context) {
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
        // Outside the organ, the Carve tool on: its interior and tets are
        // made over the next frames (busy meanwhile). Should that fail, the
        // message says why and the screenshot shows it.
        if self.opts.carve && !self.carve.ready() && !self.carve_script {
            self.carve_script = true;
            if let Some(doc) = &self.doc
                && let Some((lo, hi)) = doc.bounds()
            {
                // Turned a little and nearer, so the pit's walls show.
                self.camera = crate::render::OrbitCamera::fit(lo, hi);
                self.camera.orbit(0.5, 0.35);
                self.camera.zoom(0.6);
            }
            self.mode = super::Mode::Carve;
            self.frame_times.clear();
            return;
        }
        if self.opts.drag && left > 1 {
            self.edit_texture(|s| s.offset[0] += 0.002);
            self.interacting = true;
        }
        if self.opts.carve && self.carve.ready() && left > 1 {
            // A bowl under the view's centre: the sphere spirals out from
            // it and back, a step each frame, deeper each round.
            let a = left as f64 * 0.7;
            let r = 0.09 * ((left % 24) as f64 / 12.0 - 1.0).abs();
            let aspect = self
                .view_rect
                .map_or(1.6, |r| (r.width() / r.height().max(1.0)) as f64);
            self.carve_at(r * a.cos(), r * a.sin(), aspect);
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
