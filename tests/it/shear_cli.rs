//! The 3D collections' unlabelled shear through the real binary (issue 23):
//! `collect --task edge_5d --shear-mm --shear-deg` records it in meta.json
//! and keeps the labels; the planar task refuses the 3D-only flags.
use crate::util;
use util::{tactrace, TempDir};

fn collect(t: &TempDir, out: &str, extra: &[&str]) -> util::Run {
    let mut args = vec![
        "collect",
        "--task",
        "edge_5d",
        "--object",
        "disk",
        "--x-range",
        "3",
        "--tilt-range",
        "8",
        "--rz-range",
        "30",
        "--samples",
        "12",
        "--seed",
        "4",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    tactrace(&t.0, &args)
}

#[test]
fn collect_shear_is_recorded_and_leaves_the_labels() {
    let t = TempDir::new("shear3d");
    let plain = collect(&t, "plain", &[]);
    assert_eq!(plain.code, 0, "{}", plain.stderr);
    let sheared = collect(&t, "sheared", &["--shear-mm", "5", "--shear-deg", "5"]);
    assert_eq!(sheared.code, 0, "{}", sheared.stderr);
    let meta = |d: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(t.join(d).join("meta.json")).unwrap())
            .unwrap()
    };
    let m = meta("sheared");
    let settings = &m["settings"]["collect_3d"];
    assert_eq!(settings["shear_mm"], 5.0, "{m}");
    assert_eq!(settings["shear_deg"], 5.0, "{m}");
    assert_eq!(meta("plain")["settings"]["collect_3d"]["shear_mm"], 0.0);
    let targets = |d: &str| std::fs::read(t.join(d).join("targets.npy")).unwrap();
    let inputs = |d: &str| std::fs::read(t.join(d).join("inputs.npy")).unwrap();
    assert_eq!(targets("plain"), targets("sheared"));
    assert_ne!(inputs("plain"), inputs("sheared"));
    // Out of range: bad input.
    let bad = collect(&t, "bad", &["--shear-mm", "-1"]);
    assert_eq!(bad.code, 2, "{}", bad.stderr);
    // The planar task refuses the 3D-only flags rather than ignore them.
    for flag in ["--shear-mm", "--shear-deg", "--tilt-range"] {
        let r = tactrace(
            &t.0,
            &[
                "collect",
                "--shape",
                "disk",
                "--samples",
                "5",
                flag,
                "3",
                "--out",
                "p",
            ],
        );
        assert_eq!(r.code, 2, "{flag}: {}", r.stderr);
        assert!(r.stderr.contains(flag), "{}", r.stderr);
    }
}
