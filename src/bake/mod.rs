//! The bake: a scene file in, DIR/scene.glb, DIR/report.json,
//! DIR/preview.png (drawn by `crate::render`) and, for every node with an
//! interior, DIR/interior/NODE.nrrd out. Everything is computed in memory
//! first and the files are written last, each atomically, so a failed or
//! cancelled bake leaves DIR as it was.
//!
//! The contrast figures (how much seams and facet borders show) are
//! measured on what the output shows, blended and unblended, so the report
//! says what the blending buys: the baked atlases in atlas mode, the
//! layers a viewer blends otherwise.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::atomic::{write_file, write_png};
use crate::error::{Error, Result};
use crate::progress::{Beside, Progress, Span, both, check, timed};
use crate::scene::atlas::{self, Atlas};
use crate::scene::build::{BakedScene, FacetReport, build_prepared, prepare_scene};
use crate::scene::contrast::{Colours, Contrast, contrast};
use crate::scene::draw::DrawList;
use crate::scene::interior::InteriorLine;
use crate::scene::kept_unwrap;
use crate::scene::{file, gltf};

mod interior;

pub use interior::lap;

/// How a bake runs.
#[derive(Clone, Debug)]
pub struct BakeOptions {
    /// Write one baked atlas of this many texels square per facet instead
    /// of layered primitives.
    pub atlas: Option<usize>,
    /// Preview image size.
    pub preview: [usize; 2],
}

impl Default for BakeOptions {
    fn default() -> Self {
        BakeOptions {
            atlas: None,
            preview: [960, 720],
        }
    }
}

/// One facet's line of the report.
#[derive(Clone, Debug, Serialize)]
pub struct FacetLine {
    #[serde(flatten)]
    pub facet: FacetReport,
    /// Colour jump across seams over the jump beside them, as the output
    /// shows it (1: seams invisible; `scene::contrast`); null without
    /// seams.
    pub seam_contrast: Option<f64>,
    /// The same without seam bands and overlap rings.
    pub seam_contrast_unblended: Option<f64>,
    /// In atlas mode: its atlas's width and height, and the share of
    /// their texels the facet covers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas: Option<[usize; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas_texel_use: Option<f64>,
    /// In atlas mode: how far apart (sRGB, 0-255, root mean square) the
    /// two sides of its seams are in the atlas's filtering, as baked and
    /// after seam erasure (`scene::seam_erasure`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas_seam_mismatch: Option<[f64; 2]>,
}

/// The facet-border figures of one node.
#[derive(Clone, Debug, Serialize)]
pub struct BorderLine {
    pub node: String,
    pub border_contrast: Option<f64>,
    pub border_contrast_unblended: Option<f64>,
    /// Edges on facet borders.
    pub border_edges: usize,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    /// From the start until the surface is built (meshes, visibility,
    /// unwraps, bands and rings), the interiors running beside it.
    pub build_s: f64,
    /// Interiors (blocks, tets, LSTs), beside the surface.
    pub interior_s: f64,
    /// Atlases (in atlas mode) and contrast figures.
    pub contrast_s: f64,
    /// glTF encoding and preview.
    pub output_s: f64,
    pub total_s: f64,
    /// Each stage on each node and facet, in the order they ran (`organtex
    /// bake --profile` prints them).
    pub stages: Vec<Span>,
}

/// What report.json holds.
#[derive(Clone, Debug, Serialize)]
pub struct BakeReport {
    pub scene: String,
    pub source: PathBuf,
    /// "layered" or "atlas".
    pub mode: &'static str,
    /// Texels of the widest facet's atlas, in atlas mode (the others have
    /// the same texel density).
    pub atlas_size: Option<usize>,
    /// Atlas texels per mesh unit, in atlas mode.
    pub atlas_density: Option<f64>,
    /// The finest tissue texture's texels per mesh unit (its width over its
    /// tile size): an atlas below it blurs that tissue.
    pub texture_density: f64,
    /// The GPU adapter that drew preview.png (or tried to), "none" when
    /// there is none.
    pub preview_renderer: String,
    /// Why preview.png was not written; absent when it was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preview_error: Option<String>,
    pub facets: Vec<FacetLine>,
    pub borders: Vec<BorderLine>,
    pub interiors: Vec<InteriorLine>,
    /// The nodes meshed from a segmentation, each with what meshing it
    /// measured (as `organtex mesh --json` gives it); absent when none is.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub segmentations: Vec<SegmentationLine>,
    pub timings: Timings,
}

