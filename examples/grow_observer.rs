//! Grow the paper's constant-zone eye and watch it through an observer that receives every
//! snapshot as it is computed: `cargo run --release --example grow_observer`.

use eyeshell::growth::{Observer, ObserverError, Snapshot};
use eyeshell::{Error, Scene};

/// Prints the axial length at each snapshot and keeps the largest growth rate η seen.
struct Watch {
    max_eta: f64,
}

impl Observer for Watch {
    fn snapshot(&mut self, s: &Snapshot) -> Result<(), ObserverError> {
        let eta = s.growth.iter().map(|g| g.eta).fold(0.0, f64::max);
        self.max_eta = self.max_eta.max(eta);
        println!(
            "t = {:.2}  axial length {:.4} mm  {}  max η {eta:.2}",
            s.t,
            s.series.axial_length,
            s.series.class.as_str()
        );
        Ok(())
    }
}

fn main() -> Result<(), Error> {
    let scene = Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/const.toml"))?;
    let mut watch = Watch { max_eta: 0.0 };
    let growth = scene.grow(&mut watch)?;
    let (first, last) = (
        growth.series[0],
        *growth.series.last().expect("t_end is a snapshot"),
    );
    println!(
        "{} IDA steps in {:.3} s: the eye grew by {:.4} mm",
        growth.stats.steps,
        growth.stats.wall_seconds,
        last.axial_length - first.axial_length
    );
    assert!(last.axial_length > first.axial_length && watch.max_eta > 0.0);
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
