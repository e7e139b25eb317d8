//! Surfaces, refraction and dispersion laws on their own.

use eyeshell_optics::{
    Dispersion, Element, GrinSettings, Medium, OpticalSystem, Ray, Surface, Tracer, Vec3,
};

#[test]
fn an_aspheric_surface_is_met_exactly_and_refracts_by_snell() {
    let surface = Surface::new("asphere", 8.0, -0.5).with_aspheric(vec![1e-3, -2e-5]);
    let sys = OpticalSystem::new(
        "one surface",
        Medium::constant("air", 1.0),
        vec![Element::new(
            surface.clone(),
            10.0,
            Medium::constant("glass", 1.5),
        )],
    )
    .unwrap();
    let tr = Tracer::new(&sys, 555.0, GrinSettings::default());
    for (x, y, dx, dy) in [
        (0.0, 0.0, 0.0, 0.0),
        (1.0, 2.0, 0.05, -0.1),
        (-2.5, 0.7, 0.2, 0.1),
        (0.3, -3.0, -0.1, 0.3),
    ] {
        let d = Vec3::new(dx, dy, 1.0).unit();
        let ray = Ray {
            position: Vec3::new(x, y, -2.0),
            direction: d,
            opl: 0.0,
        };
        let out = tr.trace(ray).unwrap();
        let p = out.position;
        let sag = surface.sag(p.rho()).unwrap();
        assert!((p.z - sag).abs() < 1e-12, "{} vs {sag}", p.z);
        // On the incident ray.
        let t = (p - ray.position).dot(d);
        assert!((ray.position + d * t - p).norm() < 1e-12);
        assert!((out.opl - t).abs() < 1e-12);
        // Snell: n₁ d × N = n₂ d′ × N, and d′ in the plane of d and N.
        let n = surface.normal(p).unwrap();
        let (a, b) = (d.cross(n), out.direction.cross(n) * 1.5);
        assert!((a - b).norm() < 1e-12, "{a:?} {b:?}");
    }
}

#[test]
fn the_aspheric_terms_change_the_sag_as_written() {
    let s = Surface::new("s", 10.0, 0.0).with_aspheric(vec![1e-3, 1e-5]);
    let r: f64 = 2.0;
    let sphere = 10.0 - (100.0 - r * r).sqrt();
    let expected = sphere + 1e-3 * r.powi(4) + 1e-5 * r.powi(6);
    assert!((s.sag(r).unwrap() - expected).abs() < 1e-14);
    // Principal curvatures at the vertex are the vertex curvature; off axis they follow the
    // profile's derivatives.
    let (ks, kt) = s.principal_curvatures(0.0).unwrap();
    assert!((ks - 0.1).abs() < 1e-14 && (kt - 0.1).abs() < 1e-14);
    assert!(
        Surface::new("ellipse", 5.0, 1.0).sag(4.0).is_none(),
        "beyond an oblate ellipsoid's rim"
    );
}

#[test]
fn sellmeier_and_cauchy_laws_give_known_indices() {
    // Fused silica (Malitson): n(587.6 nm) = 1.4585.
    let silica = Dispersion::Sellmeier {
        b: vec![0.6961663, 0.4079426, 0.8974794],
        c: vec![
            0.0684043f64.powi(2),
            0.1162414f64.powi(2),
            9.896161f64.powi(2),
        ],
    };
    assert!(
        (silica.index(587.6) - 1.4585).abs() < 1e-4,
        "{}",
        silica.index(587.6)
    );
    // cauchy_through keeps the reference index.
    let c = Dispersion::cauchy_through(1.376, 555.0, 6.009687e3, -6.760760e8, 5.908450e13);
    assert!((c.index(555.0) - 1.376).abs() < 1e-14);
    assert!(c.index(400.0) > c.index(600.0));
    // A table is reproduced by its Cauchy fit to its own precision.
    let table = vec![
        (458.0, 1.3828),
        (543.0, 1.3777),
        (589.3, 1.376),
        (632.8, 1.3747),
    ];
    let t = Dispersion::Tabulated(table.clone());
    for (l, n) in table {
        assert!((t.index(l) - n).abs() < 2e-4, "{l}: {} vs {n}", t.index(l));
    }
    // Too short a table is NaN, which the system check refuses.
    assert!(Dispersion::Tabulated(vec![(500.0, 1.3)])
        .index(500.0)
        .is_nan());
    let e = OpticalSystem::new(
        "short table",
        Medium::constant("air", 1.0),
        vec![Element::new(
            Surface::new("s", 5.0, 0.0),
            1.0,
            Medium::homogeneous("m", Dispersion::Tabulated(vec![(500.0, 1.3)])),
        )],
    )
    .unwrap_err();
    assert!(e.to_string().contains("'m'"), "{e}");
}
