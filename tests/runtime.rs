//! The simulator's runtime (`organtex::runtime`): carving sessions on every
//! interior model and on the default bake (254k tets), the cut-texture
//! atlas, and bad input through the API.
//!
//! After every step the carved surface must be closed and consistently
//! oriented (each directed edge once, its reverse once), must equal the
//! last surface less the vanished faces plus the appeared ones, and every
//! appeared face's atlas texels must be the interior's colours at their
//! 3D points within 1/255.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use glam::DVec3;
use organtex::progress::Silent;
use organtex::runtime::{
    AtlasOptions, Bake, Carving, CarvingOptions, CutTextures, Model, Node, Step, Tool,
};
use organtex::solid::{Interior, InteriorMethod, Placement, interior_block};
use organtex::tetra::TetMesh;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The carved surface a session is expected to have, face by face.
type Surface = HashMap<u32, [u32; 3]>;

fn surface_of(c: &Carving) -> Surface {
    c.surface().into_iter().map(|(id, f, _)| (id, f)).collect()
}

/// How many faces use each directed edge.
fn directed_edges(surface: &Surface) -> HashMap<(u32, u32), u32> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for f in surface.values() {
        for k in 0..3 {
            *directed.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
        }
    }
    directed
}

/// The mesh's own boundary edges with more than two faces (two tets
/// touching at an edge, as isosurface stuffing sometimes leaves them):
/// carving keeps them as they are until it takes them away.
fn original_defects(c: &Carving) -> Vec<(u32, u32)> {
    let mut d: Vec<(u32, u32)> = directed_edges(&surface_of(c))
        .into_iter()
        .filter(|&(_, n)| n > 1)
        .map(|(e, _)| e)
        .collect();
    d.sort_unstable();
    d
}

/// Every directed edge once and its reverse once: closed at its edges
/// (two faces an edge) and consistently oriented; the mesh's own
/// `defects` may keep their four faces.
fn assert_closed_and_oriented(surface: &Surface, defects: &[(u32, u32)], what: &str) {
    let directed = directed_edges(surface);
    for (&(a, b), &n) in &directed {
        let allowed = if defects.binary_search(&(a, b)).is_ok() {
            2
        } else {
            1
        };
        assert!(n <= allowed, "{what}: edge {a}->{b} is used {n} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&n),
            "{what}: edge {a}->{b} has no twin"
        );
    }
}

/// Check `step` against the surface before it (updated in place), and
/// its new faces' texels and vertex colours against the interior.
fn check_step(
    c: &Carving,
    step: &Step,
    surface: &mut Surface,
    defects: &[(u32, u32)],
    what: &str,
) -> usize {
    for gone in &step.vanished {
        assert_eq!(
            surface.remove(&gone.id),
            Some(gone.vertices),
            "{what}: vanished face {} was not on the surface",
            gone.id
        );
    }
    for f in &step.appeared {
        assert!(
            surface.insert(f.id, f.vertices).is_none(),
            "{what}: face {} appeared twice",
            f.id
        );
    }
    assert_eq!(surface, &surface_of(c), "{what}: the step's faces");
    assert_closed_and_oriented(surface, defects, what);
    assert!(step.removed.windows(2).all(|w| w[0] < w[1]));
    assert!(step.removed.iter().all(|&t| !c.alive(t)));
    check_texels(c, step, what)
}

