//! `eyeshell solve`, `grow`, `check` and `keys`: one scene.

use eyeshell::rundir::run::GrowthFailure;
use eyeshell::rundir::{self, GrowthWriter};
use eyeshell::scene::{Scene, SceneError, KEYS};
use eyeshell::text::one_line;
use eyeshell::Error;

use crate::args::{GrowArgs, SceneArgs, SolveArgs};
use crate::{out, plural, progress};

/// Parse and check the `--at` material points against [ε, L] of `scene`.
pub(crate) fn parse_at(values: &[String], scene: &Scene) -> Result<Vec<f64>, Error> {
    let (lo, hi) = (scene.solver.epsilon, scene.params.length());
    values
        .iter()
        .map(|v| {
            let t = v.trim();
            let x: f64 = t.parse().map_err(|_| {
                Error::input(eyeshell::Subject::Argument("--at".into()), format!("--at: {:?} is not a number (expected material points Σ separated by commas)", t))
                    .with_value(t)
                    .with_origin(eyeshell::Origin::Argument)
            })?;
            if !x.is_finite() {
                return Err(Error::input(
                    eyeshell::Subject::Argument("--at".into()),
                    format!("--at: Σ = {t} must be a finite number"),
                )
                .with_value(t)
                .with_origin(eyeshell::Origin::Argument));
            }
            if x < lo || x > hi {
                return Err(Error::input(eyeshell::Subject::Argument("--at".into()), format!(
                    "--at: Σ = {t} is outside the shell [ε, L] = [{lo}, {hi}] (solver.epsilon, π·geometry.fraction·geometry.R0)"
                ))
                .with_value(t)
                .with_origin(eyeshell::Origin::Argument));
            }
            Ok(x)
        })
        .collect()
}

pub(crate) fn cmd_solve(a: &SolveArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let at = parse_at(&a.at, &scene)?;
    let run = rundir::run::solve_into(&scene, &a.out, &at, &[a.scene.scene.as_path()])?;
    let (solution, target) = (run.solution, run.dir);

    if !a.quiet {
        let s = &solution.stats;
        let nodes = match (&s.pass_nodes, &s.error_estimate) {
            (Some(passes), Some(e)) => format!(
                "{} ({})\n  error estimate  {:.3e} (κ {:.2e}, α_s {:.2e}, r {:.2e}, θ {:.2e}, Q {:.2e})",
                s.nodes,
                // solver.richardson alone extrapolates once on solver.nodes' mesh: no tol.
                match scene.solver.tol {
                    Some(tol) => format!(
                        "adapted to solver.tol = {} in {} pass{}: {}",
                        eyeshell::text::number(tol),
                        passes.len(),
                        if passes.len() == 1 { "" } else { "es" },
                        passes.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
                    ),
                    None => "solver.richardson: extrapolated once on the mesh of solver.nodes".into(),
                },
                e.overall,
                e.kappa,
                e.alpha_s,
                e.r,
                e.theta,
                e.q
            ),
            _ => format!(
                "{} ({} uniform + {} breakpoint + {} pole + {} cornea)",
                s.nodes, s.uniform_nodes, s.breakpoint_nodes, s.pole_nodes, s.cornea_nodes
            ),
        };
        out(&format!(
            "eyeshell: solved {} ({})\n  nodes           {}\n  Newton          {} iteration{}, residual {:.3e}\n  first integral  {:.3e} (max |Q cos θ + r t_s sin θ − r² ΔP/2|)\n{}  time            {:.3} s\n  output          {}\n",
            scene.origin,
            one_line(&scene.display_name()),
            nodes,
            s.newton_iterations,
            if s.newton_iterations == 1 { "" } else { "s" },
            s.residual_norm,
            s.first_integral_max,
            refraction_text(&scene, &solution),
            s.wall_seconds,
            crate::shown(&target),
        ));
    }
    Ok(())
}

/// The summary's line of the solve's refraction at the pole, naked eye (summary.json's
/// `refraction_D`): the dioptres, or why the optics give none; no line for a scene with no
/// optics to compute it with (an elastic scene of the shell alone), as summary.json has no
/// `refraction_D` then.
fn refraction_text(scene: &Scene, solution: &eyeshell::bvp::Solution) -> String {
    match scene.refraction_of(&solution.rows) {
        Some(d) if d.is_finite() => {
            format!("  refraction_D    {d:+.3} D (at the pole, naked eye)\n")
        }
        Some(_) => "  refraction_D    none: beyond the ±25 D the optics are traced over\n".into(),
        None => String::new(),
    }
}

