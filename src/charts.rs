//! The charts eyeshell draws from its results: the panels of the paper's result figures (its
//! section 3; docs/MODEL.md §8), `eyeshell plot`'s pictures of any run, the fit's and the
//! optics' charts; drawn from run directories read back from disk
//! ([`eyeshell::rundir::rundata`]), as PNG and SVG. "Figures" names only the paper's
//! figures (`eyeshell figures`, `study/figures.rs`, which runs their scenes).
//!
//! Panels are built by small functions (a shell cross-section, stretch profiles, axial
//! length against time, retinas); [`paper_figures`] composes them into figures (a)–(f) and
//! an HTML index, [`plot_run`] into the pictures of one run or of a sweep.

use std::path::{Path, PathBuf};

use crate::image::{self, ImageError};
use eyeshell::interop::export::{bad, ExportError, RunSnapshot};
use eyeshell::model::stimulus::Surface;
use eyeshell::rundir::rundata::{self, column, RunData, RunKind, SeriesPoint};
use eyeshell::rundir::Summary;
use eyeshell::scene::Scene;
use eyeshell::text::excerpt;
use eyeshell_plot::{self as plot, colormap, Figure, Rgb, Series, SeriesStyle};

/// Size of one panel, in pixels.
pub const PANEL: (u32, u32) = (820, 620);

const BLUE: Rgb = Rgb(31, 90, 220);
const RED: Rgb = Rgb(210, 40, 40);
const GREY: Rgb = Rgb(150, 150, 150);
const BLACK: Rgb = Rgb(0, 0, 0);

/// A figure that was written: its files and its caption (for the index).
#[derive(Clone, Debug)]
pub struct Written {
    pub id: String,
    pub title: String,
    pub caption: String,
    pub png: PathBuf,
    pub svg: PathBuf,
}

