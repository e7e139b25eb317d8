//! Studies written out: CSV tables, log-log figures (PNG and SVG) and a short text summary
//! for the command line (`eyeshell converge`, `wpd`, `refinement`).

use super::converge::{self, Knob, Ladder};
use super::{refinement, worst, wpd, write_csv, StudyError, FIELDS};
use eyeshell::growth::{GrowthSettings, Integrator};
use eyeshell::scene::Scene;
use eyeshell_plot::{Figure, Scale, Series, SeriesStyle};
use std::fmt::Write as _;
use std::path::Path;

fn plot_error(e: crate::image::ImageError) -> StudyError {
    StudyError::Invalid(e.to_string())
}

/// Write a ladder: `<stem>.csv` and a figure of each field's error against the knob.
fn write_ladder(l: &Ladder, dir: &Path, stem: &str) -> Result<(), StudyError> {
    let (header, rows) = converge::table(l);
    write_csv(&dir.join(format!("{stem}.csv")), &header, &rows)?;
    let (x_label, xs) = match l.knob {
        Knob::Nodes => ("mesh spacing h (mm)", &l.scale),
        Knob::Epsilon => ("pole truncation ε (mm)", &l.scale),
        Knob::Tolerance => ("tolerance", &l.scale),
        Knob::Steps => ("time step (t_end / steps)", &l.scale),
    };
    let errors = l.errors();
    let against = if l.err_richardson.is_some() {
        "Richardson extrapolation"
    } else {
        "finest rung"
    };
    let mut fig = Figure::new(
        format!(
            "Convergence in {} (error against the {against})",
            l.knob.name()
        ),
        x_label,
        "largest error",
    )
    .scales(Scale::Log10, Scale::Log10);
    for (c, name) in FIELDS.iter().enumerate() {
        let pts = errors
            .iter()
            .zip(xs.iter())
            .map(|(e, &x)| (x, e[c]))
            .collect();
        fig = fig.with(Series::new(*name, pts, SeriesStyle::LineAndMarkers));
    }
    crate::image::write(&fig, &dir.join(stem)).map_err(plot_error)?;
    Ok(())
}

fn describe_ladder(l: &Ladder, text: &mut String) {
    let e: Vec<String> = l
        .errors()
        .iter()
        .map(|e| format!("{:.2e}", worst(e)))
        .collect();
    let o: Vec<String> = l.worst_orders().iter().map(|o| format!("{o:.2}")).collect();
    let v: Vec<String> = l
        .values
        .iter()
        .map(|v| {
            if l.knob == Knob::Nodes {
                format!("{v}")
            } else {
                format!("{v:e}")
            }
        })
        .collect();
    let _ = writeln!(
        text,
        "  {:<10} {}\n  {:<10} {}\n  {:<10} {}",
        l.knob.name(),
        v.join(", "),
        "error",
        e.join(", "),
        "order",
        o.join(", ")
    );
}

