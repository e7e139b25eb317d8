//! Writing the results of a growth run as they come, so that nothing is lost if it fails:
//!
//! - `series.csv`: one row per output time (t = 0 first), appended and flushed at once;
//! - `snapshots/snapshot_<k>_t<t>.csv` (`snapshot_<k>_age<age>.csv` when the scene counts
//!   in ages): every elastic and growth field on every node at output time number k (names
//!   sort in time order), each written to a temporary file and renamed, so a snapshot is
//!   never half-written;
//! - `history.csv` (with `output.history_points` > 0): the same columns at every recorded
//!   time, the history times and the snapshot times, appended and flushed at once;
//! - `peripheral.csv`: the peripheral refraction at every output time, a row per field
//!   angle, naked; when the eye whose refraction the run reports wears lenses, the rows of
//!   `eyeshell optics`'s layout instead, naked and through each image of the lenses with its
//!   share ([`peripheral_records`]);
//! - `sensitivities.csv` (with `GrowthSettings::sensitivities`): one row per recorded time
//!   and parameter, [`SENSITIVITY_COLUMNS`], appended and flushed at once;
//! - with `time.unit` set, series.csv, history.csv, sensitivities.csv and peripheral.csv
//!   end in an `age` column (in that unit) after their columns without it, so a reader that takes the
//!   columns by position reads either; without a unit every file is as it always was;
//! - `summary.json`: `"status": "running"` from the start, then `"ok"`
//!   with every [`GrowthStats`] field, or `"failed"` with `failed_at_t`, `error` and the
//!   statistics so far.
//!
//! Unlike `solve`, whose directory appears whole or not at all, a growth run writes in
//! place ([`OwnedDir`]): the target is checked like [`super::OutputDir`]'s (a directory that
//! is not an eyeshell output is refused), locked for the whole run, a previous output is
//! removed first, and the directory is created fresh with its marker, so a run that was
//! killed can be replaced by the next.

use std::fs;
use std::path::{Path, PathBuf};

use super::atomic::sync_tree;
use super::summary::{GrowthSummary, RunStatus, SnapshotEntry, Summary};
use super::table::{csv_writer, QuoteStyle};
use super::{format_value, write_atomic_unsynced, OutputError, OwnedDir, SUMMARY_FILE};
use crate::bvp::COLUMNS;
use crate::growth::refraction::ThroughLenses;
use crate::growth::{
    GrowthError, GrowthStats, Observer, ObserverError, PeripheralRow, SensitivityRow, SeriesRow,
    Snapshot, GROWTH_COLUMNS, PERIPHERAL_COLUMNS,
};
use crate::outputs::{series_cells, series_columns};
use crate::scene::Scene;

/// The time series at the posterior pole, one row per output time.
pub const SERIES_FILE: &str = "series.csv";
/// The series rows at the history times (`output.history_points`), same columns as series.csv.
pub const HISTORY_FILE: &str = "history.csv";
/// The forward sensitivities (`eyeshell grow --sensitivities`).
pub const SENSITIVITIES_FILE: &str = "sensitivities.csv";
/// The columns of sensitivities.csv: the derivatives per unit of the parameter, and the
/// scaled (p/L) dL/dp.
pub const SENSITIVITY_COLUMNS: [&str; 6] = [
    "t",
    "parameter",
    "d_axial_length",
    "d_equatorial_radius",
    "d_retina_minus_blue",
    "scaled_axial_length",
];
pub use crate::outputs::AGE_COLUMN;
/// The peripheral refraction at each output time and field angle
/// ([`crate::growth::PERIPHERAL_COLUMNS`]).
pub const PERIPHERAL_FILE: &str = "peripheral.csv";
/// The directory of the snapshot files.
pub const SNAPSHOT_DIR: &str = "snapshots";
// The columns of series.csv, and what a run's files take at most: the plan a scene is
// checked against before the run, which the writer follows.
pub use crate::plan::{planned_bytes, CELL_BYTES, MAX_RUN_BYTES};

/// The file name of output time number `k` (0 for t = 0) at time `t`: names sort in time
/// order (`snapshot_00002_t0.200000.csv`); a time of 1e9 or more is written in scientific
/// notation (`snapshot_00002_t1.000000e300.csv`), so a name never outgrows the file system.
pub fn snapshot_name(k: usize, t: f64) -> String {
    format!("snapshot_{k:05}_t{}.csv", crate::text::decimals6(t))
}

