//! The stimulus a scene sets (the blue and red best-focus surfaces, or the eye's optics
//! traced to give them).

use super::{Scene, SceneError, Stimulus};
use crate::model::optics::{OpticsSpec, Source};
use crate::model::stimulus::{Surface, RED_OFFSET};

impl Scene {
    /// The blue best-focus surface in effect.
    pub fn blue(&self) -> Surface {
        self.growth.as_ref().map_or(self.stimulus.blue, |g| g.blue)
    }

    /// The red best-focus surface in effect.
    pub fn red(&self) -> Surface {
        self.growth.as_ref().map_or(self.stimulus.red, |g| g.red)
    }

    /// Change the blue surface; the red one follows it (pushed back by [`RED_OFFSET`]) as
    /// long as no red key was given.
    pub fn set_blue(&mut self, change: impl FnOnce(&mut Surface)) {
        self.edit_stimulus(|st| {
            change(&mut st.blue);
            if st.red_follows_blue {
                st.red = Surface {
                    offset: RED_OFFSET,
                    ..st.blue
                };
            }
        });
    }

    /// Change the red surface. The first red key starts from the default red surface
    /// (the published blue one pushed back by [`RED_OFFSET`]), not from the scene's blue.
    pub fn set_red(&mut self, change: impl FnOnce(&mut Surface)) {
        self.edit_stimulus(|st| {
            if st.red_follows_blue {
                st.red = Surface::default_red();
                st.red_follows_blue = false;
            }
            change(&mut st.red);
        });
    }

    /// The source of the stimulus's surfaces in effect.
    pub fn stimulus_source(&self) -> Source {
        self.growth
            .as_ref()
            .map_or(self.stimulus.source, |g| g.source)
    }

    /// The optics keys in effect.
    pub fn optics(&self) -> &OpticsSpec {
        self.growth
            .as_ref()
            .map_or(&self.stimulus.optics, |g| &g.optics)
    }

    /// The optics the scene's refraction in dioptres is computed with (docs/guide/eyewear.md,
    /// "Refraction in dioptres"): a growing scene's are those its growth run reports
    /// `refraction_D` with (its own with `stimulus.source = "optics"`, else the default
    /// optics); a scene that does not grow has optics of its own only with
    /// `stimulus.source = "optics"`. None for a scene that neither grows nor computes its
    /// optics: it has no eye to refract through.
    pub fn refraction_optics(&self) -> Option<OpticsSpec> {
        match &self.growth {
            Some(g) => Some(g.refraction_optics()),
            None if self.stimulus.source == Source::Optics => Some(self.stimulus.optics.clone()),
            None => None,
        }
    }

    /// Why [`Scene::refraction_optics`] is None, in a phrase: the scene's keys that would give
    /// it optics.
    pub fn no_refraction_optics(&self) -> String {
        "the scene has no optics to compute a refraction with: it does not grow and its stimulus.source is \"polynomial\" (set stimulus.source = \"optics\", or a growth key)".into()
    }

    /// The retina of a loaded, ungrown shell whose fields are `rows` (pole first), as a
    /// growth run measures it at t = 0 (docs/MODEL.md §6).
    pub fn retina_of(rows: &[crate::bvp::FieldRow]) -> Vec<(f64, f64)> {
        rows.iter()
            .map(|f| crate::model::stimulus::retina(f.z, f.r, f.h, f.theta))
            .collect()
    }

    /// The refraction (D) at the pole of the loaded, ungrown shell whose fields are `rows`,
    /// through the naked eye at t = 0: a growth run's first `refraction_D`. None when the
    /// scene has no optics to compute it with ([`Scene::refraction_optics`]); NaN beyond
    /// ±25 D.
    pub fn refraction_of(&self, rows: &[crate::bvp::FieldRow]) -> Option<f64> {
        let spec = self.refraction_optics()?;
        let z = rows.first().map_or(f64::NAN, |f| {
            crate::model::stimulus::retina(f.z, f.r, f.h, f.theta).0
        });
        Some(crate::growth::refraction::pole(&spec, 0.0, z))
    }

