//! The .mat and .npz readers on files made by the real writers (tests/fixtures, written by
//! tests/fixtures/make_fixtures.py with SciPy and NumPy): every value as the script's
//! formulas give it, bit for bit; and `eyeshell compare` reading them end to end.

use crate::support::*;
use eyeshell::interop::mat::{self, MatValue};
use eyeshell::interop::npz::{self, NpyArray};
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    repo().join("tests/fixtures").join(name)
}

const N: usize = 11;

/// x[j] = j / 10, as `np.arange(N) / (N - 1)`.
fn x() -> Vec<f64> {
    (0..N).map(|j| j as f64 / (N - 1) as f64).collect()
}

/// Row i of y: (i + 1) x + i.
fn y_row(i: usize) -> Vec<f64> {
    x().iter().map(|x| (i + 1) as f64 * x + i as f64).collect()
}

fn scaled(v: Vec<f64>, k: f64) -> Vec<f64> {
    v.into_iter().map(|a| k * a).collect()
}

fn var<'a>(vars: &'a [(String, MatValue)], name: &str) -> &'a MatValue {
    &vars
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .1
}

fn array<'a>(arrays: &'a [(String, NpyArray)], name: &str) -> &'a NpyArray {
    &arrays
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no array {name}"))
        .1
}

fn dims(v: &MatValue) -> Vec<usize> {
    v.dims().unwrap().to_vec()
}

/// bvp4c's solution structure as the script writes it (y and yp times `scale`).
fn assert_sol(fields: &[(String, MatValue)], solver: &str, scale: f64, what: &str) {
    let names: Vec<&str> = fields.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["solver", "x", "y", "yp", "stats"], "{what}");
    let sol = MatValue::Struct(fields.to_vec());
    assert_eq!(sol.field("solver").unwrap().text(), Some(solver), "{what}");
    let xv = sol.field("x").unwrap();
    assert_eq!(dims(xv), [1, N], "{what}");
    assert_bits(xv.data().unwrap(), &x(), "x");
    let y = sol.field("y").unwrap();
    let yp = sol.field("yp").unwrap();
    assert_eq!(dims(y), [5, N], "{what}");
    assert_eq!(dims(yp), [5, N], "{what}");
    for i in 0..5 {
        assert_bits(&y.row_of(i).unwrap(), &scaled(y_row(i), scale), "y");
        assert_bits(&yp.row_of(i).unwrap(), &[scale * (i + 1) as f64; N], "yp");
    }
    let stats = sol.field("stats").unwrap();
    for (name, v) in [
        ("nmeshpoints", 11.0),
        ("maxres", 1e-9),
        ("nODEevals", 100.0),
        ("nBCevals", 5.0),
    ] {
        assert_eq!(stats.field(name).unwrap().data(), Some(&[v][..]), "{name}");
    }
}

#[test]
fn scipy_struct_plain_and_compressed() {
    for f in ["scipy_sol.mat", "scipy_sol_z.mat"] {
        let vars = mat::read(&fixture(f)).unwrap();
        assert_eq!(vars.len(), 1, "{f}");
        let fields = var(&vars, "sol").struct_element(0).unwrap();
        assert_sol(fields, "bvp4c", 1.0, f);
    }
}

/// GNU Octave 7's `save -v7` (compressed) and `-v6` of the same bvp4c-style `sol`
/// (tests/fixtures/make_fixtures.py gives the command).
#[test]
fn octave_struct_v7_and_v6() {
    for f in ["octave_sol_v7.mat", "octave_sol_v6.mat"] {
        let vars = mat::read(&fixture(f)).unwrap();
        assert_eq!(vars.len(), 1, "{f}");
        let fields = var(&vars, "sol").struct_element(0).unwrap();
        assert_sol(fields, "bvp4c", 1.0, f);
    }
}

#[test]
fn scipy_struct_array_keeps_every_element() {
    let vars = mat::read(&fixture("scipy_structarray.mat")).unwrap();
    let sol = var(&vars, "sol");
    let MatValue::StructArray { dims, elements } = sol else {
        panic!("{sol:?}")
    };
    assert_eq!(dims, &[1, 2]);
    assert_eq!(elements.len(), 2);
    assert_sol(sol.struct_element(0).unwrap(), "bvp4c", 1.0, "sol(1)");
    assert_sol(sol.struct_element(1).unwrap(), "bvp5c", 2.0, "sol(2)");
    assert!(sol.struct_element(2).is_none());
}

