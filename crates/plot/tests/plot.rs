//! Figures as PNG and SVG (`eyeshell_plot`).
//!
//! Set `EYESHELL_PLOT_SAMPLES=DIR` to keep a copy of each test figure in DIR for a look.

use std::fs;
use std::path::{Path, PathBuf};

use eyeshell_plot::{
    self, colormap, Figure, PlotError, Rgb, Scale, Series, SeriesStyle, COLORBAR_AREA,
    NO_VALUE_COLOR, PALETTE, PANELS_TITLE_BAND,
};

/// `<stem>.png` and `<stem>.svg` as the figure renders (the crate draws to bytes; the tests
/// look at files, as eyeshell writes them).
fn save(image: eyeshell_plot::Image, stem: &Path) -> (PathBuf, PathBuf) {
    let name = stem.file_name().unwrap().to_string_lossy();
    let png = stem.with_file_name(format!("{name}.png"));
    let svg = stem.with_file_name(format!("{name}.svg"));
    fs::write(&png, &image.png).unwrap();
    fs::write(&svg, image.svg.as_bytes()).unwrap();
    (png, svg)
}

fn write(fig: &Figure, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    eyeshell_plot::render(fig).map(|image| save(image, stem))
}

fn write_panels(
    panels: &[Figure],
    columns: usize,
    title: &str,
    w: u32,
    h: u32,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), PlotError> {
    eyeshell_plot::render_panels(panels, columns, title, w, h).map(|image| save(image, stem))
}

/// The decoded PNG: width, height and RGB bytes.
fn decode_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let bytes = fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (w, h));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (w, h, buf)
}

fn pixels(rgb: &[u8]) -> impl Iterator<Item = [u8; 3]> + '_ {
    rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]])
}

/// The text of every `<text>` element of an SVG, trimmed.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (_, rest) = t.split_once('>')?;
            let (body, _) = rest.split_once("</text>")?;
            Some(body.trim().to_string())
        })
        .collect()
}

fn count_color(rgb: &[u8], c: Rgb) -> usize {
    pixels(rgb).filter(|p| *p == [c.0, c.1, c.2]).count()
}

/// Keep a copy of the figure when EYESHELL_PLOT_SAMPLES names a directory.
fn keep_sample(fig: &Figure, name: &str) {
    if let Some(dir) = std::env::var_os("EYESHELL_PLOT_SAMPLES") {
        write(fig, &PathBuf::from(dir).join(name)).unwrap();
    }
}

/// No temporary files are left next to the figures.
fn only(dir: &Path, names: &[&str]) {
    let mut found: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    found.sort();
    assert_eq!(found, names);
}

fn convergence_figure() -> Figure {
    let h: Vec<f64> = (0..6).map(|k| 0.1 / 2f64.powi(k)).collect();
    let second: Vec<(f64, f64)> = h.iter().map(|&h| (h, 3.0 * h * h)).collect();
    let mut fourth: Vec<(f64, f64)> = h.iter().map(|&h| (h, 20.0 * h.powi(4))).collect();
    // Cannot be shown on a log axis: dropped, and the rest still drawn.
    fourth.push((0.05, 0.0));
    fourth.push((-1.0, 1e-5));
    fourth.push((f64::NAN, 1e-5));
    let reference: Vec<(f64, f64)> = [0.1, 0.1 / 32.0].iter().map(|&h| (h, h * h)).collect();
    Figure {
        title: "Convergence of the elastic solve".into(),
        x_label: "h".into(),
        y_label: "max error in r".into(),
        x_scale: Scale::Log10,
        y_scale: Scale::Log10,
        series: vec![
            Series::new("trapezoid", second, SeriesStyle::LineAndMarkers),
            Series::new("hermite-simpson", fourth, SeriesStyle::Markers),
            Series::new("slope 2", reference, SeriesStyle::DashedLine),
        ],
        ..Figure::default()
    }
}

