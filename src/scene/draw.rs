//! What a baked scene draws, in no file format: per facet, primitives
//! (vertex streams) and the materials they use. The .glb writer
//! (`gltf.rs`) and the GPU renderer (`crate::render`) both read this list,
//! so the file and the screen show the same thing.
//!
//! Layered (default): per facet
//! - its own faces, opaque, its tissue texture tiled through its texture
//!   transform (tile size, rotation, offset) and, with bump, a normal map
//!   made from the tissue's height map;
//! - its overlap ring, its overlay and its seam bands as further primitives
//!   blended over the rest (alpha per vertex, overlay opacity in the
//!   material), in the order the compositor stacks them (`LayerKind`).
//!   Their vertices lie on the surface. A file lifts each layer a hair per
//!   rank along the normals (`Primitive::lift`), so a ray tracer, which has
//!   no draw order, finds them stacked. The renderer draws them on the
//!   surface itself, in order, with a depth bias: lifted there, a layer
//!   seen at a grazing angle showed through the edge of whatever stood in
//!   front of it within the hair (a dotted dark rim round every myoma).
//!
//! Moving, turning or scaling a texture changes only its material's
//! transform, never a stream.
//!
//! Atlas: one opaque primitive per facet with its baked atlas, for engines
//! that draw no alpha layers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DVec2, DVec3};

use super::atlas::Atlas;
use super::build::{BakedFacet, BakedNode, BakedScene, colour_transform, overlay_transform};
use super::composite::Transform;
use crate::db::Finish;
use crate::error::{Error, Result};

/// How a texture repeats past its edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    Repeat,
    /// Every other copy mirrored (an overlay that does not tile).
    Mirrored,
    Clamp,
}

/// Where a texture's pixels come from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A tissue's colour or overlay image, repeating.
    Image(PathBuf),
    /// A tangent-space normal map made from a tissue's height map.
    NormalsOf(PathBuf),
    /// Pixels made in memory (an atlas, a cut's picture).
    Pixels(Arc<image::RgbaImage>),
}

/// A texture, named by a key unique within a draw list (so files share
/// it across materials).
#[derive(Clone, Debug)]
pub struct TextureRef {
    pub key: String,
    pub source: Source,
    pub wrap: Wrap,
}

impl TextureRef {
    /// The texture's pixels. Repeating textures have power-of-two sides
    /// (resampled to the nearest if not): repeat and mirrored wrap with
    /// mipmaps need them on WebGL 1 and some mobile GPUs.
    pub fn image(&self) -> Result<image::DynamicImage> {
        match &self.source {
            Source::Image(path) => {
                let img = crate::synth::exemplar::read_image(path)?;
                let (w, h) = (img.width(), img.height());
                if w.is_power_of_two() && h.is_power_of_two() {
                    return Ok(img);
                }
                let pot = |n: u32| {
                    let up = n.next_power_of_two();
                    if up - n <= n - up / 2 { up } else { up / 2 }
                };
                Ok(img.resize_exact(pot(w), pot(h), image::imageops::FilterType::Lanczos3))
            }
            Source::NormalsOf(height) => Ok(image::DynamicImage::ImageRgb8(normal_map(height)?)),
            Source::Pixels(img) => Ok(image::DynamicImage::ImageRgba8((**img).clone())),
        }
    }

    /// The texture as PNG bytes: an image file that needs no resampling
    /// as it is.
    pub fn png(&self) -> Result<Vec<u8>> {
        if let Source::Image(path) = &self.source {
            let (w, h) =
                image::image_dimensions(path).map_err(|e| Error::format(path, e.to_string()))?;
            if w.is_power_of_two() && h.is_power_of_two() {
                return std::fs::read(path).map_err(|e| Error::io(path, e));
            }
        }
        png_bytes(&self.image()?)
    }
}

pub fn png_bytes(img: &image::DynamicImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| Error::invalid(format!("cannot encode PNG: {e}")))?;
    Ok(bytes)
}

