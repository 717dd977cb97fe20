//! `organtex db build`: regenerate every output of the database from its
//! sources, deterministically (same sources and parameters, same bytes),
//! into `database/build/<id>/`, with a `report.json` of quality figures and
//! timings per entry.

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::colour::{Grade, Grading, LabStats};
use super::index::{Database, Lighting, Output, Tissue};
use crate::atomic::{write_file, write_png};
use crate::error::{Error, Result};
use crate::progress::{CancelOnly, Progress, check};
use crate::synth::exemplar::Exemplar;
use crate::synth::fnpts::{SynthOptions, synthesize};
use crate::synth::height::{exemplar_height, synthesis_height};
use crate::synth::quality::{Quality, Rgb, measure};
use crate::synth::{lighting, mask, vessel_tree, vessels};

/// Bump when a change to synthesis, height maps, overlays or colour
/// grading changes what `build` or `graded_colour` writes for the same
/// entry: outputs built under another recipe are then rebuilt when a bake
/// needs them.
pub const RECIPE: u32 = 5;

#[derive(Clone, Debug, Serialize)]
pub struct Built {
    pub id: String,
    /// What the outputs were built from (`fingerprint`).
    pub fingerprint: String,
    pub outputs: Vec<Output>,
    pub usable_pixels: usize,
    pub quality: Option<Quality>,
    /// How even the lighting is, when a colour texture is built.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lighting: Option<LightingReport>,
    /// The colour texture's CIELAB statistics (`colour::LabStats`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub colour: Option<LabStats>,
    pub seconds: f64,
}

/// The lighting's unevenness: the deviation of the luminance blurred with
/// σ an eighth of the crop's shorter side, in levels of 255, in the source
/// crop and in the output tile (`synth::lighting::spread`).
#[derive(Clone, Debug, Serialize)]
pub struct LightingReport {
    pub flattened: bool,
    pub spread_before: f64,
    pub spread_after: f64,
}

/// A digest of everything an entry's outputs depend on: the recipe, the
/// entry's settings and its source (and mask) bytes.
pub fn fingerprint(db: &Database, t: &Tissue) -> Result<String> {
    let mut digest = crate::digest::Digest::default();
    let mut feed = |bytes: &[u8]| digest.feed(bytes);
    feed(&RECIPE.to_le_bytes());
    // The recipe's fields only: the name, kind, shelf, licence and credit
    // label the outputs without changing them. Plain fields with string
    // keys: serialising cannot fail.
    let recipe = Tissue {
        name: String::new(),
        kind: String::new(),
        shelf: None,
        licence: None,
        credit: None,
        capture: None,
        finish: None,
        ..t.clone()
    };
    feed(
        serde_json::to_string(&recipe)
            .expect("serialises")
            .as_bytes(),
    );
    for file in std::iter::once(&t.source).chain(t.mask.as_ref()) {
        let path = db.root.join(file);
        feed(&std::fs::read(&path).map_err(|e| Error::io(&path, e))?);
    }
    Ok(digest.hex())
}

/// Whether `t`'s outputs are built and up to date.
pub fn is_current(db: &Database, t: &Tissue) -> Result<bool> {
    let dir = db.root.join("build").join(&t.id);
    let Ok(text) = std::fs::read_to_string(dir.join("report.json")) else {
        return Ok(false);
    };
    #[derive(serde::Deserialize)]
    struct Stamp {
        fingerprint: String,
    }
    let Ok(built) = serde_json::from_str::<Stamp>(&text) else {
        return Ok(false);
    };
    let outputs = t
        .outputs
        .iter()
        .all(|&o| db.output_path(&t.id, o).is_file());
    Ok(outputs && built.fingerprint == fingerprint(db, t)?)
}

/// The exemplar an entry synthesises from: its source, cropped and masked,
/// its lighting flattened when the entry asks (`lighting = "flatten"`).
pub fn exemplar(db: &Database, t: &Tissue) -> Result<Exemplar> {
    Ok(lit_as_asked(t, masked_source(db, t)?))
}

