//! The fast paths of pin ordering give the results of the slow ones on the
//! shared real sets (issue 21, item 6): the tracker's nearest-neighbour
//! start (`tracker/grid.rs`) against every coarse-to-fine stage from the
//! centroid shift, the windowed matchings (`tracker/window.rs`)
//! against the full ones, the scaled start against the start only
//! moved, and the stalled growth matched again (`tracker/stalled.rs`)
//! against the nearest-neighbour start it spares. Fails when the data is absent unless
//! TACTRACE_SKIP_REAL_DATA=1 (see `tactrace_testdata`).

use crate::common;

use common::{difference, load, real_127_extractors, shear_set_331};
use std::path::PathBuf;

use tactrace_vision::{Frame, PinTracker};

/// The largest pin difference (px) between the usual tracker and one
/// `change`d, over every frame of the shared 127-pin set detected and
/// ordered as `PinExtractor::extract` does (with the touching-pin split;
/// both must succeed or fail alike), and the frame where it is; `None`
/// without the data.
fn largest_127_difference(change: impl FnOnce(PinTracker) -> PinTracker) -> Option<(f64, PathBuf)> {
    let (usual, changed, frames) = real_127_extractors(change)?;
    let mut largest = (0.0, PathBuf::new());
    for path in frames {
        let frame: Frame = load(&path).to_luma8();
        match (usual.extract(&frame), changed.extract(&frame)) {
            (Ok(a), Ok(b)) if difference(&a, &b) > largest.0 => {
                largest = (difference(&a, &b), path)
            }
            (Ok(_), Ok(_)) => {}
            (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{}", path.display()),
        }
    }
    Some(largest)
}

/// The same over 600 held-out frames of the 331-pin shear set (val part),
/// read as the inspection proposes against the rest layout estimated from
/// 150 taps of the train part.
fn largest_331_difference(change: impl FnOnce(PinTracker) -> PinTracker) -> Option<(f64, PathBuf)> {
    let set = tactrace_testdata::shared_set("tactip331-edge2d-shear", "README.md")?;
    let (held, rest) = shear_set_331(&set);
    let usual = PinTracker::new(rest.clone()).expect("tracker");
    let changed = change(PinTracker::new(rest).expect("tracker"));
    let mut largest = (0.0, PathBuf::new());
    for (path, detection) in held {
        let d = difference(&usual.track(&detection), &changed.track(&detection));
        if d > largest.0 {
            largest = (d, path);
        }
    }
    Some(largest)
}

/// The same pins, within 1e-6 px, with the nearest-neighbour start as
/// without, on every 127-pin frame.
#[test]
fn nearest_start_orders_every_shared_127_pin_frame_as_before() {
    if let Some((d, path)) = largest_127_difference(|t| t.with_nearest_start(false)) {
        assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
    }
}

/// The same on the 331-pin frames.
#[test]
fn nearest_start_orders_331_pin_frames_as_before() {
    if let Some((d, path)) = largest_331_difference(|t| t.with_nearest_start(false)) {
        assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
    }
}

/// The windowed matchings (`tracker/window.rs`) against the full ones on
/// every 127-pin frame: the same pins, bit for bit (largest difference
/// 0 px, the same matched flags).
#[test]
fn windowed_matchings_order_every_shared_127_pin_frame_as_before() {
    if let Some((d, path)) = largest_127_difference(|t| t.with_windows(None)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}

/// The same on the 331-pin frames.
#[test]
fn windowed_matchings_order_331_pin_frames_as_before() {
    if let Some((d, path)) = largest_331_difference(|t| t.with_windows(None)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}

/// The scaled start (`PinTracker::with_scaled_start`) against the start
/// only moved on every 127-pin frame (ordered against the undeformed
/// frame's pins, which the taps' pins spread from by about 4 %): the same
/// pins, bit for bit.
#[test]
fn scaled_start_orders_every_shared_127_pin_frame_as_before() {
    if let Some((d, path)) = largest_127_difference(|t| t.with_scaled_start(false)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}

/// The same on the 331-pin frames.
#[test]
fn scaled_start_orders_331_pin_frames_as_before() {
    if let Some((d, path)) = largest_331_difference(|t| t.with_scaled_start(false)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}

/// The stalled growth matched again (`PinTracker::with_stalled_growth`)
/// against such frames sent on to the nearest-neighbour start, on every
/// 127-pin frame: the same pins, bit for bit.
#[test]
fn stalled_growth_orders_every_shared_127_pin_frame_as_before() {
    if let Some((d, path)) = largest_127_difference(|t| t.with_stalled_growth(false)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}

/// The same on the 331-pin frames.
#[test]
fn stalled_growth_orders_331_pin_frames_as_before() {
    if let Some((d, path)) = largest_331_difference(|t| t.with_stalled_growth(false)) {
        assert_eq!(d, 0.0, "{}", path.display());
    }
}
