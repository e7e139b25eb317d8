//! LU of almost-block-diagonal (ABD) matrices with 5×5 node blocks, in safe Rust: the
//! Jacobians of the shell's finite-difference BVP (docs/MODEL.md §3), where each interval's
//! five equations couple the unknowns of two neighbouring nodes and the boundary conditions
//! sit at the two ends.
//!
//! Structure (M nodes, n = 5M unknowns, p rows at the start, 5 − p at the end):
//!
//! ```text
//!   rows 0..p          columns 0..5                  (pole: p = 3 for the shell)
//!   rows p+5k..p+5k+5  columns 5k..5k+10, k < M − 1   (interval k: nodes k and k+1)
//!   rows n−(5−p)..n    columns n−5..n                (cornea: 2 rows for the shell)
//! ```
//!
//! Breakpoint and jump nodes add no rows or unknowns (their data only enter the values), so
//! the trapezoid and Hermite–Simpson schemes, graded or not, all produce this one shape.
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
//! max |U| / max |A| of the last factorisation is kept ([`AbdLu::growth`]) as a diagnostic.
//!
//! # Storage
//!
//! The assembled matrix and the factors are kept apart: the assembler's blocks are never
//! overwritten by a factorisation, so an assembler that writes the same entries every time
//! (the discretisation writes every entry of every interval block) needs no zeroing between
//! Jacobians ([`AbdLu::zero_boundary`] clears only the boundary rows, whose entries are set
//! sparsely). Each stage's factors are one 10×10 row-major array (rows 0..p+5 used): the
//! multipliers below the diagonal of columns 0..5, U above, the pivots' reciprocals apart.

use super::LinalgError;
use crate::MatrixSink;

/// Unknowns per node: the size of a diagonal block.
pub const NODE: usize = 5;
/// Columns of an interval's block (two nodes).
const WIDE: usize = 2 * NODE;
/// A pivot at most this much of its column's largest original entry counts as singular.
const PIVOT_TOLERANCE: f64 = 1e-14;

type Row = [f64; WIDE];

/// An almost-block-diagonal matrix (see the module docs) and, after [`AbdLu::factor`], its
/// LU factors.
#[derive(Clone, Debug)]
pub struct AbdLu {
    nodes: usize,
    top: usize,
    /// The top rows over columns 0..5.
    top_rows: Vec<[f64; NODE]>,
    /// Interval k's rows over columns 5k..5k+10.
    blocks: Vec<[Row; NODE]>,
    /// The bottom rows over the last five columns.
    bottom_rows: Vec<[f64; NODE]>,
    /// Stage k's working block after elimination: rows 0..p+5 (0..5 at the last stage).
    lu: Vec<[Row; WIDE]>,
    /// Stage k: the row exchanged with row c at step c (full-row swaps, as LAPACK's getrf).
    piv: Vec<[u8; NODE]>,
    /// Stage k: 1 / U_cc.
    inv_diag: Vec<[f64; NODE]>,
    growth: f64,
    outside: usize,
    factored: bool,
}

impl AbdLu {
    /// A zero ABD matrix of `nodes` nodes (n = 5 · nodes) with `top` rows at the start
    /// (0 ≤ top ≤ 5) and 5 − top at the end.
    pub fn new(nodes: usize, top: usize) -> Result<Self, LinalgError> {
        if nodes == 0 || top > NODE {
            return Err(LinalgError::Size(format!(
                "almost-block-diagonal matrix of {nodes} nodes with {top} top rows (need ≥ 1 node and ≤ {NODE} top rows)"
            )));
        }
        // Each stage stores about 1.7 kB; more than 2^24 nodes (28 GB) is a caller's mistake.
        if nodes > 1 << 24 {
            return Err(LinalgError::Size(format!(
                "almost-block-diagonal matrix of {nodes} nodes"
            )));
        }
        Ok(AbdLu {
            nodes,
            top,
            top_rows: vec![[0.0; NODE]; top],
            blocks: vec![[[0.0; WIDE]; NODE]; nodes - 1],
            bottom_rows: vec![[0.0; NODE]; NODE - top],
            lu: vec![[[0.0; WIDE]; WIDE]; nodes],
            piv: vec![[0; NODE]; nodes],
            inv_diag: vec![[0.0; NODE]; nodes],
            growth: 0.0,
            outside: 0,
            factored: false,
        })
    }

