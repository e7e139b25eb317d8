//! Observations of a growth curve: axial lengths and/or refractions by time (or age), each
//! with its standard deviation, read from a CSV file, every row checked, every refusal one
//! line naming the file, the line and the column.
//!
//! The file: a header naming the columns, then one observation time per line; blank lines
//! and lines starting with `#` are skipped; cells are trimmed. The first column is `t` (the
//! model's time) or `age` (in the scene's time.unit); then `axial_length` (mm) and/or
//! `refraction_D` (D, the pole's refraction of the naked eye, as series.csv's), each
//! optionally with its standard deviation `sigma_axial_length` (or `sigma`, its older name)
//! and `sigma_refraction_D`, in any order. A file with both quantities gives both σ (mm and
//! D cannot share one weight); in such a file a row may leave one quantity's cells empty
//! (measured at that visit or not). Each value must be a finite number; t ≥ 0 and within
//! the scene's run [0, growth.t_end] (checked against the scene by
//! [`Observations::check_times`]); the axial length > 0 (mm); σ > 0. Rows may come in any
//! order and times may repeat (replicate measurements: each is a residual of its own). At
//! most [`MAX_OBSERVATIONS`] rows and [`MAX_DATA_BYTES`] bytes.

use std::path::Path;

use crate::rundir::read::read_text;
use crate::text::{excerpt, number};
use crate::{Error, Origin, Subject};

/// The most bytes a data file may have (16 MiB: about half a million rows).
pub const MAX_DATA_BYTES: u64 = 1 << 24;
/// The most observations a fit takes (each is a residual; the model is run once per
/// iteration whatever their number, but its recorded times grow with the distinct times).
pub const MAX_OBSERVATIONS: usize = 100_000;
/// The columns of the classic data file, the third optional.
pub const DATA_COLUMNS: [&str; 3] = ["t", "axial_length", "sigma"];
/// Every column a data file may have after its first (`t` or `age`).
pub const QUANTITY_COLUMNS: [&str; 5] = [
    "axial_length",
    "sigma_axial_length",
    "refraction_D",
    "sigma_refraction_D",
    "sigma",
];

/// What an observation measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Measured {
    /// The axial length (mm).
    #[serde(rename = "axial_length")]
    AxialLength,
    /// The pole's refraction of the naked eye (D).
    #[serde(rename = "refraction_D")]
    Refraction,
}

impl Measured {
    /// The data file's column.
    pub fn column(self) -> &'static str {
        match self {
            Measured::AxialLength => "axial_length",
            Measured::Refraction => "refraction_D",
        }
    }

    /// The unit of the values and of their σ.
    pub fn unit(self) -> &'static str {
        match self {
            Measured::AxialLength => "mm",
            Measured::Refraction => "D",
        }
    }
}

/// One observation time: the axial length (mm) and/or the refraction (D) measured at time
/// t, each with its standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    pub t: f64,
    /// The axial length (mm), if measured.
    pub axial_length: Option<f64>,
    /// Its σ (mm); None when the file gives none (every observation weighs the same).
    pub sigma: Option<f64>,
    /// The refraction (D), if measured.
    pub refraction_d: Option<f64>,
    /// Its σ (D).
    pub sigma_refraction_d: Option<f64>,
    /// The age the file gives (an `age` column in place of `t`, in the scene's time.unit);
    /// t is then the model time of that age ([`Observations::on_clock`]).
    pub age: Option<f64>,
}

impl Observation {
    /// An axial length at `t` (σ optional): the observation of the classic file.
    pub fn axial(t: f64, axial_length: f64, sigma: Option<f64>) -> Observation {
        Observation {
            t,
            axial_length: Some(axial_length),
            sigma,
            refraction_d: None,
            sigma_refraction_d: None,
            age: None,
        }
    }

    /// The value and σ of `what`, if measured.
    pub fn value(&self, what: Measured) -> Option<(f64, Option<f64>)> {
        match what {
            Measured::AxialLength => self.axial_length.map(|y| (y, self.sigma)),
            Measured::Refraction => self.refraction_d.map(|y| (y, self.sigma_refraction_d)),
        }
    }

