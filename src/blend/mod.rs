//! Blending away texture discontinuities (seed 004, section 3.5): seam bands
//! inside a chart, overlap rings between facets.

pub mod overlap;
pub mod seam;
