//! The documents `reproduce` writes: report.md, a self-contained
//! report.html (figures embedded) and metrics.json, every measured number
//! beside the report's.
use crate::error::Result;
use crate::results::{
    slug, NetRow, ReplayShapeRow, ReproduceResults, LITERATURE_CNN, REPORT_TABLE_4_1,
};
use base64::Engine as _;
use std::fmt::Write as _;
use std::path::Path;
use tactrace_store::fsutil;

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.2}")).unwrap_or_else(|| "-".into())
}

/// A networks table: each row's errors beside the two `reference` figures
/// (angle, position, formatted) that `beside` gives for it.
fn table(
    md: &mut String,
    rows: &[NetRow],
    reference: &str,
    beside: impl Fn(&NetRow) -> [String; 2],
) {
    let _ = writeln!(
        md,
        "| network | angle MAE (deg) | position MAE (mm) | {reference} angle (deg) | {reference} position (mm) | train time (s) |\n|---|---|---|---|---|---|"
    );
    for n in rows {
        let [angle, position] = beside(n);
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.3} | {angle} | {position} | {:.1} |",
            n.name, n.angle_mae_deg, n.position_mae_mm, n.train_seconds
        );
    }
    md.push('\n');
}

/// The rows beside the report's Table 4.1.
fn networks_table(md: &mut String, rows: &[NetRow]) {
    table(md, rows, "report", |n| {
        let rep = REPORT_TABLE_4_1.iter().find(|(name, _, _)| *name == n.name);
        [opt(rep.and_then(|x| x.1)), opt(rep.and_then(|x| x.2))]
    });
}

/// The rows measured on real frames, and the literature figure once, as
/// a quotation (another split, a CNN on the images; not measured here).
fn real_table(md: &mut String, rows: &[NetRow]) {
    let _ = writeln!(
        md,
        "| network | angle MAE (deg) | position MAE (mm) | train time (s) |\n|---|---|---|---|"
    );
    for n in rows {
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.3} | {:.1} |",
            n.name, n.angle_mae_deg, n.position_mae_mm, n.train_seconds
        );
    }
    let (angle, position) = LITERATURE_CNN;
    let _ = writeln!(
        md,
        "\nFor orientation only (literature, not measured here: a CNN on the images of this collection, on another split): {angle} deg / {position} mm.\n"
    );
}

/// The simulated-to-real rows beside the same network trained on real frames.
fn transfer_table(md: &mut String, rows: &[NetRow], real: &[NetRow]) {
    table(md, rows, "trained on real:", |n| {
        let same = real.iter().find(|r| r.name == n.name);
        [
            opt(same.map(|r| r.angle_mae_deg)),
            same.map_or("-".into(), |r| format!("{:.3}", r.position_mae_mm)),
        ]
    });
}

/// The few-shot calibration table (docs/calibration.md) and the figure of
/// a held-out real field beside the simulated one before and after.
fn calibration_table(md: &mut String, rows: &[crate::CalibrationRow]) {
    md.push_str(
        "## Calibrated simulator: few real taps (`tactrace calibrate`, `twin --sensor`)\n\n",
    );
    md.push_str("A PDenNN trained on the twin of a sensor calibrated with N real taps, scored on held-out real frames; field misfit of the twin against those frames before and after the correction.\n\n");
    md.push_str("| calibration taps | chosen from | scored on | position MAE (mm) | angle MAE (deg) | field RMS before (px) | after (px) | cosine before | after |\n|---|---|---|---|---|---|---|---|---|\n");
    let num = |v: Option<f64>, p: usize| v.map_or("-".into(), |v| format!("{v:.p$}"));
    for c in rows {
        let asked = c
            .taps
            .map_or(format!("all ({})", c.taps_used), |n| n.to_string());
        let _ = writeln!(
            md,
            "| {asked} | {} | {} | {:.3} | {:.2} | {} | {} | {} | {} |",
            c.pool,
            c.scored_on,
            c.position_mae_mm,
            c.angle_mae_deg,
            num(c.field_rms_before_px, 2),
            num(c.field_rms_after_px, 2),
            num(c.cosine_before, 3),
            num(c.cosine_after, 3),
        );
    }
    md.push_str("\n![a held-out real field beside the uncalibrated twin](sensor/figures/field_before.svg) ![the same real field beside the calibrated twin](sensor/figures/field_after.svg)\n\n");
}

