//! A tileable vessel overlay grown as a tree on a torus, in the colour and
//! opacity of a photograph's vessels.
//!
//! A photograph's vessels cannot tile as they are (they end at its edges),
//! and pixel-by-pixel resynthesis (FNPTS) breaks the large vessels into
//! short pieces. So the network is grown instead, by space colonisation
//! (Runions, Lane and Prusinkiewicz 2007): attraction points scattered over
//! the image, each pulling the tree node nearest it; a pulled node grows a
//! step towards the mean of its pulls, and points the tree reaches are
//! removed. Distances wrap around both axes, so the tree, and the overlay
//! drawn from it, tile. Widths follow Murray's law (a parent's cubed radius
//! is the sum of its children's), then scale so the overlay is as opaque
//! over the image, on average, as the photograph's vessels are over theirs;
//! each vessel is drawn as blood seen through tissue (`draw`).
//!
//! Hand-written: no maintained crate grows branching networks, and the
//! growth is a few loops over points.

use glam::DVec2;

use crate::rng;

/// Alpha from which an overlay pixel shows vessel: under the faintest a
/// drawn vessel's centre line gets (a leaf where it runs deepest, some 90
/// at the scales the database draws), so a drawn tree is one piece at it.
pub const VESSEL_SEEN: u8 = 64;

/// How a tree is grown: lengths in pixels of a `width` x `height` image.
#[derive(Clone, Debug)]
pub struct TreeOptions {
    pub width: usize,
    pub height: usize,
    pub seed: u64,
    /// Trees growing from as many root points.
    pub roots: usize,
    /// Mean spacing of the attraction points, in steps (at least 1).
    pub spacing: f64,
    /// Growth step.
    pub step: f64,
    /// A point pulls nodes no farther than this.
    pub reach: f64,
    /// Branches shorter than this many steps, from a fork to a tip, are
    /// pruned.
    pub twig: usize,
}

impl TreeOptions {
    pub fn new(width: usize, height: usize, seed: u64) -> Self {
        // Lengths follow the image's scale (its geometric mean side), a step
        // at least a pixel, so a thin image does not get a dense cloud.
        let side = ((width * height) as f64).sqrt().max(128.0);
        TreeOptions {
            width,
            height,
            seed,
            roots: 3,
            spacing: 8.0,
            step: side / 128.0,
            reach: side / 6.0,
            twig: 4,
        }
    }
}

/// A grown tree: nodes with their parents (roots have none) and radii
/// relative to a leaf's (1).
#[derive(Clone, Debug)]
pub struct Tree {
    pub position: Vec<DVec2>,
    pub parent: Vec<Option<usize>>,
    pub radius: Vec<f64>,
}

/// The shortest displacement from `a` to `b` on the torus.
fn towards(a: DVec2, b: DVec2, size: DVec2) -> DVec2 {
    let d = b - a;
    d - (d / size).round() * size
}

fn random_point(seed: u64, key: &[u64], size: DVec2) -> DVec2 {
    let unit = |k: u64| {
        let mut full = key.to_vec();
        full.push(k);
        (rng::hash(seed, &full) >> 11) as f64 / (1u64 << 53) as f64
    };
    DVec2::new(unit(0), unit(1)) * size
}

