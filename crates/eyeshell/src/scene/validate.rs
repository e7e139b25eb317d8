//! Validating a scene's effective values: each key's own range, then the limits that tie
//! keys together, then the sizes a run will allocate and write.

use super::keys::{KeyValue, KEYS};
use super::parse::{override_origin, source_key, LENSES_KEY, SURFACES_KEY};
use super::view::show;
use super::{Scene, SceneError, Sources};
use crate::model::optics::Source;
use crate::text::{decimals6, number};

impl Scene {
    /// Where the value of `key` came from: the last `--set` of it (or, for a surface's key,
    /// of any surface), else the scene's origin. For errors found after the scene was read
    /// (an optics key that cannot be traced).
    pub fn origin_of_key(&self, key: &str) -> String {
        let family = |k: &str| {
            if k.starts_with(SURFACES_KEY) {
                SURFACES_KEY.to_string()
            } else if k.starts_with(LENSES_KEY) {
                LENSES_KEY.to_string()
            } else {
                k.to_string()
            }
        };
        self.overrides
            .iter()
            .rev()
            .find(|text| {
                text.split_once('=')
                    .is_some_and(|(k, _)| family(k.trim()) == family(key))
            })
            .map(|text| override_origin(text.as_str()))
            .unwrap_or_else(|| self.origin.clone())
    }

    /// The origin of the most recent of `keys` to be set, else the scene's origin.
    pub(super) fn origin_of(&self, sources: &Sources, keys: &[&str]) -> String {
        keys.iter()
            .filter_map(|k| sources.get(k))
            .max_by_key(|(n, _)| *n)
            .map(|(_, o)| o.clone())
            .unwrap_or_else(|| self.origin.clone())
    }

    /// The error of `keys[0]` (blamed on whichever of `keys` was set last) at `value`.
    fn invalid(
        &self,
        sources: &Sources,
        keys: &[&str],
        value: String,
        problem: String,
    ) -> SceneError {
        SceneError::Invalid {
            origin: self.origin_of(sources, keys),
            key: keys[0].to_string(),
            value,
            problem,
        }
    }

