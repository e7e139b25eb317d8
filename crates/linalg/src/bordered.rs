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

use super::{
    AbdLu6, AbdLu6Factors, BandFactors, BandLu, Csr, DirectSolver, LinalgError, MatrixSink,
};

/// The square matrix A inside a border: factored into [`Bordering::Factors`], which then
/// solve any number of times ([`BandLu`], or the almost-block-diagonal [`AbdLu6`]).
pub trait Bordering {
    /// A's LU factors.
    type Factors: Solve;
    /// n, A's size.
    fn size(&self) -> usize;
    /// Factorise A as it was written, into the storage of `old` if it fits.
    ///
    /// # Errors
    /// [`LinalgError::Singular`] for a singular A.
    fn factor_reusing(&self, old: Option<Self::Factors>) -> Result<Self::Factors, LinalgError>;
}

/// LU factors that solve: x ← A⁻¹ x.
pub trait Solve {
    /// x ← A⁻¹ x.
    ///
    /// # Errors
    /// [`LinalgError::Length`] if x's length is not A's size.
    fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError>;
}

impl Bordering for BandLu {
    type Factors = BandFactors;
    fn size(&self) -> usize {
        BandLu::size(self)
    }
    fn factor_reusing(&self, old: Option<BandFactors>) -> Result<BandFactors, LinalgError> {
        BandLu::factor_reusing(self, old)
    }
}

impl Solve for BandFactors {
    fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError> {
        BandFactors::solve_in_place(self, x)
    }
}

impl Bordering for AbdLu6 {
    type Factors = AbdLu6Factors;
    fn size(&self) -> usize {
        AbdLu6::size(self)
    }
    fn factor_reusing(&self, old: Option<AbdLu6Factors>) -> Result<AbdLu6Factors, LinalgError> {
        AbdLu6::factor_reusing(self, old)
    }
}

impl Solve for AbdLu6Factors {
    fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError> {
        AbdLu6Factors::solve_in_place(self, x)
    }
}

/// [A c; rᵀ s] with A an n×n matrix factored by `L`; without a border, just A.
pub struct Bordered<L> {
    lu: L,
    border: bool,
    col: Vec<f64>,
    row: Vec<f64>,
    corner: f64,
}

/// The factors of a [`Bordered`] matrix as it was when [`Bordered::factor`] succeeded:
/// A's, the border row r, v = A⁻¹ c and σ = s − rᵀ v.
pub struct BorderedFactors<F> {
    lu: F,
    /// A's size.
    n: usize,
    border: bool,
    row: Vec<f64>,
    v: Vec<f64>,
    sigma: f64,
}

/// A band matrix with a border.
pub type BorderedBand = Bordered<BandLu>;
/// An almost-block-diagonal matrix of 6×6 node blocks with a border.
pub type BorderedAbd = Bordered<AbdLu6>;

impl BorderedBand {
    /// A zero matrix of size n (+ 1 with a border) whose band has these widths.
    ///
    /// # Errors
    /// [`LinalgError::Size`] for a band too large to store.
    pub fn new(n: usize, lower: usize, upper: usize, border: bool) -> Result<Self, LinalgError> {
        Ok(Bordered::around(BandLu::new(n, lower, upper)?, border))
    }

    /// (lower, upper) bandwidths of A.
    pub fn widths(&self) -> (usize, usize) {
        self.lu.widths()
    }

    /// Fill the matrix: `f(a, c, r, s)` sets the band entries of A and the border, all of
    /// which start at zero.
    ///
    /// # Errors
    /// [`LinalgError::OutsidePattern`] if `f` wrote entries outside the band.
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

    /// A.
    pub fn inner(&self) -> &L {
        &self.lu
    }

    /// Fill the matrix row by row in place: `f(a, c, r, s)` must write every row of A in
    /// full (for a band, through [`BandLu::row_mut`]: they hold the last rows written, not
    /// zeros); the border starts at zero. Cheaper than [`BorderedBand::fill`] for a caller
    /// that builds whole rows.
    ///
    /// # Errors
    /// What `f` returns.
    pub fn fill_rows(
        &mut self,
        f: impl FnOnce(&mut L, &mut [f64], &mut [f64], &mut f64) -> Result<(), LinalgError>,
    ) -> Result<(), LinalgError> {
        self.clear_border();
        f(&mut self.lu, &mut self.col, &mut self.row, &mut self.corner)
    }

    fn clear_border(&mut self) {
        self.col.fill(0.0);
        self.row.fill(0.0);
        self.corner = 0.0;
    }

    /// Factorise what was filled: A = LU, v = A⁻¹ c and σ = s − rᵀ v.
    ///
    /// # Errors
    /// [`LinalgError::Singular`] for a singular A, or a σ at most 1e-14 of
    /// |s| + Σ |r_i v_i| (the size of the terms it is the difference of).
    pub fn factor(&self) -> Result<BorderedFactors<L::Factors>, LinalgError> {
        self.factor_reusing(None)
    }

