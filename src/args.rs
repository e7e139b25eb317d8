//! The command line's arguments (clap): one struct per subcommand.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use eyeshell::scene::Scene;
use eyeshell::Error;

#[derive(Parser, Debug)]
#[command(
    name = "eyeshell",
    version,
    about = "Numerical solver for the morphoelastic shell model of eye growth",
    color = clap::ColorChoice::Never
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
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
    /// The best-focus surfaces of the scene's schematic eye (optics.*): surfaces.csv, optics.json and a figure
    Optics(OpticsArgs),
    /// Fit model parameters to measured axial lengths (Levenberg–Marquardt on IDAS's sensitivities): fit.json, scene.toml, fit.png
    Fit(FitArgs),
    /// Run the runs of a sweep that `eyeshell sweep` sends on stdin (its worker processes)
    #[command(name = "sweep-worker", hide = true)]
    SweepWorker(SweepWorkerArgs),
}

/// `eyeshell sweep-worker OUT`: a worker process of `eyeshell sweep` (src/worker).
#[derive(Args, Debug)]
pub(crate) struct SweepWorkerArgs {
    /// The sweep's output directory
    #[arg(value_name = "DIR")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct FiguresArgs {
    /// Output directory: the figures, index.html, and the runs in data/
    #[arg(long, value_name = "DIR", default_value = "figures")]
    pub(crate) out: PathBuf,
    /// Runs and drawings at once (default: one per core and one more, which computes while a run waits for the disk)
    #[arg(long, short, value_name = "N")]
    pub(crate) jobs: Option<usize>,
    /// Draw again from the runs already in DIR/data (no computation)
    #[arg(long)]
    pub(crate) replot: bool,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct PlotArgs {
    /// A run directory (of solve or grow) or a sweep directory; several growth runs are drawn together into OUT/compare.png (axial length, refraction_D and the peripheral refraction; needs --out)
    #[arg(value_name = "DIR", required = true, num_args = 1..)]
    pub(crate) dirs: Vec<PathBuf>,
    /// Where to write the pictures (default: DIR/plots); drawn whole into a new directory, replacing only an earlier plot or an empty directory (never the run or sweep drawn, nor a directory holding it)
    #[arg(long, value_name = "OUT")]
    pub(crate) out: Option<PathBuf>,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

/// `eyeshell sweep SCENE --out DIR ...`, or `eyeshell sweep merge|status DIR`. SCENE and
/// --out are required unless a subcommand is given (hence Options, always Some then).
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub(crate) struct SweepArgs {
    #[command(subcommand)]
    pub(crate) action: Option<SweepAction>,
    /// The scene (TOML) with a [sweep] table; see `eyeshell keys` for its keys
    #[arg(value_name = "SCENE.toml", required = true)]
    pub(crate) scene: Option<PathBuf>,
    /// Override a scene key, e.g. --set pressure.dP=2.5 (repeatable; later wins; not a swept key)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    /// Output directory: runs/<name>/ for each run, sweep.csv, summary.json (an earlier sweep there is replaced unless --resume or --shard; nothing else is)
    #[arg(long, value_name = "DIR", required = true)]
    pub(crate) out: Option<PathBuf>,
    /// Runs at once (default: one per core)
    #[arg(long, short, value_name = "N")]
    pub(crate) jobs: Option<usize>,
    /// Keep the finished runs of an earlier sweep into DIR (same scene) and run only the rest
    #[arg(long)]
    pub(crate) resume: bool,
    /// Run only shard K of N of the runs (writes DIR/runs/<name>/ and DIR/shards/K.json; `eyeshell sweep merge DIR` makes the table), or `slurm`: K and N from the Slurm job array
    #[arg(long, value_name = "K/N|slurm", conflicts_with = "slurm_script")]
    pub(crate) shard: Option<String>,
    /// Print an sbatch script that runs the sweep as a Slurm job array, one shard per task (runs nothing; each task's --jobs is its CPUs)
    #[arg(long, conflicts_with = "jobs")]
    pub(crate) slurm_script: bool,
    /// With --slurm-script: the number of shards (array tasks); default: one per run, at most 100
    #[arg(long, value_name = "N", requires = "slurm_script")]
    pub(crate) shards: Option<usize>,
    /// With --slurm-script: each task's time limit (sbatch --time, e.g. 2:00:00)
    #[arg(long, value_name = "TIME", requires = "slurm_script")]
    pub(crate) time: Option<String>,
    /// With --slurm-script: CPUs per task (sbatch --cpus-per-task; each shard runs that many runs at once)
    #[arg(long, value_name = "C", requires = "slurm_script")]
    pub(crate) cpus_per_task: Option<usize>,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

/// `eyeshell sweep merge DIR`, `eyeshell sweep status DIR`.
#[derive(Subcommand, Debug)]
pub(crate) enum SweepAction {
    /// Assemble DIR/sweep.csv and DIR/summary.json from the runs of the shards of a sweep; list missing and failed runs (exit 1 if any)
    Merge(SweepDirArgs),
    /// Say which runs of a sharded sweep in DIR are done, failed or missing, writing nothing (exit 1 unless all are done)
    Status(SweepDirArgs),
}

#[derive(Args, Debug)]
pub(crate) struct SweepDirArgs {
    /// The sweep's output directory (the --out of its shards)
    #[arg(value_name = "DIR")]
    pub(crate) dir: PathBuf,
    /// Print nothing when every run is done
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct ExtremesArgs {
    /// The Markdown file to write (e.g. TESTING.md); an existing file is replaced only if eyeshell wrote it
    #[arg(long, value_name = "FILE")]
    pub(crate) out: PathBuf,
    /// Replace an existing file even if eyeshell did not write it
    #[arg(long)]
    pub(crate) force: bool,
}

#[derive(Args, Debug)]
pub(crate) struct ConvergeArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// The ladder of uniform node counts (at least two)
    #[arg(long, value_delimiter = ',', default_value = "51,101,201,401,801")]
    pub(crate) nodes: Vec<usize>,
    /// Run the whole growth on each rung (the scene must have [growth])
    #[arg(long)]
    pub(crate) growth: bool,
    /// Output directory (CSV tables, PNG and SVG plots)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct StudyArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Output directory (CSV tables, PNG and SVG plots)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct RefinementArgs {
    /// Output directory (refinement.csv)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
}

/// A scene file and the overrides applied on top of it.
#[derive(Args, Debug)]
pub(crate) struct SceneArgs {
    /// The scene (TOML); see `eyeshell keys` for its keys
    #[arg(value_name = "SCENE.toml")]
    pub(crate) scene: PathBuf,
    /// Override a scene key, e.g. --set pressure.dP=2.5 or --set solver.scheme=trapezoid (repeatable; later wins)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
}

impl SceneArgs {
    pub(crate) fn load(&self) -> Result<Scene, Error> {
        Ok(Scene::from_file(&self.scene, &self.set)?)
    }
}

#[derive(Args, Debug)]
pub(crate) struct SolveArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Also write at.csv with every field at these material points Σ (in [ε, L])
    #[arg(
        long,
        value_name = "S1,S2,...",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub(crate) at: Vec<String>,
    /// Output directory (created whole or not at all; only an earlier solve output or an empty directory is replaced)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct GrowArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Output directory, written as results come (only an earlier growth run or an empty directory is replaced; on failure the results so far stay)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Forward sensitivities of the run (IDAS) with respect to these scene keys, into sensitivities.csv: growth.eta0, growth.Gamma, growth.delta, fibres.D (scenes with fibres), material.C, material.bending, pressure.dP, stimulus.blue.z_B, growth.schedule_tau, growth.schedule_centre, growth.schedule_width (the scene's named schedule), geometry.R0 (a directional difference of two more runs) (stimulus.red.offset only moves the classification: refused)
    #[arg(long, value_name = "KEY,KEY,...", value_delimiter = ',')]
    pub(crate) sensitivities: Vec<String>,
    /// Include the sensitivities in the local error test (IDASetSensErrCon): 4–75× slower, and the sensitivities converge with solver.rtol (see BENCHMARKS.md)
    #[arg(long, requires = "sensitivities")]
    pub(crate) sensitivity_error_control: bool,
    /// Threads for solver.tol's rounds of three runs: 1 runs them one after another, 2 (or more) the two test runs beside the delivered one; default: the environment's EYESHELL_JOBS, else 2 when the machine has a second core. Results are the same bit for bit
    #[arg(long, short, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub(crate) jobs: Option<u64>,
    /// Print nothing on success and draw no progress bar
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

/// `eyeshell fit SCENE --data DATA.csv --fit KEY,KEY,... --out DIR`.
#[derive(Args, Debug)]
pub(crate) struct OpticsArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Output directory: surfaces.csv, optics.json, optics.png and optics.svg (created whole or not at all; a previous eyeshell output is replaced)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// The eye at growth time T (in [0, growth.t_end], or with time.unit the age T in [time.start, time.end]; default the start): for optics keys given as tables over t
    #[arg(long, value_name = "T")]
    pub(crate) at: Option<f64>,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct FitArgs {
    /// The scene (TOML) of a fit of one scene (with --data); see `eyeshell keys` for its keys
    #[arg(
        value_name = "SCENE.toml",
        required_unless_present = "arm",
        conflicts_with = "arm"
    )]
    pub(crate) scene: Option<PathBuf>,
    /// Override a scene key, e.g. --set solver.nodes=101 (repeatable; later wins; applies to every arm's scene)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    /// The observations: a CSV file with the header t (or age), then axial_length and/or refraction_D, each optionally with its σ (sigma_axial_length or sigma, sigma_refraction_D); t in [0, growth.t_end], lengths in mm, refractions in D
    #[arg(
        long,
        value_name = "DATA.csv",
        required_unless_present = "arm",
        conflicts_with = "arm"
    )]
    pub(crate) data: Option<PathBuf>,
    /// An arm of a joint fit, NAME=SCENE.toml:DATA.csv (repeatable, two or more): the arms share every --fit key and each has its own value of every --per-arm key
    #[arg(long, value_name = "NAME=SCENE:DATA")]
    pub(crate) arm: Vec<String>,
    /// The parameters to fit, starting from the scene's values: any real-valued key of the model (growth.eta0, growth.Gamma, pressure.dP, optics.surfaces[0].radius, ...); the keys with a forward sensitivity (growth.eta0, growth.Gamma, growth.delta, fibres.D, material.C, material.bending, pressure.dP, stimulus.blue.z_B, growth.schedule_tau, growth.schedule_centre, growth.schedule_width, geometry.R0) take IDAS's for the axial length, every other column is a finite difference
    #[arg(
        long,
        value_name = "KEY,KEY,...",
        value_delimiter = ',',
        required = true
    )]
    pub(crate) fit: Vec<String>,
    /// Keys each arm of a joint fit has its own value of (with --arm), starting from each arm's scene
    #[arg(long, value_name = "KEY,KEY,...", value_delimiter = ',')]
    pub(crate) per_arm: Vec<String>,
    /// Output directory: fit.json, scene.toml (the fitted scene), residuals.csv, curve.csv, fit.png and fit.svg (created whole or not at all; only an earlier fit output or an empty directory is replaced)
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// The most Levenberg–Marquardt iterations (1 to 1000)
    #[arg(long, value_name = "N", default_value_t = 50, value_parser = clap::value_parser!(u16).range(1..=1000))]
    pub(crate) max_iterations: u16,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
