//! Unwrapping real and generated meshes: one disk chart per piece, no flips,
//! the distortion targets on the bunny, ABF++ against LSCM on a fixed cut,
//! robustness to degenerate input, and determinism.

use std::path::PathBuf;

use glam::DVec3;
use organtex::mesh::curvature::{Curvature, corner_angles};
use organtex::mesh::graph::EdgeGraph;
use organtex::mesh::shapes::{holed_slab, icosphere, open_cylinder, torus};
use organtex::mesh::{Components, Topology, TriMesh, io};
use organtex::progress::Silent;
use organtex::unwrap::cutgraph::Opened;
use organtex::unwrap::intersect::overlapping_pairs;
use organtex::unwrap::seamster::{self, Distortion, SeamOptions};
use organtex::unwrap::terminals::{disc_curvature, select};
use organtex::unwrap::visibility::Viewpoints;
use organtex::unwrap::{UnwrapOptions, Unwrapped, abf, flatten, layout, unwrap};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn run(mesh: &TriMesh) -> Unwrapped {
    unwrap(mesh, &UnwrapOptions::default(), &Silent).expect("unwrap")
}

/// Check from the output alone that every chart is a disk: glue faces by
/// their uv corners and count pieces, boundary loops and Euler
/// characteristic.
fn assert_disk_charts(u: &Unwrapped, pieces: usize) {
    let layer = u.mesh.uvs.as_ref().expect("uvs");
    let uv_mesh = TriMesh::new(
        layer
            .coords
            .iter()
            .map(|c| DVec3::new(c.x, c.y, 0.0))
            .collect(),
        layer.triangles.clone(),
    );
    let topo = Topology::build(&uv_mesh).expect("the uv layout is a manifold");
    let charts = Components::find(&topo).topology(&topo);
    assert_eq!(charts.len(), pieces, "one chart per connected piece");
    for c in &charts {
        assert_eq!((c.euler, c.boundary_loops), (1, 1), "every chart is a disk");
    }
    assert_eq!(u.report.metrics.charts, pieces);
    assert_eq!(u.report.metrics.flips, 0, "no flipped triangle");
    assert!(layer.coords.iter().all(|c| c.is_finite()));
}

#[test]
fn bunny_is_one_low_distortion_chart() {
    let mesh = io::read(&data("bunny.obj")).unwrap();
    let u = run(&mesh);
    assert_disk_charts(&u, 1);
    let m = &u.report.metrics;
    assert!(m.conf_mean <= 1.02, "conf_mean {}", m.conf_mean);
    assert!(m.area_log <= 0.25, "area_log {}", m.area_log);
    // Seams hide: on average they are less visible than the surface.
    let mean_vis: f64 =
        u.visibility.vertex.iter().map(|&v| v as f64).sum::<f64>() / mesh.num_vertices() as f64;
    assert!(
        m.seam_vis / m.seam_ratio < mean_vis,
        "seams are less visible than the average surface point"
    );

    // Refinement holds the flattening itself to the bounds, not its
    // conformal estimate (which knows nothing of angles): asked for less
    // than the default cut's conformality, it cuts on until it gets it.
    let strict = m.conf_mean - 0.002;
    let opts = UnwrapOptions {
        seams: SeamOptions {
            max_conformal: strict,
            ..SeamOptions::default()
        },
        ..UnwrapOptions::default()
    };
    let tight = unwrap(&mesh, &opts, &Silent).unwrap();
    assert_disk_charts(&tight, 1);
    let rounds = |u: &Unwrapped| u.report.pieces[0].refinement_rounds;
    assert!(u.report.pieces[0].within_bounds && tight.report.pieces[0].within_bounds);
    assert!(
        tight.report.metrics.conf_mean <= strict && rounds(&tight) > rounds(&u),
        "conf_mean {} after {} rounds, asked for {strict}; the default took {} rounds",
        tight.report.metrics.conf_mean,
        rounds(&tight),
        rounds(&u)
    );
}

