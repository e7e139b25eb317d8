//! `eyeshell fit`: growth parameters fitted to measured axial lengths and refractions, of
//! one scene (`SCENE --data DATA`) or of several arms jointly (`--arm NAME=SCENE:DATA`).
//!
//! Every check comes before anything is written (one line, exit 2): the scenes, the `--fit`
//! and `--per-arm` keys, the arms, the data files, the output directory; then the fit
//! (crates/eyeshell/src/fit), which refuses (exit 2) a parameter the data cannot identify;
//! then the directory, whole or not at all: fit.json, the fitted scene(s), residuals.csv,
//! curve.csv and the figure(s).

use std::path::{Path, PathBuf};

use eyeshell::fit::{self, Arm, FitOptions, Observations};
use eyeshell::rundir::{self, OutputDir, OutputError};
use eyeshell::{Error, Origin, Scene, Subject};

use crate::args::FitArgs;
use crate::out;

/// The report of a fit.
pub const FIT_FILE: &str = "fit.json";
/// The scene with the estimates (of a joint fit: scene-NAME.toml, one per arm).
pub const SCENE_FILE: &str = "scene.toml";
/// Each measurement against the fitted model.
pub const RESIDUALS_FILE: &str = "residuals.csv";
/// The fitted (and the initial) axial length on a fine grid of times.
pub const CURVE_FILE: &str = "curve.csv";
/// Points of the curves in curve.csv and the figure.
const CURVE_POINTS: usize = 200;

/// An arm's fitted and initial curves, (t, axial length) each.
type Curves = (Vec<(f64, f64)>, Vec<(f64, f64)>);

/// One `--arm NAME=SCENE:DATA`, split: at the first '=', and at the last ':' whose right
/// side is an existing file (a path may hold ':' or '='), else the last ':'. An error is one
/// line naming the argument.
pub(crate) fn parse_arm(text: &str) -> Result<(String, PathBuf, PathBuf), Error> {
    let bad = |why: String| {
        Error::input(
            Subject::Argument("--arm".into()),
            format!(
                "--arm {}: {why}",
                eyeshell::text::excerpt(&eyeshell::text::one_line(text), 120)
            ),
        )
        .with_value(text)
        .with_origin(Origin::Argument)
    };
    let form = "give NAME=SCENE.toml:DATA.csv";
    let Some((name, rest)) = text.split_once('=') else {
        return Err(bad(format!("{form} (no '=' after the arm's name)")));
    };
    let name = name.trim();
    let ok = |c: char| c.is_ascii_alphanumeric() || "-_.".contains(c);
    if name.is_empty() || !name.chars().all(ok) || name.starts_with('.') {
        return Err(bad(format!(
            "{form}: the arm's name {name:?} must be letters, digits, '-', '_' or '.' (it names the arm's files)"
        )));
    }
    let colons: Vec<usize> = rest.match_indices(':').map(|(i, _)| i).collect();
    let Some(&last) = colons.last() else {
        return Err(bad(format!(
            "{form} (no ':' between the scene and the data file)"
        )));
    };
    let at = colons
        .iter()
        .rev()
        .copied()
        .find(|&i| Path::new(&rest[i + 1..]).is_file())
        .unwrap_or(last);
    let (scene, data) = (&rest[..at], &rest[at + 1..]);
    if scene.is_empty() || data.is_empty() {
        return Err(bad(format!("{form} (an empty scene or data path)")));
    }
    if !Path::new(data).is_file() {
        return Err(bad(format!("the data file {data:?} does not exist")));
    }
    Ok((name.to_string(), scene.into(), data.into()))
}

