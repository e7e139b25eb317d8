//! The Schur complement of local 2×2 blocks of unknowns. The unknowns are ordered
//! [P | W | d]: P in 2×2 blocks, W the band unknowns (node by node), d an optional
//! border unknown. In the matrix
//!   [D  B  e]      D: block lower triangular (each block's rows read its own block and
//!   [C  A  0]         earlier ones, e.g. a block between two nodes reads theirs),
//!   [cᵀ aᵀ s]      A: band, B and C local (a block's rows and columns touch a few nodes),
//! eliminating P leaves S = [A − C X, −C x_d; aᵀ − cᵀX, s − cᵀ x_d] with [X x_d] = D⁻¹[B e],
//! which has A's band (every X row spans the W columns of one interval) bordered by d.
//! A solve then costs one LU of S (at setup) and one back-substitution (per solve), the
//! size of W alone.
//!
//! When A is the Jacobian of a one-step scheme on a mesh with 6 unknowns a node (rows at
//! the left end reading node 0, per interval 6 rows reading its two nodes, rows at the
//! right end reading the last node) and every block's X spans the nodes of one interval,
//! S keeps that shape: besides a band ([`Reduced::Band`]) S is almost block diagonal with
//! 6×6 node blocks, factored by [`super::AbdLu6`] ([`Reduced::Block`]: no zero band
//! entries are stored or eliminated); [`SchurSolver::new`] checks that the pattern fits.
//!
//! The elimination order is the blocks' order, so the caller numbers blocks that others
//! read first; [`SchurSolver::new`] checks the pattern for it.

use super::{
    AbdLu6, AbdLu6Factors, BandFactors, Bordered, BorderedAbd, BorderedBand, BorderedFactors, Csr,
    DirectSolver, LinalgError,
};

/// Makes a sparse direct solver for a matrix of the given pattern ([`Reduced::Sparse`]).
pub type MakeSparse = fn(&Csr) -> Result<Box<dyn DirectSolver>, LinalgError>;

/// How the reduced matrix S is factored.
#[derive(Clone, Copy, Debug)]
pub enum Reduced {
    /// The crate's band LU ([`super::BandLu`]), the border by block elimination.
    Band,
    /// The almost-block-diagonal LU of 6×6 node blocks ([`AbdLu6`]), the border by block
    /// elimination: S's rows are the left end's (node 0), each interval's (its two nodes)
    /// and the right end's (the last node), checked on the pattern by [`SchurSolver::new`].
    Block,
    /// A sparse direct solver (made by the function for S's pattern: its band rows and the
    /// border) on S as a CSR matrix; eyeshell-sundials' KLU is one.
    Sparse(MakeSparse),
}

/// A pivot block D_kk is used unpivoted only while |det D_kk| ≥ this × the product of its
/// columns' largest entries over the whole matrix (for a diagonal block: each pivot at
/// least this fraction of its column, KLU's own threshold for keeping a diagonal pivot).
/// Below it a pivoting LU would have chosen another row, and elimination in this order
/// could amplify rounding errors without bound: the factorisation reports the block as
/// singular, and the caller falls back to a pivoting solver ([`super::Fallback`]).
pub const PIVOT_TOLERANCE: f64 = 1e-3;

/// The factorisation of S.
enum ReducedSolver {
    /// S, and its factors after a successful factorisation.
    Band {
        bb: BorderedBand,
        factors: Option<BorderedFactors<BandFactors>>,
    },
    /// S's almost-block-diagonal part and border, its factors after a successful
    /// factorisation, and one row's span of scratch.
    Block {
        bb: BorderedAbd,
        factors: Option<BorderedFactors<AbdLu6Factors>>,
        row: Vec<f64>,
    },
    /// S as CSR, and its rows in dense band storage while it is built (row jw holds
    /// columns jw − lower ..= jw + upper) and its border row.
    Sparse {
        s: Csr,
        s_rows: Vec<f64>,
        s_border: Vec<f64>,
        solver: Box<dyn DirectSolver>,
    },
}

/// One block's rows after elimination: D_kk⁻¹, the couplings D_kj (j < k), and
/// X_k = D⁻¹ [B e] restricted to block k (two rows over W columns lo..lo+width, and d).
#[derive(Clone, Debug, Default)]
struct Block {
    inv: [[f64; 2]; 2],
    lower: Vec<(usize, [[f64; 2]; 2])>,
    lo: usize,
    width: usize,
    x: Vec<f64>,
    xd: [f64; 2],
}

