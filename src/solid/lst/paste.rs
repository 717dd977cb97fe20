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
//! Patches are sited and grown `BATCH` at a time, side by side (the
//! paper pastes one by one; growing and solving a clump is most of the
//! time, and sequential pasting left all but one core idle).
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

use super::mask::{Cover, MaskKind, Splotch, TabulatedSplotch, cover};
use super::model::Layer;
use crate::error::{Error, Result};
use crate::linalg::SpdPattern;
use crate::progress::{self, Progress};
use crate::rng;
use crate::tetra::TetMesh;
use crate::tetra::mesh::NO_NEIGHBOUR;

/// See the module's comment.
const TENSOR_CLOSE: f64 = 0.35;
/// Solves after the first, at most.
const REGROW: usize = 4;
/// A regrowth that adds fewer than one tet in `SETTLED` to a clump of
/// `SETTLED_FROM` tets or more is not solved again. On the default wall
/// the last solves of the largest clumps (some 70k tets, 14k unknowns)
/// each let in a few dozen tets, at 50 ms a solve: two thirds of those
/// patches' time, and the fill waited on them. Smaller clumps, where a
/// solve costs well under a millisecond, solve every regrowth as before
/// (the default scene's myomas, in small whorled patches, fill as they
/// did: without this floor two seeds in six moved a myoma's 95th
/// percentile by some 20 degrees). The tets of the
/// regrowth not solved keep the coordinates their own maps carry them to,
/// as after the last solve: on the scene's wall over seeds 1-6 the median
/// alignment is 2.35-2.57 degrees (2.37-2.47 solving every regrowth),
/// the 95th percentile 18.0-22.0 (18.0-21.7).
const SETTLED: usize = 50;
const SETTLED_FROM: usize = 1000;
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
    let splotch = &splotch.tabulated();
    let ns = samples.len();
    let mut coverage = vec![0u8; nt * ns];
    // The uncovered tets, and each one's place in that list.
    let mut uncovered: Vec<u32> = (0..nt as u32).collect();
    let mut place: Vec<u32> = (0..nt as u32).collect();
    let mut pasted: Vec<(u32, Layer)> = Vec::new();
    let mut angles: Vec<f32> = Vec::new();
    progress.stage("pasting patches", nt as u64);
    let max_patches = (ns * nt + 1) as u32;
    let mut patch = 0u32;
    let mut draw = 0u32;
    let pasting = Pasting {
        mesh,
        adjacency: &adjacency,
        fields,
        splotch,
        marks: MarksPool::default(),
    };
    while !uncovered.is_empty() {
        progress::check(progress)?;
        if patch >= max_patches {
            return Err(Error::invalid("the pasting does not converge"));
        }
        // A batch of sites, each a seed tet drawn from the uncovered ones
        // and its least covered sample point.
        let sites: Vec<Site> = (draw..draw + BATCH)
            .map(|d| {
                let seed_tet = uncovered[rng::below(seed, &[d as u64], uncovered.len())] as usize;
                let cov = &coverage[seed_tet * ns..(seed_tet + 1) * ns];
                let (sample, &then) = cov
                    .iter()
                    .enumerate()
                    .min_by_key(|&(i, &c)| (c, i))
                    .expect("165 samples");
                Site {
                    draw: d,
                    seed_tet,
                    bary: samples[sample].map(|x| x as f64),
                    sample,
                    then,
                }
            })
            .collect();
        draw += BATCH;
        let grown: Vec<Result<Grown>> = sites
            .par_iter()
            .map(|s| pasting.grow(s, &coverage, &samples))
            .collect();
        for (site, grown) in sites.iter().zip(grown) {
            // An earlier patch of the batch reached this one's centre: the
            // pasting one by one would have sited it elsewhere.
            if coverage[site.seed_tet * ns + site.sample] != site.then {
                continue;
            }
            let Grown {
                clump,
                corners,
                kind,
                angles: patch_angles,
                alphas,
            } = grown?;
            // Record the layers and add coverage (sec. 5.2.6).
            angles.extend(patch_angles);
            for (&t, w) in clump.iter().zip(&corners) {
                pasted.push((
                    t as u32,
                    Layer {
                        patch,
                        mask: kind,
                        coords: w.map(|c| c.as_vec3().to_array()),
                    },
                ));
            }
            // The uncovered list is updated in clump order, so the result
            // does not depend on threads.
            for (&t, alpha) in clump.iter().zip(alphas) {
                let Some(alpha) = alpha else { continue };
                let cov = &mut coverage[t * ns..(t + 1) * ns];
                // Covered by an earlier patch of this batch: it has left
                // the list already, and more alpha changes nothing.
                if cov.iter().all(|&c| c == 255) {
                    continue;
                }
                for (c, a) in cov.iter_mut().zip(alpha) {
                    *c = c.saturating_add(a);
                }
                if cov.iter().all(|&c| c == 255) {
                    let at = place[t] as usize;
                    let last = *uncovered.last().expect("t was uncovered");
                    uncovered.swap_remove(at);
                    if (last as usize) != t {
                        place[last as usize] = at as u32;
                    }
                    progress.advance(1);
                }
            }
            patch += 1;
        }
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

/// Patches sited at once from the same coverage and grown side by side.
/// A constant, not the thread count, so the result is the same on any
/// machine; small, so few are wasted: a patch whose centre an earlier one
/// of its batch reached is dropped (pasting one by one would not have put
/// it there), and the rest differ from one-by-one pasting only in which
/// uncovered tets they were drawn from.
const BATCH: u32 = 4;

/// Where a patch goes: its seed tet, drawn (the `draw`th) from those
/// uncovered before its batch, and the seed's least covered sample point
/// (`sample`, barycentric `bary`), covered `then` at that time.
struct Site {
    draw: u32,
    seed_tet: usize,
    bary: [f64; 4],
    sample: usize,
    then: u8,
}

/// A patch grown and solved: its clump, the texture coordinates of each
/// clump tet's corners, its mask, per clump tet and texture axis the
/// angle (degrees) between the tet's tensor axis carried into texture
/// space and that axis (`Pasted::angles`), and per clump tet the alphas it
/// adds to the coverage (`Pasting::alphas`).
struct Grown {
    clump: Vec<usize>,
    corners: Vec<[DVec3; 4]>,
    kind: MaskKind,
    angles: Vec<f32>,
    alphas: Vec<Option<Vec<u8>>>,
}

/// What growing a patch reads.
struct Pasting<'a> {
    mesh: &'a TetMesh,
    adjacency: &'a [[u32; 4]],
    fields: &'a Fields<'a>,
    splotch: &'a TabulatedSplotch<'a>,
    marks: MarksPool,
}

