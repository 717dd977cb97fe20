//! The envelope the decimation's collapses, and every step that moves the
//! surface after them, stay within: a set of points (the surface's own
//! vertices before the collapses, or the voxel corners a scan's surface
//! was made from) each within a distance of the surface, the one-sided
//! Hausdorff distance from them that the quadric error (a sum of squares)
//! does not bound. Each face carries some of the points; a change (a
//! collapse, a flip, a vertex's move) is allowed only if every point the
//! faces it changes carry lies within the distance of one of those faces
//! after it, which then carries it (the face that carried it while that
//! stays within, else the first that is; Klein, Liebich and Strasser 1996,
//! "Mesh reduction with error control", there with the nearest face, over
//! the whole surface). Without it the white matter's thin gyri were
//! collapsed away whole: six voxels from the decimated surface at 50k
//! faces, against one from the full-resolution one; and the flips and
//! relaxation after the collapses, with no envelope, took a voxel corner
//! held within 0.9 voxel to 2.5.

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::Bvh;
use super::closest::closest_point;
use super::{FaceId, TriMesh};

#[derive(Debug)]
pub struct Envelope {
    /// The points held.
    points: Vec<DVec3>,
    /// The points each face carries. A point no face carries (it lay
    /// beyond the tolerance, or a lax change left it there) is loose.
    carried: Vec<Vec<u32>>,
    tolerance_squared: f64,
    /// Whether a change that leaves a point beyond the tolerance is
    /// refused (else it is made and the point comes loose).
    strict: bool,
    /// The points round the change being tried, and the face each would
    /// be carried by after it (`LOOSE`: none), kept for `commit`.
    gathered: Vec<(u32, u32)>,
}

/// No face: a point that came loose (`Envelope::gathered`).
const LOOSE: u32 = u32::MAX;

impl Envelope {
    /// Every vertex of `mesh` carried by the first face that has it.
    pub fn new(mesh: &TriMesh, tolerance: f64) -> Envelope {
        let mut carried = vec![Vec::new(); mesh.num_faces()];
        let mut placed = vec![false; mesh.num_vertices()];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                if !std::mem::replace(&mut placed[v as usize], true) {
                    carried[f].push(v);
                }
            }
        }
        Envelope::from_parts(mesh.positions.clone(), carried, tolerance)
    }

    /// `points` held within `tolerance` of the surface `bvh` is over (its
    /// faces in order: `Bvh::over_faces`): each carried by the face nearest
    /// it; those farther than the tolerance are loose.
    pub(crate) fn holding(bvh: &Bvh, points: Vec<DVec3>, tolerance: f64) -> Envelope {
        let faces = bvh.tris.len();
        let mut envelope = Envelope::from_parts(points, vec![Vec::new(); faces], tolerance);
        envelope.carry_loose(bvh);
        envelope
    }

    /// The loose points now within the tolerance of the surface `bvh` is
    /// over (its faces in order), each carried by the face nearest it.
    pub(crate) fn carry_loose(&mut self, bvh: &Bvh) {
        let tolerance = self.tolerance();
        let loose = self.loose();
        let nearest: Vec<Option<u32>> = loose
            .par_iter()
            .map(|&p| bvh.closest_within(self.points[p as usize], tolerance))
            .collect();
        for (p, f) in loose.into_iter().zip(nearest) {
            if let Some(f) = f {
                self.carried[f as usize].push(p);
            }
        }
    }

    /// The points no face carries, in order.
    pub fn loose(&self) -> Vec<u32> {
        let mut loose = vec![true; self.points.len()];
        for &p in self.carried.iter().flatten() {
            loose[p as usize] = false;
        }
        (0..self.points.len() as u32)
            .filter(|&p| loose[p as usize])
            .collect()
    }

    /// An envelope round `points` whose face `f` carries the points
    /// `carried[f]` (a surface's pieces' envelopes joined).
    pub fn from_parts(points: Vec<DVec3>, carried: Vec<Vec<u32>>, tolerance: f64) -> Envelope {
        Envelope {
            points,
            carried,
            tolerance_squared: tolerance * tolerance,
            strict: true,
            gathered: Vec::new(),
        }
    }

    /// This envelope on the faces `faces` of its surface only, face `k` of
    /// the result carrying what `faces[k]` carries (a piece of the surface
    /// collapsed on its own; `from_parts` joins the pieces again).
    pub fn restricted(&self, faces: &[FaceId]) -> Envelope {
        let carried = faces
            .iter()
            .map(|&f| self.carried[f.idx()].clone())
            .collect();
        Envelope::from_parts(self.points.clone(), carried, self.tolerance())
    }

    /// Only the faces `alive` marks, renumbered in order (a collapse
    /// state made a surface again).
    pub fn keep_faces(&mut self, alive: &[bool]) {
        let mut k = 0;
        self.carried.retain(|_| {
            k += 1;
            alive[k - 1]
        });
    }

    /// Whether changes are refused where they leave a point beyond the
    /// tolerance (the default), or made, the point coming loose.
    pub fn set_strict(&mut self, strict: bool) {
        self.strict = strict;
    }

    /// The points held.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The same points, every one loose, to be carried again within
    /// `tolerance` (`carry_loose`).
    pub fn released(mut self, tolerance: f64) -> Envelope {
        self.carried.iter_mut().for_each(Vec::clear);
        self.tolerance_squared = tolerance * tolerance;
        self
    }

    /// The same points and tolerance, face `f` carrying `carried[f]` (the
    /// envelopes of a surface's pieces joined).
    pub fn carrying(mut self, carried: Vec<Vec<u32>>) -> Envelope {
        self.carried = carried;
        self
    }

    /// How far from the surface the points are held.
    pub fn tolerance(&self) -> f64 {
        self.tolerance_squared.sqrt()
    }

    /// The points face `f` carries.
    pub fn carried(&self, f: usize) -> &[u32] {
        &self.carried[f]
    }

    /// Whether every point `around` (the faces a change touches, those it
    /// removes included) carry lies within the tolerance of one of `after`
    /// (each surviving face and its corners after the change): the face
    /// that carried it if it is within, else the first that is.
    pub fn allows(&mut self, around: &[u32], after: &[(u32, [DVec3; 3])]) -> bool {
        self.gathered.clear();
        for &f in around {
            let carried = &self.carried[f as usize];
            if carried.is_empty() {
                continue;
            }
            let own = after.iter().find(|(g, _)| *g == f);
            for &p in carried {
                let q = self.points[p as usize];
                let within = |(_, t): &&(u32, [DVec3; 3])| {
                    closest_point(q, t).distance_squared(q) <= self.tolerance_squared
                };
                let g = match own.filter(within).or_else(|| after.iter().find(within)) {
                    Some(&(g, _)) => g,
                    None if self.strict => return false,
                    None => LOOSE,
                };
                self.gathered.push((p, g));
            }
        }
        true
    }

    /// `allows`, and if so `commit`: the change made in the envelope.
    pub fn admit(&mut self, around: &[u32], after: &[(u32, [DVec3; 3])]) -> bool {
        let ok = self.allows(around, after);
        if ok {
            self.commit(around);
        }
        ok
    }

    /// The points of the last allowed change carried by their new faces.
    pub fn commit(&mut self, around: &[u32]) {
        for &f in around {
            self.carried[f as usize].clear();
        }
        for &(p, g) in &self.gathered {
            if g != LOOSE {
                self.carried[g as usize].push(p);
            }
        }
    }
}

