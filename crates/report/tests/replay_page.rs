//! The replay page in a real browser: headless Chromium opens it at
//! `#step=5`, runs its script, and the DOM shows step 5's values. Skipped,
//! with a message saying so, where no Chromium is installed
//! (`TACTRACE_CHROMIUM=PATH` names one elsewhere).
use std::path::PathBuf;
use std::process::Command;
use tactrace_geometry::{Contour, Pose, Vec2};
use tactrace_report::replay_html::{replay_html, PinFields, ReplayPage};
use tactrace_servo::{Percept, StepRecord};

fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("TACTRACE_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"));
    path.is_file().then_some(path)
}

fn steps() -> Vec<StepRecord> {
    (0..12)
        .map(|i| StepRecord {
            step: i,
            pose: Pose::planar(
                30.0 * (i as f64 / 2.0).cos(),
                30.0 * (i as f64 / 2.0).sin(),
                0.0,
                28.6 * i as f64,
            ),
            percept: Percept {
                r_mm: 0.1 * i as f64 - 0.3,
                theta_deg: 2.0 - 0.5 * i as f64,
                mean_displacement_px: 3.0 + 0.01 * i as f64,
                contact: i != 7,
                missing_pins: 0,
            },
            delta: Pose::planar(0.0, 1.0, 0.0, 0.0),
        })
        .collect()
}

#[test]
fn the_page_opened_at_a_step_shows_that_steps_values() {
    let Some(browser) = chromium() else {
        eprintln!(
            "SKIPPED: no Chromium at /usr/bin/chromium (apt-get install chromium, or set \
             TACTRACE_CHROMIUM=PATH): the replay page was not run in a browser"
        );
        return;
    };
    let disk = Contour::new(
        (0..64)
            .map(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                Vec2::new(30.0 * a.cos(), 30.0 * a.sin())
            })
            .collect(),
    )
    .unwrap();
    let steps = steps();
    let pins = [[10.0, 10.0], [20.0, 15.0], [15.0, 25.0]];
    let fields = vec![vec![0.5f32, -0.5, 0.0, 1.0, 0.0, -1.0]; steps.len()];
    let html = replay_html(&ReplayPage {
        title: "disk (browser test)",
        contour: Some(&disk),
        steps: &steps,
        sensor_radius_mm: 20.0,
        fields: Some(PinFields {
            reference_pins: &pins,
            fields: &fields,
        }),
        frames: None,
        notes: &["a note".to_string()],
    });
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("replay.html");
    std::fs::write(&page, html).unwrap();
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--no-first-run",
            &format!("--user-data-dir={}", profile.path().display()),
            "--dump-dom",
            &format!("file://{}#step=5", page.display()),
        ])
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = &steps[5];
    let expected = format!(
        "step 5 of 11: x {:.2} mm, y {:.2} mm, angle {:.1} deg | predicted r {:.2} mm, theta {:.1} deg",
        s.pose.x, s.pose.y, s.pose.rz, s.percept.r_mm, s.percept.theta_deg
    );
    assert!(dom.contains("data-step=\"5\""), "{dom}");
    assert!(dom.contains(&expected), "wanted `{expected}` in {dom}");
    assert!(
        dom.contains("<h1 id=\"title\">disk (browser test)</h1>"),
        "{dom}"
    );
}
