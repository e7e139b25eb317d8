//! `eyeshell compare RUN REFERENCE...`: the largest differences, field by field, between a
//! run and reference results (.mat files written by eyeshell, MATLAB, Octave or SciPy;
//! .npz files; a directory of them; another eyeshell run directory).
//!
//! Every input becomes one or more [`Sample`]s: named vectors over the material points,
//! and the output time if it has one.
//! - An eyeshell run: fields.csv (one sample, no time) or each snapshot (with its time),
//!   every column by its name.
//! - A .mat / .npz file: the struct `sol` if there is one (bvp4c's solution; element 1 of a
//!   struct array), else the top level. `x` is the material coordinate Σ (so it is renamed
//!   `Sigma`); a 5×N `y` gives the rows kappa, alpha_s, r, theta, Q; a 1×1 `time` is the
//!   output time; every other vector of the same length is a field by its name.
//!
//! Each reference sample is paired with the run's sample at the same time (within 1e-9
//! relative), or with the run's only sample when either has no time. The coordinate is Σ
//! (`Sigma`) when both sides have it, else the grown arclength `sigma`. The run is
//! interpolated in that coordinate to the reference's points by local polynomials of
//! degree 5 that never cross a breakpoint ([`super::interp`]: O(h⁶), exact at a node), and
//! the largest estimate of that interpolation's error is reported beside each field: the
//! smallest tolerance that means something. The reference is used at its own points, so it
//! is never interpolated. Reference points outside the run's range are left out. A point
//! fails when |run − ref| > tol + rtol·|ref| (numpy.isclose); the relative difference
//! reported is |run − ref| / |ref|.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::export::{is_run_dir, read_run, Run, Y_ROWS};
use super::interp::{Pieces, Side};
use super::mat::{self, MatValue};
use super::npz;

/// A bad input of compare (exit 2): one line naming the file.
#[derive(Debug)]
pub struct CompareError(pub String);

impl std::fmt::Display for CompareError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CompareError {}

impl From<CompareError> for crate::Error {
    /// A comparison that cannot be made is about the files the user named (a result
    /// beyond tolerance is not an error of this kind: the command reports it itself).
    fn from(e: CompareError) -> Self {
        crate::Error::input_about_nothing(e.0)
    }
}

/// Named vectors over the material points of one result.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Where it comes from (file, and snapshot).
    pub label: String,
    pub time: Option<f64>,
    /// Every vector, all of one length.
    pub vars: BTreeMap<String, Vec<f64>>,
    /// Breakpoints of the data in Σ (an eyeshell run's thickness jumps and fibre kinks),
    /// which interpolation does not cross.
    pub breaks: Vec<f64>,
    /// Variables of the file that are not vectors over its points: name, and what it is.
    pub not_compared: Vec<(String, String)>,
}

/// The coordinates, in order of preference.
pub const COORDINATES: [&str; 2] = ["Sigma", "sigma"];

/// Which struct of a .mat file holds the result (`--field`): a variable name and a 1-based
/// element of a struct array. Default: `sol`, element 1, if there is one, else the top level.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldSpec {
    pub name: String,
    pub element: usize,
}

impl std::str::FromStr for FieldSpec {
    type Err = String;

    /// `sol`, `sol(2)`, `result`.
    fn from_str(text: &str) -> Result<FieldSpec, String> {
        let bad = || {
            format!("{text:?}: give a variable name, or NAME(K) for element K of a struct array")
        };
        let (name, element) = match text.strip_suffix(')').and_then(|t| t.split_once('(')) {
            Some((n, k)) => (n, k.trim().parse::<usize>().map_err(|_| bad())?),
            None => (text, 1),
        };
        let valid = !name.is_empty()
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && element >= 1;
        valid
            .then(|| FieldSpec {
                name: name.to_string(),
                element,
            })
            .ok_or_else(bad)
    }
}

/// Read every sample of `path`: a run directory, a directory of .mat/.npz files, or a file.
pub fn load(path: &Path) -> Result<Vec<Sample>, CompareError> {
    load_with(path, None)
}

