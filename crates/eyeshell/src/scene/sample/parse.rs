//! Reading `[sweep.sample]`: the design, each key's distribution and the correlation.

use super::{
    Design, Dist, PerRun, Sample, MAX_EYES, MAX_SOBOL_DIMENSIONS, MAX_SOBOL_POINTS,
    MIN_SALTELLI_EYES,
};
use crate::scene::{closest, describe, keys, one_line, Access, SceneError};
use crate::text::number;

/// Parse `[sweep.sample]`.
pub fn parse(t: &toml::Table, origin: &str) -> Result<Sample, SceneError> {
    let bad = |problem: String| SceneError::BadSweep {
        origin: origin.to_string(),
        problem: format!("sample: {problem}"),
    };
    let mut eyes = None;
    let mut design = Design::Random;
    let mut seed = None;
    let mut keys = Vec::new();
    let mut correlation = None;
    let mut per_run = PerRun::Directory;
    for (name, value) in t {
        match name.as_str() {
            "eyes" => match value {
                toml::Value::Integer(n) if *n >= 2 && *n as u64 <= MAX_EYES as u64 => {
                    eyes = Some(*n as usize)
                }
                v => {
                    return Err(bad(format!(
                        "eyes must be a whole number from 2 to {MAX_EYES}, found {}",
                        describe(v)
                    )))
                }
            },
            "seed" => match value {
                toml::Value::Integer(n) if *n >= 0 => seed = Some(*n as u64),
                v => {
                    return Err(bad(format!(
                        "seed must be a whole number >= 0, found {}",
                        describe(v)
                    )))
                }
            },
            "design" => design = design_of(value).map_err(bad)?,
            "keys" => match value {
                toml::Value::Table(k) => key_dists(k, "", origin, &mut keys)?,
                v => return Err(bad(format!("keys must be a table, found {}", describe(v)))),
            },
            "correlation" => match value {
                toml::Value::Table(c) => correlation = Some(c.clone()),
                v => {
                    return Err(bad(format!(
                        "correlation must be a table of keys and matrix, found {}",
                        describe(v)
                    )))
                }
            },
            "per_run" => {
                per_run = match value {
                    toml::Value::String(s) if s == "directory" => PerRun::Directory,
                    toml::Value::String(s) if s == "table" => PerRun::Table,
                    v => {
                        return Err(bad(format!(
                            "per_run must be \"directory\" (a run directory per eye) or \"table\" (a row per eye, no directories), found {}",
                            describe(v)
                        )))
                    }
                }
            }
            other => {
                let known = ["eyes", "design", "seed", "keys", "correlation", "per_run"];
                let hint = closest(other, known.into_iter())
                    .map(|s| format!(" (did you mean '{s}'?)"))
                    .unwrap_or_default();
                return Err(bad(format!(
                    "unknown entry '{}'{hint}: a sample has eyes, design, seed, keys, correlation and per_run",
                    one_line(other)
                )));
            }
        }
    }
    let Some(eyes) = eyes else {
        return Err(bad("give eyes, the number of eyes to draw".into()));
    };
    // Without a seed the cohort would differ from one run (or shard) to the next.
    let Some(seed) = seed else {
        return Err(bad(
            "give seed (a whole number): the same seed draws the same cohort".into(),
        ));
    };
    if keys.is_empty() {
        return Err(bad(
            "keys is missing or empty: give [sweep.sample.keys] with a distribution for each key"
                .into(),
        ));
    }
    check_design_size(design, eyes, keys.len()).map_err(bad)?;
    let cholesky = match correlation {
        None => None,
        Some(c) => {
            if design == Design::Saltelli {
                return Err(bad("correlation: Sobol indices (design = \"saltelli\") assume independent keys; leave out the correlation or use another design".into()));
            }
            Some(correlation_factor(&c, &keys).map_err(bad)?)
        }
    };
    let sample = Sample {
        eyes,
        design,
        seed,
        keys,
        cholesky,
        per_run,
    };
    if sample.runs() > crate::scene::sweep::MAX_PLANNED_RUNS {
        return Err(bad(format!(
            "declares {} runs, more than the {} allowed",
            sample.runs(),
            crate::scene::sweep::MAX_PLANNED_RUNS
        )));
    }
    Ok(sample)
}

