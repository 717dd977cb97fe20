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
    let scope = scene.spec.bake.preview_scope;
    let (mut picture, medium) = draw(
        gpu,
        scene,
        list,
        size,
        scene.spec.bake.preview_lighting,
        scope,
    )?;
    if scope {
        scope_field(&mut picture, medium.as_ref())?;
    }
    Ok(picture)
}

/// What lies between the scope's lens and the tissue each pixel shows:
/// the distance along the pixel's ray, row by row from the top (scene
/// units, infinite where nothing is drawn), and the view's typical depth
/// (the camera's distance to what it looks at), which the fluid's lengths
/// are measured in, as the renderer measures its light's falloff
/// (frame.wgsl), so a scene drawn at another scale looks the same.
pub struct Medium {
    pub distance: Vec<f32>,
    pub typical: f32,
}

impl Medium {
    /// The medium of a frame `camera` drew, `w` x `h` pixels, from its
    /// depth buffer (`Offscreen::read_depth`): each pixel centre's depth
    /// taken back into the scene through the inverse projection.
    fn from_depth(depth: &[f32], camera: &OrbitCamera, [w, h]: [usize; 2]) -> Medium {
        let inverse = camera.unprojection(w as f64 / h as f64);
        let eye = camera.eye();
        let distance = depth
            .iter()
            .enumerate()
            .map(|(i, &z)| {
                if z >= 1.0 {
                    return f32::INFINITY;
                }
                let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
                let ndc =
                    glam::DVec3::new(x / w as f64 * 2.0 - 1.0, 1.0 - y / h as f64 * 2.0, z as f64);
                inverse.project_point3(ndc).distance(eye) as f32
            })
            .collect();
        Medium {
            distance,
            typical: camera.distance as f32,
        }
    }
}

/// The scattering length over the typical depth: at the typical depth two
/// thirds of the light arrives unscattered.
const FREE_PATH: f32 = 2.5;
/// The forward-scattered light's spread (a Gaussian's sigma), of the
/// picture's height: small angles, as forward scattering is.
const SPREAD: f64 = 0.012;
/// The backscattered veil, linear light: blood-tinged.
const VEIL: [f32; 3] = [0.012, 0.0035, 0.0025];
/// The absorption lengths of red, green and blue over the typical depth:
/// at the typical depth, red keeps exp(-1) of its light. Chosen by eye
/// for a faint reddening with depth, not derived from haemoglobin's
/// extinction (which would make green and blue far shorter, for the
/// unknown, small share of blood in the saline).
const ABSORPTION: [f32; 3] = [2.0, 1.45, 1.3];

