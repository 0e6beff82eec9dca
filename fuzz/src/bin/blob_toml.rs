//! afl target: arbitrary text as blob-detector parameters (TOML); valid
//! parameters then list their thresholds.
fn main() {
    afl::fuzz!(|data: &[u8]| {
        let Ok(text) = std::str::from_utf8(data) else {
            return;
        };
        if let Ok(p) = tactrace_vision::BlobParams::from_toml(text) {
            assert!(p.thresholds().len() <= tactrace_vision::MAX_THRESHOLDS);
        }
    });
}
