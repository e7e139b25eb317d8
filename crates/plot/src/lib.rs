//! Figures as PNG and SVG, drawn with `plotters` (no Python), knowing nothing of eyes:
//! eyeshell draws its convergence studies, work-precision diagrams and the paper's figures with it.
//!
//! A [`Figure`] holds [`Series`] of points; [`write()`] draws it to `<stem>.png` and
//! `<stem>.svg`, and [`write_panels`] draws several figures as the panels of one image.
//! Colours come from a fixed palette ([`PALETTE`]) and marker shapes from a fixed cycle,
//! both by the series' index, so a figure looks the same on every run. A series may instead
//! be shaded point by point through [`colormap`] (viridis), against the figure's
//! [`ColorScale`], which is then shown as a colour bar.
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

use std::ops::Range;

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontTransform;

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

/// Colour of a shaded segment whose value is not finite.
pub const NO_VALUE_COLOR: RGBColor = RGBColor(170, 170, 170);

/// Anchors of matplotlib's "viridis" at 0, 1/9, ..., 1 (perceptually uniform, lightness
/// increasing, readable in grey and by colour-blind readers).
const VIRIDIS: [RGBColor; 10] = [
    RGBColor(0x44, 0x01, 0x54),
    RGBColor(0x48, 0x28, 0x78),
    RGBColor(0x3e, 0x4a, 0x89),
    RGBColor(0x31, 0x68, 0x8e),
    RGBColor(0x26, 0x82, 0x8e),
    RGBColor(0x1f, 0x9e, 0x89),
    RGBColor(0x35, 0xb7, 0x79),
    RGBColor(0x6d, 0xcd, 0x59),
    RGBColor(0xb4, 0xde, 0x2c),
    RGBColor(0xfd, 0xe7, 0x25),
];

/// The colour of `x` on the viridis colormap: dark purple at 0, yellow at 1. `x` is clamped
/// to [0, 1]; NaN gives the low end.
pub fn colormap(x: f64) -> RGBColor {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = x * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + f * (q as f64 - p as f64)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// One curve: a name for the legend, its points and how to draw them.
///
/// The optional fields default to the palette colour by index, a 2 px stroke, one colour
/// for the whole curve, and an entry in the legend.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: SeriesStyle,
    /// Overrides the palette colour (lines, markers and legend icon).
    pub color: Option<RGBColor>,
    /// Stroke width of the line in pixels (default 2; clamped to 1..=[`MAX_STROKE`]).
    pub width: Option<u32>,
    /// One value per point: the line is coloured segment by segment through [`colormap`],
    /// at the mean of the segment's two end values, scaled by the figure's colour scale
    /// (markers by their own value). A non-finite or missing value gives
    /// [`NO_VALUE_COLOR`]. Overrides `color` for lines and markers.
    pub values: Option<Vec<f64>>,
    /// Listed in the legend (default true).
    pub legend: bool,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            name: String::new(),
            points: Vec::new(),
            style: SeriesStyle::default(),
            color: None,
            width: None,
            values: None,
            legend: true,
        }
    }
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, style: SeriesStyle) -> Self {
        Series {
            name: name.into(),
            points,
            style,
            ..Series::default()
        }
    }

    /// Builder: draw in this colour instead of the palette's.
    pub fn color(mut self, color: RGBColor) -> Self {
        self.color = Some(color);
        self
    }

    /// Builder: the line's stroke width in pixels.
    pub fn width(mut self, px: u32) -> Self {
        self.width = Some(px);
        self
    }

    /// Builder: shade the curve by one value per point (see [`Series::values`]).
    pub fn shaded(mut self, values: Vec<f64>) -> Self {
        self.values = Some(values);
        self
    }

    /// Builder: keep this series out of the legend (one of a family of curves).
    pub fn no_legend(mut self) -> Self {
        self.legend = false;
        self
    }
}

/// The values of shaded series map linearly from `min` (low end of [`colormap`]) to `max`
/// (high end), clamped; `min == max` maps everything to the low end. Shown as a vertical
/// colour bar titled `label` at the right of the plot.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorScale {
    pub label: String,
    pub min: f64,
    pub max: f64,
}

