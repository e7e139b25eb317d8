//! The visual stimulus (docs/MODEL.md §6): best-focus surfaces for blue and red light, the
//! growth signal g_v, and the refractive classification.
//!
//! A surface is given in polar form about the axis point (0, z_B):
//! R(φ) = P1 φ⁴ + P2 φ² + P3 (+ an offset along the polar rays), for φ < φ_max, with
//! φ = atan2(r, z − z_B) measured from the +z axis (the posterior pole has φ = 0).

use eyeshell_optics::PolarSpline;

/// A best-focus surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    pub p1: f64,
    pub p2: f64,
    pub p3: f64,
    /// z of the polar centre on the axis.
    pub z_b: f64,
    /// The largest polar angle the surface is defined for (rad).
    pub phi_max: f64,
    /// Distance the surface is pushed back along its polar rays (mm).
    pub offset: f64,
}

/// Longitudinal chromatic aberration between 400 and 600 nm of the Indiana chromatic eye
/// (Thibos et al. 1992: 1.77 D), as a distance in a 60 D eye of index 1.336 (docs/MODEL.md §6).
pub const RED_OFFSET: f64 = 0.655;

impl Surface {
    /// The blue best-focus surface published with the paper's code.
    pub fn blue() -> Surface {
        Surface {
            p1: -4.464456500210127,
            p2: -8.019851138753314,
            p3: 23.6349728997666,
            z_b: -0.5064886748669879,
            phi_max: 0.5870000878571975,
            offset: 0.0,
        }
    }

    /// The default red surface: the blue one pushed back by [`RED_OFFSET`] (the paper's own
    /// red surface is not published).
    pub fn default_red() -> Surface {
        Surface {
            offset: RED_OFFSET,
            ..Surface::blue()
        }
    }

    /// Radius of the surface along the polar ray at angle φ.
    pub fn radius(&self, phi: f64) -> f64 {
        let p2 = phi * phi;
        (self.p1 * p2 + self.p2) * p2 + self.p3 + self.offset
    }

    /// The point (z, r) of the surface on the polar ray at angle φ.
    pub fn point(&self, phi: f64) -> (f64, f64) {
        let radius = self.radius(phi);
        (self.z_b + radius * phi.cos(), radius * phi.sin())
    }

    /// Polar angle of a point (z, r) about the surface's centre.
    pub fn angle(&self, z: f64, r: f64) -> f64 {
        r.atan2(z - self.z_b)
    }

    /// How far the surface lies behind the point (z, r) along its polar ray:
    /// d = R(φ) − |(z − z_B, r)|. Positive: the point is in front of the surface.
    pub fn depth(&self, z: f64, r: f64) -> f64 {
        self.radius(self.angle(z, r)) - r.hypot(z - self.z_b)
    }
}

/// The depth of a surface behind a point and the point's polar angle, with their gradients
/// in the point's (z, r): what the growth Jacobian needs of the stimulus.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthGradient {
    pub depth: f64,
    pub angle: f64,
    /// ∂d/∂z, ∂d/∂r.
    pub depth_z: f64,
    pub depth_r: f64,
    /// ∂φ/∂z, ∂φ/∂r.
    pub angle_z: f64,
    pub angle_r: f64,
}

impl Surface {
    /// R'(φ) = 4 P1 φ³ + 2 P2 φ.
    pub fn radius_slope(&self, phi: f64) -> f64 {
        (4.0 * self.p1 * phi * phi + 2.0 * self.p2) * phi
    }

    /// [`Surface::depth`] and [`Surface::angle`] at (z, r) with their exact gradients.
    pub fn depth_gradient(&self, z: f64, r: f64) -> DepthGradient {
        polar_depth_gradient(self.z_b, z, r, |phi| {
            (self.radius(phi), self.radius_slope(phi))
        })
    }
}

/// The depth d = R(φ) − ϱ of a polar surface about the axis point z_c and the angle φ at
/// (z, r), with their exact gradients: with Z = z − z_c and ϱ = |(Z, r)|, φ = atan2(r, Z)
/// has ∇φ = (−r, Z)/ϱ², ∇ϱ = (Z, r)/ϱ. `radius` gives R(φ) and R′(φ).
fn polar_depth_gradient(
    z_c: f64,
    z: f64,
    r: f64,
    radius: impl Fn(f64) -> (f64, f64),
) -> DepthGradient {
    let zz = z - z_c;
    let dist = r.hypot(zz);
    let angle = r.atan2(zz);
    let (inv, inv2) = (1.0 / dist, 1.0 / (dist * dist));
    let (angle_z, angle_r) = (-r * inv2, zz * inv2);
    let (radius, slope) = radius(angle);
    DepthGradient {
        depth: radius - dist,
        angle,
        depth_z: slope * angle_z - zz * inv,
        depth_r: slope * angle_r - r * inv,
        angle_z,
        angle_r,
    }
}

