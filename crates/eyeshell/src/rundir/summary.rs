//! summary.json, typed: what every eyeshell output directory says about itself, written in
//! one place ([`Summary::write`]) and read in one place ([`Summary::read`]).
//!
//! # Which summary a file is
//!
//! summary.json has no tag field (adding one would change the files), so [`Summary::parse`]
//! decides by the keys present, in this order:
//! - `sweep`: an `eyeshell sweep` directory ([`SweepSummary`]);
//! - `study`: an `eyeshell converge` / `wpd` / `refine` directory ([`StudySummary`]);
//! - `figures`: an `eyeshell figures` directory ([`FiguresSummary`]);
//! - `status` or `snapshots`: an `eyeshell grow` run, running, finished or failed
//!   ([`GrowthSummary`]; the rule export has always used);
//! - anything else: an `eyeshell solve` run ([`ElasticSummary`]).
//!
//! The sweep, study and figures summaries are variants of the same enum rather than types
//! of their own commands because summary.json is what marks any directory as eyeshell's:
//! one reader can then say what a directory is (a sweep is not a run to export, a
//! directory of figures is not a sweep to plot).
//!
//! # Bytes
//!
//! The files were written as `serde_json::Value` objects, whose keys serde_json keeps sorted
//! (the workspace does not enable `preserve_order`). [`Summary::to_text`] goes through
//! `serde_json::to_value` too, so the keys come out sorted as before whatever the field
//! order of the structs, and the bytes are those of earlier versions: non-finite numbers
//! are `null` (read back as NaN), and a trailing newline ends every summary but those of
//! the studies and the finished figures, which never had one.
//!
//! # Reading
//!
//! Missing fields take their defaults (a summary needs only the keys that say which one it
//! is, and a growth run its `status`), so older or hand-written files still read; a file
//! that is not JSON, or whose fields have the wrong types, is an error naming the file.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::growth::{HISTORY_FILE, SERIES_FILE};
use super::read::{bad, read_text, ReadError, MAX_SUMMARY_BYTES};
use super::{sundials_version, OutputError, SUMMARY_FILE};
use crate::bvp::SolveStats;
use crate::growth::{GrowthError, GrowthStats, SeriesRow};
use crate::json::{f64_or_nan, f64s_or_nan};
use crate::model::components::Components;
use crate::outputs::Measures;
use crate::scene::Scene;
use crate::text::excerpt;

/// The summary.json of any eyeshell output directory.
// One value per directory read or written: the variants' sizes do not matter, and boxing
// them would only make them clumsier to build and match.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Summary {
    /// `eyeshell solve`.
    Elastic(ElasticSummary),
    /// `eyeshell grow`.
    Growth(GrowthSummary),
    /// `eyeshell sweep`.
    Sweep(SweepSummary),
    /// `eyeshell converge`, `wpd`, `refine`.
    Study(StudySummary),
    /// `eyeshell figures`.
    Figures(FiguresSummary),
}

/// The part of summary.json every run of a scene shares: versions, the scene, the elastic
/// scheme and the effective parameters.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RunInfo {
    pub eyeshell_version: String,
    pub sundials_version: Option<String>,
    pub scene: SceneInfo,
    /// `solver.scheme`.
    pub scheme: String,
    pub scheme_order: u32,
    /// `solver.linear`.
    pub linear_solver: String,
    #[serde(deserialize_with = "f64_or_nan")]
    pub epsilon: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub length: f64,
    /// The model's components in one line.
    pub model: String,
    #[serde(with = "super::record::components::option")]
    pub components: Option<Components>,
    /// Every parameter key of the scene and its value (None: the file has none).
    pub parameters: Option<serde_json::Map<String, serde_json::Value>>,
}

/// Where a run's scene came from.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SceneInfo {
    pub name: String,
    /// The scene file (or the origin it was given).
    pub path: String,
    pub description: Option<String>,
    /// The `--set` overrides, in order.
    pub overrides: Vec<String>,
}

/// summary.json of `eyeshell solve`: the run, and every solver statistic by its name.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ElasticSummary {
    #[serde(flatten)]
    pub run: RunInfo,
    #[serde(flatten, with = "super::record::solve_stats")]
    pub stats: SolveStats,
}

/// How far a growth run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GrowthStatus {
    /// Still running, or killed (written at the start).
    Running,
    /// Reached t_end.
    Ok,
    /// Stopped by an error.
    Failed,
}

