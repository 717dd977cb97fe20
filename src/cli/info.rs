//! `organtex info FILE`: the mesh report as text or JSON.

use std::io::Write;
use std::path::{Path, PathBuf};

use organtex::Result;
use organtex::mesh::curvature::Stats;
use organtex::mesh::info::{Analysis, MeshReport, analyse};
use organtex::mesh::io;

use super::thousands;

#[derive(clap::Args)]
pub struct Args {
    /// Mesh to describe (.obj, .ply or .stl).
    file: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Split non-manifold edges and vertices instead of refusing the mesh;
    /// the report then says what was split.
    #[arg(long)]
    repair: bool,
    /// Also write per-vertex curvature as CSV (vertex, angle_defect,
    /// mixed_area, gaussian, mean), vertices numbered from 0 in file order.
    #[arg(long, value_name = "CSV")]
    curvature_out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let mesh = io::read(&args.file)?;
    let analysis = analyse(mesh, args.repair).map_err(|e| e.in_file(&args.file))?;
    if let Some(csv) = &args.curvature_out {
        write_curvature_csv(csv, &analysis)?;
    }
    let report = &analysis.report;
    if args.json {
        // Plain numbers and string keys: serialising cannot fail, and a
        // struct becomes an object, so indexing by key inserts, never panics.
        let mut value = serde_json::to_value(report).expect("the report serialises");
        value["file"] = serde_json::Value::String(args.file.display().to_string());
        println!(
            "{}",
            serde_json::to_string_pretty(&value).expect("the report serialises")
        );
    } else {
        print_text(&args.file, report);
    }
    Ok(())
}

fn write_curvature_csv(path: &Path, a: &Analysis) -> Result<()> {
    let c = &a.curvature;
    organtex::atomic::write_file(path, |w: &mut dyn Write| {
        writeln!(w, "vertex,angle_defect,mixed_area,gaussian,mean")?;
        // The curvature arrays hold one value per vertex of this mesh.
        for v in 0..a.mesh.num_vertices() {
            writeln!(
                w,
                "{v},{},{},{},{}",
                c.angle_defect[v], c.mixed_area[v], c.gaussian[v], c.mean[v]
            )?;
        }
        Ok(())
    })
}

fn print_text(file: &Path, r: &MeshReport) {
    let row = |label: &str, value: String| println!("  {label:<16}{value}");
    println!("{}", file.display());
    row("vertices", thousands(r.vertices));
    row("faces", thousands(r.faces));
    row("edges", thousands(r.edges));
    row(
        "facets",
        if r.facets.is_empty() {
            "none".into()
        } else {
            r.facets
                .iter()
                .map(|f| format!("{} ({} faces)", f.name, thousands(f.faces)))
                .collect::<Vec<_>>()
                .join(", ")
        },
    );
    row(
        "uvs",
        r.texcoords.map_or("none".into(), |n| {
            format!("{} texture coordinates", thousands(n))
        }),
    );
    row("components", thousands(r.components));
    row("genus", list(&r.genus));
    row(
        "boundary loops",
        format!(
            "{} ({} edges)",
            thousands(r.boundary_loops),
            thousands(r.boundary_edges)
        ),
    );
    row("euler", r.euler.to_string());
    if r.components > 1 {
        for (i, c) in r.component_topology.iter().enumerate().take(10) {
            row(
                &format!("  component {i}"),
                format!(
                    "{} faces, genus {}, {} boundary loops",
                    thousands(c.faces),
                    c.genus,
                    c.boundary_loops
                ),
            );
        }
        if r.components > 10 {
            row("", format!("... {} more (see --json)", r.components - 10));
        }
    }
    let d = &r.defects;
    let defects: Vec<String> = [
        (d.non_manifold_edges, "non-manifold edges"),
        (d.non_manifold_vertices, "non-manifold vertices"),
        (d.inconsistent_edges, "inconsistently oriented edges"),
        (d.degenerate_faces, "degenerate faces"),
        (d.duplicate_faces, "duplicate faces"),
        (d.repeated_vertex_faces, "faces with a repeated vertex"),
        (d.unreferenced_vertices, "unreferenced vertices"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{} {what}", thousands(*n)))
    .collect();
    row(
        "defects",
        if defects.is_empty() {
            "none".into()
        } else {
            defects.join(", ")
        },
    );
    if let Some(rep) = &r.repair {
        row(
            "repaired",
            if rep.changed_anything() {
                format!(
                    "removed {} repeated-vertex and {} duplicate faces, flipped {} faces, cut {} edges, split off {} vertices, detached {} faces",
                    rep.removed_repeated_vertex_faces,
                    rep.removed_duplicate_faces,
                    rep.flipped_faces,
                    rep.cut_edges,
                    rep.split_vertices,
                    rep.detached_faces
                )
            } else {
                "nothing to repair".into()
            },
        );
    }
    let b = &r.bounding_box;
    row(
        "bounding box",
        format!(
            "[{:.6}, {:.6}, {:.6}] .. [{:.6}, {:.6}, {:.6}] (diagonal {:.6})",
            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2], b.diagonal
        ),
    );
    row("area", number(r.area));
    row(
        "volume",
        match (r.volume, r.normals) {
            (Some(v), Some(n)) => format!("{} (closed, normals point {n})", number(v)),
            _ => "open surface".into(),
        },
    );
    let c = &r.curvature;
    row(
        "angle defect",
        format!(
            "total {:.9} = 2*pi*euler to {:.1e} (Gauss-Bonnet)",
            c.total_angle_defect, c.gauss_bonnet_error
        ),
    );
    row("gaussian K", stats(&c.gaussian));
    row("mean H", stats(&c.mean));
    row("dihedral (deg)", stats(&c.dihedral_degrees));
}

fn list(values: &[i64]) -> String {
    let shown: Vec<String> = values.iter().take(10).map(i64::to_string).collect();
    let more = if values.len() > 10 {
        format!(", ... ({} in all)", values.len())
    } else {
        String::new()
    };
    format!("{}{more}", shown.join(", "))
}

fn stats(s: &Option<Stats>) -> String {
    match s {
        Some(s) => format!(
            "min {}  p5 {}  median {}  mean {}  p95 {}  max {}",
            number(s.min),
            number(s.p05),
            number(s.median),
            number(s.mean),
            number(s.p95),
            number(s.max)
        ),
        None => "n/a".into(),
    }
}

/// Five significant digits, plain where that reads well, else scientific.
fn number(x: f64) -> String {
    let magnitude = x.abs();
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e6).contains(&magnitude) {
        let decimals = (4 - magnitude.log10().floor() as i32).clamp(0, 8) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.4e}")
    }
}
