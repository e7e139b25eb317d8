//! The stimulus's surfaces computed from a schematic eye (`stimulus.source = "optics"`,
//! docs/guide/optics.md): the scene's `optics.*` keys, the surfaces they give (traced once,
//! before a run starts), and their errors in the user's terms (the key to change).
//!
//! The first wavelength's surface is the stimulus's blue surface, the second's the red one
//! (for the classification only). Both are held as the optics crate's C² spline R(φ) about the
//! blue surface's polar centre `stimulus.blue.z_B`, so that d and φ_max keep their meaning
//! (docs/MODEL.md §6): φ_max is where the computed surface ends.

use std::sync::{Arc, Mutex};

use eyeshell_optics as optics;
use eyeshell_optics::{Criterion, OpticalSystem, OpticsError, PolarSpline, Pupil, Surfaces};

use super::eye::{self, SurfaceKeyError, SurfaceSpec};
pub use super::images::{ComputedImage, ShareCurve};
use crate::names::Quantity;
use crate::text::number;

/// The names `stimulus.source` takes, in the order of [`Source`]'s variants.
pub const SOURCES: [&str; 2] = ["polynomial", "optics"];

/// The names `optics.eye` takes: the optics crate's built-in eyes, then `custom` (the eye of
/// `[[optics.surfaces]]`).
pub const EYES: [&str; optics::eyes::BUILTIN.len() + 1] = {
    let mut names = [CUSTOM; optics::eyes::BUILTIN.len() + 1];
    let mut i = 0;
    while i < optics::eyes::BUILTIN.len() {
        names[i] = optics::eyes::BUILTIN[i];
        i += 1;
    }
    names
};
/// The name of the eye a scene describes itself.
pub const CUSTOM: &str = "custom";

/// The names `optics.focus` takes, in the order of [`FOCI`].
pub const FOCUS_NAMES: [&str; 4] = ["mean-sphere", "strehl", "sagittal", "tangential"];
const FOCI: [Criterion; 4] = [
    Criterion::MeanSphere,
    Criterion::Strehl,
    Criterion::Sagittal,
    Criterion::Tangential,
];

/// The wavelengths (nm) a custom eye may be traced at (its media are the scene's own laws,
/// checked physical at each); a built-in eye has its source's range
/// ([`OpticsSpec::wavelength_range`]).
pub const WAVELENGTH_RANGE: (f64, f64) = (300.0, 1200.0);
/// How closely a run's best foci follow the converged ones (mm): the agreement
/// [`OpticsSpec::focus_settings`] asks of a ray count and twice as many. About 3e-5 D of
/// refraction at the pole.
pub const RAYS_TOLERANCE_MM: f64 = 1e-5;

/// The gradient-index lens's integration in a run's traces: a local error of 1e-6 mm a step
/// moves a best focus by at most about 1e-6 mm (docs/optics.md's convergence table: 1.0e-6 mm
/// at 40°), a tenth of [`RAYS_TOLERANCE_MM`], in 40 % of the steps of the default 1e-8 mm.
pub(crate) fn run_grin() -> optics::GrinSettings {
    optics::GrinSettings {
        tolerance: 1e-6,
        ..Default::default()
    }
}

/// The widest pupil (mm): wider than any eye's (about 8 mm dilated), and beyond it the built-in
/// eyes' lens surfaces turn back before the rays reach them.
pub const MAX_PUPIL: f64 = 10.0;

/// Where the stimulus's surfaces come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Source {
    /// The published polynomial surfaces (`stimulus.blue.*`, `stimulus.red.*`).
    #[default]
    Polynomial,
    /// Computed from the schematic eye of `optics.*`.
    Optics,
}

/// The `optics.*` keys.
#[derive(Clone, Debug, PartialEq)]
pub struct OpticsSpec {
    /// Index into [`EYES`].
    pub eye: usize,
    /// Pupil diameter (mm); the pupil lies where the eye's source puts it.
    pub pupil: f64,
    /// Wavelengths (nm): blue (the stimulus), red (the classification), then any others
    /// (`eyeshell optics` only).
    pub wavelengths: Vec<f64>,
    /// Index into [`FOCUS_NAMES`].
    pub focus: usize,
    /// The largest field angle traced (degrees, in air).
    pub max_field: f64,
    /// The eyewear worn (`[[optics.lenses]]`), from the eye outwards.
    pub lenses: Vec<super::eyewear::LensSpec>,
    /// The wavelength (nm) of the refraction in dioptres.
    pub refraction_wavelength: f64,
    /// `stimulus.classify`: index into [`super::eyewear::CLASSIFY`].
    pub classify: usize,
    /// `stimulus.myopia_D`, `stimulus.hyperopia_D`: the dioptre thresholds.
    pub myopia_d: f64,
    pub hyperopia_d: f64,
    /// `[[optics.surfaces]]`: a custom eye's surfaces, or overrides of a built-in eye's.
    pub surfaces: Vec<SurfaceSpec>,
    /// optics.pupil_position: the stop's distance from the corneal apex (mm); unset, a
    /// built-in eye's source's (on the lens's front vertex, which it follows).
    pub pupil_position: Option<f64>,
    /// How messages name the tables' times (over t, or over ages in a scene with
    /// time.unit); the tables are over t either way.
    pub table_clock: super::eye::TableClock,
}

