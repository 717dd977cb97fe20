//! The interpolation domain (seed 003, 4.1): the exemplar planes, inserted
//! in the file's order, split the organ's interior into a BSP, as cutting a
//! real specimen in pieces does. Each exemplar splits the one region that
//! holds most of its section; its subdomain X_i is its section inside that
//! region. A region D_j is bounded by the subdomains X_i,j = X_i ∩ D_j of
//! the exemplars above it in the tree, each of which must be a disk (Fig.
//! 2: a plane through both ears of the bunny meets one region twice).

use glam::DVec3;

use super::cells::Cells;
use super::sections::Exemplar;
use crate::error::{Error, Result};
use crate::mesh::{Topology, TriMesh};

/// Cells a side of a rasterised subdomain.
const SUBDOMAIN_SIDE: usize = 512;

#[derive(Clone, Copy, Debug)]
enum Child {
    Node(usize),
    Region(usize),
}

#[derive(Clone, Copy, Debug)]
struct Node {
    exemplar: usize,
    below: Child,
    above: Child,
}

/// Which side of exemplar `.0`'s plane a region lies on (`true`: the
/// normal's side).
pub type Side = (usize, bool);

#[derive(Clone, Debug)]
pub struct Region {
    /// The half-spaces from the root down to this region.
    pub sides: Vec<Side>,
    /// The exemplar subdomains X_i,j bounding it, in insertion order.
    pub bounds: Vec<Bound>,
}

#[derive(Clone, Debug)]
pub struct Bound {
    pub exemplar: usize,
    /// X_i,j in exemplar i's pixel coordinates.
    pub cells: Cells,
}

#[derive(Clone, Debug)]
pub struct Bsp {
    root: Child,
    nodes: Vec<Node>,
    pub regions: Vec<Region>,
    /// Per exemplar, the sides of the region it split (its subdomain X_i
    /// lies inside them).
    pub split: Vec<Vec<Side>>,
}

impl Bsp {
    /// Build the BSP of `exemplars` clipped to the closed `mesh`. Refuses
    /// an exemplar plane that misses the mesh, a photograph that misses
    /// its section, coincident planes and subdomains that are not disks,
    /// each by name.
    pub fn build(mesh: &TriMesh, topology: &Topology, exemplars: &[Exemplar]) -> Result<Bsp> {
        let diagonal = mesh
            .positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let diagonal = (diagonal.1 - diagonal.0).length();
        let mut bsp = Bsp {
            root: Child::Region(0),
            nodes: Vec::new(),
            regions: vec![Region {
                sides: Vec::new(),
                bounds: Vec::new(),
            }],
            split: Vec::new(),
        };
        let mut subdomains = Vec::new();
        for (i, e) in exemplars.iter().enumerate() {
            for (j, f) in exemplars[..i].iter().enumerate() {
                let cos = e.normal.dot(f.normal);
                if cos.abs() > 1.0 - 1e-12
                    && (e.offset - cos.signum() * f.offset).abs() <= 1e-9 * diagonal.max(1.0)
                {
                    return Err(Error::invalid(format!(
                        "{} lies in the plane of {}: two coincident exemplar planes bound no region",
                        e.name(i),
                        f.name(j)
                    )));
                }
            }
            let mut cells =
                Cells::section(mesh, topology, e, 0.0, SUBDOMAIN_SIDE)?.ok_or_else(|| {
                    Error::invalid(format!(
                        "{}: its plane lies outside the mesh (the section is empty)",
                        e.name(i)
                    ))
                })?;
            // Each cell's region, found once: for the vote, then to clip.
            let region: Vec<usize> = cells
                .inside
                .iter()
                .enumerate()
                .map(|(k, &inside)| {
                    let centre = cells.centre(k % cells.w, k / cells.w);
                    if inside {
                        bsp.locate(exemplars, e.point(centre))
                    } else {
                        usize::MAX
                    }
                })
                .collect();
            let mut votes = vec![0usize; bsp.regions.len()];
            for &r in region.iter().filter(|&&r| r != usize::MAX) {
                votes[r] += 1;
            }
            let split =
                (0..votes.len()).fold(0, |best, r| if votes[r] > votes[best] { r } else { best });
            for (inside, &r) in cells.inside.iter_mut().zip(&region) {
                *inside &= r == split;
            }
            let (w, h) = (e.width as f64, e.height as f64);
            if !cells
                .centres()
                .any(|c| c.x >= 0.0 && c.y >= 0.0 && c.x <= w && c.y <= h)
            {
                return Err(Error::invalid(format!(
                    "{}: the photograph does not reach the mesh: its plane cuts the mesh \
                     outside the image's {}x{} pixels",
                    e.name(i),
                    e.width,
                    e.height
                )));
            }
            check_disk(&cells, || e.name(i))?;
            bsp.insert(i, split);
            subdomains.push(cells);
        }
        for region in &mut bsp.regions {
            for &(i, _) in &region.sides {
                let mut cells = subdomains[i].clone();
                cells.retain(&exemplars[i], 0.0, |p| {
                    region
                        .sides
                        .iter()
                        .all(|&(j, s)| j == i || (exemplars[j].height(p) >= 0.0) == s)
                });
                if cells.count() < speck(&subdomains[i]) {
                    continue;
                }
                check_disk(&cells, || {
                    format!("{} where it bounds a BSP region", exemplars[i].name(i))
                })?;
                region.bounds.push(Bound { exemplar: i, cells });
            }
        }
        Ok(bsp)
    }

