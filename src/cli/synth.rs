//! `organtex synth SRC --size WxH -o OUT.png`: FNPTS texture synthesis.

use std::path::PathBuf;

use organtex::synth::exemplar::{Crop, Exemplar};
use organtex::synth::fnpts::{SynthOptions, Synthesis, synthesize};
use organtex::{Result, memory};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// Exemplar photograph (PNG, JPEG).
    source: PathBuf,
    /// Mask of usable exemplar pixels: white usable, black masked out (the
    /// exemplar's alpha channel is used too, if it has one).
    #[arg(long, value_name = "IMAGE")]
    mask: Option<PathBuf>,
    /// Use only this part of the exemplar: X,Y,WIDTH,HEIGHT in pixels.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_crop)]
    crop: Option<Crop>,
    /// Output size, WIDTHxHEIGHT (or one number for a square).
    #[arg(long, value_name = "WxH", value_parser = parse_size, allow_negative_numbers = true)]
    size: (usize, usize),
    /// Make the output tile: it wraps around seamlessly.
    #[arg(long)]
    tileable: bool,
    /// Seed: the same seed gives the same bytes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Iterations per pixel and pyramid level (M).
    #[arg(long, default_value_t = 3)]
    iterations: usize,
    /// Pyramid levels (default: down to an exemplar of about 16 pixels a
    /// side and an output of 32; 11 and 8 for outputs under 512 pixels).
    #[arg(long, value_parser = levels_in_range)]
    levels: Option<usize>,
    /// Side of the square neighbourhood compared (odd).
    #[arg(long, default_value_t = 7)]
    neighbourhood: usize,
    /// Weight of the occurrence penalty, which spreads copies over the whole
    /// exemplar: a candidate's cost is multiplied by 1 + this x how far its
    /// source is over-used (0: the paper's cost alone). Outputs under 512
    /// pixels a side with fewer pixels than 4x the exemplar's weigh it up to
    /// 4x more, and 8x that again with under an eighth of its pixels.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    occurrence: f64,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the exemplar coordinate of every output pixel, as a 16-bit
    /// PNG (red = x, green = y).
    #[arg(long, value_name = "PNG")]
    coords_out: Option<PathBuf>,
}

fn parse_size(s: &str) -> std::result::Result<(usize, usize), String> {
    let parts: Vec<&str> = s.split(['x', 'X']).collect();
    let n = |p: &str| {
        p.trim()
            .parse::<usize>()
            .map_err(|_| format!("'{s}' is not WIDTHxHEIGHT"))
    };
    match parts.as_slice() {
        [side] => n(side).map(|v| (v, v)),
        [w, h] => Ok((n(w)?, n(h)?)),
        _ => Err(format!("'{s}' is not WIDTHxHEIGHT")),
    }
}

/// Pyramid levels, 1 to `MAX_LEVELS` (the library's own bound).
pub(super) fn levels_in_range(s: &str) -> std::result::Result<usize, String> {
    use organtex::synth::fnpts::MAX_LEVELS;
    s.trim()
        .parse::<usize>()
        .ok()
        .filter(|l| (1..=MAX_LEVELS).contains(l))
        .ok_or_else(|| format!("'{s}' is not a number of levels from 1 to {MAX_LEVELS}"))
}

pub(super) fn parse_crop(s: &str) -> std::result::Result<Crop, String> {
    let v = super::comma_numbers::<u32>(s, 4, "X,Y,WIDTH,HEIGHT")?;
    Ok(Crop {
        x: v[0],
        y: v[1],
        width: v[2],
        height: v[3],
    })
}

pub fn run(args: Args) -> Result<()> {
    let (w, h) = args.size;
    memory::ensure_fits(
        &format!("synthesising a {w}x{h} texture (--size)"),
        organtex::synth::fnpts::memory_bytes(w, h),
    )?;
    let exemplar = Exemplar::load(&args.source, args.mask.as_deref(), args.crop)?;
    exemplar
        .check_neighbourhood(args.neighbourhood)
        .map_err(|e| e.in_file(&args.source))?;
    let opts = SynthOptions {
        width: args.size.0,
        height: args.size.1,
        tileable: args.tileable,
        seed: args.seed,
        iterations: args.iterations,
        levels: args.levels,
        neighbourhood: args.neighbourhood,
        occurrence: args.occurrence,
    };
    let bars = Bars::new();
    let start = std::time::Instant::now();
    let out = synthesize(&exemplar, &opts, &bars)?;
    bars.finish();
    organtex::atomic::write_png(&args.output, &colour_image(&out))?;
    if let Some(path) = &args.coords_out {
        organtex::atomic::write_png(path, &coords_image(&out))?;
    }
    println!(
        "{}: {}x{} from a {}x{} exemplar in {:.2} s",
        args.output.display(),
        out.width,
        out.height,
        exemplar.width,
        exemplar.height,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

pub fn colour_image(s: &Synthesis) -> image::DynamicImage {
    let raw = s.pixels.iter().flatten().copied().collect();
    // `synthesize` makes width x height pixels, and the sizes fit u32
    // (at most 16384 a side), so the buffer always matches.
    image::DynamicImage::ImageRgb8(
        image::RgbImage::from_raw(s.width as u32, s.height as u32, raw)
            .expect("one pixel per entry"),
    )
}

fn coords_image(s: &Synthesis) -> image::DynamicImage {
    let raw = s
        .coords
        .iter()
        .flat_map(|c| [c[0] as u16, c[1] as u16, 0])
        .collect();
    // As in `colour_image`: one coordinate per pixel.
    image::DynamicImage::ImageRgb16(
        image::ImageBuffer::from_raw(s.width as u32, s.height as u32, raw)
            .expect("one pixel per entry"),
    )
}

/// `organtex synth-quality`: coherence, completeness and seam of any
/// texture against its exemplar.
#[derive(clap::Args)]
pub struct QualityArgs {
    /// The exemplar the texture was made from.
    exemplar: PathBuf,
    /// The synthesised texture.
    texture: PathBuf,
    /// Mask of usable exemplar pixels (white usable).
    #[arg(long, value_name = "IMAGE")]
    mask: Option<PathBuf>,
    /// The part of the exemplar used: X,Y,WIDTH,HEIGHT.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_crop)]
    crop: Option<Crop>,
}

pub fn quality(args: QualityArgs) -> Result<()> {
    let exemplar = Exemplar::load(&args.exemplar, args.mask.as_deref(), args.crop)?;
    // The figures compare 7 x 7 patches.
    exemplar
        .check_neighbourhood(7)
        .map_err(|e| e.in_file(&args.exemplar))?;
    let texture = organtex::synth::exemplar::read_image(&args.texture)?.to_rgb8();
    let pixels: Vec<[u8; 3]> = texture.pixels().map(|p| p.0).collect();
    let q = organtex::synth::quality::measure(
        &exemplar,
        &organtex::synth::quality::Rgb {
            width: texture.width() as usize,
            height: texture.height() as usize,
            pixels: &pixels,
        },
    );
    // Three numbers (NaN and infinity serialise as null): cannot fail.
    println!(
        "{}",
        serde_json::to_string_pretty(&q).expect("figures serialise")
    );
    Ok(())
}
