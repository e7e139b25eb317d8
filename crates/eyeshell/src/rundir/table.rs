//! The CSV files of eyeshell, written and read through the `csv` crate, in one dialect.
//!
//! Writing ([`csv_writer`], [`csv_bytes`]): `,` between cells, `\n` after every line (the
//! header included), numbers as [`super::format_value`] gives them. Files differ only in
//! their quoting, which each keeps from before the `csv` crate:
//! - the run files (fields.csv, at.csv, series.csv, history.csv, the snapshots) and
//!   sweep.csv: [`QuoteStyle::Necessary`], a cell is quoted when it holds a comma, a quote
//!   or a line break (only sweep.csv has text that can: swept values and error messages);
//! - the study tables (`eyeshell converge`, `wpd`, `refine`): [`QuoteStyle::Never`], as
//!   they always were written; the label of refinement.csv's first row holds commas, so
//!   that row has more cells than the header for a strict CSV reader.
//!
//! Reading ([`read_records`], and on it [`read_csv`] and
//! [`super::rundata::read_series`]): the first non-blank line is the header, blank lines
//! are skipped, cells are trimmed, quoted cells are understood, and every error names the
//! file and the line.

use std::fs;
use std::io;
use std::path::Path;

pub use csv::QuoteStyle;

use super::read::{bad, ReadError};

/// A CSV writer on `w` in eyeshell's dialect, quoting cells by `quote`. Rows may have any
/// number of cells. Call `flush` to push what is written to `w`.
pub fn csv_writer<W: io::Write>(w: W, quote: QuoteStyle) -> csv::Writer<W> {
    csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .quote_style(quote)
        .flexible(true)
        .from_writer(w)
}

/// A whole table as CSV text: the header, then the rows.
pub fn csv_bytes<H, R, C>(header: H, rows: R, quote: QuoteStyle) -> io::Result<Vec<u8>>
where
    H: IntoIterator,
    H::Item: AsRef<[u8]>,
    R: IntoIterator<Item = C>,
    C: IntoIterator,
    C::Item: AsRef<[u8]>,
{
    let mut w = csv_writer(Vec::new(), quote);
    w.write_record(header)?;
    for row in rows {
        w.write_record(row)?;
    }
    w.into_inner().map_err(|e| e.into_error())
}

/// A CSV file of numbers with a header line.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// The values of column `name`, if there is one.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let j = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[j]).collect())
    }
}

/// One line of a CSV file as read.
#[derive(Clone, Debug)]
pub struct Record<'a> {
    /// Its line number in the file (from 1).
    pub line: u64,
    /// The line as written (for error messages).
    pub text: &'a str,
    /// The cells, trimmed.
    pub cells: csv::StringRecord,
}

/// A CSV file read: the header (None for a file with no line) and the records after it.
#[derive(Clone, Debug)]
pub struct Records {
    pub header: Option<Vec<String>>,
    text: String,
    records: Vec<(u64, u64, csv::StringRecord)>,
}

impl Records {
    /// The records after the header, in order.
    pub fn iter(&self) -> impl Iterator<Item = Record<'_>> {
        self.records.iter().map(|(line, byte, cells)| {
            let rest = self.text.get(*byte as usize..).unwrap_or_default();
            Record {
                line: *line,
                text: rest.lines().next().unwrap_or_default(),
                cells: cells.clone(),
            }
        })
    }
}

/// Read the CSV file `path`: its header (the first non-blank line) and its records.
/// Errors (bad input) name the file.
pub fn read_records(path: &Path) -> Result<Records, ReadError> {
    let text = fs::read_to_string(path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut header = None;
    let mut records = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            bad(format!("{}: line {line}: {e}", path.display()))
        })?;
        // A line of blanks only.
        if record.len() == 1 && record[0].is_empty() {
            continue;
        }
        let (line, byte) = record.position().map_or((0, 0), |p| (p.line(), p.byte()));
        if header.is_none() {
            header = Some(record.iter().map(str::to_string).collect());
        } else {
            records.push((line, byte, record));
        }
    }
    Ok(Records {
        header,
        text,
        records,
    })
}

/// Read a CSV file of numbers (the header, then rows of as many values).
pub fn read_csv(path: &Path) -> Result<Table, ReadError> {
    let records = read_records(path)?;
    let columns = records
        .header
        .clone()
        .ok_or_else(|| bad(format!("{}: empty file (no header)", path.display())))?;
    let mut rows = Vec::new();
    for r in records.iter() {
        let row = r
            .cells
            .iter()
            .map(str::parse::<f64>)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|_| {
                bad(format!(
                    "{}: line {}: not a row of numbers: {:?}",
                    path.display(),
                    r.line,
                    r.text
                ))
            })?;
        if row.len() != columns.len() {
            return Err(bad(format!(
                "{}: line {}: {} values for {} columns",
                path.display(),
                r.line,
                row.len(),
                columns.len()
            )));
        }
        rows.push(row);
    }
    Ok(Table { columns, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quoting sweep.csv had before the csv crate: a cell is quoted when it holds a
    /// comma, a quote or a line break, quotes doubled.
    fn old_field(s: &str) -> String {
        if s.contains([',', '"', '\n', '\r']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    }

    #[test]
    fn necessary_quoting_is_the_old_sweep_quoting() {
        let cells = [
            "plain",
            "",
            "a, b",
            "say \"hi\"",
            "two\nlines",
            "cr\rhere",
            "1e-3",
            "≤ 0: (Σ = 1)",
            "#hash",
            " spaced ",
        ];
        let text = csv_bytes(
            ["h1", "h2"],
            [cells.iter(), cells.iter()],
            QuoteStyle::Necessary,
        )
        .unwrap();
        let line = cells
            .iter()
            .map(|c| old_field(c))
            .collect::<Vec<_>>()
            .join(",");
        assert_eq!(
            String::from_utf8(text).unwrap(),
            format!("h1,h2\n{line}\n{line}\n")
        );
    }

    #[test]
    fn never_quoting_joins_with_commas() {
        let text = csv_bytes(
            ["run", "x"],
            [["paper (a, b)", "1e0"], ["c", ""]],
            QuoteStyle::Never,
        )
        .unwrap();
        assert_eq!(text, b"run,x\npaper (a, b),1e0\nc,\n");
    }

    #[test]
    fn reading_skips_blanks_trims_and_names_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        fs::write(&path, "\n a , b\n1, 2\n  \n3,4\r\n").unwrap();
        let t = read_csv(&path).unwrap();
        assert_eq!(t.columns, vec!["a", "b"]);
        assert_eq!(t.rows, vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
        fs::write(&path, "a,b\n1,2\n1,x\n").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(
            e.ends_with("t.csv: line 3: not a row of numbers: \"1,x\""),
            "{e}"
        );
        fs::write(&path, "a,b\n1,2,3\n").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(e.ends_with("t.csv: line 2: 3 values for 2 columns"), "{e}");
        fs::write(&path, "\n\n").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(e.ends_with("t.csv: empty file (no header)"), "{e}");
        let e = read_csv(&dir.path().join("none.csv")).unwrap_err();
        assert!(e.bad_input && e.to_string().contains("none.csv: "), "{e}");
    }
}
