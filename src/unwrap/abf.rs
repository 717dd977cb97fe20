//! ABF++: angle-based flattening (Sheffer, Lévy, Mogilnitsky, Bogomyakov
//! 2005) of a disk-shaped chart.
//!
//! Unknowns: the planar angle alpha of every corner. Targets beta: the 3D
//! angles, scaled around interior vertices to sum to 2 pi, clamped to
//! [1, 179] degrees. Energy: sum (alpha - beta)^2 / beta^2, subject to
//! - triangle: the angles of each face sum to pi;
//! - planarity: the angles around each interior vertex sum to 2 pi;
//! - wheel (length): around each interior vertex, sum log sin of the angles
//!   after the vertex equals that of the angles before it (law of sines
//!   around the wheel; the log form of the paper's product).
//!
//! Newton on the Lagrangian. Every constraint is a sum of functions of
//! single angles, so the Hessian in alpha is diagonal (2/beta^2 plus the
//! wheel terms' lambda/sin^2, kept positive), and ABF++'s two eliminations
//! apply: the angle block (diagonal), then the triangle block (one row per
//! face), leaving one sparse SPD system of size 2 x interior vertices, solved
//! by sparse Cholesky (`linalg`). Steps are halved only while they would
//! leave (0, pi).

use std::f64::consts::{PI, TAU};

use crate::error::{Error, Result};
use crate::linalg::{SpdPattern, VertexOrder};
use crate::mesh::curvature::corner_angles;
use crate::mesh::{Topology, TriMesh, VertexId};

const MIN_ANGLE: f64 = PI / 180.0;
const MAX_ANGLE: f64 = PI - PI / 180.0;

#[derive(Clone, Debug)]
pub struct AbfOptions {
    pub max_iterations: usize,
    /// Converged when every constraint and every component of the
    /// Lagrangian's gradient is below this.
    pub tolerance: f64,
    /// Weight of area against angle in the balancing rounds that follow
    /// the layout (`balance`: the hybrid model's lambda; 0: ABF++ alone).
    pub area_weight: f64,
    /// At most this many balancing rounds.
    pub balance_rounds: usize,
}

impl Default for AbfOptions {
    fn default() -> Self {
        // Clean meshes converge quadratically in a handful of steps; noisy
        // scans (slivers, near-flat folds) converge linearly, about a
        // third of the residual gone per step, and need up to ~60 steps
        // to 1e-7 (a 108k-face scanned bust: 58). An angle error of 1e-7
        // rad is far below what the least-squares layout can show.
        // Area weight 0.02: on the bunny area_log falls from 0.294 after
        // the first round to 0.238 while conformality stays inside the
        // bunny's 1.02 target (1.018 -> 1.019). The
        // local/global rounds converge slowly: over rounds 10 to 100,
        // area_log keeps falling (bunny 0.261 -> 0.220, bone 0.285 ->
        // 0.235, cow 0.209 -> 0.162) while conf_mean moves by at most
        // 0.004; 30 rounds take half of that, at about 20 ms a round on
        // the bunny.
        AbfOptions {
            max_iterations: 100,
            tolerance: 1e-7,
            area_weight: 0.02,
            balance_rounds: 30,
        }
    }
}

#[derive(Clone, Debug)]
pub struct AbfSolution {
    /// Planar angle of every corner.
    pub angles: Vec<[f64; 3]>,
    pub iterations: usize,
    /// Largest constraint or gradient component of `angles`.
    pub residual: f64,
    /// Whether the residual fell below the tolerance; if not, `angles` is
    /// the iterate with the smallest residual in `max_iterations` steps,
    /// or, when the run stalled and its layout stopped improving
    /// (`solve_until`), the best-scored iterate.
    pub converged: bool,
}

/// Constraint rows of a vertex: planarity at 2k, wheel at 2k + 1, for the
/// k-th interior vertex.
#[derive(Clone)]
struct Rows {
    of_vertex: Vec<u32>,
    count: usize,
}

