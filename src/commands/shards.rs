//! A sweep beyond one process: `eyeshell sweep merge|status DIR` (the table of a sharded
//! sweep) and `eyeshell sweep SCENE --out DIR --slurm-script` (an sbatch job array, one
//! shard per task). The shards themselves are `eyeshell sweep --shard` (sweep.rs).

use std::os::unix::ffi::OsStrExt;
use std::path::Path;

use eyeshell::scene::sweep::{SweepPlan, MAX_RUNS};
use eyeshell::sweep::{RunStatus, TABLE_FILE};
use eyeshell::Error;

use crate::args::{SweepAction, SweepArgs};
use crate::{out, shell};

/// Runs named on a line of the merge's report before "and N more".
const SHOWN: usize = 5;
/// The default number of shards of a generated script: one per run, at most this many.
const DEFAULT_SHARDS: usize = 100;

/// `eyeshell sweep merge DIR` (writes sweep.csv and summary.json) and `status DIR`
/// (writes nothing): what the shards did, and how to finish what they did not.
pub(crate) fn cmd_sweep_dir(action: &SweepAction) -> Result<(), Error> {
    let (args, write) = match action {
        SweepAction::Merge(a) => (a, true),
        SweepAction::Status(a) => (a, false),
    };
    let dir = &args.dir;
    let merged = eyeshell::sweep::merge(dir, write)?;
    let records = &merged.report.records;
    let total = records.len();
    let ok = records.iter().filter(|r| r.status == RunStatus::Ok).count();
    let failed: Vec<String> = merged
        .report
        .failed()
        .map(|r| match r.status.message_line() {
            Some(m) => format!("{}: {m}", r.name),
            None => r.name.clone(),
        })
        .collect();
    let missing: Vec<String> = merged
        .missing()
        .map(|r| match merged.stale.iter().find(|(n, _)| n == &r.name) {
            Some((_, why)) => format!(
                "{} (its results cannot be trusted: {})",
                r.name,
                eyeshell::text::excerpt(why, eyeshell::sweep::SHOWN_MESSAGE)
            ),
            None => r.name.clone(),
        })
        .collect();
    let shards: Vec<String> = merged
        .records
        .iter()
        .map(|r| format!("{}/{} {}", r.shard, r.shards, r.status))
        .collect();
    let complete = failed.is_empty() && missing.is_empty();
    let figure = match write && missing.is_empty() {
        true => crate::charts::population_figure(dir, &merged.report.records)?,
        false => None,
    };
    if !(args.quiet && complete) {
        let mut text = format!(
            "eyeshell: sweep {} ({}): {ok} of {total} run{} ok, {} failed, {} missing\n  shards          {}\n",
            merged.plan.origin,
            eyeshell::text::one_line(&merged.plan.name),
            crate::plural(total),
            failed.len(),
            missing.len(),
            first(&shards, ", ")
        );
        if write {
            text.push_str(&format!(
                "  table           {}\n",
                crate::shown(&dir.join(TABLE_FILE))
            ));
            if missing.is_empty() {
                text.push_str(&super::sweep::population_lines(&(&merged.plan).into(), dir));
                if let Some(png) = &figure {
                    text.push_str(&format!("  figure          {}\n", crate::shown(png)));
                }
            }
        }
        if !failed.is_empty() {
            text.push_str(&format!("  failed          {}\n", first(&failed, "; ")));
        }
        if !missing.is_empty() {
            text.push_str(&format!("  missing         {}\n", first(&missing, ", ")));
        }
        if !complete {
            text.push_str(&resume_hint(&merged, dir));
        }
        out(&text);
    }
    if complete {
        return Ok(());
    }
    Err(Error::failed(eyeshell::Stage::Sweep, format!(
        "{} of {total} runs of the sweep in {} are not done ({} failed, {} missing): run them with the --resume command above",
        failed.len() + missing.len(),
        crate::shown(dir),
        failed.len(),
        missing.len()
    )))
}

/// The first [`SHOWN`] of `items`, then how many more.
fn first(items: &[String], sep: &str) -> String {
    let mut text = items[..items.len().min(SHOWN)].join(sep);
    if items.len() > SHOWN {
        text.push_str(&format!("{sep}and {} more", items.len() - SHOWN));
    }
    text
}

