//! `--shard slurm` and the Slurm script `eyeshell sweep --slurm` writes: one shard per task
//! merging to the plain table, and hostile paths that run nothing but eyeshell.

use super::*;

#[test]
fn the_slurm_script_runs_one_shard_per_task_and_merges_to_the_plain_table() {
    let dir = scene_dir(&format!("{SMALL}{GRID}"));
    let d = dir.path();
    let script = eyeshell_in(
        d,
        &[
            "sweep",
            "s.toml",
            "--out",
            "out",
            "--slurm-script",
            "--shards",
            "3",
            "--time",
            "10:00",
            "--cpus-per-task",
            "2",
        ],
    );
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    let text = &script.stdout;
    assert!(text.starts_with("#!/bin/bash\n"), "{text}");
    for line in [
        "#SBATCH --array=1-3\n",
        "#SBATCH --cpus-per-task=2\n",
        "#SBATCH --time=10:00\n",
        " --resume \\\n    --shard slurm --jobs \"${SLURM_CPUS_PER_TASK:-1}\"\n",
        "eyeshell sweep merge ",
    ] {
        assert!(text.contains(line), "{line:?} not in:\n{text}");
    }
    assert!(!d.join("out").exists(), "--slurm-script wrote out/");
    // The tasks as Slurm would start them (in any order), then the merge.
    for id in ["3", "1", "2"] {
        let r = eyeshell_with(
            d,
            &[
                "sweep", "s.toml", "--out", "out", "--resume", "--shard", "slurm", "-q",
            ],
            &[
                ("SLURM_ARRAY_TASK_ID", id),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "3"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ],
        );
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        assert!(d.join(format!("out/shards/{id}.json")).is_file());
    }
    let merge = eyeshell_in(d, &["sweep", "merge", "out", "-q"]);
    assert_eq!(merge.code, Some(0), "{}", merge.stderr);
    let plain = eyeshell_in(d, &["sweep", "s.toml", "--out", "plain", "-q"]);
    assert_eq!(plain.code, Some(0), "{}", plain.stderr);
    assert_eq!(
        table_without_timings(&d.join("out")),
        table_without_timings(&d.join("plain"))
    );
}

