//! The command line: `eyeshell solve | grow | check | keys | export | compare | converge |
//! wpd | refinement | extremes | sweep | figures | plot`.
//!
//! Every failure is printed as one line `eyeshell: error: <message>` on stderr. Exit codes:
//! 0 success, 2 bad input (usage, scene, validation, `--at`, an output path that may not be
//! overwritten), 1 failure of the computation or of writing the results.
//!
//! A subcommand is a variant of [`Command`] and a `fn cmd_*(&Args) -> Result<(), Error>`;
//! scene loading ([`SceneArgs`]) and output directories ([`eyeshell::rundir::OutputDir`]) are
//! shared, so later subcommands (grow, figures, converge) slot in the same way.

pub mod figures;
pub mod interop;
pub mod progress;
pub mod study;

use std::ffi::OsString;
use std::io::Write;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use eyeshell::rundir::run::GrowthFailure;
use eyeshell::rundir::summary::StudySummary;
use eyeshell::rundir::{self, GrowthWriter, OutputDir, Summary};
use eyeshell::scene::{Scene, SceneError, KEYS};

/// Exit code for bad input: usage, scene, validation.
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code for a failed computation or a failed write.
pub const EXIT_FAILURE: i32 = 1;

#[derive(Parser, Debug)]
#[command(
    name = "eyeshell",
    version,
    about = "Numerical solver for the morphoelastic shell model of eye growth",
    color = clap::ColorChoice::Never
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Solve the loaded elastic shell of a scene; write fields.csv, summary.json (and at.csv)
    Solve(SolveArgs),
    /// Grow the eye of a scene with [growth]; write series.csv, snapshots/ and summary.json as it goes
    Grow(GrowArgs),
    /// Validate a scene and print its effective parameters (as TOML)
    Check(SceneArgs),
    /// List every scene key with its type, default and meaning
    Keys,
    /// Write a run directory as MATLAB v5 .mat (bvp4c-style) and/or NumPy .npz files
    Export(ExportArgs),
    /// Compare a run with reference results (.mat, .npz, or another run); exit 1 beyond tolerance
    Compare(CompareArgs),
    /// Convergence ladders in N, ε and the tolerance: errors, observed orders, CSV and plots
    Converge(ConvergeArgs),
    /// Work-precision diagrams: error against seconds for each scheme and integrator
    Wpd(StudyArgs),
    /// The paper's refinement check of the const scene, for Euler and for CVODE
    Refinement(RefinementArgs),
    /// Push every parameter to its edge; write the table of outcomes (TESTING.md)
    Extremes(ExtremesArgs),
    /// Run every run of a sweep (a scene with [sweep]) in parallel: runs/<name>/, sweep.csv, summary.json
    Sweep(SweepArgs),
    /// Run the paper's scenes and draw its result figures (a)–(f) as PNG and SVG, with index.html
    Figures(FiguresArgs),
    /// Draw the output of any run or sweep (shells, profiles, axial length) as PNG and SVG
    Plot(PlotArgs),
}

