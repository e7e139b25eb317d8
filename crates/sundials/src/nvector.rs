//! Serial N_Vectors owned by Rust, and slice views of the N_Vectors SUNDIALS passes to
//! callbacks.

use std::rc::Rc;

use sundials_sys::{N_VDestroy, N_VGetArrayPointer, N_VGetLength, N_VNew_Serial, N_Vector};

use super::context::Context;
use super::error::SundialsError;

/// A serial N_Vector, destroyed on drop.
pub struct NVector {
    raw: N_Vector,
    len: usize,
    _ctx: Rc<Context>,
}

impl NVector {
    /// A zero-filled vector of length `len`.
    pub fn new(ctx: &Rc<Context>, len: usize) -> Result<Self, SundialsError> {
        let n = i64::try_from(len)
            .map_err(|_| SundialsError::Invalid(format!("vector length {len} too large")))?;
        // SAFETY: ctx is a live context.
        let raw = unsafe { N_VNew_Serial(n, ctx.raw()) };
        if raw.is_null() {
            return Err(SundialsError::NullHandle("N_VNew_Serial"));
        }
        let mut v = NVector {
            raw,
            len,
            _ctx: Rc::clone(ctx),
        };
        v.as_mut_slice().fill(0.0);
        Ok(v)
    }

    pub fn from_slice(ctx: &Rc<Context>, values: &[f64]) -> Result<Self, SundialsError> {
        let mut v = Self::new(ctx, values.len())?;
        v.as_mut_slice().copy_from_slice(values);
        Ok(v)
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn as_slice(&self) -> &[f64] {
        // SAFETY: `raw` is a live serial vector of length `len` owned by self.
        unsafe { slice(self.raw) }
    }

    pub fn as_mut_slice(&mut self) -> &mut [f64] {
        // SAFETY: as above, and &mut self guarantees exclusive access.
        unsafe { slice_mut(self.raw) }
    }

    /// Call `f` with a serial N_Vector that borrows `data` (N_VMake_Serial; destroyed, data
    /// untouched, when `f` returns): for the getters that write into a caller's vector
    /// (dense output). Returns what `f` returns.
    pub(crate) fn with_borrowed(
        ctx: &Context,
        data: &mut [f64],
        f: impl FnOnce(N_Vector) -> std::os::raw::c_int,
    ) -> Result<std::os::raw::c_int, SundialsError> {
        let len = i64::try_from(data.len()).map_err(|_| {
            SundialsError::Invalid(format!("vector length {} too large", data.len()))
        })?;
        // SAFETY: the vector wraps `data` without owning it (N_VDestroy leaves the data
        // alone) and is destroyed before `data`'s borrow ends; the context is live.
        let v = unsafe { sundials_sys::N_VMake_Serial(len, data.as_mut_ptr(), ctx.raw()) };
        if v.is_null() {
            return Err(SundialsError::NullHandle("N_VMake_Serial"));
        }
        let flag = f(v);
        // SAFETY: v came from N_VMake_Serial and is destroyed once.
        unsafe { N_VDestroy(v) };
        Ok(flag)
    }

    /// Turn on SUNDIALS' fused vector operations (linear combinations of several vectors in
    /// one pass) for this vector and its clones: an integrator cloned from it then touches
    /// memory fewer times per step.
    pub fn enable_fused_ops(&mut self) -> Result<(), SundialsError> {
        // SAFETY: raw is a live serial vector owned by self.
        let flag = unsafe { sundials_sys::N_VEnableFusedOps_Serial(self.raw, 1) };
        super::error::check(
            "N_VEnableFusedOps_Serial",
            flag,
            super::error::FlagFamily::Generic,
            None,
        )
    }

    pub(crate) fn raw(&self) -> N_Vector {
        self.raw
    }
}

impl Drop for NVector {
    fn drop(&mut self) {
        // SAFETY: `raw` came from N_VNew_Serial and is destroyed once.
        unsafe { N_VDestroy(self.raw) }
    }
}

impl std::fmt::Debug for NVector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

/// The data of a serial N_Vector as a slice.
///
/// # Safety
/// `v` must be a live serial N_Vector that nothing writes to while the slice lives.
pub(crate) unsafe fn slice<'a>(v: N_Vector) -> &'a [f64] {
    let len = N_VGetLength(v) as usize;
    let data = N_VGetArrayPointer(v);
    if data.is_null() || len == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(data, len)
    }
}

/// The data of a serial N_Vector as a mutable slice.
///
/// # Safety
/// `v` must be a live serial N_Vector that nothing else accesses while the slice lives.
pub(crate) unsafe fn slice_mut<'a>(v: N_Vector) -> &'a mut [f64] {
    let len = N_VGetLength(v) as usize;
    let data = N_VGetArrayPointer(v);
    if data.is_null() || len == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(data, len)
    }
}
