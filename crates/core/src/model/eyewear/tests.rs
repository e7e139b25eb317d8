//! Unit tests of the eyewear: lenses, their tables and the refraction through them.

use super::*;
use eyeshell_optics::best_focus_with;

/// A spherical retina of radius 11 mm about z = 12 (23 mm long), from just off its pole
/// outwards (as a shell's nodes are).
pub(crate) fn sphere() -> Vec<(f64, f64)> {
    (0..=240)
        .map(|k| {
            let phi = (0.01 + k as f64 * 0.5).to_radians();
            (12.0 + 11.0 * phi.cos(), 11.0 * phi.sin())
        })
        .collect()
}

/// The peripheral refraction at field 0 is the pole's refraction_D (read from the 1 D
/// table), and off the axis it is what it says: a thin spectacle lens of that power,
/// traced directly (not from the table), puts that field's best focus on the retina.
#[test]
fn peripheral_refraction_puts_each_fields_focus_on_the_retina() {
    let spec = OpticsSpec::default();
    let table = peripheral_table_at(&spec, 0.0).unwrap();
    assert_eq!(table.fields, peripheral_fields(40.0));
    assert_eq!(table.fields.len(), 9);
    let d = peripheral_refraction(&table, 12.0, &sphere());
    eprintln!("peripheral refraction of the sphere: {d:?}");
    let pole = refraction_table(&spec).unwrap().refraction(23.0).unwrap();
    assert!((d[0] - pole).abs() < 1e-3, "{} against {pole}", d[0]);
    let eye = spec.system().unwrap();
    let pupil = spec.pupil_stop(&eye);
    for (i, &field) in table.fields.iter().enumerate() {
        let worn = optics::lens::wear(&eye, &[Lens::spectacle(d[i], VERTEX_MM)]).unwrap();
        let f = best_focus_with(
            &worn,
            spec.refraction_wavelength,
            field,
            &pupil,
            spec.criterion(),
            &FocusSettings::default(),
        )
        .unwrap();
        let behind = f.r.hypot(f.z - 12.0) - 11.0;
        // 0.004 mm is about 0.01 D in this eye.
        assert!(behind.abs() < 0.004, "field {field}°: {behind} mm off");
    }
    // This sphere is steeper than the eye's image shell: its periphery is hyperopic
    // against the pole (+0.26 D at 40°), and more so at every larger field.
    assert!(d[8] > d[0] + 0.2, "{d:?}");
    assert!(d[4..].windows(2).all(|w| w[1] > w[0]), "{d:?}");
}

/// An eye whose cornea flattens over t is traced at its table times only; between them
/// its refraction is the blend of theirs, within 0.02 D of a table traced at that time
/// (at a table time, exactly the traced one).
#[test]
fn refraction_with_age_is_blended_from_the_table_times() {
    use crate::growth::settings::blend_over_ages;
    use crate::model::eye::{EyeValue, SurfaceSpec};
    let spec = OpticsSpec {
        surfaces: vec![SurfaceSpec {
            radius: Some(EyeValue::Table {
                t: vec![0.0, 0.4, 1.0],
                value: vec![7.47, 7.70, 7.77],
            }),
            ..Default::default()
        }],
        ..OpticsSpec::default()
    };
    let traced_at = |t: f64| {
        refraction_table_at(&spec, t)
            .unwrap()
            .refraction(23.0)
            .unwrap()
    };
    let blend = |t: f64| blend_over_ages(&spec, t, |at| vec![traced_at(at)])[0];
    assert_eq!(blend(0.4), traced_at(0.4));
    for t in [0.2, 0.7] {
        let (b, exact) = (blend(t), traced_at(t));
        assert!((b - exact).abs() < 0.02, "t {t}: {b} against {exact}");
    }
    // The flattening cornea loses power: the same retina grows more hyperopic.
    assert!(
        blend(1.0) > blend(0.0) + 0.5,
        "{} {}",
        blend(0.0),
        blend(1.0)
    );
}

/// A prescribed lens for a retina at 24.2 mm (a myope of about −1.5 D in the default
/// eye): the spectacle lens at 12 mm is the refraction table's own refraction there; a
/// spectacle lens at 15 mm and a contact lens take their vertex conversions, and each,
/// worn and traced directly (not from a table), puts the on-axis best focus on that
/// retina to 0.004 mm (0.01 D); `over` adds to the power.
#[test]
fn a_prescribed_lens_puts_the_focus_on_its_retina() {
    let retina = 24.2;
    let lens = |kind: usize, vertex: f64, over: f64| LensSpec {
        kind,
        vertex,
        profile: ProfileSpec::Power(over),
        lenslets: vec![],
        prescribe: Some(over),
    };
    let refraction = refraction_table(&OpticsSpec::default())
        .unwrap()
        .refraction(retina)
        .unwrap();
    assert!(refraction < -1.0 && refraction > -2.0, "{refraction}");
    for (kind, vertex, expected) in [
        (0, 12.0, refraction),
        (0, 15.0, refraction / (1.0 + refraction * 0.003)),
        (1, 12.0, refraction / (1.0 - refraction * 0.012)),
    ] {
        let spec = OpticsSpec {
            lenses: vec![lens(kind, vertex, 0.0)],
            ..OpticsSpec::default()
        };
        let prescribed = prescribe(&spec, retina).unwrap();
        let ProfileSpec::Power(p) = prescribed.lenses[0].profile else {
            panic!("{:?}", prescribed.lenses[0]);
        };
        assert!(
            (p - expected).abs() < 1e-12,
            "{kind} at {vertex}: {p} vs {expected}"
        );
        let worn = worn(&prescribed).unwrap();
        let f = best_focus_with(
            &worn,
            spec.refraction_wavelength,
            0.0,
            &spec.pupil_stop(&spec.system().unwrap()),
            spec.criterion(),
            &FocusSettings::default(),
        )
        .unwrap();
        assert!(
            (f.z - retina).abs() < 0.004,
            "{kind} at {vertex}: focus {}",
            f.z
        );
        let over = OpticsSpec {
            lenses: vec![lens(kind, vertex, -0.25)],
            ..OpticsSpec::default()
        };
        let ProfileSpec::Power(q) = prescribe(&over, retina).unwrap().lenses[0].profile else {
            panic!("not a power");
        };
        assert!((q - (p - 0.25)).abs() < 1e-12, "{q} vs {p}");
    }
    // No refraction within ±25 D: the prescribed lens's key says why.
    let far = OpticsSpec {
        lenses: vec![lens(0, 12.0, 0.0)],
        ..OpticsSpec::default()
    };
    let e = prescribe(&far, 40.0).unwrap_err();
    assert_eq!(e.key, format!("{}[0].power", Quantity::Lenses));
    assert!(e.problem.contains("beyond the ±25 D"), "{}", e.problem);
}

#[test]
fn the_fields_run_every_5_degrees_to_the_largest() {
    assert_eq!(peripheral_fields(12.0), vec![0.0, 5.0, 10.0, 12.0]);
    assert_eq!(peripheral_fields(10.0), vec![0.0, 5.0, 10.0]);
}
