//! The scene's schematic eye: a built-in eye with some of its numbers changed, or a custom
//! eye (`optics.eye = "custom"`), surface by surface (`[[optics.surfaces]]`), and numbers
//! that change over the growth's time (docs/guide/optics.md, "An eye of your own" and
//! "Optics with age").
//!
//! Each `[[optics.surfaces]]` table describes one refracting surface and what follows it:
//! `radius`, `conic`, `aspheric` (the r⁴, r⁶, ... terms), `thickness` to the next surface (the
//! last one's to the retina) and the medium behind it: `index`, or `cauchy = [a, b, c, d]`
//! (n = a + b/λ² + c/λ⁴ + d/λ⁶, λ in µm), or `sellmeier = { b = [..], c = [..] }`. For a
//! built-in eye the tables are overrides, in the eye's surface order: a key given replaces the
//! source's number, a key left out keeps it. `radius`, `conic`, `thickness` and `index` may be
//! tables over the growth's time, `{ t = [..], value = [..] }`, read through a natural cubic
//! spline in t (C² everywhere: beyond the table's ends it continues along its end slopes).

use eyeshell_optics as optics;
use eyeshell_optics::{Dispersion, Medium, MediumKind, OpticalSystem, Surface};

use crate::names::Quantity;
use crate::text::number;

/// The most surfaces a custom eye may have (a schematic eye has four to six).
pub const MAX_SURFACES: usize = 16;
/// The most aspheric terms of a surface (r⁴ to r¹⁸).
pub const MAX_ASPHERIC: usize = 8;
/// The most times of a table over time.
pub const MAX_TABLE_TIMES: usize = 100;
/// Radii (mm) a surface of an eye or an ophthalmic lens may have, in magnitude; a plane is
/// `radius = inf`. Smaller radii are a typo for an eye (a 0.01 mm cornea), larger ones a plane.
pub const RADIUS_RANGE: (f64, f64) = (0.5, 1.0e4);
/// Conic constants: beyond ±100 the conicoid is a cone or a flat disc within a few µm of
/// its vertex.
pub const CONIC_LIMIT: f64 = 100.0;
/// The longest thickness (mm): an eye is at most about 35 mm long.
pub const MAX_THICKNESS: f64 = 100.0;

/// A number of the eye: fixed, or a table over the growth's time.
#[derive(Clone, Debug, PartialEq)]
pub enum EyeValue {
    Fixed(f64),
    /// Values at increasing times (at least two), a natural cubic spline between.
    Table {
        t: Vec<f64>,
        value: Vec<f64>,
    },
}

impl EyeValue {
    /// The value at growth time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match self {
            EyeValue::Fixed(x) => *x,
            EyeValue::Table { t: ts, value } => {
                let w = spline_weights(ts, t);
                w.iter().zip(value).map(|(w, v)| w * v).sum()
            }
        }
    }

    /// The table's times (none for a fixed value).
    pub fn times(&self) -> &[f64] {
        match self {
            EyeValue::Fixed(_) => &[],
            EyeValue::Table { t, .. } => t,
        }
    }

    /// The least and the greatest value over growth times [0, `t_end`] and at the table's
    /// own points, each with its time: `((min, t), (max, t))`. Exact: on each interval the
    /// natural spline is a cubic, extreme at its ends or where its derivative (a quadratic)
    /// vanishes, and beyond the table's ends it is linear, extreme at 0 or `t_end`.
    pub fn extremes(&self, t_end: f64) -> ((f64, f64), (f64, f64)) {
        let mut candidates: Vec<f64> = vec![0.0, t_end.max(0.0)];
        if let EyeValue::Table { t: ts, value } = self {
            candidates.extend_from_slice(ts);
            let h: Vec<f64> = ts.windows(2).map(|p| p[1] - p[0]).collect();
            let s = natural_second_derivatives(ts, &h);
            let m: Vec<f64> = s
                .iter()
                .map(|row| row.iter().zip(value).map(|(w, v)| w * v).sum())
                .collect();
            for (i, &hi) in h.iter().enumerate() {
                // ds/db on the interval, b = (t − tᵢ)/hᵢ: A b² + B b + C.
                let (m0, m1) = (m[i], m[i + 1]);
                let a = hi * hi * (m1 - m0) / 2.0;
                let b = hi * hi * m0;
                let c = (value[i + 1] - value[i]) - hi * hi * (2.0 * m0 + m1) / 6.0;
                let roots = if a.abs() <= 1e-300 {
                    if b != 0.0 {
                        vec![-c / b]
                    } else {
                        vec![]
                    }
                } else {
                    let d = b * b - 4.0 * a * c;
                    if d < 0.0 {
                        vec![]
                    } else {
                        let q = -0.5 * (b + b.signum() * d.sqrt());
                        let mut r = vec![q / a];
                        if q != 0.0 {
                            r.push(c / q);
                        }
                        r
                    }
                };
                candidates.extend(
                    roots
                        .into_iter()
                        .filter(|x| *x > 0.0 && *x < 1.0)
                        .map(|x| ts[i] + x * hi),
                );
            }
        }
        let inside = |t: &f64| *t >= 0.0 && (*t <= t_end || self.times().contains(t));
        let mut lo = (f64::INFINITY, 0.0);
        let mut hi = (f64::NEG_INFINITY, 0.0);
        for t in candidates.into_iter().filter(inside) {
            let x = self.at(t);
            // A NaN is the worst of both.
            if x.is_nan() {
                return ((x, t), (x, t));
            }
            if x < lo.0 {
                lo = (x, t);
            }
            if x > hi.0 {
                hi = (x, t);
            }
        }
        (lo, hi)
    }

    fn values(&self) -> Vec<f64> {
        match self {
            EyeValue::Fixed(x) => vec![*x],
            EyeValue::Table { value, .. } => value.clone(),
        }
    }
}

