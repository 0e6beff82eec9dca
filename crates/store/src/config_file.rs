//! The one way every command reads its configuration: the defaults, then
//! the TOML file laid over them table by table (a file names only what it
//! changes; unknown keys are errors because the configuration types deny
//! them), then the command's flags (set by the caller on the result). The
//! resolved configuration is written into every run's output.
use crate::error::{Result, StoreError};
use crate::toml_integers::oversized_integer;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

/// `T`'s defaults with the file at `path` (if any) laid over them. `what`
/// names the configuration in errors ("follow configuration").
pub fn load_config<T>(path: Option<&Path>, what: &str) -> Result<T>
where
    T: Default + Serialize + DeserializeOwned,
{
    match path {
        None => Ok(T::default()),
        Some(path) => {
            let text = crate::fsutil::read_text(path)?;
            overlay(&T::default(), &text, &format!("{}: {what}", path.display()))
        }
    }
}

/// The `config.toml` every run writes: the resolved configuration
/// (defaults, file and flags applied, seeds included) under a comment
/// naming the tactrace `version`, so the file can be given back to
/// `--config` to run the same again.
pub fn resolved_config_toml<T: Serialize>(version: &str, config: &T) -> Result<String> {
    let body = toml::to_string(config).map_err(|e| config_err("resolved configuration", e))?;
    Ok(format!(
        "# The resolved configuration of this run (tactrace {version}); give it to\n\
         # --config to run the same again.\n{body}"
    ))
}

/// `base` with the keys of the TOML `text` laid over it, table by table.
/// `what` names the configuration in error messages.
pub fn overlay<T: Serialize + DeserializeOwned>(base: &T, text: &str, what: &str) -> Result<T> {
    let base = toml::Value::try_from(base).map_err(|e| config_err(what, e))?;
    overlay_value(base, text, what)
}

/// As [`overlay`] over a base given as a TOML value: for configurations
/// with required tables and no whole default (a real rig's file), whose
/// optional tables still get their defaults key by key.
pub fn overlay_value<T: DeserializeOwned>(
    mut base: toml::Value,
    text: &str,
    what: &str,
) -> Result<T> {
    let over = parse_toml(text, what)?;
    merge_into(&mut base, toml::Value::Table(over));
    base.try_into()
        .map_err(|e: toml::de::Error| config_err(what, e))
}

/// The TOML `text` parsed; refused naming the key and line of an integer
/// larger than TOML's signed 64-bit integers hold (say a seed of
/// 2^64 - 1), where the parser's own message may not name it.
pub fn parse_toml(text: &str, what: &str) -> Result<toml::Table> {
    toml::from_str(text).map_err(|e| match oversized_integer(text) {
        Some((key, line, literal)) => config_err(
            what,
            format!(
                "`{key}` = {literal} (line {line}) is out of range: a TOML integer lies in \
                 [{}, {}]",
                i64::MIN,
                i64::MAX
            ),
        ),
        None => config_err(what, e),
    })
}

fn config_err(what: &str, e: impl std::fmt::Display) -> StoreError {
    StoreError::Config {
        what: what.to_string(),
        reason: e.to_string().trim_end().to_string(),
    }
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

    /// An integer past i64 is refused naming its key and line, whatever
    /// the parser itself says; one in range still reaches the type.
    #[test]
    fn an_integer_past_i64_is_refused_naming_the_key() {
        let text = "n = 3\n[inner]\na = 18446744073709551615\n";
        let err = overlay(&base(), text, "test").unwrap_err().to_string();
        assert!(err.contains("`inner.a`") && err.contains("line 3"), "{err}");
        let got: Outer = overlay(&base(), "n = 9223372036854775807\n", "test").unwrap();
        assert_eq!(got.n as u64, i64::MAX as u64);
    }
}