    pub(super) fn validate_from(&self, sources: &Sources) -> Result<(), SceneError> {
        let invalid = |keys: &[&str], value: String, problem: String| {
            self.invalid(sources, keys, value, problem)
        };
        self.validate_table_clock(sources)?;
        for spec in KEYS {
            // A cornea that follows geometry.R0 has its value: that key's check is its own.
            if spec.key == "cornea.R0" && self.params.cornea_follows_radius {
                continue;
            }
            // So does a run's length that is the window of its ages: the clock's check
            // names time.end.
            let ages = self
                .growth
                .as_ref()
                .is_some_and(|g| g.clock.window().is_some());
            if spec.key == "growth.t_end" && ages && self.written_clock.t_end.is_none() {
                continue;
            }
            let check = match spec.get(self) {
                KeyValue::Float(x) => spec.rule.check_float(x),
                KeyValue::Count(n) => spec.rule.check_count(n),
                KeyValue::Floats(xs) => spec.rule.check_floats(&xs),
                _ => Ok(()),
            };
            if let Err(problem) = check {
                return Err(invalid(
                    &[spec.key],
                    show(&spec.get(self)),
                    problem.to_string(),
                ));
            }
        }
        // Limits that tie keys together; every key is finite and in its own range by now.
        let p = &self.params;
        let length = p.length();
        if self.solver.epsilon >= length {
            return Err(invalid(
                &["solver.epsilon", "geometry.R0", "geometry.fraction"],
                show(&KeyValue::Float(self.solver.epsilon)),
                format!(
                    "must be below the shell's length L = π·fraction·R0 = {} mm \
                     (geometry.fraction = {}, geometry.R0 = {})",
                    decimals6(length),
                    number(p.fraction),
                    number(p.r0)
                ),
            ));
        }
        self.validate_mesh(sources)?;
        self.validate_sizes(sources)?;
        self.validate_cornea(sources)?;
        self.validate_traced_optics(sources)?;
        if self.growth.is_some() {
            let o = self.optics();
            if !o.lenses.is_empty() && self.stimulus_source() != Source::Optics {
                return Err(invalid(
                    &["optics.lenses"],
                    crate::model::eyewear::lenses_text(&o.lenses),
                    "need stimulus.source = \"optics\": the published surfaces are of the naked eye".into(),
                ));
            }
            if !(o.myopia_d >= -25.0 && o.myopia_d <= 0.0) {
                return Err(invalid(
                    &["stimulus.myopia_D"],
                    number(o.myopia_d),
                    "must lie in [-25, 0] D".into(),
                ));
            }
            if !(o.hyperopia_d >= 0.0 && o.hyperopia_d <= 25.0) {
                return Err(invalid(
                    &["stimulus.hyperopia_D"],
                    number(o.hyperopia_d),
                    "must lie in [0, 25] D".into(),
                ));
            }
            let (lo, hi, why) = o.wavelength_range();
            if !(o.refraction_wavelength >= lo && o.refraction_wavelength <= hi) {
                return Err(invalid(
                    &["optics.refraction_wavelength", "optics.eye"],
                    number(o.refraction_wavelength),
                    format!("must lie between {lo} and {hi} nm {why}"),
                ));
            }
        }
        if self.solver.richardson && self.growth.is_some() {
            return Err(invalid(
                &["solver.richardson"],
                show(&KeyValue::Bool(true)),
                "is for elastic solves only: a growth run is not extrapolated".into(),
            ));
        }
        if let Some(g) = &self.growth {
            // The clock and the schedule: each problem names its key and shows its value. A
            // growth.t_end written beside ages must be their window (the run's t_end is).
            if let Some(written) = self.written_clock.t_end.filter(|_| g.clock.check().is_ok()) {
                if let Err((_, problem)) = g.clock.check_window(written) {
                    return Err(invalid(
                        &["growth.t_end", "time.end"],
                        number(written),
                        problem,
                    ));
                }
            }
            if let Some((key, problem)) = (g.clock.check())
                .and_then(|()| g.clock.check_window(g.t_end))
                .and_then(|()| g.schedule.check())
                .and_then(|()| g.schedule.check_window(&g.clock, g.t_end))
                .and_then(|()| {
                    match self.stimulus_source() == Source::Optics
                        && !self.optics().times().is_empty()
                    {
                        // The schedule's clock beside optics that change with age
                        // (growth/real_time.rs).
                        true => {
                            crate::growth::real_time::check_zeros(&g.schedule, &g.clock, g.t_end)
                        }
                        false => Ok(()),
                    }
                })
                .err()
            {
                let key = super::names::key_of(key);
                let value =
                    crate::scene::keys::find(key).map_or_else(String::new, |k| show(&k.get(self)));
                return Err(invalid(&[key], value, problem));
            }
            self.check_output_times(g, sources)?;
        }
        Ok(())
    }
}

impl Scene {
    /// output.times in the scene's terms: each in (0, growth.t_end], or with ages each in
    /// (time.start, time.end] (the model's times are those ages less time.start).
    fn check_output_times(
        &self,
        g: &crate::growth::GrowthParams,
        sources: &Sources,
    ) -> Result<(), SceneError> {
        let times = &self.growth_settings.output_times;
        let written = self.written_output_times();
        let shown = || show(&KeyValue::Floats(written.clone()));
        let fail =
            |keys: &[&str], problem: String| Err(self.invalid(sources, keys, shown(), problem));
        let Some((a0, a1)) = g.clock.window() else {
            return match times.last().filter(|&&t| t > g.t_end) {
                Some(&last) => fail(
                    &["output.times", "growth.t_end"],
                    format!(
                        "must lie in (0, growth.t_end]: {} is after growth.t_end = {}",
                        number(last),
                        number(g.t_end)
                    ),
                ),
                None => Ok(()),
            };
        };
        let unit = g.clock.unit.name();
        let age = |i: usize| number(written.get(i).copied().unwrap_or(times[i] + a0));
        if let Some(i) = times.iter().position(|&t| t <= 0.0) {
            return fail(
                &["output.times", "time.start"],
                format!(
                    "must be ages in (time.start, time.end]: {} {unit} is not after time.start = {} {unit}",
                    age(i),
                    number(a0)
                ),
            );
        }
        if let Some(i) = times.iter().position(|&t| t > g.t_end) {
            return fail(
                &["output.times", "time.end"],
                format!(
                    "must be ages in (time.start, time.end]: {} {unit} is after time.end = {} {unit}",
                    age(i),
                    number(a1)
                ),
            );
        }
        Ok(())
    }

