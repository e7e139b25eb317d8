//! A fit's report as the table `eyeshell fit` prints and `FitResult.text` holds: the
//! estimates with their standard errors, the correlations, the notes on what the data do
//! not determine, χ² and the iterations.

use super::FitReport;
use crate::scene::Scene;
use crate::text::{advice, decimals, decimals6, one_line, Advice};

/// |ρ| from which the report points a pair out.
pub const STRONG_CORRELATION: f64 = 0.99;

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// The pairs of fitted parameters correlated at |ρ| ≥ [`STRONG_CORRELATION`], with ρ: their
/// standard errors are mostly the width of a valley along which the data barely change
/// (BENCHMARKS.md, "Calibration": η0 and Γ on plateau data).
pub fn strongly_correlated(r: &FitReport) -> Vec<(String, String, f64)> {
    let mut pairs = vec![];
    for (i, p) in r.parameters.iter().enumerate() {
        for (j, q) in r.parameters.iter().enumerate().skip(i + 1) {
            let c = r.correlation[i][j];
            if c.abs() >= STRONG_CORRELATION {
                pairs.push((p.label(), q.label(), c));
            }
        }
    }
    pairs
}

/// What the reader of a fit should know beyond its numbers, one line each: pairs of
/// parameters the data determine only in combination.
pub fn notes(r: &FitReport) -> Vec<String> {
    let pairs = strongly_correlated(r);
    if pairs.is_empty() {
        return Vec::new();
    }
    let list: Vec<String> = pairs
        .iter()
        .map(|(a, b, c)| format!("{a} and {b} at {c:.4}"))
        .collect();
    // The advice names a key of the pair, never one that was not fitted; a per-arm key's
    // value is set in its arm's scene.
    let (_, example, _) = &pairs[0];
    let example = example.split('[').next().unwrap_or(example);
    vec![format!(
        "strongly correlated (|ρ| ≥ {STRONG_CORRELATION}): {}; the data determine a combination \
         of such a pair far better than either (fix one: leave {example}, say, out of the fit \
         and give its value with {}; or add observations that separate them)",
        list.join(", "),
        advice(&Advice::SetKey)
    )]
}

