//! Pin extraction on the real 127-pin TacTip frames in shared/data (when
//! the data set is absent these fail, or are skipped with a message under
//! TACTRACE_SKIP_REAL_DATA=1: see `tactrace_testdata`).

use std::path::{Path, PathBuf};

use tactrace_vision::{detect_blobs, BlobParams, Frame, PinExtractor, Tracked};

const PINS: usize = 127;

fn frames_dir() -> Option<PathBuf> {
    tactrace_testdata::real_edge_set().map(|d| d.join("frames"))
}

fn load(path: &Path) -> Frame {
    image::open(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
        .to_luma8()
}

/// Frame files `frame_<n>_0.png`, sorted by n.
fn frame_paths(dir: &Path) -> Vec<PathBuf> {
    let mut numbered: Vec<(u32, PathBuf)> = std::fs::read_dir(dir)
        .expect("frames dir readable")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let n = name
                .strip_prefix("frame_")?
                .strip_suffix("_0.png")?
                .parse()
                .ok()?;
            Some((n, p))
        })
        .collect();
    numbered.sort();
    numbered.into_iter().map(|(_, p)| p).collect()
}

fn extractor(dir: &Path) -> PinExtractor {
    let params = BlobParams::preset("real256").expect("preset");
    PinExtractor::from_reference_frame(&load(&dir.join("init_0.png")), params).expect("reference")
}

/// Largest displacement difference between a pin and any reference
/// neighbour within 1.5 spacings, px.
fn roughness(tracked: &Tracked, reference: &[[f64; 2]], spacing: f64) -> f64 {
    let d: Vec<[f64; 2]> = tracked
        .pins
        .iter()
        .zip(reference)
        .map(|(p, r)| [p[0] - r[0], p[1] - r[1]])
        .collect();
    let mut worst = 0.0f64;
    for (i, a) in reference.iter().enumerate() {
        for (j, b) in reference.iter().enumerate().skip(i + 1) {
            if (a[0] - b[0]).hypot(a[1] - b[1]) < 1.5 * spacing {
                worst = worst.max((d[i][0] - d[j][0]).hypot(d[i][1] - d[j][1]));
            }
        }
    }
    worst
}

/// Triangles of mutually neighbouring reference pins (sides below 1.5
/// spacings): a valid tracking keeps every one of them the same way round,
/// a swapped pair turns some over even under strong compression.
fn triangles(reference: &[[f64; 2]], spacing: f64) -> Vec<[usize; 3]> {
    let near = |a: usize, b: usize| {
        (reference[a][0] - reference[b][0]).hypot(reference[a][1] - reference[b][1]) < 1.5 * spacing
    };
    let n = reference.len();
    let mut out = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                if near(i, j) && near(j, k) && near(i, k) {
                    out.push([i, j, k]);
                }
            }
        }
    }
    out
}

