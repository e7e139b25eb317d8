//! LU of almost-block-diagonal (ABD) matrices with N×N node blocks, in safe Rust: the
//! Jacobians of two-point boundary-value problems discretised on a mesh (N unknowns a
//! node; each interval's N equations couple the unknowns of its two nodes, and the
//! boundary conditions sit at the two ends), and the reduced matrix of [`super::SchurSolver`]
//! when it has that shape. [`AbdLu`] is N = 5, [`AbdLu6`] N = 6. The block width is a
//! const generic, so each width gets the fixed-size code below; the text describes N = 5.
//!
//! Structure (M nodes, n = 5M unknowns, p rows at the start, 5 − p at the end):
//!
//! ```text
//!   rows 0..p          columns 0..5                  (the left boundary's conditions)
//!   rows p+5k..p+5k+5  columns 5k..5k+10, k < M − 1   (interval k: nodes k and k+1)
//!   rows n−(5−p)..n    columns n−5..n                (the right boundary's conditions)
//! ```
//!
//! Any one-step scheme on any mesh produces this one shape; what differs is only the values.
//!
//! # Elimination: row pivoting within block rows
//!
//! Stage k eliminates node k's five columns. The only rows with entries in them are the
//! p rows left over from stage k − 1 (for k = 0 the top rows) and interval k's five rows
//! (the bottom rows at the last stage): an 8×10 working block. Partial pivoting among those
//! eight rows is therefore *exactly* Gaussian elimination with partial pivoting on the whole
//! matrix (the same pivot choices as LAPACK's gbtrf or SUNDIALS' band LU, ties aside), with
//! its well-understood stability, and there is no fill-in outside the working block: the
//! five pivot rows become U (5×10: U₁₁ upper triangular, U₁₂ coupling to node k + 1) and
//! the p rows not chosen carry their last five columns into stage k + 1.
//!
//! Why not the alternate row and column elimination of Diaz, Fairweather and Keast (COLROW,
//! ABDPACK): that scheme exists to avoid the fill-in that row pivoting causes when the
//! blocks' overlap is not square and the top block has fewer rows than the overlap; it
//! trades it for column interchanges, a second permutation in every solve and a harder
//! bookkeeping. Here the overlap is exactly one node (5 columns) and the carried rows never
//! reach beyond the next block, so row pivoting has no fill to avoid: the same storage
//! (one 8×10 block per node), the same flop count (≈ 395 flops per node against ≈ 945 for
//! the band LU of widths 7 and 13, counted in BENCHMARKS.md), and a single row permutation.
//!
//! # Near-singular matrices
//!
//! A pivot of at most 1e-14 of its column's largest original entry (the tolerance of
//! [`BandLu`](super::BandLu)) is reported as [`LinalgError::Singular`], naming the node and
//! the column; non-finite entries are reported too. The growth factor
//! max |U| / max |A| is kept with the factors ([`AbdFactors::growth`]) as a diagnostic.
//!
//! # Storage
//!
//! The assembled matrix and the factors are kept apart: the assembler's blocks are never
//! overwritten by a factorisation, so an assembler that writes the same entries every time
//! (the discretisation writes every entry of every interval block) needs no zeroing between
//! Jacobians ([`Abd::zero_boundary`] clears only the boundary rows, whose entries are set
//! sparsely). Each stage's factors are one 10×10 column-major array (rows 0..p+5 used):
//! the multipliers below the diagonal of columns 0..5, U above, the pivots' reciprocals
//! apart. Column-major because the elimination then updates whole columns with
//! fixed-length vector operations, and the stage sizes are constants (dispatched on the
//! number of top rows): at N = 501 the factorisation took 165 µs row-major with runtime
//! loop bounds, 101 µs without serial reductions, 76 µs column-major with constant sizes.

use super::LinalgError;
use crate::MatrixSink;

/// Unknowns per node of [`AbdLu`]: the size of its diagonal blocks.
pub const NODE: usize = 5;
/// A pivot at most this much of its column's largest original entry counts as singular.
const PIVOT_TOLERANCE: f64 = 1e-14;

