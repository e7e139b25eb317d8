//! `eyeshell export`: a real small run (elastic N = 21, const growth N = 21) exported as
//! .mat (plain and miCOMPRESSED) and .npz, read back with eyeshell's readers, equals the
//! run's CSV files bit for bit; bad targets are refused cleanly.

use crate::support::*;
use eyeshell::interop::mat::{self, MatValue};
use eyeshell::interop::npz;
use std::path::Path;

fn var<'a>(vars: &'a [(String, MatValue)], name: &str) -> &'a MatValue {
    vars.iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v)
        .unwrap_or_else(|| panic!("no variable {name}"))
}

fn check_elastic_mat(file: &Path, fields: &Path) {
    let vars = mat::read(file).unwrap();
    assert_eq!(vars.len(), 1, "only `sol`");
    let sol = var(&vars, "sol");
    let n = column(fields, "Sigma").len();
    let x = sol.field("x").unwrap();
    assert_eq!(x.dims().unwrap(), &[1, n]);
    assert_bits(x.data().unwrap(), &column(fields, "Sigma"), "sol.x");
    let y = sol.field("y").unwrap();
    assert_eq!(y.dims().unwrap(), &[5, n]);
    for (i, name) in Y_ROWS.iter().enumerate() {
        assert_bits(
            &y.row_of(i).unwrap(),
            &column(fields, name),
            &format!("sol.y({}, :) = {name}", i + 1),
        );
    }
    for name in ELASTIC_EXTRA {
        let v = sol.field(name).unwrap_or_else(|| panic!("no sol.{name}"));
        assert_eq!(v.dims().unwrap(), &[1, n]);
        assert_bits(v.data().unwrap(), &column(fields, name), name);
    }
}

fn check_growth_mat(file: &Path, snapshot: &Path, t: f64) {
    let vars = mat::read(file).unwrap();
    let n = column(snapshot, "Sigma").len();
    for name in GROWTH_VARS {
        let v = var(&vars, name);
        assert_eq!(v.dims().unwrap(), &[1, n], "{name}");
        assert_bits(
            v.data().unwrap(),
            &column(snapshot, name),
            &format!("{}: {name}", file.display()),
        );
    }
    let time = var(&vars, "time");
    assert_eq!(time.dims().unwrap(), &[1, 1]);
    assert_eq!(time.data().unwrap()[0].to_bits(), t.to_bits());
    assert_eq!(vars.len(), GROWTH_VARS.len() + 1);
}

