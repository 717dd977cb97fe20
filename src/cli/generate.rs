//! `organtex generate SHAPE -o OUT.obj`: the test shapes with known
//! topology, written as OBJ.

use std::path::PathBuf;

use clap::ValueEnum;
use organtex::mesh::{TriMesh, io, shapes};
use organtex::{Error, Result};

#[derive(Clone, Copy, ValueEnum)]
enum Shape {
    /// Genus 1.
    Torus,
    /// Genus 2: a rounded slab with two holes.
    DoubleTorus,
    /// Open at both ends: two boundary loops.
    Cylinder,
    /// Unit icosphere, genus 0.
    Sphere,
    /// A uterine cavity seen from inside, with two myomas and a polyp (the
    /// default hysteroscopy scene's organ), facets per growth.
    Uterus,
}

#[derive(clap::Args)]
pub struct Args {
    #[arg(value_enum)]
    shape: Shape,
    /// Output .obj file.
    #[arg(short, long)]
    output: PathBuf,
    /// Resolution: larger gives more triangles (1 to 8).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=8))]
    resolution: u32,
    /// Uterus: the wall's thickness. With it the mesh is the uterine wall as
    /// a closed solid (cavity inside, facet "serosa" outside), which
    /// `organtex section` can cut; without it, the open cavity alone.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    wall_thickness: f64,
}

pub fn run(args: Args) -> Result<()> {
    let r = args.resolution as usize;
    let mesh: TriMesh = match args.shape {
        Shape::Torus => shapes::torus(1.0, 0.35, 16 * r, 6 * r),
        Shape::DoubleTorus => shapes::holed_slab(2, r + 1, 4),
        Shape::Cylinder => shapes::open_cylinder(0.5, 1.5, 12 * r, 4 * r),
        Shape::Sphere => shapes::icosphere(r),
        Shape::Uterus => {
            let params = organtex::scene::uterus::CavityParams {
                wall_thickness: args.wall_thickness,
                ..organtex::scene::uterus::demo()
            };
            organtex::scene::uterus::generate(&params).map_err(|e| {
                let key = if e.key == "wall_thickness" {
                    "--wall-thickness".into()
                } else {
                    e.key
                };
                Error::invalid(format!("{key}: {}", e.msg))
            })?
        }
    };
    if args.output.extension().and_then(|e| e.to_str()) != Some("obj") {
        return Err(Error::format(
            &args.output,
            "organtex writes meshes as .obj",
        ));
    }
    io::write_obj(&args.output, &mesh, None)?;
    println!(
        "wrote {} ({} vertices, {} faces)",
        args.output.display(),
        mesh.num_vertices(),
        mesh.num_faces()
    );
    Ok(())
}
