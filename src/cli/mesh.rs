//! `organtex mesh VOLUME (--label N | --segment NAME | --threshold T) -o OUT.obj|.ply|.stl
//! [--faces N] [--smooth K] [--smoother taubin|sinc] [--max-handle MM] [--all-components] [--fill-voids] [--json]`: one region of a CT or MRI
//! segmentation as a closed, manifold surface in the scanner's millimetres.

use std::path::PathBuf;
use std::time::Instant;

use organtex::Result;
use organtex::segment::{self, Choice, MeshOptions};
use serde::Serialize;

use super::progress::Bars;

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("region").required(true).args(["label", "segment", "threshold"])))]
pub struct Args {
    /// The segmentation: a NIfTI-1 label map or probability map (.nii,
    /// .nii.gz; placed by its sform, else qform) or a NRRD label map (.nrrd,
    /// .nhdr, 3D Slicer's .seg.nrrd; placed by its space directions and
    /// origin). Either lands in RAS millimetres, as 3D Slicer shows them.
    volume: PathBuf,
    /// The surface: .obj, .ply or .stl (binary), in world millimetres.
    #[arg(short, long)]
    output: PathBuf,
    /// The region is the voxels of this label (a label map).
    #[arg(long, allow_negative_numbers = true)]
    label: Option<i64>,
    /// The region is this segment of a 3D Slicer segmentation (.seg.nrrd),
    /// by name (its layer and label value come from the file).
    #[arg(long, value_name = "NAME")]
    segment: Option<String>,
    /// The region is the voxels at or above this value (a probability map
    /// at 0.5, or a grey volume), its surface interpolated between voxels.
    #[arg(long, allow_negative_numbers = true)]
    threshold: Option<f64>,
    /// Smoothing iterations (--smoother): takes the voxel staircase away
    /// without shrinking the region (the windowed sinc from about 10);
    /// 0 keeps the raw surface.
    #[arg(long, default_value_t = segment::DEFAULT_SMOOTH as u32, value_parser = clap::value_parser!(u32).range(0..=10_000))]
    smooth: u32,
    /// Keep every piece of the region (default: the largest, by voxels,
    /// with its enclosed voids); only a piece finer than the scan
    /// resolves is dropped: under a voxel as marched (a probability map's
    /// voxel a hair over the threshold, a lone voxel of a label) and under
    /// a sixteenth of a voxel smoothed.
    #[arg(long)]
    all_components: bool,
    /// Fill the enclosed voids of the kept pieces (a ventricle inside the
    /// white matter, a cyst inside an organ). Default: each void is kept
    /// as an inner shell of the surface, facing into it, so the enclosed
    /// volume is the tissue's; only a void whose shell, smoothed, encloses
    /// under a sixteenth of a voxel (a probability map's voxel just under
    /// the threshold, a void of a voxel or two), finer than the scan
    /// resolves, is filled.
    #[arg(long)]
    fill_voids: bool,
    /// Decimate to at most this many faces: quadric error edge collapses
    /// that keep the surface closed, manifold and of the same genus, no
    /// angle made smaller than 20 degrees (default: every face marching
    /// cubes made, about two per boundary voxel face).
    #[arg(long, value_parser = clap::value_parser!(u64).range(4..=1_000_000_000))]
    faces: Option<u64>,
    /// How the staircase is smoothed: taubin (lambda/mu; safe on thin
    /// sheets such as the white matter's gyri) or sinc (a windowed sinc,
    /// the filter VTK and 3D Slicer smooth with, pass band 0.1 unmoved:
    /// much smoother and nearer the voxels on a compact organ such as the
    /// brain or a liver, but it pulls the sides of thin sheets through
    /// each other; give it 10 iterations or more).
    #[arg(long, value_enum, default_value = "taubin")]
    smoother: SmootherArg,
    /// Cut or plug the region's handles thinner than this many mm before
    /// meshing: a bridge of tissue thinner than MM across a gap is cut, a
    /// tunnel narrower than MM is plugged, each by the fewest voxels
    /// (Wood et al. 2004's cut-or-fill, found by morphology and simple
    /// points), and only where it lowers the genus: pieces and voids stay.
    /// The genus before and after is reported. Default: the region's
    /// topology as it is.
    #[arg(long, value_name = "MM", value_parser = super::positive_length, allow_negative_numbers = true)]
    max_handle: Option<f64>,
    /// Decimate with every corner of the region's voxel boundary held
    /// within VOXELS of the surface (0.9 if none is given, the least any
    /// surface can hold; the surface is then first drawn to them), not
    /// only each round of collapses near the surface it was given: thin
    /// crests such as the white matter's gyri are kept at the face budget.
    /// At 0.9 the last fit holds every point of the voxel faces, not only
    /// their corners, and draws the surface back where it strays from
    /// them. On the MNI white matter at 50,000 faces, 0.9 keeps the
    /// surface and its voxel faces within a voxel of each other both ways
    /// (0.99 / 0.98; by default 1.14 / 2.57) but leaves it as rough as the
    /// undecimated surface (spread of mean curvature 0.50 against 0.31)
    /// and takes about 4 s more; 1.4 keeps the voxel faces within 1.44 and
    /// is as smooth as the default (0.30), 1 s more. Needs --faces.
    #[arg(long, value_name = "VOXELS", requires = "faces", num_args = 0..=1,
          default_missing_value = "0.9", value_parser = super::positive_length)]
    within_voxels: Option<f64>,
    /// Print the figures as JSON instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum SmootherArg {
    Taubin,
    Sinc,
}

