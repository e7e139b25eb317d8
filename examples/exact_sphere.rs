//! Solve the exact sphere (docs/MODEL.md §7) on three meshes and watch the error in r fall
//! at the scheme's order (4 for Hermite–Simpson): `cargo run --release --example exact_sphere`.

use eyeshell::model::cornea;
use eyeshell::{Error, Scene};

fn main() -> Result<(), Error> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/exact-sphere.toml");
    let mut scene = Scene::from_path(path)?;
    let alpha = cornea::stretch(&scene.params.cornea, scene.params.dp)?;
    let r0 = scene.params.r0;
    let mut last: Option<f64> = None;
    for nodes in [26, 51, 101] {
        scene.set("solver.nodes", nodes)?;
        let sol = scene.solve()?;
        let error = sol
            .rows
            .iter()
            .map(|row| (row.r - alpha * r0 * (row.sigma_ref / r0).sin()).abs())
            .fold(0.0, f64::max);
        let order = last.map(|e| (e / error).log2());
        let shown = order.map_or("-".to_string(), |p| format!("{p:.2}"));
        println!("N = {nodes:4}  max |r − r_exact| = {error:.3e}  observed order {shown}");
        if let Some(order) = order {
            assert!(
                order > 3.5,
                "Hermite–Simpson converges at order 4, observed {order:.2}"
            );
        }
        last = Some(error);
    }
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
