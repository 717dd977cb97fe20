//! The pipelines the renderer draws with (facets, blend layers, lines,
//! cuts through blocks and lapped solid textures, carved faces), their bind
//! group layouts and samplers, and the bind groups scene data is bound by.
//! `gpu_scene` uploads a scene's data into bind groups made here; `frame`
//! draws it.

use crate::scene::draw::Wrap;

/// Floats per vertex of carved faces: position 3, normal 3, uv 2.
pub(super) const CARVED_FLOATS: usize = 8;
/// Floats per vertex of the facet pipelines: position 3, normal 3, uv 2,
/// alpha 1, tangent 4,
/// heat 1.
pub(super) const VERTEX_FLOATS: usize = 14;
pub(super) const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub(super) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// egui takes its textures' values as sRGB-encoded bytes: a sRGB view
/// would decode them and the window would show the picture too dark.
pub(super) const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub struct Renderer {
    pub(super) globals: wgpu::Buffer,
    pub(super) globals_group: wgpu::BindGroup,
    pub(super) material_layout: wgpu::BindGroupLayout,
    pub(super) block_layout: wgpu::BindGroupLayout,
    pub(super) lst_layout: wgpu::BindGroupLayout,
    pub(super) samplers: [wgpu::Sampler; 3],
    pub(super) block_sampler: wgpu::Sampler,
    /// Facet triangles, opaque and blended over, each drawn from both
    /// sides and, for closed organs, from the front only (`cull`).
    pub(super) opaque: [wgpu::RenderPipeline; 2],
    pub(super) blended: [wgpu::RenderPipeline; 2],
    pub(super) wire: wgpu::RenderPipeline,
    pub(super) seam: wgpu::RenderPipeline,
    pub(super) cut: wgpu::RenderPipeline,
    /// Cuts through lapped solid textures (solid::lst::gpu).
    pub(super) lst_cut: wgpu::RenderPipeline,
    /// Faces a carving exposed, textured from atlas pages (`carved`).
    pub(super) carved: wgpu::RenderPipeline,
    pub(super) carve_layout: wgpu::BindGroupLayout,
    pub(super) page_layout: wgpu::BindGroupLayout,
    /// The carve mask's bind group when nothing is carved.
    pub(super) no_carving: wgpu::BindGroup,
    /// Copies a frame into a plain-bytes texture for egui where the
    /// device cannot view one texture in two formats (`Offscreen`).
    pub(super) encode_layout: wgpu::BindGroupLayout,
    pub(super) encode: wgpu::RenderPipeline,
    /// Writes the depth buffer into a plain-bytes texture, to be read
    /// back (`Offscreen::read_depth`): depth buffers themselves cannot be
    /// copied out on every backend (GL).
    pub(super) depth_layout: wgpu::BindGroupLayout,
    pub(super) depth_bytes: wgpu::RenderPipeline,
}

/// The vertex stage of the full-screen passes: one triangle over the
/// whole target, no vertex buffer.
const FULL_SCREEN_VS: &str = r"
@vertex
fn vs_full(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
}
";

/// Reads the sRGB frame (decoded as it is loaded) and writes it encoded
/// again into a texture whose format is not sRGB: the same bytes.
const ENCODE_FS: &str = r"
@group(0) @binding(0) var frame: texture_2d<f32>;

@fragment
fn fs_encode(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(frame, vec2<i32>(p.xy), 0);
    let low = c.rgb * 12.92;
    let high = 1.055 * pow(c.rgb, vec3<f32>(1.0 / 2.4)) - 0.055;
    return vec4<f32>(select(high, low, c.rgb <= vec3<f32>(0.0031308)), c.a);
}
";

/// Reads the depth buffer and writes each depth's 32 bits into red,
/// green, blue and alpha, high byte first. The depth texture is bound as
/// unfilterable float (WebGPU allows it for depth formats), since GL
/// cannot load from a `texture_depth_2d`, and read through a nearest
/// sampler at each texel's centre: GLES counts a depth texture without
/// nearest filtering as incomplete, and `textureLoad` binds no sampler.
const DEPTH_BYTES_FS: &str = r"
@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var nearest: sampler;

@fragment
fn fs_depth_bytes(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(depth));
    let v = bitcast<u32>(textureSampleLevel(depth, nearest, p.xy / size, 0.0).r);
    let bytes = vec4<u32>(v >> 24u, (v >> 16u) & 255u, (v >> 8u) & 255u, v & 255u);
    return vec4<f32>(bytes) / 255.0;
}
";

