//! `organtex synth3d SRC --size N -o BLOCK.nrrd`: a solid texture block.

use std::path::PathBuf;

use organtex::synth::block::{BlockOptions, Method, synthesize_block};
use organtex::synth::exemplar::{Crop, Exemplar};
use organtex::synth::quality::measure_block;
use organtex::synth::volume::Volume;
use organtex::{Error, Result, memory};

use super::progress::Bars;
use super::synth::parse_crop;

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    /// FNPTS with three plane neighbourhoods per voxel (seed 004, 3.3).
    Fnpts,
    /// Texture optimisation with histogram matching (Kopf et al. 2007).
    Optimize,
}

#[derive(clap::Args)]
pub struct Args {
    /// Exemplar photograph: what a slice across any axis should look like
    /// (isotropic tissue), or, with --src-y and --src-z, across x.
    source: PathBuf,
    /// Exemplar for slices across y (needs --src-z; same size as SOURCE).
    #[arg(long, value_name = "IMAGE", requires = "src_z")]
    src_y: Option<PathBuf>,
    /// Exemplar for slices across z (needs --src-y; same size as SOURCE).
    #[arg(long, value_name = "IMAGE", requires = "src_y")]
    src_z: Option<PathBuf>,
    /// Mask of usable exemplar pixels, white usable (for every exemplar).
    #[arg(long, value_name = "IMAGE")]
    mask: Option<PathBuf>,
    /// Use only this part of the exemplars: X,Y,WIDTH,HEIGHT in pixels.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_crop)]
    crop: Option<Crop>,
    /// Voxels a side; a multiple of 2^(levels - 1).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    size: usize,
    #[arg(long, value_enum, default_value = "fnpts")]
    method: MethodArg,
    /// A layered (depth-varying) exemplar for LST types 1b and 2b (seed
    /// 002, 4.2): SOURCE's rows are depth, top = outer. SOURCE is scaled to
    /// SIZE rows; the block's y is depth (named in the NRRD header), and it
    /// tiles in x and z, not in y.
    #[arg(long, conflicts_with_all = ["src_y", "src_z"])]
    layered: bool,
    /// With --layered: leave out seed 002's fix for the sweeping artefact
    /// (to measure it; the block comes out swept along a diagonal).
    #[arg(long, requires = "layered")]
    no_sweep_fix: bool,
    /// Seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Iterations per voxel and level (FNPTS's M; optimize and --layered:
    /// rounds) [default: 3; 6 with --layered].
    #[arg(long)]
    iterations: Option<usize>,
    /// Pyramid levels (default: as many as keep 16 voxels a side).
    #[arg(long, value_parser = super::synth::levels_in_range)]
    levels: Option<usize>,
    /// Side of each plane's square neighbourhood (odd).
    #[arg(long, default_value_t = 5)]
    neighbourhood: usize,
    /// Weight of the occurrence penalty, which multiplies a candidate's cost
    /// by 1 + this x how far its source is over-used (FNPTS; 0: the paper's
    /// cost alone).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    occurrence: f64,
    /// Edge length of a voxel in object units, written to the NRRD.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    spacing: f64,
    /// Output block, NRRD (raw uint8 RGB).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write a PNG montage of slices: a row per axis (x, y, z), four
    /// evenly spaced slices each.
    #[arg(long, value_name = "PNG")]
    slices: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    super::require_extension(&args.output, "nrrd")?;
    if let Some(s) = &args.slices {
        super::require_extension(s, "png")?;
    }
    super::check_spacing(args.spacing)?;
    if args.layered {
        return run_layered(&args);
    }
    let mut paths = vec![args.source.clone()];
    paths.extend(args.src_y.iter().chain(&args.src_z).cloned());
    let method = match args.method {
        MethodArg::Fnpts => Method::Fnpts,
        MethodArg::Optimize => Method::Optimize,
    };
    let n = args.size;
    memory::ensure_fits(
        &format!("synthesising a {n}x{n}x{n} block (--size)"),
        organtex::synth::block::memory_bytes(n, paths.len(), method),
    )?;
    let exemplars = paths
        .iter()
        .map(|p| {
            let e = Exemplar::load(p, args.mask.as_deref(), args.crop)?;
            e.check_neighbourhood(args.neighbourhood)
                .map_err(|err| err.in_file(p))?;
            Ok(e)
        })
        .collect::<Result<Vec<_>>>()?;
    // `paths` starts with SOURCE, so there is always a first exemplar.
    for (p, e) in paths.iter().zip(&exemplars).skip(1) {
        let first = &exemplars[0];
        if (e.width, e.height) != (first.width, first.height) {
            return Err(Error::invalid(format!(
                "is {}x{} but {} is {}x{}; the exemplars must be the same size",
                e.width,
                e.height,
                paths[0].display(),
                first.width,
                first.height
            ))
            .in_file(p));
        }
    }
    let opts = BlockOptions {
        size: args.size,
        seed: args.seed,
        iterations: args.iterations.unwrap_or(3),
        levels: args.levels,
        neighbourhood: args.neighbourhood,
        occurrence: args.occurrence,
        method,
    };
    let bars = Bars::new();
    let start = std::time::Instant::now();
    let volume = synthesize_block(&exemplars, &opts, &bars)?;
    bars.finish();
    let seconds = start.elapsed().as_secs_f64();
    let volume = Volume {
        spacing: args.spacing,
        ..volume
    };
    volume.write_nrrd(&args.output)?;
    if let Some(path) = &args.slices {
        organtex::atomic::write_png(path, &montage(&volume, 4))?;
    }
    println!(
        "{}: {n}x{n}x{n} voxels from {} {}x{} exemplar(s) in {seconds:.2} s",
        args.output.display(),
        exemplars.len(),
        exemplars[0].width,
        exemplars[0].height,
        n = args.size,
    );
    for (axis, q) in ["x", "y", "z"]
        .iter()
        .zip(measure_block(&volume, &exemplars, 4))
    {
        println!(
            "  slices across {axis}: coherence {:.2}, completeness {:.2}, tiling seam {:.2}",
            q.coherence, q.completeness, q.seam
        );
    }
    Ok(())
}

