//! The SUNContext that every SUNDIALS object is created in.
//!
//! Why `Rc<Context>`: SUNDIALS objects keep a pointer to their context, so the context must
//! outlive them; every owned handle holds an `Rc<Context>` and the context is freed when the
//! last one is dropped. Not `Send`: SUNDIALS contexts are not meant to cross threads.

use std::rc::Rc;

use sundials_sys::{SUNContext, SUNContext_Create, SUNContext_Free};

use super::error::{check, FlagFamily, SundialsError};

pub struct Context {
    raw: SUNContext,
}

impl Context {
    pub fn new() -> Result<Rc<Self>, SundialsError> {
        let mut raw: SUNContext = std::ptr::null_mut();
        // SAFETY: the first argument is the (absent) MPI communicator, a void* in 6.x;
        // `raw` is a valid out-pointer.
        let flag = unsafe { SUNContext_Create(std::ptr::null_mut(), &mut raw) };
        check("SUNContext_Create", flag, FlagFamily::Generic, None)?;
        if raw.is_null() {
            return Err(SundialsError::NullHandle("SUNContext_Create"));
        }
        Ok(Rc::new(Context { raw }))
    }

    pub(crate) fn raw(&self) -> SUNContext {
        self.raw
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: `raw` came from SUNContext_Create and every object created in it holds an
        // Rc<Context>, so none is alive any more.
        unsafe {
            SUNContext_Free(&mut self.raw);
        }
    }
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context").field("raw", &self.raw).finish()
    }
}
