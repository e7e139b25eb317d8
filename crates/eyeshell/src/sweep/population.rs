//! The population results of a sampled sweep ([`crate::scene::sample`]): `population.json`
//! and `population.csv` beside sweep.csv, and for `design = "saltelli"` the Sobol indices
//! (`sobol.csv`, and in population.json).
//!
//! For every output (axial length, equatorial radius, the two distances to the best-focus
//! surfaces, and any further numeric column of series.csv such as refraction_D) at the final
//! time and at each output time every eye reached: the mean, the standard deviation (n − 1),
//! the quantiles 0.05, 0.25, 0.5, 0.75 and 0.95 (linear interpolation between order
//! statistics, numpy's default), and their Monte Carlo standard errors: of the mean sd/√n;
//! of the sd √((m₄ − s⁴ (n−3)/(n−1)) / n) / (2 s) (the delta method on the variance); of
//! quantile p half the spread of the quantiles at p ± √(p(1−p)/n) (distribution-free, from
//! the binomial count below a quantile). Class shares with √(p(1−p)/n). Standard errors
//! are those of independent draws: for Latin-hypercube and Sobol designs they are upper
//! bounds. Only finished eyes count; a failed eye is counted as failed, never filled in.
//!
//! Sobol indices (Saltelli design, N base points, f_A, f_B, f_ABi): V the variance of f_A
//! and f_B together; first order S_i = mean((f_B − f̄) (f_ABi − f_A)) / V (Saltelli et al.
//! 2010, with f_B centred on the mean f̄ of f_A and f_B: the same limit, without the
//! variance a large mean multiplies in);
//! total S_Ti = mean((f_A − f_ABi)²) / (2V) (Jansen 1999). 95 % confidence intervals from
//! [`BOOTSTRAP`] resamples of the N base points (percentile intervals, seeded by the scene's
//! seed: reproducible).

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{json, Map, Value};

use crate::model::stimulus::Refraction;
use crate::rundir::{format_value, write_atomic, OutputError};
use crate::scene::sample::{Design, Resampler, Role, Sample, BOOTSTRAP};

use super::{RunRecord, RunStatus};

/// The population's statistics, beside sweep.csv.
pub const POPULATION_FILE: &str = "population.json";
/// The same as a table: one row per time and output.
pub const POPULATION_TABLE: &str = "population.csv";
/// The Sobol indices of a Saltelli design: one row per output and key.
pub const SOBOL_TABLE: &str = "sobol.csv";
/// The figure the command line draws beside them (`eyeshell sweep`, `sweep merge`):
/// claimed in the sweep's marker with the population files, so that a sweep that drew it
/// can be rerun, resumed, merged and read back.
pub const FIGURE_FILES: [&str; 2] = ["population.png", "population.svg"];
/// The quantiles reported.
pub const QUANTILES: [f64; 5] = [0.05, 0.25, 0.5, 0.75, 0.95];

/// Statistics of one output over the eyes.
#[derive(Clone, Debug, PartialEq)]
pub struct Stats {
    pub n: usize,
    pub mean: f64,
    pub sd: f64,
    pub quantiles: [f64; 5],
    pub mean_se: f64,
    pub sd_se: f64,
    pub quantiles_se: [f64; 5],
}

/// The statistics of `xs` (at least 2 values, all finite).
pub fn stats(xs: &[f64]) -> Stats {
    let n = xs.len();
    let nf = n as f64;
    let mean = xs.iter().sum::<f64>() / nf;
    let m2 = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / nf;
    let m4 = xs.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / nf;
    let var = m2 * nf / (nf - 1.0);
    let sd = var.sqrt();
    let mut sorted = xs.to_vec();
    sorted.sort_by(f64::total_cmp);
    let q = |p: f64| quantile(&sorted, p);
    let quantiles = QUANTILES.map(q);
    let quantiles_se = QUANTILES.map(|p| {
        let h = (p * (1.0 - p) / nf).sqrt();
        0.5 * (q((p + h).min(1.0)) - q((p - h).max(0.0)))
    });
    let var_s2 = ((m4 - var * var * (nf - 3.0) / (nf - 1.0)) / nf).max(0.0);
    let sd_se = if sd > 0.0 {
        var_s2.sqrt() / (2.0 * sd)
    } else {
        0.0
    };
    Stats {
        n,
        mean,
        sd,
        quantiles,
        mean_se: sd / nf.sqrt(),
        sd_se,
        quantiles_se,
    }
}

