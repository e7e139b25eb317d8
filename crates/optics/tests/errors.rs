//! Bad input and rays that cannot be traced: a typed error naming the surface (or medium),
//! the field angle and the wavelength; never a panic, never a NaN.

mod common;

use common::{four_surface_eye, SMALL_PUPIL};
use eyeshell_optics::eyes;
use eyeshell_optics::{
    best_focus, best_focus_with, Criterion, Element, FocusSettings, Grin, GrinSettings, Medium,
    OpticalSystem, OpticsError, Pupil, RayFailure, Surface, SurfaceSettings, Surfaces,
};

fn ray_error(e: OpticsError) -> (String, f64, RayFailure) {
    match e {
        OpticsError::Ray {
            surface,
            field_deg,
            failure,
            ..
        } => (surface, field_deg, failure),
        other => panic!("expected a ray error, got {other:?}"),
    }
}

#[test]
fn a_pupil_larger_than_a_surface_names_the_surface_and_the_angle() {
    let mut eye = four_surface_eye();
    eye.elements[2].surface.semi_diameter = Some(1.0);
    let pupil = Pupil {
        diameter: 4.0,
        position: 3.6,
    };
    let e = best_focus(&eye, 555.0, 20.0, &pupil, Criterion::Strehl).unwrap_err();
    let text = e.to_string();
    let (surface, field, failure) = ray_error(e);
    assert_eq!(surface, "anterior lens");
    assert_eq!(field, 20.0);
    assert!(
        matches!(failure, RayFailure::OutsideAperture { semi_diameter, .. } if semi_diameter == 1.0)
    );
    assert!(
        text.contains("anterior lens") && text.contains("20°") && text.contains("555 nm"),
        "{text}"
    );
}

#[test]
fn a_ray_that_misses_an_ellipsoid_is_a_miss_at_that_surface() {
    // A strongly oblate posterior lens (k = 8: its rim at r = R/√(1+k) = 2 mm) and a 6 mm pupil.
    let mut eye = four_surface_eye();
    eye.elements[3].surface.conic = 8.0;
    let pupil = Pupil {
        diameter: 6.0,
        position: 3.6,
    };
    let (surface, field, failure) =
        ray_error(best_focus(&eye, 555.0, 0.0, &pupil, Criterion::MeanSphere).unwrap_err());
    assert_eq!(surface, "posterior lens");
    assert_eq!(field, 0.0);
    assert_eq!(failure, RayFailure::Miss);
}

#[test]
fn total_internal_reflection_is_reported() {
    // Light from a dense lens (n = 2.4) into a thin medium at a steep posterior surface.
    let eye = OpticalSystem::new(
        "tir",
        Medium::constant("air", 1.0),
        vec![
            Element::new(
                Surface::new("front", 50.0, 0.0),
                2.0,
                Medium::constant("glass", 2.4),
            ),
            Element::new(
                Surface::new("back", -2.2, 0.0),
                20.0,
                Medium::constant("image", 1.0),
            ),
        ],
    )
    .unwrap();
    let pupil = Pupil {
        diameter: 3.4,
        position: 1.0,
    };
    let (surface, _, failure) =
        ray_error(best_focus(&eye, 555.0, 10.0, &pupil, Criterion::MeanSphere).unwrap_err());
    assert_eq!(surface, "back");
    assert_eq!(failure, RayFailure::TotalInternalReflection);
}

#[test]
fn a_gradient_index_that_falls_below_one_is_not_physical() {
    let mut eye = eyes::liou_brennan_1997();
    if let eyeshell_optics::MediumKind::Grin(g) = &mut eye.elements[2].medium.kind {
        g.coefficients[1][0] = -0.1; // n = 1.368 − 0.1 r²: below 1 beyond r ≈ 1.9 mm
    }
    let pupil = Pupil {
        diameter: 5.0,
        position: 3.66,
    };
    let (surface, field, failure) =
        ray_error(best_focus(&eye, 600.0, 30.0, &pupil, Criterion::Strehl).unwrap_err());
    assert!(surface.contains("lens"), "{surface}");
    assert_eq!(field, 30.0);
    assert!(
        matches!(failure, RayFailure::NonPhysicalIndex { n, .. } if n < 1.0),
        "{failure:?}"
    );
}

#[test]
fn a_gradient_integration_that_does_not_converge_is_an_error() {
    let eye = eyes::atchison_2006();
    let settings = FocusSettings {
        rays_across: 8,
        grin: GrinSettings {
            tolerance: 1e-9,
            max_steps: 2,
        },
    };
    let pupil = Pupil {
        diameter: 3.0,
        position: 3.7,
    };
    let (surface, _, failure) = ray_error(
        best_focus_with(&eye, 400.0, 10.0, &pupil, Criterion::Strehl, &settings).unwrap_err(),
    );
    assert_eq!(surface, "lens (anterior half)");
    assert!(
        matches!(failure, RayFailure::GrinNotConverged { .. }),
        "{failure:?}"
    );
}

