//! Rust kernels for the hot operations of SUNDIALS' serial vectors, installed into a
//! vector's operation table ([`install`]) so that an integrator's work vectors, cloned from
//! it, use them too.
//!
//! Why: Debian's libsundials_nvecserial runs these loops at 3–7 ns an element (measured on
//! 5059 elements: N_VLinearSum 17 µs, N_VWrmsNormMask 36 µs), against 0.5 ns for the same
//! loop compiled here. IDA on the coupled growth DAE makes some forty such passes a step,
//! which made them a quarter of its run time. The kernels compute the same expressions as
//! SUNDIALS' (`a x + b y`, `√(Σ (x w)² / n)`, …); the norms sum in four lanes, so they
//! differ from SUNDIALS' in the last bits.
//!
//! Aliasing: SUNDIALS passes the same vector as input and output (`z = a x + b z`), so the
//! kernels work on raw pointers element by element and never form overlapping slices.

use std::os::raw::c_int;

use sundials_sys::{realtype, N_VGetArrayPointer_Serial, N_VGetLength_Serial, N_Vector};

/// The data pointer and length of a serial vector.
///
/// # Safety
/// `v` must be a live serial vector.
#[inline]
unsafe fn parts(v: N_Vector) -> (*mut f64, usize) {
    (
        N_VGetArrayPointer_Serial(v),
        N_VGetLength_Serial(v).max(0) as usize,
    )
}

/// Elements a block at a time in the loops below: a block's inputs are all read into locals
/// before its outputs are written, so that the loops vectorise whatever aliases what (z may
/// be x or y), and every element is computed by the same expression as alone.
const LANES: usize = 4;

