//! The offscreen target: a colour and depth pair a frame is drawn into,
//! shown by egui in the viewer and read back as an image (the bake's
//! preview, tests, screenshots).

use super::frame::View;
use super::gpu_scene::GpuScene;
use super::pipelines::{COLOUR_FORMAT, DEPTH_FORMAT, DISPLAY_FORMAT, Renderer};
use crate::error::{Error, Result};

/// How the frame reaches egui.
enum Display {
    /// The frame's own texture viewed as plain bytes (needs the
    /// VIEW_FORMATS capability).
    Reinterpreted(wgpu::TextureView),
    /// A second texture the frame is encoded into after each draw (GL).
    Encoded {
        texture: wgpu::Texture,
        view: wgpu::TextureView,
        frame: wgpu::BindGroup,
    },
}

/// A colour and depth target of a fixed size, readable as an image.
pub struct Offscreen {
    pub size: [u32; 2],
    pub colour: wgpu::Texture,
    pub colour_view: wgpu::TextureView,
    display: Display,
    depth_view: wgpu::TextureView,
}

impl Offscreen {
    /// A target `size` pixels on `gpu`'s device, for `renderer`'s frames.
    pub fn new(gpu: &super::Gpu, renderer: &Renderer, size: [u32; 2]) -> Offscreen {
        let device = &gpu.device;
        let extent = wgpu::Extent3d {
            width: size[0].max(1),
            height: size[1].max(1),
            depth_or_array_layers: 1,
        };
        let texture = |format, usage, view_formats: &[wgpu::TextureFormat]| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("offscreen"),
                size: extent,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats,
            })
        };
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING;
        let view_formats: &[wgpu::TextureFormat] = if gpu.view_formats {
            &[DISPLAY_FORMAT]
        } else {
            &[]
        };
        let colour = texture(COLOUR_FORMAT, usage, view_formats);
        let colour_view = colour.create_view(&Default::default());
        let display = if gpu.view_formats {
            Display::Reinterpreted(colour.create_view(&wgpu::TextureViewDescriptor {
                format: Some(DISPLAY_FORMAT),
                ..Default::default()
            }))
        } else {
            let encoded = texture(DISPLAY_FORMAT, usage, &[]);
            Display::Encoded {
                view: encoded.create_view(&Default::default()),
                texture: encoded,
                frame: device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("encode"),
                    layout: &renderer.encode_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&colour_view),
                    }],
                }),
            }
        };
        let depth = texture(
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            &[],
        );
        Offscreen {
            size: [extent.width, extent.height],
            colour_view,
            display,
            colour,
            depth_view: depth.create_view(&Default::default()),
        }
    }

    /// The frame as plain sRGB-encoded bytes, for egui.
    pub fn display_view(&self) -> &wgpu::TextureView {
        match &self.display {
            Display::Reinterpreted(view) | Display::Encoded { view, .. } => view,
        }
    }

    /// Draw a frame into this target and submit it.
    pub fn draw(
        &self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &GpuScene,
        view: &View,
    ) {
        let mut encoder = device.create_command_encoder(&Default::default());
        renderer.render(
            queue,
            &mut encoder,
            (&self.colour_view, &self.depth_view),
            self.size,
            scene,
            view,
        );
        if let Display::Encoded { view, frame, .. } = &self.display {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("encode"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&renderer.encode);
            pass.set_bind_group(0, frame, &[]);
            pass.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
    }

    /// The target's pixels (sRGB, as a PNG stores them), read from what
    /// egui shows, so that tests see the display path too.
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<image::RgbaImage> {
        let shown = match &self.display {
            Display::Reinterpreted(_) => &self.colour,
            Display::Encoded { texture, .. } => texture,
        };
        let [w, h] = self.size;
        image::RgbaImage::from_raw(w, h, read_bytes(device, queue, shown, self.size)?)
            .ok_or_else(|| Error::invalid("GPU readback: fewer bytes than pixels"))
    }

    /// The last frame's depth buffer, row by row from the top: 0 at the
    /// near plane, 1 at the far plane and where nothing was drawn. Read
    /// through `renderer`'s depth-bytes pass, every bit of each depth.
    pub fn read_depth(
        &self,
        renderer: &Renderer,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<f32>> {
        let bytes = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth bytes"),
            size: wgpu::Extent3d {
                width: self.size[0],
                height: self.size[1],
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DISPLAY_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let nearest = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("depth bytes"),
            ..Default::default()
        });
        let depth = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth bytes"),
            layout: &renderer.depth_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&self.depth_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&nearest),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth bytes"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &bytes.create_view(&Default::default()),
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&renderer.depth_bytes);
            pass.set_bind_group(0, &depth, &[]);
            pass.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
        let rgba = read_bytes(device, queue, &bytes, self.size)?;
        Ok(rgba
            .chunks_exact(4)
            .map(|p| f32::from_be_bytes([p[0], p[1], p[2], p[3]]))
            .collect())
    }
}

/// The bytes of `texture`, a 4-byte-per-pixel texture `size` pixels,
/// row by row from the top.
fn read_bytes(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    [w, h]: [u32; 2],
) -> Result<Vec<u8>> {
    // Rows of a texture-to-buffer copy are padded to 256 bytes.
    let row = (4 * w).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (row * h) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::invalid(format!("GPU readback: {e}")))?;
    rx.recv()
        .map_err(|e| Error::invalid(format!("GPU readback: {e}")))?
        .map_err(|e| Error::invalid(format!("GPU readback: {e}")))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| Error::invalid(format!("GPU readback: {e}")))?;
    let mut pixels = Vec::with_capacity((4 * w * h) as usize);
    for y in 0..h as usize {
        pixels.extend_from_slice(&data[y * row as usize..y * row as usize + 4 * w as usize]);
    }
    drop(data);
    buffer.unmap();
    Ok(pixels)
}
