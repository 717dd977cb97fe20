//! Patient-specific organs from CT/MRI segmentations (issue 40): a label
//! map or a probability map in, a closed, manifold, consistently oriented
//! surface of one region out, in the scanner's millimetres.
//!
//! - `contents`: what a file holds to mesh (segments, labels, a grey
//!   range), for a user choosing;
//! - `handles`: handles thinner than a size cut or plugged in the voxels;
//! - `nifti`: NIfTI-1 volumes (`.nii`, `.nii.gz`) and their voxel-to-world
//!   map;
//! - `nrrd`: NRRD label maps and 3D Slicer's segmentations (`.seg.nrrd`),
//!   their segments' names;
//! - `surface`: the region's boundary by marching cubes with the topology
//!   of marching tetrahedra (`cubes`), which never makes a non-manifold
//!   vertex;
//! - `smooth`: Taubin's lambda/mu smoothing, which takes the voxel
//!   staircase away without shrinking the organ.

pub mod contents;
pub mod cubes;
pub mod fit;
pub mod handles;
pub mod nifti;
pub mod nrrd;
pub mod pieces;
pub mod smooth;
pub mod surface;

use std::path::Path;

use glam::{DAffine3, DVec3};

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::mesh::bvh::Bvh;
use crate::mesh::decimate::{Hold, decimate};
use crate::mesh::envelope::Envelope;
use crate::progress::Progress;

/// A scalar volume: one value per voxel, x fastest, and the map from voxel
/// indices (voxel centres at whole numbers) to world millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarVolume {
    pub size: [usize; 3],
    pub values: Vec<f32>,
    pub to_world: DAffine3,
}

impl ScalarVolume {
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.size[1] + y) * self.size[0] + x
    }

    /// The world volume of one voxel, mm^3.
    pub fn voxel_volume(&self) -> f64 {
        self.to_world.matrix3.determinant().abs()
    }

    /// Read a volume, by its name's ending: `.nii`, `.nii.gz`, `.nrrd` or
    /// `.nhdr` (one layer).
    pub fn read(path: &Path) -> Result<ScalarVolume> {
        let mut map = read_label_map(path)?;
        if map.layers.len() > 1 {
            return Err(Error::format(
                path,
                format!(
                    "holds {} layers (a Slicer segmentation whose segments overlap): name one \
                     with --segment ({})",
                    map.layers.len(),
                    segment_names(&map.segments)
                ),
            ));
        }
        Ok(map.layers.remove(0))
    }
}

/// A NIfTI volume (one layer, no segment names) or a NRRD label map.
pub fn read_label_map(path: &Path) -> Result<nrrd::LabelMap> {
    let name = path.to_string_lossy().to_ascii_lowercase();
    if name.ends_with(".nii") || name.ends_with(".nii.gz") {
        Ok(nrrd::LabelMap {
            layers: vec![nifti::read(path)?],
            segments: Vec::new(),
        })
    } else if name.ends_with(".nrrd") || name.ends_with(".nhdr") {
        nrrd::read(path)
    } else {
        Err(Error::format(
            path,
            "organtex reads segmentations from NIfTI-1 (.nii, .nii.gz) and NRRD (.nrrd, \
             .seg.nrrd, .nhdr) files",
        ))
    }
}

/// What to mesh, as a user names it.
#[derive(Clone, Debug, PartialEq)]
pub enum Choice {
    Label(i64),
    /// A segment of a Slicer segmentation, by name.
    Segment(String),
    Threshold(f64),
}

