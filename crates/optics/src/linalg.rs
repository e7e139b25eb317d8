//! The few dense solves the optics needs (least squares with a handful of unknowns).

/// Solves the square system `a x = b` by Gaussian elimination with partial pivoting; `None`
/// when it is singular to working precision.
pub(crate) fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(scale > 0.0) || !scale.is_finite() {
        return None;
    }
    for k in 0..N {
        let p = (k..N).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if !(a[p][k].abs() > 1e-14 * scale) {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..N {
            let f = a[i][k] / a[k][k];
            for j in k..N {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; N];
    for k in (0..N).rev() {
        let s: f64 = (k + 1..N).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Least squares `min |A x − b|` through the normal equations of the column-scaled matrix
/// (the unknowns here are few and well separated, so this is accurate enough).
pub(crate) fn least_squares<const N: usize>(rows: &[[f64; N]], rhs: &[f64]) -> Option<[f64; N]> {
    let mut scale = [0.0_f64; N];
    for r in rows {
        for j in 0..N {
            scale[j] = scale[j].max(r[j].abs());
        }
    }
    if scale.iter().any(|s| !(*s > 0.0)) {
        return None;
    }
    let mut m = [[0.0; N]; N];
    let mut v = [0.0; N];
    for (r, &b) in rows.iter().zip(rhs) {
        let s: [f64; N] = std::array::from_fn(|j| r[j] / scale[j]);
        for i in 0..N {
            v[i] += s[i] * b;
            for j in 0..N {
                m[i][j] += s[i] * s[j];
            }
        }
    }
    let x = solve(m, v)?;
    Some(std::array::from_fn(|j| x[j] / scale[j]))
}

/// [`least_squares`] with as many unknowns as each row has, for `K` right-hand sides at
/// once: the Zernike fits of the Strehl sum, whose terms the pupil's rings and spokes make
/// (near) orthogonal, so the normal equations are well conditioned.
pub(crate) fn least_squares_dyn<const K: usize>(
    rows: &[Vec<f64>],
    rhs: [&[f64]; K],
) -> Option<[Vec<f64>; K]> {
    let n = rows.first()?.len();
    let mut scale = vec![0.0_f64; n];
    for r in rows {
        for (s, v) in scale.iter_mut().zip(r) {
            *s = s.max(v.abs());
        }
    }
    if scale.iter().any(|s| !(*s > 0.0)) {
        return None;
    }
    let mut m = vec![vec![0.0; n]; n];
    let mut v: [Vec<f64>; K] = std::array::from_fn(|_| vec![0.0; n]);
    for (k, r) in rows.iter().enumerate() {
        let s: Vec<f64> = r.iter().zip(&scale).map(|(a, c)| a / c).collect();
        for i in 0..n {
            for (vk, b) in v.iter_mut().zip(&rhs) {
                vk[i] += s[i] * b[k];
            }
            for j in i..n {
                m[i][j] += s[i] * s[j];
            }
        }
    }
    for i in 0..n {
        for j in 0..i {
            m[i][j] = m[j][i];
        }
    }
    let mut out: [Vec<f64>; K] = std::array::from_fn(|_| Vec::new());
    for (o, vk) in out.iter_mut().zip(v) {
        let x = solve_dyn(m.clone(), vk)?;
        *o = x.iter().zip(&scale).map(|(a, c)| a / c).collect();
    }
    Some(out)
}

/// [`solve`] for a square system of any size.
fn solve_dyn(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(scale > 0.0) || !scale.is_finite() {
        return None;
    }
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if !(a[p][k].abs() > 1e-14 * scale) {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}