/// The weights w_k(t) of the natural cubic spline through values at the times `ts`: the
/// spline's value at t is Σ w_k v_k (the spline is linear in its values). Beyond the ends it
/// continues along its end slopes, which the natural ends (zero second derivative) make C².
pub fn spline_weights(ts: &[f64], t: f64) -> Vec<f64> {
    let n = ts.len();
    let mut w = vec![0.0; n];
    if n == 1 {
        w[0] = 1.0;
        return w;
    }
    // The second derivatives M = S v of the natural spline, S (n×n) from the tridiagonal
    // system; only the two rows of the interval holding t are needed, but n is small.
    let h: Vec<f64> = ts.windows(2).map(|p| p[1] - p[0]).collect();
    let s = natural_second_derivatives(ts, &h);
    let i = if t <= ts[0] {
        0
    } else {
        ts.partition_point(|&x| x <= t).saturating_sub(1).min(n - 2)
    };
    let (x0, x1, hi) = (ts[i], ts[i + 1], h[i]);
    if t < ts[0] || t > ts[n - 1] {
        // Linear beyond the end, with the end's slope (the end's M is zero).
        let (end, e) = if t < ts[0] { (0, x0) } else { (n - 1, x1) };
        // Slope at the end: (v1 − v0)/h + h/6 (−(3a² − 1) M0 + (3b² − 1) M1) with a, b the
        // end's barycentric coordinates (a = 1 at x0, b = 1 at x1).
        let (a, b) = if end == 0 { (1.0, 0.0) } else { (0.0, 1.0) };
        let dt = t - e;
        w[i] += a + dt * (-1.0 / hi);
        w[i + 1] += b + dt * (1.0 / hi);
        let c0 = dt * hi / 6.0 * (-(3.0 * a * a - 1.0));
        let c1 = dt * hi / 6.0 * (3.0 * b * b - 1.0);
        for (k, wk) in w.iter_mut().enumerate() {
            *wk += c0 * s[i][k] + c1 * s[i + 1][k];
        }
        return w;
    }
    let (a, b) = ((x1 - t) / hi, (t - x0) / hi);
    w[i] += a;
    w[i + 1] += b;
    let (c0, c1) = (
        hi * hi / 6.0 * (a * a * a - a),
        hi * hi / 6.0 * (b * b * b - b),
    );
    for (k, wk) in w.iter_mut().enumerate() {
        *wk += c0 * s[i][k] + c1 * s[i + 1][k];
    }
    w
}

