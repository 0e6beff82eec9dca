//! The fast paths of pin ordering give the results of the slow ones on the
//! shared real sets (issue 21, item 6): the tracker's nearest-neighbour
//! start (`tracker/grid.rs`) against every coarse-to-fine stage from the
//! centroid shift. Fails when the data is absent unless
//! TACTRACE_SKIP_REAL_DATA=1 (see `tactrace_testdata`).

mod common;

use common::{difference, load, real_127_extractors, shear_set_331};
use tactrace_vision::{Frame, PinTracker};

/// Every frame of the shared 127-pin set, detected and ordered as
/// `PinExtractor::extract` does (with the touching-pin split): the same
/// pins, within 1e-6 px, with the nearest-neighbour start as without.
#[test]
fn nearest_start_orders_every_shared_127_pin_frame_as_before() {
    let Some((fast, slow, frames)) = real_127_extractors(|t| t.with_nearest_start(false)) else {
        return;
    };
    for path in &frames {
        let frame: Frame = load(path).to_luma8();
        let (a, b) = (fast.extract(&frame), slow.extract(&frame));
        match (a, b) {
            (Ok(a), Ok(b)) => {
                let d = difference(&a, &b);
                assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
            }
            (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{}", path.display()),
        }
    }
}

/// 600 held-out frames of the 331-pin shear set (val part), read as the
/// inspection proposes against the rest layout estimated from 150 taps of
/// the train part: the same pins with the nearest-neighbour start as
/// without.
#[test]
fn nearest_start_orders_331_pin_frames_as_before() {
    let Some(set) = tactrace_testdata::shared_set("tactip331-edge2d-shear", "README.md") else {
        return;
    };
    let (held, rest) = shear_set_331(&set);
    let fast = PinTracker::new(rest.clone()).expect("tracker");
    let slow = PinTracker::new(rest)
        .expect("tracker")
        .with_nearest_start(false);
    for (path, detection) in &held {
        let d = difference(&fast.track(detection), &slow.track(detection));
        assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
    }
}
