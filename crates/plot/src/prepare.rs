//! What the axes show: points kept or dropped, axis ranges (with offsets and decades),
//! tick labels, the colour scale's range.

#[allow(unused_imports)]
use crate::*;

/// A series' points after dropping those the axes cannot show, with their values when the
/// series is shaded (missing ones NaN).
pub(crate) struct Curve {
    pub(crate) points: Vec<(f64, f64)>,
    pub(crate) values: Option<Vec<f64>>,
}

/// The figure's curves, the axis ranges and the range of values the colormap spans.
pub(crate) struct Prepared {
    pub(crate) curves: Vec<Curve>,
    pub(crate) x: (f64, f64),
    pub(crate) y: (f64, f64),
    pub(crate) shade: (f64, f64),
}

impl Prepared {
    pub(crate) fn new(fig: &Figure) -> Self {
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
pub(crate) fn axis_offset(values: impl Iterator<Item = f64>) -> Option<f64> {
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
pub(crate) fn offset_text(v: f64, unit_digits: usize) -> String {
    format!("{v:.unit_digits$}")
}

/// The figure with its data shifted by [`axis_offset`] on each linear axis that needs it (and
/// no explicit range), the axis titles saying so; the figure itself when none does.
pub(crate) fn offset_axes(fig: &Figure) -> std::borrow::Cow<'_, Figure> {
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
pub(crate) fn explicit_range(r: Option<(f64, f64)>, scale: Scale) -> Option<(f64, f64)> {
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
pub(crate) fn shade_range(fig: &Figure, curves: &[Curve]) -> (f64, f64) {
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
pub(crate) fn normalise(v: f64, (lo, hi): (f64, f64)) -> f64 {
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
pub(crate) fn shade_color(v: f64, range: (f64, f64)) -> Rgb {
    let t = normalise(v, range);
    if t.is_nan() {
        NO_VALUE_COLOR
    } else {
        colormap(t)
    }
}

/// The range an axis shows: every value with a margin.
pub(crate) fn axis_range(values: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
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
pub(crate) fn equal_aspect(
    x: (f64, f64),
    y: (f64, f64),
    pw: u32,
    ph: u32,
) -> ((f64, f64), (f64, f64)) {
    let (pw, ph) = (pw.max(1) as f64, ph.max(1) as f64);
    let per_px = ((x.1 - x.0) / pw).max((y.1 - y.0) / ph);
    let grow = |r: (f64, f64), px: f64| {
        let (c, half) = ((r.0 + r.1) / 2.0, per_px * px / 2.0);
        (c - half, c + half)
    };
    (grow(x, pw), grow(y, ph))
}

/// A tick label on a log axis: `1e-3`, `2e-3`, ...
pub(crate) fn log_label(v: f64) -> String {
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
pub(crate) fn linear_label(v: f64, span: f64) -> String {
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
