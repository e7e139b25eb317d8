//! Figures as PNG and SVG, drawn with `plotters` (no Python): convergence studies,
//! work-precision diagrams and, later, the paper's figures.
//!
//! A [`Figure`] holds [`Series`] of points; [`write`] draws it to `<stem>.png` and
//! `<stem>.svg`. Colours come from a fixed palette ([`PALETTE`]) and marker shapes from a
//! fixed cycle, both by the series' index, so a figure looks the same on every run.
//!
//! PNG text is rasterised from a TrueType font read at run time (Debian's
//! `fonts-dejavu-core`, see [`FONT_PATHS`]); nothing links against fontconfig. The font is
//! also what lays out the text of the SVG, but the SVG file itself holds `<text>` elements
//! in the `sans-serif` family and needs no font file to be viewed.

use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Size of a figure unless told otherwise, in pixels.
pub const DEFAULT_WIDTH: u32 = 900;
/// Size of a figure unless told otherwise, in pixels.
pub const DEFAULT_HEIGHT: u32 = 650;

/// Where the PNG font is looked for, in order (Debian first). `EYESHELL_PLOT_FONT`, when
/// set, names a TTF to try before these.
pub const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/local/share/fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// The environment variable naming a TTF font to use instead of [`FONT_PATHS`].
pub const FONT_ENV: &str = "EYESHELL_PLOT_FONT";

/// The series colours, by index (matplotlib's "tab10": distinct, and readable in print).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A solid line through the points, and a marker on each.
    #[default]
    LineAndMarkers,
    /// A marker on each point, no line.
    Markers,
    /// A solid line, no markers.
    Line,
    /// A dashed line, no markers (reference slopes, exact solutions).
    DashedLine,
}

/// The scale of an axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    #[default]
    Linear,
    /// Logarithmic, ticks at powers of ten labelled `1e-3`.
    Log10,
}

/// One curve: a name for the legend and its points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: SeriesStyle,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, style: SeriesStyle) -> Self {
        Series {
            name: name.into(),
            points,
            style,
        }
    }
}

/// A figure: title, axes and series. `Figure::default()` is 900×650 with linear axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_scale: Scale,
    pub y_scale: Scale,
    pub series: Vec<Series>,
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// One unit is the same length on both axes (shell shapes). Needs both axes linear.
    pub aspect_equal: bool,
}

impl Default for Figure {
    fn default() -> Self {
        Figure {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: Vec::new(),
            width: DEFAULT_WIDTH,
            height: DEFAULT_HEIGHT,
            aspect_equal: false,
        }
    }
}

impl Figure {
    /// A default-sized figure with linear axes and no series.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Figure {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Figure::default()
        }
    }

    /// Builder: the scales of both axes.
    pub fn scales(mut self, x: Scale, y: Scale) -> Self {
        self.x_scale = x;
        self.y_scale = y;
        self
    }

    /// Builder: add a series.
    pub fn with(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }
}

/// Failure to write a figure. Display is one line naming the path.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: no font for the figure's text (looked for {}); install one with `apt-get install fonts-dejavu-core` or name a TTF file in {FONT_ENV}", path.display(), tried.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    NoFont { path: PathBuf, tried: Vec<PathBuf> },
    #[error("{}: the font {} could not be read as TrueType", path.display(), font.display())]
    BadFont { path: PathBuf, font: PathBuf },
    #[error("{}: drawing failed: {message}", path.display())]
    Draw { path: PathBuf, message: String },
    #[error("{}: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
}

impl PlotError {
    /// The file (or stem) the error is about.
    pub fn path(&self) -> &Path {
        match self {
            PlotError::Io { path, .. }
            | PlotError::NoFont { path, .. }
            | PlotError::BadFont { path, .. }
            | PlotError::Draw { path, .. }
            | PlotError::Invalid { path, .. } => path,
        }
    }
}

