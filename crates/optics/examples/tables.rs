//! Prints the tables of docs/optics.md: the built-in eyes' paraxial figures and chromatic
//! aberration, the best-focus convergence in rays and GRIN tolerance, and the Atchison 2006
//! eye's 400 nm surfaces beside the paper's published blue surface.
//!
//! cargo run --release -p eyeshell-optics --example tables

use eyeshell_optics::{
    best_focus_with, eyes, paraxial, Criterion, Focus, FocusSettings, FocusSurface, GrinSettings,
    PolarFit, Pupil, SurfaceSettings, Surfaces,
};

fn eyes_table() {
    println!("## Built-in eyes (paraxial)\n");
    println!("| eye | F(555) D | focus(555) mm | axial length mm | F(400) − F(600) D | ΔRx(400 − 600) D | focus(600) − focus(400) mm |");
    println!("|---|---|---|---|---|---|---|");
    for name in eyes::BUILTIN {
        let eye = eyes::builtin(name).unwrap();
        let (g, b, r) = (
            paraxial(&eye, 555.0).unwrap(),
            paraxial(&eye, 400.0).unwrap(),
            paraxial(&eye, 600.0).unwrap(),
        );
        let l = eye.axial_length();
        println!(
            "| {name} | {:.3} | {:.4} | {:.2} | {:.3} | {:.3} | {:.4} |",
            g.power,
            g.focus,
            l,
            b.power - r.power,
            r.ocular_refraction(l) - b.ocular_refraction(l),
            r.focus - b.focus
        );
    }
    // The Indiana eye: Rx(λ) = 1.68524 − 0.63346/(λ − 0.21410), λ in µm.
    let rx = |l: f64| 1.68524 - 0.63346 / (l - 0.21410);
    println!(
        "\nIndiana chromatic eye: Rx(600) − Rx(400) = {:.3} D\n",
        rx(0.6) - rx(0.4)
    );
}

fn convergence() {
    let eye = eyes::atchison_2006();
    println!(
        "## Convergence (Atchison 2006, 400 nm, best-focus distance along the chief ray, mm)\n"
    );
    for (criterion, diameter) in [(Criterion::MeanSphere, 3.0), (Criterion::Strehl, 1.0)] {
        let pupil = Pupil {
            diameter,
            position: 3.7,
        };
        let at = |field: f64, n: usize, tol: f64| {
            let s = FocusSettings {
                rays_across: n,
                grin: GrinSettings {
                    tolerance: tol,
                    max_steps: 200_000,
                },
            };
            best_focus_with(&eye, 400.0, field, &pupil, criterion, &s)
                .unwrap()
                .distance
        };
        println!(
            "{} criterion, {diameter} mm pupil; rays across the pupil (GRIN tolerance 1e-9 mm):\n",
            criterion.name()
        );
        println!("| rays across | 0° | 20° | 40° |");
        println!("|---|---|---|---|");
        let fine: Vec<f64> = [0.0, 20.0, 40.0]
            .iter()
            .map(|&f| at(f, 256, 1e-9))
            .collect();
        for n in [8, 16, 32, 64, 128, 256] {
            let row: Vec<String> = [0.0, 20.0, 40.0]
                .iter()
                .zip(&fine)
                .map(|(&f, &r)| {
                    let d = at(f, n, 1e-9);
                    format!("{d:.6} ({:+.1e})", d - r)
                })
                .collect();
            println!("| {n} | {} |", row.join(" | "));
        }
        println!("\nGRIN tolerance (32 rays across):\n");
        println!("| tolerance mm | 0° | 20° | 40° |");
        println!("|---|---|---|---|");
        let fine: Vec<f64> = [0.0, 20.0, 40.0]
            .iter()
            .map(|&f| at(f, 32, 1e-12))
            .collect();
        for tol in [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11] {
            let row: Vec<String> = [0.0, 20.0, 40.0]
                .iter()
                .zip(&fine)
                .map(|(&f, &r)| {
                    let d = at(f, 32, tol);
                    format!("{d:.6} ({:+.1e})", d - r)
                })
                .collect();
            println!("| {tol:.0e} | {} |", row.join(" | "));
        }
        println!();
    }
}