/// A full-screen pass's WGSL: the shared vertex stage and `fragment`.
fn full_screen_source(fragment: &str) -> String {
    format!("{FULL_SCREEN_VS}{fragment}")
}

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

/// The frame's uniform (frame.wgsl's `Globals`), in floats.
pub(super) const GLOBALS_FLOATS: usize = 32;

fn sampler(device: &wgpu::Device, mode: wgpu::AddressMode, anisotropy: u16) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        address_mode_u: mode,
        address_mode_v: mode,
        address_mode_w: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        anisotropy_clamp: anisotropy,
        ..Default::default()
    })
}

/// How sharply textures seen edge on are filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filtering {
    /// Trilinear: a wall seen edge on blurs into streaks along it, but a
    /// software adapter keeps interactive frame rates (16x anisotropic
    /// filtering costs llvmpipe 1.7x the frame time).
    Fast,
    /// 16x anisotropic: the wall keeps its detail down the cavity. For
    /// stills (the bake's preview) and hardware adapters.
    Sharp,
}

impl Filtering {
    /// Sharp on a hardware adapter, fast on a software one.
    pub fn for_frames(gpu: &super::Gpu) -> Filtering {
        if gpu.software {
            Filtering::Fast
        } else {
            Filtering::Sharp
        }
    }

    fn anisotropy(self) -> u16 {
        match self {
            Filtering::Fast => 1,
            Filtering::Sharp => 16,
        }
    }
}

/// Facet, cut and carved-face shader sources, each after `frame.wgsl`. The cut shader includes the
/// block and LST samplers the library ships for simulators, so both draw
/// cuts the same way.
pub(crate) fn shader_sources() -> [String; 3] {
    let frame = include_str!("frame.wgsl");
    [
        format!(
            "const FILM_RELIEF: f32 = {:?};\n{frame}\n{}",
            crate::scene::draw::FILM_RELIEF as f32,
            include_str!("facet.wgsl")
        ),
        format!(
            "{frame}\n{}\n{}\n{}",
            crate::solid::SAMPLE_BLOCK_WGSL,
            crate::solid::lst::gpu::sample_lst_wgsl(),
            include_str!("cut.wgsl")
        ),
        format!("{frame}\n{}", include_str!("carved.wgsl")),
    ]
}

/// The carve mask's bind group: `mask` (its view, corner and voxel size),
/// or none (a 1-voxel texture, switched off).
pub(super) fn carve_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    sampler: &wgpu::Sampler,
    mask: Option<(&wgpu::TextureView, [f32; 4])>,
) -> wgpu::BindGroup {
    let empty;
    let (view, origin, on) = match mask {
        Some((view, origin)) => (view, origin, 1.0),
        None => {
            empty = device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some("no carve mask"),
                    size: wgpu::Extent3d {
                        width: 1,
                        height: 1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D3,
                    format: wgpu::TextureFormat::R8Unorm,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default());
            (&empty, [0.0, 0.0, 0.0, 1.0], 0.0)
        }
    };
    let uniform: [f32; 8] = [
        origin[0], origin[1], origin[2], origin[3], on, 0.0, 0.0, 0.0,
    ];
    let uniform = wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("carve"),
            contents: bytemuck::cast_slice(&uniform),
            usage: wgpu::BufferUsages::UNIFORM,
        },
    );
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("carve mask"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(sampler),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: uniform.as_entire_binding(),
            },
        ],
    })
}