/// An almost-block-diagonal matrix of 5×5 node blocks.
pub type AbdLu = Abd<NODE, { 2 * NODE }>;
/// An almost-block-diagonal matrix of 6×6 node blocks (the reduced matrix of
/// [`super::SchurSolver`], [`super::Reduced::Block`]).
pub type AbdLu6 = Abd<6, 12>;
/// The factors of an [`AbdLu`].
pub type AbdLuFactors = AbdFactors<NODE, { 2 * NODE }>;
/// The factors of an [`AbdLu6`].
pub type AbdLu6Factors = AbdFactors<6, 12>;

/// An almost-block-diagonal matrix with N×N node blocks (see the module docs; W = 2N, the
/// columns of an interval's block, a parameter of its own because stable Rust cannot
/// write array lengths 2N). [`Abd::factor`] makes its LU factors, [`AbdFactors`], the only
/// thing that solves: a solve without a factorisation, or with the factors of a matrix
/// since rewritten, cannot be written.
#[derive(Clone, Debug)]
pub struct Abd<const N: usize, const W: usize> {
    nodes: usize,
    top: usize,
    /// The top rows over columns 0..5.
    top_rows: Vec<[f64; N]>,
    /// Interval k's rows over columns 5k..5k+10, column-major: `blocks[k][j][a]`.
    blocks: Vec<[[f64; N]; W]>,
    /// The bottom rows over the last five columns.
    bottom_rows: Vec<[f64; N]>,
    outside: usize,
}

/// The LU factors of an [`Abd`] matrix as it was when [`Abd::factor`] succeeded: P A = L U,
/// stage by stage (module docs). They hold no reference to the matrix, which may be
/// rewritten and factored again into the same storage ([`Abd::factor_reusing`]).
#[derive(Clone, Debug)]
pub struct AbdFactors<const N: usize, const W: usize> {
    nodes: usize,
    top: usize,
    /// Stage k's working block after elimination, column-major (`lu[k][j][r]`): rows
    /// 0..p+N (0..N at the last stage).
    lu: Vec<[[f64; W]; W]>,
    /// Stage k: the row exchanged with row c at step c (full-row swaps, as LAPACK's getrf).
    piv: Vec<[u8; N]>,
    /// Stage k: 1 / U_cc.
    inv_diag: Vec<[f64; N]>,
    growth: f64,
}

impl<const N: usize, const W: usize> Abd<N, W> {
    /// A zero ABD matrix of `nodes` nodes (n = N · nodes) with `top` rows at the start
    /// (0 ≤ top ≤ N) and N − top at the end.
    pub fn new(nodes: usize, top: usize) -> Result<Self, LinalgError> {
        // The stage dispatch in `factor` and `solve_in_place` covers blocks up to 6 wide.
        const { assert!(W == 2 * N && N >= 1 && N <= 6) };
        if nodes == 0 || top > N {
            return Err(LinalgError::Size(format!(
                "almost-block-diagonal matrix of {nodes} nodes with {top} top rows (need ≥ 1 node and ≤ {N} top rows)"
            )));
        }
        // Each node stores at most about 1.7 kB; more than 2^24 nodes (28 GB) is a caller's
        // mistake.
        if nodes > 1 << 24 {
            return Err(LinalgError::Size(format!(
                "almost-block-diagonal matrix of {nodes} nodes"
            )));
        }
        Ok(Abd {
            nodes,
            top,
            top_rows: vec![[0.0; N]; top],
            blocks: vec![[[0.0; N]; W]; nodes - 1],
            bottom_rows: vec![[0.0; N]; N - top],
            outside: 0,
        })
    }

    /// n = N · nodes.
    pub fn size(&self) -> usize {
        N * self.nodes
    }

    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// Rows at the start (the rest of the boundary rows, N − top, are at the end).
    pub fn top(&self) -> usize {
        self.top
    }

    /// Set every entry to zero.
    pub fn zero(&mut self) {
        self.zero_boundary();
        for b in &mut self.blocks {
            *b = [[0.0; N]; W];
        }
    }

    /// Zero the boundary rows only: enough between Jacobians when the assembler writes
    /// every entry of every interval block (see the module docs).
    pub fn zero_boundary(&mut self) {
        self.top_rows.fill([0.0; N]);
        self.bottom_rows.fill([0.0; N]);
    }

    /// Fill every interval block with NaN: an assembler that leaves an entry unwritten then
    /// makes [`Abd::factor`] fail instead of using a stale value (for debug builds and
    /// tests of assemblers that rely on [`Abd::zero_boundary`]).
    pub fn poison_blocks(&mut self) {
        for b in &mut self.blocks {
            *b = [[f64::NAN; N]; W];
        }
    }

