//! The documentation runs: every command of README.md and of the user guide (docs/guide/*.md)
//! is run with this build's binary and its shown output compared; every synopsis names real
//! flags; every relative link and #anchor of the project's Markdown resolves; the keys
//! reference is `eyeshell keys` as it is now; .ci/run runs the README's test command.
//!
//! The fences (a block's info string) say what each block is:
//! - ` ```sh `: commands, one a line (`\` continues a line; `# ...` is a comment; `> FILE`
//!   sends stdout to a file). Each must start with `eyeshell` and succeed. They run in a
//!   temporary directory holding copies of `scenes/` and `examples/fit/`, one directory per
//!   Markdown file, in order, so a later block may read what an earlier one wrote.
//! - ` ```console `: `$ eyeshell ...` lines, each followed by what it prints (stdout and
//!   stderr as a terminal shows them). A command whose shown output starts with `eyeshell: error:` must fail.
//! - ` ```text ` right after a `sh` block (only blank lines between): what the block's
//!   commands print, all of them in order.
//! - ` ```sh synopsis `: usage lines, not run; each line's subcommand must exist and each
//!   `--flag` must be one its `--help` lists.
//! - ` ```toml file=PATH `: the file PATH of the repository, verbatim; ` ```toml scene `: a
//!   scene (or sweep) that `eyeshell check` accepts.
//! - ` ```sh skip-test: REASON ` (or `matlab`, `toml`): not run (installs packages, needs
//!   MATLAB or its files, or runs the whole suite); counted, and the count is pinned below so
//!   that a new one is a choice. Every other `sh`, `console`, `toml` or `matlab` block must be
//!   one of the kinds above.
//!
//! Shown output is compared line by line: a line `…` stands for any lines, `…` within a line
//! for any text, whitespace runs are equal, and numbers are equal within a relative 1e-6
//! (` ```text numbers=any `: any number, for timings). The Python blocks are pytest's
//! (crates/eyeshell-py/tests/test_docs.py), which reads the same fences.

use crate::support::{repo, s};
use std::collections::{BTreeMap, BTreeSet};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Blocks marked `skip-test` in README.md and docs/guide: the README's two set-up lines,
/// the pip line of the Python chapter, the bvp4c comparison (the MATLAB code and the
/// commands that read its files), the cohort of 10,000 eyes (minutes), and the trial study
/// (a Python script; tests/cli/trials.rs runs it and checks its tables).
const SKIPPED: usize = 7;

/// The Markdown files whose commands run: README.md and every chapter of the guide.
fn documents() -> Vec<PathBuf> {
    let mut files = vec![repo().join("README.md")];
    let mut guide: Vec<PathBuf> = std::fs::read_dir(repo().join("docs/guide"))
        .expect("docs/guide")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guide.sort();
    files.extend(guide);
    files
}

