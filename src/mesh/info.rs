//! `organtex info`: everything worth knowing about a mesh before texturing
//! it, as one serialisable report (the CLI prints it as text or JSON).

use serde::Serialize;

use super::curvature::{Curvature, Stats};
use super::defects::Defects;
use super::repair::{RepairReport, make_manifold};
use super::{ComponentTopology, Components, Topology, TriMesh};
use crate::error::{Error, Result};

#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    pub vertices: usize,
    pub faces: usize,
    pub edges: usize,
    pub facets: Vec<FacetSummary>,
    /// Number of texture coordinates, when the mesh has a uv layer.
    pub texcoords: Option<usize>,
    pub components: usize,
    /// Genus of each component.
    pub genus: Vec<i64>,
    pub boundary_loops: usize,
    pub boundary_edges: usize,
    pub euler: i64,
    pub component_topology: Vec<ComponentTopology>,
    /// Defects of the mesh as read (before any repair).
    pub defects: DefectCounts,
    /// What `--repair` changed, when it ran.
    pub repair: Option<RepairReport>,
    pub bounding_box: BoundingBox,
    pub area: f64,
    /// Enclosed volume, when every component is closed.
    pub volume: Option<f64>,
    /// "outward" or "inward" when closed: which way the face normals point.
    pub normals: Option<&'static str>,
    pub curvature: CurvatureSummary,
}

#[derive(Clone, Debug, Serialize)]
pub struct FacetSummary {
    pub name: String,
    pub faces: usize,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct DefectCounts {
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    pub inconsistent_edges: usize,
    pub degenerate_faces: usize,
    pub duplicate_faces: usize,
    pub repeated_vertex_faces: usize,
    pub unreferenced_vertices: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct BoundingBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub diagonal: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CurvatureSummary {
    /// Sum of all angle defects.
    pub total_angle_defect: f64,
    /// |total angle defect - 2 pi chi|: Gauss-Bonnet says 0.
    pub gauss_bonnet_error: f64,
    /// Angle defect over mixed Voronoi area, per vertex.
    pub gaussian: Option<Stats>,
    /// Mean curvature from the cotangent Laplacian, per vertex.
    pub mean: Option<Stats>,
    /// Signed dihedral angle of interior edges, in degrees.
    pub dihedral_degrees: Option<Stats>,
}

/// A mesh with its topology and curvature, and the report built from them.
pub struct Analysis {
    /// The mesh analysed: the input, or its repair.
    pub mesh: TriMesh,
    pub topology: Topology,
    pub curvature: Curvature,
    pub report: MeshReport,
}

/// Analyse `mesh`. A mesh a half-edge topology cannot hold is refused
/// (naming the first offending element) unless `repair` is set, in which
/// case it is split into a manifold one first and the report says how.
pub fn analyse(mesh: TriMesh, repair: bool) -> Result<Analysis> {
    let defects = Defects::find(&mesh);
    let (mesh, repair_report) = match Topology::build(&mesh) {
        Ok(_) if !repair => (mesh, None),
        Err(e) if !repair => return Err(e),
        _ => {
            let (fixed, report) = make_manifold(&mesh);
            (fixed, Some(report))
        }
    };
    let topology = Topology::build(&mesh)?;
    let components = Components::find(&topology);
    let component_topology = components.topology(&topology);
    let curvature = Curvature::compute(&mesh, &topology);

    let euler: i64 = component_topology.iter().map(|c| c.euler).sum();
    let total_angle_defect: f64 = curvature.angle_defect.iter().sum();
    let closed = topology.boundary_loops().is_empty();
    let signed_volume = mesh.signed_volume();
    let (min, max) = mesh
        .bounding_box()
        .ok_or_else(|| Error::invalid("the mesh has no vertices"))?;
    let interior_dihedrals = (0..topology.num_edges())
        .filter(|&e| !topology.is_boundary_edge(e.into()))
        .map(|e| curvature.dihedral[e].to_degrees());
    let referenced = |v: &usize| topology.is_referenced((*v).into());

    let report = MeshReport {
        vertices: mesh.num_vertices(),
        faces: mesh.num_faces(),
        edges: topology.num_edges(),
        facets: facet_summaries(&mesh),
        texcoords: mesh.uvs.as_ref().map(|uv| uv.coords.len()),
        components: components.count,
        genus: component_topology.iter().map(|c| c.genus).collect(),
        boundary_loops: topology.boundary_loops().len(),
        boundary_edges: topology.boundary_loops().iter().map(Vec::len).sum(),
        euler,
        component_topology,
        defects: DefectCounts {
            non_manifold_edges: defects.non_manifold_edges.len(),
            non_manifold_vertices: defects.non_manifold_vertices.len(),
            inconsistent_edges: defects.inconsistent_edges.len(),
            degenerate_faces: defects.degenerate_faces.len(),
            duplicate_faces: defects.duplicate_faces.len(),
            repeated_vertex_faces: defects.repeated_vertex_faces.len(),
            unreferenced_vertices: defects.unreferenced_vertices.len(),
        },
        repair: repair_report,
        bounding_box: BoundingBox {
            min: min.to_array(),
            max: max.to_array(),
            diagonal: (max - min).length(),
        },
        area: mesh.area(),
        volume: closed.then(|| signed_volume.abs()),
        normals: closed.then_some(if signed_volume >= 0.0 {
            "outward"
        } else {
            "inward"
        }),
        curvature: CurvatureSummary {
            total_angle_defect,
            gauss_bonnet_error: (total_angle_defect - std::f64::consts::TAU * euler as f64).abs(),
            gaussian: Stats::of(
                (0..mesh.num_vertices())
                    .filter(referenced)
                    .map(|v| curvature.gaussian[v]),
            ),
            mean: Stats::of(
                (0..mesh.num_vertices())
                    .filter(referenced)
                    .map(|v| curvature.mean[v]),
            ),
            dihedral_degrees: Stats::of(interior_dihedrals),
        },
    };
    Ok(Analysis {
        mesh,
        topology,
        curvature,
        report,
    })
}

fn facet_summaries(mesh: &TriMesh) -> Vec<FacetSummary> {
    let Some(facets) = &mesh.facets else {
        return Vec::new();
    };
    let mut counts = vec![0; facets.names.len()];
    for &f in &facets.of_face {
        counts[f as usize] += 1;
    }
    facets
        .names
        .iter()
        .zip(counts)
        .map(|(name, faces)| FacetSummary {
            name: name.clone(),
            faces,
        })
        .collect()
}
