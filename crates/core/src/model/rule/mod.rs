//! Growth rules: what the retina's view makes of growth (docs/MODEL.md §6, "Growth rules").
//!
//! η = g_c(Σ) · g_v, and a rule says what g_v is. At every retinal point a rule reads what
//! the point sees ([`Seen`]: the depth of the stimulus surface behind it, the red surface's,
//! the defocus in dioptres, its place and the time) and returns a *drive* (mm) with its
//! exact partial derivatives in those quantities ([`Drive`]). The integrators never name a
//! rule: they compose the drive's partials with the retina's own derivatives, read the drive
//! at φ_max for every point beyond it (the paper's crossing rule, now applied to whatever
//! the rule drives), and take g_v = [drive]⁺, since growth never shrinks (§5). With
//! `stimulus.region = "integrated"` the drives are averaged over the retina ([`Region`]) and
//! that one number drives every point.
//!
//! Adding a rule is one file holding one type that implements [`GrowthRule`], its row in
//! [`CATALOGUE`], and its keys in the scene's key table.

use std::fmt;
use std::sync::Arc;

mod blue_surface;
mod chromatic;
mod defocus;
pub mod vergence;

pub use blue_surface::BlueSurface;
pub use chromatic::Chromatic;
pub use defocus::Defocus;
pub use vergence::Vergence;

/// What a retinal point sees of one image: the inputs of a rule. Each quantity comes with
/// its gradient in the retina's (z, r) so that the integrators can build exact Jacobians.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Seen {
    /// Σ, the point's material coordinate (mm), and the growth time.
    pub sigma: f64,
    pub t: f64,
    /// The retina point (z, r) (mm).
    pub z: f64,
    pub r: f64,
    /// The polar angle about the stimulus surface's centre (rad).
    pub angle: f64,
    pub angle_grad: [f64; 2],
    /// The signed distance (mm) of the stimulus (first wavelength, "blue") surface behind the
    /// retina along its polar ray: positive when the retina lies in front of it.
    pub depth: f64,
    pub depth_grad: [f64; 2],
    /// The same for the second wavelength's ("red") surface (NaN unless the rule reads it).
    pub depth_red: f64,
    pub depth_red_grad: [f64; 2],
    /// The defocus of the stimulus image in dioptres: positive when the image lies behind
    /// the retina (hyperopic defocus), as a vergence at the corneal vertex ([`Vergence`]);
    /// NaN unless the rule reads it.
    pub defocus: f64,
    pub defocus_grad: [f64; 2],
}

/// A rule's drive at one point (mm) and its partial derivatives in the quantities of
/// [`Seen`] it reads (zero for the others).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Drive {
    pub value: f64,
    pub d_depth: f64,
    pub d_depth_red: f64,
    pub d_defocus: f64,
    /// Direct dependence on the retina's place (a rule of z or r itself).
    pub d_z: f64,
    pub d_r: f64,
}

impl Drive {
    /// The drive's gradient in the retina's (z, r), through what the point sees.
    pub fn gradient(&self, seen: &Seen) -> [f64; 2] {
        let g = |c: usize| {
            let mut v = self.d_depth * seen.depth_grad[c];
            if self.d_depth_red != 0.0 {
                v += self.d_depth_red * seen.depth_red_grad[c];
            }
            if self.d_defocus != 0.0 {
                v += self.d_defocus * seen.defocus_grad[c];
            }
            v
        };
        [g(0) + self.d_z, g(1) + self.d_r]
    }
}

/// Which of the optional quantities a rule reads: a scene pays only for these.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reads {
    pub red: bool,
    pub defocus: bool,
}

/// Why a rule could not give its drive (a rule written outside eyeshell: Python's raised,
/// returned NaN or the wrong shape, or took too long).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RuleError {
    /// The rule failed; `why` in the rule's own words.
    #[error("the growth rule {rule} failed: {why}")]
    Failed { rule: String, why: String },
    /// The rule returned a value that is not finite at retinal point `point` (Σ = sigma).
    #[error("the growth rule {rule} returned {value} at Σ = {} mm", crate::text::decimals6(*sigma))]
    NotFinite {
        rule: String,
        value: f64,
        sigma: f64,
    },
}

