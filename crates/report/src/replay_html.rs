//! A follow run as one self-contained page (`replay.html`): the contour,
//! the path so far, the sensor's pose and what the model predicted at each
//! step, and the tap's pins with their displacement arrows, with a play
//! button and a step slider. The data is inline JSON and the page's script
//! a few dozen lines: no network, no files beside it.
//!
//! Steps are numbered from 0, as in the run's `trajectory.csv` and
//! `answers.csv`; the status line also says which of how many the step is
//! ("step 367 (368 of 368)"), so it agrees with the summary's step count.
//! The page opens at step K when its address ends in `#step=K`; the
//! element `#status` then says that step's values, `#frame` names the frame
//! that answered the tap (the real-frame world), and the world canvas
//! carries its tick values and scale bar as `data-` attributes (what the
//! browser test reads). The world is drawn with its axes ticked in mm and
//! a scale bar.
use base64::engine::general_purpose::STANDARD as BASE64;
use base64::Engine as _;
use serde::Serialize;
use tactrace_geometry::Contour;
use tactrace_servo::StepRecord;

/// The taps' pin displacements: the reference pins (px) and every tap's
/// displacement vector (x of every pin, then y, px), in that pin order.
#[derive(Clone, Copy)]
pub struct PinFields<'a> {
    pub reference_pins: &'a [[f64; 2]],
    pub fields: &'a [Vec<f32>],
}

/// The frames the taps saw, as image files (PNG bytes): each distinct
/// frame once with its image name, and for every step the index of its
/// frame and how far that frame's labels were from the pose reached.
#[derive(Clone, Copy)]
pub struct StepFrames<'a> {
    /// Each distinct frame's file (PNG bytes).
    pub images: &'a [Vec<u8>],
    /// Each distinct frame's image name (its file name in the collection).
    pub names: &'a [String],
    /// For every step, the index of its frame in `images`.
    pub per_step: &'a [usize],
    /// For every step, the scaled label distance between the pose reached
    /// and the answering frame's labels (empty when not measured).
    pub distances: &'a [f64],
}

/// What the page shows of one run.
pub struct ReplayPage<'a> {
    /// The title (shape and world).
    pub title: &'a str,
    /// The true contour, when known.
    pub contour: Option<&'a Contour>,
    /// Every step of the loop.
    pub steps: &'a [StepRecord],
    /// The sensor's dome radius, mm (drawn round the pose).
    pub sensor_radius_mm: f64,
    /// The taps' pin displacements, when the run kept them.
    pub fields: Option<PinFields<'a>>,
    /// The frames of the taps, when the run kept them (drawn under the
    /// pins, in the frame's pixels).
    pub frames: Option<StepFrames<'a>>,
    /// Summary lines shown under the title (metrics, warnings).
    pub notes: &'a [String],
}

/// The page's data, as the script reads it.
#[derive(Serialize)]
struct PageData<'a> {
    title: &'a str,
    notes: &'a [String],
    radius: f64,
    contour: Vec<[f64; 2]>,
    /// x, y, angle, r_pred, theta_pred, mean displacement, contact (0/1).
    steps: Vec<[f64; 7]>,
    pins: Vec<[f64; 2]>,
    /// Per step: dx of every pin, then dy (empty when not kept).
    fields: Vec<Vec<f64>>,
    /// The distinct frames as data URIs and their image names, each step's
    /// index into them and its label distance (null when not measured).
    images: Vec<String>,
    image_names: &'a [String],
    step_image: Vec<usize>,
    step_distance: Vec<Option<f64>>,
}

fn round2(v: f64) -> f64 {
    if v.is_finite() {
        (v * 100.0).round() / 100.0
    } else {
        0.0
    }
}

/// The page as HTML text.
pub fn replay_html(page: &ReplayPage) -> String {
    let contour = page.contour.map_or(Vec::new(), |c| {
        let n = ((c.perimeter() / 0.5).ceil() as usize).clamp(16, 4000);
        c.resample(n)
            .iter()
            .map(|p| [round2(p.x), round2(p.y)])
            .collect()
    });
    let steps = page
        .steps
        .iter()
        .map(|r| {
            let p = &r.percept;
            [
                r.pose.x,
                r.pose.y,
                r.pose.rz,
                p.r_mm,
                p.theta_deg,
                p.mean_displacement_px,
                f64::from(u8::from(p.contact)),
            ]
            .map(round2)
        })
        .collect();
    let (pins, fields) = page.fields.map_or((Vec::new(), Vec::new()), |pf| {
        let (pins, f) = (pf.reference_pins, pf.fields);
        let pins = pins.iter().map(|p| [round2(p[0]), round2(p[1])]).collect();
        let f = f
            .iter()
            .map(|v| v.iter().map(|&d| round2(d as f64)).collect())
            .collect();
        (pins, f)
    });
    let uri = |png: &Vec<u8>| format!("data:image/png;base64,{}", BASE64.encode(png));
    let images = page
        .frames
        .map_or(Vec::new(), |f| f.images.iter().map(uri).collect());
    let distance = |d: &f64| d.is_finite().then(|| (d * 1000.0).round() / 1000.0);
    let frames = page.frames;
    let data = PageData {
        title: page.title,
        notes: page.notes,
        radius: page.sensor_radius_mm,
        contour,
        steps,
        pins,
        fields,
        images,
        image_names: frames.map_or(&[], |f| f.names),
        step_image: frames.map_or(Vec::new(), |f| f.per_step.to_vec()),
        step_distance: frames.map_or(Vec::new(), |f| f.distances.iter().map(distance).collect()),
    };
    // Inside a script element nothing may close it: `</` is written `<\/`.
    let json = serde_json::to_string(&data)
        .expect("page data serialises")
        .replace("</", "<\\/");
    let title = escape(page.title);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title>\n<style>{STYLE}</style></head>\n<body>\n{BODY}\
         <script type=\"application/json\" id=\"data\">{json}</script>\n\
         <script>{SCRIPT}</script>\n</body></html>\n"
    )
}

