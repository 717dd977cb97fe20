//! Where a ray meets a triangle (Moller and Trumbore 1997): the generator's
//! cavity span and the viewer's picking share it.

use glam::DVec3;

/// The distance along the ray from `origin` along `dir` (in units of
/// `dir`) to where it meets triangle `[a, b, c]`, behind the origin too
/// (negative); none when it misses or runs parallel to the triangle.
pub fn ray_triangle(origin: DVec3, dir: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| e2.dot(q) / det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_triangle_ahead_or_behind_and_misses_beside_it() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let at = |o: DVec3, d: DVec3| ray_triangle(o, d, t);
        assert_eq!(at(DVec3::new(0.2, 0.2, 2.0), -DVec3::Z), Some(2.0));
        assert_eq!(at(DVec3::new(0.2, 0.2, 2.0), DVec3::Z), Some(-2.0));
        assert_eq!(at(DVec3::new(0.9, 0.9, 2.0), -DVec3::Z), None);
        assert_eq!(at(DVec3::new(0.2, 0.2, 2.0), DVec3::X), None);
    }
}
