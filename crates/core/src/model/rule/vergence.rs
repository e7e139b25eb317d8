//! Defocus in dioptres (docs/MODEL.md §6, "Growth rules"): a distance between the retina and
//! an image, along the stimulus's polar ray, as a vergence at the corneal vertex.
//!
//! The eye's paraxial system matrix at the stimulus wavelength maps a position z behind the
//! cornea to the object vergence V(z) whose image lies there (the ocular refraction of a
//! retina at z: eyeshell_optics's `Paraxial::ocular_refraction`). A retina at distance ℓ from
//! the polar centre z_c, with the image at depth d behind it along the same ray, has defocus
//! D = V(z_c + ℓ) − V(z_c + ℓ + d): positive when the image lies behind the retina. On the
//! axis this is the paraxial defocus exactly; off it, the axial conversion is applied to the
//! distances along the polar ray (the growth reads depths there too).

use eyeshell_optics::Paraxial;

/// V(z) = 1000 (A + t C) / (B + t D), t = (z − z_last) / n: a Möbius map of z, so its slope is
/// exact in closed form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vergence {
    matrix: [[f64; 2]; 2],
    /// The last surface's vertex (mm) and the image space's index.
    z_last: f64,
    n_image: f64,
}

impl Vergence {
    /// From an eye's paraxial properties at the stimulus wavelength.
    pub fn new(p: &Paraxial) -> Vergence {
        Vergence {
            matrix: p.matrix,
            z_last: p.focus - p.back_focal_distance,
            n_image: p.n_image,
        }
    }

    /// V(z) (D) and dV/dz (D/mm).
    pub fn at(&self, z: f64) -> (f64, f64) {
        let [[a, b], [c, d]] = self.matrix;
        let t = (z - self.z_last) / self.n_image;
        let den = b + t * d;
        (
            1000.0 * (a + t * c) / den,
            1000.0 / self.n_image * (c * b - d * a) / (den * den),
        )
    }

    /// The defocus (D) of an image at depth `depth` behind a retina at distance `ell` from the
    /// polar centre `z_c`, with its partials in ℓ and in the depth.
    pub fn defocus(&self, z_c: f64, ell: f64, depth: f64) -> (f64, f64, f64) {
        let (v_ret, s_ret) = self.at(z_c + ell);
        let (v_img, s_img) = self.at(z_c + ell + depth);
        (v_ret - v_img, s_ret - s_img, -s_img)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn atchison() -> Vergence {
        let eye = eyeshell_optics::eyes::builtin("atchison-2006").expect("a built-in eye");
        Vergence::new(&eyeshell_optics::paraxial(&eye, 400.0).unwrap())
    }

    /// V is the paraxial ocular refraction, zero at the paraxial focus, and its slope is the
    /// difference quotient's.
    #[test]
    fn the_vergence_is_the_ocular_refraction_and_its_slope_exact() {
        let eye = eyeshell_optics::eyes::builtin("atchison-2006").unwrap();
        let p = eyeshell_optics::paraxial(&eye, 400.0).unwrap();
        let v = Vergence::new(&p);
        for z in [21.0, 23.5, 26.0] {
            assert!((v.at(z).0 - p.ocular_refraction(z)).abs() < 1e-12);
            let h = 1e-5;
            let fd = (v.at(z + h).0 - v.at(z - h).0) / (2.0 * h);
            assert!(
                (fd - v.at(z).1).abs() < 1e-6 * fd.abs(),
                "{fd} {:?}",
                v.at(z)
            );
        }
        assert!(v.at(p.focus).0.abs() < 1e-9);
        // About 2.7 D per mm of axial length near 23.5 mm (a reduced eye of 60 D in 1.336
        // gives n/f'² = 2.7 D/mm); longer eyes are more myopic.
        let slope = v.at(23.5).1;
        assert!((-3.1..-2.3).contains(&slope), "{slope}");
    }

    #[test]
    fn an_image_behind_the_retina_is_hyperopic_defocus() {
        let v = atchison();
        let (d, d_ell, d_depth) = v.defocus(-0.5, 23.0, 0.4);
        assert!(d > 0.9 && d < 1.3, "{d}");
        let h = 1e-6;
        let fd_ell =
            (v.defocus(-0.5, 23.0 + h, 0.4).0 - v.defocus(-0.5, 23.0 - h, 0.4).0) / (2.0 * h);
        let fd_dep =
            (v.defocus(-0.5, 23.0, 0.4 + h).0 - v.defocus(-0.5, 23.0, 0.4 - h).0) / (2.0 * h);
        assert!((fd_ell - d_ell).abs() < 1e-6 && (fd_dep - d_depth).abs() < 1e-6);
        assert_eq!(v.defocus(-0.5, 23.0, 0.0).0, 0.0);
        assert!(v.defocus(-0.5, 23.0, -0.4).0 < 0.0);
    }
}
