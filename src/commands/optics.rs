//! `eyeshell optics`: the best-focus surfaces of a scene's schematic eye (docs/guide/optics.md).
//!
//! The scene and its `optics.*` keys are checked first (one line naming the key, exit 2),
//! then the surfaces are traced: a ray that fails is the user's keys' (exit 2, the line
//! naming the surface, the field angle and the wavelength). The directory is written whole
//! or not at all: surfaces.csv, optics.json, optics.png and optics.svg. An eye whose keys
//! are tables over t is drawn as it is at `--at T` (default 0).

use eyeshell::model::optics::{OpticsKeyError, OpticsSpec};
use eyeshell::rundir::{self, OutputDir, OutputError};
use eyeshell::scene::{Scene, SceneError};
use eyeshell::Error;
use eyeshell_optics::{paraxial, ray_fan, Paraxial};

use crate::args::OpticsArgs;
use crate::out;

/// Every focus: wavelength, field, position, criterion, Strehl ratio.
pub const SURFACES_FILE: &str = "surfaces.csv";
/// The eye's paraxial figures, the chromatic aberration, the polar fits, the work.
pub const OPTICS_FILE: &str = "optics.json";
/// The figure's stem (optics.png, optics.svg).
const FIGURE: &str = "optics";
/// The first wavelength's surfaces against the scene's polynomial blue surface.
pub const PUBLISHED_FILE: &str = "published.csv";
/// Its figure's stem (published.png, published.svg).
const PUBLISHED_FIGURE: &str = "published";
/// The field angles of the figure's ray fans (degrees), those within `optics.max_field`.
const FAN_FIELDS: [f64; 3] = [0.0, 20.0, 40.0];

/// A problem with an optics key, as the scene's error (the user's: exit 2), from where the
/// key was given (the file, or the `--set` that gave it).
fn key_error(scene: &Scene, e: OpticsKeyError) -> Error {
    Error::from(SceneError::Invalid {
        origin: scene.origin_of_key(&e.key),
        key: e.key.to_string(),
        value: e.value,
        problem: e.problem,
    })
}

pub(crate) fn cmd_optics(a: &OpticsArgs) -> Result<(), Error> {
    let scene = a.scene.load()?;
    let spec: OpticsSpec = scene.optics().clone();
    // The eye over the whole span it can be drawn at (`--at`), not only at its tables' points.
    let span = scene.growth.as_ref().map_or(1.0, |g| g.t_end);
    spec.check_over(span).map_err(|e| key_error(&scene, e))?;
    let z_c = scene.blue().z_b;
    let t = growth_time(&scene, a.at)?;
    let start = std::time::Instant::now();
    let computed = spec
        .compute_eye_at(t, z_c)
        .map_err(|e| key_error(&scene, e))?;
    // The figures' rays go through the image the surfaces are (a multifocal lens at that
    // image's power).
    let system = eyeshell::model::eyewear::worn_at(&computed.main_spec(), t)
        .map_err(|e| key_error(&scene, e))?;
    let paraxials: Vec<Paraxial> = spec
        .wavelengths
        .iter()
        .map(|&w| paraxial(&system, w))
        .collect::<Result<_, _>>()
        .map_err(|e| key_error(&scene, spec.explain(&e)))?;
    // Fans of the first wavelength, drawn to just behind the farthest focus.
    let end_z = computed
        .surfaces
        .surfaces
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.z))
        .fold(0.0, f64::max)
        + 1.0;
    let pupil = spec.pupil_stop(&system);
    let mut fans = Vec::new();
    for field in FAN_FIELDS.into_iter().filter(|f| *f <= spec.max_field) {
        let fan = ray_fan(&system, spec.wavelengths[0], field, &pupil, 7, end_z)
            .map_err(|e| key_error(&scene, spec.explain(&e)))?;
        fans.push((field, fan));
    }
    // Everything traced before the directory is made: a refusal leaves nothing behind.
    let dir = OutputDir::create(&a.out, "optics", &[a.scene.scene.as_path()])?;
    let io = |name: &str, source: std::io::Error| {
        Error::from(OutputError::Io {
            path: dir.file(name),
            source,
        })
    };
    let write = |name: &str, bytes: &[u8]| dir.write_file(name, bytes).map_err(Error::from);
    let v = rundir::format_value;
    // One block of rows per image (one for a lens of one smooth profile), each focus with
    // the share of the light its image carries at that field.
    let rows = computed.images.iter().enumerate().flat_map(|(k, image)| {
        image.surfaces.surfaces.iter().flat_map(move |s| {
            s.points.iter().enumerate().map(move |(j, p)| {
                [
                    v(p.wavelength_nm),
                    v(p.field_deg),
                    v(p.z),
                    v(p.r),
                    p.criterion.name().to_string(),
                    v(p.strehl),
                    k.to_string(),
                    v(image.share.traced(j)),
                ]
            })
        })
    });
    let table = rundir::table::csv_bytes(
        [
            "wavelength_nm",
            "field_deg",
            "z",
            "r",
            "criterion",
            "strehl",
            "image",
            "share",
        ],
        rows,
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(SURFACES_FILE, e))?;
    write(SURFACES_FILE, &table)?;
    let json = optics_json(
        &spec,
        &computed,
        &paraxials,
        &system,
        z_c,
        t,
        start.elapsed().as_secs_f64(),
    );
    write(OPTICS_FILE, json.as_bytes())?;
    crate::charts::optics_figure(&system, &computed, &fans, &dir.file(FIGURE))?;
    let rows = against_polynomial(&computed, &scene.blue());
    let v = rundir::format_value;
    let table = rundir::table::csv_bytes(
        [
            "field_deg",
            "phi",
            "R_polynomial",
            "criterion_minus_polynomial",
            "sagittal_minus_polynomial",
            "tangential_minus_polynomial",
        ],
        rows.iter().map(|r| r.map(v)),
        rundir::table::QuoteStyle::Necessary,
    )
    .map_err(|e| io(PUBLISHED_FILE, e))?;
    write(PUBLISHED_FILE, &table)?;
    crate::charts::published_figure(
        &rows,
        spec.criterion().name(),
        spec.wavelengths[0],
        &dir.file(PUBLISHED_FIGURE),
    )?;
    let target = dir.commit()?;
    if !a.quiet {
        let blue = &computed.surfaces.surfaces[0];
        let when = if spec.times().is_empty() {
            String::new()
        } else {
            format!(" at t = {}", eyeshell::text::number(t))
        };
        out(&format!(
            "{} eye{when}, {} mm pupil, {}: {} surfaces of {} fields, {} rays traced\n  written to {}\n",
            spec.eye_name(),
            eyeshell::text::number(spec.pupil),
            spec.criterion().name(),
            computed.surfaces.surfaces.len(),
            blue.points.len(),
            computed.surfaces.rays_traced,
            crate::shown(&target)
        ));
    }
    Ok(())
}

