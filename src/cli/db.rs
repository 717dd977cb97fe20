//! `organtex db list|build|exemplar`: the tissue texture database.

use std::path::PathBuf;

use clap::Subcommand;
use organtex::Result;
use organtex::db::build::is_current;
use organtex::db::{Database, build, exemplar};

use super::progress::Bars;

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: DbCommand,
    /// The database folder (holding index.toml).
    #[arg(long, global = true, value_name = "DIR", default_value_os_t = default_root())]
    database: PathBuf,
}

#[derive(Subcommand)]
enum DbCommand {
    /// List the entries: kind, the viewer's shelf, outputs, licence and
    /// whether their outputs are built.
    List,
    /// Regenerate outputs from the sources (all entries, or those named).
    Build {
        /// Entry ids to build (default: all).
        ids: Vec<String>,
    },
    /// Write the exemplar an entry synthesises from, as the build prepares
    /// it (cropped, lighting flattened where asked): an RGBA PNG whose
    /// alpha is 255 on usable pixels and 0 where the mask rules hide them.
    /// `organtex synth` and other synthesisers read it as a masked exemplar.
    Exemplar {
        /// Entry id.
        id: String,
        /// Output PNG.
        #[arg(short, long)]
        output: PathBuf,
    },
}

pub fn default_root() -> PathBuf {
    organtex::scene::file::default_database()
}

pub fn run(args: Args) -> Result<()> {
    let db = Database::open(&args.database)?;
    match args.command {
        DbCommand::List => {
            let licence = |t: &organtex::db::Tissue| {
                t.licence
                    .clone()
                    .unwrap_or_else(|| "see LICENSES.md".into())
            };
            let width = |f: &dyn Fn(&organtex::db::Tissue) -> usize, title: &str| {
                db.tissues
                    .iter()
                    .map(f)
                    .chain([title.len()])
                    .max()
                    .unwrap_or(0)
                    + 2
            };
            let (wi, wn, wk, wl) = (
                width(&|t| t.id.len(), "id"),
                width(&|t| t.name.chars().count(), "name"),
                width(&|t| t.kind.len(), "kind"),
                width(&|t| licence(t).len(), "licence"),
            );
            println!(
                "{:<wi$}{:<wn$}{:<wk$}{:<10}{:<11}{:<24}{:<wl$}{:<19}built",
                "id", "name", "kind", "shelf", "capture", "outputs", "licence", "L* a* b* (mean)"
            );
            for t in &db.tissues {
                let outputs: Vec<String> = t
                    .outputs
                    .iter()
                    .map(|o| format!("{o:?}").to_lowercase())
                    .collect();
                let built = t
                    .outputs
                    .iter()
                    .all(|&o| db.output_path(&t.id, o).is_file());
                // A source that cannot be read is the build's error to
                // report; the list goes on.
                let built = match (built, built && is_current(&db, t).unwrap_or(false)) {
                    (false, _) => "no",
                    (true, false) => "out of date",
                    (true, true) => "yes",
                };
                // The colour texture's CIELAB mean, what `match` moves
                // another texture onto.
                let lab = if db
                    .output_path(&t.id, organtex::db::Output::Colour)
                    .is_file()
                {
                    organtex::db::build::stats_of(&db, &t.id)
                        .map(|s| format!("{:.0} {:.0} {:.0}", s.mean[0], s.mean[1], s.mean[2]))
                        .unwrap_or_default()
                } else {
                    "-".into()
                };
                println!(
                    "{:<wi$}{:<wn$}{:<wk$}{:<10}{:<11}{:<24}{:<wl$}{:<19}{built}",
                    t.id,
                    t.name,
                    t.kind,
                    t.shelf().title().to_lowercase(),
                    t.capture.map_or("?", |c| c.name()),
                    outputs.join(", "),
                    licence(t),
                    lab,
                );
            }
        }
        DbCommand::Build { ids } => {
            let bars = Bars::new();
            let start = std::time::Instant::now();
            let built = build(&db, &ids, &bars)?;
            bars.finish();
            for b in &built {
                let q = b
                    .quality
                    .as_ref()
                    .map(|q| {
                        format!(
                            "coherence {:.2}, completeness {:.2}, seam {:.2}",
                            q.coherence, q.completeness, q.seam
                        )
                    })
                    .unwrap_or_default();
                println!("{:<20}{:>6.2} s  {q}", b.id, b.seconds);
            }
            println!(
                "built {} entries into {} in {:.1} s",
                built.len(),
                db.root.join("build").display(),
                start.elapsed().as_secs_f64()
            );
        }
        DbCommand::Exemplar { id, output } => {
            let ex = exemplar(&db, db.tissue(&id)?)?;
            organtex::atomic::write_png(&output, &ex.to_rgba())?;
            println!("{}", output.display());
        }
    }
    Ok(())
}
