//! Observations of a growth curve: (t, axial length[, σ]) read from a CSV file, every row
//! checked, every refusal one line naming the file, the line and the column.
//!
//! The file: a header naming the columns `t,axial_length` or `t,axial_length,sigma` (in
//! that order; cells trimmed), then one observation per line; blank lines and lines
//! starting with `#` are skipped. Each value must be a finite number; t ≥ 0 and within the
//! scene's run [0, growth.t_end] (checked against the scene by [`Observations::check_times`]);
//! the axial length > 0 (mm); σ > 0 (mm), the standard deviation of that observation.
//! Rows may come in any order and times may repeat (replicate measurements: each is a
//! residual of its own). At most [`MAX_OBSERVATIONS`] rows and [`MAX_DATA_BYTES`] bytes.

use std::path::Path;

use crate::rundir::read::read_text;
use crate::text::{excerpt, number};
use crate::{Error, Origin, Subject};

/// The most bytes a data file may have (16 MiB: about half a million rows).
pub const MAX_DATA_BYTES: u64 = 1 << 24;
/// The most observations a fit takes (each is a residual; the model is run once per
/// iteration whatever their number, but its recorded times grow with the distinct times).
pub const MAX_OBSERVATIONS: usize = 100_000;
/// The columns of a data file, the third optional.
pub const DATA_COLUMNS: [&str; 3] = ["t", "axial_length", "sigma"];

/// One observation: the axial length (mm) measured at time t, with its standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    pub t: f64,
    pub axial_length: f64,
    /// σ (mm); None when the file has no sigma column (every observation weighs the same).
    pub sigma: Option<f64>,
    /// The age the file gives (an `age` column in place of `t`, in the scene's time.unit);
    /// t is then the model time of that age ([`Observations::on_clock`]).
    pub age: Option<f64>,
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
        let mut columns: Option<usize> = None;
        let mut ages = false;
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
            let Some(n) = columns else {
                let header: Vec<&str> = record.iter().collect();
                // An `age` column stands in place of t (ages in the scene's time.unit).
                let is_age = header.first() == Some(&"age");
                let mut named = header.clone();
                if is_age {
                    named[0] = "t";
                }
                if named != DATA_COLUMNS[..2] && named != DATA_COLUMNS {
                    return Err(fail(
                        Subject::Column(header.first().unwrap_or(&"").to_string()),
                        line,
                        format!(
                            "the header must be \"t,axial_length\" or \"t,axial_length,sigma\" (or age in place of t), not {:?}",
                            excerpt(&header.join(","), 80)
                        ),
                    )
                    .with_value(header.join(",")));
                }
                ages = is_age;
                columns = Some(header.len());
                continue;
            };
            if record.len() != n {
                return Err(fail(
                    file(),
                    line,
                    format!(
                        "{} values for {n} columns ({})",
                        record.len(),
                        DATA_COLUMNS[..n].join(",")
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
            let mut values = [0.0; 3];
            for (j, cell) in record.iter().enumerate() {
                let name = if j == 0 && ages {
                    "age"
                } else {
                    DATA_COLUMNS[j]
                };
                let column = format!("column {} ({name})", j + 1);
                let x: f64 = cell.parse().map_err(|_| {
                    fail(
                        Subject::Column(name.into()),
                        line,
                        format!("{column}: {:?} is not a number", excerpt(cell, 80)),
                    )
                    .with_value(cell)
                })?;
                let why = if !x.is_finite() {
                    Some("must be a finite number")
                } else if j == 0 && x < 0.0 && !ages {
                    Some("must be ≥ 0 (the run starts at t = 0)")
                } else if j > 0 && x <= 0.0 {
                    Some(if j == 1 {
                        "must be positive (mm)"
                    } else {
                        "must be positive (a standard deviation in mm)"
                    })
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(fail(
                        Subject::Column(name.into()),
                        line,
                        format!("{column} = {cell} {why}"),
                    )
                    .with_value(cell));
                }
                values[j] = x;
            }
            rows.push(Observation {
                t: values[0],
                axial_length: values[1],
                sigma: (n == 3).then_some(values[2]),
                age: ages.then_some(values[0]),
            });
        }
        if columns.is_none() {
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
        Observations::from_named_columns("t", t, axial_length, sigma, origin)
    }

    /// [`Observations::from_columns`] with ages (in the scene's time.unit) in place of t,
    /// as a file with an `age` column: checked against the scene's ages by the fit.
    pub fn from_age_columns(
        age: &[f64],
        axial_length: &[f64],
        sigma: Option<&[f64]>,
        origin: &str,
    ) -> Result<Observations, Error> {
        Observations::from_named_columns("age", age, axial_length, sigma, origin)
    }

    /// The observations of the columns (`first`: "t" or "age"), as the file with those
    /// columns would give them.
    fn from_named_columns(
        first: &str,
        t: &[f64],
        axial_length: &[f64],
        sigma: Option<&[f64]>,
        origin: &str,
    ) -> Result<Observations, Error> {
        let n = t.len();
        if axial_length.len() != n || sigma.is_some_and(|s| s.len() != n) {
            return Err(Error::input(
                Subject::Column("axial_length".into()),
                format!(
                "{origin}: {first}, axial_length and sigma must have the same length ({n}, {}, {})",
                axial_length.len(),
                sigma.map_or("none".to_string(), |s| s.len().to_string())
            ),
            )
            .with_value(format!("{} values", axial_length.len()))
            .with_origin(Origin::File(origin.into())));
        }
        let mut text = format!(
            "{first},axial_length{}\n",
            if sigma.is_some() { ",sigma" } else { "" }
        );
        for i in 0..n {
            let mut cells = vec![
                crate::rundir::format_value(t[i]),
                crate::rundir::format_value(axial_length[i]),
            ];
            if let Some(s) = sigma {
                cells.push(crate::rundir::format_value(s[i]));
            }
            text.push_str(&cells.join(","));
            text.push('\n');
        }
        Observations::parse(&text, origin)
    }

    /// Whether the observations carry their σ.
    pub fn has_sigma(&self) -> bool {
        self.rows.first().is_some_and(|r| r.sigma.is_some())
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
        assert_eq!(
            o.rows[1],
            Observation {
                t: 0.0,
                axial_length: 20.0,
                sigma: None,
                age: None
            }
        );
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
        assert_eq!(
            o.rows[1],
            Observation {
                t: 0.2,
                axial_length: 22.0,
                sigma: Some(0.1),
                age: None
            }
        );
        let e = Observations::from_columns(&[0.1], &[f64::NAN], None, "arrays").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("arrays: line 2: column 2 (axial_length) = NaN"),
            "{e}"
        );
    }
}
