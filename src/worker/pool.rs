//! The parent's side: a pool of worker processes that runs a sweep's runs
//! ([`Workers`], a [`Runner`]).

use std::io::{BufRead, BufReader, Write};
use std::path::{Component, Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::Mutex;
use std::thread::JoinHandle;

use eyeshell::scene::sweep::SweepRun;
use eyeshell::sweep::{RunResult, RunStatus, Runner};
use eyeshell::Error;

use super::{Reply, Request, REPLY_TAG, WORKER_COMMAND};

/// The runs of one sweep into `out`, each in a worker process; idle workers wait in
/// the pool for the next run. Dropping the pool ends its workers.
pub(crate) struct Workers {
    exe: PathBuf,
    out: PathBuf,
    idle: Mutex<Vec<Worker>>,
}

impl Workers {
    /// Workers that run the runs of a sweep into `out`, started from this executable.
    pub(crate) fn new(out: &Path) -> Result<Workers, Error> {
        let exe = std::env::current_exe().map_err(|e| {
            Error::failed(
                eyeshell::Stage::Sweep,
                format!("cannot find the eyeshell executable to run the sweep's runs: {e}"),
            )
            .with_source(e)
        })?;
        Ok(Workers {
            exe,
            out: out.to_path_buf(),
            idle: Mutex::new(Vec::new()),
        })
    }

    fn take(&self) -> std::io::Result<Worker> {
        let idle = self.idle.lock().unwrap_or_else(|e| e.into_inner()).pop();
        match idle {
            Some(w) => Ok(w),
            None => Worker::start(&self.exe, &self.out),
        }
    }

    fn put_back(&self, worker: Worker) {
        self.idle
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(worker);
    }

    /// `dir` relative to the sweep's directory, as a request names it.
    fn relative(&self, dir: &Path) -> Option<String> {
        let rel = dir.strip_prefix(&self.out).ok()?;
        let parts: Option<Vec<&str>> = rel
            .components()
            .map(|c| match c {
                Component::Normal(s) => s.to_str(),
                _ => None,
            })
            .collect();
        parts.filter(|p| !p.is_empty()).map(|p| p.join("/"))
    }
}

impl Runner for Workers {
    fn run(&self, run: &SweepRun, dir: &Path) -> (RunStatus, Option<RunResult>) {
        let request = self
            .relative(dir)
            .ok_or_else(|| {
                format!(
                    "internal error (a bug; please report it): {} is not below {}",
                    dir.display(),
                    self.out.display()
                )
            })
            .and_then(|rel| Request::of(run, rel));
        let request = match request {
            Ok(r) => r,
            Err(message) => return (RunStatus::Failed(message), None),
        };
        let mut worker = match self.take() {
            Ok(w) => w,
            Err(e) => {
                let message = format!("could not start a process for the run: {e}");
                return (RunStatus::Failed(message), None);
            }
        };
        match worker.ask(&request) {
            Ok(Reply::Ok(result)) => {
                self.put_back(worker);
                (RunStatus::Ok, Some(result))
            }
            Ok(Reply::Failed { message, partial }) => {
                self.put_back(worker);
                (RunStatus::Failed(message), partial)
            }
            Err(lost) => (RunStatus::Failed(worker.ended(lost)), None),
        }
    }
}

/// Why a worker gave no reply.
enum Lost {
    /// Its pipes closed: it ended (how is in its exit status).
    Ended,
    /// It answered something that is not a reply (a bug): it is stopped.
    Garbled(String),
}

/// One worker process and its pipes; its stderr is read by a thread that keeps the last
/// line.
struct Worker {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    last_words: Option<JoinHandle<String>>,
}

impl Worker {
    fn start(exe: &Path, out: &Path) -> std::io::Result<Worker> {
        let mut child = Command::new(exe)
            .arg(WORKER_COMMAND)
            .arg(out)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let (Some(stdin), Some(stdout), Some(stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(std::io::Error::other("the worker has no pipes"));
        };
        let last_words = std::thread::spawn(move || last_line(BufReader::new(stderr)));
        Ok(Worker {
            child,
            stdin: Some(stdin),
            stdout: BufReader::new(stdout),
            last_words: Some(last_words),
        })
    }

    /// Send `request` and wait for the reply.
    fn ask(&mut self, request: &Request) -> Result<Reply, Lost> {
        let line = serde_json::to_string(request).map_err(|e| Lost::Garbled(e.to_string()))?;
        let stdin = self.stdin.as_mut().ok_or(Lost::Ended)?;
        writeln!(stdin, "{line}")
            .and_then(|()| stdin.flush())
            .map_err(|_| Lost::Ended)?;
        let mut buf = Vec::new();
        loop {
            buf.clear();
            match self.stdout.read_until(b'\n', &mut buf) {
                Ok(0) | Err(_) => return Err(Lost::Ended),
                Ok(_) => {}
            }
            let text = String::from_utf8_lossy(&buf);
            if let Some(json) = text.trim_end().strip_prefix(REPLY_TAG) {
                return serde_json::from_str(json).map_err(|e| Lost::Garbled(e.to_string()));
            }
        }
    }

    /// The worker is lost: make sure it has ended, and say how, on one line.
    fn ended(mut self, lost: Lost) -> String {
        if let Lost::Garbled(_) = lost {
            let _ = self.child.kill();
        }
        let (status, words) = self.finish();
        let how = match (&lost, status) {
            (Lost::Garbled(e), _) => {
                return format!(
                    "internal error (a bug; please report it): the run's process answered something else than a result ({e})"
                )
            }
            (_, Ok(status)) => describe(status),
            (_, Err(e)) => format!("its status is unknown: {e}"),
        };
        let words = words.trim();
        let words = if words.is_empty() {
            String::new()
        } else {
            format!("; its last words: {}", eyeshell::text::one_line(words))
        };
        format!("the run's process ended abnormally ({how}){words}")
    }

    /// Close its input (it exits), reap it and collect its last line on stderr.
    fn finish(&mut self) -> (std::io::Result<ExitStatus>, String) {
        drop(self.stdin.take());
        let status = self.child.wait();
        let words = self
            .last_words
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        (status, words)
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        if self.stdin.is_some() {
            let _ = self.finish();
        }
    }
}

/// The last non-empty line of `reader` (at most 300 characters of it), read to its end,
/// leaving out Rust's notes after a panic (`note: run with `RUST_BACKTRACE=1` ...`): the
/// line before them says what happened.
fn last_line(mut reader: impl BufRead) -> String {
    let (mut last, mut buf) = (String::new(), Vec::new());
    loop {
        buf.clear();
        match reader.read_until(b'\n', &mut buf) {
            Ok(0) | Err(_) => return last,
            Ok(_) => {
                let line = String::from_utf8_lossy(&buf);
                let line = line.trim();
                if !line.is_empty() && !line.starts_with("note: ") {
                    last = line.chars().take(300).collect();
                }
            }
        }
    }
}

/// How a process that should not have ended did: "killed by signal 6: SIGABRT; out of
/// memory or a stack overflow?", "exit status 3".
fn describe(status: ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let (name, hint) = match signal {
                6 => ("SIGABRT", "; out of memory or a stack overflow?"),
                9 => ("SIGKILL", "; out of memory (the kernel's OOM killer)?"),
                11 => ("SIGSEGV", "; a stack overflow?"),
                4 => ("SIGILL", ""),
                7 => ("SIGBUS", ""),
                8 => ("SIGFPE", ""),
                15 => ("SIGTERM", ""),
                _ => ("", ""),
            };
            return match name {
                "" => format!("killed by signal {signal}"),
                _ => format!("killed by signal {signal}: {name}{hint}"),
            };
        }
    }
    match status.code() {
        Some(code) => format!("exit status {code}"),
        None => status.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_line_is_kept_short() {
        let text = "first\nthread 'main' has overflowed its stack\nfatal runtime error: stack overflow\n\n";
        assert_eq!(
            last_line(text.as_bytes()),
            "fatal runtime error: stack overflow"
        );
        let panic = "thread 'main' panicked at src/a.rs:1:2:\ncapacity overflow\nnote: run with `RUST_BACKTRACE=1` environment variable to display a backtrace\n";
        assert_eq!(last_line(panic.as_bytes()), "capacity overflow");
        let long = "x".repeat(1000);
        assert_eq!(last_line(long.as_bytes()).len(), 300);
        assert_eq!(last_line(&b""[..]), "");
    }

    #[cfg(unix)]
    #[test]
    fn ends_are_described_with_their_signal() {
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(
            describe(ExitStatus::from_raw(6)),
            "killed by signal 6: SIGABRT; out of memory or a stack overflow?"
        );
        assert_eq!(describe(ExitStatus::from_raw(31)), "killed by signal 31");
        assert_eq!(describe(ExitStatus::from_raw(3 << 8)), "exit status 3");
    }
}
