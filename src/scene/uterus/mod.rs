//! The uterine cavity seen from inside, as a hysteroscope sees it (seed 004,
//! section 4; Sierra et al.'s parametric organ models): a pear-shaped
//! surface, wide at the fundus and narrowing to the cervical canal, which is
//! left open; normals face the inside. Myomas grow as submucosal bulges and
//! polyps as stalked protrusions, each its own facet. Seeded, so a scene is
//! the same mesh every time.
//!
//! Built from an icosphere (even triangles everywhere, refined twice around
//! polyps), mapped onto the pear; myomas displace the wall along its normal
//! with a smooth, compact bump whose outline the seed makes irregular;
//! polyps remap a disc of the wall onto a surface of revolution (a rounded
//! head on a stalk, flaring into the wall), which never folds because its
//! profile curve is simple. Parameters that would make the surface cross
//! itself are refused.

use std::f64::consts::TAU;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::mesh::ray::ray_triangle;
use crate::mesh::refine::refine;
use crate::mesh::shapes::icosphere;
use crate::mesh::submesh::smooth_region;
use crate::mesh::{Facets, Topology, TriMesh};
use crate::rng;

mod polyp;
use polyp::{grow_polyp, polyp_footprint, polyp_rise};

fn default_length() -> f64 {
    40.0
}
fn default_width() -> f64 {
    32.0
}
fn default_depth() -> f64 {
    16.0
}
fn default_cervix() -> f64 {
    2.5
}
fn default_resolution() -> usize {
    5
}

/// Parameters of the cavity (lengths in millimetres, or any unit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CavityParams {
    #[serde(default)]
    pub seed: u64,
    /// Cervix to fundus.
    #[serde(default = "default_length")]
    pub length: f64,
    /// Widest, left to right.
    #[serde(default = "default_width")]
    pub width: f64,
    /// Widest, front to back (the cavity is flattened).
    #[serde(default = "default_depth")]
    pub depth: f64,
    /// Radius of the open cervical canal.
    #[serde(default = "default_cervix")]
    pub cervix_radius: f64,
    /// Icosphere subdivisions (4: 5k faces, 5: 20k, 6: 80k).
    #[serde(default = "default_resolution")]
    pub resolution: usize,
    /// The uterine wall's thickness: with it, the mesh is the wall as a
    /// closed solid, the cavity inside and the serosa (facet "serosa")
    /// outside, joined round the cervical canal, so that a cut through it
    /// shows the wall (`solid::section`); 0 (the default): the cavity
    /// surface alone, open at the canal.
    #[serde(default)]
    pub wall_thickness: f64,
    /// The wall's soft folds: seeded undulations along its normal, at
    /// most this far (0, the default: a smooth pear).
    #[serde(default)]
    pub folds: f64,
    #[serde(default, rename = "myoma")]
    pub myomas: Vec<Myoma>,
    #[serde(default, rename = "polyp")]
    pub polyps: Vec<Polyp>,
}

/// Where on the wall: `around` the long axis (0..1 of a turn, 0 = left,
/// 0.25 = front) and `up` from the cervix (0) to the fundus (1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Myoma {
    pub name: Option<String>,
    pub at: [f64; 2],
    /// Radius of its base on the wall.
    pub radius: f64,
    /// How far it bulges into the cavity.
    pub height: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Polyp {
    pub name: Option<String>,
    pub at: [f64; 2],
    pub stalk_radius: f64,
    pub stalk_length: f64,
    pub head_radius: f64,
    /// The head's height over its width: 1 a ball, more an ovoid.
    #[serde(default = "one")]
    pub elongation: f64,
    /// Seeded lobes round the head, a fraction of its radius; 0 round.
    #[serde(default)]
    pub irregularity: f64,
    /// How far the head leans over, degrees: the axis bends from upright
    /// at the base to this angle at the top, towards a seeded side.
    #[serde(default)]
    pub lean: f64,
    /// A broad-based polyp: the head sits on the wall cut above its widest
    /// part, where it is `stalk_radius` wide, on a rounded skirt
    /// `stalk_length` high; no neck. Most endometrial polyps are sessile.
    #[serde(default)]
    pub sessile: bool,
}

fn one() -> f64 {
    1.0
}

