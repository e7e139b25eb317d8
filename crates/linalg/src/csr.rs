//! A square sparse matrix in compressed rows with a pattern fixed at creation, assembled by
//! adding entries (a Jacobian's pieces add up where two terms meet).

/// CSR storage: row i's columns are `col_idx[row_ptr[i]..row_ptr[i + 1]]`, increasing.
/// A trail entry: the position k an addition of `len` values at column j found, that span
/// having been checked against the pattern (which never changes). Holding j here, the replay
/// reads the trail in order and no column index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Found {
    k: usize,
    j: usize,
    len: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Csr {
    n: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<usize>,
    values: Vec<f64>,
    /// Additions that fell outside the pattern since the last [`Csr::zero`].
    outside: usize,
    /// The positions found by the additions since the last [`Csr::zero`], in call order,
    /// and the next call's index: an assembler adds in the same order every time, so each
    /// addition first tries the position its predecessor in the last assembly found (checked
    /// against the row and column, so a different order only costs the search).
    trail: Vec<Found>,
    cursor: usize,
}

impl Csr {
    /// The n×n zero matrix whose row i may hold the columns `rows[i]` (any order, repeats
    /// allowed). Panics if a column is ≥ n: the pattern is the assembler's own.
    pub fn from_rows(rows: Vec<Vec<usize>>) -> Csr {
        let n = rows.len();
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut col_idx = Vec::new();
        row_ptr.push(0);
        for mut cols in rows {
            cols.sort_unstable();
            cols.dedup();
            assert!(
                cols.last().is_none_or(|&c| c < n),
                "column outside a {n}×{n} pattern"
            );
            col_idx.extend(cols);
            row_ptr.push(col_idx.len());
        }
        let values = vec![0.0; col_idx.len()];
        Csr {
            n,
            row_ptr,
            col_idx,
            values,
            outside: 0,
            trail: Vec::new(),
            cursor: 0,
        }
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn nnz(&self) -> usize {
        self.col_idx.len()
    }

    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }

    pub fn col_idx(&self) -> &[usize] {
        &self.col_idx
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Row i: its columns and values.
    #[inline]
    pub fn row(&self, i: usize) -> (&[usize], &[f64]) {
        let (lo, hi) = (self.row_ptr[i], self.row_ptr[i + 1]);
        (&self.col_idx[lo..hi], &self.values[lo..hi])
    }

    /// Zero the values (the pattern stays).
    pub fn zero(&mut self) {
        self.values.fill(0.0);
        self.outside = 0;
        self.cursor = 0;
    }

    #[inline]
    fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (lo, hi) = (self.row_ptr[i], self.row_ptr[i + 1]);
        self.col_idx[lo..hi].binary_search(&j).ok().map(|k| lo + k)
    }

    /// The position of a span of `len` columns from j in row i, all in the pattern: the
    /// trail's guess if it is that span in row i, else a search, remembered for the next
    /// assembly (the trail stops growing at 4 entries per nonzero, for callers that add
    /// without ever zeroing).
    #[inline]
    fn locate(&mut self, i: usize, j: usize, len: usize) -> Result<usize, usize> {
        let c = self.cursor;
        self.cursor += 1;
        if let Some(&t) = self.trail.get(c) {
            if t.j == j && t.len == len && t.k >= self.row_ptr[i] && t.k < self.row_ptr[i + 1] {
                return Ok(t.k);
            }
        }
        let found = self.span_position(i, j, len);
        let t = Found {
            k: found.unwrap_or(usize::MAX),
            j,
            len,
        };
        if c < self.trail.len() {
            self.trail[c] = t;
        } else if c == self.trail.len() && c < 4 * self.col_idx.len() + 64 {
            self.trail.push(t);
        }
        found
    }

    /// Where the span of `len` consecutive columns from j starts in row i, or the column
    /// outside the pattern.
    fn span_position(&self, i: usize, j: usize, len: usize) -> Result<usize, usize> {
        let k = self.position(i, j).ok_or(j)?;
        let end = k + len;
        if end > self.row_ptr[i + 1] || self.col_idx[end - 1] != j + len - 1 {
            return Err(j + len - 1);
        }
        Ok(k)
    }

