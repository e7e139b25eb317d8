//! The scene is checked against the plan of what a run writes (crates/eyeshell/src/plan.rs),
//! which the run directory's writer follows: the scene names nothing of the writer, so the
//! two modules do not depend on each other in a cycle (rundir reads scenes; scenes read no
//! run directory).

use std::path::Path;

use crate::support::repo;

/// The lines of the `.rs` files under `dir` (recursively) that name `what` outside comments.
fn naming(dir: &Path, what: &str, out: &mut Vec<String>) {
    for entry in std::fs::read_dir(dir)
        .expect("the scene's sources")
        .flatten()
    {
        let path = entry.path();
        if path.is_dir() {
            naming(&path, what, out);
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            if code.contains(what) {
                out.push(format!("{}:{}: {}", path.display(), i + 1, line.trim()));
            }
        }
    }
}

#[test]
fn the_scene_names_no_run_directory() {
    let scene = repo().join("crates/eyeshell/src/scene");
    let mut found = vec![];
    naming(&scene, "rundir", &mut found);
    assert!(
        found.is_empty(),
        "the scene takes the run directory's module:\n{}",
        found.join("\n")
    );
    // The search reads the sources: the scene's validation does take the plan.
    let mut plan = vec![];
    naming(&scene, "crate::plan", &mut plan);
    assert!(
        !plan.is_empty(),
        "no use of crate::plan found under {}",
        scene.display()
    );
}