/// [`load`], taking the struct named by `field` from .mat files.
pub fn load_with(path: &Path, field: Option<&FieldSpec>) -> Result<Vec<Sample>, CompareError> {
    if path.is_dir() {
        if is_run_dir(path) {
            return from_run(path);
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(|e| CompareError(format!("{}: {e}", path.display())))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.is_file()
                    && p.extension().is_some_and(|x| x == "mat" || x == "npz")
                    // An export's series and history are not fields on the nodes.
                    && !p.file_stem().is_some_and(|s| {
                        super::export::SERIES_TABLES.iter().any(|t| s == *t)
                    })
                    && !p
                        .file_name()
                        .unwrap_or_default()
                        .to_string_lossy()
                        .starts_with('.')
            })
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(CompareError(format!(
                "{}: neither an eyeshell run directory (no summary.json) nor a directory of .mat or .npz files",
                path.display()
            )));
        }
        let mut out = Vec::new();
        for f in files {
            out.push(load_file(&f, field)?);
        }
        return Ok(out);
    }
    if !path.exists() {
        return Err(CompareError(format!(
            "{}: no such file or directory",
            path.display()
        )));
    }
    Ok(vec![load_file(path, field)?])
}

fn from_run(dir: &Path) -> Result<Vec<Sample>, CompareError> {
    let run = read_run(dir).map_err(|e| CompareError(e.message))?;
    // Without a scene (a summary that cannot be rebuilt) only repeated points cut the data.
    let breaks = crate::rundir::rundata::scene(dir)
        .map(|s| crate::model::profiles::breakpoints(&s.params))
        .unwrap_or_default();
    let sample = |label: String, time: Option<f64>, t: &super::export::Table| Sample {
        label,
        time,
        breaks: breaks.clone(),
        not_compared: Vec::new(),
        vars: t
            .columns
            .iter()
            .filter_map(|c| t.column(c).map(|v| (c.clone(), v)))
            .collect(),
    };
    Ok(match run {
        Run::Elastic { file, table } => {
            let label = file.display().to_string();
            // As its export holds it: each interface twice, its one-sided values from the
            // scene's data (exact there, where the node's single row would leave the limit
            // from above to extrapolation). Fields that do not evaluate are compared as read.
            let extras = super::export::ElasticExtras::of(dir);
            match super::export::bvp4c_form(&table, &extras) {
                Ok(form) => vec![Sample {
                    label,
                    time: None,
                    breaks: breaks.clone(),
                    not_compared: Vec::new(),
                    vars: crate::bvp::COLUMNS
                        .iter()
                        .enumerate()
                        .map(|(j, c)| {
                            let v = form.rows.iter().map(|r| r.values()[j]).collect();
                            (c.to_string(), v)
                        })
                        .collect(),
                }],
                Err(_) => vec![sample(label, None, &table)],
            }
        }
        Run::Growth(snaps) => snaps
            .iter()
            .map(|s| sample(s.file.display().to_string(), Some(s.t), &s.table))
            .collect(),
    })
}

/// A value read from a file: its shape (MATLAB dims, or NumPy shape) and values in the
/// file's order (column-major for .mat, row-major for .npz).
struct Raw {
    shape: Vec<usize>,
    data: Vec<f64>,
    column_major: bool,
}

/// A variable of a reference file: numbers, or something else, described.
enum Item {
    Numbers(Raw),
    Other(String),
}

/// What a MATLAB value is, in a few words, for a message.
fn describe(v: &MatValue) -> String {
    match v {
        MatValue::Double { dims, .. } => format!("a {} numeric array", shape_text(dims)),
        MatValue::Struct(_) => "a struct".into(),
        MatValue::StructArray { dims, .. } => format!("a {} struct array", shape_text(dims)),
        MatValue::Char(_) => "text (a char array)".into(),
        MatValue::Cell { dims, .. } => format!("a {} cell array", shape_text(dims)),
        MatValue::Unread(what) => what.clone(),
    }
}

/// `5×401`, or `0-d` for a NumPy scalar.
fn shape_text(shape: &[usize]) -> String {
    if shape.is_empty() {
        return "0-d".into();
    }
    shape
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join("×")
}

