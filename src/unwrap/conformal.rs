//! The conformal flattening of least area distortion, and the Dirichlet
//! problems it is made of.
//!
//! A conformal map scales lengths by e^u, where the log scale factor u
//! solves the Poisson equation Delta u = K (K the Gaussian curvature); with
//! u = 0 on the boundary this is the conformal flattening of least area
//! distortion (Springborn, Schröder, Pinkall 2008; Sawhney and Crane 2017).
//! One sparse solve of size V instead of ABF++'s Newton steps: on the bunny
//! it predicts ABF++'s mean |log area ratio| to within 1%, which is what
//! Seamster refinement needs to decide where to cut next, and
//! `boundary_first` lays the map out when ABF++ cannot.

use std::f64::consts::TAU;

use glam::DVec2;

use super::metrics::double_area;
use crate::error::{Error, Result};
use crate::linalg::{Cholesky, SpdPattern, VertexOrder};
use crate::mesh::curvature::{angle_defects, corner_angles};
use crate::mesh::{Topology, TriMesh, VertexId};

/// Half the cotangent of an 84 degree corner: the least weight of a
/// `positive` Dirichlet problem.
const MIN_WEIGHT: f64 = 0.05;

/// The cotangent Laplacian of a chart with Dirichlet conditions on some
/// of its vertices (its boundary, or one pinned vertex), factored once for
/// any number of solves.
pub struct Dirichlet {
    /// Row of each free vertex, `u32::MAX` where the value is given.
    index: Vec<u32>,
    /// Every edge once per face with its half-cotangent weight.
    edges: Vec<(u32, u32, f64)>,
    /// The edges between a free vertex and a fixed one, as (the free one's
    /// row, the fixed vertex, weight), in `edges`' order: what moves given
    /// values to the right-hand side (a pinned chart has a handful; every
    /// solve used to look through all the edges for them).
    couplings: Vec<(u32, u32, f64)>,
    matrix: Option<Cholesky>,
}

impl Dirichlet {
    /// With `positive`, no weight is below that of an 84 degree corner
    /// (obtuse corners' cotangents are negative): every free value is
    /// then an average of its neighbours' (Tutte), so a harmonic layout
    /// cannot fold around a sliver, and no vertex leans on a single
    /// neighbour, at the price of exactness where triangles are obtuse.
    /// `order`, when given, orders the free vertices (else AMD does).
    pub fn new(
        chart: &TriMesh,
        angles: &[[f64; 3]],
        fixed: &[bool],
        positive: bool,
        order: Option<&VertexOrder>,
    ) -> Result<Dirichlet> {
        let (index, count) = unknowns(chart, |v| !fixed[v]);
        let edges = cotangent_edges(chart, angles, positive);
        // L = minus the Laplacian, integrated, over the free vertices.
        let mut positions = Vec::with_capacity(edges.len() * 3);
        let mut values = Vec::with_capacity(edges.len() * 3);
        for &(a, b, w) in &edges {
            let (p, q) = (index[a as usize], index[b as usize]);
            for (x, y, value) in [(p, p, w), (q, q, w), (p.max(q), p.min(q), -w)] {
                if x != u32::MAX && y != u32::MAX {
                    positions.push((x, y));
                    values.push(value);
                }
            }
        }
        let matrix = match count {
            0 => None,
            n => {
                let pattern = SpdPattern::of_vertices(n as usize, &positions, order, &index, 1)?;
                Some(pattern.factor(&values)?)
            }
        };
        let mut couplings = Vec::new();
        for &(a, b, w) in &edges {
            for (free, known) in [(a, b), (b, a)] {
                let k = index[free as usize];
                if k != u32::MAX && index[known as usize] == u32::MAX {
                    couplings.push((k, known, w));
                }
            }
        }
        Ok(Dirichlet {
            index,
            edges,
            couplings,
            matrix,
        })
    }

