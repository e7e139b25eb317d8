//! Typed errors for the SUNDIALS layer, and the symbolic names of the return flags.
//!
//! Why our own flag tables: `KINGetReturnFlagName` (and CVODE's `CVodeGetReturnFlagName`,
//! IDA's `IDAGetReturnFlagName`) returns a malloc'd string per call, and the same integer means
//! different things in KINSOL, KINLS, CVODE, CVLS, IDA, IDALS and SUNLinSol; a static table per
//! family gives a `&'static str` name and a fallback description when SUNDIALS sent no message.

use std::fmt;

#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SundialsError {
    /// A SUNDIALS function returned a failure flag.
    #[error("{function} failed with {name} ({flag}){}", Colon(message))]
    Flag {
        function: &'static str,
        flag: i32,
        /// The flag's symbolic name, e.g. "KIN_LINESEARCH_NONCONV".
        name: &'static str,
        /// What SUNDIALS said (captured by the error handler), or a description of the flag.
        message: String,
    },
    /// A constructor returned NULL.
    #[error("{0} returned NULL (out of memory or invalid arguments)")]
    NullHandle(&'static str),
    /// One of our callbacks failed fatally or panicked.
    #[error("callback failed: {0}")]
    Callback(String),
    /// KLU was asked for but was not found when the crate was built.
    #[error("the KLU sparse linear solver is not available: sunlinsol_klu/klu were not found when eyeshell was built (apt-get install -y libsundials-dev libsuitesparse-dev, then rebuild)")]
    KluUnavailable,
    /// The caller passed something the layer cannot use (wrong length, bad pattern, ...).
    #[error("invalid argument: {0}")]
    Invalid(String),
}

/// What joins, in a [`SundialsError::Flag`]'s message, SUNDIALS' own words and the last
/// recoverable error our callbacks reported during the failed call (the caller's words for
/// why an evaluation failed), so that a caller can tell them apart.
pub const RECOVERABLE_NOTE: &str = "; last recoverable callback error: ";

/// ": message" on one line, or nothing when the message is empty.
struct Colon<'a>(&'a str);

impl fmt::Display for Colon<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let one_line = one_line(self.0);
        if one_line.is_empty() {
            Ok(())
        } else {
            write!(f, ": {one_line}")
        }
    }
}

/// Collapse whitespace (SUNDIALS messages may contain newlines and tabs).
pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Which family a flag belongs to: the same integer means different things in each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FlagFamily {
    Kin,
    KinLs,
    Cv,
    CvLs,
    Ida,
    IdaLs,
    SunLs,
    /// Plain 0 / nonzero (SUNContext, N_Vector utilities).
    Generic,
}

impl FlagFamily {
    /// (symbolic name, short description).
    pub(crate) fn describe(self, flag: i32) -> (&'static str, &'static str) {
        let table: &[(i32, &str, &str)] = match self {
            FlagFamily::Kin => KIN_FLAGS,
            FlagFamily::KinLs => KINLS_FLAGS,
            FlagFamily::Cv => CV_FLAGS,
            FlagFamily::CvLs => CVLS_FLAGS,
            FlagFamily::Ida => IDA_FLAGS,
            FlagFamily::IdaLs => IDALS_FLAGS,
            FlagFamily::SunLs => SUNLS_FLAGS,
            FlagFamily::Generic => &[(0, "SUCCESS", "success")],
        };
        table
            .iter()
            .find(|(f, _, _)| *f == flag)
            .map(|(_, n, d)| (*n, *d))
            .unwrap_or(("UNKNOWN_FLAG", "unrecognised return flag"))
    }

    pub(crate) fn name(self, flag: i32) -> &'static str {
        self.describe(flag).0
    }
}