/// A tangent-space normal map from a 16-bit height map, tiling like it.
/// Relief: the height range spans a 64th of the texture's width, so the
/// normal scale (the facet's bump) reads as a strength near 1. The height
/// is first smoothed over a few pixels (a wet film rounds the relief off):
/// the raw synthesised height has one-pixel crevices whose normals, seen
/// edge on, turn the tissue's pit pattern into black outlines.
pub fn normal_map(height: &Path) -> Result<image::RgbImage> {
    let img = crate::synth::exemplar::read_image(height)?.to_luma16();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let mut z: Vec<f64> = img.pixels().map(|p| p[0] as f64 / 65535.0).collect();
    // Three periodic box blurs of radius 2: nearly a Gaussian of sigma 2,
    // wrapping as the texture tiles (image's blur clamps at the edges).
    for _ in 0..3 {
        z = box_blur_periodic(&z, w, h, 2);
    }
    let at =
        |x: i64, y: i64| z[y.rem_euclid(h as i64) as usize * w + x.rem_euclid(w as i64) as usize];
    let relief = w as f64 / 64.0;
    let mut out = image::RgbImage::new(w as u32, h as u32);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let dx = (at(x + 1, y) - at(x - 1, y)) / 2.0 * relief;
            // Green is up the image (glTF's +Y), against the row order.
            let dy_up = -(at(x, y + 1) - at(x, y - 1)) / 2.0 * relief;
            let n = DVec3::new(-dx, -dy_up, 1.0).normalize();
            out.put_pixel(
                x as u32,
                y as u32,
                image::Rgb(
                    n.to_array()
                        .map(|c| ((c * 0.5 + 0.5) * 255.0).round() as u8),
                ),
            );
        }
    }
    Ok(out)
}

/// `z` (w x h, row-major) averaged over (2r+1)^2 pixels, wrapping round.
fn box_blur_periodic(z: &[f64], w: usize, h: usize, r: i64) -> Vec<f64> {
    let n = (2 * r + 1) as f64;
    let wrap = |i: i64, len: usize| i.rem_euclid(len as i64) as usize;
    let mut rows = vec![0.0; z.len()];
    for y in 0..h {
        for x in 0..w {
            rows[y * w + x] = (-r..=r)
                .map(|d| z[y * w + wrap(x as i64 + d, w)])
                .sum::<f64>()
                / n;
        }
    }
    let mut out = vec![0.0; z.len()];
    for y in 0..h {
        for x in 0..w {
            out[y * w + x] = (-r..=r)
                .map(|d| rows[wrap(y as i64 + d, h) * w + x])
                .sum::<f64>()
                / n;
        }
    }
    out
}

/// The endoscope light's exposure: what a surface facing the scope at a
/// quarter of the view's typical depth receives (the renderer before its
/// tone curve; the .glb's spot light's intensity).
pub const SCOPE_EXPOSURE: f64 = 1.1;

/// The wet film's relief as a multiple of the tissue's: the light a wet
/// surface reflects sees every facet of its relief, the light the tissue
/// scatters back sees it softened, so a facet's `bump` is what its diffuse
/// light shows and the film (the renderer's clear coat, the .glb's
/// clearcoat normal map) shows this many times more. The renderer's film
/// reads the relief a few mip levels coarser (facet.wgsl's FILM_LEVELS:
/// the film levels the finest pits), where averaging has halved the
/// slopes; glTF has no such bias, so a .glb viewer's glints are finer.
/// At 10 the default preview glinted evenly all over the near wall (43
/// spots, where real frames have 1 to 29); at 5, twice, on 0.07% of it.
pub const FILM_RELIEF: f64 = 8.0;

/// The scope's light cone for a view `fov` degrees high and `aspect` wide
/// to high: (outer, inner) half angles in radians. It reaches a little
/// past the picture's corners and is full within the inner angle.
pub fn scope_cone(fov: f64, aspect: f64) -> (f64, f64) {
    let half_diagonal = ((fov.to_radians() / 2.0).tan() * (1.0 + aspect * aspect).sqrt()).atan();
    let outer = (half_diagonal * 1.15).min(std::f64::consts::FRAC_PI_2);
    let inner = ((outer.cos() + 1.0) / 2.0).acos();
    (outer, inner)
}

/// What a material's texture shows of its facet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The tissue (transform: `colour_transform`).
    Tissue,
    /// The overlay (transform: `overlay_transform`).
    Overlay,
    /// A baked picture, no transform.
    Baked,
}