/// Grow a vessel tree by space colonisation on the torus.
pub fn grow(opts: &TreeOptions) -> Tree {
    let size = DVec2::new(opts.width as f64, opts.height as f64);
    // At most a point per pixel.
    let count = ((size.x * size.y / (opts.spacing.max(1.0) * opts.step).powi(2)).ceil() as usize)
        .min(opts.width * opts.height);
    let mut points: Vec<DVec2> = (0..count as u64)
        .map(|i| random_point(opts.seed, &[1, i], size))
        .collect();
    let mut position: Vec<DVec2> = (0..opts.roots.max(1) as u64)
        .map(|i| random_point(opts.seed, &[2, i], size))
        .collect();
    let mut parent: Vec<Option<usize>> = vec![None; position.len()];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); position.len()];
    let kill = 2.0 * opts.step;
    // Each point's nearest node and its distance; new nodes can only come
    // nearer, so each round compares the points with the new nodes alone.
    let nearest_of = |p: DVec2, nodes: &[DVec2], from: usize| {
        (from..nodes.len())
            .map(|n| (n, towards(p, nodes[n], size).length()))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
    };
    let mut nearest: Vec<(usize, f64)> = points
        .iter()
        .map(|&p| nearest_of(p, &position, 0).expect("a root"))
        .collect();
    // Each round grows the tree by a step or ends it; the cap only guards
    // against a tree circling forever.
    let rounds = 8 * ((size.x + size.y) / opts.step) as usize;
    for _ in 0..rounds {
        // Points the tree has reached go.
        let mut k = 0;
        while k < points.len() {
            if nearest[k].1 < kill {
                points.swap_remove(k);
                nearest.swap_remove(k);
            } else {
                k += 1;
            }
        }
        let mut pull = vec![DVec2::ZERO; position.len()];
        let mut pulled = vec![false; position.len()];
        for (&p, &(n, d)) in points.iter().zip(&nearest) {
            if d < opts.reach {
                pull[n] += towards(position[n], p, size) / d;
                pulled[n] = true;
            }
        }
        let from = position.len();
        for n in 0..from {
            // Pulls that cancel out (a point on each side) grow nothing,
            // nor does a pull towards where the node has grown before.
            if pulled[n] && pull[n].length() > 1e-3 {
                let p = (position[n] + pull[n].normalize() * opts.step).rem_euclid(size);
                if !children[n]
                    .iter()
                    .any(|&c| towards(position[c], p, size).length() < 0.5 * opts.step)
                {
                    children[n].push(position.len());
                    children.push(Vec::new());
                    position.push(p);
                    parent.push(Some(n));
                }
            }
        }
        if position.len() == from {
            break;
        }
        for (k, &p) in points.iter().enumerate() {
            if let Some(m) = nearest_of(p, &position, from)
                && m.1 < nearest[k].1
            {
                nearest[k] = m;
            }
        }
    }
    let (mut position, parent) = prune_twigs(position, parent, opts.twig);
    smooth(&mut position, &parent, size, 4);
    // Murray's law, leaves first (a node comes after its parent).
    let (child_count, _) = child_counts(&parent);
    let mut cubed = vec![0.0f64; position.len()];
    for n in (0..position.len()).rev() {
        if child_count[n] == 0 {
            cubed[n] = 1.0;
        }
        if let Some(p) = parent[n] {
            cubed[p] += cubed[n];
        }
    }
    Tree {
        position,
        parent,
        radius: cubed.iter().map(|c| c.cbrt()).collect(),
    }
}

/// Per node, how many children it has, and its last child (its only one
/// where it has one).
fn child_counts(parent: &[Option<usize>]) -> (Vec<usize>, Vec<usize>) {
    let mut count = vec![0usize; parent.len()];
    let mut last = vec![0usize; parent.len()];
    for (n, p) in parent.iter().enumerate() {
        if let Some(p) = *p {
            count[p] += 1;
            last[p] = n;
        }
    }
    (count, last)
}

/// The tree without its twigs: branches of fewer than `twig` nodes from a
/// fork to a tip, which space colonisation sprouts wherever a last point
/// lies beside a vessel.
fn prune_twigs(
    position: Vec<DVec2>,
    parent: Vec<Option<usize>>,
    twig: usize,
) -> (Vec<DVec2>, Vec<Option<usize>>) {
    let (children, _) = child_counts(&parent);
    let mut keep = vec![true; position.len()];
    for leaf in (0..position.len()).filter(|&n| children[n] == 0) {
        let mut chain = vec![leaf];
        let mut n = leaf;
        while let Some(p) = parent[n] {
            if children[p] != 1 {
                // A fork: the chain is a branch; drop it if short.
                if chain.len() < twig {
                    for &c in &chain {
                        keep[c] = false;
                    }
                }
                break;
            }
            chain.push(p);
            n = p;
        }
    }
    let mut index = vec![usize::MAX; position.len()];
    let mut kept_position = Vec::new();
    let mut kept_parent = Vec::new();
    for n in (0..position.len()).filter(|&n| keep[n]) {
        index[n] = kept_position.len();
        kept_position.push(position[n]);
        kept_parent.push(parent[n].map(|p| index[p]));
    }
    (kept_position, kept_parent)
}

/// Kinks eased out of the vessels: `rounds` times, each node between a
/// parent and a single child moves half way towards their midpoint (tips,
/// forks and roots stay), so vessels run in curves rather than the
/// growth's straight steps.
fn smooth(position: &mut [DVec2], parent: &[Option<usize>], size: DVec2, rounds: usize) {
    let (children, child) = child_counts(parent);
    for _ in 0..rounds {
        let moved: Vec<DVec2> = (0..position.len())
            .map(|n| match parent[n] {
                Some(p) if children[n] == 1 => {
                    let here = position[n];
                    let pull =
                        towards(here, position[p], size) + towards(here, position[child[n]], size);
                    (here + pull / 4.0).rem_euclid(size)
                }
                _ => position[n],
            })
            .collect();
        position.copy_from_slice(&moved);
    }
}

/// Optical depth of blood across a leaf vessel's diameter (the leaf's
/// radius plus the half pixel of its antialiased edge): its centre is
/// 1 - e^-1.6 = 80% opaque before blurring.
const LEAF_OPTICAL_DEPTH: f64 = 1.6;