fn rel(path: &Path) -> String {
    path.strip_prefix(repo())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// One fenced block: its info string (language and options), its text and where it starts.
#[derive(Debug, Clone)]
struct Block {
    info: String,
    text: String,
    line: usize,
}

impl Block {
    fn lang(&self) -> &str {
        self.info.split_whitespace().next().unwrap_or("")
    }

    /// What follows the language: `synopsis`, `skip-test: reason`, `numbers=any`, ...
    fn options(&self) -> &str {
        self.info[self.lang().len()..].trim()
    }
}

/// The fenced blocks of a Markdown file, each with the block that follows it when only blank
/// lines lie between (its shown output).
fn blocks(text: &str) -> Vec<(Block, Option<Block>)> {
    let mut found: Vec<(Block, usize)> = Vec::new(); // (block, line after its closing fence)
    let mut lines = text.lines().enumerate();
    while let Some((i, line)) = lines.next() {
        // A fence may be indented (a block inside a list item): its lines lose that indent.
        let indent = line.len() - line.trim_start().len();
        let Some(info) = line.trim_start().strip_prefix("```") else {
            continue;
        };
        let mut body = String::new();
        let mut end = i + 1;
        for (j, l) in lines.by_ref() {
            end = j + 1;
            if l.trim() == "```" {
                break;
            }
            body.push_str(
                l.get(indent..)
                    .filter(|_| l[..indent].trim().is_empty())
                    .unwrap_or(l.trim_start()),
            );
            body.push('\n');
        }
        found.push((
            Block {
                info: info.trim().to_string(),
                text: body,
                line: i + 1,
            },
            end,
        ));
    }
    let all: Vec<&str> = text.lines().collect();
    (0..found.len())
        .map(|k| {
            let (block, end) = &found[k];
            let next = found.get(k + 1).filter(|(n, _)| {
                all[*end..n.line - 1].iter().all(|l| l.trim().is_empty()) && n.lang() == "text"
            });
            (block.clone(), next.map(|(n, _)| n.clone()))
        })
        .collect()
}

/// A command line split into words as a POSIX shell would for the quoting the docs use
/// ('...', "...", and backslashes), with `# comments` dropped and a trailing `> FILE`.
fn words(line: &str) -> (Vec<String>, Option<String>) {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                for d in chars.by_ref() {
                    if d == '\'' {
                        break;
                    }
                    word.push(d);
                }
            }
            '"' => {
                in_word = true;
                while let Some(d) = chars.next() {
                    match d {
                        '"' => break,
                        '\\' => word.extend(chars.next()),
                        _ => word.push(d),
                    }
                }
            }
            '\\' => {
                in_word = true;
                word.extend(chars.next());
            }
            '#' if !in_word => break,
            c if c.is_whitespace() => {
                if in_word {
                    out.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    if in_word {
        out.push(word);
    }
    let redirect = match out.iter().position(|w| w == ">") {
        Some(k) => {
            assert_eq!(k + 2, out.len(), "`> FILE` must end the line: {line}");
            let file = out.pop();
            out.pop();
            file
        }
        None => None,
    };
    (out, redirect)
}

/// The command lines of a `sh` block, `\`-continued lines joined, comment lines dropped.
fn command_lines(text: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut current = String::new();
    for line in text.lines() {
        if current.is_empty() && (line.trim().is_empty() || line.trim_start().starts_with('#')) {
            continue;
        }
        match line.trim_end().strip_suffix('\\') {
            Some(head) => {
                current.push_str(head);
                current.push(' ');
            }
            None => {
                current.push_str(line);
                lines.push(std::mem::take(&mut current));
            }
        }
    }
    assert!(current.is_empty(), "a `\\` continues past the block's end");
    lines
}

/// Run one documented command line in `dir`: its exit code and what it printed, stdout and
/// stderr interleaved as on a terminal (both go to one file).
fn run(dir: &Path, line: &str, origin: &str) -> (Option<i32>, String) {
    let (words, redirect) = words(line);
    assert!(
        words.first().is_some_and(|w| w == "eyeshell"),
        "{origin}: `{line}` does not start with `eyeshell`; run only eyeshell in ```sh blocks, \
         or mark the block ```sh skip-test: REASON"
    );
    let mut log = tempfile::tempfile().expect("a file for the output");
    let stdout = match redirect {
        Some(file) => std::fs::File::create(dir.join(file)).expect("create the redirect"),
        None => log.try_clone().expect("dup"),
    };
    let status = Command::new(env!("CARGO_BIN_EXE_eyeshell"))
        .args(&words[1..])
        .current_dir(dir)
        .env("CI", "1")
        .stdout(Stdio::from(stdout))
        .stderr(Stdio::from(log.try_clone().expect("dup")))
        .status()
        .expect("run eyeshell");
    let mut printed = String::new();
    log.seek(SeekFrom::Start(0)).expect("rewind");
    log.read_to_string(&mut printed).expect("read the output");
    (status.code(), printed)
}

/// A token of shown or printed output: a number, `…`, or one other non-space character.
#[derive(Debug)]
enum Token<'a> {
    Num(&'a str, f64),
    Text(&'a str),
    Any,
}

fn tokens(line: &str) -> Vec<Token<'_>> {
    let b = line.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_whitespace() {
            i += 1;
        } else if line[i..].starts_with('…') {
            out.push(Token::Any);
            i += '…'.len_utf8();
        } else if b[i].is_ascii_digit() {
            let start = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
                i += 1;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                let mut j = i + 1;
                if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
                    j += 1;
                }
                if j < b.len() && b[j].is_ascii_digit() {
                    while j < b.len() && b[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            let text = &line[start..i];
            out.push(Token::Num(text, text.parse().unwrap_or(f64::NAN)));
        } else {
            // One character a token, so that `…` may stand for part of a word.
            let n = line[i..].chars().next().map_or(1, char::len_utf8);
            out.push(Token::Text(&line[i..i + n]));
            i += n;
        }
    }
    out
}

fn numbers_equal(a: &str, x: f64, b: &str, y: f64, any: bool) -> bool {
    any || a == b || (x - y).abs() <= 1e-6 * x.abs().max(y.abs())
}

fn tokens_match(shown: &[Token], printed: &[Token], any: bool) -> bool {
    match shown.split_first() {
        None => printed.is_empty(),
        Some((Token::Any, rest)) => {
            (0..=printed.len()).any(|k| tokens_match(rest, &printed[k..], any))
        }
        Some((s, rest)) => match (s, printed.first()) {
            (Token::Text(a), Some(Token::Text(b))) if a == b => {
                tokens_match(rest, &printed[1..], any)
            }
            (Token::Num(a, x), Some(Token::Num(b, y))) if numbers_equal(a, *x, b, *y, any) => {
                tokens_match(rest, &printed[1..], any)
            }
            _ => false,
        },
    }
}

fn lines_match(shown: &[&str], printed: &[&str], any: bool) -> bool {
    match shown.split_first() {
        None => printed.is_empty(),
        Some((s, rest)) if s.trim() == "…" => {
            (0..=printed.len()).any(|k| lines_match(rest, &printed[k..], any))
        }
        Some((s, rest)) => printed.first().is_some_and(|p| {
            tokens_match(&tokens(s), &tokens(p), any) && lines_match(rest, &printed[1..], any)
        }),
    }
}

/// Whether what was printed is what the docs show (see the module's comment).
fn output_matches(shown: &str, printed: &str, numbers_any: bool) -> bool {
    let trim = |t: &str| -> Vec<String> {
        let mut v: Vec<String> = t.lines().map(|l| l.trim_end().to_string()).collect();
        while v.last().is_some_and(|l| l.is_empty()) {
            v.pop();
        }
        v
    };
    let (s, p) = (trim(shown), trim(printed));
    let s: Vec<&str> = s.iter().map(String::as_str).collect();
    let p: Vec<&str> = p.iter().map(String::as_str).collect();
    lines_match(&s, &p, numbers_any)
}

/// A fresh directory to run a file's commands in, with the inputs the docs name.
fn workdir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for sub in [
        "scenes",
        "scenes/eyewear",
        "scenes/myopia",
        "examples/fit",
        "examples/cohort",
    ] {
        let to = dir.path().join(sub);
        std::fs::create_dir_all(&to).expect("mkdir");
        for entry in std::fs::read_dir(repo().join(sub)).expect("read inputs") {
            let path = entry.expect("entry").path();
            if path.is_file() {
                std::fs::copy(&path, to.join(path.file_name().expect("name"))).expect("copy");
            }
        }
    }
    dir
}

/// The flags `eyeshell SUB --help` lists.
fn help_flags(sub: &str, cache: &mut BTreeMap<String, BTreeSet<String>>) -> BTreeSet<String> {
    cache
        .entry(sub.to_string())
        .or_insert_with(|| {
            let r = crate::support::eyeshell(&[sub, "--help"]);
            assert_eq!(
                r.code,
                Some(0),
                "`eyeshell {sub} --help` failed: {}",
                r.stderr
            );
            r.stdout
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .filter(|w| w.starts_with("--") && w.len() > 2)
                .map(str::to_string)
                .collect()
        })
        .clone()
}

/// Every command and console block of README.md and the guide runs, prints what is shown,
/// and every synopsis names real subcommands and flags.
#[test]
fn every_command_in_the_readme_and_the_guide_runs() {
    let mut help = BTreeMap::new();
    let (mut commands, mut synopses, mut compared) = (0, 0, 0);
    let mut skipped = Vec::new();
    for file in documents() {
        let text = std::fs::read_to_string(&file).expect("read the doc");
        let dir = workdir();
        for (block, shown) in blocks(&text) {
            let origin = format!("{}:{}", rel(&file), block.line);
            match (block.lang(), block.options()) {
                ("sh", "synopsis") => {
                    for line in command_lines(&block.text) {
                        let (words, _) = words(&line);
                        assert_eq!(
                            words.first().map(String::as_str),
                            Some("eyeshell"),
                            "{origin}"
                        );
                        let sub = words.get(1).map(String::as_str).unwrap_or("--help");
                        let known = help_flags(sub, &mut help);
                        for w in &words[2..] {
                            let flag = w
                                .trim_start_matches('[')
                                .split(['=', ']'])
                                .next()
                                .unwrap_or("");
                            if flag.starts_with("--") && flag.len() > 2 {
                                assert!(
                                    known.contains(flag),
                                    "{origin}: `eyeshell {sub}` has no flag {flag} (its --help: {known:?})"
                                );
                            }
                        }
                        synopses += 1;
                    }
                }
                ("sh", "") => {
                    let mut printed = String::new();
                    for line in command_lines(&block.text) {
                        let (code, out) = run(dir.path(), &line, &origin);
                        assert_eq!(code, Some(0), "{origin}: `{line}` failed:\n{out}");
                        printed.push_str(&out);
                        commands += 1;
                    }
                    if let Some(shown) = shown {
                        let any = shown
                            .options()
                            .split_whitespace()
                            .any(|o| o == "numbers=any");
                        assert!(
                            output_matches(&shown.text, &printed, any),
                            "{origin}: the output shown at line {} is not what it prints:\n--- shown\n{}--- printed\n{printed}",
                            shown.line,
                            shown.text
                        );
                        compared += 1;
                    }
                }
                ("console", "") => {
                    let mut parts: Vec<(String, String)> = Vec::new();
                    for line in block.text.lines() {
                        match line.strip_prefix("$ ") {
                            Some(cmd) => parts.push((cmd.to_string(), String::new())),
                            None => {
                                let last = parts.last_mut().unwrap_or_else(|| {
                                    panic!("{origin}: a console block starts with `$ `")
                                });
                                last.1.push_str(line);
                                last.1.push('\n');
                            }
                        }
                    }
                    for (cmd, shown) in parts {
                        let (code, printed) = run(dir.path(), &cmd, &origin);
                        let fails = shown.starts_with("eyeshell: error:");
                        assert_eq!(code == Some(0), !fails, "{origin}: `{cmd}` exited {code:?}");
                        assert!(
                            output_matches(&shown, &printed, false),
                            "{origin}: `{cmd}` prints\n{printed}\nnot what is shown:\n{shown}"
                        );
                        commands += 1;
                        compared += 1;
                    }
                }
                ("toml", opts) if opts.starts_with("file=") => {
                    let path = repo().join(&opts["file=".len()..]);
                    let file = std::fs::read_to_string(&path).expect("the file a block shows");
                    assert_eq!(block.text, file, "{origin}: not {} verbatim", rel(&path));
                }
                ("toml", "scene") => {
                    let path = dir.path().join(format!("block-{}.toml", block.line));
                    std::fs::write(&path, &block.text).expect("write the scene");
                    let r = crate::support::eyeshell_in(dir.path(), &["check", s(&path)]);
                    assert_eq!(
                        r.code,
                        Some(0),
                        "{origin}: eyeshell check refuses it: {}",
                        r.stderr
                    );
                    commands += 1;
                }
                ("sh" | "toml" | "matlab", opts) if opts.starts_with("skip-test") => {
                    let reason = opts.trim_start_matches("skip-test").trim_start_matches(':');
                    assert!(
                        !reason.trim().is_empty(),
                        "{origin}: skip-test needs a reason"
                    );
                    skipped.push(format!("{origin}: {}", reason.trim()));
                }
                ("sh" | "console" | "toml" | "matlab", opts) => {
                    panic!(
                        "{origin}: a {} block must run (fence options `{opts}`)",
                        block.lang()
                    )
                }
                _ => {}
            }
        }
    }
    println!(
        "docs: {commands} commands run, {compared} outputs compared, {synopses} synopsis lines \
         checked, {} blocks skipped:\n  {}",
        skipped.len(),
        skipped.join("\n  ")
    );
    assert!(
        commands >= 20 && compared >= 8,
        "too few commands found: the fences changed?"
    );
    assert_eq!(skipped.len(), SKIPPED, "blocks skipped: {skipped:#?}");
}

/// Every fenced block of README.md and the guide names its language (a bare fence would be
/// compiled as Rust by the doctests), and every ```rust block is one of the doctests.
#[test]
fn every_block_names_its_language_and_rust_blocks_are_doctests() {
    let lib = std::fs::read_to_string(repo().join("crates/eyeshell/src/lib.rs")).expect("lib.rs");
    let known = ["sh", "console", "text", "python", "rust", "toml", "matlab"];
    for file in documents() {
        let text = std::fs::read_to_string(&file).expect("read the doc");
        for (block, _) in blocks(&text) {
            let origin = format!("{}:{}", rel(&file), block.line);
            assert!(
                known.contains(&block.lang()),
                "{origin}: fence language `{}`",
                block.info
            );
            // CommonMark: a backtick in a fence's info string makes it no fence at all.
            assert!(
                !block.info.contains('`'),
                "{origin}: a backtick in the fence's info string"
            );
            if block.lang() == "rust" {
                let include = format!("include_str!(\"../../../{}\")", rel(&file));
                assert!(
                    lib.contains(&include),
                    "{origin}: a rust block, but lib.rs lacks #[doc = {include}]"
                );
            }
        }
    }
}

/// .ci/run runs exactly the README's test command, after installing the same packages.
#[test]
fn ci_runs_the_readme_test_command() {
    let ci = std::fs::read_to_string(repo().join(".ci/run")).expect(".ci/run");
    let readme = std::fs::read_to_string(repo().join("README.md")).expect("README.md");
    let packages = ci
        .lines()
        .find_map(|l| l.strip_prefix("packages=\""))
        .and_then(|l| l.strip_suffix('"'))
        .expect(".ci/run's packages=");
    let command = ci
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .expect(".ci/run's last line");
    let line = format!("sudo apt-get update && sudo apt-get install -y {packages} && {command}");
    assert!(
        readme.lines().any(|l| l == line),
        "README.md has no line\n{line}\n(.ci/run's packages and last line)"
    );
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors a Markdown file defines (headings outside code blocks, repeats numbered).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    let mut in_code = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code || !line.starts_with('#') {
            continue;
        }
        let heading = line.trim_start_matches('#');
        if !heading.starts_with(' ') {
            continue;
        }
        let base = slug(&heading.replace('`', ""));
        let n = seen.entry(base.clone()).or_insert(0);
        out.insert(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

/// The link targets of a Markdown file: `](target)` outside code blocks and code spans.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_code = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        // Drop code spans, which may hold `](` legitimately.
        let plain: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let mut rest = plain.as_str();
        while let Some(k) = rest.find("](") {
            rest = &rest[k + 2..];
            let end = rest.find(')').unwrap_or(rest.len());
            out.push((i + 1, rest[..end].trim().to_string()));
            rest = &rest[end..];
        }
    }
    out
}

/// The Markdown files whose links are checked: README.md, docs/**, ARCHITECTURE.md,
/// TESTING.md, BENCHMARKS.md.
fn markdown_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("read docs") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut files: Vec<PathBuf> = [
        "README.md",
        "ARCHITECTURE.md",
        "TESTING.md",
        "BENCHMARKS.md",
    ]
    .iter()
    .map(|f| repo().join(f))
    .collect();
    walk(&repo().join("docs"), &mut files);
    files.sort();
    files
}

