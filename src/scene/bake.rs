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
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::atlas::{self, Atlas};
use super::build::{BakedScene, FacetReport, build_scene};
use super::contrast::{Colours, Contrast, contrast};
use super::draw::DrawList;
use super::{file, gltf};
use crate::atomic::{write_file, write_png};
use crate::error::{Error, Result};
use crate::progress::{Progress, check};
use crate::solid::{InteriorMethod, interior_block};
use crate::synth::volume::Volume;

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

/// A node's interior block: a solid texture that tiles space from the
/// origin, one voxel `voxel_size` mesh units, for the simulator's cuts
/// (`solid::plane_section` with `Placement::new(origin 0, voxel_size)`).
#[derive(Clone, Debug, Serialize)]
pub struct InteriorLine {
    pub node: String,
    /// The tissue it was synthesised from.
    pub texture: String,
    /// How the block was made.
    pub method: InteriorMethod,
    /// Relative to the bake's folder.
    pub file: PathBuf,
    pub voxels: usize,
    pub voxel_size: f64,
    /// The node's inside as tetrahedra, when `tet_mesh = true`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tet_mesh: Option<TetLine>,
    /// The lapped solid texture, when `[node.interior.lst]` is given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lst: Option<LstLine>,
    /// The morph, when `method = "morph"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub morph: Option<MorphLine>,
}

/// A node's interior morphed from photographed cuts (seed 003). Its block
/// is the morph sampled over the node's bounding cube, placed at
/// `block_origin` (it does not tile); the sections file and photographs
/// are copied beside it for a simulator to morph cuts on demand
/// (`solid::morph::Morph`).
#[derive(Clone, Debug, Serialize)]
pub struct MorphLine {
    /// The copied sections file, relative to the bake's folder.
    pub sections: PathBuf,
    /// Photographs (exemplar planes) and the regions they split it into.
    pub exemplars: usize,
    pub regions: usize,
    /// Where the block's corner lies (its voxels span `voxel_size`).
    pub block_origin: [f64; 3],
    /// BSP, sweeps and warps.
    pub precompute_s: f64,
}

/// A node's lapped solid texture (`[node.interior.lst]`).
#[derive(Clone, Debug, Serialize)]
pub struct LstLine {
    /// The model (.lst, its tet mesh inside), relative to the bake's
    /// folder; its exemplar is the node's block.
    pub file: PathBuf,
    #[serde(rename = "type")]
    pub kind: &'static str,
    pub tets: usize,
    pub bytes: u64,
    /// Of the tets outside every region.
    #[serde(flatten)]
    pub stats: crate::solid::lst::FillStats,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<LstRegionLine>,
    pub seconds: f64,
}

/// A region of a lapped solid texture (`[[node.interior.lst.region]]`).
#[derive(Clone, Debug, Serialize)]
pub struct LstRegionLine {
    pub facet: String,
    #[serde(rename = "type")]
    pub kind: &'static str,
    pub tets: usize,
    #[serde(flatten)]
    pub stats: crate::solid::lst::FillStats,
}

/// A node's tetrahedral mesh (`[node.interior] tet_mesh = true`).
#[derive(Clone, Debug, Serialize)]
pub struct TetLine {
    /// Legacy VTK, relative to the bake's folder.
    pub file: PathBuf,
    pub vertices: usize,
    pub tets: usize,
    pub min_dihedral: f64,
    pub max_dihedral: f64,
    /// Two-sided Hausdorff distance of its boundary to the node's surface,
    /// over the surface's bounding box diagonal.
    pub hausdorff_relative: Option<f64>,
}

/// One facet's line of the report.
#[derive(Clone, Debug, Serialize)]
pub struct FacetLine {
    #[serde(flatten)]
    pub facet: FacetReport,
    /// Colour jump across seams over that across ordinary edges, as the
    /// output shows it (1: seams invisible); null without seams.
    pub seam_contrast: Option<f64>,
    /// The same without seam bands and overlap rings.
    pub seam_contrast_unblended: Option<f64>,
    /// In atlas mode: its atlas's width and height, and the share of
    /// their texels the facet covers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas: Option<[usize; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas_texel_use: Option<f64>,
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
    /// Meshes, visibility, unwraps, bands and rings.
    pub build_s: f64,
    /// Interior blocks.
    pub interior_s: f64,
    /// Atlases (in atlas mode) and contrast figures.
    pub contrast_s: f64,
    /// glTF encoding and preview.
    pub output_s: f64,
    pub total_s: f64,
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
    pub timings: Timings,
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
    let baked = build_scene(&spec, opts.atlas.is_some(), progress)?;
    let build_s = start.elapsed().as_secs_f64();