/// The matrix S with M = S v for the natural cubic spline through (ts, v): row i holds the
/// second derivative at ts[i] as a combination of the values.
fn natural_second_derivatives(ts: &[f64], h: &[f64]) -> Vec<Vec<f64>> {
    let n = ts.len();
    let mut s = vec![vec![0.0; n]; n];
    if n < 3 {
        return s;
    }
    // Interior equations h_{i-1} M_{i-1} + 2(h_{i-1}+h_i) M_i + h_i M_{i+1} = 6 (Δ_i − Δ_{i-1})
    // with M_0 = M_{n-1} = 0, solved for each unit value vector (Thomas algorithm).
    let m = n - 2;
    for k in 0..n {
        let mut d = vec![0.0; m];
        for (j, dj) in d.iter_mut().enumerate() {
            let i = j + 1;
            let v = |q: usize| if q == k { 1.0 } else { 0.0 };
            *dj = 6.0 * ((v(i + 1) - v(i)) / h[i] - (v(i) - v(i - 1)) / h[i - 1]);
        }
        let mut b: Vec<f64> = (0..m).map(|j| 2.0 * (h[j] + h[j + 1])).collect();
        for j in 1..m {
            let f = h[j] / b[j - 1];
            b[j] -= f * h[j];
            d[j] -= f * d[j - 1];
        }
        let mut x = vec![0.0; m];
        x[m - 1] = d[m - 1] / b[m - 1];
        for j in (0..m - 1).rev() {
            x[j] = (d[j] - h[j + 1] * x[j + 1]) / b[j];
        }
        for (row, xj) in s[1..=m].iter_mut().zip(&x) {
            row[k] = *xj;
        }
    }
    s
}

/// The medium behind a surface, as a scene gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum MediumSpec {
    /// One index at every wavelength (may change over time).
    Index(EyeValue),
    /// Cauchy's a, b, c, d (λ in µm), missing terms zero.
    Cauchy(Vec<f64>),
    /// Sellmeier's b and c (λ in µm).
    Sellmeier { b: Vec<f64>, c: Vec<f64> },
}

impl MediumSpec {
    fn dispersion(&self, t: f64) -> Dispersion {
        match self {
            MediumSpec::Index(v) => Dispersion::Constant(v.at(t)),
            MediumSpec::Cauchy(c) => {
                let k = |i: usize| c.get(i).copied().unwrap_or(0.0);
                Dispersion::Cauchy {
                    a: k(0),
                    b: k(1),
                    c: k(2),
                    d: k(3),
                }
            }
            MediumSpec::Sellmeier { b, c } => Dispersion::Sellmeier {
                b: b.clone(),
                c: c.clone(),
            },
        }
    }

    /// The key that gives this medium.
    fn key(&self) -> &'static str {
        match self {
            MediumSpec::Index(_) => "index",
            MediumSpec::Cauchy(_) => "cauchy",
            MediumSpec::Sellmeier { .. } => "sellmeier",
        }
    }
}

/// One `[[optics.surfaces]]` table: every key optional (a built-in eye's surface keeps what
/// is left out; a custom eye's surface needs `radius`, `thickness` and a medium).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceSpec {
    pub radius: Option<EyeValue>,
    pub conic: Option<EyeValue>,
    pub aspheric: Option<Vec<f64>>,
    pub thickness: Option<EyeValue>,
    pub medium: Option<MediumSpec>,
}

/// The keys a surface table takes, in the order they are written.
pub const SURFACE_KEYS: [&str; 7] = [
    "radius",
    "conic",
    "aspheric",
    "thickness",
    "index",
    "cauchy",
    "sellmeier",
];

/// A problem with one key of a surface table: the key (`optics.surfaces[2].radius`), its value
/// as the user wrote it and what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceKeyError {
    pub key: String,
    pub value: String,
    pub problem: String,
}

impl std::fmt::Display for SurfaceKeyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = {} {}", self.key, self.value, self.problem)
    }
}

/// `optics.surfaces[i].name`.
pub fn surface_key(i: usize, name: &str) -> String {
    format!("{}[{i}].{name}", Quantity::Surfaces)
}

impl SurfaceSpec {
    /// Every time any of this surface's tables names.
    pub fn times(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for v in [&self.radius, &self.conic, &self.thickness]
            .into_iter()
            .flatten()
        {
            out.extend_from_slice(v.times());
        }
        if let Some(MediumSpec::Index(v)) = &self.medium {
            out.extend_from_slice(v.times());
        }
        out
    }