/// Every relative link and #anchor in the project's Markdown resolves, and every chapter of
/// the guide can be reached from README.md by following links.
#[test]
fn no_dead_links_and_every_chapter_is_reachable_from_the_readme() {
    let files = markdown_files();
    let mut dead = Vec::new();
    let mut graph: BTreeMap<PathBuf, Vec<PathBuf>> = BTreeMap::new();
    let mut checked = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).expect("read");
        for (line, target) in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let to = if path.is_empty() {
                file.clone()
            } else {
                file.parent().expect("parent").join(path)
            };
            let Ok(to) = to.canonicalize() else {
                dead.push(format!("{}:{line}: {target}: no such file", rel(file)));
                continue;
            };
            if let Some(anchor) = anchor {
                let target_text = std::fs::read_to_string(&to).unwrap_or_default();
                if !anchors(&target_text).contains(anchor) {
                    dead.push(format!("{}:{line}: {target}: no such anchor", rel(file)));
                }
            }
            graph
                .entry(file.canonicalize().expect("canonical"))
                .or_default()
                .push(to);
        }
    }
    assert!(dead.is_empty(), "dead links:\n{}", dead.join("\n"));
    assert!(checked > 50, "only {checked} links found");
    let mut reached = BTreeSet::new();
    let mut todo = vec![repo().join("README.md").canonicalize().expect("README")];
    while let Some(f) = todo.pop() {
        if reached.insert(f.clone()) {
            todo.extend(graph.get(&f).into_iter().flatten().cloned());
        }
    }
    for chapter in documents() {
        let c = chapter.canonicalize().expect("chapter");
        assert!(
            reached.contains(&c),
            "{} cannot be reached from README.md",
            rel(&chapter)
        );
    }
}

