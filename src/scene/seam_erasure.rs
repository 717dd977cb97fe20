//! Seam erasure in baked atlases (after Liu, Ferguson, Jacobson and
//! Gingold, "Seamless: seam erasure and seam-aware decoupling of shape
//! from mesh resolution", 2017). A seam's two sides lie apart in a facet's
//! atlas, and a facet border's in two atlases, each drawn by bilinear
//! filtering from its own texels, so even where the compositor's colour is
//! the same on both sides (the seam band and the overlap ring make it so)
//! the two reconstructions differ by what a texel grid at two different
//! phases makes of the tissue's grain. The texels whose filter reaches a
//! seam or border are moved, by least squares over all of a node's
//! atlases at once, so that both sides' bilinear colours agree all along
//! it: mostly the ones off the charts (they show nothing else), the
//! charts' own ones only where those cannot do it. The colours are the
//! atlas's sRGB values, filtered as `Atlas::sample` reads them; a GPU
//! filtering an sRGB texture in linear light differs from that by far less
//! than the mismatch removed, since the colours either side are close.

use super::atlas::Atlas;
use super::build::BakedNode;
use super::contrast::Owners;
use crate::linalg::SpdPattern;

/// How firmly a texel inside the chart keeps its baked colour, against a
/// seam's mismatch of 1 (per sample, `SAMPLES_PER_TEXEL` along it).
const KEEP_INSIDE: f64 = 1.0;
/// The same for a texel off the chart (its margin): free to move.
const KEEP_OUTSIDE: f64 = 0.01;
/// Samples per texel of seam where the two sides are made to agree.
const SAMPLES_PER_TEXEL: f64 = 2.0;

/// A texel of one of a node's atlases: (facet, texel index).
type Texel = (usize, usize);

/// One sample along a seam or border: the facet whose seam it is (`None`:
/// a border) and the texels the two sides read, with signed weights.
type Sample = (Option<usize>, Vec<(Texel, f64)>);

/// Samples along every seam and facet border of `node`,
/// `SAMPLES_PER_TEXEL` per texel of its longer image: each the texels the
/// two sides' bilinear colours read there, with their weights, one side's
/// positive and the other's negative (a texel both read counted once), so
/// that a row's weighted sum of texel colours is the mismatch at its
/// sample; and per row, the facet whose seam it is (`None`: a border).
/// They depend on the charts alone, not on the texels' colours.
fn samples(node: &BakedNode, atlases: &[Atlas]) -> Vec<Sample> {
    let topo = &node.topology;
    let owners = Owners::of(node);
    // Texel position of node vertex `v` in the atlas of the facet owning
    // node face `face`.
    let at = |face: usize, v: u32| atlases[owners.facet(face)].texel(owners.uv(face, v).1);
    let mut rows = Vec::new();
    for (h, t, seam) in owners.joins() {
        let (fa, fb) = (topo.face(h).idx(), topo.face(t).idx());
        let (ka, kb) = (owners.facet(fa), owners.facet(fb));
        let ends = [topo.origin(h).0, topo.tip(h).0];
        let (a, b) = (ends.map(|v| at(fa, v)), ends.map(|v| at(fb, v)));
        let length = (a[1] - a[0]).length().max((b[1] - b[0]).length());
        let count = (length * SAMPLES_PER_TEXEL).ceil().max(1.0) as usize;
        for s in 0..count {
            let t = (s as f64 + 0.5) / count as f64;
            let mut row: Vec<(Texel, f64)> = Vec::with_capacity(8);
            for (k, p, sign) in [
                (ka, a[0].lerp(a[1], t), 1.0),
                (kb, b[0].lerp(b[1], t), -1.0),
            ] {
                for (texel, w) in atlases[k].taps(p) {
                    match row.iter_mut().find(|(i, _)| *i == (k, texel)) {
                        Some(entry) => entry.1 += sign * w,
                        None if w != 0.0 => row.push(((k, texel), sign * w)),
                        None => {}
                    }
                }
            }
            rows.push((seam, row));
        }
    }
    rows
}