#[test]
fn log_log_figure_is_written_as_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let fig = convergence_figure();
    assert_eq!((fig.width, fig.height), (900, 650));
    let (png_path, svg_path) = write(&fig, &dir.path().join("conv")).unwrap();
    assert_eq!(png_path, dir.path().join("conv.png"));
    assert_eq!(svg_path, dir.path().join("conv.svg"));
    only(dir.path(), &["conv.png", "conv.svg"]);

    let (w, h, rgb) = decode_png(&png_path);
    assert_eq!((w, h), (900, 650));
    let white = pixels(&rgb).filter(|p| *p == [255, 255, 255]).count();
    let dark = pixels(&rgb).filter(|p| p.iter().all(|&c| c < 80)).count();
    assert!(white > rgb.len() / 3 / 2, "mostly background");
    assert!(dark > 2000, "axes and text are drawn ({dark} dark pixels)");
    // Every series is drawn in its palette colour.
    for (k, c) in PALETTE.iter().take(3).enumerate() {
        let n = count_color(&rgb, *c);
        assert!(n > 100, "series {k}: {n} pixels of its colour");
    }
    assert_eq!(count_color(&rgb, PALETTE[3]), 0);

    let svg = fs::read_to_string(&svg_path).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
    let texts = svg_texts(&svg);
    for name in [
        "trapezoid",
        "hermite-simpson",
        "slope 2",
        "Convergence of the elastic solve",
    ] {
        assert!(
            texts.iter().any(|t| t == name),
            "{name} missing from {texts:?}"
        );
    }
    assert!(!svg.contains("no data"));
    assert!(svg.contains("<polyline") || svg.contains("<path"));
    assert!(svg.contains("<polygon"), "markers");
    // Log ticks are powers of ten.
    for tick in ["1e-3", "1e-2", "1e-1", "1e0", "1e-9", "1e-5"] {
        assert!(
            texts.iter().any(|t| t == tick),
            "tick {tick} missing from {texts:?}"
        );
    }
    keep_sample(&fig, "convergence");

    // Writing again replaces the files.
    write(&fig, &dir.path().join("conv")).unwrap();
    only(dir.path(), &["conv.png", "conv.svg"]);
}

#[test]
fn a_series_with_no_drawable_point_is_listed_as_no_data() {
    let dir = tempfile::tempdir().unwrap();
    let mut fig = convergence_figure();
    fig.series.push(Series::new(
        "diverged",
        vec![(0.1, -1.0), (0.0, 1.0), (f64::INFINITY, 1.0)],
        SeriesStyle::Line,
    ));
    fig.series
        .push(Series::new("empty", vec![], SeriesStyle::LineAndMarkers));
    let (_, svg) = write(&fig, &dir.path().join("f")).unwrap();
    let svg = fs::read_to_string(svg).unwrap();
    let texts = svg_texts(&svg);
    assert!(texts.iter().any(|t| t == "diverged (no data)"), "{texts:?}");
    assert!(texts.iter().any(|t| t == "empty (no data)"), "{texts:?}");
    // Nothing at all to draw still gives a figure.
    let nothing = Figure {
        x_scale: Scale::Log10,
        series: vec![Series::new("none", vec![(0.0, 0.0)], SeriesStyle::Markers)],
        ..Figure::new("empty", "x", "y")
    };
    let (png, _) = write(&nothing, &dir.path().join("nothing")).unwrap();
    assert_eq!(decode_png(&png).0, 900);
}