/// Each chapter says first what it is for and ends with the keys and files it touches.
#[test]
fn every_chapter_says_what_it_is_for_and_ends_with_its_keys_and_files() {
    for chapter in documents()
        .iter()
        .filter(|p| p.starts_with(repo().join("docs/guide")))
    {
        let name = chapter.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name == "README.md" || name == "keys.md" {
            continue;
        }
        let text = std::fs::read_to_string(chapter).expect("read");
        let first = text.split("\n\n").nth(1).unwrap_or("");
        assert!(
            first.starts_with("What this chapter is for:"),
            "{}: begins with {first:?}",
            rel(chapter)
        );
        let last = text.rsplit("\n## ").next().unwrap_or("");
        assert!(
            last.starts_with("Keys and files\n"),
            "{}: its last section is not \"Keys and files\"",
            rel(chapter)
        );
    }
}

/// The text of docs/guide/keys.md: `eyeshell keys` as this build prints it.
fn keys_reference() -> String {
    let r = crate::support::eyeshell(&["keys"]);
    assert_eq!(r.code, Some(0), "eyeshell keys: {}", r.stderr);
    format!(
        "# Every scene key\n\n\
         Generated: the output of `eyeshell keys` (every key, its type, default and meaning),\n\
         checked against the binary by `tests/cli/docs.rs`; after changing a key, rewrite this\n\
         page with `EYESHELL_WRITE_DOCS=1 cargo test --release --test cli docs::keys`. How\n\
         scenes and `--set` use the keys: [Scenes and keys](scenes.md). From Python:\n\
         `eyeshell.keys()`.\n\n\
         ```console\n$ eyeshell keys\n{}```\n",
        r.stdout
    )
}

