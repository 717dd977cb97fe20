//! Flatten a disk-shaped chart: ABF++ angles laid out by least squares;
//! when ABF++ fails or its layout flips a triangle, boundary first
//! flattening (the conformal map Seamster's estimate describes), and LSCM
//! last. When ABF++ does not converge (raw scans: it stops at its step
//! cap, or earlier once it stalls and the layout of its best iterate
//! stops improving, `abf::solve_until`), that layout and boundary first
//! flattening's compete: the more conformal one without flips is kept. A
//! fallback is reported with the reason, never silent. Whatever flattened
//! the chart, area balancing follows (`balance`).

use glam::DVec2;
use serde::{Deserialize, Serialize};

use super::abf::{self, AbfOptions};
use super::balance::Balancer;
use super::conformal::boundary_first;
use super::layout::{self, Layout};
use super::metrics;
use super::untangle::unfold_layout;
use crate::error::Result;
use crate::linalg::VertexOrder;
use crate::mesh::curvature::corner_angles;
use crate::mesh::{Topology, TriMesh};

/// ABF++ residuals at or below this are laid out by propagation
/// (`Layout::propagate`: no factorisation), above it by least squares.
/// Newton's steps converge quadratically, so a solve that reaches its
/// tolerance (1e-7) usually lands far below it (the bunny: 3e-10, and its
/// propagated layout lies within 1e-9 of the least squares').
const EXACT_RESIDUAL: f64 = 1e-9;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Method {
    AbfPlusPlus {
        iterations: usize,
        residual: f64,
        /// False when ABF++ stopped at its step cap, or stalled with a
        /// layout that stopped improving: the angles are its best iterate,
        /// kept because their layout has no flips and boundary first
        /// flattening's flipped or was less conformal.
        converged: bool,
        /// Triangles the layout flipped and `untangle` unfolded.
        unfolded: usize,
        /// Area balancing rounds kept after the layout (`balance`).
        balance_rounds: usize,
    },
    /// Boundary first flattening, because ABF++ could not be used:
    /// `reason` says why; `flipped` triangles stay flipped (when even
    /// LSCM flipped more).
    BoundaryFirst {
        reason: String,
        unfolded: usize,
        flipped: usize,
        balance_rounds: usize,
    },
    /// LSCM, because neither ABF++ nor boundary first flattening gave a
    /// layout without flips and LSCM flipped fewer: `reason` says why;
    /// `flipped` triangles stay flipped.
    Lscm {
        reason: String,
        unfolded: usize,
        flipped: usize,
    },
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
        .filter(|t| metrics::face_double_area(t, uv) <= 0.0)
        .count()
}

/// A chart layout's conf_mean figure (`metrics`).
pub fn conf_mean(chart: &TriMesh, uv: &[DVec2]) -> f64 {
    metrics::conf_mean((0..chart.num_faces()).map(|f| {
        let corners = chart.triangles[f].map(|v| uv[v as usize]);
        (
            chart.face_area(f),
            metrics::jacobian(chart.corners(f), corners),
        )
    }))
}

/// Flatten a disk chart. Its systems (ABF++'s, the layouts', the
/// balancing's) all take their unknowns in one AMD order of its vertices:
/// ordering a system is most of its symbolic factorisation, and AMD on
/// the vertices gives ABF++'s two unknowns per vertex the fill it finds
/// on the unknowns themselves.
pub fn flatten(chart: &TriMesh, topo: &Topology, opts: &AbfOptions) -> Result<Flattened> {
    let order = VertexOrder::of_triangles(chart.num_vertices(), &chart.triangles)?;
    flatten_ordered(chart, topo, &order, opts)
}

