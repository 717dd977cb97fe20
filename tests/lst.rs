//! Lapped solid textures (issue 22) on a kiwi-like ellipsoid and a layered
//! cake-like slab tetrahedralised here: coverage, alignment, depth, the
//! outer layer at the surface, cross-sections that agree, the same bytes
//! on any thread count, the `.lst` file, and bad input.

use glam::DVec3;
use organtex::progress::Silent;
use organtex::solid::Interior;
use organtex::solid::lst::{
    self, LstInterior, LstModel, LstOptions, MaskKind, Splotch, TextureType,
    anchors::{self, Anchor},
    fields::DepthField,
    paste::sample_points,
};
use organtex::synth::volume::Volume;
use organtex::tetra::TetOptions;

fn kiwi(kind: TextureType, cells: usize) -> Anchor {
    anchors::kiwi(kind, cells).expect("kiwi")
}

fn cake(kind: TextureType, cells: usize) -> Anchor {
    anchors::cake(kind, cells).expect("cake")
}

/// Every tet's 165 sample points covered: the masks' alpha, recomputed
/// from the stored layers, adds up to 1.
fn assert_covered(name: &str, model: &LstModel) {
    let splotch = Splotch::new(model.seed);
    let samples = sample_points();
    for t in 0..model.mesh.num_tets() {
        for (i, b) in samples.iter().enumerate() {
            let mut total = 0.0;
            for l in model.layers_of(t) {
                let w = l.at(b.map(|x| x as f64));
                total += (splotch.alpha(l.mask, w) * 255.0).round();
            }
            assert!(
                total >= 255.0,
                "{name}: tet {t} sample {i} covered {total}/255"
            );
        }
    }
}

