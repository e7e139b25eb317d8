//! Best-focus surfaces in the shell's frame, their interpolant and the polar fit.

use eyeshell_optics::eyes;
use eyeshell_optics::{
    best_focus_with, Criterion, FocusSettings, PolarFit, Pupil, SurfaceSettings, Surfaces,
};

fn atchison_surfaces(criterion: Criterion, diameter: f64) -> Surfaces {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter,
        position: eye.pupil_position.unwrap(),
    };
    Surfaces::compute(
        &eye,
        &[400.0, 600.0],
        &pupil,
        criterion,
        &SurfaceSettings::default(),
    )
    .unwrap()
}

#[test]
fn the_atchison_surfaces_are_ordered_smooth_and_fitted() {
    let s = atchison_surfaces(Criterion::MeanSphere, 3.0);
    assert_eq!(s.surfaces.len(), 2);
    let (blue, red) = (s.get(400.0).unwrap(), s.get(600.0).unwrap());
    assert_eq!(blue.points.len(), 41);
    assert_eq!(blue.points[40].field_deg, 40.0);
    // Blue focuses in front of red at every angle, by a fraction of a millimetre.
    for (b, r) in blue.points.iter().zip(&red.points) {
        let gap = (r.z - b.z).hypot(r.r - b.r);
        assert!(
            r.z > b.z && gap > 0.2 && gap < 1.5,
            "{}°: blue ({}, {}) red ({}, {})",
            b.field_deg,
            b.z,
            b.r,
            r.z,
            r.r
        );
    }
    // The polar fit reproduces each surface to a few micrometres.
    for surface in &s.surfaces {
        let fit = surface.polar_fit().unwrap();
        assert!(
            fit.rms_residual < 0.01,
            "{}: {fit:?}",
            surface.wavelength_nm
        );
        let spline = surface.interpolant(fit.z_b).unwrap();
        // The spline passes through its knots and stays near the fit between them.
        for (phi, r) in spline.knots() {
            assert!((spline.radius(phi).unwrap() - r).abs() < 1e-12);
        }
        let n = 200;
        for i in 0..=n {
            let phi = spline.phi_max() * i as f64 / n as f64;
            let r = spline.radius(phi).unwrap();
            assert!(
                (r - fit.radius(phi)).abs() < 0.05,
                "{phi}: {r} vs {}",
                fit.radius(phi)
            );
        }
        assert!(spline.radius(spline.phi_max() * 1.01).is_none());
        // depth: zero on the surface, positive in front of it.
        let p = &surface.points[20];
        assert!(spline.depth(p.z, p.r).unwrap().abs() < 1e-9);
        assert!(spline.depth(p.z - 0.3, p.r).unwrap() > 0.0);
    }
    // The blue surface's axis point is near the published one's (23.13 mm).
    let axial = blue.points[0].z;
    assert!(
        (axial - (PolarFit::PAPER_BLUE.p3 + PolarFit::PAPER_BLUE.z_b)).abs() < 1.0,
        "{axial}"
    );
}

#[test]
fn the_surfaces_do_not_depend_on_the_thread_schedule() {
    let a = atchison_surfaces(Criterion::Strehl, 3.0);
    let b = atchison_surfaces(Criterion::Strehl, 3.0);
    assert_eq!(a, b);
}

#[test]
fn with_a_small_pupil_the_strehl_surface_is_smooth_and_near_the_mean_sphere_one() {
    let strehl = atchison_surfaces(Criterion::Strehl, 0.5);
    let mean = atchison_surfaces(Criterion::MeanSphere, 0.5);
    for (s, m) in strehl.surfaces.iter().zip(&mean.surfaces) {
        assert!(s.polar_fit().unwrap().rms_residual < 0.01);
        for (a, b) in s.points.iter().zip(&m.points) {
            // Within the depth of focus of a 0.5 mm pupil (the criteria weigh the 9 D of
            // astigmatism at 40° differently).
            assert!(
                (a.distance - b.distance).abs() < 0.25,
                "{}°: {} {}",
                a.field_deg,
                a.distance,
                b.distance
            );
            assert!(
                a.strehl >= b.strehl - 1e-9,
                "{}°: the Strehl criterion's maximum {} below {}",
                a.field_deg,
                a.strehl,
                b.strehl
            );
        }
    }
}

