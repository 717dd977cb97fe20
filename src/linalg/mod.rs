//! Sparse symmetric positive definite systems, the one kind of linear algebra
//! the flattener needs (ABF++'s reduced Newton system, the least-squares
//! layout). Assembled from (row, col, value) entries, factored by faer's
//! supernodal sparse Cholesky; the choice of solver stays in this file.
//!
//! Assembly goes straight into faer's triplets rather than through sprs
//! (which DESIGN.md names for assembly): faer both assembles and factors,
//! so sprs would only add a conversion of every matrix between the two
//! crates' layouts and a second sparse dependency, for no operation faer
//! lacks.
//!
//! A `SpdPattern` fixes the sparsity once (ordering and symbolic
//! factorisation included), so Newton iterations only refill values. The
//! fill-reducing ordering (AMD) is most of a pattern's cost, and the
//! systems an unwrap solves live on a mesh's vertices (the estimate of
//! every Seamster round on the surface; ABF++'s, the layout's and the
//! balancing's on its cut chart): a `VertexOrder` orders a mesh's vertices
//! once and each of its systems takes its unknowns in that order
//! (`SpdPattern::ordered`).
//! Factorisation runs single-threaded: a parallel supernodal sum may round
//! differently with the thread count, and organtex promises the same bytes
//! on any number of threads; the callers parallelise around it instead.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::error::{Error, Result};

/// The sparsity pattern of an n x n SPD matrix, given by the (row, col)
/// positions of its entries in the lower triangle (row >= col). Positions may
/// repeat: their values are summed.
pub struct SpdPattern {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// The stored entry each given value is added to, when the positions
    /// were not given in column order (`new`); `None` when they were
    /// (`from_columns`).
    slot: Option<Vec<u32>>,
    llt: Arc<SymbolicCholesky<usize>>,
    entries: usize,
}

/// A factorised SPD matrix.
pub struct Cholesky {
    llt: Arc<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    n: usize,
}

/// A fill-reducing elimination order of a mesh's vertices (AMD on its edge
/// graph), for the systems whose unknowns are those vertices, some of
/// them, or one or two per vertex.
#[derive(Clone, Debug)]
pub struct VertexOrder {
    /// Each vertex's place in the order.
    rank: Vec<u32>,
}

impl VertexOrder {
    /// The order of `n` vertices joined by `edges`.
    pub fn amd(n: usize, edges: impl Iterator<Item = (u32, u32)>) -> Result<VertexOrder> {
        let positions: Vec<(u32, u32)> = edges
            .map(|(a, b)| (a.max(b), a.min(b)))
            .chain((0..n as u32).map(|v| (v, v)))
            .collect();
        let (col_ptr, rows, _) = gather_columns(n, &positions)?;
        let nnz = rows.len();
        let graph = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
        let mut scratch = MemBuffer::new(amd::order_scratch::<usize>(n, nnz));
        amd::order(
            &mut fwd,
            &mut inv,
            graph.as_ref(),
            amd::Control::default(),
            MemStack::new(&mut scratch),
        )
        .map_err(|e| Error::invalid(format!("vertex ordering: {e:?}")))?;
        Ok(VertexOrder {
            rank: inv.into_iter().map(|r| r as u32).collect(),
        })
    }

    /// The order of `n` vertices joined by the edges of `triangles`.
    pub fn of_triangles(n: usize, triangles: &[[u32; 3]]) -> Result<VertexOrder> {
        VertexOrder::amd(
            n,
            triangles
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]),
        )
    }

    /// The elimination order of a system whose unknowns are
    /// `block * index[v] + j` (j < `block`) for the vertices with an
    /// `index` (`u32::MAX`: none): the vertices' order, each vertex's
    /// unknowns together.
    pub fn unknowns(&self, index: &[u32], block: usize) -> Vec<usize> {
        assert_eq!(index.len(), self.rank.len(), "one index per vertex");
        let mut vertices: Vec<usize> = (0..index.len()).filter(|&v| index[v] != u32::MAX).collect();
        vertices.sort_unstable_by_key(|&v| self.rank[v]);
        vertices
            .iter()
            .flat_map(|&v| (0..block).map(move |j| block * index[v] as usize + j))
            .collect()
    }
}

