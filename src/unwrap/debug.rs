//! Pictures of an unwrap, for `organtex unwrap --debug-dir`: the mesh
//! coloured by visibility with seams and terminals drawn, the mesh textured
//! with a checker through its new uvs, and the uv layout itself.
//! Software-rendered with the visibility depth buffer, so they need no GPU.

use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};

use super::Unwrapped;
use super::visibility::{Camera, DepthBuffer, Orthographic};
use crate::mesh::{TriMesh, UvLayer};
use crate::raster;

/// Four views around the mesh, each `size` pixels square, in a 2 x 2 grid.
const VIEWS: [[f64; 3]; 4] = [
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 0.3, 0.2],
    [-1.0, 0.3, -0.2],
];

fn views(mesh: &TriMesh, size: usize) -> Vec<Orthographic> {
    let (lo, hi) = mesh.bounding_box().unwrap_or((DVec3::ZERO, DVec3::ONE));
    let center = (lo + hi) / 2.0;
    let radius = ((hi - lo).length() / 2.0).max(1e-12);
    VIEWS
        .iter()
        .map(|d| {
            Orthographic::from_direction(DVec3::from_array(*d).normalize(), center, radius, size)
        })
        .collect()
}

/// Blue (0) through green to red (1).
fn heat(x: f64) -> [f64; 3] {
    let x = x.clamp(0.0, 1.0);
    [
        (2.0 * x - 0.5).clamp(0.0, 1.0),
        1.0 - (2.0 * x - 1.0).abs(),
        (1.0 - 2.0 * x).clamp(0.0, 1.0),
    ]
}

fn shade(normal: DVec3, camera: &Orthographic, rgb: [f64; 3]) -> Rgb<u8> {
    let light = 0.35 + 0.65 * normal.dot(camera.forward).abs();
    Rgb(rgb.map(|c| (255.0 * c * light).clamp(0.0, 255.0) as u8))
}

/// Render the four views, colouring each covered pixel with `colour(face,
/// barycentric weights)`; pixels are placed in a 2 x 2 grid.
fn render_views(
    mesh: &TriMesh,
    size: usize,
    mut colour: impl FnMut(&Orthographic, usize, [f64; 3]) -> Rgb<u8>,
    mut overlay: impl FnMut(&Orthographic, &DepthBuffer, &mut dyn FnMut(usize, usize, Rgb<u8>)),
) -> RgbImage {
    let mut img = RgbImage::from_pixel(2 * size as u32, 2 * size as u32, Rgb([250, 250, 250]));
    for (k, camera) in views(mesh, size).iter().enumerate() {
        let buffer = DepthBuffer::render(camera, mesh);
        let (ox, oy) = ((k % 2) * size, (k / 2) * size);
        for y in 0..size {
            for x in 0..size {
                let f = buffer.face[y * size + x];
                if f == u32::MAX {
                    continue;
                }
                let corners = mesh
                    .corners(f as usize)
                    .map(|p| camera.project(p).map(|q| q.0).unwrap_or_default());
                let w = barycentric(corners, DVec2::new(x as f64 + 0.5, y as f64 + 0.5));
                // Image rows grow downwards, view rows upwards.
                img.put_pixel(
                    (ox + x) as u32,
                    (oy + size - 1 - y) as u32,
                    colour(camera, f as usize, w),
                );
            }
        }
        overlay(camera, &buffer, &mut |x, y, c| {
            if x < size && y < size {
                img.put_pixel((ox + x) as u32, (oy + size - 1 - y) as u32, c);
            }
        });
    }
    img
}

fn barycentric(t: [DVec2; 3], p: DVec2) -> [f64; 3] {
    let area = (t[1] - t[0]).perp_dot(t[2] - t[0]);
    if area == 0.0 {
        return [1.0 / 3.0; 3];
    }
    let w0 = (t[2] - t[1]).perp_dot(p - t[1]) / area;
    let w1 = (t[0] - t[2]).perp_dot(p - t[2]) / area;
    [w0, w1, 1.0 - w0 - w1]
}