/// Whether `envelope` (if any) allows vertex `v` of `mesh` to move to `to`,
/// its faces `ring` then carrying the points they carried (committed if
/// so); `after` is scratch.
pub fn held(
    mesh: &TriMesh,
    envelope: Option<&mut Envelope>,
    ring: &[u32],
    v: u32,
    to: DVec3,
    after: &mut Vec<(u32, [DVec3; 3])>,
) -> bool {
    let Some(envelope) = envelope else {
        return true;
    };
    after.clear();
    after.extend(ring.iter().map(|&f| {
        let t = mesh.triangles[f as usize];
        (
            f,
            t.map(|w| {
                if w == v {
                    to
                } else {
                    mesh.positions[w as usize]
                }
            }),
        )
    }));
    envelope.admit(ring, after)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;

    #[test]
    fn a_move_that_lets_a_held_point_go_is_refused_unless_lax() {
        // A unit sphere's icosphere; two points: one just outside a face,
        // one far off.
        let mesh = shapes::icosphere(2);
        let [a, b, c] = mesh.corners(0);
        let centre = (a + b + c) / 3.0;
        let outward = (b - a).cross(c - a).normalize();
        let points = vec![centre + outward * 0.05, centre + outward * 2.0];
        let bvh = Bvh::over_faces(&mesh);
        let mut envelope = Envelope::holding(&bvh, points, 0.1);
        // The near point is carried by face 0, the far one loose.
        assert_eq!(envelope.carried(0), &[0]);
        assert_eq!(envelope.loose(), vec![1]);
        // Pushing face 0's corners inwards by 0.1 takes it 0.15 away.
        let v = mesh.triangles[0][0];
        let faces_at = mesh.faces_at_vertices();
        let ring = &faces_at[v as usize];
        let mut moved = mesh.clone();
        for w in mesh.triangles[0] {
            moved.positions[w as usize] -= outward * 0.1;
        }
        let after: Vec<(u32, [DVec3; 3])> = ring
            .iter()
            .map(|&f| (f, moved.corners(f as usize)))
            .collect();
        let around: Vec<u32> = ring.clone();
        assert!(!envelope.allows(&around, &after));
        // Lax, the change is made and the point comes loose.
        envelope.set_strict(false);
        assert!(envelope.allows(&around, &after));
        envelope.commit(&around);
        assert_eq!(envelope.loose(), vec![0, 1]);
        // Back within, it is carried again.
        envelope.carry_loose(&bvh);
        assert_eq!(envelope.loose(), vec![1]);
    }
}
