//! What a carving session (`runtime::Carving`) shows on the GPU: the
//! faces it exposed, each page of its cut-texture atlas a texture that
//! the step's dirty rectangles update, and a mask of the carved space in
//! which the organ's surface is not drawn.

use std::collections::HashMap;

use glam::DVec3;
use wgpu::util::DeviceExt;

use super::pipelines::{CARVED_FLOATS, Renderer};

/// The carved space over a box: one byte a voxel (255 carved, 0 not), x
/// fastest, then y, then z; voxel (0, 0, 0)'s corner at `origin`, each
/// `voxel` units a side.
pub struct CarveMask<'a> {
    pub size: [u32; 3],
    pub origin: DVec3,
    pub voxel: f64,
    pub data: &'a [u8],
}

/// A carved face: its atlas page, corners and their texture coordinates
/// there (0..1, v down).
pub struct CarvedFace {
    pub page: u32,
    pub corners: [DVec3; 3],
    pub uvs: [[f32; 2]; 3],
}

struct Page {
    texture: wgpu::Texture,
    side: u32,
    bind_group: wgpu::BindGroup,
}

struct Mask {
    texture: wgpu::Texture,
    size: [u32; 3],
    bind_group: wgpu::BindGroup,
}

/// The carving's GPU resources, part of a `GpuScene`
/// (`GpuScene::carved_mut`).
#[derive(Default)]
pub struct GpuCarved {
    pages: HashMap<u32, Page>,
    /// Per page its faces' vertices and count.
    faces: Vec<(u32, wgpu::Buffer, u32)>,
    mask: Option<Mask>,
}

impl GpuCarved {
    /// The carve mask's bind group, if one is set.
    pub(super) fn mask(&self) -> Option<&wgpu::BindGroup> {
        self.mask.as_ref().map(|m| &m.bind_group)
    }

    /// Each page's bind group with its faces.
    pub(super) fn draws(&self) -> impl Iterator<Item = (&wgpu::BindGroup, &wgpu::Buffer, u32)> {
        self.faces.iter().filter_map(|(page, buffer, count)| {
            self.pages
                .get(page)
                .map(|p| (&p.bind_group, buffer, *count))
        })
    }
}

fn write_texels(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    rgba: &[u8],
    side: u32,
    [x, y, w, h]: [u32; 4],
) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d { x, y, z: 0 },
            aspect: wgpu::TextureAspect::All,
        },
        rgba,
        wgpu::TexelCopyBufferLayout {
            offset: 4 * (y as u64 * side as u64 + x as u64),
            bytes_per_row: Some(4 * side),
            rows_per_image: Some(side),
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
}

impl GpuCarved {
    /// Upload atlas page `page` (`side` x `side` RGBA texels): whole when
    /// it is new, else only the rectangle `dirty` (x, y, width, height).
    #[allow(clippy::too_many_arguments)]
    pub fn set_page(
        &mut self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        page: u32,
        side: u32,
        rgba: &[u8],
        dirty: [u32; 4],
    ) {
        let fresh = self.pages.get(&page).is_none_or(|p| p.side != side);
        if fresh {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("carved page"),
                size: wgpu::Extent3d {
                    width: side,
                    height: side,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba8UnormSrgb,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let bind_group =
                renderer.page_bind_group(device, &texture.create_view(&Default::default()));
            write_texels(queue, &texture, rgba, side, [0, 0, side, side]);
            self.pages.insert(
                page,
                Page {
                    texture,
                    side,
                    bind_group,
                },
            );
        } else if let Some(p) = self.pages.get(&page) {
            write_texels(queue, &p.texture, rgba, side, dirty);
        }
    }

    /// Forget a released page.
    pub fn drop_page(&mut self, page: u32) {
        self.pages.remove(&page);
    }

    /// The carved faces to draw (replacing the last set).
    pub fn set_faces(&mut self, device: &wgpu::Device, faces: &[CarvedFace]) {
        let mut by_page: HashMap<u32, Vec<f32>> = HashMap::new();
        for f in faces {
            let [a, b, c] = f.corners;
            let n = (b - a).cross(c - a).normalize_or_zero();
            let v = by_page.entry(f.page).or_default();
            for (p, uv) in f.corners.iter().zip(f.uvs) {
                v.extend([p.x, p.y, p.z, n.x, n.y, n.z].map(|x| x as f32));
                v.extend(uv);
            }
        }
        let mut pages: Vec<u32> = by_page.keys().copied().collect();
        pages.sort_unstable();
        self.faces = pages
            .into_iter()
            .map(|page| {
                let v = &by_page[&page];
                let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("carved faces"),
                    contents: bytemuck::cast_slice(v),
                    usage: wgpu::BufferUsages::VERTEX,
                });
                (page, buffer, (v.len() / CARVED_FLOATS) as u32)
            })
            .collect();
    }

    /// Triangles of carved faces drawn.
    pub fn triangles(&self) -> usize {
        self.faces.iter().map(|f| f.2 as usize / 3).sum()
    }

    /// The carved space (None: nothing carved). Uploads the whole mask when
    /// it is new or its size changed, else only the voxels of `region`
    /// (low and high corner, inclusive).
    pub fn set_mask(
        &mut self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mask: Option<&CarveMask>,
        region: Option<([u32; 3], [u32; 3])>,
    ) {
        let Some(m) = mask else {
            self.mask = None;
            return;
        };
        let fresh = self.mask.as_ref().is_none_or(|old| old.size != m.size);
        if fresh {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("carve mask"),
                size: wgpu::Extent3d {
                    width: m.size[0],
                    height: m.size[1],
                    depth_or_array_layers: m.size[2],
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let o = m.origin.as_vec3();
            let bind_group = renderer.carve_mask_bind_group(
                device,
                &texture.create_view(&Default::default()),
                [o.x, o.y, o.z, m.voxel as f32],
            );
            self.mask = Some(Mask {
                texture,
                size: m.size,
                bind_group,
            });
        }
        let (lo, hi) = match region {
            Some(r) if !fresh => r,
            _ => ([0; 3], m.size.map(|s| s - 1)),
        };
        let target = &self.mask.as_ref().expect("set above").texture;
        let [w, h, _] = m.size;
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: target,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: lo[0],
                    y: lo[1],
                    z: lo[2],
                },
                aspect: wgpu::TextureAspect::All,
            },
            m.data,
            wgpu::TexelCopyBufferLayout {
                offset: lo[0] as u64 + w as u64 * (lo[1] as u64 + h as u64 * lo[2] as u64),
                bytes_per_row: Some(w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: hi[0] - lo[0] + 1,
                height: hi[1] - lo[1] + 1,
                depth_or_array_layers: hi[2] - lo[2] + 1,
            },
        );
    }

    /// Forget the carving: no faces, no pages, no mask.
    pub fn clear(&mut self) {
        *self = GpuCarved::default();
    }
}
