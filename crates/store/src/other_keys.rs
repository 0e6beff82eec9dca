//! The catch-all of a configuration made of flattened parts: serde's
//! `deny_unknown_fields` cannot be combined with `#[serde(flatten)]`, so
//! such a configuration ends with a flattened [`NoOtherKeys`], which
//! receives every key no other field took and refuses the first, naming
//! it as `deny_unknown_fields` would.
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::ser::{SerializeMap, Serializer};
use serde::{Deserialize, Serialize};
use std::fmt;

/// No keys beyond the configuration's own: deserialised from the keys
/// left over (an error naming the first, if any), serialised as nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoOtherKeys;

impl<'de> Deserialize<'de> for NoOtherKeys {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_map(RefuseEveryKey)
    }
}

impl Serialize for NoOtherKeys {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_map(Some(0))?.end()
    }
}

/// Accepts a map only when it is empty.
struct RefuseEveryKey;

impl<'de> Visitor<'de> for RefuseEveryKey {
    type Value = NoOtherKeys;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("no keys other than the configuration's own")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NoOtherKeys, A::Error> {
        match map.next_key::<String>()? {
            None => Ok(NoOtherKeys),
            Some(key) => Err(de::Error::custom(format_args!("unknown field `{key}`"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
    #[serde(default)]
    struct Part {
        a: u32,
    }

    #[derive(Debug, Default, PartialEq, Serialize, Deserialize)]
    #[serde(default)]
    struct Whole {
        #[serde(flatten)]
        part: Part,
        b: u32,
        #[serde(flatten)]
        other_keys: NoOtherKeys,
    }

    #[test]
    fn flattened_keys_are_taken_and_any_other_is_refused_by_name() {
        let whole: Whole = toml::from_str("a = 1\nb = 2\n").unwrap();
        assert_eq!((whole.part.a, whole.b), (1, 2));
        let err = toml::from_str::<Whole>("a = 1\nc = 3\n").unwrap_err();
        assert!(err.to_string().contains("unknown field `c`"), "{err}");
    }

    #[test]
    fn it_writes_nothing() {
        let text = toml::to_string(&Whole::default()).unwrap();
        assert_eq!(text.trim(), "a = 0\nb = 0");
    }
}
