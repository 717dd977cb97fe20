//! What a simulator calls while it runs: open a bake, colour points from
//! a node's interior, texture the faces its cuts expose, and carve the
//! node's tet mesh as its tools remove tets. The one home of this for
//! every caller: the C API (`capi/`), the Python package, the viewer's
//! Carve tool and `organtex bench`.
//!
//! - `bake`: a bake folder opened, its nodes loaded on first use;
//! - `model`: a node's interior model, with the per-tet fast paths;
//! - `atlas`: the cut-texture atlas, grown page by page;
//! - `carving`: a carving session, step by step;
//! - `tool`: the tools' shapes and the tets under them;
//! - `export`: the carved surface as a .glb.
//!
//! Threads: a `Node` is read-only and `Sync`; colour queries run on any
//! thread at once. A `Carving` or `CutTextures` is used by one thread at
//! a time (it is `Send`); steps use rayon's threads inside.

pub mod atlas;
pub mod bake;
pub mod carving;
pub mod export;
pub mod model;
pub mod textures;
pub mod tool;

pub use atlas::{AtlasOptions, Chart, CutAtlas, Rect};
pub use bake::{Bake, Node};
pub use carving::{Carving, CarvingOptions, FaceId, GoneFace, NewFace, Step};
pub use export::surface_glb;
pub use model::Model;
pub use textures::CutTextures;
pub use tool::Tool;

/// GLSL: a node's block as a `sampler3D` (repeat on s, t and r, linear
/// filtering) and `organtex_block_colour(coords)` giving the colour at 3D
/// texture coordinates in voxel units (`Node::block_coordinates`), as the
/// CPU colours them. OpenGL 3.3 / GLSL ES 3.0 and Vulkan GLSL alike.
pub const SAMPLE_BLOCK_GLSL: &str = include_str!("sample_block.glsl");

/// WGSL: the same, with the block's placement as a uniform
/// (`solid::SAMPLE_BLOCK_WGSL`).
pub const SAMPLE_BLOCK_WGSL: &str = crate::solid::SAMPLE_BLOCK_WGSL;
