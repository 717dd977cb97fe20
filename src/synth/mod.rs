//! Texture synthesis: tileable 2D textures from masked tissue photographs
//! (FNPTS), their quality figures, height maps and vessel overlays.

pub mod exemplar;
pub mod fnpts;
pub mod quality;