impl From<SmootherArg> for segment::Smoother {
    fn from(s: SmootherArg) -> segment::Smoother {
        match s {
            SmootherArg::Taubin => segment::Smoother::Taubin,
            SmootherArg::Sinc => segment::Smoother::WindowedSinc,
        }
    }
}

/// What `--json` prints (and the text shows).
#[derive(Serialize)]
struct Figures {
    file: PathBuf,
    output: PathBuf,
    size: [usize; 3],
    #[serde(flatten)]
    report: segment::MeshReport,
    /// Per kept piece.
    genus: Vec<i64>,
    closed: bool,
    manifold: bool,
    /// "outward" when every face turns out of the region.
    normals: Option<&'static str>,
    seconds: f64,
}

pub fn run(args: Args) -> Result<()> {
    // clap requires one of the three.
    let choice = match (args.label, args.segment.clone(), args.threshold) {
        (Some(l), _, _) => Choice::Label(l),
        (_, Some(name), _) => Choice::Segment(name),
        (_, _, Some(t)) => Choice::Threshold(t),
        _ => unreachable!("clap requires --label, --segment or --threshold"),
    };
    organtex::mesh::io::output_format(&args.output)?;
    let start = Instant::now();
    let (volume, region) = segment::open(&args.volume, &choice)?;
    let opts = MeshOptions {
        region,
        smooth: args.smooth as usize,
        all_components: args.all_components,
        fill_voids: args.fill_voids,
        faces: args.faces.map(|f| f as usize),
        max_handle: args.max_handle,
        within_voxels: args.within_voxels,
        smoother: args.smoother.into(),
    };
    let bars = Bars::new();
    let (mesh, report) = segment::mesh(&volume, &args.volume, &opts, &bars)?;
    bars.finish();
    let analysis = organtex::mesh::info::analyse(mesh.clone(), false)?;
    let r = &analysis.report;
    organtex::mesh::io::write(&args.output, &mesh)?;
    let figures = Figures {
        file: args.volume.clone(),
        output: args.output.clone(),
        size: volume.size,
        report,
        genus: r.genus.clone(),
        closed: r.boundary_edges == 0,
        manifold: r.defects.non_manifold_edges == 0 && r.defects.non_manifold_vertices == 0,
        normals: r.normals,
        seconds: start.elapsed().as_secs_f64(),
    };
    if args.json {
        super::print_json(&figures);
        return Ok(());
    }
    let f = &figures;
    println!(
        "{}: {}x{}x{} voxels, {} in the region ({:.1} mm^3)",
        f.file.display(),
        f.size[0],
        f.size[1],
        f.size[2],
        super::thousands(f.report.region_voxels as usize),
        f.report.region_voxels as f64 * volume.voxel_volume()
    );
    if f.report.voids > 0 || f.report.components > f.report.components_kept {
        println!(
            "  meshed {} voxels ({:.1} mm^3; the largest piece unless --all-components); {} enclosed void{} {}",
            super::thousands(f.report.voxels as usize),
            f.report.voxel_volume,
            f.report.voids,
            if f.report.voids == 1 { "" } else { "s" },
            if f.report.voids_filled {
                "filled".to_string()
            } else if f.report.voids_unresolved > 0 {
                format!(
                    "kept as inner shells, but {} whose shells enclosed under a sixteenth of a voxel smoothed, finer than the scan resolves, filled (--fill-voids fills them all)",
                    f.report.voids_unresolved
                )
            } else {
                "kept as inner shells (--fill-voids fills them)".to_string()
            }
        );
    }
    if f.report.islands_unresolved > 0 {
        println!(
            "  dropped {} of the {} pieces, finer than the scan resolves: under a voxel as marched, under a sixteenth smoothed",
            f.report.islands_unresolved, f.report.components
        );
    }
    if let Some(h) = &f.report.handles {
        println!(
            "  handles thinner than {} mm: genus {} -> {} ({} cut, {} plugged; {} voxels removed, {} added)",
            h.max_handle,
            h.genus_before,
            h.genus_after,
            h.cut,
            h.filled,
            super::thousands(h.voxels_removed as usize),
            super::thousands(h.voxels_added as usize)
        );
    }
    println!(
        "  surface: {} vertices, {} faces, {} of {} piece{} kept, genus {}; {}, {}, normals {}",
        super::thousands(f.report.vertices),
        super::thousands(f.report.faces),
        f.report.components_kept,
        f.report.components,
        if f.report.components == 1 { "" } else { "s" },
        genus_list(&f.genus),
        if f.closed { "closed" } else { "open" },
        if f.manifold {
            "manifold"
        } else {
            "NOT manifold"
        },
        f.normals.unwrap_or("mixed")
    );
    println!(
        "  enclosed volume {:.1} mm^3 ({:+.2}% of the voxels'), smallest angle {:.1} deg, {:.2} s",
        f.report.volume,
        100.0 * (f.report.volume / f.report.voxel_volume - 1.0),
        f.report.min_angle,
        f.seconds
    );
    let fit = &f.report.fit;
    let far = |count: usize, farthest: Option<f64>| {
        let count = super::thousands(count);
        farthest.map_or(count.clone(), |d| format!("{count} (the farthest {d:.2})"))
    };
    println!(
        "  voxel boundary: {} points held, farther than {} voxel from the surface {}, before fitting {}",
        super::thousands(fit.points),
        segment::fit::TOLERANCE,
        far(fit.far, fit.farthest),
        far(fit.far_before, fit.farthest_before),
    );
    if let Some(faces) = fit.faces_off {
        println!(
            "  faces with a point farther than {} voxel from the voxel faces: {}",
            segment::fit::TOLERANCE,
            far(faces, fit.farthest_off),
        );
    }
    println!("wrote {}", f.output.display());
    Ok(())
}

/// The genus of each closed sheet, the first few listed (voids kept add
/// a sheet each; `--json` lists them all).
fn genus_list(genus: &[i64]) -> String {
    const SHOWN: usize = 6;
    let shown: Vec<String> = genus.iter().take(SHOWN).map(|g| g.to_string()).collect();
    match genus.len() {
        1 => shown[0].clone(),
        n if n <= SHOWN => format!("[{}]", shown.join(", ")),
        n => format!(
            "[{}, ... {} more sheets, genus {} in all]",
            shown.join(", "),
            n - SHOWN,
            genus.iter().sum::<i64>()
        ),
    }
}
