//! Scenes and bakes: the generated cavity is a clean surface, bakes hide
//! their seams and facet borders, a texture transform changes nothing but
//! the transform, bakes are deterministic, and bad scenes are refused
//! clearly with nothing written.

use std::path::{Path, PathBuf};

use glam::DVec3;
use organtex::bake::{BakeOptions, BakeReport, Baked, bake};
use organtex::mesh::{Components, Topology, TriMesh};
use organtex::progress::{Progress, Silent};
use organtex::scene::uterus::{self, CavityParams};
use organtex::solid::InteriorMethod;
use organtex::solid::section::{Plane, plane_section};
use organtex::synth::volume::Volume;
use organtex::{Error, Result};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn default_scene() -> PathBuf {
    root().join("scenes").join("hysteroscopy_myomas.toml")
}

/// Write a scene using the repo's database into `dir`.
fn scene_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!("database = {:?}\n{body}", root().join("database"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Write scene `name` into `dir` and bake it to `dir/name` with default
/// options.
fn bake_in(dir: &Path, name: &str, body: &str) -> Baked {
    let scene = scene_file(dir, &format!("{name}.toml"), body);
    bake(&scene, &dir.join(name), &BakeOptions::default(), &Silent).unwrap()
}

/// A small cavity with one myoma: quick to bake, one seam-cut wall and one
/// facet border, at the shipped scenes' resolution.
fn small_scene(rotation: f64, tile: f64, offset: [f64; 2]) -> String {
    format!(
        r#"
[[camera]]
position = [0.0, 0.0, 6.0]
look_at = [0.0, 0.0, 40.0]

[[node]]
name = "uterus"
[node.mesh.uterine_cavity]
seed = 5
resolution = 5
[[node.mesh.uterine_cavity.myoma]]
at = [0.3, 0.6]
radius = 7.0
height = 4.0

[[node.facet]]
name = "wall"
texture = "fundus-tissue"
tile_size = {tile}
rotation = {rotation}
offset = [{}, {}]
bump = 1.0

[[node.facet]]
name = "myoma-1"
texture = "ihc-glands"
tile_size = 6.0
overlap = 2.0

[node.interior]
texture = "ihc-glands"
block_size = 5.0

[bake]
interior_voxels = 16
"#,
        offset[0], offset[1]
    )
}

fn assert_hidden(report: &BakeReport, what: &str) {
    let mut seams = 0;
    for f in &report.facets {
        if let (Some(b), Some(u)) = (f.seam_contrast, f.seam_contrast_unblended) {
            seams += 1;
            assert!(
                b <= 1.2,
                "{what}: {} seam contrast {b:.3} > 1.2",
                f.facet.facet
            );
            assert!(
                u > b,
                "{what}: {} blending does not lower the seam contrast ({u:.3} -> {b:.3})",
                f.facet.facet
            );
        }
    }
    assert!(seams > 0, "{what}: no facet has seams to measure");
    for b in &report.borders {
        let (blended, plain) = (
            b.border_contrast.unwrap(),
            b.border_contrast_unblended.unwrap(),
        );
        assert!(blended <= 1.2, "{what}: border contrast {blended:.3} > 1.2");
        assert!(
            plain > 2.0 * blended,
            "{what}: borders {plain:.3} unblended vs {blended:.3}"
        );
    }
}

/// The JSON and binary chunks of a .glb.
fn glb_chunks(path: &Path) -> (serde_json::Value, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = 20 + json_len;
    assert_eq!(&bytes[bin + 4..bin + 8], b"BIN\0");
    (json, bytes[bin + 8..].to_vec())
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn the_generated_cavity_is_a_clean_open_surface_facing_inside() {
    let p = uterus::demo();
    let mesh = uterus::generate(&p).unwrap();
    let topo = Topology::build(&mesh).expect("manifold");
    let parts = Components::find(&topo).topology(&topo);
    assert_eq!(parts.len(), 1);
    assert_eq!(parts[0].genus, 0);
    assert_eq!(
        parts[0].boundary_loops, 1,
        "the cervical canal is the one opening"
    );
    let names = &mesh.facets.as_ref().unwrap().names;
    assert_eq!(names, &["wall", "myoma-1", "myoma-2", "polyp-1"]);
    for k in 0..names.len() as u32 {
        assert!(
            mesh.facets.as_ref().unwrap().of_face.contains(&k),
            "facet {k} has faces"
        );
    }
    // Normals face the inside: the enclosed volume counts negative (the
    // cervical opening is small, so its missing cap hardly counts).
    assert!(mesh.signed_volume() < -1000.0, "{}", mesh.signed_volume());
    assert_eq!(self_intersections(&mesh), 0);
    // Seeded: the same parameters give the same mesh, another seed another.
    assert_eq!(uterus::generate(&p).unwrap().positions, mesh.positions);
    let other = uterus::generate(&CavityParams { seed: 8, ..p }).unwrap();
    assert_ne!(other.positions, mesh.positions);
}

/// Share of the polyp facet's area facing back towards the wall (its
/// normal against the facet's mean normal, the polyp's axis): a head
/// overhanging a neck.
fn polyp_underside(mesh: &TriMesh) -> f64 {
    let facets = mesh.facets.as_ref().unwrap();
    let polyp = facets.names.iter().position(|n| n == "polyp-1").unwrap() as u32;
    let faces: Vec<usize> = (0..mesh.num_faces())
        .filter(|&f| facets.of_face[f] == polyp)
        .collect();
    let axis = faces
        .iter()
        .map(|&f| mesh.face_area_vector(f))
        .sum::<DVec3>()
        .normalize();
    let area = |f: usize| mesh.face_area(f);
    let under: f64 = faces
        .iter()
        .filter(|&&f| mesh.face_normal(f).dot(axis) < -0.1)
        .map(|&f| area(f))
        .sum();
    under / faces.iter().map(|&f| area(f)).sum::<f64>()
}

/// A sessile polyp (issue 39: "an irregular ovoid on a broad base") is a
/// dome on the wall with no neck: none of it faces back towards the wall,
/// where the stalked one's head overhangs its stalk; and the surface stays
/// clean.
#[test]
fn a_sessile_polyp_is_a_dome_without_a_neck() {
    let stalked = uterus::generate(&uterus::demo()).unwrap();
    let mut p = uterus::demo();
    p.polyps[0] = uterus::Polyp {
        stalk_radius: 2.3,
        stalk_length: 0.4,
        head_radius: 2.45,
        elongation: 1.8,
        irregularity: 0.3,
        lean: 10.0,
        sessile: true,
        ..p.polyps[0].clone()
    };
    let mesh = uterus::generate(&p).unwrap();
    let topo = Topology::build(&mesh).expect("manifold");
    let parts = Components::find(&topo).topology(&topo);
    assert_eq!(parts.len(), 1);
    assert_eq!((parts[0].genus, parts[0].boundary_loops), (0, 1));
    assert_eq!(self_intersections(&mesh), 0);
    let (sessile, on_stalk) = (polyp_underside(&mesh), polyp_underside(&stalked));
    assert!(
        sessile < 0.005,
        "sessile: {sessile} of its area faces the wall"
    );
    assert!(on_stalk > 0.05, "stalked: {on_stalk}");
}

#[test]
fn a_wall_thickness_closes_the_cavity_into_a_solid_a_cut_shows() {
    let p = CavityParams {
        wall_thickness: 8.0,
        ..uterus::demo()
    };
    let mesh = uterus::generate(&p).unwrap();
    let topo = Topology::build(&mesh).expect("manifold");
    let parts = Components::find(&topo).topology(&topo);
    assert_eq!(parts.len(), 1);
    assert_eq!((parts[0].genus, parts[0].boundary_loops), (0, 0), "closed");
    let names = &mesh.facets.as_ref().unwrap().names;
    assert_eq!(names, &["wall", "myoma-1", "myoma-2", "polyp-1", "serosa"]);
    // Faces face out of the solid, and the solid is the wall: the volume
    // inside the serosa minus the cavity's.
    let cavity = uterus::generate(&uterus::demo()).unwrap();
    assert!(
        mesh.signed_volume() > 1000.0 && mesh.signed_volume() > -2.0 * cavity.signed_volume(),
        "wall {} against cavity {}",
        mesh.signed_volume(),
        cavity.signed_volume()
    );
    assert_eq!(self_intersections(&mesh), 0);
    // A cut across the long axis, half way up: a ring of wall round the
    // cavity, its hole the cavity's section.
    let plane = Plane::new(DVec3::Z, 20.0).unwrap();
    let cut = plane_section(&mesh, &topo, plane).unwrap();
    assert_eq!(cut.boundary.len(), 2, "the wall's outline and the cavity");
    let rel = (cut.area() - cut.polygon_area()).abs() / cut.polygon_area();
    assert!(rel < 1e-6, "{rel}");
    let loop_area = |l: &Vec<u32>| {
        let q: Vec<_> = l.iter().map(|&i| cut.plane_point(i)).collect();
        (0..q.len())
            .map(|i| q[i].perp_dot(q[(i + 1) % q.len()]) / 2.0)
            .sum::<f64>()
    };
    let (outline, hole) = (loop_area(&cut.boundary[0]), loop_area(&cut.boundary[1]));
    assert!(
        outline > 0.0 && hole < -0.2 * outline,
        "outline {outline}, hole {hole}"
    );
    // A thickness beyond the cavity's size is refused, naming the key.
    let err = uterus::generate(&CavityParams {
        wall_thickness: 100.0,
        ..uterus::demo()
    })
    .unwrap_err();
    assert_eq!(err.key, "wall_thickness");
}

#[test]
fn a_closed_mesh_wound_inside_out_stays_double_sided() {
    let dir = tempfile::tempdir().unwrap();
    let cube = organtex::mesh::io::read(&root().join("tests/data/cube.obj")).unwrap();
    let mut inside_out = cube.clone();
    for t in &mut inside_out.triangles {
        t.swap(1, 2);
    }
    for (name, mesh, double_sided) in [("out", &cube, false), ("in", &inside_out, true)] {
        let file = dir.path().join(format!("{name}.obj"));
        organtex::mesh::io::write_obj(&file, mesh, None).unwrap();
        let baked = bake_in(
            dir.path(),
            name,
            &format!(
                "[[node]]\nname = \"cube\"\nmesh = {{ file = {file:?} }}\n[[node.facet]]\nname = \"*\"\ntexture = \"fundus-tissue\"\n"
            ),
        );
        let (json, _) = glb_chunks(&baked.glb);
        for m in json["materials"].as_array().unwrap() {
            assert_eq!(m["doubleSided"], double_sided, "{name}: {}", m["name"]);
        }
    }
}

/// Pairs of faces sharing no vertex that cross each other, found through a
/// grid of cells a few triangles wide.
fn self_intersections(mesh: &TriMesh) -> usize {
    let (lo, hi) = mesh.bounding_box().unwrap();
    let cell = 2.0 * (mesh.area() / mesh.num_faces() as f64).sqrt();
    let key = |p: DVec3| ((p - lo) / cell).floor().as_ivec3();
    let mut cells: std::collections::HashMap<glam::IVec3, Vec<usize>> = Default::default();
    for f in 0..mesh.num_faces() {
        let c = mesh.corners(f);
        let (a, b) = (key(c[0].min(c[1]).min(c[2])), key(c[0].max(c[1]).max(c[2])));
        for x in a.x..=b.x {
            for y in a.y..=b.y {
                for z in a.z..=b.z {
                    cells.entry(glam::IVec3::new(x, y, z)).or_default().push(f);
                }
            }
        }
    }
    let _ = hi;
    let mut pairs = std::collections::HashSet::new();
    for faces in cells.values() {
        for (i, &f) in faces.iter().enumerate() {
            for &g in &faces[i + 1..] {
                let (tf, tg) = (mesh.triangles[f], mesh.triangles[g]);
                if tf.iter().any(|v| tg.contains(v)) {
                    continue;
                }
                if triangles_cross(mesh.corners(f), mesh.corners(g)) {
                    pairs.insert((f.min(g), f.max(g)));
                }
            }
        }
    }
    pairs.len()
}

/// Separating axis test for two triangles (face normals and the nine edge
/// cross products); touching counts as apart.
fn triangles_cross(a: [DVec3; 3], b: [DVec3; 3]) -> bool {
    let edges = |t: [DVec3; 3]| [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let mut axes = vec![
        (a[1] - a[0]).cross(a[2] - a[0]),
        (b[1] - b[0]).cross(b[2] - b[0]),
    ];
    for ea in edges(a) {
        for eb in edges(b) {
            axes.push(ea.cross(eb));
        }
    }
    let scale = (a[1] - a[0]).length().max((b[1] - b[0]).length());
    for axis in axes {
        let len = axis.length();
        if len < 1e-12 * scale * scale {
            continue;
        }
        let project = |t: [DVec3; 3]| {
            let d = t.map(|p| p.dot(axis) / len);
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((a0, a1), (b0, b1)) = (project(a), project(b));
        let eps = 1e-9 * scale;
        if a1 <= b0 + eps || b1 <= a0 + eps {
            return false;
        }
    }
    true
}

#[test]
fn the_default_scene_bakes_with_seams_and_borders_blended_away() {
    let out = tempfile::tempdir().unwrap();
    let baked = bake(
        &default_scene(),
        out.path(),
        &BakeOptions::default(),
        &Silent,
    )
    .unwrap();
    assert_eq!(
        files_in(out.path()),
        [
            "interior",
            "preview.png",
            "report.json",
            "scene.glb",
            "unwraps"
        ]
    );
    let r = &baked.report;
    assert_eq!(r.mode, "layered");
    // A generated cavity: no segmentation meshed, none reported.
    assert!(r.segmentations.is_empty());
    // The uterus's interior: a block layered by depth from the
    // database's layered wall (issue 28), at the scene's scale. It tiles
    // across the layers (x, z); along y its rows follow the exemplar's,
    // and the file says y is depth.
    assert_eq!(r.interiors.len(), 1);
    let interior = &r.interiors[0];
    assert_eq!((interior.node.as_str(), interior.voxels), ("uterus", 64));
    assert_eq!(
        (interior.texture.as_str(), interior.method),
        ("layered-wall", InteriorMethod::Layered)
    );
    let (block, depth_axis) =
        Volume::read_nrrd_with_depth(&out.path().join(&interior.file)).unwrap();
    assert_eq!((block.size, depth_axis), ([64; 3], Some(1)));
    assert!(
        (block.spacing - 10.0 / 64.0).abs() < 1e-12,
        "{}",
        block.spacing
    );
    for axis in [0, 2] {
        assert!(
            block.seam(axis) <= 1.15,
            "axis {axis}: {}",
            block.seam(axis)
        );
    }
    let wall = organtex::synth::exemplar::Exemplar::load(
        &root().join("database/build/layered-wall/layers.png"),
        None,
        None,
    )
    .unwrap()
    .with_height(64)
    .unwrap();
    let layers = organtex::synth::block::layered::measure_layered(&block, &wall, 4);
    assert!(layers.rows_rms <= 8.0, "{layers:?}");
    // And the wall as tetrahedra (tet_mesh = true), within the proven
    // angles and 1% of the wall's surface.
    let t = interior
        .tet_mesh
        .as_ref()
        .expect("the scene asks for a tet mesh");
    assert_eq!(t.file, std::path::Path::new("interior/uterus.vtk"));
    let tets = organtex::tetra::io::read_vtk(&out.path().join(&t.file)).unwrap();
    assert_eq!((tets.num_vertices(), tets.num_tets()), (t.vertices, t.tets));
    let q = tets.quality();
    assert!(q.min_dihedral >= organtex::tetra::MIN_DIHEDRAL, "{q:?}");
    assert!(q.max_dihedral <= organtex::tetra::MAX_DIHEDRAL, "{q:?}");
    assert!(q.min_volume > 0.0);
    assert!(t.hausdorff_relative.is_some_and(|h| h <= 0.01), "{t:?}");
    // And lapped through it, layered from the serosa to the cavity: the
    // model reads back over the same tets, every tet with a layer, and a
    // cut through the wall is coloured from it.
    let l = interior.lst.as_ref().expect("the scene asks for an LST");
    assert_eq!(
        (l.file.as_path(), l.kind.as_str()),
        (std::path::Path::new("interior/uterus.lst"), "1b")
    );
    let model = organtex::solid::lst::LstModel::read(&out.path().join(&l.file)).unwrap();
    assert_eq!(model.mesh.tets, tets.tets);
    assert!((0..model.mesh.num_tets()).all(|t| !model.layers_of(t).is_empty()));
    // Each myoma a region of whorled fibres (1a, splotch masks) inside the
    // layered wall: exactly the regions' tets hold splotch layers.
    let regions: Vec<(&str, &str)> = l
        .regions
        .iter()
        .map(|r| (r.facet.as_str(), r.kind.as_str()))
        .collect();
    assert_eq!(regions, [("myoma-front", "1a"), ("myoma-back", "1a")]);
    assert!(
        l.regions
            .iter()
            .all(|r| r.tets > 100 && r.stats.patches > 0),
        "{:?}",
        l.regions
    );
    let fibrous = (0..model.mesh.num_tets())
        .filter(|&t| {
            model
                .layers_of(t)
                .iter()
                .any(|l| l.mask == organtex::solid::lst::MaskKind::Splotch)
        })
        .count();
    assert_eq!(fibrous, l.regions.iter().map(|r| r.tets).sum::<usize>());
    let cut = organtex::tetra::march::plane_cut(&model.mesh, glam::DVec3::X, 0.0);
    let lapped = organtex::solid::lst::LstInterior::new(model.into(), block.into()).unwrap();
    assert!(cut.triangles.len() > 1000, "{}", cut.triangles.len());
    assert_eq!(lapped.cut_colours(&cut).len(), cut.positions.len());
    let facets: Vec<&str> = r.facets.iter().map(|f| f.facet.facet.as_str()).collect();
    assert_eq!(
        facets,
        ["wall", "myoma-front", "myoma-back", "polyp", "serosa"]
    );
    for f in &r.facets {
        assert_eq!(f.facet.metrics.flips, 0, "{}", f.facet.facet);
        assert!(f.facet.metrics.conf_mean < 1.1, "{}", f.facet.facet);
    }
    assert!(
        r.facets.iter().skip(1).all(|f| f.facet.ring_faces > 0),
        "later facets have rings"
    );
    assert!(
        r.facets[0].facet.band_faces > 0,
        "the wall's seams have bands"
    );
    assert_hidden(r, "default scene");

    let (json, _) = glb_chunks(&baked.glb);
    let nodes: Vec<&str> = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        nodes,
        [
            "uterus/wall",
            "uterus/myoma-front",
            "uterus/myoma-back",
            "uterus/polyp",
            "uterus/serosa",
            "scope",
            "camera 1",
            "camera 2"
        ]
    );
    // The scene's cameras, the first carrying the scope's spot light, and
    // the wet film as a clear coat on every surface tissue (issue 39).
    assert_eq!(json["cameras"].as_array().unwrap().len(), 3);
    let scope = &json["nodes"][5];
    assert_eq!(scope["camera"], 0);
    assert_eq!(scope["extensions"]["KHR_lights_punctual"]["light"], 0);
    let light = &json["extensions"]["KHR_lights_punctual"]["lights"][0];
    assert_eq!(light["type"], "spot");
    assert!(light["intensity"].as_f64().unwrap() > 0.0);
    let materials = json["materials"].as_array().unwrap();
    assert!(materials.iter().all(|m| {
        m["extensions"]["KHR_materials_clearcoat"]["clearcoatFactor"].as_f64() > Some(0.0)
    }));
    // Where a tissue has relief, the film has it too, sharper, through the
    // same normal map and texture transform.
    let mut relief = 0;
    for m in materials {
        let Some(scale) = m["normalTexture"]["scale"].as_f64() else {
            continue;
        };
        let film = &m["extensions"]["KHR_materials_clearcoat"]["clearcoatNormalTexture"];
        assert_eq!(film["index"], m["normalTexture"]["index"], "{}", m["name"]);
        let ratio = film["scale"].as_f64().unwrap() / scale;
        assert!(
            (ratio - organtex::scene::draw::FILM_RELIEF).abs() < 1e-6,
            "{ratio}"
        );
        assert_eq!(
            film["extensions"]["KHR_texture_transform"],
            m["normalTexture"]["extensions"]["KHR_texture_transform"]
        );
        relief += 1;
    }
    assert!(relief > 0, "some tissue has relief");
    for used in [
        "KHR_lights_punctual",
        "KHR_materials_clearcoat",
        "KHR_texture_transform",
    ] {
        assert!(
            json["extensionsUsed"]
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e == used),
            "{used}"
        );
    }
    assert!(materials.iter().any(|m| m["alphaMode"] == "BLEND"));
    // The uterine wall is a closed solid: its back faces are never seen,
    // so engines may cull them.
    assert!(
        materials.iter().all(|m| m["doubleSided"] == false),
        "a closed organ is single-sided"
    );
    assert!(
        materials.iter().any(|m| m["normalTexture"].is_object()),
        "bump gives a normal map"
    );
    for mesh in json["meshes"].as_array().unwrap() {
        for p in mesh["primitives"].as_array().unwrap() {
            let m = &materials[p["material"].as_u64().unwrap() as usize];
            if m["alphaMode"] == "BLEND" {
                assert!(
                    p["attributes"]["COLOR_0"].is_number(),
                    "blend layers carry vertex alpha"
                );
            }
            if m["normalTexture"].is_object() {
                assert!(
                    p["attributes"]["TANGENT"].is_number(),
                    "normal maps come with tangents"
                );
            }
        }
    }
    let preview = image::open(
        baked
            .preview
            .as_ref()
            .expect("a GPU adapter drew the preview"),
    )
    .unwrap();
    assert_eq!((preview.width(), preview.height()), (960, 720));
}

#[test]
fn atlases_have_no_overlapping_charts_and_hide_seams_and_borders() {
    let out = tempfile::tempdir().unwrap();
    let opts = BakeOptions {
        atlas: Some(2048),
        ..BakeOptions::default()
    };
    let baked = bake(&default_scene(), out.path(), &opts, &Silent).unwrap();
    for f in &baked.report.facets {
        assert_eq!(
            f.facet.atlas_overlaps,
            Some(0),
            "{} overlaps in its atlas",
            f.facet.facet
        );
        assert_eq!(f.facet.metrics.flips, 0);
        // Each atlas as wide and tall as its charts, at one density: most
        // of its texels are the facet's (a square atlas round the wall's
        // chart used 27%).
        let [w, h] = f.atlas.unwrap();
        assert!(w.max(h) <= 2048, "{} atlas {w}x{h}", f.facet.facet);
        let used = f.atlas_texel_use.unwrap();
        assert!(
            used >= 0.45,
            "{} uses {used:.2} of its atlas",
            f.facet.facet
        );
    }
    // The texel density is set by what the hysteroscope sees: the wall
    // gets the full size, the serosa (seen only through the canal) does not
    // blur it.
    let facet = |name: &str| {
        baked
            .report
            .facets
            .iter()
            .find(|f| f.facet.facet == name)
            .unwrap()
    };
    assert!(facet("wall").facet.seen > 0.9 && facet("serosa").facet.seen < 0.2);
    assert_eq!(facet("wall").atlas.unwrap().into_iter().max(), Some(2048));
    assert_hidden(&baked.report, "atlas");
    // Seam erasure joins each seam's two sides in the atlases' bilinear
    // filtering (a facet without seams has nothing to erase).
    for f in &baked.report.facets {
        match (f.facet.seam_edges, f.atlas_seam_mismatch) {
            (0, m) => assert!(m.is_none(), "{}", f.facet.facet),
            (_, Some([baked, erased])) => assert!(
                erased <= 0.6 && erased < baked,
                "{}: seams {baked:.2} apart as baked, {erased:.2} erased",
                f.facet.facet
            ),
            (_, None) => panic!("{} has seams but no erasure", f.facet.facet),
        }
    }
    let (json, _) = glb_chunks(&baked.glb);
    assert!(
        json["materials"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| m["alphaMode"] != "BLEND")
    );
    assert_eq!(
        json["images"].as_array().unwrap().len(),
        5,
        "one atlas per facet"
    );
}

/// Everything of a .glb but the texture transforms.
fn without_transforms(mut json: serde_json::Value) -> serde_json::Value {
    for m in json["materials"].as_array_mut().unwrap() {
        for slot in [
            "/pbrMetallicRoughness/baseColorTexture",
            "/normalTexture",
            "/extensions/KHR_materials_clearcoat/clearcoatNormalTexture",
        ] {
            if let Some(info) = m.pointer_mut(slot) {
                info["extensions"]["KHR_texture_transform"] = serde_json::Value::Null;
            }
        }
    }
    json
}

#[test]
fn moving_turning_or_scaling_a_texture_changes_only_its_transform() {
    let dir = tempfile::tempdir().unwrap();
    let transforms = [
        (0.0, 10.0, [0.0, 0.0]),
        (35.0, 10.0, [0.3, -0.2]),
        (-60.0, 6.5, [0.7, 0.45]),
    ];
    let mut reference: Option<(serde_json::Value, Vec<u8>)> = None;
    let mut wall_transforms = Vec::new();
    for (k, (rotation, tile, offset)) in transforms.into_iter().enumerate() {
        // Same file name, so the scene's name is the same too.
        let folder = dir.path().join(format!("t{k}"));
        std::fs::create_dir(&folder).unwrap();
        let scene = scene_file(&folder, "scene.toml", &small_scene(rotation, tile, offset));
        let out = dir.path().join(format!("layered{k}"));
        let baked = bake(&scene, &out, &BakeOptions::default(), &Silent).unwrap();
        assert_hidden(&baked.report, &format!("transform {k} layered"));
        let (json, bin) = glb_chunks(&baked.glb);
        wall_transforms.push(json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"].clone());
        // The open cavity can be seen from behind: drawn from both sides.
        assert_eq!(json["materials"][0]["doubleSided"], true);
        let stripped = without_transforms(json);
        match &reference {
            None => reference = Some((stripped, bin)),
            Some((json0, bin0)) => {
                assert!(
                    bin == *bin0,
                    "transform {k}: the binary chunk (geometry, uvs, images) changed"
                );
                assert!(
                    stripped == *json0,
                    "transform {k}: more than the transform changed"
                );
            }
        }
        // The atlas, where the transform is baked in, still hides the seams.
        let atlas = BakeOptions {
            atlas: Some(2048),
            ..BakeOptions::default()
        };
        let baked = bake(
            &scene,
            &dir.path().join(format!("atlas{k}")),
            &atlas,
            &Silent,
        )
        .unwrap();
        assert_hidden(&baked.report, &format!("transform {k} atlas"));
    }
    let rotation = |t: &serde_json::Value| t["rotation"].as_f64().unwrap();
    assert!((rotation(&wall_transforms[1]) - 35f64.to_radians()).abs() < 1e-6);
    assert!((wall_transforms[2]["scale"][0].as_f64().unwrap() - 1.0 / 6.5).abs() < 1e-6);
    assert!((wall_transforms[2]["offset"][1].as_f64().unwrap() - 0.45).abs() < 1e-6);
}

#[test]
fn a_bake_gives_the_same_bytes_on_one_or_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.toml", &small_scene(20.0, 9.0, [0.1, 0.2]));
    let run = |threads: usize, name: &str| {
        let out = dir.path().join(name);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| bake(&scene, &out, &BakeOptions::default(), &Silent).unwrap());
        (
            std::fs::read(out.join("scene.glb")).unwrap(),
            std::fs::read(out.join("preview.png")).unwrap(),
            std::fs::read(out.join("interior/uterus.nrrd")).unwrap(),
        )
    };
    assert!(
        run(1, "one") == run(2, "two"),
        "the .glb, preview or interior differs with the thread count"
    );
}

/// Cancels when the named stage begins.
struct CancelAt(&'static str, std::sync::atomic::AtomicBool);
impl Progress for CancelAt {
    fn stage(&self, name: &str, _: u64) {
        if name == self.0 {
            self.1.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    }
    fn cancelled(&self) -> bool {
        self.1.load(std::sync::atomic::Ordering::SeqCst)
    }
}

#[test]
fn a_cancelled_bake_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // The surface's stages show only where no interior runs beside them;
    // a tet mesh and an LST are made in every bake into a new folder (a
    // block may be kept beside its tissue, so "block synthesis" need not
    // run). Ctrl-C in either is a cancel, not the node's error.
    let surface_only = small_scene(0.0, 10.0, [0.0, 0.0]).replace(
        "[node.interior]\ntexture = \"ihc-glands\"\nblock_size = 5.0\n",
        "",
    );
    assert!(!surface_only.contains("[node.interior]"));
    let with_tets = small_scene(0.0, 10.0, [0.0, 0.0])
        .replace("block_size = 5.0", "block_size = 5.0\ntet_mesh = true")
        .replace("resolution = 5", "resolution = 5\nwall_thickness = 6.0")
        .replace(
            "[node.interior]",
            "[[node.facet]]\nname = \"serosa\"\ntexture = \"gastric-serosa\"\n\n[node.interior]",
        );
    let surface_scene = scene_file(dir.path(), "surface.toml", &surface_only);
    let with_lst = with_tets.replace(
        "tet_mesh = true",
        "tet_mesh = true\n[node.interior.lst]\ntype = \"0\"",
    );
    let tets_scene = scene_file(dir.path(), "s.toml", &with_tets);
    let lst_scene = scene_file(dir.path(), "lst.toml", &with_lst);
    for (stage, scene) in [
        ("visibility", &surface_scene),
        ("facets", &surface_scene),
        ("writing", &surface_scene),
        ("winding numbers", &tets_scene),
        ("pasting patches", &lst_scene),
        ("writing", &tets_scene),
    ] {
        let out = dir.path().join(format!(
            "out-{stage}-{}",
            scene.file_stem().unwrap().to_string_lossy()
        ));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("scene.glb"), b"an earlier bake").unwrap();
        let progress = CancelAt(stage, Default::default());
        let result: Result<_> = bake(scene, &out, &BakeOptions::default(), &progress);
        assert!(
            matches!(result, Err(Error::Cancelled)),
            "cancelled at {stage}: {:?}",
            result.as_ref().err()
        );
        assert_eq!(files_in(&out), ["scene.glb"], "cancelled at {stage}");
        assert_eq!(
            std::fs::read(out.join("scene.glb")).unwrap(),
            b"an earlier bake"
        );
    }
}

/// The error of baking `body` (as scene file `s.toml`), with the output
/// folder checked to be left as it was; and the scene file's path and text.
fn bake_error(body: &str) -> (String, (PathBuf, String)) {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.toml", body);
    let out = dir.path().join("out");
    let err = bake(&scene, &out, &BakeOptions::default(), &Silent)
        .expect_err("the scene is refused")
        .to_string();
    assert!(files_in(&out).is_empty(), "{err}: output written");
    let text = std::fs::read_to_string(&scene).unwrap();
    (err, (scene, text))
}

fn line_of((_, text): &(PathBuf, String), needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle in scene")
        + 1
}

/// The scene `body` is refused with an error that says `message` and
/// names the line holding `needle`.
fn assert_error_at(body: &str, message: &str, needle: &str) {
    let (err, scene) = bake_error(body);
    assert!(err.contains(message), "{err}");
    assert!(
        err.contains(&format!("line {}", line_of(&scene, needle))),
        "{err}"
    );
}

#[test]
fn bad_scenes_get_errors_naming_the_key_and_line() {
    let base = small_scene(0.0, 10.0, [0.0, 0.0]);

    // (text in the base scene, what replaces it, the error's message, a
    // needle on the line the error must name).
    let cases = [
        (
            "\"ihc-glands\"",
            "\"liver-capsule\"",
            "facet 'myoma-1' texture: 'liver-capsule' is not in the tissue database",
            "liver-capsule",
        ),
        (
            "overlap = 2.0",
            "overlap = -1.0",
            "facet 'myoma-1' overlap: must be 0 or more, not -1",
            "overlap = -1.0",
        ),
        (
            "overlap = 2.0",
            "overlap = 2.0\nmax_conformal = 0.9",
            "facet 'myoma-1' max_conformal: must be 1 or more, not 0.9",
            "max_conformal",
        ),
        (
            "bump = 1.0",
            "bump = 1.0\nshine = 2.0",
            "unknown field `shine`",
            "shine",
        ),
        (
            "interior_voxels = 16",
            "interior_voxels = 20",
            "[bake] interior_voxels: 20 is not a multiple of 16",
            "interior_voxels",
        ),
        (
            "block_size = 5.0",
            "block_size = 5.0\nmethod = \"lapped\"",
            "unknown variant `lapped`, expected one of `fnpts`, `optimize`, `stereology`, `morph`",
            "lapped",
        ),
    ];
    for (from, to, message, needle) in cases {
        assert_error_at(&base.replace(from, to), message, needle);
    }

    let missing_mesh = "[[node]]\nname = \"organ\"\nmesh = { file = \"liver.obj\" }\n[[node.facet]]\nname = \"*\"\ntexture = \"colon-mucosa\"\n";
    let (err, _) = bake_error(missing_mesh);
    assert!(
        err.contains("line 4: node 'organ': mesh.file:") && err.contains("liver.obj not found"),
        "{err}"
    );

    let (err, scene) = bake_error(
        &base
            .replace("radius = 7.0", "radius = 12.0")
            .replace("height = 4.0", "height = 15.0"),
    );
    assert!(
        err.contains("mesh.uterine_cavity.myoma[0].height")
            && err.contains("larger than the cavity"),
        "{err}"
    );
    assert!(err.contains(&scene.0.display().to_string()), "{err}");

    let (err, _) = bake_error(&format!("include = [\"s.toml\"]\n{base}"));
    assert!(err.contains("include: the scene includes itself"), "{err}");

    let (err, _) = bake_error(&base.replace("name = \"myoma-1\"", "name = \"myoma-7\""));
    assert!(
        err.contains("facet 'myoma-7' is not a facet of the mesh (it has: wall, myoma-1)"),
        "{err}"
    );
}

#[test]
fn the_scene_chooses_how_its_interior_is_synthesised() {
    let dir = tempfile::tempdir().unwrap();
    let base = small_scene(0.0, 10.0, [0.0, 0.0]);
    let mut blocks = Vec::new();
    for (k, method) in ["", "method = \"fnpts\"", "method = \"optimize\""]
        .into_iter()
        .enumerate()
    {
        let body = base.replace("block_size = 5.0", &format!("block_size = 5.0\n{method}"));
        let scene = scene_file(dir.path(), &format!("s{k}.toml"), &body);
        let out = dir.path().join(format!("out{k}"));
        let baked = bake(&scene, &out, &BakeOptions::default(), &Silent).unwrap();
        let interior = &baked.report.interiors[0];
        let block = Volume::read_nrrd(&out.join(&interior.file)).unwrap();
        for axis in 0..3 {
            assert!(block.seam(axis) <= 1.15, "{method}: axis {axis}");
        }
        blocks.push((interior.method, block.voxels));
    }
    // FNPTS by default; the method named is the one run.
    assert_eq!(blocks[0].0, InteriorMethod::Fnpts);
    assert_eq!(blocks[1], blocks[0]);
    assert_eq!(blocks[2].0, InteriorMethod::Optimize);
    assert_ne!(blocks[2].1, blocks[0].1);
    // A layered block needs a tissue with a layered exemplar.
    let (err, _) =
        bake_error(&base.replace("block_size = 5.0", "block_size = 5.0\nmethod = \"layered\""));
    assert!(
        err.contains("tissue 'ihc-glands' has no \"layers\" output"),
        "{err}"
    );
}

#[test]
fn a_scene_interior_can_be_particles_from_stereology() {
    // A photograph of a section: dark discs 3-6 px across on a light
    // binder, 1/4 of its area, beside the scene file.
    let dir = tempfile::tempdir().unwrap();
    let side = 192u32;
    let mut photo = image::RgbImage::from_pixel(side, side, image::Rgb([225, 190, 200]));
    for k in 0..400u32 {
        let (cx, cy) = (
            (k * 97 % side) as f64,
            (k * 61 % side + k / 16) as f64 % side as f64,
        );
        let r = 1.5 + (k % 4) as f64 * 0.5;
        for y in 0..side {
            for x in 0..side {
                if (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) < r {
                    photo.put_pixel(x, y, image::Rgb([110, 40, 120]));
                }
            }
        }
    }
    photo.save(dir.path().join("section.png")).unwrap();
    let body = small_scene(0.0, 10.0, [0.0, 0.0]).replace(
        "block_size = 5.0",
        "block_size = 5.0\nmethod = \"stereology\"\nphotographs = [\"section.png\"]",
    );
    let scene = scene_file(dir.path(), "s.toml", &body);
    let out = dir.path().join("out");
    let baked = bake(&scene, &out, &BakeOptions::default(), &Silent).unwrap();
    let interior = &baked.report.interiors[0];
    assert_eq!(interior.method, InteriorMethod::Stereology);
    let block = Volume::read_nrrd(&out.join(&interior.file)).unwrap();
    assert_eq!(block.size, [16; 3]);
    // The particles' share of the block is the photograph's, within 10%
    // relative, and the block still tiles.
    let dark = |c: &[u8; 3]| (c[0] as u32 + c[1] as u32 + c[2] as u32) < 3 * 150;
    let photo_share = photo.pixels().filter(|p| dark(&p.0)).count() as f64 / (side * side) as f64;
    let block_share =
        block.voxels.iter().filter(|c| dark(c)).count() as f64 / block.voxels.len() as f64;
    assert!(
        (block_share / photo_share - 1.0).abs() < 0.1,
        "particles {block_share:.3} of the block, {photo_share:.3} of the photograph"
    );
    for axis in 0..3 {
        assert!(block.seam(axis) <= 1.15, "axis {axis}");
    }
    // A photograph that is not there is named.
    let missing = scene_file(
        dir.path(),
        "m.toml",
        &body.replace("section.png", "gone.png"),
    );
    let err = bake(
        &missing,
        &dir.path().join("out2"),
        &BakeOptions::default(),
        &Silent,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("gone.png"), "{err}");
}

#[test]
fn a_facet_can_ask_for_less_stretch_and_gets_it_with_more_seams() {
    let dir = tempfile::tempdir().unwrap();
    let base = small_scene(0.0, 10.0, [0.0, 0.0]);
    let wall = |body: &str, name: &str| {
        let baked = bake_in(dir.path(), name, body);
        let line = baked.report.facets.iter().find(|f| f.facet.facet == "wall");
        line.unwrap().facet.clone()
    };
    let default = wall(&base, "default");
    let asked = default.metrics.area_log * 0.8;
    let tight = wall(
        &base.replace("bump = 1.0", &format!("bump = 1.0\nmax_stretch = {asked}")),
        "tight",
    );
    assert!(
        tight.metrics.area_log <= asked && tight.seam_length > default.seam_length,
        "asked for area_log {asked}: {} with seams {} (default {} with seams {})",
        tight.metrics.area_log,
        tight.seam_length,
        default.metrics.area_log,
        default.seam_length
    );
}

#[test]
fn includes_bring_in_cameras_and_nodes() {
    let dir = tempfile::tempdir().unwrap();
    scene_file(dir.path(), "part.toml", &small_scene(0.0, 10.0, [0.0, 0.0]));
    let main = scene_file(
        dir.path(),
        "main.toml",
        "name = \"combined\"\ninclude = [\"part.toml\"]\n",
    );
    let spec = organtex::scene::file::load(&main).unwrap();
    assert_eq!(spec.name, "combined");
    assert_eq!(spec.cameras.len(), 1);
    assert_eq!(spec.nodes.len(), 1);
    assert_eq!(spec.nodes[0].facets.len(), 2);
}

#[test]
fn a_scene_interior_can_be_morphed_from_photographed_cuts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let scene = root().join("scenes").join("myoma_cuts.toml");
    let baked = bake(&scene, &out, &BakeOptions::default(), &Silent).unwrap();
    let line = &baked.report.interiors[0];
    assert_eq!(line.method, InteriorMethod::Morph);
    let m = line.morph.as_ref().expect("a morph line");
    assert_eq!((m.exemplars, m.regions), (2, 3));

    // The copied cuts are the morph: on the second cut's plane (y = 12)
    // the organ shows that photograph, and the block holds the morph's
    // colour at each voxel centre, placed as the report says.
    let spec = organtex::scene::file::load(&scene).unwrap();
    let organtex::scene::file::MeshSpec::UterineCavity(params) = &spec.nodes[0].mesh else {
        panic!("myoma_cuts generates its uterus");
    };
    let mesh = uterus::generate(params).unwrap();
    let topology = Topology::build(&mesh).unwrap();
    let morph = organtex::solid::morph::Morph::read(
        &mesh,
        &topology,
        &out.join(&m.sections),
        Default::default(),
        &Silent,
    )
    .unwrap();
    use organtex::solid::Interior;
    let photo = image::open(root().join("scenes/myoma_cuts/he_nests.jpg"))
        .unwrap()
        .to_rgb8();
    let (origin, u, v) = (
        DVec3::new(-25.6, 12.0, -1.5),
        DVec3::new(0.1, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 0.1),
    );
    let pixels: Vec<(u32, u32)> = (8..504)
        .step_by(7)
        .flat_map(|j| (8..504).step_by(5).map(move |i| (i, j)))
        .collect();
    let points: Vec<DVec3> = pixels
        .iter()
        .map(|&(i, j)| origin + u * (i as f64 + 0.5) + v * (j as f64 + 0.5))
        .collect();
    let got = morph.colours(&points);
    for (&(i, j), c) in pixels.iter().zip(&got) {
        let want = photo.get_pixel(i, j).0;
        assert!(
            (0..3).all(|k| c[k].abs_diff(want[k]) <= 2),
            "pixel ({i}, {j}): {c:?}, the photograph {want:?}"
        );
    }
    let block = Volume::read_nrrd(&out.join(&line.file)).unwrap();
    let corner = DVec3::from_array(m.block_origin);
    for i in (0..block.voxels.len()).step_by(997) {
        let n = block.size[0];
        let centre = corner
            + DVec3::new(
                (i % n) as f64 + 0.5,
                ((i / n) % n) as f64 + 0.5,
                (i / (n * n)) as f64 + 0.5,
            ) * line.voxel_size;
        assert_eq!(block.voxels[i], morph.colour(centre), "voxel {i}");
    }

    // A plane through the cavity meets the wall in a ring (here cut open by
    // the cervical canal into two pieces): refused, named, nothing written.
    let ring = dir.path().join("ring");
    std::fs::create_dir_all(&ring).unwrap();
    let text = std::fs::read_to_string(root().join("scenes/myoma_cuts/sections.toml"))
        .unwrap()
        .replace("../../database/sources/ihc.png", "ihc.png")
        .replace("origin = [-25.6, 8.0, -1.5]", "origin = [-25.6, 0.0, -1.5]");
    std::fs::copy(
        root().join("database/sources/ihc.png"),
        ring.join("ihc.png"),
    )
    .unwrap();
    std::fs::copy(
        root().join("scenes/myoma_cuts/he_nests.jpg"),
        ring.join("he_nests.jpg"),
    )
    .unwrap();
    std::fs::write(ring.join("sections.toml"), text).unwrap();
    let body = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("myoma_cuts/sections.toml", "ring/sections.toml");
    let scene = scene_file(dir.path(), "ring.toml", &body);
    let out = dir.path().join("out-ring");
    let err = bake(&scene, &out, &BakeOptions::default(), &Silent)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("node 'uterus'")
            && err.contains("exemplar 1 (ihc.png)")
            && err.contains("2 pieces")
            && err.contains("disk"),
        "{err}"
    );
    assert!(files_in(&out).is_empty(), "{err}: output written");

    // A morph names its sections; sections go with a morph alone.
    for (from, to, message) in [
        (
            "sections = \"ring/sections.toml\"",
            "",
            "interior sections: method = \"morph\" needs sections",
        ),
        (
            "method = \"morph\"",
            "texture = \"ihc-glands\"",
            "interior sections: are morphed by method = \"morph\" alone",
        ),
        ("ring/sections.toml", "gone.toml", "gone.toml not found"),
    ] {
        let (err, _) = bake_error(&body.replace(from, to));
        assert!(err.contains(message), "{err}");
    }
}