/// The arms of the command: one unnamed arm (`SCENE --data DATA`), or each `--arm`, with
/// every input path (the output directory may be none of them).
fn arms_of(a: &FitArgs) -> Result<(Vec<Arm>, Vec<PathBuf>), Error> {
    let load = |scene: &Path, data: &Path, name: Option<String>| -> Result<Arm, Error> {
        Ok(Arm {
            name,
            scene: Scene::from_file(scene, &a.set)?,
            data: Observations::read(data)?,
        })
    };
    if a.arm.is_empty() {
        let (Some(scene), Some(data)) = (&a.scene, &a.data) else {
            return Err(Error::input(
                Subject::Argument("--data".into()),
                "give SCENE.toml --data DATA.csv, or two --arm NAME=SCENE.toml:DATA.csv or more",
            )
            .with_origin(Origin::Argument));
        };
        if let Some(key) = a.per_arm.first() {
            return Err(Error::input(
                Subject::Argument("--per-arm".into()),
                format!("--per-arm {key}: a key of each arm's own needs arms (--arm NAME=SCENE.toml:DATA.csv, two or more)"),
            )
            .with_origin(Origin::Argument));
        }
        return Ok((
            vec![load(scene, data, None)?],
            vec![scene.clone(), data.clone()],
        ));
    }
    let parsed: Vec<(String, PathBuf, PathBuf)> = a
        .arm
        .iter()
        .map(|t| parse_arm(t))
        .collect::<Result<_, _>>()?;
    for (i, (name, _, _)) in parsed.iter().enumerate() {
        if parsed[..i].iter().any(|(n, _, _)| n == name) {
            return Err(Error::input(
                Subject::Argument("--arm".into()),
                format!("--arm {name}: two arms have this name (each arm's is its own)"),
            )
            .with_value(name.clone())
            .with_origin(Origin::Argument));
        }
    }
    if parsed.len() < 2 {
        return Err(Error::input(
            Subject::Argument("--arm".into()),
            format!(
                "--arm {}: a joint fit needs two arms or more (one scene is fitted as SCENE.toml --data DATA.csv)",
                parsed[0].0
            ),
        )
        .with_origin(Origin::Argument));
    }
    let mut inputs = vec![];
    let mut arms = vec![];
    for (name, scene, data) in parsed {
        arms.push(load(&scene, &data, Some(name))?);
        inputs.extend([scene, data]);
    }
    Ok((arms, inputs))
}

pub(crate) fn cmd_fit(a: &FitArgs) -> Result<(), Error> {
    let shared = fit::parse_fit_keys(&a.fit, "--fit")?;
    let per_arm = match a.per_arm.is_empty() {
        true => vec![],
        false => fit::parse_fit_keys(&a.per_arm, "--per-arm")?,
    };
    let (arms, inputs) = arms_of(a)?;
    let input_refs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let dir = OutputDir::create(&a.out, "fit", &input_refs)?;
    let options = FitOptions {
        max_iterations: a.max_iterations as usize,
        ..FitOptions::default()
    };
    let done = fit::fit_arms(
        arms.clone(),
        &shared,
        &per_arm,
        &options,
        &mut |_| {},
        &mut |_| Ok(()),
    )?;
    let r = &done.report;
    let write = |name: &str, bytes: &[u8]| dir.write_file(name, bytes).map_err(Error::from);
    write(FIT_FILE, fit::report_json(r).as_bytes())?;
    let keys: Vec<String> = r.parameters.iter().map(|p| p.key.clone()).collect();
    let mut keys_once = keys.clone();
    keys_once.dedup();
    for (arm, fitted) in arms.iter().zip(&done.scenes) {
        let file = match &arm.name {
            None => SCENE_FILE.to_string(),
            Some(n) => format!("scene-{n}.toml"),
        };
        write(
            &file,
            format!(
                "# The scene {} with {} fitted by `eyeshell fit` to {} (fit.json)\n{}",
                arm.scene.origin,
                keys_once.join(", "),
                arm.data.origin,
                fitted.to_toml()
            )
            .as_bytes(),
        )?;
    }
    // Each arm's fitted and initial curves.
    let curves: Vec<Curves> = (arms.iter().zip(&done.scenes))
        .map(|(arm, fitted)| {
            Ok((
                fit::curve(fitted, CURVE_POINTS)?,
                fit::curve(&arm.scene, CURVE_POINTS)?,
            ))
        })
        .collect::<Result<_, Error>>()?;
    write(RESIDUALS_FILE, &residuals_csv(&dir, &arms, r)?)?;
    write(CURVE_FILE, &curves_csv(&dir, &arms, &curves)?)?;
    for (arm, (f, i)) in arms.iter().zip(&curves) {
        let stem = match &arm.name {
            None => "fit".to_string(),
            Some(n) => format!("fit-{n}"),
        };
        let axis = crate::charts::TimeAxis::of(&arm.scene);
        crate::charts::fit_figure(r, arm.name.as_deref(), f, i, axis, &dir.file(&stem))?;
    }
    let target = dir.commit()?;
    if !a.quiet {
        out(&report_text(&done.scene, r, &target));
    }
    Ok(())
}

