//! The clinician's flow through the viewer, driven by egui_kittest with
//! its wgpu renderer (the software adapter in CI): open the bundled
//! scene, select a facet, pick a tissue, unwrap, drag the texture, move
//! the cut plane; and bad input shown in the window.

mod common;
use std::time::{Duration, Instant};

use common::{changed_pixels, lit_pixels};

use eframe::egui;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use organtex::app::{Mode, Options, Viewer};

fn repo(p: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn viewer(open: Option<std::path::PathBuf>) -> Harness<'static, Viewer> {
    Harness::builder()
        .with_size([1280.0, 800.0])
        .wgpu()
        .build_eframe(move |cc| {
            Viewer::new(
                cc,
                Options {
                    open,
                    ..Options::default()
                },
            )
            .expect("a viewer on the harness's wgpu device")
        })
}

/// Step frames until no job runs; returns how many frames were drawn
/// meanwhile (the UI never waits for a job).
fn settle(h: &mut Harness<'static, Viewer>) -> usize {
    let start = Instant::now();
    let mut frames = 0;
    while h.state().busy() {
        h.step();
        frames += 1;
        std::thread::sleep(Duration::from_millis(20));
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "a job never ended"
        );
    }
    h.run_steps(3);
    frames
}

/// Drag with the primary button from `from` by `by` points.
fn drag(
    h: &mut Harness<'static, Viewer>,
    from: egui::Pos2,
    by: egui::Vec2,
    modifiers: egui::Modifiers,
) {
    let press = |pressed, pos| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers,
    };
    h.input_mut()
        .events
        .push(egui::Event::ModifiersChanged(modifiers));
    h.input_mut().events.push(egui::Event::PointerMoved(from));
    h.input_mut().events.push(press(true, from));
    h.step();
    for i in 1..=4 {
        h.input_mut()
            .events
            .push(egui::Event::PointerMoved(from + by * (i as f32 / 4.0)));
        h.step();
    }
    h.input_mut().events.push(press(false, from + by));
    h.step();
    h.input_mut()
        .events
        .push(egui::Event::ModifiersChanged(Default::default()));
    h.step();
}

