//! A band (or almost-block-diagonal) matrix bordered by one dense row and column,
//! [A c; rᵀ s], solved by block elimination: A = LU by [`BandLu`] (or [`AbdLu6`]),
//! v = A⁻¹c once per factorisation, the scalar Schur
//! complement σ = s − rᵀv; then each solve is one band back-substitution:
//!   x_A = A⁻¹ b_A,  x_s = (b_s − rᵀ x_A) / σ,  x_A ← x_A − v x_s.
//! Why a border: one unknown read by many equations far apart is a dense column no band
//! can hold, and would widen the band to the whole matrix.
//!
//! Also here: [`InterleavedBand`], band LU of a whole CSR matrix in a given order with one
//! unknown as the border.

use super::{AbdLu6, BandLu, Csr, DirectSolver, LinalgError, MatrixSink};

/// The square matrix A inside a border: factored in place, then solved with any number of
/// times ([`BandLu`], or the almost-block-diagonal [`AbdLu6`]).
pub trait Bordering {
    /// n, A's size.
    fn size(&self) -> usize;
    /// Factorise A as it was written.
    fn factor(&mut self) -> Result<(), LinalgError>;
    /// x ← A⁻¹ x after a successful [`Bordering::factor`].
    fn solve_in_place(&self, x: &mut [f64]);
}

impl Bordering for BandLu {
    fn size(&self) -> usize {
        BandLu::size(self)
    }
    fn factor(&mut self) -> Result<(), LinalgError> {
        BandLu::factor(self)
    }
    fn solve_in_place(&self, x: &mut [f64]) {
        BandLu::solve_in_place(self, x)
    }
}

impl Bordering for AbdLu6 {
    fn size(&self) -> usize {
        AbdLu6::size(self)
    }
    fn factor(&mut self) -> Result<(), LinalgError> {
        AbdLu6::factor(self)
    }
    fn solve_in_place(&self, x: &mut [f64]) {
        AbdLu6::solve_in_place(self, x)
    }
}

/// [A c; rᵀ s] with A an n×n matrix factored by `L`; without a border, just A.
pub struct Bordered<L> {
    lu: L,
    border: bool,
    col: Vec<f64>,
    row: Vec<f64>,
    corner: f64,
    /// A⁻¹ c and σ = s − rᵀ A⁻¹ c, from the last factorisation.
    v: Vec<f64>,
    sigma: f64,
    /// The last factorisation succeeded, border included, and nothing was filled since.
    factored: bool,
}

/// A band matrix with a border.
pub type BorderedBand = Bordered<BandLu>;
/// An almost-block-diagonal matrix of 6×6 node blocks with a border.
pub type BorderedAbd = Bordered<AbdLu6>;

impl BorderedBand {
    /// A zero matrix of size n (+ 1 with a border) whose band has these widths.
    pub fn new(n: usize, lower: usize, upper: usize, border: bool) -> Result<Self, LinalgError> {
        Ok(Bordered::around(BandLu::new(n, lower, upper)?, border))
    }

    /// (lower, upper) bandwidths of A.
    pub fn widths(&self) -> (usize, usize) {
        self.lu.widths()
    }

    /// Fill the matrix: `f(a, c, r, s)` sets the band entries of A and the border, all of
    /// which start at zero.
    pub fn fill(
        &mut self,
        f: impl FnOnce(&mut dyn MatrixSink, &mut [f64], &mut [f64], &mut f64),
    ) -> Result<(), LinalgError> {
        self.lu.zero();
        self.lu.take_outside();
        self.clear_border();
        f(&mut self.lu, &mut self.col, &mut self.row, &mut self.corner);
        match self.lu.take_outside() {
            0 => Ok(()),
            k => Err(LinalgError::OutsidePattern(k)),
        }
    }
}

