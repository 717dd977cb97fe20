//! Lapped solid textures (seed 000; seed 002, ch. 3, 5, 6): patches of a
//! solid exemplar pasted over a tet mesh of the organ, oriented by a
//! tensor field and layered by a depth field, until every tet is covered.
//! A point's colour is its tet's patches composited in paste order, so
//! every cut through the organ shows the same tissue (the property seed
//! 000 claims over per-cut synthesis).
//!
//! - `fields`: the depth field (thin-plate RBF) and Laplacian smoothing of
//!   stroke directions and scales;
//! - `mask`: the splotch alpha mask and its depth bands;
//! - `paste`: seed, clump, least-squares texture coordinates, coverage;
//! - `model`: the result and its `.lst` file;
//! - `sample`: colours at points, as a `solid::Interior`;
//! - `gpu`: the same colours on cut surfaces in WGSL, and the buffers it
//!   reads;
//! - `locate`: which tet holds a point;
//! - `regions`: parts of the organ lapped with a texture of their own
//!   (a myoma's whorled fibres in the layered wall).
//!
//! The five texture types (seed 000, sec. 3-4), texture axes (r, s, t):
//! - 0, isotropic: each patch turned at random, scale given;
//! - 1-a, oriented: r along the stroke field, turned at random about it;
//! - 1-b, layered: s along the depth gradient and s = depth, turned at
//!   random about it, scale 1 / |grad depth|;
//! - 2-a: s along the depth gradient, r along the strokes made
//!   perpendicular to it, t = r x s, scale given;
//! - 2-b: as 2-a with s = depth and scale 1 / |grad depth|.

pub mod anchors;
pub mod fields;
pub mod gpu;
pub mod locate;
pub mod mask;
pub mod model;
pub mod paste;
pub mod regions;
pub mod sample;

use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

pub use mask::{MaskKind, Splotch};
pub use model::{Layer, LstModel};
pub use sample::LstInterior;

use crate::error::{Error, Result};
use crate::progress::{self, Progress};
use crate::rng;
use crate::tetra::TetMesh;

/// Seed 000's classification (sec. 3), the five types it fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum TextureType {
    Isotropic = 0,
    Oriented = 1,
    Layered = 2,
    Tensor = 3,
    LayeredTensor = 4,
}

impl TextureType {
    pub fn from_u8(k: u8) -> Option<TextureType> {
        use TextureType::*;
        [Isotropic, Oriented, Layered, Tensor, LayeredTensor]
            .get(k as usize)
            .copied()
    }

    /// From the paper's names: 0, 1a, 1b, 2a, 2b (a dash allowed).
    pub fn parse(s: &str) -> Result<TextureType> {
        use TextureType::*;
        Ok(
            match s.trim().to_ascii_lowercase().replace('-', "").as_str() {
                "0" => Isotropic,
                "1a" => Oriented,
                "1b" => Layered,
                "2a" => Tensor,
                "2b" => LayeredTensor,
                other => {
                    return Err(Error::invalid(format!(
                        "texture type '{other}': expected 0, 1a, 1b, 2a or 2b"
                    )));
                }
            },
        )
    }

    pub fn name(self) -> &'static str {
        ["0", "1a", "1b", "2a", "2b"][self as usize]
    }

    /// Whether the depth is the s texture coordinate (1-b, 2-b).
    pub fn layered(self) -> bool {
        matches!(self, TextureType::Layered | TextureType::LayeredTensor)
    }

    pub fn needs_depth(self) -> bool {
        !matches!(self, TextureType::Isotropic | TextureType::Oriented)
    }

    pub fn needs_strokes(self) -> bool {
        matches!(
            self,
            TextureType::Oriented | TextureType::Tensor | TextureType::LayeredTensor
        )
    }
}

/// What to fill and how.
#[derive(Clone, Debug, PartialEq)]
pub struct LstOptions {
    pub kind: TextureType,
    /// Object units one patch (the texture's [0, 1]^3) spans, for types 0,
    /// 1-a and 2-a (1-b and 2-b take 1 / |grad depth|).
    pub scale: f64,
    /// Polylines in object space along which the texture's r axis runs
    /// (1-a, 2-a, 2-b).
    pub strokes: Vec<Vec<DVec3>>,
    /// Points at depth 0 (the outer region: a facet's vertices) and at
    /// depth 1 (the inner region) for 1-b, 2-a, 2-b.
    pub depth_outer: Vec<DVec3>,
    pub depth_inner: Vec<DVec3>,
    pub seed: u64,
}