/// A figure: title, axes and series. `Figure::default()` is 900×650 with linear axes, a
/// legend, automatic ranges, no colour scale and no notes.
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
    /// The scale of shaded series, drawn as a colour bar (a strip of [`COLORBAR_AREA`]
    /// pixels at the right). Without it shaded series span their own finite values and no
    /// bar is drawn.
    pub color_scale: Option<ColorScale>,
    /// Draw the legend box (of the series that want to be listed).
    pub legend: bool,
    /// The x range shown instead of one fitted to the data; what lies outside is clipped.
    /// Ignored when not finite (or, on a log axis, not positive); the ends may come in
    /// either order, and equal ends get a margin. Widened by `aspect_equal`.
    pub x_range: Option<(f64, f64)>,
    /// As `x_range`, for y.
    pub y_range: Option<(f64, f64)>,
    /// Lines of small text in the top-left corner of the plotting area ("t = 0.1").
    pub notes: Vec<String>,
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
            color_scale: None,
            legend: true,
            x_range: None,
            y_range: None,
            notes: Vec::new(),
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

    /// Builder: the colour scale of shaded series, and its colour bar.
    pub fn color_scale(mut self, label: impl Into<String>, min: f64, max: f64) -> Self {
        self.color_scale = Some(ColorScale {
            label: label.into(),
            min,
            max,
        });
        self
    }

    /// Builder: no legend box.
    pub fn no_legend(mut self) -> Self {
        self.legend = false;
        self
    }

    /// Builder: show x from `a` to `b`.
    pub fn x_range(mut self, a: f64, b: f64) -> Self {
        self.x_range = Some((a, b));
        self
    }

    /// Builder: show y from `a` to `b`.
    pub fn y_range(mut self, a: f64, b: f64) -> Self {
        self.y_range = Some((a, b));
        self
    }

    /// Builder: add a line of text in the top-left corner of the plot.
    pub fn note(mut self, text: impl Into<String>) -> Self {
        self.notes.push(text.into());
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
/// the data), unless the figure sets them. Missing parent directories are created. Each
/// file is written under a temporary name in its directory and renamed into place, so no
/// half-written figure is left on error. Errors come back as [`PlotError`] naming the path.
pub fn write(fig: &Figure, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    check_stem(stem)?;
    check_size(stem, "figure", fig.width as u64, fig.height as u64)?;
    check_figure(stem, fig, "")?;
    let canvas = Canvas {
        size: (fig.width, fig.height),
        title: "",
        cells: vec![Cell::new(fig, (0, 0), (fig.width, fig.height))],
    };
    render(&canvas, stem)
}

/// Height in pixels of the band holding the overall title of [`write_panels`] (none when
/// the title is empty).
pub const PANELS_TITLE_BAND: u32 = 50;

/// Write several figures as the panels of one image, `<stem>.png` and `<stem>.svg`.
///
/// The panels fill a grid row by row, `columns` to a row and `ceil(n / columns)` rows, each
/// drawn in a `panel_width`×`panel_height` cell exactly as [`write()`] would draw that figure
/// at that size (the figures' own `width` and `height` are not used). A non-empty `title`
/// goes in a band of [`PANELS_TITLE_BAND`] pixels on top, so the image is
/// `columns * panel_width` by `rows * panel_height` (+ the band) pixels. Unused cells of the
/// last row stay white. Errors, without writing anything, when there is no panel,
/// `columns` is 0, a panel or the whole image is outside 100..=20000 pixels a side, or a
/// figure is invalid for [`write()`]; otherwise as [`write()`].
pub fn write_panels(
    panels: &[Figure],
    columns: usize,
    title: &str,
    panel_width: u32,
    panel_height: u32,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), PlotError> {
    check_stem(stem)?;
    if panels.is_empty() {
        return Err(invalid(stem, "no panels to draw".to_string()));
    }
    if columns == 0 {
        return Err(invalid(
            stem,
            "a grid of panels needs at least one column".to_string(),
        ));
    }
    check_size(stem, "panel", panel_width as u64, panel_height as u64)?;
    let rows = panels.len().div_ceil(columns);
    let band = if title.is_empty() {
        0
    } else {
        PANELS_TITLE_BAND
    };
    let total = |n: usize, px: u32, extra: u32| {
        (n as u64)
            .checked_mul(px as u64)
            .and_then(|v| v.checked_add(extra as u64))
            .unwrap_or(u64::MAX)
    };
    let (w, h) = (
        total(columns, panel_width, 0),
        total(rows, panel_height, band),
    );
    check_size(stem, "image", w, h)?;
    for (k, fig) in panels.iter().enumerate() {
        check_figure(stem, fig, &format!("panel {}: ", k + 1))?;
    }
    // Fits in i32: checked above to be at most 20000.
    let cells = panels
        .iter()
        .enumerate()
        .map(|(k, fig)| {
            let (r, c) = ((k / columns) as u32, (k % columns) as u32);
            let at = (c * panel_width, band + r * panel_height);
            Cell::new(fig, (at.0 as i32, at.1 as i32), (panel_width, panel_height))
        })
        .collect();
    let canvas = Canvas {
        size: (w as u32, h as u32),
        title,
        cells,
    };
    render(&canvas, stem)
}

fn invalid(stem: &Path, reason: String) -> PlotError {
    PlotError::Invalid {
        path: stem.to_path_buf(),
        reason,
    }
}

fn check_stem(stem: &Path) -> Result<(), PlotError> {
    match stem.file_name() {
        Some(_) => Ok(()),
        None => Err(invalid(
            stem,
            "the figure path has no file name".to_string(),
        )),
    }
}

/// Both sides within 100..=20000 pixels (plotters needs room for the axes; the PNG buffer
/// must fit in memory).
fn check_size(stem: &Path, what: &str, w: u64, h: u64) -> Result<(), PlotError> {
    let ok = |v: u64| (100..=20_000).contains(&v);
    if ok(w) && ok(h) {
        return Ok(());
    }
    let show = |v: u64| {
        if v == u64::MAX {
            "(too large)".to_string()
        } else {
            v.to_string()
        }
    };
    Err(invalid(
        stem,
        format!(
            "{what} size {}x{} is outside 100..=20000 pixels",
            show(w),
            show(h)
        ),
    ))
}

fn check_figure(stem: &Path, fig: &Figure, prefix: &str) -> Result<(), PlotError> {
    if fig.aspect_equal && (fig.x_scale != Scale::Linear || fig.y_scale != Scale::Linear) {
        return Err(invalid(
            stem,
            format!("{prefix}an equal aspect ratio needs both axes linear"),
        ));
    }
    Ok(())
}

/// One figure placed on a canvas: its top-left corner and its size, in pixels.
struct Cell<'a> {
    fig: std::borrow::Cow<'a, Figure>,
    prep: Prepared,
    at: (i32, i32),
    size: (u32, u32),
}