/// Text for HTML (the title).
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The page's style sheet, inlined.
const STYLE: &str = include_str!("replay_html.css");

const BODY: &str = "<h1 id=\"title\"></h1><div id=\"notes\"></div>\n\
<div class=\"panes\"><canvas id=\"world\" width=\"560\" height=\"560\"></canvas>\
<div><canvas id=\"pins\" width=\"400\" height=\"400\"></canvas>\
<div class=\"cap\">the tap&#39;s frame (when the run kept it, faded), its pins at rest (grey) and their displacement x3 (green)</div>\
<div id=\"frame\"></div></div></div>\n\
<div class=\"key\"><span><i class=\"sw\" style=\"background:#999\"></i>contour</span>\
<span><i class=\"sw\" style=\"background:#1f77b4\"></i>path (commanded)</span>\
<span><i class=\"sw\" style=\"background:#d62728\"></i>sensor and its x axis</span>\
<span><i class=\"sw\" style=\"background:#ff7f0e\"></i>edge as predicted</span>\
<span><i class=\"sw\" style=\"background:#2ca02c\"></i>pin displacement (x3)</span></div>\n\
<div class=\"controls\"><button id=\"play\">Play</button>\
<input id=\"slider\" type=\"range\" min=\"0\" value=\"0\" step=\"1\"></div>\
<div id=\"status\" data-step=\"\"></div>\n\
<div class=\"cap\">steps are numbered from 0, as in trajectory.csv</div>\n";

/// The page's script, inlined: the world with its axes in mm and a scale
/// bar, the tap's pins, the status line and the answering frame.
const SCRIPT: &str = include_str!("replay_html.js");

#[cfg(test)]
mod tests {
    use super::*;
    use tactrace_geometry::{Pose, Vec2};
    use tactrace_servo::Percept;

    fn step(i: usize) -> StepRecord {
        StepRecord {
            step: i,
            pose: Pose::planar(i as f64, 2.0 * i as f64, 0.0, 10.0),
            percept: Percept {
                r_mm: 0.25 * i as f64,
                theta_deg: -1.5,
                mean_displacement_px: 4.0,
                contact: true,
                missing_pins: 0,
            },
            delta: Pose::planar(0.0, 1.0, 0.0, 0.0),
        }
    }

    #[test]
    fn the_page_holds_its_data_and_loads_nothing_from_elsewhere() {
        let square = Contour::new(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(40.0, 0.0),
            Vec2::new(40.0, 40.0),
            Vec2::new(0.0, 40.0),
        ])
        .unwrap();
        let steps: Vec<StepRecord> = (0..4).map(step).collect();
        let pins = [[10.0, 20.0], [30.0, 40.0]];
        let fields = vec![vec![1.0f32, 2.0, 3.0, 4.0]; 4];
        let notes = ["mean L2 0.5 mm </script>".to_string()];
        let html = replay_html(&ReplayPage {
            title: "square <replay>",
            contour: Some(&square),
            steps: &steps,
            sensor_radius_mm: 20.0,
            fields: Some(PinFields {
                reference_pins: &pins,
                fields: &fields,
            }),
            frames: Some(StepFrames {
                images: &[vec![1, 2, 3]],
                names: &["frame_7_0.png".to_string()],
                per_step: &[0, 0, 0, 0],
                distances: &[0.5, f64::NAN, 0.25, 1.0 / 3.0],
            }),
            notes: &notes,
        });
        assert!(html.contains("<title>square &lt;replay&gt;</title>"));
        assert!(
            html.contains("[3.0,6.0,10.0,0.75,-1.5,4.0,1.0]"),
            "steps inline"
        );
        assert!(html.contains("[1.0,2.0,3.0,4.0]"), "fields inline");
        assert!(html.contains("[40.0,0.0]"), "contour inline");
        assert!(html.contains("\"images\":[\"data:image/png;base64,AQID\"]"));
        assert!(html.contains("\"step_image\":[0,0,0,0]"));
        assert!(html.contains("\"image_names\":[\"frame_7_0.png\"]"));
        assert!(html.contains("\"step_distance\":[0.5,null,0.25,0.333]"));
        assert!(
            html.contains("mean L2 0.5 mm <\\/script>"),
            "no early end of script"
        );
        assert_eq!(html.matches("</script>").count(), 2);
        for external in ["http:", "https:", "src=", "href=", "@import", "url("] {
            assert!(!html.contains(external), "loads {external}");
        }
    }
}
