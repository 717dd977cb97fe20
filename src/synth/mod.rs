//! Texture synthesis: tileable 2D textures from masked tissue photographs
//! (FNPTS), their quality figures, height maps, vessel overlays, and masks
//! computed from the photographs.

pub mod block;
pub mod components;
pub mod exemplar;
pub mod filter;
pub mod fnpts;
pub mod height;
pub mod lighting;
pub mod mask;
pub mod quality;
pub mod sweep;
pub mod vessel_tree;
pub mod vessels;
pub mod volume;
pub mod wrap;