/// The columns of the lower-triangle positions given (duplicates merged,
/// rows sorted): column starts, rows, and the stored entry of each
/// position. A counting sort gathers the columns and a marker per row
/// deduplicates each, so only each column's few distinct rows are
/// sorted: faer's own constructor sorts all the positions, which on an
/// unwrap's layout (2.4M of them) cost as much as the factorisation.
fn gather_columns(
    n: usize,
    positions: &[(u32, u32)],
) -> Result<(Vec<usize>, Vec<usize>, Vec<u32>)> {
    if let Some(&(r, c)) = positions.iter().find(|&&(r, c)| r < c || r as usize >= n) {
        return Err(Error::invalid(format!(
            "sparse pattern: ({r}, {c}) is not in the lower triangle of a {n} x {n} matrix"
        )));
    }
    if positions.len() > u32::MAX as usize {
        return Err(Error::invalid("sparse pattern: too many entries"));
    }
    // The positions, column by column, in their given order.
    let mut by_column = vec![0u32; n + 1];
    for &(_, c) in positions {
        by_column[c as usize + 1] += 1;
    }
    for c in 0..n {
        by_column[c + 1] += by_column[c];
    }
    let mut fill = by_column.clone();
    let mut order = vec![0u32; positions.len()];
    for (k, &(_, c)) in positions.iter().enumerate() {
        order[fill[c as usize] as usize] = k as u32;
        fill[c as usize] += 1;
    }
    // Each column's distinct rows, sorted, and where each position goes.
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut rows: Vec<usize> = Vec::new();
    let mut slot = vec![0u32; positions.len()];
    let mut slot_of_row = vec![u32::MAX; n];
    col_ptr.push(0);
    for c in 0..n {
        let column = &order[by_column[c] as usize..by_column[c + 1] as usize];
        let start = rows.len();
        for &k in column {
            let r = positions[k as usize].0 as usize;
            if slot_of_row[r] == u32::MAX {
                slot_of_row[r] = 0;
                rows.push(r);
            }
        }
        rows[start..].sort_unstable();
        for (i, &r) in rows[start..].iter().enumerate() {
            slot_of_row[r] = (start + i) as u32;
        }
        for &k in column {
            slot[k as usize] = slot_of_row[positions[k as usize].0 as usize];
        }
        for &r in &rows[start..] {
            slot_of_row[r] = u32::MAX;
        }
        col_ptr.push(rows.len());
    }
    Ok((col_ptr, rows, slot))
}

/// The symbolic Cholesky factorisation of a lower-triangle pattern, in
/// the given elimination order (`None`: AMD's).
fn symbolic_cholesky(
    pattern: &SymbolicSparseColMat<usize>,
    order: Option<&[usize]>,
) -> Result<Arc<SymbolicCholesky<usize>>> {
    let n = pattern.nrows();
    if let Some(fwd) = order
        && (fwd.len() != n || fwd.iter().any(|&i| i >= n))
    {
        return Err(Error::invalid(format!(
            "sparse pattern: the elimination order is not a permutation of {n} unknowns"
        )));
    }
    let inverse = order.map(|fwd| {
        let mut inv = vec![usize::MAX; n];
        for (k, &i) in fwd.iter().enumerate() {
            inv[i] = k;
        }
        inv
    });
    let ordering = match (order, &inverse) {
        (Some(fwd), Some(inv)) => {
            if inv
                .iter()
                .enumerate()
                .any(|(i, &k)| k == usize::MAX || fwd[k] != i)
            {
                return Err(Error::invalid(format!(
                    "sparse pattern: the elimination order is not a permutation of {n} unknowns"
                )));
            }
            SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n))
        }
        _ => SymmetricOrdering::Amd,
    };
    factorize_symbolic_cholesky(pattern.as_ref(), Side::Lower, ordering, Default::default())
        .map(Arc::new)
        .map_err(|e| Error::invalid(format!("symbolic Cholesky: {e:?}")))
}

impl SpdPattern {
    /// The pattern of the given positions, duplicates merged, ordered by
    /// AMD.
    pub fn new(n: usize, positions: &[(u32, u32)]) -> Result<SpdPattern> {
        SpdPattern::with_order(n, positions, None)
    }

