//! Argument definitions and dispatch.

mod bench;
mod db;
mod generate;
mod info;
mod progress;
mod synth;
mod unwrap;
mod uv_metrics;

use clap::{Parser, Subcommand};

use organtex::Result;

/// Automatic texturing of organ scenes for surgical simulators.
///
/// With no command, prints `info` for the bundled Stanford bunny.
#[derive(Parser)]
#[command(name = "organtex", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
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
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Some(Command::Info(args)) => info::run(args),
        Some(Command::Bench(args)) => bench::run(args),
        Some(Command::Generate(args)) => generate::run(args),
        Some(Command::Unwrap(args)) => unwrap::run(args),
        Some(Command::UvMetrics(args)) => uv_metrics::run(args),
        Some(Command::Synth(args)) => synth::run(args),
        Some(Command::Db(args)) => db::run(args),
        Some(Command::SynthQuality(args)) => synth::quality(args),
        None => info::run(info::Args::for_file(
            organtex::bench::default_root()
                .join("tests")
                .join("data")
                .join("bunny.obj"),
        )),
    }
}

/// Group digits in threes, as the reports print counts: 56172 -> "56,172".
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}
