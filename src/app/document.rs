//! The viewer's model, free of any UI: the scene being designed (its spec
//! with one settings entry per mesh facet), the node meshes, and the baked
//! (unwrapped) scene once the user has unwrapped it. Loading and saving
//! fail with errors that name the file; a failed load leaves the current
//! document as it was (the caller only replaces it on success).

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::mesh::{Topology, TriMesh};
use crate::scene::build::{BakedScene, match_facets, node_mesh_reported};
use crate::scene::file::{
    self, BakeSettings, Camera, FacetSettings, Interior, MeshSpec, NodeSpec, Origin, SceneSpec,
};
use crate::scene::uterus::CavityParams;
use crate::unwrap::seamster::SeamOptions;

pub struct Document {
    pub spec: SceneSpec,
    pub meshes: Vec<TriMesh>,
    pub topologies: Vec<Topology>,
    /// Each mesh with its openings closed (`solid::capped`), for cuts.
    pub closed: Vec<(TriMesh, Topology)>,
    /// Per node, what meshing its segmentation measured (none for a mesh
    /// file or a generated cavity).
    pub segmented: Vec<Option<crate::segment::MeshReport>>,
    /// Set by an unwrap; dropped when the cut must be redone.
    pub baked: Option<BakedScene>,
}

impl Document {
    /// A scene file (.toml), or a bare mesh given the first tissue of the
    /// bundled database on every facet.
    pub fn open(path: &Path) -> Result<Document> {
        let is_scene = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
        if is_scene {
            return Document::of_spec(file::load(path)?, &crate::progress::Silent);
        }
        if crate::segment::contents::is_segmentation(path) {
            return Err(Error::format(
                path,
                "is a segmentation: say which region to mesh (--label, --segment or --threshold)",
            ));
        }
        known_mesh(path)?;
        Document::bare(
            path,
            MeshSpec::File(path.to_path_buf()),
            &crate::progress::Silent,
        )
    }

