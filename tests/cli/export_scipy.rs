//! SciPy reads what eyeshell writes (scipy.io.loadmat on plain and compressed .mat,
//! numpy.load on .npz), with the right shapes and the same values bit for bit; and eyeshell
//! reads a compressed file written by scipy.io.savemat(do_compression=True), as MATLAB
//! writes them by default. Runs only where `python3 -c 'import scipy'` works (.ci/run
//! installs scipy); elsewhere it says SKIPPED, and with `EYESHELL_REQUIRE_SCIPY=1` (set by
//! .ci/run) it fails instead.

use crate::support::*;
use std::process::Command;

/// Run a Python script with arguments; return its stdout (JSON).
fn python(script: &str, args: &[&str]) -> serde_json::Value {
    let out = Command::new("python3")
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON from python")
}

/// Loads every file given and prints {file: {var: {"shape": [...], "data": [...]}}} with
/// shapes as SciPy/NumPy see them and data in MATLAB (column-major) / C order, each value
/// as the integer of its 64 bits (exact, whatever JSON float parsing does).
const DUMP: &str = r#"
import json, sys
import numpy as np, scipy.io
def bits(a):
    return [int(b) for b in np.ascontiguousarray(a, dtype='<f8').view('<u8')]
out = {}
for f in sys.argv[1:]:
    d = {}
    if f.endswith('.npz'):
        with np.load(f) as z:
            for k in z.files:
                a = z[k]
                d[k] = {'shape': list(a.shape), 'dtype': str(a.dtype), 'data': bits(a.ravel(order='C'))}
    else:
        m = scipy.io.loadmat(f)
        for k, a in m.items():
            if k.startswith('__'):
                continue
            if a.dtype.names:  # a struct: 1x1 array of records
                assert a.shape == (1, 1), a.shape
                for name in a.dtype.names:
                    v = a[0, 0][name]
                    if v.dtype.kind == 'U':  # a char row: its text
                        d[k + '.' + name] = {'shape': list(v.shape), 'dtype': 'char', 'text': str(v[0])}
                    elif v.dtype.names:  # a nested struct: its fields
                        for sub in v.dtype.names:
                            w = v[0, 0][sub]
                            d[k + '.' + name + '.' + sub] = {'shape': list(w.shape), 'dtype': str(w.dtype), 'data': bits(w.ravel(order='F'))}
                    else:
                        d[k + '.' + name] = {'shape': list(v.shape), 'dtype': str(v.dtype), 'data': bits(v.ravel(order='F'))}
            else:
                d[k] = {'shape': list(a.shape), 'dtype': str(a.dtype), 'data': bits(a.ravel(order='F'))}
    out[f] = d
print(json.dumps(out))
"#;

fn data(v: &serde_json::Value) -> Vec<f64> {
    v["data"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| f64::from_bits(x.as_u64().unwrap()))
        .collect()
}

fn shape(v: &serde_json::Value) -> Vec<usize> {
    v["shape"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap() as usize)
        .collect()
}

