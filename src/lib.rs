//! organtex: automatic texturing of organ scenes for surgical simulators.
//!
//! Stages are plain functions from data to data (see DESIGN.md in the
//! project's shared folder): `mesh` is the foundation every other stage
//! builds on.

pub mod atomic;
pub mod bench;
pub mod error;
pub mod mesh;

pub use error::{Error, Result};
