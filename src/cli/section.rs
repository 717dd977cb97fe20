//! `organtex section MESH (--block B.nrrd [--lst MODEL.lst] | --sections
//! S.toml) --plane NX,NY,NZ,D -o CUT.png|.glb`: the section of a closed
//! organ by a plane, textured from a solid block tiled through space, from
//! a lapped solid texture whose exemplar the block is, or morphed from
//! photographed cuts (seed 003).

use std::path::{Path, PathBuf};

use glam::DVec3;
use organtex::mesh::{Topology, TriMesh, io};
use organtex::solid::lst::{LstInterior, LstModel};
use organtex::solid::morph::{Morph, MorphOptions};
use organtex::solid::{
    Block, Placement, Plane, Section, SectionImage, plane_section, render_section,
};
use organtex::synth::volume::Volume;
use organtex::{Error, Result, memory};

#[derive(clap::Args)]
pub struct Args {
    /// Closed mesh to cut (.obj, .ply or .stl).
    mesh: PathBuf,
    /// The solid texture: an RGB uint8 NRRD volume, tiled through space
    /// (or, with --lst, the model's exemplar).
    #[arg(long, value_name = "NRRD", required_unless_present = "sections")]
    block: Option<PathBuf>,
    /// Colour the section by morphing photographed cuts placed in the mesh
    /// (a sections file: `organtex morph --help`) instead of a block.
    #[arg(long, value_name = "TOML", conflicts_with_all = ["block", "lst", "scale"])]
    sections: Option<PathBuf>,
    /// Colour the section from a lapped solid texture (`organtex lst`).
    #[arg(long, value_name = "LST")]
    lst: Option<PathBuf>,
    /// The cutting plane: the points p with N·p = D. The normal need not be
    /// unit; the section faces along it.
    #[arg(long, value_name = "NX,NY,NZ,D", value_parser = parse_plane, allow_hyphen_values = true)]
    plane: Plane,
    /// Object units one voxel spans (default: the block's NRRD spacing).
    #[arg(long, allow_negative_numbers = true)]
    scale: Option<f64>,
    /// Where the block's corner (voxel 0's low corner) sits in object space.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, allow_hyphen_values = true,
          default_value = "0,0,0")]
    origin: DVec3,
    /// Pixels along the longer side of the section image.
    #[arg(long, value_name = "PX", default_value_t = 1024, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=16384))]
    resolution: u32,
    /// Output: .png (the section drawn in its plane, transparent outside
    /// it) or .glb (the section's triangles, textured with that image).
    #[arg(short, long)]
    output: PathBuf,
}

/// `n` finite comma-separated numbers.
pub(super) fn numbers(s: &str, n: usize, what: &str) -> std::result::Result<Vec<f64>, String> {
    super::comma_numbers::<f64>(s, n, what)?
        .into_iter()
        .map(|x| {
            x.is_finite()
                .then_some(x)
                .ok_or(format!("'{s}' is not {what}"))
        })
        .collect()
}

pub(super) fn parse_plane(s: &str) -> std::result::Result<Plane, String> {
    let v = numbers(s, 4, "NX,NY,NZ,D (four finite numbers)")?;
    Plane::new(DVec3::new(v[0], v[1], v[2]), v[3]).map_err(|e| e.to_string())
}

fn parse_point(s: &str) -> std::result::Result<DVec3, String> {
    let v = numbers(s, 3, "X,Y,Z (three finite numbers)")?;
    Ok(DVec3::new(v[0], v[1], v[2]))
}