/// `design`: one of [`Design::NAMES`], else the problem (with the closest name).
fn design_of(value: &toml::Value) -> Result<Design, String> {
    let s = match value {
        toml::Value::String(s) => s.as_str(),
        v => {
            return Err(format!(
                "design must be one of {}, found {}",
                Design::NAMES.join(", "),
                describe(v)
            ))
        }
    };
    match s {
        "random" => Ok(Design::Random),
        "latin-hypercube" => Ok(Design::LatinHypercube),
        "sobol" => Ok(Design::Sobol),
        "saltelli" => Ok(Design::Saltelli),
        other => {
            let hint = closest(other, Design::NAMES.into_iter())
                .map(|s| format!(" (did you mean '{s}'?)"))
                .unwrap_or_default();
            Err(format!(
                "design '{}' is not one of {}{hint}",
                one_line(other),
                Design::NAMES.join(", ")
            ))
        }
    }
}

/// Whether `design` can draw `eyes` points over `keys` keys: Saltelli's indices need
/// enough base points to mean anything, and the Sobol sequence has only so many points and
/// dimensions (Saltelli's design takes two dimensions a key).
fn check_design_size(design: Design, eyes: usize, keys: usize) -> Result<(), String> {
    let dims = match design {
        Design::Saltelli => 2 * keys,
        _ => keys,
    };
    if design == Design::Saltelli && eyes < MIN_SALTELLI_EYES {
        return Err(format!(
            "eyes = {eyes}: the saltelli design needs at least {MIN_SALTELLI_EYES} base points for its Sobol indices to mean anything (with fewer, an index's Monte Carlo error is as large as the index); give eyes = {MIN_SALTELLI_EYES} or more"
        ));
    }
    if matches!(design, Design::Sobol | Design::Saltelli) {
        if eyes > MAX_SOBOL_POINTS {
            return Err(format!(
                "eyes = {eyes}: the {} design draws at most {MAX_SOBOL_POINTS} points of the Sobol sequence",
                design.name()
            ));
        }
        if dims > MAX_SOBOL_DIMENSIONS {
            return Err(format!(
                "{keys} keys need {dims} dimensions of the Sobol sequence, which has {MAX_SOBOL_DIMENSIONS}"
            ));
        }
    }
    Ok(())
}

/// Each key's distribution (quoted dotted keys, or nested tables of them).
fn key_dists(
    t: &toml::Table,
    prefix: &str,
    origin: &str,
    out: &mut Vec<(String, Dist)>,
) -> Result<(), SceneError> {
    for (name, value) in t {
        let key = if prefix.is_empty() {
            name.clone()
        } else {
            format!("{prefix}.{name}")
        };
        if let Some(item) = crate::scene::parse::indexed(&key) {
            let item = item.map_err(|problem| SceneError::Invalid {
                origin: format!("{origin}: [sweep.sample.keys]"),
                key: crate::text::excerpt(&one_line(&key), 80),
                value: crate::text::excerpt(&one_line(&value.to_string()), 40),
                problem,
            })?;
            if !item.is_real() {
                return Err(SceneError::BadSweep {
                    origin: origin.to_string(),
                    problem: format!(
                        "sample: {key} is not a real-valued key: only real numbers are drawn"
                    ),
                });
            }
            let toml::Value::Table(d) = value else {
                return Err(not_a_distribution(origin, &key, value));
            };
            let dist = dist(d).map_err(|p| SceneError::BadSweep {
                origin: origin.to_string(),
                problem: format!("sample: keys.{key}: {p}"),
            })?;
            out.push((key, dist));
            continue;
        }
        match (keys::find(&key), value) {
            (Some(spec), toml::Value::Table(d)) => {
                if !matches!(
                    spec.access,
                    Access::Float { .. } | Access::OptionalFloat { .. }
                ) {
                    return Err(SceneError::BadSweep {
                        origin: origin.to_string(),
                        problem: format!(
                            "sample: {key} is not a real-valued key ({}): only real numbers are drawn",
                            spec.type_name()
                        ),
                    });
                }
                let dist = dist(d).map_err(|p| SceneError::BadSweep {
                    origin: origin.to_string(),
                    problem: format!("sample: keys.{key}: {p}"),
                })?;
                out.push((key, dist));
            }
            (Some(_), v) => return Err(not_a_distribution(origin, &key, v)),
            (None, toml::Value::Table(sub)) => key_dists(sub, &key, origin, out)?,
            (None, _) => {
                return Err(crate::scene::unknown_key(
                    &format!("{origin}: [sweep.sample.keys]"),
                    &key,
                ))
            }
        }
    }
    Ok(())
}

