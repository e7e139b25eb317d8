//! `eyeshell optics`: the best-focus surfaces of a scene's schematic eye (docs/guide/optics.md).
//!
//! The scene and its `optics.*` keys are checked first (one line naming the key, exit 2),
//! then the surfaces are traced: a ray that fails is the user's keys' (exit 2, the line
//! naming the surface, the field angle and the wavelength). The directory is written whole
//! or not at all: surfaces.csv, optics.json, optics.png and optics.svg. An eye whose keys
//! are tables over t is drawn as it is at `--at T` (default 0).

use eyeshell::growth::refraction::RefractionAt;
use eyeshell::growth::GrowthParams;
use eyeshell::model::optics::{OpticsKeyError, OpticsSpec};
use eyeshell::rundir::{self, OutputDir, OutputError};
use eyeshell::scene::{Scene, SceneError};
use eyeshell::text::number;
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
/// The refraction at the pole of the loaded, ungrown eye: naked and through the lenses, at
/// t = 0 and at each table time of an eye that changes with age.
pub const REFRACTION_FILE: &str = "refraction.csv";
/// The same at each field angle: a growth run's peripheral.csv columns, then which eye.
pub const PERIPHERAL_FILE: &str = "peripheral.csv";
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
    let refraction = ungrown(&scene)?;
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
    let mut doc = optics_json(
        &spec,
        &computed,
        &paraxials,
        &system,
        z_c,
        t,
        start.elapsed().as_secs_f64(),
    );
    doc["refraction"] = write_refraction(&dir, &scene, &computed, refraction.as_ref())?;
    let mut json = serde_json::to_string_pretty(&doc).unwrap_or_default();
    json.push('\n');
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
            "{} eye{when}, {} mm pupil, {}: {} surfaces of {} fields, {} rays traced\n  {}\n  written to {}\n",
            spec.eye_name(),
            eyeshell::text::number(spec.pupil),
            spec.criterion().name(),
            computed.surfaces.surfaces.len(),
            blue.points.len(),
            computed.surfaces.rays_traced,
            refraction_line(&scene, refraction.as_ref().map(|r| r.at.as_slice())),
            crate::shown(&target)
        ));
    }
    Ok(())
}

/// refraction.csv and peripheral.csv of `refraction` (the ungrown retina and its refraction
/// at each time) into `dir`, and optics.json's `refraction` (saying why there is none for a
/// scene with no optics to compute it with).
fn write_refraction(
    dir: &OutputDir,
    scene: &Scene,
    computed: &eyeshell::model::optics::ComputedOptics,
    refraction: Option<&Ungrown>,
) -> Result<serde_json::Value, Error> {
    let Some(Ungrown { retina, at }) = refraction else {
        return Ok(serde_json::json!({ "none": scene.no_refraction_optics() }));
    };
    let shares = |image: Option<f64>, field: f64| image_share(computed, image, field);
    let io = |name: &str, source: std::io::Error| {
        Error::from(OutputError::Io {
            path: dir.file(name),
            source,
        })
    };
    let growth = scene.growth.as_ref();
    let table = refraction_csv(retina, at, &shares, growth).map_err(|e| io(REFRACTION_FILE, e))?;
    dir.write_file(REFRACTION_FILE, &table)?;
    let table = peripheral_csv(at, computed, growth).map_err(|e| io(PERIPHERAL_FILE, e))?;
    dir.write_file(PERIPHERAL_FILE, &table)?;
    Ok(refraction_json(scene, retina, at, &shares))
}

/// The growth time of `--at`: 0 by default; else a finite time within [0, growth.t_end]
/// (within [0, 1] for a scene that does not grow), or with time.unit an age within
/// [time.start, time.end] (t = age − time.start), as the user's error otherwise.
fn growth_time(scene: &Scene, at: Option<f64>) -> Result<f64, Error> {
    let Some(at) = at else {
        return Ok(0.0);
    };
    let window = scene
        .growth
        .as_ref()
        .and_then(|g| Some((g.clock.window()?, g.clock.unit)));
    let (lo, hi, what) = match window {
        Some(((a0, a1), unit)) => (
            a0,
            a1,
            format!(
                "age must lie in [{}, {}] {} (time.start, time.end)",
                number(a0),
                number(a1),
                unit.name()
            ),
        ),
        None => {
            let end = scene.growth.as_ref().map_or(1.0, |g| g.t_end);
            (
                0.0,
                end,
                format!(
                    "growth time must lie in [0, {}] (growth.t_end)",
                    number(end)
                ),
            )
        }
    };
    if !(at >= lo && at <= hi) {
        return Err(Error::input(
            eyeshell::Subject::Argument("--at".into()),
            format!("--at {}: the eye's {what}", number(at)),
        )
        .with_value(number(at))
        .with_origin(eyeshell::Origin::Argument));
    }
    Ok((at - lo).clamp(0.0, hi - lo))
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
) -> serde_json::Value {
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
    doc
}

