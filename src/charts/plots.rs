//! `eyeshell plot`: the pictures of one run, of a sweep, and of several runs compared.

use std::path::{Path, PathBuf};

use eyeshell::interop::export::{bad, ExportError, RunSnapshot};
use eyeshell::rundir::rundata::{self, RunData, RunKind};
use eyeshell::rundir::Summary;
use eyeshell_plot::{self as plot, colormap, Figure, Series, SeriesStyle};

use super::panels::{axial_panel, eta_max, profile_panel, shell_panel, TimeAxis};
use super::runs::sweep_runs;
use super::{FigureError, BLUE, PANEL, RED};
use crate::image;

/// Draw the run (or sweep) in `dir` into `out`: for a growth run its shells, stretches,
/// tensions, axial length, growth stimulus and peripheral refraction; for an elastic run its shape and fields against Σ; for a
/// sweep, each run into `out/<run>/` and the axial lengths of all runs together.
pub fn plot_run(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    if is_sweep(dir) {
        return plot_sweep(dir, out);
    }
    plot_one(dir, out)
}

/// The pictures of one run directory (never a sweep: a sweep's runs are drawn by this, so
/// a run that names a sweep, even its own, cannot send the drawing round in circles).
fn plot_one(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let run = rundata::read(dir)?;
    let stem = |name: &str| out.join(name);
    let mut files = Vec::new();
    let mut push = |f: (PathBuf, PathBuf)| files.extend([f.0, f.1]);
    match &run.kind {
        RunKind::Elastic(table) => {
            let col = |n: &str| {
                table.column(n).ok_or_else(|| {
                    bad(format!("{}: fields.csv has no column {n:?}", dir.display()))
                })
            };
            let (z, r) = (col("z")?, col("r")?);
            let mut shape = Figure::new(format!("{}: loaded shell", run.name), "z (mm)", "r (mm)")
                .with(Series::new(
                    "mid-surface",
                    z.iter().copied().zip(r.iter().copied()).collect(),
                    SeriesStyle::Line,
                ));
            shape.aspect_equal = true;
            let sigma = col("Sigma")?;
            let vs = |field: &str, label: &str| -> Result<Figure, ExportError> {
                Ok(Figure::new(label.to_string(), "Σ (mm)", label.to_string())
                    .with(Series::new(
                        label.to_string(),
                        sigma.iter().copied().zip(col(field)?).collect(),
                        SeriesStyle::Line,
                    ))
                    .no_legend())
            };
            let panels = vec![
                shape,
                vs("alpha_s", "α_s")?,
                vs("alpha_phi", "α_φ")?,
                vs("kappa", "κ (1/mm)")?,
                vs("t_s", "t_s (kPa·mm)")?,
                vs("Q", "Q")?,
            ];
            push(image::write_panels(
                &panels,
                3,
                &run.name,
                PANEL.0,
                PANEL.1,
                &stem("fields"),
            )?);
        }
        RunKind::Growth { .. } => {
            let axis = TimeAxis::of(&run.scene);
            let snaps: Vec<&RunSnapshot> = run.snapshots().iter().collect();
            let top = eta_max(&snaps);
            let shells = snaps
                .iter()
                .map(|s| shell_panel(axis.label(s.t), &run.scene, s, top))
                .collect::<Result<Vec<_>, _>>()?;
            let columns = shells.len().clamp(1, 3);
            push(image::write_panels(
                &shells,
                columns,
                &format!("{}: shells", run.name),
                PANEL.0,
                PANEL.1,
                &stem("shells"),
            )?);
            let profiles = vec![
                profile_panel("α_s", "alpha_s", "α_s", &snaps, axis)?,
                profile_panel("α_φ", "alpha_phi", "α_φ", &snaps, axis)?,
                profile_panel("η", "eta", "η (1/mm)", &snaps, axis)?,
                profile_panel("t_s", "t_s", "t_s (kPa·mm)", &snaps, axis)?,
            ];
            push(image::write_panels(
                &profiles,
                2,
                &format!("{}: profiles against σ", run.name),
                PANEL.0,
                PANEL.1,
                &stem("profiles"),
            )?);
            let tl = run.timeline();
            let axial = axial_panel("axial length", &[(run.name.clone(), &run)]).no_legend();
            let refraction = Figure::new(
                "retina behind the best-focus surfaces",
                axis.title(),
                "distance behind (mm)",
            )
            .with(
                Series::new(
                    "behind blue",
                    tl.iter()
                        .map(|p| (axis.x(p.t), p.retina_minus_blue))
                        .collect(),
                    SeriesStyle::Line,
                )
                .color(BLUE),
            )
            .with(
                Series::new(
                    "behind red",
                    tl.iter()
                        .map(|p| (axis.x(p.t), p.retina_minus_red))
                        .collect(),
                    SeriesStyle::Line,
                )
                .color(RED),
            );
            push(image::write_panels(
                &[axial, refraction],
                2,
                &format!("{}: the eye in time", run.name),
                PANEL.0,
                PANEL.1,
                &stem("timeline"),
            )?);
            push(image::write_panels(
                &stimulus_panels(dir, &snaps, axis)?,
                2,
                &format!("{}: growth stimulus and peripheral refraction", run.name),
                PANEL.0,
                PANEL.1,
                &stem("stimulus"),
            )?);
            if let Some(panels) = sensitivity_panels(dir, axis)? {
                push(image::write_panels(
                    &panels,
                    2,
                    &format!("{}: sensitivities", run.name),
                    PANEL.0,
                    PANEL.1,
                    &stem("sensitivities"),
                )?);
            }
        }
    }
    Ok(files)
}

