//! Pasting patches until every tet is covered (seed 000, sec. 5.2.3-5.2.6).
//!
//! Each patch: a seed tet drawn from the uncovered ones; the texture
//! centre put at the seed's least covered sample point; the seed's affine
//! map from object to texture space (sec. 5.2.4: its tensor axes onto the
//! texture axes, the centre onto (0.5, 0.5, 0.5), or (0.5, depth, 0.5) for
//! layered types); a clump grown across faces over tets whose tensor is
//! close to the seed's and whose image meets the mask; texture coordinates
//! of the clump's vertices by least squares (sec. 5.2.5), then regrown
//! where the warped clump leaves part of the mask uncovered, and solved
//! again; the mask's alpha added at 165 sample points of every tet in the
//! clump (sec. 5.2.6), a tet leaving the uncovered list once all of them
//! reach 1.
//!
//! Choices the paper leaves open: "close to the seed's tensor" is
//! `|A F_t - I| <= TENSOR_CLOSE` (Frobenius; `A` the seed's map, `F_t` the
//! tet's frame), which admits about 15 degrees of turn or a scale ratio
//! within about 1.25, and holds only while the clump first grows: the
//! regrowth then adds every tet the warped mask still reaches, whatever its
//! tensor, so a patch is never cut off inside its mask and the colours stay
//! continuous across tets. That costs alignment at the edges of patches
//! where the field turns (the uterine wall at 8k tets: 95th percentile
//! 18.5 degrees against 12.9 when the regrowth stopped after a ring, which
//! left visible steps along the cavity); the
//! seed's positional constraint is one extra row of the least-squares
//! system, which the solution meets exactly (the other rows do not change
//! under a translation).

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use super::mask::{MaskKind, Splotch};
use super::model::Layer;
use crate::error::{Error, Result};
use crate::linalg::SpdPattern;
use crate::progress::{self, Progress};
use crate::rng;
use crate::tetra::TetMesh;
use crate::tetra::mesh::NO_NEIGHBOUR;

/// See the module's comment.
const TENSOR_CLOSE: f64 = 0.35;
const REGROW: usize = 4;
/// Rings of tets a regrowth adds before solving again.
const RINGS_PER_SOLVE: usize = usize::MAX;
/// Sample points per tet side: barycentric (i, j, k, l) / 8 with
/// i + j + k + l = 8, 165 points (the paper's count).
const SAMPLE_DIVISIONS: usize = 8;

/// The 165 sample points' barycentric coordinates.
pub fn sample_points() -> Vec<[f32; 4]> {
    let n = SAMPLE_DIVISIONS;
    let mut out = Vec::new();
    for i in 0..=n {
        for j in 0..=n - i {
            for k in 0..=n - i - j {
                let l = n - i - j - k;
                out.push([i, j, k, l].map(|x| x as f32 / n as f32));
            }
        }
    }
    out
}

/// What the pasting reads per tet: its frame (columns: the object vectors
/// the texture's r, s and t axes map from), and for layered types the
/// vertices' depths (the s coordinate).
pub struct Fields<'a> {
    /// The frame of tet `t` in patch `p` whose seed's frame is given (the
    /// seed's own frame when none is: types whose secondary axes are drawn
    /// per patch draw them there and carry them to the other tets).
    pub frame_of: &'a (dyn Fn(usize, u32, Option<&DMat3>) -> DMat3 + Sync),
    pub depth: Option<&'a [f64]>,
}

/// What `paste` made: per tet its layers in paste order (as offsets and a
/// flat list), the number of patches, and for every layer and texture axis
/// the angle (degrees) between the tet's tensor axis carried into texture
/// space and that texture axis (sec. 5.2.5's difference vectors, as
/// angles).
pub struct Pasted {
    pub start: Vec<u32>,
    pub layers: Vec<Layer>,
    pub patches: u32,
    pub angles: Vec<f32>,
}

