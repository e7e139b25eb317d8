//! The stimulus's surfaces computed from a schematic eye (`stimulus.source = "optics"`,
//! docs/guide/optics.md): the scene's `optics.*` keys, the surfaces they give (traced once,
//! before a run starts), and their errors in the user's terms (the key to change).
//!
//! The first wavelength's surface is the stimulus's blue surface, the second's the red one
//! (for the classification only). Both are held as the optics crate's C² spline R(φ) about the
//! blue surface's polar centre `stimulus.blue.z_B`, so that d and φ_max keep their meaning
//! (docs/MODEL.md §6): φ_max is where the computed surface ends.

use std::sync::Arc;

use eyeshell_optics as optics;
use eyeshell_optics::{Criterion, OpticalSystem, OpticsError, PolarSpline, Pupil, Surfaces};

use crate::text::number;

/// The names `stimulus.source` takes, in the order of [`Source`]'s variants.
pub const SOURCES: [&str; 2] = ["polynomial", "optics"];

/// The names `optics.eye` takes: the optics crate's built-in eyes.
pub const EYES: [&str; 3] = optics::eyes::BUILTIN;

/// The names `optics.focus` takes, in the order of [`FOCI`].
pub const FOCUS_NAMES: [&str; 4] = ["mean-sphere", "strehl", "sagittal", "tangential"];
const FOCI: [Criterion; 4] = [
    Criterion::MeanSphere,
    Criterion::Strehl,
    Criterion::Sagittal,
    Criterion::Tangential,
];

/// The wavelengths (nm) the eyes' dispersion laws hold for.
pub const WAVELENGTH_RANGE: (f64, f64) = (300.0, 1200.0);
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
        }
    }
}

/// A problem with the `optics.*` keys: the key to change and why.
#[derive(Clone, Debug, PartialEq)]
pub struct OpticsKeyError {
    /// The key, or an item of it (`optics.lenses[1].zones[0].radius`).
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

    /// The built-in eye.
    pub fn system(&self) -> OpticalSystem {
        // EYES is the crate's own list of the names `builtin` accepts.
        optics::eyes::builtin(self.eye_name()).unwrap_or_else(optics::eyes::atchison_2006)
    }

    /// The pupil: `optics.pupil` wide, where the eye's source puts it.
    pub fn pupil_stop(&self, system: &OpticalSystem) -> Pupil {
        Pupil {
            diameter: self.pupil,
            position: system.pupil_position.unwrap_or(3.6),
        }
    }

    fn wavelengths_text(&self) -> String {
        let items: Vec<String> = self.wavelengths.iter().map(|w| number(*w)).collect();
        format!("[{}]", items.join(", "))
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
                "optics.pupil",
                number(self.pupil),
                format!("must lie in (0, {MAX_PUPIL}] mm (a pupil's diameter)"),
            ));
        }
        if self.wavelengths.len() < 2 {
            return Err(err(
                "optics.wavelengths",
                self.wavelengths_text(),
                "must list at least two wavelengths (nm): blue, then red".into(),
            ));
        }
        let (lo, hi) = WAVELENGTH_RANGE;
        if let Some(w) = self.wavelengths.iter().find(|w| !(**w >= lo && **w <= hi)) {
            return Err(err(
                "optics.wavelengths",
                self.wavelengths_text(),
                format!(
                    "must lie between {lo} and {hi} nm, where the eyes' dispersion laws hold ({} does not)",
                    number(*w)
                ),
            ));
        }
        if !(self.max_field >= 5.0 && self.max_field <= optics::MAX_FIELD_DEG) {
            return Err(err(
                "optics.max_field",
                number(self.max_field),
                format!(
                    "must lie in [5, {}] degrees (field angles in air)",
                    optics::MAX_FIELD_DEG
                ),
            ));
        }
        Ok(())
    }

    /// Trace the surfaces and make the stimulus's splines about `z_c`.
    pub fn compute(&self, z_c: f64) -> Result<ComputedOptics, OpticsKeyError> {
        self.check()?;
        let start = std::time::Instant::now();
        super::eyewear::check_coverage(self)?;
        let system = super::eyewear::worn(self)?;
        let settings = optics::SurfaceSettings {
            max_field_deg: self.max_field,
            // One field a degree (41 for the paper's 40°).
            fields: (self.max_field.ceil() as usize + 1).max(4),
            ..Default::default()
        };
        let surfaces = Surfaces::compute(
            &system,
            &self.wavelengths,
            &self.pupil_stop(&system),
            self.criterion(),
            &settings,
        )
        .map_err(|e| self.explain_worn(&e))?;
        let spline = |i: usize| {
            surfaces.surfaces[i]
                .interpolant(z_c)
                .map_err(|e| self.explain(&e))
        };
        let (blue, red) = (spline(0)?, spline(1)?);
        Ok(ComputedOptics {
            spec: self.clone(),
            z_c,
            blue,
            red,
            surfaces,
            wall_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// An error of the eye with its lenses on: the lenses' when the naked eye focuses on the
    /// axis (a lens that forms no image), else as [`OpticsSpec::explain`] says.
    pub fn explain_worn(&self, e: &OpticsError) -> OpticsKeyError {
        if !self.lenses.is_empty() {
            let eye = self.system();
            let naked = optics::best_focus(
                &eye,
                self.wavelengths[0],
                0.0,
                &self.pupil_stop(&eye),
                self.criterion(),
            );
            if naked.is_ok() {
                return OpticsKeyError {
                    key: super::eyewear::LENSES_KEY.into(),
                    value: super::eyewear::lenses_toml(&self.lenses),
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
    /// a surface that cannot be interpolated, the criterion's.
    pub fn explain(&self, e: &OpticsError) -> OpticsKeyError {
        let text = crate::text::one_line(&e.to_string());
        let (key, value) = match e {
            OpticsError::Ray { field_deg, .. } | OpticsError::NoFocus { field_deg, .. }
                if *field_deg > 0.0 =>
            {
                ("optics.max_field", number(self.max_field))
            }
            OpticsError::Ray { .. } | OpticsError::NoFocus { .. } => {
                ("optics.pupil", number(self.pupil))
            }
            OpticsError::InvalidInput { what, .. } if what.contains("wavelength") => {
                ("optics.wavelengths", self.wavelengths_text())
            }
            OpticsError::InvalidSystem { .. } => ("optics.wavelengths", self.wavelengths_text()),
            OpticsError::InvalidInput { what, .. } if what.contains("field") => {
                ("optics.max_field", number(self.max_field))
            }
            OpticsError::InvalidInput { .. } => ("optics.pupil", number(self.pupil)),
            OpticsError::Fit(_) => ("optics.focus", format!("\"{}\"", FOCUS_NAMES[self.focus])),
        };
        OpticsKeyError {
            key: key.to_string(),
            value,
            problem: format!("cannot be traced in the {} eye: {text}", self.eye_name()),
        }
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
    pub red: PolarSpline,
    pub surfaces: Surfaces,
    pub wall_seconds: f64,
}

/// Two computations of the same spec about the same centre are the same surfaces (the
/// computation is deterministic); only its time differs.
impl PartialEq for ComputedOptics {
    fn eq(&self, other: &Self) -> bool {
        self.spec == other.spec && self.z_c == other.z_c
    }
}

impl ComputedOptics {
    /// True when these are the surfaces of `spec` about `z_c`.
    pub fn is_for(&self, spec: &OpticsSpec, z_c: f64) -> bool {
        self.spec == *spec && self.z_c == z_c
    }
}

/// The computed surfaces shared by the copies of a scene's growth parameters.
pub type Shared = Arc<ComputedOptics>;