#[test]
fn a_bake_profiles_every_stage_and_the_cli_prints_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(
        dir.path(),
        "small.toml",
        &small_scene(0.0, 10.0, [0.0, 0.0]),
    );
    let out = dir.path().join("out");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(["bake", "--profile", "-o"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let timings = &report["timings"];
    let stages = timings["stages"].as_array().unwrap();
    // A block kept beside its tissue by an earlier bake is taken, not
    // made: its row says so.
    let has = |stage: &str, item: &str| {
        stages.iter().any(|s| {
            (s["stage"] == stage
                || (stage == "interior block" && s["stage"] == "interior block kept"))
                && s["item"] == item
                && s["seconds"].as_f64() >= Some(0.0)
        })
    };
    for (stage, item) in [
        ("tissues", "database"),
        ("mesh", "uterus"),
        ("visibility", "uterus"),
        ("unwraps and bands", "uterus"),
        ("unwrap", "uterus/wall"),
        ("unwrap", "uterus/myoma-1"),
        ("blending", "uterus"),
        ("interior block", "uterus"),
        ("contrast", ""),
        ("glb", ""),
        ("preview", ""),
    ] {
        assert!(has(stage, item), "no '{stage}' on '{item}' in {stages:?}");
    }
    // The unwraps run side by side; the stages one after another, within
    // the bake's time.
    assert!(
        stages
            .iter()
            .filter(|s| s["stage"] == "unwrap")
            .all(|s| s["parallel"] == true)
    );
    let sequential: f64 = stages
        .iter()
        .filter(|s| s["parallel"] != true)
        .map(|s| s["seconds"].as_f64().unwrap())
        .sum();
    assert!(sequential <= timings["total_s"].as_f64().unwrap());
    // The table: a row per stage and facet.
    assert!(stdout.contains("where the time went"), "{stdout}");
    for row in [
        "unwrap (in parallel)",
        "uterus/myoma-1",
        "interior block",
        "preview",
    ] {
        assert!(stdout.contains(row), "no '{row}' row in\n{stdout}");
    }
}

#[test]
fn a_second_bake_keeps_the_interior_when_only_a_tissue_changed() {
    let dir = tempfile::tempdir().unwrap();
    let with_tet_mesh = |wall: &str, block_size: f64| {
        small_scene(0.0, 10.0, [0.0, 0.0])
            .replace(
                "texture = \"fundus-tissue\"",
                &format!("texture = \"{wall}\""),
            )
            .replace(
                "block_size = 5.0",
                &format!("block_size = {block_size}\ntet_mesh = true"),
            )
            // A solid wall, so there is an inside to fill.
            .replace("resolution = 5", "resolution = 5\nwall_thickness = 6.0")
            .replace(
                "[node.interior]",
                "[[node.facet]]\nname = \"serosa\"\ntexture = \"gastric-serosa\"\n\n[node.interior]",
            )
    };
    let stage_of = |baked: &Baked| -> Vec<String> {
        baked
            .report
            .timings
            .stages
            .iter()
            .map(|s| s.stage.clone())
            .collect()
    };
    let files = ["scene.glb", "interior/uterus.nrrd", "interior/uterus.vtk"];
    // Same file name in two folders, so the scene's name is the same too.
    for d in ["a", "b"] {
        std::fs::create_dir(dir.path().join(d)).unwrap();
    }
    let bake_into = |d: &str, body: &str| bake_in(&dir.path().join(d), "scene", body);
    let first = bake_into("a", &with_tet_mesh("fundus-tissue", 5.0));
    assert!(!stage_of(&first).contains(&"interior reused".to_string()));
    assert!(stage_of(&first).contains(&"tet mesh".to_string()));

    // Only a facet's tissue changes: the interior is kept, and every file
    // is what a bake from scratch makes.
    let changed = with_tet_mesh("colon-mucosa", 5.0);
    let again = bake_into("a", &changed);
    let stages = stage_of(&again);
    assert!(
        stages.contains(&"interior reused".to_string()),
        "{stages:?}"
    );
    assert!(!stages.contains(&"tet mesh".to_string()), "{stages:?}");
    // So are the unwraps (issue 38): every facet's is taken, none made.
    assert!(stages.contains(&"unwrap reused".to_string()), "{stages:?}");
    assert!(!stages.contains(&"unwrap".to_string()), "{stages:?}");
    let fresh = bake_into("b", &changed);
    assert!(!stage_of(&fresh).contains(&"interior reused".to_string()));
    assert!(!stage_of(&fresh).contains(&"unwrap reused".to_string()));
    // The facets' figures are those of a bake from scratch.
    for (a, b) in again.report.facets.iter().zip(&fresh.report.facets) {
        let (a, b) = (&a.facet, &b.facet);
        assert_eq!(a.metrics, b.metrics);
        assert_eq!(a.flattening, b.flattening);
        assert_eq!(
            (a.seam_edges, a.charts, a.seen),
            (b.seam_edges, b.charts, b.seen)
        );
    }
    for f in files {
        assert!(
            std::fs::read(dir.path().join("a/scene").join(f)).unwrap()
                == std::fs::read(dir.path().join("b/scene").join(f)).unwrap(),
            "{f} differs from a bake from scratch"
        );
    }
    assert_eq!(
        again.report.interiors[0].tet_mesh.as_ref().unwrap().tets,
        fresh.report.interiors[0].tet_mesh.as_ref().unwrap().tets
    );

    // The interior's own settings change: it is made again; the
    // unwraps, whose inputs did not change, are still taken.
    let other = bake_into("a", &with_tet_mesh("colon-mucosa", 6.0));
    assert!(!stage_of(&other).contains(&"interior reused".to_string()));
    assert!(stage_of(&other).contains(&"unwrap reused".to_string()));
    assert!(other.report.interiors[0].voxel_size > again.report.interiors[0].voxel_size);

    // A folder whose key is gone (a bake cut short) makes it again.
    std::fs::remove_file(dir.path().join("a/scene/interior/uterus.key")).unwrap();
    let remade = bake_into("a", &with_tet_mesh("colon-mucosa", 6.0));
    assert!(!stage_of(&remade).contains(&"interior reused".to_string()));
    assert!(dir.path().join("a/scene/interior/uterus.key").is_file());

    // A facet's unwrap settings change: that facet is unwrapped again, the
    // other kept.
    let stretched = with_tet_mesh("colon-mucosa", 6.0).replace(
        "name = \"serosa\"\n",
        "name = \"serosa\"\nmax_stretch = 0.2\n",
    );
    assert_ne!(stretched, with_tet_mesh("colon-mucosa", 6.0));
    let restretched = bake_into("a", &stretched);
    let spans = &restretched.report.timings.stages;
    let made: Vec<&str> = spans
        .iter()
        .filter(|s| s.stage == "unwrap")
        .map(|s| s.item.as_str())
        .collect();
    assert_eq!(made, ["uterus/serosa"], "{spans:?}");
}

#[test]
fn a_bake_into_a_new_folder_takes_the_block_kept_beside_its_tissue() {
    // A block size no other test asks for, so no other test keeps or
    // takes this block while this one runs.
    let body =
        small_scene(0.0, 10.0, [0.0, 0.0]).replace("interior_voxels = 16", "interior_voxels = 48");
    let blocks = root().join("database/build/ihc-glands/blocks");
    let ours = || -> Vec<PathBuf> {
        std::fs::read_dir(&blocks)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.file_name().unwrap().to_string_lossy().contains("-48-0-"))
            .collect()
    };
    for p in ours() {
        std::fs::remove_file(p).unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let stages = |b: &Baked| -> Vec<String> {
        b.report
            .timings
            .stages
            .iter()
            .map(|s| s.stage.clone())
            .collect()
    };
    let block = |d: &str| std::fs::read(dir.path().join(d).join("interior/uterus.nrrd")).unwrap();
    let bake_into = |d: &str| {
        std::fs::create_dir(dir.path().join(d)).unwrap();
        bake_in(&dir.path().join(d), "scene", &body)
    };
    let first = bake_into("a");
    assert!(stages(&first).contains(&"interior block".to_string()));
    assert_eq!(ours().len(), 1, "the block is kept beside its tissue");
    // Another folder: the block is taken, the same bytes.
    let second = bake_into("b");
    assert!(
        stages(&second).contains(&"interior block kept".to_string()),
        "{:?}",
        stages(&second)
    );
    assert_eq!(block("a/scene"), block("b/scene"));
    // A kept file cut short is not taken: the block is made again.
    let kept = ours().pop().unwrap();
    let bytes = std::fs::read(&kept).unwrap();
    std::fs::write(&kept, &bytes[..bytes.len() / 2]).unwrap();
    let third = bake_into("c");
    assert!(
        stages(&third).contains(&"interior block".to_string()),
        "{:?}",
        stages(&third)
    );
    assert_eq!(block("a/scene"), block("c/scene"));
    assert_eq!(
        std::fs::read(&kept).unwrap(),
        bytes,
        "made again and kept whole"
    );
}
