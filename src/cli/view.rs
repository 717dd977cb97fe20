//! `organtex view [SCENE|MESH] [--screenshot OUT.png] [--frames N] [--drag]
//! [--carve]`: the desktop viewer.

use std::path::PathBuf;

use organtex::Result;
use organtex::app::{self, Options};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml, opened and unwrapped at once) or a mesh (.obj,
    /// .ply, .stl; every facet gets the database's first tissue, and
    /// waits for Unwrap). Default: nothing open.
    path: Option<PathBuf>,
    /// Render, save a screenshot of the whole window as PNG once loading
    /// and unwrapping are done and --frames frames have been drawn, then
    /// close; prints the median frame time. For headless checks (under
    /// Xvfb: xvfb-run -a organtex view …).
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
    /// Frames to draw before the screenshot.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// With --screenshot: drag the first facet's texture a little every
    /// frame, so the frame time is that of a texture drag.
    #[arg(long, requires = "screenshot")]
    drag: bool,
    /// With --screenshot: look at the organ from outside, turn to the
    /// Carve tool and carve a pit under the view's centre a step a frame
    /// (the scene's interior and tets are made first); prints the steps'
    /// times.
    #[arg(long, requires = "screenshot")]
    carve: bool,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(shot) = &args.screenshot
        && !shot
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        return Err(organtex::Error::invalid(format!(
            "{}: the screenshot is written as PNG; give a .png name",
            shot.display()
        )));
    }
    if let Some(p) = &args.path
        && !p.exists()
    {
        return Err(organtex::Error::invalid(format!(
            "{}: no such file",
            p.display()
        )));
    }
    app::run(Options {
        open: args.path,
        screenshot: args.screenshot,
        frames: args.frames as usize,
        drag: args.drag,
        carve: args.carve,
    })
}
