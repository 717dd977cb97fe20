//! Scene files (TOML), documented with examples in scenes/README.md.
//!
//! A scene is cameras and nodes; a node is a mesh (a file, whose groups and
//! materials are its facets, or a generated organ) and the settings of each
//! facet: the database tissue, its texture transform (tile size, rotation,
//! offset), bump, an overlay and its opacity, and the width of the overlap
//! ring in which it blends into the facets before it. Scenes may include
//! other scenes. Unknown keys and bad values are errors naming the key and
//! its line.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::uterus::CavityParams;
use crate::db::colour::Grading;
use crate::error::{Error, Result};
use crate::memory::{check, product};
use crate::solid::InteriorMethod;
use crate::synth::block::{MAX_BLOCK, Method};
use crate::unwrap::seamster::SeamOptions;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    /// Other scene files whose cameras and nodes join this one's.
    #[serde(default)]
    include: Vec<Spanned<PathBuf>>,
    /// The tissue database (default: the one next to the scenes folder).
    database: Option<PathBuf>,
    #[serde(default, rename = "camera")]
    cameras: Vec<Spanned<Camera>>,
    #[serde(default, rename = "node")]
    nodes: Vec<Node>,
    #[serde(default)]
    bake: Option<Spanned<BakeSettings>>,
}

/// A viewpoint: the first is the preview's; all are the endoscope path from
/// which seam visibility is counted (when the scene has any).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov: f64,
}

fn default_fov() -> f64 {
    70.0
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Node {
    name: String,
    mesh: Spanned<MeshSource>,
    #[serde(default, rename = "facet")]
    facets: Vec<FacetEntry>,
    #[serde(default)]
    interior: Option<Spanned<Interior>>,
}

/// Exactly one of `file`, a generator, or a segmentation.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSource {
    file: Option<Spanned<PathBuf>>,
    uterine_cavity: Option<CavityParams>,
    segmentation: Option<Spanned<Segmentation>>,
}

/// `[node.mesh.segmentation]`: one region of a CT or MRI segmentation
/// (`organtex mesh`'s input and options), meshed when the scene is built.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Segmentation {
    /// The label map or probability map (.nii, .nii.gz, .nrrd, .seg.nrrd),
    /// relative to the scene file; absolute once loaded.
    pub file: PathBuf,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub segment: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    /// Smoothing iterations.
    #[serde(default = "default_smooth")]
    pub smooth: usize,
    /// "taubin" (default) or "sinc" (windowed sinc; `mesh --smoother`).
    #[serde(default, skip_serializing_if = "crate::segment::Smoother::is_default")]
    pub smoother: crate::segment::Smoother,
    /// The face budget: a raw voxel surface has hundreds of thousands,
    /// more than the unwrap and the tet mesh need.
    #[serde(default = "default_segmentation_faces")]
    pub faces: usize,
    #[serde(default)]
    pub all_components: bool,
    #[serde(default)]
    pub fill_voids: bool,
    /// Cut or plug handles thinner than this, mm (`mesh --max-handle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_handle: Option<f64>,
    /// Hold the voxel corners within this, voxels (`--within-voxels`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub within_voxels: Option<f64>,
}

fn default_smooth() -> usize {
    crate::segment::DEFAULT_SMOOTH
}

fn default_segmentation_faces() -> usize {
    20_000
}

impl Segmentation {
    /// The region `choice` of `file`, with a scene's defaults (20 Taubin
    /// iterations, 20,000 faces, the largest piece, voids kept, not specks).
    pub fn of(file: PathBuf, choice: &crate::segment::Choice) -> Segmentation {
        use crate::segment::Choice;
        Segmentation {
            file,
            label: match choice {
                Choice::Label(l) => Some(*l),
                _ => None,
            },
            segment: match choice {
                Choice::Segment(s) => Some(s.clone()),
                _ => None,
            },
            threshold: match choice {
                Choice::Threshold(t) => Some(*t),
                _ => None,
            },
            smooth: default_smooth(),
            smoother: Default::default(),
            faces: default_segmentation_faces(),
            all_components: false,
            fill_voids: false,
            max_handle: None,
            within_voxels: None,
        }
    }