/// The p-quantile of sorted values: linear between order statistics (numpy's default).
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

/// First-order and total Sobol indices of one output and key, with 95 % intervals.
#[derive(Clone, Debug, PartialEq)]
pub struct Index {
    pub first: f64,
    pub first_ci: [f64; 2],
    pub total: f64,
    pub total_ci: [f64; 2],
}

/// The Sobol indices of each of k keys from `f[j] = [f_A, f_B, f_AB1, ..., f_ABk]` of the
/// N base points; None when the output does not vary.
pub fn sobol_indices(f: &[Vec<f64>], seed: u64) -> Option<Vec<Index>> {
    let n = f.len();
    let k = f.first()?.len().checked_sub(2)?;
    let estimate = |rows: &mut dyn Iterator<Item = &Vec<f64>>| -> Option<Vec<(f64, f64)>> {
        let rows: Vec<&Vec<f64>> = rows.collect();
        let m = rows.len() as f64;
        let all = rows.iter().flat_map(|r| [r[0], r[1]]);
        let mean = all.clone().sum::<f64>() / (2.0 * m);
        let v = all.map(|x| (x - mean).powi(2)).sum::<f64>() / (2.0 * m - 1.0);
        if !(v > 0.0) {
            return None;
        }
        Some(
            (0..k)
                .map(|i| {
                    // f_B centred: the same estimator, without the noise a large mean
                    // (an axial length of 20 mm varying by 0.03) multiplies in.
                    let s = rows
                        .iter()
                        .map(|r| (r[1] - mean) * (r[2 + i] - r[0]))
                        .sum::<f64>()
                        / m
                        / v;
                    let st =
                        rows.iter().map(|r| (r[0] - r[2 + i]).powi(2)).sum::<f64>() / (2.0 * m) / v;
                    (s, st)
                })
                .collect(),
        )
    };
    let point = estimate(&mut f.iter())?;
    let mut rng = Resampler::new(seed);
    let mut boots: Vec<Vec<(f64, f64)>> = Vec::with_capacity(BOOTSTRAP);
    for _ in 0..BOOTSTRAP {
        let pick: Vec<usize> = (0..n).map(|_| rng.below(n)).collect();
        if let Some(e) = estimate(&mut pick.iter().map(|&j| &f[j])) {
            boots.push(e);
        }
    }
    let ci = |i: usize, total: bool| -> [f64; 2] {
        let mut xs: Vec<f64> = boots
            .iter()
            .map(|b| if total { b[i].1 } else { b[i].0 })
            .collect();
        if xs.is_empty() {
            return [f64::NAN, f64::NAN];
        }
        xs.sort_by(f64::total_cmp);
        [quantile(&xs, 0.025), quantile(&xs, 0.975)]
    };
    Some(
        point
            .iter()
            .enumerate()
            .map(|(i, &(first, total))| Index {
                first,
                first_ci: ci(i, false),
                total,
                total_ci: ci(i, true),
            })
            .collect(),
    )
}

/// One row of an eye's series.csv: t, (output, value) of its numeric columns, its class.
type Row = (f64, Vec<(String, f64)>, String);
/// The population at one output time: t, each output's statistics, the class shares.
type AtTime = (f64, Vec<(String, Stats)>, Shares);
/// Each class's share and its standard error.
type Shares = BTreeMap<String, (f64, f64)>;
/// An output not every eye has: (output, how many eyes have it, how many eyes).
type Missing = (String, usize, usize);

/// One eye's outputs: (name, value) at the final time and, per output time, its row.
struct Eye {
    final_values: Vec<(String, f64)>,
    final_class: String,
    /// (t, [(output, value)], class) per row of series.csv.
    series: Vec<Row>,
    /// The age of each row (series.csv's `age` column), when the scene counts in ages.
    ages: Option<Vec<f64>>,
}