const NOT_INTERIOR: u32 = u32::MAX;

impl Rows {
    fn new(topo: &Topology) -> Rows {
        let mut k = 0;
        let of_vertex = (0..topo.num_vertices())
            .map(|v| {
                let v = VertexId::from(v);
                if topo.is_referenced(v) && !topo.is_boundary_vertex(v) {
                    k += 1;
                    k - 1
                } else {
                    NOT_INTERIOR
                }
            })
            .collect();
        Rows {
            of_vertex,
            count: k as usize,
        }
    }
    /// Global rows of the six local slots of a triangle (plan, wheel per
    /// corner), `None` for boundary vertices.
    fn slots(&self, t: &[u32; 3]) -> [Option<u32>; 6] {
        let mut s = [None; 6];
        for i in 0..3 {
            let k = self.of_vertex[t[i] as usize];
            if k != NOT_INTERIOR {
                s[2 * i] = Some(2 * k);
                s[2 * i + 1] = Some(2 * k + 1);
            }
        }
        s
    }
}

/// The Jacobian column of corner `i` of a triangle over its six local
/// slots: planarity of its own vertex, +cot on the wheel of the vertex
/// before it (it is that vertex's "next" angle), -cot on the wheel of the
/// vertex after it.
#[inline]
fn jacobian_column(i: usize, cot: f64) -> [f64; 6] {
    let mut j = [0.0; 6];
    j[2 * i] = 1.0;
    j[2 * ((i + 2) % 3) + 1] = cot;
    j[2 * ((i + 1) % 3) + 1] = -cot;
    j
}

/// The fixed data of one flattening: faces, constraint rows, targets and
/// weights.
struct Problem<'a> {
    tris: &'a [[u32; 3]],
    rows: Rows,
    beta: Vec<[f64; 3]>,
    weight: Vec<[f64; 3]>,
}

/// Angles and Lagrange multipliers (one per face, two per interior vertex).
#[derive(Clone)]
struct State {
    alpha: Vec<[f64; 3]>,
    lambda_tri: Vec<f64>,
    lambda: Vec<f64>,
}

/// The Lagrangian's gradient in every angle and every constraint's value.
struct Residuals {
    grad: Vec<[f64; 3]>,
    c_tri: Vec<f64>,
    c_vertex: Vec<f64>,
}

/// Newton steps over which a stall is judged: the best residual must at
/// least halve in this many steps.
const STALL_WINDOW: usize = 10;
/// A stalled run ends when its layout's score improved by at most this
/// since the last stall.
const SETTLED: f64 = 1e-3;

/// Flatten a disk-shaped chart's angles: ABF++ to convergence or the
/// step cap.
pub fn solve(mesh: &TriMesh, topo: &Topology, opts: &AbfOptions) -> Result<AbfSolution> {
    solve_until(mesh, topo, opts, None, &mut |_| None::<(f64, ())>).map(|(solution, _)| solution)
}

/// ABF++, stopping early once more steps would not improve the layout. On
/// a raw scan the residual can fall fast and then by only a few percent a
/// step for the rest of the step cap (a 108k-face scanned bust: 12% a step
/// to step 36, then 2%), while the layout of the best iterate stopped
/// improving long before (its conf_mean within 0.001 from step 20 to 92;
/// on parts of that bust split for an atlas it grows worse, 1.045 at the
/// first stall and 1.058 at the cap). So whenever the best residual has
/// not halved in `STALL_WINDOW` steps, `score` judges the best iterate:
/// the caller lays it out and returns its distortion, lower better, with
/// the layout, or `None` when it cannot be used (some iterates of such a
/// run cannot be laid out, or fold). Once a stall improves on the best
/// score so far by no more than `SETTLED`, the run ends with the
/// best-scored iterate, reported as not converged, and the layout its
/// score came with (so the caller does not lay it out again); so it does
/// at the step cap when a stall scored one. `order`, when given, orders
/// the mesh's vertices for the reduced system's factorisation.
pub fn solve_until<T, F>(
    mesh: &TriMesh,
    topo: &Topology,
    opts: &AbfOptions,
    order: Option<&VertexOrder>,
    score: &mut F,
) -> Result<(AbfSolution, Option<T>)>
where
    F: FnMut(&[[f64; 3]]) -> Option<(f64, T)>,
{
    Prepared::new(mesh, topo, order)?.solve_until(opts, score)
}