/// The horizontal and vertical diameters, in pixels, of a closed curve drawn in colour `c`:
/// through its centre (the median of its pixels, which a legend icon does not move far).
fn diameters(w: u32, rgb: &[u8], c: Rgb) -> (u32, u32) {
    let hits: Vec<(u32, u32)> = pixels(rgb)
        .enumerate()
        .filter(|(_, p)| *p == [c.0, c.1, c.2])
        .map(|(i, _)| (i as u32 % w, i as u32 / w))
        .collect();
    assert!(hits.len() > 200, "{} pixels of the curve", hits.len());
    let median = |mut v: Vec<u32>| {
        v.sort();
        v[v.len() / 2]
    };
    let cx = median(hits.iter().map(|p| p.0).collect());
    let cy = median(hits.iter().map(|p| p.1).collect());
    let row: Vec<u32> = hits.iter().filter(|p| p.1 == cy).map(|p| p.0).collect();
    let col: Vec<u32> = hits.iter().filter(|p| p.0 == cx).map(|p| p.1).collect();
    let span = |v: &[u32]| v.iter().max().unwrap() - v.iter().min().unwrap();
    (span(&row), span(&col))
}

#[test]
fn equal_aspect_draws_a_circle_round() {
    let dir = tempfile::tempdir().unwrap();
    let unit: Vec<(f64, f64)> = (0..=200)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 200.0;
            (2.0 + t.cos(), t.sin())
        })
        .collect();
    let fig = Figure {
        title: "Shell shape".into(),
        x_label: "x".into(),
        y_label: "z".into(),
        aspect_equal: true,
        series: vec![Series::new("unit circle", unit, SeriesStyle::Line)],
        width: 700,
        height: 400,
        ..Figure::default()
    };
    let (png, svg) = write(&fig, &dir.path().join("shape")).unwrap();
    let (w, h, rgb) = decode_png(&png);
    assert_eq!((w, h), (700, 400));
    let (dx, dy) = diameters(w, &rgb, PALETTE[0]);
    assert!(dy > 150, "circle height {dy}");
    assert!(dx.abs_diff(dy) <= 3, "circle is {dx}x{dy} pixels");
    let svg = fs::read_to_string(svg).unwrap();
    assert!(svg_texts(&svg).iter().any(|t| t == "unit circle"));
    keep_sample(&fig, "shape");

    // Without equal aspect the same circle fills the wide plot: an ellipse.
    let stretched = Figure {
        aspect_equal: false,
        ..fig.clone()
    };
    let (png, _) = write(&stretched, &dir.path().join("stretched")).unwrap();
    let (w, _, rgb) = decode_png(&png);
    let (dx, dy) = diameters(w, &rgb, PALETTE[0]);
    assert!(
        dx as f64 > 1.5 * dy as f64,
        "stretched circle is {dx}x{dy} pixels"
    );
}

#[test]
fn errors_are_typed() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    fs::write(&file, "x").unwrap();

    // Equal aspect on a log axis is refused.
    let fig = Figure {
        aspect_equal: true,
        ..convergence_figure()
    };
    let err = write(&fig, &dir.path().join("log")).unwrap_err();
    assert!(matches!(err, PlotError::Invalid { .. }), "{err:?}");
    assert!(err.to_string().contains("linear"), "{err}");
    let err = write(
        &Figure {
            width: 0,
            ..Figure::default()
        },
        &dir.path().join("tiny"),
    )
    .unwrap_err();
    assert!(matches!(err, PlotError::Invalid { .. }), "{err:?}");
    only(dir.path(), &["a-file"]);
}

/// Pixels within `tol` (per channel) of colour `c`.
fn count_near(rgb: &[u8], c: Rgb, tol: u8) -> usize {
    pixels(rgb)
        .filter(|p| {
            p.iter()
                .zip([c.0, c.1, c.2])
                .all(|(a, b)| a.abs_diff(b) <= tol)
        })
        .count()
}

/// A shell cross-section: a circle of radius 1 seen from the side, shaded by a "growth rate"
/// running from 0 at the bottom to 1 at the top, drawn thick and kept out of the legend.
fn shaded_shell(color_scale: bool) -> Figure {
    let n = 240;
    let points: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let t = -std::f64::consts::FRAC_PI_2 + k as f64 * std::f64::consts::PI / n as f64;
            (t.cos(), t.sin())
        })
        .collect();
    let rate: Vec<f64> = points.iter().map(|p| (p.1 + 1.0) / 2.0).collect();
    let mut fig = Figure::new("Growth rate on the shell", "x", "z")
        .with(
            Series::new("shell", points, SeriesStyle::Line)
                .shaded(rate)
                .width(6)
                .no_legend(),
        )
        .note("t = 0.1");
    fig.aspect_equal = true;
    fig.width = 700;
    fig.height = 600;
    if color_scale {
        fig = fig.color_scale("growth rate", 0.0, 1.0);
    }
    fig
}