    /// The pattern of the given positions, its unknowns eliminated in
    /// `order` (`VertexOrder::unknowns`).
    pub fn ordered(n: usize, positions: &[(u32, u32)], order: &[usize]) -> Result<SpdPattern> {
        SpdPattern::with_order(n, positions, Some(order))
    }

    /// The pattern of a system whose unknowns are `block * index[v] + j`
    /// for a mesh's vertices `v` (`VertexOrder::unknowns`), eliminated in
    /// `order` of those vertices when one is given, else by AMD.
    pub fn of_vertices(
        n: usize,
        positions: &[(u32, u32)],
        order: Option<&VertexOrder>,
        index: &[u32],
        block: usize,
    ) -> Result<SpdPattern> {
        match order {
            Some(order) => SpdPattern::ordered(n, positions, &order.unknowns(index, block)),
            None => SpdPattern::new(n, positions),
        }
    }

    fn with_order(
        n: usize,
        positions: &[(u32, u32)],
        order: Option<&[usize]>,
    ) -> Result<SpdPattern> {
        let (col_ptr, rows, slot) = gather_columns(n, positions)?;
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        let llt = symbolic_cholesky(&symbolic, order)?;
        Ok(SpdPattern {
            n,
            symbolic,
            slot: Some(slot),
            llt,
            entries: positions.len(),
        })
    }

    /// The pattern whose column `j` holds the rows `rows[col_start[j]..
    /// col_start[j + 1]]` (all `>= j`, each once, in any order): values
    /// are then given in that order, with no sort of the positions.
    pub fn from_columns(n: usize, col_start: Vec<usize>, rows: Vec<usize>) -> Result<SpdPattern> {
        debug_assert!((0..n).all(|j| {
            let column = &rows[col_start[j]..col_start[j + 1]];
            column.iter().all(|&r| r >= j && r < n)
                && column
                    .iter()
                    .collect::<std::collections::HashSet<_>>()
                    .len()
                    == column.len()
        }));
        let entries = rows.len();
        let symbolic = SymbolicSparseColMat::new_unsorted_checked(n, n, col_start, None, rows);
        let llt = symbolic_cholesky(&symbolic, None)?;
        Ok(SpdPattern {
            n,
            symbolic,
            slot: None,
            llt,
            entries,
        })
    }

    pub fn size(&self) -> usize {
        self.n
    }

    /// How many values `factor` takes.
    pub fn entries(&self) -> usize {
        self.entries
    }

    /// Factor the matrix whose entries (in the order of the positions given
    /// to `new`, or of the rows given to `from_columns`) are `values`. Fails if it is not positive definite.
    pub fn factor(&self, values: &[f64]) -> Result<Cholesky> {
        assert_eq!(values.len(), self.entries, "one value per position");
        let matrix = match &self.slot {
            Some(slot) => {
                let mut summed = vec![0.0; self.symbolic.row_idx().len()];
                for (&s, &v) in slot.iter().zip(values) {
                    summed[s as usize] += v;
                }
                SparseColMat::new(self.symbolic.clone(), summed)
            }
            None => SparseColMat::new(self.symbolic.clone(), values.to_vec()),
        };
        let mut values = vec![0.0; self.llt.len_val()];
        let par = Par::Seq;
        let mut scratch = MemBuffer::new(
            self.llt
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        );
        self.llt
            .factorize_numeric_llt(
                &mut values,
                matrix.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut scratch),
                Default::default(),
            )
            .map_err(|e| Error::invalid(format!("the system is not positive definite ({e:?})")))?;
        Ok(Cholesky {
            llt: self.llt.clone(),
            values,
            n: self.n,
        })
    }
}