/// The surface with each focus moved to the sagittal or tangential focus on its chief ray.
fn moved(surface: &FocusSurface, pick: impl Fn(&Focus) -> f64) -> FocusSurface {
    let mut s = surface.clone();
    for p in &mut s.points {
        let d = pick(p);
        p.z = p.chief_exit.0 + d * p.chief_direction.0;
        p.r = (p.chief_exit.1 + d * p.chief_direction.1).abs();
        p.distance = d;
    }
    s
}

fn paper() {
    let eye = eyes::atchison_2006();
    let blue = PolarFit::PAPER_BLUE;
    println!(
        "## The 400 nm surface beside the paper's blue surface (about z_B = {:.4} mm)\n",
        blue.z_b
    );
    let settings = SurfaceSettings {
        focus: FocusSettings {
            rays_across: 32,
            ..FocusSettings::default()
        },
        ..SurfaceSettings::default()
    };
    let mut columns: Vec<(String, FocusSurface)> = Vec::new();
    for diameter in [1.0, 3.0] {
        let pupil = Pupil {
            diameter,
            position: 3.7,
        };
        let st = Surfaces::compute(&eye, &[400.0], &pupil, Criterion::Strehl, &settings).unwrap();
        let ms =
            Surfaces::compute(&eye, &[400.0], &pupil, Criterion::MeanSphere, &settings).unwrap();
        columns.push((format!("Strehl {diameter} mm"), st.surfaces[0].clone()));
        columns.push((format!("mean sphere {diameter} mm"), ms.surfaces[0].clone()));
        if diameter == 1.0 {
            columns.push(("sagittal".into(), moved(&ms.surfaces[0], |p| p.sagittal)));
            columns.push((
                "tangential".into(),
                moved(&ms.surfaces[0], |p| p.tangential),
            ));
        }
    }
    let splines: Vec<_> = columns
        .iter()
        .map(|(_, s)| s.interpolant(blue.z_b).unwrap())
        .collect();
    let phi_end = splines
        .iter()
        .map(|s| s.phi_max())
        .fold(blue.phi_max, f64::min);
    println!("Computed R(φ) − published R_B(φ), mm (φ in rad; the computed surfaces end at the 40° field):\n");
    let names: Vec<&str> = columns.iter().map(|c| c.0.as_str()).collect();
    println!("| φ | R_B | {} |", names.join(" | "));
    println!("|---|---|{}", "---|".repeat(names.len()));
    let mut phi = 0.0;
    while phi <= phi_end + 1e-12 {
        let row: Vec<String> = splines
            .iter()
            .map(|s| format!("{:+.3}", s.radius(phi).unwrap() - blue.radius(phi)))
            .collect();
        println!(
            "| {phi:.3} | {:.3} | {} |",
            blue.radius(phi),
            row.join(" | ")
        );
        phi += 0.05;
    }
    println!();
    for ((name, s), sp) in columns.iter().zip(&splines) {
        let fit = s.polar_fit().unwrap();
        let about = s.polar_fit_about(blue.z_b).unwrap();
        println!(
            "{name}: φ at 40° = {:.4} rad; axial focus z = {:.4} mm; fit with free z_B: P1 {:.3} P2 {:.3} P3 {:.3} z_B {:.3} rms {:.1e}; about the published z_B: P1 {:.3} P2 {:.3} P3 {:.3} rms {:.1e}",
            sp.phi_max(),
            s.points[0].z,
            fit.p1, fit.p2, fit.p3, fit.z_b, fit.rms_residual,
            about.p1, about.p2, about.p3, about.rms_residual
        );
    }
    println!(
        "published: axial point z = {:.4} mm, φ_max = {:.4} rad",
        blue.p3 + blue.z_b,
        blue.phi_max
    );
}

fn main() {
    eyes_table();
    convergence();
    paper();
}
