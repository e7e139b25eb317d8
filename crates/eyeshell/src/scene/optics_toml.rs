//! The TOML of the optics keys: an eye's `[[optics.surfaces]]` tables and the
//! `[[optics.lenses]]`, read into and written from the model's types
//! (`model::eye::SurfaceSpec`, `model::eyewear::LensSpec`). The model holds what they mean
//! and checks their ranges; reading a scene file's values is the scene's, so that the
//! numerics crate needs no TOML.

use eyeshell_optics::refraction::VERTEX_MM;

use super::parse::{LENSES_KEY, SURFACES_KEY};
use crate::model::eye::{EyeValue, MediumSpec, SurfaceKeyError, SurfaceSpec, SURFACE_KEYS};
use crate::model::eyewear::{LensSpec, Lenslets, ProfileSpec, KINDS, MAX_LENSES, MAX_POINTS};
use crate::model::optics::OpticsKeyError;
use crate::text::number;

/// A surface of the eye read from and written as TOML (the trait brings these to
/// `SurfaceSpec`, which the numerics crate defines).
pub trait SurfaceToml: Sized {
    /// Set the key `name` of surface `i` from its TOML value (types and table shapes checked;
    /// ranges by `SurfaceSpec::check`).
    fn set(&mut self, i: usize, name: &str, v: &toml::Value) -> Result<(), SurfaceKeyError>;
    /// The surface from a TOML table.
    fn from_toml(i: usize, v: &toml::Value) -> Result<Self, SurfaceKeyError>;
    /// The surface as a TOML table (its keys in the table's own, alphabetical, order).
    fn to_toml(&self) -> toml::Value {
        self.to_toml_with(TimeKey::T)
    }
    /// [`SurfaceToml::to_toml`], its tables' times under `key` (`t`, or `age` in a scene
    /// that counts in ages).
    fn to_toml_with(&self, key: TimeKey) -> toml::Value;
}

/// What a table's times are named: `t` (the model's time) or `age` (an age in time.unit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeKey {
    T,
    Age,
}

impl TimeKey {
    pub fn name(self) -> &'static str {
        match self {
            TimeKey::T => "t",
            TimeKey::Age => "age",
        }
    }
}

/// Which time keys the tables inside `v` (a surface's value, a surface table or an array
/// of them) use: (t, age).
pub fn time_keys_in(v: &toml::Value) -> (bool, bool) {
    match v {
        toml::Value::Table(table) => {
            let own = (table.contains_key("t"), table.contains_key("age"));
            table
                .values()
                .map(time_keys_in)
                .fold(own, |a, b| (a.0 || b.0, a.1 || b.1))
        }
        toml::Value::Array(items) => items
            .iter()
            .map(time_keys_in)
            .fold((false, false), |a, b| (a.0 || b.0, a.1 || b.1)),
        _ => (false, false),
    }
}

/// `optics.surfaces[i].name`.
fn surface_key(i: usize, name: &str) -> String {
    format!("{SURFACES_KEY}[{i}].{name}")
}

fn key_error(key: String, value: String, problem: impl Into<String>) -> OpticsKeyError {
    OpticsKeyError {
        key,
        value,
        problem: problem.into(),
    }
}

fn eye_value_toml(value: &EyeValue, key: TimeKey) -> toml::Value {
    match value {
        EyeValue::Fixed(x) => toml::Value::Float(*x),
        EyeValue::Table { t, value } => {
            let list = |xs: &[f64]| {
                toml::Value::Array(xs.iter().map(|x| toml::Value::Float(*x)).collect())
            };
            let mut table = toml::Table::new();
            table.insert(key.name().into(), list(t));
            table.insert("value".into(), list(value));
            toml::Value::Table(table)
        }
    }
}

fn show_toml(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => number(*x),
        toml::Value::Integer(i) => i.to_string(),
        v => crate::text::excerpt(&crate::text::one_line(&v.to_string()), 120),
    }
}

fn float(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        // As summary.json writes the numbers JSON lacks (a plane's radius).
        toml::Value::String(s) if ["inf", "-inf", "nan"].contains(&s.as_str()) => s.parse().ok(),
        _ => None,
    }
}

fn floats(v: &toml::Value) -> Option<Vec<f64>> {
    match v {
        toml::Value::Array(items) => items.iter().map(float).collect(),
        v => float(v).map(|x| vec![x]),
    }
}