#[test]
fn a_bound_no_cut_can_meet_costs_a_few_flattenings_and_is_reported() {
    // Perfect conformality: refinement flattens `max_tries` cuts, not one
    // per round left, and the report says the bound was missed.
    let mesh = io::read(&data("bunny10k_textured.obj")).unwrap();
    let seams = SeamOptions {
        max_conformal: 1.0,
        ..SeamOptions::default()
    };
    let (max_rounds, max_tries) = (seams.max_rounds, seams.max_tries);
    let opts = UnwrapOptions {
        seams,
        ..UnwrapOptions::default()
    };
    let u = unwrap(&mesh, &opts, &Silent).unwrap();
    assert_disk_charts(&u, 1);
    let piece = &u.report.pieces[0];
    assert!(!piece.within_bounds);
    let rounds: Vec<usize> = piece.tries.iter().map(|t| t.round).collect();
    assert!(
        rounds.len() == max_tries && piece.refinement_rounds < max_rounds,
        "cuts flattened in rounds {rounds:?}"
    );
    // None meets the bound, so the one nearest it is kept.
    let conf: Vec<f64> = piece
        .tries
        .iter()
        .map(|t| t.figures.expect("every try flattened").conf_mean)
        .collect();
    let nearest = (0..conf.len())
        .min_by(|&a, &b| conf[a].total_cmp(&conf[b]))
        .unwrap();
    assert_eq!(
        piece.refinement_rounds, rounds[nearest],
        "conf_mean per try {conf:?}"
    );
    assert!(
        (u.report.metrics.conf_mean - conf[nearest]).abs() < 1e-9,
        "kept conf_mean {} is the nearest try's {}",
        u.report.metrics.conf_mean,
        conf[nearest]
    );
}

#[test]
fn when_no_cut_meets_the_bounds_the_nearest_try_is_kept() {
    // Seamster's choice among tries, given the flattenings' figures: with
    // conformality 1.0 asked for, no try meets the bounds; the one nearest
    // them is kept (not the last), and a flattening that fails is a missed
    // try, not the end.
    let mesh = io::read(&data("bunny.obj")).unwrap();
    let topo = Topology::build(&mesh).unwrap();
    let opts = SeamOptions {
        max_stretch: 10.0,
        max_conformal: 1.0,
        ..SeamOptions::default()
    };
    let conf = [1.05, 1.03, f64::NAN, 1.04];
    let mut calls = 0;
    let flatten = |_: &Opened| {
        calls += 1;
        let c = conf[calls - 1];
        if c.is_nan() {
            return Err(organtex::Error::invalid("this flattening fails"));
        }
        let figures = Distortion {
            area_log: 0.1,
            conf_mean: c,
            flipped: 0,
        };
        Ok((calls - 1, figures))
    };
    let visibility = (vec![0.0; mesh.num_vertices()], vec![0.0; topo.num_edges()]);
    let (seams, kept) = seamster::choose(
        &mesh,
        &topo,
        &visibility.0,
        &visibility.1,
        1,
        &opts,
        &Silent,
        flatten,
    )
    .unwrap();
    assert_eq!(kept, 1, "the try nearest the bounds is kept");
    assert!(!seams.within_bounds);
    assert_eq!(seams.tries.len(), opts.max_tries);
    assert!(seams.tries[2].figures.is_none(), "the failed try is listed");
    assert_eq!(seams.rounds, seams.tries[1].round);
    assert!(seams.tries[1].round < seams.tries[3].round);
}

#[test]
fn sampled_disc_curvature_finds_the_exact_terminals() {
    // Curvature discs are summed once per grid cell a quarter of the
    // radius wide, then at every vertex near a cell whose sample is
    // strong: on the bunny this gives the terminals every vertex's own
    // disc gives (a threshold of 0 sums them all), and the exact sum at
    // every vertex over the threshold.
    let mesh = io::read(&data("bunny.obj")).unwrap();
    let topo = Topology::build(&mesh).unwrap();
    let graph = EdgeGraph::new(&topo);
    let defect = Curvature::compute(&mesh, &topo).angle_defect;
    let radius = 0.05 * mesh.area().sqrt();
    let threshold = SeamOptions::default().cone_threshold;
    let exact = disc_curvature(&graph, &mesh.positions, &defect, radius, 0.0);
    let sampled = disc_curvature(&graph, &mesh.positions, &defect, radius, threshold);
    let strong: Vec<usize> = (0..exact.len())
        .filter(|&v| exact[v] >= threshold)
        .collect();
    assert!(strong.len() >= 100, "{} strong vertices", strong.len());
    for &v in &strong {
        assert_eq!(sampled[v], exact[v], "vertex {v}");
    }
    let skipped = sampled.iter().filter(|&&s| s == 0.0).count();
    assert!(
        skipped > exact.len() / 3,
        "only {skipped} of {} discs skipped",
        exact.len()
    );
    let terminals = |cone: &[f64]| {
        select(
            &graph,
            &mesh.positions,
            cone,
            2.0 * radius,
            threshold,
            &[],
            |_| true,
        )
    };
    let chosen = terminals(&exact);
    assert!(chosen.len() >= 4, "{} terminals", chosen.len());
    assert_eq!(terminals(&sampled), chosen);
}