/// A best-focus surface as the stimulus reads it: the polynomial of `stimulus.blue.*` /
/// `stimulus.red.*`, or a surface computed from a schematic eye (`stimulus.source =
/// "optics"`), the optics crate's C² spline R(φ) about its centre. Both give d, φ, φ_max
/// and the exact gradients the growth Jacobian needs.
#[derive(Clone, Copy, Debug)]
pub enum Focal<'a> {
    Polynomial(&'a Surface),
    Computed(&'a PolarSpline),
}

impl Focal<'_> {
    /// The polar centre on the axis.
    pub fn z_c(&self) -> f64 {
        match self {
            Focal::Polynomial(s) => s.z_b,
            Focal::Computed(s) => s.z_c,
        }
    }

    /// The largest polar angle the surface is defined for.
    pub fn phi_max(&self) -> f64 {
        match self {
            Focal::Polynomial(s) => s.phi_max,
            Focal::Computed(s) => s.phi_max(),
        }
    }

    /// R(φ) and R′(φ). A computed surface continues beyond φ_max along its end slope (its
    /// spline's natural end makes that C²); the growth reads it there only through the
    /// crossing rule, which needs a finite depth at every point.
    pub fn radius_and_slope(&self, phi: f64) -> (f64, f64) {
        match self {
            Focal::Polynomial(s) => (s.radius(phi), s.radius_slope(phi)),
            Focal::Computed(s) => match (s.radius(phi), s.slope(phi)) {
                (Some(r), Some(d)) => (r, d),
                _ => {
                    let top = s.phi_max();
                    let (r, d) = (
                        s.radius(top).unwrap_or(f64::NAN),
                        s.slope(top).unwrap_or(f64::NAN),
                    );
                    (r + d * (phi - top), d)
                }
            },
        }
    }

    /// Polar angle of (z, r) about the centre.
    pub fn angle(&self, z: f64, r: f64) -> f64 {
        r.atan2(z - self.z_c())
    }

    /// d = R(φ) − |(z − z_c, r)|: positive when (z, r) lies in front of the surface.
    pub fn depth(&self, z: f64, r: f64) -> f64 {
        match self {
            Focal::Polynomial(s) => s.depth(z, r),
            Focal::Computed(_) => {
                self.radius_and_slope(self.angle(z, r)).0 - r.hypot(z - self.z_c())
            }
        }
    }

    /// [`Focal::depth`] and [`Focal::angle`] with their exact gradients in (z, r).
    pub fn depth_gradient(&self, z: f64, r: f64) -> DepthGradient {
        match self {
            Focal::Polynomial(s) => s.depth_gradient(z, r),
            Focal::Computed(_) => {
                polar_depth_gradient(self.z_c(), z, r, |phi| self.radius_and_slope(phi))
            }
        }
    }
}

/// The retina, the shell's inner face, beside the mid-surface point (z, r) whose normal
/// makes the angle θ with the axis, in a shell of loaded thickness h: half a thickness
/// inwards along the normal (docs/MODEL.md §6).
pub fn retina(z: f64, r: f64, h: f64, theta: f64) -> (f64, f64) {
    (z - 0.5 * h * theta.cos(), r - 0.5 * h * theta.sin())
}

/// What a run reports of an eye: its retina at the posterior pole against both best-focus
/// surfaces, and the retina's largest radius. Growth runs (every snapshot) and elastic
/// solves (a sweep's table) measure it with this one function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeMeasure {
    /// z of the retina at the posterior pole.
    pub axial_length: f64,
    /// The largest radius of the retina.
    pub equatorial_radius: f64,
    /// Distance of the pole's retina behind the blue surface (negative: in front of it).
    pub retina_minus_blue: f64,
    /// The same for the red surface.
    pub retina_minus_red: f64,
    pub class: Refraction,
    /// The pole's refraction in dioptres (NaN until a growth scene measures it:
    /// `GrowthParams::measure`).
    pub refraction_d: f64,
}

impl EyeMeasure {
    /// From the retina at the posterior pole `(z, r)` and the retina `(z, r)` at every node
    /// in order along the meridian.
    pub fn new(
        pole: (f64, f64),
        retina: impl IntoIterator<Item = (f64, f64)>,
        blue: Focal<'_>,
        red: Focal<'_>,
    ) -> EyeMeasure {
        let depth_blue = blue.depth(pole.0, pole.1);
        let depth_red = red.depth(pole.0, pole.1);
        let retina: Vec<(f64, f64)> = retina.into_iter().collect();
        EyeMeasure {
            axial_length: pole.0,
            equatorial_radius: largest_radius(&retina),
            retina_minus_blue: -depth_blue,
            retina_minus_red: -depth_red,
            class: Refraction::classify(depth_blue, depth_red),
            refraction_d: f64::NAN,
        }
    }
}