/// Why figures could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// A run that cannot be read back (the user's when it is missing or malformed).
    #[error(transparent)]
    Read(#[from] ExportError),
    /// Drawing or writing a picture failed (a missing font, a full disk): not the user's.
    #[error(transparent)]
    Plot(#[from] ImageError),
}

impl FigureError {
    /// Is it the user's (a run that is missing or malformed)?
    pub fn is_bad_input(&self) -> bool {
        matches!(self, FigureError::Read(e) if e.bad_input)
    }
}

impl From<FigureError> for eyeshell::Error {
    fn from(e: FigureError) -> Self {
        match e {
            FigureError::Read(e) => e.into(),
            FigureError::Plot(e) => eyeshell::Error::failed(e.to_string()),
        }
    }
}

// ---------------------------------------------------------------- geometry of a snapshot

/// The curves of a shell at one snapshot: mid-surface, outer face and retina (inner face),
/// each as (z, r) points from the pole to the cornea, and η at every node.
struct Shell {
    mid: Vec<(f64, f64)>,
    outer: Vec<(f64, f64)>,
    retina: Vec<(f64, f64)>,
    eta: Vec<f64>,
}

fn shell(s: &RunSnapshot) -> Result<Shell, ExportError> {
    let (z, r, theta, h) = (
        column(s, "z")?,
        column(s, "r")?,
        column(s, "theta")?,
        column(s, "h")?,
    );
    let (zr, rr) = (column(s, "z_retina")?, column(s, "r_retina")?);
    let outer = (0..z.len())
        .map(|i| {
            (
                z[i] + 0.5 * h[i] * theta[i].cos(),
                r[i] + 0.5 * h[i] * theta[i].sin(),
            )
        })
        .collect();
    Ok(Shell {
        mid: z.iter().copied().zip(r.iter().copied()).collect(),
        outer,
        retina: zr.into_iter().zip(rr).collect(),
        eta: column(s, "eta")?,
    })
}

/// The best-focus surface as (z, r) points for φ in [0, φ_max].
fn surface_points(s: &Surface) -> Vec<(f64, f64)> {
    (0..=80)
        .map(|k| s.point(s.phi_max * k as f64 / 80.0))
        .collect()
}

fn surfaces(scene: &Scene) -> [Series; 2] {
    [
        Series::new(
            "blue best focus",
            surface_points(&scene.blue()),
            SeriesStyle::DashedLine,
        )
        .color(BLUE),
        Series::new(
            "red best focus",
            surface_points(&scene.red()),
            SeriesStyle::DashedLine,
        )
        .color(RED),
    ]
}

/// The largest η over snapshots (the common top of the colour scale).
fn eta_max(snapshots: &[&RunSnapshot]) -> f64 {
    snapshots
        .iter()
        .filter_map(|s| s.table.column("eta"))
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

fn t_label(t: f64) -> String {
    format!("t = {}", trim(t))
}

/// The time axis of a run's figures: the scene's ages when it counts in them (time.unit),
/// else the model's t, so that a scene in years is drawn in years and one without a unit
/// exactly as before.
#[derive(Clone, Copy, Debug)]
pub struct TimeAxis {
    /// The clock and growth.t_end of a scene with ages; None: t.
    clock: Option<(eyeshell::growth::schedule::Clock, f64, &'static str)>,
}

impl TimeAxis {
    /// The axis of `scene`.
    pub fn of(scene: &Scene) -> TimeAxis {
        TimeAxis {
            clock: scene
                .growth
                .as_ref()
                .and_then(|g| Some((g.clock, g.t_end, g.age_unit()?))),
        }
    }

    /// The axis of several runs drawn together: ages when every run counts in the same
    /// unit, else t (ages in years and t on one axis would mislead).
    fn of_runs<'a>(scenes: impl IntoIterator<Item = &'a Scene>) -> TimeAxis {
        let mut axes = scenes.into_iter().map(TimeAxis::of);
        let Some(first) = axes.next() else {
            return TimeAxis { clock: None };
        };
        let unit = first.clock.map(|c| c.2);
        if axes.all(|a| a.clock.map(|c| c.2) == unit) {
            first
        } else {
            TimeAxis { clock: None }
        }
    }

    /// Where time `t` of a run with this axis lies on it.
    pub fn x(&self, t: f64) -> f64 {
        match self.clock {
            Some((clock, t_end, _)) => clock.age(t, t_end),
            None => t,
        }
    }

    /// The axis' title: "age (years)", or "t".
    pub fn title(&self) -> String {
        match self.clock {
            Some((_, _, unit)) => format!("age ({unit})"),
            None => "t".to_string(),
        }
    }

    /// A legend's name for time `t`: "age 3.5 years", or "t = 0.2".
    fn label(&self, t: f64) -> String {
        match self.clock {
            Some((_, _, unit)) => format!("age {} {unit}", trim(self.x(t))),
            None => t_label(t),
        }
    }
}

/// The paper's figures are in t.
const T: TimeAxis = TimeAxis { clock: None };

/// A number as short as it reads: 0.1, 1, 23.58.
fn trim(x: f64) -> String {
    let s = format!("{x:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

// ---------------------------------------------------------------- panels

/// A cross-section of the shell at one snapshot: the mid-surface shaded by η, both faces,
/// the retina, and the blue and red best-focus surfaces.
fn shell_panel(
    title: String,
    scene: &Scene,
    s: &RunSnapshot,
    eta_top: f64,
) -> Result<Figure, ExportError> {
    let sh = shell(s)?;
    let [blue, red] = surfaces(scene);
    let mut fig = Figure::new(title, "z (mm)", "r (mm)")
        .with(
            Series::new("shell, shaded by η", sh.mid, SeriesStyle::Line)
                .width(7)
                .shaded(sh.eta)
                .no_legend(),
        )
        .with(
            Series::new("outer face", sh.outer, SeriesStyle::Line)
                .color(BLACK)
                .width(1)
                .no_legend(),
        )
        .with(
            Series::new("retina", sh.retina, SeriesStyle::Line)
                .color(BLACK)
                .width(2),
        )
        .with(blue)
        .with(red)
        .color_scale("η (1/mm)", 0.0, eta_top);
    fig.aspect_equal = true;
    Ok(fig)
}

/// One quantity against σ (grown unloaded arclength) for several snapshots, coloured by t.
fn profile_panel(
    title: &str,
    field: &str,
    label: &str,
    snaps: &[&RunSnapshot],
    axis: TimeAxis,
) -> Result<Figure, ExportError> {
    let mut fig = Figure::new(title, "σ (mm)", label);
    // Evenly spread along the colour map by order (the times themselves cluster near 0).
    let last = snaps.len().saturating_sub(1).max(1) as f64;
    for (k, s) in snaps.iter().enumerate() {
        let pts = column(s, "sigma")?
            .into_iter()
            .zip(column(s, field)?)
            .collect();
        let c = colormap(0.85 * k as f64 / last);
        fig = fig.with(Series::new(axis.label(s.t), pts, SeriesStyle::Line).color(c));
    }
    Ok(fig)
}

/// Axial length against time for several runs: against age when they all count in the
/// same unit ([`TimeAxis::of_runs`]), else against t.
fn axial_panel(title: &str, runs: &[(String, &RunData)]) -> Figure {
    let ages = TimeAxis::of_runs(runs.iter().map(|(_, r)| &r.scene));
    let mut fig = Figure::new(title, ages.title(), "axial length (mm)");
    for (k, (name, run)) in runs.iter().enumerate() {
        let axis = if ages.clock.is_some() {
            TimeAxis::of(&run.scene)
        } else {
            ages
        };
        let pts = run
            .timeline()
            .iter()
            .map(|p| (axis.x(p.t), p.axial_length))
            .collect();
        fig = fig
            .with(Series::new(name.clone(), pts, SeriesStyle::Line).color(plot::PALETTE[k % 10]));
    }
    fig
}

// ---------------------------------------------------------------- captions

/// The parameters of a scene, as the paper's captions give them.
pub fn parameters(scene: &Scene) -> String {
    let p = &scene.params;
    let thickness = match p.thickness {
        eyeshell::model::params::Thickness::Uniform => format!("uniform H = {} mm", trim(p.h0)),
        eyeshell::model::params::Thickness::NonUniform => {
            "non-uniform H(Σ) (docs/MODEL.md §4)".to_string()
        }
    };
    let mut text = format!(
        "ΔP = {} kPa, C = {} kPa, D = {} kPa, E_b = {} kPa·mm³, {thickness}",
        trim(p.dp),
        trim(p.c),
        trim(p.d),
        trim(p.e_b)
    );
    if let Some(g) = &scene.growth {
        text.push_str(&format!(
            ", η0 = {} /mm, Γ = {} mm, δ = {} mm",
            trim(g.eta0),
            trim(g.gamma),
            trim(g.delta)
        ));
    }
    text.push_str(&format!(
        "; {} nodes, {}",
        scene.solver.nodes,
        numerics(scene)
    ));
    text
}

fn numerics(scene: &Scene) -> String {
    let scheme = match scene.solver.scheme {
        eyeshell::bvp::settings::Scheme::Trapezoid => "trapezoid (order 2)",
        eyeshell::bvp::settings::Scheme::HermiteSimpson => "Hermite–Simpson (order 4)",
    };
    match (&scene.growth, scene.growth_settings.integrator) {
        (None, _) => scheme.to_string(),
        (Some(_), eyeshell::growth::Integrator::Cvode) => {
            format!("{scheme}, CVODE BDF rtol {:e}", scene.growth_settings.rtol)
        }
        (Some(_), eyeshell::growth::Integrator::Euler) => {
            format!(
                "{scheme}, explicit Euler, {} steps",
                scene.growth_settings.steps
            )
        }
        (Some(_), eyeshell::growth::Integrator::Ida) => {
            format!(
                "{scheme}, IDA BDF on the coupled DAE rtol {:e}",
                scene.growth_settings.rtol
            )
        }
    }
}

// ---------------------------------------------------------------- the paper's figures

/// The run directories the paper's figures are drawn from (each a run or a sweep's run).
pub struct PaperRuns {
    pub constant: RunData,
    pub thick: RunData,
    /// (D, run), increasing D.
    pub fibre: Vec<(f64, RunData)>,
    /// (Γ, δ, run).
    pub grid: Vec<(f64, f64, RunData)>,
}

impl PaperRuns {
    /// Read the runs under `data`: `const/`, `thick/`, and the sweeps `fibre/`, `grow/`
    /// (as `eyeshell figures` writes them).
    pub fn read(data: &Path) -> Result<PaperRuns, FigureError> {
        let fibre = read_fibre(&data.join("fibre"))?;
        let grid = read_grid(&data.join("grow"))?;
        Ok(PaperRuns {
            constant: read_single(&data.join("const"))?,
            thick: read_single(&data.join("thick"))?,
            fibre,
            grid,
        })
    }
}

/// The fibre sweep's runs as (D, run), increasing D.
pub fn read_fibre(dir: &Path) -> Result<Vec<(f64, RunData)>, FigureError> {
    let mut fibre: Vec<(f64, RunData)> = sweep_runs(dir)?
        .into_iter()
        .map(|r| (r.scene.params.d, r))
        .collect();
    fibre.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(fibre)
}

/// The growth-zone grid's runs as (Γ, δ, run), in the order of its table.
pub fn read_grid(dir: &Path) -> Result<Vec<(f64, f64, RunData)>, FigureError> {
    Ok(sweep_runs(dir)?
        .into_iter()
        .map(|r| {
            let g = r.scene.growth.clone().unwrap_or_default();
            (g.gamma, g.delta, r)
        })
        .collect())
}

/// A one-run scene's run: a run directory, or a sweep of one run.
pub fn read_single(dir: &Path) -> Result<RunData, FigureError> {
    Ok(sweep_or_run(dir)?)
}

/// The longest run directory a sweep's summary may name: a sweep names them `runs/<name>`,
/// its names cut to at most 100 bytes.
const MAX_RUN_DIR: usize = 255;

/// Every run of a sweep directory, in the order of its table.
pub fn sweep_runs(dir: &Path) -> Result<Vec<RunData>, ExportError> {
    let path = dir.join(eyeshell::rundir::SUMMARY_FILE);
    if let Err(e) = std::fs::metadata(&path) {
        return Err(bad(format!("{}: not a sweep output ({e})", dir.display())));
    }
    let text = eyeshell::rundir::read::read_text(&path, eyeshell::rundir::read::MAX_SUMMARY_BYTES)?;
    let Summary::Sweep(sweep) = Summary::parse(&path, &text)? else {
        return Err(bad(format!(
            "{}: not a sweep output (no runs in summary.json)",
            dir.display()
        )));
    };
    sweep
        .runs
        .iter()
        .filter(|r| r.status == "ok" || r.status == "reused" || r.status == "failed")
        .map(|r| {
            // A cohort kept as a table (`per_run = "table"`) has rows, not run directories:
            // what there is to see of it is its population figure, drawn by the sweep.
            if r.dir.is_empty() && dir.join(eyeshell::sweep::compact::CHECKPOINT_FILE).is_file() {
                let figure = dir.join(format!("{}.png", crate::commands::sweep::POPULATION_FIGURE));
                let shown = if figure.is_file() {
                    format!("its figure is {}", crate::shown(&figure))
                } else {
                    "its figure (population.png) is drawn once every eye has run".to_string()
                };
                return Err(bad(format!(
                    "{}: a cohort kept as a table (per_run = \"table\") has no run directories to draw, only its rows (series.csv, sweep.csv) and population bands: {shown}; set per_run = \"directory\" for a directory per eye",
                    crate::shown(dir)
                )));
            }
            // A run lives below the sweep: a plain relative path, no `..`, not the sweep,
            // nothing a message could not show, no longer than a sweep names its runs.
            let inside = !r.dir.is_empty()
                && r.dir.len() <= MAX_RUN_DIR
                && !r.dir.chars().any(char::is_control)
                && Path::new(&r.dir)
                    .components()
                    .all(|c| matches!(c, std::path::Component::Normal(_)));
            if !inside {
                return Err(bad(format!(
                    "{}: run \"{}\" points outside the sweep's runs (\"{}\")",
                    path.display(),
                    excerpt(&r.name, 80),
                    excerpt(&r.dir, 80)
                )));
            }
            rundata::read(&dir.join(&r.dir))
        })
        .collect()
}

/// The one run in `dir`: a sweep's only run (as `eyeshell figures` writes it) or a run
/// directory. Which one is decided by summary.json, never by trying one after the other: the
/// error of the first would be lost, and the second would blame the wrong file.
fn sweep_or_run(dir: &Path) -> Result<RunData, ExportError> {
    if is_sweep(dir) {
        only_run(dir)
    } else {
        rundata::read(dir)
    }
}

fn only_run(dir: &Path) -> Result<RunData, ExportError> {
    sweep_runs(dir)?
        .into_iter()
        .next()
        .ok_or_else(|| bad(format!("{}: the sweep has no finished run", dir.display())))
}

fn snapshots_at<'a>(run: &'a RunData, times: &[f64]) -> Vec<&'a RunSnapshot> {
    let mut out: Vec<&RunSnapshot> = times.iter().filter_map(|&t| run.snapshot_near(t)).collect();
    out.dedup_by(|a, b| a.t == b.t);
    out
}

/// The file stems of figures (a)–(f), each drawn as `.png` and `.svg`.
pub const PAPER_STEMS: [&str; 6] = [
    "fig_a_const_shells",
    "fig_b_const_stretches",
    "fig_c_thick",
    "fig_d_fibre",
    "fig_e_grow_retinas",
    "fig_f_axial",
];

/// Draw figures (a)–(f) from `runs` into `out`; returns them in order. They are drawn in
/// parallel: each is independent, and drawing and encoding them one after another was a
/// quarter of `eyeshell figures`' wall time on two cores.
pub fn paper_figures(runs: &PaperRuns, out: &Path) -> Result<Vec<Written>, FigureError> {
    use rayon::prelude::*;
    (0..PAPER_STEMS.len())
        .into_par_iter()
        .map(|k| paper_figure(k, runs.parts(), out))
        .collect()
}

/// What the paper's figures are drawn from: the const and thick runs, the fibre sweep and
/// the growth-zone grid (None: not read, and not needed by the figure asked for).
#[derive(Clone, Copy, Default)]
pub struct PaperParts<'a> {
    pub constant: Option<&'a RunData>,
    pub thick: Option<&'a RunData>,
    pub fibre: Option<&'a [(f64, RunData)]>,
    pub grid: Option<&'a [(f64, f64, RunData)]>,
}

/// The parts each of figures (a)–(f) is drawn from, as indices into
/// [const, thick, fibre, grid].
pub const PAPER_NEEDS: [&[usize]; 6] = [&[0], &[0], &[0, 1], &[2], &[3], &[3]];

impl PaperRuns {
    pub fn parts(&self) -> PaperParts<'_> {
        PaperParts {
            constant: Some(&self.constant),
            thick: Some(&self.thick),
            fibre: Some(&self.fibre),
            grid: Some(&self.grid),
        }
    }
}