fn signed_area(p: &[[f64; 2]], t: [usize; 3]) -> f64 {
    let [a, b, c] = t.map(|i| p[i]);
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Triangles turned over between reference and tracked pins: signed area
/// ratio below -0.25. A swap gives about -1; a triangle squashed flat
/// against the edge (ratio near 0) can tip over by detection noise alone.
fn flipped(tracked: &Tracked, reference: &[[f64; 2]], triangles: &[[usize; 3]]) -> usize {
    triangles
        .iter()
        .filter(|&&t| signed_area(&tracked.pins, t) / signed_area(reference, t) < -0.25)
        .count()
}

/// The most negative tracked/reference signed-area ratio of the frame.
fn worst_area_ratio(tracked: &Tracked, reference: &[[f64; 2]], triangles: &[[usize; 3]]) -> f64 {
    triangles
        .iter()
        .map(|&t| signed_area(&tracked.pins, t) / signed_area(reference, t))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn undeformed_frame_has_exactly_127_pins() {
    let Some(dir) = frames_dir() else { return };
    let params = BlobParams::preset("real256").expect("preset");
    let keypoints = detect_blobs(&load(&dir.join("init_0.png")), &params);
    assert_eq!(keypoints.len(), PINS);
    let extractor = extractor(&dir);
    let tracked = extractor
        .extract(&load(&dir.join("init_0.png")))
        .expect("extract");
    assert_eq!((tracked.missing, tracked.extra), (0, 0));
    assert!(tracked
        .displacement(extractor.tracker.reference())
        .iter()
        .all(|d| d.abs() < 1e-9));
}

/// Every 20th frame: all pins matched on >= 99 % of them, and the tracked
/// field is smooth: no triangle of neighbours turned over on any frame, and
/// neighbours' displacements differ by less than 1.25 spacings (a swap
/// gives about 2; compression next to the edge gives up to about 1).
#[test]
fn sampled_frames_match_all_pins_smoothly() {
    let Some(dir) = frames_dir() else { return };
    let extractor = extractor(&dir);
    let reference = extractor.tracker.reference();
    let spacing = extractor.tracker.spacing();
    let sample: Vec<PathBuf> = frame_paths(&dir).into_iter().step_by(20).collect();
    let triangles = triangles(reference, spacing);
    assert!(triangles.len() > 150, "{} triangles", triangles.len());
    let mut complete = 0;
    let mut turned = 0;
    for path in &sample {
        let tracked = extractor.extract(&load(path)).expect("enough pins");
        if tracked.missing == 0 {
            complete += 1;
        }
        let rough = roughness(&tracked, reference, spacing);
        assert!(
            rough < 1.25 * spacing,
            "{}: neighbour displacement jump {rough:.1} px",
            path.display()
        );
        if flipped(&tracked, reference, &triangles) > 0 {
            eprintln!("turned-over neighbour triangle in {}", path.display());
            turned += 1;
        }
    }
    // frame_2186 (in this sample) turned one over before the fold repair.
    assert_eq!(
        turned,
        0,
        "{turned} of {} frames turned a triangle over",
        sample.len()
    );
    let share = complete as f64 / sample.len() as f64;
    assert!(
        share >= 0.99,
        "all pins matched on only {:.1} % of {} frames",
        100.0 * share,
        sample.len()
    );
}

/// The two frames whose ordering turned a neighbour triangle over before
/// the fold repair (under ~30 px shear with strong compression at the edge;
/// a cluster of two touching pins was given one pin, the pin next to it
/// two): now fold-free, with every pin matched, by this file's own
/// triangle check and the tracker's.
#[test]
fn the_two_formerly_swapped_frames_are_fold_free() {
    let Some(dir) = frames_dir() else { return };
    let extractor = extractor(&dir);
    let reference = extractor.tracker.reference();
    let triangles = triangles(reference, extractor.tracker.spacing());
    assert_eq!(triangles.len(), extractor.tracker.triangle_count());
    for name in ["frame_2186_0.png", "frame_3040_0.png"] {
        let tracked = extractor.extract(&load(&dir.join(name))).expect("extract");
        assert_eq!(flipped(&tracked, reference, &triangles), 0, "{name}");
        assert_eq!(extractor.tracker.turned_triangles(&tracked), 0, "{name}");
        assert_eq!(tracked.missing, 0, "{name}");
    }
}

/// Run with `cargo test -p tactrace-vision --release -- --ignored --nocapture`.
#[test]
#[ignore = "all 3762 frames; prints the figures recorded in docs/vision.md"]
fn all_frames_statistics() {
    let Some(dir) = frames_dir() else { return };
    let extractor = extractor(&dir);
    let reference = extractor.tracker.reference();
    let spacing = extractor.tracker.spacing();
    let paths = frame_paths(&dir);
    let frames: Vec<Frame> = paths.iter().map(|p| load(p)).collect();
    let start = std::time::Instant::now();
    let results: Vec<_> = frames.iter().map(|f| extractor.extract(f)).collect();
    let seconds = start.elapsed().as_secs_f64();
    let mut complete = 0;
    let mut missing_hist = [0usize; 6];
    let mut rough_max = 0.0f64;
    let mut failures = 0;
    let triangles = triangles(reference, spacing);
    let mut flipped_frames = 0;
    for (path, result) in paths.iter().zip(&results) {
        let Ok(tracked) = result else {
            failures += 1;
            continue;
        };
        complete += usize::from(tracked.missing == 0);
        if tracked.missing >= 3 {
            println!("missing {} in {}", tracked.missing, path.display());
        }
        missing_hist[tracked.missing.min(5)] += 1;
        let rough = roughness(tracked, reference, spacing);
        if flipped(tracked, reference, &triangles) > 0 {
            flipped_frames += 1;
            println!("flipped triangles in {}", path.display());
        }
        let worst = worst_area_ratio(tracked, reference, &triangles);
        if worst < 0.05 {
            println!("area ratio {worst:.2} in {}", path.display());
        }
        rough_max = rough_max.max(rough);
    }
    let n = paths.len();
    println!(
        "frames {n}, all {PINS} matched {complete} ({:.2} %), errors {failures}",
        100.0 * complete as f64 / n as f64
    );
    println!("missing-pin histogram 0..=5+: {missing_hist:?}");
    println!(
        "frames with a turned-over neighbour triangle: {flipped_frames} ({} triangles)",
        triangles.len()
    );
    println!("max neighbour displacement difference {rough_max:.2} px (spacing {spacing:.2} px)");
    println!("detect+order {:.0} us/frame", 1e6 * seconds / n as f64);
}