    /// [`Bordered::factor`] into the storage of `old` factors where it fits; on an error
    /// the old factors are gone.
    ///
    /// # Errors
    /// As [`Bordered::factor`].
    pub fn factor_reusing(
        &self,
        old: Option<BorderedFactors<L::Factors>>,
    ) -> Result<BorderedFactors<L::Factors>, LinalgError> {
        let (old_lu, mut row, mut v) = match old {
            Some(f) => (Some(f.lu), f.row, f.v),
            None => (None, Vec::new(), Vec::new()),
        };
        let lu = self.lu.factor_reusing(old_lu)?;
        if !self.border {
            return Ok(BorderedFactors {
                lu,
                n: self.band_size(),
                border: false,
                row,
                v,
                sigma: 1.0,
            });
        }
        v.clear();
        v.extend_from_slice(&self.col);
        lu.solve_in_place(&mut v)?;
        row.clear();
        row.extend_from_slice(&self.row);
        let rv: f64 = row.iter().zip(&v).map(|(a, b)| a * b).sum();
        let sigma = self.corner - rv;
        let scale = self.corner.abs() + row.iter().zip(&v).map(|(a, b)| (a * b).abs()).sum::<f64>();
        if !(sigma.abs() > 1e-14 * scale) {
            return Err(LinalgError::Singular(format!(
                "the border's Schur complement is {sigma:e} (scale {scale:e})"
            )));
        }
        Ok(BorderedFactors {
            lu,
            n: self.band_size(),
            border: true,
            row,
            v,
            sigma,
        })
    }
}

impl<F: Solve> BorderedFactors<F> {
    /// The whole size: A and the border.
    pub fn len(&self) -> usize {
        self.n + usize::from(self.border)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A's factors.
    pub fn inner(&self) -> &F {
        &self.lu
    }

    /// x = M⁻¹ b, both of length [`BorderedFactors::len`].
    ///
    /// # Errors
    /// [`LinalgError::Length`] if b or x is not of that length.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        if b.len() != x.len() {
            return Err(LinalgError::Length(format!(
                "right side {} and solution {} of a bordered solve",
                b.len(),
                x.len()
            )));
        }
        x.copy_from_slice(b);
        self.solve_in_place(x)
    }

    /// x ← M⁻¹ x, of length [`BorderedFactors::len`].
    ///
    /// # Errors
    /// [`LinalgError::Length`] if x is not of that length.
    pub fn solve_in_place(&self, x: &mut [f64]) -> Result<(), LinalgError> {
        if !self.border {
            return self.lu.solve_in_place(x);
        }
        let n = self.n;
        if x.len() != n + 1 {
            return Err(LinalgError::Length(format!(
                "right side of length {} for a bordered matrix of size {}",
                x.len(),
                n + 1
            )));
        }
        let (xa, xs) = x.split_at_mut(n);
        self.lu.solve_in_place(xa)?;
        let rx: f64 = self.row.iter().zip(&*xa).map(|(a, b)| a * b).sum();
        let s = (xs[0] - rx) / self.sigma;
        for (xi, vi) in xa.iter_mut().zip(&self.v) {
            *xi -= vi * s;
        }
        xs[0] = s;
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
    /// The whole matrix's size.
    size: usize,
    perm: Vec<usize>,
    border: Option<usize>,
    bb: BorderedBand,
    /// The factors of the last successful [`DirectSolver::factor`].
    factors: Option<BorderedFactors<BandFactors>>,
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
        let size = pattern.n();
        let band = size.saturating_sub(usize::from(border.is_some()));
        if perm.len() != size
            || border.is_some_and(|b| b >= size)
            || !(0..size).all(|i| Some(i) == border || perm[i] < band)
        {
            return Err(LinalgError::Structure(format!(
                "an order of {} unknowns (border {border:?}) for a matrix of size {size}",
                perm.len()
            )));
        }
        let n = band;
        let (lower, upper) = widths_under(pattern, &perm, border);
        let bb = BorderedBand::new(n, lower, upper, border.is_some())?;
        Ok(InterleavedBand {
            size: pattern.n(),
            perm,
            border,
            bb,
            factors: None,
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
        let old = self.factors.take();
        if a.n() != self.size {
            return Err(LinalgError::Length(format!(
                "a matrix of size {} for a solver made for size {}",
                a.n(),
                self.size
            )));
        }
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
        self.factors = Some(self.bb.factor_reusing(old)?);
        Ok(())
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        let factors = self.factors.as_ref().ok_or(LinalgError::NotFactored)?;
        let n = self.bb.band_size();
        if b.len() != self.size || x.len() != self.size {
            return Err(LinalgError::Length(format!(
                "right side {} and solution {} for a matrix of size {}",
                b.len(),
                x.len(),
                self.size
            )));
        }
        for (i, &bi) in b.iter().enumerate() {
            let k = if Some(i) == self.border {
                n
            } else {
                self.perm[i]
            };
            self.b[k] = bi;
        }
        let len = self.bb.len();
        factors.solve(&self.b[..len], &mut self.x[..len])?;
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
        let factors = bb.factor().unwrap();
        let full = nalgebra::DMatrix::from_fn(n + 1, n + 1, |i, j| match (i < n, j < n) {
            (true, true) => a(i, j),
            (true, false) => c(i),
            (false, true) => r(j),
            (false, false) => 3.0,
        });
        let b: Vec<f64> = (0..=n).map(|i| (i as f64 * 0.7).cos()).collect();
        let mut x = vec![0.0; n + 1];
        factors.solve(&b, &mut x).unwrap();
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