    /// The surface with every table's times moved by `by` (a scene's ages onto the model's
    /// t, t = age − time.start, and back).
    pub fn shift_times(&mut self, by: f64) {
        let index = match &mut self.medium {
            Some(MediumSpec::Index(v)) => Some(v),
            _ => None,
        };
        for v in [&mut self.radius, &mut self.conic, &mut self.thickness]
            .into_iter()
            .flatten()
            .chain(index)
        {
            if let EyeValue::Table { t, .. } = v {
                t.iter_mut().for_each(|x| *x += by);
            }
        }
    }

    /// Each key's own range (tables: times and values), naming the key.
    pub fn check(
        &self,
        i: usize,
        wavelengths: &[f64],
        clock: TableClock,
    ) -> Result<(), SurfaceKeyError> {
        let bad = |name: &str, value, problem| surface_key_error(i, name, value, problem);
        let (rlo, rhi) = RADIUS_RANGE;
        if let Some(v) = &self.radius {
            check_value(
                i,
                "radius",
                v,
                &|x| x.is_infinite() || (x.abs() >= rlo && x.abs() <= rhi),
                &format!(
                    "between {rlo} and {} mm in magnitude, or inf for a plane",
                    number(rhi)
                ),
                clock,
            )?;
            if let EyeValue::Table { value, .. } = v {
                if value.iter().any(|x| x.is_infinite())
                    || value.windows(2).any(|w| w[0] * w[1] < 0.0)
                {
                    return Err(bad(
                        "radius",
                        format!("{{ …, value = {} }}", list_text(value)),
                        "must keep one sign and stay finite over time (a surface cannot turn through a plane)".into(),
                    ));
                }
            }
        }
        if let Some(v) = &self.conic {
            check_value(
                i,
                "conic",
                v,
                &|x| x.is_finite() && x.abs() <= CONIC_LIMIT,
                &format!("a finite number between −{CONIC_LIMIT} and {CONIC_LIMIT}"),
                clock,
            )?;
        }
        if let Some(v) = &self.thickness {
            check_value(
                i,
                "thickness",
                v,
                &|x| x > 0.0 && x <= MAX_THICKNESS,
                &format!("positive and at most {MAX_THICKNESS} mm"),
                clock,
            )?;
        }
        if let Some(a) = &self.aspheric {
            if a.is_empty() || a.len() > MAX_ASPHERIC || a.iter().any(|x| !x.is_finite()) {
                return Err(bad(
                    "aspheric",
                    list_text(a),
                    format!("must list 1 to {MAX_ASPHERIC} finite coefficients (of r⁴, r⁶, ...)"),
                ));
            }
        }
        let (nlo, nhi) = optics::INDEX_RANGE;
        match &self.medium {
            Some(MediumSpec::Index(v)) => check_value(
                i,
                "index",
                v,
                &|x| x >= nlo && x <= nhi,
                &format!("a refractive index between {nlo} and {nhi}"),
                clock,
            )?,
            Some(m) => check_medium(i, m, wavelengths)?,
            None => {}
        }
        Ok(())
    }
}

