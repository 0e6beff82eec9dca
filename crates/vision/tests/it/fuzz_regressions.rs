//! Regression tests for inputs found by the mutation fuzz of the CLI
//! (tests/it/fuzz_inputs/mod.rs at the workspace root), one per bug.
use tactrace_vision::{BlobParams, VisionError, MAX_THRESHOLDS};

/// `max_threshold = 1e308` (infinite as f32) made the threshold list grow
/// until the allocator gave up (tens of GB, or an abort).
#[test]
fn huge_max_threshold_is_rejected_not_allocated() {
    for text in [
        "max_threshold = 1e308",
        "max_threshold = 4294967296",
        "threshold_step = 1e-6",
    ] {
        let err = BlobParams::from_toml(text).expect_err(text);
        assert!(
            matches!(err, VisionError::InvalidParam { .. }),
            "{text}: {err}"
        );
        assert!(err.to_string().contains("thresholds"), "{err}");
    }
}

/// Parameters built in code skip `validate`; the list stays bounded anyway.
#[test]
fn threshold_list_is_bounded_without_validation() {
    let p = BlobParams {
        max_threshold: f32::INFINITY,
        ..BlobParams::preset("sim").expect("preset")
    };
    assert_eq!(p.thresholds().len(), MAX_THRESHOLDS);
}
