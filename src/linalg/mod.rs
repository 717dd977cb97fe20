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
//! factorisation included), so Newton iterations only refill values.
//! Factorisation runs single-threaded: a parallel supernodal sum may round
//! differently with the thread count, and organtex promises the same bytes
//! on any number of threads; the callers parallelise around it instead.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Par, Side};

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
    llt: SymbolicLlt<usize>,
    entries: usize,
}

/// A factorised SPD matrix.
pub struct Cholesky {
    llt: Llt<usize, f64>,
    n: usize,
}

impl SpdPattern {
    /// The pattern of the given positions, duplicates merged. The columns
    /// are gathered by a counting sort and each column's rows deduplicated
    /// with a marker per row, so only each column's few distinct rows are
    /// sorted: faer's own constructor sorts all the positions, which on an
    /// unwrap's layout (2.4M of them) cost as much as the factorisation.
    pub fn new(n: usize, positions: &[(u32, u32)]) -> Result<SpdPattern> {
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
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        let llt = SymbolicLlt::try_new(symbolic.as_ref(), Side::Lower)
            .map_err(|e| Error::invalid(format!("symbolic Cholesky: {e:?}")))?;
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
        let llt = SymbolicLlt::try_new(symbolic.as_ref(), Side::Lower)
            .map_err(|e| Error::invalid(format!("symbolic Cholesky: {e:?}")))?;
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
        faer::set_global_parallelism(Par::Seq);
        let llt = Llt::try_new_with_symbolic(self.llt.clone(), matrix.as_ref(), Side::Lower)
            .map_err(|e| Error::invalid(format!("the system is not positive definite ({e:?})")))?;
        Ok(Cholesky { llt, n: self.n })
    }
}

impl Cholesky {
    /// Solve `A x = b` in place (`b` becomes `x`).
    pub fn solve(&self, b: &mut [f64]) {
        assert_eq!(b.len(), self.n);
        let mut rhs = Mat::from_fn(self.n, 1, |i, _| b[i]);
        self.llt.solve_in_place(rhs.as_mut());
        for (i, x) in b.iter_mut().enumerate() {
            *x = rhs[(i, 0)];
        }
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
}
