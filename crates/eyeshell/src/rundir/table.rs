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

use std::io;
use std::path::Path;

pub use csv::QuoteStyle;

use super::read::{bad, read_text, ReadError, MAX_CSV_BYTES};
use crate::text::excerpt;

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
    let text = read_text(path, MAX_CSV_BYTES)?;
    let mut header = None;
    let mut records = Vec::new();
    scan(path, &text, |line, byte, record| {
        if header.is_none() {
            header = Some(record.iter().map(str::to_string).collect());
        } else {
            records.push((line, byte, record.clone()));
        }
        Ok(())
    })?;
    Ok(Records {
        header,
        text,
        records,
    })
}

/// Hand every record of the CSV text of `path` to `each(line, byte offset, cells)` as it is
/// parsed (so that a bad line stops the reading there, however long the file), skipping
/// blank lines. A text whose last line has no line end was cut short (eyeshell ends every
/// line, and appends whole lines), and is refused.
fn scan(
    path: &Path,
    text: &str,
    mut each: impl FnMut(u64, u64, &csv::StringRecord) -> Result<(), ReadError>,
) -> Result<(), ReadError> {
    if !text.is_empty() && !text.ends_with('\n') {
        return Err(bad(format!(
            "{}: line {}: the file ends inside this line (cut short?): {:?}",
            path.display(),
            text.lines().count(),
            excerpt(text.lines().last().unwrap_or_default(), EXCERPT)
        )));
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => return Ok(()),
            Ok(true) => {}
            Err(e) => {
                let line = e.position().map_or(0, |p| p.line());
                return Err(bad(format!(
                    "{}: line {line}: {}",
                    path.display(),
                    excerpt(&e.to_string(), EXCERPT)
                )));
            }
        }
        // A line of blanks only.
        if record.len() == 1 && record[0].is_empty() {
            continue;
        }
        let (line, byte) = record.position().map_or((0, 0), |p| (p.line(), p.byte()));
        each(line, byte, &record)?;
    }
}

/// The characters of a line (or cell) an error message quotes.
const EXCERPT: usize = 80;

/// Read a CSV file of numbers (the header, then rows of as many values). Each row is
/// checked as it is read.
pub fn read_csv(path: &Path) -> Result<Table, ReadError> {
    let text = read_text(path, MAX_CSV_BYTES)?;
    let mut columns: Option<Vec<String>> = None;
    let mut rows = Vec::new();
    scan(path, &text, |line, _, record| {
        let Some(columns) = &columns else {
            columns = Some(record.iter().map(str::to_string).collect());
            return Ok(());
        };
        if record.len() != columns.len() {
            return Err(bad(format!(
                "{}: line {line}: {} values for {} columns",
                path.display(),
                record.len(),
                columns.len()
            )));
        }
        let row = record
            .iter()
            .enumerate()
            .map(|(j, cell)| {
                cell.parse::<f64>().map_err(|_| {
                    bad(format!(
                        "{}: line {line}: value {} ({}) is not a number: {:?}",
                        path.display(),
                        j + 1,
                        excerpt(&columns[j], EXCERPT),
                        excerpt(cell, EXCERPT)
                    ))
                })
            })
            .collect::<Result<Vec<f64>, _>>()?;
        rows.push(row);
        Ok(())
    })?;
    let columns =
        columns.ok_or_else(|| bad(format!("{}: empty file (no header)", path.display())))?;
    Ok(Table { columns, rows })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

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
            e.ends_with("t.csv: line 3: value 2 (b) is not a number: \"x\""),
            "{e}"
        );
        fs::write(&path, "a,b\n1,2,3\n").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(e.ends_with("t.csv: line 2: 3 values for 2 columns"), "{e}");
        fs::write(&path, "\n\n").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(e.ends_with("t.csv: empty file (no header)"), "{e}");
        // Cut inside the last value, which still reads as a number.
        fs::write(&path, "a,b\n1,2\n3,4.12").unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(
            e.ends_with("t.csv: line 3: the file ends inside this line (cut short?): \"3,4.12\""),
            "{e}"
        );
        // A megabyte-long line is quoted in 80 characters.
        fs::write(&path, format!("a,b\n1,{}x\n", "9".repeat(1 << 20))).unwrap();
        let e = read_csv(&path).unwrap_err().to_string();
        assert!(e.len() < 200 && e.ends_with("9…\""), "{e}");
        let e = read_csv(&dir.path().join("none.csv")).unwrap_err();
        assert!(e.bad_input && e.to_string().contains("none.csv: "), "{e}");
    }
}