/// The volume and region `choice` names in the file at `path`: a segment
/// is its layer and label value. Errors name the file and list the
/// segments there are.
pub fn open(path: &Path, choice: &Choice) -> Result<(ScalarVolume, Region)> {
    match choice {
        Choice::Label(l) => Ok((ScalarVolume::read(path)?, Region::Label(*l))),
        Choice::Threshold(t) => Ok((ScalarVolume::read(path)?, Region::Threshold(*t))),
        Choice::Segment(name) => {
            let mut map = read_label_map(path)?;
            if map.segments.is_empty() {
                return Err(Error::format(
                    path,
                    format!(
                        "names no segments (segment names come from 3D Slicer's .seg.nrrd): \
                         give the label of '{name}' instead"
                    ),
                ));
            }
            let found = map
                .segments
                .iter()
                .find(|s| s.name == *name)
                .or_else(|| {
                    map.segments
                        .iter()
                        .find(|s| s.name.eq_ignore_ascii_case(name))
                })
                .cloned()
                .ok_or_else(|| {
                    Error::format(
                        path,
                        format!(
                            "has no segment '{name}' (its segments: {})",
                            segment_names(&map.segments)
                        ),
                    )
                })?;
            Ok((
                map.layers.swap_remove(found.layer),
                Region::Label(found.label),
            ))
        }
    }
}

/// The segments' names, quoted, for messages.
fn segment_names(segments: &[nrrd::Segment]) -> String {
    if segments.is_empty() {
        return "none named".into();
    }
    segments
        .iter()
        .map(|s| format!("'{}'", s.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Which voxels make the region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    /// A label map's voxels of this label.
    Label(i64),
    /// A probability map's or grey volume's voxels at or above this value.
    Threshold(f64),
}

/// Options of `mesh`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    pub region: Region,
    /// Smoothing iterations (Taubin: each a lambda and a mu step;
    /// windowed sinc: each a Chebyshev term); 0: the raw
    /// marching-cubes surface.
    pub smooth: usize,
    pub smoother: Smoother,
    /// Keep every connected piece, not only the largest (but those finer
    /// than the scan resolves: `pieces::LEAST_ISLAND`).
    pub all_components: bool,
    /// Fill the kept pieces' enclosed voids (default: each void is an
    /// inner shell of the surface, facing into it, unless finer than the
    /// scan resolves: `pieces::LEAST_VOID`).
    pub fill_voids: bool,
    /// Decimate to at most this many faces (quadric error collapses that
    /// keep the surface manifold, then tangential relaxation).
    pub faces: Option<usize>,
    /// Cut or plug the region's handles thinner than this, mm (`handles`).
    pub max_handle: Option<f64>,
    /// Decimate with every corner of the region's voxel boundary held
    /// within this many voxels of the surface (`Hold::Throughout`; at
    /// `fit::TOLERANCE`, 0.9, the surface is first drawn to them), not
    /// only each round's surface within `ENVELOPE_VOXELS`: thin crests
    /// (gyri) kept at the face budget. On the MNI white matter at 50k
    /// faces, 0.9 (where the last fit holds every point of the voxel
    /// faces and draws the surface back to them, `fit::BOTH_WAYS`) keeps
    /// the surface and the voxel faces within a voxel of each other both
    /// ways (0.99 / 0.98) but leaves it as rough as the undecimated
    /// surface; 1.4 keeps the voxel faces within 1.44 and is smoother than
    /// the default (measured in the README).
    pub within_voxels: Option<f64>,
}

/// Smoothing iterations by default (`MeshOptions::smooth`). Marching
/// cubes' edges are about a voxel long, so each umbrella step reaches
/// further than over marching tetrahedra's, for which 20 was chosen: at 10
/// the MNI white matter's decimated surface has a lower spread of mean
/// curvature (0.48 against 0.64 at 20) and lies nearer its voxels, the
/// brain's is as smooth (0.11 against 0.10; VTK's 0.14), and a ball's
/// extremes stay within half a voxel of its voxels' faces (at 20 they are
/// pulled 0.55 in).
pub const DEFAULT_SMOOTH: usize = 10;

/// How the staircase is smoothed away (`smooth`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Smoother {
    /// Taubin's lambda/mu: gentle, safe on thin sheets such as the white
    /// matter's gyri.
    #[default]
    Taubin,
    /// Windowed sinc (`sinc` in a scene), VTK's and 3D Slicer's filter: much smoother and nearer the
    /// voxels on a compact organ, but it pulls the two sides of a thin
    /// sheet through each other (degenerate faces on the white matter).
    #[serde(rename = "sinc")]
    WindowedSinc,
}