/// The correlation matrix, its labels "(i) key" in a column as wide as the longest.
fn correlation_table(r: &FitReport) -> String {
    let labels: Vec<String> = (r.parameters.iter().enumerate())
        .map(|(i, p)| format!("({}) {}", i + 1, p.label()))
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

/// `x` with its sign and `places` decimals, in scientific notation where decimals would
/// not show it ([`decimals`]): a residual of 1e148 σ (a tiny σ) is `+1.00e148`, not 150
/// digits.
fn signed(x: f64, places: usize) -> String {
    let text = decimals(x, places);
    match text.starts_with('-') || x.is_nan() {
        true => text,
        false => format!("+{text}"),
    }
}

/// In a scene that counts in ages (time.unit), each measurement against the model by age,
/// one line each in the data's order (arm by arm): what a growth curve's reader looks at
/// first (where in life the model runs ahead of the data or behind it). Empty without
/// ages, so a fit in t reports as it always did.
fn residuals_by_age(scene: &Scene, r: &FitReport) -> String {
    let Some(unit) = scene.growth.as_ref().and_then(|g| g.age_unit()) else {
        return String::new();
    };
    let joint = r
        .residuals
        .iter()
        .any(|x| x.arm.is_some() || x.refraction_d.is_some());
    let arm_width = (r.residuals.iter())
        .filter_map(|x| x.arm.as_ref().map(|a| a.chars().count()))
        .max()
        .unwrap_or(0)
        .max(3);
    let mut text = if joint {
        format!(
            "  residuals        {:arm_width$}  {:>10}  {:>13}  {:>10}  {:>10}  {:>10}\n",
            "arm",
            format!("age ({unit})"),
            "measured",
            "data",
            "model",
            "model−data"
        )
    } else {
        format!(
            "  residuals        {:>10}  {:>10}  {:>10}  {:>10}\n",
            format!("age ({unit})"),
            "data (mm)",
            "model (mm)",
            "model−data"
        )
    };
    for x in &r.residuals {
        let Some(age) = x.age else { continue };
        let weighted = if x.sigma.is_some() {
            format!("  ({} σ)", signed(x.weighted, 2))
        } else {
            String::new()
        };
        if joint {
            let m = x.measured();
            text.push_str(&format!(
                "                   {:arm_width$}  {:>10}  {:>13}  {:>10}  {:>10}  {:>10}{weighted}\n",
                x.arm.as_deref().unwrap_or(""),
                decimals(age, 4),
                format!("{} ({})", m.column(), m.unit()),
                decimals(x.observed(), 4),
                decimals(x.model, 4),
                signed(x.residual, 4),
            ));
        } else {
            text.push_str(&format!(
                "                   {:>10}  {:>10}  {:>10}  {:>10}{weighted}\n",
                decimals(age, 4),
                decimals(x.observed(), 4),
                decimals(x.model, 4),
                signed(x.residual, 4),
            ));
        }
    }
    text
}

/// The report of the fit of `scene` as a table (no trailing line on where it was written):
/// estimates to 6 decimals (6 significant digits in scientific notation outside [1e-4,
/// 1e9)), correlations and χ² to 4.
pub fn report_table(scene: &Scene, r: &FitReport) -> String {
    let n = r.parameters.len();
    let width = r
        .parameters
        .iter()
        .map(|p| p.label().chars().count())
        .max()
        .unwrap_or(0)
        .max(9);
    let weights = if r.data.sigma {
        "σ given"
    } else {
        "no σ: equal weights, covariance scaled by the residual variance"
    };
    let measured = |d: &super::DataRecord| {
        (d.measured.iter().map(|m| m.column()))
            .collect::<Vec<_>>()
            .join(" and ")
    };
    let mut text = if r.arms.is_empty() {
        format!(
            "eyeshell: fitted {} ({}) to {} ({} observation{}{}, {weights})\n",
            scene.origin,
            one_line(&scene.display_name()),
            r.data.file,
            r.data.observations,
            plural(r.data.observations),
            match r.data.measured.as_slice() {
                [super::Measured::AxialLength] => String::new(),
                _ => format!(" of {}", measured(&r.data)),
            },
        )
    } else {
        let mut text = format!(
            "eyeshell: fitted {} arms jointly ({} observations, {weights})\n",
            r.arms.len(),
            r.data.observations
        );
        for a in &r.arms {
            text.push_str(&format!(
                "  arm              {}: {} to {} ({} observation{} of {})\n",
                a.name,
                a.scene,
                a.data.file,
                a.data.observations,
                plural(a.data.observations),
                measured(&a.data)
            ));
        }
        text
    };
    text.push_str(&format!(
        "  {:width$}  {:>12}  {:>12}  {:>12}  range\n",
        "parameter", "initial", "estimate", "std. error"
    ));
    for p in &r.parameters {
        text.push_str(&format!(
            "  {:width$}  {:>12}  {:>12}  {:>12}  {}{}\n",
            p.label(),
            decimals6(p.initial),
            decimals6(p.estimate),
            decimals6(p.standard_error),
            p.range,
            if p.at_bound { " (at its bound)" } else { "" }
        ));
    }
    if n > 1 {
        text.push_str(&correlation_table(r));
    }
    for note in notes(r) {
        text.push_str(&format!("  note             {note}\n"));
    }
    let d4 = |x: f64| decimals(x, 4);
    text.push_str(&residuals_by_age(scene, r));
    let rms_unit = match r.data.measured.as_slice() {
        [super::Measured::AxialLength] => " mm",
        [super::Measured::Refraction] => " D",
        _ => " (mm and D together)",
    };
    text.push_str(&format!(
        "  χ²               {} (from {}), {} degree{} of freedom, χ²/dof {}; rms residual {}{rms_unit}\n",
        d4(r.chi2),
        d4(r.initial_chi2),
        r.degrees_of_freedom,
        plural(r.degrees_of_freedom),
        d4(r.reduced_chi2),
        d4(r.rms_residual)
    ));
    text.push_str(&format!(
        "  iterations       {} ({} growth run{}{}); {}\n  time             {:.3} s\n",
        r.iterations,
        r.model_runs,
        plural(r.model_runs),
        if r.parameters
            .iter()
            .all(|p| p.jacobian == "IDAS sensitivity")
        {
            " with sensitivities"
        } else {
            ", finite differences among them"
        },
        r.convergence_reason,
        r.wall_seconds,
    ));
    text
}