    /// Where (i, j) is stored: (which part, index of the row in it, column in the row).
    #[inline]
    fn locate(&self, i: usize, j: usize) -> Option<(Part, usize, usize)> {
        let n = self.size();
        let p = self.top;
        if i < p {
            (j < N).then_some((Part::Top, i, j))
        } else if i >= n - (N - p) {
            (i < n && j >= n - N && j < n).then(|| (Part::Bottom, i + N - p - n, j + N - n))
        } else {
            let k = (i - p) / N;
            let c0 = N * k;
            (j >= c0 && j < c0 + W).then_some((Part::Block(k), (i - p) % N, j - c0))
        }
    }

    /// The entry (i, j) as set (before factoring); zero outside the structure.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        match self.locate(i, j) {
            Some((Part::Top, a, b)) => self.top_rows[a][b],
            Some((Part::Bottom, a, b)) => self.bottom_rows[a][b],
            Some((Part::Block(k), a, b)) => self.blocks[k][b][a],
            None => 0.0,
        }
    }

    /// Row i's columns in the structure: (first, count), N columns for a boundary row and
    /// 2N for an interval's.
    ///
    /// # Errors
    /// [`LinalgError::Length`] if there is no row i (i ≥ n).
    pub fn row_span(&self, i: usize) -> Result<(usize, usize), LinalgError> {
        let (n, p) = (self.size(), self.top);
        if i >= n {
            return Err(LinalgError::Length(format!(
                "row {i} of a matrix of size {n}"
            )));
        }
        Ok(if i < p {
            (0, N)
        } else if i >= n - (N - p) {
            (n - N, N)
        } else {
            (N * ((i - p) / N), W)
        })
    }

    /// Overwrite row i over its [`Abd::row_span`] (`values` of exactly that length).
    ///
    /// # Errors
    /// [`LinalgError::Length`] if there is no row i or `values` is not as long as its span;
    /// the matrix is then unchanged.
    pub fn set_row(&mut self, i: usize, values: &[f64]) -> Result<(), LinalgError> {
        let (first, len) = self.row_span(i)?;
        if values.len() != len {
            return Err(LinalgError::Length(format!(
                "{} values for row {i}, which spans {len} columns from column {first}",
                values.len()
            )));
        }
        let (n, p) = (self.size(), self.top);
        if i < p {
            self.top_rows[i].copy_from_slice(values);
        } else if i >= n - (N - p) {
            self.bottom_rows[i + N - p - n].copy_from_slice(values);
        } else {
            let a = (i - p) % N;
            let block = &mut self.blocks[(i - p) / N];
            for (col, &v) in block.iter_mut().zip(values) {
                col[a] = v;
            }
        }
        Ok(())
    }

    /// The number of writes outside the structure since the last call, and reset it.
    pub fn take_outside(&mut self) -> usize {
        std::mem::take(&mut self.outside)
    }

    /// Factorise the matrix as set: P A = L U by Gaussian elimination with partial pivoting,
    /// stage by stage (module docs). The matrix is left as it is.
    ///
    /// # Errors
    /// [`LinalgError::Singular`] for a pivot of zero or at most 1e-14 of its column's
    /// largest original entry, or a non-finite entry, naming the node and the column.
    pub fn factor(&self) -> Result<AbdFactors<N, W>, LinalgError> {
        self.factor_reusing(None)
    }

    /// [`Abd::factor`] into the storage of `old` factors (of a matrix of the same shape;
    /// other factors or `None` are replaced by new storage): no allocation in a loop that
    /// factors a matrix after every rewrite. On an error the old factors are gone.
    ///
    /// # Errors
    /// As [`Abd::factor`].
    pub fn factor_reusing(
        &self,
        old: Option<AbdFactors<N, W>>,
    ) -> Result<AbdFactors<N, W>, LinalgError> {
        let mut f = match old {
            Some(f) if f.nodes == self.nodes && f.top == self.top => f,
            _ => AbdFactors {
                nodes: self.nodes,
                top: self.top,
                lu: vec![[[0.0; W]; W]; self.nodes],
                piv: vec![[0; N]; self.nodes],
                inv_diag: vec![[0.0; N]; self.nodes],
                growth: 0.0,
            },
        };
        let m = self.nodes;
        let (mut a_max, mut u_max) = (0.0f64, 0.0f64);
        for k in 0..m {
            // Fixed sizes let the compiler unroll the elimination and vectorise its columns:
            // R = top + N rows, instantiated for the block widths in use (5 and 6).
            let result = match (k == m - 1, self.top + N) {
                (true, _) => f.stage::<N, N>(self, k),
                (false, 5) => f.stage::<5, W>(self, k),
                (false, 6) => f.stage::<6, W>(self, k),
                (false, 7) => f.stage::<7, W>(self, k),
                (false, 8) => f.stage::<8, W>(self, k),
                (false, 9) => f.stage::<9, W>(self, k),
                (false, 10) => f.stage::<10, W>(self, k),
                (false, 11) => f.stage::<11, W>(self, k),
                (false, 12) => f.stage::<12, W>(self, k),
                (false, r) => {
                    return Err(LinalgError::Structure(format!(
                        "{r} rows in a block LU stage (new() admits N ≤ 6)"
                    )))
                }
            };
            let (stage_a, stage_u) = result?;
            a_max = a_max.max(stage_a);
            u_max = u_max.max(stage_u);
        }
        f.growth = if a_max > 0.0 { u_max / a_max } else { 0.0 };
        Ok(f)
    }

    fn count_outside(&mut self, i: usize, j: usize) {
        debug_assert!(
            false,
            "({i},{j}) is outside the almost-block-diagonal structure ({} nodes, {} top rows)",
            self.nodes, self.top
        );
        self.outside += 1;
    }
}