/// Every type covers every sample point of every tet of the kiwi. Its
/// alignment is reported, not asserted: the kiwi's depth (0 on the skin, 1
/// on the core line) makes its radial axes turn a full circle round the
/// core, which no patch follows there (`layered_walls_align_with_their_depth`
/// asserts alignment on walls without such a line).
#[test]
fn every_type_covers_every_sample_point() {
    let n = std::env::var("LST_TETS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1500);
    for kind in [
        TextureType::Isotropic,
        TextureType::Oriented,
        TextureType::Layered,
        TextureType::Tensor,
        TextureType::LayeredTensor,
    ] {
        let a = kiwi(kind, n);
        let tets = &a.tets;
        let (model, stats) = lst::fill_stats(tets, &a.options, &Silent)
            .unwrap_or_else(|e| panic!("type {}: {e}", kind.name()));
        println!(
            "kiwi type {}: {} tets, {} patches, {} layers ({:.1} per tet), alignment median {:.2} deg, \
             95th percentile {:.2}, max {:.2}",
            kind.name(),
            tets.num_tets(),
            stats.patches,
            stats.layers,
            stats.layers as f64 / tets.num_tets() as f64,
            stats.angle_median,
            stats.angle_p95,
            stats.angle_max
        );
        assert_covered(kind.name(), &model);
    }
}

#[test]
fn layered_types_take_the_depth_and_show_the_outer_layer_at_the_surface() {
    let ex = anchors::layered_exemplar();
    for (name, a) in [
        ("kiwi 2-b", kiwi(TextureType::LayeredTensor, 1500)),
        ("cake 1-b", cake(TextureType::Layered, 1500)),
    ] {
        let (tets, opts) = (&a.tets, &a.options);
        let model = lst::fill(tets, opts, &Silent).expect("fill");
        assert_covered(name, &model);
        let field = DepthField::fit(&opts.depth_outer, &opts.depth_inner).expect("depth");
        let depth = model.depth.as_ref().expect("layered models keep depths");
        for (v, &p) in tets.positions.iter().enumerate() {
            assert!(
                (depth[v] - field.value(p)).abs() <= 1e-9,
                "{name}: vertex {v}"
            );
        }
        for t in 0..tets.num_tets() {
            for l in model.layers_of(t) {
                for k in 0..4 {
                    let d = depth[tets.tets[t][k] as usize];
                    assert!((l.coords[k][1] as f64 - d).abs() <= 1e-6, "{name}: tet {t}");
                }
            }
        }
        // The exemplar's skin (red) where the depth is 0.
        let interior = LstInterior::new(model.clone().into(), ex.clone().into()).expect("interior");
        let outer: Vec<DVec3> = tets
            .positions
            .iter()
            .enumerate()
            .filter(|&(v, _)| depth[v] < 0.01)
            .map(|(_, &p)| p)
            .collect();
        assert!(outer.len() > 50, "{name}: {} outer vertices", outer.len());
        let red = interior
            .colours(&outer)
            .iter()
            .filter(|c| c[0] > 180 && c[2] < 60)
            .count();
        println!(
            "{name}: {red} of {} depth-0 vertices show the skin",
            outer.len()
        );
        assert!(
            red * 100 >= outer.len() * 95,
            "{name}: {red} of {}",
            outer.len()
        );
    }
}

/// Seed 000's claim over per-cut synthesis: two planes through one line
/// show the same colours along it.
#[test]
fn cross_sections_through_one_line_agree_on_it() {
    let a = kiwi(TextureType::LayeredTensor, 1500);
    let model = lst::fill(&a.tets, &a.options, &Silent).expect("fill");
    let ex = anchors::layered_exemplar();
    let interior = LstInterior::new(model.into(), ex.into()).expect("interior");
    let (a, dir) = (
        DVec3::new(0.1, -0.2, 0.0),
        DVec3::new(0.3, 0.2, 1.0).normalize(),
    );
    let normal_a = dir.any_orthonormal_vector();
    let normal_b = (normal_a + dir.cross(normal_a)).normalize();
    let frames = [normal_a, normal_b].map(|n| {
        organtex::solid::Frame::of(&organtex::solid::Plane::new(n, n.dot(a)).expect("plane"))
    });
    let mut worst = 0u8;
    for i in 0..200 {
        let p = a + dir * (-1.2 + 2.4 * i as f64 / 199.0);
        let c = frames.map(|f| interior.colour(f.to_3d(f.to_2d(p))));
        for (x, y) in c[0].iter().zip(&c[1]) {
            worst = worst.max(x.abs_diff(*y));
        }
    }
    assert!(
        worst <= 1,
        "colours differ by {worst}/255 along the common line"
    );
}

#[test]
fn same_bytes_on_any_thread_count_and_the_file_round_trips() {
    let a = kiwi(TextureType::Tensor, 800);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| lst::fill(&a.tets, &a.options, &Silent).expect("fill"))
    };
    let one = run(1);
    assert!(run(3) == one, "3 threads gave another model");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("kiwi.lst");
    one.write(&path).expect("write");
    let size = std::fs::metadata(&path).expect("size").len();
    assert_eq!(size, one.file_size());
    assert!(LstModel::read(&path).expect("read") == one);
    // Corrupt files: cut short, a wrong magic, a layer count too large.
    let bytes = std::fs::read(&path).expect("bytes");
    for (what, bad) in [
        ("cut short", bytes[..bytes.len() - 7].to_vec()),
        ("bad magic", [b"X".as_slice(), &bytes[1..]].concat()),
        ("trailing bytes", [bytes.as_slice(), &[0u8; 3]].concat()),
    ] {
        std::fs::write(&path, &bad).expect("write");
        let e = LstModel::read(&path).expect_err(what).to_string();
        assert!(e.contains("kiwi.lst"), "{what}: {e}");
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let a = kiwi(TextureType::Oriented, 500);
    let tets = &a.tets;
    let message = |opts: &LstOptions| {
        lst::fill(tets, opts, &Silent)
            .expect_err("must fail")
            .to_string()
    };
    let options = |kind: TextureType| LstOptions {
        kind,
        ..a.options.clone()
    };
    let mut outside = options(TextureType::Oriented);
    outside.strokes = vec![vec![DVec3::new(5.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0)]];
    assert!(
        message(&outside).contains("outside the mesh"),
        "{}",
        message(&outside)
    );
    let mut missing = options(TextureType::Layered);
    missing.depth_inner.clear();
    assert!(
        message(&missing).contains("depth 0 and at depth 1"),
        "{}",
        message(&missing)
    );
    let mut equal = options(TextureType::Layered);
    equal.depth_inner = equal.depth_outer.clone();
    assert!(message(&equal).contains("meet"), "{}", message(&equal));
    let mut no_strokes = options(TextureType::Tensor);
    no_strokes.strokes.clear();
    assert!(
        message(&no_strokes).contains("strokes"),
        "{}",
        message(&no_strokes)
    );
    assert!(TextureType::parse("3c").is_err());
    let model = lst::fill(tets, &options(TextureType::Isotropic), &Silent).expect("fill");
    let flat = Volume {
        size: [1, 32, 32],
        spacing: 1.0,
        voxels: vec![[0; 3]; 32 * 32],
    };
    let e = LstInterior::new(model.into(), flat.into())
        .err()
        .expect("flat exemplar")
        .to_string();
    assert!(e.contains("at least 2"), "{e}");
    assert_eq!(MaskKind::from_u8(9), None);
}

