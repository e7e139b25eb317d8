//! Band LU with partial pivoting, in safe Rust, for matrices with n in the thousands and
//! bandwidths under ten. It is faster than SUNDIALS' scalar band LU (about 1 Gflop/s), and
//! needs no copies into SUNDIALS objects.
//!
//! Storage: row-major band rows. Row i holds columns i − kl ..= i + ku + kl contiguously
//! (stride w = 2 kl + ku + 1): the band itself and kl more columns on the right, where
//! row interchanges put their fill (with partial pivoting U's upper bandwidth grows to
//! ku + kl, L keeps kl). In this layout the work of elimination step k is contiguous:
//! the row swap exchanges two slices, and each row below the pivot is updated by
//! `row_i[..] −= l · row_k[..]` over one slice, which the compiler vectorises; column
//! storage (LAPACK's, SUNDIALS') would make that update strided across columns.
//!
//! Pivoting is LAPACK's (gbtrf): at step k the largest |entry| of column k among rows
//! k ..= k + kl is swapped into row k, and only the active columns k.. are swapped, so the
//! multipliers of earlier columns stay where they were made (L as a product of
//! elementary transforms, applied in order by the forward solve). The multipliers are
//! also kept column by column in a separate array so the forward solve reads them
//! contiguously. As in gbtrf, the last column any U row reaches so far is tracked, so
//! without interchanges an update spans ku columns, not ku + kl.

use super::LinalgError;
use crate::MatrixSink;

/// A pivot at most this much of its column's largest original entry counts as singular.
const PIVOT_TOLERANCE: f64 = 1e-14;

/// An n×n band matrix (kl below, ku above the diagonal). [`BandLu::factor`] makes its LU
/// factors, [`BandFactors`], the only thing that solves.
#[derive(Clone, Debug)]
pub struct BandLu {
    n: usize,
    kl: usize,
    ku: usize,
    /// Row stride: 2 kl + ku + 1 (the factors' layout, so that a row is copied whole).
    w: usize,
    /// Row i, column j at `i * w + j + kl − i`.
    data: Vec<f64>,
    /// Writes outside the band since the last [`BandLu::take_outside`].
    outside: usize,
}

/// The LU factors of a [`BandLu`] matrix as it was when [`BandLu::factor`] succeeded,
/// PA = LU with partial pivoting in the band; independent of the matrix, which may be
/// rewritten and factored again into the same storage ([`BandLu::factor_reusing`]).
#[derive(Clone, Debug)]
pub struct BandFactors {
    n: usize,
    kl: usize,
    ku: usize,
    w: usize,
    /// U by rows, in the matrix's layout (with the fill columns).
    data: Vec<f64>,
    /// Column k's multipliers (rows k + 1 ..= k + kl) at `k * kl ..`.
    mult: Vec<f64>,
    /// The row swapped with row k at step k.
    piv: Vec<usize>,
    /// The last column of U's row k.
    last: Vec<usize>,
    /// 1 / U_kk.
    inv_diag: Vec<f64>,
    /// Largest |entry| of each column, the pivots' scale (scratch of the factorisation).
    col_max: Vec<f64>,
}

impl BandLu {
    /// A zero n×n matrix with lower bandwidth `kl` and upper bandwidth `ku`.
    pub fn new(n: usize, kl: usize, ku: usize) -> Result<Self, LinalgError> {
        let too_big = || LinalgError::Size(format!("band LU of size {n}, widths {kl}/{ku}"));
        let w = kl
            .checked_mul(2)
            .and_then(|x| x.checked_add(ku))
            .and_then(|x| x.checked_add(1))
            .ok_or_else(too_big)?;
        let len = n.checked_mul(w).ok_or_else(too_big)?;
        // More than 2^31 doubles (16 GiB) is a mistake in the caller, not a matrix.
        if len > 1 << 31 || n.checked_mul(kl).is_none_or(|x| x > 1 << 31) {
            return Err(too_big());
        }
        Ok(BandLu {
            n,
            kl,
            ku,
            w,
            data: vec![0.0; len],
            outside: 0,
        })
    }

    /// The size n.
    pub fn size(&self) -> usize {
        self.n
    }