impl Smoother {
    /// Taubin's, what a scene leaves unsaid.
    pub fn is_default(&self) -> bool {
        *self == Smoother::default()
    }
}

/// Tangential relaxation rounds after decimating.
const RELAX_ROUNDS: usize = 5;
/// The decimation's envelope by default, voxels: each round keeps the
/// vertices of the surface it was given within this of its result
/// (`Hold::EachRound`). Without it the white matter's thin gyri went whole
/// at 50k faces, 6.5 voxels from the decimated surface; with a quarter
/// voxel 2.6 (and 1.2 the other way, against 2.7), at about 3 s more.
const ENVELOPE_VOXELS: f64 = 0.25;

/// What `mesh` measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MeshReport {
    /// The region's voxels.
    pub region_voxels: u64,
    /// The voxels meshed (the kept pieces, their voids if filled) and
    /// their world volume, mm^3: what `volume` should come near.
    pub voxels: u64,
    pub voxel_volume: f64,
    /// Pieces the region had (voxels joined as the surface joins them),
    /// and how many were kept.
    pub components: usize,
    pub components_kept: usize,
    /// Enclosed voids in the kept pieces (each an inner shell of the
    /// surface unless filled), and whether they were filled.
    pub voids: usize,
    pub voids_filled: bool,
    /// Of the voids, those whose shell, smoothed, enclosed under
    /// `pieces::LEAST_VOID` voxel, finer than the scan resolves: filled
    /// (counted in `voxels`).
    pub voids_unresolved: usize,
    /// Of the pieces `all_components` keeps, those under
    /// `pieces::LEAST_ISLAND` voxel as marched whose shell, smoothed,
    /// enclosed under `pieces::LEAST_VOID`: dropped (not counted in
    /// `components_kept`, nor in `voxels` unless in a void filled).
    pub islands_unresolved: usize,
    pub vertices: usize,
    pub faces: usize,
    /// The enclosed volume of what was kept, mm^3.
    pub volume: f64,
    /// The smallest angle of any face, degrees.
    pub min_angle: f64,
    /// How the surface was drawn back to the voxels (`fit`).
    pub fit: fit::Fit,
    /// What `max_handle` did, genus before and after.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub handles: Option<handles::HandleFix>,
}

impl MeshReport {
    /// One line for a person: the pieces and voids kept, the faces, the
    /// volume against the voxels', and the voxel boundary's points left
    /// farther than `fit::TOLERANCE` from the surface (the bake's output,
    /// the viewer's side panel).
    pub fn summary(&self) -> String {
        use crate::progress::thousands;
        let mut pieces = match self.components {
            1 => "its one piece".to_string(),
            n => format!("{} of {n} pieces kept", self.components_kept),
        };
        if self.islands_unresolved > 0 {
            pieces += &format!(
                " ({} dropped, finer than the scan resolves)",
                self.islands_unresolved
            );
        }
        let voids = match (self.voids, self.voids_filled) {
            (0, _) => "no enclosed void".to_string(),
            (1, true) => "its enclosed void filled".to_string(),
            (n, true) => format!("{n} enclosed voids filled"),
            (n, false) => {
                let mut kept = match n {
                    1 => "an enclosed void kept as an inner shell".to_string(),
                    n => format!("{n} enclosed voids kept as inner shells"),
                };
                if self.voids_unresolved > 0 {
                    kept += &format!(
                        " ({} of them finer than the scan resolves, filled)",
                        self.voids_unresolved
                    );
                }
                kept
            }
        };
        let farthest = self
            .fit
            .farthest
            .map_or(String::new(), |d| format!(", the farthest {d:.2}"));
        format!(
            "{pieces}, {voids}; {} faces, volume {:+.2}% of the voxels'; {} of the voxel boundary's {} points farther than {} voxel from the surface{farthest}",
            thousands(self.faces),
            100.0 * (self.volume / self.voxel_volume - 1.0),
            thousands(self.fit.far),
            thousands(self.fit.points),
            fit::TOLERANCE,
        )
    }
}

