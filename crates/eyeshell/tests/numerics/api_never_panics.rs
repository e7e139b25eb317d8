//! The facade never panics: every entry point (`Scene::set` and `FromStr` for every key,
//! `solve`, `grow`, `Solution::at` and `column`, `Scene::fit`, `Observations::from_columns`,
//! `set_sensitivities`) given NaN, ±inf, subnormal, zero and huge numbers returns a value or
//! an error. A panic would reach a Python caller as an abort of the interpreter, so it is
//! caught here and reported with the input that caused it.

use std::panic::{catch_unwind, AssertUnwindSafe};

use eyeshell::fit::{FitOptions, Observations};
use eyeshell::scene::keys::{Access, KEYS};
use eyeshell::Scene;
use proptest::prelude::*;

/// The numbers an adversary tries first, as TOML reads them.
const SPECIAL: &[&str] = &[
    "nan",
    "-nan",
    "inf",
    "-inf",
    "5e-324",
    "-5e-324",
    "2.2250738585072014e-308",
    "1e-300",
    "0",
    "-0.0",
    "-1",
    "1e300",
    "1.7976931348623157e308",
    "-1.7976931348623157e308",
    "4294967296",
    "9223372036854775807",
    "[nan]",
    "[inf, 1]",
    "[]",
];

const SPECIAL_F64: &[f64] = &[
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MIN_POSITIVE,
    5e-324,
    -5e-324,
    0.0,
    -0.0,
    1e-300,
    1e300,
    f64::MAX,
    f64::MIN,
];

/// Run `f`, turning a panic into a test failure that names `what`.
fn no_panic<T>(what: &str, f: impl FnOnce() -> T) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => v,
        Err(e) => {
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            panic!("{what} panicked: {msg}")
        }
    }
}

/// A small, quick scene: 31 nodes, every run bounded in time.
fn quick() -> Scene {
    let mut s = Scene::default_scene();
    s.set("solver.nodes", 31).unwrap();
    s.set("solver.max_seconds", 5).unwrap();
    s
}

fn is_numeric(access: &Access) -> bool {
    matches!(
        access,
        Access::Float { .. }
            | Access::Count { .. }
            | Access::OptionalFloat { .. }
            | Access::Floats { .. }
    )
}

/// Every numeric key set to every special number through `set` and through a scene file's
/// text; where the scene takes it, the scene is solved (and grown, for a growth key).
#[test]
fn every_key_with_every_special_number() {
    let mut accepted = 0;
    let mut refused = 0;
    for spec in KEYS.iter().filter(|k| is_numeric(&k.access)) {
        for value in SPECIAL {
            let what = format!("{} = {value}", spec.key);
            let mut scene = quick();
            let set = no_panic(&format!("Scene::set({what})"), || {
                scene.set(spec.key, value)
            });
            let (section, name) = spec.key.rsplit_once('.').unwrap_or(("", spec.key));
            let text = if section.is_empty() {
                format!("{name} = {value}\n")
            } else {
                format!("[{section}]\n{name} = {value}\n")
            };
            let parsed = no_panic(&format!("Scene::from_str({what})"), || {
                text.parse::<Scene>()
            });
            assert_eq!(
                set.is_ok(),
                parsed.is_ok(),
                "{what}: --set and a scene file disagree"
            );
            if set.is_err() {
                refused += 1;
                continue;
            }
            accepted += 1;
            // Only the keys of a quick run are solved: a legal but huge node count or
            // Newton budget is the absurd-input tests' business (tests/cli/absurd.rs).
            if spec.key.starts_with("solver.") || spec.key.starts_with("output.") {
                continue;
            }
            let solved = no_panic(&format!("solve with {what}"), || scene.solve());
            if let Ok(sol) = &solved {
                for x in SPECIAL_F64 {
                    let _ = no_panic(&format!("Solution::at({x}) with {what}"), || sol.at(*x));
                }
            }
            if scene.growth.is_some() {
                let _ = no_panic(&format!("grow with {what}"), || scene.grow(&mut ()));
            }
        }
    }
    // The test has a subject: both outcomes occur.
    assert!(
        accepted > 20 && refused > 100,
        "{accepted} accepted, {refused} refused"
    );
}

#[test]
fn fit_and_sensitivities_take_special_numbers() {
    let mut scene = quick();
    scene.set("growth.eta0", 70).unwrap();
    for x in SPECIAL_F64 {
        let data = no_panic(&format!("Observations::from_columns({x})"), || {
            Observations::from_columns(&[0.5, *x], &[20.0, *x], Some(&[0.1, x.abs()]), "special")
        });
        if !x.is_finite() {
            assert!(data.is_err(), "{x} taken as an observation");
        }
    }
    let data = Observations::from_columns(&[0.5, 1.0], &[20.5, 21.0], None, "data").unwrap();
    for (xtol, iters) in [(f64::NAN, 3), (f64::INFINITY, 3), (0.0, 0), (5e-324, 1)] {
        let options = FitOptions {
            max_iterations: iters,
            xtol,
            ftol: xtol,
            gtol: xtol,
            setol: xtol,
        };
        let _ = no_panic(&format!("fit with tolerances {xtol}"), || {
            scene.fit(&data, &["growth.Gamma"], &options)
        });
    }
    for keys in [
        &["growth.eta0", "growth.eta0"][..],
        &[""],
        &["nan"],
        &["growth."],
    ] {
        let _ = no_panic(&format!("set_sensitivities({keys:?})"), || {
            quick().set_sensitivities(keys, true)
        });
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any f64 at all, into the interpolant of a solved shell and into a key.
    #[test]
    fn any_number_into_at_and_set(x in any::<f64>(), k in 0..KEYS.len()) {
        let sol = quick().solve().unwrap();
        let _ = no_panic(&format!("Solution::at({x:e})"), || sol.at(x));
        let spec = &KEYS[k];
        let mut scene = quick();
        let _ = no_panic(&format!("Scene::set({}, {x:e})", spec.key), || {
            scene.set(spec.key, format!("{x:e}"))
        });
    }
}
