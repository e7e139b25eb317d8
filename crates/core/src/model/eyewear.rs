//! The scene's eyewear (`[[optics.lenses]]`), the refraction in dioptres (`refraction_D`) and
//! the dioptre classification (`stimulus.classify = "dioptres"`): docs/guide/eyewear.md.
//!
//! A lens is read from its TOML table into a [`LensSpec`] (each problem names its item,
//! `optics.lenses[1].zones[0].radius`, counted from 0), and becomes the optics crate's
//! [`Lens`]. The refraction is the naked eye's, as a clinician measures it (lenses off):
//! a table of the on-axis best focus against spectacle power, traced once per optics and
//! shared by every run that has the same optics.

use std::sync::{Arc, Mutex, OnceLock};

use eyeshell_optics as optics;
use eyeshell_optics::lens::{Lens, LensBody, Mount, PowerProfile, ProfileError, Zone};
use eyeshell_optics::refraction::{
    power_grid, FieldsAt, PeripheralTable, RefractionTable, PERIPHERAL_POWERS, POWERS, VERTEX_MM,
};
use eyeshell_optics::FocusSettings;

use super::optics::{OpticsKeyError, OpticsSpec};
use crate::names::Quantity;
use crate::text::number;

/// The names `kind` takes.
pub const KINDS: [&str; 2] = ["spectacle", "contact"];
/// The names `stimulus.classify` takes.
pub const CLASSIFY: [&str; 2] = ["surfaces", "dioptres"];
/// The most lenses a scene may wear.
pub const MAX_LENSES: usize = 4;
/// The most zones or table points of one lens.
pub const MAX_POINTS: usize = 64;

/// A lens as the scene gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct LensSpec {
    /// Index into [`KINDS`].
    pub kind: usize,
    /// mm from the corneal apex to the lens's back vertex (spectacles).
    pub vertex: f64,
    pub profile: ProfileSpec,
    /// Lenslet rings: zones whose light goes partly through an add power.
    pub lenslets: Vec<Lenslets>,
    /// `power = "prescribe"`: the lens's power is the eye's own correction
    /// ([`prescribe`]), plus this offset (`over`, D). Its profile then holds the power the
    /// prescription gave (or the offset alone, before the eye is known).
    pub prescribe: Option<f64>,
}

/// A ring of lenslets (docs/guide/eyewear.md, "Simultaneous images"): a share `fill` of the
/// light crossing zone `zone` goes through segments of power `power` (D), the rest through
/// the zone's own power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lenslets {
    pub zone: usize,
    pub power: f64,
    pub fill: f64,
}

/// A lens's power, as given.
#[derive(Clone, Debug, PartialEq)]
pub enum ProfileSpec {
    Power(f64),
    Zones(Vec<(f64, f64)>),
    Table(Vec<(f64, f64)>),
    Real {
        front_radius: f64,
        back_radius: f64,
        thickness: f64,
        index: f64,
    },
}

fn key_error(key: String, value: String, problem: impl Into<String>) -> OpticsKeyError {
    OpticsKeyError {
        key,
        value,
        problem: problem.into(),
    }
}

fn profile_error(i: usize, e: ProfileError) -> OpticsKeyError {
    let item = if e.item.starts_with("zones") || e.item.starts_with("table") {
        e.item.clone()
    } else {
        "power".to_string()
    };
    key_error(
        format!("{}[{i}].{item}", Quantity::Lenses),
        number(e.value),
        e.problem,
    )
}

impl LensSpec {
    /// The optics crate's lens (lens `i` of the scene, for messages).
    pub fn lens(&self, i: usize) -> Result<Lens, OpticsKeyError> {
        self.check_lenslets(i)?;
        let body = match &self.profile {
            ProfileSpec::Power(p) => {
                LensBody::Thin(PowerProfile::uniform(*p).map_err(|e| profile_error(i, e))?)
            }
            ProfileSpec::Zones(z) => LensBody::Thin(
                PowerProfile::zones(
                    z.iter()
                        .map(|&(radius, power)| Zone { radius, power })
                        .collect(),
                )
                .map_err(|e| profile_error(i, e))?,
            ),
            ProfileSpec::Table(t) => LensBody::Thin(
                PowerProfile::table(
                    t.iter().map(|p| p.0).collect(),
                    t.iter().map(|p| p.1).collect(),
                )
                .map_err(|e| profile_error(i, e))?,
            ),
            ProfileSpec::Real {
                front_radius,
                back_radius,
                thickness,
                index,
            } => LensBody::Real {
                front_radius: *front_radius,
                back_radius: *back_radius,
                thickness: *thickness,
                index: *index,
            },
        };
        let mount = if self.kind == 1 {
            Mount::Contact
        } else {
            Mount::Spectacle {
                vertex: self.vertex,
            }
        };
        Ok(Lens { mount, body })
    }

