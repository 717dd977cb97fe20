//! Writing a baked scene as glTF 2.0 binary (.glb), self-contained (PNG
//! textures in the binary chunk): one glTF node per facet, whose mesh has
//! the facet's primitives as `draw::DrawList` lists them (see there for the
//! layered and atlas forms). Texture transforms are KHR_texture_transform,
//! per-vertex blend weights COLOR_0's alpha, bump `normalTexture.scale`.
//!
//! The GLB container (a 12-byte header and two padded chunks) is written
//! here; gltf-json provides and checks the JSON.

use std::collections::HashMap;

use glam::{DVec2, DVec3};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};

use super::composite::Transform;
use super::draw::{DrawList, Material, Part, Primitive, Stream, TextureRef, Wrap};
use super::file::Camera;
use crate::error::{Error, Result};

/// Builds the JSON and the binary chunk together.
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
    textures: HashMap<String, json::Index<json::Texture>>,
    samplers: HashMap<Wrap, json::Index<json::texture::Sampler>>,
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

    fn sampler(&mut self, kind: Wrap) -> json::Index<json::texture::Sampler> {
        if let Some(&s) = self.samplers.get(&kind) {
            return s;
        }
        let wrap = match kind {
            Wrap::Repeat => json::texture::WrappingMode::Repeat,
            Wrap::Mirrored => json::texture::WrappingMode::MirroredRepeat,
            Wrap::Clamp => json::texture::WrappingMode::ClampToEdge,
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

    /// A PNG texture, once per key.
    fn texture(&mut self, texture: &TextureRef) -> Result<json::Index<json::Texture>> {
        let key = texture.key.as_str();
        if let Some(&t) = self.textures.get(key) {
            return Ok(t);
        }
        let bytes = texture.png()?;
        let view = self.view(&bytes, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(key.to_string()),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let sampler = self.sampler(texture.wrap);
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

/// The glTF material of `m`.
fn material(b: &mut Builder, m: &Material) -> Result<json::Index<json::Material>> {
    let colour = b.texture(&m.colour)?;
    let normal = match &m.normal {
        Some(n) => {
            let index = b.texture(&n.texture)?;
            let mut others = json::extensions::material::NormalTexture::default();
            if let Some(t) = &m.transform {
                others.others.insert(
                    "KHR_texture_transform".into(),
                    serde_json::to_value(khr(t)).expect("serialises"),
                );
            }
            Some(json::material::NormalTexture {
                index,
                scale: n.scale,
                tex_coord: 0,
                extensions: Some(others),
                extras: Default::default(),
            })
        }
        None => None,
    };
    // The film sees the same relief through the same texture info, sharper
    // (draw::FILM_RELIEF).
    let film_normal = normal.as_ref().map(|n| {
        let mut info = serde_json::to_value(n).expect("serialises");
        info["scale"] = (n.scale as f64 * super::draw::FILM_RELIEF).into();
        info
    });
    Ok(b.root.push(json::Material {
        alpha_cutoff: None,
        alpha_mode: Valid(if m.blend {
            json::material::AlphaMode::Blend
        } else {
            json::material::AlphaMode::Opaque
        }),
        double_sided: m.double_sided,
        name: Some(m.name.clone()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(m.factor),
            base_color_texture: Some(info(colour, m.transform.as_ref())),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(m.finish.roughness as f32),
            metallic_roughness_texture: None,
            extensions: None,
            extras: Default::default(),
        },
        normal_texture: normal,
        occlusion_texture: None,
        emissive_texture: None,
        emissive_factor: json::material::EmissiveFactor([0.0; 3]),
        extensions: clearcoat(&m.finish, film_normal),
        extras: Default::default(),
    }))
}

/// The wet film as KHR_materials_clearcoat, on a finish that has one, with
/// its own normal map (`film_normal`, a normalTextureInfo) where the
/// tissue has relief.
fn clearcoat(
    f: &crate::db::Finish,
    film_normal: Option<serde_json::Value>,
) -> Option<json::extensions::material::Material> {
    (f.coat > 0.0).then(|| {
        let mut coat = serde_json::json!({
            "clearcoatFactor": f.coat,
            "clearcoatRoughnessFactor": f.coat_roughness,
        });
        if let Some(n) = film_normal {
            coat["clearcoatNormalTexture"] = n;
        }
        let mut e = json::extensions::material::Material::default();
        e.others.insert("KHR_materials_clearcoat".into(), coat);
        e
    })
}

/// The glTF primitive of a non-empty stream, a layer lifted off the
/// surface by its hair (a ray tracer has no draw order to stack by).
fn primitive(
    b: &mut Builder,
    p: &Primitive,
    material: json::Index<json::Material>,
) -> json::mesh::Primitive {
    let stream = &p.stream;
    let mut attributes = std::collections::BTreeMap::new();
    attributes.insert(
        Valid(json::mesh::Semantic::Positions),
        b.floats(&p.lifted_positions(), json::accessor::Type::Vec3, true),
    );
    attributes.insert(
        Valid(json::mesh::Semantic::Normals),
        b.floats(&stream.normals, json::accessor::Type::Vec3, false),
    );
    attributes.insert(
        Valid(json::mesh::Semantic::TexCoords(0)),
        b.floats(&stream.uvs, json::accessor::Type::Vec2, false),
    );
    if !stream.colours.is_empty() {
        attributes.insert(
            Valid(json::mesh::Semantic::Colors(0)),
            b.floats(&stream.colours, json::accessor::Type::Vec4, false),
        );
    }
    if !stream.tangents.is_empty() {
        attributes.insert(
            Valid(json::mesh::Semantic::Tangents),
            b.floats(&stream.tangents, json::accessor::Type::Vec4, false),
        );
    }
    json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: Default::default(),
        indices: Some(b.indices(&stream.indices)),
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    }
}

/// A glTF node named `name` with one mesh of `primitives`.
fn node(
    b: &mut Builder,
    name: &str,
    primitives: Vec<json::mesh::Primitive>,
) -> json::Index<json::Node> {
    let mesh = b.root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: Some(name.to_string()),
        primitives,
        weights: None,
    });
    b.root.push(json::Node {
        mesh: Some(mesh),
        name: Some(name.to_string()),
        ..Default::default()
    })
}

/// The .glb bytes of `list` as scene `name`, seen from `cameras` (glTF
/// cameras, in order), the first carrying the scope's light.
pub fn encode(list: &DrawList, name: &str, cameras: &[Camera]) -> Result<Vec<u8>> {
    let mut b = Builder::new();
    let mut materials = Vec::with_capacity(list.materials.len());
    for m in &list.materials {
        materials.push(material(&mut b, m)?);
    }
    let mut nodes = Vec::new();
    for part in &list.parts {
        let prims = part
            .primitives
            .iter()
            .filter(|p| !p.stream.indices.is_empty())
            .map(|p| primitive(&mut b, p, materials[p.material]))
            .collect();
        nodes.push(node(&mut b, &part.name, prims));
    }
    for (i, c) in cameras.iter().enumerate() {
        nodes.push(camera_node(&mut b, c, i));
    }
    let s = b.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(name.to_string()),
        nodes,
    });
    b.root.scene = Some(s);
    if list.materials.iter().any(|m| m.transform.is_some()) {
        b.root.extensions_used.push("KHR_texture_transform".into());
    }
    if list.materials.iter().any(|m| m.finish.coat > 0.0) {
        b.root
            .extensions_used
            .push("KHR_materials_clearcoat".into());
    }
    if let Some(first) = cameras.first() {
        b.root.extensions_used.push("KHR_lights_punctual".into());
        let mut root = json::extensions::root::Root::default();
        root.others.insert(
            "KHR_lights_punctual".into(),
            serde_json::json!({ "lights": [scope_light(first)] }),
        );
        b.root.extensions = Some(root);
    }
    b.finish()
}

