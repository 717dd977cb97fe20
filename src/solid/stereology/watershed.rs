//! Touching particles' profiles, split apart. Two particles that touch
//! (or overlap a little) leave one connected profile in a section; counted
//! as one, it is a large profile that no single particle made, and the
//! unfolding puts volume into sizes the material does not have. Splitting
//! at the necks of the distance transform (a watershed of the distance to
//! the binder, the usual way to separate touching round objects) counts
//! them apart: a neck is a saddle of the distance narrower than `NECK` of
//! the smaller particle's inscribed radius, so the bumps of one irregular
//! profile stay together.

use crate::mesh::dsu::DisjointSets;

/// A saddle at under this fraction of the lower peak splits two basins.
const NECK: f64 = 0.7;
/// Peaks lower than this (pixels from the binder) never split off: pixel
/// noise on a profile's edge, not a particle.
const MIN_PEAK: f64 = 2.0;

/// Pixel `i`'s left, right, upper and lower neighbours, where the image
/// has them.
pub(super) fn four_neighbours(i: usize, width: usize, height: usize) -> [Option<usize>; 4] {
    let (x, y) = (i % width, i / width);
    [
        (x > 0).then(|| i - 1),
        (x + 1 < width).then(|| i + 1),
        (y > 0).then(|| i - width),
        (y + 1 < height).then(|| i + width),
    ]
}

/// 4-connected components of the usable pixels where `inside` holds:
/// per pixel its component (1-based, 0 outside), and per component whether
/// it touches the image's border or an unusable pixel.
pub(super) fn components(
    width: usize,
    height: usize,
    valid: &[bool],
    inside: &dyn Fn(usize) -> bool,
) -> (Vec<u32>, Vec<bool>) {
    let mut label = vec![0u32; valid.len()];
    let mut touches = Vec::new();
    let mut stack = Vec::new();
    for start in 0..valid.len() {
        if !valid[start] || !inside(start) || label[start] != 0 {
            continue;
        }
        let id = touches.len() as u32 + 1;
        let mut touch = false;
        label[start] = id;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let (x, y) = (i % width, i / width);
            if x == 0 || y == 0 || x + 1 == width || y + 1 == height {
                touch = true;
            }
            for j in four_neighbours(i, width, height).into_iter().flatten() {
                if !valid[j] {
                    touch = true;
                } else if inside(j) && label[j] == 0 {
                    label[j] = id;
                    stack.push(j);
                }
            }
        }
        touches.push(touch);
    }
    (label, touches)
}

/// Pixels of each component of `label` (as `components` numbers them).
pub(super) fn component_sizes(label: &[u32]) -> Vec<usize> {
    let mut sizes = vec![0usize; label.iter().copied().max().unwrap_or(0) as usize];
    for &c in label {
        if c != 0 {
            sizes[c as usize - 1] += 1;
        }
    }
    sizes
}

/// Per pixel its profile (1-based, 0 not a particle) after splitting the
/// particle pixels' 4-connected regions at their necks, and per profile
/// whether it touches the image's border or an unusable pixel.
pub fn split(
    width: usize,
    height: usize,
    valid: &[bool],
    particle: &[bool],
) -> (Vec<u32>, Vec<bool>) {
    let n = width * height;
    let distance = distance_to_binder(width, height, particle);
    let mut order: Vec<usize> = (0..n).filter(|&i| particle[i]).collect();
    // Highest first; ties by index, so the result is deterministic.
    order.sort_by(|&a, &b| distance[b].total_cmp(&distance[a]).then(a.cmp(&b)));
    let mut basin = vec![u32::MAX; n];
    let mut peak: Vec<f64> = Vec::new();
    let mut sets = DisjointSets::new(n);
    let mut roots = Vec::with_capacity(8);
    for &i in &order {
        roots.clear();
        for j in four_neighbours(i, width, height).into_iter().flatten() {
            if basin[j] != u32::MAX {
                let r = sets.find(basin[j] as usize) as u32;
                if !roots.contains(&r) {
                    roots.push(r);
                }
            }
        }
        let d = distance[i];
        let Some(&first) = roots.iter().max_by(|&&a, &&b| {
            peak[a as usize]
                .total_cmp(&peak[b as usize])
                .then(b.cmp(&a))
        }) else {
            basin[i] = peak.len() as u32;
            peak.push(d);
            continue;
        };
        for &r in &roots {
            let p = peak[r as usize];
            if r != first && (p < MIN_PEAK || d >= NECK * p) {
                // Not a particle of its own: part of the higher basin.
                sets.union(first as usize, r as usize);
                let root = sets.find(first as usize);
                peak[root] = peak[first as usize].max(p);
            }
        }
        basin[i] = sets.find(first as usize) as u32;
    }
    // Number the final basins and find which touch the frame or the mask.
    let mut id = vec![0u32; peak.len()];
    let mut touches = Vec::new();
    let mut label = vec![0u32; n];
    for i in 0..n {
        if basin[i] == u32::MAX {
            continue;
        }
        let root = sets.find(basin[i] as usize);
        if id[root] == 0 {
            touches.push(false);
            id[root] = touches.len() as u32;
        }
        label[i] = id[root];
    }
    for i in 0..n {
        if label[i] == 0 {
            continue;
        }
        let (x, y) = (i % width, i / width);
        let edge = x == 0 || y == 0 || x + 1 == width || y + 1 == height;
        let masked = four_neighbours(i, width, height)
            .into_iter()
            .flatten()
            .any(|j| !valid[j]);
        if edge || masked {
            touches[label[i] as usize - 1] = true;
        }
    }
    (label, touches)
}