/// The entries of C and cᵀ (the W and d rows' entries in P columns) row by row, CSR-like:
/// row jw's are at `end[jw − 1]..end[jw]`. Row by row so that x_jw −= (C z)_jw sums in
/// registers (a list of (row, column, value) stored to x at every entry, a serial chain).
#[derive(Debug, Default)]
struct Coupling {
    end: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl Coupling {
    fn clear(&mut self) {
        self.end.clear();
        self.col.clear();
        self.val.clear();
    }

    /// x −= C z over the rows kept.
    fn subtract_from(&self, z: &[f64], x: &mut [f64]) {
        let mut start = 0;
        for (xi, &end) in x.iter_mut().zip(&self.end) {
            let (cols, vals) = (&self.col[start..end], &self.val[start..end]);
            // Four sums: the border row spans all of P.
            let mut acc = [0.0; 4];
            let (cc, vc) = (cols.chunks_exact(4), vals.chunks_exact(4));
            let tail: f64 = cc
                .remainder()
                .iter()
                .zip(vc.remainder())
                .map(|(&c, v)| v * z[c as usize])
                .sum();
            for (c, v) in cc.zip(vc) {
                for t in 0..4 {
                    acc[t] += v[t] * z[c[t] as usize];
                }
            }
            *xi -= (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail;
            start = end;
        }
    }
}

/// Solves the [P | W | d] system by eliminating P block by block.
pub struct SchurSolver {
    n_p: usize,
    n_w: usize,
    border: bool,
    blocks: Vec<Block>,
    /// Entries of C and cᵀ kept for the solves.
    coupling: Coupling,
    reduced: ReducedSolver,
    /// S's bandwidths.
    widths: (usize, usize),
    /// The sparse solver's right side (it does not solve in place).
    rhs: Vec<f64>,
    /// X = 0 in the last factorisation: S = [A a; aᵀ s], the algebraic block alone.
    algebraic_only: bool,
    /// The largest |entry| of each P column over the whole matrix, for the pivot test.
    col_max: Vec<f64>,
}

impl SchurSolver {
    /// For matrices with the pattern of `pattern`, whose first `n_p` unknowns (even) are
    /// the blocks and whose last unknown is the border when `border`.
    pub fn new(pattern: &Csr, n_p: usize, border: bool, how: Reduced) -> Result<Self, LinalgError> {
        let n = pattern.n();
        if n > u32::MAX as usize {
            return Err(LinalgError::Singular(format!(
                "{n} unknowns are more than this solver indexes"
            )));
        }
        if !n_p.is_multiple_of(2) || n_p + usize::from(border) > n {
            return Err(LinalgError::Structure(format!(
                "a partition of {n} unknowns into {n_p} block unknowns{}",
                if border { " and a border" } else { "" }
            )));
        }
        let n_w = n - n_p - usize::from(border);
        let mut blocks: Vec<Block> = Vec::with_capacity(n_p / 2);
        for k in 0..n_p / 2 {
            let (mut lo, mut hi) = (usize::MAX, 0usize);
            let mut lower: Vec<usize> = vec![];
            for row in [2 * k, 2 * k + 1] {
                for &c in pattern.row(row).0 {
                    if c < n_p && c / 2 != k {
                        let j = c / 2;
                        if j > k {
                            return Err(LinalgError::Singular(format!(
                                "block {k} reads the later block {j}: the blocks are not in elimination order"
                            )));
                        }
                        lower.push(j);
                    } else if c >= n_p && c < n_p + n_w {
                        lo = lo.min(c - n_p);
                        hi = hi.max(c - n_p + 1);
                    }
                }
            }
            lower.sort_unstable();
            lower.dedup();
            for &j in &lower {
                let b = &blocks[j];
                if b.width > 0 {
                    lo = lo.min(b.lo);
                    hi = hi.max(b.lo + b.width);
                }
            }
            let (lo, width) = if hi == 0 { (0, 0) } else { (lo, hi - lo) };
            blocks.push(Block {
                lower: lower.into_iter().map(|j| (j, [[0.0; 2]; 2])).collect(),
                lo,
                width,
                x: vec![0.0; 2 * width],
                ..Block::default()
            });
        }
        // S's band: A's entries and the fill C X, row by row; each row's first and last
        // column (for the block structure).
        let (mut lower, mut upper) = (0usize, 0usize);
        let mut spans: Vec<Option<(usize, usize)>> = vec![None; n_w];
        for (jw, row_span) in spans.iter_mut().enumerate() {
            for &c in pattern.row(n_p + jw).0 {
                let span = if c < n_p {
                    let b = &blocks[c / 2];
                    (b.width > 0).then(|| (b.lo, b.lo + b.width - 1))
                } else if c < n_p + n_w {
                    Some((c - n_p, c - n_p))
                } else {
                    None
                };
                if let Some((a, b)) = span {
                    lower = lower.max(jw.saturating_sub(a));
                    upper = upper.max(b.saturating_sub(jw));
                    let (lo, hi) = row_span.get_or_insert((a, b));
                    (*lo, *hi) = ((*lo).min(a), (*hi).max(b));
                }
            }
        }
        let reduced = match how {
            Reduced::Band => ReducedSolver::Band {
                bb: BorderedBand::new(n_w, lower, upper, border)?,
                factors: None,
            },
            Reduced::Block => ReducedSolver::Block {
                bb: Bordered::around(block_structure(&spans)?, border),
                factors: None,
                row: vec![0.0; BLOCK_WIDTH * 2],
            },
            Reduced::Sparse(make) => {
                let mut rows: Vec<Vec<usize>> = (0..n_w)
                    .map(|jw| {
                        (jw.saturating_sub(lower)..(jw + upper + 1).min(n_w))
                            .chain(border.then_some(n_w))
                            .collect()
                    })
                    .collect();
                if border {
                    rows.push((0..=n_w).collect());
                }
                let s = Csr::from_rows(rows);
                let solver = make(&s)?;
                let s_rows = vec![0.0; n_w * (lower + upper + 1)];
                let s_border = vec![0.0; n_w];
                ReducedSolver::Sparse {
                    s,
                    s_rows,
                    s_border,
                    solver,
                }
            }
        };
        Ok(SchurSolver {
            n_p,
            n_w,
            border,
            blocks,
            coupling: Coupling::default(),
            reduced,
            widths: (lower, upper),
            rhs: vec![0.0; n_w + 1],
            algebraic_only: false,
            col_max: vec![0.0; n_p],
        })
    }

    /// (lower, upper) bandwidths of the reduced matrix S.
    pub fn widths(&self) -> (usize, usize) {
        self.widths
    }

    /// The size of the reduced system (W and the border).
    fn reduced_len(&self) -> usize {
        self.n_w + usize::from(self.border)
    }

    /// x ← S⁻¹ x, x of the reduced length.
    fn reduced_solve(&mut self, x: &mut [f64]) -> Result<(), LinalgError> {
        match &mut self.reduced {
            ReducedSolver::Band { factors, .. } => factors
                .as_ref()
                .ok_or(LinalgError::NotFactored)?
                .solve_in_place(x),
            ReducedSolver::Block { factors, .. } => factors
                .as_ref()
                .ok_or(LinalgError::NotFactored)?
                .solve_in_place(x),
            ReducedSolver::Sparse { solver, .. } => {
                let rhs = &mut self.rhs[..x.len()];
                rhs.copy_from_slice(x);
                solver.solve(rhs, x)
            }
        }
    }

    /// Block k's D_kk, D_kj and X_k from its two rows of `a`.
    fn eliminate_block(&mut self, a: &Csr, k: usize) -> Result<(), LinalgError> {
        let (n_p, n_w) = (self.n_p, self.n_w);
        let (done, rest) = self.blocks.split_at_mut(k);
        let b = &mut rest[0];
        if self.algebraic_only {
            b.x.fill(0.0);
            b.xd = [0.0; 2];
            return Ok(());
        }
        let mut d = [[0.0; 2]; 2];
        b.x.fill(0.0);
        b.xd = [0.0; 2];
        for (_, m) in b.lower.iter_mut() {
            *m = [[0.0; 2]; 2];
        }
        for r in 0..2 {
            let (cols, vals) = a.row(2 * k + r);
            for (&c, &v) in cols.iter().zip(vals) {
                if c < n_p {
                    let (j, comp) = (c / 2, c % 2);
                    if j == k {
                        d[r][comp] = v;
                    } else if let Some((_, m)) = b.lower.iter_mut().find(|(i, _)| *i == j) {
                        m[r][comp] = v;
                    }
                } else if c < n_p + n_w {
                    b.x[r * b.width + c - n_p - b.lo] = v;
                } else {
                    b.xd[r] = v;
                }
            }
        }
        // [B e]_k − Σ_j D_kj X_j, then D_kk⁻¹ times it.
        for (j, m) in &b.lower {
            let xj = &done[*j];
            let off = xj.lo.wrapping_sub(b.lo);
            for r in 0..2 {
                for s in 0..2 {
                    let f = m[r][s];
                    if f == 0.0 {
                        continue;
                    }
                    for t in 0..xj.width {
                        b.x[r * b.width + off + t] -= f * xj.x[s * xj.width + t];
                    }
                    b.xd[r] -= f * xj.xd[s];
                }
            }
        }
        let det = d[0][0] * d[1][1] - d[0][1] * d[1][0];
        let (m0, m1) = (self.col_max[2 * k], self.col_max[2 * k + 1]);
        if !(det.abs() >= PIVOT_TOLERANCE * m0 * m1 && det != 0.0) {
            return Err(LinalgError::Singular(format!(
                "pivot block {k} has determinant {det:e} against columns of size {m0:e}, {m1:e}: \
                 elimination without pivoting would be unstable"
            )));
        }
        b.inv = [
            [d[1][1] / det, -d[0][1] / det],
            [-d[1][0] / det, d[0][0] / det],
        ];
        let w = b.width;
        for t in 0..w {
            let (x0, x1) = (b.x[t], b.x[w + t]);
            b.x[t] = b.inv[0][0] * x0 + b.inv[0][1] * x1;
            b.x[w + t] = b.inv[1][0] * x0 + b.inv[1][1] * x1;
        }
        let (x0, x1) = (b.xd[0], b.xd[1]);
        b.xd = [
            b.inv[0][0] * x0 + b.inv[0][1] * x1,
            b.inv[1][0] * x0 + b.inv[1][1] * x1,
        ];
        Ok(())
    }

    /// S = [A a; cᵀ s] − C X, written straight into the band LU's rows (for the block LU,
    /// a row at a time into its blocks; for KLU, into dense band rows and then the CSR
    /// matrix); keeps C's entries for the solves.
    fn reduce(&mut self, a: &Csr) -> Result<(), LinalgError> {
        let (n_p, n_w, border) = (self.n_p, self.n_w, self.border);
        let (lower, upper) = self.widths;
        let (blocks, coupling) = (&self.blocks, &mut self.coupling);
        coupling.clear();
        // Row jw keeps W column c at acc[c + off − base]: a band row (off, base) =
        // (lower, jw), a block row (0, its first column), the border row (0, 0).
        let mut reduce_row =
            |jw: usize, acc: &mut [f64], at_d: &mut f64, off: usize, base: usize| {
                acc.fill(0.0);
                *at_d = 0.0;
                let (cols, vals) = a.row(n_p + jw);
                for (&c, &v) in cols.iter().zip(vals) {
                    if c < n_p {
                        if v == 0.0 {
                            continue;
                        }
                        coupling.col.push(c as u32);
                        coupling.val.push(v);
                        let (b, r) = (&blocks[c / 2], c % 2);
                        if b.width > 0 {
                            let at = b.lo + off - base;
                            for (s, x) in acc[at..at + b.width]
                                .iter_mut()
                                .zip(&b.x[r * b.width..(r + 1) * b.width])
                            {
                                *s -= v * x;
                            }
                        }
                        *at_d -= v * b.xd[r];
                    } else if c < n_p + n_w {
                        acc[c - n_p + off - base] += v;
                    } else {
                        *at_d += v;
                    }
                }
                coupling.end.push(coupling.col.len());
            };
        match &mut self.reduced {
            ReducedSolver::Band { bb, .. } => bb.fill_rows(|lu, col, row, corner| {
                // Without a border, the border column's entries (zero) go to a scratch.
                let mut none = 0.0;
                for jw in 0..n_w {
                    let at_d = col.get_mut(jw).unwrap_or(&mut none);
                    reduce_row(jw, lu.row_mut(jw)?, at_d, lower, jw);
                }
                if border {
                    reduce_row(n_w, row, corner, 0, 0);
                }
                Ok(())
            }),
            ReducedSolver::Block { bb, row: acc, .. } => bb.fill_rows(|lu, col, row, corner| {
                let mut none = 0.0;
                for jw in 0..n_w {
                    let (first, len) = lu.row_span(jw)?;
                    let at_d = col.get_mut(jw).unwrap_or(&mut none);
                    reduce_row(jw, &mut acc[..len], at_d, 0, first);
                    lu.set_row(jw, &acc[..len])?;
                }
                if border {
                    reduce_row(n_w, row, corner, 0, 0);
                }
                Ok(())
            }),
            ReducedSolver::Sparse {
                s,
                s_rows,
                s_border,
                ..
            } => {
                let width = lower + upper + 1;
                let mut s_col = 0.0;
                s.zero();
                for (jw, r) in s_rows.chunks_exact_mut(width).enumerate() {
                    reduce_row(jw, r, &mut s_col, lower, jw);
                    let (lo, hi) = (jw.saturating_sub(lower), (jw + upper + 1).min(n_w));
                    s.add_span(jw, lo, &r[lo + lower - jw..hi + lower - jw]);
                    if border {
                        s.add(jw, n_w, s_col);
                    }
                }
                if border {
                    let mut corner = 0.0;
                    reduce_row(n_w, s_border, &mut corner, 0, 0);
                    s.add_span(n_w, 0, s_border);
                    s.add(n_w, n_w, corner);
                }
                match s.take_outside() {
                    0 => Ok(()),
                    k => Err(LinalgError::OutsidePattern(k)),
                }
            }
        }
    }

    /// Factorise only the algebraic block [A a; cᵀ s] (X taken as 0): for the algebraic
    /// derivatives at a consistent start, [A a; cᵀ s] w' = −[C; cᵀ] p'. Solve with
    /// [`SchurSolver::solve_algebraic`].
    pub fn factor_algebraic(&mut self, a: &Csr) -> Result<(), LinalgError> {
        self.algebraic_only = true;
        let r = self.factor_blocks(a);
        self.algebraic_only = false;
        r
    }

    /// w' = −[A a; cᵀ s]⁻¹ [C; cᵀ] p' after [`SchurSolver::factor_algebraic`]; `w` has the
    /// length of W and d together.
    pub fn solve_algebraic(&mut self, p_dot: &[f64], w: &mut [f64]) -> Result<(), LinalgError> {
        self.check_algebraic(p_dot, w.len(), w.len())?;
        let w = &mut w[..self.reduced_len()];
        w.fill(0.0);
        self.coupling.subtract_from(p_dot, w);
        self.reduced_solve(w)
    }

    /// w = −[A a; cᵀ s]⁻¹ ([C; cᵀ] p' + b) after [`SchurSolver::factor_algebraic`]: the
    /// algebraic block's solve with a right side of its own too (the initial forward
    /// sensitivities of parameters that enter the algebraic rows); `b` and `w` have the
    /// length of W and d together.
    pub fn solve_algebraic_with(
        &mut self,
        p_dot: &[f64],
        b: &[f64],
        w: &mut [f64],
    ) -> Result<(), LinalgError> {
        self.check_algebraic(p_dot, b.len(), w.len())?;
        let n = self.reduced_len();
        let w = &mut w[..n];
        for (wi, bi) in w.iter_mut().zip(&b[..n]) {
            *wi = -bi;
        }
        self.coupling.subtract_from(p_dot, w);
        self.reduced_solve(w)
    }

    /// The lengths of an algebraic solve's p', right side and solution: at least P's, and
    /// at least the reduced system's (W and d).
    fn check_algebraic(&self, p_dot: &[f64], b: usize, w: usize) -> Result<(), LinalgError> {
        let n = self.reduced_len();
        if p_dot.len() < self.n_p || b < n || w < n {
            return Err(LinalgError::Length(format!(
                "an algebraic solve with p' of length {} (of at least {}), right side {b} and solution {w} (of at least {n})",
                p_dot.len(),
                self.n_p
            )));
        }
        Ok(())
    }

    /// The largest |entry| of each P column (rows list columns in order, P's first).
    fn measure_columns(&mut self, a: &Csr) {
        let n_p = self.n_p;
        self.col_max.fill(0.0);
        for i in 0..a.n() {
            let (cols, vals) = a.row(i);
            for (&c, &v) in cols.iter().zip(vals) {
                if c >= n_p {
                    break;
                }
                self.col_max[c] = self.col_max[c].max(v.abs());
            }
        }
    }

    fn factor_blocks(&mut self, a: &Csr) -> Result<(), LinalgError> {
        // The last factors are gone whatever happens next: a failure leaves none.
        let (old_band, old_block) = match &mut self.reduced {
            ReducedSolver::Band { factors, .. } => (factors.take(), None),
            ReducedSolver::Block { factors, .. } => (None, factors.take()),
            ReducedSolver::Sparse { .. } => (None, None),
        };
        if a.n() != self.n_p + self.reduced_len() {
            return Err(LinalgError::Length(format!(
                "a matrix of size {} for a solver made for size {}",
                a.n(),
                self.n_p + self.reduced_len()
            )));
        }
        if !self.algebraic_only {
            self.measure_columns(a);
        }
        for k in 0..self.blocks.len() {
            self.eliminate_block(a, k)?;
        }
        self.reduce(a)?;
        match &mut self.reduced {
            ReducedSolver::Band { bb, factors } => {
                *factors = Some(bb.factor_reusing(old_band)?);
                Ok(())
            }
            ReducedSolver::Block { bb, factors, .. } => {
                *factors = Some(bb.factor_reusing(old_block)?);
                Ok(())
            }
            ReducedSolver::Sparse { s, solver, .. } => solver.factor(s),
        }
    }
}

/// Unknowns per node of S for [`Reduced::Block`].
const BLOCK_WIDTH: usize = 6;

/// The almost-block-diagonal matrix whose structure holds S's rows, given each row's first
/// and last column (None: an empty row): the top rows are the leading rows within node 0
/// (the left boundary's conditions), and every row must lie within its row's span in that
/// structure, or S is not of this shape.
fn block_structure(spans: &[Option<(usize, usize)>]) -> Result<AbdLu6, LinalgError> {
    let n = spans.len();
    if n == 0 || !n.is_multiple_of(BLOCK_WIDTH) {
        return Err(LinalgError::Structure(format!(
            "a reduced matrix of size {n} is not made of {BLOCK_WIDTH}-wide nodes"
        )));
    }
    let top = spans
        .iter()
        .take_while(|s| s.is_some_and(|(_, hi)| hi < BLOCK_WIDTH))
        .count()
        .min(BLOCK_WIDTH);
    let abd = AbdLu6::new(n / BLOCK_WIDTH, top)?;
    for (jw, span) in spans.iter().enumerate() {
        let (first, len) = abd.row_span(jw)?;
        if let Some((lo, hi)) = *span {
            if lo < first || hi >= first + len {
                return Err(LinalgError::Structure(format!(
                    "row {jw} of the reduced matrix reaches columns {lo}..={hi}, outside its \
                     block's columns {first}..{} ({top} top rows)",
                    first + len
                )));
            }
        }
    }
    Ok(abd)
}

impl DirectSolver for SchurSolver {
    fn factor(&mut self, a: &Csr) -> Result<(), LinalgError> {
        self.factor_blocks(a)
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        let (n_p, n_w, len) = (self.n_p, self.n_w, self.reduced_len());
        if b.len() != n_p + len || x.len() != n_p + len {
            return Err(LinalgError::Length(format!(
                "right side {} and solution {} for a matrix of size {}",
                b.len(),
                x.len(),
                n_p + len
            )));
        }
        let (z, xw) = x.split_at_mut(n_p);
        let xw = &mut xw[..len];
        // z = D⁻¹ b_P block by block, kept in x_P until x_P is known.
        for (k, blk) in self.blocks.iter().enumerate() {
            let mut t = [b[2 * k], b[2 * k + 1]];
            for (j, m) in &blk.lower {
                let (z0, z1) = (z[2 * j], z[2 * j + 1]);
                t[0] -= m[0][0] * z0 + m[0][1] * z1;
                t[1] -= m[1][0] * z0 + m[1][1] * z1;
            }
            z[2 * k] = blk.inv[0][0] * t[0] + blk.inv[0][1] * t[1];
            z[2 * k + 1] = blk.inv[1][0] * t[0] + blk.inv[1][1] * t[1];
        }
        // The reduced right side, b_W − C z, and S's solve, in place in x_W.
        xw.copy_from_slice(&b[n_p..n_p + len]);
        self.coupling.subtract_from(z, xw);
        self.reduced_solve(xw)?;
        let xd = if self.border { xw[n_w] } else { 0.0 };
        // x_P = z − X x_W − x_d x_d.
        for (k, blk) in self.blocks.iter().enumerate() {
            for r in 0..2 {
                let xr = &blk.x[r * blk.width..(r + 1) * blk.width];
                let dot: f64 = xr
                    .iter()
                    .zip(&xw[blk.lo..blk.lo + blk.width])
                    .map(|(a, b)| a * b)
                    .sum();
                z[2 * k + r] -= dot + blk.xd[r] * xd;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn assert_close(x: &[f64], expect: &[f64], tol: f64, who: &str) {
        for (i, (a, b)) in x.iter().zip(expect).enumerate() {
            assert!((a - b).abs() < tol, "{who} {i}: {a} vs {b}");
        }
    }

    /// A random matrix with the structure of the growth DAE (blocks reading a band window
    /// and earlier blocks, band rows reading blocks, a border), as CSR and dense, with
    /// n_p; block `weak` (if any) has its own 2×2 block scaled by `by`.
    fn structured(weak: Option<(usize, f64)>) -> (Csr, DMatrix<f64>, usize) {
        let (nb, n_w) = (6usize, 10usize);
        let n_p = 2 * nb;
        let n = n_p + n_w + 1;
        let d = n - 1;
        let rnd = |i: usize, j: usize| ((i * 31 + j * 17) as f64 * 0.37).sin();
        // Block k reads W columns 2k.. 2k+3 (clipped), blocks ≥ 3 read block k − 3, and the
        // border; W row j reads W j−2..j+2, the block j/2, and the border row reads all.
        let mut rows: Vec<Vec<usize>> = vec![vec![]; n];
        for k in 0..nb {
            for r in 0..2 {
                let row = &mut rows[2 * k + r];
                row.extend([2 * k, 2 * k + 1, d]);
                row.extend((2 * k..(2 * k + 4).min(n_w)).map(|c| n_p + c));
                if k >= 3 {
                    row.extend([2 * (k - 3), 2 * (k - 3) + 1]);
                }
            }
        }
        for j in 0..n_w {
            rows[n_p + j].extend((j.saturating_sub(2)..(j + 3).min(n_w)).map(|c| n_p + c));
            rows[n_p + j].extend([2 * (j / 2 % nb), 2 * (j / 2 % nb) + 1]);
        }
        rows[d] = (0..n).collect();
        let mut a = Csr::from_rows(rows.clone());
        let mut dense = DMatrix::zeros(n, n);
        for (i, cols) in rows.iter().enumerate() {
            for &j in cols {
                let mut v = if i == j { 8.0 + rnd(i, j) } else { rnd(i, j) };
                if let Some((k, by)) = weak {
                    if i / 2 == k && j / 2 == k && i < n_p && j < n_p {
                        v *= by;
                    }
                }
                if a.get(i, j) == 0.0 {
                    a.add(i, j, v);
                    dense[(i, j)] = v;
                }
            }
        }
        (a, dense, n_p)
    }

    /// The structured matrix against a dense LU, through all three solvers.
    #[test]
    fn schur_matches_dense_on_a_structured_matrix() {
        let (a, dense, n_p) = structured(None);
        let n = a.n();
        let (d, n_w) = (n - 1, n - n_p - 1);
        let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let expect = dense
            .clone()
            .lu()
            .solve(&DVector::from_vec(b.clone()))
            .unwrap();
        let check = |x: &[f64], who: &str| assert_close(x, expect.as_slice(), 1e-12, who);
        let mut x = vec![0.0; n];
        // A sparse solver for S: the interleaved band LU in S's own order, no border.
        let sparse: MakeSparse = |s| {
            let order = (0..s.n()).collect();
            Ok(Box::new(crate::InterleavedBand::new(s, order, None)?))
        };
        for how in [Reduced::Band, Reduced::Sparse(sparse)] {
            let mut schur = SchurSolver::new(&a, n_p, true, how).unwrap();
            schur.factor(&a).unwrap();
            schur.solve(&b, &mut x).unwrap();
            check(&x, &format!("schur {how:?}"));
        }
        let mut schur = SchurSolver::new(&a, n_p, true, Reduced::Band).unwrap();
        let perm: Vec<usize> = (0..n).map(|i| if i == d { 0 } else { i }).collect();
        let mut band = crate::InterleavedBand::new(&a, perm, Some(d)).unwrap();
        band.factor(&a).unwrap();
        band.solve(&b, &mut x).unwrap();
        check(&x, "band");
        // The algebraic block alone: [A a; cᵀ s] w = −C p.
        let p: Vec<f64> = (0..n_p).map(|i| 0.1 * i as f64).collect();
        schur.factor_algebraic(&a).unwrap();
        let mut w = vec![0.0; n_w + 1];
        schur.solve_algebraic(&p, &mut w).unwrap();
        let alg = dense.view((n_p, n_p), (n_w + 1, n_w + 1)).into_owned();
        let cp = dense.view((n_p, 0), (n_w + 1, n_p)) * DVector::from_vec(p);
        let expect_w = alg.lu().solve(&(-cp)).unwrap();
        for i in 0..=n_w {
            assert!(
                (w[i] - expect_w[i]).abs() < 1e-12,
                "algebraic {i}: {} vs {}",
                w[i],
                expect_w[i]
            );
        }
    }

    /// A growth block too small against its columns (its pivots would be below KLU's
    /// threshold) is refused as singular rather than eliminated unstably, and the fallback
    /// solves the matrix with pivoting, to the dense LU's answer.
    #[test]
    fn a_weak_pivot_block_is_refused_and_the_fallback_solves() {
        let (a, dense, n_p) = structured(Some((2, 1e-4)));
        let n = a.n();
        let mut schur = SchurSolver::new(&a, n_p, true, Reduced::Band).unwrap();
        match schur.factor(&a) {
            Err(LinalgError::Singular(why)) => assert!(why.contains("pivot block 2"), "{why}"),
            other => panic!("expected a refused pivot block, got {other:?}"),
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let expect = dense.lu().solve(&DVector::from_vec(b.clone())).unwrap();
        let pattern = a.clone();
        let mut solver = crate::Fallback::new(
            Box::new(SchurSolver::new(&a, n_p, true, Reduced::Band).unwrap()),
            Box::new(move || -> Result<Box<dyn DirectSolver>, LinalgError> {
                let perm: Vec<usize> = (0..pattern.n())
                    .map(|i| if i == pattern.n() - 1 { 0 } else { i })
                    .collect();
                Ok(Box::new(crate::InterleavedBand::new(
                    &pattern,
                    perm,
                    Some(pattern.n() - 1),
                )?))
            }),
        );
        solver.factor(&a).unwrap();
        assert_eq!(solver.fallbacks(), 1);
        let mut x = vec![0.0; n];
        solver.solve(&b, &mut x).unwrap();
        assert_close(&x, expect.as_slice(), 1e-11, "fallback");
        // A well-scaled matrix goes back to the fast path.
        let (good, dense, _) = structured(None);
        solver.factor(&good).unwrap();
        assert_eq!(solver.fallbacks(), 1);
        solver.solve(&b, &mut x).unwrap();
        let expect = dense.lu().solve(&DVector::from_vec(b)).unwrap();
        assert_close(&x, expect.as_slice(), 1e-12, "fast path again");
    }

    /// Values in [−1, 1) (xorshift).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    /// A random matrix with the growth DAE's pattern (`growth/dae.rs`): m nodes of 6 W
    /// unknowns; a growth point per node, two at the nodes in `jumps` (from below and from
    /// above) and, for Hermite–Simpson, one per interval midpoint numbered after the
    /// nodes' (reading its interval's window and its end points); 3 pole rows reading node
    /// 0 and its point, 6 rows per interval reading both nodes and the interval's points, 3
    /// cornea rows; with `border`, the unknown d read by every point and a dense row. The
    /// point blocks are c I − (random), the interval blocks [−I − hR | I − hR] with their
    /// rows shuffled (pivots off the diagonal). Returns the CSR, the dense matrix and n_p.
    fn dae_like(
        m: usize,
        hermite_simpson: bool,
        jumps: &[usize],
        border: bool,
        seed: u64,
    ) -> (Csr, DMatrix<f64>, usize) {
        let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
        // Each point's site: (node it reads, or the interval of a midpoint).
        enum Site {
            Node(usize),
            Mid(usize),
        }
        let (mut sites, mut below, mut above) = (vec![], vec![], vec![]);
        for i in 0..m {
            sites.push(Site::Node(i));
            below.push(sites.len() - 1);
            if jumps.contains(&i) && i > 0 && i < m - 1 {
                sites.push(Site::Node(i));
            }
            above.push(sites.len() - 1);
        }
        let mut mid = vec![];
        if hermite_simpson {
            for i in 0..m - 1 {
                sites.push(Site::Mid(i));
                mid.push(sites.len() - 1);
            }
        }
        let n_p = 2 * sites.len();
        let n_w = 6 * m;
        let n = n_p + n_w + usize::from(border);
        let wcols = |i: usize| (n_p + 6 * i..n_p + 6 * i + 6).collect::<Vec<_>>();
        let pcols = |k: usize| vec![2 * k, 2 * k + 1];
        let window = |i: usize| {
            let mut c = wcols(i);
            c.extend(wcols(i + 1));
            c.extend(pcols(above[i]));
            c.extend(pcols(below[i + 1]));
            if hermite_simpson {
                c.extend(pcols(mid[i]));
            }
            c
        };
        let mut a = DMatrix::zeros(n, n);
        for (k, site) in sites.iter().enumerate() {
            let cols = match *site {
                Site::Node(i) => wcols(i),
                Site::Mid(i) => window(i),
            };
            for r in 2 * k..2 * k + 2 {
                for &c in &cols {
                    a[(r, c)] = 0.5 * rng.next();
                }
                for c in 2 * k..2 * k + 2 {
                    a[(r, c)] = rng.next() + if r == c { 50.0 } else { 0.0 };
                }
                if border {
                    a[(r, n - 1)] = 0.3 * rng.next();
                }
            }
        }
        let h = 1.0 / m as f64;
        for r in 0..3 {
            let row = n_p + r;
            for c in wcols(0).into_iter().chain(pcols(above[0])) {
                a[(row, c)] = rng.next();
            }
        }
        for i in 0..m - 1 {
            let mut order: Vec<usize> = (0..6).collect();
            for r in (1..6).rev() {
                let q = (((rng.next() + 1.0) * 0.5 * (r + 1) as f64) as usize).min(r);
                order.swap(r, q);
            }
            for (a_row, &r) in order.iter().enumerate() {
                let row = n_p + 3 + 6 * i + r;
                for c in window(i) {
                    let v = rng.next();
                    let w = c.wrapping_sub(n_p);
                    a[(row, c)] = if c < n_p {
                        0.2 * v
                    } else if w == 6 * i + a_row {
                        -1.0 - h * v
                    } else if w == 6 * (i + 1) + a_row {
                        1.0 - h * v
                    } else {
                        -h * v
                    };
                }
            }
        }
        for r in 0..3 {
            let row = n_p + n_w - 3 + r;
            for c in wcols(m - 1) {
                a[(row, c)] = rng.next()
                    + if c == n_p + 6 * (m - 1) + 3 + r {
                        2.0
                    } else {
                        0.0
                    };
            }
        }
        if border {
            for c in 0..n {
                a[(n - 1, c)] = 0.1 * rng.next();
            }
            a[(n - 1, n - 1)] = 1.0;
        }
        let rows: Vec<Vec<usize>> = (0..n)
            .map(|i| (0..n).filter(|&j| a[(i, j)] != 0.0).collect())
            .collect();
        let mut csr = Csr::from_rows(rows);
        for i in 0..n {
            for j in 0..n {
                if a[(i, j)] != 0.0 {
                    csr.add(i, j, a[(i, j)]);
                }
            }
        }
        (csr, a, n_p)
    }

    /// Reduced::Block on a DAE-like matrix against nalgebra's dense LU: the relative
    /// residual max|Ax − b| / (max|A| max|x| + max|b|), which must be ≤ 1e-13, and the
    /// largest difference from the dense solution relative to its size.
    fn block_against_dense(a: &Csr, dense: &DMatrix<f64>, n_p: usize, border: bool) -> (f64, f64) {
        let n = a.n();
        let mut schur = SchurSolver::new(a, n_p, border, Reduced::Block).unwrap();
        schur.factor(a).unwrap();
        let b: Vec<f64> = (0..n).map(|i| (0.7 * i as f64 + 0.3).sin()).collect();
        let mut x = vec![0.0; n];
        schur.solve(&b, &mut x).unwrap();
        let (xv, bv) = (
            DVector::from_column_slice(&x),
            DVector::from_column_slice(&b),
        );
        let res = (dense * &xv - &bv).amax() / (dense.amax() * xv.amax() + bv.amax());
        let expect = dense.clone().lu().solve(&bv).unwrap();
        let diff = (&xv - &expect).amax() / expect.amax();
        (res, diff)
    }

    /// Every shape the schemes produce: trapezoid and Hermite–Simpson, with and without
    /// jump nodes (two growth points), with and without the border, 2 to 60 nodes.
    #[test]
    fn block_reduced_solver_on_the_dae_structure() {
        for hs in [false, true] {
            for border in [true, false] {
                for (m, jumps) in [
                    (2, vec![]),
                    (3, vec![1]),
                    (12, vec![4, 7]),
                    (60, vec![20, 21, 40]),
                ] {
                    for seed in 0..3 {
                        let (a, dense, n_p) = dae_like(m, hs, &jumps, border, seed);
                        let (res, diff) = block_against_dense(&a, &dense, n_p, border);
                        let what = format!(
                            "HS {hs}, border {border}, {m} nodes, jumps {jumps:?}, seed {seed}"
                        );
                        assert!(res <= 1e-13 && res > 0.0, "{what}: residual {res:e}");
                        assert!(diff <= 1e-11, "{what}: {diff:e} from the dense solution");
                    }
                }
            }
        }
    }

    /// A pattern that is not almost block diagonal (a pole row reaching node 2) is refused
    /// by the block path with the row named, not factored wrongly.
    #[test]
    fn a_pattern_outside_the_block_structure_is_refused() {
        let (a, _, n_p) = dae_like(4, false, &[], true, 1);
        let mut rows: Vec<Vec<usize>> = (0..a.n()).map(|i| a.row(i).0.to_vec()).collect();
        rows[n_p + 1].push(n_p + 12);
        rows[n_p + 1].sort_unstable();
        match SchurSolver::new(&Csr::from_rows(rows), n_p, true, Reduced::Block) {
            Err(LinalgError::Structure(why)) => assert!(why.contains("row 1 "), "{why}"),
            Err(e) => panic!("expected a structure error, got {e}"),
            Ok(_) => panic!("expected a structure error"),
        }
    }

    /// A singular reduced matrix (two cornea rows equal) is reported singular by the block
    /// path, and the fallback's pivoting solver cannot solve it either.
    #[test]
    fn a_singular_reduced_matrix_is_reported() {
        let (a, dense, n_p) = dae_like(8, true, &[3], true, 4);
        let n = a.n();
        let (r1, r2) = (n - 1 - 3, n - 1 - 2);
        let rows: Vec<Vec<usize>> = (0..n).map(|i| a.row(i).0.to_vec()).collect();
        let mut s = Csr::from_rows(rows);
        for i in 0..n {
            let src = if i == r2 { r1 } else { i };
            for j in 0..n {
                if dense[(src, j)] != 0.0 {
                    s.add(i, j, dense[(src, j)]);
                }
            }
        }
        let mut schur = SchurSolver::new(&s, n_p, true, Reduced::Block).unwrap();
        match schur.factor(&s) {
            Err(LinalgError::Singular(why)) => assert!(why.contains("block LU"), "{why}"),
            other => panic!("expected singular, got {other:?}"),
        }
        let mut x = vec![0.0; n];
        assert!(matches!(
            schur.solve(&vec![1.0; n], &mut x),
            Err(LinalgError::NotFactored)
        ));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

        /// Sizes, schemes, jump nodes, border and values at random: residual ≤ 1e-13.
        #[test]
        fn block_reduced_solver_proptest(
            m in 2usize..80,
            hs in proptest::bool::ANY,
            border in proptest::bool::ANY,
            jump_seed in 0u64..1000,
            seed in 0u64..1_000_000,
        ) {
            let jumps: Vec<usize> = (1..m.saturating_sub(1))
                .filter(|i| (jump_seed >> (i % 10)) & 1 == 1 && i % 3 == 0)
                .collect();
            let (a, dense, n_p) = dae_like(m, hs, &jumps, border, seed);
            let (res, _) = block_against_dense(&a, &dense, n_p, border);
            proptest::prop_assert!(res <= 1e-13, "residual {:e}", res);
        }
    }
}