#[test]
fn a_shaded_series_uses_both_ends_of_the_colormap() {
    let dir = tempfile::tempdir().unwrap();
    // No colour scale: the curve alone spans its values, and no bar is drawn.
    let fig = shaded_shell(false);
    let (png, svg) = write(&fig, &dir.path().join("shell")).unwrap();
    let (w, h, rgb) = decode_png(&png);
    assert_eq!((w, h), (700, 600));
    let low = count_near(&rgb, colormap(0.0), 6);
    let high = count_near(&rgb, colormap(1.0), 6);
    assert!(low > 20 && high > 20, "{low} low and {high} high pixels");
    assert!(count_near(&rgb, colormap(0.5), 6) > 20);
    // Not drawn in the palette colour, and kept out of the legend.
    assert_eq!(count_color(&rgb, PALETTE[0]), 0);
    let texts = svg_texts(&fs::read_to_string(svg).unwrap());
    assert!(!texts.iter().any(|t| t == "shell"), "{texts:?}");
    assert!(texts.iter().any(|t| t == "t = 0.1"), "{texts:?}");
    keep_sample(&fig, "shaded");
}

#[test]
fn the_colour_bar_is_drawn_at_the_right_with_its_label() {
    let dir = tempfile::tempdir().unwrap();
    let fig = shaded_shell(true);
    let (png, svg) = write(&fig, &dir.path().join("bar")).unwrap();
    let (w, h, rgb) = decode_png(&png);
    assert_eq!((w, h), (700, 600));
    // Both ends of the scale are in the bar's strip.
    let strip: Vec<u8> = rgb
        .chunks_exact(w as usize * 3)
        .flat_map(|row| row[(w - COLORBAR_AREA) as usize * 3..].to_vec())
        .collect();
    for end in [0.0, 1.0] {
        let n = count_near(&strip, colormap(end), 0);
        assert!(n >= 15, "{n} pixels of colormap({end}) in the bar");
    }
    let svg = fs::read_to_string(svg).unwrap();
    let texts = svg_texts(&svg);
    for t in ["growth rate", "0", "0.5", "1", "Growth rate on the shell"] {
        assert!(texts.iter().any(|x| x == t), "{t} missing from {texts:?}");
    }
    keep_sample(&fig, "colour-bar");
}

#[test]
fn non_finite_values_are_grey_and_the_scale_clamps() {
    let dir = tempfile::tempdir().unwrap();
    let points: Vec<(f64, f64)> = (0..=40).map(|k| (k as f64, 0.0)).collect();
    // Far outside the scale at both ends; a hole in the middle.
    let mut values: Vec<f64> = (0..=40)
        .map(|k| if k < 20 { -50.0 } else { 50.0 })
        .collect();
    values[10] = f64::NAN;
    values[11] = f64::INFINITY;
    let fig = Figure::new("", "x", "y")
        .with(
            Series::new("s", points, SeriesStyle::Line)
                .shaded(values)
                .width(4),
        )
        .color_scale("", 0.0, 1.0)
        .no_legend();
    let (png, _) = write(&fig, &dir.path().join("grey")).unwrap();
    let (_, _, rgb) = decode_png(&png);
    assert!(count_color(&rgb, NO_VALUE_COLOR) > 20);
    assert!(count_near(&rgb, colormap(0.0), 0) > 100);
    assert!(count_near(&rgb, colormap(1.0), 0) > 100);
}

