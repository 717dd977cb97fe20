//! Whether seams and facet borders show: the colour jump across them,
//! sampled on both sides as the output shows it (the baked atlases, or the
//! layers a viewer blends), over the jump beside them on each side.

use serde::Serialize;

use super::atlas::Atlas;
use super::build::BakedNode;
use super::composite::{Compositor, linear_to_srgb};
use glam::DVec2;

use crate::mesh::{EdgeId, HalfedgeId};

/// Contrast figures of a node.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Contrast {
    /// Per facet: the colour jump across its seams over the jump beside
    /// them (1 = seams invisible; `contrast`); `None` without seams.
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

/// Jumps across one kind of edge against the jumps beside it: summed over
/// every point compared, so a long seam weighs each of its points alike
/// and a short one is not decided by a few contrasty edges.
#[derive(Clone, Copy, Default)]
struct Jumps {
    across: f64,
    beside: f64,
    edges: usize,
}

impl Jumps {
    fn add(&mut self, (across, beside): (f64, f64)) {
        self.across += across;
        self.beside += beside;
        self.edges += 1;
    }
    fn ratio(&self) -> Option<f64> {
        (self.edges > 0 && self.beside > 0.0).then(|| self.across / self.beside)
    }
}

/// Where the output's colours are read from.
#[derive(Clone, Copy)]
pub enum Colours<'a> {
    /// Each facet's baked atlas (in facet order), as an engine drawing
    /// atlases shows them.
    Atlases(&'a [Atlas]),
    /// The compositor itself, as a viewer drawing the layered .glb shows
    /// it.
    Layers(&'a Compositor),
}

/// Which facet owns each face of a node, and where its vertices lie in
/// that facet's charts.
pub(super) struct Owners<'a> {
    node: &'a BakedNode,
    /// Per node face: the facet owning it and its face in that facet's
    /// piece (`usize::MAX` for none).
    owner: Vec<(usize, usize)>,
}