/// `eyeshell converge`: ladders in N, ε and the tolerance on a scene (growth with `growth`).
pub fn converge(
    scene: &Scene,
    nodes: &[usize],
    growth: bool,
    dir: &Path,
) -> Result<String, StudyError> {
    let g = match (growth, &scene.growth) {
        (true, Some(g)) => Some((g, &scene.growth_settings)),
        (true, None) => {
            return Err(StudyError::Invalid(
                "--growth needs a scene with a [growth] section".into(),
            ))
        }
        (false, _) => None,
    };
    let (p, s) = (&scene.params, &scene.solver);
    let mut text = String::new();
    let nodes: Vec<f64> = nodes.iter().map(|&n| n as f64).collect();
    let eps = s.epsilon;
    let tolerances: Vec<f64> = if g.is_some() {
        vec![1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
    } else {
        vec![1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
    };
    let mut ladders = vec![
        (
            Knob::Nodes,
            nodes,
            "converge_nodes".to_string(),
            g.map(|(_, s)| s.clone()),
        ),
        (
            Knob::Epsilon,
            vec![10.0 * eps, eps, eps / 10.0, eps / 100.0],
            "converge_epsilon".to_string(),
            g.map(|(_, s)| s.clone()),
        ),
    ];
    match g {
        // Growth: each time integrator on its own knob (IDA and CVODE by tolerance, the
        // published Euler by step count).
        Some((_, gs)) => {
            for integrator in [Integrator::Ida, Integrator::Cvode] {
                let s = GrowthSettings {
                    integrator,
                    ..gs.clone()
                };
                ladders.push((
                    Knob::Tolerance,
                    tolerances.clone(),
                    format!("converge_tolerance_{}", integrator.name()),
                    Some(s),
                ));
            }
            ladders.push((
                Knob::Steps,
                vec![50.0, 100.0, 200.0, 400.0, 800.0],
                "converge_steps_euler".to_string(),
                Some(gs.clone()),
            ));
        }
        None => ladders.push((
            Knob::Tolerance,
            tolerances,
            "converge_tolerance".to_string(),
            None,
        )),
    }
    for (knob, values, stem, settings) in ladders {
        let growth = g.map(|(gp, _)| gp).zip(settings.as_ref());
        let l = converge::ladder(p, s, growth, knob, &values)?;
        write_ladder(&l, dir, &stem)?;
        let _ = writeln!(
            text,
            "{}:",
            stem.trim_start_matches("converge_").replace('_', " ")
        );
        describe_ladder(&l, &mut text);
    }
    Ok(text)
}

/// `eyeshell wpd`: work-precision diagrams, elastic always, growth when the scene grows.
pub fn wpd(scene: &Scene, dir: &Path) -> Result<String, StudyError> {
    let (p, s) = (&scene.params, &scene.solver);
    let mut text = String::new();
    let nodes = [26, 51, 101, 201, 401, 801, 1601];
    let curves = wpd::elastic(p, s, &nodes)?;
    write_curves(
        &curves,
        dir,
        "wpd_elastic",
        "elastic solve: largest field error against HS on a 4× finer mesh",
        false,
    )?;
    describe_winners(
        &curves,
        &[1e-4, 1e-6, 1e-8, 1e-10, 1e-12],
        false,
        &mut text,
        "elastic",
    );
    write_tolerance(&curves, dir, &mut text)?;
    write_efficiency(&wpd::efficiency(p, s, &wpd::TOLERANCES)?, dir, &mut text)?;
    let problem = scene
        .growth_problem()
        .map_err(|e| StudyError::Invalid(e.to_string()))?;
    if let Some(problem) = &problem {
        let curves = wpd::growth(
            problem,
            &[50, 100, 200, 400, 800],
            &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8],
            1e-10,
        )?;
        write_curves(
            &curves,
            dir,
            "wpd_growth",
            "growth to t_end: largest field error against CVODE rtol 1e-10",
            false,
        )?;
        write_curves(
            &curves,
            dir,
            "wpd_growth_axial",
            "growth to t_end: axial-length error (largest over the output times) against CVODE rtol 1e-10",
            true,
        )?;
        describe_winners(
            &curves,
            &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6],
            true,
            &mut text,
            "growth (axial length)",
        );
        let tol = wpd::growth_tolerance(
            problem,
            &wpd::GROWTH_TOLERANCES,
            &wpd::GROWTH_LADDER,
            wpd::GROWTH_REFERENCE,
        )?;
        let (n, rtol) = wpd::GROWTH_REFERENCE;
        write_curves(
            &tol,
            dir,
            "wpd_growth_tol",
            &format!(
                "growth to t_end, solver.tol beside fixed (N, rtol): axial-length error against IDA N = {n}, rtol {rtol:e}"
            ),
            true,
        )?;
        write_tolerance_growth(&tol, dir, &mut text)?;
    }
    Ok(text)
}