#[derive(Clone, Debug)]
pub struct NormalMap {
    pub texture: TextureRef,
    /// Bump strength.
    pub scale: f32,
}

/// How a primitive is shaded. The normal map, if any, goes through the
/// same transform as the colour.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub colour: TextureRef,
    /// KHR_texture_transform of the texture coordinates.
    pub transform: Option<Transform>,
    /// Multiplies the texture (alpha: the overlay's opacity).
    pub factor: [f32; 4],
    pub normal: Option<NormalMap>,
    /// Alpha-blended over what is behind, else opaque.
    pub blend: bool,
    /// Drawn from both sides (glTF's doubleSided). Not for a closed
    /// organ, whose back faces are never seen (from inside its cavity, the
    /// serosa's face away): those are culled, which a software rasteriser
    /// feels.
    pub double_sided: bool,
    /// How the surface takes light (its tissue's, from the database).
    pub finish: Finish,
    /// The facet (node, facet id in the node's mesh) whose settings set
    /// the transform.
    pub facet: Option<(usize, usize)>,
    pub role: Role,
}

impl Material {
    /// An opaque material showing a picture made in memory (an atlas, a
    /// cut's picture, a flat tint), clamped at its edges.
    pub fn baked(name: String, key: String, image: image::RgbaImage) -> Material {
        Material {
            name,
            colour: TextureRef {
                key,
                source: Source::Pixels(Arc::new(image)),
                wrap: Wrap::Clamp,
            },
            transform: None,
            factor: [1.0; 4],
            normal: None,
            blend: false,
            double_sided: true,
            finish: Finish::DRY,
            facet: None,
            role: Role::Baked,
        }
    }

    /// The transform `settings` give this material (a texture moved,
    /// turned or scaled changes nothing else).
    pub fn transform_for(&self, settings: &super::file::FacetSettings) -> Option<Transform> {
        match self.role {
            Role::Tissue => Some(colour_transform(settings)),
            Role::Overlay => Some(overlay_transform(settings)),
            Role::Baked => None,
        }
    }
}

/// Vertex streams of one primitive.
#[derive(Clone, Debug, Default)]
pub struct Stream {
    pub positions: Vec<f32>,
    pub normals: Vec<f32>,
    pub uvs: Vec<f32>,
    /// RGBA per vertex (white, the blend weight in alpha), or empty.
    pub colours: Vec<f32>,
    /// With a normal map: xyz along increasing u, w the bitangent's
    /// handedness.
    pub tangents: Vec<f32>,
    pub indices: Vec<u32>,
}

impl Stream {
    pub fn vertex(&mut self, p: DVec3, n: DVec3, uv: DVec2, alpha: Option<f32>) -> u32 {
        self.positions.extend([p.x as f32, p.y as f32, p.z as f32]);
        self.normals.extend([n.x as f32, n.y as f32, n.z as f32]);
        self.uvs.extend([uv.x as f32, uv.y as f32]);
        if let Some(a) = alpha {
            self.colours.extend([1.0, 1.0, 1.0, a]);
        }
        (self.positions.len() / 3 - 1) as u32
    }

    pub fn num_vertices(&self) -> usize {
        self.positions.len() / 3
    }

    /// Per-vertex tangents for a normal map: the direction of increasing
    /// u, summed over the faces around each vertex, made perpendicular to
    /// the normal. From the untransformed coordinates, as the glTF spec has
    /// engines derive them, so the file changes in nothing but the
    /// transform when a texture moves; the price is that a rotated
    /// texture's relief is lit as if turned back by the rotation, which on
    /// isotropic tissue relief does not show.
    fn with_tangents(mut self) -> Self {
        let n = self.num_vertices();
        let p = |v: usize| {
            DVec3::new(
                self.positions[3 * v] as f64,
                self.positions[3 * v + 1] as f64,
                self.positions[3 * v + 2] as f64,
            )
        };
        let t = |v: usize| DVec2::new(self.uvs[2 * v] as f64, self.uvs[2 * v + 1] as f64);
        let mut tangent = vec![DVec3::ZERO; n];
        let mut bitangent = vec![DVec3::ZERO; n];
        for tri in self.indices.chunks(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|v| v as usize);
            let (e1, e2) = (p(b) - p(a), p(c) - p(a));
            let (d1, d2) = (t(b) - t(a), t(c) - t(a));
            let det = d1.x * d2.y - d2.x * d1.y;
            if det.abs() < 1e-300 {
                continue;
            }
            let tu = (e1 * d2.y - e2 * d1.y) / det;
            let tv = (e2 * d1.x - e1 * d2.x) / det;
            for v in [a, b, c] {
                tangent[v] += tu;
                bitangent[v] += tv;
            }
        }
        self.tangents = Vec::with_capacity(4 * n);
        for v in 0..n {
            let normal = DVec3::new(
                self.normals[3 * v] as f64,
                self.normals[3 * v + 1] as f64,
                self.normals[3 * v + 2] as f64,
            );
            let mut t = tangent[v] - normal * normal.dot(tangent[v]);
            if t.length_squared() < 1e-30 {
                t = normal.any_orthonormal_vector();
            }
            let t = t.normalize();
            let w = if normal.cross(t).dot(bitangent[v]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            self.tangents
                .extend([t.x as f32, t.y as f32, t.z as f32, w]);
        }
        self
    }
}