impl<L: Bordering> Bordered<L> {
    /// `lu` (its entries as they are) with a zero border, if `border`.
    pub fn around(lu: L, border: bool) -> Self {
        let border_len = if border { lu.size() } else { 0 };
        Bordered {
            lu,
            border,
            col: vec![0.0; border_len],
            row: vec![0.0; border_len],
            corner: 0.0,
            v: vec![0.0; border_len],
            sigma: 1.0,
            factored: false,
        }
    }

    /// The size of A.
    pub fn band_size(&self) -> usize {
        self.lu.size()
    }

    /// The whole size: A and the border.
    pub fn len(&self) -> usize {
        self.band_size() + usize::from(self.border)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A (and after a factorisation, its factors).
    pub fn inner(&self) -> &L {
        &self.lu
    }

    /// Fill the matrix row by row in place: `f(a, c, r, s)` must write every row of A in
    /// full (for a band, through [`BandLu::row_mut`]: they hold the last factors, not
    /// zeros); the border starts at zero. Cheaper than [`BorderedBand::fill`] for a caller
    /// that builds whole rows.
    pub fn fill_rows(&mut self, f: impl FnOnce(&mut L, &mut [f64], &mut [f64], &mut f64)) {
        self.clear_border();
        f(&mut self.lu, &mut self.col, &mut self.row, &mut self.corner);
    }

    fn clear_border(&mut self) {
        self.factored = false;
        self.col.fill(0.0);
        self.row.fill(0.0);
        self.corner = 0.0;
    }

    /// Factorise what was filled: A = LU, v = A⁻¹ c and σ = s − rᵀ v. A σ at most 1e-14
    /// of |s| + Σ |r_i v_i| (the size of the terms it is the difference of) is singular.
    pub fn factor(&mut self) -> Result<(), LinalgError> {
        self.factored = false;
        self.lu.factor()?;
        if !self.border {
            self.factored = true;
            return Ok(());
        }
        self.v.copy_from_slice(&self.col);
        self.lu.solve_in_place(&mut self.v);
        let rv: f64 = self.row.iter().zip(&self.v).map(|(a, b)| a * b).sum();
        self.sigma = self.corner - rv;
        let scale = self.corner.abs()
            + self
                .row
                .iter()
                .zip(&self.v)
                .map(|(a, b)| (a * b).abs())
                .sum::<f64>();
        if !(self.sigma.abs() > 1e-14 * scale) {
            return Err(LinalgError::Singular(format!(
                "the border's Schur complement is {:e} (scale {scale:e})",
                self.sigma
            )));
        }
        self.factored = true;
        Ok(())
    }

    /// x = M⁻¹ b, both of length [`Bordered::len`].
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        x.copy_from_slice(b);
        self.solve_in_place(x)
    }

    /// x ← M⁻¹ x, of length [`Bordered::len`]; an error without a successful
    /// [`Bordered::factor`] since the last fill.
    pub fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError> {
        if !self.factored {
            return Err(LinalgError::NotFactored);
        }
        let n = self.band_size();
        let (xa, xs) = x.split_at_mut(n);
        self.lu.solve_in_place(xa);
        if self.border {
            let rx: f64 = self.row.iter().zip(&*xa).map(|(a, b)| a * b).sum();
            let s = (xs[0] - rx) / self.sigma;
            for (xi, vi) in xa.iter_mut().zip(&self.v) {
                *xi -= vi * s;
            }
            xs[0] = s;
        }
        Ok(())
    }
}

/// The (lower, upper) bandwidths of `a` in the order `perm` (perm[i] = new index of i),
/// rows and columns `skip` left out.
fn widths_under(a: &Csr, perm: &[usize], skip: Option<usize>) -> (usize, usize) {
    let (mut lower, mut upper) = (0, 0);
    for i in (0..a.n()).filter(|&i| Some(i) != skip) {
        for &j in a.row(i).0.iter().filter(|&&j| Some(j) != skip) {
            let (pi, pj) = (perm[i], perm[j]);
            lower = lower.max(pi.saturating_sub(pj));
            upper = upper.max(pj.saturating_sub(pi));
        }
    }
    (lower, upper)
}

