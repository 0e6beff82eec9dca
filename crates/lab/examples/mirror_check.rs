//! Which targets a mirror of the pin layout keeps and which it negates,
//! asked of the data before trusting a sign (docs/learning.md, "Mirror
//! copies of the taps"). Not part of the product: the check behind a
//! `[reflections]` setting.
//!
//! Run: cargo run --release -p tactrace-lab --example mirror_check -- MODEL DATA AXIS_DEG...
//! MODEL: a pin model fitted without mirror copies; DATA: a dataset it
//! did not see, over the same reference pins. For every mirror line
//! `AXIS_DEG` (deg from the image's +x towards +y, through the pins'
//! centre) it mirrors DATA's taps (`tactrace_learn::mirrored_inputs`),
//! predicts them and prints, per target, the mean absolute error against
//! the labels as read (`+`) and negated (`-`), beside the taps as read.
//! The sign whose error is near the unmirrored one is the mirror's; an
//! axis where neither is near does not map the labels by a sign.
use std::path::Path;
use tactrace_learn::{mirrored_inputs, Dataset, PoseModel};
use tactrace_store::{read_dataset, StoredModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [model_dir, data_dir, axes @ ..] = args.as_slice() else {
        eprintln!("usage: mirror_check MODEL DATA AXIS_DEG...");
        std::process::exit(2);
    };
    let stored = StoredModel::load(Path::new(model_dir))?;
    let taps = read_dataset(Path::new(data_dir))?;
    let model = stored.for_data(&taps, Path::new(data_dir))?;
    let data = taps.to_learn()?;
    let pins = &taps.meta.reference_pins;
    let names: Vec<&str> = model.outputs().iter().map(|t| t.name.as_str()).collect();
    println!("{} taps; per target: MAE against +label / -label", data.n);
    println!("as read: {}", row(model, &data, &names)?);
    for axis in axes {
        let axis: f64 = axis.parse()?;
        let mirrored = mirrored_inputs(&data, pins, axis)?;
        println!("mirror at {axis} deg: {}", row(model, &mirrored, &names)?);
    }
    Ok(())
}

/// Every target's mean absolute error over `data` against its labels as
/// read and negated.
fn row(
    model: &PoseModel,
    data: &Dataset,
    names: &[&str],
) -> Result<String, Box<dyn std::error::Error>> {
    let predicted = model.predict_targets_batch(data)?;
    let mut parts = Vec::new();
    for (t, name) in names.iter().enumerate() {
        let mae = |sign: f64| {
            predicted
                .iter()
                .enumerate()
                .map(|(i, p)| (p[t] - sign * f64::from(data.y_row(i)[t])).abs())
                .sum::<f64>()
                / data.n as f64
        };
        parts.push(format!("{name} {:.4} / {:.4}", mae(1.0), mae(-1.0)));
    }
    Ok(parts.join(", "))
}
