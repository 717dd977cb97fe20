//! The project's standard workloads, timed by `organtex bench`.
//!
//! Each workload prepares its inputs untimed, then its timed step runs `runs`
//! times; the median is the figure issues quote. Add a stage's workloads to
//! `workloads` when the stage lands.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::bake::{BakeOptions, bake};
use crate::error::Result;
use crate::mesh::curvature::Curvature;
use crate::mesh::{Components, Topology, io};
use crate::progress::Silent;
use crate::solid::{Placement, Plane, plane_section, sample_colours};
use crate::synth::block::{BlockOptions, synthesize_block};
use crate::synth::exemplar::{Crop, Exemplar};
use crate::synth::fnpts::{SynthOptions, synthesize};
use crate::synth::volume::Volume;
use crate::unwrap::{UnwrapOptions, unwrap, visibility};

/// The timed step of a workload.
pub type Step = Box<dyn FnMut() -> Result<()>>;

pub struct Workload {
    pub name: &'static str,
    /// Runs at least this many times, whatever `--runs` asks (a carving
    /// tunnel's steps are its runs).
    pub min_runs: usize,
    /// What the step does, for the table's reader.
    pub what: &'static str,
    /// Load the inputs from the project folder (untimed) and return the
    /// step to time.
    pub prepare: fn(&Path) -> Result<Step>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Timing {
    pub name: &'static str,
    pub what: &'static str,
    pub runs: usize,
    pub median_s: f64,
    pub min_s: f64,
    pub max_s: f64,
}

/// The source checkout, whose tests/data and database/sources hold the
/// workloads' inputs.
pub fn default_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bunny(root: &Path) -> PathBuf {
    root.join("tests").join("data").join("bunny.obj")
}

/// Every standard workload.
pub fn workloads() -> Vec<Workload> {
    vec![
        Workload {
            name: "load bunny",
            min_runs: 1,
            what: "read bunny.obj (56k faces)",
            prepare: |root| {
                let path = bunny(root);
                Ok(Box::new(move || io::read(&path).map(drop)))
            },
        },
        Workload {
            name: "topology bunny",
            min_runs: 1,
            what: "half-edges, boundary loops, components, genus",
            prepare: |root| {
                let mesh = io::read(&bunny(root))?;
                Ok(Box::new(move || {
                    let topo = Topology::build(&mesh)?;
                    Components::find(&topo).topology(&topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "curvature bunny",
            min_runs: 1,
            what: "angle defect, mixed area, mean curvature, dihedral angles",
            prepare: |root| {
                let mesh = io::read(&bunny(root))?;
                let topo = Topology::build(&mesh)?;
                Ok(Box::new(move || {
                    Curvature::compute(&mesh, &topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "load+topology+curvature bunny",
            min_runs: 1,
            what: "the three above end to end (target < 0.3 s)",
            prepare: |root| {
                let path = bunny(root);
                Ok(Box::new(move || {
                    let mesh = io::read(&path)?;
                    let topo = Topology::build(&mesh)?;
                    Components::find(&topo).topology(&topo);
                    Curvature::compute(&mesh, &topo);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "unwrap bunny",
            min_runs: 1,
            what: "visibility, seams, ABF++ and layout, one chart (target: 1/10 of xatlas)",
            prepare: |root| {
                let mesh = io::read(&bunny(root))?;
                Ok(Box::new(move || {
                    unwrap(&mesh, &UnwrapOptions::default(), &Silent).map(drop)
                }))
            },
        },
        Workload {
            name: "visibility bunny",
            min_runs: 1,
            what: "the unwrap's first stage alone: 128 orthographic views, depth buffers, every vertex and edge tested",
            prepare: |root| {
                let mesh = io::read(&bunny(root))?;
                let topo = Topology::build(&mesh)?;
                let views = UnwrapOptions::default().viewpoints;
                Ok(Box::new(move || {
                    visibility::compute(&mesh, &topo, &views, &Silent);
                    Ok(())
                }))
            },
        },
        Workload {
            name: "tetra bunny",
            min_runs: 1,
            what: "isosurface stuffing at about TetGen's 174,388 tets (target: 1/4 of TetGen's 5.7 s)",
            prepare: |root| {
                let mesh = io::read(&bunny(root))?;
                let opts = crate::tetra::TetOptions {
                    edge_length: None,
                    cells: Some(174_388),
                    graded: false,
                };
                Ok(Box::new(move || {
                    crate::tetra::tetrahedralise(&mesh, &opts, &Silent).map(drop)
                }))
            },
        },
        Workload {
            name: "tetra uterus",
            min_runs: 1,
            what: "the bundled scene's uterine wall with the generator's stalked polyp at the default resolution (refined until the boundary is within 1% of the diagonal; about 190k tets)",
            prepare: |root| {
                let surface = bundled_surface(root)?;
                Ok(Box::new(move || {
                    crate::tetra::tetrahedralise(&surface, &Default::default(), &Silent).map(drop)
                }))
            },
        },
        Workload {
            name: "synth3d layered 64",
            min_runs: 1,
            what: "layered (depth-varying) 64^3 block from database/sources/layered_wall.png, seed 002 4.2 with the sweep fix (target <= 10 s)",
            prepare: |root| {
                let e = crate::synth::exemplar::Exemplar::load(
                    &root.join("database/sources/layered_wall.png"),
                    None,
                    None,
                )?
                .with_height(64)?;
                Ok(Box::new(move || {
                    crate::synth::block::layered::synthesize_layered(
                        &e,
                        &Default::default(),
                        &Silent,
                    )
                    .map(drop)
                }))
            },
        },
        Workload {
            name: "sweep kiwi 128",
            min_runs: 1,
            what: "sweep designer: a radial section swept to 128^3 with noise, a skin and 100 seed inclusions (target <= 2 s)",
            prepare: |_| {
                use crate::synth::sweep;
                let (section, skin, file) = sweep::kiwi_example();
                let opts = sweep::SweepOptions {
                    size: 128,
                    axis: 2,
                    noise: 1.5,
                    seed: 0,
                };
                Ok(Box::new(move || {
                    let incs = sweep::inclusions(&file, 128, std::path::Path::new("."))?;
                    sweep::sweep(&section, Some((&skin, 4)), &incs, &opts).map(drop)
                }))
            },
        },
        Workload {
            name: "stereology 128",
            min_runs: 1,
            what: "particles from database/sources/cat4_ihc_endometrium_stroma_nuclei_endonuke_a.png (stromal nuclei): split, profiles, unfolding, placement, annealing, and the photograph copied into particles and binder by guided block synthesis, 128^3 (target <= 20 s)",
            prepare: |root| {
                let img = crate::synth::exemplar::read_image(
                    &root
                        .join("database/sources/cat4_ihc_endometrium_stroma_nuclei_endonuke_a.png"),
                )?
                .to_rgb8();
                let (w, h) = (img.width() as usize, img.height() as usize);
                let pixels: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
                Ok(Box::new(move || {
                    let section = crate::solid::stereology::profiles::find(
                        w,
                        h,
                        &pixels,
                        &vec![true; w * h],
                        0,
                    )?;
                    crate::solid::stereology::synthesize(
                        &[section],
                        &crate::solid::stereology::StereologyOptions {
                            size: 128,
                            ..Default::default()
                        },
                        &Silent,
                    )
                    .map(drop)
                }))
            },
        },
        Workload {
            name: "stereology 128, 12 large",
            min_runs: 1,
            what: "particles from 12 noisy 2048x2048 sections through a Boolean model of spheres (issue 38's study, as check_stereology.py --large draws it, made untimed): the split of all 12, their profiles, unfolding, placement, annealing and block synthesis, 128^3 (target <= 20 s)",
            prepare: |_| {
                let side = 2048;
                let photographs = large_sections(12, side, 38);
                let valid = vec![true; side * side];
                Ok(Box::new(move || {
                    use crate::solid::stereology::{sections_of, split};
                    let photos: Vec<split::Photo> = photographs
                        .iter()
                        .map(|pixels| split::Photo {
                            width: side,
                            height: side,
                            pixels,
                            valid: &valid,
                        })
                        .collect();
                    let sections = sections_of(&photos, split::Particles::Auto, 0, &|e, _| e)?;
                    crate::solid::stereology::synthesize(
                        &sections,
                        &crate::solid::stereology::StereologyOptions {
                            size: 128,
                            ..Default::default()
                        },
                        &Silent,
                    )
                    .map(drop)
                }))
            },
        },
        Workload {
            name: "lst fill kiwi",
            min_runs: 1,
            what: "lapped solid texture, type 2-b, kiwi-like ellipsoid at about 4,126 tets (seed 000: 39 s; target <= 2 s)",
            prepare: |_| {
                Ok(lst_fill(crate::solid::lst::anchors::kiwi(
                    crate::solid::lst::TextureType::LayeredTensor,
                    4126,
                )?))
            },
        },
        Workload {
            name: "lst fill cake",
            min_runs: 1,
            what: "lapped solid texture, type 1-b, layered slab at about 2,734 tets (seed 000: 416 s; target <= 20 s)",
            prepare: |_| {
                Ok(lst_fill(crate::solid::lst::anchors::cake(
                    crate::solid::lst::TextureType::Layered,
                    2734,
                )?))
            },
        },
        Workload {
            name: "lst fill uterus",
            min_runs: 1,
            what: "lapped solid texture, type 1-b, the bundled scene's uterine wall with the generator's stalked polyp at its default resolution (about 190k tets; target <= 4 s)",
            prepare: |root| Ok(lst_fill(wall(&bundled_params(root)?)?)),
        },
        Workload {
            name: "lst fill uterus, scene wall",
            min_runs: 1,
            what: "the same fill on the bundled scene's own wall (its sessile polyp; about 275k tets), as the default bake fills it",
            prepare: |root| Ok(lst_fill(wall(&scene_params(root)?)?)),
        },
        Workload {
            name: "lst cut kiwi",
            min_runs: 1,
            what: "plane through the filled kiwi: marching tetrahedra and every vertex's colour (seed 000: 78 ms; target <= 5 ms)",
            prepare: lst_cut_step,
        },
        Workload {
            name: "lst cut uterus",
            min_runs: 1,
            what: "plane through the lapped uterine wall with the generator's stalked polyp (1-b, default resolution, about 190k tets): marching tetrahedra and every vertex's colour (target <= 5 ms)",
            prepare: |root| lst_cut(wall(&bundled_params(root)?)?),
        },
        Workload {
            name: "lst cut uterus, scene wall",
            min_runs: 1,
            what: "the same cut through the bundled scene's own wall (about 275k tets), as the default bake laps it",
            prepare: |root| lst_cut(wall(&scene_params(root)?)?),
        },
        Workload {
            name: "morph points",
            min_runs: 1,
            what: "1M points between the brain MRI slices of tests/data/morph, histogram matching on, warps precomputed (seed 003: 20,000 points/s; target >= 2M points/s, <= 0.5 s)",
            prepare: |root| morph_step(root, false),
        },
        Workload {
            name: "morph cut 512",
            min_runs: 1,
            what: "a 512x512 oblique cut through the same morph (target <= 150 ms)",
            prepare: |root| morph_step(root, true),
        },
        Workload {
            name: "section bunny",
            min_runs: 1,
            what: "oblique plane through the middle: loops, triangulation, block colours (target < 5 ms)",
            prepare: section_step,
        },
        #[cfg(feature = "render")]
        Workload {
            name: "frame default",
            min_runs: 1,
            what: "the default scene drawn 960x720 after a texture drag step (uniform write, draw, read back), on this machine's GPU adapter",
            prepare: frame_step,
        },
        Workload {
            name: "synth 128->256",
            min_runs: 1,
            what: "FNPTS, tileable, from a 128x128 gravel crop (target: half Embark's time)",
            prepare: |root| synth_step(root, 128, 256),
        },
        Workload {
            name: "synth 256->512",
            min_runs: 1,
            what: "FNPTS, tileable, from a 256x256 gravel crop (target: half Embark's time)",
            prepare: |root| synth_step(root, 256, 512),
        },
        Workload {
            name: "synth3d 64",
            min_runs: 1,
            what: "FNPTS block 64^3 from a 64x64 gravel crop (target < 10 s)",
            prepare: |root| synth3d_step(root, 64),
        },
        Workload {
            name: "synth3d 128",
            min_runs: 1,
            what: "FNPTS block 128^3 from a 128x128 gravel crop (target < 60 s)",
            prepare: |root| synth3d_step(root, 128),
        },
        Workload {
            name: "bake hysteroscopy_myomas",
            min_runs: 1,
            what: "the default scene from scratch into a new folder: cavity, unwraps, blends, interior (tets, LST; its block kept beside the tissue by the first, untimed bake, as the database's outputs are), contrast, .glb, preview (target <= 10 s)",
            prepare: |root| {
                let scene = root.join("scenes").join("hysteroscopy_myomas.toml");
                // Database outputs, and the interior block kept beside its
                // tissue, are made once, untimed, by a first bake.
                let out =
                    tempfile::tempdir().map_err(|e| crate::Error::io(Path::new("/tmp"), e))?;
                bake(&scene, out.path(), &BakeOptions::default(), &Silent)?;
                let mut run = 0;
                Ok(Box::new(move || {
                    // A new folder each run: nothing kept from the last.
                    run += 1;
                    let dir = out.path().join(format!("run{run}"));
                    bake(&scene, &dir, &BakeOptions::default(), &Silent).map(drop)
                }))
            },
        },
        Workload {
            name: "bake again, one tissue changed",
            min_runs: 1,
            what: "the default scene baked again into the same folder after its polyp's tissue changed (a different one each run): the interior and the unwraps kept (target <= 3 s)",
            prepare: rebake_step,
        },
        Workload {
            name: "carve wall step",
            min_runs: TUNNEL_STEPS,
            what: "one step of a burr (r 1.5) tunnelling round the default bake's wall (275k tets, LST): new faces, atlas texels at 8/unit, corner colours; 100 steps (target: median <= 2 ms, worst <= 8 ms)",
            prepare: carve_tunnel_step,
        },
        Workload {
            name: "carve 10k tets",
            min_runs: 1,
            what: "a new session on the default wall, then 10,000 tets removed in one call: new faces, uvs, corner colours, texels in the background (target <= 30 ms)",
            prepare: |root| carve_10k(root, false),
        },
        Workload {
            name: "carve 10k tets + texels",
            min_runs: 1,
            what: "the same, waiting for the background job's atlas texels",
            prepare: |root| carve_10k(root, true),
        },
    ]
}

/// Issue 38's large study, drawn as `tools/check_stereology.py --large`
/// draws it (but for the sphere count, its expectation rather than a
/// Poisson draw, and the mean sphere volume from 20,000 diameters rather
/// than 200,000): `count` photographs of `side` x `side` pixels cutting a
/// Boolean model of spheres (lognormal diameters, median 14 px, at most 40; a
/// volume fraction of 0.077), light particles (190, 150, 160) on a dark
/// binder (150, 110, 120) under Gaussian noise of 15 levels. Centres reach
/// past the frame so its border is not thinned.
fn large_sections(count: usize, side: usize, seed: u64) -> Vec<Vec<[u8; 3]>> {
    use crate::rng::{normal, unit};
    use rayon::prelude::*;
    const D_MAX: f64 = 40.0;
    const FRACTION: f64 = 0.077;
    const NOISE: f64 = 15.0;
    let (light, dark) = ([190.0, 150.0, 160.0], [150.0, 110.0, 120.0]);
    // The k-th diameter drawn under `key`, redrawn until in (2, 40] px.
    let diameter = |key: &[u64]| -> f64 {
        (0u64..)
            .map(|t| {
                let k: Vec<u64> = key.iter().copied().chain([t]).collect();
                (0.35f64.ln() + 0.35 * normal(seed, &k)).exp() * D_MAX
            })
            .find(|d| *d > 0.05 * D_MAX && *d <= D_MAX)
            .expect("the lognormal reaches (2, 40]")
    };
    let mean_volume = (0..20_000u64)
        .map(|k| std::f64::consts::PI / 6.0 * diameter(&[0, k]).powi(3))
        .sum::<f64>()
        / 20_000.0;
    // A Boolean model covers 1 - exp(-N_V E[V]) of space.
    let per_volume = -(1.0 - FRACTION).ln() / mean_volume;
    let r_max = D_MAX / 2.0;
    let span = side as f64 + 2.0 * r_max;
    let spheres = (per_volume * span * span * 2.0 * r_max).round() as u64;
    (0..count as u64)
        .into_par_iter()
        .map(|photo| {
            let mut inside = vec![false; side * side];
            for s in 0..spheres {
                let key = [1, photo, s];
                let at = |k: u64| unit(seed, &[2, photo, s, k]);
                let (cx, cy) = (at(0) * span - r_max, at(1) * span - r_max);
                let h = (2.0 * at(2) - 1.0) * r_max;
                let r2 = (diameter(&key) / 2.0).powi(2) - h * h;
                if r2 <= 0.0 {
                    continue;
                }
                let r = r2.sqrt();
                let span_of = |c: f64| {
                    (
                        (c - r).max(0.0) as usize,
                        ((c + r + 1.0).max(0.0) as usize).min(side),
                    )
                };
                let ((x0, x1), (y0, y1)) = (span_of(cx), span_of(cy));
                for y in y0..y1 {
                    for x in x0..x1 {
                        let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                        if dx * dx + dy * dy < r2 {
                            inside[y * side + x] = true;
                        }
                    }
                }
            }
            inside
                .iter()
                .enumerate()
                .map(|(i, &particle)| {
                    let base = if particle { light } else { dark };
                    [0, 1, 2].map(|c| {
                        let n = normal(seed, &[3, photo, i as u64, c as u64]);
                        (base[c] + NOISE * n).round().clamp(0.0, 255.0) as u8
                    })
                })
                .collect()
        })
        .collect()
}

/// Synthesise `output` pixels square from the top left `input` square of
/// the gravel photograph of tests/data/textures.
fn synth_step(root: &Path, input: u32, output: usize) -> Result<Step> {
    let gravel = root
        .join("tests")
        .join("data")
        .join("textures")
        .join("gravel.png");
    let crop = Crop {
        x: 0,
        y: 0,
        width: input,
        height: input,
    };
    let exemplar = Exemplar::load(&gravel, None, Some(crop))?;
    let opts = SynthOptions {
        width: output,
        height: output,
        tileable: true,
        ..SynthOptions::default()
    };
    Ok(Box::new(move || {
        synthesize(&exemplar, &opts, &Silent).map(drop)
    }))
}

/// Synthesise a block `side` voxels a side from the top left `side`
/// square of the gravel photograph of tests/data/textures.
fn synth3d_step(root: &Path, side: usize) -> Result<Step> {
    let gravel = root
        .join("tests")
        .join("data")
        .join("textures")
        .join("gravel.png");
    let crop = Crop {
        x: 0,
        y: 0,
        width: side as u32,
        height: side as u32,
    };
    let exemplar = Exemplar::load(&gravel, None, Some(crop))?;
    let opts = BlockOptions {
        size: side,
        ..BlockOptions::default()
    };
    Ok(Box::new(move || {
        synthesize_block(std::slice::from_ref(&exemplar), &opts, &Silent).map(drop)
    }))
}

/// Cut the bunny through the middle of its bounds and colour the
/// section's vertices from a 64³ block of random voxels spanning it.
fn section_step(root: &Path) -> Result<Step> {
    let mesh = io::read(&bunny(root))?;
    let topo = Topology::build(&mesh)?;
    let (lo, hi) = mesh
        .bounding_box()
        .ok_or_else(|| crate::Error::invalid("bunny.obj has no vertices"))?;
    let normal = glam::DVec3::new(0.3, 0.2, 1.0);
    let plane = Plane::new(normal, normal.dot((lo + hi) / 2.0))?;
    let n = 64;
    let volume = Volume {
        size: [n; 3],
        spacing: 1.0,
        voxels: (0..n * n * n)
            .map(|i| {
                let h = crate::rng::hash(0, &[i as u64]).to_le_bytes();
                [h[0], h[1], h[2]]
            })
            .collect(),
    };
    let placement = Placement::new(lo, (hi - lo).max_element() / n as f64)?;
    Ok(Box::new(move || {
        let section = plane_section(&mesh, &topo, plane)?;
        std::hint::black_box(sample_colours(&section, &volume, &placement));
        Ok(())
    }))
}

/// The morph of tests/data/morph (three MRI slices in a box), precomputed
/// untimed; timed: 1M scattered points, or a 512x512 oblique cut.
fn morph_step(root: &Path, cut: bool) -> Result<Step> {
    use crate::solid::Interior;
    use crate::solid::morph::{Morph, MorphOptions};
    let dir = root.join("tests").join("data").join("morph");
    let mesh = io::read(&dir.join("box.obj"))?;
    let topology = Topology::build(&mesh)?;
    let morph = Morph::read(
        &mesh,
        &topology,
        &dir.join("sections.toml"),
        MorphOptions::default(),
        &Silent,
    )?;
    let points: Vec<glam::DVec3> = if cut {
        // The plane x + z = 150 across the box, 512 points a side.
        let (o, u, v) = (
            glam::DVec3::new(150.0 - 30.0, 0.0, 30.0),
            glam::DVec3::new(-100.0, 0.0, 100.0) / 512.0,
            glam::DVec3::new(0.0, 233.0, 0.0) / 512.0,
        );
        (0..512 * 512)
            .map(|i| o + u * ((i % 512) as f64 + 0.5) + v * ((i / 512) as f64 + 0.5))
            .collect()
    } else {
        (0..1_000_000u64)
            .map(|i| {
                let h = crate::rng::hash(7, &[i]);
                let f = |k: u32| ((h >> (21 * k)) & 0x1f_ffff) as f64 / 2_097_152.0;
                glam::DVec3::new(20.0 + 157.0 * f(0), 20.0 + 193.0 * f(1), 72.0 + 48.0 * f(2))
            })
            .collect()
    };
    Ok(Box::new(move || {
        std::hint::black_box(morph.colours(&points));
        Ok(())
    }))
}

fn lst_cut_step(_: &Path) -> Result<Step> {
    use crate::solid::lst;
    let a = lst::anchors::kiwi(lst::TextureType::LayeredTensor, 4126)?;
    let model = lst::fill(&a.tets, &a.options, &Silent)?;
    let exemplar = lst::anchors::layered_exemplar();
    let interior = lst::LstInterior::new(model.into(), exemplar.into())?;
    let normal = glam::DVec3::new(0.3, 0.2, 1.0).normalize();
    Ok(Box::new(move || {
        let cut = crate::tetra::march::plane_cut(&interior.model().mesh, normal, 0.05);
        std::hint::black_box(interior.cut_colours(&cut));
        Ok(())
    }))
}

/// The lapped solid texture of an anchor (its tets made untimed).
fn lst_fill(a: crate::solid::lst::anchors::Anchor) -> Step {
    Box::new(move || crate::solid::lst::fill(&a.tets, &a.options, &Silent).map(drop))
}

/// The bundled scene's uterus as the uterine workloads take it: the
/// scene's parameters, but with the generator's stalked polyp
/// (`scene::uterus::demo`) in place of the scene's sessile one. The
/// stalk's neck refines the default tet resolution to about 190k tets,
/// the size issue 38's targets were set and measured at (the scene's own
/// wall is about 275k, the bake and carving workloads' size).
fn bundled_params(root: &Path) -> Result<crate::scene::uterus::CavityParams> {
    Ok(crate::scene::uterus::CavityParams {
        polyps: crate::scene::uterus::demo().polyps,
        ..scene_params(root)?
    })
}

/// The bundled scene's uterus as the scene gives it.
fn scene_params(root: &Path) -> Result<crate::scene::uterus::CavityParams> {
    let spec = crate::scene::file::load(&root.join("scenes").join("hysteroscopy_myomas.toml"))?;
    match &spec.nodes[0].mesh {
        crate::scene::file::MeshSpec::UterineCavity(params) => Ok(params.clone()),
        _ => Err(crate::Error::invalid(
            "the bundled scene's uterus is no longer generated",
        )),
    }
}

/// The bundled scene's uterine surface (cavity, myomas, polyp, serosa).
fn bundled_surface(root: &Path) -> Result<crate::mesh::TriMesh> {
    uterus_surface(&bundled_params(root)?)
}

/// A generated uterus, its parameter errors as organtex errors.
fn uterus_surface(params: &crate::scene::uterus::CavityParams) -> Result<crate::mesh::TriMesh> {
    crate::scene::uterus::generate(params)
        .map_err(|e| crate::Error::invalid(format!("{}: {}", e.key, e.msg)))
}

/// The LST anchor (1-b, serosa to cavity) of a uterus's wall at the
/// default tet resolution, as a bake lays it.
fn wall(params: &crate::scene::uterus::CavityParams) -> Result<crate::solid::lst::anchors::Anchor> {
    uterus_wall(
        params,
        &Default::default(),
        crate::solid::lst::TextureType::Layered,
    )
}

/// A uterine wall's anchor lapped (1-b, serosa to cavity) as a bake
/// laps it (untimed), cut across its width.
fn lst_cut(a: crate::solid::lst::anchors::Anchor) -> Result<Step> {
    use crate::solid::lst;
    let model = lst::fill(&a.tets, &a.options, &Silent)?;
    let exemplar = lst::anchors::layered_exemplar();
    let interior = lst::LstInterior::new(model.into(), exemplar.into())?;
    Ok(Box::new(move || {
        let cut = crate::tetra::march::plane_cut(&interior.model().mesh, glam::DVec3::X, 0.0);
        std::hint::black_box(interior.cut_colours(&cut));
        Ok(())
    }))
}

/// The LST anchor of the bundled scene's uterine wall (`scene::uterus`
/// with a wall thickness), its tets made
/// with `tet_options`: depth 0 at the serosa, 1 at the cavity (facet
/// "wall"), a patch the bundled block's 10 units, no strokes.
pub fn uterus_wall(
    params: &crate::scene::uterus::CavityParams,
    tet_options: &crate::tetra::TetOptions,
    kind: crate::solid::lst::TextureType,
) -> Result<crate::solid::lst::anchors::Anchor> {
    let surface = uterus_surface(params)?;
    let (depth_outer, depth_inner) =
        crate::solid::lst::facet_depth_points(&surface, "serosa", "wall")?;
    let tets = crate::tetra::tetrahedralise(&surface, tet_options, &Silent)?;
    Ok(crate::solid::lst::anchors::Anchor {
        surface,
        tets,
        options: crate::solid::lst::LstOptions {
            kind,
            scale: 10.0,
            strokes: Vec::new(),
            depth_outer,
            depth_inner,
            seed: 3,
        },
    })
}

/// Steps of the tunnel the carving workloads, tests and examples carve.
pub const TUNNEL_STEPS: usize = 100;

/// Point `step` (0 to `TUNNEL_STEPS`) of a tunnel round the default
/// scene's uterine wall at mid-depth: z = 20, an ellipse of semi-axes 18.5
/// and 11.8 units, 95% of the way round. A burr of radius 1.5 along it
/// removes some 30-60 of the wall's tets a step.
pub fn wall_tunnel(step: usize) -> glam::DVec3 {
    let a = step as f64 / TUNNEL_STEPS as f64 * 0.95 * std::f64::consts::TAU;
    glam::DVec3::new(18.5 * a.cos(), 11.8 * a.sin(), 20.0)
}

/// The default scene baked once per process (untimed), for the carving
/// workloads.
fn default_bake(root: &Path) -> Result<&'static Path> {
    static BAKED: std::sync::OnceLock<tempfile::TempDir> = std::sync::OnceLock::new();
    if let Some(dir) = BAKED.get() {
        return Ok(dir.path());
    }
    let dir = tempfile::tempdir().map_err(|e| crate::Error::io(Path::new("/tmp"), e))?;
    let scene = root.join("scenes").join("hysteroscopy_myomas.toml");
    bake(&scene, dir.path(), &BakeOptions::default(), &Silent)?;
    Ok(BAKED.get_or_init(|| dir).path())
}

/// The default wall opened and a session started (untimed); each timed
/// run carves the tunnel's next step.
fn carve_tunnel_step(root: &Path) -> Result<Step> {
    use crate::runtime::{Bake, Carving, CarvingOptions, Tool};
    let node = Bake::open(default_bake(root)?)?.node("uterus")?;
    let mut carving = Carving::new(node, CarvingOptions::default())?;
    let mut step = 0;
    Ok(Box::new(move || {
        if step == TUNNEL_STEPS {
            // Round again in a new session (runs past the tunnel).
            carving = Carving::new(carving.node().clone(), CarvingOptions::default())?;
            step = 0;
        }
        step += 1;
        let tool = Tool::Capsule {
            a: wall_tunnel(step - 1),
            b: wall_tunnel(step),
            radius: 1.5,
        };
        carving.carve(&tool).map(drop)
    }))
}

/// A session started and 10,000 tets removed by id in one call (SOFA's
/// stress test: 10,000 of 19,409), the ball of tets nearest a point in
/// the wall; with `texels`, until the background texels are written.
fn carve_10k(root: &Path, texels: bool) -> Result<Step> {
    use crate::runtime::{Bake, Carving, CarvingOptions};
    let node = Bake::open(default_bake(root)?)?.node("uterus")?;
    let mesh = node.require_tets()?;
    let centre = glam::DVec3::new(-18.5, 0.0, 25.0);
    let mut by_distance: Vec<(f64, u32)> = (0..mesh.num_tets())
        .map(|t| {
            let c = mesh.corners(t);
            (
                ((c[0] + c[1] + c[2] + c[3]) / 4.0).distance(centre),
                t as u32,
            )
        })
        .collect();
    by_distance.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let ids: Vec<u32> = by_distance[..10_000].iter().map(|&(_, t)| t).collect();
    let options = CarvingOptions {
        background_texels: true,
        ..Default::default()
    };
    // The node's face adjacency and centroid grid, made by its first
    // session (about 0.1 s) and shared by every later one, made here.
    Carving::new(node.clone(), options)?;
    Ok(Box::new(move || {
        let mut carving = Carving::new(node.clone(), options)?;
        carving.remove(&ids)?;
        if texels {
            carving.wait();
        }
        Ok(())
    }))
}

/// Time `workload`'s step `runs` times (at least once) on the inputs under
/// `root`.
pub fn time(workload: &Workload, root: &Path, runs: usize) -> Result<Timing> {
    let mut step = (workload.prepare)(root)?;
    let runs = runs.max(workload.min_runs).max(1);
    let mut secs = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        step()?;
        secs.push(start.elapsed().as_secs_f64());
    }
    secs.sort_unstable_by(f64::total_cmp);
    Ok(Timing {
        name: workload.name,
        what: workload.what,
        runs: secs.len(),
        median_s: median(&secs),
        min_s: secs[0],
        max_s: secs[secs.len() - 1],
    })
}

/// Median of sorted values.
fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 {
        sorted[n / 2]
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0
    }
}

/// The default scene baked once, untimed; each step then changes the
/// polyp's tissue (two by turns) and bakes into the same folder.
fn rebake_step(root: &Path) -> Result<Step> {
    let dir = tempfile::tempdir().map_err(|e| crate::Error::io(Path::new("/tmp"), e))?;
    let source = root.join("scenes").join("hysteroscopy_myomas.toml");
    let text = std::fs::read_to_string(&source).map_err(|e| crate::Error::io(&source, e))?;
    // Its copy names the repo's database, as the original does by place.
    let text = format!("database = {:?}\n{text}", root.join("database"));
    let scene = dir.path().join("hysteroscopy_myomas.toml");
    let out = dir.path().join("out");
    let write = move |scene: &Path, tissue: &str| {
        let body = text.replace(
            "texture = \"colon-polyp\"",
            &format!("texture = \"{tissue}\""),
        );
        std::fs::write(scene, body).map_err(|e| crate::Error::io(scene, e))
    };
    write(&scene, "colon-polyp")?;
    bake(&scene, &out, &BakeOptions::default(), &Silent)?;
    let mut run = 0;
    Ok(Box::new(move || {
        let _keep = &dir;
        run += 1;
        write(&scene, ["fundus-tissue", "colon-polyp"][run % 2])?;
        bake(&scene, &out, &BakeOptions::default(), &Silent).map(drop)
    }))
}

/// One frame of the texture-drag path: the bundled scene unwrapped and on
/// the GPU (untimed); timed: move a texture (one uniform), draw, read the
/// pixels back (so the GPU's work is inside the time).
#[cfg(feature = "render")]
fn frame_step(root: &Path) -> Result<Step> {
    use crate::render::{Filtering, Gpu, GpuScene, Layers, Offscreen, Renderer, View};
    use crate::scene::draw::DrawList;
    let spec = crate::scene::file::load(&root.join("scenes").join("hysteroscopy_myomas.toml"))?;
    let baked = crate::scene::build::build_scene(&spec, false, &Silent)?;
    let list = DrawList::of(&baked, None);
    let gpu = Gpu::headless()?;
    let renderer = Renderer::new(&gpu.device, Filtering::for_frames(&gpu));
    let scene = GpuScene::new(&renderer, &gpu.device, &gpu.queue, &list)?;
    let target = Offscreen::new(&gpu, &renderer, [960, 720]);
    let view = View {
        camera: crate::render::OrbitCamera::for_scene(&spec.cameras, scene.bounds),
        layers: Layers::default(),
        clip: None,
    };
    let mut settings = baked.nodes[0].facets[0].settings.clone();
    Ok(Box::new(move || {
        settings.offset[0] += 0.01;
        for (m, material) in list.materials.iter().enumerate() {
            if material.facet == Some((0, 0)) {
                scene.set_transform(
                    &gpu.queue,
                    &list,
                    m,
                    material.transform_for(&settings).as_ref(),
                );
            }
        }
        target.draw(&renderer, &gpu.device, &gpu.queue, &scene, &view);
        target.read(&gpu.device, &gpu.queue)?;
        gpu.take_error()
    }))
}