/// A cavity with two myomas and a fundal polyp on a stalk (what `organtex
/// generate uterus` writes; the default scene has the same cavity and
/// myomas, and a sessile polyp).
pub fn demo() -> CavityParams {
    CavityParams {
        seed: 7,
        length: default_length(),
        width: default_width(),
        depth: default_depth(),
        cervix_radius: default_cervix(),
        resolution: default_resolution(),
        wall_thickness: 0.0,
        folds: 0.8,
        myomas: vec![
            Myoma {
                name: None,
                at: [0.22, 0.62],
                radius: 7.0,
                height: 4.5,
            },
            Myoma {
                name: None,
                at: [0.6, 0.45],
                radius: 5.0,
                height: 3.0,
            },
        ],
        polyps: vec![Polyp {
            name: None,
            at: [0.9, 0.85],
            stalk_radius: 1.2,
            stalk_length: 2.0,
            head_radius: 2.4,
            elongation: 1.3,
            irregularity: 0.2,
            lean: 25.0,
            sessile: false,
        }],
    }
}

/// A problem with the parameters: the key path and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError {
    pub key: String,
    pub msg: String,
}

fn bad(key: impl Into<String>, msg: impl Into<String>) -> ParamError {
    ParamError {
        key: key.into(),
        msg: msg.into(),
    }
}

/// The pear: where unit-sphere point `q` goes (z from -1 at the cervix to 1
/// at the fundus).
fn pear(p: &CavityParams, q: DVec3) -> DVec3 {
    let t = (q.z + 1.0) / 2.0;
    let s = smoothstep(0.0, 0.8, t);
    let f = 0.35 + 0.65 * s;
    DVec3::new(
        q.x * p.width / 2.0 * f,
        q.y * p.depth / 2.0 * f,
        t * p.length,
    )
}

/// The wall's soft folds: a sum of seeded plane waves over the cavity, of
/// wavelengths from a fifth to a half of its width, in -1..1. Smooth and
/// band-limited, so the displaced wall stays as even as the pear.
struct Folds {
    waves: Vec<(DVec3, f64, f64)>,
}

impl Folds {
    const WAVES: u64 = 8;

    fn new(p: &CavityParams) -> Folds {
        let u = |k: u64, i: u64| rng::unit(p.seed, &[0xf01d, k, i]);
        let waves: Vec<(DVec3, f64, f64)> = (0..Self::WAVES)
            .map(|k| {
                // A uniform direction, a wavelength, a phase, an amplitude.
                let z = 2.0 * u(k, 0) - 1.0;
                let phi = TAU * u(k, 1);
                let r = (1.0 - z * z).sqrt();
                let dir = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                let wavelength = p.width * (0.2 + 0.3 * u(k, 2));
                (dir * (TAU / wavelength), TAU * u(k, 3), 0.5 + u(k, 4))
            })
            .collect();
        let total: f64 = waves.iter().map(|w| w.2).sum();
        Folds {
            waves: waves
                .into_iter()
                .map(|(k, ph, a)| (k, ph, a / total))
                .collect(),
        }
    }

    fn at(&self, x: DVec3) -> f64 {
        self.waves
            .iter()
            .map(|(k, ph, a)| a * (k.dot(x) + ph).sin())
            .sum()
    }
}

fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The unit-sphere point of wall position `at`.
fn sphere_point(at: [f64; 2]) -> DVec3 {
    let z = 2.0 * at[1] - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * at[0];
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A feature (myoma or polyp) placed on the wall.
struct Site {
    centre: DVec3,
    /// Into the cavity.
    normal: DVec3,
    /// Footprint radius on the wall.
    footprint: f64,
    key: String,
    name: String,
}

/// Generate the cavity.
pub fn generate(p: &CavityParams) -> Result<TriMesh, ParamError> {
    check(p)?;
    let mut sphere = icosphere(p.resolution);
    let mut sites = Vec::new();
    for (i, m) in p.myomas.iter().enumerate() {
        let name = m.name.clone().unwrap_or_else(|| format!("myoma-{}", i + 1));
        sites.push((format!("myoma[{i}]"), name, m.at, m.radius));
    }
    for (i, pl) in p.polyps.iter().enumerate() {
        let name = pl
            .name
            .clone()
            .unwrap_or_else(|| format!("polyp-{}", i + 1));
        sites.push((format!("polyp[{i}]"), name, pl.at, polyp_footprint(pl)));
    }
    let sites: Vec<Site> = sites
        .into_iter()
        .map(|(key, name, at, footprint)| {
            let q = sphere_point(at);
            Site {
                centre: pear(p, q),
                normal: -outward_normal(p, q),
                footprint,
                key,
                name,
            }
        })
        .collect();
    // Features must not overlap.
    for i in 0..sites.len() {
        for j in 0..i {
            let gap = (sites[i].centre - sites[j].centre).length();
            if gap < sites[i].footprint + sites[j].footprint {
                return Err(bad(
                    sites[i].key.clone(),
                    format!(
                        "{} overlaps {} ({} apart, their footprints need {:.3})",
                        sites[i].name,
                        sites[j].name,
                        fmt(gap),
                        sites[i].footprint + sites[j].footprint
                    ),
                ));
            }
        }
    }
    let mut names: Vec<String> = vec!["wall".into()];
    names.extend(sites.iter().map(|s| s.name.clone()));
    if let Some(dup) = (1..names.len()).find(|&i| names[..i].contains(&names[i])) {
        return Err(bad(
            sites[dup - 1].key.clone() + ".name",
            format!("the facet name '{}' is used twice", names[dup]),
        ));
    }

    // Refine the wall around polyps once: each polyp grows from its hole's
    // rim, so a finer rim makes a rounder polyp.
    let polyp_sites = &sites[p.myomas.len()..];
    for _ in 0..1 {
        let marked: Vec<bool> = (0..sphere.num_faces())
            .map(|f| {
                let c = pear(p, sphere.corners(f).iter().sum::<DVec3>() / 3.0);
                polyp_sites
                    .iter()
                    .any(|s| (c - s.centre).length() < 1.3 * s.footprint)
            })
            .collect();
        if !marked.iter().any(|&m| m) {
            break;
        }
        sphere = refine(&sphere, &marked, |a, b| ((a + b) / 2.0).normalize()).0;
    }

    // Onto the pear; remember each vertex's height fraction for the canal.
    let heights: Vec<f64> = sphere.positions.iter().map(|q| (q.z + 1.0) / 2.0).collect();
    let mut positions: Vec<DVec3> = sphere.positions.iter().map(|&q| pear(p, q)).collect();
    if p.folds > 0.0 {
        let fold = Folds::new(p);
        for (x, &q) in positions.iter_mut().zip(&sphere.positions) {
            *x += outward_normal(p, q) * (p.folds * fold.at(*x));
        }
    }
    let original = positions.clone();
    let mut facet_of_vertex = vec![0u32; positions.len()];

    // Myomas deform their footprint; a face is a myoma's when all its
    // corners are.
    for (k, site) in sites.iter().enumerate().take(p.myomas.len()) {
        let span = cavity_span(&original, &sphere.triangles, site);
        let m = &p.myomas[k];
        if m.height > 0.6 * span {
            return Err(bad(
                format!("{}.height", site.key),
                format!(
                    "{} is larger than the cavity: height {} exceeds 60% of the {:.3} across it there",
                    site.name,
                    fmt(m.height),
                    span
                ),
            ));
        }
        bulge(
            &mut positions,
            &original,
            &mut facet_of_vertex,
            (k + 1) as u32,
            site,
            m,
            p.seed ^ k as u64,
        );
    }
    let mut triangles = sphere.triangles.clone();
    let mut of_face: Vec<u32> = triangles
        .iter()
        .map(|t| {
            let f = facet_of_vertex[t[0] as usize];
            if t.iter().all(|&v| facet_of_vertex[v as usize] == f) {
                f
            } else {
                0
            }
        })
        .collect();
    // Smooth each myoma's border, so no face sticks out of it or into it.
    // The icosphere is built closed and manifold whatever the parameters
    // (`resolution` is checked to 3..=7), so this cannot fail.
    let sphere_topo = Topology::build(&sphere).expect("an icosphere is manifold");
    for k in 1..=p.myomas.len() as u32 {
        let mut region: Vec<bool> = of_face.iter().map(|&f| f == k).collect();
        smooth_region(
            &sphere_topo,
            &mut region,
            |f| of_face[f] != 0 && of_face[f] != k,
            16,
        );
        for (f, inside) in region.into_iter().enumerate() {
            if inside {
                of_face[f] = k;
            } else if of_face[f] == k {
                of_face[f] = 0;
            }
        }
    }
    let mut heights = heights;

    // Polyps grow out of holes cut in the wall.
    for (k, site) in sites.iter().enumerate().skip(p.myomas.len()) {
        let pl = &p.polyps[k - p.myomas.len()];
        let span = cavity_span(&original, &sphere.triangles, site);
        let rise = polyp_rise(pl);
        if rise > 0.6 * span {
            return Err(bad(
                site.key.clone(),
                format!(
                    "{} is larger than the cavity: it rises {} into the {:.3} across it there",
                    site.name,
                    fmt(rise),
                    span
                ),
            ));
        }
        grow_polyp(
            &mut positions,
            &mut triangles,
            &mut of_face,
            (k + 1) as u32,
            site,
            pl,
            rng::hash(p.seed, &[0x9017, k as u64]),
        )
        .map_err(|msg| bad(site.key.clone(), msg))?;
        heights.resize(positions.len(), 1.0);
    }

    // Open the cervical canal: drop the faces below the height where the
    // cavity is as narrow as the canal.
    let t_open = opening_height(p);
    let mut kept = Vec::new();
    let mut kept_facets = Vec::new();
    for (t, f) in triangles.iter().zip(&of_face) {
        if t.iter().any(|&v| heights[v as usize] >= t_open) {
            // Reversed: the normals face the inside.
            kept.push([t[0], t[2], t[1]]);
            kept_facets.push(*f);
        }
    }
    if p.wall_thickness > 0.0 {
        let serosa = names.len() as u32;
        names.push("serosa".into());
        close_wall(
            p,
            &sphere,
            &heights,
            t_open,
            &mut positions,
            &mut kept,
            &mut kept_facets,
            serosa,
        )?;
    }
    let mut mesh = compact(positions, kept);
    mesh.facets = Some(Facets {
        names,
        of_face: kept_facets,
    });
    debug_assert!(Topology::build(&mesh).is_ok());
    Ok(mesh)
}

/// Close the cavity into the uterine wall: the serosa is the pear (without
/// the myomas and polyps, which grow into the cavity) pushed out along its
/// normal by the wall's thickness, opened at the same height as the cavity,
/// and the two rims round the canal are joined face to face. Every point of
/// the serosa lies the thickness away from the pear, outwards, and every
/// feature grows inwards, so the two surfaces never meet. Faces face out of
/// the solid: into the cavity inside, away from it outside.
#[allow(clippy::too_many_arguments)]
fn close_wall(
    p: &CavityParams,
    sphere: &TriMesh,
    heights: &[f64],
    t_open: f64,
    positions: &mut Vec<DVec3>,
    triangles: &mut Vec<[u32; 3]>,
    facets: &mut Vec<u32>,
    serosa: u32,
) -> Result<(), ParamError> {
    let cavity_faces = triangles.len();
    let base = positions.len() as u32;
    positions.extend(
        sphere
            .positions
            .iter()
            .map(|&q| pear(p, q) + outward_normal(p, q) * p.wall_thickness),
    );
    for t in &sphere.triangles {
        if t.iter().any(|&v| heights[v as usize] >= t_open) {
            triangles.push(t.map(|v| v + base));
            facets.push(serosa);
        }
    }
    // The cavity's rim: its edges that no other cavity face runs the other
    // way. Each becomes a quad to the same edge of the serosa's rim, which
    // runs it the other way round (the serosa is not reversed).
    let mut directed = std::collections::HashSet::new();
    for t in &triangles[..cavity_faces] {
        for i in 0..3 {
            directed.insert((t[i], t[(i + 1) % 3]));
        }
    }
    let mut rim: Vec<(u32, u32)> = directed
        .iter()
        .filter(|&&(a, b)| !directed.contains(&(b, a)))
        .copied()
        .collect();
    rim.sort_unstable();
    if rim.iter().any(|&(a, b)| a.max(b) >= base) {
        return Err(bad(
            "wall_thickness",
            "a myoma or polyp reaches the cervical canal, so the wall cannot be closed there",
        ));
    }
    for (a, b) in rim {
        triangles.push([b, a, a + base]);
        triangles.push([b, a + base, b + base]);
        facets.extend([serosa, serosa]);
    }
    Ok(())
}

fn fmt(x: f64) -> String {
    format!("{}", (x * 1000.0).round() / 1000.0)
}

/// The largest length a parameter may have: far beyond any organ in any
/// unit, far below where squared lengths overflow and the geometry breaks.
const MAX_LENGTH: f64 = 1e6;

fn check(p: &CavityParams) -> Result<(), ParamError> {
    for (key, v) in [
        ("length", p.length),
        ("width", p.width),
        ("depth", p.depth),
        ("cervix_radius", p.cervix_radius),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(key, format!("must be a positive number, not {v}")));
        }
        if v > MAX_LENGTH {
            return Err(bad(key, format!("must be at most {MAX_LENGTH}, not {v}")));
        }
    }
    if p.cervix_radius >= p.width.min(p.depth) / 4.0 {
        return Err(bad(
            "cervix_radius",
            format!(
                "{} must be less than a quarter of the cavity's width and depth ({})",
                fmt(p.cervix_radius),
                fmt(p.width.min(p.depth) / 4.0)
            ),
        ));
    }
    if !(p.wall_thickness.is_finite() && (0.0..=p.width.min(p.depth)).contains(&p.wall_thickness)) {
        return Err(bad(
            "wall_thickness",
            format!(
                "must be from 0 to the cavity's depth and width ({}), not {}",
                fmt(p.width.min(p.depth)),
                p.wall_thickness
            ),
        ));
    }
    // Folds deeper than a twentieth of the cavity's size would crease the
    // wall at the icosphere's spacing; deeper than half the wall, they
    // would bring the cavity near the serosa.
    let deepest = (0.05 * p.width.min(p.depth)).min(if p.wall_thickness > 0.0 {
        0.5 * p.wall_thickness
    } else {
        f64::INFINITY
    });
    if !(p.folds.is_finite() && (0.0..=deepest).contains(&p.folds)) {
        return Err(bad(
            "folds",
            format!("must be from 0 to {}, not {}", fmt(deepest), p.folds),
        ));
    }
    if !(3..=7).contains(&p.resolution) {
        return Err(bad(
            "resolution",
            format!("must be from 3 to 7, not {}", p.resolution),
        ));
    }
    let check_at = |key: String, at: [f64; 2]| -> Result<(), ParamError> {
        if !(0.0..1.0).contains(&at[0]) || !(0.2..=0.95).contains(&at[1]) {
            return Err(bad(
                key + ".at",
                format!(
                    "[{}, {}] must have around in [0, 1) and up in [0.2, 0.95]",
                    at[0], at[1]
                ),
            ));
        }
        Ok(())
    };
    let positive = |key: String, v: f64| -> Result<(), ParamError> {
        if !(v.is_finite() && v > 0.0) {
            Err(bad(key, format!("must be a positive number, not {v}")))
        } else if v > MAX_LENGTH {
            Err(bad(key, format!("must be at most {MAX_LENGTH}, not {v}")))
        } else {
            Ok(())
        }
    };
    for (i, m) in p.myomas.iter().enumerate() {
        check_at(format!("myoma[{i}]"), m.at)?;
        positive(format!("myoma[{i}].radius"), m.radius)?;
        positive(format!("myoma[{i}].height"), m.height)?;
        if m.height > 1.5 * m.radius {
            return Err(bad(
                format!("myoma[{i}].height"),
                format!(
                    "{} is more than 1.5 times its radius {}: a submucosal bulge that steep would fold",
                    fmt(m.height),
                    fmt(m.radius)
                ),
            ));
        }
        if m.radius > 0.4 * p.width.min(p.length) {
            return Err(bad(
                format!("myoma[{i}].radius"),
                format!(
                    "{} is larger than the cavity (at most {})",
                    fmt(m.radius),
                    fmt(0.4 * p.width.min(p.length))
                ),
            ));
        }
    }
    for (i, pl) in p.polyps.iter().enumerate() {
        check_at(format!("polyp[{i}]"), pl.at)?;
        positive(format!("polyp[{i}].stalk_radius"), pl.stalk_radius)?;
        positive(format!("polyp[{i}].stalk_length"), pl.stalk_length)?;
        positive(format!("polyp[{i}].head_radius"), pl.head_radius)?;
        if !(0.5..=3.0).contains(&pl.elongation) {
            return Err(bad(
                format!("polyp[{i}].elongation"),
                format!("must be from 0.5 to 3, not {}", pl.elongation),
            ));
        }
        // Lobes past 0.3 of the radius could fold the head's surface.
        if !(0.0..=0.3).contains(&pl.irregularity) {
            return Err(bad(
                format!("polyp[{i}].irregularity"),
                format!("must be from 0 to 0.3, not {}", pl.irregularity),
            ));
        }
        if !(0.0..=45.0).contains(&pl.lean) {
            return Err(bad(
                format!("polyp[{i}].lean"),
                format!("must be from 0 to 45 degrees, not {}", pl.lean),
            ));
        }
        if pl.stalk_radius >= pl.head_radius {
            return Err(bad(
                format!("polyp[{i}].stalk_radius"),
                format!(
                    "{} must be less than the head radius {}",
                    fmt(pl.stalk_radius),
                    fmt(pl.head_radius)
                ),
            ));
        }
        if polyp_footprint(pl) > 0.3 * p.width.min(p.depth) {
            return Err(bad(
                format!("polyp[{i}]"),
                format!(
                    "its footprint {} is larger than the cavity allows ({})",
                    fmt(polyp_footprint(pl)),
                    fmt(0.3 * p.width.min(p.depth))
                ),
            ));
        }
    }
    Ok(())
}

