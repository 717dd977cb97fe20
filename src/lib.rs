//! organtex: automatic texturing of organ scenes for surgical simulators.
//!
//! Stages are plain functions from data to data (see DESIGN.md in the
//! project's shared folder): `mesh` is the foundation every other stage
//! builds on.

#[cfg(feature = "render")]
pub mod app;
pub mod atomic;
pub mod bake;
pub mod bench;
pub mod blend;
pub mod db;
pub mod digest;
pub mod error;
#[doc(hidden)]
pub mod fuzz;
pub mod linalg;
pub mod memory;
pub mod mesh;
pub mod progress;
pub mod raster;
#[cfg(feature = "render")]
pub mod render;
pub mod rng;
pub mod runtime;
pub mod scene;
pub mod segment;
pub mod solid;
pub mod synth;
pub mod tetra;
pub mod unwrap;

pub use error::{Error, Result};
