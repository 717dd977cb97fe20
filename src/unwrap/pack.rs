//! Charts laid out for textures: each at mesh scale and turned to fill its
//! bounding rectangle best, then packed by their outlines (`outlines`: a
//! small chart may sit in a large one's notch, turned), or side by side on
//! shelves when there are many.
//!
//! An atlas spends a texel on every point of a chart's bounding rectangle,
//! so the rectangle should be the smallest one round the chart: it has a
//! side along an edge of the chart's convex hull (Freeman and Shapira
//! 1975), so trying each hull edge finds it. The turn changes no
//! distortion figure, and a tiled texture's orientation on a chart was
//! arbitrary anyway (ABF++ lays a chart out from two pinned vertices).
//! Hand-written: the hull and the caliper loop are a few lines, and a
//! geometry crate for them would be a large dependency.

use std::f64::consts::FRAC_1_SQRT_2;

use glam::DVec2;

use super::metrics;
use crate::mesh::TriMesh;
use crate::raster;

/// The upper-right corner of uvs that start at the origin.
pub fn extent(uv: &[DVec2]) -> DVec2 {
    uv.iter().fold(DVec2::ZERO, |m, &u| m.max(u))
}

/// Scale a chart's uvs so its uv area equals its 3D area, turn it so its
/// smallest bounding rectangle lies along the axes, wider than tall, and
/// move its lower-left corner to the origin.
pub fn normalise(chart: &TriMesh, uv: Vec<DVec2>) -> Vec<DVec2> {
    let uv_area: f64 = chart
        .triangles
        .iter()
        .map(|t| (metrics::face_double_area(t, &uv) / 2.0).abs())
        .sum();
    let scale = (chart.area() / uv_area.max(1e-300)).sqrt();
    let turn = tightest_turn(&uv);
    let uv: Vec<DVec2> = uv.into_iter().map(|u| turn.rotate(u) * scale).collect();
    let (lo, _) = metrics::bounds(uv.iter().copied());
    uv.into_iter().map(|u| u - lo).collect()
}

/// Place boxes of `sizes` (charts, or pieces of charts) left to right in
/// rows (shelf packing), tallest first, with a margin: returns each one's
/// offset. Of a few row widths, from the widest box's to all in one row,
/// the one whose layout has the smallest bounding box wins (an atlas is as
/// wide and as tall as its charts).
pub fn shelves(sizes: &[DVec2]) -> Vec<DVec2> {
    let total_area: f64 = sizes.iter().map(|s| s.x * s.y).sum();
    let widest = sizes.iter().map(|s| s.x).fold(0.0, f64::max);
    let margin = shelf_margin(sizes);
    let all_in_a_row: f64 = sizes.iter().map(|s| s.x + margin).sum();
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by(|&a, &b| sizes[b].y.total_cmp(&sizes[a].y).then(a.cmp(&b)));
    let layout = |row_width: f64| {
        let mut offsets = vec![DVec2::ZERO; sizes.len()];
        let (mut x, mut y, mut row_height) = (0.0, 0.0, 0.0f64);
        let mut corner = DVec2::ZERO;
        for &i in &order {
            if x > 0.0 && x + sizes[i].x > row_width {
                x = 0.0;
                y += row_height + margin;
                row_height = 0.0;
            }
            offsets[i] = DVec2::new(x, y);
            corner = corner.max(offsets[i] + sizes[i]);
            x += sizes[i].x + margin;
            row_height = row_height.max(sizes[i].y);
        }
        (corner.x * corner.y, offsets)
    };
    let widths = row_widths(
        widest,
        (all_in_a_row - widest).max(0.0),
        total_area.sqrt().max(widest),
        16,
    );
    smallest(widths.map(layout)).unwrap_or_default()
}

/// Row widths a packer tries: `steps` + 1 from `narrowest` to `narrowest +
/// span`, closer together at the narrow end, then `square`.
fn row_widths(narrowest: f64, span: f64, square: f64, steps: usize) -> impl Iterator<Item = f64> {
    (0..=steps)
        .map(move |k| narrowest + span * (k as f64 / steps as f64).powi(2))
        .chain([square])
}

