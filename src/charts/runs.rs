//! Reading the runs back: the paper's run directories, a sweep's runs, one run.

use std::path::Path;

use eyeshell::interop::export::{bad, ExportError, RunSnapshot};
use eyeshell::rundir::rundata::{self, RunData};
use eyeshell::rundir::Summary;
use eyeshell::text::excerpt;

use super::plots::is_sweep;
use super::FigureError;

/// The run directories the paper's figures are drawn from (each a run or a sweep's run).
pub struct PaperRuns {
    pub constant: RunData,
    pub thick: RunData,
    /// (D, run), increasing D.
    pub fibre: Vec<(f64, RunData)>,
    /// (Γ, δ, run).
    pub grid: Vec<(f64, f64, RunData)>,
}

impl PaperRuns {
    /// Read the runs under `data`: `const/`, `thick/`, and the sweeps `fibre/`, `grow/`
    /// (as `eyeshell figures` writes them).
    pub fn read(data: &Path) -> Result<PaperRuns, FigureError> {
        let fibre = read_fibre(&data.join("fibre"))?;
        let grid = read_grid(&data.join("grow"))?;
        Ok(PaperRuns {
            constant: read_single(&data.join("const"))?,
            thick: read_single(&data.join("thick"))?,
            fibre,
            grid,
        })
    }
}

/// The fibre sweep's runs as (D, run), increasing D.
pub fn read_fibre(dir: &Path) -> Result<Vec<(f64, RunData)>, FigureError> {
    let mut fibre: Vec<(f64, RunData)> = sweep_runs(dir)?
        .into_iter()
        .map(|r| (r.scene.params.d, r))
        .collect();
    fibre.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(fibre)
}

/// The growth-zone grid's runs as (Γ, δ, run), in the order of its table.
pub fn read_grid(dir: &Path) -> Result<Vec<(f64, f64, RunData)>, FigureError> {
    Ok(sweep_runs(dir)?
        .into_iter()
        .map(|r| {
            let g = r.scene.growth.clone().unwrap_or_default();
            (g.gamma, g.delta, r)
        })
        .collect())
}

/// A one-run scene's run: a run directory, or a sweep of one run.
pub fn read_single(dir: &Path) -> Result<RunData, FigureError> {
    Ok(sweep_or_run(dir)?)
}

/// The longest run directory a sweep's summary may name: a sweep names them `runs/<name>`,
/// its names cut to at most 100 bytes.
const MAX_RUN_DIR: usize = 255;

/// Every run of a sweep directory, in the order of its table.
pub fn sweep_runs(dir: &Path) -> Result<Vec<RunData>, ExportError> {
    let path = dir.join(eyeshell::rundir::SUMMARY_FILE);
    if let Err(e) = std::fs::metadata(&path) {
        return Err(bad(format!("{}: not a sweep output ({e})", dir.display())));
    }
    let text = eyeshell::rundir::read::read_text(&path, eyeshell::rundir::read::MAX_SUMMARY_BYTES)?;
    let Summary::Sweep(sweep) = Summary::parse(&path, &text)? else {
        return Err(bad(format!(
            "{}: not a sweep output (no runs in summary.json)",
            dir.display()
        )));
    };
    sweep
        .runs
        .iter()
        .filter(|r| r.status == "ok" || r.status == "reused" || r.status == "failed")
        .map(|r| {
            // A cohort kept as a table (`per_run = "table"`) has rows, not run directories:
            // what there is to see of it is its population figure, drawn by the sweep.
            if r.dir.is_empty() && dir.join(eyeshell::sweep::compact::CHECKPOINT_FILE).is_file() {
                let figure = dir.join(format!("{}.png", crate::commands::sweep::POPULATION_FIGURE));
                let shown = if figure.is_file() {
                    format!("its figure is {}", crate::shown(&figure))
                } else {
                    "its figure (population.png) is drawn once every eye has run".to_string()
                };
                return Err(bad(format!(
                    "{}: a cohort kept as a table (per_run = \"table\") has no run directories to draw, only its rows (series.csv, sweep.csv) and population bands: {shown}; set per_run = \"directory\" for a directory per eye",
                    crate::shown(dir)
                )));
            }
            // A run lives below the sweep: a plain relative path, no `..`, not the sweep,
            // nothing a message could not show, no longer than a sweep names its runs.
            let inside = !r.dir.is_empty()
                && r.dir.len() <= MAX_RUN_DIR
                && !r.dir.chars().any(char::is_control)
                && Path::new(&r.dir)
                    .components()
                    .all(|c| matches!(c, std::path::Component::Normal(_)));
            if !inside {
                return Err(bad(format!(
                    "{}: run \"{}\" points outside the sweep's runs (\"{}\")",
                    path.display(),
                    excerpt(&r.name, 80),
                    excerpt(&r.dir, 80)
                )));
            }
            rundata::read(&dir.join(&r.dir))
        })
        .collect()
}

/// The one run in `dir`: a sweep's only run (as `eyeshell figures` writes it) or a run
/// directory. Which one is decided by summary.json, never by trying one after the other: the
/// error of the first would be lost, and the second would blame the wrong file.
fn sweep_or_run(dir: &Path) -> Result<RunData, ExportError> {
    if is_sweep(dir) {
        only_run(dir)
    } else {
        rundata::read(dir)
    }
}

fn only_run(dir: &Path) -> Result<RunData, ExportError> {
    sweep_runs(dir)?
        .into_iter()
        .next()
        .ok_or_else(|| bad(format!("{}: the sweep has no finished run", dir.display())))
}

pub(super) fn snapshots_at<'a>(run: &'a RunData, times: &[f64]) -> Vec<&'a RunSnapshot> {
    let mut out: Vec<&RunSnapshot> = times.iter().filter_map(|&t| run.snapshot_near(t)).collect();
    out.dedup_by(|a, b| a.t == b.t);
    out
}