/// A line of a figure: (t, value) points.
type Curve = Vec<(f64, f64)>;

/// A growth run's peripheral.csv as curves of the naked eye's relative_D against the field
/// angle, one per output time (in time order); None for a run without the file. A run of an
/// eye that wears lenses also holds the rows through them (`through` other than `naked`),
/// which these curves leave out.
fn peripheral_curves(dir: &Path) -> Result<Option<Vec<(f64, Curve)>>, ExportError> {
    use eyeshell::rundir::growth::PERIPHERAL_FILE;
    let path = dir.join(PERIPHERAL_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let records = eyeshell::rundir::table::read_records(&path)?;
    let header = records.header.clone().unwrap_or_default();
    let col = |n: &str| {
        (header.iter())
            .position(|c| c == n)
            .ok_or_else(|| bad(format!("{}: no column {n:?}", path.display())))
    };
    let (t, field, relative) = (col("t")?, col("field_deg")?, col("relative_D")?);
    let through = header.iter().position(|c| c == "through");
    let mut curves: Vec<(f64, Curve)> = vec![];
    for r in records.iter() {
        if through.is_some_and(|k| r.cells.get(k) != Some("naked")) {
            continue;
        }
        let value = |j: usize| -> Result<f64, ExportError> {
            let cell = r.cells.get(j).unwrap_or_default();
            cell.parse::<f64>().map_err(|_| {
                bad(format!(
                    "{}: line {}: {:?} ({}) is not a number",
                    path.display(),
                    r.line,
                    cell,
                    header[j]
                ))
            })
        };
        let (t, f, d) = (value(t)?, value(field)?, value(relative)?);
        match curves.last_mut() {
            Some((at, c)) if *at == t => c.push((f, d)),
            _ => curves.push((t, vec![(f, d)])),
        }
    }
    Ok(Some(curves))
}

/// The growth-rate map of a growth run: the stimulus g_v (the rate of growth at each point,
/// docs/MODEL.md §6) against σ at each output time, and the relative peripheral refraction
/// against the field angle at each output time (when the run wrote peripheral.csv).
fn stimulus_panels(
    dir: &Path,
    snaps: &[&RunSnapshot],
    axis: TimeAxis,
) -> Result<Vec<Figure>, ExportError> {
    let mut panels = vec![profile_panel(
        "growth stimulus g_v (0: no growth)",
        "g_v",
        "g_v",
        snaps,
        axis,
    )?];
    if let Some(curves) = peripheral_curves(dir)? {
        let last = curves.len().saturating_sub(1).max(1) as f64;
        let fig = curves.into_iter().enumerate().fold(
            Figure::new(
                "peripheral refraction, naked eye",
                "field angle (°)",
                "relative to the pole (D)",
            ),
            |f, (k, (t, c))| {
                f.with(
                    Series::new(axis.label(t), c, SeriesStyle::Line)
                        .color(colormap(0.85 * k as f64 / last)),
                )
            },
        );
        panels.push(fig);
    }
    Ok(panels)
}

/// Several growth runs drawn together into `out` (`compare.png`, `.svg`): their axial length
/// and their refraction_D against t, and the relative peripheral refraction against the field
/// angle at each run's last output time (runs without peripheral.csv are left out of it).
/// Each run is named by its directory.
pub fn plot_compare(dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let mut runs = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let run = rundata::read(dir)?;
        if run.timeline().is_empty() {
            return Err(FigureError::Read(bad(format!(
                "{}: is not a growth run: only growth runs are drawn together",
                dir.display()
            ))));
        }
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| dir.display().to_string());
        runs.push((name, run));
    }
    let named: Vec<(String, &RunData)> = runs.iter().map(|(n, r)| (n.clone(), r)).collect();
    let axial = axial_panel("axial length", &named);
    let ages = TimeAxis::of_runs(runs.iter().map(|(_, r)| &r.scene));
    let mut refraction = Figure::new("refraction at the pole", ages.title(), "refraction_D (D)");
    let mut peripheral = Figure::new(
        "peripheral refraction at the end, naked eye",
        "field angle (°)",
        "relative to the pole (D)",
    );
    for (k, ((name, run), dir)) in runs.iter().zip(dirs).enumerate() {
        let colour = plot::PALETTE[k % 10];
        let axis = if ages.clock.is_some() {
            TimeAxis::of(&run.scene)
        } else {
            ages
        };
        let pts = run
            .timeline()
            .iter()
            .map(|p| (axis.x(p.t), p.refraction_d))
            .collect();
        refraction =
            refraction.with(Series::new(name.clone(), pts, SeriesStyle::Line).color(colour));
        if let Some((_, last)) = peripheral_curves(dir)?.and_then(|mut c| c.pop()) {
            peripheral =
                peripheral.with(Series::new(name.clone(), last, SeriesStyle::Line).color(colour));
        }
    }
    let (png, svg) = image::write_panels(
        &[axial, refraction, peripheral],
        3,
        "growth runs compared",
        PANEL.0,
        PANEL.1,
        &out.join("compare"),
    )?;
    Ok(vec![png, svg])
}