/// The finished eye of `record`, read from its result and the text of its series.csv
/// (`series`: None if it did not grow).
fn eye(record: &RunRecord, series: &dyn Fn(&RunRecord) -> Option<String>) -> Option<Eye> {
    if !matches!(record.status, RunStatus::Ok | RunStatus::Reused) {
        return None;
    }
    let r = record.result.as_ref()?;
    let mut final_values: Vec<(String, f64)> = r
        .eye
        .numbers()
        .map(|(name, x)| (name.to_string(), x))
        .collect();
    let text = series(record);
    if text.is_none() {
        // An elastic solve has no series and does not compute what needs growth (NaN in
        // its result, refraction_D): not a value missing, so not an output of its eyes.
        final_values.retain(|(_, x)| !x.is_nan());
    }
    let mut series = Vec::new();
    let mut ages = Vec::new();
    if let Some(text) = text {
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let t_at = header.iter().position(|h| *h == "t");
        let class_at = header.iter().position(|h| *h == "class");
        let age_at = header
            .iter()
            .position(|h| *h == crate::rundir::growth::AGE_COLUMN);
        for line in lines {
            let cells: Vec<&str> = line.split(',').collect();
            let Some(t) = t_at.and_then(|i| cells.get(i)?.parse::<f64>().ok()) else {
                continue;
            };
            if let Some(i) = age_at {
                let age = cells.get(i).and_then(|c| c.parse::<f64>().ok());
                ages.push(age.unwrap_or(f64::NAN));
            }
            let values: Vec<(String, f64)> = header
                .iter()
                .zip(&cells)
                // The age is the time's, not a measure of the eye.
                .filter(|(h, _)| !matches!(**h, "t" | "class" | crate::rundir::growth::AGE_COLUMN))
                .filter_map(|(h, c)| Some((h.to_string(), c.parse::<f64>().ok()?)))
                .collect();
            let class = class_at
                .and_then(|i| cells.get(i))
                .map_or(String::new(), |c| c.to_string());
            series.push((t, values, class));
        }
        // Outputs series.csv has at the final time and the result has not: a column beyond
        // the table, or one an earlier eyeshell's result.json did not record (NaN there).
        if let Some((_, last, _)) = series.last() {
            for (h, x) in last {
                match final_values.iter_mut().find(|(k, _)| k == h) {
                    Some((_, v)) if v.is_nan() => *v = *x,
                    Some(_) => {}
                    None => final_values.push((h.clone(), *x)),
                }
            }
        }
    }
    let ages = (!ages.is_empty() && ages.len() == series.len()).then_some(ages);
    Some(Eye {
        final_values,
        final_class: r.eye.class().to_string(),
        series,
        ages,
    })
}

/// The statistics of each output over `rows` (one per eye), in the order the outputs
/// first appear: over the eyes that have the output finite, `Stats::n` saying how many. An
/// output some eyes lack (refraction_D is NaN beyond ±25 D) is never dropped for them, nor
/// filled in: the second list holds, per output that not every eye has, (output, how many
/// have it, how many eyes), and an output fewer than 2 eyes have has no statistics there.
fn outputs<'a>(
    rows: impl Iterator<Item = &'a [(String, f64)]> + Clone,
) -> (Vec<(String, Stats)>, Vec<Missing>) {
    let eyes = rows.clone().count();
    let mut names: Vec<&String> = Vec::new();
    for r in rows.clone() {
        for (name, _) in r {
            if !names.contains(&name) {
                names.push(name);
            }
        }
    }
    let mut stats_of = Vec::new();
    let mut missing = Vec::new();
    for name in names {
        let xs: Vec<f64> = rows
            .clone()
            .filter_map(|r| r.iter().find(|(k, _)| k == name).map(|(_, x)| *x))
            .filter(|x| x.is_finite())
            .collect();
        if xs.len() < eyes {
            missing.push((name.clone(), xs.len(), eyes));
        }
        if xs.len() >= 2 {
            stats_of.push((name.clone(), stats(&xs)));
        }
    }
    (stats_of, missing)
}

