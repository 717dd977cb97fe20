//! The meshes seed 000's Table 1 is measured on, made here at about its
//! tet counts: a kiwi-like ellipsoid (type 2-b, 4,126 tets in the paper)
//! and a layered cake-like slab (1-b, 2,734), with their depth constraints,
//! strokes and a layered exemplar; `organtex bench` and the tests fill
//! them (and the bundled scene's uterine wall, `bench::uterus_wall`).

use glam::DVec3;

use super::{LstOptions, TextureType};
use crate::error::Result;
use crate::mesh::TriMesh;
use crate::progress::Silent;
use crate::synth::volume::Volume;
use crate::tetra::{self, TetMesh, TetOptions};

/// An anchor: its surface, tets and fill options.
pub struct Anchor {
    pub surface: TriMesh,
    pub tets: TetMesh,
    pub options: LstOptions,
}

fn tets(surface: &TriMesh, cells: usize) -> Result<TetMesh> {
    let opts = TetOptions {
        cells: Some(cells),
        ..Default::default()
    };
    tetra::tetrahedralise(surface, &opts, &Silent)
}

/// A kiwi-like ellipsoid, radius 1 and 1.5 long: depth 0 on its skin, 1 on
/// its core (the long axis), a stroke along its length off the core.
pub fn kiwi(kind: TextureType, cells: usize) -> Result<Anchor> {
    let mut surface = crate::mesh::shapes::icosphere(3);
    for p in &mut surface.positions {
        p.z *= 1.5;
    }
    let tets = tets(&surface, cells)?;
    let core = (0..=20)
        .map(|i| DVec3::new(0.0, 0.0, -1.0 + 0.1 * i as f64))
        .collect();
    let options = LstOptions {
        kind,
        scale: 0.9,
        strokes: vec![vec![DVec3::new(0.5, 0.0, -1.0), DVec3::new(0.5, 0.0, 1.0)]],
        depth_outer: surface.positions.clone(),
        depth_inner: core,
        seed: 3,
    };
    Ok(Anchor {
        surface,
        tets,
        options,
    })
}

/// A 2 x 2 x 0.6 slab: depth 0 on its top, 1 on its bottom, a stroke
/// across it.
pub fn cake(kind: TextureType, cells: usize) -> Result<Anchor> {
    let corner = |i: usize| {
        DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -0.3 } else { 0.3 },
        )
    };
    // Two triangles per side, counter-clockwise from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut surface = TriMesh {
        positions: (0..8).map(corner).collect(),
        ..Default::default()
    };
    for q in quads {
        surface.triangles.push([q[0], q[1], q[2]]);
        surface.triangles.push([q[0], q[2], q[3]]);
    }
    let tets = tets(&surface, cells)?;
    let grid = |z: f64| -> Vec<DVec3> {
        (0..=10)
            .flat_map(|i| {
                (0..=10).map(move |j| DVec3::new(-1.0 + 0.2 * i as f64, -1.0 + 0.2 * j as f64, z))
            })
            .collect()
    };
    let options = LstOptions {
        kind,
        scale: 0.9,
        strokes: vec![vec![DVec3::new(-0.8, -0.5, 0.0), DVec3::new(0.8, 0.5, 0.0)]],
        depth_outer: grid(0.3),
        depth_inner: grid(-0.3),
        seed: 3,
    };
    Ok(Anchor {
        surface,
        tets,
        options,
    })
}

/// A 32^3 layered exemplar (the paper's are 64^3): a red skin in its first
/// 3 y slices, grey-green bands below, a little hashed texture throughout.
pub fn layered_exemplar() -> Volume {
    let n = 32;
    let mut voxels = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let h = crate::rng::below(5, &[x as u64, y as u64, z as u64], 24) as u8;
                voxels.push(if y < 3 {
                    [210, 30 + h, 30]
                } else if (y / 4) % 2 == 0 {
                    [90 + h, 140, 90]
                } else {
                    [120, 120 + h, 110]
                });
            }
        }
    }
    Volume {
        size: [n, n, n],
        spacing: 1.0,
        voxels,
    }
}
