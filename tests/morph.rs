//! Interiors morphed from photographed cuts (organtex::solid::morph, seed
//! 003) on real data: axial slices of a brain MRI template (tests/data/
//! morph, cut by tools/compare_morph.py) placed in a box, with the slices
//! held back between them as the truth.

mod common;
use common::organtex;
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use organtex::mesh::shapes::torus;
use organtex::mesh::{Topology, TriMesh, io};
use organtex::progress::Silent;
use organtex::solid::Interior;
use organtex::solid::morph::{Exemplar, Morph, MorphOptions};
use organtex::synth::filter::Plane;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/morph")
        .join(name)
}

fn brain() -> (TriMesh, Topology, Morph) {
    let mesh = io::read(&data("box.obj")).unwrap();
    let topology = Topology::build(&mesh).unwrap();
    let morph = Morph::read(
        &mesh,
        &topology,
        &data("sections.toml"),
        MorphOptions::default(),
        &Silent,
    )
    .unwrap();
    (mesh, topology, morph)
}

fn grey(name: &str) -> (usize, usize, Vec<f64>) {
    let img = image::open(data(name)).unwrap().to_luma8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    (w, h, img.pixels().map(|p| p.0[0] as f64).collect())
}

/// The morph's grey levels on the axial slice at height `z`, one point per
/// voxel centre.
fn slice(morph: &Morph, w: usize, h: usize, z: f64) -> Vec<f64> {
    let points: Vec<DVec3> = (0..w * h)
        .map(|i| DVec3::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, z))
        .collect();
    morph
        .colours(&points)
        .iter()
        .map(|c| (c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0)
        .collect()
}

#[test]
fn an_exemplar_plane_shows_its_photograph() {
    let (_, _, morph) = brain();
    for (name, z) in [
        ("slice_080.png", 80.5),
        ("slice_096.png", 96.5),
        ("slice_112.png", 112.5),
    ] {
        let (w, h, photo) = grey(name);
        let got = slice(&morph, w, h, z);
        let mut worst = 0.0f64;
        for y in 3..h - 3 {
            for x in 3..w - 3 {
                worst = worst.max((got[y * w + x] - photo[y * w + x]).abs());
            }
        }
        assert!(worst <= 2.0, "{name}: off by {worst}/255 on its own plane");
    }
}

#[test]
fn the_colour_is_continuous_across_region_boundaries() {
    let (_, _, morph) = brain();
    let h = 0.25;
    // Columns through the tissue, on a coarse lattice.
    let columns: Vec<DVec2> = (0..40)
        .flat_map(|i| {
            (0..40).map(move |j| DVec2::new(40.0 + 3.0 * i as f64, 40.0 + 4.0 * j as f64))
        })
        .collect();
    let jump = |at: &dyn Fn(DVec2) -> (DVec3, DVec3)| -> f64 {
        let (a, b): (Vec<DVec3>, Vec<DVec3>) = columns.iter().map(|&c| at(c)).unzip();
        let (ca, cb) = (morph.colours(&a), morph.colours(&b));
        ca.iter()
            .zip(&cb)
            .map(|(p, q)| {
                (0..3)
                    .map(|k| (p[k] as f64 - q[k] as f64).abs())
                    .sum::<f64>()
                    / 3.0
            })
            .sum::<f64>()
            / columns.len() as f64
    };
    let boundary = 96.5;
    assert_ne!(
        morph.region_of(DVec3::new(100.0, 100.0, boundary - h / 2.0)),
        morph.region_of(DVec3::new(100.0, 100.0, boundary + h / 2.0)),
        "the points straddle a region boundary"
    );
    let across = jump(&|c| (c.extend(boundary - h / 2.0), c.extend(boundary + h / 2.0)));
    // Ordinary neighbours at the same distance: along z inside a region,
    // and along x.
    let along_z = [86.0, 90.0, 102.0, 106.0]
        .map(|z| jump(&|c| (c.extend(z - h / 2.0), c.extend(z + h / 2.0))))
        .into_iter()
        .fold(0.0, f64::max);
    let along_x = jump(&|c| (c.extend(90.0), (c + DVec2::new(h, 0.0)).extend(90.0)));
    eprintln!("mean jump: across {across:.3}, along z {along_z:.3}, along x {along_x:.3}");
    assert!(
        across <= along_z.max(along_x),
        "mean jump across the boundary {across:.3} > across neighbours {along_z:.3} (z), {along_x:.3} (x)"
    );
}

