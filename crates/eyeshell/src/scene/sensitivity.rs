//! The scene keys sensitivities are taken to (docs/MODEL.md §10): each key's
//! [`SensParam`], or why there is none, in the key's words.

use super::keys::find;
use crate::growth::dae::SensParam;

/// The sensitivity parameter of scene key `key`. Here, on the scene's side, because the
/// reasons are about keys (the growth names its parameters' keys, it does not read the key
/// table).
///
/// # Errors
/// [`SensitivityKeyError`], naming the key.
pub fn sensitivity_param(key: &str) -> Result<SensParam, SensitivityKeyError> {
    if let Some(p) = SensParam::ALL
        .into_iter()
        .chain(SensParam::OUTSIDE)
        .find(|p| super::names::sensitivity_key(*p) == key)
    {
        return Ok(p);
    }
    let key = key.to_string();
    Err(match key.as_str() {
        "stimulus.red.offset" => SensitivityKeyError::ClassificationOnly { key },
        k if find(k).is_some() => SensitivityKeyError::NotAvailable { key },
        _ => SensitivityKeyError::NotAKey {
            key,
            list_keys: crate::text::advice(&crate::text::Advice::ListKeys),
        },
    })
}

/// Why there is no sensitivity to a key, one line naming it and the keys there are.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SensitivityKeyError {
    /// A key of the classification alone, to which every sensitivity is zero.
    #[error("{key} only affects the classification (myopic or hyperopic), not the growth: every sensitivity to it is zero (supported: {})", super::names::supported_sensitivities())]
    ClassificationOnly { key: String },
    /// A scene key that is not a parameter sensitivities are taken to.
    #[error(
        "sensitivities to {key} are not available (supported: {})",
        super::names::supported_sensitivities()
    )]
    NotAvailable { key: String },
    /// Not a scene key; `list_keys` is what lists them, in the caller's terms.
    #[error(
        "{key:?} is not a scene key (supported: {}; {list_keys} lists every key)",
        super::names::supported_sensitivities()
    )]
    NotAKey { key: String, list_keys: String },
}