#[test]
fn the_clinician_flow() {
    let mut h = viewer(Some(repo("scenes/hysteroscopy_myomas.toml")));
    // Opening a scene unwraps it at once, frames coming all along.
    let frames = settle(&mut h);
    assert!(
        frames > 5,
        "frames kept coming while loading and unwrapping ({frames})"
    );
    assert!(h.state().doc.as_ref().is_some_and(|d| d.baked.is_some()));
    assert!(h.state().message.is_none(), "{:?}", h.state().message);

    h.get_by_label("uterus / myoma-front").click();
    h.run_steps(2);
    assert_eq!(h.state().selected, Some((0, 1)));

    h.get_by_label("Colonic mucosa").click();
    settle(&mut h);
    let doc = h.state().doc.as_ref().unwrap();
    assert_eq!(doc.settings((0, 1)).texture, "colon-mucosa");
    // The shelf shows one kind at a time: histology on the interior
    // shelf, vessel overlays on the overlay shelf, laid over the facet and
    // taken off again.
    assert!(h.query_by_label("Smooth muscle (H&E)").is_none());
    h.get_by_label_contains("Interior (").click();
    h.run_steps(2);
    assert!(h.query_by_label("Smooth muscle (H&E)").is_some());
    assert!(h.query_by_label("Colonic mucosa").is_none());
    h.get_by_label_contains("Overlay (").click();
    h.run_steps(2);
    let overlay = |h: &Harness<'static, Viewer>| {
        h.state()
            .doc
            .as_ref()
            .unwrap()
            .settings((0, 1))
            .overlay
            .clone()
    };
    h.get_by_label("Mesentery vessels").click();
    settle(&mut h);
    assert_eq!(overlay(&h).as_deref(), Some("serosa-vessels"));
    h.get_by_label("Mesentery vessels").click();
    settle(&mut h);
    assert_eq!(overlay(&h), None, "a second click takes the overlay off");
    h.get_by_label_contains("Surface (").click();
    h.run_steps(2);
    assert!(h.state().message.is_none(), "{:?}", h.state().message);
    // The facet's seams-against-stretch bound is at hand.
    assert!(
        h.query_all_by_label_contains("max stretch")
            .next()
            .is_some()
    );

    // Unwrap again: the UI keeps drawing while it runs.
    h.get_by_label("Unwrap").click();
    h.step();
    assert!(h.state().busy(), "the unwrap runs in the background");
    let frames = settle(&mut h);
    assert!(
        frames > 2,
        "frames kept coming during the unwrap ({frames})"
    );
    assert!(h.state().message.is_none(), "{:?}", h.state().message);

    // Texture visible: the organ's pixels vary.
    let shot = h.state().read_scene().unwrap();
    let (lit, _, var) = lit_pixels(&shot);
    assert!(
        lit > 10_000 && var > 50.0,
        "texture visible: {lit} pixels, variance {var:.1}"
    );

    // Drag the texture: only the transform changes, nothing is uploaded.
    h.get_by_label("Texture").click();
    h.run_steps(2);
    assert_eq!(h.state().mode, Mode::Texture);
    let uploads = h.state().uploads;
    let before = h.state().doc.as_ref().unwrap().settings((0, 1)).clone();
    // The middle of the 3D view, where the selected myoma is in sight (the
    // side panel's width follows the tissue names).
    let centre = h.state().view_rect().expect("the view is drawn").center();
    drag(
        &mut h,
        centre,
        egui::vec2(60.0, 30.0),
        egui::Modifiers::NONE,
    );
    let moved = h.state().doc.as_ref().unwrap().settings((0, 1)).clone();
    assert_ne!(moved.offset, before.offset, "the drag moved the texture");
    assert_eq!(moved.rotation, before.rotation);
    // Shift-drag turns it like a dial about the view's centre, whichever
    // way the pointer goes.
    drag(
        &mut h,
        centre + egui::vec2(220.0, 0.0),
        egui::vec2(0.0, 60.0),
        egui::Modifiers::SHIFT,
    );
    let turned = h.state().doc.as_ref().unwrap().settings((0, 1)).clone();
    let swept = (60.0f64 / 220.0).atan().to_degrees();
    assert!(
        ((before.rotation - turned.rotation) - swept).abs() < 2.0,
        "shift-drag turned the texture by the angle swept: {} -> {} ({swept:.1} swept)",
        before.rotation,
        turned.rotation
    );
    assert_eq!(turned.offset, moved.offset);
    assert_eq!(
        h.state().uploads,
        uploads,
        "a texture drag uploads no mesh data"
    );

    // The cut plane: the interior block is made in the background, then
    // the section is drawn and follows the slider.
    h.get_by_label("cut plane").click();
    h.step();
    assert!(h.state().cut.on, "the checkbox turned the cut on");
    settle(&mut h);
    assert!(
        h.state().cut_triangles() > 0,
        "the section is drawn: {:?} {:?}",
        h.state().cut,
        h.state().message
    );
    assert!(h.state().message.is_none(), "{:?}", h.state().message);
    // The scene laps the wall ([node.interior.lst]): its section is drawn
    // by the LST shader.
    assert!(
        h.state().lst_cut_triangles() > 0,
        "the wall's lapped solid texture is cut"
    );
    let with_cut = h.state().read_scene().unwrap();
    // Ctrl-drag moves the plane.
    let at = h.state().cut.at;
    drag(
        &mut h,
        centre,
        egui::vec2(150.0, -100.0),
        egui::Modifiers::COMMAND,
    );
    assert_ne!(h.state().cut.at, at, "ctrl-drag moved the cut plane");
    h.run_steps(2);
    let moved_cut = h.state().read_scene().unwrap();
    let changed = changed_pixels(&with_cut, &moved_cut);
    assert!(
        changed > 1000,
        "moving the cut plane changes the picture ({changed} pixels)"
    );
    assert!(h.state().cut_triangles() > 0, "the section is drawn");
    // "facing me" turns the plane towards the camera: the section across
    // the line of sight is drawn.
    h.get_by_label("facing me").click();
    h.run_steps(2);
    let towards_eye = (h.state().camera.eye() - h.state().camera.target).normalize();
    assert!(
        h.state().cut.normal.dot(towards_eye) > 0.999,
        "{:?}",
        h.state().cut
    );
    assert!(h.state().cut_triangles() > 0, "the facing section is drawn");
    let facing = h.state().read_scene().unwrap();
    let changed = changed_pixels(&moved_cut, &facing);
    assert!(
        changed > 1000,
        "turning the cut plane changes the picture ({changed} pixels)"
    );

    // Orbit away, then Home brings back the scene's camera.
    let opened = h.state().camera.eye();
    h.get_by_label("Camera").click();
    h.run_steps(2);
    drag(
        &mut h,
        centre,
        egui::vec2(-120.0, 40.0),
        egui::Modifiers::NONE,
    );
    assert!(
        (h.state().camera.eye() - opened).length() > 1.0,
        "the drag orbited"
    );
    h.key_press(egui::Key::Home);
    h.run_steps(2);
    assert!(
        (h.state().camera.eye() - opened).length() < 1e-9,
        "Home reset the view"
    );

    // The whole window renders through egui's wgpu renderer.
    let window = h.render().expect("the harness renders the window");
    assert_eq!((window.width(), window.height()), (1280, 800));
}

