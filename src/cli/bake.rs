//! `organtex bake SCENE -o DIR [--atlas SIZE]`, or `organtex bake
//! --manifest LIST --index N -o DIR` (the N-th scene into DIR/NAME/).

use std::path::PathBuf;

use organtex::Result;
use organtex::bake::{BakeOptions, Baked, bake};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// Scene file (.toml; format in scenes/README.md).
    #[arg(required_unless_present = "manifest", conflicts_with = "manifest")]
    scene: Option<PathBuf>,
    /// A list of scenes, one path per line (relative to the list; blank
    /// and # lines skipped), for job arrays: with --index N, bake the N-th
    /// (from 0) into DIR/NAME/, NAME its file name without .toml, e.g.
    /// `--index $SLURM_ARRAY_TASK_ID` or `$JOB_COMPLETION_INDEX`.
    #[arg(long, value_name = "LIST", requires = "index")]
    manifest: Option<PathBuf>,
    /// Which scene of --manifest to bake (from 0).
    #[arg(long, value_name = "N", requires = "manifest")]
    index: Option<usize>,
    /// Folder for scene.glb, report.json, preview.png, interior/ and
    /// unwraps/ (created if missing; files already there are replaced only
    /// when the bake succeeds; interiors and unwraps a bake there made from
    /// the same inputs are taken, not made again).
    #[arg(short, long, value_name = "DIR")]
    output: PathBuf,
    /// Bake each facet into one texture with the seam blend, facet blend
    /// and overlay composited in, for engines that draw no alpha layers: one
    /// texel density across the scene, the widest facet's longer side SIZE
    /// texels, each atlas as wide and tall as its charts. Without it, the .glb holds tiled tissue textures with
    /// KHR_texture_transform and blended layers with vertex alpha.
    #[arg(long, value_name = "SIZE", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(64..=16384))]
    atlas: Option<u32>,
    /// Print where the time went: seconds per stage, per node and per
    /// facet (report.json's timings.stages holds the same).
    #[arg(long)]
    profile: bool,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(size) = args.atlas {
        // At least the widest facet's atlas, blended and unblended, and its
        // per-texel search buffer: 14 bytes a texel.
        let side = size as u64;
        organtex::memory::ensure_fits(
            &format!("--atlas {size} (one facet's {size}x{size} atlas)"),
            organtex::memory::product(&[side, side, 14]),
        )?;
    }
    let (scene, output) = match (&args.scene, &args.manifest, args.index) {
        (Some(scene), _, _) => (scene.clone(), args.output.clone()),
        (None, Some(list), Some(index)) => {
            organtex::scene::manifest::entry(list, index, &args.output)?
        }
        _ => unreachable!("clap requires a scene or --manifest with --index"),
    };
    bake_and_print(
        &scene,
        &output,
        args.atlas.map(|s| s as usize),
        args.profile,
    )
}

pub fn bake_and_print(
    scene: &std::path::Path,
    out: &std::path::Path,
    atlas: Option<usize>,
    profile: bool,
) -> Result<()> {
    let opts = BakeOptions {
        atlas,
        ..BakeOptions::default()
    };
    let bars = Bars::new();
    let result = bake(scene, out, &opts, &bars);
    bars.finish();
    let baked = result?;
    print(&baked);
    if profile {
        print_profile(&baked.report.timings);
    }
    Ok(())
}

/// The bake's stages as a table, the work done in parallel indented under
/// the stage that ran it.
fn print_profile(t: &organtex::bake::Timings) {
    println!("where the time went ({:.1} s in all):", t.total_s);
    println!(
        "  {:<34} {:<28} {:>8} {:>6}",
        "stage", "on", "seconds", "share"
    );
    for s in &t.stages {
        let stage = if s.parallel {
            format!("  {} (in parallel)", s.stage)
        } else {
            s.stage.clone()
        };
        let share = if s.parallel {
            String::new()
        } else {
            format!("{:.0}%", 100.0 * s.seconds / t.total_s.max(1e-9))
        };
        println!("  {stage:<34} {:<28} {:>8.2} {share:>6}", s.item, s.seconds);
    }
    let listed: f64 = t
        .stages
        .iter()
        .filter(|s| !s.parallel)
        .map(|s| s.seconds)
        .sum();
    println!(
        "  {:<34} {:<28} {:>8.2} {:>5.0}%",
        "(reading, checks, the rest)",
        "",
        (t.total_s - listed).max(0.0),
        100.0 * (t.total_s - listed).max(0.0) / t.total_s.max(1e-9)
    );
}

fn figure(x: Option<f64>) -> String {
    x.map_or("-".into(), |x| format!("{x:.2}"))
}

