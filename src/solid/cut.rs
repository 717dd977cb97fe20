//! Texturing the surfaces a cut exposes from the organ's solid texture: a
//! voxel block (`synth::volume::Volume`) placed in object space and tiled
//! through it.
//!
//! One convention throughout: 3D texture coordinates are in voxel units,
//! `(p - origin) / scale`, the coordinates `Volume::sample` takes. They do
//! not depend on the block's size; the GPU divides them by the texture's
//! dimensions (`SAMPLE_BLOCK_WGSL`), and both place voxel `i`'s centre at
//! `i + 0.5` and wrap around, so CPU and GPU colours agree.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::interior::Placement;
use super::section::Section;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::synth::volume::Volume;

/// WGSL: the block as a `texture_3d<f32>` with a sampler and the placement
/// as a uniform, and `block_colour(p)` giving the colour at an object-space
/// point, as `sample_points` does on the CPU (see the file's comments for
/// the bindings and the sampler it needs).
pub const SAMPLE_BLOCK_WGSL: &str = include_str!("sample_block.wgsl");

/// 3D texture coordinates, in voxel units, of object-space points.
pub fn texture_coordinates(points: &[DVec3], placement: &Placement) -> Vec<[f32; 3]> {
    points
        .iter()
        .map(|&p| placement.voxel(p).as_vec3().to_array())
        .collect()
}

/// The block's colour at object-space points: trilinear, wrapping around.
pub fn sample_points(points: &[DVec3], volume: &Volume, placement: &Placement) -> Vec<[u8; 3]> {
    points
        .iter()
        .map(|&p| to_u8(volume.sample(placement.voxel(p).to_array())))
        .collect()
}

/// The colour at each of the section's vertices.
pub fn sample_colours(section: &Section, volume: &Volume, placement: &Placement) -> Vec<[u8; 3]> {
    sample_points(&section.positions, volume, placement)
}

#[inline]
fn to_u8(c: [f32; 3]) -> [u8; 3] {
    c.map(|x| x.round().clamp(0.0, 255.0) as u8)
}

/// Per-vertex texture of a cut surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceTexture {
    /// Voxel units, for a 3D texture lookup on the GPU.
    pub texcoords: Vec<[f32; 3]>,
    /// The block's colour there, for vertex colouring.
    pub colours: Vec<[u8; 3]>,
}

/// The texture of a cut surface the simulator made (any triangle mesh: a
/// curved incision, a resected wall). The mesh is taken as given: it is the
/// caller's to bound it by the organ; its vertices are textured wherever
/// they are.
pub fn texture_surface(cut: &TriMesh, volume: &Volume, placement: &Placement) -> SurfaceTexture {
    SurfaceTexture {
        texcoords: texture_coordinates(&cut.positions, placement),
        colours: sample_points(&cut.positions, volume, placement),
    }
}

/// A section drawn in its plane, as `render_section` makes it.
#[derive(Clone, Debug)]
pub struct SectionImage {
    /// Inside the section: the block's colour, opaque. Outside: the
    /// block's colour too but transparent, so a filtered lookup near the
    /// edge reads no black fringe.
    pub image: image::RgbaImage,
    pub pixels_per_unit: f64,
    /// The plane point (section frame) at the image's top left corner; x
    /// runs along the frame's u, rows run down against its v.
    pub top_left: DVec2,
}

impl SectionImage {
    /// Pixel coordinates (not rounded) of a point of the section's plane.
    #[inline]
    pub fn pixel(&self, q: DVec2) -> DVec2 {
        DVec2::new(q.x - self.top_left.x, self.top_left.y - q.y) * self.pixels_per_unit
    }

    /// glTF texture coordinates of a point of the section's plane: 0..1
    /// across the image, v down.
    pub fn uv(&self, q: DVec2) -> DVec2 {
        self.pixel(q) / DVec2::new(self.image.width() as f64, self.image.height() as f64)
    }
}

/// The largest image side `render_section` makes.
pub const MAX_SIDE: u32 = 16384;

/// Draw `section` in its plane, `pixels_per_unit` pixels per object unit,
/// each pixel coloured from the interior at its centre's 3D point. Refuses an
/// empty section and an image over `MAX_SIDE` pixels a side.
pub fn render_section(
    section: &Section,
    interior: &dyn super::Interior,
    pixels_per_unit: f64,
) -> Result<SectionImage> {
    let (lo, hi) = section
        .bounds()
        .filter(|_| !section.is_empty())
        .ok_or_else(|| Error::invalid("the section is empty: the plane misses the mesh"))?;
    if !(pixels_per_unit > 0.0 && pixels_per_unit.is_finite()) {
        return Err(Error::invalid(format!(
            "pixels per unit must be positive, not {pixels_per_unit}"
        )));
    }
    let side = |extent: f64| (extent * pixels_per_unit).ceil().max(1.0);
    let (w, h) = (side(hi.x - lo.x), side(hi.y - lo.y));
    if w > MAX_SIDE as f64 || h > MAX_SIDE as f64 {
        return Err(Error::invalid(format!(
            "the section image would be {w}x{h} pixels, over {MAX_SIDE} a side; lower the resolution"
        )));
    }
    let (w, h) = (w as u32, h as u32);
    let mut out = SectionImage {
        image: image::RgbaImage::new(w, h),
        pixels_per_unit,
        top_left: DVec2::new(lo.x, hi.y),
    };
    let mut inside = vec![false; (w * h) as usize];
    for t in &section.triangles {
        let corners = t.map(|i| out.pixel(section.plane_point(i)));
        crate::raster::triangle(corners, w as usize, h as usize, |x, y, _| {
            inside[y * w as usize + x] = true;
        });
    }
    let top_left = out.top_left;
    out.image
        .par_chunks_mut(4 * w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, px) in row.chunks_exact_mut(4).enumerate() {
                let q = top_left + DVec2::new(x as f64 + 0.5, -(y as f64 + 0.5)) / pixels_per_unit;
                let [r, g, b] = interior.colour(section.frame.to_3d(q));
                let a = if inside[y * w as usize + x] { 255 } else { 0 };
                px.copy_from_slice(&[r, g, b, a]);
            }
        });
    Ok(out)
}
