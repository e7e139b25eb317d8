//! The refraction of a retina in dioptres (docs/MODEL.md §6, "Refraction in dioptres";
//! docs/guide/eyewear.md): at the pole (`refraction_D`) and at each field angle
//! (peripheral.csv), of the naked eye and through the lenses it wears. A growth run's series
//! and peripheral rows, `eyeshell optics` and `eyeshell solve` read the same functions here,
//! so a retina gives the same dioptres in each.

use std::sync::{Arc, Mutex};

use eyeshell_optics::refraction::{PeripheralTable, RefractionTable};

use super::settings::blend_over_ages;
use super::PeripheralRow;
use crate::model::eyewear;
use crate::model::optics::{ComputedOptics, OpticsKeyError, OpticsSpec};

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
    /// The share of the light this image carries at each field of `peripheral`: 1 for the
    /// one image of lenses of one smooth profile; a multifocal lens's from the surfaces
    /// traced for the stimulus ([`with_shares`]; NaN until then).
    pub share: Vec<f64>,
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

/// The images `spec`'s lenses form, each as the optics its light goes through: one, the
/// lenses as they are, for lenses of one smooth profile; else one per power of the
/// multifocal lens, that lens of that power everywhere, as the stimulus traces its images
/// ([`crate::model::eyewear::LensSpec::image_powers`]). None without lenses.
fn images(spec: &OpticsSpec) -> Vec<(Option<f64>, OpticsSpec)> {
    if spec.lenses.is_empty() {
        return vec![];
    }
    let multifocal = (spec.lenses.iter()).position(|l| l.image_powers().len() > 1);
    match multifocal {
        None => vec![(None, spec.clone())],
        Some(i) => (spec.lenses[i].image_powers().into_iter())
            .map(|p| {
                let mut s = spec.clone();
                s.lenses[i] = s.lenses[i].with_power(p);
                (Some(p), s)
            })
            .collect(),
    }
}

/// How many images `spec`'s lenses form, each a block of rows of peripheral.csv through the
/// lenses (0 without lenses).
pub fn image_count(spec: &OpticsSpec) -> usize {
    images(spec).len()
}

/// The tables of one image's refraction through the lenses at one time: the pole's and the
/// peripheral one.
type ThroughTables = (RefractionTable, PeripheralTable);

/// The through-lens tables kept, by the image's optics and the growth time they were traced
/// at: a growth run reads them at every output time, traced once (once per table time for
/// optics that change with age), and a sweep's runs of the same optics share them.
static THROUGH: Mutex<Vec<(OpticsSpec, f64, Arc<ThroughTables>)>> = Mutex::new(Vec::new());
/// The most tables kept: a multifocal lens's images at a few table times.
const THROUGH_CACHED: usize = 32;

/// The through-lens tables of the image whose optics are `s`, at growth time `at` (a table
/// time of an eye that changes with age, else 0), traced once and then shared.
fn through_tables(s: &OpticsSpec, at: f64) -> Result<Arc<ThroughTables>, OpticsKeyError> {
    let found = THROUGH.lock().ok().and_then(|cache| {
        (cache.iter())
            .find(|(k, t, _)| k == s && *t == at)
            .map(|(_, _, tables)| tables.clone())
    });
    if let Some(tables) = found {
        return Ok(tables);
    }
    let tables = Arc::new((
        eyewear::refraction_table_through(s, at)?,
        eyewear::peripheral_table_through(s, at)?,
    ));
    if let Ok(mut cache) = THROUGH.lock() {
        if cache.len() >= THROUGH_CACHED {
            cache.remove(0);
        }
        cache.push((s.clone(), at, tables.clone()));
    }
    Ok(tables)
}

/// The times a refraction is traced at: each table time of optics that change with age,
/// else 0 alone.
fn traced_times(spec: &OpticsSpec) -> Vec<f64> {
    let times = spec.times();
    if times.is_empty() {
        vec![0.0]
    } else {
        times
    }
}

/// The refraction through `spec`'s lenses at growth time `t` of the retina through `retina`
/// (pole first): one entry per image ([`images`]), none without lenses. The tables are
/// traced once per image (per table time for optics that change with age, the refractions
/// there blended in t as the naked eye's are: [`blend_over_ages`]) and kept, so a growth run
/// pays them once; every output time reads them.
///
/// # Errors
/// [`OpticsKeyError`] naming the key when the lenses cannot be traced with a trial lens.
pub fn through_lenses(
    spec: &OpticsSpec,
    z_c: f64,
    t: f64,
    retina: &[(f64, f64)],
) -> Result<Vec<ThroughLenses>, OpticsKeyError> {
    let images = images(spec);
    for (_, s) in &images {
        for at in traced_times(spec) {
            through_tables(s, at)?;
        }
    }
    Ok(images
        .iter()
        .map(|(power, s)| through_image(spec, s, *power, z_c, t, retina))
        .collect())
}

/// [`through_lenses`] where tables that cannot be traced give NaN rather than an error: what
/// a growth run's snapshots hold (the naked eye's rows are NaN there too).
pub fn through_lenses_or_nan(
    spec: &OpticsSpec,
    z_c: f64,
    t: f64,
    retina: &[(f64, f64)],
) -> Vec<ThroughLenses> {
    images(spec)
        .iter()
        .map(|(power, s)| through_image(spec, s, *power, z_c, t, retina))
        .collect()
}