/// Every texel whose centre lies on a new face: its page holds the
/// interior's colour there within 1/255. Vertex colours likewise. The
/// texels compared. The points are moved a hair into the face's own tet,
/// towards its centroid
/// (the surviving side): a lapped solid texture is continuous across tet
/// faces only to a few 1/255 at some faces, and the removed tet across
/// the face is no longer the organ.
fn check_texels(c: &Carving, step: &Step, what: &str) -> usize {
    let node = c.node();
    let mesh = node.tet_mesh().unwrap();
    let side = c.atlas().options().page_size;
    let mut points = Vec::new();
    let mut stored = Vec::new();
    let mut vertex_points = Vec::new();
    let mut vertex_stored = Vec::new();
    for f in &step.appeared {
        let chart = c.surface_chart(f.id).expect("a new face has a chart");
        assert_eq!(chart.page, f.page);
        let page = c.atlas().page(f.page).expect("its page lives");
        let p = f.vertices.map(|v| mesh.positions[v as usize]);
        let corners = mesh.corners((f.id / 4) as usize);
        let centroid = (corners[0] + corners[1] + corners[2] + corners[3]) / 4.0;
        let inward = |q: DVec3| q + (centroid - q) * 1e-7;
        chart.texels(|x, y, b, on| {
            if on {
                points.push(inward(p[0] * b[0] + p[1] * b[1] + p[2] * b[2]));
                let k = 4 * (y * side + x) as usize;
                stored.push([page[k], page[k + 1], page[k + 2], page[k + 3]]);
            }
        });
        for (q, colour) in p.iter().zip(f.colours) {
            vertex_points.push(inward(*q));
            vertex_stored.push(colour);
        }
    }
    let expected = node.model().colours(&points);
    for (i, (s, e)) in stored.iter().zip(&expected).enumerate() {
        let d = (0..3).map(|k| s[k].abs_diff(e[k])).max().unwrap_or(0);
        assert!(
            d <= 1 && s[3] == 255,
            "{what}: texel at {} is {s:?}, the interior has {e:?}",
            points[i]
        );
    }
    let expected = node.model().colours(&vertex_points);
    for ((s, e), p) in vertex_stored.iter().zip(&expected).zip(&vertex_points) {
        let d = (0..3).map(|k| s[k].abs_diff(e[k])).max().unwrap_or(0);
        assert!(
            d <= 1,
            "{what}: vertex at {p} is {s:?}, the interior has {e:?}"
        );
    }
    stored.len()
}

/// A closed organ-like solid and its tets: the kiwi anchor (a stretched
/// sphere), lapped as the anchor says.
fn kiwi() -> organtex::solid::lst::anchors::Anchor {
    organtex::solid::lst::anchors::kiwi(organtex::solid::lst::TextureType::Layered, 3000).unwrap()
}

/// Nodes of every interior model over small tet meshes.
fn nodes() -> Vec<Arc<Node>> {
    let a = kiwi();
    let model = organtex::solid::lst::fill(&a.tets, &a.options, &Silent).unwrap();
    let lapped = organtex::solid::lst::LstInterior::new(
        model.into(),
        organtex::solid::lst::anchors::layered_exemplar().into(),
    )
    .unwrap();
    let mut out = vec![Arc::new(Node::new(
        "lapped",
        InteriorMethod::Layered,
        Model::Lapped(lapped),
        None,
    ))];
    let photo = root().join("tests/data/tissues/he_nests.png");
    let layered = root().join("database/sources/layered_wall.png");
    for (method, texture) in [
        (InteriorMethod::Fnpts, &photo),
        (InteriorMethod::Layered, &layered),
        (InteriorMethod::Stereology, &photo),
    ] {
        let volume =
            interior_block(texture, &[], Default::default(), 16, method, 3, &Silent).unwrap();
        let placement = Placement::new(DVec3::new(0.1, -0.2, 0.3), 0.05).unwrap();
        out.push(Arc::new(Node::new(
            &format!("{method:?}"),
            method,
            Model::Block { volume, placement },
            Some(a.tets.clone()),
        )));
    }
    // A morph of brain MRI slices in a box, the box tetrahedralised.
    let dir = root().join("tests/data/morph");
    let surface = organtex::mesh::io::read(&dir.join("box.obj")).unwrap();
    let topology = organtex::mesh::Topology::build(&surface).unwrap();
    let morph = organtex::solid::morph::Morph::read(
        &surface,
        &topology,
        &dir.join("sections.toml"),
        Default::default(),
        &Silent,
    )
    .unwrap();
    let tets = organtex::tetra::tetrahedralise(
        &surface,
        &organtex::tetra::TetOptions {
            cells: Some(3000),
            ..Default::default()
        },
        &Silent,
    )
    .unwrap();
    out.push(Arc::new(Node::new(
        "morph",
        InteriorMethod::Morph,
        Model::Morph(Box::new(morph)),
        Some(tets),
    )));
    out
}