/// The Markdown text of the report.
pub fn report_markdown(r: &ReproduceResults) -> String {
    let mut md = String::from(
        "# tactrace reproduction of \"A Bio-Inspired System for Human-Like Contour Following\"\n\n",
    );
    let _ = writeln!(
        md,
        "tactrace {}, seed {}, {:.1} s in all. Simulated TacTip on a simulated arm (the report used a real UR5 and TacTip); the resolved configuration is in config.toml.\n",
        r.tactrace_version, r.seed, r.seconds
    );
    if let Some(dir) = &r.calibrated_sensor {
        let _ = writeln!(
            md,
            "The simulated TacTip is the calibrated sensor `{dir}` (`--sensor`): its taps, pin order and label convention.\n"
        );
    }
    md.push_str("## Fig. 4.1: frame, extracted pins, displacements\n\n");
    md.push_str("![Fig. 4.1 simulated tap (r = 2 mm, theta = 10 deg, nominal depth)](figures/fig4_1_simulated.svg)\n\n");
    if !r.real_networks.is_empty() {
        md.push_str(
            "![Fig. 4.1 real frame frame_0_0 of tactip127-edge2d](figures/fig4_1_real.svg)\n\n",
        );
    }
    md.push_str("## Table 4.1: validation errors (simulated disk, train and validation from separate runs)\n\n");
    networks_table(&mut md, &r.networks);
    for n in &r.networks {
        let _ = writeln!(
            md,
            "![Fig. 4.4 {0}: predicted against true](figures/fig4_4_{1}.svg)\n",
            n.name,
            slug(&n.name)
        );
    }
    md.push_str(
        "![Fig. 4.5 PDenNN: loss and total energy per epoch](models/pdennn/loss_energy.svg)\n\n",
    );
    if !r.real_networks.is_empty() {
        md.push_str("## Real TacTip frames (tactip127-edge2d, seeded 80/20 split)\n\n");
        real_table(&mut md, &r.real_networks);
    }
    if !r.sim_to_real.is_empty() {
        md.push_str("## Simulated to real: trained on the simulated twin of the real set (same labels, shear and depth; docs/results.md), validated on the same held-out real frames\n\n");
        transfer_table(&mut md, &r.sim_to_real, &r.real_networks);
    }
    if !r.calibration.is_empty() {
        calibration_table(&mut md, &r.calibration);
    }
    md.push_str("## Contour following with the PDenNN (Fig. 5.3, 5.4)\n\n");
    shapes_table(&mut md, &r.shapes, "");
    replay_links(&mut md, r.shapes.iter().map(|s| s.shape.as_str()), "follow");
    if !r.real_shapes.is_empty() {
        real_shapes_table(&mut md, r);
    }
    if !r.real_model_shapes.is_empty() {
        md.push_str("## Contour following in the calibrated simulator by the PDenNN trained on real frames\n\nThe simulated world is the sensor calibrated with 100 real taps (`sensor/`); the model was trained on the real training part only and predicts the real labels, mapped to the loop's edge pose by the sensor's label convention (docs/calibration.md).\n\n");
        shapes_table(&mut md, &r.real_model_shapes, "calibrated_");
        let shapes = r.real_model_shapes.iter().map(|s| s.shape.as_str());
        replay_links(&mut md, shapes, "follow-calibrated");
    }
    if let Some(s) = &r.surface_3d {
        crate::document3d::surface_markdown(&mut md, s);
    }
    md
}

