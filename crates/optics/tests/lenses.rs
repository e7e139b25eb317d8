//! Eyewear: thin and real spectacle lenses, zoned and tabulated profiles, contact lenses, and
//! the refraction table (docs/optics.md, "Lenses" and "Refraction").

mod common;

use eyeshell_optics::lens::{wear, Lens, LensBody, Mount, PowerProfile, Zone};
use eyeshell_optics::refraction::RefractionTable;
use eyeshell_optics::{best_focus, eyes, paraxial, Criterion, FocusSettings, Pupil};

/// The eye's paraxial image of an object of vergence `k` (D) at its first vertex: from the
/// eye's own system matrix, with no lens in it.
/// A spectacle lens at 12 mm of power `centre` (D) inside a 9 mm zone and `periphery` out to
/// 50 mm: the peripheral-plus design of scenes/eyewear.
fn peripheral_plus(centre: f64, periphery: f64) -> Lens {
    Lens {
        mount: Mount::Spectacle { vertex: 12.0 },
        body: LensBody::Thin(
            PowerProfile::zones(vec![
                Zone {
                    radius: 4.5,
                    power: centre,
                },
                Zone {
                    radius: 25.0,
                    power: periphery,
                },
            ])
            .unwrap(),
        ),
    }
}

fn image_of_vergence(eye: &eyeshell_optics::OpticalSystem, k: f64) -> f64 {
    let p = paraxial(eye, 555.0).unwrap();
    let [[a, b], [c, d]] = p.matrix;
    let k = k / 1000.0;
    // (a + t c)/(b + t d) = k, t = (z − last)/n′.
    let t = (a - k * b) / (k * d - c);
    p.focus - p.back_focal_distance + t * p.n_image
}

#[test]
fn a_thin_spectacle_lens_moves_the_focus_where_the_effective_power_says() {
    let eye = eyes::atchison_2006();
    let small = Pupil {
        diameter: 0.2,
        position: eye.pupil_position.unwrap(),
    };
    let base = best_focus(&eye, 555.0, 0.0, &small, Criterion::MeanSphere)
        .unwrap()
        .z;
    for f in [-5.0, 5.0] {
        for d in [12.0, 14.0] {
            let k = f / (1.0 - d / 1000.0 * f);
            let expected = image_of_vergence(&eye, k);
            let worn = wear(&eye, &[Lens::spectacle(f, d)]).unwrap();
            assert!((worn.origin + d).abs() < 1e-12, "the lens sits at −d");
            let parax = paraxial(&worn, 555.0).unwrap().focus;
            assert!(
                (parax - expected).abs() < 1e-6,
                "{f} D at {d} mm: {parax} vs {expected}"
            );
            // The exact trace through the lens's phase, with a pupil small enough that the
            // eye's spherical aberration is below 1e-3 mm.
            let exact = best_focus(&worn, 555.0, 0.0, &small, Criterion::MeanSphere)
                .unwrap()
                .z;
            assert!(
                (exact - expected).abs() < 0.01,
                "{f} D at {d} mm: traced {exact}, effective power says {expected}"
            );
            // The lens moves the focus by millimetres, in the right direction.
            assert!((exact - base) * f < -1.0, "{f} D: {exact} vs {base}");
        }
    }
}

#[test]
fn a_real_lens_matches_a_thin_one_of_its_power() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 0.2,
        position: eye.pupil_position.unwrap(),
    };
    // A 2 mm plano-concave lens in n = 1.5: back vertex power −1/(0.5/R + ...) exactly.
    let (r, t, n) = (-100.0, 2.0, 1.5);
    let front = (n - 1.0) / r * 1000.0;
    let real = Lens {
        mount: Mount::Spectacle { vertex: 12.0 },
        body: LensBody::Real {
            front_radius: r,
            back_radius: f64::INFINITY,
            thickness: t,
            index: n,
        },
    };
    // Back-vertex power of a plano-back lens: F1/(1 − t F1/n).
    let bvp = front / (1.0 - t / 1000.0 * front / n);
    let z_real = best_focus(
        &wear(&eye, &[real]).unwrap(),
        555.0,
        0.0,
        &pupil,
        Criterion::MeanSphere,
    )
    .unwrap()
    .z;
    let z_thin = best_focus(
        &wear(&eye, &[Lens::spectacle(bvp, 12.0)]).unwrap(),
        555.0,
        0.0,
        &pupil,
        Criterion::MeanSphere,
    )
    .unwrap()
    .z;
    assert!((z_real - z_thin).abs() < 0.005, "{z_real} vs {z_thin}");
}

