//! `organtex unwrap IN -o OUT.obj`: Seamster cut + ABF++ flattening.

use std::path::{Path, PathBuf};

use glam::DVec3;
use organtex::mesh::repair::make_manifold;
use organtex::mesh::{Topology, io};
use organtex::unwrap::seamster::SeamOptions;
use organtex::unwrap::visibility::Viewpoints;
use organtex::unwrap::{UnwrapOptions, debug, unwrap};
use organtex::{Error, Result};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// Mesh to unwrap (.obj, .ply or .stl).
    input: PathBuf,
    /// Output .obj with the new uvs (uv units are mesh units: uv area equals
    /// surface area).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the report (charts, distortion figures, timings) as JSON.
    #[arg(long, value_name = "JSON")]
    report: Option<PathBuf>,
    /// Also write pictures here: visibility.png (the mesh coloured by how
    /// visible it is, seams black, terminals yellow), checker.png (the mesh
    /// textured with a checker through its uvs), uv_layout.png.
    #[arg(long, value_name = "DIR")]
    debug_dir: Option<PathBuf>,
    /// Orthographic views, spread over a sphere around the mesh, from which
    /// seam visibility is counted.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..=1024))]
    views: u32,
    /// Count visibility from these camera positions instead (an endoscope
    /// inside a cavity): a text file with one "x y z" per line, each camera
    /// looking all around.
    #[arg(long, value_name = "FILE")]
    cameras: Option<PathBuf>,
    /// Refine the seams until the mean |log area ratio| of the flattening is
    /// at most this (0 would be no area distortion at all).
    #[arg(long, default_value_t = SeamOptions::default().max_stretch, value_name = "X",
          allow_negative_numbers = true)]
    max_stretch: f64,
    /// Refine the seams until the flattening's mean ratio of largest to
    /// smallest stretch is at most this too (1 would be perfectly
    /// conformal).
    #[arg(long, default_value_t = SeamOptions::default().max_conformal, value_name = "X",
          allow_negative_numbers = true)]
    max_conformal: f64,
    /// Split non-manifold edges and vertices first instead of refusing the
    /// mesh.
    #[arg(long)]
    repair: bool,
    /// Split any chart whose layout overlaps itself (a fold of the boundary
    /// over the chart) into charts that do not, as texture atlases and
    /// painting need. Costs seams; tiled textures do not need it.
    #[arg(long)]
    split_overlaps: bool,
}

pub fn run(args: Args) -> Result<()> {
    if !(args.max_stretch > 0.0 && args.max_stretch.is_finite()) {
        return Err(Error::invalid(format!(
            "--max-stretch must be a positive number, not {}",
            args.max_stretch
        )));
    }
    if !(args.max_conformal >= 1.0 && args.max_conformal.is_finite()) {
        return Err(Error::invalid(format!(
            "--max-conformal must be a number of at least 1, not {}",
            args.max_conformal
        )));
    }
    let mut mesh = io::read(&args.input)?;
    if args.repair {
        mesh = make_manifold(&mesh).0;
    } else {
        Topology::build(&mesh).map_err(|e| e.in_file(&args.input))?;
    }
    let mut opts = UnwrapOptions::default();
    opts.seams.max_stretch = args.max_stretch;
    opts.seams.max_conformal = args.max_conformal;
    opts.split_overlaps = args.split_overlaps;
    opts.viewpoints = match &args.cameras {
        Some(file) => Viewpoints::Cameras(read_cameras(file)?),
        None => Viewpoints::Orbit {
            views: args.views as usize,
        },
    };
    let bars = Bars::new();
    let result = unwrap(&mesh, &opts, &bars).map_err(|e| e.in_file(&args.input))?;
    bars.finish();

    io::write_obj(&args.output, &result.mesh, None)?;
    // Plain numbers and string keys: serialising cannot fail.
    let report = serde_json::to_string_pretty(&result.report).expect("the report serialises");
    if let Some(path) = &args.report {
        organtex::atomic::write_file(path, |w| writeln!(w, "{report}"))?;
    }
    if let Some(dir) = &args.debug_dir {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        save(
            &dir.join("visibility.png"),
            &debug::visibility_image(&result, 512),
        )?;
        if let Some(img) = debug::checker_image(&result.mesh, 512) {
            save(&dir.join("checker.png"), &img)?;
        }
        if let Some(img) = debug::layout_image(&result.mesh, 1024) {
            save(&dir.join("uv_layout.png"), &img)?;
        }
    }
    let missed = result
        .report
        .pieces
        .iter()
        .filter(|p| !p.within_bounds)
        .count();
    if missed > 0 {
        eprintln!(
            "note: {missed} of {} pieces miss the bounds (--max-stretch {}, --max-conformal {}, no flips) after the refinement they were given; the report's within_bounds says which",
            result.report.pieces.len(),
            args.max_stretch,
            args.max_conformal
        );
    }
    let m = &result.report.metrics;
    println!(
        "{}: {} charts, {} flips, conf_mean {:.4}, area_log {:.3}, seam_ratio {:.2}, seam_vis {:.2}, {:.2} s",
        args.output.display(),
        m.charts,
        m.flips,
        m.conf_mean,
        m.area_log,
        m.seam_ratio,
        m.seam_vis,
        result.report.timings.total_s
    );
    Ok(())
}

/// Camera positions: one "x y z" per line; blank lines and # comments
/// skipped.
fn read_cameras(path: &Path) -> Result<Vec<DVec3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut cameras = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let numbers: Vec<f64> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|w| !w.is_empty())
            .map(|w| w.parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                Error::at_line(path, n + 1, format!("'{line}' is not three finite numbers"))
            })?;
        match numbers.as_slice() {
            [x, y, z] => cameras.push(DVec3::new(*x, *y, *z)),
            _ => {
                return Err(Error::at_line(
                    path,
                    n + 1,
                    format!(
                        "expected a camera position 'x y z', found {} numbers",
                        numbers.len()
                    ),
                ));
            }
        }
    }
    if cameras.is_empty() {
        return Err(Error::format(path, "no camera positions"));
    }
    Ok(cameras)
}

fn save(path: &Path, img: &image::RgbImage) -> Result<()> {
    organtex::atomic::write_png(path, &image::DynamicImage::ImageRgb8(img.clone()))
}
