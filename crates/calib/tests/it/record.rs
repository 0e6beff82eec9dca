//! A sensor file's correction round-trips through its record (TOML) and
//! tensors and gives identical taps; another version is refused.
use crate::common;
use common::{distorted, distortion, sim_fields};
use tactrace_calib::{
    field_stats, CalibError, CalibrationRecord, LinearCorrection, Selection, FORMAT_VERSION,
};

fn fitted() -> (LinearCorrection, CalibrationRecord, tactrace_calib::Fields) {
    let sim = sim_fields(60, 20, 4, 1);
    let (a, b) = distortion(20, 2);
    let real = distorted(&sim, &a, &b, 0.01, 3);
    let fit = LinearCorrection::fit(&sim, &real, &Default::default()).unwrap();
    let after = field_stats(&fit.correction.apply(&sim).unwrap(), &real).unwrap();
    let record = CalibrationRecord {
        format_version: FORMAT_VERSION,
        pins: 10,
        params: Default::default(),
        penalty: fit.penalty,
        loo_rms_px: fit.loo_rms,
        selection: Selection {
            seed: 1,
            samples: 60,
            indices: (0..60).collect(),
        },
        held_out_before: Some(field_stats(&sim, &real).unwrap()),
        held_out_after: Some(after),
        pin_jitter: None,
    };
    (fit.correction, record, sim)
}

#[test]
fn record_and_tensors_round_trip_to_identical_taps() {
    let (corr, record, sim) = fitted();
    let text = toml::to_string(&record).unwrap();
    let back: CalibrationRecord = toml::from_str(&text).unwrap();
    assert_eq!(back, record);
    let again = LinearCorrection::from_tensors(&corr.to_tensors(), &back).unwrap();
    assert_eq!(again, corr);
    assert_eq!(
        again.apply(&sim).unwrap().to_flat(),
        corr.apply(&sim).unwrap().to_flat()
    );
}

#[test]
fn other_versions_and_shapes_are_refused() {
    let (corr, mut record, _) = fitted();
    let tensors = corr.to_tensors();
    record.pins = 11;
    assert!(matches!(
        LinearCorrection::from_tensors(&tensors, &record),
        Err(CalibError::Record(_))
    ));
    record.pins = 10;
    record.format_version = FORMAT_VERSION + 1;
    let err = LinearCorrection::from_tensors(&tensors, &record).unwrap_err();
    assert!(err.to_string().contains("version"), "{err}");
    let text = toml::to_string(&record)
        .unwrap()
        .replace("penalty", "penalty_x");
    assert!(toml::from_str::<CalibrationRecord>(&text).is_err());
}
