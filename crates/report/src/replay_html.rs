//! A follow run as one self-contained page (`replay.html`): the contour,
//! the path so far, the sensor's pose and what the model predicted at each
//! step, and the tap's pins with their displacement arrows, with a play
//! button and a step slider. The data is inline JSON and the page's script
//! a few dozen lines: no network, no files beside it.
//!
//! The page opens at step K when its address ends in `#step=K`; the
//! element `#status` then says that step's values (what the browser test
//! reads).
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
/// frame once, and for every step the index of its frame.
#[derive(Clone, Copy)]
pub struct StepFrames<'a> {
    pub images: &'a [Vec<u8>],
    pub per_step: &'a [usize],
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
    /// The distinct frames as data URIs, and each step's index into them.
    images: Vec<String>,
    step_image: Vec<usize>,
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
    let (images, step_image) = page.frames.map_or((Vec::new(), Vec::new()), |f| {
        let uri = |png: &Vec<u8>| format!("data:image/png;base64,{}", BASE64.encode(png));
        (f.images.iter().map(uri).collect(), f.per_step.to_vec())
    });
    let data = PageData {
        title: page.title,
        notes: page.notes,
        radius: page.sensor_radius_mm,
        contour,
        steps,
        pins,
        fields,
        images,
        step_image,
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

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;color:#222;background:#fafafa}\
h1{font-size:1.3em;margin:0 0 .3em}#notes{color:#555;font-size:.9em;margin:0 0 .8em}\
#notes p{margin:.15em 0}.panes{display:flex;gap:1em;flex-wrap:wrap}\
canvas{background:#fff;border:1px solid #ccc;border-radius:4px}\
.controls{display:flex;align-items:center;gap:.8em;margin:.8em 0}\
#slider{flex:0 0 820px}.cap{font-size:.85em;color:#555;max-width:400px}button{font-size:1em;padding:.3em 1em}\
#status{font-family:monospace;font-size:.95em;white-space:pre}\
.key span{display:inline-block;margin-right:1.2em;font-size:.85em}\
.sw{display:inline-block;width:1.6em;height:.35em;vertical-align:middle;margin-right:.3em}";

const BODY: &str = "<h1 id=\"title\"></h1><div id=\"notes\"></div>\n\
<div class=\"panes\"><canvas id=\"world\" width=\"560\" height=\"560\"></canvas>\
<div><canvas id=\"pins\" width=\"400\" height=\"400\"></canvas>\
<div class=\"cap\">the tap&#39;s frame (when the run kept it, faded), its pins at rest (grey) and their displacement x3 (green)</div></div></div>\n\
<div class=\"key\"><span><i class=\"sw\" style=\"background:#999\"></i>contour</span>\
<span><i class=\"sw\" style=\"background:#1f77b4\"></i>path (commanded)</span>\
<span><i class=\"sw\" style=\"background:#d62728\"></i>sensor and its x axis</span>\
<span><i class=\"sw\" style=\"background:#ff7f0e\"></i>edge as predicted</span>\
<span><i class=\"sw\" style=\"background:#2ca02c\"></i>pin displacement (x3)</span></div>\n\
<div class=\"controls\"><button id=\"play\">Play</button>\
<input id=\"slider\" type=\"range\" min=\"0\" value=\"0\" step=\"1\"></div>\
<div id=\"status\" data-step=\"\"></div>\n";

const SCRIPT: &str = r#"
const D = JSON.parse(document.getElementById('data').textContent);
const S = D.steps, slider = document.getElementById('slider');
const status = document.getElementById('status'), play = document.getElementById('play');
document.getElementById('title').textContent = D.title;
for (const n of D.notes) { const p = document.createElement('p'); p.textContent = n; document.getElementById('notes').appendChild(p); }
slider.max = Math.max(S.length - 1, 0);
const pts = D.contour.concat(S.map(s => [s[0], s[1]]));
let x0 = Math.min(...pts.map(p => p[0])) - D.radius, x1 = Math.max(...pts.map(p => p[0])) + D.radius;
let y0 = Math.min(...pts.map(p => p[1])) - D.radius, y1 = Math.max(...pts.map(p => p[1])) + D.radius;
const W = document.getElementById('world'), wc = W.getContext('2d');
const k = Math.min(W.width / (x1 - x0), W.height / (y1 - y0));
const tx = p => [(p[0] - x0) * k, W.height - (p[1] - y0) * k];
function line(c, a, b, col, w) { c.strokeStyle = col; c.lineWidth = w; c.beginPath(); c.moveTo(...a); c.lineTo(...b); c.stroke(); }
function poly(c, ps, col, w, close) {
  if (!ps.length) return; c.strokeStyle = col; c.lineWidth = w; c.beginPath(); c.moveTo(...ps[0]);
  for (const p of ps.slice(1)) c.lineTo(...p); if (close) c.closePath(); c.stroke();
}
function drawWorld(i) {
  wc.clearRect(0, 0, W.width, W.height);
  poly(wc, D.contour.map(tx), '#999', 2, true);
  poly(wc, S.slice(0, i + 1).map(s => tx(s)), '#1f77b4', 1.5, false);
  const s = S[i]; if (!s) return;
  const a = s[2] * Math.PI / 180, c = tx(s);
  wc.strokeStyle = '#d62728'; wc.lineWidth = 1.5; wc.beginPath(); wc.arc(c[0], c[1], D.radius * k, 0, 2 * Math.PI); wc.stroke();
  line(wc, c, tx([s[0] + D.radius * Math.cos(a), s[1] + D.radius * Math.sin(a)]), '#d62728', 2);
  const n = a - s[4] * Math.PI / 180, e = [s[0] - s[3] * Math.cos(n), s[1] - s[3] * Math.sin(n)];
  const t = [-Math.sin(n), Math.cos(n)], h = D.radius * 0.8;
  line(wc, tx([e[0] - h * t[0], e[1] - h * t[1]]), tx([e[0] + h * t[0], e[1] + h * t[1]]), '#ff7f0e', 3);
}
const P = document.getElementById('pins'), pc = P.getContext('2d');
const imgs = D.images.map(u => { const im = new Image(); im.onload = () => show(+slider.value); im.src = u; return im; });
function drawPins(i) {
  pc.clearRect(0, 0, P.width, P.height);
  const f = D.fields[i], im = imgs[D.step_image[i]];
  let q, ox = 20, oy = 20, px0 = 0, py0 = 0;
  if (im && im.complete && im.naturalWidth) {
    q = Math.min(P.width / im.naturalWidth, P.height / im.naturalHeight); ox = 0; oy = 0;
    pc.globalAlpha = 0.45; pc.drawImage(im, 0, 0, im.naturalWidth * q, im.naturalHeight * q); pc.globalAlpha = 1;
  }
  if (!D.pins.length || !f || !f.length) { pc.fillStyle = '#888'; pc.font = '14px sans-serif'; pc.fillText('no pin displacements kept for this run', 20, 30); return; }
  const xs = D.pins.map(p => p[0]), ys = D.pins.map(p => p[1]);
  if (!q) { px0 = Math.min(...xs); py0 = Math.min(...ys); q = (P.width - 40) / Math.max(Math.max(...xs) - px0, Math.max(...ys) - py0); }
  const m = D.pins.length;
  for (let j = 0; j < m; j++) {
    const p = [ox + (D.pins[j][0] - px0) * q, oy + (D.pins[j][1] - py0) * q];
    pc.fillStyle = '#bbb'; pc.beginPath(); pc.arc(p[0], p[1], 2.5, 0, 2 * Math.PI); pc.fill();
    line(pc, p, [p[0] + 3 * q * f[j], p[1] + 3 * q * f[m + j]], '#2ca02c', 1.5);
  }
}
function show(i) {
  i = Math.max(0, Math.min(S.length - 1, i | 0)); slider.value = i;
  drawWorld(i); drawPins(i);
  const s = S[i] || [0, 0, 0, 0, 0, 0, 0];
  status.dataset.step = i;
  status.textContent = `step ${i} of ${S.length - 1}: x ${s[0].toFixed(2)} mm, y ${s[1].toFixed(2)} mm, angle ${s[2].toFixed(1)} deg | predicted r ${s[3].toFixed(2)} mm, theta ${s[4].toFixed(1)} deg | mean |d| ${s[5].toFixed(2)} px, ${s[6] ? 'contact' : 'no contact'}`;
}
let timer = null;
play.onclick = () => {
  if (timer) { clearInterval(timer); timer = null; play.textContent = 'Play'; return; }
  if (+slider.value >= S.length - 1) show(0);
  play.textContent = 'Pause';
  timer = setInterval(() => { if (+slider.value >= S.length - 1) { play.onclick(); return; } show(+slider.value + 1); }, 60);
};
slider.oninput = () => show(+slider.value);
const m = /step=(\d+)/.exec(location.hash + location.search);
show(m ? +m[1] : S.length - 1);
"#;

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
                per_step: &[0, 0, 0, 0],
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
