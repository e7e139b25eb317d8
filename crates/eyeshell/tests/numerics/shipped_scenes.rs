//! Every shipped scene (scenes/*.toml, every run of a sweep) solves from the default guess:
//! the scene files are the files crate's, so this stays beside it while the rest of the
//! solve's promises are core's (crates/core/tests/numerics/solve_features.rs).

use eyeshell::bvp;

/// Newton converges from the inflated reference sphere on every shipped scene, with no
/// continuation.
#[test]
fn every_shipped_scene_solves_from_the_default_guess() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        // A sweep is many scenes: every run's shell must solve too.
        let sweep = eyeshell::scene::sweep::Sweep::from_file(&path, &[]).unwrap();
        for run in &sweep.runs {
            let what = format!("{} run {}", path.display(), run.name);
            let sol = bvp::solve(&run.scene.params, &run.scene.solver, None)
                .unwrap_or_else(|e| panic!("{what}: {e}"));
            println!("{what}: {} Newton iterations", sol.stats.newton_iterations);
            assert_eq!(sol.stats.continuation_stages, 0, "{what}");
            assert!(sol.stats.newton_iterations <= 8, "{what}");
            count += 1;
        }
    }
    assert!(count >= 2, "no scenes found in {}", dir.display());
}
