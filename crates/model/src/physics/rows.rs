//! The constant Jacobian rows of the translational fast path, as tables that
//! answer the two operations it needs: a row times a vector, and a vector
//! plus a multiple of a row. Small models keep dense rows whose length is a
//! compile-time constant (fully unrolled); models whose rows have few
//! non-zero entries keep only those, so the cost follows the couplings the
//! stage has (an isolator joins two bodies, a contact touches one) instead of
//! the square of its degrees of freedom: a fixed count `K` of entries per row
//! when no row has more than four (unrolled, no loop bounds to load), else
//! each row's own count.
//!
//! Every table sums a row's products in column order, so the three give the
//! same sums: the products with zero that the sparse tables leave out add an
//! exact zero.

use crate::scalar::Scalar;

/// A table of rows, each `columns()` long.
pub(crate) trait RowTable {
    /// Length of each row (the degrees of freedom).
    fn columns(&self) -> usize;
    /// Row `k` times `b`, summed in order of the columns.
    fn dot<S: Scalar>(&self, k: usize, b: &[S]) -> S;
    /// `y += alpha * row k`.
    fn axpy<S: Scalar>(&self, k: usize, alpha: S, y: &mut [S]);
}

/// Row-major dense rows of `N` entries (`N` = [`DYNAMIC`]: `nv`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct DenseRows<'a, const N: usize> {
    pub table: &'a [f64],
    pub nv: usize,
}

/// Row length marker for "known only at run time".
pub(crate) const DYNAMIC: usize = 0;

impl<const N: usize> DenseRows<'_, N> {
    #[inline(always)]
    fn row(&self, k: usize) -> &[f64] {
        let nv = self.columns();
        &self.table[k * nv..(k + 1) * nv]
    }
}

impl<const N: usize> RowTable for DenseRows<'_, N> {
    #[inline(always)]
    fn columns(&self) -> usize {
        if N == DYNAMIC { self.nv } else { N }
    }

    #[inline(always)]
    fn dot<S: Scalar>(&self, k: usize, b: &[S]) -> S {
        dot(self.row(k), b)
    }

    #[inline(always)]
    fn axpy<S: Scalar>(&self, k: usize, alpha: S, y: &mut [S]) {
        let x = self.row(k);
        let y = &mut y[..x.len()];
        for i in 0..x.len() {
            y[i] += alpha * S::constant(x[i]);
        }
    }
}

/// `a . b` over `a`'s length, summed in order (index loops over pre-sliced
/// operands compile to fewer instructions than iterator chains for the
/// handful of entries these rows have).
#[inline(always)]
pub(crate) fn dot<S: Scalar>(a: &[f64], b: &[S]) -> S {
    let b = &b[..a.len()];
    // -0.0 is the exact additive identity (+0.0 is not, for -0.0), so the
    // compiler drops the first addition.
    let mut sum = S::constant(-0.0);
    for i in 0..a.len() {
        sum += b[i] * S::constant(a[i]);
    }
    sum
}

/// The non-zero entries of each row, in column order (compressed rows).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SparseRows {
    columns: usize,
    /// Row `k` is `entries[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
    entries: Vec<(usize, f64)>,
}

impl SparseRows {
    /// The non-zero entries of a row-major table with rows of `columns`.
    pub(crate) fn from_dense(table: &[f64], columns: usize) -> Self {
        let mut starts = vec![0];
        let mut entries = Vec::new();
        for row in table.chunks(columns.max(1)) {
            entries.extend(
                row.iter()
                    .enumerate()
                    .filter(|(_, a)| **a != 0.0)
                    .map(|(i, a)| (i, *a)),
            );
            starts.push(entries.len());
        }
        Self {
            columns,
            starts,
            entries,
        }
    }

    #[inline(always)]
    fn row(&self, k: usize) -> &[(usize, f64)] {
        &self.entries[self.starts[k]..self.starts[k + 1]]
    }
}

impl RowTable for &SparseRows {
    #[inline(always)]
    fn columns(&self) -> usize {
        self.columns
    }

    #[inline(always)]
    fn dot<S: Scalar>(&self, k: usize, b: &[S]) -> S {
        let mut sum = S::constant(-0.0);
        for &(i, a) in self.row(k) {
            sum += b[i] * S::constant(a);
        }
        sum
    }