const KIN_FLAGS: &[(i32, &str, &str)] = &[
    (0, "KIN_SUCCESS", "success"),
    (
        1,
        "KIN_INITIAL_GUESS_OK",
        "the initial guess already satisfies the stopping criterion",
    ),
    (
        2,
        "KIN_STEP_LT_STPTOL",
        "the scaled step fell below the scaled step tolerance",
    ),
    (99, "KIN_WARNING", "warning"),
    (-1, "KIN_MEM_NULL", "the KINSOL memory is NULL"),
    (-2, "KIN_ILL_INPUT", "an input argument is illegal"),
    (
        -3,
        "KIN_NO_MALLOC",
        "KINSOL memory was not allocated by KINInit",
    ),
    (-4, "KIN_MEM_FAIL", "a memory allocation failed"),
    (
        -5,
        "KIN_LINESEARCH_NONCONV",
        "the line search could not find an iterate sufficiently distinct from the current one",
    ),
    (
        -6,
        "KIN_MAXITER_REACHED",
        "the maximum number of nonlinear iterations was reached",
    ),
    (
        -7,
        "KIN_MXNEWT_5X_EXCEEDED",
        "five consecutive steps had the maximum Newton step length",
    ),
    (
        -8,
        "KIN_LINESEARCH_BCFAIL",
        "the line search could not satisfy the beta condition",
    ),
    (
        -9,
        "KIN_LINSOLV_NO_RECOVERY",
        "the linear solver failed recoverably but the Jacobian is current",
    ),
    (
        -10,
        "KIN_LINIT_FAIL",
        "the linear solver initialisation failed",
    ),
    (
        -11,
        "KIN_LSETUP_FAIL",
        "the linear solver setup (Jacobian or factorisation) failed",
    ),
    (-12, "KIN_LSOLVE_FAIL", "the linear solve failed"),
    (
        -13,
        "KIN_SYSFUNC_FAIL",
        "the residual function failed unrecoverably",
    ),
    (
        -14,
        "KIN_FIRST_SYSFUNC_ERR",
        "the residual function failed recoverably at the initial guess",
    ),
    (
        -15,
        "KIN_REPTD_SYSFUNC_ERR",
        "the residual function failed recoverably repeatedly",
    ),
    (-16, "KIN_VECTOROP_ERR", "a vector operation failed"),
    (-17, "KIN_CONTEXT_ERR", "the SUNContext is invalid"),
];

const KINLS_FLAGS: &[(i32, &str, &str)] = &[
    (0, "KINLS_SUCCESS", "success"),
    (-1, "KINLS_MEM_NULL", "the KINSOL memory is NULL"),
    (
        -2,
        "KINLS_LMEM_NULL",
        "the linear solver interface is not attached",
    ),
    (
        -3,
        "KINLS_ILL_INPUT",
        "an input argument is illegal or the linear solver is incompatible",
    ),
    (-4, "KINLS_MEM_FAIL", "a memory allocation failed"),
    (-5, "KINLS_PMEM_NULL", "the preconditioner memory is NULL"),
    (-6, "KINLS_JACFUNC_ERR", "the Jacobian function failed"),
    (-7, "KINLS_SUNMAT_FAIL", "a SUNMatrix operation failed"),
    (-8, "KINLS_SUNLS_FAIL", "a SUNLinearSolver operation failed"),
];

