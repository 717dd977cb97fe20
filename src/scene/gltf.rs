//! Writing a baked scene as glTF 2.0 binary (.glb), self-contained (PNG
//! textures in the binary chunk).
//!
//! Layered (default): one glTF node per facet, whose mesh has
//! - the facet's own faces, opaque, its tissue texture tiled through
//!   KHR_texture_transform (tile size, rotation, offset) and, with bump, a
//!   normal map made from the tissue's height map (`normalTexture.scale` is
//!   the bump strength);
//! - its overlap ring, its overlay and its seam bands as further primitives
//!   blended over the rest (alpha in COLOR_0, overlay opacity in the
//!   material), lifted off the surface along the normals, a hair per layer
//!   in the order the compositor stacks them (`LayerKind`), so they
//!   never fight each other for depth and draw in the right order.
//!
//! Moving, turning or scaling a texture changes only its transform.
//!
//! Atlas (`--atlas`): one opaque primitive per facet with its baked atlas,
//! for engines that draw no alpha layers.
//!
//! The GLB container (a 12-byte header and two padded chunks) is written
//! here; gltf-json provides and checks the JSON.

use std::collections::HashMap;
use std::path::Path;

use glam::{DVec2, DVec3};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};

use super::atlas::Atlas;
use super::build::{BakedFacet, BakedNode, BakedScene, colour_transform, overlay_transform};
use super::composite::Transform;
use crate::error::{Error, Result};

/// Builds the JSON and the binary chunk together.
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    textures: HashMap<String, json::Index<json::Texture>>,
    samplers: HashMap<&'static str, json::Index<json::texture::Sampler>>,
}

impl Builder {
    fn new() -> Builder {
        Builder {
            root: json::Root {
                asset: json::Asset {
                    generator: Some(format!("organtex {}", env!("CARGO_PKG_VERSION"))),
                    version: "2.0".into(),
                    copyright: None,
                    extensions: None,
                    extras: Default::default(),
                    min_version: None,
                },
                ..Default::default()
            },
            bin: Vec::new(),
            textures: HashMap::new(),
            samplers: HashMap::new(),
        }
    }