#[test]
fn a_plus_periphery_moves_the_peripheral_foci_not_the_axial_one() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 3.0,
        position: eye.pupil_position.unwrap(),
    };
    let single = wear(&eye, &[Lens::spectacle(-2.0, 12.0)]).unwrap();
    let zoned = peripheral_plus(-2.0, 0.5);
    let zoned = wear(&eye, &[zoned]).unwrap();
    let at = |s: &eyeshell_optics::OpticalSystem, field: f64| {
        best_focus(s, 555.0, field, &pupil, Criterion::MeanSphere).unwrap()
    };
    let (a0, b0) = (at(&single, 0.0), at(&zoned, 0.0));
    assert!((a0.z - b0.z).abs() < 1e-9, "on axis: {} vs {}", a0.z, b0.z);
    // At 30° the pencil crosses the lens about 9 mm out, all of it in the plus ring: 2.5 D
    // more plus pulls the focus forward by most of a millimetre.
    let (a, b) = (at(&single, 30.0), at(&zoned, 30.0));
    assert!(
        b.distance < a.distance - 0.4,
        "30°: {} vs {}",
        b.distance,
        a.distance
    );
}

#[test]
fn profiles_are_checked_and_their_phase_is_the_integral_of_the_deflection() {
    let err = PowerProfile::zones(vec![
        Zone {
            radius: 4.5,
            power: -2.0,
        },
        Zone {
            radius: 3.0,
            power: 0.5,
        },
    ])
    .unwrap_err();
    assert_eq!(err.item, "zones[1].radius");
    assert!(PowerProfile::uniform(f64::NAN).is_err());
    assert!(PowerProfile::uniform(1e6).is_err());
    let table = PowerProfile::table(vec![0.0, 3.0, 6.0, 20.0], vec![-2.0, -2.0, 1.0, 1.0]).unwrap();
    // Monotone between points, exact at them.
    assert_eq!(table.power(3.0), -2.0);
    assert!((table.power(4.5) - -0.5).abs() < 1.0);
    for profile in [
        table,
        PowerProfile::zones(vec![
            Zone {
                radius: 4.5,
                power: -2.0,
            },
            Zone {
                radius: 25.0,
                power: 0.5,
            },
        ])
        .unwrap(),
        PowerProfile::Uniform(-5.0),
    ] {
        for h in [0.5, 2.0, 4.4, 4.6, 8.0, 15.0] {
            let dh = 1e-6;
            let numeric = (profile.phase(h + dh) - profile.phase(h - dh)) / (2.0 * dh);
            assert!(
                (numeric - profile.deflection(h)).abs() < 1e-7,
                "{profile:?} at {h}: {numeric} vs {}",
                profile.deflection(h)
            );
        }
    }
}

#[test]
fn the_refraction_put_back_as_a_lens_focuses_on_the_retina() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 3.0,
        position: eye.pupil_position.unwrap(),
    };
    let settings = FocusSettings::default();
    let table =
        RefractionTable::compute(&eye, 555.0, &pupil, Criterion::MeanSphere, &settings, 12.0)
            .unwrap();
    // An emmetrope's retina where its own best focus is: 0 D.
    let own = best_focus(&eye, 555.0, 0.0, &pupil, Criterion::MeanSphere)
        .unwrap()
        .z;
    assert!(table.refraction(own).unwrap().abs() < 0.01);
    for retina in [21.0, 22.7, 24.3, 25.5] {
        let rx = table.refraction(retina).unwrap();
        let worn = wear(&eye, &[Lens::spectacle(rx, 12.0)]).unwrap();
        let z = best_focus(&worn, 555.0, 0.0, &pupil, Criterion::MeanSphere)
            .unwrap()
            .z;
        // 0.01 D of refraction is about 0.004 mm of focus here: check in dioptres, by the
        // table's local slope.
        let slope = (table.focus(rx + 0.5).unwrap() - table.focus(rx - 0.5).unwrap()) / 1.0;
        let error_d = (z - retina) / slope;
        assert!(
            error_d.abs() < 0.01,
            "retina {retina}: {rx} D leaves {error_d} D"
        );
        // A short eye is hyperopic (plus), a long one myopic.
        assert_eq!(rx > 0.0, retina < own, "retina {retina}: {rx} D");
    }
    assert_eq!(table.refraction(10.0), None);
}