    /// The measurements of this time, axial length first.
    pub fn measured(&self) -> impl Iterator<Item = (Measured, f64, Option<f64>)> + '_ {
        [Measured::AxialLength, Measured::Refraction]
            .into_iter()
            .filter_map(|m| self.value(m).map(|(y, s)| (m, y, s)))
    }
}

/// The observations of a fit, in the order of the file.
#[derive(Clone, Debug, PartialEq)]
pub struct Observations {
    /// Where they came from (the file's path, or a name given by the caller).
    pub origin: String,
    pub rows: Vec<Observation>,
    /// FNV-1a 64 of the file's bytes, as 16 hex digits (fit.json records it); for
    /// observations not read from a file, of their values as the file would hold them.
    pub hash: String,
}

/// One column of a data file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Column {
    Time,
    Age,
    Value(Measured),
    Sigma(Measured),
}

impl Column {
    fn of(name: &str) -> Option<Column> {
        Some(match name {
            "t" => Column::Time,
            "age" => Column::Age,
            "axial_length" => Column::Value(Measured::AxialLength),
            "sigma" | "sigma_axial_length" => Column::Sigma(Measured::AxialLength),
            "refraction_D" => Column::Value(Measured::Refraction),
            "sigma_refraction_D" => Column::Sigma(Measured::Refraction),
            _ => return None,
        })
    }
}

/// Why `header` is not a data file's header, if it is not.
fn header_problem(header: &[&str], columns: &[Option<Column>]) -> Option<String> {
    let expected = "the header must be \"t,axial_length\" or \"t,axial_length,sigma\" (or age in place of t; refraction_D and sigma_refraction_D with or in place of axial_length and sigma_axial_length)";
    let shown = excerpt(&header.join(","), 80);
    if !matches!(columns.first(), Some(Some(Column::Time | Column::Age))) {
        return Some(format!("{expected}, not {shown:?}"));
    }
    if let Some(i) = columns.iter().position(Option::is_none) {
        return Some(format!(
            "{expected}, not {shown:?}: column {} ({:?}) is not one of t, age, {}",
            i + 1,
            excerpt(header[i], 40),
            QUANTITY_COLUMNS.join(", ")
        ));
    }
    for (i, c) in columns.iter().enumerate().skip(1) {
        if columns[..i].contains(c) || matches!(c, Some(Column::Time | Column::Age)) {
            return Some(format!(
                "{expected}, not {shown:?}: column {} ({}) names a column given before",
                i + 1,
                header[i]
            ));
        }
    }
    let has = |c: Column| columns.contains(&Some(c));
    let values: Vec<Measured> = [Measured::AxialLength, Measured::Refraction]
        .into_iter()
        .filter(|&m| has(Column::Value(m)))
        .collect();
    if values.is_empty() {
        return Some(format!(
            "{expected}, not {shown:?}: give axial_length or refraction_D (or both)"
        ));
    }
    for m in [Measured::AxialLength, Measured::Refraction] {
        if has(Column::Sigma(m)) && !has(Column::Value(m)) {
            return Some(format!(
                "{expected}, not {shown:?}: a σ of {} without its column {}",
                m.column(),
                m.column()
            ));
        }
    }
    if values.len() == 2 && values.iter().any(|&m| !has(Column::Sigma(m))) {
        return Some(format!(
            "{shown:?}: a file with both axial_length and refraction_D must give sigma_axial_length and sigma_refraction_D too (mm and D cannot share one weight)"
        ));
    }
    None
}

impl Observations {
    /// Read and check the data file `path`.
    pub fn read(path: &Path) -> Result<Observations, Error> {
        let text = read_text(path, MAX_DATA_BYTES)?;
        Observations::parse(&text, &path.display().to_string())
    }