impl Default for OpticsSpec {
    fn default() -> Self {
        OpticsSpec {
            eye: 0,
            pupil: 3.0,
            wavelengths: vec![400.0, 600.0],
            focus: 0,
            max_field: 40.0,
            lenses: Vec::new(),
            refraction_wavelength: 555.0,
            classify: 0,
            myopia_d: -0.5,
            hyperopia_d: 0.5,
            surfaces: Vec::new(),
            pupil_position: None,
            table_clock: Default::default(),
        }
    }
}

/// A problem with the `optics.*` keys: the key to change and why.
#[derive(Clone, Debug, PartialEq)]
pub struct OpticsKeyError {
    /// The key, or an item of it (`optics.pupil`, `optics.surfaces[2].radius`,
    /// `optics.lenses[1].zones[0].radius`).
    pub key: String,
    /// The key's value, readable.
    pub value: String,
    pub problem: String,
}

impl std::fmt::Display for OpticsKeyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} = {} {}", self.key, self.value, self.problem)
    }
}

impl OpticsSpec {
    pub fn eye_name(&self) -> &'static str {
        EYES[self.eye]
    }

    pub fn criterion(&self) -> Criterion {
        FOCI[self.focus]
    }

    /// The built-in eye these keys start from (`None` for a custom eye).
    fn base(&self) -> Option<OpticalSystem> {
        optics::eyes::builtin(self.eye_name())
    }

    /// The eye at growth time 0 (see [`OpticsSpec::system_at`]).
    pub fn system(&self) -> Result<OpticalSystem, OpticsKeyError> {
        self.system_at(0.0)
    }

    /// The optical system at growth time `t`: the eye of `optics.eye` with the surface tables
    /// applied (every table read at t), its stop at `optics.pupil_position` or where the
    /// eye's source puts it. Checked: the error names the key to change.
    pub fn system_at(&self, t: f64) -> Result<OpticalSystem, OpticsKeyError> {
        let base = self.base();
        let mut system = eye::assemble(base.as_ref(), &self.surfaces, t).map_err(surface_error)?;
        let position = match (self.pupil_position, &base) {
            (Some(z), _) => z,
            // On the same surface's vertex as in the source, wherever the tables move it.
            (None, Some(b)) => match eye::pupil_vertex(b) {
                Some(i) => system.vertices()[i],
                None => b.pupil_position.unwrap_or(3.6),
            },
            (None, None) => {
                return Err(OpticsKeyError {
                    key: Quantity::PupilPosition.to_string(),
                    value: "(none)".into(),
                    problem: format!("must be given for {} = \"custom\" (mm from the corneal apex to the pupil's centre)", Quantity::Optics),
                })
            }
        };
        let checked = OpticalSystem::new(
            system.name.clone(),
            system.object.clone(),
            system.elements.clone(),
        )
        .map_err(|e| self.explain(&e))?;
        system = checked;
        system
            .check_pupil_position(position)
            .map_err(|e| OpticsKeyError {
                key: Quantity::PupilPosition.to_string(),
                value: number(position),
                problem: match e {
                    OpticsError::InvalidInput { reason, .. } => reason,
                    e => crate::text::one_line(&e.to_string()),
                },
            })?;
        Ok(system.with_pupil_position(position))
    }

    /// The growth times at which the eye's surfaces are traced: 0 and every time a table
    /// names, in order (empty when no key is a table: the eye does not change).
    pub fn times(&self) -> Vec<f64> {
        let mut ts: Vec<f64> = self.surfaces.iter().flat_map(|s| s.times()).collect();
        if ts.is_empty() {
            return ts;
        }
        ts.push(0.0);
        ts.sort_by(f64::total_cmp);
        ts.dedup();
        ts
    }

    /// The pupil: `optics.pupil` wide, at the system's stop.
    pub fn pupil_stop(&self, system: &OpticalSystem) -> Pupil {
        Pupil {
            diameter: self.pupil,
            position: system.pupil_position.unwrap_or(3.6),
        }
    }

    fn wavelengths_text(&self) -> String {
        let items: Vec<String> = self
            .wavelengths
            .iter()
            .take(8)
            .map(|w| number(*w))
            .collect();
        let more = if self.wavelengths.len() > 8 {
            ", …"
        } else {
            ""
        };
        format!("[{}{more}]", items.join(", "))
    }

    /// The wavelengths (nm) this eye's dispersion holds for, and why: a built-in eye's, as
    /// its source gives them ([`optics::eyes::wavelength_range`]); a custom eye's media are
    /// the scene's own laws, checked physical at each wavelength, within
    /// [`WAVELENGTH_RANGE`].
    pub fn wavelength_range(&self) -> (f64, f64, String) {
        match optics::eyes::wavelength_range(self.eye_name()) {
            Some(r) => (
                r.lo,
                r.hi,
                format!("for the {} eye: {}", self.eye_name(), r.source),
            ),
            None => (
                WAVELENGTH_RANGE.0,
                WAVELENGTH_RANGE.1,
                "where the eyes' dispersion laws are used".into(),
            ),
        }
    }

    /// The check of [`OpticsSpec::check`] and the eye over the whole run, growth times
    /// [0, `t_end`]: every table over time between and beyond its points
    /// ([`eye::SurfaceSpec::check_over`]), and the eye a valid system wherever a table
    /// is extreme and at both ends of the run.
    pub fn check_over(&self, t_end: f64) -> Result<(), OpticsKeyError> {
        self.check()?;
        if self.times().is_empty() {
            return Ok(());
        }
        let mut times = vec![0.0, t_end];
        for (i, s) in self.surfaces.iter().enumerate() {
            s.check_over(i, t_end, self.table_clock)
                .map_err(surface_error)?;
            times.extend(s.extreme_times(t_end));
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        for t in times {
            self.system_checked_at(t)?;
        }
        Ok(())
    }

    /// The eye at growth time `t` a valid system at every wavelength; an error names the
    /// time when the eye changes with it.
    fn system_checked_at(&self, t: f64) -> Result<(), OpticsKeyError> {
        let timed = !self.times().is_empty();
        let at_time = |mut e: OpticsKeyError| {
            if timed {
                e.problem = format!(
                    "{} (the eye at {})",
                    e.problem,
                    self.table_clock.eye_time(t)
                );
            }
            e
        };
        let system = self.system_at(t).map_err(at_time)?;
        for &w in &self.wavelengths {
            system
                .check_wavelength(w)
                .map_err(|e| at_time(self.explain(&e)))?;
        }
        Ok(())
    }

    /// The checks that need no ray: counts and ranges, each naming its key.
    pub fn check(&self) -> Result<(), OpticsKeyError> {
        let err = |key: &str, value: String, problem: String| OpticsKeyError {
            key: key.to_string(),
            value,
            problem,
        };
        if !(self.pupil > 0.0 && self.pupil <= MAX_PUPIL) {
            return Err(err(
                Quantity::Pupil.name(),
                number(self.pupil),
                format!("must lie in (0, {MAX_PUPIL}] mm (a pupil's diameter)"),
            ));
        }
        if self.wavelengths.is_empty() {
            return Err(err(
                Quantity::Wavelengths.name(),
                self.wavelengths_text(),
                "must list at least one wavelength (nm)".into(),
            ));
        }
        let (lo, hi, why) = self.wavelength_range();
        if let Some(w) = self.wavelengths.iter().find(|w| !(**w >= lo && **w <= hi)) {
            return Err(err(
                Quantity::Wavelengths.name(),
                self.wavelengths_text(),
                format!(
                    "must lie between {lo} and {hi} nm {why} ({} does not)",
                    number(*w)
                ),
            ));
        }
        let (blue, red) = match self.wavelengths[..] {
            [blue, red, ..] => (blue, red),
            _ => (f64::NEG_INFINITY, f64::INFINITY),
        };
        if !(blue < red) {
            return Err(err(
                Quantity::Wavelengths.name(),
                self.wavelengths_text(),
                format!(
                    "must list the blue wavelength first, then a longer red one ({} nm is not shorter than {} nm): the blue surface is the stimulus, the red one classifies the eye",
                    number(blue),
                    number(red)
                ),
            ));
        }
        let contacts: Vec<usize> = (self.lenses.iter().enumerate())
            .filter(|(_, l)| l.kind == 1)
            .map(|(i, _)| i)
            .collect();
        if let [first, second, ..] = contacts[..] {
            return Err(err(
                &format!("{}[{second}].kind", Quantity::Lenses),
                "\"contact\"".into(),
                format!(
                    "is a second contact lens ({}[{first}] is one): two contact lenses cannot be worn at once, the cornea holds one",
                    Quantity::Lenses
                ),
            ));
        }
        if !(self.max_field >= 5.0 && self.max_field <= optics::MAX_FIELD_DEG) {
            return Err(err(
                Quantity::MaxField.name(),
                number(self.max_field),
                format!(
                    "must lie in [5, {}] degrees (field angles in air)",
                    optics::MAX_FIELD_DEG
                ),
            ));
        }
        if self.surfaces.len() > eye::MAX_SURFACES {
            return Err(err(
                Quantity::Surfaces.name(),
                format!("({} surface tables)", self.surfaces.len()),
                format!("must describe at most {} surfaces", eye::MAX_SURFACES),
            ));
        }
        for (i, s) in self.surfaces.iter().enumerate() {
            s.check(i, &self.wavelengths, self.table_clock)
                .map_err(surface_error)?;
        }
        if let Some(z) = self.pupil_position {
            if !(z.is_finite() && z > 0.0) {
                return Err(err(
                    Quantity::PupilPosition.name(),
                    number(z),
                    "must be a positive distance (mm from the corneal apex)".into(),
                ));
            }
        }
        // The eye at every time it is traced: each a valid system at every wavelength.
        let times = self.times();
        for &t in if times.is_empty() {
            &[0.0][..]
        } else {
            &times[..]
        } {
            self.system_checked_at(t)?;
        }
        Ok(())
    }

    /// The wavelengths a growth run reads: two at least, the blue surface's (the stimulus) and
    /// the red one's (it classifies the eye); `eyeshell optics` draws the surfaces of one.
    pub fn check_growth_wavelengths(&self) -> Result<(), OpticsKeyError> {
        if self.wavelengths.len() < 2 {
            return Err(OpticsKeyError {
                key: Quantity::Wavelengths.name().to_string(),
                value: self.wavelengths_text(),
                problem: "must list at least two wavelengths (nm) for growth: blue (the stimulus), then red (it classifies the eye)".into(),
            });
        }
        Ok(())
    }

    /// Trace the surfaces and make the stimulus's splines about `z_c`: once for an eye that
    /// does not change, else at each of [`OpticsSpec::times`] (the surfaces at time 0 are
    /// those of `surfaces`, `blue` and `red`).
    pub fn compute(&self, z_c: f64) -> Result<ComputedOptics, OpticsKeyError> {
        self.trace(z_c, self.times())
    }

    /// The surfaces a growth run to `t_end` reads: as [`OpticsSpec::compute`], traced at
    /// [`OpticsSpec::times_until`] `t_end`, so that the blend interpolates between traced
    /// eyes over the whole run and never extrapolates them (a table ending early leaves the
    /// eye changing along its end slope, which the traced surfaces' continuation does not
    /// follow: a blend carried far beyond its last time can fold the surface).
    pub fn compute_over(&self, z_c: f64, t_end: f64) -> Result<ComputedOptics, OpticsKeyError> {
        self.check_growth_wavelengths()?;
        self.trace(z_c, self.times_until(t_end))
    }

    /// [`OpticsSpec::times`], and `t_end` where it lies beyond the last of them (none for an
    /// eye that does not change).
    pub fn times_until(&self, t_end: f64) -> Vec<f64> {
        let mut ts = self.times();
        if ts
            .last()
            .is_some_and(|&last| t_end.is_finite() && t_end > last)
        {
            ts.push(t_end);
        }
        ts
    }

    fn trace(&self, z_c: f64, times: Vec<f64>) -> Result<ComputedOptics, OpticsKeyError> {
        self.check()?;
        let start = std::time::Instant::now();
        super::eyewear::check_coverage(self)?;
        let (mut surfaces, blue, red, images) = self.compute_at(0.0, z_c)?;
        let mut timed = None;
        if times.len() > 1 {
            let mut blues = vec![blue.clone()];
            let mut reds = vec![red.clone()];
            for &t in &times[1..] {
                let (more, b, r, _) = self.compute_at(t, z_c)?;
                surfaces.rays_traced += more.rays_traced;
                blues.push(b);
                reds.push(r);
            }
            timed = Some(TimedSurfaces {
                times,
                blue: blues,
                red: reds,
            });
        }
        Ok(ComputedOptics {
            spec: self.clone(),
            z_c,
            blue,
            red,
            surfaces,
            images,
            timed,
            wall_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The surfaces of the eye as it is at growth time `t` alone (its tables read at t; no
    /// blending over the other times): what `eyeshell optics --at T` draws.
    pub fn compute_eye_at(&self, t: f64, z_c: f64) -> Result<ComputedOptics, OpticsKeyError> {
        self.check()?;
        let start = std::time::Instant::now();
        super::eyewear::check_coverage(self)?;
        let (surfaces, blue, red, images) = self.compute_at(t, z_c)?;
        Ok(ComputedOptics {
            spec: self.clone(),
            z_c,
            blue,
            red,
            surfaces,
            images,
            timed: None,
            wall_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The pupil's sampling for every trace of these optics: the fewest rays across the pupil
    /// whose best foci agree with twice as many to [`RAYS_TOLERANCE_MM`]
    /// ([`optics::rays_for`]), checked once on the eye at growth time 0 and kept for every
    /// table time and every table. The probes are where the count matters most: the eye as
    /// worn on the axis and at `optics.max_field` at the stimulus's wavelengths, and the
    /// naked eye behind the strongest spectacle lenses of the refraction tables (the pole's
    /// on the axis, the peripheral table's at the largest field) at the refraction's
    /// wavelength. Optics that cannot be built keep the default; their error comes from the
    /// trace itself.
    pub fn focus_settings(&self) -> optics::FocusSettings {
        static CHOSEN: Mutex<Vec<(OpticsSpec, optics::FocusSettings)>> = Mutex::new(Vec::new());
        if let Ok(cache) = CHOSEN.lock() {
            if let Some((_, s)) = cache.iter().find(|(spec, _)| spec == self) {
                return *s;
            }
        }
        let grin = run_grin();
        let settings = optics::FocusSettings {
            rays_across: self.rays_across(grin),
            grin,
        };
        if let Ok(mut cache) = CHOSEN.lock() {
            if cache.len() >= 16 {
                cache.remove(0);
            }
            cache.push((self.clone(), settings));
        }
        settings
    }

    fn rays_across(&self, grin: optics::GrinSettings) -> usize {
        use optics::refraction::{PERIPHERAL_POWERS, POWERS, VERTEX_MM};
        let default = optics::FocusSettings::default().rays_across;
        let (Ok(worn), Ok(naked)) = (super::eyewear::worn_at(self, 0.0), self.system_at(0.0))
        else {
            return default;
        };
        let spectacles: Vec<(OpticalSystem, f64)> = [
            (POWERS.0, 0.0),
            (POWERS.1, 0.0),
            (PERIPHERAL_POWERS.0, self.max_field),
            (PERIPHERAL_POWERS.1, self.max_field),
        ]
        .into_iter()
        .filter_map(|(power, field)| {
            let lens = optics::lens::Lens::spectacle(power, VERTEX_MM);
            optics::lens::wear(&naked, &[lens]).ok().map(|s| (s, field))
        })
        .collect();
        let mut probes = Vec::new();
        for &wavelength_nm in &self.wavelengths[..2.min(self.wavelengths.len())] {
            for field_deg in [0.0, self.max_field] {
                probes.push(optics::Probe {
                    system: &worn,
                    pupil: self.pupil_stop(&worn),
                    wavelength_nm,
                    field_deg,
                });
            }
        }
        for (system, field_deg) in &spectacles {
            probes.push(optics::Probe {
                system,
                pupil: self.pupil_stop(&naked),
                wavelength_nm: self.refraction_wavelength,
                field_deg: *field_deg,
            });
        }
        optics::rays_for(&probes, self.criterion(), grin, RAYS_TOLERANCE_MM)
    }

    /// The surfaces of the eye at growth time `t`, their blue and red splines about `z_c`
    /// and its images: one for a lens of one smooth profile (the surfaces themselves), one
    /// per power for a zoned or lenslet lens, whose blue and red are then the image that
    /// carries the most light on the axis (docs/optics.md, "Simultaneous images").
    fn compute_at(&self, t: f64, z_c: f64) -> Result<Traced, OpticsKeyError> {
        if let Some((i, powers)) = self.multifocal()? {
            return super::images::trace_images(self, t, z_c, i, &powers);
        }
        let (surfaces, blue, red) = self.compute_single(t, z_c)?;
        let image = ComputedImage {
            blue: blue.clone(),
            red: red.clone(),
            share: ShareCurve::constant(1.0),
            power: None,
            surfaces: surfaces.clone(),
        };
        Ok((surfaces, blue, red, vec![image]))
    }

    /// The lens that forms several images and their powers (`None` when every lens forms
    /// one). One such lens at a time, and not with optics that change with age (their
    /// blend is of one surface per wavelength).
    fn multifocal(&self) -> Result<Option<(usize, Vec<f64>)>, OpticsKeyError> {
        let several: Vec<(usize, Vec<f64>)> = (self.lenses.iter().enumerate())
            .map(|(i, l)| (i, l.image_powers()))
            .filter(|(_, p)| p.len() > 1)
            .collect();
        let Some((i, powers)) = several.first().cloned() else {
            return Ok(None);
        };
        let key = format!("{}[{i}]", Quantity::Lenses);
        let value = self.lenses[i].describe();
        if let Some((j, _)) = several.get(1) {
            return Err(OpticsKeyError {
                key: format!("{}[{j}]", Quantity::Lenses),
                value: self.lenses[*j].describe(),
                problem: format!("forms several images, and so does {key}: one lens at a time may"),
            });
        }
        if !self.times().is_empty() {
            return Err(OpticsKeyError {
                key,
                value,
                problem: format!(
                    "forms {} images, but the eye changes with age (a surface table over t): \
                     such optics are traced as one image; give the eye fixed numbers or the lens one power",
                    powers.len()
                ),
            });
        }
        Ok(Some((i, powers)))
    }

    /// The surfaces of the eye at growth time `t` as one wavefront through each field's
    /// pupil, and their blue and red splines about `z_c`.
    pub(crate) fn compute_single(
        &self,
        t: f64,
        z_c: f64,
    ) -> Result<(Surfaces, PolarSpline, PolarSpline), OpticsKeyError> {
        let at_time = |mut e: OpticsKeyError| {
            if !self.times().is_empty() {
                e.problem = format!(
                    "{} (the eye at {})",
                    e.problem,
                    self.table_clock.eye_time(t)
                );
            }
            e
        };
        let system = super::eyewear::worn_at(self, t).map_err(at_time)?;
        let settings = optics::SurfaceSettings {
            max_field_deg: self.max_field,
            // One field a degree (41 for the paper's 40°).
            fields: (self.max_field.ceil() as usize + 1).max(4),
            focus: self.focus_settings(),
        };
        let surfaces = Surfaces::compute(
            &system,
            &self.wavelengths,
            &self.pupil_stop(&system),
            self.criterion(),
            &settings,
        )
        .map_err(|e| at_time(self.explain_worn(&e)))?;
        let spline = |i: usize| {
            surfaces.surfaces[i]
                .interpolant(z_c)
                .map_err(|e| at_time(self.explain(&e)))
        };
        // One wavelength (`eyeshell optics`; growth refuses it) has no red surface: its slot
        // holds the one surface.
        let blue = spline(0)?;
        let red = match surfaces.surfaces.len() {
            1 => blue.clone(),
            _ => spline(1)?,
        };
        Ok((surfaces, blue, red))
    }

    /// An error of the eye with its lenses on: the lenses' when the naked eye focuses on the
    /// axis (a lens that forms no image), else as [`OpticsSpec::explain`] says.
    pub fn explain_worn(&self, e: &OpticsError) -> OpticsKeyError {
        if let (false, Ok(eye)) = (self.lenses.is_empty(), self.system()) {
            let naked = optics::best_focus(
                &eye,
                self.wavelengths[0],
                0.0,
                &self.pupil_stop(&eye),
                self.criterion(),
            );
            if naked.is_ok() {
                return OpticsKeyError {
                    key: Quantity::Lenses.to_string(),
                    value: super::eyewear::lenses_text(&self.lenses),
                    problem: format!(
                        "form no image in the {} eye: {}",
                        self.eye_name(),
                        crate::text::one_line(&e.to_string())
                    ),
                };
            }
        }
        self.explain(e)
    }

    /// An optics error as a problem with the key that causes it: a ray failing on the axis
    /// (or any error of the pupil) is the pupil's; failing off the axis, the largest field's;
    /// a surface that cannot be interpolated, the criterion's. A ray that fails only because
    /// of a surface key (the built-in eye traces without the scene's changes to it) is that
    /// key's ([`OpticsSpec::surface_to_blame`]).
    pub fn explain(&self, e: &OpticsError) -> OpticsKeyError {
        let text = crate::text::one_line(&e.to_string());
        let (key, value): (String, String) = match e {
            OpticsError::Ray {
                field_deg,
                wavelength_nm,
                ..
            }
            | OpticsError::NoFocus {
                field_deg,
                wavelength_nm,
                ..
            } => match self.surface_to_blame(*field_deg, *wavelength_nm) {
                Some(blame) => blame,
                None if *field_deg > 0.0 => {
                    (Quantity::MaxField.to_string(), number(self.max_field))
                }
                None => (Quantity::Pupil.to_string(), number(self.pupil)),
            },
            OpticsError::InvalidInput { what, .. } if what.contains("wavelength") => {
                (Quantity::Wavelengths.to_string(), self.wavelengths_text())
            }
            // A surface's own number (the tables' ranges are checked first, so this is a
            // combination of them: an ellipsoid that ends before the next surface, ...).
            OpticsError::InvalidSystem { what, .. } if what.starts_with("surface '") => (
                Quantity::Surfaces.to_string(),
                format!("({} surface tables)", self.surfaces.len()),
            ),
            OpticsError::InvalidSystem { .. } => {
                (Quantity::Wavelengths.to_string(), self.wavelengths_text())
            }
            OpticsError::InvalidInput { what, .. } if what.contains("field") => {
                (Quantity::MaxField.to_string(), number(self.max_field))
            }
            OpticsError::InvalidInput { .. } => (Quantity::Pupil.to_string(), number(self.pupil)),
            OpticsError::Fit(_) => (
                Quantity::Focus.to_string(),
                format!("\"{}\"", FOCUS_NAMES[self.focus]),
            ),
            OpticsError::Eyewear { lens, .. } => (
                format!("{}[{lens}]", Quantity::Lenses),
                self.lenses
                    .get(*lens)
                    .map_or_else(|| "(none)".into(), super::eyewear::LensSpec::describe),
            ),
            // A kind of failure the optics crate adds later: the eye as a whole.
            _ => (
                Quantity::Optics.to_string(),
                format!("\"{}\"", self.eye_name()),
            ),
        };
        OpticsKeyError {
            key,
            value,
            problem: format!("cannot be traced in the {} eye: {text}", self.eye_name()),
        }
    }

    /// The surface key a ray's failure at `field_deg` and `wavelength_nm` is due to, with its
    /// value: `None` unless the built-in eye without the scene's surface keys traces there
    /// (then the pupil and the field are not to blame). The key is the first whose removal
    /// alone lets the eye trace, else the first table over time (the eye fails at a later
    /// time), else `optics.surfaces` as a whole.
    fn surface_to_blame(&self, field_deg: f64, wavelength_nm: f64) -> Option<(String, String)> {
        if self.surfaces.is_empty() || self.base().is_none() {
            return None;
        }
        let traces = |spec: &OpticsSpec| {
            spec.system().is_ok_and(|eye| {
                optics::best_focus(
                    &eye,
                    wavelength_nm,
                    field_deg,
                    &spec.pupil_stop(&eye),
                    spec.criterion(),
                )
                .is_ok()
            })
        };
        let bare = OpticsSpec {
            surfaces: vec![],
            ..self.clone()
        };
        if !traces(&bare) {
            return None;
        }
        let given: Vec<(usize, &'static str)> = (self.surfaces.iter().enumerate())
            .flat_map(|(i, s)| s.given().into_iter().map(move |name| (i, name)))
            .collect();
        let shown = |i: usize, name: &str| {
            (
                eye::surface_key(i, name),
                self.surfaces[i]
                    .shown(name, self.table_clock)
                    .unwrap_or_default(),
            )
        };
        if traces(self) {
            // The eye traces at growth time 0: a table makes it fail later.
            return given
                .iter()
                .find(|(i, name)| self.surfaces[*i].is_table(name))
                .map(|&(i, name)| shown(i, name));
        }
        for &(i, name) in &given {
            let mut without = self.clone();
            without.surfaces[i].clear(name);
            if traces(&without) {
                return Some(shown(i, name));
            }
        }
        Some((
            Quantity::Surfaces.to_string(),
            format!("({} surface tables)", self.surfaces.len()),
        ))
    }
}

/// The surfaces of one [`OpticsSpec`], traced: the blue and red splines the stimulus reads,
/// and every surface as computed.
#[derive(Clone, Debug)]
pub struct ComputedOptics {
    pub spec: OpticsSpec,
    /// The splines' polar centre.
    pub z_c: f64,
    pub blue: PolarSpline,
    /// The second wavelength's spline; with one wavelength (growth refuses it) the first's.
    pub red: PolarSpline,
    pub surfaces: Surfaces,
    /// The images on the retina (docs/optics.md, "Simultaneous images"): one for no lens or
    /// a lens of one smooth profile (then its splines are `blue` and `red`), else one per
    /// power of the lens, in the lens's order from its axis outwards; their shares sum to 1
    /// at every φ. `blue`, `red` and `surfaces` are the image that carries the most light on
    /// the axis.
    pub images: Vec<ComputedImage>,
    /// With tables over time: the splines at every traced time, blended between them.
    pub timed: Option<TimedSurfaces>,
    pub wall_seconds: f64,
}

/// An eye's traced surfaces, their blue and red splines and its images.
pub(crate) type Traced = (Surfaces, PolarSpline, PolarSpline, Vec<ComputedImage>);

/// A surface's key error as the optics keys' error.
fn surface_error(e: SurfaceKeyError) -> OpticsKeyError {
    OpticsKeyError {
        key: e.key,
        value: e.value,
        problem: e.problem,
    }
}

/// The blue and red splines of an eye that changes with growth time, traced at `times`.
#[derive(Clone, Debug)]
pub struct TimedSurfaces {
    pub times: Vec<f64>,
    pub blue: Vec<PolarSpline>,
    pub red: Vec<PolarSpline>,
}

/// The points a blended spline is resampled at (one per degree of the default 40°).
const BLEND_POINTS: usize = 41;

/// Why the best-focus surfaces at a growth time cannot be blended from the traced ones.
#[derive(Clone, Debug, thiserror::Error)]
#[error("the best-focus surface at t = {} cannot be blended from the traced ones: {source}", number(*.t))]
#[non_exhaustive]
pub struct BlendError {
    /// The growth time.
    pub t: f64,
    /// Why the blended points make no surface.
    pub source: OpticsError,
}

impl TimedSurfaces {
    /// The blue and red surfaces at growth time `t`: at each angle the natural cubic spline
    /// in t through the traced surfaces' radii (the weights of [`eye::spline_weights`]),
    /// φ_max likewise, resampled on [`BLEND_POINTS`] angles to φ_max(t). Each traced
    /// surface continues beyond its own φ_max along its end slope, as the stimulus reads it.
    /// The result is C² in t (the weights are, and so are the angles), so an integrator
    /// meets no kink at a table's time.
    ///
    /// # Errors
    /// [`BlendError`] if the blended radii make no spline (they do not increase in angle).
    pub fn at(&self, t: f64) -> Result<(PolarSpline, PolarSpline), BlendError> {
        let w = eye::spline_weights(&self.times, t);
        let blend = |splines: &[PolarSpline]| -> Result<PolarSpline, BlendError> {
            let top: f64 = w.iter().zip(splines).map(|(w, s)| w * s.phi_max()).sum();
            let z_c = splines[0].z_c;
            let phi: Vec<f64> = (0..BLEND_POINTS)
                .map(|j| top * j as f64 / (BLEND_POINTS - 1) as f64)
                .collect();
            let radius: Vec<f64> = phi
                .iter()
                .map(|&p| {
                    w.iter()
                        .zip(splines)
                        .map(|(w, s)| w * continued_radius(s, p))
                        .sum()
                })
                .collect();
            PolarSpline::from_points(z_c, phi, radius).map_err(|source| BlendError { t, source })
        };
        Ok((blend(&self.blue)?, blend(&self.red)?))
    }
}

/// The radius of `s` at φ, continued beyond its φ_max along its end slope: the radius the
/// stimulus reads (`Focal::radius_and_slope`), without the slope where it is not needed
/// (the blend evaluates it at every angle of every traced time, once per time step).
fn continued_radius(s: &PolarSpline, phi: f64) -> f64 {
    s.radius(phi).unwrap_or_else(|| {
        let top = s.phi_max();
        let (r, d) = (
            s.radius(top).unwrap_or(f64::NAN),
            s.slope(top).unwrap_or(f64::NAN),
        );
        r + d * (phi - top)
    })
}

/// Two computations of the same spec about the same centre are the same surfaces (the
/// computation is deterministic); only its time differs.
impl PartialEq for ComputedOptics {
    fn eq(&self, other: &Self) -> bool {
        self.spec == other.spec && self.z_c == other.z_c
    }
}

impl ComputedOptics {
    /// The optics of the image that carries the most light on the axis (whose surfaces are
    /// `blue`, `red` and `surfaces`): the spec itself, or with its multifocal lens at that
    /// image's power everywhere (what the ray fans and paraxial figures of `eyeshell optics`
    /// are traced through).
    pub fn main_spec(&self) -> OpticsSpec {
        let mut spec = self.spec.clone();
        let main = self.images.get(self.main_image());
        if let (Some(power), Some(i)) = (
            main.and_then(|im| im.power),
            (spec.lenses.iter()).position(|l| l.image_powers().len() > 1),
        ) {
            spec.lenses[i] = spec.lenses[i].with_power(power);
        }
        spec
    }

    /// The index in `images` of the image whose surfaces are `blue`, `red` and `surfaces`
    /// (the one that carries the most light on the axis; 0 with one image).
    pub fn main_image(&self) -> usize {
        (self.images.iter())
            .position(|im| im.blue == self.blue)
            .unwrap_or(0)
    }

    /// The share of the light the image of power `image` carries at `field` (degrees), as
    /// the surfaces traced at the first wavelength give it: 1 for the one image of a lens of
    /// one smooth profile, or no lens; NaN for a power that is none of the images or a
    /// field the surfaces were not traced at.
    pub fn image_share(&self, image: Option<f64>, field: f64) -> f64 {
        let Some(power) = image else {
            return 1.0;
        };
        let Some(im) = self.images.iter().find(|im| im.power == Some(power)) else {
            return f64::NAN;
        };
        (im.surfaces.surfaces.first())
            .and_then(|s| s.points.iter().position(|p| p.field_deg == field))
            .map_or(f64::NAN, |j| im.share.traced(j))
    }

    /// True when these are the surfaces of `spec` about `z_c`.
    pub fn is_for(&self, spec: &OpticsSpec, z_c: f64) -> bool {
        self.spec == *spec && self.z_c == z_c
    }
}

/// The computed surfaces shared by the copies of a scene's growth parameters.
pub type Shared = Arc<ComputedOptics>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::eye::EyeValue;

    /// The Atchison eye whose cornea flattens over t (three table times), a small quick trace.
    fn flattening() -> OpticsSpec {
        let mut spec = OpticsSpec {
            max_field: 10.0,
            pupil: 1.0,
            ..OpticsSpec::default()
        };
        spec.surfaces = vec![crate::model::eye::SurfaceSpec {
            radius: Some(EyeValue::Table {
                t: vec![0.0, 0.4, 1.0],
                value: vec![7.47, 7.70, 7.77],
            }),
            ..Default::default()
        }];
        spec
    }

    /// The system at time t reads every table at t; the surfaces are traced at each table
    /// time and the blend between them passes through each (to the resampling's accuracy) and
    /// is C¹ in t at a table time: no kink for the integrator.
    #[test]
    fn optics_with_age_are_traced_at_the_tables_times_and_blended_smoothly() {
        let spec = flattening();
        assert_eq!(spec.times(), vec![0.0, 0.4, 1.0]);
        let at = |t: f64| spec.system_at(t).unwrap().elements[0].surface.radius;
        assert_eq!((at(0.0), at(0.4), at(1.0)), (7.47, 7.70, 7.77));
        assert!(at(0.7) > 7.70 && at(0.7) < 7.77, "{}", at(0.7));
        let c = spec.compute(-0.5).unwrap();
        let timed = c.timed.as_ref().expect("a table over time");
        assert_eq!(timed.times, vec![0.0, 0.4, 1.0]);
        // A flatter cornea has less power: the blue focus moves back as t grows.
        let axial = |s: &PolarSpline| s.radius(0.0).unwrap();
        assert!(axial(&timed.blue[0]) + 0.3 < axial(&timed.blue[2]));
        for (k, &t) in timed.times.iter().enumerate() {
            let (blue, red) = timed.at(t).unwrap();
            for phi in [0.0, 0.05, 0.09] {
                let traced = timed.blue[k].radius(phi).unwrap();
                assert!(
                    (blue.radius(phi).unwrap() - traced).abs() < 1e-5,
                    "t {t}, φ {phi}"
                );
            }
            assert!((red.phi_max() - timed.red[k].phi_max()).abs() < 1e-12);
        }
        // One-sided slopes in t at the inner table time agree (the surface moving back).
        let r = |t: f64| timed.at(t).unwrap().0.radius(0.08).unwrap();
        let h = 1e-5;
        let (left, right) = ((r(0.4) - r(0.4 - h)) / h, (r(0.4 + h) - r(0.4)) / h);
        assert!(
            left > 0.0 && (left - right).abs() < 1e-3 * left.abs(),
            "{left} {right}"
        );
    }

    /// A table that ends before the run does: the eye is traced at the run's end too, so
    /// the blend there is the eye traced there (not the traced surfaces carried along their
    /// slope in t far beyond the last table time).
    #[test]
    fn a_table_ending_before_the_run_is_traced_at_the_runs_end() {
        let mut spec = flattening();
        spec.surfaces[0].radius = Some(EyeValue::Table {
            t: vec![0.0, 0.08],
            value: vec![7.47, 7.60],
        });
        assert_eq!(spec.times_until(1.0), vec![0.0, 0.08, 1.0]);
        assert_eq!(spec.times_until(0.05), vec![0.0, 0.08]);
        let c = spec.compute_over(-0.5, 1.0).unwrap();
        let timed = c.timed.as_ref().expect("a table over time");
        let (blue, _) = timed.at(1.0).unwrap();
        let alone = spec.compute_eye_at(1.0, -0.5).unwrap();
        for phi in [0.0, 0.05, 0.09] {
            let (b, a) = (blue.radius(phi).unwrap(), alone.blue.radius(phi).unwrap());
            assert!((b - a).abs() < 1e-5, "φ {phi}: blend {b}, traced {a}");
        }
    }

    /// A table's error names the key and the growth time of the eye that fails.
    #[test]
    fn an_eye_that_fails_at_a_later_time_names_the_time() {
        let mut spec = flattening();
        spec.surfaces[0].radius = Some(EyeValue::Table {
            t: vec![0.0, 1.0],
            value: vec![7.77, 0.6],
        });
        spec.pupil = 8.0;
        let e = spec.compute(-0.5).unwrap_err();
        assert!(e.problem.contains("(the eye at growth time t = 1)"), "{e}");
    }
}
