//! Numbers in eyeshell's JSON files. JSON has no NaN or infinity: a non-finite f64 is
//! written as `null` (serde_json's rule, which summary.json has always followed) and these
//! helpers read `null` back as NaN, so that every file eyeshell writes reads back.

use serde::{Deserialize, Deserializer};

/// An f64 that may be `null` (read as NaN).
pub(crate) fn f64_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A list of f64 that may hold `null` (read as NaN).
pub(crate) fn f64s_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|x| x.unwrap_or(f64::NAN))
        .collect())
}
