//! The output quantities ([`eyeshell_core::outputs`], re-exported here) laid out in files:
//! a row of series.csv and history.csv ([`series_columns`], [`series_cells`]), the
//! measures of a run as summary.json's `final` and a sweep run's result.json hold them
//! ([`Measures`]), and docs/guide/outputs.md ([`reference`]). The table itself is the
//! core's, being the model's; this module is the files crate's because the layouts are
//! files' (tests/cli/docs.rs checks outputs.md against [`reference`]).

use std::fmt;

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserializer, Serialize, Serializer};

pub use eyeshell_core::outputs::*;

use crate::growth::SeriesRow;
use crate::number::format_value;

/// The column series.csv, history.csv, sensitivities.csv and peripheral.csv end in when the
/// scene counts in ages (time.unit): the age of the row's t, in that unit.
pub const AGE_COLUMN: &str = "age";

/// The columns of series.csv and history.csv (before the `age` of a scene with
/// time.unit).
pub fn series_columns() -> Vec<&'static str> {
    series_quantities().iter().map(|q| q.name).collect()
}

/// The text of one cell ([`format_value`] for a number).
pub fn cell_text(cell: Cell) -> String {
    match cell {
        Cell::Number(x) => format_value(x),
        Cell::Text(s) => s.to_string(),
    }
}

/// The cells of `row` in series.csv's columns.
pub fn series_cells(row: &SeriesRow) -> Vec<String> {
    series_quantities()
        .iter()
        .map(|q| cell_text(q.value(row)))
        .collect()
}

/// The value of one measure as a file holds it.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A number (NaN where it has none: `null` in JSON).
    Number(f64),
    /// A word (the class).
    Text(String),
}

impl Value {
    /// The number (NaN for a word).
    pub fn number(&self) -> f64 {
        match self {
            Value::Number(x) => *x,
            Value::Text(_) => f64::NAN,
        }
    }

    /// Its text in a CSV cell.
    pub fn text(&self) -> String {
        match self {
            Value::Number(x) => format_value(*x),
            Value::Text(s) => s.clone(),
        }
    }
}

/// The measures of the eye at one time: each of the [`quantities`] by name, in the
/// table's order. JSON writes them as keys of the object holding them (`final` of
/// summary.json, a sweep run's result.json), numbers as numbers (NaN as null) and the
/// class as a string.
#[derive(Clone, Debug, PartialEq)]
pub struct Measures(pub Vec<(&'static str, Value)>);

impl Default for Measures {
    /// No value of each quantity: NaN, and an empty class.
    fn default() -> Measures {
        Measures(quantities().iter().map(|q| (q.name, no_value(q))).collect())
    }
}

fn no_value(q: &Quantity) -> Value {
    match q.kind {
        Kind::Number => Value::Number(f64::NAN),
        Kind::Class => Value::Text(String::new()),
    }
}

impl Measures {
    /// The measures of `row`.
    pub fn of(row: &SeriesRow) -> Measures {
        Measures(
            quantities()
                .iter()
                .map(|q| {
                    let v = match q.value(row) {
                        Cell::Number(x) => Value::Number(x),
                        Cell::Text(s) => Value::Text(s.to_string()),
                    };
                    (q.name, v)
                })
                .collect(),
        )
    }

    /// The value of `name`, if it is a quantity.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, v)| v)
    }

    /// The number of `name` (NaN without one).
    pub fn number(&self, name: &str) -> f64 {
        self.get(name).map_or(f64::NAN, Value::number)
    }

    /// The class (empty without one).
    pub fn class(&self) -> &str {
        match self.get("class") {
            Some(Value::Text(s)) => s,
            _ => "",
        }
    }

    /// The numeric measures, (name, value), in order.
    pub fn numbers(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.0.iter().filter_map(|(n, v)| match v {
            Value::Number(x) => Some((*n, *x)),
            Value::Text(_) => None,
        })
    }

    /// Read from the keys of a JSON object: a quantity missing reads as no value.
    pub fn deserialize_lenient<'de, D: Deserializer<'de>>(d: D) -> Result<Measures, D::Error> {
        d.deserialize_map(MeasuresVisitor { strict: false })
    }

    /// The same, but a quantity missing that every file has (not [`Quantity::added_later`])
    /// is an error: a file that lacks it is not one eyeshell wrote whole.
    pub fn deserialize_strict<'de, D: Deserializer<'de>>(d: D) -> Result<Measures, D::Error> {
        d.deserialize_map(MeasuresVisitor { strict: true })
    }
}

impl Serialize for Measures {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, v) in &self.0 {
            match v {
                Value::Number(x) if x.is_finite() => map.serialize_entry(name, x)?,
                Value::Number(_) => map.serialize_entry(name, &None::<f64>)?,
                Value::Text(t) => map.serialize_entry(name, t)?,
            }
        }
        map.end()
    }
}

struct MeasuresVisitor {
    strict: bool,
}

/// One measure's JSON value: a number, null or a string.
struct Any(Value);