/// The error of a sampled key given something other than a distribution's table.
fn not_a_distribution(origin: &str, key: &str, v: &toml::Value) -> SceneError {
    SceneError::BadSweep {
        origin: origin.to_string(),
        problem: format!(
            "sample: keys.{key} must be a table such as {{ dist = \"normal\", mean = 70.0, sd = 5.0 }}, found {}",
            describe(v)
        ),
    }
}

/// One key's `{ dist = ..., ... }`.
fn dist(t: &toml::Table) -> Result<Dist, String> {
    let name = match t.get("dist") {
        Some(toml::Value::String(s)) => s.clone(),
        Some(v) => return Err(format!("dist must be a string, found {}", describe(v))),
        None => return Err(format!("give dist, one of {}", Dist::NAMES.join(", "))),
    };
    let expected: &[&str] = match name.as_str() {
        "normal" | "lognormal" => &["mean", "sd"],
        "uniform" => &["low", "high"],
        "truncated-normal" => &["mean", "sd", "low", "high"],
        "triangular" => &["low", "mode", "high"],
        "empirical" => &["values"],
        other => {
            let hint = closest(other, Dist::NAMES.into_iter())
                .map(|s| format!(" (did you mean '{s}'?)"))
                .unwrap_or_default();
            return Err(format!(
                "dist '{}' is not one of {}{hint}",
                one_line(other),
                Dist::NAMES.join(", ")
            ));
        }
    };
    for k in t.keys() {
        if k != "dist" && !expected.contains(&k.as_str()) {
            return Err(format!(
                "'{}' is not a parameter of a {name} distribution (give {})",
                one_line(k),
                expected.join(", ")
            ));
        }
    }
    let real = |k: &str| -> Result<f64, String> {
        let x = match t.get(k) {
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(n)) => *n as f64,
            Some(v) => return Err(format!("{k} must be a number, found {}", describe(v))),
            None => {
                return Err(format!(
                    "give {} for a {name} distribution",
                    expected.join(", ")
                ))
            }
        };
        if !x.is_finite() || x.abs() > 1e300 {
            return Err(format!("{k} = {} is not a usable number", number(x)));
        }
        Ok(x)
    };
    let positive_sd = |sd: f64| -> Result<(), String> {
        if sd > 0.0 {
            Ok(())
        } else {
            Err(format!("sd = {} must be positive", number(sd)))
        }
    };
    let ordered = |low: f64, high: f64| -> Result<(), String> {
        if low < high {
            Ok(())
        } else {
            Err(format!(
                "low = {} must be below high = {}",
                number(low),
                number(high)
            ))
        }
    };
    Ok(match name.as_str() {
        "normal" => {
            let (mean, sd) = (real("mean")?, real("sd")?);
            positive_sd(sd)?;
            Dist::Normal { mean, sd }
        }
        "lognormal" => {
            let (mean, sd) = (real("mean")?, real("sd")?);
            positive_sd(sd)?;
            if mean <= 0.0 {
                return Err(format!(
                    "mean = {} must be positive: a lognormal value is",
                    number(mean)
                ));
            }
            Dist::LogNormal { mean, sd }
        }
        "uniform" => {
            let (low, high) = (real("low")?, real("high")?);
            ordered(low, high)?;
            Dist::Uniform { low, high }
        }
        "truncated-normal" => {
            let (mean, sd, low, high) = (real("mean")?, real("sd")?, real("low")?, real("high")?);
            positive_sd(sd)?;
            ordered(low, high)?;
            // Φ has no digits left 37 sd into a tail: no value could be drawn there.
            let (a, b) = ((low - mean) / sd, (high - mean) / sd);
            if a > 30.0 || b < -30.0 {
                return Err(format!(
                    "[low, high] = [{}, {}] lies more than 30 sd from the mean {}",
                    number(low),
                    number(high),
                    number(mean)
                ));
            }
            Dist::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            }
        }
        "triangular" => {
            let (low, mode, high) = (real("low")?, real("mode")?, real("high")?);
            ordered(low, high)?;
            if !(low..=high).contains(&mode) {
                return Err(format!(
                    "mode = {} must lie in [low, high] = [{}, {}]",
                    number(mode),
                    number(low),
                    number(high)
                ));
            }
            Dist::Triangular { low, mode, high }
        }
        _ => {
            let values = match t.get("values") {
                Some(toml::Value::Array(a)) => a
                    .iter()
                    .map(|v| match v {
                        toml::Value::Float(x) if x.is_finite() => Ok(*x),
                        toml::Value::Integer(n) => Ok(*n as f64),
                        v => Err(format!(
                            "values must be finite numbers, found {}",
                            describe(v)
                        )),
                    })
                    .collect::<Result<Vec<f64>, String>>()?,
                Some(v) => return Err(format!("values must be a list, found {}", describe(v))),
                None => return Err("give values, the measured values".into()),
            };
            if values.is_empty() || values.len() > MAX_EYES {
                return Err(format!(
                    "values must hold 1 to {MAX_EYES} numbers, found {}",
                    values.len()
                ));
            }
            Dist::Empirical { values }
        }
    })
}

