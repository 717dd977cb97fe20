//! A bake's interiors: every node's block (synthesised from its tissue,
//! layered, from stereology, or a morph sampled), its tet mesh and its
//! lapped solid texture, and the files they go to under DIR/interior/,
//! as report.json's `interiors` lines name them (`scene::interior`).
//!
//! They are most of a bake's time and depend on little: the node's mesh,
//! its `[node.interior]`, the tissue's built texture and the code. Beside
//! each node's files goes a key, a digest of those (`interior_key`); a
//! bake into the same folder whose key is the same keeps the files there
//! (the same bytes it would make) instead of making them again, so a
//! clinician who changes a facet's tissue waits for the surface alone.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::progress::{CancelOnly, Progress, Span, timed};
use crate::scene::build::PreparedScene;
use crate::scene::interior::{InteriorLine, LstLine, LstRegionLine, MorphLine, TetLine};
use crate::solid::{InteriorMethod, interior_block};
use crate::synth::volume::Volume;

/// Every node's interior block, synthesised from its tissue's colour
/// texture (seed 004, 3.3) or layered exemplar (seed 002, 4.2),
/// `[bake] interior_voxels` a side, with its tet mesh and lapped solid
/// texture where asked; one whose files in `out_dir` carry its key is kept
/// as it is there. Each step's time goes onto `spans`.
pub(super) fn interiors(
    scene: &PreparedScene,
    out_dir: &Path,
    progress: &dyn Progress,
    spans: &mut Vec<Span>,
) -> Result<Vec<Interior>> {
    let n = scene.spec.bake.interior_voxels;
    let mut out = Vec::new();
    for (k, node) in scene.spec.nodes.iter().enumerate() {
        let Some(interior) = &node.interior else {
            continue;
        };
        let name = node.name.as_str();
        if interior.method == InteriorMethod::Morph {
            let morph = timed(spans, "interior morph", name, || {
                morphed(scene, k, interior, n, &out, progress)
            })?;
            out.push(morph);
            continue;
        }
        let built = scene.tissues.of(interior.method.output());
        let texture = built.get(&interior.texture).ok_or_else(|| {
            Error::invalid(format!(
                "node '{}': interior texture '{}' was not built",
                node.name, interior.texture
            ))
        })?;
        // Names distinct as nodes may meet as file names ("a b", "a_b").
        let file = interior_file(&node.name, k, &out);
        let sources = sources_digest(texture, &interior.photographs)?;
        let key = interior_key(scene, k, &sources);
        let start = Instant::now();
        if let Some(line) = reusable(out_dir, &file, &key) {
            spans.push(Span {
                stage: "interior reused".into(),
                item: name.into(),
                seconds: start.elapsed().as_secs_f64(),
                parallel: false,
            });
            out.push(Interior {
                line,
                key: Some(key),
                volume: None,
                tets: None,
                lst: None,
                sections: None,
                surface: None,
            });
            continue;
        }
        // The block and the tet mesh (then the LST through it) need
        // nothing of each other: they run side by side, the block's own
        // progress quiet when there are tets, so the two do not fight over
        // one bar. Their spans are listed under the interior's, whose
        // seconds are the wall clock's.
        let has_tets = interior.tet_mesh || interior.lst.is_some();
        let quiet = CancelOnly(progress);
        let block_progress: &dyn Progress = if has_tets { &quiet } else { progress };
        let (mut block_spans, mut tet_spans) = (Vec::new(), Vec::new());
        // The tets and the LST through them are the longer chain: they
        // start at once on this thread, the block on whichever is free
        // (rayon runs a join's first closure here and leaves the second to
        // be taken; the block first had the tets wait for it).
        let (tets_lst, volume) = rayon::join(
            || -> Result<_> {
                let tets = if has_tets {
                    Some(timed(&mut tet_spans, "tet mesh", name, || {
                        tet_mesh(&scene.meshes[k].0, &file, &node.name, progress)
                    })?)
                } else {
                    None
                };
                let lst = match (&interior.lst, &tets) {
                    (Some(spec), Some((_, tet_mesh))) => {
                        Some(timed(&mut tet_spans, "lapped solid texture", name, || {
                            lapped(
                                spec,
                                &scene.meshes[k].0,
                                tet_mesh,
                                interior.block_size,
                                &file,
                                k as u64,
                                &node.name,
                                progress,
                            )
                        })?)
                    }
                    _ => None,
                };
                Ok((tets, lst))
            },
            || {
                let start = Instant::now();
                let (block, kept) =
                    kept_block(texture, &sources, interior, n, k as u64, block_progress)?;
                block_spans.push(Span {
                    stage: if kept {
                        "interior block kept"
                    } else {
                        "interior block"
                    }
                    .into(),
                    item: name.into(),
                    seconds: start.elapsed().as_secs_f64(),
                    parallel: false,
                });
                Ok(block)
            },
        );
        spans.push(Span {
            stage: "interior".into(),
            item: name.into(),
            seconds: start.elapsed().as_secs_f64(),
            parallel: false,
        });
        spans.extend(block_spans.into_iter().chain(tet_spans).map(|s| Span {
            parallel: true,
            ..s
        }));
        let mut volume =
            volume.map_err(|e: Error| e.within(format!("node '{}': interior", node.name)))?;
        volume.spacing = interior.block_size / n as f64;
        let (tets, lst) = tets_lst?;
        out.push(Interior {
            line: InteriorLine {
                node: node.name.clone(),
                texture: interior.texture.clone(),
                method: interior.method,
                file,
                voxels: n,
                voxel_size: volume.spacing,
                tet_mesh: tets
                    .as_ref()
                    .filter(|_| interior.tet_mesh)
                    .map(|(line, _)| line.clone()),
                lst: lst.as_ref().map(|(line, _)| line.clone()),
                morph: None,
            },
            key: Some(key),
            volume: Some(volume),
            tets: tets.map(|(_, m)| m),
            lst: lst.map(|(_, m)| m),
            sections: None,
            surface: None,
        });
    }
    Ok(out)
}