#[command(group = clap::ArgGroup::new("format").required(true).multiple(true).args(["mat", "npz"]))]
pub(crate) struct ExportArgs {
    /// The run directory (of `eyeshell solve` or `eyeshell grow`, finished or partial)
    #[arg(value_name = "RUN_DIR")]
    pub(crate) run: PathBuf,
    /// Write .mat: a file (elastic solve: struct `sol` with x, y) or a directory (growth: one file per output time)
    #[arg(long, value_name = "OUT")]
    pub(crate) mat: Option<PathBuf>,
    /// Write .npz: a file (elastic solve) or a directory (growth: one file per output time)
    #[arg(long, value_name = "OUT")]
    pub(crate) npz: Option<PathBuf>,
    /// Compress every .mat variable (miCOMPRESSED, as MATLAB saves by default)
    #[arg(long)]
    pub(crate) compress: bool,
    /// Replace an existing file even if eyeshell did not write it (never one of the run's own files)
    #[arg(long)]
    pub(crate) force: bool,
    /// Print nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct CompareArgs {
    /// The run: an eyeshell run directory (or a .mat / .npz file, or a directory of them)
    #[arg(value_name = "RUN_DIR")]
    pub(crate) run: PathBuf,
    /// Reference results: .mat or .npz files, directories of them, or eyeshell run directories
    #[arg(value_name = "REFERENCE", required = true)]
    pub(crate) references: Vec<PathBuf>,
    /// Absolute tolerance: a point fails when |run − ref| > tol + rtol·|ref|
    #[arg(
        long,
        value_name = "TOL",
        default_value_t = 1e-8,
        allow_negative_numbers = true
    )]
    pub(crate) tol: f64,
    /// Relative tolerance (see --tol)
    #[arg(
        long,
        value_name = "RTOL",
        default_value_t = 1e-8,
        allow_negative_numbers = true
    )]
    pub(crate) rtol: f64,
    /// The struct of each reference .mat file that holds the result: NAME, or NAME(K) for element K of a struct array (default: sol, element 1, if present, else the top-level variables)
    #[arg(long, value_name = "NAME[(K)]")]
    pub(crate) field: Option<eyeshell::interop::compare::FieldSpec>,
    /// Print only the error line when a field is beyond tolerance, nothing on success
    #[arg(long, short)]
    pub(crate) quiet: bool,
}
