//! The paper's rule (docs/MODEL.md §6): the drive is the depth of the blue best-focus surface
//! behind the retina, so an eye grows while its retina lies in front of that surface, at a
//! rate in proportion to the distance, and stops on it.

use super::{Drive, GrowthRule, Reads, RuleError, Seen};

/// drive = d, the depth of the stimulus surface behind the retina (mm).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BlueSurface;

impl BlueSurface {
    pub const NAME: &'static str = "blue-surface";
}

impl GrowthRule for BlueSurface {
    fn name(&self) -> &str {
        Self::NAME
    }

    fn reads(&self) -> Reads {
        Reads::default()
    }

    /// The paper's surface is one image's: through a lens of several, the brightest.
    fn reads_every_image(&self) -> bool {
        false
    }

    fn drive(&self, seen: &[Seen], _partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        for (o, s) in out.iter_mut().zip(seen) {
            *o = Drive {
                value: s.depth,
                d_depth: 1.0,
                ..Drive::default()
            };
        }
        Ok(())
    }
}
