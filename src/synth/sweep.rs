//! The sweep-painting designer (seed 002, 4.3): a solid exemplar for
//! textures that barely change along an axis (carrots, trees, a kiwi
//! without its seeds): a cross-section swept along the axis, optionally
//! displaced by band-limited noise, with a thin skin on its outer face and
//! inclusions (seeds) placed by position, orientation and scale, as the
//! thesis's user does with the mouse (Figures 4.15, 4.16).
//!
//! Axes: the section's columns and rows span the two axes other than the
//! sweep axis, in order (sweeping along z: x and y; along x: z and y;
//! along y: x and z). Swept along x or z, the section's rows are the
//! block's y, its depth (top = outer, where the skin goes), as layered
//! exemplars have it for LST types 1-b and 2-b.

use glam::{DMat3, DVec3};
use rayon::prelude::*;
use serde::Deserialize;

use super::volume::Volume;
use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use crate::rng;

/// An RGB image, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    pub fn from_rgb(img: &image::RgbImage) -> Image {
        Image {
            width: img.width() as usize,
            height: img.height() as usize,
            pixels: img.pixels().map(|p| p.0).collect(),
        }
    }

    /// Bilinear, wrapping, at continuous pixel coordinates (pixel centres
    /// at i + 0.5).
    fn sample(&self, u: f64, v: f64) -> [f64; 3] {
        let (w, h) = (self.width as f64, self.height as f64);
        let (x, y) = ((u - 0.5).rem_euclid(w), (v - 0.5).rem_euclid(h));
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (tx, ty) = (x - x0 as f64, y - y0 as f64);
        let (x1, y1) = ((x0 + 1) % self.width, (y0 + 1) % self.height);
        let p = |x: usize, y: usize| self.pixels[y * self.width + x].map(|c| c as f64);
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let top = p(x0, y0)[k] * (1.0 - tx) + p(x1, y0)[k] * tx;
            let bottom = p(x0, y1)[k] * (1.0 - tx) + p(x1, y1)[k] * tx;
            *o = top * (1.0 - ty) + bottom * ty;
        }
        out
    }
}

/// An inclusions file (`--inclusions SPEC.toml`): `[[inclusion]]` tables.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InclusionFile {
    #[serde(default, rename = "inclusion")]
    pub inclusions: Vec<InclusionSpec>,
}

/// One inclusion, in fractions of the block's side (so a file suits any
/// block size).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InclusionSpec {
    /// Centre, each coordinate in 0..1 of the block.
    pub centre: [f64; 3],
    /// An ellipsoid's semi-axes (fractions of the block) before rotation;
    /// or, with `mesh`, the size of the mesh's largest side.
    pub radii: Option<[f64; 3]>,
    /// A closed mesh (OBJ, PLY, STL, OFF; relative to the file) whose
    /// inside the inclusion fills, scaled so its bounding box's largest
    /// side is `scale` of the block.
    pub mesh: Option<String>,
    #[serde(default = "one")]
    pub scale: f64,
    /// Rotation about x, then y, then z, in degrees.
    #[serde(default)]
    pub rotation: [f64; 3],
    /// Fill colour (sRGB 0-255), or `texture`: an image tiled over the
    /// inclusion's local (x, y), one tile across its width.
    pub colour: Option<[u8; 3]>,
    pub texture: Option<String>,
}

fn one() -> f64 {
    1.0
}

/// An inclusion ready to paint.
pub struct Inclusion {
    pub centre: DVec3,
    /// World (voxel units) to local (unit ball or the mesh's frame).
    pub to_local: DMat3,
    pub shape: Shape,
    pub fill: Fill,
    /// Voxel-space half extent of its bounding box.
    pub reach: f64,
}

pub enum Shape {
    /// Inside where |local| < 1.
    Ellipsoid,
    /// Inside the mesh (centred on its bounding box, largest side 1).
    Mesh(Box<crate::tetra::winding::Winding>),
}

pub enum Fill {
    Colour([u8; 3]),
    Texture(Image),
}

