//! `organtex stereology PHOTO... [--mask M] [--bins N] --size N [--seed S]
//! -o BLOCK.nrrd [--profiles-out P.png] [--json]`.

use std::path::PathBuf;

use organtex::Result;
use organtex::solid::stereology::{self, StereologyOptions};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// Photographs of sections of the same material (PNG or JPEG), the
    /// same pixel scale: particles (one colour class) in a binder (the
    /// other), split alike in all of them.
    #[arg(required = true)]
    photos: Vec<PathBuf>,
    /// What is not tissue, black (for every photograph): profiles touching
    /// it are left out and corrected for, like those touching the border.
    #[arg(long, value_name = "IMAGE")]
    mask: Option<PathBuf>,
    /// Which colour class the particles are: auto (the binder is the
    /// phase connected across the photographs, else the minority by
    /// area; refused when neither decides), light, dark, or the class
    /// nearer a colour RRGGBB.
    #[arg(long, default_value = "auto", value_name = "auto|light|dark|RRGGBB")]
    particles: stereology::Particles,
    /// Particle-size bins reported.
    #[arg(long, default_value_t = 10)]
    bins: usize,
    /// A particle type: sphere, ellipsoid:A,B,C (semi-axes, any scale) or
    /// a closed mesh (.obj, .ply, .stl; any scale), optionally @P, its
    /// proportion. Repeat for several types sharing one size distribution
    /// (seed 001, eq. 10-12), e.g. --shape sphere@3 --shape grain.obj@1.
    /// Non-spheres unfold through a kernel by Monte Carlo slicing.
    #[arg(long = "shape", value_name = "SHAPE[@P]", default_value = "sphere",
          value_parser = stereology::shape::Shape::parse_type)]
    shapes: Vec<(stereology::shape::Shape, f64)>,
    /// How particles and binder get the photographs' texture: copied (the
    /// block synthesiser copies the largest photograph's pixels, particle
    /// voxels from particle pixels) or residual (seed 001: mean colours
    /// plus the residual resynthesised by pyramid histogram matching).
    #[arg(long, default_value = "copied")]
    detail: stereology::Detail,
    /// Colour categories of particles (seed 001, 4.2): k-means of the
    /// profiles' mean colours, each category unfolded on its own; more
    /// than 1 where particles of different sizes differ in colour.
    #[arg(long, default_value_t = 1, value_name = "K")]
    colour_classes: usize,
    /// Voxels a side (a voxel is a pixel of the photographs).
    #[arg(long, value_name = "N")]
    size: usize,
    /// Seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output block, NRRD (raw uint8 RGB), tiling in x, y and z.
    #[arg(short, long)]
    output: PathBuf,
    /// A picture of what was found in the first photograph: profiles
    /// measured in their mean colour, profiles cut by the border or the
    /// mask in red, the binder dimmed.
    #[arg(long, value_name = "PNG")]
    profiles_out: Option<PathBuf>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> Result<()> {
    super::require_extension(&args.output, "nrrd")?;
    let opts = StereologyOptions {
        size: args.size,
        bins: args.bins,
        seed: args.seed,
        shapes: args.shapes,
        detail: args.detail,
        colour_classes: args.colour_classes,
    };
    opts.check()?;
    let sections = stereology::read_sections(
        &args.photos,
        args.mask.as_deref(),
        args.particles,
        args.seed,
    )?;
    let bars = Bars::new();
    let (volume, report) =
        stereology::synthesize(&sections, &opts, &bars).map_err(|e| e.in_file(&args.photos[0]))?;
    bars.finish();
    volume.write_nrrd(&args.output)?;
    if let Some(path) = &args.profiles_out {
        let (s, pixels) = (&sections[0], &sections[0].pixels);
        let picture = image::RgbImage::from_fn(s.width as u32, s.height as u32, |x, y| {
            let i = y as usize * s.width + x as usize;
            image::Rgb(match s.labels[i] {
                0 => pixels[i].map(|c| c / 3),
                u32::MAX => [220, 30, 30],
                k => s.profiles[k as usize - 1].colour.map(|c| c as u8),
            })
        });
        organtex::atomic::write_png(path, &image::DynamicImage::ImageRgb8(picture))?;
    }
    if report.overlap_fraction > 0.01 {
        eprintln!(
            "warning: annealing left {:.1}% of the particles' volume overlapping: they are dense, \
             or large for a {}-voxel block (the largest is {:.0} pixels across); a larger --size helps",
            100.0 * report.overlap_fraction,
            args.size,
            report
                .size_distribution
                .edges
                .last()
                .copied()
                .unwrap_or(0.0)
        );
    }
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).expect("the report serialises")
        );
    } else {
        println!(
            "{}: {n}x{n}x{n} voxels, {} particles from {} profiles ({} cut by the frame; particles \
             the {} class, by {}), volume fraction {:.3} (Delesse; the block's {:.3}), overlap {:.2}%, in {:.2} s",
            args.output.display(),
            report.particles,
            report.profiles,
            report.cut_profiles,
            stereology::split::hex(report.split.particle),
            report.split.decided_by,
            report.volume_fraction,
            report.block_volume_fraction,
            100.0 * report.overlap_fraction,
            report.seconds.unfold
                + report.seconds.place
                + report.seconds.colour
                + report.seconds.detail,
            n = args.size
        );
        let d = &report.size_distribution;
        for (e, v) in d.edges.windows(2).zip(&d.per_volume) {
            println!(
                "  diameter {:6.1}-{:6.1} px: {:.3e} per cubic px",
                e[0], e[1], v
            );
        }
    }
    Ok(())
}
