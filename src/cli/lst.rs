//! `organtex lst MESH --exemplar B.nrrd --type 0|1a|1b|2a|2b [--strokes
//! S.toml] [--depth-outer FACET --depth-inner FACET] -o MODEL.lst
//! [--json]`: fill an organ with a lapped solid texture.

use std::path::PathBuf;
use std::time::Instant;

use glam::DVec3;
use organtex::mesh::io;
use organtex::solid::lst::{self, LstInterior, LstOptions, TextureType};
use organtex::synth::volume::Volume;
use organtex::tetra::{self, TetOptions};
use organtex::{Error, Result};
use serde::{Deserialize, Serialize};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// The organ's surface (.obj with groups for facets, .ply, .stl); its
    /// inside is filled with tetrahedra first (as `organtex tetra`).
    mesh: PathBuf,
    /// The solid exemplar: an RGB uint8 NRRD volume (for layered types,
    /// its y axis runs from the outer layer at y = 0 inwards).
    #[arg(long, value_name = "NRRD")]
    exemplar: PathBuf,
    /// Seed 000's texture type: 0 (isotropic), 1a (along strokes), 1b
    /// (layered by depth), 2a (depth and strokes), 2b (layered, along
    /// strokes).
    #[arg(long = "type", value_name = "TYPE", value_parser = parse_type)]
    kind: TextureType,
    /// Strokes for 1a, 2a, 2b: a TOML file of `[[stroke]] points =
    /// [[x, y, z], ...]` polylines inside the mesh along which the
    /// texture's first axis runs.
    #[arg(long, value_name = "TOML")]
    strokes: Option<PathBuf>,
    /// The facet at depth 0 (1b, 2a, 2b), e.g. the serosa.
    #[arg(long, value_name = "FACET", requires = "depth_inner")]
    depth_outer: Option<String>,
    /// The facet at depth 1, e.g. the cavity's wall.
    #[arg(long, value_name = "FACET", requires = "depth_outer")]
    depth_inner: Option<String>,
    /// Object units one patch spans (0, 1a, 2a). Default: a quarter of the
    /// bounding box diagonal.
    #[arg(long, value_parser = super::positive_length, allow_negative_numbers = true)]
    scale: Option<f64>,
    /// About this many tetrahedra (default: `organtex tetra`'s default
    /// resolution).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    cells: Option<u64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The model (.lst, with its tet mesh inside).
    #[arg(short, long)]
    output: PathBuf,
    /// Print the figures as JSON.
    #[arg(long)]
    json: bool,
}

fn parse_type(s: &str) -> std::result::Result<TextureType, String> {
    TextureType::parse(s).map_err(|e| e.to_string())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StrokeFile {
    stroke: Vec<Stroke>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Stroke {
    points: Vec<[f64; 3]>,
}

/// What the command prints.
#[derive(Serialize)]
struct Figures {
    file: PathBuf,
    output: PathBuf,
    kind: &'static str,
    tets: usize,
    patches: u32,
    layers: usize,
    layers_per_tet: f64,
    bytes: u64,
    bytes_per_tet: f64,
    alignment: lst::FillStats,
    tetra_seconds: f64,
    fill_seconds: f64,
}

pub fn run(args: Args) -> Result<()> {
    if args.output.extension().is_none_or(|e| e != "lst") {
        return Err(Error::invalid("organtex lst writes a .lst model").in_file(&args.output));
    }
    let mesh = io::read(&args.mesh)?;
    let exemplar = Volume::read_exemplar(&args.exemplar)?;
    let strokes = match &args.strokes {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            let file: StrokeFile = toml::from_str(&text)
                .map_err(|e| Error::format(path, format!("not a stroke file: {e}")))?;
            file.stroke
                .into_iter()
                .map(|s| s.points.into_iter().map(DVec3::from_array).collect())
                .collect()
        }
        None => Vec::new(),
    };
    let (depth_outer, depth_inner) = match (&args.depth_outer, &args.depth_inner) {
        (Some(o), Some(i)) => {
            lst::facet_depth_points(&mesh, o, i).map_err(|e| e.in_file(&args.mesh))?
        }
        _ if args.kind.needs_depth() => {
            return Err(Error::invalid(format!(
                "texture type {} needs a depth: give --depth-outer FACET --depth-inner FACET",
                args.kind.name()
            )));
        }
        _ => (Vec::new(), Vec::new()),
    };
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let opts = LstOptions {
        kind: args.kind,
        scale: args.scale.unwrap_or(lo.distance(hi) / 4.0),
        strokes,
        depth_outer,
        depth_inner,
        seed: args.seed,
    };
    let bars = Bars::new();
    let start = Instant::now();
    let tets = tetra::tetrahedralise(
        &mesh,
        &TetOptions {
            cells: args.cells.map(|c| c as usize),
            ..Default::default()
        },
        &bars,
    )
    .map_err(|e| e.in_file(&args.mesh))?;
    let tetra_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let (model, stats) = lst::fill_stats(&tets, &opts, &bars)?;
    let fill_seconds = start.elapsed().as_secs_f64();
    bars.finish();
    // The exemplar must suit the model before anything is written.
    LstInterior::check_exemplar(&exemplar).map_err(|e| e.in_file(&args.exemplar))?;
    model.write(&args.output)?;
    let f = Figures {
        file: args.mesh.clone(),
        output: args.output.clone(),
        kind: args.kind.name(),
        tets: tets.num_tets(),
        patches: stats.patches,
        layers: stats.layers,
        layers_per_tet: stats.layers as f64 / tets.num_tets() as f64,
        bytes: model.file_size(),
        bytes_per_tet: model.file_size() as f64 / tets.num_tets() as f64,
        alignment: stats,
        tetra_seconds,
        fill_seconds,
    };
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&f).expect("the figures serialise")
        );
        return Ok(());
    }
    println!(
        "{}: type {}, {} tets, {} patches, {:.1} layers per tet, {:.2} MB ({:.0} bytes per tet)",
        f.output.display(),
        f.kind,
        super::thousands(f.tets),
        f.patches,
        f.layers_per_tet,
        f.bytes as f64 / 1e6,
        f.bytes_per_tet
    );
    println!(
        "  alignment: median {:.2} deg, 95th percentile {:.2}, max {:.2}; tets {:.2} s, fill {:.2} s",
        f.alignment.angle_median,
        f.alignment.angle_p95,
        f.alignment.angle_max,
        f.tetra_seconds,
        f.fill_seconds
    );
    Ok(())
}
