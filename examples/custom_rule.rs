//! A growth rule of your own, as a Rust trait object (docs/MODEL.md §6, "Growth rules"):
//! `cargo run --release --example custom_rule`.
//!
//! The hypothesis: the sclera responds to the blue surface's depth as the paper's rule
//! does near focus, but saturates far from it, g_v = a · tanh(d / a) with a = 0.2 mm. The
//! rule gives its value and its exact partial in the depth (for IDA's Newton matrix); the
//! scene grows with it through [`Scene::set_rule`], and the eye, driven less while far
//! from focus, grows less than under the paper's rule.

use std::sync::Arc;

use eyeshell::model::rule::{Drive, GrowthRule, Reads, RuleError, Seen};
use eyeshell::{Error, Scene};

/// g_v = a · tanh(d / a): the paper's d near focus, at most a (mm) far from it.
#[derive(Debug)]
struct Saturating {
    a: f64,
}

impl GrowthRule for Saturating {
    fn name(&self) -> &str {
        "saturating"
    }

    /// The depth of the blue surface only: neither the red surface nor the defocus.
    fn reads(&self) -> Reads {
        Reads::default()
    }

    fn drive(&self, seen: &[Seen], _partials: bool, out: &mut [Drive]) -> Result<(), RuleError> {
        for (o, s) in out.iter_mut().zip(seen) {
            let th = (s.depth / self.a).tanh();
            *o = Drive {
                value: self.a * th,
                d_depth: 1.0 - th * th,
                ..Drive::default()
            };
        }
        Ok(())
    }

    fn parameters(&self) -> Vec<(&'static str, f64)> {
        vec![("a", self.a)]
    }
}

fn main() -> Result<(), Error> {
    let mut scene = Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/const.toml"))?;
    scene.set("solver.nodes", 101)?;
    let papers = scene.grow(&mut ())?;
    scene.set_rule(Arc::new(Saturating { a: 0.2 }))?;
    let saturating = scene.grow(&mut ())?;
    let grown = |g: &eyeshell::Growth| {
        g.series.last().map_or(f64::NAN, |r| r.axial_length) - g.series[0].axial_length
    };
    let (by_paper, by_rule) = (grown(&papers), grown(&saturating));
    println!(
        "the eye grew {by_paper:.4} mm under the paper's rule, {by_rule:.4} mm under the saturating one ({} IDA steps)",
        saturating.stats.steps
    );
    // Both grow; the saturating drive (≤ the depth, and ≤ 0.2 mm) grows the eye less.
    assert!(
        by_rule > 0.0 && by_rule < by_paper,
        "{by_rule} vs {by_paper}"
    );
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}

/// The rule's partial is its value's derivative: the Jacobian IDA builds from it is exact.
#[test]
fn the_partial_is_the_derivative() {
    let rule = Saturating { a: 0.2 };
    for d in [-0.5, -0.01, 0.0, 0.03, 0.4] {
        let at = |d: f64| {
            let mut out = [Drive::default()];
            let seen = Seen {
                depth: d,
                ..Seen::default()
            };
            rule.drive(&[seen], true, &mut out).unwrap();
            out[0]
        };
        let h = 1e-6;
        let fd = (at(d + h).value - at(d - h).value) / (2.0 * h);
        assert!((at(d).d_depth - fd).abs() < 1e-8, "at d = {d}");
    }
}
