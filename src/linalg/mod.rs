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
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Par, Side};

use crate::error::{Error, Result};

/// The sparsity pattern of an n x n SPD matrix, given by the (row, col)
/// positions of its entries in the lower triangle (row >= col). Positions may
/// repeat: their values are summed.
pub struct SpdPattern {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// Where each given value goes, when the positions were not given in
    /// column order (`new`); `None` when they were (`from_columns`).
    argsort: Option<Argsort<usize>>,
    llt: SymbolicLlt<usize>,
    entries: usize,
}

/// A factorised SPD matrix.
pub struct Cholesky {
    llt: Llt<usize, f64>,
    n: usize,
}

impl SpdPattern {
    pub fn new(n: usize, positions: &[(u32, u32)]) -> Result<SpdPattern> {
        debug_assert!(positions.iter().all(|&(r, c)| r >= c && (r as usize) < n));
        let pairs: Vec<Pair<usize, usize>> = positions
            .iter()
            .map(|&(r, c)| Pair::new(r as usize, c as usize))
            .collect();
        let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs)
            .map_err(|e| Error::invalid(format!("sparse pattern: {e:?}")))?;
        let llt = SymbolicLlt::try_new(symbolic.as_ref(), Side::Lower)
            .map_err(|e| Error::invalid(format!("symbolic Cholesky: {e:?}")))?;
        Ok(SpdPattern {
            n,
            symbolic,
            argsort: Some(argsort),
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
            argsort: None,
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
        let matrix = match &self.argsort {
            Some(argsort) => SparseColMat::new_from_argsort(self.symbolic.clone(), argsort, values)
                .map_err(|e| Error::invalid(format!("sparse matrix: {e:?}")))?,
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