#[test]
fn every_topology_becomes_disks_without_flips() {
    let cases: Vec<(&str, TriMesh)> = vec![
        ("torus", torus(1.0, 0.35, 64, 24)),
        ("double torus", holed_slab(2, 4, 4)),
        ("open cylinder", open_cylinder(0.5, 1.5, 48, 16)),
        ("cube", io::read(&data("cube.obj")).unwrap()),
        (
            "bunny with five holes",
            io::read(&data("bunny10k_textured.obj")).unwrap(),
        ),
    ];
    for (name, mesh) in cases {
        let u = run(&mesh);
        println!("{name}: {:?}", u.report.metrics);
        assert_disk_charts(&u, 1);
    }
}

#[test]
fn the_cube_unfolds_without_distortion() {
    // Every corner is a cone of pi/2: cut through all of them, the faces
    // unfold flat and keep their shape.
    let u = run(&io::read(&data("cube.obj")).unwrap());
    assert!(u.report.metrics.conf_mean < 1.0 + 1e-9);
    assert!(u.report.metrics.area_log < 1e-9);
}

#[test]
fn separate_pieces_get_separate_charts_that_do_not_overlap() {
    let mut mesh = icosphere(3);
    let other = torus(1.0, 0.3, 32, 12);
    let offset = mesh.num_vertices() as u32;
    mesh.positions
        .extend(other.positions.iter().map(|p| *p + DVec3::X * 4.0));
    mesh.triangles
        .extend(other.triangles.iter().map(|t| t.map(|v| v + offset)));
    let u = run(&mesh);
    assert_disk_charts(&u, 2);
    // No face of one piece overlaps a face of the other in uv (their boxes
    // may: a chart can sit in another's notch).
    let layer = u.mesh.uvs.as_ref().unwrap();
    let n = icosphere(3).num_faces() as u32;
    let across: Vec<[u32; 2]> = overlapping_pairs(&layer.triangles, &layer.coords)
        .into_iter()
        .filter(|&[f, g]| (f < n) != (g < n))
        .collect();
    assert!(
        across.is_empty(),
        "faces overlapping across pieces: {across:?}"
    );
}

/// The chart the unwrap cut, as a mesh of its own.
fn cut_chart(u: &Unwrapped) -> TriMesh {
    let layer = u.mesh.uvs.as_ref().unwrap();
    let mut positions = vec![DVec3::ZERO; layer.coords.len()];
    for (t, uvt) in u.mesh.triangles.iter().zip(&layer.triangles) {
        for i in 0..3 {
            positions[uvt[i] as usize] = u.mesh.positions[t[i] as usize];
        }
    }
    TriMesh::new(positions, layer.triangles.clone())
}

#[test]
fn abf_is_as_conformal_as_lscm_on_the_same_cut_and_never_flips() {
    for file in ["bunny.obj", "bunny10k_textured.obj"] {
        let u = run(&io::read(&data(file)).unwrap());
        let chart = cut_chart(&u);
        let topo = Topology::build(&chart).unwrap();
        let solution = abf::solve(&chart, &topo, &abf::AbfOptions::default()).unwrap();
        assert!(solution.converged, "{file}: residual {}", solution.residual);
        let abf_uv = layout::from_angles(&chart, &topo, &solution.angles, None).unwrap();
        let lscm_uv = layout::from_angles(&chart, &topo, &corner_angles(&chart), None).unwrap();
        assert_eq!(
            flatten::flipped(&chart, &abf_uv),
            0,
            "{file}: ABF++ flipped a triangle"
        );
        let (abf, lscm) = (
            flatten::conf_mean(&chart, &abf_uv),
            flatten::conf_mean(&chart, &lscm_uv),
        );
        println!("{file}: conf_mean ABF++ {abf:.5}, LSCM {lscm:.5}");
        assert!(abf <= lscm * 1.01, "{file}: ABF++ {abf} vs LSCM {lscm}");
    }
}

