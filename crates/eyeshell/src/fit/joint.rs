//! The model of a fit at its observations: one or several arms (a scene and its data each),
//! the parameters shared by every arm or each arm's own, the stacked residuals of every
//! measurement (axial lengths in mm, refractions in D, each over its σ) and their Jacobian.
//!
//! The Jacobian's columns: a key with a forward sensitivity ([`FitParam::param`]) takes the
//! axial length's from the run's IDAS sensitivities; every other column, and the
//! refraction's of every key, is a central difference of two runs of the scene at
//! x ± h, h = [`FD_STEP`]·|x| (or [`FD_STEP`] at x = 0), one-sided where x ± h leaves the
//! key's range. Its error is the truncation's, O(h²)·|f‴|, and the runs' own, about their
//! tolerance over h. Measured against IDAS on the const scene at its tolerances (fit/tests_joint):
//! δ's column differs by 6.1e-3 of its largest value at h = 1e-3·|x| and by 2.1e-2 at
//! h = 1e-4·|x| (the runs' error over h dominates, hence 1e-3); η0's by 2.3e-3 at either
//! step, IDAS's own error (its sensitivities take no part in the error test). Such an error
//! moves the steps of Levenberg–Marquardt, not the minimum it finds, and the standard
//! errors by as much.

use nalgebra::{DMatrix, DVector};

use super::data::{Measured, Observations};
use super::param::{with_values, FitParam};
use super::{Bounds, GrowthModel};
use crate::growth::dae::SensParam;
use crate::growth::{self};
use crate::scene::Scene;
use crate::text::number;
use crate::{Error, Origin, Stage, Subject};

/// The relative step of a finite difference (see the module's note on its error).
pub const FD_STEP: f64 = 1e-3;

/// One arm of a fit: a scene and the observations of it (on the scene's clock), and the
/// arm's name (None for the fit of one scene).
#[derive(Clone, Debug)]
pub struct Arm {
    pub name: Option<String>,
    pub scene: Scene,
    pub data: Observations,
}

/// Where the parameters of a joint fit sit in its vector: the shared keys first, then each
/// per-arm key once per arm (key by key, arms in order).
#[derive(Clone, Debug)]
pub struct Layout {
    pub shared: Vec<FitParam>,
    pub per_arm: Vec<FitParam>,
    pub arms: usize,
}

impl Layout {
    /// The number of parameters.
    pub fn len(&self) -> usize {
        self.shared.len() + self.per_arm.len() * self.arms
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The keys of one arm's scene, shared first.
    pub fn local(&self) -> Vec<FitParam> {
        self.shared.iter().chain(&self.per_arm).cloned().collect()
    }

    /// The index in the vector of arm `arm`'s local parameter `c`.
    pub fn global(&self, arm: usize, c: usize) -> usize {
        match c.checked_sub(self.shared.len()) {
            None => c,
            Some(j) => self.shared.len() + j * self.arms + arm,
        }
    }

    /// The parameter at index `g`, and its arm (None: shared).
    pub fn at(&self, g: usize) -> (&FitParam, Option<usize>) {
        match g.checked_sub(self.shared.len()) {
            None => (&self.shared[g], None),
            Some(j) => (&self.per_arm[j / self.arms], Some(j % self.arms)),
        }
    }

    /// Arm `arm`'s values of its local parameters, out of the vector `values`.
    pub fn local_values(&self, arm: usize, values: &[f64]) -> Vec<f64> {
        (0..self.shared.len() + self.per_arm.len())
            .map(|c| values[self.global(arm, c)])
            .collect()
    }
}

/// One residual of a fit: which arm, which observation (its row in the arm's data) and
/// which measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowOf {
    pub arm: usize,
    pub obs: usize,
    pub what: Measured,
}

/// The rows of the stacked residuals, in their order: arm by arm, each observation's axial
/// length before its refraction.
pub fn rows_of(arms: &[Arm]) -> Vec<RowOf> {
    let mut rows = vec![];
    for (a, arm) in arms.iter().enumerate() {
        for (i, o) in arm.data.rows.iter().enumerate() {
            for (what, _, _) in o.measured() {
                rows.push(RowOf {
                    arm: a,
                    obs: i,
                    what,
                });
            }
        }
    }
    rows
}