pub(crate) fn cmd_grow(a: &GrowArgs) -> Result<(), Error> {
    let mut scene = a.scene.load()?;
    if scene.growth.is_none() {
        return Err(Error::input(eyeshell::Subject::Key("growth".into()), format!(
            "{}: scene has no [growth] section: use `eyeshell solve`, or add growth keys (e.g. --set growth.eta0=70)",
            scene.origin
        ))
        .with_origin(eyeshell::Origin::Scene(scene.origin.clone())));
    }
    set_sensitivities(&mut scene, &a.sensitivities, a.sensitivity_error_control)?;
    scene.solver.threads = match a.jobs {
        Some(n) => Some(n as usize),
        None => eyeshell::scene::jobs_from_env()?,
    };
    let writer = GrowthWriter::create(&a.out, &scene, &[a.scene.scene.as_path()])?;
    let choosing = scene.solver.tol.map(|tol| {
        format!("choosing the mesh for solver.tol = {tol:e} (test runs on halved meshes)")
    });
    let mut bar = progress::GrowthProgress::new(progress::wanted(a.quiet), choosing.as_deref());
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
            return Err(Error::failed(
                eyeshell::Stage::Growth,
                format!("{failure} ({kept})"),
            ));
        }
        Err(GrowthFailure::Unwritten { error, .. }) => return Err(error.into()),
        Err(failure) => return Err(Error::failed(eyeshell::Stage::Growth, failure.to_string())),
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
        // Under solver.tol the run chose its own mesh and tolerances: say those, and the
        // error it estimates, not the scene's rtol and atol, which it ignored.
        let (rtol, atol, chosen) = match (&stats.accuracy, &stats.error_estimate) {
            (Some(acc), Some(est)) => {
                let e = est.bounded();
                let rounds = acc.rounds.len();
                (
                    format!("{:.3e}", acc.rtol),
                    format!("{:.3e}", acc.atol),
                    format!(
                        "  nodes           {} (chosen for solver.tol = {:e} in {} round{})\n  error estimate  {:.3e} mm (the largest over the lengths and times; their largest space part {:.2e}, time part {:.2e})\n",
                        acc.nodes,
                        acc.tol,
                        rounds,
                        plural(rounds),
                        e.total,
                        e.space,
                        e.time,
                    ),
                )
            }
            _ => (
                format!("{:e}", scene.growth_settings.rtol),
                format!("{:e}", scene.growth_settings.atol),
                String::new(),
            ),
        };
        out(&format!(
            "eyeshell: grew {} ({})\n  final           {}\n{chosen}  integrator      {} (rtol {}, atol {}), {} step{}\n  work            {} rhs evaluation{}, {} BVP solve{}, {} Newton iteration{}\n  time            {:.3} s\n  output          {}\n",
            scene.origin,
            one_line(&scene.display_name()),
            end,
            scene.growth_settings.integrator.name(),
            rtol,
            atol,
            stats.steps,
            plural(stats.steps),
            stats.rhs_evaluations,
            plural(stats.rhs_evaluations),
            stats.bvp_solves,
            plural(stats.bvp_solves),
            stats.newton_iterations,
            plural(stats.newton_iterations),
            stats.wall_seconds,
            crate::shown(&dir),
        ));
    }
    Ok(())
}

/// `--sensitivities KEY,KEY,...`: the library's checks (`Scene::set_sensitivities`: known
/// keys with sensitivities, each once, fibres.D only with fibres, IDA only), its one-line
/// refusals named after the flag.
fn set_sensitivities(scene: &mut Scene, keys: &[String], error_control: bool) -> Result<(), Error> {
    if keys.is_empty() {
        return Ok(());
    }
    scene
        .set_sensitivities(keys, error_control)
        .map_err(|e| match e {
            Error::Input(why) => {
                let message = format!("--{why}");
                Error::Input(Box::new(why.reworded(message)))
            }
            e => e,
        })
}

pub(crate) fn cmd_check(a: &SceneArgs) -> Result<(), Error> {
    let scene = match a.load() {
        Err(_) if is_sweep_file(a) => return check_sweep(a),
        other => other?,
    };
    let p = &scene.params;
    let mut text = format!(
        "# {}: valid scene '{}'\n",
        scene.origin,
        one_line(&scene.display_name())
    );
    for o in &scene.overrides {
        text.push_str(&format!("# --set {}\n", one_line(o)));
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
pub(crate) fn is_sweep_file(a: &SceneArgs) -> bool {
    matches!(
        Scene::from_file(&a.scene, &[]),
        Err(SceneError::IsSweep { .. })
    )
}

/// `eyeshell check` of a sweep: its runs and the values each sets, then the first run's scene.
pub(crate) fn check_sweep(a: &SceneArgs) -> Result<(), Error> {
    let sweep = eyeshell::scene::sweep::Sweep::from_file(&a.scene, &a.set)?;
    let mut text = format!(
        "# {}: valid sweep '{}' of {} run{} over {}\n",
        sweep.origin,
        one_line(&sweep.name),
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

pub(crate) fn cmd_keys() -> Result<(), Error> {
    out(&keys_listing());
    Ok(())
}