/// The refraction through one image, of optics `s` (`spec`'s, the multifocal lens at the
/// image's power), blended over `spec`'s table times.
fn through_image(
    spec: &OpticsSpec,
    s: &OpticsSpec,
    image_power: Option<f64>,
    z_c: f64,
    t: f64,
    retina: &[(f64, f64)],
) -> ThroughLenses {
    let retina_z = retina.first().map_or(f64::NAN, |p| p.0);
    let fields = eyewear::peripheral_fields(spec.max_field);
    let values = blend_over_ages(spec, t, |at| match through_tables(s, at) {
        Ok(tables) => {
            let pole = tables.0.refraction(retina_z).unwrap_or(f64::NAN);
            let mut v = vec![pole];
            v.extend(eyewear::peripheral_refraction(&tables.1, z_c, retina));
            v
        }
        Err(_) => vec![f64::NAN; fields.len() + 1],
    });
    let share = match image_power {
        None => 1.0,
        Some(_) => f64::NAN,
    };
    ThroughLenses {
        image_power,
        pole_d: values[0],
        peripheral: rows(&fields, &values[1..]),
        share: vec![share; fields.len()],
    }
}

/// `through` with each image's share of the light at each field, from `computed`'s images
/// (the surfaces traced at the first wavelength: [`ComputedOptics::image_share`]).
pub fn with_shares(through: &mut [ThroughLenses], computed: &ComputedOptics) {
    for l in through {
        l.share = (l.peripheral.iter())
            .map(|p| computed.image_share(l.image_power, p.field_deg))
            .collect();
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::eyewear::tests::sphere;
    use crate::model::eyewear::{LensSpec, ProfileSpec};
    use eyeshell_optics::{best_focus_with, lens::wear};

    fn wearing(kind: usize, power: f64) -> OpticsSpec {
        OpticsSpec {
            lenses: vec![LensSpec {
                kind,
                vertex: 12.0,
                profile: ProfileSpec::Power(power),
                lenslets: vec![],
                prescribe: None,
            }],
            ..OpticsSpec::default()
        }
    }

    /// The refraction through a lens is what it says: a thin trial lens of that power at
    /// 12 mm, traced directly over the eye wearing the lens (not through the tables), puts
    /// the best focus on the retina, on the axis and at 20°; through a −2 D spectacle lens at
    /// 12 mm it is the naked eye's plus 2 D (two thin lenses in contact add), and through a
    /// −2 D contact lens less than that (the same lens at the cornea is weaker at 12 mm).
    #[test]
    fn the_refraction_through_a_lens_puts_the_focus_on_the_retina() {
        let retina = sphere();
        let naked = pole(&OpticsSpec::default(), 0.0, 23.0);
        for (kind, what) in [(0, "spectacle"), (1, "contact")] {
            let spec = wearing(kind, -2.0);
            let through = through_lenses(&spec, 12.0, 0.0, &retina).unwrap();
            assert_eq!(through.len(), 1);
            let (d, rows) = (through[0].pole_d, &through[0].peripheral);
            eprintln!("{what}: naked {naked}, through {d}, rows {rows:?}");
            assert!((rows[0].refraction_d - d).abs() < 1e-3, "{what}: {rows:?}");
            let eye = spec.system().unwrap();
            let pupil = spec.pupil_stop(&eye);
            let mut lenses = vec![spec.lenses[0].lens(0).unwrap()];
            for (field, refraction) in [(0.0, d), (20.0, rows[4].refraction_d)] {
                lenses.truncate(1);
                lenses.push(eyeshell_optics::lens::Lens::spectacle(refraction, 12.0));
                if kind == 0 {
                    // The trial lens in contact with the spectacle lens: one thin lens.
                    lenses = vec![eyeshell_optics::lens::Lens::spectacle(
                        refraction - 2.0,
                        12.0,
                    )];
                }
                let worn = wear(&eye, &lenses).unwrap();
                let f = best_focus_with(
                    &worn,
                    spec.refraction_wavelength,
                    field,
                    &pupil,
                    spec.criterion(),
                    &spec.focus_settings(),
                )
                .unwrap();
                let behind = f.r.hypot(f.z - 12.0) - 11.0;
                // 0.004 mm is about 0.01 D in this eye; the pole's table is far finer.
                let tol = if field == 0.0 { 1e-5 } else { 0.004 };
                assert!(behind.abs() < tol, "{what} at {field}°: {behind} mm off");
            }
            match kind {
                0 => assert!((d - naked - 2.0).abs() < 1e-5, "{d} against {naked}"),
                _ => assert!(d > naked + 1.0 && d < naked + 2.0, "{d} against {naked}"),
            }
        }
    }

    /// Through a lens of no power the refraction is the naked eye's, at the pole and at
    /// every field, to the tables' own error: the naked default eye's tables are the kept
    /// ones (every power traced, the default rays), those through the lens are a run's
    /// (every fifth power at the pole, the rays chosen for the eye).
    #[test]
    fn through_a_plano_lens_the_refraction_is_the_naked_eyes() {
        let retina = sphere();
        let spec = wearing(0, 0.0);
        let naked = peripheral(&spec, 12.0, 0.0, &retina);
        let through = &through_lenses(&spec, 12.0, 0.0, &retina).unwrap()[0];
        let d = through.pole_d - pole(&spec, 0.0, 23.0);
        eprintln!("pole: {d}");
        assert!(d.abs() < 1e-5, "{d}");
        for (a, b) in naked.iter().zip(&through.peripheral) {
            assert_eq!(a.field_deg, b.field_deg);
            eprintln!("{}: {}", a.field_deg, a.refraction_d - b.refraction_d);
            assert!(
                (a.refraction_d - b.refraction_d).abs() < 1e-5,
                "{a:?} {b:?}"
            );
        }
    }
}
