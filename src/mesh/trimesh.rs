//! The indexed triangle mesh every stage shares.
//!
//! Invariants (established by the readers and by every function that builds
//! one): every index in `triangles` is `< positions.len()`, every position is
//! finite, `facets.of_face.len() == triangles.len()` and every facet id is
//! `< facets.names.len()`; a uv layer has one uv triangle per triangle.
//! Positions are `f64`: angle defects, ABF++ and the layout solve need the
//! precision, and organ meshes are small enough that the memory is no issue.

use glam::{DVec2, DVec3};

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    /// Counter-clockwise seen from outside (the side the normal points to).
    pub triangles: Vec<[u32; 3]>,
    /// Which facet (OBJ group/material, STL solid) each face belongs to.
    pub facets: Option<Facets>,
    /// Texture coordinates, indexed per corner like OBJ's `vt`, so a seam can
    /// give one vertex several uvs.
    pub uvs: Option<UvLayer>,
}

/// Per-face facet ids and the facets' names.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Facets {
    pub names: Vec<String>,
    pub of_face: Vec<u32>,
}

/// Texture coordinates with their own indexing: `triangles[f][i]` is the uv of
/// corner `i` of face `f`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UvLayer {
    pub coords: Vec<DVec2>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Its positions and triangles (their bits) into `digest`, for change
    /// detection of what is made from them.
    pub fn feed_geometry(&self, digest: &mut crate::digest::Digest) {
        for p in &self.positions {
            for c in p.to_array() {
                digest.feed(&c.to_le_bytes());
            }
        }
        for t in &self.triangles {
            for v in t {
                digest.feed(&v.to_le_bytes());
            }
        }
    }

    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Self {
        TriMesh {
            positions,
            triangles,
            facets: None,
            uvs: None,
        }
    }

    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    pub fn num_faces(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[f];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Twice the area times the unit normal: `(b - a) x (c - a)`.
    #[inline]
    pub fn face_area_vector(&self, f: usize) -> DVec3 {
        let [a, b, c] = self.corners(f);
        (b - a).cross(c - a)
    }

    #[inline]
    pub fn face_area(&self, f: usize) -> f64 {
        0.5 * self.face_area_vector(f).length()
    }

    /// Each vertex's faces, in face order.
    pub fn faces_at_vertices(&self) -> Vec<Vec<u32>> {
        let mut faces_at = vec![Vec::new(); self.num_vertices()];
        for (f, t) in self.triangles.iter().enumerate() {
            for &v in t {
                faces_at[v as usize].push(f as u32);
            }
        }
        faces_at
    }

    /// Each vertex's unit normal, its faces' normals weighted by their
    /// areas (zero where they cancel).
    pub fn vertex_normals(&self) -> Vec<DVec3> {
        let mut n = vec![DVec3::ZERO; self.num_vertices()];
        for (f, t) in self.triangles.iter().enumerate() {
            let a = self.face_area_vector(f);
            for &v in t {
                n[v as usize] += a;
            }
        }
        n.into_iter().map(DVec3::normalize_or_zero).collect()
    }

    /// Unit normal of face `f`, zero for a degenerate face.
    #[inline]
    pub fn face_normal(&self, f: usize) -> DVec3 {
        self.face_area_vector(f).normalize_or_zero()
    }

    pub fn area(&self) -> f64 {
        (0..self.num_faces()).map(|f| self.face_area(f)).sum()
    }

    /// Axis-aligned bounds of the referenced and unreferenced vertices alike;
    /// `None` for a mesh with no vertices.
    pub fn bounding_box(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Signed enclosed volume by the divergence theorem: sum over faces of
    /// `a . (b x c) / 6`. Only meaningful for a closed, consistently oriented
    /// mesh; positive when the normals point outwards.
    pub fn signed_volume(&self) -> f64 {
        (0..self.num_faces())
            .map(|f| {
                let [a, b, c] = self.corners(f);
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }

    /// Name of the facet of face `f`, if the mesh has facets.
    pub fn facet_name(&self, f: usize) -> Option<&str> {
        let facets = self.facets.as_ref()?;
        Some(facets.names[facets.of_face[f] as usize].as_str())
    }
}
