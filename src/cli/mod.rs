//! Argument definitions and dispatch.

mod bake;
mod bench;
mod db;
mod generate;
mod info;
mod lst;
mod mesh;
mod morph;
pub mod progress;
mod section;
mod stereology;
mod sweep;
mod synth;
mod synth3d;
mod tetra;
mod unwrap;
mod uv_metrics;
mod view;

use std::path::Path;

use clap::{Parser, Subcommand};

use organtex::Result;

/// Automatic texturing of organ scenes for surgical simulators.
///
/// With no command, bakes the bundled hysteroscopy scene
/// (scenes/hysteroscopy_myomas.toml) into out/.
#[derive(Parser)]
#[command(name = "organtex", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Bake a scene (scenes/README.md): every facet cut, flattened and
    /// textured with its tissue, seams and facet borders blended; writes
    /// DIR/scene.glb, DIR/report.json and DIR/preview.png, and keeps the
    /// interiors and unwraps (DIR/interior/, DIR/unwraps/) that a next
    /// bake into DIR takes where their inputs did not change.
    Bake(bake::Args),
    /// Describe a mesh: counts, facets, components, genus, boundary loops,
    /// defects, bounds, area, volume and curvature statistics.
    Info(info::Args),
    /// Time the project's standard workloads (median of several runs).
    Bench(bench::Args),
    /// Cut a mesh along hidden seams into disk charts and flatten them
    /// (Seamster + ABF++); writes an OBJ with uvs.
    Unwrap(unwrap::Args),
    /// Synthesise a texture (tileable with --tileable) from a masked
    /// exemplar photograph, pixel by pixel (FNPTS).
    Synth(synth::Args),
    /// Synthesise a solid texture block that tiles in 3D from one exemplar
    /// (isotropic tissue) or three (across x, y, z); writes NRRD.
    Synth3d(synth3d::Args),
    /// Design a solid exemplar by sweeping a cross-section along an axis
    /// (seed 002, 4.3): band-limited noise, a thin skin and inclusions
    /// (seeds) placed from a file; writes NRRD.
    Sweep(sweep::Args),
    /// A particles-in-a-binder block from photographs of sections (seed
    /// 001): profiles found, their sizes unfolded into the 3D size
    /// distribution, particles placed and annealed in a periodic box,
    /// coloured from the profiles; writes NRRD.
    Stereology(stereology::Args),
    /// Quality figures of a texture against its exemplar: coherence,
    /// completeness (7x7 patches, RMS) and tiling seam.
    SynthQuality(synth::QualityArgs),
    /// Distortion figures of a mesh's existing uv layout (charts, flips,
    /// conformality, area distortion, seam length and visibility).
    UvMetrics(uv_metrics::Args),
    /// The tissue texture database: list entries, build their textures.
    Db(db::Args),
    /// Write a generated test shape (torus, double torus, cylinder, sphere).
    Generate(generate::Args),
    /// Cut a closed mesh with a plane and texture the section from a solid
    /// texture block (NRRD), a lapped solid texture or photographed cuts
    /// (--sections): a .png of the section in its plane, or a .glb
    /// of its triangles. A plane that misses the mesh is an error (exit
    /// status 1) and writes nothing.
    Section(section::Args),
    /// One region of a CT or MRI segmentation (a NIfTI label map or
    /// probability map, a NRRD label map or a 3D Slicer .seg.nrrd) as a
    /// closed, manifold, smoothed surface in the scanner's millimetres;
    /// writes .obj, .ply or .stl.
    Mesh(mesh::Args),
    /// Fill a closed (or nearly closed) mesh with tetrahedra by isosurface
    /// stuffing: every dihedral angle in [10.7, 164.8] degrees, inside
    /// decided by the winding number so self-intersecting or slightly open
    /// surfaces work; writes .vtk, .msh or .mesh.
    Tetra(tetra::Args),
    /// Fill an organ with a lapped solid texture (seed 000): patches of a
    /// solid exemplar pasted over its tet mesh, oriented by strokes and
    /// layered by depth between two facets; writes a .lst model that
    /// `organtex section --lst` cuts.
    Lst(lst::Args),
    /// The colour inside an organ morphed from photographs of a few cuts
    /// placed as planes in it (seed 003): a plane section or a grid of
    /// points, computed on demand from the photographs, no volume stored.
    Morph(morph::Args),
    /// The desktop viewer: open a scene or mesh, pick tissues, unwrap,
    /// drag textures into place, cut the organ and see its inside, save
    /// and bake. Needs a display (or Xvfb).
    View(view::Args),
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Bake(args)) => bake::run(args),
        Some(Command::Info(args)) => info::run(args),
        Some(Command::Bench(args)) => bench::run(args),
        Some(Command::Generate(args)) => generate::run(args),
        Some(Command::Unwrap(args)) => unwrap::run(args),
        Some(Command::UvMetrics(args)) => uv_metrics::run(args),
        Some(Command::Synth(args)) => synth::run(args),
        Some(Command::Synth3d(args)) => synth3d::run(args),
        Some(Command::Sweep(args)) => sweep::run(args),
        Some(Command::Stereology(args)) => stereology::run(args),
        Some(Command::Db(args)) => db::run(args),
        Some(Command::Section(args)) => section::run(args),
        Some(Command::Tetra(args)) => tetra::run(args),
        Some(Command::Mesh(args)) => mesh::run(args),
        Some(Command::Lst(args)) => lst::run(args),
        Some(Command::Morph(args)) => morph::run(args),
        Some(Command::View(args)) => view::run(args),
        Some(Command::SynthQuality(args)) => synth::quality(args),
        None => {
            let root = organtex::bench::default_root();
            bake::bake_and_print(
                &root.join("scenes").join("hysteroscopy_myomas.toml"),
                Path::new("out"),
                None,
                false,
            )
        }
    }
}

/// Print figures as pretty JSON (`--json`). Plain numbers, paths and
/// strings: serialising cannot fail.
pub fn print_json(figures: &impl serde::Serialize) {
    println!(
        "{}",
        serde_json::to_string_pretty(figures).expect("the figures serialise")
    );
}

pub use organtex::progress::thousands;

/// `path` must end in `.ext` (any case): the file a command writes.
fn require_extension(path: &std::path::Path, ext: &str) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case(ext) => Ok(()),
        _ => {
            Err(organtex::Error::invalid(format!("the output must be a .{ext} file")).in_file(path))
        }
    }
}

/// A block's `--spacing` (object units a voxel spans) must be positive.
fn check_spacing(spacing: f64) -> Result<()> {
    if spacing.is_finite() && spacing > 0.0 {
        Ok(())
    } else {
        Err(organtex::Error::invalid(format!(
            "--spacing must be a positive number, not {spacing}"
        )))
    }
}

/// A finite length above 0 (`--edge-length`, `--scale`).
fn positive_length(s: &str) -> std::result::Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0)
        .ok_or_else(|| format!("'{s}' is not a positive length"))
}

/// `n` comma-separated numbers (an argument like `X,Y,Z`), or an error
/// naming the form expected.
fn comma_numbers<T: std::str::FromStr>(
    s: &str,
    n: usize,
    what: &str,
) -> std::result::Result<Vec<T>, String> {
    s.split(',')
        .map(|p| p.trim().parse::<T>().ok())
        .collect::<Option<Vec<T>>>()
        .filter(|v| v.len() == n)
        .ok_or_else(|| format!("'{s}' is not {what}"))
}