    /// Replace region `r` by exemplar `i`'s node: `r` keeps the side below
    /// the plane, a new region takes the side above.
    fn insert(&mut self, i: usize, r: usize) {
        let above = self.regions.len();
        let sides = self.regions[r].sides.clone();
        self.split.push(sides.clone());
        self.regions.push(Region {
            sides: [sides, vec![(i, true)]].concat(),
            bounds: Vec::new(),
        });
        self.regions[r].sides.push((i, false));
        let node = self.nodes.len();
        let slot = std::iter::once(&mut self.root)
            .chain(
                self.nodes
                    .iter_mut()
                    .flat_map(|n| [&mut n.below, &mut n.above]),
            )
            .find(|c| matches!(c, Child::Region(x) if *x == r));
        // Every region is a leaf of the tree: `r` came from `locate`.
        *slot.expect("region is a leaf") = Child::Node(node);
        self.nodes.push(Node {
            exemplar: i,
            below: Child::Region(r),
            above: Child::Region(above),
        });
    }

    /// The region holding `p`: down the tree by the side of each plane.
    #[inline]
    pub fn locate(&self, exemplars: &[Exemplar], p: DVec3) -> usize {
        let mut c = self.root;
        loop {
            match c {
                Child::Region(r) => return r,
                Child::Node(n) => {
                    let node = &self.nodes[n];
                    c = if exemplars[node.exemplar].height(p) >= 0.0 {
                        node.above
                    } else {
                        node.below
                    };
                }
            }
        }
    }
}

/// Pieces below this many cells are raster noise where a plane grazes the
/// surface, not a second piece.
fn speck(cells: &Cells) -> usize {
    (cells.count() / 200).max(4)
}

fn check_disk(cells: &Cells, name: impl Fn() -> String) -> Result<()> {
    let (pieces, holes) = cells.pieces_and_holes(speck(cells));
    if pieces == 1 && holes == 0 {
        return Ok(());
    }
    let what = if pieces != 1 {
        format!("meets its region in {pieces} pieces")
    } else {
        format!("has {holes} hole{}", if holes == 1 { "" } else { "s" })
    };
    Err(Error::invalid(format!(
        "{} {what}: every exemplar subdomain must be a disk (seed 003, 4.1 and Fig. 2); \
         add an exemplar plane, before this one in the file, that splits it",
        name()
    )))
}
