//! vendor-check: does eyeshell run on Debian's SUNDIALS 6.x, and which linear solvers work?
//!
//! Prints the SUNDIALS version linked at run time and the headers the build used, the
//! SUNDIALS/KLU shared libraries actually loaded (from /proc/self/maps, after creating a
//! context, dense/band/KLU solvers, KINSOL memory and IDAS memory with sensitivities), solves
//! a 3×3 system with each linear solver and checks one IDAS sensitivity against its exact
//! value; IDA must come from libsundials_idas, and libsundials_ida must not be loaded too. Exits 1 if a SUNDIALS library is not from /usr/lib or /lib, the version is
//! not 6.x (or differs from the headers), the build holds a vendored sundials-sys build, or
//! a solver that was built fails.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use eyeshell_sundials::{
    self, CallbackResult, Context, DaeSystem, Ida, IdaLinearSolver, IdaOptions, JacobianMatrix,
    Kinsol, KinsolOptions, LinearSolver, LinearSolverSpec, MatrixSink, NVector, NonlinearSystem,
    SensitivityOptions,
};

const A: [[f64; 3]; 3] = [[4.0, -1.0, 0.0], [-1.0, 4.0, -1.0], [0.0, -1.0, 4.0]];
const X: [f64; 3] = [1.0, -2.0, 3.0];

fn solve_3x3(spec: &LinearSolverSpec) -> Result<f64, eyeshell_sundials::SundialsError> {
    let ctx = Context::new()?;
    let (mut a, mut ls) = LinearSolver::for_spec(&ctx, 3, spec)?;
    {
        let mut v = a.view_mut();
        for (i, row) in A.iter().enumerate() {
            for (j, &aij) in row.iter().enumerate() {
                if aij != 0.0 {
                    v.set(i, j, aij);
                }
            }
        }
    }
    let b: Vec<f64> = A
        .iter()
        .map(|row| row.iter().zip(X).map(|(a, x)| a * x).sum())
        .collect();
    let b = NVector::from_slice(&ctx, &b)?;
    let mut x = NVector::new(&ctx, 3)?;
    ls.setup(&mut a)?;
    ls.solve(&mut a, &mut x, &b)?;
    Ok(x.as_slice()
        .iter()
        .zip(X)
        .map(|(g, w)| (g - w).abs())
        .fold(0.0, f64::max))
}

/// F(u) = u - 1, to make KINSOL memory exist (and load libsundials_kinsol).
struct Shift;

impl NonlinearSystem for Shift {
    fn residual(&mut self, u: &[f64], f: &mut [f64]) -> CallbackResult {
        f.iter_mut().zip(u).for_each(|(f, u)| *f = u - 1.0);
        Ok(())
    }

    fn jacobian(&mut self, u: &[f64], mut jac: JacobianMatrix<'_>) -> CallbackResult {
        (0..u.len()).for_each(|i| jac.set(i, i, 1.0));
        Ok(())
    }
}

/// y' = −p y, p = 1, as a DAE F = y' + p y, with its sensitivity s = ∂y/∂p (s' = −p s − y):
/// to make IDAS memory with sensitivities exist (and load libsundials_idas), and check it.
struct Decay;

impl DaeSystem for Decay {
    fn residual(&mut self, _t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> CallbackResult {
        r[0] = yp[0] + y[0];
        Ok(())
    }

    fn sensitivity_residual(
        &mut self,
        _t: f64,
        y: &[f64],
        _yp: &[f64],
        _r: &[f64],
        ys: &[&[f64]],
        yps: &[&[f64]],
        rs: &mut [&mut [f64]],
    ) -> CallbackResult {
        rs[0][0] = yps[0][0] + ys[0][0] + y[0];
        Ok(())
    }
}

/// IDAS's sensitivity of Decay at t = 1 against the exact −t e^{−t}: the error.
fn idas_sensitivity() -> Result<(Ida<Decay>, f64), eyeshell_sundials::SundialsError> {
    let options = IdaOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..IdaOptions::default()
    };
    let linear = IdaLinearSolver::Dense {
        user_jacobian: false,
    };
    let mut ida = Ida::new(Decay, 0.0, &[1.0], &[-1.0], linear, &options)?;
    let sens = SensitivityOptions {
        error_control: true,
        scales: vec![1.0],
    };
    ida.init_sensitivities(&[vec![0.0]], &[vec![-1.0]], &sens)?;
    let (mut y, mut yp) = ([0.0], [0.0]);
    let t = ida.advance_to(1.0, &mut y, &mut yp)?;
    let mut s = vec![vec![0.0]];
    ida.sensitivities_at(t, &mut s)?;
    let err = (s[0][0] + t * (-t).exp()).abs();
    Ok((ida, err))
}

fn loaded_libraries() -> Vec<String> {
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap_or_default();
    let mut libs: Vec<String> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.contains("libsundials_") || p.contains("/libklu"))
        .map(String::from)
        .collect();
    libs.sort();
    libs.dedup();
    libs
}

