//! The cut plane: the interior synthesised (a block, lapped solid textures,
//! a morph sampled) the first time it is turned on, and the section drawn
//! through it where the plane lies.

use eframe::egui;
use glam::DVec3;

use super::{Job, Viewer};
use crate::error::{Error, Result};
use crate::render::{CutMesh, GpuScene};
use crate::solid::{InteriorMethod, Placement, Plane, interior_block, plane_section};
use crate::synth::volume::Volume;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutPlane {
    pub on: bool,
    /// The plane's unit normal: the half of the scene it points into is
    /// cut away, and the section faces that way. An axis, or towards the
    /// camera when set from the view.
    pub normal: DVec3,
    /// Where across the scene's bounds along the normal, 0..1.
    pub at: f64,
}

/// What the cut plane shows inside: the interior block, and per node its
/// lapped solid texture where the scene asks for one (`[node.interior.lst]`,
/// laid as the bake lays it, the block as exemplar).
pub(super) struct Interiors {
    pub(super) block: Volume,
    pub(super) lst: Vec<Option<std::sync::Arc<crate::solid::lst::LstModel>>>,
    /// Where the block lies when it does not tile from the origin (a
    /// morph sampled over its node's bounds).
    pub(super) placement: Option<Placement>,
}

/// Voxels a side of the block a morphed interior is sampled into for the
/// cut plane (128^3 points: about 0.4 s on 2 cores).
const MORPH_VOXELS: usize = 128;

impl Viewer {
    /// The cut plane's switch, axis and position.
    pub(super) fn cut_plane_panel(&mut self, ui: &mut egui::Ui) {
        ui.separator();
        let mut on = self.cut.on;
        if ui.checkbox(&mut on, "cut plane").changed() {
            self.set_cut(on);
        }
        if self.cut.on {
            let before = self.cut;
            ui.horizontal(|ui| {
                for (normal, name) in [(DVec3::X, "x"), (DVec3::Y, "y"), (DVec3::Z, "z")] {
                    ui.radio_value(&mut self.cut.normal, normal, name);
                }
                if ui
                    .button("facing me")
                    .on_hover_text(
                        "turn the plane to face the camera, through the middle of the scene",
                    )
                    .clicked()
                {
                    self.cut_facing_view();
                }
            });
            ui.add(egui::Slider::new(&mut self.cut.at, 0.0..=1.0).text("position"));
            if self.cut != before {
                self.touch();
            }
        }
    }

    /// Mesh units one interior block covers (the scene's interior setting,
    /// else a third of the scene's diagonal), and where it starts: the
    /// origin, the placement the bake gives `interior/NODE.nrrd` (the
    /// viewer's block is a quicker 32^3 one).
    pub(super) fn block_units(&self) -> Option<(f64, DVec3)> {
        let doc = self.doc.as_ref()?;
        let (lo, hi) = doc.bounds()?;
        let units = doc
            .spec
            .nodes
            .iter()
            .find_map(|n| n.interior.as_ref().map(|i| i.block_size))
            .unwrap_or((hi - lo).length() / 3.0);
        Some((units, DVec3::ZERO))
    }

    pub(super) fn set_block(&mut self, volume: Volume, placed: Option<Placement>) {
        let Some((units, lo)) = self.block_units() else {
            return;
        };
        let placement =
            match placed.map_or_else(|| Placement::new(lo, units / volume.size[0] as f64), Ok) {
                Ok(p) => p,
                Err(e) => return self.error(e),
            };
        self.block_placement = Some(placement);
        // Kept for the carving, which colours on the CPU.
        self.interior_block = Some((volume.clone(), placement));
        if let Some(scene) = &mut self.scene
            && let Err(e) = scene.set_block(
                &self.renderer,
                &self.gpu.device,
                &self.gpu.queue,
                &volume,
                &placement,
            )
        {
            self.error(e);
        }
        self.cut_made = None;
        self.touch();
    }

    /// Whether the interior block is on the GPU.
    pub(super) fn has_block(&self) -> bool {
        self.scene.as_ref().is_some_and(GpuScene::has_block)
    }

