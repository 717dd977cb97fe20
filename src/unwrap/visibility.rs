//! How visible each vertex and edge is (seed 004, section 3.4.1; Seamster):
//! the fraction of views from which it is seen, with depth-buffered
//! rendering. Two kinds of viewpoint:
//! - `Viewpoints::Orbit`: orthographic views from directions spread evenly
//!   over the sphere (a Fibonacci lattice), for organs seen from outside;
//! - `Viewpoints::Cameras`: perspective views from given positions (an
//!   endoscope inside a cavity), each looking all around (a cube map of six
//!   90-degree views).
//!
//! A point counts as seen in a view when its depth is within half a
//! pixel's worth of the depth buffer at its pixel, or the face drawn there
//! is one of its own (`DepthBuffer::sees`). Views
//! render in parallel; counts are integers, so the result does not depend
//! on the thread count.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::mesh::{EdgeId, Topology, TriMesh, VertexId};
use crate::progress::Progress;
use crate::raster;

#[derive(Clone, Debug)]
pub enum Viewpoints {
    /// `views` orthographic directions on a Fibonacci sphere.
    Orbit { views: usize },
    /// Perspective cube maps from these positions.
    Cameras(Vec<DVec3>),
}

#[derive(Clone, Debug)]
pub struct Visibility {
    /// Fraction of views that see each vertex.
    pub vertex: Vec<f32>,
    /// Fraction of views that see each edge's midpoint, by `EdgeId`.
    pub edge: Vec<f32>,
    pub views: usize,
}

impl Visibility {
    /// The visibility of a part of the mesh `whole` was built for: `part`'s
    /// vertex `v` is `origin[v]` there, and its edges are the edges between
    /// the matching vertices.
    pub fn restrict(&self, whole: &Topology, origin: &[u32], part: &Topology) -> Visibility {
        let vertex = |v: VertexId| VertexId(origin[v.idx()]);
        Visibility {
            vertex: origin.iter().map(|&v| self.vertex[v as usize]).collect(),
            edge: (0..part.num_edges())
                .map(|e| {
                    let [a, b] = part.edge_vertices(EdgeId::from(e)).map(vertex);
                    let e = whole
                        .edge_between(a, b)
                        .expect("a part's edges are edges of the whole");
                    self.edge[e.idx()]
                })
                .collect(),
            views: self.views,
        }
    }
}

/// `n` unit directions spread evenly over the sphere (Fibonacci lattice).
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * i as f64;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// A projection of world points to pixel coordinates and a depth (smaller
/// is nearer); `None` when the point is outside the view.
pub(crate) trait Camera: Sync {
    fn resolution(&self) -> usize;
    /// Pixel position and depth of a point in front of the camera.
    fn project(&self, p: DVec3) -> Option<(DVec2, f64)>;
    /// Whether depths interpolate as 1/z (perspective) or linearly.
    fn perspective(&self) -> bool;
    /// The direction the camera looks along (through the image's centre).
    fn forward(&self) -> DVec3;
    /// World size of a pixel at `depth`.
    fn pixel_size(&self, depth: f64) -> f64;

    /// Whether the triangle's corners, as given, can be projected (all in
    /// front of the near plane).
    fn in_front(&self, p: DVec3) -> bool;
}

pub(crate) struct Orthographic {
    right: DVec3,
    up: DVec3,
    pub(crate) forward: DVec3,
    center: DVec3,
    radius: f64,
    res: usize,
}

impl Orthographic {
    /// Looking at the sphere (`center`, `radius`) from direction `dir`,
    /// `res` pixels square.
    pub(crate) fn from_direction(dir: DVec3, center: DVec3, radius: f64, res: usize) -> Self {
        let (right, up) = basis(dir);
        Orthographic {
            right,
            up,
            forward: -dir,
            center,
            radius,
            res,
        }
    }
}