/// The surface of `region` in `volume`. `name` names the file in errors.
pub fn mesh(
    volume: &ScalarVolume,
    name: &Path,
    opts: &MeshOptions,
    progress: &dyn Progress,
) -> Result<(TriMesh, MeshReport)> {
    let selected = select(volume, name, opts.region)?;
    let region_voxels = selected.iter().filter(|&&b| b).count() as u64;
    let fixed: Vec<bool>;
    let (inside, handles): (&[bool], _) = match opts.max_handle {
        Some(mm) => {
            if !(mm.is_finite() && mm > 0.0) {
                return Err(Error::invalid(format!(
                    "the handle size {mm} mm is not a length above 0"
                )));
            }
            let spacing = volume.voxel_volume().cbrt();
            let fix;
            (fixed, fix) = handles::remove_handles(volume.size, &selected, mm, spacing, progress)?;
            (&fixed, Some(fix))
        }
        None => (&selected, None),
    };
    progress.stage("finding the region's pieces and voids", 1);
    let found = pieces::pieces(volume.size, inside, progress)?;
    let components = found.count();
    // The largest piece by voxels, with its voids (see `pieces`).
    let largest = found.largest().expect("select refuses an empty region");
    let mut kept: Vec<bool> = if opts.all_components {
        inside.to_vec()
    } else {
        found.of_voxel.iter().map(|&p| p == largest).collect()
    };
    // The other pieces kept, as islands: their voxels, each with its
    // piece, in voxel order (`pieces::shells`).
    let islands: Vec<(usize, u32)> = match opts.all_components {
        true => (found.of_voxel.iter().enumerate())
            .filter(|&(_, &p)| p != pieces::NONE && p != largest)
            .map(|(i, &p)| (i, p))
            .collect(),
        false => Vec::new(),
    };
    drop(found);
    let (void_of, voids) = pieces::numbered_voids(volume.size, &kept, progress)?;
    if opts.fill_voids {
        for (k, v) in kept.iter_mut().zip(&void_of) {
            *k |= *v != pieces::NONE;
        }
    }
    progress.advance(1);
    // One step per slab of cubes, the padding's included.
    progress.stage("extracting the surface", volume.size[2] as u64 + 1);
    // A grey volume keeps its values where the kept voxels are the ones
    // selected (the surface is interpolated there). A voxel that changed
    // sides (a dropped piece, a filled void, a handle's cut or plug) is
    // set to an infinity on the side it is now on, so the surface crosses
    // its edges half way, as a label map's (a value mirrored about the
    // level would put the two sheets round a cut a hair apart where the
    // bridge's values were near the level).
    let adjusted: Vec<f32>;
    let field = match opts.region {
        Region::Label(_) => surface::Field::Binary(&kept),
        Region::Threshold(t) if kept == selected => {
            surface::Field::Scalar(&volume.values, level(t))
        }
        Region::Threshold(t) => {
            let level = level(t);
            adjusted = volume
                .values
                .iter()
                .zip(kept.iter().zip(&selected))
                .map(|(&v, (&k, &s))| match (k, s) {
                    (true, false) => f32::INFINITY,
                    (false, true) => f32::NEG_INFINITY,
                    _ => v,
                })
                .collect();
            surface::Field::Scalar(&adjusted, level)
        }
    };
    let mut mesh = surface::march(volume.size, field, progress)?;
    // Whose each shell is, told as marched (`pieces::shells`).
    let shells = (voids > 0 && !opts.fill_voids || !islands.is_empty())
        .then(|| pieces::shells(&mesh, &void_of, &islands, volume.size));
    // Smoothing in voxel units (the grid's own isotropy), then to world.
    match opts.smoother {
        Smoother::Taubin => smooth::taubin(&mut mesh, opts.smooth, progress)?,
        Smoother::WindowedSinc => {
            smooth::windowed_sinc(&mut mesh, opts.smooth, smooth::PASS_BAND, progress)?
        }
    }
    // The voids finer than the scan resolves are filled, the islands
    // dropped (`pieces::LEAST_VOID`).
    let unresolved = shells.map_or(pieces::Unresolved::default(), |shells| {
        pieces::drop_unresolved(&mut mesh, &shells, &mut kept, (&void_of, voids), &islands)
    });
    drop((void_of, islands));
    let kept_pieces = match opts.all_components {
        true => components - unresolved.islands,
        false => 1,
    };
    let voxels = kept.iter().filter(|&&b| b).count() as u64;
    for p in &mut mesh.positions {
        *p = volume.to_world.transform_point3(*p);
    }
    // A left-handed voxel-to-world map turns the faces inside out.
    if volume.to_world.matrix3.determinant() < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
    // Decimated in world units, where the angles the decimation keeps are
    // the ones a user measures; last, drawn to the voxels, so no step
    // after it moves the surface off them again. Held within the voxels,
    // the surface is drawn to them first too, so every corner is held
    // from the start (`fit`).
    let voxel_corners = fit::Voxels {
        volume,
        inside: &kept,
    };
    let (mut held, mut fitting) = (None, fit::TO_CORNERS);
    if let Some(budget) = opts.faces.filter(|&b| b < mesh.num_faces()) {
        let voxel = volume.voxel_volume().cbrt();
        let hold;
        (hold, fitting) = match opts.within_voxels {
            Some(within) if !within.is_finite() || within < fit::TOLERANCE => {
                return Err(Error::invalid(format!(
                    "the voxel corners cannot be held within {within} voxel: below {} no \
                     surface holds the corners of a diagonal staircase (a plane across it \
                     leaves them sqrt(3)/2 away)",
                    fit::TOLERANCE
                )));
            }
            // Held within the fit's own tolerance, the corners are held
            // all along; the fit after holds every point of the voxel
            // faces, so that none is left beyond a voxel, and draws the
            // surface back where it strays from them (`fit::BOTH_WAYS`; on
            // the MNI white matter at 50k faces: 0.99 / 0.98 voxels
            // against 1.14 / 1.14 with the corners alone, 2 s more).
            Some(within) if within <= fit::TOLERANCE => {
                let (_, envelope) =
                    fit::fit(&mut mesh, &voxel_corners, None, fit::TO_CORNERS, progress)?;
                (Hold::Throughout(envelope), fit::BOTH_WAYS)
            }
            // Farther, the smoothed surface holds its corners as it is (on
            // the MNI white matter the farthest is 1.11 voxels away); any
            // farther than `within` are left to the fit after.
            Some(within) => {
                let corners = voxel_corners.corners();
                let envelope = Envelope::holding(&Bvh::over_faces(&mesh), corners, within * voxel);
                (Hold::Throughout(envelope), fit::TO_CORNERS)
            }
            None => (Hold::EachRound(ENVELOPE_VOXELS * voxel), fit::TO_CORNERS),
        };
        (mesh, held) = decimate(&mesh, budget, RELAX_ROUNDS, Some(hold), progress)
            .map_err(|e| e.in_file(name))?;
        // The fit holds the corners within its own tolerance, or (both
        // ways) makes its own envelope of every voxel-face point.
        held = match fitting.both_ways {
            true => None,
            false => held.map(|e| e.released(fit::TOLERANCE * voxel)),
        };
    }
    let (fit, _) = fit::fit(&mut mesh, &voxel_corners, held, fitting, progress)?;
    let report = MeshReport {
        region_voxels,
        voxels,
        voxel_volume: voxels as f64 * volume.voxel_volume(),
        components,
        components_kept: kept_pieces,
        voids,
        voids_filled: opts.fill_voids && voids > 0,
        voids_unresolved: unresolved.voids,
        islands_unresolved: unresolved.islands,
        vertices: mesh.num_vertices(),
        faces: mesh.num_faces(),
        volume: mesh.signed_volume(),
        min_angle: (0..mesh.num_faces())
            .map(|f| {
                let [a, b, c] = mesh.corners(f);
                crate::mesh::decimate::min_angle(a, b, c)
            })
            .fold(180.0, f64::min),
        fit,
        handles,
    };
    Ok((mesh, report))
}