/// A table or a frame read with textureLoad (solid/lst/sample.wgsl, the
/// full-screen passes).
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
    pub fn new(device: &wgpu::Device, filtering: Filtering) -> Renderer {
        let aniso = filtering.anisotropy();
        let (encode_layout, encode) =
            full_screen_pipeline(device, ("encode", ENCODE_FS, "fs_encode"), false);
        let (depth_layout, depth_bytes) = full_screen_pipeline(
            device,
            ("depth bytes", DEPTH_BYTES_FS, "fs_depth_bytes"),
            true,
        );
        let [facet_src, cut_src, carved_src] = shader_sources();
        let carved_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("carved.wgsl"),
            source: wgpu::ShaderSource::Wgsl(carved_src.into()),
        });
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
        let carve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("carve mask"),
            entries: &[
                texture_entry(0, wgpu::TextureViewDimension::D3),
                sampler_entry(1),
                uniform_entry(2, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let page_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("carved page"),
            entries: &[
                texture_entry(0, wgpu::TextureViewDimension::D2),
                sampler_entry(1),
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
            size: 4 * GLOBALS_FLOATS as u64,
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
            bind_group_layouts: &[
                Some(&globals_layout),
                Some(&material_layout),
                Some(&carve_layout),
            ],
            immediate_size: 0,
        });
        let cut_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("cut"),
            bind_group_layouts: &[Some(&globals_layout), Some(&block_layout)],
            immediate_size: 0,
        });
        let carved_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("carved"),
            bind_group_layouts: &[Some(&globals_layout), Some(&page_layout)],
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
        let carved_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
        let carved_vertices = [Some(wgpu::VertexBufferLayout {
            array_stride: (CARVED_FLOATS * 4) as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &carved_attributes,
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
                    // Blend layers lie on their facets' faces (scene::draw);
                    // they must not hide each other, and a slope-scaled
                    // bias (a decal's polygon offset) keeps them from
                    // fighting the faces they cover for depth. Drawn in
                    // order, they stack as the compositor does.
                    depth_write_enabled: Some(!blend),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    bias: if blend {
                        wgpu::DepthBiasState {
                            constant: -2,
                            slope_scale: -1.0,
                            clamp: 0.0,
                        }
                    } else {
                        Default::default()
                    },
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
        let clamp = sampler(device, wgpu::AddressMode::ClampToEdge, 1);
        let no_carving = carve_bind_group(device, &carve_layout, &clamp, None);
        Renderer {
            carved: pipeline(
                "carved",
                &carved_layout,
                &carved_module,
                ("vs_carved", "fs_carved"),
                &carved_vertices,
                tri,
                false,
                false,
            ),
            carve_layout,
            page_layout,
            no_carving,
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
            depth_layout,
            depth_bytes,
            globals,
            globals_group,
            material_layout,
            block_layout,
            lst_layout,
            samplers: [
                sampler(device, wgpu::AddressMode::Repeat, aniso),
                sampler(device, wgpu::AddressMode::MirrorRepeat, aniso),
                sampler(device, wgpu::AddressMode::ClampToEdge, aniso),
            ],
            // The block tiles space (sample_block.wgsl).
            block_sampler: sampler(device, wgpu::AddressMode::Repeat, 1),
        }
    }

    /// A carved-face page's bind group (its texture, linear, clamped).
    pub(super) fn page_bind_group(
        &self,
        device: &wgpu::Device,
        page: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("carved page"),
            layout: &self.page_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(page),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&self.samplers[2]),
                },
            ],
        })
    }

    /// The carve mask's bind group for a mask texture.
    pub(super) fn carve_mask_bind_group(
        &self,
        device: &wgpu::Device,
        mask: &wgpu::TextureView,
        origin: [f32; 4],
    ) -> wgpu::BindGroup {
        carve_bind_group(
            device,
            &self.carve_layout,
            &self.samplers[2],
            Some((mask, origin)),
        )
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
}

/// A pass of one triangle over the whole target that reads one
/// unfilterable texture (binding 0), with a non-filtering sampler
/// (binding 1) if `sampled`, and writes `DISPLAY_FORMAT`: `label`, its
/// fragment stage's WGSL and entry point.
fn full_screen_pipeline(
    device: &wgpu::Device,
    (label, fragment_wgsl, fragment): (&str, &str, &str),
    sampled: bool,
) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(full_screen_source(fragment_wgsl).into()),
    });
    let texture = table_entry(0, wgpu::TextureSampleType::Float { filterable: false });
    let sampler = wgpu::BindGroupLayoutEntry {
        binding: 1,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
        count: None,
    };
    let entries = if sampled {
        &[texture, sampler][..]
    } else {
        &[texture][..]
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
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
            entry_point: Some(fragment),
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

#[cfg(test)]
mod tests {
    /// The shaders parse and validate (naga, as wgpu does), so a mistake
    /// fails here and not in a user's window.
    #[test]
    fn shaders_validate() {
        let [facet, cut, carved] = super::shader_sources();
        for src in [
            facet,
            cut,
            carved,
            super::full_screen_source(super::ENCODE_FS),
            super::full_screen_source(super::DEPTH_BYTES_FS),
        ] {
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
