//! What a segmentation holds, for a user choosing what to mesh (the
//! viewer's question "which label?"): a Slicer segmentation's named
//! segments, a label map's labels, or a grey volume's range, each with
//! its voxel count.

use std::collections::BTreeMap;
use std::path::Path;

use super::{Choice, read_label_map};
use crate::error::Result;
use crate::progress::thousands;

/// Name endings of the files `read_label_map` takes.
pub const READABLE: &[&str] = &[".nii", ".nii.gz", ".nrrd", ".nhdr"];

/// Whether `path` names a segmentation (by its ending, as
/// `read_label_map` decides).
pub fn is_segmentation(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    READABLE.iter().any(|end| name.ends_with(end))
}

/// The file's name without its ending, a segmentation's double ones
/// (`.nii.gz`, `.seg.nrrd`) included: a scene's or node's name.
pub fn stem(path: &Path) -> String {
    let name = path
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let lower = name.to_ascii_lowercase();
    let end = [".seg.nrrd", ".nii.gz"]
        .into_iter()
        .find(|e| lower.ends_with(e) && lower.len() > e.len())
        .map(str::len)
        .or_else(|| lower.rfind('.').filter(|&i| i > 0).map(|i| name.len() - i))
        .unwrap_or(0);
    match &name[..name.len() - end] {
        "" => "mesh".into(),
        s => s.into(),
    }
}

/// A label map with more distinct whole values than this is taken for a
/// grey volume or a probability map stored as integers (the MNI maps hold
/// 0..255): a label map of every structure TotalSegmentator knows has 117.
pub const MAX_LABELS: usize = 128;

/// One region a user can pick, with its size.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    pub choice: Choice,
    /// For a list: "white matter (1,234 voxels)".
    pub name: String,
    pub voxels: u64,
}

/// What can be meshed from one file.
#[derive(Clone, Debug, PartialEq)]
pub struct Contents {
    pub size: [usize; 3],
    /// Named segments (a Slicer segmentation) or labels (a label map),
    /// largest first; empty for a grey volume.
    pub regions: Vec<Candidate>,
    /// The smallest and largest value (of the first layer): the range a
    /// threshold is chosen in.
    pub range: (f32, f32),
    /// The threshold offered: 0.5 on a probability map (values within
    /// 0..1, on both sides of 0.5), else Otsu's (`otsu`).
    pub threshold: f64,
}

impl Contents {
    /// What is offered first: the largest segment or label, else the
    /// threshold.
    pub fn default_choice(&self) -> Choice {
        self.regions
            .first()
            .map_or(Choice::Threshold(self.threshold), |r| r.choice.clone())
    }
}

/// Read `path` and list what can be meshed from it. Errors name the file.
pub fn contents(path: &Path) -> Result<Contents> {
    let map = read_label_map(path)?;
    let first = &map.layers[0];
    let range = first
        .values
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let mut regions: Vec<Candidate> = if map.segments.is_empty() {
        labels(&first.values)
            .into_iter()
            .map(|(label, voxels)| Candidate {
                choice: Choice::Label(label),
                name: format!("label {label} ({} voxels)", thousands(voxels as usize)),
                voxels,
            })
            .collect()
    } else {
        map.segments
            .iter()
            .map(|s| {
                let voxels = map.layers[s.layer]
                    .values
                    .iter()
                    .filter(|&&v| v as f64 == s.label as f64)
                    .count() as u64;
                Candidate {
                    choice: Choice::Segment(s.name.clone()),
                    name: format!("{} ({} voxels)", s.name, thousands(voxels as usize)),
                    voxels,
                }
            })
            .collect()
    };
    // Largest first; a stable sort keeps the file's order among equals.
    regions.sort_by_key(|r| std::cmp::Reverse(r.voxels));
    let threshold = if range.0 >= 0.0 && range.1 <= 1.0 && range.0 < 0.5 && range.1 >= 0.5 {
        0.5
    } else {
        otsu(&first.values, range)
    };
    Ok(Contents {
        size: first.size,
        regions,
        range,
        threshold,
    })
}

