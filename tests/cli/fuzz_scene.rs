//! Random TOML documents and random `--set` values never make the scene parser panic: every
//! call returns Ok or an error whose message is one non-empty line, and a scene that parses
//! validates (Ok or a one-line error) without panicking.

use eyeshell::scene::{Scene, KEYS};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::process::Command;

fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

fn one_line(what: &str, msg: &str) -> Result<(), TestCaseError> {
    prop_assert!(!msg.is_empty(), "{what}: empty message");
    prop_assert!(
        !msg.contains('\n') && !msg.contains('\r'),
        "{what}: message not one line: {msg:?}"
    );
    Ok(())
}

/// Parse, and check the outcome: no panic, one-line errors, validate on success.
fn parse(text: &str, overrides: &[String]) -> Result<(), TestCaseError> {
    let what = format!("{text:?} with {overrides:?}");
    let r = std::panic::catch_unwind(|| Scene::from_toml_str(text, "fuzz", overrides));
    let r = r.map_err(|_| TestCaseError::fail(format!("{what}: parser panicked")))?;
    match r {
        Err(e) => one_line(&what, &e.to_string())?,
        Ok(scene) => {
            let v = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| scene.validate()));
            match v.map_err(|_| TestCaseError::fail(format!("{what}: validate panicked")))? {
                Ok(()) => {}
                Err(e) => one_line(&what, &e.to_string())?,
            }
        }
    }
    Ok(())
}

fn key_name() -> impl Strategy<Value = String> {
    let known: Vec<String> = KEYS.iter().map(|k| k.key.to_string()).collect();
    prop_oneof![
        4 => proptest::sample::select(known),
        1 => "[a-zA-Z_.]{0,12}",
        1 => "[a-z]{1,6}(\\.[a-z]{0,6}){0,5}",
        1 => any::<String>(),
    ]
}

fn scalar() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<i64>().prop_map(|i| i.to_string()),
        any::<f64>().prop_map(|x| format!("{x:?}")),
        proptest::sample::select(vec![
            "nan",
            "+nan",
            "-nan",
            "inf",
            "-inf",
            "+inf",
            "-0.0",
            "0.0",
            "1e308",
            "1.8e308",
            "-1e308",
            "5e-324",
            "0",
            "-1",
            "2",
            "1e-300",
            "0x10",
            "0o7",
            "0b1",
            "1_000",
            "true",
            "false",
            "\"\"",
            "\"trapezoid\"",
            "\"hermite-simpson\"",
            "\"klu\"",
            "\"band\"",
            "\"uniform\"",
            "\"nonuniform\"",
            "'lit'",
            "\"\\u00e9\\n\"",
            "1979-05-27",
            "07:32:00",
            "1979-05-27T07:32:00Z",
            "1979-05-27T07:32:00",
            "[]",
            "{}",
        ])
        .prop_map(str::to_string),
        "\"[^\"\\\\\\n]{0,10}\"",
    ]
}

fn value() -> impl Strategy<Value = String> {
    scalar().prop_recursive(2, 8, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..4).prop_map(|v| format!("[{}]", v.join(", "))),
            prop::collection::vec(("[a-zA-Z_]{1,6}", inner), 0..3).prop_map(|v| format!(
                "{{ {} }}",
                v.iter()
                    .map(|(k, x)| format!("{k} = {x}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        ]
    })
}

/// A TOML key as it may be written: bare when it can be, else quoted.
fn toml_key(k: &str) -> String {
    if !k.is_empty()
        && k.split('.').all(|p| {
            !p.is_empty()
                && p.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        })
    {
        k.to_string()
    } else {
        format!("{:?}", k)
    }
}

/// A document of random `key = value` lines, some under `[section]` headers.
fn document() -> impl Strategy<Value = String> {
    prop::collection::vec((key_name(), value(), 0u8..4), 0..8).prop_map(|lines| {
        let mut out = String::new();
        for (key, value, how) in lines {
            match (how, key.split_once('.')) {
                (0, Some((section, rest))) => out.push_str(&format!(
                    "[{}]\n{} = {value}\n",
                    toml_key(section),
                    toml_key(rest)
                )),
                (1, _) => out.push_str(&format!("{key} = {value}\n")), // raw, maybe invalid
                _ => out.push_str(&format!("{} = {value}\n", toml_key(&key))),
            }
        }
        out
    })
}

fn set_text() -> impl Strategy<Value = String> {
    prop_oneof![
        (key_name(), value()).prop_map(|(k, v)| format!("{k}={v}")),
        (key_name(), any::<String>()).prop_map(|(k, v)| format!("{k}={v}")),
        key_name(),                            // no '='
        value().prop_map(|v| format!("={v}")), // empty key
        ("[a-z]{0,4}(\\.[a-z]{0,4}){0,8}", value()).prop_map(|(k, v)| format!("{k}={v}")),
        any::<String>(),
    ]
}

#[test]
fn arbitrary_text_never_panics() {
    runner(1000, 1)
        .run(&any::<String>(), |text| parse(&text, &[]))
        .unwrap();
}

#[test]
fn structured_documents_never_panic() {
    runner(1000, 2)
        .run(&document(), |text| parse(&text, &[]))
        .unwrap();
}

#[test]
fn set_overrides_never_panic() {
    runner(1000, 3)
        .run(&prop::collection::vec(set_text(), 1..4), |sets| {
            parse("", &sets)
        })
        .unwrap();
}

#[test]
fn documents_with_overrides_never_panic() {
    runner(500, 4)
        .run(
            &(document(), prop::collection::vec(set_text(), 0..3)),
            |(text, sets)| parse(&text, &sets),
        )
        .unwrap();
}

#[test]
fn binary_check_fails_cleanly_on_random_sets() {
    use proptest::strategy::ValueTree;
    let strategy = set_text();
    let mut runner = runner(1, 5);
    let mut sets: Vec<String> = (0..8)
        .map(|_| strategy.new_tree(&mut runner).unwrap().current())
        .filter(|s| !s.contains('\0')) // not passable as a process argument
        .collect();
    sets.extend(
        [
            "pressure.dP",
            "=1",
            "pressure.dP=nan",
            "solver.nodes=1e308",
            "a.b.c.d.e=1",
            "material.C=[1,2]",
        ]
        .map(String::from),
    );
    for set in &sets {
        let out = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
            .args(["check", "scenes/default.toml", "--set", set])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("CI", "1")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let code = out.status.code();
        assert!(
            matches!(code, Some(0 | 2)),
            "--set {set:?}: exit {code:?}, stderr {stderr}"
        );
        assert!(!stderr.contains("panicked"), "--set {set:?}: {stderr}");
        if code == Some(2) {
            assert_eq!(
                stderr.lines().count(),
                1,
                "--set {set:?}: stderr not one line: {stderr:?}"
            );
        }
    }
}