/// The largest radius of the curve through `points` (z, r), in order along it: the vertex
/// of the parabola r(z) through the largest sample and its two neighbours. The largest
/// sample alone is off by O(h²) and jumps from node to node as the equator moves through
/// the mesh; the vertex is off by O(h³) and moves smoothly, so a growth run's equatorial
/// radius converges as its axial length does (docs/MODEL.md §6). At an end of the curve,
/// or where the three samples do not bound a concave vertex, the largest sample.
pub fn largest_radius(points: &[(f64, f64)]) -> f64 {
    let Some(k) = (0..points.len()).max_by(|&a, &b| points[a].1.total_cmp(&points[b].1)) else {
        return f64::NAN;
    };
    let top = points[k].1;
    if k == 0 || k + 1 == points.len() {
        return top;
    }
    let ((z0, r0), (z1, r1), (z2, r2)) = (points[k - 1], points[k], points[k + 1]);
    // Newton's form of the parabola: p(z) = r0 + d01 (z − z0) + c (z − z0)(z − z1).
    let d01 = (r1 - r0) / (z1 - z0);
    let d12 = (r2 - r1) / (z2 - z1);
    let curvature = (d12 - d01) / (z2 - z0);
    let z = 0.5 * (z0 + z1) - d01 / (2.0 * curvature);
    let vertex = r0 + d01 * (z - z0) + curvature * (z - z0) * (z - z1);
    let inside = (z - z0) * (z - z2) <= 0.0;
    if curvature < 0.0 && inside && vertex.is_finite() && vertex >= top {
        vertex
    } else {
        top
    }
}

/// Refractive state at a retina point (docs/MODEL.md §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refraction {
    /// In front of the blue surface: the eye still grows there.
    Hyperopic,
    /// Between the blue and the red surfaces.
    Emmetropic,
    /// Behind the red surface.
    Myopic,
    /// Not classed: the rule's quantity could not be computed (`stimulus.classify =
    /// "dioptres"` with a refraction_D of NaN, beyond the ±25 D the refraction is traced
    /// over). Never replaced by another rule's answer.
    Unknown,
}

impl Refraction {
    /// From the depths of the blue and red surfaces behind the point.
    pub fn classify(depth_blue: f64, depth_red: f64) -> Refraction {
        if depth_blue > 0.0 {
            Refraction::Hyperopic
        } else if depth_red >= 0.0 {
            Refraction::Emmetropic
        } else {
            Refraction::Myopic
        }
    }

    /// The class named by [`Refraction::as_str`], if `name` is one.
    pub fn parse(name: &str) -> Option<Refraction> {
        [
            Refraction::Hyperopic,
            Refraction::Emmetropic,
            Refraction::Myopic,
            Refraction::Unknown,
        ]
        .into_iter()
        .find(|r| r.as_str() == name)
    }