    /// n = 5 · nodes.
    pub fn size(&self) -> usize {
        NODE * self.nodes
    }

    pub fn nodes(&self) -> usize {
        self.nodes
    }

    /// Rows at the start (the rest of the boundary rows, 5 − top, are at the end).
    pub fn top(&self) -> usize {
        self.top
    }

    /// Set every entry to zero (and forget the factors).
    pub fn zero(&mut self) {
        self.zero_boundary();
        for b in &mut self.blocks {
            *b = [[0.0; WIDE]; NODE];
        }
    }

    /// Zero the boundary rows only: enough between Jacobians when the assembler writes
    /// every entry of every interval block (see the module docs).
    pub fn zero_boundary(&mut self) {
        self.top_rows.fill([0.0; NODE]);
        self.bottom_rows.fill([0.0; NODE]);
        self.factored = false;
    }

    /// Fill every interval block with NaN: an assembler that leaves an entry unwritten then
    /// makes [`AbdLu::factor`] fail instead of using a stale value (for debug builds and
    /// tests of assemblers that rely on [`AbdLu::zero_boundary`]).
    pub fn poison_blocks(&mut self) {
        for b in &mut self.blocks {
            *b = [[f64::NAN; WIDE]; NODE];
        }
        self.factored = false;
    }

    /// Where (i, j) is stored: (which part, index of the row in it, column in the row).
    #[inline]
    fn locate(&self, i: usize, j: usize) -> Option<(Part, usize, usize)> {
        let n = self.size();
        let p = self.top;
        if i < p {
            (j < NODE).then_some((Part::Top, i, j))
        } else if i >= n - (NODE - p) {
            (i < n && j >= n - NODE && j < n)
                .then(|| (Part::Bottom, i + NODE - p - n, j + NODE - n))
        } else {
            let k = (i - p) / NODE;
            let c0 = NODE * k;
            (j >= c0 && j < c0 + WIDE).then_some((Part::Block(k), (i - p) % NODE, j - c0))
        }
    }