/// The share of the light the image of power `image` carries at `field` (degrees), as
/// surfaces.csv gives it at the first wavelength
/// ([`eyeshell::model::optics::ComputedOptics::image_share`]).
fn image_share(c: &eyeshell::model::optics::ComputedOptics, image: Option<f64>, field: f64) -> f64 {
    c.image_share(image, field)
}

/// The retina a growth run starts from (the loaded, ungrown shell, pole first) and its
/// refraction at each time.
struct Ungrown {
    retina: Vec<(f64, f64)>,
    at: Vec<RefractionAt>,
}

/// The refraction of the retina a growth run starts from (the loaded, ungrown shell: the
/// scene solved), for a scene with optics to compute it with.
fn ungrown(scene: &Scene) -> Result<Option<Ungrown>, Error> {
    if scene.refraction_optics().is_none() {
        return Ok(None);
    }
    let solution = scene.solve()?;
    Ok(Some(Ungrown {
        at: scene.refraction(&solution)?,
        retina: Scene::retina_of(&solution.rows),
    }))
}

/// One eye the refraction is given through at one time: the naked eye, or an image of the
/// lenses worn, with its pole's refraction.
struct Eye {
    /// None: the naked eye; else the image's power (None for the one image of lenses of one
    /// smooth profile).
    image: Option<Option<f64>>,
    pole_d: f64,
}

/// The eyes of `at`: the naked eye, then each image the lenses form.
fn eyes(at: &RefractionAt) -> Vec<Eye> {
    let naked = Eye {
        image: None,
        pole_d: at.pole_d,
    };
    let through = at.through.iter().map(|l| Eye {
        image: Some(l.image_power),
        pole_d: l.pole_d,
    });
    std::iter::once(naked).chain(through).collect()
}

/// The trailing cells of eye number `e` (of [`eyes`]) at `field`: `through` (`naked` or
/// `lenses`), `image` (its index among the lenses' images), `image_power_D` (empty but for
/// a lens that forms several) and `share` (of the light, at that field: 1 for the naked eye).
fn eye_cells(
    e: usize,
    eye: &Eye,
    shares: &dyn Fn(Option<f64>, f64) -> f64,
    field: f64,
) -> [String; 4] {
    let v = rundir::format_value;
    match eye.image {
        None => ["naked".into(), "0".into(), String::new(), v(1.0)],
        Some(power) => [
            "lenses".into(),
            (e - 1).to_string(),
            power.map(v).unwrap_or_default(),
            v(shares(power, field)),
        ],
    }
}

/// refraction.csv: `t,axial_length,refraction_D,through,image,image_power_D,share`, a row per
/// time and eye (and `age` last in a scene that counts in ages).
fn refraction_csv(
    retina: &[(f64, f64)],
    at: &[RefractionAt],
    shares: &dyn Fn(Option<f64>, f64) -> f64,
    growth: Option<&GrowthParams>,
) -> std::io::Result<Vec<u8>> {
    let v = rundir::format_value;
    let axial = retina.first().map_or(f64::NAN, |p| p.0);
    let mut rows: Vec<Vec<String>> = Vec::new();
    for a in at {
        for (e, eye) in eyes(a).iter().enumerate() {
            let cells = eye_cells(e, eye, shares, 0.0);
            let values = [v(a.t), v(axial), v(eye.pole_d)];
            rows.push(
                values
                    .into_iter()
                    .chain(cells)
                    .chain(age(growth, a.t))
                    .collect(),
            );
        }
    }
    let columns = REFRACTION_COLUMNS.into_iter().chain(age_column(growth));
    rundir::table::csv_bytes(columns, rows, rundir::table::QuoteStyle::Necessary)
}

/// The age of growth time `t` as the last cell of a row, in a scene that counts in ages
/// (`time.unit`), as a growth run's files end in it; nothing otherwise.
fn age(growth: Option<&GrowthParams>, t: f64) -> Option<String> {
    growth.and_then(|g| g.age_of(t)).map(rundir::format_value)
}

/// The `age` column's header where [`age`] gives the cell.
fn age_column(growth: Option<&GrowthParams>) -> Option<&'static str> {
    growth
        .and_then(|g| g.age_unit())
        .map(|_| eyeshell::rundir::growth::AGE_COLUMN)
}

