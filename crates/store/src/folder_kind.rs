//! What a folder is, by the files in it, so that a folder of the wrong
//! kind (a model folder given as a dataset, a dataset as a model) is
//! named in the message together with what was expected.
use std::path::Path;

/// What `tactrace` expects in a dataset folder.
pub const DATASET_EXPECTED: &str =
    "a dataset folder holds inputs.npy, targets.npy and meta.json (from `tactrace collect`, \
     `import` or `twin`)";

/// What `tactrace` expects in a model folder.
pub const MODEL_EXPECTED: &str =
    "a model folder holds model.json, weights.safetensors and pins.json (from `tactrace train`)";

/// What `dir` is, as a phrase ("a model folder (from `tactrace train`)"),
/// when its files say so.
pub fn folder_kind(dir: &Path) -> Option<&'static str> {
    let has = |name: &str| dir.join(name).exists();
    if has("model.json") {
        Some("a model folder (from `tactrace train`)")
    } else if has("meta.json") && has("inputs.npy") {
        Some("a dataset folder (from `tactrace collect`, `import` or `twin`)")
    } else if has("sensor.toml") {
        Some("a calibrated sensor folder (from `tactrace calibrate`)")
    } else if has("trajectory.csv") {
        Some("a follow run folder (from `tactrace follow`)")
    } else if has("targets.csv") && dir.join("frames").is_dir() {
        Some("a labelled frame collection (make a dataset of it with `tactrace import`)")
    } else {
        None
    }
}

/// Why `dir` is not a `wanted` folder ("dataset", "model") when `missing`
/// is not in it: what it is instead, if known, and what was expected.
pub fn wrong_folder(dir: &Path, wanted: &str, missing: &str, expected: &str) -> String {
    let what = if dir.is_file() {
        "this is a file".to_string()
    } else if !dir.exists() {
        "there is no such folder".to_string()
    } else {
        match folder_kind(dir) {
            Some(kind) => format!("this is {kind}"),
            None => format!("no {missing} in it"),
        }
    };
    format!("not a {wanted} directory: {what}; {expected}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_of_another_kind_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let model = tmp.path().join("m");
        std::fs::create_dir(&model).unwrap();
        std::fs::write(model.join("model.json"), "{}").unwrap();
        let msg = wrong_folder(&model, "dataset", "meta.json", DATASET_EXPECTED);
        assert_eq!(
            msg,
            "not a dataset directory: this is a model folder (from `tactrace train`); a \
             dataset folder holds inputs.npy, targets.npy and meta.json (from `tactrace \
             collect`, `import` or `twin`)"
        );
        let empty = tmp.path().join("e");
        std::fs::create_dir(&empty).unwrap();
        let msg = wrong_folder(&empty, "model", "model.json", MODEL_EXPECTED);
        assert!(msg.starts_with("not a model directory: no model.json in it; a model folder holds"));
        let gone = wrong_folder(&tmp.path().join("x"), "model", "model.json", MODEL_EXPECTED);
        assert!(gone.contains("there is no such folder"), "{gone}");
    }
}