fn load_file(path: &Path, field: Option<&FieldSpec>) -> Result<Sample, CompareError> {
    let is_npz = path.extension().is_some_and(|x| x == "npz");
    let (prefix, vars): (String, Vec<(String, Item)>) = if is_npz {
        let arrays = npz::read(path).map_err(|e| CompareError(e.to_string()))?;
        let items = arrays
            .into_iter()
            .map(|(n, a)| {
                (
                    n,
                    Item::Numbers(Raw {
                        shape: a.shape,
                        data: a.data,
                        column_major: false,
                    }),
                )
            })
            .collect();
        (String::new(), items)
    } else {
        let vars = mat::read(path).map_err(|e| CompareError(e.to_string()))?;
        let (prefix, container) = match field {
            Some(spec) => (
                format!("{}.", spec.name),
                named_struct(path, &vars, spec)?,
            ),
            // bvp4c's solution struct (element 1 of a struct array), if there is one; else
            // the top level. A `sol` that is not a struct is not read as something else.
            None => match vars.iter().find(|(n, _)| n == "sol") {
                Some((_, v)) => (
                    "sol.".to_string(),
                    v.struct_element(0).map(<[_]>::to_vec).ok_or_else(|| {
                        CompareError(format!(
                            "{}: sol is {}, not bvp4c's solution struct (name the struct that holds the result with {})",
                            path.display(),
                            describe(v),
                            crate::text::advice(&crate::text::Advice::Field { name: None })
                        ))
                    })?,
                ),
                None => (String::new(), vars),
            },
        };
        let items = container
            .into_iter()
            .map(|(n, v)| match v {
                MatValue::Double { dims, data } => (
                    n,
                    Item::Numbers(Raw {
                        shape: dims,
                        data,
                        column_major: true,
                    }),
                ),
                other => {
                    let what = describe(&other);
                    (n, Item::Other(what))
                }
            })
            .collect();
        (prefix, items)
    };
    sample_from(path, &prefix, vars)
}

/// The element of the struct variable that `spec` names, or why there is none.
fn named_struct(
    path: &Path,
    vars: &[(String, MatValue)],
    spec: &FieldSpec,
) -> Result<Vec<(String, MatValue)>, CompareError> {
    let fail = |why: String| {
        let option = crate::text::advice(&crate::text::Advice::Field {
            name: Some(&spec.name),
        });
        CompareError(format!("{}: {option}: {why}", path.display()))
    };
    let (_, value) = vars.iter().find(|(n, _)| *n == spec.name).ok_or_else(|| {
        let names: Vec<&str> = vars.iter().map(|(n, _)| n.as_str()).collect();
        fail(format!("no such variable (it has {})", names.join(", ")))
    })?;
    let count = match value {
        MatValue::Struct(_) => 1,
        MatValue::StructArray { elements, .. } => elements.len(),
        _ => return Err(fail("not a struct".into())),
    };
    value
        .struct_element(spec.element - 1)
        .map(<[_]>::to_vec)
        .ok_or_else(|| {
            fail(format!(
                "element {} asked for, but the struct array has {count}",
                spec.element
            ))
        })
}