    /// One region of a segmentation (a label, a segment or a threshold,
    /// meshed as a scene's `[node.mesh.segmentation]` is), every facet
    /// given the first tissue, waiting for Unwrap as a bare mesh does.
    pub fn of_segmentation(
        segmentation: file::Segmentation,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Document> {
        let path = segmentation.file.clone();
        Document::bare(&path, MeshSpec::Segmentation(segmentation), progress)
    }

    /// A scene of one node, `mesh`, read from `path`, every facet the
    /// bundled database's first colour tissue, tiled a sixth of the
    /// bounding box's diagonal so a few copies of the texture cover the
    /// mesh whatever its units.
    fn bare(
        path: &Path,
        mesh: MeshSpec,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Document> {
        let mut doc = Document::of_spec(bare_scene(path, mesh)?, progress)?;
        if let Some((lo, hi)) = doc.bounds() {
            let tile = ((hi - lo).length() / 6.0).max(1e-9);
            for f in &mut doc.spec.nodes[0].facets {
                f.tile_size = tile;
                f.overlay_tile_size = tile;
            }
        }
        Ok(doc)
    }

    /// Read every node's mesh and give each of its facets its own
    /// settings entry (named after it), so each can be changed alone.
    pub fn of_spec(
        mut spec: SceneSpec,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Document> {
        let db = crate::db::Database::open(&spec.database)?;
        let ids: Vec<String> = db.tissues.iter().map(|t| t.id.clone()).collect();
        file::check_tissues(&spec, &ids)?;
        let mut meshes = Vec::new();
        let mut topologies = Vec::new();
        let mut segmented = Vec::new();
        for node in &mut spec.nodes {
            let (mesh, topology, report) = node_mesh_reported(node, progress)?;
            segmented.push(report);
            let names = mesh
                .facets
                .as_ref()
                .map(|f| f.names.clone())
                .unwrap_or_default();
            let mut settings = match_facets(node, &mesh)?;
            for (s, name) in settings.iter_mut().zip(names) {
                s.name = name;
            }
            node.facets = settings;
            meshes.push(mesh);
            topologies.push(topology);
        }
        let closed = meshes
            .iter()
            .zip(&topologies)
            .map(|(m, t)| crate::solid::capped(m, t))
            .collect::<Result<_>>()?;
        Ok(Document {
            spec,
            meshes,
            topologies,
            closed,
            segmented,
            baked: None,
        })
    }

    /// Settings of facet `facet` (its id in the mesh) of node `node`.
    pub fn settings(&self, (node, facet): (usize, usize)) -> &FacetSettings {
        &self.spec.nodes[node].facets[facet]
    }

    /// Change a facet's settings, in the spec and in the baked scene.
    pub fn set_settings(&mut self, (node, facet): (usize, usize), settings: FacetSettings) {
        if let Some(baked) = &mut self.baked
            && let Some(f) = baked.nodes[node]
                .facets
                .iter_mut()
                .find(|f| f.piece.facet as usize == facet)
        {
            f.settings = settings.clone();
        }
        self.spec.nodes[node].facets[facet] = settings;
    }

    /// Every facet as (node, facet id, "node / facet").
    pub fn facets(&self) -> Vec<((usize, usize), String)> {
        let mut out = Vec::new();
        for (k, node) in self.spec.nodes.iter().enumerate() {
            for (j, f) in node.facets.iter().enumerate() {
                out.push(((k, j), format!("{} / {}", node.name, f.name)));
            }
        }
        out
    }

    pub fn bounds(&self) -> Option<(glam::DVec3, glam::DVec3)> {
        self.meshes
            .iter()
            .filter_map(|m| m.bounding_box())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Write the scene as a scene file, every facet listed by name, paths
    /// absolute (so the file can be moved).
    pub fn save(&self, path: &Path) -> Result<()> {
        let out = SavedScene {
            name: &self.spec.name,
            database: (self.spec.database != crate::scene::file::default_database())
                .then(|| absolute(&self.spec.database)),
            camera: &self.spec.cameras,
            node: self
                .spec
                .nodes
                .iter()
                .map(|n| SavedNode {
                    name: &n.name,
                    mesh: match &n.mesh {
                        MeshSpec::File(p) => SavedMesh {
                            file: Some(absolute(p)),
                            uterine_cavity: None,
                            segmentation: None,
                        },
                        MeshSpec::UterineCavity(c) => SavedMesh {
                            file: None,
                            uterine_cavity: Some(c),
                            segmentation: None,
                        },
                        MeshSpec::Segmentation(s) => SavedMesh {
                            file: None,
                            uterine_cavity: None,
                            segmentation: Some(crate::scene::file::Segmentation {
                                file: absolute(&s.file),
                                ..s.clone()
                            }),
                        },
                    },
                    facet: &n.facets,
                    interior: n.interior.as_ref(),
                })
                .collect(),
            bake: &self.spec.bake,
        };
        // Plain (not pretty) TOML keeps arrays such as positions on one
        // line, as a scene written by hand has them.
        let text = toml::to_string(&out)
            .map_err(|e| Error::invalid(format!("cannot write the scene as TOML: {e}")))?;
        crate::atomic::write_file(path, |w| w.write_all(text.as_bytes()))
    }
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Whether `path` is a mesh organtex reads; else an error naming it.
fn known_mesh(path: &Path) -> Result<()> {
    let known = path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        crate::mesh::io::READABLE
            .iter()
            .any(|m| e.eq_ignore_ascii_case(m))
    });
    if known {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "not a scene (.toml), a mesh ({}) or a segmentation ({})",
            crate::mesh::io::READABLE.join(", "),
            crate::segment::contents::READABLE.join(", ")
        ),
    ))
}

/// A scene of one node, `mesh` (read from `path`), every facet the
/// bundled database's first colour tissue (tile sizes are set by `bare`,
/// once the mesh is read).
fn bare_scene(path: &Path, mesh: MeshSpec) -> Result<SceneSpec> {
    let database = crate::scene::file::default_database();
    let db = crate::db::Database::open(&database)?;
    let texture = db
        .tissues
        .iter()
        .find(|t| t.outputs.contains(&crate::db::Output::Colour))
        .map(|t| t.id.clone())
        .ok_or_else(|| Error::format(&database, "the tissue database has no colour texture"))?;
    let name = crate::segment::contents::stem(path);
    let origin = Origin {
        file: path.to_path_buf(),
        line: 0,
    };
    Ok(SceneSpec {
        path: path.to_path_buf(),
        name: name.clone(),
        database,
        cameras: Vec::new(),
        nodes: vec![NodeSpec {
            name,
            mesh,
            facets: vec![FacetSettings {
                name: "*".into(),
                texture,
                tile_size: 1.0,
                rotation: 0.0,
                offset: [0.0, 0.0],
                bump: 0.0,
                overlay: None,
                overlay_opacity: 0.6,
                overlay_tile_size: 1.0,
                overlap: 0.0,
                max_stretch: SeamOptions::default().max_stretch,
                max_conformal: SeamOptions::default().max_conformal,
                grading: Default::default(),
                origin: origin.clone(),
            }],
            interior: None,
            origin,
        }],
        bake: BakeSettings::default(),
    })
}

#[derive(Serialize)]
struct SavedScene<'a> {
    name: &'a str,
    /// Left out when it is the bundled database, so the file still
    /// works once the project is moved.
    #[serde(skip_serializing_if = "Option::is_none")]
    database: Option<PathBuf>,
    camera: &'a [Camera],
    node: Vec<SavedNode<'a>>,
    bake: &'a BakeSettings,
}