/// z_i = f(x_i, y_i) for i < n, [`LANES`] elements at a time.
///
/// # Safety
/// `xp`, `yp` and `zp` must each address n live elements (they may be the same).
#[inline(always)]
unsafe fn map2(
    n: usize,
    xp: *const f64,
    yp: *const f64,
    zp: *mut f64,
    f: impl Fn(f64, f64) -> f64,
) {
    let blocks = n / LANES;
    for b in 0..blocks {
        let i = b * LANES;
        let (mut x, mut y) = ([0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            x[l] = *xp.add(i + l);
            y[l] = *yp.add(i + l);
        }
        for l in 0..LANES {
            *zp.add(i + l) = f(x[l], y[l]);
        }
    }
    for i in blocks * LANES..n {
        *zp.add(i) = f(*xp.add(i), *yp.add(i));
    }
}

/// z = a x + b y.
unsafe extern "C" fn linear_sum(a: realtype, x: N_Vector, b: realtype, y: N_Vector, z: N_Vector) {
    let ((xp, n), (yp, _), (zp, _)) = (parts(x), parts(y), parts(z));
    map2(n, xp, yp, zp, |x, y| a * x + b * y);
}

/// z = c x.
unsafe extern "C" fn scale(c: realtype, x: N_Vector, z: N_Vector) {
    let ((xp, n), (zp, _)) = (parts(x), parts(z));
    map2(n, xp, xp, zp, |x, _| c * x);
}

/// z = c.
unsafe extern "C" fn constant(c: realtype, z: N_Vector) {
    let (zp, n) = parts(z);
    for i in 0..n {
        *zp.add(i) = c;
    }
}

/// z = x y, elementwise.
unsafe extern "C" fn prod(x: N_Vector, y: N_Vector, z: N_Vector) {
    let ((xp, n), (yp, _), (zp, _)) = (parts(x), parts(y), parts(z));
    for i in 0..n {
        *zp.add(i) = *xp.add(i) * *yp.add(i);
    }
}

/// z = x / y, elementwise.
unsafe extern "C" fn div(x: N_Vector, y: N_Vector, z: N_Vector) {
    let ((xp, n), (yp, _), (zp, _)) = (parts(x), parts(y), parts(z));
    for i in 0..n {
        *zp.add(i) = *xp.add(i) / *yp.add(i);
    }
}

/// z = |x|.
unsafe extern "C" fn abs(x: N_Vector, z: N_Vector) {
    let ((xp, n), (zp, _)) = (parts(x), parts(z));
    for i in 0..n {
        *zp.add(i) = (*xp.add(i)).abs();
    }
}

/// z = 1 / x.
unsafe extern "C" fn inv(x: N_Vector, z: N_Vector) {
    let ((xp, n), (zp, _)) = (parts(x), parts(z));
    for i in 0..n {
        *zp.add(i) = 1.0 / *xp.add(i);
    }
}

/// z = x + b.
unsafe extern "C" fn add_const(x: N_Vector, b: realtype, z: N_Vector) {
    let ((xp, n), (zp, _)) = (parts(x), parts(z));
    for i in 0..n {
        *zp.add(i) = *xp.add(i) + b;
    }
}

/// Σ (x w)² over the elements where `keep` holds, in four lanes.
#[inline]
unsafe fn weighted_squares(
    xp: *const f64,
    wp: *const f64,
    n: usize,
    keep: impl Fn(usize) -> bool,
) -> f64 {
    let mut lanes = [0.0f64; 4];
    let full = n / 4 * 4;
    for i in (0..full).step_by(4) {
        for (l, lane) in lanes.iter_mut().enumerate() {
            let k = i + l;
            let p = *xp.add(k) * *wp.add(k);
            *lane += if keep(k) { p * p } else { 0.0 };
        }
    }
    for k in full..n {
        let p = *xp.add(k) * *wp.add(k);
        lanes[0] += if keep(k) { p * p } else { 0.0 };
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// Σ (x w)².
unsafe extern "C" fn wsqrsum(x: N_Vector, w: N_Vector) -> realtype {
    let ((xp, n), (wp, _)) = (parts(x), parts(w));
    weighted_squares(xp, wp, n, |_| true)
}

/// Σ (x w)² over id > 0.
unsafe extern "C" fn wsqrsum_mask(x: N_Vector, w: N_Vector, id: N_Vector) -> realtype {
    let ((xp, n), (wp, _), (ip, _)) = (parts(x), parts(w), parts(id));
    weighted_squares(xp, wp, n, |k| *ip.add(k) > 0.0)
}

/// √(Σ (x w)² / n).
unsafe extern "C" fn wrms_norm(x: N_Vector, w: N_Vector) -> realtype {
    let n = parts(x).1.max(1);
    (wsqrsum(x, w) / n as f64).sqrt()
}

/// √(Σ_{id > 0} (x w)² / n).
unsafe extern "C" fn wrms_norm_mask(x: N_Vector, w: N_Vector, id: N_Vector) -> realtype {
    let n = parts(x).1.max(1);
    (wsqrsum_mask(x, w, id) / n as f64).sqrt()
}

/// max |x|.
unsafe extern "C" fn max_norm(x: N_Vector) -> realtype {
    let (xp, n) = parts(x);
    (0..n).fold(0.0, |m, i| f64::max(m, (*xp.add(i)).abs()))
}

/// z = Σ c_j X_j. z may be X_0 (SUNDIALS allows it): then z = c_0 z + Σ_{j ≥ 1} c_j X_j,
/// which the element-by-element loop computes correctly as well.
unsafe extern "C" fn linear_combination(
    nvec: c_int,
    c: *mut realtype,
    xs: *mut N_Vector,
    z: N_Vector,
) -> c_int {
    let nvec = nvec.max(0) as usize;
    if nvec == 0 {
        return -1;
    }
    let (zp, n) = parts(z);
    let coeffs = std::slice::from_raw_parts(c, nvec);
    let ptrs: Vec<*mut f64> = (0..nvec).map(|j| parts(*xs.add(j)).0).collect();
    // LANES elements at a time, each summed in the same order as alone (c_0 x_0, then
    // + c_j x_j for j = 1, 2, …): the lanes' loops vectorise, where a loop over j inside
    // one over the elements did not. A block's inputs are all read before its outputs are
    // written, so z = X_0 stays correct.
    let blocks = n / LANES;
    for b in 0..blocks {
        let i = b * LANES;
        let mut s = [0.0; LANES];
        let (c0, p0) = (coeffs[0], ptrs[0].add(i));
        for (l, s) in s.iter_mut().enumerate() {
            *s = c0 * *p0.add(l);
        }
        for j in 1..nvec {
            let (cj, pj) = (coeffs[j], ptrs[j].add(i));
            for (l, s) in s.iter_mut().enumerate() {
                *s += cj * *pj.add(l);
            }
        }
        for (l, s) in s.iter().enumerate() {
            *zp.add(i + l) = *s;
        }
    }
    for i in blocks * LANES..n {
        let mut s = coeffs[0] * *ptrs[0].add(i);
        for j in 1..nvec {
            s += coeffs[j] * *ptrs[j].add(i);
        }
        *zp.add(i) = s;
    }
    0
}

/// Z_j = a_j x + Y_j.
unsafe extern "C" fn scale_add_multi(
    nvec: c_int,
    a: *mut realtype,
    x: N_Vector,
    ys: *mut N_Vector,
    zs: *mut N_Vector,
) -> c_int {
    let nvec = nvec.max(0) as usize;
    let (xp, n) = parts(x);
    for j in 0..nvec {
        let aj = *a.add(j);
        let (yp, zp) = (parts(*ys.add(j)).0, parts(*zs.add(j)).0);
        map2(n, xp, yp, zp, |x, y| aj * x + y);
    }
    0
}

/// Z_j = a X_j + b Y_j.
unsafe extern "C" fn linear_sum_array(
    nvec: c_int,
    a: realtype,
    xs: *mut N_Vector,
    b: realtype,
    ys: *mut N_Vector,
    zs: *mut N_Vector,
) -> c_int {
    for j in 0..nvec.max(0) as usize {
        linear_sum(a, *xs.add(j), b, *ys.add(j), *zs.add(j));
    }
    0
}

/// Z_j = c_j X_j.
unsafe extern "C" fn scale_array(
    nvec: c_int,
    c: *mut realtype,
    xs: *mut N_Vector,
    zs: *mut N_Vector,
) -> c_int {
    for j in 0..nvec.max(0) as usize {
        scale(*c.add(j), *xs.add(j), *zs.add(j));
    }
    0
}

/// Z_j = c.
unsafe extern "C" fn constant_array(nvec: c_int, c: realtype, zs: *mut N_Vector) -> c_int {
    for j in 0..nvec.max(0) as usize {
        constant(c, *zs.add(j));
    }
    0
}

/// nrm_j = √(Σ (X_j W_j)² / n).
unsafe extern "C" fn wrms_norm_array(
    nvec: c_int,
    xs: *mut N_Vector,
    ws: *mut N_Vector,
    nrm: *mut realtype,
) -> c_int {
    for j in 0..nvec.max(0) as usize {
        *nrm.add(j) = wrms_norm(*xs.add(j), *ws.add(j));
    }
    0
}

/// nrm_j = √(Σ_{id > 0} (X_j W_j)² / n).
unsafe extern "C" fn wrms_norm_mask_array(
    nvec: c_int,
    xs: *mut N_Vector,
    ws: *mut N_Vector,
    id: N_Vector,
    nrm: *mut realtype,
) -> c_int {
    for j in 0..nvec.max(0) as usize {
        *nrm.add(j) = wrms_norm_mask(*xs.add(j), *ws.add(j), id);
    }
    0
}

/// Install the kernels into `v`'s operation table (shared with nothing: each serial vector
/// owns its table, and N_VClone copies it).
///
/// # Safety
/// `v` must be a live serial vector with an operation table.
pub(crate) unsafe fn install(v: N_Vector) {
    let ops = &mut *(*v).ops;
    ops.nvlinearsum = Some(linear_sum);
    ops.nvscale = Some(scale);
    ops.nvconst = Some(constant);
    ops.nvprod = Some(prod);
    ops.nvdiv = Some(div);
    ops.nvabs = Some(abs);
    ops.nvinv = Some(inv);
    ops.nvaddconst = Some(add_const);
    ops.nvwrmsnorm = Some(wrms_norm);
    ops.nvwrmsnormmask = Some(wrms_norm_mask);
    ops.nvwsqrsumlocal = Some(wsqrsum);
    ops.nvwsqrsummasklocal = Some(wsqrsum_mask);
    ops.nvmaxnorm = Some(max_norm);
    ops.nvlinearcombination = Some(linear_combination);
    ops.nvscaleaddmulti = Some(scale_add_multi);
    // The vector-array forms (IDA calls them once fused operations are on).
    ops.nvlinearsumvectorarray = Some(linear_sum_array);
    ops.nvscalevectorarray = Some(scale_array);
    ops.nvconstvectorarray = Some(constant_array);
    ops.nvwrmsnormvectorarray = Some(wrms_norm_array);
    ops.nvwrmsnormmaskvectorarray = Some(wrms_norm_mask_array);
}

#[cfg(test)]
mod tests {
    use super::super::{Context, NVector};
    use sundials_sys as s;

    /// The blocked linear combination sums each element in the order the element-by-element
    /// loop did (c_0 x_0, then + c_j x_j), so it gives the same bits, at lengths that are and
    /// are not multiples of its block, for 1 to 6 vectors, with z = X_0 and z apart.
    #[test]
    fn linear_combination_is_the_element_loop_to_the_bit() {
        let ctx = Context::new().unwrap();
        for n in [1, 3, 4, 5, 1013, 5059] {
            for nvec in 1..=6 {
                for aliased in [false, true] {
                    let data = |k: usize| {
                        (0..n)
                            .map(|i| {
                                ((i * 7 + k * 13) as f64 * 0.37).sin()
                                    * 10f64.powi(k as i32 % 5 - 2)
                            })
                            .collect::<Vec<_>>()
                    };
                    let columns: Vec<Vec<f64>> = (0..nvec).map(data).collect();
                    let xs: Vec<NVector> = (0..nvec)
                        .map(|k| NVector::from_slice(&ctx, &columns[k]).unwrap())
                        .collect();
                    let mut c: Vec<f64> = (0..nvec)
                        .map(|j| 0.3 - 1.7 * j as f64 + 1e-3 / (j + 1) as f64)
                        .collect();
                    let expected: Vec<f64> = (0..n)
                        .map(|i| {
                            let mut s = c[0] * columns[0][i];
                            for (j, cj) in c.iter().enumerate().skip(1) {
                                s += cj * columns[j][i];
                            }
                            s
                        })
                        .collect();
                    let z = NVector::from_slice(&ctx, &vec![f64::NAN; n]).unwrap();
                    let mut ptrs: Vec<s::N_Vector> = xs.iter().map(|x| x.raw()).collect();
                    let target = if aliased { xs[0].raw() } else { z.raw() };
                    let flag = unsafe {
                        super::linear_combination(
                            nvec as i32,
                            c.as_mut_ptr(),
                            ptrs.as_mut_ptr(),
                            target,
                        )
                    };
                    assert_eq!(flag, 0);
                    let got = if aliased {
                        xs[0].as_slice()
                    } else {
                        z.as_slice()
                    };
                    for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
                        assert_eq!(
                            g.to_bits(),
                            e.to_bits(),
                            "n {n} nvec {nvec} aliased {aliased} element {i}: {g} vs {e}"
                        );
                    }
                }
            }
        }
    }

    /// The blocked two-input kernels compute each element by the same expression as alone
    /// (z = a x + b y, z = c x, z = a x + y), at lengths that are and are not multiples of
    /// the block, with z apart, z = x and z = y.
    #[test]
    fn blocked_kernels_are_the_element_loops_to_the_bit() {
        let ctx = Context::new().unwrap();
        for n in [1, 3, 4, 7, 1013] {
            let x0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 1e3).collect();
            let y0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.71).cos() * 1e-2).collect();
            let (a, b) = (0.3, -1.7);
            type Element = fn(f64, f64) -> f64;
            let cases: [(&str, Element); 3] = [
                ("linear sum", |x, y| 0.3 * x + -1.7 * y),
                ("scale", |x, _| 0.3 * x),
                ("scale add", |x, y| 0.3 * x + y),
            ];
            for (what, f) in cases {
                for target in 0..3 {
                    let (x, y) = (
                        NVector::from_slice(&ctx, &x0).unwrap(),
                        NVector::from_slice(&ctx, &y0).unwrap(),
                    );
                    let z = NVector::from_slice(&ctx, &vec![f64::NAN; n]).unwrap();
                    let zr = [z.raw(), x.raw(), y.raw()][target];
                    unsafe {
                        match what {
                            "linear sum" => super::linear_sum(a, x.raw(), b, y.raw(), zr),
                            "scale" => super::scale(a, x.raw(), zr),
                            _ => {
                                let (mut aa, mut ys, mut zs) = ([a], [y.raw()], [zr]);
                                super::scale_add_multi(
                                    1,
                                    aa.as_mut_ptr(),
                                    x.raw(),
                                    ys.as_mut_ptr(),
                                    zs.as_mut_ptr(),
                                );
                            }
                        }
                    }
                    let got = [&z, &x, &y][target].as_slice();
                    for i in 0..n {
                        let e = f(x0[i], y0[i]);
                        assert_eq!(
                            got[i].to_bits(),
                            e.to_bits(),
                            "{what}, n {n}, target {target}, element {i}"
                        );
                    }
                }
            }
        }
    }

    /// Each kernel against SUNDIALS' own serial operation, aliased output included.
    #[test]
    fn kernels_match_sundials() {
        let ctx = Context::new().unwrap();
        let n = 1013;
        let data = |k: usize| {
            (0..n)
                .map(|i| ((i * 7 + k * 13) as f64 * 0.37).sin() + 0.1 * k as f64)
                .collect::<Vec<_>>()
        };
        let mk = |k: usize| NVector::from_slice(&ctx, &data(k)).unwrap();
        let fast = |v: &NVector| unsafe { super::install(v.raw()) };
        let (x, y, w) = (mk(1), mk(2), mk(3));
        let id = NVector::from_slice(
            &ctx,
            &(0..n)
                .map(|i| if i % 3 == 0 { 0.0 } else { 1.0 })
                .collect::<Vec<_>>(),
        )
        .unwrap();
        let (z_ref, z_fast) = (mk(4), mk(4));
        fast(&z_fast);
        let same = |a: &NVector, b: &NVector, what: &str| {
            for (p, q) in a.as_slice().iter().zip(b.as_slice()) {
                assert!(
                    (p - q).abs() <= 1e-15 * (1.0 + p.abs()),
                    "{what}: {p} vs {q}"
                );
            }
        };
        unsafe {
            s::N_VLinearSum_Serial(0.3, x.raw(), -1.7, y.raw(), z_ref.raw());
            s::N_VLinearSum(0.3, x.raw(), -1.7, y.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "linear sum");
            // Aliased: z = 2 x + 0.5 z.
            s::N_VLinearSum_Serial(2.0, x.raw(), 0.5, z_ref.raw(), z_ref.raw());
            s::N_VLinearSum(2.0, x.raw(), 0.5, z_fast.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "aliased linear sum");
            s::N_VScale_Serial(-3.0, z_ref.raw(), z_ref.raw());
            s::N_VScale(-3.0, z_fast.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "scale");
            s::N_VProd_Serial(x.raw(), y.raw(), z_ref.raw());
            s::N_VProd(x.raw(), y.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "prod");
            s::N_VDiv_Serial(x.raw(), w.raw(), z_ref.raw());
            s::N_VDiv(x.raw(), w.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "div");
            s::N_VAbs_Serial(y.raw(), z_ref.raw());
            s::N_VAbs(y.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "abs");
            s::N_VInv_Serial(w.raw(), z_ref.raw());
            s::N_VInv(w.raw(), z_fast.raw());
            same(&z_ref, &z_fast, "inv");
            s::N_VAddConst_Serial(y.raw(), 0.25, z_ref.raw());
            s::N_VAddConst(y.raw(), 0.25, z_fast.raw());
            same(&z_ref, &z_fast, "add const");
            s::N_VConst_Serial(1.5, z_ref.raw());
            s::N_VConst(1.5, z_fast.raw());
            same(&z_ref, &z_fast, "const");
            let xf = mk(1);
            fast(&xf);
            let close = |a: f64, b: f64, what: &str| {
                assert!((a - b).abs() <= 1e-13 * a.abs(), "{what}: {a} vs {b}")
            };
            close(
                s::N_VWrmsNorm_Serial(x.raw(), w.raw()),
                s::N_VWrmsNorm(xf.raw(), w.raw()),
                "wrms norm",
            );
            close(
                s::N_VWrmsNormMask_Serial(x.raw(), w.raw(), id.raw()),
                s::N_VWrmsNormMask(xf.raw(), w.raw(), id.raw()),
                "masked wrms norm",
            );
            close(
                s::N_VMaxNorm_Serial(x.raw()),
                s::N_VMaxNorm(xf.raw()),
                "max norm",
            );
            // z = Σ c_j X_j with z = X_0 (aliased).
            let mut c = [0.5, -2.0, 3.0];
            let (a0, b0) = (mk(5), mk(5));
            fast(&b0);
            let mut xs_ref = [a0.raw(), y.raw(), w.raw()];
            let mut xs_fast = [b0.raw(), y.raw(), w.raw()];
            s::N_VLinearCombination_Serial(3, c.as_mut_ptr(), xs_ref.as_mut_ptr(), a0.raw());
            s::N_VLinearCombination(3, c.as_mut_ptr(), xs_fast.as_mut_ptr(), b0.raw());
            same(&a0, &b0, "linear combination");
            // Z_j = a_j x + Y_j.
            let mut ys = [y.raw(), w.raw()];
            let (z1, z2, f1, f2) = (mk(6), mk(7), mk(6), mk(7));
            let mut zs_ref = [z1.raw(), z2.raw()];
            let mut zs_fast = [f1.raw(), f2.raw()];
            let mut a = [1.5, -0.5];
            s::N_VScaleAddMulti_Serial(
                2,
                a.as_mut_ptr(),
                x.raw(),
                ys.as_mut_ptr(),
                zs_ref.as_mut_ptr(),
            );
            s::N_VScaleAddMulti(
                2,
                a.as_mut_ptr(),
                xf.raw(),
                ys.as_mut_ptr(),
                zs_fast.as_mut_ptr(),
            );
            same(&z1, &f1, "scale add multi 0");
            same(&z2, &f2, "scale add multi 1");
            // The array forms: Z_j = c_j X_j, Z_j = a X_j + b Y_j, and the norms of the X_j.
            // Every vector of the fast side carries the kernels (SUNDIALS dispatches some
            // array forms on X_0, some on Z_0); the reference calls the serial ones directly.
            let (yf, wf, g1, g2) = (mk(2), mk(3), mk(6), mk(7));
            for v in [&yf, &wf, &g1, &g2] {
                fast(v);
            }
            let mut cs = [2.0, -0.5];
            let (mut xr, mut xq) = ([x.raw(), y.raw()], [xf.raw(), yf.raw()]);
            let (mut zr, mut zq) = ([z1.raw(), z2.raw()], [g1.raw(), g2.raw()]);
            s::N_VScaleVectorArray_Serial(2, cs.as_mut_ptr(), xr.as_mut_ptr(), zr.as_mut_ptr());
            s::N_VScaleVectorArray(2, cs.as_mut_ptr(), xq.as_mut_ptr(), zq.as_mut_ptr());
            same(&z1, &g1, "scale array 0");
            same(&z2, &g2, "scale array 1");
            let (mut yr, mut yq) = ([w.raw(), x.raw()], [wf.raw(), xf.raw()]);
            s::N_VLinearSumVectorArray_Serial(
                2,
                0.7,
                xr.as_mut_ptr(),
                -1.3,
                yr.as_mut_ptr(),
                zr.as_mut_ptr(),
            );
            s::N_VLinearSumVectorArray(
                2,
                0.7,
                xq.as_mut_ptr(),
                -1.3,
                yq.as_mut_ptr(),
                zq.as_mut_ptr(),
            );
            same(&z1, &g1, "linear sum array 0");
            same(&z2, &g2, "linear sum array 1");
            s::N_VConstVectorArray_Serial(2, 0.25, zr.as_mut_ptr());
            s::N_VConstVectorArray(2, 0.25, zq.as_mut_ptr());
            same(&z1, &g1, "const array 0");
            let (mut nr, mut nq) = ([0.0; 2], [0.0; 2]);
            let (mut wr, mut wq) = ([w.raw(), w.raw()], [wf.raw(), wf.raw()]);
            s::N_VWrmsNormVectorArray_Serial(2, xr.as_mut_ptr(), wr.as_mut_ptr(), nr.as_mut_ptr());
            s::N_VWrmsNormVectorArray(2, xq.as_mut_ptr(), wq.as_mut_ptr(), nq.as_mut_ptr());
            close(nr[0], nq[0], "wrms norm array 0");
            close(nr[1], nq[1], "wrms norm array 1");
            s::N_VWrmsNormMaskVectorArray_Serial(
                2,
                xr.as_mut_ptr(),
                wr.as_mut_ptr(),
                id.raw(),
                nr.as_mut_ptr(),
            );
            fast(&id);
            s::N_VWrmsNormMaskVectorArray(
                2,
                xq.as_mut_ptr(),
                wq.as_mut_ptr(),
                id.raw(),
                nq.as_mut_ptr(),
            );
            close(nr[0], nq[0], "masked wrms norm array 0");
            close(nr[1], nq[1], "masked wrms norm array 1");
        }
    }
}