/// A scene camera as a glTF perspective camera on a node of its own,
/// turned to look down its -Z (glTF's convention, +Y up). The first also
/// holds the scope's light.
fn camera_node(b: &mut Builder, c: &Camera, i: usize) -> json::Index<json::Node> {
    let eye = DVec3::from(c.position);
    let forward = (DVec3::from(c.look_at) - eye).normalize_or(DVec3::NEG_Z);
    // +Y up unless the camera looks along it.
    let up = if forward.y.abs() > 0.99 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    let right = forward.cross(up).normalize();
    let rotation = glam::DQuat::from_mat3(&glam::DMat3::from_cols(
        right,
        right.cross(forward),
        -forward,
    ));
    let camera = b.root.push(json::Camera {
        name: Some(format!("camera {i}")),
        orthographic: None,
        perspective: Some(json::camera::Perspective {
            aspect_ratio: None,
            yfov: c.fov.to_radians() as f32,
            zfar: None,
            znear: 0.05,
            extensions: None,
            extras: Default::default(),
        }),
        type_: Valid(json::camera::Type::Perspective),
        extensions: None,
        extras: Default::default(),
    });
    let extensions = (i == 0).then(|| {
        let mut e = json::extensions::scene::Node::default();
        e.others.insert(
            "KHR_lights_punctual".into(),
            serde_json::json!({ "light": 0 }),
        );
        e
    });
    b.root.push(json::Node {
        camera: Some(camera),
        name: Some(if i == 0 {
            "scope".into()
        } else {
            format!("camera {i}")
        }),
        translation: Some(eye.as_vec3().to_array()),
        rotation: Some(json::scene::UnitQuaternion(rotation.as_quat().to_array())),
        extensions,
        ..Default::default()
    })
}

