//! One frame: `Renderer::render` draws a scene on the GPU as a `View`
//! shows it (camera, layers, cut plane) into any colour and depth target.

use glam::DVec3;

use super::camera::OrbitCamera;
use super::gpu_scene::GpuScene;
use super::pipelines::{GLOBALS_FLOATS, Renderer};
use crate::scene::draw::LayerKind;
pub use crate::scene::file::Lighting;

/// Dark red-brown, as the inside of a body looks past the light.
const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.004,
    g: 0.002,
    b: 0.002,
    a: 1.0,
};

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
    pub lighting: Lighting,
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
            lighting: Lighting::default(),
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

impl Renderer {
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
        let mut g = [0.0f32; GLOBALS_FLOATS];
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
        g[26] = (view.layers.lighting == Lighting::Endoscope) as u8 as f32;
        g[27] = crate::scene::draw::SCOPE_EXPOSURE as f32;
        let (outer, _) = crate::scene::draw::scope_cone(cam.fov, aspect);
        g[28..31].copy_from_slice(&(cam.target - eye).normalize_or_zero().as_vec3().to_array());
        g[31] = outer.cos() as f32;
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
                    // Kept: the preview reads it back (Offscreen::read_depth).
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &self.globals_group, &[]);
        // The facets are not drawn where a carving took tissue away.
        pass.set_bind_group(2, scene.carved.mask().unwrap_or(&self.no_carving), &[]);
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
        for (page, vertices, count) in scene.carved.draws() {
            pass.set_pipeline(&self.carved);
            pass.set_bind_group(1, page, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.draw(0..count, 0..1);
        }
    }
}