/// Node `k`'s interior block, `n` voxels a side, and whether it was
/// kept: a block depends on its tissue's built texture, its photographs,
/// method and particles, its size, its seed (the node's place in the
/// scene) and the code, not on the node's mesh, so one made from the same
/// of these in any bake is kept beside the tissue's build
/// (database/build/ID/blocks/, as graded colours are) and taken from
/// there: a scene baked for the first time into a new folder, or another
/// scene with the same interior at the same place, then waits for the
/// tets and the LST alone. Keeping it is best effort (a database folder
/// that cannot be written costs the next bake time, never this one); a
/// file that does not read back as such a block is made again. A block
/// kept from the same inputs by other code is removed as the new one is
/// kept.
fn kept_block(
    texture: &Path,
    sources: &str,
    interior: &crate::scene::file::Interior,
    n: usize,
    seed: u64,
    progress: &dyn Progress,
) -> Result<(Volume, bool)> {
    let mut inputs = crate::digest::Digest::default();
    inputs.feed(format!("{:?} {:?} {n} {seed}", interior.method, interior.particles).as_bytes());
    inputs.feed(sources.as_bytes());
    let mut code = crate::digest::Digest::default();
    code.feed(env!("ORGANTEX_SOURCE_DIGEST").as_bytes());
    // METHOD-N-SEED-INPUTS-CODE.nrrd
    let stem = format!("{:?}-{n}-{seed}-{}-", interior.method, inputs.hex()).to_lowercase();
    let dir = texture.parent().unwrap_or(Path::new(".")).join("blocks");
    let path = dir.join(format!("{stem}{}.nrrd", code.hex()));
    if let Ok(block) = Volume::read_nrrd(&path)
        && block.size == [n; 3]
    {
        return Ok((block, true));
    }
    let block = interior_block(
        texture,
        &interior.photographs,
        interior.particles,
        n,
        interior.method,
        seed,
        progress,
    )?;
    if std::fs::create_dir_all(&dir).is_ok() && block.write_nrrd(&path).is_ok() {
        for old in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let name = old.file_name();
            let name = name.to_string_lossy();
            if name.starts_with(&stem) && name.ends_with(".nrrd") && old.path() != path {
                let _ = std::fs::remove_file(old.path());
            }
        }
    }
    Ok((block, false))
}