    /// Turn the cut plane on; the first time, synthesise the interior.
    pub fn set_cut(&mut self, on: bool) {
        self.cut.on = on;
        self.cut_made = None;
        self.touch();
        if on {
            self.start_interior();
        }
    }

    /// Synthesise the interior (block and lapped solid textures) unless it
    /// is there or on its way: the cut plane and the carving show it.
    pub(super) fn start_interior(&mut self) {
        if self.has_block() || self.jobs.block.is_some() {
            return;
        }
        let Some(doc) = &self.doc else { return };
        // A morphed interior (seed 003) is sampled over its node's bounds
        // at MORPH_VOXELS a side: the cut plane's GPU path reads a block.
        let morphed = doc
            .spec
            .nodes
            .iter()
            .zip(&doc.closed)
            .find_map(|(n, closed)| {
                n.interior
                    .as_ref()
                    .filter(|i| i.method == InteriorMethod::Morph)
                    .and_then(|i| i.sections.clone())
                    .map(|sections| (closed.clone(), sections))
            });
        if let Some(((mesh, topology), sections)) = morphed {
            self.jobs.block = Some(Job::spawn("interior morph", self.wake(), move |p| {
                let morph = crate::solid::morph::Morph::read(
                    &mesh,
                    &topology,
                    &sections,
                    Default::default(),
                    p,
                )?;
                let (lo, hi) = mesh
                    .bounding_box()
                    .ok_or_else(|| Error::invalid("the mesh has no vertices"))?;
                let (block, placement) = morph.block(lo, hi, MORPH_VOXELS)?;
                Ok(Interiors {
                    block,
                    lst: Vec::new(),
                    placement: Some(placement),
                })
            }));
            return;
        }
        let interior = doc.spec.nodes.iter().find_map(|n| {
            n.interior.as_ref().map(|i| {
                (
                    i.texture.clone(),
                    i.method,
                    i.photographs.clone(),
                    i.particles,
                )
            })
        });
        let Some((tissue, method, photographs, particles)) = interior.or_else(|| {
            self.selected.map(|f| {
                (
                    doc.settings(f).texture.clone(),
                    InteriorMethod::default(),
                    Vec::new(),
                    Default::default(),
                )
            })
        }) else {
            return;
        };
        let database = doc.spec.database.clone();
        // The nodes to lap: their name, surface, interior settings.
        let lapped: Vec<_> = doc
            .spec
            .nodes
            .iter()
            .zip(&doc.meshes)
            .map(|(n, mesh)| {
                n.interior
                    .as_ref()
                    .filter(|i| i.lst.is_some())
                    .map(|i| (n.name.clone(), mesh.clone(), i.clone()))
            })
            .collect();
        self.jobs.block = Some(Job::spawn(
            "interior solid texture",
            self.wake(),
            move |p| {
                let db = crate::db::Database::open(&database)?;
                let t = db.tissue(&tissue)?;
                if !crate::db::build::is_current(&db, t)? {
                    crate::db::build(&db, std::slice::from_ref(&tissue), p)?;
                }
                // Stereology's voxels are the photographs' pixels: 32 would
                // hold few particles.
                let size = if method == InteriorMethod::Stereology {
                    64
                } else {
                    32
                };
                let block = interior_block(
                    &db.output_path(&tissue, method.output()),
                    &photographs,
                    particles,
                    size,
                    method,
                    0,
                    p,
                )?;
                let lst = lapped
                    .iter()
                    .enumerate()
                    .map(|(k, node)| {
                        let Some((name, surface, interior)) = node else {
                            return Ok(None);
                        };
                        let spec = interior.lst.as_ref().expect("filtered on lst");
                        let (tets, _) = crate::tetra::tetrahedralise_report(
                            surface,
                            &crate::tetra::TetOptions::default(),
                            p,
                        )
                        .map_err(|e| e.within(format!("node '{name}': tet mesh")))?;
                        // The bake's seed, so the cut shows what it bakes.
                        let (model, _, _) = crate::bake::lap(
                            spec,
                            surface,
                            &tets,
                            interior.block_size,
                            k as u64,
                            name,
                            p,
                        )?;
                        Ok(Some(model.into()))
                    })
                    .collect::<Result<_>>()?;
                Ok(Interiors {
                    block,
                    lst,
                    placement: None,
                })
            },
        ));
    }

