//! Where a toroidal texture's tiles meet. A tileable synthesis is as
//! seamless whatever pixel it starts at, but where it starts is where
//! copies of it meet when tiled, and where a facet's colour grading
//! (`db::colour`: a transfer, hue, saturation, brightness) acts on both
//! sides of that meeting alike.
//!
//! The roll picks the wrap column and row whose colour jumps are lowest
//! against the interior's *in every direction of CIELAB*, not in RGB's sum
//! alone. A wrap chosen for its RGB sum is smooth in L* (which dominates
//! RGB differences) and less so in a* and b*: on the porcine colon, wrap
//! over interior jumps were 0.65 in L* against 0.81 in a*, so a grading
//! that raised a*'s weight (the transfer onto the colonic mucosa: gains
//! 1.08, 1.58, 0.76) moved the RGB seam score (`quality::seam`) from
//! 0.638 to 0.667. A wrap as smooth in every direction keeps that score
//! under any such reweighting (issue 39's "tiling intact", within 0.02).

use super::fnpts::Synthesis;
use palette::{FromColor, Lab, Srgb};

/// An sRGB colour in CIELAB (D65).
pub fn to_lab(rgb: [u8; 3]) -> [f32; 3] {
    let lab = Lab::from_color(Srgb::new(rgb[0], rgb[1], rgb[2]).into_format::<f32>());
    [lab.l, lab.a, lab.b]
}

/// Unit directions in CIELAB (each channel scaled by its mean interior
/// jump first): the three axes and every balanced mix of two or three,
/// the ways a grading may weigh and turn the channels.
const DIRECTIONS: usize = 13;

fn directions() -> [[f64; 3]; DIRECTIONS] {
    let raw: [[f64; 3]; DIRECTIONS] = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [0.0, 1.0, 1.0],
        [0.0, 1.0, -1.0],
        [1.0, 1.0, 1.0],
        [1.0, 1.0, -1.0],
        [1.0, -1.0, 1.0],
        [1.0, -1.0, -1.0],
    ];
    raw.map(|d| {
        let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        d.map(|x| x / n)
    })
}

/// The column and row to start a `w` x `h` toroidal image of CIELAB
/// `labs` at (`wrap_offset`'s criterion is the module's).
fn wrap_offset(labs: &[[f32; 3]], w: usize, h: usize) -> (usize, usize) {
    let at = |x: usize, y: usize| labs[(y % h) * w + x % w];
    let delta =
        |p: [f32; 3], q: [f32; 3]| -> [f64; 3] { std::array::from_fn(|c| (p[c] - q[c]) as f64) };
    // Each channel's mean jump between toroidal neighbours, so a direction
    // mixes channels in proportion to how much each varies.
    let mut scale = [0.0f64; 3];
    for y in 0..h {
        for x in 0..w {
            for d in [delta(at(x, y), at(x + 1, y)), delta(at(x, y), at(x, y + 1))] {
                for c in 0..3 {
                    scale[c] += d[c].abs();
                }
            }
        }
    }
    let scale = scale.map(|s| if s > 0.0 { (2 * w * h) as f64 / s } else { 0.0 });
    let dirs = directions();
    let project = |d: [f64; 3]| -> [f64; DIRECTIONS] {
        std::array::from_fn(|k| {
            (0..3)
                .map(|c| dirs[k][c] * d[c] * scale[c])
                .sum::<f64>()
                .abs()
        })
    };
    let add = |sum: &mut [f64; DIRECTIONS], j: [f64; DIRECTIONS]| {
        for k in 0..DIRECTIONS {
            sum[k] += j[k];
        }
    };
    // Jumps across a cut left of column x, and above row y.
    let column: Vec<[f64; DIRECTIONS]> = (0..w)
        .map(|x| {
            let mut sum = [0.0; DIRECTIONS];
            for y in 0..h {
                add(&mut sum, project(delta(at(x + w - 1, y), at(x, y))));
            }
            sum
        })
        .collect();
    let row: Vec<[f64; DIRECTIONS]> = (0..h)
        .map(|y| {
            let mut sum = [0.0; DIRECTIONS];
            for x in 0..w {
                add(&mut sum, project(delta(at(x, y + h - 1), at(x, y))));
            }
            sum
        })
        .collect();
    let mut total = [0.0; DIRECTIONS];
    for j in column.iter().chain(&row) {
        add(&mut total, *j);
    }
    let (wrap_pairs, inner_pairs) = ((w + h) as f64, (2 * w * h - w - h).max(1) as f64);
    // Per direction, wrap over interior mean jump (`quality::seam`'s
    // ratio); the cost is the roughest direction's ratio plus how far the
    // smoothest lies below it, so the wrap is smooth and alike in all.
    let cost = |x: usize, y: usize| -> f64 {
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for k in 0..DIRECTIONS {
            let wrap = column[x][k] + row[y][k];
            let inner = (total[k] - wrap) / inner_pairs;
            let ratio = if inner > 0.0 {
                wrap / wrap_pairs / inner
            } else {
                1.0
            };
            lo = lo.min(ratio);
            hi = hi.max(ratio);
        }
        2.0 * hi - lo
    };
    let mut best = (f64::INFINITY, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let c = cost(x, y);
            if c < best.0 {
                best = (c, x, y);
            }
        }
    }
    (best.1, best.2)
}

impl Synthesis {
    /// The texture rolled so copies of it meet where it is smoothest alike
    /// in every direction of colour (the module's criterion).
    pub fn rolled_to_smoothest_wrap(self) -> Synthesis {
        let (w, h) = (self.width, self.height);
        let labs: Vec<[f32; 3]> = self.pixels.iter().map(|&p| to_lab(p)).collect();
        let (ox, oy) = wrap_offset(&labs, w, h);
        let roll = |i: usize| ((i / w + oy) % h) * w + (i % w + ox) % w;
        Synthesis {
            width: w,
            height: h,
            pixels: (0..w * h).map(|i| self.pixels[roll(i)]).collect(),
            coords: (0..w * h).map(|i| self.coords[roll(i)]).collect(),
        }
    }
}
