//! The data model: a [`Figure`] of [`Series`], its scales, colours and styles.

#[allow(unused_imports)]
use crate::*;

/// Size of a figure unless told otherwise, in pixels.
pub const DEFAULT_WIDTH: u32 = 900;
/// Size of a figure unless told otherwise, in pixels.
pub const DEFAULT_HEIGHT: u32 = 650;

/// A colour by its red, green and blue components (sRGB, 0 to 255): the crate's own type,
/// so that its users need no plotters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

// Drawing takes it wherever plotters takes a colour.
impl Color for Rgb {
    fn to_backend_color(&self) -> plotters_backend::BackendColor {
        plotters_backend::BackendColor {
            alpha: 1.0,
            rgb: (self.0, self.1, self.2),
        }
    }
}

/// The series colours, by index (matplotlib's "tab10": distinct, and readable in print).
pub const PALETTE: [Rgb; 10] = [
    Rgb(31, 119, 180),
    Rgb(255, 127, 14),
    Rgb(44, 160, 44),
    Rgb(214, 39, 40),
    Rgb(148, 103, 189),
    Rgb(140, 86, 75),
    Rgb(227, 119, 194),
    Rgb(127, 127, 127),
    Rgb(188, 189, 34),
    Rgb(23, 190, 207),
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
pub const NO_VALUE_COLOR: Rgb = Rgb(170, 170, 170);

/// Anchors of matplotlib's "viridis" at 0, 1/9, ..., 1 (perceptually uniform, lightness
/// increasing, readable in grey and by colour-blind readers).
pub(crate) const VIRIDIS: [Rgb; 10] = [
    Rgb(0x44, 0x01, 0x54),
    Rgb(0x48, 0x28, 0x78),
    Rgb(0x3e, 0x4a, 0x89),
    Rgb(0x31, 0x68, 0x8e),
    Rgb(0x26, 0x82, 0x8e),
    Rgb(0x1f, 0x9e, 0x89),
    Rgb(0x35, 0xb7, 0x79),
    Rgb(0x6d, 0xcd, 0x59),
    Rgb(0xb4, 0xde, 0x2c),
    Rgb(0xfd, 0xe7, 0x25),
];

/// The colour of `x` on the viridis colormap: dark purple at 0, yellow at 1. `x` is clamped
/// to [0, 1]; NaN gives the low end.
pub fn colormap(x: f64) -> Rgb {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = x * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: u8, q: u8| (p as f64 + f * (q as f64 - p as f64)).round() as u8;
    Rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
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
    pub color: Option<Rgb>,
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
    pub fn color(mut self, color: Rgb) -> Self {
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