    /// What the region is, as `organtex mesh` takes it.
    pub fn choice(&self) -> std::result::Result<crate::segment::Choice, String> {
        use crate::segment::Choice;
        match (self.label, &self.segment, self.threshold) {
            (Some(l), None, None) => Ok(Choice::Label(l)),
            (None, Some(s), None) => Ok(Choice::Segment(s.clone())),
            (None, None, Some(t)) if t.is_finite() => Ok(Choice::Threshold(t)),
            (None, None, Some(t)) => Err(format!("threshold {t} is not a number")),
            _ => Err("give exactly one of `label`, `segment` or `threshold`".into()),
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FacetEntry {
    name: Spanned<String>,
    texture: Spanned<String>,
    #[serde(default = "default_tile")]
    tile_size: Spanned<f64>,
    #[serde(default = "zero")]
    rotation: Spanned<f64>,
    #[serde(default = "no_offset")]
    offset: Spanned<[f64; 2]>,
    #[serde(default = "zero")]
    bump: Spanned<f64>,
    overlay: Option<Spanned<String>>,
    #[serde(default = "default_opacity")]
    overlay_opacity: Spanned<f64>,
    overlay_tile_size: Option<Spanned<f64>>,
    #[serde(default = "zero")]
    overlap: Spanned<f64>,
    #[serde(default = "default_max_stretch")]
    max_stretch: Spanned<f64>,
    #[serde(default = "default_max_conformal")]
    max_conformal: Spanned<f64>,
    #[serde(default = "zero")]
    hue: Spanned<f64>,
    #[serde(default = "unit")]
    saturation: Spanned<f64>,
    #[serde(default = "unit")]
    brightness: Spanned<f64>,
    #[serde(rename = "match")]
    matched: Option<Spanned<String>>,
}

fn default_tile() -> Spanned<f64> {
    Spanned::new(0..0, 10.0)
}
fn zero() -> Spanned<f64> {
    Spanned::new(0..0, 0.0)
}
fn unit() -> Spanned<f64> {
    Spanned::new(0..0, 1.0)
}
fn no_offset() -> Spanned<[f64; 2]> {
    Spanned::new(0..0, [0.0; 2])
}
fn default_opacity() -> Spanned<f64> {
    Spanned::new(0..0, 0.6)
}
fn default_max_stretch() -> Spanned<f64> {
    Spanned::new(0..0, SeamOptions::default().max_stretch)
}
fn default_max_conformal() -> Spanned<f64> {
    Spanned::new(0..0, SeamOptions::default().max_conformal)
}

/// The solid texture filling a node's inside, for cut surfaces (baked by
/// the 3D synthesis stage).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interior {
    /// Database tissue whose exemplar the block is synthesised from
    /// (not used by method = "morph", which may leave it out).
    #[serde(default)]
    pub texture: String,
    /// Mesh units covered by one block.
    #[serde(default = "default_block_size")]
    pub block_size: f64,
    /// How the block is made: "fnpts" (sharp; streaks on cuts across x),
    /// "layered" (by depth from the tissue's layered exemplar, seed 002),
    /// "optimize" (no streaks, softer) or "stereology" (particles in a
    /// binder measured in `photographs`, seed 001) or "morph" (morphed
    /// from the photographed cuts of `sections`, seed 003).
    #[serde(default)]
    pub method: InteriorMethod,
    /// The sections file for `method = "morph"` (photographs of cuts
    /// placed as planes in the node; `organtex morph --help`), relative to
    /// the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sections: Option<PathBuf>,
    /// Photographs of sections for `method = "stereology"`, relative to
    /// the scene file (none: the tissue's colour texture).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub photographs: Vec<PathBuf>,
    /// Which colour class of the photographs is the particles for
    /// `method = "stereology"`: "auto" (the binder is the connected
    /// phase, else the minority by area), "light", "dark" or a colour
    /// "RRGGBB" (`organtex stereology --help`).
    #[serde(
        default,
        skip_serializing_if = "crate::solid::stereology::Particles::is_auto"
    )]
    pub particles: crate::solid::stereology::Particles,
    /// Also fill the node's inside with tetrahedra (isosurface stuffing at
    /// the default resolution), written as interior/NODE.vtk for the
    /// simulator's physics and for lapped solid textures.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub tet_mesh: bool,
    /// Fill the inside with a lapped solid texture of the block (seed
    /// 000), written as interior/NODE.lst: patches oriented by strokes and
    /// layered by depth between two facets.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lst: Option<LstSpec>,
}