#[test]
fn layered_walls_align_with_their_depth() {
    // The bundled scene's uterine wall (10 mm thick, no myomas).
    let params: organtex::scene::uterus::CavityParams =
        toml::from_str("seed = 7\nresolution = 4\nwall_thickness = 10.0").expect("params");
    let cells = TetOptions {
        cells: Some(30000),
        ..Default::default()
    };
    let w = organtex::bench::uterus_wall(&params, &cells, TextureType::Layered).expect("wall");
    let (tets, serosa, cavity) = (w.tets, w.options.depth_outer, w.options.depth_inner);
    let c = cake(TextureType::Layered, 2734);
    for (name, mesh, outer, inner, kind) in [
        (
            "uterus wall 1-b",
            &tets,
            &serosa,
            &cavity,
            TextureType::Layered,
        ),
        (
            "uterus wall 2-b",
            &tets,
            &serosa,
            &cavity,
            TextureType::LayeredTensor,
        ),
        (
            "cake 1-b",
            &c.tets,
            &c.options.depth_outer,
            &c.options.depth_inner,
            TextureType::Layered,
        ),
    ] {
        // A stroke inside the wall (or the slab) along its length: points
        // halfway between an outer point and its nearest inner one.
        let mid = |at: DVec3| {
            let o = *outer
                .iter()
                .min_by(|a, b| a.distance(at).total_cmp(&b.distance(at)))
                .expect("outer");
            let i = *inner
                .iter()
                .min_by(|a, b| a.distance(o).total_cmp(&b.distance(o)))
                .expect("inner");
            (o + i) / 2.0
        };
        let stroke = if name.starts_with("cake") {
            vec![DVec3::new(-0.8, -0.5, 0.0), DVec3::new(0.8, 0.5, 0.0)]
        } else {
            (0..5)
                .map(|k| mid(DVec3::new(30.0, 0.0, 12.0 + 4.0 * k as f64)))
                .collect()
        };
        let opts = LstOptions {
            kind,
            scale: 1.0,
            strokes: vec![stroke],
            depth_outer: outer.clone(),
            depth_inner: inner.clone(),
            seed: 11,
        };
        let (model, stats) =
            lst::fill_stats(mesh, &opts, &Silent).unwrap_or_else(|e| panic!("{name}: {e}"));
        println!(
            "{name}: {} tets, {} patches, {:.1} layers per tet, alignment median {:.2} deg, 95th percentile {:.2}, max {:.2}",
            mesh.num_tets(),
            stats.patches,
            stats.layers as f64 / mesh.num_tets() as f64,
            stats.angle_median,
            stats.angle_p95,
            stats.angle_max
        );
        assert_covered(name, &model);
        assert!(
            stats.angle_median <= 5.0 && stats.angle_p95 <= 15.0,
            "{name}: alignment median {:.2}, 95th percentile {:.2} degrees",
            stats.angle_median,
            stats.angle_p95
        );
    }
}

