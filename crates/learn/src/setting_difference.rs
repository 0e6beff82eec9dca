//! The first setting in which two resolved configurations differ, named
//! as a dotted key with both values, for refusals that must say what to
//! change: a continued fit's configuration against its model's (`train
//! --init`), a joined model's members against the first (`tactrace
//! ensemble`), a reused base's settings against the folder's. One walk
//! over the configurations as JSON, so every refusal names keys alike.
use serde::Serialize;
use serde_json::Value;
use std::fmt;

/// A key whose value differs between two configurations: `key` is the
/// dotted path (`pose.layers`), `was` and `now` the first and second
/// configuration's values as JSON text ("absent" where one lacks it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SettingDifference {
    pub key: String,
    pub was: String,
    pub now: String,
}

impl fmt::Display for SettingDifference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "`{}` is {}, not {}", self.key, self.now, self.was)
    }
}

/// The first key (`a`'s keys in their map's order, then `b`'s own) whose values
/// differ in `a` and `b` (objects compared key by key, anything else as a
/// whole, so arrays differ as one setting); `None` when they are equal.
pub fn first_difference(a: &Value, b: &Value) -> Option<SettingDifference> {
    walk(a, b, "")
}

/// [`first_difference`] of two values serialised to JSON (say two
/// `ModelConfig`s); the serialiser's message when either will not.
pub fn first_setting_difference<T: Serialize>(
    a: &T,
    b: &T,
) -> Result<Option<SettingDifference>, serde_json::Error> {
    Ok(first_difference(
        &serde_json::to_value(a)?,
        &serde_json::to_value(b)?,
    ))
}

fn walk(a: &Value, b: &Value, at: &str) -> Option<SettingDifference> {
    let (Value::Object(x), Value::Object(y)) = (a, b) else {
        return (a != b).then(|| differ(at, Some(a), Some(b)));
    };
    for key in x.keys().chain(y.keys().filter(|k| !x.contains_key(*k))) {
        let path = if at.is_empty() {
            key.clone()
        } else {
            format!("{at}.{key}")
        };
        match (x.get(key), y.get(key)) {
            (Some(p), Some(q)) => {
                if let Some(d) = walk(p, q, &path) {
                    return Some(d);
                }
            }
            (p, q) => return Some(differ(&path, p, q)),
        }
    }
    None
}

fn differ(key: &str, a: Option<&Value>, b: Option<&Value>) -> SettingDifference {
    let text = |v: Option<&Value>| v.map_or_else(|| "absent".to_string(), Value::to_string);
    SettingDifference {
        key: key.to_string(),
        was: text(a),
        now: text(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn equal_values_have_no_difference() {
        let a = json!({"seed": 1, "pose": {"layers": [8, 4]}});
        assert_eq!(first_difference(&a, &a.clone()), None);
    }

    /// A nested key is named by its dotted path, with both values.
    #[test]
    fn nested_key_is_named_by_its_path() {
        let a = json!({"seed": 1, "pose": {"layers": [8, 4], "beta": 0.5}});
        let b = json!({"seed": 1, "pose": {"layers": [8, 4], "beta": 0.25}});
        let d = first_difference(&a, &b).unwrap();
        assert_eq!(d.key, "pose.beta");
        assert_eq!((d.was.as_str(), d.now.as_str()), ("0.5", "0.25"));
        assert_eq!(d.to_string(), "`pose.beta` is 0.25, not 0.5");
    }

    /// A key only one side has is "absent" on the other, whichever side.
    #[test]
    fn missing_key_is_absent_on_either_side() {
        let a = json!({"seed": 1});
        let b = json!({"seed": 1, "cost": "huber"});
        let d = first_difference(&a, &b).unwrap();
        assert_eq!((d.key.as_str(), d.was.as_str()), ("cost", "absent"));
        let d = first_difference(&b, &a).unwrap();
        assert_eq!((d.key.as_str(), d.now.as_str()), ("cost", "absent"));
    }

    /// The first differing key in `a`'s order is the one named; arrays
    /// differ as a whole; values of other types differ at their key.
    #[test]
    fn first_key_in_order_and_arrays_whole() {
        let a = json!({"a": [1, 2], "b": 1});
        let b = json!({"a": [1, 3], "b": 2});
        assert_eq!(first_difference(&a, &b).unwrap().key, "a");
        let c = json!({"a": {"x": 1}});
        let d = json!({"a": null});
        let got = first_difference(&c, &d).unwrap();
        assert_eq!((got.key.as_str(), got.now.as_str()), ("a", "null"));
    }

    #[test]
    fn serialisable_values_are_compared_as_json() {
        #[derive(Serialize)]
        struct S {
            epochs: usize,
        }
        let d = first_setting_difference(&S { epochs: 3 }, &S { epochs: 4 }).unwrap();
        assert_eq!(d.unwrap().key, "epochs");
    }
}