impl SurfaceToml for SurfaceSpec {
    /// Set the key `name` of surface `i` from its TOML value (types and table shapes checked;
    /// ranges by [`SurfaceSpec::check`]).
    fn set(&mut self, i: usize, name: &str, v: &toml::Value) -> Result<(), SurfaceKeyError> {
        let err = |problem: String| SurfaceKeyError {
            key: surface_key(i, name),
            value: show_toml(v),
            problem,
        };
        let value = |timed: bool| -> Result<EyeValue, SurfaceKeyError> {
            if let Some(x) = float(v) {
                return Ok(EyeValue::Fixed(x));
            }
            let shape = if timed {
                "must be a number or a table over the growth's time, { t = [0, 0.5, 1], value = [7.4, 7.7, 7.8] }"
            } else {
                "must be a number"
            };
            let toml::Value::Table(table) = v else {
                return Err(err(shape.into()));
            };
            if !timed {
                return Err(err(shape.into()));
            }
            if let Some(k) = table
                .keys()
                .find(|k| !["t", "age", "value"].contains(&k.as_str()))
            {
                return Err(err(format!(
                    "has the unknown key '{}': {shape}",
                    crate::text::one_line(&crate::text::excerpt(k, 40))
                )));
            }
            let times = match (table.get("t"), table.get("age")) {
                (Some(_), Some(_)) => {
                    return Err(err(format!("gives both t and age: {shape}")));
                }
                (t, age) => t.or(age),
            };
            let (Some(t), Some(value)) =
                (times.and_then(floats), table.get("value").and_then(floats))
            else {
                return Err(err(format!(
                    "{shape}: t (or age) and value must both be lists of numbers"
                )));
            };
            Ok(EyeValue::Table { t, value })
        };
        match name {
            "radius" => self.radius = Some(value(true)?),
            "conic" => self.conic = Some(value(true)?),
            "thickness" => self.thickness = Some(value(true)?),
            "index" => self.medium = Some(MediumSpec::Index(value(true)?)),
            "aspheric" => {
                self.aspheric = Some(floats(v).ok_or_else(|| {
                    err("must be a list of numbers: the coefficients of r⁴, r⁶, ... (mm⁻³, mm⁻⁵, ...)".into())
                })?)
            }
            "cauchy" => {
                self.medium = Some(MediumSpec::Cauchy(floats(v).ok_or_else(|| {
                    err("must be a list of one to four numbers: a, b, c, d of n = a + b/λ² + c/λ⁴ + d/λ⁶ (λ in µm)".into())
                })?))
            }
            "sellmeier" => {
                let shape = "must be a table { b = [..], c = [..] } of Sellmeier's n² = 1 + Σ bᵢλ²/(λ² − cᵢ) (λ in µm)";
                let toml::Value::Table(table) = v else {
                    return Err(err(shape.into()));
                };
                let (Some(b), Some(c)) = (
                    table.get("b").and_then(floats),
                    table.get("c").and_then(floats),
                ) else {
                    return Err(err(shape.into()));
                };
                if table.len() != 2 {
                    return Err(err(shape.into()));
                }
                self.medium = Some(MediumSpec::Sellmeier { b, c });
            }
            _ => {
                return Err(SurfaceKeyError {
                    key: surface_key(i, &crate::text::one_line(&crate::text::excerpt(name, 40))),
                    value: show_toml(v),
                    problem: format!(
                        "is not a key of a surface: a surface takes {}",
                        SURFACE_KEYS.join(", ")
                    ),
                })
            }
        }
        Ok(())
    }

    /// The surface from a TOML table.
    fn from_toml(i: usize, v: &toml::Value) -> Result<SurfaceSpec, SurfaceKeyError> {
        let toml::Value::Table(table) = v else {
            return Err(SurfaceKeyError {
                key: format!("optics.surfaces[{i}]"),
                value: show_toml(v),
                problem: "must be a table of a surface's keys ([[optics.surfaces]])".into(),
            });
        };
        let mut s = SurfaceSpec::default();
        let media = ["index", "cauchy", "sellmeier"];
        if table.keys().filter(|k| media.contains(&k.as_str())).count() > 1 {
            return Err(SurfaceKeyError {
                key: format!("optics.surfaces[{i}]"),
                value: show_toml(v),
                problem: "gives its medium twice: give one of index, cauchy or sellmeier".into(),
            });
        }
        for (name, value) in table {
            s.set(i, name, value)?;
        }
        Ok(s)
    }