impl Cholesky {
    /// Solve `A x = b` in place (`b` becomes `x`).
    pub fn solve(&self, b: &mut [f64]) {
        assert_eq!(b.len(), self.n);
        let par = Par::Seq;
        let mut scratch = MemBuffer::new(self.llt.solve_in_place_scratch::<f64>(1, par));
        // In `b` itself, with no copy.
        LltRef::new(&self.llt, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(b, self.n, 1),
            par,
            MemStack::new(&mut scratch),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian plus identity: tridiagonal, SPD, known solution.
    #[test]
    fn solves_a_tridiagonal_system_and_sums_repeated_entries() {
        let n = 50;
        let mut positions = Vec::new();
        let mut values = Vec::new();
        for i in 0..n as u32 {
            // The diagonal 3 given as 1 + 2 to check summation.
            positions.push((i, i));
            values.push(1.0);
            positions.push((i, i));
            values.push(2.0);
            if i > 0 {
                positions.push((i, i - 1));
                values.push(-1.0);
            }
        }
        let pattern = SpdPattern::new(n, &positions).unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let mut b: Vec<f64> = (0..n)
            .map(|i| {
                3.0 * x_true[i]
                    - if i > 0 { x_true[i - 1] } else { 0.0 }
                    - x_true.get(i + 1).copied().unwrap_or(0.0)
            })
            .collect();
        pattern.factor(&values).unwrap().solve(&mut b);
        for (x, t) in b.iter().zip(&x_true) {
            assert!((x - t).abs() < 1e-12);
        }
        // Not positive definite: refused, not a panic.
        let negative: Vec<f64> = values.iter().map(|v| -v).collect();
        assert!(pattern.factor(&negative).is_err());
    }

    /// A grid's Laplacian plus identity, two unknowns per vertex, some
    /// vertices left out: solved in a `VertexOrder` of the grid as by AMD,
    /// and an order that is not a permutation is refused.
    #[test]
    fn a_vertex_order_solves_what_amd_solves() {
        let side = 12u32;
        let vertex = |x: u32, y: u32| y * side + x;
        let mut triangles = Vec::new();
        for y in 0..side - 1 {
            for x in 0..side - 1 {
                triangles.push([vertex(x, y), vertex(x + 1, y), vertex(x + 1, y + 1)]);
                triangles.push([vertex(x, y), vertex(x + 1, y + 1), vertex(x, y + 1)]);
            }
        }
        let n = (side * side) as usize;
        let order = VertexOrder::of_triangles(n, &triangles).unwrap();
        // Every third vertex has no unknowns.
        let mut index = vec![u32::MAX; n];
        let mut count = 0;
        for (v, slot) in index.iter_mut().enumerate() {
            if v % 3 != 0 {
                *slot = count;
                count += 1;
            }
        }
        let unknowns = 2 * count as usize;
        let mut positions = Vec::new();
        let mut values = Vec::new();
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (index[t[k] as usize], index[t[(k + 1) % 3] as usize]);
                for j in 0..2 {
                    for p in [a, b].into_iter().filter(|&p| p != u32::MAX) {
                        positions.push((2 * p + j, 2 * p + j));
                        values.push(1.5);
                    }
                    if a != u32::MAX && b != u32::MAX {
                        let (r, c) = (2 * a.max(b) + j, 2 * a.min(b) + j);
                        positions.push((r, c));
                        values.push(-0.5);
                    }
                }
            }
        }
        let rhs: Vec<f64> = (0..unknowns).map(|i| (i as f64 * 0.7).cos()).collect();
        let solve = |pattern: SpdPattern| {
            let mut x = rhs.clone();
            pattern.factor(&values).unwrap().solve(&mut x);
            x
        };
        let elimination = order.unknowns(&index, 2);
        let mut sorted = elimination.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..unknowns).collect::<Vec<_>>());
        let by_amd = solve(SpdPattern::new(unknowns, &positions).unwrap());
        let by_vertices = solve(SpdPattern::ordered(unknowns, &positions, &elimination).unwrap());
        for (a, b) in by_amd.iter().zip(&by_vertices) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        let mut twice = elimination.clone();
        twice[1] = twice[0];
        assert!(SpdPattern::ordered(unknowns, &positions, &twice).is_err());
        assert!(SpdPattern::ordered(unknowns, &positions, &elimination[1..]).is_err());
        let mut beyond = elimination.clone();
        beyond[0] = unknowns;
        assert!(SpdPattern::ordered(unknowns, &positions, &beyond).is_err());
    }
}