/// peripheral.csv: a growth run's columns (`t,field_deg,refraction_D,relative_D`), then
/// `through,image,image_power_D,share`, a row per time, eye and field angle (and `age` last in
/// a scene that counts in ages): the rows a growth run of a scene with lenses writes
/// ([`eyeshell::rundir::growth::peripheral_records`]), each image's share from `computed`.
fn peripheral_csv(
    at: &[RefractionAt],
    computed: &eyeshell::model::optics::ComputedOptics,
    growth: Option<&GrowthParams>,
) -> std::io::Result<Vec<u8>> {
    let mut rows: Vec<Vec<String>> = Vec::new();
    for a in at {
        let mut through = a.through.clone();
        eyeshell::growth::refraction::with_shares(&mut through, computed);
        let age = growth.and_then(|g| g.age_of(a.t));
        rows.extend(eyeshell::rundir::growth::peripheral_records(
            a.t,
            &a.peripheral,
            &through,
            true,
            age,
        ));
    }
    let columns = eyeshell::growth::PERIPHERAL_COLUMNS
        .into_iter()
        .chain(eyeshell::rundir::growth::THROUGH_COLUMNS)
        .chain(age_column(growth));
    rundir::table::csv_bytes(columns, rows, rundir::table::QuoteStyle::Necessary)
}

/// The columns of refraction.csv.
const REFRACTION_COLUMNS: [&str; 7] = [
    "t",
    "axial_length",
    "refraction_D",
    "through",
    "image",
    "image_power_D",
    "share",
];

/// optics.json's `refraction`: the optics and retina it is of, and at each time the pole's
/// refraction, naked and through each image of the lenses.
fn refraction_json(
    scene: &Scene,
    retina: &[(f64, f64)],
    at: &[RefractionAt],
    shares: &dyn Fn(Option<f64>, f64) -> f64,
) -> serde_json::Value {
    let entries: Vec<_> = at
        .iter()
        .map(|a| {
            let through: Vec<_> = (a.through.iter().enumerate())
                .map(|(k, l)| {
                    serde_json::json!({
                        "image": k,
                        "image_power_dioptres": l.image_power,
                        "share_on_axis": shares(l.image_power, 0.0),
                        "refraction_D": l.pole_d,
                    })
                })
                .collect();
            serde_json::json!({ "t": a.t, "refraction_D": a.pole_d, "through_lenses": through })
        })
        .collect();
    serde_json::json!({
        "optics": optics_phrase(scene),
        "retina": "the loaded, ungrown shell: a growth run's retina at t = 0",
        "axial_length_mm": retina.first().map(|p| p.0),
        "vertex_mm": eyeshell_optics::refraction::VERTEX_MM,
        "wavelength_nm": scene.refraction_optics().map(|s| s.refraction_wavelength),
        "at": entries,
    })
}

/// Which optics the refraction is of, in a phrase.
fn optics_phrase(scene: &Scene) -> &'static str {
    match scene.stimulus_source() {
        eyeshell::model::optics::Source::Optics => "the scene's (stimulus.source = \"optics\")",
        eyeshell::model::optics::Source::Polynomial => {
            "the default optics (stimulus.source = \"polynomial\": a growth run's refraction_D reads them)"
        }
    }
}

/// The summary's line of the refraction at the pole at t = 0: naked and through the lenses.
fn refraction_line(scene: &Scene, at: Option<&[RefractionAt]>) -> String {
    let Some(first) = at.and_then(|a| a.first()) else {
        return format!("no refraction: {}", scene.no_refraction_optics());
    };
    let d = |x: f64| match x.is_finite() {
        true => format!("{x:+.3} D"),
        false => "none (beyond ±25 D)".into(),
    };
    let mut line = format!("refraction at the pole at t = 0: {} naked", d(first.pole_d));
    if scene.stimulus_source() == eyeshell::model::optics::Source::Polynomial {
        // The optics keys above are not the ones a growth run refracts through.
        line += " (the default optics: stimulus.source is \"polynomial\")";
    }
    for (k, l) in first.through.iter().enumerate() {
        match l.image_power {
            Some(p) => line += &format!(", {} through image {k} ({p:+} D)", d(l.pole_d)),
            None => line += &format!(", {} through the lenses", d(l.pole_d)),
        }
    }
    let more = at.map_or(0, |a| a.len()) - 1;
    if more > 0 {
        line += &format!(" (and at {more} more table time{})", crate::plural(more));
    }
    line
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