/// The model of one arm at its observation times: the axial length and the refraction
/// and their derivatives by each local parameter (a column of NaN where not needed).
pub struct ArmValues {
    pub axial_length: Vec<f64>,
    pub refraction_d: Vec<f64>,
    pub d_axial_length: DMatrix<f64>,
    pub d_refraction_d: DMatrix<f64>,
    /// Growth runs made, and their seconds.
    pub runs: usize,
    pub seconds: f64,
}

/// One growth run of `scene` recording `times`, with the sensitivities to `sens` (and the
/// refraction with `refraction`).
pub fn run_model(
    scene: &Scene,
    sens: &[SensParam],
    times: &[f64],
    refraction: bool,
    step: &mut growth::ProgressFn<'_>,
) -> Result<super::ModelValues, Error> {
    let Some(problem) = scene.growth_problem()? else {
        return Err(Error::input(
            Subject::Key("growth".into()),
            format!(
                "{}: the scene has no [growth] section (a fit needs a growth run)",
                scene.origin
            ),
        )
        .with_origin(Origin::Scene(scene.origin.clone())));
    };
    let model = GrowthModel {
        problem: &problem,
        fitted: sens,
        times,
        refraction,
    };
    Ok(model.evaluate(step)?)
}

/// The model of `scene` with `params` at `values`, at the times of `data`: the
/// derivatives of what `data` measures, by IDAS where the key has a sensitivity and the
/// quantity is the axial length, else by finite differences ([`FD_STEP`]).
pub fn arm_values(
    scene: &Scene,
    params: &[FitParam],
    values: &[f64],
    data: &Observations,
    step: &mut growth::ProgressFn<'_>,
) -> Result<ArmValues, Error> {
    let (axial, refraction) = (
        data.has(Measured::AxialLength),
        data.has(Measured::Refraction),
    );
    let times: Vec<f64> = data.rows.iter().map(|o| o.t).collect();
    let s = with_values(scene, params, values)?;
    let sens: Vec<SensParam> = if axial {
        params.iter().filter_map(|p| p.param).collect()
    } else {
        vec![]
    };
    let base = run_model(&s, &sens, &times, refraction, step)?;
    let (n, k) = (times.len(), params.len());
    let mut out = ArmValues {
        axial_length: base.axial_length.clone(),
        refraction_d: base.refraction_d.clone(),
        d_axial_length: DMatrix::from_element(n, k, f64::NAN),
        d_refraction_d: DMatrix::from_element(n, k, f64::NAN),
        runs: 1,
        seconds: base.seconds,
    };
    let mut next_sens = 0;
    for (c, p) in params.iter().enumerate() {
        if p.param.is_some() && axial {
            out.d_axial_length
                .set_column(c, &base.jacobian.column(next_sens));
            next_sens += 1;
        }
        let needs_fd = (p.param.is_none() && axial) || refraction;
        if !needs_fd {
            continue;
        }
        let x = values[c];
        let h = FD_STEP * if x != 0.0 { x.abs() } else { 1.0 };
        let mut at = |v: f64| -> Result<super::ModelValues, Error> {
            let mut trial = values.to_vec();
            trial[c] = v;
            let m = run_model(
                &with_values(scene, params, &trial)?,
                &[],
                &times,
                refraction,
                step,
            )?;
            out.runs += 1;
            out.seconds += m.seconds;
            Ok(m)
        };
        let (up, down) = (
            (!p.bounds.excludes(x + h)).then_some(x + h),
            (!p.bounds.excludes(x - h)).then_some(x - h),
        );
        let (hi, lo, width) = match (up, down) {
            (Some(u), Some(d)) => (at(u)?, at(d)?, 2.0 * h),
            (Some(u), None) => (at(u)?, base.clone(), h),
            (None, Some(d)) => (base.clone(), at(d)?, h),
            (None, None) => {
                return Err(Error::failed(
                    Stage::Fit,
                    format!(
                        "{} = {}: no step of ±{} stays in its range {}, so its derivative cannot be taken",
                        p.key(),
                        number(x),
                        number(h),
                        p.bounds.describe()
                    ),
                ))
            }
        };
        for i in 0..n {
            if p.param.is_none() || !axial {
                out.d_axial_length[(i, c)] = (hi.axial_length[i] - lo.axial_length[i]) / width;
            }
            out.d_refraction_d[(i, c)] = (hi.refraction_d[i] - lo.refraction_d[i]) / width;
        }
    }
    Ok(out)
}

