//! `organtex view [SCENE|MESH|SEGMENTATION] [--label N | --segment NAME |
//! --threshold T] [--faces N] [--screenshot OUT.png] [--frames N] [--drag]
//! [--carve]`: the desktop viewer.

use std::path::PathBuf;

use organtex::Result;
use organtex::app::{self, Options};

#[derive(clap::Args)]
pub struct Args {
    /// A scene file (.toml, opened and unwrapped at once), a mesh (.obj,
    /// .ply, .stl) or a segmentation (.nii, .nii.gz, .nrrd, .seg.nrrd; the
    /// viewer lists its segments or labels and asks which to mesh, as
    /// `organtex mesh` does). A mesh or segmentation gets the database's
    /// first tissue on every facet and waits for Unwrap. Default: nothing
    /// open.
    path: Option<PathBuf>,
    /// With a segmentation: mesh this label at once instead of asking.
    #[arg(long, allow_negative_numbers = true, group = "region")]
    label: Option<i64>,
    /// With a Slicer segmentation: mesh this segment at once, by name.
    #[arg(long, value_name = "NAME", group = "region")]
    segment: Option<String>,
    /// With a segmentation: mesh the voxels at or above this value at once.
    #[arg(long, allow_negative_numbers = true, group = "region")]
    threshold: Option<f64>,
    /// With a segmentation: the face budget (default 20,000, as a scene's).
    #[arg(long, value_parser = clap::value_parser!(u64).range(4..=1_000_000_000))]
    faces: Option<u64>,
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
    let region = match (args.label, args.segment, args.threshold) {
        (Some(l), _, _) => Some(organtex::segment::Choice::Label(l)),
        (_, Some(name), _) => Some(organtex::segment::Choice::Segment(name)),
        (_, _, Some(t)) => Some(organtex::segment::Choice::Threshold(t)),
        _ => None,
    };
    let is_segmentation = args
        .path
        .as_deref()
        .is_some_and(organtex::segment::contents::is_segmentation);
    if (region.is_some() || args.faces.is_some()) && !is_segmentation {
        return Err(organtex::Error::invalid(
            "--label, --segment, --threshold and --faces choose what to mesh of a segmentation \
             (.nii, .nii.gz, .nrrd, .seg.nrrd); give one as the file to open",
        ));
    }
    app::run(Options {
        open: args.path,
        region,
        faces: args.faces.map(|f| f as usize),
        screenshot: args.screenshot,
        frames: args.frames as usize,
        drag: args.drag,
        carve: args.carve,
    })
}