#[test]
fn colour_and_width_override_the_palette_also_when_dashed() {
    let dir = tempfile::tempdir().unwrap();
    let c = Rgb(200, 30, 120);
    let line = |w: u32| {
        let fig = Figure::new("", "x", "y").with(
            Series::new("ref", vec![(0.0, 0.0), (1.0, 1.0)], SeriesStyle::DashedLine)
                .color(c)
                .width(w),
        );
        let (png, _) = write(&fig, &dir.path().join(format!("w{w}"))).unwrap();
        let (_, _, rgb) = decode_png(&png);
        assert_eq!(count_color(&rgb, PALETTE[0]), 0);
        count_color(&rgb, c)
    };
    let (thin, thick) = (line(1), line(8));
    assert!(thin > 50, "{thin}");
    assert!(thick > 4 * thin, "{thick} vs {thin}");
}

#[test]
fn explicit_ranges_clip_the_lines() {
    let dir = tempfile::tempdir().unwrap();
    // A line from x = -10 to 10, shown over 0..1: nothing may spill into the margins.
    let fig = Figure::new("", "x", "y")
        .with(Series::new(
            "long",
            vec![(-10.0, 0.5), (10.0, 0.5)],
            SeriesStyle::LineAndMarkers,
        ))
        .with(
            // One value and no colour scale: the low end.
            Series::new(
                "shaded",
                vec![(-10.0, 0.25), (10.0, 0.25)],
                SeriesStyle::Line,
            )
            .shaded(vec![1.0, 1.0]),
        )
        .x_range(0.0, 1.0)
        .y_range(0.0, 1.0)
        .no_legend();
    let (png, svg) = write(&fig, &dir.path().join("clip")).unwrap();
    let (w, _, rgb) = decode_png(&png);
    let xs = |c: Rgb| -> Vec<u32> {
        pixels(&rgb)
            .enumerate()
            .filter(|(_, p)| *p == [c.0, c.1, c.2])
            .map(|(i, _)| i as u32 % w)
            .collect()
    };
    for c in [PALETTE[0], colormap(0.0)] {
        let xs = xs(c);
        assert!(xs.len() > 500, "{} pixels", xs.len());
        // The plotting area starts after the margin (15) and the y labels (95).
        let (min, max) = (xs.iter().min().unwrap(), xs.iter().max().unwrap());
        assert!(
            *min >= 105 && *max <= w - 10,
            "drawn from x = {min} to {max}"
        );
    }
    let texts = svg_texts(&fs::read_to_string(svg).unwrap());
    for tick in ["0", "0.2", "1"] {
        assert!(
            texts.iter().any(|t| t == tick),
            "{tick} missing from {texts:?}"
        );
    }
    assert!(!texts.iter().any(|t| t == "-5" || t == "long"), "{texts:?}");
}

#[test]
fn legends_can_be_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let fam = |k: usize| {
        let s = Series::new(
            format!("curve {k}"),
            vec![(0.0, k as f64), (1.0, k as f64 + 1.0)],
            SeriesStyle::Line,
        );
        if k == 0 {
            s
        } else {
            s.no_legend()
        }
    };
    let fig = (0..4).fold(Figure::new("family", "x", "y"), |f, k| f.with(fam(k)));
    let (_, svg) = write(&fig, &dir.path().join("some")).unwrap();
    let texts = svg_texts(&fs::read_to_string(svg).unwrap());
    assert!(texts.iter().any(|t| t == "curve 0"), "{texts:?}");
    assert!(!texts.iter().any(|t| t == "curve 1"), "{texts:?}");
    let (_, svg) = write(&fig.no_legend(), &dir.path().join("none")).unwrap();
    let texts = svg_texts(&fs::read_to_string(svg).unwrap());
    assert!(!texts.iter().any(|t| t.starts_with("curve")), "{texts:?}");
}

