//! The pipelines and the one draw routine (`Renderer::render`), and the
//! offscreen target that reads a frame back as an image.

use glam::DVec3;

use super::camera::OrbitCamera;
use super::gpu_scene::{GpuScene, VERTEX_FLOATS};
use crate::error::{Error, Result};
use crate::scene::draw::{LayerKind, Wrap};

/// What a frame shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layers {
    /// Seam bands and overlap rings blended over the facets.
    pub seam_blend: bool,
    pub bump: bool,
    pub overlay: bool,
    pub wireframe: bool,
    /// Chart boundaries (seams and facet borders) as lines.
    pub seams: bool,
    /// Area distortion of the flattening instead of the texture.
    pub heat: bool,
}

impl Default for Layers {
    fn default() -> Self {
        Layers {
            seam_blend: true,
            bump: true,
            overlay: true,
            wireframe: false,
            seams: false,
            heat: false,
        }
    }
}

/// A frame's camera, layers and cut plane.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub camera: OrbitCamera,
    pub layers: Layers,
    /// Points with normal . p > offset are cut away.
    pub clip: Option<(DVec3, f64)>,
}

const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Dark red-brown, as the inside of a body looks past the light.
const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.004,
    g: 0.002,
    b: 0.002,
    a: 1.0,
};

pub struct Renderer {
    globals: wgpu::Buffer,
    globals_group: wgpu::BindGroup,
    material_layout: wgpu::BindGroupLayout,
    block_layout: wgpu::BindGroupLayout,
    lst_layout: wgpu::BindGroupLayout,
    samplers: [wgpu::Sampler; 3],
    block_sampler: wgpu::Sampler,
    /// Facet triangles, opaque and blended over, each drawn from both
    /// sides and, for closed organs, from the front only (`cull`).
    opaque: [wgpu::RenderPipeline; 2],
    blended: [wgpu::RenderPipeline; 2],
    wire: wgpu::RenderPipeline,
    seam: wgpu::RenderPipeline,
    cut: wgpu::RenderPipeline,
    /// Cuts through lapped solid textures (solid::lst::gpu).
    lst_cut: wgpu::RenderPipeline,
    /// Copies a frame into a plain-bytes texture for egui where the
    /// device cannot view one texture in two formats (`Offscreen`).
    encode_layout: wgpu::BindGroupLayout,
    encode: wgpu::RenderPipeline,
}

/// Reads the sRGB frame (decoded as it is loaded) and writes it encoded
/// again into a texture whose format is not sRGB: the same bytes.
const ENCODE_WGSL: &str = r"
@group(0) @binding(0) var frame: texture_2d<f32>;

@vertex
fn vs_full(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
}

@fragment
fn fs_encode(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(frame, vec2<i32>(p.xy), 0);
    let low = c.rgb * 12.92;
    let high = 1.055 * pow(c.rgb, vec3<f32>(1.0 / 2.4)) - 0.055;
    return vec4<f32>(select(high, low, c.rgb <= vec3<f32>(0.0031308)), c.a);
}
";

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn texture_entry(
    binding: u32,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: dimension,
            multisampled: false,
        },
        count: None,
    }
}

fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

fn sampler(device: &wgpu::Device, mode: wgpu::AddressMode) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        address_mode_u: mode,
        address_mode_v: mode,
        address_mode_w: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        anisotropy_clamp: 1,
        ..Default::default()
    })
}

/// Facet shader and cut shader sources. The cut shader includes the
/// block and LST samplers the library ships for simulators, so both draw
/// cuts the same way.
pub(crate) fn shader_sources() -> [String; 2] {
    [
        include_str!("facet.wgsl").to_string(),
        format!(
            "{}\n{}\n{}",
            crate::solid::SAMPLE_BLOCK_WGSL,
            crate::solid::lst::gpu::sample_lst_wgsl(),
            include_str!("cut.wgsl")
        ),
    ]
}

/// A table read with textureLoad (solid/lst/sample.wgsl).
fn table_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

