//! Plane sections of a closed organ: the polygon a planar cut exposes,
//! triangulated, so the simulator can texture it from the organ's solid
//! texture (see `cut`).
//!
//! How: every vertex is classed above (`n·p >= d`) or below the plane. A
//! vertex exactly on the plane counts as above: the plane is nudged
//! symbolically a hair downwards, so no vertex is ever on it and every face
//! is either missed or crossed by exactly two of its edges. A crossed face
//! gives one segment, from the crossing of its edge that runs above→below
//! to the crossing of its edge that runs below→above; across each crossed
//! edge that segment meets the neighbour face's, so following them is a
//! permutation of the crossed edges and every loop closes exactly. On an
//! outward-oriented mesh this order puts the solid on the left of each loop
//! seen from the normal's side: outer boundaries run counter-clockwise and
//! holes clockwise, so no guessing is needed to tell them apart.
//!
//! Consequences of the nudge: a plane through a face of the mesh (the top
//! of a cube) gives that face, the limit of cuts just below it; a plane
//! that only touches the mesh from below gives an empty section.

use std::collections::HashMap;
use std::ops::Range;

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::mesh::{EdgeId, Topology, TriMesh};

const NONE: u32 = u32::MAX;

/// The points `p` with `normal · p = offset`. The normal need not be unit:
/// classing vertices with the plane as given keeps a plane like
/// `x + y + z = 0.5` exact on vertices it passes through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: DVec3,
    pub offset: f64,
}

impl Plane {
    /// Refuses a zero or non-finite normal and a non-finite offset.
    pub fn new(normal: DVec3, offset: f64) -> Result<Plane> {
        if !normal.is_finite() || normal == DVec3::ZERO || !offset.is_finite() {
            return Err(Error::invalid(format!(
                "the plane needs a non-zero finite normal and a finite offset, \
                 not normal {normal} and offset {offset}"
            )));
        }
        Ok(Plane { normal, offset })
    }

    /// `normal · p - offset`: the signed distance times |normal|.
    #[inline]
    pub fn side(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }
}

/// Orthonormal 2D coordinates in a plane: `u`, `v` and the unit normal form
/// a right-handed frame, so counter-clockwise in (u, v) is counter-clockwise
/// seen from the normal's side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub origin: DVec3,
    pub u: DVec3,
    pub v: DVec3,
}

impl Frame {
    pub fn of(plane: &Plane) -> Frame {
        let len2 = plane.normal.length_squared();
        let n = plane.normal / len2.sqrt();
        let u = n.any_orthonormal_vector();
        Frame {
            origin: plane.normal * (plane.offset / len2),
            u,
            v: n.cross(u),
        }
    }

    #[inline]
    pub fn to_2d(&self, p: DVec3) -> DVec2 {
        let q = p - self.origin;
        DVec2::new(q.dot(self.u), q.dot(self.v))
    }

    #[inline]
    pub fn to_3d(&self, q: DVec2) -> DVec3 {
        self.origin + self.u * q.x + self.v * q.y
    }
}

/// The triangulated section. Invariants: every position is the crossing of
/// the plane with the mesh edge `edges[i]` and lies on one boundary loop;
/// `boundary` holds each outer loop (counter-clockwise about `normal`)
/// followed by its holes (clockwise), each loop closed implicitly from its
/// last vertex to its first, positions numbered along them in that order;
/// `triangles` cover the outer loops minus their holes, counter-clockwise
/// about `normal`.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    pub positions: Vec<DVec3>,
    pub edges: Vec<EdgeId>,
    pub triangles: Vec<[u32; 3]>,
    pub boundary: Vec<Vec<u32>>,
    /// The plane's unit normal: the section faces this way.
    pub normal: DVec3,
    pub frame: Frame,
}

impl Section {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Area of the triangulation.
    pub fn area(&self) -> f64 {
        let p = |i: u32| self.positions[i as usize];
        self.triangles
            .iter()
            .map(|&[a, b, c]| 0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length())
            .sum()
    }

    /// Area enclosed by the boundary loops (shoelace in the plane): outer
    /// loops minus holes. Independent of the triangulation, to check it.
    pub fn polygon_area(&self) -> f64 {
        self.boundary
            .iter()
            .map(|l| signed_area(&l.iter().map(|&i| self.plane_point(i)).collect::<Vec<_>>()))
            .sum()
    }

    /// Position `i` in the plane's 2D frame.
    #[inline]
    pub fn plane_point(&self, i: u32) -> DVec2 {
        self.frame.to_2d(self.positions[i as usize])
    }

