//! The shipped blob-parameter files (configs/blob-*.toml) parse, and each
//! equals the preset of the same name; TOML errors are reported by key.

use std::path::Path;

use tactrace_vision::{BlobParams, VisionError, PRESET_NAMES};

const CONFIGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs");

#[test]
fn every_blob_config_parses_and_matches_its_preset() {
    let mut seen = Vec::new();
    for entry in std::fs::read_dir(Path::new(CONFIGS)).expect("configs dir") {
        let path = entry.expect("dir entry").path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        let Some(preset) = name
            .strip_prefix("blob-")
            .and_then(|n| n.strip_suffix(".toml"))
        else {
            continue;
        };
        let text = std::fs::read_to_string(&path).expect("readable");
        let parsed = BlobParams::from_toml(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            parsed,
            BlobParams::preset(preset).expect("known preset"),
            "{name}"
        );
        seen.push(preset.to_string());
    }
    seen.sort();
    let mut want: Vec<String> = PRESET_NAMES.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(seen, want, "one config file per preset");
}

#[test]
fn unknown_key_is_an_error_naming_it() {
    let err = BlobParams::from_toml("min_area = 10.0\nmin_aera = 12.0\n").unwrap_err();
    assert_eq!(
        err,
        VisionError::UnknownKey {
            key: "min_aera".into()
        }
    );
}

#[test]
fn missing_keys_take_opencv_defaults() {
    assert_eq!(
        BlobParams::from_toml("").expect("empty"),
        BlobParams::default()
    );
    let p = BlobParams::from_toml("blob_color = 255\nmin_area = 10").expect("partial");
    assert_eq!(p.blob_color, 255);
    assert_eq!(p.min_area, 10.0);
    assert_eq!(p.max_area, 5000.0);
    assert_eq!(p.min_repeatability, 2);
    assert_eq!(p.max_convexity, f32::MAX);
}

#[test]
fn every_preset_round_trips_through_toml() {
    for name in PRESET_NAMES {
        let p = BlobParams::preset(name).expect("preset");
        p.validate().expect("valid preset");
        assert_eq!(
            BlobParams::from_toml(&p.to_toml()).expect("round trip"),
            p,
            "{name}"
        );
    }
}

#[test]
fn wrong_types_and_bad_ranges_are_errors() {
    assert!(matches!(
        BlobParams::from_toml("min_area = \"big\""),
        Err(VisionError::Toml { .. })
    ));
    assert!(matches!(
        BlobParams::from_toml("min_area = 100.0\nmax_area = 50.0"),
        Err(VisionError::InvalidParam { name: "area", .. })
    ));
    assert!(matches!(
        BlobParams::from_toml("threshold_step = 0"),
        Err(VisionError::InvalidParam {
            name: "threshold_step",
            ..
        })
    ));
    assert!(matches!(
        BlobParams::from_toml("min_repeatability = 0"),
        Err(VisionError::InvalidParam {
            name: "min_repeatability",
            ..
        })
    ));
    assert!(matches!(
        BlobParams::preset("nope"),
        Err(VisionError::UnknownPreset { .. })
    ));
}

#[test]
fn report_preset_has_the_appendix_values() {
    let p = BlobParams::preset("report").expect("preset");
    assert_eq!((p.min_threshold, p.max_threshold), (82.39, 215.98));
    assert_eq!((p.min_area, p.max_area), (82.39, 190.96));
    assert_eq!(
        (p.min_circularity, p.min_inertia_ratio, p.min_convexity),
        (0.44, 0.27, 0.57)
    );
    assert!(p.filter_by_color && p.blob_color == 255);
    assert_eq!(p.threshold_step, 10.0);
}