/// The note of an output that not every eye has (`outputs`' second list), at `when`.
fn missing_note((name, have, eyes): &Missing, when: &str) -> String {
    let why = if name == "refraction_D" {
        " (NaN: the refraction is traced over -25 to +25 D)"
    } else {
        " (NaN)"
    };
    let over = if *have >= 2 {
        format!("its statistics are over the {have} that have it")
    } else {
        "too few have it for statistics, so it has none".to_string()
    };
    format!(
        "{name}{when}: {} of {eyes} eyes have no value{why}; {over}",
        eyes - have
    )
}

fn shares<'a>(classes: impl Iterator<Item = &'a str>) -> BTreeMap<String, (f64, f64)> {
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    let mut n = 0;
    for c in classes {
        n += 1;
        if !c.is_empty() {
            *counts.entry(c.to_string()).or_default() += 1;
        }
    }
    counts
        .into_iter()
        .map(|(c, k)| {
            let p = k as f64 / n as f64;
            (c, (p, (p * (1.0 - p) / n as f64).sqrt()))
        })
        .collect()
}

fn stats_json(s: &Stats) -> Value {
    let q = |xs: &[f64; 5]| -> Value {
        Value::Object(
            QUANTILES
                .iter()
                .zip(xs)
                .map(|(p, x)| (format!("{p}"), num(*x)))
                .collect(),
        )
    };
    json!({
        "n": s.n,
        "mean": num(s.mean),
        "sd": num(s.sd),
        "quantiles": q(&s.quantiles),
        "mean_se": num(s.mean_se),
        "sd_se": num(s.sd_se),
        "quantiles_se": q(&s.quantiles_se),
    })
}

fn num(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

fn shares_json(s: &BTreeMap<String, (f64, f64)>) -> Value {
    Value::Object(
        s.iter()
            .map(|(c, (p, se))| (c.clone(), json!({ "share": num(*p), "se": num(*se) })))
            .collect(),
    )
}

/// The files written, relative to the sweep's directory.
pub struct Written {
    pub files: Vec<&'static str>,
    /// Eyes (or Saltelli rows) that finished, and all of them.
    pub finished: usize,
    pub total: usize,
    /// What the statistics could not include, as population.json's `notes` say it.
    pub notes: Vec<String>,
}

/// The Sobol indices of each output by key.
type Sobol = Vec<(String, Vec<(String, Index)>)>;

/// The population's statistics, as the files say them.
struct Population {
    /// The statistics of each output at the final time, and the class shares.
    final_stats: Vec<(String, Stats)>,
    final_shares: Shares,
    /// The same at each output time every member eye reached.
    per_time: Vec<AtTime>,
    /// When the eyes count in ages: the age of the final time and of each of `per_time`'s
    /// (NaN where the eyes' ages differ: a cohort whose clocks were drawn).
    ages: Option<(f64, Vec<f64>)>,
    /// Saltelli designs: the indices.
    sobol: Option<Sobol>,
    /// Eyes that finished, and all of them (Saltelli: the A and B rows).
    finished: usize,
    total: usize,
    notes: Vec<String>,
}

/// What population.json names: the sweep, and the unit of its ages (time.unit) if any.
#[derive(Clone, Copy, Debug)]
pub struct Names<'a> {
    pub sweep: &'a str,
    pub age_unit: Option<&'a str>,
}