/// `[node.interior.lst]`: how to lap the node's block through it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LstSpec {
    /// Seed 000's texture type: "0", "1a", "1b", "2a" or "2b".
    #[serde(rename = "type")]
    pub kind: String,
    /// The facet at depth 0 (types 1b, 2a, 2b), e.g. "serosa".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_outer: Option<String>,
    /// The facet at depth 1, e.g. "wall".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_inner: Option<String>,
    /// Polylines inside the node along which the texture's first axis runs
    /// (types 1a, 2a, 2b).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strokes: Vec<Vec<[f64; 3]>>,
    /// Mesh units one patch spans (types 0, 1a, 2a; default: the block
    /// size).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// `[[node.interior.lst.region]]`: parts lapped with a texture of
    /// their own, such as a myoma's whorled fibres in the layered wall.
    #[serde(default, rename = "region", skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionSpec>,
}

/// A region of the interior: the ball fitted to a facet (a myoma's), with
/// its own texture type.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    pub facet: String,
    /// "0" or "1a" (the default: fibres).
    #[serde(rename = "type", default = "default_region_type")]
    pub kind: String,
    /// Polylines the fibres follow (1a; default: rings round the facet's
    /// axis, a myoma's whorl).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strokes: Vec<Vec<[f64; 3]>>,
    /// Mesh units one patch spans (default: the lst's scale).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
}

fn default_region_type() -> String {
    "1a".into()
}

fn default_block_size() -> f64 {
    10.0
}

/// How the bake runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BakeSettings {
    /// Rings of triangles on each side of a seam carrying its blend.
    #[serde(default = "default_band")]
    pub seam_band: usize,
    /// Orthographic views for seam visibility when the scene has no cameras.
    #[serde(default = "default_views")]
    pub views: usize,
    /// Voxels a side of each node's interior block (a multiple of 16, at
    /// most `MAX_BLOCK`).
    #[serde(default = "default_interior_voxels")]
    pub interior_voxels: usize,
    /// The preview's light: "endoscope" (the scope's spot light, wet
    /// highlights) or "even" (for judging the textures alone).
    #[serde(default, skip_serializing_if = "is_endoscope")]
    pub preview_lighting: Lighting,
    /// The preview seen through the scope: its circular field, dark past
    /// the rim, with the lens's vignetting.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub preview_scope: bool,
}

/// How a frame is lit: the bake's preview (`[bake] preview_lighting`), and
/// the viewer's choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Lighting {
    /// The scope's light at the camera: a spot light falling off with the
    /// square of the distance, wet highlights, tone mapped.
    #[default]
    Endoscope,
    /// An even light at the camera, no highlights: for judging a texture
    /// alone.
    Even,
}

impl Lighting {
    pub const ALL: [Lighting; 2] = [Lighting::Endoscope, Lighting::Even];

    pub fn name(self) -> &'static str {
        match self {
            Lighting::Endoscope => "endoscope",
            Lighting::Even => "even",
        }
    }
}

fn is_endoscope(l: &Lighting) -> bool {
    *l == Lighting::Endoscope
}

fn default_band() -> usize {
    3
}
fn default_views() -> usize {
    128
}
fn default_interior_voxels() -> usize {
    64
}

