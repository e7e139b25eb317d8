//! Reading a run directory back for drawing: its scene, its snapshots (or fields) and its
//! time series. Everything a figure shows comes from these files, never from the solver's
//! memory, so a figure always shows what the run wrote.

use std::path::{Path, PathBuf};

use super::growth::{HISTORY_FILE, SERIES_FILE};
use super::read::ReadError as ExportError;
use super::read::{bad, read_run_with, Run, RunSnapshot, Table};
use super::summary::{RunInfo, Summary};
use super::table::read_records;
use super::SUMMARY_FILE;
use crate::growth::SeriesRow;
use crate::model::stimulus::Refraction;
use crate::scene::Scene;
use crate::text::excerpt;

/// One row of series.csv or history.csv.
pub type SeriesPoint = SeriesRow;

/// A run read back.
#[derive(Clone, Debug)]
pub struct RunData {
    pub dir: PathBuf,
    /// The scene's name (summary.json's `scene.name`), else the directory's name.
    pub name: String,
    /// The run's scene, rebuilt from the parameters in summary.json.
    pub scene: Scene,
    pub kind: RunKind,
}

#[derive(Clone, Debug)]
pub enum RunKind {
    /// `eyeshell solve`: the fields at every node.
    Elastic(Table),
    /// `eyeshell grow`: the snapshots in time order, series.csv and history.csv (empty
    /// without `output.history_points`).
    Growth {
        snapshots: Vec<RunSnapshot>,
        series: Vec<SeriesPoint>,
        history: Vec<SeriesPoint>,
        status: String,
    },
}

impl RunData {
    /// The growth snapshots (empty for an elastic run).
    pub fn snapshots(&self) -> &[RunSnapshot] {
        match &self.kind {
            RunKind::Growth { snapshots, .. } => snapshots,
            RunKind::Elastic(_) => &[],
        }
    }

    /// The densest time series written: history.csv if there is one, else series.csv.
    pub fn timeline(&self) -> &[SeriesPoint] {
        match &self.kind {
            RunKind::Growth {
                series, history, ..
            } => {
                if history.len() > series.len() {
                    history
                } else {
                    series
                }
            }
            RunKind::Elastic(_) => &[],
        }
    }

    /// The snapshot nearest to time `t`.
    pub fn snapshot_near(&self, t: f64) -> Option<&RunSnapshot> {
        self.snapshots()
            .iter()
            .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
    }
}