    let t = Instant::now();
    let interiors = interiors(&baked, progress)?;
    let interior_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let blended = match opts.atlas {
        Some(size) => Some(atlases(&baked, size, progress)?),
        None => None,
    };
    let figures: Vec<(Contrast, Contrast)> = match &blended {
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
        None => baked
            .nodes
            .par_iter()
            .map(|node| {
                (
                    contrast(node, Colours::Layers(&node.compositor)),
                    contrast(node, Colours::Layers(&node.unblended)),
                )
            })
            .collect(),
    };
    let contrast_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.stage("writing", 2);
    let list = DrawList::of(&baked, blended.as_ref().map(|(b, _)| b.as_slice()));
    let glb = gltf::encode(&list, &spec.name)?;
    progress.advance(1);
    // The preview goes through the viewer's renderer. A machine with no
    // GPU adapter, or one that cannot draw it (a limit, memory, a driver
    // error), gets the bake without it, and the report says why.
    let [w, h] = opts.preview;
    let (picture, preview_renderer, preview_error) = draw_preview(&baked, &list, [w, h]);
    progress.advance(1);
    check(progress)?;
    let output_s = t.elapsed().as_secs_f64();

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
        timings: Timings {
            build_s,
            interior_s,
            contrast_s,
            output_s,
            total_s: start.elapsed().as_secs_f64(),
        },
    };

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
    for interior in &interiors {
        let path = out.join(&interior.line.file);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        // A layered block's y axis is depth: the header says so, for the
        // LST reader and other tools.
        let depth_axis = (interior.line.method == InteriorMethod::Layered).then_some(1);
        interior.volume.write_nrrd_with_depth(&path, depth_axis)?;
        if let (Some(line), Some(tets)) = (&interior.line.tet_mesh, &interior.tets) {
            crate::tetra::io::write_vtk(&out.join(&line.file), tets)?;
        }
        if let (Some(line), Some(model)) = (&interior.line.lst, &interior.lst) {
            model.write(&out.join(&line.file))?;
        }
        if let (Some(line), Some(sections)) = (&interior.line.morph, &interior.sections) {
            let dir = out.join(&line.sections);
            crate::solid::morph::copy_sections(sections, dir.parent().unwrap_or(out))?;
        }
    }
    Ok(baked)
}

/// Every node's interior block, synthesised from its tissue's colour
/// texture (seed 004, 3.3) or layered exemplar (seed 002, 4.2),
/// `[bake] interior_voxels` a side.
fn interiors(scene: &BakedScene, progress: &dyn Progress) -> Result<Vec<Interior>> {
    let n = scene.spec.bake.interior_voxels;
    let mut out = Vec::new();
    for (k, node) in scene.spec.nodes.iter().enumerate() {
        let Some(interior) = &node.interior else {
            continue;
        };
        if interior.method == InteriorMethod::Morph {
            out.push(morphed(scene, k, interior, n, &out, progress)?);
            continue;
        }
        let built = scene.tissues.of(interior.method.output());
        let texture = built.get(&interior.texture).ok_or_else(|| {
            Error::invalid(format!(
                "node '{}': interior texture '{}' was not built",
                node.name, interior.texture
            ))
        })?;
        let mut volume = interior_block(
            texture,
            &interior.photographs,
            n,
            interior.method,
            k as u64,
            progress,
        )
        .map_err(|e| match e {
            // Ctrl-C is not the node's fault.
            Error::Cancelled => e,
            e => Error::invalid(format!("node '{}': interior: {e}", node.name)),
        })?;
        volume.spacing = interior.block_size / n as f64;
        // Names distinct as nodes may meet as file names ("a b", "a_b").
        let file = interior_file(&node.name, k, &out);
        let tets = if interior.tet_mesh || interior.lst.is_some() {
            Some(tet_mesh(&scene.nodes[k].mesh, &file, &node.name, progress)?)
        } else {
            None
        };
        let lst = match (&interior.lst, &tets) {
            (Some(spec), Some((_, tet_mesh))) => Some(lapped(
                spec,
                &scene.nodes[k].mesh,
                tet_mesh,
                interior.block_size,
                &file,
                k as u64,
                &node.name,
                progress,
            )?),
            _ => None,
        };
        out.push(Interior {
            line: InteriorLine {
                node: node.name.clone(),
                texture: interior.texture.clone(),
                method: interior.method,
                file,
                voxels: n,
                voxel_size: volume.spacing,
                tet_mesh: tets
                    .as_ref()
                    .filter(|_| interior.tet_mesh)
                    .map(|(line, _)| line.clone()),
                lst: lst.as_ref().map(|(line, _)| line.clone()),
                morph: None,
            },
            volume,
            tets: tets.map(|(_, m)| m),
            lst: lst.map(|(_, m)| m),
            sections: None,
        });
    }
    Ok(out)
}

