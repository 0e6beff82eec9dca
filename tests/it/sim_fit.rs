//! `tactrace sim-fit`: the transfer fit of the simulator's physics, end to
//! end on a few real frames (needs ../shared, see tactrace_testdata).
use crate::util;
use util::{expect_refusal, real_data, real_paths, tactrace, TempDir};

#[test]
fn sim_fit_writes_a_usable_rig_file_reproducibly_and_refuses_bad_input() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("sim-fit");
    let [frames, targets, init] = real_paths(&data);
    let (frames, targets, init) = (frames.as_str(), targets.as_str(), init.as_str());
    let args = |out: &'static str| {
        vec![
            "sim-fit",
            "--frames",
            frames,
            "--targets",
            targets,
            "--reference",
            init,
            "--limit",
            "80",
            "--generations",
            "1",
            "--population",
            "3",
            "--seed",
            "2",
            "--out",
            out,
        ]
    };
    let r = tactrace(&t.0, &args("fit"));
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stderr.matches("generation ").count(), 4, "{}", r.stderr);
    let dir = t.join("fit");
    for figure in ["convergence.svg", "convergence.png"] {
        assert!(dir.join(figure).is_file(), "{figure}");
    }
    let csv = std::fs::read_to_string(dir.join("search.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 1 + 3, "{csv}");
    assert!(csv.starts_with("generation,cost,position_mae_mm,angle_mae_deg,calibration."));
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(summary.contains("\"seed\": 2") && summary.contains("tactrace_version"));
    // The best candidate's cost is the lowest in the search (candidates
    // that are no valid sensor cost NaN and rank last).
    let costs: Vec<f64> = csv
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').nth(1)?.parse().ok())
        .collect();
    let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let best = json["best"]["cost"].as_f64().unwrap();
    assert!(best.is_finite() && costs[0].is_finite(), "{costs:?}");
    assert!(
        costs.iter().all(|c| c.is_nan() || best <= *c),
        "{best} vs {costs:?}"
    );
    // sensor.toml is a rig file the simulating commands take.
    let twin = [
        "twin",
        "--targets",
        targets,
        "--reference",
        init,
        "--config",
        "fit/sensor.toml",
        "--limit",
        "10",
        "--out",
        "tw",
    ];
    let r = tactrace(&t.0, &twin);
    assert_eq!(r.code, 0, "{}", r.stderr);
    // The same seed gives the same search.
    assert_eq!(tactrace(&t.0, &args("again")).code, 0);
    let again = std::fs::read_to_string(t.join("again/search.csv")).unwrap();
    assert_eq!(csv, again);
    // Nothing overwritten without --force; no generations is bad input.
    assert_eq!(tactrace(&t.0, &args("fit")).code, 2);
    let mut none = args("none");
    none[10] = "0";
    let r = tactrace(&t.0, &none);
    expect_refusal(&r, 2, "--generations", "--generations");
    assert!(!t.join("none").exists());
}

/// Issue 20: a pressed frame given as `--reference` was accepted
/// silently. `sim-fit` fits its layout to the reference, so a frame
/// pressed this hard is refused as bad input (lighter ones pass the layout
/// fit and get the import's "looks pressed" warning on stderr).
#[test]
fn sim_fit_refuses_a_pressed_reference() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("sim-fit-pressed");
    let [frames, targets, _] = real_paths(&data);
    let pressed = data.join("frames/frame_1432_0.png").display().to_string();
    let r = tactrace(
        &t.0,
        &[
            "sim-fit",
            "--frames",
            &frames,
            "--targets",
            &targets,
            "--reference",
            &pressed,
            "--limit",
            "80",
            "--generations",
            "1",
            "--population",
            "2",
            "--out",
            "fit",
        ],
    );
    expect_refusal(&r, 2, "not an undeformed frame", "not an undeformed frame");
    assert!(!t.join("fit").exists());
}
