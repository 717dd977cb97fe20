//! The GPU renderer offscreen, on whatever adapter the machine has (in CI
//! the software one, llvmpipe, from mesa-vulkan-drivers). No adapter is a
//! failure, not a skip.

mod common;
use common::{changed_pixels, lit_pixels};
use glam::DVec3;
use organtex::progress::Silent;
use organtex::render::{
    CutMesh, Filtering, Gpu, GpuScene, Layers, Lighting, Offscreen, OrbitCamera, Renderer, View,
};
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
    let renderer = Renderer::new(&gpu.device, Filtering::for_frames(&gpu));
    let scene = GpuScene::new(&renderer, &gpu.device, &gpu.queue, &list).unwrap();
    let target = Offscreen::new(&gpu, &renderer, [320, 240]);
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

/// The bake's preview drawn through wgpu's GL backend and its Vulkan
/// backend (llvmpipe for both where there is no GPU) is the same picture:
/// mean absolute difference under 0.5 of 255 in every channel, and no
/// more than 0.5% of the pixels off by more than 8. On GL the frame also
/// goes through the pass that encodes it for egui, which this checks.
#[test]
fn the_preview_is_the_same_on_gl_and_vulkan() {
    let spec = file::load(&repo("scenes/hysteroscopy_myomas.toml")).unwrap();
    let baked = build_scene(&spec, false, &Silent).unwrap();
    let list = DrawList::of(&baked, None);
    let draw = |backends: wgpu::Backends| {
        let gpu = Gpu::headless_with(backends)
            .unwrap_or_else(|e| panic!("{e} (tools/test.sh installs both GL and Vulkan drivers)"));
        let picture = organtex::render::preview(&gpu, &baked, &list, [480, 360]).unwrap();
        (gpu.adapter, picture)
    };
    let (gl_adapter, gl) = draw(wgpu::Backends::GL);
    let (vk_adapter, vk) = draw(wgpu::Backends::VULKAN);
    assert!(gl_adapter.contains("Gl") && vk_adapter.contains("Vulkan"));
    let mut sum = [0u64; 3];
    let mut far = 0;
    for (p, q) in gl.pixels().zip(vk.pixels()) {
        let d: Vec<u64> = (0..3).map(|c| p[c].abs_diff(q[c]) as u64).collect();
        for c in 0..3 {
            sum[c] += d[c];
        }
        far += d.iter().any(|&d| d > 8) as usize;
    }
    let n = (gl.width() * gl.height()) as f64;
    let mean = sum.map(|s| s as f64 / n);
    eprintln!(
        "GL {gl_adapter} vs Vulkan {vk_adapter}: mean |diff| {mean:.3?}, {far} pixels off by > 8"
    );
    let (_, _, var) = lit_pixels(&image::DynamicImage::ImageRgb8(gl.clone()).to_rgba8());
    assert!(
        var > 100.0,
        "GL drew the textured scene (variance {var:.1})"
    );
    assert!(mean.iter().all(|&m| m < 0.5), "mean |diff| {mean:?}");
    assert!(
        (far as f64) < 0.005 * n,
        "{far} pixels differ by more than 8"
    );
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
    let renderer = Renderer::new(&gpu.device, Filtering::for_frames(&gpu));
    let mut scene =
        GpuScene::new(&renderer, &gpu.device, &gpu.queue, &DrawList::default()).unwrap();
    let placement = Placement::new(lo, (hi - lo).x / 4.0 / n as f64).unwrap();
    scene
        .set_block(&renderer, &gpu.device, &gpu.queue, &volume, &placement)
        .unwrap();
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
    let target = Offscreen::new(&gpu, &renderer, [256, 256]);
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

/// `organtex bake scenes/bunny.toml -o DIR`, its environment set by `env`.
fn bake_bunny(
    dir: &std::path::Path,
    env: impl FnOnce(&mut std::process::Command) -> &mut std::process::Command,
) -> std::process::Output {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_organtex"));
    command
        .args(["bake", repo("scenes/bunny.toml").to_str().unwrap(), "-o"])
        .arg(dir);
    env(&mut command).output().unwrap()
}

#[test]
fn a_headless_bake_prints_no_error_lines() {
    // Without a desktop session Mesa's device-select Vulkan layer used to
    // print "error: XDG_RUNTIME_DIR is invalid" on every bake that drew a
    // preview, though nothing failed; a bake farm would flag each run.
    let dir = tempfile::tempdir().unwrap();
    let out = bake_bunny(dir.path(), |c| {
        c.env_remove("XDG_RUNTIME_DIR")
            .env_remove("NODEVICE_SELECT")
    });
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(dir.path().join("preview.png").is_file());
    assert!(
        !stderr.lines().any(|l| l.to_lowercase().contains("error")),
        "a successful bake printed: {stderr}"
    );
}

/// A GPU that cannot draw the preview (forced here by a texture limit
/// below the preview's size, a real validation error from wgpu) costs the
/// bake its preview only: exit 0, one warning line naming the reason,
/// every other output written, and report.json says why.
#[test]
fn a_preview_the_gpu_cannot_draw_is_a_warning_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = bake_bunny(dir.path(), |c| {
        c.env(organtex::render::MAX_TEXTURE_ENV, "64")
    });
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].contains("preview.png not written: GPU error")
            && warnings[0].contains("exceeds the limit"),
        "{}",
        warnings[0]
    );
    assert!(!dir.path().join("preview.png").exists());
    for f in ["scene.glb", "report.json"] {
        assert!(dir.path().join(f).is_file(), "{f} written");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report.json")).unwrap()).unwrap();
    let why = report["preview_error"].as_str().unwrap_or_default();
    assert!(why.contains("GPU error"), "report.json: {why}");
}

