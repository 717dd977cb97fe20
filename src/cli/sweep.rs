//! `organtex sweep SECTION.png --axis z --size N [--skin SKIN.png
//! --skin-depth K] [--noise A] [--inclusions SPEC.toml] -o B.nrrd`.

use std::path::PathBuf;

use organtex::synth::exemplar::read_image;
use organtex::synth::sweep::{Image, InclusionFile, SweepOptions, inclusions, sweep};
use organtex::{Error, Result};

#[derive(Clone, Copy, clap::ValueEnum)]
enum Axis {
    X,
    Y,
    Z,
}

#[derive(clap::Args)]
pub struct Args {
    /// The cross-section (square PNG or JPEG). Swept along x or z, its
    /// rows are the block's y, its depth: top = outer (LST types 1b, 2b).
    section: PathBuf,
    /// The axis the section is swept along.
    #[arg(long, value_enum, default_value = "z")]
    axis: Axis,
    /// Voxels a side.
    #[arg(long, value_name = "N")]
    size: usize,
    /// An image for a thin skin on the outer face (y = 0), tiled once
    /// across it.
    #[arg(long, value_name = "IMAGE", requires = "skin_depth")]
    skin: Option<PathBuf>,
    /// The skin's depth in voxels.
    #[arg(long, value_name = "K", requires = "skin")]
    skin_depth: Option<usize>,
    /// Displace the section by band-limited noise (features about 8 voxels
    /// across) of this amplitude, in voxels, so the sweep is not exact.
    #[arg(
        long,
        value_name = "A",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    noise: f64,
    /// Inclusions to paint in (TOML, `[[inclusion]]` tables: centre,
    /// radii or mesh, scale, rotation, colour or texture; in fractions of
    /// the block; format in the README).
    #[arg(long, value_name = "SPEC.toml")]
    inclusions: Option<PathBuf>,
    /// Seed of the noise: the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Edge length of a voxel in object units, written to the NRRD.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    spacing: f64,
    /// Output block, NRRD (raw uint8 RGB; the depth axis y named in its
    /// header when swept along x or z).
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(args: Args) -> Result<()> {
    super::require_extension(&args.output, "nrrd")?;
    super::check_spacing(args.spacing)?;
    let axis = args.axis as usize;
    let section = Image::from_rgb(&read_image(&args.section)?.to_rgb8());
    let skin = args
        .skin
        .as_ref()
        .map(|p| read_image(p).map(|i| Image::from_rgb(&i.to_rgb8())))
        .transpose()?;
    let incs = match &args.inclusions {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            let file: InclusionFile =
                toml::from_str(&text).map_err(|e| Error::format(path, e.to_string()))?;
            let dir = path.parent().unwrap_or(std::path::Path::new("."));
            inclusions(&file, args.size, dir).map_err(|e| e.in_file(path))?
        }
        None => Vec::new(),
    };
    let opts = SweepOptions {
        size: args.size,
        axis,
        noise: args.noise,
        seed: args.seed,
    };
    let start = std::time::Instant::now();
    let volume = sweep(&section, skin.as_ref().zip(args.skin_depth), &incs, &opts)
        .map_err(|e| e.in_file(&args.section))?;
    let seconds = start.elapsed().as_secs_f64();
    let volume = organtex::synth::volume::Volume {
        spacing: args.spacing,
        ..volume
    };
    let depth = (axis != 1).then_some(1);
    volume.write_nrrd_with_depth(&args.output, depth)?;
    println!(
        "{}: {n}x{n}x{n} voxels, {} swept along {}{}{}, {} inclusion(s), in {seconds:.2} s",
        args.output.display(),
        args.section.display(),
        ["x", "y", "z"][axis],
        if args.noise > 0.0 { " with noise" } else { "" },
        if skin.is_some() { ", a skin" } else { "" },
        incs.len(),
        n = args.size
    );
    Ok(())
}
