//! The organ's interior: what a cut exposes and how it is textured.
//!
//! `section` cuts a closed mesh with a plane into a triangulated polygon;
//! `cut` textures that section, or any cut surface the simulator makes,
//! from a solid texture block, on the CPU or through the WGSL snippet it
//! ships for the GPU; `cut_texture` bakes any cut surface's texture from
//! any `Interior` (block, lapped solid texture, stereology, morph).

pub mod cut;
pub mod cut_texture;
pub mod interior;
pub mod lst;
pub mod morph;
pub mod section;
pub mod stereology;

pub use cut::{
    SAMPLE_BLOCK_WGSL, SectionImage, SurfaceTexture, render_section, sample_colours, sample_points,
    texture_coordinates, texture_surface,
};
pub use cut_texture::{CutTexture, texture_cut};
pub use interior::{Block, Interior, InteriorMethod, Placement, interior_block};
pub use section::{Frame, Plane, Section, capped, plane_section};