    /// The problem with the chart's boundary fixed.
    pub fn on_boundary(
        chart: &TriMesh,
        topo: &Topology,
        angles: &[[f64; 3]],
        positive: bool,
    ) -> Result<Dirichlet> {
        let fixed: Vec<bool> = (0..chart.num_vertices())
            .map(|v| topo.is_boundary_vertex(VertexId::from(v)))
            .collect();
        Dirichlet::new(chart, angles, &fixed, positive, None)
    }

    /// The weight of the edge opposite corner `c` of face `f`.
    pub fn weight(&self, f: usize, c: usize) -> f64 {
        self.edges[3 * f + c].2
    }

    /// The x with L x = `source` at every free vertex and x = `given` at
    /// the fixed ones (`given`'s free entries are ignored).
    pub fn solve(&self, given: &[f64], source: &[f64]) -> Vec<f64> {
        let mut rhs: Vec<f64> = (0..self.index.len())
            .filter(|&v| self.index[v] != u32::MAX)
            .map(|v| source[v])
            .collect();
        // Known boundary values move to the right-hand side.
        for &(k, known, w) in &self.couplings {
            rhs[k as usize] += w * given[known as usize];
        }
        if let Some(m) = &self.matrix {
            m.solve(&mut rhs);
        }
        (0..self.index.len())
            .map(|v| match self.index[v] {
                u32::MAX => given[v],
                k => rhs[k as usize],
            })
            .collect()
    }

    /// (L x) at every vertex: at a boundary vertex, the flux of x out
    /// through it (its normal derivative, integrated).
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        for &(a, b, w) in &self.edges {
            let d = w * (x[a as usize] - x[b as usize]);
            out[a as usize] += d;
            out[b as usize] -= d;
        }
        out
    }
}

/// Log scale factor u of every vertex of a disk chart (0 on the boundary).
pub fn log_scale(chart: &TriMesh, topo: &Topology) -> Result<Vec<f64>> {
    Ok(LogScale::solve(chart, topo)?.u)
}

/// `log_scale` of the surface cut open through given vertices (its
/// boundary and its cut's), solved on the uncut surface: a vertex off the
/// cut has the same neighbours, weights and defect in both, and every copy
/// of a cut vertex is held at 0, so the cut surface need not be built.
/// Every referenced vertex is an unknown, the held ones' rows and columns
/// those of the identity (their value 0, exactly: the factor's entries in
/// them stay 0), so one pattern and one symbolic factorisation serve
/// every cut Seamster tries, each only refactored.
pub struct OpenedLogScale {
    /// Unknown of each referenced vertex, `u32::MAX` for the others.
    index: Vec<u32>,
    /// Every edge once per face with its half-cotangent weight.
    edges: Vec<(u32, u32, f64)>,
    /// -(angle defect) of each vertex.
    source: Vec<f64>,
    pattern: Option<SpdPattern>,
}

impl OpenedLogScale {
    /// `angles` and `defect` are the surface's (`corner_angles`,
    /// `angle_defects`); `order` orders its vertices.
    pub fn new(
        surface: &TriMesh,
        angles: &[[f64; 3]],
        defect: &[f64],
        order: &VertexOrder,
    ) -> Result<OpenedLogScale> {
        let (index, count) = unknowns(surface, |_| true);
        let edges = cotangent_edges(surface, angles, false);
        // Per edge its two diagonal entries and its off-diagonal one, then
        // one more diagonal entry per vertex (1 where it is held).
        let mut positions = Vec::with_capacity(edges.len() * 3 + count as usize);
        for &(a, b, _) in &edges {
            let (p, q) = (index[a as usize], index[b as usize]);
            positions.extend([(p, p), (q, q), (p.max(q), p.min(q))]);
        }
        positions.extend((0..count).map(|k| (k, k)));
        let pattern = match count {
            0 => None,
            n => Some(SpdPattern::of_vertices(
                n as usize,
                &positions,
                Some(order),
                &index,
                1,
            )?),
        };
        Ok(OpenedLogScale {
            index,
            edges,
            source: defect.iter().map(|d| -d).collect(),
            pattern,
        })
    }