/// RMS difference after a Gaussian blur of σ 2 px, and the mean gradient
/// magnitude over the truth's: compare_morph.py's measures.
fn scores(pred: &[f64], truth: &[f64], w: usize, h: usize) -> (f64, f64) {
    let ones = vec![1.0; w * h];
    let blur = |v: &[f64]| Plane::new(w, h, v.iter().map(|&x| x as f32).collect()).blur(2.0, &ones);
    let (bp, bt) = (blur(pred), blur(truth));
    let rms = (bp
        .data
        .iter()
        .zip(&bt.data)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum::<f64>()
        / (w * h) as f64)
        .sqrt();
    let gradient = |v: &[f64]| -> f64 {
        let mut sum = 0.0;
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let gx = (v[y * w + x + 1] - v[y * w + x - 1]) / 2.0;
                let gy = (v[(y + 1) * w + x] - v[(y - 1) * w + x]) / 2.0;
                sum += gx.hypot(gy);
            }
        }
        sum
    };
    (rms, gradient(pred) / gradient(truth))
}

#[test]
fn held_back_slices_beat_the_nearest_exemplar_and_keep_their_detail() {
    let (_, _, morph) = brain();
    for (truth, z, below, above) in [
        ("truth_088.png", 88.5, "slice_080.png", "slice_096.png"),
        ("truth_104.png", 104.5, "slice_096.png", "slice_112.png"),
    ] {
        let (w, h, truth) = grey(truth);
        let (_, _, a) = grey(below);
        let (_, _, b) = grey(above);
        let ours = scores(&slice(&morph, w, h, z), &truth, w, h);
        let nearest = scores(&a, &truth, w, h).0.min(scores(&b, &truth, w, h).0);
        let fade: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 0.5 * (x + y)).collect();
        let fade = scores(&fade, &truth, w, h);
        eprintln!(
            "z {z}: blurred RMS {:.2} (nearest {nearest:.2}, cross-fading {:.2}), detail {:.3} (cross-fading {:.3})",
            ours.0, fade.0, ours.1, fade.1
        );
        assert!(
            ours.0 < nearest && ours.0 <= 1.2 * fade.0,
            "z {z}: blurred RMS {:.2}, nearest exemplar {nearest:.2}, cross-fading {:.2}",
            ours.0,
            fade.0
        );
        assert!(
            (0.85..=1.2).contains(&ours.1),
            "z {z}: detail ratio {:.3} (cross-fading {:.3})",
            ours.1,
            fade.1
        );
    }
}

#[test]
fn the_same_bytes_on_any_thread_count() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let (_, _, morph) = brain();
                let points: Vec<DVec3> = (0..20_000)
                    .map(|i| {
                        let f = i as f64;
                        DVec3::new(
                            10.0 + (f * 0.618).rem_euclid(177.0),
                            10.0 + (f * 0.377).rem_euclid(213.0),
                            70.0 + (f * 0.0213).rem_euclid(50.0),
                        )
                    })
                    .collect();
                morph.colours(&points)
            })
    };
    assert_eq!(run(1), run(3));
}

/// A sections file in `dir` with one exemplar per `(image, origin, u, v)`;
/// images named `*.png` that do not exist yet are written as a 32x32 grey
/// gradient.
/// An exemplar as written in a sections file: image, origin, u, v.
type Entry<'a> = (&'a str, [f64; 3], [f64; 3], [f64; 3]);

