//! Blue and red in opposition (docs/MODEL.md §6, "Growth rules"): the paper's wavelength
//! hypothesis with both colours. The eye grows while its retina lies in front of the blue
//! best-focus surface, stops behind the red one, and between them grows in proportion to
//! how near the retina is to the blue surface: the sign of defocus read from longitudinal
//! chromatic aberration, as chicks do (Rucker & Wallman 2009).
//!
//! With d_b and d_r the depths of the blue and red surfaces behind the retina (d_r > d_b:
//! red focuses behind blue), q = d_r / (d_r − d_b) is 1 on the blue surface and 0 on the red
//! one; drive (mm) = G · clamp(q, 0, 1), G = `stimulus.chromatic_gain`.

use super::{Drive, GrowthRule, Reads, RuleError, Seen};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chromatic {
    pub gain: f64,
}

impl Chromatic {
    pub const NAME: &'static str = "chromatic";

    pub fn new(gain: f64) -> Chromatic {
        Chromatic { gain }
    }

    /// The drive at blue and red depths (d_b, d_r) and its partials in each.
    pub fn at(&self, d_b: f64, d_r: f64) -> (f64, f64, f64) {
        let gap = d_r - d_b;
        let q = d_r / gap;
        if !(q > 0.0) || !gap.is_finite() || gap <= 0.0 {
            // Behind the red surface (or red not behind blue: no colour signal to read).
            return (if gap > 0.0 { 0.0 } else { f64::NAN }, 0.0, 0.0);
        }
        if q >= 1.0 {
            return (self.gain, 0.0, 0.0);
        }
        // ∂q/∂d_b = d_r/gap², ∂q/∂d_r = −d_b/gap².
        let g2 = gap * gap;
        (self.gain * q, self.gain * d_r / g2, -self.gain * d_b / g2)
    }
}

impl GrowthRule for Chromatic {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reads(&self) -> Reads {
        Reads {
            red: true,
            ..Reads::default()
        }
    }

    fn drive(&self, seen: &[Seen], _partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        for (o, s) in out.iter_mut().zip(seen) {
            let (value, d_depth, d_depth_red) = self.at(s.depth, s.depth_red);
            *o = Drive {
                value,
                d_depth,
                d_depth_red,
                ..Drive::default()
            };
        }
        Ok(())
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("chromatic_gain", self.gain)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_in_front_of_blue_none_behind_red_linear_between() {
        let c = Chromatic::new(0.6);
        // 0.655 mm apart: in front of blue, on blue, midway, on red, behind red.
        assert_eq!(c.at(0.3, 0.955).0, 0.6);
        assert_eq!(c.at(0.0, 0.655).0, 0.6);
        assert!((c.at(-0.3275, 0.3275).0 - 0.3).abs() < 1e-15);
        assert_eq!(c.at(-0.655, 0.0).0, 0.0);
        assert_eq!(c.at(-0.9, -0.245).0, 0.0);
        assert!(c.at(0.2, 0.1).0.is_nan());
    }
}