    /// The surface as a TOML table (its keys in the table's own, alphabetical, order).
    fn to_toml_with(&self, key: TimeKey) -> toml::Value {
        let mut t = toml::Table::new();
        let mut put = |k: &str, v: toml::Value| {
            t.insert(k.to_string(), v);
        };
        let list =
            |xs: &[f64]| toml::Value::Array(xs.iter().map(|x| toml::Value::Float(*x)).collect());
        if let Some(v) = &self.radius {
            put("radius", eye_value_toml(v, key));
        }
        if let Some(v) = &self.conic {
            put("conic", eye_value_toml(v, key));
        }
        if let Some(a) = &self.aspheric {
            put("aspheric", list(a));
        }
        if let Some(v) = &self.thickness {
            put("thickness", eye_value_toml(v, key));
        }
        match &self.medium {
            Some(MediumSpec::Index(v)) => put("index", eye_value_toml(v, key)),
            Some(MediumSpec::Cauchy(c)) => put("cauchy", list(c)),
            Some(MediumSpec::Sellmeier { b, c }) => {
                let mut s = toml::Table::new();
                s.insert("b".into(), list(b));
                s.insert("c".into(), list(c));
                put("sellmeier", toml::Value::Table(s));
            }
            None => {}
        }
        toml::Value::Table(t)
    }
}

fn lens_float(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The lenses of a TOML value: an array of tables.
pub fn parse_lenses(value: &toml::Value) -> Result<Vec<LensSpec>, OpticsKeyError> {
    let toml::Value::Array(items) = value else {
        return Err(key_error(
            LENSES_KEY.into(),
            super::describe(value),
            "must be an array of tables ([[optics.lenses]])",
        ));
    };
    if items.len() > MAX_LENSES {
        return Err(key_error(
            LENSES_KEY.into(),
            format!("{} lenses", items.len()),
            format!("must list at most {MAX_LENSES} lenses"),
        ));
    }
    items
        .iter()
        .enumerate()
        .map(|(i, item)| parse_lens(i, item))
        .collect()
}

/// The lenslet rings of a lens's zones (`zones[k].lenslets = { power, fill }`), and the
/// lens's table without them (so that each zone row is its radius and power again).
fn lenslet_rings(
    i: usize,
    t: &toml::Table,
) -> Result<(toml::Table, Vec<Lenslets>), OpticsKeyError> {
    let mut t = t.clone();
    let mut rings = Vec::new();
    let Some(toml::Value::Array(rows)) = t.get_mut("zones") else {
        return Ok((t, rings));
    };
    for (k, row) in rows.iter_mut().enumerate() {
        let toml::Value::Table(r) = row else { continue };
        let Some(v) = r.remove("lenslets") else {
            continue;
        };
        let at = |name: &str| format!("{LENSES_KEY}[{i}].zones[{k}].lenslets{name}");
        let toml::Value::Table(l) = &v else {
            return Err(key_error(
                at(""),
                super::describe(&v),
                "must be a table { power = …, fill = … }",
            ));
        };
        if let Some(extra) = l
            .keys()
            .find(|x| x.as_str() != "power" && x.as_str() != "fill")
        {
            return Err(key_error(
                at(&format!(".{extra}")),
                "(given)".into(),
                "is not one of power, fill",
            ));
        }
        let get = |name: &str| match l.get(name) {
            None => Err(key_error(
                at(&format!(".{name}")),
                "(missing)".into(),
                "must be given",
            )),
            Some(v) => lens_float(v).filter(|x| x.is_finite()).ok_or_else(|| {
                key_error(
                    at(&format!(".{name}")),
                    super::describe(v),
                    "must be a finite number",
                )
            }),
        };
        rings.push(Lenslets {
            zone: k,
            power: get("power")?,
            fill: get("fill")?,
        });
    }
    Ok((t, rings))
}

/// A lens's table of (`a`, `b`) rows under `name` (its zones or its power table): 1 to
/// [`MAX_POINTS`] tables of two finite numbers; None when the lens does not give it.
fn lens_pairs(
    i: usize,
    t: &toml::Table,
    name: &str,
    a: &str,
    b: &str,
) -> Result<Option<Vec<(f64, f64)>>, OpticsKeyError> {
    let at = |name: &str| format!("{LENSES_KEY}[{i}].{name}");
    let Some(v) = t.get(name) else {
        return Ok(None);
    };
    let toml::Value::Array(rows) = v else {
        return Err(key_error(
            at(name),
            super::describe(v),
            format!("must be an array of {{ {a} = …, {b} = … }} tables"),
        ));
    };
    if rows.is_empty() || rows.len() > MAX_POINTS {
        return Err(key_error(
            at(name),
            format!("{} entries", rows.len()),
            format!("must hold 1 to {MAX_POINTS} entries"),
        ));
    }
    let mut out = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        let item = |field: &str| format!("{}[{k}].{field}", at(name));
        let toml::Value::Table(r) = row else {
            return Err(key_error(
                format!("{}[{k}]", at(name)),
                super::describe(row),
                format!("must be a table {{ {a} = …, {b} = … }}"),
            ));
        };
        if let Some(extra) = r.keys().find(|x| x.as_str() != a && x.as_str() != b) {
            return Err(key_error(
                item(extra),
                "(given)".into(),
                format!("is not one of {a}, {b}"),
            ));
        }
        let get = |field: &str| match r.get(field) {
            None => Err(key_error(item(field), "(missing)".into(), "must be given")),
            Some(v) => match lens_float(v) {
                Some(x) if x.is_finite() => Ok(x),
                Some(x) => Err(key_error(item(field), number(x), "must be a finite number")),
                None => Err(key_error(
                    item(field),
                    super::describe(v),
                    "must be a number",
                )),
            },
        };
        out.push((get(a)?, get(b)?));
    }
    Ok(Some(out))
}

