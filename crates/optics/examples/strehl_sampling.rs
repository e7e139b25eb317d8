//! Prints docs/optics.md's table of the Strehl focus against the through-focus Strehl of 128
//! traced rays across the pupil: the Atchison 2006 eye at 400 nm, 3 and 4 mm pupils, fields
//! 0–40° by 5°, and the focus at 40° against the pupil.
//!
//! cargo run --release -p eyeshell-optics --example strehl_sampling

use eyeshell_optics::{
    best_focus_with, eyes, traced_strehl, Criterion, FocusSettings, OpticalSystem, Pupil,
};

/// The maximum of the traced rays' through-focus Strehl between the astigmatic foci and
/// 0.3 mm beyond, on a 1 µm grid.
fn traced_maximum(eye: &OpticalSystem, field: f64, pupil: &Pupil, rays: usize) -> (f64, f64) {
    let settings = FocusSettings {
        rays_across: rays,
        ..FocusSettings::default()
    };
    let f = best_focus_with(eye, 400.0, field, pupil, Criterion::MeanSphere, &settings).unwrap();
    let (lo, hi) = (
        f.tangential.min(f.sagittal) - 0.3,
        f.tangential.max(f.sagittal) + 0.3,
    );
    let count = ((hi - lo) / 0.001) as usize + 1;
    let scan = traced_strehl(eye, 400.0, field, pupil, &settings, (lo, hi, count)).unwrap();
    let (i, s) =
        scan.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |b, (i, &v)| if v > b.1 { (i, v) } else { b },
        );
    // The parabola through the largest value and its neighbours.
    let h = (hi - lo) / (count - 1) as f64;
    let (a, c) = (scan[i.max(1) - 1], scan[(i + 1).min(count - 1)]);
    let shift = if 0 < i && i + 1 < count && a + c < 2.0 * s {
        0.5 * (a - c) / (a - 2.0 * s + c)
    } else {
        0.0
    };
    (lo + (i as f64 + shift) * h, s)
}

fn main() {
    let eye = eyes::atchison_2006();
    let position = eye.pupil_position.unwrap();
    let flag = |f: &str| std::env::args().any(|a| a == f);
    fields(&eye, position, flag("--traced-16"));
    against_the_pupil(&eye, position);
    if flag("--counts") {
        counts(&eye, position);
    }
    if flag("--pupils") {
        pupils(&eye, position);
    }
    if flag("--surface") {
        surface(&eye, position);
    }
    if flag("--time") {
        timing(&eye, position);
    }
    if flag("--256") {
        traced_256(&eye, position);
    }
}

/// The Strehl focus at 0–40° by 5° with 3 and 4 mm pupils against 128 traced rays (and 16).
fn fields(eye: &OpticalSystem, position: f64, traced_16: bool) {
    for diameter in [3.0, 4.0] {
        let pupil = Pupil { diameter, position };
        println!("\n{diameter} mm pupil\n");
        println!("| field ° | tangential | sagittal | Strehl focus | S | sum rays | 128 traced | S | 16 traced | S |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for field in (0..=8).map(|i| 5.0 * i as f64) {
            let t = std::time::Instant::now();
            let f = best_focus(eye, field, &pupil);
            let secs = t.elapsed().as_secs_f64();
            let (d, s) = traced_maximum(eye, field, &pupil, 128);
            let (d16, s16) = if traced_16 {
                traced_maximum(eye, field, &pupil, 16)
            } else {
                (f64::NAN, f64::NAN)
            };
            println!(
                "| {field:.0} | {:.4} | {:.4} | {:.4} | {:.4} | {} | {d:.4} | {s:.4} | {d16:.4} | {s16:.4} | ({:+.4}, {secs:.3} s)",
                f.tangential, f.sagittal, f.distance, f.strehl, f.strehl_rays, f.distance - d
            );
        }
    }
}

/// The focus at 40° against the pupil (1, 2, 3, 4 mm).
fn against_the_pupil(eye: &OpticalSystem, position: f64) {
    println!("\n40°, focus against the pupil\n");
    println!("| pupil mm | tangential | sagittal | Strehl focus | S | sum rays | 128 traced | S |");
    println!("|---|---|---|---|---|---|---|---|");
    for diameter in [1.0, 2.0, 3.0, 4.0] {
        let pupil = Pupil { diameter, position };
        let f = best_focus(eye, 40.0, &pupil);
        let (d, s) = traced_maximum(eye, 40.0, &pupil, 128);
        println!(
            "| {diameter:.0} | {:.4} | {:.4} | {:.4} | {:.4} | {} | {d:.4} | {s:.4} |",
            f.tangential, f.sagittal, f.distance, f.strehl, f.strehl_rays
        );
    }
}