impl SurfaceSpec {
    /// The keys this table gives, in [`SURFACE_KEYS`]' order.
    pub fn given(&self) -> Vec<&'static str> {
        let mut out = Vec::new();
        if self.radius.is_some() {
            out.push("radius");
        }
        if self.conic.is_some() {
            out.push("conic");
        }
        if self.aspheric.is_some() {
            out.push("aspheric");
        }
        if self.thickness.is_some() {
            out.push("thickness");
        }
        if let Some(m) = &self.medium {
            out.push(m.key());
        }
        out
    }

    /// The value of key `name` as messages show it (tables and lists shortened).
    pub fn shown(&self, name: &str, clock: TableClock) -> Option<String> {
        let value = |v: &EyeValue| match v {
            EyeValue::Fixed(x) => number(*x),
            EyeValue::Table { t, value } => clock.table_text(t, value),
        };
        match (name, &self.medium) {
            ("radius", _) => self.radius.as_ref().map(value),
            ("conic", _) => self.conic.as_ref().map(value),
            ("thickness", _) => self.thickness.as_ref().map(value),
            ("aspheric", _) => self.aspheric.as_deref().map(list_text),
            ("index", Some(MediumSpec::Index(v))) => Some(value(v)),
            ("cauchy", Some(MediumSpec::Cauchy(c))) => Some(list_text(c)),
            ("sellmeier", Some(MediumSpec::Sellmeier { b, c })) => {
                Some(format!("{{ b = {}, c = {} }}", list_text(b), list_text(c)))
            }
            _ => None,
        }
    }

    /// True when key `name` is a table over time.
    pub fn is_table(&self, name: &str) -> bool {
        let table = |v: &Option<EyeValue>| matches!(v, Some(EyeValue::Table { .. }));
        match name {
            "radius" => table(&self.radius),
            "conic" => table(&self.conic),
            "thickness" => table(&self.thickness),
            "index" => matches!(
                &self.medium,
                Some(MediumSpec::Index(EyeValue::Table { .. }))
            ),
            _ => false,
        }
    }

    /// The table without key `name` (a built-in eye's surface then keeps its source's).
    pub fn clear(&mut self, name: &str) {
        match name {
            "radius" => self.radius = None,
            "conic" => self.conic = None,
            "aspheric" => self.aspheric = None,
            "thickness" => self.thickness = None,
            _ => self.medium = None,
        }
    }

    /// Each table's values over the whole run, growth times [0, `t_end`], between and beyond
    /// its points (checked there by [`SurfaceSpec::check`]): within the key's range, a radius
    /// of one sign. The error names the key, the time and the value reached.
    pub fn check_over(
        &self,
        i: usize,
        t_end: f64,
        clock: TableClock,
    ) -> Result<(), SurfaceKeyError> {
        let (rlo, rhi) = RADIUS_RANGE;
        let (nlo, nhi) = optics::INDEX_RANGE;
        let radius_range = format!(
            "between {rlo} and {} mm in magnitude, of one sign",
            number(rhi)
        );
        let conic_range = format!("between −{CONIC_LIMIT} and {CONIC_LIMIT}");
        let thickness_range = format!("positive and at most {MAX_THICKNESS} mm");
        let index_range = format!("a refractive index between {nlo} and {nhi}");
        let index = match &self.medium {
            Some(MediumSpec::Index(v)) => Some(v),
            _ => None,
        };
        type Ok = fn(f64) -> bool;
        let keys: [(&str, Option<&EyeValue>, Ok, &str); 4] = [
            (
                "radius",
                self.radius.as_ref(),
                |x| x.abs() >= RADIUS_RANGE.0 && x.abs() <= RADIUS_RANGE.1,
                &radius_range,
            ),
            (
                "conic",
                self.conic.as_ref(),
                |x| x.abs() <= CONIC_LIMIT,
                &conic_range,
            ),
            (
                "thickness",
                self.thickness.as_ref(),
                |x| x > 0.0 && x <= MAX_THICKNESS,
                &thickness_range,
            ),
            (
                "index",
                index,
                |x| x >= optics::INDEX_RANGE.0 && x <= optics::INDEX_RANGE.1,
                &index_range,
            ),
        ];
        for (name, value, ok, range) in keys {
            let Some(v @ EyeValue::Table { t, value: vs }) = value else {
                continue;
            };
            let ((lo, t_lo), (hi, t_hi)) = v.extremes(t_end);
            let bad = if !ok(lo) || lo.is_nan() {
                Some((lo, t_lo))
            } else if !ok(hi) {
                Some((hi, t_hi))
            } else if name == "radius" && lo < 0.0 && hi > 0.0 {
                // A radius of each sign at two times passes through zero between them: the
                // extreme of the sign the table's points do not have is shown.
                Some(if vs[0] > 0.0 { (lo, t_lo) } else { (hi, t_hi) })
            } else {
                None
            };
            if let Some((x, at)) = bad {
                return Err(SurfaceKeyError {
                    key: surface_key(i, name),
                    value: clock.table_text(t, vs),
                    problem: format!(
                        "reaches {} at {} (its spline between or beyond its points): it must stay {range} for {}",
                        significant(x),
                        clock.at(at),
                        clock.span(t_end)
                    ),
                });
            }
        }
        Ok(())
    }

    /// The times [`SurfaceSpec::check_over`] found each table extreme at, within [0, `t_end`]:
    /// where the eye, checked at its table times, is checked too.
    pub fn extreme_times(&self, t_end: f64) -> Vec<f64> {
        let index = match &self.medium {
            Some(MediumSpec::Index(v)) => Some(v),
            _ => None,
        };
        [&self.radius, &self.conic, &self.thickness]
            .into_iter()
            .flatten()
            .chain(index)
            .filter(|v| matches!(v, EyeValue::Table { .. }))
            .flat_map(|v| {
                let ((_, a), (_, b)) = v.extremes(t_end);
                [a, b]
            })
            .collect()
    }
}