    /// Each lenslet ring's fill in [0, 1], its power in range and its zone one of the lens's.
    fn check_lenslets(&self, i: usize) -> Result<(), OpticsKeyError> {
        let zones = match &self.profile {
            ProfileSpec::Zones(z) => z.len(),
            _ => 0,
        };
        for l in &self.lenslets {
            let at = |name: &str| {
                format!(
                    "{}[{i}].zones[{}].lenslets.{name}",
                    Quantity::Lenses,
                    l.zone
                )
            };
            if l.zone >= zones {
                return Err(key_error(
                    at("power"),
                    number(l.power),
                    "belongs to no zone of this lens",
                ));
            }
            if !(0.0..=1.0).contains(&l.fill) {
                return Err(key_error(
                    at("fill"),
                    number(l.fill),
                    "must lie in [0, 1]: the share of the zone's light that goes through the lenslets",
                ));
            }
            if !(l.power.is_finite() && l.power.abs() <= optics::lens::MAX_POWER_D) {
                return Err(key_error(
                    at("power"),
                    number(l.power),
                    format!("must lie in [-{0}, {0}] D", optics::lens::MAX_POWER_D),
                ));
            }
        }
        Ok(())
    }

    /// The powers (D) of the images the lens forms, from its axis outwards: each zone's
    /// power and each lenslet ring's, once each, those that carry light (a fill of 1 leaves
    /// its zone's own power none). Empty for a lens of one smooth profile (one power, a
    /// table, a real lens): it forms one image, traced as it is.
    pub fn image_powers(&self) -> Vec<f64> {
        let ProfileSpec::Zones(z) = &self.profile else {
            return vec![];
        };
        let mut powers: Vec<f64> = Vec::new();
        for (k, &(_, p)) in z.iter().enumerate() {
            let l = self.lenslets.iter().find(|l| l.zone == k);
            let fill = l.map_or(0.0, |l| l.fill);
            for (q, carries) in [(p, fill < 1.0), (l.map_or(p, |l| l.power), fill > 0.0)] {
                if carries && !powers.contains(&q) {
                    powers.push(q);
                }
            }
        }
        powers
    }

    /// The share of the light crossing the lens at height `h` (mm from its axis) that goes
    /// through `power`, of a zone whose own power is `carrier`: 0 outside such zones, else 1
    /// or 0 in a plain zone, the fill (or its complement) in a lenslet ring. Beyond the lens's
    /// edge, the last zone's. Lenslets (each centred on itself) add no prism on average, so
    /// the light through them reaches the pupil as through their zone's own power.
    pub fn share_at(&self, h: f64, carrier: f64, power: f64) -> f64 {
        let ProfileSpec::Zones(z) = &self.profile else {
            return 1.0;
        };
        let k = z.iter().position(|&(r, _)| h <= r).unwrap_or(z.len() - 1);
        if z[k].1 != carrier {
            return 0.0;
        }
        let l = self.lenslets.iter().find(|l| l.zone == k);
        let fill = l.map_or(0.0, |l| l.fill);
        let mut share = 0.0;
        if carrier == power {
            share += 1.0 - fill;
        }
        if l.is_some_and(|l| l.power == power) {
            share += fill;
        }
        share
    }

    /// The zones' own powers (D), once each: what the light reaching the pupil is bent by.
    pub fn carrier_powers(&self) -> Vec<f64> {
        let mut powers: Vec<f64> = Vec::new();
        if let ProfileSpec::Zones(z) = &self.profile {
            for &(_, p) in z {
                if !powers.contains(&p) {
                    powers.push(p);
                }
            }
        }
        powers
    }

    /// The radii where the share of light changes (every zone's outer radius).
    pub fn zone_edges(&self) -> Vec<f64> {
        match &self.profile {
            ProfileSpec::Zones(z) => z.iter().map(|&(r, _)| r).collect(),
            _ => vec![],
        }
    }

    /// The item of the lens (`zones[2].power`, `zones[1].lenslets.power`) that first gives
    /// `power`.
    pub fn power_item(&self, power: f64) -> String {
        if let ProfileSpec::Zones(z) = &self.profile {
            for (k, &(_, p)) in z.iter().enumerate() {
                if p == power {
                    return format!("zones[{k}].power");
                }
                if let Some(l) = self
                    .lenslets
                    .iter()
                    .find(|l| l.zone == k && l.power == power)
                {
                    return format!("zones[{}].lenslets.power", l.zone);
                }
            }
        }
        "power".into()
    }

    /// The same lens (kind, vertex) of one power everywhere: what the light of one of its
    /// images goes through.
    pub fn with_power(&self, power: f64) -> LensSpec {
        LensSpec {
            kind: self.kind,
            vertex: self.vertex,
            profile: ProfileSpec::Power(power),
            lenslets: vec![],
            prescribe: None,
        }
    }