/// A hypothesis of what drives growth: g_v = [drive]⁺ at every point (docs/MODEL.md §6).
///
/// `drive` fills `out[k]` for `seen[k]`; with `partials` false only the values are read.
/// A rule is local: the drive at a point depends on that point's view alone (the Jacobians
/// assume it; `stimulus.region = "integrated"` averages local drives).
pub trait GrowthRule: Send + Sync + fmt::Debug {
    /// Its name, as `stimulus.rule` gives it.
    fn name(&self) -> &str;

    /// The optional quantities it reads.
    fn reads(&self) -> Reads;

    /// The drive at every point.
    ///
    /// # Errors
    /// [`RuleError`] when a rule from outside eyeshell fails; the built-in rules never do.
    fn drive(&self, seen: &[Seen], partials: bool, out: &mut [Drive]) -> Result<(), RuleError>;

    /// Whether, through a lens that forms several images at once, the rule reads every
    /// image, each with its share of the light (its drive the light-weighted mean), or only
    /// the image that carries the most light on the axis.
    fn reads_every_image(&self) -> bool {
        true
    }

    /// Its parameters, (name, value), as its key table names them after `stimulus.`:
    /// summaries and equality read them.
    fn parameters(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
}

/// The built-in rules, in the order `stimulus.rule` lists them.
pub const CATALOGUE: [&str; 3] = [BlueSurface::NAME, Defocus::NAME, Chromatic::NAME];

/// Where the rule's drive acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    /// Each point's own drive (the paper's).
    Local,
    /// The drive averaged over the retina's area from the pole out to the polar angle
    /// [`Stimulus::max_angle`] drives every point.
    Integrated,
}

impl Region {
    /// The names `stimulus.region` takes.
    pub const NAMES: [&'static str; 2] = ["local", "integrated"];
}

/// The default edge of the integrated region (degrees of polar angle): inside both the
/// published surface's φ_max (33.6°) and a computed surface's at a 40° field (about 26°).
pub const DEFAULT_MAX_FIELD: f64 = 25.0;

/// The defocus rule's default gains (mm per dioptre): the reciprocal of the Atchison 2006
/// eye's 2.7 D per mm of axial length near 23.5 mm at 400 nm ([`Vergence`]), so that with no
/// baseline a hyperopic eye is driven as under the paper's rule (g_v ≈ the depth in mm);
/// equal for both signs by default, a symmetric rule.
pub const DEFAULT_GAIN: f64 = 0.37;

/// The chromatic rule's default drive in front of the blue surface (mm): the default red
/// surface's distance behind the blue one, so that between the surfaces the drive is the
/// red depth, as the paper's rule is the blue one.
pub const DEFAULT_CHROMATIC_GAIN: f64 = crate::model::stimulus::RED_OFFSET;

/// The built-in rules' keys, as a scene gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RuleKeys {
    /// Index into [`CATALOGUE`].
    pub rule: usize,
    pub baseline: f64,
    pub hyperopic_gain: f64,
    pub myopic_gain: f64,
    pub chromatic_gain: f64,
}

impl Default for RuleKeys {
    fn default() -> Self {
        RuleKeys {
            rule: 0,
            baseline: 0.0,
            hyperopic_gain: DEFAULT_GAIN,
            myopic_gain: DEFAULT_GAIN,
            chromatic_gain: DEFAULT_CHROMATIC_GAIN,
        }
    }
}

impl RuleKeys {
    /// The rule these keys choose.
    pub fn build(&self) -> Arc<dyn GrowthRule> {
        match CATALOGUE.get(self.rule).copied() {
            Some(Defocus::NAME) => Arc::new(Defocus::new(
                self.baseline,
                self.hyperopic_gain,
                self.myopic_gain,
            )),
            Some(Chromatic::NAME) => Arc::new(Chromatic::new(self.chromatic_gain)),
            _ => Arc::new(BlueSurface),
        }
    }
}

/// The stimulus of a growth run: its rule and where the rule acts.
#[derive(Clone, Debug)]
pub struct Stimulus {
    rule: Arc<dyn GrowthRule>,
    /// Whether `rule` is the one `keys` choose (false: a rule given in code).
    builtin: bool,
    pub keys: RuleKeys,
    pub region: Region,
    /// The integrated region's edge: the polar angle about the stimulus surface's centre
    /// (degrees, as the scene gives it; [`Stimulus::max_angle`] in radians).
    pub max_field: f64,
}