#[test]
fn a_broken_mesh_shows_a_message_and_keeps_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.obj");
    std::fs::write(&broken, "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    let mut h = viewer(Some(repo("tests/data/cube.obj")));
    settle(&mut h);
    let name = h.state().doc.as_ref().unwrap().spec.name.clone();
    h.state_mut().open(broken);
    settle(&mut h);
    let m = h.state().message.clone().expect("a message");
    assert!(m.error && m.text.contains("broken.obj"), "{m:?}");
    h.get_by_label_contains("broken.obj");
    assert_eq!(
        h.state().doc.as_ref().unwrap().spec.name,
        name,
        "the cube is still open"
    );

    // A scene whose tissue texture is missing.
    let scene = dir.path().join("missing.toml");
    std::fs::write(
        &scene,
        format!(
            "[[node]]\nname = \"cube\"\nmesh.file = \"{}\"\n[[node.facet]]\nname = \"*\"\ntexture = \"no-such-tissue\"\n",
            repo("tests/data/cube.obj").display()
        ),
    )
    .unwrap();
    h.state_mut().open(scene);
    settle(&mut h);
    let m = h.state().message.clone().expect("a message");
    assert!(m.error && m.text.contains("no-such-tissue"), "{m:?}");
    assert_eq!(h.state().doc.as_ref().unwrap().spec.name, name);
}

/// A scene whose interior is morphed from photographed cuts (seed 003):
/// the cut plane samples the morph over the node and draws its section,
/// which shows the photographs' colours.
#[test]
fn the_cut_plane_shows_a_morphed_interior() {
    let mut h = viewer(Some(repo("scenes/myoma_cuts.toml")));
    settle(&mut h);
    let before = h.state().read_scene().unwrap();
    h.state_mut().set_cut(true);
    settle(&mut h);
    assert!(h.state().message.is_none(), "{:?}", h.state().message);
    assert!(h.state().cut_triangles() > 0, "the section is drawn");
    let placement = h.state().block_placement().expect("a block on the GPU");
    let lo = h.state().doc.as_ref().unwrap().closed[0]
        .0
        .bounding_box()
        .unwrap()
        .0;
    assert!(
        (placement.origin - lo).length() < 1e-9,
        "the morph's block lies on the node's bounds, not tiling from the origin: {placement:?}"
    );
    let after = h.state().read_scene().unwrap();
    assert!(
        changed_pixels(&before, &after) > 1000,
        "the section is in the picture"
    );
}