/// The mesh coloured by visibility (blue hidden, red always seen), seams in
/// black, terminals as yellow dots.
pub fn visibility_image(u: &Unwrapped, size: usize) -> RgbImage {
    let mesh = &u.mesh;
    let vis = &u.visibility.vertex;
    render_views(
        mesh,
        size,
        |camera, f, w| {
            let t = mesh.triangles[f];
            let v = (0..3).map(|i| w[i] * vis[t[i] as usize] as f64).sum();
            shade(mesh.face_normal(f), camera, heat(v))
        },
        |camera, buffer, put| {
            let seen = |p: DVec3| {
                camera
                    .project(p)
                    .and_then(|at| buffer.sees(at, |d| 0.5 * camera.pixel_size(d), |_| false))
                    == Some(true)
            };
            for &e in &u.seams {
                let [a, b] = u.topology.edge_vertices(e).map(|v| mesh.positions[v.idx()]);
                for k in 0..=8 {
                    let p = a.lerp(b, k as f64 / 8.0);
                    if let (true, Some((px, _))) = (seen(p), camera.project(p)) {
                        dot(put, px, 1, Rgb([0, 0, 0]));
                    }
                }
            }
            for t in &u.terminals {
                let p = mesh.positions[t.idx()];
                if let (true, Some((px, _))) = (seen(p), camera.project(p)) {
                    dot(put, px, 3, Rgb([255, 230, 0]));
                }
            }
        },
    )
}

fn dot(put: &mut dyn FnMut(usize, usize, Rgb<u8>), at: DVec2, radius: i64, c: Rgb<u8>) {
    for dy in -radius..=radius {
        for dx in -radius..=radius {
            if dx * dx + dy * dy <= radius * radius {
                let (x, y) = (at.x as i64 + dx, at.y as i64 + dy);
                if x >= 0 && y >= 0 {
                    put(x as usize, y as usize, c);
                }
            }
        }
    }
}

/// Checker value of a uv point, `cells` squares per `extent`.
fn checker(uv: DVec2, cell: f64) -> f64 {
    let parity = ((uv.x / cell).floor() as i64 + (uv.y / cell).floor() as i64).rem_euclid(2);
    if parity == 0 { 0.92 } else { 0.35 }
}

fn uv_extent(layer: &UvLayer) -> (DVec2, DVec2) {
    super::metrics::bounds(layer.coords.iter().copied())
}

/// The mesh textured with a checker through its uvs: squares stay square
/// where the map is conformal and keep their size where it keeps area.
pub fn checker_image(mesh: &TriMesh, size: usize) -> Option<RgbImage> {
    let layer = mesh.uvs.as_ref()?;
    let cell = mesh.area().sqrt() / 40.0;
    Some(render_views(
        mesh,
        size,
        |camera, f, w| {
            let t = layer.triangles[f];
            let uv: DVec2 = (0..3).map(|i| layer.coords[t[i] as usize] * w[i]).sum();
            let c = checker(uv, cell);
            shade(mesh.face_normal(f), camera, [c, c * 0.95, c * 0.85])
        },
        |_, _, _| {},
    ))
}

/// The uv layout, checkered, with chart borders in dark red.
pub fn layout_image(mesh: &TriMesh, size: usize) -> Option<RgbImage> {
    let layer = mesh.uvs.as_ref()?;
    let (lo, hi) = uv_extent(layer);
    let span = (hi - lo).max_element().max(1e-300);
    let scale = (size as f64 - 8.0) / span;
    let to_px = |u: DVec2| (u - lo) * scale + DVec2::splat(4.0);
    let cell = mesh.area().sqrt() / 40.0;
    let mut img = RgbImage::from_pixel(size as u32, size as u32, Rgb([255, 255, 255]));
    for t in &layer.triangles {
        let uv = t.map(|v| layer.coords[v as usize]);
        raster::triangle(uv.map(to_px), size, size, |x, y, w| {
            let p = uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
            let c = (checker(p, cell) * 255.0) as u8;
            img.put_pixel(
                x as u32,
                (size - 1 - y) as u32,
                Rgb([c, c, c.saturating_sub(20)]),
            );
        });
    }
    // Edges used by one uv triangle only are chart borders.
    let mut count = std::collections::HashMap::new();
    for t in &layer.triangles {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    for ((a, b), n) in count {
        if n != 1 {
            continue;
        }
        let (pa, pb) = (
            to_px(layer.coords[a as usize]),
            to_px(layer.coords[b as usize]),
        );
        let steps = ((pb - pa).length().ceil() as usize).max(1);
        for k in 0..=steps {
            let p = pa.lerp(pb, k as f64 / steps as f64);
            let (x, y) = (p.x as usize, size - 1 - (p.y as usize).min(size - 1));
            if x < size {
                img.put_pixel(x as u32, y as u32, Rgb([150, 0, 0]));
            }
        }
    }
    Some(img)
}