impl Default for Stimulus {
    fn default() -> Self {
        Stimulus {
            rule: Arc::new(BlueSurface),
            builtin: true,
            keys: RuleKeys::default(),
            region: Region::Local,
            max_field: DEFAULT_MAX_FIELD,
        }
    }
}

impl PartialEq for Stimulus {
    /// Built-in rules are equal when their keys are; a rule given in code only to itself.
    fn eq(&self, other: &Self) -> bool {
        let same_rule = match (self.builtin, other.builtin) {
            (true, true) => self.keys == other.keys,
            (false, false) => Arc::ptr_eq(&self.rule, &other.rule),
            _ => false,
        };
        same_rule && self.region == other.region && self.max_field == other.max_field
    }
}

impl Stimulus {
    /// The rule in effect.
    pub fn rule(&self) -> &Arc<dyn GrowthRule> {
        &self.rule
    }

    /// Change the built-in rule's keys (and with them the rule).
    pub fn set_keys(&mut self, change: impl FnOnce(&mut RuleKeys)) {
        change(&mut self.keys);
        self.rule = self.keys.build();
        self.builtin = true;
    }

    /// Run `rule`, a rule given in code (Python's, or a Rust trait object), instead of the
    /// keys' one.
    pub fn set_rule(&mut self, rule: Arc<dyn GrowthRule>) {
        self.rule = rule;
        self.builtin = false;
    }

    /// The integrated region's edge in radians.
    pub fn max_angle(&self) -> f64 {
        self.max_field.to_radians()
    }

    /// Whether the rule in effect is a built-in one (chosen by its keys).
    pub fn is_builtin(&self) -> bool {
        self.builtin
    }

    /// Whether this is the paper's stimulus: the blue-surface rule, local.
    pub fn is_papers(&self) -> bool {
        self.builtin && self.rule.name() == BlueSurface::NAME && self.region == Region::Local
    }
}

/// [x]⁺ − [−x]⁺ split: (x⁺, x⁻) with x = x⁺ − x⁻, and the slopes of the branch taken.
#[inline]
fn split(x: f64) -> ((f64, f64), (f64, f64)) {
    if x > 0.0 {
        ((x, 1.0), (0.0, 0.0))
    } else {
        ((0.0, 0.0), (-x, -1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every built-in rule's partials against central differences of its own value, over
    /// views on both sides of its kinks.
    #[test]
    fn every_rule_s_partials_match_differences() {
        let rules: Vec<Arc<dyn GrowthRule>> = vec![
            Arc::new(BlueSurface),
            Arc::new(Defocus::new(0.3, 0.05, 0.2)),
            Arc::new(Chromatic::new(0.8)),
        ];
        assert_eq!(
            rules.iter().map(|r| r.name()).collect::<Vec<_>>(),
            CATALOGUE
        );
        let views = [(0.4, 1.0, 1.3), (-0.2, 0.5, -0.7), (-0.9, -0.3, -2.6)];
        for rule in &rules {
            for &(d, dr, dd) in &views {
                let seen = Seen {
                    depth: d,
                    depth_red: dr,
                    defocus: dd,
                    ..Seen::default()
                };
                let mut out = [Drive::default()];
                rule.drive(&[seen], true, &mut out).unwrap();
                let h = 1e-6;
                // Central differences (no view sits within h of a kink).
                let at = |f: &dyn Fn(&mut Seen, f64)| {
                    let (mut a, mut b) = (seen, seen);
                    f(&mut a, h);
                    f(&mut b, -h);
                    let mut s = [Drive::default(); 2];
                    rule.drive(&[a, b], false, &mut s).unwrap();
                    (s[0].value - s[1].value) / (2.0 * h)
                };
                let fd = [
                    at(&|s, h| s.depth += h),
                    at(&|s, h| s.depth_red += h),
                    at(&|s, h| s.defocus += h),
                ];
                let exact = [out[0].d_depth, out[0].d_depth_red, out[0].d_defocus];
                for (e, f) in exact.iter().zip(fd) {
                    assert!(
                        (e - f).abs() < 1e-8,
                        "{}: {exact:?} vs {fd:?} at {seen:?}",
                        rule.name()
                    );
                }
            }
        }
    }
}