/// Write population.json, population.csv and (Saltelli) sobol.csv into `out` from the
/// finished runs of `records` (in the sweep's run order, as the sample names them), each
/// eye's series.csv text given by `series` (from its run directory, or the sweep's table).
pub fn write(
    out: &Path,
    names: Names<'_>,
    sample: &Sample,
    records: &[RunRecord],
    series: &dyn Fn(&RunRecord) -> Option<String>,
) -> Result<Written, OutputError> {
    let pop = Population::of(sample, records, series);
    let text = population_json(&pop, names, sample);
    // Every file the population adds to the sweep's directory is claimed in its marker
    // before it is written: an entry the marker does not list is somebody else's, and a
    // rerun, `--resume`, a second merge or `sweep status` would refuse the directory.
    let mut claimed = vec![POPULATION_FILE, POPULATION_TABLE];
    if pop.sobol.is_some() {
        claimed.push(SOBOL_TABLE);
    }
    claimed.extend(FIGURE_FILES);
    crate::rundir::owner::claim(out, &claimed)?;
    let io = |file: &str, e: std::io::Error| OutputError::Io {
        path: out.join(file),
        source: e,
    };
    write_atomic(&out.join(POPULATION_FILE), text.as_bytes())
        .map_err(|e| io(POPULATION_FILE, e))?;
    write_atomic(&out.join(POPULATION_TABLE), population_csv(&pop).as_bytes())
        .map_err(|e| io(POPULATION_TABLE, e))?;
    let mut files = vec![POPULATION_FILE, POPULATION_TABLE];
    if let Some(sobol) = &pop.sobol {
        write_atomic(&out.join(SOBOL_TABLE), sobol_csv(sobol).as_bytes())
            .map_err(|e| io(SOBOL_TABLE, e))?;
        files.push(SOBOL_TABLE);
    }
    Ok(Written {
        files,
        finished: pop.finished,
        total: pop.total,
        notes: pop.notes,
    })
}

impl Population {
    /// The statistics of the finished eyes of `records` (see [`write`]).
    fn of(
        sample: &Sample,
        records: &[RunRecord],
        series: &dyn Fn(&RunRecord) -> Option<String>,
    ) -> Population {
        let eyes: Vec<Option<Eye>> = records.iter().map(|r| eye(r, series)).collect();
        // The population: every eye (for Saltelli, the A and B rows: draws of the cohort).
        let members: Vec<&Eye> = eyes
            .iter()
            .enumerate()
            .filter(|(i, _)| !matches!(sample.role(*i).0, Some(Role::AB(_))))
            .filter_map(|(_, e)| e.as_ref())
            .collect();
        let total = (0..records.len())
            .filter(|&i| !matches!(sample.role(i).0, Some(Role::AB(_))))
            .count();
        let (final_stats, final_missing) =
            outputs(members.iter().map(|e| e.final_values.as_slice()));
        let final_shares = shares(members.iter().map(|e| e.final_class.as_str()));
        let mut notes: Vec<String> = final_missing
            .iter()
            .map(|m| missing_note(m, " at the final time"))
            .collect();
        let unclassed = members
            .iter()
            .filter(|e| e.final_class == Refraction::Unknown.as_str())
            .count();
        if unclassed > 0 {
            notes.push(format!(
                "{unclassed} of {} eyes could not be classed at the final time (class \"unknown\": stimulus.classify = \"dioptres\" and refraction_D NaN, beyond -25 to +25 D); the class shares are over all {} eyes, \"unknown\" among them",
                members.len(),
                members.len()
            ));
        }
        let (per_time, time_notes) = per_time(&members);
        notes.extend(time_notes);
        let sobol = match sample.design {
            Design::Saltelli => Some(sobol_of(sample, &eyes, &final_stats)),
            _ => None,
        };
        if let Some(sobol) = &sobol {
            notes.extend(sobol_note(sobol));
        }
        let ages = ages_of(&members, &per_time);
        Population {
            final_stats,
            final_shares,
            per_time,
            ages,
            sobol,
            finished: members.len(),
            total,
            notes,
        }
    }
}

/// The age at the final time and at each time of `per_time`, when every member counts in
/// ages: the one age all members have there, else NaN.
fn ages_of(members: &[&Eye], per_time: &[AtTime]) -> Option<(f64, Vec<f64>)> {
    if members.is_empty() || members.iter().any(|e| e.ages.is_none()) {
        return None;
    }
    let common = |at: &dyn Fn(&Eye) -> Option<f64>| {
        let first = at(members[0]).unwrap_or(f64::NAN);
        let same = members
            .iter()
            .all(|e| at(e).is_some_and(|a| a.to_bits() == first.to_bits()));
        if same {
            first
        } else {
            f64::NAN
        }
    };
    let last = common(&|e: &Eye| e.ages.as_ref()?.last().copied());
    let each = per_time
        .iter()
        .map(|(t, _, _)| {
            common(&|e: &Eye| {
                let k = e.series.iter().position(|(s, _, _)| s == t)?;
                e.ages.as_ref()?.get(k).copied()
            })
        })
        .collect();
    Some((last, each))
}