/// An LST cut drawn by the WGSL path (solid::lst::gpu) shows the colours
/// `LstInterior` gives on the CPU: the camera looks straight at a plane
/// cut through a layered cake (1-b, depth bands) and an isotropic kiwi (0,
/// splotches); each pixel's ray meets the plane at a point whose CPU
/// colour, lit as cut.wgsl lights it, is the expected pixel. An exemplar
/// of random voxels makes any misplaced coordinate show.
#[test]
fn an_lst_cut_on_the_gpu_shows_the_cpu_colours() {
    use organtex::solid::lst::{
        LstInterior, TextureType, anchors, gpu::CutBuffers, locate::Locator,
    };
    let gpu = gpu();
    let n = 16;
    let exemplar = Volume {
        size: [n, n, n],
        spacing: 1.0,
        voxels: (0..(n * n * n) as u64)
            .map(|i| [0, 1, 2].map(|c| organtex::rng::below(3, &[i, c], 256) as u8))
            .collect(),
    };
    let renderer = Renderer::new(&gpu.device, Filtering::for_frames(&gpu));
    let decode = |c: f64| {
        let c = c / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let encode = |l: f64| {
        let l = l.clamp(0.0, 1.0);
        255.0
            * if l <= 0.0031308 {
                l * 12.92
            } else {
                1.055 * l.powf(1.0 / 2.4) - 0.055
            }
    };
    for anchor in [
        anchors::cake(TextureType::Layered, 1500).unwrap(),
        anchors::kiwi(TextureType::Isotropic, 1500).unwrap(),
    ] {
        let model = std::sync::Arc::new(
            organtex::solid::lst::fill(&anchor.tets, &anchor.options, &Silent).unwrap(),
        );
        let interior = LstInterior::new(model.clone(), exemplar.clone().into()).unwrap();
        let (lo, hi) = anchor.surface.bounding_box().unwrap();
        let z = 0.5 * (lo.z + hi.z) + 0.013 * (hi.z - lo.z);
        let cut = organtex::tetra::march::plane_cut(&model.mesh, DVec3::Z, z);
        let mut buffers = CutBuffers::default();
        buffers.add(&model, &cut, DVec3::Z);
        let mut scene =
            GpuScene::new(&renderer, &gpu.device, &gpu.queue, &DrawList::default()).unwrap();
        scene
            .set_block(
                &renderer,
                &gpu.device,
                &gpu.queue,
                &exemplar,
                &Placement::new(lo, 1.0).unwrap(),
            )
            .unwrap();
        scene
            .set_lst_cut(&renderer, &gpu.device, &gpu.queue, Some(&buffers))
            .unwrap();
        let mut camera = OrbitCamera::fit(lo, hi);
        camera.yaw = 0.0;
        camera.pitch = 0.0;
        let size = 256u32;
        let target = Offscreen::new(&gpu, &renderer, [size, size]);
        // The even light, whose formula the CPU side repeats below.
        let view = View {
            camera,
            layers: Layers {
                lighting: Lighting::Even,
                ..Layers::default()
            },
            clip: None,
        };
        target.draw(&renderer, &gpu.device, &gpu.queue, &scene, &view);
        let img = target.read(&gpu.device, &gpu.queue).unwrap();

        // The ray through a point of the image (aspect 1), met with the
        // plane.
        let eye = camera.eye();
        let forward = (camera.target - eye).normalize();
        let (right, up) = camera.right_up();
        let tan = (camera.fov.to_radians() / 2.0).tan();
        let locator = Locator::new(&model.mesh);
        let on_plane = |px: f64, py: f64| {
            let x = px / size as f64 * 2.0 - 1.0;
            let y = 1.0 - py / size as f64 * 2.0;
            let dir = forward + tan * (x * right + y * up);
            eye + dir * ((z - eye.z) / dir.z)
        };
        let (mut compared, mut sum, mut far) = (0usize, 0.0, 0usize);
        for py in 0..size {
            for px in 0..size {
                // Inside the cut, away from its rim (where the pixel's
                // footprint leaves the mesh).
                let p = on_plane(px as f64 + 0.5, py as f64 + 0.5);
                let rim =
                    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                        .iter()
                        .any(|&(dx, dy)| {
                            locator
                                .locate(&model.mesh, on_plane(px as f64 + dx, py as f64 + dy))
                                .is_none()
                        });
                let Some((t, b)) = locator.locate(&model.mesh, p).filter(|_| !rim) else {
                    continue;
                };
                let c = interior.colour_in(t, b);
                let to_eye = eye - p;
                let d = to_eye.length();
                let falloff = 1.0 / (1.0 + (d / (1.5 * camera.distance)).powi(2));
                let light = (0.15 + 0.85 * (to_eye.z / d).abs()) * (0.4 + 1.2 * falloff);
                let got = img.get_pixel(px, py);
                for k in 0..3 {
                    let want = encode(decode(c[k] as f64) * light);
                    let diff = (got[k] as f64 - want).abs();
                    sum += diff;
                    far += (diff > 6.0) as usize;
                }
                compared += 1;
            }
        }
        let mean = sum / (3 * compared.max(1)) as f64;
        eprintln!(
            "LST cut type {}: {compared} pixels compared, mean |GPU - CPU| {mean:.3}, {far} channels off by > 6",
            model.kind.name()
        );
        assert!(
            compared > 5000,
            "the cut covers the view ({compared} pixels)"
        );
        assert!(mean < 1.0, "mean |GPU - CPU| {mean:.3} of 255");
        assert!(
            (far as f64) < 0.01 * (3 * compared) as f64,
            "{far} of {} channels off by more than 6",
            3 * compared
        );
    }
}

/// Hue (degrees, -180..180, red at 0), saturation and value of an sRGB
/// pixel, as tools/compare_frames.py measures them.
fn hsv([r, g, b]: [f64; 3]) -> (f64, f64, f64) {
    let (max, min) = (r.max(g).max(b), r.min(g).min(b));
    let d = max - min;
    let hue = if d == 0.0 {
        0.0
    } else if max == r {
        60.0 * ((g - b) / d)
    } else if max == g {
        60.0 * ((b - r) / d + 2.0)
    } else {
        60.0 * ((r - g) / d + 4.0)
    };
    let hue = if hue > 180.0 { hue - 360.0 } else { hue };
    (hue, if max > 0.0 { d / max } else { 0.0 }, max)
}

/// Spearman's rank correlation of two samples.
fn spearman(a: &[f64], b: &[f64]) -> f64 {
    let ranks = |x: &[f64]| {
        let mut order: Vec<usize> = (0..x.len()).collect();
        order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
        let mut r = vec![0.0; x.len()];
        for (rank, &i) in order.iter().enumerate() {
            r[i] = rank as f64;
        }
        r
    };
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    let mean = (n - 1.0) / 2.0;
    let cov: f64 = ra
        .iter()
        .zip(&rb)
        .map(|(x, y)| (x - mean) * (y - mean))
        .sum();
    let var: f64 = ra.iter().map(|x| (x - mean).powi(2)).sum();
    cov / var
}

/// Issue 39: the default preview is lit as an endoscope lights a cavity,
/// measured as tools/compare_frames.py measures real frames
/// (tools/frames_reference.json): specular highlights (value >= 0.9,
/// saturation <= 0.25) on 0.2-5% of the pixels, in small spots; every
/// facet's mean colour within the in-vivo frames' hue range and not grey;
/// luminance falling with the distance from the scope (Spearman <= -0.5),
/// distance and facet found by casting the pixels' rays at the mesh. The
/// distances the preview's fluid takes from the depth buffer are those
/// rays' too.
#[test]
fn the_default_preview_looks_lit_by_an_endoscope() {
    use rayon::prelude::*;
    let gpu = gpu();
    let spec = file::load(&repo("scenes/hysteroscopy_myomas.toml")).unwrap();
    let baked = build_scene(&spec, false, &Silent).unwrap();
    let list = DrawList::of(&baked, None);
    let (w, h) = (640u32, 480u32);
    let (img, medium) =
        organtex::render::picture_and_medium(&gpu, &baked, &list, [w, h], Lighting::Endoscope)
            .unwrap();
    let px = |x: u32, y: u32| img.get_pixel(x, y).0.map(|c| c as f64 / 255.0);

    // Highlights, and their spots (8-connected).
    let bright: Vec<bool> = img
        .pixels()
        .map(|p| {
            let (_, s, v) = hsv(p.0.map(|c| c as f64 / 255.0));
            v >= 0.9 && s <= 0.25
        })
        .collect();
    let total = (w * h) as f64;
    let fraction = bright.iter().filter(|&&b| b).count() as f64 / total;
    let mut spots: Vec<f64> =
        organtex::synth::components::components(&bright, w as usize, h as usize, true)
            .iter()
            .map(|c| c.cells.len() as f64 / total)
            .collect();
    spots.sort_by(f64::total_cmp);
    let median_spot = spots.get(spots.len() / 2).copied().unwrap_or(0.0);
    let largest = spots.last().copied().unwrap_or(0.0);
    println!(
        "highlights {:.2}% in {} spots, median {:.4}%, largest {:.3}%",
        100.0 * fraction,
        spots.len(),
        100.0 * median_spot,
        100.0 * largest
    );
    assert!(
        (0.002..=0.05).contains(&fraction),
        "highlights on {:.3}% of the pixels",
        100.0 * fraction
    );
    assert!(median_spot < 0.0005 && largest < 0.01, "spots too large");

    // No lone dark pixels: a blend layer drawn off the surface showed
    // through the silhouettes in front of it, a dotted dark rim round each
    // myoma and the polyp's foot. A pixel under 0.6 of the median of its
    // 3x3 neighbourhood, where that is lit, is such a dot.
    let luma: Vec<f64> = img
        .pixels()
        .map(|p| {
            let c = p.0.map(|c| c as f64 / 255.0);
            0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
        })
        .collect();
    let mut dots = 0;
    for y in 1..h as usize - 1 {
        for x in 1..w as usize - 1 {
            let mut around: Vec<f64> = (0..9)
                .map(|k| luma[(y + k / 3 - 1) * w as usize + x + k % 3 - 1])
                .collect();
            around.sort_by(f64::total_cmp);
            let median = around[4];
            if median > 0.1 && luma[y * w as usize + x] < 0.6 * median {
                dots += 1;
            }
        }
    }
    println!("lone dark pixels: {dots}");
    assert!(dots <= 2, "{dots} lone dark pixels (a dotted rim)");

    // Depth and facet per sampled pixel, by the pixel's ray.
    let node = &baked.nodes[0];
    let mesh = &node.mesh;
    let lo = mesh
        .positions
        .iter()
        .fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = mesh
        .positions
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let camera = OrbitCamera::for_scene(&spec.cameras, Some((lo, hi)));
    let aspect = w as f64 / h as f64;
    let samples: Vec<(u32, u32)> = (0..h)
        .step_by(4)
        .flat_map(|y| (0..w).step_by(4).map(move |x| (x, y)))
        .collect();
    let hits: Vec<Option<(f64, usize)>> = samples
        .par_iter()
        .map(|&(x, y)| {
            let ndc = (
                (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
            );
            let (o, d) = camera.ray(ndc.0, ndc.1, aspect);
            mesh.triangles
                .iter()
                .enumerate()
                .filter_map(|(f, t)| {
                    organtex::mesh::ray::ray_triangle(o, d, t.map(|v| mesh.positions[v as usize]))
                        .filter(|&t| t > 1e-9)
                        .map(|t| (t, f))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
        })
        .collect();
    let facets = mesh.facets.as_ref().expect("the uterus has facets");
    let mut depth = Vec::new();
    let mut luminance = Vec::new();
    let mut sums = vec![([0.0; 3], 0usize); facets.names.len()];
    for (&(x, y), hit) in samples.iter().zip(&hits) {
        let Some((t, f)) = hit else { continue };
        let c = px(x, y);
        depth.push(*t);
        luminance.push(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]);
        let s = &mut sums[facets.of_face[*f] as usize];
        for (sum, v) in s.0.iter_mut().zip(c) {
            *sum += v;
        }
        s.1 += 1;
    }
    // The depth buffer's distances against the rays': within 0.5% where
    // the ray hits (a pixel on a silhouette may see either side).
    let (mut hit, mut off) = (0, 0);
    for (&(x, y), ray) in samples.iter().zip(&hits) {
        let buffer = medium.distance[(y * w + x) as usize] as f64;
        match ray {
            Some((t, _)) => {
                hit += 1;
                off += ((buffer - t).abs() > 0.005 * t) as usize;
            }
            None => off += buffer.is_finite() as usize,
        }
    }
    println!("depth buffer off the rays by > 0.5% at {off} of {hit} pixels");
    assert!(off * 200 <= hit, "{off} of {hit} distances off the rays");
    let rho = spearman(&depth, &luminance);
    println!(
        "depth-luminance Spearman {rho:.3} over {} pixels",
        depth.len()
    );
    assert!(rho <= -0.5, "luminance does not fall with distance: {rho}");

    let reference: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(repo("tools/frames_reference.json")).unwrap(),
    )
    .unwrap();
    let range = &reference["aggregate"]["pixel_hue_p5_p95"];
    let (h0, h1) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    for (name, (sum, n)) in facets.names.iter().zip(&sums) {
        // Facets the scope barely sees (the serosa, outside) are skipped.
        if *n < 200 {
            continue;
        }
        let mean = sum.map(|s| s / *n as f64);
        let (hue, sat, _) = hsv(mean);
        println!("{name}: {n} samples, mean colour {mean:.3?}, hue {hue:.1}, saturation {sat:.2}");
        assert!(
            (h0..=h1).contains(&hue) && sat >= 0.15,
            "facet {name}: hue {hue:.1} (in-vivo frames {h0:.1}..{h1:.1}), saturation {sat:.2}"
        );
    }
}
