//! The bvp4c-style peer (`benches/peers/solve_bvp_fibre.py`): SciPy's solve_bvp,
//! split at the breakpoints, and eyeshell at N = 801 on the non-uniform fibre shell (D = 200)
//! reach the same solution, each within 1e-9 of eyeshell at N = 12801 relative to every
//! field's size. The times are BENCHMARKS.md's; here only the numbers that must hold. Runs
//! only where `python3 -c 'import scipy'` works (.ci/run installs scipy); elsewhere it
//! says SKIPPED, and with `EYESHELL_REQUIRE_SCIPY=1` (set by .ci/run) it fails instead.

use crate::support::scipy_available;
use std::process::Command;

#[test]
fn solve_bvp_and_eyeshell_agree_on_the_fibre_shell() {
    if !scipy_available("the solve_bvp peer") {
        return;
    }
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/peers/solve_bvp_fibre.py"
    );
    let out = Command::new("python3")
        .args([
            script,
            "--eyeshell",
            env!("CARGO_BIN_EXE_eyeshell"),
            "--nodes",
            "801",
        ])
        .args(["--repeats", "1", "--scipy-repeats", "1", "--json"])
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "the peer script failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    let relative = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    // The reference itself: N = 12801 against 25601.
    let reference = relative(&report["reference_vs_finer"]);
    assert!(reference.iter().all(|&e| e < 1e-10), "{reference:?}");
    let runs = report["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for run in runs {
        let errors = relative(&run["relative"]);
        assert_eq!(errors.len(), 5, "κ, α_s, r, θ, Q");
        assert!(
            errors.iter().all(|&e| e <= 1e-9 && e > 0.0),
            "{}: relative errors {errors:?}",
            run["name"]
        );
    }
}

/// The switch that keeps CI honest: the peer test, run again in a child process whose
/// `python3` cannot import SciPy, says SKIPPED and passes by default, and fails with
/// `EYESHELL_REQUIRE_SCIPY=1`. Without this, a machine that lost SciPy would pass every
/// comparison against it without making one.
#[test]
fn a_missing_scipy_fails_the_peer_test_when_scipy_is_required() {
    let bin = tempfile::tempdir().unwrap();
    let python = bin.path().join("python3");
    std::fs::write(
        &python,
        "#!/bin/sh\necho 'No module named scipy' >&2\nexit 1\n",
    )
    .unwrap();
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&python, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let peer = |require: Option<&str>| {
        let mut child = Command::new(std::env::current_exe().unwrap());
        child
            .args([
                "peer::solve_bvp_and_eyeshell_agree_on_the_fibre_shell",
                "--exact",
                "--nocapture",
                "--test-threads=1",
            ])
            .env("PATH", bin.path())
            .env_remove("EYESHELL_REQUIRE_SCIPY");
        if let Some(v) = require {
            child.env("EYESHELL_REQUIRE_SCIPY", v);
        }
        let out = child.output().expect("the test binary runs again");
        let text = String::from_utf8_lossy(&out.stdout).into_owned()
            + &String::from_utf8_lossy(&out.stderr);
        (out.status.success(), text)
    };
    let (passed, text) = peer(None);
    assert!(passed, "without the switch the test skips: {text}");
    assert!(text.contains("SKIPPED: the solve_bvp peer"), "{text}");
    assert!(
        text.contains("1 passed"),
        "the peer test ran (and skipped): {text}"
    );
    let (passed, text) = peer(Some("1"));
    assert!(
        !passed,
        "with EYESHELL_REQUIRE_SCIPY=1 a missing SciPy fails: {text}"
    );
    assert!(
        text.contains("needs python3 with scipy and numpy, and EYESHELL_REQUIRE_SCIPY=1"),
        "{text}"
    );
    assert!(text.contains("1 failed"), "{text}");
}