/// A node meshed from a CT or MRI segmentation.
#[derive(Clone, Debug, Serialize)]
pub struct SegmentationLine {
    pub node: String,
    pub mesh: crate::segment::MeshReport,
}

/// Where the bake wrote its files, and its report.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The folder baked into.
    pub dir: PathBuf,
    pub glb: PathBuf,
    pub report_json: PathBuf,
    /// None when no GPU adapter could draw it.
    pub preview: Option<PathBuf>,
    pub report: BakeReport,
}

/// Bake the scene file `scene` into `out` (created if missing).
pub fn bake(
    scene: &Path,
    out: &Path,
    opts: &BakeOptions,
    progress: &dyn Progress,
) -> Result<Baked> {
    if let Some(size) = opts.atlas
        && !(64..=16384).contains(&size)
    {
        return Err(Error::invalid(format!(
            "atlas size must be from 64 to 16384 texels, not {size}"
        )));
    }
    let start = Instant::now();
    let spec = file::load(scene)?;
    let prepared = prepare_scene(&spec, progress)?;

    // The interiors (block, tets, LST) need the nodes' meshes alone, and
    // the surface (unwraps, blending, then contrast, .glb, preview) nothing
    // of them: the two run side by side from here, the surface on the
    // cores the LST leaves idle between its batches. The interiors show
    // their progress; the surface's stays quiet beside them. A failure of
    // either stops the other, and the surface's (the scene's own errors)
    // is the one reported.
    let t = Instant::now();
    let has_interiors = spec.nodes.iter().any(|n| n.interior.is_some());
    let failed = AtomicBool::new(false);
    let beside = |quiet| Beside {
        inner: progress,
        quiet,
        failed: &failed,
    };
    let (interior_progress, surface_progress) = (beside(false), beside(has_interiors));
    let (mut interior_spans, mut surface_spans) = (Vec::new(), Vec::new());
    let (interiors, surface) = rayon::join(
        || {
            let t = Instant::now();
            let interiors =
                interior::interiors(&prepared, out, &interior_progress, &mut interior_spans);
            failed.fetch_or(interiors.is_err(), Ordering::Relaxed);
            interiors.map(|i| (i, t.elapsed().as_secs_f64()))
        },
        || {
            let surface = (|| -> Result<_> {
                let baked = build_prepared(
                    &prepared,
                    opts.atlas.is_some(),
                    Some(out),
                    &surface_progress,
                )?;
                let build_s = start.elapsed().as_secs_f64();
                let surface = surface_outputs(&baked, opts, &surface_progress, &mut surface_spans)?;
                Ok((baked, build_s, surface))
            })();
            failed.fetch_or(surface.is_err(), Ordering::Relaxed);
            surface
        },
    );
    let ((mut baked, build_s, surface), (interiors, interior_s)) = both(surface, interiors)?;
    let Surface {
        blended,
        figures,
        glb,
        picture,
        preview_renderer,
        preview_error,
        contrast_s,
        output_s,
    } = surface;
    // The tissues and meshes, then what ran side by side under one line.
    let mut stages = prepared.spans;
    stages.push(Span {
        stage: "surface and interiors".into(),
        item: String::new(),
        seconds: t.elapsed().as_secs_f64(),
        parallel: false,
    });
    stages.extend(
        std::mem::take(&mut baked.spans)
            .into_iter()
            .chain(interior_spans)
            .chain(surface_spans)
            .map(|s| Span {
                parallel: true,
                ..s
            }),
    );
    check(progress)?;

    let mut facets = Vec::new();
    let mut borders = Vec::new();
    for (n, (node, (b, u))) in baked.nodes.iter().zip(&figures).enumerate() {
        for (k, facet) in node.facets.iter().enumerate() {
            let atlas = blended.as_ref().map(|(a, _)| &a[n][k]);
            facets.push(FacetLine {
                facet: facet.report.clone(),
                seam_contrast: b.seams[k],
                seam_contrast_unblended: u.seams[k],
                atlas: atlas.map(|a| [a.width, a.height]),
                atlas_texel_use: atlas.map(|a| a.texel_use),
                atlas_seam_mismatch: atlas.and_then(|a| a.seam_mismatch),
            });
        }
        borders.push(BorderLine {
            node: node.name.clone(),
            border_contrast: b.borders,
            border_contrast_unblended: u.borders,
            border_edges: b.border_edges,
        });
    }
    let report = BakeReport {
        scene: spec.name.clone(),
        source: scene.to_path_buf(),
        mode: if opts.atlas.is_some() {
            "atlas"
        } else {
            "layered"
        },
        atlas_size: opts.atlas,
        atlas_density: opts.atlas.map(|size| atlas::density(&baked.nodes, size)),
        texture_density: texture_density(&baked),
        preview_renderer,
        preview_error,
        facets,
        borders,
        interiors: interiors.iter().map(|i| i.line.clone()).collect(),
        segmentations: spec
            .nodes
            .iter()
            .zip(&prepared.segmented)
            .filter_map(|(node, report)| {
                report.clone().map(|mesh| SegmentationLine {
                    node: node.name.clone(),
                    mesh,
                })
            })
            .collect(),
        timings: Timings {
            build_s,
            interior_s,
            contrast_s,
            output_s,
            total_s: start.elapsed().as_secs_f64(),
            stages,
        },
    };

    // Each facet's unwrap, kept for the next bake here: those made now
    // (the reused ones are in place already).
    let mut kept_paths = Vec::new();
    let mut kept = Vec::new();
    for (n, node) in baked.nodes.iter().enumerate() {
        for facet in &node.facets {
            let path = kept_unwrap::path(out, n, facet.piece.facet);
            if !facet.unwrap_reused {
                kept.push((path.clone(), facet.kept_unwrap()));
            }
            kept_paths.push(path);
        }
    }

    // The files, the interiors' (tens of MB for an LST) the larger part.
    progress.stage("writing", 2);
    check(progress)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let baked = Baked {
        dir: out.to_path_buf(),
        glb: out.join("scene.glb"),
        report_json: out.join("report.json"),
        preview: picture.as_ref().map(|_| out.join("preview.png")),
        report,
    };
    write_file(&baked.glb, |w| w.write_all(&glb))?;
    let json = serde_json::to_string_pretty(&baked.report).expect("the report serialises");
    write_file(&baked.report_json, |w| writeln!(w, "{json}"))?;
    if let (Some(path), Some(picture)) = (&baked.preview, picture) {
        write_png(path, &image::DynamicImage::ImageRgb8(picture))?;
    }
    progress.advance(1);
    interior::write(&interiors, out)?;
    // Best effort: a facet whose unwrap could not be kept (a full disk, a
    // file where the folder would go) is unwrapped again by the next bake;
    // the bake itself, whose files are written, has not failed.
    for (path, unwrap) in &kept {
        let _ = kept_unwrap::save(path, unwrap);
    }
    let _ = kept_unwrap::prune(out, &kept_paths);
    progress.advance(1);
    Ok(baked)
}

