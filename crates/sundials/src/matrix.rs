//! SUNDIALS matrices (dense, band, CSR sparse) owned by Rust, and the write-only views a
//! Jacobian assembler fills entry by entry through [`MatrixSink`].
//!
//! Why views: the assembler should not know the storage layout (column-major dense, band
//! columns with extra rows kept for LU fill-in, or CSR with a fixed pattern). It calls
//! `set(i, j, v)`; the view writes into SUNDIALS's own storage with no copy.
//!
//! A write outside the structure (outside the band, or not in the CSR pattern) is a bug in
//! the assembler: it panics in debug builds (`debug_assert`) and in release builds is not
//! written but counted, and the layer turns the count into an error after the callback.

use std::cell::Cell;
use std::rc::Rc;

use sundials_sys::{
    sunindextype, SUNBandMatrix, SUNBandMatrix_Data, SUNBandMatrix_LDim,
    SUNBandMatrix_StoredUpperBandwidth, SUNDenseMatrix, SUNDenseMatrix_Data, SUNMatDestroy,
    SUNMatrix, SUNSparseMatrix, SUNSparseMatrix_Data, SUNSparseMatrix_IndexPointers,
    SUNSparseMatrix_IndexValues, CSR_MAT,
};

pub use super::block::BlockMatrix;
use super::callback::{CallbackError, CallbackResult};
use super::context::Context;
use super::error::SundialsError;
use eyeshell_linalg::AbdLu;
pub use eyeshell_linalg::MatrixSink;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MatrixKind {
    Dense,
    Band,
    Sparse,
    /// Almost block diagonal, 5×5 node blocks ([`BlockMatrix`]).
    Block,
}

// ---------------------------------------------------------------------------------------
// Views

/// A dense matrix, column-major (SUNDIALS's layout).
pub struct DenseMut<'a> {
    data: &'a mut [f64],
    nrows: usize,
    ncols: usize,
}

impl DenseMut<'_> {
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    pub fn get(&self, i: usize, j: usize) -> f64 {
        assert!(
            i < self.nrows && j < self.ncols,
            "({i},{j}) outside a {}x{} matrix",
            self.nrows,
            self.ncols
        );
        self.data[j * self.nrows + i]
    }
}

impl MatrixSink for DenseMut<'_> {
    fn nrows(&self) -> usize {
        self.nrows
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        assert!(
            i < self.nrows && j < self.ncols,
            "({i},{j}) outside a {}x{} matrix",
            self.nrows,
            self.ncols
        );
        self.data[j * self.nrows + i] = v;
    }
}

/// A SUNDIALS band matrix: entry (i, j) with -upper ≤ i - j ≤ lower lives in column j's
/// storage at offset `smu + i - j` (smu = stored upper bandwidth, which includes LU fill).
pub struct BandMut<'a> {
    data: &'a mut [f64],
    n: usize,
    upper: usize,
    lower: usize,
    smu: usize,
    ldim: usize,
    outside: &'a Cell<usize>,
}

impl BandMut<'_> {
    pub fn upper(&self) -> usize {
        self.upper
    }

    pub fn lower(&self) -> usize {
        self.lower
    }

    /// Whether (i, j) lies in the band.
    pub fn contains(&self, i: usize, j: usize) -> bool {
        self.index(i, j).is_some()
    }

    fn index(&self, i: usize, j: usize) -> Option<usize> {
        if i >= self.n || j >= self.n || i + self.upper < j || i > j + self.lower {
            return None;
        }
        Some(j * self.ldim + self.smu + i - j)
    }

    /// The entry (i, j); zero outside the band.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.index(i, j).map_or(0.0, |k| self.data[k])
    }
}

impl MatrixSink for BandMut<'_> {
    fn nrows(&self) -> usize {
        self.n
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        match self.index(i, j) {
            Some(k) => self.data[k] = v,
            None => {
                debug_assert!(
                    false,
                    "({i},{j}) is outside the band (n {}, upper {}, lower {})",
                    self.n, self.upper, self.lower
                );
                self.outside.set(self.outside.get() + 1);
            }
        }
    }
}