    /// The log scale of the surface opened through the `opened` vertices.
    pub fn solve(&self, opened: &[bool]) -> Result<Vec<f64>> {
        let Some(pattern) = &self.pattern else {
            return Ok(vec![0.0; self.index.len()]);
        };
        let free = |v: u32| !opened[v as usize];
        let mut values = Vec::with_capacity(pattern.entries());
        for &(a, b, w) in &self.edges {
            let (fa, fb) = (free(a), free(b));
            values.extend([
                if fa { w } else { 0.0 },
                if fb { w } else { 0.0 },
                if fa && fb { -w } else { 0.0 },
            ]);
        }
        let mut rhs = Vec::with_capacity(pattern.size());
        for (v, &k) in self.index.iter().enumerate() {
            if k != u32::MAX {
                let held = opened[v];
                values.push(if held { 1.0 } else { 0.0 });
                rhs.push(if held { 0.0 } else { self.source[v] });
            }
        }
        pattern.factor(&values)?.solve(&mut rhs);
        Ok(self
            .index
            .iter()
            .map(|&k| if k == u32::MAX { 0.0 } else { rhs[k as usize] })
            .collect())
    }
}

/// The unknown of each vertex of `mesh` that a face uses and `free`
/// keeps, numbered in vertex order, `u32::MAX` for the others; and how
/// many there are.
fn unknowns(mesh: &TriMesh, free: impl Fn(usize) -> bool) -> (Vec<u32>, u32) {
    let mut referenced = vec![false; mesh.num_vertices()];
    for &v in mesh.triangles.iter().flatten() {
        referenced[v as usize] = true;
    }
    let mut index = vec![u32::MAX; mesh.num_vertices()];
    let mut count = 0u32;
    for (v, slot) in index.iter_mut().enumerate() {
        if referenced[v] && free(v) {
            *slot = count;
            count += 1;
        }
    }
    (index, count)
}

/// Every edge of `mesh` once per face, with the half cotangent of the
/// corner opposite it (floored as `Dirichlet::new` says with `positive`).
fn cotangent_edges(mesh: &TriMesh, angles: &[[f64; 3]], positive: bool) -> Vec<(u32, u32, f64)> {
    let mut edges = Vec::with_capacity(mesh.num_faces() * 3);
    for (t, a) in mesh.triangles.iter().zip(angles) {
        for i in 0..3 {
            let w = 0.5 * a[i].cos() / a[i].sin().max(1e-12);
            let w = if positive { w.max(MIN_WEIGHT) } else { w };
            edges.push((t[(i + 1) % 3], t[(i + 2) % 3], w));
        }
    }
    edges
}

/// The log scale factor and what it was solved from.
struct LogScale {
    angles: Vec<[f64; 3]>,
    defect: Vec<f64>,
    /// The cotangent Laplacian with the boundary fixed.
    dirichlet: Dirichlet,
    u: Vec<f64>,
}

impl LogScale {
    /// L u = -(angle defect) inside, u = 0 on the boundary.
    fn solve(chart: &TriMesh, topo: &Topology) -> Result<LogScale> {
        let angles = corner_angles(chart);
        let defect = angle_defects(chart, topo, &angles);
        let dirichlet = Dirichlet::on_boundary(chart, topo, &angles, false)?;
        let source: Vec<f64> = defect.iter().map(|d| -d).collect();
        let u = dirichlet.solve(&vec![0.0; chart.num_vertices()], &source);
        Ok(LogScale {
            angles,
            defect,
            dirichlet,
            u,
        })
    }
}

/// Per face, the log area ratio e^(2u) implies (u averaged over the
/// corners), shifted so the total areas agree, as the metrics scale them.
pub fn face_log_area_ratios(chart: &TriMesh, u: &[f64]) -> Vec<f64> {
    let area: Vec<f64> = (0..chart.num_faces()).map(|f| chart.face_area(f)).collect();
    let log_ratio: Vec<f64> = chart
        .triangles
        .iter()
        .map(|t| 2.0 * t.iter().map(|&v| u[v as usize]).sum::<f64>() / 3.0)
        .collect();
    let total: f64 = area.iter().sum();
    let scaled: f64 = area.iter().zip(&log_ratio).map(|(a, l)| a * l.exp()).sum();
    let shift = (total / scaled.max(1e-300)).ln();
    log_ratio.into_iter().map(|l| l + shift).collect()
}

