//! The figure of `eyeshell fit`.

use std::path::{Path, PathBuf};

use eyeshell_plot::{Figure, Series, SeriesStyle};

use super::panels::{trim, TimeAxis};
use super::{FigureError, BLUE, GREY, PANEL, RED};
use crate::image;

/// The figure of `eyeshell fit`: the observations (with ±σ bars when given) against the
/// fitted curve and the curve of the start values, as `<stem>.png` and `<stem>.svg`.
pub fn fit_figure(
    r: &eyeshell::fit::FitReport,
    fitted: &[(f64, f64)],
    initial: &[(f64, f64)],
    axis: TimeAxis,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let on_axis = |curve: &[(f64, f64)]| -> Vec<(f64, f64)> {
        curve.iter().map(|&(t, l)| (axis.x(t), l)).collect()
    };
    let estimates: Vec<String> = r
        .parameters
        .iter()
        .map(|p| {
            format!(
                "{} = {} ± {}",
                p.key,
                trim(p.estimate),
                trim(p.standard_error)
            )
        })
        .collect();
    let mut fig = Figure::new(
        "axial length: data and fit",
        axis.title(),
        "axial length (mm)",
    )
    .with(Series::new("initial", on_axis(initial), SeriesStyle::DashedLine).color(GREY))
    .with(Series::new("fitted", on_axis(fitted), SeriesStyle::Line).color(BLUE))
    .with(
        Series::new(
            "data",
            r.residuals
                .iter()
                .map(|x| (axis.x(x.t), x.axial_length))
                .collect(),
            SeriesStyle::Markers,
        )
        .color(RED),
    );
    for e in estimates {
        fig = fig.note(e);
    }
    // The ±σ bars, one short line each (at most a few hundred: beyond, the markers alone).
    if r.residuals.len() <= 500 {
        for x in &r.residuals {
            if let Some(s) = x.sigma {
                fig = fig.with(
                    Series::new(
                        "±σ",
                        vec![
                            (axis.x(x.t), x.axial_length - s),
                            (axis.x(x.t), x.axial_length + s),
                        ],
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
