//! Sweeps: one scene file that declares many runs (the paper's figures vary D, Γ and δ).
//!
//! A sweep is an ordinary scene plus a `[sweep]` table with a grid, a list, or both:
//!
//! ```toml
//! [sweep.grid]                 # every combination, the last key varying fastest
//! "growth.Gamma" = [4, 8, 12]
//! "growth.delta" = [2, 6]
//!
//! [[sweep.runs]]               # explicit runs: any keys, and an optional run name
//! name = "uniform"
//! "material.thickness" = "uniform"
//! ```
//!
//! With both, every listed run is crossed with the whole grid. Keys may be quoted dotted
//! names or nested tables (`[sweep.grid.growth] Gamma = [4, 8]`). Each run is the base scene
//! with its values set after the file; a `--set` override may not touch a swept key (it
//! would be ambiguous which wins). Every run's scene is validated before anything runs, and
//! an error names the run.

mod spec;
#[cfg(test)]
mod tests;

use super::sample::Sample;
use super::{describe, one_line, parse_table, Scene, SceneError};
pub use spec::show_value;
use spec::{
    generated_name, parse_spec, part, shorten, unique, Assignment, Axis, Combination, ListEntry,
    MAX_NAME,
};

/// The name of the sweep table.
pub const SWEEP: &str = "sweep";
/// The most runs one process holds as a [`Sweep`] (every run's scene built); a larger sweep
/// (up to [`MAX_PLANNED_RUNS`]) runs in shards, each at most this many runs.
pub const MAX_RUNS: usize = 10_000;

/// One run of a sweep: its name (a directory name), the values it sets, and its scene.
#[derive(Clone, Debug)]
pub struct SweepRun {
    pub name: String,
    /// (key, value) in the order of [`Sweep::keys`], only the keys this run sets.
    pub values: Vec<(String, toml::Value)>,
    pub scene: Scene,
}

impl SweepRun {
    /// The value this run gives `key`, as shown in tables ("" if it does not set it).
    pub fn shown(&self, key: &str) -> String {
        self.values
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| show_value(v))
            .unwrap_or_default()
    }
}

/// A parsed, expanded and validated sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub origin: String,
    /// The swept keys: the list's keys (first seen order), then the grid's.
    pub keys: Vec<String>,
    pub runs: Vec<SweepRun>,
    /// The base scene's name (the file's `name`, else its stem).
    pub name: String,
    /// The scene file, as given, when the sweep was read from one: `origin` is only its
    /// name as messages show it (control characters escaped), which may name no file.
    pub path: Option<std::path::PathBuf>,
    /// The sampled cohort, when the sweep is a `[sweep.sample]` ([`super::sample`]).
    pub sample: Option<std::sync::Arc<Sample>>,
}

impl Sweep {
    /// Read the sweep in `path`, with `overrides` applied to every run.
    pub fn from_file(path: &std::path::Path, overrides: &[String]) -> Result<Sweep, SceneError> {
        Sweep::from_plan(SweepPlan::from_file(path, overrides)?)
    }

    /// Parse a sweep (a scene without `[sweep]` is a sweep of one run, named after it) and
    /// build every run's scene ([`Sweep::from_plan`]).
    pub fn from_toml_str(
        text: &str,
        origin: &str,
        overrides: &[String],
    ) -> Result<Sweep, SceneError> {
        Sweep::from_plan(SweepPlan::from_toml_str(text, origin, overrides)?)
    }

    /// Every run of `plan`, built (at most [`MAX_RUNS`]; a larger sweep runs in shards, each
    /// building only its own runs).
    pub fn from_plan(plan: SweepPlan) -> Result<Sweep, SceneError> {
        if plan.len() > MAX_RUNS {
            let shards = crate::text::advice(&crate::text::Advice::Shards { max: MAX_RUNS });
            // A cohort kept as a table is one process's checkpoint, which shards cannot
            // share (they are refused): the advice is what works for it.
            let table =
                plan.sample.as_ref().map(|s| s.per_run) == Some(super::sample::PerRun::Table);
            let advice = match table {
                true => format!(
                    "a cohort kept as a table (per_run = \"table\") runs in one process and cannot be sharded: give at most {MAX_RUNS} eyes, or set per_run = \"directory\" and {shards}"
                ),
                false => shards,
            };
            return Err(SceneError::BadSweep {
                origin: plan.origin.clone(),
                problem: format!(
                    "declares {} runs, more than the {MAX_RUNS} allowed in one process: {advice}",
                    plan.len(),
                ),
            });
        }
        let sweep = plan.sweep_of(&(0..plan.len()).collect::<Vec<_>>())?;
        refuse_keys_not_in_effect(&plan, sweep.runs.iter().map(|r| &r.scene))?;
        Ok(sweep)
    }
}

