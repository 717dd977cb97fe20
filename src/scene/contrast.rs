//! Whether seams and facet borders show: the colour jump across them,
//! sampled on both sides as the output shows it (the baked atlases, or the
//! layers a viewer blends), over the jump across ordinary edges.

use serde::Serialize;

use super::atlas::Atlas;
use super::build::BakedNode;
use super::composite::{Compositor, linear_to_srgb};
use crate::mesh::{EdgeId, HalfedgeId};

/// Contrast figures of a node.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Contrast {
    /// Per facet: median colour jump across its seams over that across the
    /// ordinary edges of the faces along them (1 = seams invisible); `None`
    /// without seams.
    pub seams: Vec<Option<f64>>,
    /// The same across facet borders.
    pub borders: Option<f64>,
    /// How many edges the border figure is over (a short border gives a
    /// noisy figure).
    pub border_edges: usize,
}

fn jump(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>() / 3.0
}

/// Jumps across one kind of edge, summarised by their median: a seam shows
/// as a jump all along it, while a contrasty texture feature that happens
/// to cross a few edges does not make a seam visible (with a few hundred
/// seam edges, three such edges move the mean by half the reference).
#[derive(Clone, Default)]
struct Jumps(Vec<f64>);

impl Jumps {
    fn add(&mut self, x: f64) {
        self.0.push(x);
    }
    fn median(&self) -> Option<f64> {
        let mut v = self.0.clone();
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| v[v.len() / 2])
    }
    fn ratio(&self, base: &Jumps) -> Option<f64> {
        let (s, b) = (self.median()?, base.median()?);
        (b > 0.0).then(|| s / b)
    }
}