/// The region's voxels, with errors naming the file: a label absent, a
/// region empty or filling the whole volume.
fn select(volume: &ScalarVolume, name: &Path, region: Region) -> Result<Vec<bool>> {
    let inside: Vec<bool> = match region {
        Region::Label(l) => volume
            .values
            .iter()
            .map(|&v| v as f64 == l as f64)
            .collect(),
        Region::Threshold(t) => {
            if !t.is_finite() {
                return Err(Error::invalid(format!("the threshold {t} is not a number")));
            }
            let level = level(t);
            volume.values.iter().map(|&v| v >= level).collect()
        }
    };
    let count = inside.iter().filter(|&&b| b).count();
    if count == 0 {
        return Err(Error::format(
            name,
            match region {
                Region::Label(l) => {
                    format!(
                        "no voxel has label {l} (labels present: {})",
                        labels(volume)
                    )
                }
                Region::Threshold(t) => {
                    let max = volume.values.iter().copied().fold(f32::MIN, f32::max);
                    format!("no voxel reaches the threshold {t} (the largest value is {max})")
                }
            },
        ));
    }
    if count == inside.len() {
        return Err(Error::format(
            name,
            "the region fills the whole volume: no boundary inside it to mesh",
        ));
    }
    Ok(inside)
}

/// The threshold as the f32 values are compared with it: the smallest f32
/// at or above `t`, so "at or above t" picks the same voxels in f64 and in
/// f32, and the pieces found are the ones the surface marches round.
fn level(t: f64) -> f32 {
    let level = t as f32;
    if (level as f64) < t {
        level.next_up()
    } else {
        level
    }
}

