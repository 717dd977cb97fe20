//! The surface drawn back to the voxels it was made from (issue 40:
//! within a voxel of their boundary). Smoothing cuts a voxel's corner off
//! a crest, and on the MNI white matter's thin gyri a decimation held to
//! its own surface's vertices left corners of the region's voxel boundary
//! 2.8 voxels from the surface at 50k faces.
//!
//! The corners are what is held: a voxel face's extremes (a convex corner
//! stands farthest out of a smooth surface, a concave one deepest in it;
//! even a plane at the best place across a diagonal staircase leaves them
//! sqrt(3)/2 from it, hence `TOLERANCE`). They are an envelope
//! (`mesh::envelope`): the corners within the tolerance stay within it
//! through every move here and, given to the decimation, through its
//! collapses, flips and relaxation. Each loose corner (beyond it) asks
//! (and each held one farther than `NEAR`, so the moves pull both ways)
//! that the surface at its nearest point come to `AIM` of it; the vertices
//! move along their normals by the least squares of those asks plus a
//! membrane term, so a move spreads over a ring or two rather than
//! raising a spike (`offsets`), each move kept only where it flips no
//! face, turns none far, leaves none thinner than the decimation's guard
//! allows, keeps the vertex within `OFF_VOXELS` of the voxels' faces and
//! lets no held corner go, else halved or quartered. In rounds, until no
//! corner is loose (and, both ways, no face strays). `segment::mesh` fits the full surface before the
//! decimation (so every corner is held from the start) and the decimated
//! one after it (for the corners its last mends let go). Held within the
//! voxels (`MeshOptions::within_voxels` at 0.9), that last fit holds every
//! point of the voxel faces, not only the corners, and draws the surface
//! back both ways: a face with a point farther than the tolerance from
//! the voxel faces asks the same of that point towards the nearest of
//! them (`BOTH_WAYS`). Distances are in voxels: world units over the cube
//! root of a voxel's volume, exact for the isotropic voxels of most
//! segmentations.

use glam::{DAffine3, DVec3};
use rayon::prelude::*;

use crate::error::Result;
use crate::mesh::TriMesh;
use crate::mesh::bvh::Bvh;
use crate::mesh::corners::{sharpness, worst_after_move};
use crate::mesh::decimate::{MAX_TURN, MIN_ANGLE};
use crate::mesh::envelope::{self, Envelope};
use crate::progress::{self, Progress};
use crate::segment::ScalarVolume;

/// The farthest a corner of the voxel boundary may lie from the surface,
/// voxels: the diagonal staircase's sqrt(3)/2 and a little. Where the
/// surface bends between a voxel face's corners, the face's middle or
/// edges can lie farther than they do: on the MNI white matter held
/// within its voxels at 50k faces (`MeshOptions::within_voxels`), 1.14
/// voxels against 1.03 with the corners held (the points compare_mesh.py
/// takes, nine per voxel face), hence `Voxels::face_points`.
pub const TOLERANCE: f64 = 0.9;
/// Corners farther than this take part in the moves, voxels: those just
/// inside the tolerance too, so that a move towards a corner on one side
/// does not push the surface towards one on the other unopposed (with
/// only the loose corners taking part, the white matter's volume grew by
/// 1.5% at 50k faces, against 0.6%).
const NEAR: f64 = 0.85;
/// The corners farther than this at first are the ones the rounds look
/// at, voxels: a corner nearer would need the moves meant for others to
/// push the surface a fifth of a voxel from it.
const CANDIDATE: f64 = 0.7;
/// Where a corner taking part is brought to, voxels.
const AIM: f64 = 0.75;
/// The farthest a vertex moves in a round, voxels: where a vertex's
/// normal points nearly across the way to a corner, the least-squares
/// move along it would be long.
const STEP: f64 = 0.5;
/// How far from the voxels' faces a move may take a vertex, voxels (a
/// vertex already farther stays): a face between two such vertices may
/// bridge a sulcus a little farther out. Without this bound the moves
/// dragged the white matter's surface across sulci, 3.5 voxels from any
/// voxel face.
const OFF_VOXELS: f64 = 0.6;
/// How `fit` draws the surface to the voxels.
#[derive(Clone, Copy, Debug)]
pub struct Fitting {
    /// Rounds of moves at most.
    pub rounds: usize,
    /// Whether every point of the voxel faces is held
    /// (`Voxels::face_points`), not only their corners, and the surface
    /// drawn back to the voxels' faces too where it strays farther than
    /// `TOLERANCE` from them (`off_voxels`).
    pub both_ways: bool,
}

/// To the corners.
pub const TO_CORNERS: Fitting = Fitting {
    rounds: 4,
    both_ways: false,
};

