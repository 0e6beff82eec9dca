//! Configuration files that name only what they change.
//!
//! Every run configuration (follow, reproduce, model) has defaults; a TOML
//! file overlays them table by table, and unknown keys are errors because
//! the configuration types deny them.
use crate::error::{LabError, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// `base` with the keys of the TOML `text` laid over it, table by table.
/// `what` names the configuration in error messages.
pub fn overlay<T: Serialize + DeserializeOwned>(base: &T, text: &str, what: &str) -> Result<T> {
    let mut merged =
        toml::Value::try_from(base).map_err(|e| LabError::Config(format!("{what}: {e}")))?;
    let over: toml::Value =
        toml::from_str(text).map_err(|e| LabError::Config(format!("{what}: {e}")))?;
    merge_into(&mut merged, over);
    merged
        .try_into()
        .map_err(|e: toml::de::Error| LabError::Config(format!("{what}: {e}")))
}

/// Lay `over` on `base`: tables merge key by key, anything else replaces.
fn merge_into(base: &mut toml::Value, over: toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(old) => merge_into(old, v),
                    None => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Serialize, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Inner {
        a: f64,
        b: f64,
    }

    #[derive(Debug, Serialize, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Outer {
        inner: Inner,
        n: usize,
    }

    fn base() -> Outer {
        Outer {
            inner: Inner { a: 1.0, b: 2.0 },
            n: 3,
        }
    }

    #[test]
    fn keys_not_named_keep_their_defaults() {
        let got = overlay(&base(), "[inner]\nb = 5.0\n", "test").unwrap();
        assert_eq!(got.inner, Inner { a: 1.0, b: 5.0 });
        assert_eq!(got.n, 3);
    }

    #[test]
    fn unknown_keys_and_bad_toml_are_errors_naming_the_key() {
        let err = overlay(&base(), "[inner]\nc = 1.0\n", "test").unwrap_err();
        assert!(err.to_string().contains('c'), "{err}");
        assert!(overlay(&base(), "n = \"three\"", "test").is_err());
        assert!(overlay(&base(), "[inner", "test").is_err());
    }
}