/// An ABF++ problem ready for its Newton steps: the target angles and
/// weights, the reduced system's symbolic factorisation, the starting
/// state and its residuals. Made on both cores: the sparsity and its
/// symbolic factorisation on one, the angles and the first residuals on
/// the other.
pub struct Prepared<'a> {
    problem: Problem<'a>,
    pattern: Option<SpdPattern>,
    state: State,
    residuals: Residuals,
}

impl<'a> Prepared<'a> {
    /// `order`, when given, orders the mesh's vertices for the reduced
    /// system's factorisation.
    pub fn new(
        mesh: &'a TriMesh,
        topo: &Topology,
        order: Option<&VertexOrder>,
    ) -> Result<Prepared<'a>> {
        let tris = &mesh.triangles;
        let rows = Rows::new(topo);
        let (pattern, (problem, state, residuals)) = rayon::join(
            || {
                // Sparsity of the reduced system: per face, the pairs of
                // its slots.
                let mut positions = Vec::with_capacity(tris.len() * 21);
                for t in tris {
                    let s = rows.slots(t);
                    for p in s.iter().flatten() {
                        for q in s.iter().flatten() {
                            if p >= q {
                                positions.push((*p, *q));
                            }
                        }
                    }
                }
                let pattern = match rows.count {
                    0 => None,
                    n => Some(SpdPattern::of_vertices(
                        2 * n,
                        &positions,
                        order,
                        &rows.of_vertex,
                        2,
                    )?),
                };
                Ok::<_, Error>(pattern)
            },
            || {
                let problem = Problem::new(mesh, rows.clone());
                let state = State {
                    alpha: problem.beta.clone(),
                    lambda_tri: vec![0.0; tris.len()],
                    lambda: vec![0.0; 2 * problem.rows.count],
                };
                let residuals = problem.residuals(&state);
                (problem, state, residuals)
            },
        );
        Ok(Prepared {
            problem,
            pattern: pattern?,
            state,
            residuals,
        })
    }

    /// `solve_until` from here.
    pub fn solve_until<T, F>(
        self,
        opts: &AbfOptions,
        score: &mut F,
    ) -> Result<(AbfSolution, Option<T>)>
    where
        F: FnMut(&[[f64; 3]]) -> Option<(f64, T)>,
    {
        let Prepared {
            problem,
            pattern,
            mut state,
            mut residuals,
        } = self;
        let mut residual = residual_norm(&problem.weight, &residuals);
        let mut iterations = 0;
        let mut values = vec![0.0; pattern.as_ref().map_or(0, SpdPattern::entries)];
        // The iterate with the smallest residual: on a raw scan the residual
        // can creep down linearly and rise again (a 108k-face scanned bust:
        // 0.19 after 65 steps, 0.10 after 100), and the least-squares layout
        // of such angles is still far more conformal than a fallback's.
        let mut best = (residual, state.alpha.clone());
        // Best residual after each step, the step of the last stall, and the
        // best-scored iterate (score, residual, angles, layout).
        let mut best_after = vec![residual];
        let mut stalled_at = 0;
        let mut kept: Option<(f64, f64, Vec<[f64; 3]>, T)> = None;
        while residual > opts.tolerance {
            let capped = iterations == opts.max_iterations;
            let stalled = iterations >= stalled_at + STALL_WINDOW
                && best.0 > 0.5 * best_after[iterations - STALL_WINDOW];
            if stalled || (capped && kept.is_some()) {
                stalled_at = iterations;
                let previous = kept.as_ref().map(|k| k.0);
                if let Some((now, laid)) = score(&best.1)
                    && previous.is_none_or(|p| now < p)
                {
                    kept = Some((now, best.0, best.1.clone(), laid));
                }
                // Ends when the layout no longer improves by more than SETTLED
                // (an unusable one is no improvement), or at the cap.
                let settled =
                    previous.is_some_and(|p| kept.as_ref().is_some_and(|k| k.0 >= p - SETTLED));
                if (settled || capped)
                    && let Some((_, residual, angles, laid)) = kept.take()
                {
                    let solution = AbfSolution {
                        angles,
                        iterations,
                        residual,
                        converged: false,
                    };
                    return Ok((solution, Some(laid)));
                }
            }
            if capped {
                let solution = AbfSolution {
                    angles: best.1,
                    iterations,
                    residual: best.0,
                    converged: false,
                };
                return Ok((solution, None));
            }
            iterations += 1;
            let step = problem.newton_step(&state, residuals, pattern.as_ref(), &mut values)?;
            // Full Newton steps, as ABF++ takes them: the residual may rise on the
            // first steps from a sliver-rich start and then falls fast, so a
            // monotone line search would stall. Steps are only shortened to keep
            // every angle inside (0, pi).
            let mut s = 1.0;
            loop {
                let trial = state.plus(&step, s);
                if trial.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI) {
                    state = trial;
                    break;
                }
                s *= 0.5;
                if s < 1e-4 {
                    return Err(Error::invalid(format!(
                        "ABF++ could not keep the angles valid after {iterations} Newton steps"
                    )));
                }
            }
            residuals = problem.residuals(&state);
            residual = residual_norm(&problem.weight, &residuals);
            if !residual.is_finite() || residual > 1e6 {
                return Err(Error::invalid(format!(
                    "ABF++ diverged after {iterations} Newton steps (residual {residual:.2e})"
                )));
            }
            if residual < best.0 {
                best = (residual, state.alpha.clone());
            }
            best_after.push(best.0);
        }
        let solution = AbfSolution {
            angles: state.alpha,
            iterations,
            residual,
            converged: true,
        };
        Ok((solution, None))
    }
}

