//! A draw list on the GPU: one vertex buffer per primitive, one texture
//! per texture key (with mip levels), one uniform buffer per material.
//! Changing a texture transform rewrites that material's 64-byte uniform
//! and nothing else.

use std::collections::HashMap;

use glam::DVec3;
use wgpu::util::DeviceExt;

use super::pipelines::{Renderer, VERTEX_FLOATS};
use crate::error::Result;
use crate::scene::composite::Transform;
use crate::scene::draw::{DrawList, LayerKind, Material, Stream};
use crate::solid::Placement;
use crate::solid::lst::gpu::CutBuffers;
use crate::synth::volume::Volume;

pub(super) struct GpuPrimitive {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
    /// Every edge once, for the wireframe.
    pub edges: wgpu::Buffer,
    pub edge_count: u32,
    /// Edges with one face: chart boundaries (seams) and facet borders.
    pub seams: wgpu::Buffer,
    pub seam_count: u32,
    pub material: usize,
    pub layer: Option<LayerKind>,
}

pub(super) struct GpuMaterial {
    pub uniform: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
    pub blend: bool,
    /// Drawn from both sides; a closed organ's back faces are never seen.
    pub double_sided: bool,
}

/// A cut surface with the block that textures it.
pub struct CutMesh {
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

pub(super) struct GpuCut {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

pub(super) struct GpuBlock {
    /// Holds the block texture and its placement uniform alive.
    pub bind_group: wgpu::BindGroup,
    /// The block, also the exemplar of LST cuts.
    pub view: wgpu::TextureView,
}

pub(super) struct GpuLstCut {
    pub vertices: wgpu::Buffer,
    pub vertex_count: u32,
    /// The exemplar and the layer buffers.
    pub bind_group: wgpu::BindGroup,
}

/// A scene ready to draw.
pub struct GpuScene {
    pub(super) primitives: Vec<GpuPrimitive>,
    pub(super) materials: Vec<GpuMaterial>,
    pub(super) cut: Option<GpuCut>,
    pub(super) lst_cut: Option<GpuLstCut>,
    pub(super) block: Option<GpuBlock>,
    /// What a carving exposed (`carved`).
    pub(super) carved: super::carved::GpuCarved,
    /// Bounds of everything drawn.
    pub bounds: Option<(DVec3, DVec3)>,
}

/// The uniform of a material: the transform's 2x3 matrix in two rows,
/// the colour factor, the bump strength (0 without a normal map) and the
/// finish.
fn material_uniform(m: &Material, transform: Option<&Transform>) -> [f32; 16] {
    let t = transform.unwrap_or(&Transform::IDENTITY);
    let (s, c) = t.rotation.sin_cos();
    let [sx, sy] = t.scale;
    // uv' = offset + R (scale * uv), R = [[c, s], [-s, c]]
    // (KHR_texture_transform, as composite::Transform::apply).
    // row0.w: the texture is tiled through a transform (a tissue), not
    // laid out once (an atlas); facet.wgsl's wet film scales with the tile.
    let tiled = if transform.is_some() { 1.0 } else { 0.0 };
    let row0 = [c * sx, s * sy, t.offset[0], tiled].map(|v| v as f32);
    let row1 = [-s * sx, c * sy, t.offset[1], 0.0].map(|v| v as f32);
    let bump = m.normal.as_ref().map_or(0.0, |n| n.scale);
    let mut u = [0.0; 16];
    u[..4].copy_from_slice(&row0);
    u[4..8].copy_from_slice(&row1);
    u[8..12].copy_from_slice(&m.factor);
    u[12] = bump;
    u[13] = m.finish.roughness as f32;
    u[14] = m.finish.coat as f32;
    u[15] = m.finish.coat_roughness as f32;
    u
}

/// Per vertex, the log of the area stretch of the faces around it
/// (texture area over surface area, relative to the whole stream's): 0
/// where the flattening keeps areas.
fn area_heat(s: &Stream) -> Vec<f32> {
    let n = s.num_vertices();
    let p = |v: u32| {
        let v = v as usize;
        DVec3::new(
            s.positions[3 * v] as f64,
            s.positions[3 * v + 1] as f64,
            s.positions[3 * v + 2] as f64,
        )
    };
    let t = |v: u32| {
        let v = v as usize;
        glam::DVec2::new(s.uvs[2 * v] as f64, s.uvs[2 * v + 1] as f64)
    };
    let areas: Vec<(f64, f64)> = s
        .indices
        .chunks(3)
        .map(|f| {
            let a3 = (p(f[1]) - p(f[0])).cross(p(f[2]) - p(f[0])).length() / 2.0;
            let auv = (t(f[1]) - t(f[0])).perp_dot(t(f[2]) - t(f[0])).abs() / 2.0;
            (a3, auv)
        })
        .collect();
    let (total3, total_uv) = areas
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let norm = if total3 > 0.0 && total_uv > 0.0 {
        total_uv / total3
    } else {
        1.0
    };
    let mut sum = vec![0.0; n];
    let mut weight = vec![0.0; n];
    for (f, &(a3, auv)) in s.indices.chunks(3).zip(&areas) {
        if a3 <= 0.0 || auv <= 0.0 {
            continue;
        }
        let h = (auv / a3 / norm).ln();
        for &v in f {
            sum[v as usize] += h * a3;
            weight[v as usize] += a3;
        }
    }
    sum.iter()
        .zip(&weight)
        .map(|(s, w)| if *w > 0.0 { (s / w) as f32 } else { 0.0 })
        .collect()
}

/// Interleaved vertices of a stream (`VERTEX_FLOATS` each).
fn vertices(s: &Stream, heat: bool) -> Vec<f32> {
    let n = s.num_vertices();
    let heat = if heat { area_heat(s) } else { vec![0.0; n] };
    let mut out = Vec::with_capacity(n * VERTEX_FLOATS);
    for (v, &h) in heat.iter().enumerate() {
        out.extend_from_slice(&s.positions[3 * v..3 * v + 3]);
        out.extend_from_slice(&s.normals[3 * v..3 * v + 3]);
        out.extend_from_slice(&s.uvs[2 * v..2 * v + 2]);
        out.push(if s.colours.is_empty() {
            1.0
        } else {
            s.colours[4 * v + 3]
        });
        if s.tangents.is_empty() {
            out.extend_from_slice(&[0.0, 0.0, 0.0, 1.0]);
        } else {
            out.extend_from_slice(&s.tangents[4 * v..4 * v + 4]);
        }
        out.push(h);
    }
    out
}

/// Every edge once, and the edges with only one face, as line lists.
fn edge_lists(indices: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for f in indices.chunks(3) {
        for i in 0..3 {
            let (a, b) = (f[i], f[(i + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut edges: Vec<(u32, u32)> = count.keys().copied().collect();
    // Sorted, so the buffers are the same bytes every run.
    edges.sort_unstable();
    let all = edges.iter().flat_map(|&(a, b)| [a, b]).collect();
    let once = edges
        .iter()
        .filter(|e| count[e] == 1)
        .flat_map(|&(a, b)| [a, b])
        .collect();
    (all, once)
}

/// A vertex buffer and its index buffer.
fn mesh_buffers(
    device: &wgpu::Device,
    label: &str,
    vertices: &[f32],
    indices: &[u32],
) -> (wgpu::Buffer, wgpu::Buffer) {
    (
        buffer(
            device,
            label,
            bytemuck::cast_slice(vertices),
            wgpu::BufferUsages::VERTEX,
        ),
        buffer(
            device,
            label,
            bytemuck::cast_slice(indices),
            wgpu::BufferUsages::INDEX,
        ),
    )
}

fn buffer(
    device: &wgpu::Device,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage,
    })
}

/// An RGBA texture with its mip chain (each level half the last,
/// filtered on the CPU: wgpu has no mipmap generation of its own). A
/// picture wider or taller than the device allows starts at the first
/// level that fits (GL devices may allow only 2048).
fn texture_2d(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    img: &image::RgbaImage,
    srgb: bool,
) -> wgpu::TextureView {
    let limit = device.limits().max_texture_dimension_2d.max(1);
    let mut img = std::borrow::Cow::Borrowed(img);
    while img.width() > limit || img.height() > limit {
        let (w, h) = ((img.width() / 2).max(1), (img.height() / 2).max(1));
        img = std::borrow::Cow::Owned(image::imageops::resize(
            img.as_ref(),
            w,
            h,
            image::imageops::FilterType::Triangle,
        ));
    }
    let mut levels = vec![img.into_owned()];
    while levels
        .last()
        .is_some_and(|l| l.width() > 1 || l.height() > 1)
    {
        let l = levels.last().expect("non-empty");
        let (w, h) = ((l.width() / 2).max(1), (l.height() / 2).max(1));
        levels.push(image::imageops::resize(
            l,
            w,
            h,
            image::imageops::FilterType::Triangle,
        ));
    }
    let data: Vec<u8> = levels
        .iter()
        .flat_map(|l| l.as_raw().iter().copied())
        .collect();
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("texture"),
            size: wgpu::Extent3d {
                width: levels[0].width(),
                height: levels[0].height(),
                depth_or_array_layers: 1,
            },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: if srgb {
                wgpu::TextureFormat::Rgba8UnormSrgb
            } else {
                wgpu::TextureFormat::Rgba8Unorm
            },
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    );
    texture.create_view(&Default::default())
}

impl GpuScene {
    /// Upload `list`. Fails only if a texture cannot be read.
    pub fn new(
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        list: &DrawList,
    ) -> Result<GpuScene> {
        let mut views: HashMap<String, wgpu::TextureView> = HashMap::new();
        let mut view_of =
            |t: &crate::scene::draw::TextureRef, srgb: bool| -> Result<wgpu::TextureView> {
                if let Some(v) = views.get(&t.key) {
                    return Ok(v.clone());
                }
                let v = texture_2d(device, queue, &t.image()?.to_rgba8(), srgb);
                views.insert(t.key.clone(), v.clone());
                Ok(v)
            };
        let flat_normal = texture_2d(
            device,
            queue,
            &image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 128, 255, 255])),
            false,
        );
        let mut materials = Vec::new();
        for m in &list.materials {
            let colour = view_of(&m.colour, true)?;
            let normal = match &m.normal {
                Some(n) => view_of(&n.texture, false)?,
                None => flat_normal.clone(),
            };
            let uniform = buffer(
                device,
                "material",
                bytemuck::cast_slice(&material_uniform(m, m.transform.as_ref())),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            );
            let bind_group =
                renderer.material_bind_group(device, &uniform, &colour, m.colour.wrap, &normal);
            materials.push(GpuMaterial {
                uniform,
                bind_group,
                blend: m.blend,
                double_sided: m.double_sided,
            });
        }
        let mut primitives = Vec::new();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for part in &list.parts {
            for p in &part.primitives {
                for c in p.stream.positions.chunks(3) {
                    let v = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                let verts = vertices(&p.stream, p.layer.is_none());
                let (edges, seams) = edge_lists(&p.stream.indices);
                let idx = wgpu::BufferUsages::INDEX;
                let (vertices, indices) =
                    mesh_buffers(device, "primitive", &verts, &p.stream.indices);
                primitives.push(GpuPrimitive {
                    vertices,
                    indices,
                    index_count: p.stream.indices.len() as u32,
                    edges: buffer(device, "edges", bytemuck::cast_slice(&edges), idx),
                    edge_count: edges.len() as u32,
                    seams: buffer(device, "seams", bytemuck::cast_slice(&seams), idx),
                    seam_count: seams.len() as u32,
                    material: p.material,
                    layer: p.layer,
                });
            }
        }
        Ok(GpuScene {
            primitives,
            materials,
            cut: None,
            lst_cut: None,
            block: None,
            carved: Default::default(),
            bounds: lo.cmple(hi).all().then_some((lo, hi)),
        })
    }

    /// Set material `m`'s texture transform: one small uniform write, no
    /// work that grows with the mesh.
    pub fn set_transform(
        &self,
        queue: &wgpu::Queue,
        list: &DrawList,
        m: usize,
        transform: Option<&Transform>,
    ) {
        queue.write_buffer(
            &self.materials[m].uniform,
            0,
            bytemuck::cast_slice(&material_uniform(&list.materials[m], transform)),
        );
    }

    /// The interior block the cut surfaces sample, placed in object space.
    /// A block larger than the device's 3D textures is refused.
    pub fn set_block(
        &mut self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        volume: &Volume,
        placement: &Placement,
    ) -> Result<()> {
        let limit = device.limits().max_texture_dimension_3d as usize;
        if volume.size.iter().any(|&s| s > limit) {
            return Err(crate::Error::invalid(format!(
                "the interior block is {:?} voxels, over this GPU's 3D texture limit of {limit} a side; cuts are drawn without it",
                volume.size
            )));
        }
        let [w, h, d] = volume.size.map(|s| s as u32);
        let data: Vec<u8> = volume
            .voxels
            .iter()
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect();
        let texture = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("block"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: d,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::Rgba8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &data,
        );
        let view = texture.create_view(&Default::default());
        let placement = buffer(
            device,
            "block placement",
            bytemuck::cast_slice(&placement.uniform()),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = renderer.block_bind_group(device, &view, &placement);
        self.block = Some(GpuBlock { bind_group, view });
        Ok(())
    }

    pub fn has_block(&self) -> bool {
        self.block.is_some()
    }

    /// Triangles of the cut surfaces, block and LST.
    pub fn cut_triangles(&self) -> usize {
        self.cut.as_ref().map_or(0, |c| c.index_count as usize / 3)
            + self
                .lst_cut
                .as_ref()
                .map_or(0, |c| c.vertex_count as usize / 3)
    }

    /// Triangles of the cuts through lapped solid textures.
    pub fn lst_cut_triangles(&self) -> usize {
        self.lst_cut
            .as_ref()
            .map_or(0, |c| c.vertex_count as usize / 3)
    }

    /// Replace the cuts through lapped solid textures (None or no
    /// triangles: none drawn). Their exemplar is the interior block, so
    /// one must be set.
    pub fn set_lst_cut(
        &mut self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        cut: Option<&CutBuffers>,
    ) -> Result<()> {
        self.lst_cut = None;
        let Some(cut) = cut.filter(|c| c.vertex_count() > 0) else {
            return Ok(());
        };
        let block = self.block.as_ref().ok_or_else(|| {
            crate::Error::invalid("an LST cut needs the interior block, its exemplar, set first")
        })?;
        let limit = device.limits().max_texture_dimension_2d;
        let table = |label: &str, format: wgpu::TextureFormat, texels: &[u8]| {
            let texel = format.block_copy_size(None).expect("a plain format") as usize;
            let [w, h] = CutBuffers::rows(texels.len() / texel);
            if h > limit {
                return Err(crate::Error::invalid(format!(
                    "the LST cut's {label} need {h} rows of texels, over this GPU's 2D texture limit of {limit}"
                )));
            }
            let mut data = texels.to_vec();
            data.resize(w as usize * h as usize * texel, 0);
            let texture = device.create_texture_with_data(
                queue,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: w,
                        height: h,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                &data,
            );
            Ok(texture.create_view(&Default::default()))
        };
        let tets = table(
            "lst tets",
            wgpu::TextureFormat::Rgba32Uint,
            bytemuck::cast_slice(&cut.tets),
        )?;
        let layers = table(
            "lst layers",
            wgpu::TextureFormat::Rgba32Float,
            bytemuck::cast_slice(&cut.layers),
        )?;
        let waves = table(
            "lst waves",
            wgpu::TextureFormat::Rgba32Float,
            bytemuck::cast_slice(&cut.waves),
        )?;
        self.lst_cut = Some(GpuLstCut {
            vertices: buffer(
                device,
                "lst cut",
                bytemuck::cast_slice(&cut.vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            vertex_count: cut.vertex_count(),
            bind_group: renderer.lst_bind_group(device, &block.view, [&tets, &layers, &waves]),
        });
        Ok(())
    }

    /// What a carving exposed, to update.
    pub fn carved_mut(&mut self) -> &mut super::carved::GpuCarved {
        &mut self.carved
    }

    /// Triangles of carved faces drawn.
    pub fn carved_triangles(&self) -> usize {
        self.carved.triangles()
    }

    /// Take over `old`'s interior block and carving (a scene rebuilt
    /// keeps them).
    pub fn keep_block(&mut self, old: GpuScene) {
        self.block = old.block;
        self.carved = old.carved;
    }

    /// Replace the cut surface (None: no cut drawn).
    pub fn set_cut(&mut self, device: &wgpu::Device, cut: Option<&CutMesh>) {
        self.cut = cut.filter(|c| !c.triangles.is_empty()).map(|c| {
            let verts: Vec<f32> = c
                .positions
                .iter()
                .zip(&c.normals)
                .flat_map(|(p, n)| [p.x, p.y, p.z, n.x, n.y, n.z].map(|v| v as f32))
                .collect();
            let indices: Vec<u32> = c.triangles.iter().flatten().copied().collect();
            let (vertices, index_buffer) = mesh_buffers(device, "cut", &verts, &indices);
            GpuCut {
                vertices,
                indices: index_buffer,
                index_count: indices.len() as u32,
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_transform_matches_the_compositor() {
        let t = Transform {
            scale: [0.3, 0.7],
            rotation: 0.6,
            offset: [0.2, -0.4],
        };
        let m = Material {
            name: String::new(),
            colour: crate::scene::draw::TextureRef {
                key: String::new(),
                source: crate::scene::draw::Source::Image(Default::default()),
                wrap: crate::scene::draw::Wrap::Repeat,
            },
            transform: Some(t),
            factor: [1.0; 4],
            normal: None,
            blend: false,
            double_sided: true,
            finish: crate::db::Finish::WET,
            facet: None,
            role: crate::scene::draw::Role::Tissue,
        };
        let u = material_uniform(&m, Some(&t));
        let uv = glam::DVec2::new(1.3, -2.1);
        let want = t.apply(uv);
        let got = [
            u[0] as f64 * uv.x + u[1] as f64 * uv.y + u[2] as f64,
            u[4] as f64 * uv.x + u[5] as f64 * uv.y + u[6] as f64,
        ];
        assert!((got[0] - want.x).abs() < 1e-6 && (got[1] - want.y).abs() < 1e-6);
    }

    #[test]
    fn edges_once_and_boundary() {
        // Two triangles sharing an edge: 5 edges, 4 on the boundary.
        let (all, once) = edge_lists(&[0, 1, 2, 2, 1, 3]);
        assert_eq!(all.len(), 10);
        assert_eq!(once.len(), 8);
    }
}