    /// (lower, upper) bandwidths.
    pub fn widths(&self) -> (usize, usize) {
        (self.kl, self.ku)
    }

    /// Set every entry to zero.
    pub fn zero(&mut self) {
        self.data.fill(0.0);
    }

    fn index(&self, i: usize, j: usize) -> Option<usize> {
        if i >= self.n || j >= self.n || i + self.ku < j || i > j + self.kl {
            return None;
        }
        Some(i * self.w + j + self.kl - i)
    }

    /// The entry (i, j) as set (before factoring); zero outside the band.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.index(i, j).map_or(0.0, |k| self.data[k])
    }

    /// A[i][j] += v. Outside the band nothing is written and the write is counted (see
    /// [`BandLu::take_outside`]); debug builds panic.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        match self.index(i, j) {
            Some(k) => self.data[k] += v,
            None => self.count_outside(i, j),
        }
    }

    /// Row i's band: columns i − kl ..= i + ku, in that order (kl + ku + 1 entries), to be
    /// written in place. Entries for columns outside 0..n are ignored by the factorisation.
    ///
    /// # Errors
    /// [`LinalgError::Length`] if there is no row i (i ≥ n).
    pub fn row_mut(&mut self, i: usize) -> Result<&mut [f64], LinalgError> {
        if i >= self.n {
            return Err(LinalgError::Length(format!(
                "row {i} of a band matrix of size {}",
                self.n
            )));
        }
        let start = i * self.w;
        Ok(&mut self.data[start..start + self.kl + self.ku + 1])
    }

    /// Factorise the matrix as set: PA = LU with partial pivoting in the band. The matrix
    /// is left as it is.
    ///
    /// # Errors
    /// [`LinalgError::Singular`] for a pivot of zero or at most 1e-14 of its column's
    /// largest entry, naming the column.
    pub fn factor(&self) -> Result<BandFactors, LinalgError> {
        self.factor_reusing(None)
    }

    /// [`BandLu::factor`] into the storage of `old` factors (of a matrix of the same size
    /// and widths; other factors or `None` are replaced by new storage). On an error the
    /// old factors are gone.
    ///
    /// # Errors
    /// As [`BandLu::factor`].
    pub fn factor_reusing(&self, old: Option<BandFactors>) -> Result<BandFactors, LinalgError> {
        let (n, kl, ku, w) = (self.n, self.kl, self.ku, self.w);
        let mut f = match old {
            Some(f) if (f.n, f.kl, f.ku) == (n, kl, ku) => f,
            _ => BandFactors {
                n,
                kl,
                ku,
                w,
                data: vec![0.0; self.data.len()],
                mult: vec![0.0; n * kl],
                piv: vec![0; n],
                last: vec![0; n],
                inv_diag: vec![0.0; n],
                col_max: vec![0.0; n],
            },
        };
        f.eliminate(self)?;
        Ok(f)
    }

    fn count_outside(&mut self, i: usize, j: usize) {
        debug_assert!(
            false,
            "({i},{j}) is outside the band (n {}, lower {}, upper {})",
            self.n, self.kl, self.ku
        );
        self.outside += 1;
    }

    /// The number of writes outside the band since the last call, and reset it.
    pub fn take_outside(&mut self) -> usize {
        std::mem::take(&mut self.outside)
    }
}

impl BandFactors {
    /// The size n.
    pub fn size(&self) -> usize {
        self.n
    }