/// Refuse a swept or sampled key of `plan` that no run of `scenes` reads
/// ([`Scene::not_in_effect`]): its runs would be one eye under as many labels, and a
/// cohort's spread in it a spread in nothing. A key that some runs read (optics.pupil
/// crossed with stimulus.source) is swept; the runs that do not read it carry it as given.
pub fn refuse_keys_not_in_effect<'a>(
    plan: &SweepPlan,
    scenes: impl Iterator<Item = &'a Scene> + Clone,
) -> Result<(), SceneError> {
    for key in &plan.keys {
        let mut why = None;
        for scene in scenes.clone() {
            match scene.not_in_effect(key) {
                None => {
                    why = None;
                    break;
                }
                Some(w) => why = why.or(Some(w)),
            }
        }
        if let Some(why) = why {
            let verb = if plan.sample.is_some() {
                "samples"
            } else {
                "sweeps"
            };
            return Err(SceneError::BadSweep {
                origin: plan.origin.clone(),
                problem: format!(
                    "{verb} {key}, which no run reads ({why}): its runs would all be the same eye; set what turns it on, or leave it out"
                ),
            });
        }
    }
    Ok(())
}

/// Whether keys `a` and `b` set the same value: the same key, or an array
/// (`optics.lenses`) and one of its items' keys (`optics.lenses[0].power`).
fn overlap(a: &str, b: &str) -> bool {
    let item_of = |item: &str, array: &str| {
        item.strip_prefix(array)
            .is_some_and(|rest| rest.starts_with('['))
    };
    a == b || item_of(a, b) || item_of(b, a)
}

/// The most runs one sweep may plan (a typo such as a grid of many long lists is caught
/// early). A plan holds no run's scene; it holds each run's name (about 50 bytes a run)
/// only when names must be made unique in sweep order, and only once they are asked for.
pub const MAX_PLANNED_RUNS: usize = 10_000_000;

/// A sweep's run list as a recipe: run i's values and name come from its index (the list
/// entries crossed with the grid, last axis fastest), and its scene is built only when
/// asked for, so a grid of 10⁶ runs is validated and partitioned into shards without
/// holding 10⁶ scenes ([`SweepPlan::each_run`], [`SweepPlan::sweep_of`]).
#[derive(Clone, Debug)]
pub struct SweepPlan {
    pub origin: String,
    /// The swept keys: the list's keys (first seen order), then the grid's.
    pub keys: Vec<String>,
    /// The base scene's name (the file's `name`, else its stem).
    pub name: String,
    /// The scene file, as given, when the plan was read from one ([`Sweep::path`]).
    pub path: Option<std::path::PathBuf>,
    /// The sampled cohort, when the sweep is a `[sweep.sample]`: its draws are the list.
    pub sample: Option<std::sync::Arc<Sample>>,
    table: toml::Table,
    overrides: Vec<String>,
    list: Vec<ListEntry>,
    grid: Vec<Axis>,
    /// When run i's name is its given or generated name as it is, unique by construction
    /// ([`SweepPlan::direct_names`]), so that a name is made from its index alone: each
    /// grid axis's parts (`Gamma=4`) and their positions, to read a name back.
    direct: Option<Vec<std::collections::HashMap<String, usize>>>,
    /// Every run's name, made unique in sweep order: made on first use, never for a plan
    /// whose names are direct unless every name is asked for.
    names: std::sync::OnceLock<Vec<String>>,
    /// The same names as a set, for [`SweepPlan::has_name`] (made on first use).
    name_set: std::sync::OnceLock<std::collections::HashSet<String>>,
}