/// How the times of the optics' tables are shown to the user: over the model's t, or, in a
/// scene that counts in ages (time.unit), over ages, age = t + time.start. The tables
/// themselves are always over t; this only names their times in messages.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TableClock {
    /// time.start, when the scene counts in ages.
    pub ages_from: Option<f64>,
}

impl TableClock {
    /// What a table's times are called: `t`, or `age`.
    pub fn key(&self) -> &'static str {
        if self.ages_from.is_some() {
            "age"
        } else {
            "t"
        }
    }

    /// A table as written: its times as ages with a clock of ages.
    pub fn table_text(&self, t: &[f64], value: &[f64]) -> String {
        let o = self.ages_from.unwrap_or(0.0);
        let times: Vec<f64> = t.iter().map(|x| x + o).collect();
        format!(
            "{{ {} = {}, value = {} }}",
            self.key(),
            list_text(&times),
            list_text(value)
        )
    }

    /// Model time `t` in the user's words: "t = 0.5", or "age 8.5".
    pub fn at(&self, t: f64) -> String {
        match self.ages_from {
            Some(o) => format!("age {}", significant(t + o)),
            None => format!("t = {}", significant(t)),
        }
    }

    /// The eye's time `t` in the user's words: "growth time t = 0.5", or "age 8.5".
    pub fn eye_time(&self, t: f64) -> String {
        match self.ages_from {
            Some(_) => self.at(t),
            None => format!("growth time {}", self.at(t)),
        }
    }

    /// The run's span [0, `t_end`] in the user's words.
    pub fn span(&self, t_end: f64) -> String {
        match self.ages_from {
            Some(o) => format!("all ages in [{}, {}]", number(o), number(o + t_end)),
            None => format!("all t in [0, {}]", number(t_end)),
        }
    }

    /// Where a table's times may start, in the user's words.
    fn first_time(&self) -> String {
        match self.ages_from {
            Some(o) => format!(
                "finite ages from {} = {} on",
                crate::names::Quantity::TimeStart.name(),
                number(o)
            ),
            None => "finite times from 0 on (the growth's time)".into(),
        }
    }
}

/// The error of surface `i`'s key `name`, given as `value`: `problem`.
fn surface_key_error(i: usize, name: &str, value: String, problem: String) -> SurfaceKeyError {
    SurfaceKeyError {
        key: surface_key(i, name),
        value,
        problem,
    }
}

/// A key's value within its range (`ok`, in words `range`) and, for a table, its times:
/// 2 to [`MAX_TABLE_TIMES`], as many as its values, finite from 0 on, strictly increasing.
fn check_value(
    i: usize,
    name: &str,
    v: &EyeValue,
    ok: &dyn Fn(f64) -> bool,
    range: &str,
    clock: TableClock,
) -> Result<(), SurfaceKeyError> {
    let bad = |name: &str, value, problem| surface_key_error(i, name, value, problem);
    let shown = match v {
        EyeValue::Fixed(x) => number(*x),
        EyeValue::Table { t, value } => clock.table_text(t, value),
    };
    if let EyeValue::Table { t, value } = v {
        if t.len() < 2 || t.len() > MAX_TABLE_TIMES {
            return Err(bad(
                name,
                shown,
                format!("must list 2 to {MAX_TABLE_TIMES} times"),
            ));
        }
        if t.len() != value.len() {
            return Err(bad(
                name,
                shown,
                format!(
                    "must list as many values as times ({} times, {} values)",
                    t.len(),
                    value.len()
                ),
            ));
        }
        if let Some(x) = t.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            let written = x + clock.ages_from.unwrap_or(0.0);
            return Err(bad(
                name,
                shown,
                format!("must list {}, not {}", clock.first_time(), number(written)),
            ));
        }
        if let Some(w) = t.windows(2).find(|w| w[1] <= w[0]) {
            let o = clock.ages_from.unwrap_or(0.0);
            return Err(bad(
                name,
                shown,
                format!(
                    "must list strictly increasing times (they are not sorted for you): {} follows {}",
                    number(w[1] + o),
                    number(w[0] + o)
                ),
            ));
        }
    }
    if let Some(x) = v.values().into_iter().find(|x| !ok(*x)) {
        return Err(bad(
            name,
            shown,
            format!("must be {range} (not {})", number(x)),
        ));
    }
    Ok(())
}