    /// The entry (i, j) as set (before factoring); zero outside the structure.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        match self.locate(i, j) {
            Some((Part::Top, a, b)) => self.top_rows[a][b],
            Some((Part::Bottom, a, b)) => self.bottom_rows[a][b],
            Some((Part::Block(k), a, b)) => self.blocks[k][a][b],
            None => 0.0,
        }
    }

    /// Interval k's block: its five rows over columns 5k..5k+10, to be written whole.
    pub fn block_mut(&mut self, k: usize) -> &mut [[f64; WIDE]; NODE] {
        self.factored = false;
        &mut self.blocks[k]
    }

    /// The number of writes outside the structure since the last call, and reset it.
    pub fn take_outside(&mut self) -> usize {
        std::mem::take(&mut self.outside)
    }

    /// Whether [`AbdLu::factor`] succeeded since the matrix was last written.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// The growth factor max |U| / max |A| of the last successful factorisation.
    pub fn growth(&self) -> f64 {
        self.growth
    }

    /// Factorise the matrix as set: P A = L U by Gaussian elimination with partial pivoting,
    /// stage by stage (module docs). A pivot of zero or at most 1e-14 of its column's
    /// largest original entry, or a non-finite entry, is [`LinalgError::Singular`].
    pub fn factor(&mut self) -> Result<(), LinalgError> {
        self.factored = false;
        let (m, p) = (self.nodes, self.top);
        let mut a_max = 0.0f64;
        let mut u_max = 0.0f64;
        // The rows carried into the next stage (their columns there are 0..5).
        let mut carry = [[0.0; NODE]; NODE];
        carry[..p].copy_from_slice(&self.top_rows);
        // Largest original |entry| of the stage's columns seen so far (from the rows above).
        let mut col_max = [0.0f64; NODE];
        for row in &self.top_rows {
            for c in 0..NODE {
                col_max[c] = col_max[c].max(row[c].abs());
            }
        }
        for k in 0..m {
            let last = k == m - 1;
            let (rows, cols) = if last { (NODE, NODE) } else { (p + NODE, WIDE) };
            let w = &mut self.lu[k];
            for r in 0..p {
                w[r][..NODE].copy_from_slice(&carry[r]);
                w[r][NODE..].fill(0.0);
            }
            let mut next_max = [0.0f64; NODE];
            if last {
                for (a, row) in self.bottom_rows.iter().enumerate() {
                    w[p + a][..NODE].copy_from_slice(row);
                    w[p + a][NODE..].fill(0.0);
                    for c in 0..NODE {
                        col_max[c] = col_max[c].max(row[c].abs());
                    }
                }
            } else {
                for (a, row) in self.blocks[k].iter().enumerate() {
                    w[p + a] = *row;
                    for c in 0..NODE {
                        col_max[c] = col_max[c].max(row[c].abs());
                        next_max[c] = next_max[c].max(row[NODE + c].abs());
                    }
                }
            }
            let stage_max = col_max.iter().fold(0.0f64, |x, &y| x.max(y));
            if !stage_max.is_finite() || w[..rows].iter().flatten().any(|v| !v.is_finite()) {
                return Err(LinalgError::Singular(format!(
                    "block LU: node {k}'s rows hold a non-finite entry"
                )));
            }
            a_max = a_max.max(stage_max);
            for c in 0..NODE {
                let (mut best_row, mut best) = (c, w[c][c].abs());
                for r in c + 1..rows {
                    let v = w[r][c].abs();
                    if v > best {
                        (best_row, best) = (r, v);
                    }
                }
                let scale = col_max[c];
                if !(best > PIVOT_TOLERANCE * scale) {
                    let col = NODE * k + c;
                    return Err(LinalgError::Singular(if best == 0.0 {
                        format!(
                            "block LU: column {col} (node {k}, unknown {c}) has no nonzero pivot"
                        )
                    } else {
                        format!(
                            "block LU: column {col} (node {k}, unknown {c}): pivot {best:e} is below {PIVOT_TOLERANCE:e} of the column's scale {scale:e}"
                        )
                    }));
                }
                self.piv[k][c] = best_row as u8;
                w.swap(c, best_row);
                let pivot_row = w[c];
                let inv = 1.0 / pivot_row[c];
                self.inv_diag[k][c] = inv;
                for row in &mut w[c + 1..rows] {
                    let l = row[c] * inv;
                    row[c] = l;
                    if l != 0.0 {
                        for j in c + 1..cols {
                            row[j] -= l * pivot_row[j];
                        }
                    }
                }
            }
            for row in &w[..NODE] {
                for v in &row[..cols] {
                    u_max = u_max.max(v.abs());
                }
            }
            if !last {
                for r in 0..p {
                    carry[r].copy_from_slice(&w[NODE + r][NODE..]);
                }
                col_max = next_max;
            }
        }
        self.growth = if a_max > 0.0 { u_max / a_max } else { 0.0 };
        self.factored = true;
        Ok(())
    }

    /// b ← A⁻¹ b with the factors of the last [`AbdLu::factor`], which must have succeeded
    /// since the matrix was last written ([`AbdLu::is_factored`]): panics otherwise, or if
    /// b's length is not n. The factors are not changed: any number of right sides.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let (m, p) = (self.nodes, self.top);
        assert!(self.factored, "block LU solve without a successful factor");
        assert_eq!(
            b.len(),
            self.size(),
            "right side of length {} for size {}",
            b.len(),
            self.size()
        );
        // Forward: stage k reads its rows' right sides (carried ones and interval k's, which
        // start at p + 5k ≥ 5k) and leaves y_k at 5k..5k+5: in place, read before written.
        let mut carry = [0.0; NODE];
        carry[..p].copy_from_slice(&b[..p]);
        for k in 0..m {
            let rows = if k == m - 1 { NODE } else { p + NODE };
            let (w, piv) = (&self.lu[k], &self.piv[k]);
            let mut y = [0.0; WIDE];
            y[..p].copy_from_slice(&carry[..p]);
            let at = p + NODE * k;
            y[p..rows].copy_from_slice(&b[at..at + rows - p]);
            for c in 0..NODE {
                y.swap(c, piv[c] as usize);
            }
            for c in 0..NODE {
                let t = y[c];
                for r in c + 1..rows {
                    y[r] -= w[r][c] * t;
                }
            }
            b[NODE * k..NODE * k + NODE].copy_from_slice(&y[..NODE]);
            carry[..p].copy_from_slice(&y[NODE..NODE + p]);
        }
        // Back: x_k = U₁₁⁻¹ (y_k − U₁₂ x_{k+1}).
        let mut next = [0.0; NODE];
        for k in (0..m).rev() {
            let w = &self.lu[k];
            let mut y = [0.0; NODE];
            y.copy_from_slice(&b[NODE * k..NODE * k + NODE]);
            if k < m - 1 {
                for a in 0..NODE {
                    let mut s = 0.0;
                    for j in 0..NODE {
                        s += w[a][NODE + j] * next[j];
                    }
                    y[a] -= s;
                }
            }
            for c in (0..NODE).rev() {
                let mut s = y[c];
                for j in c + 1..NODE {
                    s -= w[c][j] * y[j];
                }
                y[c] = s * self.inv_diag[k][c];
            }
            b[NODE * k..NODE * k + NODE].copy_from_slice(&y);
            next = y;
        }
    }

    /// x = A⁻¹ b (see [`AbdLu::solve_in_place`]); `NotFactored` without a factorisation.
    pub fn solve(&self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        if !self.factored {
            return Err(LinalgError::NotFactored);
        }
        if b.len() != self.size() || x.len() != self.size() {
            return Err(LinalgError::Size(format!(
                "right side {} and solution {} for a matrix of size {}",
                b.len(),
                x.len(),
                self.size()
            )));
        }
        x.copy_from_slice(b);
        self.solve_in_place(x);
        Ok(())
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

#[derive(Clone, Copy)]
enum Part {
    Top,
    Bottom,
    Block(usize),
}

/// The assembler's view: `set` overwrites an entry of the structure; outside it the write
/// is counted (see [`AbdLu::take_outside`]) and debug builds panic.
impl MatrixSink for AbdLu {
    fn nrows(&self) -> usize {
        self.size()
    }

    #[inline]
    fn set(&mut self, i: usize, j: usize, v: f64) {
        self.factored = false;
        match self.locate(i, j) {
            Some((Part::Top, a, b)) => self.top_rows[a][b] = v,
            Some((Part::Bottom, a, b)) => self.bottom_rows[a][b] = v,
            Some((Part::Block(k), a, b)) => self.blocks[k][a][b] = v,
            None => self.count_outside(i, j),
        }
    }

    /// An interval's whole 5×10 block (rows p + 5k.., columns 5k..) is one copy; anything
    /// else goes entry by entry.
    #[inline]
    fn set_block(&mut self, row0: usize, col0: usize, ncols: usize, values: &[f64]) {
        let p = self.top;
        if ncols == WIDE
            && values.len() == NODE * WIDE
            && row0 >= p
            && (row0 - p) % NODE == 0
            && col0 == row0 - p
            && (row0 - p) / NODE < self.blocks.len()
        {
            self.factored = false;
            let block = &mut self.blocks[(row0 - p) / NODE];
            for (dst, src) in block.iter_mut().zip(values.chunks_exact(WIDE)) {
                dst.copy_from_slice(src);
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
