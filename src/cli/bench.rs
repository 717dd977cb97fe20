//! `organtex bench`: time the standard workloads and print a table.

use std::path::PathBuf;

use organtex::Result;
use organtex::bench::{default_root, time, workloads};

#[derive(clap::Args)]
pub struct Args {
    /// Runs per workload; the table shows their median.
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// Print the results as JSON.
    #[arg(long)]
    json: bool,
    /// Only run workloads whose name contains this text (repeatable).
    #[arg(long, value_name = "TEXT")]
    only: Vec<String>,
    /// The organtex source folder, whose tests/data and database/sources
    /// hold the workloads' inputs.
    #[arg(long, value_name = "DIR", default_value_os_t = default_root())]
    root: PathBuf,
    /// List the workloads and exit.
    #[arg(long)]
    list: bool,
}

pub fn run(args: Args) -> Result<()> {
    let chosen: Vec<_> = workloads()
        .into_iter()
        .filter(|w| args.only.is_empty() || args.only.iter().any(|o| w.name.contains(o.as_str())))
        .collect();
    if args.list {
        for w in &chosen {
            println!("{:<32}{}", w.name, w.what);
        }
        return Ok(());
    }
    if chosen.is_empty() {
        return Err(organtex::Error::invalid(format!(
            "no workload matches {:?}; `organtex bench --list` shows them",
            args.only
        )));
    }
    let mut results = Vec::new();
    if !args.json {
        println!(
            "{:<32}{:>12}{:>12}{:>12}  runs  ({} threads)",
            "workload",
            "median",
            "min",
            "max",
            rayon::current_num_threads()
        );
    }
    for w in &chosen {
        let t = time(w, &args.root, args.runs)?;
        if !args.json {
            println!(
                "{:<32}{:>12}{:>12}{:>12}  {:>4}  {}",
                t.name,
                seconds(t.median_s),
                seconds(t.min_s),
                seconds(t.max_s),
                t.runs,
                t.what
            );
        }
        results.push(t);
    }
    if args.json {
        let out = serde_json::json!({
            "threads": rayon::current_num_threads(),
            "workloads": results,
        });
        // Plain numbers and string keys: serialising cannot fail.
        println!(
            "{}",
            serde_json::to_string_pretty(&out).expect("timings serialise")
        );
    }
    Ok(())
}

fn seconds(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.1} us", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.3} s")
    }
}
