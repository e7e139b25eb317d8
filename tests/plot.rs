//! Figures as PNG and SVG (`eyeshell::output::plot`).
//!
//! Set `EYESHELL_PLOT_SAMPLES=DIR` to keep a copy of each test figure in DIR for a look.

use std::fs;
use std::path::{Path, PathBuf};

use eyeshell::output::plot::{self, Figure, PlotError, Scale, Series, SeriesStyle, PALETTE};

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

fn count_color(rgb: &[u8], c: plotters::style::RGBColor) -> usize {
    pixels(rgb).filter(|p| *p == [c.0, c.1, c.2]).count()
}

/// Keep a copy of the figure when EYESHELL_PLOT_SAMPLES names a directory.
fn keep_sample(fig: &Figure, name: &str) {
    if let Some(dir) = std::env::var_os("EYESHELL_PLOT_SAMPLES") {
        plot::write(fig, &PathBuf::from(dir).join(name)).unwrap();
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
    let (png_path, svg_path) = plot::write(&fig, &dir.path().join("conv")).unwrap();
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
    plot::write(&fig, &dir.path().join("conv")).unwrap();
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
    let (_, svg) = plot::write(&fig, &dir.path().join("f")).unwrap();
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
    let (png, _) = plot::write(&nothing, &dir.path().join("nothing")).unwrap();
    assert_eq!(decode_png(&png).0, 900);
}

/// The horizontal and vertical diameters, in pixels, of a closed curve drawn in colour `c`:
/// through its centre (the median of its pixels, which a legend icon does not move far).
fn diameters(w: u32, rgb: &[u8], c: plotters::style::RGBColor) -> (u32, u32) {
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
    let (png, svg) = plot::write(&fig, &dir.path().join("shape")).unwrap();
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
    let (png, _) = plot::write(&stretched, &dir.path().join("stretched")).unwrap();
    let (w, _, rgb) = decode_png(&png);
    let (dx, dy) = diameters(w, &rgb, PALETTE[0]);
    assert!(
        dx as f64 > 1.5 * dy as f64,
        "stretched circle is {dx}x{dy} pixels"
    );
}

#[test]
fn errors_are_typed_and_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    fs::write(&file, "x").unwrap();
    let stem = file.join("fig");
    let err = plot::write(&convergence_figure(), &stem).unwrap_err();
    assert!(matches!(err, PlotError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("a-file"), "{err}");
    assert_eq!(fs::read_to_string(&file).unwrap(), "x");
    only(dir.path(), &["a-file"]);

    // Equal aspect on a log axis is refused.
    let fig = Figure {
        aspect_equal: true,
        ..convergence_figure()
    };
    let err = plot::write(&fig, &dir.path().join("log")).unwrap_err();
    assert!(matches!(err, PlotError::Invalid { .. }), "{err:?}");
    assert!(err.to_string().contains("linear"), "{err}");
    let err = plot::write(
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