/// `ex` with its lighting flattened if the entry asks for it.
fn lit_as_asked(t: &Tissue, mut ex: Exemplar) -> Exemplar {
    if t.lighting == Lighting::Flatten {
        lighting::flatten(&mut ex);
    }
    ex
}

/// The entry's source, cropped and masked, as photographed.
fn masked_source(db: &Database, t: &Tissue) -> Result<Exemplar> {
    let source = db.root.join(&t.source);
    let mask = t.mask.as_ref().map(|m| db.root.join(m));
    let mut ex = Exemplar::load(&source, mask.as_deref(), t.crop)?;
    mask::apply(&mut ex, &t.mask_rules);
    if !ex.valid.iter().any(|&v| v) {
        return Err(Error::format(
            &source,
            format!("tissue '{}': the mask rules hide every pixel", t.id),
        ));
    }
    Ok(ex)
}

/// Build the entries `ids` (all when empty).
pub fn build(db: &Database, ids: &[String], progress: &dyn Progress) -> Result<Vec<Built>> {
    let chosen: Vec<&Tissue> = if ids.is_empty() {
        db.tissues.iter().collect()
    } else {
        ids.iter().map(|id| db.tissue(id)).collect::<Result<_>>()?
    };
    progress.stage("database", chosen.len() as u64);
    let quiet = CancelOnly(progress);
    let mut built = Vec::new();
    for t in chosen {
        check(progress)?;
        built.push(build_one(db, t, &quiet)?);
        progress.advance(1);
    }
    Ok(built)
}

fn build_one(db: &Database, t: &Tissue, progress: &dyn Progress) -> Result<Built> {
    let start = Instant::now();
    let source = masked_source(db, t)?;
    let sigma = lighting::sigma_for(source.width.min(source.height));
    let spread_before = lighting::spread(
        &source.pixels,
        &source.valid,
        source.width,
        source.height,
        sigma,
    );
    let ex = lit_as_asked(t, source);
    // Everything that can be refused is checked, and the synthesis done,
    // before the entry's folder is made: a refused entry leaves nothing.
    let synthesised = match t
        .synthesis
        .as_ref()
        .filter(|_| t.outputs.iter().any(|o| *o != Output::Overlay))
    {
        Some(p) => {
            let opts = SynthOptions {
                width: p.width,
                height: p.height,
                tileable: p.tileable,
                seed: p.seed,
                iterations: p.iterations,
                levels: None,
                neighbourhood: p.neighbourhood,
                occurrence: p.occurrence,
            };
            let source = db.root.join(&t.source);
            ex.check_neighbourhood(p.neighbourhood)
                .map_err(|e| e.in_file(&source))?;
            crate::memory::ensure_fits(
                &format!("tissue '{}': a {}x{} texture", t.id, p.width, p.height),
                crate::synth::fnpts::memory_bytes(p.width, p.height),
            )
            .map_err(|e| e.in_file(&db.root.join("index.toml")))?;
            Some(synthesize(&ex, &opts, progress).map_err(|e| e.in_file(&source))?)
        }
        None => None,
    };
    let dir = db.root.join("build").join(&t.id);
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut quality = None;
    let mut lit = None;
    let mut colour = None;
    if let Some(s) = &synthesised {
        if t.outputs.contains(&Output::Colour) {
            let raw = s.pixels.iter().flatten().copied().collect();
            // `synthesize` gives width x height pixels, each side at most
            // 16384: the buffer always fits.
            let img =
                image::RgbImage::from_raw(s.width as u32, s.height as u32, raw).expect("sized");
            colour = Some(LabStats::of(&img));
            write_png(
                &dir.join(Output::Colour.file_name()),
                &image::DynamicImage::ImageRgb8(img),
            )?;
            lit = Some(LightingReport {
                flattened: t.lighting == Lighting::Flatten,
                spread_before,
                spread_after: lighting::spread(
                    &s.pixels,
                    &vec![true; s.pixels.len()],
                    s.width,
                    s.height,
                    sigma,
                ),
            });
            quality = Some(measure(
                &ex,
                &Rgb {
                    width: s.width,
                    height: s.height,
                    pixels: &s.pixels,
                },
            ));
        }
        if t.outputs.contains(&Output::Height) {
            let h = synthesis_height(&exemplar_height(&ex), ex.width, s);
            // One height per synthesised pixel, as above.
            let img = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(
                s.width as u32,
                s.height as u32,
                h,
            )
            .expect("sized");
            write_png(
                &dir.join(Output::Height.file_name()),
                &image::DynamicImage::ImageLuma16(img),
            )?;
        }
    }
    if t.outputs.contains(&Output::Layers) {
        // The exemplar itself: resynthesising it in 2D would tile its
        // layers away; the layered block synthesis copies from it by row.
        write_png(&dir.join(Output::Layers.file_name()), &ex.to_rgba())?;
    }
    if t.outputs.contains(&Output::Overlay) {
        let side = ex.width.min(ex.height) as f32;
        let scales: Vec<f32> = [0.0015, 0.0025, 0.004, 0.006]
            .iter()
            .map(|s| (s * side).max(1.0))
            .collect();
        // The photograph's vessels give the colour and coverage; a tree
        // grown on a torus gives vessels that tile (`vessel_tree`).
        let photo = vessels::overlay(&ex, &vessels::vesselness(&ex, &scales));
        let seed = t.synthesis.as_ref().map_or(0, |p| p.seed);
        let rgba = vessel_tree::tileable_overlay(&photo, ex.width, ex.height, seed);
        let raw = rgba.iter().flatten().copied().collect();
        // One overlay pixel per exemplar pixel, each side at most 16384.
        let img =
            image::RgbaImage::from_raw(ex.width as u32, ex.height as u32, raw).expect("sized");
        write_png(
            &dir.join(Output::Overlay.file_name()),
            &image::DynamicImage::ImageRgba8(img),
        )?;
    }
    let built = Built {
        id: t.id.clone(),
        fingerprint: fingerprint(db, t)?,
        outputs: t.outputs.clone(),
        usable_pixels: ex.valid.iter().filter(|&&v| v).count(),
        quality,
        lighting: lit,
        colour,
        seconds: start.elapsed().as_secs_f64(),
    };
    // Plain fields with string keys: serialising cannot fail.
    let report = serde_json::to_string_pretty(&built).expect("serialises");
    write_file(&dir.join("report.json"), |w| writeln!(w, "{report}"))?;
    Ok(built)
}