/// The sample of one file's variables (`prefix` is how the file names their container,
/// `sol.`, for messages). The variables compare gives a meaning to are checked whole, and
/// a reference that breaks them is refused with what is wrong: `x` / `Sigma` / `sigma`
/// (a vector of at least two finite points), `y` (5 rows, one column per point) and `time`
/// (one finite number). Every other variable that is not a vector over the points is kept
/// in [`Sample::not_compared`] with what it is, so that the report can say so, and
/// [`compare_pair`] refuses it when the run has a field of that name.
fn sample_from(
    path: &Path,
    prefix: &str,
    raw: Vec<(String, Item)>,
) -> Result<Sample, CompareError> {
    let file = path.display().to_string();
    let refuse = |name: &str, why: String| CompareError(format!("{file}: {prefix}{name} {why}"));
    let mut time = None;
    let mut vectors: Vec<(String, Vec<f64>)> = Vec::new();
    let mut not_compared: Vec<(String, String)> = Vec::new();
    let mut y: Option<Raw> = None;
    // Σ is stored as `Sigma`; messages name it as the file does.
    let mut sigma_from_x = false;
    for (name, item) in raw {
        let coordinate = name == "x" || COORDINATES.contains(&name.as_str());
        let r = match item {
            Item::Numbers(r) => r,
            Item::Other(what) => {
                if coordinate || name == "y" || name == "time" {
                    return Err(refuse(
                        &name,
                        format!("is {what}: expected {}", expected(&name)),
                    ));
                }
                not_compared.push((name, what));
                continue;
            }
        };
        let n: usize = r.shape.iter().product();
        let non_unit = r.shape.iter().filter(|&&d| d != 1).count();
        let vector = non_unit <= 1 && !r.shape.is_empty() && n > 1;
        let shape = shape_text(&r.shape);
        if name == "time" {
            time = Some(time_of(&r, &shape).map_err(|why| refuse(&name, why))?);
        } else if name == "y" {
            if r.shape.len() != 2 || r.shape[0] != Y_ROWS.len() {
                let hint = if r.shape.len() == 2 && r.shape[1] == Y_ROWS.len() {
                    " (it looks transposed)"
                } else {
                    ""
                };
                return Err(refuse(
                    &name,
                    format!("is a {shape} array{hint}: expected {}", expected(&name)),
                ));
            }
            y = Some(r);
        } else if coordinate {
            if let Some(why) = coordinate_problem(&name, &r, n, vector, &shape) {
                return Err(refuse(&name, why));
            }
            sigma_from_x |= name == "x";
            let name = if name == "x" { "Sigma".into() } else { name };
            if vectors.iter().any(|(m, _)| *m == name) {
                return Err(CompareError(format!(
                    "{file}: both x and Sigma: give the material coordinate once"
                )));
            }
            vectors.push((name, r.data));
        } else if vector {
            vectors.push((name, r.data));
        } else {
            not_compared.push((
                name,
                format!("a {shape} array, not a vector over the points"),
            ));
        }
    }
    let (coord, len) = COORDINATES
        .iter()
        .find_map(|c| vectors.iter().find(|(n, _)| n == c))
        .map(|(n, v)| (n.clone(), v.len()))
        .ok_or_else(|| {
            CompareError(format!(
                "{file}: no material coordinate (a vector named Sigma, x or sigma)"
            ))
        })?;
    let coord_name = if coord == "Sigma" && sigma_from_x {
        format!("{prefix}x")
    } else {
        format!("{prefix}{coord}")
    };
    if let Some(y) = y {
        let cols = y.shape[1];
        if cols != len {
            return Err(refuse(
                "y",
                format!(
                    "has {cols} columns but {coord_name} has {len} points: expected {}",
                    expected("y")
                ),
            ));
        }
        for (i, name) in Y_ROWS.iter().enumerate() {
            let row = y_row(&y, i);
            if vectors.iter().any(|(n, _)| n == name) {
                return Err(CompareError(format!(
                    "{file}: both {prefix}y and {prefix}{name}: give {name} once"
                )));
            }
            vectors.push((name.to_string(), row));
        }
    }
    let mut vars = BTreeMap::new();
    for (name, v) in vectors {
        if v.len() == len {
            vars.insert(name, v);
        } else {
            let what = format!("{} values, but {coord_name} has {len} points", v.len());
            not_compared.push((name, what));
        }
    }
    Ok(Sample {
        label: file,
        time,
        vars,
        breaks: Vec::new(),
        not_compared,
    })
}

/// The reference's `time` (one finite number), or why it is not, after the variable's name.
fn time_of(r: &Raw, shape: &str) -> Result<f64, String> {
    match r.data[..] {
        [t] if t.is_finite() => Ok(t),
        [t] => Err(format!(
            "= {}: expected {}",
            crate::text::number(t),
            expected("time")
        )),
        _ => Err(format!("is a {shape} array: expected {}", expected("time"))),
    }
}