fn print(baked: &Baked) {
    let r = &baked.report;
    println!(
        "scene {} ({} mode), baked in {:.1} s",
        r.scene, r.mode, r.timings.total_s
    );
    for s in &r.segmentations {
        let m = &s.mesh;
        println!(
            "  node '{}' meshed from its segmentation: {}",
            s.node,
            m.summary()
        );
        if let Some(h) = &m.handles {
            println!(
                "    handles thinner than {} mm: genus {} -> {}",
                h.max_handle, h.genus_before, h.genus_after
            );
        }
    }
    println!(
        "  {:<24} {:<16} {:>7} {:>6} {:>8} {:>7} {:>10}",
        "facet", "tissue", "faces", "charts", "seam", "conf", "seam blend"
    );
    for f in &r.facets {
        println!(
            "  {:<24} {:<16} {:>7} {:>6} {:>8.1} {:>7.3} {:>5} <- {}",
            format!("{}/{}", f.facet.node, f.facet.facet),
            f.facet.texture,
            f.facet.faces,
            f.facet.charts,
            f.facet.seam_length,
            f.facet.metrics.conf_mean,
            figure(f.seam_contrast),
            figure(f.seam_contrast_unblended),
        );
    }
    for b in &r.borders {
        if b.border_contrast.is_some() {
            println!(
                "  {} facet borders ({} edges): contrast {} (unblended {})",
                b.node,
                b.border_edges,
                figure(b.border_contrast),
                figure(b.border_contrast_unblended)
            );
        }
    }
    println!(
        "  contrast: colour jump across seams/borders over the jump beside them (1 = invisible)"
    );
    let atlases: Vec<String> = r
        .facets
        .iter()
        .filter_map(|f| {
            let ([w, h], used) = (f.atlas?, f.atlas_texel_use?);
            Some(format!("{} {w}x{h} {:.0}%", f.facet.facet, 100.0 * used))
        })
        .collect();
    if !atlases.is_empty() {
        println!(
            "  atlases (texels the facet covers): {}",
            atlases.join(", ")
        );
    }
    let erased: Vec<String> = r
        .facets
        .iter()
        .filter_map(|f| {
            let [baked, erased] = f.atlas_seam_mismatch?;
            Some(format!("{} {baked:.2} -> {erased:.2}", f.facet.facet))
        })
        .collect();
    if !erased.is_empty() {
        println!(
            "  seams erased (their two sides' colours apart in the atlas, of 255): {}",
            erased.join(", ")
        );
    }
    if let Some(density) = r.atlas_density
        && density < r.texture_density / 2.0
    {
        let size = r.atlas_size.unwrap_or(0) as f64 * r.texture_density / density;
        println!(
            "  note: the atlases hold {density:.1} texels per unit, the finest tissue texture {:.1}: it is blurred (--atlas {} keeps its detail)",
            r.texture_density,
            // Within what --atlas accepts (and no overflow when density is
            // tiny).
            (size as usize).clamp(64, 16384).next_power_of_two()
        );
    }
    println!("wrote {}", baked.glb.display());
    println!("      {}", baked.report_json.display());
    match &baked.preview {
        Some(p) => println!("      {}", p.display()),
        None => eprintln!(
            "warning: preview.png not written: {}",
            r.preview_error.as_deref().unwrap_or("no reason given")
        ),
    }
    for i in &r.interiors {
        let from = match &i.morph {
            Some(m) => format!(
                "morphed from {} photographed cuts in {} regions, placed at {:?}, not tiling",
                m.exemplars, m.regions, m.block_origin
            ),
            None => format!("from {}", i.texture),
        };
        println!(
            "      {} ({} interior: {}^3 voxels of {:.4} units, {from})",
            baked.dir.join(&i.file).display(),
            i.node,
            i.voxels,
            i.voxel_size,
        );
        if let Some(m) = &i.morph {
            println!(
                "      {} (the cuts, for morphing any surface on demand: organtex morph)",
                baked.dir.join(&m.sections).display()
            );
        }
        if let Some(t) = &i.tet_mesh {
            println!(
                "      {} ({} tets, dihedral angles {:.1} to {:.1} degrees)",
                baked.dir.join(&t.file).display(),
                super::thousands(t.tets),
                t.min_dihedral,
                t.max_dihedral
            );
        }
        if let Some(l) = &i.lst {
            println!(
                "      {} (lapped solid texture, type {}: {} patches over {} tets, {:.1} MB, {:.1} s)",
                baked.dir.join(&l.file).display(),
                l.kind,
                l.stats.patches,
                super::thousands(l.tets),
                l.bytes as f64 / 1e6,
                l.seconds
            );
            for r in &l.regions {
                println!(
                    "        region '{}', type {}: {} patches over {} tets",
                    r.facet,
                    r.kind,
                    r.stats.patches,
                    super::thousands(r.tets)
                );
            }
        }
    }
}