/// Both ways, for a surface whose every voxel-face point is held
/// (`Voxels::face_points`): an edge's midpoint left beyond the tolerance
/// lies between two held corners and takes a few rounds more to draw in,
/// and a face bridging a notch in the voxels is drawn into it. On the MNI
/// white matter at 50k faces, with the corners held through the
/// decimation: the farthest face point 1.005 voxels from the surface
/// after 4 rounds, 0.98 after 6, 0.975 after 8; the farthest point of the
/// surface from the voxels 0.99 against 1.10 one way only. Scanning the
/// faces for it (every round) and the face points held cost 2 s there.
pub const BOTH_WAYS: Fitting = Fitting {
    rounds: 6,
    both_ways: true,
};

/// What `fit` did.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Fit {
    /// The points held (the voxel boundary's corners, or every point of
    /// its faces), and how many lay farther than `TOLERANCE` from the
    /// surface before the moves and after.
    pub points: usize,
    pub far_before: usize,
    pub far: usize,
    /// The farthest of those, before and after, voxels (none if none).
    pub farthest_before: Option<f64>,
    pub farthest: Option<f64>,
    /// Vertex moves made.
    pub moves: usize,
    /// Drawn both ways (`Fitting::both_ways`; else none): the faces with
    /// a sample farther than `TOLERANCE` from the voxels' faces after the
    /// moves, and the farthest sample, voxels (none if none).
    pub faces_off: Option<usize>,
    pub farthest_off: Option<f64>,
}

/// A region's voxels as `fit` holds the surface to them: `inside`, one
/// per voxel of `volume` (outside the grid is outside), placed by the
/// volume's voxel-to-world map.
pub struct Voxels<'a> {
    pub volume: &'a ScalarVolume,
    pub inside: &'a [bool],
}

