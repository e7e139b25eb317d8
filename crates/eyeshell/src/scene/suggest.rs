//! Spelling suggestions: the known key or section closest to an unknown one.

use super::keys::KEYS;
use super::SceneError;

pub(crate) fn unknown_key(origin: &str, key: &str) -> SceneError {
    SceneError::UnknownKey {
        origin: origin.to_string(),
        key: crate::text::excerpt(key, 80),
        suggestion: closest(key, KEYS.iter().map(|k| k.key)).map(str::to_string),
    }
}

/// The known name closest to `name`, if it is close enough to be a likely typo: same name
/// in another case, the same last component in another section, or a small edit distance.
pub(crate) fn closest<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_lowercase();
    let last = lower.rsplit('.').next().unwrap_or(&lower).to_string();
    let length = lower.chars().count();
    let limit = 2.max(length / 3);
    known
        .map(|k| {
            let kl = k.to_lowercase();
            let score = if kl == lower {
                0
            } else if kl.rsplit('.').next() == Some(last.as_str()) {
                1
            } else if kl.chars().count().abs_diff(length) > limit {
                // Too far apart in length to be within the limit: no need to measure (a
                // megabyte-long name would take seconds).
                usize::MAX
            } else {
                levenshtein(&lower, &kl)
            };
            (score, k)
        })
        .filter(|(score, _)| *score <= limit)
        .min_by_key(|(score, _)| *score)
        .map(|(_, k)| k)
}

pub(super) fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}