fn bounds(mesh: &TetMesh) -> (DVec3, DVec3) {
    mesh.positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}

/// A burr's path through the solid: a wavy line across its box.
fn path(mesh: &TetMesh, steps: usize) -> Vec<DVec3> {
    let (lo, hi) = bounds(mesh);
    (0..=steps)
        .map(|i| {
            let s = i as f64 / steps as f64;
            let wave = (s * 9.0).sin() * 0.2;
            lo + (hi - lo) * DVec3::new(0.1 + 0.8 * s, 0.5 + wave, 0.45 + 0.5 * wave)
        })
        .collect()
}

#[test]
fn carving_every_model_keeps_the_surface_closed_and_textured_from_the_interior() {
    for node in nodes() {
        let mesh = node.tet_mesh().unwrap();
        let what = node.name.clone();
        let (lo, hi) = bounds(mesh);
        let radius = (hi - lo).max_element() * 0.08;
        let options = CarvingOptions {
            atlas: AtlasOptions {
                texels_per_unit: 24.0 / (hi - lo).max_element() * 4.0,
                page_size: 256,
            },
            ..Default::default()
        };
        let mut c = Carving::new(node.clone(), options).unwrap();
        let mut surface = surface_of(&c);
        let defects = original_defects(&c);
        assert_closed_and_oriented(&surface, &defects, &what);
        let points = path(mesh, 20);
        let (mut removed, mut texels) = (0, 0);
        for (k, w) in points.windows(2).enumerate() {
            let tool = if k % 2 == 0 {
                Tool::Capsule {
                    a: w[0],
                    b: w[1],
                    radius,
                }
            } else {
                Tool::Sphere {
                    centre: w[1],
                    radius: radius * 1.3,
                }
            };
            let step = c.carve(&tool).unwrap();
            removed += step.removed.len();
            texels += check_step(
                &c,
                &step,
                &mut surface,
                &defects,
                &format!("{what}, step {k}"),
            );
        }
        assert!(removed > 100, "{what}: {removed} tets removed");
        assert!(texels > 5000, "{what}: {texels} texels compared");
        // Tets by id, as SOFA's TetrahedraRemoved: exactly those.
        let ids: Vec<u32> = (0..mesh.num_tets() as u32)
            .filter(|&t| c.alive(t))
            .step_by(7)
            .take(40)
            .collect();
        let step = c.remove(&ids).unwrap();
        assert_eq!(step.removed, ids);
        check_texels(&c, &step, &what);
    }
}

#[test]
fn a_step_changes_nothing_when_refused_and_the_session_goes_on() {
    let node = nodes().swap_remove(0);
    let n = node.tet_mesh().unwrap().num_tets() as u32;
    let mut c = Carving::new(node.clone(), CarvingOptions::default()).unwrap();
    c.remove(&[3, 5]).unwrap();
    let before = surface_of(&c);
    type Call = Box<dyn Fn(&mut Carving) -> organtex::Result<Step>>;
    let cases: Vec<(Call, &str)> = vec![
        (Box::new(move |c| c.remove(&[1, n])), "out of range"),
        (Box::new(|c| c.remove(&[7, 3])), "already removed"),
        (Box::new(|c| c.remove(&[8, 8])), "twice"),
        (
            Box::new(|c| {
                c.carve(&Tool::Sphere {
                    centre: DVec3::new(f64::NAN, 0.0, 0.0),
                    radius: 1.0,
                })
            }),
            "not finite",
        ),
        (
            Box::new(|c| {
                c.carve(&Tool::Capsule {
                    a: DVec3::ZERO,
                    b: DVec3::new(0.0, f64::INFINITY, 0.0),
                    radius: 1.0,
                })
            }),
            "not finite",
        ),
        (
            Box::new(|c| {
                c.carve(&Tool::Sphere {
                    centre: DVec3::ZERO,
                    radius: 0.0,
                })
            }),
            "radius",
        ),
    ];
    for (call, needle) in cases {
        let e = call(&mut c).expect_err("refused").to_string();
        assert!(e.contains(needle), "{e}");
        assert_eq!(surface_of(&c), before, "{e}");
    }
    assert!(!c.alive(3) && c.alive(7) && c.alive(8));
    assert_eq!(c.removed(), 2);
    // Still usable.
    let step = c.remove(&[7, 8]).unwrap();
    assert_eq!(step.removed, [7, 8]);
    // Bad atlas options, and pages too small for the mesh's faces.
    let longest = node.longest_edge().unwrap();
    assert!(longest > 0.0);
    for (t, p) in [
        (0.0, 1024),
        (-3.0, 1024),
        (f64::NAN, 1024),
        (8.0, 8),
        (64.0 / longest, 64),
    ] {
        let o = CarvingOptions {
            atlas: AtlasOptions {
                texels_per_unit: t,
                page_size: p,
            },
            ..Default::default()
        };
        let e = Carving::new(node.clone(), o).err().expect("refused");
        assert!(e.to_string().contains("atlas"), "{e}");
    }
    // A node without tets cannot be carved.
    let bare = Node::new(
        "bare",
        InteriorMethod::Fnpts,
        Model::Block {
            volume: organtex::solid::lst::anchors::layered_exemplar(),
            placement: Placement::new(DVec3::ZERO, 1.0).unwrap(),
        },
        None,
    );
    let e = Carving::new(Arc::new(bare), CarvingOptions::default())
        .err()
        .expect("no tets");
    assert!(e.to_string().contains("no tet mesh"), "{e}");
}