impl Camera for Orthographic {
    fn resolution(&self) -> usize {
        self.res
    }
    fn project(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let d = p - self.center;
        let scale = self.res as f64 / (2.0 * self.radius);
        let px = DVec2::new(
            d.dot(self.right) + self.radius,
            d.dot(self.up) + self.radius,
        ) * scale;
        Some((px, d.dot(self.forward)))
    }
    fn perspective(&self) -> bool {
        false
    }
    fn forward(&self) -> DVec3 {
        self.forward
    }
    fn pixel_size(&self, _depth: f64) -> f64 {
        2.0 * self.radius / self.res as f64
    }

    fn in_front(&self, _p: DVec3) -> bool {
        true
    }
}

/// One 90-degree face of a cube map around `origin`.
struct CubeFace {
    origin: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    near: f64,
    res: usize,
}

impl Camera for CubeFace {
    fn resolution(&self) -> usize {
        self.res
    }
    fn project(&self, p: DVec3) -> Option<(DVec2, f64)> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if z < self.near {
            return None;
        }
        let half = self.res as f64 / 2.0;
        Some((
            DVec2::new(
                d.dot(self.right) / z * half + half,
                d.dot(self.up) / z * half + half,
            ),
            z,
        ))
    }
    fn perspective(&self) -> bool {
        true
    }
    fn forward(&self) -> DVec3 {
        self.forward
    }
    fn pixel_size(&self, depth: f64) -> f64 {
        2.0 * depth / self.res as f64
    }

    fn in_front(&self, p: DVec3) -> bool {
        (p - self.origin).dot(self.forward) >= self.near
    }
}

/// Nearest depth per pixel, and the face it belongs to (`u32::MAX` for
/// background).
pub(crate) struct DepthBuffer {
    pub res: usize,
    pub depth: Vec<f32>,
    pub face: Vec<u32>,
}

impl DepthBuffer {
    /// Every face of `mesh` seen by `camera`.
    pub(crate) fn render(camera: &dyn Camera, mesh: &TriMesh) -> DepthBuffer {
        let projected: Vec<_> = mesh.positions.iter().map(|&p| camera.project(p)).collect();
        let mut buffer = DepthBuffer::empty();
        buffer.draw(camera, mesh, &projected, |_| true);
        buffer
    }

    /// A buffer of no pixels, for `draw` to size.
    pub(crate) fn empty() -> DepthBuffer {
        DepthBuffer {
            res: 0,
            depth: Vec::new(),
            face: Vec::new(),
        }
    }

    /// Render into this buffer's memory, every vertex already projected
    /// (`None` when behind a perspective camera's near plane), only the
    /// faces `drawn` keeps: a view after view reuses the buffer rather than
    /// fault in new pages for every one.
    pub(crate) fn draw(
        &mut self,
        camera: &dyn Camera,
        mesh: &TriMesh,
        projected: &[Option<(DVec2, f64)>],
        drawn: impl Fn(usize) -> bool,
    ) {
        let res = camera.resolution();
        self.res = res;
        self.depth.clear();
        self.depth.resize(res * res, f32::INFINITY);
        self.face.clear();
        self.face.resize(res * res, u32::MAX);
        let (depth, face) = (&mut self.depth, &mut self.face);
        let perspective = camera.perspective();
        let mut draw = |f: usize, [a, b, c]: [(DVec2, f64); 3]| {
            let z = [a.1, b.1, c.1];
            raster::triangle([a.0, b.0, c.0], res, res, |x, y, w| {
                let d = if perspective {
                    1.0 / (w[0] / z[0] + w[1] / z[1] + w[2] / z[2])
                } else {
                    w[0] * z[0] + w[1] * z[1] + w[2] * z[2]
                } as f32;
                let i = y * res + x;
                if d < depth[i] {
                    depth[i] = d;
                    face[i] = f as u32;
                }
            });
        };
        for (f, t) in mesh.triangles.iter().enumerate() {
            if !drawn(f) {
                continue;
            }
            if let [Some(a), Some(b), Some(c)] = t.map(|v| projected[v as usize]) {
                draw(f, [a, b, c]);
            } else {
                for tri in clip_to_front(camera, mesh.corners(f)) {
                    if let [Some(a), Some(b), Some(c)] = tri.map(|p| camera.project(p)) {
                        draw(f, [a, b, c]);
                    }
                }
            }
        }
    }