#[test]
fn best_focus_converges_with_rays_across_the_pupil() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 1.0,
        position: 3.7,
    };
    let at = |n: usize| {
        best_focus_with(
            &eye,
            400.0,
            20.0,
            &pupil,
            Criterion::Strehl,
            &FocusSettings {
                rays_across: n,
                ..FocusSettings::default()
            },
        )
        .unwrap()
        .distance
    };
    let (a, b, c) = (at(16), at(32), at(64));
    assert!((b - c).abs() < (a - c).abs().max(1e-6), "{a} {b} {c}");
    assert!((b - c).abs() < 1e-4, "{b} {c}");
}

#[test]
fn a_ray_fan_converges_near_the_best_focus() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 1.0,
        position: 3.7,
    };
    for field in [0.0, 30.0] {
        let focus =
            eyeshell_optics::best_focus(&eye, 555.0, field, &pupil, Criterion::MeanSphere).unwrap();
        let fan = eyeshell_optics::ray_fan(&eye, 555.0, field, &pupil, 5, focus.z).unwrap();
        assert_eq!(fan.len(), 5);
        for path in &fan {
            assert!(
                path[0].0 < 0.0 && (path.last().unwrap().0 - focus.z).abs() < 1e-9,
                "{path:?}"
            );
            assert!(path.windows(2).all(|w| w[1].0 > w[0].0));
        }
        // The middle ray is the chief ray, which passes through the best focus.
        let chief_end = fan[2].last().unwrap().1;
        assert!(
            (chief_end.abs() - focus.r).abs() < 1e-6,
            "{chief_end} {}",
            focus.r
        );
        // The fan's rays meet the focal plane within the tangential blur of a 1 mm pupil.
        let spread = fan
            .iter()
            .map(|p| p.last().unwrap().1)
            .fold(f64::NEG_INFINITY, f64::max)
            - fan
                .iter()
                .map(|p| p.last().unwrap().1)
                .fold(f64::INFINITY, f64::min);
        assert!(spread < 0.05, "{field}°: {spread}");
    }
    let e = eyeshell_optics::ray_fan(&eye, 555.0, 0.0, &pupil, 0, 30.0).unwrap_err();
    assert!(e.to_string().contains("rays of a fan"));
}

/// The spline's slope is the derivative of its radius (central differences, inside pieces,
/// at the knots, and on the even continuation below φ = 0, where it changes sign).
#[test]
fn the_spline_slope_is_the_derivative_of_its_radius() {
    let s = atchison_surfaces(Criterion::MeanSphere, 3.0);
    let spline = s.get(400.0).unwrap().interpolant(-0.5).unwrap();
    let h = 1e-6;
    let top = spline.phi_max();
    for phi in [0.0, 0.013, 0.1, 0.2345, 0.3, top * 0.97, top - 2.0 * h] {
        let slope = spline.slope(phi).unwrap();
        let fd = (spline.radius(phi + h).unwrap() - spline.radius(phi - h).unwrap()) / (2.0 * h);
        assert!((slope - fd).abs() < 1e-6, "{phi}: {slope} vs {fd}");
    }
    assert!(spline.slope(0.0).unwrap().abs() < 1e-12);
    let below = spline.slope(-0.05).unwrap();
    assert!((below + spline.slope(0.05).unwrap()).abs() < 1e-15 && below.abs() > 1e-3);
    assert!(spline.slope(top * 1.01).is_none());
}

/// The sagittal and tangential criteria put the focus at the fit's focal lines: the
/// distances along the chief ray are the foci the mean-sphere focus is the mean of.
#[test]
fn the_sagittal_and_tangential_criteria_are_the_focal_lines() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 1.0,
        position: eye.pupil_position.unwrap(),
    };
    let settings = FocusSettings::default();
    let at = |c| best_focus_with(&eye, 400.0, 30.0, &pupil, c, &settings).unwrap();
    let (mean, sag, tan) = (
        at(Criterion::MeanSphere),
        at(Criterion::Sagittal),
        at(Criterion::Tangential),
    );
    assert_eq!(sag.distance, mean.sagittal);
    assert_eq!(tan.distance, mean.tangential);
    assert!(mean.sagittal - mean.tangential > 0.5, "{mean:?}");
    assert_eq!(
        (Criterion::Sagittal.name(), Criterion::Tangential.name()),
        ("sagittal", "tangential")
    );
}