impl<'a> Cell<'a> {
    fn new(fig: &'a Figure, at: (i32, i32), size: (u32, u32)) -> Self {
        let fig = offset_axes(fig);
        let prep = Prepared::new(&fig);
        Cell {
            fig,
            prep,
            at,
            size,
        }
    }
}

/// Everything one image shows: its size, an overall title (may be empty) and the panels.
struct Canvas<'a> {
    size: (u32, u32),
    title: &'a str,
    cells: Vec<Cell<'a>>,
}

/// Draw the canvas as PNG and SVG in memory, then write both files atomically.
fn render(canvas: &Canvas, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    let png_path = with_suffix(stem, ".png");
    let svg_path = with_suffix(stem, ".svg");
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
    let (w, h) = canvas.size;
    let drawn = |path: &Path| {
        let path = path.to_path_buf();
        move |message: String| PlotError::Draw { path, message }
    };

    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn(&png_path))?;
        root.present()
            .map_err(|e| drawn(&png_path)(e.to_string()))?;
    }
    let png_bytes = encode_png(&rgb, w, h).map_err(|e| PlotError::Io {
        path: png_path.clone(),
        source: e,
    })?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn(&svg_path))?;
        root.present()
            .map_err(|e| drawn(&svg_path)(e.to_string()))?;
    }
    write_both(stem, (&png_path, &png_bytes), (&svg_path, svg.as_bytes()))?;
    Ok((png_path, svg_path))
}

/// Write the two files: both temporaries first, then both renames, so that an error
/// leaves neither half-written. Creates missing parent directories.
///
/// eyeshell's atomic writer is `eyeshell::rundir::atomic`; this crate depends on nothing of
/// eyeshell (the arrow is cli → plot), so it keeps this one small write of a figure's pair
/// of files, and its [`write()`] / [`write_panels`] keep taking a path.
fn write_both(stem: &Path, png: (&Path, &[u8]), svg: (&Path, &[u8])) -> Result<(), PlotError> {
    if let Some(parent) = stem.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).map_err(|e| PlotError::Io {
            path: parent.to_path_buf(),
            source: e,
        })?;
    }
    let png_tmp = write_temp(png.0, png.1)?;
    let svg_tmp = match write_temp(svg.0, svg.1) {
        Ok(t) => t,
        Err(e) => {
            let _ = fs::remove_file(&png_tmp);
            return Err(e);
        }
    };
    for (tmp, path) in [(&png_tmp, png.0), (&svg_tmp, svg.0)] {
        if let Err(e) = fs::rename(tmp, path) {
            let _ = fs::remove_file(&png_tmp);
            let _ = fs::remove_file(&svg_tmp);
            return Err(PlotError::Io {
                path: path.to_path_buf(),
                source: e,
            });
        }
    }
    Ok(())
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

/// A series' points after dropping those the axes cannot show, with their values when the
/// series is shaded (missing ones NaN).
struct Curve {
    points: Vec<(f64, f64)>,
    values: Option<Vec<f64>>,
}

/// The figure's curves, the axis ranges and the range of values the colormap spans.
struct Prepared {
    curves: Vec<Curve>,
    x: (f64, f64),
    y: (f64, f64),
    shade: (f64, f64),
}

impl Prepared {
    fn new(fig: &Figure) -> Self {
        let keep = |v: f64, s: Scale| v.is_finite() && (s == Scale::Linear || v > 0.0);
        let curves: Vec<Curve> = fig
            .series
            .iter()
            .map(|s| {
                let value = |i: usize| {
                    let v = s.values.as_ref()?;
                    Some(v.get(i).copied().unwrap_or(f64::NAN))
                };
                let kept = s
                    .points
                    .iter()
                    .enumerate()
                    .filter(|(_, &(x, y))| keep(x, fig.x_scale) && keep(y, fig.y_scale));
                let (points, values): (Vec<_>, Vec<_>) = kept.map(|(i, &p)| (p, value(i))).unzip();
                let values = s
                    .values
                    .as_ref()
                    .map(|_| values.into_iter().flatten().collect());
                Curve { points, values }
            })
            .collect();
        let all = || curves.iter().flat_map(|c| c.points.iter());
        let x = explicit_range(fig.x_range, fig.x_scale)
            .unwrap_or_else(|| axis_range(all().map(|p| p.0), fig.x_scale));
        let y = explicit_range(fig.y_range, fig.y_scale)
            .unwrap_or_else(|| axis_range(all().map(|p| p.1), fig.y_scale));
        let shade = shade_range(fig, &curves);
        Prepared {
            curves,
            x,
            y,
            shade,
        }
    }
}