#[test]
fn scipy_arrays_of_every_class() {
    for f in ["scipy_arrays.mat", "scipy_arrays_z.mat"] {
        let vars = mat::read(&fixture(f)).unwrap();
        let names: Vec<&str> = vars.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "Sigma", "h", "time", "M", "A3", "empty", "i8", "u8", "i16", "u16", "i32", "u32",
                "i64", "u64", "flags", "name", "greek", "rows", "cells", "nested"
            ],
            "{f}"
        );
        // 1-D arrays are rows (oned_as='row').
        assert_eq!(dims(var(&vars, "Sigma")), [1, N]);
        assert_bits(var(&vars, "Sigma").data().unwrap(), &x(), "Sigma");
        let h: Vec<f64> = x().iter().map(|x| 0.5 + x).collect();
        assert_bits(var(&vars, "h").data().unwrap(), &h, "h");
        assert_eq!(var(&vars, "time"), &MatValue::scalar(0.25));
        // M[i, j] = 4 i + j, column-major.
        let m = var(&vars, "M");
        assert_eq!(dims(m), [3, 4]);
        for i in 0..3 {
            let row: Vec<f64> = (0..4).map(|j| (4 * i + j) as f64).collect();
            assert_eq!(m.row_of(i).unwrap(), row);
        }
        // A3[i, j, k] = 12 i + 4 j + k at column-major index i + 2 j + 6 k.
        let a3 = var(&vars, "A3");
        assert_eq!(dims(a3), [2, 3, 4]);
        let d = a3.data().unwrap();
        for (i, j, k) in
            (0..2).flat_map(|i| (0..3).flat_map(move |j| (0..4).map(move |k| (i, j, k))))
        {
            assert_eq!(d[i + 2 * j + 6 * k], (12 * i + 4 * j + k) as f64);
        }
        assert_eq!(dims(var(&vars, "empty")), [0, 0]);
        assert!(var(&vars, "empty").data().unwrap().is_empty());
        let two53 = 9007199254740992.0;
        for (name, want) in [
            ("i8", [-128.0, 0.0, 127.0]),
            ("u8", [0.0, 200.0, 255.0]),
            ("i16", [-32768.0, 1.0, 32767.0]),
            ("u16", [0.0, 2.0, 65535.0]),
            ("i32", [-2147483648.0, 3.0, 2147483647.0]),
            ("u32", [0.0, 4.0, 4294967295.0]),
            ("i64", [-two53, 5.0, two53]),
            ("u64", [0.0, 6.0, two53]),
            ("flags", [1.0, 0.0, 1.0]),
        ] {
            assert_eq!(dims(var(&vars, name)), [1, 3], "{name}");
            assert_eq!(var(&vars, name).data().unwrap(), &want, "{f} {name}");
        }
        assert_eq!(var(&vars, "name").text(), Some("bvp4c"));
        assert_eq!(var(&vars, "greek").text(), Some("σ-Σ"));
        assert_eq!(var(&vars, "rows").text(), Some("ab\ncd"));
        let MatValue::Cell { dims: cd, cells } = var(&vars, "cells") else {
            panic!("cells")
        };
        assert_eq!(cd, &[1, 3]);
        assert_bits(cells[0].data().unwrap(), &x(), "cells{1}");
        assert_eq!(cells[1].text(), Some("text"));
        assert_eq!(cells[2], MatValue::scalar(7.0));
        let c = var(&vars, "nested")
            .field("a")
            .and_then(|a| a.field("b"))
            .and_then(|b| b.field("c"));
        assert_eq!(c, Some(&MatValue::scalar(1.5)));
    }
}