/// The commands that run what is left: the whole rest on one machine, or again the shards
/// that own it (as they were split).
fn resume_hint(merged: &eyeshell::sweep::shard::Merged, dir: &Path) -> String {
    let record = &merged.records[0];
    // The scene as the shards named it if it is the same file from here, else absolute.
    let same = std::fs::canonicalize(&record.scene)
        .is_ok_and(|p| p.display().to_string() == record.scene_path);
    let scene = if same {
        &record.scene
    } else {
        &record.scene_path
    };
    let mut command = format!("eyeshell sweep {}", shell::word(scene));
    for set in &record.overrides {
        command.push_str(&format!(" --set {}", shell::word(set)));
    }
    command.push_str(&format!(" --out {} --resume", shell::word(dir)));
    // A sweep larger than one process holds runs only in shards.
    let whole = merged.plan.len() <= MAX_RUNS;
    let mut text = match whole {
        true => format!("  run the rest:   {command}\n"),
        false => String::new(),
    };
    if let Some((n, ks)) = merged.shards_to_resume() {
        let ks: Vec<String> = ks.iter().map(|k| k.to_string()).collect();
        text.push_str(&format!(
            "  {}{command} --shard K/{n}   for K = {}\n",
            if whole {
                "or by shard:    "
            } else {
                "run the rest:   "
            },
            first(&ks, ", ")
        ));
    }
    text
}

/// `--slurm-script`: print an sbatch script running `plan` as a job array, one shard per
/// task, each with `--jobs` from the CPUs Slurm grants it; nothing is run or written. The
/// plan is validated first ([`eyeshell::sweep::shard::costs_of`]), and no shard may hold
/// more than [`MAX_RUNS`] runs. Every word of the user's (paths, `--set` values) reaches
/// the script through [`shell::word`].
pub(crate) fn print_slurm_script(
    a: &SweepArgs,
    plan: &SweepPlan,
    scene: &Path,
    out_dir: &Path,
) -> Result<(), Error> {
    let runs = plan.len();
    let shards = shard_count(a.shards, plan)?;
    let (cpus, time) = task_limits(a)?;
    // Refused now rather than in every task.
    eyeshell::rundir::owner::inspect(&eyeshell::rundir::owner::normalise(out_dir))?;
    let here = working_dir()?;
    let absolute = |p: &Path| {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            here.join(p)
        }
    };
    let exe = std::env::current_exe()
        .and_then(std::fs::canonicalize)
        .map_err(|source| Error::Io {
            path: "eyeshell".into(),
            source,
        })?;
    let out_abs = absolute(out_dir);
    let job = format!(
        "eyeshell-{}",
        plan.name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '-'
            })
            .take(40)
            .collect::<String>()
    );
    // Every word from the user (paths, --set values) goes through shell::word: quoted, and
    // on one line, so that none of it runs and none ends a comment line early.
    use std::ffi::OsStr;
    let mut task: Vec<&OsStr> = vec![exe.as_os_str(), OsStr::new("sweep"), scene.as_os_str()];
    for set in &a.set {
        task.extend([OsStr::new("--set"), OsStr::new(set)]);
    }
    task.extend([
        OsStr::new("--out"),
        out_abs.as_os_str(),
        OsStr::new("--resume"),
    ]);
    let merge = shell::command([
        exe.as_os_str(),
        OsStr::new("sweep"),
        OsStr::new("merge"),
        out_abs.as_os_str(),
    ]);
    // sbatch --wrap hands its text to sh: the command is quoted for sh first, then the
    // whole of it as one word for the shell the user pastes into.
    let mut wrapped = shell::posix_word(&exe);
    wrapped.extend_from_slice(b" sweep merge ");
    wrapped.extend(shell::posix_word(&out_abs));
    let wrapped = shell::word(OsStr::from_bytes(&wrapped));
    let out_word = shell::word(&out_abs);
    let time_line = match time {
        Some(t) => format!("#SBATCH --time={t}"),
        None => {
            "##SBATCH --time=1:00:00          # each task's limit: set it (remove one #)".into()
        }
    };
    // The comments and #SBATCH lines: sbatch reads `#SBATCH` lines up to the first command,
    // so each of these must stay one line whatever the words in it hold.
    let header = [
        format!(
            "# The sweep {} ({runs} run{}) as a Slurm job array: {shards} shard{}, one per task.",
            plan.origin,
            crate::plural(runs),
            crate::plural(shards)
        ),
        "# Each task runs its shard's runs into DIR/runs/<name>/ and writes".into(),
        "# DIR/shards/<task>.json (no task writes a file another one writes), where DIR is".into(),
        format!("#   {out_word}"),
        "#".into(),
        "#   submit:  sbatch THIS_FILE            (edit the #SBATCH lines first if need be)".into(),
        format!("#   then:    {merge}"),
        "#            (sweep.csv and summary.json, as a plain `eyeshell sweep` writes them; it"
            .into(),
        "#            lists runs that failed or are missing, and the command that runs them)"
            .into(),
        "#   or, merged by Slurm when every task has ended:".into(),
        format!("#            sbatch --dependency=afterany:JOBID --wrap {wrapped}"),
        "#".into(),
        "# --resume: a task submitted again (or the whole array) keeps the runs that finished."
            .into(),
        format!("#SBATCH --job-name={job}"),
        format!("#SBATCH --array=1-{shards}"),
        format!("#SBATCH --cpus-per-task={cpus}"),
        time_line,
        format!("#SBATCH --output={job}-%A_%a.out"),
    ];
    let mut script = String::from("#!/bin/bash\n");
    for line in header {
        // shell::word never breaks a line, and plan.origin is one_line'd: a break here
        // would be a bug that runs text as a command.
        debug_assert!(!line.contains(['\n', '\r']), "{line}");
        script.push_str(&eyeshell::text::one_line(&line));
        script.push('\n');
    }
    script.push_str(&format!(
        "\nset -euo pipefail\ncd {}\nexec {} \\\n    --shard slurm --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\"\n",
        shell::word(&here),
        shell::command(task),
    ));
    out(&script);
    Ok(())
}

