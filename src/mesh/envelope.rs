//! The envelope a round of the decimation's collapses stays within: every
//! vertex of the surface the round was given lies within a distance of the
//! round's result, the one-sided Hausdorff distance from it at its vertices
//! that the quadric error (a sum of squares) does not bound. Each face
//! carries some of those vertices; a collapse is allowed only if every
//! point the faces round its edge carry lies within the distance of one of
//! the faces after it, which then carries it (the face that carried it
//! while that stays within, else the first that is; Klein, Liebich and
//! Strasser 1996, "Mesh reduction with error control", there with the
//! nearest face, over the whole surface). A bound per round: `decimate`'s
//! rounds, its last (without one) and its cleanup add to it. Without it the
//! white matter's thin gyri were collapsed away whole: six voxels from the
//! decimated surface at 50k faces, against one from the full-resolution one.

use glam::DVec3;

use super::TriMesh;
use super::closest::closest_point;

pub struct Envelope {
    /// The original vertices.
    points: Vec<DVec3>,
    /// The points each face carries.
    carried: Vec<Vec<u32>>,
    tolerance_squared: f64,
    /// The points round the edge being tried, and the face each would be
    /// carried by after the collapse (kept for `commit`).
    gathered: Vec<(u32, u32)>,
}

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
        Envelope {
            points: mesh.positions.clone(),
            carried,
            tolerance_squared: tolerance * tolerance,
            gathered: Vec::new(),
        }
    }

    /// An envelope round `points` whose face `f` carries the points
    /// `carried[f]` (a surface's pieces' envelopes joined).
    pub fn from_parts(points: Vec<DVec3>, carried: Vec<Vec<u32>>, tolerance: f64) -> Envelope {
        Envelope {
            points,
            carried,
            tolerance_squared: tolerance * tolerance,
            gathered: Vec::new(),
        }
    }

    /// The points face `f` carries.
    pub fn carried(&self, f: usize) -> &[u32] {
        &self.carried[f]
    }

    /// Whether every point `around` (the faces round the edge, those the
    /// collapse removes included) carry lies within the tolerance of one of
    /// `after` (each surviving face and its corners after the collapse):
    /// the face that carried it if it is within, else the first that is.
    pub fn allows(&mut self, around: &[u32], after: &[(u32, [DVec3; 3])]) -> bool {
        self.gathered.clear();
        for &f in around {
            for &p in &self.carried[f as usize] {
                let q = self.points[p as usize];
                let within = |(_, t): &&(u32, [DVec3; 3])| {
                    closest_point(q, t).distance_squared(q) <= self.tolerance_squared
                };
                let own = after.iter().find(|(g, _)| *g == f).filter(within);
                let Some(&(g, _)) = own.or_else(|| after.iter().find(within)) else {
                    return false;
                };
                self.gathered.push((p, g));
            }
        }
        true
    }

    /// The points of the last allowed collapse carried by their new faces.
    pub fn commit(&mut self, around: &[u32]) {
        for &f in around {
            self.carried[f as usize].clear();
        }
        for &(p, g) in &self.gathered {
            self.carried[g as usize].push(p);
        }
    }
}