    /// Change the stimulus's source.
    pub fn set_stimulus_source(&mut self, source: Source) {
        self.edit_stimulus(|st| st.source = source);
    }

    /// Change the optics keys.
    pub fn set_optics(&mut self, change: impl FnOnce(&mut OpticsSpec)) {
        self.edit_stimulus(|st| change(&mut st.optics));
    }

    /// Edit the surfaces in effect (those of the growth model when the scene grows) and
    /// keep the two copies equal.
    fn edit_stimulus(&mut self, edit: impl FnOnce(&mut Stimulus)) {
        if let Some(g) = &self.growth {
            self.stimulus.blue = g.blue;
            self.stimulus.red = g.red;
            self.stimulus.source = g.source;
            self.stimulus.optics = g.optics.clone();
        }
        edit(&mut self.stimulus);
        if let Some(g) = &mut self.growth {
            g.blue = self.stimulus.blue;
            g.red = self.stimulus.red;
            g.source = self.stimulus.source;
            g.optics = self.stimulus.optics.clone();
        }
    }

    /// Trace the surfaces of a growing scene whose stimulus is computed from its optics
    /// (once: nothing is traced while the keys and the centre stay as they were traced).
    /// The error names the optics key to change.
    pub fn resolve_optics(&mut self) -> Result<(), SceneError> {
        self.trace_optics().map_err(|e| SceneError::Invalid {
            origin: self.origin_of_key(&e.key),
            key: e.key.to_string(),
            value: e.value,
            problem: e.problem,
        })
    }

    pub(super) fn trace_optics(&mut self) -> Result<(), crate::model::optics::OpticsKeyError> {
        self.prescribe_lenses()?;
        let Some(g) = &mut self.growth else {
            return Ok(());
        };
        if !g.is_resolved() {
            g.computed = Some(std::sync::Arc::new(
                g.optics.compute_over(g.blue.z_b, g.t_end)?,
            ));
        }
        crate::model::eyewear::refraction_table(&g.refraction_optics())?;
        Ok(())
    }

    /// Each prescribed lens's power (`power = "prescribe"`, docs/guide/eyewear.md): the
    /// correction of this scene's eye at t = 0, its loaded shell solved as a growth run
    /// solves it first, its retina's pole measured as refraction_D measures it
    /// (docs/MODEL.md §6), and the naked eye's refraction there
    /// ([`crate::model::eyewear::prescribe`]). Found again every time the optics are
    /// traced: any key (a cornea's radius, ΔP, the shell's size) changes the eye it corrects.
    fn prescribe_lenses(&mut self) -> Result<(), crate::model::optics::OpticsKeyError> {
        let optics = self.optics();
        let Some(first) = optics.lenses.iter().position(|l| l.prescribe.is_some()) else {
            return Ok(());
        };
        let cannot = |why: String| crate::model::optics::OpticsKeyError {
            key: format!("{}[{first}].power", super::parse::LENSES_KEY),
            value: "\"prescribe\"".into(),
            problem: format!("cannot be prescribed: {}", crate::text::one_line(&why)),
        };
        let problem = self.elastic_problem().map_err(|e| cannot(e.to_string()))?;
        let solution = problem
            .solve()
            .map_err(|e| cannot(format!("the eye at t = 0 does not solve: {e}")))?;
        let pole = solution
            .rows
            .first()
            .map(|f| crate::model::stimulus::retina(f.z, f.r, f.h, f.theta).0)
            .ok_or_else(|| cannot("the eye at t = 0 has no nodes".into()))?;
        let prescribed = crate::model::eyewear::prescribe(self.optics(), pole)?;
        self.set_optics(|o| o.lenses = prescribed.lenses);
        Ok(())
    }
}