#[derive(Args, Debug)]
struct FiguresArgs {
    /// Output directory: the figures, index.html, and the runs in data/
    #[arg(long, value_name = "DIR", default_value = "figures")]
    out: PathBuf,
    /// Runs at once (default: one per core)
    #[arg(long, short, value_name = "N")]
    jobs: Option<usize>,
    /// Draw again from the runs already in DIR/data (no computation)
    #[arg(long)]
    replot: bool,
    /// Print nothing on success
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct PlotArgs {
    /// A run directory (of solve or grow) or a sweep directory
    #[arg(value_name = "DIR")]
    dir: PathBuf,
    /// Where to write the pictures (default: DIR/plots)
    #[arg(long, value_name = "OUT")]
    out: Option<PathBuf>,
    /// Print nothing on success
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct SweepArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output directory: runs/<name>/ for each run, sweep.csv, summary.json (a previous eyeshell output is replaced unless --resume)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Runs at once (default: one per core)
    #[arg(long, short, value_name = "N")]
    jobs: Option<usize>,
    /// Keep the finished runs of an earlier sweep into DIR (same scene) and run only the rest
    #[arg(long)]
    resume: bool,
    /// Print nothing on success
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct ExtremesArgs {
    /// The Markdown file to write (e.g. TESTING.md)
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct ConvergeArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// The ladder of uniform node counts (at least two)
    #[arg(long, value_delimiter = ',', default_value = "51,101,201,401,801")]
    nodes: Vec<usize>,
    /// Run the whole growth on each rung (the scene must have [growth])
    #[arg(long)]
    growth: bool,
    /// Output directory (CSV tables, PNG and SVG plots)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct StudyArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output directory (CSV tables, PNG and SVG plots)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct RefinementArgs {
    /// Output directory (refinement.csv)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// A scene file and the overrides applied on top of it.
#[derive(Args, Debug)]
struct SceneArgs {
    /// The scene (TOML); see `eyeshell keys` for its keys
    #[arg(value_name = "SCENE.toml")]
    scene: PathBuf,
    /// Override a scene key, e.g. --set pressure.dP=2.5 or --set solver.scheme=trapezoid (repeatable; later wins)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

impl SceneArgs {
    fn load(&self) -> Result<Scene, Error> {
        Ok(Scene::from_file(&self.scene, &self.set)?)
    }
}

#[derive(Args, Debug)]
struct SolveArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Also write at.csv with every field at these material points Σ (in [ε, L])
    #[arg(
        long,
        value_name = "S1,S2,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    at: Vec<String>,
    /// Output directory (created whole or not at all; a previous eyeshell output is replaced)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print nothing on success
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct GrowArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output directory, written as results come (a previous eyeshell output is replaced; on failure the results so far stay)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print nothing on success and draw no progress bar
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
#[command(group = clap::ArgGroup::new("format").required(true).multiple(true).args(["mat", "npz"]))]
struct ExportArgs {
    /// The run directory (of `eyeshell solve` or `eyeshell grow`, finished or partial)
    #[arg(value_name = "RUN_DIR")]
    run: PathBuf,
    /// Write .mat: a file (elastic solve: struct `sol` with x, y) or a directory (growth: one file per output time)
    #[arg(long, value_name = "OUT")]
    mat: Option<PathBuf>,
    /// Write .npz: a file (elastic solve) or a directory (growth: one file per output time)
    #[arg(long, value_name = "OUT")]
    npz: Option<PathBuf>,
    /// Compress every .mat variable (miCOMPRESSED, as MATLAB saves by default)
    #[arg(long)]
    compress: bool,
    /// Print nothing on success
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct CompareArgs {
    /// The run: an eyeshell run directory (or a .mat / .npz file, or a directory of them)
    #[arg(value_name = "RUN_DIR")]
    run: PathBuf,
    /// Reference results: .mat or .npz files, directories of them, or eyeshell run directories
    #[arg(value_name = "REFERENCE", required = true)]
    references: Vec<PathBuf>,
    /// Absolute tolerance: a point fails when |run − ref| > tol + rtol·|ref|
    #[arg(
        long,
        value_name = "TOL",
        default_value_t = 1e-8,
        allow_negative_numbers = true
    )]
    tol: f64,
    /// Relative tolerance (see --tol)
    #[arg(
        long,
        value_name = "RTOL",
        default_value_t = 1e-8,
        allow_negative_numbers = true
    )]
    rtol: f64,
    /// Print only the error line when a field is beyond tolerance, nothing on success
    #[arg(long, short)]
    quiet: bool,
}

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
            cmd_study(&a.out, "wpd", |dir| crate::study::report::wpd(&scene, dir))
        }),
        Command::Refinement(a) => cmd_study(&a.out, "refinement", crate::study::report::refinement),
        Command::Extremes(a) => cmd_extremes(a),
        Command::Sweep(a) => cmd_sweep(a),
        Command::Figures(a) => cmd_figures(a),
        Command::Plot(a) => cmd_plot(a),
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
fn report(message: &str) {
    let line: String = message
        .chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect();
    let _ = writeln!(std::io::stderr(), "eyeshell: error: {line}");
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
fn out(text: &str) {
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// Parse and check the `--at` material points against [ε, L] of `scene`.
fn parse_at(values: &[String], scene: &Scene) -> Result<Vec<f64>, Error> {
    let (lo, hi) = (scene.solver.epsilon, scene.params.length());
    values
        .iter()
        .map(|v| {
            let t = v.trim();
            let x: f64 = t.parse().map_err(|_| {
                Error::input(format!("--at: {:?} is not a number (expected material points Σ separated by commas)", t))
            })?;
            if !x.is_finite() {
                return Err(Error::input(format!("--at: Σ = {t} must be a finite number")));
            }
            if x < lo || x > hi {
                return Err(Error::input(format!(
                    "--at: Σ = {t} is outside the shell [ε, L] = [{lo}, {hi}] (solver.epsilon, π·geometry.fraction·geometry.R0)"
                )));
            }
            Ok(x)
        })
        .collect()
}

fn cmd_extremes(a: &ExtremesArgs) -> Result<(), Error> {
    use crate::study::extremes;
    let results: Vec<_> = extremes::cases()
        .into_iter()
        .map(|c| {
            let o = extremes::run(&c);
            (c, o)
        })
        .collect();
    let text = format!("{}{}", extremes::PREAMBLE, extremes::table(&results));
    rundir::write_atomic(&a.out, text.as_bytes())
        .map_err(|e| Error::failed(format!("{}: {e}", a.out.display())))?;
    out(&format!(
        "eyeshell: {} cases written to {}\n",
        results.len(),
        a.out.display()
    ));
    Ok(())
}

fn cmd_converge(a: &ConvergeArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let max = eyeshell::mesh::MAX_NODES;
    if a.nodes.len() < 2 || a.nodes.iter().any(|&n| !(5..=max).contains(&n)) {
        return Err(Error::input(format!(
            "--nodes {}: give at least two counts, each from 5 to {max}",
            a.nodes
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(",")
        )));
    }
    if a.growth && scene.growth.is_none() {
        return Err(Error::input(format!(
            "{}: --growth needs a scene with a [growth] section",
            scene.origin
        )));
    }
    cmd_study(&a.out, "converge", |dir| {
        crate::study::report::converge(&scene, &a.nodes, a.growth, dir)
    })
}

/// Run a study into an output directory written all at once; print its summary.
fn cmd_study(
    out_dir: &std::path::Path,
    name: &str,
    study: impl FnOnce(&std::path::Path) -> Result<String, crate::study::StudyError>,
) -> Result<(), Error> {
    rundir::check_target(out_dir)?;
    let dir = OutputDir::create(out_dir)?;
    let text = study(&dir.file(""))?;
    Summary::Study(StudySummary {
        study: name.to_string(),
        sundials_version: rundir::sundials_version(),
        report: text.clone(),
    })
    .write_to(&dir.file(rundir::SUMMARY_FILE))
    .map_err(|e| Error::failed(e.to_string()))?;
    let target = dir.commit()?;
    out(&format!(
        "eyeshell: {name} written to {}\n{text}",
        target.display()
    ));
    Ok(())
}

fn cmd_solve(a: &SolveArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let at = parse_at(&a.at, &scene)?;
    let run = rundir::run::solve_into(&scene, &a.out, &at)?;
    let (solution, target) = (run.solution, run.dir);

    if !a.quiet {
        let s = &solution.stats;
        out(&format!(
            "eyeshell: solved {} ({})\n  nodes           {} ({} uniform + {} breakpoint + {} pole + {} cornea)\n  Newton          {} iteration{}, residual {:.3e}\n  first integral  {:.3e} (max |Q cos θ + r t_s sin θ − r² ΔP/2|)\n  time            {:.3} s\n  output          {}\n",
            scene.origin,
            scene.display_name(),
            s.nodes,
            s.uniform_nodes,
            s.breakpoint_nodes,
            s.pole_nodes,
            s.cornea_nodes,
            s.newton_iterations,
            if s.newton_iterations == 1 { "" } else { "s" },
            s.residual_norm,
            s.first_integral_max,
            s.wall_seconds,
            target.display(),
        ));
    }
    Ok(())
}

fn cmd_grow(a: &GrowArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    if scene.growth.is_none() {
        return Err(Error::input(format!(
            "{}: scene has no [growth] section: use `eyeshell solve`, or add growth keys (e.g. --set growth.eta0=70)",
            scene.origin
        )));
    }
    let writer = GrowthWriter::create(&a.out, &scene)?;
    let mut bar = progress::GrowthProgress::new(progress::wanted(a.quiet));
    let run = rundir::run::grow_with(&scene, writer, &mut bar);
    match &run.outcome {
        Ok(_) => bar.finish(),
        Err(_) => bar.abandon(),
    }
    let (stats, dir) = match run.outcome {
        Ok(done) => done,
        Err(failure @ GrowthFailure::Stopped { summary: None, .. }) => {
            let kept = match run.last {
                Some(r) => format!("results up to t = {:.6} are in {}", r.t, a.out.display()),
                None => format!(
                    "no snapshot was written; see {}",
                    a.out.join(rundir::SUMMARY_FILE).display()
                ),
            };
            return Err(Error::failed(format!("{failure} ({kept})")));
        }
        Err(GrowthFailure::Unwritten { error, .. }) => return Err(error.into()),
        Err(failure) => return Err(Error::failed(failure.to_string())),
    };
    if !a.quiet {
        let end = match run.last {
            Some(r) => format!(
                "t = {:.6}: axial length {:.6} mm, {} (retina − blue {:+.4} mm, retina − red {:+.4} mm)",
                r.t,
                r.axial_length,
                r.class.as_str(),
                r.retina_minus_blue,
                r.retina_minus_red
            ),
            None => "no snapshot was written".to_string(),
        };
        out(&format!(
            "eyeshell: grew {} ({})\n  final           {}\n  integrator      {} (rtol {:e}, atol {:e}), {} step{}\n  work            {} rhs evaluation{}, {} BVP solve{}, {} Newton iteration{}\n  time            {:.3} s\n  output          {}\n",
            scene.origin,
            scene.display_name(),
            end,
            scene.growth_settings.integrator.name(),
            scene.growth_settings.rtol,
            scene.growth_settings.atol,
            stats.steps,
            plural(stats.steps),
            stats.rhs_evaluations,
            plural(stats.rhs_evaluations),
            stats.bvp_solves,
            plural(stats.bvp_solves),
            stats.newton_iterations,
            plural(stats.newton_iterations),
            stats.wall_seconds,
            dir.display(),
        ));
    }
    Ok(())
}

/// Raised by the first Ctrl-C during a sweep: no new run starts.
static CANCEL: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// A first Ctrl-C stops new runs (the running ones finish and the table is written); a
/// second one exits at once.
fn install_interrupt() {
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

fn cmd_sweep(a: &SweepArgs) -> Result<(), Error> {
    use eyeshell::sweep::{run_sweep, RunStatus, SweepOptions};
    let sweep = eyeshell::scene::sweep::Sweep::from_file(&a.scene.scene, &a.scene.set)?;
    rundir::check_target(&a.out)?;
    if a.jobs == Some(0) {
        return Err(Error::input(
            "--jobs 0: give at least 1 (or leave it out: one per core)",
        ));
    }
    install_interrupt();
    let options = SweepOptions {
        jobs: a.jobs.unwrap_or(0),
        resume: a.resume,
        cancel: &CANCEL,
    };
    let quiet = a.quiet;
    let report = run_sweep(&sweep, &a.out, &options, &|r, n, total| {
        if quiet {
            return;
        }
        let _ = writeln!(
            std::io::stderr(),
            "eyeshell: [{n}/{total}] {} {}",
            r.name,
            r.status_text()
        );
    })?;
    let table = a.out.join(eyeshell::sweep::TABLE_FILE);
    let failed: Vec<String> = report
        .failed()
        .map(|r| match &r.status {
            RunStatus::Failed(m) => format!("{}: {m}", r.name),
            _ => r.name.clone(),
        })
        .collect();
    let finished = report
        .records
        .iter()
        .filter(|r| matches!(r.status, RunStatus::Ok | RunStatus::Reused))
        .count();
    let total = report.records.len();
    if report.interrupted {
        return Err(Error::failed(format!(
            "sweep interrupted: {finished} of {total} runs finished (table: {}); run again with --resume to do the rest",
            table.display()
        )));
    }
    if !failed.is_empty() {
        return Err(Error::failed(format!(
            "{} of {total} runs failed: {} (the other results are in {})",
            failed.len(),
            failed.join("; "),
            table.display()
        )));
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
        out(&format!(
            "eyeshell: sweep {} ({}): {total} run{} ok{reused}\n  table           {}\n",
            sweep.origin,
            sweep.name,
            plural(total),
            table.display()
        ));
    }
    Ok(())
}

fn cmd_figures(a: &FiguresArgs) -> Result<(), Error> {
    if a.jobs == Some(0) {
        return Err(Error::input(
            "--jobs 0: give at least 1 (or leave it out: one per core)",
        ));
    }
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
                f.png.display()
            ));
        }
        text.push_str(&format!(
            "  index           {}\n",
            a.out.join(crate::study::figures::INDEX_FILE).display()
        ));
        out(&text);
    }
    Ok(())
}

