//! Regression tests for inputs found by the mutation fuzz of the CLI
//! (tests/it/fuzz_inputs/mod.rs at the workspace root), one per bug.
use tactrace_arm::ArmError;
use tactrace_geometry::Pose;

/// A rig TOML with an absurd tap depth made `collect` print
/// `pose Pose { x: 59.7, y: .. } is outside the workspace`.
#[test]
fn outside_workspace_message_has_no_debug_pose() {
    let pose = Pose {
        x: 59.72,
        y: -51.5,
        z: -1.1e12,
        rx: 0.0,
        ry: 0.0,
        rz: -44.9,
    };
    let errors = [
        ArmError::OutsideWorkspace {
            pose,
            axis: 'z',
            value_mm: pose.z,
            min_mm: -30.0,
            max_mm: 150.0,
        },
        ArmError::NonFinitePose {
            pose: Pose {
                z: f64::NAN,
                ..pose
            },
        },
    ];
    for err in errors {
        let msg = err.to_string();
        assert!(!msg.contains("Pose {") && !msg.contains("x:"), "{msg}");
        assert!(
            msg.contains("(59.720, -51.500, ") && msg.contains(") deg"),
            "{msg}"
        );
    }
}