fn write_curves(
    curves: &[wpd::Curve],
    dir: &Path,
    stem: &str,
    title: &str,
    axial: bool,
) -> Result<(), StudyError> {
    let (header, rows) = wpd::table(curves);
    write_csv(&dir.join(format!("{stem}.csv")), &header, &rows)?;
    let mut fig = Figure::new(
        title,
        if axial {
            "axial-length error (mm)"
        } else {
            "largest error"
        },
        "seconds",
    )
    .scales(Scale::Log10, Scale::Log10);
    for c in curves {
        let pts = c
            .points
            .iter()
            .map(|p| (if axial { p.axial_error } else { p.error }, p.seconds))
            .collect();
        fig = fig.with(Series::new(
            c.method.clone(),
            pts,
            SeriesStyle::LineAndMarkers,
        ));
    }
    crate::image::write(&fig, &dir.join(stem)).map_err(plot_error)?;
    Ok(())
}

/// What a tolerance plot says: its title, axes, error series, file stem and report header.
struct ToleranceLabels {
    title: &'static str,
    x: &'static str,
    y: &'static str,
    error: &'static str,
    stem: &'static str,
    header: &'static str,
}

/// A curve of `solver.tol` points: `error` and the estimate against the tolerance asked
/// for, with the line error = tol, drawn and listed in the report.
fn write_tolerance_curve(
    c: &wpd::Curve,
    error: fn(&wpd::WorkPoint) -> f64,
    labels: ToleranceLabels,
    dir: &Path,
    text: &mut String,
) -> Result<(), StudyError> {
    let pick = |f: &dyn Fn(&wpd::WorkPoint) -> f64| -> Vec<(f64, f64)> {
        c.points.iter().map(|p| (p.value, f(p))).collect()
    };
    let fig = Figure::new(labels.title, labels.x, labels.y)
        .scales(Scale::Log10, Scale::Log10)
        .with(Series::new(
            labels.error.to_string(),
            pick(&error),
            SeriesStyle::LineAndMarkers,
        ))
        .with(Series::new(
            "estimate".to_string(),
            pick(&|p| p.estimate),
            SeriesStyle::LineAndMarkers,
        ))
        .with(Series::new(
            "error = tol".to_string(),
            pick(&|p| p.value),
            SeriesStyle::DashedLine,
        ));
    crate::image::write(&fig, &dir.join(labels.stem)).map_err(plot_error)?;
    let _ = writeln!(text, "{}", labels.header);
    for p in &c.points {
        let _ = writeln!(
            text,
            "  {:.0e}  {:.2e}  {:.2e}  {}  {:.4} s",
            p.value,
            error(p),
            p.estimate,
            p.nodes,
            p.seconds
        );
    }
    Ok(())
}

/// The tolerance-driven solves: true error and estimate against the tolerance asked for,
/// with the line error = tol.
fn write_tolerance(curves: &[wpd::Curve], dir: &Path, text: &mut String) -> Result<(), StudyError> {
    let Some(c) = curves.iter().find(|c| c.knob == "tol") else {
        return Ok(());
    };
    let labels = ToleranceLabels {
        title: "solver.tol: true error and estimate against the tolerance asked for",
        x: "requested tol",
        y: "largest field error",
        error: "true error",
        stem: "wpd_tolerance",
        header: "solver.tol: requested, true error, estimate, nodes, seconds",
    };
    write_tolerance_curve(c, |p| p.error, labels, dir, text)
}

/// The growth runs under solver.tol: delivered and estimated axial-length error against
/// the tolerance asked for, with the line error = tol, and the fixed ladder's rungs in the
/// report beside them.
fn write_tolerance_growth(
    curves: &[wpd::Curve],
    dir: &Path,
    text: &mut String,
) -> Result<(), StudyError> {
    let Some(c) = curves.iter().find(|c| c.knob == "tol") else {
        return Ok(());
    };
    let labels = ToleranceLabels {
        title: "growth under solver.tol: delivered and estimated axial-length error",
        x: "requested tol (mm)",
        y: "axial-length error (mm)",
        error: "delivered error",
        stem: "wpd_growth_tolerance",
        header:
            "growth solver.tol: requested, delivered axial-length error, estimate, nodes, seconds",
    };
    write_tolerance_curve(c, |p| p.axial_error, labels, dir, text)?;
    if let Some(f) = curves.iter().find(|c| c.knob == "nodes") {
        let _ = writeln!(
            text,
            "growth fixed (N, rtol): N, rtol, axial-length error, seconds"
        );
        for (p, (_, rtol)) in f.points.iter().zip(wpd::GROWTH_LADDER) {
            let _ = writeln!(
                text,
                "  {}  {rtol:.0e}  {:.2e}  {:.4} s",
                p.value, p.axial_error, p.seconds
            );
        }
    }
    Ok(())
}

