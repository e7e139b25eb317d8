//! The command line: `eyeshell solve | grow | check | keys | export | compare | converge |
//! wpd | refinement | extremes | sweep | figures | plot | fit | optics`.
//!
//! Every failure is printed as one line `eyeshell: error: <message>` on stderr. Exit codes:
//! 0 success, 2 bad input (usage, scene, validation, `--at`, an output path that may not be
//! overwritten), 1 failure of the computation or of writing the results.
//!
//! The crate is the thin binary over the `eyeshell` library: [`run`] parses (clap, `args`),
//! dispatches to one `cmd_*` function per subcommand (a file per group in `commands/`:
//! run, sweep, interop, study) and maps the library's one error to the exit code in one
//! place ([`exit_code`]). Other people's formats are the library's `eyeshell::interop`.
//! Beside the commands: `study/` (the
//! studies and the paper's figures), `charts/` (the charts drawn from runs), `image.rs`
//! (a chart written as PNG and SVG), `progress.rs` (the
//! growth bar) and `worker/` (a sweep's runs in worker processes, the hidden
//! `sweep-worker` subcommand).

mod args;
pub mod charts;
mod commands;
pub mod image;
pub mod progress;
mod shell;
pub mod study;
pub mod worker;

use std::ffi::OsString;
use std::io::Write;

use clap::Parser;

use args::{Cli, Command};
use commands::interop::{cmd_compare, cmd_export};
pub use commands::run::keys_listing;
use commands::run::{cmd_check, cmd_grow, cmd_keys, cmd_solve};
use commands::study::{cmd_converge, cmd_extremes, cmd_study};
use commands::sweep::{cmd_figures, cmd_plot, cmd_sweep};

/// Exit code for bad input: usage, scene, validation.
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code for a failed computation or a failed write.
pub const EXIT_FAILURE: i32 = 1;

// Every command returns the library's one error; its class (user's or not) was decided
// where it was made, and `run` maps it to the exit code in one place.
use eyeshell::Error;

/// Entry point of the binary: parse `std::env::args`, run, and return the exit code.
pub fn main() -> i32 {
    run(std::env::args_os())
}

/// Parse `args` (including the program name), run the command, report, return the exit code.
pub fn run<I, T>(args: I) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    let result = match &cli.command {
        Command::Solve(a) => cmd_solve(a),
        Command::Grow(a) => cmd_grow(a),
        Command::Check(a) => cmd_check(a),
        Command::Keys => cmd_keys(),
        Command::Export(a) => cmd_export(a),
        Command::Compare(a) => cmd_compare(a),
        Command::Converge(a) => cmd_converge(a),
        Command::Wpd(a) => a.scene.load().and_then(|scene| {
            cmd_study(&a.out, "wpd", &[a.scene.scene.as_path()], |dir| {
                crate::study::report::wpd(&scene, dir)
            })
        }),
        Command::Refinement(a) => {
            cmd_study(&a.out, "refinement", &[], crate::study::report::refinement)
        }
        Command::Extremes(a) => cmd_extremes(a),
        Command::Sweep(a) => cmd_sweep(a),
        Command::Figures(a) => cmd_figures(a),
        Command::Plot(a) => cmd_plot(a),
        Command::Fit(a) => commands::fit::cmd_fit(a),
        Command::Optics(a) => commands::optics::cmd_optics(a),
        Command::SweepWorker(a) => worker::serve(&a.out),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            report(&e.to_string());
            exit_code(&e)
        }
    }
}

/// The one exit-code policy: 2 for the user's mistakes, 1 for failures.
pub fn exit_code(e: &Error) -> i32 {
    if e.is_user_error() {
        EXIT_BAD_INPUT
    } else {
        EXIT_FAILURE
    }
}

/// Print one error line on stderr (control characters escaped, so it stays one line).
/// Line breaks become spaces; every other control character is shown escaped, so that a
/// name or a file's text quoted in a message cannot drive the terminal.
pub(crate) fn report(message: &str) {
    let line: String = message
        .chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect();
    let _ = writeln!(
        std::io::stderr(),
        "eyeshell: error: {}",
        eyeshell::text::one_line(&line)
    );
}

/// Help and version go to stdout with exit 0; anything else is one line and exit 2.
fn usage_error(e: clap::Error) -> i32 {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let _ = write!(std::io::stdout(), "{}", e.render());
            0
        }
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand | ErrorKind::MissingSubcommand => {
            use clap::CommandFactory;
            let names: Vec<String> = Cli::command()
                .get_subcommands()
                .filter(|c| !c.is_hide_set())
                .map(|c| c.get_name().to_string())
                .filter(|n| n != "help")
                .collect();
            report(&format!(
                "missing subcommand: one of {} (see 'eyeshell --help')",
                names.join(", ")
            ));
            EXIT_BAD_INPUT
        }
        _ => {
            // clap's message is a paragraph, then tips and usage: keep the paragraph, on one line.
            let text = e.render().to_string();
            let paragraph: Vec<&str> = text
                .lines()
                .map(str::trim)
                .skip_while(|l| l.is_empty())
                .take_while(|l| !l.is_empty())
                .collect();
            let joined = paragraph.join(" ");
            let message = joined.strip_prefix("error: ").unwrap_or(&joined);
            let message = if message.is_empty() {
                "invalid arguments"
            } else {
                message
            };
            report(&format!("{message} (see 'eyeshell --help')"));
            EXIT_BAD_INPUT
        }
    }
}

/// Write to stdout, ignoring a closed pipe (`eyeshell keys | head` must not panic).
/// Control characters other than the line breaks we print are shown escaped (the last
/// guard: names are escaped where they are printed).
pub(crate) fn out(text: &str) {
    let safe: String = text
        .split('\n')
        .map(eyeshell::text::one_line)
        .collect::<Vec<_>>()
        .join("\n");
    let _ = std::io::stdout().lock().write_all(safe.as_bytes());
}

/// A path as a summary line shows it: its control characters escaped (`\n`), so that an
/// `--out` holding a line break cannot forge a line of the report.
pub(crate) fn shown(path: &std::path::Path) -> String {
    eyeshell::text::one_line(&path.display().to_string())
}

pub(crate) fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