impl<const N: usize, const W: usize> AbdFactors<N, W> {
    /// n = N · nodes, the size of the matrix factored.
    pub fn size(&self) -> usize {
        N * self.nodes
    }

    /// The growth factor max |U| / max |A| of the factorisation.
    pub fn growth(&self) -> f64 {
        self.growth
    }

    /// Stage k: gather its R×C working block (the rows carried from stage k − 1, or the top
    /// rows, and interval k's rows, or the bottom rows), eliminate node k's five columns with
    /// partial pivoting among all R rows (full-row swaps, as LAPACK's getrf), store it.
    /// Returns (max |A| over node k's columns, max |U|).
    ///
    /// Column-major, so that each column update is one fixed-length vector operation over
    /// all R rows: the multipliers of the rows at or above the pivot are zero, which leaves
    /// them unchanged (a few wasted flops, no branches or runtime bounds).
    #[inline(always)]
    fn stage<const R: usize, const C: usize>(
        &mut self,
        m: &Abd<N, W>,
        k: usize,
    ) -> Result<(f64, f64), LinalgError> {
        // A constant but at the last stage: fixed-length copies, no memmove calls.
        let p = if C == N { self.top } else { R - N };
        let mut a = [[0.0f64; R]; C];
        // Largest original |entry| of node k's columns: from interval k − 1's right half
        // (or the top rows) and this stage's new rows.
        let mut col_max = [0.0f64; N];
        if k == 0 {
            for (r, row) in m.top_rows.iter().enumerate() {
                for j in 0..N {
                    a[j][r] = row[j];
                    col_max[j] = col_max[j].max(row[j].abs());
                }
            }
        } else {
            let prev = &self.lu[k - 1];
            for j in 0..N {
                a[j][..p].copy_from_slice(&prev[N + j][N..N + p]);
                col_max[j] = m.blocks[k - 1][N + j]
                    .iter()
                    .fold(0.0f64, |x, v| x.max(v.abs()));
            }
        }
        if C == N {
            for (r, row) in m.bottom_rows.iter().enumerate() {
                for j in 0..N {
                    a[j][p + r] = row[j];
                }
            }
        } else {
            for (col, src) in a.iter_mut().zip(&m.blocks[k]) {
                col[p..].copy_from_slice(src);
            }
        }
        for j in 0..N {
            for v in &a[j][p..] {
                col_max[j] = col_max[j].max(v.abs());
            }
        }
        let stage_max = col_max.iter().fold(0.0f64, |x, &y| x.max(y));
        let (piv, inv_diag) = (&mut self.piv[k], &mut self.inv_diag[k]);
        for c in 0..N {
            let (mut best_row, mut best) = (c, a[c][c].abs());
            for r in c + 1..R {
                let v = a[c][r].abs();
                if v > best {
                    (best_row, best) = (r, v);
                }
            }
            if !(best > PIVOT_TOLERANCE * col_max[c]) {
                let (col, scale) = (N * k + c, col_max[c]);
                return Err(LinalgError::Singular(if best == 0.0 {
                    format!("block LU: column {col} (node {k}, unknown {c}) has no nonzero pivot")
                } else if best.is_nan() || scale.is_nan() {
                    format!(
                        "block LU: column {col} (node {k}, unknown {c}) holds a non-finite entry"
                    )
                } else {
                    format!(
                        "block LU: column {col} (node {k}, unknown {c}): pivot {best:e} is below {PIVOT_TOLERANCE:e} of the column's scale {scale:e}"
                    )
                }));
            }
            piv[c] = best_row as u8;
            if best_row != c {
                for col in a.iter_mut() {
                    col.swap(c, best_row);
                }
            }
            let inv = 1.0 / a[c][c];
            inv_diag[c] = inv;
            let mut l = [0.0f64; R];
            for r in c + 1..R {
                l[r] = a[c][r] * inv;
            }
            a[c][c + 1..].copy_from_slice(&l[c + 1..]);
            for col in a[c + 1..].iter_mut() {
                let u = col[c];
                for r in 0..R {
                    col[r] -= l[r] * u;
                }
            }
        }
        // Column-wise lanes, so that neither reduction is one long dependency chain: the
        // magnitudes of U (rows 0..5), and x · 0 (0, or NaN for a NaN or an infinity that
        // compares false everywhere and could hide from the pivot test) over every entry.
        let (mut big, mut probe) = ([0.0f64; R], [0.0f64; R]);
        for col in &a {
            for r in 0..R {
                if r < N {
                    big[r] = big[r].max(col[r].abs());
                }
                probe[r] += col[r] * 0.0;
            }
        }
        if probe.iter().sum::<f64>().is_nan() || !stage_max.is_finite() {
            return Err(LinalgError::Singular(format!(
                "block LU: node {k}'s rows hold a non-finite entry"
            )));
        }
        for (dst, src) in self.lu[k].iter_mut().zip(&a) {
            dst[..R].copy_from_slice(src);
        }
        Ok((stage_max, big.iter().fold(0.0f64, |x, &y| x.max(y))))
    }