impl Renderer {
    pub fn new(device: &wgpu::Device) -> Renderer {
        let (encode_layout, encode) = encode_pipeline(device);
        let [facet_src, cut_src] = shader_sources();
        let facet = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("facet.wgsl"),
            source: wgpu::ShaderSource::Wgsl(facet_src.into()),
        });
        let cut_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cut.wgsl"),
            source: wgpu::ShaderSource::Wgsl(cut_src.into()),
        });
        let globals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("material"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                texture_entry(1, wgpu::TextureViewDimension::D2),
                sampler_entry(2),
                texture_entry(3, wgpu::TextureViewDimension::D2),
                sampler_entry(4),
            ],
        });
        let block_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("block"),
            entries: &[
                texture_entry(0, wgpu::TextureViewDimension::D3),
                sampler_entry(1),
                uniform_entry(2, wgpu::ShaderStages::VERTEX_FRAGMENT),
            ],
        });
        let lst_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lst"),
            entries: &[
                texture_entry(0, wgpu::TextureViewDimension::D3),
                sampler_entry(1),
                table_entry(2, wgpu::TextureSampleType::Uint),
                table_entry(3, wgpu::TextureSampleType::Float { filterable: false }),
                table_entry(4, wgpu::TextureSampleType::Float { filterable: false }),
            ],
        });
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: 4 * 28,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let globals_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &globals_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let facet_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("facet"),
            bind_group_layouts: &[Some(&globals_layout), Some(&material_layout)],
            immediate_size: 0,
        });
        let cut_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cut"),
            bind_group_layouts: &[Some(&globals_layout), Some(&block_layout)],
            immediate_size: 0,
        });
        let lst_cut_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lst cut"),
            bind_group_layouts: &[Some(&globals_layout), None, Some(&lst_layout)],
            immediate_size: 0,
        });
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32, 4 => Float32x4, 5 => Float32
        ];
        let facet_vertices = [Some(wgpu::VertexBufferLayout {
            array_stride: (VERTEX_FLOATS * 4) as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        })];
        let cut_attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let cut_vertices = [Some(wgpu::VertexBufferLayout {
            array_stride: 24,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &cut_attributes,
        })];
        let lst_attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32, 4 => Uint32
        ];
        let lst_vertices = [Some(wgpu::VertexBufferLayout {
            array_stride: (crate::solid::lst::gpu::VERTEX_WORDS * 4) as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &lst_attributes,
        })];
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        module: &wgpu::ShaderModule,
                        (vs, fs): (&str, &str),
                        buffers: &[Option<wgpu::VertexBufferLayout>],
                        topology: wgpu::PrimitiveTopology,
                        blend: bool,
                        cull: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: cull.then_some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    // Blend layers lie over their facets; they must not
                    // hide each other.
                    depth_write_enabled: Some(!blend),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOUR_FORMAT,
                        blend: blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let tri = wgpu::PrimitiveTopology::TriangleList;
        let line = wgpu::PrimitiveTopology::LineList;
        Renderer {
            opaque: [false, true].map(|cull| {
                pipeline(
                    "opaque",
                    &facet_layout,
                    &facet,
                    ("vs_main", "fs_main"),
                    &facet_vertices,
                    tri,
                    false,
                    cull,
                )
            }),
            blended: [false, true].map(|cull| {
                pipeline(
                    "blended",
                    &facet_layout,
                    &facet,
                    ("vs_main", "fs_main"),
                    &facet_vertices,
                    tri,
                    true,
                    cull,
                )
            }),
            wire: pipeline(
                "wire",
                &facet_layout,
                &facet,
                ("vs_line", "fs_wire"),
                &facet_vertices,
                line,
                false,
                false,
            ),
            seam: pipeline(
                "seam",
                &facet_layout,
                &facet,
                ("vs_line", "fs_seam"),
                &facet_vertices,
                line,
                false,
                false,
            ),
            cut: pipeline(
                "cut",
                &cut_layout,
                &cut_module,
                ("vs_cut", "fs_cut"),
                &cut_vertices,
                tri,
                false,
                false,
            ),
            lst_cut: pipeline(
                "lst cut",
                &lst_cut_layout,
                &cut_module,
                ("vs_lst_cut", "fs_lst_cut"),
                &lst_vertices,
                tri,
                false,
                false,
            ),
            encode_layout,
            encode,
            globals,
            globals_group,
            material_layout,
            block_layout,
            lst_layout,
            samplers: [
                sampler(device, wgpu::AddressMode::Repeat),
                sampler(device, wgpu::AddressMode::MirrorRepeat),
                sampler(device, wgpu::AddressMode::ClampToEdge),
            ],
            // The block tiles space (sample_block.wgsl).
            block_sampler: sampler(device, wgpu::AddressMode::Repeat),
        }
    }

    pub(super) fn material_bind_group(
        &self,
        device: &wgpu::Device,
        uniform: &wgpu::Buffer,
        colour: &wgpu::TextureView,
        wrap: Wrap,
        normal: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        let sampler = &self.samplers[match wrap {
            Wrap::Repeat => 0,
            Wrap::Mirrored => 1,
            Wrap::Clamp => 2,
        }];
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("material"),
            layout: &self.material_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(colour),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(normal),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::Sampler(&self.samplers[0]),
                },
            ],
        })
    }

    /// The LST cut's bind group: the exemplar (the block's texture, as
    /// the block sampler wraps it) and the three tables.
    pub(super) fn lst_bind_group(
        &self,
        device: &wgpu::Device,
        exemplar: &wgpu::TextureView,
        [tets, layers, waves]: [&wgpu::TextureView; 3],
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lst"),
            layout: &self.lst_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(exemplar),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.block_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(tets),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(layers),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: wgpu::BindingResource::TextureView(waves),
                },
            ],
        })
    }

    pub(super) fn block_bind_group(
        &self,
        device: &wgpu::Device,
        block: &wgpu::TextureView,
        placement: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("block"),
            layout: &self.block_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(block),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.block_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: placement.as_entire_binding(),
                },
            ],
        })
    }

    /// Draw `scene` as `view` shows it into `colour` and `depth`
    /// (`size` pixels), recorded into `encoder`.
    pub fn render(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        (colour, depth): (&wgpu::TextureView, &wgpu::TextureView),
        size: [u32; 2],
        scene: &GpuScene,
        view: &View,
    ) {
        let cam = &view.camera;
        let aspect = size[0] as f64 / size[1].max(1) as f64;
        let mut g = [0.0f32; 28];
        g[..16].copy_from_slice(&cam.view_proj(aspect).to_cols_array());
        let eye = cam.eye();
        g[16..19].copy_from_slice(&eye.as_vec3().to_array());
        g[19] = cam.distance as f32;
        if let Some((n, d)) = view.clip {
            g[20..23].copy_from_slice(&n.as_vec3().to_array());
            g[23] = d as f32;
        }
        g[24] = if view.layers.bump { 1.0 } else { 0.0 };
        g[25] = if view.layers.heat { 1.0 } else { 0.0 };
        queue.write_buffer(&self.globals, 0, bytemuck::cast_slice(&g));

        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: colour,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(BACKGROUND),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.globals_group, &[]);
        let layers = &view.layers;
        let shown = |layer: Option<LayerKind>| match layer {
            None => true,
            Some(LayerKind::Ring | LayerKind::Band) => layers.seam_blend && !layers.heat,
            Some(LayerKind::Overlay) => layers.overlay && !layers.heat,
            Some(LayerKind::BandOverlay) => layers.overlay && layers.seam_blend && !layers.heat,
        };
        // Opaque first, then the blend layers in the list's order (the
        // compositor's stacking).
        for blend in [false, true] {
            for p in &scene.primitives {
                let m = &scene.materials[p.material];
                if m.blend != blend || !shown(p.layer) {
                    continue;
                }
                let pipelines = if blend { &self.blended } else { &self.opaque };
                pass.set_pipeline(&pipelines[!m.double_sided as usize]);
                pass.set_bind_group(1, &m.bind_group, &[]);
                pass.set_vertex_buffer(0, p.vertices.slice(..));
                pass.set_index_buffer(p.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..p.index_count, 0, 0..1);
            }
        }
        for (on, pipeline) in [(layers.wireframe, &self.wire), (layers.seams, &self.seam)] {
            if !on {
                continue;
            }
            pass.set_pipeline(pipeline);
            for p in scene.primitives.iter().filter(|p| p.layer.is_none()) {
                pass.set_bind_group(1, &scene.materials[p.material].bind_group, &[]);
                pass.set_vertex_buffer(0, p.vertices.slice(..));
                let (buffer, count) = if std::ptr::eq(pipeline, &self.wire) {
                    (&p.edges, p.edge_count)
                } else {
                    (&p.seams, p.seam_count)
                };
                pass.set_index_buffer(buffer.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..count, 0, 0..1);
            }
        }
        if let (Some(cut), Some(block)) = (&scene.cut, &scene.block) {
            pass.set_pipeline(&self.cut);
            pass.set_bind_group(1, &block.bind_group, &[]);
            pass.set_vertex_buffer(0, cut.vertices.slice(..));
            pass.set_index_buffer(cut.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..cut.index_count, 0, 0..1);
        }
        if let Some(cut) = &scene.lst_cut {
            pass.set_pipeline(&self.lst_cut);
            pass.set_bind_group(2, &cut.bind_group, &[]);
            pass.set_vertex_buffer(0, cut.vertices.slice(..));
            pass.draw(0..cut.vertex_count, 0..1);
        }
    }
}

fn encode_pipeline(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("encode"),
        source: wgpu::ShaderSource::Wgsl(ENCODE_WGSL.into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("encode"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        }],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("encode"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("encode"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_full"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_encode"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: DISPLAY_FORMAT,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    (layout, pipeline)
}

/// egui takes its textures' values as sRGB-encoded bytes: a sRGB view
/// would decode them and the window would show the picture too dark.
const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

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
        let depth = texture(DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT, &[]);
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
            shown.as_image_copy(),
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
        image::RgbaImage::from_raw(w, h, pixels)
            .ok_or_else(|| Error::invalid("GPU readback: fewer bytes than pixels"))
    }
}

#[cfg(test)]
mod tests {
    /// The shaders parse and validate (naga, as wgpu does), so a mistake
    /// fails here and not in a user's window.
    #[test]
    fn shaders_validate() {
        let [facet, cut] = super::shader_sources();
        for src in [facet, cut, super::ENCODE_WGSL.to_string()] {
            let module = naga::front::wgsl::parse_str(&src)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::default(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{e:?}"));
        }
    }
}
