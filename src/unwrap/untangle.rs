//! Unfold the few triangles a flattening flipped, by moving single
//! vertices.
//!
//! On raw scans, a layout can be right everywhere but at a handful of
//! slivers along a hole's rim or a seam's tip, where a boundary vertex sits
//! on the wrong side of the opposite edge of one of its triangles. Every
//! triangle around a vertex v asks v to lie to the left of its opposite
//! edge a -> b (counter-clockwise); where those half-planes share a point,
//! v moves there and all its triangles are unfolded at once. Points are
//! found by cyclic projection onto the violated half-planes from where v
//! is, so v moves as little as it can; a vertex whose half-planes share no
//! point stays, and another corner of the flipped triangle may move
//! instead.

use glam::DVec2;

use super::metrics::{double_area, face_double_area};
use crate::mesh::TriMesh;

/// Unfold a chart's layout: no triangle flipped or thinner than a
/// thousandth of its own surface area at the layout's scale. Returns the
/// triangles still bad (`untangle`, 10 passes).
pub fn unfold_layout(chart: &TriMesh, uv: &mut [DVec2]) -> usize {
    let area_3d: Vec<f64> = (0..chart.num_faces())
        .map(|f| 2.0 * chart.face_area(f))
        .collect();
    let area_uv: f64 = chart
        .triangles
        .iter()
        .map(|t| face_double_area(t, uv).abs())
        .sum();
    let scale = area_uv / area_3d.iter().sum::<f64>().max(1e-300);
    let least: Vec<f64> = area_3d.iter().map(|a| 1e-3 * a * scale).collect();
    untangle(&chart.triangles, uv, &least, 10)
}

/// Move vertices of `uv` until no triangle of `triangles` is flipped or
/// thinner than `least[f]` (a double area), or `passes` passes over the
/// bad ones change nothing. Returns the triangles still bad.
pub fn untangle(triangles: &[[u32; 3]], uv: &mut [DVec2], least: &[f64], passes: usize) -> usize {
    let is_bad = |f: usize, uv: &[DVec2]| {
        // Not above its least area, or not a number.
        double_area(triangles[f].map(|v| uv[v as usize])).partial_cmp(&least[f])
            != Some(std::cmp::Ordering::Greater)
    };
    let mut bad: Vec<usize> = (0..triangles.len()).filter(|&f| is_bad(f, uv)).collect();
    // Local repair is for a few slivers; a layout folded or crushed
    // wholesale is left for the caller to judge.
    if bad.is_empty() || bad.len() > 16 + triangles.len() / 100 {
        return bad.len();
    }
    // Triangles around each vertex, as their index and the opposite edge
    // in counter-clockwise order.
    let mut ring: Vec<Vec<(usize, [u32; 2])>> = vec![Vec::new(); uv.len()];
    for (f, t) in triangles.iter().enumerate() {
        for c in 0..3 {
            ring[t[c] as usize].push((f, [t[(c + 1) % 3], t[(c + 2) % 3]]));
        }
    }
    for _ in 0..passes {
        let before = bad.len();
        for &f in &bad {
            for &v in &triangles[f] {
                if !is_bad(f, uv) {
                    break;
                }
                // A well-shaped ring if there is room, a thin one if not.
                let ring = &ring[v as usize];
                let point = [100.0, 10.0, 1.0].into_iter().find_map(|k| {
                    let wanted: Vec<f64> = ring.iter().map(|&(g, _)| k * least[g]).collect();
                    kernel_point(ring, uv, &wanted, uv[v as usize])
                });
                if let Some(p) = point.or_else(|| deepest_point(ring, uv, least)) {
                    uv[v as usize] = p;
                }
            }
        }
        bad = (0..triangles.len()).filter(|&f| is_bad(f, uv)).collect();
        if bad.is_empty() || bad.len() >= before {
            break;
        }
    }
    bad.len()
}

/// A point near `from` to the left of every edge a -> b of `ring`, with
/// each triangle's double area above `wanted` (one per ring entry; times
/// 1.01, so rounding cannot undo it), if projection finds one.
fn kernel_point(
    ring: &[(usize, [u32; 2])],
    uv: &[DVec2],
    wanted: &[f64],
    from: DVec2,
) -> Option<DVec2> {
    let mut p = from;
    for _ in 0..200 {
        let mut worst = 0.0f64;
        for (k, &(_, [a, b])) in ring.iter().enumerate() {
            let (a, b) = (uv[a as usize], uv[b as usize]);
            let edge = b - a;
            let len2 = edge.length_squared();
            if len2 == 0.0 {
                return None;
            }
            // Double area of (p, a, b) = edge x (p - a).
            let short = 1.01 * wanted[k].max(0.0) - edge.perp_dot(p - a);
            if short > 0.0 {
                // Step out along the edge's left normal, slightly past.
                p += edge.perp() * (1.01 * short / len2);
                worst = worst.max(short);
            }
        }
        if worst == 0.0 {
            return Some(p);
        }
    }
    None
}

