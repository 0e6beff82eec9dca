//! The valid inputs mutated by the fuzzer, made in a temp dir by the CLI
//! itself: frames, a contour CSV, a Bristol-layout labelled set, TOML
//! configs, a collected dataset and a trained model.
use std::path::Path;

/// Rows of the Bristol-layout labelled set: (image, r mm, theta deg).
const BRISTOL_ROWS: [(&str, f64, f64); 3] = [
    ("frame_0_0.png", 2.0, 10.0),
    ("frame_1_0.png", -1.5, -20.0),
    ("frame_2_0.png", 0.5, 30.0),
];

/// Run the CLI for a seed; a failure here is a broken seed, not a finding.
fn cli(dir: &Path, args: &[&str]) -> String {
    let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    let o = super::runner::run(dir, &args);
    assert_eq!(
        o.code,
        Some(0),
        "seed command {args:?} failed: {}",
        o.stderr
    );
    std::fs::read_to_string(dir.join("stdout.txt")).unwrap_or_default()
}

/// Write every seed into `base`.
pub fn make(base: &Path) {
    cli(
        base,
        &[
            "collect",
            "--samples",
            // 36 at least for the model's 35 components.
            "40",
            "--seed",
            "3",
            "--save-frames",
            "--out",
            "ds",
        ],
    );
    std::fs::copy(base.join("ds/frames/reference.png"), base.join("ref.png")).expect("ref");
    cli(
        base,
        &[
            "sensor", "render", "--r", "2", "--theta", "10", "--out", "tap.png",
        ],
    );
    cli(
        base,
        &["train", "--train", "ds", "--epochs", "1", "--out", "m"],
    );
    cli(
        base,
        &[
            "follow", "--model", "m", "--shape", "disk", "--steps", "2", "--out", "run",
        ],
    );
    write_contour(&base.join("contour.csv"));
    write_tomls(base);
    write_bristol(base);
}

/// A closed outline: an ellipse of 40 points, with a header.
fn write_contour(path: &Path) {
    let mut s = String::from("x,y\n");
    for k in 0..40 {
        let a = k as f64 * std::f64::consts::TAU / 40.0;
        s += &format!("{:.3},{:.3}\n", 50.0 * a.cos(), 35.0 * a.sin());
    }
    std::fs::write(path, s).expect("contour");
}

/// Blob, rig, follow, training and search-grid TOMLs.
fn write_tomls(base: &Path) {
    let blob = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/blob-sim.toml");
    std::fs::copy(blob, base.join("blob.toml")).expect("blob toml");
    let follow = std::fs::read_to_string(base.join("run/config.toml")).expect("follow config");
    std::fs::write(base.join("follow.toml"), &follow).expect("follow toml");
    let table: toml::Table = toml::from_str(&follow).expect("follow config parses");
    let rig = toml::to_string(table["rig"].as_table().expect("rig table")).expect("rig");
    std::fs::write(base.join("rig.toml"), rig).expect("rig toml");
    let train = cli(
        base,
        &[
            "train",
            "--train",
            "ds",
            "--out",
            "unused",
            "--print-config",
        ],
    );
    std::fs::write(base.join("train.toml"), train).expect("train toml");
    let grid = "hidden = [8, 16]\nbetas = [0.5]\nn_components = [5]\ntrials = 1\n";
    std::fs::write(base.join("search.toml"), grid).expect("search toml");
}

/// frames/ (init_0.png and three taps) and targets.csv in the Bristol layout.
fn write_bristol(base: &Path) {
    let dir = base.join("bristol");
    std::fs::create_dir_all(dir.join("frames")).expect("bristol dir");
    std::fs::copy(base.join("ref.png"), dir.join("frames/init_0.png")).expect("init");
    let mut csv = String::from(
        "image_name,data_name,obj_id,pose_id,pose_1,pose_2,pose_3,pose_4,pose_5,pose_6,\
         move_1,move_2,move_3,move_4,move_5,move_6\n",
    );
    for (k, (name, r, theta)) in BRISTOL_ROWS.iter().enumerate() {
        let out = format!("bristol/frames/{name}");
        let (r, t) = (r.to_string(), theta.to_string());
        cli(
            base,
            &["sensor", "render", "--r", &r, "--theta", &t, "--out", &out],
        );
        csv += &format!("{name},frame_{k},1,{k},0,{r},-0.6,0,0,{t},-2.5,-0.03,0,0,0,-4.2\n");
    }
    std::fs::write(dir.join("targets.csv"), csv).expect("targets");
}
