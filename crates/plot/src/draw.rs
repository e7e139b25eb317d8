//! Drawing with plotters: the canvas, charts, curves (solid, dashed, shaded, markers),
//! legends, notes and colour bars.

#[allow(unused_imports)]
use crate::*;

pub(crate) const MARGIN: u32 = 15;
pub(crate) const X_LABEL_AREA: u32 = 60;
pub(crate) const Y_LABEL_AREA: u32 = 95;
pub(crate) const TITLE_SIZE: f64 = 26.0;
pub(crate) const PANELS_TITLE_SIZE: f64 = 30.0;
pub(crate) const AXIS_DESC_SIZE: f64 = 20.0;
pub(crate) const TICK_SIZE: f64 = 16.0;
pub(crate) const COLORBAR_TICK_SIZE: f64 = 14.0;
pub(crate) const LEGEND_SIZE: f64 = 16.0;
/// The legend box's distance from the plot's corner, and the width of its icon column (px).
pub(crate) const LEGEND_MARGIN: f64 = 12.0;
pub(crate) const LEGEND_AREA: f64 = 36.0;
pub(crate) const NOTE_SIZE: f64 = 16.0;
pub(crate) const STROKE: u32 = 2;
/// The widest stroke drawn, in pixels (wider requests are clamped).
pub const MAX_STROKE: u32 = 64;
/// Width in pixels of the strip at the right of a figure that holds its colour bar.
pub const COLORBAR_AREA: u32 = 100;

pub(crate) fn text(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

/// The smallest size a title is shrunk to (px); a longer title is clipped at both ends.
pub(crate) const MIN_TITLE_SIZE: f64 = 12.0;

/// `size`, or smaller so that `title` fits the width of `area` less a margin on each side
/// (plotters centres a title and clips what overhangs the canvas).
pub(crate) fn title_size<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    size: f64,
) -> f64 {
    let room = f64::from(area.dim_in_pixel().0.saturating_sub(2 * MARGIN));
    match area.estimate_text_size(title, &text(size)) {
        Ok((w, _)) if f64::from(w) > room && w > 0 => {
            (size * room / f64::from(w)).floor().max(MIN_TITLE_SIZE)
        }
        _ => size,
    }
}

/// Draw the whole canvas on `root`: the overall title, then each panel in its cell.
pub(crate) fn draw_canvas<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    canvas: &Canvas,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    if !canvas.title.is_empty() {
        let size = title_size(root, canvas.title, PANELS_TITLE_SIZE);
        let style = text(size).pos(Pos::new(HPos::Center, VPos::Center));
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
pub(crate) fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    prep: &Prepared,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let area = if fig.title.is_empty() {
        root.clone()
    } else {
        let size = title_size(root, &fig.title, TITLE_SIZE);
        root.titled(&fig.title, text(size)).map_err(e)?
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

pub(crate) fn builder<'a, 'b, DB: DrawingBackend>(
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
pub(crate) fn plot_pixels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
) -> (Range<i32>, Range<i32>) {
    match builder(area).build_cartesian_2d(0.0..1.0, 0.0..1.0) {
        Ok(c) => c.plotting_area().get_pixel_range(),
        Err(_) => area.get_pixel_range(),
    }
}

/// The plotting area's size in pixels.
pub(crate) fn plot_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> (u32, u32) {
    let (x, y) = plot_pixels(area);
    let len = |r: Range<i32>| (r.end - r.start).max(0) as u32;
    (len(x), len(y))
}

/// The colour bar in its strip `bar`: the colormap from the bottom (`range.0`) to the top
/// (`range.1`) of the plot (`plot_y`, backend pixels), ticks, and the label read upwards.
pub(crate) fn draw_color_bar<DB: DrawingBackend>(
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
pub(crate) type Px = (i32, i32);

/// A marker's outline, in pixels around its point, by shape index.
pub(crate) fn marker_shape(k: usize) -> Vec<Px> {
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
pub(crate) fn legend_corner(
    fig: &Figure,
    prep: &Prepared,
    area_px: (u32, u32),
) -> SeriesLabelPosition {
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

/// Draw a polyline, solid or dashed (9 px dashes, 6 px gaps).
pub(crate) fn draw_path<DB, CT>(
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
pub(crate) const SHADE_LEVELS: f64 = 127.0;

/// The colour of a segment from the mean of its end values, on [`SHADE_LEVELS`] steps.
pub(crate) fn segment_color(a: f64, b: f64, shade: (f64, f64)) -> Rgb {
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
pub(crate) fn draw_shaded<DB, CT>(
    chart: &mut ChartContext<'_, DB, CT>,
    view: &View,
    points: &[(f64, f64)],
    values: &[f64],
    shade: (f64, f64),
    (width, dashed): (u32, bool),
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
pub(crate) fn draw_curve<'a, DB, CT>(
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
            Some(v) => draw_shaded(chart, view, &curve.points, v, shade, (width, dashed))?,
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
pub(crate) fn draw_notes<DB: DrawingBackend>(
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

pub(crate) fn chart<DB, X, Y>(
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
        .bold_line_style(Rgb(210, 210, 210))
        .light_line_style(Rgb(238, 238, 238))
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
            .border_style(Rgb(160, 160, 160))
            .draw()
            .map_err(e)?;
    }
    Ok(())
}