/// Draw figure `k` of (a)–(f) (0 is (a)) from `parts`, which hold at least what
/// [`PAPER_NEEDS`]`[k]` names.
pub fn paper_figure(k: usize, parts: PaperParts<'_>, out: &Path) -> Result<Written, FigureError> {
    let missing = || {
        FigureError::Read(ExportError {
            bad_input: false,
            message: format!("figure {k}: drawn before its runs were read (a bug)"),
        })
    };
    match k {
        0 => figure_a(parts.constant.ok_or_else(missing)?, out),
        1 => figure_b(parts.constant.ok_or_else(missing)?, out),
        2 => figure_c(
            parts.thick.ok_or_else(missing)?,
            parts.constant.ok_or_else(missing)?,
            out,
        ),
        3 => figure_d(parts.fibre.ok_or_else(missing)?, out),
        4 => figure_e(parts.grid.ok_or_else(missing)?, out),
        5 => figure_f(parts.grid.ok_or_else(missing)?, out),
        _ => Err(missing()),
    }
}

fn written(id: &str, title: &str, caption: String, files: (PathBuf, PathBuf)) -> Written {
    Written {
        id: id.into(),
        title: title.into(),
        caption,
        png: files.0,
        svg: files.1,
    }
}

/// (a) The const shell at t = 0.1, 0.2, 0.4, 1, shaded by η, with retina and surfaces.
fn figure_a(run: &RunData, out: &Path) -> Result<Written, FigureError> {
    let snaps = snapshots_at(run, &[0.1, 0.2, 0.4, 1.0]);
    let top = eta_max(&snaps);
    let panels = snaps
        .iter()
        .zip(["(a)", "(b)", "(c)", "(d)"])
        .map(|(s, l)| shell_panel(format!("{l} {}", t_label(s.t)), &run.scene, s, top))
        .collect::<Result<Vec<_>, _>>()?;
    let title = "Growth of a uniform, fibre-free sclera";
    let files = image::write_panels(
        &panels,
        2,
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[0]),
    )?;
    let end = run.timeline().last();
    let caption = format!(
        "The shell cut at t = 0.1, 0.2, 0.4 and 1 (the paper's figure 'const' a–d), its mid-surface shaded by the growth rate η, with its outer face, the retina (inner face) and the best-focus surfaces for blue and red light (dashed; red = blue pushed back 0.655 mm). At t = 1 the axial length is {} mm, {}. Scene scenes/const.toml: {}.",
        end.map_or("?".into(), |p| trim(p.axial_length)),
        end.map_or("?".into(), describe_refraction),
        parameters(&run.scene)
    );
    Ok(written("a", title, caption, files))
}