fn texture_density(scene: &BakedScene) -> f64 {
    scene
        .nodes
        .iter()
        .flat_map(|n| {
            n.facets.iter().zip(&n.compositor.looks).map(|(f, look)| {
                n.compositor.textures[look.colour].width as f64 / f.settings.tile_size
            })
        })
        .fold(0.0, f64::max)
}

/// Every facet's atlas, blended and unblended, per node.
type NodeAtlases = Vec<Vec<Atlas>>;

fn atlases(
    scene: &BakedScene,
    size: usize,
    progress: &dyn Progress,
) -> Result<(NodeAtlases, NodeAtlases)> {
    let count: usize = scene.nodes.iter().map(|n| n.facets.len()).sum();
    progress.stage("atlases", 2 * count as u64);
    let mut blended = Vec::new();
    let mut unblended = Vec::new();
    let density = atlas::density(&scene.nodes, size);
    for node in &scene.nodes {
        let pairs: Vec<(Atlas, Atlas)> = node
            .facets
            .par_iter()
            .map(|facet| {
                let b = atlas::bake(node, facet, &node.compositor, density, size);
                progress.advance(1);
                let u = atlas::bake(node, facet, &node.unblended, density, size);
                progress.advance(1);
                (b, u)
            })
            .collect();
        check(progress)?;
        let (mut b, u): (Vec<Atlas>, Vec<Atlas>) = pairs.into_iter().unzip();
        // The blended atlases' seams and borders joined in their filtering
        // too; the unblended ones, which the contrast figures compare
        // against, are left as baked.
        crate::scene::seam_erasure::erase(node, &mut b);
        blended.push(b);
        unblended.push(u);
    }
    Ok((blended, unblended))
}