/// What a fill measured besides the model.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FillStats {
    pub patches: u32,
    pub layers: usize,
    /// Alignment (sec. 5.2.5): over every layer of every tet and each
    /// texture axis, the angle between the tet's tensor axis carried into
    /// texture space and that axis, in degrees.
    pub angle_median: f64,
    pub angle_p95: f64,
    pub angle_max: f64,
}

/// A part of the mesh filled with options of its own. Seed 000 laps one
/// texture through a mesh; an organ holds several tissues, such as a
/// myoma's whorled fibres inside the layered uterine wall. Patches do not
/// cross a region's border (a myoma's pseudo-capsule is a sharp one).
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    pub name: String,
    /// Its tets, which no other region holds.
    pub tets: Vec<u32>,
    /// Types 0 and 1-a: the depth field is the organ's, not a region's.
    pub options: LstOptions,
}

/// Fill `mesh` with patches; see the module's comment.
pub fn fill(mesh: &TetMesh, opts: &LstOptions, progress: &dyn Progress) -> Result<LstModel> {
    fill_stats(mesh, opts, progress).map(|(m, _)| m)
}

/// `fill`, with what it measured.
pub fn fill_stats(
    mesh: &TetMesh,
    opts: &LstOptions,
    progress: &dyn Progress,
) -> Result<(LstModel, FillStats)> {
    fill_regions(mesh, opts, &[], progress).map(|(m, mut s)| (m, s.swap_remove(0)))
}

/// Fill the tets of each region with its options and the rest of `mesh`
/// with `main`'s, as one model; the stats of the rest, then of each
/// region. The mask's shape follows `main.seed` everywhere.
pub fn fill_regions(
    mesh: &TetMesh,
    main: &LstOptions,
    regions: &[Region],
    progress: &dyn Progress,
) -> Result<(LstModel, Vec<FillStats>)> {
    let nt = mesh.num_tets();
    if nt == 0 {
        return Err(Error::invalid("the tet mesh is empty: nothing to fill"));
    }
    mesh.validate()?;
    let mut part_of = vec![0usize; nt];
    for (k, r) in regions.iter().enumerate() {
        if r.options.kind.needs_depth() {
            return Err(Error::invalid(format!(
                "region '{}': type {} needs the depth field; a region takes type 0 or 1a",
                r.name,
                r.options.kind.name()
            )));
        }
        if r.tets.is_empty() {
            return Err(Error::invalid(format!("region '{}' holds no tets", r.name)));
        }
        for &t in &r.tets {
            let Some(p) = part_of.get_mut(t as usize) else {
                return Err(Error::invalid(format!(
                    "region '{}' names tet {t}, past the mesh's {nt}",
                    r.name
                )));
            };
            if *p != 0 {
                return Err(Error::invalid(format!(
                    "tet {t} is in regions '{}' and '{}'",
                    regions[*p - 1].name,
                    r.name
                )));
            }
            *p = k + 1;
        }
    }

    // Depth per vertex over the whole mesh, so vertices on a region's
    // border have one.
    let depth_field = if main.kind.needs_depth() {
        Some(fields::DepthField::fit(
            &main.depth_outer,
            &main.depth_inner,
        )?)
    } else {
        None
    };
    // Unclamped: a little past 0 or 1 between the constraints, the masks
    // and the exemplar's clamp take it as 0 or 1, and the gradient stays
    // that of the field.
    let depth: Option<Vec<f64>> = depth_field
        .as_ref()
        .map(|f| mesh.positions.par_iter().map(|&p| f.value(p)).collect());

    let splotch = Splotch::new(main.seed);
    let main_tets: Vec<u32> = (0..nt as u32)
        .filter(|&t| part_of[t as usize] == 0)
        .collect();
    // The parts are independent (no patch crosses a region's border): they
    // are filled side by side, only the first (the largest, the organ's
    // own) showing its progress.
    let jobs: Vec<(&Vec<u32>, &LstOptions)> = std::iter::once((&main_tets, main))
        .chain(regions.iter().map(|r| (&r.tets, &r.options)))
        .collect();
    let quiet = progress::CancelOnly(progress);
    let mut parts: Vec<Option<(paste::Pasted, FillStats)>> = jobs
        .par_iter()
        .enumerate()
        .map(|(k, &(tets, opts))| {
            let progress: &dyn Progress = if k == 0 { progress } else { &quiet };
            if tets.is_empty() {
                return Ok(None);
            }
            let filled = if tets.len() == nt {
                fill_part(
                    mesh,
                    opts,
                    depth_field.as_ref(),
                    depth.as_deref(),
                    &splotch,
                    progress,
                )?
            } else {
                let (sub, old) = mesh.subset(tets);
                let d: Option<Vec<f64>> = depth
                    .as_ref()
                    .map(|d| old.iter().map(|&v| d[v as usize]).collect());
                fill_part(
                    &sub,
                    opts,
                    depth_field.as_ref(),
                    d.as_deref(),
                    &splotch,
                    progress,
                )?
            };
            Ok(Some(filled))
        })
        .collect::<Result<_>>()?;

    let model = move |start, layers, patches| LstModel {
        kind: main.kind,
        seed: main.seed,
        mesh: mesh.clone(),
        depth: depth.filter(|_| main.kind.layered()),
        start,
        layers,
        patches,
    };
    // The organ alone: its layers are the model's as they are.
    if parts.len() == 1 {
        let (pasted, stats) = parts.pop().flatten().expect("the organ's tets were filled");
        return Ok((
            model(pasted.start, pasted.layers, pasted.patches),
            vec![stats],
        ));
    }
    // One model: each tet's layers from its part, patches numbered on
    // across the parts.
    let mut first_patch = Vec::with_capacity(parts.len());
    let mut patches = 0u32;
    for p in &parts {
        first_patch.push(patches);
        patches += p.as_ref().map_or(0, |(p, _)| p.patches);
    }
    let mut local = vec![0u32; nt];
    for tets in std::iter::once(&main_tets).chain(regions.iter().map(|r| &r.tets)) {
        for (k, &t) in tets.iter().enumerate() {
            local[t as usize] = k as u32;
        }
    }
    let mut start = Vec::with_capacity(nt + 1);
    start.push(0u32);
    let mut layers = Vec::new();
    for t in 0..nt {
        let (pasted, _) = parts[part_of[t]].as_ref().expect("a tet's part was filled");
        let l = local[t] as usize;
        let range = pasted.start[l] as usize..pasted.start[l + 1] as usize;
        layers.extend(pasted.layers[range].iter().map(|&layer| Layer {
            patch: layer.patch + first_patch[part_of[t]],
            ..layer
        }));
        start.push(layers.len() as u32);
    }
    let stats = parts
        .into_iter()
        .map(|p| p.map_or_else(FillStats::empty, |(_, s)| s))
        .collect();
    Ok((model(start, layers, patches), stats))
}