/// The scope's light as a KHR_lights_punctual spot at the camera: its
/// cone the renderer's (`draw::scope_cone`, for a 4:3 picture), its
/// intensity in candela such that a surface facing it at a quarter of the
/// view's depth gets the renderer's exposure (irradiance I / d^2, and a
/// Lambertian surface's radiance albedo E / pi).
fn scope_light(c: &Camera) -> serde_json::Value {
    let depth = (DVec3::from(c.look_at) - DVec3::from(c.position)).length();
    let (outer, inner) = super::draw::scope_cone(c.fov, 4.0 / 3.0);
    let r = depth / 4.0;
    serde_json::json!({
        "type": "spot",
        "name": "scope light",
        "color": [1.0, 0.97, 0.92],
        "intensity": std::f64::consts::PI * super::draw::SCOPE_EXPOSURE * r * r,
        "spot": { "innerConeAngle": inner, "outerConeAngle": outer },
    })
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
    let mut stream = Stream::default();
    for ((&p, &n), &uv) in positions.iter().zip(normals).zip(uvs) {
        stream.vertex(p, n, uv, None);
    }
    stream.indices = triangles.iter().flatten().copied().collect();
    let list = DrawList {
        materials: vec![Material::baked(
            name.to_string(),
            name.to_string(),
            texture.to_rgba8(),
        )],
        parts: vec![Part {
            name: name.to_string(),
            node: 0,
            facet: 0,
            primitives: vec![Primitive::opaque(stream, 0)],
        }],
    };
    encode(&list, name, &[])
}

/// The section as a .glb: its triangles facing the plane's normal, with
/// uvs into `image` (from `render_section`) as their base colour texture.
pub fn section_glb(
    section: &crate::solid::Section,
    image: &crate::solid::SectionImage,
) -> Result<Vec<u8>> {
    let uvs: Vec<DVec2> = (0..section.positions.len() as u32)
        .map(|i| image.uv(section.plane_point(i)))
        .collect();
    textured_mesh(
        "section",
        &section.positions,
        &vec![section.normal; section.positions.len()],
        &uvs,
        &section.triangles,
        &image::DynamicImage::ImageRgba8(image.image.clone()),
    )
}

/// The cut as a .glb: its triangles (corners not shared, each with its
/// chart's uv) with the texture as base colour. Triangles of zero area
/// draw nothing and have no normal: they are left out.
pub fn cut_glb(cut: &crate::mesh::TriMesh, texture: &crate::solid::CutTexture) -> Result<Vec<u8>> {
    let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
    for (t, tri) in cut.triangles.iter().enumerate() {
        let p = tri.map(|i| cut.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        if n == DVec3::ZERO {
            continue;
        }
        positions.extend(p);
        normals.extend([n; 3]);
        uvs.extend(&texture.uvs[3 * t..3 * t + 3]);
    }
    let triangles: Vec<[u32; 3]> = (0..positions.len() as u32 / 3)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    textured_mesh(
        "cut",
        &positions,
        &normals,
        &uvs,
        &triangles,
        &image::DynamicImage::ImageRgba8(texture.image.clone()),
    )
}