/// A GPU error on the viewer's device (here a texture wgpu refuses, as a
/// driver limit or a lost device would be met) is shown at the top of the
/// window; the viewer goes on drawing.
#[test]
fn a_gpu_error_shows_in_the_window_and_the_viewer_goes_on() {
    let mut h = viewer(Some(repo("tests/data/cube.obj")));
    settle(&mut h);
    let limit = h.state().gpu().device.limits().max_texture_dimension_2d;
    let _refused = h
        .state()
        .gpu()
        .device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("too wide"),
            size: wgpu::Extent3d {
                width: limit + 1,
                height: 1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
    h.run_steps(3);
    let m = h.state().message.clone().expect("a message");
    assert!(m.error && m.text.contains("GPU error"), "{m:?}");
    h.get_by_label_contains("GPU error");
    let (lit, _, _) = lit_pixels(&h.state().read_scene().unwrap());
    assert!(lit > 1000, "the cube is still drawn ({lit} lit pixels)");
}

#[test]
fn a_drag_draws_at_half_resolution_and_the_full_picture_follows() {
    let mut h = viewer(Some(repo("tests/data/cube.obj")));
    settle(&mut h);
    let full = h.state().read_scene().unwrap().dimensions();
    let at = egui::pos2(870.0, 420.0);
    let press = |pressed, pos| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    h.input_mut().events.push(egui::Event::PointerMoved(at));
    h.input_mut().events.push(press(true, at));
    h.step();
    let mut dragging = None;
    for i in 1..=4 {
        let p = at + egui::vec2(20.0 * i as f32, 0.0);
        h.input_mut().events.push(egui::Event::PointerMoved(p));
        h.step();
        dragging = Some(h.state().read_scene().unwrap().dimensions());
    }
    let dragging = dragging.unwrap();
    assert_eq!(
        dragging,
        (full.0.div_ceil(2), full.1.div_ceil(2)),
        "while the mouse moves the view, the scene is drawn at half resolution"
    );
    h.input_mut()
        .events
        .push(press(false, at + egui::vec2(80.0, 0.0)));
    h.run();
    assert_eq!(
        h.state().read_scene().unwrap().dimensions(),
        full,
        "once it stops, the full picture is drawn without more input"
    );
}

#[test]
fn saving_over_a_file_asks_first_and_writes_a_scene_that_loads() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("cube.obj");
    std::fs::copy(repo("tests/data/cube.obj"), &mesh).unwrap();
    let existing = dir.path().join("scene.toml");
    std::fs::write(&existing, "# mine\n").unwrap();
    let mut h = viewer(Some(mesh));
    settle(&mut h);

    h.get_by_label("Save…").click();
    h.run();
    h.get_by_role(egui::accesskit::Role::TextInput).focus();
    h.run_steps(1);
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    h.get_by_role(egui::accesskit::Role::TextInput)
        .type_text("scene.toml");
    h.run_steps(2);
    h.get_by_label("Save").click();
    h.run_steps(2);
    h.get_by_label_contains("already exists");
    assert_eq!(std::fs::read_to_string(&existing).unwrap(), "# mine\n");
    h.get_by_label("Keep it").click();
    h.run_steps(2);
    assert_eq!(
        std::fs::read_to_string(&existing).unwrap(),
        "# mine\n",
        "kept"
    );

    // Enter in the name field chooses too; this time replace the file.
    h.get_by_role(egui::accesskit::Role::TextInput).focus();
    h.run_steps(1);
    h.key_press(egui::Key::Enter);
    h.run_steps(2);
    h.get_by_label("Replace").click();
    h.run_steps(2);
    let text = std::fs::read_to_string(&existing).unwrap();
    assert!(text.contains("[[node]]"), "{text}");
    assert!(
        !text.contains("database"),
        "the bundled database is not written out: {text}"
    );
    organtex::app::Document::open(&existing).expect("the saved scene opens");
}

/// The Carve tool: outside the organ, a drag over it removes the tets
/// under the pointer through the runtime, the faces that appear are drawn
/// textured from the interior, the surface is not drawn over them, the
/// camera stays where it was, and the panel shows the step time.
#[test]
fn the_carve_tool_removes_tets_under_the_pointer_and_shows_the_inside() {
    let mut h = viewer(Some(repo("scenes/myoma_cuts.toml")));
    settle(&mut h);
    {
        let v = h.state_mut();
        let (lo, hi) = v.doc.as_ref().unwrap().bounds().unwrap();
        v.camera = organtex::render::OrbitCamera::fit(lo, hi);
        v.mode = Mode::Carve;
    }
    h.run_steps(2);
    settle(&mut h);
    assert!(h.state().message.is_none(), "{:?}", h.state().message);
    assert!(h.state().carve.ready(), "the node's tets are made");
    h.run_steps(2);
    let before = h.state().read_scene().unwrap();
    let eye = h.state().camera.eye();
    let centre = h.state().view_rect().unwrap().center();
    drag(
        &mut h,
        centre,
        egui::vec2(40.0, 12.0),
        egui::Modifiers::NONE,
    );
    h.run_steps(3);
    let v = h.state();
    assert!(
        v.carve.steps >= 3 && v.carve.removed > 30,
        "{} steps, {} tets removed",
        v.carve.steps,
        v.carve.removed
    );
    assert!(v.carved_triangles() > 30, "{}", v.carved_triangles());
    assert_eq!(v.carved_triangles(), v.carve.carved_faces());
    assert!(
        (v.camera.eye() - eye).length() < 1e-9,
        "carving does not turn the view"
    );
    let after = v.read_scene().unwrap();
    let changed = changed_pixels(&before, &after);
    assert!(
        changed > 300,
        "the carved pit is in the picture ({changed} pixels)"
    );
    assert!(h.query_by_label_contains("step").is_some());
    // A second drag digs on from the carved surface.
    let removed = h.state().carve.removed;
    drag(
        &mut h,
        centre,
        egui::vec2(-30.0, 0.0),
        egui::Modifiers::NONE,
    );
    assert!(h.state().carve.removed > removed);
    // Reset gives every tet back and draws no carved face.
    h.state_mut().reset_carving();
    h.run_steps(2);
    assert_eq!(
        (h.state().carve.removed, h.state().carved_triangles()),
        (0, 0)
    );
}