impl SweepPlan {
    /// time.unit of the plan's scene file when it counts in ages ("years", "days"): what
    /// the file gives, before any run's keys (a sweep of time.unit itself is not read here).
    pub fn age_unit(&self) -> Option<&'static str> {
        let given = self.table.get("time")?.get("unit")?.as_str()?;
        crate::growth::schedule::TimeUnit::NAMES[1..]
            .iter()
            .find(|&&n| n == given)
            .copied()
    }

    /// Read the sweep in `path`, with `overrides` applied to every run.
    pub fn from_file(
        path: &std::path::Path,
        overrides: &[String],
    ) -> Result<SweepPlan, SceneError> {
        let (origin, text) = super::read_scene_file(path)?;
        let mut plan = SweepPlan::from_toml_str(&text, &origin, overrides)?;
        plan.path = Some(path.to_path_buf());
        Ok(plan)
    }

    /// Parse a sweep, validate its base scene, count its runs and name them; no run's scene
    /// is built.
    pub fn from_toml_str(
        text: &str,
        origin: &str,
        overrides: &[String],
    ) -> Result<SweepPlan, SceneError> {
        let origin = one_line(origin);
        let mut table = parse_table(text, &origin)?;
        let spec = table.remove(SWEEP);
        let bad = |problem: String| SceneError::BadSweep {
            origin: origin.clone(),
            problem,
        };
        let (mut list, grid, sample) = match &spec {
            None => (Vec::new(), Vec::new(), None),
            Some(toml::Value::Table(t)) => parse_spec(t, &origin)?,
            Some(v) => return Err(bad(format!("must be a table, found {}", describe(v)))),
        };
        // A cohort is a list of runs, one per eye (or per Saltelli row), each named and
        // setting the sampled keys to its draws: everything a listed sweep does, it does.
        if let Some(sample) = &sample {
            let draws = sample.draws();
            super::sample::check_draws(sample, &draws, &origin)?;
            list = draws
                .into_iter()
                .enumerate()
                .map(|(i, row)| ListEntry {
                    name: Some(sample.run_name(i)),
                    values: sample
                        .keys
                        .iter()
                        .zip(row)
                        .map(|((k, _), x)| (k.clone(), toml::Value::Float(x)))
                        .collect(),
                })
                .collect();
        }
        for text in overrides {
            let key = text
                .split_once('=')
                .map_or(text.as_str(), |(k, _)| k.trim());
            let swept = list
                .iter()
                .flat_map(|e| e.values.iter().map(|(k, _)| k))
                .chain(grid.iter().map(|(k, _)| k))
                .find(|k| overlap(k, key));
            if let Some(swept) = swept {
                return Err(bad(format!(
                    "sweeps {swept}: {} (the sweep's values would be ambiguous)",
                    crate::text::advice(&crate::text::Advice::RemoveOverride { text })
                )));
            }
        }
        let base = Scene::from_table(&table, &origin, &[], overrides)?;
        let name = base.display_name();
        // Count before naming: a grid of many keys multiplies to more runs than memory.
        let count = grid.iter().try_fold(list.len().max(1), |n, (_, values)| {
            n.checked_mul(values.len())
        });
        match count {
            Some(n) if n <= MAX_PLANNED_RUNS => {}
            Some(n) => {
                return Err(bad(format!(
                    "declares {n} runs, more than the {MAX_PLANNED_RUNS} allowed"
                )))
            }
            None => {
                return Err(bad(format!(
                "declares more runs than can be counted, more than the {MAX_PLANNED_RUNS} allowed"
            )))
            }
        }
        let mut keys: Vec<String> = Vec::new();
        for k in list
            .iter()
            .flat_map(|e| e.values.iter().map(|(k, _)| k))
            .chain(grid.iter().map(|(k, _)| k))
        {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
        // A prescribed lens's power is each run's own (its eye's correction): a column of
        // the sweep's tables beside the swept keys ([`SweepPlan::run`] gives its value).
        if base.not_in_effect(super::parse::LENSES_KEY).is_none() {
            for (i, lens) in base.optics().lenses.iter().enumerate() {
                let key = format!("{}[{i}].power", super::parse::LENSES_KEY);
                if lens.prescribe.is_some() && !keys.contains(&key) {
                    keys.push(key);
                }
            }
        }
        let mut plan = SweepPlan {
            origin,
            keys,
            name,
            path: None,
            sample: sample.map(std::sync::Arc::new),
            table,
            overrides: overrides.to_vec(),
            list,
            grid,
            direct: None,
            names: std::sync::OnceLock::new(),
            name_set: std::sync::OnceLock::new(),
        };
        plan.direct = plan.direct_names();
        Ok(plan)
    }

    /// Are the runs' names unique by construction, so that run i's name is made from i
    /// alone, without naming the runs before it? A generated name is the entry's prefix (a
    /// given name, or the parts of the entry's values), then `_` and each grid axis's part
    /// (`Gamma=4`). It is when no name is shortened (the longest fits [`MAX_NAME`]), the
    /// entries' prefixes differ, and within each axis no part is another's, or the end of
    /// another after a `_` (`tol=1` of `newton_tol=1`): a name then reads back from its end,
    /// one axis at a time, with one candidate at each step ([`SweepPlan::index_of`]). The
    /// parts of each axis, or None. O(values), not O(runs).
    fn direct_names(&self) -> Option<Vec<std::collections::HashMap<String, usize>>> {
        let mut widest = 0;
        let mut axes = Vec::with_capacity(self.grid.len());
        for (key, values) in &self.grid {
            let parts: Vec<String> = values.iter().map(|v| part(key, v)).collect();
            let index: std::collections::HashMap<String, usize> = parts
                .iter()
                .enumerate()
                .map(|(i, p)| (p.clone(), i))
                .collect();
            if index.len() != parts.len() {
                return None;
            }
            let ends_another = parts.iter().any(|p| {
                p.match_indices('_')
                    .any(|(at, _)| index.contains_key(&p[at + 1..]))
            });
            if ends_another {
                return None;
            }
            widest += parts.iter().map(String::len).max().unwrap_or(0) + 1;
            axes.push(index);
        }
        let mut prefixes = self.prefixes();
        if self.grid.is_empty() {
            // Then an entry of no values is named "run", as an entry may be.
            for p in &mut prefixes {
                p.get_or_insert_with(|| "run".into());
            }
        }
        let distinct: std::collections::HashSet<&Option<String>> = prefixes.iter().collect();
        if distinct.len() != prefixes.len() {
            return None;
        }
        // Without a grid a run's name is its prefix, or "run".
        let longest_prefix = prefixes
            .iter()
            .map(|p| p.as_ref().map_or(3, |p| p.len() + 1))
            .max()
            .unwrap_or(0);
        (widest + longest_prefix <= MAX_NAME).then_some(axes)
    }

    /// Each list entry's prefix of its runs' names (its name, or the parts of its values;
    /// None for an entry of no values, and for the one entry of a plan without a list).
    fn prefixes(&self) -> Vec<Option<String>> {
        if self.list.is_empty() {
            return vec![None];
        }
        self.list
            .iter()
            .map(|e| match (&e.name, e.values.is_empty()) {
                (Some(name), _) => Some(name.clone()),
                (None, true) => None,
                (None, false) => Some(generated_name(&e.values)),
            })
            .collect()
    }

    /// The number of runs.
    pub fn len(&self) -> usize {
        self.grid
            .iter()
            .fold(self.list.len().max(1), |n, (_, v)| n * v.len())
    }

    /// Whether the plan has no runs (never: a sweep has at least one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every run's name, in sweep order (all of them made now, if they were not yet: for a
    /// large plan prefer [`SweepPlan::name`] and [`SweepPlan::has_name`]).
    pub fn names(&self) -> &[String] {
        self.names.get_or_init(|| self.unique_names())
    }

    /// Run `index`'s name.
    pub fn run_name(&self, index: usize) -> String {
        match self.direct {
            Some(_) => self.direct_name(index),
            None => self.names()[index].clone(),
        }
    }

    /// Whether a run of this plan has the name `name` (a directory name under `runs/`).
    /// Direct names are read back ([`SweepPlan::index_of`]) rather than listed.
    pub fn has_name(&self, name: &str) -> bool {
        match self.direct {
            Some(_) => self.index_of(name).is_some(),
            None => self
                .name_set
                .get_or_init(|| self.names().iter().cloned().collect())
                .contains(name),
        }
    }

    /// The index of the run named `name`, for direct names: its grid parts read from the
    /// end, one axis at a time (one candidate each, [`SweepPlan::direct_names`]), the rest
    /// its entry's prefix; checked by making the name again.
    fn index_of(&self, name: &str) -> Option<usize> {
        let axes = self.direct.as_ref()?;
        let mut rest = name;
        // The prefix is there when the first axis's part follows a `_`.
        let mut prefix: Option<&str> = Some(name);
        let mut digits = vec![0; axes.len()];
        for (k, parts) in axes.iter().enumerate().rev() {
            if let Some(&d) = parts.get(rest) {
                if k != 0 {
                    return None;
                }
                digits[k] = d;
                prefix = None;
                rest = "";
                continue;
            }
            let (at, d) = rest
                .match_indices('_')
                .find_map(|(at, _)| parts.get(&rest[at + 1..]).map(|&d| (at, d)))?;
            digits[k] = d;
            rest = &rest[..at];
            prefix = Some(rest);
        }
        let prefixes = self.prefixes();
        let entry = match (axes.is_empty(), prefix) {
            // Without a grid the name is the prefix, or "run" for an entry of no values.
            (true, _) => prefixes
                .iter()
                .position(|p| p.as_deref().unwrap_or("run") == name)?,
            (false, p) => prefixes.iter().position(|q| q.as_deref() == p)?,
        };
        let within = digits
            .iter()
            .zip(&self.grid)
            .fold(0, |n, (&d, (_, values))| n * values.len() + d);
        let per_entry: usize = self.grid.iter().map(|(_, v)| v.len()).product();
        let index = entry * per_entry + within;
        (index < self.len() && self.direct_name(index) == name).then_some(index)
    }

    /// Run `index`'s name when names are direct: as given or generated, never shortened.
    fn direct_name(&self, index: usize) -> String {
        let (given, values) = self.combination(index);
        given.unwrap_or_else(|| generated_name(&values))
    }

    /// Run `index`'s scene, built and validated now (an error names the run).
    pub fn run(&self, index: usize) -> Result<SweepRun, SceneError> {
        let (given, mut values) = self.combination(index);
        let run_name = match self.direct {
            Some(_) => given.unwrap_or_else(|| generated_name(&values)),
            None => self.names()[index].clone(),
        };
        let run_origin = format!("{} [sweep] run {run_name}", self.origin);
        let assignments: Vec<(String, toml::Value, String)> = values
            .iter()
            .map(|(k, v)| (k.clone(), v.clone(), run_origin.clone()))
            .collect();
        let mut scene = Scene::from_table(&self.table, &run_origin, &assignments, &self.overrides)?;
        scene.origin = self.origin.clone();
        scene.name = Some(format!("{}/{run_name}", self.name));
        values.extend(self.prescribed_powers(&scene, &values));
        values.sort_by_key(|(k, _)| self.keys.iter().position(|s| s == k));
        Ok(SweepRun {
            name: run_name,
            values,
            scene,
        })
    }

    /// The powers of `scene`'s prescribed lenses that are columns of the plan (its keys)
    /// but not among the run's `values`: each as the prescription gave it.
    fn prescribed_powers(&self, scene: &Scene, values: &[Assignment]) -> Vec<Assignment> {
        let lenses = &scene.optics().lenses;
        self.keys
            .iter()
            .filter(|k| !values.iter().any(|(v, _)| v == *k))
            .filter_map(|k| {
                let item = super::parse::indexed(k)?.ok()?;
                let lens = lenses.get(item.index)?;
                let prescribed = item.array == super::parse::LENSES_KEY
                    && item.name == "power"
                    && lens.prescribe.is_some();
                match (&lens.profile, prescribed) {
                    (crate::model::eyewear::ProfileSpec::Power(p), true) => {
                        Some((k.clone(), toml::Value::Float(*p)))
                    }
                    _ => None,
                }
            })
            .collect()
    }

    /// The runs that stand for the whole plan when it is too large to validate run by run:
    /// for each list entry, the run with every grid axis at its first value, and those
    /// with one axis at each of its other values. Every list entry and every grid value
    /// is in one of them; a combination that is invalid only together (ΔP above the
    /// cornea's limit for one cornea.C) is found by the shard that holds it, which builds
    /// and validates all its runs before it runs any. |list| · Σ|axis| runs, in sweep
    /// order.
    pub fn representatives(&self) -> Vec<usize> {
        let per_entry: usize = self.grid.iter().map(|(_, v)| v.len()).product();
        let mut out = Vec::new();
        for entry in 0..self.list.len().max(1) {
            let first = entry * per_entry;
            out.push(first);
            let mut stride = per_entry;
            for (_, axis) in &self.grid {
                stride /= axis.len();
                out.extend((1..axis.len()).map(|d| first + d * stride));
            }
        }
        out.sort_unstable();
        out
    }

    /// Whether `f` of a run's scene may differ from the base scene's: each list entry's
    /// values and each grid value set alone on the base (no scene validated; O(values)).
    /// Exact for an `f` of fields that each key sets alone, as every key's setter does.
    pub fn varies<T: PartialEq>(&self, f: impl Fn(&Scene) -> T) -> Result<bool, SceneError> {
        let base = Scene::from_table(&self.table, &self.origin, &[], &self.overrides)?;
        let shown = f(&base);
        let alone = |values: &[Assignment]| -> Result<bool, SceneError> {
            let mut scene = base.clone();
            for (key, value) in values {
                scene.set_toml(key, value, &self.origin)?;
            }
            Ok(f(&scene) != shown)
        };
        for e in &self.list {
            if alone(&e.values)? {
                return Ok(true);
            }
        }
        for (key, values) in &self.grid {
            for v in values {
                if alone(&[(key.clone(), v.clone())])? {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }

    /// Build and validate every run in turn, one scene at a time, and hand each to `f`:
    /// the first invalid run is the error.
    pub fn each_run(&self, mut f: impl FnMut(usize, &SweepRun)) -> Result<(), SceneError> {
        for i in 0..self.len() {
            f(i, &self.run(i)?);
        }
        Ok(())
    }

    /// The sweep of the runs `indices` only (each built now), in that order.
    pub fn sweep_of(&self, indices: &[usize]) -> Result<Sweep, SceneError> {
        Ok(Sweep {
            origin: self.origin.clone(),
            keys: self.keys.clone(),
            runs: indices
                .iter()
                .map(|&i| self.run(i))
                .collect::<Result<_, _>>()?,
            name: self.name.clone(),
            path: self.path.clone(),
            sample: self.sample.clone(),
        })
    }

    /// Run `index`'s name as given or generated (before it is made unique) and its values
    /// in the list's then the grid's order: the list entry is index / (grid runs), the
    /// grid's axes the digits of the rest, the last axis fastest.
    fn combination(&self, index: usize) -> Combination {
        let per_entry: usize = self.grid.iter().map(|(_, v)| v.len()).product();
        let (mut name, mut values) = match self.list.get(index / per_entry) {
            Some(e) => (e.name.clone(), e.values.clone()),
            None => (None, Vec::new()),
        };
        let mut rest = index % per_entry;
        let mut digits = vec![0; self.grid.len()];
        for (d, (_, axis)) in digits.iter_mut().zip(&self.grid).rev() {
            *d = rest % axis.len();
            rest /= axis.len();
        }
        for ((key, axis), d) in self.grid.iter().zip(digits) {
            let v = &axis[d];
            // A named run crossed with a grid keeps its name as a prefix.
            name = name.map(|n| format!("{n}_{}", part(key, v)));
            values.push((key.clone(), v.clone()));
        }
        (name, values)
    }

    /// Every run's directory name, unique: the first run of each name keeps it, and a
    /// later run of the same name becomes `name-2`, `name-3`, ..., skipping every name a
    /// run was given (a user's own `a-2` stays `a-2`, and no two runs share a name).
    fn unique_names(&self) -> Vec<String> {
        let n = self.len();
        let mut names: Vec<String> = (0..n)
            .map(|i| {
                let (given, values) = self.combination(i);
                shorten(given.unwrap_or_else(|| generated_name(&values)))
            })
            .collect();
        let repeated: Vec<bool> = {
            let mut seen = std::collections::HashSet::with_capacity(n);
            names
                .iter()
                .map(|name| !seen.insert(name.as_str()))
                .collect()
        };
        if !repeated.contains(&true) {
            return names; // the usual case: no second set of a million names
        }
        let mut taken: std::collections::HashSet<String> = names.iter().cloned().collect();
        for (name, repeated) in names.iter_mut().zip(repeated) {
            if repeated {
                *name = unique(std::mem::take(name), &taken);
                taken.insert(name.clone());
            }
        }
        names
    }
}
