//! The test binary links Debian's SUNDIALS 6.x, not a vendored copy.

use std::path::Path;

use eyeshell_sundials::{Context, Kinsol, LinearSolver, LinearSolverSpec, NonlinearSystem};

struct Id;

impl NonlinearSystem for Id {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> eyeshell_sundials::CallbackResult {
        f.copy_from_slice(u);
        Ok(())
    }

    fn jacobian(
        &mut self,
        _u: &[f64],
        _jac: eyeshell_sundials::JacobianMatrix<'_>,
    ) -> eyeshell_sundials::CallbackResult {
        Ok(())
    }
}

#[test]
fn runtime_version_is_6_and_matches_the_headers() {
    let v = eyeshell_sundials::version();
    assert!(v.starts_with("6."), "linked SUNDIALS is {v}");
    assert_eq!(v, eyeshell_sundials::BUILD_SUNDIALS_VERSION);
}

#[test]
fn loaded_sundials_libraries_are_the_system_ones() {
    // Make sure the libraries are loaded (they are linked, but be explicit).
    let ctx = Context::new().unwrap();
    let _band =
        LinearSolver::for_spec(&ctx, 3, &LinearSolverSpec::Band { upper: 1, lower: 1 }).unwrap();
    let _kin = Kinsol::new(Id, 2, LinearSolverSpec::Dense, &Default::default()).unwrap();
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
    let libs: Vec<&str> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.contains("libsundials_"))
        .collect();
    assert!(
        libs.iter().any(|p| p.contains("libsundials_kinsol")),
        "{libs:?}"
    );
    for p in &libs {
        assert!(
            p.starts_with("/usr/lib/") || p.starts_with("/lib/"),
            "not a system library: {p}"
        );
    }
}

#[test]
fn no_vendored_sundials_sys_build() {
    let build = Path::new(eyeshell_sundials::BUILD_OUT_DIR)
        .parent()
        .and_then(Path::parent)
        .unwrap();
    for e in std::fs::read_dir(build).unwrap().flatten() {
        if e.file_name().to_string_lossy().starts_with("sundials-sys-") {
            for sub in ["out/build", "out/lib"] {
                assert!(
                    !e.path().join(sub).exists(),
                    "vendored SUNDIALS at {}",
                    e.path().join(sub).display()
                );
            }
        }
    }
}