fn describe_refraction(p: &SeriesPoint) -> String {
    let side = |d: f64, surface: &str| {
        let word = if d >= 0.0 { "behind" } else { "in front of" };
        format!("{} mm {word} {surface}", trim(d.abs()))
    };
    format!(
        "{} (the retina at the pole is {}, {})",
        p.class.as_str(),
        side(p.retina_minus_blue, "blue"),
        side(p.retina_minus_red, "red")
    )
}

/// (b) α_s and α_φ against σ at t = 0, 0.1, 0.2, 0.4, 1 for the const shell.
fn figure_b(run: &RunData, out: &Path) -> Result<Written, FigureError> {
    let snaps = snapshots_at(run, &[0.0, 0.1, 0.2, 0.4, 1.0]);
    let panels = vec![
        profile_panel("(f) stretch α_s", "alpha_s", "α_s", &snaps, T)?,
        profile_panel("(g) stretch α_φ", "alpha_phi", "α_φ", &snaps, T)?,
    ];
    let title = "Stretches of the uniform sclera as it grows";
    let files = image::write_panels(
        &panels,
        2,
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[1]),
    )?;
    let caption = format!(
        "The elastic stretches α_s and α_φ against σ (arclength of the grown, unloaded shell) at t = 0, 0.1, 0.2, 0.4 and 1 (the paper's figure 'const' f–g); uniform at t = 0. Scene scenes/const.toml: {}.",
        parameters(&run.scene)
    );
    Ok(written("b", title, caption, files))
}

/// (c) Non-uniform against uniform thickness: shells at t = 0 and 1, and the stretches.
fn figure_c(thick: &RunData, constant: &RunData, out: &Path) -> Result<Written, FigureError> {
    let mut shells = Figure::new("(a) initial and final shells", "z (mm)", "r (mm)");
    shells.aspect_equal = true;
    let mut alpha_s = Figure::new(
        "(b) α_s: initial (light) and final (heavy)",
        "σ (mm)",
        "α_s",
    );
    let mut alpha_phi = Figure::new(
        "(c) α_φ: initial (light) and final (heavy)",
        "σ (mm)",
        "α_φ",
    );
    for (run, name, style) in [
        (thick, "non-uniform H", SeriesStyle::Line),
        (constant, "uniform H", SeriesStyle::DashedLine),
    ] {
        for (t, light) in [(0.0, true), (1.0, false)] {
            let Some(s) = run.snapshot_near(t) else {
                continue;
            };
            let sh = shell(s)?;
            let color = if light { GREY } else { BLACK };
            let label = format!("{name}, {}", t_label(s.t));
            shells = shells
                .with(Series::new(label.clone(), sh.outer, style).color(color))
                .with(Series::new("", sh.retina, style).color(color).no_legend());
            let width = if light { 1 } else { 3 };
            let sig = column(s, "sigma")?;
            alpha_s = alpha_s.with(
                Series::new(
                    label.clone(),
                    sig.iter().copied().zip(column(s, "alpha_s")?).collect(),
                    style,
                )
                .color(color)
                .width(width),
            );
            alpha_phi = alpha_phi.with(
                Series::new(
                    label,
                    sig.iter().copied().zip(column(s, "alpha_phi")?).collect(),
                    style,
                )
                .color(color)
                .width(width),
            );
        }
    }
    let title = "Non-uniform against uniform reference thickness";
    let files = image::write_panels(
        &[shells, alpha_s, alpha_phi],
        3,
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[2]),
    )?;
    let pole = |r: &RunData| r.timeline().last().map_or(f64::NAN, |p| p.axial_length);
    let caption = format!(
        "The paper's figure 'thick': the sclera's faces at t = 0 and t = 1, solid for the non-uniform reference thickness and dashed for the uniform one, and their stretches (light: t = 0, heavy: t = 1). Axial length at t = 1: {} mm (non-uniform) against {} mm (uniform). Scenes scenes/thick.toml: {}; and scenes/const.toml.",
        trim(pole(thick)),
        trim(pole(constant)),
        parameters(&thick.scene)
    );
    Ok(written("c", title, caption, files))
}

