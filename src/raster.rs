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
    let x0 = (lo.x - 0.5).ceil().max(0.0) as usize;
    let y0 = (lo.y - 0.5).ceil().max(0.0) as usize;
    let x1 = ((hi.x - 0.5).floor() + 1.0).clamp(0.0, width as f64) as usize;
    let y1 = ((hi.y - 0.5).floor() + 1.0).clamp(0.0, height as f64) as usize;
    let inv = 1.0 / area;
    for y in y0..y1 {
        for x in x0..x1 {
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
