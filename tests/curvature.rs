//! Curvature: Gauss-Bonnet on every test mesh, and known values on shapes
//! whose curvature is known exactly.

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::path::PathBuf;

use organtex::mesh::curvature::Curvature;
use organtex::mesh::shapes::{holed_slab, icosphere, open_cylinder, torus};
use organtex::mesh::{Components, Topology, TriMesh, io};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn euler(topo: &Topology) -> i64 {
    Components::find(topo)
        .topology(topo)
        .iter()
        .map(|c| c.euler)
        .sum()
}

/// The angle defects (with the boundary's geodesic curvature) sum to
/// 2 pi chi, to rounding.
fn assert_gauss_bonnet(name: &str, mesh: &TriMesh) {
    let topo = Topology::build(mesh).unwrap();
    let k = Curvature::compute(mesh, &topo);
    let total: f64 = k.angle_defect.iter().sum();
    let expected = TAU * euler(&topo) as f64;
    assert!(
        (total - expected).abs() < 1e-9,
        "{name}: defects sum to {total}, 2 pi chi = {expected}"
    );
}

#[test]
fn gauss_bonnet_holds_on_every_test_mesh() {
    for file in ["bunny.obj", "bunny10k_textured.obj", "cube.obj"] {
        assert_gauss_bonnet(file, &io::read(&data(file)).unwrap());
    }
    assert_gauss_bonnet("torus", &torus(1.0, 0.3, 64, 24));
    assert_gauss_bonnet("double torus", &holed_slab(2, 4, 6));
    assert_gauss_bonnet("cylinder", &open_cylinder(1.0, 1.0, 40, 10));
    assert_gauss_bonnet("sphere", &icosphere(4));
}

#[test]
fn cube_corners_carry_a_quarter_turn_and_edges_fold_ninety_degrees() {
    let mesh = io::read(&data("cube.obj")).unwrap();
    let topo = Topology::build(&mesh).unwrap();
    let k = Curvature::compute(&mesh, &topo);
    for d in &k.angle_defect {
        assert!((d - FRAC_PI_2).abs() < 1e-12);
    }
    let mut folds = k.dihedral.clone();
    folds.sort_by(f64::total_cmp);
    // 6 face diagonals are flat, 12 cube edges are convex right angles.
    assert!(folds[..6].iter().all(|a| a.abs() < 1e-12));
    assert!(folds[6..].iter().all(|a| (a - FRAC_PI_2).abs() < 1e-12));
    let area: f64 = k.mixed_area.iter().sum();
    assert!(
        (area - mesh.area()).abs() < 1e-12,
        "mixed areas tile the surface"
    );
}

#[test]
fn unit_sphere_has_unit_gaussian_and_mean_curvature() {
    let mesh = icosphere(5);
    let topo = Topology::build(&mesh).unwrap();
    let k = Curvature::compute(&mesh, &topo);
    for v in 0..mesh.num_vertices() {
        assert!((k.gaussian[v] - 1.0).abs() < 0.02, "K = {}", k.gaussian[v]);
        assert!((k.mean[v] - 1.0).abs() < 0.02, "H = {}", k.mean[v]);
    }
    let area: f64 = k.mixed_area.iter().sum();
    assert!((area - mesh.area()).abs() < 1e-9);
    assert!((mesh.area() - 4.0 * PI).abs() < 0.01);
}

#[test]
fn torus_total_curvature_vanishes_and_outer_rim_is_positive() {
    let (major, minor) = (1.0, 0.25);
    let mesh = torus(major, minor, 96, 32);
    let topo = Topology::build(&mesh).unwrap();
    let k = Curvature::compute(&mesh, &topo);
    let integral: f64 = k.angle_defect.iter().sum();
    assert!(integral.abs() < 1e-9);
    // On the outer equator K = cos v / (r (R + r cos v)) at v = 0.
    let expected = 1.0 / (minor * (major + minor));
    let outer = 0; // vertex (i = 0, j = 0) sits at v = 0
    assert!((k.gaussian[outer] - expected).abs() / expected < 0.02);
    // Mean curvature there: (1/r + cos v/(R + r cos v)) / 2.
    let h = (1.0 / minor + 1.0 / (major + minor)) / 2.0;
    assert!((k.mean[outer] - h).abs() / h < 0.02);
}

#[test]
fn concave_folds_are_negative() {
    // The inside corners of a holed slab fold inwards.
    let mesh = holed_slab(1, 2, 0);
    let topo = Topology::build(&mesh).unwrap();
    let k = Curvature::compute(&mesh, &topo);
    assert!(k.dihedral.iter().any(|&a| (a + FRAC_PI_2).abs() < 1e-9));
    assert!(k.dihedral.iter().any(|&a| (a - FRAC_PI_2).abs() < 1e-9));
}