/// (d) The fibre sweep: final shells, a close-up of the posterior pole, axial length
/// against t, and the final stretches, one colour per D.
fn figure_d(fibre: &[(f64, RunData)], out: &Path) -> Result<Written, FigureError> {
    let mut shells = Figure::new("(a) final shells", "z (mm)", "r (mm)");
    shells.aspect_equal = true;
    let mut close = Figure::new("(a, inset) posterior retina at t = 1", "z (mm)", "r (mm)");
    let mut alpha_s = Figure::new("(c) α_s at t = 1", "σ (mm)", "α_s");
    let mut alpha_phi = Figure::new("(d) α_φ at t = 1", "σ (mm)", "α_φ");
    let mut axial_runs = Vec::new();
    let mut pole_z: Vec<f64> = Vec::new();
    for (k, (d, run)) in fibre.iter().enumerate() {
        let Some(s) = run.snapshots().last() else {
            continue;
        };
        let sh = shell(s)?;
        let c = plot::PALETTE[k % 10];
        let name = format!("D = {}", trim(*d));
        pole_z.extend(sh.retina.first().map(|p| p.0));
        shells = shells
            .with(Series::new(name.clone(), sh.outer, SeriesStyle::Line).color(c))
            .with(
                Series::new("", sh.retina.clone(), SeriesStyle::Line)
                    .color(c)
                    .no_legend(),
            );
        let near: Vec<(f64, f64)> = sh.retina.iter().copied().filter(|p| p.1 <= 3.0).collect();
        close = close.with(Series::new(name.clone(), near, SeriesStyle::Line).color(c));
        let sig = column(s, "sigma")?;
        alpha_s = alpha_s.with(
            Series::new(
                name.clone(),
                sig.iter().copied().zip(column(s, "alpha_s")?).collect(),
                SeriesStyle::Line,
            )
            .color(c),
        );
        alpha_phi = alpha_phi.with(
            Series::new(
                name.clone(),
                sig.iter().copied().zip(column(s, "alpha_phi")?).collect(),
                SeriesStyle::Line,
            )
            .color(c),
        );
        axial_runs.push((name, run));
    }
    let axial = axial_panel("(b) axial length", &axial_runs);
    let title = "Effects of fibre reinforcement on scleral growth";
    let files = image::write_panels(
        &[shells, close, axial, alpha_s, alpha_phi],
        3,
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[3]),
    )?;
    let lengths: Vec<String> = fibre
        .iter()
        .map(|(d, r)| {
            format!(
                "D = {}: {} mm",
                trim(*d),
                r.timeline()
                    .last()
                    .map_or("?".into(), |p| trim(p.axial_length))
            )
        })
        .collect();
    let caption = format!(
        "The paper's figure 'fibre' for D = {} kPa: the final shells (outer face and retina), a close-up of the posterior retina (the paper's inset), the axial length against t, and the stretches at t = 1. Axial length at t = 1: {}. Scene scenes/fibre.toml (a sweep over D): {}.",
        fibre.iter().map(|(d, _)| trim(*d)).collect::<Vec<_>>().join(", "),
        lengths.join("; "),
        fibre.first().map_or(String::new(), |(_, r)| parameters(&r.scene))
    );
    Ok(written("d", title, caption, files))
}

/// (e) The retinas of the Γ × δ grid at t = 0, 0.1 and 1, shaded by η.
fn figure_e(grid: &[(f64, f64, RunData)], out: &Path) -> Result<Written, FigureError> {
    let mut grid: Vec<&(f64, f64, RunData)> = grid.iter().collect();
    grid.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let all: Vec<&RunSnapshot> = grid
        .iter()
        .flat_map(|(_, _, r)| snapshots_at(r, &[0.0, 0.1, 1.0]))
        .collect();
    let top = eta_max(&all);
    let mut panels = Vec::new();
    for (gamma, delta, run) in &grid {
        let mut fig = Figure::new(
            format!("Γ = {}, δ = {}", trim(*gamma), trim(*delta)),
            "z (mm)",
            "r (mm)",
        )
        .color_scale("η (1/mm)", 0.0, top);
        fig.aspect_equal = true;
        for s in snapshots_at(run, &[0.0, 0.1, 1.0]) {
            let sh = shell(s)?;
            fig = fig.with(
                Series::new(t_label(s.t), sh.retina, SeriesStyle::Line)
                    .width(5)
                    .shaded(sh.eta)
                    .no_legend(),
            );
        }
        let [blue, red] = surfaces(&run.scene);
        fig = fig
            .with(blue)
            .with(red)
            .note("retinas at t = 0, 0.1, 1 (outward in time)");
        panels.push(fig);
    }
    let columns = grid
        .iter()
        .map(|g| g.1.to_bits())
        .collect::<std::collections::BTreeSet<_>>()
        .len()
        .max(1);
    let title = "Effect of the growth zone on the retina";
    let files = image::write_panels(
        &panels,
        columns,
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[4]),
    )?;
    let caption = format!(
        "The paper's figure 'grow': the retina at t = 0, 0.1 and 1 for each growth zone (rows Γ, columns δ, in mm), shaded by the growth rate η on one scale, with the blue and red best-focus surfaces. Scene scenes/grow.toml (a sweep over Γ × δ): {}.",
        grid.first().map_or(String::new(), |(_, _, r)| parameters(&r.scene))
    );
    Ok(written("e", title, caption, files))
}

/// (f) Axial length against t for the grid, one panel per δ.
fn figure_f(grid: &[(f64, f64, RunData)], out: &Path) -> Result<Written, FigureError> {
    let mut deltas: Vec<f64> = grid.iter().map(|g| g.1).collect();
    deltas.sort_by(f64::total_cmp);
    deltas.dedup();
    let mut panels = Vec::new();
    let mut finals = Vec::new();
    for delta in &deltas {
        let mut rows: Vec<&(f64, f64, RunData)> = grid.iter().filter(|g| g.1 == *delta).collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        let named: Vec<(String, &RunData)> = rows
            .iter()
            .map(|(g, _, r)| (format!("Γ = {}", trim(*g)), r))
            .collect();
        for (g, _, r) in &rows {
            finals.push(format!(
                "(Γ, δ) = ({}, {}): {} mm",
                trim(*g),
                trim(*delta),
                r.timeline()
                    .last()
                    .map_or("?".into(), |p| trim(p.axial_length))
            ));
        }
        panels.push(axial_panel(&format!("δ = {}", trim(*delta)), &named));
    }
    let title = "Axial length for the growth zones";
    let files = image::write_panels(
        &panels,
        panels.len().max(1),
        title,
        PANEL.0,
        PANEL.1,
        &out.join(PAPER_STEMS[5]),
    )?;
    let caption = format!(
        "The paper's figure 'axial': axial length (pole of the retina, from z = 0) against t for Γ = 4, 8, 12 mm, one panel per δ. At t = 1: {}. Scene scenes/grow.toml.",
        finals.join("; ")
    );
    Ok(written("f", title, caption, files))
}