/// Outward normal of the pear at unit-sphere point `q` (from the map's
/// derivatives along two tangents).
fn outward_normal(p: &CavityParams, q: DVec3) -> DVec3 {
    let helper = if q.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    let t1 = q.cross(helper).normalize();
    let t2 = q.cross(t1);
    let h = 1e-5;
    let d1 = pear(p, (q + t1 * h).normalize()) - pear(p, (q - t1 * h).normalize());
    let d2 = pear(p, (q + t2 * h).normalize()) - pear(p, (q - t2 * h).normalize());
    let n = d1.cross(d2).normalize();
    // Outward: away from the long axis.
    let c = pear(p, q);
    if n.dot(c - DVec3::new(0.0, 0.0, c.z)) >= 0.0 {
        n
    } else {
        -n
    }
}

/// Distance from a site across the cavity to the opposite wall, along its
/// inward normal.
fn cavity_span(positions: &[DVec3], triangles: &[[u32; 3]], site: &Site) -> f64 {
    // The site is on the smooth pear, the mesh only near it: ignore the wall
    // under the site itself.
    triangles
        .iter()
        .filter_map(|t| ray_triangle(site.centre, site.normal, t.map(|v| positions[v as usize])))
        .filter(|&d| d > 0.25 * site.footprint)
        .fold(f64::INFINITY, f64::min)
}

