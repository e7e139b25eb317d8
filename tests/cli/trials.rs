//! The trial study of docs/guide/trials.md: `python3 examples/trials/study.py` (a joint fit
//! of Chamberlain 2019's two arms, Lam 2020's arms predicted) prints the tables the guide
//! shows, number for number, and refuses an output directory that exists.

use crate::support::*;
use std::process::Command;

/// The guide's text block after the study's command.
fn shown_tables() -> String {
    let guide = std::fs::read_to_string(repo().join("docs/guide/trials.md")).unwrap();
    let after = guide
        .split("python3 examples/trials/study.py --out out/trials\n```\n")
        .nth(1)
        .expect("the study's command in docs/guide/trials.md");
    let body = after
        .trim_start()
        .strip_prefix("```text\n")
        .expect("its text block");
    body.split("\n```").next().unwrap().to_string()
}

fn study(out: &std::path::Path) -> std::process::Output {
    Command::new("python3")
        .arg(repo().join("examples/trials/study.py"))
        .args([
            "--eyeshell",
            env!("CARGO_BIN_EXE_eyeshell"),
            "--out",
            s(out),
        ])
        .output()
        .expect("python3")
}

#[test]
fn the_trial_study_prints_the_guides_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("trials");
    let r = study(&out);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let lines = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            .collect()
    };
    assert_eq!(
        lines(stdout.trim_end()),
        lines(shown_tables().trim_end()),
        "{stdout}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("study.md")).unwrap(),
        stdout
    );
    for fitted in ["integrated/fit/fit.json", "integrated/fit/residuals.csv"] {
        assert!(out.join(fitted).is_file(), "{fitted}");
    }
    // A directory that exists is refused, and left as it was.
    let again = study(&out);
    assert_eq!(again.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&again.stderr).contains("exists: give a new directory"));
    assert_eq!(
        std::fs::read_to_string(out.join("study.md")).unwrap(),
        stdout
    );
}
