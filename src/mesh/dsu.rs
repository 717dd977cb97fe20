//! Disjoint sets (union-find) over `0..n`.
//!
//! Written here rather than taken from a crate: it is twenty lines, and the
//! crates that offer it (petgraph, union-find) would add a dependency for
//! nothing else we use.

pub struct DisjointSets {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl DisjointSets {
    pub fn new(n: usize) -> Self {
        DisjointSets {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    /// A new set of one element, and that element (`len() - 1`).
    pub fn add(&mut self) -> usize {
        self.parent.push(self.parent.len() as u32);
        self.size.push(1);
        self.parent.len() - 1
    }

    /// The number of elements.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Representative of `x`'s set (path halving).
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let grandparent = self.parent[self.parent[x] as usize];
            self.parent[x] = grandparent;
            x = grandparent as usize;
        }
        x
    }

    /// Merge the sets of `a` and `b` (union by size).
    pub fn union(&mut self, a: usize, b: usize) {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        if self.size[ra] < self.size[rb] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb] = ra as u32;
        self.size[ra] += self.size[rb];
    }

    /// Number each set `0..count` in order of first appearance; returns the
    /// label of every element and the number of sets.
    pub fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut label_of_root = vec![u32::MAX; n];
        let mut labels = Vec::with_capacity(n);
        let mut count = 0;
        for x in 0..n {
            let r = self.find(x);
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = count as u32;
                count += 1;
            }
            labels.push(label_of_root[r]);
        }
        (labels, count)
    }
}
