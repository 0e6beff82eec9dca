//! Structure-aware mutations of TOML and JSON documents: parse, delete or
//! duplicate a key, change a value's type or value, serialise again.
use rand::seq::IndexedRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value as Json;
use toml::Value as Toml;

/// Mutate one node of a TOML document.
pub fn mutate_toml(data: &[u8], rng: &mut ChaCha8Rng) -> Option<(Vec<u8>, &'static str)> {
    let text = std::str::from_utf8(data).ok()?;
    let mut doc: Toml = toml::from_str::<toml::Table>(text).ok()?.into();
    let name = mutate_node(&mut doc, rng, &toml_ops());
    Some((toml::to_string(&doc).ok()?.into_bytes(), name))
}

/// Mutate one node of a JSON document.
pub fn mutate_json(data: &[u8], rng: &mut ChaCha8Rng) -> Option<(Vec<u8>, &'static str)> {
    let mut doc: Json = serde_json::from_slice(data).ok()?;
    let name = mutate_node(&mut doc, rng, &json_ops());
    Some((serde_json::to_vec(&doc).ok()?, name))
}

/// The operations one tree kind offers to the generic walker.
struct Ops<V> {
    children: fn(&mut V) -> Vec<&mut V>,
    keys: fn(&V) -> Vec<String>,
    remove: fn(&mut V, &str),
    insert: fn(&mut V, String, V),
    get: fn(&V, &str) -> Option<V>,
    replacements: fn() -> Vec<V>,
}

/// Walk down to a random node, then delete, duplicate or retype a key.
fn mutate_node<V: Clone>(node: &mut V, rng: &mut ChaCha8Rng, ops: &Ops<V>) -> &'static str {
    let keys = (ops.keys)(node);
    let descend = rng.random_bool(0.6);
    if descend {
        let mut kids = (ops.children)(node);
        let n = kids.len();
        if n > 0 {
            return mutate_node(kids.swap_remove(rng.random_range(0..n)), rng, ops);
        }
    }
    let Some(key) = keys.choose(rng).cloned() else {
        return "unchanged";
    };
    match rng.random_range(0..4) {
        0 => {
            (ops.remove)(node, &key);
            "delete key"
        }
        1 => {
            let v = (ops.get)(node, &key).expect("key present");
            (ops.insert)(node, format!("{key}_copy"), v);
            "duplicate key"
        }
        _ => {
            let v = (ops.replacements)().choose(rng).cloned().expect("values");
            (ops.insert)(node, key, v);
            "change type or value"
        }
    }
}

fn toml_ops() -> Ops<Toml> {
    Ops {
        children: |v| match v {
            Toml::Table(t) => t.iter_mut().map(|(_, v)| v).collect(),
            Toml::Array(a) => a.iter_mut().collect(),
            _ => Vec::new(),
        },
        keys: |v| match v {
            Toml::Table(t) => t.keys().cloned().collect(),
            Toml::Array(a) => (0..a.len()).map(|i| i.to_string()).collect(),
            _ => Vec::new(),
        },
        remove: |v, k| match v {
            Toml::Table(t) => drop(t.remove(k)),
            Toml::Array(a) => drop(a.remove(k.parse().unwrap_or(0))),
            _ => {}
        },
        insert: |v, k, x| match v {
            Toml::Table(t) => drop(t.insert(k, x)),
            Toml::Array(a) => match k.parse::<usize>() {
                Ok(i) => a[i] = x,
                Err(_) => a.push(x),
            },
            _ => {}
        },
        get: |v, k| match v {
            Toml::Table(t) => t.get(k).cloned(),
            Toml::Array(a) => a.get(k.parse::<usize>().ok()?).cloned(),
            _ => None,
        },
        replacements: toml_values,
    }
}

fn toml_values() -> Vec<Toml> {
    let mut v: Vec<Toml> = [
        0.0,
        -1.0,
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        1e308,
        1e-320,
    ]
    .into_iter()
    .map(Toml::Float)
    .collect();
    v.extend([0, -1, i64::MAX, i64::MIN, 1 << 40].map(Toml::Integer));
    v.extend(["", "x", "disk", "\u{fffd}"].map(|s| Toml::String(s.into())));
    v.push(Toml::Boolean(true));
    v.push(Toml::Array(Vec::new()));
    v.push(Toml::Array(vec![Toml::Integer(-1); 3]));
    v.push(Toml::Table(toml::Table::new()));
    v
}

fn json_ops() -> Ops<Json> {
    Ops {
        children: |v| match v {
            Json::Object(m) => m.values_mut().collect(),
            Json::Array(a) => a.iter_mut().collect(),
            _ => Vec::new(),
        },
        keys: |v| match v {
            Json::Object(m) => m.keys().cloned().collect(),
            Json::Array(a) => (0..a.len()).map(|i| i.to_string()).collect(),
            _ => Vec::new(),
        },
        remove: |v, k| match v {
            Json::Object(m) => drop(m.remove(k)),
            Json::Array(a) => drop(a.remove(k.parse().unwrap_or(0))),
            _ => {}
        },
        insert: |v, k, x| match v {
            Json::Object(m) => drop(m.insert(k, x)),
            Json::Array(a) => match k.parse::<usize>() {
                Ok(i) => a[i] = x,
                Err(_) => a.push(x),
            },
            _ => {}
        },
        get: |v, k| match v {
            Json::Object(m) => m.get(k).cloned(),
            Json::Array(a) => a.get(k.parse::<usize>().ok()?).cloned(),
            _ => None,
        },
        replacements: json_values,
    }
}

fn json_values() -> Vec<Json> {
    let mut v: Vec<Json> = [0.0, -1.0, 1e308, -1e308, 1e-320, 0.5]
        .into_iter()
        .map(|f| serde_json::json!(f))
        .collect();
    v.extend([
        serde_json::json!(u64::MAX),
        serde_json::json!(i64::MIN),
        serde_json::json!(1u64 << 40),
        serde_json::json!(""),
        serde_json::json!("x"),
        serde_json::json!(null),
        serde_json::json!(true),
        serde_json::json!([]),
        serde_json::json!([-1, -1]),
        serde_json::json!({}),
    ]);
    v
}
