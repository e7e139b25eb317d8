//! The paper's result figures (a)–(f) (its section 3; docs/MODEL.md §8), each composed of
//! panels.

use std::path::{Path, PathBuf};

use eyeshell::interop::export::{ExportError, RunSnapshot};
use eyeshell::rundir::rundata::{column, RunData, SeriesPoint};
use eyeshell_plot::{self as plot, Figure, Series, SeriesStyle};

use super::panels::{
    axial_panel, eta_max, parameters, profile_panel, shell, shell_panel, surfaces, t_label, trim, T,
};
use super::runs::{snapshots_at, PaperRuns};
use super::{FigureError, Written, BLACK, GREY, PANEL};
use crate::image;

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