/// `--slurm-script` with the working directory ([`hostile_slurm_name`]), DIR, the
/// binary's folder and a --set value all hostile ([`hostile_name`]): the script, run by bash as Slurm runs a task (fake
/// array variables), executes only eyeshell, which runs its shard into exactly DIR;
/// sbatch reads every `#SBATCH` line; the merge command and the `sbatch --wrap` command
/// printed in its comments, pasted into bash (the --wrap text then run by sh, as sbatch
/// runs it), merge exactly DIR. No canary file appears. A working directory holding `\`
/// or `%` (which Slurm reads in a task's output file name) is refused.
#[test]
fn a_slurm_script_with_hostile_paths_runs_nothing_but_eyeshell() {
    let base = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
    let root = base.path();
    let evil = hostile_name();
    let exe = eyeshell_at(root, &format!("bin {evil}"));
    let work = root.join(format!("work {}", hostile_slurm_name()));
    std::fs::create_dir(&work).unwrap();
    std::fs::write(
        work.join(format!("s {evil}.toml")),
        format!("{SMALL}[sweep.grid]\n\"growth.Gamma\" = [4, 8, 12]\n"),
    )
    .unwrap();
    let out = format!("out {evil}");
    let canary = root.join("canary");
    let env_canary = (CANARY, canary.to_str().unwrap());
    let script = Command::new(&exe)
        .args(["sweep", &format!("s {evil}.toml"), "--out", &out])
        .args(["--slurm-script", "--shards", "2", "--time", "5:00"])
        .args(["--set", &format!("name={evil}")])
        .current_dir(&work)
        .env(env_canary.0, env_canary.1)
        .output()
        .unwrap();
    let script = Run::from(script);
    assert_eq!(script.code, Some(0), "{}", script.stderr);
    let text = &script.stdout;
    assert_eq!(
        sbatch_options(text),
        [
            "--job-name=eyeshell-it-s--a----touch---EYESHELL_CANARY--doll",
            "--array=1-2",
            "--cpus-per-task=1",
            "--time=5:00",
            "--output=eyeshell-it-s--a----touch---EYESHELL_CANARY--doll-%A_%a.out",
        ],
        "{text}"
    );
    // Every line up to the first command is a comment.
    let head: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("set "))
        .collect();
    assert!(
        head.iter().all(|l| l.is_empty() || l.starts_with('#')),
        "{text}"
    );
    // A working directory that Slurm cannot place a task's output in: refused, saying why.
    for bad in ["back\\slash", "per%cent"] {
        let dir = root.join(bad);
        std::fs::create_dir(&dir).unwrap();
        std::fs::copy(work.join(format!("s {evil}.toml")), dir.join("s.toml")).unwrap();
        let r = eyeshell_in(&dir, &["sweep", "s.toml", "--out", "out", "--slurm-script"]);
        assert_bad(&r, "which Slurm reads in a task's output file name", bad);
        assert!(r.stdout.is_empty(), "{bad}: {}", r.stdout);
    }
    let file = root.join("job.sh");
    std::fs::write(&file, text).unwrap();

    // A fake sbatch on PATH that records its arguments, NUL-separated.
    let fake = root.join("fakebin");
    std::fs::create_dir(&fake).unwrap();
    let argv = root.join("sbatch-argv");
    std::fs::write(
        fake.join("sbatch"),
        format!(
            "#!/bin/sh\nprintf '%s\\0' \"$@\" > '{}'\n",
            argv.to_str().unwrap()
        ),
    )
    .unwrap();
    std::fs::set_permissions(
        fake.join("sbatch"),
        std::os::unix::fs::PermissionsExt::from_mode(0o755),
    )
    .unwrap();
    let path = format!("{}:/usr/bin:/bin", fake.display());
    let bash = |args: &[&std::ffi::OsStr], envs: &[(&str, &str)]| {
        Run::from(
            Command::new("bash")
                .args(args)
                .current_dir(root)
                .env("PATH", &path)
                .env(env_canary.0, env_canary.1)
                .envs(envs.iter().copied())
                .output()
                .unwrap(),
        )
    };
    let syntax = bash(&["-n".as_ref(), file.as_os_str()], &[]);
    assert_eq!(syntax.code, Some(0), "bash -n: {}", syntax.stderr);
    // The two array tasks, as Slurm starts them (from another directory).
    for k in ["2", "1"] {
        let task = bash(
            &[file.as_os_str()],
            &[
                ("SLURM_ARRAY_TASK_ID", k),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("SLURM_CPUS_PER_TASK", "1"),
            ],
        );
        assert_eq!(task.code, Some(0), "task {k}: {}", task.stderr);
        assert!(
            work.join(&out).join(format!("shards/{k}.json")).is_file(),
            "task {k}: {}",
            task.stderr
        );
        // Its own report names DIR as one pasteable word.
        let hint = task
            .stdout
            .lines()
            .find_map(|l| l.split_once("once every shard has run: "))
            .map(|(_, cmd)| cmd.to_string())
            .unwrap_or_else(|| panic!("{}", task.stdout));
        assert!(hint.starts_with("eyeshell sweep merge $'"), "{hint}");
    }
    assert_eq!(
        std::fs::read_dir(work.join(&out).join("runs"))
            .unwrap()
            .count(),
        3
    );
    let comment = |prefix: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .unwrap_or_else(|| panic!("{prefix:?} not in {text}"))
            .to_string()
    };
    // The merge command in the comments, pasted into bash.
    let merge = comment("#   then:    ");
    let merged = bash(&["-c".as_ref(), merge.as_ref()], &[]);
    assert_eq!(merged.code, Some(0), "{merge}: {}", merged.stderr);
    assert!(
        merged.stdout.contains("3 of 3 runs ok"),
        "{}",
        merged.stdout
    );
    std::fs::remove_file(work.join(&out).join("sweep.csv")).unwrap();
    // The --wrap command: bash hands sbatch the text, which sbatch runs with sh.
    let submit = comment("#            sbatch ").replace("JOBID", "42");
    let submitted = bash(&["-c".as_ref(), format!("sbatch {submit}").as_ref()], &[]);
    assert_eq!(submitted.code, Some(0), "{submit}: {}", submitted.stderr);
    let args = std::fs::read(&argv).unwrap();
    let args: Vec<&[u8]> = args.split(|&b| b == 0).filter(|a| !a.is_empty()).collect();
    assert_eq!(args.len(), 3, "{args:?}");
    assert_eq!(args[0], b"--dependency=afterany:42");
    assert_eq!(args[1], b"--wrap");
    let wrapped = Run::from(
        Command::new("sh")
            .arg("-c")
            .arg(std::ffi::OsStr::from_bytes(args[2]))
            .current_dir(root)
            .env("PATH", &path)
            .env(env_canary.0, env_canary.1)
            .output()
            .unwrap(),
    );
    assert_eq!(wrapped.code, Some(0), "{}", wrapped.stderr);
    assert!(work.join(&out).join("sweep.csv").is_file());
    assert_eq!(canaries(root), Vec::<String>::new());
}
