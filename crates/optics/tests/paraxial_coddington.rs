//! The must-show agreements: on axis, both criteria at the paraxial focus of an independent
//! y-nu trace; off axis, the wavefront's sagittal and tangential foci at Coddington's and at
//! those of differential ray tracing.

mod common;

use common::{differential_foci, four_surface_eye, ynu_reference, SMALL_PUPIL};
use eyeshell_optics::{best_focus, coddington, paraxial, Criterion};

const N: [f64; 5] = [1.0, 1.376, 1.336, 1.42, 1.336];

#[test]
fn equivalent_power_and_back_focus_match_an_independent_ynu_trace() {
    let eye = four_surface_eye();
    let (power, bfd) = ynu_reference(&eye, &N);
    let p = paraxial(&eye, 589.0).unwrap();
    assert!((p.power - power).abs() < 0.01, "{} vs {power}", p.power);
    assert!(
        (p.back_focal_distance - bfd).abs() < 1e-6,
        "{} vs {bfd}",
        p.back_focal_distance
    );
    // Sanity: a human eye's power.
    assert!(p.power > 55.0 && p.power < 66.0, "{}", p.power);
    // Cardinal points: the nodal points sit (n′ − n)/F behind the principal points, and the
    // back focal length n′/F spans P′ to F′.
    assert!((p.focus - p.principal.1 - 1.336 / (p.power / 1000.0)).abs() < 1e-9);
    assert!((p.nodal.1 - p.principal.1 - 0.336 / (p.power / 1000.0)).abs() < 1e-9);
}

#[test]
fn on_axis_both_criteria_find_the_paraxial_focus() {
    let eye = four_surface_eye();
    let (_, bfd) = ynu_reference(&eye, &N);
    let paraxial_focus = 0.55 + 3.05 + 4.0 + bfd;
    for criterion in [Criterion::MeanSphere, Criterion::Strehl] {
        let f = best_focus(&eye, 589.0, 0.0, &SMALL_PUPIL, criterion).unwrap();
        assert!(
            (f.z - paraxial_focus).abs() < 0.01,
            "{criterion:?}: {} vs paraxial {paraxial_focus}",
            f.z
        );
        assert!(f.r.abs() < 1e-9, "{}", f.r);
        assert!(f.strehl > 0.99, "{}", f.strehl);
    }
}

#[test]
fn mean_sphere_foci_match_coddington_and_differential_ray_tracing() {
    let eye = four_surface_eye();
    for field in [10.0, 20.0, 30.0] {
        let f = best_focus(&eye, 589.0, field, &SMALL_PUPIL, Criterion::MeanSphere).unwrap();
        let (s, t) = coddington(&eye, 589.0, field, &SMALL_PUPIL).unwrap();
        let (sd, td) = differential_foci(&eye, 589.0, field, SMALL_PUPIL.position);
        // The two references agree with each other to far better than the tolerance.
        assert!(
            (s - sd).abs() < 1e-4 && (t - td).abs() < 1e-4,
            "{field}°: Coddington ({s}, {t}) vs differential ({sd}, {td})"
        );
        assert!(
            (f.sagittal - s).abs() < 0.02,
            "{field}°: sagittal {} vs {s}",
            f.sagittal
        );
        assert!(
            (f.tangential - t).abs() < 0.02,
            "{field}°: tangential {} vs {t}",
            f.tangential
        );
        let mean = 2.0 / (1.0 / s + 1.0 / t);
        assert!(
            (f.distance - mean).abs() < 0.02,
            "{field}°: mean sphere {} vs {mean}",
            f.distance
        );
        // The astigmatism is real at these angles (the test is not trivially passed).
        assert!((t - s).abs() > 0.05, "{field}°: {s} {t}");
    }
}

#[test]
fn strehl_focus_lies_between_the_astigmatic_foci_for_a_small_pupil() {
    let eye = four_surface_eye();
    for field in [10.0, 20.0, 30.0] {
        let f = best_focus(&eye, 589.0, field, &SMALL_PUPIL, Criterion::Strehl).unwrap();
        let (lo, hi) = (f.sagittal.min(f.tangential), f.sagittal.max(f.tangential));
        assert!(
            f.distance > lo && f.distance < hi,
            "{field}°: {} not in [{lo}, {hi}]",
            f.distance
        );
    }
}

#[test]
fn ocular_refraction_images_the_object_on_the_retina() {
    let eye = four_surface_eye();
    let p = paraxial(&eye, 589.0).unwrap();
    assert!(p.ocular_refraction(p.focus).abs() < 1e-9);
    // A retina 1 mm behind the focus: myopic by about F²·1 mm / n′ ≈ 2.7 D.
    let retina = p.focus + 1.0;
    let v = p.ocular_refraction(retina);
    assert!(v < -2.0 && v > -3.5, "{v}");
    // Check with the test's own paraxial trace: a ray from the object of vergence V (at
    // distance 1000/V mm in front) through height 1 at the cornea crosses the axis at the retina.
    let (mut y, mut u) = (1.0_f64, -v / 1000.0);
    for (i, e) in eye.elements.iter().enumerate() {
        let c = 1.0 / e.surface.radius;
        u = (N[i] * u - y * (N[i + 1] - N[i]) * c) / N[i + 1];
        let t = if i + 1 < eye.elements.len() {
            e.thickness
        } else {
            retina - p.focus + p.back_focal_distance
        };
        y += t * u;
    }
    assert!(y.abs() < 1e-9, "{y}");
}

#[test]
fn a_perfect_refracting_ellipsoid_has_strehl_one_at_its_geometric_focus() {
    // An ellipsoid of conic k = −1/n′² images a distant axial point perfectly, at
    // f′ = n′R/(n′ − 1) behind its vertex: every ray's optical path to that point is the same.
    use eyeshell_optics::{Element, Medium, OpticalSystem, Pupil, Surface};
    let n = 1.5;
    let eye = OpticalSystem::new(
        "ellipsoid",
        Medium::constant("air", 1.0),
        vec![
            Element::new(
                Surface::new("ellipsoid", 10.0, -1.0 / (n * n)),
                10.0,
                Medium::constant("glass", n),
            ),
            Element::new(
                Surface::plane("dummy"),
                40.0,
                Medium::constant("glass behind", n),
            ),
        ],
    )
    .unwrap();
    let f = n * 10.0 / (n - 1.0);
    let pupil = Pupil {
        diameter: 8.0,
        position: 5.0,
    };
    for criterion in [Criterion::Strehl, Criterion::MeanSphere] {
        let b = best_focus(&eye, 555.0, 0.0, &pupil, criterion).unwrap();
        assert!((b.z - f).abs() < 1e-6, "{criterion:?}: {} vs {f}", b.z);
        assert!(b.strehl > 1.0 - 1e-9, "{}", b.strehl);
        assert!((b.sagittal - b.tangential).abs() < 1e-9);
    }
    // A sphere of the same radius has spherical aberration: its Strehl focus moves in front of
    // the paraxial one and its Strehl ratio drops.
    let mut sphere = eye.clone();
    sphere.elements[0].surface.conic = 0.0;
    let b = best_focus(&sphere, 555.0, 0.0, &pupil, Criterion::Strehl).unwrap();
    assert!(b.z < f - 0.01 && b.strehl < 0.9, "{} {}", b.z, b.strehl);
}