/// Why the material coordinate `name` (`r`, of `n` numbers; `vector` when one dimension
/// at most is not 1 and it has two points or more) is not a vector of finite points, after
/// the variable's name; None when it is one.
fn coordinate_problem(name: &str, r: &Raw, n: usize, vector: bool, shape: &str) -> Option<String> {
    if !vector {
        let what = if r.shape.is_empty() {
            "is a 0-d array (one number)".to_string()
        } else if n == 0 {
            "is empty".to_string()
        } else if n == 1 {
            "has a single point".to_string()
        } else {
            format!("is a {shape} array")
        };
        return Some(format!("{what}: expected {}", expected(name)));
    }
    let k = r.data.iter().position(|v| !v.is_finite())?;
    Some(format!(
        "has {} at point {} of {n}: a material coordinate must be finite",
        crate::text::number(r.data[k]),
        k + 1
    ))
}

/// Row `i` of the 5×N array `y` (row `i` is the [`Y_ROWS`] variable `i` over the points),
/// in either storage order.
fn y_row(y: &Raw, i: usize) -> Vec<f64> {
    let cols = y.shape[1];
    (0..cols)
        .map(|j| {
            if y.column_major {
                y.data[j * Y_ROWS.len() + i]
            } else {
                y.data[i * cols + j]
            }
        })
        .collect()
}

/// What compare expects of a variable it gives a meaning to.
fn expected(name: &str) -> String {
    match name {
        "y" => format!(
            "a 5×N numeric array (rows {}), one column per point of x",
            Y_ROWS.join(", ")
        ),
        "time" => "one finite number".into(),
        _ => "a numeric vector of at least two finite points (the material coordinate)".into(),
    }
}

/// The differences of one field.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldDiff {
    pub field: String,
    pub max_abs: f64,
    /// The coordinate where `max_abs` is reached.
    pub at_abs: f64,
    pub max_rel: f64,
    pub at_rel: f64,
    /// Points where |Δ| > tol + rtol·|ref|.
    pub failures: usize,
    /// Worst |Δ| / (tol + rtol·|ref|) (> 1 fails).
    pub worst_ratio: f64,
    /// The largest estimate of the run's interpolation error at the reference's points.
    pub interpolation: f64,
    /// The largest absolute tolerance applied, tol + rtol·|ref| where |ref| is largest.
    pub allowed: f64,
}

/// One reference sample against its run sample.
#[derive(Clone, Debug, PartialEq)]
pub struct PairReport {
    pub reference: String,
    pub run: String,
    pub time: Option<f64>,
    pub coordinate: String,
    /// Reference points compared (inside the run's range).
    pub points: usize,
    /// Reference points left out (outside the run's range).
    pub outside: usize,
    pub fields: Vec<FieldDiff>,
    /// The reference's variables that were not compared (the run has no field of that
    /// name, or they are not vectors over the points): name, and why.
    pub not_compared: Vec<(String, String)>,
}

impl PairReport {
    pub fn failed(&self) -> bool {
        self.fields.iter().any(|f| f.failures > 0)
    }
}

impl FieldDiff {
    /// Take in one reference point at `x`: the run's interpolated value `a` against the
    /// reference's `b`, allowed `tol + rtol·|b|` (two NaNs, or two equal values, agree).
    fn add_point(&mut self, x: f64, a: f64, b: f64, tol: f64, rtol: f64) {
        let abs = if (a.is_nan() && b.is_nan()) || a == b {
            0.0
        } else {
            let v = (a - b).abs();
            if v.is_nan() {
                f64::INFINITY
            } else {
                v
            }
        };
        let rel = if abs == 0.0 {
            0.0
        } else if b == 0.0 {
            f64::INFINITY
        } else {
            abs / b.abs()
        };
        let allowed = tol + rtol * if b.is_finite() { b.abs() } else { 0.0 };
        self.allowed = self.allowed.max(allowed);
        let ratio = if abs == 0.0 {
            0.0
        } else if allowed > 0.0 {
            abs / allowed
        } else {
            f64::INFINITY
        };
        if abs > self.max_abs {
            self.max_abs = abs;
            self.at_abs = x;
        }
        if rel > self.max_rel {
            self.max_rel = rel;
            self.at_rel = x;
        }
        if ratio > 1.0 {
            self.failures += 1;
        }
        self.worst_ratio = self.worst_ratio.max(ratio);
    }
}

