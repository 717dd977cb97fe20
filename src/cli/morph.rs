//! `organtex morph MESH --sections S.toml (--plane NX,NY,NZ,D [--resolution
//! PX] | --grid "O;U;V;W,H") -o CUT.png|.glb [--json]`: the colour inside
//! an organ morphed from photographs of a few cuts (seed 003), on a plane
//! section of the mesh, on a grid of points, or on any cut surface
//! (`--surface CUT.obj -o CUT.glb`).

use std::path::PathBuf;
use std::time::Instant;

use glam::DVec3;
use organtex::mesh::{Topology, io};
use organtex::solid::morph::{Morph, MorphOptions};
use organtex::solid::{Interior, Plane, render_section, texture_cut};
use organtex::{Error, Result, memory};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    /// The closed organ mesh (.obj, .ply or .stl) the photographs were cut
    /// from.
    mesh: PathBuf,
    /// The sections file (TOML): each `[[exemplar]]` an image, its
    /// placement (origin, u, v: pixel (i, j) is centred at origin +
    /// (i + 0.5) u + (j + 0.5) v), an optional tissue mask and an optional
    /// `path = "arc"` with `axis = [[x, y, z], [dx, dy, dz]]` in the plane
    /// (cuts through a common axis sweep by rotating about it); the order
    /// is the order the planes split the organ.
    #[arg(long, value_name = "TOML")]
    sections: PathBuf,
    /// Colour the section of the mesh by the plane N·p = D: a .png in the
    /// plane, transparent outside the section, or a textured .glb.
    #[arg(long, value_name = "NX,NY,NZ,D", value_parser = super::section::parse_plane,
          allow_hyphen_values = true, conflicts_with_all = ["grid", "surface"],
          required_unless_present_any = ["grid", "surface"])]
    plane: Option<Plane>,
    /// Pixels along the longer side of the section image (with --plane).
    #[arg(long, value_name = "PX", default_value_t = 1024,
          value_parser = clap::value_parser!(u32).range(1..=16384))]
    resolution: u32,
    /// Colour a W x H image whose pixel (i, j) shows the point O + (i +
    /// 0.5) U + (j + 0.5) V (the sections file's convention), whether
    /// inside the mesh or not.
    #[arg(long, value_name = "OX,OY,OZ;UX,UY,UZ;VX,VY,VZ;W,H", value_parser = parse_grid,
          allow_hyphen_values = true, conflicts_with = "surface")]
    grid: Option<Grid>,
    /// Texture a cut surface the simulator made (any triangle mesh, e.g. a
    /// curved incision; .obj, .ply or .stl): each triangle laid flat in one
    /// image, written as a textured .glb.
    #[arg(long, value_name = "MESH")]
    surface: Option<PathBuf>,
    /// Texels per object unit (with --surface).
    #[arg(long, default_value_t = 4.0)]
    texels_per_unit: f64,
    /// Blur (photograph pixels) that splits the low band from the detail.
    #[arg(long, default_value_t = MorphOptions::default().low_sigma)]
    low_sigma: f32,
    /// Leave the detail band's local histogram unmatched (seed 003, 5.3).
    #[arg(long)]
    no_matching: bool,
    /// Output: .png (--plane or --grid) or .glb (--plane or --surface).
    #[arg(short, long)]
    output: PathBuf,
    /// Print a JSON summary: points, precompute_seconds, seconds and
    /// points_per_second (evaluation only).
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, Debug)]
pub struct Grid {
    origin: DVec3,
    u: DVec3,
    v: DVec3,
    width: u32,
    height: u32,
}

fn parse_grid(s: &str) -> std::result::Result<Grid, String> {
    let form = "OX,OY,OZ;UX,UY,UZ;VX,VY,VZ;W,H";
    let parts: Vec<&str> = s.split(';').collect();
    if parts.len() != 4 {
        return Err(format!("'{s}' is not {form} (four ;-separated groups)"));
    }
    let point = |p: &str| -> std::result::Result<DVec3, String> {
        let v = super::section::numbers(p, 3, "three finite numbers")?;
        Ok(DVec3::new(v[0], v[1], v[2]))
    };
    let size = super::comma_numbers::<u32>(parts[3], 2, "W,H (two whole numbers)")?;
    if size[0] == 0 || size[1] == 0 || size[0] > 16384 || size[1] > 16384 {
        return Err(format!(
            "the grid must be 1 to 16384 pixels a side, not {}x{}",
            size[0], size[1]
        ));
    }
    let (u, v) = (point(parts[1])?, point(parts[2])?);
    if u.cross(v).length() <= 1e-12 * u.length() * v.length()
        || u.length() == 0.0
        || v.length() == 0.0
    {
        return Err(format!(
            "the grid's U {u} and V {v} must be non-zero and not parallel"
        ));
    }
    Ok(Grid {
        origin: point(parts[0])?,
        u,
        v,
        width: size[0],
        height: size[1],
    })
}