/// A CSR sparse matrix with a fixed pattern: `set(i, j)` finds j among row i's column
/// indices (sorted, binary search) and writes the value there.
pub struct CsrMut<'a> {
    values: &'a mut [f64],
    row_ptr: &'a [usize],
    col_idx: &'a [usize],
    outside: &'a Cell<usize>,
}

impl CsrMut<'_> {
    pub fn row_ptr(&self) -> &[usize] {
        self.row_ptr
    }

    pub fn col_idx(&self) -> &[usize] {
        self.col_idx
    }

    fn index(&self, i: usize, j: usize) -> Option<usize> {
        if i + 1 >= self.row_ptr.len() {
            return None;
        }
        let (lo, hi) = (self.row_ptr[i], self.row_ptr[i + 1]);
        self.col_idx[lo..hi].binary_search(&j).ok().map(|k| lo + k)
    }

    /// The entry (i, j); zero outside the pattern.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.index(i, j).map_or(0.0, |k| self.values[k])
    }
}

impl MatrixSink for CsrMut<'_> {
    fn nrows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        match self.index(i, j) {
            Some(k) => self.values[k] = v,
            None => {
                debug_assert!(false, "({i},{j}) is outside the sparsity pattern");
                self.outside.set(self.outside.get() + 1);
            }
        }
    }
}

/// The matrix handed to [`NonlinearSystem::jacobian`](super::NonlinearSystem::jacobian).
pub enum JacobianMatrix<'a> {
    Dense(DenseMut<'a>),
    Band(BandMut<'a>),
    Sparse(CsrMut<'a>),
    /// The blocks themselves: an assembler writes every entry of every interval block (see
    /// [`Matrix::fill_jacobian`]).
    Block(&'a mut AbdLu),
}

impl JacobianMatrix<'_> {
    pub fn kind(&self) -> MatrixKind {
        match self {
            JacobianMatrix::Dense(_) => MatrixKind::Dense,
            JacobianMatrix::Band(_) => MatrixKind::Band,
            JacobianMatrix::Sparse(_) => MatrixKind::Sparse,
            JacobianMatrix::Block(_) => MatrixKind::Block,
        }
    }

    /// The entry (i, j) (zero outside the band or pattern).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        match self {
            JacobianMatrix::Dense(m) => m.get(i, j),
            JacobianMatrix::Band(m) => m.get(i, j),
            JacobianMatrix::Sparse(m) => m.get(i, j),
            JacobianMatrix::Block(m) => m.get(i, j),
        }
    }
}