/// The file name of output time number `k` at time `t` whose age is `age` (None: a scene
/// without time.unit, [`snapshot_name`]): with an age the name carries it in place of t
/// (`snapshot_00002_age3.500000.csv`), the age being what the user asked for; k keeps the
/// names in time order, and summary.json lists each file with its t.
pub fn snapshot_name_at(k: usize, t: f64, age: Option<f64>) -> String {
    match age {
        Some(a) => format!("snapshot_{k:05}_age{}.csv", crate::text::decimals6(a)),
        None => snapshot_name(k, t),
    }
}

/// The header of a snapshot file: the elastic [`COLUMNS`], then the [`GROWTH_COLUMNS`].
pub fn snapshot_header() -> String {
    COLUMNS
        .iter()
        .chain(GROWTH_COLUMNS.iter())
        .copied()
        .collect::<Vec<_>>()
        .join(",")
}

/// The header of series.csv: the table of outputs' [`series_columns`].
pub fn series_header() -> String {
    series_columns().join(",")
}

/// `columns`, then [`AGE_COLUMN`] when `ages` (a scene with time.unit).
pub fn with_age_column<'a>(columns: &[&'a str], ages: bool) -> Vec<&'a str> {
    let mut out = columns.to_vec();
    if ages {
        out.push(AGE_COLUMN);
    }
    out
}

/// The cells of one row of series.csv, as the table of outputs computes them.
pub fn series_record(row: &SeriesRow) -> Vec<String> {
    series_cells(row)
}

/// The text of a snapshot file: the [`snapshot_header`] columns, one row per node, then
/// [`AGE_COLUMN`] when the scene counts ages (`age`: the snapshot's age, the same on every
/// row, so that a snapshot read alone, or concatenated with others, still says when it is).
pub fn snapshot_csv(s: &Snapshot, age: Option<f64>) -> std::io::Result<Vec<u8>> {
    let columns: Vec<&str> = COLUMNS
        .iter()
        .chain(GROWTH_COLUMNS.iter())
        .copied()
        .collect();
    let header = with_age_column(&columns, age.is_some());
    let rows = s
        .fields
        .iter()
        .zip(&s.growth)
        .map(|(f, g)| f.values().into_iter().chain(g.values()).chain(age));
    Ok(super::numeric_csv(header, rows))
}

/// A snapshot file written so far: its time and its path relative to the output directory.
pub type WrittenSnapshot = SnapshotEntry;

/// Writes a growth run into its output directory as the results come; an [`Observer`] of
/// [`crate::growth::grow`]. It writes files only: a progress display is the caller's (the
/// CLI wraps this observer in one that draws a bar).
#[derive(Debug)]
pub struct GrowthWriter {
    dir: PathBuf,
    /// The directory's ownership and lock, held for the whole run.
    _owned: OwnedDir,
    scene: Scene,
    series: csv::Writer<fs::File>,
    peripheral: csv::Writer<fs::File>,
    /// peripheral.csv holds the [`THROUGH_COLUMNS`] and rows through the lenses: the eye
    /// whose refraction the run reports wears lenses.
    through_columns: bool,
    history: Option<csv::Writer<fs::File>>,
    sensitivities: Option<csv::Writer<fs::File>>,
    snapshots: Vec<WrittenSnapshot>,
    last: Option<SeriesRow>,
}

impl GrowthWriter {
    /// The age of time `t` when the scene counts in ages (time.unit), else None.
    fn age(&self, t: f64) -> Option<f64> {
        self.scene.growth.as_ref().and_then(|g| g.age_of(t))
    }
}

