//! The GPU renderer (wgpu, WGSL) that the viewer and the bake's preview
//! share: a baked scene's draw list (`scene::draw`, the same primitives
//! the .glb holds) as textured facets with their texture transforms as
//! uniforms, blend layers with per-vertex alpha, normal-mapped bump,
//! overlays, cut surfaces sampling the interior block as a 3D texture,
//! and wireframe, seam and distortion views.
//!
//! One code path: `Renderer::render` (`frame`) draws into any colour and
//! depth view, with the pipelines of `pipelines`; `gpu_scene` holds a
//! scene's data on the GPU. `Offscreen` owns such a pair and reads it back as an image (the
//! bake's preview.png, tests, `organtex view --screenshot`); the viewer
//! hands the same pair's colour texture to egui to show.

mod camera;
mod carved;
mod frame;
mod gpu;
mod gpu_scene;
mod offscreen;
mod pipelines;
mod preview;

pub use camera::OrbitCamera;
pub use carved::{CarveMask, CarvedFace, GpuCarved};
pub use frame::{Layers, Lighting, View};
pub use gpu::{Gpu, MAX_TEXTURE_ENV};
pub use gpu_scene::{CutMesh, GpuScene};
pub use offscreen::Offscreen;
pub use pipelines::{Filtering, Renderer};
pub use preview::{Medium, picture, picture_and_medium, preview, scope_field};