fn sections(dir: &Path, entries: &[Entry]) -> PathBuf {
    let mut toml = String::new();
    for (image, o, u, v) in entries {
        let path = dir.join(image);
        if !path.exists() {
            image::GrayImage::from_fn(32, 32, |x, y| image::Luma([(4 * x + 3 * y) as u8]))
                .save(&path)
                .unwrap();
        }
        toml +=
            &format!("[[exemplar]]\nimage = \"{image}\"\norigin = {o:?}\nu = {u:?}\nv = {v:?}\n\n");
    }
    let path = dir.join("sections.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

fn refused(mesh: &TriMesh, path: &Path) -> String {
    let topology = Topology::build(mesh).unwrap();
    match Morph::read(mesh, &topology, path, MorphOptions::default(), &Silent) {
        Ok(_) => panic!("accepted {}", std::fs::read_to_string(path).unwrap()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_sections_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cube = io::read(&data("box.obj")).unwrap();
    let (x, y) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let cases: Vec<(Vec<Entry>, &str)> = vec![
        (vec![("a.png", [0.0, 0.0, 300.0], x, y)], "outside the mesh"),
        (
            vec![
                ("a.png", [0.0, 0.0, 50.5], x, y),
                ("b.png", [10.0, 5.0, 50.5], x, y),
            ],
            "coincident",
        ),
        (
            vec![("a.png", [0.0, 0.0, 50.5], [0.0; 3], y)],
            "zero length",
        ),
        (
            vec![("a.png", [0.0, 0.0, 50.5], x, [2.0, 0.0, 0.0])],
            "parallel",
        ),
        (
            vec![("a.png", [500.0, 500.0, 50.5], x, y)],
            "does not reach the mesh",
        ),
    ];
    for (entries, want) in cases {
        let path = sections(d, &entries);
        let msg = refused(&cube, &path);
        assert!(msg.contains(want), "wanted '{want}' in: {msg}");
        assert!(msg.contains("sections.toml"), "the file is named: {msg}");
        assert!(msg.contains("exemplar"), "the exemplar is named: {msg}");
    }
    std::fs::write(d.join("broken.png"), b"not a png").unwrap();
    let path = sections(d, &[("broken.png", [0.0, 0.0, 50.5], x, y)]);
    let msg = refused(&cube, &path);
    assert!(msg.contains("broken.png"), "{msg}");

    // The arc path: needs its axis, which lies in the plane.
    let arc = "[[exemplar]]\nimage = \"a.png\"\norigin = [0.0, 0.0, 50.5]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 1.0, 0.0]\n";
    for (extra, want) in [
        ("path = \"arc\"\n", "needs axis"),
        (
            "axis = [[0.0, 0.0, 50.5], [1.0, 0.0, 0.0]]\n",
            "for path = \"arc\" alone",
        ),
        (
            "path = \"arc\"\naxis = [[0.0, 0.0, 60.0], [1.0, 0.0, 0.0]]\n",
            "does not lie in the exemplar's plane",
        ),
        ("path = \"spiral\"\n", "unknown variant `spiral`"),
    ] {
        let path = d.join("sections.toml");
        std::fs::write(&path, format!("{arc}{extra}")).unwrap();
        let msg = refused(&cube, &path);
        assert!(
            msg.contains(want) && msg.contains("sections.toml"),
            "wanted '{want}' in: {msg}"
        );
    }
    let path = d.join("sections.toml");
    std::fs::write(
        &path,
        format!("{arc}path = \"arc\"\naxis = [[0.0, 0.0, 50.5], [1.0, 0.0, 0.0]]\n"),
    )
    .unwrap();
    let topology = Topology::build(&cube).unwrap();
    assert!(Morph::read(&cube, &topology, &path, MorphOptions::default(), &Silent).is_ok());

    // Seed 003, Fig. 2: a subdomain that is not a disk. A torus around z
    // cut by z = 0 gives a ring (a hole); by x = 0, two discs.
    let ring = torus(3.0, 1.0, 48, 24);
    let s = 0.25;
    let path = sections(
        d,
        &[("a.png", [-5.0, -5.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0])],
    );
    let msg = refused(&ring, &path);
    assert!(msg.contains("hole") && msg.contains("disk"), "{msg}");
    let path = sections(
        d,
        &[("a.png", [0.0, -5.0, -5.0], [0.0, s, 0.0], [0.0, 0.0, s])],
    );
    let msg = refused(&ring, &path);
    assert!(msg.contains("2 pieces") && msg.contains("disk"), "{msg}");
}

#[test]
fn a_masked_photograph_is_fitted_to_the_mesh() {
    // Seed 003, 4.3: a photograph whose tissue (a disc, masked) is smaller
    // than the section is stretched onto it: no pixel the mask hides shows
    // anywhere on the plane, and the tissue's rim lands on the mesh's rim.
    let mesh = io::read(&data("box.obj")).unwrap();
    let topology = Topology::build(&mesh).unwrap();
    let (w, h) = (197, 233);
    // A disc of tissue (a green rim round a red centre) on blue that the
    // mask hides.
    let disc = |z: f64, centre: DVec2, radius: f64| {
        let from = |i: usize| (DVec2::new((i % w) as f64, (i / w) as f64) - centre).length();
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| match from(i) {
                d if d >= radius => [0.0, 0.0, 255.0],
                d if d > radius - 6.0 => [0.0, 255.0, 0.0],
                _ => [200.0, 60.0, 60.0],
            })
            .collect();
        let mask: Vec<bool> = (0..w * h).map(|i| from(i) < radius).collect();
        let place = [DVec3::new(0.0, 0.0, z), DVec3::X, DVec3::Y];
        Exemplar::new("disc.png".into(), w, h, rgb, Some(mask), place).unwrap()
    };
    let centre = DVec2::new(98.0, 116.0);
    let plane = |z: f64| -> Vec<DVec3> {
        (0..w * h)
            .map(|i| DVec3::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, z))
            .collect()
    };
    let morph = Morph::new(
        &mesh,
        &topology,
        vec![disc(96.5, centre, 60.0)],
        MorphOptions::default(),
        &Silent,
    )
    .unwrap();
    let colours = morph.colours(&plane(96.5));
    let blue = colours.iter().filter(|c| c[2] > 128).count();
    assert_eq!(blue, 0, "{blue} points show what the mask hides");
    // The rim of the box's section (its outer ring of pixels) shows the
    // disc's green rim, and its centre the disc's centre.
    let rim: Vec<&[u8; 3]> = (0..w * h)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            x == 1 || y == 1 || x == w - 2 || y == h - 2
        })
        .map(|i| &colours[i])
        .collect();
    let green = rim.iter().filter(|c| c[1] > 128 && c[0] < 128).count();
    eprintln!("{green} of {} rim points show the tissue's rim", rim.len());
    assert!(
        green as f64 >= 0.9 * rim.len() as f64,
        "{green} of {} rim points are the tissue's rim",
        rim.len()
    );
    let mid = colours[116 * w + 98];
    assert!(mid[0] > 150 && mid[1] < 110, "the centre shows {mid:?}");

    // Two such photographs, discs of other sizes in other places: between
    // their planes the morph shows tissue alone, and the warp between them
    // maps disc onto disc (the box's centre shows both discs' centres).
    let morph = Morph::new(
        &mesh,
        &topology,
        vec![
            disc(80.5, DVec2::new(70.0, 90.0), 45.0),
            disc(112.5, DVec2::new(120.0, 140.0), 70.0),
        ],
        MorphOptions::default(),
        &Silent,
    )
    .unwrap();
    for z in [84.0, 96.5, 108.0] {
        let blue = morph
            .colours(&plane(z))
            .iter()
            .filter(|c| c[2] > 128)
            .count();
        assert_eq!(blue, 0, "z {z}: {blue} points show what the masks hide");
    }
}