/// Where contrast figures read colours from.
#[derive(Clone, Copy)]
pub enum Colours<'a> {
    /// Each facet's baked atlas (in facet order), as an engine drawing
    /// atlases shows them.
    Atlases(&'a [Atlas]),
    /// The compositor itself, as a viewer drawing the layered .glb shows
    /// it.
    Layers(&'a Compositor),
}

/// Where along an edge its two sides are compared.
const ALONG: [f64; 5] = [0.2, 0.35, 0.5, 0.65, 0.8];

/// The contrast figures of `node`. Every interior edge of the node is
/// sampled on both sides at five points along it, each a tenth of the
/// node's median edge length (at most two texels of the finest texture
/// shown) in from the edge, towards the face's third corner (in the atlas
/// of the facet owning that face, or from the layers); the edge is a
/// border (owners differ), a seam (its ends' uvs differ between the two
/// faces) or ordinary. The reference for seams and borders is the ordinary
/// edges of the faces along them: the same textures, layers and sampling
/// scale, so only the seam or border itself can take the figure above 1 (a
/// facet-wide reference would count a seam that passes under a contrasty
/// neighbour's ring as visible).
pub fn contrast(node: &BakedNode, colours: Colours) -> Contrast {
    let topo = &node.topology;
    // Owner facet and piece face of every node face.
    let mut owner = vec![(usize::MAX, 0usize); node.mesh.num_faces()];
    for (k, facet) in node.facets.iter().enumerate() {
        for f in 0..facet.piece.own {
            owner[facet.piece.face_origin[f] as usize] = (k, f);
        }
    }
    // Uv corner and uv of node vertex `v` in the owner's piece of node face
    // `face`.
    let uv_of = |face: usize, v: u32| {
        let (k, f) = owner[face];
        let piece = &node.facets[k].piece;
        let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
        let i = (0..3)
            .find(|&i| piece.vertex_origin[piece.mesh.triangles[f][i] as usize] == v)
            .expect("a piece face is its node face");
        let c = layer.triangles[f][i];
        (c, layer.coords[c as usize])
    };
    // Every edge's sides are compared at the same distance from it.
    // Insets proportional to each face's height compared points farther
    // apart across a facet border (the faces along it are tall) than
    // across the ordinary edges of those faces: the default scene's atlas
    // border figure sat near 1.12, from 1.02 to 1.22 with the tissues'
    // offsets alone, for a blend with no step (at one distance, with the
    // atlas fixes that came with it: from 1.00 to 1.06).
    let mut lengths: Vec<f64> = (0..topo.num_edges())
        .map(|e| {
            let [a, b] = topo.edge_vertices(EdgeId::from(e));
            (node.mesh.positions[a.idx()] - node.mesh.positions[b.idx()]).length()
        })
        .collect();
    lengths.sort_by(f64::total_cmp);
    // At most two texels of what the output shows in from the edge, so
    // the points compared across it are within the tissue's grain. The MNI
    // brain's serosa has 0.08 mm texels: its pixels 7 apart differ by 6.4
    // of 255 on average, any two by 6.7, so at a tenth of its 2.6 mm edges
    // a seam between unrelated parts of the texture measured the same as
    // an ordinary edge (1.00 unblended; 1.25 at two texels). One texel was
    // too fine: where a stalk's chart stretches one way, an edge's two
    // points are more texels apart across it than along it, and the
    // fundus polyp's 24 border edges read 1.43 at one texel, 1.25 at half,
    // 1.03 at two, a border with no step at all.
    let texel = match colours {
        Colours::Atlases(atlases) => atlases
            .iter()
            .map(Atlas::texel_size)
            .fold(f64::INFINITY, f64::min),
        Colours::Layers(compositor) => compositor
            .looks
            .iter()
            .map(|look| look.texel_size(&compositor.textures))
            .fold(f64::INFINITY, f64::min),
    };
    let inset = (0.1 * lengths.get(lengths.len() / 2).copied().unwrap_or(0.0)).min(2.0 * texel);
    // The colour (sRGB, 0-255) on `h`'s side of its edge, `t` of the way
    // along it from h's origin, `inset` in towards the third corner (at
    // most half way).
    let side = |h: HalfedgeId, t: f64| {
        let face = topo.face(h).idx();
        let i = h.idx() % 3;
        let p = node.mesh.corners(face);
        let edge = (p[(i + 1) % 3] - p[i]).length();
        let height = 2.0 * node.mesh.face_area(face) / edge.max(1e-300);
        let third = (inset / height.max(1e-300)).min(0.5);
        let mut w = [third; 3];
        w[i] = (1.0 - third) * (1.0 - t);
        w[(i + 1) % 3] = (1.0 - third) * t;
        match colours {
            Colours::Atlases(atlases) => {
                let tri = node.mesh.triangles[face];
                let uv = (0..3).map(|k| uv_of(face, tri[k]).1 * w[k]).sum();
                atlases[owner[face].0].sample(uv)
            }
            Colours::Layers(compositor) => compositor
                .colour(face, w)
                .map(|c| linear_to_srgb(c) as f64 * 255.0),
        }
    };
    // The jump across `h`'s edge, averaged over five points along it (the
    // twin runs the other way), so one texture feature weighs less.
    let across = |h: HalfedgeId, t: HalfedgeId| {
        ALONG
            .iter()
            .map(|&a| jump(side(h, a), side(t, 1.0 - a)))
            .sum::<f64>()
            / ALONG.len() as f64
    };
    let n = node.facets.len();
    let mut seam = vec![Jumps::default(); n];
    let mut border = Jumps::default();
    // Faces along seams and borders, and the ordinary edges: each figure's
    // reference is the ordinary edges of the faces along what it measures.
    let (mut at_seam, mut at_border) = (
        vec![false; node.mesh.num_faces()],
        vec![false; node.mesh.num_faces()],
    );
    let mut ordinary = Vec::new();
    for e in 0..topo.num_edges() {
        let h = topo.edge_halfedge(EdgeId::from(e));
        let Some(t) = topo.twin(h) else { continue };
        let (fa, fb) = (topo.face(h).idx(), topo.face(t).idx());
        let d = across(h, t);
        let k = owner[fa].0;
        let ends = topo.edge_vertices(EdgeId::from(e)).map(|v| v.0);
        if k != owner[fb].0 {
            border.add(d);
            (at_border[fa], at_border[fb]) = (true, true);
        } else if ends.iter().any(|&v| uv_of(fa, v).0 != uv_of(fb, v).0) {
            seam[k].add(d);
            (at_seam[fa], at_seam[fb]) = (true, true);
        } else {
            ordinary.push((fa, fb, d));
        }
    }
    let mut near_seam = vec![Jumps::default(); n];
    let mut near_border = Jumps::default();
    for (fa, fb, d) in ordinary {
        if at_seam[fa] || at_seam[fb] {
            near_seam[owner[fa].0].add(d);
        }
        if at_border[fa] || at_border[fb] {
            near_border.add(d);
        }
    }
    Contrast {
        seams: seam
            .iter()
            .zip(&near_seam)
            .map(|(s, p)| s.ratio(p))
            .collect(),
        borders: border.ratio(&near_border),
        border_edges: border.0.len(),
    }
}