/// interior/NODE.nrrd, the name made distinct from those already taken
/// (nodes "a b" and "a_b" meet as file names).
fn interior_file(node: &str, k: usize, taken: &[Interior]) -> PathBuf {
    let mut stem = file_name(node);
    if taken
        .iter()
        .any(|i| i.line.file.file_stem() == Some(std::ffi::OsStr::new(&stem)))
    {
        stem = format!("{stem}-{k}");
    }
    PathBuf::from("interior").join(format!("{stem}.nrrd"))
}

/// Node `k`'s interior morphed from its sections (seed 003): precomputed,
/// sampled into an `n`-voxel block over its bounding cube.
fn morphed(
    scene: &BakedScene,
    k: usize,
    interior: &crate::scene::file::Interior,
    n: usize,
    taken: &[Interior],
    progress: &dyn Progress,
) -> Result<Interior> {
    use crate::solid::morph::{Morph, MorphOptions};
    let name = &scene.spec.nodes[k].name;
    let err = |e: Error| match e {
        Error::Cancelled => e,
        e => Error::invalid(format!("node '{name}': interior: {e}")),
    };
    // Checked when the scene loaded: a morph names its sections file.
    let sections = interior.sections.clone().expect("a morph has sections");
    let mesh = &scene.nodes[k].mesh;
    let topology = crate::mesh::Topology::build(mesh).map_err(err)?;
    let t = Instant::now();
    let morph = Morph::read(
        mesh,
        &topology,
        &sections,
        MorphOptions::default(),
        progress,
    )
    .map_err(err)?;
    let precompute_s = t.elapsed().as_secs_f64();
    let (lo, hi) = mesh
        .bounding_box()
        .ok_or_else(|| err(Error::invalid("the mesh has no vertices")))?;
    let (volume, placement) = morph.block(lo, hi, n).map_err(err)?;
    let file = interior_file(name, k, taken);
    let copied = file.with_file_name(format!(
        "{}-sections",
        file.file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into())
    ));
    Ok(Interior {
        line: InteriorLine {
            node: name.clone(),
            texture: interior.texture.clone(),
            method: interior.method,
            file,
            voxels: n,
            voxel_size: placement.scale,
            tet_mesh: None,
            lst: None,
            morph: Some(MorphLine {
                sections: copied.join("sections.toml"),
                exemplars: morph.exemplars().len(),
                regions: morph.regions(),
                block_origin: lo.to_array(),
                precompute_s,
            }),
        },
        volume,
        tets: None,
        lst: None,
        sections: Some(sections),
    })
}

/// The node's inside as tetrahedra at the default resolution, and its
/// report line (the file beside the block, as .vtk).
fn tet_mesh(
    mesh: &crate::mesh::TriMesh,
    block_file: &Path,
    node: &str,
    progress: &dyn Progress,
) -> Result<(TetLine, crate::tetra::TetMesh)> {
    let (tets, report) =
        crate::tetra::tetrahedralise_report(mesh, &crate::tetra::TetOptions::default(), progress)
            .map_err(|e| Error::invalid(format!("node '{node}': tet mesh: {e}")))?;
    let quality = tets.quality();
    let line = TetLine {
        file: block_file.with_extension("vtk"),
        vertices: tets.num_vertices(),
        tets: tets.num_tets(),
        min_dihedral: quality.min_dihedral,
        max_dihedral: quality.max_dihedral,
        hausdorff_relative: report.hausdorff.map(|h| h.relative()),
    };
    Ok((line, tets))
}

