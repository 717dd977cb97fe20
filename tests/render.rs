//! The GPU renderer offscreen, on whatever adapter the machine has (in CI
//! the software one, llvmpipe, from mesa-vulkan-drivers). No adapter is a
//! failure, not a skip.

mod common;
use common::{changed_pixels, lit_pixels};
use glam::DVec3;
use organtex::progress::Silent;
use organtex::render::{CutMesh, Gpu, GpuScene, Layers, Offscreen, OrbitCamera, Renderer, View};
use organtex::scene::build::build_scene;
use organtex::scene::draw::DrawList;
use organtex::scene::file;
use organtex::solid::{Placement, Plane, plane_section};
use organtex::synth::volume::Volume;

fn repo(p: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn gpu() -> Gpu {
    Gpu::headless().expect("a GPU adapter (install mesa-vulkan-drivers)")
}

#[test]
fn the_default_scene_renders_textured_and_every_layer_toggle_shows() {
    let gpu = gpu();
    let spec = file::load(&repo("scenes/hysteroscopy_myomas.toml")).unwrap();
    let baked = build_scene(&spec, false, &Silent).unwrap();
    let list = DrawList::of(&baked, None);
    let renderer = Renderer::new(&gpu.device);
    let scene = GpuScene::new(&renderer, &gpu.device, &gpu.queue, &list).unwrap();
    let target = Offscreen::new(&gpu.device, [320, 240]);
    let camera = OrbitCamera::for_scene(&spec.cameras, scene.bounds);
    let draw = |layers: Layers| {
        let view = View {
            camera,
            layers,
            clip: None,
        };
        target.draw(&renderer, &gpu.device, &gpu.queue, &scene, &view);
        target.read(&gpu.device, &gpu.queue).unwrap()
    };
    let full = draw(Layers::default());
    let (n, _, var) = lit_pixels(&full);
    assert!(
        n > 320 * 240 / 2,
        "the organ fills the view from its camera ({n} lit pixels)"
    );
    assert!(
        var > 100.0,
        "the tissue texture shows (luminance variance {var:.1})"
    );
    for (name, layers) in [
        (
            "bump",
            Layers {
                bump: false,
                ..Layers::default()
            },
        ),
        (
            "seam blend",
            Layers {
                seam_blend: false,
                ..Layers::default()
            },
        ),
        (
            "wireframe",
            Layers {
                wireframe: true,
                ..Layers::default()
            },
        ),
        (
            "seams",
            Layers {
                seams: true,
                ..Layers::default()
            },
        ),
        (
            "distortion",
            Layers {
                heat: true,
                ..Layers::default()
            },
        ),
    ] {
        let other = draw(layers);
        let changed = changed_pixels(&full, &other);
        assert!(
            changed > 100,
            "toggling {name} changes the picture ({changed} pixels)"
        );
    }
    // Same input, same pixels.
    assert_eq!(draw(Layers::default()), full);
}

#[test]
fn a_cut_face_shows_the_interior_block() {
    let gpu = gpu();
    let mesh = organtex::mesh::io::read(&repo("tests/data/bunny.obj")).unwrap();
    let topology = organtex::mesh::Topology::build(&mesh).unwrap();
    let (lo, hi) = mesh.bounding_box().unwrap();
    let centre = (lo + hi) / 2.0;
    let section = plane_section(&mesh, &topology, Plane::new(DVec3::Z, centre.z).unwrap()).unwrap();
    assert!(!section.is_empty());
    // A block of stripes along x, so the cut must show them.
    let n = 16;
    let voxels = (0..n * n * n)
        .map(|i| {
            if (i % n) / 4 % 2 == 0 {
                [230, 60, 40]
            } else {
                [40, 60, 230]
            }
        })
        .collect();
    let volume = Volume {
        size: [n, n, n],
        spacing: 1.0,
        voxels,
    };
    let renderer = Renderer::new(&gpu.device);
    let mut scene =
        GpuScene::new(&renderer, &gpu.device, &gpu.queue, &DrawList::default()).unwrap();
    let placement = Placement::new(lo, (hi - lo).x / 4.0 / n as f64).unwrap();
    scene.set_block(&renderer, &gpu.device, &gpu.queue, &volume, &placement);
    scene.set_cut(
        &gpu.device,
        Some(&CutMesh {
            normals: vec![section.normal; section.positions.len()],
            positions: section.positions.clone(),
            triangles: section.triangles.clone(),
        }),
    );
    let mut camera = OrbitCamera::fit(lo, hi);
    camera.yaw = 0.0;
    camera.pitch = 0.0;
    let target = Offscreen::new(&gpu.device, [256, 256]);
    let view = View {
        camera,
        layers: Layers::default(),
        clip: Some((DVec3::Z, centre.z)),
    };
    target.draw(&renderer, &gpu.device, &gpu.queue, &scene, &view);
    let img = target.read(&gpu.device, &gpu.queue).unwrap();
    let reds = img
        .pixels()
        .filter(|p| p[0] > 2 * p[2] && p[0] > 40)
        .count();
    let blues = img
        .pixels()
        .filter(|p| p[2] > 2 * p[0] && p[2] > 40)
        .count();
    assert!(
        reds > 500 && blues > 500,
        "both block colours show on the cut ({reds} red, {blues} blue)"
    );
}

#[test]
fn a_headless_bake_prints_no_error_lines() {
    // Without a desktop session Mesa's device-select Vulkan layer used to
    // print "error: XDG_RUNTIME_DIR is invalid" on every bake that drew a
    // preview, though nothing failed; a bake farm would flag each run.
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_organtex"))
        .args(["bake", repo("scenes/bunny.toml").to_str().unwrap(), "-o"])
        .arg(dir.path())
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(dir.path().join("preview.png").is_file());
    assert!(
        !stderr.lines().any(|l| l.to_lowercase().contains("error")),
        "a successful bake printed: {stderr}"
    );
}