/// Compare `reference` against `run` (paired already).
pub fn compare_pair(
    run: &Sample,
    reference: &Sample,
    tol: f64,
    rtol: f64,
) -> Result<PairReport, CompareError> {
    let coordinate = COORDINATES
        .iter()
        .find(|c| run.vars.contains_key(**c) && reference.vars.contains_key(**c))
        .ok_or_else(|| {
            CompareError(format!(
                "{} and {}: no common material coordinate (Sigma / x, or sigma)",
                reference.label, run.label
            ))
        })?
        .to_string();
    // A variable the run has a field for is compared, or the reference is refused: it is
    // never passed over because its shape is wrong.
    if let Some((name, what)) = reference
        .not_compared
        .iter()
        .find(|(n, _)| run.vars.contains_key(n))
    {
        return Err(CompareError(format!(
            "{}: {name} is {what}, so it cannot be compared with the run's {name} ({})",
            reference.label, run.label
        )));
    }
    let mut not_compared = reference.not_compared.clone();
    let mut fields: Vec<&String> = Vec::new();
    for k in reference.vars.keys().filter(|k| **k != coordinate) {
        if run.vars.contains_key(k) {
            fields.push(k);
        } else {
            not_compared.push((k.clone(), "the run has no such field".into()));
        }
    }
    not_compared.sort();
    if fields.is_empty() {
        return Err(CompareError(format!(
            "{} and {}: no variable in common besides {coordinate}",
            reference.label, run.label
        )));
    }
    // The run's points in increasing coordinate.
    let xr = &run.vars[&coordinate];
    let mut order: Vec<usize> = (0..xr.len()).collect();
    order.sort_by(|&a, &b| xr[a].total_cmp(&xr[b]));
    let xs: Vec<f64> = order.iter().map(|&i| xr[i]).collect();
    let (lo, hi) = match (xs.first(), xs.last()) {
        (Some(&a), Some(&b)) if a.is_finite() && b.is_finite() => (a, b),
        _ => {
            return Err(CompareError(format!(
                "{}: the coordinate {coordinate} is empty or not finite",
                run.label
            )))
        }
    };
    let pieces = Pieces::new(xs.clone(), &breaks_in(run, &coordinate));
    let slack = 1e-12 * (hi - lo).abs().max(1.0);
    let xref = &reference.vars[&coordinate];
    let inside: Vec<usize> = (0..xref.len())
        .filter(|&j| xref[j] >= lo - slack && xref[j] <= hi + slack)
        .collect();
    if inside.is_empty() {
        return Err(CompareError(format!(
            "{}: no point of {} lies inside the run's range [{}, {}] ({})",
            reference.label,
            coordinate,
            crate::text::number(lo),
            crate::text::number(hi),
            run.label
        )));
    }
    let mut diffs = Vec::new();
    for f in fields {
        let ys: Vec<f64> = order.iter().map(|&i| run.vars[f][i]).collect();
        let refv = &reference.vars[f];
        let mut d = FieldDiff {
            field: f.clone(),
            max_abs: 0.0,
            at_abs: xref[inside[0]],
            max_rel: 0.0,
            at_rel: xref[inside[0]],
            failures: 0,
            worst_ratio: 0.0,
            interpolation: 0.0,
            allowed: tol,
        };
        for &j in &inside {
            let x = xref[j].clamp(lo, hi);
            // The second of two equal reference points is the limit from above (bvp4c).
            let side = if j > 0 && xref[j - 1] == xref[j] {
                Side::Above
            } else {
                Side::Below
            };
            let (a, estimate) = pieces.eval(&ys, x, side);
            d.interpolation = d.interpolation.max(estimate);
            let b = refv[j];
            d.add_point(xref[j], a, b, tol, rtol);
        }
        diffs.push(d);
    }
    Ok(PairReport {
        reference: reference.label.clone(),
        run: run.label.clone(),
        time: reference.time.or(run.time),
        coordinate,
        points: inside.len(),
        outside: xref.len() - inside.len(),
        fields: diffs,
        not_compared,
    })
}