#[test]
fn a_contact_lens_acts_on_the_cornea() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 0.2,
        position: eye.pupil_position.unwrap(),
    };
    let contact = Lens {
        mount: Mount::Contact,
        body: LensBody::Thin(PowerProfile::Uniform(-3.0)),
    };
    let worn = wear(&eye, &[contact]).unwrap();
    assert_eq!(worn.origin, 0.0);
    let z = best_focus(&worn, 555.0, 0.0, &pupil, Criterion::MeanSphere)
        .unwrap()
        .z;
    // A contact lens's power acts at the cornea: vergence −3 D there.
    let expected = image_of_vergence(&eye, -3.0);
    assert!((z - expected).abs() < 0.01, "{z} vs {expected}");
}

#[test]
fn a_lens_that_forms_no_image_is_an_error() {
    let eye = eyes::atchison_2006();
    let pupil = Pupil {
        diameter: 3.0,
        position: eye.pupil_position.unwrap(),
    };
    // A strong ball-like lens focuses 12 mm in front of the eye: the eye then receives
    // light diverging at about −170 D and cannot bring it to a focus.
    let ball = Lens {
        mount: Mount::Spectacle { vertex: 12.0 },
        body: LensBody::Real {
            front_radius: 5.0,
            back_radius: -5.0,
            thickness: 3.0,
            index: 1.5,
        },
    };
    let worn = wear(&eye, &[ball]).unwrap();
    assert!(best_focus(&worn, 555.0, 0.0, &pupil, Criterion::MeanSphere).is_err());
    // Nor does it vouch for a ray count: where no probe forms a focus, the count is the
    // default, not the fewest tried.
    let probe = eyeshell_optics::Probe {
        system: &worn,
        pupil,
        wavelength_nm: 555.0,
        field_deg: 0.0,
    };
    let grin = eyeshell_optics::GrinSettings::default();
    assert_eq!(
        eyeshell_optics::rays_for(&[probe], Criterion::MeanSphere, grin, 1e-5),
        eyeshell_optics::FocusSettings::default().rays_across
    );
    assert!(wear(&eye, &[Lens::spectacle(-2.0, -3.0)]).is_err());
}

/// The pole's refraction table a growth run traces (every fifth dioptre, the rest filled by
/// the Möbius map of the lens's power and a cubic through the aberrations' part) against
/// every power traced: each power's focus within 1e-3 D (its distance over the focus's speed
/// per dioptre) over the whole ±25 D, and the refraction read from each within 1e-3 D, for
/// the default optics (3 mm pupil, mean sphere) and scenes/optics-age.toml's (1 mm pupil,
/// sagittal).
#[test]
fn sampled_refraction_tables_match_the_full_trace_to_a_thousandth_of_a_dioptre() {
    let eye = eyes::atchison_2006();
    let settings = FocusSettings::default();
    let mut worst: f64 = 0.0;
    for (diameter, criterion) in [(3.0, Criterion::MeanSphere), (1.0, Criterion::Sagittal)] {
        let pupil = Pupil {
            diameter,
            position: eye.pupil_position.unwrap(),
        };
        let full =
            RefractionTable::compute(&eye, 555.0, &pupil, criterion, &settings, 12.0).unwrap();
        let sampled =
            RefractionTable::compute_sampled(&eye, 555.0, &pupil, criterion, &settings, 12.0)
                .unwrap();
        assert_eq!(full.powers, sampled.powers);
        let n = full.powers.len();
        for k in 0..n {
            let speed = (full.foci[(k + 1).min(n - 1)] - full.foci[k.saturating_sub(1)])
                / (full.powers[(k + 1).min(n - 1)] - full.powers[k.saturating_sub(1)]);
            let error_d = ((sampled.foci[k] - full.foci[k]) / speed).abs();
            worst = worst.max(error_d);
            assert!(
                error_d < 1e-3,
                "{diameter} mm pupil, {criterion:?}, pole at {} D: {error_d} D",
                full.powers[k]
            );
        }
        // The refraction read from each, for retinas from −10 to +15 D.
        for retina in [20.5, 21.5, 22.5, 23.5, 24.5, 26.0] {
            let (a, b) = (
                full.refraction(retina).unwrap(),
                sampled.refraction(retina).unwrap(),
            );
            assert!((a - b).abs() < 1e-3, "retina {retina}: {a} D, {b} D");
        }
    }
    eprintln!("sampled against full refraction tables: worst {worst:.2e} D");
}