    fn view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: Default::default(),
            name: None,
            target: target.map(Valid),
        })
    }

    fn floats(
        &mut self,
        data: &[f32],
        kind: json::accessor::Type,
        bounds: bool,
    ) -> json::Index<json::Accessor> {
        let width = match kind {
            json::accessor::Type::Vec2 => 2,
            json::accessor::Type::Vec3 => 3,
            _ => 4,
        };
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ArrayBuffer));
        let (min, max) = if bounds {
            let mut lo = vec![f32::INFINITY; width];
            let mut hi = vec![f32::NEG_INFINITY; width];
            for chunk in data.chunks(width) {
                for i in 0..width {
                    lo[i] = lo[i].min(chunk[i]);
                    hi[i] = hi[i].max(chunk[i]);
                }
            }
            (Some(json::Value::from(lo)), Some(json::Value::from(hi)))
        } else {
            (None, None)
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(data.len() / width),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::F32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(kind),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn indices(&mut self, data: &[u32]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(json::buffer::Target::ElementArrayBuffer));
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(data.len()),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::U32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(json::accessor::Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn sampler(&mut self, kind: &'static str) -> json::Index<json::texture::Sampler> {
        if let Some(&s) = self.samplers.get(kind) {
            return s;
        }
        let wrap = match kind {
            "repeat" => json::texture::WrappingMode::Repeat,
            "mirrored" => json::texture::WrappingMode::MirroredRepeat,
            _ => json::texture::WrappingMode::ClampToEdge,
        };
        let s = self.root.push(json::texture::Sampler {
            mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
            min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
            name: None,
            wrap_s: Valid(wrap),
            wrap_t: Valid(wrap),
            extensions: None,
            extras: Default::default(),
        });
        self.samplers.insert(kind, s);
        s
    }

    /// A PNG texture, once per `key`.
    fn texture(
        &mut self,
        key: &str,
        sampler: &'static str,
        png: impl FnOnce() -> Result<Vec<u8>>,
    ) -> Result<json::Index<json::Texture>> {
        if let Some(&t) = self.textures.get(key) {
            return Ok(t);
        }
        let bytes = png()?;
        let view = self.view(&bytes, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(key.to_string()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let sampler = self.sampler(sampler);
        let t = self.root.push(json::Texture {
            name: Some(key.to_string()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: Default::default(),
        });
        self.textures.insert(key.to_string(), t);
        Ok(t)
    }

    fn finish(mut self) -> Result<Vec<u8>> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.buffers.push(json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let mut text = json::serialize::to_vec(&self.root)
            .map_err(|e| Error::invalid(format!("glTF JSON: {e}")))?;
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + self.bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend(text);
        out.extend((self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend(self.bin);
        Ok(out)
    }
}

/// KHR_texture_transform of `t`.
fn khr(t: &Transform) -> json::extensions::texture::TextureTransform {
    json::extensions::texture::TextureTransform {
        offset: json::extensions::texture::TextureTransformOffset([
            t.offset[0] as f32,
            t.offset[1] as f32,
        ]),
        rotation: json::extensions::texture::TextureTransformRotation(t.rotation as f32),
        scale: json::extensions::texture::TextureTransformScale([
            t.scale[0] as f32,
            t.scale[1] as f32,
        ]),
        // Explicit: gltf-json writes an unset override as null, which the
        // validator rejects.
        tex_coord: Some(0),
        extras: Default::default(),
    }
}

fn info(texture: json::Index<json::Texture>, transform: Option<&Transform>) -> json::texture::Info {
    json::texture::Info {
        index: texture,
        tex_coord: 0,
        extensions: transform.map(|t| json::extensions::texture::Info {
            texture_transform: Some(khr(t)),
            others: Default::default(),
        }),
        extras: Default::default(),
    }
}

fn material(
    name: String,
    colour: json::texture::Info,
    factor: [f32; 4],
    normal: Option<json::material::NormalTexture>,
    blend: bool,
) -> json::Material {
    json::Material {
        alpha_cutoff: None,
        alpha_mode: Valid(if blend {
            json::material::AlphaMode::Blend
        } else {
            json::material::AlphaMode::Opaque
        }),
        double_sided: true,
        name: Some(name),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(factor),
            base_color_texture: Some(colour),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(0.45),
            metallic_roughness_texture: None,
            extensions: None,
            extras: Default::default(),
        },
        normal_texture: normal,
        occlusion_texture: None,
        emissive_texture: None,
        emissive_factor: json::material::EmissiveFactor([0.0; 3]),
        extensions: None,
        extras: Default::default(),
    }
}

/// Vertex streams of one primitive.
#[derive(Default)]
struct Stream {
    positions: Vec<f32>,
    normals: Vec<f32>,
    uvs: Vec<f32>,
    colours: Vec<f32>,
    /// With a normal map: xyz along increasing u, w the bitangent's
    /// handedness.
    tangents: Vec<f32>,
    indices: Vec<u32>,
}

impl Stream {
    fn vertex(&mut self, p: DVec3, n: DVec3, uv: DVec2, alpha: Option<f32>) -> u32 {
        self.positions.extend([p.x as f32, p.y as f32, p.z as f32]);
        self.normals.extend([n.x as f32, n.y as f32, n.z as f32]);
        self.uvs.extend([uv.x as f32, uv.y as f32]);
        if let Some(a) = alpha {
            self.colours.extend([1.0, 1.0, 1.0, a]);
        }
        (self.positions.len() / 3 - 1) as u32
    }

    /// Per-vertex tangents for a normal map: the direction of increasing
    /// u, summed over the faces around each vertex, made perpendicular to
    /// the normal. From the untransformed coordinates, as the glTF spec has
    /// engines derive them, so the file changes in nothing but the
    /// transform when a texture moves; the price is that a rotated
    /// texture's relief is lit as if turned back by the rotation, which on
    /// isotropic tissue relief does not show.
    fn with_tangents(mut self) -> Self {
        let n = self.positions.len() / 3;
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

    fn primitive(
        &self,
        b: &mut Builder,
        material: json::Index<json::Material>,
    ) -> Option<json::mesh::Primitive> {
        if self.indices.is_empty() {
            return None;
        }
        let mut attributes = std::collections::BTreeMap::new();
        attributes.insert(
            Valid(json::mesh::Semantic::Positions),
            b.floats(&self.positions, json::accessor::Type::Vec3, true),
        );
        attributes.insert(
            Valid(json::mesh::Semantic::Normals),
            b.floats(&self.normals, json::accessor::Type::Vec3, false),
        );
        attributes.insert(
            Valid(json::mesh::Semantic::TexCoords(0)),
            b.floats(&self.uvs, json::accessor::Type::Vec2, false),
        );
        if !self.colours.is_empty() {
            attributes.insert(
                Valid(json::mesh::Semantic::Colors(0)),
                b.floats(&self.colours, json::accessor::Type::Vec4, false),
            );
        }
        if !self.tangents.is_empty() {
            attributes.insert(
                Valid(json::mesh::Semantic::Tangents),
                b.floats(&self.tangents, json::accessor::Type::Vec4, false),
            );
        }
        Some(json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(b.indices(&self.indices)),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
        })
    }
}

/// A tangent-space normal map (PNG) from a 16-bit height map, tiling like
/// it. Relief: the height range spans a 64th of the texture's width, so
/// `normalTexture.scale` (the facet's bump) reads as a strength near 1.
pub fn normal_map(height: &Path) -> Result<Vec<u8>> {
    let img = crate::synth::exemplar::read_image(height)?.to_luma16();
    let (w, h) = (img.width() as i64, img.height() as i64);
    let at = |x: i64, y: i64| {
        img.get_pixel(x.rem_euclid(w) as u32, y.rem_euclid(h) as u32)[0] as f64 / 65535.0
    };
    let relief = w as f64 / 64.0;
    let mut out = image::RgbImage::new(w as u32, h as u32);
    for y in 0..h {
        for x in 0..w {
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
    png_bytes(&image::DynamicImage::ImageRgb8(out))
}

fn png_bytes(img: &image::DynamicImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| Error::invalid(format!("cannot encode PNG: {e}")))?;
    Ok(bytes)
}

/// A repeating texture's PNG: the file as it is when its sides are powers
/// of two, else resampled to the nearest ones (repeat and mirrored wrap with
/// mipmaps need them on WebGL 1 and some mobile GPUs).
fn repeating_png(path: &Path) -> Result<Vec<u8>> {
    let img = crate::synth::exemplar::read_image(path)?;
    let (w, h) = (img.width(), img.height());
    if w.is_power_of_two() && h.is_power_of_two() {
        return std::fs::read(path).map_err(|e| Error::io(path, e));
    }
    let pot = |n: u32| {
        let up = n.next_power_of_two();
        if up - n <= n - up / 2 { up } else { up / 2 }
    };
    png_bytes(&img.resize_exact(pot(w), pot(h), image::imageops::FilterType::Lanczos3))
}

/// The .glb bytes of `scene`; with `atlases` (per node, per facet), in
/// atlas mode.
pub fn encode(scene: &BakedScene, atlases: Option<&[Vec<Atlas>]>) -> Result<Vec<u8>> {
    let mut b = Builder::new();
    let mut scene_nodes = Vec::new();
    for (k, node) in scene.nodes.iter().enumerate() {
        for (j, facet) in node.facets.iter().enumerate() {
            let primitives = match atlases {
                Some(a) => atlas_primitives(&mut b, node, facet, &a[k][j])?,
                None => layered_primitives(&mut b, scene, node, facet)?,
            };
            let mesh = b.root.push(json::Mesh {
                extensions: None,
                extras: Default::default(),
                name: Some(format!("{}/{}", node.name, facet.report.facet)),
                primitives,
                weights: None,
            });
            scene_nodes.push(b.root.push(json::Node {
                mesh: Some(mesh),
                name: Some(format!("{}/{}", node.name, facet.report.facet)),
                ..Default::default()
            }));
        }
    }
    let s = b.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(scene.spec.name.clone()),
        nodes: scene_nodes,
    });
    b.root.scene = Some(s);
    if atlases.is_none() {
        b.root.extensions_used.push("KHR_texture_transform".into());
    }
    b.finish()
}

/// Where a blended primitive sits in the stack over a face, as the
/// compositor stacks its layers: facet by facet in scene order, and within
/// a facet its ring's texture, its overlay (over its own faces and its ring
/// alike, fading with the ring), then its seam bands' texture and overlay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LayerKind {
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

fn layered_primitives(
    b: &mut Builder,
    scene: &BakedScene,
    node: &BakedNode,
    facet: &BakedFacet,
) -> Result<Vec<json::mesh::Primitive>> {
    let s = &facet.settings;
    let piece = &facet.piece;
    let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
    let colour_path = scene.tissues.colour[&s.texture].clone();
    let colour = b.texture(&format!("colour:{}", s.texture), "repeat", || {
        repeating_png(&colour_path)
    })?;
    let t = colour_transform(s);
    let normal = if s.bump > 0.0 {
        let height = scene.tissues.height[&s.texture].clone();
        let tex = b.texture(&format!("normal:{}", s.texture), "repeat", || {
            normal_map(&height)
        })?;
        let mut others = json::extensions::material::NormalTexture::default();
        others.others.insert(
            "KHR_texture_transform".into(),
            serde_json::to_value(khr(&t)).expect("serialises"),
        );
        Some(json::material::NormalTexture {
            index: tex,
            scale: s.bump as f32,
            tex_coord: 0,
            extensions: Some(others),
            extras: Default::default(),
        })
    } else {
        None
    };
    let name = format!("{}/{}", node.name, facet.report.facet);
    let opaque = b.root.push(material(
        name.clone(),
        info(colour, Some(&t)),
        [1.0; 4],
        normal.clone(),
        false,
    ));
    let blended = b.root.push(material(
        format!("{name} (blend)"),
        info(colour, Some(&t)),
        [1.0; 4],
        normal,
        true,
    ));
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
    // The faces `faces` lifted by `lift`, one vertex per uv corner.
    let faces_stream = |faces: std::ops::Range<usize>, lift: f64, with_alpha: bool| {
        let mut stream = Stream::default();
        let mut id_of = HashMap::new();
        for f in faces {
            for i in 0..3 {
                let id = *id_of.entry(layer.triangles[f][i]).or_insert_with(|| {
                    let (p, n, uv, alpha) = corner(f, i);
                    stream.vertex(p + n * lift, n, uv, with_alpha.then_some(alpha))
                });
                stream.indices.push(id);
            }
        }
        stream
    };
    let all = 0..piece.mesh.num_faces();
    let own = faces_stream(0..piece.own, 0.0, false);
    let ring = faces_stream(piece.own..all.end, above(LayerKind::Ring), true);
    let band_stream = |kind| {
        let mut band = Stream::default();
        for bf in &facet.band {
            for i in 0..3 {
                // In the ring the band fades out with the ring.
                let (p, n, _, ring_alpha) = corner(bf.face as usize, i);
                let id = band.vertex(
                    p + n * above(kind),
                    n,
                    bf.uv[i],
                    Some(bf.alpha[i] * ring_alpha),
                );
                band.indices.push(id);
            }
        }
        band
    };
    let mut prims: Vec<json::mesh::Primitive> = Vec::new();
    // Tangents where the tissue's normal map is drawn.
    let relief = |stream: Stream| {
        if s.bump > 0.0 {
            stream.with_tangents()
        } else {
            stream
        }
    };
    prims.extend(relief(own).primitive(b, opaque));
    prims.extend(relief(ring).primitive(b, blended));
    if let Some(o) = &s.overlay {
        let path = scene.tissues.overlay[o].clone();
        let tex = b.texture(&format!("overlay:{o}"), "mirrored", || repeating_png(&path))?;
        let m = b.root.push(material(
            format!("{name} (overlay)"),
            info(tex, Some(&overlay_transform(s))),
            [1.0, 1.0, 1.0, s.overlay_opacity as f32],
            None,
            true,
        ));
        // Over the own faces and the ring alike, fading with the ring.
        let over = faces_stream(all, above(LayerKind::Overlay), true);
        prims.extend(over.primitive(b, m));
        prims.extend(relief(band_stream(LayerKind::Band)).primitive(b, blended));
        prims.extend(band_stream(LayerKind::BandOverlay).primitive(b, m));
    } else {
        prims.extend(relief(band_stream(LayerKind::Band)).primitive(b, blended));
    }
    Ok(prims)
}

fn atlas_primitives(
    b: &mut Builder,
    node: &BakedNode,
    facet: &BakedFacet,
    atlas: &Atlas,
) -> Result<Vec<json::mesh::Primitive>> {
    let name = format!("{}/{}", node.name, facet.report.facet);
    let tex = b.texture(&format!("atlas:{name}"), "clamp", || {
        let raw = atlas.pixels.iter().flatten().copied().collect();
        let img =
            image::RgbImage::from_raw(atlas.size as u32, atlas.size as u32, raw).expect("sized");
        png_bytes(&image::DynamicImage::ImageRgb8(img))
    })?;
    let m = b
        .root
        .push(material(name, info(tex, None), [1.0; 4], None, false));
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
    Ok(own.primitive(b, m).into_iter().collect())
}

/// The .glb bytes of one opaque mesh named `name`, textured with `texture`
/// (clamped at its edges): per vertex a position, a normal and a uv, and
/// the triangles indexing them. For cut surfaces (`solid::cut`).
pub fn textured_mesh(
    name: &str,
    positions: &[DVec3],
    normals: &[DVec3],
    uvs: &[DVec2],
    triangles: &[[u32; 3]],
    texture: &image::DynamicImage,
) -> Result<Vec<u8>> {
    let mut b = Builder::new();
    let tex = b.texture(name, "clamp", || png_bytes(texture))?;
    let m = b.root.push(material(
        name.to_string(),
        info(tex, None),
        [1.0; 4],
        None,
        false,
    ));
    let mut stream = Stream::default();
    for ((&p, &n), &uv) in positions.iter().zip(normals).zip(uvs) {
        stream.vertex(p, n, uv, None);
    }
    stream.indices = triangles.iter().flatten().copied().collect();
    let primitives = stream.primitive(&mut b, m).into_iter().collect();
    let mesh = b.root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: Some(name.to_string()),
        primitives,
        weights: None,
    });
    let node = b.root.push(json::Node {
        mesh: Some(mesh),
        name: Some(name.to_string()),
        ..Default::default()
    });
    let scene = b.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(name.to_string()),
        nodes: vec![node],
    });
    b.root.scene = Some(scene);
    b.finish()
}