    /// b ← A⁻¹ b. The factors are not changed: any number of right sides.
    ///
    /// # Errors
    /// [`LinalgError::Length`] if b's length is not n (b is then unchanged).
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinalgError> {
        let (m, p) = (self.nodes, self.top);
        if b.len() != self.size() {
            return Err(LinalgError::Length(format!(
                "right side of length {} for a block LU of size {}",
                b.len(),
                self.size()
            )));
        }
        // Forward: stage k reads its rows' right sides (carried ones and interval k's, which
        // start at p + 5k ≥ 5k) and leaves y_k at 5k..5k+5: in place, read before written.
        let carry = match p {
            0 => self.forward::<0>(b),
            1 => self.forward::<1>(b),
            2 => self.forward::<2>(b),
            3 => self.forward::<3>(b),
            4 => self.forward::<4>(b),
            5 => self.forward::<5>(b),
            _ => self.forward::<6>(b),
        };
        // The last stage: the carried rows and the bottom ones.
        let k = m - 1;
        let (w, piv) = (&self.lu[k], &self.piv[k]);
        let mut y = [0.0; N];
        y[..p].copy_from_slice(&carry[..p]);
        y[p..].copy_from_slice(&b[p + N * k..]);
        for c in 0..N {
            y.swap(c, piv[c] as usize);
        }
        for c in 0..N {
            let t = y[c];
            for r in c + 1..N {
                y[r] -= w[c][r] * t;
            }
        }
        b[N * k..].copy_from_slice(&y);
        // Back: x_k = U₁₁⁻¹ (y_k − U₁₂ x_{k+1}).
        let mut next = [0.0; N];
        for k in (0..m).rev() {
            let w = &self.lu[k];
            let mut y = [0.0; N];
            y.copy_from_slice(&b[N * k..N * k + N]);
            if k < m - 1 {
                for j in 0..N {
                    let (col, t) = (&w[N + j], next[j]);
                    for a in 0..N {
                        y[a] -= col[a] * t;
                    }
                }
            }
            for c in (0..N).rev() {
                let t = y[c] * self.inv_diag[k][c];
                y[c] = t;
                for a in 0..c {
                    y[a] -= w[c][a] * t;
                }
            }
            b[N * k..N * k + N].copy_from_slice(&y);
            next = y;
        }
        Ok(())
    }