fn vendored_builds() -> Vec<PathBuf> {
    let Some(build) = Path::new(eyeshell_sundials::BUILD_OUT_DIR)
        .parent()
        .and_then(Path::parent)
    else {
        return vec![];
    };
    let Ok(entries) = std::fs::read_dir(build) else {
        return vec![];
    };
    let mut found = vec![];
    for e in entries.flatten() {
        if e.file_name().to_string_lossy().starts_with("sundials-sys-") {
            for sub in ["out/build", "out/lib"] {
                let p = e.path().join(sub);
                if p.exists() {
                    found.push(p);
                }
            }
        }
    }
    found
}

fn main() -> ExitCode {
    let mut problems: Vec<String> = vec![];

    let version = eyeshell_sundials::version();
    println!("SUNDIALS linked at run time: {version}");
    println!(
        "SUNDIALS headers at build time: {} (version {})",
        eyeshell_sundials::BUILD_SUNDIALS_INCLUDE,
        eyeshell_sundials::BUILD_SUNDIALS_VERSION
    );
    if !version.starts_with("6.") {
        problems.push(format!("the linked SUNDIALS is {version}, not 6.x"));
    }
    if version != eyeshell_sundials::BUILD_SUNDIALS_VERSION {
        problems.push(format!(
            "the linked SUNDIALS ({version}) differs from the headers ({})",
            eyeshell_sundials::BUILD_SUNDIALS_VERSION
        ));
    }

    println!("Linear solvers (3x3 solve, max error):");
    let mut specs = vec![
        ("dense", LinearSolverSpec::Dense),
        ("band", LinearSolverSpec::Band { upper: 1, lower: 1 }),
    ];
    let klu_pattern = LinearSolverSpec::Klu {
        row_ptr: vec![0, 2, 5, 7],
        col_idx: vec![0, 1, 0, 1, 2, 1, 2],
    };
    if eyeshell_sundials::klu_available() {
        specs.push(("KLU", klu_pattern));
    } else {
        println!("  KLU:   not available (built without sunlinsol_klu; apt-get install -y libsuitesparse-dev libsundials-dev, then rebuild)");
    }
    for (name, spec) in &specs {
        match solve_3x3(spec) {
            Ok(err) if err < 1e-12 => println!("  {name:<6} ok ({err:.1e})"),
            Ok(err) => {
                println!("  {name:<6} WRONG ({err:.1e})");
                problems.push(format!(
                    "the {name} solver gave a wrong solution (error {err:.1e})"
                ));
            }
            Err(e) => {
                println!("  {name:<6} FAILED: {e}");
                problems.push(format!("the {name} solver failed: {e}"));
            }
        }
    }

    // Keep objects of every kind alive while reading the memory map.
    let kinsol = Kinsol::new(
        Shift,
        3,
        LinearSolverSpec::Band { upper: 1, lower: 1 },
        &KinsolOptions::default(),
    );
    let solvers: Vec<_> = Context::new()
        .map(|ctx| {
            specs
                .iter()
                .filter_map(|(_, s)| LinearSolver::for_spec(&ctx, 3, s).ok())
                .collect()
        })
        .unwrap_or_default();
    match &kinsol {
        Ok(_) => println!("KINSOL: memory created"),
        Err(e) => problems.push(format!("KINSOL could not be created: {e}")),
    }
    let idas = idas_sensitivity();
    match &idas {
        Ok((_, err)) if *err < 1e-7 => {
            println!("IDAS: forward sensitivity of y' = -p y at t = 1 ok ({err:.1e})")
        }
        Ok((_, err)) => problems.push(format!(
            "IDAS gave a wrong sensitivity of y' = -p y (error {err:.1e})"
        )),
        Err(e) => problems.push(format!("IDAS with sensitivities failed: {e}")),
    }
    let libs = loaded_libraries();
    println!("Loaded libraries:");
    for p in &libs {
        let system = p.starts_with("/usr/lib/") || p.starts_with("/lib/");
        println!(
            "  {p}{}",
            if system {
                ""
            } else {
                "   <-- NOT a system library"
            }
        );
        if !system && p.contains("libsundials_") {
            problems.push(format!("{p} is not under /usr/lib or /lib"));
        }
    }
    if !libs.iter().any(|p| p.contains("libsundials_")) {
        problems.push("no libsundials_*.so is loaded (statically linked vendored copy?)".into());
    }
    // IDA's functions come from IDAS (a superset with the same names); both at once would
    // leave which one answers to the loader's order.
    if !libs.iter().any(|p| p.contains("libsundials_idas.")) {
        problems.push("libsundials_idas is not loaded (IDA must come from IDAS)".into());
    }
    if libs.iter().any(|p| p.contains("libsundials_ida.")) {
        problems.push("libsundials_ida is loaded beside libsundials_idas (link one)".into());
    }
    drop((kinsol, solvers, idas));

    let vendored = vendored_builds();
    if vendored.is_empty() {
        println!("Build directory: no vendored sundials-sys build");
    } else {
        for p in &vendored {
            problems.push(format!(
                "sundials-sys built its vendored SUNDIALS at {} (fix: apt-get install -y libsundials-dev libclang-dev libsuitesparse-dev pkg-config; cargo clean -p sundials-sys)",
                p.display()
            ));
        }
    }

    if problems.is_empty() {
        println!("OK: eyeshell uses the system SUNDIALS {version}");
        ExitCode::SUCCESS
    } else {
        for p in &problems {
            println!("FAIL: {p}");
        }
        ExitCode::FAILURE
    }
}
