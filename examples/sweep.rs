//! A small parameter study through the library: the loaded shell's equatorial radius for
//! four fibre stiffnesses D, run in parallel into run directories as `eyeshell sweep` would:
//! `cargo run --release --example sweep`.

use eyeshell::sweep::RunStatus;
use eyeshell::{Error, Sweep};

const SCENE: &str = r#"
name = "fibre-study"
[solver]
nodes = 101
[sweep.grid]
"fibres.D" = [0, 100, 200, 400]
"#;

fn main() -> Result<(), Error> {
    let sweep = Sweep::from_toml_str(SCENE, "fibre-study.toml", &[])?;
    let out = std::env::temp_dir().join(format!("eyeshell-example-sweep-{}", std::process::id()));
    let report = sweep.run(&out, 0, &|run, n, total| {
        println!("[{n}/{total}] {} {}", run.name, run.status_text());
    })?;
    for run in &report.records {
        assert_eq!(run.status, RunStatus::Ok, "{}", run.name);
        let result = run.result.as_ref().expect("a finished run has a result");
        println!(
            "{:<12} equatorial radius {:.6} mm",
            run.name,
            result.eye.number("equatorial_radius")
        );
    }
    println!("runs, sweep.csv and summary.json are in {}", out.display());
    std::fs::remove_dir_all(&out).map_err(|source| Error::Io { path: out, source })?;
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