/// The statistics at each output time every member eye reached (exactly the same t), and
/// the notes of outputs some eyes lack there (one per output, with at how many times).
fn per_time(members: &[&Eye]) -> (Vec<AtTime>, Vec<String>) {
    let mut times: Vec<f64> = members
        .first()
        .map(|e| e.series.iter().map(|(t, _, _)| *t).collect())
        .unwrap_or_default();
    times.retain(|t| {
        members
            .iter()
            .all(|e| e.series.iter().any(|(s, _, _)| s == t))
    });
    let mut missing_at: Vec<(String, usize)> = Vec::new();
    let per_time: Vec<AtTime> = times
        .iter()
        .map(|&t| {
            let rows: Vec<(&[(String, f64)], &str)> = members
                .iter()
                .filter_map(|e| {
                    e.series
                        .iter()
                        .find(|(s, _, _)| *s == t)
                        .map(|(_, v, c)| (v.as_slice(), c.as_str()))
                })
                .collect();
            let (stats_at, missing) = outputs(rows.iter().map(|(v, _)| *v));
            for (name, _, _) in missing {
                match missing_at.iter_mut().find(|(k, _)| *k == name) {
                    Some((_, count)) => *count += 1,
                    None => missing_at.push((name, 1)),
                }
            }
            (t, stats_at, shares(rows.iter().map(|(_, c)| *c)))
        })
        .collect();
    let notes = missing_at
        .iter()
        .map(|(name, count)| {
            format!(
                "{name}: some eyes have no value at {count} of {} output times; the statistics there are over the eyes that have it (each time's n)",
                times.len()
            )
        })
        .collect();
    (per_time, notes)
}

/// The text of population.json.
fn population_json(pop: &Population, names: Names<'_>, sample: &Sample) -> String {
    let object = |s: &[(String, Stats)]| -> Value {
        Value::Object(s.iter().map(|(k, v)| (k.clone(), stats_json(v))).collect())
    };
    let mut doc = Map::new();
    doc.insert("sweep".into(), json!(names.sweep));
    doc.insert("design".into(), json!(sample.design.name()));
    doc.insert("seed".into(), json!(sample.seed));
    doc.insert(
        "keys".into(),
        json!(sample
            .keys
            .iter()
            .map(|(k, _)| k.clone())
            .collect::<Vec<_>>()),
    );
    doc.insert("eyes".into(), json!(pop.total));
    doc.insert("eyes_finished".into(), json!(pop.finished));
    doc.insert("eyes_failed".into(), json!(pop.total - pop.finished));
    doc.insert("final".into(), object(&pop.final_stats));
    if let Some((age, _)) = &pop.ages {
        doc.insert("final_age".into(), num(*age));
        if let Some(unit) = names.age_unit {
            doc.insert("age_unit".into(), json!(unit));
        }
    }
    // Only where there is something to say: a cohort every eye of which has every output
    // writes the bytes it always wrote.
    if !pop.notes.is_empty() {
        doc.insert("notes".into(), json!(pop.notes));
    }
    doc.insert("classes".into(), shares_json(&pop.final_shares));
    doc.insert(
        "times".into(),
        Value::Array(
            pop.per_time
                .iter()
                .enumerate()
                .map(|(k, (t, s, c))| {
                    let mut at =
                        json!({ "t": num(*t), "outputs": object(s), "classes": shares_json(c) });
                    if let Some((_, ages)) = &pop.ages {
                        at["age"] = num(ages[k]);
                    }
                    at
                })
                .collect(),
        ),
    );
    if let Some(sobol) = &pop.sobol {
        doc.insert("sobol".into(), sobol_json(sobol));
    }
    let mut text = serde_json::to_string_pretty(&Value::Object(doc)).unwrap_or_default();
    text.push('\n');
    text
}