/// The run's breakpoints in `coordinate`: Σ as they are; for the grown arclength σ, its
/// value at the node where Σ is the breakpoint.
fn breaks_in(run: &Sample, coordinate: &str) -> Vec<f64> {
    if coordinate == "Sigma" {
        return run.breaks.clone();
    }
    let (Some(sig), Some(x)) = (run.vars.get("Sigma"), run.vars.get(coordinate)) else {
        return Vec::new();
    };
    run.breaks
        .iter()
        .filter_map(|b| sig.iter().position(|s| s == b).map(|k| x[k]))
        .collect()
}

/// Pair each reference sample with a run sample (see the module doc).
pub fn pair<'a>(run: &'a [Sample], reference: &Sample) -> Result<&'a Sample, CompareError> {
    if run.len() == 1 && (reference.time.is_none() || run[0].time.is_none()) {
        return Ok(&run[0]);
    }
    let Some(t) = reference.time else {
        return Err(CompareError(format!(
            "{}: has no `time`, and the run has {} output times: name one snapshot or give a file with `time`",
            reference.label,
            run.len()
        )));
    };
    run.iter()
        .filter(|s| {
            s.time
                .is_some_and(|u| (u - t).abs() <= 1e-9 * t.abs().max(1.0))
        })
        .min_by(|a, b| {
            let da = (a.time.unwrap_or(f64::NAN) - t).abs();
            let db = (b.time.unwrap_or(f64::NAN) - t).abs();
            da.total_cmp(&db)
        })
        .ok_or_else(|| {
            let times: Vec<String> = run
                .iter()
                .filter_map(|s| s.time.map(crate::text::number))
                .collect();
            CompareError(format!(
                "{}: time = {}, but the run has no output at that time (it has t = {})",
                reference.label,
                crate::text::number(t),
                times.join(", ")
            ))
        })
}

/// Load `run_path` and every reference, pair them, compare.
pub fn compare_paths(
    run_path: &Path,
    references: &[PathBuf],
    tol: f64,
    rtol: f64,
    field: Option<&FieldSpec>,
) -> Result<Vec<PairReport>, CompareError> {
    let run = load(run_path)?;
    let mut reports = Vec::new();
    for r in references {
        for sample in load_with(r, field)? {
            let partner = pair(&run, &sample)?;
            reports.push(compare_pair(partner, &sample, tol, rtol)?);
        }
    }
    Ok(reports)
}

