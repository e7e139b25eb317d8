//! Charts as PNG and SVG bytes, drawn with `plotters` (no Python), knowing nothing of eyes:
//! eyeshell draws its convergence studies, work-precision diagrams and the paper's figures with it.
//! (Its [`Figure`] is one chart: the paper's figures are eyeshell's, made of several.)
//!
//! A [`Figure`] holds [`Series`] of points; [`render()`] draws it as an [`Image`], its PNG
//! and SVG bytes, and [`render_panels`] draws several figures as the panels of one image.
//! The crate writes no file: its callers write the bytes (eyeshell through its one atomic
//! writer), and its public types are its own ([`Rgb`], not plotters').
//! Colours come from a fixed palette ([`PALETTE`]) and marker shapes from a fixed cycle,
//! both by the series' index, so a figure looks the same on every run. A series may instead
//! be shaded point by point through [`colormap`] (viridis), against the figure's
//! [`ColorScale`], which is then shown as a colour bar.
//!
//! PNG text is rasterised from a TrueType font read at run time (Debian's
//! `fonts-dejavu-core`, see [`FONT_PATHS`]); nothing links against fontconfig. The font is
//! also what lays out the text of the SVG, but the SVG file itself holds `<text>` elements
//! in the `sans-serif` family and needs no font file to be viewed.

mod clip;
mod draw;
mod figure;
mod font;
mod output;
mod prepare;

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Mutex;

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontTransform;

// The rooms share the crate's private items (and plotters' names) through these imports:
// each room begins with `use crate::*`, so moving an item between rooms changes no import.
#[allow(unused_imports)]
use clip::*;
#[allow(unused_imports)]
use draw::*;
pub use draw::{COLORBAR_AREA, MAX_STROKE};
pub use figure::*;
pub use font::{ensure_font, FONT_ENV, FONT_PATHS};
#[allow(unused_imports)]
use output::*;
pub use output::{render, render_panels, Image, PANELS_TITLE_BAND};
#[allow(unused_imports)]
use prepare::*;