/// interior/NODE.nrrd, the name made distinct from those already taken
/// (nodes "a b" and "a_b" meet as file names).
fn interior_file(node: &str, k: usize, taken: &[Interior]) -> PathBuf {
    let mut stem = file_name(node);
    if taken
        .iter()
        .any(|i| i.line.file.file_stem() == Some(std::ffi::OsStr::new(&stem)))
    {
        stem = format!("{stem}-{k}");
    }
    PathBuf::from("interior").join(format!("{stem}.nrrd"))
}

/// Node `k`'s interior morphed from its sections (seed 003): precomputed,
/// sampled into an `n`-voxel block over its bounding cube.
fn morphed(
    scene: &PreparedScene,
    k: usize,
    interior: &crate::scene::file::Interior,
    n: usize,
    taken: &[Interior],
    progress: &dyn Progress,
) -> Result<Interior> {
    use crate::solid::morph::{Morph, MorphOptions};
    let name = &scene.spec.nodes[k].name;
    let err = |e: Error| e.within(format!("node '{name}': interior"));
    // Checked when the scene loaded: a morph names its sections file.
    let sections = interior.sections.clone().expect("a morph has sections");
    let mesh = &scene.meshes[k].0;
    let topology = crate::mesh::Topology::build(mesh).map_err(err)?;
    let t = Instant::now();
    let morph = Morph::read(
        mesh,
        &topology,
        &sections,
        MorphOptions::default(),
        progress,
    )
    .map_err(err)?;
    let precompute_s = t.elapsed().as_secs_f64();
    let (lo, hi) = mesh
        .bounding_box()
        .ok_or_else(|| err(Error::invalid("the mesh has no vertices")))?;
    let (volume, placement) = morph.block(lo, hi, n).map_err(err)?;
    let file = interior_file(name, k, taken);
    let copied = file.with_file_name(format!(
        "{}-sections",
        file.file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into())
    ));
    Ok(Interior {
        line: InteriorLine {
            node: name.clone(),
            texture: interior.texture.clone(),
            method: interior.method,
            file,
            voxels: n,
            voxel_size: placement.scale,
            tet_mesh: None,
            lst: None,
            morph: Some(MorphLine {
                sections: copied.join("sections.toml"),
                surface: Some(copied.join("surface.obj")),
                exemplars: morph.exemplars().len(),
                regions: morph.regions(),
                block_origin: lo.to_array(),
                precompute_s,
            }),
        },
        key: None,
        volume: Some(volume),
        tets: None,
        lst: None,
        sections: Some(sections),
        surface: Some(mesh.clone()),
    })
}

/// The node's inside as tetrahedra at the default resolution, and its
/// report line (the file beside the block, as .vtk).
fn tet_mesh(
    mesh: &crate::mesh::TriMesh,
    block_file: &Path,
    node: &str,
    progress: &dyn Progress,
) -> Result<(TetLine, crate::tetra::TetMesh)> {
    let (tets, report) =
        crate::tetra::tetrahedralise_report(mesh, &crate::tetra::TetOptions::default(), progress)
            .map_err(|e| e.within(format!("node '{node}': tet mesh")))?;
    let quality = tets.quality();
    let line = TetLine {
        file: block_file.with_extension("vtk"),
        vertices: tets.num_vertices(),
        tets: tets.num_tets(),
        min_dihedral: quality.min_dihedral,
        max_dihedral: quality.max_dihedral,
        hausdorff_relative: report.hausdorff.map(|h| h.relative()),
    };
    Ok((line, tets))
}

