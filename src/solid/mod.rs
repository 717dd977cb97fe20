//! The organ's interior: what a cut exposes and how it is textured.
//!
//! `section` cuts a closed mesh with a plane into a triangulated polygon;
//! `cut` textures that section, or any cut surface the simulator makes,
//! from a solid texture block, on the CPU or through the WGSL snippet it
//! ships for the GPU.

pub mod cut;
pub mod interior;
pub mod lst;
pub mod morph;
pub mod section;
pub mod stereology;

pub use cut::{
    Placement, SAMPLE_BLOCK_WGSL, SectionImage, SurfaceTexture, render_section, sample_colours,
    sample_points, section_glb, texture_coordinates, texture_surface,
};
pub use interior::{Block, Interior, InteriorMethod, interior_block};
pub use section::{Frame, Plane, Section, capped, plane_section};