/// The stacked weighted residuals (model − y)/σ of every arm, their Jacobian by the
/// vector's parameters and the model's values, in the order of [`rows_of`].
pub fn stack(
    arms: &[Arm],
    layout: &Layout,
    values: &[f64],
    step: &mut growth::ProgressFn<'_>,
    runs: &mut (usize, f64),
) -> Result<super::lm::Evaluation, Error> {
    let rows = rows_of(arms);
    let local = layout.local();
    let mut r = DVector::zeros(rows.len());
    let mut j = DMatrix::zeros(rows.len(), layout.len());
    let mut model = vec![f64::NAN; rows.len()];
    let mut row = 0;
    for (a, arm) in arms.iter().enumerate() {
        let v = arm_values(
            &arm.scene,
            &local,
            &layout.local_values(a, values),
            &arm.data,
            step,
        )?;
        runs.0 += v.runs;
        runs.1 += v.seconds;
        for (i, o) in arm.data.rows.iter().enumerate() {
            for (what, y, sigma) in o.measured() {
                let (m, d) = match what {
                    Measured::AxialLength => (v.axial_length[i], &v.d_axial_length),
                    Measured::Refraction => (v.refraction_d[i], &v.d_refraction_d),
                };
                if !m.is_finite() || (0..local.len()).any(|c| !d[(i, c)].is_finite()) {
                    return Err(Error::failed(
                        Stage::Fit,
                        format!(
                            "{}: observation {} (t = {}): the growth run of {} gives no finite {}{} there (a refraction beyond ±25 D, or optics that trace no focus)",
                            arm.data.origin,
                            i + 1,
                            number(o.t),
                            arm.scene.origin,
                            what.column(),
                            if m.is_finite() { " derivative" } else { "" }
                        ),
                    ));
                }
                let w = 1.0 / sigma.unwrap_or(1.0);
                r[row] = (m - y) * w;
                model[row] = m;
                for c in 0..local.len() {
                    j[(row, layout.global(a, c))] += d[(i, c)] * w;
                }
                row += 1;
            }
        }
    }
    Ok((r, j, model))
}

/// The names of the vector's parameters as messages and the report's table show them:
/// the key, and a per-arm key's arm in brackets (`growth.Gamma[dual-focus]`).
pub fn names(layout: &Layout, arms: &[Arm]) -> Vec<String> {
    (0..layout.len())
        .map(|g| match layout.at(g) {
            (p, None) => p.key().to_string(),
            (p, Some(a)) => format!("{}[{}]", p.key(), arms[a].name.as_deref().unwrap_or("?")),
        })
        .collect()
}

/// The ranges of the vector's parameters, each narrowed in its arm's scene (or in every
/// arm's, for a shared key: the narrowest).
pub fn bounds(layout: &Layout, arms: &[Arm]) -> Vec<Bounds> {
    (0..layout.len())
        .map(|g| match layout.at(g) {
            (p, Some(a)) => p.in_scene(&arms[a].scene).bounds,
            (p, None) => {
                let mut b = p.bounds;
                for arm in arms {
                    let nb = p.in_scene(&arm.scene).bounds;
                    if let Some(hi) = nb.upper {
                        if b.upper.is_none_or(|u| hi <= u) {
                            b.upper = Some(hi);
                            b.upper_open = nb.upper_open;
                        }
                    }
                }
                b
            }
        })
        .collect()
}