impl Default for BakeSettings {
    fn default() -> Self {
        BakeSettings {
            seam_band: default_band(),
            views: default_views(),
            interior_voxels: default_interior_voxels(),
            preview_lighting: Lighting::default(),
            preview_scope: false,
        }
    }
}

/// Where a node's mesh comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshSpec {
    File(PathBuf),
    UterineCavity(CavityParams),
    Segmentation(Segmentation),
}

/// A facet's settings, checked.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FacetSettings {
    /// The facet's name in the mesh ("surface" for a mesh without facets;
    /// "*" for every facet not named otherwise).
    pub name: String,
    pub texture: String,
    /// Mesh units covered by one copy of the texture.
    pub tile_size: f64,
    /// Degrees, counter-clockwise.
    pub rotation: f64,
    /// In texture widths.
    pub offset: [f64; 2],
    /// Normal-map strength, 0 for none.
    pub bump: f64,
    pub overlay: Option<String>,
    pub overlay_opacity: f64,
    pub overlay_tile_size: f64,
    /// Width of the ring, into the facets listed before this one, over which
    /// this facet's texture fades from 1 to 0.
    pub overlap: f64,
    /// The unwrap's bounds for this facet (`SeamOptions`): seams are cut
    /// until its flattening's area_log is at most `max_stretch` ...
    pub max_stretch: f64,
    /// ... and its conf_mean at most `max_conformal`.
    pub max_conformal: f64,
    /// The tissue's colour grading (`hue`, `saturation`, `brightness`,
    /// `match`).
    #[serde(flatten)]
    pub grading: Grading,
    /// Where the facet's texture is named, for errors found later.
    #[serde(skip)]
    pub origin: Origin,
}

impl FacetSettings {
    /// The name of the facet's colour texture, graded as it asks
    /// (`Tissues::colour`'s key).
    pub fn colour_key(&self) -> String {
        self.grading.key(&self.texture)
    }
}

/// A place in a scene file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Origin {
    pub file: PathBuf,
    pub line: usize,
}

impl Origin {
    pub fn error(&self, msg: impl Into<String>) -> Error {
        Error::at_line(&self.file, self.line, msg)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct NodeSpec {
    pub name: String,
    pub mesh: MeshSpec,
    pub facets: Vec<FacetSettings>,
    pub interior: Option<Interior>,
    /// Where the mesh is declared, for errors found when it is built.
    pub origin: Origin,
}

/// A scene file with its includes, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    pub path: PathBuf,
    pub name: String,
    pub database: PathBuf,
    pub cameras: Vec<Camera>,
    pub nodes: Vec<NodeSpec>,
    pub bake: BakeSettings,
}

/// The tissue database bundled with organtex, used when a scene names
/// none.
pub fn default_database() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("database")
}

/// Line of a byte offset (counted in bytes, so any offset is safe).
fn line_of(text: &str, offset: usize) -> usize {
    let before = &text.as_bytes()[..offset.min(text.len())];
    before.iter().filter(|&&b| b == b'\n').count() + 1
}

/// Views of seam visibility a scene may ask for (as `organtex unwrap
/// --views`): each is a render of the whole mesh.
const MAX_VIEWS: usize = 1024;

