//! A triangle's shape as the decimation's guards judge it, and the
//! corner moves that mend the faces it leaves thin.

use glam::DVec3;

use super::TriMesh;
use super::envelope::{Envelope, held};

/// The cosine of the smallest angle of triangle (a, b, c), the largest of
/// its angles' cosines; 1 for a triangle with a corner on another. The
/// guards compare these rather than angles: the same order (the cosine
/// falls as the angle grows), without an arc cosine per corner, which was
/// a tenth of decimating a scan's surface.
pub fn sharpness(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let cosine = |p: DVec3, q: DVec3, r: DVec3| {
        let (u, v) = (q - p, r - p);
        let lengths = (u.length_squared() * v.length_squared()).sqrt();
        if lengths > 0.0 {
            u.dot(v) / lengths
        } else {
            1.0
        }
    };
    cosine(a, b, c).max(cosine(b, c, a)).max(cosine(c, a, b))
}

/// Whether a face whose normal (unnormalised) goes from `before` to
/// `after` keeps facing the way it did: not degenerate after, and turned
/// by no more than the angle whose cosine is `turn`. A face of no area
/// before is held to `around()` (its neighbourhood's normal) instead.
/// False where a direction is undefined (NaN compares false).
pub fn keeps_facing(
    before: DVec3,
    after: DVec3,
    around: impl FnOnce() -> DVec3,
    turn: f64,
) -> bool {
    let reference = if before.length_squared() > 0.0 {
        before
    } else {
        around()
    };
    after.length_squared() > 0.0 && reference.normalize().dot(after.normalize()) >= turn
}

/// The worst sharpness of the faces `ring` round vertex `v` with `v`
/// moved to `to`, or infinity where one of them would not keep facing the
/// way it does (`keeps_facing`, turned past `turn`, a cosine; a face of no
/// area now held to `normal`, the ring's).
pub fn worst_after_move(
    mesh: &TriMesh,
    ring: &[u32],
    v: u32,
    to: DVec3,
    normal: DVec3,
    turn: f64,
) -> f64 {
    let mut worst = f64::NEG_INFINITY;
    for &g in ring {
        let t = mesh.triangles[g as usize];
        let [x, y, z] = t.map(|w| mesh.positions[w as usize]);
        let [x1, y1, z1] = t.map(|w| {
            if w == v {
                to
            } else {
                mesh.positions[w as usize]
            }
        });
        if !keeps_facing(
            (y - x).cross(z - x),
            (y1 - x1).cross(z1 - x1),
            || normal,
            turn,
        ) {
            return f64::INFINITY;
        }
        worst = worst.max(sharpness(x1, y1, z1));
    }
    worst
}

/// Moves of the corners of each face whose sharpness is above `floor`
/// (the decimation's cleanup floor), each to the best of a few points
/// round it in its tangent plane (twelve directions, three steps up to a
/// fifth of its shortest edge) where that raises the worst angle of its
/// faces and turns none past `turn` (a cosine): the optimisation-based
/// smoothing of a vertex (Freitag and Ollivier-Gooch 1997) by sampling,
/// for the caps no flip or collapse mends. A move of a fifth of an edge in
/// the tangent plane leaves the surface by about that squared times its
/// curvature. A move `envelope` does not allow is not made. The number
/// made.
pub fn move_corners(
    mesh: &mut TriMesh,
    floor: f64,
    turn: f64,
    mut envelope: Option<&mut Envelope>,
) -> usize {
    let faces_at = mesh.faces_at_vertices();
    let mut after = Vec::new();
    let mut made = 0;
    for f in 0..mesh.num_faces() {
        for v in mesh.triangles[f] {
            let [a, b, c] = mesh.corners(f);
            if sharpness(a, b, c) <= floor {
                break;
            }
            let ring = &faces_at[v as usize];
            let p = mesh.positions[v as usize];
            let mut normal = DVec3::ZERO;
            let mut worst = f64::NEG_INFINITY;
            let mut shortest = f64::INFINITY;
            for &g in ring {
                let [x, y, z] = mesh.corners(g as usize);
                normal += (y - x).cross(z - x);
                worst = worst.max(sharpness(x, y, z));
                for q in [x, y, z] {
                    if q != p {
                        shortest = shortest.min(q.distance(p));
                    }
                }
            }
            if normal.length_squared() == 0.0 || !shortest.is_finite() {
                continue;
            }
            let (u, w) = normal.normalize().any_orthonormal_pair();
            let mut best = (worst, p);
            for step in [0.05, 0.1, 0.2] {
                for k in 0..12 {
                    let angle = k as f64 * std::f64::consts::PI / 6.0;
                    let to = p + step * shortest * (angle.cos() * u + angle.sin() * w);
                    let new_worst = worst_after_move(mesh, ring, v, to, normal, turn);
                    if new_worst < best.0 {
                        best = (new_worst, to);
                    }
                }
            }
            if best.0 < worst && held(mesh, envelope.as_deref_mut(), ring, v, best.1, &mut after) {
                mesh.positions[v as usize] = best.1;
                made += 1;
            }
        }
    }
    made
}