pub fn run(args: Args) -> Result<()> {
    let ext = organtex::error::extension(&args.output);
    let glb = match ext.as_str() {
        "png" if args.surface.is_none() => false,
        "glb" if args.grid.is_none() => true,
        _ => {
            return Err(Error::invalid(if args.grid.is_some() {
                "unknown output format (organtex morph --grid writes .png)"
            } else if args.surface.is_some() {
                "unknown output format (organtex morph --surface writes .glb)"
            } else {
                "unknown output format (organtex morph --plane writes .png or .glb)"
            })
            .in_file(&args.output));
        }
    };
    let surface = args.surface.as_deref().map(io::read).transpose()?;
    let mesh = io::read(&args.mesh)?;
    let topology = Topology::build(&mesh).map_err(|e| e.in_file(&args.mesh))?;
    Morph::check_mesh(&topology).map_err(|e| e.in_file(&args.mesh))?;
    let section = args
        .plane
        .map(|plane| super::section::cut(&mesh, &topology, plane, args.resolution, &args.mesh))
        .transpose()?;
    let options = MorphOptions {
        low_sigma: args.low_sigma,
        matching: !args.no_matching,
    };
    let bars = Bars::new();
    let start = Instant::now();
    let morph = Morph::read(&mesh, &topology, &args.sections, options, &bars)?;
    let precompute_seconds = start.elapsed().as_secs_f64();
    bars.finish();

    let (image, points, seconds) = match (&section, args.grid) {
        (None, None) => {
            let cut = surface
                .as_ref()
                .expect("clap requires --plane, --grid or --surface");
            let t = Instant::now();
            let texture = texture_cut(cut, &morph, args.texels_per_unit)
                .map_err(|e| e.in_file(args.surface.as_deref().unwrap_or(&args.mesh)))?;
            let seconds = t.elapsed().as_secs_f64();
            let bytes = organtex::scene::gltf::cut_glb(cut, &texture)?;
            organtex::atomic::write_file(&args.output, |w| w.write_all(&bytes))?;
            let covered = texture.image.pixels().filter(|p| p[3] == 255).count();
            (
                (texture.image.width(), texture.image.height()),
                covered,
                seconds,
            )
        }
        (Some((section, pixels_per_unit)), _) => {
            let t = Instant::now();
            let drawn = render_section(section, &morph, *pixels_per_unit)?;
            let seconds = t.elapsed().as_secs_f64();
            let points = drawn.image.width() as usize * drawn.image.height() as usize;
            super::section::write(section, &drawn, &args.output, glb)?;
            ((drawn.image.width(), drawn.image.height()), points, seconds)
        }
        (None, Some(g)) => {
            memory::ensure_fits(
                &format!("a {}x{} grid (--grid)", g.width, g.height),
                memory::product(&[g.width as u64, g.height as u64, 40]),
            )?;
            let points: Vec<DVec3> = (0..g.height)
                .flat_map(|j| {
                    (0..g.width)
                        .map(move |i| g.origin + g.u * (i as f64 + 0.5) + g.v * (j as f64 + 0.5))
                })
                .collect();
            let t = Instant::now();
            let colours = morph.colours(&points);
            let seconds = t.elapsed().as_secs_f64();
            let img = image::RgbImage::from_raw(g.width, g.height, colours.concat())
                .expect("one colour per pixel");
            organtex::atomic::write_png(&args.output, &image::DynamicImage::ImageRgb8(img))?;
            ((g.width, g.height), points.len(), seconds)
        }
    };
    let points_per_second = points as f64 / seconds.max(1e-9);
    if args.json {
        let out = serde_json::json!({
            "output": args.output,
            "width": image.0,
            "height": image.1,
            "points": points,
            "exemplars": morph.exemplars().len(),
            "regions": morph.regions(),
            "precompute_seconds": precompute_seconds,
            "seconds": seconds,
            "points_per_second": points_per_second,
            "threads": rayon::current_num_threads(),
        });
        println!(
            "{}",
            serde_json::to_string_pretty(&out).expect("the summary serialises")
        );
    } else {
        println!(
            "{}: {}x{} pixels morphed from {} exemplars in {} regions; precompute {:.2} s, \
             {} points in {:.1} ms ({:.2} M points/s)",
            args.output.display(),
            image.0,
            image.1,
            morph.exemplars().len(),
            morph.regions(),
            precompute_seconds,
            points,
            seconds * 1e3,
            points_per_second / 1e6
        );
    }
    Ok(())
}