/// The offset that keeps a linear axis readable when its data vary far less than their size
/// (1.0136216901 ± 1e-9): tick labels then show the variation only, and the axis title says
/// what was subtracted. None when the labels can show the values themselves.
fn axis_offset(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let span = hi - lo;
    if !(span > 0.0) || span >= 1e-4 * lo.abs().max(hi.abs()) {
        return None;
    }
    // A round number near the middle, to one digit beyond the span's.
    let unit = 10f64.powf(span.log10().floor() + 1.0);
    Some((0.5 * (lo + hi) / unit).round() * unit)
}

/// `v` with as many decimals as `unit` needs (for the offset in an axis title).
fn offset_text(v: f64, unit_digits: usize) -> String {
    format!("{v:.unit_digits$}")
}

/// The figure with its data shifted by [`axis_offset`] on each linear axis that needs it (and
/// no explicit range), the axis titles saying so; the figure itself when none does.
fn offset_axes(fig: &Figure) -> std::borrow::Cow<'_, Figure> {
    let points = || fig.series.iter().flat_map(|s| s.points.iter());
    let linear_auto =
        |scale: Scale, range: Option<(f64, f64)>| scale == Scale::Linear && range.is_none();
    let dx = if linear_auto(fig.x_scale, fig.x_range) {
        axis_offset(points().map(|p| p.0))
    } else {
        None
    };
    let dy = if linear_auto(fig.y_scale, fig.y_range) && !fig.aspect_equal {
        axis_offset(points().map(|p| p.1))
    } else {
        None
    };
    let dx = dx.filter(|_| !fig.aspect_equal);
    if dx.is_none() && dy.is_none() {
        return std::borrow::Cow::Borrowed(fig);
    }
    let mut out = fig.clone();
    let title = |label: &str, offset: f64, values: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let digits = (-(hi - lo).log10().floor() + 1.0).clamp(0.0, 17.0) as usize;
        let sign = if offset < 0.0 { "+" } else { "−" };
        format!("{label} {sign} {}", offset_text(offset.abs(), digits))
    };
    if let Some(d) = dx {
        out.x_label = title(
            &fig.x_label,
            d,
            &mut points().map(|p| p.0).filter(|v| v.is_finite()),
        );
    }
    if let Some(d) = dy {
        out.y_label = title(
            &fig.y_label,
            d,
            &mut points().map(|p| p.1).filter(|v| v.is_finite()),
        );
    }
    for s in &mut out.series {
        for p in &mut s.points {
            p.0 -= dx.unwrap_or(0.0);
            p.1 -= dy.unwrap_or(0.0);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A range the figure sets, made usable: ordered, finite, positive on a log axis, and not
/// empty. None when it cannot be (the data's range is used instead).
fn explicit_range(r: Option<(f64, f64)>, scale: Scale) -> Option<(f64, f64)> {
    let (a, b) = r?;
    let usable = |v: f64| v.is_finite() && (scale == Scale::Linear || v > 0.0);
    if !usable(a) || !usable(b) {
        return None;
    }
    if a == b {
        return Some(axis_range(std::iter::once(a), scale));
    }
    Some((a.min(b), a.max(b)))
}

/// The values at the two ends of the colormap: the colour scale's when it is finite, else
/// the shaded series' finite values (0..1 when there are none).
fn shade_range(fig: &Figure, curves: &[Curve]) -> (f64, f64) {
    if let Some(cs) = fig.color_scale.as_ref() {
        if cs.min.is_finite() && cs.max.is_finite() {
            return (cs.min, cs.max);
        }
    }
    let values = curves
        .iter()
        .filter_map(|c| c.values.as_ref())
        .flatten()
        .copied()
        .filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if lo <= hi {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// Where `v` falls on the colormap, in [0, 1]: 0 when the range is a single value, NaN
/// when `v` is not finite.
fn normalise(v: f64, (lo, hi): (f64, f64)) -> f64 {
    if !v.is_finite() {
        return f64::NAN;
    }
    // Halves, so that the differences cannot overflow for values near f64::MAX.
    let span = hi / 2.0 - lo / 2.0;
    if span == 0.0 {
        return 0.0;
    }
    ((v / 2.0 - lo / 2.0) / span).clamp(0.0, 1.0)
}

/// The colour of a value against the figure's shade range.
fn shade_color(v: f64, range: (f64, f64)) -> RGBColor {
    let t = normalise(v, range);
    if t.is_nan() {
        NO_VALUE_COLOR
    } else {
        colormap(t)
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
const PANELS_TITLE_SIZE: f64 = 30.0;
const AXIS_DESC_SIZE: f64 = 20.0;
const TICK_SIZE: f64 = 16.0;
const COLORBAR_TICK_SIZE: f64 = 14.0;
const LEGEND_SIZE: f64 = 16.0;
/// The legend box's distance from the plot's corner, and the width of its icon column (px).
const LEGEND_MARGIN: f64 = 12.0;
const LEGEND_AREA: f64 = 36.0;
const NOTE_SIZE: f64 = 16.0;
const STROKE: u32 = 2;
/// The widest stroke drawn, in pixels (wider requests are clamped).
pub const MAX_STROKE: u32 = 64;
/// Width in pixels of the strip at the right of a figure that holds its colour bar.
pub const COLORBAR_AREA: u32 = 100;

fn text(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

/// Draw the whole canvas on `root`: the overall title, then each panel in its cell.
fn draw_canvas<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    canvas: &Canvas,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    if !canvas.title.is_empty() {
        let style = text(PANELS_TITLE_SIZE).pos(Pos::new(HPos::Center, VPos::Center));
        let at = ((canvas.size.0 / 2) as i32, (PANELS_TITLE_BAND / 2) as i32);
        root.draw_text(canvas.title, &style, at).map_err(e)?;
    }
    for cell in &canvas.cells {
        let area = root.clone().shrink(cell.at, cell.size);
        draw(&area, &cell.fig, &cell.prep)?;
    }
    Ok(())
}

/// Draw one figure filling `root`. Errors as text (the caller names the file).
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
    // The colour bar's strip comes off the right before the chart is laid out, so that
    // an equal aspect ratio is computed for the plot that is actually drawn.
    let (area, bar) = match fig.color_scale.as_ref() {
        Some(cs) => {
            let width = area.dim_in_pixel().0;
            let (plot, bar) = area.split_horizontally(width.saturating_sub(COLORBAR_AREA));
            (plot, Some((bar, cs)))
        }
        None => (area, None),
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
    }?;
    if let Some((bar, cs)) = bar {
        draw_color_bar(&bar, &cs.label, prep.shade, plot_pixels(&area).1)?;
    }
    Ok(())
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

/// The plotting area's pixel ranges on the backend, inside the label areas (they have fixed
/// sizes, so this does not depend on the axis ranges). Draws nothing.
fn plot_pixels<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> (Range<i32>, Range<i32>) {
    match builder(area).build_cartesian_2d(0.0..1.0, 0.0..1.0) {
        Ok(c) => c.plotting_area().get_pixel_range(),
        Err(_) => area.get_pixel_range(),
    }
}

/// The plotting area's size in pixels.
fn plot_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> (u32, u32) {
    let (x, y) = plot_pixels(area);
    let len = |r: Range<i32>| (r.end - r.start).max(0) as u32;
    (len(x), len(y))
}

/// The colour bar in its strip `bar`: the colormap from the bottom (`range.0`) to the top
/// (`range.1`) of the plot (`plot_y`, backend pixels), ticks, and the label read upwards.
fn draw_color_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    label: &str,
    range: (f64, f64),
    plot_y: Range<i32>,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let base = bar.get_base_pixel().1;
    let (top, bottom) = (plot_y.start - base, plot_y.end - base);
    let height = (bottom - top).max(1);
    let (x0, x1) = (6, 24);
    // Bands of the [`SHADE_LEVELS`] steps the curves are drawn in, from exactly colormap(1)
    // at the top to colormap(0) at the bottom: one element per band in the SVG.
    let rows = (height - 1).max(1);
    let level = |r: i32| (SHADE_LEVELS * (1.0 - r as f64 / (rows - 1).max(1) as f64)).round();
    let mut start = 0;
    for r in 1..=rows {
        if r == rows || level(r) != level(start) {
            let color = colormap(level(start) / SHADE_LEVELS);
            let band = Rectangle::new([(x0, top + 1 + start), (x1, top + 1 + r)], color.filled());
            bar.draw(&band).map_err(e)?;
            start = r;
        }
    }
    let outline = Rectangle::new([(x0, top), (x1, top + height)], BLACK.stroke_width(1));
    bar.draw(&outline).map_err(e)?;

    let (lo, hi) = range;
    let span = (hi - lo).abs();
    let ticks: Vec<f64> = if lo == hi {
        vec![0.0]
    } else {
        vec![0.0, 0.25, 0.5, 0.75, 1.0]
    };
    let style = text(COLORBAR_TICK_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    for f in ticks {
        let y = top + height - (f * height as f64).round() as i32;
        let tick = PathElement::new(vec![(x1, y), (x1 + 4, y)], BLACK.stroke_width(1));
        bar.draw(&tick).map_err(e)?;
        // Interpolated so that neither end overflows.
        let v = lo * (1.0 - f) + hi * f;
        bar.draw_text(&linear_label(v, span), &style, (x1 + 7, y))
            .map_err(e)?;
    }
    if !label.is_empty() {
        let style = text(AXIS_DESC_SIZE)
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        let at = (COLORBAR_AREA as i32 - 4, top + height / 2);
        bar.draw_text(label, &style, at).map_err(e)?;
    }
    Ok(())
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

/// The legend corner whose box would cover the least of the curves (upper right first on
/// ties). The box's size is estimated in pixels from the entries and the longest name (as
/// plotters lays it out: `legend_area_size` for the icon, the label font's em for the
/// text); the curves are sampled along their segments, so that a steep stretch drawn
/// between two far-apart points still counts. The upper left is left to the notes when
/// there are any.
fn legend_corner(fig: &Figure, prep: &Prepared, area_px: (u32, u32)) -> SeriesLabelPosition {
    let norm = |v: f64, r: (f64, f64), s: Scale| match s {
        Scale::Linear => (v - r.0) / (r.1 - r.0),
        Scale::Log10 => (v.log10() - r.0.log10()) / (r.1.log10() - r.0.log10()),
    };
    let listed: Vec<&Series> = fig.series.iter().filter(|s| s.legend).collect();
    let chars = listed
        .iter()
        .map(|s| s.name.chars().count())
        .max()
        .unwrap_or(0);
    let (w_px, h_px) = (f64::from(area_px.0.max(1)), f64::from(area_px.1.max(1)));
    let box_w = ((LEGEND_AREA + 16.0 + 0.6 * LEGEND_SIZE * chars as f64) / w_px).min(1.0);
    let box_h = ((1.35 * LEGEND_SIZE * listed.len() as f64 + 16.0) / h_px).min(1.0);
    let (mx, my) = (LEGEND_MARGIN / w_px, LEGEND_MARGIN / h_px);
    // The boxes as (u0, u1, v0, v1) in the unit square, v upwards: UR, UL, LR, LL.
    let boxes = [
        (1.0 - mx - box_w, 1.0 - mx, 1.0 - my - box_h, 1.0 - my),
        (mx, mx + box_w, 1.0 - my - box_h, 1.0 - my),
        (1.0 - mx - box_w, 1.0 - mx, my, my + box_h),
        (mx, mx + box_w, my, my + box_h),
    ];
    let mut count = [0usize; 4];
    let mut tally = |u: f64, v: f64| {
        for (c, b) in count.iter_mut().zip(&boxes) {
            *c += (b.0..=b.1).contains(&u) as usize * (b.2..=b.3).contains(&v) as usize;
        }
    };
    for c in &prep.curves {
        let unit: Vec<(f64, f64)> = c
            .points
            .iter()
            .map(|&(x, y)| (norm(x, prep.x, fig.x_scale), norm(y, prep.y, fig.y_scale)))
            .collect();
        for (i, &(u, v)) in unit.iter().enumerate() {
            tally(u, v);
            // Up to 50 samples inside a long segment (about one per 2 % of the square).
            if let Some(&(u1, v1)) = unit.get(i + 1) {
                let steps = (((u1 - u).abs().max((v1 - v).abs())) / 0.02).min(50.0) as usize;
                for k in 1..steps {
                    let f = k as f64 / steps as f64;
                    tally(u + f * (u1 - u), v + f * (v1 - v));
                }
            }
        }
    }
    let best = (0..4)
        .filter(|&i| i != 1 || fig.notes.is_empty())
        .min_by_key(|&i| (count[i], i))
        .unwrap_or(0);
    [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ][best]
        .clone()
}

/// The visible window of a chart, for clipping lines to it: plotters draws whatever it is
/// given, also outside the plotting area. Clipping is done on the axes' own scale (log10 on
/// log axes), where lines are straight.
#[derive(Clone, Copy)]
struct View {
    x: (f64, f64),
    y: (f64, f64),
    scales: (Scale, Scale),
}

/// The part of a segment inside a [`View`]; `cut_*` tells whether an end was moved.
struct Clipped {
    a: (f64, f64),
    b: (f64, f64),
    cut_a: bool,
    cut_b: bool,
}

fn to_axis(v: f64, s: Scale) -> f64 {
    match s {
        Scale::Linear => v,
        Scale::Log10 => v.log10(),
    }
}

fn from_axis(v: f64, s: Scale) -> f64 {
    match s {
        Scale::Linear => v,
        Scale::Log10 => 10f64.powf(v),
    }
}

impl View {
    fn axis(&self, p: (f64, f64)) -> (f64, f64) {
        (to_axis(p.0, self.scales.0), to_axis(p.1, self.scales.1))
    }

    fn corners(&self) -> ((f64, f64), (f64, f64)) {
        (
            self.axis((self.x.0, self.y.0)),
            self.axis((self.x.1, self.y.1)),
        )
    }

    fn contains(&self, p: (f64, f64)) -> bool {
        let ((x0, y0), (x1, y1)) = self.corners();
        let (u, v) = self.axis(p);
        (x0..=x1).contains(&u) && (y0..=y1).contains(&v)
    }

    /// Liang–Barsky clipping of the segment p→q. Ends inside are returned unchanged.
    fn clip(&self, p: (f64, f64), q: (f64, f64)) -> Option<Clipped> {
        let ((x0, y0), (x1, y1)) = self.corners();
        let (pu, qu) = (self.axis(p), self.axis(q));
        let (dx, dy) = (qu.0 - pu.0, qu.1 - pu.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (d, room) in [
            (-dx, pu.0 - x0),
            (dx, x1 - pu.0),
            (-dy, pu.1 - y0),
            (dy, y1 - pu.1),
        ] {
            if d == 0.0 {
                if room < 0.0 {
                    return None;
                }
                continue;
            }
            let t = room / d;
            if d < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
        // f64::max and min ignore a NaN ratio (infinite / infinite), so t0, t1 stay numbers.
        if t0 > t1 {
            return None;
        }
        let at = |t: f64| {
            (
                from_axis(pu.0 + t * dx, self.scales.0),
                from_axis(pu.1 + t * dy, self.scales.1),
            )
        };
        let (cut_a, cut_b) = (t0 > 0.0, t1 < 1.0);
        Some(Clipped {
            a: if cut_a { at(t0) } else { p },
            b: if cut_b { at(t1) } else { q },
            cut_a,
            cut_b,
        })
    }
}

/// The visible pieces of a polyline, each at least two points long.
fn visible_runs(view: &View, points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    visible_runs_by(view, points, |_| ())
        .into_iter()
        .map(|(_, run)| run)
        .collect()
}

/// The visible pieces of a polyline, also split where `key(i)` of segment i changes; each
/// piece with its key and at least two points long.
fn visible_runs_by<K: PartialEq + Copy>(
    view: &View,
    points: &[(f64, f64)],
    key: impl Fn(usize) -> K,
) -> Vec<(K, Vec<(f64, f64)>)> {
    let mut runs = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut run_key: Option<K> = None;
    let mut flush = |run: &mut Vec<(f64, f64)>, k: Option<K>| {
        if let (true, Some(k)) = (run.len() >= 2, k) {
            runs.push((k, std::mem::take(run)));
        }
        run.clear();
    };
    for (i, w) in points.windows(2).enumerate() {
        let Some(c) = view.clip(w[0], w[1]) else {
            flush(&mut run, run_key);
            continue;
        };
        let k = key(i);
        // A run goes on while the previous segment ended where this one starts, in its key.
        if run.is_empty() || c.cut_a || run_key != Some(k) || run.last() != Some(&c.a) {
            flush(&mut run, run_key);
            run.push(c.a);
            run_key = Some(k);
        }
        run.push(c.b);
        if c.cut_b {
            flush(&mut run, run_key);
        }
    }
    flush(&mut run, run_key);
    runs
}

/// Draw a polyline, solid or dashed (9 px dashes, 6 px gaps).
fn draw_path<DB, CT>(
    chart: &mut ChartContext<'_, DB, CT>,
    points: Vec<(f64, f64)>,
    style: ShapeStyle,
    dashed: bool,
) -> Result<(), String>
where
    DB: DrawingBackend,
    CT: CoordTranslate<From = (f64, f64)>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    if dashed {
        chart
            .draw_series(DashedLineSeries::new(points, 9, 6, style))
            .map_err(e)?;
    } else {
        chart
            .draw_series(std::iter::once(PathElement::new(points, style)))
            .map_err(e)?;
    }
    Ok(())
}

/// Shades are drawn in this many steps of the colour map: fine enough to look continuous,
/// coarse enough that neighbouring segments share a colour and are drawn as one path (an
/// SVG holds one element per run of equal colour, not one per segment).
const SHADE_LEVELS: f64 = 127.0;

/// The colour of a segment from the mean of its end values, on [`SHADE_LEVELS`] steps.
fn segment_color(a: f64, b: f64, shade: (f64, f64)) -> RGBColor {
    // Halves first, so that the mean of two large values does not overflow.
    let t = normalise(a / 2.0 + b / 2.0, shade);
    if t.is_nan() {
        NO_VALUE_COLOR
    } else {
        colormap((t * SHADE_LEVELS).round() / SHADE_LEVELS)
    }
}

/// Draw a curve in the colours of its values: consecutive segments of one colour as one
/// path. Thick lines get round caps where the colour changes, or the joins would show gaps.
#[allow(clippy::too_many_arguments)]
fn draw_shaded<DB, CT>(
    chart: &mut ChartContext<'_, DB, CT>,
    view: &View,
    points: &[(f64, f64)],
    values: &[f64],
    shade: (f64, f64),
    width: u32,
    dashed: bool,
) -> Result<(), String>
where
    DB: DrawingBackend,
    CT: CoordTranslate<From = (f64, f64)>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let value = |i: usize| values.get(i).copied().unwrap_or(f64::NAN);
    let color = |i: usize| segment_color(value(i), value(i + 1), shade);
    for (color, run) in visible_runs_by(view, points, color) {
        let ends = [run[0], run[run.len() - 1]];
        draw_path(
            chart,
            run,
            ShapeStyle::from(color).stroke_width(width),
            dashed,
        )?;
        if width >= 3 && !dashed {
            chart
                .draw_series(ends.map(|p| Circle::new(p, width / 2, color.filled())))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// Draw series number `k`: its line, its markers and its legend entry.
fn draw_curve<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    view: &View,
    (k, series, curve): (usize, &Series, &Curve),
    shade: (f64, f64),
    in_legend: bool,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate<From = (f64, f64)>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let color = series.color.unwrap_or(PALETTE[k % PALETTE.len()]);
    let width = series.width.unwrap_or(STROKE).clamp(1, MAX_STROKE);
    let with_line = !matches!(series.style, SeriesStyle::Markers);
    let with_markers = matches!(
        series.style,
        SeriesStyle::Markers | SeriesStyle::LineAndMarkers
    );
    let dashed = series.style == SeriesStyle::DashedLine;
    let values = curve.values.as_deref();

    if with_line {
        match values {
            Some(v) => draw_shaded(chart, view, &curve.points, v, shade, width, dashed)?,
            None => {
                let style = ShapeStyle::from(color).stroke_width(width);
                for run in visible_runs(view, &curve.points) {
                    draw_path(chart, run, style, dashed)?;
                }
            }
        }
    }
    let marker = marker_shape(k);
    let marker_color = |i: usize| match values {
        Some(v) => shade_color(v.get(i).copied().unwrap_or(f64::NAN), shade),
        None => color,
    };
    let shape = marker.clone();
    let anno = chart
        .draw_series(
            curve
                .points
                .iter()
                .enumerate()
                .filter(|&(_, &p)| with_markers && view.contains(p))
                .map(|(i, &p)| {
                    EmptyElement::at(p) + Polygon::new(shape.clone(), marker_color(i).filled())
                }),
        )
        .map_err(e)?;
    if !in_legend {
        return Ok(());
    }
    let name = if curve.points.is_empty() {
        format!("{} (no data)", series.name)
    } else {
        series.name.clone()
    };
    // The legend icon: a line (dashed: two pieces) and the marker, in pixels; a shaded
    // curve shows the middle of the colormap, and a thick line is drawn thinner.
    let icon_color = if values.is_some() {
        colormap(0.5)
    } else {
        color
    };
    let line = ShapeStyle::from(icon_color).stroke_width(width.min(6));
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
            + Polygon::new(icon.clone(), icon_color.filled())
    });
    Ok(())
}

/// The notes, one per line, in the top-left corner of the plotting area `plot`, on a pale
/// background so that curves beneath do not hide them.
fn draw_notes<DB: DrawingBackend>(
    plot: &DrawingArea<DB, Shift>,
    notes: &[String],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let style = text(NOTE_SIZE);
    let line_height = (NOTE_SIZE * 1.35).round() as i32;
    for (i, note) in notes.iter().enumerate() {
        let (x, y) = (10, 8 + i as i32 * line_height);
        let (tw, th) = plot.estimate_text_size(note, &style).map_err(e)?;
        let (tw, th) = (tw.min(1 << 20) as i32, th.min(1 << 20) as i32);
        let back = Rectangle::new(
            [(x - 3, y - 2), (x + tw + 3, y + th + 2)],
            WHITE.mix(0.85).filled(),
        );
        plot.draw(&back).map_err(e)?;
        plot.draw_text(note, &style, (x, y)).map_err(e)?;
    }
    Ok(())
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

    let view = View {
        x: (x0, x1),
        y: (y0, y1),
        scales: (fig.x_scale, fig.y_scale),
    };
    let listed = |s: &Series| fig.legend && s.legend;
    for (k, (series, curve)) in fig.series.iter().zip(&prep.curves).enumerate() {
        draw_curve(
            &mut chart,
            &view,
            (k, series, curve),
            prep.shade,
            listed(series),
        )?;
    }
    if !fig.notes.is_empty() {
        draw_notes(&chart.plotting_area().strip_coord_spec(), &fig.notes)?;
    }
    if fig.series.iter().any(listed) {
        let corner = legend_corner(fig, prep, chart.plotting_area().dim_in_pixel());
        chart
            .configure_series_labels()
            .position(corner)
            .margin(LEGEND_MARGIN as u32)
            .legend_area_size(LEGEND_AREA as u32)
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
    fn luminance(c: RGBColor) -> f64 {
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
        assert_eq!(colormap(0.0), RGBColor(0x44, 0x01, 0x54));
        assert_eq!(colormap(1.0), RGBColor(0xfd, 0xe7, 0x25));
        assert_eq!(colormap(-3.0), colormap(0.0));
        assert_eq!(colormap(7.0), colormap(1.0));
        assert_eq!(colormap(f64::NAN), colormap(0.0));
        assert_eq!(colormap(f64::INFINITY), colormap(1.0));
        // The anchors are hit exactly.
        assert_eq!(colormap(5.0 / 9.0), RGBColor(0x1f, 0x9e, 0x89));
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
        let s = s.color(RED).width(5).shaded(vec![1.0]).no_legend();
        assert_eq!(
            (s.color, s.width, s.values, s.legend),
            (Some(RED), Some(5), Some(vec![1.0]), false)
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