pub fn run(args: Args) -> Result<()> {
    let extension = args
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase());
    let glb = match extension.as_deref() {
        Some("png") => false,
        Some("glb") => true,
        _ => {
            return Err(Error::invalid(
                "unknown output format (organtex section writes .png or .glb)",
            )
            .in_file(&args.output));
        }
    };
    let mesh = io::read(&args.mesh)?;
    let topology = Topology::build(&mesh).map_err(|e| e.in_file(&args.mesh))?;
    if let Some(scale) = args.scale
        && !(scale.is_finite() && scale > 0.0)
    {
        return Err(Error::invalid(format!(
            "--scale must be a positive scale (object units per voxel), not {scale}"
        )));
    }

    let start = std::time::Instant::now();
    let (section, pixels_per_unit) =
        cut(&mesh, &topology, args.plane, args.resolution, &args.mesh)?;
    let image = match (&args.block, &args.sections) {
        (_, Some(sections)) => {
            let bars = super::progress::Bars::new();
            let morph = Morph::read(&mesh, &topology, sections, MorphOptions::default(), &bars)?;
            bars.finish();
            render_section(&section, &morph, pixels_per_unit)?
        }
        (Some(block), None) => {
            // An LST exemplar's depth axis, if its header names one, runs
            // along y.
            let volume = if args.lst.is_some() {
                Volume::read_exemplar(block)?
            } else {
                Volume::read_nrrd(block)?
            };
            match args.lst.as_deref().map(LstModel::read).transpose()? {
                Some(model) => {
                    let interior = LstInterior::new(model.into(), volume.into())
                        .map_err(|e| e.in_file(block))?;
                    render_section(&section, &interior, pixels_per_unit)?
                }
                None => {
                    let placement =
                        Placement::new(args.origin, args.scale.unwrap_or(volume.spacing))?;
                    render_section(
                        &section,
                        &Block {
                            volume: &volume,
                            placement,
                        },
                        pixels_per_unit,
                    )?
                }
            }
        }
        (None, None) => unreachable!("clap requires --block or --sections"),
    };
    write(&section, &image, &args.output, glb)?;
    println!(
        "{}: section of {} boundary loops, {} triangles, area {:.6}, {}x{} pixels, in {:.2} s",
        args.output.display(),
        section.boundary.len(),
        section.triangles.len(),
        section.area(),
        image.image.width(),
        image.image.height(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The section of `mesh` by `plane`, and the pixels per unit that put
/// `resolution` pixels along its longer side. Refuses a plane that misses
/// the mesh, a section too wide to draw and an image that would not fit in
/// memory, naming `path` (the mesh's file).
pub(super) fn cut(
    mesh: &TriMesh,
    topology: &Topology,
    plane: Plane,
    resolution: u32,
    path: &Path,
) -> Result<(Section, f64)> {
    let section = plane_section(mesh, topology, plane).map_err(|e| e.in_file(path))?;
    let extent = section
        .bounds()
        .map_or(0.0, |(lo, hi)| (hi - lo).max_element());
    if section.is_empty() || extent <= 0.0 {
        return Err(Error::invalid(
            "the plane misses the mesh: the section is empty, nothing written",
        )
        .in_file(path));
    }
    if !extent.is_finite() {
        return Err(Error::invalid(format!(
            "the section spans {extent} units: too wide to draw"
        ))
        .in_file(path));
    }
    let pixels_per_unit = resolution as f64 / extent;
    if let Some((lo, hi)) = section.bounds() {
        let [w, h] = ((hi - lo) * pixels_per_unit)
            .ceil()
            .max(glam::DVec2::ONE)
            .to_array();
        // The image, its coverage, the copy handed to the encoder and the
        // encoded bytes: about 13 bytes a pixel.
        memory::ensure_fits(
            &format!("a {w}x{h} section image (--resolution)"),
            memory::product(&[w as u64, h as u64, 13]),
        )?;
    }
    Ok((section, pixels_per_unit))
}

/// Write a drawn section: the image (.png) or its triangles textured with
/// it (.glb).
pub(super) fn write(
    section: &Section,
    image: &SectionImage,
    output: &Path,
    glb: bool,
) -> Result<()> {
    if glb {
        let bytes = organtex::scene::gltf::section_glb(section, image)?;
        organtex::atomic::write_file(output, |w| w.write_all(&bytes))
    } else {
        organtex::atomic::write_png(
            output,
            &image::DynamicImage::ImageRgba8(image.image.clone()),
        )
    }
}
