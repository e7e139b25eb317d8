//! On a real Slurm: tests/slurm/cluster.sh starts munged, slurmctld and slurmd on this
//! machine (one node, 2 CPUs, its files under /var/tmp), the script of `eyeshell sweep
//! --slurm-script` runs a six-run growth sweep as a three-task job array (and a sampled
//! sweep of 8 eyes as two tasks), the merge job its
//! comment suggests (`sbatch --dependency=afterany:JOBID --wrap ...`, pasted into bash)
//! assembles it, and sweep.csv must be a plain sweep's (timings aside). The working
//! directory, DIR and the binary's folder hold line breaks, quotes, `$(...)` and
//! backticks: nothing they say may run (no canary file appears). The daemons are stopped
//! by their pid files however the test ends.
//!
//! It needs root and Debian's slurm-wlm and munge (`.ci/run` installs them). Without them
//! it prints `SKIPPED: <why>` on stderr and returns; with `EYESHELL_REQUIRE_SLURM=1` (set
//! by CI) a skip is a failure instead.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::shards::{
    canaries, eyeshell_at, hostile_name, hostile_slurm_name, sbatch_options, table_without_timings,
    CANARY, SMALL,
};
use crate::support::*;

/// The whole test, cluster included, stays well under this.
const JOB_LIMIT: Duration = Duration::from_secs(90);
const DAEMONS_LIMIT: Duration = Duration::from_secs(60);

fn skip(why: &str) {
    if std::env::var_os("EYESHELL_REQUIRE_SLURM").is_some_and(|v| v == "1") {
        panic!("Slurm test not run, but EYESHELL_REQUIRE_SLURM=1: {why}");
    }
    eprintln!("SKIPPED: the real Slurm test (tests/cli/slurm.rs): {why}");
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|path| {
        std::env::split_paths(&path)
            .chain([PathBuf::from("/usr/sbin"), PathBuf::from("/sbin")])
            .any(|d| d.join(program).is_file())
    })
}

/// Run `cmd` to its end or until `limit`, killing it then; (exit code, stdout, stderr).
fn run_with_limit(cmd: &mut Command, limit: Duration) -> Result<Run, String> {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("{cmd:?}: {e}"))?;
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(_)) => return Ok(Run::from(child.wait_with_output().unwrap())),
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let out = Run::from(child.wait_with_output().unwrap());
                return Err(format!(
                    "{cmd:?} took more than {} s: {}{}",
                    limit.as_secs(),
                    out.stdout,
                    out.stderr
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(100)),
            Err(e) => return Err(e.to_string()),
        }
    }
}

/// The cluster of tests/slurm/cluster.sh, stopped when dropped.
struct Cluster {
    dir: PathBuf,
}

impl Cluster {
    fn script() -> PathBuf {
        repo().join("tests/slurm/cluster.sh")
    }

    fn start(dir: &Path) -> Result<Cluster, String> {
        let cluster = Cluster {
            dir: dir.to_path_buf(),
        };
        let r = run_with_limit(
            Command::new("bash")
                .arg(Self::script())
                .arg("start")
                .arg(dir),
            DAEMONS_LIMIT,
        )?;
        if r.code != Some(0) {
            return Err(format!("the daemons did not start: {}", r.stderr.trim()));
        }
        Ok(cluster)
    }