/// The font registered with plotters, once found (fonts are registered for the process).
static FONT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Find a TTF and register it as plotters' "sans-serif" (once per process). Returns its
/// path. A failure is not remembered, so installing the font later helps.
pub fn ensure_font() -> Result<PathBuf, (Vec<PathBuf>, Option<PathBuf>)> {
    let mut font = FONT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(path) = font.as_ref() {
        return Ok(path.clone());
    }
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os(FONT_ENV).filter(|p| !p.is_empty()) {
        candidates.push(PathBuf::from(p));
    }
    candidates.extend(FONT_PATHS.iter().map(PathBuf::from));
    for path in &candidates {
        let Ok(bytes) = fs::read(path) else { continue };
        // plotters keeps the font for the life of the process: leak it once.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_err() {
            return Err((candidates.clone(), Some(path.clone())));
        }
        *font = Some(path.clone());
        return Ok(path.clone());
    }
    Err((candidates, None))
}

/// `<stem><ext>`: the extension is appended, so dots in the stem stay.
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = OsString::from(stem.as_os_str());
    s.push(ext);
    PathBuf::from(s)
}

/// Write `<stem>.png` and `<stem>.svg`; returns the two paths.
///
/// Points with a non-finite coordinate, or a non-positive one on a log axis, are dropped;
/// a series left empty is still in the legend, as "NAME (no data)". The axis ranges cover
/// every point with a margin (log axes: whole decades, and at least a factor 10^0.1 beyond
/// the data). Missing parent directories are created. Each file is written under a
/// temporary name in its directory and renamed into place, so no half-written figure is
/// left on error. Errors come back as [`PlotError`] naming the path.
pub fn write(fig: &Figure, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    let png_path = with_suffix(stem, ".png");
    let svg_path = with_suffix(stem, ".svg");
    let invalid = |reason: &str| PlotError::Invalid {
        path: stem.to_path_buf(),
        reason: reason.to_string(),
    };
    if stem.file_name().is_none() {
        return Err(invalid("the figure path has no file name"));
    }
    if fig.width < 100 || fig.height < 100 || fig.width > 20_000 || fig.height > 20_000 {
        return Err(invalid(&format!(
            "figure size {}x{} is outside 100..=20000 pixels",
            fig.width, fig.height
        )));
    }
    if fig.aspect_equal && (fig.x_scale != Scale::Linear || fig.y_scale != Scale::Linear) {
        return Err(invalid("an equal aspect ratio needs both axes linear"));
    }
    ensure_font().map_err(|(tried, bad)| match bad {
        Some(font) => PlotError::BadFont {
            path: png_path.clone(),
            font,
        },
        None => PlotError::NoFont {
            path: png_path.clone(),
            tried,
        },
    })?;

    let prepared = Prepared::new(fig);
    let (w, h) = (fig.width, fig.height);

    // Draw both into memory first.
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root, fig, &prepared).map_err(|message| PlotError::Draw {
            path: png_path.clone(),
            message,
        })?;
        root.present().map_err(|e| PlotError::Draw {
            path: png_path.clone(),
            message: e.to_string(),
        })?;
    }
    let png_bytes = encode_png(&rgb, w, h).map_err(|e| PlotError::Io {
        path: png_path.clone(),
        source: e,
    })?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw(&root, fig, &prepared).map_err(|message| PlotError::Draw {
            path: svg_path.clone(),
            message,
        })?;
        root.present().map_err(|e| PlotError::Draw {
            path: svg_path.clone(),
            message: e.to_string(),
        })?;
    }

    if let Some(parent) = stem.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).map_err(|e| PlotError::Io {
            path: parent.to_path_buf(),
            source: e,
        })?;
    }
    // Both temporaries first, then both renames: an error leaves neither half-written.
    let png_tmp = write_temp(&png_path, &png_bytes)?;
    let svg_tmp = match write_temp(&svg_path, svg.as_bytes()) {
        Ok(t) => t,
        Err(e) => {
            let _ = fs::remove_file(&png_tmp);
            return Err(e);
        }
    };
    for (tmp, path) in [(&png_tmp, &png_path), (&svg_tmp, &svg_path)] {
        if let Err(e) = fs::rename(tmp, path) {
            let _ = fs::remove_file(&png_tmp);
            let _ = fs::remove_file(&svg_tmp);
            return Err(PlotError::Io {
                path: path.clone(),
                source: e,
            });
        }
    }
    Ok((png_path, svg_path))
}

fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(out)
}

/// Write `bytes` to a fresh hidden sibling of `path`; returns its name. Removed on error.
fn write_temp(path: &Path, bytes: &[u8]) -> Result<PathBuf, PlotError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let tmp = path.with_file_name(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    if let Err(e) = fs::write(&tmp, bytes) {
        let _ = fs::remove_file(&tmp);
        return Err(PlotError::Io {
            path: path.to_path_buf(),
            source: e,
        });
    }
    Ok(tmp)
}

/// The figure's points after dropping those the axes cannot show, and the axis ranges.
struct Prepared {
    series: Vec<Vec<(f64, f64)>>,
    x: (f64, f64),
    y: (f64, f64),
}

impl Prepared {
    fn new(fig: &Figure) -> Self {
        let keep = |v: f64, s: Scale| v.is_finite() && (s == Scale::Linear || v > 0.0);
        let series: Vec<Vec<(f64, f64)>> = fig
            .series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .copied()
                    .filter(|&(x, y)| keep(x, fig.x_scale) && keep(y, fig.y_scale))
                    .collect()
            })
            .collect();
        let all = || series.iter().flatten();
        let x = axis_range(all().map(|p| p.0), fig.x_scale);
        let y = axis_range(all().map(|p| p.1), fig.y_scale);
        Prepared { series, x, y }
    }
}

/// The range an axis shows: every value with a margin.
fn axis_range(values: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    match scale {
        Scale::Linear => {
            if lo > hi {
                return (0.0, 1.0);
            }
            let span = hi - lo;
            let pad = if span > 0.0 {
                0.05 * span
            } else if lo != 0.0 {
                0.1 * lo.abs()
            } else {
                1.0
            };
            (lo - pad, hi + pad)
        }
        Scale::Log10 => {
            if lo > hi {
                return (1.0, 10.0);
            }
            // Whole decades, at least a factor 10^0.1 beyond the data, at least one decade.
            let a = (lo.log10() - 0.1).floor();
            let mut b = (hi.log10() + 0.1).ceil();
            if b <= a {
                b = a + 1.0;
            }
            // A hair wider, so that rounding keeps the end decades' ticks.
            (10f64.powf(a) * (1.0 - 1e-9), 10f64.powf(b) * (1.0 + 1e-9))
        }
    }
}

/// Widen the linear ranges so that one unit is as long on x as on y in a plotting area of
/// `pw`×`ph` pixels (centred on the data).
fn equal_aspect(x: (f64, f64), y: (f64, f64), pw: u32, ph: u32) -> ((f64, f64), (f64, f64)) {
    let (pw, ph) = (pw.max(1) as f64, ph.max(1) as f64);
    let per_px = ((x.1 - x.0) / pw).max((y.1 - y.0) / ph);
    let grow = |r: (f64, f64), px: f64| {
        let (c, half) = ((r.0 + r.1) / 2.0, per_px * px / 2.0);
        (c - half, c + half)
    };
    (grow(x, pw), grow(y, ph))
}

/// A tick label on a log axis: `1e-3`, `2e-3`, ...
fn log_label(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return String::new();
    }
    let e = v.log10().floor();
    let mut m = v / 10f64.powf(e);
    let mut e = e as i32;
    if (m - 10.0).abs() < 1e-9 {
        m = 1.0;
        e += 1;
    }
    let m = (m * 100.0).round() / 100.0;
    if (m - 1.0).abs() < 1e-9 {
        format!("1e{e}")
    } else {
        format!("{m}e{e}")
    }
}

