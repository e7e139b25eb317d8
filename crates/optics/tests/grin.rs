//! The gradient-index integrator's own checks: exact solutions and convergence.

use eyeshell_optics::{
    Element, Grin, GrinSettings, Medium, OpticalSystem, Ray, Surface, Tracer, Vec3,
};

fn slab(medium: Medium) -> OpticalSystem {
    OpticalSystem::new(
        "slab",
        Medium::constant("air", 1.0),
        vec![
            Element::new(Surface::plane("front"), 5.0, medium),
            Element::new(Surface::plane("back"), 10.0, Medium::constant("image", 1.0)),
        ],
    )
    .unwrap()
}

fn grin(c: Vec<Vec<f64>>) -> Medium {
    Medium::grin(
        "grin",
        Grin {
            coefficients: c,
            origin: 0.0,
            dispersion: None,
        },
    )
}

fn skew_ray() -> Ray {
    Ray {
        position: Vec3::new(0.3, -0.2, -1.0),
        direction: Vec3::new(0.05, 0.12, 1.0).unit(),
        opl: 0.0,
    }
}

#[test]
fn a_constant_gradient_index_traces_like_the_homogeneous_medium() {
    let homo = slab(Medium::constant("glass", 1.5));
    let flat = slab(grin(vec![vec![1.5]]));
    let settings = GrinSettings::default();
    let a = Tracer::new(&homo, 555.0, settings)
        .trace(skew_ray())
        .unwrap();
    let b = Tracer::new(&flat, 555.0, settings)
        .trace(skew_ray())
        .unwrap();
    assert!(
        (a.position - b.position).norm() < 1e-10,
        "{:?} {:?}",
        a.position,
        b.position
    );
    assert!((a.direction - b.direction).norm() < 1e-12);
    assert!((a.opl - b.opl).abs() < 1e-10);
}

#[test]
fn an_axial_gradient_keeps_the_transverse_optical_direction() {
    // n = 1.4 + 0.01 z: ∇n is along z, so n·dx/ds and n·dy/ds are invariants; after the slab
    // (back into index 1) the transverse direction equals the incident one.
    let sys = slab(grin(vec![vec![1.4, 0.01, -0.002]]));
    let r = Tracer::new(&sys, 555.0, GrinSettings::default())
        .trace(skew_ray())
        .unwrap();
    let d0 = skew_ray().direction;
    assert!(
        (r.direction.x - d0.x).abs() < 1e-12 && (r.direction.y - d0.y).abs() < 1e-12,
        "{:?}",
        r.direction
    );
}

#[test]
fn a_radial_gradient_follows_the_paraxial_sinusoid() {
    // n = n0 − g r², paraxially y(z) = y0 cos(√(2g/n0) z) for a ray entering parallel.
    let (n0, g) = (1.5, 0.01);
    let sys = slab(grin(vec![vec![n0], vec![-g]]));
    let y0 = 1e-3;
    let ray = Ray {
        position: Vec3::new(0.0, y0, -1.0),
        direction: Vec3::new(0.0, 0.0, 1.0),
        opl: 0.0,
    };
    let tr = Tracer::new(&sys, 555.0, GrinSettings::default());
    let out = tr.trace_surfaces(ray, 2, None).unwrap();
    let k = (2.0 * g / n0).sqrt();
    let y = y0 * (k * 5.0).cos();
    assert!(
        (out.position.y - y).abs() < 1e-9 * 10.0,
        "{} vs {y}",
        out.position.y
    );
    // The slope after leaving into air: n0·(dy/dz) inside = −n0 y0 k sin(kz).
    let slope = -n0 * y0 * k * (k * 5.0).sin();
    assert!(
        (out.direction.y - slope).abs() < 1e-9,
        "{} vs {slope}",
        out.direction.y
    );
}

#[test]
fn tightening_the_tolerance_converges() {
    let sys = slab(grin(vec![vec![1.4, 0.02, -0.004], vec![-0.003, 0.0005]]));
    let at = |tol: f64| {
        Tracer::new(
            &sys,
            555.0,
            GrinSettings {
                tolerance: tol,
                max_steps: 100_000,
            },
        )
        .trace(skew_ray())
        .unwrap()
    };
    let reference = at(1e-13);
    let mut last = f64::INFINITY;
    for tol in [1e-5, 1e-7, 1e-9, 1e-11] {
        let r = at(tol);
        let e = (r.position - reference.position).norm() + (r.opl - reference.opl).abs();
        assert!(e < last.max(1e-13), "tol {tol}: {e} after {last}");
        assert!(e < 100.0 * tol, "tol {tol}: error {e}");
        last = e;
    }
}