impl GrowthWriter {
    /// Check `target` (a directory that exists and is not an earlier growth run, or where
    /// one of `inputs`, the files the run is made from, is, is refused), remove a previous
    /// run there, and create the directory with `snapshots/`, the header of series.csv and
    /// a summary.json that says `"status": "running"`.
    pub fn create(
        target: &Path,
        scene: &Scene,
        inputs: &[&Path],
    ) -> Result<GrowthWriter, OutputError> {
        let history_points = scene.growth_settings.history_points;
        let mut entries = vec![SERIES_FILE, PERIPHERAL_FILE, SNAPSHOT_DIR, SUMMARY_FILE];
        if history_points > 0 {
            entries.push(HISTORY_FILE);
        }
        let with_sensitivities = !scene.growth_settings.sensitivities.is_empty();
        if with_sensitivities {
            entries.push(SENSITIVITIES_FILE);
        }
        let ages = scene
            .growth
            .as_ref()
            .is_some_and(|g| g.age_unit().is_some());
        let owned = OwnedDir::fresh(target, "grow", &entries, inputs)?;
        let target = owned.path().to_path_buf();
        let snapshots = target.join(SNAPSHOT_DIR);
        fs::create_dir_all(&snapshots).map_err(|e| OutputError::io(&snapshots, e))?;
        let series_path = target.join(SERIES_FILE);
        let series = create_with_header(&series_path, ages)?;
        let through_columns = (scene.refraction_optics()).is_some_and(|o| !o.lenses.is_empty());
        let mut columns = PERIPHERAL_COLUMNS.to_vec();
        if through_columns {
            columns.extend(THROUGH_COLUMNS);
        }
        let peripheral = create_with_columns(
            &target.join(PERIPHERAL_FILE),
            &with_age_column(&columns, ages),
        )?;
        let history = if history_points > 0 {
            Some(create_with_header(&target.join(HISTORY_FILE), ages)?)
        } else {
            None
        };
        let sensitivities = if with_sensitivities {
            let path = target.join(SENSITIVITIES_FILE);
            Some(create_with_columns(
                &path,
                &with_age_column(&SENSITIVITY_COLUMNS, ages),
            )?)
        } else {
            None
        };
        let writer = GrowthWriter {
            dir: target,
            _owned: owned,
            scene: scene.clone(),
            series,
            peripheral,
            through_columns,
            history,
            sensitivities,
            snapshots: Vec::new(),
            last: None,
        };
        writer.write_summary(RunStatus::Running)?;
        Ok(writer)
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The snapshots written so far, in time order.
    pub fn snapshots(&self) -> &[WrittenSnapshot] {
        &self.snapshots
    }

    /// The last row written to series.csv.
    pub fn last_row(&self) -> Option<&SeriesRow> {
        self.last.as_ref()
    }

    /// Write the snapshot file of `s`, then append its row to series.csv and flush.
    pub fn write_snapshot(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        let k = self.snapshots.len();
        let name = snapshot_name_at(k, s.t, self.age(s.t));
        let path = self.dir.join(SNAPSHOT_DIR).join(&name);
        if s.fields.len() != s.growth.len() {
            return Err(OutputError::io(
                &path,
                std::io::Error::other(format!(
                    "snapshot at t = {} has {} rows of elastic fields but {} rows of growth fields",
                    s.t,
                    s.fields.len(),
                    s.growth.len()
                )),
            ));
        }
        snapshot_csv(s, self.age(s.t))
            .and_then(|text| write_atomic_unsynced(&path, &text))
            .map_err(|e| OutputError::io(&path, e))?;
        let series_path = self.dir.join(SERIES_FILE);
        let age = self.age(s.t);
        append(&mut self.series, &s.series, age).map_err(|e| OutputError::io(&series_path, e))?;
        let peripheral_path = self.dir.join(PERIPHERAL_FILE);
        append_peripheral(&mut self.peripheral, s, self.through_columns, age)
            .map_err(|e| OutputError::io(&peripheral_path, e))?;
        self.snapshots.push(WrittenSnapshot {
            t: s.t,
            file: format!("{SNAPSHOT_DIR}/{name}"),
        });
        self.last = Some(s.series);
        Ok(())
    }

    fn write_summary(&self, status: RunStatus<'_>) -> Result<(), OutputError> {
        // A finished run's summary.json says what the run holds: its data must be on disk
        // before it is (one pass over the directory, instead of two fsyncs per snapshot as
        // it comes). The summary at the start vouches for nothing yet.
        if !matches!(status, RunStatus::Running) {
            sync_tree(&self.dir).map_err(|e| OutputError::io(&self.dir, e))?;
        }
        Summary::Growth(GrowthSummary::new(
            &self.scene,
            status,
            &self.snapshots,
            self.last.as_ref(),
        ))
        .write_to(&self.dir.join(SUMMARY_FILE))
    }

    /// The run reached its end: write summary.json with `"status": "ok"` and `stats`.
    pub fn finish(self, stats: &GrowthStats) -> Result<PathBuf, OutputError> {
        self.write_summary(RunStatus::Ok(stats))?;
        Ok(self.dir)
    }

    /// The run failed: write summary.json with `"status": "failed"`, where, why, and the
    /// statistics so far. The snapshots and series rows written stay.
    pub fn fail(self, error: &GrowthError) -> Result<PathBuf, OutputError> {
        self.write_summary(RunStatus::Failed(error))?;
        Ok(self.dir)
    }
}

/// Create `path` with the series header (and the age column with `ages`) as its first line.
fn create_with_header(path: &Path, ages: bool) -> Result<csv::Writer<fs::File>, OutputError> {
    create_with_columns(path, &with_age_column(&series_columns(), ages))
}

/// Create `path` with `columns` as its first line.
fn create_with_columns(
    path: &Path,
    columns: &[&str],
) -> Result<csv::Writer<fs::File>, OutputError> {
    let file = fs::File::create(path).map_err(|e| OutputError::io(path, e))?;
    let mut w = csv_writer(file, QuoteStyle::Necessary);
    w.write_record(columns)
        .map_err(std::io::Error::from)
        .and_then(|_| w.flush())
        .map_err(|e| OutputError::io(path, e))?;
    Ok(w)
}

/// Append the series row `row` (and its age, in a scene with ages) and flush it at once.
fn append(w: &mut csv::Writer<fs::File>, row: &SeriesRow, age: Option<f64>) -> std::io::Result<()> {
    w.write_record(series_record(row).into_iter().chain(age.map(format_value)))?;
    w.flush()
}

/// The columns peripheral.csv holds after [`PERIPHERAL_COLUMNS`] for an eye that wears
/// lenses (and always in `eyeshell optics`'s): which eye the row is through (`naked` or
/// `lenses`), the image's index among the lenses' images, its power (empty but for a lens
/// that forms several) and its share of the light at that field (1 for the naked eye).
pub const THROUGH_COLUMNS: [&str; 4] = ["through", "image", "image_power_D", "share"];

/// The rows of peripheral.csv at growth time `t`: the naked eye's `naked` at each field,
/// then, with `through_columns`, the [`THROUGH_COLUMNS`] after them and each image of the
/// lenses `through` at each field; `age` last in a scene with ages. One function for a
/// growth run's file and `eyeshell optics`'s, so the two agree row for row.
pub fn peripheral_records(
    t: f64,
    naked: &[PeripheralRow],
    through: &[ThroughLenses],
    through_columns: bool,
    age: Option<f64>,
) -> Vec<Vec<String>> {
    let v = format_value;
    let row = |p: &PeripheralRow, eye: Option<[String; 4]>| -> Vec<String> {
        [v(t), v(p.field_deg), v(p.refraction_d), v(p.relative_d)]
            .into_iter()
            .chain(eye.into_iter().flatten())
            .chain(age.map(v))
            .collect()
    };
    let naked_cells = || ["naked".into(), "0".into(), String::new(), v(1.0)];
    let mut rows: Vec<Vec<String>> = (naked.iter())
        .map(|p| row(p, through_columns.then(naked_cells)))
        .collect();
    if !through_columns {
        return rows;
    }
    for (k, l) in through.iter().enumerate() {
        for (i, p) in l.peripheral.iter().enumerate() {
            let share = l.share.get(i).copied().unwrap_or(f64::NAN);
            let cells = [
                "lenses".into(),
                k.to_string(),
                l.image_power.map(v).unwrap_or_default(),
                v(share),
            ];
            rows.push(row(p, Some(cells)));
        }
    }
    rows
}

/// Append the peripheral refraction rows of snapshot `s` ([`peripheral_records`], each with
/// its age in a scene with ages) and flush them at once.
fn append_peripheral(
    w: &mut csv::Writer<fs::File>,
    s: &Snapshot,
    through_columns: bool,
    age: Option<f64>,
) -> std::io::Result<()> {
    for row in peripheral_records(s.t, &s.peripheral, &s.through, through_columns, age) {
        w.write_record(row)?;
    }
    w.flush()
}

impl Observer for GrowthWriter {
    fn history(&mut self, row: &SeriesRow) -> Result<(), ObserverError> {
        let path = self.dir.join(HISTORY_FILE);
        let age = self.age(row.t);
        match &mut self.history {
            Some(w) => append(w, row, age).map_err(|e| OutputError::io(&path, e).into()),
            None => Ok(()),
        }
    }

    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        Ok(self.write_snapshot(s)?)
    }

