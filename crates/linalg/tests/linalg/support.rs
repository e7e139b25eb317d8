//! Shared by the test modules: a dense matrix written into a sink, and the residual a
//! solution is judged by.

/// Every nonzero of the dense `a` set into `sink` (a band or block matrix under test).
pub fn fill_from_dense<S: eyeshell_linalg::MatrixSink>(sink: &mut S, a: &nalgebra::DMatrix<f64>) {
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            if a[(i, j)] != 0.0 {
                sink.set(i, j, a[(i, j)]);
            }
        }
    }
}

/// ‖A x − b‖ / (‖A‖ ‖x‖ + ‖b‖), infinity norms.
pub fn relative_residual(a: &nalgebra::DMatrix<f64>, x: &[f64], b: &[f64]) -> f64 {
    let x = nalgebra::DVector::from_column_slice(x);
    let b = nalgebra::DVector::from_column_slice(b);
    let r = a * &x - &b;
    let norm_a = a.row_iter().map(|r| r.abs().sum()).fold(0.0, f64::max);
    r.amax() / (norm_a * x.amax() + b.amax())
}