/// Opening a segmentation asks which region to mesh: its labels are
/// listed, largest first; the one chosen is meshed in the file's world
/// millimetres and waits for Unwrap as a bare mesh does.
#[test]
fn opening_a_segmentation_asks_which_label_and_meshes_it() {
    use glam::{DAffine3, DVec3};
    use organtex::segment::{ScalarVolume, nifti};
    // Two balls: label 1 of radius 5 voxels, label 2 of radius 4.
    let size = [24, 20, 20];
    let balls = [
        (1.0, DVec3::new(6.0, 10.0, 10.0), 5.0),
        (2.0, DVec3::new(17.0, 10.0, 10.0), 4.0),
    ];
    let mut values = Vec::new();
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let p = DVec3::new(x as f64, y as f64, z as f64);
                let label = balls
                    .iter()
                    .find(|(_, c, r)| (p - *c).length() <= *r)
                    .map_or(0.0, |b| b.0);
                values.push(label);
            }
        }
    }
    let to_world = DAffine3::from_scale_rotation_translation(
        DVec3::new(0.8, 0.8, 1.5),
        glam::DQuat::IDENTITY,
        DVec3::new(-40.0, 12.0, 100.0),
    );
    let volume = ScalarVolume {
        size,
        values,
        to_world,
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("balls.nii");
    std::fs::write(&path, nifti::to_bytes(&volume)).unwrap();

    let mut h = viewer(Some(path.clone()));
    settle(&mut h);
    assert!(
        h.state().doc.is_none(),
        "nothing is meshed before the user says what"
    );
    assert!(h.state_mut().region_dialog().is_some(), "the viewer asks");
    let voxels = |label: f32| volume.values.iter().filter(|&&v| v == label).count();
    let second = format!("label 2 ({} voxels)", voxels(2.0));
    h.get_by_label(&format!("label 1 ({} voxels)", voxels(1.0)));
    h.get_by_label(&second).click();
    h.run_steps(2);
    h.get_by_label("Mesh").click();
    h.run_steps(2);
    settle(&mut h);
    assert!(h.state().message.is_none(), "{:?}", h.state().message);
    assert!(h.state_mut().region_dialog().is_none());
    let doc = h.state().doc.as_ref().expect("the region is open");
    assert!(
        doc.baked.is_none(),
        "it waits for Unwrap, as a bare mesh does"
    );
    assert_eq!(doc.spec.name, "balls");
    // What meshing found, kept with the document and shown beside it.
    let report = doc.segmented[0]
        .as_ref()
        .expect("meshed from a segmentation");
    assert_eq!(report.faces, doc.meshes[0].num_faces());
    assert_eq!((report.components, report.components_kept), (1, 1));
    let summary = report.summary();
    assert!(
        summary.starts_with("its one piece, no enclosed void"),
        "{summary}"
    );
    h.get_by_label_contains(&summary);
    // Label 2's ball, in world millimetres: its centre through the
    // transform, its radius within a voxel.
    let (lo, hi) = doc.bounds().unwrap();
    let centre = to_world.transform_point3(balls[1].1);
    let half = DVec3::new(0.8, 0.8, 1.5) * 4.5;
    for (got, want) in [(lo, centre - half), (hi, centre + half)] {
        assert!(
            (got - want).abs().cmple(DVec3::new(0.8, 0.8, 1.5)).all(),
            "box corner {got} against {want}"
        );
    }
}
