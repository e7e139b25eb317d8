//! A sampled sweep's figure (`population.png`): the cohort's final axial length and
//! refraction as histograms and its axial length against t as quantile bands.

use std::path::{Path, PathBuf};

use eyeshell::sweep::population::POPULATION_FILE;
use eyeshell::sweep::{RunRecord, RunStatus};
use eyeshell::Error;
use eyeshell_plot::{self as plot, Figure, Series, SeriesStyle};

/// The stem of a sampled sweep's figure (`population.png`, `population.svg`).
pub const POPULATION_FIGURE: &str = "population";

/// A sampled sweep's figure, beside population.json (which must have been written): the
/// histogram of the final axial length, that of the final refraction when series.csv has a
/// refraction_D column, and the axial length against t as its median with the 50 % and 90 %
/// bands (quartiles; 5 % and 95 %, dashed). Only the cohort's eyes count (for a Saltelli
/// design the A and B rows), as in population.json.
pub fn population_figure(dir: &Path, records: &[RunRecord]) -> Result<Option<PathBuf>, Error> {
    let Ok(text) = std::fs::read_to_string(dir.join(POPULATION_FILE)) else {
        return Ok(None);
    };
    let population: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        let path = dir.join(POPULATION_FILE);
        Error::failed(eyeshell::Stage::File, format!("{}: {e}", path.display())).with_source(e)
    })?;
    let eyes: Vec<&RunRecord> = records
        .iter()
        .filter(|r| matches!(r.status, RunStatus::Ok | RunStatus::Reused))
        .filter(|r| !r.name.starts_with("AB"))
        .collect();
    let lengths: Vec<f64> = eyes
        .iter()
        .filter_map(|r| r.result.as_ref().map(|x| x.eye.number("axial_length")))
        .filter(|x| x.is_finite())
        .collect();
    let refraction = final_refractions(dir, &eyes);
    let mut panels = Vec::new();
    if lengths.len() >= 2 {
        panels.push(histogram(
            &lengths,
            "Final axial length",
            "axial length (mm)",
        ));
    }
    if refraction.len() >= 2 {
        panels.push(histogram(&refraction, "Final refraction", "refraction (D)"));
    }
    let times = population["times"].as_array().cloned().unwrap_or_default();
    if times.len() >= 2 {
        panels.push(cohort_bands(&times, population["age_unit"].as_str()));
    }
    if panels.is_empty() {
        return Ok(None);
    }
    let columns = panels.len();
    let (png, _) = crate::image::write_panels(
        &panels,
        columns,
        "The cohort",
        640,
        480,
        &dir.join(POPULATION_FIGURE),
    )
    .map_err(|e| Error::failed_by(eyeshell::Stage::Plot, e))?;
    Ok(Some(png))
}

/// The final refraction of each of `eyes` that has one (the cohort's sweep in `dir`).
fn final_refractions(dir: &Path, eyes: &[&RunRecord]) -> Vec<f64> {
    // The final refraction of each eye, from its series.csv's last row, if it has one.
    // A cohort kept as a table (no run directories): each eye's last row of the sweep's
    // series.csv, whose first column is the run.
    let table: std::collections::HashMap<String, f64> = match eyes.iter().any(|r| r.dir.is_empty())
    {
        false => Default::default(),
        true => {
            let text = std::fs::read_to_string(dir.join(eyeshell::sweep::compact::SERIES_TABLE))
                .unwrap_or_default();
            let mut lines = text.lines();
            let at = lines
                .next()
                .and_then(|h| h.split(',').position(|h| h == "refraction_D"));
            lines
                .filter_map(|l| {
                    let cells: Vec<&str> = l.split(',').collect();
                    Some((cells.first()?.to_string(), cells.get(at?)?.parse().ok()?))
                })
                .collect()
        }
    };
    eyes.iter()
        .filter_map(|r| {
            if r.dir.is_empty() {
                return table.get(&r.name).copied();
            }
            let text = std::fs::read_to_string(
                dir.join(&r.dir).join(eyeshell::rundir::growth::SERIES_FILE),
            )
            .ok()?;
            let mut lines = text.lines();
            let at = lines.next()?.split(',').position(|h| h == "refraction_D")?;
            lines.last()?.split(',').nth(at)?.parse::<f64>().ok()
        })
        .filter(|x| x.is_finite())
        .collect()
}

/// The histogram of `values` as the outline of its bars (√n bins, 5 to 50).
fn histogram(values: &[f64], title: &str, label: &str) -> Figure {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let mut counts = vec![0usize; bins];
    for &x in values {
        let k = (((x - lo) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    // The histogram as the outline of its bars.
    let mut points = vec![(lo, 0.0)];
    for (k, &c) in counts.iter().enumerate() {
        let (a, b) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
        points.extend([(a, c as f64), (b, c as f64)]);
    }
    points.push((lo + bins as f64 * width, 0.0));
    Figure::new(title, label, "eyes").with(Series::new(
        format!("{} eyes", values.len()),
        points,
        SeriesStyle::Line,
    ))
}

/// The axial length of the cohort against t, or against age when the cohort counts in ages
/// (`age_unit`, every time with its age): the median, the quartiles and the 5 % and 95 %
/// quantiles of population.json's `times`.
fn cohort_bands(times: &[serde_json::Value], age_unit: Option<&str>) -> Figure {
    let by_age = age_unit.is_some() && times.iter().all(|t| t["age"].as_f64().is_some());
    let x = if by_age { "age" } else { "t" };
    let band = |q: &str| -> Vec<(f64, f64)> {
        times
            .iter()
            .filter_map(|t| {
                Some((
                    t[x].as_f64()?,
                    t["outputs"]["axial_length"]["quantiles"][q].as_f64()?,
                ))
            })
            .collect()
    };
    let label = match (by_age, age_unit) {
        (true, Some(unit)) => format!("age ({unit})"),
        _ => "t".to_string(),
    };
    Figure::new("Axial length of the cohort", label, "axial length (mm)")
        .with(
            Series::new("median", band("0.5"), SeriesStyle::LineAndMarkers).color(plot::PALETTE[0]),
        )
        .with(Series::new("25 % and 75 %", band("0.25"), SeriesStyle::Line).color(plot::PALETTE[1]))
        .with(
            Series::new("", band("0.75"), SeriesStyle::Line)
                .color(plot::PALETTE[1])
                .no_legend(),
        )
        .with(
            Series::new("5 % and 95 %", band("0.05"), SeriesStyle::DashedLine)
                .color(plot::PALETTE[3]),
        )
        .with(
            Series::new("", band("0.95"), SeriesStyle::DashedLine)
                .color(plot::PALETTE[3])
                .no_legend(),
        )
}
