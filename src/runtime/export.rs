//! The carved surface as a .glb, for any glTF viewer: the faces a carving
//! exposed textured from the atlas (a primitive per page), the mesh's
//! original boundary faces coloured per vertex from the interior (their
//! real texture is the bake's scene.glb, on the organ's surface mesh).

use glam::{DVec2, DVec3};

use super::carving::Carving;
use crate::error::Result;
use crate::scene::draw::{DrawList, Material, Part, Primitive, Stream};

/// The .glb bytes of `carving`'s surface now.
pub fn surface_glb(carving: &Carving) -> Result<Vec<u8>> {
    let node = carving.node();
    let mesh = node.require_tets()?;
    let atlas = carving.atlas();
    let side = atlas.options().page_size;
    let pages = atlas.pages();
    let mut streams: Vec<Stream> = vec![Stream::default(); pages.len() + 1];
    let surface = carving.surface();
    // Original faces' vertex colours, from the interior.
    let original: Vec<u32> = {
        let mut v: Vec<u32> = surface
            .iter()
            .filter(|(_, _, chart)| chart.is_none())
            .flat_map(|(_, f, _)| *f)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let points: Vec<DVec3> = original
        .iter()
        .map(|&v| mesh.positions[v as usize])
        .collect();
    let colours = node.colours(&points)?;
    for (_, vertices, chart) in &surface {
        let p = vertices.map(|v| mesh.positions[v as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let (stream, uvs, rgb) = match chart {
            Some(c) => {
                let k = pages.binary_search(&c.page).expect("a live chart's page") + 1;
                let uvs = c.uvs(side).map(|[u, v]| DVec2::new(u as f64, v as f64));
                (&mut streams[k], uvs, None)
            }
            None => {
                let rgb = vertices.map(|v| colours[original.binary_search(&v).expect("listed")]);
                (&mut streams[0], [DVec2::splat(0.5); 3], Some(rgb))
            }
        };
        for c in 0..3 {
            let i = stream.vertex(p[c], n, uvs[c], None);
            if let Some(rgb) = rgb {
                stream
                    .colours
                    .extend(rgb[c].map(|x| x as f32 / 255.0).into_iter().chain([1.0]));
            }
            stream.indices.push(i);
        }
    }
    let mut materials = vec![Material::baked(
        "original".into(),
        "white".into(),
        image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4])),
    )];
    for &page in &pages {
        let rgba = atlas.page(page).expect("a live page").to_vec();
        let image = image::RgbaImage::from_raw(side, side, rgba).expect("a page is side^2 RGBA");
        materials.push(Material::baked(
            format!("cut-page-{page}"),
            format!("page-{page}"),
            image,
        ));
    }
    let primitives = streams
        .into_iter()
        .enumerate()
        .filter(|(_, s)| !s.indices.is_empty())
        .map(|(k, stream)| Primitive::opaque(stream, k))
        .collect();
    let list = DrawList {
        materials,
        parts: vec![Part {
            name: node.name.clone(),
            node: 0,
            facet: 0,
            primitives,
        }],
    };
    crate::scene::gltf::encode(&list, &format!("{} carved", node.name), &[])
}