/// A tick label on a linear axis spanning `span`: short, plain or scientific.
fn linear_label(v: f64, span: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    // Ticks are about span/10 apart; one more digit than that.
    let step = (span / 10.0).abs().max(f64::MIN_POSITIVE);
    if v.abs() < step * 1e-6 {
        return "0".to_string();
    }
    let mag = v.abs().log10().floor();
    if (-3.0..5.0).contains(&mag) {
        let decimals = (-(step.log10().floor()) + 1.0).clamp(0.0, 8.0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let digits = (mag - step.log10().floor() + 1.0).clamp(0.0, 6.0) as usize;
        let s = format!("{v:.digits$e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

const MARGIN: u32 = 15;
const X_LABEL_AREA: u32 = 60;
const Y_LABEL_AREA: u32 = 95;
const TITLE_SIZE: f64 = 26.0;
const AXIS_DESC_SIZE: f64 = 20.0;
const TICK_SIZE: f64 = 16.0;
const LEGEND_SIZE: f64 = 16.0;
const STROKE: u32 = 2;

fn text(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

/// Draw the figure on `root`. Errors as text (the caller names the file).
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    prep: &Prepared,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let area = if fig.title.is_empty() {
        root.clone()
    } else {
        root.titled(&fig.title, text(TITLE_SIZE)).map_err(e)?
    };
    let (x, y) = (prep.x, prep.y);
    match (fig.x_scale, fig.y_scale) {
        (Scale::Linear, Scale::Linear) => {
            let (x, y) = if fig.aspect_equal {
                let (pw, ph) = plot_size(&area);
                equal_aspect(x, y, pw, ph)
            } else {
                (x, y)
            };
            chart(&area, fig, prep, x.0..x.1, y.0..y.1, (x, y))
        }
        (Scale::Linear, Scale::Log10) => {
            chart(&area, fig, prep, x.0..x.1, (y.0..y.1).log_scale(), (x, y))
        }
        (Scale::Log10, Scale::Linear) => {
            chart(&area, fig, prep, (x.0..x.1).log_scale(), y.0..y.1, (x, y))
        }
        (Scale::Log10, Scale::Log10) => chart(
            &area,
            fig,
            prep,
            (x.0..x.1).log_scale(),
            (y.0..y.1).log_scale(),
            (x, y),
        ),
    }
}

fn builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA);
    b
}

/// The plotting area's size in pixels, inside the label areas (they have fixed sizes, so
/// this does not depend on the ranges). Draws nothing.
fn plot_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> (u32, u32) {
    match builder(area).build_cartesian_2d(0.0..1.0, 0.0..1.0) {
        Ok(c) => c.plotting_area().dim_in_pixel(),
        Err(_) => area.dim_in_pixel(),
    }
}

/// A point in pixels, relative to an element's anchor.
type Px = (i32, i32);

/// A marker's outline, in pixels around its point, by shape index.
fn marker_shape(k: usize) -> Vec<Px> {
    match k % 4 {
        0 => (0..16)
            .map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 16.0;
                (
                    (4.5 * t.cos()).round() as i32,
                    (4.5 * t.sin()).round() as i32,
                )
            })
            .collect(),
        1 => vec![(-4, -4), (4, -4), (4, 4), (-4, 4)],
        2 => vec![(0, -6), (5, 3), (-5, 3)],
        _ => vec![(0, -6), (6, 0), (0, 6), (-6, 0)],
    }
}

/// The legend corner with fewest points near it (upper right first on ties).
fn legend_corner(fig: &Figure, prep: &Prepared) -> SeriesLabelPosition {
    let norm = |v: f64, r: (f64, f64), s: Scale| match s {
        Scale::Linear => (v - r.0) / (r.1 - r.0),
        Scale::Log10 => (v.log10() - r.0.log10()) / (r.1.log10() - r.0.log10()),
    };
    let mut count = [0usize; 4]; // UR, UL, LR, LL
    for &(x, y) in prep.series.iter().flatten() {
        let (u, v) = (norm(x, prep.x, fig.x_scale), norm(y, prep.y, fig.y_scale));
        let (right, left, up, down) = (u > 0.55, u < 0.45, v > 0.55, v < 0.45);
        count[0] += (right && up) as usize;
        count[1] += (left && up) as usize;
        count[2] += (right && down) as usize;
        count[3] += (left && down) as usize;
    }
    let best = (0..4).min_by_key(|&i| (count[i], i)).unwrap_or(0);
    [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ][best]
        .clone()
}