/// The Cholesky factor of `[sweep.sample.correlation]` (keys, matrix) over the sample's
/// keys' order; keys it leaves out are independent.
fn correlation_factor(c: &toml::Table, keys: &[(String, Dist)]) -> Result<Vec<Vec<f64>>, String> {
    for k in c.keys() {
        if k != "keys" && k != "matrix" {
            return Err(format!(
                "correlation: unknown entry '{}' (give keys and matrix)",
                one_line(k)
            ));
        }
    }
    let names: Vec<String> = match c.get("keys") {
        Some(toml::Value::Array(a)) => a
            .iter()
            .map(|v| match v {
                toml::Value::String(s) => Ok(s.clone()),
                v => Err(format!(
                    "correlation.keys must be key names, found {}",
                    describe(v)
                )),
            })
            .collect::<Result<_, _>>()?,
        _ => {
            return Err(
                "correlation: give keys, the list of sampled keys the matrix is over".into(),
            )
        }
    };
    let mut at = Vec::with_capacity(names.len());
    for n in &names {
        let Some(i) = keys.iter().position(|(k, _)| k == n) else {
            return Err(format!(
                "correlation.keys: {} is not a sampled key",
                one_line(n)
            ));
        };
        if at.contains(&i) {
            return Err(format!("correlation.keys: {} is given twice", one_line(n)));
        }
        at.push(i);
    }
    let m = names.len();
    let rows: Vec<Vec<f64>> = match c.get("matrix") {
        Some(toml::Value::Array(rows)) => rows
            .iter()
            .map(|r| match r {
                toml::Value::Array(xs) => xs
                    .iter()
                    .map(|x| match x {
                        toml::Value::Float(x) => Ok(*x),
                        toml::Value::Integer(n) => Ok(*n as f64),
                        v => Err(format!(
                            "correlation.matrix must hold numbers, found {}",
                            describe(v)
                        )),
                    })
                    .collect::<Result<Vec<f64>, String>>(),
                v => Err(format!(
                    "correlation.matrix must be a list of rows, found {}",
                    describe(v)
                )),
            })
            .collect::<Result<_, _>>()?,
        _ => return Err("correlation: give matrix, a list of rows".into()),
    };
    if rows.len() != m || rows.iter().any(|r| r.len() != m) {
        return Err(format!(
            "correlation.matrix must be {m} × {m}, one row and column per key in correlation.keys"
        ));
    }
    let k = keys.len();
    let mut full = vec![vec![0.0; k]; k];
    for (i, row) in full.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for a in 0..m {
        for b in 0..m {
            let x = rows[a][b];
            if a == b && x != 1.0 {
                return Err(format!(
                    "correlation.matrix[{}][{}] = {} must be 1 (a key's correlation with itself)",
                    a + 1,
                    b + 1,
                    number(x)
                ));
            }
            if x != rows[b][a] {
                return Err(format!(
                    "correlation.matrix is not symmetric: [{}][{}] = {} but [{}][{}] = {}",
                    a + 1,
                    b + 1,
                    number(x),
                    b + 1,
                    a + 1,
                    number(rows[b][a])
                ));
            }
            if !(-1.0..=1.0).contains(&x) || !x.is_finite() {
                return Err(format!(
                    "correlation.matrix[{}][{}] = {} must lie in [-1, 1]",
                    a + 1,
                    b + 1,
                    number(x)
                ));
            }
            full[at[a]][at[b]] = x;
        }
    }
    // Cholesky; a matrix that is not positive definite is no correlation of any keys.
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let s: f64 = full[i][j] - (0..j).map(|p| l[i][p] * l[j][p]).sum::<f64>();
            if i == j {
                if s <= 1e-12 {
                    return Err("correlation.matrix is not positive definite (no keys can be correlated so; a correlation of ±1 is not allowed either)".into());
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Ok(l)
}
