//! Growth driven by the sign and size of defocus in dioptres (docs/MODEL.md §6, "Growth
//! rules"): eyes compensate for imposed defocus of either sign, and myopic defocus is a
//! strong stop signal (Wallman & Winawer 2004; Schaeffel, Glasser & Howland 1988), while a
//! baseline drive (near work, little time outdoors: Flitcroft 2012) keeps an eye growing
//! when its image is in focus.
//!
//! drive (mm) = b + k_h · D⁺ − k_m · D⁻, with D the defocus at the point (dioptres, positive
//! when the image lies behind the retina), b = `stimulus.baseline` (mm), k_h =
//! `stimulus.hyperopic_gain` and k_m = `stimulus.myopic_gain` (mm per dioptre); g_v is its
//! positive part, as for every rule.

use super::{split, Drive, GrowthRule, Reads, RuleError, Seen};

/// The defocus rule's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Defocus {
    pub baseline: f64,
    pub hyperopic_gain: f64,
    pub myopic_gain: f64,
}

impl Defocus {
    pub const NAME: &'static str = "defocus";

    pub fn new(baseline: f64, hyperopic_gain: f64, myopic_gain: f64) -> Defocus {
        Defocus {
            baseline,
            hyperopic_gain,
            myopic_gain,
        }
    }

    /// The drive at defocus `d` (D) and its slope.
    pub fn at(&self, d: f64) -> (f64, f64) {
        let ((plus, plus_slope), (minus, minus_slope)) = split(d);
        (
            self.baseline + self.hyperopic_gain * plus - self.myopic_gain * minus,
            self.hyperopic_gain * plus_slope - self.myopic_gain * minus_slope,
        )
    }
}

impl GrowthRule for Defocus {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reads(&self) -> Reads {
        Reads {
            defocus: true,
            ..Reads::default()
        }
    }

    fn drive(&self, seen: &[Seen], _partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        for (o, s) in out.iter_mut().zip(seen) {
            let (value, slope) = self.at(s.defocus);
            *o = Drive {
                value,
                d_defocus: slope,
                ..Drive::default()
            };
        }
        Ok(())
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("baseline", self.baseline),
            ("hyperopic_gain", self.hyperopic_gain),
            ("myopic_gain", self.myopic_gain),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn myopic_defocus_slows_and_stops_growth() {
        let r = Defocus::new(0.2, 0.1, 0.4);
        // At zero defocus, the slope of the myopic side's branch.
        assert_eq!(r.at(0.0), (0.2, 0.4));
        assert!((r.at(2.0).0 - 0.4).abs() < 1e-15);
        assert!((r.at(-0.5).0 - 0.0).abs() < 1e-15);
        assert!(r.at(-1.0).0 < 0.0);
    }
}
