//! The refraction of a retina in dioptres (docs/MODEL.md §6, "Refraction in dioptres";
//! docs/guide/eyewear.md): at the pole (`refraction_D`) and at each field angle
//! (peripheral.csv), of the naked eye and through the lenses it wears. A growth run's series
//! and peripheral rows, `eyeshell optics` and `eyeshell solve` read the same functions here,
//! so a retina gives the same dioptres in each.

use super::settings::blend_over_ages;
use super::PeripheralRow;
use crate::model::eyewear;
use crate::model::optics::{OpticsKeyError, OpticsSpec};

/// The refraction (D) at growth time `t` of a retina at `retina_z` on the axis, through the
/// naked eye of `spec` (NaN beyond ±25 D or when the optics give none): read from a table
/// traced once; for optics that change with age, once per table time, and the refractions
/// there blended in t as the surfaces are ([`blend_over_ages`]).
pub fn pole(spec: &OpticsSpec, t: f64, retina_z: f64) -> f64 {
    blend_over_ages(spec, t, |at| {
        eyewear::refraction_table_at(spec, at)
            .ok()
            .and_then(|table| table.refraction(retina_z))
            .map_or(vec![f64::NAN], |d| vec![d])
    })[0]
}

/// The peripheral refraction at growth time `t` of the retina through `retina` (its points
/// (z, r) from the pole outwards), "onto" measured along rays from the axis point `z_c`:
/// one row per field angle of [`eyewear::peripheral_fields`], with the same optics and
/// conversion as [`pole`] (NaN where the optics give none), blended over ages as it is.
pub fn peripheral(
    spec: &OpticsSpec,
    z_c: f64,
    t: f64,
    retina: &[(f64, f64)],
) -> Vec<PeripheralRow> {
    let fields = eyewear::peripheral_fields(spec.max_field);
    let values = blend_over_ages(spec, t, |at| match eyewear::peripheral_table_at(spec, at) {
        Ok(table) => eyewear::peripheral_refraction(&table, z_c, retina),
        Err(_) => vec![f64::NAN; fields.len()],
    });
    rows(&fields, &values)
}

/// The peripheral rows of `values` at `fields`, each relative to the first (the pole's).
fn rows(fields: &[f64], values: &[f64]) -> Vec<PeripheralRow> {
    let pole = values.first().copied().unwrap_or(f64::NAN);
    fields
        .iter()
        .zip(values)
        .map(|(&field_deg, &d)| PeripheralRow {
            field_deg,
            refraction_d: d,
            relative_d: d - pole,
        })
        .collect()
}

/// The refraction through the lenses worn, of one image they form: the over-refraction, the
/// power of a thin trial lens at the spectacle plane (12 mm, in front of the lenses, or in
/// contact with a thin spectacle lens at that plane) that brings the image's best focus onto
/// the retina.
#[derive(Clone, Debug, PartialEq)]
pub struct ThroughLenses {
    /// The power (D) of the multifocal lens's image (None: the lenses form one image).
    pub image_power: Option<f64>,
    /// At the pole (D; NaN beyond ±25 D).
    pub pole_d: f64,
    /// At each field angle, as [`peripheral`]'s rows.
    pub peripheral: Vec<PeripheralRow>,
}

/// The refraction of one retina at one growth time: of the naked eye (what a growth run's
/// series and peripheral rows hold) and through the lenses worn.
#[derive(Clone, Debug, PartialEq)]
pub struct RefractionAt {
    pub t: f64,
    /// The naked eye's at the pole: [`pole`].
    pub pole_d: f64,
    /// The naked eye's at each field angle: [`peripheral`].
    pub peripheral: Vec<PeripheralRow>,
    /// Through the lenses, one entry per image they form (none without lenses).
    pub through: Vec<ThroughLenses>,
}

/// The refraction through `spec`'s lenses at growth time `t` of the retina through `retina`
/// (pole first): one entry per image (a lens of several powers is traced at each image's
/// power, as the stimulus traces its images; [`crate::model::eyewear::LensSpec::image_powers`]),
/// none without lenses. Traced at `t` itself (an eye that changes with age is traced at
/// each time asked).
///
/// # Errors
/// [`OpticsKeyError`] naming the key when the lenses cannot be traced with a trial lens.
pub fn through_lenses(
    spec: &OpticsSpec,
    z_c: f64,
    t: f64,
    retina: &[(f64, f64)],
) -> Result<Vec<ThroughLenses>, OpticsKeyError> {
    if spec.lenses.is_empty() {
        return Ok(vec![]);
    }
    let multifocal = (spec.lenses.iter()).position(|l| l.image_powers().len() > 1);
    let images: Vec<(Option<f64>, OpticsSpec)> = match multifocal {
        None => vec![(None, spec.clone())],
        Some(i) => (spec.lenses[i].image_powers().into_iter())
            .map(|p| {
                let mut s = spec.clone();
                s.lenses[i] = s.lenses[i].with_power(p);
                (Some(p), s)
            })
            .collect(),
    };
    let retina_z = retina.first().map_or(f64::NAN, |p| p.0);
    let fields = eyewear::peripheral_fields(spec.max_field);
    images
        .into_iter()
        .map(|(image_power, s)| {
            let table = eyewear::refraction_table_through(&s, t)?;
            let pole_d = table.refraction(retina_z).unwrap_or(f64::NAN);
            let table = eyewear::peripheral_table_through(&s, t)?;
            let values = eyewear::peripheral_refraction(&table, z_c, retina);
            Ok(ThroughLenses {
                image_power,
                pole_d,
                peripheral: rows(&fields, &values),
            })
        })
        .collect()
}

/// The refraction of the retina through `retina` (pole first; its z on the axis is the
/// axial length) at each of `times`, of the naked eye ([`pole`], [`peripheral`]) and
/// through the lenses ([`through_lenses`]).
///
/// # Errors
/// As [`through_lenses`], and the naked eye's key error when its optics give no
/// refraction table at all (a wavelength out of range, an eye that cannot be traced).
pub fn of_retina(
    spec: &OpticsSpec,
    z_c: f64,
    retina: &[(f64, f64)],
    times: &[f64],
) -> Result<Vec<RefractionAt>, OpticsKeyError> {
    let retina_z = retina.first().map_or(f64::NAN, |p| p.0);
    times
        .iter()
        .map(|&t| {
            // The tables a growth run reads, traced (or taken from the cache) here so that a
            // key that gives none is named rather than read as NaN.
            eyewear::refraction_table_at(spec, t)?;
            eyewear::peripheral_table_at(spec, t)?;
            Ok(RefractionAt {
                t,
                pole_d: pole(spec, t, retina_z),
                peripheral: peripheral(spec, z_c, t, retina),
                through: through_lenses(spec, z_c, t, retina)?,
            })
        })
        .collect()
}