/// Euclidean distance from each particle pixel to the nearest pixel that
/// is not one (outside the image counts as not), by Felzenszwalb and
/// Huttenlocher's two passes of lower envelopes of parabolas; 0 off the
/// particles. Written here: the image crate has no distance transform.
fn distance_to_binder(width: usize, height: usize, particle: &[bool]) -> Vec<f64> {
    let far = ((width + height) * (width + height)) as f64;
    // Columns, then rows, of squared distances; the frame is binder, so
    // each line is padded with a binder pixel at both ends.
    let mut squared: Vec<f64> = particle
        .iter()
        .map(|&p| if p { far } else { 0.0 })
        .collect();
    let mut line = Vec::new();
    for x in 0..width {
        line.clear();
        line.push(0.0);
        line.extend((0..height).map(|y| squared[y * width + x]));
        line.push(0.0);
        let out = envelope(&line);
        for y in 0..height {
            squared[y * width + x] = out[y + 1];
        }
    }
    for y in 0..height {
        line.clear();
        line.push(0.0);
        line.extend_from_slice(&squared[y * width..(y + 1) * width]);
        line.push(0.0);
        let out = envelope(&line);
        squared[y * width..(y + 1) * width].copy_from_slice(&out[1..width + 1]);
    }
    squared.iter().map(|s| s.sqrt()).collect()
}

/// The 1D squared distance transform of `f`: min over q of (p - q)^2 + f(q).
fn envelope(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut v = vec![0usize; n];
    let mut z = vec![0f64; n + 1];
    let mut k = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let s = |k: usize| {
            let p = v[k];
            ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2 * (q - p)) as f64
        };
        let mut sq = s(k);
        while sq <= z[k] {
            k -= 1;
            sq = s(k);
        }
        k += 1;
        v[k] = q;
        z[k] = sq;
        z[k + 1] = f64::INFINITY;
    }
    let mut out = vec![0.0; n];
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *o = (q as f64 - p as f64).powi(2) + f[p];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn discs(width: usize, height: usize, discs: &[(f64, f64, f64)]) -> Vec<bool> {
        (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f64 + 0.5, (i / width) as f64 + 0.5);
                discs.iter().any(|&(cx, cy, r)| (x - cx).hypot(y - cy) < r)
            })
            .collect()
    }

    #[test]
    fn touching_discs_come_apart_and_one_disc_stays_whole() {
        let (w, h) = (64, 40);
        let valid = vec![true; w * h];
        // Two discs of radius 8 and 6 touching, and one lone disc.
        let p = discs(
            w,
            h,
            &[(15.0, 20.0, 8.0), (28.6, 20.0, 6.0), (50.0, 20.0, 7.0)],
        );
        let (label, touches) = split(w, h, &valid, &p);
        assert_eq!(touches, vec![false; 3]);
        let at = |x: usize, y: usize| label[y * w + x];
        assert_ne!(at(15, 20), at(28, 20));
        assert!(at(15, 20) != 0 && at(28, 20) != 0 && at(50, 20) != 0);
        // No pixel lost: the split keeps the area.
        assert_eq!(
            label.iter().filter(|&&l| l != 0).count(),
            p.iter().filter(|&&x| x).count()
        );
        // An ellipse 3:1 is one profile.
        let e: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 + 0.5 - 32.0, (i / w) as f64 + 0.5 - 20.0);
                (x / 24.0).powi(2) + (y / 8.0).powi(2) < 1.0
            })
            .collect();
        let (_, touches) = split(w, h, &valid, &e);
        assert_eq!(touches.len(), 1);
    }

    #[test]
    fn the_distance_is_euclidean() {
        let (w, h) = (21, 21);
        let p: Vec<bool> = (0..w * h).map(|i| i != 10 * w + 10).collect();
        let d = distance_to_binder(w, h, &p);
        // From (13, 14) to the hole at (10, 10): 5; the frame is farther.
        assert!((d[14 * w + 13] - 5.0).abs() < 1e-9, "{}", d[14 * w + 13]);
        // Next to the frame: 1.
        assert!((d[10 * w] - 1.0).abs() < 1e-9);
    }
}
