//! `eyeshell sweep`, `figures` and `plot`: many runs, and pictures of runs.

use std::io::Write;

use eyeshell::rundir;
use eyeshell::Error;

use crate::args::{FiguresArgs, PlotArgs, SweepArgs};
use crate::{out, plural};

/// Raised by the first Ctrl-C during a sweep: no new run starts.
/// The most runs at once: each is a thread with its own solver; beyond this a typo
/// (--jobs 100000) would spend seconds spawning threads before any run starts.
const MAX_JOBS: usize = 1024;

/// `--jobs`: absent (one per core) or 1 to [`MAX_JOBS`].
fn check_jobs(jobs: Option<usize>) -> Result<(), Error> {
    match jobs {
        Some(n) if n == 0 || n > MAX_JOBS => Err(Error::input(
            eyeshell::Subject::Argument("--jobs".into()),
            format!("--jobs {n}: give 1 to {MAX_JOBS} (or leave it out: one per core)"),
        )
        .with_value(n)
        .with_origin(eyeshell::Origin::Argument)),
        _ => Ok(()),
    }
}

pub(crate) static CANCEL: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// A first Ctrl-C stops new runs (the running ones finish and the table is written); a
/// second one exits at once.
pub(crate) fn install_interrupt() {
    use std::sync::atomic::Ordering;
    let _ = ctrlc::set_handler(|| {
        if CANCEL.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        let _ = writeln!(
            std::io::stderr(),
            "eyeshell: interrupted: finishing the running runs (Ctrl-C again to stop at once)"
        );
    });
}

pub(crate) fn cmd_sweep(a: &SweepArgs) -> Result<(), Error> {
    use eyeshell::sweep::{run_shard, run_sweep, SweepOptions};
    if let Some(action) = &a.action {
        return super::shards::cmd_sweep_dir(action);
    }
    // clap requires both without a subcommand.
    let (Some(scene), Some(out_dir)) = (&a.scene, &a.out) else {
        return Err(Error::input(
            eyeshell::Subject::Argument("--out".into()),
            "sweep: give SCENE.toml and --out DIR",
        ));
    };
    check_jobs(a.jobs)?;
    let shard = shard_of(a.shard.as_deref())?;
    // A shard, or the script of a sharded sweep, plans the runs without building them all
    // (up to MAX_PLANNED_RUNS); a plain sweep builds every run (up to MAX_RUNS).
    let plan = match shard.is_some() || a.slurm_script {
        true => Some(eyeshell::scene::sweep::SweepPlan::from_file(scene, &a.set)?),
        false => None,
    };
    if a.slurm_script {
        let plan = plan.as_ref().expect("planned above");
        return super::shards::print_slurm_script(a, plan, scene, out_dir);
    }
    let sweep = match plan {
        Some(_) => None,
        None => Some(eyeshell::scene::sweep::Sweep::from_file(scene, &a.set)?),
    };
    // A shard's directory is checked by `prepare_shard`, which waits out a shard started
    // beside it that is writing the marker; checked here, that moment was refused.
    // A resumed sweep keeps what is there (its own checks follow); a fresh one replaces
    // only an earlier sweep, and never the directory its scene file is in.
    if shard.is_none() {
        match a.resume {
            true => rundir::owner::inspect(&rundir::owner::normalise(out_dir)).map(|_| ())?,
            false => rundir::check_target(out_dir, "sweep", &[scene.as_path()])?,
        }
    }
    install_interrupt();
    // Each run in a worker process: one that aborts fails alone (src/worker).
    let workers = crate::worker::Workers::new(out_dir)?;
    let options = SweepOptions {
        jobs: a.jobs.unwrap_or(0),
        resume: a.resume,
        cancel: &CANCEL,
        runner: &workers,
        inputs: &[scene.as_path()],
    };
    let quiet = a.quiet;
    let progress = |r: &eyeshell::sweep::RunRecord, n: usize, total: usize| {
        if quiet {
            return;
        }
        let _ = writeln!(
            std::io::stderr(),
            "eyeshell: [{n}/{total}] {} {}",
            r.name,
            r.status_text()
        );
    };
    let head: eyeshell::sweep::Head = match (&plan, &sweep) {
        (Some(plan), _) => plan.into(),
        (_, Some(sweep)) => sweep.into(),
        _ => unreachable!("a shard has a plan, a plain sweep its runs"),
    };
    let report = match (shard, &plan, &sweep) {
        (Some(shard), Some(plan), _) => run_shard(plan, out_dir, shard, &options, &progress)?,
        (_, _, Some(sweep)) => run_sweep(sweep, out_dir, &options, &progress)?,
        _ => unreachable!("a shard has a plan, a plain sweep its runs"),
    };
    // A sampled sweep's figure, once population.json is there (failed eyes or not).
    let figure = match (shard, report.interrupted) {
        (None, false) => crate::charts::population_figure(out_dir, &report.records)?,
        _ => None,
    };
    report_sweep(a, shard, &head, out_dir, &report, figure.as_deref())
}

