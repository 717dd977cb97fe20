//! From a scene file to baked facets: every node's mesh, its facets cut
//! into pieces with overlap rings, each piece unwrapped (seams seen from the
//! scene's cameras, the rest of the node hiding them), its seam bands, and
//! the layers every face shows (the compositor). Writing the .glb, atlases
//! and preview reads from here.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use super::composite::{Band, Compositor, Layer, Look, Overlay, Texture, Transform};
use super::file::{FacetSettings, MeshSpec, NodeSpec, SceneSpec, check_tissues};
use super::kept_unwrap::{self, KeptUnwrap};
use super::uterus;
use crate::blend::overlap::{FacetPiece, facet_pieces};
use crate::blend::seam::{BandFace, seam_bands};
use crate::db::{self, Database, Output};
use crate::error::{Error, Result};
use crate::mesh::repair::make_manifold;
use crate::mesh::{Facets, Topology, TriMesh, io};
use crate::progress::{CancelOnly, Progress, Span, check, timed};
use crate::segment::MeshReport;
use crate::unwrap::flatten::Method;
use crate::unwrap::intersect::overlapping_pairs;
use crate::unwrap::metrics::UvMetrics;
use crate::unwrap::visibility::{self, Viewpoints};
use crate::unwrap::{UnwrapOptions, unwrap_seen};

/// One facet, unwrapped, with its seam bands.
pub struct BakedFacet {
    pub settings: FacetSettings,
    /// The facet's piece, its mesh carrying the uvs.
    pub piece: FacetPiece,
    pub band: Vec<BandFace>,
    /// Per own face: whether a viewpoint sees any of its corners.
    pub seen: Vec<bool>,
    pub report: FacetReport,
    /// What its unwrap was made from (`kept_unwrap::key`), and whether it
    /// was taken from an earlier bake's folder rather than made.
    pub unwrap_key: String,
    pub unwrap_reused: bool,
}

impl BakedFacet {
    /// What a bake keeps of its unwrap for the next.
    pub fn kept_unwrap(&self) -> KeptUnwrap {
        KeptUnwrap {
            key: self.unwrap_key.clone(),
            uvs: self.piece.mesh.uvs.clone().expect("unwrapped"),
            seam_edges: self.report.seam_edges,
            metrics: self.report.metrics.clone(),
            flattening: self.report.flattening.clone(),
        }
    }
}

/// A node with its baked facets and what every face shows.
pub struct BakedNode {
    pub name: String,
    pub mesh: TriMesh,
    pub topology: Topology,
    /// Area-weighted vertex normals of the node (shared by its facets, so
    /// shading is smooth across facet borders).
    pub normals: Vec<DVec3>,
    pub facets: Vec<BakedFacet>,
    pub compositor: Compositor,
    /// The same without seam bands and overlap rings, for comparison.
    pub unblended: Compositor,
}

/// Where each database output used lives, by tissue id.
#[derive(Clone, Debug, Default)]
pub struct Tissues {
    /// By tissue id, and by `FacetSettings::colour_key` for a graded one.
    pub colour: HashMap<String, std::path::PathBuf>,
    pub height: HashMap<String, std::path::PathBuf>,
    pub overlay: HashMap<String, std::path::PathBuf>,
    pub layers: HashMap<String, std::path::PathBuf>,
    /// How each tissue takes light, by id.
    pub finish: HashMap<String, crate::db::Finish>,
}

impl Tissues {
    /// The built files of one output, by tissue id.
    pub fn of(&self, output: Output) -> &HashMap<String, std::path::PathBuf> {
        match output {
            Output::Colour => &self.colour,
            Output::Height => &self.height,
            Output::Overlay => &self.overlay,
            Output::Layers => &self.layers,
        }
    }

    /// How tissue `id` takes light (dry when the scene did not load it).
    pub fn finish_of(&self, id: &str) -> crate::db::Finish {
        self.finish
            .get(id)
            .copied()
            .unwrap_or(crate::db::Finish::DRY)
    }

