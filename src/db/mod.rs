//! The tissue texture database (seed 004, section 3.1): real photographs,
//! cropped and masked, resynthesised into tileable textures with height
//! maps, plus vessel overlays.

pub mod build;
pub mod colour;
pub mod index;

pub use build::{Built, build, exemplar};
pub use index::{Capture, Database, Finish, Output, Shelf, Tissue};
