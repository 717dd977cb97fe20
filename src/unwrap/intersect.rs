//! Which triangles of a uv layout overlap: a uniform grid of cells about
//! a mean triangle wide, and the separating axis test on each pair that
//! shares a cell. Measuring a layout (`metrics`) and splitting charts that
//! fold over themselves (`overlap`) both ask it, so it sits below both.

use glam::DVec2;
use rayon::prelude::*;

/// Pairs of triangles (lower index first, sorted) whose uv triangles
/// overlap with positive area. Triangles sharing a uv corner are never
/// counted (they are neighbours in the chart; a fold between them is a
/// flip, counted separately).
pub fn overlapping_pairs(triangles: &[[u32; 3]], uv: &[DVec2]) -> Vec<[u32; 2]> {
    if triangles.is_empty() {
        return Vec::new();
    }
    let corners = |t: &[u32; 3]| t.map(|c| uv[c as usize]);
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut extent = 0.0;
    for t in triangles {
        let p = corners(t);
        let (a, b) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        lo = lo.min(a);
        hi = hi.max(b);
        extent += (b - a).max_element();
    }
    let span = (hi - lo).max_element();
    if !(span > 0.0 && span.is_finite()) {
        return Vec::new();
    }
    let eps = 1e-9 * span;
    // A uniform grid of cells about a mean triangle wide: each triangle
    // meets a few cells, each cell a few triangles.
    let cell = (extent / triangles.len() as f64).max(span / 4096.0);
    let index = |p: DVec2| (((p - lo) / cell).floor()).as_ivec2();
    // (cell, face) for every cell a face's box touches, sorted: each cell's
    // faces are then a run, in face order. Its pairs are checked cell by
    // cell in parallel; the sort below makes the result independent of the
    // thread count.
    let mut entries: Vec<((i32, i32), u32)> = Vec::with_capacity(4 * triangles.len());
    for (f, t) in triangles.iter().enumerate() {
        let p = corners(t);
        let (a, b) = (
            index(p[0].min(p[1]).min(p[2])),
            index(p[0].max(p[1]).max(p[2])),
        );
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                entries.push(((x, y), f as u32));
            }
        }
    }
    entries.par_sort_unstable();
    let mut runs = Vec::new();
    let mut start = 0;
    for k in 1..=entries.len() {
        if k == entries.len() || entries[k].0 != entries[start].0 {
            runs.push(start..k);
            start = k;
        }
    }
    let mut pairs: Vec<[u32; 2]> = runs
        .into_par_iter()
        .flat_map_iter(|run| {
            let list = &entries[run];
            let mut found = Vec::new();
            for (i, &(_, f)) in list.iter().enumerate() {
                for &(_, g) in &list[i + 1..] {
                    let (tf, tg) = (triangles[f as usize], triangles[g as usize]);
                    if tf.iter().any(|c| tg.contains(c)) {
                        continue;
                    }
                    if triangles_overlap(corners(&tf), corners(&tg), eps) {
                        found.push([f.min(g), f.max(g)]);
                    }
                }
            }
            found
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Whether two triangles share interior area (more than `eps` deep): no
/// edge of either separates them (separating axis theorem).
pub(crate) fn triangles_overlap(a: [DVec2; 3], b: [DVec2; 3], eps: f64) -> bool {
    for tri in [a, b] {
        for i in 0..3 {
            let axis = (tri[(i + 1) % 3] - tri[i]).perp();
            let len = axis.length();
            if len == 0.0 {
                continue;
            }
            let project = |t: [DVec2; 3]| {
                let d = t.map(|p| p.dot(axis) / len);
                (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
            };
            let ((a0, a1), (b0, b1)) = (project(a), project(b));
            if a1 <= b0 + eps || b1 <= a0 + eps {
                return false;
            }
        }
    }
    true
}