#[test]
fn the_cli_writes_a_cut_or_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = data("box.obj");
    // `organtex COMMAND box.obj --sections SECTIONS MODE... -o OUT`.
    let run = |command: &str, sections: &Path, mode: &[&str], out: &Path| {
        let mut args = vec![
            command,
            mesh.to_str().unwrap(),
            "--sections",
            sections.to_str().unwrap(),
        ];
        args.extend(mode);
        args.extend(["-o", out.to_str().unwrap()]);
        organtex(&args)
    };
    let sections = data("sections.toml");
    let out = dir.path().join("cut.png");
    let grid = ["--grid", "0,0,88.5;1,0,0;0,1,0;197,233", "--json"];
    let (ok, stdout, stderr) = run("morph", &sections, &grid, &out);
    assert!(ok, "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(summary["points"], 197 * 233);
    for key in ["precompute_seconds", "seconds", "points_per_second"] {
        assert!(summary[key].as_f64().unwrap() > 0.0, "{key}: {summary}");
    }
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (197, 233));

    // A plane section (x + z = 150 cuts the box obliquely), by `organtex
    // morph` and by `organtex section --sections`: the same picture.
    let plane = ["--plane", "1,0,1,150", "--resolution", "256"];
    let cut = dir.path().join("oblique.png");
    let (ok, _, stderr) = run("morph", &sections, &plane, &cut);
    assert!(ok, "{stderr}");
    let img = image::open(&cut).unwrap().to_rgba8();
    assert!(img.pixels().filter(|p| p[3] == 255).count() > 10_000);
    let section = dir.path().join("section.png");
    let (ok, _, stderr) = run("section", &sections, &plane, &section);
    assert!(ok, "{stderr}");
    assert_eq!(image::open(&section).unwrap().to_rgba8(), img);

    // Bad sections: one message naming the file, nothing written.
    let bad = dir.path().join("bad.toml");
    let never = dir.path().join("never.png");
    let small = ["--grid", "0,0,88.5;1,0,0;0,1,0;16,16"];
    for (text, named) in [
        (
            "[[exemplar]]\nimage = \"missing.png\"\norigin = [0.0, 0.0, 50.5]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 1.0, 0.0]\n",
            "missing.png",
        ),
        ("[[exemplar]]\nimage = 3\n", "bad.toml"),
    ] {
        std::fs::write(&bad, text).unwrap();
        let (ok, _, stderr) = run("morph", &bad, &small, &never);
        assert!(!ok && stderr.contains(named), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!never.exists());
    }
    // An open mesh has no inside to fill: named, nothing written.
    let open = dir.path().join("open.obj");
    std::fs::write(&open, "v 0 0 0\nv 100 0 0\nv 0 100 100\nf 1 2 3\n").unwrap();
    let (ok, _, stderr) = organtex(&[
        "morph",
        open.to_str().unwrap(),
        "--sections",
        sections.to_str().unwrap(),
        small[0],
        small[1],
        "-o",
        never.to_str().unwrap(),
    ]);
    assert!(
        !ok && stderr.contains("open.obj") && stderr.contains("not closed"),
        "{stderr}"
    );
    assert!(!never.exists());
}