// ---------------------------------------------------------------- index

/// index.html: every figure with its caption and links to the PNG, the SVG and the data.
pub fn index_html(figures: &[Written], out: &Path, preamble: &str) -> String {
    let rel = |p: &Path| p.strip_prefix(out).unwrap_or(p).display().to_string();
    let mut html = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>eyeshell figures</title>\n<style>body{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em}figure{margin:2em 0}img{max-width:100%;border:1px solid #ccc}figcaption{margin-top:.5em;line-height:1.4}</style>\n</head>\n<body>\n<h1>eyeshell: the paper's result figures</h1>\n",
    );
    html.push_str(&format!("<p>{}</p>\n", escape(preamble)));
    for f in figures {
        html.push_str(&format!(
            "<figure id=\"fig-{id}\">\n<h2>({id}) {title}</h2>\n<img src=\"{png}\" alt=\"({id}) {title}\">\n<figcaption>{caption} <a href=\"{png}\">PNG</a> · <a href=\"{svg}\">SVG</a></figcaption>\n</figure>\n",
            id = escape(&f.id),
            title = escape(&f.title),
            png = escape(&rel(&f.png)),
            svg = escape(&rel(&f.svg)),
            caption = escape(&f.caption)
        ));
    }
    html.push_str("</body>\n</html>\n");
    html
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

// ---------------------------------------------------------------- any run

/// Draw the run (or sweep) in `dir` into `out`: for a growth run its shells, stretches,
/// tensions, axial length, growth stimulus and peripheral refraction; for an elastic run its shape and fields against Σ; for a
/// sweep, each run into `out/<run>/` and the axial lengths of all runs together.
pub fn plot_run(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    if is_sweep(dir) {
        return plot_sweep(dir, out);
    }
    plot_one(dir, out)
}

/// The pictures of one run directory (never a sweep: a sweep's runs are drawn by this, so
/// a run that names a sweep, even its own, cannot send the drawing round in circles).
fn plot_one(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let run = rundata::read(dir)?;
    let stem = |name: &str| out.join(name);
    let mut files = Vec::new();
    let mut push = |f: (PathBuf, PathBuf)| files.extend([f.0, f.1]);
    match &run.kind {
        RunKind::Elastic(table) => {
            let col = |n: &str| {
                table.column(n).ok_or_else(|| {
                    bad(format!("{}: fields.csv has no column {n:?}", dir.display()))
                })
            };
            let (z, r) = (col("z")?, col("r")?);
            let mut shape = Figure::new(format!("{}: loaded shell", run.name), "z (mm)", "r (mm)")
                .with(Series::new(
                    "mid-surface",
                    z.iter().copied().zip(r.iter().copied()).collect(),
                    SeriesStyle::Line,
                ));
            shape.aspect_equal = true;
            let sigma = col("Sigma")?;
            let vs = |field: &str, label: &str| -> Result<Figure, ExportError> {
                Ok(Figure::new(label.to_string(), "Σ (mm)", label.to_string())
                    .with(Series::new(
                        label.to_string(),
                        sigma.iter().copied().zip(col(field)?).collect(),
                        SeriesStyle::Line,
                    ))
                    .no_legend())
            };
            let panels = vec![
                shape,
                vs("alpha_s", "α_s")?,
                vs("alpha_phi", "α_φ")?,
                vs("kappa", "κ (1/mm)")?,
                vs("t_s", "t_s (kPa·mm)")?,
                vs("Q", "Q")?,
            ];
            push(image::write_panels(
                &panels,
                3,
                &run.name,
                PANEL.0,
                PANEL.1,
                &stem("fields"),
            )?);
        }
        RunKind::Growth { .. } => {
            let axis = TimeAxis::of(&run.scene);
            let snaps: Vec<&RunSnapshot> = run.snapshots().iter().collect();
            let top = eta_max(&snaps);
            let shells = snaps
                .iter()
                .map(|s| shell_panel(axis.label(s.t), &run.scene, s, top))
                .collect::<Result<Vec<_>, _>>()?;
            let columns = shells.len().clamp(1, 3);
            push(image::write_panels(
                &shells,
                columns,
                &format!("{}: shells", run.name),
                PANEL.0,
                PANEL.1,
                &stem("shells"),
            )?);
            let profiles = vec![
                profile_panel("α_s", "alpha_s", "α_s", &snaps, axis)?,
                profile_panel("α_φ", "alpha_phi", "α_φ", &snaps, axis)?,
                profile_panel("η", "eta", "η (1/mm)", &snaps, axis)?,
                profile_panel("t_s", "t_s", "t_s (kPa·mm)", &snaps, axis)?,
            ];
            push(image::write_panels(
                &profiles,
                2,
                &format!("{}: profiles against σ", run.name),
                PANEL.0,
                PANEL.1,
                &stem("profiles"),
            )?);
            let tl = run.timeline();
            let axial = axial_panel("axial length", &[(run.name.clone(), &run)]).no_legend();
            let refraction = Figure::new(
                "retina behind the best-focus surfaces",
                axis.title(),
                "distance behind (mm)",
            )
            .with(
                Series::new(
                    "behind blue",
                    tl.iter()
                        .map(|p| (axis.x(p.t), p.retina_minus_blue))
                        .collect(),
                    SeriesStyle::Line,
                )
                .color(BLUE),
            )
            .with(
                Series::new(
                    "behind red",
                    tl.iter()
                        .map(|p| (axis.x(p.t), p.retina_minus_red))
                        .collect(),
                    SeriesStyle::Line,
                )
                .color(RED),
            );
            push(image::write_panels(
                &[axial, refraction],
                2,
                &format!("{}: the eye in time", run.name),
                PANEL.0,
                PANEL.1,
                &stem("timeline"),
            )?);
            push(image::write_panels(
                &stimulus_panels(dir, &snaps, axis)?,
                2,
                &format!("{}: growth stimulus and peripheral refraction", run.name),
                PANEL.0,
                PANEL.1,
                &stem("stimulus"),
            )?);
            if let Some(panels) = sensitivity_panels(dir, axis)? {
                push(image::write_panels(
                    &panels,
                    2,
                    &format!("{}: sensitivities", run.name),
                    PANEL.0,
                    PANEL.1,
                    &stem("sensitivities"),
                )?);
            }
        }
    }
    Ok(files)
}

/// A line of a figure: (t, value) points.
type Curve = Vec<(f64, f64)>;

/// A growth run's peripheral.csv as curves of relative_D against the field angle, one per
/// output time (in time order); None for a run without the file.
fn peripheral_curves(dir: &Path) -> Result<Option<Vec<(f64, Curve)>>, ExportError> {
    use eyeshell::rundir::growth::PERIPHERAL_FILE;
    let path = dir.join(PERIPHERAL_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let table = eyeshell::interop::export::read_csv(&path)?;
    let col = |n: &str| {
        table
            .column(n)
            .ok_or_else(|| bad(format!("{}: no column {n:?}", path.display())))
    };
    let (t, field, relative) = (col("t")?, col("field_deg")?, col("relative_D")?);
    let mut curves: Vec<(f64, Curve)> = vec![];
    for ((t, f), d) in t.into_iter().zip(field).zip(relative) {
        match curves.last_mut() {
            Some((at, c)) if *at == t => c.push((f, d)),
            _ => curves.push((t, vec![(f, d)])),
        }
    }
    Ok(Some(curves))
}

/// The growth-rate map of a growth run: the stimulus g_v (the rate of growth at each point,
/// docs/MODEL.md §6) against σ at each output time, and the relative peripheral refraction
/// against the field angle at each output time (when the run wrote peripheral.csv).
fn stimulus_panels(
    dir: &Path,
    snaps: &[&RunSnapshot],
    axis: TimeAxis,
) -> Result<Vec<Figure>, ExportError> {
    let mut panels = vec![profile_panel(
        "growth stimulus g_v (0: no growth)",
        "g_v",
        "g_v",
        snaps,
        axis,
    )?];
    if let Some(curves) = peripheral_curves(dir)? {
        let last = curves.len().saturating_sub(1).max(1) as f64;
        let fig = curves.into_iter().enumerate().fold(
            Figure::new(
                "peripheral refraction, naked eye",
                "field angle (°)",
                "relative to the pole (D)",
            ),
            |f, (k, (t, c))| {
                f.with(
                    Series::new(axis.label(t), c, SeriesStyle::Line)
                        .color(colormap(0.85 * k as f64 / last)),
                )
            },
        );
        panels.push(fig);
    }
    Ok(panels)
}

/// Several growth runs drawn together into `out` (`compare.png`, `.svg`): their axial length
/// and their refraction_D against t, and the relative peripheral refraction against the field
/// angle at each run's last output time (runs without peripheral.csv are left out of it).
/// Each run is named by its directory.
pub fn plot_compare(dirs: &[PathBuf], out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let mut runs = Vec::with_capacity(dirs.len());
    for dir in dirs {
        let run = rundata::read(dir)?;
        if run.timeline().is_empty() {
            return Err(FigureError::Read(bad(format!(
                "{}: is not a growth run: only growth runs are drawn together",
                dir.display()
            ))));
        }
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| dir.display().to_string());
        runs.push((name, run));
    }
    let named: Vec<(String, &RunData)> = runs.iter().map(|(n, r)| (n.clone(), r)).collect();
    let axial = axial_panel("axial length", &named);
    let ages = TimeAxis::of_runs(runs.iter().map(|(_, r)| &r.scene));
    let mut refraction = Figure::new("refraction at the pole", ages.title(), "refraction_D (D)");
    let mut peripheral = Figure::new(
        "peripheral refraction at the end, naked eye",
        "field angle (°)",
        "relative to the pole (D)",
    );
    for (k, ((name, run), dir)) in runs.iter().zip(dirs).enumerate() {
        let colour = plot::PALETTE[k % 10];
        let axis = if ages.clock.is_some() {
            TimeAxis::of(&run.scene)
        } else {
            ages
        };
        let pts = run
            .timeline()
            .iter()
            .map(|p| (axis.x(p.t), p.refraction_d))
            .collect();
        refraction =
            refraction.with(Series::new(name.clone(), pts, SeriesStyle::Line).color(colour));
        if let Some((_, last)) = peripheral_curves(dir)?.and_then(|mut c| c.pop()) {
            peripheral =
                peripheral.with(Series::new(name.clone(), last, SeriesStyle::Line).color(colour));
        }
    }
    let (png, svg) = image::write_panels(
        &[axial, refraction, peripheral],
        3,
        "growth runs compared",
        PANEL.0,
        PANEL.1,
        &out.join("compare"),
    )?;
    Ok(vec![png, svg])
}

/// sensitivities.csv of a growth run (`grow --sensitivities`) against time (`axis`), one
/// line per parameter: dL/dp, d(equatorial radius)/dp, d(retina − blue)/dp and (p/L)
/// dL/dp. None without the file.
fn sensitivity_panels(dir: &Path, axis: TimeAxis) -> Result<Option<Vec<Figure>>, ExportError> {
    let Some(rows) = eyeshell::rundir::read::read_sensitivities(dir)? else {
        return Ok(None);
    };
    // Per parameter, in order of first appearance: its (t, value) for each column after the
    // parameter's.
    let mut lines: Vec<(String, [Curve; 4])> = vec![];
    for row in rows {
        let slot = match lines.iter().position(|(p, _)| *p == row.parameter) {
            Some(i) => i,
            None => {
                lines.push((row.parameter, Default::default()));
                lines.len() - 1
            }
        };
        for (c, v) in row.values.into_iter().enumerate() {
            lines[slot].1[c].push((axis.x(row.t), v));
        }
    }
    let labels = [
        "d(axial length)/dp",
        "d(equatorial radius)/dp",
        "d(retina − blue)/dp",
        "(p/L) dL/dp",
    ];
    let panels = labels
        .iter()
        .enumerate()
        .map(|(c, label)| {
            lines.iter().fold(
                Figure::new(label.to_string(), axis.title(), label.to_string()),
                |f, (key, cols)| {
                    f.with(Series::new(key.clone(), cols[c].clone(), SeriesStyle::Line))
                },
            )
        })
        .collect();
    Ok(Some(panels))
}

/// The figure of `eyeshell fit`: the observations (with ±σ bars when given) against the
/// fitted curve and the curve of the start values, as `<stem>.png` and `<stem>.svg`.
pub fn fit_figure(
    r: &eyeshell::fit::FitReport,
    fitted: &[(f64, f64)],
    initial: &[(f64, f64)],
    axis: TimeAxis,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let on_axis = |curve: &[(f64, f64)]| -> Vec<(f64, f64)> {
        curve.iter().map(|&(t, l)| (axis.x(t), l)).collect()
    };
    let estimates: Vec<String> = r
        .parameters
        .iter()
        .map(|p| {
            format!(
                "{} = {} ± {}",
                p.key,
                trim(p.estimate),
                trim(p.standard_error)
            )
        })
        .collect();
    let mut fig = Figure::new(
        "axial length: data and fit",
        axis.title(),
        "axial length (mm)",
    )
    .with(Series::new("initial", on_axis(initial), SeriesStyle::DashedLine).color(GREY))
    .with(Series::new("fitted", on_axis(fitted), SeriesStyle::Line).color(BLUE))
    .with(
        Series::new(
            "data",
            r.residuals
                .iter()
                .map(|x| (axis.x(x.t), x.axial_length))
                .collect(),
            SeriesStyle::Markers,
        )
        .color(RED),
    );
    for e in estimates {
        fig = fig.note(e);
    }
    // The ±σ bars, one short line each (at most a few hundred: beyond, the markers alone).
    if r.residuals.len() <= 500 {
        for x in &r.residuals {
            if let Some(s) = x.sigma {
                fig = fig.with(
                    Series::new(
                        "±σ",
                        vec![
                            (axis.x(x.t), x.axial_length - s),
                            (axis.x(x.t), x.axial_length + s),
                        ],
                        SeriesStyle::Line,
                    )
                    .color(RED)
                    .width(1)
                    .no_legend(),
                );
            }
        }
    }
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}

/// Does `dir` hold a sweep's output (summary.json with a list of runs)?
pub fn is_sweep(dir: &Path) -> bool {
    matches!(Summary::read(dir), Ok(Summary::Sweep(_)))
}

fn plot_sweep(dir: &Path, out: &Path) -> Result<Vec<PathBuf>, FigureError> {
    let runs = sweep_runs(dir)?;
    if runs.is_empty() {
        return Err(FigureError::Read(bad(format!(
            "{}: the sweep has no run to draw",
            dir.display()
        ))));
    }
    let mut files = Vec::new();
    for run in &runs {
        let name = run
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        files.extend(plot_one(&run.dir, &out.join(&name))?);
    }
    let growing: Vec<(String, &RunData)> = runs
        .iter()
        .filter(|r| !r.timeline().is_empty())
        .map(|r| {
            (
                r.dir
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                r,
            )
        })
        .collect();
    if !growing.is_empty() {
        let fig = axial_panel("axial length of every run", &growing);
        let (png, svg) = image::write(&fig, &out.join("axial_length"))?;
        files.extend([png, svg]);
    }
    Ok(files)
}

/// The first wavelength's best-focus surface of `eyeshell optics`, and its sagittal and
/// tangential focal surfaces, minus the scene's polynomial blue surface, against the polar
/// angle φ about z_B (`rows` as published.csv holds them: field, φ, R_B, then the three
/// differences).
pub fn published_figure(
    rows: &[[f64; 6]],
    criterion: &str,
    wavelength_nm: f64,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let mut fig = Figure::new(
        format!(
            "{} nm surfaces minus the polynomial blue surface",
            trim(wavelength_nm)
        ),
        "φ (rad about z_B)",
        "R − R_B (mm)",
    );
    let column = |k: usize| rows.iter().map(|r| (r[1], r[k])).collect::<Vec<_>>();
    for (k, name, colour) in [
        (4, "sagittal focus".to_string(), Rgb(90, 160, 90)),
        (5, "tangential focus".to_string(), Rgb(200, 140, 40)),
        (3, format!("best focus ({criterion})"), BLUE),
    ] {
        fig = fig.with(Series::new(name, column(k), SeriesStyle::Line).color(colour));
    }
    fig = fig.with(
        Series::new(
            "",
            vec![(0.0, 0.0), (rows.last().map_or(0.5, |r| r[1]), 0.0)],
            SeriesStyle::Line,
        )
        .color(BLACK)
        .width(1)
        .no_legend(),
    );
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}

/// A ray fan of the optics figure: its field angle (degrees) and each ray's (z, y) path.
pub type RayFan = (f64, Vec<Vec<(f64, f64)>>);

/// The eye of `eyeshell optics` in its meridional plane, like the paper's ray-trace figure:
/// each refracting surface across the pupil's height, ray fans of the first wavelength at a
/// few field angles (`fans`: angle and rays), and the best-focus surfaces (blue, red).
pub fn optics_figure(
    system: &eyeshell_optics::OpticalSystem,
    computed: &eyeshell::model::optics::ComputedOptics,
    fans: &[RayFan],
    stem: &Path,
) -> Result<(PathBuf, PathBuf), FigureError> {
    let mut fig = Figure::new(
        format!("{} eye: rays and best-focus surfaces", system.name),
        "z (mm from the corneal apex)",
        "y (mm)",
    );
    // Each surface drawn to 6 mm from the axis, or as far as its conicoid reaches.
    for (element, vertex) in system.elements.iter().zip(system.vertices()) {
        let n = 61;
        let points: Vec<(f64, f64)> = (0..n)
            .map(|i| -6.0 + 12.0 * i as f64 / (n - 1) as f64)
            .filter_map(|y| element.surface.sag(y.abs()).map(|s| (vertex + s, y)))
            .collect();
        if points.len() > 1 {
            fig = fig.with(
                Series::new("surfaces", points, SeriesStyle::Line)
                    .color(BLACK)
                    .width(1)
                    .no_legend(),
            );
        }
    }
    let fan_colours = [GREY, Rgb(90, 160, 90), Rgb(200, 140, 40)];
    for (i, (field, rays)) in fans.iter().enumerate() {
        for (k, ray) in rays.iter().enumerate() {
            let series = Series::new(
                format!("rays at {}°", trim(*field)),
                ray.clone(),
                SeriesStyle::Line,
            )
            .color(fan_colours[i % fan_colours.len()])
            .width(1);
            fig = fig.with(if k == 0 { series } else { series.no_legend() });
        }
    }
    for (s, colour) in computed.surfaces.surfaces.iter().zip([BLUE, RED]) {
        let upper: Vec<(f64, f64)> = s.points.iter().map(|p| (p.z, p.r)).collect();
        let lower: Vec<(f64, f64)> = s.points.iter().map(|p| (p.z, -p.r)).collect();
        let name = format!("best focus, {} nm", trim(s.wavelength_nm));
        fig = fig
            .with(Series::new(name, upper, SeriesStyle::Line).color(colour))
            .with(
                Series::new("", lower, SeriesStyle::Line)
                    .color(colour)
                    .no_legend(),
            );
    }
    fig.width = PANEL.0;
    fig.height = PANEL.1;
    Ok(image::write(&fig, stem)?)
}