/// Boundary first flattening (Sawhney and Crane 2017) of a disk chart,
/// with the boundary's scale kept (u = 0 there): the conformal map of least
/// area distortion, the one Seamster's estimate describes, and which needs
/// no pinned vertices. The boundary curve takes the geodesic curvature the
/// flattening gives it, k + du/dn, and its lengths are adjusted as little as
/// possible so it closes; the interior follows by harmonic extension
/// (nonnegative weights). Used when ABF++ cannot flatten a chart.
pub fn boundary_first(chart: &TriMesh, topo: &Topology) -> Result<Vec<DVec2>> {
    let LogScale {
        angles,
        defect,
        dirichlet,
        u,
    } = LogScale::solve(chart, topo)?;
    let flux = dirichlet.apply(&u);

    let cycle: Vec<usize> = match topo.boundary_loops() {
        [cycle] => cycle.iter().map(|&h| topo.origin(h).idx()).collect(),
        loops => {
            return Err(Error::invalid(format!(
                "a chart to flatten must have one boundary loop, not {}",
                loops.len()
            )));
        }
    };
    // Exterior angle at each boundary vertex (its angle defect there is
    // pi minus its angles) plus the flux; they sum to 2 pi.
    let turn: Vec<f64> = cycle.iter().map(|&v| defect[v] + flux[v]).collect();
    let total: f64 = turn.iter().sum();
    // (Also refuses a total that is not a number.)
    if (total - TAU).abs().partial_cmp(&(1e-6 * TAU)) != Some(std::cmp::Ordering::Less) {
        return Err(Error::invalid(format!(
            "boundary first flattening: the boundary turns by {total} instead of 2 pi"
        )));
    }
    // Edge i runs from cycle[i] to cycle[i + 1] and leaves in the
    // direction turned by the exterior angles up to cycle[i].
    let n = cycle.len();
    let mut heading = 0.0;
    let mut dirs = Vec::with_capacity(n);
    let mut lengths = Vec::with_capacity(n);
    for i in 0..n {
        if i > 0 {
            heading += turn[i];
        }
        dirs.push(DVec2::from_angle(heading));
        let (a, b) = (cycle[i], cycle[(i + 1) % n]);
        lengths.push((chart.positions[a] - chart.positions[b]).length());
    }
    // Closest lengths (relative to their own) for which the curve closes:
    // minimise sum (l - l0)^2 / l0 subject to sum l d = 0.
    let mut m = glam::DMat2::ZERO;
    let mut gap = DVec2::ZERO;
    for (d, &l) in dirs.iter().zip(&lengths) {
        m += glam::DMat2::from_cols(*d * d.x, *d * d.y) * l;
        gap += *d * l;
    }
    if m.determinant().abs() <= 1e-300 {
        return Err(Error::invalid(
            "boundary first flattening: the boundary curve cannot close",
        ));
    }
    let mu = m.inverse() * gap;
    let mut point = DVec2::ZERO;
    let mut boundary_x = vec![0.0; chart.num_vertices()];
    let mut boundary_y = vec![0.0; chart.num_vertices()];
    for i in 0..n {
        boundary_x[cycle[i]] = point.x;
        boundary_y[cycle[i]] = point.y;
        let l = lengths[i] * (1.0 - dirs[i].dot(mu));
        point += dirs[i] * l;
    }
    // The interior by harmonic extension, with Tutte's positive weights so
    // that slivers of a scan do not fold.
    let extension = Dirichlet::on_boundary(chart, topo, &angles, true)?;
    let zero = vec![0.0; chart.num_vertices()];
    let x = extension.solve(&boundary_x, &zero);
    let y = extension.solve(&boundary_y, &zero);
    // The curve turns left; if the loop runs clockwise around the chart
    // that mirrors it, so mirror back.
    let signed: f64 = chart
        .triangles
        .iter()
        .map(|t| {
            let q = t.map(|v| DVec2::new(x[v as usize], y[v as usize]));
            double_area(q)
        })
        .sum();
    let flip = if signed < 0.0 { -1.0 } else { 1.0 };
    Ok(x.into_iter()
        .zip(y)
        .map(|(x, y)| DVec2::new(x, flip * y))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::graph::{EdgeGraph, ShortestPaths};
    use crate::unwrap::metrics::face_double_area;

    /// One pattern serves every cut: opened through a pole-to-pole seam,
    /// and then through a longer one, the log scale solved on the uncut
    /// sphere is the cut chart's own (`log_scale`) at every copy of every
    /// vertex.
    #[test]
    fn the_opened_log_scale_is_the_cut_charts() {
        let sphere = crate::mesh::shapes::icosphere(3);
        let topo = Topology::build(&sphere).unwrap();
        let angles = corner_angles(&sphere);
        let defect = angle_defects(&sphere, &topo, &angles);
        let order = VertexOrder::of_triangles(sphere.num_vertices(), &sphere.triangles).unwrap();
        let opened_scale = OpenedLogScale::new(&sphere, &angles, &defect, &order).unwrap();
        let graph = EdgeGraph::new(&topo);
        let paths = ShortestPaths::from_sources(
            &graph,
            &graph.lengths(&sphere.positions),
            &[(VertexId(0), 0)],
        );
        let far = |k: usize| {
            let mut by_distance: Vec<usize> = (0..sphere.num_vertices()).collect();
            by_distance.sort_by(|&a, &b| paths.distance[b].total_cmp(&paths.distance[a]));
            VertexId::from(by_distance[k])
        };
        let short = paths.path_to_source(&graph, far(40));
        let mut long = paths.path_to_source(&graph, far(0));
        long.extend(paths.path_to_source(&graph, far(60)));
        long.sort_unstable();
        long.dedup();
        for seams in [short, long] {
            let cut = crate::unwrap::cutgraph::cut(&sphere, &seams);
            let chart = cut.mesh(&sphere.positions);
            let chart_topo = Topology::build(&chart).unwrap();
            let expected = log_scale(&chart, &chart_topo).unwrap();
            let mut opened = vec![false; sphere.num_vertices()];
            for v in seams.iter().flat_map(|&e| graph.ends(e)) {
                opened[v.idx()] = true;
            }
            let u = opened_scale.solve(&opened).unwrap();
            for (v, &o) in cut.origin.iter().enumerate() {
                assert!(
                    (u[o as usize] - expected[v]).abs() < 1e-9,
                    "{} against {}",
                    u[o as usize],
                    expected[v]
                );
            }
            assert!(
                expected.iter().any(|x| x.abs() > 0.1),
                "a cut sphere stretches"
            );
        }
    }

    #[test]
    fn boundary_first_lays_out_the_estimated_map_without_flips() {
        let chart = crate::unwrap::cutgraph::cut_open_sphere(3);
        let topo = Topology::build(&chart).unwrap();
        let uv = boundary_first(&chart, &topo).unwrap();
        assert_eq!(crate::unwrap::flatten::flipped(&chart, &uv), 0);
        // Its area distortion is the one `log_scale` predicts.
        let predicted = face_log_area_ratios(&chart, &log_scale(&chart, &topo).unwrap());
        let (mut total, mut weighted) = (0.0, 0.0);
        let areas: Vec<f64> = (0..chart.num_faces()).map(|f| chart.face_area(f)).collect();
        let uv_area: Vec<f64> = chart
            .triangles
            .iter()
            .map(|t| face_double_area(t, &uv) / 2.0)
            .collect();
        let k = areas.iter().sum::<f64>() / uv_area.iter().sum::<f64>();
        for f in 0..chart.num_faces() {
            let actual = (uv_area[f] * k / areas[f]).ln();
            weighted += areas[f] * (actual - predicted[f]).abs();
            total += areas[f];
        }
        assert!(weighted / total < 0.05, "{}", weighted / total);
    }
}
