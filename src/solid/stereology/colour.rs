//! Colour categories of particles (seed 001, 4.2): where particles of
//! different sizes show different colours, k-means of the profiles' mean
//! colours splits them into categories, each unfolded on its own and
//! placed together.

/// Each profile's category among `k`, by k-means of their mean colours
/// (in 0-255 RGB). Starts from the darkest profile and then, each time,
/// the profile farthest from the chosen centres (deterministic, no seed
/// needed); categories numbered from dark to light.
pub fn categories(colours: &[[f64; 3]], k: usize) -> Vec<usize> {
    let k = k.min(colours.len()).max(1);
    let dist = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>();
    let lum = |c: [f64; 3]| c[0] + c[1] + c[2];
    let darkest = (0..colours.len())
        .min_by(|&a, &b| lum(colours[a]).total_cmp(&lum(colours[b])))
        .expect("some profiles");
    let mut centres = vec![colours[darkest]];
    while centres.len() < k {
        let far = (0..colours.len())
            .max_by(|&a, &b| {
                let d = |i: usize| {
                    centres
                        .iter()
                        .map(|&c| dist(colours[i], c))
                        .fold(f64::MAX, f64::min)
                };
                d(a).total_cmp(&d(b))
            })
            .expect("some profiles");
        centres.push(colours[far]);
    }
    let nearest = |c: [f64; 3], centres: &[[f64; 3]]| {
        (0..centres.len())
            .min_by(|&a, &b| dist(c, centres[a]).total_cmp(&dist(c, centres[b])))
            .expect("some centres")
    };
    let mut of = vec![0; colours.len()];
    for _ in 0..50 {
        let next: Vec<usize> = colours.iter().map(|&c| nearest(c, &centres)).collect();
        let changed = next != of;
        of = next;
        for (j, centre) in centres.iter_mut().enumerate() {
            let members: Vec<[f64; 3]> = colours
                .iter()
                .zip(&of)
                .filter(|(_, o)| **o == j)
                .map(|(c, _)| *c)
                .collect();
            if !members.is_empty() {
                *centre = [0, 1, 2]
                    .map(|i| members.iter().map(|m| m[i]).sum::<f64>() / members.len() as f64);
            }
        }
        if !changed {
            break;
        }
    }
    // Number the categories from dark to light, so the same photographs
    // always give the same numbering.
    let mut order: Vec<usize> = (0..centres.len()).collect();
    order.sort_by(|&a, &b| lum(centres[a]).total_cmp(&lum(centres[b])));
    let mut rank = vec![0; centres.len()];
    for (r, &j) in order.iter().enumerate() {
        rank[j] = r;
    }
    of.iter().map(|&j| rank[j]).collect()
}

/// The category of a pixel of colour `c`: that of the nearest category
/// mean.
pub fn nearest(means: &[[f64; 3]], c: [u8; 3]) -> usize {
    let dist = |m: [f64; 3]| (0..3).map(|i| (m[i] - c[i] as f64).powi(2)).sum::<f64>();
    (0..means.len())
        .min_by(|&a, &b| dist(means[a]).total_cmp(&dist(means[b])))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_colours_of_profiles_fall_in_two_categories_dark_first() {
        let colours: Vec<[f64; 3]> = (0..40)
            .map(|i| {
                let j = (i % 5) as f64;
                if i % 2 == 0 {
                    [200.0 + j, 180.0, 170.0]
                } else {
                    [60.0, 40.0 + j, 90.0]
                }
            })
            .collect();
        let of = categories(&colours, 2);
        for (i, &c) in of.iter().enumerate() {
            assert_eq!(c, if i % 2 == 0 { 1 } else { 0 }, "profile {i}");
        }
        assert!(categories(&colours, 1).iter().all(|&c| c == 0));
    }
}