#[test]
fn coincident_vertices_and_zero_area_faces_give_finite_uvs_and_no_flips() {
    let mut mesh = io::read(&data("bunny10k_textured.obj")).unwrap();
    // Move a vertex onto a neighbour: its two shared faces lose all area.
    let [a, b, _] = mesh.triangles[100];
    mesh.positions[a as usize] = mesh.positions[b as usize];
    let u = run(&mesh);
    assert_disk_charts(&u, 1);
}

#[test]
fn a_cavity_seen_from_inside_unwraps_with_endoscope_cameras() {
    // A closed tube (capped cylinder), cameras along its axis inside.
    let mut mesh = holed_slab(0, 3, 2);
    mesh.positions
        .iter_mut()
        .for_each(|p| *p *= DVec3::new(1.0, 1.0, 3.0));
    let (lo, hi) = mesh.bounding_box().unwrap();
    let centre = (lo + hi) / 2.0;
    let opts = UnwrapOptions {
        viewpoints: Viewpoints::Cameras(vec![centre, centre + DVec3::X * 0.5]),
        ..UnwrapOptions::default()
    };
    let u = unwrap(&mesh, &opts, &Silent).unwrap();
    assert_eq!(u.report.views, 2);
    assert!(
        u.visibility.vertex.iter().all(|&v| v > 0.0),
        "inside walls are all seen"
    );
    assert_disk_charts(&u, 1);
}

/// The bunny with every vertex moved off the surface by up to `amount`
/// mean edge lengths, seeded: scan noise, slivers and folds.
fn noisy_bunny(amount: f64) -> TriMesh {
    let mut mesh = io::read(&data("bunny.obj")).unwrap();
    let (mut total, mut count) = (0.0, 0);
    for t in &mesh.triangles {
        total += (mesh.positions[t[0] as usize] - mesh.positions[t[1] as usize]).length();
        count += 1;
    }
    let step = amount * total / count as f64;
    for (v, p) in mesh.positions.iter_mut().enumerate() {
        let r = |k: u64| organtex::rng::hash(7, &[v as u64, k]) as f64 / u64::MAX as f64 - 0.5;
        *p += DVec3::new(r(0), r(1), r(2)) * 2.0 * step;
    }
    mesh
}

#[test]
fn a_noisy_scan_flattens_with_abf_and_its_seams_do_not_chase_the_noise() {
    let u = run(&noisy_bunny(0.4));
    assert_disk_charts(&u, 1);
    for piece in &u.report.pieces {
        for method in &piece.flattening {
            assert!(
                matches!(
                    method,
                    flatten::Method::AbfPlusPlus {
                        converged: true,
                        ..
                    }
                ),
                "{method:?}"
            );
        }
    }
    // Noise spikes are not sharp corners: the clean bunny's seams measure
    // 4.3 (seam_ratio); spikes taken for terminals made these 30.
    let m = &u.report.metrics;
    assert!(m.seam_ratio <= 20.0 && m.area_log <= 0.25, "{m:?}");
}

#[test]
fn split_overlaps_leaves_a_few_disk_charts_that_do_not_overlap() {
    // The one-chart layout of the holed bunny folds over itself in a few
    // places (87 faces overlap); an atlas needs it split.
    let mesh = io::read(&data("bunny10k_textured.obj")).unwrap();
    let opts = UnwrapOptions {
        split_overlaps: true,
        ..UnwrapOptions::default()
    };
    let whole = run(&mesh);
    assert!(whole.report.metrics.overlaps > 0);
    let u = unwrap(&mesh, &opts, &Silent).unwrap();
    let m = &u.report.metrics;
    assert_eq!(m.overlaps, 0, "{m:?}");
    // A flap per fold, not a chart per overlapping face.
    assert!((2..=8).contains(&m.charts), "{m:?}");
    assert_disk_charts(&u, m.charts);
    assert!(m.conf_mean <= 1.08 && m.area_log <= 0.25, "{m:?}");
}