fn chart<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
    prep: &Prepared,
    x_spec: X,
    y_spec: Y,
    ranges: ((f64, f64), (f64, f64)),
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut chart = builder(area)
        .build_cartesian_2d(x_spec, y_spec)
        .map_err(e)?;
    let ((x0, x1), (y0, y1)) = ranges;
    let label = |scale: Scale, span: f64| {
        move |v: &f64| match scale {
            Scale::Log10 => log_label(*v),
            Scale::Linear => linear_label(*v, span),
        }
    };
    let x_fmt = label(fig.x_scale, x1 - x0);
    let y_fmt = label(fig.y_scale, y1 - y0);
    chart
        .configure_mesh()
        .x_desc(fig.x_label.as_str())
        .y_desc(fig.y_label.as_str())
        .axis_desc_style(text(AXIS_DESC_SIZE))
        .label_style(text(TICK_SIZE))
        .x_labels(if fig.x_scale == Scale::Log10 { 8 } else { 10 })
        .y_labels(if fig.y_scale == Scale::Log10 { 8 } else { 10 })
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .max_light_lines(
            if fig.x_scale == Scale::Linear && fig.y_scale == Scale::Linear {
                4
            } else {
                10
            },
        )
        .bold_line_style(RGBColor(210, 210, 210))
        .light_line_style(RGBColor(238, 238, 238))
        .axis_style(BLACK)
        .draw()
        .map_err(e)?;

    for (k, (series, points)) in fig.series.iter().zip(&prep.series).enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let line = ShapeStyle::from(color).stroke_width(STROKE);
        let marker = marker_shape(k);
        let name = if points.is_empty() {
            format!("{} (no data)", series.name)
        } else {
            series.name.clone()
        };
        let with_line = !matches!(series.style, SeriesStyle::Markers);
        let with_markers = matches!(
            series.style,
            SeriesStyle::Markers | SeriesStyle::LineAndMarkers
        );
        let dashed = series.style == SeriesStyle::DashedLine;

        if with_line && !dashed {
            chart
                .draw_series(LineSeries::new(points.iter().copied(), line))
                .map_err(e)?;
        }
        if dashed {
            chart
                .draw_series(DashedLineSeries::new(points.iter().copied(), 9, 6, line))
                .map_err(e)?;
        }
        let shape = marker.clone();
        let anno = chart
            .draw_series(
                points
                    .iter()
                    .filter(|_| with_markers)
                    .map(|&p| EmptyElement::at(p) + Polygon::new(shape.clone(), color.filled())),
            )
            .map_err(e)?;
        // The legend icon: a line (dashed: two pieces) and the marker, in pixels.
        let (seg1, seg2): (Vec<Px>, Vec<Px>) = match series.style {
            SeriesStyle::Markers => (vec![], vec![]),
            SeriesStyle::DashedLine => (vec![(-14, 0), (-4, 0)], vec![(4, 0), (14, 0)]),
            _ => (vec![(-14, 0), (0, 0)], vec![(0, 0), (14, 0)]),
        };
        let icon = if with_markers { marker } else { vec![(0, 0)] };
        anno.label(name).legend(move |(x, y)| {
            EmptyElement::at((x + 6, y))
                + PathElement::new(seg1.clone(), line)
                + PathElement::new(seg2.clone(), line)
                + Polygon::new(icon.clone(), color.filled())
        });
    }

    if !fig.series.is_empty() {
        chart
            .configure_series_labels()
            .position(legend_corner(fig, prep))
            .margin(12)
            .legend_area_size(36)
            .label_font(text(LEGEND_SIZE))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