    /// What a run of this scene will allocate and write, counted before it starts: the
    /// largest mesh any of its solves lays (with solver.richardson, the mesh halved twice)
    /// must fit [`crate::mesh::MAX_NODES`], which bounds a solve's memory
    /// ([`crate::mesh::BYTES_PER_NODE`] a node); a growth run's files together must fit
    /// [`crate::plan::MAX_RUN_BYTES`]. The mesh itself is valid by now.
    fn validate_sizes(&self, sources: &Sources) -> Result<(), SceneError> {
        use crate::mesh::{BYTES_PER_NODE, MAX_NODES};
        let invalid = |keys: &[&str], value: String, problem: String| {
            self.invalid(sources, keys, value, problem)
        };
        let gb = |bytes: u64| format!("{:.1} GB", bytes as f64 / 1e9);
        // The nodes of the mesh solver.nodes lays (breakpoints at most 3 more).
        let planned = crate::bvp::solve::mesh_plan(&self.params, &self.solver)
            .map(|plan| plan.nodes(3))
            .unwrap_or(MAX_NODES);
        if self.solver.richardson {
            // Without solver.tol: solves on M, M halved and M halved twice (4M − 3 nodes).
            // With it, the adapted mesh M has at most ⌈max_nodes / 2⌉ nodes, so M halved
            // twice at most 2·max_nodes + 1.
            let (keys, value, finest, fix): (&[&str], usize, usize, String) = match self.solver.tol
            {
                None => (
                    &["solver.nodes", "solver.richardson"],
                    self.solver.nodes,
                    4 * planned.saturating_sub(1) + 1,
                    format!(
                        "solver.nodes at most about {}",
                        (MAX_NODES - 1) / 4 + 1 - (planned - self.solver.nodes.min(planned))
                    ),
                ),
                Some(_) => (
                    &["solver.max_nodes", "solver.richardson"],
                    self.solver.max_nodes,
                    2 * self.solver.max_nodes + 1,
                    format!("solver.max_nodes at most {}", (MAX_NODES - 1) / 2),
                ),
            };
            if finest > MAX_NODES {
                return Err(invalid(
                    keys,
                    value.to_string(),
                    format!(
                        "is too large with solver.richardson: its solve on the mesh halved twice would lay {finest} nodes, about {} of memory, more than the {MAX_NODES} nodes ({}) a solve may: give {fix}, or leave out solver.richardson",
                        gb(finest as u64 * BYTES_PER_NODE),
                        gb(MAX_NODES as u64 * BYTES_PER_NODE)
                    ),
                ));
            }
        }
        if self.growth.is_some() {
            use crate::plan::{planned_bytes, MAX_RUN_BYTES};
            let g = &self.growth_settings;
            // With solver.tol the mesh is chosen as the run starts: at most max_nodes.
            let (nodes, keys): (usize, &[&str]) = match self.solver.tol {
                None => (planned, &["output.times", "solver.nodes"]),
                Some(_) => (self.solver.max_nodes, &["output.times", "solver.max_nodes"]),
            };
            let images = (self.refraction_optics())
                .map_or(0, |o| crate::growth::refraction::image_count(&o));
            let bytes = planned_bytes(nodes, g.output_times.len(), g.history_points, images);
            if bytes > MAX_RUN_BYTES {
                return Err(invalid(
                    keys,
                    show(&KeyValue::Floats(g.output_times.clone())),
                    format!(
                        "would have the run write about {} ({} snapshot files of up to {nodes} nodes each, and the series), more than the {} a growth run may write: give fewer output.times or fewer nodes",
                        gb(bytes),
                        g.output_times.len() + 1,
                        gb(MAX_RUN_BYTES)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The cornea's pressure limit (docs/MODEL.md §3), after the sizes: a cornea that follows
    /// an absurd geometry.R0 is that key's error, said as such first.
    fn validate_cornea(&self, sources: &Sources) -> Result<(), SceneError> {
        let invalid = |keys: &[&str], value: String, problem: String| {
            self.invalid(sources, keys, value, problem)
        };
        let p = &self.params;
        let p_max = crate::model::cornea::max_pressure(&p.cornea);
        if p.dp > p_max {
            let radius = if p.cornea_follows_radius {
                "geometry.R0"
            } else {
                "cornea.R0"
            };
            return Err(invalid(
                &["pressure.dP", "cornea.C", "cornea.H", radius],
                show(&KeyValue::Float(p.dp)),
                format!(
                    "is above the cornea's limit: the largest admissible ΔP is {} kPa \
                     (4 C_c H_c / R_c · (6/7) · 7^(-1/6) with cornea.C = {}, cornea.H = {}, cornea.R0 = {}{})",
                    decimals6(p_max),
                    number(p.cornea.c),
                    number(p.cornea.h),
                    number(p.cornea.r0),
                    if p.cornea_follows_radius { ", following geometry.R0" } else { "" }
                ),
            ));
        }
        Ok(())
    }

    /// The traced optics over the whole run, and the two wavelengths a growth run reads.
    /// The optics' tables are over ages exactly when the scene counts in ages: a table over
    /// t beside time.unit, or over age without it, is refused before any other check reads
    /// its times.
    fn validate_table_clock(&self, sources: &Sources) -> Result<(), SceneError> {
        let ages = self
            .growth
            .as_ref()
            .is_some_and(|g| g.clock.window().is_some());
        let (over_t, over_age) = self.written_clock.optics_time_keys;
        if self.optics().times().is_empty() || !((ages && over_t) || (!ages && over_age)) {
            return Ok(());
        }
        let surfaces = crate::scene::keys::find("optics.surfaces")
            .map_or(String::new(), |k| show(&k.get(self)));
        let problem = if ages {
            "gives a table over t, but the scene counts in ages (time.unit): give each table's times as ages, { age = [...], value = [...] } (t is the age less time.start)"
        } else {
            "gives a table over age, but the scene counts no ages: set time.unit, time.start and time.end, or give the tables over t"
        };
        Err(self.invalid(
            sources,
            &["optics.surfaces", "time.unit"],
            surfaces,
            problem.into(),
        ))
    }

    fn validate_traced_optics(&self, sources: &Sources) -> Result<(), SceneError> {
        if self.stimulus_source() == Source::Optics {
            // The whole run: growth.t_end, or the [0, 1] an elastic scene's eye is drawn over.
            let t_end = self.growth.as_ref().map_or(1.0, |g| g.t_end);
            let growth_reads = || match self.growth {
                Some(_) => self.optics().check_growth_wavelengths(),
                None => Ok(()),
            };
            if let Err(e) = self
                .optics()
                .check_over(t_end)
                .and_then(|()| growth_reads())
            {
                return Err(SceneError::Invalid {
                    origin: self.origin_of(sources, &[source_key(&e.key)]),
                    key: e.key,
                    value: e.value,
                    problem: e.problem,
                });
            }
        }
        Ok(())
    }

    /// The mesh the solver will lay, counted before anything is allocated: every derived
    /// size (the shell's length, the pole's and the cornea's graded nodes, the total) must
    /// be finite and bounded (docs/MODEL.md §3–4, [`crate::mesh::plan`]).
    fn validate_mesh(&self, sources: &Sources) -> Result<(), SceneError> {
        use crate::mesh::MeshError;
        let Err(e) = crate::bvp::solve::mesh_plan(&self.params, &self.solver) else {
            return Ok(());
        };
        let (keys, value, problem): (&[&str], String, String) = match &e {
            MeshError::Interval { length, .. } => (
                &["geometry.R0", "geometry.fraction", "solver.epsilon"],
                number(self.params.r0),
                format!("makes the shell's length L = π·fraction·R0 = {} mm, which is not finite", number(*length)),
            ),
            MeshError::TooFewNodes { .. } | MeshError::TooManyNodes { .. } => (
                &["solver.nodes", "solver.epsilon", "material.bending", "solver.cornea_grading"],
                self.solver.nodes.to_string(),
                format!("is too large for the mesh: {e}"),
            ),
            MeshError::LayerUnresolvable { .. } => (
                &["material.bending", "solver.cornea_grading"],
                number(self.params.e_b),
                format!("is too small for this shell (ΔP, R0): {e}; raise material.bending or set solver.cornea_grading = false"),
            ),
            // A refusal the mesh adds later: the node count is what a scene sets.
            _ => (
                &["solver.nodes", "solver.epsilon"],
                self.solver.nodes.to_string(),
                format!("makes no mesh: {e}"),
            ),
        };
        Err(SceneError::Invalid {
            origin: self.origin_of(sources, keys),
            key: keys[0].to_string(),
            value,
            problem,
        })
    }
}