#[test]
fn the_same_steps_give_the_same_atlas_on_any_thread_count_and_in_the_background() {
    let node = nodes().swap_remove(0);
    let mesh = node.tet_mesh().unwrap();
    let points = path(mesh, 12);
    let (lo, hi) = bounds(mesh);
    let radius = (hi - lo).max_element() * 0.1;
    let run = |threads: usize, background: bool| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let options = CarvingOptions {
                background_texels: background,
                ..Default::default()
            };
            let mut c = Carving::new(node.clone(), options).unwrap();
            let mut steps = Vec::new();
            for w in points.windows(2) {
                let mut s = c
                    .carve(&Tool::Capsule {
                        a: w[0],
                        b: w[1],
                        radius,
                    })
                    .unwrap();
                assert_eq!(s.texels_pending, background && !s.appeared.is_empty());
                s.seconds = 0.0;
                s.texels_pending = false;
                s.dirty.clear();
                steps.push(s);
            }
            c.wait();
            let pages: Vec<Vec<u8>> = c
                .atlas()
                .pages()
                .iter()
                .map(|&p| c.atlas().page(p).unwrap().to_vec())
                .collect();
            (steps, pages)
        })
    };
    let one = run(1, false);
    assert!(!one.1.is_empty());
    assert!(one == run(2, false), "one thread and two differ");
    assert!(one == run(2, true), "background texels differ");
}

#[test]
fn faces_vanish_and_give_their_pages_back() {
    let node = nodes().swap_remove(0);
    let mesh = node.tet_mesh().unwrap();
    let options = CarvingOptions {
        atlas: AtlasOptions {
            texels_per_unit: 200.0,
            page_size: 128,
        },
        ..Default::default()
    };
    let mut c = Carving::new(node.clone(), options).unwrap();
    let (lo, hi) = bounds(mesh);
    let centre = (lo + hi) / 2.0;
    let r = (hi - lo).min_element() * 0.15;
    let first = c.carve(&Tool::Sphere { centre, radius: r }).unwrap();
    assert!(!first.appeared.is_empty());
    let pages: Vec<u32> = c.atlas().pages();
    assert!(pages.len() > 2, "{pages:?}");
    // A larger sphere takes every face the first exposed.
    let second = c
        .carve(&Tool::Sphere {
            centre,
            radius: 2.0 * r,
        })
        .unwrap();
    let gone: Vec<u32> = second.vanished.iter().map(|f| f.id).collect();
    assert!(first.appeared.iter().all(|f| gone.contains(&f.id)));
    let released: Vec<u32> = second.released.clone();
    assert!(!released.is_empty(), "no page released");
    for p in &released {
        assert!(c.atlas().page(*p).is_none());
        assert!(!second.appeared.iter().any(|f| f.page == *p));
    }
    // Dirty rectangles cover every new face's chart.
    for f in &second.appeared {
        let chart = c.surface_chart(f.id).unwrap();
        let (_, r) = second
            .dirty
            .iter()
            .find(|(p, _)| *p == f.page)
            .expect("its page is dirty");
        let s = chart.slot;
        assert!(
            s.x >= r.x
                && s.y >= r.y
                && s.x + s.width <= r.x + r.width
                && s.y + s.height <= r.y + r.height
        );
    }
}

