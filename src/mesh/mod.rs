//! The mesh layer every stage shares: the indexed triangle mesh, its
//! half-edge topology, defect detection and repair, components and genus,
//! curvature, reading and writing, and the test shapes.

pub(crate) mod bvh;
pub mod closest;
pub mod components;
pub mod corners;
pub mod curvature;
pub mod decimate;
pub mod defects;
pub(crate) mod dsu;
pub mod edges;
pub mod envelope;
pub mod fans;
pub mod graph;
pub mod halfedge;
pub mod ids;
pub mod info;
pub mod io;
pub mod ray;
pub mod refine;
pub mod repair;
pub mod shapes;
pub mod submesh;
mod trimesh;

pub use components::{ComponentTopology, Components};
pub use halfedge::Topology;
pub use ids::{EdgeId, FaceId, HalfedgeId, VertexId};
pub use trimesh::{Facets, TriMesh, UvLayer};