    fn of_mut(&mut self, output: Output) -> &mut HashMap<String, std::path::PathBuf> {
        match output {
            Output::Colour => &mut self.colour,
            Output::Height => &mut self.height,
            Output::Overlay => &mut self.overlay,
            Output::Layers => &mut self.layers,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct FacetReport {
    pub node: String,
    pub facet: String,
    pub texture: String,
    pub faces: usize,
    pub ring_faces: usize,
    pub band_faces: usize,
    pub charts: usize,
    pub seam_edges: usize,
    pub seam_length: f64,
    pub flattening: Vec<Method>,
    /// Uv distortion figures over the whole piece, ring included.
    pub metrics: UvMetrics,
    /// For atlases: the facet's own faces whose uvs overlap another own
    /// face's (the ring's may overlap: it is drawn, through its uvs, into
    /// the earlier facet's atlas). Must be 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub atlas_overlaps: Option<usize>,
    /// The share of the facet's area the viewpoints see (a face counts when
    /// a view sees any of its corners).
    pub seen: f64,
    pub unwrap_s: f64,
}

/// A scene's nodes baked, with the textures they use.
pub struct BakedScene {
    pub nodes: Vec<BakedNode>,
    pub tissues: Tissues,
    pub spec: SceneSpec,
    /// Where the surface's time went: per node its visibility, unwraps
    /// (per facet, in parallel) and blending (the tissues' and meshes' are
    /// the `PreparedScene`'s).
    pub spans: Vec<Span>,
}

/// Build every node of `spec` (database outputs it needs are built first
/// if missing); `for_atlases`: with charts that do not overlap, so each
/// facet can be baked into an atlas.
pub fn build_scene(
    spec: &SceneSpec,
    for_atlases: bool,
    progress: &dyn Progress,
) -> Result<BakedScene> {
    build_prepared(&prepare_scene(spec, progress)?, for_atlases, None, progress)
}

/// A scene's tissues built and its nodes' meshes made: all its interiors
/// need (`bake::interior`), so they can start while the surface is cut
/// and flattened (`build_prepared`).
pub struct PreparedScene {
    pub spec: SceneSpec,
    pub tissues: Tissues,
    /// Per node, its mesh and topology.
    pub meshes: Vec<(TriMesh, Topology)>,
    /// Per node, what meshing its segmentation measured (none for a mesh
    /// file or a generated cavity).
    pub segmented: Vec<Option<MeshReport>>,
    /// The database outputs' and the meshes' times.
    pub spans: Vec<Span>,
}

/// The first part of `build_scene`: the database outputs the scene needs
/// (built first if missing) and every node's mesh.
pub fn prepare_scene(spec: &SceneSpec, progress: &dyn Progress) -> Result<PreparedScene> {
    let database = Database::open(&spec.database)?;
    let ids: Vec<String> = database.tissues.iter().map(|t| t.id.clone()).collect();
    check_tissues(spec, &ids)?;
    let mut spans = Vec::new();
    let tissues = timed(&mut spans, "tissues", "database", || {
        ensure_tissues(spec, &database, progress)
    })?;
    let (mut meshes, mut segmented) = (Vec::new(), Vec::new());
    for node in &spec.nodes {
        check(progress)?;
        let (mesh, topology, report) = timed(&mut spans, "mesh", &node.name, || {
            node_mesh_reported(node, progress)
        })?;
        meshes.push((mesh, topology));
        segmented.push(report);
    }
    Ok(PreparedScene {
        spec: spec.clone(),
        tissues,
        meshes,
        segmented,
        spans,
    })
}

/// The rest of `build_scene`: every node's visibility, unwraps and
/// blending, each facet's unwrap taken from `kept_in` (a bake's output
/// folder) where one made from the same inputs was kept there
/// (`kept_unwrap`).
pub fn build_prepared(
    prepared: &PreparedScene,
    for_atlases: bool,
    kept_in: Option<&Path>,
    progress: &dyn Progress,
) -> Result<BakedScene> {
    let PreparedScene {
        spec,
        tissues,
        meshes,
        ..
    } = prepared;
    let mut spans = Vec::new();
    let mut nodes = Vec::new();
    for (node_index, (node, mesh)) in spec.nodes.iter().zip(meshes).enumerate() {
        check(progress)?;
        nodes.push(build_node(
            spec,
            (node_index, node),
            mesh.clone(),
            tissues,
            for_atlases,
            kept_in,
            progress,
            &mut spans,
        )?);
    }
    Ok(BakedScene {
        nodes,
        tissues: tissues.clone(),
        spec: spec.clone(),
        spans,
    })
}

/// Build the database entries the scene uses whose outputs are missing or
/// out of date (`db::build::is_current`).
pub fn ensure_tissues(
    spec: &SceneSpec,
    database: &Database,
    progress: &dyn Progress,
) -> Result<Tissues> {
    let mut needed: Vec<(String, Output)> = Vec::new();
    for node in &spec.nodes {
        for f in &node.facets {
            needed.push((f.texture.clone(), Output::Colour));
            if let Some(m) = &f.grading.matched {
                needed.push((m.clone(), Output::Colour));
            }
            if f.bump > 0.0 {
                needed.push((f.texture.clone(), Output::Height));
            }
            if let Some(o) = &f.overlay {
                needed.push((o.clone(), Output::Overlay));
            }
        }
        if let Some(interior) = node.interior.as_ref().filter(|i| !i.texture.is_empty()) {
            needed.push((interior.texture.clone(), interior.method.output()));
        }
    }
    let mut tissues = Tissues::default();
    let mut checked: Vec<&str> = Vec::new();
    for (id, output) in &needed {
        let t = database.tissue(id)?;
        if !t.outputs.contains(output) {
            return Err(Error::invalid(format!(
                "{}: tissue '{id}' has no \"{}\" output; add it to its `outputs`{}",
                database.root.join("index.toml").display(),
                output.name(),
                match output {
                    Output::Colour if t.outputs.contains(&Output::Layers) => {
                        " (it is a layered exemplar: an interior uses it with method = \"layered\")"
                    }
                    _ => "",
                }
            )));
        }
        // Once per entry: checking reads its sources, building makes all
        // its outputs.
        if !checked.contains(&id.as_str()) {
            checked.push(id);
            if !db::build::is_current(database, t)? {
                db::build(database, std::slice::from_ref(id), &CancelOnly(progress))?;
            }
        }
        tissues
            .of_mut(*output)
            .insert(id.clone(), database.output_path(id, *output));
        tissues.finish.insert(id.clone(), t.finish());
    }
    // Graded colours, each made once and kept beside its entry's build.
    for f in spec.nodes.iter().flat_map(|n| &n.facets) {
        if !f.grading.is_identity() {
            let path = crate::db::build::graded_colour(database, &f.texture, &f.grading)?;
            tissues.colour.insert(f.colour_key(), path);
        }
    }
    Ok(tissues)
}

/// The node's mesh, read or generated, repaired if needed, with facets; and
/// its topology. `progress` sees a segmentation meshed (the one source
/// that takes seconds) and may cancel it.
pub fn node_mesh(node: &NodeSpec, progress: &dyn Progress) -> Result<(TriMesh, Topology)> {
    node_mesh_reported(node, progress).map(|(mesh, topology, _)| (mesh, topology))
}

/// `node_mesh`, with what meshing a segmentation measured (`organtex
/// mesh`'s figures: pieces kept and dropped, voids, volume, how near the
/// voxels), for the bake's report and the viewer.
pub fn node_mesh_reported(
    node: &NodeSpec,
    progress: &dyn Progress,
) -> Result<(TriMesh, Topology, Option<MeshReport>)> {
    let mut segmented = None;
    let mut mesh = match &node.mesh {
        MeshSpec::File(path) => io::read(path)?,
        MeshSpec::UterineCavity(params) => uterus::generate(params).map_err(|e| {
            node.origin.error(format!(
                "node '{}': mesh.uterine_cavity.{}: {}",
                node.name, e.key, e.msg
            ))
        })?,
        MeshSpec::Segmentation(seg) => {
            let (mesh, report) = segmentation_mesh(seg, progress).map_err(|e| match e {
                Error::Cancelled => e,
                e => node
                    .origin
                    .error(format!("node '{}': mesh.segmentation: {e}", node.name)),
            })?;
            segmented = Some(report);
            mesh
        }
    };
    let topology = match Topology::build(&mesh) {
        Ok(t) => t,
        Err(_) => {
            mesh = make_manifold(&mesh).0;
            Topology::build(&mesh)?
        }
    };
    if mesh.facets.is_none() {
        mesh.facets = Some(Facets {
            names: vec!["surface".into()],
            of_face: vec![0; mesh.num_faces()],
        });
    }
    Ok((mesh, topology, segmented))
}

/// The surface of a `[node.mesh.segmentation]`, as `organtex mesh` makes
/// it: closed, manifold, smoothed and decimated to its face budget, in the
/// scan's millimetres.
fn segmentation_mesh(
    seg: &crate::scene::file::Segmentation,
    progress: &dyn Progress,
) -> Result<(TriMesh, MeshReport)> {
    let choice = seg.choice().map_err(Error::invalid)?;
    let (volume, region) = crate::segment::open(&seg.file, &choice)?;
    let opts = crate::segment::MeshOptions {
        region,
        smooth: seg.smooth,
        all_components: seg.all_components,
        fill_voids: seg.fill_voids,
        faces: Some(seg.faces),
        max_handle: seg.max_handle,
        within_voxels: seg.within_voxels,
        smoother: seg.smoother,
    };
    crate::segment::mesh(&volume, &seg.file, &opts, progress)
}

/// Each of the mesh's facets' settings: the entry named after it, else the
/// entry named "*".
pub fn match_facets(node: &NodeSpec, mesh: &TriMesh) -> Result<Vec<FacetSettings>> {
    let names = &mesh.facets.as_ref().expect("set by node_mesh").names;
    for f in &node.facets {
        if f.name != "*" && !names.contains(&f.name) {
            return Err(f.origin.error(format!(
                "node '{}': facet '{}' is not a facet of the mesh (it has: {})",
                node.name,
                f.name,
                names.join(", ")
            )));
        }
    }
    names
        .iter()
        .map(|name| {
            node.facets
                .iter()
                .find(|f| &f.name == name)
                .or_else(|| node.facets.iter().find(|f| f.name == "*"))
                .cloned()
                .ok_or_else(|| {
                    node.origin.error(format!(
                        "node '{}': the mesh's facet '{name}' has no [[node.facet]] settings (add one named \"{name}\" or \"*\")",
                        node.name
                    ))
                })
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn build_node(
    spec: &SceneSpec,
    (node_index, node): (usize, &NodeSpec),
    (mesh, topology): (TriMesh, Topology),
    tissues: &Tissues,
    for_atlases: bool,
    kept_in: Option<&Path>,
    progress: &dyn Progress,
    spans: &mut Vec<Span>,
) -> Result<BakedNode> {
    let name = node.name.as_str();
    let settings = match_facets(node, &mesh)?;
    let viewpoints = if spec.cameras.is_empty() {
        Viewpoints::Orbit {
            views: spec.bake.views,
        }
    } else {
        Viewpoints::Cameras(
            spec.cameras
                .iter()
                .map(|c| DVec3::from_array(c.position))
                .collect(),
        )
    };
    let seen = timed(spans, "visibility", name, || {
        visibility::compute(&mesh, &topology, &viewpoints, progress)
    });
    let facets_start = Instant::now();
    let overlaps: Vec<f64> = settings.iter().map(|s| s.overlap).collect();
    let pieces = facet_pieces(&mesh, &topology, &overlaps);
    progress.stage("facets", pieces.len() as u64);
    let quiet = CancelOnly(progress);
    let names = mesh.facets.as_ref().expect("facets").names.clone();
    let facets: Vec<BakedFacet> = pieces
        .into_par_iter()
        .map(|piece| {
            let start = Instant::now();
            let facet_settings = settings[piece.facet as usize].clone();
            let piece_topo = Topology::build(&piece.mesh)?;
            let piece_seen = seen.restrict(&topology, &piece.vertex_origin, &piece_topo);
            let mut opts = UnwrapOptions {
                split_overlaps: for_atlases,
                atlas_faces: Some(piece.own),
                ..UnwrapOptions::default()
            };
            opts.seams.max_stretch = facet_settings.max_stretch;
            opts.seams.max_conformal = facet_settings.max_conformal;
            // A bake into a folder that kept this facet's unwrap, made from
            // the same piece, views and settings, takes it (`kept_unwrap`).
            let unwrap_key = kept_unwrap::key(&piece.mesh, &piece_seen, &opts);
            let kept = kept_in.and_then(|dir| {
                kept_unwrap::load(
                    &kept_unwrap::path(dir, node_index, piece.facet),
                    &unwrap_key,
                    piece.mesh.num_faces(),
                )
            });
            let unwrap_reused = kept.is_some();
            let mut piece = piece;
            let (topology, vertex_seen, seam_edges, m, flattening) = match kept {
                Some(kept) => {
                    let KeptUnwrap {
                        uvs,
                        seam_edges,
                        metrics,
                        flattening,
                        ..
                    } = kept;
                    piece.mesh.uvs = Some(uvs);
                    (
                        piece_topo,
                        piece_seen.vertex,
                        seam_edges,
                        metrics,
                        flattening,
                    )
                }
                None => {
                    let unwrapped =
                        unwrap_seen(&piece.mesh, piece_topo, piece_seen, &opts, &quiet)?;
                    piece.mesh = unwrapped.mesh;
                    let flattening = unwrapped
                        .report
                        .pieces
                        .iter()
                        .flat_map(|p| p.flattening.clone())
                        .collect();
                    (
                        unwrapped.topology,
                        unwrapped.visibility.vertex,
                        unwrapped.seams.len(),
                        unwrapped.report.metrics,
                        flattening,
                    )
                }
            };
            let band = seam_bands(&piece.mesh, &topology, spec.bake.seam_band);
            let seen: Vec<bool> = piece.mesh.triangles[..piece.own]
                .iter()
                .map(|t| t.iter().any(|&v| vertex_seen[v as usize] > 0.0))
                .collect();
            let (mut seen_area, mut area) = (0.0, 0.0);
            for (f, &s) in seen.iter().enumerate() {
                let a = piece.mesh.face_area(f);
                area += a;
                if s {
                    seen_area += a;
                }
            }
            let atlas_overlaps = for_atlases.then(|| {
                let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
                let mut faces: Vec<u32> =
                    overlapping_pairs(&layer.triangles[..piece.own], &layer.coords)
                        .into_iter()
                        .flatten()
                        .collect();
                faces.sort_unstable();
                faces.dedup();
                faces.len()
            });
            progress.advance(1);
            Ok(BakedFacet {
                report: FacetReport {
                    node: node.name.clone(),
                    facet: names[piece.facet as usize].clone(),
                    texture: facet_settings.texture.clone(),
                    faces: piece.own,
                    ring_faces: piece.mesh.num_faces() - piece.own,
                    band_faces: band.len(),
                    charts: m.charts,
                    seam_edges,
                    seam_length: m.seam_length,
                    flattening,
                    metrics: m,
                    atlas_overlaps,
                    seen: seen_area / area.max(1e-300),
                    unwrap_s: start.elapsed().as_secs_f64(),
                },
                settings: facet_settings,
                piece,
                band,
                seen,
                unwrap_key,
                unwrap_reused,
            })
        })
        .collect::<Result<_>>()?;
    spans.push(Span {
        stage: "unwraps and bands".into(),
        item: name.into(),
        seconds: facets_start.elapsed().as_secs_f64(),
        parallel: false,
    });
    for f in &facets {
        spans.push(Span {
            stage: if f.unwrap_reused {
                "unwrap reused"
            } else {
                "unwrap"
            }
            .into(),
            item: format!("{}/{}", f.report.node, f.report.facet),
            seconds: f.report.unwrap_s,
            parallel: true,
        });
    }
    let normals = mesh.vertex_normals();
    let (compositor, unblended) = timed(spans, "blending", name, || {
        compositors(&mesh, &facets, tissues)
    })?;
    Ok(BakedNode {
        name: node.name.clone(),
        mesh,
        topology,
        normals,
        facets,
        compositor,
        unblended,
    })
}

/// A facet's texture transform (KHR_texture_transform): one copy of the
/// texture per `tile_size` mesh units, rotated and shifted.
pub fn colour_transform(s: &FacetSettings) -> Transform {
    Transform {
        scale: [1.0 / s.tile_size; 2],
        rotation: s.rotation.to_radians(),
        offset: s.offset,
    }
}

pub fn overlay_transform(s: &FacetSettings) -> Transform {
    Transform {
        scale: [1.0 / s.overlay_tile_size; 2],
        rotation: s.rotation.to_radians(),
        offset: s.offset,
    }
}

/// Reorder per-corner values of a piece face into its node face's order.
fn to_node_order<T: Copy + Default>(values: [T; 3], order: [usize; 3]) -> [T; 3] {
    let mut out = [T::default(); 3];
    for i in 0..3 {
        out[order[i]] = values[i];
    }
    out
}

/// The layers of every face of the node, bottom first: the own facet's
/// look (with its seam band), then the rings of later facets (with theirs)
/// in scene order: a later facet blends over everything of the earlier
/// ones. And the same with only the own look (no band, no ring), for
/// comparison.
fn compositors(
    mesh: &TriMesh,
    facets: &[BakedFacet],
    tissues: &Tissues,
) -> Result<(Compositor, Compositor)> {
    let mut textures: Vec<Texture> = Vec::new();
    let mut index: HashMap<std::path::PathBuf, usize> = HashMap::new();
    let mut texture = |path: &Path| -> Result<usize> {
        if let Some(&i) = index.get(path) {
            return Ok(i);
        }
        textures.push(Texture::load(path)?);
        index.insert(path.to_path_buf(), textures.len() - 1);
        Ok(textures.len() - 1)
    };
    let n = mesh.num_faces();
    let mut looks = Vec::with_capacity(facets.len());
    let mut base: Vec<Option<Layer>> = vec![None; n];
    let mut stack: Vec<Vec<(u32, Layer)>> = vec![Vec::new(); n];
    for (look, bf) in facets.iter().enumerate() {
        let s = &bf.settings;
        looks.push(Look {
            colour: texture(&tissues.colour[&s.colour_key()])?,
            transform: colour_transform(s),
            overlay: match &s.overlay {
                Some(o) => Some(Overlay {
                    texture: texture(&tissues.overlay[o])?,
                    transform: overlay_transform(s),
                    opacity: s.overlay_opacity as f32,
                }),
                None => None,
            },
        });
        let uvs = bf.piece.mesh.uvs.as_ref().expect("unwrapped");
        let mut band: Vec<Option<&BandFace>> = vec![None; bf.piece.mesh.num_faces()];
        for b in &bf.band {
            band[b.face as usize] = Some(b);
        }
        for (f, band) in band.iter().enumerate() {
            let order = bf.piece.corner_order(mesh, f);
            let layer = Layer {
                look,
                uv: to_node_order(uvs.triangles[f].map(|c| uvs.coords[c as usize]), order),
                alpha: to_node_order(
                    bf.piece.mesh.triangles[f].map(|v| bf.piece.alpha[v as usize]),
                    order,
                ),
                band: band.map(|b| Band {
                    uv: to_node_order(b.uv, order),
                    alpha: to_node_order(b.alpha, order),
                }),
            };
            let node_face = bf.piece.face_origin[f] as usize;
            if f < bf.piece.own {
                base[node_face] = Some(layer);
            } else {
                stack[node_face].push((bf.piece.facet, layer));
            }
        }
    }
    let mut blended = Vec::with_capacity(n);
    let mut plain = Vec::with_capacity(n);
    for f in 0..n {
        let own = base[f].clone().expect("every face belongs to a facet");
        stack[f].sort_by_key(|(facet, _)| *facet);
        blended.push(
            std::iter::once(own.clone())
                .chain(stack[f].drain(..).map(|(_, l)| l))
                .collect(),
        );
        plain.push(vec![Layer { band: None, ..own }]);
    }
    Ok((
        Compositor {
            textures: textures.clone(),
            looks: looks.clone(),
            layers: blended,
        },
        Compositor {
            textures,
            looks,
            layers: plain,
        },
    ))
}