    fn sensitivities(&mut self, rows: &[SensitivityRow]) -> Result<(), ObserverError> {
        let path = self.dir.join(SENSITIVITIES_FILE);
        let ages: Vec<Option<f64>> = rows.iter().map(|r| self.age(r.t)).collect();
        let Some(w) = &mut self.sensitivities else {
            return Ok(());
        };
        let write = |w: &mut csv::Writer<fs::File>| -> std::io::Result<()> {
            for (r, age) in rows.iter().zip(&ages) {
                let cells = [
                    format_value(r.t),
                    r.parameter.to_string(),
                    format_value(r.d_axial_length),
                    format_value(r.d_equatorial_radius),
                    format_value(r.d_retina_minus_blue),
                    format_value(r.scaled_axial_length()),
                ];
                w.write_record(cells.into_iter().chain(age.map(format_value)))?;
            }
            w.flush()
        };
        write(w).map_err(|e| OutputError::io(&path, e).into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::FieldRow;
    use crate::growth::GrowthRow;
    use crate::model::stimulus::Refraction;

    fn growing_scene() -> Scene {
        Scene::from_toml_str("growth.eta0 = 70\nsolver.nodes = 11", "g.toml", &[]).unwrap()
    }

    /// A synthetic snapshot at time t with n nodes.
    fn snapshot(t: f64, n: usize) -> Snapshot {
        let fields = (0..n)
            .map(|i| FieldRow {
                sigma_ref: i as f64,
                sigma: i as f64 * (1.0 + t),
                kappa: 0.1 / (1.0 + t),
                r: 1e-300 + i as f64,
                ..FieldRow::default()
            })
            .collect();
        let growth = (0..n)
            .map(|i| GrowthRow {
                rho: i as f64 + t,
                zeta: 0.65,
                eta: 70.0 / 3.0,
                g_v: t,
                z_retina: -(i as f64),
                r_retina: i as f64 * 0.5,
                drive: t - 0.5,
                defocus_d: f64::NAN,
            })
            .collect();
        let class = if t < 0.5 {
            Refraction::Hyperopic
        } else {
            Refraction::Emmetropic
        };
        Snapshot {
            t,
            fields,
            growth,
            series: SeriesRow {
                t,
                axial_length: 20.0 + t / 3.0,
                equatorial_radius: 10.0 + t,
                retina_minus_blue: t - 0.5,
                retina_minus_red: t - 1.155,
                class,
                refraction_d: 1.0 - t,
                drive: 0.5 - t,
                defocus_d: f64::NAN,
            },
            peripheral: vec![],
            through: vec![],
        }
    }

    fn read_series(dir: &Path) -> Vec<Vec<String>> {
        let text = fs::read_to_string(dir.join(SERIES_FILE)).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), series_header());
        lines
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    }