fn cmd_plot(a: &PlotArgs) -> Result<(), Error> {
    use crate::figures::plot_run;
    let target = a.out.clone().unwrap_or_else(|| a.dir.join("plots"));
    let files = plot_run(&a.dir, &target)?;
    if !a.quiet {
        out(&format!(
            "eyeshell: {} files drawn from {} into {}\n",
            files.len(),
            a.dir.display(),
            target.display()
        ));
    }
    Ok(())
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn cmd_check(a: &SceneArgs) -> Result<(), Error> {
    let scene = match a.load() {
        Err(_) if is_sweep_file(a) => return check_sweep(a),
        other => other?,
    };
    let p = &scene.params;
    let mut text = format!(
        "# {}: valid scene '{}'\n",
        scene.origin,
        scene.display_name()
    );
    for o in &scene.overrides {
        text.push_str(&format!("# --set {o}\n"));
    }
    text.push_str(&format!(
        "# L = π·fraction·R0 = {:.6} mm; cornea's limit ΔP_max = {:.6} kPa",
        p.length(),
        eyeshell::model::cornea::max_pressure(&p.cornea)
    ));
    if let Ok(alpha) = eyeshell::model::cornea::stretch(&p.cornea, p.dp) {
        text.push_str(&format!("; cornea stretch α = {alpha:.12}"));
    }
    text.push('\n');
    text.push_str(&format!("# model: {}\n", scene.components()));
    match &scene.growth {
        Some(g) => text.push_str(&format!(
            "# growth: on (η0 = {}, Γ = {}, δ = {}, t_end = {}); run it with `eyeshell grow`\n",
            g.eta0, g.gamma, g.delta, g.t_end
        )),
        None => text.push_str(
            "# growth: off (no growth.* key: a pure elastic scene; its growth keys are not shown)\n",
        ),
    }
    text.push_str(&scene.to_toml());
    out(&text);
    Ok(())
}

/// Is the scene of `a` a sweep (refused by the single-scene loader as such)?
fn is_sweep_file(a: &SceneArgs) -> bool {
    matches!(
        Scene::from_file(&a.scene, &[]),
        Err(SceneError::IsSweep { .. })
    )
}

/// `eyeshell check` of a sweep: its runs and the values each sets, then the first run's scene.
fn check_sweep(a: &SceneArgs) -> Result<(), Error> {
    let sweep = eyeshell::scene::sweep::Sweep::from_file(&a.scene, &a.set)?;
    let mut text = format!(
        "# {}: valid sweep '{}' of {} run{} over {}\n",
        sweep.origin,
        sweep.name,
        sweep.runs.len(),
        plural(sweep.runs.len()),
        sweep.keys.join(", ")
    );
    for r in &sweep.runs {
        let values: Vec<String> = r
            .values
            .iter()
            .map(|(k, v)| format!("{k} = {}", eyeshell::scene::sweep::show_value(v)))
            .collect();
        text.push_str(&format!("#   {:<24} {}\n", r.name, values.join(", ")));
    }
    if let Some(first) = sweep.runs.first() {
        text.push_str(&format!(
            "# run it with `eyeshell sweep {} --out DIR`; the first run's effective scene:\n",
            sweep.origin
        ));
        text.push_str(&first.scene.to_toml());
    }
    out(&text);
    Ok(())
}

/// The `eyeshell keys` listing.
pub fn keys_listing() -> String {
    let rows: Vec<[String; 4]> = KEYS
        .iter()
        .map(|k| {
            let range = k.rule.describe();
            let doc = if range.is_empty() {
                k.doc.to_string()
            } else {
                format!("{} [{range}]", k.doc)
            };
            [
                k.key.to_string(),
                k.type_name(),
                k.default_value().to_string(),
                doc,
            ]
        })
        .collect();
    let header = ["KEY", "TYPE", "DEFAULT", "DESCRIPTION"].map(String::from);
    let width = |i: usize| {
        rows.iter()
            .chain(std::iter::once(&header))
            .map(|r| r[i].chars().count())
            .max()
            .unwrap_or(0)
    };
    let w = [width(0), width(1), width(2)];
    let mut text = String::new();
    for r in std::iter::once(&header).chain(rows.iter()) {
        let line = format!(
            "{:w0$}  {:w1$}  {:w2$}  {}",
            r[0],
            r[1],
            r[2],
            r[3],
            w0 = w[0],
            w1 = w[1],
            w2 = w[2]
        );
        text.push_str(line.trim_end());
        text.push('\n');
    }
    text
}

fn cmd_keys() -> Result<(), Error> {
    out(&keys_listing());
    Ok(())
}

fn cmd_export(a: &ExportArgs) -> Result<(), Error> {
    use crate::interop::export::{export, Format};
    let mut jobs = Vec::new();
    if let Some(p) = &a.mat {
        jobs.push((
            p,
            Format::Mat {
                compress: a.compress,
            },
        ));
    }
    if let Some(p) = &a.npz {
        jobs.push((p, Format::Npz));
    }
    for (path, format) in jobs {
        let done = export(&a.run, path, format)?;
        if !a.quiet {
            let what = if done.growth {
                format!(
                    "{} file{} (one per output time)",
                    done.files.len(),
                    plural(done.files.len())
                )
            } else {
                "1 file".to_string()
            };
            out(&format!(
                "eyeshell: exported {} ({} nodes) to {}: {}\n",
                a.run.display(),
                done.nodes,
                done.path.display(),
                what
            ));
        }
    }
    Ok(())
}

fn cmd_compare(a: &CompareArgs) -> Result<(), Error> {
    use crate::interop::compare::{compare_paths, format_reports};
    for (name, v) in [("--tol", a.tol), ("--rtol", a.rtol)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::input(format!(
                "{name} = {v}: must be a finite number ≥ 0"
            )));
        }
    }
    let reports = compare_paths(&a.run, &a.references, a.tol, a.rtol)?;
    let failed: Vec<_> = reports
        .iter()
        .flat_map(|r| {
            r.fields
                .iter()
                .filter(|f| f.failures > 0)
                .map(move |f| (r, f))
        })
        .collect();
    if !a.quiet {
        out(&format_reports(&reports, a.tol, a.rtol));
    }
    if let Some((r, worst)) = failed
        .iter()
        .max_by(|x, y| x.1.worst_ratio.total_cmp(&y.1.worst_ratio))
    {
        return Err(Error::failed(format!(
            "{} field comparison{} beyond |Δ| ≤ {:e} + {:e}·|ref|; worst: {} in {} (max |Δ| {:.3e} at {} = {})",
            failed.len(),
            plural(failed.len()),
            a.tol,
            a.rtol,
            worst.field,
            r.reference,
            worst.max_abs,
            r.coordinate,
            worst.at_abs
        )));
    }
    Ok(())
}