#[test]
fn new_triangles_anywhere_get_charts_coloured_from_the_interior() {
    for node in nodes() {
        let mesh = node.tet_mesh().unwrap();
        let (lo, hi) = bounds(mesh);
        let mut t = CutTextures::new(
            node.clone(),
            AtlasOptions {
                texels_per_unit: 60.0 / (hi - lo).max_element(),
                page_size: 256,
            },
        )
        .unwrap();
        // A fan of triangles across the middle of the organ.
        let c = (lo + hi) / 2.0;
        let d = (hi - lo) * 0.3;
        let tris: Vec<[DVec3; 3]> = (0..12)
            .map(|k| {
                let a = k as f64 / 12.0 * std::f64::consts::TAU;
                let b = (k + 1) as f64 / 12.0 * std::f64::consts::TAU;
                [
                    c,
                    c + DVec3::new(a.cos() * d.x, a.sin() * d.y, 0.2 * d.z),
                    c + DVec3::new(b.cos() * d.x, b.sin() * d.y, -0.2 * d.z),
                ]
            })
            .collect();
        let placed = t.add(&tris).unwrap();
        let side = t.atlas().options().page_size;
        let mut compared = 0;
        for (p, tri) in placed.iter().zip(&tris) {
            let chart = t.atlas().chart(p.chart).unwrap();
            let page = t.atlas().page(p.page).unwrap();
            let mut points = Vec::new();
            let mut stored = Vec::new();
            chart.texels(|x, y, b, on| {
                if on {
                    points.push(tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2]);
                    let k = 4 * (y * side + x) as usize;
                    stored.push([page[k], page[k + 1], page[k + 2]]);
                }
            });
            for (s, e) in stored.iter().zip(node.model().colours(&points)) {
                let d = (0..3).map(|k| s[k].abs_diff(e[k])).max().unwrap();
                assert!(d <= 1, "{}: {s:?} vs {e:?}", node.name);
                compared += 1;
            }
        }
        assert!(compared > 200, "{compared}");
        let ids: Vec<u32> = placed.iter().map(|p| p.chart).collect();
        t.release(&ids).unwrap();
        assert!(t.atlas().is_empty());
        assert!(t.release(&ids).is_err());
        let nan = [[DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0)]];
        let e = t.add(&nan).expect_err("refused").to_string();
        assert!(e.contains("not finite") || e.contains("finite"), "{e}");
    }
}

/// The default scene baked once for this file's tests.
fn default_bake() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        organtex::bake::bake(
            &root().join("scenes/hysteroscopy_myomas.toml"),
            dir.path(),
            &Default::default(),
            &Silent,
        )
        .unwrap();
        dir
    })
    .path()
}

/// The tunnel the C, C++, C# and Python examples carve: 100 steps round
/// the uterine wall's middle at z = 20 (an ellipse of semi-axes 18.5 and
/// 11.8 units, 95% of the way round), a sphere of radius 1.5.
pub fn wall_path(step: usize) -> DVec3 {
    let a = step as f64 / 100.0 * 0.95 * std::f64::consts::TAU;
    DVec3::new(18.5 * a.cos(), 11.8 * a.sin(), 20.0)
}