#[test]
fn scipy_single_precision_and_columns() {
    let vars = mat::read(&fixture("scipy_single.mat")).unwrap();
    let xs: Vec<f64> = x().iter().map(|&v| v as f32 as f64).collect();
    assert_eq!(dims(var(&vars, "x")), [1, N]);
    assert_bits(var(&vars, "x").data().unwrap(), &xs, "single x");
    for i in 0..5 {
        let row: Vec<f64> = y_row(i).iter().map(|&v| v as f32 as f64).collect();
        assert_bits(&var(&vars, "y").row_of(i).unwrap(), &row, "single y");
    }
    let vars = mat::read(&fixture("scipy_column.mat")).unwrap();
    assert_eq!(dims(var(&vars, "x")), [N, 1]);
    assert_bits(var(&vars, "x").data().unwrap(), &x(), "column x");
    assert_eq!(dims(var(&vars, "h")), [N, 1]);
}

#[test]
fn scipy_sparse_is_refused_on_one_line() {
    let e = mat::read(&fixture("scipy_sparse.mat"))
        .unwrap_err()
        .to_string();
    assert!(
        e.ends_with("scipy_sparse.mat: variable J: sparse matrices are not read (save it as a full matrix: full(...))"),
        "{e}"
    );
}

fn assert_xy(arrays: &[(String, NpyArray)], what: &str) {
    let xa = array(arrays, "x");
    assert_eq!(xa.shape, [N], "{what}");
    assert_bits(&xa.data, &x(), "x");
    let y = array(arrays, "y");
    assert_eq!(y.shape, [5, N], "{what}");
    for i in 0..5 {
        assert_bits(&y.data[i * N..(i + 1) * N], &y_row(i), what);
    }
}

#[test]
fn numpy_savez_stored_deflated_fortran_big_endian() {
    for f in ["np_savez.npz", "np_savez_compressed.npz"] {
        let arrays = npz::read(&fixture(f)).unwrap();
        let names: Vec<&str> = arrays.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["x", "y", "yp", "time"], "{f}");
        assert_xy(&arrays, f);
        let yp = array(&arrays, "yp");
        for i in 0..5 {
            assert_eq!(yp.data[i * N..(i + 1) * N], [(i + 1) as f64; N]);
        }
        assert_eq!(array(&arrays, "time"), &NpyArray::scalar(0.25));
    }
    // Fortran order: transposed into C order.
    let arrays = npz::read(&fixture("np_fortran.npz")).unwrap();
    assert_xy(&arrays, "np_fortran.npz");
    let yt = array(&arrays, "yT");
    assert_eq!(yt.shape, [N, 5]);
    for j in 0..N {
        for i in 0..5 {
            assert_eq!(yt.data[j * 5 + i].to_bits(), y_row(i)[j].to_bits());
        }
    }
    let arrays = npz::read(&fixture("np_bigendian.npz")).unwrap();
    assert_xy(&arrays, "np_bigendian.npz");
    let f4: Vec<f64> = x().iter().map(|&v| v as f32 as f64).collect();
    assert_bits(&array(&arrays, "f4").data, &f4, "f4");
    assert_eq!(array(&arrays, "i4").data, [-2.0, 0.0, 2147483647.0]);
    assert_eq!(array(&arrays, "u2").data, [0.0, 1.0, 65535.0]);
}

#[test]
fn numpy_every_dtype_and_npy_version() {
    let arrays = npz::read(&fixture("np_dtypes.npz")).unwrap();
    let two53 = 9007199254740992.0;
    let f4: Vec<f64> = x().iter().map(|&v| v as f32 as f64).collect();
    assert_bits(&array(&arrays, "f4").data, &f4, "f4");
    for (name, want) in [
        ("i1", [-128.0, 0.0, 127.0]),
        ("u1", [0.0, 200.0, 255.0]),
        ("i2", [-32768.0, 1.0, 32767.0]),
        ("u2", [0.0, 2.0, 65535.0]),
        ("i4", [-2147483648.0, 3.0, 2147483647.0]),
        ("u4", [0.0, 4.0, 4294967295.0]),
        ("i8", [-two53, 5.0, two53]),
        ("u8", [0.0, 6.0, two53]),
        ("b1", [1.0, 0.0, 1.0]),
    ] {
        assert_eq!(array(&arrays, name).shape, [3], "{name}");
        assert_eq!(array(&arrays, name).data, want, "{name}");
    }
    assert_eq!(array(&arrays, "scalar"), &NpyArray::scalar(-7.0));
    assert_eq!(array(&arrays, "empty").shape, [0, 3]);
    let c: Vec<f64> = (0..24).map(f64::from).collect();
    for name in ["A3", "A3F"] {
        assert_eq!(array(&arrays, name).shape, [2, 3, 4], "{name}");
        assert_eq!(array(&arrays, name).data, c, "{name}");
    }
    for f in ["np_fortran.npy", "np_v2.npy", "np_v3.npy"] {
        let a = npz::parse_npy(&std::fs::read(fixture(f)).unwrap()).unwrap();
        assert_eq!(a.shape, [5, N], "{f}");
        for i in 0..5 {
            assert_bits(&a.data[i * N..(i + 1) * N], &y_row(i), f);
        }
    }
}