/// `flatten` with the chart's vertices eliminated in `order` (made while
/// the cut was estimated: `cutgraph::Opened`).
pub fn flatten_ordered(
    chart: &TriMesh,
    topo: &Topology,
    order: &VertexOrder,
    opts: &AbfOptions,
) -> Result<Flattened> {
    // A layout that flipped a few slivers is unfolded vertex by vertex;
    // one without flips then has its area evened out.
    let unfold = |mut uv: Vec<DVec2>| {
        let before = flipped(chart, &uv);
        let left = unfold_layout(chart, &mut uv);
        (uv, before.saturating_sub(left), left)
    };
    // A stalled ABF++ iterate is scored by its layout's conformality, when
    // that has no flips left after unfolding; the layout of the one kept
    // comes back with it.
    let mut score = |angles: &[[f64; 3]]| {
        let (uv, unfolded, left) =
            unfold(layout::from_angles(chart, topo, angles, Some(order)).ok()?);
        (left == 0).then(|| (conf_mean(chart, &uv), (uv, unfolded, left)))
    };
    // ABF++'s set-up takes both cores; then its Newton steps (serial, one
    // factorisation each) take one while the other makes the layout's
    // system and the balancing's Laplacian, which do not depend on the
    // angles.
    let balancing = opts.area_weight > 0.0 && opts.balance_rounds > 0;
    let abf = abf::Prepared::new(chart, topo, Some(order));
    let (solved, (prepared, balancer)) = rayon::join(
        || abf?.solve_until(opts, &mut score),
        || {
            rayon::join(
                || Layout::new(chart, topo, Some(order)).ok(),
                || {
                    balancing
                        .then(|| Balancer::new(chart, Some(order)))
                        .flatten()
                },
            )
        },
    );
    // Where the system could not be made, `from_angles` says why.
    let lay_out = |angles: &[[f64; 3]]| match &prepared {
        Some(layout) => layout.solve(chart, angles),
        None => layout::from_angles(chart, topo, angles, Some(order)),
    };
    let balanced = |uv: Vec<DVec2>| {
        balancer
            .as_ref()
            .and_then(|b| b.balance(chart, &uv, opts.area_weight, opts.balance_rounds))
            .unwrap_or((uv, 0))
    };
    let solved = solved.and_then(|(solution, laid)| {
        let laid = match (laid, &prepared) {
            (Some(laid), _) => laid,
            (None, Some(layout)) if solution.residual <= EXACT_RESIDUAL => {
                unfold(layout.propagate(chart, topo, &solution.angles))
            }
            (None, _) => unfold(lay_out(&solution.angles)?),
        };
        Ok((solution, laid))
    });
    let abf_method = |solution: &abf::AbfSolution, unfolded, balance_rounds| Method::AbfPlusPlus {
        iterations: solution.iterations,
        residual: solution.residual,
        converged: solution.converged,
        unfolded,
        balance_rounds,
    };
    // An unconverged ABF++ layout without flips, held against boundary
    // first flattening's.
    let mut unconverged = None;
    let reason = match solved {
        Ok((solution, laid)) => match laid {
            (uv, unfolded, 0) if solution.converged => {
                let (uv, balance_rounds) = balanced(uv);
                return Ok(Flattened {
                    uv,
                    method: abf_method(&solution, unfolded, balance_rounds),
                });
            }
            (uv, unfolded, left) => {
                let mut reason = String::new();
                if !solution.converged {
                    reason = format!(
                        "ABF++ did not converge in {} Newton steps (residual {:.2e}); ",
                        solution.iterations, solution.residual
                    );
                }
                if left == 0 {
                    reason += "its best layout was less conformal";
                    unconverged = Some((solution, uv, unfolded));
                } else {
                    reason += &format!("the ABF++ layout flipped {left} triangles");
                }
                reason
            }
        },
        Err(e) => e.to_string(),
    };
    let bff = boundary_first(chart, topo).map(unfold);
    if let Some((solution, uv, unfolded)) = unconverged {
        let abf_conf = conf_mean(chart, &uv);
        match &bff {
            Ok((bff_uv, _, 0)) if conf_mean(chart, bff_uv) < abf_conf => {}
            _ => {
                let (uv, balance_rounds) = balanced(uv);
                return Ok(Flattened {
                    uv,
                    method: abf_method(&solution, unfolded, balance_rounds),
                });
            }
        }
    }
    // Boundary first flattening, or, when it leaves flips, whichever of it
    // and LSCM leaves fewer.
    let (bff, reason) = match bff {
        Ok((uv, unfolded, 0)) => {
            let (uv, balance_rounds) = balanced(uv);
            return Ok(Flattened {
                uv,
                method: Method::BoundaryFirst {
                    reason,
                    unfolded,
                    flipped: 0,
                    balance_rounds,
                },
            });
        }
        Ok(bff) => (Some(bff), reason),
        Err(e) => (None, format!("{reason}; boundary first flattening: {e}")),
    };
    let lscm = unfold(lay_out(&corner_angles(chart))?);
    Ok(match bff {
        Some((uv, unfolded, left)) if left <= lscm.2 => {
            let (uv, balance_rounds) = balanced(uv);
            Flattened {
                method: Method::BoundaryFirst {
                    reason,
                    unfolded,
                    flipped: flipped(chart, &uv),
                    balance_rounds,
                },
                uv,
            }
        }
        _ => Flattened {
            uv: lscm.0,
            method: Method::Lscm {
                reason,
                unfolded: lscm.1,
                flipped: lscm.2,
            },
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unconverged_abf_competes_with_boundary_first_flattening() {
        // A sphere cut open pole to pole, and ABF++ given no Newton step:
        // its best iterate is the 3D angles.
        let chart = crate::unwrap::cutgraph::cut_open_sphere(3);
        let chart_topo = Topology::build(&chart).unwrap();
        let opts = AbfOptions {
            max_iterations: 0,
            ..AbfOptions::default()
        };
        let unbalanced = AbfOptions {
            balance_rounds: 0,
            ..opts.clone()
        };
        let flat = flatten(&chart, &chart_topo, &unbalanced).unwrap();
        assert_eq!(super::flipped(&chart, &flat.uv), 0);
        let bff = boundary_first(&chart, &chart_topo).unwrap();
        let angles =
            layout::from_angles(&chart, &chart_topo, &corner_angles(&chart), None).unwrap();
        let (kept, other) = match &flat.method {
            Method::AbfPlusPlus {
                converged,
                iterations,
                ..
            } => {
                assert!(!converged);
                assert_eq!(*iterations, 0);
                (conf_mean(&chart, &flat.uv), conf_mean(&chart, &bff))
            }
            Method::BoundaryFirst { reason, .. } => {
                assert!(reason.contains("did not converge"), "{reason}");
                (conf_mean(&chart, &flat.uv), conf_mean(&chart, &angles))
            }
            other => panic!("{other:?}"),
        };
        assert!(kept <= other, "kept conf {kept}, other {other}");
        // With balancing, the kept layout still has no flips.
        let balanced = flatten(&chart, &chart_topo, &opts).unwrap();
        assert_eq!(super::flipped(&chart, &balanced.uv), 0);
    }
}
