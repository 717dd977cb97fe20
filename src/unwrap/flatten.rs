//! Flatten a disk-shaped chart: ABF++ angles laid out by least squares, or
//! LSCM when ABF++ fails or its layout folds over (reported, never silent).

use glam::DVec2;
use serde::Serialize;

use super::abf::{self, AbfOptions};
use super::balance::balance;
use super::layout;
use crate::error::Result;
use crate::mesh::curvature::corner_angles;
use crate::mesh::{Topology, TriMesh};

#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Method {
    AbfPlusPlus {
        iterations: usize,
        residual: f64,
        /// Area balancing rounds kept after the layout (`balance`).
        balance_rounds: usize,
    },
    /// LSCM, because ABF++ could not be used: `reason` says why.
    Lscm { reason: String },
}

#[derive(Clone, Debug)]
pub struct Flattened {
    /// Uv of every vertex of the chart.
    pub uv: Vec<DVec2>,
    pub method: Method,
}

/// Triangles whose uv orientation is reversed (the chart's faces are
/// counter-clockwise, so their uv triangles must be too).
pub fn flipped(chart: &TriMesh, uv: &[DVec2]) -> usize {
    chart
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| uv[v as usize]);
            (b - a).perp_dot(c - a) <= 0.0
        })
        .count()
}

pub fn flatten(chart: &TriMesh, topo: &Topology, opts: &AbfOptions) -> Result<Flattened> {
    let solved = abf::solve(chart, topo, opts).and_then(|solution| {
        let uv = layout::from_angles(chart, topo, &solution.angles)?;
        Ok((solution, uv))
    });
    let reason = match solved {
        Ok((solution, uv)) => {
            let flips = flipped(chart, &uv);
            if flips == 0 {
                let (uv, balance_rounds) =
                    balance(chart, &uv, opts.area_weight, opts.balance_rounds).unwrap_or((uv, 0));
                return Ok(Flattened {
                    uv,
                    method: Method::AbfPlusPlus {
                        iterations: solution.iterations,
                        residual: solution.residual,
                        balance_rounds,
                    },
                });
            }
            format!("the ABF++ layout flipped {flips} triangles")
        }
        Err(e) => e.to_string(),
    };
    Ok(Flattened {
        uv: layout::from_angles(chart, topo, &corner_angles(chart))?,
        method: Method::Lscm { reason },
    })
}