/// `eyeshell compare` reads the fixtures end to end: bvp4c's struct (element 1 of a struct
/// array), a Fortran-ordered .npz; the fixtures are not this run's solution, so the
/// comparison reads, reports and fails (exit 1), and a sparse file is refused (exit 2).
#[test]
fn compare_reads_the_fixtures() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("solve");
    ok(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "solver.nodes=21",
        "--out",
        s(&run),
        "--quiet",
    ]);
    for f in [
        "scipy_sol.mat",
        "scipy_sol_z.mat",
        "octave_sol_v7.mat",
        "octave_sol_v6.mat",
        "scipy_structarray.mat",
        "np_fortran.npz",
        "np_bigendian.npz",
    ] {
        let r = eyeshell(&["compare", s(&run), s(&fixture(f))]);
        assert!(!r.stderr.contains("panicked"), "{f}: {}", r.stderr);
        assert_eq!(r.code, Some(1), "{f}: {}{}", r.stdout, r.stderr);
        assert!(r.stdout.contains("kappa"), "{f}: {}", r.stdout);
    }
    assert_fails(
        &eyeshell(&["compare", s(&run), s(&fixture("scipy_sparse.mat"))]),
        2,
        "sparse matrices are not read",
    );
    // --field picks the struct (and the element of a struct array) of the reference.
    let sa = fixture("scipy_structarray.mat");
    ok(&["compare", s(&sa), s(&sa), "--field", "sol(1)", "--tol", "0"]);
    let r = eyeshell(&["compare", s(&sa), s(&sa), "--field", "sol(2)"]);
    assert_eq!(r.code, Some(1), "sol(2) is y scaled by 2: {}", r.stdout);
    for (spec, needle) in [
        ("sol(3)", "element 3 asked for, but the struct array has 2"),
        ("nope", "no such variable (it has sol)"),
        ("sol(0)", "NAME(K)"),
        ("sol(x", "NAME(K)"),
    ] {
        let r = eyeshell(&["compare", s(&sa), s(&sa), "--field", spec]);
        assert_eq!(r.code, Some(2), "{spec}: {}", r.stderr);
        assert!(r.stderr.contains(needle), "{spec}: {}", r.stderr);
        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    }

    // Hostile files: one line each, exit 2, no panic text.
    let nested = dir.path().join("nested.mat");
    std::fs::write(&nested, nested_mat(5000)).unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&run), s(&nested)]),
        2,
        &format!(
            "nested.mat: variable sol{}: structs or cells nested more than 32 deep",
            ".a".repeat(32)
        ),
    );
    let bomb = dir.path().join("bomb.npz");
    let zeros = NpyArray::vector(&vec![0.0; 2 << 20]);
    std::fs::write(&bomb, npz::encode(&[("x".into(), zeros)]).unwrap()).unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&run), s(&bomb)]),
        2,
        "bomb.npz: x.npy: compressed data inflates to more than 128 times the file's size",
    );
    let v73 = dir.path().join("v73.mat");
    let mut bytes = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1".to_vec();
    bytes.resize(512, b' ');
    bytes.extend_from_slice(b"\x89HDF\r\n\x1a\n");
    bytes.resize(4096, 0);
    std::fs::write(&v73, bytes).unwrap();
    assert_fails(
        &eyeshell(&["compare", s(&run), s(&v73)]),
        2,
        "save('ref_v7.mat', 'sol', '-v7')",
    );
}