#[derive(Serialize)]
struct SavedNode<'a> {
    name: &'a str,
    mesh: SavedMesh<'a>,
    facet: &'a [FacetSettings],
    #[serde(skip_serializing_if = "Option::is_none")]
    interior: Option<&'a Interior>,
}

#[derive(Serialize)]
struct SavedMesh<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    file: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    uterine_cavity: Option<&'a CavityParams>,
    #[serde(skip_serializing_if = "Option::is_none")]
    segmentation: Option<crate::scene::file::Segmentation>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn repo(p: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(p)
    }

    #[test]
    fn a_saved_scene_loads_back_the_same() {
        let doc = Document::open(&repo("scenes/hysteroscopy_myomas.toml")).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("saved.toml");
        doc.save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        // Written as a person would: arrays on one line, no path to the
        // bundled database.
        assert!(text.contains("position = [0.0, 0.0, 4.0]"), "{text}");
        assert!(!text.contains("database"), "{text}");
        let again = Document::open(&path).unwrap();
        assert_eq!(again.spec.nodes.len(), doc.spec.nodes.len());
        for (a, b) in again.spec.nodes.iter().zip(&doc.spec.nodes) {
            assert_eq!(a.mesh, b.mesh);
            assert_eq!(a.interior, b.interior);
            let strip = |f: &FacetSettings| FacetSettings {
                origin: Origin::default(),
                ..f.clone()
            };
            assert_eq!(
                a.facets.iter().map(strip).collect::<Vec<_>>(),
                b.facets.iter().map(strip).collect::<Vec<_>>()
            );
        }
        assert_eq!(again.spec.cameras, doc.spec.cameras);
    }

    #[test]
    fn a_bare_mesh_gets_a_tissue_on_every_facet() {
        let doc = Document::open(&repo("tests/data/bunny10k_textured.obj")).unwrap();
        assert_eq!(doc.meshes.len(), 1);
        assert!(!doc.spec.nodes[0].facets.is_empty());
        assert!(doc.spec.nodes[0].facets.iter().all(|f| f.tile_size > 0.0));
    }

    #[test]
    fn a_broken_file_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("broken.obj");
        std::fs::write(&path, "v 0 0 0\nf 1 2 3\n").unwrap();
        let e = Document::open(&path).err().expect("an error").to_string();
        assert!(e.contains("broken.obj"), "{e}");
        let e = Document::open(&dir.path().join("notes.txt"))
            .err()
            .expect("an error")
            .to_string();
        assert!(e.contains("notes.txt"), "{e}");
    }
}