/// The node's lapped solid texture (`[node.interior.lst]`) and its
/// report line.
#[allow(clippy::too_many_arguments)]
fn lapped(
    spec: &crate::scene::file::LstSpec,
    surface: &crate::mesh::TriMesh,
    tets: &crate::tetra::TetMesh,
    block_size: f64,
    block_file: &Path,
    seed: u64,
    node: &str,
    progress: &dyn Progress,
) -> Result<(LstLine, crate::solid::lst::LstModel)> {
    let start = std::time::Instant::now();
    let (model, stats, regions) = lap(spec, surface, tets, block_size, seed, node, progress)?;
    let line = LstLine {
        file: block_file.with_extension("lst"),
        kind: model.kind.name(),
        tets: tets.num_tets(),
        bytes: model.file_size(),
        stats,
        regions,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((line, model))
}

/// Lap a node's block through its tets as `[node.interior.lst]` asks
/// (the bake's and the viewer's cut plane's): the model, the stats of
/// the tets outside every region, and each region's line. Errors name
/// the node.
pub fn lap(
    spec: &crate::scene::file::LstSpec,
    surface: &crate::mesh::TriMesh,
    tets: &crate::tetra::TetMesh,
    block_size: f64,
    seed: u64,
    node: &str,
    progress: &dyn Progress,
) -> Result<(
    crate::solid::lst::LstModel,
    crate::solid::lst::FillStats,
    Vec<LstRegionLine>,
)> {
    use crate::solid::lst;
    let err = |e: Error| Error::invalid(format!("node '{node}': [node.interior.lst]: {e}"));
    let kind = lst::TextureType::parse(&spec.kind).map_err(err)?;
    let (depth_outer, depth_inner) = match (&spec.depth_outer, &spec.depth_inner) {
        (Some(o), Some(i)) => lst::facet_depth_points(surface, o, i).map_err(err)?,
        (None, None) if !kind.needs_depth() => (Vec::new(), Vec::new()),
        _ => {
            return Err(err(Error::invalid(format!(
                "type {} needs depth_outer and depth_inner (two facets)",
                kind.name()
            ))));
        }
    };
    let scale = spec.scale.unwrap_or(block_size);
    let opts = lst::LstOptions {
        kind,
        scale,
        strokes: spec
            .strokes
            .iter()
            .map(|s| s.iter().map(|&p| glam::DVec3::from_array(p)).collect())
            .collect(),
        depth_outer,
        depth_inner,
        seed,
    };
    let wanted = spec
        .regions
        .iter()
        .map(|r| {
            Ok(lst::regions::FacetRegion {
                facet: r.facet.clone(),
                kind: lst::TextureType::parse(&r.kind)?,
                scale: r.scale.unwrap_or(scale),
                strokes: r
                    .strokes
                    .iter()
                    .map(|s| s.iter().map(|&p| glam::DVec3::from_array(p)).collect())
                    .collect(),
            })
        })
        .collect::<Result<Vec<_>>>()
        .map_err(err)?;
    let regions = lst::regions::facet_regions(surface, tets, &wanted, seed).map_err(err)?;
    let (model, mut stats) = lst::fill_regions(tets, &opts, &regions, progress).map_err(err)?;
    let main = stats.remove(0);
    let lines = regions
        .iter()
        .zip(stats)
        .map(|(r, stats)| LstRegionLine {
            facet: r.name.clone(),
            kind: r.options.kind.name(),
            tets: r.tets.len(),
            stats,
        })
        .collect();
    Ok((model, main, lines))
}

/// A node's interior as baked: its report line, block, tet mesh and
/// lapped solid texture.
struct Interior {
    line: InteriorLine,
    volume: Volume,
    tets: Option<crate::tetra::TetMesh>,
    lst: Option<crate::solid::lst::LstModel>,
    /// A morph's sections file, copied beside the block.
    sections: Option<PathBuf>,
}

/// A node name as a file name: letters, digits, '-' and '_' kept, the rest
/// '_'.
fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
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
        let (b, u) = pairs.into_iter().unzip();
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
