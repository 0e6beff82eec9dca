//! afl target: a saved model from arbitrary bytes (model.json, a NUL byte,
//! then weights.safetensors); a loaded model then predicts once.
fn main() {
    afl::fuzz!(|data: &[u8]| {
        let (json, weights) = tactrace_fuzz::split_at_nul(data);
        let Ok(json) = std::str::from_utf8(json) else {
            return;
        };
        if let Ok(model) = tactrace_learn::PoseModel::from_bytes(json, weights) {
            let n = model.input_dim().min(1 << 16);
            let _ = model.predict(&vec![0.5; n]);
        }
    });
}