impl FillStats {
    fn empty() -> FillStats {
        FillStats {
            patches: 0,
            layers: 0,
            angle_median: 0.0,
            angle_p95: 0.0,
            angle_max: 0.0,
        }
    }
}

/// Paste one part: `depth` and its `field` are the organ's (at this
/// part's vertices), for the types that need them.
fn fill_part(
    mesh: &TetMesh,
    opts: &LstOptions,
    depth_field: Option<&fields::DepthField>,
    depth: Option<&[f64]>,
    splotch: &Splotch,
    progress: &dyn Progress,
) -> Result<(paste::Pasted, FillStats)> {
    let kind = opts.kind;
    let scale_ok = opts.scale > 0.0 && opts.scale.is_finite();
    if !kind.layered() && !scale_ok {
        return Err(Error::invalid(format!(
            "the texture scale must be a positive length, not {}",
            opts.scale
        )));
    }
    if kind.needs_strokes() && opts.strokes.is_empty() {
        return Err(Error::invalid(format!(
            "texture type {} follows strokes: give at least one",
            kind.name()
        )));
    }
    let centroids: Vec<DVec3> = (0..mesh.num_tets())
        .map(|t| {
            let c = mesh.corners(t);
            (c[0] + c[1] + c[2] + c[3]) / 4.0
        })
        .collect();
    let depth = depth.filter(|_| kind.needs_depth());
    // The depth gradient per tet: that of the depth as the texture gets it,
    // interpolated linearly from the vertices, so the s axis of layered
    // textures follows the s coordinate exactly; the field's own gradient
    // at the centroid where the vertices' depths are all alike.
    let gradient: Vec<DVec3> = match (depth_field, depth) {
        (Some(f), Some(d)) => {
            // The field's gradient costs a term per constraint: asked only
            // where the linear one is not steeper than any it takes in the
            // mesh's box (nearly nowhere), the result the same.
            let (lo, hi) = mesh
                .positions
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                    (lo.min(p), hi.max(p))
                });
            let surely_steeper = 1e-6 * f.gradient_bound(lo, hi);
            (0..mesh.num_tets())
                .into_par_iter()
                .map(|t| {
                    let c = mesh.corners(t);
                    let v = mesh.tets[t].map(|k| d[k as usize]);
                    let g = DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
                    let linear =
                        g.inverse().transpose() * DVec3::new(v[1] - v[0], v[2] - v[0], v[3] - v[0]);
                    if linear.length() > surely_steeper {
                        return linear;
                    }
                    let analytic = f.gradient(centroids[t]);
                    if linear.length() > 1e-6 * analytic.length() {
                        linear
                    } else {
                        analytic
                    }
                })
                .collect()
        }
        _ => Vec::new(),
    };
    if let Some(t) = gradient
        .iter()
        .position(|g| g.length().is_nan() || g.length() <= 1e-12)
    {
        return Err(Error::invalid(format!(
            "the depth field is flat at tet {t} ({}): the outer and inner regions do not \
             bracket the mesh",
            centroids[t]
        )));
    }

    // The stroke field per tet (sec. 5.2.2): smoothed per vertex, averaged
    // per tet; layer-aware weights for 2-a and 2-b.
    let strokes: Vec<DVec3> = if kind.needs_strokes() {
        let neighbours = fields::vertex_neighbours(mesh);
        let spacing = mean_edge(mesh);
        let locator = locate::Locator::new(mesh);
        let constraints = fields::stroke_constraints(&opts.strokes, spacing, mesh, &locator)?;
        let sigma = match &depth {
            Some(d) => {
                let mut diffs: Vec<f64> = neighbours
                    .iter()
                    .enumerate()
                    .flat_map(|(i, r)| r.iter().map(move |&j| (d[i] - d[j as usize]).abs()))
                    .collect();
                diffs.sort_unstable_by(f64::total_cmp);
                2.0 * diffs
                    .get(diffs.len() / 2)
                    .copied()
                    .unwrap_or(1.0)
                    .max(1e-12)
            }
            None => 1.0,
        };
        let weight = |i: usize, j: usize| match (&depth, kind) {
            (Some(d), TextureType::Tensor | TextureType::LayeredTensor) => {
                (-((d[i] - d[j]) / sigma).powi(2)).exp()
            }
            _ => 1.0,
        };
        let v = fields::laplacian_smooth(mesh, &neighbours, &weight, &constraints, 3)?;
        (0..mesh.num_tets())
            .map(|t| {
                let s = mesh.tets[t].iter().fold(DVec3::ZERO, |a, &k| {
                    a + DVec3::new(v[0][k as usize], v[1][k as usize], v[2][k as usize])
                });
                s.normalize_or_zero()
            })
            .collect()
    } else {
        Vec::new()
    };

    // Per patch draws: a rotation (type 0) or a secondary direction.
    let seed = opts.seed;
    let turn = |patch: u32| -> DQuat {
        let u = |k: u64| rng::unit(seed, &[patch as u64, k]);
        // Shoemake's uniform rotation from three uniforms.
        let (u1, u2, u3) = (
            u(0),
            u(1) * std::f64::consts::TAU,
            u(2) * std::f64::consts::TAU,
        );
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        DQuat::from_xyzw(a * u2.sin(), a * u2.cos(), b * u3.sin(), b * u3.cos())
    };
    let scale = opts.scale;
    // A patch's frames: the seed's from the patch's draw; every other tet's
    // carries the seed's randomly drawn axes over (made perpendicular to
    // the tet's primary axis), so a patch turns with its field and no more.
    let frame_of = |t: usize, patch: u32, seed_frame: Option<&DMat3>| -> DMat3 {
        // Drawn only for the seed (the others carry the seed's over).
        let drawn = || turn(patch) * DVec3::X;
        // (r, s, t) columns, s along the depth gradient.
        let depth_frame = |secondary: DVec3, length: f64| {
            let f = fields::frame(gradient[t], secondary);
            DMat3::from_cols(f.col(1), f.col(0), -f.col(2)) * length
        };
        match kind {
            TextureType::Isotropic => DMat3::from_quat(turn(patch)) * scale,
            TextureType::Oriented => {
                fields::frame(strokes[t], seed_frame.map_or_else(drawn, |f| f.col(1))) * scale
            }
            TextureType::Layered => depth_frame(
                seed_frame.map_or_else(drawn, |f| f.col(0)),
                1.0 / gradient[t].length(),
            ),
            TextureType::Tensor => depth_frame(strokes[t], scale),
            TextureType::LayeredTensor => depth_frame(strokes[t], 1.0 / gradient[t].length()),
        }
    };
    // Only layered types take the depth as their s coordinate (2-a lays
    // its s axis along the gradient, at the given scale).
    let f = paste::Fields {
        frame_of: &frame_of,
        depth: depth.filter(|_| kind.layered()),
    };
    let mut pasted = paste::paste(mesh, &f, splotch, seed, progress)?;
    let [angle_median, angle_p95, angle_max] = quantiles(&mut pasted.angles, [0.5, 0.95, 1.0]);
    let stats = FillStats {
        patches: pasted.patches,
        layers: pasted.layers.len(),
        angle_median,
        angle_p95,
        angle_max,
    };
    Ok((pasted, stats))
}