const CV_FLAGS: &[(i32, &str, &str)] = &[
    (0, "CV_SUCCESS", "success"),
    (1, "CV_TSTOP_RETURN", "the stop time was reached"),
    (2, "CV_ROOT_RETURN", "a root was found"),
    (99, "CV_WARNING", "warning"),
    (
        -1,
        "CV_TOO_MUCH_WORK",
        "the maximum number of internal steps was taken before reaching tout",
    ),
    (
        -2,
        "CV_TOO_MUCH_ACC",
        "the requested accuracy could not be achieved",
    ),
    (
        -3,
        "CV_ERR_FAILURE",
        "error test failures occurred too many times or with |h| = hmin",
    ),
    (
        -4,
        "CV_CONV_FAILURE",
        "nonlinear convergence failures occurred too many times or with |h| = hmin",
    ),
    (
        -5,
        "CV_LINIT_FAIL",
        "the linear solver initialisation failed",
    ),
    (
        -6,
        "CV_LSETUP_FAIL",
        "the linear solver setup failed unrecoverably",
    ),
    (
        -7,
        "CV_LSOLVE_FAIL",
        "the linear solve failed unrecoverably",
    ),
    (
        -8,
        "CV_RHSFUNC_FAIL",
        "the right-hand side function failed unrecoverably",
    ),
    (
        -9,
        "CV_FIRST_RHSFUNC_ERR",
        "the right-hand side function failed recoverably at the first call",
    ),
    (
        -10,
        "CV_REPTD_RHSFUNC_ERR",
        "the right-hand side function failed recoverably repeatedly",
    ),
    (
        -11,
        "CV_UNREC_RHSFUNC_ERR",
        "the right-hand side function failed recoverably and could not recover",
    ),
    (-12, "CV_RTFUNC_FAIL", "the root function failed"),
    (
        -13,
        "CV_NLS_INIT_FAIL",
        "the nonlinear solver initialisation failed",
    ),
    (
        -14,
        "CV_NLS_SETUP_FAIL",
        "the nonlinear solver setup failed",
    ),
    (
        -15,
        "CV_CONSTR_FAIL",
        "the inequality constraints could not be met",
    ),
    (
        -16,
        "CV_NLS_FAIL",
        "the nonlinear solver failed unrecoverably",
    ),
    (-20, "CV_MEM_FAIL", "a memory allocation failed"),
    (-21, "CV_MEM_NULL", "the CVODE memory is NULL"),
    (-22, "CV_ILL_INPUT", "an input argument is illegal"),
    (
        -23,
        "CV_NO_MALLOC",
        "CVODE memory was not allocated by CVodeInit",
    ),
    (-24, "CV_BAD_K", "the derivative order k is illegal"),
    (-25, "CV_BAD_T", "t is outside the last step"),
    (-26, "CV_BAD_DKY", "the output vector is NULL"),
    (
        -27,
        "CV_TOO_CLOSE",
        "tout is too close to t0 to start the integration",
    ),
    (-28, "CV_VECTOROP_ERR", "a vector operation failed"),
    (-29, "CV_PROJ_MEM_NULL", "the projection memory is NULL"),
    (
        -30,
        "CV_PROJFUNC_FAIL",
        "the projection function failed unrecoverably",
    ),
    (
        -31,
        "CV_REPTD_PROJFUNC_ERR",
        "the projection function failed recoverably repeatedly",
    ),
    (-32, "CV_CONTEXT_ERR", "the SUNContext is invalid"),
    (-99, "CV_UNRECOGNIZED_ERR", "unrecognised error"),
];

const CVLS_FLAGS: &[(i32, &str, &str)] = &[
    (0, "CVLS_SUCCESS", "success"),
    (-1, "CVLS_MEM_NULL", "the CVODE memory is NULL"),
    (
        -2,
        "CVLS_LMEM_NULL",
        "the linear solver interface is not attached",
    ),
    (
        -3,
        "CVLS_ILL_INPUT",
        "an input argument is illegal or the linear solver is incompatible",
    ),
    (-4, "CVLS_MEM_FAIL", "a memory allocation failed"),
    (-5, "CVLS_PMEM_NULL", "the preconditioner memory is NULL"),
    (
        -6,
        "CVLS_JACFUNC_UNRECVR",
        "the Jacobian function failed unrecoverably",
    ),
    (
        -7,
        "CVLS_JACFUNC_RECVR",
        "the Jacobian function failed recoverably",
    ),
    (-8, "CVLS_SUNMAT_FAIL", "a SUNMatrix operation failed"),
    (-9, "CVLS_SUNLS_FAIL", "a SUNLinearSolver operation failed"),
];