/// Of (box area, layout) pairs, the layout with the smallest box (the
/// first of equals).
fn smallest<T>(layouts: impl Iterator<Item = (f64, T)>) -> Option<T> {
    layouts
        .fold(None, |best: Option<(f64, T)>, next| match best {
            Some(b) if b.0 <= next.0 => Some(b),
            _ => Some(next),
        })
        .map(|(_, layout)| layout)
}

/// Charts (triangles and uvs from the origin) placed by their outlines,
/// not their boxes: each, largest first, at the lowest then leftmost free
/// spot on a grid of about `GRID` cells across, so a small chart can sit
/// in a large one's notch; a chart may be given quarter turns to fit
/// lower. Keeps `shelves`' margin between charts and, like it, tries
/// several row widths, each with and without turns (greedy turning can
/// leave a larger box), keeping the layout with the smallest box. More
/// than `MAX_OUTLINED` charts are packed by `shelves` (each placement
/// scans the grid). Hand-written: texture-packing crates pack rectangles.
pub fn outlines(charts: &[(&[[u32; 3]], &[DVec2])]) -> Vec<Placement> {
    let sizes: Vec<DVec2> = charts.iter().map(|(_, uv)| extent(uv)).collect();
    let unturned = |offsets: Vec<DVec2>| {
        offsets
            .into_iter()
            .map(|offset| Placement { turns: 0, offset })
            .collect()
    };
    if charts.len() < 2 || charts.len() > MAX_OUTLINED {
        return unturned(shelves(&sizes));
    }
    let box_area: f64 = sizes.iter().map(|s| s.x * s.y).sum();
    let widest = sizes.iter().map(|s| s.x.max(s.y)).fold(0.0, f64::max);
    let margin = shelf_margin(&sizes);
    let cell = box_area.sqrt().max(widest) / GRID as f64;
    if !cell.is_finite() || cell <= 0.0 {
        return unturned(shelves(&sizes));
    }
    let gap = (margin / cell).ceil() as usize;
    // Per chart and quarter turn: its cells, and its cells grown by the gap.
    let masks: Vec<Vec<(Mask, Mask)>> = charts
        .iter()
        .map(|(triangles, uv)| {
            (0..TURNS)
                .map(|t| {
                    let m = Mask::of(triangles, &turned(uv, t), cell);
                    let grown = m.dilated(gap);
                    (m, grown)
                })
                .collect()
        })
        .collect();
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by(|&a, &b| {
        masks[b][0]
            .0
            .count()
            .cmp(&masks[a][0].0.count())
            .then(a.cmp(&b))
    });
    let widest_cells = masks
        .iter()
        .map(|m| m[0].0.width.max(m[1].0.width))
        .max()
        .unwrap_or(0);
    let all_in_a_row: usize = masks.iter().map(|m| m[0].0.width + gap).sum();
    let layout = |(row_width, turns): (usize, u8)| {
        let mut free = Grid::new(row_width);
        let mut placed = vec![
            Placement {
                turns: 0,
                offset: DVec2::ZERO
            };
            charts.len()
        ];
        let mut corner = DVec2::ZERO;
        for &i in &order {
            // The lowest, then leftmost, spot over the turns that fit.
            let (y, x, t) = (0..turns)
                .filter(|&t| masks[i][t as usize].1.width <= row_width)
                .map(|t| {
                    let (x, y) = free.lowest_fit(&masks[i][t as usize].1);
                    (y, x, t)
                })
                .min()
                .expect("the row fits every chart unturned");
            free.occupy(&masks[i][t as usize].0, x + gap, y + gap);
            // The mask's cell (0, 0) holds the chart's origin.
            let offset = DVec2::new((x + gap) as f64, (y + gap) as f64) * cell;
            let size = if t % 2 == 0 {
                sizes[i]
            } else {
                DVec2::new(sizes[i].y, sizes[i].x)
            };
            corner = corner.max(offset + size);
            placed[i] = Placement { turns: t, offset };
        }
        // The first chart's margin from the layout's edge is not needed.
        let lo = placed.iter().fold(DVec2::INFINITY, |m, p| m.min(p.offset));
        let corner = corner - lo;
        for p in &mut placed {
            p.offset -= lo;
        }
        (corner.x * corner.y, placed)
    };
    let fits_all = masks.iter().map(|m| m[0].1.width).max().unwrap_or(0);
    let widths = row_widths(
        (widest_cells + gap) as f64,
        all_in_a_row.saturating_sub(widest_cells) as f64,
        (box_area.sqrt() / cell).floor() + (widest_cells / 2) as f64,
        8,
    );
    let tries = widths
        .map(|w| (w as usize).max(fits_all))
        .flat_map(|w| [(w, 1), (w, TURNS)]);
    smallest(tries.map(layout)).unwrap_or_default()
}