    /// Bounds of the section in the plane's frame, `None` when empty.
    pub fn bounds(&self) -> Option<(DVec2, DVec2)> {
        let mut points = (0..self.positions.len() as u32).map(|i| self.plane_point(i));
        let first = points.next()?;
        Some(points.fold((first, first), |(lo, hi), q| (lo.min(q), hi.max(q))))
    }
}

/// Shoelace signed area: positive counter-clockwise.
pub(crate) fn signed_area(points: &[DVec2]) -> f64 {
    let n = points.len();
    0.5 * (0..n)
        .map(|i| points[i].perp_dot(points[(i + 1) % n]))
        .sum::<f64>()
}

/// Even-odd test: does `p` lie inside the closed polygon `points`?
pub(crate) fn contains(points: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let mut j = points.len() - 1;
    for (i, &a) in points.iter().enumerate() {
        let b = points[j];
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The section of the closed mesh `mesh` (with its `topology`) by `plane`.
/// A plane that misses the mesh gives an empty section; a mesh with
/// boundary loops is refused, since its section would not be closed.
pub fn plane_section(mesh: &TriMesh, topology: &Topology, plane: Plane) -> Result<Section> {
    let plane = Plane::new(plane.normal, plane.offset)?;
    let open = topology.boundary_loops().len();
    if open > 0 {
        return Err(Error::invalid(format!(
            "the mesh is not closed ({open} boundary loops); a section needs a closed organ"
        )));
    }
    if topology.num_faces() != mesh.num_faces() || topology.num_vertices() != mesh.num_vertices() {
        return Err(Error::invalid("the topology was built for another mesh"));
    }
    let frame = Frame::of(&plane);
    let side: Vec<f64> = mesh.positions.iter().map(|&p| plane.side(p)).collect();
    let above = |v: u32| side[v as usize] >= 0.0;

    // next[e]: the crossed edge that follows crossed edge e along its loop.
    let mut next = vec![NONE; topology.num_edges()];
    let mut starts = Vec::new();
    for (f, tri) in mesh.triangles.iter().enumerate() {
        let (mut down, mut up) = (NONE, NONE);
        for i in 0..3 {
            let (a, b) = (above(tri[i]), above(tri[(i + 1) % 3]));
            if a != b {
                let e = topology.edge((3 * f + i).into()).0;
                if a { down = e } else { up = e }
            }
        }
        if down != NONE {
            next[down as usize] = up;
            starts.push(down);
        }
    }

    let crossing = |e: u32| {
        let [a, b] = topology.edge_vertices(EdgeId(e));
        let (sa, sb) = (side[a.idx()], side[b.idx()]);
        // Exact at the ends: t = 1 when b lies on the plane gives b itself.
        let t = (sa / (sa - sb)).clamp(0.0, 1.0);
        mesh.positions[a.idx()] * (1.0 - t) + mesh.positions[b.idx()] * t
    };

    // Each loop as its crossing points, each with the mesh edge it lies on.
    let mut loops: Vec<Vec<(DVec3, EdgeId)>> = Vec::new();
    for &start in &starts {
        if next[start as usize] == NONE {
            continue; // already on a traced loop
        }
        let mut ring: Vec<(DVec3, EdgeId)> = Vec::new();
        let mut e = start;
        loop {
            let after = next[e as usize];
            if after == NONE {
                return Err(Error::invalid(format!(
                    "the section breaks off at mesh edge e{e}; is the mesh consistently oriented?"
                )));
            }
            next[e as usize] = NONE;
            // A vertex on the plane is the crossing of all its crossed edges:
            // keep it once.
            let p = crossing(e);
            if ring.last().is_none_or(|&(q, _)| q != p) {
                ring.push((p, EdgeId(e)));
            }
            e = after;
            if e == start {
                break;
            }
        }
        if ring.len() > 1 && ring[0].0 == ring[ring.len() - 1].0 {
            ring.pop();
        }
        if ring.len() >= 3 {
            loops.push(ring);
        }
    }

    let mut flat: Vec<Vec<DVec2>> = loops
        .iter()
        .map(|l| l.iter().map(|&(p, _)| frame.to_2d(p)).collect())
        .collect();
    let mut areas: Vec<f64> = flat.iter().map(|q| signed_area(q)).collect();
    // An inside-out mesh turns every loop round; the section's area must
    // come out positive.
    if areas.iter().sum::<f64>() < 0.0 {
        for ((l, q), a) in loops.iter_mut().zip(&mut flat).zip(&mut areas) {
            l.reverse();
            q.reverse();
            *a = -*a;
        }
    }

    // Each hole goes into the smallest outer loop around it. Loops of zero
    // area (all points on a line) enclose nothing and are left out.
    let outers: Vec<usize> = (0..loops.len()).filter(|&i| areas[i] > 0.0).collect();
    let mut holes_of: Vec<Vec<usize>> = vec![Vec::new(); outers.len()];
    for h in (0..loops.len()).filter(|&i| areas[i] < 0.0) {
        let home = (0..outers.len())
            .filter(|&k| contains(&flat[outers[k]], flat[h][0]))
            .min_by(|&a, &b| areas[outers[a]].total_cmp(&areas[outers[b]]));
        // A hole in no outer loop only comes from a self-intersecting mesh:
        // it is left out of the boundary and the triangulation alike.
        if let Some(k) = home {
            holes_of[k].push(h);
        }
    }

    let mut section = Section {
        positions: Vec::new(),
        edges: Vec::new(),
        triangles: Vec::new(),
        boundary: Vec::new(),
        normal: plane.normal.normalize(),
        frame,
    };
    // Triangulated by earcut (the georust `earcut` crate, a port of Mapbox's
    // earcut 3): handles holes by bridging, tolerates the touching and
    // collinear points sections produce, and reuses its buffers between
    // polygons. Chosen over `earcutr`, the older port of earcut 2, for being
    // the one kept in step with upstream and faster.
    let mut earcut = earcut::Earcut::new();
    let mut out: Vec<u32> = Vec::new();
    for (k, &o) in outers.iter().enumerate() {
        let first = section.positions.len() as u32;
        let mut points: Vec<[f64; 2]> = Vec::new();
        let mut rings = Vec::new();
        for r in std::iter::once(o).chain(holes_of[k].iter().copied()) {
            let at = points.len() as u32;
            rings.push(at..at + loops[r].len() as u32);
            section
                .boundary
                .push((first + at..first + at + loops[r].len() as u32).collect());
            section.positions.extend(loops[r].iter().map(|&(p, _)| p));
            section.edges.extend(loops[r].iter().map(|&(_, e)| e));
            points.extend(flat[r].iter().map(|q| q.to_array()));
        }
        let hole_starts: Vec<u32> = rings[1..].iter().map(|r| r.start).collect();
        earcut.earcut_slice(&points, &hole_starts, &mut out);
        let mut local: Vec<[u32; 3]> = out
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| DVec2::from(points[i as usize]));
                // Earcut promises no winding; the section's is counter-clockwise.
                if (b - a).perp_dot(c - a) < 0.0 {
                    [t[0], t[2], t[1]]
                } else {
                    [t[0], t[1], t[2]]
                }
            })
            .collect();
        restore_skipped(&rings, points.len(), &mut local);
        section
            .triangles
            .extend(local.iter().map(|t| t.map(|i| first + i)));
    }
    Ok(section)
}