    /// Whether a point on the surface, seen at pixel position and depth
    /// `at`, is the nearest thing at its pixel: within half a pixel of the
    /// depth drawn there (a flat neighbour), or the face drawn there is one
    /// of its own. Comparing faces rather than adding slope-dependent depth
    /// slack keeps points just past a silhouette from counting as seen.
    /// `slack(depth)` is half a pixel's size at that depth.
    pub(crate) fn sees(
        &self,
        at: (DVec2, f64),
        slack: impl Fn(f64) -> f64,
        own: impl Fn(u32) -> bool,
    ) -> Option<bool> {
        let (px, d) = at;
        // A point on the border between two cube faces may land a rounding
        // error outside both: allow half a pixel.
        let n = self.res as f64;
        if px.x < -0.5 || px.y < -0.5 || px.x >= n + 0.5 || px.y >= n + 0.5 {
            return None;
        }
        let clamp = |x: f64| (x.max(0.0) as usize).min(self.res - 1);
        let i = clamp(px.y) * self.res + clamp(px.x);
        Some(d <= self.depth[i] as f64 + slack(d) || own(self.face[i]))
    }
}

/// The parts of a triangle in front of a perspective camera's near plane
/// (Sutherland-Hodgman against one plane: at most a quad, two triangles).
fn clip_to_front(camera: &dyn Camera, corners: [DVec3; 3]) -> Vec<[DVec3; 3]> {
    let inside = corners.map(|p| camera.in_front(p));
    let mut poly: Vec<DVec3> = Vec::with_capacity(4);
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        if inside[i] {
            poly.push(p);
        }
        if inside[i] != inside[(i + 1) % 3] {
            // Bisect for the crossing: the camera only answers in/out.
            let (mut lo, mut hi) = if inside[i] { (p, q) } else { (q, p) };
            for _ in 0..40 {
                let mid = (lo + hi) / 2.0;
                if camera.in_front(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            poly.push(lo);
        }
    }
    (1..poly.len().saturating_sub(1))
        .map(|k| [poly[0], poly[k], poly[k + 1]])
        .collect()
}

/// Visibility of every vertex and edge of `mesh` from `viewpoints`.
pub fn compute(
    mesh: &TriMesh,
    topo: &Topology,
    viewpoints: &Viewpoints,
    progress: &dyn Progress,
) -> Visibility {
    let (lo, hi) = mesh.bounding_box().unwrap_or((DVec3::ZERO, DVec3::ONE));
    let center = (lo + hi) / 2.0;
    let radius = ((hi - lo).length() / 2.0).max(1e-12);
    let mean_edge = mean_edge_length(mesh, topo).max(radius * 1e-4);
    // Pixels about half an edge wide, so each vertex has its own pixel.
    let res = ((2.0 * radius / (0.5 * mean_edge)).ceil() as usize).clamp(64, 1024);
    let edge_ends: Vec<[usize; 2]> = (0..topo.num_edges())
        .map(|e| topo.edge_vertices(EdgeId::from(e)).map(|v| v.idx()))
        .collect();
    let midpoints: Vec<DVec3> = edge_ends
        .iter()
        .map(|&[a, b]| (mesh.positions[a] + mesh.positions[b]) / 2.0)
        .collect();

    // Each viewpoint: the cameras that make it up.
    let viewpoint_cameras: Vec<Vec<Box<dyn Camera>>> = match viewpoints {
        Viewpoints::Orbit { views } => fibonacci_sphere((*views).max(1))
            .into_iter()
            .map(|dir| {
                vec![
                    Box::new(Orthographic::from_direction(dir, center, radius, res))
                        as Box<dyn Camera>,
                ]
            })
            .collect(),
        Viewpoints::Cameras(positions) => positions
            .iter()
            .map(|&origin| {
                [
                    DVec3::X,
                    -DVec3::X,
                    DVec3::Y,
                    -DVec3::Y,
                    DVec3::Z,
                    -DVec3::Z,
                ]
                .into_iter()
                .map(|forward| {
                    let (right, up) = basis(-forward);
                    Box::new(CubeFace {
                        origin,
                        right,
                        up,
                        forward,
                        near: radius * 1e-4,
                        res: res.min(512),
                    }) as Box<dyn Camera>
                })
                .collect()
            })
            .collect(),
    };
    progress.stage("visibility", viewpoint_cameras.len() as u64);

    // Each vertex's faces and each edge's two (a boundary edge's one
    // twice), listed once: every view asks for them of whatever it hides.
    let mut fan_start = Vec::with_capacity(mesh.num_vertices() + 1);
    let mut fan_faces = Vec::with_capacity(3 * mesh.num_faces());
    fan_start.push(0);
    for v in 0..mesh.num_vertices() {
        fan_faces.extend(topo.outgoing(VertexId::from(v)).map(|h| topo.face(h).0));
        fan_start.push(fan_faces.len());
    }
    let vertex_faces = |v: usize| &fan_faces[fan_start[v]..fan_start[v + 1]];
    let edge_sides: Vec<[u32; 2]> = (0..topo.num_edges())
        .map(|e| {
            let h = topo.edge_halfedge(EdgeId::from(e));
            let f = topo.face(h).0;
            [f, topo.twin(h).map_or(f, |t| topo.face(t).0)]
        })
        .collect();
    let outward = outward_normals(mesh, topo);
    let nv = mesh.num_vertices();
    let ne = topo.num_edges();
    // One viewpoint: which vertices and edges any of its cameras sees, in
    // `seen` (reused from view to view, as the buffer is: fresh pages for
    // every view cost more than drawing it).
    let render_viewpoint = |cams: &Vec<Box<dyn Camera>>,
                            buffer: &mut DepthBuffer,
                            seen: &mut Seen| {
        let Seen {
            projected,
            vertex: vertex_seen,
            edge: edge_seen,
        } = seen;
        vertex_seen.clear();
        vertex_seen.resize(nv, false);
        edge_seen.clear();
        edge_seen.resize(ne, false);
        for camera in cams {
            let camera = camera.as_ref();
            projected.clear();
            projected.extend(mesh.positions.iter().map(|&p| camera.project(p)));
            // Back faces of closed pieces are never nearest from outside
            // (`outward_normals`); a perspective camera may be inside one.
            let (perspective, forward) = (camera.perspective(), camera.forward());
            buffer.draw(camera, mesh, projected, |f| {
                perspective || outward[f].dot(forward) <= 0.0
            });
            // Half a pixel, the same at every depth in an orthographic view.
            let flat = 0.5 * camera.pixel_size(1.0);
            let slack = |d: f64| {
                if perspective {
                    0.5 * camera.pixel_size(d)
                } else {
                    flat
                }
            };
            for (v, seen) in vertex_seen.iter_mut().enumerate() {
                if !*seen && let Some(at) = projected[v] {
                    *seen = buffer.sees(at, slack, |f| vertex_faces(v).contains(&f)) == Some(true);
                }
            }
            for (e, seen) in edge_seen.iter_mut().enumerate() {
                if *seen {
                    continue;
                }
                // Orthographic projection is affine: the midpoint projects to
                // the mean of its ends.
                let [a, b] = edge_ends[e];
                let at = if perspective {
                    camera.project(midpoints[e])
                } else {
                    projected[a]
                        .zip(projected[b])
                        .map(|(p, q)| ((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0))
                };
                if let Some(at) = at {
                    *seen = buffer.sees(at, slack, |f| edge_sides[e].contains(&f)) == Some(true);
                }
            }
        }
        progress.advance(1);
    };
    let (vertex_hits, edge_hits) = viewpoint_cameras
        .par_iter()
        .fold(
            || {
                let counts = (vec![0u32; nv], vec![0u32; ne]);
                (counts, DepthBuffer::empty(), Seen::default())
            },
            |((mut vc, mut ec), mut buffer, mut seen), cams| {
                render_viewpoint(cams, &mut buffer, &mut seen);
                add_hits(&mut vc, &seen.vertex);
                add_hits(&mut ec, &seen.edge);
                ((vc, ec), buffer, seen)
            },
        )
        .map(|(counts, _, _)| counts)
        .reduce(
            || (vec![0u32; nv], vec![0u32; ne]),
            |(mut va, mut ea), (vb, eb)| {
                va.iter_mut().zip(&vb).for_each(|(a, b)| *a += b);
                ea.iter_mut().zip(&eb).for_each(|(a, b)| *a += b);
                (va, ea)
            },
        );
    let views = viewpoint_cameras.len().max(1);
    let fraction = |c: &u32| *c as f32 / views as f32;
    Visibility {
        vertex: vertex_hits.iter().map(fraction).collect(),
        edge: edge_hits.iter().map(fraction).collect(),
        views,
    }
}

/// One viewpoint's scratch: its vertices projected by the camera drawn
/// last, and which vertices and edges its cameras see.
#[derive(Default)]
struct Seen {
    projected: Vec<Option<(DVec2, f64)>>,
    vertex: Vec<bool>,
    edge: Vec<bool>,
}

/// Every face's normal (unnormalised), turned to point out of the volume
/// its piece encloses, where the piece is closed; zero in open pieces.
///
/// Along a ray from outside, the first hit on a closed surface that does
/// not cross itself enters the volume it bounds, through a face turned
/// towards the ray; so an orthographic view of closed pieces need not draw
/// the faces turned away (half of them), and the depth buffer's nearest
/// depths stay the same (where two faces tie at a pixel, which one is
/// drawn may change). A piece's signed volume says which way its faces
/// turn, so an inside-out piece, or a void's shell, is culled the right
/// way. Open pieces are drawn whole: their back faces can be seen through
/// a hole. A closed piece that crosses itself (a fold through its own
/// surface) can lose the few pixels where a back face is nearest.
fn outward_normals(mesh: &TriMesh, topo: &Topology) -> Vec<DVec3> {
    let components = crate::mesh::Components::find(topo);
    let mut closed = vec![true; components.count];
    let mut volume = vec![0.0; components.count];
    // Signed volumes about a vertex of each piece, so that a piece far from
    // the origin does not lose its sum to cancellation.
    let mut anchor: Vec<Option<DVec3>> = vec![None; components.count];
    for (f, &c) in components.of_face.iter().enumerate() {
        let o = *anchor[c as usize].get_or_insert(mesh.positions[mesh.triangles[f][0] as usize]);
        let [a, b, p] = mesh.corners(f).map(|x| x - o);
        volume[c as usize] += a.dot(b.cross(p));
    }
    for h in topo.boundary_loops().iter().flatten() {
        closed[components.of_face[topo.face(*h).idx()] as usize] = false;
    }
    components
        .of_face
        .iter()
        .enumerate()
        .map(|(f, &c)| {
            let c = c as usize;
            if closed[c] && volume[c] != 0.0 {
                let [a, b, p] = mesh.corners(f);
                (b - a).cross(p - a) * volume[c].signum()
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

fn add_hits(counts: &mut [u32], hits: &[bool]) {
    for (c, &h) in counts.iter_mut().zip(hits) {
        *c += h as u32;
    }
}

/// Two unit vectors completing `dir` to a right-handed orthonormal basis.
fn basis(dir: DVec3) -> (DVec3, DVec3) {
    let helper = if dir.z.abs() < 0.9 {
        DVec3::Z
    } else {
        DVec3::X
    };
    let right = helper.cross(dir).normalize();
    let up = dir.cross(right);
    (right, up)
}

pub fn mean_edge_length(mesh: &TriMesh, topo: &Topology) -> f64 {
    let total: f64 = (0..topo.num_edges())
        .map(|e| {
            let [a, b] = topo.edge_vertices(EdgeId::from(e));
            (mesh.positions[a.idx()] - mesh.positions[b.idx()]).length()
        })
        .sum();
    total / topo.num_edges().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::{icosphere, open_cylinder};
    use crate::progress::Silent;

    #[test]
    fn fibonacci_directions_are_unit_and_balanced() {
        let dirs = fibonacci_sphere(128);
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-12));
        assert!(
            dirs.iter().sum::<DVec3>().length() < 1.0,
            "no side favoured"
        );
    }

    #[test]
    fn a_convex_sphere_shows_each_point_to_half_the_orbit() {
        // A polyhedral vertex is seen wherever one of its faces faces the
        // view, a little more than half the sphere on a fine mesh.
        let mesh = icosphere(5);
        let topo = Topology::build(&mesh).unwrap();
        let vis = compute(&mesh, &topo, &Viewpoints::Orbit { views: 200 }, &Silent);
        for &v in &vis.vertex {
            assert!((0.42..=0.58).contains(&v), "visibility {v}");
        }
    }

    /// A unit sphere, and one of `scale` inside it, turned inside out
    /// (a void's shell) when `void`.
    fn nested_spheres(scale: f64, void: bool) -> TriMesh {
        let outer = icosphere(3);
        let n = outer.num_vertices() as u32;
        let mut positions = outer.positions.clone();
        positions.extend(outer.positions.iter().map(|p| *p * scale));
        let mut triangles = outer.triangles.clone();
        triangles.extend(outer.triangles.iter().map(|t| {
            let t = t.map(|v| v + n);
            if void { [t[0], t[2], t[1]] } else { t }
        }));
        TriMesh::new(positions, triangles)
    }

    #[test]
    fn culled_back_faces_hide_nothing_and_expose_nothing() {
        // Closed pieces are drawn without their back faces: a shell inside
        // another stays unseen, whichever way it is turned, and the outer
        // one is seen as it is alone.
        let alone = icosphere(3);
        let alone_vis = compute(
            &alone,
            &Topology::build(&alone).unwrap(),
            &Viewpoints::Orbit { views: 64 },
            &Silent,
        );
        for void in [false, true] {
            let mesh = nested_spheres(0.5, void);
            let topo = Topology::build(&mesh).unwrap();
            let vis = compute(&mesh, &topo, &Viewpoints::Orbit { views: 64 }, &Silent);
            let n = alone.num_vertices();
            assert!(vis.vertex[n..].iter().all(|&v| v == 0.0), "void {void}");
            // The outer sphere's own resolution differs (the mean edge is
            // the pair's), so its figures are compared in the mean.
            let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
            assert!(
                (mean(&vis.vertex[..n]) - mean(&alone_vis.vertex)).abs() < 0.02,
                "void {void}: {} against {}",
                mean(&vis.vertex[..n]),
                mean(&alone_vis.vertex)
            );
        }
        // Turned inside out, a closed sphere is seen as before.
        let mut inside_out = alone.clone();
        for t in &mut inside_out.triangles {
            t.swap(1, 2);
        }
        let vis = compute(
            &inside_out,
            &Topology::build(&inside_out).unwrap(),
            &Viewpoints::Orbit { views: 64 },
            &Silent,
        );
        let same = vis
            .vertex
            .iter()
            .zip(&alone_vis.vertex)
            .filter(|(a, b)| a == b)
            .count();
        assert!(same * 100 >= 99 * alone.num_vertices(), "{same} the same");
    }

    #[test]
    fn a_camera_inside_a_closed_cylinder_sees_the_wall_and_an_outside_orbit_does_not_see_in() {
        // An open tube seen from outside: the inner wall is hidden from most
        // directions except along the axis.
        let mesh = open_cylinder(1.0, 8.0, 48, 32);
        let topo = Topology::build(&mesh).unwrap();
        let inside = compute(
            &mesh,
            &topo,
            &Viewpoints::Cameras(vec![DVec3::new(0.0, 0.0, 4.0)]),
            &Silent,
        );
        let hidden: Vec<_> = inside
            .vertex
            .iter()
            .enumerate()
            .filter(|(_, v)| **v < 1.0)
            .map(|(i, _)| mesh.positions[i])
            .collect();
        assert!(
            hidden.is_empty(),
            "every wall point faces the axis: {hidden:?}"
        );
        let orbit = compute(&mesh, &topo, &Viewpoints::Orbit { views: 64 }, &Silent);
        let mean: f32 = orbit.vertex.iter().sum::<f32>() / orbit.vertex.len() as f32;
        assert!(
            mean > 0.3 && mean < 0.7,
            "outside of the tube seen from about half the views"
        );
    }
}