impl MatrixSink for JacobianMatrix<'_> {
    fn nrows(&self) -> usize {
        match self {
            JacobianMatrix::Dense(m) => m.nrows(),
            JacobianMatrix::Band(m) => m.nrows(),
            JacobianMatrix::Sparse(m) => m.nrows(),
            JacobianMatrix::Block(m) => m.nrows(),
        }
    }

    fn set(&mut self, i: usize, j: usize, v: f64) {
        match self {
            JacobianMatrix::Dense(m) => m.set(i, j, v),
            JacobianMatrix::Band(m) => m.set(i, j, v),
            JacobianMatrix::Sparse(m) => m.set(i, j, v),
            JacobianMatrix::Block(m) => m.set(i, j, v),
        }
    }

    fn set_block(&mut self, row0: usize, col0: usize, ncols: usize, values: &[f64]) {
        match self {
            JacobianMatrix::Dense(m) => m.set_block(row0, col0, ncols, values),
            JacobianMatrix::Band(m) => m.set_block(row0, col0, ncols, values),
            JacobianMatrix::Sparse(m) => m.set_block(row0, col0, ncols, values),
            JacobianMatrix::Block(m) => m.set_block(row0, col0, ncols, values),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Owned matrices

fn index_type(n: usize, what: &str) -> Result<sunindextype, SundialsError> {
    sunindextype::try_from(n).map_err(|_| SundialsError::Invalid(format!("{what} {n} too large")))
}

/// A dense SUNMatrix, destroyed on drop.
pub struct DenseMatrix {
    raw: SUNMatrix,
    nrows: usize,
    ncols: usize,
    _ctx: Rc<Context>,
}

impl DenseMatrix {
    pub fn new(ctx: &Rc<Context>, nrows: usize, ncols: usize) -> Result<Self, SundialsError> {
        let (m, n) = (index_type(nrows, "rows")?, index_type(ncols, "columns")?);
        // SAFETY: ctx is live; the result is checked for NULL.
        let raw = unsafe { SUNDenseMatrix(m, n, ctx.raw()) };
        if raw.is_null() {
            return Err(SundialsError::NullHandle("SUNDenseMatrix"));
        }
        let mut a = DenseMatrix {
            raw,
            nrows,
            ncols,
            _ctx: Rc::clone(ctx),
        };
        a.zero();
        Ok(a)
    }

    pub fn nrows(&self) -> usize {
        self.nrows
    }

    pub fn ncols(&self) -> usize {
        self.ncols
    }

    fn data(&mut self) -> &mut [f64] {
        // SAFETY: a dense matrix stores nrows*ncols reals contiguously; &mut self is exclusive.
        unsafe {
            std::slice::from_raw_parts_mut(SUNDenseMatrix_Data(self.raw), self.nrows * self.ncols)
        }
    }

    pub fn zero(&mut self) {
        self.data().fill(0.0);
    }

    pub fn view_mut(&mut self) -> DenseMut<'_> {
        let (nrows, ncols) = (self.nrows, self.ncols);
        DenseMut {
            data: self.data(),
            nrows,
            ncols,
        }
    }

    pub(crate) fn raw(&self) -> SUNMatrix {
        self.raw
    }
}

/// A square band SUNMatrix with `upper`/`lower` bandwidths, destroyed on drop. SUNDIALS
/// stores `upper + lower` super-diagonals so that the band LU can fill in.
pub struct BandMatrix {
    raw: SUNMatrix,
    n: usize,
    upper: usize,
    lower: usize,
    smu: usize,
    ldim: usize,
    outside: Cell<usize>,
    _ctx: Rc<Context>,
}

impl BandMatrix {
    /// Bandwidths larger than n - 1 are clamped to n - 1.
    pub fn new(
        ctx: &Rc<Context>,
        n: usize,
        upper: usize,
        lower: usize,
    ) -> Result<Self, SundialsError> {
        if n == 0 {
            return Err(SundialsError::Invalid("a band matrix needs n ≥ 1".into()));
        }
        let (upper, lower) = (upper.min(n - 1), lower.min(n - 1));
        let nn = index_type(n, "size")?;
        // SAFETY: ctx is live; the result is checked for NULL.
        let raw =
            unsafe { SUNBandMatrix(nn, upper as sunindextype, lower as sunindextype, ctx.raw()) };
        if raw.is_null() {
            return Err(SundialsError::NullHandle("SUNBandMatrix"));
        }
        // SAFETY: raw is a live band matrix.
        let (smu, ldim) = unsafe {
            (
                SUNBandMatrix_StoredUpperBandwidth(raw) as usize,
                SUNBandMatrix_LDim(raw) as usize,
            )
        };
        let mut a = BandMatrix {
            raw,
            n,
            upper,
            lower,
            smu,
            ldim,
            outside: Cell::new(0),
            _ctx: Rc::clone(ctx),
        };
        a.zero();
        Ok(a)
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn upper(&self) -> usize {
        self.upper
    }

    pub fn lower(&self) -> usize {
        self.lower
    }

    fn data(&mut self) -> &mut [f64] {
        // SAFETY: a band matrix stores n columns of ldim reals contiguously.
        unsafe { std::slice::from_raw_parts_mut(SUNBandMatrix_Data(self.raw), self.n * self.ldim) }
    }

    pub fn zero(&mut self) {
        self.data().fill(0.0);
    }

    pub fn view_mut(&mut self) -> BandMut<'_> {
        let (n, upper, lower, smu, ldim) = (self.n, self.upper, self.lower, self.smu, self.ldim);
        // SAFETY: as in data(); `outside` is a separate field, not inside the slice.
        let data =
            unsafe { std::slice::from_raw_parts_mut(SUNBandMatrix_Data(self.raw), n * ldim) };
        BandMut {
            data,
            n,
            upper,
            lower,
            smu,
            ldim,
            outside: &self.outside,
        }
    }

    pub(crate) fn raw(&self) -> SUNMatrix {
        self.raw
    }
}

/// A square CSR SUNMatrix with a fixed sparsity pattern, destroyed on drop.
///
/// The pattern is kept in Rust and written back into the SUNMatrix before every fill
/// (`SUNMatZero`, which KINSOL calls before each Jacobian evaluation, zeroes the index
/// arrays of a sparse matrix too).
pub struct SparseMatrix {
    raw: SUNMatrix,
    n: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<usize>,
    /// A hash of the pattern (FNV-1a), so that a solver can check in O(1) that a matrix has
    /// the pattern it was made for.
    fingerprint: u64,
    outside: Cell<usize>,
    _ctx: Rc<Context>,
}

impl SparseMatrix {
    /// `row_ptr` (length n + 1, starting at 0, non-decreasing) and `col_idx` (strictly
    /// increasing within each row, < n) give the pattern, fixed for the matrix's life.
    pub fn new(
        ctx: &Rc<Context>,
        n: usize,
        row_ptr: Vec<usize>,
        col_idx: Vec<usize>,
    ) -> Result<Self, SundialsError> {
        validate_csr(n, &row_ptr, &col_idx)?;
        let nn = index_type(n, "size")?;
        let nnz = index_type(col_idx.len().max(1), "nnz")?;
        // SAFETY: ctx is live; the result is checked for NULL.
        let raw = unsafe { SUNSparseMatrix(nn, nn, nnz, CSR_MAT as i32, ctx.raw()) };
        if raw.is_null() {
            return Err(SundialsError::NullHandle("SUNSparseMatrix"));
        }
        let fingerprint = pattern_fingerprint(&row_ptr, &col_idx);
        let mut a = SparseMatrix {
            raw,
            n,
            row_ptr,
            col_idx,
            fingerprint,
            outside: Cell::new(0),
            _ctx: Rc::clone(ctx),
        };
        a.zero();
        Ok(a)
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

    /// The hash of the pattern, fixed for the matrix's life.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    fn values(&mut self) -> &mut [f64] {
        // SAFETY: the matrix was allocated with max(nnz, 1) ≥ nnz values.
        unsafe {
            std::slice::from_raw_parts_mut(SUNSparseMatrix_Data(self.raw), self.col_idx.len())
        }
    }

    /// Write our pattern into the SUNMatrix's index arrays.
    pub(crate) fn restore_pattern(&mut self) {
        // SAFETY: the matrix has n + 1 index pointers and ≥ nnz index values.
        unsafe {
            let ptrs =
                std::slice::from_raw_parts_mut(SUNSparseMatrix_IndexPointers(self.raw), self.n + 1);
            for (dst, &src) in ptrs.iter_mut().zip(&self.row_ptr) {
                *dst = src as sunindextype;
            }
            let vals = std::slice::from_raw_parts_mut(
                SUNSparseMatrix_IndexValues(self.raw),
                self.col_idx.len(),
            );
            for (dst, &src) in vals.iter_mut().zip(&self.col_idx) {
                *dst = src as sunindextype;
            }
        }
    }

    /// Whether the SUNMatrix's index arrays still hold our pattern.
    pub(crate) fn pattern_intact(&self) -> bool {
        // SAFETY: as in restore_pattern, read-only.
        unsafe {
            let ptrs =
                std::slice::from_raw_parts(SUNSparseMatrix_IndexPointers(self.raw), self.n + 1);
            let vals = std::slice::from_raw_parts(
                SUNSparseMatrix_IndexValues(self.raw),
                self.col_idx.len(),
            );
            ptrs.iter()
                .zip(&self.row_ptr)
                .all(|(&a, &b)| a as usize == b)
                && vals
                    .iter()
                    .zip(&self.col_idx)
                    .all(|(&a, &b)| a as usize == b)
        }
    }

    /// Set every value at once, in the order of the pattern (`col_idx`).
    pub fn copy_values(&mut self, values: &[f64]) -> Result<(), SundialsError> {
        if values.len() != self.col_idx.len() {
            return Err(SundialsError::Invalid(format!(
                "{} values for a pattern of {}",
                values.len(),
                self.col_idx.len()
            )));
        }
        self.values().copy_from_slice(values);
        Ok(())
    }

    /// Zero the values and (re)write the pattern.
    pub fn zero(&mut self) {
        self.values().fill(0.0);
        self.restore_pattern();
    }

    pub fn view_mut(&mut self) -> CsrMut<'_> {
        let nnz = self.col_idx.len();
        // SAFETY: as in values(); the pattern and `outside` are separate fields.
        let values = unsafe { std::slice::from_raw_parts_mut(SUNSparseMatrix_Data(self.raw), nnz) };
        CsrMut {
            values,
            row_ptr: &self.row_ptr,
            col_idx: &self.col_idx,
            outside: &self.outside,
        }
    }

    pub(crate) fn raw(&self) -> SUNMatrix {
        self.raw
    }
}