/// What eliminating one face's angles and triangle constraint leaves
/// behind: the inverse Hessian of its angles, their Jacobian columns over
/// the face's six vertex-constraint slots, b = J2 H^-1 J1^T, A = J1 H^-1
/// J1^T, and the face's reduced residual r1.
struct FaceElimination {
    inv_h: [f64; 3],
    cols: [[f64; 6]; 3],
    b: [f64; 6],
    a: f64,
    r1: f64,
}

/// A Newton direction: changes of every angle and multiplier.
type Step = State;

impl State {
    fn plus(&self, step: &Step, s: f64) -> State {
        let add = |x: &[f64], d: &[f64]| x.iter().zip(d).map(|(x, d)| x + s * d).collect();
        State {
            alpha: self
                .alpha
                .iter()
                .zip(&step.alpha)
                .map(|(a, d)| std::array::from_fn(|i| a[i] + s * d[i]))
                .collect(),
            lambda_tri: add(&self.lambda_tri, &step.lambda_tri),
            lambda: add(&self.lambda, &step.lambda),
        }
    }
}

/// Largest constraint value or gradient component, the gradient measured
/// in angle units (divided by its weight 2/beta^2).
fn residual_norm(weight: &[[f64; 3]], r: &Residuals) -> f64 {
    let g = r
        .grad
        .iter()
        .zip(weight)
        .flat_map(|(g, w)| (0..3).map(move |i| g[i] / (2.0 * w[i])));
    g.chain(r.c_tri.iter().copied())
        .chain(r.c_vertex.iter().copied())
        .fold(0.0f64, |m, x| m.max(x.abs()))
}