    fn summary(dir: &Path) -> serde_json::Value {
        serde_json::from_str(&fs::read_to_string(dir.join(SUMMARY_FILE)).unwrap()).unwrap()
    }

    #[test]
    fn header_and_names() {
        assert_eq!(
            series_header(),
            "t,axial_length,equatorial_radius,retina_minus_blue,retina_minus_red,class,refraction_D,drive,defocus_D"
        );
        let h = snapshot_header();
        assert!(h.starts_with("Sigma,sigma,kappa"), "{h}");
        assert!(
            h.ends_with("h,t_s,t_phi,rho,zeta,eta,g_v,z_retina,r_retina,drive,defocus_D"),
            "{h}"
        );
        // Names sort in time order.
        let times = [0.0, 0.1, 0.2, 0.4, 1.0, 2.5, 10.0, 100.0];
        let names: Vec<String> = times
            .iter()
            .enumerate()
            .map(|(k, &t)| snapshot_name(k, t))
            .collect();
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(names, sorted);
        assert_eq!(snapshot_name(2, 0.2), "snapshot_00002_t0.200000.csv");
        assert_eq!(snapshot_name(2, 1e300), "snapshot_00002_t1.000000e300.csv");
        // A scene with ages names them by age; without, as ever.
        assert_eq!(
            snapshot_name_at(2, 0.2, Some(3.5)),
            "snapshot_00002_age3.500000.csv"
        );
        assert_eq!(snapshot_name_at(2, 0.2, None), snapshot_name(2, 0.2));
    }