#[test]
fn odd_input_still_draws() {
    let dir = tempfile::tempdir().unwrap();
    let nan = f64::NAN;
    let figs = [
        // Values shorter than the points, stroke widths at both extremes, every style shaded.
        Figure::new("odd", "x", "y")
            .with(
                Series::new(
                    "a",
                    vec![(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)],
                    SeriesStyle::Line,
                )
                .shaded(vec![1.0])
                .width(0),
            )
            .with(
                Series::new("b", vec![(0.0, 1.0), (2.0, 1.0)], SeriesStyle::DashedLine)
                    .shaded(vec![nan, 3.0])
                    .width(1_000_000),
            )
            .with(Series::new("c", vec![(0.5, 0.5)], SeriesStyle::LineAndMarkers).shaded(vec![]))
            .with(Series::new("d", vec![], SeriesStyle::Markers).shaded(vec![1.0]))
            .color_scale("", 2.0, 2.0)
            .x_range(nan, 1.0)
            .y_range(3.0, 3.0),
        // No data at all, reversed and infinite scales, notes and a bar on a tiny figure.
        Figure {
            width: 100,
            height: 100,
            ..Figure::new("tiny", "x", "y")
                .with(Series::new("e", vec![(nan, nan)], SeriesStyle::Line).shaded(vec![nan]))
                .color_scale("rate", f64::INFINITY, 0.0)
                .note("t = 0")
                .note("")
        },
        Figure::new("", "", "")
            .scales(Scale::Log10, Scale::Log10)
            .with(
                Series::new("f", vec![(1e-3, 1e-3), (1e3, 1e3)], SeriesStyle::Line)
                    .shaded(vec![f64::MAX, -f64::MAX]),
            )
            .color_scale("g", 1.0, -1.0)
            .x_range(1e-2, 1.0)
            .y_range(-1.0, 1.0),
    ];
    for (k, fig) in figs.iter().enumerate() {
        let (png, _) = write(fig, &dir.path().join(format!("odd{k}"))).unwrap();
        let (w, h, _) = decode_png(&png);
        assert_eq!((w, h), (fig.width, fig.height));
        keep_sample(fig, &format!("odd{k}"));
    }
    let (png, _) = write_panels(&figs, 2, "odd", 200, 150, &dir.path().join("odd-panels")).unwrap();
    assert_eq!(decode_png(&png).0, 400);
}

fn panel(k: usize) -> Figure {
    let points: Vec<(f64, f64)> = (0..=20)
        .map(|i| (i as f64 / 20.0, (k + i) as f64))
        .collect();
    let fig = Figure::new(
        format!("({}) panel", (b'a' + k as u8) as char),
        "t",
        "stretch",
    )
    .with(Series::new("light", points.clone(), SeriesStyle::Line).width(1))
    .with(
        Series::new("heavy", points, SeriesStyle::Line)
            .width(4)
            .color(Rgb(0, 0, 0)),
    );
    if k == 1 {
        fig.color_scale("rate", 0.0, 1.0)
    } else {
        fig
    }
}