#[test]
fn scipy_loads_what_eyeshell_writes() {
    if !scipy_available("scipy_loads_what_eyeshell_writes") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let fields = solve.join("fields.csv");
    let n = column(&fields, "Sigma").len();
    let plain = dir.path().join("solve.mat");
    let packed = dir.path().join("solve-z.mat");
    let npz = dir.path().join("solve.npz");
    ok(&[
        "export",
        s(&solve),
        "--mat",
        s(&plain),
        "--npz",
        s(&npz),
        "--quiet",
    ]);
    ok(&[
        "export",
        s(&solve),
        "--mat",
        s(&packed),
        "--compress",
        "--quiet",
    ]);
    let dump = python(DUMP, &[s(&plain), s(&packed), s(&npz)]);
    for f in [&plain, &packed] {
        let d = &dump[s(f)];
        assert_eq!(shape(&d["sol.x"]), vec![1, n], "{}", f.display());
        assert_eq!(d["sol.x"]["dtype"], "float64");
        assert_bits(&data(&d["sol.x"]), &column(&fields, "Sigma"), "sol.x");
        assert_eq!(shape(&d["sol.y"]), vec![5, n]);
        let y = data(&d["sol.y"]); // column-major: y[j*5 + i]
        for (i, name) in Y_ROWS.iter().enumerate() {
            let row: Vec<f64> = (0..n).map(|j| y[j * 5 + i]).collect();
            assert_bits(&row, &column(&fields, name), name);
        }
        // bvp4c's own fields: solver, yp, stats.
        assert_eq!(d["sol.solver"]["text"], "bvp4c", "{}", f.display());
        assert_eq!(shape(&d["sol.yp"]), vec![5, n]);
        assert_eq!(data(&d["sol.stats.nmeshpoints"]), vec![n as f64]);
        assert!(data(&d["sol.stats.maxres"])[0] < 1e-8);
        let yp = data(&d["sol.yp"]);
        for (i, name) in Y_ROWS
            .iter()
            .enumerate()
            .filter(|(_, n)| ["r", "theta"].contains(n))
        {
            // yp is the slope of y: close to its centred differences (r and θ, whose slopes
            // are of order one; κ, α_s and Q are nearly flat on this shell).
            let (x, v) = (column(&fields, "Sigma"), column(&fields, name));
            let centred = |j: usize| (v[j + 1] - v[j - 1]) / (x[j + 1] - x[j - 1]);
            let scale = (1..n - 1).map(|j| centred(j).abs()).fold(0.0, f64::max);
            for j in n / 4..3 * n / 4 {
                let (slope, centred) = (yp[j * 5 + i], centred(j));
                assert!(
                    (slope - centred).abs() <= 0.1 * scale,
                    "{name} at node {j}: yp {slope} vs centred difference {centred}"
                );
            }
        }
        for name in ELASTIC_EXTRA {
            let v = &d[format!("sol.{name}")];
            assert_eq!(shape(v), vec![1, n]);
            assert_bits(&data(v), &column(&fields, name), name);
        }
    }
    let d = &dump[s(&npz)];
    assert_eq!(shape(&d["x"]), vec![n]);
    assert_eq!(shape(&d["y"]), vec![5, n]);
    assert_eq!(shape(&d["yp"]), vec![5, n]);
    // The same yp in both formats (C order here, column-major in .mat).
    let (yp_npz, yp_mat) = (data(&d["yp"]), data(&dump[s(&plain)]["sol.yp"]));
    for i in 0..5 {
        let row: Vec<f64> = (0..n).map(|j| yp_mat[j * 5 + i]).collect();
        assert_bits(&yp_npz[i * n..(i + 1) * n], &row, "yp");
    }
    let y = data(&d["y"]); // C order: y[i*n + j]
    for (i, name) in Y_ROWS.iter().enumerate() {
        assert_bits(&y[i * n..(i + 1) * n], &column(&fields, name), name);
    }

    // Growth: every snapshot file, .mat and .npz.
    let gm = dir.path().join("grow-mat");
    let gn = dir.path().join("grow-npz");
    ok(&[
        "export",
        s(&grow),
        "--mat",
        s(&gm),
        "--compress",
        "--npz",
        s(&gn),
        "--quiet",
    ]);
    let snaps = snapshots(&grow);
    let mut files = Vec::new();
    for (csv_file, _) in &snaps {
        let stem = csv_file.file_stem().unwrap().to_str().unwrap();
        files.push(gm.join(format!("{stem}.mat")).to_str().unwrap().to_string());
        files.push(gn.join(format!("{stem}.npz")).to_str().unwrap().to_string());
    }
    let args: Vec<&str> = files.iter().map(String::as_str).collect();
    let dump = python(DUMP, &args);
    for (k, (csv_file, t)) in snaps.iter().enumerate() {
        let m = &dump[&files[2 * k]];
        let z = &dump[&files[2 * k + 1]];
        for name in GROWTH_VARS {
            assert_eq!(shape(&m[name]), vec![1, n], "{name}");
            assert_eq!(shape(&z[name]), vec![n], "{name}");
            assert_bits(&data(&m[name]), &column(csv_file, name), name);
            assert_bits(&data(&z[name]), &column(csv_file, name), name);
        }
        assert_eq!(shape(&m["time"]), vec![1, 1]);
        assert_eq!(shape(&z["time"]), Vec::<usize>::new());
        assert_eq!(data(&m["time"]), vec![*t]);
        assert_eq!(data(&z["time"]), vec![*t]);
    }
}