impl GrowthStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            GrowthStatus::Running => "running",
            GrowthStatus::Ok => "ok",
            GrowthStatus::Failed => "failed",
        }
    }
}

/// One snapshot written: its time and its file, relative to the run directory.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SnapshotEntry {
    #[serde(deserialize_with = "f64_or_nan")]
    pub t: f64,
    pub file: String,
}

/// The last row of series.csv: its t and the measures of the eye (the table of outputs';
/// a number null where none was computed, NaN in series.csv).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SeriesEntry {
    #[serde(deserialize_with = "f64_or_nan")]
    pub t: f64,
    #[serde(flatten, deserialize_with = "Measures::deserialize_lenient")]
    pub eye: Measures,
}

/// summary.json of `eyeshell grow`: rewritten at the start (`running`), and at the end
/// (`ok` with the statistics, or `failed` with where, why and the statistics so far).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrowthSummary {
    #[serde(flatten)]
    pub run: RunInfo,
    pub status: GrowthStatus,
    /// `solver.integrator`.
    #[serde(default)]
    pub integrator: String,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub rtol: f64,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub atol: f64,
    /// `solver.steps`.
    #[serde(default)]
    pub euler_steps: usize,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub t_end: f64,
    #[serde(default, deserialize_with = "f64s_or_nan")]
    pub output_times: Vec<f64>,
    /// `growth.thickness_law`.
    #[serde(default)]
    pub thickness_law: String,
    #[serde(default)]
    pub series_file: String,
    /// With `output.history_points` > 0 only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history_file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history_points: Option<usize>,
    /// The snapshots written so far, in time order.
    #[serde(default)]
    pub snapshots: Vec<SnapshotEntry>,
    /// The time of the last snapshot (null before the first).
    #[serde(default)]
    pub last_output_t: Option<f64>,
    /// The last series row (null before the first).
    #[serde(default, rename = "final")]
    pub last: Option<SeriesEntry>,
    /// Failed runs only: where and why.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failed_at_t: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Every statistic of the run by its name (not while it runs).
    #[serde(flatten, with = "super::record::growth_stats::option")]
    pub stats: Option<GrowthStats>,
}

/// The final state of one run of a sweep: its row of sweep.csv and its `result.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// "grow" or "solve".
    pub kind: String,
    /// The time reached (growth), 0 for an elastic solve.
    #[serde(deserialize_with = "f64_or_nan")]
    pub t: f64,
    /// The age of `t` when the scene counts in ages (time.unit), in that unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub age: Option<f64>,
    /// The measures of the eye at `t` (the table of outputs': docs/MODEL.md §6). One
    /// [`crate::outputs::Quantity::added_later`] reads as NaN from the result.json of a run
    /// by an earlier eyeshell, which did not record it; any other missing is an error.
    #[serde(flatten, deserialize_with = "Measures::deserialize_strict")]
    pub eye: Measures,
    pub newton_iterations: usize,
    pub bvp_solves: usize,
    pub steps: usize,
    pub rhs_evaluations: usize,
    #[serde(deserialize_with = "f64_or_nan")]
    pub wall_seconds: f64,
    /// Every file the run wrote but result.json, as it was when the run ended: what
    /// `--resume` checks before it reuses the run. Empty in the sweep's own summary.json,
    /// and in the result.json of runs by an earlier eyeshell (`--resume` runs them again).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<RunFile>,
}

/// One file of a finished sweep run: its path relative to the run directory (`/`
/// between components), its size and its FNV-1a 64 checksum (16 hex digits).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunFile {
    pub path: String,
    pub bytes: u64,
    pub fnv1a64: String,
}

/// summary.json of `eyeshell sweep`: its status and one entry per run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SweepSummary {
    /// The sweep's name.
    pub sweep: String,
    /// The sweep's scene file.
    pub scene: String,
    /// "running", "ok", "partial" (some runs failed) or "interrupted".
    pub status: String,
    /// The swept keys.
    pub keys: Vec<String>,
    /// The table's file name.
    pub table: String,
    pub runs_total: usize,
    pub runs_failed: usize,
    pub sundials_version: Option<String>,
    pub runs: Vec<SweepRunEntry>,
}

/// One run of a sweep.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SweepRunEntry {
    pub name: String,
    /// Its directory, relative to the sweep's.
    pub dir: String,
    /// "not run", "ok", "reused" or "failed".
    pub status: String,
    /// The swept values, by key.
    pub values: BTreeMap<String, String>,
    pub result: Option<RunResult>,
    pub error: Option<String>,
}