/// population.json's `sobol`: by output, by key, the indices and their intervals.
fn sobol_json(sobol: &Sobol) -> Value {
    let index = |ix: &Index| {
        json!({
            "first": num(ix.first),
            "first_ci": [num(ix.first_ci[0]), num(ix.first_ci[1])],
            "total": num(ix.total),
            "total_ci": [num(ix.total_ci[0]), num(ix.total_ci[1])],
        })
    };
    Value::Object(
        sobol
            .iter()
            .map(|(output, indices)| {
                let by_key = indices
                    .iter()
                    .map(|(key, ix)| (key.clone(), index(ix)))
                    .collect();
                (output.clone(), Value::Object(by_key))
            })
            .collect(),
    )
}

/// The text of population.csv: t ("final" for the final time), its age when the eyes count
/// in ages, output, then the statistics; class shares as rows `class=myopic` with the share
/// as the mean.
fn population_csv(pop: &Population) -> String {
    let mut csv = String::from(if pop.ages.is_some() {
        "t,age,output,n,mean,sd"
    } else {
        "t,output,n,mean,sd"
    });
    for p in QUANTILES {
        csv.push_str(&format!(",q{p}"));
    }
    csv.push_str(",mean_se,sd_se");
    for p in QUANTILES {
        csv.push_str(&format!(",q{p}_se"));
    }
    csv.push('\n');
    let rows = |csv: &mut String, t: &str, s: &[(String, Stats)], c: &Shares, n: usize| {
        for (k, st) in s {
            csv.push_str(&format!(
                "{t},{k},{},{},{}",
                st.n,
                format_value(st.mean),
                format_value(st.sd)
            ));
            for q in st.quantiles {
                csv.push_str(&format!(",{}", format_value(q)));
            }
            csv.push_str(&format!(
                ",{},{}",
                format_value(st.mean_se),
                format_value(st.sd_se)
            ));
            for q in st.quantiles_se {
                csv.push_str(&format!(",{}", format_value(q)));
            }
            csv.push('\n');
        }
        for (class, (p, se)) in c {
            csv.push_str(&format!(
                "{t},class={class},{n},{},,,,,,,{},,,,,,\n",
                format_value(*p),
                format_value(*se)
            ));
        }
    };
    let when = |t: String, age: Option<f64>| match age {
        Some(a) => format!("{t},{}", format_value(a)),
        None => t,
    };
    let ages = pop.ages.as_ref();
    rows(
        &mut csv,
        &when("final".into(), ages.map(|(a, _)| *a)),
        &pop.final_stats,
        &pop.final_shares,
        pop.finished,
    );
    for (k, (t, s, c)) in pop.per_time.iter().enumerate() {
        let age = ages.map(|(_, each)| each[k]);
        rows(&mut csv, &when(format_value(*t), age), s, c, pop.finished);
    }
    csv
}

/// The text of sobol.csv: one row per output and key.
fn sobol_csv(sobol: &Sobol) -> String {
    let mut csv =
        String::from("output,key,first,first_low,first_high,total,total_low,total_high\n");
    for (output, indices) in sobol {
        for (key, ix) in indices {
            csv.push_str(&format!(
                "{output},{key},{},{},{},{},{},{}\n",
                format_value(ix.first),
                format_value(ix.first_ci[0]),
                format_value(ix.first_ci[1]),
                format_value(ix.total),
                format_value(ix.total_ci[0]),
                format_value(ix.total_ci[1])
            ));
        }
    }
    csv
}

/// The note of Sobol indices outside [0, 1], where a share of variance lies: their Monte
/// Carlo error, said with the largest excursion (None when every index lies in [0, 1]).
fn sobol_note(sobol: &Sobol) -> Option<String> {
    let mut count = 0;
    let mut all = 0;
    let mut worst: Option<(f64, String)> = None;
    for (output, indices) in sobol {
        for (key, ix) in indices {
            for (what, x) in [("first-order", ix.first), ("total", ix.total)] {
                all += 1;
                let beyond = (x - x.clamp(0.0, 1.0)).abs();
                if beyond > 0.0 {
                    count += 1;
                    if worst.as_ref().is_none_or(|(w, _)| beyond > *w) {
                        worst = Some((
                            beyond,
                            format!(
                                "the {what} index of {key} for {output}, {}",
                                crate::text::number(x)
                            ),
                        ));
                    }
                }
            }
        }
    }
    let (_, which) = worst?;
    Some(format!(
        "{count} of {all} Sobol indices lie outside [0, 1], where a share of variance lies (the farthest: {which}): that is their Monte Carlo error, and more eyes narrow it"
    ))
}