/// The colour statistics of built entry `id`'s colour texture.
pub fn stats_of(db: &Database, id: &str) -> Result<LabStats> {
    let path = db.output_path(id, Output::Colour);
    Ok(LabStats::of(
        &crate::synth::exemplar::read_image(&path)?.to_rgb8(),
    ))
}

/// Built entry `id`'s colour texture graded by `grading`, made once into
/// the entry's build folder (`graded/KEY.png`, named by a digest of the
/// grading and of the pixels it starts from) and reused after.
pub fn graded_colour(db: &Database, id: &str, grading: &Grading) -> Result<PathBuf> {
    let source = db.output_path(id, Output::Colour);
    let bytes = std::fs::read(&source).map_err(|e| Error::io(&source, e))?;
    let mut digest = crate::digest::Digest::default();
    // The recipe too: a change to the grading itself makes it again.
    digest.feed(&RECIPE.to_le_bytes());
    digest.feed(grading.key(id).as_bytes());
    digest.feed(&bytes);
    if let Some(m) = &grading.matched {
        let target = db.output_path(m, Output::Colour);
        digest.feed(&std::fs::read(&target).map_err(|e| Error::io(&target, e))?);
    }
    let path = db
        .root
        .join("build")
        .join(id)
        .join("graded")
        .join(format!("{}.png", digest.hex()));
    if path.is_file() {
        return Ok(path);
    }
    let img = crate::synth::exemplar::read_image(&source)?.to_rgb8();
    let transfer = match &grading.matched {
        Some(m) => Some((LabStats::of(&img), stats_of(db, m)?)),
        None => None,
    };
    let graded = Grade {
        hue: grading.hue,
        saturation: grading.saturation,
        brightness: grading.brightness,
        transfer,
    }
    .apply(&img);
    let dir = path.parent().expect("in a folder");
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_png(&path, &image::DynamicImage::ImageRgb8(graded))?;
    Ok(path)
}