    /// The forward elimination of every stage but the last, P = top rows (a constant, so
    /// that the copies and loops have fixed lengths). Returns the rows carried into the last.
    #[inline(always)]
    fn forward<const P: usize>(&self, b: &mut [f64]) -> [f64; N] {
        let mut carry = [0.0; N];
        carry[..P].copy_from_slice(&b[..P]);
        for k in 0..self.nodes - 1 {
            let (w, piv) = (&self.lu[k], &self.piv[k]);
            let mut y = [0.0; W];
            y[..P].copy_from_slice(&carry[..P]);
            let at = P + N * k;
            y[P..P + N].copy_from_slice(&b[at..at + N]);
            for c in 0..N {
                y.swap(c, piv[c] as usize);
            }
            for c in 0..N {
                let t = y[c];
                for r in c + 1..P + N {
                    y[r] -= w[c][r] * t;
                }
            }
            b[N * k..N * k + N].copy_from_slice(&y[..N]);
            carry[..P].copy_from_slice(&y[N..N + P]);
        }
        carry
    }

    /// x = A⁻¹ b (see [`AbdFactors::solve_in_place`]).
    ///
    /// # Errors
    /// [`LinalgError::Length`] if b's or x's length is not n.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        if b.len() != self.size() || x.len() != self.size() {
            return Err(LinalgError::Length(format!(
                "right side {} and solution {} for a matrix of size {}",
                b.len(),
                x.len(),
                self.size()
            )));
        }
        x.copy_from_slice(b);
        self.solve_in_place(x)
    }
}

#[derive(Clone, Copy)]
enum Part {
    Top,
    Bottom,
    Block(usize),
}

/// The assembler's view: `set` overwrites an entry of the structure; outside it the write
/// is counted (see [`Abd::take_outside`]) and debug builds panic.
impl<const N: usize, const W: usize> MatrixSink for Abd<N, W> {
    fn nrows(&self) -> usize {
        self.size()
    }

    #[inline]
    fn set(&mut self, i: usize, j: usize, v: f64) {
        match self.locate(i, j) {
            Some((Part::Top, a, b)) => self.top_rows[a][b] = v,
            Some((Part::Bottom, a, b)) => self.bottom_rows[a][b] = v,
            Some((Part::Block(k), a, b)) => self.blocks[k][b][a] = v,
            None => self.count_outside(i, j),
        }
    }

    /// An interval's whole 5×10 block (rows p + 5k.., columns 5k..) is one copy; anything
    /// else goes entry by entry.
    #[inline]
    fn set_block(&mut self, row0: usize, col0: usize, ncols: usize, values: &[f64]) {
        let p = self.top;
        if ncols == W
            && values.len() == N * W
            && row0 >= p
            && (row0 - p).is_multiple_of(N)
            && col0 == row0 - p
            && (row0 - p) / N < self.blocks.len()
        {
            let block = &mut self.blocks[(row0 - p) / N];
            for (a, src) in values.chunks_exact(W).enumerate() {
                for (col, &v) in block.iter_mut().zip(src) {
                    col[a] = v;
                }
            }
            return;
        }
        for (a, row) in values.chunks_exact(ncols).enumerate() {
            for (b, &v) in row.iter().enumerate() {
                self.set(row0 + a, col0 + b, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-node matrix by hand: the structure's rows and columns land where they should.
    #[test]
    fn set_and_get_follow_the_structure() {
        let mut a = AbdLu::new(3, 3).unwrap();
        a.set(0, 4, 1.0);
        a.set(3, 9, 2.0);
        a.set(8, 5, 3.0);
        a.set(14, 14, 4.0);
        assert_eq!(
            (a.get(0, 4), a.get(3, 9), a.get(8, 5), a.get(14, 14)),
            (1.0, 2.0, 3.0, 4.0)
        );
        assert_eq!(a.get(0, 5), 0.0);
        assert_eq!(a.take_outside(), 0);
    }
}