/// Where `outlines` put a chart: turned by `turns` quarter turns
/// (counter-clockwise, `turned`), then moved by `offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub turns: u8,
    pub offset: DVec2,
}

impl Placement {
    /// The chart's uvs (from the origin) where it was placed.
    pub fn apply(&self, uv: &[DVec2]) -> Vec<DVec2> {
        turned(uv, self.turns)
            .into_iter()
            .map(|u| u + self.offset)
            .collect()
    }
}

/// Quarter turns `outlines` tries.
const TURNS: u8 = 4;

/// Uvs from the origin turned by `turns` quarter turns counter-clockwise,
/// still from the origin.
fn turned(uv: &[DVec2], turns: u8) -> Vec<DVec2> {
    let size = extent(uv);
    uv.iter()
        .map(|&u| match turns % 4 {
            0 => u,
            1 => DVec2::new(size.y - u.y, u.x),
            2 => size - u,
            _ => DVec2::new(u.y, size.x - u.x),
        })
        .collect()
}

/// Cells across the square of the charts' total box area (`outlines`).
const GRID: usize = 160;
/// The most charts `outlines` places one by one.
const MAX_OUTLINED: usize = 64;

/// The cells a chart covers: row by row, bits from the left.
struct Mask {
    width: usize,
    rows: Vec<Vec<u64>>,
}

impl Mask {
    /// Every cell of side `cell` that a triangle touches: the rasteriser's
    /// cells whose centre lies within half a diagonal of a triangle (a
    /// superset: the distance it measures is never more than the true one).
    fn of(triangles: &[[u32; 3]], uv: &[DVec2], cell: f64) -> Mask {
        let size = extent(uv) / cell;
        let (width, height) = (size.x.ceil() as usize + 1, size.y.ceil() as usize + 1);
        let mut mask = Mask::empty(width, height);
        for t in triangles {
            let p = t.map(|v| uv[v as usize] / cell);
            raster::triangle_padded(p, width, height, FRAC_1_SQRT_2, |x, y, _| mask.set(x, y));
        }
        mask
    }

    fn empty(width: usize, height: usize) -> Mask {
        Mask {
            width,
            rows: vec![vec![0; width.div_ceil(64)]; height],
        }
    }

    fn set(&mut self, x: usize, y: usize) {
        self.rows[y][x / 64] |= 1 << (x % 64);
    }

    fn get(&self, x: usize, y: usize) -> bool {
        self.rows[y][x / 64] >> (x % 64) & 1 == 1
    }

    fn count(&self) -> u32 {
        self.rows.iter().flatten().map(|w| w.count_ones()).sum()
    }

    /// Grown by `by` cells on every side (a square neighbourhood), shifted
    /// so the original cell (0, 0) is at (`by`, `by`).
    fn dilated(&self, by: usize) -> Mask {
        let height = self.rows.len();
        let mut out = Mask::empty(self.width + 2 * by, height + 2 * by);
        for y in 0..height {
            for x in (0..self.width).filter(|&x| self.get(x, y)) {
                for yy in y..=y + 2 * by {
                    for xx in x..=x + 2 * by {
                        out.set(xx, yy);
                    }
                }
            }
        }
        out
    }
}

/// The occupied cells of a layout `width` cells wide, growing upwards.
struct Grid {
    mask: Mask,
}

impl Grid {
    fn new(width: usize) -> Grid {
        Grid {
            mask: Mask::empty(width, 0),
        }
    }