/// A myoma: the wall pushed along the site's inward normal by a smooth
/// compact bump, its outline made irregular by a few seeded harmonics.
fn bulge(
    positions: &mut [DVec3],
    original: &[DVec3],
    facet_of_vertex: &mut [u32],
    facet: u32,
    site: &Site,
    m: &Myoma,
    seed: u64,
) {
    let (e1, e2) = tangent_frame(site.normal);
    let harmonic: Vec<(f64, f64)> = (2..5)
        .map(|k| {
            let amp = 0.08 * (rng::hash(seed, &[k]) % 1000) as f64 / 1000.0;
            let phase = TAU * (rng::hash(seed, &[k, 1]) % 1000) as f64 / 1000.0;
            (amp, phase)
        })
        .collect();
    for (v, &q) in original.iter().enumerate() {
        let d = q - site.centre;
        let along = d.dot(site.normal);
        let flat = d - site.normal * along;
        let phi = flat.dot(e2).atan2(flat.dot(e1));
        let wobble: f64 = harmonic
            .iter()
            .enumerate()
            .map(|(k, (a, ph))| a * ((k as f64 + 2.0) * phi + ph).sin())
            .sum();
        let s = d.length() / (m.radius * (1.0 + wobble));
        if s < 1.0 {
            let b = (1.0 - s * s).powi(2);
            positions[v] += site.normal * m.height * b;
            if s < 0.92 {
                facet_of_vertex[v] = facet;
            }
        }
    }
}

fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.z.abs() < 0.9 { DVec3::Z } else { DVec3::X };
    let e1 = helper.cross(n).normalize();
    (e1, n.cross(e1))
}

/// The height fraction below which the cavity is narrower than the canal.
fn opening_height(p: &CavityParams) -> f64 {
    let radius = |t: f64| {
        let q = DVec3::new(
            (1.0 - (2.0 * t - 1.0).powi(2)).max(0.0).sqrt(),
            0.0,
            2.0 * t - 1.0,
        );
        let a = pear(p, q).x;
        let b = pear(p, DVec3::new(0.0, q.x, q.z)).y;
        (a * b).sqrt()
    };
    let (mut lo, mut hi) = (0.0, 0.5);
    for _ in 0..60 {
        let mid = (lo + hi) / 2.0;
        if radius(mid) < p.cervix_radius {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Drop unreferenced vertices, renumbering the rest in order.
fn compact(positions: Vec<DVec3>, mut triangles: Vec<[u32; 3]>) -> TriMesh {
    let mut map = vec![u32::MAX; positions.len()];
    let mut kept = Vec::new();
    for t in &mut triangles {
        for v in t.iter_mut() {
            if map[*v as usize] == u32::MAX {
                map[*v as usize] = kept.len() as u32;
                kept.push(positions[*v as usize]);
            }
            *v = map[*v as usize];
        }
    }
    TriMesh::new(kept, triangles)
}
