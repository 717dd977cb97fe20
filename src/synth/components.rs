//! Connected components of a set of grid cells: the pieces and holes of a
//! morph's sections, the specks a mask rule drops. Written here rather than
//! taken from imageproc: a flood fill is a screenful, and imageproc would
//! bring its own image types for it.

/// One connected set of cells.
pub struct Component {
    /// Its cells, by index.
    pub cells: Vec<usize>,
    pub touches_border: bool,
}

/// Connected components of the `true` cells of a `w` x `h` grid, by flood
/// fill: 4-connected, or 8-connected with `diagonal`.
pub fn components(set: &[bool], w: usize, h: usize, diagonal: bool) -> Vec<Component> {
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if !set[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut c = Component {
            cells: Vec::new(),
            touches_border: false,
        };
        while let Some(i) = stack.pop() {
            c.cells.push(i);
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            c.touches_border |= x == 0 || y == 0 || x as usize == w - 1 || y as usize == h - 1;
            for (dx, dy) in [
                (1, 0),
                (-1, 0),
                (0, 1),
                (0, -1),
                (1, 1),
                (1, -1),
                (-1, 1),
                (-1, -1),
            ]
            .into_iter()
            .take(if diagonal { 8 } else { 4 })
            {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx as usize >= w || ny as usize >= h {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if set[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        out.push(c);
    }
    out
}

/// `set` without its components of fewer than `min_cells` cells
/// (8-connected): specks of noise rather than the structure a rule looks for.
pub fn without_specks(set: &[bool], w: usize, h: usize, min_cells: usize) -> Vec<bool> {
    let mut out = set.to_vec();
    for c in components(set, w, h, true) {
        if c.cells.len() < min_cells {
            for i in c.cells {
                out[i] = false;
            }
        }
    }
    out
}