    /// Whether `m` placed with its cell (0, 0) at (x, y) covers an
    /// occupied cell (rows above the layout are free).
    fn collides(&self, m: &Mask, x: usize, y: usize) -> bool {
        m.rows.iter().enumerate().any(|(dy, row)| {
            let Some(free) = self.mask.rows.get(y + dy) else {
                return false;
            };
            row.iter().enumerate().any(|(k, &bits)| {
                if bits == 0 {
                    return false;
                }
                // Bits k*64.. of the mask land at x + k*64..: two words.
                let at = x + 64 * k;
                let (word, shift) = (at / 64, at % 64);
                let low = bits << shift;
                let high = if shift == 0 { 0 } else { bits >> (64 - shift) };
                free.get(word).is_some_and(|&w| w & low != 0)
                    || free.get(word + 1).is_some_and(|&w| w & high != 0)
            })
        })
    }

    /// The lowest, then leftmost, spot where `m` fits inside the width.
    fn lowest_fit(&self, m: &Mask) -> (usize, usize) {
        let span = self.mask.width.saturating_sub(m.width);
        (0..)
            .find_map(|y| {
                (0..=span)
                    .find(|&x| !self.collides(m, x, y))
                    .map(|x| (x, y))
            })
            .expect("the rows above the layout are free")
    }

    fn occupy(&mut self, m: &Mask, x: usize, y: usize) {
        let words = self.mask.width.div_ceil(64);
        while self.mask.rows.len() < y + m.rows.len() {
            self.mask.rows.push(vec![0; words]);
        }
        for dy in 0..m.rows.len() {
            for dx in (0..m.width).filter(|&dx| m.get(dx, dy)) {
                if x + dx < self.mask.width {
                    self.mask.set(x + dx, y + dy);
                }
            }
        }
    }
}

/// The gap left between packed charts: 2% of the side of their total box
/// area (or of the widest).
fn shelf_margin(sizes: &[DVec2]) -> f64 {
    let total_area: f64 = sizes.iter().map(|s| s.x * s.y).sum();
    let widest = sizes.iter().map(|s| s.x).fold(0.0, f64::max);
    0.02 * total_area.sqrt().max(widest)
}