impl<'a> Problem<'a> {
    /// The target angles (interior vertices' 3D angles scaled to sum to
    /// 2 pi) and their weights.
    fn new(mesh: &'a TriMesh, rows: Rows) -> Problem<'a> {
        let tris = &mesh.triangles;
        let theta = corner_angles(mesh);
        let mut sum_at = vec![0.0; mesh.num_vertices()];
        for (t, a) in tris.iter().zip(&theta) {
            for i in 0..3 {
                sum_at[t[i] as usize] += a[i];
            }
        }
        let beta: Vec<[f64; 3]> = tris
            .iter()
            .zip(&theta)
            .map(|(t, a)| {
                std::array::from_fn(|i| {
                    let v = t[i] as usize;
                    let scaled = if rows.of_vertex[v] != NOT_INTERIOR && sum_at[v] > 0.0 {
                        a[i] * TAU / sum_at[v]
                    } else {
                        a[i]
                    };
                    scaled.clamp(MIN_ANGLE, MAX_ANGLE)
                })
            })
            .collect();
        let weight = beta.iter().map(|b| b.map(|x| 1.0 / (x * x))).collect();
        Problem {
            tris,
            rows,
            weight,
            beta,
        }
    }

    fn residuals(&self, x: &State) -> Residuals {
        let mut c_tri = vec![0.0; self.tris.len()];
        let mut c_vertex = vec![0.0; x.lambda.len()];
        for k in 0..x.lambda.len() / 2 {
            c_vertex[2 * k] = -TAU;
        }
        let mut grad = Vec::with_capacity(self.tris.len());
        for (f, t) in self.tris.iter().enumerate() {
            let slots = self.rows.slots(t);
            let a = x.alpha[f];
            c_tri[f] = a[0] + a[1] + a[2] - PI;
            let mut g = [0.0; 3];
            for i in 0..3 {
                let j = jacobian_column(i, a[i].cos() / a[i].sin());
                g[i] = 2.0 * self.weight[f][i] * (a[i] - self.beta[f][i]) + x.lambda_tri[f];
                for (slot, &coef) in j.iter().enumerate() {
                    if let Some(r) = slots[slot] {
                        g[i] += coef * x.lambda[r as usize];
                    }
                }
                if let Some(r) = slots[2 * i] {
                    c_vertex[r as usize] += a[i];
                }
                let log_sin = a[i].sin().ln();
                if let Some(r) = slots[2 * ((i + 2) % 3) + 1] {
                    c_vertex[r as usize] += log_sin;
                }
                if let Some(r) = slots[2 * ((i + 1) % 3) + 1] {
                    c_vertex[r as usize] -= log_sin;
                }
            }
            grad.push(g);
        }
        Residuals {
            grad,
            c_tri,
            c_vertex,
        }
    }

    /// One Newton step on the Lagrangian from state `x`, whose residuals
    /// are `residuals`, with ABF++'s two eliminations.
    fn newton_step(
        &self,
        x: &State,
        residuals: Residuals,
        pattern: Option<&SpdPattern>,
        values: &mut [f64],
    ) -> Result<Step> {
        let Residuals {
            grad,
            c_tri,
            c_vertex,
        } = residuals;
        let mut rhs = c_vertex;
        let mut faces: Vec<FaceElimination> = Vec::with_capacity(self.tris.len());
        let mut next_value = 0;
        for (f, t) in self.tris.iter().enumerate() {
            let slots = self.rows.slots(t);
            let a = x.alpha[f];
            let mut e = FaceElimination {
                inv_h: [0.0; 3],
                cols: [[0.0; 6]; 3],
                b: [0.0; 6],
                a: 0.0,
                r1: c_tri[f],
            };
            for i in 0..3 {
                let (s, c) = a[i].sin_cos();
                let mut col = jacobian_column(i, c / s);
                for (slot, x) in col.iter_mut().enumerate() {
                    if slots[slot].is_none() {
                        *x = 0.0;
                    }
                }
                // d^2/da^2 log sin a = -1/sin^2 a, with the wheel's signs;
                // kept at least half the energy's curvature so the reduced
                // system stays positive definite.
                let wheel_before =
                    slots[2 * ((i + 2) % 3) + 1].map_or(0.0, |r| x.lambda[r as usize]);
                let wheel_after =
                    slots[2 * ((i + 1) % 3) + 1].map_or(0.0, |r| x.lambda[r as usize]);
                let h = 2.0 * self.weight[f][i] + (wheel_after - wheel_before) / (s * s);
                e.inv_h[i] = 1.0 / h.max(self.weight[f][i]);
                e.cols[i] = col;
                e.a += e.inv_h[i];
                e.r1 -= e.inv_h[i] * grad[f][i];
                for (slot, &coef) in col.iter().enumerate() {
                    e.b[slot] += e.inv_h[i] * coef;
                    if let Some(r) = slots[slot] {
                        // r2 = c - J2 H^-1 g
                        rhs[r as usize] -= e.inv_h[i] * grad[f][i] * coef;
                    }
                }
            }
            // Schur complement block, in the pattern's order.
            for p in 0..6 {
                for q in 0..6 {
                    if let (Some(r), Some(c)) = (slots[p], slots[q])
                        && r >= c
                    {
                        let cross: f64 = (0..3)
                            .map(|i| e.inv_h[i] * e.cols[i][p] * e.cols[i][q])
                            .sum();
                        values[next_value] = cross - e.b[p] * e.b[q] / e.a;
                        next_value += 1;
                    }
                }
            }
            // rhs2 = r2 - b r1 / A
            for (slot, row) in slots.iter().enumerate() {
                if let Some(r) = row {
                    rhs[*r as usize] -= e.b[slot] * e.r1 / e.a;
                }
            }
            faces.push(e);
        }
        let mut d_lambda = rhs;
        if let Some(pattern) = pattern {
            pattern.factor(values)?.solve(&mut d_lambda);
        }
        let mut step = State {
            alpha: vec![[0.0; 3]; self.tris.len()],
            lambda_tri: vec![0.0; self.tris.len()],
            lambda: Vec::new(),
        };
        for (f, t) in self.tris.iter().enumerate() {
            let slots = self.rows.slots(t);
            let e = &faces[f];
            let local: [f64; 6] =
                std::array::from_fn(|slot| slots[slot].map_or(0.0, |r| d_lambda[r as usize]));
            let dot = |v: &[f64; 6]| v.iter().zip(&local).map(|(x, y)| x * y).sum::<f64>();
            let d_tri = (e.r1 - dot(&e.b)) / e.a;
            step.lambda_tri[f] = d_tri;
            step.alpha[f] =
                std::array::from_fn(|i| -e.inv_h[i] * (grad[f][i] + d_tri + dot(&e.cols[i])));
        }
        step.lambda = d_lambda;
        Ok(step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Six triangles around a centre vertex lifted to height `h`.
    fn hexagon_fan(h: f64) -> TriMesh {
        let mut positions = vec![DVec3::new(0.0, 0.0, h)];
        for k in 0..6 {
            let a = std::f64::consts::TAU * k as f64 / 6.0;
            positions.push(DVec3::new(a.cos(), a.sin(), 0.0));
        }
        let triangles = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        TriMesh::new(positions, triangles)
    }

    fn solve_mesh(mesh: &TriMesh) -> AbfSolution {
        let topo = Topology::build(mesh).unwrap();
        solve(mesh, &topo, &AbfOptions::default()).unwrap()
    }

    #[test]
    fn a_flat_fan_keeps_its_angles() {
        let mesh = hexagon_fan(0.0);
        let solution = solve_mesh(&mesh);
        for (a, t) in solution.angles.iter().zip(corner_angles(&mesh)) {
            for i in 0..3 {
                assert!((a[i] - t[i]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn a_cone_fan_opens_into_a_regular_hexagon() {
        // Symmetry: the centre's six angles become 2 pi / 6 and every
        // triangle equilateral, whatever the cone's height.
        for h in [0.3, 1.0, 3.0] {
            let solution = solve_mesh(&hexagon_fan(h));
            assert!(solution.iterations > 0);
            for a in &solution.angles {
                for x in a {
                    assert!((x - PI / 3.0).abs() < 1e-9, "h {h}: angle {x}");
                }
            }
        }
    }

    #[test]
    fn a_cut_sphere_satisfies_every_constraint() {
        let chart = crate::unwrap::cutgraph::cut_open_sphere(3);
        let chart_topo = Topology::build(&chart).unwrap();
        let solution = solve(&chart, &chart_topo, &AbfOptions::default()).unwrap();
        // Triangle sums, vertex sums and wheel products hold.
        for a in &solution.angles {
            assert!((a.iter().sum::<f64>() - PI).abs() < 1e-9);
        }
        let mut sum = vec![0.0; chart.num_vertices()];
        let mut wheel = vec![0.0; chart.num_vertices()];
        for (t, a) in chart.triangles.iter().zip(&solution.angles) {
            for i in 0..3 {
                sum[t[i] as usize] += a[i];
                wheel[t[i] as usize] += a[(i + 1) % 3].sin().ln() - a[(i + 2) % 3].sin().ln();
            }
        }
        for v in 0..chart.num_vertices() {
            if !chart_topo.is_boundary_vertex(VertexId::from(v)) {
                assert!((sum[v] - TAU).abs() < 1e-9);
                assert!(wheel[v].abs() < 1e-9);
            }
        }
        let uv = crate::unwrap::layout::from_angles(&chart, &chart_topo, &solution.angles, None)
            .unwrap();
        assert_eq!(crate::unwrap::flatten::flipped(&chart, &uv), 0);
    }

    #[test]
    fn a_stalled_run_ends_once_its_layout_stops_improving_with_the_best_iterate() {
        // A tolerance of 0 cannot be met: once the residual sits at
        // rounding level the best residual stops halving, and the run
        // stalls every `STALL_WINDOW` steps.
        let chart = crate::unwrap::cutgraph::cut_open_sphere(3);
        let topo = Topology::build(&chart).unwrap();
        let opts = AbfOptions {
            tolerance: 0.0,
            max_iterations: 60,
            ..AbfOptions::default()
        };
        // The iterates scored, and how the run ended, for scores given by
        // the number of the stall.
        let run = |scores: &dyn Fn(usize) -> Option<f64>| {
            let mut seen: Vec<Vec<[f64; 3]>> = Vec::new();
            let (solution, _) = solve_until(&chart, &topo, &opts, None, &mut |angles| {
                seen.push(angles.to_vec());
                scores(seen.len() - 1).map(|s| (s, ()))
            })
            .unwrap();
            assert!(!solution.converged);
            (seen, solution)
        };
        // Unusable iterates never end the run: it stops at the step cap.
        let (seen, capped) = run(&|_| None);
        assert!(seen.len() >= 2, "asked {} times", seen.len());
        assert_eq!(capped.iterations, 60);
        // A worse layout at the second stall ends it with the first.
        let (seen, worse) = run(&|k| Some(1.0 + 0.01 * k as f64));
        assert_eq!(seen.len(), 2);
        assert!(worse.iterations < 60);
        assert_eq!(worse.angles, seen[0]);
        // So does one better by less than SETTLED, with the second.
        let (seen, settled) = run(&|k| Some(1.0 - 0.0005 * k as f64));
        assert_eq!(seen.len(), 2);
        assert_eq!(settled.angles, seen[1]);
        // Layouts that keep improving run to the cap, which keeps the best
        // scored: the one scored at the cap.
        let (seen, improving) = run(&|k| Some(1.0 - 0.01 * k as f64));
        assert!(seen.len() >= 3);
        assert_eq!(improving.iterations, 60);
        assert_eq!(&improving.angles, seen.last().unwrap());
    }
}
