//! Plane sections and cut texturing (organtex::solid) on real meshes: the
//! section is closed, lies on the mesh, is triangulated exactly (holes
//! left out), and is coloured as the block samples.

mod common;
use common::organtex;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::DVec3;
use organtex::mesh::shapes::torus;
use organtex::mesh::{Topology, TriMesh, io};
use organtex::solid::{
    Block, Placement, Plane, SAMPLE_BLOCK_WGSL, Section, plane_section, render_section,
    sample_colours, texture_coordinates, texture_surface,
};
use organtex::synth::volume::Volume;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn load(name: &str) -> (TriMesh, Topology) {
    let mesh = io::read(&data(name)).unwrap();
    let topo = Topology::build(&mesh).unwrap();
    (mesh, topo)
}

fn plane(n: [f64; 3], d: f64) -> Plane {
    Plane::new(DVec3::from(n), d).unwrap()
}

/// A block of hashed voxel colours, different along every axis.
fn block(size: [usize; 3]) -> Volume {
    let count = size[0] * size[1] * size[2];
    Volume {
        size,
        spacing: 0.5,
        voxels: (0..count as u32)
            .map(|i| {
                let h = i.wrapping_mul(2_654_435_761).to_le_bytes();
                [h[1], h[2], h[3]]
            })
            .collect(),
    }
}

/// Planes through the bunny: through the middle of its bounds across each
/// axis and obliquely, and through one of its vertices exactly.
fn bunny_planes(mesh: &TriMesh) -> Vec<Plane> {
    let (lo, hi) = mesh.bounding_box().unwrap();
    let mid = (lo + hi) / 2.0;
    let mut planes: Vec<Plane> = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(0.3, 0.2, 1.0)]
        .into_iter()
        .map(|n| Plane::new(n, n.dot(mid)).unwrap())
        .collect();
    let v = mesh.positions[mesh.num_vertices() / 2];
    planes.push(plane([0.0, 0.0, 1.0], v.z));
    planes.push(plane([1.0, 0.0, 0.0], v.x));
    planes
}

fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
    (p - (a + (b - a) * t)).length()
}

/// Every boundary vertex on the plane and on the mesh edge it names.
fn assert_on_mesh(mesh: &TriMesh, topo: &Topology, plane: &Plane, s: &Section) {
    let scale = mesh
        .bounding_box()
        .map_or(1.0, |(lo, hi)| (hi - lo).max_element());
    for l in &s.boundary {
        for &i in l {
            let p = s.positions[i as usize];
            let [a, b] = topo.edge_vertices(s.edges[i as usize]);
            let d = distance_to_segment(p, mesh.positions[a.idx()], mesh.positions[b.idx()]);
            assert!(d < 1e-9 * scale, "vertex {i} is {d} off its edge");
            let off = plane.side(p).abs() / plane.normal.length();
            assert!(off < 1e-9 * scale, "vertex {i} is {off} off the plane");
        }
    }
}