#[test]
fn eyeshell_reads_compressed_files_written_by_scipy() {
    if !scipy_available("eyeshell_reads_compressed_files_written_by_scipy") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (solve, _) = small_runs(dir.path());
    let fields = solve.join("fields.csv");
    let csv_path = fields.to_str().unwrap();
    // bvp4c-style struct from the CSV, compressed (miCOMPRESSED) as MATLAB saves by default,
    // plus a version with κ at node 6 moved by 1e-6.
    let script = r#"
import sys, json, numpy as np, scipy.io
a = np.genfromtxt(sys.argv[1], delimiter=',', names=True)
sol = {'x': a['Sigma'][None, :], 'y': np.vstack([a[k] for k in ['kappa', 'alpha_s', 'r', 'theta', 'Q']]),
       'z': a['z'][None, :]}
scipy.io.savemat(sys.argv[2], {'sol': sol}, do_compression=True)
sol['y'] = sol['y'].copy(); sol['y'][0, 5] += 1e-6
scipy.io.savemat(sys.argv[3], {'sol': sol}, do_compression=True)
# Row vectors at the top level, time as a scalar, as the published growth scripts save them.
scipy.io.savemat(sys.argv[4], {'Sigma': a['Sigma'][None, :], 'h': a['h'][None, :], 'r': a['r'][None, :], 'time': 0.0}, do_compression=True)
print(json.dumps({}))
"#;
    let good = dir.path().join("scipy.mat");
    let bad = dir.path().join("scipy-bad.mat");
    let rows = dir.path().join("scipy-rows.mat");
    python(script, &[csv_path, s(&good), s(&bad), s(&rows)]);
    let bytes = std::fs::read(&good).unwrap();
    assert_eq!(
        u32::from_le_bytes(bytes[128..132].try_into().unwrap()),
        15,
        "miCOMPRESSED"
    );
    // Our reader: the same values.
    let vars = eyeshell::interop::mat::read(&good).unwrap();
    let sol = &vars.iter().find(|(n, _)| n == "sol").unwrap().1;
    assert_bits(
        sol.field("x").unwrap().data().unwrap(),
        &column(&fields, "Sigma"),
        "x",
    );
    assert_bits(
        &sol.field("y").unwrap().row_of(2).unwrap(),
        &column(&fields, "r"),
        "y(3,:)",
    );
    // compare: accepts the faithful file, detects the perturbed one.
    let r = ok(&["compare", s(&solve), s(&good)]);
    assert!(
        r.stdout.contains("kappa") && r.stdout.contains(" z "),
        "{}",
        r.stdout
    );
    assert_fails(&eyeshell(&["compare", s(&solve), s(&bad)]), 1, "kappa");
    let r = ok(&["compare", s(&solve), s(&rows)]);
    assert!(
        r.stdout.contains(" h ") && r.stdout.contains(" r "),
        "{}",
        r.stdout
    );
}

/// A growth run's .mat export holds its series.csv and history.csv too (series.mat,
/// history.mat): SciPy reads each numeric column as a 1×R row equal to the file's values
/// bit for bit, and the classes as one char row separated by commas; eyeshell's own .mat
/// reader reads the same; the snapshot files are as before (scipy_loads_what_eyeshell_writes)
/// and `compare` still takes the export directory as the run's snapshots.
#[test]
fn scipy_loads_the_series_and_history_of_a_growth_export() {
    if !scipy_available("scipy_loads_the_series_and_history_of_a_growth_export") {
        return;
    }
    const SERIES: &str = r#"
import json, sys
import numpy as np, scipy.io
out = {}
for f in sys.argv[1:]:
    d = {}
    for k, a in scipy.io.loadmat(f).items():
        if k.startswith('__'):
            continue
        if a.dtype.kind == 'U':
            d[k] = {'text': str(a[0])}
        else:
            bits = np.ascontiguousarray(a.ravel(order='F'), dtype='<f8').view('<u8')
            d[k] = {'shape': list(a.shape), 'data': [int(b) for b in bits]}
    out[f] = d
print(json.dumps(out))
"#;
    let dir = tempfile::tempdir().unwrap();
    let (_, grow) = small_runs(dir.path());
    let out = dir.path().join("grow-mat");
    ok(&["export", s(&grow), "--mat", s(&out), "--quiet"]);
    let files: Vec<String> = ["series", "history"]
        .iter()
        .map(|t| s(&out.join(format!("{t}.mat"))).to_string())
        .collect();
    let args: Vec<&str> = files.iter().map(String::as_str).collect();
    let dump = python(SERIES, &args);
    for (stem, file) in ["series", "history"].iter().zip(&files) {
        let csv = grow.join(format!("{stem}.csv"));
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert!(rows.len() >= 5, "{stem}: {} rows", rows.len());
        let d = &dump[file];
        assert_eq!(d.as_object().unwrap().len(), header.len(), "{stem}: {d}");
        let ours = eyeshell::interop::mat::read(std::path::Path::new(file)).unwrap();
        for (j, name) in header.iter().enumerate() {
            let ours = &ours.iter().find(|(k, _)| k == name).unwrap().1;
            if *name == "class" {
                let words: Vec<&str> = rows.iter().map(|r| r[j]).collect();
                assert_eq!(d[name]["text"], words.join(","), "{stem}");
                assert!(
                    matches!(ours, eyeshell::interop::mat::MatValue::Char(t) if *t == words.join(","))
                );
                continue;
            }
            let want: Vec<f64> = rows.iter().map(|r| r[j].parse().unwrap()).collect();
            assert_eq!(shape(&d[name]), vec![1, rows.len()], "{stem}: {name}");
            assert_bits(&data(&d[name]), &want, name);
            assert_bits(ours.data().unwrap(), &want, name);
        }
    }
    // compare reads the export directory as the snapshots alone.
    ok(&["compare", s(&grow), s(&out), "--quiet"]);
}