/// ida.h; descriptions after IDA's own messages (ida_impl.h).
const IDA_FLAGS: &[(i32, &str, &str)] = &[
    (0, "IDA_SUCCESS", "success"),
    (1, "IDA_TSTOP_RETURN", "the stop time was reached"),
    (2, "IDA_ROOT_RETURN", "a root was found"),
    (99, "IDA_WARNING", "warning"),
    (-1, "IDA_TOO_MUCH_WORK", "the maximum number of internal steps was taken before reaching tout"),
    (-2, "IDA_TOO_MUCH_ACC", "the requested accuracy could not be achieved"),
    (-3, "IDA_ERR_FAIL", "error test failures occurred too many times or with |h| = hmin"),
    (-4, "IDA_CONV_FAIL", "nonlinear convergence failures occurred too many times or with |h| = hmin"),
    (-5, "IDA_LINIT_FAIL", "the linear solver initialisation failed"),
    (-6, "IDA_LSETUP_FAIL", "the linear solver setup failed unrecoverably"),
    (-7, "IDA_LSOLVE_FAIL", "the linear solve failed unrecoverably"),
    (-8, "IDA_RES_FAIL", "the residual function failed unrecoverably"),
    (-9, "IDA_REP_RES_ERR", "the residual function failed recoverably repeatedly"),
    (-10, "IDA_RTFUNC_FAIL", "the root function failed"),
    (-11, "IDA_CONSTR_FAIL", "the inequality constraints could not be met"),
    (-12, "IDA_FIRST_RES_FAIL", "the residual function failed recoverably at the first call (IDACalcIC)"),
    (-13, "IDA_LINESEARCH_FAIL", "the line search of IDACalcIC failed (step too small or too many backtracks)"),
    (-14, "IDA_NO_RECOVERY", "the residual or the linear setup or solve failed recoverably and IDACalcIC could not recover"),
    (-15, "IDA_NLS_INIT_FAIL", "the nonlinear solver initialisation failed"),
    (-16, "IDA_NLS_SETUP_FAIL", "the nonlinear solver setup failed"),
    (-17, "IDA_NLS_FAIL", "the nonlinear solver failed unrecoverably"),
    (-20, "IDA_MEM_NULL", "the IDA memory is NULL"),
    (-21, "IDA_MEM_FAIL", "a memory allocation failed"),
    (-22, "IDA_ILL_INPUT", "an input argument is illegal"),
    (-23, "IDA_NO_MALLOC", "IDA memory was not allocated by IDAInit"),
    (-24, "IDA_BAD_EWT", "an error weight became zero or negative"),
    (-25, "IDA_BAD_K", "the derivative order k is illegal"),
    (-26, "IDA_BAD_T", "t is outside the last step"),
    (-27, "IDA_BAD_DKY", "the output vector is NULL"),
    (-28, "IDA_VECTOROP_ERR", "a vector operation failed"),
    (-29, "IDA_CONTEXT_ERR", "the SUNContext is invalid"),
    // IDAS's forward sensitivities (IDA is linked as IDAS).
    (-40, "IDA_NO_SENS", "forward sensitivities were not initialised"),
    (-41, "IDA_SRES_FAIL", "the sensitivity residual failed unrecoverably"),
    (-42, "IDA_REP_SRES_ERR", "the sensitivity residual failed recoverably repeatedly"),
    (-43, "IDA_BAD_IS", "the sensitivity index is illegal"),
    (-99, "IDA_UNRECOGNIZED_ERROR", "unrecognised error"),
];

const IDALS_FLAGS: &[(i32, &str, &str)] = &[
    (0, "IDALS_SUCCESS", "success"),
    (-1, "IDALS_MEM_NULL", "the IDA memory is NULL"),
    (
        -2,
        "IDALS_LMEM_NULL",
        "the linear solver interface is not attached",
    ),
    (
        -3,
        "IDALS_ILL_INPUT",
        "an input argument is illegal or the linear solver is incompatible",
    ),
    (-4, "IDALS_MEM_FAIL", "a memory allocation failed"),
    (-5, "IDALS_PMEM_NULL", "the preconditioner memory is NULL"),
    (
        -6,
        "IDALS_JACFUNC_UNRECVR",
        "the Jacobian function failed unrecoverably",
    ),
    (
        -7,
        "IDALS_JACFUNC_RECVR",
        "the Jacobian function failed recoverably",
    ),
    (-8, "IDALS_SUNMAT_FAIL", "a SUNMatrix operation failed"),
    (-9, "IDALS_SUNLS_FAIL", "a SUNLinearSolver operation failed"),
];

