//! Charts laid out for textures: each at mesh scale and turned to fill its
//! bounding rectangle best, then packed side by side.
//!
//! An atlas spends a texel on every point of a chart's bounding rectangle,
//! so the rectangle should be the smallest one round the chart: it has a
//! side along an edge of the chart's convex hull (Freeman and Shapira
//! 1975), so trying each hull edge finds it. The turn changes no
//! distortion figure, and a tiled texture's orientation on a chart was
//! arbitrary anyway (ABF++ lays a chart out from two pinned vertices).
//! Hand-written: the hull and the caliper loop are a few lines, and a
//! geometry crate for them would be a large dependency.

use glam::DVec2;

use super::metrics;
use crate::mesh::TriMesh;

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
    let margin = 0.02 * total_area.sqrt().max(widest);
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
    const WIDTHS: usize = 16;
    (0..=WIDTHS)
        .map(|k| widest + (all_in_a_row - widest).max(0.0) * (k as f64 / WIDTHS as f64).powi(2))
        .chain([total_area.sqrt().max(widest)])
        .map(layout)
        .fold(None, |best: Option<(f64, Vec<DVec2>)>, next| match best {
            Some(b) if b.0 <= next.0 => Some(b),
            _ => Some(next),
        })
        .map_or_else(Vec::new, |(_, offsets)| offsets)
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