/// The reports as text: per pair a heading and a table
/// `field  max|Δ|  at  max rel  at  interp. ±  allowed  status`, `allowed` the absolute
/// tolerance applied where it is widest (tol + rtol·|ref|: rtol = 1e-8 at r ≈ 10 adds 1e-7
/// to a tol of 1e-8, which the summary's formula alone leaves to the reader).
pub fn format_reports(reports: &[PairReport], tol: f64, rtol: f64) -> String {
    let mut s = String::new();
    for r in reports {
        let time = r
            .time
            .map(|t| format!(" at t = {}", crate::text::number(t)))
            .unwrap_or_default();
        s.push_str(&format!(
            "{} vs {}{}: {} points in {}{}\n",
            r.reference,
            r.run,
            time,
            r.points,
            r.coordinate,
            if r.outside > 0 {
                format!(" ({} outside the run's range left out)", r.outside)
            } else {
                String::new()
            }
        ));
        s.push_str(&format!(
            "  {:<10} {:>12} {:>12} {:>12} {:>12} {:>12} {:>10}  {}\n",
            "field",
            "max |Δ|",
            format!("at {}", r.coordinate),
            "max rel",
            format!("at {}", r.coordinate),
            "interp. ±",
            "allowed",
            "status"
        ));
        for f in &r.fields {
            s.push_str(&format!(
                "  {:<10} {:>12.3e} {:>12.6} {:>12.3e} {:>12.6} {:>12.1e} {:>10.2e}  {}\n",
                f.field,
                f.max_abs,
                f.at_abs,
                f.max_rel,
                f.at_rel,
                f.interpolation,
                f.allowed,
                if f.failures > 0 {
                    format!(
                        "FAIL ({} point{})",
                        f.failures,
                        if f.failures == 1 { "" } else { "s" }
                    )
                } else {
                    "ok".to_string()
                }
            ));
        }
        if !r.not_compared.is_empty() {
            let list: Vec<String> = r
                .not_compared
                .iter()
                .map(|(n, why)| format!("{n} ({why})"))
                .collect();
            s.push_str(&format!("  not compared: {}\n", list.join("; ")));
        }
    }
    let failed: usize = reports
        .iter()
        .map(|r| r.fields.iter().filter(|f| f.failures > 0).count())
        .sum();
    let total: usize = reports.iter().map(|r| r.fields.len()).sum();
    s.push_str(&format!(
        "{} of {} field comparisons within |Δ| ≤ {} + {}·|ref|\n",
        total - failed,
        total,
        crate::text::number(tol),
        crate::text::number(rtol)
    ));
    let interp = reports
        .iter()
        .flat_map(|r| r.fields.iter().map(|f| f.interpolation))
        .fold(0.0, f64::max);
    s.push_str(&format!(
        "(interp. ±: an upper estimate of the error of interpolating the run to the reference's points, at most {interp:.1e}; a tolerance below it cannot be trusted)\n"
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(xs: &[f64], f: impl Fn(f64) -> f64, time: Option<f64>) -> Sample {
        let mut vars = BTreeMap::new();
        vars.insert("Sigma".to_string(), xs.to_vec());
        vars.insert("kappa".to_string(), xs.iter().map(|&x| f(x)).collect());
        Sample {
            label: "s".into(),
            time,
            vars,
            breaks: Vec::new(),
            not_compared: Vec::new(),
        }
    }

    /// Smooth data on a coarse run against a fine reference: the interpolation is as
    /// accurate as degree 5 on that mesh, and its estimate bounds the difference.
    #[test]
    fn interpolation_is_high_order_and_estimated() {
        let f = |x: f64| (2.0 * x).sin() + x * x * x;
        let coarse: Vec<f64> = (0..81).map(|i| i as f64 / 80.0).collect();
        let fine: Vec<f64> = (0..1001).map(|i| i as f64 / 1000.0).collect();
        let r = compare_pair(
            &sample(&coarse, f, None),
            &sample(&fine, f, None),
            1e-10,
            0.0,
        )
        .unwrap();
        let d = &r.fields[0];
        assert!(!r.failed(), "{d:?}");
        assert!(d.max_abs < 1e-11 && d.max_abs > 0.0, "{d:?}");
        assert!(d.interpolation >= d.max_abs, "{d:?}");
        assert!(d.interpolation < 1e-8, "{d:?}");
    }

    #[test]
    fn equal_samples_pass_and_a_perturbation_fails() {
        let xs: Vec<f64> = (0..11).map(|i| i as f64 / 10.0).collect();
        let run = sample(&xs, |x| x * x, None);
        let r = compare_pair(&run, &run.clone(), 1e-8, 1e-8).unwrap();
        assert!(!r.failed());
        assert_eq!(r.fields[0].max_abs, 0.0);
        let mut bad = run.clone();
        bad.vars.get_mut("kappa").unwrap()[4] += 1e-6;
        let r = compare_pair(&run, &bad, 1e-8, 1e-8).unwrap();
        assert!(r.failed());
        assert!((r.fields[0].max_abs - 1e-6).abs() < 1e-12);
        assert_eq!(r.fields[0].at_abs, 0.4);
        // Linear data on a finer reference grid: interpolation is exact up to round-off.
        let fine: Vec<f64> = (0..101).map(|i| i as f64 / 100.0).collect();
        let r = compare_pair(
            &sample(&xs, |x| 2.0 * x + 1.0, None),
            &sample(&fine, |x| 2.0 * x + 1.0, None),
            1e-12,
            0.0,
        )
        .unwrap();
        assert!(!r.failed(), "{r:?}");
    }

    #[test]
    fn pairing_by_time() {
        let xs = [0.0, 1.0];
        let run = vec![sample(&xs, |x| x, Some(0.0)), sample(&xs, |x| x, Some(0.1))];
        assert_eq!(
            pair(&run, &sample(&xs, |x| x, Some(0.1))).unwrap().time,
            Some(0.1)
        );
        assert!(pair(&run, &sample(&xs, |x| x, Some(0.2))).is_err());
        assert!(pair(&run, &sample(&xs, |x| x, None)).is_err());
    }
}