const SUNLS_FLAGS: &[(i32, &str, &str)] = &[
    (0, "SUNLS_SUCCESS", "success"),
    (-801, "SUNLS_MEM_NULL", "the linear solver memory is NULL"),
    (-802, "SUNLS_ILL_INPUT", "an input argument is illegal"),
    (-803, "SUNLS_MEM_FAIL", "a memory allocation failed"),
    (-804, "SUNLS_ATIMES_NULL", "the A-times function is NULL"),
    (
        -805,
        "SUNLS_ATIMES_FAIL_UNREC",
        "the A-times function failed unrecoverably",
    ),
    (
        -806,
        "SUNLS_PSET_FAIL_UNREC",
        "the preconditioner setup failed unrecoverably",
    ),
    (
        -807,
        "SUNLS_PSOLVE_NULL",
        "the preconditioner solve function is NULL",
    ),
    (
        -808,
        "SUNLS_PSOLVE_FAIL_UNREC",
        "the preconditioner solve failed unrecoverably",
    ),
    (
        -809,
        "SUNLS_PACKAGE_FAIL_UNREC",
        "the external package (e.g. KLU) failed unrecoverably",
    ),
    (
        -810,
        "SUNLS_GS_FAIL",
        "Gram-Schmidt orthogonalisation failed",
    ),
    (-811, "SUNLS_QRSOL_FAIL", "QR solve found a singular R"),
    (-812, "SUNLS_VECTOROP_ERR", "a vector operation failed"),
    (
        801,
        "SUNLS_RES_REDUCED",
        "nonconvergent solve, residual reduced",
    ),
    (802, "SUNLS_CONV_FAIL", "nonconvergent solve"),
    (
        803,
        "SUNLS_ATIMES_FAIL_REC",
        "the A-times function failed recoverably",
    ),
    (
        804,
        "SUNLS_PSET_FAIL_REC",
        "the preconditioner setup failed recoverably",
    ),
    (
        805,
        "SUNLS_PSOLVE_FAIL_REC",
        "the preconditioner solve failed recoverably",
    ),
    (
        806,
        "SUNLS_PACKAGE_FAIL_REC",
        "the external package (e.g. KLU: singular matrix) failed recoverably",
    ),
    (
        807,
        "SUNLS_QRFACT_FAIL",
        "QR factorisation found a singular matrix",
    ),
    (
        808,
        "SUNLS_LUFACT_FAIL",
        "LU factorisation found a singular matrix",
    ),
];

/// Ok for 0, otherwise a `Flag` error named from `family` with `message` (or the flag's
/// description when `message` is empty).
pub(crate) fn check(
    function: &'static str,
    flag: i32,
    family: FlagFamily,
    message: Option<String>,
) -> Result<(), SundialsError> {
    if flag == 0 {
        return Ok(());
    }
    Err(flag_error(function, flag, family, message))
}

