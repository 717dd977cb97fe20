//! The project's standard workloads, timed by `organtex bench`.
//!
//! Each workload prepares its inputs untimed, then its timed step runs `runs`
//! times; the median is the figure issues quote. Add a stage's workloads to
//! `workloads` when the stage lands.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::error::Result;
use crate::mesh::curvature::Curvature;
use crate::mesh::{Components, Topology, io};
use crate::progress::Silent;
use crate::unwrap::{UnwrapOptions, unwrap};

/// The timed step of a workload.
pub type Step = Box<dyn FnMut() -> Result<()>>;

pub struct Workload {
    pub name: &'static str,
    /// What the step does, for the table's reader.
    pub what: &'static str,
    /// Load the inputs from the data folder (untimed) and return the step
    /// to time.
    pub prepare: fn(&Path) -> Result<Step>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Timing {
    pub name: &'static str,
    pub what: &'static str,
    pub runs: usize,
    pub median_s: f64,
    pub min_s: f64,
    pub max_s: f64,
}

/// Where the bundled test data lives in a source checkout.
pub fn default_data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("data")
}

/// Every standard workload.
pub fn workloads() -> Vec<Workload> {
    vec![
        Workload {
            name: "load bunny",
            what: "read bunny.obj (56k faces)",
            prepare: |data| {
                let path = data.join("bunny.obj");
                Ok(Box::new(move || io::read(&path).map(drop)))
            },
        },
        Workload {
            name: "topology bunny",
            what: "half-edges, boundary loops, components, genus",
            prepare: |data| {
                let mesh = io::read(&data.join("bunny.obj"))?;
                Ok(Box::new(move || {
                    let topo = Topology::build(&mesh)?;
                    Components::find(&topo).topology(&topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "curvature bunny",
            what: "angle defect, mixed area, mean curvature, dihedral angles",
            prepare: |data| {
                let mesh = io::read(&data.join("bunny.obj"))?;
                let topo = Topology::build(&mesh)?;
                Ok(Box::new(move || {
                    Curvature::compute(&mesh, &topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "load+topology+curvature bunny",
            what: "the three above end to end (target < 0.3 s)",
            prepare: |data| {
                let path = data.join("bunny.obj");
                Ok(Box::new(move || {
                    let mesh = io::read(&path)?;
                    let topo = Topology::build(&mesh)?;
                    Components::find(&topo).topology(&topo);
                    Curvature::compute(&mesh, &topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "unwrap bunny",
            what: "visibility, seams, ABF++ and layout, one chart (target: 1/4 of xatlas)",
            prepare: |data| {
                let mesh = io::read(&data.join("bunny.obj"))?;
                Ok(Box::new(move || {
                    unwrap(&mesh, &UnwrapOptions::default(), &Silent).map(drop)
                }))
            },
        },
    ]
}

/// Time `workload`'s step `runs` times (at least once) on the inputs in
/// `data`.
pub fn time(workload: &Workload, data: &Path, runs: usize) -> Result<Timing> {
    let mut step = (workload.prepare)(data)?;
    let mut secs = Vec::with_capacity(runs.max(1));
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        step()?;
        secs.push(start.elapsed().as_secs_f64());
    }
    secs.sort_unstable_by(f64::total_cmp);
    Ok(Timing {
        name: workload.name,
        what: workload.what,
        runs: secs.len(),
        median_s: median(&secs),
        min_s: secs[0],
        max_s: secs[secs.len() - 1],
    })
}

/// Median of sorted values.
fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0
    }
}
