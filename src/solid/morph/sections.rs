//! The sections file: photographs of cuts placed as planes in the organ
//! (seed 003, 4.3). TOML, one `[[exemplar]]` table per photograph, in BSP
//! insertion order (4.1):
//!
//! ```toml
//! [[exemplar]]
//! image = "cut1.png"          # relative to this file
//! origin = [0.0, 0.0, 40.5]   # object-space top-left corner of the image
//! u = [1.0, 0.0, 0.0]         # object-space step of one pixel along a row
//! v = [0.0, 1.0, 0.0]         # object-space step of one pixel down a column
//! mask = "cut1_mask.png"      # optional: white where the photograph shows tissue
//! path = "arc"                # optional: "normal" (default) or "arc"
//! axis = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # with "arc": a point and a direction in the plane
//! ```
//!
//! `path` is how the plane sweeps through the organ to reach a point (seed
//! 003, 4.2): along its normal, or rotating about an axis in the plane (a
//! great arc, for cuts through a common axis: segments of an orange, a
//! fibroid halved twice through its stalk).
//!
//! Pixel (i, j) is centred at origin + (i + 0.5) u + (j + 0.5) v. Within
//! this module a plane point is named by its *pixel coordinates* (a, b):
//! the point origin + a u + b v, so pixel (i, j)'s centre is (i + 0.5,
//! j + 0.5).

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use serde::Deserialize;

use crate::error::{Error, Result};
use crate::synth::exemplar::read_image;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SectionsFile {
    exemplar: Vec<Entry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    image: PathBuf,
    origin: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    mask: Option<PathBuf>,
    #[serde(default)]
    path: PathKind,
    axis: Option<[[f64; 3]; 2]>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum PathKind {
    #[default]
    Normal,
    Arc,
}

/// How an exemplar plane sweeps through the organ (seed 003, 4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SweepPath {
    /// Along its normal (straight path lines).
    Normal,
    /// Rotating about the axis through `point` along unit `direction`,
    /// both in the plane (great arcs about it).
    Arc { point: DVec3, direction: DVec3 },
}

/// A photograph of a cut, placed in object space.
#[derive(Clone, Debug)]
pub struct Exemplar {
    /// The image file, for messages.
    pub image: PathBuf,
    pub width: usize,
    pub height: usize,
    /// Colours, row by row from the top left, 0..255.
    pub rgb: Vec<[f32; 3]>,
    /// Where the photograph shows tissue (`None`: everywhere).
    pub mask: Option<Vec<bool>>,
    pub origin: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    /// Unit normal, along u x v.
    pub normal: DVec3,
    /// `normal . origin`: the plane is `normal . p = offset`.
    pub offset: f64,
    /// How the plane sweeps to reach a point.
    pub path: SweepPath,
    /// The dual basis of (u, v) in the plane: `(p - origin) . du` is a.
    du: DVec3,
    dv: DVec3,
}

impl Exemplar {
    /// An exemplar from its pixels and placement. Refuses u or v of zero
    /// length or parallel, and non-finite numbers.
    pub fn new(
        image: PathBuf,
        width: usize,
        height: usize,
        rgb: Vec<[f32; 3]>,
        mask: Option<Vec<bool>>,
        [origin, u, v]: [DVec3; 3],
    ) -> Result<Exemplar> {
        if !(origin.is_finite() && u.is_finite() && v.is_finite()) {
            return Err(Error::invalid("origin, u and v must be finite"));
        }
        if u.length() == 0.0 || v.length() == 0.0 {
            return Err(Error::invalid(format!(
                "u = {u} and v = {v}: a pixel step of zero length places no image"
            )));
        }
        let n = u.cross(v);
        if n.length() <= 1e-9 * u.length() * v.length() {
            return Err(Error::invalid(format!(
                "u = {u} and v = {v} are parallel: they span no plane"
            )));
        }
        assert_eq!(rgb.len(), width * height);
        let normal = n.normalize();
        // Dual basis: du . u = 1, du . v = 0, and both lie in the plane.
        let du = v.cross(normal) / u.dot(v.cross(normal));
        let dv = normal.cross(u) / v.dot(normal.cross(u));
        Ok(Exemplar {
            image,
            width,
            height,
            rgb,
            mask,
            origin,
            u,
            v,
            normal,
            offset: normal.dot(origin),
            path: SweepPath::Normal,
            du,
            dv,
        })
    }

    /// Sweep by rotating about the axis through `point` along `direction`
    /// (seed 003's great arc); refuses an axis that does not lie in the
    /// plane.
    pub fn with_arc(mut self, point: DVec3, direction: DVec3) -> Result<Exemplar> {
        let scale = self.u.length().max(self.v.length());
        if !(point.is_finite() && direction.is_finite()) || direction.length() == 0.0 {
            return Err(Error::invalid(format!(
                "the arc's axis needs a point and a non-zero direction, not {point} and {direction}"
            )));
        }
        let direction = direction.normalize();
        if direction.dot(self.normal).abs() > 1e-6
            || self.height(point).abs() > 1e-6 * scale.max(1.0)
        {
            return Err(Error::invalid(format!(
                "the arc's axis (through {point} along {direction}) does not lie in the exemplar's plane"
            )));
        }
        self.path = SweepPath::Arc { point, direction };
        Ok(self)
    }