#[derive(Clone, Debug)]
pub struct SweepOptions {
    /// Voxels a side.
    pub size: usize,
    /// 0 = x, 1 = y, 2 = z.
    pub axis: usize,
    /// Amplitude of the noise displacing the section, in voxels (0: a
    /// pure sweep).
    pub noise: f64,
    pub seed: u64,
}

/// Inclusions from a parsed file: each checked, its mesh or texture read
/// (paths relative to `dir`). Errors say which inclusion and what.
pub fn inclusions(
    file: &InclusionFile,
    size: usize,
    dir: &std::path::Path,
) -> Result<Vec<Inclusion>> {
    let n = size as f64;
    file.inclusions
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let bad = |msg: String| Error::invalid(format!("inclusion {}: {msg}", k + 1));
            if s.centre.iter().any(|c| !c.is_finite()) {
                return Err(bad("the centre must be finite".into()));
            }
            if !(s.scale.is_finite() && s.scale > 0.0) {
                return Err(bad(format!("scale must be positive, not {}", s.scale)));
            }
            let [rx, ry, rz] = s.rotation.map(f64::to_radians);
            let rotation = DMat3::from_rotation_z(rz)
                * DMat3::from_rotation_y(ry)
                * DMat3::from_rotation_x(rx);
            let (shape, semi) = match (&s.radii, &s.mesh) {
                (Some(r), None) => {
                    if r.iter().any(|&x| !(x.is_finite() && x > 0.0)) {
                        return Err(bad(format!("radii must be positive, not {r:?}")));
                    }
                    (Shape::Ellipsoid, DVec3::from_array(*r) * s.scale * n)
                }
                (None, Some(m)) => {
                    let path = dir.join(m);
                    let mesh = crate::mesh::io::read(&path)?;
                    let unit = unit_mesh(&mesh).map_err(|e| e.in_file(&path))?;
                    (
                        Shape::Mesh(Box::new(crate::tetra::winding::Winding::new(&unit))),
                        DVec3::splat(s.scale * n),
                    )
                }
                _ => return Err(bad("give radii (an ellipsoid) or mesh, one of them".into())),
            };
            let fill = match (&s.colour, &s.texture) {
                (Some(c), None) => Fill::Colour(*c),
                (None, Some(t)) => {
                    let path = dir.join(t);
                    Fill::Texture(Image::from_rgb(
                        &super::exemplar::read_image(&path)?.to_rgb8(),
                    ))
                }
                _ => return Err(bad("give colour or texture, one of them".into())),
            };
            let to_local = DMat3::from_diagonal(semi.recip()) * rotation.transpose();
            // How far from the centre the shape can reach: the unit ball's
            // radius, or the half diagonal of the mesh's unit box.
            let reach = semi.max_element()
                * match shape {
                    Shape::Ellipsoid => 1.0,
                    Shape::Mesh(_) => 0.5 * 3f64.sqrt(),
                };
            Ok(Inclusion {
                centre: DVec3::from_array(s.centre) * n,
                to_local,
                shape,
                fill,
                reach,
            })
        })
        .collect()
}

/// The mesh centred on its bounding box, its largest side 1.
fn unit_mesh(mesh: &TriMesh) -> Result<TriMesh> {
    let (lo, hi) = mesh
        .bounding_box()
        .ok_or_else(|| Error::invalid("the inclusion mesh is empty"))?;
    let side = (hi - lo).max_element();
    if !(side > 0.0 && side.is_finite()) {
        return Err(Error::invalid("the inclusion mesh is flat or not finite"));
    }
    let centre = (lo + hi) / 2.0;
    let mut out = mesh.clone();
    for p in &mut out.positions {
        *p = (*p - centre) / side;
    }
    Ok(out)
}

