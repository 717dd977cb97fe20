//! Atlas baking: each facet's own faces rasterised in its uv charts, every
//! texel the colour the compositor gives that point (tiled texture, overlay,
//! seam bands, rings of later facets, all blended in), for engines that
//! draw no alpha layers. The charts must not overlap (the bake unwraps with
//! `split_overlaps` for atlases).

use glam::DVec2;
use rayon::prelude::*;

use super::build::{BakedFacet, BakedNode};
use super::composite::{Compositor, linear_to_srgb};
use crate::raster;
use crate::unwrap::metrics::bounds;

/// A facet's baked texture and where its chart sits in it.
#[derive(Clone, Debug)]
pub struct Atlas {
    pub width: usize,
    pub height: usize,
    /// sRGB, row by row from the top.
    pub pixels: Vec<[u8; 3]>,
    /// The share of texels the facet's own faces cover.
    pub texel_use: f64,
    /// How far apart its seams' two sides are in its filtering, as baked
    /// and after `seam_erasure::erase`; `None` without seams or erasure.
    pub seam_mismatch: Option<[f64; 2]>,
    /// Per texel: whether a face of its charts covers the texel's centre
    /// (what seam erasure may move freely is off the charts).
    pub(super) inside: Vec<bool>,
    lo: DVec2,
    /// Texels per uv (mesh) unit.
    density: f64,
}

/// Texels of margin round the charts, for filtering across their edges.
const MARGIN: f64 = 4.0;

impl Atlas {
    /// Texel coordinates (0..width, 0..height, v down) of chart uv `uv`.
    pub(super) fn texel(&self, uv: DVec2) -> DVec2 {
        (uv - self.lo) * self.density + DVec2::splat(MARGIN)
    }

    /// The side of one texel in uv (mesh) units.
    pub fn texel_size(&self) -> f64 {
        1.0 / self.density
    }

    /// Texture coordinates (0..1, v down) of chart uv `uv`.
    pub fn texcoord(&self, uv: DVec2) -> DVec2 {
        self.texel(uv) / DVec2::new(self.width as f64, self.height as f64)
    }

    /// The four texels bilinear filtering reads at texel coordinates `p`
    /// (clamped to the atlas), with their weights.
    pub(super) fn taps(&self, p: DVec2) -> [(usize, f64); 4] {
        let t = p - DVec2::splat(0.5);
        let (x0, y0) = (t.x.floor(), t.y.floor());
        let (fx, fy) = (t.x - x0, t.y - y0);
        let at = |x: f64, y: f64| {
            let xi = (x as i64).clamp(0, self.width as i64 - 1) as usize;
            let yi = (y as i64).clamp(0, self.height as i64 - 1) as usize;
            yi * self.width + xi
        };
        [
            (at(x0, y0), (1.0 - fx) * (1.0 - fy)),
            (at(x0 + 1.0, y0), fx * (1.0 - fy)),
            (at(x0, y0 + 1.0), (1.0 - fx) * fy),
            (at(x0 + 1.0, y0 + 1.0), fx * fy),
        ]
    }

    /// Bilinear sample at chart uv `uv`, in sRGB 0-255.
    pub fn sample(&self, uv: DVec2) -> [f64; 3] {
        let mut c = [0.0; 3];
        for (t, w) in self.taps(self.texel(uv)) {
            for (i, v) in c.iter_mut().enumerate() {
                *v += w * self.pixels[t][i] as f64;
            }
        }
        c
    }
}

/// The corners of the box holding `facet`'s own faces' charts (uv units
/// are mesh units), or only those of its faces that `keep`.
fn chart_box_of(facet: &BakedFacet, keep: impl Fn(usize) -> bool) -> (DVec2, DVec2) {
    let piece = &facet.piece;
    let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
    bounds(
        layer.triangles[..piece.own]
            .iter()
            .enumerate()
            .filter(|&(f, _)| keep(f))
            .flat_map(|(_, t)| t)
            .map(|&c| layer.coords[c as usize]),
    )
}

fn chart_box(facet: &BakedFacet) -> (DVec2, DVec2) {
    chart_box_of(facet, |_| true)
}

/// The widest box round what the viewpoints see of a facet, in mesh units,
/// over the facets mostly in sight (a uterus's serosa is wide, and the
/// hysteroscope sees of it only the ring round the canal, which its chart
/// may spread wide: it must not blur the wall; a facet mostly out of sight
/// gets a lower density of its own in `bake`). Every facet's seen box when
/// none is mostly in sight, their whole boxes when nothing is seen.
fn widest_seen(nodes: &[BakedNode]) -> f64 {
    let widest = |keep_seen: bool, min_seen: f64| {
        nodes
            .iter()
            .flat_map(|n| &n.facets)
            .filter(|f| f.report.seen >= min_seen)
            .map(|f| {
                let (lo, hi) = chart_box_of(f, |g| !keep_seen || f.seen[g]);
                (hi - lo).max(DVec2::ZERO).max_element()
            })
            .fold(0.0, f64::max)
    };
    [(true, 0.5), (true, 0.0), (false, 0.0)]
        .into_iter()
        .map(|(keep_seen, min_seen)| widest(keep_seen, min_seen))
        .find(|&w| w > 0.0)
        .unwrap_or(0.0)
}

