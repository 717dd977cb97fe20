//! `organtex db list|build`: the tissue texture database.

use std::path::PathBuf;

use clap::Subcommand;
use organtex::Result;
use organtex::db::{Database, build};

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
    /// List the entries and whether their outputs are built.
    List,
    /// Regenerate outputs from the sources (all entries, or those named).
    Build {
        /// Entry ids to build (default: all).
        ids: Vec<String>,
    },
}

pub fn default_root() -> PathBuf {
    organtex::scene::file::default_database()
}

pub fn run(args: Args) -> Result<()> {
    let db = Database::open(&args.database)?;
    match args.command {
        DbCommand::List => {
            println!(
                "{:<20}{:<46}{:<20}{:<24}{:<16}built",
                "id", "name", "kind", "outputs", "licence"
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
                println!(
                    "{:<20}{:<46}{:<20}{:<24}{:<16}{}",
                    t.id,
                    t.name,
                    t.kind,
                    outputs.join(", "),
                    t.licence.as_deref().unwrap_or("see LICENSES.md"),
                    if built { "yes" } else { "no" }
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
                println!("{:<16}{:>6.2} s  {q}", b.id, b.seconds);
            }
            println!(
                "built {} entries into {} in {:.1} s",
                built.len(),
                db.root.join("build").display(),
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}