    #[test]
    fn writes_as_it_goes_and_summarises_success() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let scene = growing_scene();
        let mut w = GrowthWriter::create(&dir, &scene, &[]).unwrap();
        // From the start: the directory, the series header and a running summary.
        assert!(dir.join(SNAPSHOT_DIR).is_dir());
        assert!(read_series(&dir).is_empty());
        assert_eq!(summary(&dir)["status"], "running");
        let times = [0.0, 0.1, 0.2, 0.4, 1.0];
        for (k, &t) in times.iter().enumerate() {
            Observer::snapshot(&mut w, &snapshot(t, 7)).unwrap();
            // Each row is on disk at once, in order, and parses back.
            let rows = read_series(&dir);
            assert_eq!(rows.len(), k + 1);
            let last = &rows[k];
            assert_eq!(last[0].parse::<f64>().unwrap(), t);
            assert_eq!(last[1].parse::<f64>().unwrap(), 20.0 + t / 3.0);
            assert_eq!(last[4].parse::<f64>().unwrap(), t - 1.155);
            assert_eq!(last[5], if t < 0.5 { "hyperopic" } else { "emmetropic" });
        }
        let stats = GrowthStats {
            steps: 42,
            rhs_evaluations: 99,
            bvp_solves: 99,
            t_reached: 1.0,
            wall_seconds: 0.5,
            ..GrowthStats::default()
        };
        let out = w.finish(&stats).unwrap();
        assert_eq!(out, dir);
        // Snapshot files: one per output time, the right header and one row per node,
        // round-trip values, and no temporary file left.
        let mut names: Vec<String> = fs::read_dir(dir.join(SNAPSHOT_DIR))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names.len(), times.len());
        for (k, (name, &t)) in names.iter().zip(&times).enumerate() {
            assert_eq!(name, &snapshot_name(k, t));
            let text = fs::read_to_string(dir.join(SNAPSHOT_DIR).join(name)).unwrap();
            let mut lines = text.lines();
            assert_eq!(lines.next().unwrap(), snapshot_header());
            let rows: Vec<Vec<f64>> = lines
                .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
                .collect();
            assert_eq!(rows.len(), 7);
            let expect = snapshot(t, 7);
            for (i, row) in rows.iter().enumerate() {
                assert_eq!(row.len(), COLUMNS.len() + GROWTH_COLUMNS.len());
                let mut want = expect.fields[i].values().to_vec();
                want.extend(expect.growth[i].values());
                // Bit for bit: defocus_D is NaN here, as where no rule reads defocus.
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(row), bits(&want));
            }
        }
        let v = summary(&dir);
        assert_eq!(v["status"], "ok");
        for k in [
            "steps",
            "rhs_evaluations",
            "bvp_solves",
            "newton_iterations",
            "jacobian_products",
            "error_test_failures",
            "nonlinear_iterations",
            "nonlinear_failures",
            "linear_iterations",
            "t_reached",
            "wall_seconds",
            "integrator",
            "rtol",
            "atol",
            "euler_steps",
            "sundials_version",
            "parameters",
        ] {
            assert!(v.get(k).is_some(), "missing {k}");
        }
        assert_eq!(v["steps"], 42);
        assert_eq!(v["rhs_evaluations"], 99);
        assert_eq!(v["integrator"], "ida");
        assert_eq!(v["rtol"], 1e-6);
        assert_eq!(v["parameters"]["growth.eta0"], 70.0);
        assert_eq!(v["parameters"]["solver.nodes"], 11);
        assert_eq!(v["snapshots"].as_array().unwrap().len(), 5);
        assert_eq!(v["last_output_t"], 1.0);
        assert_eq!(v["final"]["class"], "emmetropic");
        assert!(v.get("failed_at_t").is_none() && v.get("error").is_none());
        // Nothing else in the directory.
        let mut top: Vec<String> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        top.sort();
        assert_eq!(
            top,
            vec![
                super::super::MARKER_FILE,
                PERIPHERAL_FILE,
                SERIES_FILE,
                SNAPSHOT_DIR,
                SUMMARY_FILE
            ]
        );
    }

    #[test]
    fn failure_keeps_the_results_so_far() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let mut w = GrowthWriter::create(&dir, &growing_scene(), &[]).unwrap();
        w.write_snapshot(&snapshot(0.0, 5)).unwrap();
        w.write_snapshot(&snapshot(0.1, 5)).unwrap();
        let error = GrowthError {
            t: 0.1734,
            reason: "CVODE: the corrector did not converge\nat all".into(),
            stats: Box::new(GrowthStats {
                steps: 17,
                t_reached: 0.1734,
                ..GrowthStats::default()
            }),
        };
        w.fail(&error).unwrap();
        assert_eq!(read_series(&dir).len(), 2);
        assert_eq!(fs::read_dir(dir.join(SNAPSHOT_DIR)).unwrap().count(), 2);
        let v = summary(&dir);
        assert_eq!(v["status"], "failed");
        assert_eq!(v["failed_at_t"], 0.1734);
        assert_eq!(v["steps"], 17);
        assert_eq!(v["last_output_t"], 0.1);
        let e = v["error"].as_str().unwrap();
        assert!(e.starts_with("growth failed at t = 0.173400: CVODE"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn a_mismatched_snapshot_is_an_error_and_writes_nothing() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let mut w = GrowthWriter::create(&dir, &growing_scene(), &[]).unwrap();
        let mut s = snapshot(0.0, 5);
        s.growth.pop();
        let e = Observer::snapshot(&mut w, &s).unwrap_err().to_string();
        assert!(e.contains("5 rows of elastic fields but 4"), "{e}");
        assert!(read_series(&dir).is_empty());
        assert_eq!(fs::read_dir(dir.join(SNAPSHOT_DIR)).unwrap().count(), 0);
    }

    #[test]
    fn replaces_previous_outputs_and_refuses_foreign_directories() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        // A previous run (even a killed one: its summary says running) is replaced whole.
        let mut w = GrowthWriter::create(&dir, &growing_scene(), &[]).unwrap();
        w.write_snapshot(&snapshot(0.0, 3)).unwrap();
        w.write_snapshot(&snapshot(0.5, 3)).unwrap();
        drop(w);
        // ... unless it holds a file eyeshell did not write, which is never deleted.
        fs::write(dir.join("stray.txt"), "x").unwrap();
        let e = GrowthWriter::create(&dir, &growing_scene(), &[]).unwrap_err();
        assert!(e.to_string().contains("stray.txt"), "{e}");
        assert!(dir.join("stray.txt").exists());
        fs::remove_file(dir.join("stray.txt")).unwrap();
        let w = GrowthWriter::create(&dir, &growing_scene(), &[]).unwrap();
        assert!(read_series(&dir).is_empty());
        assert_eq!(fs::read_dir(dir.join(SNAPSHOT_DIR)).unwrap().count(), 0);
        drop(w);
        // A solve output is replaced too; a foreign directory is refused and untouched.
        let data = tmp.path().join("data");
        fs::create_dir(&data).unwrap();
        fs::write(data.join("precious.txt"), "keep").unwrap();
        let e = GrowthWriter::create(&data, &growing_scene(), &[]).unwrap_err();
        assert!(e.is_refusal(), "{e}");
        assert_eq!(fs::read_dir(&data).unwrap().count(), 1);
        // An empty directory and missing parents are fine.
        let empty = tmp.path().join("empty");
        fs::create_dir(&empty).unwrap();
        GrowthWriter::create(&empty, &growing_scene(), &[]).unwrap();
        GrowthWriter::create(&tmp.path().join("a/b/c"), &growing_scene(), &[]).unwrap();
        assert!(tmp.path().join("a/b/c").join(SERIES_FILE).is_file());
    }
}