pub(crate) fn flag_error(
    function: &'static str,
    flag: i32,
    family: FlagFamily,
    message: Option<String>,
) -> SundialsError {
    let (name, description) = family.describe(flag);
    let message = message
        .map(|m| one_line(&m))
        .filter(|m| !m.is_empty())
        .unwrap_or_else(|| description.to_string());
    SundialsError::Flag {
        function,
        flag,
        name,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flag_display_is_one_line_and_names_the_flag() {
        let e = flag_error(
            "KINSol",
            -5,
            FlagFamily::Kin,
            Some("line\n\tsearch  failed".into()),
        );
        assert_eq!(
            e.to_string(),
            "KINSol failed with KIN_LINESEARCH_NONCONV (-5): line search failed"
        );
        let e = flag_error("SUNLinSolSetup", 808, FlagFamily::SunLs, None);
        assert!(e
            .to_string()
            .contains("SUNLS_LUFACT_FAIL (808): LU factorisation"));
    }

    extern "C" {
        fn free(p: *mut std::ffi::c_void);
    }

    /// Call one of SUNDIALS's `*Get*ReturnFlagName` functions, which return a malloc'd string.
    fn their_name(
        f: unsafe extern "C" fn(std::os::raw::c_long) -> *mut std::os::raw::c_char,
        flag: i32,
    ) -> String {
        // SAFETY: f returns a malloc'd NUL-terminated string (or NULL) that we free once.
        unsafe {
            let p = f(flag as std::os::raw::c_long);
            if p.is_null() {
                return String::from("NONE");
            }
            let s = std::ffi::CStr::from_ptr(p).to_string_lossy().into_owned();
            free(p.cast());
            s
        }
    }

    /// Our names agree with KINSOL's own `KINGetReturnFlagName` where it has one.
    #[test]
    fn kin_names_match_kinsol() {
        for &(flag, name, _) in KIN_FLAGS {
            let theirs = their_name(sundials_sys::KINGetReturnFlagName, flag);
            if theirs == "NONE" {
                continue; // KINSOL 6.4 names only some flags (not 99, -13 ... -17)
            }
            assert_eq!(theirs, name, "flag {flag}");
        }
    }

    /// Our names agree with `CVodeGetReturnFlagName` and `CVodeGetLinReturnFlagName` wherever
    /// CVODE 6.4 has a name, except for its misspelling of -14: we keep the header's
    /// `CV_NLS_SETUP_FAIL` (cvode.h), CVODE 6.4 prints "CV_NLS_SETUPT_FAIL". CVODE 6.4 has no
    /// name (says "NONE") for 99, -15, -28, -32 and -99.
    #[test]
    fn cv_names_match_cvode() {
        let mut mismatched = Vec::new();
        let mut unnamed = Vec::new();
        for &(flag, name, _) in CV_FLAGS {
            let theirs = their_name(sundials_sys::CVodeGetReturnFlagName, flag);
            match theirs.as_str() {
                "NONE" => unnamed.push(flag),
                "CV_NLS_SETUPT_FAIL" if flag == -14 => {}
                t if t == name => {}
                _ => mismatched.push((flag, name, theirs)),
            }
        }
        assert!(mismatched.is_empty(), "ours vs CVODE's: {mismatched:?}");
        assert!(
            unnamed.len() <= 6,
            "CVODE 6.4 leaves unnamed only a few flags: {unnamed:?}"
        );
        assert_eq!(sundials_sys::CV_NLS_SETUP_FAIL, -14);
        for &(flag, name, _) in CVLS_FLAGS {
            assert_eq!(
                their_name(sundials_sys::CVodeGetLinReturnFlagName, flag),
                name,
                "CVLS flag {flag}"
            );
        }
    }

    /// Our names agree with `IDAGetReturnFlagName` and `IDAGetLinReturnFlagName` wherever IDA
    /// 6.4 has a name. IDA is linked as IDAS, whose table names -25 and -27 too (and the
    /// sensitivity flags -40 ..= -43); it has none (says "NONE") for 99, -15, -28, -29, -99.
    #[test]
    fn ida_names_match_ida() {
        let mut mismatched = Vec::new();
        let mut unnamed = Vec::new();
        for &(flag, name, _) in IDA_FLAGS {
            let theirs = their_name(sundials_sys::IDAGetReturnFlagName, flag);
            match theirs.as_str() {
                "NONE" => unnamed.push(flag),
                t if t == name => {}
                _ => mismatched.push((flag, name, theirs)),
            }
        }
        assert!(mismatched.is_empty(), "ours vs IDA's: {mismatched:?}");
        assert_eq!(
            unnamed,
            [99, -15, -28, -29, -99],
            "flags IDAS 6.4 leaves unnamed"
        );
        for &(flag, name, _) in IDALS_FLAGS {
            assert_eq!(
                their_name(sundials_sys::IDAGetLinReturnFlagName, flag),
                name,
                "IDALS flag {flag}"
            );
        }
    }
}