    /// Turn the cut plane to face the camera, half way across the scene, so
    /// the section shows what lies straight ahead.
    pub fn cut_facing_view(&mut self) {
        self.cut.normal = (self.camera.eye() - self.camera.target)
            .try_normalize()
            .unwrap_or(DVec3::Z);
        self.cut.at = 0.5;
        self.touch();
    }

    /// The plane's normal and offset in object space.
    pub fn cut_plane(&self) -> Option<(DVec3, f64)> {
        if !self.cut.on {
            return None;
        }
        let (lo, hi) = self.doc.as_ref()?.bounds()?;
        let n = self.cut.normal;
        // The bounds' extent along the normal: their corners' nearest and
        // farthest.
        let (near, far) = (0..8)
            .map(|k| {
                let corner = DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                n.dot(corner)
            })
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
                (a.min(d), b.max(d))
            });
        Some((n, near + self.cut.at * (far - near)))
    }

    /// Remake the section when the plane moved.
    pub(super) fn update_section(&mut self) {
        let plane = self.cut_plane().filter(|_| self.has_block());
        let key = plane.map(|(n, d)| (n.to_array(), d));
        if key == self.cut_made {
            return;
        }
        self.cut_made = key;
        let (Some(doc), Some(scene)) = (&self.doc, &mut self.scene) else {
            return;
        };
        let Some((normal, offset)) = plane else {
            scene.set_cut(&self.gpu.device, None);
            // Setting none cannot fail.
            let _ = scene.set_lst_cut(&self.renderer, &self.gpu.device, &self.gpu.queue, None);
            return;
        };
        let mut cut = CutMesh {
            positions: Vec::new(),
            normals: Vec::new(),
            triangles: Vec::new(),
        };
        let mut problem = None;
        let mut lst_cut = crate::solid::lst::gpu::CutBuffers::default();
        for (k, (mesh, topology)) in doc.closed.iter().enumerate() {
            if let Some(Some(model)) = self.lst.get(k) {
                let c = crate::tetra::march::plane_cut(&model.mesh, normal, offset);
                lst_cut.add(model, &c, normal);
                continue;
            }
            let section = Plane::new(normal, offset).and_then(|p| plane_section(mesh, topology, p));
            match section {
                Ok(s) => {
                    let base = cut.positions.len() as u32;
                    cut.normals
                        .extend(std::iter::repeat_n(s.normal, s.positions.len()));
                    cut.positions.extend(&s.positions);
                    cut.triangles
                        .extend(s.triangles.iter().map(|t| t.map(|v| v + base)));
                }
                Err(e) => problem = Some(format!("node '{}': {e}", doc.spec.nodes[k].name)),
            }
        }
        scene.set_cut(&self.gpu.device, Some(&cut));
        if let Err(e) = scene.set_lst_cut(
            &self.renderer,
            &self.gpu.device,
            &self.gpu.queue,
            Some(&lst_cut),
        ) {
            problem = Some(e.to_string());
        }
        if let Some(p) = problem {
            self.error(format!("cannot cut: {p}"));
        }
        self.touch();
    }

    /// Where the interior block on the GPU lies, if one is.
    pub fn block_placement(&self) -> Option<Placement> {
        self.block_placement.filter(|_| self.has_block())
    }

    pub fn cut_triangles(&self) -> usize {
        self.scene.as_ref().map_or(0, GpuScene::cut_triangles)
    }

    /// Of those, the ones through lapped solid textures.
    pub fn lst_cut_triangles(&self) -> usize {
        self.scene.as_ref().map_or(0, GpuScene::lst_cut_triangles)
    }
}