    fn conf(&self) -> PathBuf {
        self.dir.join("slurm.conf")
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let stopped = run_with_limit(
            Command::new("bash")
                .arg(Self::script())
                .arg("stop")
                .arg(&self.dir),
            DAEMONS_LIMIT,
        );
        if let Err(e) = stopped {
            eprintln!("stopping the test's Slurm: {e}");
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[test]
fn a_slurm_job_array_of_shards_merges_to_the_plain_sweeps_table() {
    let start = Instant::now();
    // Root? (`id -u`: no libc call needed.)
    let uid = Command::new("id").arg("-u").output().ok();
    let root = uid.is_some_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    if !root {
        return skip("not root (slurmctld and slurmd must run as root here)");
    }
    let missing: Vec<&str> = [
        "slurmctld",
        "slurmd",
        "sbatch",
        "scontrol",
        "sinfo",
        "munged",
        "munge",
        "unmunge",
    ]
    .into_iter()
    .filter(|p| !on_path(p))
    .collect();
    if !missing.is_empty() {
        return skip(&format!(
            "{} not installed (apt-get install slurm-wlm munge)",
            missing.join(", ")
        ));
    }
    // The cluster's files under /var (a spool on tmpfs or in a user's tmp can be refused).
    let base = tempfile::Builder::new()
        .prefix("eyeshell-slurm-")
        .tempdir_in("/var/tmp")
        .unwrap();
    let cluster = match Cluster::start(&base.path().join("cluster")) {
        Ok(c) => c,
        Err(why) => return skip(&why),
    };
    // The paper's grow sweep (Γ × δ, six runs), made small: 41 nodes, t_end = 0.2. The
    // working directory, DIR and the binary's folder have names that run commands if a
    // shell reads them unquoted, and break comment lines (crate::shards::hostile_name).
    let evil = hostile_name();
    let exe = eyeshell_at(base.path(), &format!("bin {evil}"));
    let work = base.path().join(format!("work {}", hostile_slurm_name()));
    std::fs::create_dir(&work).unwrap();
    let out = format!("out {evil}");
    let canary = base.path().join("canary");
    let grid = "[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n\"growth.delta\" = [2, 6]\n";
    let scene = SMALL.replace("nodes = 21", "nodes = 41");
    std::fs::write(work.join("s.toml"), format!("{scene}{grid}")).unwrap();
    let script = Run::from(
        Command::new(&exe)
            .args(["sweep", "s.toml", "--out", &out, "--slurm-script"])
            .args(["--shards", "3", "--time", "5:00"])
            .current_dir(&work)
            .output()
            .unwrap(),
    );
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    assert!(
        sbatch_options(&script.stdout).contains(&"--array=1-3".to_string()),
        "{}",
        script.stdout
    );
    std::fs::write(work.join("job.sh"), &script.stdout).unwrap();
    let sbatch = |args: &[&str]| {
        run_with_limit(
            Command::new("sbatch")
                .args(args)
                .current_dir(&work)
                .env("SLURM_CONF", cluster.conf())
                .env(CANARY, &canary),
            JOB_LIMIT,
        )
        .unwrap_or_else(|e| panic!("{e}\n{}", logs(&work, &cluster)))
    };
    let job = sbatch(&["--parsable", "job.sh"]);
    assert_eq!(
        job.code,
        Some(0),
        "sbatch: {}{}\n{}",
        job.stdout,
        job.stderr,
        logs(&work, &cluster)
    );
    let id = job.stdout.trim().split(';').next().unwrap().to_string();
    // The merge as the script's comment suggests it, pasted into bash: a job that waits
    // for the array (afterany) and runs `eyeshell sweep merge DIR` through sbatch --wrap.
    let wrap = script
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("#            sbatch "))
        .unwrap_or_else(|| panic!("no --wrap line in {}", script.stdout))
        .replace("JOBID", &id);
    let merge = run_with_limit(
        Command::new("bash")
            .arg("-c")
            .arg(format!("sbatch --wait {wrap}"))
            .current_dir(&work)
            .env("SLURM_CONF", cluster.conf())
            .env(CANARY, &canary),
        JOB_LIMIT,
    )
    .unwrap_or_else(|e| panic!("{e}\n{}", logs(&work, &cluster)));
    assert_eq!(
        merge.code,
        Some(0),
        "sbatch --wait {wrap}: {}{}\n{}",
        merge.stdout,
        merge.stderr,
        logs(&work, &cluster)
    );
    for k in 1..=3 {
        assert!(
            work.join(&out).join(format!("shards/{k}.json")).is_file(),
            "shard {k}: {}",
            logs(&work, &cluster)
        );
    }
    assert!(
        work.join(&out).join("sweep.csv").is_file(),
        "the merge job: {}",
        logs(&work, &cluster)
    );
    let merge = eyeshell_in(&work, &["sweep", "merge", &out]);
    assert_eq!(merge.code, Some(0), "{}{}", merge.stdout, merge.stderr);
    assert!(merge.stdout.contains("6 of 6 runs ok"), "{}", merge.stdout);
    let plain = eyeshell_in(&work, &["sweep", "s.toml", "--out", "plain", "-q"]);
    assert_eq!(plain.code, Some(0), "{}", plain.stderr);
    assert_eq!(
        table_without_timings(&work.join(&out)),
        table_without_timings(&work.join("plain"))
    );
    // A sampled sweep (a cohort of 8 eyes) as a job array of 2 tasks, merged: its
    // population files are those of the plain sweep, byte for byte.
    let cohort = "[sweep.sample]\neyes = 8\ndesign = \"latin-hypercube\"\nseed = 11\n[sweep.sample.keys]\n\"growth.eta0\" = { dist = \"normal\", mean = 70.0, sd = 5.0 }\n\"growth.Gamma\" = { dist = \"uniform\", low = 6.0, high = 10.0 }\n";
    std::fs::write(work.join("cohort.toml"), format!("{scene}{cohort}")).unwrap();
    let script = Run::from(
        Command::new(&exe)
            .args(["sweep", "cohort.toml", "--out", "cohort", "--slurm-script"])
            .args(["--shards", "2", "--time", "5:00"])
            .current_dir(&work)
            .output()
            .unwrap(),
    );
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    std::fs::write(work.join("cohort.sh"), &script.stdout).unwrap();
    let job = sbatch(&["--wait", "cohort.sh"]);
    assert_eq!(
        job.code,
        Some(0),
        "sbatch --wait cohort.sh: {}{}\n{}",
        job.stdout,
        job.stderr,
        logs(&work, &cluster)
    );
    let merge = eyeshell_in(&work, &["sweep", "merge", "cohort"]);
    assert_eq!(merge.code, Some(0), "{}{}", merge.stdout, merge.stderr);
    assert!(merge.stdout.contains("8 of 8 runs ok"), "{}", merge.stdout);
    let plain = eyeshell_in(
        &work,
        &["sweep", "cohort.toml", "--out", "cohort-plain", "-q"],
    );
    assert_eq!(plain.code, Some(0), "{}", plain.stderr);
    for f in ["population.json", "population.csv"] {
        assert_eq!(
            std::fs::read(work.join("cohort").join(f)).unwrap(),
            std::fs::read(work.join("cohort-plain").join(f)).unwrap(),
            "{f}"
        );
    }
    assert_eq!(canaries(base.path()), Vec::<String>::new());
    drop(cluster);
    eprintln!(
        "the real Slurm test ran: 3 array tasks and the merge job, hostile paths, and a cohort of 8 eyes as 2 tasks, in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

/// The tasks' output and the daemons' logs, for a failure's message.
fn logs(work: &Path, cluster: &Cluster) -> String {
    let mut text = String::new();
    let dirs = [work.to_path_buf(), cluster.dir.join("log")];
    for dir in dirs {
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let path = entry.path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name.ends_with(".out") || name.ends_with(".log") {
                let body = std::fs::read_to_string(&path).unwrap_or_default();
                let tail: Vec<&str> = body.lines().rev().take(20).collect();
                text.push_str(&format!("--- {}\n", path.display()));
                for line in tail.into_iter().rev() {
                    text.push_str(line);
                    text.push('\n');
                }
            }
        }
    }
    text
}