/// The Sobol indices of each final output, over the base points whose A, B and every AB_i
/// finished (a base point with a failed row is left out whole).
fn sobol_of(sample: &Sample, eyes: &[Option<Eye>], final_stats: &[(String, Stats)]) -> Sobol {
    let per = sample.keys.len() + 2;
    final_stats
        .iter()
        .filter_map(|(output, _)| {
            let f: Vec<Vec<f64>> = eyes
                .chunks(per)
                .filter_map(|rows| {
                    rows.iter()
                        .map(|e| {
                            let e = e.as_ref()?;
                            let x = e.final_values.iter().find(|(k, _)| k == output)?.1;
                            x.is_finite().then_some(x)
                        })
                        .collect::<Option<Vec<f64>>>()
                })
                .filter(|r| r.len() == per)
                .collect();
            if f.len() < 2 {
                return None;
            }
            let indices = sobol_indices(&f, sample.seed)?;
            Some((
                output.clone(),
                sample
                    .keys
                    .iter()
                    .map(|(k, _)| k.clone())
                    .zip(indices)
                    .collect(),
            ))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_of_a_known_sample() {
        let xs: Vec<f64> = (1..=5).map(f64::from).collect();
        let s = stats(&xs);
        assert_eq!(s.mean, 3.0);
        assert!((s.sd - 2.5f64.sqrt()).abs() < 1e-15);
        assert_eq!(s.quantiles, [1.2, 2.0, 3.0, 4.0, 4.8]);
        assert!((s.mean_se - (2.5f64 / 5.0).sqrt()).abs() < 1e-15);
    }

    /// f = x1 + x2 + x1·x2 with x1, x2 uniform on (0, 1): V1 = V2 = 0.1875, V12 = 1/144,
    /// so S1 = S2 = 0.1875 / V and ST1 = ST2 = (0.1875 + 1/144) / V, V = 0.375 + 1/144.
    /// The design and the estimators together reproduce them.
    #[test]
    fn sobol_indices_of_an_analytic_function() {
        let text = "eyes = 4096\ndesign = \"saltelli\"\nseed = 7\n[keys]\n\"growth.eta0\" = { dist = \"uniform\", low = 0, high = 1 }\n\"growth.Gamma\" = { dist = \"uniform\", low = 0, high = 1 }\n";
        let t: toml::Table = toml::from_str(text).unwrap();
        let sample = crate::scene::sample::parse(&t, "s.toml").unwrap();
        let draws = sample.draws();
        let f: Vec<Vec<f64>> = draws
            .chunks(4)
            .map(|rows| rows.iter().map(|x| x[0] + x[1] + x[0] * x[1]).collect())
            .collect();
        let ix = sobol_indices(&f, 7).unwrap();
        let v = 0.375 + 1.0 / 144.0;
        let (s, st) = (0.1875 / v, (0.1875 + 1.0 / 144.0) / v);
        for i in &ix {
            assert!((i.first - s).abs() < 0.01, "{i:?} vs {s}");
            assert!((i.total - st).abs() < 0.01, "{i:?} vs {st}");
            assert!(i.first_ci[0] < s && s < i.first_ci[1], "{i:?}");
            assert!(i.total_ci[0] < st && st < i.total_ci[1], "{i:?}");
        }
        // A function of x1 alone: S1 = ST1 = 1, S2 = ST2 = 0.
        let g: Vec<Vec<f64>> = draws
            .chunks(4)
            .map(|rows| rows.iter().map(|x| (3.0 * x[0]).sin()).collect())
            .collect();
        let ix = sobol_indices(&g, 7).unwrap();
        assert!(
            (ix[0].first - 1.0).abs() < 0.01 && (ix[0].total - 1.0).abs() < 0.01,
            "{:?}",
            ix[0]
        );
        assert!(
            ix[1].first.abs() < 1e-12 && ix[1].total.abs() < 1e-12,
            "{:?}",
            ix[1]
        );
    }
}