/// `linear` (w x h pixels, linear light) seen through the cavity's
/// distension fluid, saline with a trace of blood, by the single-scattering
/// model of underwater imaging (Jaffe 1990; McGlamery 1980):
/// - the fluid absorbs, green and blue more than red (Beer-Lambert over
///   the light's path from the scope's tip to the tissue and back, 2d),
///   so the far cavity darkens faster than the inverse square alone and
///   reddens;
/// - of what is not absorbed, the light of a pixel at distance d reaches
///   the lens unscattered with probability exp(-d / l); the rest arrives
///   scattered forward a little off its ray, a blur of the same light;
/// - the fluid the scope's light passes through sends some back: an even
///   veil over the field, the same whatever the distance, because the
///   light leaves the lens itself and falls off with the square of the
///   distance, so nearly all of the backscatter comes from the first few
///   millimetres in front of the lens, which every ray crosses.
///
/// So the far cavity's detail and vessels soften and its dark lifts to a
/// haze, while the near wall, seen through a few millimetres, stays
/// sharp and bright; a picture equally sharp at every depth reads as a
/// rendering. The tone curve has already been applied (frame.wgsl): the
/// fluid acts on the light it gives, an approximation that holds where
/// that curve is near linear, in the dim far cavity where the fluid
/// shows.
fn through_fluid(linear: &mut [[f32; 3]], w: usize, h: usize, medium: &Medium) {
    assert_eq!(medium.distance.len(), w * h, "a distance for each pixel");
    let unscattered: Vec<f32> = medium
        .distance
        .iter()
        .map(|&d| (-d / (FREE_PATH * medium.typical)).exp())
        .collect();
    let everywhere = vec![1.0; w * h];
    for c in 0..3 {
        for (p, &d) in linear.iter_mut().zip(&medium.distance) {
            p[c] *= (-2.0 * d / (ABSORPTION[c] * medium.typical)).exp();
        }
        let scattered: Vec<f32> = linear
            .iter()
            .zip(&unscattered)
            .map(|(p, k)| p[c] * (1.0 - k))
            .collect();
        let spread = Plane::new(w, h, scattered).blur((SPREAD * h as f64) as f32, &everywhere);
        for ((p, k), s) in linear.iter_mut().zip(&unscattered).zip(&spread.data) {
            p[c] = p[c] * k + s + VEIL[c];
        }
    }
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
///   the same bytes;
/// - the video chain's compression: the frame as an endoscopy recorder
///   stores it, a JPEG of quality `VIDEO_QUALITY` (HyperKvasir's frames,
///   for one, are JPEGs), with its faint 8-pixel blocks and colour
///   smeared at edges.
///
/// With a `medium`, the picture is first seen through the cavity's fluid
/// (`through_fluid`).
///
/// Real frames have all of these; a picture without them reads as a
/// rendering.
pub fn scope_field(img: &mut image::RgbImage, medium: Option<&Medium>) -> Result<()> {
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
    let mut linear: Vec<[f32; 3]> = img
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
    if let Some(medium) = medium {
        through_fluid(&mut linear, w, h, medium);
    }
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
    *img = video_frame(img)?;
    Ok(())
}

/// The JPEG quality of an endoscopy recorder's frames.
const VIDEO_QUALITY: u8 = 80;

/// `img` through a JPEG encoder and decoder at `VIDEO_QUALITY`: the same
/// bytes for the same picture (the encoder has no randomness).
fn video_frame(img: &image::RgbImage) -> Result<image::RgbImage> {
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, VIDEO_QUALITY)
        .encode_image(img)
        .and_then(|()| image::load_from_memory_with_format(&jpeg, image::ImageFormat::Jpeg))
        .map(|frame| frame.to_rgb8())
        .map_err(|e| crate::error::Error::invalid(format!("the preview's JPEG compression: {e}")))
}

/// `scene` drawn from its first camera under `lighting`.
pub fn picture(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
    lighting: Lighting,
) -> Result<image::RgbImage> {
    Ok(draw(gpu, scene, list, size, lighting, false)?.0)
}

/// `picture`, and each pixel's distance as `Medium` takes it.
pub fn picture_and_medium(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
    lighting: Lighting,
) -> Result<(image::RgbImage, Medium)> {
    let (picture, medium) = draw(gpu, scene, list, size, lighting, true)?;
    Ok((picture, medium.expect("drawn with its medium")))
}