/// The contour table and its figures (`fig5_3_{tag}{shape}`, `fig5_4_...`).
fn shapes_table(md: &mut String, shapes: &[crate::ShapeRow], tag: &str) {
    md.push_str("| shape | mean L2 (mm) | report L2 (mm) | mean track error (mm) | p95 (mm) | max (mm) | coverage | closed | steps | ending |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for s in shapes {
        let m = &s.metrics;
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0}% | {} | {} | {} |",
            s.shape,
            m.mean_l2_mm,
            s.report_l2_mm,
            m.mean_track_error_mm,
            m.p95_track_error_mm,
            m.max_track_error_mm,
            100.0 * m.coverage,
            m.closed,
            m.steps,
            s.ending
        );
    }
    md.push('\n');
    for s in shapes {
        let _ = writeln!(
            md,
            "![Fig. 5.3 {0}: trajectory over the true contour](figures/fig5_3_{1}{0}.svg) ![Fig. 5.4 {0}: L2 error along the contour](figures/fig5_4_{1}{0}.svg)\n",
            s.shape, tag
        );
    }
}

/// A line linking each run's step-by-step replay page (`DIR/SHAPE/replay.html`).
fn replay_links<'a>(md: &mut String, shapes: impl Iterator<Item = &'a str>, dir: &str) {
    let links: Vec<String> = shapes
        .map(|s| format!("[{s}]({dir}/{s}/replay.html)"))
        .collect();
    let _ = writeln!(
        md,
        "Step-by-step replays (open beside this report): {}.\n",
        links.join(", ")
    );
}

/// The four shapes in the real-frame world (`--real`), and with the image
/// model (`--image-model`).
fn real_shapes_table(md: &mut String, r: &ReproduceResults) {
    let pdennn = "the PDenNN trained on the real 80 %";
    shapes_in_real_world(md, pdennn, &r.real_shapes, "real/follow");
    if !r.real_image_shapes.is_empty() {
        let image =
            "the image model conv-dennn (whole frames, 64 px, no pins) trained on the real 80 %";
        shapes_in_real_world(md, image, &r.real_image_shapes, "real/follow-image");
    }
}

/// One table of the four shapes in the real-frame world, followed with
/// `model`, runs under `runs`.
fn shapes_in_real_world(md: &mut String, model: &str, rows: &[ReplayShapeRow], runs: &str) {
    let _ = write!(md, "## Contour following in the real-frame world ({model}; every tap answered by the held-out real frame whose labels are nearest the pose reached; docs/results.md)\n\n| shape | mean L2 (mm) | report L2 (mm) | mean track error (mm) | max (mm) | closed | steps | bank frames | label distance mean / p95 / max |\n|---|---|---|---|---|---|---|---|---|\n");
    for s in rows {
        let m = &s.metrics;
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {:.2} / {:.2} / {:.2} |",
            s.shape,
            m.mean_l2_mm,
            s.report_l2_mm,
            m.mean_track_error_mm,
            m.max_track_error_mm,
            m.closed,
            m.steps,
            s.bank_frames,
            s.label_distance_mean,
            s.label_distance_p95,
            s.label_distance_max
        );
    }
    md.push_str("\nThe frames are of a straight edge: this world cannot show curvature or corners (the sensor never feels a bend, only the change of edge pose between taps).\n\n");
    replay_links(md, rows.iter().map(|s| s.shape.as_str()), runs);
}

/// A data URI for the image file `src` (relative to `dir`), if readable.
fn data_uri(dir: &Path, src: &str) -> Option<String> {
    let mime = match Path::new(src).extension()?.to_str()? {
        "svg" => "image/svg+xml",
        "png" => "image/png",
        _ => return None,
    };
    let bytes = std::fs::read(dir.join(src)).ok()?;
    Some(format!(
        "data:{mime};base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    ))
}

/// report.md, report.html (self-contained) and metrics.json in `out`.
pub fn write_report(out: &Path, r: &ReproduceResults) -> Result<()> {
    let md = report_markdown(r);
    fsutil::write_atomic(&out.join("report.md"), md.as_bytes())?;
    let embed = |src: &str| data_uri(out, src);
    let html = crate::html::markdown_to_html(&md, &embed);
    fsutil::write_atomic(&out.join("report.html"), html.as_bytes())?;
    let json = serde_json::to_string_pretty(r).expect("results serialise");
    fsutil::write_atomic(&out.join("metrics.json"), json.as_bytes())?;
    Ok(())
}