/// The ray count a run's traces use (`rays_for`): the fewest across the pupil whose foci agree
/// with twice as many to 1e-5 mm. Across the Atchison eye's 1 mm pupil (sagittal) 4 rays do,
/// and their foci lie within 1e-5 mm of 16 rays' at every field to 40° and behind the table's
/// strongest spectacle lenses; a 3 mm pupil (mean sphere) needs 6 (4 are off by about
/// 4e-4 mm); a zoned lens keeps the default 16 whatever the pupil.
#[test]
fn the_ray_count_is_the_fewest_that_agree_with_twice_as_many() {
    use eyeshell_optics::{best_focus_with, rays_for, GrinSettings, Probe};
    let eye = eyes::atchison_2006();
    let stop = eye.pupil_position.unwrap();
    let minus = wear(&eye, &[Lens::spectacle(-25.0, 12.0)]).unwrap();
    let plus = wear(&eye, &[Lens::spectacle(20.0, 12.0)]).unwrap();
    let probes = |diameter: f64| {
        let pupil = Pupil {
            diameter,
            position: stop,
        };
        let at = |system, wavelength_nm, field_deg| Probe {
            system,
            pupil,
            wavelength_nm,
            field_deg,
        };
        vec![
            at(&eye, 400.0, 0.0),
            at(&eye, 600.0, 40.0),
            at(&minus, 555.0, 0.0),
            at(&plus, 555.0, 40.0),
        ]
    };
    let grin = GrinSettings::default();
    let n = rays_for(&probes(1.0), Criterion::Sagittal, grin, 1e-5);
    assert_eq!(n, 4);
    assert_eq!(rays_for(&probes(3.0), Criterion::MeanSphere, grin, 1e-5), 6);
    let pupil = Pupil {
        diameter: 1.0,
        position: stop,
    };
    let mut worst: f64 = 0.0;
    for (system, wavelength) in [(&eye, 400.0), (&eye, 600.0), (&minus, 555.0)] {
        for field in [0.0, 10.0, 20.0, 30.0, 40.0] {
            let focus = |rays_across| {
                let s = FocusSettings { rays_across, grin };
                best_focus_with(system, wavelength, field, &pupil, Criterion::Sagittal, &s).unwrap()
            };
            let (a, b) = (focus(n), focus(16));
            let d = (a.z - b.z).hypot(a.r - b.r);
            worst = worst.max(d);
            assert!(d < 1e-5, "{wavelength} nm, {field}°: {d} mm");
        }
    }
    eprintln!("4 against 16 rays across a 1 mm pupil: worst {worst:.2e} mm");
    // A peripheral-plus design: the zone's edge may cross some field's pencil.
    let zoned = peripheral_plus(0.0, 2.5);
    let worn = wear(&eye, &[zoned]).unwrap();
    let probe = Probe {
        system: &worn,
        pupil,
        wavelength_nm: 555.0,
        field_deg: 0.0,
    };
    let default = FocusSettings::default().rays_across;
    assert_eq!(rays_for(&[probe], Criterion::Sagittal, grin, 1e-5), default);
}