#[test]
fn panels_are_laid_out_in_a_grid() {
    let dir = tempfile::tempdir().unwrap();
    let panels: Vec<Figure> = (0..5).map(panel).collect();
    let stem = dir.path().join("grid");
    let (png, svg) = write_panels(&panels, 3, "Figure 4", 400, 300, &stem).unwrap();
    if let Some(d) = std::env::var_os("EYESHELL_PLOT_SAMPLES") {
        write_panels(
            &panels,
            3,
            "Figure 4",
            400,
            300,
            &PathBuf::from(d).join("panels"),
        )
        .unwrap();
    }
    assert_eq!(
        (png.clone(), svg.clone()),
        (dir.path().join("grid.png"), dir.path().join("grid.svg"))
    );
    only(dir.path(), &["grid.png", "grid.svg"]);
    let (w, h, rgb) = decode_png(&png);
    assert_eq!((w, h), (3 * 400, 2 * 300 + PANELS_TITLE_BAND));
    // The sixth cell is empty: white.
    let cell_white = rgb
        .chunks_exact(w as usize * 3)
        .skip((PANELS_TITLE_BAND + 300) as usize)
        .all(|row| row[800 * 3..].iter().all(|&b| b == 255));
    assert!(cell_white);
    // The colour bar of panel (b) only.
    assert!(count_near(&rgb, colormap(1.0), 0) >= 15);
    let texts = svg_texts(&fs::read_to_string(&svg).unwrap());
    for t in [
        "Figure 4",
        "(a) panel",
        "(b) panel",
        "(e) panel",
        "rate",
        "heavy",
    ] {
        assert!(texts.iter().any(|x| x == t), "{t} missing from {texts:?}");
    }
    assert_eq!(texts.iter().filter(|t| *t == "light").count(), 5);

    // Each panel is drawn as `write` draws it: the same pixels as the top-left cell.
    let alone = Figure {
        width: 400,
        height: 300,
        ..panel(0)
    };
    let (one, _) = write(&alone, &dir.path().join("one")).unwrap();
    let (_, _, single) = decode_png(&one);
    let cell: Vec<u8> = rgb
        .chunks_exact(w as usize * 3)
        .skip(PANELS_TITLE_BAND as usize)
        .take(300)
        .flat_map(|row| row[..400 * 3].to_vec())
        .collect();
    assert!(
        cell == single,
        "panel (a) differs from the figure drawn alone"
    );

    // No title: no band.
    let (png, _) = write_panels(&panels[..4], 2, "", 400, 300, &stem).unwrap();
    let (w, h, _) = decode_png(&png);
    assert_eq!((w, h), (2 * 400, 2 * 300));
    only(dir.path(), &["grid.png", "grid.svg", "one.png", "one.svg"]);
}

#[test]
fn bad_panels_are_refused_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("p");
    let panels: Vec<Figure> = (0..3).map(panel).collect();
    let log_equal = Figure {
        aspect_equal: true,
        ..convergence_figure()
    };
    let cases: Vec<(&[Figure], usize, u32, u32, &str)> = vec![
        (&[], 2, 400, 300, "no panels"),
        (&panels, 0, 400, 300, "column"),
        (&panels, 2, 50, 300, "100..=20000"),
        (&panels, 2, 400, 30_000, "100..=20000"),
        (&panels, 30, 1000, 300, "30000x350"),
        (&panels, usize::MAX, 20_000, 300, "too large"),
        (
            std::slice::from_ref(&log_equal),
            1,
            400,
            300,
            "panel 1: an equal aspect",
        ),
    ];
    for (panels, columns, pw, ph, why) in cases {
        let err = write_panels(panels, columns, "t", pw, ph, &stem).unwrap_err();
        assert!(matches!(err, PlotError::Invalid { .. }), "{err:?}");
        assert!(err.to_string().contains(why), "{err} (wanted {why})");
    }
    only(dir.path(), &[]);
}

/// A title wider than the figure is drawn smaller, whole: nothing dark in the title band's
/// outer margins (centred at its full size, it would be cut at both edges).
#[test]
fn a_long_title_is_shrunk_to_fit_not_clipped() {
    let dir = tempfile::tempdir().unwrap();
    let fig = Figure {
        title: "growth to t_end: axial-length error (largest over the output times) against CVODE rtol 1e-10".into(),
        ..convergence_figure()
    };
    keep_sample(&fig, "long_title");
    let (png_path, _) = write(&fig, &dir.path().join("long")).unwrap();
    let (w, _, rgb) = decode_png(&png_path);
    let dark_at = |x: u32, y: u32| {
        let k = 3 * (y * w + x) as usize;
        rgb[k..k + 3].iter().all(|&c| c < 128)
    };
    let band = 0..40; // the title's row, above the chart
    let dark = |xs: std::ops::Range<u32>| {
        xs.flat_map(|x| band.clone().map(move |y| (x, y)))
            .filter(|&(x, y)| dark_at(x, y))
            .count()
    };
    assert_eq!(dark(0..6), 0, "text at the left edge");
    assert_eq!(dark(w - 6..w), 0, "text at the right edge");
    assert!(dark(0..w) > 200, "the title is drawn");
}
