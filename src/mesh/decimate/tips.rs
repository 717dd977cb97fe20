//! Tips: vertices of three or four faces that meet at a point, the corner
//! of a small pyramid standing off the surface.
//!
//! The greedy collapses keep them: collapsing a tip into a neighbour turns
//! its faces by more than `MAX_TURN` (they face every way), yet what
//! replaces them faces the way the tip's faces do together, as a
//! pyramid's base faces the way its sides do. On the MNI white matter at
//! 50k faces the 212 vertices of three faces were 207 of the thousand
//! with the largest mean curvature (up to 13.5 per mm, against a median
//! of 0.15), and most of its spread.

use glam::DVec3;

use super::{State, cleanup_floor};
use crate::mesh::TriMesh;
use crate::mesh::closest::closest_point;
use crate::mesh::envelope::Envelope;

/// The most faces a tip has.
const TIP_FACES: usize = 4;
/// A vertex is a tip when its faces' summed area vector is at most this
/// share of their summed areas (1 for a flat fan; a cube's corner, three
/// faces at right angles, has 0.58).
const TIP_FLATNESS: f64 = 0.7;

/// Each tip collapsed into the neighbour that leaves the best smallest
/// angle, where that keeps the surface manifold, no face it moves turns
/// away from the way the tip's faces face together, the tip stands no
/// more than `height` off the faces left, and the worst angle of the faces
/// moved is at least the cleanup's floor or the worst among the faces
/// round the edge before. The number collapsed.
pub(super) fn flatten_tips(
    mesh: &mut TriMesh,
    height: f64,
    mut envelope: Option<&mut Envelope>,
) -> usize {
    let floor = cleanup_floor();
    let mut s = State::new(mesh);
    let (mut around, mut after) = (Vec::new(), Vec::new());
    let mut scratch = [Vec::new(), Vec::new()];
    let mut ring = Vec::new();
    let mut made = 0;
    for v in 0..mesh.num_vertices() as u32 {
        if s.removed[v as usize] {
            continue;
        }
        let faces: Vec<u32> = s.live_faces(v).collect();
        if faces.len() > TIP_FACES {
            continue;
        }
        let area = |f: u32| {
            let [a, b, c] = s.triangles[f as usize].map(|w| s.positions[w as usize]);
            (b - a).cross(c - a)
        };
        let cap: DVec3 = faces.iter().map(|&f| area(f)).sum();
        let total: f64 = faces.iter().map(|&f| area(f).length()).sum();
        if cap.length() > TIP_FLATNESS * total {
            continue;
        }
        s.neighbours(v, &mut ring);
        let best = ring
            .iter()
            .filter_map(|&a| {
                let to = s.positions[a as usize];
                let (old, new) = s.shapes(a, v, to, -1.0, &mut scratch)?;
                let tip = s.positions[v as usize];
                let mut nearest = f64::INFINITY;
                for &f in &faces {
                    let t = s.triangles[f as usize];
                    if t.contains(&a) {
                        continue;
                    }
                    let corners = t.map(|w| s.positions[if w == v { a } else { w } as usize]);
                    let [x, y, z] = corners;
                    if (y - x).cross(z - x).dot(cap) <= 0.0 {
                        return None;
                    }
                    nearest = nearest.min(closest_point(tip, &corners).distance(tip));
                }
                (nearest <= height && new <= old.max(floor)).then_some((new, a, to))
            })
            .min_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((_, a, to)) = best
            && s.held(envelope.as_deref_mut(), (a, v, to), &mut around, &mut after)
        {
            s.collapse(a, v, to);
            made += 1;
        }
    }
    if made > 0 {
        *mesh = s.into_held_mesh(envelope);
    }
    made
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    /// An icosphere with one face split at its centre, raised off the
    /// sphere by `rise` times the face's inradius: a tip of three faces.
    fn sphere_with_a_tip(rise: f64) -> (TriMesh, f64) {
        let mut mesh = shapes::icosphere(3);
        let [a, b, c] = mesh.corners(0);
        let inradius = (b - a).length() / (2.0 * 3f64.sqrt());
        let centre = (a + b + c) / 3.0;
        let normal = (b - a).cross(c - a).normalize();
        mesh.positions.push(centre + normal * rise * inradius);
        let tip = mesh.positions.len() as u32 - 1;
        let [x, y, z] = mesh.triangles[0];
        mesh.triangles[0] = [x, y, tip];
        mesh.triangles.push([y, z, tip]);
        mesh.triangles.push([z, x, tip]);
        (mesh, inradius)
    }

    #[test]
    fn a_tip_is_flattened_onto_its_base_unless_taller_than_the_bound() {
        let (mesh, inradius) = sphere_with_a_tip(2.0);
        let faces = mesh.num_faces();
        // Standing twice its base's inradius off it: kept under a bound
        // of one inradius, flattened under three, back to the sphere's
        // face.
        let mut kept = mesh.clone();
        assert_eq!(flatten_tips(&mut kept, inradius, None), 0);
        assert_eq!(kept.num_faces(), faces);
        let mut flat = mesh.clone();
        assert_eq!(flatten_tips(&mut flat, 3.0 * inradius, None), 1);
        assert_eq!(flat.num_faces(), faces - 2);
        let sphere = shapes::icosphere(3);
        assert_eq!(flat.num_vertices(), sphere.num_vertices());
        // A raised centre too low to be a tip (its faces nearly flat) stays.
        let (mut low, inradius) = sphere_with_a_tip(0.3);
        assert_eq!(flatten_tips(&mut low, 3.0 * inradius, None), 0);
    }
}