/// Otsu's threshold (Otsu 1979, "A threshold selection method from
/// gray-level histograms"): of 256 levels over `range`, the one that
/// splits the values into two classes of the largest between-class
/// variance; a grey volume's tissue from its background, a probability
/// map stored as integers at about its middle. Eleven lines, not worth a
/// crate.
fn otsu(values: &[f32], (lo, hi): (f32, f32)) -> f64 {
    const BINS: usize = 256;
    let (lo, width) = (lo as f64, (hi as f64 - lo as f64) / BINS as f64);
    // Also a NaN width (a range of infinities).
    if width.is_nan() || width <= 0.0 {
        return lo;
    }
    let mut histogram = [0u64; BINS];
    for &v in values {
        histogram[(((v as f64 - lo) / width) as usize).min(BINS - 1)] += 1;
    }
    let total = values.len() as f64;
    let sum: f64 = histogram
        .iter()
        .enumerate()
        .map(|(i, &n)| i as f64 * n as f64)
        .sum();
    let (mut below, mut below_sum, mut best) = (0.0, 0.0, (0.0, 0));
    for (i, &n) in histogram.iter().enumerate().take(BINS - 1) {
        below += n as f64;
        below_sum += i as f64 * n as f64;
        let above = total - below;
        if below == 0.0 || above == 0.0 {
            continue;
        }
        let gap = below_sum / below - (sum - below_sum) / above;
        let between = below * above * gap * gap;
        if between > best.0 {
            best = (between, i + 1);
        }
    }
    lo + best.1 as f64 * width
}

/// A label map's labels other than the background 0, with their voxel
/// counts; none when the values are not whole or too many to be labels.
fn labels(values: &[f32]) -> Vec<(i64, u64)> {
    let mut count: BTreeMap<i64, u64> = BTreeMap::new();
    for &v in values {
        if v.fract() != 0.0 || !v.is_finite() {
            return Vec::new();
        }
        if v != 0.0 {
            *count.entry(v as i64).or_default() += 1;
            if count.len() > MAX_LABELS {
                return Vec::new();
            }
        }
    }
    count.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segment::ScalarVolume;
    use glam::DAffine3;

    fn write(dir: &Path, size: [usize; 3], values: Vec<f32>) -> std::path::PathBuf {
        let path = dir.join("map.nii");
        let volume = ScalarVolume {
            size,
            values,
            to_world: DAffine3::IDENTITY,
        };
        std::fs::write(&path, crate::segment::nifti::to_bytes(&volume)).unwrap();
        path
    }

    #[test]
    fn a_label_map_lists_its_labels_largest_first() {
        let dir = tempfile::tempdir().unwrap();
        let mut values = vec![0.0; 64];
        values[..5].fill(2.0);
        values[10..30].fill(7.0);
        let c = contents(&write(dir.path(), [4, 4, 4], values)).unwrap();
        let listed: Vec<_> = c.regions.iter().map(|r| (&r.choice, r.voxels)).collect();
        assert_eq!(
            listed,
            [(&Choice::Label(7), 20), (&Choice::Label(2), 5)],
            "{c:?}"
        );
        assert_eq!(c.default_choice(), Choice::Label(7));
        assert_eq!(c.range, (0.0, 7.0));
    }

    #[test]
    fn a_probability_map_offers_a_threshold() {
        let dir = tempfile::tempdir().unwrap();
        let values = (0..64).map(|i| i as f32 / 63.0).collect();
        let c = contents(&write(dir.path(), [4, 4, 4], values)).unwrap();
        assert!(c.regions.is_empty(), "{c:?}");
        assert_eq!(c.default_choice(), Choice::Threshold(0.5));
        // Whole values, too many to be labels: a grey volume.
        // Whole values, too many to be labels: a grey volume, split
        // between its two modes.
        let values = (0..256)
            .map(|i| if i % 2 == 0 { 10 + i / 2 % 70 } else { 150 + i / 2 } as f32)
            .collect();
        let c = contents(&write(dir.path(), [8, 8, 4], values)).unwrap();
        assert!(c.regions.is_empty(), "{c:?}");
        let Choice::Threshold(t) = c.default_choice() else {
            panic!("{c:?}")
        };
        assert!(t > 79.0 && t <= 150.0, "{t}");
    }

    #[test]
    fn names_say_which_files_are_segmentations() {
        for yes in ["a.nii", "b.NII.GZ", "c.seg.nrrd", "d.nhdr"] {
            assert!(is_segmentation(Path::new(yes)), "{yes}");
        }
        for no in ["a.obj", "b.gz", "c.toml"] {
            assert!(!is_segmentation(Path::new(no)), "{no}");
        }
        for (path, stem_) in [
            ("/x/brain.seg.nrrd", "brain"),
            ("wm.NII.GZ", "wm"),
            ("bunny.obj", "bunny"),
            ("plain", "plain"),
            (".nii.gz", ".nii"),
        ] {
            assert_eq!(stem(Path::new(path)), stem_, "{path}");
        }
    }
}
