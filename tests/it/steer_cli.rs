//! Heading control on surfaces through the real binary (issue 23):
//! `follow --task surface_3d --steer` is checked before anything runs and
//! refused for the edge tasks, which turn by their predicted rz.
use crate::util;
use util::{tactrace, TempDir};

#[test]
fn steer_is_checked_and_refused_for_edge_tasks() {
    let t = TempDir::new("steer");
    let edge = tactrace(
        &t.0,
        &[
            "follow", "--task", "edge_5d", "--object", "foil", "--model", "m", "--steer", "30",
            "--out", "run",
        ],
    );
    assert_eq!(edge.code, 2, "{}", edge.stderr);
    assert!(edge.stderr.contains("--steer"), "{}", edge.stderr);
    let nan = tactrace(
        &t.0,
        &[
            "follow",
            "--task",
            "surface_3d",
            "--object",
            "saddle",
            "--model",
            "m",
            "--steer",
            "nan",
            "--out",
            "run2",
        ],
    );
    assert_eq!(nan.code, 2, "{}", nan.stderr);
    assert!(nan.stderr.contains("heading_deg"), "{}", nan.stderr);
    assert!(!t.join("run").exists() && !t.join("run2").exists());
}