/// The first few distinct whole values of a label map, for an error.
fn labels(volume: &ScalarVolume) -> String {
    let mut seen = std::collections::BTreeSet::new();
    for &v in &volume.values {
        if v.fract() == 0.0 {
            seen.insert(v as i64);
        }
        if seen.len() > 12 {
            break;
        }
    }
    let list: Vec<String> = seen.iter().take(12).map(|l| l.to_string()).collect();
    if list.is_empty() {
        "none: the values are not whole numbers; a probability map takes a threshold".into()
    } else {
        list.join(", ")
    }
}

/// The world box of a region's voxels (their centres), for checks.
pub fn region_box(volume: &ScalarVolume, inside: impl Fn(f32) -> bool) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let [nx, ny, nz] = volume.size;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if inside(volume.values[volume.index(x, y, z)]) {
                    for corner in 0..8 {
                        let c = DVec3::new(
                            x as f64 + if corner & 1 != 0 { 0.5 } else { -0.5 },
                            y as f64 + if corner & 2 != 0 { 0.5 } else { -0.5 },
                            z as f64 + if corner & 4 != 0 { 0.5 } else { -0.5 },
                        );
                        let w = volume.to_world.transform_point3(c);
                        lo = lo.min(w);
                        hi = hi.max(w);
                    }
                }
            }
        }
    }
    lo.is_finite().then_some((lo, hi))
}
