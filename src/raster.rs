//! Scan conversion of 2D triangles onto a pixel grid: the one rasteriser
//! behind visibility depth buffers, debug images and texture baking.
//!
//! Written here rather than taken from a crate: what is needed is twenty
//! lines of edge functions with barycentric weights, and the crates that
//! rasterise (tiny-skia, raqote) draw paths, not interpolated triangles.

use glam::DVec2;

/// Call `visit(x, y, [w0, w1, w2])` for every pixel of a `width` x `height`
/// grid whose centre `(x + 0.5, y + 0.5)` lies inside or on triangle
/// (a, b, c), with the barycentric weights of that centre. Either winding;
/// degenerate triangles cover nothing.
pub fn triangle(
    [a, b, c]: [DVec2; 3],
    width: usize,
    height: usize,
    mut visit: impl FnMut(usize, usize, [f64; 3]),
) {
    let area = (b - a).perp_dot(c - a);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let lo = a.min(b).min(c);
    let hi = a.max(b).max(c);
    let inv = 1.0 / area;
    for y in centres_within(lo.y, hi.y, height) {
        for x in centres_within(lo.x, hi.x, width) {
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let w0 = (c - b).perp_dot(p - b) * inv;
            let w1 = (a - c).perp_dot(p - c) * inv;
            let w2 = 1.0 - w0 - w1;
            if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                visit(x, y, [w0, w1, w2]);
            }
        }
    }
}

/// The pixels of a row of `n` whose centres `x + 0.5` lie in [lo, hi].
///
/// By truncating casts rather than `ceil` and `floor`: without SSE4.1
/// (not in the baseline x86-64 target) those are calls into libm, and a
/// visibility view rasterises some 28k triangles of a few pixels each
/// (on the bunny the calls were 3% of the visibility stage's samples,
/// the rasteriser 42%).
fn centres_within(lo: f64, hi: f64, n: usize) -> std::ops::Range<usize> {
    let (first, last) = (lo - 0.5, hi - 0.5);
    // ceil(first), at least 0 (a NaN gives 0, as `ceil` then `max` did).
    let start = if first > 0.0 {
        let t = first as usize;
        t.saturating_add(((t as f64) < first) as usize)
    } else {
        0
    };
    // floor(last) + 1, within [0, n].
    let end = if last >= 0.0 {
        (last as usize).saturating_add(1).min(n)
    } else {
        0
    };
    start..end
}

/// Barycentric weights of `p` in triangle (a, b, c), `None` when the
/// triangle is degenerate.
pub fn barycentric([a, b, c]: [DVec2; 3], p: DVec2) -> Option<[f64; 3]> {
    let area = (b - a).perp_dot(c - a);
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let w0 = (c - b).perp_dot(p - b) / area;
    let w1 = (a - c).perp_dot(p - c) / area;
    Some([w0, w1, 1.0 - w0 - w1])
}

/// Like [`triangle`], but also every pixel whose centre lies within `pad`
/// pixels outside the triangle, visited as `visit(x, y, outside)` with
/// `outside` its distance past the farthest edge it is beyond (0 inside).
/// For texture baking: texels just past a chart's edge get the colour the
/// chart would have there, so filtering across the edge reads no
/// background.
pub fn triangle_padded(
    tri: [DVec2; 3],
    width: usize,
    height: usize,
    pad: f64,
    mut visit: impl FnMut(usize, usize, f64),
) {
    let [a, b, c] = tri;
    let area = (b - a).perp_dot(c - a).abs();
    if area == 0.0 || !area.is_finite() {
        return;
    }
    // Distance from the line of the edge opposite corner i per unit of w_i.
    let heights = [(c - b).length(), (a - c).length(), (b - a).length()].map(|l| area / l);
    let lo = a.min(b).min(c) - DVec2::splat(pad);
    let hi = a.max(b).max(c) + DVec2::splat(pad);
    for y in centres_within(lo.y, hi.y, height) {
        for x in centres_within(lo.x, hi.x, width) {
            let w = barycentric(tri, DVec2::new(x as f64 + 0.5, y as f64 + 0.5))
                .expect("not degenerate");
            let outside = (0..3).map(|i| -w[i] * heights[i]).fold(0.0, f64::max);
            if outside <= pad {
                visit(x, y, outside);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_of_a_square_cover_each_pixel_once_or_on_the_diagonal_twice() {
        let n = 16;
        let s = n as f64;
        let mut count = vec![0u32; n * n];
        let corners = [
            DVec2::ZERO,
            DVec2::new(s, 0.0),
            DVec2::new(s, s),
            DVec2::new(0.0, s),
        ];
        for tri in [
            [corners[0], corners[1], corners[2]],
            [corners[0], corners[3], corners[2]],
        ] {
            triangle(tri, n, n, |x, y, w| {
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                count[y * n + x] += 1;
            });
        }
        assert!(count.iter().all(|&c| c >= 1));
        assert_eq!(
            count.iter().filter(|&&c| c == 2).count(),
            n,
            "only the diagonal pixels twice"
        );
    }

    #[test]
    fn padding_reaches_pad_pixels_past_each_edge_and_no_farther() {
        let tri = [
            DVec2::new(10.0, 10.0),
            DVec2::new(30.0, 10.0),
            DVec2::new(10.0, 30.0),
        ];
        let mut inside = 0;
        triangle(tri, 40, 40, |_, _, _| inside += 1);
        let (mut covered, mut past) = (0, 0);
        triangle_padded(tri, 40, 40, 2.0, |x, y, outside| {
            covered += 1;
            let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            // Below the bottom edge (y = 10) by exactly 10 - p.y.
            if p.y < 10.0 && p.x > 10.0 && p.x + p.y < 40.0 {
                assert!((outside - (10.0 - p.y)).abs() < 1e-9);
            }
            if outside > 0.0 {
                past += 1;
                assert!(outside <= 2.0);
            }
        });
        assert_eq!(covered - past, inside);
        // About two pixels' band along the 20 + 20 + 28 pixels of edge.
        assert!((100..180).contains(&past), "{past}");
    }

    #[test]
    fn centres_within_matches_ceil_and_floor() {
        let reference = |lo: f64, hi: f64, n: usize| {
            let start = (lo - 0.5).ceil().max(0.0) as usize;
            let end = ((hi - 0.5).floor() + 1.0).clamp(0.0, n as f64) as usize;
            start..end
        };
        let ends = [
            -3.7,
            -1.0,
            -0.5,
            -0.25,
            0.0,
            0.25,
            0.5,
            0.75,
            1.0,
            1.5,
            2.4999999,
            2.5,
            2.5000001,
            9.5,
            10.0,
            10.5,
            11.2,
            1e30,
            f64::NAN,
        ];
        for lo in ends {
            for hi in ends {
                let (a, b) = (centres_within(lo, hi, 10), reference(lo, hi, 10));
                assert!(
                    a == b || (a.is_empty() && b.is_empty()),
                    "{lo} {hi}: {a:?} {b:?}"
                );
            }
        }
    }

    #[test]
    fn weights_interpolate_corners() {
        let tri = [
            DVec2::new(1.0, 1.0),
            DVec2::new(30.0, 2.0),
            DVec2::new(5.0, 25.0),
        ];
        triangle(tri, 32, 32, |x, y, w| {
            let p = tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2];
            assert!((p - DVec2::new(x as f64 + 0.5, y as f64 + 0.5)).length() < 1e-9);
        });
    }
}