/// Earcut drops loop vertices that lie on the line through their
/// neighbours (collinear or nearly repeated crossings). Put each back by
/// splitting the triangle on the edge that skips it into a fan, so the
/// section's border holds every crossing point and meets the cut organ
/// surface with no T-junction. `rings` are the loops' index ranges,
/// `triangles` counter-clockwise, so a border edge runs along its loop.
fn restore_skipped(rings: &[Range<u32>], count: usize, triangles: &mut Vec<[u32; 3]>) {
    let mut used = vec![false; count];
    for &i in triangles.iter().flatten() {
        used[i as usize] = true;
    }
    if used.iter().all(|&u| u) {
        return;
    }
    let mut by_edge: HashMap<(u32, u32), usize> = HashMap::new();
    let index = |by_edge: &mut HashMap<(u32, u32), usize>, k: usize, t: [u32; 3]| {
        for j in 0..3 {
            by_edge.insert((t[j], t[(j + 1) % 3]), k);
        }
    };
    for (k, &t) in triangles.iter().enumerate() {
        index(&mut by_edge, k, t);
    }
    for ring in rings {
        let ids: Vec<u32> = ring.clone().collect();
        let len = ids.len();
        let Some(s) = ids.iter().position(|&i| used[i as usize]) else {
            continue;
        };
        let at = |j: usize| ids[(s + j) % len];
        let mut k = 0;
        while k < len {
            // Vertex `at(k)` is used; skip to the next used one.
            let mut j = k + 1;
            while !used[at(j) as usize] {
                j += 1;
            }
            let (a, b) = (at(k), at(j));
            if j > k + 1
                && let Some(&t) = by_edge.get(&(a, b))
            {
                let c = triangles[t]
                    .into_iter()
                    .find(|&v| v != a && v != b)
                    .expect("a triangle has a third vertex");
                let chain: Vec<u32> = (k..=j).map(at).collect();
                for (n, w) in chain.windows(2).enumerate() {
                    let fan = [w[0], w[1], c];
                    let slot = if n == 0 {
                        triangles[t] = fan;
                        t
                    } else {
                        triangles.push(fan);
                        triangles.len() - 1
                    };
                    index(&mut by_edge, slot, fan);
                }
            }
            k = j;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::icosphere;

    #[test]
    fn sphere_section_is_one_disk() {
        let mesh = icosphere(3);
        let topo = Topology::build(&mesh).unwrap();
        let s = plane_section(&mesh, &topo, Plane::new(DVec3::Z, 0.3).unwrap()).unwrap();
        assert_eq!(s.boundary.len(), 1);
        assert!(s.polygon_area() > 0.0);
        assert!((s.area() - s.polygon_area()).abs() < 1e-12);
        // A polygon inscribed in the circle of radius sqrt(1 - 0.09).
        let disk = std::f64::consts::PI * (1.0 - 0.09);
        assert!(s.area() < disk && s.area() > 0.95 * disk, "{}", s.area());
    }

    #[test]
    fn inside_out_mesh_gives_the_same_area() {
        let mut mesh = icosphere(2);
        let topo = Topology::build(&mesh).unwrap();
        let plane = Plane::new(DVec3::new(0.2, -0.3, 1.0), 0.1).unwrap();
        let a = plane_section(&mesh, &topo, plane).unwrap().area();
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        let topo = Topology::build(&mesh).unwrap();
        let s = plane_section(&mesh, &topo, plane).unwrap();
        assert!((s.area() - a).abs() < 1e-12);
        assert!((s.polygon_area() - a).abs() < 1e-12);
    }

    #[test]
    fn zero_normal_is_refused() {
        assert!(Plane::new(DVec3::ZERO, 1.0).is_err());
        assert!(Plane::new(DVec3::new(f64::NAN, 0.0, 1.0), 1.0).is_err());
    }
}

/// `mesh` with each boundary loop closed by a fan from the loop's
/// centroid, and its topology: so an organ with openings (the uterine
/// cavity's cervical canal) can still be cut, each opening sectioned as if
/// a flat lid closed it. A closed mesh comes back as it is.
pub fn capped(mesh: &TriMesh, topology: &Topology) -> Result<(TriMesh, Topology)> {
    if topology.boundary_loops().is_empty() {
        return Ok((mesh.clone(), topology.clone()));
    }
    let mut positions = mesh.positions.clone();
    let mut triangles = mesh.triangles.clone();
    for lp in topology.boundary_loops() {
        let verts: Vec<u32> = lp
            .iter()
            .map(|&h| topology.origin(h).idx() as u32)
            .collect();
        let centroid =
            verts.iter().map(|&v| positions[v as usize]).sum::<DVec3>() / verts.len() as f64;
        let c = positions.len() as u32;
        positions.push(centroid);
        // A twinless half-edge a -> b borders its face; the lid's face
        // runs b -> a so the two agree in orientation.
        for (i, &a) in verts.iter().enumerate() {
            let b = verts[(i + 1) % verts.len()];
            triangles.push([b, a, c]);
        }
    }
    let lidded = TriMesh::new(positions, triangles);
    let topology = Topology::build(&lidded)?;
    Ok((lidded, topology))
}

#[cfg(test)]
mod capped_tests {
    use super::*;

    #[test]
    fn a_capped_open_cylinder_is_closed_and_cuts() {
        let mesh = crate::mesh::shapes::open_cylinder(1.0, 2.0, 24, 6);
        let topology = Topology::build(&mesh).unwrap();
        assert_eq!(topology.boundary_loops().len(), 2);
        let (lidded, t) = capped(&mesh, &topology).unwrap();
        assert!(t.boundary_loops().is_empty());
        let s = plane_section(
            &lidded,
            &t,
            Plane::new(DVec3::new(1.0, 0.0, 0.0), 0.0).unwrap(),
        )
        .unwrap();
        // Through the axis: a 2 x 2 rectangle.
        assert!((s.area() - 4.0).abs() < 1e-9, "{}", s.area());
    }
}