/// The rotation (as a unit vector, applied with `DVec2::rotate`) that lays
/// the smallest rectangle round `points` along the axes, its longer side
/// along x.
fn tightest_turn(points: &[DVec2]) -> DVec2 {
    let hull = convex_hull(points);
    let mut best = (f64::INFINITY, DVec2::X);
    for i in 0..hull.len() {
        let d = hull[(i + 1) % hull.len()] - hull[i];
        let Some(along) = d.try_normalize() else {
            continue;
        };
        // Turning by the inverse of `along` lays this edge along x.
        let turn = DVec2::new(along.x, -along.y);
        let (lo, hi) = metrics::bounds(hull.iter().map(|&p| turn.rotate(p)));
        let size = hi - lo;
        let area = size.x * size.y;
        if area < best.0 * (1.0 - 1e-9) {
            // Longer side along x: a quarter turn more when taller.
            let turn = if size.y > size.x {
                turn.perp() * -1.0
            } else {
                turn
            };
            best = (area, turn);
        }
    }
    best.1
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's
/// monotone chain).
fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::unwrap::intersect::triangles_overlap;

    #[test]
    fn a_turned_rectangle_is_turned_back_wider_than_tall() {
        // A 4 x 1 rectangle with a bump, turned by 0.7 rad.
        let shape = [
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 1.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(1.0, 0.5),
            DVec2::new(0.0, 1.0),
        ];
        let angle = DVec2::from_angle(0.7);
        let turned: Vec<DVec2> = shape.iter().map(|&p| angle.rotate(p)).collect();
        let turn = tightest_turn(&turned);
        let back: Vec<DVec2> = turned.iter().map(|&p| turn.rotate(p)).collect();
        let (lo, hi) = metrics::bounds(back.iter().copied());
        let size = hi - lo;
        assert!(
            (size.x - 4.0).abs() < 1e-9 && (size.y - 1.0).abs() < 1e-9,
            "{size}"
        );
        // A turn, not a reflection: orientation is kept.
        let area = |q: &[DVec2]| {
            (1..q.len() - 1)
                .map(|i| (q[i] - q[0]).perp_dot(q[i + 1] - q[0]))
                .sum::<f64>()
        };
        assert!((area(&back) - area(&shape)).abs() < 1e-9);
    }

    /// Triangles of unit squares at `cells` (x, y), with their uvs.
    fn squares(cells: &[(f64, f64)], side: f64) -> (Vec<[u32; 3]>, Vec<DVec2>) {
        let mut uv = Vec::new();
        let mut triangles = Vec::new();
        for &(x, y) in cells {
            let b = uv.len() as u32;
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                uv.push(DVec2::new(x + dx, y + dy) * side);
            }
            triangles.extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
        }
        (triangles, uv)
    }

    #[test]
    fn a_small_chart_sits_in_a_large_ones_notch_without_overlapping_it() {
        // A 4 x 4 L missing its upper-right 2 x 2 quarter, and a 1.5 x 1.5
        // square: shelves put them side by side, outlines in the notch.
        let (l_tris, l_uv) = squares(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)], 2.0);
        let (s_tris, s_uv) = squares(&[(0.0, 0.0)], 1.5);
        let charts = [(&l_tris[..], &l_uv[..]), (&s_tris[..], &s_uv[..])];
        let placements = outlines(&charts);
        let placed: Vec<Vec<DVec2>> = charts
            .iter()
            .zip(&placements)
            .map(|((_, uv), p)| p.apply(uv))
            .collect();
        let (lo, hi) = metrics::bounds(placed.iter().flatten().copied());
        let packed = (hi - lo).x * (hi - lo).y;
        let sizes = [extent(&l_uv), extent(&s_uv)];
        let shelf = shelves(&sizes);
        let shelf_corner = (0..2).fold(DVec2::ZERO, |m, i| m.max(shelf[i] + sizes[i]));
        assert!(
            packed < 0.8 * shelf_corner.x * shelf_corner.y,
            "outlines {packed}, shelves {}",
            shelf_corner.x * shelf_corner.y
        );
        assert!((hi - lo).x < 4.5 && (hi - lo).y < 4.5, "{lo} {hi}");
        // The square lies in the L's box, off every L triangle by at least
        // the margin: its box grown by the margin overlaps none of them.
        let (l_lo, l_hi) = metrics::bounds(placed[0].iter().copied());
        let (s_lo, s_hi) = metrics::bounds(placed[1].iter().copied());
        assert!(
            s_lo.cmpge(l_lo).all() && s_hi.cmple(l_hi).all(),
            "{s_lo}..{s_hi} in {l_lo}..{l_hi}"
        );
        let m = 0.99 * shelf_margin(&[extent(&l_uv), extent(&s_uv)]);
        let (g_lo, g_hi) = (s_lo - m, s_hi + m);
        let grown = [
            g_lo,
            DVec2::new(g_hi.x, g_lo.y),
            g_hi,
            DVec2::new(g_lo.x, g_hi.y),
        ];
        for t in &l_tris {
            let p = t.map(|v| placed[0][v as usize]);
            for half in [[0, 1, 2], [0, 2, 3]] {
                assert!(
                    !triangles_overlap(p, half.map(|k| grown[k]), 0.0),
                    "an L triangle within the margin"
                );
            }
        }
    }

    #[test]
    fn a_quarter_turn_keeps_a_chart_from_the_origin_and_its_orientation() {
        let (tris, uv) = squares(&[(0.0, 0.0), (1.0, 0.0)], 1.0);
        let area =
            |uv: &[DVec2]| -> f64 { tris.iter().map(|t| metrics::face_double_area(t, uv)).sum() };
        for turns in 0..4 {
            let q = turned(&uv, turns);
            let (lo, hi) = metrics::bounds(q.iter().copied());
            assert!(lo.abs_diff_eq(DVec2::ZERO, 1e-12), "{turns}: {lo}");
            let size = if turns % 2 == 0 {
                DVec2::new(2.0, 1.0)
            } else {
                DVec2::new(1.0, 2.0)
            };
            assert!(hi.abs_diff_eq(size, 1e-12), "{turns}: {hi}");
            assert!((area(&q) - area(&uv)).abs() < 1e-12, "{turns}: mirrored");
        }
    }

    #[test]
    fn the_hull_drops_inner_and_collinear_points() {
        let points = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 2.0),
        ];
        assert_eq!(
            convex_hull(&points),
            [
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(0.0, 2.0)
            ]
        );
    }
}
