//! What each retinal point sees (docs/MODEL.md §6): the stimulus surfaces' depths behind it,
//! its polar angle and, for the rules that read them, the red surface and the defocus in
//! dioptres, each with its gradient in the retina's (z, r). The one place the integrators
//! turn a retina into a rule's [`Seen`]; a scene pays only for what its rule reads.

use crate::model::optics::ComputedImage;
use crate::model::rule::{Drive, GrowthRule, Reads, RuleError, Seen, Vergence};
use crate::model::stimulus::Focal;

/// The surfaces and the dioptre conversion a growth run's rule reads.
#[derive(Clone, Copy, Debug)]
pub struct Viewer<'a> {
    pub blue: Focal<'a>,
    pub red: Focal<'a>,
    pub vergence: Option<&'a Vergence>,
    pub reads: Reads,
    /// A lens's simultaneous images (docs/optics.md, "Simultaneous images"), when it forms
    /// more than one: each point's drive is then the light-weighted mean of the drives of
    /// its view through each image. Empty for one image (`blue` and `red` are it).
    pub images: &'a [ComputedImage],
    /// The index in `images` of the image whose surfaces `blue` and `red` are (unused for
    /// one image).
    pub main: usize,
}

impl Viewer<'_> {
    /// The view of every retina point (`points`: Σ and (z, r)) at time `t` and the rule's
    /// drive there (with `gradients`, each view's gradients and the drive's partials, which
    /// [`Drive::gradient`] turns into the drive's gradient in (z, r)).
    ///
    /// With several images the drive is Σ_i s_i(φ) drive_i, s_i the image's share of the
    /// light at the point's polar angle φ and drive_i the rule at the view through image i;
    /// the view returned is the brightest image's on the axis (`blue`), and the drive's
    /// gradient is carried whole in its `d_z`, `d_r` (the other partials zero).
    ///
    /// # Errors
    /// [`RuleError`] when a rule from outside eyeshell fails.
    pub fn drives(
        &self,
        rule: &dyn GrowthRule,
        points: impl ExactSizeIterator<Item = (f64, (f64, f64))> + Clone,
        t: f64,
        gradients: bool,
        seen: &mut Vec<Seen>,
        drives: &mut Vec<Drive>,
    ) -> Result<(), RuleError> {
        let n = points.len();
        seen.clear();
        drives.clear();
        drives.resize(n, Drive::default());
        if self.images.len() < 2 {
            seen.extend(
                points
                    .clone()
                    .map(|(sigma, p)| self.see(sigma, t, p, gradients)),
            );
            return rule.drive(seen, gradients, drives);
        }
        // Every (point, image) view in one call: image i's views at [i n, (i + 1) n); the
        // main image's are the views returned.
        let mut all = Vec::with_capacity(n * self.images.len());
        for im in self.images {
            let through = Viewer {
                blue: Focal::Computed(&im.blue),
                red: Focal::Computed(&im.red),
                images: &[],
                ..*self
            };
            all.extend(
                points
                    .clone()
                    .map(|(sigma, p)| through.see(sigma, t, p, gradients)),
            );
        }
        seen.extend_from_slice(&all[self.main * n..(self.main + 1) * n]);
        let mut each = vec![Drive::default(); all.len()];
        rule.drive(&all, gradients, &mut each)?;
        for (k, out) in drives.iter_mut().enumerate() {
            let phi = seen[k].angle;
            let mut d = Drive::default();
            for (i, im) in self.images.iter().enumerate() {
                let (v, e) = (&all[i * n + k], &each[i * n + k]);
                let (share, slope) = im.share.share_and_slope(phi);
                d.value += share * e.value;
                if gradients {
                    let g = e.gradient(v);
                    d.d_z += share * g[0] + e.value * slope * v.angle_grad[0];
                    d.d_r += share * g[1] + e.value * slope * v.angle_grad[1];
                }
            }
            *out = d;
        }
        Ok(())
    }

    /// The view from the retina point (z, r) of material point Σ = `sigma` at time `t`;
    /// with `gradients`, each quantity's gradient in (z, r) too.
    pub fn see(&self, sigma: f64, t: f64, (z, r): (f64, f64), gradients: bool) -> Seen {
        let mut s = Seen {
            sigma,
            t,
            z,
            r,
            depth_red: f64::NAN,
            defocus: f64::NAN,
            ..Seen::default()
        };
        if gradients {
            let g = self.blue.depth_gradient(z, r);
            (s.depth, s.angle) = (g.depth, g.angle);
            s.depth_grad = [g.depth_z, g.depth_r];
            s.angle_grad = [g.angle_z, g.angle_r];
        } else {
            (s.depth, s.angle) = (self.blue.depth(z, r), self.blue.angle(z, r));
        }
        if self.reads.red {
            if gradients {
                let g = self.red.depth_gradient(z, r);
                s.depth_red = g.depth;
                s.depth_red_grad = [g.depth_z, g.depth_r];
            } else {
                s.depth_red = self.red.depth(z, r);
            }
        }
        if let (true, Some(v)) = (self.reads.defocus, self.vergence) {
            let z_c = self.blue.z_c();
            let zz = z - z_c;
            let ell = r.hypot(zz);
            let (d, d_ell, d_depth) = v.defocus(z_c, ell, s.depth);
            s.defocus = d;
            if gradients {
                let (ell_z, ell_r) = (zz / ell, r / ell);
                s.defocus_grad = [
                    d_ell * ell_z + d_depth * s.depth_grad[0],
                    d_ell * ell_r + d_depth * s.depth_grad[1],
                ];
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::stimulus::Surface;

    /// Every gradient of a view against central differences of the view itself.
    #[test]
    fn a_view_s_gradients_match_differences() {
        let eye = eyeshell_optics::eyes::builtin("atchison-2006").unwrap();
        let v = Vergence::new(&eyeshell_optics::paraxial(&eye, 400.0).unwrap());
        let (b, rd) = (Surface::blue(), Surface::default_red());
        let viewer = Viewer {
            blue: Focal::Polynomial(&b),
            red: Focal::Polynomial(&rd),
            vergence: Some(&v),
            reads: Reads {
                red: true,
                defocus: true,
            },
            images: &[],
            main: 0,
        };
        for p in [(22.8, 0.4), (19.0, 8.5), (12.0, 11.2)] {
            let s = viewer.see(1.0, 0.0, p, true);
            let h = 1e-6;
            for c in 0..2 {
                let step = |x: f64| {
                    let q = if c == 0 {
                        (p.0 + x, p.1)
                    } else {
                        (p.0, p.1 + x)
                    };
                    viewer.see(1.0, 0.0, q, false)
                };
                let (a, bb) = (step(h), step(-h));
                let fd = |f: fn(&Seen) -> f64| (f(&a) - f(&bb)) / (2.0 * h);
                for (exact, diff) in [
                    (s.depth_grad[c], fd(|s| s.depth)),
                    (s.angle_grad[c], fd(|s| s.angle)),
                    (s.depth_red_grad[c], fd(|s| s.depth_red)),
                    (s.defocus_grad[c], fd(|s| s.defocus)),
                ] {
                    assert!(
                        (exact - diff).abs() < 1e-6 * (1.0 + diff.abs()),
                        "{p:?} c {c}: {exact} vs {diff}"
                    );
                }
            }
        }
        // What a rule does not read is not computed.
        let blind = Viewer {
            reads: Reads::default(),
            ..viewer
        };
        let s = blind.see(1.0, 0.0, (22.0, 1.0), true);
        assert!(s.depth_red.is_nan() && s.defocus.is_nan());
    }
}