    /// Parse and check CSV text (`origin` names it in messages).
    pub fn parse(text: &str, origin: &str) -> Result<Observations, Error> {
        let from = || Origin::File(origin.into());
        let file = || Subject::File(origin.into());
        let fail = |subject: Subject, line: u64, what: String| {
            Error::input(subject, format!("{origin}: line {line}: {what}")).with_origin(from())
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        let mut record = csv::StringRecord::new();
        let mut header: Option<(Vec<String>, Vec<Column>)> = None;
        let mut rows = Vec::new();
        loop {
            match reader.read_record(&mut record) {
                Ok(false) => break,
                Ok(true) => {}
                Err(e) => {
                    let line = e.position().map_or(0, |p| p.line());
                    return Err(fail(file(), line, excerpt(&e.to_string(), 80)));
                }
            }
            if record.len() == 1 && record[0].is_empty() {
                continue;
            }
            let line = record.position().map_or(0, |p| p.line());
            let Some((names, columns)) = &header else {
                let names: Vec<&str> = record.iter().collect();
                let columns: Vec<Option<Column>> = names.iter().map(|n| Column::of(n)).collect();
                if let Some(why) = header_problem(&names, &columns) {
                    return Err(fail(
                        Subject::Column(names.first().unwrap_or(&"").to_string()),
                        line,
                        why,
                    )
                    .with_value(names.join(",")));
                }
                header = Some((
                    names.iter().map(|s| s.to_string()).collect(),
                    columns.into_iter().flatten().collect(),
                ));
                continue;
            };
            if record.len() != columns.len() {
                return Err(fail(
                    file(),
                    line,
                    format!(
                        "{} values for {} columns ({})",
                        record.len(),
                        columns.len(),
                        names.join(",")
                    ),
                ));
            }
            if rows.len() == MAX_OBSERVATIONS {
                return Err(fail(
                    file(),
                    line,
                    format!("more than {MAX_OBSERVATIONS} observations, more than a fit takes"),
                ));
            }
            rows.push(read_row(&record, names, columns, line, &fail)?);
        }
        if header.is_none() {
            return Err(Error::input(file(), format!(
                "{origin}: empty file (expected the header \"t,axial_length[,sigma]\", then one observation per line)"
            )).with_origin(from()));
        }
        if rows.is_empty() {
            return Err(Error::input(
                file(),
                format!("{origin}: no observations after the header"),
            )
            .with_origin(from()));
        }
        Ok(Observations {
            origin: origin.to_string(),
            rows,
            hash: format!("{:016x}", crate::hash::fnv1a64(text.as_bytes())),
        })
    }

    /// Observations from columns (the Python package's arrays): checked as a file's rows,
    /// "line" being the row's number from 1 after the header (line 2 onwards).
    pub fn from_columns(
        t: &[f64],
        axial_length: &[f64],
        sigma: Option<&[f64]>,
        origin: &str,
    ) -> Result<Observations, Error> {
        Observations::from_table(
            "t",
            t,
            &[
                ("axial_length", axial_length),
                ("sigma", sigma.unwrap_or(&[])),
            ],
            origin,
        )
    }

    /// [`Observations::from_columns`] with ages (in the scene's time.unit) in place of t,
    /// as a file with an `age` column: checked against the scene's ages by the fit.
    pub fn from_age_columns(
        age: &[f64],
        axial_length: &[f64],
        sigma: Option<&[f64]>,
        origin: &str,
    ) -> Result<Observations, Error> {
        Observations::from_table(
            "age",
            age,
            &[
                ("axial_length", axial_length),
                ("sigma", sigma.unwrap_or(&[])),
            ],
            origin,
        )
    }

    /// The observations of named columns (`first`: "t" or "age"; the others any of
    /// [`QUANTITY_COLUMNS`], an empty one left out, NaN an empty cell), as the file with
    /// those columns would give them.
    pub fn from_table(
        first: &str,
        t: &[f64],
        columns: &[(&str, &[f64])],
        origin: &str,
    ) -> Result<Observations, Error> {
        let n = t.len();
        let given: Vec<&(&str, &[f64])> = columns.iter().filter(|(_, c)| !c.is_empty()).collect();
        if let Some((name, c)) = given.iter().find(|(_, c)| c.len() != n) {
            return Err(Error::input(
                Subject::Column(name.to_string()),
                format!(
                    "{origin}: {first} and {name} must have the same length ({n}, {})",
                    c.len()
                ),
            )
            .with_value(format!("{} values", c.len()))
            .with_origin(Origin::File(origin.into())));
        }
        let several = (given.iter())
            .filter(|(name, _)| matches!(*name, "axial_length" | "refraction_D"))
            .count()
            > 1;
        let mut text = first.to_string();
        for (name, _) in &given {
            text.push(',');
            text.push_str(name);
        }
        text.push('\n');
        for i in 0..n {
            let mut cells = vec![crate::rundir::format_value(t[i])];
            for (_, c) in &given {
                cells.push(if c[i].is_nan() && several {
                    String::new()
                } else {
                    crate::rundir::format_value(c[i])
                });
            }
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        Observations::parse(&text, origin)
    }

    /// Whether every measurement carries its σ.
    pub fn has_sigma(&self) -> bool {
        self.rows
            .iter()
            .all(|r| r.measured().all(|(_, _, s)| s.is_some()))
    }

    /// Whether any row measures `what`.
    pub fn has(&self, what: Measured) -> bool {
        self.rows.iter().any(|r| r.value(what).is_some())
    }

    /// The number of measurements (each a residual): a row of both quantities counts twice.
    pub fn measurements(&self) -> usize {
        self.rows.iter().map(|r| r.measured().count()).sum()
    }

    /// The observations on the model's clock: ages (an `age` column) mapped to t through
    /// the scene's time.* keys; each age must lie in [time.start, time.end]. Observations
    /// in t are returned as they are.
    pub fn on_clock(&self, g: &crate::growth::GrowthParams) -> Result<Observations, Error> {
        if !self.rows.iter().any(|r| r.age.is_some()) {
            return Ok(self.clone());
        }
        let clock = &g.clock;
        let (true, Some(a0), Some(a1)) = (clock.has_ages(), clock.start, clock.end) else {
            return Err(Error::input(Subject::Key("time.unit".into()), format!(
                "{}: the data give ages (an age column), but the scene counts no ages: set time.unit (\"years\" or \"days\"), time.start and time.end, or give the model's t",
                self.origin
            ))
            .with_origin(Origin::File(self.origin.clone().into())));
        };
        let unit = clock.unit.name();
        let mut out = self.clone();
        for (i, r) in out.rows.iter_mut().enumerate() {
            let a = r.age.unwrap_or(r.t);
            if a < a0 || a > a1 {
                return Err(Error::input(Subject::Column("age".into()), format!(
                    "{}: observation {} (age {} {unit}) lies outside the scene's ages [time.start, time.end] = [{}, {}] {unit}; widen them to cover the data",
                    self.origin,
                    i + 1,
                    number(a),
                    number(a0),
                    number(a1)
                ))
                .with_value(number(a))
                .with_origin(Origin::File(self.origin.clone().into())));
            }
            r.t = clock.t_of(a).clamp(0.0, g.t_end);
        }
        Ok(out)
    }

    /// Refuse times outside the run [0, `t_end`] (the model has no value there).
    pub fn check_times(&self, t_end: f64) -> Result<(), Error> {
        if let Some((i, r)) = self.rows.iter().enumerate().find(|(_, r)| r.t > t_end) {
            return Err(Error::input(Subject::Column("t".into()), format!(
                "{}: observation {} (t = {}) is after the scene's run ends (growth.t_end = {t_end}); set growth.t_end to cover the data",
                self.origin,
                i + 1,
                r.t
            ))
            .with_value(r.t)
            .with_origin(Origin::File(self.origin.clone().into())));
        }
        Ok(())
    }

    /// The distinct times, sorted; times closer than 1e-9·`t_end` count as one (the first).
    pub fn distinct_times(&self, t_end: f64) -> Vec<f64> {
        let times: Vec<f64> = self.rows.iter().map(|r| r.t).collect();
        eyeshell_core::fit::distinct_times(&times, t_end)
    }
}

/// One data line as an observation: every cell checked, a quantity's cell and its σ's
/// empty together (or neither), at least one quantity given.
fn read_row(
    record: &csv::StringRecord,
    names: &[String],
    columns: &[Column],
    line: u64,
    fail: &dyn Fn(Subject, u64, String) -> Error,
) -> Result<Observation, Error> {
    let mut o = Observation {
        t: 0.0,
        axial_length: None,
        sigma: None,
        refraction_d: None,
        sigma_refraction_d: None,
        age: None,
    };
    let several = columns
        .iter()
        .filter(|c| matches!(c, Column::Value(_)))
        .count()
        > 1;
    for (j, (cell, &c)) in record.iter().zip(columns).enumerate() {
        let name = names[j].as_str();
        let column = format!("column {} ({name})", j + 1);
        let bad = |what: String| {
            fail(
                Subject::Column(name.into()),
                line,
                format!("{column}{what}"),
            )
            .with_value(cell)
        };
        // In a file of both quantities a visit may have measured one of them only.
        if cell.is_empty() && several && matches!(c, Column::Value(_) | Column::Sigma(_)) {
            continue;
        }
        let x: f64 = cell
            .parse()
            .map_err(|_| bad(format!(": {:?} is not a number", excerpt(cell, 80))))?;
        let why = if !x.is_finite() {
            Some("must be a finite number")
        } else {
            match c {
                Column::Time if x < 0.0 => Some("must be ≥ 0 (the run starts at t = 0)"),
                Column::Value(Measured::AxialLength) if x <= 0.0 => Some("must be positive (mm)"),
                Column::Sigma(Measured::AxialLength) if x <= 0.0 => {
                    Some("must be positive (a standard deviation in mm)")
                }
                Column::Sigma(Measured::Refraction) if x <= 0.0 => {
                    Some("must be positive (a standard deviation in D)")
                }
                _ => None,
            }
        };
        if let Some(why) = why {
            return Err(bad(format!(" = {cell} {why}")));
        }
        match c {
            Column::Time => o.t = x,
            Column::Age => {
                o.t = x;
                o.age = Some(x);
            }
            Column::Value(Measured::AxialLength) => o.axial_length = Some(x),
            Column::Sigma(Measured::AxialLength) => o.sigma = Some(x),
            Column::Value(Measured::Refraction) => o.refraction_d = Some(x),
            Column::Sigma(Measured::Refraction) => o.sigma_refraction_d = Some(x),
        }
    }
    for m in [Measured::AxialLength, Measured::Refraction] {
        let has_sigma = columns.contains(&Column::Sigma(m));
        let (value, sigma) = match m {
            Measured::AxialLength => (o.axial_length, o.sigma),
            Measured::Refraction => (o.refraction_d, o.sigma_refraction_d),
        };
        if has_sigma && value.is_some() != sigma.is_some() {
            return Err(fail(
                Subject::Column(m.column().into()),
                line,
                format!(
                    "{} and its σ must be given together (one of them is empty)",
                    m.column()
                ),
            ));
        }
    }
    if o.axial_length.is_none() && o.refraction_d.is_none() {
        return Err(fail(
            Subject::Column("axial_length".into()),
            line,
            "no measurement: give the axial length or the refraction (or both)".into(),
        ));
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Observations, String> {
        Observations::parse(text, "d.csv").map_err(|e| {
            assert!(e.is_user_error());
            e.to_string()
        })
    }

    #[test]
    fn a_file_reads_with_or_without_sigma() {
        let o = parse("t,axial_length\n0.1, 21.9\n# a comment\n\n0.0,20\n").unwrap();
        assert_eq!(o.rows.len(), 2);
        assert_eq!(o.rows[1], Observation::axial(0.0, 20.0, None));
        assert!(!o.has_sigma());
        let o = parse(" t , axial_length , sigma\n0.1,21.9,0.05\n0.1,22.0,0.05").unwrap();
        assert!(o.has_sigma() && o.rows.len() == 2);
        assert_eq!(o.distinct_times(1.0), [0.1]);
    }

    #[test]
    fn every_refusal_names_the_line_and_the_column() {
        let cases = [
            ("", "d.csv: empty file"),
            ("\n\n", "d.csv: empty file"),
            (
                "t,axial_length\n",
                "d.csv: no observations after the header",
            ),
            ("time,L\n1,2\n", "d.csv: line 1: the header must be"),
            (
                "t,axial_length\n0.1,abc\n",
                "d.csv: line 2: column 2 (axial_length): \"abc\" is not a number",
            ),
            (
                "t,axial_length\n0.1,NaN\n",
                "d.csv: line 2: column 2 (axial_length) = NaN must be a finite number",
            ),
            (
                "t,axial_length\ninf,2\n",
                "d.csv: line 2: column 1 (t) = inf must be a finite number",
            ),
            (
                "t,axial_length\n-0.1,2\n",
                "d.csv: line 2: column 1 (t) = -0.1 must be ≥ 0",
            ),
            (
                "t,axial_length,sigma\n0.1,2,-0.05\n",
                "d.csv: line 2: column 3 (sigma) = -0.05 must be positive",
            ),
            (
                "t,axial_length,sigma\n0.1,2,0\n",
                "d.csv: line 2: column 3 (sigma) = 0 must be positive",
            ),
            (
                "t,axial_length\n0.1,2,3\n",
                "d.csv: line 2: 3 values for 2 columns",
            ),
            (
                "t,axial_length,sigma\n0.1,2,1\n0.2,2\n",
                "d.csv: line 3: 2 values for 3 columns",
            ),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err();
            assert!(e.starts_with(want), "{text:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let huge = format!(
            "t,axial_length\n{}",
            "0.5,22\n".repeat(MAX_OBSERVATIONS + 1)
        );
        let e = parse(&huge).unwrap_err();
        assert!(
            e.contains(&format!("line {}: more than", MAX_OBSERVATIONS + 2)),
            "{e}"
        );
    }

    #[test]
    fn a_file_of_both_quantities_reads_each_with_its_sigma() {
        let o = parse(
            "age,refraction_D,sigma_refraction_D,axial_length,sigma_axial_length\n8,0.5,0.25,23.1,0.05\n9,-0.25,0.25,,\n10,,,23.6,0.05\n",
        )
        .unwrap();
        assert_eq!(o.rows.len(), 3);
        assert_eq!(o.measurements(), 4);
        assert!(o.has_sigma() && o.has(Measured::Refraction) && o.has(Measured::AxialLength));
        let r = o.rows[1];
        assert_eq!(
            (r.t, r.age, r.refraction_d, r.sigma_refraction_d),
            (9.0, Some(9.0), Some(-0.25), Some(0.25))
        );
        assert_eq!((r.axial_length, r.sigma), (None, None));
        let only = parse("t,refraction_D\n0.5,1.25\n").unwrap();
        assert!(!only.has_sigma() && !only.has(Measured::AxialLength));
        assert_eq!(only.rows[0].refraction_d, Some(1.25));
        for (text, want) in [
            (
                "t,refraction_D,axial_length\n0.5,1,22\n",
                "must give sigma_axial_length and sigma_refraction_D too",
            ),
            (
                "t,sigma_refraction_D\n0.5,1\n",
                "give axial_length or refraction_D",
            ),
            (
                "t,axial_length,refraction_D,sigma_refraction_D\n0.5,22,1,0.2\n",
                "must give sigma_axial_length",
            ),
            (
                "t,axial_length,sigma,sigma_axial_length\n0.5,22,1,1\n",
                "column 4 (sigma_axial_length) names a column given before",
            ),
            (
                "t,axial_length,sigma_refraction_D\n0.5,22,1\n",
                "a σ of refraction_D without its column",
            ),
            (
                "t,axial_length,cornea\n0.5,22,1\n",
                "column 3 (\"cornea\") is not one of",
            ),
            (
                "t,axial_length,sigma,refraction_D,sigma_refraction_D\n0.5,22,,1,0.2\n",
                "line 2: axial_length and its σ must be given together",
            ),
            (
                "t,axial_length,sigma,refraction_D,sigma_refraction_D\n0.5,,,,\n",
                "line 2: no measurement",
            ),
            (
                "t,refraction_D,sigma_refraction_D\n0.5,1,0\n",
                "column 3 (sigma_refraction_D) = 0 must be positive (a standard deviation in D)",
            ),
            (
                "t,refraction_D\n0.5,\n",
                "column 2 (refraction_D): \"\" is not a number",
            ),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
            assert!(e.starts_with("d.csv"), "{e}");
        }
    }

    #[test]
    fn times_after_the_run_are_refused() {
        let o = parse("t,axial_length\n0.5,22\n1.5,23\n").unwrap();
        let e = o.check_times(1.0).unwrap_err().to_string();
        assert!(
            e.contains("observation 2 (t = 1.5) is after the scene's run ends"),
            "{e}"
        );
        assert!(o.check_times(2.0).is_ok());
    }

    #[test]
    fn columns_read_as_a_file_would() {
        let o = Observations::from_columns(&[0.1, 0.2], &[21.0, 22.0], Some(&[0.1, 0.1]), "arrays")
            .unwrap();
        assert_eq!(o.rows[1], Observation::axial(0.2, 22.0, Some(0.1)));
        let e = Observations::from_columns(&[0.1], &[f64::NAN], None, "arrays").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("arrays: line 2: column 2 (axial_length) = NaN"),
            "{e}"
        );
    }
}