/// A .mat file (little-endian, uncompressed) of `sol.a.a.a…`: `depth` nested 1×1 structs
/// of one field `a`, the innermost an empty array; built outside in, without recursion.
fn nested_mat(depth: usize) -> Vec<u8> {
    fn element(ty: u32, data: &[u8]) -> Vec<u8> {
        let mut out = ty.to_le_bytes().to_vec();
        out.extend_from_slice(&(data.len() as u32).to_le_bytes());
        out.extend_from_slice(data);
        out.resize(out.len().div_ceil(8) * 8, 0);
        out
    }
    let mut v = element(14, &[]);
    for level in (0..depth).rev() {
        let mut body = element(6, &[2, 0, 0, 0, 0, 0, 0, 0]);
        body.extend(element(5, &[1, 0, 0, 0, 1, 0, 0, 0]));
        body.extend(element(1, if level == 0 { b"sol" } else { b"" }));
        body.extend(element(5, &[8, 0, 0, 0]));
        body.extend(element(1, b"a\0\0\0\0\0\0\0"));
        body.extend(v);
        v = element(14, &body);
    }
    let mut file = mat::header();
    file.extend(v);
    file
}

/// compare against an independent solver: SciPy's solve_bvp, split at the
/// thickness jump, tol 1e-8 (tests/fixtures/solve_bvp_reference.py), on 8001 points and on
/// its own non-uniform mesh, against eyeshell at N = 801 (Hermite–Simpson). κ, α_s, r, θ
/// and Q agree within 1e-7; t_s within 1e-6 relative (the N = 801 run's own error next to
/// the pole: at N = 8001 eyeshell meets the reference to 1e-10). A perturbation of 1e-6 in
/// κ at any single reference point fails.
#[test]
fn compare_against_solve_bvp() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    ok(&[
        "solve",
        "scenes/default.toml",
        "--set",
        "material.thickness=nonuniform",
        "--set",
        "solver.epsilon=0.1",
        "--set",
        "solver.nodes=801",
        "--out",
        s(&run),
        "-q",
    ]);
    let dense = fixture("solve_bvp_thick_8001.npz");
    let mesh = fixture("solve_bvp_thick_mesh.npz");
    let out = ok(&[
        "compare",
        s(&run),
        s(&dense),
        s(&mesh),
        "--tol",
        "1e-7",
        "--rtol",
        "1e-6",
    ]);
    assert!(
        out.stdout.contains("12 of 12 field comparisons"),
        "{}",
        out.stdout
    );
    // κ, r, θ and Q to 1e-8 absolute on the dense points.
    let r = eyeshell(&[
        "compare",
        s(&run),
        s(&dense),
        "--tol",
        "1e-8",
        "--rtol",
        "0",
    ]);
    for field in ["kappa", "r", "theta", "Q"] {
        let line = r
            .stdout
            .lines()
            .find(|l| l.trim_start().starts_with(field))
            .unwrap();
        assert!(line.ends_with("ok"), "{field}: {line}");
    }
    // One point of κ off by 1e-6, anywhere: refused.
    let arrays = npz::read(&dense).unwrap();
    let n = arrays.iter().find(|(k, _)| k == "x").unwrap().1.data.len();
    for j in [0, 1, n / 7, n / 2 - 1, n / 2, n / 2 + 1, n - 2, n - 1] {
        let bent: Vec<(String, NpyArray)> = arrays
            .iter()
            .map(|(k, a)| {
                let mut a = a.clone();
                if k == "y" {
                    a.data[j] += 1e-6; // row 0 (κ), point j
                }
                (k.clone(), a)
            })
            .collect();
        let path = dir.path().join("bent.npz");
        npz::write(&path, &bent).unwrap();
        let r = eyeshell(&[
            "compare",
            s(&run),
            s(&path),
            "--tol",
            "1e-7",
            "--rtol",
            "1e-6",
        ]);
        assert_eq!(r.code, Some(1), "point {j}: {}", r.stdout);
        assert!(r.stderr.contains("kappa"), "point {j}: {}", r.stderr);
    }
}
