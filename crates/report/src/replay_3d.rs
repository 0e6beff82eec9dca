//! A 3D task's run as one self-contained page (`replay.html`): the surface
//! as a wire mesh, the sensor's path and its axis at each step, in a view
//! the mouse turns (drag), with a play button and a step slider. The data
//! is inline JSON and the script a few dozen lines drawing on a canvas:
//! no network, no files beside it. The page opens at step K when its
//! address ends in `#step=K`; `#status` then says that step's values.
use serde::Serialize;

/// One step as the page shows it.
#[derive(Debug, Clone, Serialize)]
pub struct Replay3dStep {
    /// The sensor's pole (x, y, z mm) and its axis (unit vector), work frame.
    pub pose: [f64; 6],
    /// The predicted label (x, y, z mm; rx, ry, rz deg; z the depth).
    pub label: [f64; 6],
    /// The true depth minus the reference depth, mm.
    pub depth_error_mm: f64,
    /// The angle between the sensor's axis and the surface normal, deg.
    pub normal_error_deg: f64,
}

/// What the page shows.
pub struct Replay3dPage<'a> {
    pub title: &'a str,
    /// The surface's wire lines (x, y, z mm).
    pub wire: &'a [Vec<[f64; 3]>],
    pub steps: &'a [Replay3dStep],
}

#[derive(Serialize)]
struct Data<'a> {
    title: &'a str,
    wire: Vec<Vec<[f64; 3]>>,
    poses: Vec<[f64; 6]>,
    steps: &'a [Replay3dStep],
}

/// The page's HTML.
pub fn replay_3d_html(page: &Replay3dPage) -> String {
    let r2 = |v: f64| (v * 100.0).round() / 100.0;
    let data = Data {
        title: page.title,
        wire: page
            .wire
            .iter()
            .map(|l| l.iter().map(|p| p.map(r2)).collect())
            .collect(),
        poses: page.steps.iter().map(|s| s.pose).collect(),
        steps: page.steps,
    };
    let json = serde_json::to_string(&data)
        .expect("page data serialises")
        .replace("</", "<\\/");
    let title = page
        .title
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{title}</title>\n<style>{STYLE}</style></head>\n<body>\n{BODY}\
         <script type=\"application/json\" id=\"data\">{json}</script>\n\
         <script>{SCRIPT}</script>\n</body></html>\n"
    )
}

const STYLE: &str = "body{font-family:sans-serif;margin:1em}canvas{border:1px solid #ccc;\
cursor:grab}#status{margin:.5em 0;font-family:monospace}";

const BODY: &str = "<h1 id=\"title\"></h1>\n<canvas id=\"view\" width=\"700\" height=\"560\"></canvas>\n\
<div>drag to turn the view; grey: the surface; blue: the sensor's path; red: its axis</div>\n\
<div><button id=\"play\">play</button> <input id=\"step\" type=\"range\" min=\"0\" value=\"0\"></div>\n\
<div id=\"status\"></div>\n";

const SCRIPT: &str = include_str!("replay_3d.js");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_3d_page_holds_its_data_and_loads_nothing() {
        let steps = vec![Replay3dStep {
            pose: [0.0, 0.0, -3.0, 0.0, 0.0, 1.0],
            label: [0.0, 0.0, 3.0, 0.1, -0.2, 0.0],
            depth_error_mm: 0.01,
            normal_error_deg: 0.5,
        }];
        let wire = vec![vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]];
        let html = replay_3d_html(&Replay3dPage {
            title: "saddle </script>",
            wire: &wire,
            steps: &steps,
        });
        assert!(html.contains("\"depth_error_mm\":0.01"));
        assert!(!html.contains("saddle </script>"));
        for far in ["http://", "https://", "src=", "import "] {
            assert!(!html.contains(far), "{far}");
        }
    }
}
