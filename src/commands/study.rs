//! `eyeshell converge`, `wpd`, `refinement` and `extremes`: studies written all at once.

use eyeshell::rundir::summary::StudySummary;
use eyeshell::rundir::{self, OutputDir, Summary};
use eyeshell::Error;

use crate::args::{ConvergeArgs, ExtremesArgs};
use crate::out;

pub(crate) fn cmd_extremes(a: &ExtremesArgs) -> Result<(), Error> {
    use crate::study::extremes;
    let ours = |p: &std::path::Path| extremes::wrote(&rundir::owner::head(p, 256));
    rundir::check_file(&a.out, a.force, ours)?;
    let results: Vec<_> = extremes::cases()
        .into_iter()
        .map(|c| {
            let o = extremes::run(&c);
            (c, o)
        })
        .collect();
    // The file may have changed during the cases: check again, and keep its tail.
    rundir::check_file(&a.out, a.force, ours)?;
    let previous = std::fs::read_to_string(&a.out).ok();
    let text = extremes::document(&extremes::table(&results), previous.as_deref());
    rundir::write_atomic(&a.out, text.as_bytes()).map_err(|e| {
        Error::failed(eyeshell::Stage::File, format!("{}: {e}", a.out.display())).with_source(e)
    })?;
    out(&format!(
        "eyeshell: {} cases written to {}\n",
        results.len(),
        crate::shown(&a.out)
    ));
    Ok(())
}

pub(crate) fn cmd_converge(a: &ConvergeArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let max = eyeshell::mesh::MAX_NODES;
    if a.nodes.len() < 2 || a.nodes.iter().any(|&n| !(5..=max).contains(&n)) {
        return Err(Error::input(
            eyeshell::Subject::Argument("--nodes".into()),
            format!(
                "--nodes {}: give at least two counts, each from 5 to {max}",
                a.nodes
                    .iter()
                    .map(|n| n.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            ),
        ));
    }
    if a.growth && scene.growth.is_none() {
        return Err(Error::input(
            eyeshell::Subject::Argument("--growth".into()),
            format!(
                "{}: --growth needs a scene with a [growth] section",
                scene.origin
            ),
        )
        .with_origin(eyeshell::Origin::Scene(scene.origin.clone())));
    }
    cmd_study(&a.out, "converge", &[a.scene.scene.as_path()], |dir| {
        crate::study::report::converge(&scene, &a.nodes, a.growth, dir)
    })
}

/// Run a study into an output directory written all at once; print its summary.
pub(crate) fn cmd_study(
    out_dir: &std::path::Path,
    name: &str,
    inputs: &[&std::path::Path],
    study: impl FnOnce(&std::path::Path) -> Result<String, crate::study::StudyError>,
) -> Result<(), Error> {
    let dir = OutputDir::create(out_dir, "study", inputs)?;
    let text = study(&dir.file(""))?;
    Summary::Study(StudySummary {
        study: name.to_string(),
        sundials_version: rundir::sundials_version(),
        report: text.clone(),
    })
    .write_to(&dir.file(rundir::SUMMARY_FILE))
    .map_err(|e| Error::failed_by(eyeshell::Stage::File, e))?;
    let target = dir.commit()?;
    out(&format!(
        "eyeshell: {name} written to {}\n{text}",
        crate::shown(&target)
    ));
    Ok(())
}
