//! A baked scene's picture, offscreen: the bake's preview.png and
//! `organtex view --screenshot` without a window.

use super::{Filtering, Gpu, GpuScene, Layers, Lighting, Offscreen, OrbitCamera, Renderer, View};
use crate::error::Result;
use crate::scene::build::BakedScene;
use crate::scene::draw::DrawList;

/// `scene` drawn from its camera, `size` pixels, every layer on, lit and
/// framed as its `[bake]` settings ask (`preview_lighting`,
/// `preview_scope`). Any GPU error on the way (a limit the adapter lacks,
/// memory) is an `Err`.
pub fn preview(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
) -> Result<image::RgbImage> {
    let mut picture = picture(gpu, scene, list, size, scene.spec.bake.preview_lighting)?;
    if scene.spec.bake.preview_scope {
        scope_field(&mut picture);
    }
    Ok(picture)
}

/// The picture as the scope's optics frame it: a circular field as wide
/// as the picture is high, the rim soft over 2% of it, and the lens's
/// natural vignetting inside (cos^4 of the angle off axis, for a field
/// 70 degrees across).
pub fn scope_field(img: &mut image::RgbImage) {
    let (w, h) = (img.width() as f64, img.height() as f64);
    let radius = h / 2.0;
    let half_field = 35f64.to_radians();
    for (x, y, p) in img.enumerate_pixels_mut() {
        let r = ((x as f64 + 0.5 - w / 2.0).hypot(y as f64 + 0.5 - h / 2.0)) / radius;
        let rim = ((1.0 - r) / 0.02).clamp(0.0, 1.0);
        let off_axis = (r.min(1.0) * half_field.tan()).atan();
        let gain = rim * off_axis.cos().powi(4);
        // In linear light (the picture is sRGB, gamma 2.2 near enough).
        for c in &mut p.0 {
            *c = (((*c as f64 / 255.0).powf(2.2) * gain).powf(1.0 / 2.2) * 255.0).round() as u8;
        }
    }
}

/// `scene` drawn from its first camera under `lighting`.
pub fn picture(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
    lighting: Lighting,
) -> Result<image::RgbImage> {
    gpu.scoped(|| {
        // A still: worth the sharpest filtering whatever the adapter.
        let renderer = Renderer::new(&gpu.device, Filtering::Sharp);
        let gpu_scene = GpuScene::new(&renderer, &gpu.device, &gpu.queue, list)?;
        let view = View {
            camera: OrbitCamera::for_scene(&scene.spec.cameras, gpu_scene.bounds),
            layers: Layers {
                lighting,
                ..Layers::default()
            },
            clip: None,
        };
        let target = Offscreen::new(gpu, &renderer, size);
        target.draw(&renderer, &gpu.device, &gpu.queue, &gpu_scene, &view);
        Ok(image::DynamicImage::ImageRgba8(target.read(&gpu.device, &gpu.queue)?).to_rgb8())
    })
}
