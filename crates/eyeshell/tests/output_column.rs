//! A column added to the table of outputs alone (`eyeshell::outputs`) reaches every file
//! made from it: a growth run's series.csv, history.csv and summary.json, a sweep's
//! sweep.csv and each run's result.json (read back on --resume), and docs/guide/outputs.md.
//! The Python frames: crates/eyeshell-py/tests/test_outputs.py.
//!
//! Its own test binary: the column is registered for this process, and no other test
//! must see it.

use eyeshell::outputs::{self, Cell, Kind, Quantity};
use eyeshell::sweep::RunStatus;
use eyeshell::Sweep;

/// A column the production table does not have: the axial length in micrometres.
const EXTRA: Quantity = Quantity {
    name: "axial_length_um",
    unit: "µm",
    description: "axial length in micrometres",
    computed: "1000 × axial_length (a column only this test adds)",
    kind: Kind::Number,
    added_later: true,
    of: |r| Cell::Number(r.axial_length * 1000.0),
};

/// Two short growth runs of the const scene on a coarse mesh.
const SCENE: &str = r#"
name = "extra-column"
[growth]
eta0 = 70.0
Gamma = 8.0
delta = 4.0
t_end = 0.2
[solver]
nodes = 41
[output]
times = [0.1, 0.2]
history_points = 2
[sweep.grid]
"growth.Gamma" = [6, 8]
"#;

/// The header and rows of a CSV file without quoted cells.
fn csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let split = |l: &str| l.split(',').map(str::to_string).collect::<Vec<_>>();
    let header = split(lines.next().unwrap());
    (header, lines.map(split).collect())
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

#[test]
fn a_column_added_to_the_table_reaches_every_file() {
    let before = outputs::reference();
    assert!(!before.contains("axial_length_um"));
    outputs::register_for_tests(EXTRA);

    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sweep");
    let sweep = Sweep::from_toml_str(SCENE, "extra.toml", &[]).unwrap();
    let report = sweep.run(&out, 1, &|_, _, _| {}).unwrap();
    assert_eq!(report.records.len(), 2);

    let (table_header, table) = csv(&out.join("sweep.csv"));
    // After the production measures, before the run's work.
    assert_eq!(
        column(&table_header, "axial_length_um"),
        column(&table_header, "defocus_D") + 1
    );
    for (record, row) in report.records.iter().zip(&table) {
        assert_eq!(record.status, RunStatus::Ok, "{}", record.name);
        let run = out.join("runs").join(&record.name);
        for file in ["series.csv", "history.csv"] {
            let (header, rows) = csv(&run.join(file));
            let (l, um) = (
                column(&header, "axial_length"),
                column(&header, "axial_length_um"),
            );
            assert_eq!(um, column(&header, "defocus_D") + 1, "{file}");
            assert!(rows.len() >= 3, "{file}: {rows:?}");
            for r in &rows {
                let length: f64 = r[l].parse().unwrap();
                assert_eq!(r[um].parse::<f64>().unwrap(), length * 1000.0, "{file}");
            }
            if file == "series.csv" {
                // sweep.csv's cell is the series' last, byte for byte.
                let last = rows.last().unwrap();
                assert_eq!(row[column(&table_header, "axial_length_um")], last[um]);
            }
        }
        let value = |file: &str, at: &[&str]| -> f64 {
            let text = std::fs::read_to_string(run.join(file)).unwrap();
            let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
            for k in at {
                v = v[*k].take();
            }
            v.as_f64().unwrap_or_else(|| panic!("{file}: {at:?}"))
        };
        let final_length = value("summary.json", &["final", "axial_length"]);
        assert_eq!(
            value("summary.json", &["final", "axial_length_um"]),
            final_length * 1000.0
        );
        assert_eq!(
            value("result.json", &["axial_length_um"]),
            final_length * 1000.0
        );
        let result = record.result.as_ref().unwrap();
        assert_eq!(result.eye.number("axial_length_um"), final_length * 1000.0);
    }

    // result.json reads back with the column: a resumed sweep reuses both runs and writes
    // the same table.
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let options = eyeshell::sweep::SweepOptions {
        jobs: 1,
        resume: true,
        cancel: &cancel,
        runner: &eyeshell::sweep::InProcess,
        inputs: &[],
    };
    let resumed = eyeshell::sweep::run_sweep(&sweep, &out, &options, &|_, _, _| {}).unwrap();
    assert!(resumed
        .records
        .iter()
        .all(|r| r.status == RunStatus::Reused));
    assert_eq!(csv(&out.join("sweep.csv")).1.len(), 2);
    assert_eq!(
        csv(&out.join("sweep.csv")).1[0][column(&table_header, "axial_length_um")],
        table[0][column(&table_header, "axial_length_um")]
    );

    let docs = outputs::reference();
    assert!(
        docs.contains("| `axial_length_um` | µm | axial length in micrometres | 1000 × axial_length (a column only this test adds) |"),
        "{docs}"
    );
    assert_eq!(
        outputs::quantity("axial_length_um").unwrap().label(),
        "axial_length_um (µm)"
    );
}