#[test]
fn export_reads_back_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let fields = solve.join("fields.csv");

    // Elastic: .mat plain and compressed, .npz.
    let plain = dir.path().join("solve.mat");
    let packed = dir.path().join("solve-z.mat");
    let npz_file = dir.path().join("solve.npz");
    let r = ok(&[
        "export",
        s(&solve),
        "--mat",
        s(&plain),
        "--npz",
        s(&npz_file),
    ]);
    assert!(
        r.stdout.contains("21") || r.stdout.contains("nodes"),
        "{}",
        r.stdout
    );
    ok(&[
        "export",
        s(&solve),
        "--mat",
        s(&packed),
        "--compress",
        "--quiet",
    ]);
    check_elastic_mat(&plain, &fields);
    check_elastic_mat(&packed, &fields);
    // The compressed file really is made of miCOMPRESSED elements (type 15) and is smaller:
    // this is the reader's compressed path, exercised without SciPy or MATLAB.
    let bytes = std::fs::read(&packed).unwrap();
    assert_eq!(u32::from_le_bytes(bytes[128..132].try_into().unwrap()), 15);
    assert!(bytes.len() < std::fs::read(&plain).unwrap().len());
    let plain_bytes = std::fs::read(&plain).unwrap();
    assert_eq!(
        u32::from_le_bytes(plain_bytes[128..132].try_into().unwrap()),
        14
    );
    assert_eq!(&plain_bytes[124..128], &[0x00, 0x01, b'I', b'M']);
    assert!(plain_bytes.starts_with(b"MATLAB 5.0 MAT-file"));

    let arrays = npz::read(&npz_file).unwrap();
    let get = |name: &str| {
        arrays
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| a)
            .unwrap()
    };
    let n = column(&fields, "Sigma").len();
    assert_eq!(get("x").shape, vec![n]);
    assert_bits(&get("x").data, &column(&fields, "Sigma"), "x");
    assert_eq!(get("y").shape, vec![5, n]);
    for (i, name) in Y_ROWS.iter().enumerate() {
        assert_bits(
            &get("y").data[i * n..(i + 1) * n],
            &column(&fields, name),
            name,
        );
    }
    for name in ELASTIC_EXTRA {
        assert_bits(&get(name).data, &column(&fields, name), name);
    }

    // Growth: a directory with one file per snapshot, named after it.
    let snaps = snapshots(&grow);
    assert!(snaps.len() >= 2);
    for compress in [false, true] {
        let out = dir
            .path()
            .join(if compress { "grow-z" } else { "grow-mat" });
        let mut args = vec!["export", s(&grow), "--mat", s(&out), "--quiet"];
        if compress {
            args.push("--compress");
        }
        ok(&args);
        let mut files: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| !p.ends_with(".eyeshell"))
            .collect();
        files.sort();
        // The series and history beside the snapshots (export_scipy.rs reads them).
        for table in ["history.mat", "series.mat"] {
            let at = files.iter().position(|p| p.ends_with(table)).unwrap();
            files.remove(at);
        }
        assert_eq!(files.len(), snaps.len());
        for (f, (csv_file, t)) in files.iter().zip(&snaps) {
            assert_eq!(f.file_stem(), csv_file.file_stem());
            assert_eq!(f.extension().unwrap(), "mat");
            check_growth_mat(f, csv_file, *t);
        }
    }
    let out = dir.path().join("grow-npz");
    ok(&["export", s(&grow), "--npz", s(&out), "--quiet"]);
    for (csv_file, t) in &snaps {
        let f = out.join(format!(
            "{}.npz",
            csv_file.file_stem().unwrap().to_str().unwrap()
        ));
        let arrays = npz::read(&f).unwrap();
        let get = |name: &str| {
            arrays
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, a)| a)
                .unwrap()
        };
        for name in GROWTH_VARS {
            assert_eq!(get(name).shape.len(), 1);
            assert_bits(&get(name).data, &column(csv_file, name), name);
        }
        assert_eq!(get("time").shape, Vec::<usize>::new());
        assert_eq!(get("time").data, vec![*t]);
    }
    // Exporting again replaces a previous export.
    ok(&["export", s(&grow), "--npz", s(&out), "--quiet"]);
}

#[test]
fn a_partial_growth_run_exports_what_it_has() {
    let dir = tempfile::tempdir().unwrap();
    let (_, grow) = small_runs(dir.path());
    // Keep only the first two snapshots, as a run killed after t = 0.1 would.
    let snaps = snapshots(&grow);
    for (f, _) in &snaps[2..] {
        std::fs::remove_file(f).unwrap();
    }
    let out = dir.path().join("partial");
    ok(&["export", s(&grow), "--mat", s(&out), "--quiet"]);
    assert_eq!(
        std::fs::read_dir(&out).unwrap().count(),
        5,
        "2 snapshots, series.mat, history.mat and .eyeshell"
    );
    let f = out.join(format!(
        "{}.mat",
        snaps[1].0.file_stem().unwrap().to_str().unwrap()
    ));
    check_growth_mat(&f, &snaps[1].0, snaps[1].1);
}

#[test]
fn bad_exports_fail_cleanly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    // Not a run directory.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let r = eyeshell(&["export", s(&empty), "--mat", s(&dir.path().join("x.mat"))]);
    assert_fails(&r, 2, "summary.json");
    assert!(!dir.path().join("x.mat").exists());
    // No format.
    let r = eyeshell(&["export", s(&solve)]);
    assert_eq!(r.code, Some(2));
    // An elastic solve exports to a file, not into a directory.
    let r = eyeshell(&["export", s(&solve), "--mat", s(&empty)]);
    assert_fails(&r, 2, "is a directory");
    assert_eq!(std::fs::read_dir(&empty).unwrap().count(), 0);
    // A growth export does not replace a directory holding other things.
    let foreign = dir.path().join("foreign");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let r = eyeshell(&["export", s(&grow), "--mat", s(&foreign)]);
    assert_fails(&r, 2, "not an eyeshell output directory");
    assert_eq!(std::fs::read_dir(&foreign).unwrap().count(), 1);
    // A snapshot that is not numbers: one line naming the file and the line; nothing written.
    let snaps = snapshots(&grow);
    std::fs::write(&snaps[1].0, "Sigma,h\n1,oops\n").unwrap();
    let out = dir.path().join("never");
    let r = eyeshell(&["export", s(&grow), "--npz", s(&out)]);
    assert_fails(&r, 2, snaps[1].0.file_name().unwrap().to_str().unwrap());
    assert!(!out.exists());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}