/// `--shards`: the number of shards (array tasks), by default as many as keep every shard
/// within [`MAX_RUNS`]; given, it must lie in 1 to the plan's runs and keep the largest
/// shard within [`MAX_RUNS`]. The plan is validated first
/// ([`eyeshell::sweep::shard::costs_of`]).
fn shard_count(shards: Option<usize>, plan: &SweepPlan) -> Result<usize, Error> {
    let runs = plan.len();
    let costs = eyeshell::sweep::shard::costs_of(plan)?;
    let largest_share = |n: usize| costs.largest_share(n);
    Ok(match shards {
        // The default, or as many more as keep every shard within MAX_RUNS.
        None => {
            let mut n = runs.min(DEFAULT_SHARDS).max(runs.div_ceil(MAX_RUNS));
            while largest_share(n) > MAX_RUNS {
                n = (2 * n).min(runs);
            }
            n
        }
        Some(n) if n >= 1 && n <= runs => match largest_share(n) {
            share if share > MAX_RUNS => {
                return Err(Error::input(eyeshell::Subject::Argument("--shards".into()), format!(
                    "--shards {n}: a shard would hold {share} of the sweep's {runs} runs, more than the {MAX_RUNS} one process runs: give more shards (at least {})",
                    runs.div_ceil(MAX_RUNS)
                ))
                .with_value(n)
                .with_origin(eyeshell::Origin::Argument))
            }
            _ => n,
        },
        Some(n) => {
            return Err(Error::input(
                eyeshell::Subject::Argument("--shards".into()),
                format!(
                    "--shards {n}: give 1 to {runs} (the sweep has {runs} run{})",
                    crate::plural(runs)
                ),
            )
            .with_value(n)
            .with_origin(eyeshell::Origin::Argument))
        }
    })
}

/// `--cpus-per-task` (1 by default, at most 1024) and `--time` (digits, `:` and `-` only, as
/// Slurm writes a time), checked.
fn task_limits(a: &SweepArgs) -> Result<(usize, Option<&str>), Error> {
    let cpus = match a.cpus_per_task {
        None => 1,
        Some(c) if (1..=1024).contains(&c) => c,
        Some(c) => {
            return Err(Error::input(
                eyeshell::Subject::Argument("--cpus-per-task".into()),
                format!("--cpus-per-task {c}: give 1 to 1024"),
            )
            .with_value(c)
            .with_origin(eyeshell::Origin::Argument))
        }
    };
    if let Some(time) = &a.time {
        let plain = !time.is_empty()
            && time
                .chars()
                .all(|c| c.is_ascii_digit() || c == ':' || c == '-');
        if !plain {
            return Err(Error::input(
                eyeshell::Subject::Argument("--time".into()),
                format!(
                    "--time {}: give a Slurm time such as 30, 2:00:00 or 1-12:00:00",
                    eyeshell::text::one_line(time)
                ),
            )
            .with_value(time)
            .with_origin(eyeshell::Origin::Argument));
        }
    }
    Ok((cpus, a.time.as_deref()))
}

/// The working directory, where the script's tasks run, unless Slurm would misread its
/// path.
fn working_dir() -> Result<std::path::PathBuf, Error> {
    let here = std::env::current_dir().map_err(|source| Error::Io {
        path: ".".into(),
        source,
    })?;
    // Slurm opens each task's output file (`--output`, relative) in the working directory
    // and reads `\` and `%` in that path as an escape and a pattern: the task could not
    // start (slurmd: "Could not open stdout file").
    if let Some(&c) = here
        .as_os_str()
        .as_bytes()
        .iter()
        .find(|b| b"\\%".contains(b))
    {
        return Err(Error::input(eyeshell::Subject::File(here.clone()), format!(
            "--slurm-script: the working directory {} holds '{}', which Slurm reads in a task's output file name as an escape or a pattern: make the script from a directory without one (the script runs there)",
            eyeshell::text::one_line(&here.display().to_string()),
            c as char
        )));
    }
    Ok(here)
}
