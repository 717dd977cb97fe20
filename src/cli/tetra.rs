//! `organtex tetra MESH -o OUT.vtk|.msh|.mesh [--edge-length L | --cells N]
//! [--graded] [--json]`: the inside of a triangle mesh as tetrahedra (isosurface
//! stuffing), for a simulator's physics and for interior textures.

use std::path::PathBuf;
use std::time::Instant;

use organtex::Result;
use organtex::mesh::io;
use organtex::tetra::{self, TetOptions};
use serde::Serialize;

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// The surface: OBJ, PLY or STL; self-intersecting, non-manifold or
    /// slightly open surfaces are filled as their inside (winding number).
    mesh: PathBuf,
    /// The tet mesh: legacy VTK (.vtk: SOFA, 3D Slicer, ParaView), gmsh 4.1
    /// (.msh) or Medit (.mesh). Each tet carries its smallest dihedral
    /// angle (`min_dihedral`, degrees) in .vtk and .msh.
    #[arg(short, long)]
    output: PathBuf,
    /// Lattice cell size in mesh units (the long edges' length). Default:
    /// the bounding box diagonal / 40, refined until the boundary lies
    /// within 1% of the diagonal from the surface.
    #[arg(long, conflicts_with = "cells", value_parser = super::positive_length, allow_negative_numbers = true)]
    edge_length: Option<f64>,
    /// About this many tetrahedra instead of an edge length.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100_000_000), allow_negative_numbers = true)]
    cells: Option<u64>,
    /// Grade the interior: tets of the edge length along the surface, up to
    /// 16 times larger deep inside, so the count follows the surface's area
    /// (the default resolution grades by itself when a uniform mesh would
    /// pass 4 million tets).
    #[arg(long)]
    graded: bool,
    /// Print the figures as JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// What `--json` prints (and the text shows).
#[derive(Serialize)]
struct Figures {
    file: PathBuf,
    output: PathBuf,
    vertices: usize,
    tets: usize,
    edge_length: f64,
    attempts: usize,
    graded: bool,
    min_dihedral: f64,
    max_dihedral: f64,
    min_radius_ratio: f64,
    /// Two-sided, over the bounding box diagonal.
    hausdorff_relative: f64,
    hausdorff: tetra::Hausdorff,
    volume: f64,
    surface_volume: f64,
    seconds: f64,
}

pub fn run(args: Args) -> Result<()> {
    let write = tetra::io::writer(&args.output)?;
    let mesh = io::read(&args.mesh)?;
    let opts = TetOptions {
        edge_length: args.edge_length,
        cells: args.cells.map(|c| c as usize),
        graded: args.graded,
    };
    let start = Instant::now();
    let bars = Bars::new();
    let (mut tets, report) =
        tetra::tetrahedralise_report(&mesh, &opts, &bars).map_err(|e| e.in_file(&args.mesh))?;
    bars.finish();
    let seconds = start.elapsed().as_secs_f64();
    // The default resolution measured it already; otherwise measure it.
    let hausdorff = report.hausdorff.unwrap_or_else(|| tets.hausdorff(&mesh));
    if report.hausdorff.is_some() && hausdorff.relative() > tetra::DEFAULT_HAUSDORFF {
        eprintln!(
            "warning: the tets' boundary stays {:.2}% of the diagonal from {} after {} lattices, \
             above the default resolution's {}%: finer lattices stopped bringing it down (parts \
             thinner than a cell, or a surface open or crossing itself); --edge-length sets a \
             finer one",
            100.0 * hausdorff.relative(),
            args.mesh.display(),
            report.attempts,
            100.0 * tetra::DEFAULT_HAUSDORFF
        );
    }
    let quality = tets.quality();
    tets.set_tet_attribute("min_dihedral", 1, tets.min_dihedrals())?;
    write(&args.output, &tets)?;
    let figures = Figures {
        file: args.mesh.clone(),
        output: args.output.clone(),
        vertices: tets.num_vertices(),
        tets: tets.num_tets(),
        edge_length: report.edge_length,
        attempts: report.attempts,
        graded: report.graded,
        min_dihedral: quality.min_dihedral,
        max_dihedral: quality.max_dihedral,
        min_radius_ratio: quality.min_radius_ratio,
        hausdorff_relative: hausdorff.relative(),
        hausdorff,
        volume: tets.volume(),
        surface_volume: mesh.signed_volume().abs(),
        seconds,
    };
    if args.json {
        super::print_json(&figures);
        return Ok(());
    }
    let f = &figures;
    println!(
        "{}: {} vertices, {} tets (edge length {:.4}, {} {}lattice{}) in {:.2} s",
        f.file.display(),
        super::thousands(f.vertices),
        super::thousands(f.tets),
        f.edge_length,
        f.attempts,
        if f.graded { "graded " } else { "" },
        if f.attempts == 1 { "" } else { "s" },
        f.seconds
    );
    println!(
        "  dihedral angles {:.2} to {:.2} deg (bound {} to {}), min radius ratio {:.3}",
        f.min_dihedral,
        f.max_dihedral,
        tetra::MIN_DIHEDRAL,
        tetra::MAX_DIHEDRAL,
        f.min_radius_ratio
    );
    println!(
        "  boundary to surface {:.3}%, surface to boundary {:.3}% of the diagonal",
        100.0 * f.hausdorff.boundary_to_surface / f.hausdorff.diagonal,
        100.0 * f.hausdorff.surface_to_boundary / f.hausdorff.diagonal
    );
    println!(
        "  volume {:.6} ({:+.2}% of the surface's enclosed {:.6})",
        f.volume,
        100.0 * (f.volume / f.surface_volume - 1.0),
        f.surface_volume
    );
    println!("wrote {}", f.output.display());
    Ok(())
}
