//! Build script: insist on the system (Debian) SUNDIALS 6.x, refuse sundials-sys's vendored
//! fallback, and bind what sundials-sys does not (the KLU linear solver, the version query).
//!
//! Why: sundials-sys silently compiles its own SUNDIALS with cmake when it cannot use the
//! system one. That copy is a different version (7.x), a different build configuration and
//! has no KLU, so results would silently differ from the ones we validate. We would rather
//! fail the build with one clear instruction.
//!
//! Note on ordering: cargo only orders build-script *runs* for dependencies that declare
//! `links`, which sundials-sys does not, so its build script is not guaranteed to have run
//! before this one. The vendored-directory check below is therefore a best effort; the
//! header check uses the same condition sundials-sys uses (system headers, major ≥ 6), so if
//! it passes sundials-sys binds the system headers too. `cargo run -p vendor-check` and
//! `tests/sundials/linkage.rs` check what the binaries actually load.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};

const APT_HINT: &str =
    "apt-get install -y libsundials-dev libclang-dev libsuitesparse-dev pkg-config";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    for var in [
        "SUNDIALS_INCLUDE_DIR",
        "SUNDIALS_LIBRARY_DIR",
        "SUITESPARSE_INCLUDE_DIR",
        "EYESHELL_NO_KLU",
    ] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    println!("cargo::rustc-check-cfg=cfg(eyeshell_klu)");

    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));

    // 1. The system SUNDIALS headers, version 6.x.
    let include_dir = env::var("SUNDIALS_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from("/usr/include"));
    let config_h = include_dir.join("sundials/sundials_config.h");
    println!("cargo:rerun-if-changed={}", config_h.display());
    let (major, version) = match sundials_version(&config_h) {
        Ok(v) => v,
        Err(why) => panic!(
            "eyeshell needs the system SUNDIALS 6.x headers, but {why}. Install them with: {APT_HINT} \
             (or set SUNDIALS_INCLUDE_DIR to the directory holding sundials/sundials_config.h)"
        ),
    };
    if !(6..7).contains(&major) {
        panic!(
            "eyeshell needs SUNDIALS 6.x, but {} says version {version}. Install Debian's 6.x with: {APT_HINT} \
             (or set SUNDIALS_INCLUDE_DIR to a SUNDIALS 6.x include directory)",
            config_h.display()
        );
    }

    // 2. Refuse sundials-sys's vendored build (see the ordering note above).
    if let Some(vendored) = vendored_sundials_sys(&out_dir) {
        panic!(
            "sundials-sys built its vendored SUNDIALS (found {}), so the binary would not use the \
             system SUNDIALS {version}. Fix: make sure `{APT_HINT}` is done and libclang works, \
             then run `cargo clean -p sundials-sys` and build again.",
            vendored.display()
        );
    }

    println!(
        "cargo:rustc-env=EYESHELL_SUNDIALS_INCLUDE={}",
        include_dir.display()
    );
    println!("cargo:rustc-env=EYESHELL_SUNDIALS_VERSION={version}");
    if let Ok(dir) = env::var("SUNDIALS_LIBRARY_DIR") {
        println!("cargo:rustc-link-search=native={dir}");
    }

    // 3. Bindings sundials-sys lacks: the version query (always) and KLU (when present).
    let version_h = include_dir.join("sundials/sundials_version.h");
    let version_bindings = bindgen::Builder::default()
        .header_contents(
            "eyeshell_version.h",
            "#include <sundials/sundials_version.h>\n",
        )
        .clang_arg(format!("-I{}", include_dir.display()))
        .allowlist_function("SUNDIALSGetVersion.*")
        .generate()
        .unwrap_or_else(|e| {
            panic!(
                "bindgen could not read {} ({e}). Install: {APT_HINT}",
                version_h.display()
            )
        });
    version_bindings
        .write_to_file(out_dir.join("version_bindings.rs"))
        .expect("write version_bindings.rs");

    match klu(&include_dir, &out_dir) {
        Ok(()) => {
            println!("cargo:rustc-cfg=eyeshell_klu");
            println!("cargo:rustc-link-lib=dylib=sundials_sunlinsolklu");
            println!("cargo:rustc-link-lib=dylib=klu");
        }
        Err(why) => {
            println!("cargo:warning=eyeshell: building without the KLU sparse solver: {why}");
        }
    }
}

