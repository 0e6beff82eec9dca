//! The replay page in a real browser: headless Chromium opens it at
//! `#step=5`, runs its script, and the DOM shows step 5's values. Skipped,
//! with a message saying so, where no Chromium is installed
//! (`TACTRACE_CHROMIUM=PATH` names one elsewhere). With
//! `TACTRACE_REPLAY_SCREENSHOT=FILE.png` the real-frame page is also
//! photographed there, to look at.
use std::path::{Path, PathBuf};
use std::process::Command;
use tactrace_geometry::{Contour, Pose, Vec2};
use tactrace_report::replay_html::{replay_html, PinFields, ReplayPage, StepFrames};
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

const SKIPPED: &str = "SKIPPED: no Chromium at /usr/bin/chromium (apt-get install chromium, or \
     set TACTRACE_CHROMIUM=PATH): the replay page was not run in a browser";

fn disk() -> Contour {
    Contour::new(
        (0..64)
            .map(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                Vec2::new(30.0 * a.cos(), 30.0 * a.sin())
            })
            .collect(),
    )
    .unwrap()
}

/// Headless Chromium's arguments, with a fresh profile in `profile`.
fn browser_args(profile: &Path) -> Vec<String> {
    [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
        "--hide-scrollbars",
    ]
    .iter()
    .map(|a| a.to_string())
    .chain([format!("--user-data-dir={}", profile.display())])
    .collect()
}

/// The page's DOM after its script ran, opened at `fragment`.
fn dump_dom(browser: &Path, html: &str, fragment: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("replay.html");
    std::fs::write(&page, html).unwrap();
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(browser)
        .args(browser_args(profile.path()))
        .arg("--dump-dom")
        .arg(format!("file://{}{fragment}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A screenshot of the page at `shot` (to look at).
fn screenshot(browser: &Path, html: &str, shot: &Path) {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("replay.html");
    std::fs::write(&page, html).unwrap();
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(browser)
        .args(browser_args(profile.path()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg("--window-size=1100,900")
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs");
    assert!(out.status.success() && shot.is_file(), "no screenshot");
}

/// The value of attribute `name` on the element with id `id` in `dom`.
fn attribute<'a>(dom: &'a str, id: &str, name: &str) -> &'a str {
    let start = dom.find(&format!("id=\"{id}\"")).expect("element");
    let tag = &dom[dom[..start].rfind('<').unwrap()..];
    let tag = &tag[..tag.find('>').unwrap()];
    let key = format!("{name}=\"");
    let at = tag
        .find(&key)
        .unwrap_or_else(|| panic!("no {name} in {tag}"))
        + key.len();
    &tag[at..at + tag[at..].find('"').unwrap()]
}

#[test]
fn the_page_opened_at_a_step_shows_that_steps_values() {
    let Some(browser) = chromium() else {
        eprintln!("{SKIPPED}");
        return;
    };
    let disk = disk();
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
    let dom = dump_dom(&browser, &html, "#step=5");
    let s = &steps[5];
    let expected = format!(
        "step 5 (6 of 12): x {:.2} mm, y {:.2} mm, angle {:.1} deg | predicted r {:.2} mm, theta {:.1} deg",
        s.pose.x, s.pose.y, s.pose.rz, s.percept.r_mm, s.percept.theta_deg
    );
    assert!(dom.contains("data-step=\"5\""), "{dom}");
    assert!(dom.contains(&expected), "wanted `{expected}` in {dom}");
    assert!(
        dom.contains("<h1 id=\"title\">disk (browser test)</h1>"),
        "{dom}"
    );
}

/// A 64 x 64 grey frame with a bright square, as PNG bytes.
fn frame_png(shade: u8) -> Vec<u8> {
    let img = image::GrayImage::from_fn(64, 64, |x, y| {
        image::Luma([if (20..44).contains(&x) && (20..44).contains(&y) {
            255
        } else {
            shade
        }])
    });
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).unwrap();
    png.into_inner()
}

/// Issue 20: the page said "step 367 of 367" under "368 steps", had no
/// axes or scale, and did not say which real frame answered a tap. Now the
/// last of 12 steps is "step 11 (12 of 12)", the world's axes are ticked
/// in mm over the data with a scale bar, and `#frame` names the answering
/// frame and its label distance.
#[test]
fn the_page_has_mm_axes_a_scale_bar_and_names_the_answering_frame() {
    let Some(browser) = chromium() else {
        eprintln!("{SKIPPED}");
        return;
    };
    let disk = disk();
    let steps = steps();
    let images = [frame_png(60), frame_png(120)];
    let names = ["frame_10_0.png".to_string(), "frame_25_0.png".to_string()];
    let per_step: Vec<usize> = (0..steps.len()).map(|i| usize::from(i >= 6)).collect();
    let distances: Vec<f64> = (0..steps.len()).map(|i| 0.05 * i as f64).collect();
    let notes = [format!("Closed: {} steps", steps.len())];
    let html = replay_html(&ReplayPage {
        title: "disk (real-frame world)",
        contour: Some(&disk),
        steps: &steps,
        sensor_radius_mm: 20.0,
        fields: None,
        frames: Some(StepFrames {
            images: &images,
            names: &names,
            per_step: &per_step,
            distances: &distances,
        }),
        notes: &notes,
    });
    let dom = dump_dom(&browser, &html, "");
    assert!(dom.contains("12 steps"), "{dom}");
    assert!(dom.contains("step 11 (12 of 12):"), "{dom}");
    assert!(
        dom.contains("answered by the real frame frame_25_0.png, label distance 0.550"),
        "{dom}"
    );
    let at_step_2 = dump_dom(&browser, &html, "#step=2");
    assert!(
        at_step_2.contains("answered by the real frame frame_10_0.png, label distance 0.100"),
        "{at_step_2}"
    );
    // The disk and the path lie within 30 mm of the origin, the sensor's
    // 20 mm round them: the ticks cover -50..50 mm in round steps.
    for axis in ["data-x-ticks", "data-y-ticks"] {
        let ticks: Vec<f64> = attribute(&dom, "world", axis)
            .split(' ')
            .map(|t| t.parse().expect("a tick in mm"))
            .collect();
        assert!(ticks.len() >= 4, "{axis}: {ticks:?}");
        assert!(
            ticks[0] <= -40.0 && *ticks.last().unwrap() >= 40.0,
            "{axis}: {ticks:?}"
        );
        let step = ticks[1] - ticks[0];
        assert!([10.0, 20.0, 25.0].contains(&step), "{axis}: {ticks:?}");
    }
    assert_eq!(attribute(&dom, "world", "data-scale-bar"), "20 mm");
    if let Some(shot) = std::env::var_os("TACTRACE_REPLAY_SCREENSHOT") {
        screenshot(&browser, &html, Path::new(&shot));
    }
}