/// The swept block.
pub fn sweep(
    section: &Image,
    skin: Option<(&Image, usize)>,
    inclusions: &[Inclusion],
    opts: &SweepOptions,
) -> Result<Volume> {
    let n = opts.size;
    if !(4..=super::block::MAX_BLOCK).contains(&n) {
        return Err(Error::invalid(format!(
            "the block size must be from 4 to {} voxels, not {n}",
            super::block::MAX_BLOCK
        )));
    }
    if opts.axis > 2 {
        return Err(Error::invalid(format!(
            "axis {} is not x, y or z",
            opts.axis
        )));
    }
    // A cross-section is square; and scaling it up more than twice would
    // blur it past use.
    if section.width.abs_diff(section.height) > section.width.max(section.height) / 50
        || 2 * section.width.min(section.height) < n
    {
        return Err(Error::invalid(format!(
            "the section is {}x{}: it must be square (within 2%) and at least {} pixels a side \
             for a {n}-voxel block",
            section.width,
            section.height,
            n.div_ceil(2)
        )));
    }
    if !(opts.noise.is_finite() && opts.noise >= 0.0) {
        return Err(Error::invalid(format!(
            "the noise amplitude must be 0 or more voxels, not {}",
            opts.noise
        )));
    }
    if let Some((s, depth)) = skin
        && (depth == 0 || depth >= n || opts.axis == 1 || s.width == 0 || s.height == 0)
    {
        return Err(Error::invalid(format!(
            "the skin must be 1 to {} voxels deep, on a block swept along x or z (its outer \
             face is y = 0), not {depth} deep along {}",
            n - 1,
            ["x", "y", "z"][opts.axis]
        )));
    }
    let (u_axis, v_axis) = match opts.axis {
        0 => (2, 1),
        1 => (0, 2),
        _ => (0, 1),
    };
    let scale = [
        section.width as f64 / n as f64,
        section.height as f64 / n as f64,
    ];
    let noise = Noise::new(opts.seed, n);
    let voxels: Vec<[u8; 3]> = (0..n * n * n)
        .into_par_iter()
        .map(|v| {
            let p = [v % n, v / n % n, v / (n * n)];
            let (mut u, mut w) = (p[u_axis] as f64 + 0.5, p[v_axis] as f64 + 0.5);
            if opts.noise > 0.0 {
                let q = p.map(|c| c as f64);
                u += opts.noise * noise.at(q, 0);
                w += opts.noise * noise.at(q, 1);
            }
            let mut c = section.sample(u * scale[0], w * scale[1]);
            if let Some((s, depth)) = skin
                && p[1] < depth
            {
                // Tiled across the outer face, one tile across the block.
                let (a, b) = (p[0] as f64 + 0.5, p[2] as f64 + 0.5);
                c = s.sample(
                    a * s.width as f64 / n as f64,
                    b * s.height as f64 / n as f64,
                );
            }
            c.map(|x| x.round().clamp(0.0, 255.0) as u8)
        })
        .collect();
    let mut volume = Volume {
        size: [n; 3],
        spacing: 1.0,
        voxels,
    };
    paint(&mut volume, inclusions);
    Ok(volume)
}

/// Paint each inclusion over the voxels inside it, in file order.
fn paint(volume: &mut Volume, inclusions: &[Inclusion]) {
    let n = volume.size[0] as i64;
    for inc in inclusions {
        let lo = (inc.centre - DVec3::splat(inc.reach)).floor().as_i64vec3();
        let hi = (inc.centre + DVec3::splat(inc.reach)).ceil().as_i64vec3();
        let mut painted: Vec<(usize, [u8; 3])> = Vec::new();
        for z in lo.z.max(0)..hi.z.min(n) {
            for y in lo.y.max(0)..hi.y.min(n) {
                for x in lo.x.max(0)..hi.x.min(n) {
                    let q = DVec3::new(x as f64, y as f64, z as f64) + 0.5;
                    let local = inc.to_local * (q - inc.centre);
                    let inside = match &inc.shape {
                        Shape::Ellipsoid => local.length_squared() < 1.0,
                        Shape::Mesh(w) => w.inside(local),
                    };
                    if inside {
                        let c = match &inc.fill {
                            Fill::Colour(c) => *c,
                            Fill::Texture(t) => t
                                .sample(
                                    (local.x + 1.0) / 2.0 * t.width as f64,
                                    (local.y + 1.0) / 2.0 * t.height as f64,
                                )
                                .map(|x| x.round().clamp(0.0, 255.0) as u8),
                        };
                        painted.push((volume.index(x as usize, y as usize, z as usize), c));
                    }
                }
            }
        }
        for (i, c) in painted {
            volume.voxels[i] = c;
        }
    }
}