/// Read the run in `dir` (an `eyeshell solve` or `eyeshell grow` output, finished or not).
pub fn read(dir: &Path) -> Result<RunData, ExportError> {
    let summary = Summary::read(dir)?;
    let summary_path = dir.join(SUMMARY_FILE);
    let Some(run) = summary.run() else {
        // Not a run: read_run_with says what it is.
        read_run_with(dir, &summary)?;
        return Err(bad(format!("{}: not a run", dir.display())));
    };
    let scene = scene_of(run, &summary_path)?;
    let name = Some(run.scene.name.clone())
        .filter(|n| !n.is_empty())
        .or_else(|| dir.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_default();
    let kind = match read_run_with(dir, &summary)? {
        Run::Elastic { table, .. } => RunKind::Elastic(table),
        Run::Growth(snapshots) => RunKind::Growth {
            snapshots,
            series: read_series(&dir.join(SERIES_FILE))?,
            history: match dir.join(HISTORY_FILE) {
                p if p.is_file() => read_series(&p)?,
                _ => Vec::new(),
            },
            status: match &summary {
                Summary::Growth(g) => g.status.as_str().to_string(),
                _ => "unknown".to_string(),
            },
        },
    };
    Ok(RunData {
        dir: dir.to_path_buf(),
        name,
        scene,
        kind,
    })
}

/// The scene of the run in `dir`, rebuilt from its summary.json.
pub fn scene(dir: &Path) -> Result<Scene, ExportError> {
    let summary = Summary::read(dir)?;
    let run = summary
        .run()
        .ok_or_else(|| bad(format!("{}: not a run", dir.display())))?;
    scene_of(run, &dir.join(SUMMARY_FILE))
}

/// The scene of a run: every key of summary.json's `parameters` set on the defaults.
fn scene_of(run: &RunInfo, path: &Path) -> Result<Scene, ExportError> {
    let params = run
        .parameters
        .as_ref()
        .ok_or_else(|| bad(format!("{}: no \"parameters\" object", path.display())))?;
    let origin = path.display().to_string();
    let assignments: Vec<(String, toml::Value, String)> = params
        .iter()
        .filter_map(|(k, v)| Some((k.clone(), json_to_toml(v)?, origin.clone())))
        .collect();
    Scene::from_parameters(&assignments, &origin).map_err(|e| bad(e.to_string()))
}

fn json_to_toml(v: &serde_json::Value) -> Option<toml::Value> {
    Some(match v {
        serde_json::Value::Bool(b) => toml::Value::Boolean(*b),
        serde_json::Value::Number(n) => match n.as_i64() {
            Some(i) => toml::Value::Integer(i),
            None => toml::Value::Float(n.as_f64()?),
        },
        serde_json::Value::String(s) => toml::Value::String(s.clone()),
        serde_json::Value::Array(items) => {
            toml::Value::Array(items.iter().filter_map(json_to_toml).collect())
        }
        // A lens of optics.lenses or a surface of optics.surfaces.
        serde_json::Value::Object(map) => toml::Value::Table(
            map.iter()
                .filter_map(|(k, v)| Some((k.clone(), json_to_toml(v)?)))
                .collect(),
        ),
        serde_json::Value::Null => return None,
    })
}

/// series.csv or history.csv, each column found by its header's name as the table of
/// outputs ([`crate::outputs::series_quantities`]) names it: a column the table marks as
/// added later, which runs written before it existed lack, is read as NaN; any other is
/// required.
pub fn read_series(path: &Path) -> Result<Vec<SeriesPoint>, ExportError> {
    let records = read_records(path)?;
    let header = records.header.clone().unwrap_or_default();
    let table = crate::outputs::series_quantities();
    let mut at = std::collections::HashMap::new();
    for q in &table {
        match header.iter().position(|h| h == q.name) {
            Some(j) => {
                at.insert(q.name, j);
            }
            None if q.added_later => {}
            None => {
                return Err(bad(format!(
                    "{}: no {:?} column in its header",
                    path.display(),
                    q.name
                )))
            }
        }
    }
    let mut out = Vec::new();
    for r in records.iter() {
        // A column's cell; None (NaN) for a later column the file lacks.
        let cell = |name: &str| at.get(name).map(|&j| r.cells.get(j));
        let number = |name: &str| cell(name)??.parse::<f64>().ok();
        let optional = |name: &str| match cell(name) {
            None => Some(f64::NAN),
            Some(v) => v?.parse::<f64>().ok(),
        };
        let row = (|| {
            Some(SeriesPoint {
                t: number("t")?,
                axial_length: number("axial_length")?,
                equatorial_radius: number("equatorial_radius")?,
                retina_minus_blue: number("retina_minus_blue")?,
                retina_minus_red: number("retina_minus_red")?,
                class: Refraction::parse(cell("class")??)?,
                refraction_d: optional("refraction_D")?,
                drive: optional("drive")?,
                defocus_d: optional("defocus_D")?,
            })
        })();
        out.push(row.ok_or_else(|| {
            bad(format!(
                "{}: line {}: not a series row: {:?}",
                path.display(),
                r.line,
                excerpt(r.text, 80)
            ))
        })?);
    }
    Ok(out)
}

/// A table column, or an error naming the file.
pub fn column(s: &RunSnapshot, name: &str) -> Result<Vec<f64>, ExportError> {
    s.table
        .column(name)
        .ok_or_else(|| bad(format!("{}: no column {name:?}", s.file.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row written in the table's columns reads back whole, and a file without a column
    /// the table requires is refused naming it: the columns read are the table's.
    #[test]
    fn a_series_row_reads_back_through_the_table_s_columns() {
        let row = SeriesPoint {
            t: 0.5,
            axial_length: 22.125,
            equatorial_radius: 12.25,
            retina_minus_blue: -0.375,
            retina_minus_red: 0.0625,
            class: Refraction::Myopic,
            refraction_d: -1.5,
            drive: 0.75,
            defocus_d: 0.875,
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("series.csv");
        let columns = crate::outputs::series_columns();
        let text = format!(
            "{}\n{}\n",
            columns.join(","),
            crate::outputs::series_cells(&row).join(",")
        );
        std::fs::write(&path, &text).unwrap();
        assert_eq!(read_series(&path).unwrap(), vec![row]);
        // Without the required axial_length column.
        let k = columns.iter().position(|c| *c == "axial_length").unwrap();
        let drop = |line: &str| {
            let mut cells: Vec<&str> = line.split(',').collect();
            cells.remove(k);
            cells.join(",")
        };
        let lines: Vec<String> = text.lines().map(drop).collect();
        std::fs::write(&path, lines.join("\n") + "\n").unwrap();
        let e = read_series(&path).unwrap_err().to_string();
        assert!(e.contains("no \"axial_length\" column"), "{e}");
    }
}
