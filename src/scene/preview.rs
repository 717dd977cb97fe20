//! The bake's preview: the scene rendered from its first camera (or, with
//! no camera, from an orbit view), in software, each pixel the colour the
//! compositor gives its point, lit by a light at the camera as an endoscope
//! lights what it sees.

use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};

use super::build::BakedScene;
use super::composite::linear_to_srgb;
use super::file::Camera;
use crate::raster;

/// A default view of the scene's bounds when it has no camera.
fn orbit_camera(scene: &BakedScene) -> Camera {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for n in &scene.nodes {
        if let Some((a, b)) = n.mesh.bounding_box() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    let centre = (lo + hi) / 2.0;
    let radius = (hi - lo).length() / 2.0;
    let dir = DVec3::new(0.35, 0.3, 1.0).normalize();
    Camera {
        position: (centre + dir * radius * 3.0).to_array(),
        look_at: centre.to_array(),
        fov: 40.0,
    }
}

/// Render `width` x `height` pixels.
pub fn render(scene: &BakedScene, width: usize, height: usize) -> RgbImage {
    let camera = scene
        .spec
        .cameras
        .first()
        .cloned()
        .unwrap_or_else(|| orbit_camera(scene));
    let eye = DVec3::from_array(camera.position);
    let forward = (DVec3::from_array(camera.look_at) - eye).normalize();
    // +Y is up, as in glTF.
    let helper = if forward.y.abs() < 0.95 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let right = forward.cross(helper).normalize();
    let up = right.cross(forward);
    let focal = (height as f64 / 2.0) / (camera.fov.to_radians() / 2.0).tan();
    let near = 1e-3;
    let project = |p: DVec3| {
        let d = p - eye;
        let z = d.dot(forward);
        (z > near).then(|| {
            (
                DVec2::new(
                    width as f64 / 2.0 + focal * d.dot(right) / z,
                    height as f64 / 2.0 - focal * d.dot(up) / z,
                ),
                z,
            )
        })
    };
    // Nearest face per pixel, with its perspective-correct barycentrics.
    let mut depth = vec![f64::INFINITY; width * height];
    let mut hit: Vec<Option<(usize, usize, [f64; 3])>> = vec![None; width * height];
    for (k, node) in scene.nodes.iter().enumerate() {
        for f in 0..node.mesh.num_faces() {
            let corners = node.mesh.corners(f).map(project);
            let [Some(a), Some(b), Some(c)] = corners else {
                continue;
            };
            let z = [a.1, b.1, c.1];
            raster::triangle([a.0, b.0, c.0], width, height, |x, y, w| {
                let inv = w[0] / z[0] + w[1] / z[1] + w[2] / z[2];
                let d = 1.0 / inv;
                let i = y * width + x;
                if d < depth[i] {
                    depth[i] = d;
                    hit[i] = Some((k, f, [w[0] / z[0] * d, w[1] / z[1] * d, w[2] / z[2] * d]));
                }
            });
        }
    }
    let finite: Vec<f64> = depth.iter().copied().filter(|d| d.is_finite()).collect();
    let typical = if finite.is_empty() {
        1.0
    } else {
        finite.iter().sum::<f64>() / finite.len() as f64
    };
    let mut img = RgbImage::from_pixel(width as u32, height as u32, Rgb([12, 8, 8]));
    for (i, h) in hit.iter().enumerate() {
        let Some((k, f, w)) = *h else { continue };
        let node = &scene.nodes[k];
        let t = node.mesh.triangles[f];
        let n = (0..3)
            .map(|c| node.normals[t[c] as usize] * w[c])
            .sum::<DVec3>()
            .normalize_or_zero();
        let p = (0..3)
            .map(|c| node.mesh.positions[t[c] as usize] * w[c])
            .sum::<DVec3>();
        let to_eye = (eye - p).normalize_or_zero();
        let falloff = 1.0 / (1.0 + (depth[i] / (1.5 * typical)).powi(2));
        let light = (0.15 + 0.85 * n.dot(to_eye).abs()) * (0.4 + 1.2 * falloff);
        // A pixel covers depth / focal mesh units (more where the surface
        // is seen edge-on; this is the least, as mipmapping takes it).
        let c = node.compositor.colour_over(f, w, depth[i] / focal);
        img.put_pixel(
            (i % width) as u32,
            (i / width) as u32,
            Rgb(c.map(|v| (linear_to_srgb(v * light as f32) * 255.0).round() as u8)),
        );
    }
    img
}
