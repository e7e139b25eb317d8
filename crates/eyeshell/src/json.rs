//! Numbers in eyeshell's JSON files. JSON has no NaN or infinity: a non-finite f64 is
//! written as `null` (serde_json's rule, which summary.json has always followed) and these
//! helpers read `null` back as NaN, so that every file eyeshell writes reads back.

use serde::{Deserialize, Deserializer};

/// An f64 that may be `null` (read as NaN).
pub fn f64_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A list of f64 that may hold `null` (read as NaN).
pub fn f64s_or_nan<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    Ok(Vec::<Option<f64>>::deserialize(d)?
        .into_iter()
        .map(|x| x.unwrap_or(f64::NAN))
        .collect())
}

#[cfg(test)]
mod tests {
    /// Numbers read back from JSON (a sweep worker's results, summaries) are the numbers
    /// written, to the last bit: serde_json's default parser may be one ulp off, so the
    /// workspace enables its `float_roundtrip` feature. 23.037595267862706 came back as
    /// ...702 without it (a sweep table disagreeing with its run's series.csv).
    #[test]
    fn floats_survive_a_json_round_trip_exactly() {
        let mut x = 23.037595267862706_f64;
        for _ in 0..10_000 {
            let text = serde_json::to_string(&x).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{text}");
            x = f64::from_bits(
                x.to_bits()
                    .wrapping_mul(6364136223846793005)
                    .rotate_left(17)
                    % 0x7fe0_0000_0000_0000,
            );
        }
    }
}
