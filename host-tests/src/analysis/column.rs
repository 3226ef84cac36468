//! A candidate's column over the observations, stored dense or as its nonzero entries: a position error acts
//! on the blocks of one dwell, a channel's term on that channel's blocks, so most candidates are mostly zero.
//! Stored so, the candidates' memory grows with the observations, not with their square
//! (docs/analysis.md#memory-limit).

use std::borrow::Cow;

/// A column over `len` observations.
#[derive(Clone, Debug)]
pub(super) struct Column {
    len: usize,
    store: Store,
}

#[derive(Clone, Debug)]
enum Store {
    Dense(Vec<f64>),
    /// The nonzero entries, by increasing index.
    Sparse {
        index: Vec<u32>,
        value: Vec<f64>,
    },
}

/// Bytes of a dense entry and of a sparse one (index and value).
const DENSE_ENTRY_BYTES: usize = 8;
const SPARSE_ENTRY_BYTES: usize = 12;

impl Column {
    /// `values`, kept as its nonzero entries when that takes less memory.
    pub fn new(values: Vec<f64>) -> Column {
        let nonzero = values.iter().filter(|v| **v != 0.0).count();
        if nonzero * SPARSE_ENTRY_BYTES >= values.len() * DENSE_ENTRY_BYTES || values.len() > u32::MAX as usize {
            return Column { len: values.len(), store: Store::Dense(values) };
        }
        Column::from_entries(values.len(), values.iter().copied().enumerate())
    }

    /// The column of `len` observations that is zero except at `entries` (by increasing index).
    pub fn from_entries(len: usize, entries: impl IntoIterator<Item = (usize, f64)>) -> Column {
        let (mut index, mut value) = (Vec::new(), Vec::new());
        for (i, v) in entries.into_iter().filter(|(_, v)| *v != 0.0) {
            debug_assert!(i < len && index.last().is_none_or(|&last| (last as usize) < i));
            index.push(i as u32);
            value.push(v);
        }
        Column { len, store: Store::Sparse { index, value } }
    }

    /// Every entry.
    pub fn dense(&self) -> Cow<'_, [f64]> {
        match &self.store {
            Store::Dense(v) => Cow::Borrowed(v),
            Store::Sparse { index, value } => {
                let mut v = vec![0.0; self.len];
                for (&i, &x) in index.iter().zip(value) {
                    v[i as usize] = x;
                }
                Cow::Owned(v)
            }
        }
    }

    /// Calls `f(index, value)` for every nonzero entry, by increasing index.
    pub fn for_each_nonzero(&self, mut f: impl FnMut(usize, f64)) {
        match &self.store {
            Store::Dense(v) => v.iter().enumerate().filter(|(_, x)| **x != 0.0).for_each(|(i, &x)| f(i, x)),
            Store::Sparse { index, value } => index.iter().zip(value).for_each(|(&i, &x)| f(i as usize, x)),
        }
    }

    /// `sum_i w_i c_i v_i`.
    pub fn weighted_dot(&self, weights: &[f64], v: &[f64]) -> f64 {
        let mut sum = 0.0;
        self.for_each_nonzero(|i, x| sum += weights[i] * x * v[i]);
        sum
    }

    /// `sum_i w_i c_i o_i` of two columns of the same observations.
    pub fn weighted_dot_column(&self, weights: &[f64], other: &Column) -> f64 {
        match (&self.store, &other.store) {
            (Store::Dense(v), _) => other.weighted_dot(weights, v),
            (_, Store::Dense(v)) => self.weighted_dot(weights, v),
            (Store::Sparse { index: ia, value: va }, Store::Sparse { index: ib, value: vb }) => {
                let (mut a, mut b, mut sum) = (0, 0, 0.0);
                while a < ia.len() && b < ib.len() {
                    match ia[a].cmp(&ib[b]) {
                        std::cmp::Ordering::Less => a += 1,
                        std::cmp::Ordering::Greater => b += 1,
                        std::cmp::Ordering::Equal => {
                            sum += weights[ia[a] as usize] * va[a] * vb[b];
                            (a, b) = (a + 1, b + 1);
                        }
                    }
                }
                sum
            }
        }
    }

    /// Per column `x` of `columns`: `sum_i w_i x_i c_i`.
    pub fn weighted_products(&self, weights: &[f64], columns: &[&[f64]]) -> Vec<f64> {
        let mut out = vec![0.0; columns.len()];
        self.for_each_nonzero(|i, c| {
            let wc = weights[i] * c;
            for (o, x) in out.iter_mut().zip(columns) {
                *o += wc * x[i];
            }
        });
        out
    }

    /// Index of the entry of the largest magnitude (0 for a zero column).
    pub fn argmax_abs(&self) -> usize {
        let mut best = (0, 0.0f64);
        self.for_each_nonzero(|i, x| {
            // The last of equal magnitudes.
            if x.abs() >= best.1 {
                best = (i, x.abs());
            }
        });
        best.0
    }

    /// The column `f` makes of every entry of this one.
    pub fn map_dense(&self, f: impl FnOnce(&[f64]) -> Vec<f64>) -> Column {
        Column::new(f(&self.dense()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mostly_zero_column_is_kept_sparse_and_every_product_matches_the_dense_one() {
        let a = vec![0.0, 2.0, 0.0, 0.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0];
        let b = vec![1.0, 0.5, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0];
        let dense_b: Vec<f64> = (0..12).map(|i| 0.25 * i as f64 - 1.0).collect();
        let w: Vec<f64> = (0..12).map(|i| 1.0 + 0.1 * i as f64).collect();
        let (ca, cb, cd) = (Column::new(a.clone()), Column::new(b.clone()), Column::new(dense_b.clone()));
        assert!(matches!(ca.store, Store::Sparse { .. }) && matches!(cd.store, Store::Dense(_)));
        assert_eq!(ca.dense().as_ref(), a.as_slice());
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).zip(&w).map(|((x, y), w)| w * x * y).sum::<f64>();
        assert_eq!(ca.weighted_dot_column(&w, &cb), dot(&a, &b));
        assert_eq!(ca.weighted_dot_column(&w, &cd), dot(&a, &dense_b));
        assert_eq!(cd.weighted_dot_column(&w, &ca), dot(&a, &dense_b));
        assert_eq!(ca.weighted_products(&w, &[&b, &dense_b]), vec![dot(&a, &b), dot(&a, &dense_b)]);
        assert_eq!(ca.argmax_abs(), 11);
        assert_eq!(Column::from_entries(12, [(1, 2.0), (5, -1.5), (11, 3.0)]).dense().as_ref(), a.as_slice());
    }
}