/// `synth3d --layered`: the layered block, its depth axis in the header.
fn run_layered(args: &Args) -> Result<()> {
    use organtex::synth::block::layered::{LayeredOptions, measure_layered, synthesize_layered};
    let n = args.size;
    memory::ensure_fits(
        &format!("synthesising a {n}x{n}x{n} layered block (--size)"),
        organtex::synth::block::memory_bytes(n, 1, Method::Optimize),
    )?;
    let exemplar = Exemplar::load(&args.source, args.mask.as_deref(), args.crop)?;
    // Scaling up by more than 2 would invent the layers' detail.
    if 2 * exemplar.height < n {
        return Err(Error::invalid(format!(
            "has {} rows; a layered block of {n} voxels takes its depth from at least {} of \
             them (scaling up more invents detail): give a smaller --size or a taller image",
            exemplar.height,
            n.div_ceil(2)
        ))
        .in_file(&args.source));
    }
    let exemplar = exemplar
        .with_height(n)
        .map_err(|e| e.in_file(&args.source))?;
    let opts = LayeredOptions {
        size: n,
        seed: args.seed,
        iterations: args
            .iterations
            .unwrap_or(LayeredOptions::default().iterations),
        levels: args.levels,
        neighbourhood: args.neighbourhood,
        sweep_fix: !args.no_sweep_fix,
    };
    let bars = Bars::new();
    let start = std::time::Instant::now();
    let volume =
        synthesize_layered(&exemplar, &opts, &bars).map_err(|e| e.in_file(&args.source))?;
    bars.finish();
    let seconds = start.elapsed().as_secs_f64();
    let volume = Volume {
        spacing: args.spacing,
        ..volume
    };
    volume.write_nrrd_with_depth(&args.output, Some(1))?;
    if let Some(path) = &args.slices {
        organtex::atomic::write_png(path, &montage(&volume, 4))?;
    }
    let q = measure_layered(&volume, &exemplar, 4);
    println!(
        "{}: {n}x{n}x{n} layered voxels (depth along y, outer at y = 0) from a {}x{} exemplar in {seconds:.2} s{}",
        args.output.display(),
        exemplar.width,
        exemplar.height,
        if opts.sweep_fix {
            ""
        } else {
            ", sweep fix off"
        }
    );
    println!(
        "  mean colour per depth row vs the exemplar's: RMS {:.2}; slices through depth: coherence {:.2}, completeness {:.2}; sweep {:.3}",
        q.rows_rms, q.coherence, q.completeness, q.sweep
    );
    // The yardstick (issue 23): a tileable 2D synthesis of the slice's
    // size from the same exemplar.
    let flat = organtex::synth::fnpts::synthesize(
        &exemplar,
        &organtex::synth::fnpts::SynthOptions {
            width: n,
            height: n,
            tileable: true,
            seed: args.seed,
            ..Default::default()
        },
        &organtex::progress::Silent,
    )?;
    let q2 = organtex::synth::quality::measure(
        &exemplar,
        &organtex::synth::quality::Rgb {
            width: flat.width,
            height: flat.height,
            pixels: &flat.pixels,
        },
    );
    println!(
        "  a {n}x{n} 2D synthesis from the same exemplar: coherence {:.2}, completeness {:.2}",
        q2.coherence, q2.completeness
    );
    Ok(())
}

/// A row of `per_axis` evenly spaced slices for each axis, 2 pixels apart.
fn montage(volume: &Volume, per_axis: usize) -> image::DynamicImage {
    let n = volume.size[0] as u32;
    let gap = 2;
    let k = per_axis as u32;
    let mut img = image::RgbImage::from_pixel(
        k * (n + gap) - gap,
        3 * (n + gap) - gap,
        image::Rgb([255; 3]),
    );
    for axis in 0..3 {
        for s in 0..k {
            let (w, _, pixels) = volume.slice(axis, (s * n / k) as usize);
            for (i, p) in pixels.iter().enumerate() {
                let (x, y) = ((i % w) as u32, (i / w) as u32);
                img.put_pixel(
                    s * (n + gap) + x,
                    axis as u32 * (n + gap) + y,
                    image::Rgb(*p),
                );
            }
        }
    }
    image::DynamicImage::ImageRgb8(img)
}