/// residuals.csv: the classic columns for the axial lengths of one scene; with
/// refractions or arms, one row per measurement naming it (and its arm).
fn residuals_csv(dir: &OutputDir, arms: &[Arm], r: &fit::FitReport) -> Result<Vec<u8>, Error> {
    let v = rundir::format_value;
    let g = arms[0].scene.growth.as_ref();
    let ages = g.is_some_and(|g| g.age_unit().is_some());
    let named = arms.iter().any(|a| a.name.is_some());
    let classic = !named && r.residuals.iter().all(|x| x.refraction_d.is_none());
    let io = |source| {
        Error::from(OutputError::Io {
            path: dir.file(RESIDUALS_FILE),
            source,
        })
    };
    let mut columns: Vec<&str> = vec![];
    if named {
        columns.push("arm");
    }
    if classic {
        columns.extend(["t", "axial_length"]);
    } else {
        columns.extend(["t", "measured", "value"]);
    }
    columns.extend(["sigma", "model", "residual", "weighted_residual"]);
    let rows = r.residuals.iter().map(|x| {
        let mut cells: Vec<String> = vec![];
        if named {
            cells.push(x.arm.clone().unwrap_or_default());
        }
        cells.push(v(x.t));
        if !classic {
            cells.push(x.measured().column().to_string());
        }
        cells.extend([
            v(x.observed()),
            x.sigma.map_or(String::new(), v),
            v(x.model),
            v(x.residual),
            v(x.weighted),
        ]);
        cells.extend(x.age.map(v));
        cells
    });
    rundir::table::csv_bytes(
        rundir::growth::with_age_column(&columns, ages),
        rows,
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(io)
}

/// curve.csv: the fitted and the initial axial length of each arm on a fine grid of times
/// (an arm column first in a joint fit).
fn curves_csv(dir: &OutputDir, arms: &[Arm], curves: &[Curves]) -> Result<Vec<u8>, Error> {
    let v = rundir::format_value;
    let named = arms.iter().any(|a| a.name.is_some());
    let g = arms[0].scene.growth.as_ref();
    let ages = g.is_some_and(|g| g.age_unit().is_some());
    let mut rows: Vec<Vec<String>> = vec![];
    for (arm, (f, i)) in arms.iter().zip(curves) {
        let g = arm.scene.growth.as_ref();
        for (f, i) in f.iter().zip(i) {
            let mut cells: Vec<String> = vec![];
            if let Some(n) = &arm.name {
                cells.push(n.clone());
            }
            cells.extend([v(f.0), v(f.1), v(i.1)]);
            cells.extend(g.and_then(|g| g.age_of(f.0)).map(v));
            rows.push(cells);
        }
    }
    let mut columns = vec![];
    if named {
        columns.push("arm");
    }
    columns.extend(["t", "fitted_axial_length", "initial_axial_length"]);
    rundir::table::csv_bytes(
        rundir::growth::with_age_column(&columns, ages),
        rows,
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|source| {
        Error::from(OutputError::Io {
            path: dir.file(CURVE_FILE),
            source,
        })
    })
}

/// The table `eyeshell fit` prints: the library's report, and where it was written.
pub fn report_text(scene: &Scene, r: &fit::FitReport, target: &std::path::Path) -> String {
    format!(
        "{}  output           {}\n",
        fit::report::report_table(scene, r),
        crate::shown(target)
    )
}
