//! Scenes: organ meshes split into facets, each with its tissue, baked into
//! assets a simulator loads.

pub mod atlas;
pub mod build;
pub mod composite;
pub mod contrast;
pub mod draw;
pub mod file;
pub mod gltf;
pub mod interior;
pub mod kept_unwrap;
pub mod manifest;
pub mod seam_erasure;
pub mod uterus;