/// `--shard`: none, `slurm` (the task's shard from Slurm's variables) or K/N.
fn shard_of(text: Option<&str>) -> Result<Option<eyeshell::sweep::Shard>, Error> {
    use eyeshell::sweep::Shard;
    Ok(match text {
        None => None,
        Some("slurm") => {
            Some(Shard::from_slurm(|name| std::env::var(name).ok()).map_err(Error::from)?)
        }
        Some(text) => Some(Shard::parse(text).map_err(Error::from)?),
    })
}

/// How a sweep (or a shard of one) ended: an error naming the runs that failed or were
/// left by an interruption, with where the other results are; else, unless `--quiet`,
/// the lines naming its table (or the shard's record) and figures.
fn report_sweep(
    a: &SweepArgs,
    shard: Option<eyeshell::sweep::Shard>,
    head: &eyeshell::sweep::Head<'_>,
    out_dir: &std::path::Path,
    report: &eyeshell::sweep::SweepReport,
    figure: Option<&std::path::Path>,
) -> Result<(), Error> {
    use eyeshell::sweep::RunStatus;
    // Where the results are: the table, or the shard's record.
    let (table, shard_text, again) = match shard {
        Some(s) => (
            out_dir
                .join(eyeshell::sweep::SHARDS_DIR)
                .join(s.file_name()),
            format!(" shard {s}"),
            format!(" --shard {s}"),
        ),
        None => (
            out_dir.join(eyeshell::sweep::TABLE_FILE),
            String::new(),
            String::new(),
        ),
    };
    let failed: Vec<String> = report
        .failed()
        .map(|r| match r.status.message_line() {
            Some(m) => format!("{}: {m}", r.name),
            None => r.name.clone(),
        })
        .collect();
    let finished = report
        .records
        .iter()
        .filter(|r| matches!(r.status, RunStatus::Ok | RunStatus::Reused))
        .count();
    let total = report.records.len();
    if report.interrupted {
        return Err(Error::failed(eyeshell::Stage::Sweep, format!(
            "sweep{shard_text} interrupted: {finished} of {total} runs finished ({}: {}); run again with --resume{again} to do the rest",
            if shard.is_some() { "record" } else { "table" },
            table.display()
        )));
    }
    if !failed.is_empty() {
        return Err(Error::failed(
            eyeshell::Stage::Sweep,
            format!(
                "{} of {total} runs{shard_text} failed: {} (the other results are in {})",
                failed.len(),
                first_few(&failed),
                table.display()
            ),
        ));
    }
    if !a.quiet {
        let reused = report
            .records
            .iter()
            .filter(|r| r.status == RunStatus::Reused)
            .count();
        let reused = if reused > 0 {
            format!(" ({reused} reused from the earlier sweep)")
        } else {
            String::new()
        };
        let mut text = format!(
            "eyeshell: sweep {} ({}){shard_text}: {total} run{} ok{reused}\n",
            head.origin,
            eyeshell::text::one_line(head.name),
            plural(total),
        );
        match shard {
            Some(_) => text.push_str(&format!(
                "  record          {}\n  once every shard has run: eyeshell sweep merge {}\n",
                crate::shown(&table),
                crate::shell::word(out_dir)
            )),
            None => {
                text.push_str(&format!("  table           {}\n", crate::shown(&table)));
                text.push_str(&population_lines(head, out_dir));
                if let Some(png) = figure {
                    text.push_str(&format!("  figure          {}\n", crate::shown(png)));
                }
            }
        }
        out(&text);
    }
    Ok(())
}