/// Paste until covered.
pub fn paste(
    mesh: &TetMesh,
    fields: &Fields,
    splotch: &Splotch,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Pasted> {
    let adjacency = mesh.face_adjacency()?;
    let nt = mesh.num_tets();
    let samples = sample_points();
    let ns = samples.len();
    let mut coverage = vec![0u8; nt * ns];
    // The uncovered tets, and each one's place in that list.
    let mut uncovered: Vec<u32> = (0..nt as u32).collect();
    let mut place: Vec<u32> = (0..nt as u32).collect();
    let mut pasted: Vec<(u32, Layer)> = Vec::new();
    let mut local = vec![u32::MAX; mesh.num_vertices()];
    let mut in_clump = vec![false; nt];
    let mut angles: Vec<f32> = Vec::new();
    progress.stage("pasting patches", nt as u64);
    let max_patches = (ns * nt + 1) as u32;
    let mut patch = 0u32;
    while !uncovered.is_empty() {
        progress::check(progress)?;
        if patch >= max_patches {
            return Err(Error::invalid("the pasting does not converge"));
        }
        let seed_tet = uncovered[rng::below(seed, &[patch as u64], uncovered.len())] as usize;
        // The centre at the least covered sample point.
        let cov = &coverage[seed_tet * ns..(seed_tet + 1) * ns];
        let (best, _) = cov
            .iter()
            .enumerate()
            .min_by_key(|&(i, &c)| (c, i))
            .expect("165 samples");
        let bary = samples[best].map(|x| x as f64);
        let corners = mesh.corners(seed_tet);
        let centre_obj = (0..4).fold(DVec3::ZERO, |a, k| a + corners[k] * bary[k]);
        let seed_depth = fields.depth.map(|d| {
            (0..4)
                .map(|k| d[mesh.tets[seed_tet][k] as usize] * bary[k])
                .sum::<f64>()
        });
        let kind = seed_depth.map_or(MaskKind::Splotch, MaskKind::for_depth);
        let centre_tex = DVec3::new(0.5, seed_depth.unwrap_or(0.5), 0.5);
        let seed_frame = (fields.frame_of)(seed_tet, patch, None);
        let frame = |t: usize| (fields.frame_of)(t, patch, Some(&seed_frame));
        let map = seed_frame.inverse();
        let seed_map = |p: DVec3| map * (p - centre_obj) + centre_tex;

        // Grow the clump (sec. 5.2.4).
        let mut clump = vec![seed_tet];
        in_clump[seed_tet] = true;
        let mut head = 0;
        while head < clump.len() {
            let t = clump[head];
            head += 1;
            for &n in &adjacency[t] {
                if n == NO_NEIGHBOUR || in_clump[n as usize] {
                    continue;
                }
                let n = n as usize;
                let close = (map * frame(n) - DMat3::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
                    <= TENSOR_CLOSE;
                if close && meets_mask(splotch, kind, &mesh.corners(n).map(seed_map)) {
                    in_clump[n] = true;
                    clump.push(n);
                }
            }
        }

        // Optimise, regrow, optimise (sec. 5.2.5). A regrowth adds ring
        // after ring of tets the warped mask still reaches (their new
        // corners carried by each tet's own map from a known corner) until
        // none is left, and solves again; a solve that lets nothing more
        // in ends it. After the last solve the clump is grown once more
        // the same way without solving, so no tet the mask reaches is left
        // out (a layer missing there would show as a step in the colours).
        let mut coords;
        let mut solves = 0;
        loop {
            coords = optimise(
                mesh,
                fields.depth,
                &frame,
                &clump,
                &mut local,
                seed_tet,
                bary,
                centre_tex,
            )?;
            solves += 1;
            let last = solves > REGROW;
            let mut grown = false;
            let mut ring_start = 0;
            let mut rings = 0;
            loop {
                let mut added = Vec::new();
                for &t in &clump[ring_start..] {
                    for &n in &adjacency[t] {
                        if n == NO_NEIGHBOUR || in_clump[n as usize] {
                            continue;
                        }
                        let n = n as usize;
                        let tet = mesh.tets[n];
                        let Some(k0) = (0..4).find(|&k| local[tet[k] as usize] != u32::MAX) else {
                            continue;
                        };
                        let a = frame(n).inverse();
                        let base = mesh.positions[tet[k0] as usize];
                        let w0 = coords[local[tet[k0] as usize] as usize];
                        let mut w = tet.map(|v| match local[v as usize] {
                            u32::MAX => w0 + a * (mesh.positions[v as usize] - base),
                            l => coords[l as usize],
                        });
                        if let Some(d) = fields.depth {
                            for (k, v) in tet.iter().enumerate() {
                                w[k].y = d[*v as usize];
                            }
                        }
                        if meets_mask(splotch, kind, &w) {
                            in_clump[n] = true;
                            added.push(n);
                            for (k, &v) in tet.iter().enumerate() {
                                if local[v as usize] == u32::MAX {
                                    local[v as usize] = coords.len() as u32;
                                    coords.push(w[k]);
                                }
                            }
                        }
                    }
                }
                if added.is_empty() {
                    break;
                }
                grown = true;
                ring_start = clump.len();
                clump.extend(added);
                rings += 1;
                if rings == RINGS_PER_SOLVE {
                    break;
                }
            }
            if !grown || last {
                break;
            }
        }

        // Record the layers and add coverage (sec. 5.2.6).
        for &t in &clump {
            let w = mesh.tets[t].map(|v| coords[local[v as usize] as usize]);
            let c = mesh.corners(t);
            let g = DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
            let j = DMat3::from_cols(w[1] - w[0], w[2] - w[0], w[3] - w[0]) * g.inverse();
            let f = frame(t);
            for axis in 0..3 {
                let v = j * f.col(axis);
                let cos = (v[axis] / v.length()).clamp(-1.0, 1.0);
                angles.push(cos.acos().to_degrees() as f32);
            }
            pasted.push((
                t as u32,
                Layer {
                    patch,
                    mask: kind,
                    coords: w.map(|c| c.as_vec3().to_array()),
                },
            ));
        }
        // The masks' alpha at every sample of every clump tet, in parallel
        // (the tets are independent); the uncovered list is updated after,
        // in clump order, so the result does not depend on threads.
        let alphas: Vec<Vec<u8>> = clump
            .par_iter()
            .map(|&t| {
                let w = mesh.tets[t].map(|v| coords[local[v as usize] as usize]);
                samples
                    .iter()
                    .map(|b| {
                        let p = w[0] * b[0] as f64
                            + w[1] * b[1] as f64
                            + w[2] * b[2] as f64
                            + w[3] * b[3] as f64;
                        (splotch.alpha(kind, p.to_array()) * 255.0).round() as u8
                    })
                    .collect()
            })
            .collect();
        for (&t, alpha) in clump.iter().zip(alphas) {
            let cov = &mut coverage[t * ns..(t + 1) * ns];
            let was_covered = cov.iter().all(|&c| c == 255);
            for (c, a) in cov.iter_mut().zip(alpha) {
                *c = c.saturating_add(a);
            }
            if !was_covered && cov.iter().all(|&c| c == 255) {
                let at = place[t] as usize;
                let last = *uncovered.last().expect("t was uncovered");
                uncovered.swap_remove(at);
                if (last as usize) != t {
                    place[last as usize] = at as u32;
                }
                progress.advance(1);
            }
        }
        for &t in &clump {
            in_clump[t] = false;
            for v in mesh.tets[t] {
                local[v as usize] = u32::MAX;
            }
        }
        patch += 1;
    }
    // Per tet, in paste order: a stable counting sort by tet.
    let mut start = vec![0u32; nt + 1];
    for (t, _) in &pasted {
        start[*t as usize + 1] += 1;
    }
    for t in 0..nt {
        start[t + 1] += start[t];
    }
    let mut fill = start.clone();
    let mut layers = vec![
        Layer {
            patch: 0,
            mask: MaskKind::Splotch,
            coords: [[0.0; 3]; 4],
        };
        pasted.len()
    ];
    for (t, l) in pasted {
        layers[fill[t as usize] as usize] = l;
        fill[t as usize] += 1;
    }
    Ok(Pasted {
        start,
        layers,
        patches: patch,
        angles,
    })
}

/// Whether the tet with texture-space corners `w` meets the mask: alpha
/// above 0 at a corner, an edge midpoint, a face centroid or the centroid,
/// or the texture's centre inside it (a tet larger than the mask).
fn meets_mask(splotch: &Splotch, kind: MaskKind, w: &[DVec3; 4]) -> bool {
    let probe = |p: DVec3| splotch.alpha(kind, p.to_array()) > 0.0;
    let sum = w[0] + w[1] + w[2] + w[3];
    for i in 0..4 {
        if probe(w[i]) || probe((sum - w[i]) / 3.0) {
            return true;
        }
        for j in i + 1..4 {
            if probe((w[i] + w[j]) / 2.0) {
                return true;
            }
        }
    }
    if probe(sum / 4.0) {
        return true;
    }
    let b = super::locate::barycentric(w, DVec3::splat(0.5));
    b.iter().all(|&x| x >= 0.0)
}

/// Texture coordinates of the clump's vertices (sec. 5.2.5): for every
/// tet, its frame's axes mapped by the (per-tet linear) texture map should
/// be the texture's unit axes; the seed point maps to `centre`. For
/// layered types the s coordinate is the vertex's depth, and only r and t
/// are solved. Fills `local` (vertex -> index into the result).
#[allow(clippy::too_many_arguments)]
fn optimise(
    mesh: &TetMesh,
    depth: Option<&[f64]>,
    frame_of: &dyn Fn(usize) -> DMat3,
    clump: &[usize],
    local: &mut [u32],
    seed_tet: usize,
    seed_bary: [f64; 4],
    centre: DVec3,
) -> Result<Vec<DVec3>> {
    let mut verts: Vec<u32> = Vec::new();
    for &t in clump {
        for v in mesh.tets[t] {
            local[v as usize] = u32::MAX;
        }
    }
    for &t in clump {
        for v in mesh.tets[t] {
            if local[v as usize] == u32::MAX {
                local[v as usize] = verts.len() as u32;
                verts.push(v);
            }
        }
    }
    let m = verts.len();
    // Rows: four coefficients on the tet's local vertices; targets per
    // component. The normal matrix is shared by the components.
    let mut positions: Vec<(u32, u32)> = Vec::with_capacity(clump.len() * 10 + 10);
    let mut values: Vec<f64> = Vec::with_capacity(clump.len() * 30 + 10);
    let mut rhs = [vec![0.0; m], vec![0.0; m], vec![0.0; m]];
    let mut add_row = |ids: [u32; 4],
                       a: [f64; 4],
                       target: [f64; 3],
                       positions: &mut Vec<(u32, u32)>,
                       values: &mut Vec<f64>| {
        for i in 0..4 {
            for j in 0..4 {
                if ids[i] >= ids[j] {
                    positions.push((ids[i], ids[j]));
                    values.push(a[i] * a[j]);
                }
            }
            for c in 0..3 {
                rhs[c][ids[i] as usize] += a[i] * target[c];
            }
        }
    };
    for &t in clump {
        let tet = mesh.tets[t];
        let ids = tet.map(|v| local[v as usize]);
        let c = mesh.corners(t);
        let g = DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
        let gi = g.inverse();
        let frame = frame_of(t);
        for axis in 0..3 {
            let beta = gi * frame.col(axis);
            let a = [-(beta.x + beta.y + beta.z), beta.x, beta.y, beta.z];
            let mut target = [0.0; 3];
            target[axis] = 1.0;
            add_row(ids, a, target, &mut positions, &mut values);
        }
    }
    let seed_ids = mesh.tets[seed_tet].map(|v| local[v as usize]);
    add_row(
        seed_ids,
        seed_bary,
        centre.to_array(),
        &mut positions,
        &mut values,
    );
    let pattern = SpdPattern::new(m, &positions)?;
    let chol = pattern.factor(&values)?;
    let solve = |c: usize, rhs: &mut [Vec<f64>; 3]| chol.solve(&mut rhs[c]);
    solve(0, &mut rhs);
    solve(2, &mut rhs);
    match depth {
        Some(d) => {
            for (i, &v) in verts.iter().enumerate() {
                rhs[1][i] = d[v as usize];
            }
        }
        None => solve(1, &mut rhs),
    }
    Ok((0..m)
        .map(|i| DVec3::new(rhs[0][i], rhs[1][i], rhs[2][i]))
        .collect())
}
