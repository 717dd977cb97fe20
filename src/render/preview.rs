//! A baked scene's picture, offscreen: the bake's preview.png and
//! `organtex view --screenshot` without a window.

use super::{Gpu, GpuScene, Layers, Offscreen, OrbitCamera, Renderer, View};
use crate::error::Result;
use crate::scene::build::BakedScene;
use crate::scene::draw::DrawList;

/// `scene` drawn from its camera, `size` pixels, every layer on. Any GPU
/// error on the way (a limit the adapter lacks, memory) is an `Err`.
pub fn preview(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
) -> Result<image::RgbImage> {
    gpu.scoped(|| {
        let renderer = Renderer::new(&gpu.device);
        let gpu_scene = GpuScene::new(&renderer, &gpu.device, &gpu.queue, list)?;
        let view = View {
            camera: OrbitCamera::for_scene(&scene.spec.cameras, gpu_scene.bounds),
            layers: Layers::default(),
            clip: None,
        };
        let target = Offscreen::new(gpu, &renderer, size);
        target.draw(&renderer, &gpu.device, &gpu.queue, &gpu_scene, &view);
        Ok(image::DynamicImage::ImageRgba8(target.read(&gpu.device, &gpu.queue)?).to_rgb8())
    })
}