/// A real lens's profile from its front_radius, back_radius, thickness and index (all
/// given, in their ranges; a spectacle lens only, `kind` 0).
fn real_lens(i: usize, kind: usize, real: &[Option<f64>]) -> Result<ProfileSpec, OpticsKeyError> {
    let at = |name: &str| format!("{LENSES_KEY}[{i}].{name}");
    let names = ["front_radius", "back_radius", "thickness", "index"];
    if let Some(k) = real.iter().position(Option::is_none) {
        return Err(key_error(
            at(names[k]),
            "(missing)".into(),
            "must be given for a real lens",
        ));
    }
    if kind == 1 {
        return Err(key_error(
            at("front_radius"),
            number(real[0].unwrap_or(0.0)),
            "a contact lens is thin here: give its power, zones or table",
        ));
    }
    let v: Vec<f64> = real.iter().map(|x| x.unwrap_or(0.0)).collect();
    if !(v[2] > 0.0 && v[2] <= 20.0) {
        return Err(key_error(
            at("thickness"),
            number(v[2]),
            "must lie in (0, 20] mm",
        ));
    }
    if !(v[3] >= 1.0 && v[3] <= 3.0) {
        return Err(key_error(at("index"), number(v[3]), "must lie in [1, 3]"));
    }
    for (k, r) in v[..2].iter().enumerate() {
        if r.abs() < 1.0 {
            return Err(key_error(
                at(names[k]),
                number(*r),
                "must be at least 1 mm in size (a plane is inf)",
            ));
        }
    }
    Ok(ProfileSpec::Real {
        front_radius: v[0],
        back_radius: v[1],
        thickness: v[2],
        index: v[3],
    })
}

/// The keys of one lens table, each also set alone as `optics.lenses[i].key`.
pub const LENS_KEYS: [&str; 10] = [
    "kind",
    "vertex",
    "power",
    "over",
    "zones",
    "table",
    "front_radius",
    "back_radius",
    "thickness",
    "index",
];

/// The value of `power` that makes a lens the eye's own correction
/// ([`crate::model::eyewear::prescribe`]).
pub const PRESCRIBE: &str = "prescribe";

/// Lens `i`'s table with its key `name` set to `value`: `lenses[i]`'s own keys, or a new
/// lens's (a spectacle lens at the default vertex) for `i` = `lenses.len()`.
pub fn set_lens_key(
    lenses: &[LensSpec],
    i: usize,
    name: &str,
    value: &toml::Value,
) -> Result<LensSpec, OpticsKeyError> {
    // A lens's TOML always reads back (a test of its own); were it not to, the lens's
    // other keys would be missing and the lens refused naming them, never half-set.
    let mut table = match lenses.get(i) {
        Some(lens) => match format!("v = {}", lens.to_toml()).parse::<toml::Table>() {
            Ok(mut t) => match t.remove("v") {
                Some(toml::Value::Table(t)) => t,
                _ => toml::Table::new(),
            },
            Err(_) => toml::Table::new(),
        },
        None => toml::Table::new(),
    };
    // A lens made a contact lens sits on the cornea: the vertex it had as a spectacle lens
    // goes (a contact lens takes none).
    if name == "kind" && value.as_str() == Some(KINDS[1]) {
        table.remove("vertex");
    }
    table.insert(name.to_string(), value.clone());
    parse_lens(i, &toml::Value::Table(table))
}