    /// A(i, j) += v. Outside the pattern nothing is written and the miss is counted
    /// ([`Csr::take_outside`]); debug builds panic.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        match self.locate(i, j, 1) {
            Ok(k) => self.values[k] += v,
            Err(col) => self.miss(i, col),
        }
    }

    /// A(i, j0 + t) += v\[t\] for consecutive columns j0, j0 + 1, …, all in the pattern: one
    /// search for the whole span.
    #[inline]
    pub fn add_span(&mut self, i: usize, j0: usize, v: &[f64]) {
        match self.locate(i, j0, v.len()) {
            Ok(k) => {
                for (a, b) in self.values[k..k + v.len()].iter_mut().zip(v) {
                    *a += b;
                }
            }
            Err(col) => self.miss(i, col),
        }
    }

    fn miss(&mut self, i: usize, j: usize) {
        debug_assert!(false, "({i}, {j}) is outside the pattern");
        self.outside += 1;
    }

    /// The number of additions outside the pattern since the last zero; resets it.
    pub fn take_outside(&mut self) -> usize {
        std::mem::take(&mut self.outside)
    }

    /// A(i, j), zero outside the pattern.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.position(i, j).map_or(0.0, |k| self.values[k])
    }

    /// y = A x.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate().take(self.n) {
            let (cols, vals) = self.row(i);
            *yi = cols.iter().zip(vals).map(|(&j, v)| v * x[j]).sum();
        }
    }

    /// Y_j = A X_j for several vectors in one pass over A per four of them (the pattern and
    /// values, larger than the cache, are read once for all four); each product sums in
    /// [`Csr::mul`]'s order, so it is the same to the bit.
    pub fn mul_many(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        assert_eq!(xs.len(), ys.len(), "as many products as vectors");
        for (x, y) in xs.chunks(4).zip(ys.chunks_mut(4)) {
            match x.len() {
                1 => self.mul_lanes::<1>(x, y),
                2 => self.mul_lanes::<2>(x, y),
                3 => self.mul_lanes::<3>(x, y),
                _ => self.mul_lanes::<4>(x, y),
            }
        }
    }

    fn mul_lanes<const W: usize>(&self, xs: &[&[f64]], ys: &mut [&mut [f64]]) {
        let x: [&[f64]; W] = std::array::from_fn(|l| &xs[l][..self.n]);
        for i in 0..self.n {
            let (cols, vals) = self.row(i);
            let mut acc = [-0.0; W];
            for (&j, &v) in cols.iter().zip(vals) {
                for l in 0..W {
                    acc[l] += v * x[l][j];
                }
            }
            for l in 0..W {
                ys[l][i] = acc[l];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adds_within_the_pattern_and_counts_misses() {
        let mut a = Csr::from_rows(vec![vec![2, 0, 0], vec![1], vec![0, 1, 2]]);
        assert_eq!((a.n(), a.nnz()), (3, 6));
        a.add(0, 2, 1.5);
        a.add(0, 2, 0.5);
        a.add_span(2, 0, &[1.0, 2.0, 3.0]);
        assert_eq!(a.get(0, 2), 2.0);
        assert_eq!(a.row(2).1, &[1.0, 2.0, 3.0]);
        let mut y = [0.0; 3];
        a.mul(&[1.0, 1.0, 1.0], &mut y);
        assert_eq!(y, [2.0, 0.0, 6.0]);
        // Several products at once, in groups of four and a remainder.
        let xs: Vec<Vec<f64>> = (0..6)
            .map(|k| vec![1.0, k as f64, -0.5 * k as f64])
            .collect();
        let mut ys = vec![vec![0.0; 3]; 6];
        let xr: Vec<&[f64]> = xs.iter().map(|v| v.as_slice()).collect();
        let mut yr: Vec<&mut [f64]> = ys.iter_mut().map(|v| v.as_mut_slice()).collect();
        a.mul_many(&xr, &mut yr);
        for (x, y) in xs.iter().zip(&ys) {
            let mut one = [0.0; 3];
            a.mul(x, &mut one);
            assert_eq!(y.as_slice(), &one);
        }
        assert_eq!(ys[2], [-2.0, 0.0, 1.0 + 2.0 * 2.0 - 3.0]);
        if cfg!(not(debug_assertions)) {
            a.add(1, 0, 1.0);
            a.add_span(0, 0, &[1.0, 1.0]); // column 1 is not in row 0
            assert_eq!(a.take_outside(), 2);
            assert_eq!(a.take_outside(), 0);
        }
    }

    /// The trail replays the last assembly's positions; a different order of additions
    /// still lands every value where it belongs.
    #[test]
    fn a_changed_order_of_additions_is_still_right() {
        let rows = vec![vec![0, 1, 3], vec![1, 2], vec![0, 2, 3], vec![3]];
        let mut a = Csr::from_rows(rows);
        let adds = [
            (0, 3, 1.0),
            (2, 0, 2.0),
            (1, 1, 3.0),
            (3, 3, 4.0),
            (2, 2, 5.0),
        ];
        let expect = |a: &Csr| {
            for &(i, j, v) in &adds {
                assert_eq!(a.get(i, j), v, "({i}, {j})");
            }
            assert_eq!(a.values().iter().sum::<f64>(), 15.0);
        };
        for order in [
            [0, 1, 2, 3, 4],
            [0, 1, 2, 3, 4],
            [4, 2, 0, 3, 1],
            [1, 0, 2, 4, 3],
        ] {
            a.zero();
            for k in order {
                let (i, j, v) = adds[k];
                a.add(i, j, v);
            }
            expect(&a);
        }
        // Without zeroing, the trail stops growing but additions stay right.
        for _ in 0..100 {
            a.add(0, 1, 1.0);
        }
        assert_eq!(a.get(0, 1), 100.0);
        assert!(a.trail.len() <= 4 * a.nnz() + 64);
    }

    /// The trail replays a span only as it was checked: the same start in another row, or
    /// a longer span from it, is searched and checked again (and refused where it leaves
    /// the pattern), never written past the row.
    #[test]
    fn a_remembered_span_is_replayed_only_as_checked() {
        let mut a = Csr::from_rows(vec![vec![0, 1, 3], vec![0, 1], vec![], vec![]]);
        for _ in 0..2 {
            a.zero();
            a.add_span(0, 0, &[1.0, 2.0]);
            assert_eq!(a.row(0).1, &[1.0, 2.0, 0.0]);
        }
        a.zero();
        a.add_span(1, 0, &[4.0, 5.0]);
        assert_eq!((a.row(0).1, a.row(1).1), (&[0.0; 3][..], &[4.0, 5.0][..]));
        if cfg!(not(debug_assertions)) {
            a.zero();
            a.add_span(0, 0, &[1.0, 2.0, 3.0]); // column 2 is not in row 0
            assert_eq!(a.take_outside(), 1);
            assert_eq!(a.row(0).1, &[0.0; 3]);
            a.add_span(1, 0, &[1.0, 2.0, 3.0]); // past row 1's end
            assert_eq!(a.take_outside(), 1);
            assert_eq!(a.row(1).1, &[0.0; 2]);
        }
    }
}