/// docs/guide/keys.md is the output of `eyeshell keys` of this build.
#[test]
fn keys_reference_is_current() {
    let path = repo().join("docs/guide/keys.md");
    let now = keys_reference();
    if std::env::var_os("EYESHELL_WRITE_DOCS").is_some() {
        std::fs::write(&path, &now).expect("write keys.md");
    }
    let written = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        written == now,
        "docs/guide/keys.md is not `eyeshell keys` of this build: rewrite it with \
         EYESHELL_WRITE_DOCS=1 cargo test --release --test cli docs::keys"
    );
}

/// docs/guide/outputs.md is the table of outputs as this build lays it out
/// (`eyeshell::outputs::reference`).
#[test]
fn outputs_reference_is_current() {
    let path = repo().join("docs/guide/outputs.md");
    let now = eyeshell::outputs::reference();
    if std::env::var_os("EYESHELL_WRITE_DOCS").is_some() {
        std::fs::write(&path, &now).expect("write outputs.md");
    }
    let written = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        written == now,
        "docs/guide/outputs.md is not the table of outputs of this build: rewrite it with \
         EYESHELL_WRITE_DOCS=1 cargo test --release --test cli docs::outputs"
    );
}

/// The comparison of shown output itself: elisions, numbers, whitespace.
#[test]
fn shown_output_is_compared_as_documented() {
    assert!(output_matches("a 1.0 b\n", "a  1.0000001 b\n", false));
    assert!(!output_matches("a 1.0 b\n", "a 1.1 b\n", false));
    assert!(output_matches("a 1.0 b\n", "a 7 b\n", true));
    assert!(!output_matches("a 1.0 b\n", "a 7 c\n", true));
    assert!(output_matches("x\n…\nz\n", "x\ny1\ny2\nz\n", false));
    assert!(output_matches("x\n…\nz\n", "x\nz\n", false));
    assert!(!output_matches("x\n…\nz\n", "x\ny\n", false));
    assert!(output_matches("time … s\n", "time 0.208 s\n", false));
    assert!(!output_matches("time … s\n", "elapsed 0.208 s\n", false));
    assert!(output_matches(
        "limit 16.113018 kPa (…)\n",
        "limit 16.113018 kPa (the rest)\n",
        false
    ));
    assert!(!output_matches("one\n", "one\ntwo\n", false));
    assert_eq!(
        words("eyeshell a 'b c' \"d\\\"e\" # comment"),
        (
            vec!["eyeshell".into(), "a".into(), "b c".into(), "d\"e".into()],
            None
        )
    );
    assert_eq!(words("eyeshell keys > k.txt").1.as_deref(), Some("k.txt"));
    assert_eq!(
        command_lines("eyeshell a \\\n    b\n# c\n\neyeshell d\n"),
        vec!["eyeshell a      b", "eyeshell d"]
    );
    assert_eq!(
        slug("Sweeps on a cluster (shards, Slurm, merge)"),
        "sweeps-on-a-cluster-shards-slurm-merge"
    );
    assert_eq!(
        slug("Ask for an accuracy: solver.tol"),
        "ask-for-an-accuracy-solvertol"
    );
}