/// Where a blended primitive sits in the stack over a face, as the
/// compositor stacks its layers: facet by facet in scene order, and within
/// a facet its ring's texture, its overlay (over its own faces and its ring
/// alike, fading with the ring), then its seam bands' texture and overlay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    Ring,
    Overlay,
    Band,
    BandOverlay,
}

/// How many hairs off the surface a facet's layer of kind `kind` is lifted.
fn layer_rank(facet: u32, kind: LayerKind) -> u32 {
    1 + 4 * facet + kind as u32
}

/// A hair along the normal: 1e-4 of the node's size.
fn lift(node: &BakedNode) -> f64 {
    node.mesh
        .bounding_box()
        .map_or(0.0, |(lo, hi)| (hi - lo).length() * 1e-4)
}

#[derive(Clone, Debug)]
pub struct Primitive {
    pub stream: Stream,
    /// Index into `DrawList::materials`.
    pub material: usize,
    /// None for a facet's own opaque faces.
    pub layer: Option<LayerKind>,
    /// How far along its normals a file lifts this layer off the surface
    /// (object units; 0 for opaque faces).
    pub lift: f32,
}

impl Primitive {
    /// A facet's own faces: opaque, on the surface.
    pub fn opaque(stream: Stream, material: usize) -> Primitive {
        Primitive {
            stream,
            material,
            layer: None,
            lift: 0.0,
        }
    }

    /// The stream's positions lifted by `lift` along its normals.
    pub fn lifted_positions(&self) -> Vec<f32> {
        let s = &self.stream;
        s.positions
            .iter()
            .zip(&s.normals)
            .map(|(p, n)| p + n * self.lift)
            .collect()
    }
}

/// One facet's primitives.
#[derive(Clone, Debug)]
pub struct Part {
    /// "node/facet".
    pub name: String,
    pub node: usize,
    /// The facet's id in the node's mesh.
    pub facet: usize,
    pub primitives: Vec<Primitive>,
}

/// Everything a baked scene draws, in drawing order.
#[derive(Clone, Debug, Default)]
pub struct DrawList {
    pub materials: Vec<Material>,
    pub parts: Vec<Part>,
}

impl DrawList {
    /// Layered, or with `atlases` (per node, per facet) one baked texture
    /// per facet.
    pub fn of(scene: &BakedScene, atlases: Option<&[Vec<Atlas>]>) -> DrawList {
        let mut list = DrawList::default();
        for (k, node) in scene.nodes.iter().enumerate() {
            // Closed and facing out: single-sided (a file's mesh may be
            // wound inside out: that one stays double-sided).
            let single_sided =
                node.topology.boundary_loops().is_empty() && node.mesh.signed_volume() > 0.0;
            for (j, facet) in node.facets.iter().enumerate() {
                let primitives = match atlases {
                    Some(a) => {
                        let finish = scene.tissues.finish_of(&facet.settings.texture);
                        list.atlas_primitives(node, facet, &a[k][j], finish)
                    }
                    None => list.layered_primitives(scene, (k, j)),
                };
                if single_sided {
                    for p in &primitives {
                        list.materials[p.material].double_sided = false;
                    }
                }
                list.parts.push(Part {
                    name: format!("{}/{}", node.name, facet.report.facet),
                    node: k,
                    facet: facet.piece.facet as usize,
                    primitives: primitives
                        .into_iter()
                        .filter(|p| !p.stream.indices.is_empty())
                        .collect(),
                });
            }
        }
        list
    }