/// summary.json of a study (`eyeshell converge`, `wpd`, `refine`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StudySummary {
    pub study: String,
    pub sundials_version: Option<String>,
    /// The text the command printed.
    pub report: String,
}

/// summary.json of `eyeshell figures`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FiguresSummary {
    pub figures: Vec<FigureEntry>,
    /// The runs' directory (once finished).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub data: Option<String>,
    /// The index page (once finished).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index: Option<String>,
    /// "running", then "ok".
    pub status: String,
    /// The runs solved, and those copied from a run that is the same (once finished; not
    /// for a replot, which runs nothing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_solved: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs_shared: Option<usize>,
}

/// One figure: its files relative to the figures' directory.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FigureEntry {
    pub id: String,
    pub title: String,
    pub caption: String,
    pub png: String,
    pub svg: String,
}

/// A choice key's value (`solver.scheme`, ...) as summary.json names it.
fn key_name(scene: &Scene, key: &str) -> String {
    crate::scene::keys::find(key)
        .map(|s| s.get(scene).to_json())
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

impl RunInfo {
    /// What every run of `scene` writes.
    pub fn of(scene: &Scene) -> RunInfo {
        let parameters = match scene.parameters_json() {
            serde_json::Value::Object(map) => map,
            _ => serde_json::Map::new(),
        };
        RunInfo {
            eyeshell_version: env!("CARGO_PKG_VERSION").to_string(),
            sundials_version: sundials_version(),
            scene: SceneInfo {
                name: scene.display_name(),
                path: scene.origin.clone(),
                description: scene.description.clone(),
                overrides: scene.overrides.clone(),
            },
            scheme: key_name(scene, "solver.scheme"),
            scheme_order: scene.solver.scheme.order(),
            linear_solver: key_name(scene, "solver.linear"),
            epsilon: scene.solver.epsilon,
            length: scene.params.length(),
            model: scene.components().to_string(),
            components: Some(scene.components()),
            parameters: Some(parameters),
        }
    }
}

impl ElasticSummary {
    /// The summary of one solve of `scene`.
    pub fn new(scene: &Scene, stats: &SolveStats) -> ElasticSummary {
        ElasticSummary {
            run: RunInfo::of(scene),
            stats: stats.clone(),
        }
    }
}

/// How a growth run ended, for its summary.
#[derive(Clone, Copy, Debug)]
pub enum RunStatus<'a> {
    /// Still running (or killed): written at the start.
    Running,
    /// Reached t_end.
    Ok(&'a GrowthStats),
    /// Stopped by an error.
    Failed(&'a GrowthError),
}

impl GrowthSummary {
    /// The summary of a growth run of `scene`, given the snapshots written so far (time,
    /// file) and the last series row.
    pub fn new(
        scene: &Scene,
        status: RunStatus<'_>,
        snapshots: &[SnapshotEntry],
        last: Option<&SeriesRow>,
    ) -> GrowthSummary {
        let growth = scene.growth.clone().unwrap_or_default();
        let settings = &scene.growth_settings;
        let history = settings.history_points > 0;
        let (status_kind, stats, failed_at_t, error) = match status {
            RunStatus::Running => (GrowthStatus::Running, None, None, None),
            RunStatus::Ok(stats) => (GrowthStatus::Ok, Some(stats.clone()), None, None),
            RunStatus::Failed(e) => (
                GrowthStatus::Failed,
                Some(e.stats.as_ref().clone()),
                Some(e.t),
                Some(one_line(&e.to_string())),
            ),
        };
        GrowthSummary {
            run: RunInfo::of(scene),
            status: status_kind,
            integrator: key_name(scene, "solver.integrator"),
            rtol: settings.rtol,
            atol: settings.atol,
            euler_steps: settings.steps,
            t_end: growth.t_end,
            output_times: settings.output_times.clone(),
            thickness_law: key_name(scene, "growth.thickness_law"),
            series_file: SERIES_FILE.to_string(),
            history_file: history.then(|| HISTORY_FILE.to_string()),
            history_points: history.then_some(settings.history_points),
            snapshots: snapshots.to_vec(),
            last_output_t: snapshots.last().map(|s| s.t),
            last: last.map(|r| SeriesEntry {
                t: r.t,
                eye: Measures::of(r),
            }),
            failed_at_t,
            error,
            stats,
        }
    }
}

fn one_line(s: &str) -> String {
    s.chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect()
}

impl Summary {
    /// Which summary this is, in a word ("elastic run", "growth run", "sweep", ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Summary::Elastic(_) => "elastic run",
            Summary::Growth(_) => "growth run",
            Summary::Sweep(_) => "sweep",
            Summary::Study(_) => "study",
            Summary::Figures(_) => "figures",
        }
    }

    /// The run part, for an elastic or growth run.
    pub fn run(&self) -> Option<&RunInfo> {
        match self {
            Summary::Elastic(s) => Some(&s.run),
            Summary::Growth(s) => Some(&s.run),
            _ => None,
        }
    }

    /// The text of summary.json: pretty-printed with sorted keys (see the module doc),
    /// with the trailing newline each kind has always had.
    pub fn to_text(&self) -> String {
        let value = serde_json::to_value(self).unwrap_or_default();
        let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
        let newline = match self {
            Summary::Study(_) => false,
            Summary::Figures(f) => f.status == "running",
            _ => true,
        };
        if newline {
            text.push('\n');
        }
        text
    }

    /// Write the summary to `path` (a file named summary.json), atomically.
    pub fn write_to(&self, path: &Path) -> Result<(), OutputError> {
        super::write_atomic(path, self.to_text().as_bytes()).map_err(|e| OutputError::io(path, e))
    }

    /// Write the summary into the directory `dir`, atomically.
    pub fn write(&self, dir: &Path) -> Result<(), OutputError> {
        self.write_to(&dir.join(SUMMARY_FILE))
    }

    /// Read the summary.json of `dir`. Errors (bad input) name the directory when there is
    /// no summary to read, the file when it is not one.
    pub fn read(dir: &Path) -> Result<Summary, ReadError> {
        let path = dir.join(SUMMARY_FILE);
        if let Err(e) = fs::metadata(&path) {
            return Err(bad(format!(
                "{}: not an eyeshell run directory ({SUMMARY_FILE}: {e})",
                dir.display()
            )));
        }
        Summary::parse(&path, &read_text(&path, MAX_SUMMARY_BYTES)?)
    }

    /// Parse the text of summary.json (`path` for the messages); see the module doc for
    /// how the kind is told.
    pub fn parse(path: &Path, text: &str) -> Result<Summary, ReadError> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
            bad(format!(
                "{}: not valid JSON: {}",
                path.display(),
                excerpt(&e.to_string(), 200)
            ))
        })?;
        let has = |k: &str| value.get(k).is_some();
        let typed = |kind: &str, r: Result<Summary, serde_json::Error>| {
            r.map_err(|e| {
                bad(format!(
                    "{}: not a valid {kind} summary: {}",
                    path.display(),
                    excerpt(&e.to_string(), 200)
                ))
            })
        };
        if !value.is_object() {
            return Err(bad(format!(
                "{}: not an eyeshell summary (not a JSON object)",
                path.display()
            )));
        }
        if has("sweep") {
            typed("sweep", serde_json::from_value(value).map(Summary::Sweep))
        } else if has("study") {
            typed("study", serde_json::from_value(value).map(Summary::Study))
        } else if has("figures") {
            typed(
                "figures",
                serde_json::from_value(value).map(Summary::Figures),
            )
        } else if has("status") || has("snapshots") {
            let growth = serde_json::from_value::<GrowthSummary>(value).map(|mut g| {
                // The statistics' fields all have defaults, so they always parse: a running
                // run has none.
                if g.status == GrowthStatus::Running {
                    g.stats = None;
                }
                Summary::Growth(g)
            });
            typed("growth run", growth)
        } else {
            typed(
                "elastic run",
                serde_json::from_value(value).map(Summary::Elastic),
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn growing_scene() -> Scene {
        Scene::from_toml_str(
            "growth.eta0 = 70\nsolver.nodes = 11\noutput.history_points = 5",
            "g.toml",
            &["pressure.dP=2.5".to_string()],
        )
        .unwrap()
    }

    fn round_trip(s: &Summary) -> Summary {
        Summary::parse(Path::new("summary.json"), &s.to_text()).unwrap()
    }

    #[test]
    fn keys_come_out_sorted_like_a_json_value() {
        let s = Summary::Elastic(ElasticSummary::new(
            &Scene::default(),
            &SolveStats::default(),
        ));
        let text = s.to_text();
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        let mut again = serde_json::to_string_pretty(&value).unwrap();
        again.push('\n');
        assert_eq!(text, again);
        let keys: Vec<&String> = value.as_object().unwrap().keys().collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted);
        assert!(text.find("\"atol\"").is_none());
        assert!(text.find("\"components\"").unwrap() < text.find("\"epsilon\"").unwrap());
    }

    #[test]
    fn every_kind_reads_back_as_itself() {
        let scene = growing_scene();
        let elastic = Summary::Elastic(ElasticSummary::new(
            &scene,
            &SolveStats {
                nodes: 11,
                residual_norm: f64::NAN,
                ..SolveStats::default()
            },
        ));
        let Summary::Elastic(back) = round_trip(&elastic) else {
            panic!("not elastic")
        };
        assert!(back.stats.residual_norm.is_nan());
        assert_eq!(back.stats.nodes, 11);
        assert_eq!(back.run, elastic.run().unwrap().clone());

        let snaps = [SnapshotEntry {
            t: 0.0,
            file: "snapshots/snapshot_00000_t0.000000.csv".into(),
        }];
        let running = Summary::Growth(GrowthSummary::new(&scene, RunStatus::Running, &snaps, None));
        assert_eq!(round_trip(&running), running);
        let stats = GrowthStats {
            steps: 3,
            t_reached: 0.25,
            ..GrowthStats::default()
        };
        let error = GrowthError {
            t: 0.25,
            reason: "no\nway".into(),
            stats: Box::new(stats.clone()),
        };
        let failed = Summary::Growth(GrowthSummary::new(
            &scene,
            RunStatus::Failed(&error),
            &snaps,
            None,
        ));
        let back = round_trip(&failed);
        assert_eq!(back, failed);
        let Summary::Growth(g) = back else {
            panic!("not growth")
        };
        assert_eq!(g.status, GrowthStatus::Failed);
        assert_eq!(g.failed_at_t, Some(0.25));
        assert_eq!(
            g.error.as_deref(),
            Some("growth failed at t = 0.250000: no way")
        );
        assert_eq!(g.stats, Some(stats.clone()));
        assert_eq!(g.history_file.as_deref(), Some(HISTORY_FILE));
        let ok = Summary::Growth(GrowthSummary::new(
            &scene,
            RunStatus::Ok(&stats),
            &snaps,
            None,
        ));
        assert_eq!(round_trip(&ok), ok);

        let sweep = Summary::Sweep(SweepSummary {
            sweep: "s".into(),
            status: "ok".into(),
            runs: vec![SweepRunEntry {
                name: "a".into(),
                status: "ok".into(),
                ..SweepRunEntry::default()
            }],
            ..SweepSummary::default()
        });
        assert_eq!(round_trip(&sweep), sweep);
        let study = Summary::Study(StudySummary {
            study: "converge".into(),
            sundials_version: None,
            report: "r".into(),
        });
        assert_eq!(round_trip(&study), study);
        assert!(!study.to_text().ends_with('\n'));
        let figures = Summary::Figures(FiguresSummary {
            status: "running".into(),
            ..FiguresSummary::default()
        });
        assert_eq!(
            figures.to_text(),
            "{\n  \"figures\": [],\n  \"status\": \"running\"\n}\n"
        );
        assert_eq!(round_trip(&figures), figures);
    }

    #[test]
    fn bad_files_are_errors_naming_them() {
        let p = Path::new("run/summary.json");
        let e = Summary::parse(p, "{ nope").unwrap_err();
        assert!(e.bad_input && e.message.starts_with("run/summary.json: not valid JSON: "));
        let e = Summary::parse(p, "[1]").unwrap_err();
        assert!(e.message.contains("not a JSON object"), "{e}");
        let e = Summary::parse(p, "{\"status\": \"sleeping\"}").unwrap_err();
        assert!(e.message.contains("not a valid growth run summary"), "{e}");
        let e = Summary::parse(p, "{\"nodes\": \"many\"}").unwrap_err();
        assert!(e.message.contains("not a valid elastic run summary"), "{e}");
        // A minimal file still reads.
        assert!(matches!(
            Summary::parse(p, "{}").unwrap(),
            Summary::Elastic(_)
        ));
        let dir = tempfile::tempdir().unwrap();
        let e = Summary::read(dir.path()).unwrap_err();
        assert!(
            e.message
                .contains("not an eyeshell run directory (summary.json: "),
            "{e}"
        );
    }
}