#[test]
fn unusable_requests_are_typed_errors() {
    let eye = four_surface_eye();
    let bad = [
        (555.0, 0.0, 0.0, 3.6),
        (555.0, 0.0, -1.0, 3.6),
        (555.0, 0.0, f64::NAN, 3.6),
        (555.0, f64::NAN, 0.5, 3.6),
        (555.0, 95.0, 0.5, 3.6),
        (5.0, 0.0, 0.5, 3.6),
        (f64::INFINITY, 0.0, 0.5, 3.6),
        (555.0, 0.0, 0.5, -1.0),
        (555.0, 0.0, 0.5, 1e9),
    ];
    for (w, f, d, p) in bad {
        let pupil = Pupil {
            diameter: d,
            position: p,
        };
        let e = best_focus(&eye, w, f, &pupil, Criterion::Strehl).unwrap_err();
        assert!(
            matches!(
                e,
                OpticsError::InvalidInput { .. } | OpticsError::InvalidSystem { .. }
            ),
            "{w} {f} {d} {p}: {e:?}"
        );
    }
    // A stop inside a gradient-index lens is refused.
    let lb = eyes::liou_brennan_1997();
    let e = best_focus(
        &lb,
        555.0,
        0.0,
        &Pupil {
            diameter: 1.0,
            position: 5.0,
        },
        Criterion::Strehl,
    )
    .unwrap_err();
    assert!(e.to_string().contains("lens (anterior half)"), "{e}");
}

#[test]
fn invalid_systems_are_refused_with_the_surface_and_key() {
    let cases: Vec<(Vec<Element>, &str)> = vec![
        (
            vec![Element::new(
                Surface::new("s", 0.0, 0.0),
                1.0,
                Medium::constant("m", 1.3),
            )],
            "radius",
        ),
        (
            vec![Element::new(
                Surface::new("s", 5.0, f64::NAN),
                1.0,
                Medium::constant("m", 1.3),
            )],
            "conic",
        ),
        (
            vec![Element::new(
                Surface::new("s", 5.0, 0.0),
                -1.0,
                Medium::constant("m", 1.3),
            )],
            "thickness",
        ),
        (
            vec![Element::new(
                Surface::new("s", 5.0, 0.0),
                1.0,
                Medium::constant("m", 0.5),
            )],
            "refractive index of 'm'",
        ),
        (
            vec![Element::new(
                Surface::new("s", 5.0, 0.0),
                1.0,
                Medium::constant("m", f64::NAN),
            )],
            "refractive index of 'm'",
        ),
        (
            vec![Element::new(
                Surface::new("s", 5.0, 0.0),
                1.0,
                Medium::grin(
                    "g",
                    Grin {
                        coefficients: vec![vec![1.4]],
                        origin: 0.0,
                        dispersion: None,
                    },
                ),
            )],
            "image space",
        ),
        (vec![], "no surfaces"),
    ];
    for (elements, key) in cases {
        let e = OpticalSystem::new("bad", Medium::constant("air", 1.0), elements).unwrap_err();
        assert!(e.to_string().contains(key), "{e} lacks {key}");
    }
}

#[test]
fn surfaces_report_the_first_failing_angle_in_order() {
    let mut eye = four_surface_eye();
    eye.elements[2].surface.semi_diameter = Some(2.03);
    let pupil = Pupil {
        diameter: 4.0,
        position: 3.6,
    };
    let settings = SurfaceSettings {
        fields: 9,
        ..SurfaceSettings::default()
    };
    let e =
        Surfaces::compute(&eye, &[400.0, 600.0], &pupil, Criterion::Strehl, &settings).unwrap_err();
    let (surface, field, _) = ray_error(e);
    assert_eq!(surface, "anterior lens");
    // The smallest failing angle of the first wavelength.
    let ok = |f: f64| best_focus(&eye, 400.0, f, &pupil, Criterion::Strehl).is_ok();
    assert!(!ok(field));
    let step = 40.0 / 8.0;
    let mut a = 0.0;
    while a < field {
        assert!(ok(a), "{a}° fails before {field}°");
        a += step;
    }
}

#[test]
fn nothing_nan_in_a_computed_surface() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 4.0,
        position: 3.7,
    };
    let s = Surfaces::compute(
        &eye,
        &[400.0],
        &pupil,
        Criterion::Strehl,
        &SurfaceSettings {
            fields: 9,
            ..SurfaceSettings::default()
        },
    )
    .unwrap();
    for p in &s.surfaces[0].points {
        assert!(
            p.z.is_finite()
                && p.r.is_finite()
                && p.strehl.is_finite()
                && p.strehl > 0.0
                && p.strehl <= 1.0 + 1e-12,
            "{p:?}"
        );
    }
    let _ = SMALL_PUPIL;
}