/// A dispersive medium's coefficients (Cauchy's or Sellmeier's) well formed and giving a
/// physical index at the scene's wavelengths and at 555 nm.
fn check_medium(i: usize, m: &MediumSpec, wavelengths: &[f64]) -> Result<(), SurfaceKeyError> {
    let bad = |name: &str, value, problem| surface_key_error(i, name, value, problem);
    let (nlo, nhi) = optics::INDEX_RANGE;
    let shown = match m {
        MediumSpec::Cauchy(c) => list_text(c),
        MediumSpec::Sellmeier { b, c } => {
            format!("{{ b = {}, c = {} }}", list_text(b), list_text(c))
        }
        MediumSpec::Index(_) => String::new(),
    };
    let shape_ok = match m {
        MediumSpec::Cauchy(c) => !c.is_empty() && c.len() <= 4 && c.iter().all(|x| x.is_finite()),
        MediumSpec::Sellmeier { b, c } => {
            !b.is_empty()
                && b.len() == c.len()
                && b.len() <= 6
                && b.iter().chain(c).all(|x| x.is_finite())
        }
        MediumSpec::Index(_) => true,
    };
    if !shape_ok {
        return Err(bad(
            m.key(),
            shown,
            match m {
                MediumSpec::Cauchy(_) => {
                    "must list one to four finite numbers: a, b, c, d (λ in µm)".into()
                }
                _ => "must give as many b as c, one to six of each, all finite".into(),
            },
        ));
    }
    let d = m.dispersion(0.0);
    // The scene's wavelengths and 555 nm, where every system is checked.
    for &w in wavelengths.iter().chain(&[555.0]) {
        let n = d.index(w);
        if !(n >= nlo && n <= nhi) {
            return Err(bad(
                m.key(),
                shown,
                format!(
                    "gives the index {} at {} nm, not a physical one (between {nlo} and {nhi})",
                    number(n),
                    number(w)
                ),
            ));
        }
    }
    Ok(())
}

/// `x` to 6 significant digits, shortest form: a value the spline reaches between points
/// (840, not 840.0000000000002).
fn significant(x: f64) -> String {
    number(format!("{x:.5e}").parse().unwrap_or(x))
}

fn list_text(xs: &[f64]) -> String {
    let items: Vec<String> = xs.iter().take(8).map(|x| number(*x)).collect();
    let more = if xs.len() > 8 { ", …" } else { "" };
    format!("[{}{more}]", items.join(", "))
}

