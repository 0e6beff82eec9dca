//! Every prediction of a saved pose model on a dataset's rows, printed to
//! full precision (`r_mm,theta_deg` a line), so two builds of the
//! prediction path can be compared row by row (docs/results.md, "Speed":
//! the projection's summation order).
//!
//! `cargo run --release -p tactrace-learn --example predict_dump -- \
//!     MODEL_DIR DATASET_DIR/inputs.npy > predictions.csv`

use tactrace_learn::PoseModel;

/// The values of a little-endian f32 `.npy` file (version 1 or 2 header).
fn read_npy_f32(bytes: &[u8]) -> Result<Vec<f32>, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file".into());
    }
    let (len, start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        _ if bytes.len() >= 12 => {
            let n = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
            (n as usize, 12)
        }
        _ => return Err("short .npy header".into()),
    };
    let header = bytes.get(start..start + len).ok_or("short .npy header")?;
    if !String::from_utf8_lossy(header).contains("'<f4'") {
        return Err("not little-endian f32".into());
    }
    let data = &bytes[start + len..];
    Ok(data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: predict_dump MODEL_DIR INPUTS.npy";
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().ok_or(usage)?);
    let inputs = std::path::PathBuf::from(args.next().ok_or(usage)?);
    let json = std::fs::read_to_string(dir.join("model.json"))?;
    let weights = std::fs::read(dir.join("weights.safetensors"))?;
    let model = PoseModel::from_bytes(&json, &weights)?;
    let rows = read_npy_f32(&std::fs::read(inputs)?)?;
    println!("r_mm,theta_deg");
    for [r, theta] in model.predict_rows(&rows)? {
        println!("{r:e},{theta:e}");
    }
    Ok(())
}