impl Voxels<'_> {
    fn at(&self, x: i64, y: i64, z: i64) -> bool {
        let [nx, ny, nz] = self.volume.size.map(|n| n as i64);
        (0..nx).contains(&x)
            && (0..ny).contains(&y)
            && (0..nz).contains(&z)
            && self.inside[self.volume.index(x as usize, y as usize, z as usize)]
    }

    /// The corners of the voxel boundary: the lattice points where inside
    /// and outside voxels meet, in world units, in lattice order.
    pub fn corners(&self) -> Vec<DVec3> {
        let [nx, ny, nz] = self.volume.size;
        // Per slab of voxels, how many of the four voxels round each
        // lattice column (x - 1 and x, y - 1 and y) are inside; a corner's
        // eight are its two slabs' counts (sums rather than eight lookups
        // per corner: the volume's every lattice point is visited).
        let quads = |z: usize| -> Vec<u8> {
            let mut out = vec![0u8; (nx + 1) * (ny + 1)];
            if z == 0 || z > nz {
                return out;
            }
            let slab = &self.inside[(z - 1) * nx * ny..z * nx * ny];
            for y in 0..=ny {
                for x in 0..=nx {
                    let mut count = 0;
                    for (yy, xx) in [(y, x), (y, x + 1), (y + 1, x), (y + 1, x + 1)] {
                        if (1..=ny).contains(&yy) && (1..=nx).contains(&xx) {
                            count += slab[(yy - 1) * nx + xx - 1] as u8;
                        }
                    }
                    out[y * (nx + 1) + x] = count;
                }
            }
            out
        };
        (0..=nz)
            .into_par_iter()
            .flat_map_iter(|z| {
                let (below, above) = (quads(z), quads(z + 1));
                let mut slab = Vec::new();
                for (i, (a, b)) in below.iter().zip(&above).enumerate() {
                    let count = a + b;
                    if count > 0 && count < 8 {
                        let (x, y) = (i % (nx + 1), i / (nx + 1));
                        let p = DVec3::new(x as f64 - 0.5, y as f64 - 0.5, z as f64 - 0.5);
                        slab.push(self.volume.to_world.transform_point3(p));
                    }
                }
                slab
            })
            .collect()
    }

    /// The axes along which voxel `v`'s face on its upper side lies between
    /// an inside voxel and an outside one.
    fn boundary_axes(&self, v: [i64; 3]) -> impl Iterator<Item = usize> + '_ {
        let here = self.at(v[0], v[1], v[2]);
        (0..3).filter(move |&axis| {
            let mut next = v;
            next[axis] += 1;
            self.at(next[0], next[1], next[2]) != here
        })
    }

    /// The points compare_mesh.py measures a surface's distance from: the
    /// nine of each face between an inside voxel and an outside one (its
    /// corners, its edges' midpoints, its centre), each once, in world
    /// units, sorted by x, then y, then z. Where the surface bends between a face's
    /// corners, its middle lies farther than they do.
    pub fn face_points(&self) -> Vec<DVec3> {
        let [nx, ny, nz] = self.volume.size.map(|n| n as i64);
        // On the lattice of half voxels (voxel i's centre at 2i), so that
        // the points faces share sort together and are kept once.
        let mut halves: Vec<[i64; 3]> = (-1..nz)
            .into_par_iter()
            .flat_map_iter(|z| {
                let mut slab = Vec::new();
                for y in -1..ny {
                    for x in -1..nx {
                        for axis in self.boundary_axes([x, y, z]) {
                            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                            let mut centre = [2 * x, 2 * y, 2 * z];
                            centre[axis] += 1;
                            for du in -1..=1 {
                                for dv in -1..=1 {
                                    let mut q = centre;
                                    q[u] += du;
                                    q[v] += dv;
                                    slab.push(q);
                                }
                            }
                        }
                    }
                }
                slab
            })
            .collect();
        halves.par_sort_unstable();
        halves.dedup();
        halves
            .into_iter()
            .map(|[x, y, z]| {
                let p = DVec3::new(x as f64, y as f64, z as f64) / 2.0;
                self.volume.to_world.transform_point3(p)
            })
            .collect()
    }

    /// Whether `p` (world units) lies within `limit` voxels of a face
    /// between an inside voxel and an outside one (voxel coordinates; one
    /// within two voxels of it: `limit` below 1.5). The nearest voxels are
    /// looked at first, and the search stops at the first face within.
    fn within(&self, to_voxel: &DAffine3, p: DVec3, limit: f64) -> bool {
        let q = to_voxel.transform_point3(p);
        let c = q.round().as_i64vec3();
        let limit = limit * limit;
        // Loops rather than an iterator chain: this is the fit's innermost
        // test, and with an iterator the white matter at --within-voxels
        // 0.9 took 8.3 s against 7.4 (same bytes).
        for &[dx, dy, dz] in NEIGHBOURHOOD.iter() {
            let [x, y, z] = [c.x + dx, c.y + dy, c.z + dz];
            let here = self.at(x, y, z);
            for axis in 0..3 {
                let mut next = [x, y, z];
                next[axis] += 1;
                if self.at(next[0], next[1], next[2]) != here {
                    let mut centre = DVec3::new(x as f64, y as f64, z as f64);
                    centre[axis] += 0.5;
                    if off_face(q, centre, axis).length_squared() <= limit {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The point nearest `p` (world units) of the faces between inside
    /// and outside voxels, world units; none if none lies within 16
    /// voxels of it.
    fn nearest_on_faces(&self, to_voxel: &DAffine3, p: DVec3) -> Option<DVec3> {
        let q = to_voxel.transform_point3(p);
        let c = q.round().as_i64vec3();
        // The faces of the voxels within r of c along every axis, widening
        // r: any other face lies at least r from q (q is within half a
        // voxel of c's centre, a face within half a voxel of its voxel's),
        // so the nearest of these, if within r, is the nearest of all.
        for r in [2, 4, 8, 16] {
            let mut best: Option<DVec3> = None;
            for z in c.z - r..=c.z + r {
                for y in c.y - r..=c.y + r {
                    for x in c.x - r..=c.x + r {
                        for axis in self.boundary_axes([x, y, z]) {
                            let mut centre = DVec3::new(x as f64, y as f64, z as f64);
                            centre[axis] += 0.5;
                            let point = q - off_face(q, centre, axis);
                            if best
                                .is_none_or(|b| point.distance_squared(q) < b.distance_squared(q))
                            {
                                best = Some(point);
                            }
                        }
                    }
                }
            }
            if let Some(nearest) = best.filter(|b| b.distance(q) <= r as f64) {
                return Some(self.volume.to_world.transform_point3(nearest));
            }
        }
        None
    }

    /// Whether `to` lies nearer the faces between inside and outside
    /// voxels than `from` does (world units).
    fn nearer(&self, to_voxel: &DAffine3, from: DVec3, to: DVec3) -> bool {
        let distance = |p: DVec3| {
            self.nearest_on_faces(to_voxel, p)
                .map_or(f64::INFINITY, |n| n.distance(p))
        };
        distance(to) < distance(from)
    }
}

/// The way from the voxel face centred at `centre` across `axis` (a unit
/// square) to `q`: from the face's point nearest `q`, voxel coordinates.
fn off_face(q: DVec3, centre: DVec3, axis: usize) -> DVec3 {
    let d = q - centre;
    let mut off = d - d.clamp(DVec3::splat(-0.5), DVec3::splat(0.5));
    off[axis] = d[axis];
    off
}

/// The voxels within two of a voxel, nearest first (`Voxels::within`).
static NEIGHBOURHOOD: std::sync::LazyLock<Vec<[i64; 3]>> = std::sync::LazyLock::new(|| {
    let mut offsets: Vec<[i64; 3]> = (-2..=2)
        .flat_map(|z| (-2..=2).flat_map(move |y| (-2..=2).map(move |x| [x, y, z])))
        .collect();
    offsets.sort_by_key(|o| (o.iter().map(|d| d * d).sum::<i64>(), *o));
    offsets
});

/// Moves `mesh`'s vertices (world units) so that every corner of
/// `voxels`' boundary (every point of its faces, both ways) lies within
/// `TOLERANCE` voxels of it, as the module says, as nearly as the guards
/// allow, as `fitting` asks. `held` is the envelope of those points on
/// `mesh` as the decimation left them (none: made here), given back with
/// the points the moves brought within carried.
/// Same bytes on any thread count (the distances are taken in parallel,
/// the moves made in vertex order).
pub fn fit(
    mesh: &mut TriMesh,
    voxels: &Voxels,
    held: Option<Envelope>,
    fitting: Fitting,
    progress: &dyn Progress,
) -> Result<(Fit, Envelope)> {
    let voxel = voxels.volume.voxel_volume().cbrt();
    let to_voxel = voxels.volume.to_world.inverse();
    progress.stage("fitting the surface to the voxels", fitting.rounds as u64);
    let (tolerance, aim) = (TOLERANCE * voxel, AIM * voxel);
    let turn = MAX_TURN.to_radians().cos();
    let floor = MIN_ANGLE.to_radians().cos();
    let faces_at = mesh.faces_at_vertices();
    let neighbours = super::smooth::vertex_neighbours(mesh);
    // Built once; the moves only refit it.
    let mut bvh = Bvh::over_faces(mesh);
    // The corners within the tolerance stay within it (a move towards one
    // corner may not push the surface off another); the moves are for the
    // loose ones, those beyond it.
    let mut held = match held {
        Some(mut held) => {
            held.carry_loose(&bvh);
            held
        }
        None if fitting.both_ways => Envelope::holding(&bvh, voxels.face_points(), tolerance),
        None => Envelope::holding(&bvh, voxels.corners(), tolerance),
    };
    let loose = |held: &Envelope, bvh: &Bvh| {
        let points: Vec<DVec3> = held
            .loose()
            .iter()
            .map(|&p| held.points()[p as usize])
            .collect();
        farther(bvh, &points, tolerance)
    };
    let beyond = |far: &[(DVec3, u32, DVec3)]| {
        let farthest = far
            .iter()
            .map(|(p, _, q)| p.distance(*q) / voxel)
            .reduce(f64::max);
        (far.len(), farthest)
    };
    let mut after = Vec::new();
    let mut report = Fit {
        points: held.points().len(),
        far_before: 0,
        far: 0,
        farthest_before: None,
        farthest: None,
        moves: 0,
        faces_off: None,
        farthest_off: None,
    };
    (report.far_before, report.farthest_before) = beyond(&loose(&held, &bvh));
    // The corners farther than CANDIDATE at first are the ones the rounds
    // look at; those farther than NEAR take part in the moves.
    let candidates: Vec<DVec3> = farther(&bvh, held.points(), CANDIDATE * voxel)
        .into_iter()
        .map(|(p, _, _)| p)
        .collect();
    // Where the surface strays from the voxel faces (`off_voxels`, as
    // `beyond` counts it), while no move has made it stale.
    let mut strays = None;
    for round in 0..fitting.rounds {
        progress::check(progress)?;
        if round > 0 {
            bvh.refit(|f| mesh.corners(f as usize));
            held.carry_loose(&bvh);
        }
        let off = match fitting.both_ways {
            true => off_voxels(mesh, voxels, &to_voxel, voxel, TOLERANCE),
            false => Vec::new(),
        };
        // The surface as it stands strays where `off` says, until a move.
        strays = Some(beyond(&off));
        if held.loose().is_empty() && off.is_empty() {
            break;
        }
        let mut far = farther(&bvh, &candidates, NEAR * voxel);
        far.extend(off);
        let wanted = offsets(mesh, &neighbours, &far, aim, STEP * voxel);
        let mut made = 0;
        for (v, step) in wanted.iter().enumerate() {
            if *step == DVec3::ZERO {
                continue;
            }
            let p = mesh.positions[v];
            // Nor off the voxels: no farther than OFF_VOXELS from their
            // faces (a vertex already farther may not move).
            let ring = &faces_at[v];
            let allowed = [1.0, 0.5, 0.25]
                .into_iter()
                .map(|share| p + *step * share)
                .find(|&to| {
                    (voxels.within(&to_voxel, to, OFF_VOXELS)
                        || fitting.both_ways && voxels.nearer(&to_voxel, p, to))
                        && keeps_shapes(mesh, ring, v as u32, to, turn, floor)
                        && envelope::held(mesh, Some(&mut held), ring, v as u32, to, &mut after)
                });
            if let Some(to) = allowed {
                mesh.positions[v] = to;
                made += 1;
            }
        }
        report.moves += made;
        progress.advance(1);
        if made > 0 {
            strays = None;
        } else {
            break;
        }
    }
    bvh.refit(|f| mesh.corners(f as usize));
    held.carry_loose(&bvh);
    (report.far, report.farthest) = beyond(&loose(&held, &bvh));
    if fitting.both_ways {
        let (faces, farthest) = strays
            .unwrap_or_else(|| beyond(&off_voxels(mesh, voxels, &to_voxel, voxel, TOLERANCE)));
        (report.faces_off, report.farthest_off) = (Some(faces), farthest);
    }
    Ok((report, held))
}

/// Those of `points` farther than `distance` from the triangles of `bvh`,
/// each with the face nearest it (its index in the mesh) and the point of
/// that face nearest it, in the order of `points`.
fn farther(bvh: &Bvh, points: &[DVec3], distance: f64) -> Vec<(DVec3, u32, DVec3)> {
    points
        .par_iter()
        .filter_map(|&p| bvh.closest_beyond(p, distance).map(|(f, q)| (p, f, q)))
        .collect()
}

/// Where the surface strays farther than `limit` voxels from the voxels'
/// faces (a face across a sulcus, or cut into a crest): of each face of
/// `mesh`, the sample (a barycentric grid `SAMPLE` voxels apart) farthest
/// from them, as (the nearest point of the voxel faces, the face, the
/// sample), in face order; the same misses `offsets` takes for corners.
fn off_voxels(
    mesh: &TriMesh,
    voxels: &Voxels,
    to_voxel: &DAffine3,
    voxel: f64,
    limit: f64,
) -> Vec<(DVec3, u32, DVec3)> {
    (0..mesh.num_faces())
        .into_par_iter()
        .filter_map(|f| {
            let t = mesh.corners(f);
            let longest = (0..3)
                .map(|k| t[k].distance(t[(k + 1) % 3]))
                .fold(0.0, f64::max);
            let n = ((longest / (SAMPLE * voxel)).ceil() as usize).max(1);
            let mut worst: Option<(f64, DVec3, DVec3)> = None;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let q = t[0] * (1.0 - u - v) + t[1] * u + t[2] * v;
                    if voxels.within(to_voxel, q, limit) {
                        continue;
                    }
                    if let Some(p) = voxels.nearest_on_faces(to_voxel, q) {
                        let d = p.distance(q);
                        if worst.is_none_or(|(w, _, _)| d > w) {
                            worst = Some((d, p, q));
                        }
                    }
                }
            }
            worst.map(|(_, p, q)| (p, f as u32, q))
        })
        .collect()
}

/// The spacing of `off_voxels`' samples, voxels: compare_mesh.py's.
const SAMPLE: f64 = 0.3;

/// The vertices' moves that bring the surface to `aim` of each of the
/// corners `far` (each with the face nearest it and the point of that face
/// nearest it) as nearly as a smooth move can: each vertex moves along its
/// normal by h, the h minimising the squared misses (the move at a
/// corner's nearest point, the barycentric mean of its face's corners'
/// moves towards the corner, against what it lacks) plus `STIFFNESS` times
/// the squared differences of h along the edges, so a move spreads over a
/// ring or two instead of raising a spike (a membrane energy; moving one
/// vertex at a time doubled the brain's spread of mean curvature). Gauss-
/// Seidel sweeps in vertex order over the vertices within `REACH` edges of
/// a corner's face; the others stay where they are.
fn offsets(
    mesh: &TriMesh,
    neighbours: &[Vec<u32>],
    far: &[(DVec3, u32, DVec3)],
    aim: f64,
    step: f64,
) -> Vec<DVec3> {
    let n = mesh.num_vertices();
    let normals = mesh.vertex_normals();
    // Each miss: its face's corners, their coefficients (barycentric
    // weight times how far the vertex's normal points towards the
    // corner) and the way still to go.
    let misses: Vec<([u32; 3], [f64; 3], f64)> = far
        .iter()
        .map(|&(p, f, q)| {
            let t = mesh.triangles[f as usize];
            let w = barycentric(q, &mesh.corners(f as usize));
            let d = p.distance(q);
            let towards = (p - q) / d;
            let a = std::array::from_fn(|k| w[k] * normals[t[k] as usize].dot(towards));
            (t, a, d - aim)
        })
        .collect();
    let mut of_vertex: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (i, (t, _, _)) in misses.iter().enumerate() {
        for &v in t {
            of_vertex[v as usize].push(i as u32);
        }
    }
    // The vertices that may move: within REACH edges of a miss's face.
    let mut active = vec![false; n];
    let mut front: Vec<u32> = misses.iter().flat_map(|(t, _, _)| *t).collect();
    for &v in &front {
        active[v as usize] = true;
    }
    for _ in 0..REACH {
        let mut next = Vec::new();
        for &v in &front {
            for &u in &neighbours[v as usize] {
                if !std::mem::replace(&mut active[u as usize], true) {
                    next.push(u);
                }
            }
        }
        front = next;
    }
    let order: Vec<u32> = (0..n as u32).filter(|&v| active[v as usize]).collect();
    let mut h = vec![0.0; n];
    for _ in 0..SWEEPS {
        for &v in &order {
            let v = v as usize;
            let (mut lhs, mut rhs) = (0.0, 0.0);
            for &i in &of_vertex[v] {
                let (t, a, miss) = &misses[i as usize];
                let k = t
                    .iter()
                    .position(|&x| x as usize == v)
                    .expect("a corner of its face");
                let others: f64 = (0..3)
                    .filter(|&j| j != k)
                    .map(|j| a[j] * h[t[j] as usize])
                    .sum();
                lhs += a[k] * a[k];
                rhs += a[k] * (miss - others);
            }
            for &u in &neighbours[v] {
                lhs += STIFFNESS;
                rhs += STIFFNESS * h[u as usize];
            }
            if lhs > 0.0 {
                h[v] = (rhs / lhs).clamp(-step, step);
            }
        }
    }
    h.iter().zip(&normals).map(|(&h, &m)| m * h).collect()
}

/// The membrane's weight against the misses (`offsets`).
const STIFFNESS: f64 = 0.25;
/// How many edges from a miss's face a vertex may move.
const REACH: usize = 2;
/// Gauss-Seidel sweeps per round.
const SWEEPS: usize = 20;

/// Whether moving vertex `v` to `to` turns none of its faces (`ring`) past
/// `turn` (a cosine) and leaves their worst sharpness at most `floor`'s or
/// what it was.
fn keeps_shapes(mesh: &TriMesh, ring: &[u32], v: u32, to: DVec3, turn: f64, floor: f64) -> bool {
    let (mut normal, mut worst) = (DVec3::ZERO, f64::NEG_INFINITY);
    for &f in ring {
        let [a, b, c] = mesh.corners(f as usize);
        normal += (b - a).cross(c - a);
        worst = worst.max(sharpness(a, b, c));
    }
    worst_after_move(mesh, ring, v, to, normal, turn) <= worst.max(floor)
}

/// The barycentric coordinates of `q` (a point of triangle `t`) as x, y, z.
fn barycentric(q: DVec3, t: &[DVec3; 3]) -> DVec3 {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], q - t[0]);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den.abs() <= f64::MIN_POSITIVE {
        return DVec3::splat(1.0 / 3.0);
    }
    let v = (d22 * d1 - d12 * d2) / den;
    let w = (d11 * d2 - d12 * d1) / den;
    DVec3::new(1.0 - v - w, v, w)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::mesh::closest::closest_point;
    use crate::progress::Silent;
    use crate::segment::{MeshOptions, Region, Smoother, mesh};

    /// A ball of radius 9 voxels with two fins two voxels thick standing
    /// out of it, one square to the grid and one across its diagonal: thin
    /// crests, as a gyrus's, which smoothing and decimation cut into.
    /// Voxels of 0.8 mm.
    fn finned_ball() -> ScalarVolume {
        let size = [36, 36, 36];
        let mut values = Vec::new();
        for z in 0..size[2] {
            for y in 0..size[1] {
                for x in 0..size[0] {
                    let p = DVec3::new(x as f64, y as f64, z as f64) - DVec3::splat(17.5);
                    let ball = p.length() <= 9.0;
                    let tall = p.z.abs() <= 14.0 && p.length() <= 15.0;
                    let square = p.x.abs() <= 1.0 && p.y.abs() <= 9.0;
                    let diagonal = (p.x + p.y).abs() <= 1.5 && (p.x - p.y).abs() <= 14.0;
                    let inside = ball || (tall && (square || diagonal));
                    values.push(if inside { 1.0 } else { 0.0 });
                }
            }
        }
        ScalarVolume {
            size,
            values,
            to_world: DAffine3::from_scale(DVec3::splat(0.8)),
        }
    }

    /// The finned ball meshed to `faces`, held `within_voxels`.
    fn finned_surface(
        volume: &ScalarVolume,
        faces: usize,
        within_voxels: Option<f64>,
    ) -> (TriMesh, crate::segment::MeshReport) {
        let opts = MeshOptions {
            region: Region::Label(1),
            smooth: crate::segment::DEFAULT_SMOOTH,
            smoother: Smoother::Taubin,
            all_components: false,
            fill_voids: false,
            faces: Some(faces),
            max_handle: None,
            within_voxels,
        };
        mesh(volume, Path::new("finned.nii"), &opts, &Silent).unwrap()
    }

    /// Every face between an inside voxel and an outside one of the finned
    /// ball's grid (outside it counts as outside), by brute force: the
    /// voxel on its lower side and the axis it faces along.
    fn boundary_faces(voxels: &Voxels) -> Vec<([i64; 3], usize)> {
        let mut faces = Vec::new();
        for z in -1..36i64 {
            for y in -1..36i64 {
                for x in -1..36i64 {
                    for axis in 0..3 {
                        let mut next = [x, y, z];
                        next[axis] += 1;
                        // Not `boundary_axes`: the test checks it.
                        if voxels.at(x, y, z) != voxels.at(next[0], next[1], next[2]) {
                            faces.push(([x, y, z], axis));
                        }
                    }
                }
            }
        }
        faces
    }

    /// The farthest of `points` from `surface`, by brute force, voxels of
    /// 0.8.
    fn farthest_from(surface: &TriMesh, points: &[DVec3]) -> f64 {
        points
            .iter()
            .map(|&p| {
                (0..surface.num_faces())
                    .map(|f| closest_point(p, &surface.corners(f)).distance(p))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
            / 0.8
    }

    #[test]
    fn every_voxel_corner_ends_within_a_voxel_of_the_surface() {
        let volume = finned_ball();
        let (surface, report) = finned_surface(&volume, FACES, None);
        let fit = report.fit;
        // Decimated this far, the surface had left corners more than a
        // voxel behind.
        assert!(fit.farthest_before > Some(1.0) && fit.moves > 0, "{fit:?}");
        let inside: Vec<bool> = volume.values.iter().map(|&v| v == 1.0).collect();
        let voxels = Voxels {
            volume: &volume,
            inside: &inside,
        };
        let corners = voxels.corners();
        assert_eq!(corners.len(), fit.points);
        // The corners are the lattice points with inside and outside
        // voxels among their eight.
        let mut expected = Vec::new();
        for z in 0..=36i64 {
            for y in 0..=36i64 {
                for x in 0..=36i64 {
                    let count = (0..8)
                        .filter(|k| {
                            voxels.at(x - 1 + (k & 1), y - 1 + ((k >> 1) & 1), z - 1 + (k >> 2))
                        })
                        .count();
                    if (1..8).contains(&count) {
                        expected
                            .push(DVec3::new(x as f64 - 0.5, y as f64 - 0.5, z as f64 - 0.5) * 0.8);
                    }
                }
            }
        }
        assert_eq!(corners, expected);
        // The faces' points: the corners, and each boundary face's edge
        // midpoints and centre, on the half-voxel lattice.
        let points = voxels.face_points();
        let halves: std::collections::BTreeSet<[i64; 3]> = points
            .iter()
            .map(|p| (*p / 0.4).round().as_i64vec3().to_array())
            .collect();
        assert_eq!(halves.len(), points.len(), "each point once");
        let faces = boundary_faces(&voxels);
        for &([x, y, z], axis) in &faces {
            let mut centre = [2 * x, 2 * y, 2 * z];
            centre[axis] += 1;
            assert!(halves.contains(&centre), "{centre:?}");
        }
        let faces = faces.len();
        for c in &corners {
            assert!(halves.contains(&(*c / 0.4).round().as_i64vec3().to_array()));
        }
        // The rest are the edges' midpoints: this boundary has no edge
        // where four faces meet, so each of its faces' four edges is
        // shared by two of them.
        let midpoints = points.len() - faces - corners.len();
        assert_eq!(midpoints, 2 * faces);
        let farthest = farthest_from(&surface, &corners);
        assert!(
            farthest <= 1.0,
            "a voxel corner {farthest} voxels from the surface ({fit:?})"
        );
        // The report says the same.
        match fit.farthest {
            Some(d) => assert!((d - farthest).abs() < 1e-9, "{farthest} {fit:?}"),
            None => assert!(farthest <= TOLERANCE, "{farthest} {fit:?}"),
        }
        // Still a closed surface with the decimation's angles.
        assert!(report.min_angle >= MIN_ANGLE, "{}", report.min_angle);
    }

    #[test]
    fn the_nearest_point_of_the_voxel_faces_is_the_nearest_of_all() {
        let volume = finned_ball();
        let inside: Vec<bool> = volume.values.iter().map(|&v| v == 1.0).collect();
        let voxels = Voxels {
            volume: &volume,
            inside: &inside,
        };
        let faces: Vec<(DVec3, usize)> = boundary_faces(&voxels)
            .into_iter()
            .map(|([x, y, z], axis)| {
                let mut centre = DVec3::new(x as f64, y as f64, z as f64);
                centre[axis] += 0.5;
                (centre, axis)
            })
            .collect();
        let to_voxel = volume.to_world.inverse();
        // Points inside, outside, near the fins and far from everything
        // (towards the corners of the grid, 20 voxels from the fins).
        let (mut widened, mut none) = (0, 0);
        for k in 0..400 {
            let q = DVec3::new(
                (k * 7 % 40) as f64 - 2.3,
                (k * 13 % 40) as f64 - 2.7,
                (k * 29 % 40) as f64 - 2.1,
            );
            let brute = faces
                .iter()
                .map(|&(c, a)| off_face(q, c, a).length())
                .fold(f64::INFINITY, f64::min);
            let p = volume.to_world.transform_point3(q);
            match voxels.nearest_on_faces(&to_voxel, p) {
                Some(found) => {
                    let distance = to_voxel.transform_point3(found).distance(q);
                    assert!(
                        (distance - brute).abs() < 1e-9,
                        "{q}: {distance} against {brute}"
                    );
                    widened += (brute > 2.0) as usize;
                }
                None => {
                    assert!(brute > 16.0, "{q}: none found, {brute} away");
                    none += 1;
                }
            }
            assert_eq!(voxels.within(&to_voxel, p, 1.0), brute <= 1.0, "{q}");
        }
        // The search widened past two voxels, and gave up past sixteen.
        assert!(widened > 0 && none > 0, "{widened} {none}");
    }

    #[test]
    fn held_within_its_voxels_the_surface_and_its_voxel_faces_meet_both_ways() {
        // Every point of the voxel faces within a voxel of the surface, and
        // every point of the surface within a voxel of the voxel faces,
        // checked by brute force.
        let volume = finned_ball();
        let (surface, report) = finned_surface(&volume, FACES_BOTH_WAYS, Some(TOLERANCE));
        let fit = report.fit;
        let inside: Vec<bool> = volume.values.iter().map(|&v| v == 1.0).collect();
        let voxels = Voxels {
            volume: &volume,
            inside: &inside,
        };
        let points = voxels.face_points();
        assert_eq!(fit.points, points.len());
        let farthest = farthest_from(&surface, &points);
        assert!(
            farthest <= 1.0,
            "a voxel-face point {farthest} voxels off ({fit:?})"
        );
        let to_voxel = volume.to_world.inverse();
        let mut off: f64 = 0.0;
        for f in 0..surface.num_faces() {
            let t = surface.corners(f);
            for (u, v) in [
                (0.0, 0.0),
                (1.0, 0.0),
                (0.0, 1.0),
                (1.0 / 3.0, 1.0 / 3.0),
                (0.5, 0.0),
                (0.5, 0.5),
                (0.0, 0.5),
            ] {
                let q = t[0] * (1.0 - u - v) + t[1] * u + t[2] * v;
                let n = voxels.nearest_on_faces(&to_voxel, q).unwrap();
                off = off.max(n.distance(q) / 0.8);
            }
        }
        assert!(
            off <= 1.0,
            "a point of the surface {off} voxels off ({fit:?})"
        );
        assert!(
            fit.farthest_off.is_none_or(|d| d <= 1.0) && fit.faces_off.is_some(),
            "{fit:?}"
        );
        assert!(report.min_angle >= MIN_ANGLE, "{}", report.min_angle);
    }

    /// Decimated to this within its voxels, a point of the finned ball's
    /// voxel faces lies 1.005 voxels from the surface before the last fit
    /// (within a voxel after it); at 400, 800 or 1000 faces the decimation
    /// alone keeps them within.
    const FACES_BOTH_WAYS: usize = 600;

    /// Decimated to this, the fins' crests are cut by more than a voxel
    /// (1.19 before the fit, 0.96 after).
    const FACES: usize = 1000;
}