/// The lines naming a sampled sweep's population files ("" for another sweep).
pub(crate) fn population_lines(head: &eyeshell::sweep::Head<'_>, dir: &std::path::Path) -> String {
    use eyeshell::sweep::population::{POPULATION_FILE, POPULATION_TABLE, SOBOL_TABLE};
    let Some(sample) = head.sample else {
        return String::new();
    };
    let mut text = format!(
        "  population      {}\n  table           {}\n",
        crate::shown(&dir.join(POPULATION_FILE)),
        crate::shown(&dir.join(POPULATION_TABLE))
    );
    if sample.design == eyeshell::scene::sample::Design::Saltelli {
        text.push_str(&format!(
            "  sobol indices   {}\n",
            crate::shown(&dir.join(SOBOL_TABLE))
        ));
    }
    // What the statistics could not include (eyes without refraction_D, eyes not classed,
    // unreliable indices) is said here as well as in population.json, never only there.
    let notes = std::fs::read_to_string(dir.join(POPULATION_FILE))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("notes").and_then(|n| n.as_array()).cloned())
        .unwrap_or_default();
    for note in notes.iter().filter_map(|n| n.as_str()) {
        text.push_str(&format!(
            "  note            {}\n",
            eyeshell::text::one_line(note)
        ));
    }
    text
}

/// The first [`SHOWN_FAILURES`] of `failed`, then how many more: the error line stays
/// short however many runs failed (the table has every message).
fn first_few(failed: &[String]) -> String {
    let mut text = failed[..failed.len().min(SHOWN_FAILURES)].join("; ");
    if failed.len() > SHOWN_FAILURES {
        text.push_str(&format!("; and {} more", failed.len() - SHOWN_FAILURES));
    }
    text
}

/// Failed runs named in the error line of a sweep.
const SHOWN_FAILURES: usize = 3;

pub(crate) fn cmd_figures(a: &FiguresArgs) -> Result<(), Error> {
    check_jobs(a.jobs)?;
    install_interrupt();
    let quiet = a.quiet;
    let start = std::time::Instant::now();
    let figures =
        crate::study::figures::make(&a.out, a.jobs.unwrap_or(0), a.replot, &CANCEL, &|line| {
            if !quiet {
                let _ = writeln!(std::io::stderr(), "eyeshell: {line}");
            }
        })?;
    if !a.quiet {
        let mut text = format!(
            "eyeshell: {} figures in {:.1} s\n",
            figures.len(),
            start.elapsed().as_secs_f64()
        );
        for f in &figures {
            text.push_str(&format!(
                "  ({}) {:<50} {}\n",
                f.id,
                f.title,
                crate::shown(&f.png)
            ));
        }
        text.push_str(&format!(
            "  index           {}\n",
            crate::shown(&a.out.join(crate::study::figures::INDEX_FILE))
        ));
        out(&text);
    }
    Ok(())
}

pub(crate) fn cmd_plot(a: &PlotArgs) -> Result<(), Error> {
    use crate::charts::{plot_compare, plot_run};
    let target = match (&a.out, a.dirs.as_slice()) {
        (Some(out), _) => out.clone(),
        (None, [dir]) => dir.join("plots"),
        (None, _) => {
            return Err(Error::input(
                eyeshell::Subject::Argument("--out".into()),
                format!(
                    "plot: {} runs are drawn together into one directory: give it with --out OUT",
                    a.dirs.len()
                ),
            ))
        }
    };
    // Drawn into a temporary directory and moved into place whole, with its marker: only an
    // empty directory or an earlier plot is replaced, never a run or sweep it is drawn
    // from, nor a directory that holds one.
    let inputs: Vec<&std::path::Path> = a.dirs.iter().map(|d| d.as_path()).collect();
    let dir = rundir::OutputDir::create(&target, "plot", &inputs)?;
    let files = match a.dirs.as_slice() {
        [one] => plot_run(one, &dir.file(""))?,
        several => plot_compare(several, &dir.file(""))?,
    };
    let target = dir.commit()?;
    if !a.quiet {
        let from = match a.dirs.as_slice() {
            [one] => crate::shown(one),
            several => format!("{} runs", several.len()),
        };
        out(&format!(
            "eyeshell: {} files drawn from {from} into {}\n",
            files.len(),
            crate::shown(&target)
        ));
    }
    Ok(())
}
