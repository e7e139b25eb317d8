//! `eyeshell fit`: growth parameters fitted to measured axial lengths.
//!
//! Every check comes before anything is written (one line, exit 2): the scene, the
//! `--fit` keys, the data file, the output directory; then the fit (crates/eyeshell/src/fit),
//! which refuses (exit 2) a parameter the data cannot identify; then the directory, whole
//! or not at all: fit.json, scene.toml, residuals.csv, curve.csv, fit.png and fit.svg.

use eyeshell::fit::{self, FitOptions, Observations};
use eyeshell::rundir::{self, OutputDir, OutputError};
use eyeshell::Error;

use crate::args::FitArgs;
use crate::out;

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
    // A scene in ages: residuals.csv and curve.csv end in the age column, as series.csv.
    let g = scene.growth.as_ref();
    let ages = g.is_some_and(|g| g.age_unit().is_some());
    let age_cell = |t: f64| g.and_then(|g| g.age_of(t)).map(v);
    let rows = r.residuals.iter().map(|x| {
        [
            v(x.t),
            v(x.axial_length),
            x.sigma.map_or(String::new(), v),
            v(x.model),
            v(x.residual),
            v(x.weighted),
        ]
        .into_iter()
        .chain(x.age.map(v))
        .collect::<Vec<_>>()
    });
    let table = rundir::table::csv_bytes(
        rundir::growth::with_age_column(
            &[
                "t",
                "axial_length",
                "sigma",
                "model",
                "residual",
                "weighted_residual",
            ],
            ages,
        ),
        rows,
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(RESIDUALS_FILE, e))?;
    write(RESIDUALS_FILE, &table)?;
    let curve = rundir::table::csv_bytes(
        rundir::growth::with_age_column(
            &["t", "fitted_axial_length", "initial_axial_length"],
            ages,
        ),
        fitted.iter().zip(&initial).map(|(f, i)| {
            [v(f.0), v(f.1), v(i.1)]
                .into_iter()
                .chain(age_cell(f.0))
                .collect::<Vec<_>>()
        }),
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(CURVE_FILE, e))?;
    write(CURVE_FILE, &curve)?;
    let axis = crate::charts::TimeAxis::of(&scene);
    crate::charts::fit_figure(r, &fitted, &initial, axis, &dir.file("fit"))?;
    let target = dir.commit()?;
    if !a.quiet {
        out(&report_text(&scene, r, &target));
    }
    Ok(())
}

/// The table `eyeshell fit` prints: the library's report, and where it was written.
pub fn report_text(
    scene: &eyeshell::Scene,
    r: &fit::FitReport,
    target: &std::path::Path,
) -> String {
    format!(
        "{}  output           {}\n",
        fit::report::report_table(scene, r),
        crate::shown(target)
    )
}