/// Read a scene and everything it includes.
pub fn load(path: &Path) -> Result<SceneSpec> {
    let mut stack = Vec::new();
    let mut spec = load_into(path, &mut stack)?;
    spec.path = path.to_path_buf();
    if spec.nodes.is_empty() {
        return Err(Error::format(path, "the scene has no [[node]]"));
    }
    // Interior blocks are synthesised one after another and all kept until
    // written: the largest synthesis plus 3 bytes a voxel per block.
    let interiors: Vec<&Interior> = spec
        .nodes
        .iter()
        .filter_map(|n| n.interior.as_ref())
        .collect();
    if let Some(worst) = interiors
        .iter()
        .map(|i| {
            // Stereology copies its photograph by guided FNPTS; a morph
            // samples its block at the same size (counted as the same); a
            // layered block optimises, as `synth3d --layered` counts it.
            let method = match i.method {
                InteriorMethod::Layered => Method::Optimize,
                m => m.block().unwrap_or(Method::Fnpts),
            };
            crate::synth::block::memory_bytes(spec.bake.interior_voxels, 1, method)
        })
        .max()
    {
        let n = spec.bake.interior_voxels;
        let kept = product(&[n as u64, n as u64, n as u64, 3, interiors.len() as u64]);
        let blocks = match interiors.len() {
            1 => "1 interior block".to_string(),
            k => format!("{k} interior blocks"),
        };
        check(
            &format!("[bake] interior_voxels: synthesising {blocks} of {n}^3 voxels"),
            worst.saturating_add(kept),
        )
        .map_err(|msg| Error::format(path, msg))?;
    }
    Ok(spec)
}

fn load_into(path: &Path, stack: &mut Vec<PathBuf>) -> Result<SceneSpec> {
    // A device or pipe (an include of /dev/zero, found by fuzzing) would
    // be read without end.
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::format(path, "is not a regular file, not a scene"));
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| line_of(&text, s.start));
        match line {
            Some(line) => Error::at_line(path, line, e.message().to_string()),
            None => Error::format(path, e.message().to_string()),
        }
    })?;
    let at = |span: std::ops::Range<usize>, msg: String| {
        Error::at_line(path, line_of(&text, span.start), msg)
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let canonical = path.canonicalize().map_err(|e| Error::io(path, e))?;
    stack.push(canonical);

    let bake = file.bake.as_ref();
    let mut spec = SceneSpec {
        path: path.to_path_buf(),
        name: file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into()
        }),
        database: match &file.database {
            Some(d) => dir.join(d),
            None => default_database(),
        },
        cameras: file.cameras.iter().map(|c| c.get_ref().clone()).collect(),
        nodes: Vec::new(),
        bake: bake.map(|b| b.get_ref().clone()).unwrap_or_default(),
    };
    // The line setting `key` in the [bake] table, else the table's line.
    let bake_error = |key: &str, msg: String| match bake {
        Some(b) => {
            let start = b.span().start;
            let line = line_of(&text, start);
            let set = text
                .get(start..)
                .unwrap_or("")
                .lines()
                .take_while(|l| !l.trim_start().starts_with("[["))
                .position(|l| {
                    l.trim_start()
                        .strip_prefix(key)
                        .is_some_and(|rest| rest.trim_start().starts_with('='))
                });
            Error::at_line(path, line + set.unwrap_or(0), msg)
        }
        None => Error::format(path, msg),
    };
    let voxels = spec.bake.interior_voxels;
    if !(16..=MAX_BLOCK).contains(&voxels) || !voxels.is_multiple_of(16) {
        return Err(bake_error(
            "interior_voxels",
            format!(
                "[bake] interior_voxels: {voxels} is not a multiple of 16 from 16 to {MAX_BLOCK}"
            ),
        ));
    }
    let views = spec.bake.views;
    if !(1..=MAX_VIEWS).contains(&views) {
        return Err(bake_error(
            "views",
            format!("[bake] views: must be from 1 to {MAX_VIEWS}, not {views}"),
        ));
    }
    for c in &file.cameras {
        let cam = c.get_ref();
        let finite = |p: [f64; 3]| p.iter().all(|x| x.is_finite());
        if !(finite(cam.position) && finite(cam.look_at)) {
            return Err(at(
                c.span(),
                format!(
                    "camera: position and look_at must be finite numbers, not {:?} and {:?}",
                    cam.position, cam.look_at
                ),
            ));
        }
        if !(1.0..=170.0).contains(&cam.fov) || cam.position == cam.look_at {
            return Err(at(
                c.span(),
                format!(
                    "camera at {:?}: fov must be from 1 to 170 degrees and look_at differ from position",
                    cam.position
                ),
            ));
        }
    }
    for inc in &file.include {
        let target = dir.join(inc.get_ref());
        let canonical = target
            .canonicalize()
            .map_err(|e| at(inc.span(), format!("include: {}: {e}", target.display())))?;
        if let Some(first) = stack.iter().position(|p| *p == canonical) {
            let chain: Vec<String> = stack[first..]
                .iter()
                .chain([&canonical])
                .map(|p| p.display().to_string())
                .collect();
            let what = if first + 1 == stack.len() {
                "the scene includes itself"
            } else {
                "the includes form a cycle"
            };
            return Err(at(
                inc.span(),
                format!("include: {what} ({})", chain.join(" -> ")),
            ));
        }
        let included = load_into(&target, stack)?;
        spec.cameras.extend(included.cameras);
        spec.nodes.extend(included.nodes);
    }
    for node in &file.nodes {
        spec.nodes.push(node_spec(node, dir, path, &text)?);
    }
    let mut names = std::collections::HashSet::new();
    for n in &spec.nodes {
        if !names.insert(n.name.clone()) {
            return Err(Error::format(
                path,
                format!("node '{}' is defined twice", n.name),
            ));
        }
    }
    stack.pop();
    Ok(spec)
}