    /// This lens with `f` (D) added to its power everywhere (its lenslets' too): a thin lens
    /// of power f in contact with it, as a trial lens held against a spectacle lens at its
    /// own plane. None for a real lens, which has a thickness to hold it against.
    pub fn plus(&self, f: f64) -> Option<LensSpec> {
        let shift = |v: &[(f64, f64)]| v.iter().map(|&(r, p)| (r, p + f)).collect();
        let profile = match &self.profile {
            ProfileSpec::Power(p) => ProfileSpec::Power(p + f),
            ProfileSpec::Zones(z) => ProfileSpec::Zones(shift(z)),
            ProfileSpec::Table(t) => ProfileSpec::Table(shift(t)),
            ProfileSpec::Real { .. } => return None,
        };
        let lenslets = (self.lenslets.iter())
            .map(|l| Lenslets {
                power: l.power + f,
                ..*l
            })
            .collect();
        Some(LensSpec {
            profile,
            lenslets,
            ..self.clone()
        })
    }

    /// The radii where the lens's zones begin after the first, with their items: the
    /// zones the pupil's rays may or may not cross (a table's points are one smooth profile,
    /// not zones).
    pub fn zone_starts(&self) -> Vec<(String, f64)> {
        match &self.profile {
            ProfileSpec::Zones(z) => (1..z.len())
                .map(|k| (format!("zones[{k}]"), z[k - 1].0))
                .collect(),
            _ => vec![],
        }
    }

    /// The item naming the lens's edge, and the edge (mm).
    fn edge(&self) -> Option<(String, f64)> {
        match &self.profile {
            ProfileSpec::Zones(z) => z
                .last()
                .map(|l| (format!("zones[{}].radius", z.len() - 1), l.0)),
            ProfileSpec::Table(t) => t
                .last()
                .map(|l| (format!("table[{}].radius", t.len() - 1), l.0)),
            _ => None,
        }
    }

    /// The power (D) of this lens that corrects an eye of refraction `refraction` (D, as
    /// refraction_D gives it: the thin spectacle power at [`VERTEX_MM`] that brings the
    /// naked eye's on-axis best focus onto the retina), plus the prescription's offset
    /// `over`. A lens elsewhere must image the same far point: at d mm in front of the
    /// corneal apex (0 for a contact lens) its power is R / (1 + R·(d − 12)/1000), the
    /// vertex-distance conversion of thin lenses, exact for the ideal thin lenses the
    /// optics trace (each turns the plane wave into the same spherical wave at the cornea).
    pub fn correcting_power(&self, refraction: f64) -> f64 {
        let at = if self.kind == 1 { 0.0 } else { self.vertex };
        refraction / (1.0 + refraction * (at - VERTEX_MM) * 1e-3) + self.prescribe.unwrap_or(0.0)
    }

    /// The lens in a few words, for messages (never its whole profile):
    /// `spectacle lens at 12 mm, 20 zones`.
    pub fn describe(&self) -> String {
        let body = match &self.profile {
            ProfileSpec::Power(p) if self.prescribe.is_some() => {
                format!("{} D prescribed", number(*p))
            }
            ProfileSpec::Power(p) => format!("{} D", number(*p)),
            ProfileSpec::Zones(z) if !self.lenslets.is_empty() => {
                format!("{} zones, {} of lenslets", z.len(), self.lenslets.len())
            }
            ProfileSpec::Zones(z) => format!("{} zones", z.len()),
            ProfileSpec::Table(t) => format!("a table of {} points", t.len()),
            ProfileSpec::Real { .. } => "a real lens".into(),
        };
        match self.kind {
            1 => format!("(contact lens, {body})"),
            _ => format!("(spectacle lens at {} mm, {body})", number(self.vertex)),
        }
    }