/// The efficiency table of solver.tol (CSV, and markdown rows in the report).
fn write_efficiency(
    rows: &[wpd::Efficiency],
    dir: &Path,
    text: &mut String,
) -> Result<(), StudyError> {
    use super::cell;
    let header: Vec<String> = [
        "tol",
        "adapted_nodes",
        "adapted_error",
        "estimate",
        "adapted_seconds",
        "uniform",
        "fixed_nodes",
        "fixed_error",
        "fixed_seconds",
    ]
    .map(String::from)
    .to_vec();
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                cell(r.tol),
                r.adapted_nodes.to_string(),
                cell(r.adapted_error),
                cell(r.estimate),
                cell(r.adapted_seconds),
                r.uniform.to_string(),
                r.fixed_nodes.to_string(),
                cell(r.fixed_error),
                cell(r.fixed_seconds),
            ]
        })
        .collect();
    write_csv(&dir.join("wpd_efficiency.csv"), &header, &table)?;
    let _ = writeln!(
        text,
        "solver.tol against the uniform + graded mesh of the same true error:\n\
         | tol | adapted nodes | true error | estimate | time | uniform N | its nodes | its error | its time | nodes ratio | time ratio |\n\
         |---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        let _ = writeln!(
            text,
            "| {:.0e} | {} | {:.2e} | {:.2e} | {:.3} ms | {} | {} | {:.2e} | {:.3} ms | {:.2} | {:.2} |",
            r.tol,
            r.adapted_nodes,
            r.adapted_error,
            r.estimate,
            1e3 * r.adapted_seconds,
            r.uniform,
            r.fixed_nodes,
            r.fixed_error,
            1e3 * r.fixed_seconds,
            r.adapted_nodes as f64 / r.fixed_nodes as f64,
            r.adapted_seconds / r.fixed_seconds
        );
    }
    Ok(())
}

fn describe_winners(
    curves: &[wpd::Curve],
    targets: &[f64],
    axial: bool,
    text: &mut String,
    what: &str,
) {
    let _ = writeln!(
        text,
        "{what}: the cheapest method that reaches each accuracy"
    );
    for (target, method, t) in wpd::winners(curves, targets, axial) {
        let _ = writeln!(text, "  error ≤ {target:.0e}: {method} ({:.4} s)", t);
    }
}

/// `eyeshell refinement`: the paper's refinement check of the const scene.
pub fn refinement(dir: &Path) -> Result<String, StudyError> {
    let changes = refinement::check(&[1e-4, 1e-6, 1e-8])?;
    let (header, rows) = refinement::table(&changes);
    write_csv(&dir.join("refinement.csv"), &header, &rows)?;
    let mut text = format!(
        "{:<34} {:>9} {:>9} {:>9} {:>9} {:>8}\n",
        "relative change at t = 1", "kappa", "alpha_s", "r", "theta", "seconds"
    );
    for r in &rows {
        let _ = writeln!(
            text,
            "{:<34} {:>9} {:>9} {:>9} {:>9} {:>8}",
            r[0],
            short(&r[1]),
            short(&r[2]),
            short(&r[3]),
            short(&r[4]),
            short(&r[5])
        );
    }
    Ok(text)
}

fn short(cell: &str) -> String {
    cell.parse::<f64>()
        .map_or(String::new(), |x| format!("{x:.2e}"))
}
