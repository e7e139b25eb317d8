//! `eyeshell fit`: growth parameters fitted to measured axial lengths.
//!
//! Every check comes before anything is written (one line, exit 2): the scene, the
//! `--fit` keys, the data file, the output directory; then the fit (crates/eyeshell/src/fit),
//! which refuses (exit 2) a parameter the data cannot identify; then the directory, whole
//! or not at all: fit.json, scene.toml, residuals.csv, curve.csv, fit.png and fit.svg.

use eyeshell::fit::{self, FitOptions, Observations};
use eyeshell::rundir::{self, OutputDir, OutputError};
use eyeshell::text::one_line;
use eyeshell::Error;

use crate::args::FitArgs;
use crate::{out, plural};

/// The report of a fit.
pub const FIT_FILE: &str = "fit.json";
/// The scene with the estimates.
pub const SCENE_FILE: &str = "scene.toml";
/// Each observation against the fitted model.
pub const RESIDUALS_FILE: &str = "residuals.csv";
/// The fitted (and the initial) axial length on a fine grid of times.
pub const CURVE_FILE: &str = "curve.csv";
/// Points of the curves in curve.csv and the figure.
const CURVE_POINTS: usize = 200;

pub(crate) fn cmd_fit(a: &FitArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let params = fit::parse_keys(&a.fit, "--fit")?;
    let data = Observations::read(&a.data)?;
    let dir = OutputDir::create(&a.out, "fit", &[a.scene.scene.as_path(), a.data.as_path()])?;
    let options = FitOptions {
        max_iterations: a.max_iterations as usize,
        ..FitOptions::default()
    };
    let done = fit::fit(&scene, &data, &params, &options, &mut |_| {})?;
    let fitted = fit::curve(&done.scene, CURVE_POINTS)?;
    let initial = fit::curve(&scene, CURVE_POINTS)?;
    let r = &done.report;
    let io = |name: &str, source: std::io::Error| {
        Error::from(OutputError::Io {
            path: dir.file(name),
            source,
        })
    };
    let write = |name: &str, bytes: &[u8]| dir.write_file(name, bytes).map_err(Error::from);
    write(FIT_FILE, fit::report_json(r).as_bytes())?;
    write(
        SCENE_FILE,
        format!(
            "# The scene {} with {} fitted by `eyeshell fit` to {} (fit.json)\n{}",
            scene.origin,
            r.parameters
                .iter()
                .map(|p| p.key.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            data.origin,
            done.scene.to_toml()
        )
        .as_bytes(),
    )?;
    let v = rundir::format_value;
    let rows = r.residuals.iter().map(|x| {
        [
            v(x.t),
            v(x.axial_length),
            x.sigma.map_or(String::new(), v),
            v(x.model),
            v(x.residual),
            v(x.weighted),
        ]
    });
    let table = rundir::table::csv_bytes(
        [
            "t",
            "axial_length",
            "sigma",
            "model",
            "residual",
            "weighted_residual",
        ],
        rows,
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(RESIDUALS_FILE, e))?;
    write(RESIDUALS_FILE, &table)?;
    let curve = rundir::table::csv_bytes(
        ["t", "fitted_axial_length", "initial_axial_length"],
        fitted
            .iter()
            .zip(&initial)
            .map(|(f, i)| [v(f.0), v(f.1), v(i.1)]),
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(CURVE_FILE, e))?;
    write(CURVE_FILE, &curve)?;
    crate::figures::fit_figure(r, &fitted, &initial, &dir.file("fit"))?;
    let target = dir.commit()?;
    if !a.quiet {
        out(&report_text(&scene, r, &target));
    }
    Ok(())
}

/// The correlation matrix, its labels "(i) key" in a column as wide as the longest.
fn correlation_table(r: &fit::FitReport) -> String {
    let labels: Vec<String> = (r.parameters.iter().enumerate())
        .map(|(i, p)| format!("({}) {}", i + 1, p.key))
        .collect();
    let width = labels
        .iter()
        .map(|l| l.chars().count())
        .chain(["correlation".len()])
        .max()
        .unwrap_or(0);
    let mut text = format!("  {:width$}", "correlation");
    for j in 0..labels.len() {
        text.push_str(&format!("  {:>10}", format!("({})", j + 1)));
    }
    text.push('\n');
    for (label, row) in labels.iter().zip(&r.correlation) {
        text.push_str(&format!("  {label:width$}"));
        for c in row {
            text.push_str(&format!("  {c:>10.4}"));
        }
        text.push('\n');
    }
    text
}

/// |ρ| from which the report points a pair out.
const STRONG_CORRELATION: f64 = 0.99;

/// The pairs of fitted parameters correlated at |ρ| ≥ [`STRONG_CORRELATION`], with ρ: their
/// standard errors are mostly the width of a valley along which the data barely change
/// (BENCHMARKS.md, "Calibration": η0 and Γ on plateau data).
fn strongly_correlated(r: &fit::FitReport) -> Vec<(&str, &str, f64)> {
    let mut pairs = vec![];
    for (i, p) in r.parameters.iter().enumerate() {
        for (j, q) in r.parameters.iter().enumerate().skip(i + 1) {
            let c = r.correlation[i][j];
            if c.abs() >= STRONG_CORRELATION {
                pairs.push((p.key.as_str(), q.key.as_str(), c));
            }
        }
    }
    pairs
}

/// The table `eyeshell fit` prints.
pub fn report_text(
    scene: &eyeshell::Scene,
    r: &fit::FitReport,
    target: &std::path::Path,
) -> String {
    let n = r.parameters.len();
    let width = r
        .parameters
        .iter()
        .map(|p| p.key.chars().count())
        .max()
        .unwrap_or(0)
        .max(9);
    let mut text = format!(
        "eyeshell: fitted {} ({}) to {} ({} observation{}, {})\n",
        scene.origin,
        one_line(&scene.display_name()),
        r.data.file,
        r.data.observations,
        plural(r.data.observations),
        if r.data.sigma {
            "σ given"
        } else {
            "no σ: equal weights, covariance scaled by the residual variance"
        },
    );
    text.push_str(&format!(
        "  {:width$}  {:>12}  {:>12}  {:>12}  range\n",
        "parameter", "initial", "estimate", "std. error"
    ));
    let d6 = eyeshell::text::decimals6;
    for p in &r.parameters {
        text.push_str(&format!(
            "  {:width$}  {:>12}  {:>12}  {:>12}  {}{}\n",
            p.key,
            d6(p.initial),
            d6(p.estimate),
            d6(p.standard_error),
            p.range,
            if p.at_bound { " (at its bound)" } else { "" }
        ));
    }
    if n > 1 {
        text.push_str(&correlation_table(r));
    }
    let d4 = |x: f64| eyeshell::text::decimals(x, 4);
    let pairs = strongly_correlated(r);
    if !pairs.is_empty() {
        let list: Vec<String> = pairs
            .iter()
            .map(|(a, b, c)| format!("{a} and {b} at {c:.4}"))
            .collect();
        text.push_str(&format!(
            "  note             strongly correlated (|ρ| ≥ {STRONG_CORRELATION}): {}; the data determine a \
             combination of such a pair far better than either (fix one with --set, or add \
             observations that separate them)\n",
            list.join(", ")
        ));
    }
    text.push_str(&format!(
        "  χ²               {} (from {}), {} degree{} of freedom, χ²/dof {}; rms residual {} mm\n",
        d4(r.chi2),
        d4(r.initial_chi2),
        r.degrees_of_freedom,
        plural(r.degrees_of_freedom),
        d4(r.reduced_chi2),
        d4(r.rms_residual)
    ));
    text.push_str(&format!(
        "  iterations       {} ({} growth run{} with sensitivities); {}\n  time             {:.3} s\n  output           {}\n",
        r.iterations,
        r.model_runs,
        plural(r.model_runs),
        r.convergence_reason,
        r.wall_seconds,
        target.display()
    ));
    text
}