/// Band LU of a whole CSR matrix after the symmetric permutation `perm` (chosen to keep
/// the band narrow), with the unknown `border` (if any) kept out of the band.
pub struct InterleavedBand {
    perm: Vec<usize>,
    border: Option<usize>,
    bb: BorderedBand,
    b: Vec<f64>,
    x: Vec<f64>,
}

impl InterleavedBand {
    /// `perm[i]`: where unknown i goes in the band (a permutation of 0..n−1 without
    /// `border`, whose own entry is ignored).
    pub fn new(
        pattern: &Csr,
        perm: Vec<usize>,
        border: Option<usize>,
    ) -> Result<Self, LinalgError> {
        let n = pattern.n() - usize::from(border.is_some());
        let (lower, upper) = widths_under(pattern, &perm, border);
        let bb = BorderedBand::new(n, lower, upper, border.is_some())?;
        Ok(InterleavedBand {
            perm,
            border,
            bb,
            b: vec![0.0; n + 1],
            x: vec![0.0; n + 1],
        })
    }

    pub fn widths(&self) -> (usize, usize) {
        self.bb.widths()
    }
}

impl DirectSolver for InterleavedBand {
    fn factor(&mut self, a: &Csr) -> Result<(), LinalgError> {
        let (perm, border) = (&self.perm, self.border);
        self.bb.fill(|band, col, row, corner| {
            for i in 0..a.n() {
                let (cols, vals) = a.row(i);
                for (&j, &v) in cols.iter().zip(vals) {
                    match (Some(i) == border, Some(j) == border) {
                        (false, false) => band.set(perm[i], perm[j], v),
                        (false, true) => col[perm[i]] = v,
                        (true, false) => row[perm[j]] = v,
                        (true, true) => *corner = v,
                    }
                }
            }
        })?;
        self.bb.factor()
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        let n = self.bb.band_size();
        for (i, &bi) in b.iter().enumerate() {
            let k = if Some(i) == self.border {
                n
            } else {
                self.perm[i]
            };
            self.b[k] = bi;
        }
        let len = self.bb.len();
        self.bb.solve(&self.b[..len], &mut self.x[..len])?;
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = self.x[if Some(i) == self.border {
                n
            } else {
                self.perm[i]
            }];
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small bordered system against a dense solve.
    #[test]
    fn bordered_band_solves_against_dense() {
        let n = 7;
        let mut bb = BorderedBand::new(n, 1, 2, true).unwrap();
        let a = |i: usize, j: usize| {
            if i == j {
                4.0 + i as f64
            } else if (j + 1 == i) || (j == i + 1) || (j == i + 2) {
                0.3 * (i + 2 * j) as f64 / 7.0
            } else {
                0.0
            }
        };
        let c = |i: usize| 0.1 * (i as f64 + 1.0);
        let r = |j: usize| 0.2 * (j as f64).sin();
        bb.fill(|m, col, row, corner| {
            for i in 0..n {
                for j in 0..n {
                    if a(i, j) != 0.0 {
                        m.set(i, j, a(i, j));
                    }
                }
                col[i] = c(i);
                row[i] = r(i);
            }
            *corner = 3.0;
        })
        .unwrap();
        bb.factor().unwrap();
        let full = nalgebra::DMatrix::from_fn(n + 1, n + 1, |i, j| match (i < n, j < n) {
            (true, true) => a(i, j),
            (true, false) => c(i),
            (false, true) => r(j),
            (false, false) => 3.0,
        });
        let b: Vec<f64> = (0..=n).map(|i| (i as f64 * 0.7).cos()).collect();
        let mut x = vec![0.0; n + 1];
        bb.solve(&b, &mut x).unwrap();
        let expect = full.lu().solve(&nalgebra::DVector::from_vec(b)).unwrap();
        for i in 0..=n {
            assert!(
                (x[i] - expect[i]).abs() < 1e-13,
                "{i}: {} vs {}",
                x[i],
                expect[i]
            );
        }
    }
}