    /// Pixel coordinates of `p`'s projection onto the plane along its
    /// normal.
    #[inline]
    pub fn pixel_coords(&self, p: DVec3) -> DVec2 {
        let q = p - self.origin;
        DVec2::new(q.dot(self.du), q.dot(self.dv))
    }

    /// The plane point at pixel coordinates `q`.
    #[inline]
    pub fn point(&self, q: DVec2) -> DVec3 {
        self.origin + self.u * q.x + self.v * q.y
    }

    /// Signed distance of `p` from the plane, along the normal.
    #[inline]
    pub fn height(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }

    /// Whether pixel (x, y) shows tissue.
    #[inline]
    pub fn tissue(&self, x: usize, y: usize) -> bool {
        self.mask.as_ref().is_none_or(|m| m[y * self.width + x])
    }

    /// A short name for messages: "exemplar 2 (cut2.png)", 1-based.
    pub fn name(&self, index: usize) -> String {
        let file = self.image.file_name().map_or_else(
            || self.image.display().to_string(),
            |f| f.to_string_lossy().into(),
        );
        format!("exemplar {} ({file})", index + 1)
    }
}

/// Read a sections file and its photographs (and masks). Each problem is
/// one error naming the file and the exemplar.
pub fn read_sections(path: &Path) -> Result<Vec<Exemplar>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file: SectionsFile = toml::from_str(&text).map_err(|e| {
        let msg = e.message().to_string();
        match e.span() {
            Some(span) => Error::at_line(path, text[..span.start].lines().count().max(1), msg),
            None => Error::format(path, msg),
        }
    })?;
    if file.exemplar.is_empty() {
        return Err(Error::format(path, "no [[exemplar]] tables"));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    file.exemplar
        .iter()
        .enumerate()
        .map(|(k, entry)| {
            let at = |msg: String| Error::at_element(path, format!("exemplar {}", k + 1), msg);
            let image_path = dir.join(&entry.image);
            let image = read_image(&image_path)?.to_rgb8();
            let (w, h) = (image.width() as usize, image.height() as usize);
            let rgb = image.pixels().map(|p| p.0.map(f32::from)).collect();
            let mask = match &entry.mask {
                Some(m) => {
                    let mask_path = dir.join(m);
                    let grey = read_image(&mask_path)?.to_luma8();
                    if (grey.width() as usize, grey.height() as usize) != (w, h) {
                        return Err(Error::format(
                            &mask_path,
                            format!(
                                "the mask is {}x{} but its image {} is {w}x{h}",
                                grey.width(),
                                grey.height(),
                                image_path.display()
                            ),
                        ));
                    }
                    let mask: Vec<bool> = grey.pixels().map(|p| p.0[0] >= 128).collect();
                    if !mask.iter().any(|&t| t) {
                        return Err(Error::format(&mask_path, "the mask shows no tissue"));
                    }
                    Some(mask)
                }
                None => None,
            };
            let [origin, u, v] = [entry.origin, entry.u, entry.v].map(DVec3::from_array);
            let exemplar = Exemplar::new(image_path, w, h, rgb, mask, [origin, u, v]);
            let exemplar = match (entry.path, entry.axis) {
                (PathKind::Normal, None) => exemplar,
                (PathKind::Arc, Some([p, d])) => {
                    exemplar.and_then(|e| e.with_arc(DVec3::from_array(p), DVec3::from_array(d)))
                }
                (PathKind::Arc, None) => {
                    return Err(at(
                        "path = \"arc\" needs axis = [[x, y, z], [dx, dy, dz]]".into()
                    ));
                }
                (PathKind::Normal, Some(_)) => {
                    return Err(at("axis is for path = \"arc\" alone".into()));
                }
            };
            exemplar.map_err(|e| match e {
                Error::Invalid { msg, .. } => at(msg),
                e => e,
            })
        })
        .collect()
}

/// Copy a sections file and its photographs (and masks) into `dir`, the
/// images renamed `exemplar-K.EXT` (and `exemplar-K-mask.EXT`) beside a
/// rewritten `sections.toml`: a bake's output then holds everything a
/// simulator needs to morph the interior. Returns the new file's path.
pub fn copy_sections(path: &Path, dir: &Path) -> Result<PathBuf> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let file: SectionsFile = toml::from_str(&text).map_err(|e| Error::format(path, e.message()))?;
    let from = path.parent().unwrap_or(Path::new(""));
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let copy = |src: &Path, name: String| -> Result<String> {
        let ext = crate::error::extension(src);
        let name = format!("{name}.{ext}");
        let src = from.join(src);
        std::fs::copy(&src, dir.join(&name)).map_err(|e| Error::io(&src, e))?;
        Ok(name)
    };
    let mut out = String::from(
        "# Photographs of cuts placed as planes in the organ (organtex morph --help).\n",
    );
    for (k, e) in file.exemplar.iter().enumerate() {
        let image = copy(&e.image, format!("exemplar-{}", k + 1))?;
        let f = |v: [f64; 3]| format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2]);
        out += &format!(
            "\n[[exemplar]]\nimage = {image:?}\norigin = {}\nu = {}\nv = {}\n",
            f(e.origin),
            f(e.u),
            f(e.v)
        );
        if let Some(mask) = &e.mask {
            out += &format!(
                "mask = {:?}\n",
                copy(mask, format!("exemplar-{}-mask", k + 1))?
            );
        }
    }
    let target = dir.join("sections.toml");
    std::fs::write(&target, out).map_err(|e| Error::io(&target, e))?;
    Ok(target)
}