#[test]
fn carving_the_default_wall_along_a_tunnel() {
    let bake = Bake::open(default_bake()).unwrap();
    assert_eq!(bake.nodes(), ["uterus"]);
    let node = bake.node("uterus").unwrap();
    assert!(Arc::ptr_eq(&node, &bake.node("uterus").unwrap()));
    let mesh = node.tet_mesh().unwrap();
    assert_eq!(mesh.num_tets(), 275_122);
    let mut c = Carving::new(node.clone(), CarvingOptions::default()).unwrap();
    let mut surface = surface_of(&c);
    // The stuffed wall's boundary has one edge where two tets touch.
    let defects = original_defects(&c);
    assert!(defects.len() <= 4, "{defects:?}");
    assert_closed_and_oriented(&surface, &defects, "the wall before carving");
    let (mut removed, mut faces) = (Vec::new(), Vec::new());
    for i in 1..=100 {
        let step = c
            .carve(&Tool::Capsule {
                a: wall_path(i - 1),
                b: wall_path(i),
                radius: 1.5,
            })
            .unwrap();
        check_step(&c, &step, &mut surface, &defects, &format!("step {i}"));
        removed.push(step.removed.len());
        faces.push(step.appeared.len());
    }
    removed.sort_unstable();
    faces.sort_unstable();
    // A real tunnel: every step bites, tens of tets at a time.
    assert!(removed[5] >= 15 && removed[95] <= 150, "{removed:?}");
    assert!(faces[50] >= 30, "{faces:?}");
    // The carved surface as a .glb that glTF readers open.
    let glb = organtex::runtime::surface_glb(&c).unwrap();
    assert_eq!(&glb[0..4], b"glTF");
    // Memory: node and session within twice the interior files.
    let files: u64 = ["uterus.nrrd", "uterus.vtk", "uterus.lst"]
        .iter()
        .map(|f| {
            std::fs::metadata(default_bake().join("interior").join(f))
                .unwrap()
                .len()
        })
        .sum();
    let held = (node.bytes() + c.bytes()) as u64;
    assert!(held <= 2 * files, "{held} bytes held, files {files}");
}

#[test]
fn bad_bakes_and_nodes_are_named() {
    let e = Bake::open(Path::new("/nonexistent/bake")).err().unwrap();
    assert!(e.to_string().contains("not a folder"), "{e}");
    let empty = tempfile::tempdir().unwrap();
    let e = Bake::open(empty.path()).err().unwrap();
    assert!(e.to_string().contains("no report.json"), "{e}");
    std::fs::write(empty.path().join("report.json"), "{\"interiors\": 3}").unwrap();
    let e = Bake::open(empty.path()).err().unwrap().to_string();
    assert!(e.contains("report.json") && e.contains("not a bake"), "{e}");
    let report = |file: &str| {
        format!(
            r#"{{"interiors": [{{"node": "n", "texture": "t", "method": "fnpts",
                "file": "{file}", "voxels": 8, "voxel_size": 0.5}}]}}"#
        )
    };
    std::fs::write(empty.path().join("report.json"), report("../escape.nrrd")).unwrap();
    let e = Bake::open(empty.path()).err().unwrap().to_string();
    assert!(e.contains("not inside"), "{e}");
    std::fs::write(empty.path().join("report.json"), report("interior/n.nrrd")).unwrap();
    let e = Bake::open(empty.path()).err().unwrap().to_string();
    assert!(
        e.contains("missing") && e.contains("interior/n.nrrd"),
        "{e}"
    );
    let bake = Bake::open(default_bake()).unwrap();
    let e = bake.node("liver").err().unwrap().to_string();
    assert!(e.contains("no node 'liver'") && e.contains("uterus"), "{e}");
    let node = bake.node("uterus").unwrap();
    let e = node
        .colours(&[DVec3::ZERO, DVec3::new(f64::INFINITY, 0.0, 0.0)])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("point 1"), "{e}");
    let e = node.block_coordinates(&[DVec3::ZERO]).err().unwrap();
    assert!(e.to_string().contains("not a block"), "{e}");
    assert_eq!(node.colours(&[]).unwrap(), Vec::<[u8; 3]>::new());
    let c = node.colours(&[DVec3::new(18.5, 0.0, 20.0)]).unwrap();
    assert_eq!(c, node.model().colours(&[DVec3::new(18.5, 0.0, 20.0)]));
}