/// The values at ascending quantiles `qs` of `values` (the element at
/// rank round((n - 1) q)), 0 for none; reorders `values`. By selection,
/// each from the part above the last: the default wall's 5.8 million
/// angles took 0.12 s to sort on one core, and take 0.015 s to select.
fn quantiles<const N: usize>(values: &mut [f32], qs: [f64; N]) -> [f64; N] {
    let mut below = 0;
    qs.map(|q| {
        let Some(last) = values.len().checked_sub(1) else {
            return 0.0;
        };
        let rank = (last as f64 * q).round() as usize;
        let (_, &mut x, _) = values[below..].select_nth_unstable_by(rank - below, f32::total_cmp);
        below = rank;
        x as f64
    })
}

/// The depth constraints of a natural default for organs (issue 22): depth
/// 0 at the vertices of facet `outer` (the serosa), 1 at those of facet
/// `inner` (the cavity), less the vertices the two share (where they meet,
/// round the cervical canal, the depth is neither). Errors name a missing
/// facet, the same facet twice, or facets that share every vertex.
pub fn facet_depth_points(
    mesh: &crate::mesh::TriMesh,
    outer: &str,
    inner: &str,
) -> Result<(Vec<DVec3>, Vec<DVec3>)> {
    if outer == inner {
        return Err(Error::invalid(format!(
            "the depth's outer and inner facets are both '{outer}': give two facets"
        )));
    }
    let facets = mesh
        .facets
        .as_ref()
        .ok_or_else(|| Error::invalid("the mesh has no facets to take the depth from"))?;
    let id = |name: &str| {
        facets.names.iter().position(|n| n == name).ok_or_else(|| {
            Error::invalid(format!(
                "no facet '{name}' for the depth (the mesh has: {})",
                facets.names.join(", ")
            ))
        })
    };
    let (o, i) = (id(outer)? as u32, id(inner)? as u32);
    // By position: readers copy the vertices facets share along borders.
    let bits = |p: DVec3| p.to_array().map(f64::to_bits);
    let mut on: std::collections::HashMap<[u64; 3], (DVec3, u8)> = Default::default();
    let mut order: Vec<[u64; 3]> = Vec::new();
    for (t, &f) in mesh.triangles.iter().zip(&facets.of_face) {
        let bit = if f == o {
            1
        } else if f == i {
            2
        } else {
            0
        };
        for &v in t {
            let p = mesh.positions[v as usize];
            let e = on.entry(bits(p)).or_insert_with(|| {
                order.push(bits(p));
                (p, 0)
            });
            e.1 |= bit;
        }
    }
    let pick = |bit: u8| -> Vec<DVec3> {
        order
            .iter()
            .map(|k| on[k])
            .filter(|&(_, b)| b == bit)
            .map(|(p, _)| p)
            .collect()
    };
    let (a, b) = (pick(1), pick(2));
    if a.is_empty() || b.is_empty() {
        return Err(Error::invalid(format!(
            "facets '{outer}' and '{inner}' share all their vertices: no depth between them"
        )));
    }
    Ok((a, b))
}

/// The mean length of the tets' edges.
pub fn mean_edge(mesh: &TetMesh) -> f64 {
    let mut total = 0.0;
    for t in 0..mesh.num_tets() {
        let c = mesh.corners(t);
        for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            total += c[i].distance(c[j]);
        }
    }
    total / (6.0 * mesh.num_tets().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_by_selection_are_those_of_the_sorted_values() {
        let mut values: Vec<f32> = (0..1001u64)
            .map(|i| (rng::unit(7, &[i]) * 180.0) as f32)
            .collect();
        let mut sorted = values.clone();
        sorted.sort_unstable_by(f32::total_cmp);
        let qs = [0.0, 0.5, 0.95, 1.0];
        let want = qs.map(|q: f64| sorted[(1000.0 * q).round() as usize] as f64);
        assert_eq!(quantiles(&mut values, qs), want);
        assert_eq!(quantiles(&mut [], [0.5]), [0.0]);
        assert_eq!(quantiles(&mut [3.0], [0.5, 1.0]), [3.0, 3.0]);
    }
}
