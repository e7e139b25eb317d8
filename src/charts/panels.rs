//! The panels the figures are built from: a shell's cross-section, stretch profiles, axial
//! length against time, and the captions that state a run's parameters and numerics.

use eyeshell::interop::export::{ExportError, RunSnapshot};
use eyeshell::model::stimulus::Surface;
use eyeshell::rundir::rundata::{column, RunData};
use eyeshell::scene::Scene;
use eyeshell_plot::{self as plot, colormap, Figure, Series, SeriesStyle};

use super::{BLACK, BLUE, RED};

/// The curves of a shell at one snapshot: mid-surface, outer face and retina (inner face),
/// each as (z, r) points from the pole to the cornea, and η at every node.
pub(super) struct Shell {
    pub(super) mid: Vec<(f64, f64)>,
    pub(super) outer: Vec<(f64, f64)>,
    pub(super) retina: Vec<(f64, f64)>,
    pub(super) eta: Vec<f64>,
}

pub(super) fn shell(s: &RunSnapshot) -> Result<Shell, ExportError> {
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

pub(super) fn surfaces(scene: &Scene) -> [Series; 2] {
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
pub(super) fn eta_max(snapshots: &[&RunSnapshot]) -> f64 {
    snapshots
        .iter()
        .filter_map(|s| s.table.column("eta"))
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

pub(super) fn t_label(t: f64) -> String {
    format!("t = {}", trim(t))
}

/// The time axis of a run's figures: the scene's ages when it counts in them (time.unit),
/// else the model's t, so that a scene in years is drawn in years and one without a unit
/// exactly as before.
#[derive(Clone, Copy, Debug)]
pub struct TimeAxis {
    /// The clock of a scene with ages, and its unit; None: t.
    pub(super) clock: Option<(eyeshell::growth::schedule::Clock, &'static str)>,
}

impl TimeAxis {
    /// The axis of `scene`.
    pub fn of(scene: &Scene) -> TimeAxis {
        TimeAxis {
            clock: scene
                .growth
                .as_ref()
                .and_then(|g| Some((g.clock, g.age_unit()?))),
        }
    }

    /// The axis of several runs drawn together: ages when every run counts in the same
    /// unit, else t (ages in years and t on one axis would mislead).
    pub(super) fn of_runs<'a>(scenes: impl IntoIterator<Item = &'a Scene>) -> TimeAxis {
        let mut axes = scenes.into_iter().map(TimeAxis::of);
        let Some(first) = axes.next() else {
            return TimeAxis { clock: None };
        };
        let unit = first.clock.map(|c| c.1);
        if axes.all(|a| a.clock.map(|c| c.1) == unit) {
            first
        } else {
            TimeAxis { clock: None }
        }
    }

    /// Where time `t` of a run with this axis lies on it.
    pub fn x(&self, t: f64) -> f64 {
        match self.clock {
            Some((clock, _)) => clock.age(t),
            None => t,
        }
    }

    /// The axis' title: "age (years)", or "t".
    pub fn title(&self) -> String {
        match self.clock {
            Some((_, unit)) => format!("age ({unit})"),
            None => "t".to_string(),
        }
    }

    /// A legend's name for time `t`: "age 3.5 years", or "t = 0.2".
    pub(super) fn label(&self, t: f64) -> String {
        match self.clock {
            Some((_, unit)) => format!("age {} {unit}", trim(self.x(t))),
            None => t_label(t),
        }
    }
}

/// The paper's figures are in t.
pub(super) const T: TimeAxis = TimeAxis { clock: None };

/// A number as short as it reads: 0.1, 1, 23.58.
pub(super) fn trim(x: f64) -> String {
    let s = format!("{x:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

// ---------------------------------------------------------------- panels

/// A cross-section of the shell at one snapshot: the mid-surface shaded by η, both faces,
/// the retina, and the blue and red best-focus surfaces.
pub(super) fn shell_panel(
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
pub(super) fn profile_panel(
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
pub(super) fn axial_panel(title: &str, runs: &[(String, &RunData)]) -> Figure {
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