/// A region (a myoma's ball inside a layered wall) is filled with its own
/// type: every sample point of every tet still covered; the region's tets
/// hold only its splotch patches, the rest only depth-band patches, and no
/// patch crosses the border. Regions that need the depth, overlap or hold
/// nothing are refused by name.
#[test]
fn a_region_gets_its_own_type_and_no_patch_crosses_its_border() {
    let c = cake(TextureType::Layered, 2734);
    let ball = lst::regions::Ball {
        centre: DVec3::ZERO,
        radius: 0.45,
        axis: DVec3::Z,
    };
    let tets = lst::regions::tets_in_ball(&c.tets, &ball);
    assert!(tets.len() > 50, "{} tets in the ball", tets.len());
    let strokes = lst::regions::whorl(&ball, &c.tets.subset(&tets).0);
    assert!(!strokes.is_empty(), "the whorl has rings inside the ball");
    let region = lst::Region {
        name: "myoma".into(),
        tets: tets.clone(),
        options: LstOptions {
            kind: TextureType::Oriented,
            scale: 0.3,
            strokes,
            depth_outer: Vec::new(),
            depth_inner: Vec::new(),
            seed: 11,
        },
    };
    let (model, stats) =
        lst::fill_regions(&c.tets, &c.options, std::slice::from_ref(&region), &Silent)
            .expect("fill");
    assert_eq!(stats.len(), 2);
    eprintln!(
        "cake 1-b with a 1-a ball: rest {} patches, align median {:.2} p95 {:.2}; ball {} patches, median {:.2} p95 {:.2}",
        stats[0].patches,
        stats[0].angle_median,
        stats[0].angle_p95,
        stats[1].patches,
        stats[1].angle_median,
        stats[1].angle_p95
    );
    assert_covered("cake with a ball", &model);
    let mut inside = vec![false; model.mesh.num_tets()];
    for &t in &tets {
        inside[t as usize] = true;
    }
    let mut patch_side = std::collections::HashMap::new();
    for (t, &in_ball) in inside.iter().enumerate() {
        for l in model.layers_of(t) {
            assert_eq!(
                l.mask == MaskKind::Splotch,
                in_ball,
                "tet {t} (in the ball: {in_ball}) has a {:?} layer",
                l.mask
            );
            assert_eq!(
                *patch_side.entry(l.patch).or_insert(in_ball),
                in_ball,
                "patch {} crosses the border",
                l.patch
            );
        }
    }
    // The file keeps the mix.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("mixed.lst");
    model.write(&path).expect("write");
    assert_eq!(LstModel::read(&path).expect("read"), model);

    let refused = |regions: &[lst::Region]| {
        lst::fill_regions(&c.tets, &c.options, regions, &Silent)
            .expect_err("must fail")
            .to_string()
    };
    let mut layered = region.clone();
    layered.options.kind = TextureType::Layered;
    let e = refused(std::slice::from_ref(&layered));
    assert!(e.contains("'myoma'") && e.contains("depth"), "{e}");
    let mut twin = region.clone();
    twin.name = "twin".into();
    let e = refused(&[region.clone(), twin]);
    assert!(e.contains("'myoma' and 'twin'"), "{e}");
    let mut empty = region.clone();
    empty.tets.clear();
    let e = refused(&[empty]);
    assert!(e.contains("holds no tets"), "{e}");
}