/// The focus at 0, 20, 30, 40° against the traced rays across the pupil.
fn counts(eye: &OpticalSystem, position: f64) {
    for diameter in [1.0, 3.0, 4.0] {
        let pupil = Pupil { diameter, position };
        for field in [0.0, 20.0, 30.0, 40.0] {
            let row: Vec<String> = [4, 6, 8, 12, 16, 32]
                .iter()
                .map(|&n| {
                    let s = FocusSettings {
                        rays_across: n,
                        ..FocusSettings::default()
                    };
                    let f =
                        best_focus_with(eye, 400.0, field, &pupil, Criterion::Strehl, &s).unwrap();
                    format!("{n}: {:.5} {:.4} ({})", f.distance, f.strehl, f.strehl_rays)
                })
                .collect();
            println!("{diameter} mm {field}°: {}", row.join(" | "));
        }
    }
}

/// The focus at 40° against the pupil by 0.25 mm, its second differences, and the Strehl
/// ratio of 128 traced rays on each line.
fn pupils(eye: &OpticalSystem, position: f64) {
    let d: Vec<f64> = (0..=12)
        .map(|i| {
            let pupil = Pupil {
                diameter: 1.0 + 0.25 * i as f64,
                position,
            };
            let f = best_focus(eye, 40.0, &pupil);
            println!(
                "{:.2} mm: {:.5} ({:.5} {:.5}) S {:.4} rays {}",
                pupil.diameter, f.distance, f.tangential, f.sagittal, f.strehl, f.strehl_rays
            );
            f.distance
        })
        .collect();
    for diameter in [1.0, 3.0, 4.0] {
        let pupil = Pupil { diameter, position };
        let f = best_focus(eye, 40.0, &pupil);
        let settings = FocusSettings {
            rays_across: 128,
            ..FocusSettings::default()
        };
        let at = |s: f64| {
            traced_strehl(eye, 400.0, 40.0, &pupil, &settings, (s, s + 1e-6, 2)).unwrap()[0]
        };
        println!(
            "{diameter} mm, 40°, 128 traced: S on the tangential line {:.4}, on the sagittal line {:.4}, at the Strehl focus {:.4}",
            at(f.tangential),
            at(f.sagittal),
            at(f.distance)
        );
    }
    let second: Vec<String> = d
        .windows(3)
        .map(|w| format!("{:+.4}", w[0] - 2.0 * w[1] + w[2]))
        .collect();
    println!("second differences: {}", second.join(" "));
}

/// The focus's place between the lines, field by field, with 1 and 3 mm pupils.
fn surface(eye: &OpticalSystem, position: f64) {
    // The focus's place between the lines, u = (s − s_t)/(s_s − s_t), field by field.
    for diameter in [1.0, 3.0] {
        let pupil = Pupil { diameter, position };
        let row: Vec<String> = (0..=40)
            .map(|field| {
                let f = best_focus(eye, field as f64, &pupil);
                let u = (f.distance - f.tangential) / (f.sagittal - f.tangential);
                format!("{field}: {u:.3} ({:.4})", f.strehl)
            })
            .collect();
        println!("{diameter} mm, u: {}", row.join(" "));
    }
}

/// The surfaces bench's work in CPU time.
fn timing(eye: &OpticalSystem, position: f64) {
    // The surfaces bench's work (400 and 600 nm × 41 fields, 16 rays across), timed in
    // this process's CPU seconds (/proc/self/stat: utime + stime, in 1/100 s).
    let cpu = || -> f64 {
        let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
        let after = stat.rsplit(')').next().unwrap_or("");
        // Fields 14 and 15 of the line; the first after the name is field 3.
        let f: Vec<&str> = after.split_whitespace().collect();
        let tick = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok());
        match (tick(11), tick(12)) {
            (Some(u), Some(s)) => (u + s) / 100.0,
            _ => f64::NAN,
        }
    };
    for (criterion, diameter) in [
        (Criterion::Strehl, 3.0),
        (Criterion::Strehl, 4.0),
        (Criterion::MeanSphere, 3.0),
    ] {
        let pupil = Pupil { diameter, position };
        let repeats = 10;
        let (c0, t0) = (cpu(), std::time::Instant::now());
        for _ in 0..repeats {
            eyeshell_optics::Surfaces::compute(
                eye,
                &[400.0, 600.0],
                &pupil,
                criterion,
                &eyeshell_optics::SurfaceSettings::default(),
            )
            .unwrap();
        }
        println!(
            "{} {diameter} mm: {:.0} ms CPU, {:.0} ms wall per computation",
            criterion.name(),
            (cpu() - c0) / repeats as f64 * 1e3,
            t0.elapsed().as_secs_f64() / repeats as f64 * 1e3
        );
    }
}

/// The 128 traced rays' maxima at 40° against 256 traced rays'.
fn traced_256(eye: &OpticalSystem, position: f64) {
    for diameter in [3.0, 4.0] {
        let pupil = Pupil { diameter, position };
        let (d, s) = traced_maximum(eye, 40.0, &pupil, 256);
        println!("256 traced, {diameter} mm, 40°: {d:.4} {s:.4}");
    }
}

fn best_focus(eye: &OpticalSystem, field: f64, pupil: &Pupil) -> eyeshell_optics::Focus {
    best_focus_with(
        eye,
        400.0,
        field,
        pupil,
        Criterion::Strehl,
        &FocusSettings::default(),
    )
    .unwrap()
}