/// (major, "x.y.z") from sundials_config.h.
fn sundials_version(config_h: &Path) -> Result<(u32, String), String> {
    let text = fs::read_to_string(config_h)
        .map_err(|e| format!("{} could not be read ({e})", config_h.display()))?;
    let define = |name: &str| -> Option<String> {
        text.lines().find_map(|line| {
            let mut words = line.split_whitespace();
            (words.next() == Some("#define") && words.next() == Some(name))
                .then(|| words.next().map(|v| v.trim_matches('"').to_string()))
                .flatten()
        })
    };
    let major: u32 = define("SUNDIALS_VERSION_MAJOR")
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| format!("{} has no SUNDIALS_VERSION_MAJOR", config_h.display()))?;
    let version = define("SUNDIALS_VERSION").unwrap_or_else(|| major.to_string());
    Ok((major, version))
}

/// A sibling `sundials-sys-*/out/{build,lib}` directory: the trace of a vendored cmake build.
fn vendored_sundials_sys(out_dir: &Path) -> Option<PathBuf> {
    // OUT_DIR = target/<profile>/build/eyeshell-sundials-<hash>/out
    let build_dir = out_dir.parent()?.parent()?;
    let entries = fs::read_dir(build_dir).ok()?;
    for entry in entries.flatten() {
        if !entry
            .file_name()
            .to_string_lossy()
            .starts_with("sundials-sys-")
        {
            continue;
        }
        for sub in ["out/build", "out/lib"] {
            let p = entry.path().join(sub);
            if p.is_dir() {
                return Some(p);
            }
        }
    }
    None
}

fn library_dirs() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Ok(d) = env::var("SUNDIALS_LIBRARY_DIR") {
        dirs.push(PathBuf::from(d));
    }
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let multiarch = format!("{arch}-linux-gnu");
    for d in [
        format!("/usr/lib/{multiarch}"),
        "/usr/lib".into(),
        format!("/lib/{multiarch}"),
        "/usr/lib64".into(),
        "/usr/local/lib".into(),
    ] {
        dirs.push(PathBuf::from(d));
    }
    dirs
}

fn find_library(name: &str) -> Option<PathBuf> {
    library_dirs()
        .into_iter()
        .map(|d| d.join(format!("lib{name}.so")))
        .find(|p| p.exists())
}

/// Generate OUT_DIR/klu_bindings.rs, or say why KLU is not available.
fn klu(include_dir: &Path, out_dir: &Path) -> Result<(), String> {
    if env::var_os("EYESHELL_NO_KLU").is_some() {
        return Err("EYESHELL_NO_KLU is set".into());
    }
    let klu_h = include_dir.join("sunlinsol/sunlinsol_klu.h");
    if !klu_h.exists() {
        return Err(format!(
            "{} not found (install libsundials-dev)",
            klu_h.display()
        ));
    }
    let ss_include = env::var("SUITESPARSE_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from("/usr/include/suitesparse"));
    if !ss_include.join("klu.h").exists() {
        return Err(format!(
            "{}/klu.h not found (install libsuitesparse-dev)",
            ss_include.display()
        ));
    }
    for lib in ["sundials_sunlinsolklu", "klu"] {
        if find_library(lib).is_none() {
            return Err(format!(
                "lib{lib}.so not found (install libsundials-dev libsuitesparse-dev)"
            ));
        }
    }
    let bindings = bindgen::Builder::default()
        .header_contents("eyeshell_klu.h", "#include <sunlinsol/sunlinsol_klu.h>\n")
        .clang_arg(format!("-I{}", include_dir.display()))
        .clang_arg(format!("-I{}", ss_include.display()))
        // The constructor, ReInit and SetOrdering; not the getters of KLU's internal structs.
        .allowlist_function("SUNLinSol_KLU(ReInit|SetOrdering)?")
        .allowlist_var("SUNKLU_.*")
        // Every type they use is SUNDIALS-generic and comes from sundials-sys (same types,
        // so a KLU solver is an ordinary sundials_sys::SUNLinearSolver).
        .allowlist_recursively(false)
        .blocklist_type(
            "SUNMatrix|SUNLinearSolver|SUNContext|N_Vector|sunindextype|realtype|sunrealtype",
        )
        .blocklist_type(
            "_generic_.*|_SUNContext|SUNLinearSolver_Type|SUNLinearSolver_ID|booleantype",
        )
        .raw_line("#[allow(unused_imports)]\nuse sundials_sys::*;")
        .generate()
        .map_err(|e| format!("bindgen failed on {} ({e})", klu_h.display()))?;
    bindings
        .write_to_file(out_dir.join("klu_bindings.rs"))
        .map_err(|e| format!("could not write klu_bindings.rs ({e})"))?;
    Ok(())
}