impl<'a> Owners<'a> {
    pub(super) fn of(node: &'a BakedNode) -> Owners<'a> {
        let mut owner = vec![(usize::MAX, 0usize); node.mesh.num_faces()];
        for (k, facet) in node.facets.iter().enumerate() {
            for f in 0..facet.piece.own {
                owner[facet.piece.face_origin[f] as usize] = (k, f);
            }
        }
        Owners { node, owner }
    }

    /// The facet owning node face `face` (`usize::MAX` for none).
    pub(super) fn facet(&self, face: usize) -> usize {
        self.owner[face].0
    }

    /// The node's seams and facet borders, in edge order: each as a
    /// halfedge and its twin (which runs the other way), with the facet
    /// whose seam it is (an edge whose ends' uv corners differ between its
    /// two faces) or `None` for a border (an edge whose two faces have
    /// different owners, both owned).
    pub(super) fn joins(&self) -> Vec<(HalfedgeId, HalfedgeId, Option<usize>)> {
        let topo = &self.node.topology;
        let mut joins = Vec::new();
        for e in 0..topo.num_edges() {
            let h = topo.edge_halfedge(EdgeId::from(e));
            let Some(t) = topo.twin(h) else { continue };
            let (fa, fb) = (topo.face(h).idx(), topo.face(t).idx());
            let (ka, kb) = (self.facet(fa), self.facet(fb));
            if ka == usize::MAX || kb == usize::MAX {
                continue;
            }
            let ends = topo.edge_vertices(EdgeId::from(e)).map(|v| v.0);
            if ka != kb {
                joins.push((h, t, None));
            } else if ends.iter().any(|&v| self.uv(fa, v).0 != self.uv(fb, v).0) {
                joins.push((h, t, Some(ka)));
            }
        }
        joins
    }

    /// Uv corner and uv of node vertex `v` in the owner's piece of node
    /// face `face`.
    pub(super) fn uv(&self, face: usize, v: u32) -> (u32, DVec2) {
        let (k, f) = self.owner[face];
        let piece = &self.node.facets[k].piece;
        let layer = piece.mesh.uvs.as_ref().expect("unwrapped");
        let i = (0..3)
            .find(|&i| piece.vertex_origin[piece.mesh.triangles[f][i] as usize] == v)
            .expect("a piece face is its node face");
        let c = layer.triangles[f][i];
        (c, layer.coords[c as usize])
    }
}

/// How many points along an edge its sides are compared at (evenly, from
/// a tenth to nine tenths of it). On the default scene's 5-unit polyp
/// seam, layered, 20 points rather than 5 took the spread of its figure
/// over 18 texture placements from about 0.08 to 0.06.
const ALONG: usize = 16;

/// The contrast figures of `node`, for its seams (an edge whose ends'
/// uvs differ between its two faces) and facet borders (an edge whose two
/// faces have different owners). Each such edge is read at `ALONG` points
/// along it, on both sides at a distance `d` from it towards each face's
/// third corner and again at `3 d` (in the atlas of the facet owning the
/// face, or from the layers): the jump across the edge (between the two
/// points at `d`, `2 d` apart) is set against the jumps beside it on each
/// side (from `d` to `3 d`: the same distance, the same direction, the
/// same textures, stretch and blend). For a continuous colour the jump
/// across is at most the jumps beside (the triangle inequality), so a
/// seam or border without a step reads 1 or less whatever the texture's
/// grain; one with a step reads its step over the tissue's local change.
/// `d` is a quarter texel of the finest texture shown (the layers'
/// tissues, or the atlases), so the four points lie within about one
/// bilinear cell of what is shown, and at most a sixth of each face's
/// height, so the farther point stays in its face. At half a texel the
/// points straddled the kinks of the bilinear cells (the atlas's own, or a
/// mip level's): the default scene's polyp seam in the atlas read 1.19,
/// and 0.84 with its texture moved by one texel; at a quarter, 0.92-1.15
/// over 19 placements. Layered, at a quarter, 1.01-1.27: its cut's branch
/// of one edge to a terminal leaves a real step (`blend::seam`).
///
/// The figure it replaced set the jump across seams, at `2 d` = four
/// texels, against the ordinary edges of the faces along them: beyond the
/// grain of a fine tissue, points that far apart are unrelated, so a seam
/// with no blend at all read little above 1 (the default scene's polyp
/// seam, unblended, 1.06 to 1.92 over 18 texture placements in the atlas,
/// against 3.6 to 6.0 now), and the figure of a blended one went from 0.80
/// to 1.31 with the placement alone.
pub fn contrast(node: &BakedNode, colours: Colours) -> Contrast {
    let topo = &node.topology;
    let owners = Owners::of(node);
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
    // The height of `h`'s face over h's edge.
    let height = |h: HalfedgeId| {
        let face = topo.face(h).idx();
        let i = h.idx() % 3;
        let p = node.mesh.corners(face);
        let edge = (p[(i + 1) % 3] - p[i]).length();
        2.0 * node.mesh.face_area(face) / edge.max(1e-300)
    };
    // The colour (sRGB, 0-255) on `h`'s side of its edge, `t` of the way
    // along it from h's origin, `dist` in towards the third corner.
    let side = |h: HalfedgeId, t: f64, dist: f64| {
        let face = topo.face(h).idx();
        let i = h.idx() % 3;
        let third = dist / height(h).max(1e-300);
        let mut w = [third; 3];
        w[i] = (1.0 - third) * (1.0 - t);
        w[(i + 1) % 3] = (1.0 - third) * t;
        match colours {
            Colours::Atlases(atlases) => {
                let tri = node.mesh.triangles[face];
                let uv = (0..3).map(|k| owners.uv(face, tri[k]).1 * w[k]).sum();
                atlases[owners.facet(face)].sample(uv)
            }
            Colours::Layers(compositor) => compositor
                .colour(face, w)
                .map(|c| linear_to_srgb(c) as f64 * 255.0),
        }
    };
    // The jumps across `h`'s edge and beside it (the twin `t` runs the
    // other way), summed along it.
    let jumps = |h: HalfedgeId, t: HalfedgeId| {
        let d = (0.25 * texel).min(height(h) / 6.0).min(height(t) / 6.0);
        let (mut across, mut beside) = (0.0, 0.0);
        for j in 0..ALONG {
            let a = 0.1 + 0.8 * (j as f64 + 0.5) / ALONG as f64;
            let (p, q) = (side(h, a, d), side(t, 1.0 - a, d));
            across += jump(p, q);
            beside += 0.5 * (jump(p, side(h, a, 3.0 * d)) + jump(q, side(t, 1.0 - a, 3.0 * d)));
        }
        (across, beside)
    };
    let mut seams = vec![Jumps::default(); node.facets.len()];
    let mut border = Jumps::default();
    for (h, t, seam) in owners.joins() {
        match seam {
            Some(k) => seams[k].add(jumps(h, t)),
            None => border.add(jumps(h, t)),
        }
    }
    Contrast {
        seams: seams.iter().map(Jumps::ratio).collect(),
        borders: border.ratio(),
        border_edges: border.edges,
    }
}