fn parse_lens(i: usize, item: &toml::Value) -> Result<LensSpec, OpticsKeyError> {
    let at = |name: &str| format!("{LENSES_KEY}[{i}].{name}");
    let toml::Value::Table(t) = item else {
        return Err(key_error(
            format!("{LENSES_KEY}[{i}]"),
            super::describe(item),
            "must be a table (kind, vertex, power | zones | table | front_radius, back_radius, thickness, index)",
        ));
    };
    if let Some(k) = t.keys().find(|k| !LENS_KEYS.contains(&k.as_str())) {
        return Err(key_error(
            at(k),
            "(given)".into(),
            format!("is not a lens key (one of {})", LENS_KEYS.join(", ")),
        ));
    }
    let number_at = |name: &str| -> Result<Option<f64>, OpticsKeyError> {
        match t.get(name) {
            None => Ok(None),
            Some(v) => match lens_float(v) {
                Some(x) if x.is_finite() => Ok(Some(x)),
                Some(x) => Err(key_error(at(name), number(x), "must be a finite number")),
                None => Err(key_error(at(name), super::describe(v), "must be a number")),
            },
        }
    };
    let kind = match t.get("kind") {
        None => 0,
        Some(toml::Value::String(s)) => KINDS.iter().position(|k| k == s).ok_or_else(|| {
            key_error(
                at("kind"),
                format!("\"{s}\""),
                "must be \"spectacle\" or \"contact\"",
            )
        })?,
        Some(v) => {
            return Err(key_error(
                at("kind"),
                super::describe(v),
                "must be \"spectacle\" or \"contact\"",
            ))
        }
    };
    let vertex = match number_at("vertex")? {
        Some(_) if kind == 1 => {
            return Err(key_error(
                at("vertex"),
                number(number_at("vertex")?.unwrap_or(0.0)),
                "is for spectacle lenses: a contact lens sits on the cornea",
            ))
        }
        Some(v) if !(v > 0.0 && v <= 50.0) => return Err(key_error(
            at("vertex"),
            number(v),
            "must lie in (0, 50] mm: the spectacle lens's back vertex in front of the corneal apex",
        )),
        Some(v) => v,
        None => VERTEX_MM,
    };
    let prescribe = match t.get("power") {
        Some(toml::Value::String(s)) if s == PRESCRIBE => Some(number_at("over")?.unwrap_or(0.0)),
        Some(toml::Value::String(s)) => {
            return Err(key_error(
                at("power"),
                super::view::describe_string(s),
                format!("must be a number (D) or \"{PRESCRIBE}\" (the eye's own correction)"),
            ))
        }
        _ => None,
    };
    if prescribe.is_none() && t.contains_key("over") {
        return Err(key_error(
            at("over"),
            show_toml(&t["over"]),
            format!("is the offset of a prescribed lens: give it with power = \"{PRESCRIBE}\""),
        ));
    }
    // A prescribed lens holds its offset until the eye it corrects is known.
    let power = match prescribe {
        Some(over) => Some(over),
        None => number_at("power")?,
    };
    let (t, lenslets) = &lenslet_rings(i, t)?;
    let zones = lens_pairs(i, t, "zones", "radius", "power")?;
    let table = lens_pairs(i, t, "table", "radius", "power")?;
    let real = ["front_radius", "back_radius", "thickness", "index"]
        .iter()
        .map(|n| number_at(n))
        .collect::<Result<Vec<_>, _>>()?;
    let given = [
        power.is_some(),
        zones.is_some(),
        table.is_some(),
        real.iter().any(Option::is_some),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(key_error(
            format!("{LENSES_KEY}[{i}]"),
            "(this lens)".into(),
            "must give exactly one of power, zones, table, or front_radius/back_radius/thickness/index (a real lens)",
        ));
    }
    let profile = if let Some(p) = power {
        ProfileSpec::Power(p)
    } else if let Some(z) = zones {
        ProfileSpec::Zones(z)
    } else if let Some(t) = table {
        ProfileSpec::Table(t)
    } else {
        real_lens(i, kind, &real)?
    };
    let spec = LensSpec {
        kind,
        vertex,
        profile,
        lenslets: lenslets.clone(),
        prescribe,
    };
    spec.lens(i)?;
    Ok(spec)
}