/// Band-limited noise that tiles the block: values on a lattice 8 voxels
/// apart, smoothly interpolated (cubic Hermite), in -1..1.
struct Noise {
    seed: u64,
    /// Lattice points a side.
    cells: usize,
    step: f64,
}

impl Noise {
    fn new(seed: u64, n: usize) -> Noise {
        let cells = (n / 8).max(1);
        Noise {
            seed,
            cells,
            step: n as f64 / cells as f64,
        }
    }

    fn lattice(&self, i: [usize; 3], channel: u64) -> f64 {
        let c = self.cells;
        2.0 * rng::unit(
            self.seed,
            &[
                (i[0] % c) as u64,
                (i[1] % c) as u64,
                (i[2] % c) as u64,
                channel,
            ],
        ) - 1.0
    }

    fn at(&self, p: [f64; 3], channel: u64) -> f64 {
        let g = p.map(|x| x / self.step);
        let i = g.map(|x| x.floor() as usize);
        let t = [0, 1, 2].map(|k| {
            let f = g[k] - i[k] as f64;
            f * f * (3.0 - 2.0 * f)
        });
        let mut out = 0.0;
        for corner in 0..8 {
            let mut w = 1.0;
            let mut at = i;
            for k in 0..3 {
                if corner >> k & 1 == 1 {
                    w *= t[k];
                    at[k] += 1;
                } else {
                    w *= 1.0 - t[k];
                }
            }
            out += w * self.lattice(at, channel);
        }
        out
    }
}

/// A kiwi-like design (seed 002, Figure 4.16), the test's and the bench's:
/// a radial section (a pale core, green flesh with radial streaks), a
/// brown skin image, and 100 black seeds in a ring round the core, 10
/// around by 10 along the axis (z), each turned to point outwards.
pub fn kiwi_example() -> (Image, Image, InclusionFile) {
    let n = 128usize;
    let section = Image {
        width: n,
        height: n,
        pixels: (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 + 0.5 - 64.0, (i / n) as f64 + 0.5 - 64.0);
                let (r, a) = ((x * x + y * y).sqrt() / 64.0, y.atan2(x));
                let streak = 0.5 + 0.5 * (a * 40.0).sin();
                if r < 0.2 {
                    [235, 235, 200]
                } else {
                    let g = (150.0 + 60.0 * streak * (1.0 - r)).min(255.0);
                    [(90.0 + 40.0 * r) as u8, g as u8, 40]
                }
            })
            .collect(),
    };
    let skin = Image {
        width: 16,
        height: 16,
        pixels: (0..256u64)
            .map(|i| {
                let h = rng::below(3, &[i], 30) as u8;
                [110 + h, 80 + h / 2, 40]
            })
            .collect(),
    };
    let inclusions = (0..100)
        .map(|k| {
            let (around, along) = ((k % 10) as f64, (k / 10) as f64);
            let a = around / 10.0 * std::f64::consts::TAU + 0.3 * along;
            let r = 0.3;
            InclusionSpec {
                centre: [0.5 + r * a.cos(), 0.5 + r * a.sin(), (along + 0.5) / 10.0],
                radii: Some([0.025, 0.012, 0.012]),
                mesh: None,
                scale: 1.0,
                rotation: [0.0, 0.0, a.to_degrees()],
                colour: Some([20, 15, 10]),
                texture: None,
            }
        })
        .collect();
    (section, skin, InclusionFile { inclusions })
}
