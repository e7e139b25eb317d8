//! The figures of `eyeshell optics`: the best-focus surfaces against the published ones, and
//! the eye's ray trace.

use std::path::{Path, PathBuf};

use eyeshell_plot::{Figure, Rgb, Series, SeriesStyle};

use super::panels::trim;
use super::{FigureError, BLACK, BLUE, GREY, PANEL, RED};
use crate::image;

/// The first wavelength's best-focus surface of `eyeshell optics`, and its sagittal and
/// tangential focal surfaces, minus the scene's polynomial blue surface, against the polar
/// angle φ about z_B (`rows` as published.csv holds them: field, φ, R_B, then the three
/// differences).
pub fn published_figure(
    rows: &[[f64; 6]],
    criterion: &str,
    wavelength_nm: f64,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let mut fig = Figure::new(
        format!(
            "{} nm surfaces minus the polynomial blue surface",
            trim(wavelength_nm)
        ),
        "φ (rad about z_B)",
        "R − R_B (mm)",
    );
    let column = |k: usize| rows.iter().map(|r| (r[1], r[k])).collect::<Vec<_>>();
    for (k, name, colour) in [
        (4, "sagittal focus".to_string(), Rgb(90, 160, 90)),
        (5, "tangential focus".to_string(), Rgb(200, 140, 40)),
        (3, format!("best focus ({criterion})"), BLUE),
    ] {
        fig = fig.with(Series::new(name, column(k), SeriesStyle::Line).color(colour));
    }
    fig = fig.with(
        Series::new(
            "",
            vec![(0.0, 0.0), (rows.last().map_or(0.5, |r| r[1]), 0.0)],
            SeriesStyle::Line,
        )
        .color(BLACK)
        .width(1)
        .no_legend(),
    );
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}

/// A ray fan of the optics figure: its field angle (degrees) and each ray's (z, y) path.
pub type RayFan = (f64, Vec<Vec<(f64, f64)>>);

/// The eye of `eyeshell optics` in its meridional plane, like the paper's ray-trace figure:
/// each refracting surface across the pupil's height, ray fans of the first wavelength at a
/// few field angles (`fans`: angle and rays), and the best-focus surfaces (blue, red).
pub fn optics_figure(
    system: &eyeshell_optics::OpticalSystem,
    computed: &eyeshell::model::optics::ComputedOptics,
    fans: &[RayFan],
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let mut fig = Figure::new(
        format!("{} eye: rays and best-focus surfaces", system.name),
        "z (mm from the corneal apex)",
        "y (mm)",
    );
    // Each surface drawn to 6 mm from the axis, or as far as its conicoid reaches.
    for (element, vertex) in system.elements.iter().zip(system.vertices()) {
        let n = 61;
        let points: Vec<(f64, f64)> = (0..n)
            .map(|i| -6.0 + 12.0 * i as f64 / (n - 1) as f64)
            .filter_map(|y| element.surface.sag(y.abs()).map(|s| (vertex + s, y)))
            .collect();
        if points.len() > 1 {
            fig = fig.with(
                Series::new("surfaces", points, SeriesStyle::Line)
                    .color(BLACK)
                    .width(1)
                    .no_legend(),
            );
        }
    }
    let fan_colours = [GREY, Rgb(90, 160, 90), Rgb(200, 140, 40)];
    for (i, (field, rays)) in fans.iter().enumerate() {
        for (k, ray) in rays.iter().enumerate() {
            let series = Series::new(
                format!("rays at {}°", trim(*field)),
                ray.clone(),
                SeriesStyle::Line,
            )
            .color(fan_colours[i % fan_colours.len()])
            .width(1);
            fig = fig.with(if k == 0 { series } else { series.no_legend() });
        }
    }
    for (s, colour) in computed.surfaces.surfaces.iter().zip([BLUE, RED]) {
        let upper: Vec<(f64, f64)> = s.points.iter().map(|p| (p.z, p.r)).collect();
        let lower: Vec<(f64, f64)> = s.points.iter().map(|p| (p.z, -p.r)).collect();
        let name = format!("best focus, {} nm", trim(s.wavelength_nm));
        fig = fig
            .with(Series::new(name, upper, SeriesStyle::Line).color(colour))
            .with(
                Series::new("", lower, SeriesStyle::Line)
                    .color(colour)
                    .no_legend(),
            );
    }
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}
