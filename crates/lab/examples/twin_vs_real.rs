//! Where a simulated twin and the real frames of the same labels differ,
//! by edge position r (docs/sensor-model.md, eqs. S4a and S6a). Not part
//! of the product: the diagnostic behind the compliance and screening.
//!
//! Run: cargo run --release -p tactrace-lab --example twin_vs_real -- REAL TWIN
//! REAL: a dataset of real frames (`tactrace import`), TWIN: the twin of
//! the same labels (`tactrace twin`); samples are paired by image name.
//! Per 2 mm bin of r it prints:
//! - gain: the least-squares size of the real field against the twin's,
//!   sum(real . twin) / sum(twin . twin) over the bin's frames;
//! - d/dtheta: the change of the field per 45 deg of edge angle, fitted
//!   in the bin by least squares on [1, theta / 45, r]: the cosine of the
//!   real and twin changes and the ratio of their sizes (twin / real).
//!   A model trained on the twin reads the angle along the twin's change.
use std::path::Path;
use tactrace_store::{read_dataset, TapData};

const BINS: [(f64, f64); 5] = [
    (-5.1, -3.0),
    (-3.0, -1.0),
    (-1.0, 1.0),
    (1.0, 3.0),
    (3.0, 5.1),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [real, twin] = args.as_slice() else {
        eprintln!("usage: twin_vs_real REAL_DATASET TWIN_DATASET");
        std::process::exit(2);
    };
    let real = read_dataset(Path::new(real))?;
    let twin = paired(&real, &read_dataset(Path::new(twin))?)?;
    let dim = real.dim();
    let rms = (real
        .inputs
        .iter()
        .zip(&twin.inputs)
        .map(|(a, b)| ((a - b) as f64).powi(2))
        .sum::<f64>()
        / real.inputs.len() as f64)
        .sqrt();
    println!(
        "{} frames, per-coordinate field RMS {rms:.3} px",
        real.len()
    );
    println!("r bin (mm)      frames  gain   d/dtheta cos  ratio");
    for (lo, hi) in BINS {
        let rows: Vec<usize> = (0..real.len())
            .filter(|&i| (lo..hi).contains(&(real.targets[2 * i] as f64)))
            .collect();
        let gain = gain(&real, &twin, &rows, dim);
        let (a, b) = (theta_slope(&real, &rows), theta_slope(&twin, &rows));
        let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        let (na, nb) = (norm(&a), norm(&b));
        println!(
            "[{lo:+.0}, {hi:+.0})  {:>11}  {gain:.3}  {:.3}         {:.3}",
            rows.len(),
            dot / (na * nb),
            nb / na
        );
    }
    Ok(())
}

/// The twin's samples in the order of `real`'s, matched by image name.
fn paired(real: &TapData, twin: &TapData) -> Result<TapData, String> {
    let at = twin.image_rows();
    let rows = real
        .meta
        .images
        .iter()
        .map(|n| {
            at.get(n.as_str())
                .copied()
                .ok_or(format!("{n} is not in the twin"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(twin.subset(&rows))
}

fn gain(real: &TapData, twin: &TapData, rows: &[usize], dim: usize) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for &i in rows {
        let (a, b) = (
            &real.inputs[i * dim..][..dim],
            &twin.inputs[i * dim..][..dim],
        );
        for (x, y) in a.iter().zip(b) {
            num += (x * y) as f64;
            den += (y * y) as f64;
        }
    }
    num / den
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Per input coordinate, the coefficient of theta / 45 in the least-squares
/// fit x = c0 + c1 theta / 45 + c2 r over `rows`.
fn theta_slope(data: &TapData, rows: &[usize]) -> Vec<f64> {
    let dim = data.dim();
    let features = |i: usize| {
        let t = &data.targets[2 * i..2 * i + 2];
        [1.0, t[1] as f64 / 45.0, t[0] as f64]
    };
    let mut gram = nalgebra::Matrix3::<f64>::zeros();
    for &i in rows {
        let f = nalgebra::Vector3::from(features(i));
        gram += f * f.transpose();
    }
    let Some(inv) = gram.try_inverse() else {
        return vec![f64::NAN; dim];
    };
    (0..dim)
        .map(|k| {
            let mut rhs = nalgebra::Vector3::<f64>::zeros();
            for &i in rows {
                rhs += nalgebra::Vector3::from(features(i)) * data.inputs[i * dim + k] as f64;
            }
            (inv * rhs)[1]
        })
        .collect()
}