    fn material(&mut self, m: Material) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    fn layered_primitives(&mut self, scene: &BakedScene, (k, j): (usize, usize)) -> Vec<Primitive> {
        let node = &scene.nodes[k];
        let facet = &node.facets[j];
        let s = &facet.settings;
        let piece = &facet.piece;
        let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
        let colour = TextureRef {
            key: format!("colour:{}", s.colour_key()),
            source: Source::Image(scene.tissues.colour[&s.colour_key()].clone()),
            wrap: Wrap::Repeat,
        };
        let normal = (s.bump > 0.0).then(|| NormalMap {
            texture: TextureRef {
                key: format!("normal:{}", s.texture),
                source: Source::NormalsOf(scene.tissues.height[&s.texture].clone()),
                wrap: Wrap::Repeat,
            },
            scale: s.bump as f32,
        });
        let name = format!("{}/{}", node.name, facet.report.facet);
        // Materials name the facet by its id in the mesh, as `plain` does.
        let j = piece.facet as usize;
        let tissue = |name: String, blend: bool| Material {
            name,
            colour: colour.clone(),
            transform: Some(colour_transform(s)),
            factor: [1.0; 4],
            normal: normal.clone(),
            blend,
            double_sided: true,
            finish: scene.tissues.finish_of(&s.texture),
            facet: Some((k, j)),
            role: Role::Tissue,
        };
        let opaque = self.material(tissue(name.clone(), false));
        let blended = self.material(tissue(format!("{name} (blend)"), true));
        let eps = lift(node);
        let above = |kind| eps * layer_rank(piece.facet, kind) as f64;
        let normal_of = |v: u32| node.normals[piece.vertex_origin[v as usize] as usize];
        let corner = |f: usize, i: usize| {
            let v = piece.mesh.triangles[f][i];
            (
                piece.mesh.positions[v as usize],
                normal_of(v),
                layer.coords[layer.triangles[f][i] as usize],
                piece.alpha[v as usize],
            )
        };
        // The faces `faces`, one vertex per uv corner.
        let faces_stream = |faces: std::ops::Range<usize>, with_alpha: bool| {
            let mut stream = Stream::default();
            let mut id_of = HashMap::new();
            for f in faces {
                for i in 0..3 {
                    let id = *id_of.entry(layer.triangles[f][i]).or_insert_with(|| {
                        let (p, n, uv, alpha) = corner(f, i);
                        stream.vertex(p, n, uv, with_alpha.then_some(alpha))
                    });
                    stream.indices.push(id);
                }
            }
            stream
        };
        let all = 0..piece.mesh.num_faces();
        let own = faces_stream(0..piece.own, false);
        let ring = faces_stream(piece.own..all.end, true);
        let band_stream = || {
            let mut band = Stream::default();
            for bf in &facet.band {
                for i in 0..3 {
                    // In the ring the band fades out with the ring.
                    let (p, n, _, ring_alpha) = corner(bf.face as usize, i);
                    let id = band.vertex(p, n, bf.uv[i], Some(bf.alpha[i] * ring_alpha));
                    band.indices.push(id);
                }
            }
            band
        };
        // Tangents where the tissue's normal map is drawn.
        let relief = |stream: Stream| {
            if s.bump > 0.0 {
                stream.with_tangents()
            } else {
                stream
            }
        };
        let layer = |stream, material, kind| Primitive {
            stream,
            material,
            layer: Some(kind),
            lift: above(kind) as f32,
        };
        let mut prims = vec![
            Primitive::opaque(relief(own), opaque),
            layer(relief(ring), blended, LayerKind::Ring),
        ];
        if let Some(o) = &s.overlay {
            let m = self.material(Material {
                name: format!("{name} (overlay)"),
                colour: TextureRef {
                    key: format!("overlay:{o}"),
                    source: Source::Image(scene.tissues.overlay[o].clone()),
                    wrap: Wrap::Mirrored,
                },
                transform: Some(overlay_transform(s)),
                factor: [1.0, 1.0, 1.0, s.overlay_opacity as f32],
                normal: None,
                blend: true,
                double_sided: true,
                // The vessels lie under the tissue's own film.
                finish: scene.tissues.finish_of(&s.texture),
                facet: Some((k, j)),
                role: Role::Overlay,
            });
            // Over the own faces and the ring alike, fading with the ring.
            let over = faces_stream(all, true);
            prims.push(layer(over, m, LayerKind::Overlay));
            prims.push(layer(relief(band_stream()), blended, LayerKind::Band));
            prims.push(layer(band_stream(), m, LayerKind::BandOverlay));
        } else {
            prims.push(layer(relief(band_stream()), blended, LayerKind::Band));
        }
        prims
    }

