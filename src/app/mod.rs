//! The desktop viewer (`organtex view`): eframe + egui on wgpu, the scene
//! drawn by `crate::render`, the same renderer as the bake's preview.
//! Clinicians open a scene, a mesh or a segmentation (asked which region), pick tissues, unwrap, move the
//! texture by mouse and cut the organ to see its inside.

mod document;
mod file_dialog;
mod jobs;
mod region_dialog;
mod viewer;

pub use document::Document;
pub use viewer::{CutPlane, Message, Mode, Options, Viewer};

use eframe::egui;

use crate::error::{Error, Result};

/// What the window leaves for `run`: the screenshot's outcome and the
/// frame times.
type Outcome =
    std::sync::Arc<std::sync::Mutex<Option<(Option<Result<()>>, Vec<f64>, Option<String>)>>>;

/// Open the viewer window; returns when it closes. With a screenshot
/// asked for, the window closes by itself once it is saved, and the
/// frame times are printed.
pub fn run(opts: Options) -> Result<()> {
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        return Err(Error::invalid(
            "no display to open the viewer on (DISPLAY is not set); on a machine without one run it under Xvfb: xvfb-run -a organtex view …",
        ));
    }
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("organtex")
            .with_inner_size([1280.0, 800.0]),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    let slot: Outcome = Default::default();
    let out = slot.clone();
    let frames_wanted = opts.screenshot.is_some();
    let result = eframe::run_native(
        "organtex",
        native,
        Box::new(move |cc| {
            let viewer = Viewer::new(cc, opts)?;
            Ok(Box::new(Reporter { viewer, out }))
        }),
    );
    result.map_err(|e| Error::invalid(format!("the viewer failed: {e}")))?;
    let (shot, times, carving) =
        slot.lock()
            .expect("not poisoned")
            .take()
            .unwrap_or((None, Vec::new(), None));
    if frames_wanted {
        match shot {
            Some(r) => r?,
            None => {
                return Err(Error::invalid(
                    "the window closed before the screenshot was taken",
                ));
            }
        }
        if !times.is_empty() {
            let mut t = times;
            t.sort_by(f64::total_cmp);
            println!(
                "frames: {}, median frame time {:.2} ms",
                t.len(),
                t[t.len() / 2] * 1e3
            );
        }
        if let Some(line) = carving {
            println!("{line}");
        }
    }
    Ok(())
}

/// Hands the screenshot's outcome and the frame times back to `run` when
/// the window closes.
struct Reporter {
    viewer: Viewer,
    out: Outcome,
}

impl eframe::App for Reporter {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.viewer.ui(ui, frame);
        let shot = self
            .viewer
            .screenshot_slot()
            .lock()
            .expect("not poisoned")
            .take();
        if let Some(r) = shot {
            *self.out.lock().expect("not poisoned") = Some((
                Some(r),
                self.viewer.frame_times.clone(),
                self.viewer.carve.summary(),
            ));
            ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }
}