/// A small scene baked with `interior`, its box a 12-face cube of MRI
/// coordinates (tests/data/morph/box.obj).
fn bake_box(dir: &Path, interior: &str) -> PathBuf {
    let data = root().join("tests/data/morph");
    std::fs::create_dir_all(dir).unwrap();
    let scene = dir.join("box.toml");
    std::fs::write(
        &scene,
        format!(
            r#"
database = "{db}"
[[node]]
name = "brain"
mesh = {{ file = "{mesh}" }}
[[node.facet]]
name = "*"
texture = "fundus-tissue"
tile_size = 40.0
[node.interior]
texture = "fundus-tissue"
{interior}
[bake]
interior_voxels = 16
"#,
            db = root().join("database").display(),
            mesh = data.join("box.obj").display(),
        ),
    )
    .unwrap();
    let out = dir.join("out");
    organtex::bake::bake(&scene, &out, &Default::default(), &Silent).unwrap();
    out
}

/// Through a bake on disk: a morph's node colours points as the morph
/// itself does (the bake writes the surface it needs beside the
/// sections); a block's node gives 3D texture coordinates that sample the
/// block to the colours it reports, and its tet mesh carves.
#[test]
fn a_bake_opens_morph_and_block_nodes_as_the_models_colour() {
    let dir = tempfile::tempdir().unwrap();
    let sections = root().join("tests/data/morph/sections.toml");
    let out = bake_box(
        &dir.path().join("morph"),
        &format!("method = \"morph\"\nsections = \"{}\"", sections.display()),
    );
    let node = Bake::open(&out).unwrap().node("brain").unwrap();
    assert!(matches!(node.model(), Model::Morph(_)));
    assert!(node.tet_mesh().is_none());
    let surface = organtex::mesh::io::read(&root().join("tests/data/morph/box.obj")).unwrap();
    let topology = organtex::mesh::Topology::build(&surface).unwrap();
    let morph = organtex::solid::morph::Morph::read(
        &surface,
        &topology,
        &sections,
        Default::default(),
        &Silent,
    )
    .unwrap();
    let (lo, hi) = surface.bounding_box().unwrap();
    let points: Vec<DVec3> = (0..500)
        .map(|i| {
            let f = |k: u64| organtex::rng::unit(9, &[i, k]);
            lo + (hi - lo) * DVec3::new(f(0), f(1), f(2))
        })
        .collect();
    let ours = node.colours(&points).unwrap();
    let theirs = morph.colours(&points);
    let worst = ours
        .iter()
        .zip(&theirs)
        .flat_map(|(a, b)| (0..3).map(move |k| a[k].abs_diff(b[k])))
        .max()
        .unwrap();
    assert!(worst <= 1, "the baked morph colours differ by {worst}/255");
    let e = Carving::new(node, CarvingOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("no tet mesh"), "{e}");

    let out = bake_box(&dir.path().join("block"), "tet_mesh = true");
    let node = Bake::open(&out).unwrap().node("brain").unwrap();
    let Some((volume, placement)) = node.model().block() else {
        panic!("a block node");
    };
    let coords = node.block_coordinates(&points).unwrap();
    let colours = node.colours(&points).unwrap();
    for (c, want) in coords.iter().zip(&colours) {
        let got = volume
            .sample([c[0] as f64, c[1] as f64, c[2] as f64])
            .map(|x| x.round() as u8);
        let d = (0..3).map(|k| got[k].abs_diff(want[k])).max().unwrap();
        assert!(d <= 1, "{got:?} {want:?}");
    }
    assert!(placement.scale > 0.0 && placement.origin == DVec3::ZERO);
    let mesh = node.tet_mesh().expect("tet_mesh = true");
    let mut c = Carving::new(node.clone(), CarvingOptions::default()).unwrap();
    let centre = (lo + hi) / 2.0;
    let step = c
        .carve(&Tool::Sphere {
            centre,
            radius: (hi - lo).min_element() * 0.2,
        })
        .unwrap();
    assert!(!step.removed.is_empty() && !step.appeared.is_empty());
    assert!(mesh.num_tets() > step.removed.len());
    check_texels(&c, &step, "block bake");
}