    /// As TOML: an inline table that reads back to this lens.
    pub fn to_toml(&self) -> String {
        let f = crate::text::toml_float;
        let mut parts = vec![format!("kind = \"{}\"", KINDS[self.kind])];
        if self.kind == 0 {
            parts.push(format!("vertex = {}", f(self.vertex)));
        }
        let rows = |v: &[(f64, f64)]| {
            v.iter()
                .map(|(r, p)| format!("{{ radius = {}, power = {} }}", f(*r), f(*p)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match &self.profile {
            // The prescription, not the power it gave: read back, the lens is prescribed
            // again for the eye it is worn by.
            ProfileSpec::Power(_) if self.prescribe.is_some() => {
                parts.push("power = \"prescribe\"".into());
                match self.prescribe {
                    Some(over) if over != 0.0 => parts.push(format!("over = {}", f(over))),
                    _ => {}
                }
            }
            ProfileSpec::Power(p) => parts.push(format!("power = {}", f(*p))),
            ProfileSpec::Zones(z) => {
                let rows: Vec<String> = z
                    .iter()
                    .enumerate()
                    .map(
                        |(k, (r, p))| match self.lenslets.iter().find(|l| l.zone == k) {
                            Some(l) => format!(
                            "{{ radius = {}, power = {}, lenslets = {{ power = {}, fill = {} }} }}",
                            f(*r),
                            f(*p),
                            f(l.power),
                            f(l.fill)
                        ),
                            None => format!("{{ radius = {}, power = {} }}", f(*r), f(*p)),
                        },
                    )
                    .collect();
                parts.push(format!("zones = [{}]", rows.join(", ")))
            }
            ProfileSpec::Table(t) => parts.push(format!("table = [{}]", rows(t))),
            ProfileSpec::Real {
                front_radius,
                back_radius,
                thickness,
                index,
            } => parts.push(format!(
                "front_radius = {}, back_radius = {}, thickness = {}, index = {}",
                f(*front_radius),
                f(*back_radius),
                f(*thickness),
                f(*index)
            )),
        }
        format!("{{ {} }}", parts.join(", "))
    }
}

/// The lenses in a few words, for messages: `2 lenses: (spectacle lens at 12 mm, -2 D),
/// (contact lens, 20 zones)`.
pub fn lenses_text(lenses: &[LensSpec]) -> String {
    let n = lenses.len();
    let items: Vec<String> = lenses.iter().map(LensSpec::describe).collect();
    format!(
        "({n} lens{}: {})",
        if n == 1 { "" } else { "es" },
        items.join(", ")
    )
}

/// The lenses as TOML (an inline array of tables).
pub fn lenses_toml(lenses: &[LensSpec]) -> String {
    format!(
        "[{}]",
        lenses
            .iter()
            .map(LensSpec::to_toml)
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// The eye of `spec` with its lenses on.
pub fn worn(spec: &OpticsSpec) -> Result<optics::OpticalSystem, OpticsKeyError> {
    worn_at(spec, 0.0)
}

/// The eye at growth time `t` (its surface tables read at t) with the lenses on.
pub fn worn_at(spec: &OpticsSpec, t: f64) -> Result<optics::OpticalSystem, OpticsKeyError> {
    let eye = spec.system_at(t)?;
    if spec.lenses.is_empty() {
        return Ok(eye);
    }
    let lenses = spec
        .lenses
        .iter()
        .enumerate()
        .map(|(i, l)| l.lens(i))
        .collect::<Result<Vec<_>, _>>()?;
    optics::lens::wear(&eye, &lenses).map_err(|e| {
        key_error(
            Quantity::Lenses.to_string(),
            lenses_text(&spec.lenses),
            format!("cannot be worn: {}", crate::text::one_line(&e.to_string())),
        )
    })
}

/// How far from each lens's axis the pupil's rays cross it (mm), in the order of
/// `spec.lenses`: the heights of the meridional fan at `optics.max_field` (the beam's far
/// edge) at the plane where the lens's profile acts, traced with the lenses' edges removed.
pub fn lens_reach(spec: &OpticsSpec) -> Result<Vec<f64>, OpticsKeyError> {
    if spec.lenses.is_empty() {
        return Ok(vec![]);
    }
    let mut open = spec.clone();
    // Zones of one power with an edge far out: the heights at the lens barely depend on the
    // profile (only through the aiming of rays at the pupil behind it), and no ray leaves.
    for l in &mut open.lenses {
        if matches!(l.profile, ProfileSpec::Zones(_) | ProfileSpec::Table(_)) {
            l.profile = ProfileSpec::Power(0.0);
            l.lenslets.clear();
        }
    }
    let system = worn(&open)?;
    let pupil = open.pupil_stop(&system);
    let fan = optics::ray_fan(
        &system,
        spec.wavelengths[0],
        spec.max_field,
        &pupil,
        9,
        system.last_vertex() + 1.0,
    )
    .map_err(|e| spec.explain_worn(&e))?;
    Ok(spec
        .lenses
        .iter()
        .map(|lens| {
            // The plane where the lens's profile acts: its vertex, or the corneal apex.
            let z = if lens.kind == 1 { 0.0 } else { -lens.vertex };
            fan.iter()
                .filter_map(|path| height_at(path, z))
                .fold(0.0_f64, f64::max)
        })
        .collect())
}

/// Each lens must cover what the pupil sees through it out to `optics.max_field`: rays
/// beyond a lens's edge would miss it. Zones beyond what the pupil sees are allowed (every
/// real lens is wider than the part of it an eye looks through); optics.json lists them
/// (`zones_no_ray_crosses`).
pub fn check_coverage(spec: &OpticsSpec) -> Result<(), OpticsKeyError> {
    let reach = lens_reach(spec)?;
    for (i, (lens, reach)) in spec.lenses.iter().zip(reach).enumerate() {
        if let Some((item, edge)) = lens.edge() {
            if edge < reach {
                return Err(key_error(
                    format!("{}[{i}].{item}", Quantity::Lenses),
                    number(edge),
                    format!(
                        "is the lens's edge, but the pupil's rays cross the lens up to {} mm from its axis at {} = {}°: make it at least that",
                        number((reach * 100.0).ceil() / 100.0),
                        Quantity::MaxField,
                        number(spec.max_field)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// |y| where a polyline (z, y) crosses the plane z (interpolated), if it does.
fn height_at(path: &[(f64, f64)], z: f64) -> Option<f64> {
    path.windows(2).find_map(|w| {
        let ((z0, y0), (z1, y1)) = (w[0], w[1]);
        (z0 <= z && z <= z1 && z1 > z0).then(|| (y0 + (y1 - y0) * (z - z0) / (z1 - z0)).abs())
    })
}

/// The optics the refraction is computed with: the scene's eye, pupil, criterion and
/// reference wavelength (for `stimulus.source = "polynomial"`, the defaults: the
/// Atchison 2006 eye, a 3 mm pupil, the mean sphere, 555 nm).
#[derive(Clone, Debug, PartialEq)]
struct RefractionKey {
    eye: usize,
    surfaces: Vec<super::eye::SurfaceSpec>,
    pupil_position: Option<f64>,
    pupil: f64,
    focus: usize,
    wavelength: f64,
    /// The growth time the surface tables were read at (0 for an eye without tables).
    t: f64,
    /// The rays across the pupil the table is traced with (0 before they are chosen: the
    /// kept default tables are recognised without choosing them).
    rays_across: usize,
}

impl RefractionKey {
    /// The key of `spec`'s naked eye at growth time `t` (0 for an eye without tables).
    fn of(spec: &OpticsSpec, t: f64) -> RefractionKey {
        RefractionKey {
            eye: spec.eye,
            surfaces: spec.surfaces.clone(),
            pupil_position: spec.pupil_position,
            pupil: spec.pupil,
            focus: spec.focus,
            wavelength: spec.refraction_wavelength,
            t: if spec.times().is_empty() { 0.0 } else { t },
            rays_across: 0,
        }
    }

    /// This key with the rays `spec`'s traces use ([`OpticsSpec::focus_settings`]): the
    /// lenses worn can change them, so the same naked eye may be traced with another count.
    fn traced(self, spec: &OpticsSpec) -> RefractionKey {
        RefractionKey {
            rays_across: spec.focus_settings().rays_across,
            ..self
        }
    }
}

type Cache = Vec<(RefractionKey, Arc<RefractionTable>)>;
static TABLES: Mutex<Cache> = Mutex::new(Vec::new());
/// The tables kept: a sweep over the optics keys traces each new one once.
const CACHED: usize = 16;

/// The refraction table of `spec`'s naked eye, traced once and then shared. The error names
/// the key to change.
pub fn refraction_table(spec: &OpticsSpec) -> Result<Arc<RefractionTable>, OpticsKeyError> {
    refraction_table_at(spec, 0.0)
}

/// [`refraction_table`] of the naked eye at growth time `t` (one table a time only for an
/// eye whose surfaces change with age). The default optics' table is kept, not traced
/// ([`default_tables`]).
pub fn refraction_table_at(
    spec: &OpticsSpec,
    t: f64,
) -> Result<Arc<RefractionTable>, OpticsKeyError> {
    let key = RefractionKey::of(spec, t);
    if key == RefractionKey::of(&OpticsSpec::default(), 0.0) {
        return Ok(default_tables().0);
    }
    let key = key.traced(spec);
    if let Ok(cache) = TABLES.lock() {
        if let Some((_, t)) = cache.iter().find(|(k, _)| *k == key) {
            return Ok(t.clone());
        }
    }
    let table = Arc::new(trace_pole(
        spec,
        key.t,
        RefractionTable::compute_sampled,
        &spec.focus_settings(),
    )?);
    if let Ok(mut cache) = TABLES.lock() {
        if cache.len() >= CACHED {
            cache.remove(0);
        }
        cache.push((key, table.clone()));
    }
    Ok(table)
}

/// Trace the refraction table of `spec`'s naked eye at growth time `t`, every power of
/// [`POWERS`], with the default pupil sampling (no cache, no kept table): what the kept
/// default tables are. A run's tables
/// ([`refraction_table_at`]) trace every fifth power and fill the rest
/// ([`RefractionTable::compute_sampled`], within 1e-5 D of this). The error names the key to
/// change.
pub fn trace_refraction_table(
    spec: &OpticsSpec,
    t: f64,
) -> Result<RefractionTable, OpticsKeyError> {
    trace_pole(spec, t, RefractionTable::compute, &FocusSettings::default())
}

type PoleTrace = fn(
    &eyeshell_optics::OpticalSystem,
    f64,
    &eyeshell_optics::Pupil,
    eyeshell_optics::Criterion,
    &FocusSettings,
    f64,
) -> Result<RefractionTable, eyeshell_optics::OpticsError>;

fn trace_pole(
    spec: &OpticsSpec,
    t: f64,
    trace: PoleTrace,
    settings: &FocusSettings,
) -> Result<RefractionTable, OpticsKeyError> {
    let (lo, hi) = super::optics::WAVELENGTH_RANGE;
    if !(spec.refraction_wavelength >= lo && spec.refraction_wavelength <= hi) {
        return Err(key_error(
            Quantity::RefractionWavelength.to_string(),
            number(spec.refraction_wavelength),
            format!("must lie between {lo} and {hi} nm"),
        ));
    }
    let eye = spec.system_at(t)?;
    trace(
        &eye,
        spec.refraction_wavelength,
        &spec.pupil_stop(&eye),
        spec.criterion(),
        settings,
        VERTEX_MM,
    )
    .map_err(|e| {
        key_error(
            Quantity::RefractionWavelength.to_string(),
            number(spec.refraction_wavelength),
            format!(
                "gives no refraction in the {} eye: {}",
                spec.eye_name(),
                crate::text::one_line(&e.to_string())
            ),
        )
    })
}

/// The tables of the default optics (the Atchison 2006 eye, a 3 mm pupil, the mean sphere,
/// 555 nm, fields every 5° to 40°), kept in default_tables.rs rather than traced: every
/// scene without optics of its own reports its refraction with them, and tracing them
/// (about 0.2 s of CPU) cost a 10 ms growth run twenty times over. The numerics test
/// `default_refraction_tables_are_a_fresh_trace` checks them against a new trace at the
/// grid's powers and at those traced between them where the cubic misses
/// ([`PeripheralTable::between`]).
pub fn default_tables() -> (Arc<RefractionTable>, Arc<PeripheralTable>) {
    static KEPT: OnceLock<(Arc<RefractionTable>, Arc<PeripheralTable>)> = OnceLock::new();
    KEPT.get_or_init(|| {
        use super::default_tables as kept;
        let pole = RefractionTable {
            wavelength_nm: kept::WAVELENGTH_NM,
            vertex: VERTEX_MM,
            powers: power_grid(POWERS),
            foci: kept::POLE_FOCI.to_vec(),
        };
        let peripheral = PeripheralTable {
            wavelength_nm: kept::WAVELENGTH_NM,
            vertex: VERTEX_MM,
            fields: kept::FIELDS.to_vec(),
            powers: power_grid(PERIPHERAL_POWERS),
            foci: kept::PERIPHERAL_FOCI.iter().map(|f| f.to_vec()).collect(),
            between: kept::PERIPHERAL_BETWEEN
                .iter()
                .map(|b| b.to_vec())
                .collect(),
        };
        (Arc::new(pole), Arc::new(peripheral))
    })
    .clone()
}

/// The field angles (degrees) of the peripheral refraction: every 5° from the axis to
/// `optics.max_field` (and `max_field` itself when it is not a multiple of 5).
pub fn peripheral_fields(max_field: f64) -> Vec<f64> {
    let mut fields: Vec<f64> = (0..)
        .map(|k| 5.0 * k as f64)
        .take_while(|f| *f <= max_field)
        .collect();
    if fields.last().is_some_and(|f| *f < max_field) {
        fields.push(max_field);
    }
    fields
}

static PERIPHERAL: Mutex<Vec<(RefractionKey, f64, Arc<PeripheralTable>)>> = Mutex::new(Vec::new());

/// The peripheral refraction table of `spec`'s naked eye at growth time `t` (at
/// [`peripheral_fields`] of `optics.max_field`), traced once and then shared, as
/// [`refraction_table_at`]'s.
pub fn peripheral_table_at(
    spec: &OpticsSpec,
    t: f64,
) -> Result<Arc<PeripheralTable>, OpticsKeyError> {
    let key = RefractionKey::of(spec, t);
    let default = OpticsSpec::default();
    if key == RefractionKey::of(&default, 0.0) && spec.max_field == default.max_field {
        return Ok(default_tables().1);
    }
    let key = key.traced(spec);
    if let Ok(cache) = PERIPHERAL.lock() {
        if let Some((_, _, t)) = cache
            .iter()
            .find(|(k, m, _)| *k == key && *m == spec.max_field)
        {
            return Ok(t.clone());
        }
    }
    // The pole's table checks the wavelength and the eye, and names the key that fails.
    refraction_table_at(spec, key.t)?;
    let table = Arc::new(trace_peripheral(spec, key.t, &spec.focus_settings())?);
    if let Ok(mut cache) = PERIPHERAL.lock() {
        if cache.len() >= CACHED {
            cache.remove(0);
        }
        cache.push((key, spec.max_field, table.clone()));
    }
    Ok(table)
}

/// Trace the peripheral refraction table of `spec`'s naked eye at growth time `t` with the
/// default pupil sampling (no cache, no kept table): what the kept default table is.
pub fn trace_peripheral_table(
    spec: &OpticsSpec,
    t: f64,
) -> Result<PeripheralTable, OpticsKeyError> {
    trace_peripheral(spec, t, &FocusSettings::default())
}

fn trace_peripheral(
    spec: &OpticsSpec,
    t: f64,
    settings: &FocusSettings,
) -> Result<PeripheralTable, OpticsKeyError> {
    let eye = spec.system_at(t)?;
    PeripheralTable::compute(
        &eye,
        spec.refraction_wavelength,
        &spec.pupil_stop(&eye),
        spec.criterion(),
        settings,
        FieldsAt {
            vertex: VERTEX_MM,
            fields: &peripheral_fields(spec.max_field),
        },
    )
    .map_err(|e| spec.explain(&e))
}

/// The peripheral refraction of a retina given by its points (z, r) from the posterior pole
/// outwards: for each field angle of `table`, the spectacle power (D) that brings that
/// field's best focus onto the retina (NaN where none of ±25 D does). "Onto" is measured
/// along rays from the axis point `z_c` (the stimulus's polar centre), as the stimulus
/// measures the retina against its surfaces.
pub fn peripheral_refraction(table: &PeripheralTable, z_c: f64, retina: &[(f64, f64)]) -> Vec<f64> {
    let polar: Vec<(f64, f64)> = retina
        .iter()
        .map(|&(z, r)| (r.abs().atan2(z - z_c), r.hypot(z - z_c)))
        .collect();
    let behind = |z: f64, r: f64| -> Option<f64> {
        let phi = r.abs().atan2(z - z_c);
        // Between the axis and the first node (a shell's nodes begin just off the pole) the
        // retina's radius is the first node's: it is even in φ, flat to first order.
        if let Some(&(p0, r0)) = polar.first() {
            if phi < p0 {
                return Some(r.hypot(z - z_c) - r0);
            }
        }
        let w = polar
            .windows(2)
            .find(|w| (w[0].0 <= phi && phi <= w[1].0) || (w[1].0 <= phi && phi <= w[0].0))?;
        let ((p0, r0), (p1, r1)) = (w[0], w[1]);
        let s = if p1 == p0 {
            0.0
        } else {
            (phi - p0) / (p1 - p0)
        };
        Some(r.hypot(z - z_c) - (r0 + s * (r1 - r0)))
    };
    (0..table.fields.len())
        .map(|i| table.refraction(i, behind).unwrap_or(f64::NAN))
        .collect()
}

/// `lenses` with a thin trial lens of power `f` (D) at the spectacle plane ([`VERTEX_MM`]):
/// a lens of its own there, or, where a thin spectacle lens is worn at that plane, added to
/// that lens's power (two thin lenses in contact; [`LensSpec::plus`]). None when a real lens
/// sits at that plane.
fn with_trial(lenses: &[LensSpec], f: f64) -> Option<Vec<LensSpec>> {
    let mut out = lenses.to_vec();
    match (out.iter()).position(|l| l.kind == 0 && l.vertex == VERTEX_MM) {
        Some(i) => out[i] = out[i].plus(f)?,
        None => out.push(LensSpec {
            kind: 0,
            vertex: VERTEX_MM,
            profile: ProfileSpec::Power(f),
            lenslets: vec![],
            prescribe: None,
        }),
    }
    Some(out)
}

/// The eye of `spec` at growth time `t` through its lenses with a trial lens of each power
/// ([`with_trial`]): what the tables through the lenses are traced through. A trial that
/// cannot be worn is the lenses' error, naming the lens.
fn trial_through(
    spec: &OpticsSpec,
    t: f64,
) -> Result<impl Fn(f64) -> Result<optics::OpticalSystem, optics::OpticsError> + Sync, OpticsKeyError>
{
    let eye = spec.system_at(t)?;
    let lenses = spec.lenses.clone();
    Ok(move |f: f64| {
        let trial = with_trial(&lenses, f).ok_or_else(|| optics::OpticsError::Eyewear {
            lens: lenses.iter().position(|l| l.vertex == VERTEX_MM).unwrap_or(0),
            reason: format!(
                "is a real lens at {VERTEX_MM} mm, where the trial lens of a refraction through the lenses is held"
            ),
        })?;
        let worn = (trial.iter().enumerate())
            .map(|(i, l)| {
                l.lens(i).map_err(|e| optics::OpticsError::Eyewear {
                    lens: i,
                    reason: format!("{} = {} {}", e.key, e.value, e.problem),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        optics::lens::wear(&eye, &worn)
    })
}

/// A real spectacle lens that spans the spectacle plane leaves the trial lens of a refraction
/// through the lenses nowhere to be held: refused, naming its vertex.
fn check_trial_plane(spec: &OpticsSpec) -> Result<(), OpticsKeyError> {
    for (i, l) in spec.lenses.iter().enumerate() {
        if let (0, ProfileSpec::Real { thickness, .. }) = (l.kind, &l.profile) {
            if l.vertex <= VERTEX_MM && VERTEX_MM <= l.vertex + thickness {
                return Err(key_error(
                    format!("{}[{i}].vertex", Quantity::Lenses),
                    number(l.vertex),
                    format!(
                        "puts a real lens across the spectacle plane ({VERTEX_MM} mm), where the trial lens of the refraction through the lenses is held: give it a vertex beyond {} mm, or below {} mm",
                        number(VERTEX_MM),
                        number(VERTEX_MM - thickness)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A refraction through the lenses that cannot be traced, as the lenses' error.
fn through_error(spec: &OpticsSpec, e: &optics::OpticsError) -> OpticsKeyError {
    key_error(
        Quantity::Lenses.to_string(),
        lenses_text(&spec.lenses),
        format!(
            "give no refraction through them in the {} eye: {}",
            spec.eye_name(),
            crate::text::one_line(&e.to_string())
        ),
    )
}

/// The refraction table of `spec`'s eye at growth time `t` through the lenses it wears, as
/// [`refraction_table_at`] traces the naked eye's (the same powers, rays and vertex): the
/// over-refraction, the trial lens held at the spectacle plane in front of the lenses
/// ([`with_trial`]). A lens that forms several images is traced at one power: give `spec`
/// with that lens at the image's power ([`LensSpec::with_power`]). Traced each call (no
/// cache: `eyeshell optics` asks once).
pub fn refraction_table_through(
    spec: &OpticsSpec,
    t: f64,
) -> Result<RefractionTable, OpticsKeyError> {
    // The naked eye's table checks the wavelength and the eye, and names the key that fails.
    refraction_table_at(spec, t)?;
    check_trial_plane(spec)?;
    let trial = trial_through(spec, t)?;
    let eye = spec.system_at(t)?;
    RefractionTable::compute_sampled_through(
        &trial,
        spec.refraction_wavelength,
        &spec.pupil_stop(&eye),
        spec.criterion(),
        &spec.focus_settings(),
        VERTEX_MM,
    )
    .map_err(|e| through_error(spec, &e))
}

/// The peripheral refraction table of `spec`'s eye at growth time `t` through the lenses it
/// wears, as [`peripheral_table_at`] traces the naked eye's and as
/// [`refraction_table_through`] holds the trial lens.
pub fn peripheral_table_through(
    spec: &OpticsSpec,
    t: f64,
) -> Result<PeripheralTable, OpticsKeyError> {
    peripheral_table_at(spec, t)?;
    let trial = trial_through(spec, t)?;
    let eye = spec.system_at(t)?;
    PeripheralTable::compute_through(
        &trial,
        spec.refraction_wavelength,
        &spec.pupil_stop(&eye),
        spec.criterion(),
        &spec.focus_settings(),
        FieldsAt {
            vertex: VERTEX_MM,
            fields: &peripheral_fields(spec.max_field),
        },
    )
    .map_err(|e| through_error(spec, &e))
}

/// `spec` with the power of each prescribed lens (`power = "prescribe"`) its eye's own
/// correction ([`LensSpec::correcting_power`]) from the refraction of the naked eye at growth
/// time 0 of a retina whose pole lies `retina_z` mm behind the corneal apex: the
/// refraction_D a growth run of these optics reports at t = 0. That table is traced with
/// the rays the eye needs as it wears its lenses ([`OpticsSpec::focus_settings`]), which a
/// lens's power can change, so the power is found again until it no longer changes (the
/// ray count changes in steps: twice, or three times when a step is crossed). `spec` as it
/// is when no lens is prescribed.
///
/// # Errors
/// The prescribed lens's power key when the refraction lies beyond the table (±25 D) or the
/// optics cannot be traced.
pub fn prescribe(spec: &OpticsSpec, retina_z: f64) -> Result<OpticsSpec, OpticsKeyError> {
    let Some(first) = spec.lenses.iter().position(|l| l.prescribe.is_some()) else {
        return Ok(spec.clone());
    };
    let mut now = spec.clone();
    for _ in 0..4 {
        let table = refraction_table(&now)?;
        let Some(refraction) = table.refraction(retina_z) else {
            return Err(key_error(
                format!("{}[{first}].power", Quantity::Lenses),
                "\"prescribe\"".into(),
                format!(
                    "cannot be prescribed: the naked eye's refraction at t = 0 (its retina's pole at {} mm) lies beyond the ±25 D the refraction is traced over",
                    number(retina_z)
                ),
            ));
        };
        let mut next = now.clone();
        for lens in next.lenses.iter_mut().filter(|l| l.prescribe.is_some()) {
            lens.profile = ProfileSpec::Power(lens.correcting_power(refraction));
        }
        if next == now {
            break;
        }
        now = next;
    }
    Ok(now)
}

/// The optics whose refraction a growth scene reports: its own with `stimulus.source =
/// "optics"`, else the defaults.
pub fn refraction_optics(spec: &OpticsSpec, computed: bool) -> OpticsSpec {
    if computed {
        spec.clone()
    } else {
        OpticsSpec::default()
    }
}

#[cfg(test)]
pub(crate) mod tests;