/// The preview, the adapter that drew it (or "none") and, when it could
/// not be drawn, why.
#[cfg(feature = "render")]
fn draw_preview(
    baked: &BakedScene,
    list: &DrawList,
    [w, h]: [usize; 2],
) -> (Option<image::RgbImage>, String, Option<String>) {
    match crate::render::Gpu::headless() {
        Ok(gpu) => match crate::render::preview(&gpu, baked, list, [w as u32, h as u32]) {
            Ok(picture) => (Some(picture), gpu.adapter, None),
            Err(e) => (None, gpu.adapter, Some(e.to_string())),
        },
        Err(e) => (None, "none".into(), Some(e.to_string())),
    }
}

#[cfg(not(feature = "render"))]
fn draw_preview(
    _: &BakedScene,
    _: &DrawList,
    _: [usize; 2],
) -> (Option<image::RgbImage>, String, Option<String>) {
    let why = "organtex was built without its renderer (feature `render`)";
    (None, "none".into(), Some(why.into()))
}

/// What the surface's outputs made (`bake`, beside the interiors).
struct Surface {
    blended: Option<(NodeAtlases, NodeAtlases)>,
    figures: Vec<(Contrast, Contrast)>,
    glb: Vec<u8>,
    picture: Option<image::RgbImage>,
    preview_renderer: String,
    preview_error: Option<String>,
    contrast_s: f64,
    output_s: f64,
}

/// The atlases where asked, the seams' and borders' contrast, the .glb and
/// the preview, each step's time onto `stages`.
fn surface_outputs(
    baked: &BakedScene,
    opts: &BakeOptions,
    progress: &dyn Progress,
    stages: &mut Vec<Span>,
) -> Result<Surface> {
    let t = Instant::now();
    let blended = match opts.atlas {
        Some(size) => Some(timed(stages, "atlases", "", || {
            atlases(baked, size, progress)
        })?),
        None => None,
    };
    let figures: Vec<(Contrast, Contrast)> = timed(stages, "contrast", "", || match &blended {
        Some((b, u)) => baked
            .nodes
            .iter()
            .zip(b.iter().zip(u))
            .map(|(node, (b, u))| {
                (
                    contrast(node, Colours::Atlases(b)),
                    contrast(node, Colours::Atlases(u)),
                )
            })
            .collect(),
        // Blended and unblended side by side: a scene of one node gets
        // both cores too.
        None => baked
            .nodes
            .par_iter()
            .map(|node| {
                rayon::join(
                    || contrast(node, Colours::Layers(&node.compositor)),
                    || contrast(node, Colours::Layers(&node.unblended)),
                )
            })
            .collect(),
    });
    let contrast_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.stage("glb and preview", 2);
    let (list, glb) = timed(stages, "glb", "", || {
        let list = DrawList::of(baked, blended.as_ref().map(|(b, _)| b.as_slice()));
        gltf::encode(&list, &baked.spec.name, &baked.spec.cameras).map(|glb| (list, glb))
    })?;
    progress.advance(1);
    // The preview goes through the viewer's renderer. A machine with no
    // GPU adapter, or one that cannot draw it (a limit, memory, a driver
    // error), gets the bake without it, and the report says why.
    let (picture, preview_renderer, preview_error) = timed(stages, "preview", "", || {
        draw_preview(baked, &list, opts.preview)
    });
    progress.advance(1);
    Ok(Surface {
        blended,
        figures,
        glb,
        picture,
        preview_renderer,
        preview_error,
        contrast_s,
        output_s: t.elapsed().as_secs_f64(),
    })
}
