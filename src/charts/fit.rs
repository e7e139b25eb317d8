//! The figure of `eyeshell fit`.

use std::path::{Path, PathBuf};

use eyeshell_plot::{Figure, Series, SeriesStyle};

use super::panels::{trim, TimeAxis};
use super::{FigureError, BLUE, GREY, PANEL, RED};
use crate::image;

/// The figure of `eyeshell fit`: the axial lengths observed (with ±σ bars when given; of
/// arm `arm` alone in a joint fit) against the fitted curve and the curve of the start
/// values, as `<stem>.png` and `<stem>.svg`.
pub fn fit_figure(
    r: &eyeshell::fit::FitReport,
    arm: Option<&str>,
    fitted: &[(f64, f64)],
    initial: &[(f64, f64)],
    axis: TimeAxis,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let on_axis = |curve: &[(f64, f64)]| -> Vec<(f64, f64)> {
        curve.iter().map(|&(t, l)| (axis.x(t), l)).collect()
    };
    let rows: Vec<(f64, f64, Option<f64>)> = (r.residuals.iter())
        .filter(|x| x.arm.as_deref() == arm)
        .filter_map(|x| Some((x.t, x.axial_length?, x.sigma)))
        .collect();
    let estimates: Vec<String> = r
        .parameters
        .iter()
        .filter(|p| p.arm.is_none() || p.arm.as_deref() == arm)
        .map(|p| {
            format!(
                "{} = {} ± {}",
                p.label(),
                trim(p.estimate),
                trim(p.standard_error)
            )
        })
        .collect();
    let title = match arm {
        Some(a) => format!("axial length of {a}: data and fit"),
        None => "axial length: data and fit".to_string(),
    };
    let mut fig = Figure::new(&title, axis.title(), "axial length (mm)")
        .with(Series::new("initial", on_axis(initial), SeriesStyle::DashedLine).color(GREY))
        .with(Series::new("fitted", on_axis(fitted), SeriesStyle::Line).color(BLUE))
        .with(
            Series::new(
                "data",
                rows.iter().map(|&(t, l, _)| (axis.x(t), l)).collect(),
                SeriesStyle::Markers,
            )
            .color(RED),
        );
    for e in estimates {
        fig = fig.note(e);
    }
    // The ±σ bars, one short line each (at most a few hundred: beyond, the markers alone).
    if rows.len() <= 500 {
        for &(t, l, sigma) in &rows {
            if let Some(s) = sigma {
                fig = fig.with(
                    Series::new(
                        "±σ",
                        vec![(axis.x(t), l - s), (axis.x(t), l + s)],
                        SeriesStyle::Line,
                    )
                    .color(RED)
                    .width(1)
                    .no_legend(),
                );
            }
        }
    }
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}