impl<'de> serde::Deserialize<'de> for Any {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Any, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Any;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, null or a string")
            }
            fn visit_f64<E>(self, x: f64) -> Result<Any, E> {
                Ok(Any(Value::Number(x)))
            }
            fn visit_i64<E>(self, x: i64) -> Result<Any, E> {
                Ok(Any(Value::Number(x as f64)))
            }
            fn visit_u64<E>(self, x: u64) -> Result<Any, E> {
                Ok(Any(Value::Number(x as f64)))
            }
            fn visit_unit<E>(self) -> Result<Any, E> {
                Ok(Any(Value::Number(f64::NAN)))
            }
            fn visit_none<E>(self) -> Result<Any, E> {
                Ok(Any(Value::Number(f64::NAN)))
            }
            fn visit_str<E>(self, s: &str) -> Result<Any, E> {
                Ok(Any(Value::Text(s.to_string())))
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, mut a: A) -> Result<Any, A::Error> {
                // Not a measure's value: skipped whole (it is another key's).
                while a.next_element::<de::IgnoredAny>()?.is_some() {}
                Ok(Any(Value::Text(String::new())))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut a: A) -> Result<Any, A::Error> {
                while a.next_entry::<de::IgnoredAny, de::IgnoredAny>()?.is_some() {}
                Ok(Any(Value::Text(String::new())))
            }
            fn visit_bool<E>(self, _: bool) -> Result<Any, E> {
                Ok(Any(Value::Text(String::new())))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Visitor<'de> for MeasuresVisitor {
    type Value = Measures;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("the measures of the eye")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Measures, A::Error> {
        let table = quantities();
        let mut found: Vec<Option<Value>> = vec![None; table.len()];
        while let Some(key) = map.next_key::<String>()? {
            let value = map.next_value::<Any>()?.0;
            if let Some(i) = table.iter().position(|q| q.name == key) {
                let ok = matches!(
                    (&value, table[i].kind),
                    (Value::Number(_), Kind::Number) | (Value::Text(_), Kind::Class)
                );
                if !ok {
                    return Err(de::Error::custom(format!(
                        "{key}: not a {}",
                        match table[i].kind {
                            Kind::Number => "number",
                            Kind::Class => "class",
                        }
                    )));
                }
                found[i] = Some(value);
            }
        }
        let mut out = Vec::with_capacity(table.len());
        for (q, v) in table.iter().zip(found) {
            match v {
                Some(v) => out.push((q.name, v)),
                None if self.strict && !q.added_later => {
                    return Err(de::Error::missing_field(q.name));
                }
                None => out.push((q.name, no_value(q))),
            }
        }
        Ok(Measures(out))
    }
}

/// docs/guide/outputs.md: every output quantity, where it is written, and how numbers
/// are written, from the table (tests/cli/docs.rs keeps the file equal to it).
pub fn reference() -> String {
    let mut md = String::from(
        "# Outputs\n\n\
         What this chapter is for: what each column of eyeshell's tables means, its unit and how \
         it is computed. Generated from the table of outputs (`crates/core/src/outputs.rs`) by \
         `eyeshell::outputs::reference`; after changing the table, rewrite this page with \
         `EYESHELL_WRITE_DOCS=1 cargo test --release --test cli docs::outputs`.\n\n\
         ## The measures of the eye\n\n\
         One entry per quantity, in the order of the columns. The same names head the columns \
         of a growth run's `series.csv` and `history.csv` (after `t`), a sweep's `sweep.csv` \
         (after `kind` and `t`) and a cohort's `series.csv` (after `run`), key `final` of a \
         growth run's `summary.json` and a sweep run's `result.json`, name the outputs of \
         `population.json`, `population.csv` and `sobol.csv`, the columns of Python's \
         `Growth.series`, `Growth.history` and `SweepResults.to_frame()`, and label the plots' \
         axes.\n\n\
         | column | unit | what it is | how it is computed |\n\
         | --- | --- | --- | --- |\n",
    );
    for q in series_quantities() {
        let unit = if q.unit.is_empty() { "" } else { q.unit };
        md.push_str(&format!(
            "| `{}` | {} | {} | {} |\n",
            q.name, unit, q.description, q.computed
        ));
    }
    md.push_str(&format!(
        "\nWith `time.unit` set, `series.csv`, `history.csv`, `sensitivities.csv` and \
         `peripheral.csv` end in an `{}` column: the age of the row's `t`, in that unit; so \
         does a table cohort's one `series.csv`, and each snapshot file (its age on every \
         node). A sweep's `sweep.csv` and a cohort's \
         `population.csv` give it after `t`, `population.json` at each time (`age`), at the \
         final time (`final_age`) with its unit (`age_unit`), a run's `result.json` as `age`, \
         and `population.png` is drawn against it.\n\n\
         ## Numbers in the CSV files\n\n\
         Each number is the shortest decimal that reads back to the same double, written as \
         Python's `repr` writes it: `22.63564555774848`, `8.0`, `400.0`, `0.0001`; in exponent \
         form below 1e-4 and from 1e16 on (`1e-05`, `1e+16`, `-2.5e+17`, `5e-324`). A value \
         that could not be computed is `NaN`; the infinities are `inf` and `-inf`. Files \
         written by earlier versions (`2.263564555774848e1`, `8e0`) read the same: every \
         reader of eyeshell, Python's `float`, NumPy and pandas read both to the same double.\n\n\
         ## Keys and files\n\n\
         Files: `series.csv`, `history.csv`, `summary.json` (`final`), a sweep's `sweep.csv`, \
         `population.json`, `population.csv`, `sobol.csv`, a run's `result.json`. Keys: \
         `output.times`, `output.history_points`, `time.unit`, `stimulus.classify`, \
         `stimulus.refraction_nm`.\n",
        AGE_COLUMN
    ));
    md
}