#[test]
fn a_curved_cut_is_textured_from_the_morph() {
    // A ball of radius 30 in the brain's box, across the three exemplar
    // planes: each triangle's chart shows the morph at the surface point
    // it maps to, and no chart reads another's texels.
    let (_, _, morph) = brain();
    let mut cut = organtex::mesh::shapes::icosphere(3);
    let centre = DVec3::new(98.0, 116.0, 96.5);
    for p in &mut cut.positions {
        *p = centre + *p * 30.0;
    }
    let texture = organtex::solid::texture_cut(&cut, &morph, 4.0).unwrap();
    let (w, h) = (texture.image.width() as f64, texture.image.height() as f64);
    let mut close = 0;
    for (t, tri) in cut.triangles.iter().enumerate() {
        let centroid = tri
            .iter()
            .map(|&i| cut.positions[i as usize])
            .sum::<DVec3>()
            / 3.0;
        let uv = (texture.uvs[3 * t] + texture.uvs[3 * t + 1] + texture.uvs[3 * t + 2]) / 3.0;
        let texel = texture
            .image
            .get_pixel((uv.x * w) as u32, (uv.y * h) as u32);
        assert_eq!(texel[3], 255, "triangle {t}'s centre is covered");
        let want = morph.colour(centroid);
        if (0..3).all(|k| texel[k].abs_diff(want[k]) <= 6) {
            close += 1;
        }
    }
    assert!(
        close as f64 >= 0.95 * cut.triangles.len() as f64,
        "{close} of {} triangles show the morph at their centre",
        cut.triangles.len()
    );
    let glb = organtex::scene::gltf::cut_glb(&cut, &texture).unwrap();
    assert_eq!(&glb[..4], b"glTF");
}