/// Atlas texels per mesh unit when the widest box round what is seen of a
/// facet gets `largest` texels, margins included.
pub fn density(nodes: &[BakedNode], largest: usize) -> f64 {
    (largest as f64 - 2.0 * MARGIN).max(1.0) / widest_seen(nodes).max(1e-300)
}

/// Bake `facet`'s atlas from `compositor` at `density` texels per mesh
/// unit (one density across the scene, so a tissue seen across a facet
/// border is equally sharp on both sides; lower for a facet too wide for
/// `largest` texels at it, which only a facet mostly out of sight can be):
/// as wide and as tall as the facet's charts, plus margins.
/// (`seam_erasure::erase` then joins its seams and borders in the
/// atlases' filtering.)
pub fn bake(
    node: &BakedNode,
    facet: &BakedFacet,
    compositor: &Compositor,
    density: f64,
    largest: usize,
) -> Atlas {
    let (lo, hi) = chart_box(facet);
    let size = (hi - lo).max(DVec2::ZERO);
    let fits = (largest as f64 - 2.0 * MARGIN).max(1.0) / size.max_element().max(1e-300);
    let density = density.min(fits);
    let piece = &facet.piece;
    let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
    let side = |e: f64| ((e * density - 1e-6).ceil() as usize + 2 * MARGIN as usize).max(16);
    let (width, height) = (side(size.x), side(size.y));
    let mut atlas = Atlas {
        width,
        height,
        pixels: vec![[0, 0, 0]; width * height],
        texel_use: 0.0,
        seam_mismatch: None,
        inside: Vec::new(),
        lo,
        density,
    };
    let texel_uv: Vec<[DVec2; 3]> = (0..piece.own)
        .map(|f| layer.triangles[f].map(|c| atlas.texel(layer.coords[c as usize])))
        .collect();
    // Each texel's face: the one holding its centre, else the nearest one
    // within PAD texels (the texel then shows the chart continued past its
    // edge). Ties go to the lower face number, so the result is the same
    // whatever the order. Coverage is cheap; colours are the cost, so they
    // are computed once per texel, in parallel, below.
    const PAD: f64 = 2.0;
    let mut best = vec![(f32::INFINITY, u32::MAX); width * height];
    for (f, &tri) in texel_uv.iter().enumerate() {
        raster::triangle_padded(tri, width, height, PAD, |x, y, outside| {
            let candidate = (outside as f32, f as u32);
            let slot = &mut best[y * width + x];
            if candidate < *slot {
                *slot = candidate;
            }
        });
    }
    // Mesh units per texel: textures finer than that are averaged down.
    let footprint = 1.0 / density;
    let node_order: Vec<[usize; 3]> = (0..piece.own)
        .map(|f| piece.corner_order(&node.mesh, f))
        .collect();
    atlas
        .pixels
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, pixel) in row.iter_mut().enumerate() {
                let (_, f) = best[y * width + x];
                if f == u32::MAX {
                    continue;
                }
                let f = f as usize;
                let centre = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let Some(w) = raster::barycentric(texel_uv[f], centre) else {
                    continue;
                };
                let mut node_w = [0.0; 3];
                for i in 0..3 {
                    node_w[node_order[f][i]] = w[i];
                }
                let c = compositor.colour_over(piece.face_origin[f] as usize, node_w, footprint);
                *pixel = c.map(|v| (linear_to_srgb(v) * 255.0).round() as u8);
            }
        });
    // Texels whose centre a face covers (the padding round the charts
    // does not count).
    atlas.texel_use =
        best.iter().filter(|&&(d, _)| d == 0.0).count() as f64 / (width * height) as f64;
    let mut covered: Vec<bool> = best.iter().map(|&(_, f)| f != u32::MAX).collect();
    dilate(&mut atlas.pixels, &mut covered, [width, height], 4);
    atlas.inside = best.iter().map(|&(d, _)| d == 0.0).collect();
    atlas
}

/// Spread covered texels into uncovered neighbours, `steps` times, so
/// filtering at chart edges never reads background.
fn dilate(pixels: &mut [[u8; 3]], covered: &mut [bool], [width, height]: [usize; 2], steps: usize) {
    for _ in 0..steps {
        let before = covered.to_vec();
        let source = pixels.to_vec();
        for y in 0..height {
            for x in 0..width {
                let i = y * width + x;
                if before[i] {
                    continue;
                }
                let mut sum = [0u32; 3];
                let mut n = 0;
                for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < width && (ny as usize) < height {
                        let j = ny as usize * width + nx as usize;
                        if before[j] {
                            for c in 0..3 {
                                sum[c] += source[j][c] as u32;
                            }
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    pixels[i] = sum.map(|s| (s / n) as u8);
                    covered[i] = true;
                }
            }
        }
    }
}
