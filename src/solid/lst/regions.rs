//! Regions of an organ lapped with a texture of their own (`fill_regions`),
//! found from the surface: a myoma is the ball that fits its facet, and
//! its fibres whorl round the facet's axis (a leiomyoma's smooth muscle
//! runs in concentric bundles), so with no strokes given a type 1-a region
//! gets rings round that axis.

use glam::{DMat4, DVec3, DVec4};

use super::locate::Locator;
use super::{LstOptions, Region, TextureType};
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::rng;
use crate::tetra::TetMesh;

/// The ball fitted to a facet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ball {
    pub centre: DVec3,
    pub radius: f64,
    /// The facet's area-weighted mean normal (out of the solid).
    pub axis: DVec3,
}

/// A region asked for by its facet.
#[derive(Clone, Debug, PartialEq)]
pub struct FacetRegion {
    pub facet: String,
    /// 0 or 1-a.
    pub kind: TextureType,
    /// Object units one patch spans.
    pub scale: f64,
    /// For 1-a; none: rings round the facet's axis.
    pub strokes: Vec<Vec<DVec3>>,
}

/// The least-squares ball through facet `name`'s vertices (the algebraic
/// fit: |p|^2 = 2 c.p + k, linear in the centre c and k). Errors name a
/// missing facet or one too flat for a ball.
pub fn facet_ball(surface: &TriMesh, name: &str) -> Result<Ball> {
    let facets = surface
        .facets
        .as_ref()
        .ok_or_else(|| Error::invalid("the mesh has no facets to find regions by"))?;
    let id = facets.names.iter().position(|n| n == name).ok_or_else(|| {
        Error::invalid(format!(
            "no facet '{name}' for a region (the mesh has: {})",
            facets.names.join(", ")
        ))
    })? as u32;
    let mut on = vec![false; surface.positions.len()];
    let mut axis = DVec3::ZERO;
    for (t, _) in surface
        .triangles
        .iter()
        .zip(&facets.of_face)
        .filter(|&(_, &f)| f == id)
    {
        let [a, b, c] = t.map(|v| surface.positions[v as usize]);
        axis += (b - a).cross(c - a);
        for &v in t {
            on[v as usize] = true;
        }
    }
    let points: Vec<DVec3> = (0..on.len())
        .filter(|&v| on[v])
        .map(|v| surface.positions[v])
        .collect();
    let flat = || {
        Error::invalid(format!(
            "facet '{name}' is too flat for a region: no ball fits its {} vertices",
            points.len()
        ))
    };
    if points.len() < 4 {
        return Err(flat());
    }
    // Centred on the mean, for conditioning.
    let mean = points.iter().sum::<DVec3>() / points.len() as f64;
    let (mut ata, mut atb) = (DMat4::ZERO, DVec4::ZERO);
    for &p in &points {
        let q = p - mean;
        let row = DVec4::new(2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0);
        ata += DMat4::from_cols(row * row.x, row * row.y, row * row.z, row * row.w);
        atb += row * q.length_squared();
    }
    if ata.determinant().abs() < 1e-12 * ata.col(3).w.powi(4).max(1e-300) {
        return Err(flat());
    }
    let x = ata.inverse() * atb;
    let centre = DVec3::new(x.x, x.y, x.z);
    let radius = (x.w + centre.length_squared()).sqrt();
    let extent = points.iter().map(|p| p.distance(mean)).fold(0.0, f64::max);
    // A nearly flat facet fits a huge ball far away: not a mass.
    if !radius.is_finite() || radius > 4.0 * extent.max(1e-300) {
        return Err(flat());
    }
    Ok(Ball {
        centre: centre + mean,
        radius,
        axis: axis.normalize_or(DVec3::Z),
    })
}

/// The tets whose centroid lies in the ball.
pub fn tets_in_ball(mesh: &TetMesh, ball: &Ball) -> Vec<u32> {
    (0..mesh.num_tets())
        .filter(|&t| {
            let c = mesh.corners(t);
            ((c[0] + c[1] + c[2] + c[3]) / 4.0).distance(ball.centre) < ball.radius
        })
        .map(|t| t as u32)
        .collect()
}