/// Every loop closed and simple, every vertex on one loop once, and the
/// triangulation's border is exactly the loops, each edge once.
fn assert_closed(s: &Section) {
    let mut seen = vec![0; s.positions.len()];
    let mut loop_edges = HashMap::new();
    for l in &s.boundary {
        assert!(l.len() >= 3, "a loop of {} vertices", l.len());
        for (k, &a) in l.iter().enumerate() {
            seen[a as usize] += 1;
            let b = l[(k + 1) % l.len()];
            *loop_edges.entry((a, b)).or_insert(0) += 1;
        }
    }
    assert!(
        seen.iter().all(|&c| c == 1),
        "a vertex off or twice on loops"
    );
    assert!(
        loop_edges.values().all(|&c| c == 1),
        "a loop edge used twice"
    );
    let mut tri_edges: HashMap<(u32, u32), i32> = HashMap::new();
    for t in &s.triangles {
        for k in 0..3 {
            *tri_edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let border: HashMap<(u32, u32), i32> = tri_edges
        .iter()
        .filter(|&(&(a, b), _)| !tri_edges.contains_key(&(b, a)))
        .map(|(&e, &c)| (e, c))
        .collect();
    assert_eq!(
        border, loop_edges,
        "triangulation border differs from the loops"
    );
}

fn assert_area_exact(s: &Section) {
    let (a, p) = (s.area(), s.polygon_area());
    assert!(p > 0.0);
    assert!(
        ((a - p) / p).abs() < 1e-6,
        "triangulated {a} vs polygon {p}"
    );
}

#[test]
fn bunny_sections_lie_on_the_surface() {
    let (mesh, topo) = load("bunny.obj");
    for p in bunny_planes(&mesh) {
        let s = plane_section(&mesh, &topo, p).unwrap();
        assert!(!s.is_empty(), "{p:?}");
        assert_on_mesh(&mesh, &topo, &p, &s);
    }
}

#[test]
fn bunny_sections_are_closed() {
    let (mesh, topo) = load("bunny.obj");
    for p in bunny_planes(&mesh) {
        assert_closed(&plane_section(&mesh, &topo, p).unwrap());
    }
}

#[test]
fn triangulated_area_is_the_polygon_area() {
    let (mesh, topo) = load("bunny.obj");
    for p in bunny_planes(&mesh) {
        assert_area_exact(&plane_section(&mesh, &topo, p).unwrap());
    }
    let (cube, topo) = load("cube.obj");
    // Across the cube the faces' diagonals cross on the square's sides:
    // collinear points, kept on the border all the same.
    let s = plane_section(&cube, &topo, plane([0.0, 0.0, 1.0], 0.1)).unwrap();
    assert_closed(&s);
    assert!((s.area() - 1.0).abs() < 1e-12 && (s.polygon_area() - 1.0).abs() < 1e-12);
}

#[test]
fn a_plane_that_misses_gives_an_empty_section() {
    let (mesh, topo) = load("bunny.obj");
    let (_, hi) = mesh.bounding_box().unwrap();
    let s = plane_section(&mesh, &topo, plane([0.0, 1.0, 0.0], hi.y + 1.0)).unwrap();
    assert!(s.is_empty() && s.boundary.is_empty() && s.positions.is_empty());
    assert_eq!(s.area(), 0.0);
}

#[test]
fn a_mesh_with_holes_is_refused() {
    let (mesh, topo) = load("bunny10k_textured.obj");
    let e = plane_section(&mesh, &topo, plane([0.0, 0.0, 1.0], 0.0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the mesh is not closed (5 boundary loops); a section needs a closed organ"),
        "{e}"
    );
}

#[test]
fn planes_through_vertices_still_close() {
    let (cube, topo) = load("cube.obj");
    // Through three corners and the face diagonals between them: the
    // triangle with sides sqrt(2).
    let p = plane([1.0, 1.0, 1.0], 0.5);
    let s = plane_section(&cube, &topo, p).unwrap();
    assert_closed(&s);
    assert_on_mesh(&cube, &topo, &p, &s);
    assert_eq!(s.boundary.len(), 1);
    assert_eq!(s.boundary[0].len(), 3, "{:?}", s.positions);
    assert!((s.area() - 3f64.sqrt() / 2.0).abs() < 1e-12, "{}", s.area());
    // Through the top face: the face itself, the limit of cuts below it.
    let s = plane_section(&cube, &topo, plane([0.0, 0.0, 1.0], 0.5)).unwrap();
    assert_closed(&s);
    assert_eq!(s.boundary[0].len(), 4);
    assert!((s.area() - 1.0).abs() < 1e-12);
    // Through the bottom face the cut lies just below the cube.
    let s = plane_section(&cube, &topo, plane([0.0, 0.0, 1.0], -0.5)).unwrap();
    assert!(s.is_empty());
    // Through the middle, across the faces' diagonals: a hexagon.
    let s = plane_section(&cube, &topo, plane([1.0, 1.0, 1.0], 0.0)).unwrap();
    assert_closed(&s);
    assert_eq!(s.boundary[0].len(), 6);
    assert!((s.area() - 3.0 * 3f64.sqrt() / 4.0).abs() < 1e-12);
}

#[test]
fn planes_through_many_vertices_close_and_triangulate_exactly() {
    let (mesh, topo) = load("bunny.obj");
    let torus = torus(2.0, 0.75, 48, 16);
    let torus_topo = Topology::build(&torus).unwrap();
    let n = mesh.num_vertices();
    for k in 0..30 {
        let v = mesh.positions[(k * 7919) % n];
        let axis = k % 3;
        let mut normal = [0.0; 3];
        normal[axis] = 1.0;
        let p = plane(normal, v[axis]);
        let s = plane_section(&mesh, &topo, p).unwrap();
        assert_closed(&s);
        assert_on_mesh(&mesh, &topo, &p, &s);
        assert_area_exact(&s);
    }
    // The torus's equator runs through a ring of vertices on each wall.
    for p in [plane([0.0, 0.0, 1.0], 0.0), plane([0.0, 1.0, 0.0], 0.0)] {
        let s = plane_section(&torus, &torus_topo, p).unwrap();
        assert_closed(&s);
        assert_on_mesh(&torus, &torus_topo, &p, &s);
        assert_area_exact(&s);
        assert_eq!(s.boundary.len(), 2);
    }
}

#[test]
fn a_torus_section_leaves_its_hole_out() {
    let (major, minor) = (2.0, 0.75);
    let mesh = torus(major, minor, 64, 24);
    let topo = Topology::build(&mesh).unwrap();
    let p = plane([0.0, 0.0, 1.0], 0.1);
    let s = plane_section(&mesh, &topo, p).unwrap();
    assert_closed(&s);
    assert_on_mesh(&mesh, &topo, &p, &s);
    assert_area_exact(&s);
    assert_eq!(s.boundary.len(), 2);
    let pts = |l: &Vec<u32>| l.iter().map(|&i| s.plane_point(i)).collect::<Vec<_>>();
    let shoelace = |q: &[glam::DVec2]| {
        (0..q.len())
            .map(|i| q[i].perp_dot(q[(i + 1) % q.len()]))
            .sum::<f64>()
            / 2.0
    };
    let (outer, hole) = (pts(&s.boundary[0]), pts(&s.boundary[1]));
    let (a_out, a_hole) = (shoelace(&outer), shoelace(&hole));
    assert!(a_out > 0.0 && a_hole < 0.0, "outer ccw, hole cw");
    assert!((s.area() - (a_out + a_hole)).abs() < 1e-9 * a_out);
    // No triangle covers the hole's centre.
    let centre = s.frame.to_2d(DVec3::new(0.0, 0.0, 0.1));
    for t in &s.triangles {
        let [a, b, c] = t.map(|i| s.plane_point(i));
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).perp_dot(centre - u) > 0.0);
        assert!(!inside, "triangle {t:?} covers the hole");
    }
    // The ring between the tube's walls, less what the polygons cut off.
    let w = (minor * minor - 0.01f64).sqrt();
    let annulus = std::f64::consts::PI * ((major + w).powi(2) - (major - w).powi(2));
    assert!(
        (s.area() / annulus - 1.0).abs() < 0.03,
        "{} vs {annulus}",
        s.area()
    );
    // Across the tube: two disks, no hole.
    let s = plane_section(&mesh, &topo, plane([1.0, 0.0, 0.0], 0.05)).unwrap();
    assert_closed(&s);
    assert_area_exact(&s);
    assert_eq!(s.boundary.len(), 2);
    assert!(s.boundary.iter().all(|l| shoelace(&pts(l)) > 0.0));
}

#[test]
fn colours_are_the_block_samples() {
    let (mesh, topo) = load("bunny.obj");
    let volume = block([16, 12, 8]);
    let placement = Placement::new(DVec3::new(-0.3, 0.1, 0.2), 0.004).unwrap();
    let s = plane_section(&mesh, &topo, bunny_planes(&mesh)[3]).unwrap();
    let colours = sample_colours(&s, &volume, &placement);
    let coords = texture_coordinates(&s.positions, &placement);
    assert_eq!(colours.len(), s.positions.len());
    for ((c, t), &p) in colours.iter().zip(&coords).zip(&s.positions) {
        let v = (p - placement.origin) / placement.scale;
        let expect = volume.sample(v.to_array()).map(|x| x.round() as u8);
        assert_eq!(*c, expect);
        for k in 0..3 {
            assert!((t[k] as f64 - v[k]).abs() <= 1e-5 * v[k].abs().max(1.0));
        }
    }
    // A cut surface is textured vertex by vertex the same way.
    let surface = texture_surface(&mesh, &volume, &placement);
    assert_eq!(surface.texcoords.len(), mesh.num_vertices());
    let v = placement.voxel(mesh.positions[7]);
    assert_eq!(
        surface.colours[7],
        volume.sample(v.to_array()).map(|x| x.round() as u8)
    );
}

#[test]
fn the_rendered_section_covers_the_section_in_block_colours() {
    let (cube, topo) = load("cube.obj");
    let s = plane_section(&cube, &topo, plane([0.0, 0.0, 1.0], 0.1)).unwrap();
    let volume = block([8, 8, 8]);
    let placement = Placement::of_volume(&volume);
    let img = render_section(
        &s,
        &Block {
            volume: &volume,
            placement,
        },
        100.0,
    )
    .unwrap();
    assert_eq!(img.image.dimensions(), (100, 100));
    let opaque = img.image.pixels().filter(|p| p[3] == 255).count();
    assert_eq!(opaque, 100 * 100, "the unit square covers every pixel");
    // Each pixel is the block at its centre's 3D point.
    for (x, y) in [(0u32, 0u32), (37, 81), (99, 99)] {
        let q = img.top_left + glam::DVec2::new(x as f64 + 0.5, -(y as f64 + 0.5)) / 100.0;
        let p = s.frame.to_3d(q);
        assert!((p.z - 0.1).abs() < 1e-12);
        let expect = volume.sample(placement.voxel(p).to_array());
        let got = img.image.get_pixel(x, y);
        for k in 0..3 {
            assert_eq!(got[k], expect[k].round() as u8);
        }
    }
    // A diamond covers about half its bounding square.
    let s = plane_section(&cube, &topo, plane([1.0, 1.0, 1.0], 0.5)).unwrap();
    let img = render_section(
        &s,
        &Block {
            volume: &volume,
            placement,
        },
        200.0,
    )
    .unwrap();
    let opaque = img.image.pixels().filter(|p| p[3] == 255).count() as f64;
    let expect = s.area() * 200.0 * 200.0;
    assert!((opaque / expect - 1.0).abs() < 0.02, "{opaque} vs {expect}");
}

#[test]
fn the_section_glb_is_a_textured_mesh() {
    let (mesh, topo) = load("bunny.obj");
    let s = plane_section(&mesh, &topo, bunny_planes(&mesh)[2]).unwrap();
    let volume = block([8, 8, 8]);
    let placement = Placement::new(DVec3::ZERO, 0.01).unwrap();
    let img = render_section(
        &s,
        &Block {
            volume: &volume,
            placement,
        },
        2000.0,
    )
    .unwrap();
    let bytes = organtex::scene::gltf::section_glb(&s, &img).unwrap();
    assert_eq!(&bytes[0..4], b"glTF");
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let prim = &json["meshes"][0]["primitives"][0];
    let count =
        |a: &serde_json::Value| json["accessors"][a.as_u64().unwrap() as usize]["count"].clone();
    assert_eq!(count(&prim["attributes"]["POSITION"]), s.positions.len());
    assert_eq!(count(&prim["indices"]), 3 * s.triangles.len());
    assert!(json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].is_object());
    assert_eq!(json["images"][0]["mimeType"], "image/png");
}

