//! `organtex uv-metrics MESH.obj`: the distortion figures of any uv layout
//! (ours, xatlas's, Blender's), measured the same way.

use std::path::PathBuf;

use organtex::mesh::repair::make_manifold;
use organtex::mesh::{Topology, io};
use organtex::unwrap::metrics::measure;
use organtex::unwrap::visibility::{Viewpoints, compute};
use organtex::{Error, Result};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// A mesh with texture coordinates (OBJ with vt).
    file: PathBuf,
    /// Orthographic views for the seams' visibility.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..=1024))]
    views: u32,
    /// Split non-manifold edges and vertices first instead of refusing the
    /// mesh (scans often have some), as `unwrap --repair` does.
    #[arg(long)]
    repair: bool,
}

pub fn run(args: Args) -> Result<()> {
    let mut mesh = io::read(&args.file)?;
    if args.repair {
        mesh = make_manifold(&mesh).0;
    }
    let topo = Topology::build(&mesh).map_err(|e| e.in_file(&args.file))?;
    let bars = Bars::new();
    let vis = compute(
        &mesh,
        &topo,
        &Viewpoints::Orbit {
            views: args.views as usize,
        },
        &bars,
    );
    bars.finish();
    let metrics = measure(&mesh, &topo, &vis.edge).ok_or_else(|| {
        Error::format(
            &args.file,
            "the mesh has no texture coordinates on every face",
        )
    })?;
    // Plain numbers and string keys: serialising cannot fail.
    println!(
        "{}",
        serde_json::to_string_pretty(&metrics).expect("metrics serialise")
    );
    Ok(())
}