/// A growth's marks: per vertex its index among the clump's vertices
/// (`u32::MAX`: none), per tet whether the clump holds it.
struct Marks {
    local: Vec<u32>,
    in_clump: Vec<bool>,
}

/// Marks kept between growths, all clear: made anew per patch, the
/// default wall's half a megabyte of them was a page fault per page
/// touched (3% of the fill). A pool, not a thread's own: a growth waits
/// on its alphas' parallel loop, where the thread may start another.
#[derive(Default)]
struct MarksPool(std::sync::Mutex<Vec<Marks>>);

impl MarksPool {
    fn take(&self, mesh: &TetMesh) -> Marks {
        let pooled = self.0.lock().unwrap_or_else(|e| e.into_inner()).pop();
        pooled.unwrap_or_else(|| Marks {
            local: vec![u32::MAX; mesh.num_vertices()],
            in_clump: vec![false; mesh.num_tets()],
        })
    }

    /// `marks`, cleared where `clump`'s growth set them.
    fn give_back(&self, mut marks: Marks, mesh: &TetMesh, clump: &[usize]) {
        for &t in clump {
            marks.in_clump[t] = false;
            for v in mesh.tets[t] {
                marks.local[v as usize] = u32::MAX;
            }
        }
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(marks);
    }
}

impl Pasting<'_> {
    /// Seed, clump and texture coordinates of the patch at `site` (sec.
    /// 5.2.3-5.2.5), and its alphas against `coverage`, the coverage its
    /// batch was sited from.
    fn grow(&self, site: &Site, coverage: &[u8], samples: &[[f32; 4]]) -> Result<Grown> {
        let Pasting {
            mesh,
            adjacency,
            fields,
            splotch,
            ..
        } = *self;
        let (seed_tet, bary) = (site.seed_tet, site.bary);
        let mut marks = self.marks.take(mesh);
        let Marks { local, in_clump } = &mut marks;
        let corners = mesh.corners(seed_tet);
        let centre_obj = (0..4).fold(DVec3::ZERO, |a, k| a + corners[k] * bary[k]);
        let seed_depth = fields.depth.map(|d| {
            (0..4)
                .map(|k| d[mesh.tets[seed_tet][k] as usize] * bary[k])
                .sum::<f64>()
        });
        let kind = seed_depth.map_or(MaskKind::Splotch, MaskKind::for_depth);
        let centre_tex = DVec3::new(0.5, seed_depth.unwrap_or(0.5), 0.5);
        let seed_frame = (fields.frame_of)(seed_tet, site.draw, None);
        let frame = |t: usize| (fields.frame_of)(t, site.draw, Some(&seed_frame));
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
        // in, or next to nothing (`SETTLED`), ends it, as does the
        // `REGROW`th. After the last solve the clump is grown once more
        // the same way without solving, so no tet the mask reaches is left
        // out (a layer missing there would show as a step in the colours).
        let mut coords;
        let mut solves = 0;
        let mut rows: Vec<TetRows> = Vec::with_capacity(clump.len());
        loop {
            // Each tet's rows once per patch: the clump only grows.
            rows.extend(
                clump[rows.len()..]
                    .iter()
                    .map(|&t| TetRows::new(mesh, t, &frame(t))),
            );
            coords = optimise(
                mesh,
                fields.depth,
                &rows,
                &clump,
                local,
                seed_tet,
                bary,
                centre_tex,
            )?;
            solves += 1;
            let last = solves > REGROW;
            let before = clump.len();
            let mut ring_start = 0;
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
                ring_start = clump.len();
                clump.extend(added);
            }
            let added = clump.len() - before;
            let settled = before >= SETTLED_FROM && added * SETTLED < before;
            if added == 0 || last || settled {
                break;
            }
        }
        let corners: Vec<[DVec3; 4]> = clump
            .iter()
            .map(|&t| mesh.tets[t].map(|v| coords[local[v as usize] as usize]))
            .collect();
        self.marks.give_back(marks, mesh, &clump);
        let mut angles = Vec::with_capacity(3 * clump.len());
        for (&t, w) in clump.iter().zip(&corners) {
            let c = mesh.corners(t);
            let g = DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]);
            let j = DMat3::from_cols(w[1] - w[0], w[2] - w[0], w[3] - w[0]) * g.inverse();
            let f = frame(t);
            for axis in 0..3 {
                let v = j * f.col(axis);
                let cos = (v[axis] / v.length()).clamp(-1.0, 1.0);
                angles.push(cos.acos().to_degrees() as f32);
            }
        }
        let alphas = self.alphas(kind, &clump, &corners, coverage, samples);
        Ok(Grown {
            clump,
            corners,
            kind,
            angles,
            alphas,
        })
    }

    /// The mask's alpha at every sample of a grown patch's tets (sec.
    /// 5.2.6), as bytes to add to their coverage; `None` for a tet it adds
    /// nothing to. Reckoned against the coverage the patch's batch was
    /// sited from, beside the patch's growth (on a core the batch's
    /// unequal clumps would leave idle): a sample covered then takes
    /// nothing (more alpha changes nothing there), and one an earlier
    /// patch of the batch covers takes its alpha to no effect, as the
    /// coverage saturates. A tet the mask leaves out, or covers whole,
    /// takes 0 or 1 without its samples (`mask::cover`, exact: alpha is 0
    /// or 1 there too). The tets are independent: in parallel.
    fn alphas(
        &self,
        kind: MaskKind,
        clump: &[usize],
        corners: &[[DVec3; 4]],
        coverage: &[u8],
        samples: &[[f32; 4]],
    ) -> Vec<Option<Vec<u8>>> {
        let (splotch, ns) = (self.splotch, samples.len());
        clump
            .par_iter()
            .zip(corners)
            .map(|(&t, w)| {
                let cov = &coverage[t * ns..(t + 1) * ns];
                if cov.iter().all(|&c| c == 255) {
                    return None;
                }
                Some(match cover(kind, &w.map(|c| c.to_array()), 0.0) {
                    Cover::None => return None,
                    Cover::Full => vec![255; ns],
                    Cover::Part => samples
                        .iter()
                        .zip(cov)
                        .map(|(b, &c)| {
                            if c == 255 {
                                return 0;
                            }
                            let p = w[0] * b[0] as f64
                                + w[1] * b[1] as f64
                                + w[2] * b[2] as f64
                                + w[3] * b[3] as f64;
                            // Rounded: alpha is never negative, so a half
                            // up and truncation (no libm call).
                            (splotch.alpha(kind, p.to_array()) * 255.0 + 0.5) as u8
                        })
                        .collect(),
                })
            })
            .collect()
    }
}

