//! Typed element ids, so a vertex index is never passed where a face index
//! belongs (geometry-central does the same). All are `u32`: organ meshes stay
//! far below four billion elements and the smaller ids halve the memory of
//! the connectivity arrays.

macro_rules! element_id {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default, serde::Serialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            #[inline]
            pub fn idx(self) -> usize {
                self.0 as usize
            }
        }

        impl From<usize> for $name {
            #[inline]
            fn from(i: usize) -> Self {
                debug_assert!(i <= u32::MAX as usize);
                $name(i as u32)
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($prefix, "{}"), self.0)
            }
        }
    };
}

element_id!(
    /// A vertex: index into `TriMesh::positions`.
    VertexId,
    "v"
);
element_id!(
    /// A triangle: index into `TriMesh::triangles`.
    FaceId,
    "f"
);
element_id!(
    /// A half-edge: corner `h % 3` of face `h / 3`, running from that corner
    /// to the next one.
    HalfedgeId,
    "h"
);
element_id!(
    /// An undirected edge of the half-edge topology.
    EdgeId,
    "e"
);