/// `picture`, and with `medium` the frame's `Medium` (its depth read
/// back, a pass and a copy only the scope's fluid needs).
fn draw(
    gpu: &Gpu,
    scene: &BakedScene,
    list: &DrawList,
    size: [u32; 2],
    lighting: Lighting,
    medium: bool,
) -> Result<(image::RgbImage, Option<Medium>)> {
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
        let picture = image::DynamicImage::ImageRgba8(target.read(&gpu.device, &gpu.queue)?);
        let medium = if medium {
            let depth = target.read_depth(&renderer, &gpu.device, &gpu.queue)?;
            let size = target.size.map(|s| s as usize);
            Some(Medium::from_depth(&depth, &view.camera, size))
        } else {
            None
        };
        Ok((picture.to_rgb8(), medium))
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
        scope_field(&mut framed, None).unwrap();
        let mut again = picture.clone();
        scope_field(&mut again, None).unwrap();
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

    #[test]
    fn through_the_fluid_far_detail_softens_and_hazes_while_near_detail_stays() {
        // In linear light, a checkerboard of 4-pixel squares (0 and 0.5),
        // its left half 3 units from the lens (the near wall), its right
        // half 100 (the far cavity); the view's typical depth 35. Its
        // bottom rows see nothing (infinite distance).
        let (w, h) = (320usize, 240usize);
        let checker: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [((i % w / 4 + i / w / 4) % 2) as f32 * 0.5; 3])
            .collect();
        let distance: Vec<f32> = (0..w * h)
            .map(|i| match (i % w < w / 2, i / w < h - 20) {
                (_, false) => f32::INFINITY,
                (true, true) => 3.0,
                (false, true) => 100.0,
            })
            .collect();
        let medium = Medium {
            distance,
            typical: 35.0,
        };
        let mut wet = checker.clone();
        through_fluid(&mut wet, w, h, &medium);
        // Mean and spread of one channel over a 16-pixel square.
        let stats = |img: &[[f32; 3]], (x0, y0): (usize, usize), c: usize| {
            let v: Vec<f64> = (y0..y0 + 16)
                .flat_map(|y| (x0..x0 + 16).map(move |x| img[y * w + x][c] as f64))
                .collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64;
            (mean, var.sqrt())
        };
        for c in 0..3 {
            // The share of channel c the fluid leaves over a path of 2d.
            let unabsorbed = |d: f64| (-2.0 * d / (ABSORPTION[c] as f64 * 35.0)).exp();
            let unscattered = |d: f64| (-d / (FREE_PATH as f64 * 35.0)).exp();
            let veil = VEIL[c] as f64;
            let (near, far) = ((96, 40), (208, 40));
            let (near_dry, near_dry_spread) = stats(&checker, near, c);
            let (near_wet, near_wet_spread) = stats(&wet, near, c);
            let (far_dry, far_dry_spread) = stats(&checker, far, c);
            let (far_wet, far_wet_spread) = stats(&wet, far, c);
            // Near, 3 units of fluid: the squares keep nearly all their
            // contrast and, but for a little absorption and the veil,
            // their level.
            assert!(
                near_wet_spread > 0.95 * unabsorbed(3.0) * near_dry_spread,
                "near contrast {near_wet_spread} against {near_dry_spread} dry"
            );
            let near_level = near_dry * unabsorbed(3.0) + veil;
            assert!((near_wet - near_level).abs() < 1e-4 * near_level);
            // Far, 100 units: most of the light arrives scattered, so the
            // squares keep only their unscattered share's contrast (the
            // blur takes the rest into their mean); what is not absorbed
            // is not lost.
            let kept = unabsorbed(100.0) * unscattered(100.0);
            assert!(
                (far_wet_spread - kept * far_dry_spread).abs() < 0.05 * kept * far_dry_spread,
                "far contrast {far_wet_spread}, {kept} of {far_dry_spread} dry"
            );
            let far_level = far_dry * unabsorbed(100.0) + veil;
            assert!((far_wet - far_level).abs() < 1e-3 * far_level);
            // Where nothing is seen, the veil alone.
            assert_eq!(wet[w * h - 1][c], VEIL[c]);
        }
        // A red haze: where nothing is seen, red more than twice green.
        let [r, g, b] = wet[w * h - 1];
        assert!(r > 2.0 * g && g >= b, "haze {r} {g} {b}");

        // Through the whole scope, the same picture gives the same bytes.
        let picture = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
            image::Rgb(checker[y as usize * w + x as usize].map(|v| (v * 255.0) as u8))
        });
        let mut once = picture.clone();
        scope_field(&mut once, Some(&medium)).unwrap();
        let mut again = picture.clone();
        scope_field(&mut again, Some(&medium)).unwrap();
        assert_eq!(once, again, "same picture, same bytes");
    }
}