    pub fn as_str(self) -> &'static str {
        match self {
            Refraction::Hyperopic => "hyperopic",
            Refraction::Emmetropic => "emmetropic",
            Refraction::Myopic => "myopic",
            Refraction::Unknown => "unknown",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_retina_is_half_a_thickness_inside_along_the_normal() {
        assert_eq!(retina(24.0, 0.0, 0.8, 0.0), (23.6, 0.0));
        let (z, r) = retina(12.0, 10.0, 0.5, std::f64::consts::FRAC_PI_2);
        assert!((z - 12.0).abs() < 1e-15 && (r - 9.75).abs() < 1e-15);
    }

    #[test]
    fn an_eye_is_measured_at_its_pole_against_both_surfaces() {
        let (blue, red) = (Surface::blue(), Surface::default_red());
        for z in [20.0, 22.5, 23.2, 25.0] {
            let eye = EyeMeasure::new(
                (z, 0.0),
                [(24.0, 3.0), (12.0, 11.5), (1.0, 9.0)],
                Focal::Polynomial(&blue),
                Focal::Polynomial(&red),
            );
            assert_eq!(eye.axial_length, z);
            // The parabola through (24, 3), (12, 11.5), (1, 9) peaks above its middle sample.
            let vertex = largest_radius(&[(24.0, 3.0), (12.0, 11.5), (1.0, 9.0)]);
            assert!(vertex > 11.5 && vertex < 12.5, "{vertex}");
            assert_eq!(eye.equatorial_radius, vertex);
            assert_eq!(eye.retina_minus_blue, -blue.depth(z, 0.0));
            assert_eq!(eye.retina_minus_red, -red.depth(z, 0.0));
            let expect = Refraction::classify(blue.depth(z, 0.0), red.depth(z, 0.0));
            assert_eq!(eye.class, expect);
        }
        // The red surface lies behind the blue one: a retina between them is emmetropic.
        let between = 0.5 * (blue.point(0.0).0 + red.point(0.0).0);
        let eye = EyeMeasure::new(
            (between, 0.0),
            [(12.0, 10.0)],
            Focal::Polynomial(&blue),
            Focal::Polynomial(&red),
        );
        assert_eq!(eye.class, Refraction::Emmetropic);
    }

    /// On a circle of radius 11 sampled every h in angle, the largest sample is off by
    /// O(h²) and the vertex by O(h⁴) (the samples are placed off-symmetric).
    #[test]
    fn the_largest_radius_is_the_vertex_through_the_samples() {
        let circle = |h: f64| -> Vec<(f64, f64)> {
            (0..=(3.0 / h) as usize)
                .map(|k| {
                    let a = 0.1 + 0.37 * h + k as f64 * h;
                    (11.0 * a.cos(), 11.0 * a.sin())
                })
                .collect()
        };
        let sample = |pts: &[(f64, f64)]| pts.iter().map(|p| p.1).fold(f64::MIN, f64::max);
        for h in [0.1, 0.05, 0.025] {
            let pts = circle(h);
            let (top, vertex) = (sample(&pts), largest_radius(&pts));
            // The sample is off by up to 11·(h/2)²/2; the vertex by O(h⁴) (the top of
            // r(z) is symmetric, so the cubic term of the parabola's error vanishes there).
            assert!(11.0 - top <= 1.4 * h * h, "h {h}: sample {top}");
            assert!(
                (vertex - 11.0).abs() <= 20.0 * h.powi(4),
                "h {h}: vertex {vertex}"
            );
        }
        // An end of the curve, and a flat top, are the largest sample.
        assert_eq!(largest_radius(&[(1.0, 1.0), (2.0, 3.0)]), 3.0);
        assert_eq!(largest_radius(&[(1.0, 2.0), (2.0, 2.0), (3.0, 2.0)]), 2.0);
        assert!(largest_radius(&[]).is_nan());
    }

    #[test]
    fn blue_surface_on_the_axis() {
        let b = Surface::blue();
        assert_eq!(b.radius(0.0), b.p3);
        // A point on the axis 1 mm in front of the surface has depth 1.
        let z = b.z_b + b.p3 - 1.0;
        assert!((b.depth(z, 0.0) - 1.0).abs() < 1e-12);
        assert_eq!(b.angle(z, 0.0), 0.0);
    }

    /// The gradients of depth and angle against central differences.
    #[test]
    fn depth_gradient_matches_differences() {
        let b = Surface::blue();
        for (z, r) in [(22.5, 0.3), (18.0, 9.5), (3.0, 11.0)] {
            let g = b.depth_gradient(z, r);
            assert_eq!((g.depth, g.angle), (b.depth(z, r), b.angle(z, r)));
            let h = 1e-6;
            let fd = |f: &dyn Fn(f64, f64) -> f64| {
                (
                    (f(z + h, r) - f(z - h, r)) / (2.0 * h),
                    (f(z, r + h) - f(z, r - h)) / (2.0 * h),
                )
            };
            let (dz, dr) = fd(&|z, r| b.depth(z, r));
            let (az, ar) = fd(&|z, r| b.angle(z, r));
            for (a, e) in [
                (g.depth_z, dz),
                (g.depth_r, dr),
                (g.angle_z, az),
                (g.angle_r, ar),
            ] {
                assert!((a - e).abs() < 1e-8, "{a} vs {e} at ({z}, {r})");
            }
        }
    }

    #[test]
    fn red_lies_behind_blue_by_the_chromatic_offset() {
        let (b, r) = (Surface::blue(), Surface::default_red());
        for phi in [0.0, 0.2, 0.5] {
            assert!((r.radius(phi) - b.radius(phi) - 0.655).abs() < 1e-12);
        }
    }

    #[test]
    fn classification_follows_the_surfaces() {
        assert_eq!(Refraction::classify(0.1, 0.7), Refraction::Hyperopic);
        assert_eq!(Refraction::classify(-0.1, 0.5), Refraction::Emmetropic);
        assert_eq!(Refraction::classify(-0.7, -0.05), Refraction::Myopic);
    }
}