    #[inline(always)]
    fn axpy<S: Scalar>(&self, k: usize, alpha: S, y: &mut [S]) {
        for &(i, a) in self.row(k) {
            y[i] += alpha * S::constant(a);
        }
    }
}

/// Exactly `K` entries per row, in column order: a row's non-zero entries,
/// padded with zero coefficients on its last column (adding an exact zero
/// after the row's sum changes nothing but, at most, the sign of a zero sum).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PackedRows<const K: usize> {
    columns: usize,
    rows: Vec<[(usize, f64); K]>,
}

impl<const K: usize> PackedRows<K> {
    /// The non-zero entries of a row-major table with rows of `columns`, or
    /// `None` when a row has more than `K` of them.
    pub(crate) fn from_dense(table: &[f64], columns: usize) -> Option<Self> {
        let columns = columns.max(1);
        let rows = table
            .chunks(columns)
            .map(|row| {
                let mut packed = [(columns - 1, 0.0); K];
                let mut nonzero = row.iter().enumerate().filter(|(_, a)| **a != 0.0);
                for slot in &mut packed {
                    if let Some((i, a)) = nonzero.next() {
                        *slot = (i, *a);
                    }
                }
                nonzero.next().is_none().then_some(packed)
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Self { columns, rows })
    }
}

impl<const K: usize> RowTable for &PackedRows<K> {
    #[inline(always)]
    fn columns(&self) -> usize {
        self.columns
    }

    #[inline(always)]
    fn dot<S: Scalar>(&self, k: usize, b: &[S]) -> S {
        let b = &b[..self.columns];
        let mut sum = S::constant(-0.0);
        for &(i, a) in &self.rows[k] {
            sum += b[i] * S::constant(a);
        }
        sum
    }

    #[inline(always)]
    fn axpy<S: Scalar>(&self, k: usize, alpha: S, y: &mut [S]) {
        let y = &mut y[..self.columns];
        for &(i, a) in &self.rows[k] {
            y[i] += alpha * S::constant(a);
        }
    }
}

/// The most non-zero entries in any row of the row-major `tables` with rows
/// of `columns`.
pub(crate) fn most_nonzeros(tables: &[&[f64]], columns: usize) -> usize {
    tables
        .iter()
        .flat_map(|table| table.chunks(columns.max(1)))
        .map(|row| row.iter().filter(|a| **a != 0.0).count())
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_rows_give_the_dense_products() {
        let table = [0.0, 2.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 1.0];
        let sparse = SparseRows::from_dense(&table, 4);
        let dense = DenseRows::<4> {
            table: &table,
            nv: 4,
        };
        let b = [1.0, -3.0, 0.5, 2.0];
        for k in 0..3 {
            assert_eq!((&sparse).dot(k, &b), dense.dot(k, &b));
            let (mut y_sparse, mut y_dense) = ([1.0; 4], [1.0; 4]);
            (&sparse).axpy(k, 0.7, &mut y_sparse);
            dense.axpy(k, 0.7, &mut y_dense);
            assert_eq!(y_sparse, y_dense);
        }
        assert_eq!(sparse.entries.len(), 4);
        assert_eq!((&sparse).dot(1, &b), 0.0);
    }

    #[test]
    fn packed_rows_give_the_dense_products_and_refuse_full_rows() {
        let table = [0.0, 2.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 1.0];
        assert_eq!(most_nonzeros(&[&table], 4), 2);
        assert!(PackedRows::<1>::from_dense(&table, 4).is_none());
        let packed = PackedRows::<2>::from_dense(&table, 4).unwrap();
        let dense = DenseRows::<4> {
            table: &table,
            nv: 4,
        };
        let b = [1.0, -3.0, 0.5, 2.0];
        for k in 0..3 {
            assert_eq!((&packed).dot(k, &b), dense.dot(k, &b));
            let (mut y_packed, mut y_dense) = ([1.0; 4], [1.0; 4]);
            (&packed).axpy(k, 0.7, &mut y_packed);
            dense.axpy(k, 0.7, &mut y_dense);
            assert_eq!(y_packed, y_dense);
        }
    }
}
