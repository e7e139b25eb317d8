//! A property test over the keys that describe an eye and its years: lenses (kinds, powers,
//! zones, tables, real lenses, several at once), the eye's surfaces as tables over time,
//! wavelengths, schedules, clocks, and sampled cohorts of them. Every generated scene is read
//! as a user's file would be, and each case must end in one of two ways:
//!
//! - refused: one line of at most 300 characters that names a scene key (and so never
//!   echoes a whole input), within a time bound, without a panic;
//! - accepted: then nothing the run will read lies, over the whole run t ∈ [0, growth.t_end]
//!   and not only at the tables' points: every surface of the eye keeps one sign and a
//!   radius of at least 0.5 mm, every thickness stays positive, every age of the clock is
//!   finite, the schedule's clock S(t_end) is finite and positive, the traced best-focus
//!   surfaces are finite at every time, and each built-in eye's power falls from the blue
//!   wavelength to the red one.
//!
//! A few of the cases also run the binary (`eyeshell grow` on 21 nodes): exit 0 with finite
//! series, or exit 2 with one line and nothing written. The cases are seeded (ChaCha) and
//! their counts fixed, so CI runs the same ones every time (a few seconds in release);
//! `EYESHELL_FUZZ_SCALE=N cargo test --release --test cli fuzz_eye` multiplies them.

use crate::fuzz_readers::runner;
use crate::support::*;
use eyeshell::model::eye::{EyeValue, RADIUS_RANGE};
use eyeshell::scene::sweep::Sweep;
use eyeshell::scene::{Scene, KEYS};
use proptest::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};

/// The bound on reading one scene (tracing its optics included).
const TIME_BOUND: Duration = Duration::from_secs(30);

fn float() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-50.0f64..50.0).prop_map(|x| format!("{x:?}")),
        2 => (0.0f64..3.0).prop_map(|x| format!("{x:?}")),
        1 => any::<f64>().prop_map(|x| format!("{x:?}")),
        2 => proptest::sample::select(vec![
            "nan", "inf", "-inf", "0", "-0.0", "1e308", "-1e308", "5e-324", "1e-300", "1",
            "-1", "2", "0.5", "100", "1e6",
        ])
        .prop_map(String::from),
    ]
}

fn floats(max: usize) -> impl Strategy<Value = String> {
    prop::collection::vec(float(), 0..max).prop_map(|v| format!("[{}]", v.join(", ")))
}

/// Increasing lists most of the time (the interesting cases pass the points' checks).
fn times(max: usize) -> impl Strategy<Value = Vec<f64>> {
    prop_oneof![
        4 => prop::collection::vec(0.01f64..1.0, 1..max).prop_map(|steps| {
            let mut t = 0.0;
            steps.iter().map(|s| { let x = t; t += s; x }).collect()
        }),
        1 => prop::collection::vec(-1.0f64..3.0, 0..max),
    ]
}