/// Blur of a vessel's image by the tissue over it, per pixel of radius:
/// wider vessels lie deeper, and light scattered by more tissue spreads
/// their image wider.
const SCATTER_PER_RADIUS: f64 = 0.35;

/// Opacity of the tree drawn `width` x `height`, wrapping around, each
/// segment a cylinder of blood of its child's radius times `scale`
/// (pixels) seen from above through the tissue.
///
/// By Beer-Lambert a line of sight through the cylinder is 1 - e^(-mu L)
/// opaque for the chord L it cuts (mu fixed by `LEAF_OPTICAL_DEPTH`), so
/// thin vessels are fainter than thick ones. The tissue over the vessel
/// scatters that image: the profile is taken as a Gaussian of the chord
/// profile's spread widened by the scatter (`SCATTER_PER_RADIUS`), its
/// peak lowered so the blood seen stays the same. Deep, wide vessels are
/// broad and soft, capillaries thin and sharp, as under a mucosa (a flat
/// capsule made every vessel an evenly inked line). `depth` (0..1 over
/// the image, 1 at the surface) fades a vessel where it runs deeper.
pub fn draw(tree: &Tree, width: usize, height: usize, scale: f64, depth: &[f32]) -> Vec<f32> {
    let size = DVec2::new(width as f64, height as f64);
    let mu = LEAF_OPTICAL_DEPTH / (2.0 * (scale + 0.5));
    let mut alpha = vec![0.0f32; width * height];
    for (n, parent) in tree.parent.iter().enumerate() {
        let Some(p) = *parent else { continue };
        let a = tree.position[n];
        let b = a + towards(a, tree.position[p], size);
        let r = tree.radius[n] * scale + 0.5;
        // The chord profile's spread (a half disc's: r / 2) widened by
        // the scatter; 3 spreads out it is about 1% of its peak.
        let chord_spread = 0.5 * r;
        let scatter = SCATTER_PER_RADIUS * (r - 0.5);
        let spread = (chord_spread * chord_spread + scatter * scatter).sqrt();
        let peak = (1.0 - (-mu * 2.0 * r).exp()) * chord_spread / spread;
        let reach = 3.0 * spread;
        let lo = (a.min(b) - reach).floor();
        let hi = (a.max(b) + reach).ceil();
        let ab = b - a;
        for y in lo.y as i64..=hi.y as i64 {
            for x in lo.x as i64..=hi.x as i64 {
                let q = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let t = ((q - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
                let d2 = (q - (a + ab * t)).length_squared();
                if d2 < reach * reach {
                    let i = y.rem_euclid(height as i64) as usize * width
                        + x.rem_euclid(width as i64) as usize;
                    let v = (peak * (-d2 / (2.0 * spread * spread)).exp()) as f32 * depth[i];
                    alpha[i] = alpha[i].max(v);
                }
            }
        }
    }
    alpha
}

/// How near the surface the vessels run over a `width` x `height` tile, in
/// [0.5, 1]: a smooth random field of a few waves that fit the tile
/// (whole periods across it, so it tiles), seeded. Real vessels dip in
/// and out of sight along their course.
pub fn vessel_depth(width: usize, height: usize, seed: u64) -> Vec<f32> {
    let waves: Vec<(f64, f64, f64)> = (0..4u64)
        .map(|k| {
            let pick = |j: u64| rng::hash(seed, &[3, k, j]);
            let kx = (pick(0) % 5) as f64 - 2.0;
            let ky = (pick(1) % 3) as f64 + 1.0;
            let phase = (pick(2) >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
            (kx, ky, phase)
        })
        .collect();
    (0..width * height)
        .map(|i| {
            let (x, y) = (
                (i % width) as f64 / width as f64,
                (i / width) as f64 / height as f64,
            );
            let n = waves
                .iter()
                .map(|&(kx, ky, phase)| (std::f64::consts::TAU * (kx * x + ky * y) + phase).sin())
                .sum::<f64>()
                / waves.len() as f64;
            // n is within [-1, 1], mostly within [-0.5, 0.5].
            (0.75 + 0.5 * n).clamp(0.5, 1.0) as f32
        })
        .collect()
}

/// Mean opacity: how much vessel an overlay shows, soft edges counted by
/// their share.
pub fn opacity(alpha: impl Iterator<Item = u8>) -> f64 {
    let (mut sum, mut all) = (0.0f64, 0usize);
    for a in alpha {
        sum += a as f64 / 255.0;
        all += 1;
    }
    sum / all.max(1) as f64
}

/// A tileable overlay in the colours and opacity of `photo`, a vessel
/// overlay (RGBA, vessels opaque) made from a photograph: its vessels'
/// mean colour and mean opacity, drawn on a tree grown from `seed`. The
/// opacity, not the count of opaque pixels, is matched: the drawn vessels
/// are soft (`draw`), and a threshold would count their blurred edges
/// in or out wholesale. A photograph without vessels gives a transparent
/// overlay.
pub fn tileable_overlay(photo: &[[u8; 4]], width: usize, height: usize, seed: u64) -> Vec<[u8; 4]> {
    let target = opacity(photo.iter().map(|p| p[3]));
    let (mut sum, mut weight) = ([0.0f64; 3], 0.0f64);
    for p in photo {
        let w = p[3] as f64;
        for k in 0..3 {
            sum[k] += w * p[k] as f64;
        }
        weight += w;
    }
    let colour = sum.map(|s| (s / weight.max(1.0)).round() as u8);
    if target <= 0.0 || width == 0 || height == 0 {
        return vec![[colour[0], colour[1], colour[2], 0]; width * height];
    }
    let tree = grow(&TreeOptions::new(width, height, seed));
    // Opacity grows with the width (about linearly): the leaf radius
    // rescaled in proportion a few times finds the photograph's.
    let depth = vessel_depth(width, height, seed);
    let drawn = |scale: f64| -> Vec<u8> {
        draw(&tree, width, height, scale, &depth)
            .iter()
            .map(|&a| (a * 255.0).round() as u8)
            .collect()
    };
    let mut scale = 0.75;
    let mut alpha = drawn(scale);
    for _ in 0..4 {
        let c = opacity(alpha.iter().copied());
        if c <= 0.0 || ((c - target) / target).abs() < 0.02 {
            break;
        }
        scale *= target / c;
        alpha = drawn(scale);
    }
    alpha
        .into_iter()
        .map(|a| [colour[0], colour[1], colour[2], a])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grown_tree_reaches_all_over_the_tile_in_short_segments() {
        let opts = TreeOptions::new(128, 128, 3);
        let size = DVec2::splat(128.0);
        let tree = grow(&opts);
        assert!(tree.position.len() > 100, "{} nodes", tree.position.len());
        for (n, p) in tree.parent.iter().enumerate() {
            if let Some(p) = *p {
                // Short segments, none jumping across the tile.
                let step = towards(tree.position[p], tree.position[n], size).length();
                assert!(step > 0.0 && step <= 1.5 * opts.step, "{step}");
            }
        }
        // No bare patch: every pixel within a point's reach of the tree,
        // across the tile's edges too.
        let farthest = (0..128 * 128)
            .map(|i| {
                let q = DVec2::new((i % 128) as f64 + 0.5, (i / 128) as f64 + 0.5);
                tree.position
                    .iter()
                    .map(|&p| towards(q, p, size).length())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(farthest <= opts.reach, "{farthest} > {}", opts.reach);
    }

    #[test]
    fn wide_vessels_are_darker_and_softer_than_capillaries() {
        // Two straight vessels across a 64-pixel tile, radii 1 and 4 leaves
        // at a pixel a leaf, at the surface (depth 1) everywhere.
        // (Segments shorter than half the tile: the shorter way round.)
        let tree = Tree {
            position: vec![
                DVec2::new(16.0, 4.0),
                DVec2::new(16.0, 32.0),
                DVec2::new(16.0, 60.0),
                DVec2::new(48.0, 4.0),
                DVec2::new(48.0, 32.0),
                DVec2::new(48.0, 60.0),
            ],
            parent: vec![None, Some(0), Some(1), None, Some(3), Some(4)],
            radius: vec![1.0, 1.0, 1.0, 4.0, 4.0, 4.0],
        };
        let alpha = draw(&tree, 64, 64, 1.0, &[1.0; 64 * 64]);
        let across = |x: usize| alpha[32 * 64 + x];
        let (thin, wide) = (across(16), across(48));
        assert!(thin > 0.5 && wide > thin + 0.1, "{thin} {wide}");
        // A pixel past its edge (radius 1.5 and 4.5 with the antialiasing
        // half pixel) the capillary is gone, and the wide vessel's
        // scattered image is still a tenth of its peak.
        assert!(across(18) < 0.01 * thin, "{}", across(18));
        assert!(across(53) > 0.1 * wide, "{}", across(53));
        // A vessel running deeper is fainter.
        let deeper = draw(&tree, 64, 64, 1.0, &[0.5; 64 * 64]);
        assert!((deeper[32 * 64 + 48] - 0.5 * wide).abs() < 1e-6);
    }

    #[test]
    fn a_photograph_without_vessels_gives_a_transparent_overlay() {
        let photo = vec![[200, 90, 80, 0]; 64 * 64];
        let overlay = tileable_overlay(&photo, 64, 64, 0);
        assert_eq!(overlay.len(), 64 * 64);
        assert!(overlay.iter().all(|p| p[3] == 0));
    }
}
