//! A texture for any cut surface, from any interior model: each triangle of
//! the cut laid flat at its true shape, packed into one image on shelves,
//! and every texel coloured from the interior at the 3D point it shows.
//! What a simulator needs for a curved incision at full resolution when the
//! interior has no 3D texture to sample on the GPU (a morph, seed 003) or
//! when a baked image is wanted anyway.
//!
//! Per-triangle charts rather than an unwrap: a cut is made at run time and
//! must be textured in milliseconds; Seamster and ABF++ are for the organ's
//! surface. Every chart has a `GUTTER`-texel border coloured as the
//! triangle continued, so bilinear filtering never reads a neighbour.

use glam::{DVec2, DVec3};

use super::Interior;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;

/// Texels of border round each triangle's chart.
const GUTTER: f64 = 2.0;
/// The largest image side.
pub const MAX_SIDE: usize = 8192;

/// A cut surface's texture: one chart per triangle.
#[derive(Clone, Debug)]
pub struct CutTexture {
    /// Per triangle corner (3 per triangle, in the cut's order): texture
    /// coordinates, 0..1 across the image, v down (glTF's convention).
    pub uvs: Vec<DVec2>,
    pub image: image::RgbaImage,
}

/// Texture `cut` from `interior` at `texels_per_unit` texels per object
/// unit. Refuses a density that is not positive and an image over
/// `MAX_SIDE` a side.
pub fn texture_cut(
    cut: &TriMesh,
    interior: &dyn Interior,
    texels_per_unit: f64,
) -> Result<CutTexture> {
    if !(texels_per_unit > 0.0 && texels_per_unit.is_finite()) {
        return Err(Error::invalid(format!(
            "texels per unit must be positive, not {texels_per_unit}"
        )));
    }
    // Each triangle flat in its own frame, in texels: a at the origin, b
    // along +x, c above.
    let flat: Vec<[DVec2; 3]> = cut
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| cut.positions[i as usize]);
            let e1 = (b - a).normalize_or_zero();
            let e2 = (b - a).cross(c - a).cross(e1).normalize_or_zero();
            [
                DVec2::ZERO,
                DVec2::new((b - a).length(), 0.0),
                DVec2::new((c - a).dot(e1), (c - a).dot(e2)),
            ]
            .map(|p| p * texels_per_unit)
        })
        .collect();
    let size = |f: &[DVec2; 3]| {
        let lo = f[0].min(f[1]).min(f[2]);
        let hi = f[0].max(f[1]).max(f[2]);
        (lo, (hi - lo + DVec2::splat(2.0 * GUTTER)).ceil())
    };
    // Shelves: tallest first, left to right, a new shelf when a row is full.
    let mut order: Vec<usize> = (0..flat.len()).collect();
    order.sort_by(|&i, &j| {
        size(&flat[j])
            .1
            .y
            .total_cmp(&size(&flat[i]).1.y)
            .then(i.cmp(&j))
    });
    let area: f64 = flat.iter().map(|f| size(f).1.x * size(f).1.y).sum();
    let widest = flat.iter().map(|f| size(f).1.x).fold(1.0, f64::max);
    let width = (area.sqrt() * 1.1).max(widest).ceil();
    let mut corner = vec![DVec2::ZERO; flat.len()];
    let (mut x, mut y, mut shelf) = (0.0, 0.0, 0.0);
    for &i in &order {
        let (_, s) = size(&flat[i]);
        if x + s.x > width {
            (x, y, shelf) = (0.0, y + shelf, 0.0);
        }
        corner[i] = DVec2::new(x, y);
        x += s.x;
        shelf = f64::max(shelf, s.y);
    }
    let height = (y + shelf).max(1.0);
    if width > MAX_SIDE as f64 || height > MAX_SIDE as f64 {
        return Err(Error::invalid(format!(
            "the cut's texture would be {width}x{height} texels, over {MAX_SIDE} a side; \
             lower the texel density"
        )));
    }
    let (w, h) = (width as usize, height as usize);
    crate::memory::ensure_fits(
        &format!("a {w}x{h} cut texture"),
        crate::memory::product(&[w as u64, h as u64, 40]),
    )?;
    // The chart of triangle i in the image: its flat corners moved into
    // place, the gutter inside its box.
    let placed: Vec<[DVec2; 3]> = flat
        .iter()
        .zip(&corner)
        .map(|(f, &c)| {
            let (lo, _) = size(f);
            f.map(|p| p - lo + c + DVec2::splat(GUTTER))
        })
        .collect();
    let mut owner = vec![u32::MAX; w * h];
    let mut points = vec![DVec3::ZERO; w * h];
    for (i, chart) in placed.iter().enumerate() {
        let [a, b, c] = cut.triangles[i].map(|k| cut.positions[k as usize]);
        crate::raster::triangle_padded(*chart, w, h, GUTTER, |x, y, _| {
            let Some(bary) =
                crate::raster::barycentric(*chart, DVec2::new(x as f64 + 0.5, y as f64 + 0.5))
            else {
                return;
            };
            // Past the edge the triangle continues (the gutter): the plane
            // of the triangle, extrapolated a texel or two.
            owner[y * w + x] = i as u32;
            points[y * w + x] = a * bary[0] + b * bary[1] + c * bary[2];
        });
    }
    let used: Vec<usize> = (0..w * h).filter(|&k| owner[k] != u32::MAX).collect();
    let colours = interior.colours(&used.iter().map(|&k| points[k]).collect::<Vec<_>>());
    let mut image = image::RgbaImage::new(w as u32, h as u32);
    let raw: &mut [u8] = &mut image;
    for (&k, c) in used.iter().zip(&colours) {
        raw[4 * k..4 * k + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
    }
    let scale = DVec2::new(w as f64, h as f64);
    let uvs = placed
        .iter()
        .flat_map(|chart| chart.map(|p| p / scale))
        .collect();
    Ok(CutTexture { uvs, image })
}