fn list(xs: &[f64]) -> String {
    format!(
        "[{}]",
        xs.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// A value near a surface key's own (radius, conic, thickness, index), fixed or a table.
fn surface_key() -> impl Strategy<Value = String> {
    let key = proptest::sample::select(vec!["radius", "conic", "thickness", "index"]);
    let near = |k: &str| -> (f64, f64) {
        match k {
            "radius" => (-12.0, 12.0),
            "conic" => (-6.0, 2.0),
            "thickness" => (-0.5, 8.0),
            _ => (1.2, 1.6),
        }
    };
    (
        key,
        0usize..5,
        times(6),
        prop::collection::vec(0.0f64..1.0, 6),
        float(),
        any::<bool>(),
    )
        .prop_map(move |(k, i, t, u, fixed, table)| {
            let (lo, hi) = near(k);
            let value = if table {
                let v: Vec<f64> = u.iter().take(t.len()).map(|u| lo + u * (hi - lo)).collect();
                format!("{{ t = {}, value = {} }}", list(&t), list(&v))
            } else {
                fixed
            };
            format!("optics.surfaces[{i}].{k}={value}")
        })
}

fn rows(max: usize) -> impl Strategy<Value = String> {
    prop_oneof![
        3 => prop::collection::vec((0.0f64..20.0, -5.0f64..5.0), 0..max).prop_map(|mut v| {
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            format!(
                "[{}]",
                v.iter()
                    .map(|(r, p)| format!("{{ radius = {r:?}, power = {p:?} }}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }),
        1 => prop::collection::vec((float(), float()), 0..max).prop_map(|v| {
            format!(
                "[{}]",
                v.iter()
                    .map(|(r, p)| format!("{{ radius = {r}, power = {p} }}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }),
    ]
}

fn lens() -> impl Strategy<Value = String> {
    let kind = proptest::sample::select(vec![
        None,
        Some("spectacle"),
        Some("contact"),
        Some("bifocal"),
    ]);
    let vertex = prop_oneof![3 => Just(None), 1 => float().prop_map(Some)];
    let profile = prop_oneof![
        3 => float().prop_map(|p| format!("power = {p}")),
        3 => rows(8).prop_map(|z| format!("zones = {z}")),
        3 => rows(8).prop_map(|z| format!("table = {z}")),
        1 => (float(), float(), float(), float()).prop_map(|(a, b, c, d)| format!(
            "front_radius = {a}, back_radius = {b}, thickness = {c}, index = {d}"
        )),
        1 => (float(), rows(3)).prop_map(|(p, z)| format!("power = {p}, zones = {z}")),
        1 => Just(String::new()),
    ];
    (kind, vertex, profile).prop_map(|(kind, vertex, profile)| {
        let mut parts = vec![];
        if let Some(k) = kind {
            parts.push(format!("kind = \"{k}\""));
        }
        if let Some(v) = vertex {
            parts.push(format!("vertex = {v}"));
        }
        if !profile.is_empty() {
            parts.push(profile);
        }
        format!("{{ {} }}", parts.join(", "))
    })
}

fn schedule() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        2 => Just(vec![]),
        1 => float().prop_map(|x| vec!["growth.schedule=\"exponential\"".into(), format!("growth.schedule_tau={x}")]),
        1 => (float(), float()).prop_map(|(c, w)| vec![
            "growth.schedule=\"logistic\"".into(),
            format!("growth.schedule_centre={c}"),
            format!("growth.schedule_width={w}"),
        ]),
        2 => (times(5), prop_oneof![3 => prop::collection::vec(0.0f64..2.0, 0..5).prop_map(|v| list(&v)), 1 => floats(5)])
            .prop_map(|(t, f)| vec![
                "growth.schedule=\"table\"".into(),
                format!("growth.schedule_times={}", list(&t)),
                format!("growth.schedule_factors={f}"),
            ]),
        1 => Just(vec!["growth.schedule=\"weekly\"".into()]),
    ]
}

fn clock() -> impl Strategy<Value = Vec<String>> {
    prop_oneof![
        3 => Just(vec![]),
        2 => (proptest::sample::select(vec!["years", "days", "none"]), float(), float())
            .prop_map(|(u, a, b)| vec![
                format!("time.unit=\"{u}\""),
                format!("time.start={a}"),
                format!("time.end={b}"),
            ]),
        1 => (0.0f64..10.0, 10.0f64..1e300).prop_map(|(a, b)| vec![
            "time.unit=\"years\"".into(),
            format!("time.start={a:?}"),
            format!("time.end={b:?}"),
        ]),
    ]
}

/// One scene as the `--set` list a user would give on top of the const scene's growth.
fn case() -> impl Strategy<Value = Vec<String>> {
    let optics = prop_oneof![
        1 => Just(vec![]),
        4 => (
            proptest::sample::select(vec!["atchison-2006", "liou-brennan-1997", "escudero-sanz-navarro-1999", "custom"]),
            proptest::sample::select(vec!["[400, 600]", "[450, 650]", "[600, 400]", "[400, 800]", "[300, 1200]", "[555, 555]", "[380, 750]", "[nan, 600]"]),
            proptest::sample::select(vec!["1", "3", "6", "0", "11"]),
            proptest::sample::select(vec!["5", "10", "10", "40", "80"]),
            prop::collection::vec(surface_key(), 0..3),
            prop_oneof![3 => Just(None), 2 => prop::collection::vec(lens(), 0..3).prop_map(Some)],
            proptest::sample::select(vec![None, Some("555"), Some("800"), Some("1e9")]),
        )
            .prop_map(|(eye, waves, pupil, field, surfaces, lenses, rw)| {
                let mut v = vec![
                    "stimulus.source=\"optics\"".to_string(),
                    format!("optics.eye=\"{eye}\""),
                    format!("optics.wavelengths={waves}"),
                    format!("optics.pupil={pupil}"),
                    format!("optics.max_field={field}"),
                ];
                v.extend(surfaces);
                if let Some(l) = lenses {
                    v.push(format!("optics.lenses=[{}]", l.join(", ")));
                }
                if let Some(w) = rw {
                    v.push(format!("optics.refraction_wavelength={w}"));
                }
                v
            }),
    ];
    let t_end = proptest::sample::select(vec![
        None,
        Some("2"),
        Some("0.5"),
        Some("1e-50"),
        Some("1e6"),
    ]);
    (optics, schedule(), clock(), t_end).prop_map(|(mut o, s, c, t)| {
        o.extend(s);
        o.extend(c);
        if let Some(t) = t {
            o.push(format!("growth.t_end={t}"));
        }
        o
    })
}

const BASE: &str = "growth.eta0 = 70\nsolver.nodes = 21\n";

/// A refusal's message: one line of at most 300 characters naming a key.
fn refusal(what: &str, msg: &str) -> Result<(), TestCaseError> {
    prop_assert!(!msg.is_empty() && !msg.contains('\n'), "{what}: {msg:?}");
    prop_assert!(
        msg.chars().count() <= 300,
        "{what}: {} characters: {msg}",
        msg.chars().count()
    );
    let names_key = KEYS.iter().any(|k| msg.contains(k.key))
        || ["optics.lenses", "optics.surfaces", "[sweep", "--set"]
            .iter()
            .any(|k| msg.contains(k));
    prop_assert!(names_key, "{what}: no key named: {msg}");
    Ok(())
}

/// What an accepted scene's run reads, checked over its whole run.
fn accepted(what: &str, scene: &Scene) -> Result<(), TestCaseError> {
    let Some(g) = &scene.growth else {
        return Ok(());
    };
    let t_end = g.t_end;
    let ts: Vec<f64> = (0..=64).map(|k| t_end * (k as f64 / 64.0)).collect();
    // The clock: every age finite.
    for &t in &ts {
        let a = g.clock.age(t);
        prop_assert!(a.is_finite(), "{what}: age {a} at t = {t}");
    }
    // The schedule: S(t_end) finite and positive.
    let warp = eyeshell::growth::schedule::Warp::new(&g.schedule, &g.clock);
    let tau = warp.clock(t_end);
    prop_assert!(tau.is_finite() && tau > 0.0, "{what}: S(t_end) = {tau}");
    if g.source != eyeshell::model::optics::Source::Optics {
        return Ok(());
    }
    let o = &g.optics;
    // The eye over the run, between and beyond its tables' points.
    for s in &o.surfaces {
        let table = |v: &Option<EyeValue>| v.clone().filter(|v| !v.times().is_empty());
        if let Some(r) = table(&s.radius) {
            let sign = r.at(0.0).signum();
            for &t in &ts {
                let x = r.at(t);
                prop_assert!(
                    x.signum() == sign && x.abs() >= RADIUS_RANGE.0,
                    "{what}: radius {x} at t = {t}"
                );
            }
        }
        if let Some(h) = table(&s.thickness) {
            for &t in &ts {
                prop_assert!(h.at(t) > 0.0, "{what}: thickness {} at t = {t}", h.at(t));
            }
        }
    }
    for &t in &ts {
        prop_assert!(o.system_at(t).is_ok(), "{what}: no eye at t = {t}");
    }
    // Blue before red, and each built-in eye's power falling from one to the other.
    let (blue, red) = (o.wavelengths[0], o.wavelengths[1]);
    prop_assert!(blue < red, "{what}: {blue} nm before {red} nm");
    if o.eye_name() != "custom" && o.surfaces.is_empty() {
        let eye = o.system().unwrap();
        let p = |w: f64| eyeshell_optics::paraxial(&eye, w).map(|p| p.power);
        if let (Ok(pb), Ok(pr)) = (p(blue), p(red)) {
            prop_assert!(pb > pr, "{what}: {pb} D at {blue} nm, {pr} D at {red} nm");
        }
    }
    // The traced surfaces at every time the run reads them.
    let c = g
        .computed
        .as_ref()
        .expect("a validated optics scene is traced");
    let finite = |s: &eyeshell_optics::PolarSpline| {
        (0..=20).all(|k| {
            let phi = s.phi_max() * k as f64 / 20.0;
            s.radius(phi).is_some_and(f64::is_finite)
        })
    };
    prop_assert!(
        finite(&c.blue) && finite(&c.red),
        "{what}: a traced surface is not finite"
    );
    if let Some(timed) = &c.timed {
        for &t in &ts {
            let (b, r) = timed
                .at(t)
                .map_err(|e| TestCaseError::fail(format!("{what}: {e}")))?;
            prop_assert!(
                finite(&b) && finite(&r),
                "{what}: the blend at t = {t} is not finite"
            );
        }
    }
    Ok(())
}

fn read(sets: &[String]) -> Result<(), TestCaseError> {
    let what = format!("{sets:?}");
    let start = Instant::now();
    let r = catch_unwind(AssertUnwindSafe(|| {
        Scene::from_toml_str(BASE, "fuzz.toml", sets)
    }))
    .map_err(|_| TestCaseError::fail(format!("{what}: panicked")))?;
    prop_assert!(
        start.elapsed() < TIME_BOUND,
        "{what}: took {:?}",
        start.elapsed()
    );
    match r {
        Err(e) => refusal(&what, &e.to_string()),
        Ok(scene) => accepted(&what, &scene),
    }
}

#[test]
fn fuzz_eye_scenes_never_lie() {
    runner(150, 41).run(&case(), |sets| read(&sets)).unwrap();
}

/// Sampled cohorts over the same keys: the sweep is refused in one short line naming the
/// key, or every eye is a scene whose run reads nothing that lies.
#[test]
fn fuzz_eye_sampled_cohorts_never_lie() {
    let dist = prop_oneof![
        (float(), float())
            .prop_map(|(m, s)| format!("{{ dist = \"normal\", mean = {m}, sd = {s} }}")),
        (float(), float())
            .prop_map(|(a, b)| format!("{{ dist = \"uniform\", low = {a}, high = {b} }}")),
        (float(), float())
            .prop_map(|(m, s)| format!("{{ dist = \"lognormal\", mean = {m}, sd = {s} }}")),
        floats(4).prop_map(|v| format!("{{ dist = \"empirical\", values = {v} }}")),
        Just("{ dist = \"cauchy\" }".to_string()),
    ];
    let key = proptest::sample::select(vec![
        "growth.schedule_tau",
        "growth.schedule_centre",
        "time.end",
        "time.start",
        "growth.t_end",
        "optics.pupil",
        "optics.max_field",
        "optics.refraction_wavelength",
    ]);
    let cohort = (
        prop::collection::vec((key, dist), 1..3),
        schedule(),
        clock(),
        any::<bool>(),
        2usize..5,
    );
    runner(60, 42)
        .run(&cohort, |(keys, sched, clock, optics, eyes)| {
            let mut text =
                format!("{BASE}[sweep.sample]\neyes = {eyes}\nseed = 3\n[sweep.sample.keys]\n");
            let mut keys = keys;
            keys.dedup_by(|a, b| a.0 == b.0);
            for (k, d) in &keys {
                text.push_str(&format!("\"{k}\" = {d}\n"));
            }
            let mut sets: Vec<String> = sched.into_iter().chain(clock).collect();
            if optics {
                sets.extend([
                    "stimulus.source=\"optics\"".into(),
                    "optics.pupil=1".into(),
                    "optics.max_field=10".into(),
                ]);
            }
            let what = format!("{text:?} {sets:?}");
            let start = Instant::now();
            let r = catch_unwind(AssertUnwindSafe(|| {
                Sweep::from_toml_str(&text, "fuzz.toml", &sets)
            }))
            .map_err(|_| TestCaseError::fail(format!("{what}: panicked")))?;
            prop_assert!(
                start.elapsed() < TIME_BOUND,
                "{what}: took {:?}",
                start.elapsed()
            );
            match r {
                Err(e) => refusal(&what, &e.to_string()),
                Ok(sweep) => {
                    for run in &sweep.runs {
                        accepted(&format!("{what} {}", run.name), &run.scene)?;
                    }
                    Ok(())
                }
            }
        })
        .unwrap();
}

/// The binary on some of the cases: `eyeshell grow` exits 0 with finite series, or 2 with
/// one line and nothing written (bounded in time and memory).
#[test]
fn fuzz_eye_runs_end_cleanly() {
    use proptest::strategy::ValueTree;
    let scale: usize = std::env::var("EYESHELL_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let strategy = case();
    let mut r = runner(1, 43);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), BASE).unwrap();
    for k in 0..4 * scale {
        let sets = strategy.new_tree(&mut r).unwrap().current();
        let out = format!("out{k}");
        let mut args = vec!["grow", "scene.toml", "--out", &out, "--quiet"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let what = format!("{sets:?}");
        let run = bounded(dir.path(), &args);
        match run.code {
            Some(0) => {
                let (header, rows) = csv_cells(&dir.path().join(&out).join("series.csv"));
                let j = header.iter().position(|h| h == "axial_length").unwrap();
                for row in rows {
                    let x: f64 = row[j].parse().unwrap();
                    assert!(x.is_finite(), "{what}: axial length {x}");
                }
            }
            Some(2) => {
                one_clean_line(&run, &what);
                assert!(
                    run.stderr.trim_end().chars().count() <= 300,
                    "{what}: {}",
                    run.stderr
                );
                assert!(!dir.path().join(&out).exists(), "{what}: {out} was written");
            }
            code => panic!("{what}: exit {code:?}: {}", run.stderr),
        }
    }
}