/// The eye at growth time `t`: the base (a built-in eye, or none for a custom one) with the
/// surface tables applied. `pupil` is the built-in eye's stop as the surface whose vertex it
/// lies on, so that a changed anterior chamber carries the pupil with the lens.
pub fn assemble(
    base: Option<&OpticalSystem>,
    surfaces: &[SurfaceSpec],
    t: f64,
) -> Result<OpticalSystem, SurfaceKeyError> {
    let missing = |i: usize, name: &str, what: &str| SurfaceKeyError {
        key: surface_key(i, name),
        value: "(none)".into(),
        problem: format!("must be given for a custom eye's surface ({what})"),
    };
    let mut elements = Vec::new();
    match base {
        Some(eye) => {
            if surfaces.len() > eye.elements.len() {
                return Err(SurfaceKeyError {
                    key: format!("{}[{}]", Quantity::Surfaces, eye.elements.len()),
                    value: format!("({} surface tables)", surfaces.len()),
                    problem: format!(
                        "is beyond the {} eye's {} surfaces (surfaces are counted from 0; give \"custom\" as {} to describe an eye of your own)",
                        eye.name,
                        eye.elements.len(),
                        Quantity::Optics
                    ),
                });
            }
            for (i, e) in eye.elements.iter().enumerate() {
                let mut e = e.clone();
                if let Some(s) = surfaces.get(i) {
                    if let Some(v) = &s.radius {
                        e.surface.radius = v.at(t);
                    }
                    if let Some(v) = &s.conic {
                        e.surface.conic = v.at(t);
                    }
                    if let Some(a) = &s.aspheric {
                        e.surface.aspheric = a.clone();
                    }
                    if let Some(v) = &s.thickness {
                        e.thickness = v.at(t);
                    }
                    if let Some(m) = &s.medium {
                        if let MediumKind::Grin(_) = e.medium.kind {
                            return Err(SurfaceKeyError {
                                key: surface_key(i, m.key()),
                                value: "(given)".into(),
                                problem: format!(
                                    "cannot replace the gradient-index medium '{}' of the {} eye (its profile is the source's)",
                                    e.medium.name, eye.name
                                ),
                            });
                        }
                        e.medium = Medium::homogeneous(e.medium.name.clone(), m.dispersion(t));
                    }
                }
                elements.push(e);
            }
        }
        None => {
            if surfaces.len() < 2 {
                return Err(SurfaceKeyError {
                    key: Quantity::Surfaces.to_string(),
                    value: format!("({} surface tables)", surfaces.len()),
                    problem: format!(
                        "must describe 2 to {MAX_SURFACES} surfaces for {} = \"custom\" (one [[{}]] table each)",
                        Quantity::Optics,
                        Quantity::Surfaces
                    ),
                });
            }
            for (i, s) in surfaces.iter().enumerate() {
                let radius = s
                    .radius
                    .as_ref()
                    .ok_or_else(|| missing(i, "radius", "mm, inf for a plane"))?;
                let thickness = s.thickness.as_ref().ok_or_else(|| {
                    missing(
                        i,
                        "thickness",
                        "mm to the next surface, or the last one's to the retina",
                    )
                })?;
                let medium = s.medium.as_ref().ok_or_else(|| {
                    missing(
                        i,
                        "index",
                        "the medium behind it: index, cauchy or sellmeier",
                    )
                })?;
                let name = format!("surface {i}");
                let surface = Surface::new(
                    name.clone(),
                    radius.at(t),
                    s.conic.as_ref().map_or(0.0, |v| v.at(t)),
                )
                .with_aspheric(s.aspheric.clone().unwrap_or_default());
                elements.push(optics::Element::new(
                    surface,
                    thickness.at(t),
                    Medium::homogeneous(format!("medium after surface {i}"), medium.dispersion(t)),
                ));
            }
        }
    }
    Ok(OpticalSystem {
        name: base.map_or("custom".into(), |b| b.name.clone()),
        object: Medium::constant("air", 1.0),
        elements,
        pupil_position: None,
        retina: None,
        origin: 0.0,
    })
}

/// The surface (index into the elements) whose vertex a built-in eye's stop lies on, if it
/// lies on one.
pub fn pupil_vertex(eye: &OpticalSystem) -> Option<usize> {
    let z = eye.pupil_position?;
    eye.vertices().iter().position(|v| (v - z).abs() < 1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weights reproduce the natural cubic spline: exact for a straight line (inside and
    /// beyond the ends), interpolating at the knots, C¹ at an interior knot.
    #[test]
    fn spline_weights_are_a_natural_cubic_spline() {
        let ts = [0.0, 0.3, 0.5, 1.0];
        let line = |t: f64| 2.0 - 3.0 * t;
        let v: Vec<f64> = ts.iter().map(|&t| line(t)).collect();
        let at = |t: f64| -> f64 {
            spline_weights(&ts, t)
                .iter()
                .zip(&v)
                .map(|(w, v)| w * v)
                .sum()
        };
        for t in [-0.5, 0.0, 0.1, 0.3, 0.77, 1.0, 1.4] {
            assert!((at(t) - line(t)).abs() < 1e-12, "{t}: {}", at(t));
        }
        let value = EyeValue::Table {
            t: ts.to_vec(),
            value: vec![7.4, 7.6, 7.7, 7.8],
        };
        for (t, x) in ts.iter().zip([7.4, 7.6, 7.7, 7.8]) {
            assert!((value.at(*t) - x).abs() < 1e-12);
        }
        // One-sided slopes at the knot 0.3 and at the end 1.0 agree (C¹, and C¹ into the
        // linear continuation).
        let h = 1e-6;
        for k in [0.3, 0.5, 1.0, 0.0] {
            let left = (value.at(k) - value.at(k - h)) / h;
            let right = (value.at(k + h) - value.at(k)) / h;
            assert!((left - right).abs() < 1e-4, "{k}: {left} vs {right}");
        }
    }
}