    fn atlas_primitives(
        &mut self,
        node: &BakedNode,
        facet: &BakedFacet,
        atlas: &Atlas,
        finish: Finish,
    ) -> Vec<Primitive> {
        let name = format!("{}/{}", node.name, facet.report.facet);
        let raw = atlas
            .pixels
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        let img = image::RgbaImage::from_raw(atlas.width as u32, atlas.height as u32, raw)
            .expect("sized");
        let m = self.material(Material {
            finish,
            ..Material::baked(name.clone(), format!("atlas:{name}"), img)
        });
        let piece = &facet.piece;
        let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
        let mut own = Stream::default();
        for (f, t3) in piece.mesh.triangles.iter().enumerate().take(piece.own) {
            for (&v, &c) in t3.iter().zip(&layer.triangles[f]) {
                let uv = atlas.texcoord(layer.coords[c as usize]);
                let id = own.vertex(
                    piece.mesh.positions[v as usize],
                    node.normals[piece.vertex_origin[v as usize] as usize],
                    uv,
                    None,
                );
                own.indices.push(id);
            }
        }
        vec![Primitive::opaque(own, m)]
    }
}

/// A tint per facet for meshes not yet unwrapped, so facets can be told
/// apart (sRGB).
const FACET_TINTS: [[u8; 3]; 6] = [
    [196, 140, 132],
    [150, 168, 190],
    [176, 188, 140],
    [200, 170, 110],
    [168, 140, 186],
    [130, 180, 170],
];

impl DrawList {
    /// Meshes before unwrapping: each facet's faces in a flat tint of its
    /// own (no texture coordinates yet), `highlight` (node, facet) lighter.
    pub fn plain(meshes: &[&crate::mesh::TriMesh], highlight: Option<(usize, usize)>) -> DrawList {
        let mut list = DrawList::default();
        for (k, mesh) in meshes.iter().enumerate() {
            let normals = mesh.vertex_normals();
            let (names, of_face) = match &mesh.facets {
                Some(f) => (f.names.clone(), f.of_face.clone()),
                None => (vec!["surface".to_string()], vec![0; mesh.num_faces()]),
            };
            for (j, name) in names.iter().enumerate() {
                let tint = FACET_TINTS[j % FACET_TINTS.len()];
                let tint = if highlight == Some((k, j)) {
                    tint.map(|c| c / 2 + 128)
                } else {
                    tint
                };
                let m = list.material(Material {
                    facet: Some((k, j)),
                    ..Material::baked(
                        name.clone(),
                        format!("tint:{k}:{j}:{tint:?}"),
                        image::RgbaImage::from_pixel(
                            1,
                            1,
                            image::Rgba([tint[0], tint[1], tint[2], 255]),
                        ),
                    )
                });
                let mut stream = Stream::default();
                let mut id_of = HashMap::new();
                for (f, t) in mesh.triangles.iter().enumerate() {
                    if of_face[f] as usize != j {
                        continue;
                    }
                    for &v in t {
                        let id = *id_of.entry(v).or_insert_with(|| {
                            stream.vertex(
                                mesh.positions[v as usize],
                                normals[v as usize],
                                DVec2::ZERO,
                                None,
                            )
                        });
                        stream.indices.push(id);
                    }
                }
                if !stream.indices.is_empty() {
                    list.parts.push(Part {
                        name: name.clone(),
                        node: k,
                        facet: j,
                        primitives: vec![Primitive::opaque(stream, m)],
                    });
                }
            }
        }
        list
    }
}
