//! The must-show of a custom eye read from a scene (`optics.eye = "custom"`,
//! `[[optics.surfaces]]`): the four-surface eye with constant indices of the optics crate's
//! own checks, written as a scene, a 0.5 mm pupil. On axis its best focus is the paraxial
//! focus of an independent y-nu trace and its equivalent power that trace's; off axis its
//! mean-sphere foci are those of differential ray tracing. The references are the optics
//! crate's test helpers, written without the library's paraxial or focus code.

#[path = "../../../optics/tests/common/mod.rs"]
mod optics_common;

use eyeshell::scene::Scene;
use eyeshell_optics::{paraxial, Criterion};
use optics_common::{differential_foci, four_surface_eye, ynu_reference};

/// The eye of `optics_common::four_surface_eye`, as a scene gives it.
const SCENE: &str = r#"
growth.eta0 = 70
stimulus.source = "optics"

[optics]
eye = "custom"
pupil = 0.5
pupil_position = 3.6
focus = "mean-sphere"
wavelengths = [589, 600]
max_field = 30

[[optics.surfaces]]   # anterior cornea
radius = 7.8
conic = -0.25
thickness = 0.55
index = 1.376

[[optics.surfaces]]   # posterior cornea
radius = 6.5
conic = -0.3
thickness = 3.05
index = 1.336

[[optics.surfaces]]   # anterior lens
radius = 10.2
conic = -3
thickness = 4
index = 1.42

[[optics.surfaces]]   # posterior lens
radius = -6
conic = -1
thickness = 16.4
index = 1.336
"#;

const N: [f64; 5] = [1.0, 1.376, 1.336, 1.42, 1.336];

#[test]
fn a_custom_eye_from_a_scene_focuses_where_ynu_and_differential_rays_say() {
    let scene = Scene::from_toml_str(SCENE, "custom.toml", &[]).unwrap();
    let spec = scene.optics();
    let system = spec.system().unwrap();
    assert_eq!(system.elements.len(), 4);
    assert_eq!(system.pupil_position, Some(3.6));
    // The references trace the optics crate's own copy of the eye: the scene must give the
    // same numbers (or the references would check another eye).
    let reference = four_surface_eye();
    for (a, b) in system.elements.iter().zip(&reference.elements) {
        assert_eq!(
            (a.surface.radius, a.surface.conic, a.thickness),
            (b.surface.radius, b.surface.conic, b.thickness)
        );
    }
    let (power, bfd) = ynu_reference(&reference, &N);
    let p = paraxial(&system, 589.0).unwrap();
    assert!(
        (p.power - power).abs() < 0.01,
        "power {} vs {power}",
        p.power
    );
    // The surfaces the growth would read, traced as the scene was read.
    let computed = scene.growth.as_ref().unwrap().computed.clone().unwrap();
    let blue = &computed.surfaces.surfaces[0];
    assert_eq!((blue.wavelength_nm, blue.points.len()), (589.0, 31));
    assert_eq!(blue.criterion, Criterion::MeanSphere);
    let axis = &blue.points[0];
    let paraxial_focus = 0.55 + 3.05 + 4.0 + bfd;
    assert!(
        (axis.z - paraxial_focus).abs() < 0.01 && axis.r.abs() < 1e-9,
        "axial focus {} vs y-nu {paraxial_focus}",
        axis.z
    );
    for field in [10usize, 20, 30] {
        let f = &blue.points[field];
        assert_eq!(f.field_deg, field as f64);
        let (s, t) = differential_foci(&reference, 589.0, field as f64, 3.6);
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
            "{field}°: {} vs {mean}",
            f.distance
        );
        // Astigmatic enough that the agreement is not trivial.
        assert!((t - s).abs() > 0.05, "{field}°: {s} {t}");
    }
}
