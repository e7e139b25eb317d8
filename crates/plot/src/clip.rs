//! Clipping lines to the plotting area, on the axes' own scale (log10 on log axes).

#[allow(unused_imports)]
use crate::*;

/// The visible window of a chart, for clipping lines to it: plotters draws whatever it is
/// given, also outside the plotting area. Clipping is done on the axes' own scale (log10 on
/// log axes), where lines are straight.
#[derive(Clone, Copy)]
pub(crate) struct View {
    pub(crate) x: (f64, f64),
    pub(crate) y: (f64, f64),
    pub(crate) scales: (Scale, Scale),
}

/// The part of a segment inside a [`View`]; `cut_*` tells whether an end was moved.
pub(crate) struct Clipped {
    pub(crate) a: (f64, f64),
    pub(crate) b: (f64, f64),
    pub(crate) cut_a: bool,
    pub(crate) cut_b: bool,
}

pub(crate) fn to_axis(v: f64, s: Scale) -> f64 {
    match s {
        Scale::Linear => v,
        Scale::Log10 => v.log10(),
    }
}

pub(crate) fn from_axis(v: f64, s: Scale) -> f64 {
    match s {
        Scale::Linear => v,
        Scale::Log10 => 10f64.powf(v),
    }
}

impl View {
    pub(crate) fn axis(&self, p: (f64, f64)) -> (f64, f64) {
        (to_axis(p.0, self.scales.0), to_axis(p.1, self.scales.1))
    }

    pub(crate) fn corners(&self) -> ((f64, f64), (f64, f64)) {
        (
            self.axis((self.x.0, self.y.0)),
            self.axis((self.x.1, self.y.1)),
        )
    }

    pub(crate) fn contains(&self, p: (f64, f64)) -> bool {
        let ((x0, y0), (x1, y1)) = self.corners();
        let (u, v) = self.axis(p);
        (x0..=x1).contains(&u) && (y0..=y1).contains(&v)
    }

    /// Liang–Barsky clipping of the segment p→q. Ends inside are returned unchanged.
    pub(crate) fn clip(&self, p: (f64, f64), q: (f64, f64)) -> Option<Clipped> {
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
pub(crate) fn visible_runs(view: &View, points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    visible_runs_by(view, points, |_| ())
        .into_iter()
        .map(|(_, run)| run)
        .collect()
}

/// The visible pieces of a polyline, also split where `key(i)` of segment i changes; each
/// piece with its key and at least two points long.
pub(crate) fn visible_runs_by<K: PartialEq + Copy>(
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