/// The node's lapped solid texture (`[node.interior.lst]`) and its
/// report line.
#[allow(clippy::too_many_arguments)]
fn lapped(
    spec: &crate::scene::file::LstSpec,
    surface: &crate::mesh::TriMesh,
    tets: &crate::tetra::TetMesh,
    block_size: f64,
    block_file: &Path,
    seed: u64,
    node: &str,
    progress: &dyn Progress,
) -> Result<(LstLine, crate::solid::lst::LstModel)> {
    let start = std::time::Instant::now();
    let (model, stats, regions) = lap(spec, surface, tets, block_size, seed, node, progress)?;
    let line = LstLine {
        file: block_file.with_extension("lst"),
        kind: model.kind.name().into(),
        tets: tets.num_tets(),
        bytes: model.file_size(),
        stats,
        regions,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((line, model))
}

/// Lap a node's block through its tets as `[node.interior.lst]` asks
/// (the bake's and the viewer's cut plane's): the model, the stats of
/// the tets outside every region, and each region's line. Errors name
/// the node.
pub fn lap(
    spec: &crate::scene::file::LstSpec,
    surface: &crate::mesh::TriMesh,
    tets: &crate::tetra::TetMesh,
    block_size: f64,
    seed: u64,
    node: &str,
    progress: &dyn Progress,
) -> Result<(
    crate::solid::lst::LstModel,
    crate::solid::lst::FillStats,
    Vec<LstRegionLine>,
)> {
    use crate::solid::lst;
    let err = |e: Error| e.within(format!("node '{node}': [node.interior.lst]"));
    let kind = lst::TextureType::parse(&spec.kind).map_err(err)?;
    let (depth_outer, depth_inner) = match (&spec.depth_outer, &spec.depth_inner) {
        (Some(o), Some(i)) => lst::facet_depth_points(surface, o, i).map_err(err)?,
        (None, None) if !kind.needs_depth() => (Vec::new(), Vec::new()),
        _ => {
            return Err(err(Error::invalid(format!(
                "type {} needs depth_outer and depth_inner (two facets)",
                kind.name()
            ))));
        }
    };
    let scale = spec.scale.unwrap_or(block_size);
    let opts = lst::LstOptions {
        kind,
        scale,
        strokes: spec
            .strokes
            .iter()
            .map(|s| s.iter().map(|&p| glam::DVec3::from_array(p)).collect())
            .collect(),
        depth_outer,
        depth_inner,
        seed,
    };
    let wanted = spec
        .regions
        .iter()
        .map(|r| {
            Ok(lst::regions::FacetRegion {
                facet: r.facet.clone(),
                kind: lst::TextureType::parse(&r.kind)?,
                scale: r.scale.unwrap_or(scale),
                strokes: r
                    .strokes
                    .iter()
                    .map(|s| s.iter().map(|&p| glam::DVec3::from_array(p)).collect())
                    .collect(),
            })
        })
        .collect::<Result<Vec<_>>>()
        .map_err(err)?;
    let regions = lst::regions::facet_regions(surface, tets, &wanted, seed).map_err(err)?;
    let (model, mut stats) = lst::fill_regions(tets, &opts, &regions, progress).map_err(err)?;
    let main = stats.remove(0);
    let lines = regions
        .iter()
        .zip(stats)
        .map(|(r, stats)| LstRegionLine {
            facet: r.name.clone(),
            kind: r.options.kind.name().into(),
            tets: r.tets.len(),
            stats,
        })
        .collect();
    Ok((model, main, lines))
}

/// A node's interior as baked: its report line, block, tet mesh and
/// lapped solid texture.
pub(super) struct Interior {
    pub line: InteriorLine,
    /// The digest of its inputs (`interior_key`); none for a morph, which
    /// is made every time.
    key: Option<String>,
    /// None when the files already in the bake's folder are kept.
    volume: Option<Volume>,
    tets: Option<crate::tetra::TetMesh>,
    lst: Option<crate::solid::lst::LstModel>,
    /// A morph's sections file, copied beside the block.
    sections: Option<PathBuf>,
    /// A morph's domain, written beside its sections.
    surface: Option<crate::mesh::TriMesh>,
}

/// A node name as a file name: letters, digits, '-' and '_' kept, the rest
/// '_'.
fn file_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Write every interior's files under `out` (each atomically), and its
/// key last; the ones kept are already there.
pub(super) fn write(interiors: &[Interior], out: &Path) -> Result<()> {
    for interior in interiors {
        let Some(volume) = &interior.volume else {
            continue;
        };
        let path = out.join(&interior.line.file);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        // No key while the files change: a bake cut short leaves none.
        let key_file = path.with_extension("key");
        match std::fs::remove_file(&key_file) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Error::io(&key_file, e));
            }
            _ => {}
        }
        // A layered block's y axis is depth: the header says so, for the
        // LST reader and other tools.
        let depth_axis = (interior.line.method == InteriorMethod::Layered).then_some(1);
        volume.write_nrrd_with_depth(&path, depth_axis)?;
        if let (Some(line), Some(tets)) = (&interior.line.tet_mesh, &interior.tets) {
            crate::tetra::io::write_vtk(&out.join(&line.file), tets)?;
        }
        if let (Some(line), Some(model)) = (&interior.line.lst, &interior.lst) {
            model.write(&out.join(&line.file))?;
        }
        if let (Some(line), Some(sections)) = (&interior.line.morph, &interior.sections) {
            let dir = out.join(&line.sections);
            crate::solid::morph::copy_sections(sections, dir.parent().unwrap_or(out))?;
            if let (Some(path), Some(mesh)) = (&line.surface, &interior.surface) {
                crate::mesh::io::write_obj(&out.join(path), mesh, None)?;
            }
        }
        if let Some(key) = &interior.key {
            let stamp = KeyFile {
                key: key.clone(),
                line: interior.line.clone(),
            };
            let json = serde_json::to_string_pretty(&stamp).expect("the key serialises");
            crate::atomic::write_file(&key_file, |w| writeln!(w, "{json}"))?;
        }
    }
    Ok(())
}