/// Failure to draw a figure. Display is one line; the caller names the file it was for.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    #[error("no font for the figure's text (looked for {}); install one with `apt-get install fonts-dejavu-core` or name a TTF file in {FONT_ENV}", tried.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    NoFont { tried: Vec<PathBuf> },
    #[error("the font {} could not be read as TrueType", font.display())]
    BadFont { font: PathBuf },
    #[error("drawing failed: {message}")]
    Draw { message: String },
    #[error("{reason}")]
    Invalid { reason: String },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A steep stretch drawn between two far-apart samples (a sensitivity diving between
    /// history times) keeps the legend off it, and points away from a corner do not: by
    /// points per quadrant the lower left (one sample) would win.
    #[test]
    fn the_legend_avoids_a_sparsely_sampled_dive() {
        let row = |x0: f64, y: f64| (0..=10).map(|i| (x0 + 0.01 * i as f64, y)).collect();
        let fig = Figure::new("dive", "t", "s")
            .with(Series::new(
                "dive",
                vec![(0.0, 0.0), (0.06, -1.0), (0.3, 0.0)],
                SeriesStyle::Line,
            ))
            .with(Series::new("high", row(0.9, 1.0), SeriesStyle::Line))
            .with(Series::new("low", row(0.9, -1.0), SeriesStyle::Line))
            .with(Series::new("middle", row(0.3, 0.7), SeriesStyle::Line));
        let prep = Prepared::new(&fig);
        let corner = legend_corner(&fig, &prep, (800, 600));
        assert!(
            matches!(corner, SeriesLabelPosition::UpperLeft),
            "{corner:?}"
        );
    }

    #[test]
    fn log_ranges_are_whole_decades_around_the_data() {
        let near = |r: (f64, f64), a: f64, b: f64| {
            (r.0 / a - 1.0).abs() < 1e-6 && (r.1 / b - 1.0).abs() < 1e-6 && r.0 <= a && r.1 >= b
        };
        let r = axis_range([2e-3, 5e-1].into_iter(), Scale::Log10);
        assert!(near(r, 1e-3, 1.0), "{r:?}");
        // Data on a power of ten gets room beyond it.
        let r = axis_range([1e-3, 1e-1].into_iter(), Scale::Log10);
        assert!(near(r, 1e-4, 1.0), "{r:?}");
        // One value: at least a decade.
        let (a, b) = axis_range([3.0].into_iter(), Scale::Log10);
        assert!(a < 3.0 && b > 3.0 && b / a >= 10.0 - 1e-9);
        assert_eq!(axis_range(std::iter::empty(), Scale::Log10), (1.0, 10.0));
        // The end decades are ticks.
        let r = axis_range([1.9e-9, 3e-2].into_iter(), Scale::Log10);
        let coord: LogCoord<f64> = (r.0..r.1).log_scale().into();
        let ticks = coord.key_points(8);
        assert!((ticks[0] / 1e-9 - 1.0).abs() < 1e-6, "{ticks:?}");
        assert!(
            (ticks[ticks.len() - 1] / 0.1 - 1.0).abs() < 1e-6,
            "{ticks:?}"
        );
    }

    #[test]
    fn linear_ranges_have_a_margin() {
        let (a, b) = axis_range([0.0, 10.0].into_iter(), Scale::Linear);
        assert!(a < 0.0 && b > 10.0);
        let (a, b) = axis_range([0.0, 0.0].into_iter(), Scale::Linear);
        assert!(a < 0.0 && b > 0.0);
        let (a, b) = axis_range([5.0].into_iter(), Scale::Linear);
        assert!(a < 5.0 && b > 5.0);
    }

    #[test]
    fn equal_aspect_gives_the_same_units_per_pixel() {
        let ((x0, x1), (y0, y1)) = equal_aspect((0.0, 1.0), (-3.0, 3.0), 800, 500);
        let (ux, uy) = ((x1 - x0) / 800.0, (y1 - y0) / 500.0);
        assert!((ux - uy).abs() < 1e-12 * ux);
        assert!(x0 <= 0.0 && x1 >= 1.0 && y0 <= -3.0 && y1 >= 3.0);
    }

    #[test]
    fn tiny_variations_are_drawn_about_an_offset() {
        assert_eq!(axis_offset([1.0, 2.0].into_iter()), None);
        assert_eq!(axis_offset([5.0, 5.0].into_iter()), None);
        let d = axis_offset([1.0136216901, 1.0136216911].into_iter()).unwrap();
        assert!((d - 1.013621690).abs() < 1e-9 + 1e-12, "{d}");
        let fig = Figure::new("", "x", "α_s").with(Series::new(
            "a",
            vec![(0.0, 1.0136216901), (1.0, 1.0136216911)],
            SeriesStyle::Line,
        ));
        let shifted = offset_axes(&fig);
        assert_eq!(shifted.x_label, "x");
        assert!(
            shifted.y_label.starts_with("α_s − 1.0136216"),
            "{}",
            shifted.y_label
        );
        let ys: Vec<f64> = shifted.series[0].points.iter().map(|p| p.1).collect();
        assert!(ys.iter().all(|y| y.abs() < 1e-8), "{ys:?}");
        // An ordinary figure is drawn as it is.
        let plain = Figure::new("", "x", "y").with(Series::new(
            "a",
            vec![(0.0, 1.0), (1.0, 2.0)],
            SeriesStyle::Line,
        ));
        assert!(matches!(offset_axes(&plain), std::borrow::Cow::Borrowed(_)));
    }

    #[test]
    fn tick_labels() {
        assert_eq!(log_label(1e-3), "1e-3");
        assert_eq!(log_label(1.0), "1e0");
        assert_eq!(log_label(2e-3), "2e-3");
        assert_eq!(log_label(1e5), "1e5");
        assert_eq!(linear_label(0.5, 1.0), "0.5");
        assert_eq!(linear_label(2.0, 10.0), "2");
        assert_eq!(linear_label(1e-16, 10.0), "0");
        assert_eq!(linear_label(2.5e-6, 1e-5), "2.5e-6");
        assert_eq!(linear_label(125000.0, 1e5), "1.25e5");
    }
    /// Relative luminance of an sRGB colour.
    fn luminance(c: Rgb) -> f64 {
        let lin = |v: u8| {
            let v = v as f64 / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(c.0) + 0.7152 * lin(c.1) + 0.0722 * lin(c.2)
    }

    #[test]
    fn colormap_is_viridis_with_increasing_luminance() {
        assert_eq!(colormap(0.0), Rgb(0x44, 0x01, 0x54));
        assert_eq!(colormap(1.0), Rgb(0xfd, 0xe7, 0x25));
        assert_eq!(colormap(-3.0), colormap(0.0));
        assert_eq!(colormap(7.0), colormap(1.0));
        assert_eq!(colormap(f64::NAN), colormap(0.0));
        assert_eq!(colormap(f64::INFINITY), colormap(1.0));
        // The anchors are hit exactly.
        assert_eq!(colormap(5.0 / 9.0), Rgb(0x1f, 0x9e, 0x89));
        let lum: Vec<f64> = (0..=200)
            .map(|i| luminance(colormap(i as f64 / 200.0)))
            .collect();
        for (i, w) in lum.windows(2).enumerate() {
            assert!(w[1] >= w[0], "luminance falls at {i}/200: {w:?}");
        }
        assert!(lum[200] > 10.0 * lum[0]);
    }

    #[test]
    fn values_map_onto_the_colour_scale() {
        assert_eq!(normalise(5.0, (0.0, 10.0)), 0.5);
        assert_eq!(normalise(-1.0, (0.0, 10.0)), 0.0);
        assert_eq!(normalise(11.0, (0.0, 10.0)), 1.0);
        // A single value: the low end. Reversed: high values low.
        assert_eq!(normalise(3.0, (2.0, 2.0)), 0.0);
        assert_eq!(normalise(3.0, (0.0, 5e-324)), 0.0);
        assert_eq!(normalise(10.0, (10.0, 0.0)), 0.0);
        assert!(normalise(f64::NAN, (0.0, 1.0)).is_nan());
        assert!(normalise(f64::INFINITY, (0.0, 1.0)).is_nan());
        assert_eq!(shade_color(f64::NAN, (0.0, 1.0)), NO_VALUE_COLOR);
        assert_eq!(shade_color(1.0, (0.0, 1.0)), colormap(1.0));
        // Huge ends do not give NaN.
        assert!(!normalise(1e308, (-1e308, 1e308)).is_nan());

        let curve = |values: Option<Vec<f64>>| Curve {
            points: vec![],
            values,
        };
        let fig = Figure::default();
        let curves = [
            curve(Some(vec![3.0, f64::NAN, -1.0])),
            curve(None),
            curve(Some(vec![f64::INFINITY, 7.0])),
        ];
        assert_eq!(shade_range(&fig, &curves), (-1.0, 7.0));
        assert_eq!(shade_range(&fig, &[]), (0.0, 1.0));
        let fig = Figure::default().color_scale("g", 0.0, 2.0);
        assert_eq!(shade_range(&fig, &curves), (0.0, 2.0));
        let fig = Figure::default().color_scale("g", f64::NAN, 2.0);
        assert_eq!(shade_range(&fig, &curves), (-1.0, 7.0));
    }

    #[test]
    fn explicit_ranges_are_made_usable() {
        assert_eq!(explicit_range(None, Scale::Linear), None);
        assert_eq!(
            explicit_range(Some((1.0, -2.0)), Scale::Linear),
            Some((-2.0, 1.0))
        );
        assert_eq!(explicit_range(Some((f64::NAN, 1.0)), Scale::Linear), None);
        assert_eq!(explicit_range(Some((0.0, 1.0)), Scale::Log10), None);
        assert_eq!(
            explicit_range(Some((1e-3, 1.0)), Scale::Log10),
            Some((1e-3, 1.0))
        );
        let (a, b) = explicit_range(Some((2.0, 2.0)), Scale::Linear).unwrap();
        assert!(a < 2.0 && b > 2.0);
        // Points keep their values when others are dropped.
        let fig = Figure::default()
            .with(
                Series::new(
                    "s",
                    vec![(0.0, 0.0), (f64::NAN, 1.0), (2.0, 2.0)],
                    SeriesStyle::Line,
                )
                .shaded(vec![10.0, 11.0]),
            )
            .x_range(5.0, -5.0);
        let prep = Prepared::new(&fig);
        assert_eq!(prep.curves[0].points, vec![(0.0, 0.0), (2.0, 2.0)]);
        let v = prep.curves[0].values.as_ref().unwrap();
        assert_eq!(v[0], 10.0);
        assert!(v[1].is_nan(), "{v:?}");
        assert_eq!(prep.x, (-5.0, 5.0));
    }

    #[test]
    fn lines_are_clipped_to_the_view() {
        let view = View {
            x: (0.0, 1.0),
            y: (0.0, 1.0),
            scales: (Scale::Linear, Scale::Linear),
        };
        let c = view.clip((0.25, 0.5), (0.75, 0.5)).unwrap();
        assert_eq!(
            (c.a, c.b, c.cut_a, c.cut_b),
            ((0.25, 0.5), (0.75, 0.5), false, false)
        );
        let c = view.clip((-1.0, 0.5), (0.5, 0.5)).unwrap();
        assert_eq!((c.a, c.cut_a, c.cut_b), ((0.0, 0.5), true, false));
        assert!(view.clip((-1.0, 2.0), (-0.5, 3.0)).is_none());
        assert!(view.clip((2.0, 0.5), (2.0, 0.7)).is_none());
        assert!(view.clip((-1e308, 0.5), (1e308, 0.5)).is_some());
        // In, out, in: two runs.
        let runs = visible_runs(
            &view,
            &[(0.1, 0.1), (0.2, 0.2), (0.5, 3.0), (0.8, 0.2), (0.9, 0.1)],
        );
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[0].len(), 3);
        assert_eq!(runs[0][..2], [(0.1, 0.1), (0.2, 0.2)]);
        assert!((runs[0][2].1 - 1.0).abs() < 1e-12);
        assert_eq!(runs[1].last(), Some(&(0.9, 0.1)));
        assert!(visible_runs(&view, &[(0.5, 0.5)]).is_empty());
        assert!(visible_runs(&view, &[]).is_empty());
        // On a log axis a straight line is straight in log10: cut at a decade.
        let view = View {
            x: (1e-2, 1.0),
            y: (0.0, 1.0),
            scales: (Scale::Log10, Scale::Linear),
        };
        let c = view.clip((1e-4, 0.0), (1.0, 1.0)).unwrap();
        assert!(
            (c.a.0 / 1e-2 - 1.0).abs() < 1e-9 && (c.a.1 - 0.5).abs() < 1e-9,
            "{:?}",
            c.a
        );
        assert!(view.contains((0.1, 0.5)) && !view.contains((1e-3, 0.5)));
    }

    #[test]
    fn defaults_keep_the_old_behaviour() {
        let s = Series::new("a", vec![], SeriesStyle::Line);
        assert!(s.legend && s.color.is_none() && s.width.is_none() && s.values.is_none());
        assert!(Series::default().legend);
        let s = s
            .color(Rgb(255, 0, 0))
            .width(5)
            .shaded(vec![1.0])
            .no_legend();
        assert_eq!(
            (s.color, s.width, s.values, s.legend),
            (Some(Rgb(255, 0, 0)), Some(5), Some(vec![1.0]), false)
        );
        let f = Figure::default();
        assert!(f.legend && f.color_scale.is_none() && f.notes.is_empty());
        assert!(f.x_range.is_none() && f.y_range.is_none());
        let f = f
            .no_legend()
            .x_range(0.0, 1.0)
            .y_range(2.0, 3.0)
            .note("t = 0.1")
            .color_scale("g", 0.0, 1.0);
        assert!(!f.legend);
        assert_eq!((f.x_range, f.y_range), (Some((0.0, 1.0)), Some((2.0, 3.0))));
        assert_eq!(f.notes, ["t = 0.1"]);
        assert_eq!(f.color_scale.unwrap().label, "g");
    }
}