#[test]
fn a_great_arc_path_keeps_the_distance_to_the_axis() {
    // Seed 003, 4.2: cuts through a common axis (an orange's segments)
    // sweep by rotating about it. Two cuts through the z axis of a ball,
    // each showing rings about the axis: between them the rings stay
    // rings (the colour depends on the distance to the axis alone), where
    // straight normal paths would shrink them by cos 45° midway.
    let mut ball = organtex::mesh::shapes::icosphere(4);
    for p in &mut ball.positions {
        *p *= 40.0;
    }
    let topology = Topology::build(&ball).unwrap();
    let ring = |d: f64| 128.0 + 100.0 * (std::f64::consts::TAU * d / 10.0).sin();
    let (n, s) = (320usize, 0.25);
    let photo: Vec<[f32; 3]> = (0..n * n)
        .map(|i| [ring((((i % n) as f64 + 0.5) * s - 40.0).abs()) as f32; 3])
        .collect();
    let cut = |origin: DVec3, u: DVec3| {
        Exemplar::new(
            "rings.png".into(),
            n,
            n,
            photo.clone(),
            None,
            [origin, u * s, DVec3::Z * s],
        )
        .unwrap()
    };
    let planes = || {
        [
            cut(DVec3::new(-40.0, 0.0, -40.0), DVec3::X),
            cut(DVec3::new(0.0, -40.0, -40.0), DVec3::Y),
        ]
    };
    let arcs: Vec<Exemplar> = planes()
        .into_iter()
        .map(|e| e.with_arc(DVec3::ZERO, DVec3::Z).unwrap())
        .collect();
    let error = |exemplars: Vec<Exemplar>| {
        let morph = Morph::new(
            &ball,
            &topology,
            exemplars,
            MorphOptions::default(),
            &Silent,
        )
        .unwrap();
        let mut sum = 0.0;
        let mut count = 0.0;
        for k in 0..400 {
            let d = 6.0 + 28.0 * (k % 20) as f64 / 20.0;
            let angle = -(0.3 + 0.97 * (k / 20) as f64 / 20.0); // -17° to -73°
            let p = DVec3::new(
                d * angle.cos(),
                d * angle.sin(),
                -10.0 + (k % 7) as f64 * 3.0,
            );
            sum += (morph.colour(p)[0] as f64 - ring(d)).abs();
            count += 1.0;
        }
        sum / count
    };
    let (arc, straight) = (error(arcs), error(planes().to_vec()));
    eprintln!("mean error from the rings: arc {arc:.1}, normal {straight:.1}");
    assert!(
        arc < 10.0 && straight > 3.0 * arc,
        "arc {arc:.1}, normal {straight:.1}"
    );

    // An axis off the plane is refused.
    let off = planes()[0]
        .clone()
        .with_arc(DVec3::new(0.0, 1.0, 0.0), DVec3::Z);
    assert!(
        off.unwrap_err()
            .to_string()
            .contains("does not lie in the exemplar's plane")
    );
}