/// What a node's interior key file holds: the digest of its inputs and
/// the report line of the files made from them.
#[derive(serde::Serialize, serde::Deserialize)]
struct KeyFile {
    key: String,
    line: InteriorLine,
}

/// The report line of the interior files in `out` for block `file`, when
/// its key file says they were made from inputs with digest `key` and
/// every file it names is there.
fn reusable(out: &Path, file: &Path, key: &str) -> Option<InteriorLine> {
    let text = std::fs::read_to_string(out.join(file).with_extension("key")).ok()?;
    let stamp: KeyFile = serde_json::from_str(&text).ok()?;
    (stamp.key == key
        && stamp.line.file == file
        && stamp.line.files().iter().all(|f| out.join(f).is_file()))
    .then_some(stamp.line)
}

/// A digest of everything node `k`'s interior is made from: the code (the
/// library's source digest, from build.rs), its `[node.interior]` and the
/// bake's block size in voxels, the node's mesh and facets, and its
/// sources (`sources_digest`).
fn interior_key(scene: &PreparedScene, k: usize, sources: &str) -> String {
    let mut digest = crate::digest::Digest::default();
    digest.feed(env!("ORGANTEX_SOURCE_DIGEST").as_bytes());
    let spec = scene.spec.nodes[k].interior.as_ref().expect("an interior");
    digest.feed(serde_json::to_string(spec).expect("serialises").as_bytes());
    digest.feed(&(scene.spec.bake.interior_voxels as u64).to_le_bytes());
    digest.feed(&(k as u64).to_le_bytes());
    let mesh = &scene.meshes[k].0;
    mesh.feed_geometry(&mut digest);
    if let Some(f) = &mesh.facets {
        for name in &f.names {
            digest.feed(name.as_bytes());
            digest.feed(&[0]);
        }
        for id in &f.of_face {
            digest.feed(&id.to_le_bytes());
        }
    }
    digest.feed(sources.as_bytes());
    digest.hex()
}

/// A digest of the bytes of an interior's tissue texture and its
/// photographs, read once for both its keys (`interior_key`, `kept_block`).
fn sources_digest(texture: &Path, photographs: &[PathBuf]) -> Result<String> {
    let mut digest = crate::digest::Digest::default();
    for file in std::iter::once(texture).chain(photographs.iter().map(PathBuf::as_path)) {
        digest.feed(&std::fs::read(file).map_err(|e| Error::io(file, e))?);
    }
    Ok(digest.hex())
}
