//! A baked scene's picture, offscreen: the bake's preview.png and
//! `organtex view --screenshot` without a window.

use super::{Filtering, Gpu, GpuScene, Layers, Lighting, Offscreen, OrbitCamera, Renderer, View};
use crate::error::Result;
use crate::scene::build::BakedScene;
use crate::scene::draw::DrawList;
use crate::synth::filter::Plane;

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

/// The picture as a hysteroscope's optics and sensor give it, in linear
/// light (the picture is sRGB, gamma 2.2 near enough):
/// - the wide-angle lens's barrel distortion, the field's centre
///   magnified `BARREL` over its rim, which stays where it was (r_u =
///   r_d (1 + k r_d^2) / (1 + k), r relative to the field's radius), with
///   a hair of lateral colour (red drawn a little wider, blue narrower);
/// - the lens's blur, a Gaussian of `BLUR` of the picture's height;
/// - a circular field `FIELD` times the picture's width across, so its
///   corners are dark, as a video endoscope's frames are; the rim soft
///   over 2% of it. The darkening
///   towards the edge of the view is the scope's light cone, which the
///   renderer draws (frame.wgsl), in the light before the sensor clips
///   it; a lens vignette here, after the tone curve, would dim the
///   glints that a real sensor clips;
/// - the sensor's noise: shot noise growing with the square root of the
///   light plus a floor, seeded by the pixel, so the same picture gives
///   the same bytes.
///
/// Real frames have all of these; a picture without them reads as a
/// rendering.
pub fn scope_field(img: &mut image::RgbImage) {
    const BARREL: f64 = 0.15;
    const LATERAL_COLOUR: f64 = 0.004;
    const BLUR: f64 = 0.0007;
    const FIELD: f64 = 1.2;
    const SHOT: f64 = 0.012;
    const FLOOR: f64 = 0.0002;
    let (w, h) = (img.width() as usize, img.height() as usize);
    // A near-white pixel is the wet film's reflection, which the
    // renderer's tone curve rolls into its shoulder (frame.wgsl) where a
    // sensor would clip it: it stands for several times the light it
    // shows. The lens spreads and dims that light and the sensor clips it
    // again, so a glint stays a white spot, a little softened, as in real
    // frames.
    const CLIPPED: f32 = 4.0;
    let linear: Vec<[f32; 3]> = img
        .pixels()
        .map(|p| {
            let gain = if p.0.iter().all(|&c| c >= 204) {
                CLIPPED
            } else {
                1.0
            };
            p.0.map(|c| (c as f32 / 255.0).powf(2.2) * gain)
        })
        .collect();
    let radius = FIELD * w as f64 / 2.0;
    let centre = (w as f64 / 2.0, h as f64 / 2.0);
    let bilinear = |x: f64, y: f64, c: usize| -> f32 {
        let (x, y) = (
            (x - 0.5).clamp(0.0, (w - 1) as f64),
            (y - 0.5).clamp(0.0, (h - 1) as f64),
        );
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let at = |x: usize, y: usize| linear[y * w + x][c];
        let top = at(x0, y0) + (at(x1, y0) - at(x0, y0)) * fx;
        let bottom = at(x0, y1) + (at(x1, y1) - at(x0, y1)) * fx;
        top + (bottom - top) * fy
    };
    let everywhere = vec![1.0; w * h];
    let blurred: Vec<Plane> = (0..3)
        .map(|c| {
            let distorted = (0..w * h)
                .map(|i| {
                    let (dx, dy) = (
                        (i % w) as f64 + 0.5 - centre.0,
                        (i / w) as f64 + 0.5 - centre.1,
                    );
                    let r2 = (dx * dx + dy * dy) / (radius * radius);
                    let s = (1.0 + BARREL * r2) / (1.0 + BARREL)
                        * (1.0 + LATERAL_COLOUR * (1.0 - c as f64) * r2);
                    bilinear(centre.0 + dx * s, centre.1 + dy * s, c)
                })
                .collect();
            Plane::new(w, h, distorted).blur((BLUR * h as f64) as f32, &everywhere)
        })
        .collect();
    for (i, p) in img.pixels_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let r = ((x as f64 + 0.5 - centre.0).hypot(y as f64 + 0.5 - centre.1)) / radius;
        let rim = ((1.0 - r) / 0.02).clamp(0.0, 1.0);
        for (c, v) in p.0.iter_mut().enumerate() {
            let light = blurred[c].data[i] as f64 * rim;
            let key = [x as u64, y as u64, c as u64];
            let noise = crate::rng::normal(0x5c09e, &key) * (SHOT * light.sqrt() + FLOOR);
            *v = ((light + noise).clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_and_spread(img: &image::RgbImage, (x0, y0): (u32, u32), size: u32) -> (f64, f64) {
        let v: Vec<f64> = (y0..y0 + size)
            .flat_map(|y| (x0..x0 + size).map(move |x| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y).0[1] as f64)
            .collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64;
        (mean, var.sqrt())
    }

    #[test]
    fn the_scope_camera_magnifies_the_centre_masks_the_corners_and_adds_a_little_noise() {
        // Grey with a white disc of radius 20 at the centre.
        let (w, h) = (320u32, 240u32);
        let disc = 20.0;
        let picture = image::RgbImage::from_fn(w, h, |x, y| {
            let r = (x as f64 + 0.5 - 160.0).hypot(y as f64 + 0.5 - 120.0);
            image::Rgb(if r < disc { [255; 3] } else { [128; 3] })
        });
        let mut framed = picture.clone();
        scope_field(&mut framed);
        let mut again = picture.clone();
        scope_field(&mut again);
        assert_eq!(framed, again, "same picture, same bytes");
        // Past the field's rim (the corners): dark but for the sensor's
        // faint noise.
        for (x, y) in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)] {
            assert!(framed.get_pixel(x, y).0.iter().all(|&c| c < 16));
        }
        // The disc grows by the barrel's central magnification, 1.15: its
        // edge (half white) from radius 20 to 23.
        let edge = (0..100)
            .map(|k| 160.0 + k as f64 * 0.5)
            .find(|&x| framed.get_pixel(x as u32, 120).0[1] < 190)
            .unwrap()
            - 160.0;
        assert!((22.5..24.0).contains(&edge), "disc edge at {edge}");
        // Grey between the disc and the rim keeps its level and gains a
        // little noise.
        let (mean, spread) = mean_and_spread(&framed, (160 - 8, 120 - 60), 16);
        assert!((mean - 128.0).abs() < 6.0, "mean {mean}");
        assert!((0.3..4.0).contains(&spread), "noise spread {spread}");
    }
}
