//! The worker's side: `eyeshell sweep-worker OUT` serves run requests until its input
//! ends (see the module doc of `worker` for the protocol).

use std::io::{BufRead, Write};
use std::path::{Component, Path, PathBuf};
use std::sync::mpsc;

use eyeshell::sweep::{run_scene, RunStatus};
use eyeshell::Error;

use super::{scene_of, Reply, Request, ABORT_ENV, REPLY_TAG};

/// Serve the runs of the sweep into `out`, one request line at a time.
pub(crate) fn serve(out: &Path) -> Result<(), Error> {
    // A Ctrl-C at the terminal reaches the workers too: the parent alone decides.
    let _ = ctrlc::set_handler(|| {});
    let requests = read_requests();
    let abort_on = std::env::var(ABORT_ENV).ok();
    let mut stdout = std::io::stdout().lock();
    for line in requests {
        let reply = answer(out, &line, abort_on.as_deref());
        let json = serde_json::to_string(&reply)
            .map_err(|e| Error::failed_by(eyeshell::Stage::Sweep, e))?;
        writeln!(stdout, "{REPLY_TAG}{json}")
            .and_then(|()| stdout.flush())
            .map_err(|e| {
                Error::failed(eyeshell::Stage::Sweep, format!("sweep worker: stdout: {e}"))
                    .with_source(e)
            })?;
    }
    Ok(())
}

/// The request lines, read by a thread that ends the process when its input ends: the
/// parent is done with this worker, or gone, and a run in progress is of no use to anyone.
fn read_requests() -> mpsc::Receiver<String> {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if send.send(line).is_err() {
                break;
            }
        }
        std::process::exit(0);
    });
    receive
}

/// Run the request `line` and say how it ended.
fn answer(out: &Path, line: &str, abort_on: Option<&str>) -> Reply {
    let failed = |message: String| Reply::Failed {
        message,
        partial: None,
    };
    let request: Request = match serde_json::from_str(line) {
        Ok(r) => r,
        Err(e) => {
            return failed(format!(
            "internal error (a bug; please report it): the run's process got a bad request: {e}"
        ))
        }
    };
    let Some(dir) = below(out, &request.dir) else {
        return failed(format!(
            "internal error (a bug; please report it): the run's process was asked to write outside the sweep ({})",
            eyeshell::text::one_line(&request.dir)
        ));
    };
    let scene = match scene_of(&request) {
        Ok(s) => s,
        Err(e) => return failed(e.to_string()),
    };
    if abort_on.is_some_and(|name| dir.file_name().is_some_and(|n| n == name)) {
        std::process::abort();
    }
    match run_scene(&scene, &dir) {
        (RunStatus::Ok, Some(result)) => Reply::Ok(result),
        (RunStatus::Failed(message), partial) => Reply::Failed { message, partial },
        (status, _) => failed(format!(
            "internal error (a bug; please report it): the run ended as {status:?}"
        )),
    }
}

/// `rel` (plain components only) inside `out`.
fn below(out: &Path, rel: &str) -> Option<PathBuf> {
    let rel = Path::new(rel);
    let plain = rel.components().next().is_some()
        && rel.components().all(|c| matches!(c, Component::Normal(_)));
    plain.then(|| out.join(rel))
}
