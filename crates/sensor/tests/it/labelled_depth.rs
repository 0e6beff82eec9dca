//! The labelled depth (`DepthSearch::labelled_depth`): every tap pressed
//! to its labelled `dz` and the field's gain fitted in the depth law's
//! place. A synthetic sensor that presses to the labelled depth with a
//! weaker field is recovered from its taps (the gain within 0.1, the
//! depth law exactly the labelled one); the default search fits the
//! depth law and records no gain.
use crate::common;

use tactrace_sensor::{fit_depth, DepthSearch, FitSample, TacTipConfig};

/// 30 taps of `truth`, theta in [-60, 60] deg, slides of up to 2 mm
/// and 2 deg ([`common::depth_taps`]).
fn taps(truth: &TacTipConfig) -> (Vec<[f64; 2]>, Vec<FitSample>) {
    common::depth_taps(truth, 30, 2.0, |k| {
        -60.0 + 120.0 * common::spread(k, 11, 30)
    })
}

/// The default sensor pressed to the labelled depth with the field's
/// gain `g` (eqs. S6, S8: layer thickness / g, lift gain x g).
fn labelled(g: f64) -> TacTipConfig {
    let mut c = TacTipConfig::default();
    c.calibration.tap_depth_mm = 0.0;
    c.calibration.depth_per_offset = 1.0;
    c.mechanics.layer_thickness_mm /= g;
    c.mechanics.lift_gain *= g;
    c
}

fn search(labelled_depth: bool) -> DepthSearch {
    DepthSearch {
        threads: 2,
        iterations: 60,
        labelled_depth,
        ..DepthSearch::default()
    }
}

#[test]
fn a_sensor_pressed_to_its_labelled_depth_with_a_weaker_field_is_recovered() {
    let (rest, samples) = taps(&labelled(0.6));
    let own = TacTipConfig::default();
    let fit = fit_depth(&own, &rest, &samples, &search(true)).unwrap();
    assert!(!fit.kept_own, "{}", fit.describe());
    let c = fit.chosen;
    assert_eq!((c.tap_depth_mm, c.depth_per_offset), (0.0, 1.0));
    let g = c.field_gain.expect("the gain is recorded");
    assert!(
        (g - 0.6).abs() < 0.1,
        "gain {g} for 0.6; {}",
        fit.describe()
    );
    assert!(c.rms_px < 0.5 * fit.own.rms_px, "{}", fit.describe());
    let applied = fit.apply(&own);
    let want = own.mechanics.lift_gain * g;
    assert!((applied.mechanics.lift_gain - want).abs() < 1e-12);
}

#[test]
fn the_default_search_fits_the_depth_law_and_records_no_gain() {
    let (rest, samples) = taps(&labelled(1.0));
    let fit = fit_depth(&TacTipConfig::default(), &rest, &samples, &search(false)).unwrap();
    assert_eq!(fit.chosen.field_gain, None, "{}", fit.describe());
    assert!(!fit.kept_own, "{}", fit.describe());
}