/// The growth time of `--at`: 0 by default; else a finite time within [0, growth.t_end]
/// (within [0, 1] for a scene that does not grow), as the user's error otherwise.
fn growth_time(scene: &Scene, at: Option<f64>) -> Result<f64, Error> {
    let Some(t) = at else {
        return Ok(0.0);
    };
    let end = scene.growth.as_ref().map_or(1.0, |g| g.t_end);
    if !(t >= 0.0 && t <= end) {
        return Err(Error::input(
            eyeshell::Subject::Argument("--at".into()),
            format!(
                "--at {}: the eye's growth time must lie in [0, {}] (growth.t_end)",
                eyeshell::text::number(t),
                eyeshell::text::number(end)
            ),
        )
        .with_value(eyeshell::text::number(t))
        .with_origin(eyeshell::Origin::Argument));
    }
    Ok(t)
}

/// The first wavelength's best focus, and its sagittal and tangential foci, against the
/// scene's polynomial blue surface (`stimulus.blue.*`, the published one by default), in its
/// polar frame about z_B: for each field, the field, the best focus's φ, R_B(φ) and each
/// focus's R − R_B(φ) at its own φ (mm; negative: in front of the polynomial surface).
fn against_polynomial(
    c: &eyeshell::model::optics::ComputedOptics,
    blue: &eyeshell::model::stimulus::Surface,
) -> Vec<[f64; 6]> {
    let diff = |z: f64, r: f64| blue.depth(z, r);
    c.surfaces.surfaces[0]
        .points
        .iter()
        .map(|p| {
            let on_chief = |s: f64| {
                let (z, y) = (
                    p.chief_exit.0 + s * p.chief_direction.0,
                    p.chief_exit.1 + s * p.chief_direction.1,
                );
                -diff(z, y.abs())
            };
            let phi = blue.angle(p.z, p.r);
            [
                p.field_deg,
                phi,
                blue.radius(phi),
                -diff(p.z, p.r),
                on_chief(p.sagittal),
                on_chief(p.tangential),
            ]
        })
        .collect()
}