fn node_spec(node: &Node, dir: &Path, path: &Path, text: &str) -> Result<NodeSpec> {
    let at = |span: std::ops::Range<usize>, key: &str, msg: String| {
        Error::at_line(
            path,
            line_of(text, span.start),
            format!("node '{}': {key}: {msg}", node.name),
        )
    };
    let source = node.mesh.get_ref();
    let mesh = match (&source.file, &source.uterine_cavity, &source.segmentation) {
        (Some(file), None, None) => {
            let full = dir.join(file.get_ref());
            if !full.is_file() {
                return Err(at(
                    file.span(),
                    "mesh.file",
                    format!("{} not found", full.display()),
                ));
            }
            MeshSpec::File(full)
        }
        (None, Some(params), None) => MeshSpec::UterineCavity(params.clone()),
        (None, None, Some(seg)) => {
            let mut spec = seg.get_ref().clone();
            spec.file = dir.join(&spec.file);
            let here = |msg: String| at(seg.span(), "mesh.segmentation", msg);
            spec.choice().map_err(here)?;
            if !spec.file.is_file() {
                return Err(here(format!("{} not found", spec.file.display())));
            }
            if spec.faces < 4 {
                return Err(here(format!(
                    "faces must be at least 4, not {}",
                    spec.faces
                )));
            }
            if spec.smooth > 10_000 {
                return Err(here(format!(
                    "smooth must be from 0 to 10000 iterations, not {}",
                    spec.smooth
                )));
            }
            MeshSpec::Segmentation(spec)
        }
        _ => {
            return Err(at(
                node.mesh.span(),
                "mesh",
                "give exactly one of `file`, `[node.mesh.uterine_cavity]` or \
                 `[node.mesh.segmentation]`"
                    .into(),
            ));
        }
    };
    let mut facets = Vec::new();
    for f in &node.facets {
        let name = f.name.get_ref().clone();
        // A value within its range, or an error naming the key and line.
        let checked =
            |v: &Spanned<f64>, k: &str, ok: fn(f64) -> bool, range: &str| -> Result<f64> {
                let x = *v.get_ref();
                if x.is_finite() && ok(x) {
                    Ok(x)
                } else {
                    Err(at(
                        v.span(),
                        &format!("facet '{name}' {k}"),
                        format!("must be {range}, not {x}"),
                    ))
                }
            };
        let positive = |v: &Spanned<f64>, k: &str| checked(v, k, |x| x > 0.0, "a positive number");
        let overlap = checked(&f.overlap, "overlap", |x| x >= 0.0, "0 or more")?;
        let bump = checked(
            &f.bump,
            "bump",
            |x| (0.0..=10.0).contains(&x),
            "from 0 to 10",
        )?;
        let opacity = checked(
            &f.overlay_opacity,
            "overlay_opacity",
            |x| (0.0..=1.0).contains(&x),
            "from 0 to 1",
        )?;
        let tile_size = positive(&f.tile_size, "tile_size")?;
        let max_stretch = positive(&f.max_stretch, "max_stretch")?;
        let max_conformal = checked(&f.max_conformal, "max_conformal", |x| x >= 1.0, "1 or more")?;
        let rotation = checked(
            &f.rotation,
            "rotation",
            |_| true,
            "a finite number of degrees",
        )?;
        let grading = Grading {
            hue: checked(&f.hue, "hue", |_| true, "a finite number of degrees")?,
            saturation: checked(
                &f.saturation,
                "saturation",
                |x| (0.0..=4.0).contains(&x),
                "from 0 to 4",
            )?,
            brightness: checked(
                &f.brightness,
                "brightness",
                |x| x > 0.0 && x <= 4.0,
                "above 0, at most 4",
            )?,
            matched: f.matched.as_ref().map(|m| m.get_ref().clone()),
        };
        let offset = *f.offset.get_ref();
        if !offset.iter().all(|x| x.is_finite()) {
            return Err(at(
                f.offset.span(),
                &format!("facet '{name}' offset"),
                format!("must be two finite numbers, not {offset:?}"),
            ));
        }
        facets.push(FacetSettings {
            name: name.clone(),
            texture: f.texture.get_ref().clone(),
            tile_size,
            rotation,
            offset,
            bump,
            overlay: f.overlay.as_ref().map(|o| o.get_ref().clone()),
            overlay_opacity: opacity,
            overlay_tile_size: match &f.overlay_tile_size {
                Some(t) => positive(t, "overlay_tile_size")?,
                None => 2.0 * tile_size,
            },
            overlap,
            max_stretch,
            max_conformal,
            grading,
            origin: Origin {
                file: path.to_path_buf(),
                line: line_of(text, f.texture.span().start),
            },
        });
    }
    if let Some(interior) = &node.interior {
        let size = interior.get_ref().block_size;
        if !(size.is_finite() && size > 0.0) {
            return Err(at(
                interior.span(),
                "interior block_size",
                format!("must be a positive number of mesh units, not {size}"),
            ));
        }
        let i = interior.get_ref();
        if i.method != InteriorMethod::Stereology && !i.photographs.is_empty() {
            return Err(at(
                interior.span(),
                "interior photographs",
                "are measured by method = \"stereology\" alone".to_string(),
            ));
        }
        match (&i.sections, i.method == InteriorMethod::Morph) {
            (None, true) => {
                return Err(at(
                    interior.span(),
                    "interior sections",
                    "method = \"morph\" needs sections = \"FILE.toml\" (the placed photographs)"
                        .to_string(),
                ));
            }
            (Some(_), false) => {
                return Err(at(
                    interior.span(),
                    "interior sections",
                    "are morphed by method = \"morph\" alone".to_string(),
                ));
            }
            (Some(s), true) if !dir.join(s).is_file() => {
                return Err(at(
                    interior.span(),
                    "interior sections",
                    format!("{} not found", dir.join(s).display()),
                ));
            }
            _ => {}
        }
        if i.texture.is_empty() && i.method != InteriorMethod::Morph {
            return Err(at(
                interior.span(),
                "interior texture",
                "is needed: the tissue the block is synthesised from".to_string(),
            ));
        }
        if i.method == InteriorMethod::Morph && (i.lst.is_some() || i.tet_mesh) {
            return Err(at(
                interior.span(),
                "interior",
                "method = \"morph\" colours the node from its sections alone: \
                 leave out lst and tet_mesh"
                    .to_string(),
            ));
        }
        if let Some(missing) = i.photographs.iter().find(|p| !dir.join(p).is_file()) {
            return Err(at(
                interior.span(),
                "interior photographs",
                format!("{} not found", dir.join(missing).display()),
            ));
        }
        if let Some(lst) = &interior.get_ref().lst {
            let bad = |msg: String| at(interior.span(), "interior lst", msg);
            let kind =
                crate::solid::lst::TextureType::parse(&lst.kind).map_err(|e| bad(e.to_string()))?;
            if let Some(scale) = lst.scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(bad(format!(
                    "scale must be a positive number of mesh units, not {scale}"
                )));
            }
            if kind.needs_depth() != (lst.depth_outer.is_some() && lst.depth_inner.is_some()) {
                return Err(bad(format!(
                    "type {} {} depth_outer and depth_inner",
                    kind.name(),
                    if kind.needs_depth() {
                        "needs"
                    } else {
                        "takes no"
                    }
                )));
            }
            if kind.needs_strokes() && lst.strokes.is_empty() {
                return Err(bad(format!(
                    "type {} follows strokes: give at least one",
                    kind.name()
                )));
            }
            for (k, r) in lst.regions.iter().enumerate() {
                let bad = |msg: String| bad(format!("region {} ('{}'): {msg}", k + 1, r.facet));
                let kind = crate::solid::lst::TextureType::parse(&r.kind)
                    .map_err(|e| bad(e.to_string()))?;
                if kind.needs_depth() {
                    return Err(bad(format!(
                        "type {} needs the depth field; a region takes type 0 or 1a",
                        kind.name()
                    )));
                }
                if let Some(scale) = r.scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
                    return Err(bad(format!(
                        "scale must be a positive number of mesh units, not {scale}"
                    )));
                }
                if lst.regions[..k].iter().any(|o| o.facet == r.facet) {
                    return Err(bad("the facet has a region already".into()));
                }
            }
            let known: Vec<&str> = facets.iter().map(|f| f.name.as_str()).collect();
            let region_facets = lst.regions.iter().map(|r| &r.facet);
            for f in [&lst.depth_outer, &lst.depth_inner]
                .into_iter()
                .flatten()
                .chain(region_facets)
            {
                // With a "*" facet the mesh's own names decide (at the bake).
                if !known.contains(&f.as_str()) && !known.contains(&"*") {
                    return Err(bad(format!(
                        "no facet '{f}' in this node (it has: {})",
                        known.join(", ")
                    )));
                }
            }
        }
    }
    Ok(NodeSpec {
        name: node.name.clone(),
        mesh,
        facets,
        interior: node.interior.as_ref().map(|i| Interior {
            photographs: i
                .get_ref()
                .photographs
                .iter()
                .map(|p| dir.join(p))
                .collect(),
            sections: i.get_ref().sections.as_ref().map(|s| dir.join(s)),
            ..i.get_ref().clone()
        }),
        origin: Origin {
            file: path.to_path_buf(),
            line: line_of(text, node.mesh.span().start),
        },
    })
}

/// Check every texture and overlay id against the database's, naming the
/// scene line that uses an unknown one.
pub fn check_tissues(spec: &SceneSpec, ids: &[String]) -> Result<()> {
    let known = |id: &str| ids.iter().any(|k| k == id);
    for node in &spec.nodes {
        for f in &node.facets {
            for (key, id) in [
                ("texture", Some(&f.texture)),
                ("overlay", f.overlay.as_ref()),
                ("match", f.grading.matched.as_ref()),
            ] {
                if let Some(id) = id
                    && !known(id)
                {
                    return Err(f.origin.error(format!(
                        "node '{}': facet '{}' {key}: '{id}' is not in the tissue database (it has: {})",
                        node.name,
                        f.name,
                        ids.join(", ")
                    )));
                }
            }
        }
        if let Some(interior) = &node.interior
            && !interior.texture.is_empty()
            && !known(&interior.texture)
        {
            return Err(node.origin.error(format!(
                "node '{}': interior texture: '{}' is not in the tissue database",
                node.name, interior.texture
            )));
        }
    }
    Ok(())
}