/// Rings round the ball's axis at a few heights and radii, cut to the
/// runs inside `region` (the region's own tets). A ring's segments are
/// shorter than the region's tet edges, so the fill's stroke constraints
/// (one at each segment's middle) fall where this checked.
pub fn whorl(ball: &Ball, region: &TetMesh) -> Vec<Vec<DVec3>> {
    let locator = Locator::new(region);
    let spacing = super::mean_edge(region);
    let u = ball.axis.any_orthonormal_vector();
    let v = ball.axis.cross(u);
    let inside = |p: DVec3| locator.locate(region, p).is_some();
    let mut strokes = Vec::new();
    for h in [-0.5, 0.0, 0.5] {
        for rho in [0.3, 0.55, 0.8] {
            if h * h + rho * rho >= 0.9 {
                continue;
            }
            let around = std::f64::consts::TAU * rho * ball.radius;
            let n = ((2.0 * around / spacing).ceil() as usize).clamp(12, 4096);
            let ring: Vec<DVec3> = (0..n)
                .map(|k| {
                    let a = k as f64 / n as f64 * std::f64::consts::TAU;
                    ball.centre + ball.radius * (h * ball.axis + rho * (a.cos() * u + a.sin() * v))
                })
                .collect();
            // Segment k runs from point k to k + 1; kept when both ends and
            // its middle are inside.
            let kept: Vec<bool> = (0..n)
                .map(|k| {
                    let (a, b) = (ring[k], ring[(k + 1) % n]);
                    inside(a) && inside(b) && inside(a + (b - a) * 0.5)
                })
                .collect();
            if kept.iter().all(|&k| k) {
                let mut closed = ring.clone();
                closed.push(ring[0]);
                strokes.push(closed);
                continue;
            }
            // Runs of kept segments, starting after a dropped one so a run
            // is not split at index 0.
            let first = kept.iter().position(|&k| !k).unwrap_or(0);
            let mut run: Vec<DVec3> = Vec::new();
            for j in 1..=n {
                let k = (first + j) % n;
                if kept[k] {
                    if run.is_empty() {
                        run.push(ring[k]);
                    }
                    run.push(ring[(k + 1) % n]);
                } else if !run.is_empty() {
                    if run.len() >= 4 {
                        strokes.push(std::mem::take(&mut run));
                    }
                    run.clear();
                }
            }
            if run.len() >= 4 {
                strokes.push(run);
            }
        }
    }
    strokes
}

/// The regions asked for, each the tets in its facet's ball not already
/// taken by an earlier one; seeds drawn from `seed`. Errors name the
/// facet of a region that holds no tets or, for 1-a, no stroke inside.
pub fn facet_regions(
    surface: &TriMesh,
    mesh: &TetMesh,
    wanted: &[FacetRegion],
    seed: u64,
) -> Result<Vec<Region>> {
    let mut taken = vec![false; mesh.num_tets()];
    let mut out = Vec::new();
    for (k, w) in wanted.iter().enumerate() {
        let err = |e: Error| Error::invalid(format!("region '{}': {e}", w.facet));
        if w.kind.needs_depth() {
            return Err(err(Error::invalid(format!(
                "type {} needs the depth field; a region takes type 0 or 1a",
                w.kind.name()
            ))));
        }
        let ball = facet_ball(surface, &w.facet).map_err(err)?;
        let tets: Vec<u32> = tets_in_ball(mesh, &ball)
            .into_iter()
            .filter(|&t| !taken[t as usize])
            .collect();
        if tets.is_empty() {
            return Err(err(Error::invalid(format!(
                "no tet lies in the ball fitted to the facet (centre {}, radius {:.3})",
                ball.centre, ball.radius
            ))));
        }
        for &t in &tets {
            taken[t as usize] = true;
        }
        let strokes = if w.kind.needs_strokes() && w.strokes.is_empty() {
            let rings = whorl(&ball, &mesh.subset(&tets).0);
            if rings.is_empty() {
                return Err(err(Error::invalid(
                    "no ring round the facet's axis lies inside it: give strokes",
                )));
            }
            rings
        } else {
            w.strokes.clone()
        };
        out.push(Region {
            name: w.facet.clone(),
            tets,
            options: LstOptions {
                kind: w.kind,
                scale: w.scale,
                strokes,
                depth_outer: Vec::new(),
                depth_inner: Vec::new(),
                seed: rng::hash(seed, &[k as u64 + 1]),
            },
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cap_of_a_sphere_fits_its_ball() {
        // A spherical cap (the top 40% of a sphere of radius 3 at (1, 2,
        // 3)) as facet 0, the rest facet 1.
        let sphere = crate::mesh::shapes::icosphere(4);
        let mut mesh = sphere.clone();
        for p in &mut mesh.positions {
            *p = *p * 3.0 + DVec3::new(1.0, 2.0, 3.0);
        }
        let of_face = mesh
            .triangles
            .iter()
            .map(|t| {
                let z = t
                    .iter()
                    .map(|&v| sphere.positions[v as usize].z)
                    .sum::<f64>()
                    / 3.0;
                u32::from(z < 0.4)
            })
            .collect();
        mesh.facets = Some(crate::mesh::Facets {
            names: vec!["cap".into(), "rest".into()],
            of_face,
        });
        let ball = facet_ball(&mesh, "cap").unwrap();
        assert!(
            ball.centre.distance(DVec3::new(1.0, 2.0, 3.0)) < 0.05,
            "{ball:?}"
        );
        assert!((ball.radius - 3.0).abs() < 0.05, "{ball:?}");
        assert!(ball.axis.dot(DVec3::Z) > 0.99, "{ball:?}");
        assert!(facet_ball(&mesh, "nope").is_err());
    }
}