/// Whether the tet with texture-space corners `w` meets the mask: alpha
/// above 0 at a corner, an edge midpoint, a face centroid or the centroid,
/// or the texture's centre inside it (a tet larger than the mask).
fn meets_mask(splotch: &TabulatedSplotch, kind: MaskKind, w: &[DVec3; 4]) -> bool {
    // Whole tets inside the mask's core meet it without probes; tets where
    // it is 0 all over do not, even one holding the texture's centre (a
    // band's alpha is 0 there when the tet lies out of the band).
    match cover(kind, &w.map(|c| c.to_array()), 0.0) {
        Cover::None => return false,
        Cover::Full => return true,
        Cover::Part => {}
    }
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

/// A tet's three rows of the least-squares system (sec. 5.2.5): per
/// texture axis, the coefficients on its four vertices of the texture map
/// applied to its frame's axis (target: the unit axis); and their normal
/// block, the sum of the rows' outer products.
struct TetRows {
    coefficients: [[f64; 4]; 3],
    block: [[f64; 4]; 4],
}

impl TetRows {
    fn new(mesh: &TetMesh, t: usize, frame: &DMat3) -> TetRows {
        let c = mesh.corners(t);
        let gi = DMat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]).inverse();
        let coefficients = [0, 1, 2].map(|axis| {
            let beta = gi * frame.col(axis);
            [-(beta.x + beta.y + beta.z), beta.x, beta.y, beta.z]
        });
        let mut block = [[0.0; 4]; 4];
        for a in &coefficients {
            for i in 0..4 {
                for j in 0..4 {
                    block[i][j] += a[i] * a[j];
                }
            }
        }
        TetRows {
            coefficients,
            block,
        }
    }
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
    rows: &[TetRows],
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
    // The normal matrix, sum over tets of a 4 x 4 block: each tet's three
    // rows (one per axis, four coefficients on its vertices, target the
    // unit axis) and the seed's row, summed per tet before assembly; the
    // three components share it. Assembled once per vertex pair, column
    // by column over the tets at each vertex (a counting sort, no
    // comparison sort of every row's entries: this solve runs a few times
    // per patch, thousands of times per organ).
    let mut rhs = [vec![0.0; m], vec![0.0; m], vec![0.0; m]];
    let mut blocks: Vec<([u32; 4], [[f64; 4]; 4])> = Vec::with_capacity(clump.len() + 1);
    for (&t, r) in clump.iter().zip(rows) {
        let ids = mesh.tets[t].map(|v| local[v as usize]);
        for (axis, a) in r.coefficients.iter().enumerate() {
            for i in 0..4 {
                rhs[axis][ids[i] as usize] += a[i];
            }
        }
        blocks.push((ids, r.block));
    }
    let seed_ids = mesh.tets[seed_tet].map(|v| local[v as usize]);
    let mut seed_block = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            seed_block[i][j] = seed_bary[i] * seed_bary[j];
        }
        for c in 0..3 {
            rhs[c][seed_ids[i] as usize] += seed_bary[i] * centre[c];
        }
    }
    blocks.push((seed_ids, seed_block));
    // The blocks at each vertex (CSR by vertex).
    let mut at_start = vec![0u32; m + 1];
    for (ids, _) in &blocks {
        for &v in ids {
            at_start[v as usize + 1] += 1;
        }
    }
    for v in 0..m {
        at_start[v + 1] += at_start[v];
    }
    let mut at = vec![0u32; at_start[m] as usize];
    let mut fill = at_start.clone();
    for (b, (ids, _)) in blocks.iter().enumerate() {
        for &v in ids {
            at[fill[v as usize] as usize] = b as u32;
            fill[v as usize] += 1;
        }
    }
    // Column j: rows i >= j of the blocks at j, each pair once.
    let mut col_start = Vec::with_capacity(m + 1);
    col_start.push(0);
    let mut rows_at: Vec<usize> = Vec::with_capacity(8 * m);
    let mut values: Vec<f64> = Vec::with_capacity(8 * m);
    let mut slot = vec![usize::MAX; m];
    for j in 0..m {
        let first = rows_at.len();
        for &b in &at[at_start[j] as usize..at_start[j + 1] as usize] {
            let (ids, block) = &blocks[b as usize];
            let kj = ids
                .iter()
                .position(|&v| v as usize == j)
                .expect("at lists its own");
            for (ki, &i) in ids.iter().enumerate() {
                if (i as usize) < j {
                    continue;
                }
                let e = slot[i as usize];
                let e = if e != usize::MAX && e >= first {
                    e
                } else {
                    slot[i as usize] = rows_at.len();
                    rows_at.push(i as usize);
                    values.push(0.0);
                    rows_at.len() - 1
                };
                values[e] += block[ki][kj];
            }
        }
        col_start.push(rows_at.len());
    }
    let pattern = SpdPattern::from_columns(m, col_start, rows_at)?;
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