/// FNV-1a over the pattern's lengths and indices.
fn pattern_fingerprint(row_ptr: &[usize], col_idx: &[usize]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &v in [row_ptr.len(), col_idx.len()]
        .iter()
        .chain(row_ptr)
        .chain(col_idx)
    {
        h ^= v as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

fn validate_csr(n: usize, row_ptr: &[usize], col_idx: &[usize]) -> Result<(), SundialsError> {
    let bad = |why: String| Err(SundialsError::Invalid(format!("CSR pattern: {why}")));
    if n == 0 {
        return bad("n must be ≥ 1".into());
    }
    if row_ptr.len() != n + 1 {
        return bad(format!(
            "row_ptr has {} entries, expected n + 1 = {}",
            row_ptr.len(),
            n + 1
        ));
    }
    if row_ptr[0] != 0 || row_ptr[n] != col_idx.len() {
        return bad(format!(
            "row_ptr must start at 0 and end at nnz = {} (got {} .. {})",
            col_idx.len(),
            row_ptr[0],
            row_ptr[n]
        ));
    }
    for i in 0..n {
        if row_ptr[i] > row_ptr[i + 1] {
            return bad(format!("row_ptr decreases at row {i}"));
        }
        let row = &col_idx[row_ptr[i]..row_ptr[i + 1]];
        if row.iter().any(|&j| j >= n) {
            return bad(format!("row {i} has a column index ≥ n = {n}"));
        }
        if row.windows(2).any(|w| w[0] >= w[1]) {
            return bad(format!(
                "row {i}'s column indices are not strictly increasing"
            ));
        }
    }
    Ok(())
}

macro_rules! destroy_on_drop {
    ($($t:ty),*) => {$(
        impl Drop for $t {
            fn drop(&mut self) {
                // SAFETY: `raw` came from its SUNDIALS constructor and is destroyed once;
                // solvers that use it hold it only while they are alive, and owners drop
                // them first (see Kinsol's field order).
                unsafe { SUNMatDestroy(self.raw) }
            }
        }
    )*};
}
destroy_on_drop!(DenseMatrix, BandMatrix, SparseMatrix);

/// One of the owned matrix types.
pub enum Matrix {
    Dense(DenseMatrix),
    Band(BandMatrix),
    Sparse(SparseMatrix),
    Block(BlockMatrix),
}

impl Matrix {
    pub fn kind(&self) -> MatrixKind {
        match self {
            Matrix::Dense(_) => MatrixKind::Dense,
            Matrix::Band(_) => MatrixKind::Band,
            Matrix::Sparse(_) => MatrixKind::Sparse,
            Matrix::Block(_) => MatrixKind::Block,
        }
    }

    pub fn nrows(&self) -> usize {
        match self {
            Matrix::Dense(m) => m.nrows(),
            Matrix::Band(m) => m.n(),
            Matrix::Sparse(m) => m.n(),
            Matrix::Block(m) => m.lu().size(),
        }
    }

    pub fn ncols(&self) -> usize {
        match self {
            Matrix::Dense(m) => m.ncols(),
            Matrix::Band(m) => m.n(),
            Matrix::Sparse(m) => m.n(),
            Matrix::Block(m) => m.lu().size(),
        }
    }

    /// Zero every entry (for a sparse matrix, the values; the pattern is rewritten).
    pub fn zero(&mut self) {
        match self {
            Matrix::Dense(m) => m.zero(),
            Matrix::Band(m) => m.zero(),
            Matrix::Sparse(m) => m.zero(),
            Matrix::Block(m) => m.lu_mut().zero(),
        }
    }

    pub fn view_mut(&mut self) -> JacobianMatrix<'_> {
        match self {
            Matrix::Dense(m) => JacobianMatrix::Dense(m.view_mut()),
            Matrix::Band(m) => JacobianMatrix::Band(m.view_mut()),
            Matrix::Sparse(m) => JacobianMatrix::Sparse(m.view_mut()),
            Matrix::Block(m) => JacobianMatrix::Block(m.lu_mut()),
        }
    }

    /// Copy `other`'s entries into this matrix (same kind and shape; a sparse matrix's
    /// pattern too): SUNMatCopy, or the blocks for a block matrix. For benchmarks and
    /// callers that keep an assembled matrix to factor again (dense and band LU factor in
    /// place).
    pub fn copy_from(&mut self, other: &Matrix) -> Result<(), SundialsError> {
        if self.kind() != other.kind() || self.nrows() != other.nrows() {
            return Err(SundialsError::Invalid(format!(
                "cannot copy a {} into a {}",
                other.describe(),
                self.describe()
            )));
        }
        if let (Matrix::Block(dst), Matrix::Block(src)) = (&mut *self, other) {
            dst.lu_mut().clone_from(src.lu());
            return Ok(());
        }
        // SAFETY: both matrices are live SUNDIALS matrices of the same kind and size,
        // distinct (one is borrowed mutably); SUNMatCopy only reads `other`.
        let flag = unsafe { sundials_sys::SUNMatCopy(other.raw(), self.raw()) };
        if flag != 0 {
            return Err(SundialsError::Invalid(format!(
                "SUNMatCopy failed with flag {flag}"
            )));
        }
        Ok(())
    }

    /// The body of every Jacobian callback (KINSOL's, CVODE's, IDA's): zero the matrix, let
    /// `fill` set its structural entries, and fail (Fatal) if any write fell outside the
    /// structure (release builds count those writes instead of panicking).
    ///
    /// A block matrix is not zeroed whole: only its boundary rows, whose entries assemblers
    /// set sparsely. Its interval blocks are dense and must be written whole (the factors
    /// live apart, so they keep the last assembly's values otherwise); debug builds fill
    /// them with NaN first, so that an entry left unwritten fails the factorisation.
    pub(crate) fn fill_jacobian(
        &mut self,
        fill: impl FnOnce(JacobianMatrix<'_>) -> CallbackResult,
    ) -> CallbackResult {
        match self {
            Matrix::Block(m) => {
                m.lu_mut().zero_boundary();
                if cfg!(debug_assertions) {
                    m.lu_mut().poison_blocks();
                }
            }
            _ => self.zero(),
        }
        self.take_outside();
        fill(self.view_mut())?;
        match self.take_outside() {
            0 => Ok(()),
            k => Err(CallbackError::Fatal(format!(
                "{k} entries were set outside the structure of the {} Jacobian",
                self.describe()
            ))),
        }
    }

    /// How many writes fell outside the band/pattern since the last call; resets the count.
    pub(crate) fn take_outside(&mut self) -> usize {
        match self {
            Matrix::Dense(_) => 0,
            Matrix::Band(m) => m.outside.replace(0),
            Matrix::Sparse(m) => m.outside.replace(0),
            Matrix::Block(m) => m.lu_mut().take_outside(),
        }
    }

    /// Make the SUNMatrix consistent before SUNDIALS factorises it (sparse: pattern).
    pub(crate) fn before_setup(&mut self) {
        if let Matrix::Sparse(m) = self {
            if !m.pattern_intact() {
                m.restore_pattern();
            }
        }
    }

    pub(crate) fn raw(&self) -> SUNMatrix {
        match self {
            Matrix::Dense(m) => m.raw(),
            Matrix::Band(m) => m.raw(),
            Matrix::Sparse(m) => m.raw(),
            Matrix::Block(m) => m.raw(),
        }
    }

    /// A short description for messages, e.g. "band (upper 1, lower 1)".
    pub fn describe(&self) -> String {
        match self {
            Matrix::Dense(m) => format!("dense {}x{}", m.nrows(), m.ncols()),
            Matrix::Band(m) => format!(
                "band n={} (upper {}, lower {})",
                m.n(),
                m.upper(),
                m.lower()
            ),
            Matrix::Sparse(m) => format!("CSR n={} nnz={}", m.n(), m.nnz()),
            Matrix::Block(m) => format!(
                "almost block diagonal n={} ({} nodes, {} top rows)",
                m.lu().size(),
                m.lu().nodes(),
                m.lu().top()
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_view_writes_into_sundials_band_storage() {
        let ctx = Context::new().unwrap();
        let mut a = BandMatrix::new(&ctx, 5, 1, 2).unwrap();
        {
            let mut v = a.view_mut();
            for j in 0..5usize {
                for i in j.saturating_sub(1)..(j + 3).min(5) {
                    v.set(i, j, (10 * i + j) as f64);
                }
            }
        }
        // Read back through SUNDIALS's own column accessor: col_j[i - j] after SM_COLUMN_B.
        for j in 0..5usize {
            // SAFETY: test-only read of a live band matrix.
            let col = unsafe { sundials_sys::SUNBandMatrix_Column(a.raw(), j as sunindextype) };
            for i in j.saturating_sub(1)..(j + 3).min(5) {
                let got = unsafe { *col.offset(i as isize - j as isize) };
                assert_eq!(got, (10 * i + j) as f64, "({i},{j})");
            }
        }
        let v = a.view_mut();
        assert!(!v.contains(0, 2) && !v.contains(3, 0) && v.contains(2, 0));
    }

    #[test]
    fn csr_validation_rejects_bad_patterns() {
        let ctx = Context::new().unwrap();
        assert!(SparseMatrix::new(&ctx, 2, vec![0, 1, 2], vec![0, 1]).is_ok());
        assert!(SparseMatrix::new(&ctx, 2, vec![0, 2, 2], vec![1, 0]).is_err()); // unsorted
        assert!(SparseMatrix::new(&ctx, 2, vec![0, 1, 2], vec![0, 2]).is_err()); // j ≥ n
        assert!(SparseMatrix::new(&ctx, 2, vec![0, 1], vec![0]).is_err()); // short row_ptr
    }

    #[test]
    fn sparse_pattern_survives_sunmatzero() {
        let ctx = Context::new().unwrap();
        let mut a =
            Matrix::Sparse(SparseMatrix::new(&ctx, 2, vec![0, 2, 3], vec![0, 1, 1]).unwrap());
        // SAFETY: test-only; this is what KINSOL does before each Jacobian evaluation.
        unsafe { sundials_sys::SUNMatZero(a.raw()) };
        let Matrix::Sparse(s) = &a else {
            unreachable!()
        };
        assert!(!s.pattern_intact());
        a.before_setup();
        let Matrix::Sparse(s) = &a else {
            unreachable!()
        };
        assert!(s.pattern_intact());
    }

    #[test]
    #[cfg(not(debug_assertions))]
    fn release_counts_writes_outside_the_band() {
        let ctx = Context::new().unwrap();
        let mut a = Matrix::Band(BandMatrix::new(&ctx, 4, 1, 1).unwrap());
        a.view_mut().set(0, 3, 1.0);
        assert_eq!(a.take_outside(), 1);
        assert_eq!(a.take_outside(), 0);
    }
}