    /// Gaussian elimination of `a` into these factors (their storage has a's shape).
    fn eliminate(&mut self, a: &BandLu) -> Result<(), LinalgError> {
        let (n, kl, ku, w) = (self.n, self.kl, self.ku, self.w);
        // Copy the matrix, clearing what is not the matrix (columns outside 0..n, the fill
        // columns), and take each column's scale.
        self.col_max.fill(0.0);
        for (i, (row, src)) in self
            .data
            .chunks_exact_mut(w)
            .zip(a.data.chunks_exact(w))
            .enumerate()
        {
            let first = kl.saturating_sub(i);
            let end = (kl + ku + 1).min(n + kl - i);
            row[..first].fill(0.0);
            row[first..end].copy_from_slice(&src[first..end]);
            row[end..].fill(0.0);
            let c0 = i + first - kl;
            for (m, v) in self.col_max[c0..c0 + end - first]
                .iter_mut()
                .zip(&row[first..end])
            {
                *m = m.max(v.abs());
            }
        }
        // The last column reached by any U row so far.
        let mut ju = 0;
        for k in 0..n {
            let below = kl.min(n - 1 - k);
            let (mut p, mut best) = (k, self.data[k * w + kl].abs());
            for d in 1..=below {
                let v = self.data[(k + d) * w + kl - d].abs();
                if v > best {
                    (p, best) = (k + d, v);
                }
            }
            let scale = self.col_max[k];
            if !(best > PIVOT_TOLERANCE * scale) {
                return Err(LinalgError::Singular(if best == 0.0 {
                    format!("band LU: column {k} has no nonzero pivot")
                } else {
                    format!(
                        "band LU: column {k}'s pivot {best:e} is below {PIVOT_TOLERANCE:e} of the column's scale {scale:e}"
                    )
                }));
            }
            self.piv[k] = p;
            ju = ju.max((p + ku).min(n - 1));
            self.last[k] = ju;
            // Columns k..=ju of the pivot row and the rows below.
            let len = ju - k + 1;
            if p != k {
                let d = p - k;
                let (top, bottom) = self.data.split_at_mut(p * w);
                top[k * w + kl..k * w + kl + len]
                    .swap_with_slice(&mut bottom[kl - d..kl - d + len]);
            }
            let (top, bottom) = self.data.split_at_mut((k + 1) * w);
            let pivot_row = &top[k * w + kl..k * w + kl + len];
            let inv = 1.0 / pivot_row[0];
            self.inv_diag[k] = inv;
            let mult = &mut self.mult[k * kl..(k + 1) * kl];
            mult.fill(0.0);
            for d in 1..=below {
                let at = (d - 1) * w + kl - d;
                let row = &mut bottom[at..at + len];
                let l = row[0] * inv;
                mult[d - 1] = l;
                if l != 0.0 {
                    for (x, u) in row[1..].iter_mut().zip(&pivot_row[1..]) {
                        *x -= l * u;
                    }
                }
            }
        }
        Ok(())
    }

    /// b ← A⁻¹ b. The factors are not changed: any number of right sides.
    ///
    /// # Errors
    /// [`LinalgError::Length`] if b's length is not n (b is then unchanged).
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinalgError> {
        let (n, kl, w) = (self.n, self.kl, self.w);
        if b.len() != n {
            return Err(LinalgError::Length(format!(
                "right side of length {} for a band LU of size {n}",
                b.len()
            )));
        }
        // L: the swaps and multipliers in the order they were made.
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            let below = kl.min(n - 1 - k);
            if bk != 0.0 {
                for (x, l) in b[k + 1..k + 1 + below].iter_mut().zip(&self.mult[k * kl..]) {
                    *x -= l * bk;
                }
            }
        }
        // U, row by row from the bottom. The term in b[k + 1], the only one waiting on the
        // previous row, is added last so the rest of the dot product overlaps that wait.
        for k in (0..n).rev() {
            let len = self.last[k] - k;
            let row = &self.data[k * w + kl + 1..k * w + kl + 1 + len];
            let s = match len {
                0 => 0.0,
                _ => dot(&row[1..], &b[k + 2..k + 1 + len]) + row[0] * b[k + 1],
            };
            b[k] = (b[k] - s) * self.inv_diag[k];
        }
        Ok(())
    }
}

/// Σ a_i b_i in four independent sums (vectorised; one sum would be a serial chain).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for t in 0..4 {
            acc[t] += x[t] * y[t];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// The assembler's view: `set` overwrites a band entry; outside the band it counts (see
/// [`BandLu::take_outside`]) and debug builds panic.
impl MatrixSink for BandLu {
    fn nrows(&self) -> usize {
        self.n
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        match self.index(i, j) {
            Some(k) => self.data[k] = v,
            None => self.count_outside(i, j),
        }
    }
}