#[test]
fn the_wgsl_snippet_validates_and_matches_the_uniform() {
    let check = |src: &str| {
        let module = naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{e}"));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{e:?}"));
        module
    };
    let module = check(SAMPLE_BLOCK_WGSL);
    // Placement::uniform() is origin x, y, z then scale: 16 bytes.
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("BlockPlacement"))
        .unwrap();
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("BlockPlacement is not a struct");
    };
    assert_eq!(*span, 16);
    let offsets: Vec<u32> = members.iter().map(|m| m.offset).collect();
    assert_eq!(offsets, [0, 12]);
    assert_eq!(
        Placement::new(DVec3::new(1.0, 2.0, 3.0), 0.5)
            .unwrap()
            .uniform(),
        [1.0, 2.0, 3.0, 0.5]
    );
    // A fragment shader built on it, as a renderer would include it.
    check(&format!(
        "{SAMPLE_BLOCK_WGSL}\n\
         @fragment fn main(@location(0) p: vec3<f32>) -> @location(0) vec4<f32> {{\n\
             return vec4<f32>(block_colour(p), 1.0);\n\
         }}\n"
    ));
}

#[test]
fn the_cli_writes_a_png_and_a_glb() {
    let dir = tempfile::tempdir().unwrap();
    let nrrd = dir.path().join("block.nrrd");
    block([16, 16, 16]).write_nrrd(&nrrd).unwrap();
    let bunny = data("bunny.obj");
    for (name, size) in [("cut.png", "300"), ("cut.glb", "256")] {
        let out: PathBuf = dir.path().join(name);
        let (ok, stdout, stderr) = organtex(&[
            "section",
            bunny.to_str().unwrap(),
            "--block",
            nrrd.to_str().unwrap(),
            "--plane",
            "0.3,0.2,1,0.5",
            "--scale",
            "0.002",
            "--origin",
            "-0.1,0,0.02",
            "--resolution",
            size,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{stderr}");
        assert!(stdout.contains("boundary loops"), "{stdout}");
        check_output(&out);
    }
}

fn check_output(out: &Path) {
    let bytes = std::fs::read(out).unwrap();
    if out.extension().unwrap() == "png" {
        let img = image::load_from_memory(&bytes).unwrap().to_rgba8();
        assert_eq!(img.width().max(img.height()), 300);
        assert!(img.pixels().any(|p| p[3] == 255) && img.pixels().any(|p| p[3] == 0));
    } else {
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
            bytes.len()
        );
    }
}