/// sensitivities.csv of a growth run (`grow --sensitivities`) against time (`axis`), one
/// line per parameter: dL/dp, d(equatorial radius)/dp, d(retina − blue)/dp and (p/L)
/// dL/dp. None without the file.
fn sensitivity_panels(dir: &Path, axis: TimeAxis) -> Result<Option<Vec<Figure>>, ExportError> {
    let Some(rows) = eyeshell::rundir::read::read_sensitivities(dir)? else {
        return Ok(None);
    };
    // Per parameter, in order of first appearance: its (t, value) for each column after the
    // parameter's.
    let mut lines: Vec<(String, [Curve; 4])> = vec![];
    for row in rows {
        let slot = match lines.iter().position(|(p, _)| *p == row.parameter) {
            Some(i) => i,
            None => {
                lines.push((row.parameter, Default::default()));
                lines.len() - 1
            }
        };
        for (c, v) in row.values.into_iter().enumerate() {
            lines[slot].1[c].push((axis.x(row.t), v));
        }
    }
    let labels = [
        "d(axial length)/dp",
        "d(equatorial radius)/dp",
        "d(retina − blue)/dp",
        "(p/L) dL/dp",
    ];
    let panels = labels
        .iter()
        .enumerate()
        .map(|(c, label)| {
            lines.iter().fold(
                Figure::new(label.to_string(), axis.title(), label.to_string()),
                |f, (key, cols)| {
                    f.with(Series::new(key.clone(), cols[c].clone(), SeriesStyle::Line))
                },
            )
        })
        .collect();
    Ok(Some(panels))
}

/// Does `dir` hold a sweep's output (summary.json with a list of runs)?
pub fn is_sweep(dir: &Path) -> bool {
    matches!(Summary::read(dir), Ok(Summary::Sweep(_)))
}

fn plot_sweep(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let runs = sweep_runs(dir)?;
    if runs.is_empty() {
        return Err(FigureError::Read(bad(format!(
            "{}: the sweep has no run to draw",
            dir.display()
        ))));
    }
    let mut files = Vec::new();
    for run in &runs {
        let name = run
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        files.extend(plot_one(&run.dir, &out.join(&name))?);
    }
    let growing: Vec<(String, &RunData)> = runs
        .iter()
        .filter(|r| !r.timeline().is_empty())
        .map(|r| {
            (
                r.dir
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                r,
            )
        })
        .collect();
    if !growing.is_empty() {
        let fig = axial_panel("axial length of every run", &growing);
        let (png, svg) = image::write(&fig, &out.join("axial_length"))?;
        files.extend([png, svg]);
    }
    Ok(files)
}