/// optics.json: the request, the paraxial figures at each wavelength, the longitudinal
/// chromatic aberration between the first two, each surface's polar fit about z_B.
fn optics_json(
    spec: &OpticsSpec,
    c: &eyeshell::model::optics::ComputedOptics,
    paraxials: &[Paraxial],
    system: &eyeshell_optics::OpticalSystem,
    z_b: f64,
    t: f64,
    wall_seconds: f64,
) -> String {
    use serde_json::json;
    let par: Vec<_> = paraxials
        .iter()
        .map(|p| {
            serde_json::json!({
                "wavelength_nm": p.wavelength_nm,
                "power_dioptres": p.power,
                "back_focal_distance_mm": p.back_focal_distance,
                "focus_mm": p.focus,
            })
        })
        .collect();
    let surfaces: Vec<_> = c
        .surfaces
        .surfaces
        .iter()
        .map(|s| {
            let fit = s.polar_fit_about(z_b).ok().map(|f| {
                json!({
                    "P1": f.p1, "P2": f.p2, "P3": f.p3, "z_B": f.z_b, "phi_max": f.phi_max,
                    "rms_residual_mm": f.rms_residual, "max_residual_mm": f.max_residual,
                })
            });
            serde_json::json!({
                "wavelength_nm": s.wavelength_nm,
                "fields": s.points.len(),
                "axial_focus_mm": s.points.first().map(|p| p.z),
                "polar_fit": fit,
            })
        })
        .collect();
    let mut doc = json!({
        "eye": spec.eye_name(),
        "pupil_mm": spec.pupil,
        "pupil_position_mm": spec.pupil_stop(system).position,
        "focus": spec.criterion().name(),
        "max_field_deg": spec.max_field,
        "wavelengths_nm": spec.wavelengths,
        "paraxial": par,
        "chromatic_aberration": chromatic_json(paraxials, system),
        "surfaces": surfaces,
        "images": images_json(c),
        "rays_traced": c.surfaces.rays_traced,
        "wall_seconds": wall_seconds,
    });
    // Eyewear: how far out the pupil's rays cross each lens, and the zones they never
    // reach (allowed: a real lens is wider than what the eye looks through).
    if !spec.lenses.is_empty() {
        // The same fan the surfaces' computation checked the lenses' edges with, so it
        // traces here.
        let reach = eyeshell::model::eyewear::lens_reach(spec).unwrap_or_default();
        let lenses: Vec<_> = spec
            .lenses
            .iter()
            .zip(reach)
            .enumerate()
            .map(|(i, (lens, reach))| {
                let unseen: Vec<_> = lens
                    .zone_starts()
                    .into_iter()
                    .filter(|(_, start)| *start >= reach)
                    .map(|(item, start)| {
                        json!({ "zone": format!("optics.lenses[{i}].{item}"), "starts_mm": start })
                    })
                    .collect();
                json!({ "lens": i, "rays_reach_mm": reach, "zones_no_ray_crosses": unseen })
            })
            .collect();
        doc["lenses"] = json!(lenses);
    }
    // An eye that changes with age says which time it was traced at.
    if !spec.times().is_empty() {
        doc["t"] = json!(t);
    }
    let mut text = serde_json::to_string_pretty(&doc).unwrap_or_default();
    text.push('\n');
    text
}

/// The longitudinal chromatic aberration between the first two wavelengths (null with one):
/// the difference of equivalent power, of the paraxial foci, and the chromatic difference of
/// refraction Rx(second) − Rx(first), the ocular refraction at the first vertex (the corneal
/// apex, or the spectacle lens worn) of an eye whose retina lies at the eye's axial length:
/// the quantity of Thibos et al. 1992's Indiana chromatic eye (docs/optics.md, "The eyes'
/// paraxial figures and chromatic aberration").
fn chromatic_json(
    paraxials: &[Paraxial],
    system: &eyeshell_optics::OpticalSystem,
) -> serde_json::Value {
    let [a, b, ..] = paraxials else {
        return serde_json::Value::Null;
    };
    let retina = system.axial_length();
    serde_json::json!({
        "wavelengths_nm": [a.wavelength_nm, b.wavelength_nm],
        "power_difference_dioptres": a.power - b.power,
        "focus_difference_mm": b.focus - a.focus,
        "refraction_difference_dioptres": b.ocular_refraction(retina) - a.ocular_refraction(retina),
        "refraction_retina_mm": retina,
    })
}

/// Each image's power (null for the one image of a lens of one smooth profile), its share of
/// the light on the axis and its axial focus at each wavelength.
fn images_json(c: &eyeshell::model::optics::ComputedOptics) -> serde_json::Value {
    let images: Vec<_> = (c.images.iter().enumerate())
        .map(|(k, image)| {
            let foci: Vec<_> = (image.surfaces.surfaces.iter())
                .map(|s| serde_json::json!({ "wavelength_nm": s.wavelength_nm, "axial_focus_mm": s.points.first().map(|p| p.z) }))
                .collect();
            serde_json::json!({
                "image": k,
                "power_dioptres": image.power,
                "share_on_axis": image.share.traced(0),
                "foci": foci,
            })
        })
        .collect();
    serde_json::json!(images)
}