/// How far apart the two sides of each facet's seams are in `atlases` at
/// the `rows` along them: the root mean square, over the samples and the
/// three channels, of the difference of their bilinear colours (sRGB,
/// 0-255); `None` for a facet without seams.
fn mismatch(rows: &[Sample], atlases: &[Atlas]) -> Vec<Option<f64>> {
    let mut sums = vec![(0.0, 0usize); atlases.len()];
    for (facet, row) in rows {
        let Some(k) = *facet else { continue };
        for c in 0..3 {
            let d: f64 = row
                .iter()
                .map(|&((a, t), w)| w * atlases[a].pixels[t][c] as f64)
                .sum();
            sums[k].0 += d * d;
        }
        sums[k].1 += 3;
    }
    sums.iter()
        .map(|&(sum, n)| (n > 0).then(|| (sum / n as f64).sqrt()))
        .collect()
}

/// Erase the seams and facet borders of `node` from its `atlases` (in
/// facet order, as `atlas::bake` made them), noting in each atlas how far
/// apart its seams' two sides were as baked and are after
/// (`Atlas::seam_mismatch`). Minimises, per channel, the squared mismatch
/// of the two sides' bilinear colours at the samples along every seam and
/// border plus each texel's squared change weighted by `KEEP_INSIDE` or
/// `KEEP_OUTSIDE`: one sparse SPD system over the texels the samples read,
/// factored once for the three channels. On the default scene's atlases
/// at 2048: the polyp's seams from 1.28 to 0.42, the wall's from 0.51 to
/// 0.25, the serosa's from 1.29 to 0.26.
pub fn erase(node: &BakedNode, atlases: &mut [Atlas]) {
    let rows = samples(node, atlases);
    let baked = mismatch(&rows, atlases);
    solve(&rows, atlases);
    let erased = mismatch(&rows, atlases);
    for ((a, b), e) in atlases.iter_mut().zip(baked).zip(erased) {
        a.seam_mismatch = b.zip(e).map(|(b, e)| [b, e]);
    }
}

/// The least squares of `erase` at `rows`, its result written into
/// `atlases`.
fn solve(rows: &[Sample], atlases: &mut [Atlas]) {
    // The texels the samples read become unknowns, numbered in the order
    // first met.
    let mut unknown: Vec<Vec<u32>> = atlases
        .iter()
        .map(|a| vec![u32::MAX; a.width * a.height])
        .collect();
    let mut texels: Vec<Texel> = Vec::new();
    for &((k, t), _) in rows.iter().flat_map(|(_, row)| row) {
        if unknown[k][t] == u32::MAX {
            unknown[k][t] = texels.len() as u32;
            texels.push((k, t));
        }
    }
    if texels.is_empty() {
        return;
    }
    // The normal equations (R'R + K) x = K x0, lower triangle.
    let keep: Vec<f64> = texels
        .iter()
        .map(|&(k, t)| match atlases[k].inside[t] {
            true => KEEP_INSIDE,
            false => KEEP_OUTSIDE,
        })
        .collect();
    let mut positions: Vec<(u32, u32)> = (0..texels.len() as u32).map(|i| (i, i)).collect();
    let mut values = keep.clone();
    for (_, row) in rows {
        for (p, &((ka, ta), wi)) in row.iter().enumerate() {
            for &((kb, tb), wj) in &row[..=p] {
                let (i, j) = (unknown[ka][ta], unknown[kb][tb]);
                positions.push((i.max(j), i.min(j)));
                values.push(wi * wj);
            }
        }
    }
    // The matrix is a sum of squares plus a positive diagonal: positive
    // definite whatever the seams, so neither step can fail on well-formed
    // atlases; if one did, they are left as baked.
    let Ok(pattern) = SpdPattern::new(texels.len(), &positions) else {
        return;
    };
    let Ok(cholesky) = pattern.factor(&values) else {
        return;
    };
    for c in 0..3 {
        let mut x: Vec<f64> = texels
            .iter()
            .zip(&keep)
            .map(|(&(k, t), &w)| w * atlases[k].pixels[t][c] as f64)
            .collect();
        cholesky.solve(&mut x);
        for (&(k, t), v) in texels.iter().zip(x) {
            atlases[k].pixels[t][c] = v.round().clamp(0.0, 255.0) as u8;
        }
    }
}
