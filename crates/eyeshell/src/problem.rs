//! A scene's problems: the checked [`ElasticProblem`] and [`GrowthProblem`] of the core
//! (eyeshell_core::problem), built from a scene after its keys are validated, so that
//! nothing is solved or grown on values no one checked (a scene whose fields were changed
//! since it was read is validated again here). A problem's own refusal is reported in the
//! scene's terms: the key that sets the quantity, its value and the scene's origin.

pub use eyeshell_core::problem::{
    ElasticProblem, ElasticProblemBuilder, GrowthProblem, GrowthProblemBuilder, ProblemError,
    Quantity,
};

use crate::scene::{Scene, SceneError};

/// The scene key that sets `quantity` (the scene layer's table, scene/names.rs).
pub use crate::scene::names::key_of;

/// A problem's refusal as the scene's: origin, key, value, what is wrong.
fn scene_error(scene: &Scene, e: ProblemError) -> SceneError {
    let key = key_of(e.quantity());
    let value = crate::scene::keys::find(key)
        .map(|spec| crate::scene::show(&spec.get(scene)))
        .unwrap_or_default();
    SceneError::Invalid {
        origin: scene.origin.clone(),
        key: key.to_string(),
        value,
        problem: e.to_string(),
    }
}

impl Scene {
    /// The scene's elastic problem (docs/MODEL.md §3): its keys validated, then checked by
    /// the problem's builder.
    ///
    /// # Errors
    /// A [`SceneError::Invalid`] naming the key, as [`Scene::validate`] reports it.
    pub fn elastic_problem(&self) -> Result<ElasticProblem, SceneError> {
        self.validate()?;
        ElasticProblem::builder()
            .params(self.params)
            .solver(self.solver)
            .build()
            .map_err(|e| scene_error(self, e))
    }

    /// The scene's growth problem (docs/MODEL.md §5–6), None for a scene that does not grow.
    ///
    /// # Errors
    /// As [`Scene::elastic_problem`].
    pub fn growth_problem(&self) -> Result<Option<GrowthProblem>, SceneError> {
        let Some(growth) = &self.growth else {
            return Ok(None);
        };
        let elastic = self.elastic_problem()?;
        GrowthProblem::builder(elastic)
            .growth(growth.clone())
            .settings(self.growth_settings.clone())
            .build()
            .map(Some)
            .map_err(|e| scene_error(self, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvp::settings::SolverSettings;
    use crate::growth::{GrowthParams, GrowthSettings};
    use crate::model::params::Params;

    /// The paper's scene with growth on, on a small mesh.
    fn growing() -> Scene {
        let mut scene = Scene::default_scene();
        scene
            .set_all([("solver.nodes", "51"), ("growth.eta0", "70")])
            .unwrap();
        scene
    }

    /// The key a scene's validation blames, and the key its problem's refusal names.
    fn keys(scene: &Scene) -> (Option<String>, Option<String>) {
        let validated = scene
            .validate()
            .err()
            .and_then(|e| e.key().map(str::to_string));
        let built = match scene.growth {
            Some(_) => scene.growth_problem().map(|_| ()),
            None => scene.elastic_problem().map(|_| ()),
        };
        (
            validated,
            built.err().and_then(|e| e.key().map(str::to_string)),
        )
    }

    /// Values only a change of the scene's fields can give (Scene::set refuses them): a
    /// scene's problem refuses each, naming the key its validation names, and the core's
    /// builder, given the same parts, refuses the cross-key limits and the numbers it
    /// needs itself, naming the quantity of that key.
    #[test]
    fn the_builder_refuses_what_validation_refuses_by_key() {
        type Change = fn(&mut Scene);
        let cases: [(&str, Change, bool); 10] = [
            ("pressure.dP", |s| s.params.dp = 1e3, true),
            ("pressure.dP", |s| s.params.dp = f64::NAN, true),
            ("solver.epsilon", |s| s.solver.epsilon = 40.0, true),
            ("material.H0", |s| s.params.h0 = -0.1, true),
            ("geometry.fraction", |s| s.params.fraction = 1.5, false),
            ("solver.richardson", |s| s.solver.richardson = true, true),
            ("growth.t_end", |s| s.growth_mut().t_end = 1e-200, true),
            (
                "output.times",
                |s| s.growth_settings.output_times = vec![0.5, 3.0],
                true,
            ),
            ("solver.rtol", |s| s.growth_settings.rtol = 0.0, true),
            ("growth.delta", |s| s.growth_mut().delta = -1.0, true),
        ];
        for (key, change, by_core) in cases {
            let mut scene = growing();
            change(&mut scene);
            let (validated, built) = keys(&scene);
            assert_eq!(validated.as_deref(), Some(key), "validation of {key}");
            assert_eq!(built.as_deref(), Some(key), "the scene's problem for {key}");
            let core = ElasticProblem::builder()
                .params(scene.params)
                .solver(scene.solver)
                .build()
                .and_then(|elastic| {
                    GrowthProblem::builder(elastic)
                        .growth(scene.growth.clone().unwrap())
                        .settings(scene.growth_settings.clone())
                        .build()
                });
            match by_core {
                true => assert_eq!(
                    core.map(|_| ()).map_err(|e| key_of(e.quantity())),
                    Err(key),
                    "the core's builder for {key}"
                ),
                // A key's own range that only the scene knows.
                false => assert!(core.is_ok(), "{key}"),
            }
        }
    }

    /// A scene whose fields were changed since it was read is validated again before it is
    /// solved or grown: no solve runs on values nobody checked.
    #[test]
    fn a_changed_scene_is_checked_before_it_is_solved() {
        // A shell past the equator: the solver would take it, the scene's range does not.
        let mut scene = Scene::default_scene();
        scene.params.fraction = 1.5;
        let e = scene.solve().unwrap_err().to_string();
        assert!(e.contains("geometry.fraction") && e.contains("1.5"), "{e}");
        let mut scene = growing();
        scene.growth_settings.output_times = vec![2.0];
        let e = scene.grow(&mut ()).unwrap_err().to_string();
        assert!(e.contains("output.times"), "{e}");
    }

    /// The problem built from a scene is the scene's parts, and grows as they do.
    #[test]
    fn the_scenes_problem_is_its_parts() {
        let scene = growing();
        let problem = scene.growth_problem().unwrap().unwrap();
        assert_eq!(problem.params(), &scene.params);
        assert_eq!(problem.solver(), &scene.solver);
        assert_eq!(Some(problem.growth()), scene.growth.as_ref());
        assert_eq!(problem.settings(), &scene.growth_settings);
        let by_scene = scene.grow(&mut ()).unwrap();
        let by_problem = crate::growth::grow(&problem, &mut ()).unwrap();
        assert_eq!(by_scene.stats.steps, by_problem.steps);
        assert!(by_scene.series.last().unwrap().axial_length > 0.0);
        // The defaults build, and an elastic scene has no growth problem.
        let elastic = ElasticProblem::builder()
            .params(Params::default())
            .solver(SolverSettings::default())
            .build()
            .unwrap();
        GrowthProblem::builder(elastic)
            .growth(GrowthParams::default())
            .settings(GrowthSettings::default())
            .build()
            .unwrap();
        assert!(Scene::default_scene().growth_problem().unwrap().is_none());
    }
}