/// The point deepest inside every edge a -> b of `ring` (the centre of
/// the largest circle on their left, kept within the ring's bounds), if
/// it lies strictly inside: a two-variable linear programme, solved by
/// trying every three constraints, as rings are small.
fn deepest_point(ring: &[(usize, [u32; 2])], uv: &[DVec2], least: &[f64]) -> Option<DVec2> {
    // Each constraint: n . p - c >= t, n a unit normal pointing inside.
    let mut halves: Vec<(DVec2, f64)> = Vec::with_capacity(ring.len() + 4);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for &(_, [a, b]) in ring {
        let (a, b) = (uv[a as usize], uv[b as usize]);
        lo = lo.min(a).min(b);
        hi = hi.max(a).max(b);
        let n = (b - a).perp();
        let len = n.length();
        if len == 0.0 {
            return None;
        }
        halves.push((n / len, (n / len).dot(a)));
    }
    // The ring's box, so a boundary vertex's open fan has a deepest point.
    for (n, at) in [
        (DVec2::X, lo),
        (DVec2::Y, lo),
        (DVec2::NEG_X, hi),
        (DVec2::NEG_Y, hi),
    ] {
        halves.push((n, n.dot(at)));
    }
    let mut best: Option<(f64, DVec2)> = None;
    let k = halves.len();
    for i in 0..k {
        for j in i + 1..k {
            for l in j + 1..k {
                // n . p - t = c for the three.
                let m = glam::DMat3::from_cols(
                    glam::DVec3::new(halves[i].0.x, halves[j].0.x, halves[l].0.x),
                    glam::DVec3::new(halves[i].0.y, halves[j].0.y, halves[l].0.y),
                    glam::DVec3::splat(-1.0),
                );
                if m.determinant().abs() < 1e-12 {
                    continue;
                }
                let x = m.inverse() * glam::DVec3::new(halves[i].1, halves[j].1, halves[l].1);
                let (p, t) = (DVec2::new(x.x, x.y), x.z);
                let feasible = halves
                    .iter()
                    .all(|&(n, c)| n.dot(p) - c >= t - 1e-12 * (1.0 + t.abs()));
                if feasible && best.is_none_or(|(d, _)| t > d) {
                    best = Some((t, p));
                }
            }
        }
    }
    // Deep enough for every triangle's least area.
    let (_, p) = best?;
    ring.iter()
        .all(|&(f, [a, b])| double_area([p, uv[a as usize], uv[b as usize]]) > least[f].max(0.0))
        .then_some(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_vertex_pushed_across_its_ring_comes_back() {
        // A hexagon fan with its centre dragged outside the rim: two
        // triangles flip; moving the centre back unfolds them.
        let mut uv: Vec<DVec2> = (0..6)
            .map(|k| DVec2::from_angle(std::f64::consts::TAU * k as f64 / 6.0))
            .collect();
        uv.push(DVec2::new(1.3, 0.2));
        let triangles: Vec<[u32; 3]> = (0..6).map(|k| [6, k, (k + 1) % 6]).collect();
        let folded = triangles
            .iter()
            .filter(|t| double_area(t.map(|v| uv[v as usize])) <= 0.0)
            .count();
        assert!(folded > 0);
        assert_eq!(untangle(&triangles, &mut uv, &[1e-3; 6], 5), 0);
        assert!(uv[6].length() < 1.0, "inside the rim: {:?}", uv[6]);
    }

    #[test]
    fn a_layout_without_flips_is_left_untouched() {
        let mut uv: Vec<DVec2> = (0..6)
            .map(|k| DVec2::from_angle(std::f64::consts::TAU * k as f64 / 6.0))
            .collect();
        uv.push(DVec2::new(0.3, -0.1));
        let triangles: Vec<[u32; 3]> = (0..6).map(|k| [6, k, (k + 1) % 6]).collect();
        let before = uv.clone();
        assert_eq!(untangle(&triangles, &mut uv, &[1e-3; 6], 5), 0);
        assert_eq!(uv, before);
    }
}
